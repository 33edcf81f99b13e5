/* Dynamic light sets and doors in the bake. (Being written: until then a scene with sets or
 * doors is refused with a clear message rather than baked wrongly.) */
#include "bake/bake_sets.h"

#include <stdio.h>
#include <string.h>

#include "cli/cli.h"

int bk_set_bakes_prepare(bk_set_bakes *sets, const bk_scene *scene, bk_progress *progress, char *err,
                         size_t err_len)
{
    (void)progress;
    memset(sets, 0, sizeof *sets);
    for (size_t i = 0; i < scene->light_count; i++)
        if (scene->lights[i].light_set[0]) {
            snprintf(err, err_len, "light '%s' is in dynamic light set '%s': light sets are not supported by this build",
                     scene->lights[i].name, scene->lights[i].light_set);
            return LBK_EXIT_INPUT;
        }
    for (size_t i = 0; i < scene->object_count; i++)
        if (scene->objects[i].light_set[0] || scene->objects[i].door[0]) {
            snprintf(err, err_len, "object '%s' is a door or in a light set: not supported by this build",
                     scene->objects[i].name);
            return LBK_EXIT_INPUT;
        }
    return 0;
}

void bk_set_bakes_base_hooks(bk_set_bakes *sets, const bk_scene *scene, bk_transport_options *base)
{
    (void)sets, (void)scene, (void)base;
}

int bk_set_bakes_run(bk_set_bakes *sets, const bk_set_inputs *in, char *err, size_t err_len)
{
    (void)sets, (void)in, (void)err, (void)err_len;
    return 0;
}

lbk_result bk_set_bakes_sections(bk_set_bakes *sets, const bk_set_inputs *in, void **dls, size_t *dls_size,
                                 void **door, size_t *door_size)
{
    (void)sets, (void)in;
    *dls = *door = NULL;
    *dls_size = *door_size = 0;
    return LBK_OK;
}

void bk_set_bakes_free(bk_set_bakes *sets)
{
    memset(sets, 0, sizeof *sets);
}
