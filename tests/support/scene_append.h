/* The appending primitives the test scene builders (transport_scenes, uv_scenes, probe_scenes)
 * share: growing a bk_scene's arrays one element at a time, a vertex, a triangle, an object, the
 * box topology and the vertex bounds. Everything aborts on allocation failure (tests only);
 * release a scene with bk_scene_free. */
#ifndef SA_SCENE_APPEND_H
#define SA_SCENE_APPEND_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"

/* realloc to a power-of-two capacity >= count elements (at least 16); call before each append. */
void *sa_grow(void *p, size_t count, size_t elem);
/* Appends a vertex (position, normal; uv0 = uv1 = 0) and returns its index. */
uint32_t sa_vertex(bk_scene *s, const float p[3], const float n[3]);
/* Appends triangle (a, b, c) over existing vertices to the last object (there must be one). */
void sa_tri(bk_scene *s, uint32_t a, uint32_t b, uint32_t c, uint32_t material);
/* Appends an object named `name` (everything else zero, identity transform) whose triangles
 * start at the current triangle count; triangles added afterwards belong to it. */
bk_object *sa_object(bk_scene *s, const char *name);
/* The 8 corners of the box [mn, mx], indexed by bits x | y << 1 | z << 2. */
void sa_box_corners(const float mn[3], const float mx[3], float c[8][3]);
/* The box's 6 faces (-x, +x, -y, +y, -z, +z) as corner indices, counter-clockwise seen from
 * outside. */
extern const int sa_box_faces[6][4];
/* bounds_min/bounds_max over the vertices only (an empty scene keeps +inf / -inf). */
void sa_vertex_bounds(bk_scene *s);

#endif
