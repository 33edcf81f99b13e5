/* The path check (bake/transport/check.c, TRANSPORT.md §Path check) against what it must be:
 *  - unbiased: on a room lit by an emitter hung 1 cm under its ceiling (light samples, MIS, a
 *    gap the cache gets wrong), every checked receiver's mean agrees with the independent path
 *    tracer (tests/support/ref_path.h) within 4.5 of their joint standard errors, and the
 *    z-scores' RMS is that of noise ([0.5, 1.6] for 24 draws);
 *  - its variance is the mean's: in a furnace (albedo 0.9, Russian roulette on almost every
 *    path) every mean is within 4.5 of its own standard error of π·Le/(1 − ρ);
 *  - the draws: only receivers of the group, slots filled, weights 1/(K·p) with p a probability
 *    (Σ over a group's slots of 1/weight = K² · Σp ≤ K², and weights > 0);
 *  - byte-identical at 1 and 2 threads;
 *  - through the baker (lbk_bake_from_scene): a sky-lit floor and block at 64 samples, not
 *    denoised, where the error is the noise (no thin parts, no gap, no edge the cache gets
 *    wrong by more): each object's check within [0.5, 2]× its noise estimate (16 draws put the
 *    check's squared error within ±35 % of the truth at one standard deviation, so the bounds
 *    are ~4 deviations of the root away), 16 draws per object, the object's figure the larger of
 *    the two, and the container's bytes the same with --path-check off. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/transport/transport.h"
#include "lbk/bake.h"
#include "support/ref_path.h"
#include "support/transport_scenes.h"

#define N TSC_LAMP_ROOM_RECEIVERS
#define K 12

static double lumf(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }
static double lumd(const double *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* The room of test_bias's emitter-under-a-ceiling case (support/transport_scenes.h): receivers
 * on the floor (group 0) and a wall (group 1). */
static void lamp_room(bk_scene *s, bk_receiver *r, uint32_t *group)
{
    tsc_lamp_room(s);
    tsc_lamp_room_receivers(r);
    for (int i = 0; i < N; i++) group[i] = i < 16 ? 0 : 1;
}

typedef struct check_out {
    uint32_t recv[2 * K];
    float weight[2 * K], irr[3 * 2 * K], var[2 * K];
} check_out;

static void run_check(const bk_scene *s, const bk_tracer *t, const bk_receiver *r, const uint32_t *group,
                      uint32_t groups, int threads, int samples, check_out *co)
{
    lbk_sh9_rgb rad[N];
    float irr[3 * N];
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = rad;
    out.irradiance = irr;
    out.check_receiver = co->recv;
    out.check_weight = co->weight;
    out.check_irradiance = co->irr;
    out.check_variance = co->var;
    bk_transport_options o = tsc_fixed_passes(3, 5);
    o.threads = threads;
    o.check_group = group;
    o.check_groups = groups;
    o.check_per_group = K;
    o.check_samples = samples;
    bk_transport_stats st;
    assert_int_equal(bk_transport_run(s, t, r, N, &o, &out, &st), LBK_OK);
    assert_int_equal(st.check_samples, samples);
    assert_true(st.check_rays >= (uint64_t)groups * K * (uint64_t)samples);
    assert_true(st.rays < st.check_rays); /* the passes' rays only: 3 passes at 16·2^p */
}

static void test_unbiased_against_reference(void **state)
{
    (void)state;
    bk_scene s;
    bk_receiver r[N];
    uint32_t group[N];
    lamp_room(&s, r, group);
    char err[128];
    assert_int_equal(rp_check(&s, err, sizeof err), 0);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    float p[3 * N], n[3 * N];
    for (int i = 0; i < N; i++) {
        memcpy(p + 3 * i, r[i].position, 12);
        memcpy(n + 3 * i, r[i].normal, 12);
    }
    double ref[3 * N], se[N];
    rp_irradiance(&s, t, p, n, N, 16384, 17, 2, ref, se);
    check_out co;
    run_check(&s, t, r, group, 2, 2, 8192, &co);
    double z2 = 0, worst = 0;
    for (int j = 0; j < 2 * K; j++) {
        const uint32_t i = co.recv[j];
        assert_true(i < N);
        assert_int_equal(group[i], (uint32_t)(j / K)); /* drawn from its own group */
        assert_true(co.weight[j] > 0);
        const double z = (lumf(co.irr + 3 * j) - lumd(ref + 3 * i)) / sqrt(co.var[j] + se[i] * se[i]);
        z2 += z * z;
        worst = fmax(worst, fabs(z));
    }
    const double zrms = sqrt(z2 / (2 * K));
    print_message("path check vs reference: z RMS %.2f, worst |z| %.2f over %d draws\n", zrms, worst, 2 * K);
    assert_true(worst <= 4.5);
    assert_true(zrms >= 0.5 && zrms <= 1.6);
    /* weights are 1/(K·p): the draws' probabilities of one group sum to at most 1 */
    for (int g = 0; g < 2; g++) {
        double sum_p = 0;
        for (int j = g * K; j < (g + 1) * K; j++) sum_p += 1.0 / (K * (double)co.weight[j]);
        assert_true(sum_p <= K * 1.0001);
    }
    /* any thread count, the same bytes */
    check_out c1;
    run_check(&s, t, r, group, 2, 1, 8192, &c1);
    assert_memory_equal(&c1, &co, sizeof co);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static void test_furnace_mean_and_variance(void **state)
{
    (void)state;
    const double rho = 0.9, le = 1.0;
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, (float)rho, (float)rho, (float)rho, (float)le, (float)le, (float)le);
    s.materials[m].double_sided = 0;
    const float mn[3] = {0, 0, 0}, mx[3] = {1, 1, 1};
    tsc_box(&s, mn, mx, 2, 1, m);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    bk_receiver r[N];
    uint32_t group[N];
    memset(r, 0, sizeof r);
    for (int i = 0; i < N; i++) {
        r[i].position[0] = 0.1f + 0.8f * (float)(i % 5) / 4;
        r[i].position[1] = 0.1f + 0.8f * (float)(i / 5) / 4;
        r[i].normal[2] = 1;
        group[i] = 0;
    }
    check_out co;
    run_check(&s, t, r, group, 1, 2, 4096, &co);
    const double e_true = M_PI * le / (1 - rho);
    double z2 = 0;
    for (int j = 0; j < K; j++) {
        const double z = (lumf(co.irr + 3 * j) - e_true) / sqrt(co.var[j]);
        z2 += z * z;
        assert_true(fabs(z) <= 4.5);
    }
    print_message("furnace rho %.1f: z RMS %.2f over %d draws (E = %.3f)\n", rho, sqrt(z2 / K), K, e_true);
    assert_true(sqrt(z2 / K) >= 0.4 && sqrt(z2 / K) <= 1.8);
    /* the second half of the slots is unused: only one group */
    bk_tracer_destroy(t);
    tsc_free(&s);
}

/* A 6 m floor (object 0) with a 1 m block on it (object 1), under a uniform sky. */
static lbk_bake_output *bake_block(int path_check)
{
    static const float pos[] = {-3, 0, -3, 3, 0, -3, 3, 0, 3, -3, 0, 3, /* floor, facing +y */
                                -0.5f, 0, -0.5f, 0.5f, 0, -0.5f, 0.5f, 1, -0.5f, -0.5f, 1, -0.5f, /* block */
                                -0.5f, 0, 0.5f, 0.5f, 0, 0.5f, 0.5f, 1, 0.5f, -0.5f, 1, 0.5f};
    static const uint32_t idx[] = {0, 2, 1, 0, 3, 2,
                                   4, 7, 6, 4, 6, 5, 8, 9, 10, 8, 10, 11, 4, 8, 11, 4, 11, 7,
                                   5, 6, 10, 5, 10, 9, 7, 11, 10, 7, 10, 6};
    lbk_bake_material mat = {"grey", {0.6f, 0.6f, 0.6f}, {0, 0, 0}, 0};
    lbk_bake_object obj[2] = {{"floor", 0, 2, 0, LBK_BAKE_LIGHTING_LIGHTMAP, 4, NULL, NULL},
                              {"block", 2, 10, 0, LBK_BAKE_LIGHTING_LIGHTMAP, 8, NULL, NULL}};
    lbk_bake_scene sc = {0};
    sc.name = "block";
    sc.vertex_count = 12;
    sc.positions = pos;
    sc.triangle_count = 12;
    sc.indices = idx;
    sc.material_count = 1;
    sc.materials = &mat;
    sc.object_count = 2;
    sc.objects = obj;
    sc.sky[0] = sc.sky[1] = sc.sky[2] = 1;
    lbk_bake_desc d = {0};
    d.size = sizeof d; /* path_check came after version 1 */
    d.seed = 3;
    d.threads = 2;
    d.max_samples = 64;
    d.target_error = -1;
    d.no_glg = 1;
    d.denoise = LBK_BAKE_DENOISE_OFF;
    d.path_check = path_check;
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&sc, &d, &out), LBK_OK);
    return out;
}

static void test_through_the_baker(void **state)
{
    (void)state;
    lbk_bake_output *on = bake_block(0), *off = bake_block(-1);
    const lbk_bake_report *r = lbk_bake_output_report(on);
    assert_int_equal(r->object_estimate_count, 2);
    assert_non_null(r->object_checks);
    assert_int_equal(r->check.receivers, 2 * 16);
    assert_true(r->check.samples >= 256 && r->check.rel_rmse > 0);
    for (size_t i = 0; i < 2; i++) {
        const lbk_bake_object_estimate *e = &r->object_estimates[i];
        const lbk_bake_object_check *ck = &r->object_checks[i];
        const double noise = hypot(e->noise, e->bias);
        print_message("%s: noise estimate %.2f %%, path check %.2f %% [%.2f, %.2f]\n", e->name, 100 * noise,
                      100 * ck->rel_rmse, 100 * ck->low, 100 * ck->high);
        assert_int_equal(ck->receivers, 16);
        assert_true(ck->rel_rmse >= 0.5 * noise && ck->rel_rmse <= 2 * noise);
        assert_true(ck->low <= ck->rel_rmse && ck->rel_rmse <= ck->high);
        assert_true(e->rel_rmse == fmax(noise, ck->rel_rmse) || fabs(e->rel_rmse - fmax(noise, ck->rel_rmse)) < 1e-12);
    }
    const lbk_bake_report *r0 = lbk_bake_output_report(off);
    assert_true(r0->object_checks == NULL && r0->check.receivers == 0);
    void *a, *b;
    size_t na, nb;
    assert_int_equal(lbk_bake_output_container(on, &a, &na), LBK_OK);
    assert_int_equal(lbk_bake_output_container(off, &b, &nb), LBK_OK);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    lbk_free(NULL, a);
    lbk_free(NULL, b);
    lbk_bake_output_free(on);
    lbk_bake_output_free(off);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unbiased_against_reference),
        cmocka_unit_test(test_furnace_mean_and_variance),
        cmocka_unit_test(test_through_the_baker),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
