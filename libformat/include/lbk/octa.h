/* Octahedral direction mapping and the OCTP section: GIBS-style octahedral probes
 * (seed 003, "1024 Bytes Per Probe"). Layout: spec/container.md §14.
 *
 * Mapping (full sphere, Cigolle et al. 2014): for a unit d, p = d / (|x|+|y|+|z|);
 * (u, v) = (p.x, p.y) if p.z ≥ 0, else ((1 − |p.y|)·sign(p.x), (1 − |p.x|)·sign(p.y)) with
 * sign(0) = +1. (u, v) ∈ [−1, 1]². Decoding inverts it and normalises.
 *
 * A probe is 1024 bytes:
 *   0    u32[6×6]       irradiance, R11G11B10F, row-major; interior 4×4 plus a 1-texel border
 *   144  u16[14×14][2]  depth moments (mean distance, mean squared distance) as half, interior
 *                        12×12 plus a 1-texel border
 *   928  f32[3]         probe position (world)
 *   940  u8[84]         reserved, zero
 * Interior texel (i, j) of an N×N interior (stored at (i+1, j+1)) holds the direction
 * oct_decode(((i + ½)/N)·2 − 1, ((j + ½)/N)·2 − 1). Border texels copy interior texels so that
 * bilinear filtering wraps across the octahedron's edges (DDGI convention): with S = N + 1,
 *   top    (x, 0)   ← (S − x, 1)        bottom (x, S)   ← (S − x, N)      for 1 ≤ x ≤ N
 *   left   (0, y)   ← (1, S − y)        right  (S, y)   ← (N, S − y)      for 1 ≤ y ≤ N
 *   corners (0,0) ← (N,N), (S,0) ← (1,N), (0,S) ← (N,1), (S,S) ← (1,1).
 *
 * Scale: stored irradiance × scale = irradiance in lux (lbk.h, "radiometric scale"): the probe
 * descs, lbk_octp_probe_get and lbk_octp_irradiance are physical; depth moments are not scaled.
 *
 * Thread safety: every function is safe to call from any thread; views are read-only. */
#ifndef LBK_OCTA_H
#define LBK_OCTA_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_OCTP_HEADER_SIZE 16u
#define LBK_OCTP_PROBE_SIZE 1024u
#define LBK_OCTP_IRR_N 4u    /* interior irradiance texels per side */
#define LBK_OCTP_DEPTH_N 12u /* interior depth texels per side */
#define LBK_OCTP_IRR_OFFSET 0u
#define LBK_OCTP_DEPTH_OFFSET 144u
#define LBK_OCTP_POSITION_OFFSET 928u

LBK_API void lbk_oct_encode(const float dir[3], float uv[2]);
LBK_API void lbk_oct_decode(const float uv[2], float dir[3]);
/* The interior texel a stored texel (x, y) of an (N+2)² border layout shows: itself when
 * interior, its source when on the border. */
LBK_API void lbk_oct_border_source(uint32_t n, uint32_t x, uint32_t y, uint32_t *sx, uint32_t *sy);
/* Direction at the centre of interior texel (i, j) of an N×N map. */
LBK_API void lbk_oct_texel_direction(uint32_t n, uint32_t i, uint32_t j, float dir[3]);

/* Builder input: interior data only; borders are filled by the builder. An array element (frozen),
 * also what lbk_octp_probe_get fills. */
typedef struct lbk_octp_probe_desc {
    float position[3];
    float irradiance[4 * 4][3];  /* interior, row-major (j·4 + i) */
    float depth[12 * 12][2];     /* interior: mean distance, mean squared distance (≥ 0) */
} lbk_octp_probe_desc;

/* Size-tagged (lbk.h): set size with LBK_OCTP_BUILD_DESC_INIT. */
typedef struct lbk_octp_build_desc {
    size_t size;
    const lbk_octp_probe_desc *probes;
    uint32_t probe_count;
    float scale; /* 0: 1; else a positive normal power of two */
} lbk_octp_build_desc;
#define LBK_OCTP_BUILD_DESC_INIT LBK_SIZED_INIT(lbk_octp_build_desc)

/* Serialises the probes (deterministic). Free the buffer with lbk_free. */
LBK_API lbk_result lbk_octp_build(const lbk_octp_build_desc *desc, const lbk_allocator *allocator, void **out,
                                  size_t *size);

typedef struct lbk_octp_view {
    const uint8_t *data;
    size_t size;
    uint32_t probe_count;
    const uint8_t *probes; /* probe_count × 1024 bytes */
    float scale;           /* stored irradiance × scale = physical */
} lbk_octp_view;

LBK_API lbk_result lbk_octp_open(const void *data, size_t size, lbk_octp_view *out);
/* Decodes one probe's interior back into the builder form (physical irradiance). */
LBK_API lbk_result lbk_octp_probe_get(const lbk_octp_view *view, uint32_t index, lbk_octp_probe_desc *out);
/* Bilinear physical irradiance lookup in direction dir (uses the border, never reads outside the probe). */
LBK_API lbk_result lbk_octp_irradiance(const lbk_octp_view *view, uint32_t index, const float dir[3], float rgb[3]);

#ifdef __cplusplus
}
#endif
#endif
