/* AHD texel: linear-form identities, quantisation error for lighting the model represents
 * exactly, model error for general coloured lighting, additivity for light-set sums,
 * re-encoding stability, light from below the surface, special inputs, byte layout. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/pixel.h"

#define PI 3.14159265358979323846

static uint32_t rng_next(uint32_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    return *s;
}
static double rnd(uint32_t *s) { return (rng_next(s) >> 8) * (1.0 / 16777216.0); }

static void random_hemi_dir(uint32_t *s, float d[3])
{
    const double z = rnd(s), ph = 2.0 * PI * rnd(s), r = sqrt(1.0 - z * z);
    d[0] = (float)(r * cos(ph));
    d[1] = (float)(r * sin(ph));
    d[2] = (float)z;
}

/* Hemisphere normals on a fixed spiral. */
#define NN 256
static float normals[NN][3];
static void init_normals(void)
{
    for (int i = 0; i < NN; i++) {
        const double z = (i + 0.5) / NN, r = sqrt(1.0 - z * z), ph = i * 2.399963229728653;
        normals[i][0] = (float)(r * cos(ph));
        normals[i][1] = (float)(r * sin(ph));
        normals[i][2] = (float)z;
    }
}

/* max over hemisphere normals and channels of |E_a − E_b| / max_n E_a (per channel) */
static double rel_error(const lbk_ahd_linear *ref, const lbk_ahd_texel *t)
{
    double worst = 0.0;
    for (int c = 0; c < 3; c++) {
        double peak = 0.0, err = 0.0;
        for (int i = 0; i < NN; i++) {
            float a[3], b[3];
            lbk_ahd_linear_eval(ref, normals[i], a);
            lbk_ahd_irradiance(t, normals[i], b);
            peak = fmax(peak, a[c]);
            err = fmax(err, fabs((double)a[c] - b[c]));
        }
        if (peak > 0.0) worst = fmax(worst, err / peak);
    }
    return worst;
}

/* Ambient + 1..3 distant lights from the upper hemisphere, at a random overall scale.
 * chroma 0: everything shares one random tint (the model is exact);
 * chroma 1: every term has its own tint within ±30% per channel of a shared one (sky + sun);
 * chroma 2: every term has an independent saturated colour, channels in [0.1, 1.1]. */
static float tint_of(uint32_t *seed, int chroma, const float base[3], int c)
{
    if (chroma == 0) return base[c];
    if (chroma == 1) return base[c] * (float)(0.7 + 0.6 * rnd(seed));
    return (float)(0.1 + rnd(seed));
}

static void make_lighting(uint32_t *seed, int chroma, lbk_ahd_linear *lin)
{
    memset(lin, 0, sizeof *lin);
    float base[3];
    for (int c = 0; c < 3; c++) base[c] = (float)(0.2 + rnd(seed));
    const float amb = (float)(rnd(seed) * rnd(seed));
    float a[3];
    for (int c = 0; c < 3; c++) a[c] = amb * tint_of(seed, chroma, base, c);
    lbk_ahd_linear_add_ambient(lin, a);
    const int nl = 1 + (int)(rng_next(seed) % 3u);
    for (int l = 0; l < nl; l++) {
        float d[3], col[3];
        random_hemi_dir(seed, d);
        const float inten = (float)(0.1 + 4.0 * rnd(seed));
        for (int c = 0; c < 3; c++) col[c] = inten * tint_of(seed, chroma, base, c);
        lbk_ahd_linear_add_light(lin, d, col);
    }
    const float scale = (float)pow(2.0, 20.0 * rnd(seed) - 10.0);
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) lin->c[c][i] *= scale;
}

static void linear_form_identities(void **state)
{
    (void)state;
    init_normals();
    uint32_t seed = 99u;
    for (int t = 0; t < 500; t++) {
        lbk_ahd_texel tex;
        tex.irradiance_z = rng_next(&seed) & ~((1u << 31) | (1u << 30) | (1u << 20) | (1u << 9)); /* no Inf/NaN codes */
        const uint32_t b = rng_next(&seed);
        memcpy(tex.rgba, &b, 4);
        lbk_ahd_linear lin;
        lbk_ahd_to_linear(&tex, &lin);
        float ez[3];
        lbk_r11g11b10f_unpack(tex.irradiance_z, ez);
        /* the linear form reproduces the stored +Z irradiance and the ratio by luminance */
        const float up[3] = {0, 0, 1};
        float e[3];
        lbk_ahd_linear_eval(&lin, up, e);
        for (int c = 0; c < 3; c++) assert_true(fabsf(e[c] - ez[c]) <= 1e-5f * ez[c] + 1e-30f);
        /* the gradient of every channel is parallel to the decoded direction, of length I/2 */
        /* decode == evaluation of the linear form */
        for (int i = 0; i < NN; i += 17) {
            float x[3], y[3];
            lbk_ahd_irradiance(&tex, normals[i], x);
            lbk_ahd_linear_eval(&lin, normals[i], y);
            for (int c = 0; c < 3; c++) assert_true(x[c] == y[c]);
        }
    }
    /* band-1 irradiance of a unit directional light: 1/4 + n·d/2 */
    lbk_ahd_linear lin;
    memset(&lin, 0, sizeof lin);
    const float d[3] = {0.6f, 0.0f, 0.8f}, one[3] = {1, 1, 1};
    lbk_ahd_linear_add_light(&lin, d, one);
    float e[3];
    lbk_ahd_linear_eval(&lin, d, e);
    assert_true(fabsf(e[1] - 0.75f) < 1e-6f);
    /* from SH: a constant radiance L = 1 gives e0 = π and no gradient */
    lbk_sh9_rgb sh;
    memset(&sh, 0, sizeof sh);
    for (int c = 0; c < 3; c++) sh.c[c][0] = (float)(2.0 * sqrt(PI));
    lbk_ahd_linear_from_sh9(&sh, &lin);
    assert_true(fabsf(lin.c[0][0] - (float)PI) < 1e-5f && lin.c[0][1] == 0.0f);
    /* from SH: a delta light (projected) gives the same linear form as add_light */
    memset(&sh, 0, sizeof sh);
    lbk_sh9_add_sample(&sh, d, one, 1.0f);
    lbk_ahd_linear l2, l3;
    lbk_ahd_linear_from_sh9(&sh, &l2);
    memset(&l3, 0, sizeof l3);
    lbk_ahd_linear_add_light(&l3, d, one);
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) assert_true(fabsf(l2.c[c][i] - l3.c[c][i]) < 1e-6f);
}

/* Lighting with one chroma (any number of lights, any directions in the upper hemisphere):
 * the model is exact, only quantisation remains. */
static void quantisation_error_bound(void **state)
{
    (void)state;
    init_normals();
    uint32_t seed = 12345u;
    double worst = 0.0, sum = 0.0;
    const int trials = 4000;
    for (int t = 0; t < trials; t++) {
        lbk_ahd_linear lin;
        make_lighting(&seed, 0, &lin);
        lbk_ahd_texel tex;
        lbk_ahd_from_linear(&lin, &tex);
        const double e = rel_error(&lin, &tex);
        worst = fmax(worst, e);
        sum += e;
    }
    printf("AHD quantisation error (one chroma): max %.4f mean %.4f of peak irradiance\n", worst, sum / trials);
    /* Bound: Ez ≤ 2^−6 (uf10 blue), ratio ≤ 1/510 times a factor ≤ 3, direction ≤ ~1/255 rad
     * times |∇E| ≤ peak: about 0.016 + 0.006 + 0.006 ≈ 0.03 */
    assert_true(worst < 0.03);
    assert_true(worst > 0.002);
}

/* General coloured lighting: the 8-byte texel cannot hold per-channel directions or separate
 * chroma for ambient and highlight; measure how far that takes it. */
static void coloured_model_error_run(int chroma, double *max_out, double *mean_out, double *p95_out)
{
    uint32_t seed = 777u + (uint32_t)chroma;
    enum { TRIALS = 4000 };
    static double errs[TRIALS];
    double worst = 0.0, sum = 0.0;
    for (int t = 0; t < TRIALS; t++) {
        lbk_ahd_linear lin;
        make_lighting(&seed, chroma, &lin);
        lbk_ahd_texel tex;
        lbk_ahd_from_linear(&lin, &tex);
        errs[t] = rel_error(&lin, &tex);
        worst = fmax(worst, errs[t]);
        sum += errs[t];
    }
    /* 95th percentile by counting */
    double lo = 0.0, hi = worst;
    for (int it = 0; it < 40; it++) {
        const double mid = 0.5 * (lo + hi);
        int below = 0;
        for (int t = 0; t < TRIALS; t++) below += errs[t] <= mid;
        if (below >= TRIALS * 95 / 100) hi = mid;
        else lo = mid;
    }
    *max_out = worst;
    *mean_out = sum / TRIALS;
    *p95_out = hi;
}

static void coloured_model_error(void **state)
{
    (void)state;
    init_normals();
    double mx, mean, p95;
    coloured_model_error_run(1, &mx, &mean, &p95);
    printf("AHD error, terms tinted ±30%%: max %.4f mean %.4f p95 %.4f of peak irradiance\n", mx, mean, p95);
    /* measured 0.448 / 0.060 / 0.153: a scalar ratio cannot give ambient and highlight their own
     * chroma; the error grows as the highlight nears the horizon (k → 1/4) */
    assert_true(mx < 0.5 && mean < 0.08 && p95 < 0.2);
    coloured_model_error_run(2, &mx, &mean, &p95);
    printf("AHD error, independent saturated colours: max %.4f mean %.4f p95 %.4f\n", mx, mean, p95);
    assert_true(mx < 1.0 && mean < 0.25);
    assert_true(mean > 0.05); /* the limit of the representation is real */
}

/* Dynamic light sets: texels combine through the linear form. */
static void additive_sets(void **state)
{
    (void)state;
    init_normals();
    uint32_t seed = 4242u;
    double worst = 0.0;
    for (int t = 0; t < 1000; t++) {
        lbk_ahd_linear base, set;
        make_lighting(&seed, 0, &base);
        make_lighting(&seed, 0, &set);
        /* same chroma for both so the sum is representable */
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < 4; i++) set.c[c][i] = set.c[0][i] * base.c[c][0] / base.c[0][0];
        lbk_ahd_texel tb, ts, tsum;
        lbk_ahd_from_linear(&base, &tb);
        lbk_ahd_from_linear(&set, &ts);
        const float w = (float)rnd(&seed);
        lbk_ahd_linear lb, ls, total;
        lbk_ahd_to_linear(&tb, &lb);
        lbk_ahd_to_linear(&ts, &ls);
        total = lb;
        lbk_ahd_linear_add_scaled(&total, &ls, w);
        lbk_ahd_from_linear(&total, &tsum);
        lbk_ahd_linear exact = base;
        lbk_ahd_linear_add_scaled(&exact, &set, w);
        worst = fmax(worst, rel_error(&exact, &tsum));
    }
    printf("AHD base + w·set through the linear form (one chroma): max error %.4f\n", worst);
    assert_true(worst < 0.05); /* two quantisations of the inputs plus one of the sum */
}

static void reencode_stable(void **state)
{
    (void)state;
    uint32_t seed = 31337u;
    int exact = 0;
    const int trials = 5000;
    for (int t = 0; t < trials; t++) {
        lbk_ahd_linear lin, back;
        make_lighting(&seed, 1, &lin);
        lbk_ahd_texel a, b;
        lbk_ahd_from_linear(&lin, &a);
        lbk_ahd_to_linear(&a, &back);
        lbk_ahd_from_linear(&back, &b);
        for (int i = 0; i < 4; i++) assert_true(abs((int)a.rgba[i] - (int)b.rgba[i]) <= 1);
        float ea[3], eb[3];
        lbk_r11g11b10f_unpack(a.irradiance_z, ea);
        lbk_r11g11b10f_unpack(b.irradiance_z, eb);
        for (int c = 0; c < 3; c++) assert_true(fabsf(ea[c] - eb[c]) <= 0.04f * ea[c] + 1e-30f);
        exact += memcmp(&a, &b, sizeof a) == 0;
    }
    printf("AHD re-encode of a decoded texel: %d of %d bit-identical\n", exact, trials);
    assert_true(exact > trials / 2);
}

static void light_from_below(void **state)
{
    (void)state;
    lbk_ahd_linear lin;
    lbk_ahd_texel tex;
    /* a light grazing from below: direction projected onto the tangent plane (A byte 0) */
    memset(&lin, 0, sizeof lin);
    const float below[3] = {0.8f, 0.0f, -0.6f}, col[3] = {1, 1, 1}, amb[3] = {0.5f, 0.5f, 0.5f};
    lbk_ahd_linear_add_ambient(&lin, amb);
    lbk_ahd_linear_add_light(&lin, below, col);
    lbk_ahd_from_linear(&lin, &tex);
    assert_int_equal(tex.rgba[3], 0);
    assert_int_equal(tex.rgba[1], 255);
    assert_int_equal(tex.rgba[2], 128);
    float e[3];
    const float up[3] = {0, 0, 1};
    lbk_ahd_irradiance(&tex, up, e);
    /* horizontal d: I = 2·(g·d) = 0.8, a = e0 − I/4 = 0.55, Ez = a + I/4 = 0.75 */
    assert_true(fabsf(e[0] - 0.75f) < 0.75f * 0.01f);
    /* straight from below: no direction left → +Z, all ambient (ratio 255) */
    memset(&lin, 0, sizeof lin);
    const float down[3] = {0, 0, -1};
    lbk_ahd_linear_add_light(&lin, down, col);
    lbk_ahd_from_linear(&lin, &tex);
    assert_int_equal(tex.rgba[0], 255);
    assert_int_equal(tex.rgba[3], 255);
    lbk_ahd_irradiance(&tex, up, e);
    assert_true(fabsf(e[1] - 0.25f) < 0.25f * 0.01f); /* e0 = 1/4 kept as ambient */
}

static void special_inputs(void **state)
{
    (void)state;
    lbk_ahd_linear lin;
    lbk_ahd_texel tex;
    memset(&lin, 0, sizeof lin);
    lbk_ahd_from_linear(&lin, &tex);
    assert_int_equal(tex.irradiance_z, 0);
    assert_int_equal(tex.rgba[0], 255);
    assert_int_equal(tex.rgba[1], 128);
    assert_int_equal(tex.rgba[2], 128);
    assert_int_equal(tex.rgba[3], 255);
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) lin.c[c][i] = (i + c) % 2 ? NAN : INFINITY;
    lin.c[1][0] = -INFINITY;
    lbk_ahd_from_linear(&lin, &tex);
    float ez[3];
    lbk_r11g11b10f_unpack(tex.irradiance_z, ez);
    for (int c = 0; c < 3; c++) assert_true(isfinite(ez[c]) && ez[c] >= 0.0f);
    /* negative irradiance (e.g. a subtracted set) clamps to black */
    memset(&lin, 0, sizeof lin);
    for (int c = 0; c < 3; c++) lin.c[c][0] = -2.0f;
    lbk_ahd_from_linear(&lin, &tex);
    assert_int_equal(tex.irradiance_z, 0);
    /* decode of hand-made bytes: a short direction vector means +Z; NaN code decodes black */
    tex.irradiance_z = 0x7ffu; /* R channel NaN code */
    tex.rgba[0] = 0;
    tex.rgba[1] = 128;
    tex.rgba[2] = 127;
    tex.rgba[3] = 0;
    lbk_ahd_linear out;
    lbk_ahd_to_linear(&tex, &out);
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) assert_true(isfinite(out.c[c][i]));
    assert_true(out.c[0][0] == 0.0f);
    uint8_t bytes[8];
    tex.irradiance_z = 0x11223344u;
    lbk_ahd_texel_pack(&tex, bytes);
    const uint8_t expect[8] = {0x44, 0x33, 0x22, 0x11, 0, 128, 127, 0};
    assert_memory_equal(bytes, expect, 8);
    lbk_ahd_texel back;
    lbk_ahd_texel_unpack(bytes, &back);
    assert_memory_equal(&back, &tex, sizeof tex);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(linear_form_identities), cmocka_unit_test(quantisation_error_bound),
        cmocka_unit_test(coloured_model_error),   cmocka_unit_test(additive_sets),
        cmocka_unit_test(reencode_stable),        cmocka_unit_test(light_from_below),
        cmocka_unit_test(special_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
