/* glTF 2.0 import: a .gltf or .glb file (untrusted) → bk_scene (see scene.h, spec/authoring.md). */
#ifndef BK_IMPORT_H
#define BK_IMPORT_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What the import dropped or changed without failing; all zero for a clean file. */
typedef struct bk_import_report {
    size_t ignored_primitives;     /* points and lines (the baker only uses triangles) */
    size_t skipped_nodes;          /* mesh nodes with a singular transform (zero scale) */
    size_t downsampled_images;     /* textures reduced to max_texture_size */
    size_t ignored_textures;       /* textures using TEXCOORD_1 or an undecodable format */
    size_t repaired_normals;       /* zero-length normals replaced by the face normal */
    size_t warnings;               /* every call of the warn callback */
} bk_import_report;

/* Zero-initialised = defaults (given in brackets). */
typedef struct bk_import_options {
    int skip_textures;             /* 1: decode no texture; materials use their factors only */
    size_t max_triangles;          /* cap on imported triangles [16 Mi]; vertices are capped at
                                      3 × max_triangles */
    size_t max_file_bytes;         /* cap on any single file read: .gltf/.glb/.bin/image/EXR [1 GiB] */
    size_t max_json_bytes;         /* cap on the JSON text (.gltf, or the GLB JSON chunk); parsed
                                      JSON takes ~20-50× its size in memory [64 MiB] */
    size_t max_image_bytes;        /* cap on the float RGBA kept in scene->images [512 MiB] */
    int max_texture_size;          /* textures are box-filtered down to at most this side [1024] */
    int max_sky_size;              /* the sky EXR is box-filtered down to at most this width [2048] */
    size_t max_image_pixels;       /* a texture or EXR larger than this (before filtering) is an
                                      error, so a forged header cannot make us allocate [64 Mi] */
    /* Resources (buffers, images, the lbk_sky EXR) must resolve, symlinks included, inside the
     * scene file's folder; this names one more folder they may come from. NULL: none. */
    const char *allow_outside;
    /* 1: positions relative to a level origin chosen in double precision (bk_scene.origin; what
     * the bake uses, so a 1 mm object 1e5 m away keeps its shape); 0: world positions as floats
     * (origin 0), what tools comparing with world-space data want. */
    int recentre;
    /* 1: also read each material's normalTexture (bk_material.normal_tex1, normal_scale; decoded
     * as linear data) and give the scene tangents (bk_scene.tangents: TANGENT where a primitive
     * has it with NORMAL, else derived). For readers that shade with normal maps (lbk render,
     * lbk export --gltf); the bake leaves it 0, so its import and source hash are unchanged.
     * Normal textures are decoded even with skip_textures (which then skips the others). */
    int normal_maps;
    /* Optional: receives each warning (one line, no newline). */
    void (*warn)(void *user, const char *message);
    void *warn_user;
    /* Optional: filled with counts of what the import dropped or changed. */
    bk_import_report *report;
} bk_import_options;

/* Reads `path` (.gltf or .glb, by content) into `out` (which is zeroed first; on error it is left
 * empty, with nothing to free). Returns 0 on success; otherwise non-zero with a message in `err`
 * that names the file and the node, mesh/primitive, accessor, material, light or extras key at
 * fault. `opt` may be NULL. Not thread-safe with respect to `out` only; no global state. */
int bk_import_gltf(const char *path, const bk_import_options *opt, bk_scene *out,
                   char *err, size_t err_len);

#ifdef __cplusplus
}
#endif
#endif
