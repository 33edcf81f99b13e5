/* Series-expansion light transport; see transport.h and TRANSPORT.md. The run and its pass loop;
 * the parts are behind transport_impl.h. */
#include "bake/transport/transport_impl.h"

#include "scene/clock.h"
#include "scene/parallel.h"

/* ---- the run ---------------------------------------------------------------------------------- */

/* Footprint ranges inside options.footprint, triangles and their vertices inside the footprint
 * scene, finite maps. */
static int footprints_valid(const bk_scene *scene, const bk_transport_options *opt, const bk_receiver *r, size_t n)
{
    const bk_scene *fs = opt->footprint_scene ? opt->footprint_scene : scene;
    for (size_t i = 0; i < n; i++) {
        if (!r[i].footprint_count) continue;
        if (!opt->footprint || r[i].footprint_first > opt->footprint_count ||
            r[i].footprint_count > opt->footprint_count - r[i].footprint_first)
            return 0;
    }
    for (size_t k = 0; k < (opt->footprint ? opt->footprint_count : 0); k++) {
        const bk_footprint_tri *f = &opt->footprint[k];
        if (f->tri >= fs->tri_count || !fs->tris || !fs->positions) return 0;
        for (int v = 0; v < 3; v++)
            if (fs->tris[3 * (size_t)f->tri + v] >= fs->vertex_count) return 0;
        for (int a = 0; a < 2; a++)
            for (int b = 0; b < 3; b++)
                if (!isfinite(f->uv[a][b])) return 0;
    }
    return 1;
}

static lbk_result check_inputs(const bk_scene *scene, const bk_tracer *tracer, const bk_receiver *receivers,
                               size_t count, const bk_transport_options *opt, const bk_transport_output *output)
{
    if (!scene || !tracer || !output || (count > 0 && (!receivers || !output->radiance))) return LBK_ERR_INVALID_ARGUMENT;
    if (bk_tracer_tri_count(tracer) != scene->tri_count) return LBK_ERR_INVALID_ARGUMENT;
    if (scene->tri_count > 0 && !scene->tris) return LBK_ERR_INVALID_ARGUMENT;
    for (size_t i = 0; i < count; i++) {
        const bk_receiver *r = &receivers[i];
        for (int k = 0; k < 3; k++)
            if (!isfinite(r->position[k]) || !isfinite(r->normal[k])) return LBK_ERR_INVALID_ARGUMENT;
    }
    const size_t *end = opt->class_end;
    if (end[BK_RECEIVER_CLASSES - 1] && (end[BK_RECEIVER_CLASSES - 1] != count || end[0] > end[1] || end[1] > end[2]))
        return LBK_ERR_INVALID_ARGUMENT;
    if (opt->check_groups && opt->check_per_group > 0) {
        if (!opt->check_group || !output->check_receiver || !output->check_weight || !output->check_irradiance ||
            !output->check_variance || opt->check_per_group > 65536)
            return LBK_ERR_INVALID_ARGUMENT;
        for (size_t i = 0; i < count; i++) {
            const bk_receiver *r = &receivers[i];
            if (opt->check_group[i] != UINT32_MAX && r->normal[0] == 0 && r->normal[1] == 0 && r->normal[2] == 0)
                return LBK_ERR_INVALID_ARGUMENT;
        }
    }
    return footprints_valid(scene, opt, receivers, count) ? LBK_OK : LBK_ERR_INVALID_ARGUMENT;
}

/* Non-zero when the caller's progress callback asks to stop (LBK_ERR_CANCELLED). */
static int report_progress(const tp_ctx *c, const char *phase, double done_spp)
{
    const bk_transport_options *opt = c->opt;
    if (!opt->progress) return 0;
    double f = fmax(done_spp / c->max_samples, opt->time_limit > 0 ? (bk_now() - c->t0) / opt->time_limit : 0);
    return opt->progress(opt->user, phase, f > 1 ? 1 : f);
}

/* Cache rays per cell and bounce in pass p: about as many as the active receivers trace this pass
 * (over ~4 bounces), within [min(4·2^(p/2), cap), cap], cap = cache_rays·2^p; both estimates
 * shrink together. */
static int pass_cache_rays(const tp_ctx *c, int pass, size_t active)
{
    int sp = pass < 20 ? pass : 20;
    double nc = c->cell_count ? (double)c->cell_count : 1;
    double cap = fmin((double)(c->opt->cache_rays > 0 ? c->opt->cache_rays : 16) * ldexp(1.0, sp), 65536.0);
    double lo = fmin(cap, 4.0 * ldexp(1.0, sp / 2));
    double want = ceil((double)c->s0 * ldexp(1.0, sp) * (double)active / (4.0 * nc));
    return (int)fmax(lo, fmin(cap, want));
}

static void extra_gather(tp_ctx *c, size_t begin, size_t end, int thread)
{
    for (size_t p = begin; p < end; p++) bk_tr_recv_gather(c, c->extra[p], c->extra[p] + 1, thread);
}

static void extra_punctual(tp_ctx *c, size_t begin, size_t end, int thread)
{
    for (size_t p = begin; p < end; p++) bk_tr_recv_punctual(c, c->extra[p], c->extra[p] + 1, thread);
}

/* fn over class k's extra receivers; what they trace goes to the extra counters. */
static void extra_run(tp_ctx *c, int k, tp_fn fn)
{
    const size_t b = c->extra_first[k], e = c->extra_first[k + 1];
    if (b == e) return;
    uint64_t before[3], after[3];
    bk_tr_count_totals(c, before);
    bk_tr_parallel_range(c, b, e, 16, fn);
    bk_tr_count_totals(c, after);
    c->extra_rays += after[0] - before[0];
    c->extra_shadow += after[1] - before[1];
    c->extra_nonfinite += after[2] - before[2];
}

void bk_tr_count_totals(const tp_ctx *c, uint64_t t[3])
{
    t[0] = t[1] = t[2] = 0;
    for (int k = 0; k < c->threads; k++) {
        t[0] += c->thread_rays[k];
        t[1] += c->thread_shadow[k];
        t[2] += c->thread_nonfinite[k];
    }
}

/* One pass: both halves' caches, then the final gather at the receivers (in blocks, so
 * progress can be reported). */
static lbk_result run_pass(tp_ctx *c, int pass, tp_chain_result chain[2])
{
    const size_t active = bk_tr_active_receivers(c);
    int cache_rays = pass_cache_rays(c, pass, active);
    for (int h = 0; h < 2; h++) {
        uint64_t before[3], after[3];
        bk_tr_count_totals(c, before);
        chain[h] = bk_tr_run_chain(c, h, pass, cache_rays, c->tail_tol, c->max_bounces);
        bk_tr_count_totals(c, after);
        c->cache_rays += after[0] - before[0];
        c->cache_shadow += after[1] - before[1];
        c->cache_nonfinite += after[2] - before[2];
        if (chain[h].bounces < 0) return c->chain_err ? c->chain_err : LBK_ERR_OUT_OF_MEMORY;
        if (report_progress(c, "cache", c->spp)) return LBK_ERR_CANCELLED;
    }
    c->pass = pass;
    c->rays = c->s0 << (pass < 20 ? pass : 20);
    if (bk_tr_lattice_init(&c->lat, (uint32_t)c->rays) != LBK_OK) return LBK_ERR_OUT_OF_MEMORY;
    c->pass_weight = ldexp(1.0, pass);
    for (int h = 0; h < 2 && c->slc; h++)
        if (bk_tr_slc_draw(c, DOM_SLC_RECV, h, pass, c->slc_recv, &c->draw_recv[h]) != LBK_OK)
            return LBK_ERR_OUT_OF_MEMORY;
    if (c->vpl) {
        lbk_result res = bk_tr_vpl_pass(c, pass);
        if (res != LBK_OK) return res;
    }
    size_t all = 0, done = 0;
    for (int k = 0; k < c->ncls; k++)
        if (c->cls[k].active) all += c->cls[k].end - c->cls[k].begin;
    const size_t block = all / 8 + 1;
    for (int k = 0; k < c->ncls; k++) {
        if (!c->cls[k].active) continue;
        for (size_t b = c->cls[k].begin; b < c->cls[k].end; b += block) {
            size_t e = b + block < c->cls[k].end ? b + block : c->cls[k].end;
            /* a distributed run gathers only its own receivers; each receiver's result depends
             * on nothing but its own streams, so the cut changes no value */
            size_t gb = b > c->g_begin ? b : c->g_begin, ge = e < c->g_end ? e : c->g_end;
            if (gb < ge) bk_tr_parallel_range(c, gb, ge, 16, bk_tr_recv_gather);
            done += e - b;
            if (report_progress(c, "gather", c->spp + 2.0 * c->rays * (double)done / (double)(all ? all : 1)))
                return LBK_ERR_CANCELLED;
        }
    }
    for (int k = 0; k < c->ncls; k++)
        if (c->cls[k].active) extra_run(c, k, extra_gather);
    for (int h = 0; h < 2; h++) {
        bk_slc_draw_destroy(c->draw_recv[h]);
        c->draw_recv[h] = NULL;
    }
    bk_tr_vpl_pass_end(c);
    if (c->oct_count) {
        const int f = c->opt->octa_ray_factor > 0 ? c->opt->octa_ray_factor : 4;
        c->oct_rays = c->rays * (f > 64 ? 64 : f);
        if (bk_tr_lattice_init(&c->oct_lat, (uint32_t)c->oct_rays) != LBK_OK) return LBK_ERR_OUT_OF_MEMORY;
        bk_tr_parallel_range(c, 0, c->oct_count, 1, bk_tr_octa_gather);
        c->oct_total += 2.0 * c->oct_rays;
    }
    c->oct_weight += c->pass_weight;
    for (int k = 0; k < c->ncls; k++) {
        if (!c->cls[k].active) continue;
        c->cls[k].weight_sum += c->pass_weight;
        c->cls[k].spp += 2.0 * c->rays;
        if (c->cls[k].spp > c->spp) c->spp = c->cls[k].spp;
    }
    bk_tr_add_block_weights(c, c->pass_weight);
    bk_tr_mark_rough(c);
    return LBK_OK;
}

/* The weight sum of receiver i's passes. */
static double recv_weight(const tp_ctx *c, size_t i) { return c->recv_count ? c->blk_w[bk_tr_block_of(c, i)] : 0; }

void bk_tr_recv_halves(const tp_ctx *c, double *const x_acc[2], size_t i, double h[2])
{
    const double w = recv_weight(c, i);
    h[0] = w > 0 ? x_acc[0][i] / w : 0;
    h[1] = w > 0 ? x_acc[1][i] / w : 0;
}

/* Each receiver's X of the two halves, normalised by its block's pass weights. */
void bk_tr_write_halves(const tp_ctx *c, double *const x_acc[2], float *halves)
{
    for (size_t i = 0; i < c->recv_count; i++) {
        double h[2];
        bk_tr_recv_halves(c, x_acc, i, h);
        halves[2 * i] = (float)h[0];
        halves[2 * i + 1] = (float)h[1];
    }
}

/* Normalises the pass-weighted sums, then adds the noise-free punctual light. */
static void finish_outputs(tp_ctx *c)
{
    const bk_transport_output *output = c->out;
    for (size_t i = 0; i < c->recv_count; i++) {
        double w = recv_weight(c, i);
        float inv = (float)(w > 0 ? 1.0 / w : 0.0);
        for (int a = 0; a < 3; a++) {
            for (int k = 0; k < 9; k++) {
                output->radiance[i].c[a][k] *= inv;
                if (output->direct) output->direct[i].c[a][k] *= inv;
            }
            if (output->irradiance) output->irradiance[3 * i + a] *= inv;
        }
    }
    /* per-receiver variance of X from the two halves (the denoiser's input) */
    if (output->variance)
        for (size_t i = 0; i < c->recv_count; i++) {
            double h[2];
            bk_tr_recv_halves(c, c->x_acc, i, h);
            output->variance[i] = (float)bk_tr_halves_variance(h);
        }
    if (output->halves) bk_tr_write_halves(c, c->x_acc, output->halves);
    if (c->light_count && !c->slc) { /* (culled light is in the passes' sums already) */
        float *pl = c->punct_lum;
        c->punct_lum = NULL; /* bk_tr_recv_punctual now writes into the outputs */
        bk_tr_parallel_range(c, c->g_begin, c->g_end, 64, bk_tr_recv_punctual);
        c->punct_lum = pl;
    }
}

static void fill_stats(const tp_ctx *c, int passes, double err, double bias, const tp_errors *ce,
                       const tp_chain_result chain[2], bk_transport_stats *stats)
{
    const tp_class *lead = bk_tr_lead_class(c);
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) stats->class_rel_rmse[k] = ce->cls[k];
    stats->probe_rel_rmse = ce->probe;
    stats->seconds = bk_now() - c->t0;
    stats->passes = passes;
    stats->samples_per_receiver = bk_tr_lead_samples(c);
    for (int k = 0; k < c->ncls; k++)
        stats->class_samples[k] = c->cls[k].spp, stats->class_mean_samples[k] = bk_tr_mean_samples(c, k);
    stats->est_rel_rmse = err;
    stats->est_cache_bias = bias;
    stats->bounces = chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces;
    stats->q = 0.5 * (chain[0].q + chain[1].q);
    double tot = chain[0].total_energy + chain[1].total_energy;
    stats->tail_fraction = tot > 0 ? (chain[0].tail_energy + chain[1].tail_energy) / tot : 0;
    stats->cells = c->cell_count;
    uint64_t tested = 0, vt = 0;
    for (int t = 0; t < c->threads; t++) {
        stats->rays += c->thread_rays[t];
        stats->shadow_rays += c->thread_shadow[t];
        stats->nonfinite += c->thread_nonfinite[t];
        tested += c->thread_slc_tested[t];
        vt += c->thread_vpl_tested[t];
    }
    stats->stop = lead->stop;
    stats->nee = c->nee;
    stats->slc = c->slc;
    stats->slc_delta = c->slc_delta;
    double recv_spp = 0; /* receiver-draws: each receiver draws twice (halves) per pass it sampled */
    for (int k = 0; k < c->ncls; k++) recv_spp += (double)(c->cls[k].end - c->cls[k].begin);
    stats->slc_lights_tested = recv_spp > 0 ? (double)tested / recv_spp : 0;
    stats->vpl = c->vpl;
    stats->vpl_delta = c->vpl_delta;
    stats->vpl_share = c->vpl_share;
    stats->vpl_made = c->vpl_made;
    stats->vpl_tested = recv_spp > 0 ? (double)vt / recv_spp : 0;
}

/* What a pass reports. */
void bk_tr_sample_of(const tp_ctx *c, double spp, double err, int bounces, int pass, const tp_errors *ce,
                     bk_transport_sample *smp)
{
    memset(smp, 0, sizeof *smp);
    smp->seconds = bk_now() - c->t0;
    smp->samples_per_receiver = spp;
    smp->est_rel_rmse = err;
    smp->bounces = bounces;
    smp->pass = pass;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) {
        smp->class_rel_rmse[k] = ce->cls[k];
        smp->class_samples[k] = c->cls[k].spp;
        smp->class_mean_samples[k] = bk_tr_mean_samples(c, k);
    }
    smp->probe_rel_rmse = ce->probe;
}

lbk_result bk_transport_run(const bk_scene *scene, const bk_tracer *tracer, const bk_receiver *receivers,
                            size_t count, const bk_transport_options *options,
                            const bk_transport_output *output, bk_transport_stats *stats)
{
    double t0 = bk_now();
    bk_transport_options defaults;
    memset(&defaults, 0, sizeof defaults);
    const bk_transport_options *opt = options ? options : &defaults;
    if (stats) memset(stats, 0, sizeof *stats);
    lbk_result res = check_inputs(scene, tracer, receivers, count, opt, output);
    if (res != LBK_OK) return res;
    const bk_transport_split *split = opt->split;
    if (split && opt->time_limit > 0) return LBK_ERR_INVALID_ARGUMENT; /* the passes would depend on the machine */
    size_t g_begin = 0, g_end = count;
    int own = 1;
    if (split && !split->replay) {
        res = split->run_range(split->user, count, &own, &g_begin, &g_end);
        if (res != LBK_OK) return res;
        if (own && (g_begin > g_end || g_end > count)) return LBK_ERR_INVALID_ARGUMENT;
    }
    const int rec = split && !split->replay && own == 1; /* own == 2: baked whole, not recorded */

    tp_ctx c;
    memset(&c, 0, sizeof c);
    c.scene = scene;
    c.tracer = tracer;
    c.opt = opt;
    c.seed = opt->seed;
    c.threads = bk_thread_count(opt->threads);
    c.recv = receivers;
    c.recv_count = count;
    c.fscene = opt->footprint_scene ? opt->footprint_scene : scene;
    c.out = output;
    /* a distributed run's octahedral probes are gathered by the unit whose slice starts at 0 */
    const int octa_here = !split || split->replay || (own == 1 && g_begin == 0);
    c.oct_count = output->octa_irradiance && opt->octa_points && octa_here ? opt->octa_count : 0;
    c.t0 = t0;
    c.max_bounces = opt->max_bounces > 0 ? opt->max_bounces : 64;
    c.max_samples = opt->max_samples > 0 ? opt->max_samples : 4096;
    c.target = opt->target_error == 0 ? 0.01 : opt->target_error;
    c.s0 = opt->first_pass_samples > 0 ? opt->first_pass_samples : 16;
    c.tail_tol = fmax(0.1 * (c.target > 0 ? c.target : 0.001), 1e-5);
    c.g_begin = g_begin;
    c.g_end = g_end;
    if (split && split->replay) {
        res = bk_tr_replay_run(&c, stats);
        goto done;
    }
    if (!own) {
        res = bk_tr_schedule_only(&c, stats);
        goto done;
    }
    res = bk_tr_init_classes(&c); /* (before bk_tr_ctx_init: culling's δ is measured per class) */
    if (res == LBK_OK) res = bk_tr_ctx_init(&c);
    if (res == LBK_OK) res = bk_tr_stop_init(&c);
    if (res != LBK_OK) goto done;

    for (size_t i = 0; i < count; i++) {
        memset(&output->radiance[i], 0, sizeof output->radiance[i]);
        if (output->direct) memset(&output->direct[i], 0, sizeof output->direct[i]);
        if (output->irradiance) output->irradiance[3 * i] = output->irradiance[3 * i + 1] = output->irradiance[3 * i + 2] = 0;
    }
    if (c.oct_count) memset(output->octa_irradiance, 0, c.oct_count * 48 * sizeof(float));
    if (c.light_count && !c.slc) { /* luminance only, for the error */
        bk_tr_parallel_range(&c, c.g_begin, c.g_end, 64, bk_tr_recv_punctual);
        for (int k = 0; k < c.ncls; k++) extra_run(&c, k, extra_punctual);
    }

    double err = 0, bias = 0;
    tp_errors ce = {{0}, 0}, sce;
    int pass = 0;
    tp_chain_result chain[2] = {{0, 0, 0, 0}, {0, 0, 0, 0}};
    if (opt->checkpoint && !split) {
        int done_passes = 0;
        res = bk_tr_load_state(&c, chain, &done_passes);
        if (res != LBK_OK) goto done;
        if (done_passes > 0) {
            /* resumed: the saved passes' reports again, then the stop rule after the last one */
            if (opt->report)
                for (int p = 0; p < done_passes; p++) opt->report(opt->user, &c.samples[p]);
            bk_tr_estimate_error(&c, &err, &bias, &ce);
            bk_tr_stop_errors(&c, &ce, &sce);
            pass = done_passes - 1;
            bk_tr_adapt_mark(&c, pass, c.x_acc);
            bk_tr_reopen_classes(&c);
            if (bk_tr_stop_after(&c, pass, &sce, 0)) goto finished;
            pass = done_passes;
        }
    }
    for (;; pass++) {
        double pass_start = bk_now();
        res = run_pass(&c, pass, chain);
        if (res != LBK_OK) goto done;
        bk_tr_estimate_error(&c, &err, &bias, &ce);
        bk_tr_adapt_mark(&c, pass, c.x_acc);
        if (rec && (res = bk_tr_record_pass(&c, pass, chain)) != LBK_OK) goto done;
        bk_transport_sample smp;
        bk_tr_sample_of(&c, bk_tr_lead_samples(&c), err,
                        chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces, pass, &ce, &smp);
        if (pass < BK_TRANSPORT_MAX_PASSES) c.samples[pass] = smp;
        if (opt->report) opt->report(opt->user, &smp);
        if (opt->checkpoint && !split && (res = bk_tr_save_state(&c, pass, chain)) != LBK_OK) goto done;
        bk_tr_stop_errors(&c, &ce, &sce);
        if (bk_tr_stop_after(&c, pass, &sce, bk_now() - pass_start)) break;
    }
finished:
    finish_outputs(&c);
    const double oct_err = c.oct_count ? bk_tr_octa_finish(&c) : 0;
    if (stats) {
        fill_stats(&c, pass + 1, err, bias, &ce, chain, stats);
        stats->octa_rel_rmse = oct_err;
        stats->octa_rays = c.oct_total;
    }
    /* after the stats: the check's rays are not in them (a distributed merge, which cannot run
     * it, counts the same rays as the local bake) */
    if (opt->check_groups && opt->check_per_group > 0 && !split && (res = bk_tr_check_run(&c)) != LBK_OK) goto done;
    if (stats) {
        stats->check_rays = c.check_rays;
        stats->check_samples = c.check_samples;
    }
    if (rec) {
        bk_transport_totals t;
        bk_tr_totals_of(&c, pass + 1, chain, &t);
        t.octa_count = c.oct_count;
        t.octa_rays = c.oct_total;
        t.octa_rel_rmse = oct_err;
        res = split->record_done(split->user, output, &t);
    }
done:
    bk_tr_free_ctx(&c);
    return res;
}
