/* The GPU path (gpu/) against liblbk, on whatever Vulkan device the loader finds — lavapipe on a
 * machine without a GPU (mesa-vulkan-drivers; VK_ICD_FILENAMES or LBK_GPU_DEVICE choose one):
 *   - dls_apply.comp, batched and one dispatch per cluster, over a sequence of weights (first
 *     apply, incremental, all off, doors, weights of ±3e38 whose sums overflow):
 *     the LMAP planes and probe arrays are byte-identical to lbk_dls_apply's, on every form;
 *     the naive gather gives the same bytes; dispatches and bytes moved are reported;
 *   - the encoders alone (codec_pack.comp) on RGB9E5 rounding ties and near-zero directions;
 *   - the reference shaders — AHD decode, SH9 irradiance, the GLG walk, LLG sampling — give
 *     liblbk's floats bit for bit;
 *   - build/lbk-gpu-apply --check on a whole container agrees with lbk_dls_apply.
 * Byte identity is asserted on CPU devices (lavapipe: tests/run.sh runs this a second time with
 * GALLIUM_OVERRIDE_CPU_CAPS=avx, llvmpipe's code for AVX2 hosts without AVX-512). On a GPU,
 * whose double division and square root Vulkan does not require to be correctly rounded, a
 * differing texel or probe must be within its decoded rounding bound (GPU.md, "Exactness").
 * Without Vulkan (headers, glslang or a device) every test is SKIPPED, with the reason. */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats: experimental (lbk/dls.h) */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/sh.h"
#include "support/dls_fixture.h"

#if LBK_HAVE_VULKAN
#include "gpu/host/gpu_dls.h"
#include "gpu/host/gpu_samplers.h"

static gpu_ctx ctx;
static int ctx_state; /* 0 not tried, 1 open, 2 none */
static char ctx_reason[256];

static gpu_ctx *device(void)
{
    if (ctx_state == 0) {
        int r = gpu_open(&ctx, ctx_reason, sizeof ctx_reason);
        ctx_state = r == 0 ? 1 : 2;
        if (r == 0) print_message("GPU device: %s%s\n", ctx.device_name, ctx.cpu_device ? " (a CPU device: times are not GPU times)" : "");
        if (r < 0) fail_msg("Vulkan error: %s", ctx_reason);
    }
    if (ctx_state != 1) {
        print_message("GPU tests SKIPPED: %s\n", ctx_reason);
        skip();
    }
    return &ctx;
}

/* The instance stays until exit: vkDestroyInstance unloads the driver, after which LeakSanitizer
 * reports the driver's static data (lavapipe's) as leaks of an unknown module. */
static int teardown(void **state)
{
    (void)state;
    if (ctx_state == 1) gpu_close_device(&ctx);
    return 0;
}

/* ---- DLS apply ------------------------------------------------------------------------------- */

#define W 60
#define H 50
#define PAGES 2 /* 2 × 60 × 50 = 6000 texels */

typedef struct level {
    dlsfx fx;
    void *dls, *door, *lmap;
    size_t dls_size, door_size, lmap_size;
    lbk_dls_view *view;
    lbk_door_view *doors;
    uint8_t *base_probe[2], *out_probe[2];
    uint8_t *out_plane[PAGES][2];
} level;

static void level_build(level *lv, uint64_t seed)
{
    uint64_t rng = seed;
    const uint32_t nsets = 24;
    dlsfx_init(&lv->fx, nsets, PAGES * W * H, 500, 400);
    for (uint32_t s = 0; s < nsets - 1; s++)
        for (uint32_t sp = 0; sp < 3; sp++) {
            const uint32_t span = (uint32_t)lv->fx.desc.target_count[sp], len = 10 + (uint32_t)(dlsfx_rand(&rng) % (span / 3));
            const uint32_t start = (uint32_t)(dlsfx_rand(&rng) % (span - len));
            for (uint32_t t = start; t < start + len; t++)
                if (dlsfx_rand(&rng) % 6) dlsfx_add(&lv->fx, &rng, s, sp, t);
        }
    /* set 1 a door's open set, 2 its bounce, 23 the combination {0, 1} */
    lv->fx.sets[1].kind = LBK_DLS_KIND_DOOR_OPEN;
    lv->fx.sets[2].kind = LBK_DLS_KIND_DOOR_CLOSED;
    const uint32_t mem[2] = {0, 1};
    dlsfx_combination(&lv->fx, nsets - 1, 2, mem);
    for (uint32_t t = 0; t < 400; t++) dlsfx_add(&lv->fx, &rng, nsets - 1, 0, 2000 + t);
    lbk_dls_stats st;
    assert_int_equal(lbk_dls_build(&lv->fx.desc, NULL, &lv->dls, &lv->dls_size, &st), LBK_OK);
    for (int f = 0; f < LBK_DLS_FORM_COUNT_; f++) assert_true(f == LBK_DLS_FORM_PREFIX8 || st.clusters_by_form[f] > 0);
    assert_int_equal(lbk_dls_open(lv->dls, lv->dls_size, NULL, &lv->view), LBK_OK);
    lbk_door_desc door = {.name = "door", .axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, .half_extents = {1, 1, 0.1f},
                          .open_set = 1, .closed_set = 2};
    const uint32_t door0 = 0;
    lbk_door_state_desc state = {1, &door0, nsets - 1};
    lbk_door_build_desc dd = {.door_count = 1, .doors = &door, .state_count = 1, .states = &state};
    assert_int_equal(lbk_door_build(&dd, NULL, &lv->door, &lv->door_size), LBK_OK);
    assert_int_equal(lbk_door_open(lv->door, lv->door_size, NULL, &lv->doors), LBK_OK);
    /* the base: an LMAP section of random texels, random probes */
    lbk_ahd_texel *tx = malloc(sizeof *tx * PAGES * W * H);
    for (uint32_t t = 0; t < PAGES * W * H; t++) {
        uint8_t b[8];
        dlsfx_random_texel(&rng, 2.0f, b);
        lbk_ahd_texel_unpack(b, &tx[t]);
    }
    lbk_lmap_page_desc pages[PAGES];
    for (int p = 0; p < PAGES; p++) pages[p] = (lbk_lmap_page_desc){W, H, tx + p * W * H};
    lbk_lmap_build_desc ld = {.pages = pages, .page_count = PAGES};
    assert_int_equal(lbk_lmap_build(&ld, NULL, &lv->lmap, &lv->lmap_size), LBK_OK);
    free(tx);
    for (int p = 0; p < 2; p++) {
        const uint64_t n = lv->fx.desc.target_count[1 + p];
        lv->base_probe[p] = malloc(28 * n), lv->out_probe[p] = calloc(n, 28);
        for (uint64_t t = 0; t < n; t++) dlsfx_random_probe(&rng, 2.0f, lv->base_probe[p] + 28 * t);
    }
    for (int p = 0; p < PAGES; p++) lv->out_plane[p][0] = calloc(W * H, 4), lv->out_plane[p][1] = calloc(W * H, 4);
}

static void level_free(level *lv)
{
    lbk_door_close(lv->doors);
    lbk_dls_close(lv->view);
    free(lv->dls), free(lv->door), free(lv->lmap);
    for (int p = 0; p < 2; p++) free(lv->base_probe[p]), free(lv->out_probe[p]);
    for (int p = 0; p < PAGES; p++) free(lv->out_plane[p][0]), free(lv->out_plane[p][1]);
    dlsfx_free(&lv->fx);
}

/* The CPU runtime over the LMAP section's pages in place. */
static lbk_dls_runtime *cpu_runtime(level *lv)
{
    lbk_lmap_view lm;
    assert_int_equal(lbk_lmap_open(lv->lmap, lv->lmap_size, &lm), LBK_OK);
    lbk_dls_page pages[PAGES];
    for (uint32_t p = 0; p < PAGES; p++) {
        lbk_lmap_page pg;
        assert_int_equal(lbk_lmap_page_get(&lm, p, &pg), LBK_OK);
        pages[p] = (lbk_dls_page){.width = pg.width, .height = pg.height, .base_irradiance = pg.irradiance,
                                  .base_rgba = pg.rgba, .out_irradiance = lv->out_plane[p][0], .out_rgba = lv->out_plane[p][1]};
    }
    lbk_dls_runtime_desc d = {.size = sizeof d, .dls = lv->view, .doors = lv->doors, .base_glg = lv->base_probe[0],
                              .base_llg = lv->base_probe[1], .out_glg = lv->out_probe[0], .out_llg = lv->out_probe[1],
                              .page_count = PAGES, .pages = pages};
    lbk_dls_runtime *r;
    assert_int_equal(lbk_dls_runtime_open(&d, &r), LBK_OK);
    return r;
}

/* Texels and probes whose GPU bytes are not the CPU's, over a test (GPU.md, "Exactness"). */
static uint64_t texels_compared, texels_differing;

/* ---- the encoders alone ------------------------------------------------------------------------ */

/* lbk_sh9_pack on the device against liblbk: half the probes have a DC whose RGB9E5 mantissas
 * land exactly on k + 1/2 for every k of 0..511 (even and odd: ties to even; 511.5 moves the
 * shared exponent), the rest random coefficients of random scales. A snorm8 or unorm8 code
 * never meets a tie (x · 127 and x · 255 are never k + 1/2 for a float x), an RGB9E5 mantissa
 * often does: this is what found llvmpipe's roundEven (GPU.md). */
static void test_gpu_encoder_ties(void **state)
{
    (void)state;
    gpu_ctx *c = device();
    enum { N = 8192 };
    float *sh = malloc(108 * (size_t)N);
    uint8_t *got = malloc(28 * (size_t)N);
    uint64_t rng = 21;
    uint32_t ties_odd = 0;
    for (uint32_t i = 0; i < N; i++) {
        float *p = sh + 27 * i;
        const int e = (int)(dlsfx_rand(&rng) % 30) - 16; /* shared exponent e + 16, within 0..29 */
        for (int ch = 0; ch < 3; ch++) {
            for (int k = 1; k < 9; k++) p[9 * ch + k] = (2 * dlsfx_uniform(&rng) - 1) * ldexpf(1.0f, e);
            p[9 * ch] = ldexpf(1.0f + dlsfx_uniform(&rng), e);
        }
        if (i % 2 == 0) { /* channel 0 sets the exponent (mantissa 256..511, or 511.5), 1 and 2 tie */
            const uint32_t k = (i / 2) % 512;
            p[0] = ldexpf(i % 64 == 0 ? 511.5f : (float)(256 + dlsfx_rand(&rng) % 256), e - 8);
            p[9] = ldexpf((float)k + 0.5f, e - 8);
            p[18] = ldexpf((float)(511 - k) + 0.5f, e - 8);
            ties_odd += (k & 1) + ((511 - k) & 1);
        }
    }
    assert_true(ties_odd > N / 4); /* ties whose round-half-up differs from ties-to-even */
    assert_int_equal(gpu_sh9_pack(c, sh, N, got), 0);
    for (uint32_t i = 0; i < N; i++) {
        lbk_sh9_rgb s;
        memcpy(&s, sh + 27 * i, sizeof s);
        uint8_t want[28];
        lbk_sh9_pack(&s, want);
        if (memcmp(want, got + 28 * i, 28))
            fail_msg("probe %u (DC %a %a %a): CPU RGB9E5 %02x%02x%02x%02x, GPU %02x%02x%02x%02x", i, (double)s.c[0][0],
                     (double)s.c[1][0], (double)s.c[2][0], want[3], want[2], want[1], want[0], got[28 * i + 3],
                     got[28 * i + 2], got[28 * i + 1], got[28 * i]);
    }
    free(sh), free(got);
}

/* lbk_ahd_from_linear on the device: gradients whose three channels nearly cancel (the summed
 * direction near zero, where a last-bit difference moves the direction codes), at scales 1 and
 * 2^-10, and in the lower hemisphere. */
static void test_gpu_encoder_directions(void **state)
{
    (void)state;
    gpu_ctx *c = device();
    enum { N = 20000 };
    float *lin = malloc(48 * (size_t)N);
    uint32_t *got = malloc(8 * (size_t)N);
    uint64_t rng = 22;
    for (uint32_t i = 0; i < N; i++) {
        float *p = lin + 12 * i, g[3];
        for (int k = 0; k < 3; k++) g[k] = 2 * dlsfx_uniform(&rng) - 1;
        const float scale = i % 2 ? ldexpf(1.0f, -10) : 1.0f, spread = i % 4 < 2 ? 0.01f : 1e-6f;
        for (int ch = 0; ch < 3; ch++) {
            p[4 * ch] = 2 * dlsfx_uniform(&rng);
            for (int k = 0; k < 3; k++) p[4 * ch + 1 + k] = scale * (g[k] * spread + (2 * dlsfx_uniform(&rng) - 1) * spread);
        }
    }
    assert_int_equal(gpu_ahd_from_linear(c, lin, N, got), 0);
    for (uint32_t i = 0; i < N; i++) {
        lbk_ahd_linear l;
        memcpy(&l, lin + 12 * i, sizeof l);
        lbk_ahd_texel t;
        lbk_ahd_from_linear(&l, &t);
        uint32_t rgba;
        memcpy(&rgba, t.rgba, 4);
        if (t.irradiance_z != got[2 * i] || rgba != got[2 * i + 1])
            fail_msg("texel %u: CPU %08x %08x, GPU %08x %08x", i, t.irradiance_z, rgba, got[2 * i], got[2 * i + 1]);
    }
    free(lin), free(got);
}

/* A texel the GPU rounded differently: its decoded irradiance along the six axes within 2^-5 of
 * the texel's largest (one R11G11B10F step is 2^-6 relative, one direction or ratio code
 * 1/255 of the directional part; a direction whose summed vector is near zero may flip, which
 * moves almost nothing). */
static void check_texel_close(uint32_t za, const uint8_t *ra, uint32_t zb, const uint8_t *rb)
{
    lbk_ahd_texel a = {.irradiance_z = za}, b = {.irradiance_z = zb};
    memcpy(a.rgba, ra, 4), memcpy(b.rgba, rb, 4);
    static const float axes[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    float ea[6][3], eb[6][3], top = 0;
    for (int k = 0; k < 6; k++) {
        lbk_ahd_irradiance(&a, axes[k], ea[k]);
        lbk_ahd_irradiance(&b, axes[k], eb[k]);
        for (int c = 0; c < 3; c++) top = fmaxf(top, fmaxf(fabsf(ea[k][c]), fabsf(eb[k][c])));
    }
    for (int k = 0; k < 6; k++)
        for (int c = 0; c < 3; c++)
            if (!(fabsf(ea[k][c] - eb[k][c]) <= ldexpf(top, -5)))
                fail_msg("texel off by more than its rounding: %g vs %g (largest %g)", (double)eb[k][c], (double)ea[k][c], (double)top);
}

/* A probe the GPU rounded differently: every decoded coefficient within 2^-4 of the probe's
 * largest (one snorm8 code is 1/127 of the band scale; near zero a code may move by a few). */
static void check_probe_close(const uint8_t *a, const uint8_t *b)
{
    lbk_sh9_rgb sa, sb;
    lbk_sh9_unpack(a, &sa), lbk_sh9_unpack(b, &sb);
    float top = 0;
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++) top = fmaxf(top, fmaxf(fabsf(sa.c[c][k]), fabsf(sb.c[c][k])));
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++)
            if (!(fabsf(sa.c[c][k] - sb.c[c][k]) <= ldexpf(top, -4)))
                fail_msg("probe coefficient off by more than its rounding: %g vs %g (largest %g)", (double)sb.c[c][k],
                         (double)sa.c[c][k], (double)top);
}

/* The GPU's output LMAP bytes against the CPU's output planes: identical, except texels a GPU
 * may round differently (its double division and square root need not be exact: GPU.md), each
 * within its rounding; probes likewise. The caller decides how many may differ (none on lavapipe). */
static void check_outputs(const level *lv, const gpu_dls *g)
{
    const uint8_t *out = gpu_dls_lmap(g);
    lbk_lmap_view lm;
    assert_int_equal(lbk_lmap_open(out, lv->lmap_size, &lm), LBK_OK);
    for (uint32_t p = 0; p < PAGES; p++) {
        lbk_lmap_page pg;
        assert_int_equal(lbk_lmap_page_get(&lm, p, &pg), LBK_OK);
        const uint8_t *gz = pg.irradiance, *gr = pg.rgba, *cz = lv->out_plane[p][0], *cr = lv->out_plane[p][1];
        for (uint32_t t = 0; t < W * H; t++) {
            texels_compared++;
            if (!memcmp(gz + 4 * t, cz + 4 * t, 4) && !memcmp(gr + 4 * t, cr + 4 * t, 4)) continue;
            texels_differing++;
            uint32_t za, zb;
            memcpy(&za, cz + 4 * t, 4), memcpy(&zb, gz + 4 * t, 4);
            check_texel_close(za, cr + 4 * t, zb, gr + 4 * t);
        }
    }
    for (uint32_t s = 1; s <= 2; s++) {
        const uint8_t *gp = gpu_dls_probes(g, s), *cp = lv->out_probe[s - 1];
        for (uint64_t t = 0; t < lv->fx.desc.target_count[s]; t++) {
            texels_compared++;
            if (!memcmp(gp + 28 * t, cp + 28 * t, 28)) continue;
            texels_differing++;
            check_probe_close(cp + 28 * t, gp + 28 * t);
        }
    }
}

static void test_gpu_apply_matches_cpu(void **state)
{
    (void)state;
    gpu_ctx *c = device();
    level lv;
    memset(&lv, 0, sizeof lv);
    level_build(&lv, 5);
    gpu_dls_level gl = {.dls = lv.dls, .dls_size = lv.dls_size, .door = lv.door, .door_size = lv.door_size,
                        .lmap = lv.lmap, .lmap_size = lv.lmap_size, .glg = lv.base_probe[0], .llg = lv.base_probe[1], .naive = 1};
    gpu_dls *g;
    char err[256] = "";
    if (gpu_dls_open(c, &gl, &g, err, sizeof err)) fail_msg("gpu_dls_open: %s", err);
    lbk_dls_runtime *r = cpu_runtime(&lv);
    const uint32_t nsets = lbk_dls_set_count(lv.view);
    uint64_t rng = 17;
    float w[24];
    float omega = 0.0f;
    for (int step = 0; step < 7; step++) {
        if (step == 0 || step == 3) /* everything changes */
            for (uint32_t s = 0; s < nsets; s++) w[s] = dlsfx_rand(&rng) % 4 ? 2.0f * dlsfx_uniform(&rng) - 0.25f : 0.0f;
        else if (step == 1) w[4] += 0.5f, w[9] = 0.0f; /* two sets change: most dispatches skipped */
        else if (step == 2) omega = 0.5f;              /* the door opens halfway: sets 1, 2 and 23 */
        else if (step == 4) memset(w, 0, sizeof w), omega = 0.0f; /* all off, door closed */
        else if (step == 5) w[7] = 1.0f;
        else /* sums that overflow to ±Inf and NaN, and tiny weights: the encoder's clamping paths */
            w[3] = 3e38f, w[5] = -3e38f, w[6] = 3e38f, w[8] = 1e-30f, w[10] = -2.5f;
        lbk_dls_apply_stats cs;
        gpu_dls_stats gs;
        gpu_dls_per_cluster(g, step % 2); /* the seed's dispatch per cluster, and the batched one */
        assert_int_equal(lbk_dls_apply(r, w, &omega, &cs), LBK_OK);
        assert_int_equal(gpu_dls_apply(g, w, &omega, &gs), 0);
        check_outputs(&lv, g);
        assert_int_equal(gs.clusters_applied, cs.clusters_applied);
        if (step == 0) { /* all-zero clusters: the CPU copies their base, the GPU already did (full copy) */
            assert_int_equal(gs.clusters_skipped, cs.clusters_skipped + cs.clusters_copied);
        } else {
            assert_int_equal(gs.clusters_skipped, cs.clusters_skipped);
            assert_int_equal(gs.clusters_copied, cs.clusters_copied);
        }
        print_message("apply %d (%s): %u dispatches (+%u base copies) for %u clusters, %llu invocations, %.2f MB moved, "
                      "%.3f ms device, %.3f ms wall\n", step, step % 2 ? "per cluster" : "batched", gs.dispatches, gs.copies,
                      gpu_dls_cluster_count(g) - gs.clusters_skipped,
                      (unsigned long long)gs.invocations, gs.bytes_moved / 1e6, gs.gpu_ms, gs.wall_ms);
    }
    /* the naive gather, every target every time: the same bytes in 3 dispatches */
    gpu_dls_stats ns;
    assert_int_equal(gpu_dls_apply_naive(g, w, &omega, &ns), 0);
    check_outputs(&lv, g);
    assert_int_equal(ns.dispatches, 3);
    double dc, dn;
    gpu_dls_divergence(g, &dc, &dn);
    print_message("naive gather: %u dispatches, %.2f MB moved; idle lanes of the entry loop (waves of 32): clustered "
                  "%.1f%%, naive %.1f%%\n", ns.dispatches, ns.bytes_moved / 1e6, 100 * dc, 100 * dn);
    assert_true(dn > dc);
    /* bit-exact on lavapipe at every CPU feature level; on a GPU (not measured yet) a few texels
     * within their rounding are tolerated, never many (GPU.md, "Exactness") */
    print_message("texels and probes: %llu compared, %llu with other bytes than the CPU's\n",
                  (unsigned long long)texels_compared, (unsigned long long)texels_differing);
    if (c->cpu_device) assert_int_equal(texels_differing, 0);
    else assert_true(texels_differing * 50 <= texels_compared);
    lbk_dls_runtime_close(r);
    gpu_dls_close(g);
    level_free(&lv);
}

/* ---- reference shaders ------------------------------------------------------------------------ */

static void unit(uint64_t *rng, float n[3], int upper)
{
    float x, y, z, l;
    do {
        x = 2 * dlsfx_uniform(rng) - 1, y = 2 * dlsfx_uniform(rng) - 1, z = 2 * dlsfx_uniform(rng) - 1;
        l = x * x + y * y + z * z;
    } while (l < 0.01f || l > 1.0f);
    l = sqrtf(l);
    n[0] = x / l, n[1] = y / l, n[2] = upper ? fabsf(z / l) : z / l;
}

static void test_gpu_ahd_irradiance(void **state)
{
    (void)state;
    gpu_ctx *c = device();
    enum { N = 20000 };
    uint32_t *tx = malloc(8 * N);
    float *nrm = malloc(12 * N), *got = malloc(12 * N);
    uint64_t rng = 3;
    for (uint32_t i = 0; i < N; i++) {
        uint8_t b[8];
        if (i % 4 == 3) for (int k = 0; k < 8; k++) b[k] = (uint8_t)dlsfx_rand(&rng); /* any bytes, exponent 31 too */
        else dlsfx_random_texel(&rng, ldexpf(1.0f, (int)(dlsfx_rand(&rng) % 30) - 15), b);
        lbk_ahd_texel t;
        lbk_ahd_texel_unpack(b, &t);
        tx[2 * i] = t.irradiance_z;
        memcpy(&tx[2 * i + 1], t.rgba, 4);
        unit(&rng, &nrm[3 * i], 1);
    }
    assert_int_equal(gpu_ahd_irradiance(c, tx, nrm, N, got), 0);
    for (uint32_t i = 0; i < N; i++) {
        lbk_ahd_texel t = {tx[2 * i], {0}};
        memcpy(t.rgba, &tx[2 * i + 1], 4);
        float want[3];
        lbk_ahd_irradiance(&t, &nrm[3 * i], want);
        if (memcmp(want, &got[3 * i], 12))
            fail_msg("texel %u (%08x %08x): CPU %a %a %a, GPU %a %a %a", i, tx[2 * i], tx[2 * i + 1], want[0], want[1], want[2],
                     got[3 * i], got[3 * i + 1], got[3 * i + 2]);
    }
    free(tx), free(nrm), free(got);
}

static void test_gpu_sh9_irradiance(void **state)
{
    (void)state;
    gpu_ctx *c = device();
    enum { N = 20000 };
    uint8_t *pr = malloc(28 * N);
    float *nrm = malloc(12 * N), *got = malloc(12 * N);
    uint64_t rng = 4;
    for (uint32_t i = 0; i < N; i++) {
        if (i % 4 == 3) for (int k = 0; k < 28; k++) pr[28 * i + k] = (uint8_t)dlsfx_rand(&rng);
        else dlsfx_random_probe(&rng, ldexpf(1.0f, (int)(dlsfx_rand(&rng) % 30) - 15), pr + 28 * i);
        unit(&rng, &nrm[3 * i], 0);
    }
    assert_int_equal(gpu_sh9_irradiance(c, pr, nrm, N, got), 0);
    for (uint32_t i = 0; i < N; i++) {
        lbk_sh9_rgb sh;
        lbk_sh9_unpack(pr + 28 * i, &sh);
        float want[3];
        lbk_sh9_irradiance(&sh, &nrm[3 * i], want);
        if (memcmp(want, &got[3 * i], 12))
            fail_msg("probe %u: CPU %a %a %a, GPU %a %a %a", i, want[0], want[1], want[2], got[3 * i], got[3 * i + 1], got[3 * i + 2]);
    }
    free(pr), free(nrm), free(got);
}

/* A GLG on a jittered nx × ny × nz lattice, each cell split into 6 tetras along its diagonal
 * (Kuhn), random probes and visibility, scale 1/4. */
static void glg_lattice(uint64_t *rng, int nx, int ny, int nz, void **bytes, size_t *size)
{
    const uint32_t np = (uint32_t)(nx * ny * nz), nt = (uint32_t)((nx - 1) * (ny - 1) * (nz - 1) * 6);
    float(*pos)[3] = calloc(np, sizeof *pos);
    uint32_t(*tets)[4] = calloc(nt, sizeof *tets);
    uint8_t(*vis)[4] = calloc(nt, sizeof *vis);
    lbk_sh9_rgb *probes = calloc(np, sizeof *probes);
#define V(x, y, z) ((uint32_t)((x) + nx * ((y) + ny * (z))))
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++)
            for (int x = 0; x < nx; x++) {
                const uint32_t v = V(x, y, z);
                pos[v][0] = (float)x + 0.2f * (dlsfx_uniform(rng) - 0.5f);
                pos[v][1] = (float)y + 0.2f * (dlsfx_uniform(rng) - 0.5f);
                pos[v][2] = (float)z + 0.2f * (dlsfx_uniform(rng) - 0.5f);
                for (int i = 0; i < 3; i++) {
                    float d[3], rgb[3] = {dlsfx_uniform(rng), dlsfx_uniform(rng), dlsfx_uniform(rng)};
                    unit(rng, d, 0);
                    lbk_sh9_add_sample(&probes[v], d, rgb, 3.0f);
                }
            }
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    uint32_t t = 0;
    for (int cz = 0; cz < nz - 1; cz++)
        for (int cy = 0; cy < ny - 1; cy++)
            for (int cx = 0; cx < nx - 1; cx++)
                for (int p = 0; p < 6; p++, t++) {
                    int q[3] = {cx, cy, cz};
                    tets[t][0] = V(q[0], q[1], q[2]);
                    for (int k = 0; k < 3; k++) {
                        q[perms[p][k]]++;
                        tets[t][k + 1] = V(q[0], q[1], q[2]);
                    }
                    for (int k = 0; k < 4; k++) vis[t][k] = (uint8_t)(dlsfx_rand(rng) % 5 ? 128 + dlsfx_rand(rng) % 128 : 0);
                }
#undef V
    lbk_glg_build_desc d = {.probe_count = np, .tetra_count = nt, .positions = (const float(*)[3])pos, .probes = probes,
                            .tetras = (const uint32_t(*)[4])tets, .visibility = (const uint8_t(*)[4])vis, .scale = 0.25f};
    assert_int_equal(lbk_glg_build(&d, NULL, bytes, size), LBK_OK);
    free(pos), free(tets), free(vis), free(probes);
}

static void test_gpu_glg_walk(void **state)
{
    (void)state;
    gpu_ctx *c = device();
    enum { GN = 5, NT = (GN - 1) * (GN - 1) * (GN - 1) * 6, N = 4000 };
    uint64_t rng = 6;
    void *bytes;
    size_t size;
    glg_lattice(&rng, GN, GN, GN, &bytes, &size);
    lbk_glg_view v;
    assert_int_equal(lbk_glg_open(bytes, size, &v), LBK_OK);
    float *pts = malloc(12 * N), *sh = malloc(4 * 27 * N), *wts = malloc(16 * N);
    uint32_t *hints = malloc(4 * N), *tet = malloc(4 * N);
    for (uint32_t i = 0; i < N; i++) { /* inside, and up to a cell outside the hull */
        for (int k = 0; k < 3; k++) pts[3 * i + k] = (GN + 1.0f) * dlsfx_uniform(&rng) - 1.0f;
        hints[i] = (uint32_t)(dlsfx_rand(&rng) % (NT + 10));
    }
    assert_int_equal(gpu_glg_sample(c, bytes, size, pts, hints, N, sh, tet, wts), 0);
    for (uint32_t i = 0; i < N; i++) {
        uint32_t hint = hints[i];
        lbk_sh9_rgb want;
        lbk_glg_sample_info info;
        assert_int_equal(lbk_glg_sample(&v, &pts[3 * i], &hint, &want, &info), LBK_OK);
        assert_int_equal(tet[i], hint);
        assert_memory_equal(&wts[4 * i], info.weights, 16);
        for (int ch = 0; ch < 3; ch++)
            if (memcmp(want.c[ch], &sh[27 * i + 9 * ch], 36)) fail_msg("query %u channel %d: SH differs", i, ch);
    }
    free(pts), free(sh), free(wts), free(hints), free(tet), free(bytes);
}

static void test_gpu_llg_sampling(void **state)
{
    (void)state;
    gpu_ctx *c = device();
    enum { N = 4000, NV = 50 };
    uint64_t rng = 8;
    lbk_llg_grid_desc grids[2];
    lbk_sh9_rgb *probes[2];
    lbk_llg_vertex verts[2][NV];
    for (int g = 0; g < 2; g++) {
        /* a rotated box: axes from a random unit quaternion */
        float q[4], n2 = 0;
        for (int k = 0; k < 4; k++) q[k] = 2 * dlsfx_uniform(&rng) - 1, n2 += q[k] * q[k];
        for (int k = 0; k < 4; k++) q[k] /= sqrtf(n2);
        const float x = q[0], y = q[1], z = q[2], w = q[3];
        const float r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)},
                               {2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)},
                               {2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)}};
        grids[g] = (lbk_llg_grid_desc){.centre = {3.0f * g, 1, -2}, .half_extents = {1.5f, 0.75f, 2.0f},
                                       .dims = {3 + 2u * g, 4, 2 + 3u * g}, .vertex_count = NV, .vertices = verts[g]};
        memcpy(grids[g].axes, r, sizeof r);
        const uint32_t np = grids[g].dims[0] * grids[g].dims[1] * grids[g].dims[2];
        probes[g] = calloc(np, sizeof(lbk_sh9_rgb));
        for (uint32_t i = 0; i < np; i++)
            for (int s = 0; s < 3; s++) {
                float d[3], rgb[3] = {dlsfx_uniform(&rng), dlsfx_uniform(&rng), dlsfx_uniform(&rng)};
                unit(&rng, d, 0);
                lbk_sh9_add_sample(&probes[g][i], d, rgb, 2.0f);
            }
        grids[g].probes = probes[g];
        for (int i = 0; i < NV; i++) {
            verts[g][i].visibility = dlsfx_uniform(&rng);
            unit(&rng, verts[g][i].bent_normal, 0);
        }
    }
    lbk_llg_build_desc d = {.grids = grids, .grid_count = 2, .scale = 2.0f};
    void *bytes;
    size_t size;
    assert_int_equal(lbk_llg_build(&d, NULL, &bytes, &size), LBK_OK);
    lbk_llg_view v;
    assert_int_equal(lbk_llg_open(bytes, size, &v), LBK_OK);
    float *pts = malloc(12 * N), *sh = malloc(4 * 27 * N), *rgb = malloc(12 * N);
    uint32_t *gi = malloc(4 * N), *vi = malloc(4 * N);
    for (uint32_t i = 0; i < N; i++) {
        gi[i] = (uint32_t)(dlsfx_rand(&rng) % 2), vi[i] = (uint32_t)(dlsfx_rand(&rng) % NV);
        for (int k = 0; k < 3; k++) pts[3 * i + k] = grids[gi[i]].centre[k] + 5.0f * dlsfx_uniform(&rng) - 2.5f; /* in and out */
    }
    assert_int_equal(gpu_llg_sample(c, bytes, size, pts, gi, vi, N, sh, rgb), 0);
    for (uint32_t i = 0; i < N; i++) {
        lbk_sh9_rgb want;
        float e[3];
        assert_int_equal(lbk_llg_sample(&v, gi[i], &pts[3 * i], &want), LBK_OK);
        assert_int_equal(lbk_llg_vertex_irradiance(&v, gi[i], vi[i], &pts[3 * i], e), LBK_OK);
        for (int ch = 0; ch < 3; ch++)
            if (memcmp(want.c[ch], &sh[27 * i + 9 * ch], 36)) fail_msg("query %u channel %d: SH differs", i, ch);
        if (memcmp(e, &rgb[3 * i], 12)) fail_msg("query %u: vertex irradiance CPU %a %a %a GPU %a %a %a", i, e[0], e[1], e[2],
                                               rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
    }
    free(pts), free(sh), free(rgb), free(gi), free(vi), free(bytes), free(probes[0]), free(probes[1]);
}


/* build/lbk-gpu-apply on a whole container (DLS, DOOR, LMAP, GLG, LLG as lbk bake writes them):
 * uploads, applies its default sequence and --check compares every apply with lbk_dls_apply. */
static void test_gpu_apply_tool(void **state)
{
    (void)state;
    (void)device();
    char tool[512];
    const char *build = getenv("BUILD");
    snprintf(tool, sizeof tool, "%s/lbk-gpu-apply", build && *build ? build : "build");
    FILE *probe = fopen(tool, "rb");
    if (!probe) fail_msg("%s is missing: make test builds it with Vulkan", tool);
    fclose(probe);
    level lv;
    memset(&lv, 0, sizeof lv);
    level_build(&lv, 9);
    uint64_t rng = 10;
    void *glg, *llg;
    size_t glg_size, llg_size;
    glg_lattice(&rng, 10, 10, 5, &glg, &glg_size); /* the level's 500 GLG probes */
    lbk_sh9_rgb *probes = calloc(400, sizeof *probes);
    for (int i = 0; i < 400; i++) probes[i].c[0][0] = probes[i].c[1][0] = probes[i].c[2][0] = 1.0f + 0.01f * (float)i;
    lbk_llg_grid_desc grid = {.centre = {0, 0, 0}, .axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, .half_extents = {1, 1, 1},
                              .dims = {10, 10, 4}, .probes = probes}; /* the level's 400 LLG probes */
    lbk_llg_build_desc ld = {.grids = &grid, .grid_count = 1};
    assert_int_equal(lbk_llg_build(&ld, NULL, &llg, &llg_size), LBK_OK);
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, lv.lmap, lv.lmap_size, NULL), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_GLG, glg, glg_size, NULL), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LLG, llg, llg_size, NULL), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_DLS, lv.dls, lv.dls_size, NULL), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_DOOR, lv.door, lv.door_size, NULL), LBK_OK);
    char path[] = "/tmp/lbk_test_gpu_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    assert_int_equal(lbk_writer_to_file(w, path), LBK_OK);
    lbk_writer_close(w);
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "%s %s --check --naive --doors 0.5 > %s.log 2>&1", tool, path, path);
    const int rc = system(cmd);
    char log[600];
    snprintf(log, sizeof log, "%s.log", path);
    FILE *f = fopen(log, "r");
    int identical = 0, differ = 0;
    for (char line[512]; f && fgets(line, sizeof line, f);) {
        identical += strstr(line, "identical to lbk_dls_apply") != NULL;
        differ += strstr(line, "bytes differ from lbk_dls_apply") != NULL;
        print_message("  %s", line);
    }
    if (f) fclose(f);
    unlink(log), unlink(path);
    if (texels_differing == 0) { /* an exact driver (test_gpu_apply_matches_cpu ran first) */
        assert_int_equal(rc, 0);
        assert_int_equal(identical, 4); /* the default sequence: 4 applies */
    } else { /* a driver that rounds some texels differently: the tool must say so, exit 1 */
        assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
        assert_true(differ >= 1);
    }
    free(glg), free(llg), free(probes);
    level_free(&lv);
}

#else /* no Vulkan at build time */

static void skipped(void)
{
    print_message("GPU tests SKIPPED: built without Vulkan (libvulkan-dev and glslang-tools; `make deps` installs them)\n");
    skip();
}
static void test_gpu_apply_matches_cpu(void **state) { (void)state, skipped(); }
static void test_gpu_ahd_irradiance(void **state) { (void)state, skipped(); }
static void test_gpu_sh9_irradiance(void **state) { (void)state, skipped(); }
static void test_gpu_glg_walk(void **state) { (void)state, skipped(); }
static void test_gpu_llg_sampling(void **state) { (void)state, skipped(); }
static void test_gpu_encoder_ties(void **state) { (void)state, skipped(); }
static void test_gpu_encoder_directions(void **state) { (void)state, skipped(); }
static void test_gpu_apply_tool(void **state) { (void)state, skipped(); }
static int teardown(void **state) { (void)state; return 0; }
#endif

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gpu_apply_matches_cpu), cmocka_unit_test(test_gpu_ahd_irradiance),
        cmocka_unit_test(test_gpu_sh9_irradiance), cmocka_unit_test(test_gpu_glg_walk),
        cmocka_unit_test(test_gpu_llg_sampling), cmocka_unit_test(test_gpu_encoder_ties),
        cmocka_unit_test(test_gpu_encoder_directions), cmocka_unit_test(test_gpu_apply_tool),
    };
    return cmocka_run_group_tests(tests, NULL, teardown);
}
