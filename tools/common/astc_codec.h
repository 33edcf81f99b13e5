/* ASTC 4×4 through ARM's astcenc (Debian libastcenc), for the LMAP ASTC plane encodings
 * (spec/container.md §9.2): lbk convert encodes, the tools decode. A C interface over astcenc's
 * C++ header (astc_codec.cc is, with the glTF import shim, the only C++ in lbk). liblbk itself
 * does not decode ASTC (lbk/bc.h says why). */
#ifndef LBK_TOOLS_ASTC_CODEC_H
#define LBK_TOOLS_ASTC_CODEC_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* rgba: width × height × 4 floats (hdr: RGB HDR with alpha 1, profile HDR RGB + LDR A; else LDR
 * in [0, 1], linear), width and height multiples of 4. out: 16 bytes per block, row-major blocks.
 * Quality: astcenc's "thorough" preset, one thread, deterministic. Returns 0, or -1 with err. */
int tl_astc_encode(const float *rgba, uint32_t width, uint32_t height, int hdr, uint8_t *out, size_t out_size,
                   char *err, size_t err_len);
/* The inverse: rgba receives width × height × 4 floats. */
int tl_astc_decode(const uint8_t *blocks, size_t size, uint32_t width, uint32_t height, int hdr, float *rgba,
                   char *err, size_t err_len);

#ifdef __cplusplus
}
#endif
#endif
