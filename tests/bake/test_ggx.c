/* The glTF metallic-roughness BRDF (bake/transport/ggx.h): the visible-normal density
 * integrates to 1 (Smith's G1 is the right normalisation of D), the specular lobe's
 * directional albedo is ≤ 1 at every roughness and angle and equal to two independent
 * quadratures and to visible-normal sampling, how far the glTF reference mix is from energy
 * conservation (it is not, at grazing angles), reciprocity, and the sampler's density is the
 * one bk_ggx_pdf states. The coupled BSDF the transport bounces light with (bk_mr_lobe): its
 * albedo table against the quadrature, total directional albedo ≤ 1 (energy conservation of the
 * Kelemen–Szirmay-Kalos coupling), its sampler against quadrature, reciprocity. */
#include <stdlib.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "bake/transport/ggx.h"

#define PI 3.14159265358979323846

static const double ALPHAS[] = {0.05, 0.1, 0.2, 0.4, 0.7, 1.0};
static const double ANGLES[] = {0, 30, 60, 75, 85, 89}; /* θ_v in degrees */

static void dir_of(double theta, double phi, double d[3])
{
    d[0] = sin(theta) * cos(phi), d[1] = sin(theta) * sin(phi), d[2] = cos(theta);
}

/* The microfacet normal for (s, φ): GGX-distributed in its projected area, D(h)·cos θ_h dω_h =
 * du·dφ/2π exactly with u = 1 − s², so a midpoint rule in (s, φ) with weight 2s integrates
 * g·D·cos θ_h without resolving the peak of D, and the 1/cos θ_h ~ 1/s of the integrands below
 * at grazing microfacets is cancelled by the weight. Returns the weight 2s. */
static double h_of(double alpha, double s, double phi, double h[3])
{
    double u = 1 - s * s;
    double t2 = alpha * alpha * u / (s * s);
    double c = 1 / sqrt(1 + t2);
    dir_of(acos(c), phi, h);
    return 2 * s;
}

#define NU 1500
#define NP 192

/* ∫ G1(v)·max(0, v·h)·D(h)/(n·v) dω_h (should be 1). */
static double vndf_norm(double alpha, const double v[3])
{
    double sum = 0;
    for (int i = 0; i < NU; i++)
        for (int j = 0; j < NP; j++) {
            double h[3];
            double w = h_of(alpha, (i + 0.5) / NU, 2 * PI * (j + 0.5) / NP, h);
            double vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            if (vh > 0) sum += w * bk_ggx_g1(alpha, v[2]) * vh / (h[2] * v[2]);
        }
    return sum / ((double)NU * NP);
}

/* ∫ F(v·h)·spec(v, l)·cos θ_l dω_l over l = reflect(v, h), in h-space (dω_l = 4(v·h) dω_h);
 * f0 = 1: Fresnel 1. */
static double spec_albedo_h(double alpha, const double v[3], double f0)
{
    double sum = 0;
    for (int i = 0; i < NU; i++)
        for (int j = 0; j < NP; j++) {
            double h[3], l[3];
            double w = h_of(alpha, (i + 0.5) / NU, 2 * PI * (j + 0.5) / NP, h);
            double vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            if (!(vh > 0)) continue;
            for (int k = 0; k < 3; k++) l[k] = 2 * vh * h[k] - v[k];
            if (!(l[2] > 0)) continue;
            sum += w * bk_ggx_fresnel(f0, vh) * bk_ggx_g2(alpha, v[2], l[2]) * vh / (v[2] * h[2]);
        }
    return sum / ((double)NU * NP);
}

/* ∫ g(v, l)·cos θ_l dω_l by a plain midpoint rule in (cos² θ_l, φ_l): smooth integrands only
 * (the diffuse lobe, broad specular lobes). which: 0 the specular lobe (F = 1), 1 the whole glTF
 * BRDF minus its specular part's F·spec (the diffuse term alone). */
static double albedo_l(double alpha, const double v[3], int which, double base, double metallic)
{
    const int NT = 1200, NF = 480;
    double sum = 0;
    for (int i = 0; i < NT; i++)
        for (int j = 0; j < NF; j++) {
            /* cos θ dω = d(cos²θ)/2 dφ */
            double c2 = (i + 0.5) / NT, l[3];
            dir_of(acos(sqrt(c2)), 2 * PI * (j + 0.5) / NF, l);
            double f;
            if (which == 0) {
                f = bk_ggx_spec(alpha, v, l);
            } else {
                double h[3] = {v[0] + l[0], v[1] + l[1], v[2] + l[2]}, n = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
                double vh = (v[0] * h[0] + v[1] * h[1] + v[2] * h[2]) / n;
                double f0 = 0.04 + (base - 0.04) * metallic;
                f = (1 - bk_ggx_fresnel(f0, vh)) * (1 - metallic) * base / PI;
            }
            sum += f;
        }
    return sum * PI / ((double)NT * NF); /* ∫∫ … d(c²)/2 dφ, dφ total 2π */
}

static void test_visible_normals_normalised(void **state)
{
    (void)state;
    double worst = 0;
    for (size_t a = 0; a < sizeof ALPHAS / sizeof *ALPHAS; a++)
        for (size_t t = 0; t < sizeof ANGLES / sizeof *ANGLES; t++) {
            double v[3];
            dir_of(ANGLES[t] * PI / 180, 0.3, v);
            double n = vndf_norm(ALPHAS[a], v);
            worst = fmax(worst, fabs(n - 1));
            assert_true(fabs(n - 1) < 2e-3);
        }
    print_message("visible-normal density: |integral - 1| <= %.2g\n", worst);
}

static void test_specular_albedo(void **state)
{
    (void)state;
    for (size_t a = 0; a < sizeof ALPHAS / sizeof *ALPHAS; a++) {
        const double alpha = ALPHAS[a];
        for (size_t t = 0; t < sizeof ANGLES / sizeof *ANGLES; t++) {
            double v[3];
            dir_of(ANGLES[t] * PI / 180, 1.1, v);
            const double A = spec_albedo_h(alpha, v, 1);
            assert_true(A > 0 && A <= 1 + 1e-9);
            /* α = 1 at normal incidence in closed form: D = 1/π, G2 = 2c/(1 + c), so
             * A = ∫₀¹ c/(1 + c) dc = 1 − ln 2 */
            if (alpha == 1.0 && ANGLES[t] == 0) assert_true(fabs(A - (1 - log(2.0))) < 1e-5);
            /* visible-normal sampling: weight G2/G1(v), 2^16 stratified samples */
            const int S = 256;
            double m = 0, m2 = 0;
            for (int i = 0; i < S; i++)
                for (int j = 0; j < S; j++) {
                    double l[3];
                    double pdf = bk_ggx_sample(alpha, v, (i + 0.5) / S, (j + 0.37) / S, l);
                    double w = 0;
                    if (pdf > 0) {
                        assert_true(fabs(pdf - bk_ggx_pdf(alpha, v, l)) <= 1e-9 * pdf);
                        w = bk_ggx_spec(alpha, v, l) * l[2] / pdf;
                        assert_true(fabs(w - bk_ggx_g2(alpha, v[2], l[2]) / bk_ggx_g1(alpha, v[2])) < 1e-9);
                    }
                    m += w;
                    m2 += w * w;
                }
            m /= (double)S * S;
            const double se = sqrt(fmax(0.0, m2 / ((double)S * S) - m * m) / ((double)S * S));
            /* stratified: the iid standard error overstates the spread; 3e-4 for quadrature */
            assert_true(fabs(m - A) < 4 * se + 3e-4);
            if (alpha >= 0.2 && ANGLES[t] <= 75) { /* broad enough for the plain rule in l */
                const double B = albedo_l(alpha, v, 0, 0, 0);
                assert_true(fabs(B - A) < 2e-3);
            }
            if (t == 0 || t == sizeof ANGLES / sizeof *ANGLES - 1)
                print_message("alpha %.2f theta %2.0f: albedo %.5f (sampled %.5f)\n", alpha, ANGLES[t], A, m);
        }
    }
}

/* The glTF mix with base colour 1 (dielectric, metallic 0; metal, metallic 1). The metal is its
 * specular lobe (≤ 1, above). The dielectric's reference mix (1 − F(v·h))·c/π + F·spec is NOT
 * energy conserving: at grazing v the diffuse term keeps ~93 % while F(v·h) → 1 adds most of
 * the specular lobe on top. Measured here: 1.48 at α 0.05, 89°; ≤ 1 near normal incidence. A
 * transport must not bounce light with it as it stands (bake/transport/GGX.md: the
 * Kelemen–Szirmay-Kalos coupling of the diffuse lobe is the planned fix). */
static void test_gltf_mix_energy(void **state)
{
    (void)state;
    double worst_metal = 0, worst_normal = 0, worst_grazing = 0;
    for (int metal = 0; metal < 2; metal++)
        for (size_t a = 0; a < sizeof ALPHAS / sizeof *ALPHAS; a++)
            for (size_t t = 0; t < sizeof ANGLES / sizeof *ANGLES; t++) {
                double v[3];
                dir_of(ANGLES[t] * PI / 180, 0.7, v);
                const double f0 = metal ? 1.0 : 0.04;
                double total = spec_albedo_h(ALPHAS[a], v, f0) + (metal ? 0 : albedo_l(0, v, 1, 1, 0));
                assert_true(total > (metal ? 0.3 : 0.9));
                if (metal) worst_metal = fmax(worst_metal, total);
                else if (ANGLES[t] <= 30) worst_normal = fmax(worst_normal, total);
                else worst_grazing = fmax(worst_grazing, total);
            }
    print_message("glTF mix, base colour 1: metal <= %.4f; dielectric <= %.4f up to 30 deg, %.4f beyond\n",
                  worst_metal, worst_normal, worst_grazing);
    assert_true(worst_metal <= 1 + 1e-9);
    assert_true(worst_normal <= 1 + 1e-3);
    assert_true(worst_grazing > 1.3); /* the reference mix's known excess (measured 1.48) */
}

static void test_reciprocity(void **state)
{
    (void)state;
    for (int i = 0; i < 200; i++) {
        double v[3], l[3];
        dir_of(0.007 * i, 0.3 * i, v);
        dir_of(1.5 - 0.0071 * i, 2.1 + 0.17 * i, l);
        for (size_t a = 0; a < sizeof ALPHAS / sizeof *ALPHAS; a++) {
            double f1 = bk_mr_brdf(0.8, 0.3, sqrt(ALPHAS[a]), v, l), f2 = bk_mr_brdf(0.8, 0.3, sqrt(ALPHAS[a]), l, v);
            assert_true(f1 >= 0 && fabs(f1 - f2) <= 1e-12 * fmax(f1, 1e-300));
        }
    }
    double below[3] = {0.6, 0, -0.8}, up[3] = {0, 0, 1};
    assert_true(bk_mr_brdf(1, 0, 0.5, up, below) == 0 && bk_ggx_pdf(0.2, up, below) == 0);
}

/* ---- the coupled BSDF (bk_mr_lobe, GGX.md) -------------------------------------------------- */

static const double ROUGH[] = {0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0}; /* glTF roughness, α = r² */
static const double TANGLES[] = {0, 30, 60, 75, 85};

static bk_ggx_table *table(void)
{
    bk_ggx_table *t = malloc(sizeof *t);
    assert_non_null(t);
    bk_ggx_table_init(t);
    return t;
}

/* The table's E_s = F0·A + B against the h-space quadrature (F0 = 1 and the dielectric 0.04). */
static void test_albedo_table(void **state)
{
    (void)state;
    bk_ggx_table *t = table();
    double worst = 0;
    for (size_t r = 0; r < sizeof ROUGH / sizeof *ROUGH; r++)
        for (size_t k = 0; k < sizeof TANGLES / sizeof *TANGLES; k++) {
            double v[3], a, b;
            dir_of(TANGLES[k] * PI / 180, 0.4, v);
            bk_ggx_table_eval(t, ROUGH[r], v[2], &a, &b);
            for (int f = 0; f < 2; f++) {
                double f0 = f ? 1.0 : 0.04;
                double q = spec_albedo_h(ROUGH[r] * ROUGH[r], v, f0), e = f0 * a + b;
                worst = fmax(worst, fabs(e - q));
            }
        }
    print_message("albedo table: |E_s(table) - quadrature| <= %.2g (roughness 0.05-1, 0-85 deg)\n", worst);
    assert_true(worst < 2.5e-3);
    free(t);
}

/* ∫ f·cos over l of the coupled lobe: its specular part by the h-space rule (exact Fresnel, no
 * table), its diffuse part by the plain rule in l (smooth). */
static double coupled_albedo(const bk_mr_lobe *lb, int ch)
{
    const double spec = spec_albedo_h(lb->alpha, lb->v, lb->f0[ch]);
    const int NT = 400, NF = 160;
    double sum = 0;
    for (int i = 0; i < NT; i++)
        for (int j = 0; j < NF; j++) {
            double c2 = (i + 0.5) / NT, l[3], a, b;
            dir_of(acos(sqrt(c2)), 2 * PI * (j + 0.5) / NF, l);
            bk_ggx_table_eval(lb->t, lb->roughness, l[2], &a, &b);
            sum += lb->kd[ch] * (1 - fmin(1.0, lb->f0[ch] * a + b));
        }
    return spec + sum * PI / ((double)NT * NF);
}

/* Energy: base colour 1, metallic 0 (where the glTF mix reached 1.48) and 0.5, and a metal: the
 * total directional albedo stays ≤ 1 up to the table's error, and equals what the coupling
 * promises, E_s(v) + c_diff(1 − E_s(v)). */
static void test_coupled_energy(void **state)
{
    (void)state;
    bk_ggx_table *t = table();
    const double metals[] = {0, 0.5, 1}, base[3] = {1, 1, 1};
    double worst = 0, worst_promise = 0;
    for (size_t m = 0; m < 3; m++)
        for (size_t r = 0; r < sizeof ROUGH / sizeof *ROUGH; r++)
            for (size_t k = 0; k < sizeof TANGLES / sizeof *TANGLES; k++) {
                double v[3];
                dir_of(TANGLES[k] * PI / 180, 0.9, v);
                bk_mr_lobe lb;
                assert_true(bk_mr_lobe_init(&lb, t, base, metals[m], ROUGH[r], v));
                double total = coupled_albedo(&lb, 0), a, b;
                bk_ggx_table_eval(t, ROUGH[r], v[2], &a, &b);
                double es = lb.f0[0] * a + b, promise = es + (1 - metals[m]) * (1 - es);
                worst = fmax(worst, total);
                worst_promise = fmax(worst_promise, fabs(total - promise));
            }
    print_message("coupled BSDF, base colour 1: total albedo <= %.5f; |total - promised| <= %.2g\n", worst,
                  worst_promise);
    assert_true(worst <= 1 + 2.5e-3); /* the table's error (test_albedo_table) */
    assert_true(worst_promise < 2.5e-3);
    double below[3] = {0.6, 0, -0.8};
    bk_mr_lobe lb;
    assert_false(bk_mr_lobe_init(&lb, t, base, 0, 0.5, below)); /* nothing reflects towards below */
    free(t);
}

/* The sampler: its density is bk_mr_lobe_pdf's, and the mean of f·cos/pdf is the quadrature. */
static void test_coupled_sampling(void **state)
{
    (void)state;
    bk_ggx_table *t = table();
    const double base[3] = {0.9, 0.5, 0.2};
    for (size_t r = 1; r < sizeof ROUGH / sizeof *ROUGH; r += 2)
        for (size_t k = 0; k < 4; k++) {
            double v[3];
            dir_of(TANGLES[k] * PI / 180, 2.0, v);
            bk_mr_lobe lb;
            assert_true(bk_mr_lobe_init(&lb, t, base, 0.3, ROUGH[r], v));
            const int S = 48;
            double m[3] = {0, 0, 0};
            uint64_t rs = 88172645463325252ull;
            for (int i = 0; i < S; i++)
                for (int j = 0; j < S; j++) {
                    /* the lobe choice: 8 strata shifted by one random offset per (i, j), so the
                     * expected share of each lobe is exactly its probability */
                    rs ^= rs << 13, rs ^= rs >> 7, rs ^= rs << 17;
                    const double shift = (double)(rs >> 11) * 0x1p-53;
                    for (int q = 0; q < 8; q++) {
                        double l[3], f[3], u0 = (q + shift) / 8;
                        double pdf = bk_mr_lobe_sample(&lb, u0, (i + 0.5) / S, (j + 0.5) / S, l);
                        if (!(pdf > 0)) continue;
                        assert_true(fabs(pdf - bk_mr_lobe_pdf(&lb, l)) <= 1e-9 * pdf);
                        bk_mr_lobe_eval(&lb, l, f);
                        for (int c = 0; c < 3; c++) m[c] += f[c] * l[2] / pdf;
                    }
                }
            for (int c = 0; c < 3; c++) {
                double est = m[c] / (8.0 * S * S), q = coupled_albedo(&lb, c);
                if (!(fabs(est - q) < 0.01 * q + 2e-3))
                    print_message("roughness %.2f theta %.0f channel %d: sampled %.5f, quadrature %.5f\n", ROUGH[r],
                                  TANGLES[k], c, est, q);
                assert_true(fabs(est - q) < 0.01 * q + 2e-3);
            }
        }
    free(t);
}

static void test_coupled_reciprocity(void **state)
{
    (void)state;
    bk_ggx_table *t = table();
    const double base[3] = {0.8, 0.6, 0.3};
    for (int i = 0; i < 100; i++) {
        double v[3], l[3], f1[3], f2[3];
        dir_of(0.014 * i, 0.3 * i, v);
        dir_of(1.4 - 0.013 * i, 2.1 + 0.17 * i, l);
        bk_mr_lobe a, b;
        assert_true(bk_mr_lobe_init(&a, t, base, 0.4, 0.3, v) && bk_mr_lobe_init(&b, t, base, 0.4, 0.3, l));
        bk_mr_lobe_eval(&a, l, f1);
        bk_mr_lobe_eval(&b, v, f2);
        for (int c = 0; c < 3; c++) assert_true(f1[c] > 0 && fabs(f1[c] - f2[c]) <= 1e-9 * f1[c]);
    }
    free(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_visible_normals_normalised),
        cmocka_unit_test(test_specular_albedo),
        cmocka_unit_test(test_gltf_mix_energy),
        cmocka_unit_test(test_reciprocity),
        cmocka_unit_test(test_albedo_table),
        cmocka_unit_test(test_coupled_energy),
        cmocka_unit_test(test_coupled_sampling),
        cmocka_unit_test(test_coupled_reciprocity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
