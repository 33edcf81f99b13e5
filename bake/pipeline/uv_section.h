/* The LMUV section (spec/container.md §16) from the atlas: for every object the object table
 * lists as lightmapped, how an engine maps its vertices to lightmap coordinates — the authored
 * TEXCOORD_1 by scale and offset, or the generated charts as a vertex remap, an index buffer and
 * coordinates per glTF primitive. */
#ifndef BK_UV_SECTION_H
#define BK_UV_SECTION_H

#include <stddef.h>

#include "lbk/lbk.h"
#include "bake/layout/atlas.h"
#include "bake/layout/classify.h"
#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The object table's rule (bake.c build_objects): lightmapped when classified so and placed on
 * a page. */
int bk_uv_section_lightmapped(const bk_atlas *atlas, const bk_object_class *classes, size_t object);

/* Section bytes in *out (free with lbk_free), or *out = NULL and *size = 0 when no object is
 * lightmapped or the scene carries no glTF provenance (a scene not made by bk_import_gltf).
 * Coordinates are the atlas's page texel coordinates (atlas.tri_uv), so they are the ones the
 * texels were rasterised with. Errors: LBK_ERR_OUT_OF_MEMORY; LBK_ERR_INVALID_ARGUMENT when the
 * atlas and the scene's provenance disagree (an internal error). */
lbk_result bk_uv_section_build(const bk_scene *scene, const bk_atlas *atlas, const bk_object_class *classes,
                               void **out, size_t *size);

#ifdef __cplusplus
}
#endif
#endif
