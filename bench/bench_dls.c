/* DLS apply (lbk_dls_apply) against memcpy, measured in the same run.
 *
 * Level: synthetic, the size of seed 001's ESTATE (Table 1: 2,637,824 lightmap texels, 229,725
 * GLG and 50,805 LLG probes, 132 light sets, 28 MB without and 77 MB with the sets): texels in
 * three pages (2 × 1024², 1024 × 528); 116 "room" sets, each a cluster of 10–16 charts
 * (rectangles of 12–96 texels a side) around a centre, plus 16 "hall" sets overlapping one
 * region 12–16 deep (the seed's stealth level, Fig. 5: most receivers see few sets, a few see
 * many); probes in intervals of the probe order around the room's place. The overlaps are
 * Poisson-like with a mean of about 1.7 sets per target, which puts the DLS payload near the
 * seed's 49 MB.
 *
 * Measured: apply when every set's weight changes (the seed's synchronous debug mode, its
 * 1.47 ms on a PS4 GPU) and when one set changes, on 1 and 2 threads (the job API), as the
 * bandwidth of the bytes apply must move — each applied target's base read and output written,
 * each entry it blends read — against memcpy moving the same traffic (a copy of half as many
 * bytes, reading and writing each) on as many threads. Also the same on the door/light-set
 * levels of the room_with_doors scene (tests/support/door_scenes.h) as lbk bake writes them.
 * `bench_dls --quick` skips the baked levels. */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats, lbk_dls_runtime_path: experimental (lbk/dls.h) */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bake/pipeline/bake.h"
#include "bake/util/clock.h"
#include "bake/util/parallel.h"
#include "bake/util/rng.h"
#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/lightmap.h"
#include "lbk/sh.h"
/* The generators live with the tests; benches link the tools only, so take their source. */
#include "tests/support/dls_fixture.c"
#include "tests/support/door_scenes.c"

#define NSETS 132
#define ROOMS 116
#define PAGES 3

static const uint32_t page_w[PAGES] = {1024, 1024, 1024}, page_h[PAGES] = {1024, 1024, 528};
static const uint64_t T = 2637824, G = 229725, L = 50805;

/* ---- the synthetic level ------------------------------------------------------------------- */

typedef struct level {
    dlsfx fx;
    void *bytes;
    size_t size;
    lbk_dls_view *view;
    lbk_dls_stats st;
} level;

static uint64_t page_first(uint32_t p)
{
    uint64_t f = 0;
    for (uint32_t q = 0; q < p; q++) f += (uint64_t)page_w[q] * page_h[q];
    return f;
}

/* Marks a rectangle of page p in mark[] (one byte per texel). */
static void mark_rect(uint8_t *mark, uint32_t p, int x0, int y0, int w, int h)
{
    const int W = (int)page_w[p], H = (int)page_h[p];
    for (int y = y0 < 0 ? 0 : y0; y < y0 + h && y < H; y++)
        for (int x = x0 < 0 ? 0 : x0; x < x0 + w && x < W; x++) mark[page_first(p) + (uint64_t)y * W + x] = 1;
}

static void add_marked(dlsfx *fx, uint64_t *rng, uint32_t s, uint8_t *mark)
{
    for (uint64_t t = 0; t < T; t++)
        if (mark[t]) dlsfx_add(fx, rng, s, LBK_DLS_SPACE_TEXEL, (uint32_t)t), mark[t] = 0;
}

static void add_interval(dlsfx *fx, uint64_t *rng, uint32_t s, uint32_t sp, uint64_t n, int64_t centre, int64_t len,
                         uint8_t *mark)
{
    int64_t a = centre - len / 2, b = centre + len / 2;
    if (a < 0) a = 0;
    if (b > (int64_t)n) b = (int64_t)n;
    for (int64_t t = a; t < b; t++) mark[t] = 1;
    (void)rng, (void)fx, (void)s, (void)sp;
}

static void add_marked_probes(dlsfx *fx, uint64_t *rng, uint32_t s, uint32_t sp, uint64_t n, uint8_t *mark)
{
    for (uint64_t t = 0; t < n; t++)
        if (mark[t]) dlsfx_add(fx, rng, s, sp, (uint32_t)t), mark[t] = 0;
}

static int level_build(level *lv)
{
    uint64_t rng = 2024;
    dlsfx_init(&lv->fx, NSETS, T, G, L);
    uint8_t *mark = calloc(T, 1);
    for (uint32_t s = 0; s < NSETS; s++) {
        uint32_t p;
        int cx, cy, glg_len, llg_len, spread;
        if (s < ROOMS) {
            p = (uint32_t)(dlsfx_rand(&rng) % 5) / 2; /* pages 0, 0, 1, 1, 2: by area */
            cx = (int)(dlsfx_rand(&rng) % page_w[p]), cy = (int)(dlsfx_rand(&rng) % page_h[p]);
            const int charts = 10 + (int)(dlsfx_rand(&rng) % 7);
            for (int c = 0; c < charts; c++) {
                int w = 12 + (int)(dlsfx_rand(&rng) % 85), h = 12 + (int)(dlsfx_rand(&rng) % 85);
                int dx = (int)(dlsfx_rand(&rng) % 321) - 160, dy = (int)(dlsfx_rand(&rng) % 321) - 160;
                mark_rect(mark, p, cx + dx - w / 2, cy + dy - h / 2, w, h);
            }
            glg_len = 700 + (int)(dlsfx_rand(&rng) % 1500), llg_len = 100 + (int)(dlsfx_rand(&rng) % 300), spread = 2;
        } else { /* the hall: 256 × 200 texels of page 0, each set leaving out a corner */
            p = 0, cx = 728, cy = 200;
            int cut_w = (int)(dlsfx_rand(&rng) % 96), cut_h = (int)(dlsfx_rand(&rng) % 80);
            mark_rect(mark, 0, 600, 100, 256, 200);
            for (int y = 100; y < 100 + cut_h; y++)
                for (int x = 600; x < 600 + cut_w; x++) mark[(uint64_t)y * 1024 + x] = 0;
            glg_len = 3000, llg_len = 500, spread = 0;
        }
        add_marked(&lv->fx, &rng, s, mark);
        /* probes: the room's place in the level, as a position in probe order */
        const double at = (double)(page_first(p) + (uint64_t)cy * page_w[p] + (uint64_t)cx) / (double)T;
        for (int i = 0; i <= spread / 2; i++) {
            const int64_t off = spread ? (int64_t)(dlsfx_rand(&rng) % 4000) - 2000 : 0;
            add_interval(&lv->fx, &rng, s, 1, G, (int64_t)(at * (double)G) + off, glg_len, mark);
        }
        add_marked_probes(&lv->fx, &rng, s, LBK_DLS_SPACE_GLG, G, mark);
        for (int i = 0; i <= spread / 2; i++) {
            const int64_t off = spread ? (int64_t)(dlsfx_rand(&rng) % 600) - 300 : 0;
            add_interval(&lv->fx, &rng, s, 2, L, (int64_t)(at * (double)L) + off, llg_len, mark);
        }
        add_marked_probes(&lv->fx, &rng, s, LBK_DLS_SPACE_LLG, L, mark);
    }
    free(mark);
    const double t0 = bk_now();
    lbk_result r = lbk_dls_build(&lv->fx.desc, NULL, &lv->bytes, &lv->size, &lv->st);
    const double t_build = bk_now() - t0;
    if (r != LBK_OK || lbk_dls_open(lv->bytes, lv->size, NULL, &lv->view) != LBK_OK) {
        fprintf(stderr, "build failed: %s\n", lbk_result_name(r));
        return 1;
    }
    const lbk_dls_stats *st = &lv->st;
    uint64_t entries = st->entries[0] + st->entries[1] + st->entries[2];
    printf("level (ESTATE-sized): %llu texels in %d pages, %llu GLG, %llu LLG probes, %d sets, %llu entries (%.2f per "
           "target); DLS %.1f MB (payload %.1f MB, ancillary %.0f KB; seed: ~49 MB, ~132 KB); build %.2f s\n",
           (unsigned long long)T, PAGES, (unsigned long long)G, (unsigned long long)L, NSETS, (unsigned long long)entries,
           (double)entries / (double)(T + G + L), st->section_bytes / 1e6, st->payload_bytes / 1e6, st->ancillary_bytes / 1e3,
           t_build);
    printf("  clusters %u: dedicated %u, packed %u (%u sub-groups), prefix-2 %u, prefix-3 %u, prefix-8 %u\n", st->cluster_count,
           st->clusters_by_form[0], st->clusters_by_form[1], st->packed_subgroups, st->clusters_by_form[2],
           st->clusters_by_form[3], st->clusters_by_form[4]);
    printf("  texels by overlap (0, 1, 2, …, 16, more):");
    for (int b = 0; b < LBK_DLS_HISTOGRAM_BINS; b++) printf(" %llu", (unsigned long long)st->histogram[0][b]);
    printf("\n  texels by form: dedicated %.1f%%, packed %.2f%%, prefix %.2f%% of the touched\n",
           100.0 * (double)st->targets_by_form[0] / (double)(st->touched[0] + st->touched[1] + st->touched[2]),
           100.0 * (double)st->targets_by_form[1] / (double)(st->touched[0] + st->touched[1] + st->touched[2]),
           100.0 * (double)(st->targets_by_form[2] + st->targets_by_form[3] + st->targets_by_form[4]) /
               (double)(st->touched[0] + st->touched[1] + st->touched[2]));
    return 0;
}

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

/* Best of `reps` memcpys moving `traffic` bytes (a copy of traffic / 2) on `threads` threads. */
static clocks memcpy_time(uint64_t traffic, int threads, int reps)
{
    const size_t n = (size_t)(traffic / 2) + 64;
    uint8_t *src = malloc(n), *dst = malloc(n);
    memset(src, 1, n), memset(dst, 2, n);
    memcpy_job m = {dst, src, n};
    clocks best = {1e9, 1e9};
    for (int i = 0; i < reps; i++) {
        const clocks t0 = clocks_now();
        if (threads == 1) memcpy(dst, src, n);
        else bk_parallel_chunks(0, 16, 1, threads, memcpy_chunk, &m);
        clocks_best(&best, t0, threads);
    }
    free(src), free(dst);
    return best;
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
 * and output, and every entry it blends (all of them: every set is on in these scenarios). */
static uint64_t traffic(const lbk_dls_view *v, const float *w_old, const float *w_new)
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
        const uint64_t psize = ci.space == LBK_DLS_SPACE_TEXEL ? 8 : 28;
        if (changed) bytes += psize * (2 * (uint64_t)ci.target_count + ci.entry_count);
    }
    return bytes;
}

typedef struct scenario_result {
    clocks apply, copy;
    uint64_t bytes;
} scenario_result;

/* Every set's weight changes between applies (on, 0.5…0.6), or only set `one` (≥ 0). */
static int measure(lbk_dls_runtime *rt, const lbk_dls_view *v, uint32_t nsets, const float *dw, int one, int threads,
                   int reps, scenario_result *out)
{
    float w0[256], w1[256];
    out->apply = (clocks){1e9, 1e9};
    for (int i = 0; i < reps; i++) {
        for (uint32_t s = 0; s < nsets; s++) w0[s] = 0.5f + 0.01f * (float)(i % 7), w1[s] = w0[s] + 0.005f;
        if (one >= 0) {
            memcpy(w1, w0, nsets * sizeof *w0);
            w1[one] = 0.25f;
        }
        if (apply_threads(rt, w0, dw, threads) != LBK_OK) return 1; /* the previous frame */
        const clocks t0 = clocks_now();
        if (apply_threads(rt, w1, dw, threads) != LBK_OK) return 1;
        clocks_best(&out->apply, t0, threads);
        out->bytes = traffic(v, w0, w1);
    }
    out->copy = memcpy_time(out->bytes, threads, reps + 2);
    return 0;
}

/* Ratios to memcpy by wall time and by CPU time per thread. */
static void report(const char *what, int threads, const scenario_result *r)
{
    printf("  %-18s %d thread%s: %7.2f MB moved in %8.3f ms wall (%5.2f GB/s), %8.3f ms CPU/thread; memcpy of that "
           "traffic %7.3f ms wall, %7.3f ms CPU: %.3f of memcpy (wall), %.3f (CPU)\n",
           what, threads, threads > 1 ? "s" : " ", r->bytes / 1e6, r->apply.wall * 1e3, r->bytes / r->apply.wall / 1e9,
           r->apply.cpu * 1e3, r->copy.wall * 1e3, r->copy.cpu * 1e3, r->copy.wall / r->apply.wall, r->copy.cpu / r->apply.cpu);
}

/* ---- the synthetic level's applies --------------------------------------------------------- */

static int estate(void)
{
    level lv;
    memset(&lv, 0, sizeof lv);
    if (level_build(&lv)) return 1;
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
    for (uint32_t p = 0; p < PAGES; p++) {
        const uint64_t f = page_first(p);
        pages[p] = (lbk_dls_page){.width = page_w[p], .height = page_h[p], .base_irradiance = base0 + 4 * f,
                                  .base_rgba = base1 + 4 * f, .out_irradiance = out0 + 4 * f, .out_rgba = out1 + 4 * f};
    }
    int bad = 0;
    for (int path = 0; path < 2 && !bad; path++) {
        lbk_dls_runtime_desc d = {.size = sizeof d, .dls = lv.view, .base_glg = bg, .base_llg = bl, .out_glg = og,
                                  .out_llg = ol, .page_count = PAGES, .pages = pages,
                                  .flags = path ? LBK_DLS_RUNTIME_SCALAR : 0};
        lbk_dls_runtime *rt;
        if (lbk_dls_runtime_open(&d, &rt) != LBK_OK) return 1;
        printf(" path %s:\n", lbk_dls_runtime_path(rt));
        scenario_result r;
        for (int threads = 1; threads <= (path ? 1 : 2) && !bad; threads++) {
            bad |= measure(rt, lv.view, NSETS, NULL, -1, threads, path ? 1 : 4, &r);
            report("every set changes", threads, &r);
            if (path) break;
            bad |= measure(rt, lv.view, NSETS, NULL, 5, threads, 8, &r);
            report("one set changes", threads, &r);
        }
        uint32_t nranges = lbk_dls_dirty_range_count(rt, 0), nrects = 0;
        for (uint32_t p = 0; p < PAGES; p++) nrects += lbk_dls_dirty_rect_count(rt, p);
        if (!path) printf("  after the last apply: %u dirty texel ranges, %u rectangles over %d pages\n", nranges, nrects, PAGES);
        lbk_dls_runtime_close(rt);
    }
    free(base0), free(base1), free(out0), free(out1), free(bg), free(og), free(bl), free(ol);
    lbk_dls_close(lv.view);
    free(lv.bytes);
    dlsfx_free(&lv.fx);
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
    bk_bake_options bo;
    memset(&bo, 0, sizeof bo);
    bo.input = gltf, bo.output = path, bo.seed = 1, bo.target_error = 1e-9, bo.max_samples = 64;
    bk_progress pr;
    bk_progress_init(&pr, 1);
    bk_bake_summary sum;
    int rc = bk_bake(&bo, &pr, &sum, err, sizeof err);
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
    lbk_dls_runtime_desc rdsc = {.size = sizeof rdsc, .dls = dv, .doors = door, .base_glg = bg, .base_llg = bl,
                                 .out_glg = og, .out_llg = ol, .page_count = lm.page_count, .pages = pages};
    lbk_dls_runtime *rt;
    if (lbk_dls_runtime_open(&rdsc, &rt) != LBK_OK) return 1;
    lbk_dls_stats st;
    lbk_dls_stats_get(dv, &st);
    printf(" %s: %llu texels, %llu GLG + %llu LLG probes, %u sets, %u clusters, %.1f KB DLS\n", name,
           (unsigned long long)lm.texel_count, (unsigned long long)ng, (unsigned long long)nl, st.set_count, st.cluster_count,
           st.section_bytes / 1e3);
    const float dw[8] = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f};
    scenario_result r;
    bad |= measure(rt, dv, st.set_count, door ? dw : NULL, -1, 1, 50, &r);
    report("every set changes", 1, &r);
    bad |= measure(rt, dv, st.set_count, door ? dw : NULL, 0, 1, 50, &r);
    report("one set changes", 1, &r);
    lbk_dls_runtime_close(rt);
    for (uint32_t p = 0; p < 2 * lm.page_count; p++) free(outs[p]);
    free(outs), free(pages), free(bg), free(og), free(bl), free(ol);
    if (door) lbk_door_close(door);
    lbk_dls_close(dv);
    lbk_reader_close(rd);
    unlink(path);
    return bad;
}

int main(int argc, char **argv)
{
    const int quick = argc > 1 && !strcmp(argv[1], "--quick");
    int bad = estate();
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
