/* The seed's guided door estimator (seed 001 §4.2), `lbk bake --door-method guided`: the light a
 * door lets through when open, S_O, computed at the base bake's receivers without full
 * transport runs. Method, approximations and measurements: bake/sets/SETS.md ("Guided door
 * estimator"). Stages:
 *   0. direct through the door (paths LD*PR): punctual lights whose shadow ray crosses the
 *      portal (noise-free), plus stratified samples on the portal (the door as an area light,
 *      more samples where it subtends a larger solid angle) whose rays continue beyond the
 *      doorway and read what the base bake knows there (sky, emission, the base's cached
 *      irradiance at the nearest texel);
 *   1. one bounce (LPDR): final-gather rays, uniform and guided towards the shadow-photon boxes,
 *      combined by the balance heuristic; at each hit the door-direct light is evaluated with
 *      the box's light list (direct light culling) plus one portal sample;
 *   2+. further bounces inside the scene (LPDD+R, which the seed leaves out): uniform gathers
 *      reading the previous bounce at the nearest texel, then a geometric tail.
 * Deterministic for any thread count (counter-based random numbers per receiver). */
#ifndef BK_DOOR_GUIDED_H
#define BK_DOOR_GUIDED_H

#include <stddef.h>
#include <stdint.h>

#include "bake/sets/door_sampling.h"
#include "bake/transport/transport.h"
#include "lbk/sh.h"

typedef struct bk_door_guided_inputs {
    const bk_scene *scene;            /* the scene WITHOUT the door's triangles (door open) */
    const bk_tracer *tracer;          /* over `scene` */
    bk_portal portal;                 /* the door's OBB as a portal (bk_portal_from_obb) */
    const bk_receiver *receivers;     /* the base bake's receivers */
    size_t receiver_count;
    size_t texel_receivers;           /* receivers [0, texel_receivers) are texels: the cache */
    const float *texel_size;          /* per texel receiver, metres: cache lookup radius */
    const uint8_t *not_cache;         /* per texel receiver, optional: 1 = never read it (door texels) */
    const lbk_sh9_rgb *base_radiance; /* the base bake per receiver: what lies beyond the door */
    uint64_t seed;
    int threads;                      /* 0: all cores */
    int samples;                      /* budget per receiver and stage; 0: 64 (bake/sets/SETS.md) */
    size_t photons;                   /* shadow photons; 0: 4096 */
    int use_sky;                      /* the base's sky shines through the door */
    int max_bounces;                  /* explicit bounces after the first; 0: 4, then the tail */
    const bk_guide_boxes *boxes;      /* optional: use these boxes instead of shooting photons */
    float *irradiance;                /* optional output, 3 per receiver: S_O's irradiance along texel
                                         normals (fluence for probes), estimated directly like
                                         bk_transport_output.irradiance */
} bk_door_guided_inputs;

typedef struct bk_door_guided_stats {
    size_t photons;          /* photons that landed */
    int boxes;
    int bounces;             /* explicit bounces (stage 1 is bounce 1) */
    double q;                /* energy ratio used for the tail */
    double seconds;
    uint64_t rays;           /* all rays traced (gather, shadow, portal) */
    double portal_samples;   /* mean portal samples per receiver that sees the door */
    double stage_energy[3];  /* Σ luminance of E over texels: stage 0, 1, 2+ (incl. tail) */
} bk_door_guided_stats;

/* S_O per receiver into radiance (SH9, required) and its direct part (optional: punctual and
 * portal rays that end on an emitter or the sky). boxes_out (optional) gets the photon boxes
 * (free with bk_guide_boxes_free). Errors: LBK_ERR_INVALID_ARGUMENT, LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_door_guided_run(const bk_door_guided_inputs *in, lbk_sh9_rgb *radiance, lbk_sh9_rgb *direct,
                              bk_door_guided_stats *stats, bk_guide_boxes *boxes_out);

#endif
