/* Small float and normalised integer codecs. The float encoders work on the IEEE bit pattern so
 * rounding is exact (ties to even) and independent of the FPU rounding mode. */
#include "lbk/pixel.h"

#include <math.h>
#include <string.h>

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

static float bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* Encodes the magnitude `a` (bits of a finite, non-negative float) into a float with a 5-bit
 * exponent (bias 15) and `mbits` mantissa bits, saturating at the largest finite code. */
static uint32_t small_from_magnitude(uint32_t a, unsigned mbits)
{
    const uint32_t max_code = (30u << mbits) | ((1u << mbits) - 1u);
    const uint32_t exp = a >> 23;
    if (exp >= 113u) { /* |x| ≥ 2^−14: a normal of the target, or overflow */
        if (exp > 142u) return max_code; /* ≥ 2^16 > every max finite */
        const unsigned shift = 23u - mbits;
        const uint32_t t = a - (112u << 23); /* rebias the exponent field from 127 to 15 */
        const uint32_t r = (t + ((1u << (shift - 1u)) - 1u) + ((t >> shift) & 1u)) >> shift;
        return r > max_code ? max_code : r; /* a carry into exponent 31 saturates */
    }
    /* target denormal: code = x / 2^(−14−mbits), rounded to nearest even */
    const uint32_t sig = exp == 0 ? (a & 0x7fffffu) : ((a & 0x7fffffu) | 0x800000u);
    const int e = exp == 0 ? -126 : (int)exp - 127;
    const int rshift = 23 - 14 - (int)mbits - e; /* ≥ 24 − mbits since e ≤ −15 */
    if (rshift > 24) return 0;                   /* sig < 2^24 ≤ half a step */
    uint32_t q = sig >> rshift;
    const uint32_t rem = sig & ((1u << rshift) - 1u), half = 1u << (rshift - 1);
    if (rem > half || (rem == half && (q & 1u))) q++;
    return q; /* q == 1 << mbits is the smallest normal, which has the same code */
}

static uint32_t small_unsigned_encode(float x, unsigned mbits)
{
    const uint32_t u = float_bits(x);
    if ((u & 0x7fffffffu) > 0x7f800000u) return 0; /* NaN */
    if (u >> 31) return 0;                          /* negatives, −0 and −Inf */
    if (u == 0x7f800000u) return (30u << mbits) | ((1u << mbits) - 1u);
    return small_from_magnitude(u, mbits);
}

static float small_decode(uint32_t code, unsigned mbits)
{
    const uint32_t e = code >> mbits, m = code & ((1u << mbits) - 1u);
    if (e == 0) return ldexpf((float)m, -14 - (int)mbits);
    if (e == 31) return m ? NAN : INFINITY;
    return bits_float(((e + 112u) << 23) | (m << (23u - mbits)));
}

uint32_t lbk_float_to_uf11(float x) { return small_unsigned_encode(x, 6); }
uint32_t lbk_float_to_uf10(float x) { return small_unsigned_encode(x, 5); }
float lbk_uf11_to_float(uint32_t code) { return small_decode(code & 0x7ffu, 6); }
float lbk_uf10_to_float(uint32_t code) { return small_decode(code & 0x3ffu, 5); }

uint32_t lbk_r11g11b10f_pack(const float rgb[3])
{
    return lbk_float_to_uf11(rgb[0]) | (lbk_float_to_uf11(rgb[1]) << 11) | (lbk_float_to_uf10(rgb[2]) << 22);
}

void lbk_r11g11b10f_unpack(uint32_t packed, float rgb[3])
{
    rgb[0] = lbk_uf11_to_float(packed);
    rgb[1] = lbk_uf11_to_float(packed >> 11);
    rgb[2] = lbk_uf10_to_float(packed >> 22);
}

uint16_t lbk_float_to_half(float x)
{
    const uint32_t u = float_bits(x);
    const uint32_t a = u & 0x7fffffffu;
    if (a > 0x7f800000u) return 0; /* NaN */
    const uint32_t sign = (u >> 16) & 0x8000u;
    if (a == 0x7f800000u) return (uint16_t)(sign | 0x7bffu);
    return (uint16_t)(sign | small_from_magnitude(a, 10));
}

float lbk_half_to_float(uint16_t h)
{
    const float m = small_decode(h & 0x7fffu, 10);
    return (h & 0x8000u) ? -m : m;
}

/* Round to nearest, ties to even, of a finite double, without depending on the rounding mode. */
static double rne(double x)
{
    const double f = floor(x), d = x - f;
    if (d > 0.5) return f + 1.0;
    if (d < 0.5) return f;
    return fmod(f, 2.0) == 0.0 ? f : f + 1.0;
}

/* Clamps to [0, hi]; NaN → 0. */
static double clamp_nonneg(float x, double hi)
{
    if (!(x > 0.0f)) return 0.0; /* NaN, negatives, −0 */
    return (double)x > hi ? hi : (double)x;
}

uint32_t lbk_rgb9e5_pack(const float rgb[3])
{
    const double c[3] = {clamp_nonneg(rgb[0], LBK_RGB9E5_MAX), clamp_nonneg(rgb[1], LBK_RGB9E5_MAX),
                         clamp_nonneg(rgb[2], LBK_RGB9E5_MAX)};
    double maxc = c[0] > c[1] ? c[0] : c[1];
    if (c[2] > maxc) maxc = c[2];
    int exp_shared = 0;
    if (maxc > 0.0) {
        int e2;
        (void)frexp(maxc, &e2); /* maxc = f · 2^e2, f ∈ [0.5, 1): floor(log2 maxc) = e2 − 1 */
        exp_shared = (e2 - 1 < -16 ? -16 : e2 - 1) + 16;
        if (rne(ldexp(maxc, 24 - exp_shared)) >= 512.0) exp_shared++;
    }
    uint32_t out = (uint32_t)exp_shared << 27;
    for (int i = 0; i < 3; i++) {
        const double m = rne(ldexp(c[i], 24 - exp_shared)); /* ≤ 511 by the exponent choice */
        out |= (uint32_t)m << (9 * i);
    }
    return out;
}

void lbk_rgb9e5_unpack(uint32_t packed, float rgb[3])
{
    const int e = (int)(packed >> 27) - 24;
    for (int i = 0; i < 3; i++) rgb[i] = ldexpf((float)((packed >> (9 * i)) & 0x1ffu), e);
}

uint8_t lbk_float_to_unorm8(float x)
{
    if (!(x > 0.0f)) return 0;
    if (x >= 1.0f) return 255;
    return (uint8_t)rne((double)x * 255.0);
}

float lbk_unorm8_to_float(uint8_t code) { return (float)code / 255.0f; }

uint8_t lbk_float_to_snorm8(float x)
{
    if (x != x) return 0;
    if (x >= 1.0f) return 127;
    if (x <= -1.0f) return (uint8_t)(int8_t)-127;
    return (uint8_t)(int8_t)rne((double)x * 127.0);
}

float lbk_snorm8_to_float(uint8_t code)
{
    const float v = (float)(int8_t)code / 127.0f;
    return v < -1.0f ? -1.0f : v;
}
