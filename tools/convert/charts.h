/* Which chart each lightmap texel belongs to, from OBJS and LMUV: what the block encoders use to
 * keep two charts that share a 4×4 block apart (each gets its own endpoints where the format
 * allows), and what the pack error calls a seam. */
#ifndef LBK_TOOLS_CHARTS_H
#define LBK_TOOLS_CHARTS_H

#include <stdint.h>

#include "lbk/lightmap_uv.h"
#include "lbk/objects.h"

/* Page `page`'s chart map, w × h texels: per texel the chart whose triangles cover its centre,
 * -1 for gutters (texels the baker dilated into) and gaps. Objects with generated charts (an LMUV
 * record of that kind) are rasterised chart by chart, a chart being the triangles of a primitive
 * that share vertices (the baker splits vertices where charts split, spec §16.4); any other
 * lightmapped object (authored TEXCOORD_1, whose triangles are only in the glTF, or lmuv NULL)
 * counts as one chart filling its rectangle. Ids are unique over the calls that share *next_id
 * (not dense). malloc'ed; NULL when out of memory. */
int32_t *tl_chart_map(const lbk_objects_view *objs, const lbk_lmuv_view *lmuv, uint32_t page, uint32_t w, uint32_t h,
                      int32_t *next_id);

#endif
