/* DLS builder: per-set sparse entries → combination clusters → section bytes (spec §12).
 *
 * Per target space: sort all (target, set) entries, find each target's combination of sets, give
 * every distinct combination a canonical number (by size, then lexicographic set list), and
 * route each combination to a form:
 *   k ≤ 8 and more than 128 targets → dedicated cluster;
 *   k ≤ 4 and at most 128 targets   → class (1) packed clusters of the same k;
 *   5 ≤ k ≤ 8, at most 128 targets  → class (2) 2-bit prefix clusters;
 *   9 ≤ k ≤ 16                      → class (2) 3-bit prefix clusters;
 *   17 ≤ k ≤ 255                    → class (3) 8-bit prefix clusters;
 *   k > 255                         → LBK_ERR_OVERLAPS.
 * Packed and prefix clusters are grown greedily so that each dispatch lists few sets (the whole
 * dispatch reruns when any of its sets changes): a cluster starts from the largest remaining
 * combination, takes every combination that adds no new set, and while it holds fewer than
 * min_dispatch_targets targets also the one adding the fewest new sets. */
#include <stdlib.h>

#include "dls_format.h"

/* ---- growable buffer -------------------------------------------------------------------- */

typedef struct vec {
    uint8_t *p;
    size_t len, cap;
    const lbk_allocator *a;
    bool oom;
} vec;

static uint8_t *vec_grow(vec *v, size_t n)
{
    if (v->oom) return NULL;
    if (n > SIZE_MAX - v->len) { v->oom = true; return NULL; }
    if (v->len + n > v->cap) {
        size_t cap = v->cap ? v->cap : 256;
        while (cap < v->len + n) {
            if (cap > SIZE_MAX / 2) { v->oom = true; return NULL; }
            cap *= 2;
        }
        uint8_t *q = lbk_alloc(v->a, cap);
        if (!q) { v->oom = true; return NULL; }
        if (v->len) memcpy(q, v->p, v->len);
        lbk_dealloc(v->a, v->p);
        v->p = q;
        v->cap = cap;
    }
    uint8_t *at = v->p + v->len;
    v->len += n;
    return at;
}
static void vec_u32(vec *v, uint32_t x) { uint8_t *p = vec_grow(v, 4); if (p) lbk_wr32(p, x); }
static void vec_u16(vec *v, uint16_t x) { uint8_t *p = vec_grow(v, 2); if (p) lbk_wr16(p, x); }
static void vec_u8(vec *v, uint8_t x) { uint8_t *p = vec_grow(v, 1); if (p) *p = x; }
static void vec_bytes(vec *v, const void *src, size_t n) { uint8_t *p = vec_grow(v, n); if (p && n) memcpy(p, src, n); }
static void vec_free(vec *v) { lbk_dealloc(v->a, v->p); v->p = NULL; v->len = v->cap = 0; }

/* ---- per-space working data --------------------------------------------------------------- */

typedef struct rec {
    uint32_t target, set;
    const uint8_t *payload;
} rec;

typedef struct group {   /* one touched target */
    uint32_t target;
    uint32_t k;
    uint64_t rec_first;  /* its k records, ascending set */
    uint32_t combo;
} group;

typedef struct combo {
    uint32_t k;
    uint64_t rep;        /* a group with this combination (for its set list) */
    uint64_t n;          /* targets */
    uint64_t g_first;    /* into combo_groups */
} combo;

typedef struct chunk {   /* consecutive targets of one combination */
    uint32_t combo;
    uint64_t first, count; /* into the combination's groups */
} chunk;

typedef struct builder {
    const lbk_allocator *a;
    const lbk_dls_build_desc *desc;
    uint32_t min_fill, packed_cap;
    /* per space */
    uint32_t space;
    rec *recs;
    uint64_t nrecs;
    group *groups;
    uint64_t ngroups;
    combo *combos;
    uint32_t ncombos;
    uint64_t *combo_groups; /* group indices, by combination, ascending target */
    /* output arrays */
    vec clusters, cluster_sets, runs, subgroups, words, base16, base32, slots, texels, probes;
    uint64_t tot_sets, tot_runs, tot_subgroups, tot_words, tot_base16, tot_base32, tot_slots, tot_entries[2];
    lbk_result err;
} builder;

static int cmp_rec(const void *a, const void *b)
{
    const rec *x = a, *y = b;
    if (x->target != y->target) return x->target < y->target ? -1 : 1;
    return x->set < y->set ? -1 : x->set > y->set;
}

static const rec *group_recs(const builder *b, uint64_t g) { return b->recs + b->groups[g].rec_first; }

static int cmp_group_sets(const builder *b, uint64_t g1, uint64_t g2)
{
    const group *x = &b->groups[g1], *y = &b->groups[g2];
    uint32_t n = x->k < y->k ? x->k : y->k;
    const rec *rx = group_recs(b, g1), *ry = group_recs(b, g2);
    for (uint32_t i = 0; i < n; i++)
        if (rx[i].set != ry[i].set) return rx[i].set < ry[i].set ? -1 : 1;
    return x->k < y->k ? -1 : x->k > y->k;
}

typedef struct combo_key {
    const builder *b;
    uint32_t id;
} combo_key;

static int cmp_combo_key(const void *a, const void *bb)
{
    const combo_key *x = a, *y = bb;
    const builder *b = x->b;
    const combo *cx = &b->combos[x->id], *cy = &b->combos[y->id];
    if (cx->k != cy->k) return cx->k < cy->k ? -1 : 1;
    return cmp_group_sets(b, cx->rep, cy->rep);
}

static uint64_t hash_sets(const rec *r, uint32_t k)
{
    uint64_t h = 1469598103934665603ull;
    for (uint32_t i = 0; i < k; i++) {
        h ^= r[i].set;
        h *= 1099511628211ull;
    }
    return h ^ (h >> 29);
}

/* Sort records, form target groups, number the combinations canonically. */
static lbk_result find_combinations(builder *b)
{
    qsort(b->recs, b->nrecs, sizeof *b->recs, cmp_rec);
    uint64_t ng = 0;
    for (uint64_t i = 0; i < b->nrecs; i++) {
        if (i && b->recs[i].target == b->recs[i - 1].target && b->recs[i].set == b->recs[i - 1].set)
            return LBK_ERR_INVALID_ARGUMENT; /* a set lists a target twice */
        if (i == 0 || b->recs[i].target != b->recs[i - 1].target) ng++;
    }
    b->ngroups = ng;
    b->groups = lbk_calloc(b->a, ng ? ng : 1, sizeof *b->groups);
    if (!b->groups) return LBK_ERR_OUT_OF_MEMORY;
    ng = 0;
    for (uint64_t i = 0; i < b->nrecs; i++) {
        if (i == 0 || b->recs[i].target != b->recs[i - 1].target) {
            b->groups[ng].target = b->recs[i].target;
            b->groups[ng].rec_first = i;
            ng++;
        }
        if (++b->groups[ng - 1].k > LBK_DLS_MAX_OVERLAPS) return LBK_ERR_OVERLAPS;
    }

    /* Hash the set lists (open addressing; table ≥ 2 × groups). */
    uint64_t cap = 16;
    while (cap < 2 * ng) cap *= 2;
    uint32_t *table = lbk_alloc(b->a, cap * sizeof *table);
    b->combos = lbk_calloc(b->a, ng ? ng : 1, sizeof *b->combos);
    if (!table || !b->combos) {
        lbk_dealloc(b->a, table);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    memset(table, 0xFF, cap * sizeof *table);
    uint32_t nc = 0;
    for (uint64_t g = 0; g < ng; g++) {
        uint64_t h = hash_sets(group_recs(b, g), b->groups[g].k) & (cap - 1);
        for (;;) {
            uint32_t id = table[h];
            if (id == UINT32_MAX) {
                table[h] = nc;
                b->combos[nc] = (combo){b->groups[g].k, g, 0, 0};
                b->groups[g].combo = nc++;
                break;
            }
            if (cmp_group_sets(b, b->combos[id].rep, g) == 0) {
                b->groups[g].combo = id;
                break;
            }
            h = (h + 1) & (cap - 1);
        }
    }
    lbk_dealloc(b->a, table);
    b->ncombos = nc;

    /* Canonical numbering: by k, then lexicographic set list. */
    combo_key *keys = lbk_alloc(b->a, (nc ? nc : 1) * sizeof *keys);
    uint32_t *rank = lbk_alloc(b->a, (nc ? nc : 1) * sizeof *rank);
    combo *sorted = lbk_alloc(b->a, (nc ? nc : 1) * sizeof *sorted);
    b->combo_groups = lbk_alloc(b->a, (ng ? ng : 1) * sizeof *b->combo_groups);
    lbk_result r = LBK_OK;
    if (!keys || !rank || !sorted || !b->combo_groups) {
        r = LBK_ERR_OUT_OF_MEMORY;
        goto out;
    }
    for (uint32_t i = 0; i < nc; i++) keys[i] = (combo_key){b, i};
    qsort(keys, nc, sizeof *keys, cmp_combo_key);
    for (uint32_t i = 0; i < nc; i++) {
        rank[keys[i].id] = i;
        sorted[i] = b->combos[keys[i].id];
    }
    memcpy(b->combos, sorted, nc * sizeof *sorted);
    for (uint64_t g = 0; g < ng; g++) {
        b->groups[g].combo = rank[b->groups[g].combo];
        b->combos[b->groups[g].combo].n++;
    }
    uint64_t at = 0;
    for (uint32_t i = 0; i < nc; i++) {
        b->combos[i].g_first = at;
        at += b->combos[i].n;
        b->combos[i].n = 0;
    }
    for (uint64_t g = 0; g < ng; g++) { /* stable: ascending target within a combination */
        combo *c = &b->combos[b->groups[g].combo];
        b->combo_groups[c->g_first + c->n++] = g;
    }
out:
    lbk_dealloc(b->a, keys);
    lbk_dealloc(b->a, rank);
    lbk_dealloc(b->a, sorted);
    return r;
}

/* ---- greedy grouping of candidate chunks into dispatches ---------------------------------- */

typedef struct caps {
    uint64_t targets, entries;
} caps;

/* Fills cluster_of[i] for every chunk; returns the cluster count or UINT32_MAX on OOM. Clusters
 * are numbered in creation order. */
static uint32_t greedy(builder *b, const chunk *ch, uint32_t n, caps cap, uint32_t *cluster_of)
{
    const uint32_t nsets = b->desc->set_count;
    uint32_t *growth = lbk_alloc(b->a, (n ? n : 1) * sizeof *growth);
    uint8_t *remaining = lbk_alloc(b->a, n ? n : 1);
    uint32_t *ready = lbk_alloc(b->a, (n ? n : 1) * sizeof *ready);
    uint8_t *in_union = lbk_calloc(b->a, nsets ? nsets : 1, 1);
    uint32_t *inv_off = lbk_calloc(b->a, (size_t)nsets + 1, sizeof *inv_off);
    uint32_t unions[LBK_DLS_MAX_CLUSTER_SETS];
    uint64_t memberships = 0;
    for (uint32_t i = 0; i < n; i++) memberships += b->combos[ch[i].combo].k;
    uint32_t *inv = lbk_alloc(b->a, (memberships ? memberships : 1) * sizeof *inv);
    uint32_t clusters = UINT32_MAX;
    if (!growth || !remaining || !ready || !in_union || !inv_off || !inv) goto out;

    /* Inverted index set → chunks. */
    for (uint32_t i = 0; i < n; i++) {
        const combo *c = &b->combos[ch[i].combo];
        const rec *r = group_recs(b, c->rep);
        for (uint32_t j = 0; j < c->k; j++) inv_off[r[j].set + 1]++;
    }
    for (uint32_t s = 0; s < nsets; s++) inv_off[s + 1] += inv_off[s];
    {
        uint32_t *fill = lbk_calloc(b->a, nsets ? nsets : 1, sizeof *fill);
        if (!fill) goto out;
        for (uint32_t i = 0; i < n; i++) {
            const combo *c = &b->combos[ch[i].combo];
            const rec *r = group_recs(b, c->rep);
            for (uint32_t j = 0; j < c->k; j++) inv[inv_off[r[j].set] + fill[r[j].set]++] = i;
        }
        lbk_dealloc(b->a, fill);
    }
    memset(remaining, 1, n);
    uint32_t left = n;
    clusters = 0;
    while (left) {
        uint32_t seed = UINT32_MAX;
        uint64_t best = 0;
        for (uint32_t i = 0; i < n; i++) {
            if (!remaining[i]) continue;
            uint64_t e = ch[i].count * b->combos[ch[i].combo].k;
            if (seed == UINT32_MAX || e > best) { seed = i; best = e; }
            growth[i] = b->combos[ch[i].combo].k;
        }
        uint32_t nunion = 0, head = 0, tail = 0;
        uint64_t targets = 0, entries = 0;
        uint32_t pick = seed;
        while (pick != UINT32_MAX) {
            /* add */
            const combo *c = &b->combos[ch[pick].combo];
            remaining[pick] = 0;
            left--;
            cluster_of[pick] = clusters;
            targets += ch[pick].count;
            entries += ch[pick].count * c->k;
            const rec *r = group_recs(b, c->rep);
            for (uint32_t j = 0; j < c->k; j++) {
                uint32_t s = r[j].set;
                if (in_union[s]) continue;
                in_union[s] = 1;
                unions[nunion++] = s;
                for (uint32_t q = inv_off[s]; q < inv_off[s + 1]; q++) {
                    uint32_t o = inv[q];
                    if (remaining[o] && --growth[o] == 0) ready[tail++] = o;
                }
            }
            /* next: a combination adding no set, else (while small) the one adding fewest */
            pick = UINT32_MAX;
            while (head < tail) {
                uint32_t o = ready[head++];
                if (remaining[o] && targets + ch[o].count <= cap.targets &&
                    entries + ch[o].count * b->combos[ch[o].combo].k <= cap.entries) {
                    pick = o;
                    break;
                }
            }
            if (pick == UINT32_MAX && targets < b->min_fill) {
                uint32_t best_growth = UINT32_MAX;
                for (uint32_t i = 0; i < n; i++) {
                    if (!remaining[i] || growth[i] >= best_growth) continue;
                    if (targets + ch[i].count > cap.targets ||
                        entries + ch[i].count * b->combos[ch[i].combo].k > cap.entries ||
                        nunion + growth[i] > LBK_DLS_MAX_CLUSTER_SETS)
                        continue;
                    pick = i;
                    best_growth = growth[i];
                    if (best_growth <= 1) break;
                }
            }
        }
        for (uint32_t j = 0; j < nunion; j++) in_union[unions[j]] = 0;
        clusters++;
    }
out:
    lbk_dealloc(b->a, growth);
    lbk_dealloc(b->a, remaining);
    lbk_dealloc(b->a, ready);
    lbk_dealloc(b->a, in_union);
    lbk_dealloc(b->a, inv_off);
    lbk_dealloc(b->a, inv);
    return clusters;
}

/* ---- emission ------------------------------------------------------------------------------- */

static void emit_runs(builder *b, const uint32_t *targets, uint64_t n, uint32_t *run_count)
{
    uint32_t count = 0;
    for (uint64_t i = 0; i < n;) {
        uint64_t j = i + 1;
        while (j < n && targets[j] == targets[j - 1] + 1) j++;
        vec_u32(&b->runs, targets[i]);
        vec_u32(&b->runs, (uint32_t)(j - i));
        count++;
        i = j;
    }
    *run_count = count;
}

static vec *entry_vec(builder *b) { return b->space == LBK_DLS_SPACE_TEXEL ? &b->texels : &b->probes; }

static void emit_entries_of_group(builder *b, uint64_t g)
{
    uint32_t psize = dls_payload_size(b->space);
    const rec *r = group_recs(b, g);
    for (uint32_t j = 0; j < b->groups[g].k; j++) vec_bytes(entry_vec(b), r[j].payload, psize);
}

typedef struct cluster_rec {
    uint32_t form, k, set_count, run_count, target_count, aux_count, entry_count;
    uint64_t nb; /* bases */
} cluster_rec;

static void emit_cluster_record(builder *b, const cluster_rec *c)
{
    uint8_t r[DLS_CLUSTER_SIZE] = {0};
    const dls_prefix_form *pf = dls_prefix(c->form);
    int stride = b->space == LBK_DLS_SPACE_TEXEL ? 0 : 1;
    lbk_wr32(r + DLS_C_FORM, c->form);
    lbk_wr32(r + DLS_C_SPACE, b->space);
    lbk_wr32(r + DLS_C_OVERLAPS, c->k);
    lbk_wr32(r + DLS_C_SET_FIRST, (uint32_t)b->tot_sets);
    lbk_wr32(r + DLS_C_SET_COUNT, c->set_count);
    lbk_wr32(r + DLS_C_RUN_FIRST, (uint32_t)b->tot_runs);
    lbk_wr32(r + DLS_C_RUN_COUNT, c->run_count);
    lbk_wr32(r + DLS_C_TARGET_COUNT, c->target_count);
    lbk_wr32(r + DLS_C_AUX_FIRST, c->form == LBK_DLS_FORM_PACKED ? (uint32_t)b->tot_subgroups : pf ? (uint32_t)b->tot_words : 0);
    lbk_wr32(r + DLS_C_AUX_COUNT, c->aux_count);
    lbk_wr32(r + DLS_C_BASE_FIRST, pf ? (uint32_t)(pf->base_bytes == 2 ? b->tot_base16 : b->tot_base32) : 0);
    lbk_wr32(r + DLS_C_ENTRY_COUNT, c->entry_count);
    lbk_wr64(r + DLS_C_ENTRY_FIRST, b->tot_entries[stride]);
    lbk_wr64(r + DLS_C_SLOT_FIRST, pf ? b->tot_slots : 0);
    vec_bytes(&b->clusters, r, sizeof r);
    b->tot_sets += c->set_count;
    b->tot_runs += c->run_count;
    if (c->form == LBK_DLS_FORM_PACKED) b->tot_subgroups += c->aux_count;
    if (pf) {
        b->tot_words += c->aux_count;
        if (pf->base_bytes == 2) b->tot_base16 += c->nb; else b->tot_base32 += c->nb;
        b->tot_slots += c->entry_count;
    }
    b->tot_entries[stride] += c->entry_count;
}

static uint32_t *chunk_targets(builder *b, const chunk *c)
{
    uint32_t *t = lbk_alloc(b->a, (c->count ? c->count : 1) * sizeof *t);
    if (!t) return NULL;
    const combo *co = &b->combos[c->combo];
    for (uint64_t i = 0; i < c->count; i++) t[i] = b->groups[b->combo_groups[co->g_first + c->first + i]].target;
    return t;
}

static void emit_dedicated(builder *b, const chunk *c)
{
    const combo *co = &b->combos[c->combo];
    uint32_t *t = chunk_targets(b, c);
    if (!t) { b->err = LBK_ERR_OUT_OF_MEMORY; return; }
    const rec *r = group_recs(b, co->rep);
    for (uint32_t j = 0; j < co->k; j++) vec_u32(&b->cluster_sets, r[j].set);
    cluster_rec cr = {LBK_DLS_FORM_DEDICATED, co->k, co->k, 0, (uint32_t)c->count, 0, (uint32_t)(c->count * co->k), 0};
    emit_runs(b, t, c->count, &cr.run_count);
    for (uint64_t i = 0; i < c->count; i++) emit_entries_of_group(b, b->combo_groups[co->g_first + c->first + i]);
    lbk_dealloc(b->a, t);
    emit_cluster_record(b, &cr);
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Sorted union of the sets of the chunks. */
static uint32_t chunk_union(builder *b, const chunk *ch, const uint32_t *members, uint32_t n, uint32_t *out)
{
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
        const combo *co = &b->combos[ch[members[i]].combo];
        const rec *r = group_recs(b, co->rep);
        for (uint32_t j = 0; j < co->k; j++) {
            uint32_t q = 0;
            while (q < m && out[q] != r[j].set) q++;
            if (q == m) out[m++] = r[j].set;
        }
    }
    qsort(out, m, sizeof *out, cmp_u32);
    return m;
}

static uint8_t slot_of(const uint32_t *list, uint32_t n, uint32_t set)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (list[mid] < set) lo = mid + 1; else hi = mid;
    }
    return (uint8_t)lo;
}

static void emit_packed(builder *b, const chunk *ch, const uint32_t *members, uint32_t n, uint32_t k)
{
    uint32_t list[LBK_DLS_MAX_CLUSTER_SETS];
    uint32_t m = chunk_union(b, ch, members, n, list);
    for (uint32_t j = 0; j < m; j++) vec_u32(&b->cluster_sets, list[j]);
    cluster_rec cr = {LBK_DLS_FORM_PACKED, k, m, 0, 0, n, 0, 0};
    uint64_t run_at = b->tot_runs;
    for (uint32_t i = 0; i < n; i++) {
        const chunk *c = &ch[members[i]];
        const combo *co = &b->combos[c->combo];
        uint32_t *t = chunk_targets(b, c);
        if (!t) { b->err = LBK_ERR_OUT_OF_MEMORY; return; }
        uint32_t rc;
        emit_runs(b, t, c->count, &rc);
        lbk_dealloc(b->a, t);
        uint8_t g[DLS_SUBGROUP_SIZE] = {0};
        lbk_wr32(g + DLS_G_RUN_FIRST, (uint32_t)run_at);
        lbk_wr32(g + DLS_G_RUN_COUNT, rc);
        lbk_wr32(g + DLS_G_TARGET_FIRST, cr.target_count);
        const rec *r = group_recs(b, co->rep);
        for (uint32_t j = 0; j < k; j++) g[DLS_G_SLOTS + j] = slot_of(list, m, r[j].set);
        vec_bytes(&b->subgroups, g, sizeof g);
        for (uint64_t q = 0; q < c->count; q++) emit_entries_of_group(b, b->combo_groups[co->g_first + c->first + q]);
        run_at += rc;
        cr.run_count += rc;
        cr.target_count += (uint32_t)c->count;
    }
    cr.entry_count = cr.target_count * k;
    emit_cluster_record(b, &cr);
}

typedef struct tg {
    uint32_t target;
    uint64_t group;
} tg;
static int cmp_tg(const void *a, const void *b)
{
    const tg *x = a, *y = b;
    return x->target < y->target ? -1 : x->target > y->target;
}

static void emit_prefix(builder *b, uint32_t form, const chunk *ch, const uint32_t *members, uint32_t n)
{
    const dls_prefix_form *pf = dls_prefix(form);
    uint32_t list[LBK_DLS_MAX_CLUSTER_SETS];
    uint32_t m = chunk_union(b, ch, members, n, list);
    for (uint32_t j = 0; j < m; j++) vec_u32(&b->cluster_sets, list[j]);
    uint64_t T = 0;
    for (uint32_t i = 0; i < n; i++) T += ch[members[i]].count;
    tg *all = lbk_alloc(b->a, (T ? T : 1) * sizeof *all);
    uint32_t *targets = lbk_alloc(b->a, (T ? T : 1) * sizeof *targets);
    if (!all || !targets) {
        lbk_dealloc(b->a, all);
        lbk_dealloc(b->a, targets);
        b->err = LBK_ERR_OUT_OF_MEMORY;
        return;
    }
    uint64_t at = 0;
    for (uint32_t i = 0; i < n; i++) {
        const chunk *c = &ch[members[i]];
        const combo *co = &b->combos[c->combo];
        for (uint64_t q = 0; q < c->count; q++) {
            uint64_t g = b->combo_groups[co->g_first + c->first + q];
            all[at++] = (tg){b->groups[g].target, g};
        }
    }
    qsort(all, T, sizeof *all, cmp_tg);
    for (uint64_t i = 0; i < T; i++) targets[i] = all[i].target;
    cluster_rec cr = {form, 0, m, 0, (uint32_t)T, 0, 0, 0};
    emit_runs(b, targets, T, &cr.run_count);
    /* prefix words, bases, slots, entries */
    uint32_t word = 0;
    uint64_t entries = 0;
    for (uint64_t i = 0; i < T; i++) {
        const group *g = &b->groups[all[i].group];
        if (i % pf->batch == 0) {
            if (pf->base_bytes == 2) vec_u16(&b->base16, (uint16_t)entries); else vec_u32(&b->base32, (uint32_t)entries);
            cr.nb++;
        }
        word |= (g->k - pf->bias) << (pf->bits * (uint32_t)(i % pf->per_word));
        if (i % pf->per_word == pf->per_word - 1 || i + 1 == T) {
            vec_u32(&b->words, word);
            cr.aux_count++;
            word = 0;
        }
        const rec *r = group_recs(b, all[i].group);
        for (uint32_t j = 0; j < g->k; j++) vec_u8(&b->slots, slot_of(list, m, r[j].set));
        emit_entries_of_group(b, all[i].group);
        entries += g->k;
    }
    cr.entry_count = (uint32_t)entries;
    lbk_dealloc(b->a, all);
    lbk_dealloc(b->a, targets);
    emit_cluster_record(b, &cr);
}

/* Groups chunks greedily and emits the clusters, members in canonical chunk order. */
static void emit_grouped(builder *b, uint32_t form, uint32_t k, const chunk *ch, uint32_t n, caps cap)
{
    if (!n || b->err) return;
    uint32_t *cluster_of = lbk_alloc(b->a, n * sizeof *cluster_of);
    uint32_t *order = lbk_alloc(b->a, n * sizeof *order);
    uint32_t *start = NULL;
    if (!cluster_of || !order) { b->err = LBK_ERR_OUT_OF_MEMORY; goto out; }
    uint32_t nc = greedy(b, ch, n, cap, cluster_of);
    if (nc == UINT32_MAX) { b->err = LBK_ERR_OUT_OF_MEMORY; goto out; }
    start = lbk_calloc(b->a, (size_t)nc + 1, sizeof *start);
    if (!start) { b->err = LBK_ERR_OUT_OF_MEMORY; goto out; }
    for (uint32_t i = 0; i < n; i++) start[cluster_of[i] + 1]++;
    for (uint32_t c = 0; c < nc; c++) start[c + 1] += start[c];
    {
        uint32_t *fill = lbk_calloc(b->a, nc ? nc : 1, sizeof *fill);
        if (!fill) { b->err = LBK_ERR_OUT_OF_MEMORY; goto out; }
        for (uint32_t i = 0; i < n; i++) order[start[cluster_of[i]] + fill[cluster_of[i]]++] = i;
        lbk_dealloc(b->a, fill);
    }
    for (uint32_t c = 0; c < nc && !b->err; c++) {
        if (form == LBK_DLS_FORM_PACKED) emit_packed(b, ch, order + start[c], start[c + 1] - start[c], k);
        else emit_prefix(b, form, ch, order + start[c], start[c + 1] - start[c]);
    }
out:
    lbk_dealloc(b->a, cluster_of);
    lbk_dealloc(b->a, order);
    lbk_dealloc(b->a, start);
}

/* Splits a combination into chunks of at most max_targets targets, appending to list. */
static uint32_t add_chunks(const combo *co, uint32_t id, uint64_t max_targets, chunk *list, uint32_t n)
{
    for (uint64_t f = 0; f < co->n; f += max_targets)
        list[n++] = (chunk){id, f, co->n - f < max_targets ? co->n - f : max_targets};
    return n;
}

static lbk_result build_space(builder *b)
{
    lbk_result r = find_combinations(b);
    if (r != LBK_OK) return r;
    uint32_t nc = b->ncombos;
    /* Worst case one chunk per target. */
    uint64_t maxch = b->ngroups + nc;
    chunk *lists[LBK_DLS_FORM_COUNT_ + 3] = {0}; /* dedicated, packed k=1..4, prefix2, prefix3, prefix8 */
    uint32_t counts[LBK_DLS_FORM_COUNT_ + 3] = {0};
    for (int i = 0; i < LBK_DLS_FORM_COUNT_ + 3; i++) {
        lists[i] = lbk_alloc(b->a, (maxch ? maxch : 1) * sizeof *lists[i]);
        if (!lists[i]) { r = LBK_ERR_OUT_OF_MEMORY; goto out; }
    }
    if (maxch > UINT32_MAX) { r = LBK_ERR_LIMIT; goto out; }
    enum { L_DED = 0, L_PACK1 = 1, L_P2 = 5, L_P3 = 6, L_P8 = 7 };
    for (uint32_t i = 0; i < nc; i++) {
        const combo *co = &b->combos[i];
        uint32_t k = co->k;
        if (k <= LBK_DLS_MAX_DEDICATED_SETS && co->n > LBK_DLS_SMALL_COMBINATION)
            counts[L_DED] = add_chunks(co, i, UINT32_MAX / k, lists[L_DED], counts[L_DED]);
        else if (k <= LBK_DLS_MAX_PACKED_SETS)
            counts[L_PACK1 + k - 1] = add_chunks(co, i, co->n, lists[L_PACK1 + k - 1], counts[L_PACK1 + k - 1]);
        else if (k <= 8)
            counts[L_P2] = add_chunks(co, i, LBK_DLS_PREFIX16_MAX_ENTRIES / k, lists[L_P2], counts[L_P2]);
        else if (k <= 16)
            counts[L_P3] = add_chunks(co, i, LBK_DLS_PREFIX16_MAX_ENTRIES / k, lists[L_P3], counts[L_P3]);
        else
            counts[L_P8] = add_chunks(co, i, UINT32_MAX / k, lists[L_P8], counts[L_P8]);
    }
    for (uint32_t i = 0; i < counts[L_DED] && !b->err; i++) emit_dedicated(b, &lists[L_DED][i]);
    for (uint32_t k = 1; k <= LBK_DLS_MAX_PACKED_SETS; k++)
        emit_grouped(b, LBK_DLS_FORM_PACKED, k, lists[L_PACK1 + k - 1], counts[L_PACK1 + k - 1],
                     (caps){b->packed_cap, UINT32_MAX});
    emit_grouped(b, LBK_DLS_FORM_PREFIX2, 0, lists[L_P2], counts[L_P2], (caps){UINT32_MAX, LBK_DLS_PREFIX16_MAX_ENTRIES});
    emit_grouped(b, LBK_DLS_FORM_PREFIX3, 0, lists[L_P3], counts[L_P3], (caps){UINT32_MAX, LBK_DLS_PREFIX16_MAX_ENTRIES});
    emit_grouped(b, LBK_DLS_FORM_PREFIX8, 0, lists[L_P8], counts[L_P8], (caps){UINT32_MAX, UINT32_MAX});
    r = b->err;
out:
    for (int i = 0; i < LBK_DLS_FORM_COUNT_ + 3; i++) lbk_dealloc(b->a, lists[i]);
    return r;
}

/* ---- input checks ---------------------------------------------------------------------------- */

static bool cstr_ok(const char *s)
{
    if (!s) return false;
    size_t n = strlen(s);
    return n > 0 && n < UINT32_MAX && lbk_dls_string_ok((const uint8_t *)s, n, 0, (uint32_t)n);
}

static int cmp_cstr(const void *a, const void *b) { return strcmp(*(const char *const *)a, *(const char *const *)b); }

static lbk_result check_desc(const lbk_dls_build_desc *d, const lbk_allocator *a)
{
    if (d->set_count && !d->sets) return LBK_ERR_INVALID_ARGUMENT;
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++)
        if (d->target_count[s] > (uint64_t)UINT32_MAX + 1) return LBK_ERR_RANGE;
    for (uint32_t i = 0; i < d->set_count; i++) {
        const lbk_dls_set_desc *s = &d->sets[i];
        if (!cstr_ok(s->name) || s->kind >= LBK_DLS_KIND_COUNT_) return LBK_ERR_INVALID_ARGUMENT;
        if (s->light_count && !s->light_names) return LBK_ERR_INVALID_ARGUMENT;
        for (uint32_t l = 0; l < s->light_count; l++)
            if (!cstr_ok(s->light_names[l])) return LBK_ERR_INVALID_ARGUMENT;
        if (s->kind == LBK_DLS_KIND_COMBINATION) {
            if (s->member_count < 2 || !s->members) return LBK_ERR_INVALID_ARGUMENT;
            for (uint32_t m = 0; m < s->member_count; m++) {
                uint32_t x = s->members[m];
                if (x >= d->set_count || x == i || d->sets[x].kind == LBK_DLS_KIND_COMBINATION) return LBK_ERR_INVALID_ARGUMENT;
                for (uint32_t q = 0; q < m; q++)
                    if (s->members[q] == x) return LBK_ERR_INVALID_ARGUMENT;
            }
        } else if (s->member_count) {
            return LBK_ERR_INVALID_ARGUMENT;
        }
        for (int sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) {
            const lbk_dls_sparse *e = &s->entries[sp];
            if (e->count && (!e->targets || !e->payloads)) return LBK_ERR_INVALID_ARGUMENT;
            for (uint64_t q = 0; q < e->count; q++)
                if (e->targets[q] >= d->target_count[sp]) return LBK_ERR_RANGE;
            if (sp == LBK_DLS_SPACE_TEXEL) /* R11G11B10F exponent 31 (Inf/NaN) is invalid in files */
                for (uint64_t q = 0; q < e->count; q++) {
                    uint32_t v = lbk_rd32((const uint8_t *)e->payloads + q * LBK_DLS_TEXEL_PAYLOAD);
                    if (((v >> 6) & 31) == 31 || ((v >> 17) & 31) == 31 || ((v >> 27) & 31) == 31)
                        return LBK_ERR_INVALID_ARGUMENT;
                }
        }
    }
    /* Unique names. */
    const char **names = lbk_alloc(a, (d->set_count ? d->set_count : 1) * sizeof *names);
    if (!names) return LBK_ERR_OUT_OF_MEMORY;
    for (uint32_t i = 0; i < d->set_count; i++) names[i] = d->sets[i].name;
    qsort(names, d->set_count, sizeof *names, cmp_cstr);
    lbk_result r = LBK_OK;
    for (uint32_t i = 1; i < d->set_count; i++)
        if (strcmp(names[i], names[i - 1]) == 0) r = LBK_ERR_INVALID_ARGUMENT;
    lbk_dealloc(a, names);
    return r;
}

/* ---- assembly -------------------------------------------------------------------------------- */

static void put_array(uint8_t *out, const dls_layout *L, int a, const vec *v)
{
    if (v->len) memcpy(out + L->offset[a], v->p, v->len);
}

/* The set table's arrays: set records, light references, combination members, names. */
typedef struct set_table {
    vec sets, lrefs, members, strings;
} set_table;

/* Every target space's clusters (build_space) from the sets' entries of that space. */
static lbk_result build_spaces(builder *b)
{
    const lbk_dls_build_desc *desc = b->desc;
    const lbk_allocator *a = b->a;
    lbk_result r = LBK_OK;
    for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_ && r == LBK_OK; sp++) {
        b->space = sp;
        uint64_t n = 0;
        for (uint32_t s = 0; s < desc->set_count; s++) n += desc->sets[s].entries[sp].count;
        if (n == 0) continue;
        if (n > SIZE_MAX / sizeof(rec)) { r = LBK_ERR_LIMIT; break; }
        b->recs = lbk_alloc(a, n * sizeof *b->recs);
        if (!b->recs) { r = LBK_ERR_OUT_OF_MEMORY; break; }
        uint32_t psize = dls_payload_size(sp);
        b->nrecs = 0;
        for (uint32_t s = 0; s < desc->set_count; s++) {
            const lbk_dls_sparse *e = &desc->sets[s].entries[sp];
            for (uint64_t q = 0; q < e->count; q++)
                b->recs[b->nrecs++] = (rec){e->targets[q], s, (const uint8_t *)e->payloads + q * psize};
        }
        r = build_space(b);
        lbk_dealloc(a, b->recs);
        lbk_dealloc(a, b->groups);
        lbk_dealloc(a, b->combos);
        lbk_dealloc(a, b->combo_groups);
        b->recs = NULL; b->groups = NULL; b->combos = NULL; b->combo_groups = NULL;
    }
    return r;
}

/* Set table and strings. */
static lbk_result build_set_table(const lbk_dls_build_desc *desc, const lbk_allocator *a, set_table *t)
{
    for (uint32_t s = 0; s < desc->set_count; s++) {
        const lbk_dls_set_desc *sd = &desc->sets[s];
        uint8_t rec_[DLS_SET_SIZE] = {0};
        size_t nl = strlen(sd->name);
        lbk_wr32(rec_ + DLS_S_NAME_OFF, (uint32_t)t->strings.len);
        lbk_wr32(rec_ + DLS_S_NAME_LEN, (uint32_t)nl);
        vec_bytes(&t->strings, sd->name, nl);
        lbk_wr32(rec_ + DLS_S_KIND, sd->kind);
        lbk_wr32(rec_ + DLS_S_LIGHT_FIRST, (uint32_t)(t->lrefs.len / DLS_LIGHT_REF_SIZE));
        lbk_wr32(rec_ + DLS_S_LIGHT_COUNT, sd->light_count);
        lbk_wr32(rec_ + DLS_S_MEMBER_FIRST, (uint32_t)(t->members.len / 4));
        lbk_wr32(rec_ + DLS_S_MEMBER_COUNT, sd->kind == LBK_DLS_KIND_COMBINATION ? sd->member_count : 0);
        vec_bytes(&t->sets, rec_, sizeof rec_);
        for (uint32_t l = 0; l < sd->light_count; l++) {
            size_t ll = strlen(sd->light_names[l]);
            vec_u32(&t->lrefs, (uint32_t)t->strings.len);
            vec_u32(&t->lrefs, (uint32_t)ll);
            vec_bytes(&t->strings, sd->light_names[l], ll);
        }
        if (sd->kind == LBK_DLS_KIND_COMBINATION) {
            uint32_t sorted[LBK_DLS_MAX_OVERLAPS];
            uint32_t *m = sd->member_count <= LBK_DLS_MAX_OVERLAPS ? sorted : lbk_alloc(a, sd->member_count * sizeof *m);
            if (!m) return LBK_ERR_OUT_OF_MEMORY;
            memcpy(m, sd->members, sd->member_count * sizeof *m);
            qsort(m, sd->member_count, sizeof *m, cmp_u32);
            for (uint32_t q = 0; q < sd->member_count; q++) vec_u32(&t->members, m[q]);
            if (m != sorted) lbk_dealloc(a, m);
        }
    }
    return LBK_OK;
}

/* The section's bytes: the layout of every array, the header, then the arrays in place. */
static lbk_result assemble(const builder *b, const set_table *t, uint8_t **bytes, dls_layout *L)
{
    const lbk_dls_build_desc *desc = b->desc;
    L->count[DLS_A_SETS] = desc->set_count;
    L->count[DLS_A_LIGHT_REFS] = t->lrefs.len / DLS_LIGHT_REF_SIZE;
    L->count[DLS_A_MEMBERS] = t->members.len / 4;
    L->count[DLS_A_CLUSTERS] = b->clusters.len / DLS_CLUSTER_SIZE;
    L->count[DLS_A_CLUSTER_SETS] = b->tot_sets;
    L->count[DLS_A_RUNS] = b->tot_runs;
    L->count[DLS_A_SUBGROUPS] = b->tot_subgroups;
    L->count[DLS_A_PREFIX_WORDS] = b->tot_words;
    L->count[DLS_A_BASE16] = b->tot_base16;
    L->count[DLS_A_BASE32] = b->tot_base32;
    L->count[DLS_A_SLOTS] = b->tot_slots;
    L->count[DLS_A_TEXEL_ENTRIES] = b->tot_entries[0];
    L->count[DLS_A_PROBE_ENTRIES] = b->tot_entries[1];
    L->count[DLS_A_STRINGS] = t->strings.len;
    if (!dls_layout_compute(L) || L->size > SIZE_MAX) return LBK_ERR_LIMIT;
    uint8_t *out = *bytes = lbk_calloc(b->a, 1, (size_t)L->size);
    if (!out) return LBK_ERR_OUT_OF_MEMORY;
    static const int hdr_u32[] = {DLS_H_SET_COUNT, DLS_H_LIGHT_REF_COUNT, DLS_H_MEMBER_COUNT, DLS_H_CLUSTER_COUNT,
                                  DLS_H_CLUSTER_SET_COUNT, DLS_H_RUN_COUNT, DLS_H_SUBGROUP_COUNT,
                                  DLS_H_PREFIX_WORD_COUNT, DLS_H_BASE16_COUNT, DLS_H_BASE32_COUNT};
    for (int i = 0; i < 10; i++) lbk_wr32(out + hdr_u32[i], (uint32_t)L->count[i]);
    lbk_wr64(out + DLS_H_SLOT_COUNT, L->count[DLS_A_SLOTS]);
    lbk_wr64(out + DLS_H_TEXEL_ENTRY_COUNT, L->count[DLS_A_TEXEL_ENTRIES]);
    lbk_wr64(out + DLS_H_PROBE_ENTRY_COUNT, L->count[DLS_A_PROBE_ENTRIES]);
    lbk_wr64(out + DLS_H_STRING_BYTES, L->count[DLS_A_STRINGS]);
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) lbk_wr64(out + DLS_H_TARGET_COUNT + 8 * s, desc->target_count[s]);
    put_array(out, L, DLS_A_SETS, &t->sets);
    put_array(out, L, DLS_A_LIGHT_REFS, &t->lrefs);
    put_array(out, L, DLS_A_MEMBERS, &t->members);
    put_array(out, L, DLS_A_CLUSTERS, &b->clusters);
    put_array(out, L, DLS_A_CLUSTER_SETS, &b->cluster_sets);
    put_array(out, L, DLS_A_RUNS, &b->runs);
    put_array(out, L, DLS_A_SUBGROUPS, &b->subgroups);
    put_array(out, L, DLS_A_PREFIX_WORDS, &b->words);
    put_array(out, L, DLS_A_BASE16, &b->base16);
    put_array(out, L, DLS_A_BASE32, &b->base32);
    put_array(out, L, DLS_A_SLOTS, &b->slots);
    put_array(out, L, DLS_A_TEXEL_ENTRIES, &b->texels);
    put_array(out, L, DLS_A_PROBE_ENTRIES, &b->probes);
    put_array(out, L, DLS_A_STRINGS, &t->strings);
    return LBK_OK;
}

lbk_result lbk_dls_build(const lbk_dls_build_desc *caller_desc, const lbk_dls_build_options *caller_options,
                         void **out, size_t *out_size, lbk_dls_stats *stats)
{
    if (!caller_desc || !out || !out_size) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *out_size = 0;
    lbk_dls_build_desc in;
    lbk_dls_build_options options;
    lbk_result r = LBK_SIZED_IN(&in, caller_desc, lbk_dls_build_desc, target_count);
    if (r == LBK_OK) r = LBK_SIZED_IN(&options, caller_options, lbk_dls_build_options, tuning);
    if (r != LBK_OK) return r;
    const lbk_dls_build_desc *desc = &in;
    const lbk_dls_tuning tuning = options.tuning ? *options.tuning : (lbk_dls_tuning){0};
    const lbk_allocator *a = options.allocator;
    r = check_desc(desc, a);
    if (r != LBK_OK) return r;

    builder b;
    memset(&b, 0, sizeof b);
    b.a = a;
    b.desc = desc;
    b.min_fill = tuning.min_dispatch_targets ? tuning.min_dispatch_targets : 256;
    b.packed_cap = tuning.packed_max_targets ? tuning.packed_max_targets : 4096;
    vec *vs[] = {&b.clusters, &b.cluster_sets, &b.runs, &b.subgroups, &b.words, &b.base16, &b.base32, &b.slots, &b.texels, &b.probes};
    for (size_t i = 0; i < sizeof vs / sizeof vs[0]; i++) vs[i]->a = a;
    set_table t = {.sets = {.a = a}, .lrefs = {.a = a}, .members = {.a = a}, .strings = {.a = a}};

    r = build_spaces(&b);
    if (r == LBK_OK) r = build_set_table(desc, a, &t);
    if (t.strings.len > UINT32_MAX) r = LBK_ERR_LIMIT;
    for (size_t i = 0; i < sizeof vs / sizeof vs[0]; i++)
        if (vs[i]->oom) r = LBK_ERR_OUT_OF_MEMORY;
    if (t.sets.oom || t.lrefs.oom || t.members.oom || t.strings.oom) r = LBK_ERR_OUT_OF_MEMORY;
    if (r == LBK_OK && (b.tot_runs > UINT32_MAX || b.tot_sets > UINT32_MAX || b.tot_words > UINT32_MAX ||
                        b.tot_base16 > UINT32_MAX || b.tot_base32 > UINT32_MAX || b.tot_subgroups > UINT32_MAX ||
                        b.clusters.len / DLS_CLUSTER_SIZE > UINT32_MAX))
        r = LBK_ERR_LIMIT;

    uint8_t *bytes = NULL;
    dls_layout L;
    memset(&L, 0, sizeof L);
    if (r == LBK_OK) r = assemble(&b, &t, &bytes, &L);
    for (size_t i = 0; i < sizeof vs / sizeof vs[0]; i++) vec_free(vs[i]);
    vec_free(&t.sets);
    vec_free(&t.lrefs);
    vec_free(&t.members);
    vec_free(&t.strings);
    if (r != LBK_OK) {
        lbk_dealloc(a, bytes);
        return r;
    }

    /* Self-check: the output must pass the section's own rules (and gives the statistics). */
    lbk_dls_view *v;
    r = lbk_dls_open(bytes, (size_t)L.size, a, &v);
    if (r != LBK_OK) {
        lbk_dealloc(a, bytes);
        return LBK_ERR_CORRUPT;
    }
    if (stats) lbk_dls_stats_get(v, stats);
    lbk_dls_close(v);
    *out = bytes;
    *out_size = (size_t)L.size;
    return LBK_OK;
}
