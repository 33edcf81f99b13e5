/* How one apply is cut into jobs, and what a job does. A job (chunk) is a stretch of one
 * cluster's targets in cluster order — whole sub-groups for packed clusters, whole prefix batches
 * for the prefix forms, so that its first entry offset is known without a scan — or a stretch of
 * targets no cluster has (copied from the base on a full apply). Within a job, targets go to the
 * kernels (dls_kernel.h) in spans that are contiguous in every plane. */
#include <stdlib.h>

#include "dls_runtime.h"

/* ---- texel planes ------------------------------------------------------------------------ */

/* A page's linear planes: present, rows of at least 16·width bytes, float-aligned pitches. */
static bool linear_plane(rt_plane *pl, const lbk_dls_linear_page *lp, uint32_t width)
{
    const size_t row = 16 * (size_t)width;
    for (int c = 0; c < 3; c++) {
        pl->lo[c] = lp->out[c];
        pl->lp[c] = lp->out_pitch[c] ? lp->out_pitch[c] : row;
        if (!pl->lo[c] || pl->lp[c] < row || pl->lp[c] % 4) return false;
    }
    return true;
}

lbk_result rt_planes_make(lbk_dls_runtime *r)
{
    const lbk_dls_runtime_desc *d = &r->desc;
    const uint64_t texels = r->raw.target_count[LBK_DLS_SPACE_TEXEL];
    if (d->page_count) {
        if (!d->pages || d->base_irradiance_z || d->base_rgba || d->out_irradiance_z || d->out_rgba)
            return LBK_ERR_INVALID_ARGUMENT;
        if (r->linear && !d->linear_pages) return LBK_ERR_INVALID_ARGUMENT;
        r->planes = lbk_calloc(r->alloc, d->page_count, sizeof *r->planes);
        if (!r->planes) return LBK_ERR_OUT_OF_MEMORY;
        uint64_t first = 0;
        for (uint32_t p = 0; p < d->page_count; p++) {
            const lbk_dls_page *pg = &d->pages[p];
            rt_plane *pl = &r->planes[p];
            if (!pg->width || !pg->height || !pg->base_irradiance || !pg->base_rgba ||
                (!r->linear && (!pg->out_irradiance || !pg->out_rgba)))
                return LBK_ERR_INVALID_ARGUMENT;
            const size_t row = 4 * (size_t)pg->width;
            if (r->linear && !linear_plane(pl, &d->linear_pages[p], pg->width)) return LBK_ERR_INVALID_ARGUMENT;
            pl->first = first;
            pl->width = pg->width;
            pl->height = pg->height;
            pl->base0 = pg->base_irradiance, pl->base1 = pg->base_rgba;
            pl->out0 = pg->out_irradiance, pl->out1 = pg->out_rgba;
            pl->bp0 = pg->base_irradiance_pitch ? pg->base_irradiance_pitch : row;
            pl->bp1 = pg->base_rgba_pitch ? pg->base_rgba_pitch : row;
            pl->op0 = pg->out_irradiance_pitch ? pg->out_irradiance_pitch : row;
            pl->op1 = pg->out_rgba_pitch ? pg->out_rgba_pitch : row;
            if (pl->bp0 < row || pl->bp1 < row || (!r->linear && (pl->op0 < row || pl->op1 < row)))
                return LBK_ERR_INVALID_ARGUMENT;
            pl->packed = pl->bp0 == row && pl->bp1 == row &&
                         (r->linear ? pl->lp[0] == 4 * row && pl->lp[1] == 4 * row && pl->lp[2] == 4 * row
                                    : pl->op0 == row && pl->op1 == row);
            first += (uint64_t)pg->width * pg->height;
        }
        if (first != texels) return LBK_ERR_INVALID_ARGUMENT;
        r->nplanes = r->npages = d->page_count;
        return LBK_OK;
    }
    if (!d->base_irradiance_z || texels == 0) return LBK_OK; /* no texels to write */
    if (r->linear && (!d->out_linear_texel[0] || !d->out_linear_texel[1] || !d->out_linear_texel[2]))
        return LBK_ERR_INVALID_ARGUMENT;
    r->planes = lbk_calloc(r->alloc, 1, sizeof *r->planes);
    if (!r->planes) return LBK_ERR_OUT_OF_MEMORY;
    rt_plane *pl = &r->planes[0];
    pl->width = texels, pl->height = 1;
    pl->base0 = (const uint8_t *)d->base_irradiance_z, pl->base1 = d->base_rgba;
    pl->out0 = (uint8_t *)d->out_irradiance_z, pl->out1 = d->out_rgba;
    pl->bp0 = pl->bp1 = pl->op0 = pl->op1 = 4 * (size_t)texels;
    for (int c = 0; r->linear && c < 3; c++) pl->lo[c] = d->out_linear_texel[c], pl->lp[c] = 16 * (size_t)texels;
    pl->packed = true;
    r->nplanes = 1;
    return LBK_OK;
}

static uint32_t plane_of(const lbk_dls_runtime *r, uint64_t t, uint32_t hint)
{
    if (hint < r->nplanes && r->planes[hint].first <= t && t < r->planes[hint].first + r->planes[hint].width * r->planes[hint].height)
        return hint;
    uint32_t lo = 0, hi = r->nplanes; /* the last plane with first <= t */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (r->planes[mid].first <= t) lo = mid;
        else hi = mid;
    }
    return lo;
}

void rt_texel_span(const lbk_dls_runtime *r, uint64_t t, uint64_t len, uint32_t *hint, texel_seg *s)
{
    const uint32_t p = plane_of(r, t, *hint);
    const rt_plane *pl = &r->planes[p];
    const uint64_t local = t - pl->first;
    s->plane = *hint = p;
    s->y = local / pl->width;
    s->x = local % pl->width;
    const uint64_t room = pl->packed ? pl->width * pl->height - local : pl->width - s->x;
    s->len = (uint32_t)(len < room ? len : room);
    s->b0 = pl->base0 + s->y * pl->bp0 + 4 * s->x;
    s->b1 = pl->base1 + s->y * pl->bp1 + 4 * s->x;
    s->o0 = s->o1 = NULL;
    s->l[0] = s->l[1] = s->l[2] = NULL;
    if (r->linear) {
        for (int c = 0; c < 3; c++) s->l[c] = (float *)((uint8_t *)pl->lo[c] + s->y * pl->lp[c]) + 4 * s->x;
    } else {
        s->o0 = pl->out0 + s->y * pl->op0 + 4 * s->x;
        s->o1 = pl->out1 + s->y * pl->op1 + 4 * s->x;
    }
}

/* ---- spans of a chunk -------------------------------------------------------------------- */

static uint32_t run_start(const uint8_t *runs, uint32_t i) { return lbk_rd32(runs + DLS_RUN_SIZE * i); }
static uint32_t run_len(const uint8_t *runs, uint32_t i) { return lbk_rd32(runs + DLS_RUN_SIZE * i + 4); }

static const uint8_t *subgroup(const lbk_dls_runtime *r, const rt_cluster *c, uint32_t g)
{
    return c->subgroups + DLS_SUBGROUP_SIZE * (size_t)g;
}
static const uint8_t *subgroup_runs(const lbk_dls_runtime *r, const uint8_t *gr)
{
    return r->raw.d + r->raw.offset[DLS_A_RUNS] + (uint64_t)lbk_rd32(gr + DLS_G_RUN_FIRST) * DLS_RUN_SIZE;
}
static uint32_t subgroup_targets(const lbk_dls_runtime *r, const uint8_t *gr)
{
    const uint8_t *runs = subgroup_runs(r, gr);
    uint32_t n = 0;
    for (uint32_t i = 0; i < lbk_rd32(gr + DLS_G_RUN_COUNT); i++) n += run_len(runs, i);
    return n;
}


/* Runs are short (a chart row: tens of texels) and lie rows apart, beyond what a hardware
 * prefetcher follows, so the first lines of every run's bases and outputs would each be a miss:
 * ask for the next run's while this one computes. A hint only; nothing depends on it. */
#define PREFETCH_LINES 4
/* The linear mode's outputs are 4× wider and its inputs stream: there the whole next run's
 * output lines (up to a 96-texel chart row), which measured 0.32–0.37 of memcpy instead of
 * 0.28–0.29 on one thread (bench_dls, alternate runs) — with ordinary stores (the scalar path).
 * A path that streams its outputs (dls_kernels.lin_streams: whole lines written without a read)
 * gets no output prefetch: it would read the lines that path avoids reading. */
#define PREFETCH_LINEAR_TEXELS 96
static void prefetch_lines(const void *p, size_t bytes, int write)
{
    const char *c = p;
    const size_t n = bytes < PREFETCH_LINES * 64 || write == 2 ? bytes : PREFETCH_LINES * 64; /* 2: all of it */
#if defined(__GNUC__) || defined(__clang__)
    for (size_t o = 0; o < n; o += 64) {
        if (write) __builtin_prefetch(c + o, 1);
        else __builtin_prefetch(c + o, 0);
    }
#else
    (void)c, (void)n, (void)write;
#endif
}
static void prefetch_run(const lbk_dls_runtime *r, uint32_t space, uint64_t t, uint32_t len, uint32_t *hint)
{
    if (r->linear && r->kern->lin_streams) return; /* written without reads: lin_streams */
    if (space != LBK_DLS_SPACE_TEXEL && r->linear) { /* the prepared data streams; the outputs jump */
        if (r->probe_lin[space]) prefetch_lines(r->probe_lin[space] + 27 * t, 4 * 27 * (size_t)len, 1);
        return;
    }
    if (space != LBK_DLS_SPACE_TEXEL) {
        if (!r->probe_base[space] || !r->probe_out[space]) return;
        prefetch_lines(r->probe_base[space] + LBK_DLS_PROBE_PAYLOAD * t, (size_t)LBK_DLS_PROBE_PAYLOAD * len, 0);
        prefetch_lines(r->probe_out[space] + LBK_DLS_PROBE_PAYLOAD * t, (size_t)LBK_DLS_PROBE_PAYLOAD * len, 1);
        return;
    }
    if (!r->nplanes) return;
    texel_seg s;
    rt_texel_span(r, t, len, hint, &s);
    if (r->linear) {
        const size_t bytes = 16 * (size_t)(s.len < PREFETCH_LINEAR_TEXELS ? s.len : PREFETCH_LINEAR_TEXELS);
        for (int c = 0; c < 3; c++) prefetch_lines(s.l[c], bytes, 2);
        return;
    }
    prefetch_lines(s.b0, 4 * (size_t)s.len, 0), prefetch_lines(s.b1, 4 * (size_t)s.len, 0);
    prefetch_lines(s.o0, 4 * (size_t)s.len, 1), prefetch_lines(s.o1, 4 * (size_t)s.len, 1);
}

void rt_chunk_spans(const lbk_dls_runtime *r, const rt_chunk *ch, rt_span_fn fn, void *ctx)
{
    if (ch->cluster == RT_GAP) {
        fn(ctx, ch->ordinal, ch->count);
        return;
    }
    const rt_cluster *c = &r->cl[ch->cluster];
    uint32_t left = ch->count;
    if (c->form == LBK_DLS_FORM_PACKED) {
        for (uint32_t g = ch->subgroup; left > 0; g++) {
            const uint8_t *gr = subgroup(r, c, g), *runs = subgroup_runs(r, gr);
            for (uint32_t i = 0; i < lbk_rd32(gr + DLS_G_RUN_COUNT) && left > 0; i++) {
                fn(ctx, run_start(runs, i), run_len(runs, i));
                left -= run_len(runs, i);
            }
        }
        return;
    }
    uint32_t hint = 0;
    for (uint32_t i = ch->run, skip = ch->skip; left > 0; i++, skip = 0) {
        uint32_t len = run_len(c->runs, i) - skip;
        if (len > left) len = left;
        if (len < left) prefetch_run(r, c->space, run_start(c->runs, i + 1), run_len(c->runs, i + 1), &hint);
        fn(ctx, (uint64_t)run_start(c->runs, i) + skip, len);
        left -= len;
    }
}

/* ---- the chunk table --------------------------------------------------------------------- */

typedef struct chunk_list {
    lbk_dls_runtime *r;
    uint32_t n, cap;
    rt_chunk *v;
} chunk_list;

static bool chunk_push(chunk_list *l, const rt_chunk *c)
{
    if (l->n == l->cap) {
        uint32_t cap = l->cap ? 2 * l->cap : 64;
        rt_chunk *v = lbk_alloc(l->r->alloc, (size_t)cap * sizeof *v);
        if (!v) return false;
        if (l->n) memcpy(v, l->v, (size_t)l->n * sizeof *v);
        lbk_dealloc(l->r->alloc, l->v);
        l->v = v, l->cap = cap;
    }
    l->v[l->n++] = *c;
    return true;
}

static int cmp_u32_pair(const void *a, const void *b)
{
    uint32_t x = ((const uint32_t *)a)[0], y = ((const uint32_t *)b)[0];
    return x < y ? -1 : x > y;
}

/* The targets of space s in no cluster, in chunks of at most `per` targets. */
static lbk_result gap_chunks(lbk_dls_runtime *r, uint32_t s, uint32_t per, chunk_list *out)
{
    uint64_t n = 0;
    for (uint32_t i = 0; i < r->ncl; i++)
        if (r->cl[i].space == s) n += r->cl[i].run_count;
    uint32_t *runs = lbk_alloc(r->alloc, (n ? n : 1) * 8);
    if (!runs) return LBK_ERR_OUT_OF_MEMORY;
    uint64_t at = 0;
    for (uint32_t i = 0; i < r->ncl; i++) {
        if (r->cl[i].space != s) continue;
        for (uint32_t q = 0; q < r->cl[i].run_count; q++, at++) {
            runs[2 * at] = run_start(r->cl[i].runs, q);
            runs[2 * at + 1] = run_len(r->cl[i].runs, q);
        }
    }
    qsort(runs, n, 8, cmp_u32_pair);
    uint64_t next = 0, total = r->raw.target_count[s];
    lbk_result res = LBK_OK;
    for (uint64_t i = 0; i <= n && res == LBK_OK; i++) {
        const uint64_t start = i < n ? runs[2 * i] : total;
        for (uint64_t t = next; t < start; t += per) {
            const uint64_t len = start - t < per ? start - t : per;
            rt_chunk c = {.cluster = RT_GAP, .space = s, .count = (uint32_t)len, .ordinal = t};
            if (!chunk_push(out, &c)) { res = LBK_ERR_OUT_OF_MEMORY; break; }
        }
        if (i < n) next = (uint64_t)runs[2 * i] + runs[2 * i + 1];
    }
    lbk_dealloc(r->alloc, runs);
    return res;
}

static lbk_result cluster_chunks(lbk_dls_runtime *r, uint32_t ci, uint32_t per, chunk_list *out)
{
    const rt_cluster *c = &r->cl[ci];
    rt_chunk ch = {.cluster = ci, .space = c->space};
    if (c->form == LBK_DLS_FORM_PACKED) { /* whole sub-groups: their weights differ */
        for (uint32_t g = 0; g < c->subgroup_count;) {
            ch.subgroup = g;
            ch.count = 0;
            ch.entry = ch.ordinal * c->k;
            while (g < c->subgroup_count && (ch.count == 0 || ch.count + subgroup_targets(r, subgroup(r, c, g)) <= per))
                ch.count += subgroup_targets(r, subgroup(r, c, g++));
            if (!chunk_push(out, &ch)) return LBK_ERR_OUT_OF_MEMORY;
            ch.ordinal += ch.count;
        }
        return LBK_OK;
    }
    const dls_prefix_form *pf = dls_prefix(c->form);
    /* prefix chunks start at a batch so that their first entry is the batch's base */
    if (pf) per = per < pf->batch ? pf->batch : per / pf->batch * pf->batch;
    uint32_t run = 0, skip = 0;
    for (uint64_t ord = 0; ord < c->target_count;) {
        ch.run = run, ch.skip = skip, ch.ordinal = ord;
        ch.count = (uint32_t)(c->target_count - ord < per ? c->target_count - ord : per);
        if (!pf) ch.entry = ord * c->k;
        else ch.entry = pf->base_bytes == 2 ? lbk_rd16(c->bases + 2 * (ord / pf->batch)) : lbk_rd32(c->bases + 4 * (ord / pf->batch));
        if (!chunk_push(out, &ch)) return LBK_ERR_OUT_OF_MEMORY;
        for (uint32_t left = ch.count; left > 0;) { /* advance (run, skip) past this chunk */
            const uint32_t in_run = run_len(c->runs, run) - skip;
            if (in_run > left) { skip += left; left = 0; }
            else { left -= in_run; run++; skip = 0; }
        }
        ord += ch.count;
    }
    return LBK_OK;
}

/* ---- each chunk's pieces: up to 4 ranges, and one rectangle per page it touches ----------- */

#define PIECE_RANGES 4

typedef struct piece_ctx {
    lbk_dls_runtime *r;
    uint32_t space, hint;
    lbk_dls_range *spans;
    uint32_t nspans, cap;
    bool oom;
} piece_ctx;

static void collect_span(void *vctx, uint64_t start, uint32_t len)
{
    piece_ctx *p = vctx;
    if (p->oom) return;
    if (p->nspans == p->cap) {
        uint32_t cap = p->cap ? 2 * p->cap : 64;
        lbk_dls_range *v = lbk_alloc(p->r->alloc, (size_t)cap * sizeof *v);
        if (!v) { p->oom = true; return; }
        if (p->nspans) memcpy(v, p->spans, (size_t)p->nspans * sizeof *v);
        lbk_dealloc(p->r->alloc, p->spans);
        p->spans = v, p->cap = cap;
    }
    p->spans[p->nspans++] = (lbk_dls_range){start, len};
}

static int cmp_range_first(const void *a, const void *b)
{
    const lbk_dls_range *x = a, *y = b;
    return x->first < y->first ? -1 : x->first > y->first;
}

typedef struct piece_list {
    uint32_t n, cap;
    rt_piece *v;
} piece_list;

static bool piece_push(lbk_dls_runtime *r, piece_list *l, const rt_piece *p)
{
    if (l->n == l->cap) {
        uint32_t cap = l->cap ? 2 * l->cap : 256;
        rt_piece *v = lbk_alloc(r->alloc, (size_t)cap * sizeof *v);
        if (!v) return false;
        if (l->n) memcpy(v, l->v, (size_t)l->n * sizeof *v);
        lbk_dealloc(r->alloc, l->v);
        l->v = v, l->cap = cap;
    }
    l->v[l->n++] = *p;
    return true;
}

static void rect_union(lbk_dls_rect *a, const lbk_dls_rect *b)
{
    if (a->width == 0) { *a = *b; return; }
    uint32_t x0 = a->x < b->x ? a->x : b->x, y0 = a->y < b->y ? a->y : b->y;
    uint32_t x1 = a->x + a->width > b->x + b->width ? a->x + a->width : b->x + b->width;
    uint32_t y1 = a->y + a->height > b->y + b->height ? a->y + a->height : b->y + b->height;
    *a = (lbk_dls_rect){x0, y0, x1 - x0, y1 - y0};
}

/* The ranges of the spans merged over their narrowest gaps down to PIECE_RANGES, and per page the
 * bounding rectangle. */
static bool chunk_pieces(lbk_dls_runtime *r, rt_chunk *ch, piece_ctx *pc, piece_list *out)
{
    pc->nspans = 0;
    pc->space = ch->space;
    rt_chunk_spans(r, ch, collect_span, pc);
    if (pc->oom) return false;
    ch->piece_first = out->n;
    qsort(pc->spans, pc->nspans, sizeof *pc->spans, cmp_range_first); /* packed sub-groups interleave */
    const uint32_t n = rt_ranges_merge(pc->spans, pc->nspans, PIECE_RANGES);
    for (uint32_t i = 0; i < n; i++) {
        rt_piece p = {.first = pc->spans[i].first, .count = pc->spans[i].count, .page = RT_GAP};
        if (!piece_push(r, out, &p)) return false;
    }
    if (ch->space == LBK_DLS_SPACE_TEXEL && r->npages) { /* rectangles, from the unmerged spans */
        pc->nspans = 0;
        rt_chunk_spans(r, ch, collect_span, pc);
        if (pc->oom) return false;
        rt_piece cur = {.page = RT_GAP};
        for (uint32_t i = 0; i < pc->nspans; i++) {
            for (uint64_t t = pc->spans[i].first, left = pc->spans[i].count; left > 0;) {
                const uint32_t p = plane_of(r, t, pc->hint);
                const rt_plane *pl = &r->planes[p];
                pc->hint = p;
                const uint64_t local = t - pl->first, room = pl->width * pl->height - local;
                const uint64_t len = left < room ? left : room;
                const uint64_t y0 = local / pl->width, y1 = (local + len - 1) / pl->width;
                lbk_dls_rect rc = y0 == y1 ? (lbk_dls_rect){(uint32_t)(local % pl->width), (uint32_t)y0, (uint32_t)len, 1}
                                           : (lbk_dls_rect){0, (uint32_t)y0, (uint32_t)pl->width, (uint32_t)(y1 - y0 + 1)};
                if (cur.page != p) {
                    if (cur.page != RT_GAP && !piece_push(r, out, &cur)) return false;
                    cur = (rt_piece){.page = p};
                }
                rect_union(&cur.rect, &rc);
                t += len, left -= len;
            }
        }
        if (cur.page != RT_GAP && !piece_push(r, out, &cur)) return false;
    }
    ch->piece_count = out->n - ch->piece_first;
    return true;
}

lbk_result rt_chunks_make(lbk_dls_runtime *r)
{
    const uint32_t per = r->desc.job_targets ? r->desc.job_targets : 4096;
    chunk_list l = {.r = r};
    lbk_result res = LBK_OK;
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_ && res == LBK_OK; s++)
        if (r->space_on[s]) res = gap_chunks(r, s, per > UINT32_MAX / 16 ? UINT32_MAX : 16 * per, &l);
    for (uint32_t i = 0; i < r->ncl && res == LBK_OK; i++)
        if (r->space_on[r->cl[i].space]) res = cluster_chunks(r, i, per, &l);
    piece_ctx pc = {.r = r};
    piece_list pl = {0};
    for (uint32_t i = 0; i < l.n && res == LBK_OK; i++)
        if (!chunk_pieces(r, &l.v[i], &pc, &pl)) res = LBK_ERR_OUT_OF_MEMORY;
    lbk_dealloc(r->alloc, pc.spans);
    r->chunks = l.v, r->nchunks = l.n;
    r->pieces = pl.v, r->npieces = pl.n;
    return res;
}

/* ---- the work of one chunk --------------------------------------------------------------- */

/* A batch template: weights and entry layout; run_spans fills in the addresses span by span. */
typedef struct work {
    const lbk_dls_runtime *r;
    const rt_cluster *c;
    uint32_t space, hint;
    bool copy;
    dls_batch b;
    uint64_t entry; /* entry offset (within the cluster) of the next target */
} work;

static void copy_span(void *vw, uint64_t t, uint32_t len)
{
    work *w = vw;
    const lbk_dls_runtime *r = w->r;
    if (w->space != LBK_DLS_SPACE_TEXEL) {
        memcpy(r->probe_out[w->space] + LBK_DLS_PROBE_PAYLOAD * t, r->probe_base[w->space] + LBK_DLS_PROBE_PAYLOAD * t,
               (size_t)len * LBK_DLS_PROBE_PAYLOAD);
        return;
    }
    for (uint64_t left = len; left > 0;) {
        texel_seg s;
        rt_texel_span(r, t, left, &w->hint, &s);
        memcpy(s.o0, s.b0, 4 * (size_t)s.len);
        memcpy(s.o1, s.b1, 4 * (size_t)s.len);
        t += s.len, left -= s.len;
    }
}

/* Fixed forms: every target of the span has `stride` entries. */
static void fixed_span(void *vw, uint64_t t, uint32_t len)
{
    work *w = vw;
    if (w->copy) { copy_span(vw, t, len); return; }
    const lbk_dls_runtime *r = w->r;
    const uint32_t psize = dls_payload_size(w->space);
    dls_batch b = w->b;
    if (w->space != LBK_DLS_SPACE_TEXEL) {
        b.count = len;
        b.entries = w->c->payload + w->entry * psize;
        b.base0 = r->probe_base[w->space] + LBK_DLS_PROBE_PAYLOAD * t;
        b.out0 = r->probe_out[w->space] + LBK_DLS_PROBE_PAYLOAD * t;
        r->kern->probes(&b);
        w->entry += (uint64_t)len * b.stride;
        return;
    }
    for (uint64_t left = len; left > 0;) {
        texel_seg s;
        rt_texel_span(r, t, left, &w->hint, &s);
        b.count = s.len;
        b.entries = w->c->payload + w->entry * psize;
        b.base0 = s.b0, b.base1 = s.b1, b.out0 = s.o0, b.out1 = s.o1;
        r->kern->texels(&b);
        w->entry += (uint64_t)s.len * b.stride;
        t += s.len, left -= s.len;
    }
}

/* The active entries of a fixed target: position within the target's entries, weight. */
static uint32_t active_entries(const float *wl, const uint8_t *slot_of, uint32_t k, uint32_t *idx, float *w)
{
    uint32_t m = 0;
    for (uint32_t j = 0; j < k; j++) {
        const float x = wl[slot_of ? slot_of[j] : j];
        if (x != 0.0f) idx[m] = j, w[m++] = x;
    }
    return m;
}

#define VAR_BATCH 16 /* prefix targets per kernel call: the entry weights fit the stack */

typedef struct var_work {
    work w;
    const dls_prefix_form *pf;
    const float *wl;
    uint64_t ordinal;
} var_work;

static void var_span(void *vv, uint64_t t, uint32_t len)
{
    var_work *v = vv;
    const lbk_dls_runtime *r = v->w.r;
    const rt_cluster *c = v->w.c;
    const uint32_t psize = dls_payload_size(c->space);
    uint32_t n[VAR_BATCH], off[VAR_BATCH];
    float we[VAR_BATCH * LBK_DLS_MAX_OVERLAPS];
    for (uint32_t done = 0; done < len;) {
        uint32_t cnt = len - done < VAR_BATCH ? len - done : VAR_BATCH, hint = v->w.hint;
        texel_seg s = {0};
        if (c->space == LBK_DLS_SPACE_TEXEL) {
            rt_texel_span(r, t + done, cnt, &hint, &s);
            cnt = s.len;
            v->w.hint = hint;
        }
        const uint64_t first = v->w.entry;
        for (uint32_t i = 0; i < cnt; i++, v->ordinal++) {
            n[i] = dls_prefix_field(c->words, v->pf, v->ordinal) + v->pf->bias;
            off[i] = (uint32_t)(v->w.entry - first);
            for (uint32_t e = 0; e < n[i]; e++) we[off[i] + e] = v->wl[c->slots[v->w.entry + e]];
            v->w.entry += n[i];
        }
        dls_var_batch b = {.count = cnt, .n = n, .off = off, .we = we, .entries = c->payload + first * psize};
        if (c->space == LBK_DLS_SPACE_TEXEL) {
            b.base0 = s.b0, b.base1 = s.b1, b.out0 = s.o0, b.out1 = s.o1;
            r->kern->texels_var(&b);
        } else {
            b.base0 = r->probe_base[c->space] + LBK_DLS_PROBE_PAYLOAD * (t + done);
            b.out0 = r->probe_out[c->space] + LBK_DLS_PROBE_PAYLOAD * (t + done);
            r->kern->probes_var(&b);
        }
        done += cnt;
    }
}

void rt_chunk_run(const lbk_dls_runtime *r, const rt_chunk *ch)
{
    if (r->linear) {
        rt_linear_chunk_run(r, ch);
        return;
    }
    work w = {.r = r, .space = ch->space, .entry = ch->entry};
    if (ch->cluster == RT_GAP) {
        copy_span(&w, ch->ordinal, ch->count);
        return;
    }
    const rt_cluster *c = w.c = &r->cl[ch->cluster];
    const float *wl = r->cw + c->set_first;
    uint32_t idx[LBK_DLS_MAX_CLUSTER_SETS];
    float wa[LBK_DLS_MAX_CLUSTER_SETS];
    w.b = (dls_batch){.stride = c->k, .idx = idx, .w = wa};
    if (r->action[ch->cluster] == RT_COPY) {
        w.copy = true;
        rt_chunk_spans(r, ch, copy_span, &w);
    } else if (c->form == LBK_DLS_FORM_DEDICATED) {
        w.b.m = active_entries(wl, NULL, c->k, idx, wa);
        w.copy = w.b.m == 0;
        rt_chunk_spans(r, ch, fixed_span, &w);
    } else if (c->form == LBK_DLS_FORM_PACKED) {
        for (uint32_t g = ch->subgroup, done = 0; done < ch->count; g++) {
            const uint8_t *gr = subgroup(r, c, g), *runs = subgroup_runs(r, gr);
            w.b.m = active_entries(wl, gr + DLS_G_SLOTS, c->k, idx, wa);
            w.copy = w.b.m == 0;
            for (uint32_t i = 0; i < lbk_rd32(gr + DLS_G_RUN_COUNT); i++) {
                fixed_span(&w, run_start(runs, i), run_len(runs, i));
                if (w.copy) w.entry += (uint64_t)run_len(runs, i) * c->k;
                done += run_len(runs, i);
            }
        }
    } else {
        var_work v = {.w = w, .pf = dls_prefix(c->form), .wl = wl, .ordinal = ch->ordinal};
        rt_chunk_spans(r, ch, var_span, &v);
    }
}
