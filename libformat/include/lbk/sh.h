/* Real spherical harmonics up to band 2 (9 coefficients) and the 28-byte SH9 probe.
 * Normative description: spec/container.md §5.5.
 *
 * Basis (orthonormal over the unit sphere, no Condon–Shortley phase), for a unit direction
 * (x, y, z), index k = l(l+1) + m:
 *   k=0 Y00  = 0.282094791773878  (1 / (2√π))
 *   k=1 Y1−1 = 0.488602511902920 · y      (√(3/(4π)))
 *   k=2 Y10  = 0.488602511902920 · z
 *   k=3 Y11  = 0.488602511902920 · x
 *   k=4 Y2−2 = 1.092548430592079 · x y    (√(15/(4π)))
 *   k=5 Y2−1 = 1.092548430592079 · y z
 *   k=6 Y20  = 0.315391565252520 · (3z² − 1)  (√(5/(16π)))
 *   k=7 Y21  = 1.092548430592079 · x z
 *   k=8 Y22  = 0.546274215296040 · (x² − y²)  (√(15/(16π)))
 * Radiance L(ω) ≈ Σ_k L_k Y_k(ω). Irradiance for a unit normal n (clamped-cosine convolution,
 * Ramamoorthi & Hanrahan 2001): E(n) = Σ_k A_l(k) L_k Y_k(n), A0 = π, A1 = 2π/3, A2 = π/4.
 *
 * Every function here is linear in the coefficients except pack/unpack, so lighting from
 * several sources is summed coefficient by coefficient (lbk_sh9_add_scaled).
 *
 * Thread safety: every function is pure (no state): safe to call from any thread. */
#ifndef LBK_SH_H
#define LBK_SH_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_SH9_COUNT 9
#define LBK_SH9_PACKED_SIZE 28u

#define LBK_SH_Y00 0.282094791773878f
#define LBK_SH_Y1 0.488602511902920f
#define LBK_SH_Y2 1.092548430592079f
#define LBK_SH_Y20 0.315391565252520f
#define LBK_SH_Y22 0.546274215296040f
#define LBK_SH_A0 3.14159265358979f /* π */
#define LBK_SH_A1 2.09439510239320f /* 2π/3 */
#define LBK_SH_A2 0.785398163397448f /* π/4 */

/* RGB radiance SH: c[channel][k], channel 0 = R, 1 = G, 2 = B. */
typedef struct lbk_sh9_rgb {
    float c[3][LBK_SH9_COUNT];
} lbk_sh9_rgb;

/* The 9 basis values at a unit direction. */
LBK_API void lbk_sh9_basis(const float dir[3], float out[LBK_SH9_COUNT]);
/* sh += weight · rgb · Y(dir). Monte-Carlo projection of radiance samples: with N directions
 * drawn uniformly over the sphere use weight 4π/N; with pdf p(ω) use 1/(N p(ω)). dir must be a
 * unit vector. */
LBK_API void lbk_sh9_add_sample(lbk_sh9_rgb *sh, const float dir[3], const float rgb[3], float weight);
/* dst += w · src (coefficient-wise; the basis of additive lighting). */
LBK_API void lbk_sh9_add_scaled(lbk_sh9_rgb *dst, const lbk_sh9_rgb *src, float w);
/* Radiance in direction dir. */
LBK_API void lbk_sh9_eval(const lbk_sh9_rgb *sh, const float dir[3], float rgb[3]);
/* Irradiance at a unit normal n (not clamped: a ringing SH can give small negative values). */
LBK_API void lbk_sh9_irradiance(const lbk_sh9_rgb *sh, const float n[3], float rgb[3]);
/* Rotates the coefficients into the frame whose rows are the unit axes (t, b, n), i.e. the result
 * is the same radiance expressed with direction components (ω·t, ω·b, ω·n). rows must be
 * orthonormal. Bands 0 and 1 are exact; band 2 uses the exact quadratic form. */
LBK_API void lbk_sh9_rotate(const lbk_sh9_rgb *sh, const float rows[3][3], lbk_sh9_rgb *out);

/* The 28-byte probe (spec §5.5):
 *   bytes 0–3   u32 RGB9E5 of the DC coefficients (L0 of R, G, B);
 *   bytes 4–27  24 snorm8: for k = 1..8, for channel R, G, B (byte 4 + 3(k−1) + channel):
 *               q = snorm8(L_k / (s_l · D)) where D is the *decoded* DC of that channel and
 *               s_1 = √3, s_2 = √5.
 * For a non-negative radiance |L1m| ≤ √3 L00 and |L2m| ≤ √5 L00, so the ratio lies in [−1, 1];
 * ratios outside are clamped. D == 0 (zero, tiny below RGB9E5 range, negative or NaN DC) → all
 * higher coefficients of that channel are stored as 0.
 * Decode: L0 = RGB9E5 value; L_k = snorm8_value(q) · s_l · L0. */
LBK_API void lbk_sh9_pack(const lbk_sh9_rgb *sh, uint8_t out[LBK_SH9_PACKED_SIZE]);
LBK_API void lbk_sh9_unpack(const uint8_t in[LBK_SH9_PACKED_SIZE], lbk_sh9_rgb *sh);

#ifdef __cplusplus
}
#endif
#endif
