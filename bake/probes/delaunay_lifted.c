/* The lifted path of bk_delaunay (delaunay.c): the regular triangulation of the points with
 * tie-breaking weights, from qhull's 4-d hull of their lift with ghosts beside the flat sides of
 * their box, and the pockets those ghosts cut into the hull filled afterwards. Why each step is
 * there: the comments below and bake/probes/PROBES.md. */
#include "bake/probes/delaunay_parts.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- the lifted path: a regular triangulation with tie-breaking weights --------------------
 * Delaunay is the lower hull of the points lifted onto the paraboloid |p|². On a lattice qhull's
 * time goes into merging facets: the cospherical corners of every cube, and above all the
 * vertical facets over the flat faces of the points' hull, each holding thousands of coplanar
 * points (about n^1.6 on lattices, PROBES.md). Both degeneracies are removed here:
 * - Each lift is lowered by a tiny weight (a hash of the point's index times 10⁻³ of its nearest
 *   neighbour's distance squared), which breaks every cospherical tie. The lower hull is then
 *   the regular triangulation of the same, unmoved points: exactly Delaunay wherever the points
 *   are not within 10⁻³ of cospherical, one valid choice among the ties where they are. No
 *   tetrahedron can be flat (four coplanar points lift onto a vertical hyperplane, never a lower
 *   facet) and the weights depend only on the points and their order: deterministic.
 * - Ghost points beyond each face of the bounding box that holds many points (a lattice's
 *   sides), lifted above the paraboloid, so that the face's points make no vertical facet;
 *   lower facets through a ghost lie outside the points' hull and are dropped. Only there: a
 *   ghost near a sliver of a hull in general position (its circumsphere reaching the ghost)
 *   would cut into it, and such hulls have no big flat faces to merge.
 * - qhull runs without pre-merging ('Q0'): nothing should need merging, and its pre-merge merged
 *   facets of a two-layer town lattice anyway.
 * A boundary that is not convex (a ghost cut into the hull) has its pockets filled (below). Where
 * the box's ghosts fail, the caller tries ghosts beside the hull's facets (hull_ghosts). Any other
 * sign that this did not hold — a lower facet of more than 4 vertices, a point in no tetrahedron,
 * a flat or non-manifold result, a pocket not filled — falls back to run_qhull's merged cells
 * (bk_tetmesh.merged_cells). */
#define LIFT_TIE_WEIGHT 1e-3
#define LIFT_NN_CANDIDATES 64
#define LIFT_GHOST_MIN_POINTS 16  /* a face of the box holding this many points gets ghosts */
#define LIFT_FACE_TOLERANCE 1e-7  /* on a face of the box: this close, in units of the points' radius */
#define LIFT_GHOST_PATCH 256.0    /* face points per ghost, about */
#define LIFT_GHOST_GRID 64        /* most ghosts along a face's side */
#define LIFT_GHOSTS (6 * LIFT_GHOST_GRID * LIFT_GHOST_GRID)
#define LIFT_GHOST_DISTANCE 4.0   /* beyond the face, in patch sizes */
#define LIFT_GHOST_HEIGHT 16.0    /* above the paraboloid, × its distance squared: it cuts no
                                     boundary tetrahedron whose circumsphere is under ~4 distances
                                     (1 and 1: 5 of 12 generated levels' slivers were cut) */
/* On a facet of the points' hull, in units of their diagonal: for the facet's ghosts (loose: a
 * point counted wrongly only moves a ghost) and for a pocket's walls (tight: a wall taken for the
 * hull leaves its pocket unfilled, which the checks refuse) */
#define LIFT_HULL_FACET_TOLERANCE 1e-6
#define POCKET_HULL_TOLERANCE 1e-7

static double index_unit(uint64_t i) /* splitmix64 of the index, in [0, 1) */
{
    uint64_t z = i + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

/* Per point, the squared distance to the nearest other point among those in the 27 grid cells
 * around it (the first LIFT_NN_CANDIDATES of them); cell² where none is found. An overestimate
 * only makes a weight larger, which the checks after qhull catch if it ever hides a point. */
int bk_dl_nearest_sq(const double *pts, size_t n, double *nn2)
{
    double lo[3], hi[3];
    point_box(pts, n, lo, hi);
    double ext[3], vol = 1.0, diag = box_diag(lo, hi);
    for (int k = 0; k < 3; k++) ext[k] = hi[k] - lo[k];
    for (int k = 0; k < 3; k++) vol *= fmax(ext[k], 1e-3 * diag);
    double cell = cbrt(vol / (double)n) * 1.5;
    cell_key *keys = malloc(n * sizeof *keys);
    if (!keys) return BK_DELAUNAY_NO_MEMORY;
    for (size_t i = 0; i < n; i++) {
        keys[i].x = (int64_t)floor((pts[3 * i] - lo[0]) / cell);
        keys[i].y = (int64_t)floor((pts[3 * i + 1] - lo[1]) / cell);
        keys[i].z = (int64_t)floor((pts[3 * i + 2] - lo[2]) / cell);
        keys[i].index = (uint32_t)i;
    }
    qsort(keys, n, sizeof *keys, cmp_cell_key);
    for (size_t i = 0; i < n; i++) {
        const double *p = pts + 3 * i;
        int64_t c[3];
        for (int k = 0; k < 3; k++) c[k] = (int64_t)floor((p[k] - lo[k]) / cell);
        double best = cell * cell;
        int seen = 0;
        for (int dx = -1; dx <= 1; dx++) for (int dy = -1; dy <= 1; dy++) for (int dz = -1; dz <= 1; dz++) {
            size_t s = lower_bound_cell(keys, n, c[0] + dx, c[1] + dy, c[2] + dz);
            for (; s < n && seen < LIFT_NN_CANDIDATES && keys[s].x == c[0] + dx && keys[s].y == c[1] + dy &&
                   keys[s].z == c[2] + dz; s++) {
                if (keys[s].index == i) continue;
                const double *q = pts + 3 * (size_t)keys[s].index;
                double d2 = (p[0]-q[0])*(p[0]-q[0]) + (p[1]-q[1])*(p[1]-q[1]) + (p[2]-q[2])*(p[2]-q[2]);
                if (d2 < best) best = d2;
                seen++;
            }
        }
        nn2[i] = best;
    }
    free(keys);
    return BK_DELAUNAY_OK;
}

typedef struct hull_plane { double n[3], offset; } hull_plane;

/* The facets of the points' convex hull (qhull's merged, coplanar ones one plane) and its
 * volume. */
static int hull_planes(const double *pts, size_t n, hull_plane **planes, size_t *count, double *volume)
{
    dl_qhull q = {0};
    coordT *coords = malloc(3 * n * sizeof *coords);
    *planes = NULL;
    *count = 0;
    int status = coords ? BK_DELAUNAY_OK : BK_DELAUNAY_NO_MEMORY;
    if (coords) memcpy(coords, pts, 3 * n * sizeof *coords);
    char flags[] = "qhull";
    if (status == BK_DELAUNAY_OK) status = dl_qhull_run(&q, 3, n, coords, flags);
    if (status == BK_DELAUNAY_OK) {
        qhT *qh = q.qh;
        facetT *facet;
        size_t k = 0;
        FORALLfacets k++;
        if ((*planes = malloc((k ? k : 1) * sizeof **planes))) {
            FORALLfacets {
                hull_plane *h = *planes + (*count)++;
                for (int j = 0; j < 3; j++) h->n[j] = facet->normal[j];
                h->offset = facet->offset;
            }
            qh_getarea(qh, qh->facet_list);
            *volume = qh->totvol;
        } else {
            status = BK_DELAUNAY_NO_MEMORY;
        }
    }
    dl_qhull_end(&q);
    free(coords);
    return status;
}

/* The ghosts beyond face f (axis f / 2, the high side when f is odd) of the box lo..hi holding m
 * points: a grid of patches of about LIFT_GHOST_PATCH points, one ghost at LIFT_GHOST_DISTANCE
 * patch sizes beyond each patch's centre (one ghost for a whole face made it a vertex of every
 * facet over the face, and qhull updates each vertex's neighbour set facet by facet: quadratic). */
static size_t face_ghosts(int f, size_t m, const double lo[3], const double hi[3], double r, coordT *out)
{
    int a = f / 2, b = (a + 1) % 3, c = (a + 2) % 3;
    double eb = fmax(hi[b] - lo[b], 1e-9 * r), ec = fmax(hi[c] - lo[c], 1e-9 * r);
    double g = sqrt(eb * ec / (double)m * LIFT_GHOST_PATCH);
    int nb = (int)fmin(ceil(eb / g), LIFT_GHOST_GRID), nc = (int)fmin(ceil(ec / g), LIFT_GHOST_GRID);
    double d = LIFT_GHOST_DISTANCE * fmax(eb / nb, ec / nc);
    size_t k = 0;
    for (int i = 0; i < nb; i++)
        for (int j = 0; j < nc; j++, k++) {
            coordT *q = out + 4 * k;
            q[a] = f & 1 ? hi[a] + d : lo[a] - d;
            q[b] = lo[b] + (i + 0.5) * eb / nb;
            q[c] = lo[c] + (j + 0.5) * ec / nc;
            q[3] = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + LIFT_GHOST_HEIGHT * d * d) / r;
        }
    return k;
}

/* The ghosts beyond every facet of the points' hull holding LIFT_GHOST_MIN_POINTS or more of
 * them, placed as face_ghosts places a box face's over the facet's extent in its plane, appended
 * to *c (which holds n lifted points and *count ghosts already, and is grown). For hulls whose
 * slanted facets hold rows of coplanar points (roofs of different heights): those lift onto
 * vertical facets, which qhull without pre-merging cannot always handle. */
static int hull_ghosts(const double *pts, size_t n, double r, coordT **c, size_t *count)
{
    hull_plane *planes = NULL;
    size_t np = 0;
    double volume, lo[3], hi[3];
    int status = hull_planes(pts, n, &planes, &np, &volume);
    if (status != BK_DELAUNAY_OK) return status;
    point_box(pts, n, lo, hi);
    double diag = box_diag(lo, hi);
    for (size_t f = 0; f < np && status == BK_DELAUNAY_OK; f++) {
        const double *nf = planes[f].n;
        /* a frame of the plane: u off the axis least along the normal */
        int a = fabs(nf[0]) <= fabs(nf[1]) && fabs(nf[0]) <= fabs(nf[2]) ? 0 : fabs(nf[1]) <= fabs(nf[2]) ? 1 : 2;
        double e[3] = {0, 0, 0}, u[3], v[3];
        e[a] = 1;
        u[0] = e[1] * nf[2] - e[2] * nf[1]; u[1] = e[2] * nf[0] - e[0] * nf[2]; u[2] = e[0] * nf[1] - e[1] * nf[0];
        double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (int k = 0; k < 3; k++) u[k] /= ul;
        v[0] = nf[1] * u[2] - nf[2] * u[1]; v[1] = nf[2] * u[0] - nf[0] * u[2]; v[2] = nf[0] * u[1] - nf[1] * u[0];
        double s0 = DBL_MAX, s1 = -DBL_MAX, t0 = DBL_MAX, t1 = -DBL_MAX;
        size_t on = 0;
        for (size_t i = 0; i < n; i++) {
            const double *p = pts + 3 * i;
            if (fabs(nf[0] * p[0] + nf[1] * p[1] + nf[2] * p[2] + planes[f].offset) > LIFT_HULL_FACET_TOLERANCE * diag)
                continue;
            double s = u[0] * p[0] + u[1] * p[1] + u[2] * p[2], t = v[0] * p[0] + v[1] * p[1] + v[2] * p[2];
            s0 = fmin(s0, s); s1 = fmax(s1, s); t0 = fmin(t0, t); t1 = fmax(t1, t);
            on++;
        }
        if (on < LIFT_GHOST_MIN_POINTS) continue;
        double es = fmax(s1 - s0, 1e-9 * r), et = fmax(t1 - t0, 1e-9 * r);
        double g = sqrt(es * et / (double)on * LIFT_GHOST_PATCH);
        int ns = (int)fmin(ceil(es / g), LIFT_GHOST_GRID), nt = (int)fmin(ceil(et / g), LIFT_GHOST_GRID);
        double d = LIFT_GHOST_DISTANCE * fmax(es / ns, et / nt);
        coordT *grown = realloc(*c, 4 * (n + *count + (size_t)ns * nt) * sizeof *grown);
        if (!grown) { status = BK_DELAUNAY_NO_MEMORY; break; }
        *c = grown;
        for (int i = 0; i < ns; i++)
            for (int j = 0; j < nt; j++) {
                coordT *q = *c + 4 * (n + (*count)++);
                double s = s0 + (i + 0.5) * es / ns, t = t0 + (j + 0.5) * et / nt, h = -planes[f].offset + d;
                for (int k = 0; k < 3; k++) q[k] = s * u[k] + t * v[k] + h * nf[k];
                q[3] = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + LIFT_GHOST_HEIGHT * d * d) / r;
            }
    }
    free(planes);
    return status;
}

/* The lifted points ids[0..m) (all n points when ids is NULL: 4 coordinates, the lift scaled to
 * their radius, which leaves the lower hull as it is), then the ghosts `ghosts` asks for (hull
 * ghosts: all points only). A point's weight depends on its index among all n points, so a
 * subset's ties break as the whole set's. */
static int lifted_points(const double *pts, const uint32_t *ids, size_t m, const double *nn2,
                         enum bk_dl_ghosts ghosts, coordT **out, size_t *ghost_count)
{
    coordT *c = *out = malloc(4 * (m + (ghosts == BK_DL_BOX_GHOSTS ? LIFT_GHOSTS : 0)) * sizeof *c);
    if (!c) return BK_DELAUNAY_NO_MEMORY;
    double lo[3], hi[3], r2 = 0.0;
    for (int k = 0; k < 3; k++) { lo[k] = DBL_MAX; hi[k] = -DBL_MAX; }
    for (size_t j = 0; j < m; j++) {
        const double *p = pts + 3 * (size_t)(ids ? ids[j] : j);
        r2 = fmax(r2, p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (int k = 0; k < 3; k++) { lo[k] = fmin(lo[k], p[k]); hi[k] = fmax(hi[k], p[k]); }
    }
    double r = sqrt(r2) > 0.0 ? sqrt(r2) : 1.0;
    size_t on_face[6] = {0};
    for (size_t j = 0; j < m; j++) {
        size_t i = ids ? ids[j] : j;
        const double *p = pts + 3 * i;
        double w = LIFT_TIE_WEIGHT * index_unit(i) * nn2[i];
        c[4 * j] = p[0]; c[4 * j + 1] = p[1]; c[4 * j + 2] = p[2];
        c[4 * j + 3] = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - w) / r;
        for (int k = 0; k < 3; k++) {
            on_face[2 * k] += p[k] - lo[k] <= LIFT_FACE_TOLERANCE * r;
            on_face[2 * k + 1] += hi[k] - p[k] <= LIFT_FACE_TOLERANCE * r;
        }
    }
    size_t g = 0;
    for (int f = 0; ghosts == BK_DL_BOX_GHOSTS && f < 6; f++)
        if (on_face[f] >= LIFT_GHOST_MIN_POINTS) g += face_ghosts(f, on_face[f], lo, hi, r, c + 4 * (m + g));
    *ghost_count = g;
    if (ghosts != BK_DL_HULL_GHOSTS) return BK_DELAUNAY_OK;
    int status = ids ? BK_DELAUNAY_FAILED : hull_ghosts(pts, m, r, out, ghost_count);
    return status;
}

/* The lower facets of the lifted points ids[0..m) (all n when ids is NULL), by their indices
 * among all n, into *out; BK_DELAUNAY_FAILED when a tie was not broken (a lower facet of more
 * than 4 vertices) or qhull failed. Facets through a ghost lie outside the points' hull. */
static int lifted_tets(const double *pts, const uint32_t *ids, size_t m, const double *nn2,
                       enum bk_dl_ghosts ghosts, int premerge, tet_list *out)
{
    size_t ghost_count = 0;
    coordT *coords = NULL;
    dl_qhull q = {0};
    int status = lifted_points(pts, ids, m, nn2, ghosts, &coords, &ghost_count);
    /* Q0 unless `premerge`: with the ties broken nothing needs merging, and qhull's conservative
     * pre-merge still merged facets of a 2 km, two-layer town lattice (a lower facet of 5
     * vertices at any weight up to 10⁻¹); a real precision problem is an error, or fails the
     * checks. */
    char q0_flags[] = "qhull Q0", merge_flags[] = "qhull";
    if (status == BK_DELAUNAY_OK) status = dl_qhull_run(&q, 4, m + ghost_count, coords, premerge ? merge_flags : q0_flags);
    qhT *qh = q.qh;
    facetT *facet;
    for (facet = status == BK_DELAUNAY_OK ? qh->facet_list : NULL; facet && facet->next; facet = facet->next) {
        if (!(facet->normal[3] < -qh_ZEROdelaunay * qh->ANGLEround)) continue; /* upper (as qhull's 'd') */
        uint32_t id[4];
        size_t k = 0;
        int ghost = 0;
        vertexT *vertex, **vertexp;
        FOREACHvertex_(facet->vertices) {
            int pid = qh_pointid(qh, vertex->point);
            if (pid < 0 || (size_t)pid >= m) ghost = 1;
            else if (k < 4) id[k] = ids ? ids[pid] : (uint32_t)pid;
            k++;
        }
        if (ghost) continue;
        if (k != 4) { status = BK_DELAUNAY_FAILED; break; } /* a tie not broken */
        tet_push(out, id[0], id[1], id[2], id[3]);
    }
    if (status == BK_DELAUNAY_OK && out->oom) status = BK_DELAUNAY_NO_MEMORY;
    dl_qhull_end(&q);
    free(coords);
    return status;
}

int bk_dl_lifted(const double *pts, size_t n, const double *nn2, enum bk_dl_ghosts ghosts, tet_list *out)
{
    uint8_t *used = calloc(n, 1);
    if (!used) return BK_DELAUNAY_NO_MEMORY;
    int status = lifted_tets(pts, NULL, n, nn2, ghosts, 0, out);
    for (size_t t = 0; status == BK_DELAUNAY_OK && t < out->n; t++)
        for (int j = 0; j < 4; j++) used[out->v[4 * t + j]] = 1;
    for (size_t i = 0; status == BK_DELAUNAY_OK && i < n; i++)
        if (!used[i]) status = BK_DELAUNAY_FAILED; /* a weight hid a point */
    free(used);
    return status;
}


/* ---- pockets: where the ghosts cut into the hull ---------------------------------------------
 * A ghost beyond a box face also lies inside the near-half-space circumspheres of thin
 * tetrahedra along a slanted side of the points' hull (a fine layer reaching past a coarse one,
 * roofs of different heights), so those tetrahedra are missing: the lifted result leaves
 * pockets between its boundary and the hull. Every point is a vertex of the kept tetrahedra, so
 * no point lies inside a pocket, and each tetrahedron of the true (regular) triangulation filling
 * a pocket has its corners on the pocket's walls (the kept boundary faces inside the hull).
 * Such a tetrahedron's power sphere is empty of all points, so also of the walls' corners Q: it
 * is a tetrahedron of Q's own triangulation, which is small and computed without ghosts. Those of
 * Q's tetrahedra on the outer side of a wall, and those reached from them without crossing a
 * wall, fill the pockets. The caller checks the union like any lifted result, and its volume
 * against the hull's. */
typedef struct wall { uint32_t v[3]; uint32_t inner; } wall; /* sorted corners; the kept side's apex */

static int cmp_wall(const void *pa, const void *pb)
{
    const wall *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->v[k] != b->v[k]) return a->v[k] < b->v[k] ? -1 : 1;
    return 0;
}

/* 1 when the boundary face a, b, c (d: the kept tetrahedron's fourth corner) lies on a facet of
 * the hull, within tol, facing out. */
static int on_hull(const double *pts, const uint32_t *f, uint32_t d, const hull_plane *planes, size_t np,
                   double tol)
{
    const double *a = pts + 3 * (size_t)f[0], *b = pts + 3 * (size_t)f[1], *c = pts + 3 * (size_t)f[2];
    const double *e = pts + 3 * (size_t)d;
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double nf[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    if (nf[0] * (e[0] - a[0]) + nf[1] * (e[1] - a[1]) + nf[2] * (e[2] - a[2]) > 0)
        for (int k = 0; k < 3; k++) nf[k] = -nf[k];
    for (size_t i = 0; i < np; i++) {
        const hull_plane *h = planes + i;
        if (h->n[0] * nf[0] + h->n[1] * nf[1] + h->n[2] * nf[2] <= 0.0) continue;
        int on = 1;
        for (int j = 0; on && j < 3; j++) {
            const double *p = pts + 3 * (size_t)f[j];
            on = fabs(h->n[0] * p[0] + h->n[1] * p[1] + h->n[2] * p[2] + h->offset) <= tol;
        }
        if (on) return 1;
    }
    return 0;
}

/* The walls: boundary faces of m (whose vertices are the distinct points, none unused) that do
 * not lie on the hull; *walls sorted, *corners their sorted distinct corners. */
static int pocket_walls(const double *pts, const bk_tetmesh *m, const hull_plane *planes, size_t np, double tol,
                        wall **walls_out, size_t *nw_out, uint32_t **corners_out, size_t *nc_out)
{
    size_t nb = 0;
    for (size_t k = 0; k < 4 * m->tet_count; k++) nb += m->neighbours[k] == BK_TET_NONE;
    wall *walls = *walls_out = malloc((nb ? nb : 1) * sizeof *walls);
    uint32_t *corners = *corners_out = malloc((nb ? 3 * nb : 1) * sizeof *corners);
    if (!walls || !corners) return BK_DELAUNAY_NO_MEMORY;
    size_t nw = 0;
    for (size_t t = 0; t < m->tet_count; t++)
        for (int i = 0; i < 4; i++) {
            if (m->neighbours[4 * t + i] != BK_TET_NONE) continue;
            wall w;
            int k = 0;
            for (int j = 0; j < 4; j++) if (j != i) w.v[k++] = m->tets[4 * t + j];
            w.inner = m->tets[4 * t + i];
            if (on_hull(pts, w.v, w.inner, planes, np, tol)) continue;
            sort3(w.v);
            walls[nw++] = w;
        }
    qsort(walls, nw, sizeof *walls, cmp_wall);
    size_t nc = 0;
    for (size_t w = 0; w < nw; w++) for (int k = 0; k < 3; k++) corners[nc++] = walls[w].v[k];
    qsort(corners, nc, sizeof *corners, cmp_u32);
    size_t u = 0;
    for (size_t c = 0; c < nc; c++) if (!u || corners[u - 1] != corners[c]) corners[u++] = corners[c];
    *nw_out = nw;
    *nc_out = u;
    return BK_DELAUNAY_OK;
}

static double orient_ids(const double *pts, const uint32_t *f, uint32_t d)
{
    return orient(pts + 3 * (size_t)f[0], pts + 3 * (size_t)f[1], pts + 3 * (size_t)f[2], pts + 3 * (size_t)d);
}

/* Of q's tetrahedra, those filling the pockets (above), appended to out. BK_DELAUNAY_FAILED
 * unless each wall has exactly one of q's tetrahedra on its outer side. */
static int pick_pocket_tets(const double *pts, const tet_list *q, const wall *walls, size_t nw, tet_list *out)
{
    size_t nf = 4 * q->n;
    face_rec *faces = malloc((nf ? nf : 1) * sizeof *faces);
    uint32_t *across = malloc((nf ? nf : 1) * sizeof *across); /* the tetrahedron across, or NONE */
    uint8_t *is_wall = calloc(nf ? nf : 1, 1), *in = calloc(q->n ? q->n : 1, 1);
    uint32_t *stack = malloc((q->n ? q->n : 1) * sizeof *stack);
    int status = BK_DELAUNAY_OK;
    if (!faces || !across || !is_wall || !in || !stack) { status = BK_DELAUNAY_NO_MEMORY; goto done; }
    for (size_t t = 0; t < q->n; t++)
        for (uint32_t i = 0; i < 4; i++) {
            face_rec *f = faces + 4 * t + i;
            int k = 0;
            for (int j = 0; j < 4; j++) if ((uint32_t)j != i) f->v[k++] = q->v[4 * t + j];
            sort3(f->v);
            f->tet = (uint32_t)t; f->slot = i;
            across[4 * t + i] = BK_TET_NONE;
        }
    qsort(faces, nf, sizeof *faces, cmp_face);
    size_t sp = 0, matched = 0;
    for (size_t s = 0; s < nf;) {
        size_t e = s + 1;
        while (e < nf && memcmp(faces[e].v, faces[s].v, sizeof faces[s].v) == 0) e++;
        if (e - s > 2) { status = BK_DELAUNAY_FAILED; goto done; }
        if (e - s == 2) {
            across[4 * (size_t)faces[s].tet + faces[s].slot] = faces[s + 1].tet;
            across[4 * (size_t)faces[s + 1].tet + faces[s + 1].slot] = faces[s].tet;
        }
        wall key = {{faces[s].v[0], faces[s].v[1], faces[s].v[2]}, 0};
        const wall *w = bsearch(&key, walls, nw, sizeof *walls, cmp_wall);
        for (size_t r = s; w && r < e; r++) {
            uint32_t t = faces[r].tet;
            is_wall[4 * (size_t)t + faces[r].slot] = 1;
            uint32_t apex = q->v[4 * (size_t)t + faces[r].slot];
            if (orient_ids(pts, w->v, apex) * orient_ids(pts, w->v, w->inner) >= 0.0) continue;
            matched++;
            if (!in[t]) { in[t] = 1; stack[sp++] = t; }
        }
        s = e;
    }
    if (matched != nw) { status = BK_DELAUNAY_FAILED; goto done; }
    while (sp) {
        uint32_t t = stack[--sp];
        const uint32_t *v = q->v + 4 * (size_t)t;
        tet_push(out, v[0], v[1], v[2], v[3]);
        for (int i = 0; i < 4; i++) {
            uint32_t u = across[4 * (size_t)t + i];
            if (is_wall[4 * (size_t)t + i] || u == BK_TET_NONE || in[u]) continue;
            in[u] = 1;
            stack[sp++] = u;
        }
    }
    if (out->oom) status = BK_DELAUNAY_NO_MEMORY;
done:
    free(faces); free(across); free(is_wall); free(in); free(stack);
    return status;
}

int bk_dl_fill_pockets(const double *pts, size_t n, const double *nn2, const bk_tetmesh *m, tet_list *tl,
                       double *hull_volume, size_t *filled)
{
    hull_plane *planes = NULL;
    wall *walls = NULL;
    uint32_t *corners = NULL;
    tet_list q = {0};
    size_t np = 0, nw = 0, nc = 0, before = tl->n;
    double lo[3], hi[3];
    point_box(pts, n, lo, hi);
    double diag = box_diag(lo, hi);
    int status = hull_planes(pts, n, &planes, &np, hull_volume);
    if (status == BK_DELAUNAY_OK)
        status = pocket_walls(pts, m, planes, np, POCKET_HULL_TOLERANCE * diag, &walls, &nw, &corners, &nc);
    if (status == BK_DELAUNAY_OK && nc < 4) status = BK_DELAUNAY_FAILED;
    if (status == BK_DELAUNAY_OK && nc == 4) { /* one tetrahedron: too few points for qhull's 4-d hull */
        tet_push(&q, corners[0], corners[1], corners[2], corners[3]);
    } else if (status == BK_DELAUNAY_OK) {
        /* Without ghosts the flat sides of the corners' hull lift onto vertical facets. qhull
         * without pre-merging handles them on some inputs and stops on a flipped facet on others
         * (the city's 4 × 4 district); its pre-merge handles those but may merge a lower facet
         * elsewhere. Each is tried, in that order. */
        status = lifted_tets(pts, corners, nc, nn2, BK_DL_NO_GHOSTS, 0, &q);
        if (status == BK_DELAUNAY_FAILED) {
            q.n = 0;
            status = lifted_tets(pts, corners, nc, nn2, BK_DL_NO_GHOSTS, 1, &q);
        }
    }
    if (status == BK_DELAUNAY_OK) status = pick_pocket_tets(pts, &q, walls, nw, tl);
    *filled = tl->n - before;
    free(planes); free(walls); free(corners); free(q.v);
    return status;
}
