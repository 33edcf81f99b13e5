/* Texel receivers (bake/layout/texels.h): coverage, footprints, normals and tangent frames,
 * push-out at wall/floor junctions, inside-geometry detection, dilation. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/atlas.h"
#include "bake/layout/seams.h"
#include "bake/layout/texels.h"
#include "scene/tracer.h"
#include "support/uv_scenes.h"

static uint32_t quad_object(bk_scene *s, const char *name, const float p0[3], const float p1[3], const float p2[3],
                            const float p3[3], int n)
{
    uint32_t o = uvs_object(s, name);
    uvs_quad(s, p0, p1, p2, p3, n, 0, NULL, 1.0f);
    return o;
}

static void build(const bk_scene *s, float density, bk_atlas *a, bk_texels *tx)
{
    bk_atlas_options o = {0};
    o.default_density = density;
    assert_int_equal(bk_atlas_build(s, NULL, &o, a), LBK_OK);
    assert_int_equal(bk_texels_build(s, a, tx), LBK_OK);
}

static double len3(const float v[3]) { return sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]); }

/* ---------------------------------------------------------------------------------------- */

/* A flat 1 m quad at d texels/m covers exactly d × d texels with their centres inside, plus
 * the ring of 4d + 4 texels that bilinear filtering reads along its border: those sample the
 * quad's closest point, moved 1 % of a texel in from the border (bake/layout/edge_inset.h: off
 * every outer edge, also the corner ones at the ends of the quad's diagonal, which belong to the
 * other triangle), and are marked EDGE, and RING because the quad lies on the texel grid, so
 * their squares only share a side or a corner with it (zero area: no footprint). */
static void test_quad_texel_count(void **state)
{
    (void)state;
    const int dens[] = {4, 8, 13};
    for (int i = 0; i < 3; i++) {
        bk_scene s;
        uvs_init(&s);
        float p0[3] = {0, 0, 0}, p1[3] = {1, 0, 0}, p2[3] = {1, 0, -1}, p3[3] = {0, 0, -1};
        quad_object(&s, "q", p0, p1, p2, p3, 3);
        bk_atlas a;
        bk_texels tx;
        build(&s, (float)dens[i], &a, &tx);
        assert_int_equal(tx.count, (size_t)((dens[i] + 2) * (dens[i] + 2)));
        size_t inside = 0;
        for (size_t r = 0; r < tx.count; r++) {
            const float *p = tx.receivers[r].position;
            const double step = 0.01 / dens[i];
            const double edge_dist[4] = {p[0], 1.0 - p[0], -(double)p[2], 1.0 + p[2]};
            double nearest = 1;
            for (int k = 0; k < 4; k++) nearest = fmin(nearest, edge_dist[k]);
            inside += tx.receivers[r].flags == BK_TEXEL_VALID;
            if (tx.receivers[r].flags != BK_TEXEL_VALID) {
                assert_int_equal(tx.receivers[r].flags, BK_TEXEL_VALID | BK_TEXEL_EDGE | BK_TEXEL_RING);
                assert_int_equal(tx.receivers[r].footprint_count, 0);
                assert_true(nearest > 0.99 * step && nearest < 1.01 * step); /* inset, still at the border */
            }
            assert_true(p[0] >= 0.0f && p[0] <= 1.0f && p[2] <= 0.0f && p[2] >= -1.0f);
            assert_int_equal(tx.receivers[r].object, 0);
            assert_float_equal(tx.receivers[r].texel_size, 1.0 / dens[i], 1e-5);
            assert_float_equal(tx.receivers[r].position[1], 0.0, 1e-6);
        }
        bk_texels_free(&tx);
        bk_atlas_free(&a);
        uvs_free(&s);
    }
}

/* Every texel whose centre lies (strictly) inside a chart triangle is a valid receiver on
 * that triangle's plane; every receiver is unit-normal with a unit tangent ⟂ normal. */
static void test_coverage_and_frames(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "sphere");
    float c[3] = {0, 1, 0};
    uvs_sphere(&s, c, 0.8f, 20, 10, 0);
    uvs_object(&s, "box");
    float mn[3] = {2, 0, 0}, mx[3] = {2.7f, 0.45f, 1.3f};
    uvs_box(&s, mn, mx, 2, 0, 0);
    float p0[3] = {-3, 0, 3}, p1[3] = {4, 0, 3}, p2[3] = {4, 0.3f, -3}, p3[3] = {-3, 0, -3}; /* not planar */
    quad_object(&s, "floor", p0, p1, p2, p3, 5);
    bk_atlas a;
    bk_texels tx;
    build(&s, 9.5f, &a, &tx);
    size_t strictly_inside = 0;
    for (size_t e = 0; e < a.tri_count; e++) {
        const float *uv = a.tri_uv + 6 * e;
        double x0 = uv[0], y0 = uv[1], x1 = uv[2], y1 = uv[3], x2 = uv[4], y2 = uv[5];
        double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
        int page = a.charts[a.tri_chart[e]].page;
        int xa = (int)floor(fmin(x0, fmin(x1, x2))), xb = (int)ceil(fmax(x0, fmax(x1, x2)));
        int ya = (int)floor(fmin(y0, fmin(y1, y2))), yb = (int)ceil(fmax(y0, fmax(y1, y2)));
        for (int y = ya; y <= yb; y++)
            for (int x = xa; x <= xb; x++) {
                double px = x + 0.5, py = y + 0.5;
                double w0 = ((x1 - px) * (y2 - py) - (x2 - px) * (y1 - py)) / area;
                double w1 = ((x2 - px) * (y0 - py) - (x0 - px) * (y2 - py)) / area;
                double w2 = 1.0 - w0 - w1;
                if (!(w0 > 1e-4 && w1 > 1e-4 && w2 > 1e-4)) continue;
                strictly_inside++;
                const bk_texel *r = bk_texels_at(&tx, (uint32_t)page, x, y);
                assert_non_null(r);
                assert_true(r->flags & BK_TEXEL_VALID);
                assert_false(r->flags & BK_TEXEL_EDGE);
                assert_int_equal(r->tri, a.tris[e]);
                /* the sample is the barycentric point of that triangle */
                for (int k = 0; k < 3; k++) {
                    const float *P0 = s.positions + 3 * s.tris[3 * a.tris[e]], *P1 = s.positions + 3 * s.tris[3 * a.tris[e] + 1],
                                *P2 = s.positions + 3 * s.tris[3 * a.tris[e] + 2];
                    assert_float_equal(r->position[k], w0 * P0[k] + w1 * P1[k] + w2 * P2[k], 1e-4);
                }
            }
    }
    assert_true(strictly_inside > 1000);
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *r = &tx.receivers[i];
        assert_float_equal(len3(r->normal), 1.0, 1e-5);
        assert_float_equal(len3(r->tangent), 1.0, 1e-5);
        double d = (double)r->normal[0] * r->tangent[0] + (double)r->normal[1] * r->tangent[1] +
                   (double)r->normal[2] * r->tangent[2];
        assert_float_equal(d, 0.0, 1e-5);
        assert_true(r->texel_size > 0.0f && isfinite(r->texel_size));
        /* index and receiver agree */
        assert_ptr_equal(bk_texels_at(&tx, r->page, r->x, r->y), r);
    }
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* T is dP/du: the receiver one texel to the right lies one texel_size along T, and B = N×T
 * points to the receiver one texel down (generated charts are never mirrored). */
static void test_tangent_convention(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    float p0[3] = {0, 0, 0}, p1[3] = {0.6f, 0.8f, 0}, p2[3] = {0.6f, 0.8f, -2}, p3[3] = {0, 0, -2}; /* tilted */
    quad_object(&s, "ramp", p0, p1, p2, p3, 2);
    bk_atlas a;
    bk_texels tx;
    build(&s, 10.0f, &a, &tx);
    size_t checked = 0;
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *r = &tx.receivers[i], *right = bk_texels_at(&tx, r->page, r->x + 1, r->y),
                          *down = bk_texels_at(&tx, r->page, r->x, r->y + 1);
        if (!right || !down || (r->flags | right->flags | down->flags) & BK_TEXEL_EDGE) continue;
        float b[3] = {r->normal[1] * r->tangent[2] - r->normal[2] * r->tangent[1],
                      r->normal[2] * r->tangent[0] - r->normal[0] * r->tangent[2],
                      r->normal[0] * r->tangent[1] - r->normal[1] * r->tangent[0]};
        for (int k = 0; k < 3; k++) {
            assert_float_equal(right->position[k] - r->position[k], r->tangent[k] * r->texel_size, 1e-4);
            assert_float_equal(down->position[k] - r->position[k], b[k] * r->texel_size, 1e-4);
        }
        checked++;
    }
    assert_true(checked > 100);
    /* the helper */
    float n[3] = {0, 0, 1}, dpdu[3] = {2, 0, 1}, t[3], bb[3];
    bk_tangent_frame(n, dpdu, t, bb);
    assert_float_equal(t[0], 1, 1e-6);
    assert_float_equal(t[1], 0, 1e-6);
    assert_float_equal(t[2], 0, 1e-6);
    assert_float_equal(bb[0], 0, 1e-6);
    assert_float_equal(bb[1], 1, 1e-6);
    assert_float_equal(bb[2], 0, 1e-6);
    float zero[3] = {0, 0, 0}, n2[3] = {0.f, -0.6f, 0.8f};
    bk_tangent_frame(n2, zero, t, bb);
    assert_float_equal(len3(t), 1.0, 1e-6);
    assert_float_equal(len3(bb), 1.0, 1e-6);
    assert_float_equal(t[0] * n2[0] + t[1] * n2[1] + t[2] * n2[2], 0.0, 1e-6);
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Degenerate triangles and uv-collapsed triangles never produce receivers or NaNs. */
static void test_degenerate(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    float p0[3] = {0, 0, 0}, p1[3] = {1, 0, 0}, p2[3] = {1, 0, -1}, p3[3] = {0, 0, -1};
    quad_object(&s, "q", p0, p1, p2, p3, 1);
    float c0[3] = {0, 1, 0}, c1[3] = {1, 1, 0}, c2[3] = {2, 1, 0};
    uvs_tri(&s, c0, c1, c2, 0);
    uvs_tri(&s, c0, c0, c0, 0);
    bk_atlas a;
    bk_texels tx;
    build(&s, 6.0f, &a, &tx);
    assert_int_equal(tx.count, 8 * 8); /* 6 × 6 and the bilinear ring */
    for (size_t i = 0; i < tx.count; i++) {
        assert_int_not_equal(tx.receivers[i].tri, 2);
        assert_int_not_equal(tx.receivers[i].tri, 3);
        for (int k = 0; k < 3; k++) assert_true(isfinite(tx.receivers[i].position[k]));
    }
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* ---------------------------------------------------------------------------------------- */
/* Push-out                                                                                 */

/* An L junction: a floor (y = 0, facing +y) that runs 0.12 m under a wall (x = 0, facing +x)
 * which itself reaches 0.12 m below the floor. Texels are 0.1 m. */
static void l_junction(bk_scene *s)
{
    uvs_init(s);
    float f0[3] = {-0.12f, 0, 0}, f1[3] = {2, 0, 0}, f2[3] = {2, 0, -2}, f3[3] = {-0.12f, 0, -2};
    quad_object(s, "floor", f0, f1, f2, f3, 4);
    float w0[3] = {0, -0.12f, 0}, w1[3] = {0, -0.12f, -2}, w2[3] = {0, 2, -2}, w3[3] = {0, 2, 0};
    quad_object(s, "wall", w0, w1, w2, w3, 4);
    uvs_update_bounds(s);
}

static void test_pushout_l_junction(void **state)
{
    (void)state;
    bk_scene s;
    l_junction(&s);
    bk_atlas a;
    bk_texels tx;
    build(&s, 10.0f, &a, &tx);
    bk_tracer *tr = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    /* before: samples behind the wall (floor, x < 0) and under the floor (wall, y < 0) */
    size_t behind = 0;
    float *before = malloc(tx.count * 3 * sizeof(float));
    assert_non_null(before);
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *r = &tx.receivers[i];
        memcpy(before + 3 * i, r->position, 3 * sizeof(float));
        if ((r->object == 0 && r->position[0] < 0) || (r->object == 1 && r->position[1] < 0)) behind++;
    }
    assert_true(behind >= 2 * 20); /* one column of 20 texels on each side */
    bk_pushout_stats st;
    assert_int_equal(bk_texels_push_out(&tx, &s, tr, NULL, &st), LBK_OK);
    assert_int_equal(st.tested, tx.count);
    /* the two ring texels at the far corners sample the corner vertex itself, on the edge of
     * the other quad, where the short rays graze past it; only filtering behind the wall reads
     * them */
    assert_true(st.pushed + 2 >= behind);
    assert_int_equal(st.inside, 0);
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *r = &tx.receivers[i];
        assert_true(r->flags & BK_TEXEL_VALID);
        /* nothing behind the wall or below the floor (but those two corners), and nothing
         * moved far */
        int corner = (r->flags & BK_TEXEL_EDGE) && !(r->flags & BK_TEXEL_PUSHED) &&
                     ((r->object == 0 && before[3 * i] == -0.12f) || (r->object == 1 && before[3 * i + 1] == -0.12f));
        assert_true(r->position[0] >= 0.0f || corner);
        assert_true(r->position[1] >= 0.0f || corner);
        double mv = 0;
        for (int k = 0; k < 3; k++) mv += (r->position[k] - before[3 * i + k]) * (r->position[k] - before[3 * i + k]);
        assert_true(sqrt(mv) <= 0.15 + 1e-4);
        /* samples well clear of the junction are untouched */
        int far_from_junction = r->object == 0 ? before[3 * i] > 0.2f : before[3 * i + 1] > 0.2f;
        if (far_from_junction) {
            assert_false(r->flags & BK_TEXEL_PUSHED);
            assert_memory_equal(r->position, before + 3 * i, 3 * sizeof(float));
        }
    }
    free(before);
    bk_tracer_destroy(tr);
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* A closed box standing on a floor that runs under it: floor texels deep under the box are
 * marked inside (and still baked: the transport makes them black), those near its walls are
 * pushed out, the rest untouched. The result is the same for 1 and 3 threads. */
static void test_pushout_inside_and_threads(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    float f0[3] = {-2, 0, 2}, f1[3] = {2, 0, 2}, f2[3] = {2, 0, -2}, f3[3] = {-2, 0, -2};
    quad_object(&s, "floor", f0, f1, f2, f3, 4);
    uvs_object(&s, "box");
    float mn[3] = {-0.5f, 0, -0.5f}, mx[3] = {0.5f, 1, 0.5f};
    uvs_box(&s, mn, mx, 1, 0, 0);
    uvs_update_bounds(&s);
    bk_atlas a;
    bk_texels t1, t3;
    build(&s, 10.0f, &a, &t1);
    assert_int_equal(bk_texels_build(&s, &a, &t3), LBK_OK);
    bk_tracer *tr = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    bk_pushout_options o1 = {0}, o3 = {0};
    o1.threads = 1;
    o3.threads = 3;
    bk_pushout_stats st;
    assert_int_equal(bk_texels_push_out(&t1, &s, tr, &o1, &st), LBK_OK);
    assert_int_equal(bk_texels_push_out(&t3, &s, tr, &o3, NULL), LBK_OK);
    assert_int_equal(t1.count, t3.count);
    assert_memory_equal(t1.receivers, t3.receivers, t1.count * sizeof *t1.receivers);
    size_t inside = 0;
    for (size_t i = 0; i < t1.count; i++) {
        const bk_texel *r = &t1.receivers[i];
        if (r->object != 0) {
            assert_true(r->flags & BK_TEXEL_VALID);
            continue;
        }
        double ax = fabs(r->position[0]), az = fabs(r->position[2]);
        int under = ax < 0.5 && az < 0.5;
        assert_true(r->flags & BK_TEXEL_VALID);
        /* a floor sample under the box is marked inside; one marked inside is under it */
        if (under) assert_true(r->flags & BK_TEXEL_INSIDE);
        if (r->flags & BK_TEXEL_INSIDE) {
            assert_true(under);
            inside++;
        }
        if (ax < 0.3 && az < 0.3) assert_true(r->flags & BK_TEXEL_INSIDE); /* deep under */
        /* well clear: untouched (the floor's border ring is EDGE and RING: the 4 m floor lies on
         * the texel grid at 10 texels/m, so the ring's squares only touch it) */
        if (ax > 0.7 || az > 0.7)
            assert_int_equal(r->flags & ~(uint32_t)(BK_TEXEL_EDGE | BK_TEXEL_RING), BK_TEXEL_VALID);
    }
    assert_int_equal(inside, st.inside);
    assert_true(inside >= 36);
    bk_tracer_destroy(tr);
    bk_texels_free(&t1);
    bk_texels_free(&t3);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* A panel hung 5 mm over a floor at 10 texels/m (the band: a tenth of a texel), its back to the
 * floor, like the Cornell box's light under its ceiling: floor texels whose square the panel
 * hides in part lose their footprint (they keep their point: averaged over the hidden part,
 * bilinear filtering would spread it over the floor beside the panel), the others keep it. */
static void test_pushout_hidden_footprint(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    float f0[3] = {0, 0, 0}, f1[3] = {2, 0, 0}, f2[3] = {2, 0, -2}, f3[3] = {0, 0, -2};
    quad_object(&s, "floor", f0, f1, f2, f3, 4);
    const float h = 0.005f;
    float q0[3] = {0.5f, h, -0.5f}, q1[3] = {0.9f, h, -0.5f}, q2[3] = {0.9f, h, -0.9f}, q3[3] = {0.5f, h, -0.9f};
    quad_object(&s, "panel", q0, q1, q2, q3, 1);
    uvs_update_bounds(&s);
    bk_atlas a;
    bk_texels tx;
    build(&s, 10.0f, &a, &tx);
    float *centre = malloc(3 * tx.count * sizeof *centre);
    assert_non_null(centre);
    for (size_t i = 0; i < tx.count; i++) memcpy(centre + 3 * i, tx.receivers[i].position, 12);
    bk_tracer *tr = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    assert_int_equal(bk_texels_push_out(&tx, &s, tr, NULL, NULL), LBK_OK);
    size_t hidden = 0, kept = 0;
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *r = &tx.receivers[i];
        if (r->object != 0 || (r->flags & BK_TEXEL_RING)) continue;
        /* the square's overlap with the panel's shadow, per axis (texels: 0.1 m, half 0.05) */
        double ox = 0.25 - fabs(centre[3 * i] - 0.7), oz = 0.25 - fabs(centre[3 * i + 2] + 0.7);
        /* more than a probe cell (1/8 texel) of overlap on both axes: the 4 × 4 probes see it */
        if (ox > 0.0125 && oz > 0.0125) {
            assert_int_equal(r->footprint_count, 0);
            hidden++;
        }
        if (ox < 0 || oz < 0) {
            assert_true(r->footprint_count >= 1);
            kept++;
        }
    }
    assert_true(hidden >= 16); /* the 4 × 4 texels under the panel, at least */
    assert_true(kept > 300);
    free(centre);
    bk_tracer_destroy(tr);
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* ---------------------------------------------------------------------------------------- */
/* Dilation                                                                                 */

/* A filled rectangle: `passes` passes fill exactly the ring of Chebyshev distance ≤ passes
 * and every filled texel copies the nearest valid texel (clamp to the rectangle). */
static void test_dilate_ring_values(void **state)
{
    (void)state;
    const int W = 24, H = 20, bx0 = 7, bx1 = 14, by0 = 5, by1 = 11;
    float *data = calloc((size_t)W * H * 2, sizeof(float));
    uint8_t *mask = calloc((size_t)W * H, 1);
    assert_non_null(data);
    assert_non_null(mask);
    for (int y = by0; y <= by1; y++)
        for (int x = bx0; x <= bx1; x++) {
            mask[y * W + x] = 1;
            data[2 * (y * W + x)] = (float)(x * 100 + y);
            data[2 * (y * W + x) + 1] = (float)-x;
        }
    for (int passes = 1; passes <= 3; passes++) {
        float *d = malloc((size_t)W * H * 2 * sizeof(float));
        uint8_t *m = malloc((size_t)W * H);
        memcpy(d, data, (size_t)W * H * 2 * sizeof(float));
        memcpy(m, mask, (size_t)W * H);
        size_t filled = bk_dilate(d, 2, m, W, H, passes);
        size_t ring = (size_t)(bx1 - bx0 + 1 + 2 * passes) * (size_t)(by1 - by0 + 1 + 2 * passes) -
                      (size_t)(bx1 - bx0 + 1) * (size_t)(by1 - by0 + 1);
        assert_int_equal(filled, ring);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                int dx = x < bx0 ? bx0 - x : x > bx1 ? x - bx1 : 0;
                int dy = y < by0 ? by0 - y : y > by1 ? y - by1 : 0;
                int cheb = dx > dy ? dx : dy;
                if (cheb == 0) {
                    assert_int_equal(m[y * W + x], 1);
                } else if (cheb <= passes) {
                    assert_int_equal(m[y * W + x], 2);
                    int cx = x < bx0 ? bx0 : x > bx1 ? bx1 : x, cy = y < by0 ? by0 : y > by1 ? by1 : y;
                    assert_float_equal(d[2 * (y * W + x)], (float)(cx * 100 + cy), 0);
                    assert_float_equal(d[2 * (y * W + x) + 1], (float)-cx, 0);
                } else {
                    assert_int_equal(m[y * W + x], 0);
                    assert_float_equal(d[2 * (y * W + x)], 0.0f, 0);
                }
            }
        free(d);
        free(m);
    }
    /* an L-shaped hole between two values gets their mean where both are 4-neighbours */
    float v[9] = {1, 0, 0, 0, 0, 0, 0, 0, 0};
    uint8_t mk[9] = {1, 0, 1, 0, 0, 0, 0, 0, 0};
    v[2] = 3;
    assert_int_equal(bk_dilate(v, 1, mk, 3, 3, 1), 4);
    assert_float_equal(v[1], 2.0f, 0);       /* between 1 and 3 */
    assert_float_equal(v[3], 1.0f, 0);       /* below 1 */
    assert_float_equal(v[4], 2.0f, 0);       /* diagonal to both */
    assert_int_equal(mk[6], 0);              /* distance 2 */
    /* bad arguments fill nothing */
    assert_int_equal(bk_dilate(NULL, 1, mk, 3, 3, 1), 0);
    assert_int_equal(bk_dilate(v, 0, mk, 3, 3, 1), 0);
    free(data);
    free(mask);
}

/* Conservative coverage: bilinear filtering at any point of any chart triangle (corners, edge
 * points, interior points) reads only texels that hold a receiver of that same chart, for
 * generated charts (boxes, spheres, thin strips, turned by the packer) and an authored uv1
 * layout. Dilation afterwards fills only texels outside every chart's footprint: it never
 * changes what filtering reads. */
static void test_conservative_coverage(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    for (int i = 0; i < 6; i++) {
        uvs_object(&s, "box");
        float mn[3] = {(float)i * 2, 0, 0}, mx[3] = {(float)i * 2 + 0.3f + 0.17f * (float)i, 0.6f, 0.4f + 0.1f * (float)i};
        uvs_box(&s, mn, mx, 1, 0, 0);
    }
    uvs_object(&s, "sphere");
    float c[3] = {0, 3, 0};
    uvs_sphere(&s, c, 0.7f, 24, 12, 0);
    uvs_object(&s, "strips");
    for (int i = 0; i < 5; i++) {
        float z = -0.4f * (float)i, len = 0.7f + 0.3f * (float)i;
        float p0[3] = {0, 5, z}, p1[3] = {len, 5, z}, p2[3] = {len, 5, z - 0.07f}, p3[3] = {0, 5, z - 0.07f};
        uvs_quad(&s, p0, p1, p2, p3, 1, 0, NULL, 1.0f);
    }
    uint32_t authored = uvs_object(&s, "authored");
    float p0[3] = {3, 5, 0}, p1[3] = {4.3f, 5, 0}, p2[3] = {4.3f, 5, -0.9f}, p3[3] = {3, 5, -0.9f};
    float uo[2] = {0.1f, 0.05f};
    uvs_quad(&s, p0, p1, p2, p3, 3, 0, uo, 0.8f);
    s.objects[authored].has_uv1 = 1;
    uvs_update_bounds(&s);
    bk_atlas a;
    bk_texels tx;
    build(&s, 13.0f, &a, &tx);
    assert_int_equal(a.objects[a.object_slot[authored]].uv_source, BK_UV_AUTHORED);
    size_t points = 0;
    for (size_t e = 0; e < a.tri_count; e++) {
        const float *q = a.tri_uv + 6 * e;
        uint32_t chart = a.tri_chart[e];
        int page = a.charts[chart].page, W = a.pages[page].width, H = a.pages[page].height;
        /* a barycentric grid of 16 steps: corners, edge points and interior points */
        for (int i = 0; i <= 16; i++)
            for (int j = 0; i + j <= 16; j++) {
                double w1 = i / 16.0, w2 = j / 16.0, w0 = 1.0 - w1 - w2;
                double x = w0 * q[0] + w1 * q[2] + w2 * q[4], y = w0 * q[1] + w1 * q[3] + w2 * q[5];
                int32_t idx[4];
                double wt[4];
                bk_bilinear_taps(x, y, W, H, idx, wt);
                for (int k = 0; k < 4; k++) {
                    if (wt[k] == 0.0) continue;
                    const bk_texel *r = bk_texels_at(&tx, (uint32_t)page, idx[k] % W, idx[k] / W);
                    assert_non_null(r);
                    assert_int_equal(a.tri_chart[a.scene_tri_entry[r->tri]], chart);
                }
                points++;
            }
    }
    assert_true(points > 10000);
    /* dilation fills only what no chart's filter reads */
    for (uint32_t p = 0; p < a.page_count; p++) {
        int W = a.pages[p].width, H = a.pages[p].height;
        float *d = calloc((size_t)W * H, sizeof(float));
        uint8_t *m = calloc((size_t)W * H, 1);
        assert_non_null(d);
        assert_non_null(m);
        for (int i = 0; i < W * H; i++) {
            const bk_texel *r = bk_texels_at(&tx, p, i % W, i / W);
            if (!r) continue;
            m[i] = 1;
            d[i] = (float)a.tri_chart[a.scene_tri_entry[r->tri]];
        }
        bk_dilate(d, 1, m, W, H, a.margin + 2);
        for (int i = 0; i < W * H; i++) {
            const bk_texel *r = bk_texels_at(&tx, p, i % W, i / W);
            if (r) assert_float_equal(d[i], (float)a.tri_chart[a.scene_tri_entry[r->tri]], 0);
        }
        free(d);
        free(m);
    }
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Extremes: the same furnished room at 1 mm, 10 km, and 1e5 m from the origin. The atlas
 * keeps its rules and budget, and every receiver is finite with unit vectors after push-out;
 * valid floor samples never end up under the box. */
static void test_extreme_scales(void **state)
{
    (void)state;
    const double scales[3] = {1e-3, 1e4, 1.0};
    const double offsets[3] = {0.0, 0.0, 1e5};
    for (int v = 0; v < 3; v++) {
        bk_scene s;
        uvs_init(&s);
        uvs_object(&s, "room");
        float rmn[3] = {-2, 0, -2}, rmx[3] = {2, 2.5f, 2};
        uvs_box(&s, rmn, rmx, 2, 1, 0);
        uvs_object(&s, "box");
        float bmn[3] = {-0.5f, 0, -0.5f}, bmx[3] = {0.5f, 1, 0.5f};
        uvs_box(&s, bmn, bmx, 1, 0, 0);
        for (size_t i = 0; i < 3 * s.vertex_count; i++)
            s.positions[i] = (float)(s.positions[i] * scales[v] + (i % 3 == 0 ? offsets[v] : 0.0));
        uvs_update_bounds(&s);
        bk_atlas_options o = {0};
        o.default_density = 8.0f;
        o.texel_budget = 1u << 16;
        bk_atlas a;
        assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
        assert_true(a.texels > 0);
        uint64_t rects = 0;
        for (size_t i = 0; i < a.object_count; i++) rects += (uint64_t)a.objects[i].w * (uint64_t)a.objects[i].h;
        assert_true(rects <= o.texel_budget);
        for (size_t i = 0; i < a.tri_count * 6; i++) assert_true(isfinite(a.tri_uv[i]));
        for (size_t i = 0; i < a.vertex_count * 2; i++)
            assert_true(a.vertex_uv[i] >= 0.0f && a.vertex_uv[i] <= 1.0f);
        bk_texels tx;
        assert_int_equal(bk_texels_build(&s, &a, &tx), LBK_OK);
        bk_tracer *tr = NULL;
        assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
        assert_int_equal(bk_texels_push_out(&tx, &s, tr, NULL, NULL), LBK_OK);
        double half = 0.5 * scales[v];
        for (size_t i = 0; i < tx.count; i++) {
            const bk_texel *r = &tx.receivers[i];
            for (int k = 0; k < 3; k++) assert_true(isfinite(r->position[k]));
            assert_float_equal(len3(r->normal), 1.0, 1e-5);
            assert_float_equal(len3(r->tangent), 1.0, 1e-5);
            assert_true(r->texel_size > 0.0f && isfinite(r->texel_size));
            if (r->object == 0 && !(r->flags & BK_TEXEL_INSIDE) && r->position[1] < 0.5 * scales[v]) {
                double x = r->position[0] - offsets[v], z = r->position[2];
                /* floor texels not marked inside: never strictly under the box (its footprint
                 * minus rounding) */
                assert_false(fabs(x) < half * 0.98 && fabs(z) < half * 0.98);
            }
        }
        bk_tracer_destroy(tr);
        bk_texels_free(&tx);
        bk_atlas_free(&a);
        uvs_free(&s);
    }
}

/* Footprints against brute force: for random points of every texel's square, "some footprint
 * triangle covers it" equals "some triangle of the texel's chart covers it" (the whole chart
 * searched), and both give the same world point. A ring texel (read only by bilinear filtering:
 * its chart meets the square of half-size 1 around its centre but not its own square) has no
 * footprint, and the brute force finds no chart point in its square either. A sphere of many
 * small triangles (charts of many triangles per texel) and a box (chart borders, padding) at
 * two densities. */
static void test_footprint_equals_chart_cover(void **state)
{
    (void)state;
    const float dens[2] = {6.0f, 23.0f};
    for (int dv = 0; dv < 2; dv++) {
        bk_scene s;
        uvs_init(&s);
        uvs_object(&s, "sphere");
        float c[3] = {0, 1, 0};
        uvs_sphere(&s, c, 0.6f, 32, 16, 0);
        uvs_object(&s, "box");
        float mn[3] = {1, 0, -0.3f}, mx[3] = {1.7f, 0.4f, 0.3f};
        uvs_box(&s, mn, mx, 2, 0, 0);
        uvs_update_bounds(&s);
        bk_atlas a;
        bk_texels tx;
        build(&s, dens[dv], &a, &tx);
        uint64_t rng = 0x1234567ull + (uint64_t)dv;
        size_t points = 0, covered = 0, multi = 0, rings = 0;
        for (size_t i = 0; i < tx.count; i++) {
            const bk_texel *r = &tx.receivers[i];
            assert_true(r->flags & BK_TEXEL_VALID);
            if (r->flags & BK_TEXEL_RING) {
                assert_int_equal(r->footprint_count, 0);
                assert_true(r->flags & BK_TEXEL_EDGE); /* its centre is off the chart, too */
                rings++;
            } else {
                assert_true(r->footprint_count >= 1);
            }
            assert_true((size_t)r->footprint_first + r->footprint_count <= tx.footprint_count);
            multi += r->footprint_count > 1;
            int32_t own = a.scene_tri_entry[r->tri];
            assert_true(own >= 0);
            const bk_atlas_chart *ch = &a.charts[a.tri_chart[own]];
            for (int k = 0; k < 24; k++) {
                rng = rng * 6364136223846793005ull + 1442695040888963407ull;
                double ps = (double)(rng >> 11) / 9007199254740992.0;
                rng = rng * 6364136223846793005ull + 1442695040888963407ull;
                double pt = (double)(rng >> 11) / 9007199254740992.0;
                /* brute force over the chart, in page coordinates; skip points within 1e-6 of an edge */
                double px = r->x + ps, py = r->y + pt, bf[3] = {0, 0, 0};
                int bf_hit = 0, near_edge = 0;
                for (uint32_t e = ch->first; e < ch->first + ch->count && !bf_hit; e++) {
                    const float *uv = a.tri_uv + 6 * (size_t)e;
                    double d = (uv[2] - uv[0]) * (uv[5] - uv[1]) - (uv[4] - uv[0]) * (uv[3] - uv[1]);
                    if (d == 0) continue;
                    double w1 = ((px - uv[0]) * (uv[5] - uv[1]) - (uv[4] - uv[0]) * (py - uv[1])) / d;
                    double w2 = ((uv[2] - uv[0]) * (py - uv[1]) - (px - uv[0]) * (uv[3] - uv[1])) / d;
                    double w0 = 1 - w1 - w2;
                    if (fabs(w0) < 1e-6 || fabs(w1) < 1e-6 || fabs(w2) < 1e-6) near_edge = 1;
                    if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                    bf_hit = 1;
                    const uint32_t *ix = s.tris + 3 * (size_t)a.tris[e];
                    for (int q = 0; q < 3; q++)
                        bf[q] = w0 * s.positions[3 * ix[0] + q] + w1 * s.positions[3 * ix[1] + q] +
                                w2 * s.positions[3 * ix[2] + q];
                }
                if (near_edge) continue;
                int fp_hit = 0;
                double fp[3] = {0, 0, 0};
                for (uint32_t k2 = 0; k2 < r->footprint_count && !fp_hit; k2++) {
                    const bk_footprint_tri *f = &tx.footprint[r->footprint_first + k2];
                    double u = f->uv[0][0] + f->uv[0][1] * ps + f->uv[0][2] * pt;
                    double v = f->uv[1][0] + f->uv[1][1] * ps + f->uv[1][2] * pt;
                    if (u < 0 || v < 0 || u + v > 1) continue;
                    fp_hit = 1;
                    const uint32_t *ix = s.tris + 3 * (size_t)f->tri;
                    for (int q = 0; q < 3; q++)
                        fp[q] = (1 - u - v) * s.positions[3 * ix[0] + q] + u * s.positions[3 * ix[1] + q] +
                                v * s.positions[3 * ix[2] + q];
                }
                points++;
                assert_int_equal(fp_hit, bf_hit);
                if (!bf_hit) continue;
                covered++;
                for (int q = 0; q < 3; q++) assert_true(fabs(fp[q] - bf[q]) < 1e-4);
            }
        }
        print_message("density %g: %zu texels (%zu ring), %zu footprint triangles (%zu texels with several), %zu of "
                      "%zu points covered\n",
                      dens[dv], tx.count, rings, tx.footprint_count, multi, covered, points);
        assert_true(rings > 0 && rings < tx.count / 2); /* the conservative ring exists, around charts */
        assert_true(tx.footprint_count >= tx.count - rings);
        assert_true(multi > tx.count / 20);  /* many small triangles: texels do span several */
        assert_true(covered < points);       /* chart borders: parts of squares are uncovered */
        bk_texels_free(&tx);
        bk_atlas_free(&a);
        uvs_free(&s);
    }
}

/* An authored layout is one chart of many islands: two faces of a slab (top up, bottom down)
 * whose islands touch in uv1. A texel on the seam overlaps both, but its footprint keeps only
 * its own island (else a floor texel would average in the floor's underside). */
static void test_footprint_stays_on_island(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uint32_t o = uvs_object(&s, "slab");
    float t0[3] = {0, 0.1f, 0}, t1[3] = {2, 0.1f, 0}, t2[3] = {2, 0.1f, -2}, t3[3] = {0, 0.1f, -2};
    float b0[3] = {0, 0, -2}, b1[3] = {2, 0, -2}, b2[3] = {2, 0, 0}, b3[3] = {0, 0, 0};
    const float top_uv[2] = {0.0f, 0.0f}, bottom_uv[2] = {0.5f, 0.0f};
    uvs_quad(&s, t0, t1, t2, t3, 2, 0, top_uv, 0.5f);
    uvs_quad(&s, b0, b1, b2, b3, 2, 0, bottom_uv, 0.5f);
    s.objects[o].has_uv1 = 1;
    uvs_update_bounds(&s);
    bk_atlas a;
    bk_texels tx;
    build(&s, 8.0f, &a, &tx);
    assert_int_equal(a.objects[0].uv_source, BK_UV_AUTHORED);
    size_t seam = 0;
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *r = &tx.receivers[i];
        int own_up = r->normal[1] > 0;
        for (uint32_t k = 0; k < r->footprint_count; k++) {
            uint32_t t = tx.footprint[r->footprint_first + k].tri;
            const float *n = s.normals + 3 * (size_t)s.tris[3 * (size_t)t];
            assert_int_equal(n[1] > 0, own_up);
        }
        /* texels whose square crosses the seam between the islands */
        int32_t e = a.scene_tri_entry[r->tri];
        double mx = 0;
        for (int c = 0; c < 3; c++) mx = fmax(mx, a.tri_uv[6 * (size_t)e + 2 * c]);
        seam += own_up && r->x + 1 > mx - 1e-3 && r->x < mx;
    }
    assert_true(seam >= 4);
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quad_texel_count),
        cmocka_unit_test(test_coverage_and_frames),
        cmocka_unit_test(test_footprint_equals_chart_cover),
        cmocka_unit_test(test_footprint_stays_on_island),
        cmocka_unit_test(test_tangent_convention),
        cmocka_unit_test(test_degenerate),
        cmocka_unit_test(test_pushout_l_junction),
        cmocka_unit_test(test_pushout_inside_and_threads),
        cmocka_unit_test(test_pushout_hidden_footprint),
        cmocka_unit_test(test_dilate_ring_values),
        cmocka_unit_test(test_conservative_coverage),
        cmocka_unit_test(test_extreme_scales),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
