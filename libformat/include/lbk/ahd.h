/* AHD lightmap texel (ambient + highlight direction, seed 001 §2.2 after id Software 1999 and
 * Sloan & Silvennoinen 2018). Normative description: spec/container.md §5.6.
 *
 * A texel is 8 bytes split over the two planes of an LMAP page:
 *   plane 0: u32 R11G11B10F  Ez = irradiance along the local +Z (the surface normal), RGB;
 *   plane 1: u8 R  ratio r = lum(ambient part of Ez) / lum(Ez), unorm8 in [0, 1];
 *            u8 G  unorm8((d.x + 1) / 2)   highlight direction d in tangent space
 *            u8 B  unorm8((d.y + 1) / 2)
 *            u8 A  unorm8(d.z)             d.z ≥ 0 always (see below)
 * lum(c) = 0.2126 R + 0.7152 G + 0.0722 B (Rec. 709).
 *
 * Lighting model. A texel holds an ambient irradiance a (RGB) plus a distant light of
 * irradiance I (RGB, at normal incidence) from direction d, both projected to band-1 SH and
 * convolved with the clamped cosine, so the irradiance is *linear* in the normal:
 *     E(n) = a + I · (1/4 + (n·d)/2),    evaluated as max(0, E(n)).
 * (1/4 and 1/2 are π·Y00² and (2π/3)·Y1²: the band-1 irradiance of a unit directional light.)
 * Decoding assumes a and I have the chroma of Ez: a = r·Ez, I = (1 − r)·Ez / k with
 * k = 1/4 + d.z/2 ∈ [1/4, 3/4]. d is decoded as the normalised vector (2G/255 − 1, 2B/255 − 1,
 * A/255); a vector shorter than 1/2 (only filtered or hand-made bytes) decodes as +Z.
 *
 * Linear form. Because E(n) is linear in n, a texel is exactly the band-1 irradiance
 *     E_c(n) = e0_c + g_c · n     (lbk_ahd_linear: c[ch] = {e0, g.x, g.y, g.z}, 12 floats)
 * with e0 = a + I/4 and g = I·d/2. Lighting adds in this form: to combine contributions (base
 * bake + Σ w_j · dynamic set j), decode every texel with lbk_ahd_to_linear, sum the 12 floats
 * with the weights, and re-encode once with lbk_ahd_from_linear. Irradiance SH from any source
 * (lbk_ahd_linear_from_sh9) lives in the same space.
 *
 * Encoding (lbk_ahd_from_linear), deterministic:
 *   1. non-finite components become 0, magnitudes are clamped to 1e30;
 *   2. d = normalize(Σ_c lum_c g_c); if d.z < 0 it is projected onto the tangent plane
 *      (d.z = 0, renormalised) because light from below the surface cannot reach it; if that
 *      leaves no direction (|Σ lum g|, or its xy part when projecting, < 1e−30) d = +Z;
 *   3. d is quantised to (G, B, A) and decoded again; the rest uses the decoded d so encoder and
 *      decoder agree;
 *   4. I_c = 2·max(0, g_c·d), a_c = max(0, e0_c − I_c/4), Ez_c = a_c + I_c·k;
 *   5. plane 0 = R11G11B10F(Ez) (rules of lbk/pixel.h), r = lum(a)/lum(Ez) (1 when lum(Ez) ≤ 0).
 * Exact (up to quantisation) for any lighting whose channels share one gradient direction and
 * whose ambient and directional parts share a chroma; the measured error bounds are in the spec.
 *
 * Thread safety: every function is pure (no state): safe to call from any thread. */
#ifndef LBK_AHD_H
#define LBK_AHD_H

#include "lbk/sh.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_AHD_TEXEL_SIZE 8u
#define LBK_LUM_R 0.2126f
#define LBK_LUM_G 0.7152f
#define LBK_LUM_B 0.0722f

typedef struct lbk_ahd_texel {
    uint32_t irradiance_z; /* plane 0: R11G11B10F, host order (stored little-endian) */
    uint8_t rgba[4];       /* plane 1: ratio, direction x, y, z */
} lbk_ahd_texel;

/* Band-1 irradiance in tangent space: E_ch(n) = c[ch][0] + c[ch][1]·n.x + c[ch][2]·n.y + c[ch][3]·n.z. */
typedef struct lbk_ahd_linear {
    float c[3][4];
} lbk_ahd_linear;

LBK_API void lbk_ahd_from_linear(const lbk_ahd_linear *lin, lbk_ahd_texel *out);
LBK_API void lbk_ahd_to_linear(const lbk_ahd_texel *texel, lbk_ahd_linear *out);
/* Irradiance for a unit tangent-space normal (max(0, ·) per channel). */
LBK_API void lbk_ahd_irradiance(const lbk_ahd_texel *texel, const float n[3], float rgb[3]);
LBK_API void lbk_ahd_linear_eval(const lbk_ahd_linear *lin, const float n[3], float rgb[3]);

/* Builders of the linear form. */
/* From tangent-space radiance SH (bands 0–1 are used; band 2 has no linear part). Its value along
 * +Z is band-1, 3/4 of the true irradiance for head-on light: a writer that knows the true Ez
 * scales the form to it (spec §5.6, informative note; lbk's baker does):
 * e0 = π·Y00·L00, g = (2π/3)·Y1·(L11, L1−1, L10). */
LBK_API void lbk_ahd_linear_from_sh9(const lbk_sh9_rgb *radiance, lbk_ahd_linear *out);
/* lin += uniform ambient irradiance (what a +Z surface receives from a constant environment). */
LBK_API void lbk_ahd_linear_add_ambient(lbk_ahd_linear *lin, const float rgb[3]);
/* lin += a distant light of irradiance rgb at normal incidence from unit direction dir:
 * e0 += rgb/4, g += rgb·dir/2. */
LBK_API void lbk_ahd_linear_add_light(lbk_ahd_linear *lin, const float dir[3], const float rgb[3]);
/* dst += w · src. */
LBK_API void lbk_ahd_linear_add_scaled(lbk_ahd_linear *dst, const lbk_ahd_linear *src, float w);

/* ---- tangent frame (spec §5.6 "Tangent frame") -------------------------------------------------
 * d, the highlight direction, is stored in the frame of the surface point the texel was lit from:
 *   N = the unit interpolated shading normal (+Z);
 *   T = dP/dX, the derivative of the world position along the lightmap coordinate X (to the right
 *       on the page, spec §16.1; normalised u = X / width has the same direction), made orthogonal
 *       to N and unit length (+X);
 *   B = N × T (+Y): always right-handed, no handedness sign is stored, also for mirrored
 *       authored TEXCOORD_1 (for generated charts B points along +Y, down the page).
 * A world direction w has tangent coordinates (w·T, w·B, w·N). When dP/dX is zero or within
 * 1e-6 (relative) of parallel to N, T is the first vector of the branchless orthonormal basis of N
 * (Duff et al. 2017): with s = sign(N.z) (+1 at 0) and a = −1/(s + N.z),
 * T = (1 + s·N.x²·a, s·N.x·N.y·a, −s·N.x). A renderer rebuilds T per vertex or per pixel from the
 * lightmap coordinates' derivatives the same way. */
/* The frame for a normal n (normalised here; a zero n means +Z) and dP/dX. Computed in double. */
LBK_API void lbk_ahd_tangent_frame(const float n[3], const float dpdx[3], float t[3], float b[3]);
/* dP/dX of a triangle from its world positions and lightmap coordinates (any units of X: only the
 * direction matters); zero when the coordinates span no area. */
LBK_API void lbk_ahd_triangle_dpdx(const float p[3][3], const float coord[3][2], float dpdx[3]);

/* The 8 bytes as the spec's texel view (u32 LE then RGBA) — for tools that keep texels packed. */
LBK_API void lbk_ahd_texel_pack(const lbk_ahd_texel *texel, uint8_t out[LBK_AHD_TEXEL_SIZE]);
LBK_API void lbk_ahd_texel_unpack(const uint8_t in[LBK_AHD_TEXEL_SIZE], lbk_ahd_texel *texel);

#ifdef __cplusplus
}
#endif
#endif
