/* Scene builders for the transport and tracer tests: bk_scene structs made directly in C (no
 * import). Release with tsc_free (bk_scene_free). Every function aborts on allocation failure
 * (tests only). */
#ifndef TSC_TRANSPORT_SCENES_H
#define TSC_TRANSPORT_SCENES_H

#include <stdint.h>

#include "scene/scene.h"
#include "bake/transport/transport.h"

void tsc_init(bk_scene *s);                /* empty scene, sky 0, one object "tsc" */
void tsc_free(bk_scene *s);
/* A material (double sided, untextured); returns its index. */
uint32_t tsc_material(bk_scene *s, float ar, float ag, float ab, float er, float eg, float eb);
/* Starts a new object; later triangles belong to it. Returns its index. */
uint32_t tsc_object(bk_scene *s, const char *name, const char *light_set, const char *door);
/* Triangle (a, b, c), front face counter-clockwise. */
void tsc_tri(bk_scene *s, const float a[3], const float b[3], const float c[3], uint32_t material);
/* Quad p0 p1 p2 p3 (counter-clockwise seen from the front), split into n×n sub-quads. */
void tsc_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3],
              int n, uint32_t material);
/* Axis-aligned box [mn, mx], faces facing inward (inward = 1) or outward, each n×n quads. */
void tsc_box(bk_scene *s, const float mn[3], const float mx[3], int n, int inward, uint32_t material);
uint32_t tsc_point_light(bk_scene *s, const float pos[3], float r, float g, float b, float range);
uint32_t tsc_spot_light(bk_scene *s, const float pos[3], const float dir[3], float intensity, float inner,
                        float outer);
uint32_t tsc_dir_light(bk_scene *s, const float dir[3], float lux);
/* p -> p·scale + offset for vertices and light positions; ranges scale too. Recomputes bounds. */
void tsc_transform(bk_scene *s, double scale, const double offset[3]);
void tsc_update_bounds(bk_scene *s);
/* Rotates vertices, vertex normals and light positions/directions about the origin by the
 * Euler angles (radians, x then y then z). */
void tsc_rotate(bk_scene *s, double ax, double ay, double az);

/* Transport options of a fixed schedule: exactly `passes` passes (16 samples in the first, each
 * doubling; no error target), 2 threads, a 512-cell cache, the given seed. */
bk_transport_options tsc_fixed_passes(int passes, uint64_t seed);

/* A closed 2 m room (x and z in [-1, 1], y in [0, 2], each face one quad, grey `wall`) with an
 * emitter over [x0, x1] × [z0, z1] hung 1 cm under the ceiling, facing down and double-sided (its
 * upper side lights the gap): albedo `lamp`, radiance `le`. The Cornell box's light. */
void tsc_ceiling_lamp_room(bk_scene *s, float wall, float lamp, float le, float x0, float x1, float z0, float z1);
/* The one test_bias and test_path_check share: grey 0.5, a 1 × 1 m lamp of radiance 4 and albedo
 * 0.5 over [-0.35, 0.65]². */
#define TSC_LAMP_ROOM_RECEIVERS 24
void tsc_lamp_room(bk_scene *s);
/* Its receivers: 16 on the floor (a 4 × 4 grid at 0.5 m), then 8 up the wall x = -1. */
void tsc_lamp_room_receivers(bk_receiver r[TSC_LAMP_ROOM_RECEIVERS]);

#endif
