/* lbk diff output: JSON (spec/diff-json.md), text, heatmap PNGs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "lbk/error_map.h"
#include "tools/inspect/diff.h"

static void hex64(uint64_t v, char out[17]) { snprintf(out, 17, "%016llx", (unsigned long long)v); }

static cJSON *num_or_null(double v) { return isfinite(v) ? cJSON_CreateNumber(v) : cJSON_CreateNull(); }

static cJSON *stats_json(const tl_err_stats *s, int texels)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "count", (double)s->count);
    cJSON_AddNumberToObject(o, "over_tolerance", (double)s->over);
    cJSON_AddNumberToObject(o, "over_share", s->count ? (double)s->over / (double)s->count : 0.0);
    cJSON_AddItemToObject(o, "max_abs", num_or_null(s->max_abs));
    cJSON_AddItemToObject(o, "mean_abs", num_or_null(tl_err_mean(s)));
    cJSON_AddItemToObject(o, "rel_rmse", num_or_null(tl_err_rel_rmse(s)));
    if (texels) {
        cJSON *at = cJSON_CreateArray();
        cJSON_AddItemToArray(at, cJSON_CreateNumber(s->max_x));
        cJSON_AddItemToArray(at, cJSON_CreateNumber(s->max_y));
        cJSON_AddItemToObject(o, "max_at", s->count ? at : (cJSON_Delete(at), cJSON_CreateNull()));
        if (s->has_region) {
            cJSON *r = cJSON_CreateObject();
            cJSON_AddNumberToObject(r, "x0", s->x0);
            cJSON_AddNumberToObject(r, "y0", s->y0);
            cJSON_AddNumberToObject(r, "x1", s->x1);
            cJSON_AddNumberToObject(r, "y1", s->y1);
            cJSON_AddItemToObject(o, "over_region", r);
        } else {
            cJSON_AddNullToObject(o, "over_region");
        }
    } else {
        if (s->count) cJSON_AddNumberToObject(o, "max_at", s->max_x);
        else cJSON_AddNullToObject(o, "max_at");
        if (s->has_region) {
            cJSON *r = cJSON_CreateObject();
            cJSON_AddNumberToObject(r, "first", s->x0);
            cJSON_AddNumberToObject(r, "last", s->x1);
            cJSON_AddItemToObject(o, "over_region", r);
        } else {
            cJSON_AddNullToObject(o, "over_region");
        }
    }
    return o;
}

static cJSON *noise_json(const tl_noise_stats *n)
{
    if (!n->evaluated) return cJSON_CreateNull();
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "class", tl_noise_class_get(n->cls)->name);
    cJSON_AddNumberToObject(o, "count", (double)n->count);
    cJSON_AddItemToObject(o, "mean_shift", num_or_null(n->mean_shift));
    cJSON_AddItemToObject(o, "z", num_or_null(n->z));
    cJSON_AddItemToObject(o, "rmse", num_or_null(n->rmse));
    cJSON *nz = cJSON_AddObjectToObject(o, "noise");
    cJSON_AddNumberToObject(nz, "a", n->noise_a);
    cJSON_AddNumberToObject(nz, "b", n->noise_b);
    cJSON_AddNumberToObject(nz, "common", n->noise_common);
    cJSON_AddNumberToObject(nz, "mean", n->noise_mean);
    cJSON_AddNumberToObject(nz, "model", n->noise_model);
    cJSON_AddNumberToObject(nz, "empirical", n->noise_empirical);
    cJSON_AddNumberToObject(o, "tested", (double)n->tested);
    cJSON_AddNumberToObject(o, "significant", (double)n->significant);
    cJSON_AddNumberToObject(o, "significant_share", n->significant_share);
    cJSON_AddItemToObject(o, "sample_rms", num_or_null(n->sample_rms));
    cJSON_AddNumberToObject(o, "extreme", (double)n->extreme);
    cJSON_AddBoolToObject(o, "count_test", n->count_test);
    cJSON_AddNumberToObject(o, "share_limit", n->share_limit);
    cJSON_AddBoolToObject(o, "shift_significant", n->shift_significant);
    cJSON_AddBoolToObject(o, "share_significant", n->share_significant);
    cJSON *ch = cJSON_AddObjectToObject(o, "chroma");
    cJSON *shift = cJSON_AddArrayToObject(ch, "shift");
    for (int k = 0; k < 3; k++) cJSON_AddItemToArray(shift, num_or_null(n->chroma_shift[k]));
    cJSON_AddItemToObject(ch, "noise", num_or_null(n->chroma_noise));
    cJSON_AddItemToObject(ch, "z", num_or_null(n->chroma_z));
    cJSON_AddBoolToObject(o, "chroma_significant", n->chroma_significant);
    cJSON_AddBoolToObject(o, "within_noise", n->within_noise);
    return o;
}

static const char *repr_name(uint32_t r) { return r >= LBK_REPRESENTATION_COUNT_ ? NULL : lbk_representation_name(r); }

static cJSON *rect_json(uint32_t page, const uint32_t rect[4])
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "page", page);
    cJSON_AddNumberToObject(o, "x", rect[0]);
    cJSON_AddNumberToObject(o, "y", rect[1]);
    cJSON_AddNumberToObject(o, "w", rect[2]);
    cJSON_AddNumberToObject(o, "h", rect[3]);
    return o;
}

static cJSON *side_json(uint32_t repr, uint32_t index, const uint32_t rect[4], uint64_t hash)
{
    if (repr >= LBK_REPRESENTATION_COUNT_) return cJSON_CreateNull();
    cJSON *o = cJSON_CreateObject();
    char h[17];
    hex64(hash, h);
    cJSON_AddStringToObject(o, "geometry_hash", h);
    cJSON_AddStringToObject(o, "representation", repr_name(repr));
    if (repr == LBK_REPRESENTATION_LIGHTMAP) cJSON_AddItemToObject(o, "rect", rect_json(index, rect));
    else if (repr == LBK_REPRESENTATION_LLG) cJSON_AddNumberToObject(o, "grid", index);
    return o;
}

static const char *space_name(uint32_t sp) { return sp == LBK_DLS_SPACE_TEXEL ? "texels" : sp == LBK_DLS_SPACE_GLG ? "glg" : "llg"; }

static cJSON *states_json(const uint32_t n[3])
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "active", n[LBK_OCTP_ACTIVE]);
    cJSON_AddNumberToObject(o, "inside", n[LBK_OCTP_INSIDE]);
    cJSON_AddNumberToObject(o, "no_nearby", n[LBK_OCTP_NO_NEARBY]);
    return o;
}

static cJSON *octp_json(const tl_diff_octp *d)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "status", tl_diff_status_name(d->status));
    cJSON_AddNumberToObject(o, "a_probes", d->count_a);
    cJSON_AddNumberToObject(o, "b_probes", d->count_b);
    cJSON_AddNumberToObject(o, "a_levels", d->levels_a);
    cJSON_AddNumberToObject(o, "b_levels", d->levels_b);
    const int both = d->status == TL_DIFF_SAME || d->status == TL_DIFF_CHANGED;
    cJSON_AddBoolToObject(o, "comparable", both && d->comparable);
    cJSON_AddItemToObject(o, "states_a", d->levels_a ? states_json(d->states_a) : cJSON_CreateNull());
    cJSON_AddItemToObject(o, "states_b", d->levels_b ? states_json(d->states_b) : cJSON_CreateNull());
    if (both && d->comparable) {
        cJSON_AddNumberToObject(o, "state_changes", d->state_changes);
        cJSON_AddNumberToObject(o, "moved", d->moved);
        cJSON_AddItemToObject(o, "lighting", stats_json(&d->lighting, 0));
        cJSON_AddItemToObject(o, "depth", stats_json(&d->depth, 0));
    } else {
        cJSON_AddNullToObject(o, "state_changes");
        cJSON_AddNullToObject(o, "moved");
        cJSON_AddNullToObject(o, "lighting");
        cJSON_AddNullToObject(o, "depth");
    }
    cJSON_AddItemToObject(o, "noise", noise_json(&d->noise));
    return o;
}

static void add_noise_model(cJSON *root, const tl_diff_result *r)
{
    if (r->mode == TL_DIFF_MODE_NOISE) {
        cJSON *nm = cJSON_AddObjectToObject(root, "noise_model");
        cJSON_AddNumberToObject(nm, "false_alarm", r->noise.false_alarm);
        cJSON_AddNumberToObject(nm, "k_mean", r->noise.k_mean);
        cJSON_AddNumberToObject(nm, "k_sample", r->noise.k_sample);
        cJSON_AddNumberToObject(nm, "k_chroma", r->noise.k_chroma);
        cJSON_AddNumberToObject(nm, "texel_spread", r->noise.texel_spread);
        /* schema 2's fields, kept: the GLG's sample spread, the texels' p₀ in units of α */
        cJSON_AddNumberToObject(nm, "probe_spread", tl_noise_class_get(TL_NOISE_GLG)->sample_spread);
        cJSON_AddNumberToObject(nm, "share_factor", tl_noise_class_get(TL_NOISE_TEXELS)->sample_rate / r->noise.false_alarm);
        cJSON_AddNumberToObject(nm, "common", r->noise.common);
        cJSON_AddNumberToObject(nm, "chroma_min_share", TL_NOISE_CHROMA_MIN_SHARE);
        cJSON *cl = cJSON_AddObjectToObject(nm, "classes");
        for (int k = 0; k < TL_NOISE_CLASS_COUNT_; k++) {
            const tl_noise_class_params *c = tl_noise_class_get(k);
            cJSON *co = cJSON_AddObjectToObject(cl, c->name);
            cJSON_AddNumberToObject(co, "mean_scale", c->mean_scale);
            cJSON_AddNumberToObject(co, "sample_spread", c->sample_spread);
            cJSON_AddNumberToObject(co, "sample_rate", c->sample_rate);
            cJSON_AddNumberToObject(co, "chroma_scale", c->chroma_scale);
            cJSON_AddNumberToObject(co, "chroma_common", c->chroma_common);
            cJSON_AddNumberToObject(co, "empirical_scale", c->empirical_scale);
            cJSON_AddNumberToObject(co, "floor_scale", c->floor_scale);
            cJSON_AddNumberToObject(co, "extreme_rate", c->extreme_rate);
        }
        cJSON *ra = cJSON_AddObjectToObject(nm, "rept_a"), *rb = cJSON_AddObjectToObject(nm, "rept_b");
        cJSON_AddNumberToObject(ra, "texel_rel_rmse", r->noise.rept[0][0]);
        cJSON_AddNumberToObject(ra, "probe_rel_rmse", r->noise.rept[0][1]);
        cJSON_AddNumberToObject(rb, "texel_rel_rmse", r->noise.rept[1][0]);
        cJSON_AddNumberToObject(rb, "probe_rel_rmse", r->noise.rept[1][1]);
        cJSON_AddNumberToObject(ra, "texel_level", r->noise.level_ref[0][0]);
        cJSON_AddNumberToObject(ra, "probe_level", r->noise.level_ref[0][1]);
        cJSON_AddNumberToObject(rb, "texel_level", r->noise.level_ref[1][0]);
        cJSON_AddNumberToObject(rb, "probe_level", r->noise.level_ref[1][1]);
    } else {
        cJSON_AddNullToObject(root, "noise_model");
    }
}

static void add_summary(cJSON *root, const tl_diff_result *r)
{
    cJSON *sum = cJSON_AddObjectToObject(root, "summary");
    cJSON_AddNumberToObject(sum, "objects_added", r->objects_added);
    cJSON_AddNumberToObject(sum, "objects_removed", r->objects_removed);
    cJSON_AddNumberToObject(sum, "objects_changed", r->objects_changed);
    cJSON_AddNumberToObject(sum, "pages_changed", r->pages_changed);
    cJSON_AddNumberToObject(sum, "light_sets_changed", r->sets_changed);
    cJSON_AddNumberToObject(sum, "doors_changed", r->doors_changed);
    cJSON_AddNumberToObject(sum, "sections_changed", r->sections_changed);
    cJSON_AddNumberToObject(sum, "params_changed", r->params_changed);
    cJSON_AddNumberToObject(sum, "texels_over_tolerance", (double)r->texels_over);
    cJSON_AddNumberToObject(sum, "probes_over_tolerance", (double)r->probes_over);
    cJSON_AddNumberToObject(sum, "beyond_noise", r->items_beyond_noise);
    cJSON_AddNumberToObject(sum, "inputs_changed", (double)r->change_count);
}

static cJSON *change_json(const tl_diff_change *c)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "kind", tl_change_kind_name(c->kind));
    cJSON_AddStringToObject(o, "status", tl_diff_status_name(c->status));
    cJSON_AddStringToObject(o, "name", c->name);
    if (c->a) cJSON_AddStringToObject(o, "a", c->a);
    else cJSON_AddNullToObject(o, "a");
    if (c->b) cJSON_AddStringToObject(o, "b", c->b);
    else cJSON_AddNullToObject(o, "b");
    cJSON_AddStringToObject(o, "what", c->what);
    return o;
}

static cJSON *object_json(const tl_diff_result *r, const tl_diff_object *d)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "name", d->name);
    if (d->renamed) cJSON_AddStringToObject(o, "b_name", d->name_b);
    else cJSON_AddNullToObject(o, "b_name");
    cJSON_AddStringToObject(o, "status", tl_diff_status_name(d->status));
    cJSON *flags = cJSON_AddArrayToObject(o, "changes");
    if (d->renamed) cJSON_AddItemToArray(flags, cJSON_CreateString("renamed"));
    if (d->geometry_changed) cJSON_AddItemToArray(flags, cJSON_CreateString("geometry"));
    if (d->representation_changed) cJSON_AddItemToArray(flags, cJSON_CreateString("representation"));
    if (d->rect_changed) cJSON_AddItemToArray(flags, cJSON_CreateString("placement"));
    if (r->mode == TL_DIFF_MODE_NOISE ? (d->noise.evaluated && !d->noise.within_noise) : d->lighting.over > 0)
        cJSON_AddItemToArray(flags, cJSON_CreateString("lighting"));
    cJSON *in = cJSON_AddArrayToObject(o, "inputs_changed");
    if (d->inputs_changed & TL_INPUT_GEOMETRY) cJSON_AddItemToArray(in, cJSON_CreateString("geometry"));
    if (d->inputs_changed & TL_INPUT_MATERIAL) cJSON_AddItemToArray(in, cJSON_CreateString("material"));
    if (d->inputs_changed & TL_INPUT_OPTIONS) cJSON_AddItemToArray(in, cJSON_CreateString("options"));
    cJSON_AddItemToObject(o, "a", side_json(d->repr_a, d->page_a, d->rect_a, d->hash_a));
    cJSON_AddItemToObject(o, "b", side_json(d->repr_b, d->page_b, d->rect_b, d->hash_b));
    cJSON_AddBoolToObject(o, "resampled", d->resampled);
    if (d->compared) cJSON_AddItemToObject(o, "lighting", stats_json(&d->lighting, d->repr_a == LBK_REPRESENTATION_LIGHTMAP));
    else cJSON_AddNullToObject(o, "lighting");
    cJSON_AddItemToObject(o, "noise", noise_json(&d->noise));
    return o;
}

static cJSON *page_json(const tl_diff_page *p)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "index", p->index);
    cJSON_AddStringToObject(o, "status", tl_diff_status_name(p->status));
    cJSON *sa = cJSON_CreateArray(), *sb = cJSON_CreateArray();
    cJSON_AddItemToArray(sa, cJSON_CreateNumber(p->wa));
    cJSON_AddItemToArray(sa, cJSON_CreateNumber(p->ha));
    cJSON_AddItemToArray(sb, cJSON_CreateNumber(p->wb));
    cJSON_AddItemToArray(sb, cJSON_CreateNumber(p->hb));
    cJSON_AddItemToObject(o, "a_size", sa);
    cJSON_AddItemToObject(o, "b_size", sb);
    cJSON_AddBoolToObject(o, "resized", p->resized);
    if (p->status == TL_DIFF_SAME || p->status == TL_DIFF_CHANGED) cJSON_AddItemToObject(o, "lighting", stats_json(&p->lighting, 1));
    else cJSON_AddNullToObject(o, "lighting");
    return o;
}

static cJSON *set_json(const tl_diff_set *d)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "name", d->name);
    cJSON_AddStringToObject(o, "status", tl_diff_status_name(d->status));
    cJSON_AddBoolToObject(o, "definition_changed", d->meta_changed);
    for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) {
        if (d->compared[sp]) cJSON_AddItemToObject(o, space_name(sp), stats_json(&d->lighting[sp], sp == LBK_DLS_SPACE_TEXEL));
        else if (d->not_comparable[sp]) cJSON_AddStringToObject(o, space_name(sp), "not comparable");
        else cJSON_AddNullToObject(o, space_name(sp));
    }
    cJSON *nz = cJSON_AddObjectToObject(o, "noise");
    for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++)
        cJSON_AddItemToObject(nz, space_name(sp), noise_json(&d->noise[sp]));
    return o;
}

char *tl_diff_json(const tl_diff_result *r, const char *path_a, const char *path_b)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "schema", "lbk-diff");
    cJSON_AddNumberToObject(root, "schema_version", TL_DIFF_SCHEMA_VERSION);
    cJSON_AddStringToObject(root, "a", path_a);
    cJSON_AddStringToObject(root, "b", path_b);
    cJSON *tol = cJSON_AddObjectToObject(root, "tolerance");
    cJSON_AddNumberToObject(tol, "abs", r->abs_tol);
    cJSON_AddNumberToObject(tol, "rel", r->rel_tol);
    cJSON_AddBoolToObject(root, "equal", !r->differ);
    cJSON_AddStringToObject(root, "mode", tl_diff_mode_name(r->mode));
    cJSON_AddStringToObject(root, "mode_reason", r->mode_reason ? r->mode_reason : "");
    add_noise_model(root, r);
    add_summary(root, r);
    cJSON *inputs = cJSON_AddArrayToObject(root, "inputs");
    for (size_t i = 0; i < r->change_count; i++) cJSON_AddItemToArray(inputs, change_json(&r->changes[i]));

    cJSON *secs = cJSON_AddArrayToObject(root, "sections");
    for (size_t i = 0; i < r->section_count; i++) {
        const tl_diff_section *s = &r->sections[i];
        cJSON *o = cJSON_CreateObject();
        char t[5];
        lbk_fourcc_string(s->type, t);
        cJSON_AddStringToObject(o, "type", t);
        cJSON_AddStringToObject(o, "status", tl_diff_status_name(s->status));
        cJSON_AddNumberToObject(o, "a_decoded_bytes", (double)s->a_decoded);
        cJSON_AddNumberToObject(o, "b_decoded_bytes", (double)s->b_decoded);
        cJSON_AddItemToArray(secs, o);
    }
    cJSON *params = cJSON_AddArrayToObject(root, "params");
    for (size_t i = 0; i < r->param_count; i++) {
        const tl_diff_param *p = &r->params[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "key", p->key);
        cJSON_AddStringToObject(o, "status", tl_diff_status_name(p->status));
        if (p->a) cJSON_AddStringToObject(o, "a", p->a);
        else cJSON_AddNullToObject(o, "a");
        if (p->b) cJSON_AddStringToObject(o, "b", p->b);
        else cJSON_AddNullToObject(o, "b");
        cJSON_AddItemToArray(params, o);
    }
    cJSON *objs = cJSON_AddArrayToObject(root, "objects");
    for (size_t i = 0; i < r->object_count; i++) cJSON_AddItemToArray(objs, object_json(r, &r->objects[i]));
    cJSON *pages = cJSON_AddArrayToObject(root, "pages");
    for (size_t i = 0; i < r->page_count; i++) cJSON_AddItemToArray(pages, page_json(&r->pages[i]));
    cJSON *glg = cJSON_AddObjectToObject(root, "glg");
    cJSON_AddStringToObject(glg, "status", tl_diff_status_name(r->glg.status));
    cJSON_AddNumberToObject(glg, "a_probes", r->glg.count_a);
    cJSON_AddNumberToObject(glg, "b_probes", r->glg.count_b);
    cJSON_AddBoolToObject(glg, "resampled", r->glg.resampled);
    if (r->glg.status == TL_DIFF_SAME || r->glg.status == TL_DIFF_CHANGED) cJSON_AddItemToObject(glg, "lighting", stats_json(&r->glg.lighting, 0));
    else cJSON_AddNullToObject(glg, "lighting");
    cJSON_AddItemToObject(glg, "noise", noise_json(&r->glg.noise));
    cJSON_AddItemToObject(root, "octp", octp_json(&r->octp));
    cJSON *sets = cJSON_AddArrayToObject(root, "light_sets");
    for (size_t i = 0; i < r->set_count; i++) cJSON_AddItemToArray(sets, set_json(&r->sets[i]));
    cJSON *doors = cJSON_AddArrayToObject(root, "doors");
    for (size_t i = 0; i < r->door_count; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", r->doors[i].name);
        cJSON_AddStringToObject(o, "status", tl_diff_status_name(r->doors[i].status));
        cJSON_AddItemToArray(doors, o);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    return text;
}

static void print_noise(FILE *f, const tl_noise_stats *n)
{
    if (!n->evaluated) return;
    fprintf(f, "\n    %s: shift %+.4f (z %+.2f, noise of the mean %.4f), rmse %.6g, significant %llu/%llu (%.3g%%, limit %.3g%%)",
            n->within_noise ? "within noise" : "BEYOND NOISE", n->mean_shift, n->z, n->noise_mean, n->rmse,
            (unsigned long long)n->significant, (unsigned long long)n->tested, 100 * n->significant_share,
            100 * n->share_limit);
    fprintf(f, "\n      chromaticity R %+.4f G %+.4f B %+.4f (z %.2f, noise %.4f)%s [%s]", n->chroma_shift[0],
            n->chroma_shift[1], n->chroma_shift[2], n->chroma_z, n->chroma_noise,
            n->chroma_significant ? " BEYOND NOISE" : "", tl_noise_class_get(n->cls)->name);
}

static void print_stats(FILE *f, const tl_err_stats *s, int texels)
{
    fprintf(f, "max %.6g  mean %.6g  rel-rmse %.6g  over %llu/%llu (%.3g%%)", s->max_abs, tl_err_mean(s),
            tl_err_rel_rmse(s), (unsigned long long)s->over, (unsigned long long)s->count,
            s->count ? 100.0 * (double)s->over / (double)s->count : 0.0);
    if (s->has_region) {
        if (texels) fprintf(f, "  region x %u..%u y %u..%u", s->x0, s->x1, s->y0, s->y1);
        else fprintf(f, "  probes %u..%u", s->x0, s->x1);
    }
}

static void print_octp(FILE *f, const tl_diff_octp *d, int verbose)
{
    if (d->status < 0 || (d->status == TL_DIFF_SAME && !verbose)) return;
    fprintf(f, "octp %s %u -> %u probes, %u -> %u levels", tl_diff_status_name(d->status), d->count_a, d->count_b,
            d->levels_a, d->levels_b);
    if (d->status != TL_DIFF_SAME && d->status != TL_DIFF_CHANGED) {
        fprintf(f, " (%s)\n", d->status == TL_DIFF_ADDED ? "only in B" : "only in A");
        return;
    }
    if (!d->comparable) {
        fprintf(f, "\n    not comparable (volume layout changed: form, levels, grid dims, origins or probe positions)\n");
        return;
    }
    fprintf(f, "\n    irradiance: ");
    print_stats(f, &d->lighting, 0);
    print_noise(f, &d->noise);
    fprintf(f, "\n    depth moments: ");
    print_stats(f, &d->depth, 0);
    fprintf(f, "\n    states: %u changed, %u moved", d->state_changes, d->moved);
    if (d->levels_a)
        fprintf(f, "; active %u -> %u, inside %u -> %u, no nearby geometry %u -> %u", d->states_a[0], d->states_b[0],
                d->states_a[1], d->states_b[1], d->states_a[2], d->states_b[2]);
    fprintf(f, "\n");
}

void tl_diff_print(FILE *f, const tl_diff_result *r, int verbose)
{
    if (r->mode == TL_DIFF_MODE_NOISE)
        fprintf(f, "%s (noise mode, false-alarm rate %g per item: %s)\n", r->differ ? "DIFFERENT" : "EQUAL within noise",
                r->noise.false_alarm, r->mode_reason);
    else
        fprintf(f, "%s (abs-tol %g, rel-tol %g; tolerance mode: %s)\n", r->differ ? "DIFFERENT" : "EQUAL within tolerance",
                r->abs_tol, r->rel_tol, r->mode_reason ? r->mode_reason : "");
    if (r->change_count) {
        fprintf(f, "inputs and options:");
        for (size_t i = 0; i < r->change_count; i++) fprintf(f, "%s%s", i ? "; " : " ", r->changes[i].what);
        fprintf(f, "\n");
    }
    fprintf(f, "objects: %u added, %u removed, %u changed; pages changed %u; light sets changed %u; doors changed %u\n",
            r->objects_added, r->objects_removed, r->objects_changed, r->pages_changed, r->sets_changed, r->doors_changed);
    if (r->mode == TL_DIFF_MODE_NOISE)
        fprintf(f, "items beyond noise %u (objects, the GLG, OCTP, light-set spaces)\n", r->items_beyond_noise);
    else
        fprintf(f, "texels over tolerance %llu, probes over tolerance %llu\n", (unsigned long long)r->texels_over,
                (unsigned long long)r->probes_over);
    for (size_t i = 0; i < r->section_count; i++) {
        const tl_diff_section *s = &r->sections[i];
        if (s->status == TL_DIFF_SAME && !verbose) continue;
        char t[5];
        lbk_fourcc_string(s->type, t);
        fprintf(f, "section %-4s %-8s %llu -> %llu decoded bytes", t, tl_diff_status_name(s->status),
                (unsigned long long)s->a_decoded, (unsigned long long)s->b_decoded);
        if (s->type == LBK_SECTION_TERR && (s->status == TL_DIFF_ADDED || s->status == TL_DIFF_REMOVED))
            fprintf(f, " (the per-texel error map is present in %s only: a diagnostic, not compared)",
                    s->status == TL_DIFF_ADDED ? "B" : "A");
        fputc('\n', f);
    }
    for (size_t i = 0; i < r->param_count; i++) {
        const tl_diff_param *p = &r->params[i];
        if ((p->a && strchr(p->a, '\n')) || (p->b && strchr(p->b, '\n'))) { /* lists: the inputs line says what */
            if (verbose) fprintf(f, "param %s %s\n", p->key, tl_diff_status_name(p->status));
            continue;
        }
        fprintf(f, "param %s %s: %s -> %s\n", p->key, tl_diff_status_name(p->status), p->a ? p->a : "(none)",
                p->b ? p->b : "(none)");
    }
    for (size_t i = 0; i < r->object_count; i++) {
        const tl_diff_object *d = &r->objects[i];
        if (d->status == TL_DIFF_SAME && !verbose) continue;
        fprintf(f, "object %s %s", d->name, tl_diff_status_name(d->status));
        if (d->renamed) fprintf(f, " (renamed to %s)", d->name_b);
        if (d->geometry_changed) fprintf(f, " (geometry changed)");
        if (d->representation_changed) fprintf(f, " (%s -> %s)", repr_name(d->repr_a), repr_name(d->repr_b));
        if (d->rect_changed) fprintf(f, " (placement changed%s)", d->resampled ? ", resampled" : "");
        if (d->inputs_changed)
            fprintf(f, " (inputs changed:%s%s%s)", d->inputs_changed & TL_INPUT_GEOMETRY ? " geometry" : "",
                    d->inputs_changed & TL_INPUT_MATERIAL ? " material" : "", d->inputs_changed & TL_INPUT_OPTIONS ? " options" : "");
        if (d->compared) {
            fprintf(f, "\n    ");
            print_stats(f, &d->lighting, d->repr_a == LBK_REPRESENTATION_LIGHTMAP);
            print_noise(f, &d->noise);
        }
        fprintf(f, "\n");
    }
    for (size_t i = 0; i < r->page_count; i++) {
        const tl_diff_page *p = &r->pages[i];
        if (p->status == TL_DIFF_SAME && !verbose) continue;
        fprintf(f, "page %u %s %ux%u -> %ux%u", p->index, tl_diff_status_name(p->status), p->wa, p->ha, p->wb, p->hb);
        if (p->status == TL_DIFF_SAME || p->status == TL_DIFF_CHANGED) {
            fprintf(f, "\n    ");
            print_stats(f, &p->lighting, 1);
        }
        fprintf(f, "\n");
    }
    if (r->glg.status >= 0 && (r->glg.status != TL_DIFF_SAME || verbose)) {
        fprintf(f, "glg %s %u -> %u probes%s", tl_diff_status_name(r->glg.status), r->glg.count_a, r->glg.count_b,
                r->glg.resampled ? " (resampled at A's probes)" : "");
        if (r->glg.status == TL_DIFF_SAME || r->glg.status == TL_DIFF_CHANGED) {
            fprintf(f, "\n    ");
            print_stats(f, &r->glg.lighting, 0);
            print_noise(f, &r->glg.noise);
        }
        fprintf(f, "\n");
    }
    print_octp(f, &r->octp, verbose);
    for (size_t i = 0; i < r->set_count; i++) {
        const tl_diff_set *d = &r->sets[i];
        if (d->status == TL_DIFF_SAME && !verbose) continue;
        fprintf(f, "light set %s %s%s\n", d->name, tl_diff_status_name(d->status), d->meta_changed ? " (definition changed)" : "");
        for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) {
            if (d->not_comparable[sp]) fprintf(f, "    %s: not comparable (layout changed)\n", space_name(sp));
            if (!d->compared[sp]) continue;
            fprintf(f, "    %s: ", space_name(sp));
            print_stats(f, &d->lighting[sp], sp == LBK_DLS_SPACE_TEXEL);
            print_noise(f, &d->noise[sp]);
            fprintf(f, "\n");
        }
    }
    for (size_t i = 0; i < r->door_count; i++)
        if (r->doors[i].status != TL_DIFF_SAME || verbose)
            fprintf(f, "door %s %s\n", r->doors[i].name, tl_diff_status_name(r->doors[i].status));
}

int tl_diff_heatmaps(const tl_diff_result *r, const char *dir, char err[TL_ERR_LEN])
{
    if (tl_mkdirs(dir, err)) return -1;
    for (size_t i = 0; i < r->page_count; i++) {
        const tl_diff_page *p = &r->pages[i];
        if (!p->error_map) continue;
        const size_t n = (size_t)p->wa * p->ha;
        double max_over = 0;
        for (size_t k = 0; k < n; k++)
            if (p->over_map[k] && isfinite(p->error_map[k]) && p->error_map[k] > max_over) max_over = p->error_map[k];
        uint8_t *rgb = malloc(n * 3);
        if (!rgb) {
            snprintf(err, TL_ERR_LEN, "out of memory");
            return -1;
        }
        for (size_t k = 0; k < n; k++) {
            uint8_t *c = rgb + 3 * k;
            float e = p->error_map[k];
            if (isnan(e)) { /* not compared (outside the common region of a resized page) */
                c[0] = c[1] = c[2] = 64;
            } else if (!p->over_map[k]) {
                c[0] = c[1] = c[2] = 0;
            } else if (!isfinite(e) || max_over <= 0) {
                tl_heat_color(1.0f, c);
            } else {
                tl_heat_color((float)(0.15 + 0.85 * e / max_over), c);
            }
        }
        char path[4096];
        snprintf(path, sizeof path, "%s/page_%03u.diff.png", dir, p->index);
        int rc = tl_png_write_rgb8(path, (int)p->wa, (int)p->ha, rgb, err);
        free(rgb);
        if (rc) return -1;
    }
    return 0;
}
