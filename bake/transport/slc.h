/* Stochastic light culling (Tokuyoshi & Harada; seed 002 §3.1) for many punctual lights: every
 * light gets one uniform ξ per draw, which gives it the finite range √(I/(δξ)); inside it a point
 * accepts the light with p = min(E/δ, 1) (E: the luminance of the light's irradiance at normal
 * incidence there, ≤ I/l²) and divides its contribution by p, outside it the light is never
 * accepted. The estimate is unbiased for any δ > 0; its variance per draw is at most δ·E_total
 * at a point that receives E_total (bake/transport/SLC.md).
 *
 * The CPU form of tiled culling: items (receivers, cache cells) are grouped by index into tiles
 * of BK_SLC_TILE and blocks of BK_SLC_BLOCK, each with the bounding box of the points that will
 * be shaded in it. A draw tests every light's sphere against every block's box (in parallel,
 * each block's list in light order), and a tile's list is cut from its block's on demand, so a
 * point tests only the lights whose sphere reaches its tile.
 *
 * Determinism: the lists depend only on the boxes, the ξ and δ, never on thread count. */
#ifndef BK_SLC_H
#define BK_SLC_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"

#define BK_SLC_TILE 16
#define BK_SLC_BLOCK 1024

typedef struct bk_slc bk_slc;           /* the lights and the item boxes (one per run) */
typedef struct bk_slc_draw bk_slc_draw; /* one draw: ranges and block lists */

/* lights: `count` pointers (the run's selection, in the order the caller indexes them).
 * boxes: 6 floats per item (min xyz, max xyz) holding every point the caller will shade for it;
 * a box with min > max is empty (the item never shades). */
lbk_result bk_slc_create(const bk_light *const *lights, size_t count, const float *boxes, size_t items, bk_slc **out);
void bk_slc_destroy(bk_slc *s);

/* Lights that are never culled: directional ones (no position, no range). */
size_t bk_slc_always(const bk_slc *s, const uint32_t **ids);

/* A draw for the given ξ (one per light, in [0, 1)) and δ > 0, its block lists built on `threads`
 * threads. */
lbk_result bk_slc_draw_create(const bk_slc *s, const double *xi, double delta, int threads, bk_slc_draw **out);
void bk_slc_draw_destroy(bk_slc_draw *d);

/* The culled lights of `item`'s tile into ids (room for bk_slc_light_count entries); returns
 * their count. */
size_t bk_slc_tile_lights(const bk_slc_draw *d, size_t item, uint32_t *ids);
size_t bk_slc_light_count(const bk_slc *s);
/* The tiles and blocks themselves, for other culled sources over the same items (the VPLs of
 * bake/transport/vpl.c): item i lies in tile i / BK_SLC_TILE and block i / BK_SLC_BLOCK; a box
 * is 6 floats (min xyz, max xyz), min > max when empty. */
size_t bk_slc_item_count(const bk_slc *s);
size_t bk_slc_tile_count(const bk_slc *s);
size_t bk_slc_block_count(const bk_slc *s);
const float *bk_slc_tile_box(const bk_slc *s, size_t tile);
const float *bk_slc_block_box(const bk_slc *s, size_t block);
double bk_slc_draw_xi(const bk_slc_draw *d, uint32_t light);

/* The weight of a light whose irradiance luminance at the point is `lum`: 1/p when accepted
 * (ξ < p = min(lum/δ, 1)), else 0. */
static inline double bk_slc_weight(double lum, double delta, double xi)
{
    double p = lum / delta;
    if (!(p < 1)) return lum > 0 ? 1.0 : 0.0;
    return xi < p ? 1.0 / p : 0.0;
}

#endif
