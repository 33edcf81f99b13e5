/* Point location in a tetrahedral mesh by walking neighbour links (the GLG lookup).
 * The mesh is read in its on-disk form (little-endian arrays, spec/container.md §10), so a
 * mapped file is used as it is.
 *
 * Barycentrics: for tetra (v0, v1, v2, v3), b_i = vol(tetra with v_i replaced by p) / vol(tetra),
 * computed in double; Σ b_i = 1 and p = Σ b_i v_i. Face i is the face opposite v_i and adjacency
 * entry i names the tetra across it (LBK_TETRA_NONE at the hull).
 *
 * Walk: from the start tetra (the hint if < tetra_count, else 0), while some b_i < −1e−6, step
 * across the face with the most negative b_i that has a neighbour. When every negative face is a
 * hull face the point is outside the hull: negative weights are clamped to 0 and the rest
 * renormalised (the point is projected onto that part of the hull), inside = 0. The walk takes at
 * most tetra_count + 64 steps (a Delaunay mesh needs at most tetra_count); after that, or on a
 * cycle caused by a non-Delaunay or malicious mesh, every tetra is scanned and the one whose
 * smallest barycentric is largest is used. Out-of-range indices and tetras of non-positive volume
 * met on the way give LBK_ERR_CORRUPT; nothing is read outside the arrays. A tetra index past
 * the end is LBK_ERR_NOT_FOUND.
 *
 * Thread safety: every function only reads the mesh: safe to call from any thread. */
#ifndef LBK_TETRA_H
#define LBK_TETRA_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_TETRA_NONE 0xFFFFFFFFu

typedef struct lbk_tetra_mesh {
    const uint8_t *positions; /* vertex_count × f32[3] */
    const uint8_t *tetras;    /* tetra_count × u32[4] vertex indices, positively oriented */
    const uint8_t *adjacency; /* tetra_count × u32[4]: neighbour across the face opposite vertex i */
    uint32_t vertex_count, tetra_count;
} lbk_tetra_mesh;

typedef struct lbk_tetra_location {
    uint32_t tetra;
    uint32_t vertices[4];
    float bary[4];   /* ≥ 0, sum 1 */
    int inside;      /* 0: outside the hull, bary clamped */
    uint32_t steps;  /* tetras visited by the walk */
    int scanned;     /* 1: the step cap was hit and the mesh was scanned */
} lbk_tetra_location;

/* Signed barycentrics of p in one tetra (unclamped). */
LBK_API lbk_result lbk_tetra_barycentric(const lbk_tetra_mesh *mesh, uint32_t tetra, const float p[3], float bary[4]);
LBK_API lbk_result lbk_tetra_locate(const lbk_tetra_mesh *mesh, const float p[3], uint32_t hint, lbk_tetra_location *out);
/* 6 × signed volume of (a, b, c, d) = det[b−a, c−a, d−a] in double; > 0 is positive orientation. */
LBK_API double lbk_tetra_orient(const float a[3], const float b[3], const float c[3], const float d[3]);

#ifdef __cplusplus
}
#endif
#endif
