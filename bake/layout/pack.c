/* MaxRects rectangle packing with quarter turns (see pack.h). */
#include "bake/layout/pack.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct mr_rect {
    int x, y, w, h;
} mr_rect;

typedef struct maxrects {
    mr_rect *f;          /* maximal free rectangles */
    size_t n, cap;
    mr_rect *fresh;      /* scratch: the pieces of one split */
    size_t fresh_cap;
} maxrects;

static int mr_reserve(mr_rect **v, size_t *cap, size_t need)
{
    if (need <= *cap) return 1;
    size_t nc = *cap ? *cap : 64;
    while (nc < need) nc *= 2;
    mr_rect *p = realloc(*v, nc * sizeof *p);
    if (!p) return 0;
    *v = p;
    *cap = nc;
    return 1;
}

static int mr_init(maxrects *m, int width, int height)
{
    memset(m, 0, sizeof *m);
    if (!mr_reserve(&m->f, &m->cap, 64)) return 0;
    m->f[0] = (mr_rect){0, 0, width, height};
    m->n = 1;
    return 1;
}

static void mr_free(maxrects *m)
{
    free(m->f);
    free(m->fresh);
}

/* The best free rectangle and orientation for a w × h rectangle (pack.h rule); 0: none. */
static int mr_find(const maxrects *m, int w, int h, int turnable, int *bx, int *by, int *bt)
{
    int found = 0;
    long long bs = 0, bl = 0;
    for (size_t i = 0; i < m->n; i++) {
        const mr_rect *f = &m->f[i];
        for (int t = 0; t <= turnable; t++) {
            int rw = t ? h : w, rh = t ? w : h;
            if (rw > f->w || rh > f->h) continue;
            long long dw = f->w - rw, dh = f->h - rh;
            long long s = dw < dh ? dw : dh, l = dw < dh ? dh : dw;
            int better = !found || s < bs || (s == bs && l < bl) ||
                         (s == bs && l == bl && (f->y < *by || (f->y == *by && (f->x < *bx || (f->x == *bx && t < *bt)))));
            if (!better) continue;
            found = 1;
            bs = s;
            bl = l;
            *bx = f->x;
            *by = f->y;
            *bt = t;
        }
    }
    return found;
}

static int contains(const mr_rect *a, const mr_rect *b)
{
    return b->x >= a->x && b->y >= a->y && b->x + b->w <= a->x + a->w && b->y + b->h <= a->y + a->h;
}

static int mr_push_fresh(maxrects *m, size_t *nf, int x, int y, int w, int h)
{
    if (w <= 0 || h <= 0) return 1;
    if (!mr_reserve(&m->fresh, &m->fresh_cap, *nf + 1)) return 0;
    m->fresh[(*nf)++] = (mr_rect){x, y, w, h};
    return 1;
}

/* Occupies r: every free rectangle it overlaps is replaced by its (up to 4) maximal
 * remainders, and remainders inside another free rectangle are dropped. The untouched free
 * rectangles were maximal before and stay so; only the new pieces need the check. */
static int mr_place(maxrects *m, const mr_rect *r)
{
    size_t kept = 0, nf = 0;
    for (size_t i = 0; i < m->n; i++) {
        mr_rect f = m->f[i];
        if (r->x >= f.x + f.w || r->x + r->w <= f.x || r->y >= f.y + f.h || r->y + r->h <= f.y) {
            m->f[kept++] = f;
            continue;
        }
        if (!mr_push_fresh(m, &nf, f.x, f.y, r->x - f.x, f.h) ||
            !mr_push_fresh(m, &nf, r->x + r->w, f.y, f.x + f.w - r->x - r->w, f.h) ||
            !mr_push_fresh(m, &nf, f.x, f.y, f.w, r->y - f.y) ||
            !mr_push_fresh(m, &nf, f.x, r->y + r->h, f.w, f.y + f.h - r->y - r->h))
            return 0;
    }
    m->n = kept;
    for (size_t i = 0; i < nf; i++) {
        const mr_rect *c = &m->fresh[i];
        int drop = 0;
        for (size_t k = 0; k < kept && !drop; k++) drop = contains(&m->f[k], c);
        /* among equal pieces the first one stays */
        for (size_t j = 0; j < nf && !drop; j++)
            if (j != i && contains(&m->fresh[j], c) && (!contains(c, &m->fresh[j]) || j < i)) drop = 1;
        if (drop) continue;
        if (!mr_reserve(&m->f, &m->cap, m->n + 1)) return 0;
        m->f[m->n++] = *c;
    }
    return 1;
}

static int cmp_pack(const void *a, const void *b)
{
    const bk_pack_rect *p = a, *q = b;
    int pl = p->w > p->h ? p->w : p->h, ql = q->w > q->h ? q->w : q->h;
    int ps = p->w > p->h ? p->h : p->w, qs = q->w > q->h ? q->h : q->w;
    if (pl != ql) return pl > ql ? -1 : 1;
    if (ps != qs) return ps > qs ? -1 : 1;
    if (p->h != q->h) return p->h > q->h ? -1 : 1;
    return (p->id > q->id) - (p->id < q->id);
}

void bk_pack_sort(bk_pack_rect *r, int n)
{
    if (n > 1) qsort(r, (size_t)n, sizeof *r, cmp_pack);
}

int bk_pack_into(bk_pack_rect *r, int n, int width, int height, int *used_w, int *used_h)
{
    maxrects m;
    *used_w = *used_h = 0;
    if (!mr_init(&m, width, height)) {
        mr_free(&m);
        return -1;
    }
    int placed = 0, uw = 0, uh = 0;
    for (int i = 0; i < n; i++) {
        if (r[i].placed) continue;
        int x = 0, y = 0, t = 0;
        if (!mr_find(&m, r[i].w, r[i].h, r[i].turnable != 0, &x, &y, &t)) continue;
        mr_rect pr = {x, y, t ? r[i].h : r[i].w, t ? r[i].w : r[i].h};
        if (!mr_place(&m, &pr)) {
            mr_free(&m);
            return -1;
        }
        r[i].x = x;
        r[i].y = y;
        r[i].turned = (uint8_t)t;
        r[i].placed = 1;
        placed++;
        if (x + pr.w > uw) uw = x + pr.w;
        if (y + pr.h > uh) uh = y + pr.h;
    }
    mr_free(&m);
    *used_w = uw;
    *used_h = uh;
    return placed;
}

static int align_up(int v, int a) { return (v + a - 1) / a * a; }

/* One trial: all n rectangles into w × h; 1 all placed (extent in *uw, *uh), 0 not, -1 OOM. */
static int trial(const bk_pack_rect *r, bk_pack_rect *t, int n, int w, int h, int *uw, int *uh)
{
    for (int i = 0; i < n; i++) {
        t[i] = r[i];
        t[i].placed = 0;
        t[i].turned = 0;
    }
    int placed = bk_pack_into(t, n, w, h, uw, uh);
    if (placed < 0) return -1;
    return placed == n;
}

typedef struct tight_best {
    int found, w, h;
    long long area;
    int side;
} tight_best;

/* Keeps trial t (extent uw × uh) in r when its aligned area beats the best so far. */
static void keep_if_better(bk_pack_rect *r, const bk_pack_rect *t, int n, int uw, int uh, int align, int score_align,
                           int max_h, tight_best *b)
{
    int aw = align_up(uw, align), ah = align_up(uh, align);
    if (ah > max_h) return;
    long long a = (long long)align_up(aw, score_align) * align_up(ah, score_align);
    int side = aw > ah ? aw : ah;
    if (b->found && !(a < b->area || (a == b->area && side < b->side))) return;
    b->found = 1;
    b->area = a;
    b->side = side;
    b->w = aw;
    b->h = ah;
    memcpy(r, t, (size_t)n * sizeof *r);
}

int bk_pack_tight(bk_pack_rect *r, int n, int max_w, int max_h, int align, int score_align, int *out_w, int *out_h)
{
    if (n == 0) {
        *out_w = *out_h = 0;
        return 1;
    }
    if (align < 1) align = 1;
    if (score_align < 1) score_align = 1;
    bk_pack_sort(r, n);
    double area = 0.0;
    int need_w = 0, need_h = 0; /* the narrowest and lowest any orientation allows */
    long long sum_w = 0;
    for (int i = 0; i < n; i++) {
        int mn = r[i].w < r[i].h ? r[i].w : r[i].h;
        int nw = r[i].turnable ? mn : r[i].w, nh = r[i].turnable ? mn : r[i].h;
        area += (double)r[i].w * r[i].h;
        if (nw > need_w) need_w = nw;
        if (nh > need_h) need_h = nh;
        sum_w += r[i].w > r[i].h && r[i].turnable ? r[i].h : r[i].w;
    }
    /* candidate widths: for a few rectangles an even sweep from the narrowest possible, else
     * multiples of sqrt(area); fewer trials for very many (each is O(n × free rectangles)) */
    static const double factors[] = {1.0, 1.05, 1.1, 1.2, 1.3, 1.45, 1.6, 1.8, 2.0, 2.5, 3.0, 4.0};
    enum { SWEEP = 48 };
    int cands[SWEEP + 16], nc = 0;
    int steps = n > 2048 ? 0 : n > 256 ? 4 : 16;
    if (n <= 64) {
        double top = fmin((double)max_w, fmax((double)sum_w, ceil(sqrt(area) * 4.0)));
        int lo_w = need_w, span = (int)top - lo_w;
        int step = span / SWEEP > align ? span / SWEEP : align;
        for (int w = lo_w; w <= (int)top && nc < SWEEP + 8; w += step) cands[nc++] = w;
    } else {
        int nfac = n > 2048 ? 3 : (int)(sizeof factors / sizeof factors[0]);
        for (int f = 0; f < nfac; f++) {
            double w = ceil(sqrt(area) * factors[f]);
            cands[nc++] = w > max_w ? max_w : (int)w;
        }
    }
    cands[nc++] = sum_w > max_w ? max_w : (int)sum_w;
    cands[nc++] = max_w;
    bk_pack_rect *t = malloc((size_t)n * sizeof *t);
    if (!t) return -1;
    tight_best best = {0};
    int prev = -1, oom = 0;
    for (int c = 0; c < nc; c++) {
        int w = align_up(cands[c] < need_w ? need_w : cands[c], align);
        if (w > max_w) w = max_w / align * align;
        if (w < need_w || w == prev) continue;
        prev = w;
        int uw, uh;
        int ok = trial(r, t, n, w, max_h, &uw, &uh);
        if (ok < 0) oom = 1;
        if (ok <= 0) {
            if (oom) break;
            continue;
        }
        keep_if_better(r, t, n, uw, uh, align, score_align, max_h, &best);
        /* the least height that still holds everything, by bisection (MaxRects is not
         * strictly monotone in the height; any height found to work is a valid packing) */
        int lo = (int)ceil(area / w) - 1, hi = uh;
        if (lo < need_h - 1) lo = need_h - 1;
        for (int s = 0; s < steps && hi - lo > 1; s++) {
            int mid = lo + (hi - lo) / 2;
            ok = trial(r, t, n, w, mid, &uw, &uh);
            if (ok < 0) {
                oom = 1;
                break;
            }
            if (ok) {
                hi = mid;
                keep_if_better(r, t, n, uw, uh, align, score_align, max_h, &best);
            } else {
                lo = mid;
            }
        }
        if (oom) break;
    }
    free(t);
    if (oom) return -1;
    if (!best.found) return 0;
    *out_w = best.w;
    *out_h = best.h;
    return 1;
}
