/* LLG section: local light grids — per object an oriented box with a regular lattice of SH9
 * radiance probes, plus per-vertex self-visibility of the object (seed 001 §2.2).
 * Layout: spec/container.md §11.
 *
 * Lattice: dims (nx, ny, nz), each 2..64. Probe (i, j, k) sits at
 *     centre + Σ_a axis_a · half_extents_a · (2·idx_a / (n_a − 1) − 1)
 * and is stored at probe_offset + i + nx·(j + ny·k) of the section's shared probe array.
 * Sampling a world point p: local l_a = ((p − centre)·axis_a) / half_extents_a, clamped to
 * [−1, 1] (points outside the box take the value at the nearest box point), lattice coordinate
 * g_a = (l_a + 1)/2 · (n_a − 1), trilinear blend of the 8 unpacked probes around g.
 *
 * Per-vertex self-visibility, 4 bytes per vertex of the object, in the object's vertex order:
 *   byte 0  unorm8 visibility V (fraction of the hemisphere around the normal not blocked by
 *           the object itself), byte 1–2 bent normal b as unorm8((u+1)/2), unorm8((v+1)/2) of
 *           its octahedral coordinates (lbk/octa.h) in the grid frame (components along
 *           axis0, axis1, axis2), byte 3 reserved 0.
 * Apply: E_vertex = V · E_sh(b_world), b_world = Σ_a b_a·axis_a, with E_sh the SH irradiance
 * (lbk_sh9_irradiance) of the trilinearly interpolated radiance at the vertex position. Because
 * the data are in the box frame, instances of a model share them.
 *
 * Scale: packed probe × scale = radiance (lbk.h, "radiometric scale"): the grid descs' SH,
 * lbk_llg_sample and lbk_llg_vertex_irradiance are physical; the bytes at view->probes and DLS
 * LLG payloads are stored units.
 *
 * Thread safety: every function is safe to call from any thread; views are read-only. */
#ifndef LBK_LLG_H
#define LBK_LLG_H

#include "lbk/sh.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_LLG_HEADER_SIZE 32u
#define LBK_LLG_GRID_SIZE 96u
#define LBK_LLG_MIN_DIM 2u
#define LBK_LLG_MAX_DIM 64u

typedef struct lbk_llg_vertex {
    float visibility;     /* [0, 1] */
    float bent_normal[3]; /* unit, grid frame */
} lbk_llg_vertex;

/* One grid (an array element: frozen). */
typedef struct lbk_llg_grid_desc {
    float centre[3];
    float axes[3][3];       /* orthonormal rows: axis0, axis1, axis2 */
    float half_extents[3];   /* > 0 */
    uint32_t dims[3];       /* 2..64 each */
    const lbk_sh9_rgb *probes;        /* dims[0]·dims[1]·dims[2], i fastest */
    const lbk_llg_vertex *vertices;   /* vertex_count (may be 0) */
    uint32_t vertex_count;
} lbk_llg_grid_desc;

/* Size-tagged (lbk.h): set size with LBK_LLG_BUILD_DESC_INIT. */
typedef struct lbk_llg_build_desc {
    size_t size;
    const lbk_llg_grid_desc *grids;
    uint32_t grid_count;
    float scale; /* 0: 1; else a positive normal power of two (the probes are divided by it) */
} lbk_llg_build_desc;
#define LBK_LLG_BUILD_DESC_INIT LBK_SIZED_INIT(lbk_llg_build_desc)

/* Serialises the grids (deterministic). Free the buffer with lbk_free. */
LBK_API lbk_result lbk_llg_build(const lbk_llg_build_desc *desc, const lbk_allocator *allocator, void **out,
                                 size_t *size);

typedef struct lbk_llg_view {
    const uint8_t *data;
    size_t size;
    uint32_t grid_count;
    uint64_t probe_count, vertex_count;
    const uint8_t *probes;   /* probe_count × 28 */
    const uint8_t *vertices; /* vertex_count × 4 */
    float scale;             /* stored × scale = physical */
} lbk_llg_view;

typedef struct lbk_llg_grid {
    float centre[3], axes[3][3], half_extents[3];
    uint32_t dims[3];
    uint64_t probe_offset, vertex_offset;
    uint32_t vertex_count;
} lbk_llg_grid;

/* Structure only (sizes, offsets, reserved bytes); lbk_validate checks the frames. */
LBK_API lbk_result lbk_llg_open(const void *data, size_t size, lbk_llg_view *out);
LBK_API lbk_result lbk_llg_grid_get(const lbk_llg_view *view, uint32_t index, lbk_llg_grid *out);
LBK_API void lbk_llg_probe_position(const lbk_llg_grid *grid, uint32_t i, uint32_t j, uint32_t k, float out[3]);
/* Trilinear physical radiance SH at world position p. */
LBK_API lbk_result lbk_llg_sample(const lbk_llg_view *view, uint32_t grid, const float p[3], lbk_sh9_rgb *out);
LBK_API void lbk_llg_vertex_pack(const lbk_llg_vertex *v, uint8_t out[4]);
LBK_API void lbk_llg_vertex_unpack(const uint8_t in[4], lbk_llg_vertex *v);
/* E = V · E_sh(bent normal in world) at world position p for vertex `vertex` of grid `grid`. */
LBK_API lbk_result lbk_llg_vertex_irradiance(const lbk_llg_view *view, uint32_t grid, uint32_t vertex, const float p[3],
                                             float rgb[3]);

/* ---- vertex order (spec §11 "Vertex order") -------------------------------------------------
 * A grid's vertex records follow the object's glTF mesh: its triangle primitives in order
 * (mode 4, 5 or 6 with at least one triangle; points and lines are skipped), within each its
 * vertices in index order, keeping only the vertices some triangle uses. A primitive without
 * NORMAL is flat shaded: every triangle corner is a vertex of its own, corner c of triangle t
 * being vertex 3t + c, all used. lbk_llg_vertex_map turns that rule into a lookup table. */

/* One triangle primitive of the object's mesh (an array element: frozen). */
typedef struct lbk_llg_source_primitive {
    uint32_t vertex_count;   /* vertices of the glTF primitive (POSITION count, or Draco points) */
    uint32_t index_count;    /* 3 × its triangles */
    const uint32_t *indices; /* its triangle list as glTF defines it: strips and fans expanded,
                                strip triangles with a repeated index (restarts) dropped */
    uint32_t flat;           /* non-zero: no NORMAL, one record per corner (an engine that split the
                                corners already passes its split vertices with flat = 0: same order) */
} lbk_llg_source_primitive;

#define LBK_LLG_NO_VERTEX 0xFFFFFFFFu

/* Fills map, primitive after primitive, with one entry per vertex (flat: per corner, i.e. per
 * index): the vertex's record within its grid (add lbk_llg_grid.vertex_offset to index the
 * section's array), or LBK_LLG_NO_VERTEX for a vertex no triangle uses. map_count must be
 * Σ (flat ? index_count : vertex_count). *record_count gets the number of records, which equals
 * the grid's vertex_count when the mesh is the one that was baked. LBK_ERR_INVALID_ARGUMENT for
 * NULL arrays, an index_count that is not a multiple of 3, an index ≥ vertex_count or another
 * map_count; LBK_ERR_LIMIT past 2^32 − 2 records. Reads nothing but its arguments. */
LBK_API lbk_result lbk_llg_vertex_map(const lbk_llg_source_primitive *primitives, uint32_t primitive_count,
                                      uint32_t *map, uint64_t map_count, uint32_t *record_count);

#ifdef __cplusplus
}
#endif
#endif
