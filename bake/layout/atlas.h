/* Lightmap atlas: every lightmapped object's charts (uvgen.h) packed into pages.
 *
 * Layout rules (what the container's object table and the runtime rely on):
 * - Texel (x, y) of a page covers [x, x+1]×[y, y+1] in texel coordinates; its centre is
 *   (x+0.5, y+0.5). Normalised uv = texel coordinate / page size; u to the right, v down
 *   (row 0 at the top, as bk_image and glTF TEXCOORD).
 * - All charts of one object are on one page, inside the object's rectangle (x, y, w, h):
 *   the charts are first packed into an object-local rectangle, then object rectangles are
 *   packed into pages. So runtime uv = (rect.xy + local·rect.wh) / page size is possible.
 * - Each chart owns a block of its content size (ceil of its extent, at least 1×1) plus a
 *   margin of ceil(padding/2) texels on every side; blocks never overlap, so the content of
 *   two charts is at least `padding` (default 2) texels apart and every chart has a ring of
 *   margin texels of its own: bilinear filtering reads one texel around the content, and
 *   texels.h bakes exactly those texels (its conservative coverage), so padding 2 is enough
 *   for filtering never to read another chart.
 * - Page size: page_size (default 1024, rounded up to a multiple of 4; more if one object
 *   needs it, up to max_page_size). The last page is shrunk to the area it uses (both sides
 *   multiples of 4 for block compression), and repacked to be as small as it can be, so a
 *   small scene gets one small page.
 * - Packing: MaxRects, best short side fit (pack.h), rectangles sorted by longer side, then
 *   shorter side, then index; inside an object the packing tries a sweep of widths, each with
 *   the least height found by bisection, and keeps the smallest area (both sides rounded up to
 *   4 when the object is the only one, since its rectangle then becomes the page).
 *   Generated charts may be placed turned by a quarter (a rotation, never a mirror), and so may
 *   the rectangle of an object whose charts are all generated; the two turns compose
 *   (bk_atlas_chart.quarter_turns). Authored TEXCOORD_1 layouts are never turned: the runtime
 *   maps them linearly into the object's rectangle. Triangle corners (tri_uv, vertex_uv) are
 *   in final page coordinates, so the tangent frame (texels.h: T = dP/du on the page) turns
 *   with the chart. Deterministic: integer decisions on the input only, no threads.
 * - Density per object: density_override if > 0, else bk_object.texel_density if > 0, else
 *   default_density. If the summed object rectangles exceed texel_budget, the charts of lone
 *   triangles longer than a default page shrink first (down to a default page's side), then
 *   every density is scaled by the same factor (density_scale < 1, reported) until they fit.
 *   A triangle is never split (the engine draws the glTF's triangles): one longer than a
 *   max_page_size page gets a chart of its own at the density that fits (uvgen.h). An object
 *   too large for one max_page_size page first shrinks its large triangles' charts, then gets a
 *   lower density on its own (reported in its note). No page is wider or taller than
 *   max_page_size.
 * - Lightmap vertices: scene vertices are split where charts meet (and between objects), so
 *   each lightmap vertex has one uv; scene_tri_vertices maps every triangle of an atlas
 *   object to its three lightmap vertices (zero-area triangles too, with a uv of a vertex
 *   they share, or of the object's first texel). */
#ifndef BK_ATLAS_H
#define BK_ATLAS_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"
#include "bake/layout/uvgen.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bk_atlas_options {
    float default_density;   /* texels per metre; 0: 8 (the `fast` preset; `high` uses 16) */
    float density_override;  /* > 0: every object uses this (CLI --texel-density) */
    int page_size;           /* 0: 1024 */
    int max_page_size;       /* 0: 4096 */
    int padding;             /* empty texels between charts; 0: 2 */
    uint64_t texel_budget;   /* upper bound on Σ object rectangles, texels; 0: 16 Mi */
    bk_uv_options uv;        /* max_chart_texels 0: page_size − 2·margin */
    int block_align;         /* 1: chart blocks (chart + margins) sized to multiples of 4, so every
                                chart and object rectangle starts on a 4-texel boundary */
} bk_atlas_options;

typedef struct bk_atlas_page {
    int width, height;       /* multiples of 4 */
} bk_atlas_page;

typedef struct bk_atlas_object {
    uint32_t object;         /* scene object index */
    int32_t page;            /* -1: nothing to lightmap (every triangle has zero area) */
    int32_t x, y, w, h;      /* object rectangle in page texels (charts + margins) */
    int uv_source;           /* enum bk_uv_source */
    float requested_density; /* texels per metre asked for (override / object / default) */
    float density;           /* texels per metre used */
    uint32_t first_chart, chart_count;
    uint32_t degenerate_tris;
    char note[192];          /* uv1 rejection reason, density changes; "" */
    /* BK_UV_AUTHORED: page texel coordinate X = uv1_offset[0] + uv1_scale · u1, Y likewise (the
     * rule of spec/container.md §16.3 in real arithmetic); uv1_min/max: the uv1 bounding box */
    double uv1_scale, uv1_offset[2], uv1_min[2], uv1_max[2];
} bk_atlas_object;

typedef struct bk_atlas_chart {
    uint32_t slot;           /* index into bk_atlas.objects */
    int32_t page;
    int32_t x, y, w, h;      /* content rectangle in page texels: every corner of its triangles is
                                inside; baked texels reach one texel further (texels.h) */
    uint32_t first, count;   /* range in bk_atlas.tris */
    uint8_t quarter_turns;   /* 0-2: turned by the packer (inside its object, with its object) */
} bk_atlas_chart;

typedef struct bk_atlas {
    int padding;             /* the padding actually guaranteed (2 × margin) */
    int margin;              /* texels of each chart's own ring */
    float density_scale;     /* uniform factor applied for texel_budget (1: none) */
    uint64_t texels;         /* Σ page width × height */
    size_t page_count;
    bk_atlas_page *pages;
    size_t object_count;     /* lightmapped objects, in scene order */
    bk_atlas_object *objects;
    size_t scene_object_count;
    int32_t *object_slot;    /* per scene object: index into objects, or -1 */
    size_t chart_count;
    bk_atlas_chart *charts;
    size_t tri_count;        /* triangles with texels */
    uint32_t *tris;          /* scene triangle per entry, grouped by chart */
    uint32_t *tri_chart;     /* chart per entry */
    float *tri_uv;           /* 6 per entry: the corners in page texel coordinates */
    size_t scene_tri_count;
    int32_t *scene_tri_entry;/* per scene triangle: entry index, or -1 */
    size_t vertex_count;     /* lightmap vertices */
    uint32_t *vertex_source; /* scene vertex */
    uint32_t *vertex_slot;   /* atlas object */
    float *vertex_uv;        /* 2 per vertex: normalised page uv */
    uint32_t *scene_tri_vertices; /* 3 per scene triangle: lightmap vertex, UINT32_MAX if none */
    char note[192];          /* budget scaling message; "" */
} bk_atlas;

/* The density an object asks for before budget scaling (override, object extras, default). */
float bk_atlas_requested_density(const bk_scene *scene, uint32_t object, const bk_atlas_options *opt);

/* Builds the atlas for the objects with lightmapped[i] != 0 (object_count entries; NULL:
 * every object). opt may be NULL. On error *out is zeroed. Errors: LBK_ERR_INVALID_ARGUMENT,
 * LBK_ERR_OUT_OF_MEMORY, LBK_ERR_LIMIT (more than 2^31 texels or entries). */
lbk_result bk_atlas_build(const bk_scene *scene, const uint8_t *lightmapped, const bk_atlas_options *opt,
                          bk_atlas *out);
void bk_atlas_free(bk_atlas *atlas);

#ifdef __cplusplus
}
#endif
#endif
