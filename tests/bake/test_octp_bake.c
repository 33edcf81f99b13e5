/* The OCTP probe volume's bake side: irradiance texels gathered by the transport (against an
 * analytic integral, and beyond what SH9 can hold), classification and relocation of probes
 * inside closed geometry, probes with no nearby geometry, depth moments of a known wall. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/probes/octa_bake.h"
#include "bake/transport/transport.h"
#include "lbk/octa.h"
#include "lbk/sh.h"
#include "support/transport_scenes.h"

/* Irradiance at the origin, normal n, from a uniformly emitting square in the plane x = x0
 * (|y|, |z| ≤ h) of radiance L facing the origin: ∫ L·max(0, n·ω)·cosθ'/r² dA, midpoint rule
 * on 400² cells (error < 1e-5 relative for these sizes). */
static double square_irradiance(double x0, double h, double L, const float n[3])
{
    const int N = 400;
    double e = 0, da = (2 * h / N) * (2 * h / N);
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            double y = -h + (i + 0.5) * 2 * h / N, z = -h + (j + 0.5) * 2 * h / N;
            double r2 = x0 * x0 + y * y + z * z, r = sqrt(r2);
            double w[3] = {x0 / r, y / r, z / r};
            double c = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
            if (c > 0) e += L * c * (fabs(x0) / r) / r2 * da;
        }
    return e;
}

/* A red square (emission 1, 0, 0) at x = −0.5 and a green one (0, 1, 0) at x = +0.5, both
 * 0.5 m wide and black otherwise, nothing else: one octahedral probe at the origin. Texel
 * (0, 1) looks towards −x, texel (3, 1) towards +x (18° off the axis). */
static void two_colour_squares(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    uint32_t red = tsc_material(&s, 0, 0, 0, 1, 0, 0), green = tsc_material(&s, 0, 0, 0, 0, 1, 0);
    const float h = 0.25f;
    float r0[3] = {-0.5f, -h, -h}, r1[3] = {-0.5f, h, -h}, r2[3] = {-0.5f, h, h}, r3[3] = {-0.5f, -h, h};
    tsc_quad(&s, r0, r1, r2, r3, 2, red); /* front towards +x */
    float g0[3] = {0.5f, -h, -h}, g1[3] = {0.5f, -h, h}, g2[3] = {0.5f, h, h}, g3[3] = {0.5f, h, -h};
    tsc_quad(&s, g0, g1, g2, g3, 2, green); /* front towards −x */
    tsc_update_bounds(&s);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    bk_receiver rc;
    memset(&rc, 0, sizeof rc); /* one GLG-like sphere receiver at the same point: its SH9 */
    lbk_sh9_rgb sh;
    float irr[3], oct[48];
    const float pt[3] = {0, 0, 0};
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.seed = 5;
    o.threads = 2;
    o.target_error = -1;
    o.max_samples = 2 * 16 * 63; /* 6 passes */
    o.octa_points = pt;
    o.octa_count = 1;
    bk_transport_output out = {&sh, NULL, irr, NULL, oct, NULL, NULL, NULL, NULL, NULL};
    bk_transport_stats st;
    assert_int_equal(bk_transport_run(&s, t, &rc, 1, &o, &out, &st), LBK_OK);
    assert_true(st.octa_rays >= 4 * 2 * 16 * 63 - 1); /* 4× the receivers' rays */
    float nm[3], np[3];
    lbk_oct_texel_direction(4, 0, 1, nm);
    lbk_oct_texel_direction(4, 3, 1, np);
    assert_true(nm[0] < -0.9f && np[0] > 0.9f);
    const float *em = &oct[3 * (1 * 4 + 0)], *ep = &oct[3 * (1 * 4 + 3)];
    const double ref_m = square_irradiance(-0.5, h, 1, nm), ref_p = square_irradiance(0.5, h, 1, np);
    print_message("octp texel -x: R %.4f (exact %.4f) G %g; +x: G %.4f (exact %.4f) R %g; est rel RMSE %.4f\n",
                  em[0], ref_m, em[1], ep[1], ref_p, ep[0], st.octa_rel_rmse);
    /* the facing texel holds its square's irradiance (4096-ray estimate, 2 % of the value is
     * ~3 × the reported noise) and none of the other colour: from the −x texel's hemisphere the
     * green square is entirely behind the horizon, so its exact share is 0, and every sample
     * the transport adds (gather hits and light samples) is weighted by max(0, cos) */
    assert_true(fabs(em[0] - ref_m) < 0.02 * ref_m);
    assert_true(fabs(ep[1] - ref_p) < 0.02 * ref_p);
    assert_true(em[1] == 0.0f && em[2] == 0.0f);
    assert_true(ep[0] == 0.0f && ep[2] == 0.0f);
    assert_true(st.octa_rel_rmse > 0 && st.octa_rel_rmse < 0.02);
    /* SH9 cannot hold it: the GLG's SH9 of the same transport puts green into the −x
     * direction (ringing of a 35° source: ≥ 2 % of the green the +x texel sees) */
    float shm[3], shp[3];
    lbk_sh9_irradiance(&sh, nm, shm);
    lbk_sh9_irradiance(&sh, np, shp);
    print_message("sh9: -x R %.4f G %.4f; +x G %.4f R %.4f\n", shm[0], shm[1], shp[1], shp[0]);
    assert_true(fabsf(shm[1]) > 0.02f * ep[1]);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static uint32_t count_state(const bk_octa_volume *v, uint32_t state)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < v->count; i++) n += v->info[i].state == state;
    return n;
}

/* A closed solid box [-1, 1]³ (single-sided, faces outward) inside a large open room: grid
 * probes deep inside the solid are inactive, those inside within 0.45 spacing of a face move
 * out through it, and those in the middle of the room see no geometry within a cell diagonal. */
static void classify_and_relocate(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    s.materials[m].double_sided = 0;
    const float mn[3] = {-1.1f, -1.1f, -1.1f}, mx[3] = {1.1f, 1.1f, 1.1f};
    tsc_box(&s, mn, mx, 1, 0, m);
    tsc_update_bounds(&s);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    /* a grid of spacing 0.5 over [-3.25, 3.25]³: 13³ probes at multiples of 0.5 */
    const float bmin[3] = {-3.25f, -3.25f, -3.25f}, bmax[3] = {3.25f, 3.25f, 3.25f};
    bk_octa_volume v;
    bk_octa_options oo = {.spacing = 0.5f};
    assert_int_equal(bk_octa_place(&s, t, bmin, bmax, &oo, &v), LBK_OK);
    assert_int_equal(v.count, 13 * 13 * 13);
    assert_int_equal(v.level_count, 1);
    assert_float_equal(v.levels[0].spacing, 0.5f, 0);
    uint32_t inside = 0, moved = 0;
    for (uint32_t i = 0; i < v.count; i++) {
        const lbk_octp_probe_info *in = &v.info[i];
        const float *p = &v.positions[3 * i];
        float g[3];
        for (int a = 0; a < 3; a++) g[a] = p[a] - in->offset[a];
        const float linf = fmaxf(fabsf(g[0]), fmaxf(fabsf(g[1]), fabsf(g[2])));
        for (int a = 0; a < 3; a++) assert_true(fabsf(in->offset[a]) <= 0.45f * 0.5f + 1e-6f);
        if (in->state == LBK_OCTP_INSIDE) {
            inside++;
            assert_true(linf < 1.1f); /* only grid points inside the solid */
        } else {
            /* every active probe stands outside the solid, at least 0.1 spacing from it */
            const float pl = fmaxf(fabsf(p[0]), fmaxf(fabsf(p[1]), fabsf(p[2])));
            assert_true(pl > 1.1f + 0.04f);
        }
        if (in->offset[0] != 0 || in->offset[1] != 0 || in->offset[2] != 0) moved++;
    }
    /* grid points inside: |g| ≤ 1 per axis (5³ = 125). Those at 1.0 (0.1 from a face) move out;
     * those at ≤ 0.5 (≥ 0.6 from every face) cannot within 0.225: 3³ = 27 stay, inactive. */
    print_message("inside %u, relocated %u, no nearby %u of %u\n", inside, moved, count_state(&v, LBK_OCTP_NO_NEARBY), v.count);
    assert_int_equal(inside, 27);
    assert_true(moved >= 125 - 27);
    /* no nearby geometry: the nearest surface farther than a cell diagonal (0.866) */
    for (uint32_t i = 0; i < v.count; i++)
        if (v.info[i].state == LBK_OCTP_NO_NEARBY) assert_true(v.info[i].nearest > 0.866f);
    assert_true(count_state(&v, LBK_OCTP_NO_NEARBY) > 0);
    /* depth moments from a probe at (2, 0, 0) towards −x: the face at x = 1.1 is 0.9 away */
    float depth[144][2];
    const float p[3] = {2, 0, 0};
    bk_octa_depth(t, p, v.levels[0].miss_distance, depth);
    float dir[3] = {-1, 0, 0}, uv[2];
    lbk_oct_encode(dir, uv);
    int i = (int)((uv[0] + 1) * 0.5f * 12), j = (int)((uv[1] + 1) * 0.5f * 12);
    if (i > 11) i = 11;
    if (j > 11) j = 11;
    const float *m1 = depth[j * 12 + i];
    print_message("depth toward -x: mean %.4f, var %.6f\n", m1[0], m1[1] - m1[0] * m1[0]);
    /* within the texel's cone (≤ 15° off the axis) the plane is between 0.9 and 0.9/cos 15° */
    assert_true(m1[0] >= 0.9f && m1[0] <= 0.9f / cosf(0.27f));
    assert_true(m1[1] - m1[0] * m1[0] >= -1e-5f);
    bk_octa_volume_free(&v);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(two_colour_squares),
        cmocka_unit_test(classify_and_relocate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
