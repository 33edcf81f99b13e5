/* The bake pipeline: import → classify → atlas + texels → GLG / LLG placement → transport →
 * sets → encode. Each phase is its own module; this file wires them together behind
 * lbk_bake_from_file / lbk_bake_from_scene (lbk/bake.h), owns the presets, checks the desc, and
 * routes messages and progress to the caller's callbacks. The phases: phase_import.c,
 * phase_layout.c, phase_light.c; the distributed bakes' calls (lbk/bake_dist.h): bake_dist.c. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "bake/dist/checkpoint.h"
#include "bake/dist/dist.h"
#include "bake/pipeline/pipeline.h"
#include "bake/denoise/denoise.h"
#include "scene/clock.h"

const bk_preset bk_presets[LBK_BAKE_PRESET_COUNT_] = {
    [LBK_BAKE_PRESET_FAST] = {"fast", 8.0f, 2.0f, 1024, 0.03, 32},
    [LBK_BAKE_PRESET_HIGH] = {"high", 16.0f, 1.0f, 16384, 0.01, 128},
};

/* The size of version 1 of lbk_bake_desc, what size 0 means. When fields are added, this stays
 * the offset of the first new one. */
#define BK_DESC_SIZE_V1 offsetof(lbk_bake_desc, block_align)

/* ---- talking to the caller ------------------------------------------------------------- */

lbk_result bk_pipeline_fail(bk_pipeline *b, lbk_result code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(b->err, sizeof b->err, fmt, ap);
    va_end(ap);
    return code;
}

lbk_result bk_pipeline_failed(bk_pipeline *b, lbk_result r, const char *what)
{
    if (r == LBK_ERR_CANCELLED) return r;
    bk_pipeline_fail(b, r, "%s: %s", what, lbk_result_message(r));
    return r == LBK_ERR_OUT_OF_MEMORY ? r : LBK_ERR_INTERNAL;
}

int bk_pipeline_progress(bk_pipeline *b, double fraction)
{
    if (b->cancelled) return 1;
    if (!b->opt->progress || b->phase_count == 0) return 0;
    lbk_bake_progress p;
    memset(&p, 0, sizeof p);
    p.phase = b->phases[b->phase_count - 1];
    p.fraction = fraction >= 0 ? (fraction <= 1 ? fraction : 1) : 0;
    p.elapsed_seconds = bk_now() - b->start;
    p.est_rel_rmse = b->est;
    if (b->opt->progress(b->opt->user, &p)) b->cancelled = 1;
    return b->cancelled;
}

static void events_message(void *user, lbk_bake_severity severity, const char *text)
{
    const bk_pipeline *b = user;
    if (b->opt->message) b->opt->message(b->opt->user, severity, text);
}

static int events_progress(void *user, double fraction)
{
    return bk_pipeline_progress(user, fraction);
}

/* The process's peak resident set so far, bytes (Linux reports ru_maxrss in KiB); 0 if unknown. */
static uint64_t peak_rss_bytes(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0 || ru.ru_maxrss < 0) return 0;
    return (uint64_t)ru.ru_maxrss * 1024u;
}

/* Ends the current phase: its wall time and the memory high-water mark it left. */
static void close_phase(bk_pipeline *b, double now)
{
    if (b->phase_count == 0) return;
    b->phase_seconds[b->phase_count - 1] = now - b->phase_start;
    b->phase_peak_rss[b->phase_count - 1] = peak_rss_bytes();
}

/* Starts a phase: closes the previous one's time, then a checkpoint at 0. */
lbk_result bk_pipeline_phase(bk_pipeline *b, lbk_bake_phase ph)
{
    double now = bk_now();
    close_phase(b, now);
    if (b->phase_count < BK_MAX_PHASES) b->phases[b->phase_count++] = ph;
    b->phase_start = now;
    return bk_pipeline_progress(b, 0) ? LBK_ERR_CANCELLED : LBK_OK;
}

lbk_result bk_pipeline_checkpoint(bk_pipeline *b, double fraction)
{
    return bk_pipeline_progress(b, fraction) ? LBK_ERR_CANCELLED : LBK_OK;
}

/* ---- the call -------------------------------------------------------------------------- */

static lbk_result list_inputs(bk_pipeline *b)
{
    const bk_scene *s = &b->scene;
    b->inputs = calloc(s->input_count ? s->input_count : 1, sizeof *b->inputs);
    if (!b->inputs) return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    for (size_t i = 0; i < s->input_count; i++) {
        snprintf(b->inputs[i].path, sizeof b->inputs[i].path, "%s", s->inputs[i].path);
        snprintf(b->inputs[i].role, sizeof b->inputs[i].role, "%s", s->inputs[i].role);
        b->inputs[i].bytes = s->inputs[i].bytes;
        b->inputs[i].xxh3 = s->inputs[i].hash;
    }
    b->input_count = s->input_count;
    b->transport_runs = (uint32_t)(1 + bk_set_bakes_transport_runs(&b->sets, (int)b->opt->door_method, NULL));
    return LBK_OK;
}

/* Per-receiver state freed as soon as its last phase is done, so that no two phases' largest
 * arrays are alive at once (issue 36's bytes per texel; DENOISE.md, "Memory"). The transport's
 * receivers (~56 B each) serve the base and set runs only. */
static void release_after_transport(bk_pipeline *b)
{
    free(b->receivers);
    b->receivers = NULL;
}

/* The denoiser (its geometry, charts, patches and weights: ~100 B per texel) and the halves
 * serve the estimates and the sets' entries; the write phase reads only the filtered values. */
static void release_before_write(bk_pipeline *b)
{
    bk_denoiser_destroy(b->denoiser);
    b->denoiser = NULL;
    free(b->halves);
    b->halves = NULL;
}

static lbk_result run(bk_pipeline *b, const char *path, const lbk_bake_scene *desc)
{
    lbk_result r = bk_phase_import(b, path, desc);
    if (!r && b->inputs_only) {
        r = bk_set_bakes_prepare(&b->sets, &b->scene, &b->events, b->err, sizeof b->err);
        return r ? r : list_inputs(b);
    }
    if (!r) r = bk_phase_layout(b);
    if (!r) r = bk_set_bakes_prepare(&b->sets, &b->scene, &b->events, b->err, sizeof b->err);
    if (!r) r = bk_phase_transport(b);
    if (!r && b->sets.set_count) {
        r = bk_phase_sets(b);
        if (r && b->dist) {
            lbk_result d = bk_pipeline_replay_failure(b, r);
            if (d) r = d;
        }
    }
    if (!r && b->dist && bk_dist_error(b->dist)[0]) r = bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s", bk_dist_error(b->dist));
    if (b->dist && !r) {
        /* a unit ends with its part; the merge checks it replayed every run of the parts */
        void *part = NULL;
        size_t part_size = 0;
        r = bk_dist_finish(b->dist, &part, &part_size, b->err, sizeof b->err);
        if (!r && part) {
            b->part = part;
            b->part_size = part_size;
            close_phase(b, bk_now());
            return LBK_OK;
        }
    }
    release_after_transport(b);
    if (!r) r = bk_phase_denoise(b);
    if (!r) r = bk_object_estimates(b);
    if (!r) r = bk_check_compare(b);
    if (!r && b->sets.set_count) r = bk_phase_emit_sets(b);
    release_before_write(b);
    if (!r) r = bk_pipeline_phase(b, LBK_BAKE_PHASE_WRITE);
    if (!r) r = bk_pipeline_encode(b);
    if (r && r != LBK_ERR_CANCELLED && b->ckpt && bk_ckpt_error(b->ckpt)[0])
        r = bk_pipeline_fail(b, bk_ckpt_code(b->ckpt), "%s", bk_ckpt_error(b->ckpt));
    if (!r && b->ckpt) {
        int runs = 0, passes = 0;
        bk_ckpt_counts(b->ckpt, &runs, &passes);
        if (b->opt->resume)
            bk_events_say(&b->events, LBK_BAKE_SEVERITY_NOTE, "resumed %d transport runs from %s (%d passes not traced again)",
                          runs, b->opt->checkpoint_dir, passes);
    }
    close_phase(b, bk_now());
    if (!r) r = bk_pipeline_report(b, b->out);
    if (r == LBK_ERR_OUT_OF_MEMORY && !b->err[0]) bk_pipeline_fail(b, r, "out of memory");
    return r;
}

static int finite_nonneg(double v) { return isfinite(v) && v >= 0; }

static lbk_result check_desc(bk_pipeline *b)
{
    const lbk_bake_desc *d = &b->desc;
#define BAD(...) return bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT, __VA_ARGS__)
    if ((unsigned)d->preset >= LBK_BAKE_PRESET_COUNT_) BAD("lbk_bake_desc.preset: unknown preset %d", (int)d->preset);
    if ((unsigned)d->door_method >= LBK_BAKE_DOOR_METHOD_COUNT_)
        BAD("lbk_bake_desc.door_method: unknown method %d", (int)d->door_method);
    if ((unsigned)d->denoise >= LBK_BAKE_DENOISE_COUNT_) BAD("lbk_bake_desc.denoise: unknown mode %d", (int)d->denoise);
    if (d->threads < 0) BAD("lbk_bake_desc.threads: %d is negative", d->threads);
    if (!isfinite(d->target_error)) BAD("lbk_bake_desc.target_error is not finite");
    if (!finite_nonneg(d->time_limit)) BAD("lbk_bake_desc.time_limit: %g is not a finite number >= 0", d->time_limit);
    if (d->max_samples < 0 || d->max_bounces < 0) BAD("lbk_bake_desc: max_samples and max_bounces must be >= 0");
    if (!(d->texel_density >= 0 && d->texel_density <= LBK_BAKE_TEXEL_DENSITY_MAX))
        BAD("lbk_bake_desc.texel_density: %g is not a number in [0, %g] (0: the default)", d->texel_density,
            LBK_BAKE_TEXEL_DENSITY_MAX);
    if (!finite_nonneg(d->glg_spacing)) BAD("lbk_bake_desc.glg_spacing: %g is not a finite number >= 0", d->glg_spacing);
    if (!finite_nonneg(d->glg_lighting_threshold))
        BAD("lbk_bake_desc.glg_lighting_threshold: %g is not a finite number >= 0", d->glg_lighting_threshold);
    if (!isfinite(d->dls_threshold)) BAD("lbk_bake_desc.dls_threshold is not finite");
    if (d->light_culling < -1 || d->light_culling > 1) BAD("lbk_bake_desc.light_culling: %d is not -1, 0 or 1", d->light_culling);
    if (!finite_nonneg(d->light_culling_delta) || d->light_culling_delta > 1e6)
        BAD("lbk_bake_desc.light_culling_delta: %g is not a finite number in [0, 1e6]", d->light_culling_delta);
    if (d->glossy_vpl < -1 || d->glossy_vpl > 1) BAD("lbk_bake_desc.glossy_vpl: %d is not -1, 0 or 1", d->glossy_vpl);
    if (d->adaptive < -1 || d->adaptive > 0) BAD("lbk_bake_desc.adaptive: %d is not -1 or 0", d->adaptive);
    if (d->glossy_vpl_photons < 0 || d->glossy_vpl_photons > (1 << 20))
        BAD("lbk_bake_desc.glossy_vpl_photons: %d is not in [0, 2^20]", d->glossy_vpl_photons);
    if (!finite_nonneg(d->glossy_vpl_delta) || d->glossy_vpl_delta > 1e6)
        BAD("lbk_bake_desc.glossy_vpl_delta: %g is not a finite number in [0, 1e6]", d->glossy_vpl_delta);
    if (d->max_page != 0 && (d->max_page < LBK_BAKE_MAX_PAGE_MIN || d->max_page > LBK_BAKE_MAX_PAGE_MAX))
        BAD("lbk_bake_desc.max_page: %d is not 0 or in [%d, %d]", d->max_page, LBK_BAKE_MAX_PAGE_MIN,
            LBK_BAKE_MAX_PAGE_MAX);
    /* a GLG section counts its probes in a u32 (spec/container.md §10); 4 make one tetrahedron */
    if (d->max_probes != 0 && (d->max_probes < 4 || d->max_probes > (1u << 28)))
        BAD("lbk_bake_desc.max_probes: %u is not 0 or in [4, 2^28]", d->max_probes);
    if (d->path_check < -1 || d->path_check > 1024)
        BAD("lbk_bake_desc.path_check: %d is not -1 (off), 0 (16) or in [1, 1024]", d->path_check);
    if (d->sky_override && !d->sky_exr)
        for (int k = 0; k < 3; k++)
            if (!finite_nonneg(d->sky[k]) || !(d->sky[k] < 1e30f)) BAD("lbk_bake_desc.sky: radiance must be finite and >= 0");
#undef BAD
    return LBK_OK;
}

/* The caller's desc at this library's size: a shorter one (an older caller) is zero-extended,
 * a longer one (a newer caller) is accepted when everything past what we know is zero. */
static lbk_result copy_desc(bk_pipeline *b, const lbk_bake_desc *d)
{
    memset(&b->desc, 0, sizeof b->desc);
    if (d) {
        size_t n = d->size ? d->size : BK_DESC_SIZE_V1;
        if (n < sizeof d->size) return LBK_ERR_INVALID_ARGUMENT; /* nothing in it can be trusted, not even message */
        memcpy(&b->desc, d, n < sizeof b->desc ? n : sizeof b->desc);
        for (size_t i = sizeof b->desc; i < n; i++)
            if (((const unsigned char *)d)[i])
                return bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT,
                                        "lbk_bake_desc: a field this library (%zu bytes of lbk_bake_desc) does not know is set",
                                        sizeof b->desc);
    }
    b->desc.size = sizeof b->desc;
    return check_desc(b);
}

static lbk_result output_create(bk_pipeline *b)
{
    lbk_allocator a;
    memset(&a, 0, sizeof a);
    if (b->opt->allocator && b->opt->allocator->alloc && b->opt->allocator->free) a = *b->opt->allocator;
    lbk_bake_output tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.allocator = a;
    b->out = bk_output_alloc(&tmp, sizeof *b->out);
    if (!b->out) return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    *b->out = tmp;
    return LBK_OK;
}

static void pipeline_free(bk_pipeline *b)
{
    bk_set_bakes_free(&b->sets);
    bk_denoiser_destroy(b->denoiser);
    free(b->variance);
    free(b->halves);
    free(b->object_est);
    free(b->llg_fit_grid);
    free(b->llg_est);
    free(b->object_filtered);
    free(b->check);
    free(b->check_group);
    free(b->check_weight);
    free(b->check_irradiance);
    free(b->check_variance);
    free(b->object_check);
    free(b->texel_rel_error);
    free(b->samples);
    free(b->radiance);
    free(b->texel_of_receiver);
    free(b->receivers);
    free(b->cell_size);
    bk_llg_fit_plan_free(&b->llg_fit);
    for (size_t i = 0; i < b->llg_count; i++) bk_llg_free(&b->llgs[i]);
    free(b->llgs);
    free(b->object_llg);
    bk_glg_free(&b->glg);
    bk_octa_volume_free(&b->octa);
    free(b->octa_irradiance);
    if (b->tracer) bk_tracer_destroy(b->tracer);
    bk_texels_free(&b->texels);
    bk_seams_free(&b->seams);
    bk_atlas_free(&b->atlas);
    free(b->classes);
    bk_scene_free(&b->scene);
}

/* What a distributed bake cannot cut (lbk/bake_dist.h): a stop that needs every receiver. */
static lbk_result check_dist(bk_pipeline *b)
{
    const lbk_bake_desc *d = &b->desc;
    if (d->time_limit > 0)
        return bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT,
                                "a distributed bake cannot have a time limit: the passes it allows depend on the machine, "
                                "so the units would not agree");
    return LBK_OK;
}

lbk_result bk_pipeline_bake(const char *path, const lbk_bake_scene *desc, const lbk_bake_desc *options,
                            lbk_bake_output **out, bk_dist *dist, void **part, size_t *part_size,
                            lbk_bake_input **inputs, size_t *input_count, uint32_t *runs)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    bk_pipeline *b = calloc(1, sizeof *b);
    if (!b) return LBK_ERR_OUT_OF_MEMORY;
    b->dist = dist;
    b->inputs_only = inputs != NULL;
    b->start = bk_now();
    b->est = -1;
    b->opt = &b->desc;
    b->events.message = events_message;
    b->events.progress = events_progress;
    b->events.user = b;
    b->scene.sky_image = -1;
    lbk_result r = copy_desc(b, options);
    b->pre = &bk_presets[r ? 0 : b->desc.preset];
    if (path) {
        const char *base = strrchr(path, '/');
        b->input = path;
        b->scene_name = base ? base + 1 : path;
    } else {
        b->input = b->scene_name = desc && desc->name && desc->name[0] ? desc->name : "scene";
    }
    if (!r && !path && !desc) r = bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT, "no scene");
    if (!r && b->desc.gather_limit > 0 && (dist || b->desc.checkpoint_dir))
        r = bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT,
                             "a ray-length limit (--gather-limit) cannot be baked distributed or with checkpoints yet");
    /* the octahedral volume's accumulators are not in checkpoints yet (parts hold its result) */
    if (!r && b->desc.octahedral_probes && b->desc.checkpoint_dir)
        r = bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT, "octahedral probes (--octahedral) cannot be baked with checkpoints yet");
    if (!r && dist) r = check_dist(b);
    if (!r && !dist && b->desc.checkpoint_dir) {
        /* the budgets may change between a bake and its --continue; nothing else may */
        r = bk_ckpt_create(b->desc.checkpoint_dir, b->desc.resume, bk_pipeline_options_hash(&b->desc, 0), &b->ckpt, b->err, sizeof b->err);
    } else if (!r && b->desc.resume) {
        r = bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT, "lbk_bake_desc.resume needs checkpoint_dir");
    }
    if (!r) r = output_create(b);
    if (!r) r = run(b, path, desc);
    if (r) {
        if (r != LBK_ERR_CANCELLED)
            bk_events_say(&b->events, LBK_BAKE_SEVERITY_ERROR, "%s", b->err[0] ? b->err : lbk_result_message(r));
        lbk_bake_output_free(b->out);
    } else if (b->inputs_only) {
        lbk_bake_output_free(b->out);
    } else if (part) {
        *part = b->part;
        *part_size = b->part_size;
        b->part = NULL;
        lbk_bake_output_free(b->out);
    } else {
        *out = b->out;
    }
    if (inputs && !r) {
        *inputs = b->inputs;
        *input_count = b->input_count;
        if (runs) *runs = b->transport_runs;
        b->inputs = NULL;
    }
    free(b->inputs);
    free(b->part);
    bk_ckpt_destroy(b->ckpt);
    pipeline_free(b);
    free(b);
    return r;
}

lbk_result lbk_bake_from_file(const char *path, const lbk_bake_desc *desc, lbk_bake_output **out)
{
    if (!path) {
        if (out) *out = NULL;
        return LBK_ERR_INVALID_ARGUMENT;
    }
    return bk_pipeline_bake(path, NULL, desc, out, NULL, NULL, NULL, NULL, NULL, NULL);
}

lbk_result lbk_bake_from_scene(const lbk_bake_scene *scene, const lbk_bake_desc *desc, lbk_bake_output **out)
{
    if (!scene) {
        if (out) *out = NULL;
        return LBK_ERR_INVALID_ARGUMENT;
    }
    return bk_pipeline_bake(NULL, scene, desc, out, NULL, NULL, NULL, NULL, NULL, NULL);
}

const char *lbk_bake_preset_name(lbk_bake_preset preset)
{
    return (unsigned)preset < LBK_BAKE_PRESET_COUNT_ ? bk_presets[preset].name : "unknown";
}
