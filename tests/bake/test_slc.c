/* Stochastic light culling (bake/transport/slc.h, SLC.md): unbiased against every light with a
 * shadow ray (the mean over seeds within the derived per-draw variance bound δ·E), culling that
 * actually culls, the same bytes at 1 and 2 threads, the auto switch, and the cache's first
 * bounce unbiased too. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/transport/shading.h"
#include "bake/transport/slc.h"
#include "bake/transport/transport.h"
#include "support/mem_checkpoint.h"
#include "support/transport_scenes.h"

#define NL 300   /* lights of the test level */
#define NR 160   /* receivers: texels on the floor and on the pillars' tops, probes above */

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 11;
}
static double unit(uint64_t *s) { return (double)lcg(s) / 9007199254740992.0; }

/* A 40 × 40 m floor with 16 pillars, NL lights 0.5–3 m above it: point lights of intensities
 * spread over two decades (some with a range), spot lights, one directional light. */
static void level(bk_scene *s, float albedo)
{
    tsc_init(s);
    uint32_t m = tsc_material(s, albedo, albedo, albedo, 0, 0, 0);
    float p0[3] = {-20, -20, 0}, p1[3] = {20, -20, 0}, p2[3] = {20, 20, 0}, p3[3] = {-20, 20, 0};
    tsc_quad(s, p0, p1, p2, p3, 8, m);
    for (int i = 0; i < 16; i++) {
        float x = -15 + 10 * (float)(i % 4), y = -15 + 10 * (float)(i / 4);
        float mn[3] = {x, y, 0}, mx[3] = {x + 1, y + 1, 2.5f};
        tsc_box(s, mn, mx, 1, 0, m);
    }
    uint64_t r = 7;
    for (int i = 0; i < NL; i++) {
        float pos[3] = {(float)(-20 + 40 * unit(&r)), (float)(-20 + 40 * unit(&r)), (float)(0.5 + 2.5 * unit(&r))};
        float I = (float)(5 * pow(10.0, 2 * unit(&r)));
        if (i % 10 == 3) {
            float dir[3] = {0.3f, -0.2f, -1};
            tsc_spot_light(s, pos, dir, I, 0.3f, 0.8f);
        } else {
            tsc_point_light(s, pos, I, 0.8f * I, 0.6f * I, i % 7 == 0 ? 6.0f : 0.0f);
        }
    }
    float d[3] = {0.2f, 0.1f, -1};
    tsc_dir_light(s, d, 0.5f);
    tsc_update_bounds(s);
}

/* Receivers come in tiles of 16 that lie together (as a chart's texels do): floor texels in
 * 2 × 2 m patches (some in pillar shadows), the pillars' tops, probes in 4 × 4 × 1 m groups. */
static void receivers(bk_receiver *rc)
{
    uint64_t r = 99;
    memset(rc, 0, NR * sizeof *rc);
    double cx = 0, cy = 0;
    for (int i = 0; i < NR; i++) {
        bk_receiver *q = &rc[i];
        if (i % 16 == 0) cx = -17 + 34 * unit(&r), cy = -17 + 34 * unit(&r);
        if (i < 120) {
            q->position[0] = (float)(cx + 2 * unit(&r));
            q->position[1] = (float)(cy + 2 * unit(&r));
            q->normal[2] = 1;
        } else if (i < 136) { /* pillar tops */
            int k = i - 120;
            q->position[0] = -14.5f + 10 * (float)(k % 4);
            q->position[1] = -14.5f + 10 * (float)(k / 4);
            q->position[2] = 2.5f;
            q->normal[2] = 1;
        } else { /* probes */
            q->position[0] = (float)(cx + 4 * unit(&r));
            q->position[1] = (float)(cy + 4 * unit(&r));
            q->position[2] = (float)(0.8 + unit(&r));
        }
    }
}

static bk_transport_options opts(int slc, uint64_t seed, int threads)
{
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.seed = seed;
    o.threads = threads;
    o.target_error = -1;
    o.first_pass_samples = 8;
    o.max_samples = 16; /* one pass: both halves, pass 0's δ */
    o.max_cells = 2048;
    o.slc = slc;
    o.slc_delta = 0.2;
    return o;
}

typedef struct out { float irr[3 * NR]; lbk_sh9_rgb rad[NR], dir[NR]; bk_transport_stats st; } out;

static void run(const bk_scene *s, const bk_tracer *t, const bk_receiver *rc, const bk_transport_options *o, out *res)
{
    bk_transport_output op = {res->rad, res->dir, res->irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    assert_int_equal(bk_transport_run(s, t, rc, NR, o, &op, &res->st), LBK_OK);
    assert_int_equal(res->st.nonfinite, 0);
}

static double lum3(const float *v) { return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]; }

/* Black surfaces, no sky: the irradiance is punctual light alone, and brute force is exact.
 * Over K seeds (each the mean of two draws): the per-receiver spread s² of the runs obeys the
 * bound Var ≤ δ·E/2 (SLC.md), and z = (mean − E)/(s/√K) has E[z²] ≈ 1 when the mean is E. */
static void test_unbiased_against_brute_force(void **state)
{
    (void)state;
    bk_scene s;
    level(&s, 0);
    bk_receiver rc[NR];
    receivers(rc);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    out *bf = calloc(1, sizeof *bf), *sl = calloc(1, sizeof *sl);
    bk_transport_options o = opts(-1, 1, 2);
    run(&s, t, rc, &o, bf);
    assert_int_equal(bf->st.slc, 0);
    enum { K = 48 };
    double *mean = calloc(NR, sizeof *mean), *sq = calloc(NR, sizeof *sq), delta = 0, tested = 0;
    double lv = 0, lv2 = 0; /* per run: Σ_i (X_i − E_i)/E_i over the receivers, and its square */
    int differ = 0;
    for (int k = 0; k < K; k++) {
        o = opts(1, 100 + (uint64_t)k, 2);
        run(&s, t, rc, &o, sl);
        assert_int_equal(sl->st.slc, 1);
        assert_true(sl->st.slc_delta > 0);
        if (k) assert_true(sl->st.slc_delta == delta); /* δ depends on the scene, not the seed */
        delta = sl->st.slc_delta;
        tested += sl->st.slc_lights_tested / 2; /* per draw */
        double dev = 0;
        for (int i = 0; i < NR; i++) {
            double e = lum3(&bf->irr[3 * i]);
            if (e > 0) dev += (lum3(&sl->irr[3 * i]) - e) / e;
            mean[i] += lum3(&sl->irr[3 * i]) / K;
            sq[i] += lum3(&sl->irr[3 * i]) * lum3(&sl->irr[3 * i]) / K;
            differ += fabs(lum3(&sl->irr[3 * i]) - lum3(&bf->irr[3 * i])) > 1e-3 * lum3(&bf->irr[3 * i]);
        }
        lv += dev / K;
        lv2 += dev * dev / K;
    }
    double z2 = 0, zmax = 0, vratio = 0, bmax = 0;
    int lit = 0, noisy = 0;
    for (int i = 0; i < NR; i++) {
        double e = lum3(&bf->irr[3 * i]);
        if (!(e > 0)) { /* a floor point inside a pillar */
            assert_true(mean[i] == 0);
            continue;
        }
        lit++;
        double zb = (mean[i] - e) / sqrt(delta * e / (2.0 * K)); /* against the bound */
        bmax = fmax(bmax, fabs(zb));
        double var = fmax(0.0, (sq[i] - mean[i] * mean[i]) * K / (K - 1));
        vratio = fmax(vratio, var / (delta * e / 2));
        if (!(var > 1e-12 * e * e)) continue; /* every light accepted for certain: exact */
        double z = (mean[i] - e) / sqrt(var / K);
        noisy++;
        z2 += z * z;
        zmax = fmax(zmax, fabs(z));
    }
    /* the runs are independent, the receivers of one run are not (they share its ξ): the bias
     * common to the receivers is measured on the per-run sum of relative deviations */
    const double zall = lv / sqrt((lv2 - lv * lv) / (K - 1));
    print_message("slc: delta %.4g, lights tested per draw %.1f of %d; %d noisy receivers: mean t^2 %.3f, "
                  "max |t| %.2f; largest variance / bound %.3f; mean relative deviation %.2f sigma; max |z| against the bound %.2f\n",
                  delta, tested / K, NL, noisy, z2 / noisy, zmax, vratio, zall, bmax);
    assert_true(noisy > NR / 2);
    /* The t statistics (own spread) are skewed negative for these right-skewed draws (a run
     * with a rare accepted light has a high mean and a high spread), so the bias test uses the
     * bound, which is ≥ the variance (checked): a real bias would show as many bound-sigmas. */
    assert_true(vratio < 1.5);            /* Var ≤ δE/2, up to the spread of s² */
    assert_true(fabs(zall) < 4);          /* no bias common to the receivers */
    assert_true(bmax < 5);                /* nor at any one */
    assert_true(z2 / noisy > 0.5 && z2 / noisy < 2); /* the spread is the one of the draws */
    assert_true(lit > NR * 9 / 10);
    assert_true(tested / K < 0.5 * NL);    /* the tiles cull */
    assert_true(differ > NR / 4);          /* and the draws are draws (noise, not brute force) */
    free(mean);
    free(sq);
    free(bf);
    free(sl);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

/* Grey surfaces: the cache's first bounce is culled too. The level-wide mean of K seeds with and
 * without culling agrees within 4 standard errors (both are noisy: the spread of the seeds). */
static void test_cache_bounce_unbiased(void **state)
{
    (void)state;
    bk_scene s;
    level(&s, 0.6f);
    bk_receiver rc[NR];
    receivers(rc);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    out *r = calloc(1, sizeof *r);
    enum { K = 10 };
    double m[2] = {0, 0}, m2[2] = {0, 0};
    for (int v = 0; v < 2; v++)
        for (int k = 0; k < K; k++) {
            bk_transport_options o = opts(v ? 1 : -1, 500 + (uint64_t)k, 2);
            run(&s, t, rc, &o, r);
            double ind = 0; /* indirect part: radiance − direct, L00, over the texels */
            for (int i = 0; i < 136; i++) ind += r->rad[i].c[1][0] - r->dir[i].c[1][0];
            ind /= 136;
            m[v] += ind / K;
            m2[v] += ind * ind / K;
        }
    double se = sqrt((m2[0] - m[0] * m[0]) / (K - 1) + (m2[1] - m[1] * m[1]) / (K - 1));
    print_message("indirect L00: brute %.5g, culled %.5g, standard error %.3g\n", m[0], m[1], se);
    assert_true(m[0] > 0 && se > 0);
    assert_true(fabs(m[1] - m[0]) < 4 * se);
    free(r);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static void test_threads_identical_and_auto(void **state)
{
    (void)state;
    bk_scene s;
    level(&s, 0.6f);
    bk_receiver rc[NR];
    receivers(rc);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    out *a = calloc(1, sizeof *a), *b = calloc(1, sizeof *b);
    bk_transport_options o = opts(0, 9, 1); /* auto: NL > BK_SLC_AUTO_LIGHTS */
    o.max_samples = 48;                     /* two passes */
    run(&s, t, rc, &o, a);
    o.threads = 2;
    run(&s, t, rc, &o, b);
    assert_int_equal(a->st.slc, 1);
    assert_memory_equal(a->irr, b->irr, sizeof a->irr);
    assert_memory_equal(a->rad, b->rad, sizeof a->rad);
    assert_memory_equal(a->dir, b->dir, sizeof a->dir);
    assert_true(a->st.est_rel_rmse == b->st.est_rel_rmse);
    bk_tracer_destroy(t);
    /* few lights: auto is off */
    s.light_count = BK_SLC_AUTO_LIGHTS;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    o.max_samples = 16;
    run(&s, t, rc, &o, a);
    assert_int_equal(a->st.slc, 0);
    s.light_count = NL + 1;
    free(a);
    free(b);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static int count_chains(void *user, const char *phase, double f)
{
    (void)f;
    if (!strcmp(phase, "cache")) ++*(int *)user;
    return 0;
}

/* A run resumed after its second pass (as after a crash) ends with the bytes of one that was
 * not interrupted: every pass's draws depend on (seed, half, pass) only. */
static void test_resume_identical(void **state)
{
    (void)state;
    bk_scene s;
    level(&s, 0.6f);
    bk_receiver rc[NR];
    receivers(rc);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    out *a = calloc(1, sizeof *a), *b = calloc(1, sizeof *b);
    mem_ckpt *k = malloc(sizeof *k);
    bk_transport_checkpoint cp;
    mem_ckpt_init(k, &cp);
    bk_transport_options o = opts(1, 21, 2);
    o.max_samples = 2 * 8 * 7; /* three passes */
    o.checkpoint = &cp;
    int chains = 0;
    o.progress = count_chains;
    o.user = &chains;
    run(&s, t, rc, &o, a); /* saves after every pass (and loads nothing: at = -1) */
    assert_int_equal(k->saved, 3);
    assert_int_equal(a->st.passes, 3);
    assert_int_equal(chains, 6); /* two caches per pass */
    mem_ckpt_drop(k, 2);   /* resume after pass 2 (0-based 1) */
    k->at = 1;
    chains = 0;
    run(&s, t, rc, &o, b); /* loads the state after pass 2, runs pass 3 only */
    assert_int_equal(chains, 2);
    assert_int_equal(b->st.slc, 1);
    assert_memory_equal(a->irr, b->irr, sizeof a->irr);
    assert_memory_equal(a->rad, b->rad, sizeof a->rad);
    assert_memory_equal(a->dir, b->dir, sizeof a->dir);
    assert_true(a->st.est_rel_rmse == b->st.est_rel_rmse);
    mem_ckpt_drop(k, 0);
    free(k);
    free(a);
    free(b);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

/* The module alone: a tile's list holds every light a point of it would accept. */
static void test_tile_lists_conservative(void **state)
{
    (void)state;
    bk_scene s;
    level(&s, 0);
    const bk_light *lp[NL + 1];
    for (size_t i = 0; i < s.light_count; i++) lp[i] = &s.lights[i];
    enum { N = 3000 };
    float *boxes = malloc(6 * N * sizeof(float));
    double *pts = malloc(3 * N * sizeof(double));
    uint64_t r = 5;
    double cen[3] = {0, 0, 0};
    for (int i = 0; i < N; i++) {
        if (i % 16 == 0)
            for (int a = 0; a < 3; a++) cen[a] = a < 2 ? -20 + 39 * unit(&r) : 2 * unit(&r);
        for (int a = 0; a < 3; a++) pts[3 * i + a] = cen[a] + unit(&r); /* tiles of 1 m cubes */
        for (int a = 0; a < 3; a++) boxes[6 * i + a] = boxes[6 * i + 3 + a] = (float)pts[3 * i + a];
        for (int a = 0; a < 3; a++) pts[3 * i + a] = boxes[6 * i + a];
    }
    bk_slc *slc = NULL;
    assert_int_equal(bk_slc_create(lp, s.light_count, boxes, N, &slc), LBK_OK);
    double xi[NL + 1];
    for (size_t i = 0; i < s.light_count; i++) xi[i] = unit(&r);
    bk_slc_draw *d = NULL;
    const double delta = 5;
    assert_int_equal(bk_slc_draw_create(slc, xi, delta, 2, &d), LBK_OK);
    uint32_t ids[NL + 1];
    size_t listed = 0, accepted = 0;
    for (int i = 0; i < N; i++) {
        size_t n = bk_slc_tile_lights(d, (size_t)i, ids);
        listed += n;
        for (size_t li = 0; li < s.light_count; li++) {
            double val[3], dir[3], dist;
            if (s.lights[li].type == BK_LIGHT_DIRECTIONAL || !bk_light_eval(&s.lights[li], &pts[3 * i], val, dir, &dist)) continue;
            double lum = 0.2126 * val[0] + 0.7152 * val[1] + 0.0722 * val[2];
            if (bk_slc_weight(lum, delta, xi[li]) == 0) continue;
            accepted++;
            int found = 0;
            for (size_t k = 0; k < n; k++) found |= ids[k] == li;
            assert_true(found);
        }
    }
    print_message("per point: %.1f listed, %.1f accepted, of %zu lights\n", (double)listed / N, (double)accepted / N,
                  s.light_count);
    assert_true(accepted > 0 && listed < (size_t)N * s.light_count / 2);
    bk_slc_draw_destroy(d);
    bk_slc_destroy(slc);
    free(boxes);
    free(pts);
    tsc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tile_lists_conservative),
        cmocka_unit_test(test_unbiased_against_brute_force),
        cmocka_unit_test(test_cache_bounce_unbiased),
        cmocka_unit_test(test_threads_identical_and_auto),
        cmocka_unit_test(test_resume_identical),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
