/* lbk_lmuv_object_check (lbk/lightmap_uv.h, spec/container.md §16.4): an LMUV record against the
 * glTF mesh an engine loaded. A section built here by lbk_lmuv_build for two glTF primitives —
 * a quad with NORMAL whose vertex 2 lies on a chart seam (two new vertices), and two flat-shaded
 * triangles without NORMAL (one new vertex per corner) — and an AUTHORED record:
 *  - the mesh as the glTF has it passes (LBK_OK, detail code 0, empty message);
 *  - each way a mesh can differ is refused with LBK_ERR_MISMATCH and its own detail code, naming
 *    the primitive, triangle and corner and both values: node, primitive count, source
 *    primitive, source vertex count, triangle count, a corner whose new vertex copies another
 *    source vertex (also a winding left mirrored), the vertex order of §16.4 both ways;
 *  - the caller's mistakes (a corner outside its primitive, unknown flags, NULLs, size-tagged
 *    sizes) are LBK_ERR_INVALID_ARGUMENT / _UNSUPPORTED_FEATURE; a record or view that
 *    lbk_lmuv_open did not check is LBK_ERR_RANGE; hostile counts (UINT32_MAX triangles or
 *    primitives behind a two-element array) are refused before any read (ASan would see one). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "lbk/lightmap_uv.h"

/* glTF primitive 0: a quad (source vertices 0..3), triangles (0,1,2) and (0,2,3); the second
 * triangle's corner at source vertex 2 is on another chart, so vertex 2 has two new vertices
 * (remap ascending: 0, 1, 2, 2, 3). */
static const uint32_t quad_corners[6] = {0, 1, 2, 0, 2, 3};
static const uint32_t quad_remap[5] = {0, 1, 2, 2, 3}, quad_idx[6] = {0, 1, 2, 0, 3, 4};
static const float quad_xy[10] = {1, 1, 9, 1, 9, 9, 11, 9, 3, 9};
/* glTF primitive 2: no NORMAL, source vertices 0..2, triangles (2,0,1) and (1,0,2): a new vertex
 * per corner, in corner order. */
static const uint32_t flat_corners[6] = {2, 0, 1, 1, 0, 2};
static const uint32_t flat_remap[6] = {2, 0, 1, 1, 0, 2}, flat_idx[6] = {0, 1, 2, 3, 4, 5};
static const float flat_xy[12] = {1, 20, 9, 20, 5, 28, 11, 20, 19, 20, 15, 28};

typedef struct fixture {
    void *bytes;
    size_t size;
    lbk_lmuv_view view;
    lbk_lmuv_object authored, generated;
    lbk_lmuv_mesh_primitive prims[2];
    uint32_t quad[6], flat[6]; /* the corners the mesh hands in: edited by the cases */
    lbk_lmuv_mesh_desc mesh;
} fixture;

/* A section of the two records with the given arrays for the quad (the order cases replace it). */
static void build(fixture *f, const uint32_t *qremap, const uint32_t *qidx, uint32_t qverts, const float *qxy)
{
    const lbk_lmuv_primitive_desc prims[2] = {
        {.source_primitive = 0, .source_vertex_count = 4, .vertex_count = qverts, .index_count = 6, .remap = qremap,
         .indices = qidx, .coords = qxy},
        {.source_primitive = 2, .source_vertex_count = 3, .vertex_count = 6, .index_count = 6, .remap = flat_remap,
         .indices = flat_idx, .coords = flat_xy}};
    lbk_lmuv_object_desc rec[2] = {{.object = 1, .kind = LBK_LMUV_AUTHORED, .source_node = 3, .scale = {8, 8},
                                    .offset = {1, 1}, .uv_min = {0, 0}, .uv_max = {1, 1}},
                                   {.object = 4, .kind = LBK_LMUV_GENERATED, .source_node = 7, .primitive_count = 2,
                                    .primitives = prims}};
    assert_int_equal(lbk_lmuv_build(rec, 2, NULL, &f->bytes, &f->size), LBK_OK);
    assert_int_equal(lbk_lmuv_open(f->bytes, f->size, &f->view), LBK_OK);
    assert_int_equal(lbk_lmuv_get_object(&f->view, 0, &f->authored), LBK_OK);
    assert_int_equal(lbk_lmuv_get_object(&f->view, 1, &f->generated), LBK_OK);
}

/* The mesh as the glTF has it (node 7). */
static void mesh_reset(fixture *f)
{
    memcpy(f->quad, quad_corners, sizeof f->quad);
    memcpy(f->flat, flat_corners, sizeof f->flat);
    f->prims[0] = (lbk_lmuv_mesh_primitive){
        .source_primitive = 0, .source_vertex_count = 4, .triangle_count = 2, .flags = 0, .corners = f->quad};
    f->prims[1] = (lbk_lmuv_mesh_primitive){.source_primitive = 2, .source_vertex_count = 3, .triangle_count = 2,
                                            .flags = LBK_LMUV_MESH_NO_NORMAL, .corners = f->flat};
    f->mesh = (lbk_lmuv_mesh_desc)LBK_LMUV_MESH_DESC_INIT;
    f->mesh.source_node = 7;
    f->mesh.primitive_count = 2;
    f->mesh.primitives = f->prims;
}

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    if (!f) return -1;
    build(f, quad_remap, quad_idx, 5, quad_xy);
    mesh_reset(f);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    lbk_free(NULL, f->bytes);
    free(f);
    return 0;
}

/* What a refusal must say. */
typedef struct expect {
    lbk_result result;
    uint32_t code, primitive, triangle, corner;
    uint64_t record_value, mesh_value;
} expect;

static void check(fixture *f, const lbk_lmuv_object *record, expect e)
{
    lbk_lmuv_check_detail d;
    memset(&d, 0x5a, sizeof d);
    const lbk_result r = lbk_lmuv_object_check(&f->view, record, &f->mesh, &d);
    print_message("  %-34s %-24s %s\n", lbk_lmuv_check_code_name(d.code), lbk_result_name(r), d.message);
    assert_int_equal(r, e.result);
    assert_int_equal(d.code, e.code);
    assert_int_equal(d.primitive, e.primitive);
    assert_int_equal(d.triangle, e.triangle);
    assert_int_equal(d.corner, e.corner);
    assert_int_equal(d.record_value, e.record_value);
    assert_int_equal(d.mesh_value, e.mesh_value);
    assert_true(e.code == LBK_LMUV_CHECK_OK ? d.message[0] == 0 : strlen(d.message) > 10);
    assert_non_null(memchr(d.message, 0, sizeof d.message));
    /* the same verdict without a detail */
    assert_int_equal(lbk_lmuv_object_check(&f->view, record, &f->mesh, NULL), e.result);
    mesh_reset(f);
}

static const expect ok = {LBK_OK, LBK_LMUV_CHECK_OK, 0, 0, 0, 0, 0};

static void the_mesh_passes(void **state)
{
    fixture *f = *state;
    check(f, &f->generated, ok);
    check(f, &f->authored, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_NODE, 0, 0, 0, 3, 7}); /* another node */
    f->mesh.source_node = 3;
    f->mesh.primitive_count = 0; /* AUTHORED: TEXCOORD_1 is the layout, the primitives are not read */
    f->mesh.primitives = NULL;
    check(f, &f->authored, ok);
}

static void each_difference(void **state)
{
    fixture *f = *state;
    f->mesh.source_node = 8;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_NODE, 0, 0, 0, 7, 8});
    f->mesh.primitive_count = 1;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_PRIMITIVE_COUNT, 0, 0, 0, 2, 1});
    f->prims[1].source_primitive = 1;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_SOURCE_PRIMITIVE, 1, 0, 0, 2, 1});
    f->prims[0].source_vertex_count = 5;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_SOURCE_VERTEX_COUNT, 0, 0, 0, 4, 5});
    f->prims[1].triangle_count = 1;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_TRIANGLE_COUNT, 1, 0, 0, 2, 1});
    /* triangle 1, corner 2 is source vertex 3; the mesh says 1 (in range, another vertex) */
    f->quad[5] = 1;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_CORNER, 0, 1, 2, 3, 1});
    /* the winding a mirroring node gives: corners 1 and 2 swapped */
    f->quad[1] = 2, f->quad[2] = 1;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_CORNER, 0, 0, 1, 1, 2});
    f->flat[3] = 2; /* the flat primitive's triangle 1, corner 0 */
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_CORNER, 1, 1, 0, 1, 2});
}

/* §16.4's order: a primitive with NORMAL ascending by source vertex, one without one new vertex
 * per corner in corner order. The flag decides which rule applies. */
static void vertex_order(void **state)
{
    fixture *f = *state;
    f->prims[1].flags = 0; /* the flat primitive's remap 2, 0, ... is not ascending */
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER, 1, 1, 0, 0, 2});
    f->prims[0].flags = LBK_LMUV_MESH_NO_NORMAL; /* 5 new vertices for 6 corners */
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER, 0, 0, 0, 5, 6});
    /* the quad with its seam vertices swapped (remap 0, 1, 2, 3, 2): same corners, wrong order */
    fixture g = {0};
    static const uint32_t remap[5] = {0, 1, 2, 3, 2}, idx[6] = {0, 1, 2, 0, 4, 3};
    build(&g, remap, idx, 5, quad_xy);
    mesh_reset(&g);
    check(&g, &g.generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER, 0, 4, 0, 2, 3});
    lbk_free(NULL, g.bytes);
    /* a quad without NORMAL, a vertex per corner but not in corner order (corner 1 uses vertex 2) */
    static const uint32_t remap6[6] = {0, 2, 1, 0, 2, 3}, idx6[6] = {0, 2, 1, 3, 4, 5};
    build(&g, remap6, idx6, 6, flat_xy);
    mesh_reset(&g);
    g.prims[0].flags = LBK_LMUV_MESH_NO_NORMAL;
    check(&g, &g.generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER, 0, 1, 0, 2, 1});
    /* nor is it for a primitive with NORMAL: remap 0, 2, 1 descends at new vertex 2 */
    check(&g, &g.generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER, 0, 2, 0, 1, 2});
    lbk_free(NULL, g.bytes);
}

static void callers_mistakes(void **state)
{
    fixture *f = *state;
    f->quad[4] = 4; /* source vertex 4 of a 4-vertex primitive */
    check(f, &f->generated, (expect){LBK_ERR_INVALID_ARGUMENT, LBK_LMUV_CHECK_MESH_CORNER, 0, 1, 1, 0, 4});
    f->quad[0] = UINT32_MAX;
    check(f, &f->generated, (expect){LBK_ERR_INVALID_ARGUMENT, LBK_LMUV_CHECK_MESH_CORNER, 0, 0, 0, 0, UINT32_MAX});
    f->prims[1].flags = 6;
    check(f, &f->generated, (expect){LBK_ERR_INVALID_ARGUMENT, LBK_LMUV_CHECK_MESH_FLAGS, 1, 0, 0, 0, 6});
    f->prims[1].corners = NULL;
    check(f, &f->generated, (expect){LBK_ERR_INVALID_ARGUMENT, LBK_LMUV_CHECK_MESH_CORNER, 1, 0, 0, 0, 0});
    lbk_lmuv_check_detail d;
    assert_int_equal(lbk_lmuv_object_check(NULL, &f->generated, &f->mesh, &d), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_lmuv_object_check(&f->view, NULL, &f->mesh, &d), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_lmuv_object_check(&f->view, &f->generated, NULL, &d), LBK_ERR_INVALID_ARGUMENT);
    f->mesh.primitives = NULL;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &f->generated, &f->mesh, &d), LBK_ERR_INVALID_ARGUMENT);
    mesh_reset(f);
    lbk_lmuv_object odd = f->generated;
    odd.kind = 2;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &odd, &f->mesh, &d), LBK_ERR_INVALID_ARGUMENT);
    /* size-tagged: 0 reads as the first layout, too small is refused, a larger struct passes
     * when its unknown bytes are zero */
    f->mesh.size = 0;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &f->generated, &f->mesh, &d), LBK_OK);
    f->mesh.size = sizeof(size_t) + 4;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &f->generated, &f->mesh, &d), LBK_ERR_INVALID_ARGUMENT);
    struct {
        lbk_lmuv_mesh_desc m;
        uint64_t later;
    } big = {f->mesh, 0};
    big.m.size = sizeof big;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &f->generated, &big.m, &d), LBK_OK);
    big.later = 1;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &f->generated, &big.m, &d), LBK_ERR_UNSUPPORTED_FEATURE);
}

/* Counts no real mesh has, behind arrays of two: refused on the counts, nothing read past them. */
static void hostile_counts(void **state)
{
    fixture *f = *state;
    f->mesh.primitive_count = UINT32_MAX;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_PRIMITIVE_COUNT, 0, 0, 0, 2, UINT32_MAX});
    f->prims[0].triangle_count = UINT32_MAX; /* 3 × that would wrap to 0xFFFFFFFD in 32 bits */
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_TRIANGLE_COUNT, 0, 0, 0, 2, UINT32_MAX});
    f->prims[0].triangle_count = 0x55555556u; /* 3 × that is 2^32 + 2: compared in 64 bits */
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_TRIANGLE_COUNT, 0, 0, 0, 2, 0x55555556u});
    f->prims[1].source_vertex_count = UINT32_MAX;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_SOURCE_VERTEX_COUNT, 1, 0, 0, 3, UINT32_MAX});
    f->mesh.source_node = UINT32_MAX;
    check(f, &f->generated, (expect){LBK_ERR_MISMATCH, LBK_LMUV_CHECK_NODE, 0, 0, 0, 7, UINT32_MAX});
}

/* A record or view that lbk_lmuv_open did not check (made by hand): LBK_ERR_RANGE, no read out
 * of the section. */
static void unchecked_views(void **state)
{
    fixture *f = *state;
    lbk_lmuv_check_detail d;
    lbk_lmuv_object r = f->generated;
    r.primitive_first = 1; /* primitives 1..2 of a 2-primitive table */
    assert_int_equal(lbk_lmuv_object_check(&f->view, &r, &f->mesh, &d), LBK_ERR_RANGE);
    r.primitive_first = UINT32_MAX;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &r, &f->mesh, &d), LBK_ERR_RANGE);
    r = f->generated;
    r.primitive_count = 0;
    f->mesh.primitive_count = 0;
    assert_int_equal(lbk_lmuv_object_check(&f->view, &r, &f->mesh, &d), LBK_ERR_RANGE);
    mesh_reset(f);
    /* an index past its primitive's vertices, written after the view was opened */
    uint8_t *copy = malloc(f->size);
    assert_non_null(copy);
    memcpy(copy, f->bytes, f->size);
    lbk_lmuv_view v = f->view;
    v.indices = copy + (f->view.indices - (const uint8_t *)f->bytes);
    v.remap = copy + (f->view.remap - (const uint8_t *)f->bytes);
    const uint32_t bad = 0x7fffffffu;
    memcpy(copy + (f->view.indices - (const uint8_t *)f->bytes) + 4 * 4, &bad, 4); /* quad index 4 */
    assert_int_equal(lbk_lmuv_object_check(&v, &f->generated, &f->mesh, &d), LBK_ERR_RANGE);
    /* a view whose counts are smaller than the record's primitive ranges */
    v = f->view;
    v.vertex_count = 5;
    assert_int_equal(lbk_lmuv_object_check(&v, &f->generated, &f->mesh, &d), LBK_ERR_RANGE);
    free(copy);
}

static void names(void **state)
{
    (void)state;
    const char *seen[LBK_LMUV_CHECK_CODE_COUNT_];
    for (uint32_t c = 0; c < LBK_LMUV_CHECK_CODE_COUNT_; c++) {
        seen[c] = lbk_lmuv_check_code_name(c);
        assert_int_equal(strncmp(seen[c], "LBK_LMUV_CHECK_", 15), 0);
        for (uint32_t k = 0; k < c; k++) assert_string_not_equal(seen[k], seen[c]);
    }
    assert_string_equal(lbk_lmuv_check_code_name(LBK_LMUV_CHECK_CORNER), "LBK_LMUV_CHECK_CORNER");
    assert_string_equal(lbk_lmuv_check_code_name(LBK_LMUV_CHECK_CODE_COUNT_), "LBK_LMUV_CHECK_UNKNOWN");
    assert_string_equal(lbk_result_name(LBK_ERR_MISMATCH), "LBK_ERR_MISMATCH");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(the_mesh_passes, setup, teardown),
        cmocka_unit_test_setup_teardown(each_difference, setup, teardown),
        cmocka_unit_test_setup_teardown(vertex_order, setup, teardown),
        cmocka_unit_test_setup_teardown(callers_mistakes, setup, teardown),
        cmocka_unit_test_setup_teardown(hostile_counts, setup, teardown),
        cmocka_unit_test_setup_teardown(unchecked_views, setup, teardown),
        cmocka_unit_test(names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
