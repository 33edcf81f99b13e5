/* Pack error against the source (pack_error.h). */
#include "tools/convert/pack_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/error_util.h"
#include "tools/convert/charts.h"

/* Level-wide histogram: bin 0 holds exact zeros (and anything below 1e-7), then HIST_PER_DECADE
 * logarithmic bins per decade from 1e-7 to 1e3; larger errors land in the last bin. */
#define HIST_PER_DECADE 256
#define HIST_LO_EXP (-7)
#define HIST_DECADES 10
#define HIST_BINS (1 + HIST_PER_DECADE * HIST_DECADES)

typedef struct hist {
    uint64_t n[HIST_BINS];
    uint64_t count;
    double sum, max;
} hist;

static void hist_add(hist *h, double x)
{
    int b = 0;
    if (x >= 1e-7) {
        b = 1 + (int)floor((log10(x) - HIST_LO_EXP) * HIST_PER_DECADE);
        if (b >= HIST_BINS) b = HIST_BINS - 1;
    }
    h->n[b]++;
    h->count++;
    h->sum += x;
    if (x > h->max) h->max = x;
}

static tl_pack_stats hist_stats(const hist *h)
{
    tl_pack_stats s = {h->count, 0, 0, 0};
    if (!h->count) return s;
    s.mean = h->sum / (double)h->count;
    s.max = h->max;
    /* the rank of the exact nearest-rank p99 (as in the per-object stats), found in its bin */
    const uint64_t rank = (uint64_t)(0.99 * (double)(h->count - 1));
    uint64_t seen = 0;
    for (int b = 0; b < HIST_BINS; b++) {
        seen += h->n[b];
        if (seen > rank) {
            const double edge = b ? pow(10.0, HIST_LO_EXP + (double)b / HIST_PER_DECADE) : 0.0;
            s.p99 = edge < h->max ? edge : h->max;
            break;
        }
    }
    return s;
}

/* Samples of one object, exact statistics. */
typedef struct vec {
    float *v;
    size_t n, cap;
} vec;

static int vec_push(vec *s, double x)
{
    if (s->n == s->cap) {
        const size_t cap = s->cap ? 2 * s->cap : 1024;
        float *v = realloc(s->v, cap * sizeof *v);
        if (!v) return -1;
        s->v = v, s->cap = cap;
    }
    s->v[s->n++] = (float)x;
    return 0;
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static tl_pack_stats vec_stats(vec *s)
{
    tl_pack_stats r = {s->n, 0, 0, 0};
    if (!s->n) return r;
    double sum = 0;
    for (size_t i = 0; i < s->n; i++) sum += s->v[i];
    qsort(s->v, s->n, sizeof *s->v, cmp_float);
    r.mean = sum / (double)s->n;
    r.p99 = s->v[(size_t)(0.99 * (double)(s->n - 1))];
    r.max = s->v[s->n - 1];
    return r;
}

static double lum(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* A texel the baker never wrote (a rectangle's unused corner): all zero, not drawn. */
static int unwritten(const tl_bake *b, uint32_t page, uint32_t x, uint32_t y)
{
    lbk_ahd_texel_f t;
    if (tl_bake_texel_get(b, page, x, y, &t, NULL, NULL)) return 1;
    return t.ez[0] == 0 && t.ez[1] == 0 && t.ez[2] == 0 && t.rgba[0] == 0 && t.rgba[3] == 0;
}

/* 1% of the mean luminance at +Z over the objects' written texels. */
static double luminance_floor(const tl_bake *a)
{
    double sum = 0;
    uint64_t n = 0;
    for (uint32_t i = 0; i < a->objs.count; i++) {
        lbk_object o;
        lbk_objects_get(&a->objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP) continue;
        for (uint32_t y = 0; y < o.rect_h; y++)
            for (uint32_t x = 0; x < o.rect_w; x++) {
                float v[TL_TEXEL_NORMALS][3];
                if (unwritten(a, o.index, o.rect_x + x, o.rect_y + y) ||
                    tl_bake_texel_eval(a, o.index, o.rect_x + x, o.rect_y + y, v))
                    continue;
                sum += lum(v[0]), n++;
            }
    }
    return n ? 0.01 * sum / (double)n : 0;
}

/* Per page: how many objects' rectangles touch each 4×4 block (saturating at 255). */
static uint8_t *block_owners(const tl_bake *b, uint32_t page, uint32_t w, uint32_t h)
{
    const uint32_t bw = (w + 3) / 4, bh = (h + 3) / 4;
    uint8_t *n = calloc((size_t)bw * bh + 1, 1);
    if (!n) return NULL;
    for (uint32_t i = 0; i < b->objs.count; i++) {
        lbk_object o;
        lbk_objects_get(&b->objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP || o.index != page || !o.rect_w || !o.rect_h) continue;
        for (uint32_t by = o.rect_y / 4; by <= (o.rect_y + o.rect_h - 1) / 4 && by < bh; by++)
            for (uint32_t bx = o.rect_x / 4; bx <= (o.rect_x + o.rect_w - 1) / 4 && bx < bw; bx++)
                if (n[(size_t)by * bw + bx] < 255) n[(size_t)by * bw + bx]++;
    }
    return n;
}

/* A seam texel: a gutter texel (no chart covers its centre) or one within TL_SEAM_TEXELS
 * (Chebyshev) of a texel of another chart, a gutter or the page's edge — the texels a bilinear
 * sample at a chart's border reads, where a block that mixes two charts would show. */
static int is_seam(const int32_t *m, uint32_t w, uint32_t h, uint32_t x, uint32_t y)
{
    const int32_t id = m[(size_t)y * w + x];
    if (id < 0) return 1;
    const int r = TL_SEAM_TEXELS;
    for (int dy = -r; dy <= r; dy++)
        for (int dx = -r; dx <= r; dx++) {
            const int64_t nx = (int64_t)x + dx, ny = (int64_t)y + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h || m[(size_t)ny * w + (size_t)nx] != id) return 1;
        }
    return 0;
}

typedef struct acc {
    hist all_l, all_c, seam_l, seam_c, shared_l, shared_c;
    uint64_t texels, shared_texels;
    double y_floor;
} acc;

/* One object's texels: its exact statistics into *oe, its samples into the level histograms. */
static int compare_object(const tl_bake *a, const tl_bake *p, const lbk_object *o, const uint8_t *owners,
                          const int32_t *charts, uint32_t w, uint32_t h, acc *g, tl_pack_object_error *oe)
{
    vec v[4] = {{0}}; /* lum, colour, seam lum, seam colour */
    int rc = 0;
    for (uint32_t y = 0; y < o->rect_h && !rc; y++)
        for (uint32_t x = 0; x < o->rect_w && !rc; x++) {
            const uint32_t px = o->rect_x + x, py = o->rect_y + y;
            float va[TL_TEXEL_NORMALS][3], vp[TL_TEXEL_NORMALS][3];
            if (unwritten(a, o->index, px, py) || tl_bake_texel_eval(a, o->index, px, py, va) ||
                tl_bake_texel_eval(p, o->index, px, py, vp))
                continue;
            if (px >= w || py >= h) continue;
            const int seam = is_seam(charts, w, h, px, py);
            const int shared = owners[(size_t)(py / 4) * ((w + 3) / 4) + px / 4] > 1;
            oe->texels++, g->texels++;
            g->shared_texels += (uint64_t)shared;
            for (int n = 0; n < TL_TEXEL_NORMALS && !rc; n++) {
                const double ya = lum(va[n]), yp = lum(vp[n]);
                const double el = fabs(yp - ya) / fmax(ya, g->y_floor);
                rc |= vec_push(&v[0], el);
                hist_add(&g->all_l, el);
                if (seam) rc |= vec_push(&v[2], el), hist_add(&g->seam_l, el);
                if (shared) hist_add(&g->shared_l, el);
                const double sa = va[n][0] + va[n][1] + va[n][2], sp = vp[n][0] + vp[n][1] + vp[n][2];
                if (!(ya > g->y_floor && sa > 0 && sp > 0)) continue;
                const double ec = hypot(vp[n][0] / sp - va[n][0] / sa, vp[n][1] / sp - va[n][1] / sa);
                rc |= vec_push(&v[1], ec);
                hist_add(&g->all_c, ec);
                if (seam) rc |= vec_push(&v[3], ec), hist_add(&g->seam_c, ec);
                if (shared) hist_add(&g->shared_c, ec);
            }
        }
    oe->all.lum = vec_stats(&v[0]);
    oe->all.colour = vec_stats(&v[1]);
    oe->seam.lum = vec_stats(&v[2]);
    oe->seam.colour = vec_stats(&v[3]);
    for (int i = 0; i < 4; i++) free(v[i].v);
    return rc;
}

int tl_pack_error_compute(const tl_bake *a, const tl_bake *p, tl_pack_error *out, char err[TL_ERR_LEN])
{
    memset(out, 0, sizeof *out);
    if (!a->has_lmap || !p->has_lmap || !a->has_objs || !p->has_objs)
        return tl_fail(err, -1, "pack error: the source or the pack has no lightmap");
    if (a->objs.count != p->objs.count || a->lmap.page_count != p->lmap.page_count)
        return tl_fail(err, -1, "pack error: the pack's objects or pages are not the source's");
    acc *g = calloc(1, sizeof *g);
    out->objects = calloc((size_t)a->objs.count + 1, sizeof *out->objects);
    if (!g || !out->objects) {
        free(g), free(out->objects), out->objects = NULL;
        return tl_fail(err, -1, "out of memory");
    }
    g->y_floor = luminance_floor(a);
    /* per page, how many rectangles touch each block (blocks are 1/16 of the texels) */
    const uint32_t np = p->lmap.page_count;
    uint8_t **owners = calloc((size_t)np + 1, sizeof *owners);
    int32_t **charts = calloc((size_t)np + 1, sizeof *charts);
    uint32_t *pw = calloc((size_t)np + 1, sizeof *pw), *ph = calloc((size_t)np + 1, sizeof *ph);
    int32_t next_id = 0;
    int rc = owners && charts && pw && ph ? 0 : tl_fail(err, -1, "out of memory");
    for (uint32_t pg = 0; pg < np && !rc; pg++) {
        lbk_lmap_planes pl;
        if (tl_bake_planes(p, pg, &pl)) continue;
        pw[pg] = pl.width, ph[pg] = pl.height;
        owners[pg] = block_owners(p, pg, pl.width, pl.height);
        charts[pg] = tl_chart_map(&a->objs, a->has_lmuv ? &a->lmuv : NULL, pg, pl.width, pl.height, &next_id);
        if (!owners[pg] || !charts[pg]) rc = tl_fail(err, -1, "out of memory");
    }
    for (uint32_t i = 0; i < a->objs.count && !rc; i++) {
        lbk_object o, q;
        lbk_objects_get(&a->objs, i, &o);
        lbk_objects_get(&p->objs, i, &q);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP || o.index >= np) continue;
        if (q.representation != o.representation || q.index != o.index || q.rect_x != o.rect_x ||
            q.rect_y != o.rect_y || q.rect_w != o.rect_w || q.rect_h != o.rect_h) {
            rc = tl_fail(err, -1, "pack error: object %u's rectangle differs in the pack", i);
            break;
        }
        tl_pack_object_error *oe = &out->objects[out->object_count++];
        oe->object = i;
        oe->name = strndup(o.name.data ? o.name.data : "", o.name.size);
        if (!oe->name) {
            rc = tl_fail(err, -1, "out of memory");
            break;
        }
        if (!owners[o.index] || !charts[o.index]) continue;
        if (compare_object(a, p, &o, owners[o.index], charts[o.index], pw[o.index], ph[o.index], g, oe))
            rc = tl_fail(err, -1, "out of memory");
    }
    for (uint32_t pg = 0; owners && charts && pg < np; pg++) free(owners[pg]), free(charts[pg]);
    free(owners), free(charts), free(pw), free(ph);
    out->y_floor = g->y_floor;
    out->texels = g->texels;
    out->shared_block_texels = g->shared_texels;
    out->all = (tl_pack_part){hist_stats(&g->all_l), hist_stats(&g->all_c)};
    out->seam = (tl_pack_part){hist_stats(&g->seam_l), hist_stats(&g->seam_c)};
    out->shared = (tl_pack_part){hist_stats(&g->shared_l), hist_stats(&g->shared_c)};
    free(g);
    if (rc) tl_pack_error_free(out);
    return rc;
}

void tl_pack_error_free(tl_pack_error *e)
{
    for (uint32_t i = 0; e->objects && i < e->object_count; i++) free(e->objects[i].name);
    free(e->objects);
    memset(e, 0, sizeof *e);
}

int tl_pack_error_meets(const tl_pack_stats *s, double mean_goal, double p99_goal)
{
    return s->mean <= mean_goal && s->p99 <= p99_goal;
}
