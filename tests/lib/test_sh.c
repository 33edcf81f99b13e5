/* Band-2 SH: orthonormality, exact projection, irradiance against direct integration, rotation,
 * the non-negative-function band bounds, and the 28-byte probe (extremes, special DC values,
 * the measured round-trip error against its analytic bound). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lbk/pixel.h"
#include "lbk/sh.h"

#define PI 3.14159265358979323846

/* ---- quadrature: Gauss–Legendre in z × uniform φ, exact for polynomials of degree ≤ 2n−1 in
 * z and < nphi in φ-harmonics ---------------------------------------------------------------- */
#define GL_N 8
#define PHI_N 16

static void gauss_legendre(double x[GL_N], double w[GL_N])
{
    for (int i = 0; i < GL_N; i++) {
        double z = cos(PI * (i + 0.75) / (GL_N + 0.5));
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= GL_N; k++) {
                const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            const double dp = GL_N * (z * p1 - p0) / (z * z - 1.0);
            const double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-15) {
                x[i] = z;
                w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
                break;
            }
        }
    }
}

typedef void (*sphere_fn)(const float dir[3], double weight, void *user);

static void for_quadrature(sphere_fn fn, void *user)
{
    double x[GL_N], w[GL_N];
    gauss_legendre(x, w);
    for (int i = 0; i < GL_N; i++)
        for (int j = 0; j < PHI_N; j++) {
            const double phi = 2.0 * PI * j / PHI_N, s = sqrt(1.0 - x[i] * x[i]);
            const float d[3] = {(float)(s * cos(phi)), (float)(s * sin(phi)), (float)x[i]};
            fn(d, w[i] * 2.0 * PI / PHI_N, user);
        }
}

static void acc_gram(const float d[3], double w, void *user)
{
    double *g = user;
    float y[9];
    lbk_sh9_basis(d, y);
    for (int i = 0; i < 9; i++)
        for (int j = 0; j < 9; j++) g[i * 9 + j] += w * y[i] * y[j];
}

static void orthonormal_basis(void **state)
{
    (void)state;
    double g[81] = {0};
    for_quadrature(acc_gram, g);
    for (int i = 0; i < 9; i++)
        for (int j = 0; j < 9; j++) assert_true(fabs(g[i * 9 + j] - (i == j ? 1.0 : 0.0)) < 1e-6);
    /* the constants of the header */
    assert_true(fabs(LBK_SH_Y00 - 0.5 / sqrt(PI)) < 1e-7);
    assert_true(fabs(LBK_SH_Y1 - sqrt(3.0 / (4.0 * PI))) < 1e-7);
    assert_true(fabs(LBK_SH_Y2 - sqrt(15.0 / (4.0 * PI))) < 1e-6);
    assert_true(fabs(LBK_SH_Y20 - sqrt(5.0 / (16.0 * PI))) < 1e-7);
    assert_true(fabs(LBK_SH_Y22 - sqrt(15.0 / (16.0 * PI))) < 1e-7);
}

/* A degree-2 radiance, channel-dependent: exactly representable in band 2. */
static double poly_radiance(const float d[3], int c)
{
    const double x = d[0], y = d[1], z = d[2];
    return 1.0 + 0.3 * c + (0.4 - 0.1 * c) * z + 0.2 * x - 0.15 * y + 0.35 * x * y + 0.1 * c * y * z +
           0.25 * z * z - 0.2 * x * x + 0.05 * x * z;
}

static void acc_project(const float d[3], double w, void *user)
{
    lbk_sh9_rgb *sh = user;
    const float rgb[3] = {(float)poly_radiance(d, 0), (float)poly_radiance(d, 1), (float)poly_radiance(d, 2)};
    lbk_sh9_add_sample(sh, d, rgb, (float)w);
}

static void projection_and_irradiance_exact(void **state)
{
    (void)state;
    lbk_sh9_rgb sh;
    memset(&sh, 0, sizeof sh);
    for_quadrature(acc_project, &sh);
    /* reconstruction is exact for a degree-2 function */
    for (int t = 0; t < 50; t++) {
        const double th = acos(1.0 - 2.0 * (t + 0.5) / 50.0), ph = t * 2.399963;
        const float d[3] = {(float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th)};
        float rgb[3];
        lbk_sh9_eval(&sh, d, rgb);
        for (int c = 0; c < 3; c++) assert_true(fabs(rgb[c] - poly_radiance(d, c)) < 1e-5);
    }
    /* irradiance = ∫ L(ω) max(0, n·ω) dω (Funk–Hecke: exact for band ≤ 2), checked against a
     * fine midpoint integration over the sphere */
    const float normals[4][3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {-0.48f, 0.6f, -0.64f}, {0, -1, 0}};
    for (int t = 0; t < 4; t++) {
        double ref[3] = {0, 0, 0};
        const int NT = 400, NP = 800;
        for (int i = 0; i < NT; i++)
            for (int j = 0; j < NP; j++) {
                const double z = -1.0 + 2.0 * (i + 0.5) / NT, s = sqrt(1.0 - z * z), ph = 2.0 * PI * (j + 0.5) / NP;
                const float d[3] = {(float)(s * cos(ph)), (float)(s * sin(ph)), (float)z};
                const double cosv = normals[t][0] * d[0] + normals[t][1] * d[1] + normals[t][2] * d[2];
                if (cosv <= 0) continue;
                for (int c = 0; c < 3; c++) ref[c] += poly_radiance(d, c) * cosv * (2.0 / NT) * (2.0 * PI / NP);
            }
        float e[3];
        lbk_sh9_irradiance(&sh, normals[t], e);
        for (int c = 0; c < 3; c++) assert_true(fabs(e[c] - ref[c]) < 2e-3 * ref[c]);
    }
    /* constant radiance L gives irradiance πL for every normal */
    lbk_sh9_rgb k;
    memset(&k, 0, sizeof k);
    for (int c = 0; c < 3; c++) k.c[c][0] = (float)(2.0 * sqrt(PI)); /* L = 1 */
    float e[3];
    lbk_sh9_irradiance(&k, normals[2], e);
    assert_true(fabs(e[0] - PI) < 1e-5);
}

static void rotation_matches_evaluation(void **state)
{
    (void)state;
    lbk_sh9_rgb sh, rot;
    memset(&sh, 0, sizeof sh);
    for_quadrature(acc_project, &sh);
    /* an orthonormal frame (rows t, b, n) */
    const double a = 0.7, b = -0.4, c = 1.1;
    double r[3][3] = {{cos(a) * cos(b), cos(a) * sin(b) * sin(c) - sin(a) * cos(c), cos(a) * sin(b) * cos(c) + sin(a) * sin(c)},
                      {sin(a) * cos(b), sin(a) * sin(b) * sin(c) + cos(a) * cos(c), sin(a) * sin(b) * cos(c) - cos(a) * sin(c)},
                      {-sin(b), cos(b) * sin(c), cos(b) * cos(c)}};
    float rf[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) rf[i][j] = (float)r[i][j];
    lbk_sh9_rotate(&sh, (const float(*)[3])rf, &rot);
    for (int t = 0; t < 40; t++) {
        const double th = acos(1.0 - 2.0 * (t + 0.5) / 40.0), ph = t * 2.399963;
        const float w[3] = {(float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th)};
        float wp[3];
        for (int i = 0; i < 3; i++) wp[i] = rf[i][0] * w[0] + rf[i][1] * w[1] + rf[i][2] * w[2];
        float e0[3], e1[3];
        lbk_sh9_eval(&sh, w, e0);
        lbk_sh9_eval(&rot, wp, e1);
        for (int k = 0; k < 3; k++) assert_true(fabs(e0[k] - e1[k]) < 1e-5);
    }
}

/* |Y_lm(ω)| / Y00 ≤ √(2l+1) for all ω, with equality reached, so a non-negative function
 * (a positive mixture of deltas) has |L_lm| ≤ √(2l+1) L00. */
static void nonnegative_band_bound(void **state)
{
    (void)state;
    double max1 = 0.0, max2 = 0.0;
    for (int i = 0; i <= 400; i++)
        for (int j = 0; j < 400; j++) {
            const double th = PI * i / 400.0, ph = 2.0 * PI * j / 400.0;
            const float d[3] = {(float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th)};
            float y[9];
            lbk_sh9_basis(d, y);
            for (int k = 1; k < 4; k++) max1 = fmax(max1, fabs(y[k]) / y[0]);
            for (int k = 4; k < 9; k++) max2 = fmax(max2, fabs(y[k]) / y[0]);
        }
    assert_true(max1 <= sqrt(3.0) * (1 + 1e-6));
    assert_true(max1 >= sqrt(3.0) * (1 - 1e-6)); /* reached along an axis */
    assert_true(max2 <= sqrt(5.0) * (1 + 1e-6));
    assert_true(max2 >= sqrt(5.0) * (1 - 1e-6)); /* reached by Y20 at the poles */
}

static void pack_extremes_and_special_dc(void **state)
{
    (void)state;
    uint8_t p[28];
    lbk_sh9_rgb sh, out;
    /* a delta light along +Z: L20 / L00 = √5 and L10 / L00 = √3 exactly → codes ±127 */
    memset(&sh, 0, sizeof sh);
    const float up[3] = {0, 0, 1}, white[3] = {2.0f, 1.0f, 0.5f};
    lbk_sh9_add_sample(&sh, up, white, 1.0f);
    lbk_sh9_pack(&sh, p);
    for (int c = 0; c < 3; c++) {
        assert_int_equal(p[4 + 3 * (2 - 1) + c], 127); /* k=2: Y10 */
        assert_int_equal(p[4 + 3 * (6 - 1) + c], 127); /* k=6: Y20 */
        assert_int_equal(p[4 + 3 * (1 - 1) + c], 0);
    }
    lbk_sh9_unpack(p, &out);
    /* DC off by at most half an RGB9E5 step (≤ 2^−9 of the largest DC); band l inherits
     * s_l times that through the decoded DC, codes ±127 being exact */
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++)
            assert_true(fabs(out.c[c][k] - sh.c[c][k]) <= sqrt(5.0) * ldexp(sh.c[0][0], -9) + 1e-6);
    /* DC layout: RGB9E5 of (L00 R, G, B) little-endian at bytes 0..3 */
    const uint32_t dc = (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
    const float dcin[3] = {sh.c[0][0], sh.c[1][0], sh.c[2][0]};
    assert_int_equal(dc, lbk_rgb9e5_pack(dcin));

    /* zero / negative / NaN / tiny DC: higher bands of that channel are 0 */
    memset(&sh, 0, sizeof sh);
    sh.c[0][0] = 0.0f;
    sh.c[1][0] = -1.0f;
    sh.c[2][0] = NAN;
    for (int c = 0; c < 3; c++)
        for (int k = 1; k < 9; k++) sh.c[c][k] = 0.5f;
    lbk_sh9_pack(&sh, p);
    for (int i = 0; i < 28; i++) assert_int_equal(p[i], 0);
    sh.c[0][0] = ldexpf(1.0f, -30); /* below the smallest RGB9E5 step */
    sh.c[1][0] = 1.0f;
    sh.c[2][0] = 1.0f;
    sh.c[2][1] = 100.0f;  /* out of range: clamped to +1 */
    sh.c[2][4] = -100.0f; /* clamped to −1 */
    sh.c[1][3] = INFINITY;
    sh.c[1][5] = NAN;
    lbk_sh9_pack(&sh, p);
    lbk_sh9_unpack(p, &out);
    for (int k = 0; k < 9; k++) assert_true(out.c[0][k] == 0.0f);
    assert_int_equal(p[4 + 0 + 2], 127);
    assert_int_equal(p[4 + 9 + 2], 0x81);
    assert_int_equal(p[4 + 6 + 1], 127);
    assert_int_equal(p[4 + 12 + 1], 0);
    assert_true(fabsf(out.c[2][1] - sqrtf(3.0f)) < 1e-6f);
    assert_true(fabsf(out.c[2][4] + sqrtf(5.0f)) < 1e-6f);
}

static uint32_t rng_next(uint32_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    return *s;
}
static double rnd(uint32_t *s) { return (rng_next(s) >> 8) * (1.0 / 16777216.0); }

static void random_dir(uint32_t *s, float d[3])
{
    const double z = 2.0 * rnd(s) - 1.0, ph = 2.0 * PI * rnd(s), r = sqrt(1.0 - z * z);
    d[0] = (float)(r * cos(ph));
    d[1] = (float)(r * sin(ph));
    d[2] = (float)z;
}

/* Random non-negative lighting (ambient + 1..4 coloured deltas); error of pack/unpack in
 * irradiance over normals, relative to the DC irradiance A0·Y00·L00 of the same channel. */
static void pack_error_bound(void **state)
{
    (void)state;
    /* analytic bound: DC rel. error ≤ 2^−9·(maxDC/DC) (RGB9E5), each ratio ≤ 1/254 off */
    double s1 = 0, s2 = 0;
    for (int i = 0; i <= 200; i++)
        for (int j = 0; j < 200; j++) {
            const double th = PI * i / 200.0, ph = 2.0 * PI * j / 200.0;
            const float d[3] = {(float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th)};
            float y[9];
            lbk_sh9_basis(d, y);
            double a = 0, b = 0;
            for (int k = 1; k < 4; k++) a += fabs(y[k]);
            for (int k = 4; k < 9; k++) b += fabs(y[k]);
            s1 = fmax(s1, a);
            s2 = fmax(s2, b);
        }
    const double band_bound = (LBK_SH_A1 * sqrt(3.0) * s1 + LBK_SH_A2 * sqrt(5.0) * s2) / (254.0 * LBK_SH_A0 * LBK_SH_Y00);
    uint32_t seed = 0x5eed1234u;
    double worst_gray = 0.0, worst_col = 0.0, sum = 0.0;
    long count = 0;
    for (int trial = 0; trial < 3000; trial++) {
        lbk_sh9_rgb sh;
        memset(&sh, 0, sizeof sh);
        const int colored = trial & 1;
        const float amb = (float)(0.05 + rnd(&seed));
        for (int c = 0; c < 3; c++) sh.c[c][0] = (float)(amb * 2.0 * sqrt(PI)) * (colored ? (float)(0.25 + 0.75 * c / 2.0) : 1.0f);
        const int nl = 1 + (int)(rng_next(&seed) % 4u);
        for (int l = 0; l < nl; l++) {
            float d[3], col[3];
            random_dir(&seed, d);
            const float inten = (float)(10.0 * rnd(&seed));
            for (int c = 0; c < 3; c++) col[c] = colored ? inten * (float)(0.25 + 0.75 * rnd(&seed)) : inten;
            lbk_sh9_add_sample(&sh, d, col, 1.0f);
        }
        /* exercise the exponent over the range where the largest DC has a full 9-bit mantissa */
        const float scale = (float)pow(2.0, 24.0 * rnd(&seed) - 12.0);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) sh.c[c][k] *= scale;
        uint8_t p[28];
        lbk_sh9_rgb out;
        lbk_sh9_pack(&sh, p);
        lbk_sh9_unpack(p, &out);
        const double maxdc = fmax(fmax(sh.c[0][0], sh.c[1][0]), sh.c[2][0]);
        for (int t = 0; t < 64; t++) {
            float n[3], e0[3], e1[3];
            random_dir(&seed, n);
            lbk_sh9_irradiance(&sh, n, e0);
            lbk_sh9_irradiance(&out, n, e1);
            for (int c = 0; c < 3; c++) {
                const double edc = LBK_SH_A0 * LBK_SH_Y00 * sh.c[c][0];
                const double rel = fabs((double)e1[c] - e0[c]) / edc;
                const double dc_bound = ldexp(1.0, -9) * maxdc / sh.c[c][0];
                /* float rounding slack 1e-5 */
                if (rel > band_bound * (1.0 + dc_bound) + dc_bound + 1e-5)
                    fail_msg("trial %d: rel error %g > bound %g", trial, rel, band_bound + dc_bound);
                if (colored) worst_col = fmax(worst_col, rel);
                else worst_gray = fmax(worst_gray, rel);
                sum += rel;
                count++;
            }
        }
    }
    printf("SH9 pack: analytic band bound %.4f; measured max %.4f (gray), %.4f (coloured), mean %.5f\n",
           band_bound, worst_gray, worst_col, sum / (double)count);
    assert_true(band_bound < 0.025);
    assert_true(worst_gray > 0.002); /* quantisation is really happening */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(orthonormal_basis),           cmocka_unit_test(projection_and_irradiance_exact),
        cmocka_unit_test(rotation_matches_evaluation), cmocka_unit_test(nonnegative_band_bound),
        cmocka_unit_test(pack_extremes_and_special_dc), cmocka_unit_test(pack_error_bound),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
