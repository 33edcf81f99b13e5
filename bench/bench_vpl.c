/* Glossy bounce light through VPLs (bake/transport/VPL.md; printed, not asserted): seed 002's
 * Figure 10 on a CPU. A 10 × 10 × 4 m room whose floor is a GGX metal (F0 0.95, α 0.05, 0.1,
 * 0.2, 0.4), grey walls and ceiling, lit by a spot light that reaches the floor only, so every
 * VPL is glossy; the floor's lobe throws a caustic onto the far wall and the ceiling.
 * NVPL photons make the VPLs; receivers are 25 cm texels in 1 × 1 m patches of 4 × 4 (one
 * culling tile each, the analogue of the seed's 16 × 16 pixel tiles) on every surface.
 *
 * Per roughness:
 *   Figure 10: VPLs listed per receiver (its tile's list after culling) and false positives per
 *     receiver (listed but not accepted, ξ ≥ p) for the three bounds of glossy VPLs: (a) the
 *     sphere at the VPL of radius r/α, (b) the sphere around the spheroid, (c) the spheroid; and
 *     the CPU time of one draw (culling + gather with shadow rays).
 *   error: one SLC draw (spheroid) against the brute-force gather (every VPL, every receiver,
 *     shadow rays: the exact answer for these VPLs), relative RMSE; and brute force cut to the
 *     SLC draw's time (a uniform subset of K VPLs, × N/K) at the same time.
 * Then diffuse VPLs (a second spot light onto a grey wall): the sphere at the VPL against the
 * seed's §6 sphere.
 * δ = δ_rel × the receivers' mean irradiance (from the brute-force gather), as SLC.md sets it
 * for punctual lights; δ_rel 0.2 (few accepted VPLs per receiver, the seed's regime) and 0.02. Time is this thread's CPU time (the machine is shared). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench/bench_util.h"
#include "bake/transport/shading.h"
#include "bake/transport/vpl.h"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"

#define NVPL 2048
#define PATCHES 160
#define NRECV (PATCHES * 16)
#define DRAWS 4 /* SLC draws per roughness (the error is their RMS; the counts their mean) */

typedef struct room {
    bk_scene s;
    bk_tracer *t;
    bk_vpl_material mats[2];
    bk_vpl_point pts[NRECV];
    float boxes[NRECV * 6];
} room;

static void build(room *R)
{
    bk_scene *s = &R->s;
    tsc_init(s);
    uint32_t fm = tsc_material(s, 0.95f, 0.95f, 0.95f, 0, 0, 0), wm = tsc_material(s, 0.6f, 0.6f, 0.6f, 0, 0, 0);
    const float X = 10, Y = 10, Z = 4;
    float f0[3] = {0, 0, 0}, f1[3] = {X, 0, 0}, f2[3] = {X, Y, 0}, f3[3] = {0, Y, 0};
    float c0[3] = {0, 0, Z}, c1[3] = {X, 0, Z}, c2[3] = {X, Y, Z}, c3[3] = {0, Y, Z};
    tsc_quad(s, f0, f1, f2, f3, 20, fm);
    tsc_quad(s, c0, c3, c2, c1, 20, wm);
    tsc_quad(s, f0, c0, c1, f1, 20, wm);
    tsc_quad(s, f1, c1, c2, f2, 20, wm);
    tsc_quad(s, f2, c2, c3, f3, 20, wm);
    tsc_quad(s, f3, c3, c0, f0, 20, wm);
    float lp[3] = {1.5f, 5, 3.8f}, ld[3] = {2.5f, 0, -3.8f};
    tsc_spot_light(s, lp, ld, 1000, 0.25f, 0.35f);
    float wp[3] = {5, 5, 3.5f}, wd[3] = {0, 1, -0.25f}; /* light 1: onto the grey wall y = 10 only */
    tsc_spot_light(s, wp, wd, 1000, 0.18f, 0.25f);
    tsc_update_bounds(s);
    if (bk_tracer_create(s, 1, &R->t) != LBK_OK) abort();
    memset(R->mats, 0, sizeof R->mats);
    for (int k = 0; k < 3; k++) R->mats[fm].f0[k] = 0.95f, R->mats[wm].kd[k] = 0.6f;
    /* patches: 1 × 1 m at random places, on each face in proportion to its area */
    bench_rng r = {7};
    const double area[6] = {100, 100, 40, 40, 40, 40};
    for (int k = 0; k < PATCHES; k++) {
        double u = bench_next(&r) * 360, a = 0;
        int f = 0;
        while (f < 5 && u > a + area[f]) a += area[f++];
        double o[3] = {0}, ax[3] = {0}, ay[3] = {0}, n[3] = {0}, p = 0.05 + 8.9 * bench_next(&r), q = 0.05 + 8.9 * bench_next(&r),
               h = 0.05 + 2.9 * bench_next(&r);
        switch (f) {
        case 0: o[0] = p, o[1] = q, o[2] = 0; ax[0] = 1, ay[1] = 1, n[2] = 1; break;
        case 1: o[0] = p, o[1] = q, o[2] = Z; ax[0] = 1, ay[1] = 1, n[2] = -1; break;
        case 2: o[0] = p, o[1] = 0, o[2] = h; ax[0] = 1, ay[2] = 1, n[1] = 1; break;
        case 3: o[0] = X, o[1] = p, o[2] = h; ax[1] = 1, ay[2] = 1, n[0] = -1; break;
        case 4: o[0] = p, o[1] = Y, o[2] = h; ax[0] = 1, ay[2] = 1, n[1] = -1; break;
        default: o[0] = 0, o[1] = p, o[2] = h; ax[1] = 1, ay[2] = 1, n[0] = 1; break;
        }
        for (int j = 0; j < 16; j++) {
            bk_vpl_point *pt = &R->pts[16 * k + j];
            for (int c = 0; c < 3; c++) {
                pt->p[c] = o[c] + (0.25 * (j % 4) + 0.125) * ax[c] + (0.25 * (j / 4) + 0.125) * ay[c];
                pt->n[c] = n[c];
            }
            float pf[3] = {(float)pt->p[0], (float)pt->p[1], (float)pt->p[2]}, nf[3] = {(float)n[0], (float)n[1], (float)n[2]};
            bk_offset_ray_origin_scaled(pf, nf, 10, pt->org);
            for (int c = 0; c < 3; c++) R->boxes[6 * (16 * k + j) + c] = R->boxes[6 * (16 * k + j) + 3 + c] = pf[c];
        }
    }
}

static double lum3(const double *v) { return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]; }

static double rel_rmse(const double *x, const double *ref)
{
    double num = 0, den = 0;
    for (int i = 0; i < NRECV; i++) {
        double d = lum3(&x[3 * i]) - lum3(&ref[3 * i]);
        num += d * d;
        den += lum3(&ref[3 * i]) * lum3(&ref[3 * i]);
    }
    return sqrt(num / den);
}

typedef struct row { double listed, fp, seconds, err; } row;

/* DRAWS draws with the given bound: mean counts per receiver, mean time, RMS error. */
static row slc_rows(const room *R, const bk_vpl *v, size_t nv, const bk_slc *tiles, double delta, int bound,
                    const double *bf, double *irr)
{
    row out = {0, 0, 0, 0};
    double *xi = malloc(nv * sizeof *xi);
    for (int k = 0; k < DRAWS; k++) {
        bench_rng r = {1000 + (uint64_t)k};
        for (size_t i = 0; i < nv; i++) xi[i] = bench_next(&r);
        double t0 = bench_thread_cpu();
        bk_vpl_draw *d = NULL;
        bk_vpl_stats st;
        if (bk_vpl_draw_create(v, nv, xi, delta, bound, tiles, 1, &d) != LBK_OK ||
            bk_vpl_gather(v, nv, d, R->t, R->pts, NRECV, 1, irr, &st) != LBK_OK)
            abort();
        out.seconds += (bench_thread_cpu() - t0) / DRAWS;
        bk_vpl_draw_destroy(d);
        out.listed += (double)st.listed / NRECV / DRAWS;
        out.fp += (double)(st.listed - st.accepted) / NRECV / DRAWS;
        double e = rel_rmse(irr, bf);
        out.err += e * e / DRAWS;
    }
    out.err = sqrt(out.err);
    free(xi);
    return out;
}

/* Brute force over a uniform subset of K VPLs (the same for every receiver), weighted N/K. */
static double subset_err(const room *R, const bk_vpl *v, size_t nv, size_t K, const double *bf, double *irr)
{
    double e2 = 0;
    bk_vpl *sub = malloc(K * sizeof *sub);
    for (int k = 0; k < DRAWS; k++) {
        bench_rng r = {77 + (uint64_t)k};
        for (size_t i = 0; i < K; i++) {
            sub[i] = v[(size_t)(bench_next(&r) * nv) % nv];
            for (int c = 0; c < 3; c++) sub[i].flux[c] *= (double)nv / K;
        }
        if (bk_vpl_gather(sub, K, NULL, R->t, R->pts, NRECV, 1, irr, NULL) != LBK_OK) abort();
        double e = rel_rmse(irr, bf);
        e2 += e * e / DRAWS;
    }
    free(sub);
    return sqrt(e2);
}

/* Diffuse VPLs (light 1 lights a grey wall): the sphere at the VPL of radius R = √(Φk/(πδξ))
 * (the intensity's maximum) against the seed's §6 sphere. */
static void diffuse(room *R, const bk_slc *tiles, double delta_rel, double *bf, double *irr)
{
    bk_vpl_shoot_desc sd = {.scene = &R->s, .tracer = R->t, .materials = R->mats, .seed = 1, .photons = NVPL, .threads = 1, .key = 1};
    bk_vpl *v = NULL;
    size_t nv = 0;
    if (bk_vpl_shoot(&sd, &R->s.lights[1], &v, &nv) != LBK_OK) abort();
    size_t glossy = 0;
    for (size_t i = 0; i < nv; i++) glossy += v[i].kind == BK_VPL_GLOSSY;
    double t0 = bench_thread_cpu();
    if (bk_vpl_gather(v, nv, NULL, R->t, R->pts, NRECV, 1, bf, NULL) != LBK_OK) abort();
    const double bft = bench_thread_cpu() - t0;
    double mean = 0;
    for (int i = 0; i < NRECV; i++) mean += lum3(&bf[3 * i]) / NRECV;
    row a = slc_rows(R, v, nv, tiles, delta_rel * mean, BK_VPL_BOUND_SPHERE_AT_VPL, bf, irr);
    row c = slc_rows(R, v, nv, tiles, delta_rel * mean, BK_VPL_BOUND_ELLIPSOID, bf, irr);
    size_t K = (size_t)(nv * c.seconds / bft + 0.5);
    if (K < 1) K = 1;
    const double sub = subset_err(R, v, nv, K, bf, irr);
    printf("\n  diffuse VPLs (a second spot light onto a grey wall: %zu VPLs, %zu glossy), delta %.3g x mean:\n", nv, glossy,
           delta_rel);
    printf("  %-32s %14s %22s %12s %12s\n", "bound", "VPLs/receiver", "false positives/rcv", "cpu s/draw", "rel RMSE");
    printf("  %-32s %14.1f %22.1f %12.3f %11.2f %%\n", "sphere at the VPL, radius R", a.listed, a.fp, a.seconds, 100 * a.err);
    printf("  %-32s %14.1f %22.1f %12.3f %11.2f %%\n", "seed 6 sphere", c.listed, c.fp, c.seconds, 100 * c.err);
    printf("  false positives cut by the seed's sphere: %.1f %%; brute force %.3f s, at SLC time (K = %zu) %.2f %% (%.2fx SLC's)\n\n",
           100 * (1 - c.fp / a.fp), bft, K, 100 * sub, sub / c.err);
    free(v);
}

static void run(room *R, const bk_slc *tiles, double delta_rel, double *bf, double *irr)
{
    const double alphas[4] = {0.4, 0.2, 0.1, 0.05};
    const char *names[3] = {"(a) sphere at the VPL", "(b) sphere around it", "(c) spheroid"};
    const int bounds[3] = {BK_VPL_BOUND_SPHERE_AT_VPL, BK_VPL_BOUND_SPHERE_AROUND, BK_VPL_BOUND_ELLIPSOID};
    row fig[4][3];
    double bft[4], bferr_sub[4], slc_err[4], slc_t[4];
    size_t subk[4];
    printf("glossy VPLs with stochastic light culling (seed 002 Fig. 10), one thread: %d photons from a spot light onto a "
           "GGX metal floor, %d receivers in tiles of 16, %zu triangles, delta %.3g x mean irradiance, %d draws\n",
           NVPL, NRECV, R->s.tri_count, delta_rel, DRAWS);
    for (int a = 0; a < 4; a++) {
        R->mats[0].alpha = (float)alphas[a];
        bk_vpl_shoot_desc sd = {.scene = &R->s, .tracer = R->t, .materials = R->mats, .seed = 1, .photons = NVPL, .threads = 1, .key = 0};
        bk_vpl *v = NULL;
        size_t nv = 0;
        if (bk_vpl_shoot(&sd, &R->s.lights[0], &v, &nv) != LBK_OK) abort();
        double t0 = bench_thread_cpu();
        if (bk_vpl_gather(v, nv, NULL, R->t, R->pts, NRECV, 1, bf, NULL) != LBK_OK) abort();
        bft[a] = bench_thread_cpu() - t0;
        double mean = 0;
        for (int i = 0; i < NRECV; i++) mean += lum3(&bf[3 * i]) / NRECV;
        for (int b = 0; b < 3; b++) fig[a][b] = slc_rows(R, v, nv, tiles, delta_rel * mean, bounds[b], bf, irr);
        slc_err[a] = fig[a][2].err;
        slc_t[a] = fig[a][2].seconds;
        subk[a] = (size_t)(nv * slc_t[a] / bft[a] + 0.5);
        if (subk[a] < 1) subk[a] = 1;
        bferr_sub[a] = subset_err(R, v, nv, subk[a], bf, irr);
        free(v);
    }
    printf("\n  %-9s %-22s %14s %22s %12s\n", "roughness", "bound", "VPLs/receiver", "false positives/rcv", "cpu s/draw");
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 3; b++)
            printf("  %-9.2f %-22s %14.1f %22.1f %12.3f\n", alphas[a], names[b], fig[a][b].listed, fig[a][b].fp,
                   fig[a][b].seconds);
    printf("\n  false positives cut by the spheroid: ");
    for (int a = 0; a < 4; a++)
        printf("%s%.1f %% vs (a), %.1f %% vs (b) at %.2f", a ? "; " : "", 100 * (1 - fig[a][2].fp / fig[a][0].fp),
               100 * (1 - fig[a][2].fp / fig[a][1].fp), alphas[a]);
    printf("\n\n  %-9s %12s %12s %12s %24s %10s\n", "roughness", "brute cpu s", "SLC cpu s", "SLC rel RMSE",
           "brute at SLC time (K)", "vs SLC");
    for (int a = 0; a < 4; a++)
        printf("  %-9.2f %12.3f %12.3f %11.2f %% %15.2f %% (%4zu) %9.2fx\n", alphas[a], bft[a], slc_t[a], 100 * slc_err[a],
               100 * bferr_sub[a], subk[a], bferr_sub[a] / slc_err[a]);
    printf("  (brute force: every VPL with a shadow ray at every receiver, the exact gather of these VPLs; at SLC time:\n"
           "   a uniform subset of K VPLs weighted N/K, K = N x SLC time / brute time)\n");
    diffuse(R, tiles, delta_rel, bf, irr);
}

int main(void)
{
    room *R = calloc(1, sizeof *R);
    build(R);
    bk_slc *tiles = NULL;
    if (bk_slc_create(NULL, 0, R->boxes, NRECV, &tiles) != LBK_OK) abort();
    double *bf = malloc(3 * NRECV * sizeof *bf), *irr = malloc(3 * NRECV * sizeof *irr);
    run(R, tiles, 0.2, bf, irr);
    run(R, tiles, 0.02, bf, irr);
    bk_slc_destroy(tiles);
    bk_tracer_destroy(R->t);
    tsc_free(&R->s);
    free(bf);
    free(irr);
    free(R);
    return 0;
}
