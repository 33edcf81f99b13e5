/* The gap room: the Cornell box's light in the terms of the transport tests. A closed 2 m room
 * of albedo 0.725 (each face one quad: two triangles) with a 0.5 × 0.4 m double-sided emitter
 * (emission 8, albedo 0.999) hung 1 cm under the ceiling, off-centre so that no cache cell lines
 * up with it. Its upper side lights the 1 cm gap, which amplifies that light (~2.6× in the
 * middle) and leaks it into the room through the mouth at grazing angles; a radiosity cache of
 * cells far larger than the gap reads the gap's average there (TRANSPORT.md, gap cells).
 * Untextured, no punctual light: within the reference path tracer's model (ref_path.h).
 * Receivers: GSC_PER on the floor, on two walls (0.4–1.9 m up) and on the ceiling beside the
 * slit (10–30 cm from its mouth, facing down). Release with tsc_free. */
#ifndef GSC_GAP_SCENE_H
#define GSC_GAP_SCENE_H

#include "scene/scene.h"
#include "bake/transport/transport.h"

enum { GSC_PER = 16, GSC_GROUPS = 3, GSC_N = GSC_PER * GSC_GROUPS };
#define GSC_CELL 0.125f /* cache cells: the fast preset's texel, 12.5× the gap */

extern const char *const gsc_group_names[GSC_GROUPS]; /* floor, walls, ceiling by the slit */

void gsc_build(bk_scene *s);
/* GSC_N receivers, group g at [g·GSC_PER, (g + 1)·GSC_PER); positions and normals also as
 * 3 floats each into p and n (for the reference). */
void gsc_receivers(bk_receiver r[GSC_N], float p[3 * GSC_N], float n[3 * GSC_N]);

#endif
