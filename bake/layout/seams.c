/* Lightmap seams: finding them, scoring them, stitching them (see seams.h). */
#include "bake/layout/seams.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/edge_key.h"
#include "bake/layout/uv_math.h"
#include "scene/parallel.h"

#define SMOOTH_DOT 0.999
#define UV_SAME_EPS 1e-3          /* texels: an edge mapped to the same place on both sides */
#define STITCH_LAMBDA (1.0 / 4096.0)
#define STITCH_TOL 1e-4
#define STITCH_EPS (1.0 / 1024.0) /* stop at this RMS mismatch relative to the RMS filtered value */
#define STITCH_CHECK 4            /* iterations between two looks at the mismatch */
#define STITCH_MAX_ITER 1000
#define STITCH_MU2 16.0          /* weight² of holding a colour's irradiance at zero */
#define STITCH_ROUNDS 4

void bk_seams_free(bk_seams *s)
{
    if (!s) return;
    free(s->seams);
    memset(s, 0, sizeof *s);
}

/* ---------------------------------------------------------------------------------------- */
/* Finding                                                                                  */

typedef struct weld_key {
    float p[3];
    uint32_t corner;     /* 3 × local triangle + k */
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

typedef struct edge_key {
    uint32_t a, b;       /* welded ids, a < b */
    uint32_t tri;        /* local triangle */
    uint8_t ka, kb;      /* its corners at a and b */
} edge_key;

static int cmp_edge(const void *pa, const void *pb)
{
    const edge_key *x = pa, *y = pb;
    return bk_edge_order(x->a, x->b, x->tri, y->a, y->b, y->tri);
}

typedef struct seam_vec {
    bk_seam *v;
    size_t n, cap;
} seam_vec;

static int seam_push(seam_vec *a, const bk_seam *s)
{
    if (a->n == a->cap) {
        size_t nc = a->cap ? 2 * a->cap : 64;
        bk_seam *p = realloc(a->v, nc * sizeof *p);
        if (!p) return 0;
        a->v = p;
        a->cap = nc;
    }
    a->v[a->n++] = *s;
    return 1;
}

/* Unit shading normal of corner k of scene triangle tri (the face normal without normals). */
static void corner_normal(const bk_scene *s, uint32_t tri, int k, double n[3])
{
    double p[3][3];
    n[0] = n[1] = n[2] = 0.0;
    if (s->normals) bkv_load(n, s->normals + 3 * (size_t)s->tris[3 * (size_t)tri + (size_t)k]);
    if (bkv_normalize(n) > 0.0) return;
    if (bk_tri_positions(s, tri, p)) {
        bk_tri_cross(p, n);
        bkv_normalize(n);
    }
}

/* dP/du of atlas entry e, orthogonalised against unit n and normalised; 0 when undefined. */
static int entry_tangent(const bk_scene *s, const bk_atlas *a, uint32_t e, const double n[3], double t[3])
{
    double p[3][3];
    if (!bk_tri_positions(s, a->tris[e], p)) return 0;
    const float *uv = a->tri_uv + 6 * (size_t)e;
    double e1[3], e2[3];
    bkv_sub(e1, p[1], p[0]);
    bkv_sub(e2, p[2], p[0]);
    double du1 = (double)uv[2] - uv[0], dv1 = (double)uv[3] - uv[1];
    double du2 = (double)uv[4] - uv[0], dv2 = (double)uv[5] - uv[1];
    double det = du1 * dv2 - du2 * dv1;
    if (!(fabs(det) > 0.0) || !isfinite(det)) return 0;
    for (int c = 0; c < 3; c++) t[c] = (e1[c] * dv2 - e2[c] * dv1) / det;
    double d = bkv_dot(t, n);
    for (int c = 0; c < 3; c++) t[c] -= d * n[c];
    return bkv_normalize(t) > 0.0;
}

/* The seam between the two triangles of edge group x[0], x[1] of object triangles from
 * `first`, when the edge is mapped to two places; returns 1 with *out set. */
static int make_seam(const bk_scene *s, const bk_atlas *a, uint32_t first, const edge_key x[2], bk_seam *out)
{
    uint32_t tri[2], e[2];
    for (int side = 0; side < 2; side++) {
        tri[side] = first + x[side].tri;
        int32_t en = a->scene_tri_entry[tri[side]];
        if (en < 0) return 0;
        e[side] = (uint32_t)en;
    }
    memset(out, 0, sizeof *out);
    double diff = 0.0;
    for (int side = 0; side < 2; side++) {
        const float *uv = a->tri_uv + 6 * (size_t)e[side];
        out->uv[side][0] = uv[2 * x[side].ka];
        out->uv[side][1] = uv[2 * x[side].ka + 1];
        out->uv[side][2] = uv[2 * x[side].kb];
        out->uv[side][3] = uv[2 * x[side].kb + 1];
    }
    for (int k = 0; k < 4; k++) diff += fabs((double)out->uv[0][k] - out->uv[1][k]);
    if (!(diff > UV_SAME_EPS)) return 0;
    out->entry[0] = e[0];
    out->entry[1] = e[1];
    out->slot = a->charts[a->tri_chart[e[0]]].slot;
    out->page = (uint32_t)a->charts[a->tri_chart[e[0]]].page;
    double pa[3], pb[3], d[3];
    bkv_load(pa, s->positions + 3 * (size_t)s->tris[3 * (size_t)tri[0] + x[0].ka]);
    bkv_load(pb, s->positions + 3 * (size_t)s->tris[3 * (size_t)tri[0] + x[0].kb]);
    bkv_sub(d, pb, pa);
    out->length = (float)bkv_len(d);
    double na[2][3], nb[2][3], n[3] = {0, 0, 0};
    for (int side = 0; side < 2; side++) {
        corner_normal(s, tri[side], x[side].ka, na[side]);
        corner_normal(s, tri[side], x[side].kb, nb[side]);
        for (int c = 0; c < 3; c++) n[c] += na[side][c] + nb[side][c];
    }
    out->smooth = bkv_dot(na[0], na[1]) >= SMOOTH_DOT && bkv_dot(nb[0], nb[1]) >= SMOOTH_DOT;
    out->rot[0] = 1.0f;
    out->rot[1] = 0.0f;
    double t0[3], t1[3], b0[3];
    if (bkv_normalize(n) > 0.0 && entry_tangent(s, a, e[0], n, t0) && entry_tangent(s, a, e[1], n, t1)) {
        bkv_cross(b0, n, t0);
        out->rot[0] = (float)bkv_dot(t0, t1);
        out->rot[1] = (float)bkv_dot(b0, t1);
    }
    return 1;
}

/* The seams of atlas object `slot`, appended to v. */
static lbk_result object_seams(const bk_scene *s, const bk_atlas *a, size_t slot, seam_vec *v)
{
    const bk_object *ob = &s->objects[a->objects[slot].object];
    if (a->objects[slot].page < 0 || ob->tri_count == 0) return LBK_OK;
    uint32_t n = ob->tri_count, first = ob->first_tri;
    size_t nc = 3 * (size_t)n;
    weld_key *wk = malloc(nc * sizeof *wk);
    uint32_t *wid = malloc(nc * sizeof *wid);
    edge_key *ek = malloc(nc * sizeof *ek);
    lbk_result r = wk && wid && ek ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    size_t m = 0, ne = 0;
    for (uint32_t i = 0; r == LBK_OK && i < n; i++) {
        for (int k = 0; k < 3; k++) wid[3 * (size_t)i + (size_t)k] = UINT32_MAX;
        if (a->scene_tri_entry[first + i] < 0) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t vi = s->tris[3 * ((size_t)first + i) + (size_t)k];
            for (int c = 0; c < 3; c++) wk[m].p[c] = s->positions[3 * (size_t)vi + (size_t)c] + 0.0f;
            wk[m].corner = 3 * i + (uint32_t)k;
            m++;
        }
    }
    if (r == LBK_OK) {
        qsort(wk, m, sizeof *wk, cmp_weld);
        uint32_t id = 0;
        for (size_t i = 0; i < m; i++) {
            if (i > 0 && memcmp(wk[i].p, wk[i - 1].p, sizeof wk[i].p) != 0) id++;
            wid[wk[i].corner] = id;
        }
        for (uint32_t i = 0; i < n; i++)
            for (int k = 0; k < 3; k++) {
                uint32_t wa = wid[3 * (size_t)i + (size_t)k], wb = wid[3 * (size_t)i + (size_t)((k + 1) % 3)];
                if (wa == UINT32_MAX || wa == wb) continue;
                edge_key *q = &ek[ne++];
                q->tri = i;
                q->a = wa < wb ? wa : wb;
                q->b = wa < wb ? wb : wa;
                q->ka = (uint8_t)(wa < wb ? k : (k + 1) % 3);
                q->kb = (uint8_t)(wa < wb ? (k + 1) % 3 : k);
            }
        qsort(ek, ne, sizeof *ek, cmp_edge);
    }
    for (size_t i = 0; r == LBK_OK && i < ne;) {
        size_t j = i + 1;
        while (j < ne && ek[j].a == ek[i].a && ek[j].b == ek[i].b) j++;
        bk_seam sm;
        /* manifold edges only: with three or more sides there is no one "other side" */
        if (j - i == 2 && ek[i].tri != ek[i + 1].tri && make_seam(s, a, first, &ek[i], &sm) && !seam_push(v, &sm))
            r = LBK_ERR_OUT_OF_MEMORY;
        i = j;
    }
    free(wk);
    free(wid);
    free(ek);
    return r;
}

lbk_result bk_seams_find(const bk_scene *scene, const bk_atlas *atlas, bk_seams *out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!scene || !atlas || (atlas->object_count && !atlas->scene_tri_entry)) return LBK_ERR_INVALID_ARGUMENT;
    seam_vec v = {0};
    for (size_t slot = 0; slot < atlas->object_count; slot++) {
        lbk_result r = object_seams(scene, atlas, slot, &v);
        if (r != LBK_OK) {
            free(v.v);
            return r;
        }
    }
    out->seams = v.v;
    out->count = v.n;
    for (size_t i = 0; i < v.n; i++) out->smooth_count += v.v[i].smooth;
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Filtering and score                                                                      */

void bk_bilinear_taps(double x, double y, int width, int height, int32_t idx[4], double w[4])
{
    double fx = x - 0.5, fy = y - 0.5;
    double x0 = floor(fx), y0 = floor(fy);
    double ax = fx - x0, ay = fy - y0;
    int ix[2] = {(int)x0, (int)x0 + 1}, iy[2] = {(int)y0, (int)y0 + 1};
    for (int k = 0; k < 2; k++) {
        ix[k] = ix[k] < 0 ? 0 : ix[k] >= width ? width - 1 : ix[k];
        iy[k] = iy[k] < 0 ? 0 : iy[k] >= height ? height - 1 : iy[k];
    }
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            idx[2 * j + i] = (int32_t)((size_t)iy[j] * (size_t)width + (size_t)ix[i]);
            w[2 * j + i] = (i ? ax : 1.0 - ax) * (j ? ay : 1.0 - ay);
        }
}

int bk_seam_points(const bk_seam *sm)
{
    double l = 0.0;
    for (int side = 0; side < 2; side++) {
        double dx = (double)sm->uv[side][2] - sm->uv[side][0], dy = (double)sm->uv[side][3] - sm->uv[side][1];
        l = fmax(l, sqrt(dx * dx + dy * dy));
    }
    double n = ceil(2.0 * l);
    return n < 2.0 ? 2 : n > 1e6 ? 1000000 : (int)n;
}

/* Point i of n on side `side` of a seam, page texel coordinates. */
static void seam_point(const bk_seam *sm, int side, int i, int n, double *x, double *y)
{
    double t = (i + 0.5) / n;
    const float *u = sm->uv[side];
    *x = u[0] + t * ((double)u[2] - u[0]);
    *y = u[1] + t * ((double)u[3] - u[1]);
}

/* The two sides' filtered luminance at point i of n of a seam. */
static void point_lum(const bk_seam *sm, int i, int n, int w, int h, const float *lum, double v[2])
{
    for (int side = 0; side < 2; side++) {
        double x, y, tw[4];
        int32_t ti[4];
        seam_point(sm, side, i, n, &x, &y);
        bk_bilinear_taps(x, y, w, h, ti, tw);
        v[side] = 0.0;
        for (int t = 0; t < 4; t++) v[side] += tw[t] * lum[ti[t]];
    }
}

void bk_seams_score(const bk_seams *s, const bk_atlas_page *pages, size_t page_count, const float *const *lum,
                    bk_seam_score *out)
{
    memset(out, 0, sizeof *out);
    if (!s || !pages || !lum) return;
    /* pass 0: the mean level along the seams (the floor of the denominator); pass 1: jumps */
    double level = 0.0, level_w = 0.0, wsum = 0.0, jsum = 0.0;
    for (int pass = 0; pass < 2; pass++) {
        double floor_l = level_w > 0.0 ? level / level_w / 16.0 : 0.0;
        for (size_t k = 0; k < s->count; k++) {
            const bk_seam *sm = &s->seams[k];
            if (!sm->smooth || sm->page >= page_count || !lum[sm->page]) continue;
            if (pass) {
                out->seams++;
                out->length += sm->length;
            }
            int w = pages[sm->page].width, h = pages[sm->page].height, n = bk_seam_points(sm);
            for (int i = 0; i < n; i++) {
                double v[2];
                point_lum(sm, i, n, w, h, lum[sm->page], v);
                double mean = 0.5 * (v[0] + v[1]);
                if (!pass) {
                    if (isfinite(mean)) level += mean * sm->length / n, level_w += sm->length / n;
                    continue;
                }
                double den = fmax(mean, floor_l);
                if (!(den > 0.0)) continue;
                double j = fabs(v[0] - v[1]) / den;
                jsum += j * sm->length / n;
                wsum += sm->length / n;
                if (j > out->max) out->max = j;
                out->points++;
            }
        }
    }
    out->mean = wsum > 0.0 ? jsum / wsum : 0.0;
}

/* ---------------------------------------------------------------------------------------- */
/* Stitching                                                                                */

#define CH 12

typedef struct stitch_point {
    uint32_t t[2][4];    /* unknown index of each tap */
    double w[2][4];
    double c, s;         /* side 0 → side 1 rotation of the tangent-plane pairs */
} stitch_point;

typedef struct stitch_sys {
    stitch_point *pt;
    size_t np;
    size_t nu;           /* unknown texels */
    int32_t *texel;      /* page index of each unknown */
    uint8_t *held;       /* 3 per unknown: colour held at zero irradiance along the normal */
} stitch_sys;

/* R·v on the three (g.x, g.y) pairs of a 12-float AHD linear form, identity elsewhere. */
static void rotate12(const double v[CH], double c, double s, int transpose, double out[CH])
{
    memcpy(out, v, CH * sizeof *v);
    double ss = transpose ? -s : s;
    for (int col = 0; col < 3; col++) {
        double x = v[4 * col + 1], y = v[4 * col + 2];
        out[4 * col + 1] = c * x + ss * y;
        out[4 * col + 2] = -ss * x + c * y;
    }
}

/* out = λ·v + Σ_points Jᵀ J v + μ² Σ_held Hᵀ H v, with J v = R·f0(v) − f1(v) and H v =
 * e0 + g.z of a held colour (its irradiance along the normal). */
static void stitch_apply(const stitch_sys *sys, const double *v, double *out)
{
    for (size_t i = 0; i < sys->nu * CH; i++) out[i] = STITCH_LAMBDA * v[i];
    for (size_t u = 0; u < sys->nu; u++)
        for (int col = 0; col < 3; col++) {
            if (!sys->held[3 * u + (size_t)col]) continue;
            size_t e0 = u * CH + 4 * (size_t)col, gz = e0 + 3;
            double h = STITCH_MU2 * (v[e0] + v[gz]);
            out[e0] += h;
            out[gz] += h;
        }
    for (size_t p = 0; p < sys->np; p++) {
        const stitch_point *q = &sys->pt[p];
        double f[2][CH], rf[CH], r[CH], back[CH];
        for (int side = 0; side < 2; side++) {
            memset(f[side], 0, sizeof f[side]);
            for (int k = 0; k < 4; k++)
                for (int c = 0; c < CH; c++) f[side][c] += q->w[side][k] * v[(size_t)q->t[side][k] * CH + (size_t)c];
        }
        rotate12(f[0], q->c, q->s, 0, rf);
        for (int c = 0; c < CH; c++) r[c] = rf[c] - f[1][c];
        rotate12(r, q->c, q->s, 1, back);
        for (int k = 0; k < 4; k++)
            for (int c = 0; c < CH; c++) {
                out[(size_t)q->t[0][k] * CH + (size_t)c] += q->w[0][k] * back[c];
                out[(size_t)q->t[1][k] * CH + (size_t)c] -= q->w[1][k] * r[c];
            }
    }
}

static double dot_n(const double *a, const double *b, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++) s += a[i] * b[i];
    return s;
}

/* Jacobi preconditioner: the diagonal of the operator (the seam part is the same for the 12
 * channels of a texel: the rotations keep lengths). */
static void stitch_diagonal(const stitch_sys *sys, double *diag)
{
    for (size_t i = 0; i < sys->nu * CH; i++) diag[i] = STITCH_LAMBDA;
    for (size_t p = 0; p < sys->np; p++)
        for (int side = 0; side < 2; side++)
            for (int k = 0; k < 4; k++)
                for (int c = 0; c < CH; c++)
                    diag[(size_t)sys->pt[p].t[side][k] * CH + (size_t)c] += sys->pt[p].w[side][k] * sys->pt[p].w[side][k];
    for (size_t u = 0; u < sys->nu; u++)
        for (int col = 0; col < 3; col++)
            if (sys->held[3 * u + (size_t)col]) {
                diag[u * CH + 4 * (size_t)col] += STITCH_MU2;
                diag[u * CH + 4 * (size_t)col + 3] += STITCH_MU2;
            }
}

/* The seams' state at v: *mis = Σ_points |R·f0(v) − f1(v)|² + Σ_held (e0 + g.z)² (what the
 * encoder will show of the seams and of the clamp), *val = Σ_points (|f0(v)|² + |f1(v)|²) / 2
 * (the level of the light there), both over all 12 channels, and *obj the objective the solve
 * minimises, Σ_points |J v|² + μ² Σ_held |H v|² + λ |v − x0|². */
static void stitch_measure(const stitch_sys *sys, const double *v, const double *x0, double *mis, double *val,
                           double *obj)
{
    double m = 0.0, l = 0.0, h2 = 0.0, d2 = 0.0;
    for (size_t p = 0; p < sys->np; p++) {
        const stitch_point *q = &sys->pt[p];
        double f[2][CH], rf[CH];
        for (int side = 0; side < 2; side++) {
            memset(f[side], 0, sizeof f[side]);
            for (int k = 0; k < 4; k++)
                for (int c = 0; c < CH; c++) f[side][c] += q->w[side][k] * v[(size_t)q->t[side][k] * CH + (size_t)c];
        }
        rotate12(f[0], q->c, q->s, 0, rf);
        for (int c = 0; c < CH; c++) {
            double d = rf[c] - f[1][c];
            m += d * d;
            l += 0.5 * (f[0][c] * f[0][c] + f[1][c] * f[1][c]);
        }
    }
    for (size_t u = 0; u < sys->nu; u++)
        for (int col = 0; col < 3; col++)
            if (sys->held[3 * u + (size_t)col]) {
                double h = v[u * CH + 4 * (size_t)col] + v[u * CH + 4 * (size_t)col + 3];
                h2 += h * h;
            }
    for (size_t i = 0; i < sys->nu * CH; i++) d2 += (v[i] - x0[i]) * (v[i] - x0[i]);
    *mis = m + h2;
    *val = l;
    *obj = m + STITCH_MU2 * h2 + STITCH_LAMBDA * d2;
}

/* Whether solving on from v can still change what the encoder stores. R11G11B10F rounds each
 * side by up to 2^-7 relative (2^-6 for blue), so an RMS mismatch of ε = 2^-10 of the light is
 * 8× below what the stored texels can tell apart: done when the mismatch is below that, or when
 * the last STITCH_CHECK iterations lowered the objective (a sum over the same points) by less
 * than ε²/16 of the light — where the seams cannot match better (charts of a few texels whose
 * texels serve several seams keep ~0.2 % RMS at the optimum), the solve would otherwise crawl
 * on for hundreds of iterations moving bits the encoder drops (bench/stitch_level.py's merged
 * props: 578 iterations in four rounds at 1e-4 of the first residual alone; stitching's CPU
 * 4.4 s → 1.3 s with components and this rule, the stored seam score 0.0051 → 0.0053). Relative to the
 * light, not to the first residual: a bright and a dark component stop alike. *prev: the
 * objective at the last look (< 0: none yet). */
static int stitch_done(const stitch_sys *sys, const double *v, const double *x0, double *prev)
{
    double mis, val, obj;
    stitch_measure(sys, v, x0, &mis, &val, &obj);
    double floor2 = STITCH_EPS * STITCH_EPS * val;
    int done = mis <= floor2 || (*prev >= 0.0 && *prev - obj <= floor2 / 16.0);
    *prev = obj;
    return done;
}

/* Preconditioned conjugate gradients for (λI + JᵀJ + μ²HᵀH) x = λ x0, starting at x (warm);
 * stops when solving on no longer changes what the encoder stores (stitch_done, looked at
 * every STITCH_CHECK iterations) or the residual is below STITCH_TOL × *ref (*ref ≤ 0: set to
 * the first residual). Returns the iterations, -1 when out of memory. */
static int stitch_solve(const stitch_sys *sys, const double *x0, double *x, double *ref)
{
    size_t n = sys->nu * CH;
    double prev = -1.0;
    if (stitch_done(sys, x, x0, &prev)) return 0;
    double *r = malloc(n * sizeof *r), *z = malloc(n * sizeof *z), *p = malloc(n * sizeof *p);
    double *ap = malloc(n * sizeof *ap), *diag = malloc(n * sizeof *diag);
    int it = -1;
    if (r && z && p && ap && diag) {
        stitch_diagonal(sys, diag);
        stitch_apply(sys, x, ap);
        for (size_t i = 0; i < n; i++) {
            r[i] = STITCH_LAMBDA * x0[i] - ap[i];
            z[i] = r[i] / diag[i];
            p[i] = z[i];
        }
        double rr = dot_n(r, r, n), rz = dot_n(r, z, n);
        if (!(*ref > 0.0)) *ref = rr;
        for (it = 0; it < STITCH_MAX_ITER && rr > STITCH_TOL * STITCH_TOL * *ref && rz > 0.0; it++) {
            if (it > 0 && it % STITCH_CHECK == 0 && stitch_done(sys, x, x0, &prev)) break;
            stitch_apply(sys, p, ap);
            double pap = dot_n(p, ap, n);
            if (!(pap > 0.0)) break;
            double alpha = rz / pap;
            for (size_t i = 0; i < n; i++) {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
                z[i] = r[i] / diag[i];
            }
            double rz1 = dot_n(r, z, n), beta = rz1 / rz;
            rz = rz1;
            rr = dot_n(r, r, n);
            for (size_t i = 0; i < n; i++) p[i] = z[i] + beta * p[i];
        }
    }
    free(r), free(z), free(p), free(ap), free(diag);
    return it;
}

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

static uint32_t unknown_of(const stitch_sys *sys, int32_t texel)
{
    size_t lo = 0, hi = sys->nu;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (sys->texel[mid] < texel) lo = mid + 1;
        else hi = mid;
    }
    return (uint32_t)lo;
}

/* The points of the smooth seams [k0, k1) whose filters read only filled texels, and their
 * taps as unknowns. Returns 0 when out of memory. */
static int stitch_setup(const bk_seams *s, size_t k0, size_t k1, int width, int height, const uint8_t *mask,
                        stitch_sys *sys)
{
    memset(sys, 0, sizeof *sys);
    size_t cap = 0;
    for (size_t k = k0; k < k1; k++)
        if (s->seams[k].smooth) cap += (size_t)bk_seam_points(&s->seams[k]);
    if (cap == 0) return 1;
    sys->pt = malloc(cap * sizeof *sys->pt);
    sys->texel = malloc(cap * 8 * sizeof *sys->texel);
    if (!sys->pt || !sys->texel) return 0;
    int32_t (*taps)[2][4] = malloc(cap * sizeof *taps);
    if (!taps) return 0;
    size_t nt = 0;
    for (size_t k = k0; k < k1; k++) {
        const bk_seam *sm = &s->seams[k];
        if (!sm->smooth) continue;
        int n = bk_seam_points(sm);
        for (int i = 0; i < n; i++) {
            stitch_point *q = &sys->pt[sys->np];
            int ok = 1;
            for (int side = 0; side < 2 && ok; side++) {
                double x, y;
                seam_point(sm, side, i, n, &x, &y);
                bk_bilinear_taps(x, y, width, height, taps[sys->np][side], q->w[side]);
                for (int t = 0; t < 4; t++) ok &= mask[taps[sys->np][side][t]] != 0 || q->w[side][t] == 0.0;
            }
            if (!ok) continue;
            q->c = sm->rot[0];
            q->s = sm->rot[1];
            for (int side = 0; side < 2; side++)
                for (int t = 0; t < 4; t++) sys->texel[nt++] = taps[sys->np][side][t];
            sys->np++;
        }
    }
    qsort(sys->texel, nt, sizeof *sys->texel, cmp_i32);
    size_t u = 0;
    for (size_t i = 0; i < nt; i++)
        if (u == 0 || sys->texel[i] != sys->texel[u - 1]) sys->texel[u++] = sys->texel[i];
    sys->nu = u;
    for (size_t p = 0; p < sys->np; p++)
        for (int side = 0; side < 2; side++)
            for (int t = 0; t < 4; t++) sys->pt[p].t[side][t] = unknown_of(sys, taps[p][side][t]);
    free(taps);
    return 1;
}

static void stitch_free(stitch_sys *sys)
{
    free(sys->pt), free(sys->texel), free(sys->held);
    memset(sys, 0, sizeof *sys);
}

static uint32_t uf_find(uint32_t *parent, uint32_t a)
{
    while (parent[a] != a) {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    return a;
}

/* Splits one object's system into its connected components (unknowns that share no point
 * are independent): each is solved on its own, to its own light level, and they run in
 * parallel even within one object. Components are numbered by their first unknown (the
 * lowest page index), unknowns and points keep their order: deterministic. On success *out
 * holds *count systems and sys is freed; returns 0 when out of memory (sys kept). */
static int stitch_split(stitch_sys *sys, stitch_sys **out, size_t *count)
{
    *out = NULL;
    *count = 0;
    if (sys->np == 0) return 1;
    size_t nu = sys->nu;
    uint32_t *parent = malloc(nu * sizeof *parent), *comp = malloc(nu * sizeof *comp);
    uint32_t *local = malloc(nu * sizeof *local);
    size_t *nu_c = NULL, *np_c = NULL, nc = 0;
    stitch_sys *cs = NULL;
    int ok = parent && comp && local;
    for (size_t u = 0; ok && u < nu; u++) parent[u] = (uint32_t)u;
    for (size_t p = 0; ok && p < sys->np; p++)
        for (int side = 0; side < 2; side++)
            for (int t = 0; t < 4; t++) {
                uint32_t a = uf_find(parent, sys->pt[p].t[0][0]), b = uf_find(parent, sys->pt[p].t[side][t]);
                if (a != b) parent[a > b ? a : b] = a < b ? a : b; /* the lower index is the root */
            }
    for (size_t u = 0; ok && u < nu; u++) {
        uint32_t root = uf_find(parent, (uint32_t)u);
        comp[u] = root == u ? (uint32_t)nc++ : comp[root]; /* a root comes before its members */
    }
    if (ok) {
        nu_c = calloc(nc, sizeof *nu_c), np_c = calloc(nc, sizeof *np_c), cs = calloc(nc, sizeof *cs);
        ok = nu_c && np_c && cs;
    }
    for (size_t u = 0; ok && u < nu; u++) local[u] = (uint32_t)nu_c[comp[u]]++;
    for (size_t p = 0; ok && p < sys->np; p++) np_c[comp[sys->pt[p].t[0][0]]]++;
    for (size_t c = 0; ok && c < nc; c++) {
        cs[c].pt = malloc(np_c[c] * sizeof *cs[c].pt);
        cs[c].texel = malloc(nu_c[c] * sizeof *cs[c].texel);
        ok = cs[c].pt && cs[c].texel;
    }
    for (size_t u = 0; ok && u < nu; u++) cs[comp[u]].texel[cs[comp[u]].nu++] = sys->texel[u];
    for (size_t p = 0; ok && p < sys->np; p++) {
        stitch_sys *c = &cs[comp[sys->pt[p].t[0][0]]];
        stitch_point *q = &c->pt[c->np++];
        *q = sys->pt[p];
        for (int side = 0; side < 2; side++)
            for (int t = 0; t < 4; t++) q->t[side][t] = local[q->t[side][t]];
    }
    if (!ok && cs)
        for (size_t c = 0; c < nc; c++) stitch_free(&cs[c]);
    free(parent), free(comp), free(local), free(nu_c), free(np_c);
    if (!ok) {
        free(cs);
        return 0;
    }
    stitch_free(sys);
    *out = cs;
    *count = nc;
    return 1;
}

/* Solves, then holds at zero every colour whose irradiance along the normal came out negative
 * (the encoder would clamp it and break the match) and solves again from there, a few rounds.
 * Returns 0 when out of memory. */
static int stitch_rounds(stitch_sys *sys, const double *x0, double *x)
{
    double ref = 0.0;
    memcpy(x, x0, sys->nu * CH * sizeof *x);
    for (int round = 0; round < STITCH_ROUNDS; round++) {
        if (stitch_solve(sys, x0, x, &ref) < 0) return 0;
        int more = 0;
        for (size_t u = 0; u < sys->nu; u++)
            for (int col = 0; col < 3; col++) {
                size_t e0 = u * CH + 4 * (size_t)col;
                if (sys->held[3 * u + (size_t)col] || !(x[e0] + x[e0 + 3] < 0.0)) continue;
                sys->held[3 * u + (size_t)col] = 1;
                more = 1;
            }
        if (!more) break;
    }
    return 1;
}

/* Stitches one component (its texels are its own); returns the texels changed, (size_t)-1
 * when out of memory. */
static size_t stitch_component(stitch_sys *sys, float *data)
{
    size_t n = sys->nu * CH, changed = 0;
    double *x0 = malloc(n * sizeof *x0), *x = malloc(n * sizeof *x);
    sys->held = calloc(3 * sys->nu, 1);
    if (!x0 || !x || !sys->held) {
        free(x0), free(x);
        return (size_t)-1;
    }
    for (size_t u = 0; u < sys->nu; u++)
        for (int c = 0; c < CH; c++) x0[u * CH + (size_t)c] = data[(size_t)sys->texel[u] * CH + (size_t)c];
    if (!stitch_rounds(sys, x0, x)) {
        free(x0), free(x);
        return (size_t)-1;
    }
    for (size_t u = 0; u < sys->nu; u++) {
        int diff = 0;
        for (int c = 0; c < CH; c++) {
            float v = (float)x[u * CH + (size_t)c];
            float *d = &data[(size_t)sys->texel[u] * CH + (size_t)c];
            if (isfinite(v) && v != *d) {
                *d = v;
                diff = 1;
            }
        }
        changed += (size_t)diff;
    }
    free(x0), free(x);
    return changed;
}

typedef struct stitch_job {
    const bk_seams *s;
    const size_t *range;  /* 2 per object: seams [range[2g], range[2g+1]) */
    int width, height;
    float *data;
    const uint8_t *mask;
    stitch_sys **comps;   /* per object: its components (stitch_split) */
    size_t *ncomp;        /* per object: how many; (size_t)-1 when out of memory */
    stitch_sys **flat;    /* every object's components, object by object */
    size_t *changed;      /* per component */
} stitch_job;

static void setup_chunk(void *user, size_t begin, size_t end, int thread)
{
    const stitch_job *j = user;
    (void)thread;
    for (size_t g = begin; g < end; g++) {
        stitch_sys sys;
        if (!stitch_setup(j->s, j->range[2 * g], j->range[2 * g + 1], j->width, j->height, j->mask, &sys) ||
            !stitch_split(&sys, &j->comps[g], &j->ncomp[g]))
            j->ncomp[g] = (size_t)-1;
        stitch_free(&sys);
    }
}

static void solve_chunk(void *user, size_t begin, size_t end, int thread)
{
    const stitch_job *j = user;
    (void)thread;
    for (size_t c = begin; c < end; c++) j->changed[c] = stitch_component(j->flat[c], j->data);
}

/* Objects of page `page` as seam ranges (seams come object by object): 2 per object in
 * *range; returns the count, (size_t)-1 when out of memory. */
static size_t page_objects(const bk_seams *s, uint32_t page, size_t **range_out)
{
    size_t groups = 0;
    for (size_t k = 0; k < s->count; k++)
        if (s->seams[k].page == page && (k == 0 || s->seams[k].slot != s->seams[k - 1].slot || s->seams[k - 1].page != page))
            groups++;
    *range_out = NULL;
    if (groups == 0) return 0;
    size_t *range = malloc(2 * groups * sizeof *range);
    if (!range) return (size_t)-1;
    size_t g = 0;
    for (size_t k = 0; k < s->count; k++) {
        if (s->seams[k].page != page) continue;
        if (g == 0 || s->seams[k].slot != s->seams[range[2 * (g - 1) + 1] - 1].slot || range[2 * (g - 1) + 1] != k) {
            range[2 * g] = k;
            g++;
        }
        range[2 * (g - 1) + 1] = k + 1;
    }
    *range_out = range;
    return g;
}

/* Every component of the job's objects, in order, into j->flat; returns the count, (size_t)-1
 * when an object ran out of memory or the list cannot be made. */
static size_t flatten(stitch_job *j, size_t groups)
{
    size_t total = 0;
    for (size_t g = 0; g < groups; g++) {
        if (j->ncomp[g] == (size_t)-1) return (size_t)-1;
        total += j->ncomp[g];
    }
    j->flat = malloc((total ? total : 1) * sizeof *j->flat);
    j->changed = calloc(total ? total : 1, sizeof *j->changed);
    if (!j->flat || !j->changed) return (size_t)-1;
    size_t c = 0;
    for (size_t g = 0; g < groups; g++)
        for (size_t k = 0; k < j->ncomp[g]; k++) j->flat[c++] = &j->comps[g][k];
    return total;
}

size_t bk_seams_stitch(const bk_seams *s, uint32_t page, int width, int height, float *data, const uint8_t *mask,
                       int threads)
{
    if (!s || !data || !mask || width <= 0 || height <= 0 || s->smooth_count == 0) return 0;
    /* objects own disjoint texels, and within one the connected components of the seam points'
     * taps do: every component is an independent system, so any thread count gives the same
     * result. First the systems, object by object, then the solves, component by component. */
    size_t *range = NULL, groups = page_objects(s, page, &range);
    if (groups == 0 || groups == (size_t)-1) return groups;
    stitch_job job = {s, range, width, height, data, mask, NULL, NULL, NULL, NULL};
    job.comps = calloc(groups, sizeof *job.comps);
    job.ncomp = calloc(groups, sizeof *job.ncomp);
    int nt = bk_thread_count(threads);
    size_t total = (size_t)-1, comps = (size_t)-1;
    if (job.comps && job.ncomp) {
        bk_parallel_chunks(0, groups, 1, nt, setup_chunk, &job);
        comps = flatten(&job, groups);
    }
    if (comps != (size_t)-1) {
        bk_parallel_chunks(0, comps, 1, nt, solve_chunk, &job);
        total = 0;
        for (size_t c = 0; c < comps && total != (size_t)-1; c++)
            total = job.changed[c] == (size_t)-1 ? (size_t)-1 : total + job.changed[c];
    }
    for (size_t g = 0; job.comps && job.ncomp && g < groups; g++) {
        for (size_t k = 0; job.ncomp[g] != (size_t)-1 && k < job.ncomp[g]; k++) stitch_free(&job.comps[g][k]);
        free(job.comps[g]);
    }
    free(job.comps), free(job.ncomp), free(job.flat), free(job.changed), free(range);
    return total;
}
