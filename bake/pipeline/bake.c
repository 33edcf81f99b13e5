/* The bake pipeline: import → classify → atlas + texels → GLG / LLG placement → transport →
 * encode → container. Each phase is its own module; this file only wires them together, owns
 * the presets, and decides which sections the scene needs. */
#include "bake/pipeline/bake.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "bake/layout/atlas.h"
#include "bake/sets/bake_sets.h"
#include "bake/layout/classify.h"
#include "bake/pipeline/encode.h"
#include "bake/scene/exr_read.h"
#include "bake/probes/glg_place.h"
#include "bake/scene/import.h"
#include "bake/probes/llg_place.h"
#include "bake/probes/octa_bake.h"
#include "bake/scene/scene.h"
#include "bake/layout/texels.h"
#include "bake/transport/tracer.h"
#include "bake/transport/transport.h"
#include "cli/cli.h"
#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/octa.h"
#include "lbk/report.h"
#include "lbk/sh.h"

/* What a preset sets; every field can be overridden from the command line. */
typedef struct preset {
    const char *name;
    float texel_density;   /* texels per metre */
    float glg_spacing;     /* metres (halved once near geometry) */
    int max_samples;       /* gather rays per receiver, both halves, whole run */
    double target_error;   /* relative RMSE */
    int llg_visibility_rays;
} preset;

static const preset presets[] = {
    {"fast", 8.0f, 2.0f, 1024, 0.03, 32},
    {"high", 16.0f, 1.0f, 16384, 0.01, 128},
};

typedef struct bake {
    const bk_bake_options *opt;
    const preset *pre;
    bk_progress *progress;
    char *err;
    size_t err_len;
    bk_scene scene;
    bk_object_class *classes;
    bk_atlas atlas;
    bk_texels texels;
    bk_tracer *tracer;
    bk_glg glg;
    int have_glg;
    bk_llg *llgs;
    size_t llg_count;
    int32_t *object_llg;            /* per scene object: LLG index or -1 */
    /* receivers handed to transport: valid texels, then GLG probes, then LLG probes */
    bk_receiver *receivers;
    size_t receiver_count, texel_receivers, glg_first, llg_first;
    uint32_t *texel_of_receiver;    /* receiver → index in texels.receivers */
    lbk_sh9_rgb *radiance;
    float *cell_size;               /* per scene triangle: the radiosity cache's cell size (texel size) */
    bk_transport_stats stats;
    bk_transport_sample *samples;
    size_t sample_count, sample_cap;
    double phase_seconds[8];
    const char *phase_names[8];
    int phase_count;
    double phase_start;
    bk_set_bakes sets;              /* dynamic light sets and doors (bake_sets.c) */
    float origin[3];                /* world position of the bake frame's origin (recentre()) */
    uint64_t saturated, flushed;    /* texel channels outside the R11G11B10F range (stored units) */
    float scale[3];                 /* LMAP, GLG, LLG scales (spec §5.7); DLS payloads use them */
    float octp_scale;
} bake;

static int fail(bake *b, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail(bake *b, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(b->err, b->err_len, fmt, ap);
    va_end(ap);
    return code;
}

static void phase(bake *b, const char *name)
{
    double now = bk_now();
    if (b->phase_count > 0) b->phase_seconds[b->phase_count - 1] = now - b->phase_start;
    if (b->phase_count < 8) b->phase_names[b->phase_count++] = name;
    b->phase_start = now;
    bk_progress_phase(b->progress, name);
}

static void import_warning(void *user, const char *message)
{
    bake *b = user;
    bk_progress_note(b->progress, "lbk bake: warning: %s", message);
}

static void transport_progress(void *user, const char *ph, double fraction)
{
    (void)ph;
    bake *b = user;
    bk_progress_update(b->progress, fraction);
}

static void base_albedo(void *user, uint32_t tri, float albedo[3])
{
    bake *b = user;
    bk_set_bakes_base_albedo(&b->sets, &b->scene, tri, albedo);
}

static void transport_report(void *user, const bk_transport_sample *s)
{
    bake *b = user;
    if (b->sample_count == b->sample_cap) {
        size_t cap = b->sample_cap ? 2 * b->sample_cap : 16;
        bk_transport_sample *n = realloc(b->samples, cap * sizeof *n);
        if (!n) return; /* the report loses a row; the bake goes on */
        b->samples = n;
        b->sample_cap = cap;
    }
    b->samples[b->sample_count++] = *s;
    bk_progress_note(b->progress, "  pass %d: %7.0f samples/receiver  est. error %6.2f%%  %2d bounces  %7.1f s",
                     s->pass, s->samples_per_receiver, 100 * s->est_rel_rmse, s->bounces, s->seconds);
}

/* ---- phases ---------------------------------------------------------------------------- */

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
 * added back. The shift is an integer number of metres, along each axis where the level lies
 * farther from the origin than twice its extent: then every p − c is exact in float (Sterbenz),
 * and so is p − c + c, so geometry hashes and written positions are unchanged. */
static void recentre(bake *b)
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
    if (!any) return;
    for (size_t v = 0; v < s->vertex_count; v++)
        for (int k = 0; k < 3; k++) s->positions[3 * v + k] = (float)((double)s->positions[3 * v + k] - c[k]);
    for (size_t i = 0; i < s->light_count; i++)
        for (int k = 0; k < 3; k++) s->lights[i].position[k] = (float)((double)s->lights[i].position[k] - c[k]);
    for (int k = 0; k < 3; k++) {
        s->bounds_min[k] = (float)((double)s->bounds_min[k] - c[k]);
        s->bounds_max[k] = (float)((double)s->bounds_max[k] - c[k]);
        b->origin[k] = (float)c[k];
    }
}

static void to_world(const bake *b, const float local[3], float world[3])
{
    for (int k = 0; k < 3; k++) world[k] = local[k] + b->origin[k];
}

static int do_import(bake *b)
{
    phase(b, "import");
    bk_import_options io;
    memset(&io, 0, sizeof io);
    io.warn = import_warning;
    io.warn_user = b;
    char msg[512];
    FILE *probe = fopen(b->opt->input, "rb");
    if (!probe) return fail(b, LBK_EXIT_IO, "%s: cannot open: %s", b->opt->input, strerror(errno));
    fclose(probe);
    if (bk_import_gltf(b->opt->input, &io, &b->scene, msg, sizeof msg))
        return fail(b, LBK_EXIT_INPUT, "%s", msg);
    if (b->opt->sky_exr) {
        bk_image im;
        memset(&im, 0, sizeof im);
        if (bk_exr_read(b->opt->sky_exr, (size_t)64 << 20, &im, msg, sizeof msg))
            return fail(b, LBK_EXIT_INPUT, "--sky: %s", msg);
        bk_image *n = realloc(b->scene.images, (b->scene.image_count + 1) * sizeof *n);
        if (!n) {
            free(im.rgba);
            return fail(b, LBK_EXIT_INTERNAL, "out of memory");
        }
        b->scene.images = n;
        b->scene.images[b->scene.image_count] = im;
        b->scene.sky_image = (int)b->scene.image_count++;
        b->scene.sky[0] = b->scene.sky[1] = b->scene.sky[2] = 0;
    } else if (b->opt->sky_set) {
        memcpy(b->scene.sky, b->opt->sky, sizeof b->scene.sky);
        b->scene.sky_image = -1;
    }
    if (b->scene.tri_count == 0) return fail(b, LBK_EXIT_INPUT, "%s: the scene has no triangles", b->opt->input);
    if (!has_triangle_with_area(&b->scene))
        return fail(b, LBK_EXIT_INPUT, "%s: all %zu triangles are degenerate (zero area): nothing to light",
                    b->opt->input, b->scene.tri_count);
    recentre(b);
    if (!bk_scene_has_light(&b->scene))
        return fail(b, LBK_EXIT_INPUT,
                    "%s: the scene has no light: no KHR_lights_punctual light, no emissive material "
                    "and no sky (add one, or pass --sky R,G,B)",
                    b->opt->input);
    bk_progress_update(b->progress, 1);
    return 0;
}

static float density_for(const bake *b)
{
    return b->opt->texel_density > 0 ? b->opt->texel_density : 0;
}

static int do_layout(bake *b)
{
    phase(b, "layout");
    const bk_scene *s = &b->scene;
    b->classes = calloc(s->object_count ? s->object_count : 1, sizeof *b->classes);
    uint8_t *lightmapped = calloc(s->object_count ? s->object_count : 1, 1);
    b->object_llg = malloc((s->object_count ? s->object_count : 1) * sizeof *b->object_llg);
    if (!b->classes || !lightmapped || !b->object_llg) {
        free(lightmapped);
        return fail(b, LBK_EXIT_INTERNAL, "out of memory");
    }
    lbk_result r = bk_classify_objects(s, NULL, b->classes);
    if (r) {
        free(lightmapped);
        return fail(b, LBK_EXIT_INTERNAL, "classifying objects: %s", lbk_result_message(r));
    }
    size_t n_lm = 0, n_llg = 0;
    for (size_t i = 0; i < s->object_count; i++) {
        lightmapped[i] = b->classes[i].rep == BK_REP_LIGHTMAP;
        n_lm += lightmapped[i];
        n_llg += b->classes[i].rep == BK_REP_LLG;
        b->object_llg[i] = -1;
    }
    bk_progress_update(b->progress, 0.1);

    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.default_density = b->pre->texel_density;
    ao.density_override = density_for(b);
    if (n_lm) {
        r = bk_atlas_build(s, lightmapped, &ao, &b->atlas);
        if (r) {
            free(lightmapped);
            return fail(b, r == LBK_ERR_LIMIT ? LBK_EXIT_INPUT : LBK_EXIT_INTERNAL, "lightmap atlas: %s",
                        lbk_result_message(r));
        }
        if (b->atlas.note[0]) bk_progress_note(b->progress, "lbk bake: note: %s", b->atlas.note);
        for (size_t i = 0; i < b->atlas.object_count; i++)
            if (b->atlas.objects[i].note[0])
                bk_progress_note(b->progress, "lbk bake: note: object '%s': %s",
                                 s->objects[b->atlas.objects[i].object].name, b->atlas.objects[i].note);
    }
    free(lightmapped);
    bk_progress_update(b->progress, 0.4);

    r = bk_tracer_create(s, b->opt->threads, &b->tracer);
    if (r) return fail(b, LBK_EXIT_INTERNAL, "ray tracer (Embree): %s", lbk_result_message(r));

    if (n_lm) {
        r = bk_texels_build(s, &b->atlas, &b->texels);
        if (r) return fail(b, LBK_EXIT_INTERNAL, "lightmap texels: %s", lbk_result_message(r));
        bk_pushout_options po;
        memset(&po, 0, sizeof po);
        po.threads = b->opt->threads ? b->opt->threads : 0;
        bk_pushout_stats ps;
        r = bk_texels_push_out(&b->texels, s, b->tracer, &po, &ps);
        if (r) return fail(b, LBK_EXIT_INTERNAL, "texel push-out: %s", lbk_result_message(r));
    }
    bk_progress_update(b->progress, 0.6);

    /* GLG: the level's empty space, for movers and volumetrics. */
    if (!b->opt->no_glg) {
        bk_glg_options go;
        memset(&go, 0, sizeof go);
        go.spacing = b->opt->glg_spacing > 0 ? b->opt->glg_spacing : b->pre->glg_spacing;
        r = bk_glg_build(s, b->tracer, &go, b->opt->threads, &b->glg);
        if (r) return fail(b, LBK_EXIT_INTERNAL, "global light grid: %s", lbk_result_message(r));
        b->have_glg = b->glg.status == BK_GLG_OK && b->glg.probe_count >= 4 && b->glg.tet_count > 0;
        if (!b->have_glg) {
            static const char *why[] = {"ok", "the scene has no geometry", "there is no free space for 4 probes",
                                        "the free space is flat (one layer of probes)", "the tetrahedralisation failed"};
            int st = b->glg.status >= 0 && b->glg.status <= 4 ? b->glg.status : 4;
            bk_progress_note(b->progress, "lbk bake: no global light grid: %s", why[st]);
        }
    }
    bk_progress_update(b->progress, 0.8);

    /* LLGs for props. */
    if (n_llg) {
        b->llgs = calloc(n_llg, sizeof *b->llgs);
        if (!b->llgs) return fail(b, LBK_EXIT_INTERNAL, "out of memory");
        bk_llg_options lo;
        memset(&lo, 0, sizeof lo);
        lo.visibility_rays = b->pre->llg_visibility_rays;
        for (size_t i = 0; i < s->object_count; i++) {
            if (b->classes[i].rep != BK_REP_LLG) continue;
            r = bk_llg_place(s, (uint32_t)i, &lo, b->opt->threads, &b->llgs[b->llg_count]);
            if (r) {
                bk_progress_note(b->progress, "lbk bake: warning: object '%s': no local light grid (%s)",
                                 s->objects[i].name, lbk_result_message(r));
                b->classes[i].rep = BK_REP_NONE;
                continue;
            }
            b->object_llg[i] = (int32_t)b->llg_count++;
        }
    }
    bk_progress_update(b->progress, 1);
    return 0;
}

static int build_receivers(bake *b)
{
    size_t n = 0;
    for (size_t i = 0; i < b->texels.count; i++) n += (b->texels.receivers[i].flags & BK_TEXEL_VALID) != 0;
    b->texel_receivers = n;
    b->glg_first = n;
    if (b->have_glg) n += b->glg.probe_count;
    b->llg_first = n;
    for (size_t g = 0; g < b->llg_count; g++) n += bk_llg_probe_count(&b->llgs[g]);
    b->receiver_count = n;
    b->receivers = calloc(n ? n : 1, sizeof *b->receivers);
    b->texel_of_receiver = calloc(b->texel_receivers ? b->texel_receivers : 1, sizeof *b->texel_of_receiver);
    b->radiance = calloc(n ? n : 1, sizeof *b->radiance);
    if (!b->receivers || !b->texel_of_receiver || !b->radiance) return fail(b, LBK_EXIT_INTERNAL, "out of memory");
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
    if (b->have_glg)
        for (size_t p = 0; p < b->glg.probe_count; p++, k++) memcpy(b->receivers[k].position, &b->glg.positions[3 * p], 12);
    for (size_t g = 0; g < b->llg_count; g++) {
        const bk_llg *l = &b->llgs[g];
        for (uint32_t z = 0; z < l->dims[2]; z++)
            for (uint32_t y = 0; y < l->dims[1]; y++)
                for (uint32_t x = 0; x < l->dims[0]; x++, k++) bk_llg_probe_position(l, x, y, z, b->receivers[k].position);
    }
    return 0;
}

static void bk_bake_transport_options(const bk_bake_options *opt, int preset_max_samples, double preset_target,
                               bk_transport_options *to)
{
    memset(to, 0, sizeof *to);
    to->seed = opt->seed;
    to->threads = opt->threads;
    to->max_bounces = opt->max_bounces;
    to->max_samples = opt->max_samples > 0 ? opt->max_samples : preset_max_samples;
    to->target_error = opt->target_error > 0 ? opt->target_error : preset_target;
    to->time_limit = opt->time_limit;
}

static void set_inputs(const bake *b, bk_set_inputs *in)
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
    in->llgs = b->llgs;
    in->llg_grids = b->llg_count;
    in->texel_of_receiver = b->texel_of_receiver;
    in->texels = &b->texels;
    in->atlas_margin = b->atlas.margin;
    in->base_radiance = b->radiance;
    bk_bake_transport_options(b->opt, b->pre->max_samples, b->pre->target_error, &in->transport);
    in->transport.cell_size = b->cell_size;
    in->transport.footprint = b->texels.footprint;
    in->transport.footprint_count = b->texels.footprint_count;
    in->transport.footprint_scene = &b->scene; /* door runs trace a scene without the door */
    in->base_samples_per_receiver = b->stats.samples_per_receiver;
    in->threshold = b->opt->dls_threshold;
    in->progress = b->progress;
    in->door_method = b->opt->door_method;
    memcpy(in->origin, b->origin, sizeof in->origin);
}

/* The radiosity cache as fine as the lightmap: cells of a lightmapped triangle are its object's
 * texel size (bake/transport/TRANSPORT.md §Bias); other triangles share the default budget. */
static int build_cell_sizes(bake *b)
{
    const bk_scene *s = &b->scene;
    b->cell_size = calloc(s->tri_count ? s->tri_count : 1, sizeof *b->cell_size);
    if (!b->cell_size) return fail(b, LBK_EXIT_INTERNAL, "out of memory");
    for (size_t t = 0; t < s->tri_count; t++) {
        uint32_t o = s->tri_object ? s->tri_object[t] : UINT32_MAX;
        int32_t slot = o < b->atlas.scene_object_count && b->atlas.object_slot ? b->atlas.object_slot[o] : -1;
        if (slot < 0) continue;
        float density = b->atlas.objects[slot].density;
        if (density > 0 && isfinite(density)) b->cell_size[t] = 1.0f / density;
    }
    return 0;
}

static int do_transport(bake *b)
{
    phase(b, "light");
    int rc = build_receivers(b);
    if (!rc) rc = build_cell_sizes(b);
    if (rc) return rc;
    bk_transport_options to;
    bk_bake_transport_options(b->opt, b->pre->max_samples, b->pre->target_error, &to);
    to.cell_size = b->cell_size;
    to.footprint = b->texels.footprint;
    to.footprint_count = b->texels.footprint_count;
    to.progress = transport_progress;
    to.report = transport_report;
    to.user = b;
    if (bk_set_bakes_base_hooks(&b->sets, &b->scene, &to)) to.albedo_hook = base_albedo;
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = b->radiance;
    lbk_result r = bk_transport_run(&b->scene, b->tracer, b->receivers, b->receiver_count, &to, &out, &b->stats);
    if (r) return fail(b, LBK_EXIT_INTERNAL, "light transport: %s", lbk_result_message(r));
    if (b->stats.nonfinite)
        bk_progress_note(b->progress, "lbk bake: warning: %llu non-finite samples were dropped",
                         (unsigned long long)b->stats.nonfinite);
    return 0;
}

typedef struct section_list {
    uint32_t type[16];
    void *data[16];
    size_t size[16];
    int count;
} section_list;

static void sections_free(section_list *sl)
{
    for (int i = 0; i < sl->count; i++) lbk_free(NULL, sl->data[i]);
    sl->count = 0;
}

static lbk_result sections_add(section_list *sl, uint32_t type, lbk_result r, void *data, size_t size)
{
    if (r) return r;
    sl->type[sl->count] = type;
    sl->data[sl->count] = data;
    sl->size[sl->count++] = size;
    return LBK_OK;
}

static lbk_result build_lmap(bake *b, section_list *sl)
{
    const bk_texels *tx = &b->texels;
    size_t nt = tx->count;
    lbk_ahd_linear *lin = calloc(nt ? nt : 1, sizeof *lin);
    uint8_t *has = calloc(nt ? nt : 1, 1);
    lbk_ahd_texel **pages = calloc(tx->page_count, sizeof *pages);
    lbk_lmap_page_desc *desc = calloc(tx->page_count, sizeof *desc);
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (!lin || !has || !pages || !desc) goto done;
    for (size_t k = 0; k < b->texel_receivers; k++) {
        uint32_t ti = b->texel_of_receiver[k];
        bk_texel_linear(&tx->receivers[ti], &b->radiance[k], &lin[ti]);
        has[ti] = 1;
    }
    /* the scale puts the brightest texel (base or any light set) at 2^13..2^14 stored */
    double set_max[3];
    bk_set_bakes_max(&b->sets, set_max);
    const float scale = b->scale[0] = bk_scale_for(fmax(bk_texel_max(lin, has, nt), set_max[0]));
    const float inv = 1.0f / scale;
    bk_count_out_of_range(lin, has, nt, inv, &b->saturated, &b->flushed);
    if (b->saturated)
        bk_progress_note(b->progress,
                         "lbk bake: warning: %llu texel channels exceed 65024 times the lightmap scale %g, the "
                         "largest R11G11B10F value, and are stored saturated",
                         (unsigned long long)b->saturated, (double)scale);
    if (b->flushed)
        bk_progress_note(b->progress,
                         "lbk bake: warning: %llu lit texel channels are below 2^-21 times the lightmap scale %g "
                         "and are stored as 0: the level's irradiance spans more than the format's range "
                         "(~7e10) within one lightmap",
                         (unsigned long long)b->flushed, (double)scale);
    r = bk_encode_pages(tx, b->atlas.margin, lin, has, inv, pages);
    if (r) goto done;
    for (size_t p = 0; p < tx->page_count; p++) {
        desc[p].width = (uint32_t)tx->pages[p].width;
        desc[p].height = (uint32_t)tx->pages[p].height;
        desc[p].texels = pages[p];
    }
    void *data;
    size_t size;
    r = lbk_lmap_build(desc, (uint32_t)tx->page_count, scale, NULL, &data, &size);
    r = sections_add(sl, LBK_SECTION_LMAP, r, data, size);
done:
    if (pages)
        for (size_t p = 0; p < tx->page_count; p++) free(pages[p]);
    free(pages), free(desc), free(lin), free(has);
    return r;
}

static lbk_result build_glg(bake *b, section_list *sl)
{
    uint8_t(*vis)[4] = calloc(b->glg.tet_count, sizeof *vis);
    float(*world)[3] = calloc(b->glg.probe_count, sizeof *world);
    if (!vis || !world) {
        free(vis), free(world);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    bk_glg_visibility_unorm8(&b->glg, vis);
    for (size_t i = 0; i < b->glg.probe_count; i++) to_world(b, &b->glg.positions[3 * i], world[i]);
    lbk_glg_desc d;
    memset(&d, 0, sizeof d);
    d.probe_count = (uint32_t)b->glg.probe_count;
    d.tetra_count = (uint32_t)b->glg.tet_count;
    d.positions = (const float(*)[3])world;
    d.probes = &b->radiance[b->glg_first];
    d.tetras = (const uint32_t(*)[4])b->glg.tets;
    d.adjacency = (const uint32_t(*)[4])b->glg.neighbours;
    d.visibility = (const uint8_t(*)[4])vis;
    double set_max[3];
    bk_set_bakes_max(&b->sets, set_max);
    d.scale = b->scale[1] = bk_scale_for(fmax(bk_probe_max(d.probes, d.probe_count), set_max[1]));
    void *data;
    size_t size;
    lbk_result r = lbk_glg_build(&d, NULL, &data, &size);
    free(vis), free(world);
    return sections_add(sl, LBK_SECTION_GLG, r, data, size);
}

static lbk_result build_octp(bake *b, section_list *sl)
{
    lbk_octp_probe_desc *p = calloc(b->glg.probe_count, sizeof *p);
    if (!p) return LBK_ERR_OUT_OF_MEMORY;
    float diag = 0;
    for (int a = 0; a < 3; a++) {
        float e = b->scene.bounds_max[a] - b->scene.bounds_min[a];
        diag += e * e;
    }
    diag = sqrtf(diag);
    if (!(diag > 0) || !isfinite(diag)) diag = 1;
    for (size_t i = 0; i < b->glg.probe_count; i++)
    {
        bk_octa_probe(b->tracer, &b->glg.positions[3 * i], &b->radiance[b->glg_first + i], diag, &p[i]);
        to_world(b, &b->glg.positions[3 * i], p[i].position);
    }
    void *data;
    size_t size;
    double m = 0;
    for (size_t i = 0; i < b->glg.probe_count; i++)
        for (int t = 0; t < 16; t++)
            for (int c = 0; c < 3; c++)
                if (p[i].irradiance[t][c] > m && isfinite(p[i].irradiance[t][c])) m = p[i].irradiance[t][c];
    b->octp_scale = bk_scale_for(m);
    lbk_result r = lbk_octp_build(p, (uint32_t)b->glg.probe_count, b->octp_scale, NULL, &data, &size);
    free(p);
    return sections_add(sl, LBK_SECTION_OCTP, r, data, size);
}

static lbk_result build_llg(bake *b, section_list *sl)
{
    lbk_llg_grid_desc *g = calloc(b->llg_count, sizeof *g);
    lbk_llg_vertex **verts = calloc(b->llg_count, sizeof *verts);
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (!g || !verts) goto done;
    size_t probe = b->llg_first;
    for (size_t i = 0; i < b->llg_count; i++) {
        const bk_llg *l = &b->llgs[i];
        to_world(b, l->centre, g[i].centre);
        memcpy(g[i].axes, l->axes, sizeof g[i].axes);
        memcpy(g[i].half_extent, l->half_extents, sizeof g[i].half_extent);
        memcpy(g[i].dims, l->dims, sizeof g[i].dims);
        g[i].probes = &b->radiance[probe];
        probe += bk_llg_probe_count(l);
        verts[i] = calloc(l->vertex_count ? l->vertex_count : 1, sizeof **verts);
        if (!verts[i]) goto done;
        bk_llg_vertex_records(l, verts[i]);
        g[i].vertices = verts[i];
        g[i].vertex_count = (uint32_t)l->vertex_count;
    }
    void *data;
    size_t size;
    double set_max[3];
    bk_set_bakes_max(&b->sets, set_max);
    b->scale[2] = bk_scale_for(fmax(bk_probe_max(&b->radiance[b->llg_first], b->receiver_count - b->llg_first), set_max[2]));
    r = lbk_llg_build(g, (uint32_t)b->llg_count, b->scale[2], NULL, &data, &size);
    r = sections_add(sl, LBK_SECTION_LLG, r, data, size);
done:
    if (verts)
        for (size_t i = 0; i < b->llg_count; i++) free(verts[i]);
    free(verts), free(g);
    return r;
}

typedef struct named {
    const char *name;
    uint32_t index;
} named;

static int by_name_then_index(const void *a, const void *b)
{
    const named *x = a, *y = b;
    int c = strcmp(x->name, y->name);
    return c ? c : (x->index > y->index) - (x->index < y->index);
}

/* OBJS names must be unique for tools to match objects across revisions (spec §8.2): the k-th
 * repeat of a name in scene order becomes "name#k" (k from 2). */
static int unique_names(const bk_scene *s, char (*names)[sizeof s->objects[0].name + 24])
{
    size_t n = s->object_count;
    named *order = malloc((n ? n : 1) * sizeof *order);
    if (!order) return -1;
    for (size_t i = 0; i < n; i++) order[i] = (named){s->objects[i].name, (uint32_t)i};
    qsort(order, n, sizeof *order, by_name_then_index);
    size_t k = 1;
    for (size_t i = 0; i < n; i++) {
        k = i > 0 && !strcmp(order[i - 1].name, order[i].name) ? k + 1 : 1;
        if (k == 1)
            snprintf(names[order[i].index], sizeof names[0], "%s", order[i].name);
        else
            snprintf(names[order[i].index], sizeof names[0], "%s#%zu", order[i].name, k);
    }
    free(order);
    return 0;
}

static lbk_result build_objects(bake *b, section_list *sl)
{
    const bk_scene *s = &b->scene;
    lbk_object *objs = calloc(s->object_count ? s->object_count : 1, sizeof *objs);
    char(*names)[sizeof s->objects[0].name + 24] = calloc(s->object_count ? s->object_count : 1, sizeof *names);
    float *xyz = NULL;
    size_t xyz_cap = 0;
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (!objs || !names || unique_names(s, names)) goto done;
    for (size_t i = 0; i < s->object_count; i++) {
        const bk_object *o = &s->objects[i];
        lbk_object *t = &objs[i];
        t->name.data = names[i];
        t->name.size = strlen(names[i]);
        if (o->tri_count > xyz_cap) {
            free(xyz);
            xyz_cap = o->tri_count;
            xyz = malloc(xyz_cap * 9 * sizeof *xyz);
            if (!xyz) goto done;
        }
        for (uint32_t k = 0; k < o->tri_count; k++)
            for (int c = 0; c < 3; c++)
                to_world(b, &s->positions[3 * (size_t)s->tris[3 * ((size_t)o->first_tri + k) + c]], &xyz[9 * k + 3 * c]);
        t->geometry_hash = lbk_objects_geometry_hash(xyz, o->tri_count);
        t->representation = LBK_REPRESENTATION_NONE;
        int32_t slot = b->atlas.object_slot && i < b->atlas.scene_object_count ? b->atlas.object_slot[i] : -1;
        if (b->classes[i].rep == BK_REP_LIGHTMAP && slot >= 0 && b->atlas.objects[slot].page >= 0) {
            const bk_atlas_object *ao = &b->atlas.objects[slot];
            t->representation = LBK_REPRESENTATION_LIGHTMAP;
            t->index = (uint32_t)ao->page;
            t->rect_x = (uint32_t)ao->x, t->rect_y = (uint32_t)ao->y;
            t->rect_w = (uint32_t)ao->w, t->rect_h = (uint32_t)ao->h;
        } else if (b->classes[i].rep == BK_REP_LLG && b->object_llg[i] >= 0) {
            t->representation = LBK_REPRESENTATION_LLG;
            t->index = (uint32_t)b->object_llg[i];
        }
    }
    void *data;
    size_t size;
    r = lbk_objects_build(objs, (uint32_t)s->object_count, NULL, &data, &size);
    r = sections_add(sl, LBK_SECTION_OBJS, r, data, size);
done:
    free(objs), free(names), free(xyz);
    return r;
}

static lbk_result build_meta(bake *b, section_list *sl)
{
    char hash[17], seed[32], density[32], spacing[32], samples[32], target[32], bounces[32], tlimit[32], ts[32];
    lbk_meta_hash_hex(b->scene.source_hash, hash);
    snprintf(seed, sizeof seed, "%llu", (unsigned long long)b->opt->seed);
    snprintf(density, sizeof density, "%g", b->opt->texel_density > 0 ? b->opt->texel_density : b->pre->texel_density);
    snprintf(spacing, sizeof spacing, "%g", b->opt->glg_spacing > 0 ? b->opt->glg_spacing : b->pre->glg_spacing);
    snprintf(samples, sizeof samples, "%d", b->opt->max_samples > 0 ? b->opt->max_samples : b->pre->max_samples);
    snprintf(target, sizeof target, "%g", b->opt->target_error > 0 ? b->opt->target_error : b->pre->target_error);
    snprintf(bounces, sizeof bounces, "%d", b->opt->max_bounces);
    snprintf(tlimit, sizeof tlimit, "%g", b->opt->time_limit);
    const char *base = strrchr(b->opt->input, '/');
    base = base ? base + 1 : b->opt->input;
    lbk_meta_pair p[16];
    size_t n = 0;
    p[n++] = (lbk_meta_pair){LBK_META_WRITER, "lbk bake"};
    p[n++] = (lbk_meta_pair){LBK_META_WRITER_VERSION, LBK_LIBRARY_VERSION_STRING};
    p[n++] = (lbk_meta_pair){LBK_META_SCENE_HASH, hash};
    p[n++] = (lbk_meta_pair){"scene.name", base};
    p[n++] = (lbk_meta_pair){"bake.preset", b->pre->name};
    p[n++] = (lbk_meta_pair){"bake.seed", seed};
    p[n++] = (lbk_meta_pair){"bake.texel_density", density};
    p[n++] = (lbk_meta_pair){"bake.glg_spacing", spacing};
    p[n++] = (lbk_meta_pair){"bake.max_samples", samples};
    p[n++] = (lbk_meta_pair){"bake.target_error", target};
    p[n++] = (lbk_meta_pair){"bake.max_bounces", bounces};
    p[n++] = (lbk_meta_pair){"bake.time_limit", tlimit};
    if (b->opt->revision) p[n++] = (lbk_meta_pair){LBK_META_REVISION, b->opt->revision};
    if (b->opt->timestamp) {
        time_t now = time(NULL);
        struct tm tmv;
        gmtime_r(&now, &tmv);
        strftime(ts, sizeof ts, "%Y-%m-%dT%H:%M:%SZ", &tmv);
        p[n++] = (lbk_meta_pair){LBK_META_TIMESTAMP, ts};
    }
    void *data;
    size_t size;
    lbk_result r = lbk_meta_build(p, n, NULL, &data, &size);
    return sections_add(sl, LBK_SECTION_META, r, data, size);
}

static uint32_t bake_status(const bake *b)
{
    switch (b->stats.stop) {
    case BK_STOP_TARGET: return LBK_BAKE_TARGET_REACHED;
    case BK_STOP_TIME: return LBK_BAKE_TIME_LIMIT;
    default: return LBK_BAKE_SAMPLE_LIMIT;
    }
}

static lbk_result build_report(bake *b, section_list *sl)
{
    size_t n = b->sample_count ? b->sample_count : 1;
    lbk_report_record *rec = calloc(n, sizeof *rec);
    if (!rec) return LBK_ERR_OUT_OF_MEMORY;
    int has_probes = b->receiver_count > b->texel_receivers;
    for (size_t i = 0; i < b->sample_count; i++) {
        const bk_transport_sample *s = &b->samples[i];
        /* Wall-clock seconds would make the file differ run to run; the stored report measures
         * work in samples and rays (times are in --json-report). */
        rec[i].samples_per_texel = (uint32_t)fmin(s->samples_per_receiver, 4e9);
        rec[i].bounces = (uint32_t)(s->bounces > 0 ? s->bounces : 0);
        rec[i].texel_rel_rmse = b->texel_receivers ? (float)s->est_rel_rmse : 0;
        rec[i].probe_rel_rmse = has_probes ? (float)s->est_rel_rmse : 0;
        if (i > 0 && rec[i].samples_per_texel < rec[i - 1].samples_per_texel) rec[i].samples_per_texel = rec[i - 1].samples_per_texel;
        if (i > 0 && rec[i].bounces < rec[i - 1].bounces) rec[i].bounces = rec[i - 1].bounces;
        rec[i].rays_traced = (uint64_t)((double)b->stats.rays * (s->samples_per_receiver /
                                                                 fmax(b->stats.samples_per_receiver, 1)));
        if (i > 0 && rec[i].rays_traced < rec[i - 1].rays_traced) rec[i].rays_traced = rec[i - 1].rays_traced;
    }
    if (b->sample_count) rec[b->sample_count - 1].rays_traced = b->stats.rays;
    lbk_report rp;
    memset(&rp, 0, sizeof rp);
    rp.status = bake_status(b);
    rp.max_samples_per_texel = (uint32_t)(b->opt->max_samples > 0 ? b->opt->max_samples : b->pre->max_samples);
    /* Passes double their samples, so the budget stops the bake at the last pass that fits in it:
     * the limit recorded is what that pass reached. */
    if (rp.status == LBK_BAKE_SAMPLE_LIMIT && b->sample_count) rp.max_samples_per_texel = rec[b->sample_count - 1].samples_per_texel;
    rp.time_limit_seconds = b->opt->time_limit;
    rp.target_rel_rmse = (float)(b->opt->target_error > 0 ? b->opt->target_error : b->pre->target_error);
    rp.records = rec;
    rp.record_count = (uint32_t)n;
    void *data;
    size_t size;
    lbk_result r = lbk_report_build(&rp, NULL, &data, &size);
    free(rec);
    return sections_add(sl, LBK_SECTION_REPT, r, data, size);
}

static int do_encode_and_write(bake *b, bk_bake_summary *sum)
{
    phase(b, "write");
    section_list sl;
    memset(&sl, 0, sizeof sl);
    lbk_result r = build_meta(b, &sl);
    if (!r && b->sample_count) r = build_report(b, &sl);
    if (!r) r = build_objects(b, &sl);
    if (!r && b->texels.page_count && b->texel_receivers) r = build_lmap(b, &sl);
    if (!r && b->have_glg) r = build_glg(b, &sl);
    if (!r && b->llg_count) r = build_llg(b, &sl);
    if (!r && b->opt->octahedral_probes && b->have_glg) r = build_octp(b, &sl);
    if (!r && b->sets.set_count) {
        bk_set_inputs in;
        set_inputs(b, &in);
        memcpy(in.scale, b->scale, sizeof in.scale);
        void *dls = NULL, *door = NULL;
        size_t dls_size = 0, door_size = 0;
        r = bk_set_bakes_sections(&b->sets, &in, &dls, &dls_size, &door, &door_size);
        if (!r && dls) r = sections_add(&sl, LBK_SECTION_DLS, r, dls, dls_size);
        if (!r && door) r = sections_add(&sl, LBK_SECTION_DOOR, r, door, door_size);
    }
    bk_progress_update(b->progress, 0.5);
    lbk_writer *w = NULL;
    if (!r) r = lbk_writer_create(NULL, &w);
    for (int i = 0; !r && i < sl.count; i++) {
        lbk_section_options so;
        memset(&so, 0, sizeof so);
        /* Lighting payloads stay uncompressed so a runtime can upload them in place; `lbk
         * convert` makes compressed packs. The small CPU-side tables are required to read them. */
        if (sl.type[i] == LBK_SECTION_OBJS || sl.type[i] == LBK_SECTION_DLS || sl.type[i] == LBK_SECTION_DOOR)
            so.flags = LBK_SECTION_FLAG_REQUIRED;
        r = lbk_writer_add_section(w, sl.type[i], sl.data[i], sl.size[i], &so);
    }
    sections_free(&sl);
    if (r) {
        lbk_writer_destroy(w);
        return fail(b, LBK_EXIT_INTERNAL, "encoding the container: %s", lbk_result_message(r));
    }
    r = lbk_writer_to_file(w, b->opt->output);
    lbk_writer_destroy(w);
    if (r) return fail(b, LBK_EXIT_IO, "writing %s: %s", b->opt->output, lbk_result_message(r));
    FILE *f = fopen(b->opt->output, "rb");
    if (f) {
        fseek(f, 0, SEEK_END);
        sum->file_bytes = (uint64_t)ftell(f);
        fclose(f);
    }
    bk_progress_update(b->progress, 1);
    return 0;
}

static int write_json_report(bake *b, const bk_bake_summary *sum)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "schema", "lbk-bake-report/1");
    cJSON_AddStringToObject(root, "input", b->opt->input);
    cJSON_AddStringToObject(root, "output", b->opt->output);
    cJSON_AddStringToObject(root, "preset", b->pre->name);
    cJSON_AddNumberToObject(root, "seed", (double)b->opt->seed);
    cJSON_AddStringToObject(root, "status", lbk_bake_status_name(bake_status(b)));
    cJSON_AddNumberToObject(root, "target_error", b->opt->target_error > 0 ? b->opt->target_error : b->pre->target_error);
    cJSON_AddNumberToObject(root, "time_limit", b->opt->time_limit);
    cJSON *samples = cJSON_AddArrayToObject(root, "samples");
    for (size_t i = 0; i < b->sample_count; i++) {
        const bk_transport_sample *s = &b->samples[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "seconds", s->seconds);
        cJSON_AddNumberToObject(o, "samples_per_receiver", s->samples_per_receiver);
        cJSON_AddNumberToObject(o, "est_rel_rmse", s->est_rel_rmse);
        cJSON_AddNumberToObject(o, "bounces", s->bounces);
        cJSON_AddNumberToObject(o, "pass", s->pass);
        cJSON_AddItemToArray(samples, o);
    }
    cJSON *st = cJSON_AddObjectToObject(root, "transport");
    cJSON_AddNumberToObject(st, "seconds", b->stats.seconds);
    cJSON_AddNumberToObject(st, "passes", b->stats.passes);
    cJSON_AddNumberToObject(st, "rays", (double)b->stats.rays);
    cJSON_AddNumberToObject(st, "bounces", b->stats.bounces);
    cJSON_AddNumberToObject(st, "bounce_ratio_q", b->stats.q);
    cJSON_AddNumberToObject(st, "tail_fraction", b->stats.tail_fraction);
    cJSON_AddNumberToObject(st, "cache_cells", (double)b->stats.cells);
    cJSON_AddNumberToObject(st, "nonfinite_dropped", (double)b->stats.nonfinite);
    cJSON_AddNumberToObject(st, "texel_channels_saturated", (double)b->saturated);
    cJSON_AddNumberToObject(st, "texel_channels_flushed", (double)b->flushed);
    /* the radiometric scale of each lighting section written (spec §5.7); 0: section absent */
    cJSON *sc = cJSON_AddObjectToObject(root, "scales");
    cJSON_AddNumberToObject(sc, "lmap", sum->texels ? b->scale[0] : 0);
    cJSON_AddNumberToObject(sc, "glg", sum->glg_probes ? b->scale[1] : 0);
    cJSON_AddNumberToObject(sc, "llg", sum->llgs ? b->scale[2] : 0);
    cJSON_AddNumberToObject(sc, "octp", b->opt->octahedral_probes && sum->glg_probes ? b->octp_scale : 0);
    cJSON *c = cJSON_AddObjectToObject(root, "counts");
    cJSON_AddNumberToObject(c, "objects", (double)sum->objects);
    cJSON_AddNumberToObject(c, "texels", (double)sum->texels);
    cJSON_AddNumberToObject(c, "pages", (double)sum->pages);
    cJSON_AddNumberToObject(c, "glg_probes", (double)sum->glg_probes);
    cJSON_AddNumberToObject(c, "llgs", (double)sum->llgs);
    cJSON_AddNumberToObject(c, "llg_probes", (double)sum->llg_probes);
    cJSON_AddNumberToObject(c, "light_sets", sum->sets);
    cJSON_AddNumberToObject(c, "doors", sum->doors);
    cJSON_AddNumberToObject(c, "file_bytes", (double)sum->file_bytes);
    cJSON *ph = cJSON_AddArrayToObject(root, "phases");
    for (int i = 0; i < b->phase_count; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", b->phase_names[i]);
        cJSON_AddNumberToObject(o, "seconds", b->phase_seconds[i]);
        cJSON_AddItemToArray(ph, o);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) return fail(b, LBK_EXIT_INTERNAL, "out of memory");
    FILE *f = fopen(b->opt->json_report, "w");
    int ok = f && fputs(text, f) >= 0 && fputc('\n', f) != EOF;
    if (f && fclose(f)) ok = 0;
    free(text);
    if (!ok) return fail(b, LBK_EXIT_IO, "writing %s failed", b->opt->json_report);
    return 0;
}

static void bake_free(bake *b)
{
    bk_set_bakes_free(&b->sets);
    free(b->samples);
    free(b->radiance);
    free(b->texel_of_receiver);
    free(b->receivers);
    free(b->cell_size);
    for (size_t i = 0; i < b->llg_count; i++) bk_llg_free(&b->llgs[i]);
    free(b->llgs);
    free(b->object_llg);
    bk_glg_free(&b->glg);
    if (b->tracer) bk_tracer_destroy(b->tracer);
    bk_texels_free(&b->texels);
    bk_atlas_free(&b->atlas);
    free(b->classes);
    bk_scene_free(&b->scene);
}

int bk_bake(const bk_bake_options *opt, bk_progress *progress, bk_bake_summary *summary, char *err, size_t err_len)
{
    bake b;
    memset(&b, 0, sizeof b);
    memset(summary, 0, sizeof *summary);
    b.opt = opt;
    b.progress = progress;
    b.err = err;
    b.err_len = err_len;
    b.pre = &presets[0];
    if (opt->preset && !strcmp(opt->preset, "high")) b.pre = &presets[1];
    double start = bk_now();
    int rc = do_import(&b);
    if (!rc) rc = do_layout(&b);
    if (!rc) rc = bk_set_bakes_prepare(&b.sets, &b.scene, progress, err, err_len);
    if (!rc) rc = do_transport(&b);
    if (!rc && b.sets.set_count) {
        phase(&b, "sets");
        bk_set_inputs in;
        set_inputs(&b, &in);
        rc = bk_set_bakes_run(&b.sets, &in, err, err_len);
    }
    if (!rc) {
        summary->objects = b.scene.object_count;
        summary->texels = b.atlas.texels;
        summary->pages = b.atlas.page_count;
        summary->glg_probes = b.have_glg ? b.glg.probe_count : 0;
        summary->llgs = b.llg_count;
        summary->llg_probes = b.receiver_count - b.llg_first;
        summary->sets = b.sets.set_count;
        summary->doors = b.sets.door_count;
        summary->final_error = b.stats.est_rel_rmse;
        rc = do_encode_and_write(&b, summary);
        summary->texel_channels_saturated = b.saturated;
        summary->texel_channels_flushed = b.flushed;
    }
    if (b.phase_count > 0) b.phase_seconds[b.phase_count - 1] = bk_now() - b.phase_start;
    summary->seconds = bk_now() - start;
    if (!rc && opt->json_report) rc = write_json_report(&b, summary);
    bake_free(&b);
    return rc;
}
