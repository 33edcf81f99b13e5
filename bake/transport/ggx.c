/* GGX + Smith + Schlick, the glTF metallic-roughness mix, visible-normal sampling; ggx.h. */
#include "bake/transport/ggx.h"

#include <math.h>

#define GGX_PI 3.14159265358979323846

static double clamp_alpha(double a) { return a > BK_GGX_ALPHA_MIN ? (a < 1 ? a : 1) : BK_GGX_ALPHA_MIN; }

double bk_ggx_d(double alpha, double cos_h)
{
    if (!(cos_h > 0)) return 0;
    const double a2 = clamp_alpha(alpha) * clamp_alpha(alpha), c2 = cos_h * cos_h;
    const double k = c2 * (a2 - 1) + 1; /* α²cos² + sin² */
    return a2 / (GGX_PI * k * k);
}

double bk_ggx_lambda(double alpha, double cos_t)
{
    if (!(cos_t > 0)) return INFINITY;
    const double a = clamp_alpha(alpha), c2 = cos_t * cos_t, t2 = (1 - c2) / c2; /* tan² θ */
    return 0.5 * (sqrt(1 + a * a * t2) - 1);
}

double bk_ggx_g1(double alpha, double cos_t) { return cos_t > 0 ? 1 / (1 + bk_ggx_lambda(alpha, cos_t)) : 0; }

double bk_ggx_g2(double alpha, double cos_v, double cos_l)
{
    if (!(cos_v > 0) || !(cos_l > 0)) return 0;
    return 1 / (1 + bk_ggx_lambda(alpha, cos_v) + bk_ggx_lambda(alpha, cos_l));
}

static int half_vector(const double v[3], const double l[3], double h[3])
{
    double s[3] = {v[0] + l[0], v[1] + l[1], v[2] + l[2]};
    double n = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    if (!(n > 0)) return 0;
    for (int k = 0; k < 3; k++) h[k] = s[k] / n;
    return 1;
}

double bk_ggx_spec(double alpha, const double v[3], const double l[3])
{
    double h[3];
    if (!(v[2] > 0) || !(l[2] > 0) || !half_vector(v, l, h)) return 0;
    return bk_ggx_d(alpha, h[2]) * bk_ggx_g2(alpha, v[2], l[2]) / (4 * v[2] * l[2]);
}

double bk_ggx_fresnel(double f0, double v_dot_h)
{
    double m = 1 - (v_dot_h > 0 ? (v_dot_h < 1 ? v_dot_h : 1) : 0);
    double m2 = m * m;
    return f0 + (1 - f0) * m2 * m2 * m;
}

double bk_mr_brdf(double base, double metallic, double roughness, const double v[3], const double l[3])
{
    double h[3];
    if (!(v[2] > 0) || !(l[2] > 0) || !half_vector(v, l, h)) return 0;
    const double f0 = 0.04 + (base - 0.04) * metallic, c_diff = (1 - metallic) * base;
    const double vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
    const double F = bk_ggx_fresnel(f0, vh);
    return (1 - F) * c_diff / GGX_PI + F * bk_ggx_spec(roughness * roughness, v, l);
}

/* Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018. */
double bk_ggx_sample(double alpha, const double v[3], double u1, double u2, double l[3])
{
    const double a = clamp_alpha(alpha);
    double vh[3] = {a * v[0], a * v[1], v[2]};
    double len = sqrt(vh[0] * vh[0] + vh[1] * vh[1] + vh[2] * vh[2]);
    for (int k = 0; k < 3; k++) vh[k] /= len;
    double lensq = vh[0] * vh[0] + vh[1] * vh[1];
    double t1[3] = {1, 0, 0};
    if (lensq > 0) {
        double il = 1 / sqrt(lensq);
        t1[0] = -vh[1] * il, t1[1] = vh[0] * il, t1[2] = 0;
    }
    double t2[3] = {vh[1] * t1[2] - vh[2] * t1[1], vh[2] * t1[0] - vh[0] * t1[2], vh[0] * t1[1] - vh[1] * t1[0]};
    double r = sqrt(u1), phi = 2 * GGX_PI * u2;
    double p1 = r * cos(phi), p2 = r * sin(phi), s = 0.5 * (1 + vh[2]);
    p2 = (1 - s) * sqrt(fmax(0.0, 1 - p1 * p1)) + s * p2;
    double p3 = sqrt(fmax(0.0, 1 - p1 * p1 - p2 * p2));
    double nh[3];
    for (int k = 0; k < 3; k++) nh[k] = p1 * t1[k] + p2 * t2[k] + p3 * vh[k];
    double h[3] = {a * nh[0], a * nh[1], fmax(1e-12, nh[2])};
    len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int k = 0; k < 3; k++) h[k] /= len;
    double vdh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
    for (int k = 0; k < 3; k++) l[k] = 2 * vdh * h[k] - v[k];
    return bk_ggx_pdf(alpha, v, l);
}

double bk_ggx_pdf(double alpha, const double v[3], const double l[3])
{
    double h[3];
    if (!(v[2] > 0) || !(l[2] > 0) || !half_vector(v, l, h)) return 0;
    return bk_ggx_g1(alpha, v[2]) * bk_ggx_d(alpha, h[2]) / (4 * v[2]);
}
