/* GLG placement, per-face visibility, LLG OBB/lattice and self-visibility. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/probes/delaunay.h"
#include "bake/probes/glg_place.h"
#include "bake/probes/llg_place.h"
#include "scene/tracer.h"
#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/llg.h"
#include "tests/support/probe_scenes.h"

/* A closed room [0,10]x[0,6]x[0,8] (walls facing inward) holding a solid block
 * [2,2.8]x[0,1]x[1,2] (faces outward). */
static const float ROOM_LO[3] = {0, 0, 0}, ROOM_HI[3] = {10, 6, 8};
static const float BLOCK_LO[3] = {2, 0, 1}, BLOCK_HI[3] = {2.8f, 1, 2};

static void room_scene(bk_scene *s)
{
    psc_init(s);
    psc_box(s, ROOM_LO, ROOM_HI, 2, 1);
    psc_box(s, BLOCK_LO, BLOCK_HI, 1, 0);
    psc_update_bounds(s);
}

static double box_distance_inside(const float *p, const float lo[3], const float hi[3])
{
    double d = 1e30;
    for (int k = 0; k < 3; k++) d = fmin(d, fmin(p[k] - lo[k], hi[k] - p[k]));
    return d;   /* negative when outside */
}

static double box_distance_outside(const float *p, const float lo[3], const float hi[3])
{
    double s = 0.0;
    int inside = 1;
    for (int k = 0; k < 3; k++) {
        double e = fmax(fmax(lo[k] - p[k], p[k] - hi[k]), 0.0);
        if (p[k] < lo[k] || p[k] > hi[k]) inside = 0;
        s += e * e;
    }
    return inside ? -1.0 : sqrt(s);
}

static double nearest_other(const float *pts, size_t n, size_t i)
{
    double best = 1e30;
    for (size_t j = 0; j < n; j++) {
        if (j == i) continue;
        double dx = pts[3 * j] - pts[3 * i], dy = pts[3 * j + 1] - pts[3 * i + 1], dz = pts[3 * j + 2] - pts[3 * i + 2];
        best = fmin(best, sqrt(dx * dx + dy * dy + dz * dz));
    }
    return best;
}

static void test_glg_room_placement(void **state)
{
    (void)state;
    bk_scene s;
    room_scene(&s);
    bk_tracer *tr;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    bk_glg_options o = {0};
    o.min_distance = 0.1f;
    bk_glg_probes p;
    assert_int_equal(bk_glg_place(&s, tr, &o, 2, &p), LBK_OK);
    assert_true(p.count > 100);
    assert_true(p.rejected_solid > 0);        /* cell centres inside the block */
    assert_int_equal(p.refine_levels, 1);
    assert_true(p.spacing <= 1.0f);
    double near_sum = 0, far_sum = 0;
    size_t near_n = 0, far_n = 0;
    for (size_t i = 0; i < p.count; i++) {
        const float *q = p.positions + 3 * i;
        double dw = box_distance_inside(q, ROOM_LO, ROOM_HI);
        double db = box_distance_outside(q, BLOCK_LO, BLOCK_HI);
        assert_true(dw >= 0.1 - 1e-4);          /* inside the room, clear of its walls */
        assert_true(db >= 0.1 - 1e-4);          /* outside the block, clear of it */
        double nn = nearest_other(p.positions, p.count, i);
        assert_true(nn <= 1.0 + 1e-4);          /* spacing at most 1 m everywhere */
        double dist = fmin(dw, db);
        if (dist < 0.5) { near_sum += nn; near_n++; }
        else if (dist > 1.6) { far_sum += nn; far_n++; }   /* no refined neighbour cell */
    }
    assert_true(near_n > 0 && far_n > 0);
    /* near surfaces the octants give half spacing; far from them the full 1 m grid */
    assert_true(near_sum / near_n < 0.6);
    assert_true(far_sum / far_n > 0.99);
    /* coverage: every free point of the room has a probe within a cell diagonal */
    for (int i = 0; i < 200; i++) {
        float q[3] = {0.3f + 9.4f * (float)((i * 37) % 200) / 200.0f, 0.3f + 5.4f * (float)((i * 71) % 200) / 200.0f,
                      0.3f + 7.4f * (float)((i * 13) % 200) / 200.0f};
        if (box_distance_outside(q, BLOCK_LO, BLOCK_HI) < 0.3) continue;
        double best = 1e30;
        for (size_t j = 0; j < p.count; j++) {
            double dx = p.positions[3 * j] - q[0], dy = p.positions[3 * j + 1] - q[1], dz = p.positions[3 * j + 2] - q[2];
            best = fmin(best, sqrt(dx * dx + dy * dy + dz * dz));
        }
        assert_true(best <= 0.5 * sqrt(3.0) + 1e-4);
    }
    /* deterministic and independent of the thread count */
    bk_glg_probes p1;
    assert_int_equal(bk_glg_place(&s, tr, &o, 1, &p1), LBK_OK);
    assert_int_equal(p1.count, p.count);
    assert_memory_equal(p1.positions, p.positions, 3 * p.count * sizeof(float));
    bk_glg_probes_free(&p1);
    bk_glg_probes_free(&p);
    bk_tracer_destroy(tr);
    psc_free(&s);
}

/* The tetrahedra tile the convex hull of the probes: no gap, no overlap. The probes inside the
 * room's walls span a box, and when its 8 corners are probes the hull is that box, so its volume
 * is Δx·Δy·Δz (no qhull needed). Both sides are computed in double from float positions, so the
 * comparison allows their rounding (u = 2^-53, γ_n = n·u / (1 − n·u), Higham ch. 3):
 *   - one tetra: orient = Σ ± u_i·v_j·w_k over 6 terms; each term passes 3 subtractions (the
 *     edge vectors), 3 products and 2 additions, and /6 adds one more: |err| ≤ γ_9 · P / 6 with
 *     P the permanent of the absolute edge matrix; γ_10 covers the rounding of P itself;
 *   - the sum of N positive volumes: ≤ γ_N · Σ vol;
 *   - the box: 3 subtractions and 2 products, ≤ γ_5 · box.
 * A missing or doubled tetra (volume ≫ that bound: 145 tetras give about 4e-12 here) fails. */
static double gamma_n(double n) { return n * (DBL_EPSILON / 2) / (1 - n * (DBL_EPSILON / 2)); }

static void assert_tets_fill_box_hull(const bk_glg *g)
{
    float lo[3], hi[3];
    memcpy(lo, g->positions, sizeof lo);
    memcpy(hi, g->positions, sizeof hi);
    for (size_t i = 0; i < g->probe_count; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], g->positions[3 * i + k]);
            hi[k] = fmaxf(hi[k], g->positions[3 * i + k]);
        }
    unsigned corners = 0; /* bit c: corner (x: bit 0, y: bit 1, z: bit 2 of c; set = hi) is a probe */
    for (size_t i = 0; i < g->probe_count; i++) {
        int c = 0, on = 1;
        for (int k = 0; k < 3; k++) {
            float x = g->positions[3 * i + k];
            on &= x == lo[k] || x == hi[k];
            c |= (x == hi[k]) << k;
        }
        if (on) corners |= 1u << c;
    }
    assert_int_equal(corners, 0xff); /* the hull is the box */
    const double box = ((double)hi[0] - lo[0]) * ((double)hi[1] - lo[1]) * ((double)hi[2] - lo[2]);
    double sum = 0.0, perm = 0.0;
    for (size_t t = 0; t < g->tet_count; t++) {
        const float *p[4];
        for (int i = 0; i < 4; i++) p[i] = g->positions + 3 * (size_t)g->tets[4 * t + (size_t)i];
        sum += bk_tet_signed_volume(p[0], p[1], p[2], p[3]);
        double e[3][3];
        for (int r = 0; r < 3; r++)
            for (int k = 0; k < 3; k++) e[r][k] = fabs((double)p[r + 1][k] - p[0][k]);
        perm += e[0][0] * (e[1][1] * e[2][2] + e[1][2] * e[2][1]) + e[0][1] * (e[1][0] * e[2][2] + e[1][2] * e[2][0]) +
                e[0][2] * (e[1][0] * e[2][1] + e[1][1] * e[2][0]);
    }
    const double bound = gamma_n(10) * perm / 6 + gamma_n((double)g->tet_count) * sum + gamma_n(5) * box;
    print_message("tetra volumes %.17g, hull (box) %.17g, |difference| %.3g, bound %.3g\n", sum, box, fabs(sum - box),
                  bound);
    assert_true(fabs(sum - box) <= bound);
}

static void test_glg_cap_and_build(void **state)
{
    (void)state;
    bk_scene s;
    room_scene(&s);
    bk_tracer *tr;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    bk_glg_options o = {0};
    o.max_probes = 60;
    bk_glg g;
    assert_int_equal(bk_glg_build(&s, tr, &o, 2, &g), LBK_OK);
    assert_int_equal(g.status, BK_GLG_OK);
    assert_true(g.probe_count <= 60 && g.probe_count >= 4);
    assert_int_equal(g.refine_levels, 0);      /* coarsened near surfaces first */
    assert_true(g.tet_count > 0);
    for (size_t t = 0; t < g.tet_count; t++) {
        const uint32_t *v = g.tets + 4 * t;
        assert_true(bk_tet_signed_volume(g.positions + 3 * (size_t)v[0], g.positions + 3 * (size_t)v[1],
                                         g.positions + 3 * (size_t)v[2], g.positions + 3 * (size_t)v[3]) > 0.0);
        for (int i = 0; i < 4; i++) {
            float f = g.face_visibility[4 * t + (size_t)i];
            assert_true(f >= 0.0f && f <= 1.0f);
        }
    }
    assert_tets_fill_box_hull(&g);
    /* the container's GLG builder accepts the mesh as is (orientation, adjacency, visibility) */
    uint8_t (*vis8)[4] = malloc(g.tet_count * sizeof *vis8);
    lbk_sh9_rgb *sh = calloc(g.probe_count, sizeof *sh);
    bk_glg_visibility_unorm8(&g, vis8);
    for (size_t t = 0; t < g.tet_count; t++)
        for (int i = 0; i < 4; i++)
            assert_int_equal(vis8[t][i], (int)lrintf(g.face_visibility[4 * t + (size_t)i] * 255.0f));
    lbk_glg_build_desc desc = {.probe_count = (uint32_t)g.probe_count, .tetra_count = (uint32_t)g.tet_count,
        .positions = (const float (*)[3])g.positions, .probes = sh, .tetras = (const uint32_t (*)[4])g.tets,
        .adjacency = (const uint32_t (*)[4])g.neighbours, .visibility = (const uint8_t (*)[4])vis8};
    void *bytes = NULL;
    size_t size = 0;
    assert_int_equal(lbk_glg_build(&desc, NULL, &bytes, &size), LBK_OK);
    lbk_glg_view view;
    assert_int_equal(lbk_glg_open(bytes, size, &view), LBK_OK);
    assert_int_equal(view.tetra_count, g.tet_count);
    /* the stored tetras are ours unchanged (already positively oriented) */
    assert_memory_equal(view.mesh.tetras, g.tets, 16 * g.tet_count);
    lbk_free(NULL, bytes);
    free(sh);
    free(vis8);
    bk_glg_free(&g);
    bk_tracer_destroy(tr);
    psc_free(&s);
}

/* The room scaled to 10 km, moved 1e5 m away, and shrunk to 1 mm. */
static void test_glg_extreme_scales(void **state)
{
    (void)state;
    const double scales[3] = {1000.0, 1.0, 1e-4};
    const double offsets[3] = {0.0, 1e5, 0.0};
    for (int c = 0; c < 3; c++) {
        bk_scene s;
        room_scene(&s);
        for (size_t v = 0; v < 3 * s.vertex_count; v++) s.positions[v] = (float)(s.positions[v] * scales[c] + offsets[c]);
        bk_tracer *tr;
        assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
        bk_glg_options o = {0};
        o.max_probes = 2000;
        bk_glg g;
        assert_int_equal(bk_glg_build(&s, tr, &o, 2, &g), LBK_OK);
        {
            /* 1 mm across: one cell, its 8 octants (the clearance scales with the cell) */
            assert_int_equal(g.status, BK_GLG_OK);
            assert_true(g.probe_count <= 2000 && g.tet_count > 0);
            for (size_t i = 0; i < g.probe_count; i++) {
                float q[3];
                for (int k = 0; k < 3; k++) q[k] = (float)((g.positions[3 * i + k] - offsets[c]) / scales[c]);
                assert_true(isfinite(q[0]) && isfinite(q[1]) && isfinite(q[2]));
                assert_true(box_distance_inside(q, ROOM_LO, ROOM_HI) > 0.0);
                assert_true(box_distance_outside(q, BLOCK_LO, BLOCK_HI) > 0.0);
            }
            for (size_t t = 0; t < 4 * g.tet_count; t++) assert_true(isfinite(g.face_visibility[t]));
            if (c < 2) assert_tets_fill_box_hull(&g); /* at 1 mm the probes do not span a box */
        }
        bk_glg_free(&g);
        bk_tracer_destroy(tr);
        psc_free(&s);
    }
}

/* A single floor quad: no volume to fill, so no GLG. */
static void test_glg_flat_scene(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    const float a[3] = {0, 0, 0}, b[3] = {10, 0, 0}, c[3] = {10, 10, 0}, d[3] = {0, 10, 0};
    psc_quad(&s, a, b, c, d, 1);
    bk_tracer *tr;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    bk_glg g;
    assert_int_equal(bk_glg_build(&s, tr, NULL, 1, &g), LBK_OK);
    assert_true(g.status == BK_GLG_FLAT || g.status == BK_GLG_NO_FREE_SPACE);
    assert_int_equal(g.tet_count, 0);
    assert_null(g.tets);
    bk_glg_free(&g);
    bk_tracer_destroy(tr);
    psc_free(&s);
    /* and an empty scene */
    psc_init(&s);
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    assert_int_equal(bk_glg_build(&s, tr, NULL, 1, &g), LBK_OK);
    assert_int_equal(g.status, BK_GLG_EMPTY_SCENE);
    bk_glg_free(&g);
    bk_tracer_destroy(tr);
    psc_free(&s);
}

/* One tetrahedron, apex at the origin, opposite face in z = 2; an occluder square at z = 1
 * covering x < 0. Level-1 samples are the centroids of the 4 midpoint sub-triangles; a segment
 * from the apex to a sample s crosses z = 1 at s/2, blocked iff s.x/2 < 0. */
static void test_face_visibility(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    const float q0[3] = {-5, -5, 1}, q1[3] = {0, -5, 1}, q2[3] = {0, 5, 1}, q3[3] = {-5, 5, 1};
    psc_quad(&s, q0, q1, q2, q3, 1);
    bk_tracer *tr;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    const float pos[4 * 3] = {0, 0, 0, -1.7f, -1, 2, 1, -1, 2, 0.5f, 1.5f, 2};
    const uint32_t tet[4] = {0, 1, 2, 3};
    float vis[4];
    bk_glg_face_visibility(tr, pos, 1, tet, 1, 1, vis);
    /* expected from the sample points directly */
    const float *f0 = pos + 3, *f1 = pos + 6, *f2 = pos + 9;
    const float bary[4][3] = {{1.0f / 6, 1.0f / 6, 2.0f / 3}, {1.0f / 6, 2.0f / 3, 1.0f / 6},
                              {2.0f / 3, 1.0f / 6, 1.0f / 6}, {1.0f / 3, 1.0f / 3, 1.0f / 3}};
    int open = 0;
    for (int i = 0; i < 4; i++) {
        float x = bary[i][0] * f0[0] + bary[i][1] * f1[0] + bary[i][2] * f2[0];
        open += x >= 0.0f;
    }
    assert_true(open > 0 && open < 4);         /* the geometry really splits the face */
    assert_true(fabsf(vis[0] - open / 4.0f) < 1e-6f);
    /* the face vertices see the apex region across z = 1 partly blocked; the vertex at x=1
     * looks at points with x/2 + 1/2 ... just bound them */
    for (int i = 1; i < 4; i++) assert_true(vis[i] >= 0.0f && vis[i] <= 1.0f);
    /* finer strata: 16 samples, still the blocked fraction of the face */
    bk_glg_face_visibility(tr, pos, 1, tet, 2, 1, vis);
    assert_true(vis[0] > 0.0f && vis[0] < 1.0f);
    bk_tracer_destroy(tr);
    psc_free(&s);
    /* nothing in the way: all 1 */
    psc_init(&s);
    const float far0[3] = {50, 50, 50}, far1[3] = {51, 50, 50}, far2[3] = {50, 51, 50};
    psc_tri(&s, far0, far1, far2);
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    bk_glg_face_visibility(tr, pos, 1, tet, 1, 1, vis);
    for (int i = 0; i < 4; i++) assert_true(vis[i] == 1.0f);
    bk_tracer_destroy(tr);
    psc_free(&s);
}

/* A 4 x 2 x 1 box rotated by a known quaternion: the OBB must recover its axes and extents. */
static void test_llg_obb_rotated_box(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    uint32_t obj = psc_object(&s, "prop", BK_LIGHTING_LLG);
    const float lo[3] = {8, 3, -2}, hi[3] = {12, 5, -1};
    psc_box(&s, lo, hi, 3, 0);
    /* rotation 30° about (1, 2, 3)/|…| */
    double ax[3] = {1, 2, 3}, al = sqrt(14.0), h = 0.5 * 30.0 * M_PI / 180.0;
    double q[4] = {ax[0] / al * sin(h), ax[1] / al * sin(h), ax[2] / al * sin(h), cos(h)};
    const float pivot[3] = {10, 4, -1.5f};
    psc_rotate_tris(&s, s.objects[obj].first_tri, q, pivot);
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                      {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                      {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    bk_llg l;
    bk_llg_options o = {0};
    o.visibility_rays = 8;
    assert_int_equal(bk_llg_place(&s, obj, &o, 1, &l), LBK_OK);
    const double expect_he[3] = {2.0, 1.0, 0.5};
    for (int a = 0; a < 3; a++) {
        /* axis a of the box (x, y, z before rotation) is column a of R */
        double d = fabs(l.axes[a][0] * R[0][a] + l.axes[a][1] * R[1][a] + l.axes[a][2] * R[2][a]);
        assert_true(d > 1.0 - 1e-5);
        assert_true(fabs(l.obb_half_extents[a] - expect_he[a]) < 1e-4);
        assert_true(fabs(l.centre[a] - pivot[a]) < 1e-4);
        /* sign convention: largest component positive (axes 0, 1), axis 2 = axis 0 × axis 1 */
        if (a < 2) {
            int big = 0;
            for (int k = 1; k < 3; k++) if (fabsf(l.axes[a][k]) > fabsf(l.axes[a][big])) big = k;
            assert_true(l.axes[a][big] > 0.0f);
        }
    }
    float cx = l.axes[0][1] * l.axes[1][2] - l.axes[0][2] * l.axes[1][1];
    assert_true(fabsf(cx - l.axes[2][0]) < 1e-6f);
    /* lattice: margin 10% of 2 m = 0.2 m; dims = ceil(2h / 1.5) + 1 */
    assert_true(fabsf(l.half_extents[0] - 2.2f) < 1e-4f);
    assert_true(fabsf(l.half_extents[2] - 0.7f) < 1e-4f);
    assert_int_equal(l.dims[0], 4);   /* 4.4 / 1.5 -> 3 steps */
    assert_int_equal(l.dims[1], 3);   /* 2.4 / 1.5 -> 2 steps */
    assert_int_equal(l.dims[2], 2);   /* 1.4 / 1.5 -> 1 step  */
    /* every lattice probe lies outside the box (the lattice is bigger than the OBB) */
    for (uint32_t k = 0; k < l.dims[2]; k++) for (uint32_t j = 0; j < l.dims[1]; j++)
        for (uint32_t i = 0; i < l.dims[0]; i++) {
            float p[3];
            bk_llg_probe_position(&l, i, j, k, p);
            double local[3];
            for (int a = 0; a < 3; a++)
                local[a] = R[0][a] * (p[0] - pivot[0]) + R[1][a] * (p[1] - pivot[1]) + R[2][a] * (p[2] - pivot[2]);
            int inside = fabs(local[0]) < 2.0 && fabs(local[1]) < 1.0 && fabs(local[2]) < 0.5;
            assert_false(inside);
        }
    /* 24 box corners as separate vertices per face: 6 faces x 16 grid vertices */
    assert_int_equal(l.vertex_count, 6 * 16);
    /* the container's LLG builder takes the grid; its probe positions match ours */
    {
        lbk_llg_vertex *recs = malloc(l.vertex_count * sizeof *recs);
        bk_llg_vertex_records(&l, recs);
        for (size_t v = 0; v < l.vertex_count; v++) {
            /* grid-frame bent normal maps back to the world one */
            for (int k = 0; k < 3; k++) {
                float wv = 0.0f;
                for (int a = 0; a < 3; a++) wv += recs[v].bent_normal[a] * l.axes[a][k];
                assert_true(fabsf(wv - l.bent_normals[3 * v + k]) < 1e-5f);
            }
        }
        lbk_sh9_rgb *sh = calloc(bk_llg_probe_count(&l), sizeof *sh);
        lbk_llg_grid_desc gd;
        memset(&gd, 0, sizeof gd);
        memcpy(gd.centre, l.centre, sizeof gd.centre);
        memcpy(gd.axes, l.axes, sizeof gd.axes);
        memcpy(gd.half_extents, l.half_extents, sizeof gd.half_extents);
        memcpy(gd.dims, l.dims, sizeof gd.dims);
        gd.probes = sh;
        gd.vertices = recs;
        gd.vertex_count = (uint32_t)l.vertex_count;
        void *bytes = NULL;
        size_t size = 0;
        assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &gd,
            .grid_count = 1}, NULL, &bytes, &size), LBK_OK);
        lbk_llg_view view;
        lbk_llg_grid grid;
        assert_int_equal(lbk_llg_open(bytes, size, &view), LBK_OK);
        assert_int_equal(lbk_llg_grid_get(&view, 0, &grid), LBK_OK);
        for (uint32_t k = 0; k < l.dims[2]; k++) for (uint32_t j = 0; j < l.dims[1]; j++)
            for (uint32_t i = 0; i < l.dims[0]; i++) {
                float a[3], b[3];
                bk_llg_probe_position(&l, i, j, k, a);
                lbk_llg_probe_position(&grid, i, j, k, b);
                for (int c = 0; c < 3; c++) assert_true(fabsf(a[c] - b[c]) < 1e-4f);
            }
        lbk_free(NULL, bytes);
        free(sh);
        free(recs);
    }
    bk_llg_free(&l);
    /* a 200 m rod: the per-axis limit of the container (64) also lowers the resolution */
    {
        bk_scene r;
        psc_init(&r);
        uint32_t rod = psc_object(&r, "rod", BK_LIGHTING_LLG);
        const float rlo[3] = {0, 0, 0}, rhi[3] = {200, 0.2f, 0.2f};
        psc_box(&r, rlo, rhi, 1, 0);
        bk_llg_options ro = {0};
        ro.visibility_rays = 4;
        ro.max_probes = 100000;
        assert_int_equal(bk_llg_place(&r, rod, &ro, 1, &l), LBK_OK);
        assert_true(l.dims[0] <= 64 && l.dims[0] >= 60);
        bk_llg_free(&l);
        psc_free(&r);
    }

    /* cap: at most 20 probes -> the spacing grows */
    o.max_probes = 20;
    assert_int_equal(bk_llg_place(&s, obj, &o, 1, &l), LBK_OK);
    assert_true(bk_llg_probe_count(&l) <= 20);
    assert_true(l.spacing > 1.5f);
    for (int a = 0; a < 3; a++) assert_true(l.dims[a] >= 2);
    bk_llg_free(&l);
    /* density override: an explicit LLG with texel_density 2 per metre -> 0.5 m */
    s.objects[obj].texel_density = 2.0f;
    o.max_probes = 0;
    assert_int_equal(bk_llg_place(&s, obj, &o, 1, &l), LBK_OK);
    assert_true(fabsf(l.spacing - 0.5f) < 1e-6f);
    assert_int_equal(l.dims[0], 10);  /* 4.4 / 0.5 = 8.8 -> 9 steps */
    bk_llg_free(&l);
    psc_free(&s);
}

/* A flat object (one quad) gets a minimum thickness so the lattice has volume. */
static void test_llg_flat_object(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    uint32_t obj = psc_object(&s, "sign", BK_LIGHTING_LLG);
    const float a[3] = {0, 0, 0}, b[3] = {2, 0, 0}, c[3] = {2, 0, 1}, d[3] = {0, 0, 1};
    psc_quad(&s, a, b, c, d, 1);
    bk_llg l;
    assert_int_equal(bk_llg_place(&s, obj, NULL, 1, &l), LBK_OK);
    assert_true(l.obb_half_extents[2] < 1e-6f);
    assert_true(fabsf(l.half_extents[2] - (0.05f + 0.1f)) < 1e-5f);   /* 5% floor + 10% margin */
    assert_true(fabsf(l.axes[2][1]) > 0.9999f);                       /* normal of the quad */
    assert_int_equal(l.vertex_count, 4);
    for (size_t v = 0; v < l.vertex_count; v++) assert_true(l.visibility[v] == 1.0f);
    bk_llg_free(&l);
    /* an object without triangles */
    uint32_t empty = psc_object(&s, "empty", BK_LIGHTING_LLG);
    assert_int_equal(bk_llg_place(&s, empty, NULL, 1, &l), LBK_ERR_INVALID_ARGUMENT);
    psc_free(&s);
}

static void test_llg_self_visibility(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    /* L shape: floor [0,2]x[0,2] at z=0 facing +z and a wall at x=0 facing +x; the vertex of
     * the floor at the inside corner (0, 1, 0) sees the wall over half its hemisphere */
    uint32_t l_obj = psc_object(&s, "L", BK_LIGHTING_LLG);
    const float f0[3] = {0, 0, 0}, f1[3] = {2, 0, 0}, f2[3] = {2, 2, 0}, f3[3] = {0, 2, 0};
    const float w0[3] = {0, 0, 0}, w1[3] = {0, 2, 0}, w2[3] = {0, 2, 2}, w3[3] = {0, 0, 2};
    psc_quad(&s, f0, f1, f2, f3, 2);
    psc_quad(&s, w0, w1, w2, w3, 2);
    /* a sphere elsewhere, plus another object right on top of it that must NOT shadow it */
    uint32_t sph = psc_object(&s, "sphere", BK_LIGHTING_LLG);
    const float centre[3] = {10, 0, 0};
    psc_sphere(&s, centre, 1.0f, 12, 16);
    psc_object(&s, "lid", BK_LIGHTING_LIGHTMAP);
    const float l0[3] = {8, -2, 1.5f}, l1[3] = {8, 2, 1.5f}, l2[3] = {12, 2, 1.5f}, l3[3] = {12, -2, 1.5f};
    psc_quad(&s, l0, l1, l2, l3, 1);   /* faces down onto the sphere */

    bk_llg_options o = {0};
    o.visibility_rays = 256;
    bk_llg l;
    assert_int_equal(bk_llg_place(&s, l_obj, &o, 2, &l), LBK_OK);
    int found = 0;
    for (size_t v = 0; v < l.vertex_count; v++) {
        const float *p = s.positions + 3 * (size_t)l.vertices[v], *n = s.normals + 3 * (size_t)l.vertices[v];
        if (p[0] == 0.0f && p[1] == 1.0f && p[2] == 0.0f && n[2] > 0.5f) {
            found = 1;
            /* analytic: cosine-weighted visibility past a wall through the vertex = 1/2;
             * the wall is finite (2 m), so a little more gets out */
            assert_true(l.visibility[v] > 0.45f && l.visibility[v] < 0.6f);
            /* bent normal leans away from the wall (+x) */
            assert_true(l.bent_normals[3 * v] > 0.3f);
        }
        if (p[0] == 2.0f && p[2] == 0.0f && n[2] > 0.5f && p[1] == 1.0f) {
            /* far edge of the floor: the wall subtends atan(2/2) of elevation only */
            assert_true(l.visibility[v] > 0.7f && l.visibility[v] < 1.0f);
        }
    }
    assert_true(found);
    bk_llg_free(&l);

    assert_int_equal(bk_llg_place(&s, sph, &o, 2, &l), LBK_OK);
    assert_true(l.vertex_count > 100);
    for (size_t v = 0; v < l.vertex_count; v++) {
        const float *n = s.normals + 3 * (size_t)l.vertices[v];
        assert_true(l.visibility[v] > 0.999f);   /* convex, and the lid is another object */
        float dot = n[0] * l.bent_normals[3 * v] + n[1] * l.bent_normals[3 * v + 1] + n[2] * l.bent_normals[3 * v + 2];
        assert_true(dot > 0.999f);
    }
    /* deterministic and thread-count independent */
    bk_llg lb;
    assert_int_equal(bk_llg_place(&s, sph, &o, 1, &lb), LBK_OK);
    assert_memory_equal(lb.visibility, l.visibility, l.vertex_count * sizeof(float));
    assert_memory_equal(lb.bent_normals, l.bent_normals, 3 * l.vertex_count * sizeof(float));
    bk_llg_free(&lb);
    bk_llg_free(&l);
    psc_free(&s);
}

/* Connected objects (the seed's extra LLG probes): two 1 × 0.2 × 0.2 m bars end to end at x = 1
 * touch, a third 3 m away and a small box inside the first bar's box do not count; a connected
 * bar gets half the spacing (3 probes along it instead of 2). */
static void test_llg_connected(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    const float boxes[4][6] = {{0, 0, 0, 1, 0.2f, 0.2f}, {1, 0, 0, 2, 0.2f, 0.2f}, {5, 0, 0, 6, 0.2f, 0.2f},
                               {0.4f, 0.05f, 0.05f, 0.6f, 0.15f, 0.15f}};
    uint32_t id[4];
    for (int i = 0; i < 4; i++) {
        char name[16];
        snprintf(name, sizeof name, "bar%d", i);
        id[i] = psc_object(&s, name, BK_LIGHTING_LLG);
        psc_box(&s, boxes[i], boxes[i] + 3, 1, 0);
    }
    assert_true(s.object_count <= 8);
    uint8_t cand[8] = {0}, out[8];
    for (int i = 0; i < 4; i++) cand[id[i]] = 1;
    assert_int_equal(bk_llg_connections(&s, cand, 0, out), LBK_OK);
    assert_int_equal(out[id[0]], 1);
    assert_int_equal(out[id[1]], 1);
    assert_int_equal(out[id[2]], 0);
    assert_int_equal(out[id[3]], 0);   /* inside bar 0's box: not a joint */
    /* only candidates count: without bar 1, bar 0 has no partner */
    cand[id[1]] = 0;
    assert_int_equal(bk_llg_connections(&s, cand, 0, out), LBK_OK);
    assert_int_equal(out[id[0]], 0);
    assert_int_equal(out[id[1]], 0);
    /* bars 1 and 2 are 3 m apart: a gap of 3.1 m joins them, 2.9 m does not */
    uint8_t c12[8] = {0};
    c12[id[1]] = c12[id[2]] = 1;
    assert_int_equal(bk_llg_connections(&s, c12, 3.1f, out), LBK_OK);
    assert_true(out[id[1]] && out[id[2]]);
    assert_int_equal(bk_llg_connections(&s, c12, 2.9f, out), LBK_OK);
    assert_true(!out[id[1]] && !out[id[2]]);
    bk_llg_options o = {0};
    o.visibility_rays = 4;
    bk_llg l;
    assert_int_equal(bk_llg_place(&s, id[0], &o, 1, &l), LBK_OK);
    assert_int_equal(l.dims[0], 2);   /* 2 × 0.55 m / 1.5 m -> 1 step */
    bk_llg_free(&l);
    o.connected = 1;
    assert_int_equal(bk_llg_place(&s, id[0], &o, 1, &l), LBK_OK);
    assert_float_equal(l.spacing, 0.75f, 1e-6);
    assert_int_equal(l.dims[0], 3);   /* 1.1 m / 0.75 m -> 2 steps */
    bk_llg_free(&l);
    /* the cap still wins: 8 probes at most keeps 2 per axis */
    o.max_probes = 8;
    assert_int_equal(bk_llg_place(&s, id[0], &o, 1, &l), LBK_OK);
    assert_true(bk_llg_probe_count(&l) <= 8);
    bk_llg_free(&l);
    psc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_glg_room_placement),
        cmocka_unit_test(test_glg_cap_and_build),
        cmocka_unit_test(test_glg_extreme_scales),
        cmocka_unit_test(test_glg_flat_scene),
        cmocka_unit_test(test_face_visibility),
        cmocka_unit_test(test_llg_obb_rotated_box),
        cmocka_unit_test(test_llg_flat_object),
        cmocka_unit_test(test_llg_self_visibility),
        cmocka_unit_test(test_llg_connected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
