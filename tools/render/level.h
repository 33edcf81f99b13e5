/* The renderer's level: the glTF scene (geometry, materials) and the container (lighting),
 * matched object by object, with the light-set and door weights applied. Internal to
 * tools/render. */
#ifndef LBK_TOOLS_RENDER_LEVEL_H
#define LBK_TOOLS_RENDER_LEVEL_H

#include <stdint.h>

#include "scene/scene.h"
#include "scene/tracer.h"
#include "tools/common/bake_data.h"
#include "tools/render/render.h"

typedef struct rl_level {
    bk_scene scene;          /* world space, as scene/'s importer gives it */
    tl_bake bake;            /* the container with a view on every section */
    bk_tracer *tracer;       /* Embree over the scene's triangles */
    lbk_object *objects;     /* the OBJS record of every scene object (same order) */
    float *corner_coord;     /* 6 per triangle: lightmap coordinate (X, Y) of its corners (LMUV) */
    uint32_t *vertex_record; /* per scene vertex: its LLG vertex record within its grid, or
                                LBK_LLG_NO_VERTEX */
    unsigned char *hidden;   /* per object: not drawn (a door that is fully open) */
    /* lighting after lbk_dls_apply: texels over the global texel index, and the section views
     * with their probe pointers on the applied probes */
    uint32_t *texel_ez;      /* plane 0 word (R11G11B10F) of every texel */
    uint8_t *texel_rgba;     /* plane 1, 4 bytes per texel */
    lbk_ahd_texel_f *texel_f;/* a block-compressed pack (spec §9.2) without DLS: every texel as decoded
                                (lbk/bc.h, astcenc), sampled instead of texel_ez/rgba; else NULL */
    lbk_lmap_page *pages;    /* width, height and first_texel of every page (the plane pointers only
                                on 1.0 pages) */
    lbk_glg_view glg;
    lbk_llg_view llg;
    int has_glg, has_llg;
    uint8_t *applied_glg, *applied_llg; /* owned probe arrays when the level has a DLS */
    float sky[3];            /* uniform sky radiance (when scene.sky_image < 0) */
} rl_level;

/* Loads, matches and applies the weights of o. Returns a tl_render_status with err. */
int rl_level_load(const char *scene_path, const char *lbk_path, const tl_render_options *o, rl_level *L,
                  char err[TL_ERR_LEN]);
void rl_level_free(rl_level *L);

/* One primary-ray hit. */
typedef struct rl_hit {
    int sphere;      /* index of the test sphere hit, or -1: the triangle `tri` */
    uint32_t tri;
    float u, v;      /* barycentrics of corners 1 and 2 */
    int front;       /* the ray arrived on the triangle's front (counter-clockwise) side */
    float p[3];      /* world position */
    float dir[3];    /* the ray's unit direction */
} rl_hit;

/* Outgoing radiance towards the camera at a hit (shade.c). hint: the caller's GLG walk hint. */
void rl_shade(const rl_level *L, const tl_render_options *o, const rl_hit *h, uint32_t *hint, float rgb[3]);
/* Radiance of the sky in direction d (unit). */
void rl_sky(const rl_level *L, const float d[3], float rgb[3]);
/* The lightmap coordinate of a hit on a lightmapped triangle (shade.c); 0 when it is not one. */
int rl_hit_coord(const rl_level *L, const rl_hit *h, uint32_t *page, float coord[2]);

#endif
