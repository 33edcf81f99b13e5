/* Distributed runs (bk_transport_split, DIST.md): what a unit records per pass and at the end,
 * the merge's replay of the units' records, and the schedule of a unit without a share. */
#include "bake/transport/transport_impl.h"

#include "scene/clock.h"

/* ---- distributed runs (bk_transport_split) ------------------------------------------------ */

lbk_result bk_tr_record_pass(const tp_ctx *c, int pass, const tp_chain_result chain[2])
{
    const bk_transport_split *sp = c->opt->split;
    bk_transport_pass_record pr;
    memset(&pr, 0, sizeof pr);
    pr.pass = pass;
    pr.bounces = chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces;
    pr.samples_per_receiver = bk_tr_lead_samples(c);
    for (int k = 0; k < c->ncls; k++) pr.weight_sum[k] = c->cls[k].weight_sum, pr.class_samples[k] = c->cls[k].spp;
    for (int h = 0; h < 2; h++) pr.x_acc[h] = c->x_acc[h], pr.b_acc[h] = c->b_acc[h];
    return sp->record_pass(sp->user, &pr);
}

void bk_tr_totals_of(const tp_ctx *c, int passes, const tp_chain_result chain[2], bk_transport_totals *t)
{
    memset(t, 0, sizeof *t);
    uint64_t all[3];
    bk_tr_count_totals(c, all);
    t->passes = passes;
    t->stop = bk_tr_lead_class(c)->stop;
    t->nee = c->nee;
    t->bounces = chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces;
    t->q = 0.5 * (chain[0].q + chain[1].q);
    double tot = chain[0].total_energy + chain[1].total_energy;
    t->tail_fraction = tot > 0 ? (chain[0].tail_energy + chain[1].tail_energy) / tot : 0;
    t->cells = c->cell_count;
    t->cache_rays = c->cache_rays, t->cache_shadow = c->cache_shadow, t->cache_nonfinite = c->cache_nonfinite;
    t->recv_rays = all[0] - c->cache_rays - c->extra_rays, t->recv_shadow = all[1] - c->cache_shadow - c->extra_shadow;
    t->recv_nonfinite = all[2] - c->cache_nonfinite - c->extra_nonfinite;
}

/* The merge: every pass's estimate and report from the units' accumulators, then their outputs,
 * then the stats, as the run over all receivers computed them. */
/* What a replay is handed comes from part files, which may be corrupt or forged past their
 * checksums: numbers no run makes are refused before anything casts or indexes with them. */
static int replay_count_ok(double x) { return isfinite(x) && x >= 0 && x <= 0x1p50; }

static int replay_totals_ok(const bk_transport_totals *t)
{
    return t->passes >= 1 && t->passes <= BK_TRANSPORT_MAX_PASSES && t->stop >= BK_STOP_TARGET && t->stop <= BK_STOP_BUDGET &&
           (t->nee == 0 || t->nee == 1) && t->bounces >= 0 && t->bounces <= 1 << 16 && isfinite(t->q) && t->q >= 0 &&
           t->q <= 1 && replay_count_ok(t->tail_fraction);
}

static int replay_pass_ok(const bk_transport_pass_record *pr, size_t n)
{
    if (pr->bounces < 0 || pr->bounces > 1 << 16 || !replay_count_ok(pr->samples_per_receiver)) return 0;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++)
        if (!replay_count_ok(pr->weight_sum[k]) || !replay_count_ok(pr->class_samples[k])) return 0;
    for (int h = 0; h < 2; h++)
        for (size_t i = 0; i < n; i++)
            if (!isfinite(pr->x_acc[h][i]) || !isfinite(pr->b_acc[h][i])) return 0;
    return 1;
}

static int finite_floats(const float *a, size_t n)
{
    for (size_t i = 0; a && i < n; i++)
        if (!isfinite(a[i])) return 0;
    return 1;
}

/* The transport never writes a non-finite output (such samples are counted and dropped). */
static int replay_outputs_ok(const bk_transport_output *o, size_t n)
{
    return finite_floats((const float *)o->radiance, 27 * n) && finite_floats((const float *)o->direct, 27 * n) &&
           finite_floats(o->irradiance, 3 * n) && finite_floats(o->variance, n) && finite_floats(o->halves, 2 * n);
}

lbk_result bk_tr_replay_run(tp_ctx *c, bk_transport_stats *stats)
{
    const bk_transport_options *opt = c->opt;
    const bk_transport_split *sp = opt->split;
    lbk_result res = bk_tr_init_classes(c);
    if (res == LBK_OK) res = bk_tr_stop_init(c); /* (the subsets adaptive sampling reads) */
    if (res) return res;
    bk_transport_totals t;
    memset(&t, 0, sizeof t);
    res = sp->replay_totals(sp->user, c->recv_count, &t);
    if (res) return res;
    if (!replay_totals_ok(&t) || t.octa_count != (uint64_t)c->oct_count || !replay_count_ok(t.octa_rays) ||
        !replay_count_ok(t.octa_rel_rmse))
        return LBK_ERR_BAD_INPUT;
    bk_transport_pass_record pr;
    memset(&pr, 0, sizeof pr);
    const size_t n = c->recv_count ? c->recv_count : 1;
    for (int h = 0; h < 2; h++) {
        pr.x_acc[h] = calloc(n, sizeof(double));
        pr.b_acc[h] = calloc(n, sizeof(double));
        if (!pr.x_acc[h] || !pr.b_acc[h]) res = LBK_ERR_OUT_OF_MEMORY;
    }
    double err = 0, bias = 0;
    tp_errors ce = {{0}, 0};
    for (int pass = 0; !res && pass < t.passes; pass++) {
        pr.pass = pass;
        res = sp->replay_pass(sp->user, &pr);
        if (!res && !replay_pass_ok(&pr, c->recv_count)) res = LBK_ERR_BAD_INPUT;
        if (res) break;
        /* the classes that sampled in this pass are those whose weight grew; their marked
         * blocks stopped before it, as bk_tr_stop_after stopped them in the run */
        for (int k = 0; k < c->ncls; k++) {
            c->cls[k].active = pr.weight_sum[k] > c->cls[k].weight_sum;
            c->cls[k].weight_sum = pr.weight_sum[k], c->cls[k].spp = pr.class_samples[k];
        }
        for (int k = 0; k < c->ncls; k++)
            if (c->cls[k].active) bk_tr_adapt_apply(c, k);
        bk_tr_add_block_weights(c, ldexp(1.0, pass));
        bk_tr_estimate_error_of(c, pr.x_acc, pr.b_acc, &err, &bias, &ce);
        bk_tr_adapt_mark(c, pass, pr.x_acc);
        if (opt->report) {
            bk_transport_sample smp;
            bk_tr_sample_of(c, pr.samples_per_receiver, err, pr.bounces, pass, &ce, &smp);
            opt->report(opt->user, &smp);
        }
        if (opt->progress && opt->progress(opt->user, "gather", (double)(pass + 1) / t.passes)) res = LBK_ERR_CANCELLED;
    }
    /* the parts carry the accumulators of every pass, so the halves come from the last one */
    if (!res && c->out->halves) bk_tr_write_halves(c, pr.x_acc, c->out->halves);
    for (int h = 0; h < 2; h++) free(pr.x_acc[h]), free(pr.b_acc[h]);
    if (!res) res = sp->replay_outputs(sp->user, c->out);
    if (!res && (!replay_outputs_ok(c->out, c->recv_count) || !finite_floats(c->out->octa_irradiance, 48 * c->oct_count)))
        res = LBK_ERR_BAD_INPUT;
    if (res || !stats) return res;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) stats->class_rel_rmse[k] = ce.cls[k];
    stats->probe_rel_rmse = ce.probe;
    stats->seconds = bk_now() - c->t0;
    stats->passes = t.passes;
    stats->samples_per_receiver = pr.samples_per_receiver;
    for (int k = 0; k < c->ncls; k++)
        stats->class_samples[k] = c->cls[k].spp, stats->class_mean_samples[k] = bk_tr_mean_samples(c, k);
    stats->est_rel_rmse = err;
    stats->est_cache_bias = bias;
    stats->bounces = t.bounces;
    stats->q = t.q;
    stats->tail_fraction = t.tail_fraction;
    stats->cells = (size_t)t.cells;
    stats->rays = t.cache_rays + t.recv_rays;
    stats->shadow_rays = t.cache_shadow + t.recv_shadow;
    stats->nonfinite = t.cache_nonfinite + t.recv_nonfinite;
    stats->stop = t.stop;
    stats->nee = t.nee;
    stats->octa_rel_rmse = t.octa_rel_rmse;
    stats->octa_rays = t.octa_rays;
    return LBK_OK;
}

/* A unit's run it has no share of (bk_transport_split.run_range): no cache, no gather; zero
 * outputs and the passes and samples the fixed schedule gives (run_pass, bk_tr_stop_after with no
 * target and no time limit), which later runs may depend on (door runs' budget). */
lbk_result bk_tr_schedule_only(tp_ctx *c, bk_transport_stats *stats)
{
    lbk_result res = bk_tr_init_classes(c);
    if (res) return res;
    const tp_errors none = {{0}, 0};
    int pass = 0;
    for (;; pass++) {
        for (int k = 0; k < c->ncls; k++) {
            if (!c->cls[k].active) continue;
            c->cls[k].weight_sum += ldexp(1.0, pass);
            c->cls[k].spp += 2.0 * (c->s0 << (pass < 20 ? pass : 20));
        }
        if (bk_tr_stop_after(c, pass, &none, 0)) break;
    }
    const bk_transport_output *o = c->out;
    memset(o->radiance, 0, c->recv_count * sizeof *o->radiance);
    if (o->direct) memset(o->direct, 0, c->recv_count * sizeof *o->direct);
    if (o->irradiance) memset(o->irradiance, 0, c->recv_count * 3 * sizeof *o->irradiance);
    if (o->variance) memset(o->variance, 0, c->recv_count * sizeof *o->variance);
    if (o->halves) memset(o->halves, 0, c->recv_count * 2 * sizeof *o->halves);
    if (!stats) return LBK_OK;
    const tp_class *lead = bk_tr_lead_class(c);
    stats->passes = pass + 1;
    stats->samples_per_receiver = lead->spp;
    for (int k = 0; k < c->ncls; k++) stats->class_samples[k] = c->cls[k].spp, stats->class_mean_samples[k] = c->cls[k].spp;
    stats->stop = lead->stop;
    stats->seconds = bk_now() - c->t0;
    return LBK_OK;
}
