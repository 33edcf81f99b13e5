/* An in-memory scene description (lbk_bake_scene, lbk/bake.h) → bk_scene, by the glTF
 * importer's rules (scene/gltf_*.cc): flat shading where there are no normals, base
 * colours clamped to 1, lights as KHR_lights_punctual gives them, identity node frames. The
 * description is untrusted: every index, count and number is checked. */
#ifndef BK_SCENE_DESC_H
#define BK_SCENE_DESC_H

#include <stddef.h>

#include "scene/scene.h"
#include "bake/util/events.h"
#include "lbk/bake.h"

/* Fills `out` (zeroed first; on failure left empty). Warnings go to ev. Returns LBK_OK,
 * LBK_ERR_INVALID_ARGUMENT (a count without its array, a bad size field), LBK_ERR_BAD_INPUT (a
 * rule of the description broken) with the reason in err, or LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_scene_from_desc(const lbk_bake_scene *desc, const bk_events *ev, bk_scene *out, char *err,
                              size_t err_len);

#endif
