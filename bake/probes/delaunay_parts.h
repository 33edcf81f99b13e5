/* What delaunay.c (the driver and the merged-cells path) and delaunay_lifted.c (the lifted path
 * and its pockets) share: the growing tetrahedron list, face records, orientation, qhull's
 * release. Internal to bake/probes. */
#ifndef BK_DELAUNAY_PARTS_H
#define BK_DELAUNAY_PARTS_H

#include "bake/probes/delaunay.h"

#include <libqhull_r/qhull_ra.h>

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static inline double orient(const double *a, const double *b, const double *c, const double *d)
{
    double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
    return ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx);
}

/* ---- growable tetra list ------------------------------------------------------------------ */
typedef struct tet_list { uint32_t *v; size_t n, cap; int oom; } tet_list;

static inline void tet_push(tet_list *l, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    if (l->oom) return;
    if (l->n == l->cap) {
        size_t cap = l->cap ? l->cap * 2 : 256;
        uint32_t *v = realloc(l->v, cap * 4 * sizeof *v);
        if (!v) { l->oom = 1; return; }
        l->v = v; l->cap = cap;
    }
    uint32_t *t = l->v + 4 * l->n++;
    t[0] = a; t[1] = b; t[2] = c; t[3] = d;
}

/* ---- duplicate merging: sorted cell keys, first point (input order) wins ------------------ */
typedef struct cell_key { int64_t x, y, z; uint32_t index; } cell_key;

static inline int cmp_cell_key(const void *pa, const void *pb)
{
    const cell_key *a = pa, *b = pb;
    if (a->x != b->x) return a->x < b->x ? -1 : 1;
    if (a->y != b->y) return a->y < b->y ? -1 : 1;
    if (a->z != b->z) return a->z < b->z ? -1 : 1;
    return (a->index > b->index) - (a->index < b->index);
}

static inline size_t lower_bound_cell(const cell_key *keys, size_t n, int64_t x, int64_t y, int64_t z)
{
    size_t lo = 0, hi = n;
    cell_key probe = {x, y, z, 0};
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (cmp_cell_key(&keys[mid], &probe) < 0) lo = mid + 1; else hi = mid;
    }
    return lo;
}

static inline int cmp_u32(const void *pa, const void *pb)
{
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    return (a > b) - (a < b);
}

/* ---- face records for adjacency ----------------------------------------------------------- */
typedef struct face_rec { uint32_t v[3]; uint32_t tet; uint32_t slot; } face_rec;

static inline int cmp_face(const void *pa, const void *pb)
{
    const face_rec *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->v[k] != b->v[k]) return a->v[k] < b->v[k] ? -1 : 1;
    if (a->tet != b->tet) return a->tet < b->tet ? -1 : 1;
    return (a->slot > b->slot) - (a->slot < b->slot);
}

static inline void sort3(uint32_t *v)
{
    uint32_t t;
    if (v[0] > v[1]) { t = v[0]; v[0] = v[1]; v[1] = t; }
    if (v[1] > v[2]) { t = v[1]; v[1] = v[2]; v[2] = t; }
    if (v[0] > v[1]) { t = v[0]; v[0] = v[1]; v[1] = t; }
}

static inline void point_box(const double *pts, size_t n, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) { lo[k] = DBL_MAX; hi[k] = -DBL_MAX; }
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) { lo[k] = fmin(lo[k], pts[3 * i + k]); hi[k] = fmax(hi[k], pts[3 * i + k]); }
}

/* The diagonal of a box: the points' scale, which every tolerance here is a fraction of. */
static inline double box_diag(const double lo[3], const double hi[3])
{
    return sqrt((hi[0]-lo[0])*(hi[0]-lo[0]) + (hi[1]-lo[1])*(hi[1]-lo[1]) + (hi[2]-lo[2])*(hi[2]-lo[2]));
}

/* One qhull run: its state and the stream for its messages. qhull wants a stream; an in-memory
 * one needs no file system (a fopen of /dev/null fails in a sandbox or on a full descriptor
 * table, and was then reported as out of memory). What qhull writes past the buffer is dropped. */
typedef struct dl_qhull {
    qhT *qh;
    FILE *sink;
    int started, code;     /* code: qh_new_qhull's (qh_ERRsingular, ...) */
    char text[1024];
} dl_qhull;

/* Runs qhull on n points of dim coordinates with flags: BK_DELAUNAY_OK, NO_MEMORY or FAILED
 * (q->code says why). dl_qhull_end frees it whatever this returned. */
static inline int dl_qhull_run(dl_qhull *q, int dim, size_t n, coordT *coords, char *flags)
{
    q->qh = calloc(1, sizeof *q->qh);
    q->sink = fmemopen(q->text, sizeof q->text, "w");
    if (!q->qh || !q->sink) return BK_DELAUNAY_NO_MEMORY;
    qh_zero(q->qh, q->sink);
    q->started = 1;
    q->code = qh_new_qhull(q->qh, dim, (int)n, coords, False, flags, NULL, q->sink);
    return q->code == qh_ERRmem ? BK_DELAUNAY_NO_MEMORY : q->code ? BK_DELAUNAY_FAILED : BK_DELAUNAY_OK;
}

static inline void dl_qhull_end(dl_qhull *q)
{
    if (q->started) {
        int curlong, totlong;
        qh_freeqhull(q->qh, !qh_ALL);
        qh_memfreeshort(q->qh, &curlong, &totlong);
    }
    if (q->sink) fclose(q->sink);
    free(q->qh);
}

/* ---- the lifted path (delaunay_lifted.c) ---------------------------------------------------- */

/* Per point, the squared distance to its nearest neighbour (the tie-breaking weights' scale). */
int bk_dl_nearest_sq(const double *pts, size_t n, double *nn2);
enum bk_dl_ghosts {
    BK_DL_NO_GHOSTS,
    BK_DL_BOX_GHOSTS,   /* beyond each face of the points' box holding many of them */
    BK_DL_HULL_GHOSTS   /* beyond each facet of the points' convex hull holding many of them */
};
/* BK_DELAUNAY_OK with every lower facet of the weighted, ghosted lift a tetrahedron in *out and
 * every point in one; BK_DELAUNAY_FAILED when that did not hold (the caller falls back). */
int bk_dl_lifted(const double *pts, size_t n, const double *nn2, enum bk_dl_ghosts ghosts, tet_list *out);
/* Appends to tl the tetrahedra filling the pockets the ghosts cut between m (the canonical mesh
 * of tl, every point a vertex) and the points' hull; *hull_volume gets the hull's volume for the
 * caller's check, *filled how many were appended. */
int bk_dl_fill_pockets(const double *pts, size_t n, const double *nn2, const bk_tetmesh *m, tet_list *tl,
                       double *hull_volume, size_t *filled);

#endif
