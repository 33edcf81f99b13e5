/* LLG probes fitted to their object's vertices (least-squares vertex baking, Kavan, Bargteil and
 * Sloan 2011). A runtime shades an LLG object's vertex with E = V · E_sh(b) of the probes
 * interpolated at the vertex (lbk/llg.h, spec §11); probes traced at their own lattice points
 * give that formula's value, not the vertex's irradiance, which near another object (a prop
 * stacked on a prop, a contact with the floor) is far off: the 2×2×2 lattices of room_with_doors'
 * spheres were 26–35 % off Cycles. The baker traces the irradiance at a subset of the object's
 * vertices ("targets", ordinary receivers with the vertex normal) and solves for the probes that
 * make the apply formula closest to it, regularised towards the traced probes so a probe that no
 * target constrains keeps its traced value. The fit is linear in (targets, traced probes), so a
 * light set's or door's contribution fitted alone adds up to the fit of the sum: toggled sets stay
 * consistent with the base. See bake/probes/PROBES.md §LLG fit. */
#ifndef BK_LLG_FIT_H
#define BK_LLG_FIT_H

#include <stddef.h>
#include <stdint.h>

#include "bake/probes/llg_place.h"
#include "scene/scene.h"
#include "scene/tracer.h"
#include "lbk/lbk.h"
#include "lbk/sh.h"

/* Grids with more probes than this keep their traced probes (the dense solve grows as probes³). */
#define BK_LLG_FIT_MAX_PROBES 64u

/* The targets of an LLG: up to `count` of the `usable` vertices (indices into llg->vertices,
 * ascending; NULL: all), evenly spaced, offset half a step from the first. Returns how many. */
size_t bk_llg_fit_targets(const bk_llg *llg, const uint32_t *usable, size_t usable_count, uint32_t *out, size_t count);
/* How many targets a grid gets from `usable` vertices: 0 when it is not fitted (too many probes,
 * or the scene has no normals). */
size_t bk_llg_fit_target_count(const bk_llg *llg, const bk_scene *scene, size_t usable);

typedef struct bk_llg_fit_stats {
    /* at the targets, over the grids fitted: Σ target luminance, Σ (model − target)² of the
     * traced probes and of the fitted ones, and the target count */
    double target_sum, traced_sq, fitted_sq;
    size_t targets;
} bk_llg_fit_stats;

/* Replaces the probes of `llg` (lattice order, dims product entries) by the fit to the targets'
 * irradiance (rgb, 3 per target; targets as bk_llg_fit_targets gave them). inside (per probe, or
 * NULL: none) marks probes inside geometry, whose traced value (black) is no prior: they take
 * their neighbours' through the smoothness term. stats may be NULL (else added to).
 * Deterministic. LBK_ERR_OUT_OF_MEMORY; a singular system keeps the traced probes. */
lbk_result bk_llg_fit(const bk_llg *llg, const bk_scene *scene, const uint32_t *targets, size_t target_count,
                      const float *irradiance, const uint8_t *inside, lbk_sh9_rgb *probes, bk_llg_fit_stats *stats);

/* Every grid's targets as receivers: targets of grid g are receivers [first + begin[g],
 * first + begin[g + 1]), vertex[k] the index into llgs[g].vertices of target k. */
typedef struct bk_llg_fit_plan {
    size_t first, count, grids;
    uint32_t *vertex;
    size_t *begin;
    uint8_t *inside; /* per LLG probe, grid after grid: 1 inside geometry */
} bk_llg_fit_plan;

/* Vertices inside other geometry (at least half of 16 hemisphere rays from just above them end
 * on back faces: the pole of a sphere that dips into the next, a foot sunk into the floor) are
 * no targets: no one sees them, and their black would pull the fit down around them. */
lbk_result bk_llg_fit_plan_build(const bk_llg *llgs, size_t grids, const bk_scene *scene, const bk_tracer *tracer,
                                 size_t first, bk_llg_fit_plan *out);
void bk_llg_fit_plan_free(bk_llg_fit_plan *plan);
/* The target receiver k's position and normal (the vertex's, in the scene frame). */
void bk_llg_fit_receiver(const bk_llg_fit_plan *plan, const bk_llg *llgs, const bk_scene *scene, size_t k,
                         float position[3], float normal[3]);
/* The part of the fit's residual Σ (model − target)² that the targets' own noise makes:
 * Σ_t σ_t² (1 − unknowns/targets) per grid (least squares absorbs a share unknowns/targets of
 * it), σ_t² the transport's variance of target t's luminance (variance per receiver). */
double bk_llg_fit_noise(const bk_llg_fit_plan *plan, const bk_llg *llgs, const float *variance);
/* The same for grid g alone (the terms bk_llg_fit_noise sums). */
double bk_llg_fit_noise_grid(const bk_llg_fit_plan *plan, const bk_llg *llgs, const float *variance, size_t g);
/* Fits every grid of one run: irradiance (3 per receiver) and radiance (per receiver) are the
 * run's outputs, the LLG probes of grid after grid from receiver llg_first. stats (NULL: none)
 * is added to; per_grid (NULL: none; plan->grids entries) gets each grid's own. */
lbk_result bk_llg_fit_run(const bk_llg_fit_plan *plan, const bk_llg *llgs, const bk_scene *scene,
                          const float *irradiance, lbk_sh9_rgb *radiance, size_t llg_first, bk_llg_fit_stats *stats,
                          bk_llg_fit_stats *per_grid);

#endif
