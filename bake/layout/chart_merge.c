/* Merging small generated charts into a neighbour by hinge unfolding (see chart_merge.h). */
#include "bake/layout/chart_merge.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/uv_math.h"

#define SMALL_AREA 16
#define TINY_AREA 4
#define HARD_EDGE_COS 0.5   /* cos 60° */
#define OVERLAP_EPS 1e-4
#define NONE UINT32_MAX

typedef struct merge_ctx {
    const bk_scene *s;
    const bk_chart_graph *g;
    bk_uv_object *o;
    double density;
    int cap;
    uint32_t *pos_of;          /* local triangle → entry of o->tris, NONE */
    uint32_t *chart_of;        /* entry → chart */
    uint32_t *next;            /* entry → next entry of the same chart, NONE */
    uint32_t *head, *tail, *count;
    float *w, *h;              /* per chart extent */
    uint8_t *dead;             /* chart merged into another */
    uint32_t *slot;            /* entry → index in the trial buffers + 1, 0: not in the trial */
    double *uv;                /* trial: 6 per laid triangle */
    uint32_t *laid;            /* trial: entries in laying order */
} merge_ctx;

static int content(float e) { return e <= 1.0f ? 1 : (int)ceil((double)e); }
static long long block(float w, float h) { return (long long)(content(w) + 2) * (content(h) + 2); }

static int is_small(const merge_ctx *m, uint32_t c)
{
    int cw = content(m->w[c]), ch = content(m->h[c]);
    return cw * ch <= SMALL_AREA || cw <= 1 || ch <= 1;
}

static void world(const merge_ctx *m, uint32_t entry, int k, double p[3])
{
    uint32_t tri = m->o->tris[entry];
    bkv_load(p, m->s->positions + 3 * (size_t)m->s->tris[3 * (size_t)tri + (size_t)k]);
}

static int is_tiny(const merge_ctx *m, uint32_t c) { return content(m->w[c]) * content(m->h[c]) <= TINY_AREA; }

/* Cosine of the angle between the face normals of two entries (1: coplanar). */
static double hinge_cos(const merge_ctx *m, uint32_t a, uint32_t b)
{
    double p[3][3], na[3], nb[3];
    for (int k = 0; k < 3; k++) world(m, a, k, p[k]);
    bk_tri_cross(p, na);
    for (int k = 0; k < 3; k++) world(m, b, k, p[k]);
    bk_tri_cross(p, nb);
    if (bkv_normalize(na) == 0.0 || bkv_normalize(nb) == 0.0) return -1.0;
    return bkv_dot(na, nb);
}

/* The corners (ka, kb of local triangle t; ja, jb of local u) of the edge t and u share;
 * 0 when they share none. */
static int shared_edge(const merge_ctx *m, uint32_t t, uint32_t u, int *ka, int *kb, int *ja, int *jb)
{
    const uint32_t *wt = m->g->wid + 3 * (size_t)t, *wu = m->g->wid + 3 * (size_t)u;
    for (int k = 0; k < 3; k++) {
        int k2 = (k + 1) % 3;
        for (int j = 0; j < 3; j++) {
            int j2 = (j + 1) % 3;
            if (wt[k] == NONE || wt[k2] == NONE) continue;
            if (wt[k] == wu[j2] && wt[k2] == wu[j]) {
                *ka = k, *kb = k2, *ja = j2, *jb = j;
                return 1;
            }
            if (wt[k] == wu[j] && wt[k2] == wu[j2]) {
                *ka = k, *kb = k2, *ja = j, *jb = j2;
                return 1;
            }
        }
    }
    return 0;
}

static double edge_length(const merge_ctx *m, uint32_t entry, int ka, int kb)
{
    double a[3], b[3], d[3];
    world(m, entry, ka, a);
    world(m, entry, kb, b);
    bkv_sub(d, b, a);
    return bkv_len(d);
}

static double cross2(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Lays triangle `entry` with corners ka, kb at ua, ub: corner kc goes where the similarity
 * of the hinge puts it, on the side that keeps the triangle counter-clockwise, which must be
 * the side away from `other` (the third corner across the hinge). Returns 0 when it cannot. */
static int lay(const merge_ctx *m, uint32_t entry, int ka, int kb, const double ua[2], const double ub[2],
               const double other[2], double out[6])
{
    int kc = 3 - ka - kb;
    double pa[3], pb[3], pc[3], e[3], f[3];
    world(m, entry, ka, pa);
    world(m, entry, kb, pb);
    world(m, entry, kc, pc);
    bkv_sub(e, pb, pa);
    bkv_sub(f, pc, pa);
    double l2 = bkv_dot(e, e);
    if (!(l2 > 0.0)) return 0;
    double along = bkv_dot(f, e) / l2, perp[3];
    for (int c = 0; c < 3; c++) perp[c] = f[c] - along * e[c];
    double hgt = bkv_len(perp) / sqrt(l2);
    double d[2] = {ub[0] - ua[0], ub[1] - ua[1]};
    out[2 * ka] = ua[0], out[2 * ka + 1] = ua[1];
    out[2 * kb] = ub[0], out[2 * kb + 1] = ub[1];
    for (int side = 1; side >= -1; side -= 2) {
        out[2 * kc] = ua[0] + along * d[0] - side * hgt * d[1];
        out[2 * kc + 1] = ua[1] + along * d[1] + side * hgt * d[0];
        if (cross2(out, out + 2, out + 4) > 0.0) break;
        if (side == -1) return 0;
    }
    double so = d[0] * (other[1] - ua[1]) - d[1] * (other[0] - ua[0]);
    double sq = d[0] * (out[2 * kc + 1] - ua[1]) - d[1] * (out[2 * kc] - ua[0]);
    return so * sq < 0.0;
}

/* Interiors of two triangles overlap (no separating edge axis, with a tolerance). */
static int tri_overlap(const double *a, const double *b)
{
    const double *t[2] = {a, b};
    for (int s = 0; s < 2; s++)
        for (int k = 0; k < 3; k++) {
            const double *p = t[s] + 2 * k, *q = t[s] + 2 * ((k + 1) % 3);
            double nx = q[1] - p[1], ny = p[0] - q[0], len = sqrt(nx * nx + ny * ny);
            if (!(len > 0.0)) continue;
            double mn[2] = {INFINITY, INFINITY}, mx[2] = {-INFINITY, -INFINITY};
            for (int u = 0; u < 2; u++)
                for (int c = 0; c < 3; c++) {
                    double v = (nx * t[u][2 * c] + ny * t[u][2 * c + 1]) / len;
                    mn[u] = fmin(mn[u], v);
                    mx[u] = fmax(mx[u], v);
                }
            if (mx[0] <= mn[1] + OVERLAP_EPS || mx[1] <= mn[0] + OVERLAP_EPS) return 0;
        }
    return 1;
}

static void entry_uv(const merge_ctx *m, uint32_t entry, double out[6])
{
    for (int k = 0; k < 6; k++) out[k] = m->o->uv[6 * (size_t)entry + (size_t)k];
}

/* The uv of an entry in the trial (laid) or, for the neighbour, as it is. */
static const double *trial_uv(const merge_ctx *m, uint32_t entry) { return m->uv + 6 * (size_t)(m->slot[entry] - 1); }

/* Lays every triangle of chart c onto chart n, starting across the longest shared edge;
 * returns how many were laid (all of c, or 0 when it cannot be done). */
static uint32_t unfold(merge_ctx *m, uint32_t c, uint32_t n)
{
    const bk_chart_graph *g = m->g;
    uint32_t seed = NONE, nb_seed = NONE;
    int ka = 0, kb = 0, ja = 0, jb = 0;
    double best = 0.0;
    for (uint32_t e = m->head[c]; e != NONE; e = m->next[e]) {
        uint32_t t = m->o->tris[e] - g->first;
        for (uint32_t k = g->adj_start[t]; k < g->adj_start[t + 1]; k++) {
            uint32_t pe = m->pos_of[g->adj[k]];
            int a, b, x, y;
            if (pe == NONE || m->chart_of[pe] != n || !shared_edge(m, t, g->adj[k], &a, &b, &x, &y)) continue;
            double l = edge_length(m, e, a, b);
            if (l > best) {
                best = l, seed = e, nb_seed = pe;
                ka = a, kb = b, ja = x, jb = y;
            }
        }
    }
    if (seed == NONE) return 0;
    /* a fold steeper than 60° is a hard edge: filtering across it would mix two faces' light,
     * so only a tiny chart (no texel of its own to lose) crosses one */
    if (!is_tiny(m, c) && hinge_cos(m, seed, nb_seed) < HARD_EDGE_COS) return 0;
    double nuv[6];
    entry_uv(m, nb_seed, nuv);
    double ua[2] = {nuv[2 * ja], nuv[2 * ja + 1]}, ub[2] = {nuv[2 * jb], nuv[2 * jb + 1]};
    double scale = sqrt((ub[0] - ua[0]) * (ub[0] - ua[0]) + (ub[1] - ua[1]) * (ub[1] - ua[1])) / best;
    if (!(scale >= 0.5 * m->density && scale <= 2.0 * m->density)) return 0;
    int jc = 3 - ja - jb;
    double other[2] = {nuv[2 * jc], nuv[2 * jc + 1]};
    uint32_t nl = 0;
    m->laid[nl] = seed;
    m->slot[seed] = nl + 1;
    if (!lay(m, seed, ka, kb, ua, ub, other, m->uv)) {
        m->slot[seed] = 0;
        return 0;
    }
    nl++;
    int ok = 1;
    /* breadth first over c's own edges; each triangle laid across the edge it was reached by */
    for (uint32_t q = 0; q < nl && ok; q++) {
        uint32_t e = m->laid[q], t = m->o->tris[e] - g->first;
        const double *tu = trial_uv(m, e);
        for (uint32_t k = g->adj_start[t]; k < g->adj_start[t + 1] && ok; k++) {
            uint32_t pe = m->pos_of[g->adj[k]];
            int a, b, x, y;
            if (pe == NONE || m->chart_of[pe] != c || m->slot[pe] || !shared_edge(m, g->adj[k], t, &a, &b, &x, &y))
                continue;
            double pa[2] = {tu[2 * x], tu[2 * x + 1]}, pb[2] = {tu[2 * y], tu[2 * y + 1]};
            int z = 3 - x - y;
            double ot[2] = {tu[2 * z], tu[2 * z + 1]};
            m->laid[nl] = pe;
            m->slot[pe] = nl + 1;
            ok = lay(m, pe, a, b, pa, pb, ot, m->uv + 6 * (size_t)nl);
            nl++;
        }
    }
    if (!ok || nl != m->count[c]) {
        for (uint32_t i = 0; i < nl; i++) m->slot[m->laid[i]] = 0;
        return 0;
    }
    return nl;
}

/* Whether laid triangles overlap each other or a triangle of chart n. */
static int laid_overlaps(const merge_ctx *m, uint32_t n, uint32_t nl)
{
    for (uint32_t i = 0; i < nl; i++) {
        const double *a = m->uv + 6 * (size_t)i;
        double amn[2] = {fmin(a[0], fmin(a[2], a[4])), fmin(a[1], fmin(a[3], a[5]))};
        double amx[2] = {fmax(a[0], fmax(a[2], a[4])), fmax(a[1], fmax(a[3], a[5]))};
        for (uint32_t j = i + 1; j < nl; j++)
            if (tri_overlap(a, m->uv + 6 * (size_t)j)) return 1;
        for (uint32_t e = m->head[n]; e != NONE; e = m->next[e]) {
            double b[6];
            entry_uv(m, e, b);
            if (fmax(b[0], fmax(b[2], b[4])) <= amn[0] || fmin(b[0], fmin(b[2], b[4])) >= amx[0] ||
                fmax(b[1], fmax(b[3], b[5])) <= amn[1] || fmin(b[1], fmin(b[3], b[5])) >= amx[1])
                continue;
            if (tri_overlap(a, b)) return 1;
        }
    }
    return 0;
}

/* Moves (x, y) of the merged chart to its final place: shifted to the origin, turned
 * landscape (the quarter turn (y, w − x) of uvgen). */
static void settle(double *x, double *y, const double mn[2], double w, double h, int turn)
{
    double px = *x - mn[0], py = *y - mn[1];
    if (turn) {
        double t = px;
        px = py;
        py = w - t;
    }
    double fw = turn ? h : w, fh = turn ? w : h;
    *x = fmin(fmax(px, 0.0), fw);
    *y = fmin(fmax(py, 0.0), fh);
}

/* Merges chart c into n when the rules of chart_merge.h allow; returns 1 when done. */
static int try_merge(merge_ctx *m, uint32_t c, uint32_t n)
{
    uint32_t nl = unfold(m, c, n);
    if (nl == 0) return 0;
    int done = 0;
    double mn[2] = {INFINITY, INFINITY}, mx[2] = {-INFINITY, -INFINITY};
    for (uint32_t e = m->head[n]; e != NONE; e = m->next[e])
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 2; a++) {
                double v = m->o->uv[6 * (size_t)e + 2 * (size_t)k + (size_t)a];
                mn[a] = fmin(mn[a], v), mx[a] = fmax(mx[a], v);
            }
    for (uint32_t i = 0; i < nl; i++)
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 2; a++) {
                double v = m->uv[6 * (size_t)i + 2 * (size_t)k + (size_t)a];
                mn[a] = fmin(mn[a], v), mx[a] = fmax(mx[a], v);
            }
    double w = mx[0] - mn[0], h = mx[1] - mn[1];
    int turn = h > w * (1.0 + 1e-9);
    if (fmax(w, h) <= m->cap && block((float)w, (float)h) < block(m->w[n], m->h[n]) + block(m->w[c], m->h[c]) &&
        !laid_overlaps(m, n, nl)) {
        for (uint32_t e = m->head[n]; e != NONE; e = m->next[e])
            for (int k = 0; k < 3; k++) {
                double x = m->o->uv[6 * (size_t)e + 2 * (size_t)k], y = m->o->uv[6 * (size_t)e + 2 * (size_t)k + 1];
                settle(&x, &y, mn, w, h, turn);
                m->o->uv[6 * (size_t)e + 2 * (size_t)k] = (float)x;
                m->o->uv[6 * (size_t)e + 2 * (size_t)k + 1] = (float)y;
            }
        for (uint32_t i = 0; i < nl; i++)
            for (int k = 0; k < 3; k++) {
                double x = m->uv[6 * (size_t)i + 2 * (size_t)k], y = m->uv[6 * (size_t)i + 2 * (size_t)k + 1];
                settle(&x, &y, mn, w, h, turn);
                m->o->uv[6 * (size_t)m->laid[i] + 2 * (size_t)k] = (float)x;
                m->o->uv[6 * (size_t)m->laid[i] + 2 * (size_t)k + 1] = (float)y;
            }
        for (uint32_t e = m->head[c]; e != NONE; e = m->next[e]) m->chart_of[e] = n;
        m->next[m->tail[n]] = m->head[c];
        m->tail[n] = m->tail[c];
        m->count[n] += m->count[c];
        m->w[n] = (float)(turn ? h : w);
        m->h[n] = (float)(turn ? w : h);
        m->dead[c] = 1;
        done = 1;
    }
    for (uint32_t i = 0; i < nl; i++) m->slot[m->laid[i]] = 0;
    return done;
}

typedef struct nb_len {
    uint32_t chart;
    double len;
} nb_len;

static int cmp_nb(const void *a, const void *b)
{
    const nb_len *x = a, *y = b;
    if (x->len != y->len) return x->len > y->len ? -1 : 1;
    return (x->chart > y->chart) - (x->chart < y->chart);
}

/* The charts next to c with the length of edge they share, longest first, into nb (cap
 * entries); returns how many. */
static size_t neighbours(const merge_ctx *m, uint32_t c, nb_len *nb, size_t cap)
{
    const bk_chart_graph *g = m->g;
    size_t k = 0;
    for (uint32_t e = m->head[c]; e != NONE; e = m->next[e]) {
        uint32_t t = m->o->tris[e] - g->first;
        for (uint32_t a = g->adj_start[t]; a < g->adj_start[t + 1]; a++) {
            uint32_t pe = m->pos_of[g->adj[a]];
            int ka, kb, ja, jb;
            if (pe == NONE || m->chart_of[pe] == c || !shared_edge(m, t, g->adj[a], &ka, &kb, &ja, &jb)) continue;
            uint32_t n = m->chart_of[pe];
            size_t i = 0;
            while (i < k && nb[i].chart != n) i++;
            if (i == k) {
                if (k == cap) continue;
                nb[k].chart = n;
                nb[k].len = 0.0;
                k++;
            }
            nb[i].len += edge_length(m, e, ka, kb);
        }
    }
    qsort(nb, k, sizeof *nb, cmp_nb);
    return k;
}

typedef struct area_key {
    int area;
    uint32_t chart;
} area_key;

static int cmp_area(const void *a, const void *b)
{
    const area_key *x = a, *y = b;
    if (x->area != y->area) return x->area < y->area ? -1 : 1;
    return (x->chart > y->chart) - (x->chart < y->chart);
}

/* Rewrites o's arrays chart by chart (surviving charts in their order, entries in list
 * order). */
static lbk_result rebuild(merge_ctx *m)
{
    bk_uv_object *o = m->o;
    size_t nt = o->tri_count, nc = 0;
    bk_uv_chart *ch = malloc((o->chart_count ? o->chart_count : 1) * sizeof *ch);
    uint32_t *tris = malloc((nt ? nt : 1) * sizeof *tris);
    float *uv = malloc((nt ? nt : 1) * 6 * sizeof *uv);
    if (!ch || !tris || !uv) {
        free(ch), free(tris), free(uv);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t t = 0;
    for (uint32_t c = 0; c < o->chart_count; c++) {
        if (m->dead[c]) continue;
        ch[nc].first = (uint32_t)t;
        ch[nc].count = m->count[c];
        ch[nc].width = m->w[c];
        ch[nc].height = m->h[c];
        nc++;
        for (uint32_t e = m->head[c]; e != NONE; e = m->next[e], t++) {
            tris[t] = o->tris[e];
            memcpy(uv + 6 * t, o->uv + 6 * (size_t)e, 6 * sizeof *uv);
        }
    }
    free(o->charts), free(o->tris), free(o->uv);
    o->charts = ch;
    o->tris = tris;
    o->uv = uv;
    o->chart_count = nc;
    return LBK_OK;
}

static void ctx_free(merge_ctx *m)
{
    free(m->pos_of), free(m->chart_of), free(m->next), free(m->head), free(m->tail), free(m->count);
    free(m->w), free(m->h), free(m->dead), free(m->slot), free(m->uv), free(m->laid);
}

static lbk_result ctx_init(merge_ctx *m)
{
    bk_uv_object *o = m->o;
    size_t nt = o->tri_count, nc = o->chart_count, n = m->g->n;
    m->pos_of = malloc((n ? n : 1) * sizeof *m->pos_of);
    m->chart_of = malloc(nt * sizeof *m->chart_of);
    m->next = malloc(nt * sizeof *m->next);
    m->slot = calloc(nt, sizeof *m->slot);
    m->laid = malloc(nt * sizeof *m->laid);
    m->uv = malloc(nt * 6 * sizeof *m->uv);
    m->head = malloc(nc * sizeof *m->head);
    m->tail = malloc(nc * sizeof *m->tail);
    m->count = malloc(nc * sizeof *m->count);
    m->w = malloc(nc * sizeof *m->w);
    m->h = malloc(nc * sizeof *m->h);
    m->dead = calloc(nc, 1);
    if (!m->pos_of || !m->chart_of || !m->next || !m->slot || !m->laid || !m->uv || !m->head || !m->tail ||
        !m->count || !m->w || !m->h || !m->dead)
        return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < n; i++) m->pos_of[i] = NONE;
    for (uint32_t c = 0; c < nc; c++) {
        const bk_uv_chart *ch = &o->charts[c];
        m->head[c] = ch->first;
        m->tail[c] = ch->first + ch->count - 1;
        m->count[c] = ch->count;
        m->w[c] = ch->width;
        m->h[c] = ch->height;
        for (uint32_t i = ch->first; i < ch->first + ch->count; i++) {
            m->pos_of[o->tris[i] - m->g->first] = i;
            m->chart_of[i] = c;
            m->next[i] = i + 1 < ch->first + ch->count ? i + 1 : NONE;
        }
    }
    return LBK_OK;
}

lbk_result bk_merge_small_charts(const bk_scene *s, const bk_chart_graph *g, double density, int cap,
                                 bk_uv_object *o, size_t *merged)
{
    *merged = 0;
    if (o->chart_count < 2) return LBK_OK;
    merge_ctx m;
    memset(&m, 0, sizeof m);
    m.s = s, m.g = g, m.o = o, m.density = density, m.cap = cap;
    lbk_result r = ctx_init(&m);
    size_t nc = o->chart_count, nsmall = 0;
    area_key *order = r == LBK_OK ? malloc(nc * sizeof *order) : NULL;
    enum { MAX_NB = 32 };
    nb_len nb[MAX_NB];
    if (r == LBK_OK && !order) r = LBK_ERR_OUT_OF_MEMORY;
    for (uint32_t c = 0; r == LBK_OK && c < nc; c++)
        if (is_small(&m, c)) {
            order[nsmall].area = content(m.w[c]) * content(m.h[c]);
            order[nsmall].chart = c;
            nsmall++;
        }
    if (r == LBK_OK) qsort(order, nsmall, sizeof *order, cmp_area);
    for (size_t i = 0; r == LBK_OK && i < nsmall; i++) {
        uint32_t c = order[i].chart;
        if (m.dead[c] || !is_small(&m, c)) continue;
        size_t k = neighbours(&m, c, nb, MAX_NB);
        for (size_t j = 0; j < k; j++)
            if (try_merge(&m, c, nb[j].chart)) {
                (*merged)++;
                break;
            }
    }
    if (r == LBK_OK && *merged) r = rebuild(&m);
    free(order);
    ctx_free(&m);
    return r;
}
