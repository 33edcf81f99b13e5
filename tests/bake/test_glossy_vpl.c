/* Glossy VPLs in the transport (bake/transport/VPL.md "In the transport"): an open metal floor
 * (metallic 1, base 0.9, roughness 0.25) lit by a spot light, receivers on a ceiling row facing
 * down and on a wall column facing the light's mirror lobe. The only light they get is one
 * specular bounce off the floor (no sky, no emitters, no other geometry, no direct light), so
 * the reference is the floor integral E(r) = ∫ f(v, l)·E_floor(y)·cos θ_y·cos θ_r / d² dA (the
 * glTF specular lobe of ggx.h, the spot's irradiance from bk_light_eval), by the midpoint rule on
 * 5 mm cells. With VPLs on (auto turns them on here) and off, K seeds each:
 *   - both means agree with the reference per receiver and in total within 4 standard errors
 *     of the K seeds plus the quadrature's 1 % (each receiver gets its noise bound from the
 *     seeds' spread), and the same bound rejects the double-counted estimate (on + off: the
 *     light → floor → receiver path counted by both) and a 5 % bias of the total: the test can
 *     fail;
 *   - VPLs on have lower noise (seed-to-seed variance summed over the receivers, and the bake's
 *     own two-halves estimate), and that estimate sees the VPLs' noise (within a factor 2.5 of
 *     the seeds' measured relative RMSE);
 *   - byte-identical irradiance and SH at 1 and 2 threads with VPLs on. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/transport/ggx.h"
#include "bake/transport/shading.h"
#include "bake/transport/transport.h"
#include "support/transport_scenes.h"

#define NR 20      /* receivers: 12 on the ceiling row, 8 on the wall column */
#define NCEIL 12
#define SEEDS 6
#define PASSES 4
static const float BASE = 0.9f, ROUGH = 0.25f, INTENSITY = 40;
static const float LPOS[3] = {-0.8f, 0, 1.2f}, LDIR[3] = {1.1f, 0, -1.2f};

static void build(bk_scene *s, bk_receiver r[NR])
{
    tsc_init(s);
    uint32_t m = tsc_material(s, BASE, BASE, BASE, 0, 0, 0);
    s->materials[m].metallic = 1;
    s->materials[m].roughness = ROUGH;
    float p0[3] = {-20, -20, 0}, p1[3] = {20, -20, 0}, p2[3] = {20, 20, 0}, p3[3] = {-20, 20, 0};
    tsc_quad(s, p0, p1, p2, p3, 8, m);
    tsc_spot_light(s, LPOS, LDIR, INTENSITY, 0.3f, 0.5f);
    memset(r, 0, NR * sizeof *r);
    for (int i = 0; i < NCEIL; i++) { /* the ceiling row under the lobe, facing down */
        r[i].position[0] = -0.5f + 3.5f * (float)i / (NCEIL - 1);
        r[i].position[2] = 2;
        r[i].normal[2] = -1;
    }
    for (int i = NCEIL; i < NR; i++) { /* the wall column the lobe runs into, facing the light */
        r[i].position[0] = 2.5f;
        r[i].position[2] = 0.4f + 1.8f * (float)(i - NCEIL) / (NR - NCEIL - 1);
        r[i].normal[0] = -1;
    }
}

/* The reflected irradiance at every receiver by the floor integral (midpoint rule, 5 mm cells
 * over the part of the floor the spot lights: its cone meets the floor inside x ∈ [−0.6, 2.8],
 * |y| < 1.6; the box is larger). */
static void reference(const bk_scene *s, const bk_receiver r[NR], double ref[NR])
{
    bk_ggx_table *t = malloc(sizeof *t);
    assert_non_null(t);
    bk_ggx_table_init(t);
    const double x0 = -1.5, x1 = 4.5, y0 = -3.0, y1 = 3.0, h = 0.005;
    const int nx = (int)((x1 - x0) / h + 0.5), ny = (int)((y1 - y0) / h + 0.5);
    const double b3[3] = {BASE, BASE, BASE};
    for (int k = 0; k < NR; k++) ref[k] = 0;
    for (int i = 0; i < nx; i++)
        for (int j = 0; j < ny; j++) {
            double y[3] = {x0 + h * (i + 0.5), y0 + h * (j + 0.5), 0}, val[3], l[3], dist;
            if (!bk_light_eval(&s->lights[0], y, val, l, &dist) || !(l[2] > 0)) continue;
            const double ef = val[0] * l[2]; /* the floor's irradiance */
            for (int k = 0; k < NR; k++) {
                double d[3] = {r[k].position[0] - y[0], r[k].position[1] - y[1], r[k].position[2] - y[2]};
                double dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                double v[3] = {d[0] / dn, d[1] / dn, d[2] / dn};
                double cr = -(v[0] * r[k].normal[0] + v[1] * r[k].normal[1] + v[2] * r[k].normal[2]);
                if (!(cr > 0)) continue;
                bk_mr_lobe lb;
                if (!bk_mr_lobe_init(&lb, t, b3, 1, ROUGH, v)) continue;
                double f[3];
                bk_mr_lobe_eval(&lb, l, f);
                ref[k] += f[0] * ef * v[2] * cr / (dn * dn) * h * h;
            }
        }
    free(t);
}

typedef struct run_out {
    float irr[3 * NR];
    lbk_sh9_rgb rad[NR];
    bk_transport_stats st;
} run_out;

static void run(const bk_scene *s, const bk_receiver r[NR], int vpl, uint64_t seed, int threads, run_out *o)
{
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(s, 0, &t), LBK_OK);
    bk_transport_options opt = tsc_fixed_passes(PASSES, seed);
    opt.threads = threads;
    opt.glossy_vpl = vpl;
    memset(o, 0, sizeof *o);
    bk_transport_output out = {o->rad, NULL, o->irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    assert_int_equal(bk_transport_run(s, t, r, NR, &opt, &out, &o->st), LBK_OK);
    assert_int_equal(o->st.nonfinite, 0);
    bk_tracer_destroy(t);
}

/* Largest |mean − ref| / (4·se + 1 % of the largest reference) over the receivers, and the same
 * for the total (the bound holds where it is ≤ 1). */
static double worst_ratio(const double mean[NR], const double se[NR], const double ref[NR], double *total_ratio)
{
    double peak = 0, sm = 0, sr = 0, sv = 0, worst = 0;
    for (int k = 0; k < NR; k++) peak = fmax(peak, ref[k]);
    for (int k = 0; k < NR; k++) {
        worst = fmax(worst, fabs(mean[k] - ref[k]) / (4 * se[k] + 0.01 * peak));
        sm += mean[k], sr += ref[k], sv += se[k] * se[k];
    }
    *total_ratio = fabs(sm - sr) / (4 * sqrt(sv) + 0.01 * sr);
    return worst;
}

static void stats_of(const double x[SEEDS][NR], double mean[NR], double se[NR], double *var_sum)
{
    *var_sum = 0;
    for (int k = 0; k < NR; k++) {
        double m = 0, v = 0;
        for (int q = 0; q < SEEDS; q++) m += x[q][k];
        m /= SEEDS;
        for (int q = 0; q < SEEDS; q++) v += (x[q][k] - m) * (x[q][k] - m);
        v /= SEEDS - 1;
        mean[k] = m;
        se[k] = sqrt(v / SEEDS);
        *var_sum += v;
    }
}

static void test_vpl_matches_the_floor_integral(void **state)
{
    (void)state;
    bk_scene s;
    bk_receiver r[NR];
    build(&s, r);
    double ref[NR];
    reference(&s, r, ref);
    static double x[2][SEEDS][NR];
    double est[2] = {0, 0}, mean[2][NR], se[2][NR], var[2], refsq = 0;
    run_out *o = malloc(sizeof *o);
    assert_non_null(o);
    for (int mode = 0; mode < 2; mode++) /* 0: VPLs on (auto), 1: off */
        for (int q = 0; q < SEEDS; q++) {
            run(&s, r, mode ? -1 : 0, 100 + (uint64_t)q, 2, o);
            assert_int_equal(o->st.vpl, mode ? 0 : 1);
            if (!mode) assert_true(o->st.vpl_share > 0.3 && o->st.vpl_made > 0);
            est[mode] += o->st.est_rel_rmse / SEEDS;
            for (int k = 0; k < NR; k++) x[mode][q][k] = o->irr[3 * k]; /* no direct light reaches them */
        }
    for (int mode = 0; mode < 2; mode++) stats_of(x[mode], mean[mode], se[mode], &var[mode]);
    for (int k = 0; k < NR; k++) refsq += ref[k] * ref[k];
    double tot[2], w[2];
    for (int mode = 0; mode < 2; mode++) w[mode] = worst_ratio(mean[mode], se[mode], ref, &tot[mode]);
    double sum_ref = 0, sum_on = 0, sum_off = 0;
    for (int k = 0; k < NR; k++) sum_ref += ref[k], sum_on += mean[0][k], sum_off += mean[1][k];
    /* the observed relative RMSE of one run (the seeds' spread), against the bake's estimate */
    const double obs_on = sqrt(var[0] / refsq), obs_off = sqrt(var[1] / refsq);
    print_message("reference total %.5f; VPLs on %.5f (%+.2f %%), off %.5f (%+.2f %%); worst receiver / bound: on %.2f, "
                  "off %.2f; total / bound: on %.2f, off %.2f\n",
                  sum_ref, sum_on, 100 * (sum_on / sum_ref - 1), sum_off, 100 * (sum_off / sum_ref - 1), w[0], w[1],
                  tot[0], tot[1]);
    print_message("one run's relative RMSE over the seeds: on %.2f %%, off %.2f %%; the bake's estimate: on %.2f %%, "
                  "off %.2f %%\n", 100 * obs_on, 100 * obs_off, 100 * est[0], 100 * est[1]);
    assert_true(w[0] <= 1 && tot[0] <= 1);
    assert_true(w[1] <= 1 && tot[1] <= 1);
    /* the bounds are tight enough to see double counting and a 5 % bias */
    double dbl[NR], dse[NR], biased[NR], t_dbl, t_b;
    for (int k = 0; k < NR; k++) {
        dbl[k] = mean[0][k] + mean[1][k];
        dse[k] = sqrt(se[0][k] * se[0][k] + se[1][k] * se[1][k]);
        biased[k] = 1.05 * mean[0][k];
    }
    worst_ratio(dbl, dse, ref, &t_dbl);
    worst_ratio(biased, se[0], ref, &t_b);
    print_message("rejected: double counted total / bound %.1f, 5 %% bias %.2f\n", t_dbl, t_b);
    assert_true(t_dbl > 1 && t_b > 1);
    /* lower noise with VPLs, and the estimate sees it */
    assert_true(var[0] < 0.5 * var[1]);
    assert_true(est[0] < est[1]);
    assert_true(est[0] < 2.5 * obs_on && obs_on < 2.5 * est[0]);
    free(o);
    tsc_free(&s);
}

static void test_vpl_threads_identical(void **state)
{
    (void)state;
    bk_scene s;
    bk_receiver r[NR];
    build(&s, r);
    run_out *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    assert_non_null(a);
    assert_non_null(b);
    run(&s, r, 1, 7, 1, a);
    run(&s, r, 1, 7, 2, b);
    assert_int_equal(a->st.vpl, 1);
    assert_memory_equal(a->irr, b->irr, sizeof a->irr);
    assert_memory_equal(a->rad, b->rad, sizeof a->rad);
    assert_true(a->st.vpl_made == b->st.vpl_made && a->st.rays == b->st.rays);
    /* off: the VPLs and the split are gone, so the result differs */
    run(&s, r, -1, 7, 2, b);
    assert_int_equal(b->st.vpl, 0);
    assert_memory_not_equal(a->irr, b->irr, sizeof a->irr);
    free(a);
    free(b);
    tsc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vpl_matches_the_floor_integral),
        cmocka_unit_test(test_vpl_threads_identical),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
