/* Distributed bakes: the part format (spec/part.md) and the transport's record and replay
 * (bk_transport_split). Multi-byte values are little-endian; floats are IEEE-754 bit patterns. */
#include "bake/dist/dist.h"

#include "bake/dist/cache_share.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define XXH_INLINE_ALL /* as the rest of the baker: liblbkbake links no xxhash of its own */
#include <xxhash.h>

#include "lbk/byteorder.h"

typedef struct buf {
    uint8_t *p;
    size_t n, cap;
    int failed;
} buf;

static uint8_t *buf_grow(buf *b, size_t more)
{
    if (b->failed) return NULL;
    if (more > SIZE_MAX / 2 - b->n) { b->failed = 1; return NULL; }
    if (b->n + more > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + more) cap *= 2;
        uint8_t *q = realloc(b->p, cap);
        if (!q) { b->failed = 1; return NULL; }
        b->p = q;
        b->cap = cap;
    }
    uint8_t *at = b->p + b->n;
    b->n += more;
    return at;
}

/* ---- record sizes -------------------------------------------------------------------------- */

static const int out_floats[4] = {27, 27, 3, 1}; /* radiance, direct, irradiance, variance */

size_t bk_part_run_size(uint64_t n, uint32_t passes, uint32_t mask)
{
    if (n > (SIZE_MAX >> 12)) return 0;
    size_t per = (size_t)passes * 32;
    for (int k = 0; k < 4; k++)
        if (mask & (1u << k)) per += 4 * (size_t)out_floats[k];
    return BK_PART_RUN_HEADER_SIZE + (size_t)passes * BK_PART_PASS_HEADER_SIZE + (size_t)n * per;
}

/* runs, units <= 2^16 and count < 2^40 (checked by the callers), so the products fit */
void bk_dist_unit_runs(uint32_t runs, uint32_t units, uint32_t unit, uint32_t *first, uint32_t *end)
{
    if (units <= runs) {
        *first = (uint32_t)((uint64_t)runs * unit / units);
        *end = (uint32_t)((uint64_t)runs * (unit + 1) / units);
    } else {
        /* the run r with units·r/runs <= unit < units·(r+1)/runs */
        *first = (uint32_t)(((uint64_t)runs * (unit + 1) - 1) / units);
        *end = *first + 1;
    }
}

void bk_dist_run_units(uint32_t runs, uint32_t units, uint32_t run, uint32_t *first, uint32_t *end)
{
    if (units <= runs) {
        /* the unit k with runs·k/units <= run < runs·(k+1)/units */
        *first = (uint32_t)(((uint64_t)units * (run + 1) - 1) / runs);
        *end = *first + 1;
    } else {
        *first = (uint32_t)((uint64_t)units * run / runs);
        *end = (uint32_t)((uint64_t)units * (run + 1) / runs);
    }
}

void bk_dist_range(uint64_t count, uint32_t runs, uint32_t units, uint32_t unit, uint32_t run, uint64_t *begin,
                   uint64_t *end)
{
    uint32_t u0, u1;
    bk_dist_run_units(runs, units, run, &u0, &u1);
    /* whole blocks of adaptive sampling (BK_TRANSPORT_BLOCK): a block's stop reads all of it */
    const uint64_t m = u1 - u0, j = unit - u0, B = BK_TRANSPORT_BLOCK, blocks = (count + B - 1) / B;
    *begin = blocks * j / m * B < count ? blocks * j / m * B : count;
    *end = blocks * (j + 1) / m * B < count ? blocks * (j + 1) / m * B : count;
}

static lbk_result say(char *err, size_t len, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static lbk_result say(char *err, size_t len, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    if (err && len) vsnprintf(err, len, fmt, ap);
    va_end(ap);
    return LBK_ERR_BAD_INPUT;
}

lbk_result bk_part_parse(const void *bytes, size_t size, bk_part_view *v, char *err, size_t err_len)
{
    memset(v, 0, sizeof *v);
    const uint8_t *p = bytes;
    if (!p || size < BK_PART_HEADER_SIZE || memcmp(p, BK_PART_MAGIC, 8))
        return say(err, err_len, "not a part file (no LBKPART header)");
    if (lbk_rd32(p + 8) != BK_PART_VERSION) return say(err, err_len, "part format version %u (this lbk reads %u)", lbk_rd32(p + 8), BK_PART_VERSION);
    if (lbk_rd32(p + 12) != BK_PART_HEADER_SIZE || lbk_rd64(p + 48) > BK_PART_MAX_OCTA || lbk_rd32(p + 60) != 0)
        return say(err, err_len, "corrupt part header");
    if (XXH64(p, 88, 0) != lbk_rd64(p + 88)) return say(err, err_len, "corrupt part header (checksum)");
    v->options_hash = lbk_rd64(p + 80);
    v->plan_hash = lbk_rd64(p + 16);
    v->units = lbk_rd32(p + 24);
    v->unit = lbk_rd32(p + 28);
    v->receiver_count = lbk_rd64(p + 32);
    v->total_runs = lbk_rd32(p + 40);
    v->first_run = lbk_rd32(p + 44);
    v->run_count = lbk_rd32(p + 56);
    v->octa_count = lbk_rd64(p + 48);
    uint64_t payload = lbk_rd64(p + 64);
    if (v->units == 0 || v->units > BK_PART_MAX_UNITS || v->unit >= v->units || v->receiver_count >= ((uint64_t)1 << 40) ||
        v->total_runs == 0 || v->total_runs > BK_PART_MAX_RUNS)
        return say(err, err_len, "corrupt part header (unit %u of %u, %llu receivers, %u runs)", v->unit, v->units,
                   (unsigned long long)v->receiver_count, v->total_runs);
    uint32_t r0, r1;
    bk_dist_unit_runs(v->total_runs, v->units, v->unit, &r0, &r1);
    if (v->first_run != r0 || v->run_count != r1 - r0) return say(err, err_len, "corrupt part header (its runs)");
    if (payload != size - BK_PART_HEADER_SIZE)
        return say(err, err_len, "truncated or padded part: %zu bytes, the header says %llu", size,
                   (unsigned long long)(payload + BK_PART_HEADER_SIZE));
    if (XXH64(p + BK_PART_HEADER_SIZE, (size_t)payload, 0) != lbk_rd64(p + 72)) return say(err, err_len, "corrupt part (payload checksum)");
    v->runs = calloc(v->run_count ? v->run_count : 1, sizeof *v->runs);
    if (!v->runs) return LBK_ERR_OUT_OF_MEMORY;
    size_t at = BK_PART_HEADER_SIZE;
    for (uint32_t r = 0; r < v->run_count; r++) {
        if (size - at < BK_PART_RUN_HEADER_SIZE) goto bad;
        uint32_t passes = lbk_rd32(p + at), mask = lbk_rd32(p + at + 4);
        if (passes == 0 || passes > BK_PART_MAX_PASSES || mask > 15 || !(mask & BK_PART_RADIANCE)) goto bad;
        uint64_t b, e;
        bk_dist_range(v->receiver_count, v->total_runs, v->units, v->unit, v->first_run + r, &b, &e);
        if (lbk_rd64(p + at + 96) != b || lbk_rd64(p + at + 104) != e) goto bad;
        size_t n = bk_part_run_size(e - b, passes, mask);
        if (!n || n > size - at) goto bad;
        v->runs[r] = p + at;
        at += n;
    }
    if (v->octa_count) { /* <= BK_PART_MAX_OCTA: no overflow */
        const size_t need = 16 + (size_t)v->octa_count * 48 * 4;
        if (size - at != need) goto bad;
        v->octa = p + at;
        at += need;
    }
    if (at != size) goto bad;
    return LBK_OK;
bad:
    free(v->runs);
    v->runs = NULL;
    return say(err, err_len, "corrupt part (run records)");
}

/* ---- record and replay --------------------------------------------------------------------- */

struct bk_dist {
    int replay;
    uint64_t plan_hash, options_hash;
    uint32_t units, unit;
    uint64_t count;
    uint32_t total_runs, first_run, end_run; /* the bake's runs; this unit's [first_run, end_run) */
    uint32_t base_dependent;                 /* runs from this one on take the base's samples */
    int targeted, have_cut;
    bk_transport_split split;
    uint32_t run;     /* the run under way (record) or being replayed (replay) */
    uint64_t begin, end; /* record: this unit's receivers in that run */
    /* record */
    buf out;          /* finished runs */
    buf passes;       /* the current run's pass records */
    uint32_t run_count, run_passes;
    buf octa;         /* the octahedral probes' block, when this unit gathered them */
    uint64_t octa_count;
    /* replay */
    const bk_part_view *parts;
    uint32_t owners[2]; /* the units that hold the run being replayed */
    const bk_part_view *octa_part; /* the part holding the octahedral probes (replay, run 0) */
    bk_cache_share *share; /* record: the shared caches' folder, NULL: none */
    char err[512];
};

static lbk_result fail(bk_dist *d, lbk_result code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static lbk_result fail(bk_dist *d, lbk_result code, const char *fmt, ...)
{
    if (!d->err[0]) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(d->err, sizeof d->err, fmt, ap);
        va_end(ap);
    }
    return code;
}

static lbk_result rec_range(void *user, size_t count, int *own, size_t *begin, size_t *end)
{
    bk_dist *d = user;
    if (!d->have_cut || count != d->count)
        return fail(d, LBK_ERR_INTERNAL, "a transport run of %zu receivers, the bake has %llu", count, (unsigned long long)d->count);
    if (d->run >= d->total_runs)
        return fail(d, LBK_ERR_INTERNAL, "the bake makes more than the %u transport runs it counted", d->total_runs);
    *own = d->run >= d->first_run && d->run < d->end_run;
    /* the base, unrecorded, gathering only the receivers its stop rule reads: where an error
     * target stops it decides the budget of this unit's door runs */
    if (!*own && d->run == 0 && d->targeted && d->end_run > d->base_dependent) {
        *own = 2;
        *begin = 0;
        *end = 0;
    }
    if (*own == 1) {
        bk_dist_range(d->count, d->total_runs, d->units, d->unit, d->run, &d->begin, &d->end);
        *begin = (size_t)d->begin;
        *end = (size_t)d->end;
    }
    d->run++;
    return LBK_OK;
}

static lbk_result rec_pass(void *user, const bk_transport_pass_record *pr)
{
    bk_dist *d = user;
    const size_t n = (size_t)(d->end - d->begin);
    if (d->run_passes >= BK_PART_MAX_PASSES) return LBK_ERR_LIMIT;
    uint8_t *w = buf_grow(&d->passes, BK_PART_PASS_HEADER_SIZE + 32 * n);
    if (!w) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(w, (uint32_t)pr->pass);
    lbk_wr32(w + 4, (uint32_t)pr->bounces);
    lbk_wrf64(w + 8, pr->samples_per_receiver);
    for (int k = 0; k < 3; k++) lbk_wrf64(w + 16 + 8 * k, pr->weight_sum[k]), lbk_wrf64(w + 40 + 8 * k, pr->class_samples[k]);
    w += BK_PART_PASS_HEADER_SIZE;
    for (size_t i = 0; i < n; i++, w += 32) {
        size_t r = (size_t)d->begin + i;
        lbk_wrf64(w, pr->x_acc[0][r]);
        lbk_wrf64(w + 8, pr->x_acc[1][r]);
        lbk_wrf64(w + 16, pr->b_acc[0][r]);
        lbk_wrf64(w + 24, pr->b_acc[1][r]);
    }
    d->run_passes++;
    return LBK_OK;
}

static uint32_t mask_of(const bk_transport_output *o)
{
    return (o->radiance ? BK_PART_RADIANCE : 0) | (o->direct ? BK_PART_DIRECT : 0) | (o->irradiance ? BK_PART_IRRADIANCE : 0) |
           (o->variance ? BK_PART_VARIANCE : 0);
}

static const float *out_array(const bk_transport_output *o, int k)
{
    return k == 0 ? (const float *)o->radiance : k == 1 ? (const float *)o->direct : k == 2 ? o->irradiance : o->variance;
}

static void put_totals(uint8_t *w, uint32_t passes, uint32_t mask, const bk_transport_totals *t)
{
    lbk_wr32(w, passes);
    lbk_wr32(w + 4, mask);
    lbk_wr32(w + 8, (uint32_t)t->stop);
    lbk_wr32(w + 12, (uint32_t)t->nee);
    lbk_wr32(w + 16, (uint32_t)t->bounces);
    lbk_wr32(w + 20, 0);
    lbk_wrf64(w + 24, t->q);
    lbk_wrf64(w + 32, t->tail_fraction);
    lbk_wr64(w + 40, t->cells);
    lbk_wr64(w + 48, t->cache_rays);
    lbk_wr64(w + 56, t->cache_shadow);
    lbk_wr64(w + 64, t->cache_nonfinite);
    lbk_wr64(w + 72, t->recv_rays);
    lbk_wr64(w + 80, t->recv_shadow);
    lbk_wr64(w + 88, t->recv_nonfinite);
}

/* The receivers a run record holds (bytes 96–111 of its header, checked by bk_part_parse). */
static void put_range(uint8_t *w, uint64_t begin, uint64_t end)
{
    lbk_wr64(w + 96, begin);
    lbk_wr64(w + 104, end);
}

static void get_totals(const uint8_t *w, bk_transport_totals *t)
{
    memset(t, 0, sizeof *t);
    t->passes = (int)lbk_rd32(w);
    t->stop = (int)lbk_rd32(w + 8);
    t->nee = (int)lbk_rd32(w + 12);
    t->bounces = (int)lbk_rd32(w + 16);
    t->q = lbk_rdf64(w + 24);
    t->tail_fraction = lbk_rdf64(w + 32);
    t->cells = lbk_rd64(w + 40);
    t->cache_rays = lbk_rd64(w + 48);
    t->cache_shadow = lbk_rd64(w + 56);
    t->cache_nonfinite = lbk_rd64(w + 64);
    t->recv_rays = lbk_rd64(w + 72);
    t->recv_shadow = lbk_rd64(w + 80);
    t->recv_nonfinite = lbk_rd64(w + 88);
}

static lbk_result rec_done(void *user, const bk_transport_output *o, const bk_transport_totals *t)
{
    bk_dist *d = user;
    const size_t n = (size_t)(d->end - d->begin);
    const uint32_t mask = mask_of(o);
    if ((uint32_t)t->passes != d->run_passes || d->run_count >= BK_PART_MAX_RUNS) return LBK_ERR_INTERNAL;
    size_t total = bk_part_run_size(n, d->run_passes, mask);
    uint8_t *w = total ? buf_grow(&d->out, total) : NULL;
    if (!w || d->passes.failed) return LBK_ERR_OUT_OF_MEMORY;
    put_totals(w, d->run_passes, mask, t);
    put_range(w, d->begin, d->end);
    w += BK_PART_RUN_HEADER_SIZE;
    memcpy(w, d->passes.p, d->passes.n);
    w += d->passes.n;
    for (int k = 0; k < 4; k++) {
        if (!(mask & (1u << k))) continue;
        const float *a = out_array(o, k) + (size_t)d->begin * out_floats[k];
        for (size_t i = 0; i < n * (size_t)out_floats[k]; i++, w += 4) lbk_wrf32(w, a[i]);
    }
    d->passes.n = 0;
    d->run_passes = 0;
    d->run_count++;
    if (t->octa_count && o->octa_irradiance) { /* one unit gathers them, in the base run */
        if (d->octa_count || t->octa_count > BK_PART_MAX_OCTA) return LBK_ERR_INTERNAL;
        const size_t nf = (size_t)t->octa_count * 48;
        uint8_t *q = buf_grow(&d->octa, 16 + 4 * nf);
        if (!q) return LBK_ERR_OUT_OF_MEMORY;
        lbk_wrf64(q, t->octa_rays);
        lbk_wrf64(q + 8, t->octa_rel_rmse);
        for (size_t i = 0; i < nf; i++) lbk_wrf32(q + 16 + 4 * i, o->octa_irradiance[i]);
        d->octa_count = t->octa_count;
    }
    return LBK_OK;
}

/* Run d->run's record in unit u's part, and the receivers it holds. */
static const uint8_t *record_of(const bk_dist *d, uint32_t u, size_t *begin, size_t *n)
{
    const bk_part_view *v = &d->parts[u];
    const uint8_t *rh = v->runs[d->run - v->first_run];
    *begin = (size_t)lbk_rd64(rh + 96);
    *n = (size_t)(lbk_rd64(rh + 104) - lbk_rd64(rh + 96));
    return rh;
}

/* The base run's octahedral probes: held by at most one part, one of the run's units. */
static lbk_result play_octa_totals(bk_dist *d, bk_transport_totals *t)
{
    d->octa_part = NULL;
    for (uint32_t u = 0; u < d->units; u++) {
        if (!d->parts[u].octa_count) continue;
        if (d->octa_part || u < d->owners[0] || u >= d->owners[1])
            return fail(d, LBK_ERR_BAD_INPUT, "unit %u holds octahedral probes it cannot have gathered", u);
        d->octa_part = &d->parts[u];
    }
    if (d->octa_part) {
        t->octa_count = d->octa_part->octa_count;
        t->octa_rays = lbk_rdf64(d->octa_part->octa);
        t->octa_rel_rmse = lbk_rdf64(d->octa_part->octa + 8);
    }
    return LBK_OK;
}

static lbk_result play_totals(void *user, size_t count, bk_transport_totals *t)
{
    bk_dist *d = user;
    if (count != d->count)
        return fail(d, LBK_ERR_BAD_INPUT, "the parts were baked with %llu receivers, this run has %zu", (unsigned long long)d->count, count);
    if (d->run >= d->total_runs)
        return fail(d, LBK_ERR_BAD_INPUT, "the parts hold %u transport runs, this bake makes more: the parts come from another "
                    "scene, options or lbk version", d->total_runs);
    bk_dist_run_units(d->total_runs, d->units, d->run, &d->owners[0], &d->owners[1]);
    memset(t, 0, sizeof *t);
    const uint8_t *first = NULL;
    for (uint32_t u = d->owners[0]; u < d->owners[1]; u++) {
        size_t b, n;
        const uint8_t *rh = record_of(d, u, &b, &n);
        bk_transport_totals x;
        get_totals(rh, &x);
        if (!first) {
            first = rh;
            *t = x;
            continue;
        }
        /* the caches are global: every unit of the run must have computed the same ones */
        if (memcmp(rh, first, 72))
            return fail(d, LBK_ERR_BAD_INPUT, "run %u: unit %u disagrees with unit %u on what every unit of the run computes "
                        "alike (passes, caches, ray counts): the parts were baked by different lbk builds or from different "
                        "inputs", d->run, u, d->owners[0]);
        t->recv_rays += x.recv_rays;
        t->recv_shadow += x.recv_shadow;
        t->recv_nonfinite += x.recv_nonfinite;
    }
    return d->run == 0 ? play_octa_totals(d, t) : LBK_OK;
}

static lbk_result play_pass(void *user, bk_transport_pass_record *pr)
{
    bk_dist *d = user;
    const uint8_t *head = NULL;
    for (uint32_t u = d->owners[0]; u < d->owners[1]; u++) {
        size_t b, n;
        const uint8_t *w = record_of(d, u, &b, &n);
        if ((uint32_t)pr->pass >= lbk_rd32(w)) return fail(d, LBK_ERR_BAD_INPUT, "run %u: unit %u has fewer passes", d->run, u);
        w += BK_PART_RUN_HEADER_SIZE + (size_t)pr->pass * (BK_PART_PASS_HEADER_SIZE + 32 * n);
        if (!head) {
            head = w;
            pr->bounces = (int)lbk_rd32(w + 4);
            pr->samples_per_receiver = lbk_rdf64(w + 8);
            for (int k = 0; k < 3; k++) pr->weight_sum[k] = lbk_rdf64(w + 16 + 8 * k), pr->class_samples[k] = lbk_rdf64(w + 40 + 8 * k);
        } else if (memcmp(w, head, BK_PART_PASS_HEADER_SIZE)) {
            return fail(d, LBK_ERR_BAD_INPUT, "run %u pass %d: unit %u disagrees with unit %u on the pass", d->run, pr->pass, u,
                        d->owners[0]);
        }
        w += BK_PART_PASS_HEADER_SIZE;
        for (size_t i = 0; i < n; i++, w += 32) {
            size_t r = b + i;
            pr->x_acc[0][r] = lbk_rdf64(w);
            pr->x_acc[1][r] = lbk_rdf64(w + 8);
            pr->b_acc[0][r] = lbk_rdf64(w + 16);
            pr->b_acc[1][r] = lbk_rdf64(w + 24);
        }
    }
    return LBK_OK;
}

static lbk_result play_outputs(void *user, const bk_transport_output *o)
{
    bk_dist *d = user;
    const uint32_t mask = mask_of(o);
    for (uint32_t u = d->owners[0]; u < d->owners[1]; u++) {
        size_t b, n;
        const uint8_t *rh = record_of(d, u, &b, &n);
        const uint32_t passes = lbk_rd32(rh), pmask = lbk_rd32(rh + 4);
        if (pmask != mask)
            return fail(d, LBK_ERR_BAD_INPUT, "run %u: the part holds other outputs (%#x) than this bake needs (%#x)", d->run,
                        pmask, mask);
        const uint8_t *w = rh + BK_PART_RUN_HEADER_SIZE + (size_t)passes * (BK_PART_PASS_HEADER_SIZE + 32 * n);
        for (int k = 0; k < 4; k++) {
            if (!(mask & (1u << k))) continue;
            float *a = (float *)out_array(o, k) + b * out_floats[k];
            for (size_t i = 0; i < n * (size_t)out_floats[k]; i++, w += 4) a[i] = lbk_rdf32(w);
        }
    }
    if (d->run == 0 && d->octa_part && o->octa_irradiance) /* (the count checked by the transport) */
        for (size_t i = 0; i < (size_t)d->octa_part->octa_count * 48; i++)
            o->octa_irradiance[i] = lbk_rdf32(d->octa_part->octa + 16 + 4 * i);
    d->run++;
    return LBK_OK;
}

/* A bounce of the run under way: with other units sharing the run, cut into their shares
 * (cache_share.h); else computed whole here. */
static lbk_result rec_cache_bounce(void *user, const bk_cache_bounce *b)
{
    bk_dist *d = user;
    const uint32_t run = d->run - 1; /* rec_range counted it */
    uint32_t first = 0, end = 0;
    if (run < d->total_runs) bk_dist_run_units(d->total_runs, d->units, run, &first, &end);
    if (end - first < 2) { /* (installed with a share only: bk_dist_set_cache_share) */
        uint64_t counts[3]; /* already in the run's counters */
        return b->compute(b->ctx, 0, b->cells, counts);
    }
    const uint32_t mine = d->unit >= first && d->unit < end ? d->unit - first : end - first;
    char why[sizeof d->err];
    lbk_result r = bk_cache_share_bounce(d->share, run, end - first, mine, b, why, sizeof why);
    if (r && r != LBK_ERR_OUT_OF_MEMORY) return fail(d, r, "%s", why);
    return r;
}

void bk_dist_set_cache_share(bk_dist *d, bk_cache_share *share)
{
    d->share = share;
    d->split.cache_bounce = share && !d->replay ? rec_cache_bounce : NULL;
}

lbk_result bk_dist_create(int replay, uint64_t plan_hash, uint64_t options_hash, uint32_t units, uint32_t unit,
                          const bk_part_view *parts, bk_dist **out)
{
    *out = NULL;
    if (units == 0 || units > BK_PART_MAX_UNITS || (!replay && unit >= units) || (replay && !parts)) return LBK_ERR_INVALID_ARGUMENT;
    bk_dist *d = calloc(1, sizeof *d);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    d->replay = replay;
    d->plan_hash = plan_hash;
    d->options_hash = options_hash;
    d->units = units;
    d->unit = unit;
    d->parts = parts;
    d->split.replay = replay;
    d->split.user = d;
    d->split.run_range = rec_range;
    d->split.record_pass = rec_pass;
    d->split.record_done = rec_done;
    d->split.replay_totals = play_totals;
    d->split.replay_pass = play_pass;
    d->split.replay_outputs = play_outputs;
    *out = d;
    return LBK_OK;
}

void bk_dist_destroy(bk_dist *d)
{
    if (!d) return;
    free(d->out.p);
    free(d->passes.p);
    free(d->octa.p);
    free(d);
}

lbk_result bk_dist_set_cut(bk_dist *d, uint64_t count, uint32_t runs, uint32_t base_dependent, int targeted, char *err,
                           size_t err_len)
{
    if (count >= ((uint64_t)1 << 40)) return say(err, err_len, "too many receivers for a distributed bake");
    if (runs == 0 || runs > BK_PART_MAX_RUNS) return say(err, err_len, "too many transport runs for a distributed bake");
    d->count = count;
    d->total_runs = runs;
    d->base_dependent = base_dependent;
    d->targeted = targeted;
    d->have_cut = 1;
    if (d->replay) {
        if (d->parts[0].receiver_count != count)
            return say(err, err_len, "the parts were baked with %llu receivers, this scene and options give %llu: they "
                       "come from another scene, options or lbk version", (unsigned long long)d->parts[0].receiver_count,
                       (unsigned long long)count);
        if (d->parts[0].total_runs != runs)
            return say(err, err_len, "the parts were cut from %u transport runs, this scene and options make %u: they "
                       "come from another scene, options or lbk version", d->parts[0].total_runs, runs);
        return LBK_OK;
    }
    bk_dist_unit_runs(runs, d->units, d->unit, &d->first_run, &d->end_run);
    return LBK_OK;
}

const bk_transport_split *bk_dist_split(const bk_dist *d) { return &d->split; }

const char *bk_dist_error(const bk_dist *d) { return d ? d->err : ""; }

lbk_result bk_dist_finish(bk_dist *d, void **bytes, size_t *size, char *err, size_t err_len)
{
    if (d->replay) {
        if (d->run != d->total_runs)
            return say(err, err_len, "the parts hold %u transport runs, this bake made %u: they come from another scene, "
                       "options or lbk version", d->total_runs, d->run);
        return LBK_OK;
    }
    if (!d->have_cut || d->out.failed) return LBK_ERR_INTERNAL;
    if (d->run != d->total_runs || d->run_count != d->end_run - d->first_run) {
        snprintf(d->err, sizeof d->err, "the bake made %u transport runs, its cut counted %u", d->run, d->total_runs);
        return say(err, err_len, "%s", d->err), LBK_ERR_INTERNAL;
    }
    if (d->octa.failed) return LBK_ERR_OUT_OF_MEMORY;
    const size_t payload = d->out.n + d->octa.n;
    size_t total = BK_PART_HEADER_SIZE + payload;
    uint8_t *p = malloc(total);
    if (!p) return LBK_ERR_OUT_OF_MEMORY;
    memset(p, 0, BK_PART_HEADER_SIZE);
    memcpy(p, BK_PART_MAGIC, 8);
    lbk_wr32(p + 8, BK_PART_VERSION);
    lbk_wr32(p + 12, BK_PART_HEADER_SIZE);
    lbk_wr64(p + 16, d->plan_hash);
    lbk_wr32(p + 24, d->units);
    lbk_wr32(p + 28, d->unit);
    lbk_wr64(p + 32, d->count);
    lbk_wr32(p + 40, d->total_runs);
    lbk_wr32(p + 44, d->first_run);
    lbk_wr64(p + 48, d->octa_count);
    lbk_wr32(p + 56, d->run_count);
    lbk_wr64(p + 64, payload);
    if (d->out.n) memcpy(p + BK_PART_HEADER_SIZE, d->out.p, d->out.n);
    if (d->octa.n) memcpy(p + BK_PART_HEADER_SIZE + d->out.n, d->octa.p, d->octa.n);
    lbk_wr64(p + 72, XXH64(p + BK_PART_HEADER_SIZE, payload, 0));
    lbk_wr64(p + 80, d->options_hash);
    lbk_wr64(p + 88, XXH64(p, 88, 0));
    *bytes = p;
    *size = total;
    return LBK_OK;
}
