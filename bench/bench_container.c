/* Container benchmarks (printed, never asserted):
 *  1. load throughput of a ~50 MB container (a real LMAP of 6.25 M texels plus META/OBJS):
 *     uncompressed, open + checksum + validation next to memcpy of the same bytes (goal: within
 *     20 %; an uncompressed LMAP is checksummed and its texels block-tested in one pass over
 *     memory, libformat/src/lightmap.c lbk_lmap_hash_prescan, with xxHash's AVX2 dispatch and AVX2
 *     block tests where the CPU has them); zstd levels 3 and 19, the section's decode next to libzstd decoding the same frame in
 *     the same run (goal: at least 80 % of its speed);
 *  2. non-payload overhead of a container with 1 M lightmap texels (8 MB of planes) and 100 k
 *     SH9 probes (2.8 MB, as LLG grids), with META, REPT and OBJS: goal < 0.5 % of the file. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/report.h"
#include "lbk/validate.h"

#include "scene/clock.h"

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

static volatile uint8_t sink;
static int only_uncompressed;

/* A loader that trusts nothing: open, validate through the reader (each section checksummed and
 * decoded once), then take every section's bytes (cached: free). */
static double load_validated(const void *file, size_t size, unsigned *issues)
{
    double t0 = bk_now();
    lbk_reader *r;
    CHECK(lbk_reader_open_memory(file, size, NULL, &r));
    lbk_validate_summary s;
    *issues = 0;
    CHECK(lbk_reader_validate(r, count_issues, issues, &s));
    for (uint32_t i = 0; i < lbk_reader_section_count(r); i++) {
        const void *d;
        size_t n;
        CHECK(lbk_reader_section_data(r, i, &d, &n));
        sink ^= ((const uint8_t *)d)[n - 1];
    }
    lbk_reader_close(r);
    return bk_now() - t0;
}

/* The section's decoded bytes only (open + checksum + decode, no content validation), into memory
 * the reader allocates (dst NULL) or into a caller buffer (lbk_reader_section_unpack). */
static double load_section(const void *file, size_t size, uint32_t type, void *dst, size_t dst_size)
{
    double t0 = bk_now();
    lbk_reader *r;
    CHECK(lbk_reader_open_memory(file, size, NULL, &r));
    uint32_t i;
    CHECK(lbk_reader_section_find(r, type, &i));
    if (dst) {
        CHECK(lbk_reader_section_unpack(r, i, dst, dst_size));
        sink ^= ((const uint8_t *)dst)[dst_size - 1];
    } else {
        const void *d;
        size_t n;
        CHECK(lbk_reader_section_data(r, i, &d, &n));
        sink ^= ((const uint8_t *)d)[n - 1];
    }
    lbk_reader_close(r);
    return bk_now() - t0;
}

/* libzstd on the same frame, in the same run: into a fresh allocation (what a loader that
 * allocates pays, page faults included) or into a reused buffer (zstd's own speed). */
static double zstd_once(const void *frame, size_t frame_size, void *dst, size_t n)
{
    double t0 = bk_now();
    void *out = dst ? dst : malloc(n);
    ZSTD_DCtx *dctx = ZSTD_createDCtx();
    size_t got = ZSTD_decompressDCtx(dctx, out, n, frame, frame_size);
    ZSTD_freeDCtx(dctx);
    if (ZSTD_isError(got) || got != n) {
        fprintf(stderr, "bench_container: zstd failed\n");
        exit(1);
    }
    sink ^= ((uint8_t *)out)[n - 1];
    if (!dst) free(out);
    return bk_now() - t0;
}

static double memcpy_once(void *dst, const void *src, size_t n)
{
    double t0 = bk_now();
    memcpy(dst, src, n);
    sink ^= ((uint8_t *)dst)[n / 2];
    return bk_now() - t0;
}

static double best(double a, double b) { return a < b ? a : b; }

static void throughput(void)
{
    void *lmap, *meta, *rept, *objs;
    size_t lmap_n, meta_n, rept_n, objs_n;
    build_lmap(4, 1250, &lmap, &lmap_n); /* 6.25 M texels, 50 MB of planes */
    build_small_sections(1024, &meta, &meta_n, &rept, &rept_n, &objs, &objs_n, 0, 32, 32);
    const size_t decoded = meta_n + rept_n + objs_n + lmap_n;
    printf("throughput: loading a %.1f MB container (4 LMAP pages 1250x1250, META, REPT, OBJS), best of 25 (uncompressed) and 7 (zstd) runs\n",
           (double)decoded / 1e6);
    void *dst = malloc(decoded), *dst2 = malloc(lmap_n);
    memset(dst, 1, decoded);
    memset(dst2, 1, lmap_n);
    const int levels[3] = {0, 3, 19};
    for (int v = 0; v < (only_uncompressed ? 1 : 3); v++) {
        lbk_writer *w;
        CHECK(lbk_writer_open(NULL, &w));
        lbk_section_options o = {.flags = LBK_SECTION_FLAG_REQUIRED,
            .compression = levels[v] ? LBK_COMPRESSION_ZSTD : 0, .zstd_level = levels[v]};
        CHECK(lbk_writer_section_add(w, LBK_SECTION_META, meta, meta_n, NULL));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_REPT, rept, rept_n, NULL));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_OBJS, objs, objs_n, &o));
        CHECK(lbk_writer_section_add(w, LBK_SECTION_LMAP, lmap, lmap_n, &o));
        void *file;
        size_t size;
        CHECK(lbk_writer_to_memory(w, &file, &size));
        lbk_writer_close(w);
        lbk_reader *r;
        lbk_section_info si;
        uint32_t li;
        CHECK(lbk_reader_open_memory(file, size, NULL, &r));
        CHECK(lbk_reader_section_find(r, LBK_SECTION_LMAP, &li));
        CHECK(lbk_reader_section_get(r, li, &si));
        lbk_reader_close(r);
        const uint8_t *frame = (const uint8_t *)file + si.offset;
        double t_valid = 1e9, t_copy = 1e9, t_sec = 1e9, t_unpack = 1e9, t_zf = 1e9, t_zr = 1e9;
        unsigned issues = 0;
        for (int rep = 0; rep < (levels[v] ? 7 : 25); rep++) {
            t_valid = best(t_valid, load_validated(file, size, &issues));
            if (!levels[v]) t_copy = best(t_copy, memcpy_once(dst, file, size < decoded ? size : decoded));
            t_sec = best(t_sec, load_section(file, size, LBK_SECTION_LMAP, NULL, 0));
            t_unpack = best(t_unpack, load_section(file, size, LBK_SECTION_LMAP, dst2, lmap_n));
            if (levels[v]) {
                t_zf = best(t_zf, zstd_once(frame, (size_t)si.stored_size, NULL, lmap_n));
                t_zr = best(t_zr, zstd_once(frame, (size_t)si.stored_size, dst2, lmap_n));
            }
        }
        const double gbs = 1e-9;
        if (!levels[v]) {
            printf("  uncompressed (%.1f MB): open + checksum + validate %.2f GB/s (%.1f ms), memcpy %.2f GB/s (%.1f ms),"
                   " issues %u\n", (double)size / 1e6, gbs * decoded / t_valid, 1e3 * t_valid, gbs * decoded / t_copy,
                   1e3 * t_copy, issues);
            printf("    ratio checksum+validation / memcpy = %.2f   (goal <= 1.20)\n", t_valid / t_copy);
        } else {
            printf("  zstd level %d (%.1f MB, LMAP ratio %.2f): LMAP section %.2f GB/s, libzstd same frame %.2f GB/s"
                   " (fresh buffer);\n    unpack into caller memory %.2f GB/s, libzstd into a reused buffer %.2f GB/s;"
                   " whole file validated %.2f GB/s, issues %u\n",
                   levels[v], (double)size / 1e6, (double)lmap_n / (double)si.stored_size, gbs * lmap_n / t_sec,
                   gbs * lmap_n / t_zf, gbs * lmap_n / t_unpack, gbs * lmap_n / t_zr, gbs * decoded / t_valid, issues);
            printf("    ratio lbk / libzstd = %.2f (fresh buffer), %.2f (caller buffer)   (goal >= 0.80)\n", t_zf / t_sec,
                   t_zr / t_unpack);
        }
        lbk_free(NULL, file);
    }
    printf("  (validate = lbk_reader_open_memory + lbk_reader_validate + every lbk_reader_section_data;\n"
           "   section = open + lbk_reader_section_data (checksum + decode); unpack = lbk_reader_section_unpack;\n"
           "   GB/s of decoded bytes; the zstd goal of 1 GB/s per core depends on the machine and the data:\n"
           "   this data is noisy on purpose, real bakes compress better and decode faster)\n\n");
    free(dst);
    free(dst2);
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

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "--uncompressed")) { /* for profiling the validation alone */
        only_uncompressed = 1;
        throughput();
        return 0;
    }
    throughput();
    overhead();
    return 0;
}
