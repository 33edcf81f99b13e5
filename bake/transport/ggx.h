/* The glTF metallic-roughness BRDF (glTF 2.0 spec, Appendix B): a GGX (Trowbridge-Reitz)
 * microfacet specular lobe with the height-correlated Smith masking-shadowing term and Schlick
 * Fresnel, mixed with a Lambertian diffuse lobe by the Fresnel term:
 *
 *   f = (1 − F(v·h))·c_diff/π + F(v·h)·D(h)·G2(v, l)/(4|n·v||n·l|),
 *   c_diff = (1 − metallic)·baseColor,  F0 = lerp(0.04, baseColor, metallic),  α = roughness².
 *
 * Plus sampling of the visible normals (Heitz 2018), so a baker can continue a path through the
 * specular lobe with weight F·G2/G1(v). Directions are in the local frame (n = +z); v is the
 * outgoing direction (towards the viewer / the receiver), l the incoming one (towards the
 * light); both point away from the surface. Test: test_ggx (the specular lobe's directional
 * albedo ≤ 1 at every roughness and angle, equal to quadrature and to 1 − ln 2 where that is
 * exact; the visible-normal density integrates to 1; reciprocity). The reference mix is NOT
 * energy conserving at grazing angles (measured 1.48): bake/transport/GGX.md. The transport
 * bounces light with the energy-conserving coupled form below (bk_mr_lobe), not with it. */
#ifndef BK_GGX_H
#define BK_GGX_H

/* α below this is treated as this (a mirror has a delta lobe the quadrature cannot see). */
#define BK_GGX_ALPHA_MIN 1e-3

/* GGX normal distribution D(h) for cos θ_h = n·h (0 for cos ≤ 0). */
double bk_ggx_d(double alpha, double cos_h);
/* Smith Λ(ω) for cos θ = n·ω: G1 = 1/(1 + Λ); the height-correlated G2 = 1/(1 + Λ(v) + Λ(l)). */
double bk_ggx_lambda(double alpha, double cos_t);
double bk_ggx_g1(double alpha, double cos_t);
double bk_ggx_g2(double alpha, double cos_v, double cos_l);
/* The specular lobe with Fresnel 1: D·G2/(4|n·v||n·l|) (0 below the horizon). */
double bk_ggx_spec(double alpha, const double v[3], const double l[3]);
/* Schlick's Fresnel. */
double bk_ggx_fresnel(double f0, double v_dot_h);

/* The whole glTF BRDF for one channel. */
double bk_mr_brdf(double base, double metallic, double roughness, const double v[3], const double l[3]);

/* A visible normal for v from (u1, u2) ∈ [0,1)², reflected into l; returns the density of l per
 * unit solid angle, G1(v)·D(h)/(4·n·v) (0 when l is below the horizon: the sample is lost). */
double bk_ggx_sample(double alpha, const double v[3], double u1, double u2, double l[3]);
/* The density bk_ggx_sample draws l with. */
double bk_ggx_pdf(double alpha, const double v[3], const double l[3]);

/* ---- the coupled BSDF the transport bounces light with (GGX.md) ---------------------------------
 * Kelemen & Szirmay-Kalos style coupling of the diffuse lobe to the specular one: per channel
 *
 *   f = F(v·h)·D·G2/(4|n·v||n·l|) + c_diff/π · (1 − E_s(v))(1 − E_s(l)) / (1 − Ē_s),
 *
 * E_s(μ) = F0·A(α, μ) + B(α, μ) the specular lobe's directional albedo with Schlick's Fresnel
 * split into A = ∫(1 − (1 − v·h)⁵)·spec·cos and B = ∫(1 − v·h)⁵·spec·cos, Ē_s = 2∫E_s(μ)μ dμ its
 * cosine-weighted mean. Reciprocal, and the total directional albedo is
 * E_s(v) + c_diff·(1 − E_s(v)) ≤ 1 (the table's E_s and Ē_s are consistent by construction: Ē_s
 * is the exact integral of the interpolated table). A and B come from a table in (roughness, μ)
 * (bilinear), made by stratified visible-normal quadrature. */
#define BK_GGX_TABLE_R 33   /* roughness nodes 0, 1/32, ..., 1 */
#define BK_GGX_TABLE_MU 33  /* cos θ nodes 0, 1/32, ..., 1 (node 0 evaluated at 1e-4) */

typedef struct bk_ggx_table {
    float a[BK_GGX_TABLE_R][BK_GGX_TABLE_MU], b[BK_GGX_TABLE_R][BK_GGX_TABLE_MU];
    double abar[BK_GGX_TABLE_R], bbar[BK_GGX_TABLE_R]; /* 2∫A μ dμ, 2∫B μ dμ of the interpolant */
} bk_ggx_table;

/* Fills the table (deterministic; ~10^6 lobe samples). */
void bk_ggx_table_init(bk_ggx_table *t);
/* A(α = r², μ), B(α = r², μ) by bilinear interpolation; r and μ clamped to [0, 1]. */
void bk_ggx_table_eval(const bk_ggx_table *t, double roughness, double mu, double *a, double *b);
/* Ā, B̄ at roughness r (linear between the roughness nodes: the exact mean of the interpolant). */
void bk_ggx_table_mean(const bk_ggx_table *t, double roughness, double *abar, double *bbar);

/* The coupled BSDF at one point for one outgoing direction v (local frame, v.z > 0). */
typedef struct bk_mr_lobe {
    double alpha, roughness;
    double f0[3];          /* lerp(0.04, base, metallic) */
    double kd[3];          /* c_diff·(1 − E_s(v)) / (π(1 − Ē_s)) */
    double p_spec;         /* probability that a sample takes the specular lobe */
    const bk_ggx_table *t;
    double v[3];
} bk_mr_lobe;

/* The specular reflectance at normal incidence of glTF's metallic-roughness model:
 * lerp(0.04, base, metallic), base clamped to [0, 1]. */
double bk_mr_f0(double base, double metallic);

/* base colour (linear, ≤ 1), metallic and roughness in [0, 1]. Returns 0 when v is below the
 * horizon (nothing is reflected towards it). */
int bk_mr_lobe_init(bk_mr_lobe *lb, const bk_ggx_table *t, const double base[3], double metallic, double roughness,
                    const double v[3]);
/* f(v, l) per channel (without the cosine); 0 below the horizon. */
void bk_mr_lobe_eval(const bk_mr_lobe *lb, const double l[3], double f[3]);
/* The coupled diffuse part alone, c_diff/π·(1 − E_s(v))(1 − E_s(l))/(1 − Ē_s) (eval minus the
 * specular lobe F·D·G2/(4|n·v||n·l|)): what the transport evaluates at a glossy point for the
 * lights whose specular bounce glossy VPLs carry (VPL.md). */
void bk_mr_lobe_eval_diffuse(const bk_mr_lobe *lb, const double l[3], double f[3]);
/* The density (solid angle) sampling draws l with. */
double bk_mr_lobe_pdf(const bk_mr_lobe *lb, const double l[3]);
/* A direction from (u0, u1, u2) ∈ [0,1)³ (u0 picks the lobe); returns its density (0: lost). */
double bk_mr_lobe_sample(const bk_mr_lobe *lb, double u0, double u1, double u2, double l[3]);
/* The total directional albedo towards v as the coupling makes it, E_s(v) + c_diff(1 − E_s(v))
 * per channel (from the table), and its cosine-weighted mean over v: what a Lambertian stand-in
 * of the material reflects. */
void bk_mr_albedo_mean(const bk_ggx_table *t, const double base[3], double metallic, double roughness, double out[3]);

#endif
