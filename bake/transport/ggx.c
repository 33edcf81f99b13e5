/* GGX + Smith + Schlick, the glTF metallic-roughness mix, visible-normal sampling; ggx.h. */
#include "bake/transport/ggx.h"
#include "bake/transport/shading.h"

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

/* ---- the albedo table and the coupled BSDF (ggx.h) ------------------------------------------- */

/* stratified visible-normal samples per table entry: TABLE_NU in u1 (the radius on the
 * projected hemisphere, whose rim holds the directions lost below the horizon: it needs the
 * finer grid) × TABLE_NP in u2 */
#ifndef TABLE_NU
#define TABLE_NU 256
#endif
#ifndef TABLE_NP
#define TABLE_NP 8
#endif

static double clamp01(double x) { return x > 0 ? (x < 1 ? x : 1) : 0; }

double bk_mr_f0(double base, double metallic) { return 0.04 + (clamp01(base) - 0.04) * metallic; }

/* A and B at (α, μ) by the visible-normal estimator: E = E_vndf[F·G2/G1(v)]. */
static void table_entry(double alpha, double mu, double *a, double *b)
{
    const double v[3] = {sqrt(fmax(0.0, 1 - mu * mu)), 0, mu};
    const double g1 = bk_ggx_g1(alpha, mu);
    double sa = 0, sb = 0;
    for (int i = 0; i < TABLE_NU; i++)
        for (int j = 0; j < TABLE_NP; j++) {
            double l[3];
            if (!(bk_ggx_sample(alpha, v, (i + 0.5) / TABLE_NU, (j + 0.5) / TABLE_NP, l) > 0)) continue;
            double h[3] = {v[0] + l[0], v[1] + l[1], v[2] + l[2]};
            double hn = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            double vh = hn > 0 ? (v[0] * h[0] + v[1] * h[1] + v[2] * h[2]) / hn : 0;
            double w = bk_ggx_g2(alpha, mu, l[2]) / g1;
            double m = 1 - clamp01(vh), m5 = m * m * m * m * m;
            sa += (1 - m5) * w;
            sb += m5 * w;
        }
    *a = sa / (TABLE_NU * TABLE_NP);
    *b = sb / (TABLE_NU * TABLE_NP);
}

void bk_ggx_table_init(bk_ggx_table *t)
{
    const double h = 1.0 / (BK_GGX_TABLE_MU - 1);
    for (int i = 0; i < BK_GGX_TABLE_R; i++) {
        double r = (double)i / (BK_GGX_TABLE_R - 1);
        for (int j = 0; j < BK_GGX_TABLE_MU; j++) {
            double mu = j ? j * h : 1e-4, a, b;
            table_entry(r * r, mu, &a, &b);
            t->a[i][j] = (float)a;
            t->b[i][j] = (float)b;
        }
        /* 2∫X(μ)μ dμ of the piecewise-linear interpolant (as evaluated: the float nodes) */
        double sa = 0, sb = 0;
        for (int j = 0; j + 1 < BK_GGX_TABLE_MU; j++) {
            double m0 = j * h, m1 = (j + 1) * h;
            sa += h * (t->a[i][j] * (2 * m0 + m1) + t->a[i][j + 1] * (m0 + 2 * m1)) / 6;
            sb += h * (t->b[i][j] * (2 * m0 + m1) + t->b[i][j + 1] * (m0 + 2 * m1)) / 6;
        }
        t->abar[i] = 2 * sa;
        t->bbar[i] = 2 * sb;
    }
}

static void cell_of(double x, int n, int *i, double *f)
{
    double s = clamp01(x) * (n - 1);
    int k = (int)s;
    if (k > n - 2) k = n - 2;
    *i = k;
    *f = s - k;
}

void bk_ggx_table_eval(const bk_ggx_table *t, double roughness, double mu, double *a, double *b)
{
    int i, j;
    double fr, fm;
    cell_of(roughness, BK_GGX_TABLE_R, &i, &fr);
    cell_of(mu, BK_GGX_TABLE_MU, &j, &fm);
    double w00 = (1 - fr) * (1 - fm), w01 = (1 - fr) * fm, w10 = fr * (1 - fm), w11 = fr * fm;
    *a = w00 * t->a[i][j] + w01 * t->a[i][j + 1] + w10 * t->a[i + 1][j] + w11 * t->a[i + 1][j + 1];
    *b = w00 * t->b[i][j] + w01 * t->b[i][j + 1] + w10 * t->b[i + 1][j] + w11 * t->b[i + 1][j + 1];
}

void bk_ggx_table_mean(const bk_ggx_table *t, double roughness, double *abar, double *bbar)
{
    int i;
    double fr;
    cell_of(roughness, BK_GGX_TABLE_R, &i, &fr);
    *abar = (1 - fr) * t->abar[i] + fr * t->abar[i + 1];
    *bbar = (1 - fr) * t->bbar[i] + fr * t->bbar[i + 1];
}

int bk_mr_lobe_init(bk_mr_lobe *lb, const bk_ggx_table *t, const double base[3], double metallic, double roughness,
                    const double v[3])
{
    if (!(v[2] > 0)) return 0;
    metallic = clamp01(metallic);
    roughness = clamp01(roughness);
    lb->t = t;
    lb->roughness = roughness;
    lb->alpha = roughness * roughness;
    for (int k = 0; k < 3; k++) lb->v[k] = v[k];
    double a, b, abar, bbar, es[3], cd[3];
    bk_ggx_table_eval(t, roughness, v[2], &a, &b);
    bk_ggx_table_mean(t, roughness, &abar, &bbar);
    for (int k = 0; k < 3; k++) {
        double bc = clamp01(base[k]);
        lb->f0[k] = bk_mr_f0(bc, metallic);
        es[k] = fmin(1.0, lb->f0[k] * a + b);
        double ebar = fmin(1.0, lb->f0[k] * abar + bbar);
        double c_diff = (1 - metallic) * bc;
        cd[k] = c_diff * (1 - es[k]);
        lb->kd[k] = ebar < 1 ? cd[k] / (GGX_PI * (1 - ebar)) : 0;
    }
    /* pick a lobe in proportion to what it reflects towards v (any split is unbiased) */
    double ws = bk_lum(es), wd = bk_lum(cd);
    lb->p_spec = ws + wd > 0 ? ws / (ws + wd) : 1;
    if (wd <= 0) lb->p_spec = 1;
    return 1;
}

void bk_mr_lobe_eval(const bk_mr_lobe *lb, const double l[3], double f[3])
{
    f[0] = f[1] = f[2] = 0;
    double h[3];
    if (!(l[2] > 0) || !half_vector(lb->v, l, h)) return;
    double spec = bk_ggx_spec(lb->alpha, lb->v, l);
    double vh = lb->v[0] * h[0] + lb->v[1] * h[1] + lb->v[2] * h[2];
    double a, b, es_l;
    bk_ggx_table_eval(lb->t, lb->roughness, l[2], &a, &b);
    for (int k = 0; k < 3; k++) {
        es_l = fmin(1.0, lb->f0[k] * a + b);
        f[k] = bk_ggx_fresnel(lb->f0[k], vh) * spec + lb->kd[k] * (1 - es_l);
    }
}

void bk_mr_lobe_eval_diffuse(const bk_mr_lobe *lb, const double l[3], double f[3])
{
    f[0] = f[1] = f[2] = 0;
    if (!(l[2] > 0)) return;
    double a, b;
    bk_ggx_table_eval(lb->t, lb->roughness, l[2], &a, &b);
    for (int k = 0; k < 3; k++) f[k] = lb->kd[k] * (1 - fmin(1.0, lb->f0[k] * a + b));
}

double bk_mr_lobe_pdf(const bk_mr_lobe *lb, const double l[3])
{
    if (!(l[2] > 0)) return 0;
    double ps = lb->p_spec;
    return ps * bk_ggx_pdf(lb->alpha, lb->v, l) + (1 - ps) * l[2] / GGX_PI;
}

double bk_mr_lobe_sample(const bk_mr_lobe *lb, double u0, double u1, double u2, double l[3])
{
    if (u0 < lb->p_spec) {
        bk_ggx_sample(lb->alpha, lb->v, u1, u2, l);
    } else {
        double r = sqrt(u1), ph = 2 * GGX_PI * u2;
        l[0] = r * cos(ph), l[1] = r * sin(ph), l[2] = sqrt(fmax(0.0, 1 - u1));
    }
    return bk_mr_lobe_pdf(lb, l);
}

void bk_mr_albedo_mean(const bk_ggx_table *t, const double base[3], double metallic, double roughness, double out[3])
{
    double abar, bbar;
    metallic = clamp01(metallic);
    bk_ggx_table_mean(t, clamp01(roughness), &abar, &bbar);
    for (int k = 0; k < 3; k++) {
        double bc = clamp01(base[k]);
        double f0 = bk_mr_f0(bc, metallic);
        double ebar = fmin(1.0, f0 * abar + bbar);
        /* mean over v of E_s(v) + c_diff(1 − E_s(v)): the mean of a linear function of E_s */
        out[k] = ebar + (1 - metallic) * bc * (1 - ebar);
    }
}
