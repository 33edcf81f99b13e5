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
 * energy conserving at grazing angles (measured 1.48): bake/transport/GGX.md. Not used by the
 * transport yet (GGX.md). */
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

#endif
