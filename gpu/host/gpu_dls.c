/* DLS apply on a Vulkan device (gpu_dls.h). */
#include "gpu/host/gpu_dls.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/lightmap.h"

#include "dls_apply.spv.h"
#include "dls_naive.spv.h"

enum { B_DLS, B_RUN_ORD, B_WEIGHTS, B_LMAP, B_LMAP_OUT, B_GLG, B_GLG_OUT, B_LLG, B_LLG_OUT, B_TABLE, B_REC, B_OFFS, B_COUNT };

typedef struct apply_push {
    uint32_t cluster, mode;
    uint32_t clusters, cluster_sets, runs, subgroups, prefix_words, base16, base32, slots, texel_entries, probe_entries;
} apply_push;

typedef struct naive_push {
    uint32_t space, count, offsets; /* the space's first entry in the offsets buffer */
} naive_push;

typedef struct cluster {
    lbk_dls_cluster_info info;
    uint32_t set_first;    /* into sets[] / set_entries[] */
    uint32_t run_first;    /* its first run in the section's run array */
} cluster;

struct gpu_dls {
    gpu_ctx *c;
    lbk_dls_view *view;
    lbk_door_view *doors;
    uint32_t nsets, ndoors, ncl;
    uint64_t targets[3];
    uint8_t *kinds;
    uint32_t *member_first, *members, *door_of_set;
    cluster *cl;
    uint32_t *sets;           /* every cluster's set list, concatenated */
    uint64_t *set_entries;    /* entries per (cluster, set) */
    float *w, *last;
    int valid, per_cluster;
    gpu_buffer buf[B_COUNT];
    gpu_pipeline apply, naive;
    apply_push push;
    uint64_t naive_words[3], naive_first[3]; /* per space: record words, first record word / offset */
    double div_clustered, div_naive;
    uint8_t *count[3];        /* entries per target (every set on) */
    uint32_t *run_ord;        /* per run: the cluster-order position of its first target */
};

/* ---- the level's index data on the host ----------------------------------------------------- */

typedef struct wave_acc {
    uint64_t idle, total;
    uint32_t lane, max, sum;
} wave_acc;

typedef struct decode_ctx {
    gpu_dls *g;
    uint32_t cluster, *slot_of;
    wave_acc *wave;
    /* naive records */
    uint32_t *rec, *offs;
    uint32_t space;
} decode_ctx;

/* Idle lane-iterations over waves of WAVE consecutive invocations: Σ (max n − n) / Σ max n. */
#define WAVE 32u

static void wave_add(wave_acc *a, uint32_t n)
{
    if (n > a->max) a->max = n;
    a->sum += n;
    if (++a->lane == WAVE) {
        a->idle += (uint64_t)a->max * WAVE - a->sum, a->total += (uint64_t)a->max * WAVE;
        a->lane = a->max = a->sum = 0;
    }
}

static void wave_flush(wave_acc *a)
{
    if (a->lane) a->idle += (uint64_t)a->max * a->lane - a->sum, a->total += (uint64_t)a->max * a->lane;
    a->lane = a->max = a->sum = 0;
}

static int count_entries(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    decode_ctx *d = user;
    gpu_dls *g = d->g;
    const cluster *c = &g->cl[d->cluster];
    for (uint32_t j = 0; j < count; j++) g->set_entries[c->set_first + d->slot_of[sets[j]]]++;
    g->count[c->info.space][target] = (uint8_t)(count > 255 ? 255 : count);
    wave_add(d->wave, count); /* one dispatch per cluster, invocations in cluster order */
    (void)payloads;
    return 0;
}

static int write_record(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    decode_ctx *d = user;
    const uint32_t pw = d->space == 0 ? 2 : 7;
    uint32_t *r = d->rec + d->offs[target] - d->g->naive_first[d->space];
    r[0] = count;
    for (uint32_t j = 0; j < count; j++) {
        r[1 + (1 + pw) * j] = sets[j];
        memcpy(&r[2 + (1 + pw) * j], payloads + (size_t)j * 4 * pw, 4 * pw);
    }
    return 0;
}

static int index_data(gpu_dls *g)
{
    uint32_t total_sets = 0;
    g->cl = calloc(g->ncl ? g->ncl : 1, sizeof *g->cl);
    for (uint32_t i = 0; i < g->ncl; i++) {
        if (!g->cl) return -1;
        lbk_dls_cluster_get(g->view, i, &g->cl[i].info);
        g->cl[i].set_first = total_sets;
        total_sets += g->cl[i].info.set_count;
    }
    g->sets = calloc(total_sets + 1, sizeof *g->sets);
    g->set_entries = calloc(total_sets + 1, sizeof *g->set_entries);
    uint32_t *slot_of = calloc(g->nsets + 1, sizeof *slot_of);
    for (int s = 0; s < 3; s++) g->count[s] = calloc(g->targets[s] + 1, 1);
    if (!g->sets || !g->set_entries || !slot_of || !g->count[0] || !g->count[1] || !g->count[2]) {
        free(slot_of);
        return -1;
    }
    wave_acc cl = {0}, nv = {0};
    decode_ctx d = {.g = g, .slot_of = slot_of, .wave = &cl};
    for (uint32_t i = 0; i < g->ncl; i++) {
        const cluster *c = &g->cl[i];
        for (uint32_t j = 0; j < c->info.set_count; j++) {
            lbk_dls_cluster_set_get(g->view, i, j, &g->sets[c->set_first + j]);
            slot_of[g->sets[c->set_first + j]] = j;
        }
        d.cluster = i;
        lbk_dls_cluster_decode(g->view, i, count_entries, &d);
        wave_flush(&cl);
    }
    free(slot_of);
    for (uint32_t s = 0; s < 3; s++) { /* the naive gather: one dispatch per space, target order */
        for (uint64_t t = 0; t < g->targets[s]; t++) wave_add(&nv, g->count[s][t]);
        wave_flush(&nv);
    }
    g->div_clustered = cl.total ? (double)cl.idle / (double)cl.total : 0.0;
    g->div_naive = nv.total ? (double)nv.idle / (double)nv.total : 0.0;
    return 0;
}

/* Per run: the cluster-order position of its first target (a GPU thread's binary search key). */
static int run_ordinals(gpu_dls *g, uint32_t **out, uint64_t *n_out)
{
    uint64_t off, n;
    lbk_dls_array_get(g->view, LBK_DLS_ARRAY_RUNS, &off, &n);
    uint32_t *ord = calloc(n + 1, sizeof *ord);
    if (!ord) return -1;
    const uint8_t *runs = (const uint8_t *)g->buf[B_DLS].map + off;
    for (uint32_t i = 0; i < g->ncl; i++) {
        /* cluster record: run_first at byte 20, run_count at 24 (spec §12.4) */
        uint64_t coff;
        lbk_dls_array_get(g->view, LBK_DLS_ARRAY_CLUSTERS, &coff, NULL);
        const uint8_t *cr = (const uint8_t *)g->buf[B_DLS].map + coff + 64ull * i;
        uint32_t first, count, at = 0;
        memcpy(&first, cr + 20, 4), memcpy(&count, cr + 24, 4);
        g->cl[i].run_first = first;
        for (uint32_t r = 0; r < count; r++) {
            uint32_t len;
            memcpy(&len, runs + 8ull * (first + r) + 4, 4);
            ord[first + r] = at;
            at += len;
        }
    }
    *out = ord, *n_out = n;
    return 0;
}

/* The naive gather's records: per target its entry count, then per entry (set, payload). */
static int naive_records(gpu_dls *g, uint32_t **rec_out, uint32_t **offs_out, uint64_t *rec_words, uint64_t *offs_n)
{
    uint64_t words = 0, noffs = 0;
    for (int s = 0; s < 3; s++) {
        g->naive_first[s] = words;
        for (uint64_t t = 0; t < g->targets[s]; t++) words += 1 + (uint64_t)g->count[s][t] * (s == 0 ? 3 : 8);
        noffs += g->targets[s];
    }
    uint32_t *rec = calloc(words + 1, 4), *offs = calloc(noffs + 1, 4);
    if (!rec || !offs) {
        free(rec), free(offs);
        return -1;
    }
    uint64_t at = 0, o = 0;
    for (int s = 0; s < 3; s++)
        for (uint64_t t = 0; t < g->targets[s]; t++, o++) {
            offs[o] = (uint32_t)at;
            at += 1 + (uint64_t)g->count[s][t] * (s == 0 ? 3 : 8);
        }
    decode_ctx d = {.g = g, .rec = rec};
    for (uint32_t i = 0; i < g->ncl; i++) {
        d.space = g->cl[i].info.space;
        d.offs = offs + (d.space == 0 ? 0 : d.space == 1 ? g->targets[0] : g->targets[0] + g->targets[1]);
        d.rec = rec + g->naive_first[d.space];
        lbk_dls_cluster_decode(g->view, i, write_record, &d);
    }
    *rec_out = rec, *offs_out = offs, *rec_words = words, *offs_n = noffs;
    return 0;
}

/* ---- open / close ---------------------------------------------------------------------------- */

static uint32_t word_offset(const lbk_dls_view *v, uint32_t array)
{
    uint64_t off;
    lbk_dls_array_get(v, array, &off, NULL);
    return (uint32_t)(off / 4);
}

static int load_sets(gpu_dls *g)
{
    g->kinds = calloc(g->nsets + 1, 1);
    g->member_first = calloc(g->nsets + 2, sizeof *g->member_first);
    g->door_of_set = calloc(g->nsets + 1, sizeof *g->door_of_set);
    g->w = calloc(g->nsets + 1, sizeof *g->w);
    g->last = calloc(g->nsets + 1, sizeof *g->last);
    uint32_t nm = 0;
    for (uint32_t s = 0; s < g->nsets; s++) {
        lbk_dls_set_info si;
        lbk_dls_set_get(g->view, s, &si);
        nm += si.member_count;
    }
    g->members = calloc(nm + 1, sizeof *g->members);
    if (!g->kinds || !g->member_first || !g->door_of_set || !g->w || !g->last || !g->members) return -1;
    uint32_t at = 0;
    for (uint32_t s = 0; s < g->nsets; s++) {
        lbk_dls_set_info si;
        lbk_dls_set_get(g->view, s, &si);
        g->kinds[s] = (uint8_t)si.kind;
        g->member_first[s] = at;
        for (uint32_t j = 0; j < si.member_count; j++) lbk_dls_set_member_get(g->view, s, j, &g->members[at++]);
        g->door_of_set[s] = LBK_DLS_NO_SET;
    }
    g->member_first[g->nsets] = at;
    for (uint32_t p = 0; p < g->ndoors; p++) {
        lbk_door_info di;
        lbk_door_get(g->doors, p, &di);
        g->door_of_set[di.open_set] = p;
        if (di.closed_set != LBK_DLS_NO_SET) g->door_of_set[di.closed_set] = p;
    }
    return 0;
}

int gpu_dls_open(gpu_ctx *c, const gpu_dls_level *lv, gpu_dls **out, char *err, size_t n)
{
    *out = NULL;
    gpu_dls *g = calloc(1, sizeof *g);
    if (!g) return -1;
    g->c = c;
#define FAIL(...)                                                                                                  \
    do {                                                                                                           \
        snprintf(err, n, __VA_ARGS__);                                                                             \
        gpu_dls_close(g);                                                                                          \
        return -1;                                                                                                 \
    } while (0)
    if (lbk_dls_open(lv->dls, lv->dls_size, NULL, &g->view) != LBK_OK) FAIL("the DLS section does not open");
    if (lv->door && lbk_door_open(lv->door, lv->door_size, NULL, &g->doors) != LBK_OK) FAIL("the DOOR section does not open");
    if (g->doors && lbk_door_check_dls(g->doors, g->view) != LBK_OK) FAIL("DOOR and DLS disagree");
    g->nsets = lbk_dls_set_count(g->view);
    g->ndoors = g->doors ? lbk_door_count(g->doors) : 0;
    g->ncl = lbk_dls_cluster_count(g->view);
    for (int s = 0; s < 3; s++) g->targets[s] = lbk_dls_target_count(g->view, (uint32_t)s);
    lbk_lmap_view lm;
    if (g->targets[0] && (!lv->lmap || lbk_lmap_open(lv->lmap, lv->lmap_size, &lm) != LBK_OK || lm.texel_count != g->targets[0]))
        FAIL("the LMAP section is missing or does not match the DLS texels");
    if ((g->targets[1] && !lv->glg) || (g->targets[2] && !lv->llg)) FAIL("base probes missing");
    if (lv->dls_size > c->max_storage_range || lv->lmap_size > c->max_storage_range)
        FAIL("a section is larger than the device's maxStorageBufferRange");
    if (load_sets(g) || index_data(g)) FAIL("out of memory");
    int bad = gpu_buffer_create(c, lv->dls_size, lv->dls, &g->buf[B_DLS]);
    uint32_t *ord = NULL, *rec = NULL, *offs = NULL;
    uint64_t nruns = 0, rec_words = 0, noffs = 0;
    bad = bad || run_ordinals(g, &ord, &nruns);
    bad = bad || gpu_buffer_create(c, 4 * nruns, ord, &g->buf[B_RUN_ORD]);
    g->run_ord = ord, ord = NULL; /* kept for the batched dispatch's table */
    bad = bad || gpu_buffer_create(c, 4 * (uint64_t)g->nsets, NULL, &g->buf[B_WEIGHTS]);
    bad = bad || gpu_buffer_create(c, lv->lmap ? lv->lmap_size : 16, lv->lmap, &g->buf[B_LMAP]);
    bad = bad || gpu_buffer_create(c, lv->lmap ? lv->lmap_size : 16, lv->lmap, &g->buf[B_LMAP_OUT]);
    bad = bad || gpu_buffer_create(c, 28 * g->targets[1], lv->glg, &g->buf[B_GLG]);
    bad = bad || gpu_buffer_create(c, 28 * g->targets[1], NULL, &g->buf[B_GLG_OUT]);
    bad = bad || gpu_buffer_create(c, 28 * g->targets[2], lv->llg, &g->buf[B_LLG]);
    bad = bad || gpu_buffer_create(c, 28 * g->targets[2], NULL, &g->buf[B_LLG_OUT]);
    uint64_t groups = 0; /* the batched dispatch's table: a workgroup of 64 per stretch of a cluster */
    for (uint32_t i = 0; i < g->ncl; i++) groups += (g->cl[i].info.target_count + 63) / 64;
    bad = bad || gpu_buffer_create(c, 12 * groups, NULL, &g->buf[B_TABLE]);
    if (!bad && lv->naive) bad = naive_records(g, &rec, &offs, &rec_words, &noffs);
    bad = bad || gpu_buffer_create(c, 4 * rec_words, rec, &g->buf[B_REC]);
    bad = bad || gpu_buffer_create(c, 4 * noffs, offs, &g->buf[B_OFFS]);
    free(ord), free(rec), free(offs);
    if (bad) FAIL("out of device memory");
    if (gpu_pipeline_create(c, dls_apply_spv, sizeof dls_apply_spv, 10, sizeof(apply_push), &g->apply) ||
        gpu_pipeline_create(c, dls_naive_spv, sizeof dls_naive_spv, 9, sizeof(naive_push), &g->naive))
        FAIL("pipeline creation failed");
    const gpu_buffer *ab[10] = {&g->buf[B_DLS], &g->buf[B_RUN_ORD], &g->buf[B_WEIGHTS], &g->buf[B_LMAP], &g->buf[B_LMAP_OUT],
                                &g->buf[B_GLG], &g->buf[B_GLG_OUT], &g->buf[B_LLG], &g->buf[B_LLG_OUT], &g->buf[B_TABLE]};
    gpu_pipeline_bind(c, &g->apply, ab);
    const gpu_buffer *nb[9] = {&g->buf[B_REC], &g->buf[B_OFFS], &g->buf[B_WEIGHTS], &g->buf[B_LMAP], &g->buf[B_LMAP_OUT],
                               &g->buf[B_GLG], &g->buf[B_GLG_OUT], &g->buf[B_LLG], &g->buf[B_LLG_OUT]};
    gpu_pipeline_bind(c, &g->naive, nb);
    apply_push *p = &g->push;
    p->clusters = word_offset(g->view, LBK_DLS_ARRAY_CLUSTERS);
    p->cluster_sets = word_offset(g->view, LBK_DLS_ARRAY_CLUSTER_SETS);
    p->runs = word_offset(g->view, LBK_DLS_ARRAY_RUNS);
    p->subgroups = word_offset(g->view, LBK_DLS_ARRAY_SUBGROUPS);
    p->prefix_words = word_offset(g->view, LBK_DLS_ARRAY_PREFIX_WORDS);
    p->base16 = word_offset(g->view, LBK_DLS_ARRAY_BASE16);
    p->base32 = word_offset(g->view, LBK_DLS_ARRAY_BASE32);
    p->slots = word_offset(g->view, LBK_DLS_ARRAY_SLOTS);
    p->texel_entries = word_offset(g->view, LBK_DLS_ARRAY_TEXEL_ENTRIES);
    p->probe_entries = word_offset(g->view, LBK_DLS_ARRAY_PROBE_ENTRIES);
    *out = g;
    return 0;
#undef FAIL
}

void gpu_dls_close(gpu_dls *g)
{
    if (!g) return;
    gpu_pipeline_destroy(g->c, &g->apply);
    gpu_pipeline_destroy(g->c, &g->naive);
    for (int b = 0; b < B_COUNT; b++) gpu_buffer_destroy(g->c, &g->buf[b]);
    if (g->doors) lbk_door_close(g->doors);
    lbk_dls_close(g->view);
    free(g->kinds), free(g->member_first), free(g->members), free(g->door_of_set), free(g->w), free(g->last);
    free(g->cl), free(g->sets), free(g->set_entries), free(g->run_ord);
    for (int s = 0; s < 3; s++) free(g->count[s]);
    free(g);
}

void gpu_dls_invalidate(gpu_dls *g) { g->valid = 0; }
void gpu_dls_per_cluster(gpu_dls *g, int on) { g->per_cluster = on; }
uint32_t gpu_dls_cluster_count(const gpu_dls *g) { return g->ncl; }
const uint8_t *gpu_dls_lmap(const gpu_dls *g) { return g->buf[B_LMAP_OUT].map; }
const uint8_t *gpu_dls_probes(const gpu_dls *g, uint32_t space) { return g->buf[space == 1 ? B_GLG_OUT : B_LLG_OUT].map; }

void gpu_dls_divergence(const gpu_dls *g, double *clustered, double *naive)
{
    *clustered = g->div_clustered;
    *naive = g->div_naive;
}

/* ---- apply ------------------------------------------------------------------------------------- */

/* lbk_dls_effective_weights' rules (lbk/dls.h), on the views. */
static int effective_weights(const gpu_dls *g, const float *sw, const float *dw, float *out)
{
    for (uint32_t p = 0; dw && p < g->ndoors; p++)
        if (!isfinite(dw[p])) return -1;
    for (uint32_t s = 0; s < g->nsets; s++) {
        float w = sw ? sw[s] : 0.0f;
        const uint32_t p = g->door_of_set[s];
        if (p != LBK_DLS_NO_SET) {
            const float omega = dw ? dw[p] : 0.0f;
            w = g->kinds[s] == LBK_DLS_KIND_DOOR_OPEN ? omega : 1.0f - omega;
        }
        if (g->kinds[s] != LBK_DLS_KIND_COMBINATION && !isfinite(w)) return -1;
        out[s] = w;
    }
    for (uint32_t s = 0; s < g->nsets; s++) {
        if (g->kinds[s] != LBK_DLS_KIND_COMBINATION) continue;
        float w = 1.0f;
        for (uint32_t q = g->member_first[s]; q < g->member_first[s + 1]; q++) w *= out[g->members[q]];
        out[s] = w;
    }
    return 0;
}

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void copy_buffer(gpu_ctx *c, const gpu_buffer *src, const gpu_buffer *dst)
{
    VkBufferCopy r = {.size = src->size < dst->size ? src->size : dst->size};
    vkCmdCopyBuffer(c->cmd, src->buf, dst->buf, 1, &r);
}

/* Records the three base → output copies (every target starts as its base) and counts them. */
static void record_base_copies(gpu_dls *g, gpu_dls_stats *s)
{
    copy_buffer(g->c, &g->buf[B_LMAP], &g->buf[B_LMAP_OUT]);
    copy_buffer(g->c, &g->buf[B_GLG], &g->buf[B_GLG_OUT]);
    copy_buffer(g->c, &g->buf[B_LLG], &g->buf[B_LLG_OUT]);
    s->copies = 3;
    s->bytes_moved += 2 * (g->buf[B_LMAP].size + g->buf[B_GLG].size + g->buf[B_LLG].size);
}

int gpu_dls_apply(gpu_dls *g, const float *set_weights, const float *door_weights, gpu_dls_stats *st)
{
    gpu_dls_stats s = {0};
    if (effective_weights(g, set_weights, door_weights, g->w)) return -1;
    const double t0 = now_ms();
    const int full = !g->valid;
    memcpy(g->buf[B_WEIGHTS].map, g->w, 4 * (size_t)g->nsets);
    gpu_ctx *c = g->c;
    if (gpu_begin(c)) return -1;
    gpu_timestamp(c, 0);
    if (full) { /* every target starts as its base; then the clusters with a non-zero weight */
        record_base_copies(g, &s);
        gpu_barrier(c);
    }
    uint32_t *table = g->buf[B_TABLE].map, groups = 0;
    for (uint32_t i = 0; i < g->ncl; i++) {
        const cluster *cl = &g->cl[i];
        bool changed = full, nonzero = false;
        uint64_t active = 0;
        for (uint32_t j = 0; j < cl->info.set_count; j++) {
            const uint32_t set = g->sets[cl->set_first + j];
            changed |= memcmp(&g->w[set], &g->last[set], sizeof(float)) != 0;
            if (g->w[set] != 0.0f) {
                nonzero = true;
                active += g->set_entries[cl->set_first + j];
            }
        }
        if (!changed || (full && !nonzero)) { /* unchanged, or already the base */
            s.clusters_skipped++;
            continue;
        }
        if (g->per_cluster) {
            apply_push p = g->push;
            p.cluster = i;
            p.mode = nonzero ? 0 : 1;
            gpu_dispatch(c, &g->apply, &p, cl->info.target_count);
            s.dispatches++;
        } else { /* a workgroup per 64 targets: its cluster, first target and the run that holds it */
            const uint32_t *ord = g->run_ord + cl->run_first;
            for (uint32_t first = 0, run = 0; first < cl->info.target_count; first += 64, groups++) {
                while (run + 1 < cl->info.run_count && ord[run + 1] <= first) run++;
                table[3 * groups] = i | (nonzero ? 0u : 0x80000000u);
                table[3 * groups + 1] = first;
                table[3 * groups + 2] = cl->run_first + run;
            }
        }
        s.invocations += cl->info.target_count;
        const uint64_t psize = cl->info.space == 0 ? 8 : 28;
        s.bytes_moved += psize * (2 * (uint64_t)cl->info.target_count + active);
        if (nonzero) s.clusters_applied++;
        else s.clusters_copied++;
    }
    if (groups) {
        apply_push p = g->push;
        p.mode = 2;
        gpu_dispatch(c, &g->apply, &p, 64 * (uint64_t)groups);
        s.dispatches++;
    }
    gpu_timestamp(c, 1);
    gpu_barrier(c);
    if (gpu_submit(c)) return -1;
    s.gpu_ms = gpu_elapsed_ms(c);
    s.wall_ms = now_ms() - t0;
    memcpy(g->last, g->w, 4 * (size_t)g->nsets);
    g->valid = 1;
    if (st) *st = s;
    return 0;
}

int gpu_dls_copy_bases(gpu_dls *g, gpu_dls_stats *st)
{
    gpu_dls_stats s = {0};
    const double t0 = now_ms();
    gpu_ctx *c = g->c;
    if (gpu_begin(c)) return -1;
    gpu_timestamp(c, 0);
    record_base_copies(g, &s);
    gpu_timestamp(c, 1);
    gpu_barrier(c);
    if (gpu_submit(c)) return -1;
    s.gpu_ms = gpu_elapsed_ms(c);
    s.wall_ms = now_ms() - t0;
    g->valid = 0; /* the outputs are the bases now, not the last weights' */
    if (st) *st = s;
    return 0;
}

int gpu_dls_apply_naive(gpu_dls *g, const float *set_weights, const float *door_weights, gpu_dls_stats *st)
{
    gpu_dls_stats s = {0};
    if (g->buf[B_OFFS].size < 4 * (g->targets[0] + g->targets[1] + g->targets[2])) return -1; /* not built */
    if (effective_weights(g, set_weights, door_weights, g->w)) return -1;
    const double t0 = now_ms();
    memcpy(g->buf[B_WEIGHTS].map, g->w, 4 * (size_t)g->nsets);
    gpu_ctx *c = g->c;
    if (gpu_begin(c)) return -1;
    gpu_timestamp(c, 0);
    for (uint32_t sp = 0; sp < 3; sp++) {
        if (!g->targets[sp]) continue;
        /* the offsets of space sp follow those of the spaces before it */
        naive_push p = {sp, (uint32_t)g->targets[sp], (uint32_t)(sp == 0 ? 0 : sp == 1 ? g->targets[0] : g->targets[0] + g->targets[1])};
        gpu_dispatch(c, &g->naive, &p, g->targets[sp]);
        s.dispatches++;
        s.invocations += g->targets[sp];
        const uint64_t psize = sp == 0 ? 8 : 28;
        uint64_t entries = 0;
        for (uint64_t t = 0; t < g->targets[sp]; t++) entries += g->count[sp][t];
        s.bytes_moved += g->targets[sp] * (2 * psize + 8) + entries * (psize + 4);
    }
    gpu_timestamp(c, 1);
    gpu_barrier(c);
    if (gpu_submit(c)) return -1;
    s.gpu_ms = gpu_elapsed_ms(c);
    s.wall_ms = now_ms() - t0;
    g->valid = 0; /* the clustered path's skipping state no longer describes the outputs */
    if (st) *st = s;
    return 0;
}
