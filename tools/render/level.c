/* Loading a level for rendering: what an engine does once, when it builds its meshes and
 * uploads the lighting (see render.h). */
#include "tools/render/level.h"

#include <stdlib.h>
#include <string.h>

#include "lbk/pixel.h"
#include "scene/import.h"
#include "tools/common/error_util.h"
#include "tools/common/lmuv_match.h"
#include "tools/common/objects_match.h"

/* The scene primitives of object i: [*first, *first + *count) (they are in object order). */
static void object_primitives(const bk_scene *s, size_t i, size_t *first, size_t *count)
{
    size_t p = 0;
    while (p < s->primitive_count && s->primitives[p].object < i) p++;
    *first = p;
    while (p < s->primitive_count && s->primitives[p].object == i) p++;
    *count = p - *first;
}

/* OBJS lists the scene's mesh nodes in order; the geometry hash (spec §8.3) proves each is the
 * mesh that was baked (liblbk's lbk_objects_geometry_check, what lbk export / view check too). */
static int match_objects(rl_level *L, char err[TL_ERR_LEN])
{
    const bk_scene *s = &L->scene;
    int rc = tl_objects_match(s, L->bake.has_objs ? &L->bake.objs : NULL, TL_RENDER_INPUT, TL_RENDER_INTERNAL, err);
    if (rc) return rc;
    L->objects = calloc(s->object_count + 1, sizeof *L->objects);
    if (!L->objects) return tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    for (size_t i = 0; i < s->object_count; i++) lbk_objects_get(&L->bake.objs, (uint32_t)i, &L->objects[i]);
    return 0;
}

/* The lightmap coordinate of every corner of a lightmapped object's triangles (spec §16):
 * AUTHORED maps TEXCOORD_1 by the record's scale and offset; GENERATED gives triangle j of each
 * primitive its corners' coordinates through the record's index buffer. */
static int lightmap_coords(rl_level *L, size_t i, char err[TL_ERR_LEN])
{
    const bk_scene *s = &L->scene;
    const lbk_lmuv_view *lv = &L->bake.lmuv;
    uint32_t rec;
    lbk_lmuv_object r;
    if (!L->bake.has_lmuv || lbk_lmuv_find_object(lv, (uint32_t)i, &rec) != LBK_OK ||
        lbk_lmuv_get_object(lv, rec, &r) != LBK_OK)
        return tl_fail(err, TL_RENDER_INPUT, "object %zu ('%.60s') is lightmapped but has no LMUV record", i,
                       s->objects[i].name);
    const bk_object *o = &s->objects[i];
    int rc = tl_lmuv_match_object(s, i, lv, &r, TL_RENDER_INPUT, err); /* what lbk export / view check */
    if (rc) return rc;
    if (r.kind == LBK_LMUV_AUTHORED) {
        for (size_t k = 0; k < 3 * (size_t)o->tri_count; k++) {
            const size_t t = 3 * (size_t)o->first_tri + k;
            lbk_lmuv_authored_coord(&r, &s->uv1[2 * (size_t)s->tris[t]], &L->corner_coord[2 * t]);
        }
        return 0;
    }
    size_t pf, pn;
    object_primitives(s, i, &pf, &pn);
    /* the importer swapped corners 1 and 2 of a mirrored node's triangles; LMUV keeps glTF's winding */
    static const uint32_t straight[3] = {0, 1, 2}, swapped[3] = {0, 2, 1};
    const uint32_t *order = o->mirrored ? swapped : straight;
    for (size_t k = 0; k < pn; k++) {
        const bk_primitive *p = &s->primitives[pf + k];
        lbk_lmuv_primitive q;
        lbk_lmuv_get_primitive(lv, r.primitive_first + (uint32_t)k, &q);
        for (uint32_t j = 0; j < p->tri_count; j++)
            for (uint32_t c = 0; c < 3; c++) {
                uint32_t nv, src;
                lbk_lmuv_index(lv, &q, 3 * j + order[c], &nv);
                lbk_lmuv_vertex(lv, &q, nv, &src, &L->corner_coord[2 * (3 * ((size_t)p->first_tri + j) + c)]);
            }
    }
    return 0;
}

/* Which LLG vertex record every vertex of an LLG object has (spec §11 "Vertex order"). The
 * importer has already split flat-shaded primitives per corner, so its vertices go in as they
 * are (flat = 0). */
static int llg_records(rl_level *L, size_t i, char err[TL_ERR_LEN])
{
    const bk_scene *s = &L->scene;
    size_t pf, pn;
    object_primitives(s, i, &pf, &pn);
    lbk_llg_source_primitive *sp = calloc(pn + 1, sizeof *sp);
    uint32_t **idx = calloc(pn + 1, sizeof *idx);
    int rc = sp && idx ? 0 : tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    uint64_t nmap = 0;
    for (size_t k = 0; k < pn && !rc; k++) {
        const bk_primitive *p = &s->primitives[pf + k];
        if (!(idx[k] = malloc(3 * (size_t)p->tri_count * sizeof **idx))) rc = tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
        for (size_t t = 0; !rc && t < 3 * (size_t)p->tri_count; t++)
            idx[k][t] = s->tris[3 * (size_t)p->first_tri + t] - p->first_vertex;
        sp[k] = (lbk_llg_source_primitive){.vertex_count = p->vertex_count, .index_count = 3 * p->tri_count, .indices = idx[k]};
        nmap += p->vertex_count;
    }
    uint32_t records = 0;
    lbk_llg_grid g;
    if (!rc && pn > 0 &&
        lbk_llg_vertex_map(sp, (uint32_t)pn, &L->vertex_record[s->primitives[pf].first_vertex], nmap, &records) != LBK_OK)
        rc = tl_fail(err, TL_RENDER_INPUT, "object %zu: its primitives give no LLG vertex order", i);
    if (!rc && (lbk_llg_grid_get(&L->llg, L->objects[i].index, &g) != LBK_OK || g.vertex_count != records))
        rc = tl_fail(err, TL_RENDER_INPUT, "object %zu: the scene gives %u LLG vertices, the grid has %u", i, records,
                     g.vertex_count);
    for (size_t k = 0; idx && k < pn; k++) free(idx[k]);
    free(idx), free(sp);
    return rc;
}

/* Set weights by name: a light set not named stays on (1, the scene as authored). */
static int set_weights(const rl_level *L, const tl_render_options *o, float *w, char err[TL_ERR_LEN])
{
    const lbk_dls_view *dls = L->bake.dls;
    for (uint32_t j = 0; j < lbk_dls_set_count(dls); j++) {
        lbk_dls_set_info info;
        lbk_dls_set_get(dls, j, &info);
        w[j] = info.kind == LBK_DLS_KIND_LIGHTS ? 1.0f : 0.0f;
    }
    for (size_t k = 0; k < o->set_count; k++) {
        uint32_t j;
        if (lbk_dls_set_find(dls, o->sets[k].name, &j) != LBK_OK)
            return tl_fail(err, TL_RENDER_USAGE, "the level has no light set '%.60s'", o->sets[k].name);
        w[j] = o->sets[k].weight;
    }
    return 0;
}

/* Door openness by name: a door not named stays closed (ω = 0, the geometry of the scene). A fully
 * open door (ω = 1) is not drawn. */
static int door_weights(rl_level *L, const tl_render_options *o, float *w, char err[TL_ERR_LEN])
{
    const lbk_door_view *dv = L->bake.door;
    const uint32_t nd = dv ? lbk_door_count(dv) : 0;
    for (uint32_t d = 0; d < nd; d++) w[d] = 0.0f;
    for (size_t k = 0; k < o->door_count; k++) {
        uint32_t d = 0;
        lbk_door_info info;
        for (; d < nd; d++) {
            lbk_door_get(dv, d, &info);
            if (info.name_length == strlen(o->doors[k].name) && !memcmp(info.name, o->doors[k].name, info.name_length))
                break;
        }
        if (d == nd) return tl_fail(err, TL_RENDER_USAGE, "the level has no door '%.60s'", o->doors[k].name);
        w[d] = o->doors[k].weight;
        for (size_t i = 0; i < L->scene.object_count; i++)
            if (!strcmp(L->scene.objects[i].door, o->doors[k].name)) L->hidden[i] = w[d] >= 1.0f;
    }
    return 0;
}

/* Final texels and probes: the base bake, plus Σ ω_j S_j of the light sets and doors through
 * liblbk's reference runtime (what an engine runs when a light is switched or a door moves). */
static int apply_sets(rl_level *L, const tl_render_options *o, char err[TL_ERR_LEN])
{
    const uint64_t nt = L->bake.has_lmap ? L->bake.lmap.texel_count : 0;
    uint32_t *base_ez = L->texel_ez;
    uint8_t *base_rgba = L->texel_rgba;
    const uint32_t ns = lbk_dls_set_count(L->bake.dls), nd = L->bake.door ? lbk_door_count(L->bake.door) : 0;
    float *sw = calloc(ns + 1, sizeof *sw), *dw = calloc(nd + 1, sizeof *dw);
    L->texel_ez = malloc((nt + 1) * sizeof *L->texel_ez);
    L->texel_rgba = malloc((nt + 1) * 4);
    if (L->has_glg) L->applied_glg = malloc((size_t)L->glg.probe_count * LBK_SH9_PACKED_SIZE + 1);
    if (L->has_llg) L->applied_llg = malloc((size_t)L->llg.probe_count * LBK_SH9_PACKED_SIZE + 1);
    int rc = 0;
    if (!sw || !dw || !L->texel_ez || !L->texel_rgba || (L->has_glg && !L->applied_glg) || (L->has_llg && !L->applied_llg))
        rc = tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    if (!rc) rc = set_weights(L, o, sw, err);
    if (!rc) rc = door_weights(L, o, dw, err);
    lbk_dls_runtime_desc d = LBK_DLS_RUNTIME_DESC_INIT;
    d.dls = L->bake.dls;
    d.doors = L->bake.door;
    d.base_irradiance_z = base_ez, d.base_rgba = base_rgba, d.out_irradiance_z = L->texel_ez, d.out_rgba = L->texel_rgba;
    if (L->has_glg) d.base_glg = L->glg.probes, d.out_glg = L->applied_glg;
    if (L->has_llg) d.base_llg = L->llg.probes, d.out_llg = L->applied_llg;
    lbk_dls_runtime *rt = NULL;
    lbk_result r = LBK_OK;
    if (!rc && ((r = lbk_dls_runtime_open(&d, &rt)) != LBK_OK || (r = lbk_dls_apply(rt, sw, dw, NULL)) != LBK_OK))
        rc = tl_fail(err, TL_RENDER_INPUT, "light sets: %s", lbk_result_message(r));
    lbk_dls_runtime_close(rt);
    /* the views now read the applied probes */
    if (!rc && L->has_glg) L->glg.probes = L->applied_glg;
    if (!rc && L->has_llg) L->llg.probes = L->applied_llg;
    free(base_ez), free(base_rgba), free(sw), free(dw);
    return rc;
}

/* Every texel in the global texel index (spec §9), the space DLS targets address. */
static int gather_texels(rl_level *L, char err[TL_ERR_LEN])
{
    const lbk_lmap_view *m = &L->bake.lmap;
    const uint32_t np = L->bake.has_lmap ? m->page_count : 0;
    const uint64_t nt = L->bake.has_lmap ? m->texel_count : 0;
    L->pages = calloc(np + 1, sizeof *L->pages);
    L->texel_ez = malloc((nt + 1) * sizeof *L->texel_ez);
    L->texel_rgba = malloc((nt + 1) * 4);
    if (!L->pages || !L->texel_ez || !L->texel_rgba) return tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    int block = 0;
    for (uint32_t p = 0; p < np; p++) {
        lbk_lmap_planes pl;
        if (lbk_lmap_planes_get(m, p, &pl) != LBK_OK)
            return tl_fail(err, TL_RENDER_INPUT, "lightmap page %u: unreadable planes", p);
        block |= pl.format[0] != LBK_LMAP_R11G11B10F || pl.format[1] != LBK_LMAP_RGBA8;
    }
    /* a block-compressed pack is drawn from its decoded texels (what a GPU samples); light sets
     * and doors apply to 1.0 texels, so with a DLS the decoded texels are stored as 1.0 texels
     * first (R11G11B10F: 2^-7 relative on top of the block codec's error) */
    if (block && !L->bake.dls && !(L->texel_f = malloc((nt + 1) * sizeof *L->texel_f)))
        return tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    for (uint32_t p = 0; p < np; p++) {
        lbk_lmap_planes pl;
        lbk_lmap_planes_get(m, p, &pl);
        lbk_lmap_page *pg = &L->pages[p];
        if (lbk_lmap_page_get(m, p, pg) != LBK_OK)
            *pg = (lbk_lmap_page){.width = pl.width, .height = pl.height, .first_texel = pl.first_texel, .scale = pl.scale};
        for (uint32_t y = 0; y < pg->height; y++)
            for (uint32_t x = 0; x < pg->width; x++) {
                const uint64_t i = pg->first_texel + (uint64_t)y * pg->width + x;
                lbk_ahd_texel_f tf;
                if (block && tl_bake_texel_get(&L->bake, p, x, y, &tf, NULL, NULL))
                    return tl_fail(err, TL_RENDER_INPUT, "lightmap page %u texel (%u, %u): unreadable", p, x, y);
                if (L->texel_f) {
                    L->texel_f[i] = tf;
                    continue;
                }
                lbk_ahd_texel t;
                if (block) {
                    t.irradiance_z = lbk_r11g11b10f_pack(tf.ez);
                    for (int k = 0; k < 4; k++) t.rgba[k] = lbk_float_to_unorm8(tf.rgba[k]);
                } else if (lbk_lmap_page_texel_get(pg, x, y, &t) != LBK_OK) {
                    return tl_fail(err, TL_RENDER_INPUT, "lightmap page %u texel (%u, %u): unreadable", p, x, y);
                }
                L->texel_ez[i] = t.irradiance_z;
                memcpy(&L->texel_rgba[4 * i], t.rgba, 4);
            }
    }
    return 0;
}

static int load(const char *scene_path, const char *lbk_path, const tl_render_options *o, rl_level *L,
                char err[TL_ERR_LEN])
{
    char msg[512];
    /* normal maps: the material's normalTexture and the vertices' tangents (shade.c) */
    const bk_import_options io = {.normal_maps = 1};
    if (bk_import_gltf(scene_path, &io, &L->scene, msg, sizeof msg)) return tl_fail(err, TL_RENDER_INPUT, "%.250s", msg);
    const bk_scene *s = &L->scene;
    if (!s->primitives) return tl_fail(err, TL_RENDER_INTERNAL, "the scene import gave no primitive table");
    tl_open_status st = tl_bake_open_file_capped(lbk_path, o->max_decoded_bytes, &L->bake, err);
    if (st != TL_OPEN_OK) return st == TL_OPEN_IO ? TL_RENDER_IO : st == TL_OPEN_INVALID ? TL_RENDER_INPUT : TL_RENDER_INTERNAL;
    L->glg = L->bake.glg, L->has_glg = L->bake.has_glg;
    L->llg = L->bake.llg, L->has_llg = L->bake.has_llg;
    int rc = match_objects(L, err);
    if (rc) return rc;
    L->corner_coord = calloc(6 * (s->tri_count + 1), sizeof *L->corner_coord);
    L->vertex_record = malloc((s->vertex_count + 1) * sizeof *L->vertex_record);
    L->hidden = calloc(s->object_count + 1, 1);
    if (!L->corner_coord || !L->vertex_record || !L->hidden) return tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    for (size_t v = 0; v < s->vertex_count; v++) L->vertex_record[v] = LBK_LLG_NO_VERTEX;
    for (size_t i = 0; i < s->object_count && !rc; i++) {
        if (L->objects[i].representation == LBK_REPRESENTATION_LIGHTMAP)
            rc = L->bake.has_lmap && L->objects[i].index < L->bake.lmap.page_count ? lightmap_coords(L, i, err)
                                                                                 : tl_fail(err, TL_RENDER_INPUT, "object %zu: no page", i);
        else if (L->objects[i].representation == LBK_REPRESENTATION_LLG)
            rc = L->has_llg ? llg_records(L, i, err) : tl_fail(err, TL_RENDER_INPUT, "object %zu: no LLG section", i);
    }
    if (!rc) rc = gather_texels(L, err);
    if (!rc && L->bake.dls) rc = apply_sets(L, o, err);
    else if (!rc && (o->set_count || o->door_count))
        rc = tl_fail(err, TL_RENDER_USAGE, "the level has no light sets or doors (no DLS section)");
    if (rc) return rc;
    for (int c = 0; c < 3; c++) L->sky[c] = o->sky_override ? o->sky[c] : s->sky[c];
    if (o->sky_override) L->scene.sky_image = -1;
    lbk_result r = bk_tracer_create(s, 0, &L->tracer);
    return r == LBK_OK ? 0 : tl_fail(err, TL_RENDER_INTERNAL, "Embree: %s", lbk_result_message(r));
}

int rl_level_load(const char *scene_path, const char *lbk_path, const tl_render_options *o, rl_level *L,
                  char err[TL_ERR_LEN])
{
    memset(L, 0, sizeof *L);
    L->scene.sky_image = -1;
    int rc = load(scene_path, lbk_path, o, L, err);
    if (rc) rl_level_free(L);
    return rc;
}

void rl_level_free(rl_level *L)
{
    bk_tracer_destroy(L->tracer);
    tl_bake_close(&L->bake);
    bk_scene_free(&L->scene);
    free(L->objects), free(L->corner_coord), free(L->vertex_record), free(L->hidden);
    free(L->texel_ez), free(L->texel_rgba), free(L->texel_f), free(L->pages), free(L->applied_glg), free(L->applied_llg);
    memset(L, 0, sizeof *L);
}
