/* The DLS runtime's API: open (cluster table, texel planes, chunks), effective weights, and
 * apply as begin / jobs / end. L = L_B + Σ_j w_j S_j per spec/container.md §12.8; the per-target
 * arithmetic is dls_kernel_*.c, the cutting into jobs dls_plan.c, the changed regions
 * dls_dirty.c. */
#include <math.h>
#include <stdlib.h>

#include "dls_runtime.h"
#include "lbk/door.h"

_Static_assert((int)LBK_DLS_ARRAY_STRINGS == (int)DLS_A_STRINGS, "lbk_dls_array follows the DLS_A_* order");

void lbk_dls_runtime_close(lbk_dls_runtime *r)
{
    if (!r) return;
    const lbk_allocator *a = r->alloc;
    lbk_dealloc(a, r->kinds);
    lbk_dealloc(a, r->member_offset);
    lbk_dealloc(a, r->members);
    lbk_dealloc(a, r->door_of_set);
    lbk_dealloc(a, r->cl);
    lbk_dealloc(a, r->planes);
    lbk_dealloc(a, r->chunks);
    lbk_dealloc(a, r->pieces);
    lbk_dealloc(a, r->w);
    lbk_dealloc(a, r->last);
    lbk_dealloc(a, r->cw);
    lbk_dealloc(a, r->changed);
    lbk_dealloc(a, r->action);
    lbk_dealloc(a, r->jobs);
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) lbk_dealloc(a, r->ranges[s]);
    lbk_dealloc(a, r->nrects);
    lbk_dealloc(a, r->rects);
    lbk_dealloc(a, r->lin_block);
    lbk_dealloc(a, r);
}

static void load_cluster(const lbk_dls_raw *raw, uint32_t i, rt_cluster *c)
{
    const uint8_t *cr = raw->d + raw->offset[DLS_A_CLUSTERS] + (uint64_t)i * DLS_CLUSTER_SIZE;
    c->form = lbk_rd32(cr + DLS_C_FORM);
    c->space = lbk_rd32(cr + DLS_C_SPACE);
    c->k = lbk_rd32(cr + DLS_C_OVERLAPS);
    c->nsets = lbk_rd32(cr + DLS_C_SET_COUNT);
    c->set_first = lbk_rd32(cr + DLS_C_SET_FIRST);
    c->run_count = lbk_rd32(cr + DLS_C_RUN_COUNT);
    c->target_count = lbk_rd32(cr + DLS_C_TARGET_COUNT);
    c->entry_count = lbk_rd32(cr + DLS_C_ENTRY_COUNT);
    c->sets = raw->d + raw->offset[DLS_A_CLUSTER_SETS] + 4ull * c->set_first;
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

/* Sets, their kinds and members, and the door that drives each kind 1/2 set. */
static lbk_result load_sets(lbk_dls_runtime *r)
{
    const lbk_allocator *a = r->alloc;
    const size_t ns = r->nsets ? r->nsets : 1;
    r->kinds = lbk_alloc(a, ns);
    r->member_offset = lbk_alloc(a, (ns + 1) * sizeof *r->member_offset);
    r->members = lbk_alloc(a, (r->raw.count[DLS_A_MEMBERS] ? r->raw.count[DLS_A_MEMBERS] : 1) * sizeof *r->members);
    r->door_of_set = lbk_alloc(a, ns * sizeof *r->door_of_set);
    if (!r->kinds || !r->member_offset || !r->members || !r->door_of_set) return LBK_ERR_OUT_OF_MEMORY;
    uint32_t at = 0;
    for (uint32_t s = 0; s < r->nsets; s++) {
        lbk_dls_set_info info;
        lbk_dls_set_get(r->desc.dls, s, &info);
        r->kinds[s] = (uint8_t)info.kind;
        r->member_offset[s] = at;
        for (uint32_t j = 0; j < info.member_count; j++) lbk_dls_set_member_get(r->desc.dls, s, j, &r->members[at++]);
        r->door_of_set[s] = LBK_DLS_NO_SET;
    }
    r->member_offset[r->nsets] = at;
    for (uint32_t p = 0; p < r->ndoors; p++) {
        lbk_door_info di;
        lbk_door_get(r->desc.doors, p, &di);
        r->door_of_set[di.open_set] = p;
        if (di.closed_set != LBK_DLS_NO_SET) r->door_of_set[di.closed_set] = p;
    }
    return LBK_OK;
}

/* A space is written when its buffers are given; a space with clusters needs them. */
static lbk_result check_spaces(lbk_dls_runtime *r)
{
    const lbk_dls_runtime_desc *d = &r->desc;
    r->probe_base[LBK_DLS_SPACE_GLG] = d->base_glg, r->probe_out[LBK_DLS_SPACE_GLG] = d->out_glg;
    r->probe_base[LBK_DLS_SPACE_LLG] = d->base_llg, r->probe_out[LBK_DLS_SPACE_LLG] = d->out_llg;
    if (r->linear) {
        r->probe_lin[LBK_DLS_SPACE_GLG] = d->out_linear_glg, r->probe_lin[LBK_DLS_SPACE_LLG] = d->out_linear_llg;
        r->probe_out[LBK_DLS_SPACE_GLG] = r->probe_out[LBK_DLS_SPACE_LLG] = NULL; /* not written */
    }
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        bool have, partial;
        if (s == LBK_DLS_SPACE_TEXEL) {
            const bool outs = r->linear ? d->out_linear_texel[0] && d->out_linear_texel[1] && d->out_linear_texel[2]
                                        : d->out_irradiance_z && d->out_rgba;
            const bool some = r->linear ? d->out_linear_texel[0] || d->out_linear_texel[1] || d->out_linear_texel[2]
                                        : d->out_irradiance_z || d->out_rgba;
            have = d->page_count ? true : d->base_irradiance_z && d->base_rgba && outs;
            partial = d->page_count ? false : (d->base_irradiance_z || d->base_rgba || some);
        } else {
            const bool out = r->linear ? r->probe_lin[s] != NULL : r->probe_out[s] != NULL;
            have = r->probe_base[s] && out;
            partial = r->probe_base[s] || out;
        }
        bool needed = false;
        for (uint32_t i = 0; i < r->ncl; i++) needed |= r->cl[i].space == s;
        if ((needed && !have) || (partial && !have)) return LBK_ERR_INVALID_ARGUMENT;
        r->space_on[s] = have && r->raw.target_count[s] > 0;
    }
    return LBK_OK;
}

lbk_result lbk_dls_runtime_open(const lbk_dls_runtime_desc *caller_desc, lbk_dls_runtime **out)
{
    if (!caller_desc || !out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    lbk_dls_runtime_desc in;
    lbk_result rc = LBK_SIZED_IN(&in, caller_desc, lbk_dls_runtime_desc, allocator);
    if (rc != LBK_OK) return rc;
    if (!in.dls || (in.flags & ~(LBK_DLS_RUNTIME_SCALAR | LBK_DLS_RUNTIME_LINEAR))) return LBK_ERR_INVALID_ARGUMENT;
    if (in.doors) {
        lbk_result cr = lbk_door_check_dls(in.doors, in.dls);
        if (cr != LBK_OK) return cr;
    }
    lbk_dls_runtime *r = lbk_calloc(in.allocator, 1, sizeof *r);
    if (!r) return LBK_ERR_OUT_OF_MEMORY;
    if (in.allocator) r->alloc_copy = *in.allocator;
    r->alloc = in.allocator ? &r->alloc_copy : NULL;
    r->desc = in;
    r->linear = (in.flags & LBK_DLS_RUNTIME_LINEAR) != 0;
    lbk_dls_view_raw(in.dls, &r->raw);
    r->nsets = lbk_dls_set_count(in.dls);
    r->ndoors = in.doors ? lbk_door_count(in.doors) : 0;
    r->ncl = lbk_dls_cluster_count(in.dls);
    r->kern = (in.flags & LBK_DLS_RUNTIME_SCALAR) ? NULL : dls_kernels_avx2();
    if (!r->kern) r->kern = dls_kernels_scalar();
    const lbk_allocator *a = r->alloc;
    const size_t ns = r->nsets ? r->nsets : 1;
    r->cl = lbk_calloc(a, r->ncl ? r->ncl : 1, sizeof *r->cl);
    r->w = lbk_calloc(a, ns, sizeof *r->w);
    r->last = lbk_calloc(a, ns, sizeof *r->last);
    r->changed = lbk_calloc(a, ns, 1);
    r->action = lbk_calloc(a, r->ncl ? r->ncl : 1, 1);
    r->cw = lbk_calloc(a, r->raw.count[DLS_A_CLUSTER_SETS] ? r->raw.count[DLS_A_CLUSTER_SETS] : 1, sizeof *r->cw);
    lbk_result res = LBK_OK;
    if (!r->cl || !r->w || !r->last || !r->changed || !r->action || !r->cw) res = LBK_ERR_OUT_OF_MEMORY;
    if (res == LBK_OK) res = load_sets(r);
    for (uint32_t i = 0; res == LBK_OK && i < r->ncl; i++) load_cluster(&r->raw, i, &r->cl[i]);
    if (res == LBK_OK) res = check_spaces(r);
    if (res == LBK_OK) res = rt_planes_make(r);
    if (res == LBK_OK) res = rt_chunks_make(r);
    if (res == LBK_OK && r->linear) res = rt_linear_prepare(r);
    if (res == LBK_OK) {
        r->jobs = lbk_alloc(a, (r->nchunks ? r->nchunks : 1) * sizeof *r->jobs);
        if (!r->jobs) res = LBK_ERR_OUT_OF_MEMORY;
    }
    if (res == LBK_OK) res = rt_dirty_alloc(r);
    if (res != LBK_OK) {
        lbk_dls_runtime_close(r);
        return res;
    }
    *out = r;
    return LBK_OK;
}

void lbk_dls_runtime_invalidate(lbk_dls_runtime *runtime)
{
    if (runtime) runtime->valid = 0;
}

uint64_t lbk_dls_runtime_linear_bytes(const lbk_dls_runtime *runtime) { return runtime ? runtime->lin_bytes : 0; }

const char *lbk_dls_runtime_path(const lbk_dls_runtime *runtime) { return runtime ? runtime->kern->name : ""; }

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

lbk_result lbk_dls_apply_begin(lbk_dls_runtime *r, const float *set_weights, const float *door_weights, uint32_t *job_count)
{
    if (job_count) *job_count = 0;
    if (!r || !job_count || r->in_apply) return LBK_ERR_INVALID_ARGUMENT;
    lbk_result res = lbk_dls_effective_weights(r, set_weights, door_weights, r->w);
    if (res != LBK_OK) return res;
    lbk_dls_apply_stats st = {0};
    r->full = !r->valid;
    for (uint32_t s = 0; s < r->nsets; s++) r->changed[s] = r->full || memcmp(&r->w[s], &r->last[s], sizeof(float)) != 0;
    for (uint32_t i = 0; i < r->ncl; i++) {
        const rt_cluster *c = &r->cl[i];
        r->action[i] = RT_SKIP;
        if (!r->space_on[c->space]) continue;
        bool any_changed = false, any_nonzero = false;
        for (uint32_t j = 0; j < c->nsets; j++) {
            const uint32_t s = lbk_rd32(c->sets + 4 * j);
            r->cw[c->set_first + j] = r->w[s];
            any_changed |= r->changed[s];
            any_nonzero |= r->w[s] != 0.0f;
        }
        if (!any_changed) {
            st.clusters_skipped++;
            continue;
        }
        r->action[i] = any_nonzero ? RT_APPLY : RT_COPY;
        if (any_nonzero) st.clusters_applied++;
        else st.clusters_copied++;
        st.targets_written += c->target_count;
    }
    uint32_t n = 0;
    for (uint32_t i = 0; i < r->nchunks; i++) {
        const rt_chunk *ch = &r->chunks[i];
        const bool gap = ch->cluster == RT_GAP;
        if (gap ? r->full : r->action[ch->cluster] != RT_SKIP) r->jobs[n++] = i;
        if (gap && r->full) st.targets_written += ch->count;
    }
    r->njobs = n;
    r->stats = st;
    r->in_apply = 1;
    *job_count = n;
    return LBK_OK;
}

void lbk_dls_apply_job(lbk_dls_runtime *r, uint32_t job)
{
    if (!r || !r->in_apply || job >= r->njobs) return;
    rt_chunk_run(r, &r->chunks[r->jobs[job]]);
}

lbk_result lbk_dls_apply_end(lbk_dls_runtime *r, lbk_dls_apply_stats *stats)
{
    if (!r || !r->in_apply) return LBK_ERR_INVALID_ARGUMENT;
    rt_dirty_collect(r);
    memcpy(r->last, r->w, r->nsets * sizeof *r->w);
    r->valid = 1;
    r->in_apply = 0;
    if (stats) *stats = r->stats;
    return LBK_OK;
}

lbk_result lbk_dls_apply(lbk_dls_runtime *r, const float *set_weights, const float *door_weights, lbk_dls_apply_stats *stats)
{
    uint32_t n;
    lbk_result res = lbk_dls_apply_begin(r, set_weights, door_weights, &n);
    if (res != LBK_OK) return res;
    for (uint32_t j = 0; j < n; j++) lbk_dls_apply_job(r, j);
    return lbk_dls_apply_end(r, stats);
}

/* ---- what changed ---------------------------------------------------------------------------- */

uint32_t lbk_dls_dirty_range_count(const lbk_dls_runtime *r, uint32_t space)
{
    return r && space < LBK_DLS_SPACE_COUNT_ ? r->nranges[space] : 0;
}

lbk_result lbk_dls_dirty_range_get(const lbk_dls_runtime *r, uint32_t space, uint32_t i, lbk_dls_range *out)
{
    if (!r || !out || space >= LBK_DLS_SPACE_COUNT_) return LBK_ERR_INVALID_ARGUMENT;
    if (i >= r->nranges[space]) return LBK_ERR_NOT_FOUND;
    *out = r->ranges[space][i];
    return LBK_OK;
}

uint32_t lbk_dls_dirty_rect_count(const lbk_dls_runtime *r, uint32_t page)
{
    return r && page < r->npages ? r->nrects[page] : 0;
}

lbk_result lbk_dls_dirty_rect_get(const lbk_dls_runtime *r, uint32_t page, uint32_t i, lbk_dls_rect *out)
{
    if (!r || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (page >= r->npages || i >= r->nrects[page]) return LBK_ERR_NOT_FOUND;
    *out = r->rects[(size_t)page * LBK_DLS_DIRTY_RECTS + i];
    return LBK_OK;
}
