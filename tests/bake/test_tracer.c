/* Tracer: hits, misses, occlusion, self-intersection robustness far from the origin and at
 * extreme scales, degenerate input. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/tracer.h"
#include "support/transport_scenes.h"

static void test_quad_hit_and_miss(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float p0[3] = {-1, -1, 0}, p1[3] = {1, -1, 0}, p2[3] = {1, 1, 0}, p3[3] = {-1, 1, 0};
    tsc_quad(&s, p0, p1, p2, p3, 1, m);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    assert_int_equal(bk_tracer_tri_count(t), 2);
    assert_float_equal(bk_tracer_tri_area(t, 0) + bk_tracer_tri_area(t, 1), 4.0f, 1e-6f);

    float org[3] = {0.5f, -0.25f, 3}, dir[3] = {0, 0, -2};
    bk_hit h;
    assert_int_equal(bk_tracer_intersect(t, org, dir, 0, INFINITY, &h), 1);
    assert_float_equal(h.t, 1.5f, 1e-6f); /* t in units of |dir| = 2 */
    assert_int_equal(h.tri, 0);           /* (0.5,-0.25) lies in triangle p0 p1 p2 */
    assert_float_equal(h.ng[2], 1.0f, 1e-6f);
    assert_int_equal(h.front, 1);
    /* barycentrics reproduce the hit point */
    const float *v0 = s.positions + 3 * s.tris[0], *v1 = s.positions + 3 * s.tris[1], *v2 = s.positions + 3 * s.tris[2];
    for (int k = 0; k < 3; k++) {
        float p = (1 - h.u - h.v) * v0[k] + h.u * v1[k] + h.v * v2[k];
        assert_float_equal(p, org[k] + h.t * dir[k], 1e-5f);
    }
    /* from below: back face */
    float org2[3] = {-0.5f, 0.5f, -1}, up[3] = {0, 0, 1};
    assert_int_equal(bk_tracer_intersect(t, org2, up, 0, INFINITY, &h), 1);
    assert_int_equal(h.tri, 1);
    assert_int_equal(h.front, 0);
    /* tmax short of the plane: miss; outside the quad: miss */
    assert_int_equal(bk_tracer_intersect(t, org, dir, 0, 1.4f, &h), 0);
    assert_int_equal(bk_tracer_occluded(t, org, dir, 0, 1.4f), 0);
    assert_int_equal(bk_tracer_occluded(t, org, dir, 0, 1.6f), 1);
    float org3[3] = {1.5f, 0, 3};
    assert_int_equal(bk_tracer_intersect(t, org3, dir, 0, INFINITY, &h), 0);
    /* non-finite rays are misses, never errors */
    float bad[3] = {NAN, 0, 0}, zero[3] = {0, 0, 0};
    assert_int_equal(bk_tracer_intersect(t, bad, dir, 0, INFINITY, &h), 0);
    assert_int_equal(bk_tracer_occluded(t, org, zero, 0, INFINITY), 0);
    /* stream variant equals single calls */
    float orgs[6] = {0.5f, -0.25f, 3, 1.5f, 0, 3}, dirs[6] = {0, 0, -2, 0, 0, -2}, tmaxs[2] = {INFINITY, INFINITY};
    bk_hit hs[2];
    bk_tracer_intersect_n(t, 2, orgs, dirs, 0, tmaxs, hs);
    assert_int_equal(hs[0].tri, 0);
    assert_float_equal(hs[0].t, 1.5f, 1e-6f);
    assert_int_equal(hs[1].tri, UINT32_MAX);
    assert_int_equal(bk_tracer_embree_error(t, NULL), 0);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static uint64_t splitmix(uint64_t *x)
{
    uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static double uni(uint64_t *x) { return (double)(splitmix(x) >> 11) * (1.0 / 9007199254740992.0); }

/* Rays leaving random points of a box's inner walls (points interpolated from the vertices in
 * float, as the baker computes them), offset along the normal, must reach the far side:
 * the hit distance is at least the box's smallest extent times cos, never ~0. */
static void self_intersection_case(double scale, double offset, int rotate)
{
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {1, 1, 1};
    tsc_box(&s, mn, mx, 3, 1, m);
    if (rotate) tsc_rotate(&s, 0.3, 0.77, -1.1);
    double off[3] = {offset, offset * 0.7, -offset * 0.3};
    tsc_transform(&s, scale, off);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    uint64_t rng = 12345;
    int fails = 0;
    for (int i = 0; i < 20000; i++) {
        uint32_t tri = (uint32_t)(splitmix(&rng) % s.tri_count);
        double a = uni(&rng), b = uni(&rng);
        if (a + b > 1) { a = 1 - a; b = 1 - b; }
        const float *v0 = s.positions + 3 * s.tris[3 * tri], *v1 = s.positions + 3 * s.tris[3 * tri + 1],
                    *v2 = s.positions + 3 * s.tris[3 * tri + 2];
        /* Points within a few ulps of an edge can round to the far side of the adjacent wall's
         * plane (see tracer.h); the baker keeps its sample points clear of edges, and so do we. */
        {
            double e = 0, area2 = 2.0 * bk_tracer_tri_area(t, tri);
            for (int k = 0; k < 3; k++) {
                double l0 = 0, l1 = 0, l2 = 0;
                l0 += ((double)v1[k] - v0[k]) * ((double)v1[k] - v0[k]);
                l1 += ((double)v2[k] - v1[k]) * ((double)v2[k] - v1[k]);
                l2 += ((double)v0[k] - v2[k]) * ((double)v0[k] - v2[k]);
                e = fmax(e, fmax(l0, fmax(l1, l2)));
            }
            double altitude = area2 / sqrt(e);
            double ulp = bk_tracer_tri_scale(t, tri) * 1.1920928955078125e-07;
            double mb = fmin(a, fmin(b, 1 - a - b));
            if (mb * altitude < 8 * ulp) continue;
        }
        float p[3], n[3], o[3], d[3];
        for (int k = 0; k < 3; k++) p[k] = (float)((1 - a - b) * v0[k] + a * v1[k] + b * v2[k]);
        bk_tracer_tri_normal(t, tri, n);
        /* cosine-ish direction into the box: normal plus a random tangent tilt */
        /* from steep to grazing (down to ~0.5 degrees above the wall) */
        double r[3] = {uni(&rng) * 2 - 1, uni(&rng) * 2 - 1, uni(&rng) * 2 - 1};
        double rn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
        for (int k = 0; k < 3; k++) r[k] -= rn * n[k];
        double lift = (i % 4 == 0) ? 0.01 : uni(&rng) * 2;
        for (int k = 0; k < 3; k++) d[k] = (float)(n[k] * lift + r[k]);
        if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] <= 0) continue;
        float cosd = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        bk_offset_ray_origin_scaled(p, n, bk_tracer_tri_scale(t, tri), o);
        bk_hit h;
        if (!bk_tracer_intersect(t, o, d, 0, INFINITY, &h)) {
            fails++;
            if (getenv("TSC_DEBUG"))
                fprintf(stderr, "escaped: a %g b %g scale %g off %g rot %d tri %u lift %g p %.9g %.9g %.9g o %.9g %.9g %.9g\n", a, b, scale,
                        offset, rotate, tri, lift, p[0], p[1], p[2], o[0], o[1], o[2]);
            continue;
        }
        /* a hit on the wall the ray left (coplanar triangle, same normal) is self-intersection;
         * hitting an adjacent wall very close to an edge is legitimate */
        (void)cosd;
        float hn[3];
        bk_tracer_tri_normal(t, h.tri, hn);
        if (hn[0] * n[0] + hn[1] * n[1] + hn[2] * n[2] > 0.5f) {
            fails++;
            if (getenv("TSC_DEBUG"))
                fprintf(stderr, "self-hit: scale %g off %g rot %d tri %u -> %u t %g lift %g\n", scale, offset, rotate,
                        tri, h.tri, h.t * sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), lift);
        }
    }
    assert_int_equal(fails, 0);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static void test_self_intersection_unit(void **state)
{
    (void)state;
    self_intersection_case(1, 0, 0);
    self_intersection_case(1, 0, 1);
}
static void test_self_intersection_far(void **state)
{
    (void)state;
    self_intersection_case(20, 1e5, 0);
    self_intersection_case(20, 1e5, 1);
}
static void test_self_intersection_mm(void **state)
{
    (void)state;
    self_intersection_case(1e-3, 0, 0);
    self_intersection_case(1e-3, 0, 1);
}
static void test_self_intersection_10km(void **state)
{
    (void)state;
    self_intersection_case(1e4, 0, 0);
    self_intersection_case(1e4, 0, 1);
}
static void test_self_intersection_mm_far(void **state)
{
    (void)state;
    self_intersection_case(1e-3, 3.0, 1);
}

static void test_degenerate_input(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {2, 0, 0}, d[3] = {0, 1, 0};
    tsc_tri(&s, a, a, a, m); /* point */
    tsc_tri(&s, a, b, c, m); /* collinear */
    tsc_tri(&s, a, b, b, m); /* duplicate vertex */
    tsc_tri(&s, a, b, d, m); /* a real one */
    tsc_tri(&s, a, b, d, m); /* and its exact duplicate */
    float nanp[3] = {NAN, 0, 0}, infp[3] = {0, INFINITY, 0};
    tsc_tri(&s, nanp, b, d, m);
    tsc_tri(&s, infp, b, d, m);
    s.tris[3 * 6 + 1] = 99999; /* out-of-range index on the last triangle */
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    assert_float_equal(bk_tracer_tri_area(t, 0), 0, 0);
    assert_float_equal(bk_tracer_tri_area(t, 1), 0, 0);
    assert_float_equal(bk_tracer_tri_area(t, 2), 0, 0);
    assert_float_equal(bk_tracer_tri_area(t, 3), 0.5f, 1e-7f);
    assert_float_equal(bk_tracer_tri_area(t, 5), 0, 0);
    assert_float_equal(bk_tracer_tri_area(t, 6), 0, 0);
    bk_hit h;
    float org[3] = {0.2f, 0.2f, 1}, dir[3] = {0, 0, -1};
    assert_int_equal(bk_tracer_intersect(t, org, dir, 0, INFINITY, &h), 1);
    assert_true(h.tri == 3 || h.tri == 4);
    assert_true(isfinite(h.t) && isfinite(h.u) && isfinite(h.v));
    /* grazing the degenerate ones along the x axis: finite results or misses, nothing else */
    float org2[3] = {-1, 0, 0}, dir2[3] = {1, 0, 0};
    if (bk_tracer_intersect(t, org2, dir2, 0, INFINITY, &h)) {
        assert_true(isfinite(h.t) && isfinite(h.ng[0]) && isfinite(h.ng[1]) && isfinite(h.ng[2]));
        assert_true(h.tri == 3 || h.tri == 4);
    }
    for (int i = 0; i < 1000; i++) {
        float o[3] = {-1 + i * 0.003f, 0, 1}, dd[3] = {0, 0, -1};
        if (bk_tracer_intersect(t, o, dd, 0, INFINITY, &h))
            assert_true(isfinite(h.t) && isfinite(h.ng[2]) && fabsf(h.ng[2]) > 0.99f);
    }
    assert_int_equal(bk_tracer_embree_error(t, NULL), 0);
    bk_tracer_destroy(t);
    tsc_free(&s);

    /* an empty scene is a valid scene where everything misses */
    tsc_init(&s);
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    assert_int_equal(bk_tracer_intersect(t, org, dir, 0, INFINITY, &h), 0);
    assert_int_equal(bk_tracer_occluded(t, org, dir, 0, INFINITY), 0);
    bk_tracer_destroy(t);
    tsc_free(&s);
    assert_int_equal(bk_tracer_create(NULL, 0, &t), LBK_ERR_INVALID_ARGUMENT);
}

static void test_offset_ray_origin(void **state)
{
    (void)state;
    /* far from 0: exactly 8·n_k ulps of each coordinate, in the direction of n */
    float p[3] = {1e5f, -1e5f, 4.0f}, n[3] = {1, 1, 0}, o[3];
    const float ulp = 0.0078125f; /* ulp(1e5) = 2^16 · 2^-23 */
    bk_offset_ray_origin(p, n, o);
    assert_float_equal(o[0] - p[0], 8 * ulp, 0);
    assert_float_equal(o[1] - p[1], 8 * ulp, 0);
    assert_true(o[2] == p[2]);
    float nm[3] = {-0.5f, -0.5f, 0};
    bk_offset_ray_origin(p, nm, o);
    assert_float_equal(o[0] - p[0], -4 * ulp, 0);
    assert_float_equal(o[1] - p[1], -4 * ulp, 0);
    /* near 0: a fixed offset of 2^-19 · scale */
    float q[3] = {0, 1e-6f, -1e-6f}, m[3] = {0, 0, -1};
    bk_offset_ray_origin(q, m, o);
    assert_float_equal(o[2], -1e-6f - 1.0f / 524288, 1e-12f);
    bk_offset_ray_origin_scaled(q, m, 1e-3f, o);
    assert_float_equal(o[2], -1e-6f - 1e-3f / 524288, 1e-14f);
    assert_true(o[2] < q[2]);
    /* garbage normals never produce NaN */
    float nn[3] = {NAN, INFINITY, -INFINITY};
    bk_offset_ray_origin(p, nn, o);
    assert_true(isfinite(o[0]) && isfinite(o[1]) && isfinite(o[2]));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quad_hit_and_miss),
        cmocka_unit_test(test_self_intersection_unit),
        cmocka_unit_test(test_self_intersection_far),
        cmocka_unit_test(test_self_intersection_mm),
        cmocka_unit_test(test_self_intersection_10km),
        cmocka_unit_test(test_self_intersection_mm_far),
        cmocka_unit_test(test_degenerate_input),
        cmocka_unit_test(test_offset_ray_origin),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
