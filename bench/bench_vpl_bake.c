/* Glossy VPLs in the whole transport (bake/transport/VPL.md "In the transport"; printed, not
 * asserted): the glossy-bounce metal room (bench/cycles/make_metal_room.py: 6 × 5 × 3 m, metal floor of
 * base 0.9 and glTF roughness r, plaster walls 0.75, ceiling 0.8, a grey box 0.6, one 300 cd spot
 * light aimed down and across the room) at r = 0.05, 0.1, 0.2, 0.4. Receivers: 25 cm texels on
 * the floor, the ceiling and the four walls (2,016, in 1 × 1 m patches of 4 × 4: one culling tile
 * each), as points with the surface's normal.
 *
 * Per roughness, the same transport (2 threads, fixed passes, 4,096-cell cache) with glossy VPLs
 * on and off; the error is the relative RMSE of the irradiance (luminance) over the receivers
 * (and per surface) against a long reference run with VPLs on (2 × 16 · (2^7 − 1) = 4,064
 * samples, another seed; both estimators are unbiased: tests/bake/test_glossy_vpl.c), from which
 * the reference's own estimated noise is removed in quadrature. "at equal CPU" scales an error
 * to the VPL run's CPU time by √(t/T) (the passes' noise falls as 1/√samples); VPLs off also
 * runs at 1 and 2 more passes (≈ 2× and 4× its time) as measured, not scaled, points. CPU is the process's
 * (both threads). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/bench_util.h"
#include "bake/transport/shading.h"
#include "bake/transport/transport.h"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"

#define X 6.0f
#define Y 5.0f
#define Z 3.0f
#define MAXR 2016
enum { G_FLOOR, G_CEIL, G_WALLS, G_N };

typedef struct room {
    bk_scene s;
    bk_tracer *t;
    bk_receiver r[MAXR];
    int group[MAXR];
    size_t n;
} room;

/* A face's texels in 1 m patches of 4 × 4: origin o, unit axes ax, ay, sizes in metres. */
static void face(room *R, const float o[3], const float ax[3], const float ay[3], int w, int h, const float n[3], int g)
{
    for (int pj = 0; pj < h; pj++)
        for (int pi = 0; pi < w; pi++)
            for (int j = 0; j < 16; j++) {
                bk_receiver *r = &R->r[R->n];
                memset(r, 0, sizeof *r);
                const double u = pi + 0.25 * (j % 4) + 0.125, v = pj + 0.25 * (j / 4) + 0.125;
                for (int c = 0; c < 3; c++) {
                    r->position[c] = (float)(o[c] + u * ax[c] + v * ay[c]);
                    r->normal[c] = n[c];
                }
                R->group[R->n++] = g;
            }
}

static void build(room *R, float rough)
{
    bk_scene *s = &R->s;
    tsc_init(s);
    uint32_t metal = tsc_material(s, 0.9f, 0.9f, 0.9f, 0, 0, 0), plaster = tsc_material(s, 0.75f, 0.75f, 0.75f, 0, 0, 0),
             ceil = tsc_material(s, 0.8f, 0.8f, 0.8f, 0, 0, 0), grey = tsc_material(s, 0.6f, 0.6f, 0.6f, 0, 0, 0);
    s->materials[metal].metallic = 1;
    s->materials[metal].roughness = rough;
    float f0[3] = {0, 0, 0}, f1[3] = {X, 0, 0}, f2[3] = {X, Y, 0}, f3[3] = {0, Y, 0};
    float c0[3] = {0, 0, Z}, c1[3] = {X, 0, Z}, c2[3] = {X, Y, Z}, c3[3] = {0, Y, Z};
    tsc_quad(s, f0, f1, f2, f3, 12, metal); /* faces +z */
    tsc_quad(s, c0, c3, c2, c1, 12, ceil);
    tsc_quad(s, f0, c0, c1, f1, 12, plaster); /* y = 0, faces +y */
    tsc_quad(s, f1, c1, c2, f2, 12, plaster); /* x = X, faces −x */
    tsc_quad(s, f2, c2, c3, f3, 12, plaster); /* y = Y */
    tsc_quad(s, f3, c3, c0, f0, 12, plaster); /* x = 0 */
    float bmn[3] = {3.6f, 3.2f, 0}, bmx[3] = {4.4f, 4.0f, 0.8f};
    tsc_box(s, bmn, bmx, 2, 0, grey);
    float lp[3] = {1.0f, 2.5f, 2.7f}, ld[3] = {1.6f, 0, -2.7f};
    tsc_spot_light(s, lp, ld, 300, 0.3f, 0.5f);
    tsc_update_bounds(s);
    if (bk_tracer_create(s, 1, &R->t) != LBK_OK) abort();
    R->n = 0;
    const float ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    const float nz[3] = {0, 0, 1}, nzm[3] = {0, 0, -1}, ny[3] = {0, 1, 0}, nym[3] = {0, -1, 0}, nx[3] = {1, 0, 0},
                nxm[3] = {-1, 0, 0};
    face(R, (float[3]){0, 0, 1e-3f}, ex, ey, 6, 5, nz, G_FLOOR);
    face(R, (float[3]){0, 0, Z - 1e-3f}, ex, ey, 6, 5, nzm, G_CEIL);
    face(R, (float[3]){0, 1e-3f, 0}, ex, ez, 6, 3, ny, G_WALLS);
    face(R, (float[3]){0, Y - 1e-3f, 0}, ex, ez, 6, 3, nym, G_WALLS);
    face(R, (float[3]){1e-3f, 0, 0}, ey, ez, 5, 3, nx, G_WALLS);
    face(R, (float[3]){X - 1e-3f, 0, 0}, ey, ez, 5, 3, nxm, G_WALLS);
}

typedef struct result {
    double irr[MAXR], cpu, est;
    bk_transport_stats st;
} result;

static void bake(const room *R, int vpl, int passes, uint64_t seed, result *o)
{
    bk_transport_options opt = tsc_fixed_passes(passes, seed);
    opt.max_cells = 4096;
    opt.glossy_vpl = vpl;
    const char *ph = getenv("BENCH_VPL_PHOTONS"), *de = getenv("BENCH_VPL_DELTA");
    if (ph) opt.glossy_vpl_photons = (size_t)atol(ph);
    if (de) opt.glossy_vpl_delta = atof(de);
    static float irr[3 * MAXR];
    static lbk_sh9_rgb rad[MAXR];
    bk_transport_output out = {rad, NULL, irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    const double t0 = bench_process_cpu();
    if (bk_transport_run(&R->s, R->t, R->r, R->n, &opt, &out, &o->st) != LBK_OK) abort();
    o->cpu = bench_process_cpu() - t0;
    o->est = o->st.est_rel_rmse;
    for (size_t i = 0; i < R->n; i++) o->irr[i] = 0.2126 * irr[3 * i] + 0.7152 * irr[3 * i + 1] + 0.0722 * irr[3 * i + 2];
}

/* Relative RMSE against the reference over group g (G_N: all), its noise (est) removed. */
static double err_of(const room *R, const result *x, const result *ref, int g)
{
    double num = 0, den = 0;
    for (size_t i = 0; i < R->n; i++) {
        if (g < G_N && R->group[i] != g) continue;
        const double d = x->irr[i] - ref->irr[i];
        num += d * d;
        den += ref->irr[i] * ref->irr[i];
    }
    const double e2 = num / den - (g == G_N ? ref->est * ref->est : 0);
    return sqrt(e2 > 0 ? e2 : 0);
}

int main(void)
{
    const float rough[4] = {0.05f, 0.1f, 0.2f, 0.4f};
    const int P = 4;
    static room R;
    static result ref, on, off, off1, off2;
    printf("bench_vpl_bake: metal room, 2016 texel receivers, 2 threads, fixed passes; error = rel. RMSE\n"
           "of the irradiance against a VPL-on reference of 4064 samples (its own estimated noise removed over all)\n");
    printf("| roughness | run | samples | CPU s | VPLs | est. error | error all | floor | ceiling | walls | all at VPL-on's CPU |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < 4; k++) {
        memset(&R, 0, sizeof R);
        build(&R, rough[k]);
        bake(&R, 1, 7, 1000, &ref);
        bake(&R, 1, P, 1, &on);
        bake(&R, -1, P, 1, &off);
        bake(&R, -1, P + 1, 1, &off1);
        bake(&R, -1, P + 2, 1, &off2);
        const result *rows[5] = {&on, &off, &off1, &off2, &ref};
        const char *name[5] = {"VPLs on", "VPLs off", "VPLs off", "VPLs off", "reference (on)"};
        const int passes[5] = {P, P, P + 1, P + 2, 7};
        for (int q = 0; q < 5; q++) {
            const result *x = rows[q];
            printf("| %.2f | %s | %d | %.2f | %llu | %.2f %% |", rough[k], name[q], 2 * 16 * ((1 << passes[q]) - 1), x->cpu,
                   (unsigned long long)x->st.vpl_made, 100 * x->est);
            if (q == 4) {
                printf(" — | — | — | — | — |\n");
                continue;
            }
            for (int g = G_N; g >= 0; g--) /* all, then floor, ceiling, walls */
                printf(" %.2f %% |", 100 * err_of(&R, x, &ref, g == G_N ? G_N : G_N - 1 - g));
            printf(" %.2f %% |\n", 100 * err_of(&R, x, &ref, G_N) * sqrt(x->cpu / on.cpu));
        }
        printf("| %.2f | share of the light's flux in sharp glossy VPLs (auto's measure) %.1f %%, auto %s | | | | | | | | | |\n",
               rough[k], 100 * ref.st.vpl_share, ref.st.vpl_share >= BK_VPL_AUTO_SHARE ? "on" : "off");
        fflush(stdout);
        bk_tracer_destroy(R.t);
        tsc_free(&R.s);
    }
    return 0;
}
