/* The DLS arithmetic on 8 targets at a time with AVX2 and FMA: the bytes of dls_kernel_scalar.c
 * (lbk_ahd_to_linear / _from_linear, lbk_sh9_unpack / _pack and pixel.c's codecs), lane for lane.
 *
 * Decoding follows the scalar operations in the same order and precision — float where they use
 * float, double where they use double, every rounding to nearest-even by an instruction that
 * ignores the rounding mode where the scalar code does so too — with one substitution: a float
 * division a / b is computed as Markstein's correctly rounded quotient from y = RN(1/b)
 * (q = RN(a·y); r = a − b·q, exact in one fused multiply-add; RN(q + r·y) = RN(a/b) when no
 * step overflows or underflows, which holds for every decode here), so one true division serves
 * three quotients. The FMAs are only those of that correction: the definition's own products and
 * sums stay unfused (contraction is off).
 *
 * Encoding (texel_encode_fast) computes the bytes that need the encoder's double sums, division
 * and square roots (the direction and the ambient ratio) in float, with an error below 3e-4 of a
 * byte code (derived at texel_encode_fast), and keeps a byte only when
 * its value lies farther than NEAR_MARGIN from a rounding boundary; a group of 8 with a lane
 * nearer than that goes through the operation-by-operation encoder (texel_encode). So the bytes
 * are the definition's, and the slow encoder runs for about 1 group in 150 on the benchmark level. */
#include "dls_kernel.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define DLS_AVX2 1
#endif

#ifndef DLS_AVX2
const dls_kernels *dls_kernels_avx2(void) { return 0; }
#else

#include <string.h>

#include "internal.h"
#include "lbk/ahd.h"
#include "lbk/pixel.h"
#include "lbk/sh.h"

#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,fma"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,fma")
#endif
#include <immintrin.h>

#define INL static inline __attribute__((always_inline))
#define RNE (_MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC)

typedef __m256 vf;
typedef __m256i vi;
typedef __m256d vd;

INL vf fset(float x) { return _mm256_set1_ps(x); }
INL vi iset(int x) { return _mm256_set1_epi32(x); }
INL vf add(vf a, vf b) { return _mm256_add_ps(a, b); }
INL vf sub(vf a, vf b) { return _mm256_sub_ps(a, b); }
INL vf mul(vf a, vf b) { return _mm256_mul_ps(a, b); }
INL vf dvd(vf a, vf b) { return _mm256_div_ps(a, b); }
INL vf sel(vf mask, vf yes, vf no) { return _mm256_blendv_ps(no, yes, mask); }
INL vf gt(vf a, vf b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }

/* RN(a / b) from y = RN(1 / b), by Markstein's correction (see the top of the file). */
INL vf quot(vf a, vf b, vf y)
{
    const vf q = mul(a, y);
    return _mm256_fmadd_ps(_mm256_fnmadd_ps(q, b, a), y, q);
}
INL vf quot_by(vi n, float b) { return quot(_mm256_cvtepi32_ps(n), fset(b), fset(1.0f / b)); }
/* lbk_unorm8_to_float: c/255 */
INL vf unorm_f(vi c) { return quot_by(c, 255.0f); }
/* decode_direction's x and y: 2c/255 − 1 */
INL vf dir_f(vi c) { return sub(quot_by(_mm256_add_epi32(c, c), 255.0f), fset(1.0f)); }
/* lbk_snorm8_to_float: max(q/127, −1) for the signed byte q */
INL vf snorm_f(vi q) { return _mm256_max_ps(quot_by(q, 127.0f), fset(-1.0f)); }
INL vi byte_at(vi w, int i) { return _mm256_and_si256(_mm256_srli_epi32(w, 8 * i), iset(0xff)); }

/* The two halves of 8 floats as doubles, and 8 doubles back to floats (rounded as (float)x). */
INL vd lo_d(vf x) { return _mm256_cvtps_pd(_mm256_castps256_ps128(x)); }
INL vd hi_d(vf x) { return _mm256_cvtps_pd(_mm256_extractf128_ps(x, 1)); }
INL vf to_f(vd lo, vd hi) { return _mm256_set_m128(_mm256_cvtpd_ps(hi), _mm256_cvtpd_ps(lo)); }

/* ---- pixel.c codecs --------------------------------------------------------------------- */

/* small_decode for a 5-bit exponent and M mantissa bits, then lbk_ahd_to_linear's handling of
 * exponent 31 (NaN → 0, Inf → LBK_UF11_MAX). */
INL vf uf_decode(vi code, int M)
{
    const vi e = _mm256_srli_epi32(code, M), m = _mm256_and_si256(code, iset((1 << M) - 1));
    const vf normal = _mm256_castsi256_ps(_mm256_add_epi32(_mm256_slli_epi32(code, 23 - M), iset(112 << 23)));
    const vf denormal = mul(_mm256_cvtepi32_ps(m), fset(M == 6 ? 0x1p-20f : 0x1p-19f));
    vf v = sel(_mm256_castsi256_ps(_mm256_cmpeq_epi32(e, _mm256_setzero_si256())), denormal, normal);
    const vf special = sel(_mm256_castsi256_ps(_mm256_cmpeq_epi32(m, _mm256_setzero_si256())), fset(LBK_UF11_MAX),
                           _mm256_setzero_ps());
    return sel(_mm256_castsi256_ps(_mm256_cmpeq_epi32(e, iset(31))), special, v);
}

/* small_unsigned_encode of values that are ≥ +0 and finite (the encoder's Ez). */
INL vi uf_encode(vf x, int M)
{
    const vi a = _mm256_castps_si256(x);
    const int shift = 23 - M;
    const vi t = _mm256_sub_epi32(a, iset(112 << 23));
    const vi lsb = _mm256_and_si256(_mm256_srli_epi32(t, shift), iset(1));
    vi normal = _mm256_srli_epi32(_mm256_add_epi32(_mm256_add_epi32(t, iset((1 << (shift - 1)) - 1)), lsb), shift);
    normal = _mm256_min_epu32(normal, iset((30 << M) | ((1 << M) - 1)));
    /* below 2^−14: a denormal of the target, code = rne(x / 2^(−14−M)); the product is exact */
    const vi denormal = _mm256_cvtps_epi32(_mm256_round_ps(mul(x, fset(M == 6 ? 0x1p20f : 0x1p19f)), RNE));
    const vi is_normal = _mm256_cmpgt_epi32(a, iset((113 << 23) - 1));
    return _mm256_blendv_epi8(denormal, normal, is_normal);
}

/* lbk_float_to_unorm8 of x ∈ [0, 1] (as every caller here guarantees): rne((double)x · 255). */
INL vi unorm8(vf x)
{
    x = _mm256_min_ps(_mm256_max_ps(x, _mm256_setzero_ps()), fset(1.0f));
    const vd k = _mm256_set1_pd(255.0);
    const __m128i lo = _mm256_cvtpd_epi32(_mm256_round_pd(_mm256_mul_pd(lo_d(x), k), RNE));
    const __m128i hi = _mm256_cvtpd_epi32(_mm256_round_pd(_mm256_mul_pd(hi_d(x), k), RNE));
    return _mm256_set_m128i(hi, lo);
}

/* lbk_float_to_snorm8: NaN → 0, clamp to [−1, 1], rne((double)x · 127); the byte in the low 8 bits. */
INL vi snorm8(vf x)
{
    x = _mm256_and_ps(x, _mm256_cmp_ps(x, x, _CMP_ORD_Q));
    x = _mm256_min_ps(_mm256_max_ps(x, fset(-1.0f)), fset(1.0f));
    const vd k = _mm256_set1_pd(127.0);
    const __m128i lo = _mm256_cvtpd_epi32(_mm256_round_pd(_mm256_mul_pd(lo_d(x), k), RNE));
    const __m128i hi = _mm256_cvtpd_epi32(_mm256_round_pd(_mm256_mul_pd(hi_d(x), k), RNE));
    return _mm256_and_si256(_mm256_set_m128i(hi, lo), iset(0xff));
}

/* ---- AHD texels (ahd.c) ------------------------------------------------------------------ */

typedef struct lin8 {
    vf c[3][4];
} lin8;

/* decode_direction of the G, B, A bytes of rgba; k = 1/4 + d.z/2. */
INL void direction(vi rgba, vf d[3], vf *k)
{
    const vf x = dir_f(byte_at(rgba, 1)), y = dir_f(byte_at(rgba, 2));
    const vf z = unorm_f(_mm256_srli_epi32(rgba, 24));
    const vf len = _mm256_sqrt_ps(add(add(mul(x, x), mul(y, y)), mul(z, z)));
    const vf shortv = _mm256_cmp_ps(len, fset(0.5f), _CMP_LT_OQ);
    const vf inv = dvd(fset(1.0f), len); /* len ≥ 1/255: x, y are odd multiples of 1/255 */
    d[0] = sel(shortv, _mm256_setzero_ps(), quot(x, len, inv));
    d[1] = sel(shortv, _mm256_setzero_ps(), quot(y, len, inv));
    d[2] = sel(shortv, fset(1.0f), quot(z, len, inv));
    *k = add(fset(0.25f), mul(fset(0.5f), d[2]));
}

/* lbk_ahd_to_linear. */
INL void texel_decode(vi z, vi rgba, lin8 *out)
{
    vf d[3], k;
    direction(rgba, d, &k);
    const vf r = unorm_f(_mm256_and_si256(rgba, iset(0xff)));
    const vf one_r = sub(fset(1.0f), r);
    const vf e[3] = {uf_decode(_mm256_and_si256(z, iset(0x7ff)), 6),
                     uf_decode(_mm256_and_si256(_mm256_srli_epi32(z, 11), iset(0x7ff)), 6),
                     uf_decode(_mm256_srli_epi32(z, 22), 5)};
    const vf inv_k = dvd(fset(1.0f), k); /* k ∈ [1/4, 3/4] */
    for (int c = 0; c < 3; c++) {
        const vf amb = mul(r, e[c]);
        const vf inten = quot(mul(one_r, e[c]), k, inv_k);
        out->c[c][0] = add(amb, mul(fset(0.25f), inten));
        const vf h = mul(fset(0.5f), inten);
        for (int i = 0; i < 3; i++) out->c[c][1 + i] = mul(h, d[i]);
    }
}

INL void texel_accumulate(lin8 *acc, const lin8 *l, vf w)
{
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) acc->c[c][i] = add(acc->c[c][i], mul(w, l->c[c][i]));
}

/* ahd.c's sanitize: NaN → 0, clamped to ±1e30. */
INL vf sanitize(vf x)
{
    x = _mm256_and_ps(x, _mm256_cmp_ps(x, x, _CMP_ORD_Q));
    return _mm256_min_ps(_mm256_max_ps(x, fset(-1e30f)), fset(1e30f));
}

/* One half (4 lanes) of the encoder's direction in double: s = Σ lum_c g_c, then dir. */
INL void encode_dir_half(const vd g[3][3], vd dir[3])
{
    const vd lw[3] = {_mm256_set1_pd((double)LBK_LUM_R), _mm256_set1_pd((double)LBK_LUM_G),
                      _mm256_set1_pd((double)LBK_LUM_B)};
    vd s[3];
    for (int i = 0; i < 3; i++) /* 0 + x is x here: a zero's sign cannot reach the bytes */
        s[i] = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(lw[0], g[0][i]), _mm256_mul_pd(lw[1], g[1][i])),
                             _mm256_mul_pd(lw[2], g[2][i]));
    const vd xy = _mm256_add_pd(_mm256_mul_pd(s[0], s[0]), _mm256_mul_pd(s[1], s[1]));
    const vd len = _mm256_sqrt_pd(_mm256_add_pd(xy, _mm256_mul_pd(s[2], s[2])));
    const vd lxy = _mm256_sqrt_pd(xy);
    const vd tiny = _mm256_set1_pd(1e-30), zero = _mm256_setzero_pd();
    const vd up = _mm256_cmp_pd(s[2], zero, _CMP_GE_OQ);
    const vd has_len = _mm256_cmp_pd(len, tiny, _CMP_GE_OQ);
    const vd use = _mm256_and_pd(has_len, _mm256_or_pd(up, _mm256_cmp_pd(lxy, tiny, _CMP_GE_OQ)));
    const vd den = _mm256_blendv_pd(lxy, len, up);
    dir[0] = _mm256_and_pd(use, _mm256_div_pd(s[0], den));
    dir[1] = _mm256_and_pd(use, _mm256_div_pd(s[1], den));
    const vd z = _mm256_and_pd(up, _mm256_div_pd(s[2], den));
    dir[2] = _mm256_blendv_pd(_mm256_set1_pd(1.0), z, use);
}

/* One half of Σ_c lum_c · v_c in double, in channel order. */
INL vd lum_half(vd v0, vd v1, vd v2)
{
    return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd((double)LBK_LUM_R), v0),
                                       _mm256_mul_pd(_mm256_set1_pd((double)LBK_LUM_G), v1)),
                         _mm256_mul_pd(_mm256_set1_pd((double)LBK_LUM_B), v2));
}

/* lbk_ahd_from_linear. */
INL void texel_encode(const lin8 *lin, vi *z_out, vi *rgba_out)
{
    vf e0[3], g[3][3];
    /* sanitize changes nothing unless a component is NaN or beyond ±1e30: test that first */
    vi big = _mm256_setzero_si256();
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) big = _mm256_max_epu32(big, _mm256_and_si256(_mm256_castps_si256(lin->c[c][i]), iset(0x7fffffff)));
    const int clean = _mm256_testz_si256(_mm256_cmpgt_epi32(big, iset(0x7149F2CA)), iset(-1)); /* bits of 1e30f */
    for (int c = 0; c < 3; c++) {
        e0[c] = clean ? lin->c[c][0] : sanitize(lin->c[c][0]);
        for (int i = 0; i < 3; i++) g[c][i] = clean ? lin->c[c][1 + i] : sanitize(lin->c[c][1 + i]);
    }
    vd gl[3][3], gh[3][3], dl[3], dh[3];
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 3; i++) gl[c][i] = lo_d(g[c][i]), gh[c][i] = hi_d(g[c][i]);
    encode_dir_half(gl, dl);
    encode_dir_half(gh, dh);
    const vd one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    vi q[3];
    for (int i = 0; i < 2; i++)
        q[i] = unorm8(to_f(_mm256_mul_pd(_mm256_add_pd(dl[i], one), half), _mm256_mul_pd(_mm256_add_pd(dh[i], one), half)));
    q[2] = unorm8(to_f(dl[2], dh[2]));
    vi rgba = _mm256_or_si256(_mm256_slli_epi32(q[0], 8), _mm256_or_si256(_mm256_slli_epi32(q[1], 16), _mm256_slli_epi32(q[2], 24)));
    vf d[3], k;
    direction(rgba, d, &k);
    vf a[3], ez[3];
    for (int c = 0; c < 3; c++) {
        const vf gd = add(add(mul(g[c][0], d[0]), mul(g[c][1], d[1])), mul(g[c][2], d[2]));
        const vf inten = _mm256_and_ps(gt(gd, _mm256_setzero_ps()), mul(fset(2.0f), gd));
        const vf amb = sub(e0[c], mul(fset(0.25f), inten));
        a[c] = _mm256_and_ps(gt(amb, _mm256_setzero_ps()), amb);
        ez[c] = add(a[c], mul(inten, k));
    }
    const vd la_l = lum_half(lo_d(a[0]), lo_d(a[1]), lo_d(a[2])), la_h = lum_half(hi_d(a[0]), hi_d(a[1]), hi_d(a[2]));
    const vd le_l = lum_half(lo_d(ez[0]), lo_d(ez[1]), lo_d(ez[2])), le_h = lum_half(hi_d(ez[0]), hi_d(ez[1]), hi_d(ez[2]));
    const vi ratio = unorm8(to_f(_mm256_div_pd(la_l, le_l), _mm256_div_pd(la_h, le_h)));
    const vf lit = _mm256_set_m128(_mm256_cvtpd_ps(_mm256_cmp_pd(le_h, _mm256_setzero_pd(), _CMP_GT_OQ)),
                                   _mm256_cvtpd_ps(_mm256_cmp_pd(le_l, _mm256_setzero_pd(), _CMP_GT_OQ)));
    /* the converted all-ones doubles are NaNs: their floats still have the sign bit blendv reads */
    const vi r = _mm256_castps_si256(sel(lit, _mm256_castsi256_ps(ratio), _mm256_castsi256_ps(iset(255))));
    *rgba_out = _mm256_or_si256(rgba, r);
    *z_out = _mm256_or_si256(uf_encode(ez[0], 6),
                             _mm256_or_si256(_mm256_slli_epi32(uf_encode(ez[1], 6), 11), _mm256_slli_epi32(uf_encode(ez[2], 5), 22)));
}

/* Byte codes from values v within 3e-4 of the exact ones: rne(v) clamped to [0, 255]; a lane whose
 * v lies within NEAR_MARGIN of a half-integer (or is NaN) is marked in *near. */
#define NEAR_MARGIN 0x1p-11f
INL vi byte_of(vf v, vf *near)
{
    const vf r = _mm256_round_ps(v, RNE);
    const vf dist = _mm256_andnot_ps(fset(-0.0f), sub(v, r));
    *near = _mm256_or_ps(*near, _mm256_cmp_ps(dist, fset(0.5f - NEAR_MARGIN), _CMP_NLE_UQ));
    return _mm256_cvtps_epi32(_mm256_min_ps(_mm256_max_ps(r, _mm256_setzero_ps()), fset(255.0f)));
}

INL vf fabs8(vf x) { return _mm256_andnot_ps(fset(-0.0f), x); }

/* lbk_ahd_from_linear for inputs that need no sanitising, in float, returning the lanes whose
 * bytes must come from texel_encode instead (bit i: lane i). Only the direction and ratio bytes
 * are approximations; d, k, the Ez words and the ambient terms are the definition's own float
 * operations on the direction bytes.
 *
 * The bounds (u = 2^−24). Direction: the exact code forms s = Σ_c lum_c g_c in double (error
 * ~2^−52 of A = Σ_i Σ_c |lum_c g_ci|), divides by |s| (or |s_xy| when s.z < 0), rounds (dir + 1)/2
 * to float (2^−25) and codes rne(255·x); z: rne(255·fl32(dir.z)). Here s is summed in float
 * (|error| ≤ γ3·A), and a lane goes on only if A ≤ 2·|s|, so the float s is within 6u·|s| of the
 * true one and its direction within 12u; |s|² in float, its square root, the reciprocal and the
 * product add 4.5u. So v = fl(fl(d + 1)·127.5) is within 127.5·(12u + 4.5u + u) + 2^−17 < 1.5e-4
 * of 127.5·(1 + s/|s|) and the exact code's value within 255·2^−25 of that: < 1.6e-4 apart; z
 * (255·d.z): < 255·16.5u + 2^−17 + 255·2^−25 < 2.7e-4. The sign of s.z decides the branch: a lane
 * with |s.z| ≤ 4u·A_z is left to texel_encode. s = 0 exactly (A = 0, or every product below
 * 2^−149: then |s| < 1e-30 too) is the exact (0, 0, 1). Ratio: a and e are sums of non-negative
 * terms, each within γ3 relative in float; with the division (u) and the product by 255 (2^−17)
 * and the exact code's float rounding (255·2^−25): < 255·7u + 2^−17 + 255·2^−25 < 1.2e-4 (a lane
 * with e < 2^−100 is left to texel_encode, so float underflow of a is negligible). All are below
 * NEAR_MARGIN = 2^−11 = 4.9e-4, so a value farther than that from a half-integer gives the byte
 * of the exact code. */
INL uint32_t texel_encode_fast(const lin8 *lin, vi *z_out, vi *rgba_out)
{
    const vf *g[3] = {&lin->c[0][1], &lin->c[1][1], &lin->c[2][1]};
    const vf lw[3] = {fset(LBK_LUM_R), fset(LBK_LUM_G), fset(LBK_LUM_B)};
    vf sv[3], A[3];
    for (int i = 0; i < 3; i++) {
        sv[i] = add(add(mul(lw[0], g[0][i]), mul(lw[1], g[1][i])), mul(lw[2], g[2][i]));
        A[i] = add(add(mul(lw[0], fabs8(g[0][i])), mul(lw[1], fabs8(g[1][i]))), mul(lw[2], fabs8(g[2][i])));
    }
    const vf zero = _mm256_setzero_ps(), all = add(add(A[0], A[1]), A[2]);
    const vf up = _mm256_cmp_ps(sv[2], zero, _CMP_GE_OQ);
    const vf xy = add(mul(sv[0], sv[0]), mul(sv[1], sv[1]));
    const vf den2 = sel(up, add(xy, mul(sv[2], sv[2])), xy);
    const vf den = _mm256_sqrt_ps(den2);
    const vf none = _mm256_cmp_ps(all, zero, _CMP_EQ_OQ); /* s = 0: the exact (0, 0, 1) */
    vf near = _mm256_cmp_ps(all, mul(den, fset(2.0f)), _CMP_NLE_UQ);
    near = _mm256_or_ps(near, _mm256_cmp_ps(den2, fset(0x1p-120f), _CMP_NGE_UQ));
    near = _mm256_or_ps(near, _mm256_cmp_ps(den2, fset(0x1p120f), _CMP_NLE_UQ));
    near = _mm256_or_ps(near, _mm256_cmp_ps(fabs8(sv[2]), mul(A[2], fset(0x1p-22f)), _CMP_LE_OQ));
    const vf inv = dvd(fset(1.0f), den);
    const vi q0 = byte_of(mul(add(mul(sv[0], inv), fset(1.0f)), fset(127.5f)), &near);
    const vi q1 = byte_of(mul(add(mul(sv[1], inv), fset(1.0f)), fset(127.5f)), &near);
    vf near_z = zero;
    const vi q2 = _mm256_and_si256(byte_of(mul(mul(sv[2], inv), fset(255.0f)), &near_z), _mm256_castps_si256(up));
    near = _mm256_andnot_ps(none, _mm256_or_ps(near, _mm256_and_ps(near_z, up)));
    vi rgba = _mm256_or_si256(_mm256_slli_epi32(q0, 8), _mm256_or_si256(_mm256_slli_epi32(q1, 16), _mm256_slli_epi32(q2, 24)));
    rgba = _mm256_castps_si256(sel(none, _mm256_castsi256_ps(iset((int)0xFF808000u)), _mm256_castsi256_ps(rgba)));
    vf d[3], k;
    direction(rgba, d, &k);
    vf a[3], ez[3];
    for (int c = 0; c < 3; c++) {
        const vf gd = add(add(mul(g[c][0], d[0]), mul(g[c][1], d[1])), mul(g[c][2], d[2]));
        const vf inten = _mm256_and_ps(gt(gd, zero), mul(fset(2.0f), gd));
        const vf amb = sub(lin->c[c][0], mul(fset(0.25f), inten));
        a[c] = _mm256_and_ps(gt(amb, zero), amb);
        ez[c] = add(a[c], mul(inten, k));
    }
    const vf la = add(add(mul(lw[0], a[0]), mul(lw[1], a[1])), mul(lw[2], a[2]));
    const vf le = add(add(mul(lw[0], ez[0]), mul(lw[1], ez[1])), mul(lw[2], ez[2]));
    /* the exact code's e > 0 (double, exact products): some ez_c > 0 */
    const vf lit = _mm256_cmp_ps(_mm256_max_ps(_mm256_max_ps(ez[0], ez[1]), ez[2]), zero, _CMP_GT_OQ);
    vf near_r = _mm256_cmp_ps(le, fset(0x1p-100f), _CMP_LT_OQ);
    const vi ratio = byte_of(mul(dvd(la, le), fset(255.0f)), &near_r);
    near = _mm256_or_ps(near, _mm256_and_ps(near_r, lit));
    const vi r = _mm256_castps_si256(sel(lit, _mm256_castsi256_ps(ratio), _mm256_castsi256_ps(iset(255))));
    *rgba_out = _mm256_or_si256(rgba, r);
    *z_out = _mm256_or_si256(uf_encode(ez[0], 6),
                             _mm256_or_si256(_mm256_slli_epi32(uf_encode(ez[1], 6), 11), _mm256_slli_epi32(uf_encode(ez[2], 5), 22)));
    return (uint32_t)_mm256_movemask_ps(near);
}

/* Components at most 1e30 in magnitude and no NaN: what lbk_ahd_from_linear's sanitize leaves as it is. */
INL int texel_clean(const lin8 *lin)
{
    vi big = _mm256_setzero_si256();
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) big = _mm256_max_epu32(big, _mm256_and_si256(_mm256_castps_si256(lin->c[c][i]), iset(0x7fffffff)));
    return _mm256_testz_si256(_mm256_cmpgt_epi32(big, iset(0x7149F2CA)), iset(-1)); /* bits of 1e30f */
}

/* lbk_ahd_from_linear of 8 lanes: the fast encoder, the exact one where it cannot decide. */
INL void texel_encode8(const lin8 *lin, vi *z, vi *rgba)
{
    if (!texel_clean(lin) || texel_encode_fast(lin, z, rgba)) texel_encode(lin, z, rgba);
}

/* ---- the texel kernels ------------------------------------------------------------------- */

INL vi load8(const uint8_t *p) { return _mm256_loadu_si256((const __m256i *)(const void *)p); }
INL void store8(uint8_t *p, vi v) { _mm256_storeu_si256((__m256i *)(void *)p, v); }

/* Entry words of 8 targets `stride` entries apart: word 0 (Ez) and word 1 (RGBA) of each. */
INL void texel_entries(const uint8_t *first, vi index, vi *z, vi *rgba)
{
    *z = _mm256_i32gather_epi32((const int *)(const void *)first, index, 4);
    *rgba = _mm256_i32gather_epi32((const int *)(const void *)(first + 4), index, 4);
}

/* The entries of 8 consecutive targets with one entry each: 64 contiguous bytes, split into the
 * Ez and RGBA words by shuffles instead of two gathers. */
INL void texel_entries_packed(const uint8_t *first, vi *z, vi *rgba)
{
    const vf a = _mm256_castsi256_ps(load8(first)), b = _mm256_castsi256_ps(load8(first + 32));
    *z = _mm256_permute4x64_epi64(_mm256_castps_si256(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0))), _MM_SHUFFLE(3, 1, 2, 0));
    *rgba = _mm256_permute4x64_epi64(_mm256_castps_si256(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1))), _MM_SHUFFLE(3, 1, 2, 0));
}

/* Eight targets from SoA buffers; n ≤ 8 valid lanes (the others compute on copies). */
INL void texel8(const uint8_t *bz, const uint8_t *brgba, uint8_t *oz, uint8_t *orgba,
                const uint8_t *entries, vi index, uint32_t stride, uint32_t m, const uint32_t *idx, const float *w)
{
    lin8 acc, l;
    texel_decode(load8(bz), load8(brgba), &acc);
    for (uint32_t j = 0; j < m; j++) {
        vi ez, erg;
        if (stride == 1) texel_entries_packed(entries, &ez, &erg); /* then m = 1 and idx[0] = 0 */
        else texel_entries(entries + (size_t)idx[j] * LBK_DLS_TEXEL_PAYLOAD, index, &ez, &erg);
        texel_decode(ez, erg, &l);
        texel_accumulate(&acc, &l, fset(w[j]));
    }
    vi z, rgba;
    texel_encode8(&acc, &z, &rgba);
    store8(oz, z);
    store8(orgba, rgba);
}

static void texels(const dls_batch *b)
{
    const uint32_t words = 2 * b->stride; /* entry words per target */
    const vi index = _mm256_mullo_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), iset((int)words));
    const size_t step = (size_t)8 * b->stride * LBK_DLS_TEXEL_PAYLOAD;
    uint32_t t = 0;
    for (; t + 8 <= b->count; t += 8)
        texel8(b->base0 + 4 * (size_t)t, b->base1 + 4 * (size_t)t, b->out0 + 4 * (size_t)t,
               b->out1 + 4 * (size_t)t, b->entries + (t / 8) * step, index, b->stride, b->m, b->idx, b->w);
    if (t == b->count) return;
    /* the tail: lanes past the end repeat the last target, and only the valid lanes are stored */
    const uint32_t n = b->count - t;
    uint8_t bz[32], brgba[32], oz[32], orgba[32];
    for (uint32_t i = 0; i < 8; i++) {
        const uint32_t s = i < n ? i : n - 1;
        memcpy(bz + 4 * i, b->base0 + 4 * (size_t)(t + s), 4);
        memcpy(brgba + 4 * i, b->base1 + 4 * (size_t)(t + s), 4);
    }
    const vi tail_index = _mm256_mullo_epi32(_mm256_min_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), iset((int)n - 1)),
                                             iset((int)words));
    texel8(bz, brgba, oz, orgba, b->entries + (t / 8) * step, tail_index, 0, b->m, b->idx, b->w); /* 0: gather */
    memcpy(b->out0 + 4 * (size_t)t, oz, 4 * (size_t)n);
    memcpy(b->out1 + 4 * (size_t)t, orgba, 4 * (size_t)n);
}

/* ---- SH9 probes (sh.c) ------------------------------------------------------------------- */

#define BS1 1.7320508075688772f /* sh.c band_scale: √3, √5 */
#define BS2 2.2360679774997897f

typedef struct sh8 {
    vf c[3][9];
} sh8;

/* Byte `b` of 8 probes whose 7 words are in w[0..6], sign-extended. */
INL vi probe_sbyte(const vi w[7], int b) { return _mm256_srai_epi32(_mm256_slli_epi32(w[b / 4], 24 - 8 * (b % 4)), 24); }

/* lbk_rgb9e5_unpack. */
INL void rgb9e5_unpack(vi w, vf dq[3])
{
    const vf scale = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_add_epi32(_mm256_srli_epi32(w, 27), iset(103)), 23));
    for (int c = 0; c < 3; c++)
        dq[c] = mul(_mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(w, 9 * c), iset(0x1ff))), scale);
}

/* lbk_sh9_unpack. */
INL void probe_decode(const vi w[7], sh8 *out)
{
    vf dq[3];
    rgb9e5_unpack(w[0], dq);
    for (int c = 0; c < 3; c++) {
        out->c[c][0] = dq[c];
        for (int k = 1; k < 9; k++)
            out->c[c][k] = mul(mul(snorm_f(probe_sbyte(w, 4 + 3 * (k - 1) + c)), fset(k < 4 ? BS1 : BS2)), dq[c]);
    }
}

/* lbk_rgb9e5_pack, in float: every scaling is by a power of two, so it is exact where the
 * scalar double code is (and a product too small to be exact rounds to 0 in both). */
INL vi rgb9e5_pack(const vf rgb[3])
{
    vf c[3];
    for (int i = 0; i < 3; i++) c[i] = _mm256_min_ps(_mm256_max_ps(rgb[i], _mm256_setzero_ps()), fset(LBK_RGB9E5_MAX));
    const vf maxc = _mm256_max_ps(_mm256_max_ps(c[0], c[1]), c[2]);
    /* floor(log2 maxc) from the exponent field; a float denormal (or 0) is below −16 anyway */
    vi e = _mm256_sub_epi32(_mm256_srli_epi32(_mm256_castps_si256(maxc), 23), iset(127));
    e = _mm256_add_epi32(_mm256_max_epi32(e, iset(-16)), iset(16));
    vf scale = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_sub_epi32(iset(24 + 127), e), 23));
    const vf top = _mm256_round_ps(mul(maxc, scale), RNE);
    const vi bump = _mm256_castps_si256(_mm256_cmp_ps(top, fset(512.0f), _CMP_GE_OQ));
    e = _mm256_sub_epi32(e, bump); /* bump is −1 where set */
    scale = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_sub_epi32(iset(24 + 127), e), 23));
    vi out = _mm256_slli_epi32(e, 27);
    for (int i = 0; i < 3; i++)
        out = _mm256_or_si256(out, _mm256_slli_epi32(_mm256_cvtps_epi32(_mm256_round_ps(mul(c[i], scale), RNE)), 9 * i));
    return out;
}

/* lbk_sh9_pack into 7 words per lane. */
INL void probe_encode(const sh8 *sh, vi w[7])
{
    const vf dc[3] = {sh->c[0][0], sh->c[1][0], sh->c[2][0]};
    w[0] = rgb9e5_pack(dc);
    vf dq[3];
    rgb9e5_unpack(w[0], dq);
    for (int i = 1; i < 7; i++) w[i] = _mm256_setzero_si256();
    for (int c = 0; c < 3; c++) {
        const vf pos = gt(dq[c], _mm256_setzero_ps());
        const vf div1 = mul(fset(BS1), dq[c]), div2 = mul(fset(BS2), dq[c]);
        for (int k = 1; k < 9; k++) {
            vi q = snorm8(dvd(sh->c[c][k], k < 4 ? div1 : div2));
            q = _mm256_and_si256(q, _mm256_castps_si256(pos));
            const int b = 4 + 3 * (k - 1) + c;
            w[b / 4] = _mm256_or_si256(w[b / 4], _mm256_slli_epi32(q, 8 * (b % 4)));
        }
    }
}

INL void probe_accumulate(sh8 *acc, const sh8 *l, vf w)
{
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++) acc->c[c][k] = add(acc->c[c][k], mul(w, l->c[c][k]));
}

/* The 7 words of 8 probes `stride` bytes apart (index: lane · stride / 4). */
INL void probe_gather(const uint8_t *first, vi index, vi w[7])
{
    for (int i = 0; i < 7; i++) w[i] = _mm256_i32gather_epi32((const int *)(const void *)(first + 4 * i), index, 4);
}

INL void probe_scatter(uint8_t *out, const vi w[7], uint32_t n)
{
    uint32_t tmp[7][8];
    for (int i = 0; i < 7; i++) _mm256_storeu_si256((__m256i *)(void *)tmp[i], w[i]);
    for (uint32_t l = 0; l < n; l++)
        for (int i = 0; i < 7; i++) memcpy(out + LBK_DLS_PROBE_PAYLOAD * l + 4 * i, &tmp[i][l], 4);
}

static void probes(const dls_batch *b)
{
    const vi lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const vi base_index = _mm256_mullo_epi32(lane, iset(7));
    for (uint32_t t = 0; t < b->count; t += 8) {
        const uint32_t n = b->count - t < 8 ? b->count - t : 8;
        const vi valid = _mm256_min_epi32(lane, iset((int)n - 1));
        const vi bi = n == 8 ? base_index : _mm256_mullo_epi32(valid, iset(7));
        const vi ei = _mm256_mullo_epi32(valid, iset((int)(7 * b->stride)));
        vi w[7];
        sh8 acc, l;
        probe_gather(b->base0 + LBK_DLS_PROBE_PAYLOAD * (size_t)t, bi, w);
        probe_decode(w, &acc);
        const uint8_t *e = b->entries + (size_t)t * b->stride * LBK_DLS_PROBE_PAYLOAD;
        for (uint32_t j = 0; j < b->m; j++) {
            probe_gather(e + (size_t)b->idx[j] * LBK_DLS_PROBE_PAYLOAD, ei, w);
            probe_decode(w, &l);
            probe_accumulate(&acc, &l, fset(b->w[j]));
        }
        probe_encode(&acc, w);
        probe_scatter(b->out0 + LBK_DLS_PROBE_PAYLOAD * (size_t)t, w, n);
    }
}

/* ---- variable entries per target (prefix forms) ------------------------------------------ */

/* Lanes run to the longest target's count; an entry past a lane's own count, or of a set that
 * is off, gets weight 0: acc + 0·S = acc exactly for the finite S a decode gives (up to a
 * zero's sign, which cannot reach the bytes), so it changes nothing. A lane none of whose
 * weights is non-zero takes the base bytes, as the definition says. */
static void texels_var(const dls_var_batch *b)
{
    for (uint32_t t = 0; t < b->count; t += 8) {
        const uint32_t n = b->count - t < 8 ? b->count - t : 8;
        uint32_t most = 0;
        int32_t off[8];
        uint32_t active = 0;
        for (uint32_t i = 0; i < 8; i++) {
            const uint32_t s = t + (i < n ? i : n - 1);
            off[i] = (int32_t)(2 * b->off[s]);
            if (b->n[s] > most) most = b->n[s];
            for (uint32_t j = 0; j < b->n[s]; j++)
                if (b->we[b->off[s] - b->off[0] + j] != 0.0f) { active |= 1u << i; break; }
        }
        uint8_t bz[32], brgba[32], oz[32], orgba[32];
        for (uint32_t i = 0; i < 8; i++) {
            const uint32_t s = t + (i < n ? i : n - 1);
            memcpy(bz + 4 * i, b->base0 + 4 * (size_t)s, 4);
            memcpy(brgba + 4 * i, b->base1 + 4 * (size_t)s, 4);
        }
        lin8 acc, l;
        texel_decode(load8(bz), load8(brgba), &acc);
        const vi base_index = _mm256_loadu_si256((const __m256i *)(const void *)off);
        for (uint32_t j = 0; j < most; j++) {
            float wl[8];
            int32_t at[8];
            for (uint32_t i = 0; i < 8; i++) {
                const uint32_t s = t + (i < n ? i : n - 1);
                const bool has = j < b->n[s];
                wl[i] = has ? b->we[b->off[s] - b->off[0] + j] : 0.0f;
                at[i] = has ? (int32_t)(2 * j) : 0;
            }
            const vi index = _mm256_add_epi32(base_index, _mm256_loadu_si256((const __m256i *)(const void *)at));
            vi ez, erg;
            texel_entries(b->entries, index, &ez, &erg);
            texel_decode(ez, erg, &l);
            texel_accumulate(&acc, &l, _mm256_loadu_ps(wl));
        }
        vi z, rgba;
        texel_encode8(&acc, &z, &rgba);
        store8(oz, z);
        store8(orgba, rgba);
        for (uint32_t i = 0; i < n; i++) {
            const bool on = active >> i & 1u;
            memcpy(b->out0 + 4 * (size_t)(t + i), on ? oz + 4 * i : bz + 4 * i, 4);
            memcpy(b->out1 + 4 * (size_t)(t + i), on ? orgba + 4 * i : brgba + 4 * i, 4);
        }
    }
}

static void probes_var(const dls_var_batch *b)
{
    const vi lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    for (uint32_t t = 0; t < b->count; t += 8) {
        const uint32_t n = b->count - t < 8 ? b->count - t : 8;
        uint32_t most = 0, active = 0;
        int32_t off[8];
        for (uint32_t i = 0; i < 8; i++) {
            const uint32_t s = t + (i < n ? i : n - 1);
            off[i] = (int32_t)(7 * b->off[s]);
            if (b->n[s] > most) most = b->n[s];
            for (uint32_t j = 0; j < b->n[s]; j++)
                if (b->we[b->off[s] - b->off[0] + j] != 0.0f) { active |= 1u << i; break; }
        }
        const vi bi = _mm256_mullo_epi32(_mm256_min_epi32(lane, iset((int)n - 1)), iset(7));
        vi w[7];
        sh8 acc, l;
        probe_gather(b->base0 + LBK_DLS_PROBE_PAYLOAD * (size_t)t, bi, w);
        probe_decode(w, &acc);
        const vi base_index = _mm256_loadu_si256((const __m256i *)(const void *)off);
        for (uint32_t j = 0; j < most; j++) {
            float wl[8];
            int32_t at[8];
            for (uint32_t i = 0; i < 8; i++) {
                const uint32_t s = t + (i < n ? i : n - 1);
                const bool has = j < b->n[s];
                wl[i] = has ? b->we[b->off[s] - b->off[0] + j] : 0.0f;
                at[i] = has ? (int32_t)(7 * j) : 0;
            }
            probe_gather(b->entries, _mm256_add_epi32(base_index, _mm256_loadu_si256((const __m256i *)(const void *)at)), w);
            probe_decode(w, &l);
            probe_accumulate(&acc, &l, _mm256_loadu_ps(wl));
        }
        probe_encode(&acc, w);
        uint8_t out[8 * LBK_DLS_PROBE_PAYLOAD];
        probe_scatter(out, w, n);
        for (uint32_t i = 0; i < n; i++) {
            const uint8_t *src = active >> i & 1u ? out + LBK_DLS_PROBE_PAYLOAD * i : b->base0 + LBK_DLS_PROBE_PAYLOAD * (size_t)(t + i);
            memcpy(b->out0 + LBK_DLS_PROBE_PAYLOAD * (size_t)(t + i), src, LBK_DLS_PROBE_PAYLOAD);
        }
    }
}

/* ---- the codecs alone (tests) -------------------------------------------------------------- */

static void texel_decode_n(const uint32_t *z, const uint32_t *rgba, uint32_t count, lbk_ahd_linear *out)
{
    for (uint32_t t = 0; t < count; t += 8) {
        const uint32_t n = count - t < 8 ? count - t : 8;
        uint32_t bz[8], brgba[8];
        float lanes[12][8];
        for (uint32_t i = 0; i < 8; i++) bz[i] = z[t + (i < n ? i : n - 1)], brgba[i] = rgba[t + (i < n ? i : n - 1)];
        lin8 l;
        texel_decode(load8((const uint8_t *)bz), load8((const uint8_t *)brgba), &l);
        for (int c = 0; c < 12; c++) _mm256_storeu_ps(lanes[c], l.c[c / 4][c % 4]);
        for (uint32_t i = 0; i < n; i++)
            for (int c = 0; c < 12; c++) out[t + i].c[c / 4][c % 4] = lanes[c][i];
    }
}

static void texel_encode_n(const lbk_ahd_linear *in, uint32_t count, uint32_t *z, uint32_t *rgba)
{
    for (uint32_t t = 0; t < count; t += 8) {
        const uint32_t n = count - t < 8 ? count - t : 8;
        float lanes[12][8];
        for (uint32_t i = 0; i < 8; i++)
            for (int c = 0; c < 12; c++) lanes[c][i] = in[t + (i < n ? i : n - 1)].c[c / 4][c % 4];
        lin8 l;
        for (int c = 0; c < 12; c++) l.c[c / 4][c % 4] = _mm256_loadu_ps(lanes[c]);
        vi vz, vrgba;
        uint32_t oz[8], orgba[8];
        texel_encode8(&l, &vz, &vrgba);
        store8((uint8_t *)oz, vz), store8((uint8_t *)orgba, vrgba);
        memcpy(z + t, oz, 4 * (size_t)n), memcpy(rgba + t, orgba, 4 * (size_t)n);
    }
}

static void probe_decode_n(const uint8_t *p, uint32_t count, lbk_sh9_rgb *out)
{
    const vi lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    for (uint32_t t = 0; t < count; t += 8) {
        const uint32_t n = count - t < 8 ? count - t : 8;
        vi w[7];
        sh8 l;
        float lanes[27][8];
        probe_gather(p + LBK_DLS_PROBE_PAYLOAD * (size_t)t, _mm256_mullo_epi32(_mm256_min_epi32(lane, iset((int)n - 1)), iset(7)), w);
        probe_decode(w, &l);
        for (int c = 0; c < 27; c++) _mm256_storeu_ps(lanes[c], l.c[c / 9][c % 9]);
        for (uint32_t i = 0; i < n; i++)
            for (int c = 0; c < 27; c++) out[t + i].c[c / 9][c % 9] = lanes[c][i];
    }
}

/* ---- the linear mode: the scalar lin_sum / lin_var element by element, 8 (or 4) lanes wide;
 * the same multiplies and adds in the same order, so the same floats. -------------------------- */

#define LIN_MAX_SRC 8 /* fixed forms: dedicated clusters have ≤ 8 sets, packed ones ≤ 4 */

/* One output element by the definition (the head and tail of a streamed stretch). */
INL float lin_one(const float *base, const float *const *src, const float *w, uint32_t m, size_t i)
{
    float acc = base[i];
    for (uint32_t j = 0; j < m; j++) acc += w[j] * src[j][i];
    return acc;
}

/* Step of 4 floats (one texel's plane; the ends of a stretch), an ordinary store. */
INL void lin_step4(const float *base, const float *const *src, const float *w, uint32_t m, size_t i, float *out)
{
    __m128 a = _mm_loadu_ps(base + i);
    for (uint32_t j = 0; j < m; j++) a = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(w[j]), _mm_loadu_ps(src[j] + i)));
    _mm_storeu_ps(out + i, a);
}

/* Inputs are fetched this many floats (1 KiB) ahead: a cluster's 3·(1 + m) input streams advance
 * one chart row at a time, interleaved, and the hardware's stream prefetcher, which stops at each
 * 4 KiB boundary, lags them. Measured on the ESTATE-sized level (bench_dls, one thread, four
 * alternations, non-temporal outputs): 0.47 of memcpy without, 0.50 / 0.51 / 0.50 at 128 / 256 /
 * 512 floats. A prefetch past an array's end is harmless (prefetches do not fault). */
#define LIN_PREFETCH 256

/* Step of 16 floats (one 64-byte output line) with two accumulators. */
INL void lin_step16(const float *base, const float *const *src, const vf *wv, uint32_t m, size_t i, float *out, int stream)
{
    _mm_prefetch((const char *)(base + i + LIN_PREFETCH), _MM_HINT_T0);
    for (uint32_t j = 0; j < m; j++) _mm_prefetch((const char *)(src[j] + i + LIN_PREFETCH), _MM_HINT_T0);
    vf a0 = _mm256_loadu_ps(base + i), a1 = _mm256_loadu_ps(base + i + 8);
    for (uint32_t j = 0; j < m; j++) {
        const float *s = src[j] + i;
        a0 = add(a0, mul(wv[j], _mm256_loadu_ps(s)));
        a1 = add(a1, mul(wv[j], _mm256_loadu_ps(s + 8)));
    }
    if (stream) _mm256_stream_ps(out + i, a0), _mm256_stream_ps(out + i + 8, a1);
    else _mm256_storeu_ps(out + i, a0), _mm256_storeu_ps(out + i + 8, a1);
}

/* The outputs' whole 64-byte lines are written with non-temporal stores: an apply writes every
 * output once and reads none, and an ordinary store first reads the line for ownership: on the
 * ESTATE-sized level that takes a full apply's reads (the limit on one thread) from the 287 MB of
 * inputs to 444 MB with the outputs' lines. The lines an output stretch only partly covers
 * (chart rows start anywhere) keep ordinary stores: a partial non-temporal line costs a read at
 * the memory controller instead. The job ends with lin_end's store fence. */
static void lin_sum_wide(const float *base, const float *const *src, const float *w, uint32_t m, size_t n, float *out)
{
    vf wv[LIN_MAX_SRC];
    for (uint32_t j = 0; j < m; j++) wv[j] = fset(w[j]);
    size_t i = 0;
    const uintptr_t mis = (uintptr_t)out % 64;
    if (mis % 4 == 0 && n >= 16) { /* up to the first line boundary, then whole lines streamed */
        const size_t head = mis ? (64 - mis) / 4 : 0;
        for (; i + 4 <= head; i += 4) lin_step4(base, src, w, m, i, out);
        for (; i < head; i++) out[i] = lin_one(base, src, w, m, i);
        for (; i + 16 <= n; i += 16) lin_step16(base, src, wv, m, i, out, 1);
    }
    for (; i + 16 <= n; i += 16) lin_step16(base, src, wv, m, i, out, 0);
    for (; i + 8 <= n; i += 8) {
        vf a = _mm256_loadu_ps(base + i);
        for (uint32_t j = 0; j < m; j++) a = add(a, mul(wv[j], _mm256_loadu_ps(src[j] + i)));
        _mm256_storeu_ps(out + i, a);
    }
    if (i + 4 <= n) lin_step4(base, src, w, m, i, out), i += 4;
    for (; i < n; i++) out[i] = lin_one(base, src, w, m, i);
}

static void lin_sum(const float *base, const float *const *src, const float *w, uint32_t m, size_t n, float *out)
{
    if (m > LIN_MAX_SRC) { /* not reached by the runtime; the definition, in groups of 8 lanes */
        for (size_t i = 0; i < n; i++) {
            float acc = base[i];
            for (uint32_t j = 0; j < m; j++) acc += w[j] * src[j][i];
            out[i] = acc;
        }
        return;
    }
    lin_sum_wide(base, src, w, m, n, out);
}

static void lin_var(const float *base, const float *entries, const float *we, const uint32_t *n, uint32_t count, uint32_t f,
                    float *out)
{
    for (uint32_t t = 0; t < count; t++) {
        uint32_t i = 0;
        for (; i + 8 <= f; i += 8) {
            vf a = _mm256_loadu_ps(base + i);
            for (uint32_t e = 0; e < n[t]; e++)
                if (we[e] != 0.0f) a = add(a, mul(fset(we[e]), _mm256_loadu_ps(entries + (size_t)e * f + i)));
            _mm256_storeu_ps(out + i, a);
        }
        for (; i + 4 <= f; i += 4) {
            __m128 a = _mm_loadu_ps(base + i);
            for (uint32_t e = 0; e < n[t]; e++)
                if (we[e] != 0.0f) a = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(we[e]), _mm_loadu_ps(entries + (size_t)e * f + i)));
            _mm_storeu_ps(out + i, a);
        }
        for (; i < f; i++) {
            float acc = base[i];
            for (uint32_t e = 0; e < n[t]; e++)
                if (we[e] != 0.0f) acc += we[e] * entries[(size_t)e * f + i];
            out[i] = acc;
        }
        base += f, out += f;
        entries += (size_t)n[t] * f, we += n[t];
    }
}

/* Orders lin_sum's non-temporal stores before whatever follows the job (its completion). */
static void lin_end(void) { _mm_sfence(); }

#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

const dls_kernels *dls_kernels_avx2(void)
{
    static const dls_kernels k = {"avx2", texels, probes, texels_var, probes_var, texel_decode_n, texel_encode_n, probe_decode_n,
                                  lin_sum, lin_var, lin_end, true};
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") ? &k : 0;
}
#endif
