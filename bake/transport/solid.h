/* Which triangles bound a closed solid: the transport's notion of "inside".
 *
 * Triangles are welded by exact vertex position and joined into edge-connected components. A
 * component is closed when every one of its edges is used equally often in both directions
 * (a watertight, consistently wound surface; several closed shells touching along an edge stay
 * closed). Zero-area triangles take no part: a mesh that needs them to close counts as open.
 *
 * Why: the back side of a closed solid can never be seen from outside it, so a ray that reaches
 * one started inside the solid (a point under a wall slab, in a sealed cavity's wall, in a table
 * leg let into the floor). Such a ray must see black (a receiver inside a solid is dark, as in
 * a path tracer), and a radiosity-cache sample at such a point must not count towards its
 * cell's radiance at all (the cell stands for the part of its surface that can be seen). Open
 * surfaces (a single plane, a quad of foliage) keep their back sides: double-sided materials
 * reflect there, one-sided ones are black, as before. Deterministic (sorts only). */
#ifndef BK_SOLID_H
#define BK_SOLID_H

#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"

/* closed[t] = 1 for every triangle of a closed component, else 0 (tri_count entries).
 * Errors: LBK_ERR_INVALID_ARGUMENT (NULL), LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_closed_triangles(const bk_scene *scene, uint8_t *closed);

#endif
