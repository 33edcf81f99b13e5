/* The per-texel error map (error_map.h). */
#include "bake/pipeline/error_map.h"

#include <math.h>
#include <stdlib.h>

#include "bake/transport/shading.h"
#include "lbk/error_map.h"

void bk_error_map_from_transport(const float *variance, const float *irradiance, size_t n, float *rel)
{
    for (size_t k = 0; k < n; k++) {
        const double lum = bk_lumf(&irradiance[3 * k]);
        const double v = variance[k];
        rel[k] = lum > 0 && isfinite(lum) && v >= 0 && isfinite(v) ? (float)(sqrt(v) / lum) : -1.0f;
    }
}

lbk_result bk_error_map_section(const bk_texels *tx, const uint32_t *texel_of_receiver, size_t n, const float *rel,
                                uint32_t flags, void **data, size_t *size)
{
    const size_t total = tx->page_offset[tx->page_count];
    uint8_t *codes = calloc(total ? total : 1, 1);
    if (!codes) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t k = 0; k < n; k++) {
        const bk_texel *t = &tx->receivers[texel_of_receiver[k]];
        const size_t i = tx->page_offset[t->page] + (size_t)t->y * tx->pages[t->page].width + t->x;
        codes[i] = rel[k] < 0 ? LBK_TERR_NO_ESTIMATE : lbk_terr_encode(rel[k]);
    }
    lbk_result r = lbk_terr_build(flags, codes, total, NULL, data, size);
    free(codes);
    return r;
}
