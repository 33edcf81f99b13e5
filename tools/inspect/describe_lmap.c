/* LMAP in `lbk inspect`: pages and texels; both AHD planes (8 bytes per texel) go to the GPU. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/lightmap.h"

void inspect_describe_lmap(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_lmap_view v;
    if (lbk_lmap_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    out->lm_pages = v.page_count;
    out->lm_texels = v.texel_count;
    out->gpu_bytes = v.texel_count * 8; /* R11G11B10F plane + RGBA8 plane */
    snprintf(out->detail, sizeof out->detail, "%u pages, %llu texels (8 B/texel), scale 2^%d", v.page_count,
             (unsigned long long)v.texel_count, inspect_scale_log2(v.scale));
}
