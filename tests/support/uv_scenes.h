/* Scene builders for the lightmap UV, atlas, texel and classification tests: bk_scene structs
 * made directly in C (no import). Release with uvs_free. Aborts on allocation failure. */
#ifndef UVS_UV_SCENES_H
#define UVS_UV_SCENES_H

#include <stdint.h>

#include "scene/scene.h"

void uvs_init(bk_scene *s);                 /* empty scene, sky 0, one grey material (0) */
void uvs_free(bk_scene *s);
uint32_t uvs_material(bk_scene *s, float albedo, float emission);
/* Starts a new object; triangles added afterwards belong to it. */
uint32_t uvs_object(bk_scene *s, const char *name);
/* A vertex (normal given) and a triangle over existing vertices. */
uint32_t uvs_vertex(bk_scene *s, const float p[3], const float n[3]);
void uvs_tri_idx(bk_scene *s, uint32_t a, uint32_t b, uint32_t c, uint32_t material);
/* A flat triangle with its own vertices (face normal from the winding; zero if degenerate). */
void uvs_tri(bk_scene *s, const float a[3], const float b[3], const float c[3], uint32_t material);
/* Quad p0 p1 p2 p3 (counter-clockwise seen from the front) as an n×n grid with shared
 * vertices; uv1 of the grid vertex (i, j) is uv1_origin + (i/n, j/n)·uv1_size (p0 → p1 is
 * +u, p0 → p3 is +v). Returns the first vertex index. */
uint32_t uvs_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n,
                  uint32_t material, const float uv1_origin[2], float uv1_size);
/* Axis-aligned box [mn, mx], faces outward (inward = 0) or inward, each face an n×n grid. */
void uvs_box(bk_scene *s, const float mn[3], const float mx[3], int n, int inward, uint32_t material);
/* UV sphere with shared vertices and smooth normals: segments × rings, poles as fans, so
 * 2·segments·(rings−1) triangles (64 × 32 → 3,968, as in room_with_doors). */
void uvs_sphere(bk_scene *s, const float c[3], float r, int segments, int rings, uint32_t material);
void uvs_update_bounds(bk_scene *s);

#endif
