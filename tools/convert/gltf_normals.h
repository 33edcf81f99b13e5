/* Normal maps in lbk export --gltf (tools/convert/README.md "glTF export"): each material's
 * normalTexture as a PNG beside the GLB (the texels the importer decoded: linear data, 8 bits),
 * with its scale, and TANGENT on the primitives that use it (bk_scene.tangents: the glTF's, or
 * derived as spec/authoring.md "Normal maps" says), so a loader shades them as lbk render does.
 * With `texels`, the material's extras also carry the texels as an accessor (lbk view's page reads
 * them synchronously: it loads no image). */
#ifndef LBK_TOOLS_GLTF_NORMALS_H
#define LBK_TOOLS_GLTF_NORMALS_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"
#include "tools/convert/glb.h"

typedef struct tl_gltf_normals {
    const bk_scene *s;
    int *texture;           /* per source material: its normal map's glTF texture, -1 none yet */
    uint32_t *order;        /* source materials given a normal texture, in texture order */
    uint32_t count;
    uint32_t first_texture; /* textures before these (the lightmap pages') */
    int texels;             /* also the texels as an accessor in the material's extras */
} tl_gltf_normals;

/* Returns -1 when out of memory. */
int tl_gltf_normals_init(tl_gltf_normals *n, const bk_scene *s, uint32_t first_texture, int texels);
void tl_gltf_normals_free(tl_gltf_normals *n);
/* 1 when source material mi has a normal map the scene can shade (a texture and tangents). */
int tl_gltf_normals_has(const tl_gltf_normals *n, uint32_t mi);
/* mat (a glTF material of source material mi) gets normalTexture; with texels, extras.lbk
 * (which must exist) gets normal_map {width, height, scale, texels: accessor of RGB bytes, row 0
 * the image's top}. No-op without a normal map. */
void tl_gltf_normals_material(tl_gltf_normals *n, tl_glb *g, cJSON *mat, uint32_t mi);
/* attributes gets TANGENT (VEC4, the scene vertices sv[0..nv)) when mi has a normal map. Returns
 * -1 when out of memory. */
int tl_gltf_normals_tangents(const tl_gltf_normals *n, tl_glb *g, cJSON *attributes, uint32_t mi, const uint32_t *sv,
                             size_t nv);
/* The images (DIR/STEM.normal_NNN.png), textures and their sampler (linear, mipmapped, repeat),
 * after the pages' textures. Returns 0, or -1 with err (*png_files counts what was written). */
int tl_gltf_normals_write(const tl_gltf_normals *n, cJSON *root, const char *dir, const char *stem, uint32_t *png_files,
                          char err[TL_ERR_LEN]);

#endif
