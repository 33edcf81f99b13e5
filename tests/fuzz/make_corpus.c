/* Writes the seed corpus of fuzz_container into tests/fuzz/corpus (run once by hand; the files
 * are committed). Besides copies of the golden files it writes containers with an object table
 * that references a real LMAP and LLG, raw and zstd, so the fuzzer starts from inputs that reach
 * the cross-section checks (lmuv_raw.lbk: also a 1.1 LMUV section, authored and generated):
 *   cc -std=c11 -Ilibformat/include tests/fuzz/make_corpus.c build/liblbk.a -lzstd -lxxhash -lm \
 *      -o /tmp/make_corpus && /tmp/make_corpus */
#include <stdio.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/lightmap_uv.h"
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
    /* floor (object 0, rect 0,0 8x4): generated, two primitives; wall (object 1, rect 0,0 4x2
     * on page 1): authored */
    const uint32_t remap[4] = {0, 1, 2, 3}, idx[6] = {0, 1, 2, 0, 2, 3}, idx1[3] = {0, 1, 2};
    const float xy[8] = {0.5f, 0.5f, 7.5f, 0.5f, 7.5f, 3.5f, 0.5f, 3.5f};
    const lbk_lmuv_primitive_desc prims[2] = {{0, 4, 4, 6, remap, idx, xy}, {1, 3, 3, 3, remap, idx1, xy}};
    lbk_lmuv_object_desc uv[2];
    memset(uv, 0, sizeof uv);
    uv[0].object = 0, uv[0].kind = LBK_LMUV_GENERATED, uv[0].source_node = 0, uv[0].primitive_count = 2;
    uv[0].primitives = prims;
    uv[1].object = 1, uv[1].kind = LBK_LMUV_AUTHORED, uv[1].source_node = 1;
    uv[1].scale[0] = 3, uv[1].scale[1] = 1, uv[1].offset[0] = uv[1].offset[1] = 0.5f;
    uv[1].uv_max[0] = uv[1].uv_max[1] = 1;
    void *lmuv, *bytes;
    size_t lmuvn, n;
    lbk_writer *w;
    lbk_section_options o = {.flags = LBK_SECTION_FLAG_REQUIRED};
    if (lbk_lmuv_build(uv, 2, NULL, &lmuv, &lmuvn) || lbk_writer_open(NULL, &w) ||
        lbk_writer_section_add(w, LBK_SECTION_OBJS, ob, obn, &o) || lbk_writer_section_add(w, LBK_SECTION_LMAP, lm, lmn, &o) ||
        lbk_writer_section_add(w, LBK_SECTION_LLG, llg, llgn, &o) || lbk_writer_section_add(w, LBK_SECTION_LMUV, lmuv, lmuvn, NULL) ||
        lbk_writer_to_memory(w, &bytes, &n) || write_file("tests/fuzz/corpus/lmuv_raw.lbk", bytes, n))
        return 1;
    lbk_free(NULL, bytes);
    lbk_writer_close(w);
    return 0;
}
