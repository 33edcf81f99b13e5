/* Container benchmarks (printed, never asserted):
 *  1. open + validate + decode throughput of a ~50 MB container (a real LMAP of 6.25 M texels
 *     plus META/OBJS), uncompressed and zstd, next to memcpy of the same bytes in the same run;
 *  2. non-payload overhead of a container with 1 M lightmap texels (8 MB of planes) and 100 k
 *     SH9 probes (2.8 MB, as LLG grids), with META, REPT and OBJS: goal < 0.5 % of the file. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/report.h"
#include "lbk/validate.h"

#include "bake/util/clock.h"

static uint32_t rng_state = 12345;
static uint32_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return rng_state;
}

#define CHECK(x)                                                                        \
    do {                                                                                \
        lbk_result r_ = (x);                                                            \
        if (r_ != LBK_OK) {                                                             \
            fprintf(stderr, "bench_container: %s failed: %s\n", #x, lbk_result_name(r_)); \
            exit(1);                                                                    \
        }                                                                               \
    } while (0)

/* Smooth lighting with noise in the low mantissa bits: finite R11G11B10F (exponents ≤ 15),
 * highlight direction near +Z. Compresses about as well as a real bake's pages. */
static void fill_texels(lbk_ahd_texel *t, uint32_t w, uint32_t h)
{
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint32_t e = 8 + ((x / 64 + y / 64) & 7), noise = rnd();
            uint32_t r = e << 6 | (noise & 0x3f), g = e << 6 | ((noise >> 6) & 0x3f), b = e << 5 | ((noise >> 12) & 0x1f);
            t[(size_t)y * w + x] = (lbk_ahd_texel){r | g << 11 | b << 22,
                                                   {(uint8_t)(100 + (noise >> 24) % 100), 128, 128, 255}};
        }
}

static void build_lmap(uint32_t pages, uint32_t side, void **out, size_t *size)
{
    lbk_ahd_texel *t = malloc(sizeof *t * side * side);
    fill_texels(t, side, side);
    lbk_lmap_page_desc *p = malloc(sizeof *p * pages);
    for (uint32_t i = 0; i < pages; i++) p[i] = (lbk_lmap_page_desc){side, side, t};
    CHECK(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = p, .page_count = pages}, NULL, out, size));
    free(p);
    free(t);
}

/* META, REPT (16 records) and OBJS: llg_grids LLG objects, then lightmapped objects with
 * chart×chart charts tiling page 0 row by row (per_row charts per row). */
static void build_small_sections(uint32_t objects, void **meta, size_t *meta_n, void **rept, size_t *rept_n,
                                 void **objs, size_t *objs_n, uint32_t llg_grids, uint32_t chart, uint32_t per_row)
{
    const lbk_meta_pair pairs[] = {{"writer", "lbk"}, {"writer.version", LBK_LIBRARY_VERSION_STRING},
                                   {"scene.hash", "0123456789abcdef"}, {"bake.seed", "1"},
                                   {"bake.preset", "high"}, {"bake.target_error", "0.02"}};
    CHECK(lbk_meta_build(pairs, 6, NULL, meta, meta_n));
    lbk_report_record rec[16];
    for (int i = 0; i < 16; i++)
        rec[i] = (lbk_report_record){0, (uint64_t)(i + 1) << 24, (uint32_t)(i + 1) * 16, 3, 0.5f / (float)(i + 1),
                                     0.4f / (float)(i + 1)};
    lbk_report rep = {.status = LBK_BAKE_TARGET_REACHED, .max_samples_per_texel = 1024, .target_rel_rmse = 0.04f,
        .records = rec, .record_count = 16};
    CHECK(lbk_report_build(&rep, NULL, rept, rept_n));
    lbk_object *o = calloc(objects, sizeof *o);
    char (*names)[32] = calloc(objects, 32);
    for (uint32_t i = 0; i < objects; i++) {
        int n = snprintf(names[i], 32, "object_%05u", i);
        o[i].name = (lbk_string){names[i], (size_t)n};
        o[i].geometry_hash = (uint64_t)rnd() << 32 | rnd();
        if (i < llg_grids) {
            o[i].representation = LBK_REPRESENTATION_LLG;
            o[i].index = i;
        } else {
            o[i].representation = LBK_REPRESENTATION_LIGHTMAP;
            uint32_t k = i - llg_grids;
            o[i].rect_x = (k % per_row) * chart;
            o[i].rect_y = (k / per_row) * chart;
            o[i].rect_w = o[i].rect_h = chart;
        }
    }
    CHECK(lbk_objects_build(o, objects, NULL, objs, objs_n));
    free(o);
    free(names);
}

static int count_issues(void *user, const lbk_issue *issue)
{
    (void)issue;
    ++*(unsigned *)user;
    return 0;
}

/* validate, then open + decode every section; returns total seconds, *validate_s the first part. */
static double load_once(const void *file, size_t size, unsigned *issues, double *validate_s)
{
    double t0 = bk_now();
    lbk_validate_summary s;
    *issues = 0;
    CHECK(lbk_validate_memory(file, size, NULL, count_issues, issues, &s));
    *validate_s = bk_now() - t0;
    lbk_reader *r;
    CHECK(lbk_reader_open_memory(file, size, NULL, &r));
    volatile uint8_t sink = 0;
    for (uint32_t i = 0; i < lbk_reader_section_count(r); i++) {
        const void *d;
        size_t n;
        CHECK(lbk_reader_section_data(r, i, &d, &n));
        sink ^= ((const uint8_t *)d)[n - 1];
    }
    lbk_reader_close(r);
    (void)sink;
    return bk_now() - t0;
}

static double memcpy_once(void *dst, const void *src, size_t n)
{
    double t0 = bk_now();
    memcpy(dst, src, n);
    volatile uint8_t sink = ((uint8_t *)dst)[n / 2];
    (void)sink;
    return bk_now() - t0;
}

static void throughput(void)
{
    void *lmap, *meta, *rept, *objs;
    size_t lmap_n, meta_n, rept_n, objs_n;
    build_lmap(4, 1250, &lmap, &lmap_n); /* 6.25 M texels, 50 MB of planes */
    build_small_sections(1024, &meta, &meta_n, &rept, &rept_n, &objs, &objs_n, 0, 32, 32);
    printf("throughput: open + validate + decode of a %.1f MB container (4 LMAP pages 1250x1250, META, REPT, OBJS)\n",
           (double)(lmap_n + meta_n + rept_n + objs_n) / 1e6);
    printf("  %-18s %10s %10s %12s %12s %10s %8s\n", "variant", "file MB", "decoded MB", "load GB/s", "memcpy GB/s",
           "ratio", "issues");
    for (int zstd = 0; zstd < 2; zstd++) {
        lbk_writer *w;
        CHECK(lbk_writer_open(NULL, &w));
        lbk_section_options o = {.flags = LBK_SECTION_FLAG_REQUIRED, .compression = zstd ? LBK_COMPRESSION_ZSTD : 0,
            .zstd_level = 3};
        CHECK(lbk_writer_section_add(w, LBK_SECTION_META, meta, meta_n, NULL));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_REPT, rept, rept_n, NULL));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_OBJS, objs, objs_n, &o));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_LMAP, lmap, lmap_n, &o));
        void *file;
        size_t size;
        CHECK(lbk_writer_to_memory(w, &file, &size));
        lbk_writer_close(w);
        size_t decoded = meta_n + rept_n + objs_n + lmap_n;
        void *dst = malloc(decoded);
        memset(dst, 1, decoded);
        double best_load = 1e9, best_copy = 1e9, best_validate = 1e9;
        unsigned issues = 0;
        for (int rep = 0; rep < 5; rep++) {
            double v;
            double t = load_once(file, size, &issues, &v);
            if (t < best_load) best_load = t;
            if (v < best_validate) best_validate = v;
            t = memcpy_once(dst, lmap, lmap_n);
            if (t < best_copy) best_copy = t;
        }
        double load_gbs = (double)decoded / best_load / 1e9, copy_gbs = (double)lmap_n / best_copy / 1e9;
        printf("  %-18s %10.1f %10.1f %12.2f %12.2f %9.2fx %8u   (validate %.0f ms, open+decode %.0f ms)\n",
               zstd ? "zstd level 3" : "uncompressed", (double)size / 1e6, (double)decoded / 1e6, load_gbs, copy_gbs,
               copy_gbs / load_gbs, issues, 1e3 * best_validate, 1e3 * (best_load - best_validate));
        free(dst);
        lbk_free(NULL, file);
    }
    printf("  (load GB/s = decoded bytes / time of lbk_validate_memory + lbk_reader_open_memory + every\n"
           "   lbk_reader_section_data; best of 5; ratio = how many times slower than memcpy)\n\n");
    lbk_free(NULL, lmap);
    lbk_free(NULL, meta);
    lbk_free(NULL, rept);
    lbk_free(NULL, objs);
}

static void overhead_row(const char *label, void *lmap, size_t lmap_n, void *llg, size_t llg_n, uint32_t objects,
                         uint32_t grids, uint32_t chart, uint32_t per_row, uint64_t texels, uint64_t probe_count)
{
    void *meta = NULL, *rept = NULL, *objs = NULL;
    size_t meta_n = 0, rept_n = 0, objs_n = 0;
    if (objects) build_small_sections(objects, &meta, &meta_n, &rept, &rept_n, &objs, &objs_n, grids, chart, per_row);
    lbk_writer *w;
    CHECK(lbk_writer_open(NULL, &w));
    CHECK(lbk_writer_section_add(w, LBK_SECTION_LMAP, lmap, lmap_n, NULL));
    CHECK(lbk_writer_section_add(w, LBK_SECTION_LLG, llg, llg_n, NULL));
    if (objects) {
        CHECK(lbk_writer_section_add(w, LBK_SECTION_META, meta, meta_n, NULL));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_REPT, rept, rept_n, NULL));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_OBJS, objs, objs_n, NULL));
    }
    void *file;
    size_t size;
    CHECK(lbk_writer_to_memory(w, &file, &size));
    lbk_writer_close(w);
    lbk_validate_summary s;
    CHECK(lbk_validate_memory(file, size, NULL, NULL, NULL, &s));
    const uint64_t payload = texels * 8 + probe_count * 28;
    uint32_t n = objects ? 5 : 2;
    uint64_t framing = 64 + 48 * n, sections = lmap_n + llg_n + meta_n + rept_n + objs_n;
    printf("  %s: file %zu bytes, valid %s\n", label, size, s.fatal + s.errors ? "NO" : "yes");
    printf("    header+table %llu, padding %llu, LMAP structure %llu, LLG structure %llu",
           (unsigned long long)framing, (unsigned long long)(size - framing - sections),
           (unsigned long long)(lmap_n - texels * 8), (unsigned long long)(llg_n - probe_count * 28));
    if (objects) printf(", META %zu, REPT %zu, OBJS %zu (%u objects)", meta_n, rept_n, objs_n, objects);
    printf("\n    non-payload %llu bytes = %.4f %% of the file (goal < 0.5 %%)\n",
           (unsigned long long)(size - payload), 100.0 * (double)(size - payload) / (double)size);
    lbk_free(NULL, file);
    lbk_free(NULL, meta);
    lbk_free(NULL, rept);
    lbk_free(NULL, objs);
}

static void overhead(void)
{
    /* 1 M texels: one 1024×1024 page. 100 k probes: 100 LLG grids of 10×10×10. */
    void *lmap, *llg;
    size_t lmap_n, llg_n;
    build_lmap(1, 1024, &lmap, &lmap_n);
    enum { GRIDS = 100, DIM = 10 };
    lbk_sh9_rgb *probes = calloc(DIM * DIM * DIM, sizeof *probes);
    for (int i = 0; i < DIM * DIM * DIM; i++)
        for (int c = 0; c < 3; c++) probes[i].c[c][0] = 1.0f + 0.001f * (float)i;
    lbk_llg_grid_desc g[GRIDS];
    for (int i = 0; i < GRIDS; i++)
        g[i] = (lbk_llg_grid_desc){{(float)i, 0, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {1, 1, 1},
                                   {DIM, DIM, DIM}, probes, NULL, 0};
    CHECK(lbk_llg_build(&(lbk_llg_build_desc){.grids = g, .grid_count = GRIDS}, NULL, &llg, &llg_n));
    free(probes);
    const uint64_t texels = 1024 * 1024, probe_count = GRIDS * DIM * DIM * DIM;
    printf("overhead: 1,048,576 texels (8 B each) + %llu SH9 probes (28 B each) = %.3f MB of payload\n",
           (unsigned long long)probe_count, (double)(texels * 8 + probe_count * 28) / 1e6);
    overhead_row("LMAP + LLG (framing and section structure only)", lmap, lmap_n, llg, llg_n, 0, GRIDS, 0, 0, texels,
                 probe_count);
    overhead_row("+ META, REPT, OBJS with 100 LLG + 256 lightmapped objects (64x64 charts)", lmap, lmap_n, llg, llg_n,
                 GRIDS + 256, GRIDS, 64, 16, texels, probe_count);
    overhead_row("+ META, REPT, OBJS with 100 LLG + 4096 lightmapped objects (16x16 charts: OBJS is 52 B/object)",
                 lmap, lmap_n, llg, llg_n, GRIDS + 4096, GRIDS, 16, 64, texels, probe_count);
    lbk_free(NULL, lmap);
    lbk_free(NULL, llg);
}

int main(void)
{
    throughput();
    overhead();
    return 0;
}
