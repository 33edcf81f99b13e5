/* The reference shaders of gpu/shaders run over arrays of queries: what an engine's shaders do to
 * read lbk data (AHD lightmap texels, SH9 probes, the GLG walk, LLG lattices), checked against
 * liblbk bit for bit (tests/gpu/test_gpu.c). Each call uploads, dispatches once, reads back.
 * 0 on success. */
#ifndef LBK_GPU_SAMPLERS_H
#define LBK_GPU_SAMPLERS_H

#include "gpu/host/vk_context.h"

/* lbk_ahd_irradiance: texels as (Ez word, RGBA word) pairs, tangent-space normals xyz. */
int gpu_ahd_irradiance(gpu_ctx *c, const uint32_t *texels, const float *normals, uint32_t n, float *rgb);
/* lbk_sh9_unpack + lbk_sh9_irradiance: 28-byte probes, unit normals. */
int gpu_sh9_irradiance(gpu_ctx *c, const uint8_t *probes, const float *normals, uint32_t n, float *rgb);
/* lbk_glg_sample on GLG section bytes: points xyz and start hints; out 27 SH floats (channel-major),
 * the tetra found and the 4 blend weights per query. */
int gpu_glg_sample(gpu_ctx *c, const void *glg, size_t size, const float *points, const uint32_t *hints, uint32_t n,
                   float *sh, uint32_t *tetra, float *weights);
/* lbk_llg_sample and lbk_llg_vertex_irradiance on LLG section bytes: per query a point, a grid and
 * a vertex of it; out 27 SH floats and 3 irradiance floats. */
int gpu_llg_sample(gpu_ctx *c, const void *llg, size_t size, const float *points, const uint32_t *grids,
                   const uint32_t *vertices, uint32_t n, float *sh, float *rgb);
/* The encoders alone (codec_pack.comp): lbk_sh9_pack of 27 floats (channel-major) per probe into
 * 28 bytes, and lbk_ahd_from_linear of 12 floats ({e0, gx, gy, gz} per channel) per texel into
 * (Ez word, RGBA word). */
int gpu_sh9_pack(gpu_ctx *c, const float *sh, uint32_t n, uint8_t *probes);
int gpu_ahd_from_linear(gpu_ctx *c, const float *lin, uint32_t n, uint32_t *texels);

#endif
