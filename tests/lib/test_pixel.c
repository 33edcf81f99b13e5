/* Pixel codecs: exhaustive round trips of every code of the small formats, a strided sweep over
 * all 2^32 float bit patterns against an independent nearest-value reference, error bounds and
 * the special-value rules of lbk/pixel.h. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/pixel.h"

static float bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* ---- an independent reference: the sorted table of every finite non-negative value ------- */
typedef struct table {
    double v[32768];
    uint32_t n; /* codes 0..n-1 are the finite non-negative values, increasing */
} table;

/* Builds the value table from the format definition (not from the library's decoder). */
static void build_table(table *t, unsigned mbits)
{
    t->n = 31u << mbits;
    for (uint32_t c = 0; c < t->n; c++) {
        const uint32_t e = c >> mbits, m = c & ((1u << mbits) - 1);
        t->v[c] = e == 0 ? ldexp((double)m, -14 - (int)mbits) : ldexp(1.0 + ldexp((double)m, -(int)mbits), (int)e - 15);
    }
}

/* Nearest code for a finite x ≥ 0, ties to the even code, saturating at the largest. */
static uint32_t reference_encode(const table *t, double x)
{
    if (x >= t->v[t->n - 1]) return t->n - 1;
    uint32_t lo = 0, hi = t->n - 1; /* v[lo] ≤ x < v[hi] */
    while (hi - lo > 1) {
        const uint32_t mid = (lo + hi) / 2;
        if (t->v[mid] <= x) lo = mid;
        else hi = mid;
    }
    const double dl = x - t->v[lo], dh = t->v[hi] - x;
    if (dl < dh) return lo;
    if (dh < dl) return hi;
    return (lo & 1u) ? hi : lo;
}

static void every_code_round_trips(void **state)
{
    (void)state;
    for (uint32_t c = 0; c < (31u << 6); c++) assert_int_equal(lbk_float_to_uf11(lbk_uf11_to_float(c)), c);
    for (uint32_t c = 0; c < (31u << 5); c++) assert_int_equal(lbk_float_to_uf10(lbk_uf10_to_float(c)), c);
    for (uint32_t c = 0; c < 0x10000u; c++) {
        if ((c & 0x7c00u) == 0x7c00u) continue; /* Inf/NaN codes: never produced */
        assert_int_equal(lbk_float_to_half(lbk_half_to_float((uint16_t)c)), c);
    }
    for (uint32_t c = 0; c < 256; c++) assert_int_equal(lbk_float_to_unorm8(lbk_unorm8_to_float((uint8_t)c)), c);
    for (uint32_t c = 0; c < 256; c++) {
        const uint32_t expect = c == 0x80u ? 0x81u : c; /* −128 means −1, which encodes as −127 */
        assert_int_equal(lbk_float_to_snorm8(lbk_snorm8_to_float((uint8_t)c)), expect);
    }
    assert_true(lbk_snorm8_to_float(0x80) == -1.0f);
    assert_true(lbk_snorm8_to_float(0x81) == -1.0f);
    assert_true(lbk_snorm8_to_float(0x7f) == 1.0f);
}

static void decoders_match_definition(void **state)
{
    (void)state;
    table *t = malloc(sizeof *t);
    assert_non_null(t);
    build_table(t, 6);
    for (uint32_t c = 0; c < t->n; c++) assert_true((double)lbk_uf11_to_float(c) == t->v[c]);
    build_table(t, 5);
    for (uint32_t c = 0; c < t->n; c++) assert_true((double)lbk_uf10_to_float(c) == t->v[c]);
    build_table(t, 10);
    for (uint32_t c = 0; c < t->n; c++) {
        assert_true((double)lbk_half_to_float((uint16_t)c) == t->v[c]);
        assert_true((double)lbk_half_to_float((uint16_t)(c | 0x8000u)) == -t->v[c]);
    }
    assert_true(lbk_uf11_to_float(0x7ff) != lbk_uf11_to_float(0x7ff)); /* NaN code */
    assert_true(isinf(lbk_uf11_to_float(0x7c0)));
    assert_true(lbk_uf11_to_float(1) == ldexpf(1.0f, -20)); /* smallest denormal */
    assert_true(lbk_uf10_to_float(1) == ldexpf(1.0f, -19));
    assert_true(lbk_half_to_float(1) == ldexpf(1.0f, -24));
    assert_true(lbk_uf11_to_float(0x7bf) == LBK_UF11_MAX);
    assert_true(lbk_uf10_to_float(0x3df) == LBK_UF10_MAX);
    assert_true(lbk_half_to_float(0x7bff) == LBK_HALF_MAX);
    free(t);
}

/* Stride through all 2^32 patterns (odd stride, so every residue class of low bits is hit). */
#define SWEEP_STRIDE 521u

static void sweep_small(unsigned mbits, uint32_t (*enc)(float), float (*dec)(uint32_t), int is_half)
{
    table *t = malloc(sizeof *t);
    assert_non_null(t);
    build_table(t, mbits);
    const double max_rel = ldexp(1.0, -(int)mbits - 1); /* half an ulp of the mantissa */
    const double denorm_step = ldexp(1.0, -14 - (int)mbits);
    uint64_t checked = 0;
    for (uint64_t i = 0; i < (1ull << 32); i += SWEEP_STRIDE) {
        const uint32_t u = (uint32_t)i;
        const float x = bits_float(u);
        const uint32_t got = enc(x);
        uint32_t expect;
        const int neg = (u >> 31) != 0;
        if (isnan(x)) expect = 0;
        else if (isinf(x)) expect = (is_half && neg) ? 0x8000u | (t->n - 1) : (neg && !is_half ? 0 : t->n - 1);
        else if (neg && !is_half) expect = 0;
        else {
            expect = reference_encode(t, fabs((double)x));
            if (is_half && neg) expect |= 0x8000u;
        }
        if (got != expect) fail_msg("pattern 0x%08x (%g): got 0x%x expected 0x%x", u, (double)x, got, expect);
        /* error bound for finite in-range values */
        if (isfinite(x) && (!neg || is_half)) {
            const double ax = fabs((double)x), d = fabs((double)dec(got & 0x7fffu));
            if (ax <= t->v[t->n - 1]) {
                if (ax >= ldexp(1.0, -14)) assert_true(fabs(d - ax) <= max_rel * ax);
                else assert_true(fabs(d - ax) <= 0.5 * denorm_step);
            } else {
                assert_true(d == t->v[t->n - 1]);
            }
        }
        checked++;
    }
    assert_true(checked > 8000000u);
    free(t);
}

static float dec_uf11(uint32_t c) { return lbk_uf11_to_float(c); }
static float dec_uf10(uint32_t c) { return lbk_uf10_to_float(c); }
static float dec_half(uint32_t c) { return lbk_half_to_float((uint16_t)c); }
static uint32_t enc_half(float x) { return lbk_float_to_half(x); }

static void sweep_uf11(void **state) { (void)state; sweep_small(6, lbk_float_to_uf11, dec_uf11, 0); }
static void sweep_uf10(void **state) { (void)state; sweep_small(5, lbk_float_to_uf10, dec_uf10, 0); }
static void sweep_half(void **state) { (void)state; sweep_small(10, enc_half, dec_half, 1); }

static void sweep_norm8(void **state)
{
    (void)state;
    for (uint64_t i = 0; i < (1ull << 32); i += SWEEP_STRIDE * 3u) {
        const float x = bits_float((uint32_t)i);
        /* reference: exhaustive nearest code, ties to even code */
        uint32_t eu = 0, es = 0;
        if (!isnan(x)) {
            const double cu = x < 0.0f ? 0.0 : (x > 1.0f ? 1.0 : (double)x);
            double best = 1e9;
            for (uint32_t c = 0; c < 256; c++) {
                const double dd = fabs(c / 255.0 - cu);
                if (dd < best || (dd == best && !(c & 1u))) { best = dd; eu = c; }
            }
            const double cs = x < -1.0f ? -1.0 : (x > 1.0f ? 1.0 : (double)x);
            best = 1e9;
            for (int c = -127; c <= 127; c++) {
                const double dd = fabs(c / 127.0 - cs);
                if (dd < best || (dd == best && !(c & 1))) { best = dd; es = (uint32_t)(uint8_t)(int8_t)c; }
            }
        }
        assert_int_equal(lbk_float_to_unorm8(x), eu);
        assert_int_equal(lbk_float_to_snorm8(x), es);
    }
}

static void special_values(void **state)
{
    (void)state;
    const float nan = NAN, inf = INFINITY;
    /* NaN → 0 everywhere */
    assert_int_equal(lbk_float_to_uf11(nan), 0);
    assert_int_equal(lbk_float_to_uf10(-nan), 0);
    assert_int_equal(lbk_float_to_half(nan), 0);
    assert_int_equal(lbk_float_to_unorm8(nan), 0);
    assert_int_equal(lbk_float_to_snorm8(nan), 0);
    /* +Inf and overflow → max finite; negatives → 0 for unsigned formats */
    assert_int_equal(lbk_float_to_uf11(inf), 0x7bf);
    assert_int_equal(lbk_float_to_uf11(1e30f), 0x7bf);
    assert_int_equal(lbk_float_to_uf11(65535.0f), 0x7bf); /* would round to 2^16 = Inf */
    assert_int_equal(lbk_float_to_uf10(inf), 0x3df);
    assert_int_equal(lbk_float_to_uf11(-inf), 0);
    assert_int_equal(lbk_float_to_uf11(-1.0f), 0);
    assert_int_equal(lbk_float_to_uf11(-0.0f), 0);
    assert_int_equal(lbk_float_to_half(inf), 0x7bff);
    assert_int_equal(lbk_float_to_half(-inf), 0xfbff);
    assert_int_equal(lbk_float_to_half(65520.0f), 0x7bff); /* IEEE would give Inf */
    assert_int_equal(lbk_float_to_half(-0.0f), 0x8000);
    assert_int_equal(lbk_float_to_half(-2.0f), 0xc000);
    /* ties to even at the mantissa: 1 + 1/128 is halfway between uf11 1 and 1 + 1/64 */
    assert_int_equal(lbk_float_to_uf11(1.0f + 1.0f / 128.0f), 0x3c0);
    assert_int_equal(lbk_float_to_uf11(1.0f + 3.0f / 128.0f), 0x3c2);
    assert_int_equal(lbk_float_to_uf11(nextafterf(1.0f + 1.0f / 128.0f, 2.0f)), 0x3c1);
    /* denormals of the target kept; half the smallest denormal → 0 (tie to even), above → 1 */
    assert_int_equal(lbk_float_to_uf11(ldexpf(1.0f, -20)), 1);
    assert_int_equal(lbk_float_to_uf11(ldexpf(1.0f, -21)), 0);
    assert_int_equal(lbk_float_to_uf11(nextafterf(ldexpf(1.0f, -21), 1.0f)), 1);
    assert_int_equal(lbk_float_to_uf11(ldexpf(3.0f, -21)), 2); /* 1.5 steps → even 2 */
    assert_int_equal(lbk_float_to_half(ldexpf(1.0f, -25)), 0);
    assert_int_equal(lbk_float_to_half(ldexpf(3.0f, -25)), 2);
    assert_int_equal(lbk_float_to_half(ldexpf(1.0f, -149)), 0); /* float denormal */
    /* largest denormal rounding up into the smallest normal */
    assert_int_equal(lbk_float_to_uf11(ldexpf(127.0f, -21)), 0x40);
    /* unorm8 / snorm8 */
    assert_int_equal(lbk_float_to_unorm8(-5.0f), 0);
    assert_int_equal(lbk_float_to_unorm8(inf), 255);
    assert_int_equal(lbk_float_to_unorm8(0.5f), 128); /* 127.5 → even */
    assert_int_equal(lbk_float_to_snorm8(-inf), 0x81);
    assert_int_equal(lbk_float_to_snorm8(2.0f), 0x7f);
    assert_int_equal(lbk_float_to_snorm8(0.5f), 64); /* 63.5 → even */
    assert_int_equal(lbk_float_to_snorm8(-0.5f), (uint8_t)(int8_t)-64);
}

/* RGB9E5: every decoded value of a canonical code round-trips; encoding checked against the
 * definition (minimal exponent holding the largest channel, per-channel nearest-even). */
static uint32_t rgb9e5_code(uint32_t e, uint32_t r, uint32_t g, uint32_t b) { return (e << 27) | r | (g << 9) | (b << 18); }

static void rgb9e5_round_trip(void **state)
{
    (void)state;
    uint32_t rng = 12345u;
    for (uint32_t e = 0; e < 32; e++)
        for (int ch = 0; ch < 3; ch++)
            for (uint32_t m = 0; m < 512; m++) {
                rng = rng * 1664525u + 1013904223u;
                uint32_t mm[3] = {(rng >> 8) & 0x1ffu, (rng >> 17) & 0x1ffu, 0};
                mm[2] = (rng >> 3) & 0xffu; /* a third value */
                uint32_t v[3];
                v[ch] = m;
                v[(ch + 1) % 3] = e == 0 ? mm[0] : (256u | mm[2]); /* keeps the code canonical */
                v[(ch + 2) % 3] = mm[1];
                const uint32_t code = rgb9e5_code(e, v[0], v[1], v[2]);
                float f[3];
                lbk_rgb9e5_unpack(code, f);
                for (int i = 0; i < 3; i++) assert_true(f[i] == ldexpf((float)v[i], (int)e - 24));
                assert_int_equal(lbk_rgb9e5_pack(f), code);
            }
    float f[3];
    lbk_rgb9e5_unpack(rgb9e5_code(31, 511, 511, 511), f);
    assert_true(f[0] == LBK_RGB9E5_MAX);
}

static void rgb9e5_sweep(void **state)
{
    (void)state;
    uint32_t rng = 777u;
    for (uint64_t i = 0; i < (1ull << 32); i += SWEEP_STRIDE * 5u) {
        rng = rng * 1664525u + 1013904223u;
        const float x = bits_float((uint32_t)i);
        /* the other two channels: scaled copies of x, or patterns of their own */
        const float in[3] = {x, (rng & 1u) ? x * 0.37f : bits_float(rng), (rng & 2u) ? 0.0f : x * 1e-3f};
        const uint32_t code = lbk_rgb9e5_pack(in);
        float out[3];
        lbk_rgb9e5_unpack(code, out);
        double c[3], maxc = 0.0;
        for (int k = 0; k < 3; k++) {
            c[k] = (isnan(in[k]) || in[k] <= 0.0f) ? 0.0 : fmin((double)in[k], LBK_RGB9E5_MAX);
            if (c[k] > maxc) maxc = c[k];
        }
        const int e = (int)(code >> 27);
        const double step = ldexp(1.0, e - 24);
        for (int k = 0; k < 3; k++) {
            const double err = fabs((double)out[k] - c[k]);
            assert_true(err <= 0.5 * step);
            /* ties to even */
            if (err == 0.5 * step) assert_true((((code >> (9 * k)) & 1u)) == 0);
        }
        /* the exponent is minimal: one less could not hold the largest channel */
        if (e > 0) assert_true(maxc >= ldexp(511.5, e - 25));
        /* relative error of the largest channel ≤ 2^−9 */
        if (maxc > ldexp(1.0, -15)) {
            double mo = fmax(fmax(out[0], out[1]), out[2]);
            assert_true(fabs(mo - maxc) <= ldexp(1.0, -9) * maxc);
        }
    }
    /* specials */
    const float nan = NAN, inf = INFINITY;
    const float s[3] = {nan, -1.0f, inf};
    assert_int_equal(lbk_rgb9e5_pack(s), rgb9e5_code(31, 0, 0, 511));
    const float z[3] = {0.0f, -0.0f, ldexpf(1.0f, -26)};
    assert_int_equal(lbk_rgb9e5_pack(z), 0);
    const float tiny[3] = {ldexpf(3.0f, -25), 0.0f, 0.0f}; /* 1.5 steps at exponent 0 → 2 */
    assert_int_equal(lbk_rgb9e5_pack(tiny), rgb9e5_code(0, 2, 0, 0));
    const float bump[3] = {511.75f, 1.0f, 0.0f}; /* rounds to 512 at e=24 → e=25 */
    assert_int_equal(lbk_rgb9e5_pack(bump), rgb9e5_code(25, 256, 0, 0));
}

static void r11g11b10_layout(void **state)
{
    (void)state;
    const float one[3] = {1.0f, 2.0f, 4.0f};
    /* 1.0 = e15 → 0x3c0 (uf11); 2.0 = e16 → 0x400; 4.0 (uf10) = e17 → 17 << 5 = 0x220 */
    assert_int_equal(lbk_r11g11b10f_pack(one), 0x3c0u | (0x400u << 11) | (0x220u << 22));
    float out[3];
    lbk_r11g11b10f_unpack(0x3c0u | (0x400u << 11) | (0x220u << 22), out);
    assert_true(out[0] == 1.0f && out[1] == 2.0f && out[2] == 4.0f);
    const float spec[3] = {NAN, -3.0f, INFINITY};
    assert_int_equal(lbk_r11g11b10f_pack(spec), 0x3dfu << 22);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_code_round_trips), cmocka_unit_test(decoders_match_definition),
        cmocka_unit_test(sweep_uf11),             cmocka_unit_test(sweep_uf10),
        cmocka_unit_test(sweep_half),             cmocka_unit_test(sweep_norm8),
        cmocka_unit_test(special_values),         cmocka_unit_test(rgb9e5_round_trip),
        cmocka_unit_test(rgb9e5_sweep),           cmocka_unit_test(r11g11b10_layout),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
