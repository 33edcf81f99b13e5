/* The bake report: filled from the pipeline as data (lbk_bake_report), and its JSON
 * (spec/bake-report-json.md, schema lbk-bake-report/1: fields are only ever added). */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "bake/pipeline/pipeline.h"
#include "scene/clock.h"
#include "lbk/dls.h"

static const char *const phase_names[LBK_BAKE_PHASE_COUNT_] = {
    [LBK_BAKE_PHASE_IMPORT] = "import", [LBK_BAKE_PHASE_LAYOUT] = "layout", [LBK_BAKE_PHASE_LIGHT] = "light",
    [LBK_BAKE_PHASE_SETS] = "sets",     [LBK_BAKE_PHASE_WRITE] = "write",
};

const char *lbk_bake_phase_name(lbk_bake_phase phase)
{
    return (unsigned)phase < LBK_BAKE_PHASE_COUNT_ ? phase_names[phase] : "unknown";
}

static void fill_transport(const bk_pipeline *b, lbk_bake_transport *t)
{
    t->seconds = b->stats.seconds;
    t->passes = b->stats.passes;
    t->rays = b->stats.rays;
    t->bounces = b->stats.bounces;
    t->bounce_ratio_q = b->stats.q;
    t->tail_fraction = b->stats.tail_fraction;
    t->cache_cells = b->stats.cells;
    t->nonfinite_dropped = b->stats.nonfinite;
    t->texel_channels_saturated = b->saturated;
    t->texel_channels_flushed = b->flushed;
    t->est_rel_rmse = b->stats.est_rel_rmse;
}

static void fill_counts(const bk_pipeline *b, lbk_bake_counts *c)
{
    c->objects = b->scene.object_count;
    c->texels = b->atlas.texels;
    c->pages = b->atlas.page_count;
    c->glg_probes = b->have_glg ? b->glg.probe_count : 0;
    c->llgs = b->llg_count;
    c->llg_probes = b->receiver_count - b->llg_first;
    c->light_sets = b->sets.set_count;
    c->doors = b->sets.door_count;
    c->file_bytes = b->container_bytes;
}

/* Each stored set's estimate (bk_set_bakes_estimates) as lbk_bake_set_estimate. */
static int fill_set_estimates(const bk_pipeline *b, lbk_bake_output *out, lbk_bake_report *r)
{
    size_t n;
    const bk_set_estimate *e = bk_set_bakes_estimates(&b->sets, &n);
    if (!n) return 0;
    out->set_estimates = bk_output_alloc(out, n * sizeof *out->set_estimates);
    out->set_names = bk_output_alloc(out, n * sizeof e->name);
    if (!out->set_estimates || !out->set_names) return 1;
    for (size_t i = 0; i < n; i++) {
        char *name = out->set_names + i * sizeof e->name;
        memcpy(name, e[i].name, sizeof e->name);
        const bk_denoise_error *x = &e[i].error;
        const int ft = e[i].filtered[BK_CLASS_TEXEL], fg = e[i].filtered[BK_CLASS_GLG];
        out->set_estimates[i] = (lbk_bake_set_estimate){
            name, e[i].set, e[i].kind, ft || fg,
            {{x->rel_rmse[BK_CLASS_TEXEL], x->rel_rmse[BK_CLASS_GLG], x->rel_rmse[BK_CLASS_LLG], x->probe_rel_rmse},
             x->noise[BK_CLASS_TEXEL], x->bias[BK_CLASS_TEXEL], x->noise[BK_CLASS_GLG], x->bias[BK_CLASS_GLG], x->seconds,
             ft, fg}};
    }
    r->set_estimates = out->set_estimates;
    r->set_estimate_count = n;
    return 0;
}

/* Each lightmapped object's estimate (object_errors.c), copied into the output. */
static int fill_object_estimates(const bk_pipeline *b, lbk_bake_output *out, lbk_bake_report *r)
{
    size_t n = 0;
    for (size_t o = 0; b->object_est && o < b->scene.object_count; o++) n += b->object_est[o].texels > 0;
    if (!n) return 0;
    const size_t name_len = sizeof b->scene.objects[0].name;
    out->object_estimates = bk_output_alloc(out, n * sizeof *out->object_estimates);
    out->object_names = bk_output_alloc(out, n * name_len);
    if (b->object_check) out->object_checks = bk_output_alloc(out, n * sizeof *out->object_checks);
    if (!out->object_estimates || !out->object_names || (b->object_check && !out->object_checks)) return 1;
    size_t k = 0;
    for (size_t o = 0; o < b->scene.object_count; o++) {
        if (!b->object_est[o].texels) continue;
        char *name = out->object_names + k * name_len;
        memcpy(name, b->scene.objects[o].name, name_len);
        name[name_len - 1] = 0;
        out->object_estimates[k] = b->object_est[o];
        out->object_estimates[k].name = name;
        if (b->object_check) out->object_checks[k] = b->object_check[o];
        k++;
    }
    r->object_estimates = out->object_estimates;
    r->object_estimate_count = n;
    r->object_checks = out->object_checks;
    if (b->object_check)
        r->check = (lbk_bake_check){(uint32_t)b->check_done, (uint32_t)b->stats.check_samples, b->stats.check_rays,
                                    b->check_level};
    return 0;
}

/* Each LLG prop's estimate (llg_fit_error), in scene object order, copied into the output. */
static int fill_llg_estimates(const bk_pipeline *b, lbk_bake_output *out, lbk_bake_report *r)
{
    if (!b->llg_est || !b->llg_count || !b->object_llg) return 0;
    const size_t name_len = sizeof b->scene.objects[0].name;
    out->llg_estimates = bk_output_alloc(out, b->llg_count * sizeof *out->llg_estimates);
    out->llg_names = bk_output_alloc(out, b->llg_count * name_len);
    if (!out->llg_estimates || !out->llg_names) return 1;
    size_t k = 0;
    for (size_t o = 0; o < b->scene.object_count && k < b->llg_count; o++) {
        if (b->object_llg[o] < 0) continue;
        char *name = out->llg_names + k * name_len;
        memcpy(name, b->scene.objects[o].name, name_len);
        name[name_len - 1] = 0;
        out->llg_estimates[k] = b->llg_est[b->object_llg[o]];
        out->llg_estimates[k].name = name;
        k++;
    }
    r->llg_estimates = out->llg_estimates;
    r->llg_estimate_count = k;
    return 0;
}

lbk_result bk_pipeline_report(const bk_pipeline *b, lbk_bake_output *out)
{
    lbk_bake_report *r = &out->report;
    memset(r, 0, sizeof *r);
    r->size = sizeof *r;
    size_t len = strlen(b->input);
    out->input = bk_output_alloc(out, len + 1);
    out->passes = bk_output_alloc(out, (b->sample_count ? b->sample_count : 1) * sizeof *out->passes);
    out->pass_errors = bk_output_alloc(out, (b->sample_count ? b->sample_count : 1) * sizeof *out->pass_errors);
    if (!out->input || !out->passes || !out->pass_errors) return LBK_ERR_OUT_OF_MEMORY;
    memcpy(out->input, b->input, len + 1);
    r->input = out->input;
    r->preset = b->opt->preset;
    r->seed = b->opt->seed;
    r->status = bk_pipeline_status(b);
    r->target_error = b->opt->target_error > 0 ? b->opt->target_error : b->pre->target_error;
    r->time_limit = b->opt->time_limit;
    for (size_t i = 0; i < b->sample_count; i++) {
        const bk_transport_sample *s = &b->samples[i];
        out->passes[i] = (lbk_bake_pass){s->pass, s->seconds, s->samples_per_receiver, s->est_rel_rmse, s->bounces};
    }
    r->passes = out->passes;
    r->pass_count = b->sample_count;
    r->pass_errors = out->pass_errors;
    for (size_t i = 0; i < b->sample_count; i++) {
        const bk_transport_sample *s = &b->samples[i];
        out->pass_errors[i] = (lbk_bake_class_errors){s->class_rel_rmse[BK_CLASS_TEXEL], s->class_rel_rmse[BK_CLASS_GLG],
                                                      s->class_rel_rmse[BK_CLASS_LLG], s->probe_rel_rmse};
    }
    r->errors = (lbk_bake_class_errors){b->stats.class_rel_rmse[BK_CLASS_TEXEL], b->stats.class_rel_rmse[BK_CLASS_GLG],
                                        b->stats.class_rel_rmse[BK_CLASS_LLG], b->stats.probe_rel_rmse};
    size_t nrun;
    const bk_set_run_error *runs = bk_set_bakes_run_errors(&b->sets, &nrun);
    if (nrun) {
        out->set_runs = bk_output_alloc(out, nrun * sizeof *out->set_runs);
        out->set_labels = bk_output_alloc(out, nrun * sizeof runs->label);
        if (!out->set_runs || !out->set_labels) return LBK_ERR_OUT_OF_MEMORY;
        for (size_t i = 0; i < nrun; i++) {
            char *label = out->set_labels + i * sizeof runs->label;
            memcpy(label, runs[i].label, sizeof runs->label);
            out->set_runs[i] = (lbk_bake_set_run){label, runs[i].est_rel_rmse,
                                                  {runs[i].class_rel_rmse[BK_CLASS_TEXEL], runs[i].class_rel_rmse[BK_CLASS_GLG],
                                                   runs[i].class_rel_rmse[BK_CLASS_LLG], runs[i].probe_rel_rmse},
                                                  runs[i].seconds};
        }
    }
    r->set_runs = out->set_runs;
    r->set_run_count = nrun;
    if (b->have_denoised) r->denoised = b->denoised;
    if (fill_set_estimates(b, out, r) || fill_object_estimates(b, out, r) || fill_llg_estimates(b, out, r))
        return LBK_ERR_OUT_OF_MEMORY;
    fill_transport(b, &r->transport);
    fill_counts(b, &r->counts);
    r->scales.lmap = r->counts.texels ? b->scale[0] : 0;
    r->scales.glg = r->counts.glg_probes ? b->scale[1] : 0;
    r->scales.llg = r->counts.llgs ? b->scale[2] : 0;
    r->scales.octp = b->octa.count && b->octa_irradiance ? b->octp_scale : 0;
    if (r->scales.octp > 0) {
        r->octp.probes = b->octa.count;
        for (uint32_t i = 0; i < b->octa.count; i++) {
            const lbk_octp_probe_info *in = &b->octa.info[i];
            r->octp.inside += in->state == LBK_OCTP_INSIDE;
            r->octp.no_nearby += in->state == LBK_OCTP_NO_NEARBY;
            r->octp.relocated += in->offset[0] != 0 || in->offset[1] != 0 || in->offset[2] != 0;
        }
        r->octp.rel_rmse = b->octa_rel_rmse;
        r->octp.rays = b->octa_rays;
        r->octp_levels = b->octa.level_count;
    }
    for (int i = 0; i < b->phase_count; i++) out->phases[i] = (lbk_bake_phase_time){b->phases[i], b->phase_seconds[i]};
    r->phases = out->phases;
    memcpy(out->phase_peak_rss, b->phase_peak_rss, sizeof out->phase_peak_rss);
    r->phase_peak_rss = out->phase_peak_rss;
    r->phase_count = (size_t)b->phase_count;
    r->seconds = bk_now() - b->start;
    return LBK_OK;
}

/* ---- JSON -------------------------------------------------------------------------------- */

static void json_transport(cJSON *root, const lbk_bake_report *r)
{
    const lbk_bake_transport *t = &r->transport;
    cJSON *st = cJSON_AddObjectToObject(root, "transport");
    cJSON_AddNumberToObject(st, "seconds", t->seconds);
    cJSON_AddNumberToObject(st, "passes", t->passes);
    cJSON_AddNumberToObject(st, "rays", (double)t->rays);
    cJSON_AddNumberToObject(st, "bounces", t->bounces);
    cJSON_AddNumberToObject(st, "bounce_ratio_q", t->bounce_ratio_q);
    cJSON_AddNumberToObject(st, "tail_fraction", t->tail_fraction);
    cJSON_AddNumberToObject(st, "cache_cells", (double)t->cache_cells);
    cJSON_AddNumberToObject(st, "nonfinite_dropped", (double)t->nonfinite_dropped);
    cJSON_AddNumberToObject(st, "texel_channels_saturated", (double)t->texel_channels_saturated);
    cJSON_AddNumberToObject(st, "texel_channels_flushed", (double)t->texel_channels_flushed);
}

static void json_counts(cJSON *root, const lbk_bake_report *r)
{
    /* the radiometric scale of each lighting section written (spec §5.7); 0: section absent */
    cJSON *sc = cJSON_AddObjectToObject(root, "scales");
    cJSON_AddNumberToObject(sc, "lmap", r->scales.lmap);
    cJSON_AddNumberToObject(sc, "glg", r->scales.glg);
    cJSON_AddNumberToObject(sc, "llg", r->scales.llg);
    cJSON_AddNumberToObject(sc, "octp", r->scales.octp);
    const lbk_bake_counts *n = &r->counts;
    cJSON *c = cJSON_AddObjectToObject(root, "counts");
    cJSON_AddNumberToObject(c, "objects", (double)n->objects);
    cJSON_AddNumberToObject(c, "texels", (double)n->texels);
    cJSON_AddNumberToObject(c, "pages", (double)n->pages);
    cJSON_AddNumberToObject(c, "glg_probes", (double)n->glg_probes);
    cJSON_AddNumberToObject(c, "llgs", (double)n->llgs);
    cJSON_AddNumberToObject(c, "llg_probes", (double)n->llg_probes);
    cJSON_AddNumberToObject(c, "light_sets", n->light_sets);
    cJSON_AddNumberToObject(c, "doors", n->doors);
    cJSON_AddNumberToObject(c, "file_bytes", (double)n->file_bytes);
}

/* "errors": {"texels", "glg", "llg", "probes"}: the estimated relative RMSE per receiver class. */
static void json_classes(cJSON *parent, const lbk_bake_class_errors *e)
{
    cJSON *o = cJSON_AddObjectToObject(parent, "errors");
    cJSON_AddNumberToObject(o, "texels", e->texels);
    cJSON_AddNumberToObject(o, "glg", e->glg);
    cJSON_AddNumberToObject(o, "llg", e->llg);
    cJSON_AddNumberToObject(o, "probes", e->probes);
}

static const char *const set_kind_names[LBK_DLS_KIND_COUNT_] = {"lights", "door_open", "door_closed", "combination"};

static void json_set_estimates(cJSON *root, const lbk_bake_report *r)
{
    cJSON *arr = cJSON_AddArrayToObject(root, "set_estimates");
    for (size_t i = 0; i < r->set_estimate_count; i++) {
        const lbk_bake_set_estimate *e = &r->set_estimates[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", e->name ? e->name : "");
        cJSON_AddNumberToObject(o, "set", e->set);
        cJSON_AddStringToObject(o, "kind", e->kind < LBK_DLS_KIND_COUNT_ ? set_kind_names[e->kind] : "unknown");
        cJSON_AddBoolToObject(o, "denoised", e->denoised);
        cJSON_AddBoolToObject(o, "texels_filtered", e->error.texels_filtered);
        cJSON_AddBoolToObject(o, "glg_filtered", e->error.glg_filtered);
        json_classes(o, &e->error.errors);
        cJSON_AddNumberToObject(o, "texel_noise", e->error.texel_noise);
        cJSON_AddNumberToObject(o, "texel_bias", e->error.texel_bias);
        cJSON_AddNumberToObject(o, "glg_noise", e->error.glg_noise);
        cJSON_AddNumberToObject(o, "glg_bias", e->error.glg_bias);
        cJSON_AddItemToArray(arr, o);
    }
}

/* "objects": each lightmapped object's estimate as stored (lbk_bake_object_estimate). */
static void json_object_estimates(cJSON *root, const lbk_bake_report *r)
{
    const int checked = r->size >= offsetof(lbk_bake_report, check) + sizeof r->check && r->object_checks;
    if (checked && r->check.receivers) {
        cJSON *c = cJSON_AddObjectToObject(root, "path_check");
        cJSON_AddNumberToObject(c, "texels", r->check.receivers);
        cJSON_AddNumberToObject(c, "samples", r->check.samples);
        cJSON_AddNumberToObject(c, "rays", (double)r->check.rays);
        cJSON_AddNumberToObject(c, "rel_rmse", r->check.rel_rmse);
    }
    cJSON *arr = cJSON_AddArrayToObject(root, "objects");
    for (size_t i = 0; i < r->object_estimate_count; i++) {
        const lbk_bake_object_estimate *e = &r->object_estimates[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", e->name ? e->name : "");
        cJSON_AddNumberToObject(o, "object", e->object);
        cJSON_AddNumberToObject(o, "texels", e->texels);
        cJSON_AddNumberToObject(o, "est_rel_rmse", e->rel_rmse);
        cJSON_AddNumberToObject(o, "noise", e->noise);
        cJSON_AddNumberToObject(o, "bias", e->bias);
        const lbk_bake_object_check *ck = checked ? &r->object_checks[i] : NULL;
        if (ck && ck->receivers) {
            cJSON *c = cJSON_AddObjectToObject(o, "check");
            cJSON_AddNumberToObject(c, "texels", ck->receivers);
            cJSON_AddNumberToObject(c, "rel_rmse", ck->rel_rmse);
            cJSON_AddNumberToObject(c, "low", ck->low);
            cJSON_AddNumberToObject(c, "high", ck->high);
        }
        cJSON_AddItemToArray(arr, o);
    }
}

/* "llg_objects": each LLG prop's estimate (lbk_bake_llg_estimate). */
static void json_llg_estimates(cJSON *root, const lbk_bake_report *r)
{
    cJSON *arr = cJSON_AddArrayToObject(root, "llg_objects");
    for (size_t i = 0; i < r->llg_estimate_count; i++) {
        const lbk_bake_llg_estimate *e = &r->llg_estimates[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", e->name ? e->name : "");
        cJSON_AddNumberToObject(o, "object", e->object);
        cJSON_AddNumberToObject(o, "targets", e->targets);
        cJSON_AddNumberToObject(o, "est_rel_rmse", e->rel_rmse);
        cJSON_AddNumberToObject(o, "noise", e->noise);
        cJSON_AddNumberToObject(o, "fit", e->fit);
        cJSON_AddItemToArray(arr, o);
    }
}

static cJSON *json_report(const lbk_bake_report *r, const char *container_path)
{
    /* a report struct from before the per-class fields were appended has none of them */
    const int appended = r->size >= offsetof(lbk_bake_report, set_run_count) + sizeof r->set_run_count;
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "schema", "lbk-bake-report/1");
    cJSON_AddStringToObject(root, "input", r->input ? r->input : "");
    cJSON_AddStringToObject(root, "output", container_path ? container_path : "");
    cJSON_AddStringToObject(root, "preset", lbk_bake_preset_name(r->preset));
    cJSON_AddNumberToObject(root, "seed", (double)r->seed);
    cJSON_AddStringToObject(root, "status", lbk_bake_status_name(r->status));
    cJSON_AddNumberToObject(root, "target_error", r->target_error);
    cJSON_AddNumberToObject(root, "time_limit", r->time_limit);
    cJSON *samples = cJSON_AddArrayToObject(root, "samples");
    for (size_t i = 0; i < r->pass_count; i++) {
        const lbk_bake_pass *s = &r->passes[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "seconds", s->seconds);
        cJSON_AddNumberToObject(o, "samples_per_receiver", s->samples_per_receiver);
        cJSON_AddNumberToObject(o, "est_rel_rmse", s->est_rel_rmse);
        cJSON_AddNumberToObject(o, "bounces", s->bounces);
        cJSON_AddNumberToObject(o, "pass", s->pass);
        if (appended && r->pass_errors) json_classes(o, &r->pass_errors[i]);
        cJSON_AddItemToArray(samples, o);
    }
    if (appended) json_classes(root, &r->errors);
    cJSON *sr = cJSON_AddArrayToObject(root, "set_runs");
    for (size_t i = 0; appended && i < r->set_run_count; i++) {
        const lbk_bake_set_run *e = &r->set_runs[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "label", e->label ? e->label : "");
        cJSON_AddNumberToObject(o, "est_rel_rmse", e->est_rel_rmse);
        json_classes(o, &e->classes);
        cJSON_AddNumberToObject(o, "seconds", e->seconds);
        cJSON_AddItemToArray(sr, o);
    }
    json_transport(root, r);
    json_counts(root, r);
    if (r->size >= offsetof(lbk_bake_report, octp) + sizeof r->octp && r->octp.probes) {
        cJSON *o = cJSON_AddObjectToObject(root, "octp");
        cJSON_AddNumberToObject(o, "probes", r->octp.probes);
        cJSON_AddNumberToObject(o, "inside", r->octp.inside);
        cJSON_AddNumberToObject(o, "no_nearby", r->octp.no_nearby);
        cJSON_AddNumberToObject(o, "relocated", r->octp.relocated);
        cJSON_AddNumberToObject(o, "rel_rmse", r->octp.rel_rmse);
        cJSON_AddNumberToObject(o, "rays_per_probe", r->octp.rays);
        if (r->size >= offsetof(lbk_bake_report, octp_levels) + sizeof r->octp_levels && r->octp_levels)
            cJSON_AddNumberToObject(o, "levels", r->octp_levels);
    }
    if (r->size >= offsetof(lbk_bake_report, set_estimate_count) + sizeof r->set_estimate_count && r->set_estimate_count)
        json_set_estimates(root, r);
    if (r->size >= offsetof(lbk_bake_report, denoised) + sizeof r->denoised && r->denoised.errors.texels + r->denoised.errors.glg > 0) {
        cJSON *o = cJSON_AddObjectToObject(root, "denoised");
        json_classes(o, &r->denoised.errors);
        cJSON_AddNumberToObject(o, "texel_noise", r->denoised.texel_noise);
        cJSON_AddNumberToObject(o, "texel_bias", r->denoised.texel_bias);
        cJSON_AddNumberToObject(o, "glg_noise", r->denoised.glg_noise);
        cJSON_AddNumberToObject(o, "glg_bias", r->denoised.glg_bias);
        cJSON_AddNumberToObject(o, "seconds", r->denoised.seconds);
        cJSON_AddBoolToObject(o, "texels_filtered", r->denoised.texels_filtered);
        cJSON_AddBoolToObject(o, "glg_filtered", r->denoised.glg_filtered);
    }
    if (r->size >= offsetof(lbk_bake_report, object_estimate_count) + sizeof r->object_estimate_count &&
        r->object_estimate_count)
        json_object_estimates(root, r);
    if (r->size >= offsetof(lbk_bake_report, llg_estimate_count) + sizeof r->llg_estimate_count && r->llg_estimate_count)
        json_llg_estimates(root, r);
    const uint64_t *rss = r->size >= offsetof(lbk_bake_report, phase_peak_rss) + sizeof r->phase_peak_rss
                              ? r->phase_peak_rss : NULL;
    cJSON *ph = cJSON_AddArrayToObject(root, "phases");
    for (size_t i = 0; i < r->phase_count; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", lbk_bake_phase_name(r->phases[i].phase));
        cJSON_AddNumberToObject(o, "seconds", r->phases[i].seconds);
        if (rss && rss[i]) { /* a high-water mark: the most the process held up to this phase's end */
            cJSON_AddNumberToObject(o, "peak_rss_bytes", (double)rss[i]);
            if (r->counts.texels)
                cJSON_AddNumberToObject(o, "peak_rss_bytes_per_texel", (double)rss[i] / (double)r->counts.texels);
        }
        cJSON_AddItemToArray(ph, o);
    }
    return root;
}

/* cJSON_Print's text (malloc'ed; cJSON has no per-call allocator), or NULL. */
static char *print_report(const lbk_bake_report *r, const char *container_path)
{
    cJSON *root = json_report(r, container_path);
    char *text = root ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    return text;
}

lbk_result lbk_bake_report_json(const lbk_bake_report *report, const char *container_path, const lbk_allocator *allocator,
                                char **text, size_t *size)
{
    if (!report || !text) return LBK_ERR_INVALID_ARGUMENT;
    *text = NULL;
    char *t = print_report(report, container_path);
    if (!t) return LBK_ERR_OUT_OF_MEMORY;
    size_t n = strlen(t);
    lbk_bake_output tmp;
    memset(&tmp, 0, sizeof tmp);
    if (allocator && allocator->alloc && allocator->free) tmp.allocator = *allocator;
    *text = bk_output_alloc(&tmp, n + 1);
    if (*text) memcpy(*text, t, n + 1);
    free(t);
    if (!*text) return LBK_ERR_OUT_OF_MEMORY;
    if (size) *size = n;
    return LBK_OK;
}

lbk_result lbk_bake_report_write_json(const lbk_bake_report *report, const char *container_path, const char *json_path)
{
    if (!report || !json_path) return LBK_ERR_INVALID_ARGUMENT;
    char *text = print_report(report, container_path);
    if (!text) return LBK_ERR_OUT_OF_MEMORY;
    FILE *f = fopen(json_path, "w");
    int ok = f && fputs(text, f) >= 0 && fputc('\n', f) != EOF;
    if (f && fclose(f)) ok = 0;
    free(text);
    return ok ? LBK_OK : LBK_ERR_IO;
}

