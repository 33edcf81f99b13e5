/* The linear mode of the DLS runtime (LBK_DLS_RUNTIME_LINEAR, lbk/dls.h): at open, every
 * clustered target's base and every entry decoded once into the additive forms (lbk_ahd_linear:
 * 3 planes × 4 floats per texel; lbk_sh9_rgb: 27 floats per probe), in cluster order; an apply is
 * then the kernels' lin_sum / lin_var over contiguous floats. The accumulation is the byte
 * kernels' (acc = base, += w·S for the non-zero weights in ascending set order, unfused), so each
 * output is the float the byte mode encodes. */
#include <stdint.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "dls_runtime.h"
#include "lbk/ahd.h"
#include "lbk/sh.h"

#define TEXEL_PLANES 3u
#define TEXEL_FLOATS 4u  /* per texel and plane */
#define PROBE_FLOATS 27u /* lbk_sh9_rgb */
#define LIN_ALIGN 16u    /* floats: each array starts on a 64-byte line */

static uint32_t planes_of(uint32_t space) { return space == LBK_DLS_SPACE_TEXEL ? TEXEL_PLANES : 1u; }
static uint32_t floats_of(uint32_t space) { return space == LBK_DLS_SPACE_TEXEL ? TEXEL_FLOATS : PROBE_FLOATS; }
static uint64_t pad(uint64_t n) { return (n + LIN_ALIGN - 1) / LIN_ALIGN * LIN_ALIGN; }
static bool fixed_form(uint32_t form) { return form == LBK_DLS_FORM_DEDICATED || form == LBK_DLS_FORM_PACKED; }

/* Floats of cluster c's prepared block; sets its strides. */
static uint64_t cluster_floats(rt_cluster *c)
{
    const uint64_t np = planes_of(c->space), f = floats_of(c->space);
    c->stride = pad((uint64_t)c->target_count * f);
    c->estride = fixed_form(c->form) ? 0 : pad((uint64_t)c->entry_count * f);
    return fixed_form(c->form) ? np * c->stride * (1 + (uint64_t)c->k) : np * (c->stride + c->estride);
}

/* ---- prepare -------------------------------------------------------------------------------- */

typedef struct prep {
    const lbk_dls_runtime *r;
    rt_cluster *c;
    uint32_t hint;
    uint64_t ord, entry;
    lbk_result res;
} prep;

/* Where target ordinal o's base (e = −1) or its entry e lands in plane p. */
static float *prep_at(const rt_cluster *c, uint32_t p, uint64_t o, uint64_t entry, int64_t e)
{
    const uint64_t np = planes_of(c->space), f = floats_of(c->space);
    if (e < 0) return c->lin + p * c->stride + o * f;
    if (fixed_form(c->form)) return c->lin + (np * (1 + (uint64_t)e) + p) * c->stride + o * f;
    return c->lin + np * c->stride + p * c->estride + (entry + (uint64_t)e) * f;
}

static int prep_target(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    prep *pp = user;
    const lbk_dls_runtime *r = pp->r;
    const rt_cluster *c = pp->c;
    (void)sets;
    if (c->space == LBK_DLS_SPACE_TEXEL) {
        uint32_t z[1 + LBK_DLS_MAX_OVERLAPS], rgba[1 + LBK_DLS_MAX_OVERLAPS];
        lbk_ahd_linear lin[1 + LBK_DLS_MAX_OVERLAPS];
        texel_seg s;
        rt_texel_span(r, target, 1, &pp->hint, &s);
        z[0] = lbk_rd32(s.b0);
        memcpy(&rgba[0], s.b1, 4);
        for (uint32_t e = 0; e < count; e++) {
            z[1 + e] = lbk_rd32(payloads + LBK_DLS_TEXEL_PAYLOAD * (size_t)e);
            memcpy(&rgba[1 + e], payloads + LBK_DLS_TEXEL_PAYLOAD * (size_t)e + 4, 4);
        }
        r->kern->texel_decode(z, rgba, 1 + count, lin);
        for (uint32_t p = 0; p < TEXEL_PLANES; p++)
            for (int64_t e = -1; e < (int64_t)count; e++)
                memcpy(prep_at(c, p, pp->ord, pp->entry, e), lin[1 + e].c[p], TEXEL_FLOATS * sizeof(float));
    } else {
        lbk_sh9_rgb sh[1 + LBK_DLS_MAX_OVERLAPS];
        r->kern->probe_decode(r->probe_base[c->space] + LBK_DLS_PROBE_PAYLOAD * (size_t)target, 1, &sh[0]);
        r->kern->probe_decode(payloads, count, &sh[1]);
        for (int64_t e = -1; e < (int64_t)count; e++) memcpy(prep_at(c, 0, pp->ord, pp->entry, e), &sh[1 + e], sizeof sh[0]);
    }
    pp->ord++;
    pp->entry += count;
    return 0;
}

/* Blocks of HUGE_MIN bytes or more start on a 2 MiB boundary and ask the kernel for huge pages
 * (Linux, where transparent huge pages are often "madvise" only): an apply streams 3·(1 + m)
 * arrays of a cluster at once while its outputs jump from chart row to chart row, and with 4 KiB
 * pages the inputs alone cross a page every 1024 floats. Measured on the ESTATE-sized level
 * (bench_dls, alternating builds, machine idle): one thread 0.37–0.40 of memcpy → 0.43–0.46, two
 * threads 0.45–0.53 → 0.48–0.56. Advice only: the bytes are the same with or without it, and an allocator whose
 * memory refuses it (or another OS) just keeps small pages. */
#define HUGE_PAGE ((size_t)2 << 20)
#define HUGE_MIN ((uint64_t)64 << 20)
static void advise_huge(void *p, size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    (void)madvise(p, bytes / HUGE_PAGE * HUGE_PAGE, MADV_HUGEPAGE);
#else
    (void)p, (void)bytes;
#endif
}

lbk_result rt_linear_prepare(lbk_dls_runtime *r)
{
    uint64_t total = 0;
    for (uint32_t i = 0; i < r->ncl; i++) {
        if (!r->space_on[r->cl[i].space]) continue;
        const uint64_t n = cluster_floats(&r->cl[i]);
        if (n > (UINT64_MAX - total) / 8) return LBK_ERR_LIMIT;
        total += n;
    }
    if (total > (SIZE_MAX - HUGE_PAGE) / sizeof(float)) return LBK_ERR_LIMIT;
    const bool huge = total * sizeof(float) >= HUGE_MIN;
    const size_t align = huge ? HUGE_PAGE : 64;
    r->lin_bytes = total * sizeof(float) + align;
    r->lin_block = lbk_alloc(r->alloc, (size_t)r->lin_bytes);
    if (!r->lin_block) return LBK_ERR_OUT_OF_MEMORY;
    float *at = (float *)(void *)((uint8_t *)r->lin_block + (align - (uintptr_t)r->lin_block % align) % align);
    if (huge) advise_huge(at, total * sizeof(float));
    for (uint32_t i = 0; i < r->ncl; i++) {
        rt_cluster *c = &r->cl[i];
        if (!r->space_on[c->space]) continue;
        c->lin = at;
        at += cluster_floats(c);
        prep pp = {.r = r, .c = c};
        lbk_result res = lbk_dls_cluster_decode(r->desc.dls, i, prep_target, &pp);
        if (res != LBK_OK) return res;
        if (pp.ord != c->target_count || pp.entry != c->entry_count) return LBK_ERR_CORRUPT; /* the view checked it */
    }
    return LBK_OK;
}

/* ---- apply ---------------------------------------------------------------------------------- */

#define GAP_BATCH 64

/* Targets in no cluster (full applies only): their decoded base, straight from the base bytes. */
static void gap_run(const lbk_dls_runtime *r, uint32_t space, uint64_t t, uint64_t count)
{
    uint32_t hint = 0;
    while (count > 0) {
        uint32_t n = count < GAP_BATCH ? (uint32_t)count : GAP_BATCH;
        if (space == LBK_DLS_SPACE_TEXEL) {
            texel_seg s;
            rt_texel_span(r, t, n, &hint, &s);
            n = s.len;
            uint32_t z[GAP_BATCH], rgba[GAP_BATCH];
            lbk_ahd_linear lin[GAP_BATCH];
            for (uint32_t i = 0; i < n; i++) z[i] = lbk_rd32(s.b0 + 4 * i), memcpy(&rgba[i], s.b1 + 4 * i, 4);
            r->kern->texel_decode(z, rgba, n, lin);
            for (uint32_t p = 0; p < TEXEL_PLANES; p++)
                for (uint32_t i = 0; i < n; i++) memcpy(s.l[p] + TEXEL_FLOATS * i, lin[i].c[p], TEXEL_FLOATS * sizeof(float));
        } else {
            lbk_sh9_rgb sh[GAP_BATCH];
            r->kern->probe_decode(r->probe_base[space] + LBK_DLS_PROBE_PAYLOAD * t, n, sh);
            memcpy(r->probe_lin[space] + PROBE_FLOATS * t, sh, (size_t)n * sizeof sh[0]);
        }
        t += n, count -= n;
    }
}

typedef struct lin_work {
    const lbk_dls_runtime *r;
    const rt_cluster *c;
    uint32_t hint, m;
    uint32_t idx[LBK_DLS_MAX_CLUSTER_SETS];
    float w[LBK_DLS_MAX_CLUSTER_SETS];
    uint64_t ord, entry;   /* cluster-order position and entry offset of the next target */
    const float *wl;       /* the cluster's set weights (prefix forms) */
    const dls_prefix_form *pf;
} lin_work;

/* Fixed forms (and copies): the m active slots idx[] with weights w[] for `len` targets. */
static void sum_targets(lin_work *lw, float *const *out, uint32_t len)
{
    const rt_cluster *c = lw->c;
    const uint32_t f = floats_of(c->space);
    const float *src[LBK_DLS_MAX_CLUSTER_SETS];
    for (uint32_t p = 0; p < planes_of(c->space); p++) {
        for (uint32_t j = 0; j < lw->m; j++) src[j] = prep_at(c, p, lw->ord, 0, lw->idx[j]);
        lw->r->kern->lin_sum(prep_at(c, p, lw->ord, 0, -1), src, lw->w, lw->m, (size_t)len * f, out[p]);
    }
    lw->ord += len;
}

/* Prefix forms: per target its entry count and the weights of its entries' sets. */
#define VAR_BATCH 16
static void var_targets(lin_work *lw, float *const *out, uint32_t len)
{
    const rt_cluster *c = lw->c;
    const uint32_t f = floats_of(c->space);
    uint32_t n[VAR_BATCH];
    float we[VAR_BATCH * LBK_DLS_MAX_OVERLAPS];
    for (uint32_t done = 0; done < len;) {
        const uint32_t cnt = len - done < VAR_BATCH ? len - done : VAR_BATCH;
        const uint64_t ord0 = lw->ord, entry0 = lw->entry;
        uint32_t k = 0;
        for (uint32_t i = 0; i < cnt; i++, lw->ord++) {
            n[i] = dls_prefix_field(c->words, lw->pf, lw->ord) + lw->pf->bias;
            for (uint32_t e = 0; e < n[i]; e++) we[k++] = lw->wl[c->slots[lw->entry + e]];
            lw->entry += n[i];
        }
        for (uint32_t p = 0; p < planes_of(c->space); p++)
            lw->r->kern->lin_var(prep_at(c, p, ord0, 0, -1), prep_at(c, p, 0, entry0, 0), we, n, cnt, f,
                                 out[p] + (size_t)done * f);
        done += cnt;
    }
}

static void lin_span(void *ctx, uint64_t t, uint32_t len)
{
    lin_work *lw = ctx;
    const lbk_dls_runtime *r = lw->r;
    const uint32_t space = lw->c->space;
    const bool var = lw->pf != NULL;
    if (space != LBK_DLS_SPACE_TEXEL) {
        float *out[1] = {r->probe_lin[space] + PROBE_FLOATS * t};
        if (var) var_targets(lw, out, len);
        else sum_targets(lw, out, len);
        return;
    }
    for (uint64_t left = len; left > 0;) {
        texel_seg s;
        rt_texel_span(r, t, left, &lw->hint, &s);
        if (var) var_targets(lw, s.l, s.len);
        else sum_targets(lw, s.l, s.len);
        t += s.len, left -= s.len;
    }
}

static uint32_t active_slots(const float *wl, const uint8_t *slot_of, uint32_t k, uint32_t *idx, float *w)
{
    uint32_t m = 0;
    for (uint32_t j = 0; j < k; j++) {
        const float x = wl[slot_of ? slot_of[j] : j];
        if (x != 0.0f) idx[m] = j, w[m++] = x;
    }
    return m;
}

void rt_linear_chunk_run(const lbk_dls_runtime *r, const rt_chunk *ch)
{
    if (ch->cluster == RT_GAP) {
        gap_run(r, ch->space, ch->ordinal, ch->count);
        return;
    }
    lin_work lw = {.r = r, .c = &r->cl[ch->cluster], .ord = ch->ordinal, .entry = ch->entry};
    const rt_cluster *c = lw.c;
    lw.wl = r->cw + c->set_first;
    if (r->action[ch->cluster] == RT_COPY) { /* m = 0: the base, whatever the form */
        rt_chunk_spans(r, ch, lin_span, &lw);
    } else if (c->form == LBK_DLS_FORM_DEDICATED) {
        lw.m = active_slots(lw.wl, NULL, c->k, lw.idx, lw.w);
        rt_chunk_spans(r, ch, lin_span, &lw);
    } else if (c->form == LBK_DLS_FORM_PACKED) {
        for (uint32_t g = ch->subgroup, done = 0; done < ch->count; g++) {
            const uint8_t *gr = c->subgroups + DLS_SUBGROUP_SIZE * (size_t)g;
            const uint8_t *runs = r->raw.d + r->raw.offset[DLS_A_RUNS] + (uint64_t)lbk_rd32(gr + DLS_G_RUN_FIRST) * DLS_RUN_SIZE;
            lw.m = active_slots(lw.wl, gr + DLS_G_SLOTS, c->k, lw.idx, lw.w);
            for (uint32_t i = 0; i < lbk_rd32(gr + DLS_G_RUN_COUNT); i++) {
                const uint32_t start = lbk_rd32(runs + DLS_RUN_SIZE * i), len = lbk_rd32(runs + DLS_RUN_SIZE * i + 4);
                lin_span(&lw, start, len);
                done += len;
            }
        }
    } else {
        lw.pf = dls_prefix(c->form);
        rt_chunk_spans(r, ch, lin_span, &lw);
    }
    if (r->kern->lin_end) r->kern->lin_end();
}
