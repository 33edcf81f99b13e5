/* TERR: the per-texel error map (format 1.4, optional). One u8 per LMAP texel: the estimated
 * relative standard error of the texel's irradiance (luminance), on a log scale. Layout:
 * spec/container.md §18.
 *
 * Thread safety: every function is safe to call from any thread; views are read-only. */
#ifndef LBK_ERROR_MAP_H
#define LBK_ERROR_MAP_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_SECTION_TERR LBK_FOURCC('T', 'E', 'R', 'R') /* per-texel error estimate (1.4) */
#define LBK_TERR_HEADER_SIZE 16u

/* encoding 0, the only one: code c ≥ 1 means relative error 2^((c − LBK_TERR_CODE_ONE) / 16) */
#define LBK_TERR_LOG2_U8 0u
#define LBK_TERR_CODE_ONE 161       /* the code of relative error 1 (100 %) */
#define LBK_TERR_STEPS_PER_OCTAVE 16
#define LBK_TERR_NO_ESTIMATE 0      /* code 0: no estimate (no receiver, no light) */
/* Flag: the lightmap was denoised after the estimate was taken; the map is the noise of the
 * undenoised texels (spec §18.2). */
#define LBK_TERR_DENOISED 0x1u

/* Code of relative error `rel` (§18.2): 0 for NaN, negative or infinite (no estimate); 1 for
 * rel ≤ 2^-10 (0 included); 255 for rel ≥ 2^5.875; else 161 + round(16·log2 rel), ties to even,
 * computed exactly from the binary32 bits (no libm: the same code on every platform). */
LBK_API uint8_t lbk_terr_encode(float rel);
/* Relative error of a code ≥ 1: 2^((code − 161)/16) (binary64, exact to its rounding); code 0: -1. */
LBK_API double lbk_terr_decode(uint8_t code);

/* Builds TERR bytes for `texel_count` codes (LMAP's texel index order, §9.1). Rejects
 * (LBK_ERR_INVALID_ARGUMENT) texel_count 0, NULL codes, unknown flag bits. *out is allocated
 * with the allocator; free it with lbk_free. */
LBK_API lbk_result lbk_terr_build(uint32_t flags, const uint8_t *codes, uint64_t texel_count,
                                  const lbk_allocator *allocator, void **out, size_t *size);

typedef struct lbk_terr_view {
    uint32_t encoding;    /* LBK_TERR_LOG2_U8 */
    uint32_t flags;       /* LBK_TERR_DENOISED */
    uint64_t texel_count; /* equals LMAP's */
    const uint8_t *codes; /* texel_count codes, into the section's bytes */
} lbk_terr_view;

/* Checks the header and size (LBK_ERR_TRUNCATED / LBK_ERR_CORRUPT; unknown encoding or flags:
 * LBK_ERR_UNSUPPORTED_FEATURE) and fills the view. */
LBK_API lbk_result lbk_terr_open(const void *data, size_t size, lbk_terr_view *out);
/* The code of texel `index` (LBK_ERR_NOT_FOUND beyond texel_count). */
LBK_API lbk_result lbk_terr_code_get(const lbk_terr_view *view, uint64_t index, uint8_t *code);

#ifdef __cplusplus
}
#endif
#endif
