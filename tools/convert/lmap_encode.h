/* Block encoders for the LMAP plane encodings of format 1.2 (spec/container.md §9.2), used by
 * lbk convert. They live in the tools, not in liblbk (which only decodes, lbk/bc.h): encoding is
 * an offline step, and the ASTC one needs astcenc.
 *
 * Every encoder takes a page as floats plus a weight per texel: 0 marks a texel no object uses
 * (atlas gaps and the page padding), which then costs nothing, so a block at the edge of a chart
 * fits the chart's texels only. */
#ifndef LBK_TOOLS_LMAP_ENCODE_H
#define LBK_TOOLS_LMAP_ENCODE_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/ahd.h"

/* BC6H_UF16 of one 4×4 block: rgb[16][3] ≥ 0 (stored units, clamped to 65504), weights[16] ≥ 0,
 * owner[16] the texels' objects (-1 none) or NULL.
 * One-region modes 11–14 (the best of the four by weighted squared error in half-float bit
 * space, ~relative error), endpoints by principal axis, refined by least squares, then a
 * coordinate descent on the quantised endpoints (one channel, or all three, a step at a time);
 * where that fits badly (an edge, two charts, a dark corner), the two-region modes 1–10 on the four
 * shapes that split the block best, the three best candidates refined the same way. */
void tl_bc6h_encode_block(const float rgb[16][3], const float weight[16], const int owner[16], uint8_t out[16]);
/* BC4_UNORM of one block: v[16] in [0, 1]. The 8-value mode, endpoints searched around the
 * weighted range. */
void tl_bc4_encode_block(const float v[16], const float weight[16], uint8_t out[8]);

/* A whole page: texels width × height (multiples of 4), weights (NULL: all 1), owners (the object
 * each texel belongs to, -1 none; NULL: unknown) so that a block two charts share can give each its
 * own BC6H region. *plane0 / *plane1
 * are malloc'ed, lbk_lmap_plane_size bytes. format0 / format1 as in lbk/lightmap.h. Returns 0 or
 * -1 (out of memory, or an ASTC encode failure: err says). */
int tl_lmap_encode_page(const lbk_ahd_texel_f *texels, const float *weights, const int32_t *owners, uint32_t width,
                        uint32_t height, uint32_t format0, uint32_t format1, void **plane0, void **plane1, char *err,
                        size_t err_len);

#endif
