/* GIBS-style octahedral probe volume (seed 003; spec/container.md §14, volume form): a regular
 * grid over the level, each probe classified and relocated (bk_octa_place), its 16 irradiance
 * texels gathered by the transport (bk_transport_options.octa_points) and its 12×12 depth
 * moments traced here (bk_octa_depth). Method and measurements: bake/probes/PROBES.md §OCTP. */
#ifndef BK_OCTA_BAKE_H
#define BK_OCTA_BAKE_H

#include <stddef.h>

#include "scene/scene.h"
#include "scene/tracer.h"
#include "lbk/octa.h"

/* Depth rays per texel: a 4×4 stratified grid over the texel's square of the octahedral map
 * (the texel's cone); distances are capped at the level's miss distance, what a miss records. */
#define BK_OCTA_DEPTH_SIDE 4
/* Classification rays per probe (spherical Fibonacci, fixed). */
#define BK_OCTA_CLASSIFY_RAYS 128
/* More than this fraction of back-face hits: the probe is inside closed geometry. */
#define BK_OCTA_INSIDE_FRACTION 0.25f
/* Probes per axis of a clip level (seed 003: 32³) and the most levels. */
#define BK_OCTA_CLIP 32u

typedef struct bk_octa_options {
    float spacing;      /* the finest level's, metres; 0: 1 (the baker passes min(GLG spacing,
                           largest extent / 8)) */
    uint32_t max_probes; /* per level; 0: 32768; the last level's spacing grows by 1.25 until it fits */
    uint32_t levels;    /* at most this many clip levels, 1 … 3; 0: 3 */
    uint32_t clip;      /* probes per axis of a level, 2 … 32; 0: 32 (seed 003's 32³ clip) */
    int has_centre;     /* 1: the clip levels are centred on `centre` (clamped into the bounds),
                           else on the bounds' centre */
    float centre[3];
} bk_octa_options;

typedef struct bk_octa_volume {
    lbk_octp_level levels[LBK_OCTP_MAX_LEVELS]; /* finest first, first_probe set, scene frame */
    uint32_t level_count;
    uint32_t count;              /* probes: Σ of the levels' dims products */
    float *positions;            /* 3 per probe: grid point + offset */
    lbk_octp_probe_info *info;   /* offset, state, back-face fraction, nearest hit */
} bk_octa_volume;

/* Clip levels over [bmin, bmax] (PROBES.md §OCTP): level l has spacing s·2^l (s = options'
 * spacing) and covers the bounds clipped to a box of `clip` spacings per axis around the centre,
 * max(2, ceil(extent/spacing)) probes per axis, centred in that box (so the outermost probes
 * stand half a spacing inside it). The first level that holds the whole bounds within `clip`
 * probes per axis is the last: a level smaller than clip × s gets one level, as before. The
 * last allowed level (options.levels) always covers the whole bounds, its spacing growing by
 * 1.25 until it fits. Miss distance per level min(255, its grid diagonal);
 * then per probe: classification rays from the grid point; inside (back-face fraction >
 * BK_OCTA_INSIDE_FRACTION) → moved through the nearest back face to 0.1·spacing beyond it,
 * too close to a front face (< 0.1·spacing) → moved away from it; offsets bounded by 0.45 ×
 * spacing per axis, at most 3 moves, re-classified after each; still inside → LBK_OCTP_INSIDE
 * (offset 0); no hit within a cell diagonal → LBK_OCTP_NO_NEARBY. Deterministic. */
lbk_result bk_octa_place(const bk_scene *scene, const bk_tracer *tracer, const float bmin[3], const float bmax[3],
                         const bk_octa_options *options, bk_octa_volume *out);
void bk_octa_volume_free(bk_octa_volume *v);
/* The level of probe i (levels are stored finest first, each a contiguous run of probes). */
uint32_t bk_octa_probe_level(const bk_octa_volume *v, uint32_t i);

/* 12×12 interior depth moments (mean, mean² of min(hit distance, miss)) from p, 16 rays per
 * texel (BK_OCTA_DEPTH_SIDE²). */
void bk_octa_depth(const bk_tracer *tracer, const float p[3], float miss, float depth[12 * 12][2]);

#endif
