/* The layout phase: a representation per object (lightmap, LLG or none), the lightmap atlas,
 * its seams and texels, the ray tracer, the GLG, the octahedral probe volume and the LLGs. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/pipeline/pipeline.h"
#include "bake/probes/glg_coarse.h"

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
    ao.max_page_size = b->opt->max_page;
    ao.texel_budget = b->opt->texel_budget;
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
    go.max_probes = b->opt->max_probes ? b->opt->max_probes : LBK_BAKE_MAX_PROBES_DEFAULT;
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
    if (b->have_glg) {
        char path[96];
        if (b->glg.merged_cells) snprintf(path, sizeof path, "merged cells");
        else if (b->glg.pocket_tets || b->glg.hull_ghosts)
            snprintf(path, sizeof path, "lifted, %s ghosts, %zu tetrahedra filled into pockets",
                     b->glg.hull_ghosts ? "hull" : "box", b->glg.pocket_tets);
        else snprintf(path, sizeof path, "lifted");
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_INFO, "global light grid: %zu probes, %zu tetrahedra (Delaunay %.1f s: %s)",
                      b->glg.probe_count, b->glg.tet_count, b->glg.delaunay_seconds, path);
    }
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

lbk_result bk_phase_layout(bk_pipeline *b)
{
    lbk_result r = bk_pipeline_phase(b, LBK_BAKE_PHASE_LAYOUT);
    if (r) return r;
    const size_t n_obj = b->scene.object_count ? b->scene.object_count : 1;
    b->classes = calloc(n_obj, sizeof *b->classes);
    b->object_llg = malloc(n_obj * sizeof *b->object_llg);
    uint8_t *lightmapped = calloc(n_obj, 1);
    size_t n_lm = 0, n_llg = 0;
    r = b->classes && b->object_llg && lightmapped ? LBK_OK : bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    if (!r) r = layout_classify(b, lightmapped, &n_lm, &n_llg);
    if (!r) r = bk_pipeline_checkpoint(b, 0.1);
    if (!r && n_lm) r = layout_atlas(b, lightmapped);
    free(lightmapped);
    if (!r) r = bk_pipeline_checkpoint(b, 0.4);
    if (!r) {
        r = bk_tracer_create(&b->scene, b->opt->threads, &b->tracer);
        if (r) r = bk_pipeline_failed(b, r, "ray tracer (Embree)");
    }
    if (!r && n_lm) r = layout_texels(b);
    if (!r) r = bk_pipeline_checkpoint(b, 0.6);
    if (!r && !b->opt->no_glg) r = layout_glg(b);
    if (!r && b->opt->octahedral_probes) r = layout_octa(b);
    if (!r) r = bk_pipeline_checkpoint(b, 0.8);
    if (!r && n_llg) r = layout_llgs(b, n_llg);
    if (!r) r = bk_pipeline_checkpoint(b, 1);
    return r;
}
