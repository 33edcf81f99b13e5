/* The light phases: the receivers (texels, the LLG fit's vertex targets, GLG and LLG probes in
 * one array), the base transport run, the set bakes' runs, the denoiser (its weights from the
 * base and every set) and the sets' entries denoised with the same weights. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/dist/checkpoint.h"
#include "bake/dist/dist.h"
#include "bake/encode/encode.h"
#include "bake/pipeline/error_map.h"
#include "bake/pipeline/gather_limit.h"
#include "bake/pipeline/pipeline.h"
#include "bake/denoise/denoise.h"
#include "scene/clock.h"

static int transport_progress(void *user, const char *ph, double fraction)
{
    (void)ph;
    return bk_pipeline_progress(user, fraction);
}

static void base_albedo(void *user, uint32_t tri, float albedo[3])
{
    bk_pipeline *b = user;
    bk_set_bakes_base_albedo(&b->sets, &b->scene, tri, albedo);
}

static void transport_report(void *user, const bk_transport_sample *s)
{
    bk_pipeline *b = user;
    b->est = s->est_rel_rmse;
    if (b->sample_count == b->sample_cap) {
        size_t cap = b->sample_cap ? 2 * b->sample_cap : 16;
        bk_transport_sample *n = realloc(b->samples, cap * sizeof *n);
        if (!n) return; /* the report loses a row; the bake goes on */
        b->samples = n;
        b->sample_cap = cap;
    }
    b->samples[b->sample_count++] = *s;
    /* samples_per_receiver is the mean; where adaptive sampling gave some blocks more, the most */
    char peak[32] = "";
    const double most = s->class_samples[BK_CLASS_TEXEL];
    if (most > s->class_mean_samples[BK_CLASS_TEXEL] + 0.5) snprintf(peak, sizeof peak, " (max %.0f)", most);
    if (b->llg_first > b->texel_receivers || b->receiver_count > b->llg_first)
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_INFO,
                      "pass %d: %7.0f samples/texel%s  est. error %6.2f%%, probes %6.2f%% at %.0f samples  %2d bounces  %7.1f s",
                      s->pass, s->samples_per_receiver, peak, 100 * s->class_rel_rmse[BK_CLASS_TEXEL], 100 * s->probe_rel_rmse,
                      fmax(s->class_samples[BK_CLASS_GLG], s->class_samples[BK_CLASS_LLG]), s->bounces, s->seconds);
    else
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_INFO,
                      "pass %d: %7.0f samples/receiver%s  est. error %6.2f%%  %2d bounces  %7.1f s", s->pass,
                      s->samples_per_receiver, peak, 100 * s->est_rel_rmse, s->bounces, s->seconds);
}

static lbk_result build_receivers(bk_pipeline *b)
{
    size_t n = 0;
    for (size_t i = 0; i < b->texels.count; i++) n += (b->texels.receivers[i].flags & BK_TEXEL_VALID) != 0;
    b->texel_receivers = n;
    /* the LLG fit's vertex targets: surface receivers sampled and estimated with the texels */
    if (bk_llg_fit_plan_build(b->llgs, b->llg_count, &b->scene, b->tracer, n, &b->llg_fit))
        return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    n += b->llg_fit.count;
    b->glg_first = n;
    if (b->have_glg) n += b->glg.probe_count;
    b->llg_first = n;
    for (size_t g = 0; g < b->llg_count; g++) n += bk_llg_probe_count(&b->llgs[g]);
    b->receiver_count = n;
    b->receivers = calloc(n ? n : 1, sizeof *b->receivers);
    b->texel_of_receiver = calloc(b->texel_receivers ? b->texel_receivers : 1, sizeof *b->texel_of_receiver);
    b->radiance = calloc(n ? n : 1, sizeof *b->radiance);
    if (!b->receivers || !b->texel_of_receiver || !b->radiance)
        return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    size_t k = 0;
    for (size_t i = 0; i < b->texels.count; i++) {
        const bk_texel *t = &b->texels.receivers[i];
        if (!(t->flags & BK_TEXEL_VALID)) continue;
        /* the texel's value is the average over its square (texels.h, Footprint) */
        bk_receiver_from_texel(t, &b->receivers[k]);
        b->texel_of_receiver[k++] = (uint32_t)i;
    }
    for (size_t t = 0; t < b->llg_fit.count; t++, k++)
        bk_llg_fit_receiver(&b->llg_fit, b->llgs, &b->scene, t, b->receivers[k].position, b->receivers[k].normal);
    if (b->have_glg)
        for (size_t p = 0; p < b->glg.probe_count; p++, k++) memcpy(b->receivers[k].position, &b->glg.positions[3 * p], 12);
    for (size_t g = 0; g < b->llg_count; g++) {
        const bk_llg *l = &b->llgs[g];
        for (uint32_t z = 0; z < l->dims[2]; z++)
            for (uint32_t y = 0; y < l->dims[1]; y++)
                for (uint32_t x = 0; x < l->dims[0]; x++, k++) bk_llg_probe_position(l, x, y, z, b->receivers[k].position);
    }
    return LBK_OK;
}

static void transport_options(const bk_pipeline *b, bk_transport_options *to)
{
    const lbk_bake_desc *opt = b->opt;
    memset(to, 0, sizeof *to);
    to->seed = opt->seed;
    to->threads = opt->threads;
    to->max_bounces = opt->max_bounces;
    to->max_samples = opt->max_samples > 0 ? opt->max_samples : b->pre->max_samples;
    /* < 0: no target, the passes stop at max_samples (what a distributed bake needs) */
    to->target_error = opt->target_error > 0 ? opt->target_error : opt->target_error < 0 ? -1 : b->pre->target_error;
    to->time_limit = opt->time_limit;
    to->cell_size = b->cell_size;
    to->footprint = b->texels.footprint;
    to->footprint_count = b->texels.footprint_count;
    to->class_end[BK_CLASS_TEXEL] = b->glg_first; /* texels and the LLG fit's targets */
    to->class_end[BK_CLASS_GLG] = b->llg_first;
    to->class_end[BK_CLASS_LLG] = b->receiver_count;
    to->split = b->dist ? bk_dist_split(b->dist) : NULL;
    to->checkpoint = b->ckpt && !b->dist ? bk_ckpt_transport(b->ckpt) : NULL;
    to->slc = opt->light_culling;
    to->slc_delta = opt->light_culling_delta;
    to->glossy_vpl = opt->glossy_vpl;
    to->glossy_vpl_photons = opt->glossy_vpl_photons > 0 ? (size_t)opt->glossy_vpl_photons : 0;
    to->glossy_vpl_delta = opt->glossy_vpl_delta;
    to->adaptive = opt->adaptive >= 0;
}

void bk_pipeline_set_inputs(const bk_pipeline *b, bk_set_inputs *in)
{
    memset(in, 0, sizeof *in);
    in->scene = &b->scene;
    in->tracer = b->tracer;
    in->receivers = b->receivers;
    in->receiver_count = b->receiver_count;
    in->texel_receivers = b->texel_receivers;
    in->glg_first = b->glg_first;
    in->glg_count = b->llg_first - b->glg_first;
    in->llg_first = b->llg_first;
    in->llg_count = b->receiver_count - b->llg_first;
    in->llg_fit = &b->llg_fit;
    in->llgs = b->llgs;
    in->llg_grids = b->llg_count;
    in->texel_of_receiver = b->texel_of_receiver;
    in->texels = &b->texels;
    in->atlas_margin = b->atlas.margin;
    in->seams = b->opt->no_seam_stitch ? NULL : &b->seams;
    in->base_radiance = b->radiance;
    transport_options(b, &in->transport);
    in->transport.footprint_scene = &b->scene; /* door runs trace a scene without the door */
    in->base_samples_per_receiver = b->stats.samples_per_receiver;
    in->threshold = b->opt->dls_threshold;
    in->events = &b->events;
    in->door_method = (int)b->opt->door_method;
    in->skip_guided = b->dist && !bk_dist_split(b->dist)->replay; /* the merge makes them */
    in->denoiser = b->denoiser;
    in->denoise_always = b->opt->denoise == LBK_BAKE_DENOISE_ON;
    in->deadline = b->opt->time_limit > 0 ? b->start + b->opt->time_limit : 0;
    memcpy(in->origin, b->origin, sizeof in->origin);
}

/* The radiosity cache as fine as the lightmap: cells of a lightmapped triangle are its object's
 * texel size (bake/transport/TRANSPORT.md §Bias); other triangles share the default budget. */
static lbk_result build_cell_sizes(bk_pipeline *b)
{
    const bk_scene *s = &b->scene;
    b->cell_size = calloc(s->tri_count ? s->tri_count : 1, sizeof *b->cell_size);
    if (!b->cell_size) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t t = 0; t < s->tri_count; t++) {
        uint32_t o = s->tri_object ? s->tri_object[t] : UINT32_MAX;
        int32_t slot = o < b->atlas.scene_object_count && b->atlas.object_slot ? b->atlas.object_slot[o] : -1;
        if (slot < 0) continue;
        float density = b->atlas.objects[slot].density;
        if (density > 0 && isfinite(density)) b->cell_size[t] = 1.0f / density;
    }
    return LBK_OK;
}

/* Each grid's probes' two-halves estimate (bk_denoise_groups_unfiltered, the transport's formula
 * per group) into noise (llg_count); the class's figure where there are no halves (a distributed
 * merge without them). 0 or LBK_ERR_OUT_OF_MEMORY. */
static lbk_result llg_grid_noise(const bk_pipeline *b, double class_noise, double *noise)
{
    for (size_t g = 0; g < b->llg_count; g++) noise[g] = class_noise;
    if (!b->halves) return LBK_OK;
    const size_t n = b->receiver_count;
    uint32_t *group = malloc((n ? n : 1) * sizeof *group);
    bk_denoise_group_error *e = calloc(b->llg_count, sizeof *e);
    lbk_result r = group && e ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    size_t i = 0;
    for (; !r && i < b->llg_first && i < n; i++) group[i] = UINT32_MAX;
    for (size_t g = 0; !r && g < b->llg_count; g++)
        for (size_t k = bk_llg_probe_count(&b->llgs[g]); k > 0 && i < n; k--) group[i++] = (uint32_t)g;
    for (; !r && i < n; i++) group[i] = UINT32_MAX;
    const bk_denoise_groups gs = {n, group, b->llg_count, e};
    if (!r) r = bk_denoise_groups_unfiltered(b->halves, &gs);
    for (size_t g = 0; !r && g < b->llg_count; g++) noise[g] = e[g].noise;
    free(group), free(e);
    return r;
}

/* Each LLG prop's estimate (lbk_bake_llg_estimate): the class's two terms over one grid, its
 * probes' two halves and its targets' fit residual. Out of memory: none (the report leaves
 * them out). */
static void llg_object_estimates(bk_pipeline *b, double class_noise, int less_noise)
{
    free(b->llg_est);
    b->llg_est = b->llg_fit_grid && b->llg_count ? calloc(b->llg_count, sizeof *b->llg_est) : NULL;
    double *noise = b->llg_est ? malloc(b->llg_count * sizeof *noise) : NULL;
    if (b->llg_est && (!noise || llg_grid_noise(b, class_noise, noise))) free(b->llg_est), b->llg_est = NULL;
    for (size_t g = 0; b->llg_est && g < b->llg_count; g++) {
        double fit = 0;
        const bk_llg_fit_stats *f = &b->llg_fit_grid[g];
        if (f->targets && f->target_sum > 0) {
            const double n = (double)f->targets, mean = f->target_sum / n;
            const double noise_sq = less_noise ? bk_llg_fit_noise_grid(&b->llg_fit, b->llgs, b->variance, g) : 0;
            fit = sqrt(fmax(0, f->fitted_sq - noise_sq) / n) / mean;
        }
        b->llg_est[g] = (lbk_bake_llg_estimate){NULL, b->llgs[g].object, (uint32_t)f->targets, hypot(noise[g], fit),
                                                noise[g], fit};
    }
    free(noise);
}

/* The LLG class's estimate gains the fit's residual at its targets (bake/probes/PROBES.md §LLG
 * fit): the halves' difference sees the noise of the probes, not what the lattice cannot
 * represent, and that is what LLG objects get at run time. The residual also holds the targets'
 * own noise; its expected share is taken off where the transport measured it. */
static void llg_fit_error(bk_pipeline *b)
{
    const bk_llg_fit_stats *f = &b->llg_fit_stats;
    /* without the targets' own noise where the transport measured it (b->variance: denoised bakes) */
    const int less_noise = b->variance && b->opt->denoise != LBK_BAKE_DENOISE_OFF; /* (not for --error-map alone: same bytes) */
    llg_object_estimates(b, b->stats.class_rel_rmse[BK_CLASS_LLG], less_noise);
    if (!f->targets || !(f->target_sum > 0)) return;
    const double n = (double)f->targets, mean = f->target_sum / n;
    const double noise_sq = less_noise ? bk_llg_fit_noise(&b->llg_fit, b->llgs, b->variance) : 0;
    const double fitted = sqrt(fmax(0, f->fitted_sq - noise_sq) / n) / mean, traced = sqrt(f->traced_sq / n) / mean;
    double *e = &b->stats.class_rel_rmse[BK_CLASS_LLG];
    const double noise = *e;
    *e = sqrt(noise * noise + fitted * fitted);
    bk_events_say(&b->events, LBK_BAKE_SEVERITY_INFO,
                  "LLG fit: %zu vertex targets, residual %.1f%% without their noise (traced probes %.1f%%); LLG error "
                  "%.1f%% (noise %.1f%%)",
                  f->targets, 100 * fitted, 100 * traced, 100 * *e, 100 * noise);
}

/* A distributed run that failed: the recorder's or player's own message (bk_dist_error), or, for
 * a replay the transport refused (LBK_ERR_BAD_INPUT: numbers no run makes), that a part is
 * corrupt or forged. LBK_OK: not the parts' fault. */
lbk_result bk_pipeline_replay_failure(bk_pipeline *b, lbk_result r)
{
    if (bk_dist_error(b->dist)[0]) return bk_pipeline_fail(b, r, "%s", bk_dist_error(b->dist));
    if (r == LBK_ERR_BAD_INPUT)
        return bk_pipeline_fail(b, r, "the parts hold numbers no bake makes (sample counts, weights, accumulators or "
                                      "outputs negative, huge or not finite): a part is corrupt or forged");
    return LBK_OK;
}

lbk_result bk_phase_transport(bk_pipeline *b)
{
    lbk_result r = bk_pipeline_phase(b, LBK_BAKE_PHASE_LIGHT);
    if (!r) r = build_receivers(b);
    if (!r) r = build_cell_sizes(b);
    if (!r && b->dist) {
        int ls = 0;
        const int runs = 1 + bk_set_bakes_transport_runs(&b->sets, (int)b->opt->door_method, &ls);
        r = bk_dist_set_cut(b->dist, b->receiver_count, (uint32_t)runs, (uint32_t)(1 + ls), !(b->opt->target_error < 0), b->err,
                            sizeof b->err);
    }
    if (r) return r;
    bk_transport_options to;
    transport_options(b, &to);
    if (b->opt->time_limit > 0) {
        /* one budget for the whole bake (from its start): the base gets an equal share of what
         * is left with every light-set and door run still to come */
        const int runs = 1 + bk_set_bakes_planned_runs(&b->sets);
        to.time_limit = fmax(1e-3, (b->start + b->opt->time_limit - bk_now()) / runs);
    }
    to.progress = transport_progress;
    to.report = transport_report;
    to.user = b;
    if (bk_set_bakes_base_hooks(&b->sets, &b->scene, &to)) to.albedo_hook = base_albedo;
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = b->radiance;
    if (b->opt->denoise != LBK_BAKE_DENOISE_OFF || b->opt->error_map) {
        b->variance = calloc(b->receiver_count ? b->receiver_count : 1, sizeof *b->variance);
        if (!b->variance) return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
        out.variance = b->variance;
    }
    { /* the denoised estimate and each object's estimate (object_errors.c) read them */
        b->halves = calloc(b->receiver_count ? 2 * b->receiver_count : 1, sizeof *b->halves);
        if (!b->halves) return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
        out.halves = b->halves;
    }
    float *irradiance = malloc((b->receiver_count ? b->receiver_count : 1) * 3 * sizeof *irradiance);
    if (!irradiance) return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    out.irradiance = irradiance;
    if (b->octa.count) {
        b->octa_irradiance = calloc((size_t)b->octa.count * 48, sizeof(float));
        if (!b->octa_irradiance) {
            free(irradiance);
            return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
        }
        to.octa_points = b->octa.positions;
        to.octa_count = b->octa.count;
        out.octa_irradiance = b->octa_irradiance;
    }
    bk_far_probes far;
    memset(&far, 0, sizeof far);
    if (b->opt->gather_limit > 0) { /* the GLG first, read by the base run's long rays (gather_limit.h) */
        r = bk_far_probes_bake(b, &to, &far);
        if (r) {
            free(irradiance);
            return bk_pipeline_failed(b, r, "light transport (the probes for --gather-limit)");
        }
        if (far.bytes) {
            to.gather_limit = b->opt->gather_limit;
            to.far_radiance = bk_far_probes_radiance;
            to.far_user = &far;
        } else {
            bk_events_say(&b->events, LBK_BAKE_SEVERITY_WARNING, "--gather-limit needs a global light grid to fall back on; gathering in full");
        }
    }
    r = bk_check_plan(b);
    if (!r && b->check_count) {
        to.check_group = b->check_group;
        to.check_groups = (uint32_t)b->scene.object_count;
        to.check_per_group = (int)b->check_per_object;
        out.check_receiver = b->check;
        out.check_weight = b->check_weight;
        out.check_irradiance = b->check_irradiance;
        out.check_variance = b->check_variance;
    }
    if (!r) r = bk_transport_run(&b->scene, b->tracer, b->receivers, b->receiver_count, &to, &out, &b->stats);
    bk_far_probes_free(&far);
    if (!r) bk_texels_match_irradiance(&b->texels, b->texel_of_receiver, b->texel_receivers, b->radiance, irradiance);
    if (!r && b->llg_count && !b->llg_fit_grid && !(b->llg_fit_grid = calloc(b->llg_count, sizeof *b->llg_fit_grid)))
        r = LBK_ERR_OUT_OF_MEMORY;
    if (!r)
        r = bk_llg_fit_run(&b->llg_fit, b->llgs, &b->scene, irradiance, b->radiance, b->llg_first, &b->llg_fit_stats,
                           b->llg_fit_grid);
    if (!r && b->opt->error_map) { /* before denoising: the transport's own estimate (error_map.h) */
        b->texel_rel_error = malloc((b->texel_receivers ? b->texel_receivers : 1) * sizeof *b->texel_rel_error);
        if (!b->texel_rel_error) r = LBK_ERR_OUT_OF_MEMORY;
        else bk_error_map_from_transport(b->variance, irradiance, b->texel_receivers, b->texel_rel_error);
    }
    free(irradiance);
    b->octa_rel_rmse = b->stats.octa_rel_rmse;
    b->octa_rays = b->stats.octa_rays;
    if (r && b->dist) {
        lbk_result d = bk_pipeline_replay_failure(b, r);
        if (d) return d;
    }
    if (r) return bk_pipeline_failed(b, r, "light transport");
    llg_fit_error(b);
    if (b->stats.vpl_share > 0 || b->stats.vpl) /* (a scene with glossy cells and a point or spot light) */
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_INFO,
                      "glossy VPLs %s: the lights put %.1f %% of their flux into glossy surfaces of roughness <= %.1f "
                      "(auto: on from %.0f %%); %llu VPLs, %.1f tested per receiver",
                      b->stats.vpl ? "on" : "off", 100 * b->stats.vpl_share, BK_VPL_AUTO_ROUGHNESS,
                      100 * BK_VPL_AUTO_SHARE, (unsigned long long)b->stats.vpl_made, b->stats.vpl_tested);
    if (b->stats.nonfinite)
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_WARNING, "%llu non-finite samples were dropped",
                      (unsigned long long)b->stats.nonfinite);
    return LBK_OK;
}

lbk_result bk_phase_sets(bk_pipeline *b)
{
    lbk_result r = bk_pipeline_phase(b, LBK_BAKE_PHASE_SETS);
    if (r) return r;
    bk_set_inputs in;
    bk_pipeline_set_inputs(b, &in);
    return bk_set_bakes_run(&b->sets, &in, b->err, sizeof b->err);
}

/* What the denoised base delivers: the two halves through the same weights (bk_denoiser_error;
 * it reads the halves only, so it runs before the filter), its noise from each half filtered by
 * its own weights (cross, bk_denoiser_half_delta; NULL: the same weights'). The LLG class is not filtered and
 * keeps the base estimate with its fit residual. With --denoise auto (choose) a class whose
 * filtered estimate is not below its unfiltered one (the transport's) stays unfiltered and its
 * error is the transport's; do_denoise then filters the classes marked filtered. */
static lbk_result denoised_error(bk_pipeline *b, int choose, const float *cross, bk_denoise_ride *ride)
{
    bk_transport_options to;
    transport_options(b, &to);
    bk_denoise_error e;
    /* each object's estimate from the same filter pass (object_errors.c) */
    const size_t no = b->scene.object_count;
    uint32_t *group = bk_texel_object_groups(b);
    b->object_filtered = calloc(no ? no : 1, sizeof *b->object_filtered);
    const bk_denoise_groups g = {b->texel_receivers, group, no, b->object_filtered};
    lbk_result r = group && b->object_filtered ? bk_denoiser_error_groups(b->denoiser, b->halves, to.class_end, &e, &g, cross, ride)
                                               : LBK_ERR_OUT_OF_MEMORY;
    free(group);
    if (r) return r;
    lbk_bake_denoised *d = &b->denoised;
    const double raw_t = b->stats.class_rel_rmse[BK_CLASS_TEXEL], raw_g = b->stats.class_rel_rmse[BK_CLASS_GLG];
    d->texels_filtered = !choose || e.rel_rmse[BK_CLASS_TEXEL] < raw_t;
    d->glg_filtered = !choose || e.rel_rmse[BK_CLASS_GLG] < raw_g;
    if (!d->texels_filtered) e.rel_rmse[BK_CLASS_TEXEL] = e.noise[BK_CLASS_TEXEL] = raw_t, e.bias[BK_CLASS_TEXEL] = 0;
    if (!d->glg_filtered) {
        e.rel_rmse[BK_CLASS_GLG] = e.noise[BK_CLASS_GLG] = raw_g, e.bias[BK_CLASS_GLG] = 0;
        e.probe_rel_rmse = b->stats.probe_rel_rmse;
    }
    d->errors.texels = e.rel_rmse[BK_CLASS_TEXEL];
    d->errors.glg = e.rel_rmse[BK_CLASS_GLG];
    d->errors.llg = b->stats.class_rel_rmse[BK_CLASS_LLG];
    d->errors.probes = e.probe_rel_rmse;
    d->texel_noise = e.noise[BK_CLASS_TEXEL], d->texel_bias = e.bias[BK_CLASS_TEXEL];
    d->glg_noise = e.noise[BK_CLASS_GLG], d->glg_bias = e.bias[BK_CLASS_GLG];
    d->seconds = e.seconds;
    b->have_denoised = 1;
    bk_events_say(&b->events, LBK_BAKE_SEVERITY_INFO,
                  "denoised: texels %.2f%% (noise %.2f%%, bias %.2f%%; before %.2f%%%s), GLG probes %.2f%% (before %.2f%%%s)",
                  100 * d->errors.texels, 100 * d->texel_noise, 100 * d->texel_bias, 100 * raw_t,
                  d->texels_filtered ? "" : ": kept unfiltered", 100 * d->errors.glg, 100 * raw_g,
                  d->glg_filtered ? "" : ": kept unfiltered");
    return LBK_OK;
}

/* The noise of the denoised base as another seed would see it (bk_denoiser_half_delta): two
 * more filters, each built from the guide with the base at one half's level and twice its
 * variance. Measured on six dev levels of bench/levels (DENOISE.md): the estimate was 0.58–0.71
 * of the seed-to-seed noise of the stored texels with the same weights' Σ (Dδ)², 0.72–0.84 with
 * this; ~3 % more CPU. */
static lbk_result half_cross_delta(const bk_pipeline *b, const bk_denoise_inputs *in, float **cross)
{
    *cross = malloc((b->receiver_count ? b->receiver_count : 1) * sizeof **cross);
    lbk_result r = *cross ? bk_denoiser_half_delta(b->denoiser, in, b->radiance, b->variance, b->halves, *cross)
                          : LBK_ERR_OUT_OF_MEMORY;
    if (r) free(*cross), *cross = NULL;
    return r;
}

/* The denoising weights (texels and GLG probes) from the base + every light set and door (the
 * guide), applied to the base here and to every set by bk_set_bakes_emit with the same weights
 * (bake/denoise/DENOISE.md). */
lbk_result bk_phase_denoise(bk_pipeline *b)
{
    if (b->opt->denoise == LBK_BAKE_DENOISE_OFF) return LBK_OK;
    const lbk_sh9_rgb *set_sum;
    const float *set_var;
    bk_set_bakes_guide(&b->sets, &set_sum, &set_var);
    lbk_sh9_rgb *guide = NULL;
    float *guide_var = NULL;
    if (set_sum) {
        size_t n = b->receiver_count ? b->receiver_count : 1;
        guide = malloc(n * sizeof *guide);
        guide_var = malloc(n * sizeof *guide_var);
        if (!guide || !guide_var) {
            free(guide), free(guide_var);
            return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
        }
        for (size_t i = 0; i < b->receiver_count; i++) {
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 9; k++) guide[i].c[c][k] = b->radiance[i].c[c][k] + set_sum[i].c[c][k];
            guide_var[i] = b->variance[i] + set_var[i];
        }
    }
    bk_denoise_inputs in;
    memset(&in, 0, sizeof in);
    in.scene = &b->scene;
    in.tracer = b->tracer;
    in.atlas = &b->atlas;
    in.texels = &b->texels;
    in.texel_of_receiver = b->texel_of_receiver;
    in.texel_count = b->texel_receivers;
    in.glg = b->have_glg ? &b->glg : NULL;
    in.glg_first = b->glg_first;
    in.receiver_count = b->receiver_count;
    in.radiance = guide ? guide : b->radiance;
    in.variance = guide_var ? guide_var : b->variance;
    bk_denoise_options o;
    memset(&o, 0, sizeof o);
    o.threads = b->opt->threads;
    float *cross = NULL;
    lbk_result r = bk_denoiser_create(&in, &o, &b->denoiser);
    if (!r && b->halves) r = half_cross_delta(b, &in, &cross);
    free(guide), free(guide_var);
    /* the base's texels filtered in the estimate's pass, kept if the estimate keeps them */
    bk_denoise_ride ride = {b->radiance, NULL, 0};
    ride.filtered = b->texel_receivers ? malloc(b->texel_receivers * sizeof(lbk_sh9_rgb)) : NULL;
    if (!r) r = denoised_error(b, b->opt->denoise == LBK_BAKE_DENOISE_AUTO, cross, ride.filtered ? &ride : NULL);
    free(cross);
    const int texels = b->denoised.texels_filtered;
    if (!r && texels && ride.done) r = bk_denoiser_blend_texels(b->denoiser, b->radiance, ride.filtered);
    free(ride.filtered);
    const int filter[BK_RECEIVER_CLASSES] = {texels && !ride.done, b->denoised.glg_filtered, 0};
    if (!r) r = bk_denoiser_apply_classes(b->denoiser, b->radiance, filter);
    if (r) return bk_pipeline_failed(b, r, "denoising");
    return LBK_OK;
}

/* The sets' entries, denoised with the same weights as the base (bake/sets/set_entries.c). */
lbk_result bk_phase_emit_sets(bk_pipeline *b)
{
    bk_set_inputs in;
    bk_pipeline_set_inputs(b, &in);
    return bk_set_bakes_emit(&b->sets, &in, b->err, sizeof b->err);
}
