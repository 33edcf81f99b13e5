/* DLS apply (lbk_dls_apply) against memcpy, measured in the same run.
 *
 * Level: the synthetic ESTATE-sized level of tests/support/estate_level.h (seed 001 Table 1:
 * 2.64 M texels, 280 k probes, 132 sets).
 *
 * Measured: apply when every set's weight changes (the seed's synchronous debug mode, its
 * 1.47 ms on a PS4 GPU) and when one set changes, on 1 and 2 threads (the job API), as the
 * bandwidth of the bytes apply must move — each applied target's base read and output written,
 * each entry it blends read — against memcpy moving the same traffic (a copy of half as many
 * bytes, reading and writing each) on as many threads. Also the same on the door/light-set
 * levels of the room_with_doors scene (tests/support/door_scenes.h) as lbk bake writes them.
 * Both modes of the runtime: bytes (AHD / packed SH9 outputs, the bytes of the scalar
 * definition) and linear (LBK_DLS_RUNTIME_LINEAR: float outputs from prepared floats, whose
 * traffic is 48 bytes per texel and 108 per probe for each base, entry and output; memcpy is
 * measured on that traffic), with the linear mode's prepared memory (both modes on the baked levels too). Threads run the jobs of
 * lbk_dls_apply_begin (bk_parallel_chunks), memcpy on as many threads over 16 slices.
 * `bench_dls --quick` skips the baked levels; `--linear` also runs only the linear mode's SIMD path.
 * Each scenario alternates apply and memcpy (9 or 8 times) and reports the medians of the
 * per-repetition ratios, with the load average before and after. */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats, lbk_dls_runtime_path: experimental (lbk/dls.h) */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "scene/clock.h"
#include "scene/parallel.h"
#include "bake/util/rng.h"
#include "lbk/ahd.h"
#include "lbk/bake.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/lightmap.h"
#include "lbk/sh.h"
/* The generators live with the tests; benches link the tools only, so take their source. */
#include "tests/support/bake_file.c"
#include "tests/support/dls_fixture.c"
#include "tests/support/door_scenes.c"
#include "tests/support/estate_level.c"

#define NSETS ESTATE_SETS
#define PAGES ESTATE_PAGES
#define T ESTATE_TEXELS
#define G ESTATE_GLG
#define L ESTATE_LLG

/* ---- timing -------------------------------------------------------------------------------- */

/* Wall and CPU seconds (the process's, over all its threads). On a shared machine the CPU time
 * of one thread is the steadier number: wall time includes the time other processes had. */
typedef struct clocks {
    double wall, cpu;
} clocks;

static clocks clocks_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (clocks){bk_now(), (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec};
}

static void clocks_best(clocks *best, clocks t0, int threads)
{
    const clocks t1 = clocks_now();
    const double wall = t1.wall - t0.wall, cpu = (t1.cpu - t0.cpu) / threads;
    if (wall < best->wall) best->wall = wall;
    if (cpu < best->cpu) best->cpu = cpu;
}

typedef struct memcpy_job {
    uint8_t *dst;
    const uint8_t *src;
    size_t n;
} memcpy_job;

static void memcpy_chunk(void *user, size_t begin, size_t end, int thread)
{
    const memcpy_job *m = user;
    const size_t part = (m->n + 15) / 16;
    for (size_t i = begin; i < end; i++) {
        const size_t a = i * part, b = a + part < m->n ? a + part : m->n;
        if (a < b) memcpy(m->dst + a, m->src + a, b - a);
    }
    (void)thread;
}

/* One memcpy moving the traffic of a `n`-byte copy on `threads` threads (16 slices). */
static clocks memcpy_once(memcpy_job *m, int threads)
{
    clocks t = {1e9, 1e9};
    const clocks t0 = clocks_now();
    if (threads == 1) memcpy(m->dst, m->src, m->n);
    else bk_parallel_chunks(0, 16, 1, threads, memcpy_chunk, m);
    clocks_best(&t, t0, threads);
    return t;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void job_chunk(void *user, size_t begin, size_t end, int thread)
{
    for (size_t j = begin; j < end; j++) lbk_dls_apply_job(user, (uint32_t)j);
    (void)thread;
}

static lbk_result apply_threads(lbk_dls_runtime *rt, const float *w, const float *dw, int threads)
{
    uint32_t n;
    lbk_result r = lbk_dls_apply_begin(rt, w, dw, &n);
    if (r != LBK_OK) return r;
    if (threads == 1) job_chunk(rt, 0, n, 0);
    else bk_parallel_chunks(0, n, 1, threads, job_chunk, rt);
    return lbk_dls_apply_end(rt, NULL);
}

/* The bytes an apply of these weights moves: per cluster with a changed set, its targets' base
 * and output, and every entry it blends (all of them: every set is on in these scenarios) — as
 * stored (8 / 28 bytes) in the byte mode, as prepared floats (48 / 108 bytes) in the linear one. */
static uint64_t traffic(const lbk_dls_view *v, const float *w_old, const float *w_new, bool linear)
{
    uint64_t bytes = 0;
    for (uint32_t c = 0; c < lbk_dls_cluster_count(v); c++) {
        lbk_dls_cluster_info ci;
        lbk_dls_cluster_get(v, c, &ci);
        bool changed = !w_old;
        for (uint32_t j = 0; j < ci.set_count && !changed; j++) {
            uint32_t s;
            lbk_dls_cluster_set_get(v, c, j, &s);
            changed = w_old[s] != w_new[s];
        }
        const uint64_t psize = ci.space == LBK_DLS_SPACE_TEXEL ? (linear ? 48 : 8) : (linear ? 108 : 28);
        if (changed) bytes += psize * (2 * (uint64_t)ci.target_count + ci.entry_count);
    }
    return bytes;
}

#define MAX_REPS 64
typedef struct scenario_result {
    clocks apply, copy;         /* medians */
    double ratio_wall, ratio_cpu; /* medians of the per-repetition ratios memcpy / apply */
    uint64_t bytes;
    int reps;
} scenario_result;

/* Every set's weight changes between applies (on, 0.5…0.6), or only set `one` (≥ 0). Each
 * repetition times one apply and then one memcpy of the same traffic, back to back, so both see
 * the same load from the other processes; the ratios are per repetition, reported as medians. */
static int measure(lbk_dls_runtime *rt, const lbk_dls_view *v, uint32_t nsets, const float *dw, int one, int threads,
                   int reps, scenario_result *out)
{
    const bool linear = lbk_dls_runtime_linear_bytes(rt) > 0;
    float w0[256], w1[256];
    double aw[MAX_REPS], ac[MAX_REPS], cw[MAX_REPS], cc[MAX_REPS], rw[MAX_REPS], rc[MAX_REPS];
    if (reps > MAX_REPS) reps = MAX_REPS;
    memcpy_job m = {NULL, NULL, 0};
    for (int i = 0; i < reps; i++) {
        for (uint32_t s = 0; s < nsets; s++) w0[s] = 0.5f + 0.01f * (float)(i % 7), w1[s] = w0[s] + 0.005f;
        if (one >= 0) {
            memcpy(w1, w0, nsets * sizeof *w0);
            w1[one] = 0.25f;
        }
        if (i == 0) { /* the traffic is the same every repetition (the same sets change) */
            out->bytes = traffic(v, w0, w1, linear);
            m.n = (size_t)(out->bytes / 2) + 64;
            uint8_t *src = malloc(m.n), *dst = malloc(m.n);
            if (!src || !dst) return 1;
            memset(src, 1, m.n), memset(dst, 2, m.n);
            m.src = src, m.dst = dst;
            (void)memcpy_once(&m, threads); /* warm */
        }
        if (apply_threads(rt, w0, dw, threads) != LBK_OK) return 1; /* the previous frame */
        clocks a = {1e9, 1e9};
        const clocks t0 = clocks_now();
        if (apply_threads(rt, w1, dw, threads) != LBK_OK) return 1;
        clocks_best(&a, t0, threads);
        const clocks c = memcpy_once(&m, threads);
        aw[i] = a.wall, ac[i] = a.cpu, cw[i] = c.wall, cc[i] = c.cpu;
        rw[i] = c.wall / a.wall, rc[i] = c.cpu / a.cpu;
    }
    free((void *)m.src), free(m.dst);
    out->reps = reps;
    out->apply = (clocks){median(aw, reps), median(ac, reps)};
    out->copy = (clocks){median(cw, reps), median(cc, reps)};
    out->ratio_wall = median(rw, reps), out->ratio_cpu = median(rc, reps);
    return 0;
}

/* Ratios to memcpy by wall time and by CPU time per thread: medians over the repetitions. */
static void report(const char *what, int threads, const scenario_result *r)
{
    printf("  %-18s %d thread%s: %7.2f MB moved in %8.3f ms wall (%5.2f GB/s), %8.3f ms CPU/thread; memcpy of that "
           "traffic %7.3f ms wall, %7.3f ms CPU: %.3f of memcpy (wall), %.3f (CPU), medians of %d alternations\n",
           what, threads, threads > 1 ? "s" : " ", r->bytes / 1e6, r->apply.wall * 1e3, r->bytes / r->apply.wall / 1e9,
           r->apply.cpu * 1e3, r->copy.wall * 1e3, r->copy.cpu * 1e3, r->ratio_wall, r->ratio_cpu, r->reps);
}

/* ---- the bound: a contiguous kernel of the same traffic ------------------------------------- */

#if defined(__x86_64__) || defined(__SSE2__)
#include <immintrin.h>
#define HAVE_STREAM 1
#endif

/* out = a + w·b over contiguous arrays, 4 floats a step (SSE, baseline on x86-64), ordinary or
 * non-temporal stores: the linear apply's arithmetic with its read/write proportion and none of
 * its access pattern (interleaved chart-row streams, outputs a page row apart). */
static void triad(const float *a, const float *b, float *o, size_t n, int nt)
{
#if HAVE_STREAM
    const __m128 w = _mm_set1_ps(0.5f);
    for (size_t i = 0; i + 4 <= n; i += 4) {
        const __m128 x = _mm_add_ps(_mm_loadu_ps(a + i), _mm_mul_ps(w, _mm_loadu_ps(b + i)));
        if (nt) _mm_stream_ps(o + i, x);
        else _mm_storeu_ps(o + i, x);
    }
    if (nt) _mm_sfence();
#else
    for (size_t i = 0; i < n; i++) o[i] = a[i] + 0.5f * b[i];
    (void)nt;
#endif
}

/* The ESTATE level's linear traffic (`bytes`) as that contiguous kernel, one thread, against
 * memcpy of the same traffic, alternating: what the machine allows the apply's arithmetic. */
static int triad_bound(uint64_t bytes)
{
    const size_t n = (size_t)(bytes / 12 + 15) / 16 * 16; /* floats per array: 2 read, 1 written */
    float *a = aligned_alloc(64, 4 * n), *b = aligned_alloc(64, 4 * n), *o = aligned_alloc(64, 4 * n);
    memcpy_job m = {NULL, NULL, 6 * n};
    uint8_t *src = malloc(m.n), *dst = malloc(m.n);
    if (!a || !b || !o || !src || !dst) return 1;
    memset(a, 0, 4 * n), memset(b, 0, 4 * n), memset(o, 0, 4 * n), memset(src, 1, m.n), memset(dst, 2, m.n);
    m.src = src, m.dst = dst;
    double r[2][9];
    for (int i = 0; i < 9; i++) {
        const double c = memcpy_once(&m, 1).cpu;
        for (int nt = 0; nt < 2; nt++) {
            const clocks t0 = clocks_now();
            triad(a, b, o, n, nt);
            clocks t = {1e9, 1e9};
            clocks_best(&t, t0, 1);
            r[nt][i] = c / t.cpu;
        }
    }
    printf("  the bound: out = a + w*b over contiguous arrays, %.1f MB of traffic, 1 thread: %.3f of memcpy with ordinary "
           "stores, %.3f with non-temporal ones (CPU time, medians of 9 alternations)\n",
           12.0 * (double)n / 1e6, median(r[0], 9), median(r[1], 9));
    free(a), free(b), free(o), free(src), free(dst);
    return 0;
}

/* ---- the synthetic level's applies --------------------------------------------------------- */

static int estate(int only_linear)
{
    estate_level lv;
    if (estate_build(&lv)) return 1;
    estate_describe(&lv);
    uint64_t rng = 99;
    uint8_t *base0 = malloc(T * 4), *base1 = malloc(T * 4), *out0 = malloc(T * 4), *out1 = malloc(T * 4);
    uint8_t *bg = malloc(G * 28), *og = malloc(G * 28), *bl = malloc(L * 28), *ol = malloc(L * 28);
    for (uint64_t t = 0; t < T; t++) {
        uint8_t b[8];
        dlsfx_random_texel(&rng, 2.0f, b);
        memcpy(base0 + 4 * t, b, 4), memcpy(base1 + 4 * t, b + 4, 4);
    }
    for (uint64_t t = 0; t < G; t++) dlsfx_random_probe(&rng, 2.0f, bg + 28 * t);
    for (uint64_t t = 0; t < L; t++) dlsfx_random_probe(&rng, 2.0f, bl + 28 * t);
    lbk_dls_page pages[PAGES];
    lbk_dls_linear_page lpages[PAGES];
    float *lin = malloc((size_t)T * 48), *lg = malloc((size_t)G * 108), *ll = malloc((size_t)L * 108);
    for (uint32_t p = 0; p < PAGES; p++) {
        const uint64_t f = estate_page_first(p);
        pages[p] = (lbk_dls_page){.width = estate_page_w[p], .height = estate_page_h[p], .base_irradiance = base0 + 4 * f,
                                  .base_rgba = base1 + 4 * f, .out_irradiance = out0 + 4 * f, .out_rgba = out1 + 4 * f};
        for (int c = 0; c < 3; c++) lpages[p].out[c] = lin + (size_t)T * 4 * c + 4 * f, lpages[p].out_pitch[c] = 0;
    }
    /* paths: the byte mode (SIMD, scalar), then the linear mode (SIMD, scalar) */
    static const uint32_t flags[4] = {0, LBK_DLS_RUNTIME_SCALAR, LBK_DLS_RUNTIME_LINEAR,
                                      LBK_DLS_RUNTIME_LINEAR | LBK_DLS_RUNTIME_SCALAR};
    int bad = 0;
    for (int path = only_linear ? 2 : 0; path < (only_linear ? 3 : 4) && !bad; path++) {
        const bool linear = flags[path] & LBK_DLS_RUNTIME_LINEAR, scalar = flags[path] & LBK_DLS_RUNTIME_SCALAR;
        lbk_dls_runtime_desc d = {.size = sizeof d, .dls = lv.view, .base_glg = bg, .base_llg = bl, .out_glg = og,
                                  .out_llg = ol, .page_count = PAGES, .pages = pages, .flags = flags[path],
                                  .linear_pages = lpages, .out_linear_glg = lg, .out_linear_llg = ll};
        lbk_dls_runtime *rt;
        const double t0 = bk_now();
        if (lbk_dls_runtime_open(&d, &rt) != LBK_OK) return 1;
        const double open_s = bk_now() - t0;
        printf(" %s mode, path %s:", linear ? "linear" : "byte", lbk_dls_runtime_path(rt));
        if (linear)
            printf(" prepared %.1f MB (%.2f x the %.1f MB DLS section; outputs %.1f MB), open %.0f ms", lbk_dls_runtime_linear_bytes(rt) / 1e6,
                   lbk_dls_runtime_linear_bytes(rt) / (double)lv.st.section_bytes, lv.st.section_bytes / 1e6,
                   (48.0 * T + 108.0 * (G + L)) / 1e6, open_s * 1e3);
        printf("\n");
        scenario_result r;
        for (int threads = 1; threads <= (scalar ? 1 : 2) && !bad; threads++) {
            bad |= measure(rt, lv.view, NSETS, NULL, -1, threads, scalar ? 1 : 9, &r);
            report("every set changes", threads, &r);
            if (linear && !scalar && threads == 1) bad |= triad_bound(r.bytes);
            if (scalar) break;
            bad |= measure(rt, lv.view, NSETS, NULL, 5, threads, 8, &r);
            report("one set changes", threads, &r);
        }
        uint32_t nranges = lbk_dls_dirty_range_count(rt, 0), nrects = 0;
        for (uint32_t p = 0; p < PAGES; p++) nrects += lbk_dls_dirty_rect_count(rt, p);
        if (!scalar) printf("  after the last apply: %u dirty texel ranges, %u rectangles over %d pages\n", nranges, nrects, PAGES);
        lbk_dls_runtime_close(rt);
    }
    free(lin), free(lg), free(ll);
    free(base0), free(base1), free(out0), free(out1), free(bg), free(og), free(bl), free(ol);
    estate_free(&lv);
    return bad;
}

/* ---- the baked door/light-set levels ------------------------------------------------------- */

static int baked(const char *dir, const char *name, const ds_options *o)
{
    char gltf[256], path[256], err[512];
    snprintf(gltf, sizeof gltf, "%s/%s.gltf", dir, name);
    snprintf(path, sizeof path, "%s/%s.lbk", dir, name);
    if (ds_write_room_scene(DS_ROOM_GLB, gltf, o, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", name, err);
        return 1;
    }
    tb_job bo;
    memset(&bo, 0, sizeof bo);
    bo.in = gltf, bo.out = path;
    bo.d.seed = 1, bo.d.target_error = 1e-9, bo.d.max_samples = 64;
    lbk_bake_report sum;
    int rc = tb_bake(&bo, &sum, err, sizeof err);
    unlink(gltf);
    if (rc) {
        fprintf(stderr, "%s: bake failed: %s\n", name, err);
        return 1;
    }
    lbk_reader *rd;
    const void *d;
    size_t n;
    lbk_lmap_view lm;
    lbk_dls_view *dv = NULL;
    lbk_door_view *door = NULL;
    int bad = lbk_reader_open_file(path, NULL, &rd) != LBK_OK;
    bad = bad || lbk_reader_section_by_type(rd, LBK_SECTION_LMAP, &d, &n) || lbk_lmap_open(d, n, &lm);
    bad = bad || lbk_reader_section_by_type(rd, LBK_SECTION_DLS, &d, &n) || lbk_dls_open(d, n, NULL, &dv);
    if (!bad && lbk_reader_section_by_type(rd, LBK_SECTION_DOOR, &d, &n) == LBK_OK) bad = lbk_door_open(d, n, NULL, &door) != LBK_OK;
    if (bad) {
        fprintf(stderr, "%s: cannot read %s\n", name, path);
        return 1;
    }
    /* pages in place: the LMAP planes are the bases, outputs laid out the same way */
    lbk_dls_page *pages = calloc(lm.page_count, sizeof *pages);
    uint8_t **outs = calloc(2 * lm.page_count, sizeof *outs);
    for (uint32_t p = 0; p < lm.page_count; p++) {
        lbk_lmap_page pg;
        lbk_lmap_page_get(&lm, p, &pg);
        outs[2 * p] = malloc(4 * (size_t)pg.width * pg.height), outs[2 * p + 1] = malloc(4 * (size_t)pg.width * pg.height);
        pages[p] = (lbk_dls_page){.width = pg.width, .height = pg.height, .base_irradiance = pg.irradiance,
                                  .base_rgba = pg.rgba, .out_irradiance = outs[2 * p], .out_rgba = outs[2 * p + 1]};
    }
    const uint64_t ng = lbk_dls_target_count(dv, 1), nl = lbk_dls_target_count(dv, 2);
    uint8_t *bg = calloc(ng + 1, 28), *og = calloc(ng + 1, 28), *bl = calloc(nl + 1, 28), *ol = calloc(nl + 1, 28);
    /* the linear mode's outputs: three RGBA32F planes per page, 27 floats per probe */
    lbk_dls_linear_page *lpages = calloc(lm.page_count, sizeof *lpages);
    float *lin = malloc(48 * (size_t)lm.texel_count + 16), *lg = malloc(108 * (ng + 1)), *ll = malloc(108 * (nl + 1));
    for (uint64_t p = 0, first = 0; p < lm.page_count; first += (uint64_t)pages[p].width * pages[p].height, p++)
        for (int c = 0; c < 3; c++) lpages[p].out[c] = lin + 4 * (lm.texel_count * (uint64_t)c + first);
    lbk_dls_stats st;
    lbk_dls_stats_get(dv, &st);
    printf(" %s: %llu texels, %llu GLG + %llu LLG probes, %u sets, %u clusters, %.1f KB DLS\n", name,
           (unsigned long long)lm.texel_count, (unsigned long long)ng, (unsigned long long)nl, st.set_count, st.cluster_count,
           st.section_bytes / 1e3);
    for (int linear = 0; linear < 2 && !bad; linear++) {
        lbk_dls_runtime_desc rdsc = {.size = sizeof rdsc, .dls = dv, .doors = door, .base_glg = bg, .base_llg = bl,
                                     .out_glg = og, .out_llg = ol, .page_count = lm.page_count, .pages = pages,
                                     .flags = linear ? LBK_DLS_RUNTIME_LINEAR : 0, .linear_pages = lpages,
                                     .out_linear_glg = lg, .out_linear_llg = ll};
        lbk_dls_runtime *rt;
        if (lbk_dls_runtime_open(&rdsc, &rt) != LBK_OK) return 1;
        printf("  %s mode, path %s:\n", linear ? "linear" : "byte", lbk_dls_runtime_path(rt));
        const float dw[8] = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f};
        scenario_result r;
        bad |= measure(rt, dv, st.set_count, door ? dw : NULL, -1, 1, 50, &r);
        report("every set changes", 1, &r);
        bad |= measure(rt, dv, st.set_count, door ? dw : NULL, 0, 1, 50, &r);
        report("one set changes", 1, &r);
        lbk_dls_runtime_close(rt);
    }
    for (uint32_t p = 0; p < 2 * lm.page_count; p++) free(outs[p]);
    free(outs), free(pages), free(lpages), free(lin), free(lg), free(ll), free(bg), free(og), free(bl), free(ol);
    if (door) lbk_door_close(door);
    lbk_dls_close(dv);
    lbk_reader_close(rd);
    unlink(path);
    return bad;
}

/* The machine's load (Linux /proc/loadavg): ratios on a shared machine mean little without it. */
static void print_load(const char *when)
{
    FILE *f = fopen("/proc/loadavg", "r");
    char line[128] = "";
    if (f && fgets(line, sizeof line, f)) printf("load average %s: %s", when, line);
    if (f) fclose(f);
    printf("online CPUs: %ld\n", sysconf(_SC_NPROCESSORS_ONLN));
}

int main(int argc, char **argv)
{
    const int linear = argc > 1 && !strcmp(argv[1], "--linear");
    const int quick = linear || (argc > 1 && !strcmp(argv[1], "--quick"));
    print_load("before");
    int bad = estate(linear);
    print_load("after the ESTATE-sized level");
    if (!quick && !bad) {
        char dir[] = "/tmp/lbk_bench_dls_XXXXXX";
        if (!mkdtemp(dir)) return 1;
        printf("levels baked by lbk bake from room_with_doors (door_scenes.h):\n");
        ds_options sets = {DS_DOOR_PLAIN, DS_INSIDE_SETS, 0, 1, 0.5f, 8, 0, 0, 0};
        ds_options door = {DS_DOOR_TAGGED, DS_INSIDE_SETS, 1, 1, 0.5f, 8, 0, 0, 0};
        bad |= baked(dir, "sets A+B", &sets);
        bad |= baked(dir, "sets A+B+C0 + door", &door);
        rmdir(dir);
    }
    return bad;
}
