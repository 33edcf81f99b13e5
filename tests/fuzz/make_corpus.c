/* Writes the seed corpus of fuzz_container into tests/fuzz/corpus (run once by hand; the files
 * are committed). Besides copies of the golden files it writes containers with an object table
 * that references a real LMAP and LLG, raw and zstd, so the fuzzer starts from inputs that reach
 * the cross-section checks, and a DLS + DOOR container with clusters of every form (the runtime
 * runs on it):
 *   cc -std=c11 -Ilibformat/include tests/fuzz/make_corpus.c build/liblbk.a -lzstd -lxxhash -lm \
 *      -o /tmp/make_corpus && /tmp/make_corpus */
#include <stdio.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/report.h"

static int write_file(const char *path, const void *d, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(d, 1, n, f) != n) return 1;
    return fclose(f) != 0;
}

/* 24 sets over 600 texels and 64 + 64 probes: a wide single-set region (dedicated), small
 * combinations of 1–4 sets (packed), and a corner where 6, 12 and 20 sets overlap (prefix-2, -3,
 * -8); set 1 a door's open set, 2 its bounce, 23 the combination {0, 1}. */
static int write_dls(void)
{
    enum { NSETS = 24, T = 600, G = 64, L = 64 };
    static uint32_t targets[NSETS][3][T];
    static uint8_t payloads[NSETS][3][T * 28];
    static lbk_dls_set_desc sets[NSETS];
    static char names[NSETS][8];
    const uint32_t count[3] = {T, G, L};
    uint32_t rng = 12345;
    for (uint32_t s = 0; s < NSETS; s++) {
        snprintf(names[s], sizeof names[s], "s%u", s);
        sets[s].name = names[s];
        for (uint32_t sp = 0; sp < 3; sp++) {
            uint32_t n = 0;
            for (uint32_t t = 0; t < count[sp]; t++) {
                rng = rng * 1664525u + 1013904223u;
                const int wide = s == 0 && t < count[sp] / 2;              /* set 0 alone: dedicated */
                const int small = s < 8 && (rng >> 28) == s % 4 + 1;       /* scattered small combinations */
                const int deep = t >= count[sp] - 20 && (s < 6 + (count[sp] - t) % 3 * 7); /* 6, 13, 20 deep */
                if (!(wide || small || deep)) continue;
                targets[s][sp][n] = t;
                uint8_t *p = payloads[s][sp] + (size_t)n * (sp ? 28 : 8);
                for (uint32_t b = 0; b < (sp ? 28u : 8u); b++) p[b] = (uint8_t)(rng >> (b % 24));
                if (sp == 0) p[1] &= 0xfb, p[2] &= 0xdf, p[3] &= 0x7f; /* no exponent-31 channel in Ez (rule 850) */
                n++;
            }
            sets[s].entries[sp] = (lbk_dls_sparse){n, targets[s][sp], payloads[s][sp]};
        }
    }
    sets[1].kind = LBK_DLS_KIND_DOOR_OPEN;
    sets[2].kind = LBK_DLS_KIND_DOOR_CLOSED;
    static const uint32_t members[2] = {0, 1};
    sets[NSETS - 1].kind = LBK_DLS_KIND_COMBINATION, sets[NSETS - 1].member_count = 2, sets[NSETS - 1].members = members;
    lbk_dls_build_desc dd = {.set_count = NSETS, .sets = sets, .target_count = {T, G, L}};
    const lbk_door_desc door = {.name = "door", .axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, .half_extents = {1, 1, 0.1f},
                                .open_set = 1, .closed_set = 2};
    const uint32_t door0 = 0;
    const lbk_door_state_desc state = {1, &door0, NSETS - 1};
    const lbk_door_build_desc od = {.door_count = 1, .doors = &door, .state_count = 1, .states = &state};
    void *dls, *dr, *bytes;
    size_t dn, drn, n;
    lbk_writer *w;
    if (lbk_dls_build(&dd, NULL, &dls, &dn, NULL) || lbk_door_build(&od, NULL, &dr, &drn) || lbk_writer_open(NULL, &w) ||
        lbk_writer_section_add(w, LBK_SECTION_DLS, dls, dn, NULL) || lbk_writer_section_add(w, LBK_SECTION_DOOR, dr, drn, NULL) ||
        lbk_writer_to_memory(w, &bytes, &n))
        return 1;
    int r = write_file("tests/fuzz/corpus/dls.lbk", bytes, n);
    lbk_free(NULL, bytes), lbk_free(NULL, dls), lbk_free(NULL, dr);
    lbk_writer_close(w);
    return r;
}

int main(void)
{
    static lbk_ahd_texel texels[8 * 4];
    for (int i = 0; i < 8 * 4; i++) texels[i] = (lbk_ahd_texel){0x3c00u + (uint32_t)i, {200, 128, 128, 255}};
    lbk_lmap_page_desc pages[2] = {{8, 4, texels}, {4, 4, texels}};
    static lbk_sh9_rgb probes[8];
    for (int i = 0; i < 8; i++) probes[i].c[0][0] = probes[i].c[1][0] = probes[i].c[2][0] = 1.0f + (float)i;
    lbk_llg_vertex verts[3] = {{1, {0, 0, 1}}, {0.5f, {0, 1, 0}}, {0.25f, {1, 0, 0}}};
    lbk_llg_grid_desc grid = {{0, 1, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {1, 2, 1}, {2, 2, 2}, probes, verts, 3};
    const lbk_object objs[3] = {
        {{"floor", 5}, 11, LBK_REPRESENTATION_LIGHTMAP, 0, 0, 0, 8, 4},
        {{"wall", 4}, 12, LBK_REPRESENTATION_LIGHTMAP, 1, 0, 0, 4, 2},
        {{"chair", 5}, 13, LBK_REPRESENTATION_LLG, 0, 0, 0, 0, 0},
    };
    const lbk_meta_pair meta[2] = {{"writer", "make_corpus"}, {"writer.version", "1"}};
    const lbk_report_record rec[2] = {{0, 10, 1, 1, 0.5f, 0.5f}, {0, 20, 2, 1, 0.25f, 0.3f}};
    const lbk_report rep = {.status = LBK_BAKE_SAMPLE_LIMIT, .max_samples_per_texel = 2, .records = rec,
        .record_count = 2};
    void *lm, *llg, *ob, *me, *re;
    size_t lmn, llgn, obn, men, ren;
    if (lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages, .page_count = 2}, NULL, &lm, &lmn) ||
        lbk_llg_build(&(lbk_llg_build_desc){.grids = &grid, .grid_count = 1}, NULL, &llg, &llgn) ||
        lbk_objects_build(objs, 3, NULL, &ob, &obn) || lbk_meta_build(meta, 2, NULL, &me, &men) ||
        lbk_report_build(&rep, NULL, &re, &ren))
        return 1;
    for (int zstd = 0; zstd < 2; zstd++) {
        lbk_writer *w;
        lbk_write_options wo = {.section_alignment = zstd ? 16 : 64};
        lbk_section_options o = {.flags = LBK_SECTION_FLAG_REQUIRED, .compression = zstd ? LBK_COMPRESSION_ZSTD : 0,
            .zstd_level = 3};
        if (lbk_writer_open(&wo, &w) || lbk_writer_section_add(w, LBK_SECTION_META, me, men, NULL) ||
            lbk_writer_section_add(w, LBK_SECTION_REPT, re, ren, &o) ||
            lbk_writer_section_add(w, LBK_SECTION_OBJS, ob, obn, &o) ||
            lbk_writer_section_add(w, LBK_SECTION_LMAP, lm, lmn, &o) ||
            lbk_writer_section_add(w, LBK_SECTION_LLG, llg, llgn, &o))
            return 1;
        void *bytes;
        size_t n;
        if (lbk_writer_to_memory(w, &bytes, &n)) return 1;
        if (write_file(zstd ? "tests/fuzz/corpus/objects_zstd.lbk" : "tests/fuzz/corpus/objects_raw.lbk", bytes, n))
            return 1;
        lbk_free(NULL, bytes);
        lbk_writer_close(w);
    }
    return write_dls();
}
