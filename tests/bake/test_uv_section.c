/* LMUV from the baker (bake/pipeline/uv_section.c) against the baker's own placement:
 *  - the texel rule (spec/container.md §16.1): for every texel the baker lit, the lightmap
 *    coordinate the section gives for the texel's sample point (barycentric interpolation of the
 *    section's per-vertex coordinates, as a GPU does) lies in that texel, and at its centre when
 *    the sample was the centre; authored objects through scale + offset of TEXCOORD_1 (§16.3);
 *  - generated objects rebuilt as an engine would (§16.4): the new index buffer's source corners
 *    are the glTF primitive's triangles in its own winding, also under a mirroring node, for
 *    flat-shaded primitives and strips with restarts, with the points primitive left out; and
 *    every record passes liblbk's check of a record against its mesh (lbk_lmuv_object_check,
 *    vertex order included) fed from the glTF's own triangles and, through the readers' adapter,
 *    from the imported scene;
 *  - the tangent frame of lbk/ahd.h (§5.6) is the baker's, bit for bit.
 * Levels: a hand-made one (tests/support/lmuv_scene.h) and the shared cornell_box_bjs (authored
 * and generated objects mixed) and cornell_box (no UVs at all). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bake/layout/atlas.h"
#include "bake/layout/classify.h"
#include "bake/layout/texels.h"
#include "bake/pipeline/uv_section.h"
#include "scene/import.h"
#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/lightmap_uv.h"
#include "support/lmuv_scene.h"
#include "support/scenes_dir.h"
#include "tools/common/lmuv_match.h"

/* Everything the rule check needs: the scene, the baker's layout, and the section. */
typedef struct level {
    bk_scene scene;
    bk_object_class *classes;
    bk_atlas atlas;
    bk_texels texels;
    void *bytes;
    size_t size;
    lbk_lmuv_view view;
} level;

/* Import, classify, atlas, texels, section — as bake.c does_layout (no push-out: the test wants
 * the sample points the rasteriser chose). */
static int level_open(const char *path, float density, level *l)
{
    memset(l, 0, sizeof *l);
    char err[512];
    if (bk_import_gltf(path, NULL, &l->scene, err, sizeof err)) {
        print_message("import %s: %s\n", path, err);
        return -1;
    }
    const bk_scene *s = &l->scene;
    l->classes = calloc(s->object_count, sizeof *l->classes);
    uint8_t *lm = calloc(s->object_count, 1);
    assert_non_null(l->classes);
    assert_non_null(lm);
    assert_int_equal(bk_classify_objects(s, NULL, l->classes), LBK_OK);
    for (size_t i = 0; i < s->object_count; i++) lm[i] = l->classes[i].rep == BK_REP_LIGHTMAP;
    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.default_density = density;
    assert_int_equal(bk_atlas_build(s, lm, &ao, &l->atlas), LBK_OK);
    free(lm);
    assert_int_equal(bk_texels_build(s, &l->atlas, &l->texels), LBK_OK);
    assert_int_equal(bk_uv_section_build(s, &l->atlas, l->classes, &l->bytes, &l->size), LBK_OK);
    assert_non_null(l->bytes);
    assert_int_equal(lbk_lmuv_open(l->bytes, l->size, &l->view), LBK_OK);
    return 0;
}

static void level_close(level *l)
{
    lbk_free(NULL, l->bytes);
    bk_texels_free(&l->texels);
    bk_atlas_free(&l->atlas);
    free(l->classes);
    bk_scene_free(&l->scene);
}

/* The scene primitive holding triangle `tri`, and that primitive's index among its object's. */
static const bk_primitive *primitive_of(const bk_scene *s, uint32_t tri, uint32_t *k)
{
    for (size_t p = 0; p < s->primitive_count; p++) {
        const bk_primitive *q = &s->primitives[p];
        if (tri >= q->first_tri && tri - q->first_tri < q->tri_count) {
            *k = 0;
            while (p > *k && s->primitives[p - *k - 1].object == q->object) (*k)++;
            return q;
        }
    }
    return NULL;
}

static const int straight[3] = {0, 1, 2}, swapped[3] = {0, 2, 1};

/* The section's lightmap coordinates of a scene triangle's corners, in scene corner order. */
static void corner_coords(const level *l, uint32_t tri, float xy[3][2], int *authored)
{
    const bk_scene *s = &l->scene;
    const uint32_t object = s->tri_object[tri];
    uint32_t r;
    assert_int_equal(lbk_lmuv_find_object(&l->view, object, &r), LBK_OK);
    lbk_lmuv_object o;
    lbk_lmuv_get_object(&l->view, r, &o);
    *authored = o.kind == LBK_LMUV_AUTHORED;
    if (*authored) {
        for (int c = 0; c < 3; c++) lbk_lmuv_authored_coord(&o, &s->uv1[2 * (size_t)s->tris[3 * (size_t)tri + c]], xy[c]);
        return;
    }
    uint32_t k;
    const bk_primitive *p = primitive_of(s, tri, &k);
    assert_non_null(p);
    lbk_lmuv_primitive q;
    assert_int_equal(lbk_lmuv_get_primitive(&l->view, o.primitive_first + k, &q), LBK_OK);
    const int *order = s->objects[object].mirrored ? swapped : straight;
    for (int c = 0; c < 3; c++) {
        uint32_t v;
        assert_int_equal(lbk_lmuv_index(&l->view, &q, 3 * (tri - p->first_tri) + (uint32_t)order[c], &v), LBK_OK);
        assert_int_equal(lbk_lmuv_vertex(&l->view, &q, v, NULL, xy[c]), LBK_OK);
    }
}

/* Barycentric weights of world point x in a triangle (least squares in its plane, double). */
static void barycentric(const bk_scene *s, uint32_t tri, const float x[3], double w[3])
{
    double p[3][3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) p[k][c] = s->positions[3 * (size_t)s->tris[3 * (size_t)tri + k] + c];
    double e1[3], e2[3], d[3];
    for (int c = 0; c < 3; c++) e1[c] = p[1][c] - p[0][c], e2[c] = p[2][c] - p[0][c], d[c] = x[c] - p[0][c];
    double a = 0, b = 0, cc = 0, r1 = 0, r2 = 0;
    for (int c = 0; c < 3; c++) a += e1[c] * e1[c], b += e1[c] * e2[c], cc += e2[c] * e2[c], r1 += d[c] * e1[c], r2 += d[c] * e2[c];
    const double det = a * cc - b * b;
    w[1] = (cc * r1 - b * r2) / det;
    w[2] = (a * r2 - b * r1) / det;
    w[0] = 1 - w[1] - w[2];
}

typedef struct rule_stats {
    size_t texels, centres, edges, authored, outside;
    double max_centre_dev, max_outside; /* texels */
    double max_authored_dev;            /* baker placement vs the stored rule, texels */
} rule_stats;

/* §16.1 against every texel the baker placed. */
static rule_stats check_rule(const level *l)
{
    rule_stats st;
    memset(&st, 0, sizeof st);
    const double eps = 1.0 / 1024; /* binary32 rounding of the rule and of the sample point */
    for (size_t i = 0; i < l->texels.count; i++) {
        const bk_texel *t = &l->texels.receivers[i];
        float xy[3][2];
        int authored;
        corner_coords(l, t->tri, xy, &authored);
        double w[3];
        barycentric(&l->scene, t->tri, t->position, w);
        double X = 0, Y = 0;
        for (int c = 0; c < 3; c++) X += w[c] * xy[c][0], Y += w[c] * xy[c][1];
        st.texels++;
        st.authored += (size_t)authored;
        const double out = fmax(fmax(t->x - X, X - (t->x + 1.0)), fmax(t->y - Y, Y - (t->y + 1.0)));
        if (out > 0) st.outside++, st.max_outside = fmax(st.max_outside, out);
        /* a texel whose centre no triangle covers (EDGE) is baked at the triangle's closest point
         * to its centre; the triangle meets the open square of half-size 1 around the centre
         * (texels.h), so that point is within sqrt(2) of the centre: at most sqrt(2) - 1/2
         * outside the texel's own square */
        const double limit = (t->flags & BK_TEXEL_EDGE) ? sqrt(2.0) - 0.5 + eps : eps;
        if (out > limit) fail_msg("texel (%u, %u) of page %u: the section puts its sample at (%.6f, %.6f)", t->x, t->y, t->page, X, Y);
        if (!(t->flags & BK_TEXEL_EDGE)) {
            const double dev = fmax(fabs(X - (t->x + 0.5)), fabs(Y - (t->y + 0.5)));
            st.max_centre_dev = fmax(st.max_centre_dev, dev);
            if (dev > eps) fail_msg("texel (%u, %u): centre sample maps to (%.6f, %.6f)", t->x, t->y, X, Y);
            st.centres++;
        } else {
            st.edges++;
        }
    }
    /* the baker's own corner placement (atlas.tri_uv) against the stored rule */
    for (size_t e = 0; e < l->atlas.tri_count; e++) {
        float xy[3][2];
        int authored;
        corner_coords(l, l->atlas.tris[e], xy, &authored);
        for (int c = 0; c < 3; c++) {
            const double dx = fabs((double)l->atlas.tri_uv[6 * e + 2 * (size_t)c] - xy[c][0]);
            const double dy = fabs((double)l->atlas.tri_uv[6 * e + 2 * (size_t)c + 1] - xy[c][1]);
            if (authored) st.max_authored_dev = fmax(st.max_authored_dev, fmax(dx, dy));
            else if (dx != 0 || dy != 0) fail_msg("generated corner differs from the atlas by (%g, %g)", dx, dy);
        }
    }
    return st;
}

static void print_stats(const char *what, const rule_stats *st)
{
    print_message("%s: %zu texels (%zu authored), %zu centre samples max %.2e texel off the centre, %zu edge samples, "
                  "%zu outside their square by <= %.2e; authored placement vs rule <= %.2e texel\n",
                  what, st->texels, st->authored, st->centres, st->max_centre_dev, st->edges, st->outside,
                  st->max_outside, st->max_authored_dev);
}

/* §16.4 as an engine applies it: remap[new index] gives the source corners in glTF winding. */
static void check_rebuild(const level *l, size_t object, int expect_mirrored)
{
    const bk_scene *s = &l->scene;
    assert_int_equal(s->objects[object].mirrored, expect_mirrored);
    uint32_t r;
    assert_int_equal(lbk_lmuv_find_object(&l->view, (uint32_t)object, &r), LBK_OK);
    lbk_lmuv_object o;
    lbk_lmuv_get_object(&l->view, r, &o);
    assert_int_equal(o.kind, LBK_LMUV_GENERATED);
    assert_int_equal(o.source_node, s->objects[object].node);
    assert_int_equal(o.primitive_count, 3); /* the points primitive is not lightmapped */
    static const uint32_t want_prim[3] = {0, 2, 3}, want_vertices[3] = {9, 5, 8};
    for (uint32_t k = 0; k < 3; k++) {
        lbk_lmuv_primitive q;
        lbk_lmuv_get_primitive(&l->view, o.primitive_first + k, &q);
        assert_int_equal(q.source_primitive, want_prim[k]);
        assert_int_equal(q.source_vertex_count, want_vertices[k]);
        size_t nt;
        const uint32_t *tris = lmuv_scene_triangles(want_prim[k], &nt);
        assert_int_equal(q.index_count, 3 * nt);
        for (uint32_t i = 0; i < q.index_count; i++) {
            uint32_t v, src;
            lbk_lmuv_index(&l->view, &q, i, &v);
            lbk_lmuv_vertex(&l->view, &q, v, &src, NULL);
            if (src != tris[i]) fail_msg("object %zu primitive %u index %u: source vertex %u, the glTF has %u", object, want_prim[k], i, src, tris[i]);
        }
    }
    /* liblbk's check, fed from the glTF's own triangles (not the importer's): the baker's record
     * passes it, vertex order included (primitive 2 has no NORMAL: a new vertex per corner in
     * corner order; 0 and 3 ascending by source vertex), mirrored node or not */
    lbk_lmuv_mesh_primitive mp[3];
    for (uint32_t k = 0; k < 3; k++) {
        size_t nt;
        const uint32_t *tris = lmuv_scene_triangles(want_prim[k], &nt);
        mp[k] = (lbk_lmuv_mesh_primitive){.source_primitive = want_prim[k], .source_vertex_count = want_vertices[k],
                                          .triangle_count = (uint32_t)nt,
                                          .flags = want_prim[k] == 2 ? LBK_LMUV_MESH_NO_NORMAL : 0, .corners = tris};
    }
    lbk_lmuv_mesh_desc mesh = LBK_LMUV_MESH_DESC_INIT;
    mesh.source_node = o.source_node;
    mesh.primitive_count = 3;
    mesh.primitives = mp;
    lbk_lmuv_check_detail why;
    if (lbk_lmuv_object_check(&l->view, &o, &mesh, &why) != LBK_OK) fail_msg("object %zu: %s", object, why.message);
    mp[1].flags = 0; /* the flat primitive's remap is not ascending: the flag is what lets it pass */
    assert_int_equal(lbk_lmuv_object_check(&l->view, &o, &mesh, &why), LBK_ERR_MISMATCH);
    assert_int_equal(why.code, LBK_LMUV_CHECK_VERTEX_ORDER);
    /* and through the readers' adapter (the imported scene described as an engine would) */
    char err[TL_ERR_LEN];
    if (tl_lmuv_match_object(s, object, &l->view, &o, 4, err)) fail_msg("%s", err);
}

/* Every record of a level passes the readers' check (tools/common/lmuv_match.h over liblbk's
 * lbk_lmuv_object_check), vertex order included. */
static void check_all_records(const level *l)
{
    for (uint32_t r = 0; r < l->view.record_count; r++) {
        lbk_lmuv_object o;
        char err[TL_ERR_LEN];
        assert_int_equal(lbk_lmuv_get_object(&l->view, r, &o), LBK_OK);
        if (tl_lmuv_match_object(&l->scene, o.object, &l->view, &o, 4, err)) fail_msg("%s", err);
    }
}

static void hand_made_level(void **state)
{
    (void)state;
    char dir[] = "/tmp/lbk-lmuv-XXXXXX", path[64];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/level.gltf", dir);
    assert_int_equal(lmuv_scene_write(path), 0);
    level l;
    assert_int_equal(level_open(path, 16, &l), 0);
    unlink(path);
    rmdir(dir);
    assert_int_equal(l.scene.object_count, 3);
    assert_int_equal(l.view.record_count, 3);
    check_rebuild(&l, 0, 0);
    check_rebuild(&l, 1, 1);
    lbk_lmuv_object o;
    lbk_lmuv_get_object(&l.view, 2, &o);
    assert_int_equal(o.kind, LBK_LMUV_AUTHORED); /* the decal keeps its (mirrored) TEXCOORD_1 */
    assert_true(o.scale[0] > 0 && o.scale[0] == o.scale[1]);
    assert_true(o.uv_min[0] == 0.1f && o.uv_max[1] == 0.9f);
    rule_stats st = check_rule(&l);
    assert_true(st.authored > 0 && st.centres > 0 && st.edges > 0);
    print_stats("hand-made level", &st);
    level_close(&l);
}

static void shared_levels(void **state)
{
    (void)state;
    static const struct {
        const char *file;
        float density;
        int authored;
    } levels[] = {{"cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf", 8, 1}, {"cornell_box/CornellBox-Original.gltf", 16, 0}};
    for (size_t i = 0; i < sizeof levels / sizeof levels[0]; i++) {
        char path[1024];
        SD_REQUIRE(sd_path(path, sizeof path, levels[i].file));
        level l;
        assert_int_equal(level_open(path, levels[i].density, &l), 0);
        rule_stats st = check_rule(&l);
        check_all_records(&l);
        assert_int_equal(st.authored > 0, levels[i].authored);
        assert_true(st.max_authored_dev < 1.0 / 1024);
        print_stats(levels[i].file, &st);
        level_close(&l);
    }
}

/* The old claim of the README (texel (i, j) of an object's rectangle is at TEXCOORD_1
 * ((i + 0.5)/w, (j + 0.5)/h)) against the stored rule on the real authored objects: how far
 * apart they put the same TEXCOORD_1, in texels. Not an assertion of the old rule: a measurement
 * for the record (spec §16.3 explains why they differ). */
static void old_rule_measured(void **state)
{
    (void)state;
    char path[1024];
    SD_REQUIRE(sd_path(path, sizeof path, "cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf"));
    level l;
    assert_int_equal(level_open(path, 8, &l), 0);
    double worst = 0;
    for (uint32_t r = 0; r < l.view.record_count; r++) {
        lbk_lmuv_object o;
        lbk_lmuv_get_object(&l.view, r, &o);
        if (o.kind != LBK_LMUV_AUTHORED) continue;
        const bk_atlas_object *ao = &l.atlas.objects[l.atlas.object_slot[o.object]];
        const float corners[2][2] = {{o.uv_min[0], o.uv_min[1]}, {o.uv_max[0], o.uv_max[1]}};
        double off = 0;
        for (int c = 0; c < 2; c++) {
            float xy[2];
            lbk_lmuv_authored_coord(&o, corners[c], xy);
            const double old_x = ao->x + corners[c][0] * ao->w, old_y = ao->y + corners[c][1] * ao->h;
            off = fmax(off, fmax(fabs(old_x - xy[0]), fabs(old_y - xy[1])));
        }
        print_message("  object %u '%s': uv box [%.3f,%.3f]-[%.3f,%.3f], rect %dx%d, old rule off by %.2f texels\n",
                      o.object, l.scene.objects[o.object].name, (double)o.uv_min[0], (double)o.uv_min[1],
                      (double)o.uv_max[0], (double)o.uv_max[1], ao->w, ao->h, off);
        worst = fmax(worst, off);
    }
    print_message("cornell_box_bjs authored objects: the old per-object rule is off by up to %.2f texels\n", worst);
    assert_true(worst > 0.5); /* the reason the rule had to be stored */
    level_close(&l);
}

/* lbk_ahd_tangent_frame (what a renderer calls) is bk_tangent_frame (what the baker encodes
 * with), bit for bit, including the fallback cases. */
static void tangent_frame_is_the_bakers(void **state)
{
    (void)state;
    uint64_t x = 0x9e3779b97f4a7c15ull;
#define RND() ((float)((x = x * 6364136223846793005ull + 1442695040888963407ull) >> 40) / 16777216.0f * 2.0f - 1.0f)
    for (int i = 0; i < 20000; i++) {
        float n[3] = {RND(), RND(), RND()}, d[3] = {RND(), RND(), RND()};
        if (i % 5 == 1) memset(d, 0, sizeof d);                             /* no dP/dX */
        if (i % 5 == 2) memcpy(d, n, sizeof d);                             /* parallel to N */
        if (i % 5 == 3) n[0] = n[1] = 0, n[2] = i % 2 ? -1.0f : 1.0f;       /* the ONB's branch */
        if (i % 97 == 4) memset(n, 0, sizeof n);                            /* no normal: +Z */
        float t0[3], b0[3], t1[3], b1[3];
        bk_tangent_frame(n, d, t0, b0);
        lbk_ahd_tangent_frame(n, d, t1, b1);
        if (memcmp(t0, t1, sizeof t0) || memcmp(b0, b1, sizeof b0)) fail_msg("case %d: frames differ", i);
    }
#undef RND
    /* and the receivers' tangents are what a renderer rebuilds from the stored coordinates */
    char path[1024];
    SD_REQUIRE(sd_path(path, sizeof path, "cornell_box/CornellBox-Original.gltf"));
    level l;
    assert_int_equal(level_open(path, 16, &l), 0);
    double worst = 0;
    for (size_t i = 0; i < l.texels.count; i++) {
        const bk_texel *t = &l.texels.receivers[i];
        float xy[3][2], p[3][3], dpdx[3], tt[3], bb[3];
        int authored;
        corner_coords(&l, t->tri, xy, &authored);
        for (int k = 0; k < 3; k++) memcpy(p[k], &l.scene.positions[3 * (size_t)l.scene.tris[3 * (size_t)t->tri + k]], sizeof p[k]);
        lbk_ahd_triangle_dpdx(p, (const float(*)[2])xy, dpdx);
        lbk_ahd_tangent_frame(t->normal, dpdx, tt, bb);
        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(tt[c] - t->tangent[c]));
    }
    print_message("cornell_box receivers: tangent rebuilt from LMUV within %.2e\n", worst);
    assert_true(worst < 1e-5);
    level_close(&l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(hand_made_level),
        cmocka_unit_test(shared_levels),
        cmocka_unit_test(old_rule_measured),
        cmocka_unit_test(tangent_frame_is_the_bakers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
