/* The GPU path (gpu/) on the ESTATE-sized level of tests/support/estate_level.h: the clustered
 * apply (dls_apply.comp: one batched dispatch, or one per cluster whose sets changed as in the
 * seed) against the naive per-target
 * gather the seed replaced (one dispatch per space, dls_naive.comp) — dispatches, invocations,
 * bytes moved, the divergence proxy (idle lanes of the entry loop in waves of 32) and device time
 * — when every set changes and when one does. Seed 001 reports 20 ms for its old shaders and
 * 1.47 ms for the clustered ones on a PS4 GPU for its ESTATE, every set updated synchronously.
 * On lavapipe (a CPU device) the times are CPU times, not GPU times: the counts and bytes carry
 * over, the milliseconds do not. The first clustered apply is also checked byte for byte against
 * lbk_dls_apply. Prints SKIPPED without Vulkan. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/dls.h"
#include "lbk/lightmap.h"
#include "bench/bench_util.h"
/* The generators live with the tests; benches link the tools only, so take their source. */
#include "tests/support/dls_fixture.c"
#include "tests/support/estate_level.c"

#if LBK_HAVE_VULKAN
#include "gpu/host/gpu_dls.h"

/* The GPU's outputs equal the CPU runtime's, byte for byte. */
static int outputs_match(const gpu_dls *g, const uint8_t *lmap, size_t lmap_size, const uint8_t *glg, const uint8_t *llg)
{
    return !memcmp(gpu_dls_lmap(g), lmap, lmap_size) && !memcmp(gpu_dls_probes(g, 1), glg, 28 * (size_t)ESTATE_GLG) &&
           !memcmp(gpu_dls_probes(g, 2), llg, 28 * (size_t)ESTATE_LLG);
}

static void line(const char *what, const gpu_dls_stats *s)
{
    printf("  %-34s %5u dispatches, %8llu invocations, %7.2f MB moved, %9.2f ms device, %9.2f ms wall\n", what, s->dispatches,
           (unsigned long long)s->invocations, s->bytes_moved / 1e6, s->gpu_ms, s->wall_ms);
}

static void best(gpu_dls_stats *b, const gpu_dls_stats *s)
{
    if (b->dispatches == 0 || s->gpu_ms < b->gpu_ms) *b = *s;
}

int main(void)
{
    gpu_ctx ctx;
    char err[256];
    int r = gpu_open(&ctx, err, sizeof err);
    if (r) {
        printf("bench_gpu: SKIPPED (%s)\n", err);
        return r < 0;
    }
    printf("device: %s%s\n", ctx.device_name, ctx.cpu_device ? " — a CPU device: its milliseconds are CPU time, not GPU time" : "");
    estate_level lv;
    if (estate_build(&lv)) return 1;
    estate_describe(&lv);
    /* the base: an LMAP section of random texels; random probes */
    uint64_t rng = 99;
    lbk_ahd_texel *tx = malloc(sizeof *tx * ESTATE_TEXELS);
    for (uint32_t t = 0; t < ESTATE_TEXELS; t++) {
        uint8_t b[8];
        dlsfx_random_texel(&rng, 2.0f, b);
        lbk_ahd_texel_unpack(b, &tx[t]);
    }
    lbk_lmap_page_desc pages[ESTATE_PAGES];
    for (uint32_t p = 0; p < ESTATE_PAGES; p++)
        pages[p] = (lbk_lmap_page_desc){estate_page_w[p], estate_page_h[p], tx + estate_page_first(p)};
    void *lmap;
    size_t lmap_size;
    lbk_lmap_build_desc ld = {.pages = pages, .page_count = ESTATE_PAGES};
    if (lbk_lmap_build(&ld, NULL, &lmap, &lmap_size) != LBK_OK) return 1;
    free(tx);
    uint8_t *glg = malloc(28 * (size_t)ESTATE_GLG), *llg = malloc(28 * (size_t)ESTATE_LLG);
    for (uint32_t t = 0; t < ESTATE_GLG; t++) dlsfx_random_probe(&rng, 2.0f, glg + 28 * (size_t)t);
    for (uint32_t t = 0; t < ESTATE_LLG; t++) dlsfx_random_probe(&rng, 2.0f, llg + 28 * (size_t)t);
    gpu_dls_level gl = {.dls = lv.bytes, .dls_size = lv.size, .lmap = lmap, .lmap_size = lmap_size, .glg = glg, .llg = llg,
                        .naive = 1};
    gpu_dls *g;
    if (gpu_dls_open(&ctx, &gl, &g, err, sizeof err)) {
        printf("bench_gpu: %s\n", err);
        return 1;
    }
    /* the CPU reference for the first check */
    lbk_lmap_view lm;
    lbk_lmap_open(lmap, lmap_size, &lm);
    uint8_t *cpu_lmap = malloc(lmap_size), *cpu_glg = malloc(28 * (size_t)ESTATE_GLG), *cpu_llg = malloc(28 * (size_t)ESTATE_LLG);
    memcpy(cpu_lmap, lmap, lmap_size);
    lbk_dls_page dp[ESTATE_PAGES];
    for (uint32_t p = 0; p < ESTATE_PAGES; p++) {
        lbk_lmap_page pg;
        lbk_lmap_page_get(&lm, p, &pg);
        dp[p] = (lbk_dls_page){.width = pg.width, .height = pg.height, .base_irradiance = pg.irradiance, .base_rgba = pg.rgba,
                               .out_irradiance = cpu_lmap + pg.irradiance_offset, .out_rgba = cpu_lmap + pg.rgba_offset};
    }
    lbk_dls_runtime_desc rd = {.size = sizeof rd, .dls = lv.view, .base_glg = glg, .base_llg = llg, .out_glg = cpu_glg,
                               .out_llg = cpu_llg, .page_count = ESTATE_PAGES, .pages = dp};
    lbk_dls_runtime *rt;
    if (lbk_dls_runtime_open(&rd, &rt) != LBK_OK) return 1;

    float w[ESTATE_SETS];
    gpu_dls_stats s, all = {0}, one = {0}, all1 = {0}, one1 = {0}, naive = {0};
    for (int i = 0; i < ESTATE_SETS; i++) w[i] = 0.5f;
    gpu_dls_apply(g, w, NULL, &s);
    lbk_dls_apply(rt, w, NULL, NULL);
    const int same = outputs_match(g, cpu_lmap, lmap_size, cpu_glg, cpu_llg);
    printf("buffers in %s memory\n", ctx.buffers_device_local ? "device-local, host-visible (resizable BAR)" : "host-visible, not device-local");
    printf("clustered, the first apply (base copies + every cluster):\n");
    line("first apply", &s);
    printf("  bytes %s lbk_dls_apply's\n", same ? "identical to" : "DIFFERENT FROM");
    /* the references: the base copies alone (the device's copy speed over the output bytes), and
     * whole applies (copies + every cluster) again, best of 3 */
    gpu_dls_stats copies = {0}, full = {0};
    for (int rep = 0; rep < 3; rep++) {
        gpu_dls_copy_bases(g, &s);
        best(&copies, &s);
        for (int i = 0; i < ESTATE_SETS; i++) w[i] = 0.55f + 0.01f * (float)rep;
        gpu_dls_invalidate(g);
        gpu_dls_apply(g, w, NULL, &s);
        best(&full, &s);
    }
    line("base copies alone (the reference)", &copies);
    line("whole apply (copies + clusters)", &full);
    for (int per_cluster = 0; per_cluster < 2; per_cluster++) {
        gpu_dls_per_cluster(g, per_cluster);
        for (int rep = 0; rep < 2; rep++) {
            for (int i = 0; i < ESTATE_SETS; i++) w[i] = 0.6f + 0.01f * (float)rep + 0.05f * (float)per_cluster;
            gpu_dls_apply(g, w, NULL, &s);
            best(per_cluster ? &all1 : &all, &s);
        }
        for (int rep = 0; rep < 3; rep++) {
            w[5] = 0.3f + 0.1f * (float)rep;
            gpu_dls_apply(g, w, NULL, &s);
            best(per_cluster ? &one1 : &one, &s);
        }
    }
    gpu_dls_apply_naive(g, w, NULL, &naive);
    /* the CPU runtime on the same machine, same weights, one thread: the ratio that carries over
     * between machines; and a second byte check, after eleven GPU applies of changing weights */
    double cpu_all = 1e30;
    for (int rep = 0; rep < 3; rep++) {
        float wc[ESTATE_SETS];
        for (int i = 0; i < ESTATE_SETS; i++) wc[i] = 0.8f + 0.01f * (float)rep;
        const double t0 = bench_thread_cpu();
        lbk_dls_apply(rt, wc, NULL, NULL);
        const double t = 1e3 * (bench_thread_cpu() - t0);
        if (t < cpu_all) cpu_all = t;
    }
    lbk_dls_apply(rt, w, NULL, NULL);
    const int same_last = outputs_match(g, cpu_lmap, lmap_size, cpu_glg, cpu_llg);
    double dc, dn;
    gpu_dls_divergence(g, &dc, &dn);
    printf("clustered (dls_apply.comp) vs the naive gather (dls_naive.comp), best of the runs:\n");
    line("batched, every set changes", &all);
    line("batched, one set changes", &one);
    line("per cluster, every set changes", &all1);
    line("per cluster, one set changes", &one1);
    line("naive gather (cannot skip)", &naive);
    printf("  naive / batched (every set): %.2f× the device time, %.2f× the bytes; idle lanes of the entry loop "
           "(waves of 32): clustered %.1f%%, naive %.1f%% (seed: 20 ms old shaders → 1.47 ms clustered on a PS4 GPU)\n",
           naive.gpu_ms / all.gpu_ms, (double)naive.bytes_moved / (double)all.bytes_moved, 100 * dc, 100 * dn);
    printf("  batched every-set apply / base copies: %.2f× the device time for %.2f× the bytes (copy %.1f GB/s)\n",
           all.gpu_ms / copies.gpu_ms, (double)all.bytes_moved / (double)copies.bytes_moved,
           copies.bytes_moved / (copies.gpu_ms * 1e6));
    printf("  lbk_dls_apply on this machine's CPU, every set changes, 1 thread: %.2f ms CPU; / GPU batched: %.1f×; "
           "GPU batched moves %.1f GB/s\n",
           cpu_all, cpu_all / all.gpu_ms, all.bytes_moved / (all.gpu_ms * 1e6));
    printf("  bytes after the last apply (naive gather) %s lbk_dls_apply's\n", same_last ? "identical to" : "DIFFERENT FROM");
    lbk_dls_runtime_close(rt);
    gpu_dls_close(g);
    gpu_close(&ctx);
    free(cpu_lmap), free(cpu_glg), free(cpu_llg), free(glg), free(llg), lbk_free(NULL, lmap);
    estate_free(&lv);
    return same && same_last ? 0 : 1;
}
#else
int main(void)
{
    printf("bench_gpu: SKIPPED (built without Vulkan: libvulkan-dev and glslang-tools, `make deps` installs them)\n");
    return 0;
}
#endif
