/* Lightmap parametrisation of one object: its triangles grouped into charts, each with 2D
 * coordinates in texels (x to the right, y down, like the atlas pages: row 0 at the top).
 *
 * Authored: where the object has TEXCOORD_1 (bk_object.has_uv1) the layout is kept as one
 * chart and only scaled uniformly so that its texel density matches the requested density
 * on average (s = density · sqrt(world area / uv area) texels per uv unit); its bounding box
 * becomes the chart, up to the larger of max_chart_texels and max_triangle_texels a side (a
 * lower density beyond, noted). The author's own island spacing is kept as is. It is rejected, with the
 * reason in bk_uv_object.note, and the layout generated instead, when: a uv1 coordinate is
 * not finite or lies outside [0, 1]; the uv area is zero; triangles with (almost) zero uv
 * area cover more than 1% of the object's surface; or triangles overlap at the target
 * resolution (more than 0.2% of the covered texel centres claimed twice).
 *
 * Generated: triangles are welded by exact position, grown into charts over shared edges
 * (seeded from the largest triangle not yet taken; a neighbour joins while its normal is
 * within the cone angle of both the seed normal and the chart's running area-weighted
 * normal), each chart is projected onto the plane of its area-weighted normal, scaled by
 * sqrt(world area / projected area) so the chart as a whole keeps density texels per metre,
 * rotated to its minimum-area bounding rectangle (then 90° so that width >= height) and
 * moved to the origin. A chart whose projection overlaps itself at texel resolution, or
 * whose longer side exceeds max_chart_texels, is split at the median of its triangles along
 * its longer side (then into connected pieces) until it fits. A single triangle longer than
 * max_chart_texels keeps its chart at the object's density up to max_triangle_texels (the
 * atlas passes a maximum page's side, so the page grows to hold it); a triangle longer still
 * gets a chart of its own at the density that fits (reported in note): the rest of the object
 * keeps its density, so one large triangle never lowers a whole object's. Finally small
 * charts (at most 16 texels of content, or one texel thin) are unfolded onto a neighbour
 * across their longest shared edge when that makes the pair's blocks smaller (chart_merge.h):
 * small objects no longer shatter into 1–3-texel charts, each with its own margin ring.
 *
 * Degenerate triangles (zero or non-finite area, indices out of range) get no chart: they
 * are counted in degenerate_count and receive no texels.
 *
 * Everything is deterministic: ties are broken by triangle index, no hashing of pointers. */
#ifndef BK_UVGEN_H
#define BK_UVGEN_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

enum bk_uv_source {
    BK_UV_EMPTY = 0,     /* no triangle with area: nothing to lightmap */
    BK_UV_AUTHORED,      /* TEXCOORD_1 kept */
    BK_UV_GENERATED      /* generated (object had no uv1, or uv1 was rejected: see note) */
};

typedef struct bk_uv_options {
    float cone_degrees;      /* chart normal cone half-angle; 0: 40 */
    int max_chart_texels;    /* longest chart side; 0: 1020 (a 1024 page minus padding) */
    int max_triangle_texels; /* longest side of a one-triangle chart (a triangle cannot be split);
                                longer ones are scaled down to it; 0: max_chart_texels */
} bk_uv_options;

typedef struct bk_uv_chart {
    uint32_t first, count;   /* range in bk_uv_object.tris */
    float width, height;     /* extent of the chart's coordinates: all lie in [0,width]×[0,height] */
} bk_uv_chart;

typedef struct bk_uv_object {
    uint32_t object;         /* scene object index */
    int source;              /* enum bk_uv_source */
    char note[192];          /* why uv1 was rejected and/or why the density was lowered; "" */
    float density;           /* texels per metre actually used */
    size_t chart_count;
    bk_uv_chart *charts;
    size_t tri_count;        /* triangles that have a chart */
    uint32_t *tris;          /* scene triangle indices, grouped by chart */
    float *uv;               /* 6 per entry of tris: the 3 corners' chart coordinates, texels */
    size_t degenerate_count; /* the object's triangles without a chart */
    size_t big_tris;         /* one-triangle charts that at the object's density are longer than
                                max_chart_texels or max_triangle_texels (generated) */
    size_t scaled_tris;      /* of those, longer than max_triangle_texels: scaled down to it */
    float scaled_density;    /* the lowest density among the scaled ones (scaled_tris > 0) */
    /* BK_UV_AUTHORED: the one chart's coordinates are (uv1 − uv1_min) · uv1_scale texels, per
     * axis; uv1_min/uv1_max bound the uv1 of the triangles that have area (0 otherwise) */
    double uv1_scale, uv1_min[2], uv1_max[2];
} bk_uv_object;

/* Charts for scene object `object` at `density` texels per metre (> 0, finite). opt may be
 * NULL (defaults). On success *out owns its arrays (free with bk_uv_object_free); on error
 * *out is zeroed. Errors: LBK_ERR_INVALID_ARGUMENT (bad object index, triangle range outside
 * the scene, density <= 0), LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_uvgen_object(const bk_scene *scene, uint32_t object, float density,
                           const bk_uv_options *opt, bk_uv_object *out);
void bk_uv_object_free(bk_uv_object *uvo);

/* Counts texel centres of a texel grid that lie inside more than one triangle, triangles
 * given as 6 floats each (texel coordinates), with a top-left fill rule so that triangles
 * sharing an edge never both claim a centre on it. covered (optional) receives the number of
 * centres inside at least one triangle. Triangles outside [0,w]×[0,h] are clipped to it.
 * Returns (size_t)-1 on allocation failure. Used for the uv1 and chart overlap checks. */
size_t bk_uv_count_overlaps(const float *uv, size_t tri_count, int width, int height,
                            size_t *covered);

#ifdef __cplusplus
}
#endif
#endif
