/* The bias scene: a furnished room lit only by a uniform sky through a large window, built the
 * way levels are modelled (closed slabs that overlap at the corners, so parts of faces are
 * sealed inside other slabs), with indirect-dominated receivers (ceiling, the inner side of the
 * window wall, the underside of a thin table top), thin parts (a 4 cm table top on 5 cm legs,
 * a 3 cm shelf let into a wall, a 2 cm pole), a cavity sealed inside a wall (its faces must
 * bake to exactly 0) and an optional ground outside. Everything double sided (as Blender
 * exports), untextured, no punctual light: within the reference path tracer's model
 * (ref_path.h). Interior: x in [0, 5], y in [0, 4], z in [0, 2.8]; the window is in the y = 4
 * wall, x in [1, 4], z in [0.8, 2.3]. Release with bk_scene_free. */
#ifndef BSC_BIAS_SCENE_H
#define BSC_BIAS_SCENE_H

#include <stdint.h>

#include "scene/scene.h"

/* Surface groups for the per-surface numbers (bsc_group). */
enum bsc_group {
    BSC_OUTSIDE = 0,   /* exterior faces and faces inside slabs: not evaluated */
    BSC_FLOOR,
    BSC_CEILING,
    BSC_WINDOW_WALL,   /* inner side of the window wall */
    BSC_WALLS,         /* inner sides of the other three walls */
    BSC_TABLE_TOP,
    BSC_TABLE_UNDER,
    BSC_LEGS,          /* the table's legs */
    BSC_POLE,
    BSC_SHELF,
    BSC_SEALED,        /* the cavity's faces: exactly 0 */
    BSC_BURIED,        /* texels whose whole footprint lies inside a slab (set by the caller from
                          bsc_solid_depth of the texel centre): exactly 0 */
    BSC_GROUPS
};
extern const char *const bsc_group_name[BSC_GROUPS];

typedef struct bsc_options {
    int ground;        /* 1: a 35 m ground outside (albedo 0.25) */
    int detail;        /* subdivision multiplier of every face (1: ~4k triangles) */
} bsc_options;

void bsc_build(bk_scene *s, const bsc_options *opt);
/* How deep p lies inside the deepest closed slab (metres, > 0 inside, <= 0 outside all). */
double bsc_solid_depth(const float p[3]);
/* Group of a point with unit normal n on triangle tri of the bias scene. */
int bsc_group(const bk_scene *s, uint32_t tri, const float p[3], const float n[3]);

#endif
