/* Reference runtime for dynamic light sets: L = L_B + Σ_j w_j S_j, one cluster (dispatch) at a
 * time, each target written exactly once per full apply. spec/container.md §12.8. */
#include <math.h>
#include <stdlib.h>

#include "dls_format.h"
#include "lbk/ahd.h"
#include "lbk/door.h"
#include "lbk/sh.h"

typedef struct rt_cluster {
    uint32_t form, space, k, nsets, run_count, subgroup_count, target_count;
    const uint8_t *sets, *runs, *subgroups, *words, *bases, *slots, *payload;
} rt_cluster;

struct lbk_dls_runtime {
    lbk_allocator alloc_copy;
    const lbk_allocator *alloc;
    lbk_dls_runtime_desc desc;
    lbk_dls_raw raw;
    uint32_t nsets, ndoors;
    uint8_t *kinds;
    uint32_t *member_offset, *members;
    uint32_t *door_of_set;   /* kind 1/2 sets named by a door: the door; else LBK_DLS_NO_SET */
    uint32_t ncl;
    rt_cluster *cl;
    uint32_t *gaps[LBK_DLS_SPACE_COUNT_]; /* (start, length) pairs of targets in no cluster */
    uint64_t ngaps[LBK_DLS_SPACE_COUNT_];
    bool space_on[LBK_DLS_SPACE_COUNT_];
    float *w, *last;
    uint8_t *changed;
    int valid; /* the outputs hold the result of the weights in `last` */
};

/* ---- per-target kernels ---------------------------------------------------------------------- */

#define FORCE_INLINE static inline __attribute__((always_inline))

FORCE_INLINE void texel_load_linear(uint32_t z, const uint8_t *rgba, lbk_ahd_linear *out)
{
    lbk_ahd_texel t;
    t.irradiance_z = z;
    memcpy(t.rgba, rgba, 4);
    lbk_ahd_to_linear(&t, out);
}

FORCE_INLINE void texel_add_entry(lbk_ahd_linear *acc, const uint8_t *e, float w)
{
    lbk_ahd_linear l;
    texel_load_linear(lbk_rd32(e), e + 4, &l);
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) acc->c[c][i] += w * l.c[c][i];
}

FORCE_INLINE void texel_store(const lbk_dls_runtime *r, uint32_t t, const lbk_ahd_linear *acc)
{
    lbk_ahd_texel o;
    lbk_ahd_from_linear(acc, &o);
    r->desc.out_irradiance_z[t] = o.irradiance_z;
    memcpy(r->desc.out_rgba + 4 * (size_t)t, o.rgba, 4);
}

FORCE_INLINE void probe_add_entry(lbk_sh9_rgb *acc, const uint8_t *e, float w)
{
    lbk_sh9_rgb l;
    lbk_sh9_unpack(e, &l);
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < LBK_SH9_COUNT; i++) acc->c[c][i] += w * l.c[c][i];
}

static const uint8_t *base_probes(const lbk_dls_runtime *r, uint32_t space)
{
    return space == LBK_DLS_SPACE_GLG ? r->desc.base_glg : r->desc.base_llg;
}
static uint8_t *out_probes(const lbk_dls_runtime *r, uint32_t space)
{
    return space == LBK_DLS_SPACE_GLG ? r->desc.out_glg : r->desc.out_llg;
}

static void copy_base(const lbk_dls_runtime *r, uint32_t space, uint32_t start, uint32_t len)
{
    if (space == LBK_DLS_SPACE_TEXEL) {
        memcpy(r->desc.out_irradiance_z + start, r->desc.base_irradiance_z + start, (size_t)len * 4);
        memcpy(r->desc.out_rgba + 4 * (size_t)start, r->desc.base_rgba + 4 * (size_t)start, (size_t)len * 4);
    } else {
        memcpy(out_probes(r, space) + LBK_DLS_PROBE_PAYLOAD * (size_t)start,
               base_probes(r, space) + LBK_DLS_PROBE_PAYLOAD * (size_t)start, (size_t)len * LBK_DLS_PROBE_PAYLOAD);
    }
}

/* A list of runs whose targets each carry `stride` entries, of which the M at idx[] have
 * non-zero weights wa[]. M is a compile-time constant in the specialised instances. */
FORCE_INLINE void texels_fixed(const lbk_dls_runtime *r, const uint8_t *runs, uint32_t nruns, const uint8_t *payload,
                               uint32_t stride, const uint32_t M, const uint32_t *idx, const float *wa)
{
    const uint32_t *bz = r->desc.base_irradiance_z;
    const uint8_t *brgba = r->desc.base_rgba;
    for (uint32_t i = 0; i < nruns; i++) {
        uint32_t start = lbk_rd32(runs + DLS_RUN_SIZE * i), len = lbk_rd32(runs + DLS_RUN_SIZE * i + 4);
        for (uint32_t t = start; t < start + len; t++, payload += (size_t)stride * LBK_DLS_TEXEL_PAYLOAD) {
            lbk_ahd_linear acc;
            texel_load_linear(bz[t], brgba + 4 * (size_t)t, &acc);
            for (uint32_t j = 0; j < M; j++) texel_add_entry(&acc, payload + (size_t)idx[j] * LBK_DLS_TEXEL_PAYLOAD, wa[j]);
            texel_store(r, t, &acc);
        }
    }
}

FORCE_INLINE void probes_fixed(const lbk_dls_runtime *r, uint32_t space, const uint8_t *runs, uint32_t nruns,
                               const uint8_t *payload, uint32_t stride, const uint32_t M, const uint32_t *idx,
                               const float *wa)
{
    const uint8_t *base = base_probes(r, space);
    uint8_t *out = out_probes(r, space);
    for (uint32_t i = 0; i < nruns; i++) {
        uint32_t start = lbk_rd32(runs + DLS_RUN_SIZE * i), len = lbk_rd32(runs + DLS_RUN_SIZE * i + 4);
        for (uint32_t t = start; t < start + len; t++, payload += (size_t)stride * LBK_DLS_PROBE_PAYLOAD) {
            lbk_sh9_rgb acc;
            lbk_sh9_unpack(base + LBK_DLS_PROBE_PAYLOAD * (size_t)t, &acc);
            for (uint32_t j = 0; j < M; j++) probe_add_entry(&acc, payload + (size_t)idx[j] * LBK_DLS_PROBE_PAYLOAD, wa[j]);
            lbk_sh9_pack(&acc, out + LBK_DLS_PROBE_PAYLOAD * (size_t)t);
        }
    }
}

/* Specialised instances for 1–8 active sets, a general loop beyond. */
static void apply_fixed(const lbk_dls_runtime *r, uint32_t space, const uint8_t *runs, uint32_t nruns,
                        const uint8_t *payload, uint32_t stride, uint32_t m, const uint32_t *idx, const float *wa)
{
#define CASE(M)                                                                          \
    case M:                                                                              \
        if (space == LBK_DLS_SPACE_TEXEL) texels_fixed(r, runs, nruns, payload, stride, M, idx, wa); \
        else probes_fixed(r, space, runs, nruns, payload, stride, M, idx, wa);           \
        return;
    switch (m) {
        CASE(1) CASE(2) CASE(3) CASE(4) CASE(5) CASE(6) CASE(7) CASE(8)
    default:
        if (space == LBK_DLS_SPACE_TEXEL) texels_fixed(r, runs, nruns, payload, stride, m, idx, wa);
        else probes_fixed(r, space, runs, nruns, payload, stride, m, idx, wa);
    }
#undef CASE
}

/* Prefix forms: per target n = field + bias entries; the entries of the targets of batch b
 * start at base[b] (relative to the cluster), which is what lets a GPU thread find its entries. */
static void apply_prefix(const lbk_dls_runtime *r, const rt_cluster *c, const float *wl)
{
    const dls_prefix_form *pf = dls_prefix(c->form);
    const uint32_t psize = dls_payload_size(c->space);
    uint64_t ordinal = 0, off = 0;
    for (uint32_t i = 0; i < c->run_count; i++) {
        uint32_t start = lbk_rd32(c->runs + DLS_RUN_SIZE * i), len = lbk_rd32(c->runs + DLS_RUN_SIZE * i + 4);
        for (uint32_t t = start; t < start + len; t++, ordinal++) {
            if (ordinal % pf->batch == 0)
                off = pf->base_bytes == 2 ? lbk_rd16(c->bases + 2 * (ordinal / pf->batch))
                                          : lbk_rd32(c->bases + 4 * (ordinal / pf->batch));
            uint32_t n = dls_prefix_field(c->words, pf, ordinal) + pf->bias;
            const uint8_t *slots = c->slots + off;
            const uint8_t *e = c->payload + off * psize;
            bool active = false;
            for (uint32_t j = 0; j < n; j++) active |= wl[slots[j]] != 0.0f;
            if (!active) {
                copy_base(r, c->space, t, 1); /* exactly the base, as for an all-zero dispatch */
            } else if (c->space == LBK_DLS_SPACE_TEXEL) {
                lbk_ahd_linear acc;
                texel_load_linear(r->desc.base_irradiance_z[t], r->desc.base_rgba + 4 * (size_t)t, &acc);
                for (uint32_t j = 0; j < n; j++)
                    if (wl[slots[j]] != 0.0f) texel_add_entry(&acc, e + (size_t)j * psize, wl[slots[j]]);
                texel_store(r, t, &acc);
            } else {
                lbk_sh9_rgb acc;
                lbk_sh9_unpack(base_probes(r, c->space) + LBK_DLS_PROBE_PAYLOAD * (size_t)t, &acc);
                for (uint32_t j = 0; j < n; j++)
                    if (wl[slots[j]] != 0.0f) probe_add_entry(&acc, e + (size_t)j * psize, wl[slots[j]]);
                lbk_sh9_pack(&acc, out_probes(r, c->space) + LBK_DLS_PROBE_PAYLOAD * (size_t)t);
            }
            off += n;
        }
    }
}

/* ---- cluster dispatch ------------------------------------------------------------------------ */

static void copy_runs(const lbk_dls_runtime *r, uint32_t space, const uint8_t *runs, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) copy_base(r, space, lbk_rd32(runs + DLS_RUN_SIZE * i), lbk_rd32(runs + DLS_RUN_SIZE * i + 4));
}

static void apply_cluster(const lbk_dls_runtime *r, const rt_cluster *c, const float *wl)
{
    uint32_t idx[LBK_DLS_MAX_CLUSTER_SETS];
    float wa[LBK_DLS_MAX_CLUSTER_SETS];
    if (c->form == LBK_DLS_FORM_DEDICATED) {
        uint32_t m = 0;
        for (uint32_t j = 0; j < c->k; j++)
            if (wl[j] != 0.0f) { idx[m] = j; wa[m++] = wl[j]; }
        apply_fixed(r, c->space, c->runs, c->run_count, c->payload, c->k, m, idx, wa);
    } else if (c->form == LBK_DLS_FORM_PACKED) {
        const uint32_t psize = dls_payload_size(c->space);
        const uint8_t *payload = c->payload;
        for (uint32_t g = 0; g < c->subgroup_count; g++) {
            const uint8_t *gr = c->subgroups + DLS_SUBGROUP_SIZE * g;
            const uint8_t *runs = r->raw.d + r->raw.offset[DLS_A_RUNS] + (uint64_t)lbk_rd32(gr + DLS_G_RUN_FIRST) * DLS_RUN_SIZE;
            uint32_t nruns = lbk_rd32(gr + DLS_G_RUN_COUNT);
            uint32_t m = 0;
            for (uint32_t j = 0; j < c->k; j++) {
                float w = wl[gr[DLS_G_SLOTS + j]];
                if (w != 0.0f) { idx[m] = j; wa[m++] = w; }
            }
            if (m == 0) copy_runs(r, c->space, runs, nruns);
            else apply_fixed(r, c->space, runs, nruns, payload, c->k, m, idx, wa);
            uint32_t targets = 0;
            for (uint32_t i = 0; i < nruns; i++) targets += lbk_rd32(runs + DLS_RUN_SIZE * i + 4);
            payload += (size_t)targets * c->k * psize;
        }
    } else {
        apply_prefix(r, c, wl);
    }
}

/* ---- creation -------------------------------------------------------------------------------- */

static int cmp_run(const void *a, const void *b)
{
    uint32_t x = ((const uint32_t *)a)[0], y = ((const uint32_t *)b)[0];
    return x < y ? -1 : x > y;
}

static lbk_result make_gaps(lbk_dls_runtime *r)
{
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        uint64_t n = 0;
        for (uint32_t i = 0; i < r->ncl; i++)
            if (r->cl[i].space == s) n += r->cl[i].run_count;
        uint32_t *runs = lbk_alloc(r->alloc, (n ? n : 1) * 8);
        r->gaps[s] = lbk_alloc(r->alloc, (n + 1) * 8);
        if (!runs || !r->gaps[s]) {
            lbk_dealloc(r->alloc, runs);
            return LBK_ERR_OUT_OF_MEMORY;
        }
        uint64_t at = 0;
        for (uint32_t i = 0; i < r->ncl; i++) {
            if (r->cl[i].space != s) continue;
            for (uint32_t q = 0; q < r->cl[i].run_count; q++) {
                runs[2 * at] = lbk_rd32(r->cl[i].runs + DLS_RUN_SIZE * q);
                runs[2 * at + 1] = lbk_rd32(r->cl[i].runs + DLS_RUN_SIZE * q + 4);
                at++;
            }
        }
        qsort(runs, n, 8, cmp_run);
        uint64_t next = 0, ng = 0, total = r->raw.target_count[s];
        for (uint64_t i = 0; i <= n; i++) {
            uint64_t start = i < n ? runs[2 * i] : total;
            if (start > next) {
                r->gaps[s][2 * ng] = (uint32_t)next;
                r->gaps[s][2 * ng + 1] = (uint32_t)(start - next);
                ng++;
            }
            if (i < n) next = (uint64_t)runs[2 * i] + runs[2 * i + 1];
        }
        r->ngaps[s] = ng;
        lbk_dealloc(r->alloc, runs);
    }
    return LBK_OK;
}

void lbk_dls_runtime_close(lbk_dls_runtime *r)
{
    if (!r) return;
    const lbk_allocator *a = r->alloc;
    lbk_dealloc(a, r->kinds);
    lbk_dealloc(a, r->member_offset);
    lbk_dealloc(a, r->members);
    lbk_dealloc(a, r->door_of_set);
    lbk_dealloc(a, r->cl);
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) lbk_dealloc(a, r->gaps[s]);
    lbk_dealloc(a, r->w);
    lbk_dealloc(a, r->last);
    lbk_dealloc(a, r->changed);
    lbk_dealloc(a, r);
}

lbk_result lbk_dls_runtime_open(const lbk_dls_runtime_desc *caller_desc, lbk_dls_runtime **out)
{
    if (!caller_desc || !out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    lbk_dls_runtime_desc in;
    lbk_result rc = LBK_SIZED_IN(&in, caller_desc, lbk_dls_runtime_desc, allocator);
    if (rc != LBK_OK) return rc;
    const lbk_dls_runtime_desc *desc = &in;
    if (!desc->dls) return LBK_ERR_INVALID_ARGUMENT;
    if (desc->doors) {
        lbk_result cr = lbk_door_check_dls(desc->doors, desc->dls);
        if (cr != LBK_OK) return cr;
    }
    lbk_dls_runtime *r = lbk_calloc(desc->allocator, 1, sizeof *r);
    if (!r) return LBK_ERR_OUT_OF_MEMORY;
    if (desc->allocator) r->alloc_copy = *desc->allocator;
    r->alloc = desc->allocator ? &r->alloc_copy : NULL;
    r->desc = *desc;
    lbk_dls_view_raw(desc->dls, &r->raw);
    const lbk_dls_raw *raw = &r->raw;
    r->nsets = lbk_dls_set_count(desc->dls);
    r->ndoors = desc->doors ? lbk_door_count(desc->doors) : 0;
    r->ncl = lbk_dls_cluster_count(desc->dls);
    const lbk_allocator *a = r->alloc;
    size_t ns = r->nsets ? r->nsets : 1;
    r->kinds = lbk_alloc(a, ns);
    r->member_offset = lbk_alloc(a, (ns + 1) * sizeof *r->member_offset);
    r->members = lbk_alloc(a, (raw->count[DLS_A_MEMBERS] ? raw->count[DLS_A_MEMBERS] : 1) * sizeof *r->members);
    r->door_of_set = lbk_alloc(a, ns * sizeof *r->door_of_set);
    r->cl = lbk_calloc(a, r->ncl ? r->ncl : 1, sizeof *r->cl);
    r->w = lbk_calloc(a, ns, sizeof *r->w);
    r->last = lbk_calloc(a, ns, sizeof *r->last);
    r->changed = lbk_calloc(a, ns, 1);
    lbk_result res = LBK_OK;
    if (!r->kinds || !r->member_offset || !r->members || !r->door_of_set || !r->cl || !r->w || !r->last || !r->changed) {
        res = LBK_ERR_OUT_OF_MEMORY;
        goto fail;
    }
    uint32_t at = 0;
    for (uint32_t s = 0; s < r->nsets; s++) {
        lbk_dls_set_info info;
        lbk_dls_set_get(desc->dls, s, &info);
        r->kinds[s] = (uint8_t)info.kind;
        r->member_offset[s] = at;
        for (uint32_t j = 0; j < info.member_count; j++) lbk_dls_set_member_get(desc->dls, s, j, &r->members[at++]);
        r->door_of_set[s] = LBK_DLS_NO_SET;
    }
    r->member_offset[r->nsets] = at;
    for (uint32_t p = 0; p < r->ndoors; p++) {
        lbk_door_info di;
        lbk_door_get(desc->doors, p, &di);
        r->door_of_set[di.open_set] = p;
        if (di.closed_set != LBK_DLS_NO_SET) r->door_of_set[di.closed_set] = p;
    }
    for (uint32_t i = 0; i < r->ncl; i++) {
        const uint8_t *cr = raw->d + raw->offset[DLS_A_CLUSTERS] + (uint64_t)i * DLS_CLUSTER_SIZE;
        rt_cluster *c = &r->cl[i];
        c->form = lbk_rd32(cr + DLS_C_FORM);
        c->space = lbk_rd32(cr + DLS_C_SPACE);
        c->k = lbk_rd32(cr + DLS_C_OVERLAPS);
        c->nsets = lbk_rd32(cr + DLS_C_SET_COUNT);
        c->run_count = lbk_rd32(cr + DLS_C_RUN_COUNT);
        c->target_count = lbk_rd32(cr + DLS_C_TARGET_COUNT);
        c->sets = raw->d + raw->offset[DLS_A_CLUSTER_SETS] + 4ull * lbk_rd32(cr + DLS_C_SET_FIRST);
        c->runs = raw->d + raw->offset[DLS_A_RUNS] + (uint64_t)DLS_RUN_SIZE * lbk_rd32(cr + DLS_C_RUN_FIRST);
        c->payload = raw->d + raw->offset[c->space == LBK_DLS_SPACE_TEXEL ? DLS_A_TEXEL_ENTRIES : DLS_A_PROBE_ENTRIES] +
                     dls_payload_size(c->space) * lbk_rd64(cr + DLS_C_ENTRY_FIRST);
        const dls_prefix_form *pf = dls_prefix(c->form);
        if (c->form == LBK_DLS_FORM_PACKED) {
            c->subgroup_count = lbk_rd32(cr + DLS_C_AUX_COUNT);
            c->subgroups = raw->d + raw->offset[DLS_A_SUBGROUPS] + (uint64_t)DLS_SUBGROUP_SIZE * lbk_rd32(cr + DLS_C_AUX_FIRST);
        } else if (pf) {
            c->words = raw->d + raw->offset[DLS_A_PREFIX_WORDS] + 4ull * lbk_rd32(cr + DLS_C_AUX_FIRST);
            c->bases = raw->d + raw->offset[pf->base_bytes == 2 ? DLS_A_BASE16 : DLS_A_BASE32] +
                       (uint64_t)pf->base_bytes * lbk_rd32(cr + DLS_C_BASE_FIRST);
            c->slots = raw->d + raw->offset[DLS_A_SLOTS] + lbk_rd64(cr + DLS_C_SLOT_FIRST);
        }
    }
    /* A space is written when its buffers are given; a space with clusters needs them. */
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        bool have = s == LBK_DLS_SPACE_TEXEL ? desc->base_irradiance_z && desc->base_rgba && desc->out_irradiance_z && desc->out_rgba
                    : s == LBK_DLS_SPACE_GLG ? desc->base_glg && desc->out_glg
                                             : desc->base_llg && desc->out_llg;
        bool partial = s == LBK_DLS_SPACE_TEXEL ? (desc->base_irradiance_z || desc->base_rgba || desc->out_irradiance_z || desc->out_rgba)
                       : s == LBK_DLS_SPACE_GLG ? (desc->base_glg || desc->out_glg)
                                                : (desc->base_llg || desc->out_llg);
        bool needed = false;
        for (uint32_t i = 0; i < r->ncl; i++) needed |= r->cl[i].space == s;
        if ((needed && !have) || (partial && !have)) {
            res = LBK_ERR_INVALID_ARGUMENT;
            goto fail;
        }
        r->space_on[s] = have && raw->target_count[s] > 0;
    }
    res = make_gaps(r);
    if (res != LBK_OK) goto fail;
    *out = r;
    return LBK_OK;
fail:
    lbk_dls_runtime_close(r);
    return res;
}

void lbk_dls_runtime_invalidate(lbk_dls_runtime *runtime)
{
    if (runtime) runtime->valid = 0;
}

/* ---- weights and apply ----------------------------------------------------------------------- */

lbk_result lbk_dls_effective_weights(const lbk_dls_runtime *r, const float *set_weights, const float *door_weights,
                                     float *out)
{
    if (!r || !out) return LBK_ERR_INVALID_ARGUMENT;
    for (uint32_t p = 0; door_weights && p < r->ndoors; p++)
        if (!isfinite(door_weights[p])) return LBK_ERR_INVALID_ARGUMENT;
    for (uint32_t s = 0; s < r->nsets; s++) {
        float w = set_weights ? set_weights[s] : 0.0f;
        uint32_t p = r->door_of_set[s];
        if (p != LBK_DLS_NO_SET) {
            float omega = door_weights ? door_weights[p] : 0.0f;
            w = r->kinds[s] == LBK_DLS_KIND_DOOR_OPEN ? omega : 1.0f - omega;
        }
        if (r->kinds[s] != LBK_DLS_KIND_COMBINATION && !isfinite(w)) return LBK_ERR_INVALID_ARGUMENT;
        out[s] = w;
    }
    for (uint32_t s = 0; s < r->nsets; s++) {
        if (r->kinds[s] != LBK_DLS_KIND_COMBINATION) continue;
        float w = 1.0f;
        for (uint32_t q = r->member_offset[s]; q < r->member_offset[s + 1]; q++) w *= out[r->members[q]];
        out[s] = w;
    }
    return LBK_OK;
}

lbk_result lbk_dls_apply(lbk_dls_runtime *r, const float *set_weights, const float *door_weights, lbk_dls_apply_stats *stats)
{
    if (!r) return LBK_ERR_INVALID_ARGUMENT;
    lbk_dls_apply_stats st = {0};
    lbk_result res = lbk_dls_effective_weights(r, set_weights, door_weights, r->w);
    if (res != LBK_OK) return res;
    const bool full = !r->valid;
    for (uint32_t s = 0; s < r->nsets; s++) r->changed[s] = full || memcmp(&r->w[s], &r->last[s], sizeof(float)) != 0;
    if (full)
        for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
            if (!r->space_on[s]) continue;
            for (uint64_t g = 0; g < r->ngaps[s]; g++) {
                copy_base(r, s, r->gaps[s][2 * g], r->gaps[s][2 * g + 1]);
                st.targets_written += r->gaps[s][2 * g + 1];
            }
        }
    float wl[LBK_DLS_MAX_CLUSTER_SETS];
    for (uint32_t i = 0; i < r->ncl; i++) {
        const rt_cluster *c = &r->cl[i];
        if (!r->space_on[c->space]) continue;
        bool any_changed = false, any_nonzero = false;
        for (uint32_t j = 0; j < c->nsets; j++) {
            uint32_t s = lbk_rd32(c->sets + 4 * j);
            wl[j] = r->w[s];
            any_changed |= r->changed[s];
            any_nonzero |= wl[j] != 0.0f;
        }
        if (!any_changed) {
            st.clusters_skipped++;
            continue;
        }
        if (!any_nonzero) {
            copy_runs(r, c->space, c->runs, c->run_count);
            st.clusters_copied++;
        } else {
            apply_cluster(r, c, wl);
            st.clusters_applied++;
        }
        st.targets_written += c->target_count;
    }
    memcpy(r->last, r->w, r->nsets * sizeof *r->w);
    r->valid = 1;
    if (stats) *stats = st;
    return LBK_OK;
}
