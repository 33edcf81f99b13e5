/* Many-light direct lighting (bake/transport/SLC.md; printed, not asserted): a generated street
 * of lamps (one point light every 4 m, 3 m up, intensities over two decades, pillars and low
 * walls casting shadows) with 1,000 and 10,000 lights; 4,096 floor texels in 4 × 4 patches of
 * 25 cm texels (a patch is one culling tile; patches in Z-order, as a lightmap's charts keep
 * texels together). Per receiver, the luminance of the irradiance from:
 *   brute force  every light with a shadow ray (exact: the reference);
 *   uniform      K lights drawn uniformly (brute force cut to a time budget), × N/K;
 *   power        K lights drawn in proportion to their intensity (power), each / (K·P);
 *   SLC          one stochastic-light-culling draw (bk_slc, the transport's code) at δ
 *                relative to the mean irradiance at 256 receivers, as the transport uses it.
 * Time is this thread's CPU time (the machine is shared). Errors are the relative RMSE of the
 * transport's estimate (RMSE over the receivers / RMS of the reference). "at SLC time" scales
 * each error to the SLC run's time by √(t/T) (Monte Carlo error ∝ 1/√time); the last column is
 * that error over SLC's. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench/bench_util.h"
#include "bake/transport/shading.h"
#include "bake/transport/slc.h"
#include "bake/transport/transport.h"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"

#define PATCHES 256
#define NRECV (PATCHES * 16)

typedef struct level {
    bk_scene s;
    bk_tracer *t;
    double size;
    double pts[NRECV][3];
    float o[NRECV][3];
} level;

/* nx × ny lamps, 4 m apart; a 1 × 1 × 5 m pillar in every other 8 m cell, a 1.2 m wall
 * along every fourth row. */
static void build(level *L, int nx, int ny)
{
    bk_scene *s = &L->s;
    tsc_init(s);
    const double sx = 4.0 * nx, sy = 4.0 * ny, size = sx > sy ? sx : sy;
    L->size = size;
    uint32_t m = tsc_material(s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float p0[3] = {0, 0, 0}, p1[3] = {(float)sx, 0, 0}, p2[3] = {(float)sx, (float)sy, 0}, p3[3] = {0, (float)sy, 0};
    tsc_quad(s, p0, p1, p2, p3, 4, m);
    for (int y = 0; y < ny / 2; y++)
        for (int x = 0; x < nx / 2; x++) {
            if ((x + y) % 2) continue;
            float mn[3] = {8.0f * x + 5, 8.0f * y + 5, 0}, mx[3] = {mn[0] + 1, mn[1] + 1, 5};
            tsc_box(s, mn, mx, 1, 0, m);
        }
    for (int y = 0; y < ny / 4; y++) {
        float mn[3] = {1, 16.0f * y + 10, 0}, mx[3] = {(float)sx * 0.6f, 16.0f * y + 10.3f, 1.2f};
        tsc_box(s, mn, mx, 1, 0, m);
    }
    bench_rng r = {42};
    for (int y = 0; y < ny; y++)
        for (int x = 0; x < nx; x++) {
            float pos[3] = {4.0f * x + 2, 4.0f * y + 2, 3};
            float I = (float)(10 * pow(10.0, 2 * bench_next(&r)));
            tsc_point_light(s, pos, I, 0.9f * I, 0.7f * I, 0);
        }
    tsc_update_bounds(s);
    if (bk_tracer_create(s, 1, &L->t) != LBK_OK) abort();
    /* patches on a jittered 16 × 16 grid, in Z-order; texels 25 cm, normal up */
    const double cx_cell = sx / 16, cy_cell = sy / 16;
    for (int k = 0; k < PATCHES; k++) {
        int px = 0, py = 0;
        for (int b = 0; b < 4; b++) {
            px |= ((k >> (2 * b)) & 1) << b;
            py |= ((k >> (2 * b + 1)) & 1) << b;
        }
        double cx = (px + 0.1 + 0.8 * bench_next(&r)) * cx_cell - 0.5, cy = (py + 0.1 + 0.8 * bench_next(&r)) * cy_cell - 0.5;
        for (int j = 0; j < 16; j++) {
            double *p = L->pts[16 * k + j];
            p[0] = cx + 0.25 * (j % 4) + 0.125;
            p[1] = cy + 0.25 * (j / 4) + 0.125;
            p[2] = 0;
            float pf[3] = {(float)p[0], (float)p[1], 0}, nf[3] = {0, 0, 1};
            bk_offset_ray_origin_scaled(pf, nf, (float)size, L->o[16 * k + j]);
        }
    }
}

static void level_free(level *L)
{
    bk_tracer_destroy(L->t);
    tsc_free(&L->s);
}

/* Irradiance luminance of light li at receiver i, weighted w, with its shadow ray. */
static double shade(const level *L, size_t li, int i, double w, uint64_t *rays)
{
    double val[3], ld[3], dist;
    if (!bk_light_eval(&L->s.lights[li], L->pts[i], val, ld, &dist)) return 0;
    if (ld[2] <= 0) return 0;
    (*rays)++;
    if (!bk_light_visible(L->t, L->o[i], ld, dist)) return 0;
    return bk_lum(val) * ld[2] * w;
}

typedef struct result { double seconds, tested, rays, err; } result;

static double rel_rmse(const double *x, const double *ref)
{
    double num = 0, den = 0;
    for (int i = 0; i < NRECV; i++) {
        num += (x[i] - ref[i]) * (x[i] - ref[i]);
        den += ref[i] * ref[i];
    }
    return sqrt(num / den);
}

static result brute(const level *L, double *out)
{
    uint64_t rays = 0;
    double t0 = bench_thread_cpu();
    for (int i = 0; i < NRECV; i++) {
        double e = 0;
        for (size_t li = 0; li < L->s.light_count; li++) e += shade(L, li, i, 1, &rays);
        out[i] = e;
    }
    result r = {bench_thread_cpu() - t0, (double)L->s.light_count, (double)rays / NRECV, 0};
    return r;
}

/* K lights per receiver from the CDF (NULL: uniform), with replacement. */
static result sampled(const level *L, const double *cdf, int K, uint64_t seed, const double *ref)
{
    const size_t n = L->s.light_count;
    double *x = malloc(NRECV * sizeof *x);
    uint64_t rays = 0;
    double t0 = bench_thread_cpu();
    for (int i = 0; i < NRECV; i++) {
        bench_rng r = {bench_mix(seed * 1000003u + (uint64_t)i)};
        double e = 0;
        for (int k = 0; k < K; k++) {
            double u = bench_next(&r);
            size_t li;
            double p;
            if (!cdf) {
                li = (size_t)(u * (double)n);
                if (li >= n) li = n - 1;
                p = 1.0 / (double)n;
            } else {
                size_t lo = 0, hi = n - 1;
                while (lo < hi) {
                    size_t mid = (lo + hi) / 2;
                    if (cdf[mid] > u) hi = mid; else lo = mid + 1;
                }
                li = lo;
                p = cdf[li] - (li ? cdf[li - 1] : 0);
            }
            e += shade(L, li, i, 1.0 / (K * p), &rays);
        }
        x[i] = e;
    }
    result res = {bench_thread_cpu() - t0, K, (double)rays / NRECV, rel_rmse(x, ref)};
    free(x);
    return res;
}

/* One culling draw over the whole level (block lists, tile lists, accepted lights), at δ
 * relative to the mean irradiance of the receivers (as the transport). */
static result slc(const level *L, bk_slc *sl, double delta, uint64_t seed, const double *ref)
{
    const size_t n = L->s.light_count;
    double *x = malloc(NRECV * sizeof *x), *xi = malloc(n * sizeof *xi);
    uint32_t *ids = malloc(n * sizeof *ids);
    uint64_t rays = 0, tested = 0;
    double t0 = bench_thread_cpu();
    bench_rng r = {bench_mix(seed)};
    for (size_t li = 0; li < n; li++) xi[li] = bench_next(&r);
    bk_slc_draw *d = NULL;
    if (bk_slc_draw_create(sl, xi, delta, 1, &d) != LBK_OK) abort();
    size_t cnt = 0;
    for (int i = 0; i < NRECV; i++) {
        if (i % BK_SLC_TILE == 0) cnt = bk_slc_tile_lights(d, (size_t)i, ids);
        tested += cnt;
        double e = 0;
        for (size_t k = 0; k < cnt; k++) {
            double val[3], ld[3], dist;
            const bk_light *l = &L->s.lights[ids[k]];
            if (!bk_light_eval(l, L->pts[i], val, ld, &dist)) continue;
            double w = bk_slc_weight(bk_lum(val), delta, xi[ids[k]]);
            if (w > 0) e += shade(L, ids[k], i, w, &rays);
        }
        x[i] = e;
    }
    bk_slc_draw_destroy(d);
    result res = {bench_thread_cpu() - t0, (double)tested / NRECV, (double)rays / NRECV, rel_rmse(x, ref)};
    free(x);
    free(xi);
    free(ids);
    return res;
}

/* The mean of R runs' errors in quadrature (their RMS), times and counts averaged. */
static result avg(result *r, int R)
{
    result a = {0, 0, 0, 0};
    for (int k = 0; k < R; k++) {
        a.seconds += r[k].seconds / R;
        a.tested += r[k].tested / R;
        a.rays += r[k].rays / R;
        a.err += r[k].err * r[k].err / R;
    }
    a.err = sqrt(a.err);
    return a;
}

static void row(const char *name, result r, const result *base)
{
    double at = r.err * sqrt(r.seconds / base->seconds);
    printf("  %-22s %10.1f %10.1f %9.4f %9.2f %% %9.2f %% %8.2fx\n", name, r.tested, r.rays, r.seconds, 100 * r.err,
           100 * at, base->err > 0 ? at / base->err : 0);
}

static void run_level(int nx, int ny, const double *deltas, int nd)
{
    level *L = calloc(1, sizeof *L);
    build(L, nx, ny);
    const size_t n = L->s.light_count;
    double *ref = malloc(NRECV * sizeof *ref);
    result bf = brute(L, ref);
    /* δ's scale, as the transport: the mean irradiance at 256 receivers (with 10,000 lights the
     * transport takes 419: at most 2^22 shadow rays; the same mean up to sampling) */
    double mean = 0;
    for (int k = 0; k < 256; k++) mean += ref[k * NRECV / 256] / 256;
    float *boxes = malloc(6 * NRECV * sizeof(float));
    for (int i = 0; i < NRECV; i++)
        for (int a = 0; a < 3; a++) boxes[6 * i + a] = boxes[6 * i + 3 + a] = (float)L->pts[i][a];
    const bk_light **lp = malloc(n * sizeof *lp);
    for (size_t i = 0; i < n; i++) lp[i] = &L->s.lights[i];
    bk_slc *sl = NULL;
    if (bk_slc_create(lp, n, boxes, NRECV, &sl) != LBK_OK) abort();
    double *cdf = malloc(n * sizeof *cdf), tot = 0;
    for (size_t i = 0; i < n; i++) cdf[i] = (tot += 0.2126 * lp[i]->color[0] + 0.7152 * lp[i]->color[1] + 0.0722 * lp[i]->color[2]);
    for (size_t i = 0; i < n; i++) cdf[i] /= tot;
    cdf[n - 1] = 1;
    enum { R = 4 };
    printf("\n%zu lights, %d receivers, %zu triangles; brute force %.2f s (%.0f shadow rays per receiver)\n", n, NRECV,
           L->s.tri_count, bf.seconds, bf.rays);
    printf("  %-22s %10s %10s %9s %11s %11s %9s\n", "method", "tested/rcv", "rays/rcv", "cpu s", "rel RMSE", "at SLC time",
           "vs SLC");
    result base = {0, 0, 0, 0};
    for (int k = 0; k < nd; k++) {
        result rs[R];
        for (int q = 0; q < R; q++) rs[q] = slc(L, sl, deltas[k] * mean, 7 + (uint64_t)q, ref);
        result a = avg(rs, R);
        if (k == 0) {
            base = a;
            row("brute force (exact)", bf, &base);
        }
        char name[64];
        snprintf(name, sizeof name, "SLC delta %.4g%s", deltas[k], deltas[k] == BK_SLC_DEFAULT_DELTA ? " (dflt)" : "");
        row(name, a, &base);
    }
    /* uniform and power sampling with the SLC run's shadow rays per receiver (≈ its time), then
     * scaled to its time exactly */
    int K = (int)fmax(1, round(base.rays));
    result ru[R], rp[R];
    for (int q = 0; q < R; q++) {
        ru[q] = sampled(L, NULL, K, 11 + (uint64_t)q, ref);
        rp[q] = sampled(L, cdf, K, 21 + (uint64_t)q, ref);
    }
    char name[64];
    snprintf(name, sizeof name, "uniform K=%d", K);
    row(name, avg(ru, R), &base);
    snprintf(name, sizeof name, "power K=%d", K);
    row(name, avg(rp, R), &base);
    printf("  (brute force at SLC time: uniform subset; exact brute force takes %.1fx the SLC time)\n",
           bf.seconds / base.seconds);
    bk_slc_destroy(sl);
    free(cdf);
    free(lp);
    free(boxes);
    free(ref);
    level_free(L);
    free(L);
}

/* ---- the transport: where culling starts to pay, and which δ ------------------------------
 * Whole bakes (grey surfaces, cache bounces, 4 passes, 2 threads) of the street with N lamps,
 * culling off and on; the transport's own error estimate (two halves; it measures the culling's
 * noise too) gives the efficiency 1/(err²·time), compared at equal time as err·√time. */
static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

typedef struct bake_result { double seconds, err, shadow; } bake_result;

static bake_result bake(const level *L, int slc_mode, double delta)
{
    bk_receiver *rc = calloc(NRECV, sizeof *rc);
    for (int i = 0; i < NRECV; i++) {
        for (int a = 0; a < 3; a++) rc[i].position[a] = (float)L->pts[i][a];
        rc[i].normal[2] = 1;
    }
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.seed = 5;
    o.threads = 2;
    o.target_error = -1;
    o.max_samples = 2 * 16 * 15; /* 4 passes */
    o.max_cells = 2048;
    o.no_sky = 1;
    o.slc = slc_mode;
    o.slc_delta = delta;
    float *irr = malloc(3 * NRECV * sizeof *irr);
    lbk_sh9_rgb *rad = malloc(NRECV * sizeof *rad);
    bk_transport_output out = {rad, NULL, irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    bk_transport_stats st;
    double t0 = wall_now();
    if (bk_transport_run(&L->s, L->t, rc, NRECV, &o, &out, &st) != LBK_OK) abort();
    bake_result r = {wall_now() - t0, st.est_rel_rmse, (double)st.shadow_rays / NRECV};
    free(irr);
    free(rad);
    free(rc);
    return r;
}

static void transport_table(void)
{
    printf("\ntransport (4 passes, 480 samples per receiver, 2 threads; err = the bake's estimate):\n");
    printf("  %-8s %-16s %9s %9s %14s %13s\n", "lights", "culling", "wall s", "err", "shadow/rcv", "err at equal t");
    const int sides[][2] = {{4, 4}, {8, 8}, {16, 16}, {40, 25}};
    for (int k = 0; k < 4; k++) {
        level *L = calloc(1, sizeof *L);
        build(L, sides[k][0], sides[k][1]);
        const size_t n = L->s.light_count;
        bake_result off = {0, 0, 0};
        if (n <= 256) {
            off = bake(L, -1, 0);
            printf("  %-8zu %-16s %9.2f %8.2f%% %14.0f %13s\n", n, "off (brute)", off.seconds, 100 * off.err, off.shadow, "1.00x");
        }
        const double ds[] = {0.01, 0.03, 0.1, 0.3};
        for (int d = 0; d < 4; d++) {
            if (n < 256 && ds[d] != BK_SLC_DEFAULT_DELTA) continue;
            bake_result on = bake(L, 1, ds[d]);
            char name[32], eq[32] = "-";
            snprintf(name, sizeof name, "delta %.3g", ds[d]);
            if (off.seconds > 0) snprintf(eq, sizeof eq, "%.2fx", on.err * sqrt(on.seconds) / (off.err * sqrt(off.seconds)));
            printf("  %-8zu %-16s %9.2f %8.2f%% %14.0f %13s\n", n, name, on.seconds, 100 * on.err, on.shadow, eq);
        }
        level_free(L);
        free(L);
    }
    printf("  (err at equal t: culled err·√t over brute force's; < 1: culling wins)\n");
}

int main(void)
{
    printf("stochastic light culling vs brute force vs power sampling (direct light, one thread)\n");
    const double deltas[] = {BK_SLC_DEFAULT_DELTA, 0.3, 0.03, 0.01, 0.003, 0.001};
    if (!getenv("BENCH_SLC_TRANSPORT_ONLY")) {
        run_level(40, 25, deltas, 6);   /* 1,000 lights */
        run_level(100, 100, deltas, 6); /* 10,000 lights */
    }
    transport_table();
    return 0;
}
