/* What the last apply wrote: merged ranges per space and rectangles per page, from the pieces
 * dls_plan.c computed for each chunk at open, so collecting them costs per job, not per target. */
#include <stdlib.h>

#include "dls_runtime.h"

static uint64_t gap_after(const lbk_dls_range *v, uint32_t i) { return v[i + 1].first - (v[i].first + v[i].count); }

uint32_t rt_ranges_merge(lbk_dls_range *v, uint32_t n, uint32_t cap)
{
    if (n == 0) return 0;
    /* overlapping or touching ranges are one (v is sorted by first) */
    uint32_t m = 0;
    for (uint32_t i = 1; i < n; i++) {
        const uint64_t end = v[m].first + v[m].count;
        if (v[i].first <= end) {
            const uint64_t e2 = v[i].first + v[i].count;
            if (e2 > end) v[m].count = e2 - v[m].first;
        } else {
            v[++m] = v[i];
        }
    }
    n = m + 1;
    if (n <= cap) return n;
    /* keep the cap − 1 widest gaps (the first on ties) and close the others */
    uint32_t cut[LBK_DLS_DIRTY_RANGES], ncut = 0;
    const uint32_t keep = cap - 1;
    for (uint32_t i = 0; i + 1 < n; i++) {
        const uint64_t g = gap_after(v, i);
        uint32_t at = ncut;
        while (at > 0 && gap_after(v, cut[at - 1]) < g) at--;
        if (at >= keep) continue;
        if (ncut < keep) ncut++;
        memmove(cut + at + 1, cut + at, (size_t)(ncut - 1 - at) * sizeof *cut);
        cut[at] = i;
    }
    for (uint32_t i = 1; i < ncut; i++)
        for (uint32_t j = i; j > 0 && cut[j - 1] > cut[j]; j--) {
            uint32_t t = cut[j];
            cut[j] = cut[j - 1], cut[j - 1] = t;
        }
    uint32_t out = 0;
    for (uint32_t q = 0, from = 0; q <= ncut; q++) {
        const uint32_t to = q < ncut ? cut[q] : n - 1;
        const lbk_dls_range r = {v[from].first, v[to].first + v[to].count - v[from].first};
        v[out++] = r;
        from = to + 1;
    }
    return out;
}

lbk_result rt_dirty_alloc(lbk_dls_runtime *r)
{
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        r->ranges[s] = lbk_alloc(r->alloc, sizeof(lbk_dls_range) * (r->npieces + LBK_DLS_DIRTY_RANGES));
        if (!r->ranges[s]) return LBK_ERR_OUT_OF_MEMORY;
    }
    const size_t pages = r->npages ? r->npages : 1;
    r->nrects = lbk_calloc(r->alloc, pages, sizeof *r->nrects);
    r->rects = lbk_calloc(r->alloc, pages * LBK_DLS_DIRTY_RECTS, sizeof *r->rects);
    return r->nrects && r->rects ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
}

static uint64_t area(const lbk_dls_rect *a) { return (uint64_t)a->width * a->height; }

static lbk_dls_rect rect_join(const lbk_dls_rect *a, const lbk_dls_rect *b)
{
    const uint32_t x0 = a->x < b->x ? a->x : b->x, y0 = a->y < b->y ? a->y : b->y;
    const uint32_t x1 = a->x + a->width > b->x + b->width ? a->x + a->width : b->x + b->width;
    const uint32_t y1 = a->y + a->height > b->y + b->height ? a->y + a->height : b->y + b->height;
    return (lbk_dls_rect){x0, y0, x1 - x0, y1 - y0};
}

static bool rect_touch(const lbk_dls_rect *a, const lbk_dls_rect *b)
{
    return a->x <= b->x + b->width && b->x <= a->x + a->width && a->y <= b->y + b->height && b->y <= a->y + a->height;
}

/* Adds rc to a page's list: it absorbs every rectangle it touches; on a full list it joins the
 * one whose bounding box grows least. */
static void rect_insert(lbk_dls_rect *list, uint32_t *n, lbk_dls_rect rc)
{
    for (;;) {
        bool joined = false;
        for (uint32_t i = 0; i < *n && !joined; i++)
            if (rect_touch(&list[i], &rc)) {
                rc = rect_join(&rc, &list[i]);
                list[i] = list[--*n];
                joined = true;
            }
        if (joined) continue;
        if (*n < LBK_DLS_DIRTY_RECTS) break;
        uint32_t best = 0;
        uint64_t best_growth = UINT64_MAX;
        for (uint32_t i = 0; i < *n; i++) {
            const lbk_dls_rect u = rect_join(&rc, &list[i]);
            const uint64_t growth = area(&u) - area(&list[i]);
            if (growth < best_growth) best_growth = growth, best = i;
        }
        rc = rect_join(&rc, &list[best]);
        list[best] = list[--*n];
    }
    list[(*n)++] = rc;
}

static int cmp_range(const void *a, const void *b)
{
    const lbk_dls_range *x = a, *y = b;
    return x->first < y->first ? -1 : x->first > y->first;
}

static int cmp_rect(const void *a, const void *b)
{
    const lbk_dls_rect *x = a, *y = b;
    if (x->y != y->y) return x->y < y->y ? -1 : 1;
    return x->x < y->x ? -1 : x->x > y->x;
}

void rt_dirty_collect(lbk_dls_runtime *r)
{
    const uint32_t pages = r->npages;
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) r->nranges[s] = 0;
    for (uint32_t p = 0; p < pages; p++) r->nrects[p] = 0;
    if (r->full) {
        for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++)
            if (r->space_on[s]) {
                r->ranges[s][0] = (lbk_dls_range){0, r->raw.target_count[s]};
                r->nranges[s] = 1;
            }
        for (uint32_t p = 0; p < pages; p++) {
            r->rects[(size_t)p * LBK_DLS_DIRTY_RECTS] = (lbk_dls_rect){0, 0, (uint32_t)r->planes[p].width, (uint32_t)r->planes[p].height};
            r->nrects[p] = 1;
        }
        return;
    }
    for (uint32_t j = 0; j < r->njobs; j++) {
        const rt_chunk *ch = &r->chunks[r->jobs[j]];
        for (uint32_t q = 0; q < ch->piece_count; q++) {
            const rt_piece *pc = &r->pieces[ch->piece_first + q];
            if (pc->page == RT_GAP) r->ranges[ch->space][r->nranges[ch->space]++] = (lbk_dls_range){pc->first, pc->count};
            else rect_insert(r->rects + (size_t)pc->page * LBK_DLS_DIRTY_RECTS, &r->nrects[pc->page], pc->rect);
        }
    }
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        qsort(r->ranges[s], r->nranges[s], sizeof(lbk_dls_range), cmp_range);
        r->nranges[s] = rt_ranges_merge(r->ranges[s], r->nranges[s], LBK_DLS_DIRTY_RANGES);
    }
    for (uint32_t p = 0; p < pages; p++)
        qsort(r->rects + (size_t)p * LBK_DLS_DIRTY_RECTS, r->nrects[p], sizeof(lbk_dls_rect), cmp_rect);
}
