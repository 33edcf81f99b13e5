/* LMAP in `lbk inspect`: pages, texels and the GPU bytes of both AHD planes in their encodings
 * (8 bytes per texel for R11G11B10F + RGBA8; block encodings: spec/container.md §9.2). */
#include <stdio.h>

#include "tools/common/lmap_decode.h"
#include "tools/inspect/describe.h"
#include "lbk/lightmap.h"

void inspect_describe_lmap(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_lmap_view v;
    if (lbk_lmap_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    out->lm_pages = v.page_count;
    out->lm_texels = v.texel_count;
    uint64_t gpu = 0;
    uint32_t f0 = 0, f1 = 0;
    int mixed = 0;
    for (uint32_t p = 0; p < v.page_count; p++) {
        lbk_lmap_planes pl;
        lbk_lmap_planes_get(&v, p, &pl);
        gpu += pl.bytes[0] + pl.bytes[1];
        if (p == 0) f0 = pl.format[0], f1 = pl.format[1];
        mixed |= pl.format[0] != f0 || pl.format[1] != f1;
    }
    out->gpu_bytes = gpu; /* the planes as stored: what a renderer uploads */
    char enc[64];
    if (mixed) snprintf(enc, sizeof enc, "mixed encodings");
    else snprintf(enc, sizeof enc, "%s + %s", tl_lmap_format_name(0, f0), tl_lmap_format_name(1, f1));
    snprintf(out->detail, sizeof out->detail, "%u pages, %llu texels (%.3g B/texel, %s), scale 2^%d", v.page_count,
             (unsigned long long)v.texel_count, v.texel_count ? (double)gpu / (double)v.texel_count : 0.0, enc,
             inspect_scale_log2(v.scale));
}
