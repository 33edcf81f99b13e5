/* Virtual point lights for single-bounce glossy and diffuse light, culled stochastically (seed
 * 002, Tokuyoshi & Harada, "Stochastic light culling for VPLs on GGX microsurfaces"; the math
 * and the measurements are in bake/transport/VPL.md).
 *
 * 1. bk_vpl_shoot: photons from one spot or point light; where one hits a surface, a VPL per
 *    lobe of the surface's bk_vpl_material (a diffuse one with reflectance k, a glossy GGX one
 *    with F0 and α), each with the photon's flux Φ, the hit, the normal and the incoming
 *    direction. Its radiant intensity towards ω_o is I(ω_o) = Φ·f(ω_i, ω_o)·max(ω_o·n, 0).
 * 2. bk_vpl_draw_create: one uniform ξ per VPL; a receiver at distance l in direction ω_o
 *    accepts the VPL with p = min(I(ω_o)/(δl²), 1) (luminance) and divides its contribution by
 *    p, so the gather is unbiased for any δ > 0. Accepted points lie inside l < √(I(ω_o)/(δξ)),
 *    which is bounded by one of three volumes (enum bk_vpl_bound): for glossy VPLs the sphere at
 *    the VPL of radius r/α, the sphere around the seed's spheroid (§4), or the spheroid itself;
 *    diffuse VPLs the sphere at the VPL of radius R or the seed's §6 sphere (both other modes).
 *    Every bound is conservative, so the three give
 *    the same gather (tested); they differ only in how many VPLs a tile has to test.
 * 3. The culling reuses bk_slc's receiver tiles (16 items) and blocks (1024 items) and their
 *    boxes: every VPL's volume against every block box, then a tile's list cut from its block's.
 * 4. bk_vpl_gather: irradiance at receivers, a shadow ray (scene/tracer.h) per accepted
 *    VPL, contribution / p; or every VPL with weight 1 (brute force, the reference).
 *
 * Determinism: photons and lists depend only on the seed, the ξ, δ and the boxes; every
 * receiver sums its VPLs in index order: byte-identical at any thread count (tested). Nothing
 * is clamped: a receiver very close to a VPL receives I/l² (the VPL singularity), unbiased,
 * with the variance that brings (VPL.md). `lbk bake` uses the glossy VPLs where they pay
 * (bake/transport/culling_glue.c and gather.c, VPL.md "In the transport"). */
#ifndef BK_VPL_H
#define BK_VPL_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"
#include "bake/transport/slc.h"
#include "scene/tracer.h"

enum bk_vpl_kind { BK_VPL_DIFFUSE = 0, BK_VPL_GLOSSY = 1 };

/* How a VPL's range is bounded. */
enum bk_vpl_bound {
    BK_VPL_BOUND_ELLIPSOID = 0,  /* glossy: the seed's spheroid (§4, Eq. 13–15), diffuse: the §6
                                    sphere; the default */
    BK_VPL_BOUND_SPHERE_AT_VPL,  /* centre q, radius from the intensity's maximum: r/α (the NDF's
                                    maximum; seed §7 (a)), diffuse √(Φk/(πδξ)) */
    BK_VPL_BOUND_SPHERE_AROUND,  /* centre c, radius r_u: the sphere around the spheroid (b);
                                    diffuse: the §6 sphere */
    BK_VPL_BOUND_NONE            /* no culling: every VPL listed for every tile (tests) */
};

/* The surface a photon can land on, one per scene material. The lobes add:
 * f = kd/π + F_Schlick(F0, ω_i·h)·D·G2/(4|n·ω_i||n·ω_o|) (ggx.h). A lobe whose reflectance is
 * 0 makes no VPL. How a glTF material maps to this is the caller's choice (VPL.md). */
typedef struct bk_vpl_material {
    float kd[3];   /* diffuse reflectance, linear RGB */
    float f0[3];   /* GGX reflectance at normal incidence, linear RGB */
    float alpha;   /* GGX α (glTF roughness²), used in [BK_GGX_ALPHA_MIN, 1] */
} bk_vpl_material;

typedef struct bk_vpl {
    double pos[3];   /* the hit moved off the surface along n (shadow rays aim here) */
    double n[3];     /* unit geometric normal on the side the photon arrived from */
    double wi[3];    /* unit, from the hit back towards the light */
    double flux[3];  /* Φ, the photon's flux (W or lm, linear RGB) */
    double refl[3];  /* diffuse: kd; glossy: F0 */
    double alpha;    /* glossy: GGX α; diffuse: 0 */
    int kind;        /* enum bk_vpl_kind */
    uint32_t photon; /* the photon it came from */
} bk_vpl;

typedef struct bk_vpl_shoot_desc {
    const bk_scene *scene;
    const bk_tracer *tracer;           /* over scene */
    const bk_vpl_material *materials;  /* scene->material_count entries */
    uint64_t seed;
    size_t photons;                    /* from the light (at most BK_VPL_MAX_PHOTONS) */
    int threads;                       /* 0: every core */
    uint64_t key;                      /* names the photons' stream with the seed: give each
                                          light (and pass) its own, or their photons correlate */
    /* NULL: `materials` by the hit triangle's material. Else the surface at each photon hit
     * (the hit, and the hit point x): fills *m and returns 1, or returns 0 where the photon
     * makes no VPL (a textured or per-cell material, a surface the caller treats as black).
     * Must be deterministic and thread-safe. */
    int (*material_at)(void *user, const bk_hit *hit, const double x[3], bk_vpl_material *m);
    void *user;
} bk_vpl_shoot_desc;

/* Shooting holds 2 VPL slots (136 bytes each) per photon: 2^22 photons take 1.1 GB at most. */
#define BK_VPL_MAX_PHOTONS ((size_t)1 << 22)

/* Photons from `light` (a point light over the sphere, a spot light uniformly over its outer
 * cone), each carrying Φ = I(ω)·Ω/N (I with the light's cone and range window, Ω the sampled
 * solid angle), to their first hit. *out (free() it) holds the VPLs in photon order, the
 * diffuse before the glossy one of a photon. Directional lights: LBK_ERR_UNSUPPORTED_FEATURE. */
lbk_result bk_vpl_shoot(const bk_vpl_shoot_desc *desc, const bk_light *light, bk_vpl **out, size_t *count);

/* The luminance and RGB radiant intensity of v towards unit wo (0 below its horizon). */
double bk_vpl_intensity(const bk_vpl *v, const double wo[3], double rgb[3]);

/* One bounding volume: a sphere (ru == rv) or a spheroid with semi-axis ru along unit u and rv
 * across; `infinite` when ξ = 0 (the range is unbounded). */
typedef struct bk_vpl_volume {
    double c[3], u[3];
    double ru, rv;
    int infinite;
} bk_vpl_volume;

/* v's volume for ξ > 0, δ > 0 and the bound (radii inflated by 1e-6 relative). */
void bk_vpl_volume_of(const bk_vpl *v, double xi, double delta, int bound, bk_vpl_volume *out);
/* min over the box of |S(x − c)|², S stretching the volume into the unit sphere: ≤ 1 exactly
 * where the box meets the volume (0 inside; INFINITY for an empty box). Exact up to rounding:
 * the convex quadratic's minimum over the box, from its 27 faces. */
double bk_vpl_box_dist(const bk_vpl_volume *vol, const float box[6]);
int bk_vpl_volume_meets_box(const bk_vpl_volume *vol, const float box[6]);

typedef struct bk_vpl_draw bk_vpl_draw;

/* A draw over `tiles` (a bk_slc made for the receivers; its lights are not used): xi one per VPL
 * in [0, 1). The VPLs must outlive the draw. */
lbk_result bk_vpl_draw_create(const bk_vpl *vpls, size_t count, const double *xi, double delta, int bound,
                              const bk_slc *tiles, int threads, bk_vpl_draw **out);
void bk_vpl_draw_destroy(bk_vpl_draw *d);
/* The VPLs whose volume reaches item's tile into ids (room for `count`); returns how many. */
size_t bk_vpl_tile_list(const bk_vpl_draw *d, size_t item, uint32_t *ids);

/* A receiver: position, unit normal (zero: no cosine, irradiance at normal incidence) and the
 * origin of its shadow rays (the position moved off its surface, bk_offset_ray_origin). */
typedef struct bk_vpl_point {
    double p[3], n[3];
    float org[3];
} bk_vpl_point;

typedef struct bk_vpl_stats {
    uint64_t listed;    /* Σ over receivers of the VPLs their tile listed */
    uint64_t accepted;  /* of those, accepted (ξ < p): the rest are the culling's false positives */
    uint64_t rays;      /* shadow rays */
} bk_vpl_stats;

/* ξ of VPL vi in the draw, and the draw's δ. */
double bk_vpl_draw_xi(const bk_vpl_draw *d, uint32_t vi);
double bk_vpl_draw_delta(const bk_vpl_draw *d);

/* One VPL at one receiver, as bk_vpl_gather evaluates it: with culling (delta > 0) weight 1/p
 * where ξ < p = min(lum(I(ω_o))/(δl²), 1), else 0; then a shadow ray. Returns 1 (and *ray = 1)
 * when it contributes: rgb = weight·I(ω_o)/l² (the irradiance at normal incidence) arriving
 * from unit direction `to` (receiver → VPL); the receiver's cosine is the caller's (rgb·(n·to)).
 * *accepted = 1 when the draw accepted it (before the shadow ray). */
int bk_vpl_eval(const bk_vpl *v, double xi, double delta, const bk_tracer *tracer, const bk_vpl_point *q,
                double rgb[3], double to[3], int *accepted, int *ray);

/* Irradiance (3 per point) at the n points, which are the items of d's tiles (n ≤ the bk_slc's
 * items); d NULL: brute force, every VPL with weight 1. stats may be NULL. */
lbk_result bk_vpl_gather(const bk_vpl *vpls, size_t count, const bk_vpl_draw *d, const bk_tracer *tracer,
                         const bk_vpl_point *pts, size_t n, int threads, double *irr, bk_vpl_stats *stats);

#endif
