/* Two rooms that cannot see each other, as an in-memory scene (lbk/bake.h), for the noise-aware
 * diff tests: room A is an open-topped box lit only by the sky; room B a closed box lit only by
 * a point light. A change to the sky can only reach A's objects, a change to the lamp or to a
 * wall of B only B's objects — so a diff that flags the other room's objects is wrong. */
#ifndef DS_DIFF_SCENES_H
#define DS_DIFF_SCENES_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/bake.h"

typedef struct ds_variant {
    float sky;             /* uniform sky radiance (nits), grey; the base is 1 */
    float lamp_offset[3];  /* added to the lamp's position (metres) */
    float wall_albedo;     /* albedo of B's east wall ("B_wall_east"); the base is 0.7 */
    const char *lamp_set;  /* the lamp's lbk_light_set (NULL: static, in the base bake) */
} ds_variant;

#define DS_BASE ((ds_variant){1.0f, {0, 0, 0}, 0.7f, NULL})

/* Object names: A_floor, A_wall_west, A_wall_east, A_wall_north, A_wall_south, B_floor,
 * B_ceiling, B_wall_west, B_wall_east, B_wall_north, B_wall_south. */
#define DS_OBJECTS 11

/* The scene of a variant (everything it points to is owned by `store`). */
typedef struct ds_store {
    float *pos, *nrm;
    uint32_t *idx;
    lbk_bake_object objects[DS_OBJECTS];
    lbk_bake_material materials[DS_OBJECTS];
    lbk_bake_light light;
} ds_store;

void ds_build(const ds_variant *v, ds_store *store, lbk_bake_scene *scene);
void ds_free(ds_store *store);

/* 1 when object `name` is in room A. */
int ds_in_room_a(const char *name);

#endif
