/* LMUV (spec/container.md §16): builder → view round trip, a clean container through
 * lbk_validate_memory, every rule of IDs 1100–1119 caught on a deliberately broken copy, the
 * builder's refusals, hostile bytes (every bit flipped, every truncation, absurd counts: no
 * crash, and whatever the validator accepts the view opens), and the version/order rules of a
 * 1.1 file. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/lightmap_uv.h"
#include "lbk/objects.h"
#include "lbk/validate.h"

/* ---- the fixture: OBJS (4 objects, 3 lightmapped), one 64×64 LMAP page, LMUV -------------- */

static const uint32_t remap0[4] = {0, 1, 2, 3}, idx0[6] = {0, 1, 2, 0, 2, 3};
static const float xy0[8] = {33, 1, 63, 1, 63, 15, 33, 15};
static const uint32_t remap1[6] = {0, 1, 2, 0, 1, 2}, idx1[6] = {0, 1, 2, 3, 4, 5};
static const float xy1[12] = {40, 2, 50, 2, 45, 10, 52, 2, 60, 2, 56, 12};
static const uint32_t remap2[3] = {2, 0, 1}, idx2[3] = {0, 1, 2};
static const float xy2[6] = {1.5f, 33.5f, 14.5f, 33.5f, 8, 46};

static lbk_lmuv_primitive_desc prims_a[2], prims_b[1];
static lbk_lmuv_object_desc records[3];

static void fixture_records(void)
{
    memset(prims_a, 0, sizeof prims_a);
    memset(prims_b, 0, sizeof prims_b);
    memset(records, 0, sizeof records);
    prims_a[0] = (lbk_lmuv_primitive_desc){0, 4, 4, 6, remap0, idx0, xy0};
    prims_a[1] = (lbk_lmuv_primitive_desc){2, 3, 6, 6, remap1, idx1, xy1};
    prims_b[0] = (lbk_lmuv_primitive_desc){1, 3, 3, 3, remap2, idx2, xy2};
    records[0].object = 0; /* authored: [0,1]² → [1, 31]² inside rect (0,0 32×32) */
    records[0].kind = LBK_LMUV_AUTHORED;
    records[0].source_node = 5;
    records[0].scale[0] = records[0].scale[1] = 30;
    records[0].offset[0] = records[0].offset[1] = 1;
    records[0].uv_max[0] = records[0].uv_max[1] = 1;
    records[1].object = 2; /* generated, rect (32,0 32×16) */
    records[1].kind = LBK_LMUV_GENERATED;
    records[1].source_node = 7;
    records[1].primitive_count = 2;
    records[1].primitives = prims_a;
    records[2].object = 3; /* generated, rect (0,32 16×16) */
    records[2].kind = LBK_LMUV_GENERATED;
    records[2].source_node = 9;
    records[2].primitive_count = 1;
    records[2].primitives = prims_b;
}

/* Offsets of the fixture's arrays (§16.2): 3 records at 32, 3 primitives at align16(200) = 208,
 * 13 remap entries at 304, 15 indices at align16(356) = 368, coordinates at align16(428) = 432,
 * the end at 432 + 13·8 = 536. */
enum { REC = 32, PRIM = 208, REMAP = 304, INDICES = 368, COORDS = 432, SIZE = 536 };

/* Bytes whose every flip the validator must see: the header, the records' object, kind, ranges
 * and reserved word, the primitives' counts and firsts, the padding. (Not: source nodes and
 * primitives, authored floats, remap entries and indices that stay in range, coordinates.) */
static int structural(size_t at)
{
    if (at < REC) return 1;
    if (at < REC + 3 * 56) {
        const size_t off = (at - REC) % 56;
        return off < 8 || (off >= 12 && off < 24);
    }
    if (at < PRIM) return 1;
    if (at < PRIM + 3 * 32) return (at - PRIM) % 32 >= 8;
    return (at >= REMAP + 52 && at < INDICES) || (at >= INDICES + 60 && at < COORDS);
}

static void build_lmuv(uint8_t **out, size_t *size)
{
    fixture_records();
    void *d;
    assert_int_equal(lbk_lmuv_build(records, 3, NULL, &d, size), LBK_OK);
    *out = d;
}

/* A container: OBJS + LMAP (+ LMUV bytes if given, + an extra section if given). */
static void container(const uint8_t *lmuv, size_t lmuv_size, int with_objs, uint32_t extra, void **out, size_t *size)
{
    lbk_object o[4];
    memset(o, 0, sizeof o);
    const char *names[4] = {"wall", "prop", "floor", "lamp"};
    for (int i = 0; i < 4; i++) o[i].name = (lbk_string){names[i], strlen(names[i])};
    o[1].representation = LBK_REPRESENTATION_NONE;
    o[0].rect_w = o[0].rect_h = 32;
    o[2].rect_x = 32, o[2].rect_w = 32, o[2].rect_h = 16;
    o[3].rect_y = 32, o[3].rect_w = o[3].rect_h = 16;
    static lbk_ahd_texel texels[64 * 64];
    lbk_lmap_page_desc pg = {64, 64, texels};
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    void *d;
    size_t n;
    lbk_section_options so = {0};
    if (with_objs) {
        assert_int_equal(lbk_objects_build(o, 4, NULL, &d, &n), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_OBJS, d, n, &so), LBK_OK);
        lbk_free(NULL, d);
    }
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = &pg, .page_count = 1}, NULL, &d, &n), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, d, n, &so), LBK_OK);
    lbk_free(NULL, d);
    if (lmuv) assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMUV, lmuv, lmuv_size, &so), LBK_OK);
    static const uint8_t xtra[16] = {1};
    if (extra) assert_int_equal(lbk_writer_section_add(w, extra, xtra, sizeof xtra, &so), LBK_OK);
    assert_int_equal(lbk_writer_to_memory(w, out, size), LBK_OK);
    lbk_writer_close(w);
}

typedef struct issues {
    uint32_t id[512];
    lbk_severity sev[512];
    int n;
} issues;

static int collect(void *user, const lbk_issue *issue)
{
    issues *is = user;
    if (is->n < 512) {
        is->id[is->n] = issue->id;
        is->sev[is->n] = issue->severity;
        is->n++;
    }
    return 0;
}

static int has(const issues *is, uint32_t id)
{
    for (int i = 0; i < is->n; i++)
        if (is->id[i] == id) return 1;
    return 0;
}

/* Validates a container holding these LMUV bytes; returns the summary. */
static lbk_validate_summary validate_lmuv(const uint8_t *lmuv, size_t size, int with_objs, issues *is)
{
    void *f;
    size_t n;
    container(lmuv, size, with_objs, 0, &f, &n);
    memset(is, 0, sizeof *is);
    lbk_validate_summary sum;
    assert_int_equal(lbk_validate_memory(f, n, NULL, collect, is, &sum), LBK_OK);
    lbk_free(NULL, f);
    return sum;
}

/* ---- tests ------------------------------------------------------------------------------------ */

static void round_trip(void **state)
{
    (void)state;
    uint8_t *d;
    size_t n;
    build_lmuv(&d, &n);
    assert_int_equal(n, SIZE);
    lbk_lmuv_view v;
    assert_int_equal(lbk_lmuv_open(d, n, &v), LBK_OK);
    assert_int_equal(v.record_count, 3);
    assert_int_equal(v.primitive_count, 3);
    assert_int_equal(v.vertex_count, 13);
    assert_int_equal(v.index_count, 15);
    assert_ptr_equal(v.primitives, d + PRIM);
    assert_ptr_equal(v.coords, d + COORDS);
    lbk_lmuv_object o;
    assert_int_equal(lbk_lmuv_get_object(&v, 0, &o), LBK_OK);
    assert_int_equal(o.kind, LBK_LMUV_AUTHORED);
    assert_int_equal(o.source_node, 5);
    assert_true(o.scale[0] == 30 && o.offset[1] == 1 && o.uv_max[0] == 1 && o.uv_min[1] == 0);
    assert_int_equal(lbk_lmuv_get_object(&v, 3, &o), LBK_ERR_NOT_FOUND);
    uint32_t r;
    assert_int_equal(lbk_lmuv_find_object(&v, 2, &r), LBK_OK);
    assert_int_equal(r, 1);
    assert_int_equal(lbk_lmuv_find_object(&v, 3, &r), LBK_OK);
    assert_int_equal(r, 2);
    assert_int_equal(lbk_lmuv_find_object(&v, 1, &r), LBK_ERR_NOT_FOUND);
    /* every array element comes back */
    const lbk_lmuv_primitive_desc *want[3] = {&prims_a[0], &prims_a[1], &prims_b[0]};
    for (uint32_t p = 0; p < 3; p++) {
        lbk_lmuv_primitive q;
        assert_int_equal(lbk_lmuv_get_primitive(&v, p, &q), LBK_OK);
        assert_int_equal(q.source_primitive, want[p]->source_primitive);
        assert_int_equal(q.source_vertex_count, want[p]->source_vertex_count);
        assert_int_equal(q.vertex_count, want[p]->vertex_count);
        for (uint32_t k = 0; k < q.vertex_count; k++) {
            uint32_t src;
            float xy[2];
            assert_int_equal(lbk_lmuv_vertex(&v, &q, k, &src, xy), LBK_OK);
            assert_int_equal(src, want[p]->remap[k]);
            assert_true(xy[0] == want[p]->coords[2 * k] && xy[1] == want[p]->coords[2 * k + 1]);
        }
        for (uint32_t k = 0; k < q.index_count; k++) {
            uint32_t ix;
            assert_int_equal(lbk_lmuv_index(&v, &q, k, &ix), LBK_OK);
            assert_int_equal(ix, want[p]->indices[k]);
        }
        assert_int_equal(lbk_lmuv_index(&v, &q, q.index_count, &r), LBK_ERR_RANGE);
        q.index_first = v.index_count; /* a hand-made primitive outside the view */
        assert_int_equal(lbk_lmuv_index(&v, &q, 0, &r), LBK_ERR_RANGE);
    }
    /* the same content gives the same bytes */
    uint8_t *d2;
    size_t n2;
    build_lmuv(&d2, &n2);
    assert_memory_equal(d, d2, n);
    lbk_free(NULL, d2);
    /* and validates clean in a container */
    issues is;
    lbk_validate_summary s = validate_lmuv(d, n, 1, &is);
    if (is.n) fail_msg("clean LMUV: issue %u", is.id[0]);
    assert_int_equal(s.errors + s.warnings + s.fatal, 0);
    lbk_free(NULL, d);
}

/* §16.1, §16.3: the binary32 rule, the texel of a coordinate, normalised uv. */
static void the_rule(void **state)
{
    (void)state;
    lbk_lmuv_object o;
    memset(&o, 0, sizeof o);
    o.scale[0] = 100.0f, o.scale[1] = 50.0f;
    o.offset[0] = 3.25f, o.offset[1] = -0.5f;
    const float uv[2] = {0.5f, 0.25f};
    float xy[2];
    lbk_lmuv_authored_coord(&o, uv, xy);
    assert_true(xy[0] == 53.25f && xy[1] == 12.0f);
    /* two roundings, never an FMA: 1/3·3 rounds to 1 first, then + 2^-24 is lost in the sum */
    o.scale[0] = 3.0f, o.offset[0] = 1.0f;
    const float third[2] = {1.0f / 3.0f, 0};
    lbk_lmuv_authored_coord(&o, third, xy);
    assert_true(xy[0] == (float)(1.0f + (float)(3.0f * (1.0f / 3.0f))));
    int64_t x, y;
    const float c[2] = {12.0f, 12.999999f};
    lbk_lmuv_texel_of(c, &x, &y);
    assert_true(x == 12 && y == 12); /* texel 12 covers [12, 13) */
    const float neg[2] = {-0.25f, NAN};
    lbk_lmuv_texel_of(neg, &x, &y);
    assert_true(x == -1 && y < -((int64_t)1 << 61)); /* NaN clamps, never UB */
    const float huge[2] = {1e30f, -1e30f};
    lbk_lmuv_texel_of(huge, &x, &y);
    assert_true(x == (int64_t)1 << 62 && y == -((int64_t)1 << 62));
    /* texel centres: ((x + 1/2)/w, (y + 1/2)/h) */
    const float centre[2] = {10.5f, 3.5f};
    float n[2];
    lbk_lmuv_normalized(centre, 64, 16, n);
    assert_true(n[0] == 10.5f / 64 && n[1] == 3.5f / 16);
    assert_string_equal(lbk_lmuv_kind_name(LBK_LMUV_GENERATED), "generated");
    assert_string_equal(lbk_lmuv_kind_name(9), "unknown");
}

static void builder_refuses(void **state)
{
    (void)state;
    void *d;
    size_t n;
#define REFUSE(edit)                                                                            \
    do {                                                                                        \
        fixture_records();                                                                      \
        edit;                                                                                   \
        assert_int_equal(lbk_lmuv_build(records, 3, NULL, &d, &n), LBK_ERR_INVALID_ARGUMENT);   \
        assert_null(d);                                                                         \
    } while (0)
    REFUSE(records[1].object = 0);                      /* not ascending */
    REFUSE(records[2].kind = 2);                        /* unknown kind */
    REFUSE(records[0].primitive_count = 1);             /* authored with primitives */
    REFUSE(records[0].scale[1] = 0);                    /* scale <= 0 */
    REFUSE(records[0].offset[0] = NAN);                 /* not finite */
    REFUSE(records[0].uv_min[0] = 2);                   /* box inverted */
    REFUSE(records[1].scale[0] = 1);                    /* generated with an authored field */
    REFUSE(records[2].primitive_count = 0);             /* generated without primitives */
    REFUSE(prims_a[1].source_primitive = 0);            /* primitives not ascending */
    REFUSE(prims_a[0].index_count = 5);                 /* not a multiple of 3 */
    REFUSE(prims_a[0].vertex_count = 0);                /* empty */
    REFUSE(prims_b[0].source_vertex_count = 2);         /* remap 2 >= 2 */
    static const uint32_t bad_idx[3] = {0, 1, 3};
    REFUSE(prims_b[0].indices = bad_idx);               /* index 3 >= 3 vertices */
    static const float nan_xy[6] = {1, 1, NAN, 1, 2, 2};
    REFUSE(prims_b[0].coords = nan_xy);
#undef REFUSE
    fixture_records();
    assert_int_equal(lbk_lmuv_build(records, 0, NULL, &d, &n), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_lmuv_build(NULL, 1, NULL, &d, &n), LBK_ERR_INVALID_ARGUMENT);
    /* -0 is stored as +0: one content, one encoding */
    records[0].uv_min[0] = -0.0f;
    assert_int_equal(lbk_lmuv_build(records, 3, NULL, &d, &n), LBK_OK);
    assert_int_equal(((const uint8_t *)d)[REC + 40 + 3], 0);
    lbk_free(NULL, d);
}

static void wr32(uint8_t *p, uint32_t v) { p[0] = (uint8_t)v, p[1] = (uint8_t)(v >> 8), p[2] = (uint8_t)(v >> 16), p[3] = (uint8_t)(v >> 24); }
static void wrf(uint8_t *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    wr32(p, u);
}

typedef struct rule {
    const char *what;
    void (*edit)(uint8_t *d);
    uint32_t id;
    int open_ok; /* lbk_lmuv_open still accepts the bytes (a rule only the validator can see) */
} rule;

static void e_reserved(uint8_t *d) { d[24] = 1; }
static void e_padding(uint8_t *d) { d[REC + 3 * 56 + 2] = 7; }
static void e_no_records(uint8_t *d) { wr32(d, 0); }
static void e_verts(uint8_t *d) { wr32(d + 8, 14); }
static void e_prims(uint8_t *d) { wr32(d + 4, 2); }
static void e_order(uint8_t *d) { wr32(d + REC + 56, 0); }
static void e_range(uint8_t *d) { wr32(d + REC + 112, 9); }
static void e_not_lm(uint8_t *d) { wr32(d + REC + 56, 1); }
static void e_kind(uint8_t *d) { wr32(d + REC + 112 + 4, 7); }
static void e_unused_auth(uint8_t *d) { wr32(d + REC + 20, 1); }
static void e_unused_gen(uint8_t *d) { wrf(d + REC + 56 + 24, 1.0f); }
static void e_scale(uint8_t *d) { wrf(d + REC + 24, 0.0f); }
static void e_offset_nan(uint8_t *d) { wrf(d + REC + 32, NAN); }
static void e_box(uint8_t *d) { wrf(d + REC + 32, 10.0f); }
static void e_node(uint8_t *d) { wr32(d + REC + 112 + 8, 7); }
static void e_rec_first(uint8_t *d) { wr32(d + REC + 112 + 12, 1); }
static void e_prim_first(uint8_t *d) { wr32(d + PRIM + 32 + 16, 3); }
static void e_prim_order(uint8_t *d) { wr32(d + PRIM + 32, 0); }
static void e_index(uint8_t *d) { wr32(d + INDICES + 4 * 7, 9); }
static void e_remap(uint8_t *d) { wr32(d + REMAP + 4 * 3, 4); }
static void e_coord(uint8_t *d) { wrf(d + COORDS, 5.0f); }
static void e_coord_nan(uint8_t *d) { wrf(d + COORDS + 8 * 12 + 4, NAN); }
static void e_unused_vertex(uint8_t *d) { wr32(d + INDICES + 4 * 9, 0), wr32(d + INDICES + 4 * 10, 1), wr32(d + INDICES + 4 * 11, 2); }

static void rules(void **state)
{
    (void)state;
    const rule rs[] = {
        {"header reserved", e_reserved, 1101, 0},
        {"padding after the records", e_padding, 1101, 1},
        {"no records", e_no_records, 1102, 0},
        {"vertex count vs size", e_verts, 1103, 0},
        {"primitive count vs records", e_prims, 1103, 0},
        {"objects not ascending", e_order, 1105, 1},
        {"object out of range", e_range, 1105, 1},
        {"object not lightmapped", e_not_lm, 1106, 1},
        {"unknown kind", e_kind, 1107, 0},
        {"authored reserved", e_unused_auth, 1101, 1},
        {"generated with a scale", e_unused_gen, 1108, 1},
        {"authored scale 0", e_scale, 1109, 1},
        {"authored offset NaN", e_offset_nan, 1109, 1},
        {"authored box outside the rect", e_box, 1110, 1},
        {"two records, one node", e_node, 1111, 1},
        {"record primitive_first", e_rec_first, 1112, 0},
        {"primitive vertex_first", e_prim_first, 1112, 0},
        {"source primitives not ascending", e_prim_order, 1113, 1},
        {"index out of range", e_index, 1114, 0},
        {"remap out of range", e_remap, 1115, 0},
        {"coordinate outside the rect", e_coord, 1116, 1},
        {"coordinate NaN", e_coord_nan, 1116, 1},
        {"vertex used by no triangle", e_unused_vertex, 1117, 1},
    };
    uint8_t *d;
    size_t n;
    build_lmuv(&d, &n);
    uint8_t *c = malloc(n);
    for (size_t i = 0; i < sizeof rs / sizeof rs[0]; i++) {
        memcpy(c, d, n);
        rs[i].edit(c);
        issues is;
        lbk_validate_summary s = validate_lmuv(c, n, 1, &is);
        if (!has(&is, rs[i].id)) fail_msg("%s: expected issue %u (got %d issues, first %u)", rs[i].what, rs[i].id, is.n, is.n ? is.id[0] : 0);
        for (int k = 0; k < is.n; k++)
            if (is.id[k] < 1100 || is.id[k] > 1119) fail_msg("%s: issue %u outside LMUV's block", rs[i].what, is.id[k]);
        if (rs[i].id == 1117) assert_int_equal(s.errors + s.fatal, 0); /* a warning: still valid */
        else assert_true(s.errors > 0);
        lbk_lmuv_view v;
        lbk_result r = lbk_lmuv_open(c, n, &v);
        if ((r == LBK_OK) != rs[i].open_ok) fail_msg("%s: lbk_lmuv_open gave %s", rs[i].what, lbk_result_name(r));
    }
    free(c);
    /* a lightmapped object without a record: warning 1118 */
    fixture_records();
    void *two;
    size_t tn;
    assert_int_equal(lbk_lmuv_build(records, 2, NULL, &two, &tn), LBK_OK);
    issues is;
    lbk_validate_summary s = validate_lmuv(two, tn, 1, &is);
    assert_true(has(&is, 1118) && s.errors == 0 && s.warnings == 1);
    lbk_free(NULL, two);
    /* no OBJS: 1119, and no rectangle can be checked */
    s = validate_lmuv(d, n, 0, &is);
    assert_true(has(&is, 1119));
    assert_false(has(&is, 1116));
    /* shorter than the header */
    s = validate_lmuv(d, 31, 1, &is);
    assert_true(has(&is, 1100) && s.errors == 1);
    lbk_free(NULL, d);
}

/* Untrusted bytes: every bit of the section flipped, every truncation, absurd counts. Nothing
 * may crash (ASan), and the view must open whenever the validator finds no error. */
static void hostile(void **state)
{
    (void)state;
    uint8_t *d;
    size_t n;
    build_lmuv(&d, &n);
    uint8_t *c = malloc(n);
    size_t opened = 0, rejected = 0;
    for (size_t bit = 0; bit < 8 * n; bit++) {
        memcpy(c, d, n);
        c[bit / 8] ^= (uint8_t)(1u << (bit % 8));
        issues is;
        lbk_validate_summary s = validate_lmuv(c, n, 1, &is);
        lbk_lmuv_view v;
        const lbk_result r = lbk_lmuv_open(c, n, &v);
        if (s.errors == 0 && s.fatal == 0 && r != LBK_OK)
            fail_msg("bit %zu: valid for lbk_validate but lbk_lmuv_open says %s", bit, lbk_result_name(r));
        if (r == LBK_OK) {
            opened++;
            for (uint32_t p = 0; p < v.primitive_count; p++) { /* everything the view promises is readable */
                lbk_lmuv_primitive q;
                assert_int_equal(lbk_lmuv_get_primitive(&v, p, &q), LBK_OK);
                for (uint32_t k = 0; k < q.index_count; k++) {
                    uint32_t ix;
                    assert_int_equal(lbk_lmuv_index(&v, &q, k, &ix), LBK_OK);
                    assert_true(ix < q.vertex_count);
                }
                for (uint32_t k = 0; k < q.vertex_count; k++) {
                    uint32_t src;
                    float xy[2];
                    assert_int_equal(lbk_lmuv_vertex(&v, &q, k, &src, xy), LBK_OK);
                    assert_true(src < q.source_vertex_count);
                }
            }
        } else {
            rejected++;
        }
        if (s.errors == 0 && s.fatal == 0 && structural(bit / 8))
            fail_msg("bit %zu (byte %zu) flipped without an error", bit, bit / 8);
    }
    print_message("LMUV bit flips: %zu of %zu opened, %zu rejected by lbk_lmuv_open\n", opened, 8 * n, rejected);
    for (size_t len = 1; len < n; len++) { /* a section has at least one byte (§3.1) */
        issues is;
        lbk_validate_summary s = validate_lmuv(d, len, 1, &is);
        assert_true(s.errors > 0);
        lbk_lmuv_view v;
        assert_int_not_equal(lbk_lmuv_open(d, len, &v), LBK_OK);
    }
    /* counts whose sizes overflow 64 bits or point far outside the section */
    const uint64_t absurd[4][2] = {{0xffffffffu, 0xffffffffu}, {1, UINT64_MAX}, {1, UINT64_MAX / 8}, {3, 1ull << 61}};
    for (int k = 0; k < 4; k++) {
        memcpy(c, d, n);
        wr32(c, (uint32_t)absurd[k][0]);
        for (int b = 0; b < 8; b++) c[8 + b] = (uint8_t)(absurd[k][1] >> (8 * b));
        issues is;
        validate_lmuv(c, n, 1, &is);
        assert_true(has(&is, 1103));
        lbk_lmuv_view v;
        assert_int_not_equal(lbk_lmuv_open(c, n, &v), LBK_OK);
    }
    free(c);
    lbk_free(NULL, d);
}

/* §1.3: a file with LMUV is 1.1, one without stays 1.0 byte for byte; §3.2: LMUV sorts after the
 * 1.0 types by code, like any type a 1.0 reader does not know, so a 1.0 reader accepts the order. */
static void version_and_order(void **state)
{
    (void)state;
    uint8_t *d;
    size_t n;
    build_lmuv(&d, &n);
    void *f;
    size_t fn;
    container(d, n, 1, 0, &f, &fn);
    assert_int_equal(((const uint8_t *)f)[10], 1); /* version_minor */
    lbk_free(NULL, f);
    container(NULL, 0, 1, 0, &f, &fn);
    assert_int_equal(((const uint8_t *)f)[10], 0);
    lbk_free(NULL, f);
    const uint32_t before = LBK_FOURCC('A', 'B', 'C', 'D'), after = LBK_FOURCC('X', 'T', 'R', 'Z');
    assert_true(before < LBK_SECTION_LMUV && after > LBK_SECTION_LMUV);
    for (int k = 0; k < 2; k++) {
        const uint32_t other = k ? after : before;
        container(d, n, 1, other, &f, &fn);
        lbk_reader *rd;
        assert_int_equal(lbk_reader_open_memory(f, fn, NULL, &rd), LBK_OK);
        uint32_t at_lmuv, at_other;
        assert_int_equal(lbk_reader_section_find(rd, LBK_SECTION_LMUV, &at_lmuv), LBK_OK);
        assert_int_equal(lbk_reader_section_find(rd, other, &at_other), LBK_OK);
        assert_true(k ? at_lmuv < at_other : at_other < at_lmuv); /* ascending code among the non-1.0 types */
        lbk_reader_close(rd);
        issues is;
        memset(&is, 0, sizeof is);
        lbk_validate_summary s;
        assert_int_equal(lbk_validate_memory(f, fn, NULL, collect, &is, &s), LBK_OK);
        assert_int_equal(s.errors, 0);
        assert_true(has(&is, 213) && !has(&is, 202)); /* only the unknown one is "skipped" */
        assert_int_equal(s.warnings, 1);
        lbk_free(NULL, f);
    }
    lbk_free(NULL, d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(round_trip), cmocka_unit_test(the_rule), cmocka_unit_test(builder_refuses),
        cmocka_unit_test(rules),      cmocka_unit_test(hostile),  cmocka_unit_test(version_and_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
