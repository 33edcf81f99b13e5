/* Scenes for the probe tests, built directly as bk_scene structs. Materials are single sided
 * unless asked (the GLG solid test depends on it). Release with psc_free. Aborts on OOM. */
#ifndef PSC_PROBE_SCENES_H
#define PSC_PROBE_SCENES_H

#include <stdint.h>

#include "scene/scene.h"

void psc_init(bk_scene *s);                 /* empty: one grey single-sided material */
void psc_free(bk_scene *s);
uint32_t psc_object(bk_scene *s, const char *name, int lighting);
void psc_tri(bk_scene *s, const float a[3], const float b[3], const float c[3]);
/* Quad p0..p3 counter-clockwise seen from the front, split into n×n pairs of triangles. */
void psc_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n);
/* Axis-aligned box [mn, mx]; faces face inward (a room) or outward (a solid block). */
void psc_box(bk_scene *s, const float mn[3], const float mx[3], int n, int inward);
/* UV sphere (stacks × slices), outward, smooth vertex normals = radial. Vertices are shared. */
void psc_sphere(bk_scene *s, const float centre[3], float radius, int stacks, int slices);
/* Rotates the vertices (and normals) of triangles [first_tri, end) about `pivot` by the unit
 * quaternion q (x, y, z, w). */
void psc_rotate_tris(bk_scene *s, uint32_t first_tri, const double q[4], const float pivot[3]);
void psc_update_bounds(bk_scene *s);

#endif
