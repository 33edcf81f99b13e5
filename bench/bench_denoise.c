/* Denoiser measurements (printed, not asserted; bake/denoise/DENOISE.md quotes them):
 *  contact  the contact-shadow scene (tests/support/lightmap_fixture.h) with albedo 0: the
 *           reference is the direct irradiance integrated independently (no baker code), so
 *           the error includes the denoiser's bias. Per method: relative RMSE over the floor,
 *           the shadow strip next to the slab (mean over seeds vs analytic: bias), cost.
 *  room     a furnished room with GI (bench_transport's): reference a long bake, so the error
 *           is the noise only; raw bakes at 2× and 4× the samples give the equal-time rows.
 * Usage: bench_denoise [contact|room|all] [seeds (2)]. CPU seconds (the machine is shared). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench/bench_util.h"
#include "bake/denoise/denoise.h"
#include "bake/transport/transport.h"
#include "lbk/sh.h"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"
#include "tests/support/lightmap_fixture.c"

typedef struct method {
    const char *name;
    bk_denoise_options o;
    int off;
} method;

static method methods[32];
static int method_count;

static void add(const char *name, int m, int it, int radius, float sl, float clamp, float alb)
{
    method *x = &methods[method_count++];
    memset(x, 0, sizeof *x);
    x->name = name;
    x->o.method = m;
    x->o.iterations = it;
    x->o.radius = radius;
    x->o.sigma_lum = sl;
    x->o.clamp = clamp;
    x->o.sigma_albedo = alb;
    x->o.threads = 2;
    x->off = m < 0;
}

/* The candidates of DENOISE.md: the chosen one (auto = NLM, k 1, 11×11 window), the à-trous
 * alternative and a few neighbours of each, and the geometry-only blur as the control. */
static void default_methods(void)
{
    add("off", -1, 0, 0, 0, 0, 0);
    add("auto (nlm r5 k1)", BK_DENOISE_AUTO, 0, 0, 0, 0, 0);
    add("nlm r3 k1", BK_DENOISE_NLM, 0, 3, 1.0f, 0, 0);
    add("nlm r5 k0.45", BK_DENOISE_NLM, 0, 5, 0.45f, 0, 0);
    add("nlm r5 k1.5", BK_DENOISE_NLM, 0, 5, 1.5f, 0, 0);
    add("nlm r5 k1 no clamp", BK_DENOISE_NLM, 0, 5, 1.0f, -1, 0);
    add("nlm r5 k1 albedo", BK_DENOISE_NLM, 0, 5, 1.0f, 0, 0.1f);
    add("atrous L4 s4", BK_DENOISE_ATROUS, 4, 0, 4, 0, 0);
    add("atrous L3 s4", BK_DENOISE_ATROUS, 3, 0, 4, 0, 0);
    add("atrous L4 s2", BK_DENOISE_ATROUS, 4, 0, 2, 0, 0);
    add("blur r4 (control)", BK_DENOISE_BLUR, 0, 4, 0, -1, 0);
}

/* The error is measured on the transport's direct irradiance estimate, carried through the
 * denoiser as the DC of an SH (E = π·Y00·L00) and filtered with the weights built from the
 * real SH: the SH9 irradiance of a small, close emitter has a representation error of its own
 * (4.6 % on the contact strip at 1024 spp) that has nothing to do with the denoiser. */
#define DC_TO_E (3.14159265358979 * 0.282094791773878)

static float texel_lum(const lmf *f, size_t k, const lbk_sh9_rgb *sh)
{
    (void)f;
    return (float)(DC_TO_E * (0.2126 * sh->c[0][0] + 0.7152 * sh->c[1][0] + 0.0722 * sh->c[2][0]));
}

static void irradiance_as_sh(size_t n, const float *irr, lbk_sh9_rgb *out)
{
    memset(out, 0, n * sizeof *out);
    for (size_t k = 0; k < n; k++)
        for (int c = 0; c < 3; c++) out[k].c[c][0] = (float)(irr[3 * k + c] / DC_TO_E);
}

static double bake(const bk_scene *s, const lmf *f, int samples, uint64_t seed, lbk_sh9_rgb *rad, float *var,
                   lbk_sh9_rgb *irr_sh)
{
    float *irr = malloc(3 * f->count * sizeof *irr);
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.seed = seed;
    o.threads = 2;
    o.target_error = -1;
    o.max_samples = samples;
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = rad;
    out.variance = var;
    out.irradiance = irr;
    bk_transport_stats st;
    double t0 = bench_process_cpu();
    if (bk_transport_run(s, f->tracer, f->receivers, f->count, &o, &out, &st)) abort();
    double dt = bench_process_cpu() - t0;
    irradiance_as_sh(f->count, irr, irr_sh);
    free(irr);
    return dt;
}

static double denoise(const bk_scene *s, const lmf *f, const method *m, const lbk_sh9_rgb *base, const float *var,
                      const lbk_sh9_rgb *data, lbk_sh9_rgb *out)
{
    memcpy(out, data, f->count * sizeof *out);
    if (m->off) return 0;
    bk_denoise_inputs in;
    memset(&in, 0, sizeof in);
    in.scene = s;
    in.atlas = &f->atlas;
    in.texels = &f->texels;
    in.texel_of_receiver = f->texel_of_receiver;
    in.texel_count = f->count;
    in.receiver_count = f->count;
    in.radiance = base;
    in.variance = var;
    double t0 = bench_process_cpu();
    bk_denoiser *d;
    if (bk_denoiser_create(&in, &m->o, &d) || bk_denoiser_apply(d, out)) abort();
    double dt = bench_process_cpu() - t0;
    bk_denoiser_destroy(d);
    return dt;
}

/* ---- contact ---------------------------------------------------------------------------------- */

static void contact(int seeds)
{
    const float density = 32;
    bk_scene s;
    lmf_contact_scene(&s, 0);
    lmf f;
    lmf_build(&s, density, &f);
    size_t n = f.count;
    /* floor texels and their analytic irradiance; the strip: 4 texels next to the slab's shadow side */
    double *ref = calloc(n, sizeof *ref);
    unsigned char *floor_t = calloc(n, 1), *strip = calloc(n, 1);
    size_t nf = 0, ns = 0;
    double ref_strip = 0;
    for (size_t k = 0; k < n; k++) {
        const bk_texel *t = &f.texels.receivers[f.texel_of_receiver[k]];
        if (t->object != 0) continue;
        floor_t[k] = 1, nf++;
        ref[k] = lmf_contact_irradiance(t->position[0], t->position[1], 256, 1);
        if (t->position[0] > LMF_SLAB_T && t->position[0] < LMF_SLAB_T + 4 / density && fabsf(t->position[1]) < 0.3f) {
            strip[k] = 1, ns++;
            ref_strip += ref[k];
        }
    }
    ref_strip /= ns;
    printf("contact: %zu receivers, %zu floor texels, strip %zu texels, analytic strip mean %.4f (open floor ~%.3f)\n", n,
           nf, ns, ref_strip, lmf_contact_irradiance(-0.5, 0, 256, 1));
    lbk_sh9_rgb *base = calloc(n, sizeof *base), *out = calloc(n, sizeof *out), *irr = calloc(n, sizeof *irr);
    float *var = calloc(n, sizeof *var);
    static const int budgets[] = {64, 256, 1024};
    for (int bi = 0; bi < 3; bi++) {
        int spp = budgets[bi];
        double rm[32] = {0}, strip_mean[32] = {0}, strip_abs[32] = {0}, tt = 0, td[32] = {0};
        for (int sd = 0; sd < seeds; sd++) {
            tt += bake(&s, &f, spp, 100 + (uint64_t)sd, base, var, irr);
            for (int mi = 0; mi < method_count; mi++) {
                td[mi] += denoise(&s, &f, &methods[mi], base, var, irr, out);
                double num = 0, den = 0, sm = 0;
                for (size_t k = 0; k < n; k++) {
                    if (!floor_t[k]) continue;
                    double y = texel_lum(&f, k, &out[k]);
                    num += (y - ref[k]) * (y - ref[k]);
                    den += ref[k] * ref[k];
                    if (strip[k]) sm += y;
                }
                rm[mi] += num / den;
                sm /= ns;
                strip_mean[mi] += sm;
                strip_abs[mi] += fabs(sm - ref_strip);
            }
        }
        printf("  %5d spp, transport %.3f s CPU per bake (%d seeds)\n", spp, tt / seeds, seeds);
        printf("    %-22s %9s %12s %12s %10s\n", "method", "rel RMSE", "strip bias", "strip |err|", "cost s");
        for (int mi = 0; mi < method_count; mi++)
            printf("    %-22s %8.2f%% %+11.2f%% %11.2f%% %10.4f\n", methods[mi].name, 100 * sqrt(rm[mi] / seeds),
                   100 * (strip_mean[mi] / seeds / ref_strip - 1), 100 * strip_abs[mi] / seeds / ref_strip, td[mi] / seeds);
    }
    free(ref), free(floor_t), free(strip), free(base), free(out), free(var), free(irr);
    lmf_free(&f);
    tsc_free(&s);
}

/* ---- room ------------------------------------------------------------------------------------- */

static void build_room(bk_scene *s)
{
    tsc_init(s);
    uint32_t wall = tsc_material(s, 0.75f, 0.75f, 0.75f, 0, 0, 0);
    uint32_t red = tsc_material(s, 0.7f, 0.15f, 0.1f, 0, 0, 0);
    uint32_t green = tsc_material(s, 0.1f, 0.6f, 0.15f, 0, 0, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {6, 5, 3};
    tsc_box(s, mn, mx, 8, 1, wall);
    float r0[3] = {0.01f, 0.01f, 0.01f}, r1[3] = {0.01f, 4.99f, 0.01f}, r2[3] = {0.01f, 4.99f, 2.99f}, r3[3] = {0.01f, 0.01f, 2.99f};
    tsc_quad(s, r0, r3, r2, r1, 6, red);
    for (int i = 0; i < 6; i++) {
        tsc_object(s, "box", "", "");
        float a[3] = {0.6f + i * 0.9f, 1 + (i % 3) * 1.1f, 0}, b[3] = {a[0] + 0.6f, a[1] + 0.7f, 0.4f + 0.25f * i};
        tsc_box(s, a, b, 3, 0, i % 2 ? green : wall);
    }
    tsc_object(s, "emitter", "", "");
    uint32_t em = tsc_material(s, 0, 0, 0, 20, 18, 15);
    s->materials[em].double_sided = 0;
    float e0[3] = {2.5f, 2, 2.95f}, e1[3] = {2.5f, 3, 2.95f}, e2[3] = {3.5f, 3, 2.95f}, e3[3] = {3.5f, 2, 2.95f};
    tsc_quad(s, e0, e1, e2, e3, 1, em);
    float lp[3] = {5, 4, 2.5f};
    tsc_point_light(s, lp, 60, 50, 40, 0);
    tsc_update_bounds(s);
}

static double rel_rmse(const lmf *f, const lbk_sh9_rgb *a, const float *ref)
{
    double num = 0, den = 0;
    for (size_t k = 0; k < f->count; k++) {
        double y = texel_lum(f, k, &a[k]);
        num += (y - ref[k]) * (y - ref[k]);
        den += (double)ref[k] * ref[k];
    }
    return sqrt(num / den);
}

static void room(int seeds)
{
    bk_scene s;
    build_room(&s);
    lmf f;
    lmf_build(&s, 6, &f);
    size_t n = f.count;
    lbk_sh9_rgb *base = calloc(n, sizeof *base), *out = calloc(n, sizeof *out), *irr = calloc(n, sizeof *irr);
    float *var = calloc(n, sizeof *var), *ref = calloc(n, sizeof *ref);
    double tref = bake(&s, &f, 2 * 16 * 1023, 999, base, var, irr);
    for (size_t k = 0; k < n; k++) ref[k] = texel_lum(&f, k, &irr[k]);
    printf("room: %zu texels; reference 32736 spp (%.1f s CPU): errors below are noise only\n", n, tref);
    static const int budgets[] = {96, 224, 480, 992, 2016};
    double raw_err[5] = {0}, raw_t[5] = {0};
    for (int bi = 0; bi < 5; bi++) {
        int spp = budgets[bi];
        double rm[32] = {0}, tt = 0, td[32] = {0};
        for (int sd = 0; sd < seeds; sd++) {
            tt += bake(&s, &f, spp, 100 + (uint64_t)sd, base, var, irr);
            for (int mi = 0; mi < method_count; mi++) {
                td[mi] += denoise(&s, &f, &methods[mi], base, var, irr, out);
                double e = rel_rmse(&f, out, ref);
                rm[mi] += e * e;
            }
        }
        raw_err[bi] = sqrt(rm[0] / seeds), raw_t[bi] = tt / seeds;
        printf("  %5d spp, transport %.3f s CPU per bake\n", spp, tt / seeds);
        for (int mi = 0; mi < method_count; mi++)
            printf("    %-22s %8.2f%%  cost %.4f s\n", methods[mi].name, 100 * sqrt(rm[mi] / seeds), td[mi] / seeds);
    }
    printf("  raw error vs CPU time:");
    for (int bi = 0; bi < 5; bi++) printf(" %.2f%%@%.2fs", 100 * raw_err[bi], raw_t[bi]);
    printf("\n");
    free(base), free(out), free(var), free(ref), free(irr);
    lmf_free(&f);
    tsc_free(&s);
}

int main(int argc, char **argv)
{
    const char *what = argc > 1 ? argv[1] : "all";
    int seeds = argc > 2 ? atoi(argv[2]) : 2; /* DENOISE.md: contact 8 seeds, room 2 */
    if (seeds < 1) seeds = 1;
    default_methods();
    if (!strcmp(what, "contact") || !strcmp(what, "all")) contact(seeds);
    if (!strcmp(what, "room") || !strcmp(what, "all")) room(seeds);
    return 0;
}
