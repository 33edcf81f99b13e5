/* lbk render: a reference renderer of a baked level, written to show an engine programmer how to
 * use the data. Geometry comes from the glTF the level was baked from (scene/'s importer,
 * primary rays through Embree); every bit of lighting comes from the container through liblbk's
 * public runtime API only:
 *
 *   lightmapped objects  LMUV (lbk/lightmap_uv.h) gives each vertex its lightmap coordinate; the
 *                        page is sampled bilinearly and the AHD texel decoded for the shading
 *                        normal, the normal map's where the material has one (lbk/ahd.h, tangent
 *                        frame of spec §5.6; README.md "Normal maps");
 *   LLG objects          the object's local grid sampled at the hit point (lbk/llg.h), evaluated
 *                        along the interpolated bent normal and scaled by the interpolated
 *                        per-vertex self-visibility (vertex order: lbk_llg_vertex_map);
 *   dynamic objects      (representation "none", and the --probe-spheres test spheres) the global
 *                        grid (lbk/glg.h): SH9 at the hit point, irradiance along the normal;
 *   light sets, doors    weights through lbk_dls_apply (lbk/dls.h) before anything is sampled.
 *
 * Outgoing radiance of a Lambert surface: L = albedo · E / π + emission (nits, with E in lux);
 * a ray that leaves the level sees the sky radiance. Output is linear radiance.
 *
 * Files: level.c (load the container, match it to the scene, apply light sets: what an engine
 * does at load time), shade.c (per hit: what a pixel shader does), render.c (cameras, the pixel
 * loop, output), camera.c (glTF cameras), seams.c (chart-boundary mask for the bench). */
#ifndef LBK_TOOLS_RENDER_H
#define LBK_TOOLS_RENDER_H

#include <stddef.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */

typedef struct tl_camera {
    float from[3], at[3], up[3]; /* world space; up need not be orthogonal to the view */
    float yfov;                  /* vertical field of view, radians */
} tl_camera;

typedef struct tl_weight {
    const char *name; /* a DLS light set (--set) or a door (--door) */
    float weight;     /* light sets: 0 off .. 1 on; doors: openness ω, 0 closed .. 1 open */
} tl_weight;

typedef struct tl_sphere {
    float centre[3], radius; /* a white Lambert test sphere lit from the GLG */
} tl_sphere;

/* Zero-initialised = defaults, given in brackets. */
typedef struct tl_render_options {
    int width, height;        /* [160 × 120] */
    int samples;              /* primary rays per pixel per axis (samples² stratified, box filter) [2] */
    int threads;              /* [0: all cores] */
    tl_camera camera;         /* yfov 0: the default camera (the glTF's first, else a view of the level) */
    int sky_override;         /* 1: `sky` replaces the scene's sky for rays that leave the level */
    float sky[3];
    const tl_weight *sets;    /* light sets not named keep weight 1 (on, as in the scene) */
    size_t set_count;
    const tl_weight *doors;   /* doors not named stay closed (ω = 0, as in the scene's geometry) */
    size_t door_count;
    const tl_sphere *spheres;
    size_t sphere_count;
    int seams;                /* 1: also fill tl_image.seam (seams.c) */
    /* cap on the bytes the container's decoded sections may take (lbk_read_options
     * .max_decoded_bytes, `--max-memory`); 0: liblbk's default */
    uint64_t max_decoded_bytes;
} tl_render_options;

typedef struct tl_image {
    int width, height;
    float *rgb;     /* width × height × 3 radiance (nits), row 0 at the top */
    unsigned char *seam; /* with options.seams: bit 0: a chart boundary lies between this pixel and
                          * the one to its right, bit 1: it is flat (both sides on one plane);
                          * bits 2 and 3: the same towards the pixel below (seams.h); else NULL */
    unsigned char *lightmapped; /* with options.seams: 1 where the centre ray hit a lightmapped surface */
} tl_image;

typedef enum tl_render_status {
    TL_RENDER_OK = 0,
    TL_RENDER_USAGE,   /* a name in sets/doors/spheres/camera the level does not have */
    TL_RENDER_IO,      /* a file could not be read */
    TL_RENDER_INPUT,   /* the scene or container is unusable or they do not belong together */
    TL_RENDER_INTERNAL /* out of memory, Embree */
} tl_render_status;

/* Renders the level `lbk_path` baked from `scene_path`. Returns a tl_render_status; err says why
 * when it is not TL_RENDER_OK. Free the image with tl_image_free. */
int tl_render(const char *scene_path, const char *lbk_path, const tl_render_options *options, tl_image *out,
              char err[TL_ERR_LEN]);
void tl_image_free(tl_image *image);

/* Camera `index` of the glTF file (node transform, perspective yfov); TL_RENDER_USAGE when the file
 * has no such camera, TL_RENDER_IO / TL_RENDER_INPUT when it cannot be read. */
int tl_gltf_camera(const char *scene_path, int index, tl_camera *out, char err[TL_ERR_LEN]);

/* EXR (R, G, B float) and, when png_path is set, an sRGB preview with the p99 exposure of
 * tools/common/image_io.h. Returns 0, or -1 with err. */
int tl_image_write(const tl_image *image, const char *exr_path, const char *png_path, char err[TL_ERR_LEN]);

/* The seam mask of an image rendered with options.seams: channels "lightmapped" (0/1) and "seam"
 * (the bits of tl_image.seam as a float). Returns 0, or -1 with err. */
int tl_image_write_seams(const tl_image *image, const char *exr_path, char err[TL_ERR_LEN]);

#endif
