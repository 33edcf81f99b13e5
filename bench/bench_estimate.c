/* Is the reported error what a user gets? For each scene: two bakes that differ only in the seed
 * (denoiser off, so the transport's estimate is the whole error; the bias is not in it — the
 * Cycles harness measures that), the measured noise per receiver class from their difference,
 * against what each bake's report estimated for that class. Measured error of one bake:
 * √(Σ (x₁ − x₂)²/2 / Σ ((x₁ + x₂)/2)²) over the class's receivers — the same RMS-relative
 * definition as REPT's (spec §7.1) — with x the luminance of a texel's stored irradiance along
 * its normal, or of a probe's SH DC term (fluence ∝ DC). Prints the ratio estimate / measured;
 * the goal is within 2× (0.5–2) for every class.
 * Usage: bench_estimate [scenes-dir]. Wall seconds (the machine is shared). */
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
    lbk_bake_class_errors est;
    double seconds;
} run;

static int bake(const char *path, const float *sky, uint64_t seed, run *out)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.preset = LBK_BAKE_PRESET_FAST;
    d.seed = seed;
    d.threads = 2;
    d.denoise = LBK_BAKE_DENOISE_OFF;
    if (sky) {
        d.sky_override = 1;
        memcpy(d.sky, sky, sizeof d.sky);
    }
    lbk_bake_output *o;
    lbk_result r = lbk_bake_from_file(path, &d, &o);
    if (r) {
        fprintf(stderr, "bench_estimate: %s: %s\n", path, lbk_result_message(r));
        return 1;
    }
    const lbk_bake_report *rep = lbk_bake_output_report(o);
    out->est = rep->errors;
    out->seconds = rep->seconds;
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

static double estimate(const lbk_bake_class_errors *e, int c) { return c == C_TEXEL ? e->texels : c == C_GLG ? e->glg : e->llg; }

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : getenv("LBK_SCENES") ? getenv("LBK_SCENES") : "../shared/scenes";
    static const float white[3] = {1, 1, 1};
    const struct {
        const char *file;
        const float *sky;
    } scenes[] = {
        {"cornell_box/CornellBox-Original.gltf", NULL},
        {"room_with_doors/room.glb", white},
        {"lights_punctual_lamp/LightsPunctualLamp.gltf", NULL},
    };
    printf("%-22s %-11s %9s %9s %9s %7s\n", "scene", "class", "receivers", "estimate", "measured", "ratio");
    int worst_out = 0;
    for (size_t s = 0; s < sizeof scenes / sizeof *scenes; s++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, scenes[s].file);
        FILE *f = fopen(path, "rb");
        if (!f) {
            printf("%-22s SKIPPED (no %s)\n", scenes[s].file, path);
            continue;
        }
        fclose(f);
        run a, b;
        if (bake(path, scenes[s].sky, 1, &a) || bake(path, scenes[s].sky, 2, &b)) return 1;
        for (int c = 0; c < C_COUNT; c++) {
            if (!a.v.n[c]) continue;
            double m = measured(&a, &b, c), e = 0.5 * (estimate(&a.est, c) + estimate(&b.est, c));
            double ratio = m > 0 ? e / m : 0;
            if (!(ratio >= 0.5 && ratio <= 2)) worst_out = 1;
            char name[32];
            snprintf(name, sizeof name, "%.22s", scenes[s].file);
            char *slash = strchr(name, '/');
            if (slash) *slash = 0;
            printf("%-22s %-11s %9zu %8.2f%% %8.2f%% %7.2f\n", name, class_names[c], a.v.n[c], 100 * e, 100 * m, ratio);
        }
        for (int c = 0; c < C_COUNT; c++) free(a.v.x[c]), free(b.v.x[c]);
    }
    printf(worst_out ? "some class is outside 2x of its measured error\n" : "every class within 2x of its measured error\n");
    return 0;
}
