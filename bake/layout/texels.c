/* Texel receivers, push-out, tangent frames and dilation (see texels.h). */
#include "bake/layout/texels.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/edge_inset.h"
#include "bake/layout/uv_math.h"
#include "bake/layout/uv_raster.h"
#include "scene/parallel.h"

/* ---------------------------------------------------------------------------------------- */
/* Tangent frame                                                                            */

static void frame_d(const double n[3], const double dpdu[3], double t[3], double b[3])
{
    double d = bkv_dot(n, dpdu);
    t[0] = dpdu[0] - n[0] * d;
    t[1] = dpdu[1] - n[1] * d;
    t[2] = dpdu[2] - n[2] * d;
    /* dP/du nearly parallel to N (or zero): no usable direction, take the fixed basis */
    if (!(bkv_len(t) > 1e-6 * bkv_len(dpdu)) || bkv_normalize(t) == 0.0) {
        double tb[3];
        bkv_basis(n, t, tb);
    }
    bkv_cross(b, n, t);
    bkv_normalize(b);
}

void bk_tangent_frame(const float n[3], const float dpdu[3], float t[3], float b[3])
{
    double nn[3], du[3], tt[3], bb[3];
    bkv_load(nn, n);
    bkv_load(du, dpdu);
    if (bkv_normalize(nn) == 0.0) {
        nn[0] = 0;
        nn[1] = 0;
        nn[2] = 1;
    }
    frame_d(nn, du, tt, bb);
    for (int k = 0; k < 3; k++) {
        t[k] = (float)tt[k];
        b[k] = (float)bb[k];
    }
}

/* ---------------------------------------------------------------------------------------- */
/* Coverage                                                                                 */

void bk_texels_free(bk_texels *tx)
{
    if (!tx) return;
    free(tx->footprint);
    free(tx->pages);
    free(tx->page_offset);
    free(tx->index);
    free(tx->receivers);
    memset(tx, 0, sizeof *tx);
}

void bk_receiver_from_texel(const bk_texel *t, bk_receiver *r)
{
    memset(r, 0, sizeof *r);
    memcpy(r->position, t->position, sizeof t->position);
    memcpy(r->normal, t->normal, sizeof t->normal);
    r->footprint_first = t->footprint_first;
    r->footprint_count = t->footprint_count;
    memcpy(r->footprint_box, t->footprint_box, sizeof t->footprint_box);
    r->footprint_hidden = t->footprint_hidden;
}

const bk_texel *bk_texels_at(const bk_texels *tx, uint32_t page, int x, int y)
{
    if (!tx || page >= tx->page_count) return NULL;
    const bk_atlas_page *p = &tx->pages[page];
    if (x < 0 || y < 0 || x >= p->width || y >= p->height) return NULL;
    int32_t r = tx->index[tx->page_offset[page] + (size_t)y * (size_t)p->width + (size_t)x];
    return r >= 0 ? &tx->receivers[r] : NULL;
}

void bk_texels_valid_mask(const bk_texels *tx, uint32_t page, uint8_t *mask)
{
    if (!tx || !mask || page >= tx->page_count) return;
    size_t n = (size_t)tx->pages[page].width * (size_t)tx->pages[page].height;
    const int32_t *idx = tx->index + tx->page_offset[page];
    for (size_t i = 0; i < n; i++) mask[i] = idx[i] >= 0 && (tx->receivers[idx[i]].flags & BK_TEXEL_VALID);
}

/* Fills a receiver from triangle entry e at texel (x, y); w are barycentric weights. */
static void make_receiver(const bk_scene *s, const bk_atlas *a, uint32_t e, const double w[3], bk_texel *r)
{
    uint32_t tri = a->tris[e];
    const float *uv = a->tri_uv + 6 * (size_t)e;
    double p[3][3];
    memset(r, 0, sizeof *r);
    r->tri = tri;
    r->object = s->tri_object ? s->tri_object[tri] : a->objects[a->charts[a->tri_chart[e]].slot].object;
    bk_tri_positions(s, tri, p); /* atlas triangles passed this check in uvgen */
    double pos[3] = {0, 0, 0}, nrm[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        uint32_t v = s->tris[3 * (size_t)tri + (size_t)k];
        for (int c = 0; c < 3; c++) {
            pos[c] += w[k] * p[k][c];
            if (s->normals) nrm[c] += w[k] * (double)s->normals[3 * (size_t)v + (size_t)c];
        }
    }
    double ng[3];
    bk_tri_cross(p, ng);
    double area2 = bkv_normalize(ng);
    if (!(bkv_normalize(nrm) > 0.0) || !isfinite(nrm[0] + nrm[1] + nrm[2])) memcpy(nrm, ng, sizeof nrm);
    /* dP/du and the world size of a texel from the triangle's uv mapping */
    double e1[3], e2[3];
    bkv_sub(e1, p[1], p[0]);
    bkv_sub(e2, p[2], p[0]);
    double du1 = (double)uv[2] - uv[0], dv1 = (double)uv[3] - uv[1];
    double du2 = (double)uv[4] - uv[0], dv2 = (double)uv[5] - uv[1];
    double det = du1 * dv2 - du2 * dv1;
    double dpdu[3] = {0, 0, 0};
    double size = 0.0;
    if (fabs(det) > 0.0 && isfinite(det)) {
        for (int c = 0; c < 3; c++) dpdu[c] = (e1[c] * dv2 - e2[c] * dv1) / det;
        size = sqrt(0.5 * area2 / (0.5 * fabs(det)));
    }
    if (!(size > 0.0) || !isfinite(size)) {
        const bk_atlas_object *o = &a->objects[a->charts[a->tri_chart[e]].slot];
        size = o->density > 0.0f ? 1.0 / o->density : 1.0;
    }
    double t[3], b[3];
    frame_d(nrm, dpdu, t, b);
    for (int c = 0; c < 3; c++) {
        r->position[c] = (float)pos[c];
        r->normal[c] = (float)nrm[c];
        r->tangent[c] = (float)t[c];
    }
    r->texel_size = (float)size;
    r->flags = BK_TEXEL_VALID;
}

/* ---------------------------------------------------------------------------------------- */
/* Footprint                                                                                */

/* 1 unless a separating axis (the square's two, the triangle's three edge normals) splits the
 * triangle from the square [x, x+1] × [y, y+1]; touching counts as overlapping. */
static int tri_overlaps_square(const bk_rtri *t, double x, double y)
{
    double mnx = fmin(t->x[0], fmin(t->x[1], t->x[2])), mxx = fmax(t->x[0], fmax(t->x[1], t->x[2]));
    double mny = fmin(t->y[0], fmin(t->y[1], t->y[2])), mxy = fmax(t->y[0], fmax(t->y[1], t->y[2]));
    if (mxx < x || mnx > x + 1 || mxy < y || mny > y + 1) return 0;
    const double cx[4] = {x, x + 1, x + 1, x}, cy[4] = {y, y, y + 1, y + 1};
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3; /* edge a→b; corner k is inside (orientation > 0) */
        int outside = 0;
        for (int q = 0; q < 4; q++)
            outside += bk_orient_raw(t->x[a], t->y[a], t->x[b], t->y[b], cx[q], cy[q]) < 0.0;
        if (outside == 4) return 0;
    }
    return 1;
}

/* Barycentric weights (original corner order) of any point, inside or not. */
static void rtri_weights(const bk_rtri *t, double px, double py, double w[3])
{
    double e[3];
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        e[k] = bk_orient_raw(t->x[a], t->y[a], t->x[b], t->y[b], px, py) / t->area2;
    }
    w[0] = e[0];
    w[1] = t->flipped ? e[2] : e[1];
    w[2] = t->flipped ? e[1] : e[2];
}

/* UV islands: entries of one chart joined by edges they share both in uv and in the world
 * (exact corner coordinates), where the surface is smooth: their face normals within
 * ISLAND_CREASE_COS of each other. An authored layout is one chart holding many islands, often
 * closer than a texel or even touching; a texel's footprint stays on its own island, as a
 * renderer's bake stays on the texel's triangle. A generated chart may fold over a hard edge
 * (chart_merge.c lays a table top's 7 cm rim strip beside its top): the footprint must not
 * follow it, or the top's texels along the rim average in points of the rim, which see half
 * the sky (measured: −18 % at 2 texels/m on a slab under a sky), and the underside's the
 * rim's sky (TRANSPORT.md, Thin geometry). */
#define ISLAND_CREASE_COS 0.7660444431 /* cos 40°: uvgen's chart cone (uvgen.h cone_degrees) */
typedef struct fp_edge { uint32_t chart; float k[10]; uint32_t entry; } fp_edge; /* uv a, uv b, world a, b */

static int cmp_edge(const void *p, const void *q)
{
    const fp_edge *a = p, *b = q;
    if (a->chart != b->chart) return a->chart < b->chart ? -1 : 1;
    for (int k = 0; k < 10; k++)
        if (a->k[k] != b->k[k]) return a->k[k] < b->k[k] ? -1 : 1;
    return (a->entry > b->entry) - (a->entry < b->entry);
}

static int same_edge(const fp_edge *a, const fp_edge *b)
{
    if (a->chart != b->chart) return 0;
    for (int k = 0; k < 10; k++)
        if (a->k[k] != b->k[k]) return 0;
    return 1;
}

static uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

/* Whether entries i and j of the atlas meet at no crease (face normals within the island's
 * crease angle); a degenerate triangle joins anything, as before. */
static int smooth_join(const bk_scene *s, const bk_atlas *a, uint32_t i, uint32_t j)
{
    double p[3][3], ni[3], nj[3];
    if (!bk_tri_positions(s, a->tris[i], p)) return 1;
    bk_tri_cross(p, ni);
    if (!bk_tri_positions(s, a->tris[j], p)) return 1;
    bk_tri_cross(p, nj);
    if (!(bkv_normalize(ni) > 0.0) || !(bkv_normalize(nj) > 0.0)) return 1;
    return bkv_dot(ni, nj) >= ISLAND_CREASE_COS;
}

static uint32_t *uv_islands(const bk_scene *s, const bk_atlas *a)
{
    size_t n = a->tri_count;
    uint32_t *parent = malloc((n ? n : 1) * sizeof *parent);
    fp_edge *e = malloc((n ? 3 * n : 1) * sizeof *e);
    if (!parent || !e) {
        free(parent);
        free(e);
        return NULL;
    }
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        parent[i] = (uint32_t)i;
        const float *uv = a->tri_uv + 6 * i;
        const uint32_t *ix = s->tris + 3 * (size_t)a->tris[i];
        for (int k = 0; k < 3; k++) {
            int k2 = (k + 1) % 3;
            float ka[5] = {uv[2 * k], uv[2 * k + 1], 0, 0, 0}, kb[5] = {uv[2 * k2], uv[2 * k2 + 1], 0, 0, 0};
            int ok = ix[k] < s->vertex_count && ix[k2] < s->vertex_count;
            for (int c = 0; ok && c < 3; c++) {
                ka[2 + c] = s->positions[3 * (size_t)ix[k] + c];
                kb[2 + c] = s->positions[3 * (size_t)ix[k2] + c];
            }
            for (int c = 0; c < 5; c++) ok = ok && isfinite(ka[c]) && isfinite(kb[c]);
            if (!ok) continue;
            int swap = 0; /* the lexicographically smaller corner first, so both sides agree */
            for (int c = 0; c < 5 && !swap; c++) {
                if (kb[c] < ka[c]) swap = 1;
                if (kb[c] != ka[c]) break;
            }
            fp_edge *x = &e[m++];
            x->chart = a->tri_chart[i];
            for (int c = 0; c < 5; c++) {
                x->k[c] = swap ? kb[c] : ka[c];
                x->k[5 + c] = swap ? ka[c] : kb[c];
            }
            x->entry = (uint32_t)i;
        }
    }
    qsort(e, m, sizeof *e, cmp_edge);
    for (size_t i = 1; i < m; i++) {
        const fp_edge *p = &e[i - 1], *q = &e[i];
        if (!same_edge(p, q) || !smooth_join(s, a, p->entry, q->entry)) continue;
        uint32_t r1 = uf_find(parent, p->entry), r2 = uf_find(parent, q->entry);
        if (r1 != r2) parent[r1 > r2 ? r1 : r2] = r1 > r2 ? r2 : r1;
    }
    for (size_t i = 0; i < n; i++) parent[i] = uf_find(parent, (uint32_t)i);
    free(e);
    return parent;
}

typedef struct fp_pair { size_t texel; uint32_t entry; } fp_pair;

static int cmp_pair(const void *a, const void *b)
{
    const fp_pair *p = a, *q = b;
    if (p->texel != q->texel) return p->texel < q->texel ? -1 : 1;
    return (p->entry > q->entry) - (p->entry < q->entry);
}

/* (texel, entry) for every chart triangle over a texel its chart owns; idx holds the owning
 * entry per texel (or -1). Sorted by texel, then entry: receiver order. */
static lbk_result footprint_pairs(const bk_scene *s, const bk_atlas *a, const bk_texels *out, const int32_t *idx_all,
                                  fp_pair **pairs, size_t *count)
{
    size_t n = 0, cap = 0;
    fp_pair *v = NULL;
    uint32_t *island = uv_islands(s, a);
    if (!island) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t c = 0; c < a->chart_count; c++) {
        const bk_atlas_chart *ch = &a->charts[c];
        if (ch->page < 0 || (size_t)ch->page >= out->page_count) continue;
        int pw = out->pages[ch->page].width, ph = out->pages[ch->page].height;
        size_t base = out->page_offset[ch->page];
        const int32_t *idx = idx_all + base;
        for (uint32_t e = ch->first; e < ch->first + ch->count; e++) {
            bk_rtri t;
            if (!bk_rtri_setup(a->tri_uv + 6 * (size_t)e, &t)) continue;
            int x0, x1, y0, y1;
            bk_rtri_texel_box(&t, pw, ph, &x0, &x1, &y0, &y1);
            for (int y = y0; y <= y1; y++)
                for (int x = x0; x <= x1; x++) {
                    size_t i = (size_t)y * (size_t)pw + (size_t)x;
                    if (idx[i] < 0 || island[idx[i]] != island[e]) continue;
                    if (!tri_overlaps_square(&t, x, y)) continue;
                    if (n == cap) {
                        size_t nc = cap ? 2 * cap : 1024;
                        fp_pair *nv = realloc(v, nc * sizeof *nv);
                        if (!nv) { free(v); free(island); return LBK_ERR_OUT_OF_MEMORY; }
                        v = nv;
                        cap = nc;
                    }
                    v[n].texel = base + i;
                    v[n].entry = e;
                    n++;
                }
        }
    }
    free(island);
    if (n) qsort(v, n, sizeof *v, cmp_pair);
    *pairs = v;
    *count = n;
    return LBK_OK;
}

/* Grows box (s0, t0, s1, t1) by the part of triangle `entry` inside texel (x, y)'s square
 * (Sutherland–Hodgman against the square's four sides, in texel-local coordinates); returns
 * that part's area (in texels). */
static double clip_box(const bk_atlas *a, uint32_t entry, int x, int y, double box[4])
{
    const float *uv = a->tri_uv + 6 * (size_t)entry;
    double poly[2][16][2];
    int n = 3, cur = 0;
    for (int k = 0; k < 3; k++) {
        poly[0][k][0] = uv[2 * k] - x;
        poly[0][k][1] = uv[2 * k + 1] - y;
    }
    for (int side = 0; side < 4 && n > 0; side++) {
        const int axis = side & 1;
        const double lim = side < 2 ? 0.0 : 1.0, sg = side < 2 ? 1.0 : -1.0; /* keep sg·(c − lim) >= 0 */
        int m = 0;
        for (int k = 0; k < n; k++) {
            const double *p = poly[cur][k], *q = poly[cur][(k + 1) % n];
            double dp = sg * (p[axis] - lim), dq = sg * (q[axis] - lim);
            if (dp >= 0 && m < 16) { poly[!cur][m][0] = p[0]; poly[!cur][m][1] = p[1]; m++; }
            if ((dp >= 0) != (dq >= 0) && m < 16) {
                double f = dp / (dp - dq);
                poly[!cur][m][0] = p[0] + f * (q[0] - p[0]);
                poly[!cur][m][1] = p[1] + f * (q[1] - p[1]);
                m++;
            }
        }
        n = m;
        cur = !cur;
    }
    double area2 = 0.0;
    for (int k = 0; k < n; k++) {
        const double *p = poly[cur][k], *q = poly[cur][(k + 1) % n];
        area2 += p[0] * q[1] - q[0] * p[1];
        box[0] = fmin(box[0], p[0]);
        box[1] = fmin(box[1], p[1]);
        box[2] = fmax(box[2], p[0]);
        box[3] = fmax(box[3], p[1]);
    }
    return 0.5 * fabs(area2);
}

/* The footprint triangle of `entry` over texel (x, y): barycentrics as affine maps of (s, t). */
static void footprint_tri(const bk_atlas *a, uint32_t entry, int x, int y, bk_footprint_tri *f)
{
    bk_rtri t;
    bk_rtri_setup(a->tri_uv + 6 * (size_t)entry, &t);
    double w00[3], w10[3], w01[3];
    rtri_weights(&t, x, y, w00);
    rtri_weights(&t, x + 1, y, w10);
    rtri_weights(&t, x, y + 1, w01);
    f->tri = a->tris[entry];
    for (int k = 0; k < 2; k++) {
        f->uv[k][0] = (float)w00[k + 1];
        f->uv[k][1] = (float)(w10[k + 1] - w00[k + 1]);
        f->uv[k][2] = (float)(w01[k + 1] - w00[k + 1]);
    }
}

/* The owning triangle entry of every covered texel into out->index (coverage rule in texels.h);
 * best[i]: its squared distance to the centre, -1 when the centre is inside. */
static void rasterise_owners(const bk_atlas *a, bk_texels *out, float *best)
{
    for (size_t c = 0; c < a->chart_count; c++) {
        const bk_atlas_chart *ch = &a->charts[c];
        if (ch->page < 0 || (size_t)ch->page >= out->page_count) continue;
        int pw = a->pages[ch->page].width, ph = a->pages[ch->page].height;
        int32_t *idx = out->index + out->page_offset[ch->page];
        float *bst = best + out->page_offset[ch->page];
        for (uint32_t e = ch->first; e < ch->first + ch->count; e++) {
            bk_rtri t;
            if (!bk_rtri_setup(a->tri_uv + 6 * (size_t)e, &t)) continue;
            int x0, x1, y0, y1;
            bk_rtri_texel_box(&t, pw, ph, &x0, &x1, &y0, &y1);
            for (int y = y0; y <= y1; y++)
                for (int x = x0; x <= x1; x++) {
                    double cx = x + 0.5, cy = y + 0.5;
                    float d;
                    if (bk_rtri_inside(&t, cx, cy, NULL)) {
                        d = -1.0f;
                    } else {
                        /* the bilinear footprint: filtering at some point of the triangle reads it */
                        if (!bk_rtri_meets_square(&t, cx, cy, 1.0)) continue;
                        d = (float)bk_rtri_closest(&t, cx, cy, NULL, NULL, NULL);
                    }
                    size_t i = (size_t)y * (size_t)pw + (size_t)x;
                    if (d < bst[i]) {
                        bst[i] = d;
                        idx[i] = (int32_t)e;
                    }
                }
        }
    }
}

/* Below this area (texels) the chart does not cover a texel's square: triangles that only touch
 * it (an edge along the square's side) or a sliver of rounding. */
#define RING_AREA 1e-6

/* Texel (x, y) (global index g) gets its footprint: the pairs of g, from *fp on (sorted alike),
 * as maps and as the bounding box of the part of its square they cover; a texel whose square
 * the chart does not cover is a ring texel (texels.h). */
static void texel_footprint(const bk_atlas *a, const fp_pair *pairs, size_t npairs, size_t *fp, size_t g, int x,
                            int y, bk_footprint_tri *fps, bk_texel *rc)
{
    while (*fp < npairs && pairs[*fp].texel < g) (*fp)++;
    rc->footprint_first = (uint32_t)*fp;
    double box[4] = {1, 1, 0, 0}, area = 0.0;
    while (*fp < npairs && pairs[*fp].texel == g) {
        footprint_tri(a, pairs[*fp].entry, x, y, &fps[*fp]);
        area += clip_box(a, pairs[*fp].entry, x, y, box);
        (*fp)++;
    }
    rc->footprint_count = (uint32_t)(*fp - rc->footprint_first);
    if (!(area > RING_AREA)) { /* only bilinear filtering reads it (texels.h, Ring) */
        rc->footprint_count = 0;
        rc->flags |= BK_TEXEL_RING;
        memset(rc->footprint_box, 0, sizeof rc->footprint_box);
        return;
    }
    /* a little larger against rounding */
    for (int k = 0; k < 2; k++) {
        double lo = fmax(0.0, box[k] - 1e-4), hi = fmin(1.0, box[k + 2] + 1e-4);
        rc->footprint_box[k] = (float)lo;
        rc->footprint_box[k + 2] = (float)fmax(0.0, hi - lo);
    }
}

lbk_result bk_texels_build(const bk_scene *s, const bk_atlas *a, bk_texels *out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!s || !a || (a->tri_count && (!a->tris || !a->tri_uv))) return LBK_ERR_INVALID_ARGUMENT;
    size_t np = a->page_count, total = 0;
    for (size_t p = 0; p < np; p++) {
        if (a->pages[p].width <= 0 || a->pages[p].height <= 0 || a->pages[p].width > 65535 ||
            a->pages[p].height > 65535)
            return LBK_ERR_LIMIT;
        total += (size_t)a->pages[p].width * (size_t)a->pages[p].height;
    }
    if (total > (size_t)INT32_MAX) return LBK_ERR_LIMIT;
    out->page_count = np;
    out->pages = malloc((np ? np : 1) * sizeof *out->pages);
    out->page_offset = malloc((np + 1) * sizeof *out->page_offset);
    out->index = malloc((total ? total : 1) * sizeof *out->index);
    float *best = malloc((total ? total : 1) * sizeof *best);
    if (!out->pages || !out->page_offset || !out->index || !best) {
        free(best);
        bk_texels_free(out);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t off = 0;
    for (size_t p = 0; p < np; p++) {
        out->pages[p] = a->pages[p];
        out->page_offset[p] = off;
        off += (size_t)a->pages[p].width * (size_t)a->pages[p].height;
    }
    out->page_offset[np] = off;
    /* index holds the owning triangle entry during rasterisation; best its squared
     * distance (-1: centre inside) */
    for (size_t i = 0; i < total; i++) {
        out->index[i] = -1;
        best[i] = INFINITY;
    }
    rasterise_owners(a, out, best);
    size_t count = 0;
    for (size_t i = 0; i < total; i++) count += out->index[i] >= 0;
    fp_pair *pairs = NULL;
    size_t npairs = 0;
    out->receivers = malloc((count ? count : 1) * sizeof *out->receivers);
    if (!out->receivers || footprint_pairs(s, a, out, out->index, &pairs, &npairs) != LBK_OK ||
        !(out->footprint = malloc((npairs ? npairs : 1) * sizeof *out->footprint))) {
        free(best);
        free(pairs);
        bk_texels_free(out);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    out->footprint_count = npairs;
    if (npairs > UINT32_MAX) { /* footprint_first is 32-bit */
        free(best);
        free(pairs);
        bk_texels_free(out);
        return LBK_ERR_LIMIT;
    }
    size_t r = 0, fp = 0;
    for (size_t p = 0; p < np; p++) {
        int pw = a->pages[p].width, ph = a->pages[p].height;
        int32_t *idx = out->index + out->page_offset[p];
        const float *bst = best + out->page_offset[p];
        for (int y = 0; y < ph; y++)
            for (int x = 0; x < pw; x++) {
                size_t i = (size_t)y * (size_t)pw + (size_t)x;
                if (idx[i] < 0) continue;
                uint32_t e = (uint32_t)idx[i];
                bk_rtri t;
                bk_rtri_setup(a->tri_uv + 6 * (size_t)e, &t);
                double w[3];
                int edge = 0;
                if (!(bst[i] < 0.0f) || !bk_rtri_inside(&t, x + 0.5, y + 0.5, w)) {
                    bk_rtri_closest(&t, x + 0.5, y + 0.5, w, NULL, NULL);
                    edge = 1;
                }
                bk_texel *rc = &out->receivers[r];
                make_receiver(s, a, e, w, rc);
                if (edge) rc->flags |= BK_TEXEL_EDGE;
                rc->page = (uint32_t)p;
                rc->x = (uint16_t)x;
                rc->y = (uint16_t)y;
                texel_footprint(a, pairs, npairs, &fp, out->page_offset[p] + i, x, y, out->footprint, rc);
                idx[i] = (int32_t)r;
                r++;
            }
    }
    out->count = count;
    free(best);
    free(pairs);
    lbk_result res = bk_texels_inset_edges(out, s);
    if (res != LBK_OK) bk_texels_free(out);
    return res;
}

/* ---------------------------------------------------------------------------------------- */
/* Push-out                                                                                 */

typedef struct push_job {
    bk_texels *tx;
    const bk_scene *scene;
    const bk_tracer *tracer;
    float reach;
    float far_dist;
    bk_pushout_stats *thread_stats; /* one per thread, summed at the end */
} push_job;

/* Fixed hemisphere directions (local frame, z up): a Fibonacci spiral, deterministic. */
#define LONG_RAYS 16
static void hemisphere_dir(int i, int n, double d[3])
{
    const double golden = 2.39996322972865332; /* π(3 − √5) */
    double z = 1.0 - (i + 0.5) / n;            /* uniform in solid angle over z ∈ (0, 1] */
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = r * cos(golden * i);
    d[1] = r * sin(golden * i);
    d[2] = z;
}

static void to_world(const double t[3], const double b[3], const double n[3], const double l[3], float out[3])
{
    for (int c = 0; c < 3; c++) out[c] = (float)(l[0] * t[c] + l[1] * b[c] + l[2] * n[c]);
}

/* Geometric normal of triangle tri, oriented to agree with the shading normal sn. */
static void oriented_geo_normal(const bk_scene *s, uint32_t tri, const float sn[3], double ng[3])
{
    double p[3][3];
    if (!bk_tri_positions(s, tri, p)) {
        bkv_load(ng, sn);
        return;
    }
    bk_tri_cross(p, ng);
    if (bkv_normalize(ng) == 0.0) {
        bkv_load(ng, sn);
        return;
    }
    double sd[3];
    bkv_load(sd, sn);
    if (bkv_dot(ng, sd) < 0.0) {
        ng[0] = -ng[0];
        ng[1] = -ng[1];
        ng[2] = -ng[2];
    }
}

static void hit_point(const bk_scene *s, const bk_hit *h, float out[3])
{
    double p[3][3];
    if (!bk_tri_positions(s, h->tri, p)) return;
    double w0 = 1.0 - h->u - h->v;
    for (int c = 0; c < 3; c++) out[c] = (float)(w0 * p[0][c] + h->u * p[1][c] + h->v * p[2][c]);
}

/* Whether q, projected onto triangle tri's plane, lies on the triangle (barycentrics >= -1e-4):
 * a pushed point must stay on its own face, not move past its edge onto another surface. */
static int on_own_triangle(const bk_scene *s, uint32_t tri, const float q[3])
{
    double p[3][3], e1[3], e2[3], d[3], n[3];
    if (!bk_tri_positions(s, tri, p)) return 0;
    double qd[3];
    bkv_load(qd, q);
    bkv_sub(e1, p[1], p[0]);
    bkv_sub(e2, p[2], p[0]);
    bkv_sub(d, qd, p[0]);
    bkv_cross(n, e1, e2);
    double nn = bkv_dot(n, n);
    if (!(nn > 0)) return 0;
    double c1[3], c2[3];
    bkv_cross(c1, d, e2);
    bkv_cross(c2, e1, d);
    double u = bkv_dot(c1, n) / nn, v = bkv_dot(c2, n) / nn;
    const double tol = 1e-4;
    return u >= -tol && v >= -tol && u + v <= 1 + tol;
}

/* Whether a pushed point q stays on the texel's own face: on its own triangle, on one of its
 * footprint triangles (its chart's triangles over its square), or — for a texel whose point lies
 * on a triangle's border or corner (the bilinear ring, texels.h, has no footprint) — on a
 * triangle of the same object in the same plane, found by a short probe ray down onto q. So the
 * point moves onto the next triangle of its face, never off the face onto another surface. */
static int on_own_face(const push_job *j, const bk_texel *r, const double ng[3], double band, const float q[3])
{
    const bk_scene *s = j->scene;
    if (on_own_triangle(s, r->tri, q)) return 1;
    for (uint32_t k = 0; k < r->footprint_count; k++)
        if (on_own_triangle(s, j->tx->footprint[r->footprint_first + k].tri, q)) return 1;
    float org[3], dir[3];
    for (int c = 0; c < 3; c++) {
        org[c] = (float)(q[c] + band * ng[c]);
        dir[c] = (float)-ng[c];
    }
    bk_hit h;
    /* q is within `band` of the texel's plane (push_one): the face lies within 2·band below org */
    if (!bk_tracer_intersect(j->tracer, org, dir, 0.0f, (float)(2.5 * band), &h)) return 0;
    if (!s->tri_object || s->tri_object[h.tri] != r->object) return 0;
    double hn[3];
    oriented_geo_normal(s, h.tri, r->normal, hn);
    return bkv_dot(hn, ng) > 0.999;
}

/* A texel whose square is partly hidden behind a surface in front of it (a back face within
 * `band` along the normal: a light panel hung a centimetre under a ceiling, its back to it)
 * loses its footprint and keeps its (pushed) point. A renderer never
 * shows the hidden part, but bilinear filtering spreads the texel's value over the visible
 * surface beside it: averaged over the panel's back-lit ceiling, the ceiling next to the Cornell
 * box's light baked 4–8× too bright (a halo one texel wide). Probed on a 4 × 4 grid of the
 * square's points, one short ray each. */
#define VIS_GRID 4
static void drop_hidden_footprint(const push_job *j, bk_texel *r, double band)
{
    if (!r->footprint_count) return;
    const bk_scene *s = j->scene;
    for (int cy = 0; cy < VIS_GRID; cy++)
        for (int cx = 0; cx < VIS_GRID; cx++) {
            double ps = (cx + 0.5) / VIS_GRID, pt = (cy + 0.5) / VIS_GRID;
            for (uint32_t k = 0; k < r->footprint_count; k++) {
                const bk_footprint_tri *f = &j->tx->footprint[r->footprint_first + k];
                double u = f->uv[0][0] + f->uv[0][1] * ps + f->uv[0][2] * pt;
                double v = f->uv[1][0] + f->uv[1][1] * ps + f->uv[1][2] * pt;
                if (!(u >= 0 && v >= 0 && u + v <= 1)) continue;
                double q[3][3], n[3];
                if (!bk_tri_positions(s, f->tri, q)) break;
                oriented_geo_normal(s, f->tri, r->normal, n);
                float pf[3], nf[3] = {(float)n[0], (float)n[1], (float)n[2]}, org[3];
                for (int c = 0; c < 3; c++) pf[c] = (float)((1 - u - v) * q[0][c] + u * q[1][c] + v * q[2][c]);
                bk_offset_ray_origin_scaled(pf, nf, bk_tracer_tri_scale(j->tracer, f->tri), org);
                bk_hit h;
                if (bk_tracer_intersect(j->tracer, org, nf, 0.0f, (float)band, &h) && !h.front) {
                    r->footprint_count = 0;
                    memset(r->footprint_box, 0, sizeof r->footprint_box);
                    return;
                }
                break;
            }
        }
}

/* Whether the footprint point at texel-local (s, t) lies beyond another surface seen from the
 * texel's point: 1 hidden, 0 visible, -1 no footprint triangle covers it. */
static int footprint_point_hidden(const push_job *j, const bk_texel *r, const double a[3], const double ng[3],
                                  double s, double t)
{
    double p[3], n[3];
    const bk_footprint_tri *fp = j->tx->footprint + r->footprint_first;
    if (!bk_footprint_point(j->scene, fp, r->footprint_count, s, t, p, n)) return -1;
    return bk_footprint_segment_blocked(j->tracer, j->scene, fp, r->footprint_count, r->tri, a, ng, p, n);
}

/* The texel's point on its own triangle's plane: where the push-out carried it onto a surface
 * just above its own (a floor texel beside a panel hung 5 mm over the floor lands on the panel's
 * top), every segment back down to its footprint would cross that surface. */
static void point_on_own_plane(const push_job *j, const bk_texel *r, const double ng[3], double a[3])
{
    double q[3][3];
    for (int c = 0; c < 3; c++) a[c] = r->position[c];
    if (!bk_tri_positions(j->scene, r->tri, q)) return;
    const double h = (a[0] - q[0][0]) * ng[0] + (a[1] - q[0][1]) * ng[1] + (a[2] - q[0][2]) * ng[2];
    for (int c = 0; c < 3; c++) a[c] -= h * ng[c];
}

/* Marks the cells of the texel's square whose footprint points lie beyond another surface, seen
 * from the texel's own (pushed) point: the footprint is the texel's value only where it is the
 * same stretch of surface. A wall texel whose square runs 3 cm into a sill resting in the wall's
 * window reveal gathered a fifth of its rays inside the sill and read 18 % dark (dev level
 * sill_niche_00, against Cycles on the visible part); a wall under a box pushed through it reads
 * the covered part black. Each test is one short segment (bk_footprint_segment_blocked: raised
 * 0.1 % of its length, so a coplanar duplicate face is not "another surface"). A 4 x 4 pass first
 * (16 segments, every footprint texel); only a texel with a hidden cell is marked on the 8 x 8
 * grid the transport rejects samples by (64 more); near the covering surface's edge the
 * transport tests each sample itself (bk_footprint_sample_hidden), so no sample crosses it. */
static void mask_covered_footprint(const push_job *j, bk_texel *r, const double ng[3])
{
    r->footprint_hidden = 0;
    if (!r->footprint_count || (r->flags & BK_TEXEL_INSIDE)) return;
    double a[3];
    point_on_own_plane(j, r, ng, a);
    int any = 0;
    for (int cy = 0; cy < 4 && !any; cy++)
        for (int cx = 0; cx < 4 && !any; cx++)
            any = footprint_point_hidden(j, r, a, ng, (cx + 0.5) / 4, (cy + 0.5) / 4) == 1;
    if (!any) return;
    uint64_t hidden = 0;
    int visible = 0;
    for (int cy = 0; cy < BK_FOOTPRINT_GRID; cy++)
        for (int cx = 0; cx < BK_FOOTPRINT_GRID; cx++) {
            int h = footprint_point_hidden(j, r, a, ng, (cx + 0.5) / BK_FOOTPRINT_GRID,
                                           (cy + 0.5) / BK_FOOTPRINT_GRID);
            if (h == 1)
                hidden |= (uint64_t)1 << (cy * BK_FOOTPRINT_GRID + cx);
            else if (h == 0)
                visible++;
        }
    /* nothing of the square is the texel's own stretch: its point alone */
    if (!visible && hidden) {
        r->footprint_count = 0;
        memset(r->footprint_box, 0, sizeof r->footprint_box);
        return;
    }
    r->footprint_hidden = hidden;
}

static void push_one(const push_job *j, bk_texel *r, bk_pushout_stats *st)
{
    const bk_scene *s = j->scene;
    double ng[3], t[3], b[3];
    oriented_geo_normal(s, r->tri, r->normal, ng);
    bkv_basis(ng, t, b);
    float ngf[3] = {(float)ng[0], (float)ng[1], (float)ng[2]};
    float reach = j->reach * r->texel_size;
    uint32_t cur_tri = r->tri;
    float cur_n[3] = {ngf[0], ngf[1], ngf[2]};
    /* a move must stay on the texel: to a hit this close to the texel's own plane */
    const float p0[3] = {r->position[0], r->position[1], r->position[2]};
    const double band = 0.1 * r->texel_size;
    /* short rays: 8 along the tangent plane (raised ~3°), 5 over the hemisphere */
    double local[13][3];
    for (int i = 0; i < 8; i++) {
        double a = i * (3.14159265358979323846 / 4.0);
        local[i][0] = cos(a) * 0.9986;
        local[i][1] = sin(a) * 0.9986;
        local[i][2] = 0.0523;
    }
    for (int i = 0; i < 4; i++) {
        double a = (i + 0.5) * (3.14159265358979323846 / 2.0);
        local[8 + i][0] = cos(a) * 0.7071;
        local[8 + i][1] = sin(a) * 0.7071;
        local[8 + i][2] = 0.7071;
    }
    local[12][0] = local[12][1] = 0.0;
    local[12][2] = 1.0;
    for (int iter = 0; iter < 3; iter++) {
        float org[3];
        bk_offset_ray_origin_scaled(r->position, cur_n, bk_tracer_tri_scale(j->tracer, cur_tri), org);
        bk_hit best;
        int found = 0;
        for (int i = 0; i < 13; i++) {
            float d[3];
            to_world(t, b, ng, local[i], d);
            bk_hit h;
            if (!bk_tracer_intersect(j->tracer, org, d, 0.0f, reach, &h)) continue;
            if (h.front) continue;
            float q[3] = {p0[0], p0[1], p0[2]};
            hit_point(s, &h, q);
            double height = (q[0] - p0[0]) * ng[0] + (q[1] - p0[1]) * ng[1] + (q[2] - p0[2]) * ng[2];
            if (fabs(height) > band) continue;
            float qo[3]; /* where the point would go: just in front of the surface hit */
            bk_offset_ray_origin_scaled(q, h.ng, bk_tracer_tri_scale(j->tracer, h.tri), qo);
            if (!on_own_face(j, r, ng, band, qo)) continue;
            if (!found || h.t < best.t) {
                best = h;
                found = 1;
            }
        }
        if (!found) break;
        float q[3] = {r->position[0], r->position[1], r->position[2]};
        hit_point(s, &best, q);
        /* just in front of the surface we were behind: its front side is along ng */
        bk_offset_ray_origin_scaled(q, best.ng, bk_tracer_tri_scale(j->tracer, best.tri), r->position);
        cur_tri = best.tri;
        memcpy(cur_n, best.ng, sizeof cur_n);
        r->flags |= BK_TEXEL_PUSHED;
    }
    if (r->flags & BK_TEXEL_PUSHED) st->pushed++;
    drop_hidden_footprint(j, r, band);
    /* inside closed geometry? */
    float org[3];
    bk_offset_ray_origin_scaled(r->position, cur_n, bk_tracer_tri_scale(j->tracer, cur_tri), org);
    int back = 0;
    for (int i = 0; i < LONG_RAYS; i++) {
        double l[3];
        hemisphere_dir(i, LONG_RAYS, l);
        float d[3];
        to_world(t, b, ng, l, d);
        bk_hit h;
        if (bk_tracer_intersect(j->tracer, org, d, 0.0f, j->far_dist, &h) && !h.front) back++;
        /* early out once the answer cannot change */
        if (2 * back >= LONG_RAYS || 2 * (back + LONG_RAYS - 1 - i) < LONG_RAYS) break;
    }
    if (2 * back >= LONG_RAYS) {
        r->flags |= BK_TEXEL_INSIDE; /* still baked: black inside closed solids (texels.h) */
        st->inside++;
    }
    mask_covered_footprint(j, r, ng);
    st->tested++;
}

static void push_chunk(void *user, size_t begin, size_t end, int thread)
{
    const push_job *j = user;
    for (size_t i = begin; i < end; i++) push_one(j, &j->tx->receivers[i], &j->thread_stats[thread]);
}

lbk_result bk_texels_push_out(bk_texels *tx, const bk_scene *scene, const bk_tracer *tracer,
                              const bk_pushout_options *opt, bk_pushout_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    if (!tx || !scene || !tracer) return LBK_ERR_INVALID_ARGUMENT;
    float reach = opt && opt->reach > 0.0f && isfinite(opt->reach) ? opt->reach : 1.5f;
    int threads = bk_thread_count(opt ? opt->threads : 0);
    /* long rays: beyond the scene's extent */
    double diag = 0.0;
    for (int c = 0; c < 3; c++) {
        double d = (double)scene->bounds_max[c] - scene->bounds_min[c];
        if (isfinite(d) && d > 0) diag += d * d;
    }
    float far_dist = diag > 0.0 ? (float)(2.0 * sqrt(diag)) : FLT_MAX;
    if (!isfinite(far_dist) || far_dist <= 0.0f) far_dist = FLT_MAX;
    push_job job = {tx, scene, tracer, reach, far_dist, calloc((size_t)threads, sizeof(bk_pushout_stats))};
    if (!job.thread_stats) return LBK_ERR_OUT_OF_MEMORY;
    /* 64 receivers a chunk (up to 3·13 short and 16 long rays each): coarse enough to hide the
     * shared counter, fine enough to balance walls against cluttered corners */
    bk_parallel_chunks(0, tx->count, 64, threads, push_chunk, &job);
    if (stats)
        for (int k = 0; k < threads; k++) {
            stats->tested += job.thread_stats[k].tested;
            stats->pushed += job.thread_stats[k].pushed;
            stats->inside += job.thread_stats[k].inside;
        }
    free(job.thread_stats);
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Dilation                                                                                 */

#define DILATE_NEW 0xFFu /* filled during the current pass */

size_t bk_dilate(float *data, int channels, uint8_t *mask, int width, int height, int passes)
{
    if (!data || !mask || channels <= 0 || width <= 0 || height <= 0 || passes <= 0) return 0;
    size_t n = (size_t)width * (size_t)height;
    for (size_t i = 0; i < n; i++)
        if (mask[i] == DILATE_NEW) mask[i] = 1;
    size_t filled = 0;
    static const int d4[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    static const int dd[4][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
    for (int pass = 0; pass < passes; pass++) {
        size_t this_pass = 0;
        for (int y = 0; y < height; y++)
            for (int x = 0; x < width; x++) {
                size_t i = (size_t)y * (size_t)width + (size_t)x;
                if (mask[i]) continue;
                for (int set = 0; set < 2; set++) {
                    const int(*d)[2] = set ? dd : d4;
                    int cnt = 0;
                    for (int k = 0; k < 4; k++) {
                        int nx = x + d[k][0], ny = y + d[k][1];
                        if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
                        uint8_t m = mask[(size_t)ny * (size_t)width + (size_t)nx];
                        if (m && m != DILATE_NEW) cnt++;
                    }
                    if (!cnt) continue;
                    float *dst = data + i * (size_t)channels;
                    for (int c = 0; c < channels; c++) {
                        double acc = 0.0;
                        for (int k = 0; k < 4; k++) {
                            int nx = x + d[k][0], ny = y + d[k][1];
                            if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
                            size_t j = (size_t)ny * (size_t)width + (size_t)nx;
                            if (mask[j] && mask[j] != DILATE_NEW) acc += data[j * (size_t)channels + (size_t)c];
                        }
                        dst[c] = (float)(acc / cnt);
                    }
                    mask[i] = DILATE_NEW;
                    this_pass++;
                    break;
                }
            }
        for (size_t i = 0; i < n; i++)
            if (mask[i] == DILATE_NEW) mask[i] = 2;
        filled += this_pass;
        if (this_pass == 0) break;
    }
    return filled;
}
