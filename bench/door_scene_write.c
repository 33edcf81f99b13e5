/* Writes the light-set and door level of lbk diff's reseed study (bench/diff_reseed.py, scene
 * "room_sets_doors"): tests/support/door_scenes.h's room with the north door tagged "north", the
 * two inside lamps in light sets "A" and "B", the 300 cd light outside the north doorway and a
 * 0.5-nit sky, at 4 texels per metre. Every class of lbk diff's noise verdict that comes from
 * light sets and doors (set_texels, set_probes, door_texels, door_probes) has items in it; the
 * study bakes it with --octahedral for the octp class.
 *
 * With "b" after the path, the study's second level "room_sets_doors_b" (held out until it failed;
 * the high-pass and extreme rates were then changed on it): a second door "outer" outside the
 * north one with the combination state north+outer, a 3-lux sun through the north doorway, a
 * 0.3-nit sky, 6 texels per metre.
 *
 * With "c", a third level written after the diff's high-pass was changed on what "b" showed, so
 * the one still held out: the two doors without the combination, the black light set "C", no
 * light outside, a 5-lux sun, a 0.8-nit sky, 5 texels per metre.
 *
 * usage: door_scene_write OUT.gltf [b|c]   (run from the repository root, or with $LBK_SCENES set) */
#include <stdio.h>
#include <string.h>

/* The generator lives with the tests; benches link the tools only, so take its source. */
#include "tests/support/door_scenes.c"

int main(int argc, char **argv)
{
    const int b = argc == 3 && strcmp(argv[2], "b") == 0, c = argc == 3 && strcmp(argv[2], "c") == 0;
    if (argc != 2 && !b && !c) {
        fprintf(stderr, "usage: %s OUT.gltf [b|c]\n", argv[0]);
        return 2;
    }
    ds_options o = {.door = DS_DOOR_TAGGED, .inside = DS_INSIDE_SETS, .outside_light = 1, .sky = 0.5f,
                    .texel_density = 4};
    if (b) o.outer_door = DS_DOOR_TAGGED, o.combinations = 1, o.sun = 3, o.sky = 0.3f, o.texel_density = 6;
    if (c) o.outer_door = DS_DOOR_TAGGED, o.zero_set = 1, o.outside_light = 0, o.sun = 5, o.sky = 0.8f, o.texel_density = 5;
    char err[512];
    if (ds_write_room_scene(DS_ROOM_GLB, argv[1], &o, err, sizeof err)) {
        fprintf(stderr, "door_scene_write: %s\n", err);
        return 1;
    }
    return 0;
}
