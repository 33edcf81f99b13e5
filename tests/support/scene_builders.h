/* Small bk_scene structs built directly in C (no glTF), for baker tests. Everything is
 * malloc'ed exactly as bk_import_gltf does, so bk_scene_free releases it. Builders abort on
 * allocation failure (tests only). All materials are double sided and untextured; every scene
 * has one object per call of the builder. */
#ifndef SB_SCENE_BUILDERS_H
#define SB_SCENE_BUILDERS_H

#include "scene/scene.h"

/* Closed axis-aligned cube [-size/2, size/2]³, faces facing inward, each face split into n×n
 * quads (2·n² triangles), one material with the given albedo (grey) and emission (grey
 * radiance): the furnace scene. */
void sb_closed_box(bk_scene *s, float size, float albedo, float emission, int n);

/* A square floor [-half, half]² at y = 0 facing +y (albedo grey), n×n quads, and one point
 * light at (0, height, 0) with intensity `candela` (white). */
void sb_plane_point_light(bk_scene *s, float half, float height, float candela, float albedo, int n);

/* Appends a quad p0 p1 p2 p3 (counter-clockwise seen from the front) split into n×n quads to
 * object `object` with material `material`; vertex normals are the face normal. Usable on any
 * scene built here (it grows the arrays). */
void sb_add_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n,
                 uint32_t material, uint32_t object);

#endif
