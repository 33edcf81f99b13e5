/* GLG section: the global light grid — SH9 radiance probes on a tetrahedral mesh with per-tetra
 * face visibility (seed 001 §2.2 after Iwanicki & Sloan 2017). Layout: spec/container.md §10.
 *
 * Visibility: per tetra 4 unorm8 values; value i is the fraction of unoccluded rays between
 * probe i of the tetra and sample points on the opposite face (255 = fully visible). Sampling
 * weights probe i by bary_i · vis_i / 255 and renormalises; when every product is 0 the plain
 * barycentrics are used. Outside the hull the walk's clamped barycentrics are used (lbk/tetra.h).
 *
 * Scale: packed probe × scale = radiance (lbk.h, "radiometric scale"): the build desc's SH and
 * lbk_glg_probe_get / lbk_glg_sample are physical; the bytes at view->probes and DLS GLG payloads
 * are stored units.
 *
 * Thread safety: every function is safe to call from any thread; views are read-only (the
 * sampling hint is the caller's). */
#ifndef LBK_GLG_H
#define LBK_GLG_H

#include "lbk/sh.h"
#include "lbk/tetra.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_GLG_HEADER_SIZE 32u

/* Size-tagged (lbk.h): set size with LBK_GLG_BUILD_DESC_INIT. */
typedef struct lbk_glg_build_desc {
    size_t size;
    uint32_t probe_count; /* ≥ 4 */
    uint32_t tetra_count; /* ≥ 1 */
    const float (*positions)[3];      /* probe_count, finite */
    const lbk_sh9_rgb *probes;        /* probe_count radiance SH, packed to 28 bytes each */
    const uint32_t (*tetras)[4];      /* tetra_count; either orientation (the builder orients them) */
    const uint32_t (*adjacency)[4];   /* NULL: derived from shared faces */
    const uint8_t (*visibility)[4];   /* NULL: all 255 */
    float scale;                      /* 0: 1; else a positive normal power of two */
} lbk_glg_build_desc;
#define LBK_GLG_BUILD_DESC_INIT LBK_SIZED_INIT(lbk_glg_build_desc)

/* Serialises a GLG (deterministic). Tetras of negative volume are re-oriented by swapping their
 * vertices 2 and 3 (with their adjacency and visibility entries); zero volume, out-of-range
 * indices, non-finite positions or a face shared by more than two tetras give
 * LBK_ERR_INVALID_ARGUMENT. Free the buffer with lbk_free. */
LBK_API lbk_result lbk_glg_build(const lbk_glg_build_desc *desc, const lbk_allocator *allocator, void **out,
                                 size_t *size);

typedef struct lbk_glg_view {
    const uint8_t *data;
    size_t size;
    uint32_t probe_count, tetra_count;
    lbk_tetra_mesh mesh;        /* positions, tetras, adjacency inside data */
    const uint8_t *probes;      /* probe_count × 28 bytes */
    const uint8_t *visibility;  /* tetra_count × 4 bytes */
    float scale;                /* stored × scale = physical */
} lbk_glg_view;

/* Structure only (header, sizes, reserved and padding bytes); lbk_validate checks the mesh. */
LBK_API lbk_result lbk_glg_open(const void *data, size_t size, lbk_glg_view *out);
/* Position and physical radiance SH (unpacked × scale) of one probe; either may be NULL. */
LBK_API lbk_result lbk_glg_probe_get(const lbk_glg_view *view, uint32_t index, float position[3],
                                     lbk_sh9_rgb *sh);

typedef struct lbk_glg_sample_info {
    lbk_tetra_location location;
    float weights[4]; /* the visibility-weighted weights actually used, sum 1 */
} lbk_glg_sample_info;

/* Physical radiance SH at p: locate (starting at *hint if hint is non-NULL; the found tetra is written
 * back for the next call), weight, and blend the four unpacked probes. */
LBK_API lbk_result lbk_glg_sample(const lbk_glg_view *view, const float p[3], uint32_t *hint, lbk_sh9_rgb *out,
                                  lbk_glg_sample_info *info);

#ifdef __cplusplus
}
#endif
#endif
