/* Sampling tools of the seed's guided door estimator (seed 001 §4.2; bake/sets/SETS.md "Guided door
 * estimator"): the door's OBB as a portal (an area light the receivers sample), shadow photons
 * shot from the portal towards the lights and clustered into at most 12 boxes (proxy area lights
 * that guide final-gather rays, each with the list of lights whose photons landed in it), and
 * the pdf / multiple-importance-sampling weights that combine box-guided directions with
 * uniform ones. Pure geometry and sampling; the estimator itself is bake/sets/door_guided.c. */
#ifndef BK_DOOR_SAMPLING_H
#define BK_DOOR_SAMPLING_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"
#include "scene/tracer.h"
#include "bake/util/rng.h"

#define BK_GUIDE_MAX_BOXES 12 /* the seed's count */

/* The portal of a door: the rectangle through the OBB's centre spanned by its two longest axes
 * (the thinnest axis is the normal). Every ray that passes through the doorway the door closes
 * crosses it, so sampling it samples "the door as an area light". */
typedef struct bk_portal {
    double centre[3];
    double u[3], v[3], n[3]; /* unit; u, v in the plane, n = u × v */
    double hu, hv;           /* half sizes along u, v */
    double area;             /* 4·hu·hv */
} bk_portal;

/* obb: centre, rows = orthonormal axes, half extents (bake_sets.c's door OBB). */
void bk_portal_from_obb(const float centre[3], const float axes[3][3], const float half[3], bk_portal *out);
/* The point at (a, b) ∈ [0,1)² of the rectangle (a along u). */
void bk_portal_point(const bk_portal *p, double a, double b, double out[3]);
/* 1 when o + t·d crosses the rectangle for t ∈ (0, tmax); *t gets the crossing. */
int bk_portal_crosses(const bk_portal *p, const double o[3], const double d[3], double tmax, double *t);
/* Solid angle the rectangle subtends at x (exact, Van Oosterom–Strackee on its two triangles). */
double bk_portal_solid_angle(const bk_portal *p, const double x[3]);

/* ---- scene lookups shared by the door estimator ------------------------------------------ */

/* The door estimator's stream for (seed, domain, a, item b) (bake/util/rng.h; draw with
 * bk_rng_next), independent of threads. */
bk_rng bk_door_rng_make(uint64_t seed, uint64_t domain, uint64_t a, uint64_t b);

/* Punctual lights and the sky are evaluated by bake/transport/shading.h (bk_light_eval, bk_sky_radiance),
 * the very functions the transport uses, so both estimators see the same lights. */

/* Albedo (clamped to ≤ 0.999) and emitted radiance (0 unless the triangle's object is in
 * light_set; NULL = "" the base) of triangle tri at barycentrics (u, v), textures by uv0 (the
 * material lookups of bake/transport/shading.h). */
void bk_door_surface(const bk_scene *s, uint32_t tri, double u, double v, const char *light_set, double albedo[3],
                     double emission[3]);
/* Emissive triangles of light_set picked by power (area × luminance of the emission factor). */
typedef struct bk_door_emitters {
    size_t count;
    uint32_t *tri;
    double *cdf;   /* inclusive, last = 1 */
    double power;  /* Σ area·lum */
} bk_door_emitters;
lbk_result bk_door_emitters_build(const bk_scene *s, const bk_tracer *t, const char *light_set, bk_door_emitters *out);
void bk_door_emitters_free(bk_door_emitters *e);

/* ---- shadow photons and their boxes ------------------------------------------------------- */

typedef struct bk_photon {
    float p[3];       /* where it landed */
    float w;          /* flux-like weight (luminance through the portal / probability) */
    uint32_t source;  /* punctual light index in the scene, or BK_SOURCE_SKY / BK_SOURCE_EMITTERS */
} bk_photon;

#define BK_SOURCE_SKY 0xFFFFFFFEu
#define BK_SOURCE_EMITTERS 0xFFFFFFFDu

typedef struct bk_guide_box {
    double lo[3], hi[3]; /* axis-aligned, inflated */
    double weight;       /* sum of its photons' weights: the probability of guiding towards it */
    double area;         /* surface area (the guided pdf samples points on the surface) */
    uint32_t light_first, light_count; /* its punctual lights: bk_guide_boxes.lights[first..] */
    uint32_t photons;
} bk_guide_box;

typedef struct bk_guide_boxes {
    int count;                       /* 0..BK_GUIDE_MAX_BOXES, sorted by weight, heaviest first */
    bk_guide_box box[BK_GUIDE_MAX_BOXES];
    uint32_t *lights;                /* scene punctual light indices, ascending per box */
    size_t light_total;
    double weight_sum;
    uint32_t source_mask;            /* bit 0: sky photons landed, bit 1: emitter photons */
} bk_guide_boxes;

typedef struct bk_photon_options {
    uint64_t seed;
    size_t count;               /* photon paths to try; 0: 4096 */
    int use_sky;                /* the sky is a source (base bakes) */
    const char *light_set;      /* "" or NULL: the base's lights and emitters */
} bk_photon_options;

/* Shoots shadow photons (seed §4.2): uniform points on the portal, a source chosen uniformly
 * among the punctual lights (of light_set), the sky and the emitters (picked by power, then a
 * uniform point on the triangle); an unoccluded shadow ray towards the source (in `tracer`, the
 * scene with the door removed) is continued in the opposite direction into the scene and a
 * photon is stored where it lands. *out (malloc'ed) gets the photons, *n their count.
 * Deterministic in (seed, scene). */
lbk_result bk_shoot_shadow_photons(const bk_scene *scene, const bk_tracer *tracer, const bk_portal *portal,
                                   const bk_photon_options *opt, bk_photon **out, size_t *n);

/* Clusters photons into at most max_boxes (≤ 12) axis-aligned boxes by weighted k-means
 * (deterministic farthest-point start), inflates each by inflate_rel × its largest extent plus
 * inflate_abs on every side (the seed's inflation against lights missed by tight boxes), and
 * records per box the punctual lights its photons came from. */
lbk_result bk_cluster_photons(const bk_photon *ph, size_t n, int max_boxes, double inflate_rel, double inflate_abs,
                              bk_guide_boxes *out);
void bk_guide_boxes_free(bk_guide_boxes *b);

/* The first (heaviest) box containing x, or -1. */
int bk_guide_box_containing(const bk_guide_boxes *b, const double x[3]);

/* Box-guided direction from x: a box by weight (u0), a uniform point on its surface (u1, u2),
 * d = unit(point − x). Returns 0 when no box can be sampled (none, or x on the point). */
int bk_guide_sample(const bk_guide_boxes *b, const double x[3], double u0, double u1, double u2, double d[3]);
/* Solid-angle density of bk_guide_sample producing unit direction d at x: Σ_b P(b)/A_b ·
 * Σ_{surface crossings} t²/|cos θ| (a ray crosses a convex box's surface at most twice). */
double bk_guide_pdf(const bk_guide_boxes *b, const double x[3], const double d[3]);

/* Multi-sample balance heuristic with n_a samples of pdf p_a and n_b of p_b: the weight of the
 * strategy a for a direction both can produce; w_a + w_b = 1 wherever n_a·p_a + n_b·p_b > 0. */
double bk_mis_balance(double n_a, double p_a, double n_b, double p_b);

#endif
