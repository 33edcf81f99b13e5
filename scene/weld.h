/* Vertices welded by exact position: which scene vertices are one point of the surface.
 *
 * glTF splits a vertex wherever its normal or UVs change (a cube's corner is three vertices),
 * so triangles that meet along an edge often share no index. Code that asks "which triangles
 * meet here" (closed solids in the transport, the surfaces that meet an edge texel's border in
 * the layout) compares welded ids instead. Exact equality only: nearly equal positions stay
 * apart, as a renderer's watertight intersection treats them. Deterministic (sorts only). */
#ifndef BK_WELD_H
#define BK_WELD_H

#include <stdint.h>

#include "scene/scene.h"

/* A welded id per vertex (vertex_count entries, malloc'd; free() it): the smallest index among
 * the vertices at exactly the same position. Non-finite positions keep their own id. NULL when
 * out of memory. */
uint32_t *bk_weld_vertices(const bk_scene *s);

#endif
