/* Lightmap charts per object: authored TEXCOORD_1 or generated (see uvgen.h for the rules). */
#include "bake/layout/uvgen.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/chart_merge.h"
#include "bake/layout/edge_key.h"
#include "bake/layout/uv_math.h"
#include "bake/layout/uv_raster.h"

#define UV_RANGE_EPS 1e-3            /* uv1 may stray this far outside [0,1] (exporter rounding) */
#define UV_COLLAPSED_AREA_FRACTION 0.01
#define UV_OVERLAP_FRACTION 0.002

/* ---------------------------------------------------------------------------------------- */
/* Overlap counting                                                                         */

size_t bk_uv_count_overlaps(const float *uv, size_t tri_count, int width, int height, size_t *covered)
{
    if (covered) *covered = 0;
    if (width <= 0 || height <= 0) return 0;
    size_t cells = (size_t)width * (size_t)height;
    uint8_t *hits = calloc(cells, 1);
    if (!hits) return (size_t)-1;
    size_t over = 0, cov = 0;
    for (size_t i = 0; i < tri_count; i++) {
        bk_rtri t;
        if (!bk_rtri_setup(uv + 6 * i, &t)) continue;
        double mnx = fmin(t.x[0], fmin(t.x[1], t.x[2])), mxx = fmax(t.x[0], fmax(t.x[1], t.x[2]));
        double mny = fmin(t.y[0], fmin(t.y[1], t.y[2])), mxy = fmax(t.y[0], fmax(t.y[1], t.y[2]));
        /* texel x has its centre at x + 0.5 */
        int x0 = (int)fmax(0.0, floor(mnx - 0.5)), x1 = (int)fmin((double)width - 1, ceil(mxx - 0.5));
        int y0 = (int)fmax(0.0, floor(mny - 0.5)), y1 = (int)fmin((double)height - 1, ceil(mxy - 0.5));
        for (int y = y0; y <= y1; y++)
            for (int x = x0; x <= x1; x++) {
                if (!bk_rtri_inside(&t, x + 0.5, y + 0.5, NULL)) continue;
                uint8_t *h = &hits[(size_t)y * (size_t)width + (size_t)x];
                if (*h == 0) cov++;
                else if (*h == 1) over++;
                if (*h < 2) (*h)++;
            }
    }
    free(hits);
    if (covered) *covered = cov;
    return over;
}

/* ---------------------------------------------------------------------------------------- */
/* Per-object triangle data                                                                 */

typedef struct tri_info {
    double n[3];     /* unit face normal */
    double area;     /* world m² */
    int live;        /* has area */
} tri_info;

typedef struct gen_ctx {
    const bk_scene *s;
    uint32_t first, n;        /* object triangle range */
    tri_info *ti;
    uint32_t *wid;            /* welded position id per corner (3n) */
    uint32_t *adj_start, *adj;/* CSR adjacency over local triangle indices */
    uint32_t *mark;           /* scratch: membership stamp per triangle */
    uint32_t stamp;
} gen_ctx;

static int tri_geometry(const bk_scene *s, size_t tri, tri_info *t, double diag2)
{
    double p[3][3], c[3];
    memset(t, 0, sizeof *t);
    if (!bk_tri_positions(s, tri, p)) return 0;
    bk_tri_cross(p, c);
    double l = bkv_len(c);
    /* relative threshold: area below 1e-14 of the object's squared size is rounding noise */
    if (!(l > 0.0) || !isfinite(l) || l * l <= 1e-28 * diag2 * diag2) return 0;
    t->n[0] = c[0] / l;
    t->n[1] = c[1] / l;
    t->n[2] = c[2] / l;
    t->area = 0.5 * l;
    t->live = 1;
    return 1;
}

/* ---------------------------------------------------------------------------------------- */
/* Welding and adjacency                                                                    */

typedef struct weld_key {
    float p[3];
    uint32_t corner;
} weld_key;

static int cmp_weld(const void *a, const void *b)
{
    const weld_key *x = a, *y = b;
    for (int k = 0; k < 3; k++) {
        if (x->p[k] < y->p[k]) return -1;
        if (x->p[k] > y->p[k]) return 1;
    }
    return (x->corner > y->corner) - (x->corner < y->corner);
}

typedef bk_edge_key edge_key;

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static lbk_result build_adjacency(gen_ctx *g)
{
    const bk_scene *s = g->s;
    uint32_t n = g->n;
    size_t nc = 3 * (size_t)n;
    weld_key *wk = malloc((nc ? nc : 1) * sizeof *wk);
    g->wid = malloc((nc ? nc : 1) * sizeof *g->wid);
    if (!wk || !g->wid) {
        free(wk);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) g->wid[3 * (size_t)i + (size_t)k] = UINT32_MAX;
        if (!g->ti[i].live) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t v = s->tris[3 * ((size_t)g->first + i) + (size_t)k];
            for (int c = 0; c < 3; c++) wk[m].p[c] = s->positions[3 * (size_t)v + (size_t)c] + 0.0f;
            wk[m].corner = 3 * i + (uint32_t)k;
            m++;
        }
    }
    qsort(wk, m, sizeof *wk, cmp_weld);
    uint32_t id = 0;
    for (size_t i = 0; i < m; i++) {
        if (i > 0 && memcmp(wk[i].p, wk[i - 1].p, sizeof wk[i].p) != 0) id++;
        g->wid[wk[i].corner] = id;
    }
    free(wk);

    edge_key *ek = malloc((nc ? nc : 1) * sizeof *ek);
    if (!ek) return LBK_ERR_OUT_OF_MEMORY;
    size_t e = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (!g->ti[i].live) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = g->wid[3 * (size_t)i + (size_t)k], b = g->wid[3 * (size_t)i + (size_t)((k + 1) % 3)];
            if (a == b) continue;
            ek[e].a = a < b ? a : b;
            ek[e].b = a < b ? b : a;
            ek[e].tri = i;
            e++;
        }
    }
    qsort(ek, e, sizeof *ek, bk_edge_key_cmp);
    /* links: consecutive triangles of a group of equal edges (2 for a manifold edge) */
    g->adj_start = calloc((size_t)n + 1, sizeof *g->adj_start);
    uint32_t *pairs = malloc((e ? e : 1) * 2 * sizeof *pairs);
    if (!g->adj_start || !pairs) {
        free(ek);
        free(pairs);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t np = 0;
    for (size_t i = 1; i < e; i++) {
        if (ek[i].a == ek[i - 1].a && ek[i].b == ek[i - 1].b && ek[i].tri != ek[i - 1].tri) {
            pairs[2 * np] = ek[i - 1].tri;
            pairs[2 * np + 1] = ek[i].tri;
            np++;
        }
    }
    free(ek);
    for (size_t i = 0; i < np; i++) {
        g->adj_start[pairs[2 * i] + 1]++;
        g->adj_start[pairs[2 * i + 1] + 1]++;
    }
    for (uint32_t i = 0; i < n; i++) g->adj_start[i + 1] += g->adj_start[i];
    g->adj = malloc((np ? 2 * np : 1) * sizeof *g->adj);
    uint32_t *fill = malloc(((size_t)n + 1) * sizeof *fill);
    if (!g->adj || !fill) {
        free(pairs);
        free(fill);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    memcpy(fill, g->adj_start, ((size_t)n + 1) * sizeof *fill);
    for (size_t i = 0; i < np; i++) {
        uint32_t a = pairs[2 * i], b = pairs[2 * i + 1];
        g->adj[fill[a]++] = b;
        g->adj[fill[b]++] = a;
    }
    for (uint32_t i = 0; i < n; i++)
        qsort(g->adj + g->adj_start[i], g->adj_start[i + 1] - g->adj_start[i], sizeof *g->adj, cmp_u32);
    free(fill);
    free(pairs);
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Growable arrays                                                                          */

typedef struct u32vec {
    uint32_t *v;
    size_t n, cap;
} u32vec;

static int u32_push(u32vec *a, uint32_t x)
{
    if (a->n == a->cap) {
        size_t nc = a->cap ? 2 * a->cap : 64;
        uint32_t *p = realloc(a->v, nc * sizeof *p);
        if (!p) return 0;
        a->v = p;
        a->cap = nc;
    }
    a->v[a->n++] = x;
    return 1;
}

/* A piece of work: triangles (local indices) in `tris[first..first+count)` of a pool. */
typedef struct piece {
    size_t first, count;
} piece;

typedef struct piecevec {
    piece *v;
    size_t n, cap;
} piecevec;

static int piece_push(piecevec *a, size_t first, size_t count)
{
    if (a->n == a->cap) {
        size_t nc = a->cap ? 2 * a->cap : 16;
        piece *p = realloc(a->v, nc * sizeof *p);
        if (!p) return 0;
        a->v = p;
        a->cap = nc;
    }
    a->v[a->n].first = first;
    a->v[a->n].count = count;
    a->n++;
    return 1;
}

/* ---------------------------------------------------------------------------------------- */
/* Region growing                                                                           */

typedef struct area_order {
    double area;
    uint32_t tri;
} area_order;

static int cmp_area_desc(const void *a, const void *b)
{
    const area_order *x = a, *y = b;
    if (x->area != y->area) return x->area > y->area ? -1 : 1;
    return (x->tri > y->tri) - (x->tri < y->tri);
}

/* Fills pool with triangles grouped by chart; pieces get one entry per chart. */
static lbk_result grow_charts(gen_ctx *g, double cos_cone, u32vec *pool, piecevec *pieces)
{
    uint32_t n = g->n;
    area_order *ord = malloc((n ? n : 1) * sizeof *ord);
    uint8_t *taken = calloc(n ? n : 1, 1);
    if (!ord || !taken) {
        free(ord);
        free(taken);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    uint32_t live = 0;
    for (uint32_t i = 0; i < n; i++)
        if (g->ti[i].live) {
            ord[live].area = g->ti[i].area;
            ord[live].tri = i;
            live++;
        }
    qsort(ord, live, sizeof *ord, cmp_area_desc);
    lbk_result r = LBK_OK;
    for (uint32_t o = 0; o < live && r == LBK_OK; o++) {
        uint32_t seed = ord[o].tri;
        if (taken[seed]) continue;
        size_t start = pool->n;
        const double *sn = g->ti[seed].n;
        double sum[3] = {sn[0] * g->ti[seed].area, sn[1] * g->ti[seed].area, sn[2] * g->ti[seed].area};
        taken[seed] = 1;
        if (!u32_push(pool, seed)) {
            r = LBK_ERR_OUT_OF_MEMORY;
            break;
        }
        /* breadth first: the pool itself is the queue */
        for (size_t q = start; q < pool->n; q++) {
            uint32_t t = pool->v[q];
            for (uint32_t k = g->adj_start[t]; k < g->adj_start[t + 1]; k++) {
                uint32_t nb = g->adj[k];
                if (taken[nb]) continue;
                const double *nn = g->ti[nb].n;
                if (bkv_dot(nn, sn) < cos_cone) continue;
                double avg[3] = {sum[0], sum[1], sum[2]};
                bkv_normalize(avg);
                if (bkv_dot(nn, avg) < cos_cone) continue;
                taken[nb] = 1;
                for (int c = 0; c < 3; c++) sum[c] += nn[c] * g->ti[nb].area;
                if (!u32_push(pool, nb)) {
                    r = LBK_ERR_OUT_OF_MEMORY;
                    break;
                }
            }
            if (r != LBK_OK) break;
        }
        if (r == LBK_OK && !piece_push(pieces, start, pool->n - start)) r = LBK_ERR_OUT_OF_MEMORY;
    }
    free(ord);
    free(taken);
    return r;
}

/* ---------------------------------------------------------------------------------------- */
/* Projection and orientation of one piece                                                  */

typedef struct pt2 {
    double x, y;
} pt2;

static int cmp_pt2(const void *a, const void *b)
{
    const pt2 *p = a, *q = b;
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    if (p->y != q->y) return p->y < q->y ? -1 : 1;
    return 0;
}

static double cross2(pt2 o, pt2 a, pt2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/* Andrew's monotone chain; pts is sorted in place; hull receives up to n+1 points. */
static size_t convex_hull(pt2 *pts, size_t n, pt2 *hull)
{
    qsort(pts, n, sizeof *pts, cmp_pt2);
    if (n < 3) {
        for (size_t i = 0; i < n; i++) hull[i] = pts[i];
        return n;
    }
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        while (k >= 2 && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0) k--;
        hull[k++] = pts[i];
    }
    for (size_t i = n - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0) k--;
        hull[k++] = pts[i];
    }
    return k - 1;
}

typedef struct frame2 {
    double c, s;   /* rotation: x' = c·x + s·y, y' = -s·x + c·y */
} frame2;

/* The rotation whose axis-aligned bounding box of the points has the least area (an edge of
 * the convex hull is always on the optimal rectangle). */
static frame2 min_area_rotation(const pt2 *hull, size_t h)
{
    frame2 best = {1.0, 0.0};
    double best_area = DBL_MAX;
    for (size_t i = 0; i < h; i++) {
        pt2 a = hull[i], b = hull[(i + 1) % h];
        double dx = b.x - a.x, dy = b.y - a.y, l = sqrt(dx * dx + dy * dy);
        if (!(l > 0.0)) continue;
        double c = dx / l, s = dy / l;
        double mnx = DBL_MAX, mxx = -DBL_MAX, mny = DBL_MAX, mxy = -DBL_MAX;
        for (size_t j = 0; j < h; j++) {
            double x = c * hull[j].x + s * hull[j].y, y = -s * hull[j].x + c * hull[j].y;
            mnx = fmin(mnx, x); mxx = fmax(mxx, x);
            mny = fmin(mny, y); mxy = fmax(mxy, y);
        }
        double area = (mxx - mnx) * (mxy - mny);
        /* prefer the axis-aligned answer on (near) ties so walls stay as authored */
        if (area < best_area * (1.0 - 1e-9)) {
            best_area = area;
            best.c = c;
            best.s = s;
        }
    }
    /* fold to the smallest rotation among the four equivalent ones (deterministic, stable) */
    for (int r = 0; r < 4; r++) {
        if (best.c > 0.0 && best.c >= fabs(best.s)) break;
        double c = best.c, s = best.s;
        best.c = s;
        best.s = -c;
    }
    return best;
}

typedef struct piece_result {
    float width, height;
    int flipped_or_overlap;   /* 1: the projection folds over itself */
    double tri_scale;         /* a one-triangle piece longer than tri_cap: the factor its chart was
                                 scaled by to fit (< 1); else 1 */
} piece_result;

/* Projects the piece's triangles into `uv` (6 per triangle, same order as tris) at density
 * texels per metre and checks it. A lone triangle longer than tri_cap is scaled down to fit on
 * its own (res->tri_scale): only that triangle's chart loses density, never the object. */
static lbk_result project_piece(gen_ctx *g, const uint32_t *tris, size_t count, double density, int cap,
                                int tri_cap, float *uv, piece_result *res, pt2 *scratch, pt2 *hull)
{
    const bk_scene *s = g->s;
    memset(res, 0, sizeof *res);
    res->tri_scale = 1.0;
    double nsum[3] = {0, 0, 0}, aw = 0.0;
    uint32_t largest = tris[0];
    for (size_t i = 0; i < count; i++) {
        const tri_info *t = &g->ti[tris[i]];
        for (int c = 0; c < 3; c++) nsum[c] += t->n[c] * t->area;
        aw += t->area;
        if (t->area > g->ti[largest].area) largest = tris[i];
    }
    if (bkv_normalize(nsum) == 0.0) memcpy(nsum, g->ti[largest].n, sizeof nsum);
    double tb[3], bb[3], origin[3];
    bkv_basis(nsum, tb, bb);
    bkv_load(origin, s->positions + 3 * (size_t)s->tris[3 * ((size_t)g->first + tris[0])]);

    size_t np = 0;
    double ap = 0.0;
    int folded = 0;
    for (size_t i = 0; i < count; i++) {
        pt2 q[3];
        for (int k = 0; k < 3; k++) {
            double p[3], d[3];
            bkv_load(p, s->positions + 3 * (size_t)s->tris[3 * ((size_t)g->first + tris[i]) + (size_t)k]);
            bkv_sub(d, p, origin);
            q[k].x = bkv_dot(d, tb);
            q[k].y = bkv_dot(d, bb);
            scratch[np++] = q[k];
        }
        double a2 = cross2(q[0], q[1], q[2]);
        if (!(a2 > 0.0)) folded = 1;
        ap += 0.5 * fabs(a2);
    }
    size_t h = convex_hull(scratch, np, hull);
    frame2 f = min_area_rotation(hull, h);
    double scale = density * (ap > 0.0 ? sqrt(aw / ap) : 1.0);
    if (!isfinite(scale)) scale = density;
    double mnx = DBL_MAX, mxx = -DBL_MAX, mny = DBL_MAX, mxy = -DBL_MAX;
    for (size_t i = 0; i < h; i++) {
        double x = f.c * hull[i].x + f.s * hull[i].y, y = -f.s * hull[i].x + f.c * hull[i].y;
        mnx = fmin(mnx, x); mxx = fmax(mxx, x);
        mny = fmin(mny, y); mxy = fmax(mxy, y);
    }
    if (h == 0) mnx = mxx = mny = mxy = 0.0;
    /* landscape: turn by 90° (a rotation, not a mirror) when taller than wide */
    int turn = (mxy - mny) > (mxx - mnx) * (1.0 + 1e-9);
    double w = (mxx - mnx) * scale, hh = (mxy - mny) * scale;
    const double w_unturned = w;
    if (turn) {
        double t = w;
        w = hh;
        hh = t;
    }
    for (size_t i = 0; i < count; i++) {
        for (int k = 0; k < 3; k++) {
            double p[3], d[3];
            bkv_load(p, s->positions + 3 * (size_t)s->tris[3 * ((size_t)g->first + tris[i]) + (size_t)k]);
            bkv_sub(d, p, origin);
            double x0 = bkv_dot(d, tb), y0 = bkv_dot(d, bb);
            double x = (f.c * x0 + f.s * y0 - mnx) * scale, y = (-f.s * x0 + f.c * y0 - mny) * scale;
            if (turn) {
                /* (x, y) → (y, w - x): a quarter turn that keeps everything in [0,w]×[0,h] */
                double nx = y, ny = w_unturned - x;
                x = nx;
                y = ny;
            }
            /* clamp rounding so every coordinate lies in [0,w]×[0,h] exactly */
            x = fmin(fmax(x, 0.0), w);
            y = fmin(fmax(y, 0.0), hh);
            uv[6 * i + 2 * (size_t)k] = (float)x;
            uv[6 * i + 2 * (size_t)k + 1] = (float)y;
        }
    }
    res->width = (float)w;
    res->height = (float)hh;
    double longest = fmax(w, hh);
    if (count == 1) {
        if (longest > tri_cap) {
            /* a little under the cap so the chart's ceil() extent stays within it after rounding */
            double fit = (double)tri_cap / longest * (1.0 - 1e-6);
            for (int k = 0; k < 6; k++) uv[k] = (float)((double)uv[k] * fit);
            res->width = (float)(w * fit);
            res->height = (float)(hh * fit);
            res->tri_scale = fit;
        }
        return LBK_OK;
    }
    if (longest > cap) return LBK_OK;  /* will be split anyway; skip the overlap raster */
    if (folded) {
        res->flipped_or_overlap = 1;
        return LBK_OK;
    }
    int gw = (int)ceil(w) + 1, gh = (int)ceil(hh) + 1;
    size_t over = bk_uv_count_overlaps(uv, count, gw, gh, NULL);
    if (over == (size_t)-1) return LBK_ERR_OUT_OF_MEMORY;
    res->flipped_or_overlap = over > 0;
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Splitting                                                                                */

typedef struct centroid_key {
    double c;
    uint32_t tri;
} centroid_key;

static int cmp_centroid(const void *a, const void *b)
{
    const centroid_key *x = a, *y = b;
    if (x->c != y->c) return x->c < y->c ? -1 : 1;
    return (x->tri > y->tri) - (x->tri < y->tri);
}

/* Splits tris (whose projected coordinates are uv) at the median along the longer side and
 * appends the connected parts of each half to pool/pieces. */
static lbk_result split_piece(gen_ctx *g, const uint32_t *tris, size_t count, const float *uv,
                              const piece_result *pr, u32vec *pool, piecevec *work)
{
    centroid_key *ck = malloc(count * sizeof *ck);
    if (!ck) return LBK_ERR_OUT_OF_MEMORY;
    int axis = pr->width >= pr->height ? 0 : 1;
    for (size_t i = 0; i < count; i++) {
        ck[i].c = ((double)uv[6 * i + (size_t)axis] + uv[6 * i + 2 + (size_t)axis] + uv[6 * i + 4 + (size_t)axis]);
        ck[i].tri = tris[i];
    }
    qsort(ck, count, sizeof *ck, cmp_centroid);
    size_t half = count / 2;
    lbk_result r = LBK_OK;
    for (int side = 0; side < 2 && r == LBK_OK; side++) {
        size_t lo = side ? half : 0, hi = side ? count : half;
        g->stamp++;
        uint32_t in = g->stamp;
        for (size_t i = lo; i < hi; i++) g->mark[ck[i].tri] = in;
        g->stamp++;
        uint32_t done = g->stamp;
        for (size_t i = lo; i < hi && r == LBK_OK; i++) {
            uint32_t seed = ck[i].tri;
            if (g->mark[seed] != in) continue;
            size_t start = pool->n;
            g->mark[seed] = done;
            if (!u32_push(pool, seed)) {
                r = LBK_ERR_OUT_OF_MEMORY;
                break;
            }
            for (size_t q = start; q < pool->n; q++) {
                uint32_t t = pool->v[q];
                for (uint32_t k = g->adj_start[t]; k < g->adj_start[t + 1]; k++) {
                    uint32_t nb = g->adj[k];
                    if (g->mark[nb] != in) continue;
                    g->mark[nb] = done;
                    if (!u32_push(pool, nb)) {
                        r = LBK_ERR_OUT_OF_MEMORY;
                        break;
                    }
                }
                if (r != LBK_OK) break;
            }
            if (r == LBK_OK && !piece_push(work, start, pool->n - start)) r = LBK_ERR_OUT_OF_MEMORY;
        }
    }
    free(ck);
    return r;
}

/* ---------------------------------------------------------------------------------------- */
/* Output assembly                                                                          */

typedef struct out_builder {
    bk_uv_object *o;
    size_t chart_cap, tri_cap;
} out_builder;

static lbk_result out_add_chart(out_builder *b, const uint32_t *tris, const float *uv, size_t count,
                                float w, float h, uint32_t first_tri)
{
    bk_uv_object *o = b->o;
    if (o->chart_count == b->chart_cap) {
        size_t nc = b->chart_cap ? 2 * b->chart_cap : 16;
        bk_uv_chart *p = realloc(o->charts, nc * sizeof *p);
        if (!p) return LBK_ERR_OUT_OF_MEMORY;
        o->charts = p;
        b->chart_cap = nc;
    }
    if (o->tri_count + count > b->tri_cap) {
        size_t nc = b->tri_cap ? b->tri_cap : 64;
        while (nc < o->tri_count + count) nc *= 2;
        uint32_t *pt = realloc(o->tris, nc * sizeof *pt);
        if (!pt) return LBK_ERR_OUT_OF_MEMORY;
        o->tris = pt;
        float *pu = realloc(o->uv, nc * 6 * sizeof *pu);
        if (!pu) return LBK_ERR_OUT_OF_MEMORY;
        o->uv = pu;
        b->tri_cap = nc;
    }
    bk_uv_chart *c = &o->charts[o->chart_count++];
    c->first = (uint32_t)o->tri_count;
    c->count = (uint32_t)count;
    c->width = w;
    c->height = h;
    for (size_t i = 0; i < count; i++) o->tris[o->tri_count + i] = first_tri + tris[i];
    memcpy(o->uv + 6 * o->tri_count, uv, count * 6 * sizeof *uv);
    o->tri_count += count;
    return LBK_OK;
}

static void note_append(bk_uv_object *o, const char *msg)
{
    size_t l = strlen(o->note);
    if (l + 3 >= sizeof o->note) return;
    snprintf(o->note + l, sizeof o->note - l, "%s%s", l ? "; " : "", msg);
}

/* ---------------------------------------------------------------------------------------- */
/* Authored uv1                                                                             */

/* What the authored uv1 of the object's live triangles spans. */
typedef struct uv1_extent {
    double world_area, uv_area;
    double mnu, mxu, mnv, mxv;
    uint32_t live;
} uv1_extent;

/* Measures the uv1 layout; 0 (note set) when a coordinate is outside [0,1] (an authored
 * lightmap layout lives in the unit square). */
static int uv1_measure(const gen_ctx *g, bk_uv_object *o, uv1_extent *e)
{
    const bk_scene *s = g->s;
    e->world_area = e->uv_area = 0.0;
    e->mnu = e->mnv = DBL_MAX;
    e->mxu = e->mxv = -DBL_MAX;
    e->live = 0;
    for (uint32_t i = 0; i < g->n; i++) {
        if (!g->ti[i].live) continue;
        e->live++;
        double q[3][2];
        for (int k = 0; k < 3; k++) {
            uint32_t v = s->tris[3 * ((size_t)g->first + i) + (size_t)k];
            q[k][0] = s->uv1[2 * (size_t)v];
            q[k][1] = s->uv1[2 * (size_t)v + 1];
            if (!isfinite(q[k][0]) || !isfinite(q[k][1]) || q[k][0] < -UV_RANGE_EPS || q[k][0] > 1 + UV_RANGE_EPS ||
                q[k][1] < -UV_RANGE_EPS || q[k][1] > 1 + UV_RANGE_EPS) {
                char msg[128];
                snprintf(msg, sizeof msg, "uv1 rejected: coordinate (%g, %g) outside [0,1]", q[k][0], q[k][1]);
                note_append(o, msg);
                return 0;
            }
            e->mnu = fmin(e->mnu, q[k][0]); e->mxu = fmax(e->mxu, q[k][0]);
            e->mnv = fmin(e->mnv, q[k][1]); e->mxv = fmax(e->mxv, q[k][1]);
        }
        e->world_area += g->ti[i].area;
        e->uv_area += 0.5 * fabs((q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]));
    }
    return 1;
}

/* The live triangles' uv1 in texels (offset to the layout's corner, scaled by sc, clamped to
 * w × h) into uv, their indices into tl; returns how many, *collapsed_area the world area of
 * those whose texel area is below a millionth of what their world area asks for. */
static uint32_t uv1_to_texels(const gen_ctx *g, const uv1_extent *e, double sc, double w, double h, double density,
                              float *uv, uint32_t *tl, double *collapsed_area)
{
    const bk_scene *s = g->s;
    *collapsed_area = 0.0;
    uint32_t m = 0;
    for (uint32_t i = 0; i < g->n; i++) {
        if (!g->ti[i].live) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t v = s->tris[3 * ((size_t)g->first + i) + (size_t)k];
            double x = (s->uv1[2 * (size_t)v] - e->mnu) * sc, y = (s->uv1[2 * (size_t)v + 1] - e->mnv) * sc;
            uv[6 * (size_t)m + 2 * (size_t)k] = (float)fmin(fmax(x, 0.0), w);
            uv[6 * (size_t)m + 2 * (size_t)k + 1] = (float)fmin(fmax(y, 0.0), h);
        }
        const float *q = uv + 6 * (size_t)m;
        double a2 = fabs(((double)q[2] - q[0]) * ((double)q[5] - q[1]) - ((double)q[3] - q[1]) * ((double)q[4] - q[0]));
        if (a2 * 0.5 < 1e-6 * g->ti[i].area * density * density) *collapsed_area += g->ti[i].area;
        tl[m++] = i;
    }
    return m;
}

/* LBK_OK with *acceptable = 0 (note set) when too much of the layout is collapsed or claimed
 * twice; an authored layout with either would bake wrong light, so it is generated instead. */
static lbk_result uv1_check_layout(const float *uv, uint32_t m, double w, double h, double collapsed_area,
                                   double world_area, bk_uv_object *o, int *acceptable)
{
    char msg[128];
    *acceptable = 0;
    if (collapsed_area > UV_COLLAPSED_AREA_FRACTION * world_area) {
        snprintf(msg, sizeof msg, "uv1 rejected: triangles with zero uv area cover %.1f%% of the surface",
                 100.0 * collapsed_area / world_area);
        note_append(o, msg);
        return LBK_OK;
    }
    size_t covered = 0;
    size_t over = bk_uv_count_overlaps(uv, m, (int)ceil(w) + 1, (int)ceil(h) + 1, &covered);
    if (over == (size_t)-1) return LBK_ERR_OUT_OF_MEMORY;
    if ((double)over > UV_OVERLAP_FRACTION * (double)covered) {
        snprintf(msg, sizeof msg, "uv1 rejected: overlapping triangles (%zu of %zu texels claimed twice)", over,
                 covered);
        note_append(o, msg);
        return LBK_OK;
    }
    *acceptable = 1;
    return LBK_OK;
}

/* Returns LBK_OK with *used = 1 when the authored layout was taken, *used = 0 (note set)
 * when it must be generated instead. */
static lbk_result try_authored(gen_ctx *g, double density, int cap, bk_uv_object *o, int *used)
{
    *used = 0;
    if (!g->s->uv1) {
        note_append(o, "uv1 rejected: the scene has no uv1 array");
        return LBK_OK;
    }
    uv1_extent e;
    if (!uv1_measure(g, o, &e) || e.live == 0) return LBK_OK;
    if (!(e.uv_area > 0.0)) {
        note_append(o, "uv1 rejected: zero uv area");
        return LBK_OK;
    }
    double sc = density * sqrt(e.world_area / e.uv_area);
    double w = (e.mxu - e.mnu) * sc, h = (e.mxv - e.mnv) * sc;
    if (fmax(w, h) > cap) {
        double f = cap / fmax(w, h);
        sc *= f;
        w *= f;
        h *= f;
        char msg[128];
        snprintf(msg, sizeof msg, "density lowered from %g to %g texels/m so the uv1 layout fits %d texels", density,
                 density * f, cap);
        note_append(o, msg);
    }
    float *uv = malloc((size_t)e.live * 6 * sizeof *uv);
    uint32_t *tl = malloc((size_t)e.live * sizeof *tl);
    lbk_result r = uv && tl ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    int acceptable = 0;
    if (r == LBK_OK) {
        double collapsed_area;
        uint32_t m = uv1_to_texels(g, &e, sc, w, h, density, uv, tl, &collapsed_area);
        r = uv1_check_layout(uv, m, w, h, collapsed_area, e.world_area, o, &acceptable);
        if (r == LBK_OK && acceptable) {
            out_builder b = {o, 0, 0};
            r = out_add_chart(&b, tl, uv, m, (float)w, (float)h, g->first);
        }
    }
    free(uv);
    free(tl);
    if (r != LBK_OK || !acceptable) return r;
    o->density = (float)(sc * sqrt(e.uv_area / e.world_area));
    o->source = BK_UV_AUTHORED;
    o->uv1_scale = sc;
    o->uv1_min[0] = e.mnu, o->uv1_min[1] = e.mnv;
    o->uv1_max[0] = e.mxu, o->uv1_max[1] = e.mxv;
    *used = 1;
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Generation                                                                               */

/* Charts at `density`; a lone triangle longer than tri_cap gets a chart of its own at the
 * density that fits (counted in o->scaled_tris, the lowest in o->scaled_density). */
static lbk_result generate(gen_ctx *g, double density, int cap, int tri_cap, double cos_cone, bk_uv_object *o)
{
    u32vec pool = {0};
    piecevec work = {0};
    lbk_result r = grow_charts(g, cos_cone, &pool, &work);
    size_t maxc = 0;
    for (size_t i = 0; i < work.n; i++)
        if (work.v[i].count > maxc) maxc = work.v[i].count;
    float *uv = NULL;
    pt2 *scratch = NULL, *hull = NULL;
    if (r == LBK_OK && maxc > 0) {
        uv = malloc(maxc * 6 * sizeof *uv);
        scratch = malloc(maxc * 3 * sizeof *scratch);
        hull = malloc((maxc * 3 + 1) * sizeof *hull);
        if (!uv || !scratch || !hull) r = LBK_ERR_OUT_OF_MEMORY;
    }
    out_builder b = {o, 0, 0};
    /* a stack, processed from the front in creation order so chart order is stable */
    for (size_t w = 0; w < work.n && r == LBK_OK; w++) {
        piece pc = work.v[w];
        const uint32_t *tris = pool.v + pc.first;
        piece_result pr;
        r = project_piece(g, tris, pc.count, density, cap, tri_cap, uv, &pr, scratch, hull);
        if (r != LBK_OK) break;
        if (pc.count == 1 && fmax(pr.width, pr.height) / pr.tri_scale > (cap < tri_cap ? cap : tri_cap)) o->big_tris++;
        if (pr.tri_scale < 1.0) {
            float dd = (float)(density * pr.tri_scale);
            if (o->scaled_tris == 0 || dd < o->scaled_density) o->scaled_density = dd;
            o->scaled_tris++;
        }
        if (pc.count > 1 && (fmax(pr.width, pr.height) > cap || pr.flipped_or_overlap)) {
            /* copy: split_piece appends to pool, which may move it */
            uint32_t *copy = malloc(pc.count * sizeof *copy);
            if (!copy) {
                r = LBK_ERR_OUT_OF_MEMORY;
                break;
            }
            memcpy(copy, tris, pc.count * sizeof *copy);
            r = split_piece(g, copy, pc.count, uv, &pr, &pool, &work);
            free(copy);
            continue;
        }
        r = out_add_chart(&b, tris, uv, pc.count, pr.width, pr.height, g->first);
    }
    free(uv);
    free(scratch);
    free(hull);
    free(pool.v);
    free(work.v);
    return r;
}

lbk_result bk_uvgen_object(const bk_scene *scene, uint32_t object, float density, const bk_uv_options *opt,
                           bk_uv_object *out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!scene || object >= scene->object_count || !(density > 0.0f) || !isfinite(density))
        return LBK_ERR_INVALID_ARGUMENT;
    const bk_object *ob = &scene->objects[object];
    if ((uint64_t)ob->first_tri + ob->tri_count > scene->tri_count) return LBK_ERR_INVALID_ARGUMENT;
    double cone = opt && opt->cone_degrees > 0.0f && opt->cone_degrees < 89.0f ? opt->cone_degrees : 40.0;
    int cap = opt && opt->max_chart_texels > 0 ? opt->max_chart_texels : 1020;
    int tri_cap = opt && opt->max_triangle_texels > 0 ? opt->max_triangle_texels : cap;
    out->object = object;
    out->density = density;

    gen_ctx g = {0};
    g.s = scene;
    g.first = ob->first_tri;
    g.n = ob->tri_count;
    g.ti = calloc(g.n ? g.n : 1, sizeof *g.ti);
    g.mark = calloc(g.n ? g.n : 1, sizeof *g.mark);
    lbk_result r = (g.ti && g.mark) ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    /* object size for the relative degeneracy threshold */
    double mn[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, mx[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (uint32_t i = 0; r == LBK_OK && i < g.n; i++) {
        double p[3][3];
        if (!bk_tri_positions(scene, (size_t)g.first + i, p)) continue;
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++) {
                mn[c] = fmin(mn[c], p[k][c]);
                mx[c] = fmax(mx[c], p[k][c]);
            }
    }
    double diag2 = 0.0;
    for (int c = 0; c < 3; c++)
        if (mx[c] >= mn[c]) diag2 += (mx[c] - mn[c]) * (mx[c] - mn[c]);
    uint32_t live = 0;
    for (uint32_t i = 0; r == LBK_OK && i < g.n; i++) live += (uint32_t)tri_geometry(scene, (size_t)g.first + i, &g.ti[i], diag2);
    out->degenerate_count = g.n - live;

    int done = 0;
    if (r == LBK_OK && live == 0) {
        out->source = BK_UV_EMPTY;
        done = 1;
    }
    if (r == LBK_OK && !done && ob->has_uv1) {
        int used = 0;
        /* an authored layout is one chart that cannot be split: like a lone triangle it may
         * take up to the one-triangle cap (a whole maximum page in the atlas) */
        r = try_authored(&g, density, tri_cap > cap ? tri_cap : cap, out, &used);
        done = used;
    }
    if (r == LBK_OK && !done) {
        r = build_adjacency(&g);
        double d = density;
        if (r == LBK_OK) r = generate(&g, d, cap, tri_cap, cos(cone * 3.14159265358979323846 / 180.0), out);
        if (r == LBK_OK && out->scaled_tris) {
            char msg[160];
            snprintf(msg, sizeof msg, "%zu triangle%s longer than %d texels at %g texels/m: %s own chart%s at %g texels/m",
                     out->scaled_tris, out->scaled_tris == 1 ? "" : "s", tri_cap, d,
                     out->scaled_tris == 1 ? "its" : "their", out->scaled_tris == 1 ? "" : "s (down to)",
                     (double)out->scaled_density);
            note_append(out, msg);
        }
        if (r == LBK_OK) {
            bk_chart_graph cg = {g.first, g.n, g.wid, g.adj_start, g.adj};
            size_t merged;
            r = bk_merge_small_charts(scene, &cg, d, cap, out, &merged);
        }
        out->density = (float)d;
        out->source = BK_UV_GENERATED;
    }
    free(g.ti);
    free(g.mark);
    free(g.wid);
    free(g.adj_start);
    free(g.adj);
    if (r != LBK_OK) {
        bk_uv_object_free(out);
        memset(out, 0, sizeof *out);
    }
    return r;
}

void bk_uv_object_free(bk_uv_object *uvo)
{
    if (!uvo) return;
    free(uvo->charts);
    free(uvo->tris);
    free(uvo->uv);
    uvo->charts = NULL;
    uvo->tris = NULL;
    uvo->uv = NULL;
    uvo->chart_count = uvo->tri_count = 0;
}
