/* Where chart boundaries of the lightmaps cross the rendered view, for the bench's seam score
 * (bench/render/README.md): a pixel pair is on a seam when both centre rays hit lightmapped
 * surfaces that are geometrically continuous (each hit within two pixel footprints of the
 * other's triangle plane: not an occlusion edge) while the lightmap parameterisation is not
 * (another page, or the first triangle's lightmap mapping, extrapolated to the second hit,
 * misses its coordinate by more than one texel). A seam is "flat" when the two triangles' planes
 * agree within about 1°: there the true image is smooth and any jump is the lightmap's.
 * Internal to tools/render. */
#ifndef LBK_TOOLS_RENDER_SEAMS_H
#define LBK_TOOLS_RENDER_SEAMS_H

#include <stddef.h>

#include "tools/render/level.h"

typedef struct rl_gbuffer {
    rl_hit *hit;          /* the centre ray's hit per pixel */
    unsigned char *valid; /* 1 where it hit something */
} rl_gbuffer;

rl_gbuffer *rl_gbuffer_create(size_t pixels);
void rl_gbuffer_free(rl_gbuffer *g);
/* Fills out->seam (tl_image.seam's bits) and out->lightmapped. footprint: a pixel's size per metre of distance; from: the
 * camera position. Returns -1 when out of memory. */
int rl_seams(const rl_gbuffer *g, const rl_level *L, int width, int height, float footprint, const float from[3],
             tl_image *out);

#endif
