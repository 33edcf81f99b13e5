/* The light-set and door test level, generated from the shared room_with_doors scene
 * (scenes/room_with_doors/room.glb, MIT, Godot demo projects): the room mesh only
 * (232 triangles, 10 × 5 × 10 m, a doorway in each wall; the 16 spheres are left out to keep
 * bakes fast), plus, by option:
 *   - a closed door panel (a thin box, grey 0.8 like the walls) in the north doorway (z = −5),
 *     tagged extras lbk_door "north" or plain geometry;
 *   - a point light outside that doorway at (0, 2, −8), 300 cd: it reaches the room only
 *     through that doorway;
 *   - two point lights inside at (∓2.5, 3.5, 2.5), 20 cd, in light sets "A" and "B" or static;
 *   - a light in set "C" with intensity 0;
 *   - a uniform sky (scene extras lbk_sky) that enters through every open doorway;
 *   - a second, free-standing panel "outer" outside the north door, a sun through the north
 *     doorway, and the lbk_combinations key (see the fields below).
 * Written as a self-contained .gltf (buffer as a base64 data: URI). Used by tests/bake/test_sets.c
 * and bench/bench_sets.c. */
#ifndef DS_DOOR_SCENES_H
#define DS_DOOR_SCENES_H

#include <stddef.h>

/* room_with_doors/room.glb in the scenes directory (tests/support/scenes_dir.h: scenes/ of the
 * repository, or $LBK_SCENES). ds_write_room_scene fails naming the file when it is missing. */
const char *ds_room_glb(void);
#define DS_ROOM_GLB ds_room_glb()

enum ds_door { DS_NO_DOOR = 0, DS_DOOR_TAGGED, DS_DOOR_PLAIN };
enum ds_inside { DS_INSIDE_NONE = 0, DS_INSIDE_SETS, DS_INSIDE_STATIC };

typedef struct ds_options {
    int door;              /* enum ds_door */
    int inside;            /* enum ds_inside: lights A and B */
    int zero_set;          /* 1: a black light in set "C" */
    int outside_light;     /* 1: the light outside the north doorway */
    float sky;             /* uniform sky radiance (nits); 0: none */
    float texel_density;   /* lbk_texel_density on room and door; 0: not written */
    /* appended for the guided door estimator and combination states (tests/bake/test_doors.c): */
    int outer_door;        /* enum ds_door: a second panel "outer", free-standing 1.5 m outside the
                              north door, between it and the outside light (it shadows the doorway) */
    int combinations;      /* 1: scene extras lbk_combinations [["north", "outer"]] */
    float sun;             /* lux of a directional light travelling (0, −1, 1)/√2: in through the north
                              doorway onto the floor (x ±1.25, z from −5 to about −1.7); 0: none */
} ds_options;

/* Writes the level to out_path. Returns 0, else non-zero with a message in err. */
int ds_write_room_scene(const char *room_glb, const char *out_path, const ds_options *o, char *err, size_t err_len);

#endif
