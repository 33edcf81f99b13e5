/* lbk export --gltf: the level as glTF 2.0 (GLB) with TEXCOORD_1 on every lightmapped primitive,
 * the lightmap pages as linear EXR and PNG previews beside it, and the GLG/LLG probes as data.
 * The container holds no geometry, so the scene it was baked from is read again (scene/'s
 * importer) and matched object by object (geometry hash, glTF node and primitives). Conventions:
 * tools/convert/README.md "glTF export". */
#ifndef LBK_TOOLS_GLTF_EXPORT_H
#define LBK_TOOLS_GLTF_EXPORT_H

#include "tools/common/bake_data.h"

typedef struct tl_gltf_options {
    const char *output;    /* OUT.glb; the sidecar images go beside it */
    const char *scene;     /* the .gltf/.glb the container was baked from */
    const char *container; /* the container's file name, recorded in the extras; NULL: none */
    int normal_texels;     /* 1: each normal map's texels also as an accessor in its material's
                              extras (lbk view's page, which loads no image; gltf_normals.h) */
} tl_gltf_options;

typedef struct tl_gltf_stats {
    uint32_t nodes, primitives, lightmapped, authored, generated, pages, exr_files, png_files;
    uint64_t triangles, vertices;
    float exposure; /* of the PNG previews (tools/convert/README.md "Previews") */
} tl_gltf_stats;

typedef enum tl_gltf_status {
    TL_GLTF_OK = 0,
    TL_GLTF_IO,       /* a file could not be read or written */
    TL_GLTF_INPUT,    /* the scene cannot be imported or does not match the container */
    TL_GLTF_INTERNAL  /* out of memory */
} tl_gltf_status;

/* Returns a tl_gltf_status; err says why when it is not TL_GLTF_OK. */
int tl_gltf_export(const tl_bake *bake, const tl_gltf_options *options, tl_gltf_stats *stats, char err[TL_ERR_LEN]);

#endif
