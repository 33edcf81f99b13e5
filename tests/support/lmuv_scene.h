/* A small glTF level for the lightmap-coordinate tests (LMUV, spec/container.md §16): what real
 * levels do that a one-primitive mesh does not. Mesh 0 has four primitives — indexed triangles
 * with normals, points (ignored by the baker), indexed triangles without normals (flat shading:
 * split per corner) and a triangle strip with a restart — and is instanced twice, once through a
 * mirroring node (scale −1 in x). Mesh 1 is a quad with an authored TEXCOORD_1 that runs
 * backwards in u (a mirrored layout). Every node asks for a lightmap (lbk_lighting); the scene
 * has a uniform sky, so it bakes. Written as .gltf with the buffer as a data: URI. */
#ifndef LMUV_SCENE_H
#define LMUV_SCENE_H

#include <stddef.h>
#include <stdint.h>

enum { LMUV_SCENE_NODES = 3 };

/* Writes the level; 0 on success. */
int lmuv_scene_write(const char *path);

/* The triangles glTF primitive `primitive` (0..3) of mesh 0 defines, corners in glTF order as an
 * engine reads them (strip restarts dropped, odd strip triangles with their first two corners
 * swapped); NULL with *count = 0 for the points primitive. */
const uint32_t *lmuv_scene_triangles(uint32_t primitive, size_t *count);

#endif
