/* 3D Delaunay tetrahedralisation of probe positions (libqhull_r), made robust for the inputs
 * probe placement produces: perfect regular grids (cospherical), duplicates, flat sets.
 * How each degenerate case is handled is documented in bake/probes/PROBES.md. */
#ifndef BK_DELAUNAY_H
#define BK_DELAUNAY_H

#include <stddef.h>
#include <stdint.h>

#define BK_TET_NONE 0xFFFFFFFFu        /* no neighbour: the face lies on the convex hull */

enum bk_delaunay_status {
    BK_DELAUNAY_OK = 0,
    BK_DELAUNAY_TOO_FEW,               /* fewer than 4 distinct points: no tetrahedra */
    BK_DELAUNAY_FLAT,                  /* all points on one plane (or line): no tetrahedra */
    BK_DELAUNAY_NO_MEMORY,
    BK_DELAUNAY_FAILED                 /* qhull reported an error it could not recover from */
};

typedef struct bk_delaunay_options {
    /* Points closer than this are merged into the first of them (input order).
     * 0: 1e-6 × the diagonal of the points' bounding box. */
    double merge_distance;
    /* 1: split qhull's merged cospherical cells without trying the tie-breaking weights first
     * (the path bk_delaunay falls back to when they fail; n^1.6 on lattices). 0: weights first. */
    int merged_cells;
} bk_delaunay_options;

typedef struct bk_tetmesh {
    /* Vertices: the distinct input points that are corners of at least one tetrahedron,
     * in input order. */
    size_t point_count;
    float *points;                     /* 3 per point */
    uint32_t *point_source;            /* per point: its index in the input */
    size_t input_count;
    uint32_t *input_to_point;          /* per input point: its vertex, or BK_TET_NONE (unused) */
    /* Tetrahedra: 4 vertex indices each, positively oriented:
     * dot(p1 - p0, cross(p2 - p0, p3 - p0)) > 0. Sorted by their sorted vertex tuple. */
    size_t tet_count;
    uint32_t *tets;
    /* neighbours[4t + i]: the tetrahedron across the face opposite vertex i of t,
     * BK_TET_NONE on the hull. Symmetric. */
    uint32_t *neighbours;
    /* diagnostics */
    size_t merged_count;               /* input points merged into an earlier one */
    size_t unused_count;               /* distinct points that ended in no tetrahedron */
    size_t dropped_flat;               /* near-zero-volume tetrahedra removed (0 for sane input) */
    size_t nonmanifold_faces;          /* faces shared by more than two tetrahedra (0 expected) */
    double volume;                     /* total volume of the tetrahedra */
    size_t pocket_tets;                /* lifted path: tetrahedra filled into the pockets its ghosts
                                          cut into the hull (PROBES.md) */
    int hull_ghosts;                   /* 1: the lifted path's ghosts beside the box's faces failed
                                          and it ran again with ghosts beside the hull's facets */
    int merged_cells;                  /* 1: the tie-breaking weights failed and qhull's merged
                                          cospherical cells were split instead (PROBES.md) */
} bk_tetmesh;

/* Tetrahedralises points[3*count]. On any status other than OK, *out holds no tetrahedra but
 * is still safe to free. Deterministic: the same input gives the same output. */
int bk_delaunay(const float *points, size_t count, const bk_delaunay_options *options,
                bk_tetmesh *out);
void bk_tetmesh_free(bk_tetmesh *mesh);
const char *bk_delaunay_status_name(int status);

/* Signed volume of a tetrahedron (positive when oriented as bk_tetmesh requires). */
double bk_tet_signed_volume(const float *p0, const float *p1, const float *p2, const float *p3);

#endif
