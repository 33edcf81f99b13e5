/* Pixel codecs: the small float and normalised integer encodings the payloads use.
 * Normative description: spec/container.md §5.1–§5.4.
 *
 * Every encoder rounds to nearest, ties to even, and maps every float input (NaN, ±Inf,
 * negatives, denormals, out-of-range) to a defined code:
 *
 *   input                  | unsigned floats (uf11, uf10, R11G11B10F, RGB9E5) | half (signed)
 *   -----------------------+--------------------------------------------------+-----------------------
 *   NaN (any payload)      | 0                                                | +0
 *   −Inf, negative, −0     | 0                                                | sign kept, magnitude as for +
 *   +Inf, > max finite     | max finite (never Inf)                           | ±max finite (65504)
 *   in range               | round to nearest even; the target's denormals are kept
 *   < ½ smallest denormal  | 0 (exactly ½ rounds to even, i.e. 0)             | ±0
 *
 * Decoders are exact (every code maps to one float, computed without rounding). Codes the
 * encoders never produce (exponent 31: Inf/NaN in uf11/uf10/half) decode as IEEE says; validators
 * reject them in files.
 *
 * unorm8: code = rne(clamp(x, 0, 1) · 255), NaN → 0; value = code / 255.
 * snorm8: code = rne(clamp(x, −1, 1) · 127) stored as two's complement int8, NaN → 0;
 *         value = max(code / 127, −1) (so −128 and −127 both mean −1, as on GPUs).
 *
 * Thread safety: every function is pure (no state): safe to call from any thread. */
#ifndef LBK_PIXEL_H
#define LBK_PIXEL_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest finite values. */
#define LBK_UF11_MAX 65024.0f   /* 2^15 · (1 + 63/64) */
#define LBK_UF10_MAX 64512.0f   /* 2^15 · (1 + 31/32) */
#define LBK_HALF_MAX 65504.0f   /* 2^15 · (1 + 1023/1024) */
#define LBK_RGB9E5_MAX 65408.0f /* 2^16 · 511/512 */

/* Unsigned 11-bit float (5-bit exponent, bias 15, 6-bit mantissa) and 10-bit (5-bit mantissa),
 * as the channels of DXGI_FORMAT_R11G11B10_FLOAT. */
LBK_API uint32_t lbk_float_to_uf11(float x);
LBK_API uint32_t lbk_float_to_uf10(float x);
LBK_API float lbk_uf11_to_float(uint32_t code); /* uses the low 11 bits */
LBK_API float lbk_uf10_to_float(uint32_t code); /* uses the low 10 bits */

/* DXGI_FORMAT_R11G11B10_FLOAT packed into one u32: R bits 0–10, G bits 11–21, B bits 22–31. */
LBK_API uint32_t lbk_r11g11b10f_pack(const float rgb[3]);
LBK_API void lbk_r11g11b10f_unpack(uint32_t packed, float rgb[3]);

/* DXGI_FORMAT_R9G9B9E5_SHAREDEXP: R bits 0–8, G 9–17, B 18–26, shared exponent 27–31 (bias 15),
 * value = mantissa · 2^(exponent − 24), no implicit leading one. The exponent is chosen from the
 * largest channel after clamping; if rounding that channel's mantissa gives 512 the exponent is
 * raised by one. Each mantissa is rounded to nearest even at the chosen exponent. */
LBK_API uint32_t lbk_rgb9e5_pack(const float rgb[3]);
LBK_API void lbk_rgb9e5_unpack(uint32_t packed, float rgb[3]);

/* IEEE-754 binary16. */
LBK_API uint16_t lbk_float_to_half(float x);
LBK_API float lbk_half_to_float(uint16_t h);

LBK_API uint8_t lbk_float_to_unorm8(float x);
LBK_API float lbk_unorm8_to_float(uint8_t code);
LBK_API uint8_t lbk_float_to_snorm8(float x); /* returns the int8 bit pattern */
LBK_API float lbk_snorm8_to_float(uint8_t code);

#ifdef __cplusplus
}
#endif
#endif
