/* The path check (TRANSPORT.md §Path check): a few receivers traced by unbiased paths, so the
 * bake's error can be measured against something that does not share its shortcuts.
 *
 * Why: the two halves' difference sees noise only. Both halves read the same kind of cache
 * (cells constant over a texel, the Neumann tail, the continuation rules), so whatever those
 * get wrong — light through a slab thinner than a cell, a cell straddling a shadow edge — is in
 * both and cancels. A path that continues every hit at its exact point, by Russian roulette,
 * with the same sources (sky, MIS-weighted emission and light samples, one punctual light per
 * vertex) has none of it: its mean is the texel's true irradiance over the same footprint. The
 * caller compares it with what it stores (bake/pipeline/object_errors.c). */
#include "bake/transport/transport_impl.h"

/* Paths continue at most this many vertices; past TP_EXACT_RR_DEPTH Russian roulette ends
 * them first in all but the whitest rooms (albedo 0.99: 0.99^256 ≈ 8 % of the paths reach it). */
#define TP_CHECK_DEPTH 256

/* The first-vertex numbers of one path: its direction (u1 and the angle as cos, sin) and its
 * light sample's point, from replicate r's shifted lattice (check_range). */
typedef struct check_dir { double u1, cphi, sphi, l0, l1; } check_dir;

/* One path sample of receiver r's irradiance into e (RGB). */
static void check_sample(tp_ctx *c, const bk_receiver *r, const check_dir *q, bk_rng *rng, tp_count *cnt, double e[3])
{
    static const tp_near_mode md = {NULL, NULL, 1, TP_CHECK_DEPTH, 0, NULL, 0, 1};
    tp_origin g;
    bk_tr_recv_origin(c, r, &g);
    if (r->footprint_count) bk_tr_footprint_sample(c, r, rng, &g);
    double t[3], b[3];
    bk_onb(g.n, t, b);
    const double rr = sqrt(q->u1), lz = sqrt(fmax(0.0, 1 - q->u1));
    double d[3], L[3];
    for (int a = 0; a < 3; a++) d[a] = rr * q->cphi * t[a] + rr * q->sphi * b[a] + lz * g.n[a];
    bk_tr_cont_trace(c, &md, g.o, d, lz / TP_PI, 0, rng, cnt, L);
    for (int a = 0; a < 3; a++) e[a] = TP_PI * L[a];
    if (c->nee) {
        double ld[3], cq, val[3];
        if (bk_tr_nee_sample(c, g.o, g.n, PG_COSINE, q->l0, q->l1, ld, &cq, val, &cnt->shadow) && bk_finite3(val))
            for (int a = 0; a < 3; a++) e[a] += val[a] * cq;
    }
    if (c->light_count) bk_tr_cont_punctual(c, g.p, g.n, g.o, NULL, 0, rng, e, cnt);
}

/* Randomised quasi-Monte Carlo: TP_CHECK_REPLICATES independent replicates, each a randomly
 * shifted rank-1 lattice over the first direction and light sample (the bake's own lattice).
 * Each replicate's mean is unbiased and they are independent, so the spread of the replicate
 * means gives the variance of their mean without bias; the lattice stratifies the first
 * bounce — most of the variance of a texel lit through a window or by a lamp — which iid
 * paths left 1.5–3× as noisy as the error they were to measure (sill_niche_00). */
#define TP_CHECK_REPLICATES 8

/* Check slots [begin, end) (a tp_fn): the mean of check_samples paths each, and the variance of
 * that mean's luminance. A receiver's paths come from its own stream (seed, receiver index), so
 * its result does not depend on which others are checked or on the thread. */
static void check_range(tp_ctx *c, size_t begin, size_t end, int thread)
{
    const bk_transport_output *out = c->out;
    const tp_lattice *lat = &c->check_lat;
    const uint32_t M = lat->S;
    tp_count cnt = {0, 0, 0};
    for (size_t j = begin; j < end; j++) {
        const uint32_t i = out->check_receiver[j];
        if (i == UINT32_MAX) continue;
        const bk_receiver *r = &c->recv[i];
        bk_rng rng = bk_tr_rng(c->seed, DOM_CHECK, 0, 0, 0, i);
        double sum[3] = {0, 0, 0}, sm = 0, smm = 0;
        for (int k = 0; k < TP_CHECK_REPLICATES; k++) {
            const tp_shift sh = bk_tr_lattice_shift(bk_rng_next(&rng), bk_rng_next(&rng));
            const double t1 = bk_rng_next(&rng), t2 = bk_rng_next(&rng);
            double rs[3] = {0, 0, 0};
            for (uint32_t m = 0; m < M; m++) {
                check_dir q;
                bk_tr_lattice(lat, m, &sh, &q.u1, &q.cphi, &q.sphi);
                bk_tr_lattice_uv(lat, m, t1, t2, &q.l0, &q.l1);
                double e[3];
                check_sample(c, r, &q, &rng, &cnt, e);
                if (!bk_finite3(e)) { /* counted, taken as 0: the replicate stays a lattice */
                    cnt.bad++;
                    continue;
                }
                for (int a = 0; a < 3; a++) rs[a] += e[a];
            }
            for (int a = 0; a < 3; a++) sum[a] += rs[a] / M;
            const double y = bk_lum(rs) / M;
            sm += y;
            smm += y * y;
        }
        const double R = TP_CHECK_REPLICATES, mean = sm / R;
        for (int a = 0; a < 3; a++) out->check_irradiance[3 * j + a] = (float)(sum[a] / R);
        /* the replicate means' variance over R − 1, of their mean: / R */
        out->check_variance[j] = (float)(fmax(0.0, smm - R * mean * mean) / (R - 1) / R);
    }
    c->thread_rays[thread] += cnt.rays + cnt.shadow;
    c->thread_shadow[thread] += cnt.shadow;
    c->thread_nonfinite[thread] += cnt.bad;
}

/* Paths per checked receiver: the caller's, else a quarter of the rays the receivers traced in
 * the passes spread over the checks (a path is ~6 rays: its continuations, light samples and
 * shadow rays, measured on the bench levels), within [TP_CHECK_MIN_SAMPLES, 16384]. The floor:
 * fewer paths leave a draw's own variance above the error it is to measure (a sun-lit level of
 * 162 samples per texel gave 312 paths a draw, and most objects' checks read 0). */
#define TP_CHECK_MIN_SAMPLES 2048
static int check_samples(const tp_ctx *c, uint64_t rays_so_far, size_t checks)
{
    if (c->opt->check_samples > 0) return c->opt->check_samples;
    const double recv = (double)(rays_so_far - (c->cache_rays < rays_so_far ? c->cache_rays : rays_so_far));
    const double s = 0.25 * recv / (6.0 * (double)(checks ? checks : 1));
    return (int)fmin(16384.0, fmax((double)TP_CHECK_MIN_SAMPLES, floor(s)));
}

/* Receiver i's noise variance (its two halves' difference) and its value's luminance. */
static void recv_var_value(const tp_ctx *c, size_t i, double *var, double *val)
{
    double h[2];
    bk_tr_recv_halves(c, c->x_acc, i, h);
    *var = bk_tr_halves_variance(h);
    const float *e = c->out->irradiance ? &c->out->irradiance[3 * i] : NULL;
    *val = e ? bk_lumf(e) : 0.5 * (h[0] + h[1]);
}

/* A member's probability of being drawn: half its share of the group's noise Σvar, half its
 * share of Σ E² (all of one where the group lacks the other). A third drawn uniformly as well
 * (for errors neither points at), at 32 draws each with half the paths, put 16 of 41 objects'
 * estimates under half the measured error instead of 11 (bench/levels dev levels, TRANSPORT.md
 * Log 2026-12-06): the draws' own noise grew more than the misses shrank. */
static double check_weight(double v, double sv, double e2, double se)
{
    if (!(sv > 0)) return e2 / se;
    if (!(se > 0)) return v / sv;
    return 0.5 * v / sv + 0.5 * e2 / se;
}

/* One group's picks into slots [slot, slot + K): K draws (systematic, one random offset) from its
 * members in proportion to check_weight — where the noise is and where the light is, so a texel
 * next to a lamp that carries a tenth of the object's error is not left to a 1-in-K chance — each
 * with its weight 1/(K·p_i), so Σ_j weight_j·d_j estimates Σ_i d_i over the group without bias
 * for any d. */
static void pick_group(const tp_ctx *c, const uint32_t *members, size_t m, uint32_t g, size_t slot)
{
    const bk_transport_output *out = c->out;
    const size_t K = (size_t)c->opt->check_per_group;
    double sv = 0, se = 0;
    for (size_t k = 0; k < m; k++) {
        double v, e;
        recv_var_value(c, members[k], &v, &e);
        sv += v;
        se += e * e;
    }
    if (!(se > 0) && !(sv > 0)) return; /* an unlit group: nothing to measure */
    bk_rng rng = bk_tr_rng(c->seed, DOM_CHECK, 1, 0, 0, g);
    const double u0 = bk_rng_next(&rng);
    double acc = 0;
    size_t k = 0;
    for (size_t j = 0; j < K; j++) {
        const double target = (j + u0) / (double)K;
        double w = 0;
        for (; k < m; k++) {
            double v, e;
            recv_var_value(c, members[k], &v, &e);
            w = check_weight(v, sv, e * e, se);
            if (acc + w > target || k + 1 == m) break;
            acc += w;
        }
        out->check_receiver[slot + j] = members[k];
        out->check_weight[slot + j] = w > 0 ? (float)(1.0 / ((double)K * w)) : 0.0f;
    }
}

lbk_result bk_tr_check_run(tp_ctx *c)
{
    const bk_transport_options *o = c->opt;
    const size_t groups = o->check_groups, K = (size_t)o->check_per_group, slots = groups * K;
    const bk_transport_output *out = c->out;
    for (size_t j = 0; j < slots; j++) out->check_receiver[j] = UINT32_MAX;
    /* each group's receivers together, in receiver order (a counting sort) */
    size_t *first = calloc(groups + 1, sizeof *first);
    uint32_t *members = malloc((c->recv_count ? c->recv_count : 1) * sizeof *members);
    if (!first || !members) {
        free(first);
        free(members);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < c->recv_count; i++)
        if (o->check_group[i] < groups) first[o->check_group[i] + 1]++;
    for (size_t g = 0; g < groups; g++) first[g + 1] += first[g];
    size_t *fill = calloc(groups ? groups : 1, sizeof *fill);
    if (!fill) {
        free(first);
        free(members);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < c->recv_count; i++) {
        const uint32_t g = o->check_group[i];
        if (g < groups) members[first[g] + fill[g]++] = (uint32_t)i;
    }
    size_t used = 0;
    for (size_t g = 0; g < groups; g++)
        if (first[g + 1] > first[g]) {
            pick_group(c, members + first[g], first[g + 1] - first[g], (uint32_t)g, g * K);
            used += out->check_receiver[g * K] != UINT32_MAX ? K : 0;
        }
    free(fill);
    free(first);
    free(members);
    uint64_t before[3], after[3];
    bk_tr_count_totals(c, before);
    c->check_samples = check_samples(c, before[0], used);
    /* whole replicates: the lattice's size is the samples per replicate */
    const uint32_t per = (uint32_t)((c->check_samples + TP_CHECK_REPLICATES - 1) / TP_CHECK_REPLICATES);
    c->check_samples = (int)per * TP_CHECK_REPLICATES;
    if (bk_tr_lattice_init(&c->check_lat, per) != LBK_OK) return LBK_ERR_OUT_OF_MEMORY;
    bk_tr_parallel_range(c, 0, slots, 1, check_range);
    bk_tr_count_totals(c, after);
    c->check_rays = after[0] - before[0];
    return LBK_OK;
}
