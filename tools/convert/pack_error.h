/* The error a pack's lightmap adds to the bake it was made from: both containers decoded (block
 * pages through the decoders of lbk/bc.h and astcenc, tools/common/lmap_decode.h) and compared
 * texel by texel in the rendered irradiance. lbk convert reports it for the pack it just wrote;
 * bench_packs prints it per profile and shared scene.
 *
 * What is compared (tools/convert/profiles/README.md "Pack error"):
 *   - every texel inside a lightmapped object's rectangle that the baker wrote (an all-zero texel
 *     is a rectangle's unused corner, never drawn), evaluated at the five normals lbk diff uses
 *     (+Z and 45° toward ±X, ±Y; tools/common/bake_data.h), physical irradiance;
 *   - luminance: |ΔY| / max(Y, Y_floor), Y_floor = 1 % of the mean Y over those texels at +Z,
 *     so the black corners of a level do not dominate;
 *   - colour: |Δ(r, g)| of the chromaticity r = R/(R+G+B), g = G/(R+G+B), where Y > Y_floor;
 *   - seam texels: where charts end, the texels a bilinear sample at a chart's border reads and
 *     where a 4×4 block can mix two charts: gutter texels (no triangle of a chart covers their
 *     centre) and texels within TL_SEAM_TEXELS of another chart, a gutter or the page's edge.
 *     Charts come from LMUV (generated charts, rasterised); an object with authored TEXCOORD_1
 *     (its triangles are in the glTF only) or without LMUV counts as one chart filling its
 *     rectangle;
 *   - shared blocks: the texels of 4×4 blocks that two objects' rectangles share;
 *   - mean, 99th percentile and maximum over the samples (texels × normals): per object exact
 *     (nearest rank); over the level from a histogram with 256 logarithmic bins per decade, the
 *     p99 being its bin's upper edge (at most 0.9 % above the exact one, never below), so a
 *     level of any size costs a fixed amount of memory. */
#ifndef LBK_TOOLS_PACK_ERROR_H
#define LBK_TOOLS_PACK_ERROR_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/bake_data.h"

#define TL_SEAM_TEXELS 2
/* What a pack should keep of the bake (luminance, over all texels): the goals lbk convert and
 * bench_packs print against. */
#define TL_PACK_GOAL_MEAN 0.01
#define TL_PACK_GOAL_P99 0.05

typedef struct tl_pack_stats {
    uint64_t samples;
    double mean, p99, max;
} tl_pack_stats;

typedef struct tl_pack_part {
    tl_pack_stats lum, colour;
} tl_pack_part;

typedef struct tl_pack_object_error {
    uint32_t object;     /* index in the object table */
    char *name;          /* its name (malloc'ed, NUL-terminated) */
    uint64_t texels;     /* texels compared */
    tl_pack_part all, seam;
} tl_pack_object_error;

typedef struct tl_pack_error {
    double y_floor;               /* physical luminance below which errors are relative to it */
    uint64_t texels;              /* texels compared, all objects */
    uint64_t shared_block_texels; /* of them, in 4×4 blocks two objects' rectangles share */
    tl_pack_part all, seam, shared;/* every texel; seam texels; texels of shared blocks */
    uint32_t object_count;        /* lightmapped objects */
    tl_pack_object_error *objects;/* malloc'ed, object_count of them */
} tl_pack_error;

/* Compares the lightmap of `pack` with that of `source` (same objects and rectangles: a pack of
 * that source). 0, or -1 with err (no lightmap in one of them, object tables that differ, out of
 * memory). Free with tl_pack_error_free. */
int tl_pack_error_compute(const tl_bake *source, const tl_bake *pack, tl_pack_error *out, char err[TL_ERR_LEN]);
void tl_pack_error_free(tl_pack_error *e);

/* 1 when s meets the goals mean ≤ mean_goal and p99 ≤ p99_goal, else 0. */
int tl_pack_error_meets(const tl_pack_stats *s, double mean_goal, double p99_goal);

#endif
