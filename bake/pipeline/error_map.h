/* The per-texel error map (TERR, spec/container.md §18): what the baker stores as each lightmap
 * texel's estimated relative standard error. */
#ifndef BK_ERROR_MAP_H
#define BK_ERROR_MAP_H

#include <stddef.h>
#include <stdint.h>

#include "bake/layout/texels.h"
#include "lbk/lbk.h"

/* rel[k] for texel receivers k < n: √variance / luminance of the irradiance (BT.709, as the
 * transport's error scalar X), i.e. the relative standard error of the transport's estimate
 * from its two halves (one degree of freedom per texel); -1 where there is no estimate (no
 * light arrived, or a non-finite input). */
void bk_error_map_from_transport(const float *variance, const float *irradiance, size_t n, float *rel);

/* TERR bytes (lbk_terr_build; free with lbk_free(NULL, ·)) from rel[k] of texel receivers k < n
 * (texel_of_receiver[k] names the texel): each texel's code in LMAP's texel index space, 0 where
 * no receiver or rel < 0. `flags`: LBK_TERR_DENOISED when the stored texels were denoised after
 * this estimate. The one place the map is filled: any per-texel relative error (e.g. a denoised
 * estimate) can be fed here. */
lbk_result bk_error_map_section(const bk_texels *tx, const uint32_t *texel_of_receiver, size_t n, const float *rel,
                                uint32_t flags, void **data, size_t *size);

#endif
