/* Is the reported error what a user gets? For each scene: two bakes that differ only in the seed
 * (denoiser off, so the transport's estimate is the whole error; the bias is not in it — the
 * Cycles harness measures that), the measured noise per receiver class from their difference,
 * against what each bake's report estimated for that class. Measured error of one bake:
 * √(Σ (x₁ − x₂)²/2 / Σ ((x₁ + x₂)/2)²) over the class's receivers — the same RMS-relative
 * definition as REPT's (spec §7.1) — with x the luminance of a texel's stored irradiance along
 * its normal, or of a probe's SH DC term (fluence ∝ DC). Prints the ratio estimate / measured;
 * the goal is within 2× (0.5–2) for every class.
 * Then the same for denoised bakes (denoised_rows): the denoised estimate against the error
 * measured against a long undenoised reference, which holds the denoiser's bias.
 * Usage: bench_estimate [scenes-dir [scene-name-part]]. Wall seconds (the machine is shared). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/bake.h"
#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/pixel.h"

enum { C_TEXEL, C_GLG, C_LLG, C_COUNT };
static const char *const class_names[C_COUNT] = {"texels", "GLG probes", "LLG probes"};

typedef struct values {
    double *x[C_COUNT];
    size_t n[C_COUNT];
} values;

static double lum(const float c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

static void push(values *v, int c, double x)
{
    v->x[c] = realloc(v->x[c], (v->n[c] + 1) * sizeof *v->x[c]);
    if (!v->x[c]) abort();
    v->x[c][v->n[c]++] = x;
}

static void read_lmap(lbk_reader *r, values *v)
{
    const void *d;
    size_t n;
    lbk_lmap_view lv;
    if (lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &d, &n) || lbk_lmap_open(d, n, &lv)) return;
    for (uint64_t t = 0; t < lv.texel_count; t++) {
        lbk_ahd_texel tx;
        float ez[3];
        if (lbk_lmap_texel_get(&lv, t, &tx, NULL)) continue;
        lbk_r11g11b10f_unpack(tx.irradiance_z, ez);
        push(v, C_TEXEL, lum(ez) * lv.scale);
    }
}

static void read_probes(lbk_reader *r, values *v)
{
    const void *d;
    size_t n;
    lbk_glg_view gv;
    if (!lbk_reader_section_by_type(r, LBK_SECTION_GLG, &d, &n) && !lbk_glg_open(d, n, &gv))
        for (uint32_t i = 0; i < gv.probe_count; i++) {
            lbk_sh9_rgb sh;
            if (lbk_glg_probe_get(&gv, i, NULL, &sh)) continue;
            const float dc[3] = {sh.c[0][0], sh.c[1][0], sh.c[2][0]};
            push(v, C_GLG, lum(dc));
        }
    lbk_llg_view lv;
    if (lbk_reader_section_by_type(r, LBK_SECTION_LLG, &d, &n) || lbk_llg_open(d, n, &lv)) return;
    for (uint32_t g = 0; g < lv.grid_count; g++) {
        lbk_llg_grid grid;
        if (lbk_llg_grid_get(&lv, g, &grid)) continue;
        for (uint32_t k = 0; k < grid.dims[2]; k++)
            for (uint32_t j = 0; j < grid.dims[1]; j++)
                for (uint32_t i = 0; i < grid.dims[0]; i++) {
                    float p[3];
                    lbk_sh9_rgb sh;
                    lbk_llg_probe_position(&grid, i, j, k, p);
                    if (lbk_llg_sample(&lv, g, p, &sh)) continue;
                    const float dc[3] = {sh.c[0][0], sh.c[1][0], sh.c[2][0]};
                    push(v, C_LLG, lum(dc));
                }
    }
}

typedef struct run {
    values v;
    lbk_bake_class_errors est;      /* the report's estimate (the denoised one for denoised bakes) */
    double seconds, samples;
} run;

typedef struct bake_how {
    const float *sky;
    uint64_t seed;
    int denoise;                    /* 0 off, 1 auto */
    int fixed_samples;              /* > 0: no target, this many samples (the reference) */
} bake_how;

static int bake(const char *path, const bake_how *h, run *out)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.preset = LBK_BAKE_PRESET_FAST;
    d.seed = h->seed;
    d.threads = 2;
    d.denoise = h->denoise ? LBK_BAKE_DENOISE_AUTO : LBK_BAKE_DENOISE_OFF;
    if (h->fixed_samples > 0) d.target_error = -1, d.max_samples = h->fixed_samples;
    if (h->sky) {
        d.sky_override = 1;
        memcpy(d.sky, h->sky, sizeof d.sky);
    }
    lbk_bake_output *o;
    lbk_result r = lbk_bake_from_file(path, &d, &o);
    if (r) {
        fprintf(stderr, "bench_estimate: %s: %s\n", path, lbk_result_message(r));
        return 1;
    }
    const lbk_bake_report *rep = lbk_bake_output_report(o);
    out->est = h->denoise ? rep->denoised.errors : rep->errors;
    out->seconds = rep->seconds;
    out->samples = rep->pass_count ? rep->passes[rep->pass_count - 1].samples_per_receiver : 0;
    void *bytes;
    size_t size;
    lbk_reader *rd;
    if (lbk_bake_output_container(o, &bytes, &size) || lbk_reader_open_memory(bytes, size, NULL, &rd)) return 1;
    memset(&out->v, 0, sizeof out->v);
    read_lmap(rd, &out->v);
    read_probes(rd, &out->v);
    lbk_reader_close(rd);
    lbk_free(NULL, bytes);
    lbk_bake_output_free(o);
    return 0;
}

static void run_free(run *r)
{
    for (int c = 0; c < C_COUNT; c++) free(r->v.x[c]);
}

/* The noise of one bake from two seeds: √(Σ (x₁ − x₂)²/2 / Σ ((x₁ + x₂)/2)²). */
static double measured(const run *a, const run *b, int c)
{
    if (a->v.n[c] != b->v.n[c] || !a->v.n[c]) return 0;
    double num = 0, den = 0;
    for (size_t i = 0; i < a->v.n[c]; i++) {
        double x1 = a->v.x[c][i], x2 = b->v.x[c][i];
        num += 0.5 * (x1 - x2) * (x1 - x2);
        den += 0.25 * (x1 + x2) * (x1 + x2);
    }
    return den > 0 ? sqrt(num / den) : 0;
}

/* The error of bake a against the long reference ref, its own noise (ref_est, relative) taken
 * off: √(Σ (x − r)² / Σ r² − ref_est²), 0 when not resolved. */
static double against(const run *a, const run *ref, int c, double ref_est)
{
    if (a->v.n[c] != ref->v.n[c] || !a->v.n[c]) return 0;
    double num = 0, den = 0;
    for (size_t i = 0; i < a->v.n[c]; i++) {
        double x = a->v.x[c][i], r = ref->v.x[c][i];
        num += (x - r) * (x - r);
        den += r * r;
    }
    double e2 = den > 0 ? num / den - ref_est * ref_est : 0;
    return e2 > 0 ? sqrt(e2) : 0;
}

static double estimate(const lbk_bake_class_errors *e, int c) { return c == C_TEXEL ? e->texels : c == C_GLG ? e->glg : e->llg; }

static int within(double ratio) { return ratio >= 0.5 && ratio <= 2; }

static void short_name(const char *file, char name[32])
{
    snprintf(name, 32, "%.22s", file);
    char *slash = strchr(name, '/');
    if (slash) *slash = 0;
}

/* Denoised bakes: the report's estimate of the denoised result (the halves through the
 * filter) against their noise between seeds and against a long undenoised reference of the
 * same scene and texel layout (8x the samples, its own estimated noise taken off): the error
 * the user gets, the denoiser's bias included. Texels and GLG probes (LLG probes are not
 * filtered). */
static int denoised_rows(const char *name, const char *path, const float *sky, const run *plain)
{
    run da, db, ref;
    bake_how h1 = {sky, 1, 1, 0}, h2 = {sky, 2, 1, 0}, hr = {sky, 3, 0, (int)(8 * plain->samples)};
    if (bake(path, &h1, &da) || bake(path, &h2, &db) || bake(path, &hr, &ref)) return -1;
    int out = 0;
    for (int c = 0; c < C_LLG; c++) {
        if (!da.v.n[c]) continue;
        const double e = 0.5 * (estimate(&da.est, c) + estimate(&db.est, c)), noise = measured(&da, &db, c);
        const double err = 0.5 * (against(&da, &ref, c, estimate(&ref.est, c)) + against(&db, &ref, c, estimate(&ref.est, c)));
        /* a reference noisier than the error it measures does not resolve it */
        const int resolved = err > estimate(&ref.est, c);
        const double ratio = err > 0 ? e / err : 0;
        if (resolved && !within(ratio)) out = 1;
        char rs[16];
        snprintf(rs, sizeof rs, resolved ? "%7.2f" : "    n/r", ratio);
        printf("%-22s %-11s %9zu %8.2f%% %8.2f%% %s   (denoised; noise between seeds %.2f%%, reference %d spp, "
               "its noise %.2f%%)\n",
               name, class_names[c], da.v.n[c], 100 * e, 100 * err, rs, 100 * noise, (int)ref.samples,
               100 * estimate(&ref.est, c));
    }
    run_free(&da), run_free(&db), run_free(&ref);
    return out;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : getenv("LBK_SCENES") ? getenv("LBK_SCENES") : "scenes";
    static const float white[3] = {1, 1, 1};
    /* the furnished room (many small authored charts) is written by make bench-cycles
     * (bench/cycles/make_furnished_room.py, Blender): measured where that has run */
    const char *furnished = getenv("LBK_FURNISHED_ROOM") ? getenv("LBK_FURNISHED_ROOM")
                                                         : "build/bench-cycles/furnished_room.gltf";
    const struct {
        const char *file;
        const float *sky;
        const char *path; /* NULL: file in the scenes folder */
    } scenes[] = {
        {"cornell_box/CornellBox-Original.gltf", NULL, NULL},
        {"room_with_doors/room.glb", white, NULL},
        {"lights_punctual_lamp/LightsPunctualLamp.gltf", NULL, NULL},
        {"furnished_room.gltf", white, furnished},
    };
    printf("%-22s %-11s %9s %9s %9s %7s\n", "scene", "class", "receivers", "estimate", "measured", "ratio");
    int worst_out = 0;
    const char *only = argc > 2 ? argv[2] : NULL; /* a part of the scene's file name */
    for (size_t s = 0; s < sizeof scenes / sizeof *scenes; s++) {
        if (only && !strstr(scenes[s].file, only)) continue;
        char path[1024], name[32];
        if (scenes[s].path) snprintf(path, sizeof path, "%s", scenes[s].path);
        else snprintf(path, sizeof path, "%s/%s", dir, scenes[s].file);
        short_name(scenes[s].file, name);
        FILE *f = fopen(path, "rb");
        if (!f) {
            printf("%-22s SKIPPED (no %s%s)\n", scenes[s].file, path,
                   scenes[s].path ? ": make bench-cycles writes it" : "");
            continue;
        }
        fclose(f);
        run a, b;
        bake_how h1 = {scenes[s].sky, 1, 0, 0}, h2 = {scenes[s].sky, 2, 0, 0};
        if (bake(path, &h1, &a) || bake(path, &h2, &b)) return 1;
        for (int c = 0; c < C_COUNT; c++) {
            if (!a.v.n[c]) continue;
            double m = measured(&a, &b, c), e = 0.5 * (estimate(&a.est, c) + estimate(&b.est, c));
            double ratio = m > 0 ? e / m : 0;
            if (!within(ratio)) worst_out = 1;
            printf("%-22s %-11s %9zu %8.2f%% %8.2f%% %7.2f\n", name, class_names[c], a.v.n[c], 100 * e, 100 * m, ratio);
        }
        int d = denoised_rows(name, path, scenes[s].sky, &a);
        if (d < 0) return 1;
        worst_out |= d;
        run_free(&a), run_free(&b);
    }
    printf(worst_out ? "some class is outside 2x of its measured error\n" : "every class within 2x of its measured error\n");
    return 0;
}
