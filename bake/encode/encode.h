/* Encoding baked radiance into container payloads: the AHD lightmap pages (tangent frame,
 * dilation, AHD) — shared by the base bake and the dynamic-set bakes. */
#ifndef BK_ENCODE_H
#define BK_ENCODE_H

#include <stdint.h>

#include "bake/layout/seams.h"
#include "bake/layout/texels.h"
#include "lbk/ahd.h"
#include "lbk/sh.h"

/* Tangent-space band-1 irradiance (the AHD linear form) of a texel receiver from its
 * world-space incident radiance SH (frame convention: bake/layout/texels.h). */
void bk_texel_linear(const bk_texel *t, const lbk_sh9_rgb *radiance_world, lbk_ahd_linear *out);

/* Makes a texel's stored irradiance along its normal the transport's direct estimate `e` (RGB,
 * bk_transport_output.irradiance) instead of the band-1 value of its radiance SH: the radiance
 * is scaled per channel by f = e / E_band1(n), f clamped to [0, 4/3]. Why: the AHD model (lbk/ahd.h)
 * holds band-1 irradiance, which is 3/4 of the truth for light arriving head-on and more than the
 * truth at grazing angles, so concentrated sources (emitters, windows, a light above a floor)
 * were stored up to 25 % low; scaling keeps the highlight direction and the ambient/directional
 * split, so only the value along the normal changes (other normals, normal maps, stay band-1).
 * The bound: for radiance that is non-negative and zero below the horizon, each direction adds
 * (1/4 + cos θ/2) ≥ (3/4)·cos θ to the band-1 value for cos θ to the truth, so f ≤ 4/3; a larger
 * ratio can only be noise. Channels whose band-1 value is not positive are left alone.
 * Returns the largest |f − 1| applied (for statistics). */
double bk_texel_match_irradiance(const bk_texel *t, lbk_sh9_rgb *radiance_world, const float e[3]);
/* The same for receivers [0, n), the texels texel_of_receiver names; irradiance: 3 per receiver. */
void bk_texels_match_irradiance(const bk_texels *tx, const uint32_t *texel_of_receiver, size_t n,
                                lbk_sh9_rgb *radiance, const float *irradiance);

/* The payload of one page made ready to encode, in place: dilation (margin + 2 passes, so
 * bilinear filtering never reads an empty texel near a chart) and then, when seams is not
 * NULL, seam stitching of that page (bake/layout/seams.h). data: 12 floats per texel
 * (lbk_ahd_linear), mask as for bk_dilate. Shared by the base bake and the dynamic sets, so
 * that both are treated alike. threads: for the stitching (0: all cores; the result is the same
 * for any count). Errors: LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_finish_page(float *data, uint8_t *mask, int width, int height, int margin, const bk_seams *seams,
                          uint32_t page, int threads);

/* AHD pages from per-texel linear forms (physical): `lin` and `has` are indexed like
 * tx->receivers; texels without a value are filled by dilation (margin + 2 passes) where a chart
 * is near, else zero; then the seams are stitched (seams may be NULL: not stitched). Every
 * value is multiplied by inv_scale (1/the LMAP scale, a power of two: exact) before dilation
 * and encoding, so the texels are in stored units.
 * pages_out[p] receives a malloc'ed width×height array per page (free each with free()). */
lbk_result bk_encode_pages(const bk_texels *tx, int margin, const bk_seams *seams, int threads,
                           const lbk_ahd_linear *lin, const uint8_t *has, float inv_scale, lbk_ahd_texel **pages_out);

/* The radiometric scale of a lighting section (spec/container.md §5.7) whose largest value
 * (texels: irradiance along the normal; probes: SH DC; any channel) is max_value: the power of
 * two 2^k that puts it in [2^13, 2^14) stored — 2^2 below the R11G11B10F / RGB9E5 maximum
 * (~2^16), headroom for dilation and for DLS sums at run time, 2^34 above the smallest
 * R11G11B10F step. 1 when max_value is 0 or not finite; k is clamped to [-126, 127]. */
float bk_scale_for(double max_value);

/* Largest irradiance along the normal (any channel) over the texels with `has` set. */
double bk_texel_max(const lbk_ahd_linear *lin, const uint8_t *has, size_t n);

/* Largest SH DC coefficient (any channel) over n probes. */
double bk_probe_max(const lbk_sh9_rgb *sh, size_t n);

/* Texel colour channels whose stored irradiance along the normal (physical × inv_scale) lies
 * outside what R11G11B10F holds: above its largest value 65024 (stored saturated) or positive
 * but below half its smallest step 2^-20 (stored as 0). With the scale of bk_scale_for this
 * happens only when the values within the section span more than the format's ~2^36.
 * `lin`/`has` as for bk_encode_pages; n entries. */
void bk_count_out_of_range(const lbk_ahd_linear *lin, const uint8_t *has, size_t n, float inv_scale,
                           uint64_t *saturated, uint64_t *flushed);

#endif
