/* Glossy (GGX metallic-roughness) materials in the transport (bake/transport/GGX.md) against
 * answers derived without the baker: a metal plane under a uniform sky seen from above (the
 * reflected sky is π·L·Ē_s, Ē_s by quadrature), a closed glossy furnace (radiance between the
 * bounds its directional albedo range allows), the lobe a metal floor reflects a point light
 * into (its profile, total and centroid on a ceiling against a brute-force integral over the
 * floor), and that a material with metallic 0 and no texture runs exactly the Lambertian path. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/transport/ggx.h"
#include "bake/transport/transport.h"
#include "support/transport_scenes.h"

#define PI 3.14159265358979323846

static void plane(bk_scene *s, float half, float z, int n, uint32_t mat)
{
    float p0[3] = {-half, -half, z}, p1[3] = {half, -half, z}, p2[3] = {half, half, z}, p3[3] = {-half, half, z};
    tsc_quad(s, p0, p1, p2, p3, n, mat);
}

static uint32_t metal(bk_scene *s, float base, float metallic, float roughness, float emission)
{
    uint32_t m = tsc_material(s, base, base, base, emission, emission, emission);
    s->materials[m].metallic = metallic;
    s->materials[m].roughness = roughness;
    return m;
}

static void receiver(bk_receiver *r, float x, float y, float z, float nz)
{
    memset(r, 0, sizeof *r);
    r->position[0] = x; r->position[1] = y; r->position[2] = z;
    r->normal[2] = nz;
}

static float *irradiance(const bk_scene *s, const bk_receiver *r, size_t n, const bk_transport_options *o)
{
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(s, 0, &t), LBK_OK);
    lbk_sh9_rgb *rad = calloc(n, sizeof *rad);
    float *irr = calloc(3 * n, sizeof *irr);
    bk_transport_output out = {rad, NULL, irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    bk_transport_stats st;
    assert_int_equal(bk_transport_run(s, t, r, n, o, &out, &st), LBK_OK);
    assert_int_equal(st.nonfinite, 0);
    for (size_t i = 0; i < 3 * n; i++) assert_true(isfinite(irr[i]) && irr[i] >= 0);
    bk_tracer_destroy(t);
    free(rad);
    return irr;
}

/* E_s(μ) with Fresnel f0 by a midpoint rule over the GGX normals in their projected area
 * (test_ggx's h-space rule: the peak of D needs no resolving). */
static double spec_albedo(double alpha, double mu, double f0)
{
    const int NU = 600, NP = 96;
    const double v[3] = {sqrt(1 - mu * mu), 0, mu};
    double sum = 0;
    for (int i = 0; i < NU; i++)
        for (int j = 0; j < NP; j++) {
            double s = (i + 0.5) / NU, phi = 2 * PI * (j + 0.5) / NP, u = 1 - s * s;
            double c = 1 / sqrt(1 + alpha * alpha * u / (s * s)), sn = sqrt(1 - c * c);
            double h[3] = {sn * cos(phi), sn * sin(phi), c}, l[3];
            double vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            if (!(vh > 0)) continue;
            for (int k = 0; k < 3; k++) l[k] = 2 * vh * h[k] - v[k];
            if (!(l[2] > 0)) continue;
            sum += 2 * s * bk_ggx_fresnel(f0, vh) * bk_ggx_g2(alpha, mu, l[2]) * vh / (mu * c);
        }
    return sum / ((double)NU * NP);
}

/* Ē_s = 2∫E_s(μ)μ dμ (midpoint in μ², so the rule sees cos-weighting exactly). */
static double spec_albedo_mean(double alpha, double f0)
{
    const int N = 48;
    double sum = 0;
    for (int i = 0; i < N; i++) sum += spec_albedo(alpha, sqrt((i + 0.5) / N), f0);
    return sum / N;
}

/* A metal plane (50 m half size) under a uniform sky L: a receiver 1 m above it facing down sees
 * the plane reflect the sky, E = π·L·Ē_s(F0 = base) (the plane hides the sky below 88.9°, what
 * it leaves out is < 4e-4); one facing up sees the sky, π·L. The plane's own reflection is
 * evaluated at the exact points, so this is the lobe sampler's estimate alone. */
static void test_metal_plane_sky(void **state)
{
    (void)state;
    const float base = 0.8f, rough = 0.4f;
    bk_scene s;
    tsc_init(&s);
    plane(&s, 50, 0, 4, metal(&s, base, 1, rough, 0));
    s.sky[0] = s.sky[1] = s.sky[2] = 2;
    enum { N = 32 };
    bk_receiver r[N];
    for (int i = 0; i < N; i++) receiver(&r[i], (float)(i % 8) - 4, (float)(i / 8) - 2, 1, i < N / 2 ? -1.0f : 1.0f);
    bk_transport_options o = tsc_fixed_passes(6, 5);
    float *irr = irradiance(&s, r, N, &o);
    const double expect_down = PI * 2 * spec_albedo_mean((double)rough * rough, base), expect_up = PI * 2;
    double mean_down = 0, mean_up = 0, worst = 0;
    for (int i = 0; i < N; i++) {
        double e = irr[3 * i + 1];
        if (i < N / 2) {
            mean_down += e / (N / 2);
            worst = fmax(worst, fabs(e / expect_down - 1));
        } else {
            mean_up += e / (N / 2);
        }
    }
    print_message("metal plane under the sky: down %.4f (expected %.4f, %+.2f %%, worst receiver %.2f %%), up %.4f "
                  "(expected %.4f)\n", mean_down, expect_down, 100 * (mean_down / expect_down - 1), 100 * worst,
                  mean_up, expect_up);
    assert_true(fabs(mean_down / expect_down - 1) < 0.01);
    assert_true(worst < 0.05);
    assert_true(fabs(mean_up / expect_up - 1) < 1e-3);
    /* the Lambertian stand-in would give π·L·ρ: the test tells them apart */
    assert_true(fabs(expect_down / (PI * 2 * base) - 1) > 0.02);
    free(irr);
    tsc_free(&s);
}

/* A closed glossy furnace: a box whose inward walls (metallic 0.5, base 0.8, roughness 0.5)
 * all emit Le. The radiance leaving a wall towards ω is Le + E_tot(ω)·L̄ for the mean incident
 * L̄, so every radiance lies within [Le/(1 − E_min), Le/(1 − E_max)], E_tot = E_s + c_diff(1 − E_s)
 * the coupled BSDF's directional albedo over all angles (quadrature); irradiance/π at
 * receivers inside too. The uncoupled glTF mix (which exceeds 1 at grazing) or a lost lobe
 * would leave the bounds. */
static void test_glossy_furnace(void **state)
{
    (void)state;
    const float base = 0.8f, metallic = 0.5f, rough = 0.5f, le = 1;
    bk_scene s;
    tsc_init(&s);
    float mn[3] = {-1, -1, -1}, mx[3] = {1, 1, 1};
    tsc_box(&s, mn, mx, 2, 1, metal(&s, base, metallic, rough, le));
    enum { N = 27 };
    bk_receiver r[N];
    for (int i = 0; i < N; i++) {
        float p[3] = {0.5f * (float)(i % 3 - 1), 0.5f * (float)((i / 3) % 3 - 1), 0.5f * (float)(i / 9 - 1)};
        receiver(&r[i], p[0], p[1], p[2], 0);
        r[i].normal[i % 3] = (i / 3) % 2 ? 1.0f : -1.0f;
    }
    bk_transport_options o = tsc_fixed_passes(5, 5);
    float *irr = irradiance(&s, r, N, &o);
    const double f0 = 0.04 + (base - 0.04) * metallic, c_diff = (1 - metallic) * base;
    double emin = 1, emax = 0;
    for (int k = 0; k <= 20; k++) {
        double mu = k ? k / 20.0 : 0.02, es = spec_albedo((double)rough * rough, mu, f0);
        double et = es + c_diff * (1 - es);
        emin = fmin(emin, et);
        emax = fmax(emax, et);
    }
    const double lo = le / (1 - emin), hi = le / (1 - emax);
    double mean = 0, worst_lo = INFINITY, worst_hi = 0;
    for (int i = 0; i < N; i++) {
        double l = irr[3 * i] / PI;
        mean += l / N;
        worst_lo = fmin(worst_lo, l);
        worst_hi = fmax(worst_hi, l);
    }
    print_message("glossy furnace: radiance %.4f (receivers %.4f-%.4f) within [%.4f, %.4f] (E_tot %.4f-%.4f)\n", mean,
                  worst_lo, worst_hi, lo, hi, emin, emax);
    /* 3 % for the receivers' noise and the Neumann tail's estimate */
    assert_true(worst_lo >= 0.97 * lo && worst_hi <= 1.03 * hi);
    free(irr);
    tsc_free(&s);
}

/* A point light 1 m above a metal floor (roughness 0.3, base 0.9) and a row of receivers on a
 * "ceiling" 2 m up facing down, x ∈ [−1.5, 1.5] at y = 0, light at x = −0.5: the floor
 * reflects the light into a lobe that a mirror would centre above the light's image (x = −0.5;
 * the row's asymmetry and the lobe's shape move the centroid), and nothing else reflects. The reflected irradiance (total minus the light's direct I·cos/d²) is
 * compared receiver by receiver, in total and by its centroid with a brute-force integral over
 * the floor: E(r) = ∫ f(v, l)·(I cos θ_l / d_l²)·cos θ_y cos θ_r / d_r² dA. */
#define ROW 16
static void lobe_brute(const bk_ggx_table *t, const double light[3], double I, double base, double rough,
                       const double rp[3], double *out)
{
    const int NG = 600;
    const double half = 4;
    double sum = 0, b3[3] = {base, base, base};
    for (int i = 0; i < NG; i++)
        for (int j = 0; j < NG; j++) {
            double y[3] = {-half + 2 * half * (i + 0.5) / NG, -half + 2 * half * (j + 0.5) / NG, 0};
            double dl[3] = {light[0] - y[0], light[1] - y[1], light[2] - y[2]};
            double dr[3] = {rp[0] - y[0], rp[1] - y[1], rp[2] - y[2]};
            double nl = sqrt(dl[0] * dl[0] + dl[1] * dl[1] + dl[2] * dl[2]);
            double nr = sqrt(dr[0] * dr[0] + dr[1] * dr[1] + dr[2] * dr[2]);
            double l[3] = {dl[0] / nl, dl[1] / nl, dl[2] / nl}, v[3] = {dr[0] / nr, dr[1] / nr, dr[2] / nr};
            bk_mr_lobe lb;
            if (!bk_mr_lobe_init(&lb, t, b3, 1, rough, v)) continue;
            double f[3];
            bk_mr_lobe_eval(&lb, l, f);
            sum += f[0] * I * l[2] / (nl * nl) * v[2] * v[2] / (nr * nr); /* cos θ_r = v_z (facing down) */
        }
    *out = sum * (2 * half / NG) * (2 * half / NG);
}

static void test_reflected_lobe(void **state)
{
    (void)state;
    const float base = 0.9f, rough = 0.3f, I = 10;
    bk_scene s;
    tsc_init(&s);
    plane(&s, 20, 0, 8, metal(&s, base, 1, rough, 0));
    const float lp[3] = {-0.5f, 0, 1};
    tsc_point_light(&s, lp, I, I, I, 0);
    bk_receiver r[ROW];
    for (int i = 0; i < ROW; i++) receiver(&r[i], -1.5f + 3.0f * (float)i / (ROW - 1), 0, 2, -1);
    bk_transport_options o = tsc_fixed_passes(8, 5);
    float *irr = irradiance(&s, r, ROW, &o);
    bk_ggx_table *t = malloc(sizeof *t);
    assert_non_null(t);
    bk_ggx_table_init(t);
    double light[3] = {lp[0], lp[1], lp[2]};
    double sum_b = 0, sum_l = 0, cx_b = 0, cx_l = 0, worst = 0, peak = 0;
    double brute[ROW], mine[ROW];
    for (int i = 0; i < ROW; i++) {
        double rp[3] = {r[i].position[0], 0, 2};
        lobe_brute(t, light, I, base, rough, rp, &brute[i]);
        double d2 = (rp[0] - lp[0]) * (rp[0] - lp[0]) + 1.0; /* the light's direct part (1 m below) */
        double direct = I * (1.0 / sqrt(d2)) / d2;
        mine[i] = irr[3 * i] - direct;
        sum_b += brute[i], sum_l += mine[i];
        cx_b += rp[0] * brute[i], cx_l += rp[0] * mine[i];
        peak = fmax(peak, brute[i]);
    }
    for (int i = 0; i < ROW; i++) worst = fmax(worst, fabs(mine[i] - brute[i]) / peak);
    cx_b /= sum_b, cx_l /= sum_l;
    print_message("reflected lobe: total %.4f vs brute force %.4f (%+.2f %%), centroid x %.4f vs %.4f, worst receiver "
                  "%.2f %% of the peak\n", sum_l, sum_b, 100 * (sum_l / sum_b - 1), cx_l, cx_b, 100 * worst);
    assert_true(fabs(sum_l / sum_b - 1) < 0.03);
    assert_true(fabs(cx_l - cx_b) < 0.03);
    assert_true(worst < 0.12); /* one receiver's noise at 8160 rays (8 % measured) */
    /* the mirror geometry: the brute-force profile peaks above the light's image */
    int ipk = 0;
    for (int i = 1; i < ROW; i++)
        if (brute[i] > brute[ipk]) ipk = i;
    assert_true(fabs(r[ipk].position[0] - lp[0]) <= 0.25);
    free(t);
    free(irr);
    tsc_free(&s);
}

/* metallic 0 without a texture is the Lambertian path bit for bit, whatever the roughness; a
 * metallic value changes the result. */
static void test_lambertian_unchanged(void **state)
{
    (void)state;
    float *res[3];
    for (int k = 0; k < 3; k++) {
        bk_scene s;
        tsc_init(&s);
        uint32_t m = tsc_material(&s, 0.6f, 0.6f, 0.6f, 0, 0, 0);
        s.materials[m].roughness = k == 1 ? 0.2f : 0;
        s.materials[m].metallic = k == 2 ? 0.01f : 0;
        plane(&s, 5, 0, 2, m);
        float mn[3] = {-1, -1, 0.5f}, mx[3] = {1, 1, 2};
        tsc_box(&s, mn, mx, 1, 0, tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0));
        s.sky[0] = s.sky[1] = s.sky[2] = 1;
        bk_receiver r[8];
        for (int i = 0; i < 8; i++) receiver(&r[i], -2 + 0.5f * (float)i, 0.3f, 0.01f, 1);
        bk_transport_options o = tsc_fixed_passes(3, 5);
        res[k] = irradiance(&s, r, 8, &o);
        tsc_free(&s);
    }
    assert_memory_equal(res[0], res[1], 3 * 8 * sizeof(float));
    assert_memory_not_equal(res[0], res[2], 3 * 8 * sizeof(float));
    for (int k = 0; k < 3; k++) free(res[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_metal_plane_sky),
        cmocka_unit_test(test_glossy_furnace),
        cmocka_unit_test(test_reflected_lobe),
        cmocka_unit_test(test_lambertian_unchanged),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
