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
 *   928  f32[3]         probe position (world; in a volume: grid point + offset)
 *   940  volume (1.3): f32[3] relocation offset, u32 state, u32 rays, f32 back-face fraction,
 *        f32 nearest hit; then u8[56] reserved. List form: u8[84] reserved, zero.
 * Two forms (spec/container.md §14): a list of probes (level_count 0, the 1.0–1.2 content) and
 * a probe volume (1.3): 1–3 regular grid levels (clipmap style, finest first), probes of a
 * level x-fastest, then y, then z, levels in order.
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
#define LBK_OCTP_INFO_OFFSET 940u   /* volume form: offset, state, rays, back-face fraction, nearest */
#define LBK_OCTP_LEVEL_SIZE 48u
#define LBK_OCTP_MAX_LEVELS 3u
#define LBK_OCTP_MAX_DIM 256u       /* probes per axis of a level */
#define LBK_OCTP_MAX_MISS 255.0f    /* largest miss distance: its square stays a finite half */

/* Probe states (volume form). Inside-geometry probes are inactive: a sampler skips them. */
enum { LBK_OCTP_ACTIVE = 0, LBK_OCTP_INSIDE = 1, LBK_OCTP_NO_NEARBY = 2 };

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

/* One grid level of a probe volume: probe (x, y, z) of the level sits at grid point
 * origin + spacing·(x, y, z) (plus its offset), index first_probe + x + dims0·(y + dims1·z). */
typedef struct lbk_octp_level {
    float origin[3];
    float spacing;       /* finite, > 0; strictly increasing from level to level */
    uint32_t dims[3];    /* 2 … LBK_OCTP_MAX_DIM each */
    uint32_t first_probe;
    float miss_distance; /* what a depth ray that hits nothing records; (0, LBK_OCTP_MAX_MISS] */
} lbk_octp_level;

/* Per-probe data of the volume form (an array element, frozen). */
typedef struct lbk_octp_probe_info {
    float offset[3];      /* relocation: position − grid point; |each| ≤ spacing/2 */
    uint32_t state;       /* LBK_OCTP_ACTIVE, _INSIDE, _NO_NEARBY */
    uint32_t rays;        /* irradiance gather rays the probe traced (statistics) */
    float backface;       /* fraction of classification rays that hit a back face, [0, 1] */
    float nearest;        /* nearest hit of the classification rays (miss distance when none) */
} lbk_octp_probe_info;

/* Size-tagged (lbk.h): set size with LBK_OCTP_BUILD_DESC_INIT. level_count 0 writes the list
 * form (info ignored); 1…3 a volume: probe_count = Σ dims products, info[probe_count] needed,
 * levels' first_probe recomputed by the builder (the caller's value is ignored), position of
 * probe i = grid point + info[i].offset (the probes' position fields are ignored). */
typedef struct lbk_octp_build_desc {
    size_t size;
    const lbk_octp_probe_desc *probes;
    uint32_t probe_count;
    float scale; /* 0: 1; else a positive normal power of two */
    const lbk_octp_level *levels;
    uint32_t level_count;
    const lbk_octp_probe_info *info;
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
    uint32_t level_count;  /* 0: a list of probes; 1–3: a volume */
    lbk_octp_level levels[3];
} lbk_octp_view;

LBK_API lbk_result lbk_octp_open(const void *data, size_t size, lbk_octp_view *out);
/* Decodes one probe's interior back into the builder form (physical irradiance). */
LBK_API lbk_result lbk_octp_probe_get(const lbk_octp_view *view, uint32_t index, lbk_octp_probe_desc *out);
/* Bilinear physical irradiance lookup in direction dir (uses the border, never reads outside the probe). */
LBK_API lbk_result lbk_octp_irradiance(const lbk_octp_view *view, uint32_t index, const float dir[3], float rgb[3]);

/* Volume form: a probe's relocation offset, state and statistics (list form: NOT_FOUND). */
LBK_API lbk_result lbk_octp_probe_info_get(const lbk_octp_view *view, uint32_t index, lbk_octp_probe_info *out);
/* Bilinear depth moments (mean, mean²) of probe `index` in direction dir, as stored (metres). */
LBK_API lbk_result lbk_octp_depth(const lbk_octp_view *view, uint32_t index, const float dir[3], float m[2]);

/* The runtime sampler (spec/container.md §14.3). Size-tagged; zero means defaults. */
enum {
    LBK_OCTP_SAMPLE_NO_CHEBYSHEV = 1u, /* no depth-moment visibility weight */
    LBK_OCTP_SAMPLE_NO_BACKFACE = 2u,  /* no back-face (probe behind the surface) weight */
    LBK_OCTP_SAMPLE_NO_BLEND = 4u      /* the finest level containing the point only */
};
typedef struct lbk_octp_sample_desc {
    size_t size;
    float position[3];
    float normal[3];   /* unit surface normal; zero: a point in the air (no normal bias, no
                          back-face weight; irradiance of the direction `view` or +z) */
    float view[3];     /* unit direction from the point towards the viewer; zero: no view bias */
    float normal_bias; /* × level spacing; 0: 0.2; < 0: none */
    float view_bias;   /* × level spacing; 0: 0.1; < 0: none */
    uint32_t flags;    /* LBK_OCTP_SAMPLE_* */
} lbk_octp_sample_desc;
#define LBK_OCTP_SAMPLE_DESC_INIT LBK_SIZED_INIT(lbk_octp_sample_desc)

/* Irradiance (lux) at a surface point with the given normal: the weighted blend of the 8 probes
 * of the point's cell (trilinear × back-face × Chebyshev visibility; inactive probes skipped),
 * blended between levels near a finer level's edge. Outside every level: the nearest cell of
 * the coarsest level (clamped). All weights zero: rgb = 0 and *weight_sum (optional) = 0.
 * Errors: INVALID_ARGUMENT (NULL, non-finite position), UNSUPPORTED_FEATURE (a list-form view). */
LBK_API lbk_result lbk_octp_sample(const lbk_octp_view *view, const lbk_octp_sample_desc *desc, float rgb[3],
                                   float *weight_sum);

#ifdef __cplusplus
}
#endif
#endif
