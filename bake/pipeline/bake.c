/* The bake pipeline: import → classify → atlas + texels → GLG / LLG placement → transport →
 * sets → encode. Each phase is its own module; this file wires them together behind
 * lbk_bake_from_file / lbk_bake_from_scene (lbk/bake.h), owns the presets, routes messages and
 * progress to the caller's callbacks, and decides which sections the scene needs. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/probes/glg_coarse.h"
#include "bake/dist/checkpoint.h"
#include "bake/dist/dist.h"
#include "bake/encode/encode.h"
#include "bake/pipeline/gather_limit.h"
#include "bake/pipeline/pipeline.h"
#include "bake/pipeline/error_map.h"
#include "bake/pipeline/provenance.h"
#include "scene/exr_read.h"
#include "scene/import.h"
#include "bake/pipeline/scene_desc.h"
#include "bake/denoise/denoise.h"
#include "scene/clock.h"
#include "lbk/bake_dist.h"

#define XXH_INLINE_ALL /* as the rest of the baker: liblbkbake links no xxhash of its own */
#include <xxhash.h>

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

/* Starts a phase: closes the previous one's time, then a checkpoint at 0. */
static lbk_result phase(bk_pipeline *b, lbk_bake_phase ph)
{
    double now = bk_now();
    if (b->phase_count > 0) b->phase_seconds[b->phase_count - 1] = now - b->phase_start;
    if (b->phase_count < BK_MAX_PHASES) b->phases[b->phase_count++] = ph;
    b->phase_start = now;
    return bk_pipeline_progress(b, 0) ? LBK_ERR_CANCELLED : LBK_OK;
}

static lbk_result checkpoint(bk_pipeline *b, double fraction)
{
    return bk_pipeline_progress(b, fraction) ? LBK_ERR_CANCELLED : LBK_OK;
}

static void import_warning(void *user, const char *message)
{
    bk_pipeline *b = user;
    bk_events_say(&b->events, LBK_BAKE_SEVERITY_WARNING, "%s", message);
}

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

/* ---- import ---------------------------------------------------------------------------- */

static lbk_result import_file(bk_pipeline *b, const char *path)
{
    bk_import_options io;
    memset(&io, 0, sizeof io);
    io.warn = import_warning;
    io.warn_user = b;
    io.allow_outside = b->opt->allow_outside;
    io.recentre = 1;
    FILE *probe = fopen(path, "rb");
    if (!probe) return bk_pipeline_fail(b, LBK_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    fclose(probe);
    char msg[512];
    if (bk_import_gltf(path, &io, &b->scene, msg, sizeof msg)) return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s", msg);
    return LBK_OK;
}

/* The desc's sky, when it overrides the scene's: a uniform radiance or an EXR. */
static lbk_result apply_sky(bk_pipeline *b)
{
    if (!b->opt->sky_override) return LBK_OK;
    if (!b->opt->sky_exr) {
        memcpy(b->scene.sky, b->opt->sky, sizeof b->scene.sky);
        b->scene.sky_image = -1;
        return LBK_OK;
    }
    char msg[512];
    bk_image im;
    memset(&im, 0, sizeof im);
    if (bk_exr_read(b->opt->sky_exr, (size_t)64 << 20, &im, msg, sizeof msg))
        return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "sky: %s", msg);
    if (bk_provenance_add_file(&b->scene, b->opt->sky_exr, "sky")) {
        free(im.rgba);
        return bk_pipeline_fail(b, LBK_ERR_IO, "sky: %s: cannot read it again to hash it", b->opt->sky_exr);
    }
    bk_image *n = realloc(b->scene.images, (b->scene.image_count + 1) * sizeof *n);
    if (!n) {
        free(im.rgba);
        return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    }
    b->scene.images = n;
    b->scene.images[b->scene.image_count] = im;
    b->scene.sky_image = (int)b->scene.image_count++;
    b->scene.sky[0] = b->scene.sky[1] = b->scene.sky[2] = 0;
    return LBK_OK;
}

/* A scene whose every triangle has zero area would bake to an empty container: refuse it. */
static int has_triangle_with_area(const bk_scene *s)
{
    for (size_t t = 0; t < s->tri_count; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++) p[k] = s->positions + 3 * (size_t)s->tris[3 * t + k];
        double e1[3], e2[3];
        for (int c = 0; c < 3; c++) e1[c] = (double)p[1][c] - p[0][c], e2[c] = (double)p[2][c] - p[0][c];
        double n0 = e1[1] * e2[2] - e1[2] * e2[1], n1 = e1[2] * e2[0] - e1[0] * e2[2], n2 = e1[0] * e2[1] - e1[1] * e2[0];
        if (n0 * n0 + n1 * n1 + n2 * n2 > 0) return 1;
    }
    return 0;
}

/* A level far from the origin (1e5 m) leaves floats a 7.8 mm step there, and ray offsets scale
 * with coordinate magnitude (~6 cm), which brightened such a level by 20 % (test_extremes).
 * So the bake runs in a frame centred on the level, and every stored position gets the origin
 * added back. The importer already chose the frame in double precision (bk_scene.origin); this
 * is for scenes given as floats (lbk_bake_from_scene). The shift is an integer number of metres, along each axis where the level lies
 * farther from the origin than twice its extent: then every p − c is exact in float (Sterbenz),
 * and so is p − c + c, so geometry hashes and written positions are unchanged. */
static void recentre(bk_pipeline *b)
{
    bk_scene *s = &b->scene;
    double extent = 0, c[3];
    int any = 0;
    for (int k = 0; k < 3; k++) extent = fmax(extent, (double)s->bounds_max[k] - s->bounds_min[k]);
    for (int k = 0; k < 3; k++) {
        /* per axis, so a level near the origin along an axis keeps its coordinates there */
        double mid = 0.5 * ((double)s->bounds_min[k] + s->bounds_max[k]);
        c[k] = isfinite(mid) && fabs(mid) > 2 * extent ? nearbyint(mid) : 0;
        any |= c[k] != 0;
    }
    for (int k = 0; k < 3; k++) b->origin[k] = (float)(s->origin[k] + c[k]); /* integers below 2^24: exact */
    if (!any) return;
    for (size_t v = 0; v < s->vertex_count; v++)
        for (int k = 0; k < 3; k++) s->positions[3 * v + k] = (float)((double)s->positions[3 * v + k] - c[k]);
    for (size_t i = 0; i < s->light_count; i++)
        for (int k = 0; k < 3; k++) s->lights[i].position[k] = (float)((double)s->lights[i].position[k] - c[k]);
    for (size_t i = 0; i < s->playable_count; i++)
        for (int k = 0; k < 3; k++) {
            s->playable[i].min[k] = (float)((double)s->playable[i].min[k] - c[k]);
            s->playable[i].max[k] = (float)((double)s->playable[i].max[k] - c[k]);
        }
    for (int k = 0; k < 3; k++) {
        s->bounds_min[k] = (float)((double)s->bounds_min[k] - c[k]);
        s->bounds_max[k] = (float)((double)s->bounds_max[k] - c[k]);
        s->origin[k] += c[k];
    }
}

void bk_pipeline_to_world(const bk_pipeline *b, const float local[3], float world[3])
{
    for (int k = 0; k < 3; k++) world[k] = local[k] + b->origin[k];
}

/* What every scene must have, however it came in. */
static lbk_result check_scene(bk_pipeline *b)
{
    if (b->scene.tri_count == 0) return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s: the scene has no triangles", b->input);
    if (!has_triangle_with_area(&b->scene))
        return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s: all %zu triangles are degenerate (zero area): nothing to light",
                                b->input, b->scene.tri_count);
    recentre(b);
    if (!bk_scene_has_light(&b->scene))
        return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT,
                                "%s: the scene has no light: no KHR_lights_punctual light, no emissive material "
                                "and no sky (add one, or give the bake a sky: lbk bake --sky R,G,B)",
                                b->input);
    return checkpoint(b, 1);
}

/* desc.expect_inputs: the files must be the ones listed, byte for byte (a distributed bake's
 * units and merge against the plan). Only what the import itself read is compared: no path of
 * the list is ever opened. */
static lbk_result check_inputs(bk_pipeline *b)
{
    const lbk_bake_input *want = b->opt->expect_inputs;
    if (!want) return LBK_OK;
    const size_t n = b->opt->expect_input_count, got = b->scene.input_count;
    for (size_t i = 0; i < n || i < got; i++) {
        const bk_input_file *f = i < got ? &b->scene.inputs[i] : NULL;
        const lbk_bake_input *w = i < n ? &want[i] : NULL;
        if (!f)
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "the bake read %zu files, the plan lists %zu (%s '%.200s' was not "
                                    "read): the scene changed since the plan was made; make a new plan", got, n, w->role,
                                    w->path);
        if (!w)
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s '%.200s' is not among the %zu files the plan lists: the scene "
                                    "changed since the plan was made; make a new plan", f->role, f->path, n);
        if (strncmp(f->path, w->path, sizeof w->path) || strncmp(f->role, w->role, sizeof w->role))
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "file %zu read is %s '%.200s', the plan lists %s '%.200s': the scene "
                                    "changed since the plan was made; make a new plan", i + 1, f->role, f->path, w->role,
                                    w->path);
        if (f->bytes != w->bytes || f->hash != w->xxh3)
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s '%.200s' changed since the plan was made (%llu bytes, XXH3 "
                                    "%016llx; the plan's: %llu bytes, %016llx): make a new plan", f->role, f->path,
                                    (unsigned long long)f->bytes, (unsigned long long)f->hash,
                                    (unsigned long long)w->bytes, (unsigned long long)w->xxh3);
    }
    return LBK_OK;
}

static lbk_result do_import(bk_pipeline *b, const char *path, const lbk_bake_scene *desc)
{
    lbk_result r = phase(b, LBK_BAKE_PHASE_IMPORT);
    if (r) return r;
    if (path) {
        r = import_file(b, path);
    } else {
        r = bk_scene_from_desc(desc, &b->events, &b->scene, b->err, sizeof b->err);
        if (r == LBK_ERR_OUT_OF_MEMORY) bk_pipeline_fail(b, r, "out of memory");
    }
    if (!r) r = apply_sky(b);
    if (!r) r = check_inputs(b);
    if (!r) r = check_scene(b);
    return r;
}

/* ---- layout ---------------------------------------------------------------------------- */

/* A representation per object; lightmapped[i] marks the atlas's objects. */
static lbk_result layout_classify(bk_pipeline *b, uint8_t *lightmapped, size_t *n_lm, size_t *n_llg)
{
    const bk_scene *s = &b->scene;
    lbk_result r = bk_classify_objects(s, NULL, b->classes);
    if (r) return bk_pipeline_failed(b, r, "classifying objects");
    *n_lm = *n_llg = 0;
    for (size_t i = 0; i < s->object_count; i++) {
        lightmapped[i] = b->classes[i].rep == BK_REP_LIGHTMAP;
        *n_lm += lightmapped[i];
        *n_llg += b->classes[i].rep == BK_REP_LLG;
        b->object_llg[i] = -1;
    }
    return LBK_OK;
}

static lbk_result layout_atlas(bk_pipeline *b, const uint8_t *lightmapped)
{
    const bk_scene *s = &b->scene;
    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.default_density = b->pre->texel_density;
    ao.density_override = b->opt->texel_density > 0 ? b->opt->texel_density : 0;
    ao.block_align = b->opt->block_align;
    lbk_result r = bk_atlas_build(s, lightmapped, &ao, &b->atlas);
    if (r == LBK_ERR_LIMIT) return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "lightmap atlas: %s", lbk_result_message(r));
    if (r) return bk_pipeline_failed(b, r, "lightmap atlas");
    if (b->atlas.note[0]) bk_events_say(&b->events, LBK_BAKE_SEVERITY_NOTE, "%s", b->atlas.note);
    if (!b->opt->no_seam_stitch && (r = bk_seams_find(s, &b->atlas, &b->seams)) != LBK_OK)
        return bk_pipeline_failed(b, r, "lightmap seams");
    for (size_t i = 0; i < b->atlas.object_count; i++)
        if (b->atlas.objects[i].note[0])
            bk_events_say(&b->events, LBK_BAKE_SEVERITY_NOTE, "object '%s': %s", s->objects[b->atlas.objects[i].object].name,
                          b->atlas.objects[i].note);
    return LBK_OK;
}

static lbk_result layout_texels(bk_pipeline *b)
{
    lbk_result r = bk_texels_build(&b->scene, &b->atlas, &b->texels);
    if (r) return bk_pipeline_failed(b, r, "lightmap texels");
    bk_pushout_options po;
    memset(&po, 0, sizeof po);
    po.threads = b->opt->threads ? b->opt->threads : 0;
    bk_pushout_stats ps;
    r = bk_texels_push_out(&b->texels, &b->scene, b->tracer, &po, &ps);
    return r ? bk_pipeline_failed(b, r, "texel push-out") : LBK_OK;
}

/* GLG: the level's empty space, for movers and volumetrics. */
static lbk_result layout_glg(bk_pipeline *b)
{
    bk_glg_options go;
    memset(&go, 0, sizeof go);
    go.spacing = b->opt->glg_spacing > 0 ? b->opt->glg_spacing : b->pre->glg_spacing;
    bk_glg_coarse coarse;
    memset(&coarse, 0, sizeof coarse);
    if (b->opt->glg_lighting) {   /* the density rule's coarse pass (bake/probes/glg_coarse.h) */
        coarse.scene = &b->scene;
        coarse.tracer = b->tracer;
        coarse.seed = b->opt->seed;
        coarse.threads = b->opt->threads;
        go.lighting = bk_glg_coarse_lighting;
        go.lighting_user = &coarse;
        go.lighting_threshold = b->opt->glg_lighting_threshold;
    }
    lbk_result r = bk_glg_build(&b->scene, b->tracer, &go, b->opt->threads, &b->glg);
    if (r) return bk_pipeline_failed(b, r, "global light grid");
    if (b->opt->glg_lighting)
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_INFO, "global light grid by lighting: coarse pass %.1f Mrays, %.2f s",
                      (double)coarse.rays * 1e-6, coarse.seconds);
    b->have_glg = b->glg.status == BK_GLG_OK && b->glg.probe_count >= 4 && b->glg.tet_count > 0;
    if (!b->have_glg) {
        static const char *why[] = {"ok", "the scene has no geometry", "there is no free space for 4 probes",
                                    "the free space is flat (one layer of probes)", "the tetrahedralisation failed"};
        int st = b->glg.status >= 0 && b->glg.status <= 4 ? b->glg.status : 4;
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_NOTE, "no global light grid: %s", why[st]);
    }
    return LBK_OK;
}

/* OCTP: clip levels around the playable space's centre (the level's when it has none), the
 * finest at the GLG's spacing, or finer in a small level (bake/probes/octa_bake.h). */
static lbk_result layout_octa(bk_pipeline *b)
{
    bk_octa_options oo;
    memset(&oo, 0, sizeof oo);
    const lbk_bake_desc *d = b->opt;
    oo.spacing = d->glg_spacing > 0 ? d->glg_spacing : b->pre->glg_spacing;
    /* at least 8 probes along the level's longest side: a small room gets a usable volume */
    float ext = 0;
    for (int a = 0; a < 3; a++) ext = fmaxf(ext, b->scene.bounds_max[a] - b->scene.bounds_min[a]);
    if (ext > 0 && ext / 8 < oo.spacing) oo.spacing = ext / 8;
    if (d->octp_spacing > 0) oo.spacing = d->octp_spacing;
    oo.levels = d->octp_levels > 0 ? (uint32_t)d->octp_levels : 0;
    oo.clip = d->octp_clip > 0 ? (uint32_t)d->octp_clip : 0;
    if (b->scene.playable_count) { /* the centre of the playable boxes' union */
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < b->scene.playable_count; i++)
            for (int a = 0; a < 3; a++) {
                lo[a] = fminf(lo[a], b->scene.playable[i].min[a]);
                hi[a] = fmaxf(hi[a], b->scene.playable[i].max[a]);
            }
        oo.has_centre = 1;
        for (int a = 0; a < 3; a++) oo.centre[a] = 0.5f * (lo[a] + hi[a]);
    }
    lbk_result r = bk_octa_place(&b->scene, b->tracer, b->scene.bounds_min, b->scene.bounds_max, &oo, &b->octa);
    return r ? bk_pipeline_failed(b, r, "octahedral probe volume") : LBK_OK;
}

/* LLGs for props; an object whose grid cannot be placed loses its lighting, with a warning. */
static lbk_result layout_llgs(bk_pipeline *b, size_t n_llg)
{
    const bk_scene *s = &b->scene;
    b->llgs = calloc(n_llg, sizeof *b->llgs);
    if (!b->llgs) return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    bk_llg_options lo;
    memset(&lo, 0, sizeof lo);
    lo.visibility_rays = b->pre->llg_visibility_rays;
    lo.min_dim = 3; /* bake/probes/PROBES.md §LLG fit */
    /* --llg-connected: twice the probes per axis for LLG objects that meet end to end */
    uint8_t *cand = NULL, *conn = NULL;
    if (b->opt->llg_connected) {
        cand = calloc(s->object_count ? s->object_count : 1, 1);
        conn = calloc(s->object_count ? s->object_count : 1, 1);
        if (!cand || !conn) {
            free(cand), free(conn);
            return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
        }
        for (size_t i = 0; i < s->object_count; i++) cand[i] = b->classes[i].rep == BK_REP_LLG;
        lbk_result r = bk_llg_connections(s, cand, 0, conn);
        if (r) {
            free(cand), free(conn);
            return bk_pipeline_failed(b, r, "connected LLG objects");
        }
    }
    size_t n_conn = 0;
    for (size_t i = 0; i < s->object_count; i++) {
        if (b->classes[i].rep != BK_REP_LLG) continue;
        lo.connected = conn ? conn[i] : 0;
        n_conn += lo.connected != 0;
        lbk_result r = bk_llg_place(s, (uint32_t)i, &lo, b->opt->threads, &b->llgs[b->llg_count]);
        if (r) {
            bk_events_say(&b->events, LBK_BAKE_SEVERITY_WARNING, "object '%s': no local light grid (%s)", s->objects[i].name,
                          lbk_result_message(r));
            b->classes[i].rep = BK_REP_NONE;
            continue;
        }
        b->object_llg[i] = (int32_t)b->llg_count++;
    }
    if (conn) bk_events_say(&b->events, LBK_BAKE_SEVERITY_NOTE, "%zu LLG objects connect to another: finer grids", n_conn);
    free(cand), free(conn);
    return LBK_OK;
}

static lbk_result do_layout(bk_pipeline *b)
{
    lbk_result r = phase(b, LBK_BAKE_PHASE_LAYOUT);
    if (r) return r;
    const size_t n_obj = b->scene.object_count ? b->scene.object_count : 1;
    b->classes = calloc(n_obj, sizeof *b->classes);
    b->object_llg = malloc(n_obj * sizeof *b->object_llg);
    uint8_t *lightmapped = calloc(n_obj, 1);
    size_t n_lm = 0, n_llg = 0;
    r = b->classes && b->object_llg && lightmapped ? LBK_OK : bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    if (!r) r = layout_classify(b, lightmapped, &n_lm, &n_llg);
    if (!r) r = checkpoint(b, 0.1);
    if (!r && n_lm) r = layout_atlas(b, lightmapped);
    free(lightmapped);
    if (!r) r = checkpoint(b, 0.4);
    if (!r) {
        r = bk_tracer_create(&b->scene, b->opt->threads, &b->tracer);
        if (r) r = bk_pipeline_failed(b, r, "ray tracer (Embree)");
    }
    if (!r && n_lm) r = layout_texels(b);
    if (!r) r = checkpoint(b, 0.6);
    if (!r && !b->opt->no_glg) r = layout_glg(b);
    if (!r && b->opt->octahedral_probes) r = layout_octa(b);
    if (!r) r = checkpoint(b, 0.8);
    if (!r && n_llg) r = layout_llgs(b, n_llg);
    if (!r) r = checkpoint(b, 1);
    return r;
}

/* ---- light ----------------------------------------------------------------------------- */

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
        memcpy(b->receivers[k].position, t->position, sizeof t->position);
        memcpy(b->receivers[k].normal, t->normal, sizeof t->normal);
        /* the texel's value is the average over its square (texels.h, Footprint) */
        b->receivers[k].footprint_first = t->footprint_first;
        b->receivers[k].footprint_count = t->footprint_count;
        memcpy(b->receivers[k].footprint_box, t->footprint_box, sizeof t->footprint_box);
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

/* The LLG class's estimate gains the fit's residual at its targets (bake/probes/PROBES.md §LLG
 * fit): the halves' difference sees the noise of the probes, not what the lattice cannot
 * represent, and that is what LLG objects get at run time. The residual also holds the targets'
 * own noise; its expected share is taken off where the transport measured it. */
static void llg_fit_error(bk_pipeline *b)
{
    const bk_llg_fit_stats *f = &b->llg_fit_stats;
    if (!f->targets || !(f->target_sum > 0)) return;
    const double n = (double)f->targets, mean = f->target_sum / n;
    /* without the targets' own noise where the transport measured it (b->variance: denoised bakes) */
    const double noise_sq = b->variance && b->opt->denoise != LBK_BAKE_DENOISE_OFF /* (not for --error-map alone: same bytes) */
                                ? bk_llg_fit_noise(&b->llg_fit, b->llgs, b->variance) : 0;
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
static lbk_result replay_failure(bk_pipeline *b, lbk_result r)
{
    if (bk_dist_error(b->dist)[0]) return bk_pipeline_fail(b, r, "%s", bk_dist_error(b->dist));
    if (r == LBK_ERR_BAD_INPUT)
        return bk_pipeline_fail(b, r, "the parts hold numbers no bake makes (sample counts, weights, accumulators or "
                                      "outputs negative, huge or not finite): a part is corrupt or forged");
    return LBK_OK;
}

static lbk_result do_transport(bk_pipeline *b)
{
    lbk_result r = phase(b, LBK_BAKE_PHASE_LIGHT);
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
    if (b->opt->denoise != LBK_BAKE_DENOISE_OFF) { /* only the denoised estimate reads them */
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
    r = bk_transport_run(&b->scene, b->tracer, b->receivers, b->receiver_count, &to, &out, &b->stats);
    bk_far_probes_free(&far);
    if (!r) bk_texels_match_irradiance(&b->texels, b->texel_of_receiver, b->texel_receivers, b->radiance, irradiance);
    if (!r) r = bk_llg_fit_run(&b->llg_fit, b->llgs, &b->scene, irradiance, b->radiance, b->llg_first, &b->llg_fit_stats);
    if (!r && b->opt->error_map) { /* before denoising: the transport's own estimate (error_map.h) */
        b->texel_rel_error = malloc((b->texel_receivers ? b->texel_receivers : 1) * sizeof *b->texel_rel_error);
        if (!b->texel_rel_error) r = LBK_ERR_OUT_OF_MEMORY;
        else bk_error_map_from_transport(b->variance, irradiance, b->texel_receivers, b->texel_rel_error);
    }
    free(irradiance);
    b->octa_rel_rmse = b->stats.octa_rel_rmse;
    b->octa_rays = b->stats.octa_rays;
    if (r && b->dist) {
        lbk_result d = replay_failure(b, r);
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

static lbk_result do_sets(bk_pipeline *b)
{
    lbk_result r = phase(b, LBK_BAKE_PHASE_SETS);
    if (r) return r;
    bk_set_inputs in;
    bk_pipeline_set_inputs(b, &in);
    return bk_set_bakes_run(&b->sets, &in, b->err, sizeof b->err);
}

/* What the denoised base delivers: the two halves through the same weights (bk_denoiser_error;
 * it reads the halves only, so it runs before the filter). The LLG class is not filtered and
 * keeps the base estimate with its fit residual. With --denoise auto (choose) a class whose
 * filtered estimate is not below its unfiltered one (the transport's) stays unfiltered and its
 * error is the transport's; do_denoise then filters the classes marked filtered. */
static lbk_result denoised_error(bk_pipeline *b, int choose)
{
    bk_transport_options to;
    transport_options(b, &to);
    bk_denoise_error e;
    lbk_result r = bk_denoiser_error(b->denoiser, b->halves, to.class_end, &e);
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

/* The denoising weights (texels and GLG probes) from the base + every light set and door (the
 * guide), applied to the base here and to every set by bk_set_bakes_emit with the same weights
 * (bake/denoise/DENOISE.md). */
static lbk_result do_denoise(bk_pipeline *b)
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
    lbk_result r = bk_denoiser_create(&in, &o, &b->denoiser);
    free(guide), free(guide_var);
    if (!r) r = denoised_error(b, b->opt->denoise == LBK_BAKE_DENOISE_AUTO);
    const int filter[BK_RECEIVER_CLASSES] = {b->denoised.texels_filtered, b->denoised.glg_filtered, 0};
    if (!r) r = bk_denoiser_apply_classes(b->denoiser, b->radiance, filter);
    if (r) return bk_pipeline_failed(b, r, "denoising");
    return LBK_OK;
}

/* The sets' entries, denoised with the same weights as the base (bake_sets.c). */
static lbk_result emit_sets(bk_pipeline *b)
{
    bk_set_inputs in;
    bk_pipeline_set_inputs(b, &in);
    return bk_set_bakes_emit(&b->sets, &in, b->err, sizeof b->err);
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

static lbk_result run(bk_pipeline *b, const char *path, const lbk_bake_scene *desc)
{
    lbk_result r = do_import(b, path, desc);
    if (!r && b->inputs_only) {
        r = bk_set_bakes_prepare(&b->sets, &b->scene, &b->events, b->err, sizeof b->err);
        return r ? r : list_inputs(b);
    }
    if (!r) r = do_layout(b);
    if (!r) r = bk_set_bakes_prepare(&b->sets, &b->scene, &b->events, b->err, sizeof b->err);
    if (!r) r = do_transport(b);
    if (!r && b->sets.set_count) {
        r = do_sets(b);
        if (r && b->dist) {
            lbk_result d = replay_failure(b, r);
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
            if (b->phase_count > 0) b->phase_seconds[b->phase_count - 1] = bk_now() - b->phase_start;
            return LBK_OK;
        }
    }
    if (!r) r = do_denoise(b);
    if (!r && b->sets.set_count) r = emit_sets(b);
    if (!r) r = phase(b, LBK_BAKE_PHASE_WRITE);
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
    if (b->phase_count > 0) b->phase_seconds[b->phase_count - 1] = bk_now() - b->phase_start;
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

static uint64_t options_hash(const lbk_bake_desc *options, int budgets);

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

static lbk_result bake(const char *path, const lbk_bake_scene *desc, const lbk_bake_desc *options, lbk_bake_output **out,
                       bk_dist *dist, void **part, size_t *part_size, lbk_bake_input **inputs, size_t *input_count,
                       uint32_t *runs)
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
    /* the octahedral volume's accumulators are neither in parts nor in checkpoints yet */
    if (!r && b->desc.gather_limit > 0 && (dist || b->desc.checkpoint_dir))
        r = bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT,
                             "a ray-length limit (--gather-limit) cannot be baked distributed or with checkpoints yet");
    if (!r && b->desc.octahedral_probes && (dist || b->desc.checkpoint_dir))
        r = bk_pipeline_fail(b, LBK_ERR_INVALID_ARGUMENT,
                             "octahedral probes (--octahedral) cannot be baked distributed or with checkpoints yet");
    if (!r && dist) r = check_dist(b);
    if (!r && !dist && b->desc.checkpoint_dir) {
        /* the budgets may change between a bake and its --continue; nothing else may */
        r = bk_ckpt_create(b->desc.checkpoint_dir, b->desc.resume, options_hash(&b->desc, 0), &b->ckpt, b->err, sizeof b->err);
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
    return bake(path, NULL, desc, out, NULL, NULL, NULL, NULL, NULL, NULL);
}

lbk_result lbk_bake_from_scene(const lbk_bake_scene *scene, const lbk_bake_desc *desc, lbk_bake_output **out)
{
    if (!scene) {
        if (out) *out = NULL;
        return LBK_ERR_INVALID_ARGUMENT;
    }
    return bake(NULL, scene, desc, out, NULL, NULL, NULL, NULL, NULL, NULL);
}

const char *lbk_bake_preset_name(lbk_bake_preset preset)
{
    return (unsigned)preset < LBK_BAKE_PRESET_COUNT_ ? bk_presets[preset].name : "unknown";
}

/* ---- distributed bakes (lbk/bake_dist.h) --------------------------------------------------- */

/* The identity of the options that shape a bake's bytes (not threads, callbacks, allocator):
 * a part baked with other options is refused by the merge instead of replayed under them. */
static void hash_str(XXH64_state_t *st, const char *s)
{
    XXH64_update(st, s ? s : "", s ? strlen(s) + 1 : 1);
}

static uint64_t options_hash(const lbk_bake_desc *options, int budgets)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    if (options) memcpy(&d, options, options->size && options->size < sizeof d ? options->size : sizeof d);
    XXH64_state_t *st = XXH64_createState();
    if (!st) return 0;
    XXH64_reset(st, 0x6c626b70);
    if (!budgets) d.target_error = d.time_limit = 0, d.max_samples = 0;
    const int64_t ints[] = {d.preset, (int64_t)d.seed, d.max_samples, d.max_bounces, d.sky_override, d.no_glg,
                            d.octahedral_probes, d.no_seam_stitch, d.door_method, d.denoise, d.timestamp, d.block_align};
    const double reals[] = {d.target_error, d.time_limit, d.texel_density, d.glg_spacing, d.sky[0], d.sky[1], d.sky[2],
                            d.dls_threshold};
    XXH64_update(st, ints, sizeof ints);
    XXH64_update(st, reals, sizeof reals);
    hash_str(st, d.sky_exr);
    hash_str(st, d.revision);
    hash_str(st, d.allow_outside);
    if (d.glg_lighting || d.glg_lighting_threshold > 0) { /* (absent from older hashes: same values) */
        const double gl[2] = {(double)d.glg_lighting, (double)d.glg_lighting_threshold};
        XXH64_update(st, gl, sizeof gl);
    }
    if (d.light_culling || d.light_culling_delta > 0) { /* (absent from older hashes: same values) */
        const double lc[2] = {(double)d.light_culling, d.light_culling_delta};
        XXH64_update(st, lc, sizeof lc);
    }
    if (d.glossy_vpl || d.glossy_vpl_photons || d.glossy_vpl_delta > 0) { /* (absent from older hashes) */
        const double gv[3] = {(double)d.glossy_vpl, (double)d.glossy_vpl_photons, d.glossy_vpl_delta};
        XXH64_update(st, gv, sizeof gv);
    }
    if (d.adaptive) { /* (absent from older hashes: on) */
        const int64_t ad = d.adaptive;
        XXH64_update(st, &ad, sizeof ad);
    }
    if (d.error_map) { /* units must record the variance the merge's map needs */
        const int64_t em = d.error_map;
        XXH64_update(st, &em, sizeof em);
    }
    /* the baker's version: another transport gives other values for the same options, so its
     * parts and checkpoints are refused rather than mixed with this one's (absent before 1.8.1) */
    const int64_t version[3] = {LBK_BAKE_LIBRARY_VERSION_MAJOR, LBK_BAKE_LIBRARY_VERSION_MINOR,
                                LBK_BAKE_LIBRARY_VERSION_PATCH};
    XXH64_update(st, version, sizeof version);
    uint64_t h = XXH64_digest(st);
    XXH64_freeState(st);
    return h;
}

lbk_result lbk_bake_unit_from_file(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash, uint32_t units,
                                   uint32_t unit, void **part, size_t *part_size)
{
    if (!part || !part_size) return LBK_ERR_INVALID_ARGUMENT;
    *part = NULL;
    *part_size = 0;
    if (!path || units == 0 || units > BK_PART_MAX_UNITS || unit >= units) return LBK_ERR_INVALID_ARGUMENT;
    bk_dist *d = NULL;
    lbk_result r = bk_dist_create(0, plan_hash, options_hash(desc, 1), units, unit, NULL, &d);
    if (r) return r;
    lbk_bake_output *out = NULL;
    r = bake(path, NULL, desc, &out, d, part, part_size, NULL, NULL, NULL);
    bk_dist_destroy(d);
    return r;
}

void lbk_bake_part_free(void *part) { free(part); }

lbk_result lbk_bake_inputs_from_file(const char *path, const lbk_bake_desc *desc, lbk_bake_input **inputs, size_t *count,
                                     uint32_t *runs)
{
    if (!inputs || !count) return LBK_ERR_INVALID_ARGUMENT;
    *inputs = NULL;
    *count = 0;
    if (runs) *runs = 0;
    if (!path) return LBK_ERR_INVALID_ARGUMENT;
    lbk_bake_output *out = NULL;
    return bake(path, NULL, desc, &out, NULL, NULL, NULL, inputs, count, runs);
}

void lbk_bake_inputs_free(lbk_bake_input *inputs) { free(inputs); }

lbk_result lbk_bake_part_check(const void *part, size_t size, uint64_t plan_hash, uint32_t units, lbk_bake_part_info *info,
                               char *err, size_t err_len)
{
    bk_part_view v;
    char why[256];
    lbk_result r = bk_part_parse(part, size, &v, why, sizeof why);
    if (r) {
        if (err && err_len) snprintf(err, err_len, "%s", r == LBK_ERR_OUT_OF_MEMORY ? "out of memory" : why);
        return r;
    }
    free(v.runs);
    if (info) {
        memset(info, 0, sizeof *info);
        info->plan_hash = v.plan_hash;
        info->units = v.units;
        info->unit = v.unit;
        info->runs = v.run_count;
        info->total_runs = v.total_runs;
        info->first_run = v.first_run;
        info->receivers = v.receiver_count;
        bk_dist_range(v.receiver_count, v.total_runs, v.units, v.unit, v.first_run, &info->first, &info->end);
    }
    if (plan_hash && v.plan_hash != plan_hash) {
        if (err && err_len)
            snprintf(err, err_len, "belongs to another plan (plan hash %016llx, this plan's is %016llx)",
                     (unsigned long long)v.plan_hash, (unsigned long long)plan_hash);
        return LBK_ERR_BAD_INPUT;
    }
    if (units && v.units != units) {
        if (err && err_len) snprintf(err, err_len, "is unit %u of %u, this plan has %u units", v.unit, v.units, units);
        return LBK_ERR_BAD_INPUT;
    }
    return LBK_OK;
}

static void say_error(const lbk_bake_desc *desc, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void say_error(const lbk_bake_desc *desc, const char *fmt, ...)
{
    if (!desc || !desc->message) return;
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    desc->message(desc->user, LBK_BAKE_SEVERITY_ERROR, text);
}

/* Every part checked and put in unit order before anything is baked: a bad set of parts is
 * refused in a second, not after the layout. */
static lbk_result order_parts(const lbk_bake_desc *desc, uint64_t plan_hash, uint32_t units, const void *const *parts,
                              const size_t *sizes, size_t count, bk_part_view *views)
{
    lbk_result r = LBK_OK;
    size_t k = 0;
    for (; k < count && !r; k++) {
        bk_part_view v;
        char why[256];
        r = bk_part_parse(parts[k], sizes[k], &v, why, sizeof why);
        if (r) {
            say_error(desc, "part %zu: %s", k + 1, r == LBK_ERR_OUT_OF_MEMORY ? "out of memory" : why);
            break;
        }
        if (v.plan_hash != plan_hash) {
            say_error(desc, "part %zu (unit %u) belongs to another plan (plan hash %016llx, this plan's is %016llx)", k + 1,
                      v.unit, (unsigned long long)v.plan_hash, (unsigned long long)plan_hash);
            r = LBK_ERR_BAD_INPUT;
        } else if (v.units != units) {
            say_error(desc, "part %zu is unit %u of %u, this plan has %u units", k + 1, v.unit, v.units, units);
            r = LBK_ERR_BAD_INPUT;
        } else if (views[v.unit].runs) {
            say_error(desc, "unit %u is given twice (parts %zu and another)", v.unit, k + 1);
            r = LBK_ERR_BAD_INPUT;
        } else if (v.receiver_count != views[0].receiver_count && views[0].runs) {
            say_error(desc, "part %zu (unit %u) has %llu receivers, unit 0 has %llu", k + 1, v.unit,
                      (unsigned long long)v.receiver_count, (unsigned long long)views[0].receiver_count);
            r = LBK_ERR_BAD_INPUT;
        }
        if (r) {
            free(v.runs);
            break;
        }
        views[v.unit] = v;
    }
    if (r) return r;
    char missing[256] = "";
    size_t nmiss = 0, len = 0;
    for (uint32_t u = 0; u < units; u++) {
        if (views[u].runs) continue;
        if (nmiss++ < 16 && len < sizeof missing - 16) len += (size_t)snprintf(missing + len, sizeof missing - len, "%s%u", nmiss > 1 ? ", " : "", u);
    }
    if (nmiss) {
        say_error(desc, "%zu of %u units missing: %s%s (lbk bake-unit PLAN K for each)", nmiss, units, missing, nmiss > 16 ? ", ..." : "");
        return LBK_ERR_BAD_INPUT;
    }
    for (uint32_t u = 1; u < units; u++)
        if (views[u].receiver_count != views[0].receiver_count || views[u].total_runs != views[0].total_runs) {
            say_error(desc, "unit %u's part disagrees with unit 0's (receivers, runs): the parts come from different "
                      "scenes, options or lbk versions", u);
            return LBK_ERR_BAD_INPUT;
        }
    return LBK_OK;
}

lbk_result lbk_bake_merge_from_file(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash, uint32_t units,
                                    const void *const *parts, const size_t *part_sizes, size_t part_count,
                                    lbk_bake_output **out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!path || units == 0 || units > BK_PART_MAX_UNITS || (part_count && (!parts || !part_sizes))) return LBK_ERR_INVALID_ARGUMENT;
    bk_part_view *views = calloc(units, sizeof *views);
    if (!views) return LBK_ERR_OUT_OF_MEMORY;
    lbk_result r = order_parts(desc, plan_hash, units, parts, part_sizes, part_count, views);
    bk_dist *d = NULL;
    const uint64_t oh = options_hash(desc, 1);
    for (uint32_t u = 0; !r && u < units; u++)
        if (views[u].options_hash != oh) {
            say_error(desc, "unit %u's part was baked with other bake options than this merge's (seed, samples, "
                      "density, ...): it belongs to another bake", u);
            r = LBK_ERR_BAD_INPUT;
        }
    if (!r) r = bk_dist_create(1, plan_hash, oh, units, 0, views, &d);
    if (!r) r = bake(path, NULL, desc, out, d, NULL, NULL, NULL, NULL, NULL);
    bk_dist_destroy(d);
    for (uint32_t u = 0; u < units; u++) free(views[u].runs);
    free(views);
    return r;
}
