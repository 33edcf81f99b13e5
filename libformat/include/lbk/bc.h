/* Block-compressed texture decoders for the LMAP plane encodings of format 1.2 (spec/container.md
 * §9.2): BC6H unsigned (plane 0, HDR irradiance) and BC4 / BC5 unsigned (plane 1, the ratio and
 * the direction). Bit-exact with the D3D11 functional specification and the Khronos Data Format
 * specification (checked against Mesa's decoders, bench/mesa_bc_check.c); what a GPU's texture unit
 * returns. They live in liblbk because readers other than a GPU need texel values — DLS apply on
 * the CPU, the validator, tools — and they are small and dependency-free. (The ASTC encodings are
 * decoded by the tools through astcenc: liblbk reports LBK_ERR_UNSUPPORTED_FEATURE for them.)
 *
 * Blocks are 4×4 texels, texel (x, y) of the block at index 4y + x.
 *
 * Thread safety: every function is pure: safe to call from any thread. */
#ifndef LBK_BC_H
#define LBK_BC_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_BC6H_BLOCK_SIZE 16u
#define LBK_BC4_BLOCK_SIZE 8u
#define LBK_BC5_BLOCK_SIZE 16u

/* BC6H_UF16 (DXGI_FORMAT_BC6H_UF16): the 16 texels as IEEE binary16 bit patterns (R, G, B), never
 * negative or Inf/NaN. A block with one of the four reserved modes decodes to zero. */
LBK_API void lbk_bc6h_unpack(const uint8_t block[LBK_BC6H_BLOCK_SIZE], uint16_t out[16][3]);
/* The block's mode: 1..14 as the D3D specification numbers them, 0 for a reserved mode. */
LBK_API int lbk_bc6h_mode(const uint8_t block[LBK_BC6H_BLOCK_SIZE]);
/* The inverse (for encoders): mode 1..14, shape 0..31 (two-region modes), quantised endpoints
 * (region 0: [0], [1]; region 1: [2], [3]) at the mode's endpoint precision, indices (3 bits for
 * two-region modes, 4 for one-region). LBK_ERR_RANGE when a transformed mode cannot hold an
 * endpoint's delta or an anchor texel's index has its top bit set (texel 0, and the shape's anchor
 * for region 1: swap that region's endpoints and invert its indices first). */
LBK_API lbk_result lbk_bc6h_pack(int mode, int shape, const int endpoints[4][3], const uint8_t index[16],
                                 uint8_t out[LBK_BC6H_BLOCK_SIZE]);
/* A mode's parameters: regions (1 or 2; 0 for an unknown mode), endpoint precision, delta (or
 * second-endpoint) precision per channel, whether endpoints 1.. are deltas from endpoint 0. */
LBK_API void lbk_bc6h_mode_info(int mode, int *regions, int *endpoint_bits, int delta_bits[3], int *transformed);
/* Two-region shape s: bit t set = texel t in region 1; and region 1's anchor texel. */
LBK_API uint16_t lbk_bc6h_shape(int shape);
LBK_API int lbk_bc6h_anchor(int shape);
/* BC4_UNORM: 16 values in [0, 1] (the interpolated palette entry / 255, or / 7 and / 5 of it). */
LBK_API void lbk_bc4_unpack(const uint8_t block[LBK_BC4_BLOCK_SIZE], float out[16]);
/* BC5_UNORM: two BC4 blocks, red then green. */
LBK_API void lbk_bc5_unpack(const uint8_t block[LBK_BC5_BLOCK_SIZE], float out[16][2]);

#ifdef __cplusplus
}
#endif
#endif
