/* The write phase: every section the scene needs, encoded from the pipeline's results into the
 * container's writer. Which sections: LMAP with lightmapped texels, GLG when there is free space
 * for it, LLG with props, OCTP when asked, DLS and DOOR with light sets and doors; META, REPT and
 * OBJS always. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake/pipeline/error_map.h"
#include "lbk/error_map.h"
#include "bake/encode/encode.h"
#include "bake/pipeline/pipeline.h"
#include "bake/pipeline/provenance.h"
#include "bake/pipeline/uv_section.h"
#include "bake/probes/octa_bake.h"
#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/octa.h"
#include "lbk/report.h"

uint32_t bk_pipeline_status(const bk_pipeline *b)
{
    switch (b->stats.stop) {
    case BK_STOP_TARGET: return LBK_BAKE_TARGET_REACHED;
    case BK_STOP_TIME: return LBK_BAKE_TIME_LIMIT;
    default: return LBK_BAKE_SAMPLE_LIMIT;
    }
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

static lbk_result build_lmap(bk_pipeline *b, section_list *sl)
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
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_WARNING,
                      "%llu texel channels exceed 65024 times the lightmap scale %g, the "
                      "largest R11G11B10F value, and are stored saturated",
                      (unsigned long long)b->saturated, (double)scale);
    if (b->flushed)
        bk_events_say(&b->events, LBK_BAKE_SEVERITY_WARNING,
                      "%llu lit texel channels are below 2^-21 times the lightmap scale %g "
                      "and are stored as 0: the level's irradiance spans more than the format's range "
                      "(~7e10) within one lightmap",
                      (unsigned long long)b->flushed, (double)scale);
    r = bk_encode_pages(tx, b->atlas.margin, b->opt->no_seam_stitch ? NULL : &b->seams, b->opt->threads, lin, has, inv,
                        pages);
    if (r) goto done;
    for (size_t p = 0; p < tx->page_count; p++) {
        desc[p].width = (uint32_t)tx->pages[p].width;
        desc[p].height = (uint32_t)tx->pages[p].height;
        desc[p].texels = pages[p];
    }
    void *data;
    size_t size;
    r = lbk_lmap_build(&(lbk_lmap_build_desc){.pages = desc, .page_count = (uint32_t)tx->page_count, .scale = scale}, NULL, &data, &size);
    r = sections_add(sl, LBK_SECTION_LMAP, r, data, size);
done:
    if (pages)
        for (size_t p = 0; p < tx->page_count; p++) free(pages[p]);
    free(pages), free(desc), free(lin), free(has);
    return r;
}

static lbk_result build_glg(bk_pipeline *b, section_list *sl)
{
    uint8_t(*vis)[4] = calloc(b->glg.tet_count, sizeof *vis);
    float(*world)[3] = calloc(b->glg.probe_count, sizeof *world);
    if (!vis || !world) {
        free(vis), free(world);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    bk_glg_visibility_unorm8(&b->glg, vis);
    for (size_t i = 0; i < b->glg.probe_count; i++) bk_pipeline_to_world(b, &b->glg.positions[3 * i], world[i]);
    lbk_glg_build_desc d;
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

/* OCTP: the probe volume, its transport-gathered irradiance texels and its traced depth
 * moments; inside probes keep zero data (a sampler skips them). */
static lbk_result build_octp(bk_pipeline *b, section_list *sl)
{
    const bk_octa_volume *v = &b->octa;
    lbk_octp_probe_desc *p = calloc(v->count, sizeof *p);
    lbk_octp_probe_info *info = malloc((size_t)v->count * sizeof *info);
    if (!p || !info) {
        free(p), free(info);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    double m = 0;
    for (uint32_t i = 0; i < v->count; i++) {
        info[i] = v->info[i];
        info[i].rays = b->octa_rays < 4e9 ? (uint32_t)b->octa_rays : UINT32_MAX;
        if (info[i].state == LBK_OCTP_INSIDE) continue;
        bk_octa_depth(b->tracer, &v->positions[3 * i], v->levels[bk_octa_probe_level(v, i)].miss_distance, p[i].depth);
        for (int t = 0; t < 16; t++)
            for (int c = 0; c < 3; c++) {
                const float e = b->octa_irradiance[((size_t)i * 16 + (size_t)t) * 3 + (size_t)c];
                p[i].irradiance[t][c] = e > 0 && isfinite(e) ? e : 0;
                if (p[i].irradiance[t][c] > m) m = p[i].irradiance[t][c];
            }
    }
    lbk_octp_level levels[LBK_OCTP_MAX_LEVELS];
    for (uint32_t l = 0; l < v->level_count; l++) {
        levels[l] = v->levels[l];
        bk_pipeline_to_world(b, v->levels[l].origin, levels[l].origin);
    }
    b->octp_scale = bk_scale_for(m);
    void *data;
    size_t size;
    lbk_result r = lbk_octp_build(&(lbk_octp_build_desc){.size = sizeof(lbk_octp_build_desc), .probes = p, .probe_count = v->count, .scale = b->octp_scale,
                                                          .levels = levels, .level_count = v->level_count, .info = info},
                                  NULL, &data, &size);
    free(p), free(info);
    return sections_add(sl, LBK_SECTION_OCTP, r, data, size);
}

static lbk_result build_llg(bk_pipeline *b, section_list *sl)
{
    lbk_llg_grid_desc *g = calloc(b->llg_count, sizeof *g);
    lbk_llg_vertex **verts = calloc(b->llg_count, sizeof *verts);
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (!g || !verts) goto done;
    size_t probe = b->llg_first;
    for (size_t i = 0; i < b->llg_count; i++) {
        const bk_llg *l = &b->llgs[i];
        bk_pipeline_to_world(b, l->centre, g[i].centre);
        memcpy(g[i].axes, l->axes, sizeof g[i].axes);
        memcpy(g[i].half_extents, l->half_extents, sizeof g[i].half_extents);
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
    r = lbk_llg_build(&(lbk_llg_build_desc){.grids = g, .grid_count = (uint32_t)b->llg_count, .scale = b->scale[2]}, NULL, &data, &size);
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

static lbk_result build_objects(bk_pipeline *b, section_list *sl)
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
                bk_pipeline_to_world(b, &s->positions[3 * (size_t)s->tris[3 * ((size_t)o->first_tri + k) + c]], &xyz[9 * k + 3 * c]);
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

static lbk_result build_meta(bk_pipeline *b, section_list *sl)
{
    void *data;
    size_t size;
    lbk_result r = bk_provenance_meta(b, &data, &size);
    return sections_add(sl, LBK_SECTION_META, r, data, size);
}

static lbk_result build_report(bk_pipeline *b, section_list *sl)
{
    /* a denoised bake ends with one more record: the same work, the estimate of what the
     * denoiser delivers (spec §7.1, DENOISE.md) */
    const size_t extra = b->have_denoised && b->sample_count ? 1 : 0;
    size_t n = b->sample_count ? b->sample_count + extra : 1;
    lbk_report_record *rec = calloc(n, sizeof *rec);
    if (!rec) return LBK_ERR_OUT_OF_MEMORY;
    int has_probes = b->receiver_count > b->texel_receivers;
    for (size_t i = 0; i < b->sample_count; i++) {
        const bk_transport_sample *s = &b->samples[i];
        /* Wall-clock seconds would make the file differ run to run; the stored report measures
         * work in samples and rays (times are in --json-report). */
        rec[i].samples_per_texel = (uint32_t)fmin(s->samples_per_receiver, 4e9);
        rec[i].bounces = (uint32_t)(s->bounces > 0 ? s->bounces : 0);
        rec[i].texel_rel_rmse = b->texel_receivers ? (float)s->class_rel_rmse[BK_CLASS_TEXEL] : 0;
        rec[i].probe_rel_rmse = has_probes ? (float)s->probe_rel_rmse : 0;
        if (i > 0 && rec[i].samples_per_texel < rec[i - 1].samples_per_texel) rec[i].samples_per_texel = rec[i - 1].samples_per_texel;
        if (i > 0 && rec[i].bounces < rec[i - 1].bounces) rec[i].bounces = rec[i - 1].bounces;
        rec[i].rays_traced = (uint64_t)((double)b->stats.rays * (s->samples_per_receiver /
                                                                 fmax(b->stats.samples_per_receiver, 1)));
        if (i > 0 && rec[i].rays_traced < rec[i - 1].rays_traced) rec[i].rays_traced = rec[i - 1].rays_traced;
    }
    if (b->sample_count) rec[b->sample_count - 1].rays_traced = b->stats.rays;
    if (extra) {
        rec[n - 1] = rec[n - 2];
        rec[n - 1].texel_rel_rmse = b->texel_receivers ? (float)b->denoised.errors.texels : 0;
        rec[n - 1].probe_rel_rmse = has_probes ? (float)b->denoised.errors.probes : 0;
    }
    lbk_report rp;
    memset(&rp, 0, sizeof rp);
    rp.status = bk_pipeline_status(b);
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

static lbk_result build_sets(bk_pipeline *b, section_list *sl)
{
    bk_set_inputs in;
    bk_pipeline_set_inputs(b, &in);
    memcpy(in.scale, b->scale, sizeof in.scale);
    void *dls = NULL, *door = NULL;
    size_t dls_size = 0, door_size = 0;
    lbk_result r = bk_set_bakes_sections(&b->sets, &in, &dls, &dls_size, &door, &door_size);
    if (!r && dls) r = sections_add(sl, LBK_SECTION_DLS, r, dls, dls_size);
    else lbk_free(NULL, dls);
    if (!r && door) r = sections_add(sl, LBK_SECTION_DOOR, r, door, door_size);
    else lbk_free(NULL, door);
    return r;
}

static lbk_result build_sections(bk_pipeline *b, section_list *sl)
{
    lbk_result r = build_meta(b, sl);
    if (!r && b->sample_count) r = build_report(b, sl);
    if (!r) r = build_objects(b, sl);
    if (!r) { /* lightmap coordinates for engines (spec §16) */
        void *uv = NULL;
        size_t uv_size = 0;
        r = bk_uv_section_build(&b->scene, &b->atlas, b->classes, &uv, &uv_size);
        if (!r && uv) r = sections_add(sl, LBK_SECTION_LMUV, r, uv, uv_size);
    }
    if (!r && b->texels.page_count && b->texel_receivers) r = build_lmap(b, sl);
    if (!r && b->texels.page_count && b->texel_receivers && b->texel_rel_error) { /* --error-map (spec §18) */
        void *terr = NULL;
        size_t terr_size = 0;
        const uint32_t flags = b->have_denoised && b->denoised.texels_filtered ? LBK_TERR_DENOISED : 0;
        r = bk_error_map_section(&b->texels, b->texel_of_receiver, b->texel_receivers, b->texel_rel_error, flags, &terr,
                                 &terr_size);
        r = sections_add(sl, LBK_SECTION_TERR, r, terr, terr_size);
    }
    if (!r && b->have_glg) r = build_glg(b, sl);
    if (!r && b->llg_count) r = build_llg(b, sl);
    if (!r && b->octa.count && b->octa_irradiance) r = build_octp(b, sl);
    if (!r && b->sets.set_count) r = build_sets(b, sl);
    return r;
}

lbk_result bk_pipeline_encode(bk_pipeline *b)
{
    section_list sl;
    memset(&sl, 0, sizeof sl);
    lbk_result r = build_sections(b, &sl);
    if (bk_pipeline_progress(b, 0.5)) r = r ? r : LBK_ERR_CANCELLED;
    lbk_write_options wo;
    memset(&wo, 0, sizeof wo);
    wo.allocator = &b->out->allocator;
    if (!r) r = lbk_writer_open(&wo, &b->out->writer);
    for (int i = 0; !r && i < sl.count; i++) {
        lbk_section_options so;
        memset(&so, 0, sizeof so);
        /* Lighting payloads stay uncompressed so a runtime can upload them in place; `lbk
         * convert` makes compressed packs. The small CPU-side tables are required to read them. */
        if (sl.type[i] == LBK_SECTION_OBJS || sl.type[i] == LBK_SECTION_DLS || sl.type[i] == LBK_SECTION_DOOR)
            so.flags = LBK_SECTION_FLAG_REQUIRED;
        r = lbk_writer_section_add(b->out->writer, sl.type[i], sl.data[i], sl.size[i], &so);
    }
    sections_free(&sl);
    /* the size as baked, for the report: serialising is a copy, cheap next to the bake */
    void *bytes = NULL;
    size_t size = 0;
    if (!r) r = lbk_writer_to_memory(b->out->writer, &bytes, &size);
    lbk_free(&b->out->allocator, bytes);
    if (r) return bk_pipeline_failed(b, r, "encoding the container");
    b->container_bytes = size;
    return bk_pipeline_progress(b, 1) ? LBK_ERR_CANCELLED : LBK_OK;
}
