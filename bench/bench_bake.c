/* Whole-pipeline bake benchmarks (printed, not asserted):
 *  a. error against run time on cornell_box and room_with_doors (--sky 1,1,1): one long
 *     reference bake, then bakes at growing sample budgets; for each, the error the baker
 *     estimated (the bake report) next to the error measured against the reference (relative
 *     RMSE of the decoded texel irradiance, normalised like the estimate) and their ratio
 *     (goal: within 2×). The reference's own estimated error is printed too: the measured
 *     error includes it (and the ~0.5 % RMS rounding of R11G11B10F).
 *  b. wall time of room_with_doors at --preset fast (goal ≤ 60 s on the 2-core machine) and at
 *     --preset high, with the machine's core count.
 * LBK_SCENES overrides scenes/; LBK_BENCH_QUICK=1 shrinks the budgets (smoke run). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lbk/bake.h"
#include "scene/parallel.h"
#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/pixel.h"
#include "tests/support/bake_file.c"

static const char *scenes_dir(void)
{
    const char *d = getenv("LBK_SCENES");
    return d && *d ? d : "scenes";
}

static int quick(void)
{
    const char *q = getenv("LBK_BENCH_QUICK");
    return q && *q && *q != '0';
}

static char tmpdir[256];

typedef struct texels {
    size_t n;
    float *lum;
} texels;

static float lum(const float c[3]) { return LBK_LUM_R * c[0] + LBK_LUM_G * c[1] + LBK_LUM_B * c[2]; }

static int load_texels(const char *path, texels *t)
{
    memset(t, 0, sizeof *t);
    lbk_reader *r;
    if (lbk_reader_open_file(path, NULL, &r)) return -1;
    const void *data;
    size_t size;
    lbk_lmap_view v;
    int rc = -1;
    if (lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &data, &size) == LBK_OK && lbk_lmap_open(data, size, &v) == LBK_OK) {
        t->n = (size_t)v.texel_count;
        t->lum = malloc((t->n ? t->n : 1) * sizeof *t->lum);
        if (t->lum) {
            rc = 0;
            for (uint64_t i = 0; i < v.texel_count; i++) {
                lbk_ahd_texel tx;
                float rgb[3];
                if (lbk_lmap_texel_get(&v, i, &tx, NULL)) {
                    rc = -1;
                    break;
                }
                lbk_r11g11b10f_unpack(tx.irradiance_z, rgb);
                t->lum[i] = lum(rgb);
            }
        }
    }
    lbk_reader_close(r);
    return rc;
}

/* sqrt(Σ (x − ref)² / Σ ref²) over texels lit in the reference: the estimate's normalisation. */
static double rel_rmse(const texels *x, const texels *ref)
{
    if (x->n != ref->n) return NAN;
    double d2 = 0, v2 = 0;
    for (size_t i = 0; i < ref->n; i++) {
        if (ref->lum[i] <= 0) continue;
        double d = (double)x->lum[i] - ref->lum[i];
        d2 += d * d;
        v2 += (double)ref->lum[i] * ref->lum[i];
    }
    return v2 > 0 ? sqrt(d2 / v2) : NAN;
}

static void base_options(tb_job *o, const char *in, const char *out, const char *sky)
{
    memset(o, 0, sizeof *o);
    o->in = in;
    o->out = out;
    o->d.preset = LBK_BAKE_PRESET_FAST;
    o->d.seed = 1;
    o->d.target_error = 1e-6; /* the sample budget decides */
    if (sky) {
        o->d.sky_override = 1;
        sscanf(sky, "%f,%f,%f", &o->d.sky[0], &o->d.sky[1], &o->d.sky[2]);
    }
}

static int bake(const tb_job *o, lbk_bake_report *sum)
{
    char err[512] = "";
    int rc = tb_bake(o, sum, err, sizeof err);
    if (rc) fprintf(stderr, "bench_bake: %s: %s\n", o->in, err);
    return rc;
}

static void error_vs_time(const char *label, const char *rel, const char *sky, int ref_samples, const int *budgets,
                          int nb)
{
    char in[512], ref_out[512], out[512];
    snprintf(in, sizeof in, "%s/%s", scenes_dir(), rel);
    if (access(in, R_OK) != 0) {
        printf("%s: %s missing (set LBK_SCENES), skipped\n", label, in);
        return;
    }
    snprintf(ref_out, sizeof ref_out, "%s/ref.lbk", tmpdir);
    snprintf(out, sizeof out, "%s/run.lbk", tmpdir);
    tb_job o;
    base_options(&o, in, ref_out, sky);
    o.d.max_samples = ref_samples;
    lbk_bake_report ref_sum;
    if (bake(&o, &ref_sum)) return;
    texels ref;
    if (load_texels(ref_out, &ref)) {
        fprintf(stderr, "bench_bake: cannot decode %s\n", ref_out);
        return;
    }
    printf("%s: reference %d samples/receiver budget, %.1f s, %llu texels, est. error %.2f%%\n", label, ref_samples,
           ref_sum.seconds, (unsigned long long)ref_sum.counts.texels, 100 * ref_sum.transport.est_rel_rmse);
    printf("  %8s %9s %10s %10s %10s %8s\n", "samples", "seconds", "estimated", "measured", "meas.-ref", "est/meas");
    for (int i = 0; i < nb; i++) {
        o.out = out;
        o.d.max_samples = budgets[i];
        lbk_bake_report sum;
        if (bake(&o, &sum)) break;
        texels t;
        if (load_texels(out, &t)) break;
        double m = rel_rmse(&t, &ref);
        /* the reference's own noise is independent of this bake's: remove it in quadrature */
        double mc = sqrt(fmax(m * m - ref_sum.transport.est_rel_rmse * ref_sum.transport.est_rel_rmse, 0));
        printf("  %8d %9.2f %9.2f%% %9.2f%% %9.2f%% %8.2f\n", budgets[i], sum.seconds, 100 * sum.transport.est_rel_rmse, 100 * m,
               100 * mc, sum.transport.est_rel_rmse / m);
        free(t.lum);
    }
    /* and a wall-clock budget, the way artists use it */
    o.d.max_samples = ref_samples;
    o.d.time_limit = quick() ? 0.5 : 2;
    lbk_bake_report sum;
    texels t;
    if (!bake(&o, &sum) && !load_texels(out, &t)) {
        double m = rel_rmse(&t, &ref);
        printf("  --time-limit %.1f: %.2f s total, estimated %.2f%%, measured %.2f%%, ratio %.2f\n", o.d.time_limit,
               sum.seconds, 100 * sum.transport.est_rel_rmse, 100 * m, sum.transport.est_rel_rmse / m);
        free(t.lum);
    }
    free(ref.lum);
}

static void wall_time(const char *preset)
{
    char in[512], out[512];
    snprintf(in, sizeof in, "%s/room_with_doors/room.glb", scenes_dir());
    if (access(in, R_OK) != 0) {
        printf("room_with_doors missing (set LBK_SCENES), skipped\n");
        return;
    }
    snprintf(out, sizeof out, "%s/rwd_%s.lbk", tmpdir, preset);
    tb_job o;
    base_options(&o, in, out, "1,1,1");
    o.d.preset = strcmp(preset, "high") ? LBK_BAKE_PRESET_FAST : LBK_BAKE_PRESET_HIGH;
    o.d.target_error = -1; /* the preset's own stop rules */
    lbk_bake_report sum;
    if (bake(&o, &sum)) return;
    printf("room_with_doors --preset %-4s: %6.1f s wall (all cores), est. error %.2f%%, %llu texels, %llu GLG + "
           "%llu LLG probes, %llu bytes%s\n",
           preset, sum.seconds, 100 * sum.transport.est_rel_rmse, (unsigned long long)sum.counts.texels,
           (unsigned long long)sum.counts.glg_probes, (unsigned long long)sum.counts.llg_probes, (unsigned long long)sum.counts.file_bytes,
           !strcmp(preset, "fast") ? (sum.seconds <= 60 ? "  [goal <= 60 s: met]" : "  [goal <= 60 s: MISSED]") : "");
}

int main(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0); /* progress visible when piped */
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk-bench-bake-%d", (int)getpid());
    char cmd[300];
    snprintf(cmd, sizeof cmd, "mkdir -p %s", tmpdir);
    if (system(cmd)) return 1;
    int cores = bk_online_cores();
    double load[1] = {0};
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &load[0]) != 1) load[0] = 0;
        fclose(f);
    }
    printf("bench_bake: %d cores online, load average %.2f%s\n", cores, load[0], quick() ? " (quick)" : "");

    /* Pass p traces 32·2^p rays per receiver (both halves), so P passes cost 32·(2^P − 1): the
     * budgets below stop after exactly 1, 2, 3, … passes. */
    static const int budgets[] = {32, 96, 224, 480, 992, 2016};
    int q = quick();
    error_vs_time("cornell_box", "cornell_box/CornellBox-Original.gltf", NULL, q ? 480 : 8160, budgets, q ? 2 : 6);
    error_vs_time("room_with_doors", "room_with_doors/room.glb", "1,1,1", q ? 224 : 2016, budgets, q ? 2 : 4);
    wall_time("fast");
    if (!q) wall_time("high");

    snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
    return system(cmd) ? 1 : 0;
}
