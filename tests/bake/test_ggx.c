/* The glTF metallic-roughness BRDF (bake/transport/ggx.h): the visible-normal density
 * integrates to 1 (Smith's G1 is the right normalisation of D), the specular lobe's
 * directional albedo is ≤ 1 at every roughness and angle and equal to two independent
 * quadratures and to visible-normal sampling, how far the glTF reference mix is from energy
 * conservation (it is not, at grazing angles), reciprocity, and the sampler's density is the
 * one bk_ggx_pdf states. */
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_visible_normals_normalised),
        cmocka_unit_test(test_specular_albedo),
        cmocka_unit_test(test_gltf_mix_energy),
        cmocka_unit_test(test_reciprocity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
