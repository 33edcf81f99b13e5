/* How well an atlas uses its pages: fill and chart statistics (bench_atlas, tests).
 *
 * A texel is covered when a chart triangle overlaps its square (the texel centre lies inside
 * the triangle, or the triangle's closest point to the centre lies strictly within half a
 * texel on both axes): the texels the charts themselves need, without margins or the
 * bilinear ring. Fill = covered texels / page texels; a chart is tiny when it covers at most
 * 3 texels. */
#ifndef BK_ATLAS_STATS_H
#define BK_ATLAS_STATS_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "bake/layout/atlas.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bk_atlas_stats {
    uint64_t page_texels;      /* Σ page width × height */
    uint64_t rect_texels;      /* Σ object rectangles */
    uint64_t block_texels;     /* Σ chart blocks: content plus the margin ring */
    uint64_t covered_texels;   /* see above */
    size_t charts, tiny_charts, rotated_charts;
    double fill;               /* covered / page texels */
    double fill_rects;         /* covered / object rectangles */
} bk_atlas_stats;

/* Errors: LBK_ERR_INVALID_ARGUMENT, LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_atlas_stats_compute(const bk_atlas *atlas, bk_atlas_stats *out);

#ifdef __cplusplus
}
#endif
#endif
