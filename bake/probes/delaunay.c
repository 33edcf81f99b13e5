/* Delaunay tetrahedralisation on top of libqhull_r.
 *
 * First the lifted path (delaunay_lifted.c): qhull's 4-d hull of the points lifted onto the
 * paraboloid with tiny tie-breaking weights and ghost points beside the hull's flat faces, which
 * leaves qhull nothing to merge — ×10 faster on lattices, the probe placement's common case —
 * then the pockets its ghosts cut into a hull with slanted sides filled. Where its checks fail,
 * qhull's own Delaunay ('d') is run WITHOUT triangulated output ('Qt'): where points are
 * cospherical (every cube of a regular grid) it returns one merged, non-simplicial Delaunay
 * cell, and we triangulate those cells ourselves with a "pulling" triangulation keyed on global
 * point indices. Each 2-face of a cell is computed as the
 * intersection of the vertex sets of the two cells that share it and is split by a fan from its
 * lowest-index vertex, so both sides of a shared face always agree and no zero-volume "glue"
 * tetrahedra are needed. 'Qt' by contrast triangulates each cell from its own first vertex and
 * leaves flat tetrahedra where the two sides disagree, and 'QJ' moves the points (randomly) and
 * leaves slivers. See bake/probes/PROBES.md. */
#include "bake/probes/delaunay_parts.h"
#include "bake/probes/probe_math.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A tetrahedron whose volume is below this fraction of its longest edge cubed is flat. A regular
 * tetrahedron scores 0.118; genuine Delaunay slivers of sane input stay far above 1e-9. */
#define FLAT_VOLUME_RATIO 1e-9
/* The lifted result with its pockets filled must have the hull's volume within this, relative. */
#define POCKET_VOLUME_TOLERANCE 1e-6

const char *bk_delaunay_status_name(int status)
{
    switch (status) {
    case BK_DELAUNAY_OK: return "ok";
    case BK_DELAUNAY_TOO_FEW: return "fewer than 4 distinct points";
    case BK_DELAUNAY_FLAT: return "all points on one plane";
    case BK_DELAUNAY_NO_MEMORY: return "out of memory";
    case BK_DELAUNAY_FAILED: return "qhull failed";
    default: return "unknown";
    }
}

double bk_tet_signed_volume(const float *p0, const float *p1, const float *p2, const float *p3)
{
    double a[3] = {p0[0], p0[1], p0[2]}, b[3] = {p1[0], p1[1], p1[2]};
    double c[3] = {p2[0], p2[1], p2[2]}, d[3] = {p3[0], p3[1], p3[2]};
    return orient(a, b, c, d) / 6.0;
}

void bk_tetmesh_free(bk_tetmesh *m)
{
    if (!m) return;
    free(m->points);
    free(m->point_source);
    free(m->input_to_point);
    free(m->tets);
    free(m->neighbours);
    memset(m, 0, sizeof *m);
}

static int cmp_tet_sorted(const void *pa, const void *pb)
{
    const uint32_t *a = pa, *b = pb;  /* records of 8: sorted tuple then oriented tuple */
    for (int k = 0; k < 4; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}

/* ---- triangulation of one merged (non-simplicial) Delaunay cell --------------------------- */
typedef struct angle_item { double angle; uint32_t id; } angle_item;

static int cmp_angle(const void *pa, const void *pb)
{
    const angle_item *a = pa, *b = pb;
    if (a->angle != b->angle) return a->angle < b->angle ? -1 : 1;
    return (a->id > b->id) - (a->id < b->id);
}

/* Fans the convex polygon with (ascending) vertex set face[0..n) from its lowest vertex and
 * cones each triangle to apex. The result depends only on the vertex set, so the two cells
 * that share the face split it the same way. */
static void cone_over_face(tet_list *out, const double *pts, uint32_t apex, const uint32_t *face,
                           size_t n, angle_item *scratch)
{
    if (n < 3) return;
    if (n == 3) { tet_push(out, apex, face[0], face[1], face[2]); return; }
    const double *p0 = pts + 3 * (size_t)face[0];
    size_t far = 1; double best = -1.0;
    for (size_t i = 1; i < n; i++) {
        const double *p = pts + 3 * (size_t)face[i];
        double d = (p[0]-p0[0])*(p[0]-p0[0]) + (p[1]-p0[1])*(p[1]-p0[1]) + (p[2]-p0[2])*(p[2]-p0[2]);
        if (d > best) { best = d; far = i; }
    }
    const double *p1 = pts + 3 * (size_t)face[far];
    double u[3] = {p1[0]-p0[0], p1[1]-p0[1], p1[2]-p0[2]}, nrm[3] = {0, 0, 0};
    best = -1.0;
    for (size_t i = 1; i < n; i++) {
        const double *p = pts + 3 * (size_t)face[i];
        double w[3] = {p[0]-p0[0], p[1]-p0[1], p[2]-p0[2]};
        double c[3] = {u[1]*w[2]-u[2]*w[1], u[2]*w[0]-u[0]*w[2], u[0]*w[1]-u[1]*w[0]};
        double l = c[0]*c[0] + c[1]*c[1] + c[2]*c[2];
        if (l > best) { best = l; nrm[0] = c[0]; nrm[1] = c[1]; nrm[2] = c[2]; }
    }
    if (!(best > 0.0)) return;  /* collinear face: contributes no volume */
    double ul = sqrt(u[0]*u[0] + u[1]*u[1] + u[2]*u[2]), nl = sqrt(best);
    double e0[3] = {u[0]/ul, u[1]/ul, u[2]/ul}, nn[3] = {nrm[0]/nl, nrm[1]/nl, nrm[2]/nl};
    double e1[3] = {nn[1]*e0[2]-nn[2]*e0[1], nn[2]*e0[0]-nn[0]*e0[2], nn[0]*e0[1]-nn[1]*e0[0]};
    double cen[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) cen[k] += pts[3 * (size_t)face[i] + k] / (double)n;
    size_t start = 0;
    for (size_t i = 0; i < n; i++) {
        const double *p = pts + 3 * (size_t)face[i];
        double d[3] = {p[0]-cen[0], p[1]-cen[1], p[2]-cen[2]};
        scratch[i].angle = atan2(d[0]*e1[0] + d[1]*e1[1] + d[2]*e1[2], d[0]*e0[0] + d[1]*e0[1] + d[2]*e0[2]);
        scratch[i].id = face[i];
    }
    qsort(scratch, n, sizeof *scratch, cmp_angle);
    for (size_t i = 0; i < n; i++) if (scratch[i].id == face[0]) start = i;
    /* fan from face[0] (the lowest index); triangles along an edge through it are flat */
    double edge_scale = best;  /* |u × w|² of the widest triangle: a scale for flatness */
    for (size_t k = 1; k + 1 < n; k++) {
        uint32_t b = scratch[(start + k) % n].id, c = scratch[(start + k + 1) % n].id;
        const double *pb = pts + 3 * (size_t)b, *pc = pts + 3 * (size_t)c;
        double v1[3] = {pb[0]-p0[0], pb[1]-p0[1], pb[2]-p0[2]}, v2[3] = {pc[0]-p0[0], pc[1]-p0[1], pc[2]-p0[2]};
        double cr[3] = {v1[1]*v2[2]-v1[2]*v2[1], v1[2]*v2[0]-v1[0]*v2[2], v1[0]*v2[1]-v1[1]*v2[0]};
        if (cr[0]*cr[0] + cr[1]*cr[1] + cr[2]*cr[2] <= 1e-18 * edge_scale) continue;
        tet_push(out, apex, face[0], b, c);
    }
}

static size_t facet_point_ids(qhT *qh, facetT *facet, uint32_t *ids, size_t cap)
{
    vertexT *vertex, **vertexp;
    size_t n = 0;
    FOREACHvertex_(facet->vertices) {
        if (n < cap) ids[n] = (uint32_t)qh_pointid(qh, vertex->point);
        n++;
    }
    if (n <= cap) qsort(ids, n, sizeof *ids, cmp_u32);
    return n;
}

/* Grows the four per-facet scratch buffers to cap entries together (a huge cospherical cell).
 * 0 when out of memory; every pointer stays valid (grown or not) for the caller to free. */
static int scratch_grow(size_t cap, uint32_t **ids, uint32_t **nids, uint32_t **common, angle_item **scratch)
{
    uint32_t *a = realloc(*ids, cap * sizeof *a); if (a) *ids = a;
    uint32_t *b = realloc(*nids, cap * sizeof *b); if (b) *nids = b;
    uint32_t *c = realloc(*common, cap * sizeof *c); if (c) *common = c;
    angle_item *s = realloc(*scratch, cap * sizeof *s); if (s) *scratch = s;
    return a && b && c && s;
}

static int run_qhull(const double *pts, size_t n, tet_list *out)
{
    int status = BK_DELAUNAY_OK;
    dl_qhull q = {0};
    qhT *qh = NULL;
    coordT *coords = malloc(3 * n * sizeof *coords);
    uint32_t *ids = NULL, *nids = NULL, *common = NULL;
    angle_item *scratch = NULL;
    if (!coords) { status = BK_DELAUNAY_NO_MEMORY; goto freeqh; }
    memcpy(coords, pts, 3 * n * sizeof *coords);
    char flags[] = "qhull d Qbb Qc Qz Q12";
    status = dl_qhull_run(&q, 3, n, coords, flags);
    if (q.code == qh_ERRsingular) status = BK_DELAUNAY_FLAT;
    if (status != BK_DELAUNAY_OK) goto freeqh;
    qh = q.qh;

    size_t cap = 64;
    ids = malloc(cap * sizeof *ids); nids = malloc(cap * sizeof *nids);
    common = malloc(cap * sizeof *common); scratch = malloc(cap * sizeof *scratch);
    if (!ids || !nids || !common || !scratch) { status = BK_DELAUNAY_NO_MEMORY; goto freeqh; }

    facetT *facet, *neighbor, **neighborp;
    FORALLfacets {
        if (facet->upperdelaunay) continue;
        size_t k = facet_point_ids(qh, facet, ids, cap);
        if (k > cap) {  /* a huge cospherical cell: grow the scratch buffers and retry */
            cap = k;
            if (!scratch_grow(cap, &ids, &nids, &common, &scratch)) { status = BK_DELAUNAY_NO_MEMORY; goto freeqh; }
            k = facet_point_ids(qh, facet, ids, cap);
        }
        if (k < 4 || ids[k - 1] >= n) continue;  /* the point at infinity ('Qz') */
        if (k == 4) { tet_push(out, ids[0], ids[1], ids[2], ids[3]); continue; }
        uint32_t apex = ids[0];
        FOREACHneighbor_(facet) {
            size_t m = facet_point_ids(qh, neighbor, nids, cap);
            if (m > cap) {
                cap = m;
                if (!scratch_grow(cap, &ids, &nids, &common, &scratch)) { status = BK_DELAUNAY_NO_MEMORY; goto freeqh; }
                k = facet_point_ids(qh, facet, ids, cap);
                m = facet_point_ids(qh, neighbor, nids, cap);
            }
            size_t c = 0, i = 0, j = 0;
            while (i < k && j < m) {
                if (ids[i] == nids[j]) { common[c++] = ids[i]; i++; j++; }
                else if (ids[i] < nids[j]) i++;
                else j++;
            }
            if (c < 3 || common[0] == apex) continue;  /* faces through the apex: no volume */
            cone_over_face(out, pts, apex, common, c, scratch);
        }
    }
    if (out->oom) status = BK_DELAUNAY_NO_MEMORY;
freeqh:
    dl_qhull_end(&q);
    free(ids); free(nids); free(common); free(scratch);
    free(coords);
    return status;
}

/* ---- bk_delaunay, step by step ---------------------------------------------------------- */

static int finite_point(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

/* Bounding box of the finite points; returns how many there are. */
static size_t finite_bounds(const float *points, size_t count, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = DBL_MAX;
        hi[k] = -DBL_MAX;
    }
    size_t finite = 0;
    for (size_t i = 0; i < count; i++) {
        const float *p = points + 3 * i;
        if (!finite_point(p)) continue;
        finite++;
        for (int k = 0; k < 3; k++) {
            if (p[k] < lo[k]) lo[k] = p[k];
            if (p[k] > hi[k]) hi[k] = p[k];
        }
    }
    return finite;
}

/* Merges points within eps: binned into cells of size eps, each point looks in the 27 cells
 * around it for an earlier representative. rep[i] gets i's representative (itself when it is
 * one, BK_TET_NONE when not finite), *distinct how many representatives there are. */
static int merge_close_points(const float *points, size_t count, const double lo[3], double eps, uint32_t *rep,
                              size_t *distinct, size_t *merged)
{
    cell_key *keys = malloc((count ? count : 1) * sizeof *keys);
    if (!keys) return BK_DELAUNAY_NO_MEMORY;
    size_t nk = 0;
    for (size_t i = 0; i < count; i++) {
        const float *p = points + 3 * i;
        rep[i] = BK_TET_NONE;
        if (!finite_point(p)) continue;
        keys[nk].x = (int64_t)floor((p[0] - lo[0]) / eps);
        keys[nk].y = (int64_t)floor((p[1] - lo[1]) / eps);
        keys[nk].z = (int64_t)floor((p[2] - lo[2]) / eps);
        keys[nk].index = (uint32_t)i;
        nk++;
    }
    qsort(keys, nk, sizeof *keys, cmp_cell_key);
    size_t nd = 0;
    for (size_t i = 0; i < count; i++) {
        const float *p = points + 3 * i;
        if (!finite_point(p)) continue;
        int64_t cx = (int64_t)floor((p[0] - lo[0]) / eps), cy = (int64_t)floor((p[1] - lo[1]) / eps);
        int64_t cz = (int64_t)floor((p[2] - lo[2]) / eps);
        uint32_t best = BK_TET_NONE;
        for (int dx = -1; dx <= 1; dx++) for (int dy = -1; dy <= 1; dy++) for (int dz = -1; dz <= 1; dz++) {
            size_t s = lower_bound_cell(keys, nk, cx + dx, cy + dy, cz + dz);
            for (; s < nk && keys[s].x == cx + dx && keys[s].y == cy + dy && keys[s].z == cz + dz; s++) {
                uint32_t j = keys[s].index;
                if (j >= i) break;             /* sorted by index within a cell */
                if (rep[j] != j || j >= best) continue;
                const float *q = points + 3 * (size_t)j;
                double ddx = (double)p[0] - q[0], ddy = (double)p[1] - q[1], ddz = (double)p[2] - q[2];
                if (ddx*ddx + ddy*ddy + ddz*ddz <= eps * eps) best = j;
            }
        }
        if (best == BK_TET_NONE) { rep[i] = (uint32_t)i; nd++; }
        else { rep[i] = best; (*merged)++; }
    }
    free(keys);
    *distinct = nd;
    return BK_DELAUNAY_OK;
}

/* The nd representatives in input order (*distinct_out: their input indices) as doubles,
 * centred on the bounding box so far-from-origin levels keep precision. */
static int centred_distinct_points(const float *points, size_t count, const uint32_t *rep, size_t nd,
                                   const double lo[3], const double hi[3], uint32_t **distinct_out,
                                   double **pts_out)
{
    uint32_t *distinct = *distinct_out = malloc(nd * sizeof *distinct);
    double *pts = *pts_out = malloc(3 * nd * sizeof *pts);
    if (!distinct || !pts) return BK_DELAUNAY_NO_MEMORY;
    double centre[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    size_t d = 0;
    for (size_t i = 0; i < count; i++) {
        if (rep[i] != i) continue;
        distinct[d] = (uint32_t)i;
        for (int k = 0; k < 3; k++) pts[3 * d + k] = (double)points[3 * i + k] - centre[k];
        d++;
    }
    return BK_DELAUNAY_OK;
}

/* Points within eps of their least-squares plane span no volume. qhull would find
 * float-rounding-thin tetrahedra there instead of refusing. */
static int spans_no_volume(const double *pts, size_t nd, double eps)
{
    double mean[3] = {0, 0, 0}, cov[9] = {0}, val[3], vec[3][3], dev = 0.0;
    for (size_t d = 0; d < nd; d++) for (int k = 0; k < 3; k++) mean[k] += pts[3 * d + k] / (double)nd;
    for (size_t d = 0; d < nd; d++)
        for (int r = 0; r < 3; r++) for (int c = 0; c < 3; c++)
            cov[3 * r + c] += (pts[3 * d + r] - mean[r]) * (pts[3 * d + c] - mean[c]);
    bk_sym3_eigen(cov, val, vec);
    for (size_t d = 0; d < nd; d++) {
        double x = 0.0;
        for (int k = 0; k < 3; k++) x += (pts[3 * d + k] - mean[k]) * vec[2][k];
        if (fabs(x) > dev) dev = fabs(x);
    }
    return dev <= eps;
}

/* 1 when the tetrahedron is flat by FLAT_VOLUME_RATIO; *orientation gets its orient(). */
static int tet_is_flat(const double *a, const double *b, const double *c, const double *d, double *orientation)
{
    double o = orient(a, b, c, d);
    double l = 0.0;
    const double *q[4] = {a, b, c, d};
    for (int x = 0; x < 4; x++) for (int y = x + 1; y < 4; y++) {
        double e = (q[x][0]-q[y][0])*(q[x][0]-q[y][0]) + (q[x][1]-q[y][1])*(q[x][1]-q[y][1]) + (q[x][2]-q[y][2])*(q[x][2]-q[y][2]);
        if (e > l) l = e;
    }
    *orientation = o;
    return !(fabs(o) / 6.0 > FLAT_VOLUME_RATIO * l * sqrt(l));
}

/* qhull's tetrahedra oriented positively, flat ones dropped, duplicates removed, in canonical
 * order: records of 8 (sorted vertex tuple, then the oriented tuple) in *recs_out. */
static int canonical_tets(const tet_list *tl, const double *pts, uint32_t **recs_out, size_t *count_out,
                          size_t *dropped_flat)
{
    uint32_t *recs = *recs_out = malloc((tl->n ? tl->n : 1) * 8 * sizeof *recs);
    if (!recs) return BK_DELAUNAY_NO_MEMORY;
    size_t nt = 0;
    for (size_t t = 0; t < tl->n; t++) {
        const uint32_t *v = tl->v + 4 * t;
        double o;
        if (tet_is_flat(pts + 3 * (size_t)v[0], pts + 3 * (size_t)v[1], pts + 3 * (size_t)v[2],
                        pts + 3 * (size_t)v[3], &o)) {
            (*dropped_flat)++;
            continue;
        }
        uint32_t *r = recs + 8 * nt++;
        memcpy(r, v, 4 * sizeof *r);
        /* insertion sort of the tuple */
        for (int x = 1; x < 4; x++) for (int y = x; y > 0 && r[y-1] > r[y]; y--) { uint32_t s = r[y]; r[y] = r[y-1]; r[y-1] = s; }
        r[4] = v[0]; r[5] = v[1];
        if (o > 0) { r[6] = v[2]; r[7] = v[3]; } else { r[6] = v[3]; r[7] = v[2]; }
    }
    qsort(recs, nt, 8 * sizeof *recs, cmp_tet_sorted);
    size_t unique = 0;
    for (size_t t = 0; t < nt; t++) {
        if (unique && memcmp(recs + 8 * (unique - 1), recs + 8 * t, 4 * sizeof *recs) == 0) continue;
        memmove(recs + 8 * unique, recs + 8 * t, 8 * sizeof *recs);
        unique++;
    }
    *count_out = unique;
    return unique ? BK_DELAUNAY_OK : BK_DELAUNAY_FLAT;
}

/* The mesh from the canonical records: the distinct points some tetrahedron uses become the
 * vertices (in input order), every input point maps to its representative's vertex, the
 * tetrahedra are renumbered onto them and their volume summed. */
static int mesh_from_tets(const float *points, size_t count, const uint32_t *rep, const uint32_t *distinct,
                          size_t nd, const uint32_t *recs, size_t nt, bk_tetmesh *out)
{
    uint32_t *vertex_of = calloc(nd, sizeof *vertex_of); /* distinct index -> vertex index + 1 */
    if (!vertex_of) return BK_DELAUNAY_NO_MEMORY;
    for (size_t t = 0; t < nt; t++) for (int k = 0; k < 4; k++) vertex_of[recs[8 * t + k]] = 1;
    size_t np = 0;
    for (size_t d = 0; d < nd; d++) if (vertex_of[d]) vertex_of[d] = (uint32_t)++np;
    out->unused_count = nd - np;
    out->point_count = np;
    out->points = malloc(3 * np * sizeof *out->points);
    out->point_source = malloc(np * sizeof *out->point_source);
    out->tets = malloc(4 * nt * sizeof *out->tets);
    if (!out->points || !out->point_source || !out->tets) {
        free(vertex_of);
        return BK_DELAUNAY_NO_MEMORY;
    }
    for (size_t d = 0; d < nd; d++) {
        if (!vertex_of[d]) continue;
        uint32_t v = vertex_of[d] - 1, src = distinct[d];
        out->point_source[v] = src;
        memcpy(out->points + 3 * (size_t)v, points + 3 * (size_t)src, 3 * sizeof(float));
    }
    for (size_t i = 0; i < count; i++)
        if (rep[i] != BK_TET_NONE) {
            /* rep[i] is an input index; find its distinct slot by binary search */
            size_t a = 0, b = nd;
            while (a < b) { size_t mid = (a + b) / 2; if (distinct[mid] < rep[i]) a = mid + 1; else b = mid; }
            out->input_to_point[i] = vertex_of[a] ? vertex_of[a] - 1 : BK_TET_NONE;
        }
    out->tet_count = nt;
    for (size_t t = 0; t < nt; t++) {
        for (int k = 0; k < 4; k++) out->tets[4 * t + k] = vertex_of[recs[8 * t + 4 + k]] - 1;
        const float *P = out->points;
        const uint32_t *v = out->tets + 4 * t;
        out->volume += bk_tet_signed_volume(P + 3 * (size_t)v[0], P + 3 * (size_t)v[1],
                                            P + 3 * (size_t)v[2], P + 3 * (size_t)v[3]);
    }
    free(vertex_of);
    return BK_DELAUNAY_OK;
}

/* Adjacency by face sorting: faces shared by exactly two tetrahedra are linked, faces shared
 * by more are counted as non-manifold. */
static int link_neighbours(bk_tetmesh *out)
{
    size_t nt = out->tet_count;
    out->neighbours = malloc((nt ? 4 * nt : 1) * sizeof *out->neighbours);
    face_rec *faces = malloc((nt ? 4 * nt : 1) * sizeof *faces);
    if (!out->neighbours || !faces) {
        free(faces);
        return BK_DELAUNAY_NO_MEMORY;
    }
    for (size_t t = 0; t < nt; t++)
        for (uint32_t i = 0; i < 4; i++) {
            face_rec *f = faces + 4 * t + i;
            int w = 0;
            for (int k = 0; k < 4; k++) if ((uint32_t)k != i) f->v[w++] = out->tets[4 * t + k];
            sort3(f->v);
            f->tet = (uint32_t)t; f->slot = i;
            out->neighbours[4 * t + i] = BK_TET_NONE;
        }
    qsort(faces, 4 * nt, sizeof *faces, cmp_face);
    for (size_t s = 0; s < 4 * nt;) {
        size_t e = s + 1;
        while (e < 4 * nt && memcmp(faces[e].v, faces[s].v, sizeof faces[s].v) == 0) e++;
        if (e - s == 2) {
            out->neighbours[4 * (size_t)faces[s].tet + faces[s].slot] = faces[s + 1].tet;
            out->neighbours[4 * (size_t)faces[s + 1].tet + faces[s + 1].slot] = faces[s].tet;
        } else if (e - s > 2) {
            out->nonmanifold_faces++;
        }
        s = e;
    }
    free(faces);
    return BK_DELAUNAY_OK;
}

/* ---- the hull check of the lifted path -------------------------------------------------------
 * The mesh covers the points' convex hull exactly when every point is a vertex (checked in
bk_dl_lifted) and its boundary is convex; a closed, connected, locally convex surface
 * bounds a convex body, so checking each boundary edge's two faces suffices: the far vertex of
 * one face must not lie outside the other's plane. A ghost lifted too low would cut a dent. */
typedef struct edge_rec { uint32_t a, b, face; } edge_rec;

static int cmp_edge(const void *pa, const void *pb)
{
    const edge_rec *x = pa, *y = pb;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    if (x->b != y->b) return x->b < y->b ? -1 : 1;
    return x->face < y->face ? -1 : x->face > y->face;
}

static void vertex_d(const bk_tetmesh *m, uint32_t v, double out[3])
{
    for (int k = 0; k < 3; k++) out[k] = m->points[3 * (size_t)v + k];
}

/* 1 when w lies outside the plane of face f (3 vertices, the tetrahedron's side positive). */
static int outside_face(const bk_tetmesh *m, const uint32_t *f, uint32_t w)
{
    double a[3], b[3], c[3], d[3];
    vertex_d(m, f[0], a); vertex_d(m, f[1], b); vertex_d(m, f[2], c); vertex_d(m, w, d);
    double l = 0.0;
    const double *q[4] = {a, b, c, d};
    for (int x = 0; x < 4; x++) for (int y = x + 1; y < 4; y++)
        l = fmax(l, (q[x][0]-q[y][0])*(q[x][0]-q[y][0]) + (q[x][1]-q[y][1])*(q[x][1]-q[y][1]) + (q[x][2]-q[y][2])*(q[x][2]-q[y][2]));
    return orient(a, b, c, d) < -FLAT_VOLUME_RATIO * 6.0 * l * sqrt(l);
}

static int boundary_is_convex(const bk_tetmesh *m, int *convex)
{
    size_t nf = 0;
    for (size_t k = 0; k < 4 * m->tet_count; k++) nf += m->neighbours[k] == BK_TET_NONE;
    uint32_t (*face)[3] = malloc((nf ? nf : 1) * sizeof *face);
    edge_rec *edges = malloc((nf ? 3 * nf : 1) * sizeof *edges);
    if (!face || !edges) { free(face); free(edges); return BK_DELAUNAY_NO_MEMORY; }
    size_t f = 0;
    for (size_t t = 0; t < m->tet_count; t++)
        for (int i = 0; i < 4; i++) {
            if (m->neighbours[4 * t + i] != BK_TET_NONE) continue;
            const uint32_t *v = m->tets + 4 * t;
            uint32_t *o = face[f];
            int w = 0;
            for (int k = 0; k < 4; k++) if (k != i) o[w++] = v[k];
            double a[3], b[3], c[3], d[3];
            vertex_d(m, o[0], a); vertex_d(m, o[1], b); vertex_d(m, o[2], c); vertex_d(m, v[i], d);
            if (orient(a, b, c, d) < 0) { uint32_t x = o[1]; o[1] = o[2]; o[2] = x; }
            for (int e = 0; e < 3; e++) {
                uint32_t p = o[e], q = o[(e + 1) % 3];
                edges[3 * f + e] = (edge_rec){p < q ? p : q, p < q ? q : p, (uint32_t)f};
            }
            f++;
        }
    qsort(edges, 3 * nf, sizeof *edges, cmp_edge);
    *convex = nf >= 4;
    for (size_t e = 0; *convex && e < 3 * nf; e += 2) {
        if (e + 1 >= 3 * nf || edges[e + 1].a != edges[e].a || edges[e + 1].b != edges[e].b ||
            (e + 2 < 3 * nf && edges[e + 2].a == edges[e].a && edges[e + 2].b == edges[e].b)) {
            *convex = 0; /* an edge not shared by exactly two boundary faces */
            break;
        }
        const uint32_t *F = face[edges[e].face], *G = face[edges[e + 1].face];
        uint32_t w = G[0] + G[1] + G[2] - edges[e].a - edges[e].b; /* G's vertex off the edge */
        if (outside_face(m, F, w)) *convex = 0;
    }
    free(face);
    free(edges);
    return BK_DELAUNAY_OK;
}

/* A failed run keeps only what says why: the input count, the merges and an all-unused
 * input_to_point. */
static void clear_failed_mesh(bk_tetmesh *out, size_t count)
{
    uint32_t *keep = out->input_to_point;
    size_t merged = out->merged_count;
    out->input_to_point = NULL;
    bk_tetmesh_free(out);
    out->input_to_point = keep;
    out->input_count = count;
    out->merged_count = merged;
    if (keep) for (size_t i = 0; i < count; i++) keep[i] = BK_TET_NONE;
}

/* The canonical mesh of tl and its neighbours; on the lifted path, BK_DELAUNAY_FAILED for any
 * result bk_delaunay would not keep, and *convex says whether its boundary is. */
static int mesh_of(const float *points, size_t count, const uint32_t *rep, const uint32_t *distinct,
                   const double *pts, size_t nd, const tet_list *tl, int merged, bk_tetmesh *out, int *convex)
{
    uint32_t *recs = NULL;
    size_t nt = 0;
    int status = canonical_tets(tl, pts, &recs, &nt, &out->dropped_flat);
    if (status == BK_DELAUNAY_OK) status = mesh_from_tets(points, count, rep, distinct, nd, recs, nt, out);
    if (status == BK_DELAUNAY_OK) status = link_neighbours(out);
    *convex = 0;
    if (status == BK_DELAUNAY_OK && !merged) {
        status = boundary_is_convex(out, convex);
        if (status == BK_DELAUNAY_OK && (out->dropped_flat || out->nonmanifold_faces || out->unused_count))
            status = BK_DELAUNAY_FAILED;
    }
    if (!merged && status == BK_DELAUNAY_FLAT) status = BK_DELAUNAY_FAILED; /* nothing kept: try merged */
    free(recs);
    return status;
}

/* One try of the lifted path with the given ghosts: the weighted lower hull, its pockets filled
 * when its boundary is not convex (then checked again, with its volume against the hull's). */
static int lifted_try(const float *points, size_t count, const uint32_t *rep, const uint32_t *distinct,
                      const double *pts, size_t nd, const double *nn2, enum bk_dl_ghosts ghosts, tet_list *tl,
                      bk_tetmesh *out)
{
    int convex = 0, status = bk_dl_lifted(pts, nd, nn2, ghosts, tl);
    if (status == BK_DELAUNAY_OK) status = mesh_of(points, count, rep, distinct, pts, nd, tl, 0, out, &convex);
    if (status == BK_DELAUNAY_OK && !convex) {
        double hull_volume = 0.0;
        size_t filled = 0;
        status = bk_dl_fill_pockets(pts, nd, nn2, out, tl, &hull_volume, &filled);
        clear_failed_mesh(out, count);
        if (status == BK_DELAUNAY_OK) status = mesh_of(points, count, rep, distinct, pts, nd, tl, 0, out, &convex);
        out->pocket_tets = filled;
        if (status == BK_DELAUNAY_OK &&
            (!convex || !(fabs(out->volume - hull_volume) <= POCKET_VOLUME_TOLERANCE * hull_volume)))
            status = BK_DELAUNAY_FAILED;
    }
    return status;
}

/* The lifted path: ghosts beside the box's faces first; where that fails (qhull's error on a
 * hull whose slanted facets hold rows of coplanar points, or any check but flatness), ghosts
 * beside the hull's facets. */
static int triangulate_lifted(const float *points, size_t count, const uint32_t *rep, const uint32_t *distinct,
                              const double *pts, size_t nd, tet_list *tl, bk_tetmesh *out)
{
    double *nn2 = malloc(nd * sizeof *nn2);
    if (!nn2) return BK_DELAUNAY_NO_MEMORY;
    int status = bk_dl_nearest_sq(pts, nd, nn2);
    if (status == BK_DELAUNAY_OK)
        status = lifted_try(points, count, rep, distinct, pts, nd, nn2, BK_DL_BOX_GHOSTS, tl, out);
    /* flat slivers (a hull in general position with near-flat sides) are the points' own: other
     * ghosts would leave them as flat */
    if (status == BK_DELAUNAY_FAILED && !out->dropped_flat) {
        clear_failed_mesh(out, count);
        tl->n = 0;
        tl->oom = 0;
        status = lifted_try(points, count, rep, distinct, pts, nd, nn2, BK_DL_HULL_GHOSTS, tl, out);
        out->hull_ghosts = 1;
    }
    free(nn2);
    return status;
}

/* qhull (lifted, or merged cells split), then the canonical mesh and its neighbours. On the
 * lifted path, BK_DELAUNAY_FAILED for any result bk_delaunay would not keep from it. */
static int triangulate(const float *points, size_t count, const uint32_t *rep, const uint32_t *distinct,
                       const double *pts, size_t nd, int merged, bk_tetmesh *out)
{
    tet_list tl = {0};
    int convex, status;
    if (merged) {
        status = run_qhull(pts, nd, &tl);
        if (status == BK_DELAUNAY_OK) status = mesh_of(points, count, rep, distinct, pts, nd, &tl, 1, out, &convex);
    } else {
        status = triangulate_lifted(points, count, rep, distinct, pts, nd, &tl, out);
    }
    free(tl.v);
    return status;
}

int bk_delaunay(const float *points, size_t count, const bk_delaunay_options *options,
                bk_tetmesh *out)
{
    memset(out, 0, sizeof *out);
    out->input_count = count;
    if (count > 0xFFFFFFF0u) return BK_DELAUNAY_FAILED;
    int status = BK_DELAUNAY_OK;
    uint32_t *rep = NULL, *distinct = NULL;
    double *pts = NULL;
    size_t nd = 0;
    out->input_to_point = malloc((count ? count : 1) * sizeof *out->input_to_point);
    rep = malloc((count ? count : 1) * sizeof *rep);
    if (!out->input_to_point || !rep) { status = BK_DELAUNAY_NO_MEMORY; goto done; }
    for (size_t i = 0; i < count; i++) out->input_to_point[i] = BK_TET_NONE;

    double lo[3], hi[3];
    if (finite_bounds(points, count, lo, hi) < 4) { status = BK_DELAUNAY_TOO_FEW; goto done; }
    double diag = box_diag(lo, hi);
    if (!(diag > 0.0)) { status = BK_DELAUNAY_TOO_FEW; goto done; }
    double eps = options && options->merge_distance > 0.0 ? options->merge_distance : 1e-6 * diag;
    if (eps < diag * 1e-12) eps = diag * 1e-12;  /* keeps cell keys within int64 */

    status = merge_close_points(points, count, lo, eps, rep, &nd, &out->merged_count);
    if (status == BK_DELAUNAY_OK && nd < 4) status = BK_DELAUNAY_TOO_FEW;
    if (status == BK_DELAUNAY_OK) status = centred_distinct_points(points, count, rep, nd, lo, hi, &distinct, &pts);
    if (status == BK_DELAUNAY_OK && spans_no_volume(pts, nd, eps)) status = BK_DELAUNAY_FLAT;
    int merged = out->merged_cells = options && options->merged_cells;
    if (status == BK_DELAUNAY_OK) status = triangulate(points, count, rep, distinct, pts, nd, merged, out);
    if (status == BK_DELAUNAY_FAILED && !merged) { /* the lifted path's checks failed */
        clear_failed_mesh(out, count);
        out->merged_cells = 1;
        status = triangulate(points, count, rep, distinct, pts, nd, 1, out);
    }
done:
    free(pts); free(distinct); free(rep);
    if (status != BK_DELAUNAY_OK) clear_failed_mesh(out, count);
    return status;
}
