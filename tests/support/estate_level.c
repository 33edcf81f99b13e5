/* The ESTATE-sized synthetic level (estate_level.h). */
#include "estate_level.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

const uint32_t estate_page_w[ESTATE_PAGES] = {1024, 1024, 1024}, estate_page_h[ESTATE_PAGES] = {1024, 1024, 528};
#define T ESTATE_TEXELS
#define G ESTATE_GLG
#define L ESTATE_LLG
#define ROOMS 116

uint64_t estate_page_first(uint32_t p)
{
    uint64_t f = 0;
    for (uint32_t q = 0; q < p; q++) f += (uint64_t)estate_page_w[q] * estate_page_h[q];
    return f;
}

/* Marks a rectangle of page p in mark[] (one byte per texel). */
static void mark_rect(uint8_t *mark, uint32_t p, int x0, int y0, int w, int h)
{
    const int W = (int)estate_page_w[p], H = (int)estate_page_h[p];
    for (int y = y0 < 0 ? 0 : y0; y < y0 + h && y < H; y++)
        for (int x = x0 < 0 ? 0 : x0; x < x0 + w && x < W; x++) mark[estate_page_first(p) + (uint64_t)y * W + x] = 1;
}

static void mark_interval(uint8_t *mark, uint64_t n, int64_t centre, int64_t len)
{
    int64_t a = centre - len / 2, b = centre + len / 2;
    if (a < 0) a = 0;
    if (b > (int64_t)n) b = (int64_t)n;
    for (int64_t t = a; t < b; t++) mark[t] = 1;
}

/* The marked targets become set s's entries in space sp (random payloads); the marks are cleared. */
static void add_marked(dlsfx *fx, uint64_t *rng, uint32_t s, uint32_t sp, uint64_t n, uint8_t *mark)
{
    for (uint64_t t = 0; t < n; t++)
        if (mark[t]) dlsfx_add(fx, rng, s, sp, (uint32_t)t), mark[t] = 0;
}

int estate_build(estate_level *lv)
{
    memset(lv, 0, sizeof *lv);
    uint64_t rng = 2024;
    dlsfx_init(&lv->fx, ESTATE_SETS, T, G, L);
    uint8_t *mark = calloc(T, 1);
    if (!mark) return 1;
    for (uint32_t s = 0; s < ESTATE_SETS; s++) {
        uint32_t p;
        int cx, cy, glg_len, llg_len, spread;
        if (s < ROOMS) {
            p = (uint32_t)(dlsfx_rand(&rng) % 5) / 2; /* pages 0, 0, 1, 1, 2: by area */
            cx = (int)(dlsfx_rand(&rng) % estate_page_w[p]), cy = (int)(dlsfx_rand(&rng) % estate_page_h[p]);
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
        add_marked(&lv->fx, &rng, s, LBK_DLS_SPACE_TEXEL, T, mark);
        /* probes: the room's place in the level, as a position in probe order */
        const double at = (double)(estate_page_first(p) + (uint64_t)cy * estate_page_w[p] + (uint64_t)cx) / (double)T;
        for (int i = 0; i <= spread / 2; i++) {
            const int64_t off = spread ? (int64_t)(dlsfx_rand(&rng) % 4000) - 2000 : 0;
            mark_interval(mark, G, (int64_t)(at * (double)G) + off, glg_len);
        }
        add_marked(&lv->fx, &rng, s, LBK_DLS_SPACE_GLG, G, mark);
        for (int i = 0; i <= spread / 2; i++) {
            const int64_t off = spread ? (int64_t)(dlsfx_rand(&rng) % 600) - 300 : 0;
            mark_interval(mark, L, (int64_t)(at * (double)L) + off, llg_len);
        }
        add_marked(&lv->fx, &rng, s, LBK_DLS_SPACE_LLG, L, mark);
    }
    free(mark);
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    lbk_result r = lbk_dls_build(&lv->fx.desc, NULL, &lv->bytes, &lv->size, &lv->st);
    clock_gettime(CLOCK_MONOTONIC, &b);
    lv->build_seconds = (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec);
    if (r != LBK_OK || lbk_dls_open(lv->bytes, lv->size, NULL, &lv->view) != LBK_OK) {
        fprintf(stderr, "ESTATE level: build failed: %s\n", lbk_result_name(r));
        return 1;
    }
    return 0;
}

void estate_free(estate_level *lv)
{
    lbk_dls_close(lv->view);
    free(lv->bytes);
    dlsfx_free(&lv->fx);
}

void estate_describe(const estate_level *lv)
{
    const lbk_dls_stats *st = &lv->st;
    const uint64_t entries = st->entries[0] + st->entries[1] + st->entries[2];
    const uint64_t touched = st->touched[0] + st->touched[1] + st->touched[2];
    printf("level (ESTATE-sized): %u texels in %d pages, %u GLG, %u LLG probes, %d sets, %llu entries (%.2f per "
           "target); DLS %.1f MB (payload %.1f MB, ancillary %.0f KB; seed: ~49 MB, ~132 KB); build %.2f s\n",
           T, ESTATE_PAGES, G, L, ESTATE_SETS, (unsigned long long)entries, (double)entries / (double)(T + G + L),
           st->section_bytes / 1e6, st->payload_bytes / 1e6, st->ancillary_bytes / 1e3, lv->build_seconds);
    printf("  clusters %u: dedicated %u, packed %u (%u sub-groups), prefix-2 %u, prefix-3 %u, prefix-8 %u\n", st->cluster_count,
           st->clusters_by_form[0], st->clusters_by_form[1], st->packed_subgroups, st->clusters_by_form[2],
           st->clusters_by_form[3], st->clusters_by_form[4]);
    printf("  texels by overlap (0, 1, 2, …, 16, more):");
    for (int b = 0; b < LBK_DLS_HISTOGRAM_BINS; b++) printf(" %llu", (unsigned long long)st->histogram[0][b]);
    printf("\n  touched targets by form: dedicated %.1f%%, packed %.2f%%, prefix %.2f%%\n",
           100.0 * (double)st->targets_by_form[0] / (double)touched, 100.0 * (double)st->targets_by_form[1] / (double)touched,
           100.0 * (double)(st->targets_by_form[2] + st->targets_by_form[3] + st->targets_by_form[4]) / (double)touched);
}
