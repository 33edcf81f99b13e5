/* The radiosity cache's bias in a narrow gap, against an independent reference (printed, not
 * asserted; tests/bake/test_bias.c asserts a smaller version).
 *
 * Scene: the Cornell box's light in test_bias's terms: a closed 2 m room of albedo 0.725 with a
 * 0.5 × 0.4 m double-sided emitter (emission 8, albedo 0.999) hung 1 cm under the ceiling, so its
 * upper side lights a 1 cm gap that amplifies it (~2.6× in the middle) and leaks into the room
 * through the mouth at grazing angles. Cache cells of 0.125 m (the fast preset's texel), far
 * larger than the gap. Receivers: 16 on the floor, 16 on two walls, 16 on the ceiling beside the
 * slit (10–30 cm from its mouth). Reference: the brute-force path tracer
 * (tests/support/ref_path.h), 65,536 paths per point by default.
 *
 * Prints the reference's noise per group, then per seed the transport's seconds and the signed
 * mean relative error Σ(lbk − ref)/Σref of each group and of all receivers; then the mean over
 * seeds and the standard deviation of one seed's all-receiver figure (what test_bias's
 * test_light_gap_unbiased derives its bound from).
 *
 *   bench_gap [--samples N] [--seeds S] [--ref-paths P] [--threads T] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake/transport/shading.h"
#include "bake/transport/transport.h"
#include "tests/support/gap_scene.c"
#include "tests/support/ref_path.c"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"

static int group_of(int i) { return i / GSC_PER; }

static double lum(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    int samples = 2016, seeds = 4, ref_paths = 65536, threads = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--samples")) samples = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--seeds")) seeds = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--ref-paths")) ref_paths = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--threads")) threads = atoi(argv[i + 1]);
        else { fprintf(stderr, "bench_gap: unknown option %s\n", argv[i]); return 2; }
    }
    if (samples < 32 || seeds < 1 || seeds > 16 || ref_paths < 16) { fprintf(stderr, "bench_gap: bad values\n"); return 2; }
    bk_scene s;
    gsc_build(&s);
    char err[128];
    if (rp_check(&s, err, sizeof err)) { fprintf(stderr, "bench_gap: %s\n", err); return 1; }
    bk_receiver r[GSC_N];
    float p[3 * GSC_N], n[3 * GSC_N];
    gsc_receivers(r, p, n);
    bk_tracer *t = NULL;
    if (bk_tracer_create(&s, 0, &t) != LBK_OK) return 1;
    double ref[3 * GSC_N], se[GSC_N];
    double t0 = seconds();
    rp_irradiance(&s, t, p, n, GSC_N, ref_paths, 17, threads > 0 ? threads : 2, ref, se);
    double ref_s = seconds() - t0;
    double gref[GSC_GROUPS] = {0}, gvar[GSC_GROUPS] = {0};
    for (int i = 0; i < GSC_N; i++) {
        gref[group_of(i)] += bk_lum(ref + 3 * i);
        gvar[group_of(i)] += se[i] * se[i];
    }
    printf("bench_gap: 2 m room (albedo 0.725), 0.5 x 0.4 m emitter 1 cm under the ceiling, cells 0.125 m; "
           "reference %d paths/point (%.1f s)\n", ref_paths, ref_s);
    for (int g = 0; g < GSC_GROUPS; g++)
        printf("  %-20s reference mean %.4f, its noise %.2f %%\n", gsc_group_names[g],
               gref[g] / GSC_PER, 100 * sqrt(gvar[g]) / gref[g]);
    float *cell = malloc(s.tri_count * sizeof *cell);
    for (size_t i = 0; i < s.tri_count; i++) cell[i] = GSC_CELL;
    int passes = 1; /* the most passes whose 2·16·(2^p − 1) samples fit */
    while (passes < 12 && 2 * 16 * ((2 << passes) - 1) <= samples) passes++;
    double mean_bias[GSC_GROUPS] = {0}, mean_s = 0;
    printf("  %-6s %8s", "seed", "seconds");
    for (int g = 0; g < GSC_GROUPS; g++) printf("  %20s", gsc_group_names[g]);
    printf("  %14s\n", "all receivers");
    double all_ref = gref[0] + gref[1] + gref[2], all_mean = 0, all_sq = 0;
    double x_sum[GSC_N] = {0}, x_sq[GSC_N] = {0};
    for (int seed = 1; seed <= seeds; seed++) {
        lbk_sh9_rgb rad[GSC_N];
        float irr[3 * GSC_N];
        bk_transport_output out = {rad, NULL, irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
        bk_transport_options o = tsc_fixed_passes(passes, (uint64_t)seed);
        o.threads = threads;
        o.cell_size = cell; /* every triangle sized: max_cells unused */
        bk_transport_stats st;
        t0 = seconds();
        if (bk_transport_run(&s, t, r, GSC_N, &o, &out, &st) != LBK_OK) { fprintf(stderr, "bench_gap: transport failed\n"); return 1; }
        double dt = seconds() - t0;
        double gsum[GSC_GROUPS] = {0};
        for (int i = 0; i < GSC_N; i++) {
            gsum[group_of(i)] += lum(irr + 3 * i) - bk_lum(ref + 3 * i);
            x_sum[i] += lum(irr + 3 * i);
            x_sq[i] += lum(irr + 3 * i) * lum(irr + 3 * i);
        }
        printf("  %-6d %8.2f", seed, dt);
        for (int g = 0; g < GSC_GROUPS; g++) {
            printf("  %+19.2f%%", 100 * gsum[g] / gref[g]);
            mean_bias[g] += gsum[g] / gref[g] / seeds;
        }
        double all = (gsum[0] + gsum[1] + gsum[2]) / all_ref;
        all_mean += all / seeds;
        all_sq += all * all;
        printf("  %+13.2f%%   (%d samples/receiver)\n", 100 * all, (int)o.max_samples);
        mean_s += dt / seeds;
    }
    printf("  %-6s %8.2f", "mean", mean_s);
    for (int g = 0; g < GSC_GROUPS; g++) printf("  %+19.2f%%", 100 * mean_bias[g]);
    double sd = seeds > 1 ? sqrt(fmax(0, (all_sq - seeds * all_mean * all_mean) / (seeds - 1))) : 0;
    printf("  %+13.2f%%   (one seed's spread: %.2f %%)\n", 100 * all_mean, 100 * sd);
    double var = 0; /* a receiver's noise: its spread over the seeds, RMS over receivers / their mean */
    for (int i = 0; i < GSC_N && seeds > 1; i++)
        var += (x_sq[i] - x_sum[i] * x_sum[i] / seeds) / (seeds - 1) / GSC_N;
    printf("  one receiver's noise (RMS over receivers, relative to their mean): %.2f %%\n",
           100 * sqrt(fmax(var, 0)) / (all_ref / GSC_N));
    free(cell);
    bk_tracer_destroy(t);
    tsc_free(&s);
    return 0;
}
