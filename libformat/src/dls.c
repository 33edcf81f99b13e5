/* DLS section: the structural checker (shared by the validator and the view), the view, the
 * cluster decoder and the statistics. Layout and rules: spec/container.md §12, IDs 800–899 of
 * spec/validation.md. */
#include <stdio.h>
#include <stdlib.h>

#include "dls_format.h"
#include "text.h"

/* ---- strings ---------------------------------------------------------------------------- */

bool lbk_dls_string_ok(const uint8_t *blob, uint64_t blob_size, uint32_t off, uint32_t len)
{
    return len > 0 && lbk_range_ok(off, len, blob_size) && lbk_utf8_valid(blob + off, len);
}

/* ---- the checker ------------------------------------------------------------------------ */

#define DLS_REPORTS_PER_ID 16u

typedef struct dls_chk {
    lbk_vctx *ctx; /* NULL: count only (view mode) */
    const lbk_allocator *alloc;
    const uint8_t *d;
    uint64_t size;
    dls_layout L;
    uint64_t target_count[LBK_DLS_SPACE_COUNT_];
    uint32_t errors;
    bool oom;
    uint16_t reported[100];
} dls_chk;

static void rep(dls_chk *c, uint32_t id, uint64_t off, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void rep(dls_chk *c, uint32_t id, uint64_t off, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    lbk_vreport_capped(c->ctx, &c->errors, c->reported, 800, DLS_REPORTS_PER_ID, id, off, fmt, ap);
    va_end(ap);
}

static bool stopped(const dls_chk *c) { return c->ctx && c->ctx->stop; }

static const uint8_t *arr(const dls_chk *c, int a, uint64_t index, uint64_t elem)
{
    return c->d + c->L.offset[a] + index * elem;
}
static uint64_t arr_off(const dls_chk *c, int a, uint64_t index, uint64_t elem) { return c->L.offset[a] + index * elem; }

static const char *space_name(uint32_t s)
{
    static const char *names[] = {"texel", "GLG probe", "LLG probe"};
    return s < LBK_DLS_SPACE_COUNT_ ? names[s] : "?";
}

/* Header, size, padding and target spaces. False when nothing further can be read. */
static bool check_frame(dls_chk *c)
{
    if (c->size < DLS_HEADER_SIZE) {
        rep(c, 800, 0, "DLS is %llu bytes, shorter than its 96-byte header", (unsigned long long)c->size);
        return false;
    }
    dls_layout_from_header(c->d, &c->L);
    if (!dls_layout_compute(&c->L) || c->L.size != c->size) {
        rep(c, 801, 0, "DLS is %llu bytes but its header counts imply %llu", (unsigned long long)c->size,
            (unsigned long long)c->L.size);
        return false;
    }
    static const uint32_t elem[DLS_A_COUNT] = {DLS_SET_SIZE, DLS_LIGHT_REF_SIZE, 4, DLS_CLUSTER_SIZE, 4,
                                               DLS_RUN_SIZE, DLS_SUBGROUP_SIZE, 4, 2, 4, 1,
                                               LBK_DLS_TEXEL_PAYLOAD, LBK_DLS_PROBE_PAYLOAD, 1};
    for (int a = 0; a < DLS_A_COUNT; a++) {
        uint64_t end = c->L.offset[a] + c->L.count[a] * elem[a];
        uint64_t next = a + 1 < DLS_A_COUNT ? c->L.offset[a + 1] : c->L.size;
        for (uint64_t p = end; p < next; p++)
            if (c->d[p]) {
                rep(c, 802, p, "padding byte at %llu is 0x%02x", (unsigned long long)p, c->d[p]);
                break;
            }
    }
    bool ok = true;
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        c->target_count[s] = lbk_rd64(c->d + DLS_H_TARGET_COUNT + 8 * s);
        if (c->target_count[s] > (uint64_t)UINT32_MAX + 1) {
            rep(c, 804, DLS_H_TARGET_COUNT + 8 * s, "%s space size %llu exceeds 2^32", space_name(s),
                (unsigned long long)c->target_count[s]);
            ok = false;
        }
    }
    return ok;
}

static void check_cross_section(dls_chk *c)
{
    lbk_vctx *x = c->ctx;
    if (!x) return;
    const struct {
        int ok;
        uint64_t count;
        const char *name;
    } facts[3] = {{x->lmap_ok, x->lmap_texel_count, "LMAP"},
                  {x->glg_ok, x->glg_probe_count, "GLG"},
                  {x->llg_ok, x->llg_probe_count, "LLG"}};
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        if (facts[s].ok ? c->target_count[s] != facts[s].count : c->target_count[s] != 0)
            rep(c, 803, DLS_H_TARGET_COUNT + 8 * s, "DLS %s space has %llu targets but %s %s %llu",
                space_name(s), (unsigned long long)c->target_count[s], facts[s].name,
                facts[s].ok ? "has" : "is missing or unusable, so", (unsigned long long)(facts[s].ok ? facts[s].count : 0));
    }
}

typedef struct name_key {
    const uint8_t *p;
    uint32_t len;
    uint32_t set;
} name_key;

static int cmp_name(const void *a, const void *b)
{
    const name_key *x = a, *y = b;
    uint32_t n = x->len < y->len ? x->len : y->len;
    int r = memcmp(x->p, y->p, n);
    if (r) return r;
    if (x->len != y->len) return x->len < y->len ? -1 : 1;
    return x->set < y->set ? -1 : x->set > y->set;
}

static void check_sets(dls_chk *c)
{
    const uint64_t nsets = c->L.count[DLS_A_SETS];
    const uint8_t *blob = c->d + c->L.offset[DLS_A_STRINGS];
    const uint64_t blob_size = c->L.count[DLS_A_STRINGS];
    uint64_t light_sum = 0, member_sum = 0;
    bool ranges_ok = true;
    for (uint64_t s = 0; s < nsets && !stopped(c); s++) {
        const uint8_t *r = arr(c, DLS_A_SETS, s, DLS_SET_SIZE);
        uint64_t ro = arr_off(c, DLS_A_SETS, s, DLS_SET_SIZE);
        uint32_t noff = lbk_rd32(r + DLS_S_NAME_OFF), nlen = lbk_rd32(r + DLS_S_NAME_LEN);
        if (!lbk_dls_string_ok(blob, blob_size, noff, nlen))
            rep(c, 810, ro, "set %llu name (offset %u, length %u) is empty, outside the %llu-byte blob or not UTF-8",
                (unsigned long long)s, noff, nlen, (unsigned long long)blob_size);
        uint32_t kind = lbk_rd32(r + DLS_S_KIND);
        if (kind >= LBK_DLS_KIND_COUNT_) rep(c, 812, ro + DLS_S_KIND, "set %llu kind %u is unknown", (unsigned long long)s, kind);
        if (lbk_rd32(r + DLS_S_RESERVED)) rep(c, 816, ro + DLS_S_RESERVED, "set %llu reserved field is not zero", (unsigned long long)s);
        uint32_t lf = lbk_rd32(r + DLS_S_LIGHT_FIRST), lc = lbk_rd32(r + DLS_S_LIGHT_COUNT);
        uint32_t mf = lbk_rd32(r + DLS_S_MEMBER_FIRST), mc = lbk_rd32(r + DLS_S_MEMBER_COUNT);
        if (lf != light_sum || mf != member_sum || light_sum + lc > c->L.count[DLS_A_LIGHT_REFS] ||
            member_sum + mc > c->L.count[DLS_A_MEMBERS]) {
            rep(c, 813, ro + DLS_S_LIGHT_FIRST,
                "set %llu lights [%u, +%u) / members [%u, +%u) differ from the packed layout (%llu, %llu)",
                (unsigned long long)s, lf, lc, mf, mc, (unsigned long long)light_sum, (unsigned long long)member_sum);
            ranges_ok = false;
            break;
        }
        for (uint32_t i = 0; i < lc; i++) {
            const uint8_t *lr = arr(c, DLS_A_LIGHT_REFS, lf + i, DLS_LIGHT_REF_SIZE);
            if (!lbk_dls_string_ok(blob, blob_size, lbk_rd32(lr), lbk_rd32(lr + 4)))
                rep(c, 814, arr_off(c, DLS_A_LIGHT_REFS, lf + i, DLS_LIGHT_REF_SIZE),
                    "set %llu light %u name (offset %u, length %u) is empty, outside the blob or not UTF-8",
                    (unsigned long long)s, i, lbk_rd32(lr), lbk_rd32(lr + 4));
        }
        light_sum += lc;
        member_sum += mc;
    }
    if (ranges_ok && !stopped(c) &&
        (light_sum != c->L.count[DLS_A_LIGHT_REFS] || member_sum != c->L.count[DLS_A_MEMBERS]))
        rep(c, 805, DLS_H_LIGHT_REF_COUNT, "header has %llu light names and %llu members, the sets use %llu and %llu",
            (unsigned long long)c->L.count[DLS_A_LIGHT_REFS], (unsigned long long)c->L.count[DLS_A_MEMBERS],
            (unsigned long long)light_sum, (unsigned long long)member_sum);
    if (!ranges_ok || stopped(c)) return;

    /* Members: only combinations have them, ≥ 2, ascending, elementary sets other than itself. */
    for (uint64_t s = 0; s < nsets && !stopped(c); s++) {
        const uint8_t *r = arr(c, DLS_A_SETS, s, DLS_SET_SIZE);
        uint32_t kind = lbk_rd32(r + DLS_S_KIND);
        uint32_t mf = lbk_rd32(r + DLS_S_MEMBER_FIRST), mc = lbk_rd32(r + DLS_S_MEMBER_COUNT);
        uint64_t ro = arr_off(c, DLS_A_SETS, s, DLS_SET_SIZE);
        if (kind != LBK_DLS_KIND_COMBINATION) {
            if (mc) rep(c, 815, ro + DLS_S_MEMBER_COUNT, "set %llu of kind %u has %u members; only combinations have members",
                        (unsigned long long)s, kind, mc);
            continue;
        }
        if (mc < 2) {
            rep(c, 815, ro + DLS_S_MEMBER_COUNT, "combination set %llu has %u members, needs at least 2", (unsigned long long)s, mc);
            continue;
        }
        uint32_t prev = 0;
        for (uint32_t i = 0; i < mc; i++) {
            uint32_t m = lbk_rd32(arr(c, DLS_A_MEMBERS, mf + i, 4));
            uint64_t mo = arr_off(c, DLS_A_MEMBERS, mf + i, 4);
            if (m >= nsets || m == s || (i && m <= prev)) {
                rep(c, 815, mo, "combination set %llu member %u is %u: out of range, itself or not ascending",
                    (unsigned long long)s, i, m);
                break;
            }
            uint32_t mk = lbk_rd32(arr(c, DLS_A_SETS, m, DLS_SET_SIZE) + DLS_S_KIND);
            if (mk == LBK_DLS_KIND_COMBINATION) {
                rep(c, 815, mo, "combination set %llu has member %u, itself a combination", (unsigned long long)s, m);
                break;
            }
            prev = m;
        }
    }

    /* Unique names: sort (name, index) and compare neighbours. */
    name_key *keys = lbk_calloc(c->alloc, nsets ? nsets : 1, sizeof *keys);
    if (!keys) {
        c->oom = true;
        return;
    }
    uint64_t nk = 0;
    for (uint64_t s = 0; s < nsets; s++) {
        const uint8_t *r = arr(c, DLS_A_SETS, s, DLS_SET_SIZE);
        uint32_t noff = lbk_rd32(r + DLS_S_NAME_OFF), nlen = lbk_rd32(r + DLS_S_NAME_LEN);
        if (!lbk_range_ok(noff, nlen, blob_size)) continue;
        keys[nk++] = (name_key){blob + noff, nlen, (uint32_t)s};
    }
    qsort(keys, nk, sizeof *keys, cmp_name);
    for (uint64_t i = 1; i < nk; i++)
        if (keys[i].len == keys[i - 1].len && memcmp(keys[i].p, keys[i - 1].p, keys[i].len) == 0)
            rep(c, 811, arr_off(c, DLS_A_SETS, keys[i].set, DLS_SET_SIZE), "sets %u and %u are both named '%.*s'",
                keys[i - 1].set, keys[i].set, (int)(keys[i].len > 60 ? 60 : keys[i].len), (const char *)keys[i].p);
    lbk_dealloc(c->alloc, keys);
}

typedef struct run_key {
    uint32_t space, start, length, cluster;
} run_key;

static int cmp_run(const void *a, const void *b)
{
    const run_key *x = a, *y = b;
    if (x->space != y->space) return x->space < y->space ? -1 : 1;
    if (x->start != y->start) return x->start < y->start ? -1 : 1;
    return x->cluster < y->cluster ? -1 : x->cluster > y->cluster;
}

/* Runs [first, first+count) of one list (a cluster or a packed sub-group): non-empty, inside the
 * space, strictly ascending and not touching. Returns the target sum, or UINT64_MAX if broken. */
static uint64_t check_runs(dls_chk *c, uint64_t ci, uint32_t space, uint64_t first, uint64_t count)
{
    uint64_t sum = 0, prev_end = 0;
    for (uint64_t i = 0; i < count; i++) {
        const uint8_t *r = arr(c, DLS_A_RUNS, first + i, DLS_RUN_SIZE);
        uint64_t start = lbk_rd32(r), len = lbk_rd32(r + 4);
        if (len == 0 || start + len > c->target_count[space] || (i && start <= prev_end)) {
            rep(c, 826, arr_off(c, DLS_A_RUNS, first + i, DLS_RUN_SIZE),
                "cluster %llu run %llu [%llu, +%llu) is empty, past the %llu %s targets or not after the previous run",
                (unsigned long long)ci, (unsigned long long)(first + i), (unsigned long long)start,
                (unsigned long long)len, (unsigned long long)c->target_count[space], space_name(space));
            return UINT64_MAX;
        }
        prev_end = start + len;
        sum += len;
    }
    return sum;
}

/* Running totals over the clusters: every *_first must equal them (packed layout). */
typedef struct dls_totals {
    uint64_t sets, runs, subgroups, words, base16, base32, slots, entries[2];
} dls_totals;

static void check_subgroups(dls_chk *c, uint64_t ci, const uint8_t *cr, uint32_t k, uint32_t nsets_c, bool *used)
{
    uint32_t run_first = lbk_rd32(cr + DLS_C_RUN_FIRST), run_count = lbk_rd32(cr + DLS_C_RUN_COUNT);
    uint32_t g_first = lbk_rd32(cr + DLS_C_AUX_FIRST), g_count = lbk_rd32(cr + DLS_C_AUX_COUNT);
    uint32_t targets = lbk_rd32(cr + DLS_C_TARGET_COUNT);
    if (g_count == 0) {
        rep(c, 830, arr_off(c, DLS_A_CLUSTERS, ci, DLS_CLUSTER_SIZE) + DLS_C_AUX_COUNT, "packed cluster %llu has no sub-groups",
            (unsigned long long)ci);
        return;
    }
    uint64_t runs_at = run_first, tsum = 0;
    for (uint32_t g = 0; g < g_count && !stopped(c); g++) {
        const uint8_t *gr = arr(c, DLS_A_SUBGROUPS, (uint64_t)g_first + g, DLS_SUBGROUP_SIZE);
        uint64_t go = arr_off(c, DLS_A_SUBGROUPS, (uint64_t)g_first + g, DLS_SUBGROUP_SIZE);
        uint32_t grf = lbk_rd32(gr + DLS_G_RUN_FIRST), grc = lbk_rd32(gr + DLS_G_RUN_COUNT);
        uint32_t gtf = lbk_rd32(gr + DLS_G_TARGET_FIRST);
        if (grf != runs_at || grc == 0 || runs_at + grc > (uint64_t)run_first + run_count || gtf != tsum) {
            rep(c, 830, go, "packed cluster %llu sub-group %u: runs [%u, +%u), first target %u, expected runs from %llu and target %llu",
                (unsigned long long)ci, g, grf, grc, gtf, (unsigned long long)runs_at, (unsigned long long)tsum);
            return;
        }
        uint64_t n = check_runs(c, ci, lbk_rd32(cr + DLS_C_SPACE), grf, grc);
        if (n == UINT64_MAX) return;
        if (n > LBK_DLS_SMALL_COMBINATION) {
            rep(c, 830, go, "packed cluster %llu sub-group %u has %llu targets, more than %u", (unsigned long long)ci, g,
                (unsigned long long)n, LBK_DLS_SMALL_COMBINATION);
            return;
        }
        const uint8_t *slots = gr + DLS_G_SLOTS;
        for (uint32_t j = 0; j < LBK_DLS_MAX_PACKED_SETS; j++) {
            bool bad = j < k ? (slots[j] >= nsets_c || (j && slots[j] <= slots[j - 1])) : slots[j] != 0;
            if (bad) {
                rep(c, 831, go + DLS_G_SLOTS + j,
                    "packed cluster %llu sub-group %u slot %u is %u (cluster has %u sets, %u per sub-group)",
                    (unsigned long long)ci, g, j, slots[j], nsets_c, k);
                return;
            }
            if (j < k) used[slots[j]] = true;
        }
        runs_at += grc;
        tsum += n;
    }
    if (runs_at != (uint64_t)run_first + run_count || tsum != targets)
        rep(c, 830, arr_off(c, DLS_A_CLUSTERS, ci, DLS_CLUSTER_SIZE),
            "packed cluster %llu sub-groups cover %llu runs and %llu targets, the cluster has %u and %u",
            (unsigned long long)ci, (unsigned long long)(runs_at - run_first), (unsigned long long)tsum, run_count, targets);
}

static void check_prefix(dls_chk *c, uint64_t ci, const uint8_t *cr, uint32_t form, uint32_t nsets_c, bool *used)
{
    const dls_prefix_form *pf = dls_prefix(form);
    uint64_t co = arr_off(c, DLS_A_CLUSTERS, ci, DLS_CLUSTER_SIZE);
    uint64_t T = lbk_rd32(cr + DLS_C_TARGET_COUNT);
    uint64_t E = lbk_rd32(cr + DLS_C_ENTRY_COUNT);
    uint32_t w_first = lbk_rd32(cr + DLS_C_AUX_FIRST), w_count = lbk_rd32(cr + DLS_C_AUX_COUNT);
    uint64_t words_needed = (T + pf->per_word - 1) / pf->per_word;
    if (w_count != words_needed) {
        rep(c, 840, co + DLS_C_AUX_COUNT, "cluster %llu has %u prefix words, %llu targets need %llu",
            (unsigned long long)ci, w_count, (unsigned long long)T, (unsigned long long)words_needed);
        return;
    }
    const uint8_t *words = arr(c, DLS_A_PREFIX_WORDS, w_first, 4);
    for (uint64_t w = 0; w < words_needed; w++) {
        uint64_t fields = w + 1 < words_needed ? pf->per_word : T - w * pf->per_word;
        uint64_t used_bits = fields * pf->bits;
        uint32_t mask = used_bits >= 32 ? 0xFFFFFFFFu : ((1u << used_bits) - 1u);
        uint32_t v = lbk_rd32(words + 4 * w);
        if (v & ~mask) {
            rep(c, 841, arr_off(c, DLS_A_PREFIX_WORDS, w_first + w, 4),
                "cluster %llu prefix word %llu is 0x%08x: bits past its %llu fields are set", (unsigned long long)ci,
                (unsigned long long)w, v, (unsigned long long)fields);
            return;
        }
    }
    if (E > pf->max_entries) {
        rep(c, 828, co + DLS_C_ENTRY_COUNT, "cluster %llu has %llu entries, more than the form's %llu",
            (unsigned long long)ci, (unsigned long long)E, (unsigned long long)pf->max_entries);
        return;
    }
    uint64_t nb = (T + pf->batch - 1) / pf->batch;
    int base_arr = pf->base_bytes == 2 ? DLS_A_BASE16 : DLS_A_BASE32;
    uint32_t b_first = lbk_rd32(cr + DLS_C_BASE_FIRST);
    uint64_t sum = 0;
    for (uint64_t b = 0; b < nb; b++) {
        const uint8_t *bp = arr(c, base_arr, b_first + b, pf->base_bytes);
        uint64_t base = pf->base_bytes == 2 ? lbk_rd16(bp) : lbk_rd32(bp);
        if (base != sum) {
            rep(c, 842, arr_off(c, base_arr, b_first + b, pf->base_bytes),
                "cluster %llu base %llu is %llu, the counts before it sum to %llu", (unsigned long long)ci,
                (unsigned long long)b, (unsigned long long)base, (unsigned long long)sum);
            return;
        }
        uint64_t end = (b + 1) * pf->batch < T ? (b + 1) * pf->batch : T;
        for (uint64_t i = b * pf->batch; i < end; i++) sum += dls_prefix_field(words, pf, i) + pf->bias;
    }
    if (sum != E) {
        rep(c, 843, co + DLS_C_ENTRY_COUNT, "cluster %llu prefix counts sum to %llu, its entry count is %llu",
            (unsigned long long)ci, (unsigned long long)sum, (unsigned long long)E);
        return;
    }
    uint64_t s_first = lbk_rd64(cr + DLS_C_SLOT_FIRST);
    const uint8_t *slots = arr(c, DLS_A_SLOTS, s_first, 1);
    uint64_t at = 0;
    for (uint64_t i = 0; i < T && !stopped(c); i++) {
        uint32_t n = dls_prefix_field(words, pf, i) + pf->bias;
        for (uint32_t j = 0; j < n; j++) {
            uint8_t s = slots[at + j];
            if (s >= nsets_c) {
                rep(c, 844, arr_off(c, DLS_A_SLOTS, s_first + at + j, 1),
                    "cluster %llu target %llu entry %u slot %u is outside its %u sets", (unsigned long long)ci,
                    (unsigned long long)i, j, s, nsets_c);
                return;
            }
            if (j && s <= slots[at + j - 1]) {
                rep(c, 845, arr_off(c, DLS_A_SLOTS, s_first + at + j, 1),
                    "cluster %llu target %llu entry %u slot %u does not follow slot %u", (unsigned long long)ci,
                    (unsigned long long)i, j, s, slots[at + j - 1]);
                return;
            }
            used[s] = true;
        }
        at += n;
    }
}

/* The set list, overlaps field, runs and entries of cluster ci, whose first indices are the
 * packed layout's (check_clusters); its runs go to runs[*nruns]. */
static void check_cluster_contents(dls_chk *c, uint64_t ci, run_key *runs, uint64_t *nruns)
{
    const uint64_t nsets = c->L.count[DLS_A_SETS];
    const uint8_t *cr = arr(c, DLS_A_CLUSTERS, ci, DLS_CLUSTER_SIZE);
    uint64_t co = arr_off(c, DLS_A_CLUSTERS, ci, DLS_CLUSTER_SIZE);
    uint32_t form = lbk_rd32(cr + DLS_C_FORM), space = lbk_rd32(cr + DLS_C_SPACE);
    uint32_t k = lbk_rd32(cr + DLS_C_OVERLAPS);
    uint32_t set_first = lbk_rd32(cr + DLS_C_SET_FIRST), set_count = lbk_rd32(cr + DLS_C_SET_COUNT);
    uint32_t run_first = lbk_rd32(cr + DLS_C_RUN_FIRST), run_count = lbk_rd32(cr + DLS_C_RUN_COUNT);
    uint32_t T = lbk_rd32(cr + DLS_C_TARGET_COUNT), E = lbk_rd32(cr + DLS_C_ENTRY_COUNT);

    /* Set list. */
    static const uint32_t min_sets[LBK_DLS_FORM_COUNT_] = {1, 1, 5, 9, 17};
    uint32_t max_sets = form == LBK_DLS_FORM_DEDICATED ? LBK_DLS_MAX_DEDICATED_SETS : LBK_DLS_MAX_CLUSTER_SETS;
    bool sets_ok = set_count >= min_sets[form] && set_count <= max_sets;
    for (uint32_t j = 0; sets_ok && j < set_count; j++) {
        uint32_t s = lbk_rd32(arr(c, DLS_A_CLUSTER_SETS, (uint64_t)set_first + j, 4));
        if (s >= nsets || (j && s <= lbk_rd32(arr(c, DLS_A_CLUSTER_SETS, (uint64_t)set_first + j - 1, 4)))) sets_ok = false;
    }
    if (!sets_ok) {
        rep(c, 824, co + DLS_C_SET_COUNT, "cluster %llu (form %u) lists %u sets: count outside %u..%u, a set out of range or not ascending",
            (unsigned long long)ci, form, set_count, min_sets[form], max_sets);
        return;
    }
    bool k_ok = form == LBK_DLS_FORM_DEDICATED ? k == set_count
                : form == LBK_DLS_FORM_PACKED  ? (k >= 1 && k <= LBK_DLS_MAX_PACKED_SETS && k <= set_count)
                                               : k == 0;
    if (!k_ok) {
        rep(c, 825, co + DLS_C_OVERLAPS, "cluster %llu (form %u, %u sets) has overlaps field %u", (unsigned long long)ci,
            form, set_count, k);
        return;
    }

    /* Runs and target count. */
    if (run_count == 0 || T == 0) {
        rep(c, 827, co + DLS_C_TARGET_COUNT, "cluster %llu has %u runs and %u targets", (unsigned long long)ci, run_count, T);
        return;
    }
    uint64_t tsum = 0;
    if (form == LBK_DLS_FORM_PACKED) {
        for (uint32_t i = 0; i < run_count; i++) tsum += lbk_rd32(arr(c, DLS_A_RUNS, (uint64_t)run_first + i, DLS_RUN_SIZE) + 4);
    } else {
        tsum = check_runs(c, ci, space, run_first, run_count);
        if (tsum == UINT64_MAX) return;
    }
    if (tsum != T) {
        rep(c, 827, co + DLS_C_TARGET_COUNT, "cluster %llu target count %u differs from its runs' %llu",
            (unsigned long long)ci, T, (unsigned long long)tsum);
        return;
    }
    for (uint32_t i = 0; i < run_count; i++) {
        const uint8_t *r = arr(c, DLS_A_RUNS, (uint64_t)run_first + i, DLS_RUN_SIZE);
        runs[(*nruns)++] = (run_key){space, lbk_rd32(r), lbk_rd32(r + 4), (uint32_t)ci};
    }

    /* Entries. */
    bool used[LBK_DLS_MAX_CLUSTER_SETS] = {0};
    if (form == LBK_DLS_FORM_DEDICATED || form == LBK_DLS_FORM_PACKED) {
        if ((uint64_t)T * k != E) {
            rep(c, 828, co + DLS_C_ENTRY_COUNT, "cluster %llu has %u entries, %u targets × %u sets need %llu",
                (unsigned long long)ci, E, T, k, (unsigned long long)T * k);
            return;
        }
        if (form == LBK_DLS_FORM_PACKED) {
            uint32_t before = c->errors;
            check_subgroups(c, ci, cr, k, set_count, used);
            if (c->errors != before) return;
        }
    } else {
        uint32_t before = c->errors;
        check_prefix(c, ci, cr, form, set_count, used);
        if (c->errors != before) return;
    }
    if (form != LBK_DLS_FORM_DEDICATED)
        for (uint32_t j = 0; j < set_count; j++)
            if (!used[j]) {
                rep(c, 832, co + DLS_C_SET_FIRST, "cluster %llu lists set %u but no target uses it", (unsigned long long)ci,
                    lbk_rd32(arr(c, DLS_A_CLUSTER_SETS, (uint64_t)set_first + j, 4)));
                break;
            }
}

/* The header's array counts against what the clusters use (t). */
static void check_cluster_totals(dls_chk *c, const dls_totals *t)
{
    const struct {
        uint64_t have, want;
        const char *what;
    } tot[] = {{t->sets, c->L.count[DLS_A_CLUSTER_SETS], "cluster sets"},
               {t->runs, c->L.count[DLS_A_RUNS], "runs"},
               {t->subgroups, c->L.count[DLS_A_SUBGROUPS], "sub-groups"},
               {t->words, c->L.count[DLS_A_PREFIX_WORDS], "prefix words"},
               {t->base16, c->L.count[DLS_A_BASE16], "u16 bases"},
               {t->base32, c->L.count[DLS_A_BASE32], "u32 bases"},
               {t->slots, c->L.count[DLS_A_SLOTS], "slots"},
               {t->entries[0], c->L.count[DLS_A_TEXEL_ENTRIES], "texel entries"},
               {t->entries[1], c->L.count[DLS_A_PROBE_ENTRIES], "probe entries"}};
    for (size_t i = 0; i < sizeof tot / sizeof tot[0]; i++)
        if (tot[i].have != tot[i].want)
            rep(c, 805, DLS_H_CLUSTER_SET_COUNT, "header declares %llu %s, the clusters use %llu",
                (unsigned long long)tot[i].want, tot[i].what, (unsigned long long)tot[i].have);
}

/* Each target in at most one cluster: runs sorted, neighbours of a space must not overlap. */
static void check_run_overlaps(dls_chk *c, run_key *runs, uint64_t nruns)
{
    qsort(runs, nruns, sizeof *runs, cmp_run);
    for (uint64_t i = 1; i < nruns && !stopped(c); i++) {
        const run_key *a = &runs[i - 1], *b = &runs[i];
        if (a->space == b->space && (uint64_t)a->start + a->length > b->start)
            rep(c, 829, arr_off(c, DLS_A_CLUSTERS, b->cluster, DLS_CLUSTER_SIZE),
                "%s target %u is in cluster %u and cluster %u", space_name(a->space), b->start, a->cluster, b->cluster);
    }
}

/* Every cluster record: form, space and order, first indices against the packed layout, ranges
 * inside the arrays; then the form-specific checks (check_cluster_contents: k, set count range,
 * subgroup/prefix usage), the header's totals and each target in at most one cluster. */
static void check_clusters(dls_chk *c)
{
    const uint64_t ncl = c->L.count[DLS_A_CLUSTERS];
    dls_totals t = {0};
    uint32_t prev_key = 0;
    bool totals_ok = true;
    run_key *runs = lbk_calloc(c->alloc, c->L.count[DLS_A_RUNS] ? c->L.count[DLS_A_RUNS] : 1, sizeof *runs);
    if (!runs) {
        c->oom = true;
        return;
    }
    uint64_t nruns = 0;
    for (uint64_t ci = 0; ci < ncl && !stopped(c); ci++) {
        const uint8_t *cr = arr(c, DLS_A_CLUSTERS, ci, DLS_CLUSTER_SIZE);
        uint64_t co = arr_off(c, DLS_A_CLUSTERS, ci, DLS_CLUSTER_SIZE);
        uint32_t form = lbk_rd32(cr + DLS_C_FORM), space = lbk_rd32(cr + DLS_C_SPACE);
        uint32_t set_first = lbk_rd32(cr + DLS_C_SET_FIRST), set_count = lbk_rd32(cr + DLS_C_SET_COUNT);
        uint32_t run_first = lbk_rd32(cr + DLS_C_RUN_FIRST), run_count = lbk_rd32(cr + DLS_C_RUN_COUNT);
        uint32_t T = lbk_rd32(cr + DLS_C_TARGET_COUNT), E = lbk_rd32(cr + DLS_C_ENTRY_COUNT);
        uint32_t aux_first = lbk_rd32(cr + DLS_C_AUX_FIRST), aux_count = lbk_rd32(cr + DLS_C_AUX_COUNT);
        uint32_t base_first = lbk_rd32(cr + DLS_C_BASE_FIRST);
        uint64_t entry_first = lbk_rd64(cr + DLS_C_ENTRY_FIRST), slot_first = lbk_rd64(cr + DLS_C_SLOT_FIRST);
        if (form >= LBK_DLS_FORM_COUNT_) {
            rep(c, 820, co + DLS_C_FORM, "cluster %llu form %u is unknown", (unsigned long long)ci, form);
            totals_ok = false;
            break;
        }
        if (space >= LBK_DLS_SPACE_COUNT_) {
            rep(c, 821, co + DLS_C_SPACE, "cluster %llu target space %u is unknown", (unsigned long long)ci, space);
            totals_ok = false;
            break;
        }
        uint32_t key = space * LBK_DLS_FORM_COUNT_ + form;
        if (ci && key < prev_key)
            rep(c, 822, co, "cluster %llu (space %u, form %u) comes after a cluster of a later (space, form)",
                (unsigned long long)ci, space, form);
        prev_key = key;

        /* Packed layout: each *_first is the running total; fields a form does not use are 0. */
        const dls_prefix_form *pf = dls_prefix(form);
        int stride = space == LBK_DLS_SPACE_TEXEL ? 0 : 1;
        uint64_t exp_aux = form == LBK_DLS_FORM_PACKED ? t.subgroups : pf ? t.words : 0;
        uint64_t exp_base = pf ? (pf->base_bytes == 2 ? t.base16 : t.base32) : 0;
        uint64_t nb = pf ? ((uint64_t)T + pf->batch - 1) / pf->batch : 0;
        bool canon = set_first == t.sets && run_first == t.runs && aux_first == exp_aux && base_first == exp_base &&
                     entry_first == t.entries[stride] && slot_first == (pf ? t.slots : 0) &&
                     (form == LBK_DLS_FORM_DEDICATED ? aux_count == 0 : 1);
        /* Every range must lie inside its array before anything is read from it. */
        bool in_range = t.sets + set_count <= c->L.count[DLS_A_CLUSTER_SETS] &&
                        t.runs + run_count <= c->L.count[DLS_A_RUNS] &&
                        (form != LBK_DLS_FORM_PACKED || t.subgroups + aux_count <= c->L.count[DLS_A_SUBGROUPS]) &&
                        (!pf || t.words + aux_count <= c->L.count[DLS_A_PREFIX_WORDS]) &&
                        (!pf || exp_base + nb <= c->L.count[pf->base_bytes == 2 ? DLS_A_BASE16 : DLS_A_BASE32]) &&
                        (!pf || t.slots + E <= c->L.count[DLS_A_SLOTS]) &&
                        t.entries[stride] + E <= c->L.count[stride ? DLS_A_PROBE_ENTRIES : DLS_A_TEXEL_ENTRIES];
        if (!canon) {
            rep(c, 823, co + DLS_C_SET_FIRST,
                "cluster %llu first indices (sets %u, runs %u, aux %u, base %u, entries %llu, slots %llu) differ from the packed layout",
                (unsigned long long)ci, set_first, run_first, aux_first, base_first, (unsigned long long)entry_first,
                (unsigned long long)slot_first);
        }
        if (!in_range) {
            rep(c, 805, co, "cluster %llu reaches past the arrays the header declares", (unsigned long long)ci);
            totals_ok = false;
            break;
        }
        t.sets += set_count;
        t.runs += run_count;
        if (form == LBK_DLS_FORM_PACKED) t.subgroups += aux_count;
        if (pf) {
            t.words += aux_count;
            if (pf->base_bytes == 2) t.base16 += nb; else t.base32 += nb;
            t.slots += E;
        }
        t.entries[stride] += E;
        if (canon) check_cluster_contents(c, ci, runs, &nruns);
    }
    if (totals_ok && !stopped(c)) check_cluster_totals(c, &t);
    check_run_overlaps(c, runs, nruns);
    lbk_dealloc(c->alloc, runs);
}

/* Texel payloads: R11G11B10F channels with exponent 31 (Inf/NaN) are never written by encoders. */
static void check_payloads(dls_chk *c)
{
    const uint64_t n = c->L.count[DLS_A_TEXEL_ENTRIES];
    for (uint64_t i = 0; i < n && !stopped(c); i++) {
        uint32_t v = lbk_rd32(arr(c, DLS_A_TEXEL_ENTRIES, i, LBK_DLS_TEXEL_PAYLOAD));
        if (((v >> 6) & 31) == 31 || ((v >> 17) & 31) == 31 || ((v >> 27) & 31) == 31)
            rep(c, 850, arr_off(c, DLS_A_TEXEL_ENTRIES, i, LBK_DLS_TEXEL_PAYLOAD),
                "texel entry %llu irradiance 0x%08x has an Inf/NaN channel", (unsigned long long)i, v);
    }
}

static void dls_check(dls_chk *c)
{
    if (!check_frame(c)) return;
    check_cross_section(c);
    if (stopped(c)) return;
    check_sets(c);
    if (c->oom || stopped(c)) return;
    check_clusters(c);
    if (c->oom || stopped(c)) return;
    check_payloads(c);
}

/* ---- validator ------------------------------------------------------------------------------ */

/* Facts for DOOR: set kinds and combination members, in one allocation that validate.c frees. */
static void record_facts(lbk_vctx *ctx, const dls_chk *c)
{
    uint64_t nsets = c->L.count[DLS_A_SETS], nmem = c->L.count[DLS_A_MEMBERS];
    uint64_t bytes;
    if (!lbk_madd_u64(4 * (nsets + 1) + 4 * nmem, nsets, 1, &bytes)) return;
    uint8_t *blob = lbk_alloc(ctx->allocator, (size_t)bytes);
    if (!blob) return;
    uint32_t *offs = (uint32_t *)(void *)blob;
    uint32_t *mem = offs + nsets + 1;
    uint8_t *kinds = (uint8_t *)(mem + nmem);
    for (uint64_t s = 0; s < nsets; s++) {
        const uint8_t *r = arr(c, DLS_A_SETS, s, DLS_SET_SIZE);
        kinds[s] = (uint8_t)lbk_rd32(r + DLS_S_KIND);
        offs[s] = lbk_rd32(r + DLS_S_MEMBER_FIRST);
    }
    offs[nsets] = (uint32_t)nmem;
    for (uint64_t m = 0; m < nmem; m++) mem[m] = lbk_rd32(arr(c, DLS_A_MEMBERS, m, 4));
    ctx->dls_facts = blob;
    ctx->dls_set_kind = kinds;
    ctx->dls_member_offset = offs;
    ctx->dls_members = mem;
}

void lbk_validate_dls(lbk_vctx *ctx, const uint8_t *data, size_t size)
{
    dls_chk c;
    memset(&c, 0, sizeof c);
    c.ctx = ctx;
    c.alloc = ctx->allocator;
    c.d = data;
    c.size = size;
    dls_check(&c);
    if (c.oom) lbk_vreport(ctx, 805, 0, "out of memory while checking the DLS section");
    if (c.errors == 0 && !c.oom && !ctx->stop) {
        ctx->dls_ok = 1;
        ctx->dls_set_count = (uint32_t)c.L.count[DLS_A_SETS];
        record_facts(ctx, &c);
    }
}

/* ---- view ----------------------------------------------------------------------------------- */

struct lbk_dls_view {
    const lbk_allocator *alloc;
    lbk_allocator alloc_copy;
    const uint8_t *d;
    uint64_t size;
    dls_layout L;
    uint64_t target_count[LBK_DLS_SPACE_COUNT_];
};

lbk_result lbk_dls_open(const void *data, size_t size, const lbk_allocator *allocator, lbk_dls_view **out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    dls_chk c;
    memset(&c, 0, sizeof c);
    c.alloc = allocator;
    c.d = data;
    c.size = size;
    dls_check(&c);
    if (c.oom) return LBK_ERR_OUT_OF_MEMORY;
    if (c.errors) return size < DLS_HEADER_SIZE || (c.L.size > size && c.L.size) ? LBK_ERR_TRUNCATED : LBK_ERR_CORRUPT;
    lbk_dls_view *v = lbk_calloc(allocator, 1, sizeof *v);
    if (!v) return LBK_ERR_OUT_OF_MEMORY;
    if (allocator) v->alloc_copy = *allocator;
    v->alloc = allocator ? &v->alloc_copy : NULL;
    v->d = data;
    v->size = size;
    v->L = c.L;
    memcpy(v->target_count, c.target_count, sizeof v->target_count);
    *out = v;
    return LBK_OK;
}

void lbk_dls_close(lbk_dls_view *view)
{
    if (view) lbk_dealloc(view->alloc, view);
}

static const uint8_t *varr(const lbk_dls_view *v, int a, uint64_t index, uint64_t elem)
{
    return v->d + v->L.offset[a] + index * elem;
}

uint32_t lbk_dls_set_count(const lbk_dls_view *view) { return view ? (uint32_t)view->L.count[DLS_A_SETS] : 0; }

lbk_result lbk_dls_set_get(const lbk_dls_view *view, uint32_t set, lbk_dls_set_info *out)
{
    if (!view || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (set >= view->L.count[DLS_A_SETS]) return LBK_ERR_NOT_FOUND;
    const uint8_t *r = varr(view, DLS_A_SETS, set, DLS_SET_SIZE);
    out->name = (const char *)view->d + view->L.offset[DLS_A_STRINGS] + lbk_rd32(r + DLS_S_NAME_OFF);
    out->name_length = lbk_rd32(r + DLS_S_NAME_LEN);
    out->kind = lbk_rd32(r + DLS_S_KIND);
    out->light_count = lbk_rd32(r + DLS_S_LIGHT_COUNT);
    out->member_count = lbk_rd32(r + DLS_S_MEMBER_COUNT);
    return LBK_OK;
}

lbk_result lbk_dls_set_light_get(const lbk_dls_view *view, uint32_t set, uint32_t i, const char **name, uint32_t *length)
{
    if (!view || !name || !length) return LBK_ERR_INVALID_ARGUMENT;
    if (set >= view->L.count[DLS_A_SETS]) return LBK_ERR_NOT_FOUND;
    const uint8_t *r = varr(view, DLS_A_SETS, set, DLS_SET_SIZE);
    if (i >= lbk_rd32(r + DLS_S_LIGHT_COUNT)) return LBK_ERR_NOT_FOUND;
    const uint8_t *lr = varr(view, DLS_A_LIGHT_REFS, (uint64_t)lbk_rd32(r + DLS_S_LIGHT_FIRST) + i, DLS_LIGHT_REF_SIZE);
    *name = (const char *)view->d + view->L.offset[DLS_A_STRINGS] + lbk_rd32(lr);
    *length = lbk_rd32(lr + 4);
    return LBK_OK;
}

lbk_result lbk_dls_set_member_get(const lbk_dls_view *view, uint32_t set, uint32_t i, uint32_t *member)
{
    if (!view || !member) return LBK_ERR_INVALID_ARGUMENT;
    if (set >= view->L.count[DLS_A_SETS]) return LBK_ERR_NOT_FOUND;
    const uint8_t *r = varr(view, DLS_A_SETS, set, DLS_SET_SIZE);
    if (i >= lbk_rd32(r + DLS_S_MEMBER_COUNT)) return LBK_ERR_NOT_FOUND;
    *member = lbk_rd32(varr(view, DLS_A_MEMBERS, (uint64_t)lbk_rd32(r + DLS_S_MEMBER_FIRST) + i, 4));
    return LBK_OK;
}

lbk_result lbk_dls_set_find(const lbk_dls_view *view, const char *name, uint32_t *set)
{
    if (!view || !name || !set) return LBK_ERR_INVALID_ARGUMENT;
    size_t n = strlen(name);
    for (uint32_t s = 0; s < view->L.count[DLS_A_SETS]; s++) {
        lbk_dls_set_info info;
        lbk_dls_set_get(view, s, &info);
        if (info.name_length == n && memcmp(info.name, name, n) == 0) {
            *set = s;
            return LBK_OK;
        }
    }
    return LBK_ERR_NOT_FOUND;
}

uint64_t lbk_dls_target_count(const lbk_dls_view *view, uint32_t space)
{
    return view && space < LBK_DLS_SPACE_COUNT_ ? view->target_count[space] : 0;
}

uint32_t lbk_dls_cluster_count(const lbk_dls_view *view) { return view ? (uint32_t)view->L.count[DLS_A_CLUSTERS] : 0; }

lbk_result lbk_dls_cluster_get(const lbk_dls_view *view, uint32_t cluster, lbk_dls_cluster_info *out)
{
    if (!view || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (cluster >= view->L.count[DLS_A_CLUSTERS]) return LBK_ERR_NOT_FOUND;
    const uint8_t *cr = varr(view, DLS_A_CLUSTERS, cluster, DLS_CLUSTER_SIZE);
    out->form = lbk_rd32(cr + DLS_C_FORM);
    out->space = lbk_rd32(cr + DLS_C_SPACE);
    out->set_count = lbk_rd32(cr + DLS_C_SET_COUNT);
    out->overlaps = lbk_rd32(cr + DLS_C_OVERLAPS);
    out->target_count = lbk_rd32(cr + DLS_C_TARGET_COUNT);
    out->entry_count = lbk_rd32(cr + DLS_C_ENTRY_COUNT);
    out->run_count = lbk_rd32(cr + DLS_C_RUN_COUNT);
    out->subgroup_count = out->form == LBK_DLS_FORM_PACKED ? lbk_rd32(cr + DLS_C_AUX_COUNT) : 0;
    return LBK_OK;
}

lbk_result lbk_dls_cluster_set_get(const lbk_dls_view *view, uint32_t cluster, uint32_t i, uint32_t *set)
{
    if (!view || !set) return LBK_ERR_INVALID_ARGUMENT;
    if (cluster >= view->L.count[DLS_A_CLUSTERS]) return LBK_ERR_NOT_FOUND;
    const uint8_t *cr = varr(view, DLS_A_CLUSTERS, cluster, DLS_CLUSTER_SIZE);
    if (i >= lbk_rd32(cr + DLS_C_SET_COUNT)) return LBK_ERR_NOT_FOUND;
    *set = lbk_rd32(varr(view, DLS_A_CLUSTER_SETS, (uint64_t)lbk_rd32(cr + DLS_C_SET_FIRST) + i, 4));
    return LBK_OK;
}

lbk_result lbk_dls_array_get(const lbk_dls_view *view, uint32_t array, uint64_t *offset, uint64_t *count)
{
    if (!view) return LBK_ERR_INVALID_ARGUMENT;
    if (array >= LBK_DLS_ARRAY_COUNT_) return LBK_ERR_NOT_FOUND;
    /* lbk_dls_array numbers the arrays as the spec orders them, as DLS_A_* does */
    if (offset) *offset = view->L.offset[array];
    if (count) *count = view->L.count[array];
    return LBK_OK;
}

void lbk_dls_view_raw(const lbk_dls_view *v, lbk_dls_raw *raw)
{
    raw->d = v->d;
    raw->size = v->size;
    for (int a = 0; a < DLS_A_COUNT; a++) {
        raw->offset[a] = v->L.offset[a];
        raw->count[a] = v->L.count[a];
    }
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) raw->target_count[s] = v->target_count[s];
}

lbk_result lbk_dls_cluster_decode(const lbk_dls_view *view, uint32_t cluster, lbk_dls_target_fn fn, void *user)
{
    if (!view || !fn) return LBK_ERR_INVALID_ARGUMENT;
    if (cluster >= view->L.count[DLS_A_CLUSTERS]) return LBK_ERR_NOT_FOUND;
    const uint8_t *cr = varr(view, DLS_A_CLUSTERS, cluster, DLS_CLUSTER_SIZE);
    uint32_t form = lbk_rd32(cr + DLS_C_FORM), space = lbk_rd32(cr + DLS_C_SPACE);
    uint32_t psize = dls_payload_size(space);
    uint32_t nsets = lbk_rd32(cr + DLS_C_SET_COUNT), k = lbk_rd32(cr + DLS_C_OVERLAPS);
    const uint8_t *set_list = varr(view, DLS_A_CLUSTER_SETS, lbk_rd32(cr + DLS_C_SET_FIRST), 4);
    uint32_t all_sets[LBK_DLS_MAX_CLUSTER_SETS], sets[LBK_DLS_MAX_CLUSTER_SETS];
    for (uint32_t j = 0; j < nsets; j++) all_sets[j] = lbk_rd32(set_list + 4 * j);
    const uint8_t *payload = varr(view, space == LBK_DLS_SPACE_TEXEL ? DLS_A_TEXEL_ENTRIES : DLS_A_PROBE_ENTRIES,
                                  lbk_rd64(cr + DLS_C_ENTRY_FIRST), psize);
    uint32_t run_first = lbk_rd32(cr + DLS_C_RUN_FIRST), run_count = lbk_rd32(cr + DLS_C_RUN_COUNT);
    if (form == LBK_DLS_FORM_DEDICATED) {
        for (uint32_t i = 0; i < run_count; i++) {
            const uint8_t *r = varr(view, DLS_A_RUNS, (uint64_t)run_first + i, DLS_RUN_SIZE);
            uint32_t start = lbk_rd32(r), len = lbk_rd32(r + 4);
            for (uint32_t t = 0; t < len; t++, payload += (size_t)k * psize)
                if (fn(user, start + t, k, all_sets, payload)) return LBK_OK;
        }
    } else if (form == LBK_DLS_FORM_PACKED) {
        uint32_t g_first = lbk_rd32(cr + DLS_C_AUX_FIRST), g_count = lbk_rd32(cr + DLS_C_AUX_COUNT);
        for (uint32_t g = 0; g < g_count; g++) {
            const uint8_t *gr = varr(view, DLS_A_SUBGROUPS, (uint64_t)g_first + g, DLS_SUBGROUP_SIZE);
            for (uint32_t j = 0; j < k; j++) sets[j] = all_sets[gr[DLS_G_SLOTS + j]];
            uint32_t grf = lbk_rd32(gr + DLS_G_RUN_FIRST), grc = lbk_rd32(gr + DLS_G_RUN_COUNT);
            for (uint32_t i = 0; i < grc; i++) {
                const uint8_t *r = varr(view, DLS_A_RUNS, (uint64_t)grf + i, DLS_RUN_SIZE);
                uint32_t start = lbk_rd32(r), len = lbk_rd32(r + 4);
                for (uint32_t t = 0; t < len; t++, payload += (size_t)k * psize)
                    if (fn(user, start + t, k, sets, payload)) return LBK_OK;
            }
        }
    } else {
        const dls_prefix_form *pf = dls_prefix(form);
        const uint8_t *words = varr(view, DLS_A_PREFIX_WORDS, lbk_rd32(cr + DLS_C_AUX_FIRST), 4);
        const uint8_t *slots = varr(view, DLS_A_SLOTS, lbk_rd64(cr + DLS_C_SLOT_FIRST), 1);
        uint64_t ordinal = 0;
        for (uint32_t i = 0; i < run_count; i++) {
            const uint8_t *r = varr(view, DLS_A_RUNS, (uint64_t)run_first + i, DLS_RUN_SIZE);
            uint32_t start = lbk_rd32(r), len = lbk_rd32(r + 4);
            for (uint32_t t = 0; t < len; t++, ordinal++) {
                uint32_t n = dls_prefix_field(words, pf, ordinal) + pf->bias;
                for (uint32_t j = 0; j < n; j++) sets[j] = all_sets[slots[j]];
                if (fn(user, start + t, n, sets, payload)) return LBK_OK;
                slots += n;
                payload += (size_t)n * psize;
            }
        }
    }
    return LBK_OK;
}

/* ---- statistics ----------------------------------------------------------------------------- */

static int stats_target(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    (void)target; (void)sets; (void)payloads;
    uint64_t *hist = user;
    hist[count <= 16 ? count : 17]++;
    return 0;
}

lbk_result lbk_dls_stats_get(const lbk_dls_view *view, lbk_dls_stats *out)
{
    if (!view || !out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const dls_layout *L = &view->L;
    out->set_count = (uint32_t)L->count[DLS_A_SETS];
    for (uint32_t s = 0; s < out->set_count; s++) {
        uint32_t kind = lbk_rd32(varr(view, DLS_A_SETS, s, DLS_SET_SIZE) + DLS_S_KIND);
        out->sets_by_kind[kind]++;
    }
    out->cluster_count = (uint32_t)L->count[DLS_A_CLUSTERS];
    for (uint32_t ci = 0; ci < out->cluster_count; ci++) {
        lbk_dls_cluster_info info;
        lbk_dls_cluster_get(view, ci, &info);
        const dls_prefix_form *pf = dls_prefix(info.form);
        out->clusters_by_form[info.form]++;
        out->packed_subgroups += info.subgroup_count;
        out->touched[info.space] += info.target_count;
        out->targets_by_form[info.form] += info.target_count;
        out->entries[info.space] += info.entry_count;
        uint64_t idx = DLS_CLUSTER_SIZE + 4ull * info.set_count + (uint64_t)DLS_RUN_SIZE * info.run_count +
                       (uint64_t)DLS_SUBGROUP_SIZE * info.subgroup_count;
        if (pf)
            idx += 4ull * ((info.target_count + pf->per_word - 1) / pf->per_word) +
                   (uint64_t)pf->base_bytes * ((info.target_count + pf->batch - 1) / pf->batch) + info.entry_count;
        out->index_bytes[info.space] += idx;
        lbk_dls_cluster_decode(view, ci, stats_target, out->histogram[info.space]);
    }
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        out->target_count[s] = view->target_count[s];
        out->histogram[s][0] = view->target_count[s] - out->touched[s];
        out->index_bits_per_target[s] = out->touched[s] ? 8.0 * (double)out->index_bytes[s] / (double)out->touched[s] : 0.0;
    }
    out->section_bytes = view->size;
    out->payload_bytes = L->count[DLS_A_TEXEL_ENTRIES] * LBK_DLS_TEXEL_PAYLOAD + L->count[DLS_A_PROBE_ENTRIES] * LBK_DLS_PROBE_PAYLOAD;
    out->ancillary_bytes = out->section_bytes - out->payload_bytes;
    return LBK_OK;
}
