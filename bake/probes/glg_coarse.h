/* The GLG density rule's coarse probe pass (bake/probes/PROBES.md §Density by playable space and
 * lighting): a cheap, deterministic transport run at the candidate points, read as irradiance
 * towards the six axis directions, with the transport's noise estimate. Pass bk_glg_coarse_lighting with a bk_glg_coarse as
 * bk_glg_options.lighting / lighting_user. */
#ifndef BK_GLG_COARSE_H
#define BK_GLG_COARSE_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"
#include "scene/tracer.h"
#include "lbk/lbk.h"

typedef struct bk_glg_coarse {    /* zero-initialised = defaults, except scene and tracer */
    const bk_scene *scene;
    const bk_tracer *tracer;
    uint64_t seed;                /* the bake's seed (the pass has its own stream: seed ^ a constant) */
    int threads;                  /* 0: all cores; the result does not depend on it */
    int samples;                  /* gather rays per point, both halves; 0: 256 */
    int max_cells;                /* radiosity cache cells; 0: 4096 (a coarse cache is enough) */
    int max_bounces;              /* explicit bounces before the transport's analytic tail; 0: 4 */
    /* filled by the pass: rays traced, seconds */
    uint64_t rays;
    double seconds;
} bk_glg_coarse;

/* bk_glg_lighting_fn over bk_transport_run (base lighting: static lights, emitters and sky). */
lbk_result bk_glg_coarse_lighting(void *coarse, const float *points, size_t n, float *out);

#endif
