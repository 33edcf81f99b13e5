/* Encoding baked radiance into container payloads: the AHD lightmap pages (tangent frame,
 * dilation, AHD) — shared by the base bake and the dynamic-set bakes. */
#ifndef BK_ENCODE_H
#define BK_ENCODE_H

#include <stdint.h>

#include "bake/texels.h"
#include "lbk/ahd.h"
#include "lbk/sh.h"

/* Tangent-space band-1 irradiance (the AHD linear form) of a texel receiver from its
 * world-space incident radiance SH (frame convention: bake/texels.h). */
void bk_texel_linear(const bk_texel *t, const lbk_sh9_rgb *radiance_world, lbk_ahd_linear *out);

/* AHD pages from per-texel linear forms: `lin` and `has` are indexed like tx->receivers; texels
 * without a value are filled by dilation (margin + 2 passes) where a chart is near, else zero.
 * pages_out[p] receives a malloc'ed width×height array per page (free each with free()). */
lbk_result bk_encode_pages(const bk_texels *tx, int margin, const lbk_ahd_linear *lin, const uint8_t *has,
                           lbk_ahd_texel **pages_out);

/* Texel colour channels whose irradiance along the normal lies outside what R11G11B10F holds:
 * above its largest value 65024 (stored saturated) or positive but below half its smallest step
 * 2^-20 (stored as 0). `lin`/`has` as for bk_encode_pages; n entries. */
void bk_count_out_of_range(const lbk_ahd_linear *lin, const uint8_t *has, size_t n, uint64_t *saturated,
                           uint64_t *flushed);

#endif
