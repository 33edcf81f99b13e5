/* Whether an LMUV record (spec/container.md §16) describes the scene object it names: the one
 * check every reader that maps LMUV onto the glTF makes (lbk render, lbk export --gltf and so
 * lbk view), so that they accept and refuse the same containers. liblbk's validator cannot make
 * it: it needs the glTF, which liblbk never sees. */
#ifndef LBK_TOOLS_LMUV_MATCH_H
#define LBK_TOOLS_LMUV_MATCH_H

#include <stddef.h>

#include "lbk/lightmap_uv.h"
#include "scene/scene.h"
#include "tools/common/image_io.h" /* TL_ERR_LEN */

/* The scene primitives of object i: [*first, *first + *count). */
void tl_object_primitives(const bk_scene *s, size_t i, size_t *first, size_t *count);

/* Checks record r (of an LMUV view that liblbk opened) against scene object i: the glTF node;
 * for a GENERATED record its primitives (count, source primitive, source vertex count, triangle
 * count) and, at every triangle corner, that the new vertex the index buffer names comes from the
 * glTF vertex the scene has there (remap, in the glTF winding: §16.4). Returns 0, or `status`
 * with the reason in err. */
int tl_lmuv_match_object(const bk_scene *s, size_t i, const lbk_lmuv_view *lv, const lbk_lmuv_object *r, int status,
                         char err[TL_ERR_LEN]);

#endif
