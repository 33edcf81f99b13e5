/* The denoiser (bake/denoise/denoise.h, DENOISE.md):
 *  - furnace: a closed box of albedo 0.9 emitting Le baked through atlas, texels and the
 *    transport's fixed 6-pass schedule, then denoised: every texel still within the furnace
 *    bound of TRANSPORT.md (the weights are a normalised non-negative combination, so an output
 *    cannot leave the range of its inputs), GLG probes still exact;
 *  - contact shadow: a black slab standing on a black floor under a small emitter (albedo 0:
 *    the floor's light is the emitter's direct light only, integrated here independently). The
 *    mean irradiance of the 4-texel strip against the slab's shadow side (the contact shadow)
 *    after denoising must agree with the analytic one within the derived bound below; a
 *    geometry-only blur of the same footprint must not (the test can fail); texels whose
 *    variance is exactly 0 (the umbra) come out bit-identical;
 *  - the estimate of the denoised result (bk_denoiser_error) within 2× of the error measured
 *    against the analytic floor irradiance, for the default filter and for a biased blur;
 *  - never across charts: two coplanar quads (two charts) of values 1 and 100 with a variance
 *    so large that the luminance test would mix them keep their values exactly, while the same
 *    step inside one chart is smoothed;
 *  - linearity: denoise(base) + denoise(set) = denoise(base + set) with the base's weights;
 *  - probes: across a wall the tetrahedra connect probes that cannot see each other; a probe
 *    behind the wall keeps its value, and without the wall it does not;
 *  - the result does not depend on the thread count. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/probes/delaunay.h"
#include "bake/probes/glg_place.h"
#include "bake/denoise/denoise.h"
#include "bake/transport/transport.h"
#include "lbk/sh.h"
#include "support/lightmap_fixture.h"
#include "support/transport_scenes.h"

/* The transport's irradiance estimate carried as the DC of an SH: E = π·Y00·L00. The denoiser
 * filters it with the weights built from the real SH, so the error is measured on the quantity
 * the bounds talk about (the SH9 irradiance of a small close emitter has a representation error
 * of its own, ~5 % on the contact strip, that is not the denoiser's). */
#define DC_TO_E (3.14159265358979 * 0.282094791773878)

static void e_to_sh(const float *irr, size_t n, lbk_sh9_rgb *out)
{
    memset(out, 0, n * sizeof *out);
    for (size_t k = 0; k < n; k++)
        for (int c = 0; c < 3; c++) out[k].c[c][0] = (float)(irr[3 * k + c] / DC_TO_E);
}

static double sh_e(const lbk_sh9_rgb *s, int c) { return DC_TO_E * s->c[c][0]; }

typedef struct run {
    lbk_sh9_rgb *rad, *e;   /* SH, and the irradiance estimate as SH */
    float *var;
} run;

static void run_alloc(run *r, size_t n)
{
    r->rad = calloc(n, sizeof *r->rad);
    r->e = calloc(n, sizeof *r->e);
    r->var = calloc(n, sizeof *r->var);
    assert_non_null(r->rad);
    assert_non_null(r->e);
    assert_non_null(r->var);
}

static void run_free(run *r) { free(r->rad), free(r->e), free(r->var); }

static void bake_halves(const bk_scene *s, const bk_tracer *tr, const bk_receiver *recv, size_t n, uint64_t seed, int samples,
                        int cells, run *r, float *halves)
{
    float *irr = calloc(3 * n, sizeof *irr);
    assert_non_null(irr);
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.seed = seed;
    o.threads = 2;
    o.target_error = -1;
    o.max_samples = samples;
    o.first_pass_samples = 16;
    o.max_cells = cells;
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = r->rad;
    out.irradiance = irr;
    out.variance = r->var;
    out.halves = halves;
    bk_transport_stats st;
    assert_int_equal(bk_transport_run(s, tr, recv, n, &o, &out, &st), LBK_OK);
    e_to_sh(irr, n, r->e);
    free(irr);
}

static void bake(const bk_scene *s, const bk_tracer *tr, const bk_receiver *recv, size_t n, uint64_t seed, int samples,
                 int cells, run *r)
{
    bake_halves(s, tr, recv, n, seed, samples, cells, r, NULL);
}

static bk_denoise_inputs texel_inputs(const bk_scene *s, const lmf *f, const run *r)
{
    bk_denoise_inputs in;
    memset(&in, 0, sizeof in);
    in.scene = s;
    in.tracer = f->tracer;
    in.atlas = &f->atlas;
    in.texels = &f->texels;
    in.texel_of_receiver = f->texel_of_receiver;
    in.texel_count = f->count;
    in.receiver_count = f->count;
    in.radiance = r->rad;
    in.variance = r->var;
    return in;
}

/* ---- furnace ------------------------------------------------------------------------------ */

/* TRANSPORT.md §Furnace: after P passes of 16·2^p samples per half every texel is within
 * Σ 2^p/S_p / Σ 2^p (+ float rounding); 6 passes: 0.60 %. */
static double furnace_bound(void)
{
    double num = 0, w = 0;
    for (int p = 0; p < 6; p++) num += ldexp(1, p) / (16 * ldexp(1, p)), w += ldexp(1, p);
    return num / w + 1e-5;
}

static void test_furnace_unbiased(void **state)
{
    (void)state;
    const double rho = 0.9, le = 1.0, e_true = M_PI * le / (1 - rho);
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, (float)rho, (float)rho, (float)rho, (float)le, (float)le, (float)le);
    s.materials[m].double_sided = 0;
    float mn[3] = {0, 0, 0}, mx[3] = {1, 1, 1};
    tsc_box(&s, mn, mx, 2, 1, m);
    tsc_update_bounds(&s);
    lmf f;
    lmf_build(&s, 8, &f);
    assert_true(f.count >= 300);
    /* GLG probes inside the box, after the texels (as bake.c numbers receivers) */
    bk_glg glg;
    bk_glg_options go;
    memset(&go, 0, sizeof go);
    go.spacing = 0.4f;
    assert_int_equal(bk_glg_build(&s, f.tracer, &go, 2, &glg), LBK_OK);
    assert_int_equal(glg.status, BK_GLG_OK);
    size_t n = f.count + glg.probe_count;
    bk_receiver *recv = calloc(n, sizeof *recv);
    assert_non_null(recv);
    memcpy(recv, f.receivers, f.count * sizeof *recv);
    for (size_t i = 0; i < glg.probe_count; i++) memcpy(recv[f.count + i].position, &glg.positions[3 * i], 12);
    run r;
    run_alloc(&r, n);
    bake(&s, f.tracer, recv, n, 7, 2 * 16 * 63, 768, &r);
    bk_denoise_inputs in = texel_inputs(&s, &f, &r);
    in.glg = &glg;
    in.glg_first = f.count;
    in.receiver_count = n;
    bk_denoiser *d;
    assert_int_equal(bk_denoiser_create(&in, NULL, &d), LBK_OK);
    lbk_sh9_rgb *sh = malloc(n * sizeof *sh);
    assert_non_null(sh);
    memcpy(sh, r.rad, n * sizeof *sh);
    double raw_max = 0, den_max = 0, sh_max = 0, probe_max = 0;
    for (size_t k = 0; k < f.count; k++) raw_max = fmax(raw_max, fabs(sh_e(&r.e[k], 1) / e_true - 1));
    assert_int_equal(bk_denoiser_apply(d, r.e), LBK_OK);
    assert_int_equal(bk_denoiser_apply(d, sh), LBK_OK);
    for (size_t k = 0; k < f.count; k++) {
        den_max = fmax(den_max, fabs(sh_e(&r.e[k], 1) / e_true - 1));
        float e[3];
        lbk_sh9_irradiance(&sh[k], recv[k].normal, e);
        sh_max = fmax(sh_max, fabs(e[1] / e_true - 1));
    }
    for (size_t i = f.count; i < n; i++) probe_max = fmax(probe_max, fabs(4 * M_PI * sh[i].c[1][0] * 0.282094791773878 / 4 / e_true - 1));
    bk_denoise_stats ds;
    bk_denoiser_stats(d, &ds);
    print_message("furnace rho 0.9: %zu texels, %zu probes; max texel error raw %.5f denoised %.5f (bound %.5f), "
                  "SH %.4f, probes %.2g\n",
                  f.count, glg.probe_count, raw_max, den_max, furnace_bound(), sh_max, probe_max);
    assert_int_equal(ds.texels, f.count);
    assert_int_equal(ds.probes, glg.probe_count);
    assert_true(raw_max <= furnace_bound());
    assert_true(den_max <= furnace_bound());
    assert_true(den_max <= raw_max + 1e-6); /* a normalised average never leaves its inputs' range */
    assert_true(sh_max < 0.02);           /* test_furnace's SH tolerance */
    assert_true(probe_max <= 1e-5);
    bk_denoiser_destroy(d);
    free(sh), free(recv);
    run_free(&r);
    bk_glg_free(&glg);
    lmf_free(&f);
    tsc_free(&s);
}

/* ---- contact shadow ---------------------------------------------------------------------------- */

#define CONTACT_DENSITY 32.0f
#define CONTACT_SEEDS 4
#define CONTACT_SPP 64

typedef struct contact_result {
    double strip_mean;   /* mean over seeds of the strip's mean irradiance */
    double rmse;         /* floor relative RMSE vs the analytic irradiance, RMS over seeds */
} contact_result;

static void test_contact_shadow(void **state)
{
    (void)state;
    bk_scene s;
    lmf_contact_scene(&s, 0);
    lmf f;
    lmf_build(&s, CONTACT_DENSITY, &f);
    size_t n = f.count;
    /* the strip: floor texels within 4 texels of the slab's shadow-side face, away from its ends */
    double *ref = calloc(n, sizeof *ref);
    uint8_t *strip = calloc(n, 1), *floor_t = calloc(n, 1);
    assert_non_null(ref);
    assert_non_null(strip);
    assert_non_null(floor_t);
    size_t ns = 0;
    double f_strip = 0, f_strip_fine = 0, open_strip = 0;
    for (size_t k = 0; k < n; k++) {
        const bk_texel *t = &f.texels.receivers[f.texel_of_receiver[k]];
        if (t->object != 0) continue;
        floor_t[k] = 1;
        ref[k] = lmf_contact_irradiance(t->position[0], t->position[1], 64, 1);
        if (t->position[0] > LMF_SLAB_T && t->position[0] < LMF_SLAB_T + 4 / CONTACT_DENSITY && fabsf(t->position[1]) < 0.3f) {
            strip[k] = 1, ns++;
            f_strip += lmf_contact_irradiance(t->position[0], t->position[1], 256, 1);
            f_strip_fine += lmf_contact_irradiance(t->position[0], t->position[1], 512, 1);
            open_strip += lmf_contact_irradiance(t->position[0], t->position[1], 64, 0);
        }
    }
    assert_true(ns >= 60);
    f_strip /= ns, f_strip_fine /= ns, open_strip /= ns;
    const double quad_err = fabs(f_strip_fine - f_strip); /* the quadrature's own error */

    enum { RAW, AUTO, BLUR, NM };
    contact_result res[NM];
    memset(res, 0, sizeof res);
    double var_sum = 0;  /* Σ over seeds of the raw strip mean's variance (transport's estimate) */
    size_t zero_var = 0, zero_var_same = 0;
    run r;
    run_alloc(&r, n);
    lbk_sh9_rgb *y = malloc(n * sizeof *y);
    assert_non_null(y);
    for (int sd = 0; sd < CONTACT_SEEDS; sd++) {
        bake(&s, f.tracer, f.receivers, n, 100 + (uint64_t)sd, CONTACT_SPP, 0, &r);
        double v = 0;
        for (size_t k = 0; k < n; k++)
            if (strip[k]) v += r.var[k];
        var_sum += v / ((double)ns * ns);
        for (int mth = 0; mth < NM; mth++) {
            memcpy(y, r.e, n * sizeof *y);
            if (mth != RAW) {
                bk_denoise_options o;
                memset(&o, 0, sizeof o);
                if (mth == BLUR) o.method = BK_DENOISE_BLUR, o.radius = 4, o.clamp = -1;
                bk_denoise_inputs in = texel_inputs(&s, &f, &r);
                bk_denoiser *d;
                assert_int_equal(bk_denoiser_create(&in, &o, &d), LBK_OK);
                assert_int_equal(bk_denoiser_apply(d, y), LBK_OK);
                bk_denoiser_destroy(d);
            }
            double sm = 0, num = 0, den = 0;
            for (size_t k = 0; k < n; k++) {
                double e = 0.2126 * sh_e(&y[k], 0) + 0.7152 * sh_e(&y[k], 1) + 0.0722 * sh_e(&y[k], 2);
                if (strip[k]) sm += e;
                if (floor_t[k]) num += (e - ref[k]) * (e - ref[k]), den += ref[k] * ref[k];
                if (mth == AUTO && floor_t[k] && r.var[k] == 0) {
                    zero_var++;
                    zero_var_same += !memcmp(&y[k], &r.e[k], sizeof y[k]);
                }
            }
            res[mth].strip_mean += sm / ns / CONTACT_SEEDS;
            res[mth].rmse += num / den / CONTACT_SEEDS;
        }
    }
    /* The bound. Each texel's raw estimate is unbiased with the variance the transport reports
     * (calibrated: estimate/true 0.97–1.07 in bench_denoise), independent between texels here
     * (albedo 0: no cache), so the mean of the strip over K seeds has standard deviation
     * σ_K = sqrt(Σ_seeds var(strip mean)) / K. The denoised strip mean must agree with the
     * analytic one within 3 σ_K plus the quadrature error: whatever bias the denoiser adds to
     * the contact shadow must be smaller than what K raw bakes can resolve. */
    const double sigma_k = sqrt(var_sum) / CONTACT_SEEDS;
    const double bound = 3 * sigma_k + quad_err;
    const double depth = 1 - f_strip / open_strip;
    for (int mth = 0; mth < NM; mth++) res[mth].rmse = sqrt(res[mth].rmse);
    print_message("contact strip: %zu texels, analytic %.4f (open floor %.4f: depth %.3f), bound ±%.4f (3σ %.4f, "
                  "quadrature %.1e)\n",
                  ns, f_strip, open_strip, depth, bound, 3 * sigma_k, quad_err);
    static const char *names[NM] = {"raw", "auto", "blur"};
    for (int mth = 0; mth < NM; mth++)
        print_message("  %-5s strip %.4f (error %+.4f, depth %.3f), floor rel. RMSE %.2f%%\n", names[mth], res[mth].strip_mean,
                      res[mth].strip_mean - f_strip, 1 - res[mth].strip_mean / open_strip, 100 * res[mth].rmse);
    print_message("  %zu floor texels with variance 0, %zu of them unchanged\n", zero_var, zero_var_same);
    assert_true(fabs(res[RAW].strip_mean - f_strip) <= bound);   /* the reference is right */
    assert_true(fabs(res[AUTO].strip_mean - f_strip) <= bound);  /* the denoiser keeps the shadow */
    assert_true(fabs(res[BLUR].strip_mean - f_strip) > bound);   /* a blur does not: the test can fail */
    /* and it pays: measured 0.47 of the raw error at this budget (bench_denoise) */
    assert_true(res[AUTO].rmse < 0.6 * res[RAW].rmse);
    assert_true(zero_var > 0);
    assert_int_equal(zero_var_same, zero_var);
    free(y), free(ref), free(strip), free(floor_t);
    run_free(&r);
    lmf_free(&f);
    tsc_free(&s);
}

/* ---- the estimate of the denoised result -------------------------------------------------------- */

static double lum_e(const lbk_sh9_rgb *y) { return 0.2126 * sh_e(y, 0) + 0.7152 * sh_e(y, 1) + 0.0722 * sh_e(y, 2); }

/* The floor class's noise estimate with each half filtered by its own weights
 * (bk_denoiser_half_delta, as the pipeline calls it), through bk_denoiser_error_groups with one
 * group, the floor. */
static double cross_noise(const bk_denoiser *d, const bk_denoise_inputs *in, const run *r, const float *halves,
                          const size_t class_end[BK_RECEIVER_CLASSES], float *cross)
{
    assert_int_equal(bk_denoiser_half_delta(d, in, r->rad, r->var, halves, cross), LBK_OK);
    uint32_t *group = calloc(class_end[0] + 1, sizeof *group); /* every floor texel in group 0 */
    assert_non_null(group);
    bk_denoise_group_error g0;
    const bk_denoise_groups g = {class_end[0], group, 1, &g0};
    bk_denoise_error e;
    /* the radiance riding on the same pass (as the pipeline filters the base): the same floats as
     * filtering it on its own */
    const size_t n = in->receiver_count, nt = in->texel_count;
    float *filtered = malloc((nt ? nt : 1) * sizeof(lbk_sh9_rgb));
    lbk_sh9_rgb *ridden = malloc(n * sizeof *ridden), *alone = malloc(n * sizeof *alone);
    assert_non_null(filtered), assert_non_null(ridden), assert_non_null(alone);
    bk_denoise_ride ride = {r->rad, filtered, 0};
    assert_int_equal(bk_denoiser_error_groups(d, halves, class_end, &e, &g, cross, &ride), LBK_OK);
    assert_int_equal(ride.done, 1); /* the default filter has one level */
    memcpy(ridden, r->rad, n * sizeof *ridden);
    memcpy(alone, r->rad, n * sizeof *alone);
    assert_int_equal(bk_denoiser_blend_texels(d, ridden, filtered), LBK_OK);
    const int texels_only[BK_RECEIVER_CLASSES] = {1, 0, 0};
    assert_int_equal(bk_denoiser_apply_classes(d, alone, texels_only), LBK_OK);
    assert_memory_equal(ridden, alone, n * sizeof *ridden);
    assert_true(memcmp(ridden, r->rad, nt * sizeof *ridden) != 0); /* it filtered something */
    free(filtered), free(ridden), free(alone);
    /* without a ride: the same estimate */
    bk_denoise_error e2;
    assert_int_equal(bk_denoiser_error_groups(d, halves, class_end, &e2, &g, cross, NULL), LBK_OK);
    assert_memory_equal(e2.rel_rmse, e.rel_rmse, sizeof e.rel_rmse);
    free(group);
    assert_true(fabs(g0.noise - e.noise[BK_CLASS_TEXEL]) <= 1e-9 + 1e-6 * g0.noise); /* the group is the class */
    return e.noise[BK_CLASS_TEXEL];
}

/* bk_denoiser_error against the truth. The contact scene's floor (receivers reordered so that
 * the floor is the first class) has an analytic irradiance, so the error each denoised bake
 * really has is known: √(Σ (D − E)² / Σ D²) over the floor, normalised like the estimate. The
 * estimate must be within 2× of it (the goal for every class), for the default filter,
 * whose error is mostly the noise it leaves, and for the geometry-only blur, whose error is
 * mostly its bias across the shadow (the estimate without its bias term is ~0.1× the blur's
 * error here: this is what makes the case fail when the bias term is missing). With every
 * variance 0 the filter is the identity and the estimate is exactly the transport's. */
static void test_denoised_estimate(void **state)
{
    (void)state;
    bk_scene s;
    lmf_contact_scene(&s, 0);
    lmf f;
    lmf_build(&s, CONTACT_DENSITY, &f);
    const size_t n = f.count;
    /* floor texels first */
    uint32_t *tor = malloc(n * sizeof *tor);
    bk_receiver *recv = malloc(n * sizeof *recv);
    double *ref = calloc(n, sizeof *ref);
    assert_non_null(tor), assert_non_null(recv), assert_non_null(ref);
    size_t nf = 0;
    for (size_t k = 0; k < n; k++) nf += f.texels.receivers[f.texel_of_receiver[k]].object == 0;
    size_t at = 0;
    for (int pass = 0; pass < 2; pass++)
        for (size_t k = 0; k < n; k++) {
            const bk_texel *t = &f.texels.receivers[f.texel_of_receiver[k]];
            if ((t->object == 0) != (pass == 0)) continue;
            tor[at] = f.texel_of_receiver[k];
            recv[at] = f.receivers[k];
            if (pass == 0) ref[at] = lmf_contact_irradiance(t->position[0], t->position[1], 64, 1);
            at++;
        }
    assert_int_equal(at, n);
    assert_true(nf > 1000 && nf < n);
    const size_t class_end[BK_RECEIVER_CLASSES] = {nf, n, n};
    run r;
    run_alloc(&r, n);
    float *halves = malloc(2 * n * sizeof *halves);
    lbk_sh9_rgb *y = malloc(n * sizeof *y);
    assert_non_null(halves), assert_non_null(y);
    enum { AUTO, BLUR, NM };
    double est[NM] = {0}, meas[NM] = {0}, est_noise_only[NM] = {0}, est_cross = 0;
    double *xs = malloc(CONTACT_SEEDS * nf * sizeof *xs); /* the denoised floor per seed */
    float *cross = malloc(n * sizeof *cross);
    assert_non_null(xs), assert_non_null(cross);
    for (int sd = 0; sd < CONTACT_SEEDS; sd++) {
        bake_halves(&s, f.tracer, recv, n, 300 + (uint64_t)sd, CONTACT_SPP, 0, &r, halves);
        for (int mth = 0; mth < NM; mth++) {
            bk_denoise_options o;
            memset(&o, 0, sizeof o);
            if (mth == BLUR) o.method = BK_DENOISE_BLUR, o.radius = 4, o.clamp = -1;
            bk_denoise_inputs in = texel_inputs(&s, &f, &r);
            in.texel_of_receiver = tor;
            bk_denoiser *d;
            assert_int_equal(bk_denoiser_create(&in, &o, &d), LBK_OK);
            memcpy(y, r.e, n * sizeof *y);
            assert_int_equal(bk_denoiser_apply(d, y), LBK_OK);
            bk_denoise_error e;
            assert_int_equal(bk_denoiser_error(d, halves, class_end, &e), LBK_OK);
            if (mth == AUTO) est_cross += cross_noise(d, &in, &r, halves, class_end, cross) / CONTACT_SEEDS;
            bk_denoiser_destroy(d);
            double num = 0, den = 0;
            for (size_t k = 0; k < nf; k++) {
                const double x = lum_e(&y[k]);
                num += (x - ref[k]) * (x - ref[k]), den += x * x;
                if (mth == AUTO) xs[(size_t)sd * nf + k] = x;
            }
            meas[mth] += sqrt(num / den) / CONTACT_SEEDS;
            est[mth] += e.rel_rmse[BK_CLASS_TEXEL] / CONTACT_SEEDS;
            est_noise_only[mth] += e.noise[BK_CLASS_TEXEL] / CONTACT_SEEDS;
        }
    }
    static const char *names[NM] = {"auto", "blur"};
    for (int mth = 0; mth < NM; mth++) {
        print_message("denoised floor (%s): estimated %.2f%% (noise alone %.2f%%), measured against the analytic "
                      "irradiance %.2f%%: %.2f\n",
                      names[mth], 100 * est[mth], 100 * est_noise_only[mth], 100 * meas[mth], est[mth] / meas[mth]);
        assert_true(est[mth] >= 0.5 * meas[mth] && est[mth] <= 2 * meas[mth]);
    }
    assert_true(est_noise_only[BLUR] < 0.5 * meas[BLUR]); /* the blur's error is its bias */
    /* The noise the default filter leaves, against how its output differs between seeds: the
     * same weights' Σ (Dδ)² misses what the weights add by following the noise; each half
     * filtered by its own weights (bk_denoiser_half_delta) sees it. */
    double var = 0, sq = 0;
    for (size_t k = 0; k < nf; k++) {
        double m = 0, v = 0;
        for (int sd = 0; sd < CONTACT_SEEDS; sd++) m += xs[(size_t)sd * nf + k] / CONTACT_SEEDS;
        for (int sd = 0; sd < CONTACT_SEEDS; sd++) v += (xs[(size_t)sd * nf + k] - m) * (xs[(size_t)sd * nf + k] - m);
        var += v / (CONTACT_SEEDS - 1), sq += m * m;
    }
    const double seed_noise = sqrt(var / sq);
    print_message("denoised floor (auto), noise between seeds %.2f%%: same weights %.2f%% (%.2f), each half its own "
                  "weights %.2f%% (%.2f)\n",
                  100 * seed_noise, 100 * est_noise_only[AUTO], est_noise_only[AUTO] / seed_noise, 100 * est_cross,
                  est_cross / seed_noise);
    assert_true(est_cross > est_noise_only[AUTO]);
    assert_true(est_cross >= 0.5 * seed_noise && est_cross <= 2 * seed_noise);
    free(xs), free(cross);

    /* identity: every variance 0, so every texel keeps its input */
    bk_denoise_inputs in = texel_inputs(&s, &f, &r);
    in.texel_of_receiver = tor;
    memset(r.var, 0, n * sizeof *r.var);
    bk_denoiser *d;
    assert_int_equal(bk_denoiser_create(&in, NULL, &d), LBK_OK);
    bk_denoise_error e;
    assert_int_equal(bk_denoiser_error(d, halves, class_end, &e), LBK_OK);
    double num = 0, den = 0;
    for (size_t k = 0; k < nf; k++) {
        const double a = halves[2 * k], b = halves[2 * k + 1];
        num += 0.25 * (a - b) * (a - b), den += 0.25 * (a + b) * (a + b);
    }
    assert_true(fabs(e.rel_rmse[BK_CLASS_TEXEL] - sqrt(num / den)) <= 1e-6 * sqrt(num / den));
    assert_true(e.bias[BK_CLASS_TEXEL] == 0);
    const size_t bad_end[BK_RECEIVER_CLASSES] = {n, nf, n};
    assert_int_equal(bk_denoiser_error(d, halves, bad_end, &e), LBK_ERR_INVALID_ARGUMENT);
    bk_denoiser_destroy(d);
    free(tor), free(recv), free(ref), free(halves), free(y);
    run_free(&r);
    lmf_free(&f);
    tsc_free(&s);
}

/* ---- charts ------------------------------------------------------------------------------------ */

static void two_quads(bk_scene *s)
{
    tsc_init(s);
    uint32_t m = tsc_material(s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, a2[3] = {1, 1, 0}, a3[3] = {0, 1, 0};
    tsc_quad(s, a0, a1, a2, a3, 1, m);
    tsc_object(s, "b", "", "");
    float b0[3] = {1, 0, 0}, b1[3] = {2, 0, 0}, b2[3] = {2, 1, 0}, b3[3] = {1, 1, 0};
    tsc_quad(s, b0, b1, b2, b3, 1, m);
    tsc_update_bounds(s);
}

/* Synthetic base: irradiance value(k) as DC, variance v everywhere. */
static void synthetic(const lmf *f, double (*value)(const bk_texel *), float v, run *r)
{
    for (size_t k = 0; k < f->count; k++) {
        const bk_texel *t = &f->texels.receivers[f->texel_of_receiver[k]];
        memset(&r->rad[k], 0, sizeof r->rad[k]);
        for (int c = 0; c < 3; c++) r->rad[k].c[c][0] = (float)(value(t) / DC_TO_E);
        r->var[k] = v;
    }
}

static double by_object(const bk_texel *t) { return t->object == 0 ? 1.0 : 100.0; }
static double by_half(const bk_texel *t) { return t->position[0] < 0.5f ? 1.0 : 100.0; }

static void test_never_across_charts(void **state)
{
    (void)state;
    bk_scene s;
    two_quads(&s);
    lmf f;
    lmf_build(&s, 16, &f);
    assert_int_equal(f.atlas.chart_count, 2);
    /* the charts are within the filter's reach of each other in lightmap space */
    int close = 0;
    for (size_t a = 0; a < f.count && !close; a++)
        for (size_t b = 0; b < f.count && !close; b++) {
            const bk_texel *ta = &f.texels.receivers[f.texel_of_receiver[a]], *tb = &f.texels.receivers[f.texel_of_receiver[b]];
            close = ta->object != tb->object && ta->page == tb->page && abs((int)ta->x - (int)tb->x) <= 5 &&
                    abs((int)ta->y - (int)tb->y) <= 5;
        }
    assert_true(close);
    static const int methods[] = {BK_DENOISE_AUTO, BK_DENOISE_ATROUS, BK_DENOISE_NLM, BK_DENOISE_BLUR};
    run r;
    run_alloc(&r, f.count);
    lbk_sh9_rgb *y = malloc(f.count * sizeof *y);
    assert_non_null(y);
    for (int mi = 0; mi < 4; mi++) {
        bk_denoise_options o;
        memset(&o, 0, sizeof o);
        o.method = methods[mi];
        /* two charts: 1 and 100, a variance (σ = 1000) under which 1 and 100 look alike */
        synthetic(&f, by_object, 1e6f, &r);
        bk_denoise_inputs in = texel_inputs(&s, &f, &r);
        bk_denoiser *d;
        assert_int_equal(bk_denoiser_create(&in, &o, &d), LBK_OK);
        memcpy(y, r.rad, f.count * sizeof *y);
        assert_int_equal(bk_denoiser_apply(d, y), LBK_OK);
        for (size_t k = 0; k < f.count; k++) assert_memory_equal(&y[k], &r.rad[k], sizeof y[k]);
        bk_denoiser_destroy(d);
        /* the same step inside one chart is smoothed: only the chart border stopped it above */
        synthetic(&f, by_half, 1e6f, &r);
        in = texel_inputs(&s, &f, &r);
        assert_int_equal(bk_denoiser_create(&in, &o, &d), LBK_OK);
        memcpy(y, r.rad, f.count * sizeof *y);
        assert_int_equal(bk_denoiser_apply(d, y), LBK_OK);
        double moved = 0;
        for (size_t k = 0; k < f.count; k++) moved = fmax(moved, fabs(sh_e(&y[k], 1) - sh_e(&r.rad[k], 1)));
        print_message("method %d: within one chart the step moved by up to %.2f\n", methods[mi], moved);
        assert_true(moved > 1);
        bk_denoiser_destroy(d);
    }
    free(y);
    run_free(&r);
    lmf_free(&f);
    tsc_free(&s);
}

/* ---- linearity ---------------------------------------------------------------------------------- */

static void test_light_set_linearity(void **state)
{
    (void)state;
    bk_scene s;
    lmf_contact_scene(&s, 0.5f);
    lmf f;
    lmf_build(&s, 16, &f);
    size_t n = f.count;
    run base, set;
    run_alloc(&base, n);
    run_alloc(&set, n);
    bake(&s, f.tracer, f.receivers, n, 1, 64, 4096, &base);
    bake(&s, f.tracer, f.receivers, n, 2, 64, 4096, &set); /* another noisy field: the "set" */
    bk_denoise_inputs in = texel_inputs(&s, &f, &base);
    bk_denoiser *d;
    assert_int_equal(bk_denoiser_create(&in, NULL, &d), LBK_OK);
    lbk_sh9_rgb *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *sum = malloc(n * sizeof *sum);
    assert_non_null(a);
    assert_non_null(b);
    assert_non_null(sum);
    memcpy(a, base.rad, n * sizeof *a);
    memcpy(b, set.rad, n * sizeof *b);
    for (size_t k = 0; k < n; k++)
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < 9; i++) sum[k].c[c][i] = base.rad[k].c[c][i] + set.rad[k].c[c][i];
    assert_int_equal(bk_denoiser_apply(d, a), LBK_OK);
    assert_int_equal(bk_denoiser_apply(d, b), LBK_OK);
    assert_int_equal(bk_denoiser_apply(d, sum), LBK_OK);
    double worst = 0, scale = 0, changed = 0;
    for (size_t k = 0; k < n; k++)
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < 9; i++) {
                worst = fmax(worst, fabs(a[k].c[c][i] + b[k].c[c][i] - sum[k].c[c][i]));
                scale = fmax(scale, fabs(sum[k].c[c][i]));
                changed = fmax(changed, fabs(a[k].c[c][i] - base.rad[k].c[c][i]));
            }
    print_message("linearity: max |d(base) + d(set) - d(base + set)| = %.3g (values up to %.3g; denoising moved "
                  "values by up to %.3g)\n",
                  worst, scale, changed);
    assert_true(changed > 1e-3 * scale); /* it did filter */
    assert_true(worst <= 1e-5 * scale);  /* float rounding: a few ulps of the largest value */
    bk_denoiser_destroy(d);
    free(a), free(b), free(sum);
    run_free(&base), run_free(&set);
    lmf_free(&f);
    tsc_free(&s);
}

/* ---- probes -------------------------------------------------------------------------------------- */

/* Probes on a jittered 4×3×3 grid, x in {0, 1, 2, 3}; a wall at x = wall_x (a big double-sided
 * quad). Probes with x < 1.5 are dark (0), the others lit (10); every variance 1e4 (σ = 100),
 * so by luminance alone dark and lit probes would be averaged. Returns the largest change of a
 * dark probe; *cross counts the tetrahedron edges joining a dark and a lit probe. */
static double probe_case(float wall_x, size_t *cross, size_t *visible, size_t *edges)
{
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float w0[3] = {wall_x, -2, -2}, w1[3] = {wall_x, 4, -2}, w2[3] = {wall_x, 4, 4}, w3[3] = {wall_x, -2, 4};
    tsc_quad(&s, w0, w1, w2, w3, 1, m);
    tsc_update_bounds(&s);
    bk_tracer *tr;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    float pts[36 * 3];
    size_t np = 0;
    for (int z = 0; z < 3; z++)
        for (int y = 0; y < 3; y++)
            for (int x = 0; x < 4; x++, np++) {
                uint32_t h = (uint32_t)(np * 2654435761u);
                pts[3 * np] = x + 0.1f * ((h & 255) / 255.0f - 0.5f);
                pts[3 * np + 1] = y + 0.1f * (((h >> 8) & 255) / 255.0f - 0.5f);
                pts[3 * np + 2] = z + 0.1f * (((h >> 16) & 255) / 255.0f - 0.5f);
            }
    bk_tetmesh tm;
    assert_int_equal(bk_delaunay(pts, np, NULL, &tm), BK_DELAUNAY_OK);
    assert_int_equal(tm.point_count, np);
    bk_glg glg;
    memset(&glg, 0, sizeof glg);
    glg.status = BK_GLG_OK;
    glg.probe_count = np;
    glg.positions = pts;
    glg.tet_count = tm.tet_count;
    glg.tets = tm.tets;
    *cross = 0;
    for (size_t t = 0; t < tm.tet_count; t++)
        for (int a = 0; a < 4; a++)
            for (int b = a + 1; b < 4; b++) *cross += (pts[3 * tm.tets[4 * t + a]] < 1.5f) != (pts[3 * tm.tets[4 * t + b]] < 1.5f);
    lbk_sh9_rgb *sh = calloc(np, sizeof *sh), *y = calloc(np, sizeof *y);
    float *var = calloc(np, sizeof *var);
    assert_non_null(sh);
    assert_non_null(y);
    assert_non_null(var);
    for (size_t i = 0; i < np; i++) {
        double fl = pts[3 * i] < 1.5f ? 0 : 10; /* fluence/4 = π·Y00·L00 */
        for (int c = 0; c < 3; c++) sh[i].c[c][0] = (float)(fl / DC_TO_E);
        var[i] = 1e4f;
    }
    bk_denoise_inputs in;
    memset(&in, 0, sizeof in);
    in.tracer = tr;
    in.glg = &glg;
    in.glg_first = 0;
    in.receiver_count = np;
    in.radiance = sh;
    in.variance = var;
    bk_denoiser *d;
    assert_int_equal(bk_denoiser_create(&in, NULL, &d), LBK_OK);
    memcpy(y, sh, np * sizeof *y);
    assert_int_equal(bk_denoiser_apply(d, y), LBK_OK);
    bk_denoise_stats st;
    bk_denoiser_stats(d, &st);
    *visible = st.probe_edges_visible, *edges = st.probe_edges;
    double worst = 0;
    for (size_t i = 0; i < np; i++)
        if (pts[3 * i] < 1.5f) worst = fmax(worst, fabs(sh_e(&y[i], 1) - sh_e(&sh[i], 1)));
    bk_denoiser_destroy(d);
    free(sh), free(y), free(var);
    glg.positions = NULL, glg.tets = NULL;
    bk_tetmesh_free(&tm);
    bk_tracer_destroy(tr);
    tsc_free(&s);
    return worst;
}

static void test_probes_respect_visibility(void **state)
{
    (void)state;
    size_t cross, vis, edges;
    double wall = probe_case(1.5f, &cross, &vis, &edges);
    print_message("probes, wall at x = 1.5: %zu edges (%zu visible), %zu tet edges cross; dark probes moved by %.3g\n",
                  edges, vis, cross, wall);
    assert_true(cross > 0);
    assert_true(vis < edges);
    assert_true(wall == 0);
    double open = probe_case(10.0f, &cross, &vis, &edges);
    print_message("probes, wall out of the way: %zu of %zu edges visible; dark probes moved by up to %.3g\n", vis, edges, open);
    assert_int_equal(vis, edges);
    assert_true(open > 0.5);
}

/* ---- threads ------------------------------------------------------------------------------------- */

static void test_thread_count_independent(void **state)
{
    (void)state;
    bk_scene s;
    lmf_contact_scene(&s, 0.5f);
    lmf f;
    lmf_build(&s, 16, &f);
    size_t n = f.count;
    run r;
    run_alloc(&r, n);
    bake(&s, f.tracer, f.receivers, n, 3, 64, 4096, &r);
    static const int methods[] = {BK_DENOISE_AUTO, BK_DENOISE_ATROUS, BK_DENOISE_NLM};
    lbk_sh9_rgb *y1 = malloc(n * sizeof *y1), *y3 = malloc(n * sizeof *y3);
    assert_non_null(y1);
    assert_non_null(y3);
    for (int mi = 0; mi < 3; mi++) {
        bk_denoise_inputs in = texel_inputs(&s, &f, &r);
        bk_denoise_options o;
        memset(&o, 0, sizeof o);
        o.method = methods[mi];
        bk_denoiser *d;
        o.threads = 1;
        assert_int_equal(bk_denoiser_create(&in, &o, &d), LBK_OK);
        memcpy(y1, r.rad, n * sizeof *y1);
        assert_int_equal(bk_denoiser_apply(d, y1), LBK_OK);
        bk_denoiser_destroy(d);
        o.threads = 3;
        assert_int_equal(bk_denoiser_create(&in, &o, &d), LBK_OK);
        memcpy(y3, r.rad, n * sizeof *y3);
        assert_int_equal(bk_denoiser_apply(d, y3), LBK_OK);
        bk_denoiser_destroy(d);
        assert_memory_equal(y1, y3, n * sizeof *y1);
        assert_memory_not_equal(y1, r.rad, n * sizeof *y1);
    }
    free(y1), free(y3);
    run_free(&r);
    lmf_free(&f);
    tsc_free(&s);
}

static void test_invalid_arguments(void **state)
{
    (void)state;
    bk_denoiser *d = (bk_denoiser *)&d;
    assert_int_equal(bk_denoiser_create(NULL, NULL, &d), LBK_ERR_INVALID_ARGUMENT);
    assert_null(d);
    bk_denoise_inputs in;
    memset(&in, 0, sizeof in);
    in.receiver_count = 4;
    assert_int_equal(bk_denoiser_create(&in, NULL, &d), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_denoiser_create(&in, NULL, NULL), LBK_ERR_INVALID_ARGUMENT);
    /* nothing to filter: a no-op denoiser */
    lbk_sh9_rgb sh[4];
    float var[4] = {0};
    memset(sh, 0, sizeof sh);
    in.radiance = sh;
    in.variance = var;
    assert_int_equal(bk_denoiser_create(&in, NULL, &d), LBK_OK);
    assert_int_equal(bk_denoiser_apply(d, sh), LBK_OK);
    assert_int_equal(bk_denoiser_apply(d, NULL), LBK_ERR_INVALID_ARGUMENT);
    /* the halves' filters share d's geometry: d must be built from the same receivers */
    float halves[8] = {1, 1, 2, 2, 3, 3, 4, 4}, cross[4] = {9, 9, 9, 9};
    assert_int_equal(bk_denoiser_half_delta(NULL, &in, sh, var, halves, cross), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_denoiser_half_delta(d, &in, sh, var, halves, NULL), LBK_ERR_INVALID_ARGUMENT);
    in.receiver_count = 3;
    assert_int_equal(bk_denoiser_half_delta(d, &in, sh, var, halves, cross), LBK_ERR_INVALID_ARGUMENT);
    in.receiver_count = 4;
    /* nothing filtered: each half passes through, so cross is (A − B)/2 = 0 */
    assert_int_equal(bk_denoiser_half_delta(d, &in, sh, var, halves, cross), LBK_OK);
    for (int i = 0; i < 4; i++) assert_true(cross[i] == 0);
    bk_denoiser_destroy(d);
    bk_denoiser_destroy(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_furnace_unbiased),
        cmocka_unit_test(test_contact_shadow),
        cmocka_unit_test(test_denoised_estimate),
        cmocka_unit_test(test_never_across_charts),
        cmocka_unit_test(test_light_set_linearity),
        cmocka_unit_test(test_probes_respect_visibility),
        cmocka_unit_test(test_thread_count_independent),
        cmocka_unit_test(test_invalid_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
