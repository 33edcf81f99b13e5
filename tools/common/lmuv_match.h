/* Whether an LMUV record (spec/container.md §16) describes the scene object it names: liblbk's
 * lbk_lmuv_object_check, the one check every reader that maps LMUV onto the glTF makes (lbk
 * render, lbk export --gltf and so lbk view, and an engine), fed from the imported scene, so that
 * they accept and refuse the same containers. lbk validate cannot make it: it needs the glTF. */
#ifndef LBK_TOOLS_LMUV_MATCH_H
#define LBK_TOOLS_LMUV_MATCH_H

#include <stddef.h>

#include "lbk/lightmap_uv.h"
#include "scene/scene.h"
#include "tools/common/image_io.h" /* TL_ERR_LEN */

/* The scene primitives of object i: [*first, *first + *count). */
void tl_object_primitives(const bk_scene *s, size_t i, size_t *first, size_t *count);

/* Checks record r (of an LMUV view that liblbk opened) against scene object i through
 * lbk_lmuv_object_check (lbk/lightmap_uv.h says what it checks): the object's primitives as the
 * glTF has them (corners in the glTF winding, NO_NORMAL where the importer split the vertices
 * per corner). Returns 0, or `status` with the reason in err. */
int tl_lmuv_match_object(const bk_scene *s, size_t i, const lbk_lmuv_view *lv, const lbk_lmuv_object *r, int status,
                         char err[TL_ERR_LEN]);

#endif
