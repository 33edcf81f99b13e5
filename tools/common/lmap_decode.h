/* Decoding a whole LMAP page to float texels, whatever its planes' encoding (spec/container.md
 * §9.2): 1.0 planes and BC6H / BC4 / BC5 through liblbk (lbk/bc.h), ASTC through astcenc. What
 * diff, export and inspect read block-encoded packs with. */
#ifndef LBK_TOOLS_LMAP_DECODE_H
#define LBK_TOOLS_LMAP_DECODE_H

#include <stddef.h>

#include "lbk/lightmap.h"

/* out: width × height texels, row-major, stored units. Returns 0 or -1 (err says why). */
int tl_lmap_page_decode(const lbk_lmap_planes *planes, lbk_ahd_texel_f *out, char *err, size_t err_len);

/* Short names of the encodings ("r11g11b10f", "bc6h", "astc4x4_hdr"; "rgba8", "bc5_bc4",
 * "astc4x4"), as the profiles write them; NULL for unknown values. */
const char *tl_lmap_format_name(int plane, uint32_t format);
/* The inverse: -1 for an unknown name. */
int tl_lmap_format_parse(int plane, const char *name);

#endif
