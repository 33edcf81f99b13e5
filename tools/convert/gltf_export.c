/* lbk export --gltf (see gltf_export.h; conventions: tools/convert/README.md "glTF export").
 *
 * One node per object of the object table, in its order, with world-space geometry (identity
 * transforms: the scene's importer flattens the hierarchy) and one glTF primitive per triangle
 * primitive of the source mesh. Lightmapped primitives get TEXCOORD_1 = the normalised page uv
 * of their lightmap coordinates (spec/container.md §16): generated charts are rebuilt from LMUV
 * (vertices split where charts split), authored TEXCOORD_1 mapped by the record's scale and
 * offset. */
#include "tools/convert/gltf_export.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/import.h"
#include "tools/common/error_util.h"
#include "tools/common/lmuv_match.h"
#include "tools/common/objects_match.h"
#include "tools/convert/glb.h"
#include "tools/convert/gltf_normals.h"
#include "lbk/pixel.h"

#define PI_F 3.14159265358979f
#define SAMPLER_LINEAR 9729
#define WRAP_CLAMP 33071

typedef struct ex {
    const tl_bake *b;
    const bk_scene *s;
    tl_glb g;
    cJSON *nodes, *meshes, *materials, *extras;
    uint32_t pages;
    uint32_t *page_w, *page_h;
    int *lm_material;    /* per (source material, page): glTF material, or -1 */
    int *plain_material; /* per source material */
    int *llg_material;   /* per source material: the vertex-colour preview of LLG objects */
    float *texels;       /* 3 per texel of every page: physical irradiance along the normal */
    float exposure;      /* of every preview: the p99 rule of tools/convert/README.md "Previews" */
    float *page_scale;   /* per page: the irradiance (lux) of code 255 of its emissive PNG */
    float radiance_scale; /* every radiance in the file is nits × this (a power of two ≤ 1: LLG props'
                             COLOR_0 must stay ≤ 1; README "In engines") */
    int any_unlit, any_strength;
    char dir[4096], stem[200];
    tl_gltf_stats *st;
    tl_gltf_normals normals; /* normalTexture + TANGENT where a material has a normal map */
    char *err;
} ex;

/* Attributes of one exported primitive, gathered from scene vertices. */
typedef struct prim_data {
    size_t nv, ni;
    uint32_t *sv;       /* per vertex: the scene vertex it copies */
    float *uv1;         /* 2 per vertex: TEXCOORD_1; NULL when not lightmapped */
    float *vis, *bent;  /* LLG per-vertex data; NULL when absent */
    float *col;         /* LLG: 3 per vertex, the preview of V·E(bent normal) × exposure, clamped */
    uint32_t *idx;      /* world winding (the scene's) */
} prim_data;

static void prim_free(prim_data *p)
{
    free(p->sv), free(p->uv1), free(p->vis), free(p->bent), free(p->col), free(p->idx);
    memset(p, 0, sizeof *p);
}

static int prim_alloc(prim_data *p, size_t nv, size_t ni, int lightmapped)
{
    p->nv = nv;
    p->ni = ni;
    p->sv = malloc((nv ? nv : 1) * sizeof *p->sv);
    p->idx = malloc((ni ? ni : 1) * sizeof *p->idx);
    p->uv1 = lightmapped ? malloc((nv ? nv : 1) * 2 * sizeof *p->uv1) : NULL;
    return p->sv && p->idx && (!lightmapped || p->uv1) ? 0 : -1;
}

/* ---- matching the scene to the container -------------------------------------------------- */

/* The scene's objects are the container's (count and geometry hash: the check lbk render makes). */
static int check_objects(ex *e)
{
    return tl_objects_match(e->s, e->b->has_objs ? &e->b->objs : NULL, TL_GLTF_INPUT, TL_GLTF_INTERNAL, e->err);
}

/* The scene primitives of object i: [*first, *first + *count). */
static void object_primitives(const bk_scene *s, size_t i, size_t *first, size_t *count)
{
    size_t p = 0;
    while (p < s->primitive_count && s->primitives[p].object < i) p++;
    *first = p;
    while (p < s->primitive_count && s->primitives[p].object == i) p++;
    *count = p - *first;
}

/* A record must describe exactly the scene object it names (the check lbk render makes too). */
static int check_record(ex *e, size_t i, const lbk_lmuv_object *r)
{
    return tl_lmuv_match_object(e->s, i, &e->b->lmuv, r, TL_GLTF_INPUT, e->err);
}

/* ---- primitives ------------------------------------------------------------------------------ */

/* A plain or authored primitive: the scene's own vertices and triangles. */
static int gather_plain(ex *e, const bk_primitive *p, const lbk_lmuv_object *authored, uint32_t page, prim_data *d)
{
    const bk_scene *s = e->s;
    if (prim_alloc(d, p->vertex_count, 3 * (size_t)p->tri_count, authored != NULL))
        return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    for (size_t v = 0; v < d->nv; v++) {
        d->sv[v] = p->first_vertex + (uint32_t)v;
        if (!authored) continue;
        float xy[2];
        lbk_lmuv_authored_coord(authored, &s->uv1[2 * (size_t)d->sv[v]], xy);
        lbk_lmuv_normalized(xy, e->page_w[page], e->page_h[page], &d->uv1[2 * v]);
    }
    for (size_t k = 0; k < d->ni; k++) d->idx[k] = s->tris[3 * (size_t)p->first_tri + k] - p->first_vertex;
    return 0;
}

/* A generated primitive rebuilt from LMUV: new vertex i copies the scene vertex that carries
 * source vertex remap[i] at the corner the index buffer puts it. */
static int gather_generated(ex *e, const bk_primitive *p, const lbk_lmuv_primitive *q, int mirrored, uint32_t page,
                            prim_data *d)
{
    const bk_scene *s = e->s;
    const lbk_lmuv_view *lv = &e->b->lmuv;
    if (prim_alloc(d, q->vertex_count, q->index_count, 1)) return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    for (size_t v = 0; v < d->nv; v++) d->sv[v] = UINT32_MAX;
    static const int straight[3] = {0, 1, 2}, swapped[3] = {0, 2, 1}; /* §16.4: the glTF winding */
    const int *order = mirrored ? swapped : straight;
    for (uint32_t t = 0; t < p->tri_count; t++)
        for (int c = 0; c < 3; c++) {
            uint32_t nv;
            lbk_lmuv_index(lv, q, 3 * t + (uint32_t)order[c], &nv);
            d->idx[3 * (size_t)t + (size_t)c] = nv;
            if (d->sv[nv] == UINT32_MAX) d->sv[nv] = s->tris[3 * ((size_t)p->first_tri + t) + (size_t)c];
        }
    for (uint32_t v = 0; v < q->vertex_count; v++) {
        uint32_t src;
        float xy[2];
        lbk_lmuv_vertex(lv, q, v, &src, xy);
        if (d->sv[v] == UINT32_MAX) /* used by no triangle (warning 1117): any scene copy of it */
            for (uint32_t k = 0; k < p->vertex_count && d->sv[v] == UINT32_MAX; k++)
                if (s->vertex_source[p->first_vertex + k] == src) d->sv[v] = p->first_vertex + k;
        if (d->sv[v] == UINT32_MAX || s->vertex_source[d->sv[v]] != src)
            return tl_fail(e->err, TL_GLTF_INPUT, "glTF primitive %u: LMUV vertex %u (source vertex %u) is not where the "
                           "scene has it", q->source_primitive, v, src);
        lbk_lmuv_normalized(xy, e->page_w[page], e->page_h[page], &d->uv1[2 * (size_t)v]);
    }
    return 0;
}

/* The LLG vertex index of every scene vertex of an object: the grid's vertices are the object's
 * used scene vertices in ascending order (bake/probes/llg_place.h). rank: vertex_count entries,
 * UINT32_MAX where unused. Returns the number of used vertices. */
static uint32_t llg_ranks(const bk_scene *s, size_t object, uint32_t *rank)
{
    const bk_object *o = &s->objects[object];
    for (size_t v = 0; v < s->vertex_count; v++) rank[v] = UINT32_MAX;
    for (size_t k = 0; k < 3 * (size_t)o->tri_count; k++) rank[s->tris[3 * (size_t)o->first_tri + k]] = 0;
    uint32_t n = 0;
    for (size_t v = 0; v < s->vertex_count; v++)
        if (rank[v] != UINT32_MAX) rank[v] = n++;
    return n;
}

/* LLG data per exported vertex: visibility, the bent normal in world space and COLOR_0, the
 * radiance of a white surface lit by the probes, V · E(bent normal) / π × radiance_scale. */
static int gather_llg(ex *e, size_t object, uint32_t grid, prim_data *d)
{
    const bk_scene *s = e->s;
    lbk_llg_grid g;
    if (!e->b->has_llg || lbk_llg_grid_get(&e->b->llg, grid, &g) != LBK_OK) /* invalid (411, 412): as lbk render */
        return tl_fail(e->err, TL_GLTF_INPUT, "object %zu: OBJS names LLG grid %u, the container has %u", object, grid,
                       e->b->has_llg ? e->b->llg.grid_count : 0);
    uint32_t *rank = malloc((s->vertex_count ? s->vertex_count : 1) * sizeof *rank);
    d->vis = malloc((d->nv ? d->nv : 1) * sizeof *d->vis);
    d->bent = malloc((d->nv ? d->nv : 1) * 3 * sizeof *d->bent);
    d->col = malloc((d->nv ? d->nv : 1) * 3 * sizeof *d->col);
    if (!rank || !d->vis || !d->bent || !d->col) {
        free(rank);
        return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    }
    /* a grid with another number of vertex records than the mesh has used vertices does not
     * describe it (spec §11 "Vertex order"): refused, as lbk render refuses it */
    const uint32_t used = llg_ranks(s, object, rank);
    if (used != g.vertex_count) {
        free(rank);
        return tl_fail(e->err, TL_GLTF_INPUT, "object %zu: the scene gives %u LLG vertices, the grid has %u", object,
                       used, g.vertex_count);
    }
    for (size_t v = 0; v < d->nv; v++) {
        const uint32_t sv = d->sv[v];
        lbk_llg_vertex lv = {1.0f, {0, 0, 1}};
        float rgb[3] = {0, 0, 0};
        const int have = rank[sv] != UINT32_MAX;
        if (have) {
            lbk_llg_vertex_unpack(e->b->llg.vertices + 4 * (g.vertex_offset + rank[sv]), &lv);
            lbk_llg_vertex_irradiance(&e->b->llg, grid, rank[sv], &s->positions[3 * (size_t)sv], rgb);
        }
        d->vis[v] = lv.visibility;
        for (int c = 0; c < 3; c++) {
            d->bent[3 * v + (size_t)c] = have ? lv.bent_normal[0] * g.axes[0][c] + lv.bent_normal[1] * g.axes[1][c] +
                                                    lv.bent_normal[2] * g.axes[2][c]
                                              : s->normals[3 * (size_t)sv + (size_t)c];
            const float x = rgb[c] / PI_F * e->radiance_scale;
            d->col[3 * v + (size_t)c] = x > 0.0f ? (x < 1.0f ? x : 1.0f) : 0.0f;
        }
    }
    free(rank);
    return 0;
}

static float clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }

static cJSON *material_extras(const bk_material *m, int page)
{
    cJSON *x = cJSON_CreateObject(), *l = cJSON_AddObjectToObject(x, "lbk");
    cJSON_AddStringToObject(l, "source_material", m->name);
    cJSON_AddItemToObject(l, "albedo", cJSON_CreateFloatArray(m->albedo, 3));
    cJSON_AddItemToObject(l, "emission", cJSON_CreateFloatArray(m->emission, 3));
    if (page >= 0) cJSON_AddNumberToObject(l, "lightmap_page", page);
    return x;
}

#define MATERIAL_PLAIN (-1)
#define MATERIAL_LLG (-2)

/* emissiveFactor × KHR_materials_emissive_strength = rgb (nits): the factor's largest channel is
 * 1 and the strength carries the rest, since glTF factors stop at 1. */
static void add_emission(ex *e, cJSON *mat, const float nits[3])
{
    const float rgb[3] = {nits[0] * e->radiance_scale, nits[1] * e->radiance_scale, nits[2] * e->radiance_scale};
    float m = fmaxf(rgb[0], fmaxf(rgb[1], rgb[2]));
    if (!(m > 0.0f) || !isfinite(m)) return;
    const float f[3] = {clamp01(rgb[0] / m), clamp01(rgb[1] / m), clamp01(rgb[2] / m)};
    cJSON_AddItemToObject(mat, "emissiveFactor", cJSON_CreateFloatArray(f, 3));
    if (m != 1.0f) {
        cJSON *x = cJSON_GetObjectItem(mat, "extensions");
        if (!x) x = cJSON_AddObjectToObject(mat, "extensions");
        cJSON_AddNumberToObject(cJSON_AddObjectToObject(x, "KHR_materials_emissive_strength"), "emissiveStrength", m);
        e->any_strength = 1;
    }
}

/* Lightmapped: the baked light as emission, which every stock glTF loader draws: base colour black
 * (so the engine's own lights and ambient add no second diffuse term), emissiveTexture = the page's
 * emissive PNG on TEXCOORD_1 (sRGB of E / scale), emissiveFactor = albedo and emissiveStrength =
 * scale / π, i.e. the Lambert radiance albedo · E / π in nits (tools/convert/README.md "In
 * engines"). An emitting material keeps its own emission instead (glTF has one emissive slot).
 * LLG objects: unlit, albedo × COLOR_0 (their probe lighting per vertex as radiance of white).
 * Every radiance is nits × radiance_scale.
 * Others (not lit by the bake): plain PBR factors and their emission in nits. */
static int material_for(ex *e, uint32_t mi, int page)
{
    int *slot = page >= 0 ? &e->lm_material[(size_t)mi * e->pages + (uint32_t)page]
                          : page == MATERIAL_LLG ? &e->llg_material[mi] : &e->plain_material[mi];
    if (*slot >= 0) return *slot;
    const bk_material *m = &e->s->materials[mi];
    cJSON *mat = cJSON_CreateObject(), *pbr = cJSON_AddObjectToObject(mat, "pbrMetallicRoughness");
    char name[96];
    if (page >= 0) snprintf(name, sizeof name, "%s@lightmap%u", m->name, (unsigned)page);
    else snprintf(name, sizeof name, page == MATERIAL_LLG ? "%s@llg" : "%s", m->name);
    cJSON_AddStringToObject(mat, "name", name);
    const float base[4] = {clamp01(m->albedo[0]), clamp01(m->albedo[1]), clamp01(m->albedo[2]), 1.0f};
    static const float black[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    cJSON_AddItemToObject(pbr, "baseColorFactor", cJSON_CreateFloatArray(page >= 0 ? black : base, 4));
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0);
    cJSON_AddNumberToObject(pbr, "roughnessFactor", 1);
    const int emits = m->emission[0] > 0 || m->emission[1] > 0 || m->emission[2] > 0;
    if (page == MATERIAL_LLG) {
        cJSON_AddObjectToObject(cJSON_AddObjectToObject(mat, "extensions"), "KHR_materials_unlit");
        e->any_unlit = 1;
    } else if (page >= 0 && !emits) {
        cJSON *tex = cJSON_AddObjectToObject(mat, "emissiveTexture");
        cJSON_AddNumberToObject(tex, "index", page);
        cJSON_AddNumberToObject(tex, "texCoord", 1);
        const float s = e->page_scale[page] / PI_F * e->radiance_scale;
        cJSON_AddItemToObject(mat, "emissiveFactor", cJSON_CreateFloatArray(base, 3));
        if (s != 1.0f) {
            cJSON_AddNumberToObject(cJSON_AddObjectToObject(cJSON_AddObjectToObject(mat, "extensions"),
                                                            "KHR_materials_emissive_strength"),
                                    "emissiveStrength", s);
            e->any_strength = 1;
        }
    } else {
        add_emission(e, mat, m->emission);
    }
    if (m->double_sided) cJSON_AddBoolToObject(mat, "doubleSided", 1);
    cJSON_AddItemToObject(mat, "extras", material_extras(m, page));
    tl_gltf_normals_material(&e->normals, &e->g, mat, mi);
    cJSON_AddItemToArray(e->materials, mat);
    return *slot = cJSON_GetArraySize(e->materials) - 1;
}

/* Vertex attributes and indices into the buffer; returns the primitive object or NULL. */
static cJSON *emit_primitive(ex *e, const prim_data *d, int material)
{
    const bk_scene *s = e->s;
    float *pos = malloc(d->nv * 3 * sizeof *pos), *nrm = malloc(d->nv * 3 * sizeof *nrm);
    float *uv0 = malloc(d->nv * 2 * sizeof *uv0);
    cJSON *p = cJSON_CreateObject(), *at = p ? cJSON_AddObjectToObject(p, "attributes") : NULL;
    if (!pos || !nrm || !uv0 || !at) {
        free(pos), free(nrm), free(uv0);
        cJSON_Delete(p);
        return NULL;
    }
    for (size_t v = 0; v < d->nv; v++) {
        memcpy(&pos[3 * v], &s->positions[3 * (size_t)d->sv[v]], 3 * sizeof(float));
        memcpy(&nrm[3 * v], &s->normals[3 * (size_t)d->sv[v]], 3 * sizeof(float));
        memcpy(&uv0[2 * v], &s->uv0[2 * (size_t)d->sv[v]], 2 * sizeof(float));
    }
    cJSON_AddNumberToObject(at, "POSITION", tl_glb_accessor_f32(&e->g, pos, d->nv, 3, TL_GLTF_ARRAY_BUFFER, 1));
    cJSON_AddNumberToObject(at, "NORMAL", tl_glb_accessor_f32(&e->g, nrm, d->nv, 3, TL_GLTF_ARRAY_BUFFER, 0));
    /* always: TEXCOORD sets must start at 0 (glTF 2.0 §3.7.2.1) */
    cJSON_AddNumberToObject(at, "TEXCOORD_0", tl_glb_accessor_f32(&e->g, uv0, d->nv, 2, TL_GLTF_ARRAY_BUFFER, 0));
    if (d->uv1) cJSON_AddNumberToObject(at, "TEXCOORD_1", tl_glb_accessor_f32(&e->g, d->uv1, d->nv, 2, TL_GLTF_ARRAY_BUFFER, 0));
    if (d->col) cJSON_AddNumberToObject(at, "COLOR_0", tl_glb_accessor_f32(&e->g, d->col, d->nv, 3, TL_GLTF_ARRAY_BUFFER, 0));
    if (d->vis) {
        cJSON_AddNumberToObject(at, "_LBK_LLG_VISIBILITY", tl_glb_accessor_f32(&e->g, d->vis, d->nv, 1, TL_GLTF_ARRAY_BUFFER, 0));
        cJSON_AddNumberToObject(at, "_LBK_LLG_BENT_NORMAL", tl_glb_accessor_f32(&e->g, d->bent, d->nv, 3, TL_GLTF_ARRAY_BUFFER, 0));
    }
    cJSON_AddNumberToObject(p, "indices", tl_glb_accessor_u32(&e->g, d->idx, d->ni, TL_GLTF_ELEMENT_ARRAY_BUFFER));
    cJSON_AddNumberToObject(p, "material", material);
    cJSON_AddNumberToObject(p, "mode", 4);
    free(pos), free(nrm), free(uv0);
    e->st->primitives++;
    e->st->vertices += d->nv;
    e->st->triangles += d->ni / 3;
    return p;
}

static cJSON *lightmap_extras(const ex *e, uint32_t page, uint32_t source_primitive)
{
    char f[4][256];
    snprintf(f[0], sizeof f[0], "%s.lightmap_%03u.exr", e->stem, page);
    snprintf(f[1], sizeof f[1], "%s.lightmap_%03u.ahd.exr", e->stem, page);
    snprintf(f[2], sizeof f[2], "%s.lightmap_%03u.png", e->stem, page);
    snprintf(f[3], sizeof f[3], "%s.lightmap_%03u.emissive.png", e->stem, page);
    cJSON *x = cJSON_CreateObject(), *l = cJSON_AddObjectToObject(x, "lbk");
    cJSON_AddNumberToObject(l, "source_primitive", source_primitive);
    cJSON *lm = cJSON_AddObjectToObject(l, "lightmap");
    cJSON_AddNumberToObject(lm, "page", page);
    cJSON_AddNumberToObject(lm, "texcoord", 1);
    cJSON_AddStringToObject(lm, "irradiance", f[0]);
    cJSON_AddStringToObject(lm, "ahd", f[1]);
    cJSON_AddStringToObject(lm, "preview", f[2]);
    cJSON_AddStringToObject(lm, "emissive", f[3]);
    cJSON_AddNumberToObject(lm, "emissive_scale", e->page_scale[page]);
    cJSON_AddStringToObject(lm, "decode", "lbk-ahd/1");
    return x;
}

/* ---- objects ----------------------------------------------------------------------------------- */

static cJSON *node_extras(uint32_t i, const lbk_object *ob, const lbk_lmuv_object *rec, const bk_object *so)
{
    cJSON *x = cJSON_CreateObject(), *l = cJSON_AddObjectToObject(x, "lbk");
    cJSON_AddNumberToObject(l, "object", i);
    cJSON_AddStringToObject(l, "representation", lbk_representation_name(ob->representation));
    cJSON_AddNumberToObject(l, "source_node", so->node);
    /* what the baker read from the source node, so the export bakes the same way */
    if (so->light_set[0]) cJSON_AddStringToObject(x, "lbk_light_set", so->light_set);
    if (so->door[0]) cJSON_AddStringToObject(x, "lbk_door", so->door);
    if (ob->representation == LBK_REPRESENTATION_LIGHTMAP) {
        const int rect[4] = {(int)ob->rect_x, (int)ob->rect_y, (int)ob->rect_w, (int)ob->rect_h};
        cJSON_AddNumberToObject(l, "page", ob->index);
        cJSON_AddItemToObject(l, "rect", cJSON_CreateIntArray(rect, 4));
        cJSON_AddStringToObject(l, "uv_source", lbk_lmuv_kind_name(rec->kind));
    } else if (ob->representation == LBK_REPRESENTATION_LLG) {
        cJSON_AddNumberToObject(l, "llg_grid", ob->index);
    }
    return x;
}

static int emit_object_primitive(ex *e, size_t i, const lbk_object *ob, const lbk_lmuv_object *rec, size_t k,
                                 cJSON *prims)
{
    const bk_scene *s = e->s;
    size_t pf, pn;
    object_primitives(s, i, &pf, &pn);
    const bk_primitive *p = &s->primitives[pf + k];
    const int lm = ob->representation == LBK_REPRESENTATION_LIGHTMAP;
    prim_data d;
    memset(&d, 0, sizeof d);
    int rc;
    if (lm && rec->kind == LBK_LMUV_GENERATED) {
        lbk_lmuv_primitive q;
        lbk_lmuv_get_primitive(&e->b->lmuv, rec->primitive_first + (uint32_t)k, &q);
        rc = gather_generated(e, p, &q, s->objects[i].mirrored, ob->index, &d);
        e->st->generated += rc == 0;
    } else {
        rc = gather_plain(e, p, lm ? rec : NULL, ob->index, &d);
        e->st->authored += rc == 0 && lm;
    }
    if (!rc && ob->representation == LBK_REPRESENTATION_LLG) rc = gather_llg(e, i, ob->index, &d);
    if (rc) {
        prim_free(&d);
        return rc;
    }
    const uint32_t mi = d.ni ? s->tri_material[p->first_tri] : 0; /* the primitive's material */
    const int kind = lm ? (int)ob->index : d.col ? MATERIAL_LLG : MATERIAL_PLAIN;
    cJSON *gp = emit_primitive(e, &d, material_for(e, mi, kind));
    if (gp && tl_gltf_normals_tangents(&e->normals, &e->g, cJSON_GetObjectItem(gp, "attributes"), mi, d.sv, d.nv))
        e->g.failed = 1;
    prim_free(&d);
    if (!gp) return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    if (lm) {
        cJSON_AddItemToObject(gp, "extras", lightmap_extras(e, ob->index, p->gltf_primitive));
        e->st->lightmapped++;
    }
    cJSON_AddItemToArray(prims, gp);
    return 0;
}

static int emit_object(ex *e, size_t i)
{
    lbk_object ob;
    lbk_objects_get(&e->b->objs, (uint32_t)i, &ob);
    lbk_lmuv_object rec;
    memset(&rec, 0, sizeof rec);
    if (ob.representation == LBK_REPRESENTATION_LIGHTMAP) {
        uint32_t r;
        if (!e->b->has_lmuv || lbk_lmuv_find_object(&e->b->lmuv, (uint32_t)i, &r) != LBK_OK)
            return tl_fail(e->err, TL_GLTF_INPUT,
                           "object %zu is lightmapped but the container has no LMUV record for it (baked before format "
                           "1.1?): re-bake to export its lightmap coordinates",
                           i);
        lbk_lmuv_get_object(&e->b->lmuv, r, &rec);
        if (check_record(e, i, &rec)) return TL_GLTF_INPUT;
    }
    char name[129];
    tl_string_copy(name, sizeof name, ob.name);
    cJSON *mesh = cJSON_CreateObject(), *node = cJSON_CreateObject();
    cJSON *prims = mesh ? cJSON_AddArrayToObject(mesh, "primitives") : NULL;
    if (!prims || !node) {
        cJSON_Delete(mesh), cJSON_Delete(node);
        return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    }
    cJSON_AddStringToObject(mesh, "name", name);
    cJSON_AddItemToArray(e->meshes, mesh);
    size_t pf, pn;
    object_primitives(e->s, i, &pf, &pn);
    for (size_t k = 0; k < pn; k++) {
        int rc = emit_object_primitive(e, i, &ob, &rec, k, prims);
        if (rc) {
            cJSON_Delete(node);
            return rc;
        }
    }
    cJSON_AddStringToObject(node, "name", name);
    cJSON_AddNumberToObject(node, "mesh", cJSON_GetArraySize(e->meshes) - 1);
    cJSON_AddItemToObject(node, "extras", node_extras((uint32_t)i, &ob, &rec, &e->s->objects[i]));
    if (ob.representation == LBK_REPRESENTATION_LLG && e->b->has_llg) {
        lbk_llg_grid g;
        if (lbk_llg_grid_get(&e->b->llg, ob.index, &g) == LBK_OK) {
            cJSON *l = cJSON_GetObjectItem(cJSON_GetObjectItem(node, "extras"), "lbk"), *x = cJSON_AddObjectToObject(l, "llg");
            cJSON_AddItemToObject(x, "centre", cJSON_CreateFloatArray(g.centre, 3));
            cJSON *axes = cJSON_AddArrayToObject(x, "axes");
            for (int a = 0; a < 3; a++) cJSON_AddItemToArray(axes, cJSON_CreateFloatArray(g.axes[a], 3));
            cJSON_AddItemToObject(x, "half_extents", cJSON_CreateFloatArray(g.half_extents, 3));
            const int dims[3] = {(int)g.dims[0], (int)g.dims[1], (int)g.dims[2]};
            cJSON_AddItemToObject(x, "dims", cJSON_CreateIntArray(dims, 3));
            size_t n = (size_t)g.dims[0] * g.dims[1] * g.dims[2];
            float *sh = malloc(n * 27 * sizeof *sh);
            if (!sh) return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
            for (size_t q = 0; q < n; q++) {
                lbk_sh9_rgb v;
                tl_probe_unpack(e->b->llg.probes + (g.probe_offset + q) * LBK_SH9_PACKED_SIZE, e->b->llg.scale, &v);
                memcpy(sh + 27 * q, v.c, sizeof v.c);
            }
            cJSON_AddNumberToObject(x, "sh9", tl_glb_accessor_f32(&e->g, sh, 27 * n, 1, 0, 0));
            free(sh);
        }
    }
    cJSON_AddItemToArray(e->nodes, node);
    e->st->nodes++;
    return 0;
}

/* ---- pages, probes, root ----------------------------------------------------------------------- */

/* Every page's irradiance along the normal, physical (stored × scale: exact, a power of two). */
static int decode_texels(ex *e)
{
    const lbk_lmap_view *lm = &e->b->lmap;
    e->texels = malloc(((size_t)(e->pages ? lm->texel_count : 0) + 1) * 3 * sizeof *e->texels);
    if (!e->texels) return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    e->page_scale = malloc(((size_t)e->pages + 1) * sizeof *e->page_scale);
    if (!e->page_scale) return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    size_t k = 0;
    for (uint32_t p = 0; p < e->pages; p++) {
        lbk_lmap_planes pg;
        tl_bake_planes(e->b, p, &pg);
        float top = 0.0f;
        for (uint32_t y = 0; y < pg.height; y++)
            for (uint32_t x = 0; x < pg.width; x++, k++) {
                lbk_ahd_texel_f t; /* any encoding (spec §9.2) */
                tl_bake_texel_get(e->b, p, x, y, &t, NULL, NULL);
                for (int c = 0; c < 3; c++) {
                    const float v = t.ez[c] * lm->scale;
                    e->texels[3 * k + (size_t)c] = v;
                    if (isfinite(v) && v > top) top = v;
                }
            }
        /* the page's largest value is code 255: nothing clips, the 8-bit sRGB steps are relative
         * (README "In engines" gives the error measured against the EXR) */
        e->page_scale[p] = top > 0.0f ? top : 1.0f;
    }
    return 0;
}

/* The preview exposure: p99 over every texel (tools/convert/README.md "Previews"); a bake without
 * lightmaps uses its LLG vertices' irradiance instead. The radiance scale: 1, or the power of two
 * that brings the largest LLG vertex value V · E / π to at most 1 (COLOR_0 cannot go above). */
static int compute_exposure(ex *e)
{
    e->exposure = 1.0f;
    e->radiance_scale = 1.0f;
    if (e->pages) e->exposure = tl_exposure_p99(e->texels, (size_t)e->b->lmap.texel_count, 3);
    if (!e->b->has_llg || e->b->llg.vertex_count == 0) return 0;
    const bk_scene *s = e->s;
    float *rgb = malloc((size_t)e->b->llg.vertex_count * 3 * sizeof *rgb);
    uint32_t *rank = malloc((s->vertex_count ? s->vertex_count : 1) * sizeof *rank);
    if (!rgb || !rank) {
        free(rgb), free(rank);
        return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    }
    size_t n = 0;
    for (size_t i = 0; i < s->object_count; i++) {
        lbk_object ob;
        lbk_objects_get(&e->b->objs, (uint32_t)i, &ob);
        lbk_llg_grid g;
        if (ob.representation != LBK_REPRESENTATION_LLG || lbk_llg_grid_get(&e->b->llg, ob.index, &g) != LBK_OK ||
            llg_ranks(s, i, rank) != g.vertex_count)
            continue;
        for (size_t v = 0; v < s->vertex_count && n < e->b->llg.vertex_count; v++)
            if (rank[v] != UINT32_MAX &&
                lbk_llg_vertex_irradiance(&e->b->llg, ob.index, rank[v], &s->positions[3 * v], rgb + 3 * n) == LBK_OK)
                n++;
    }
    if (!e->pages) e->exposure = tl_exposure_p99(rgb, n, 3);
    float top = 0.0f;
    for (size_t i = 0; i < 3 * n; i++)
        if (isfinite(rgb[i]) && rgb[i] / PI_F > top) top = rgb[i] / PI_F;
    while (top * e->radiance_scale > 1.0f && e->radiance_scale > 0x1p-100f) e->radiance_scale *= 0.5f;
    free(rgb), free(rank);
    return 0;
}

static int write_pages(ex *e)
{
    static const char *const RGB[3] = {"R", "G", "B"};
    static const char *const AHD[7] = {"plane0.R", "plane0.G", "plane0.B", "plane1.R", "plane1.G", "plane1.B", "plane1.A"};
    int rc = 0;
    size_t first = 0;
    for (uint32_t p = 0; p < e->pages && !rc; p++) {
        lbk_lmap_planes pg;
        tl_bake_planes(e->b, p, &pg);
        const size_t n = (size_t)pg.width * pg.height;
        const float *ez = e->texels + 3 * first;
        float *ahd = malloc(n * 7 * sizeof *ahd);
        uint8_t *png = malloc(n * 3);
        char path[4400];
        if (!ahd || !png) rc = tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
        for (size_t t = 0; !rc && t < n; t++) {
            memcpy(ahd + 7 * t, ez + 3 * t, 3 * sizeof(float));
            lbk_ahd_texel_f tf;
            tl_bake_texel_get(e->b, p, (uint32_t)(t % pg.width), (uint32_t)(t / pg.width), &tf, NULL, NULL);
            memcpy(ahd + 7 * t + 3, tf.rgba, sizeof tf.rgba);
        }
        if (!rc) {
            snprintf(path, sizeof path, "%s/%s.lightmap_%03u.exr", e->dir, e->stem, p);
            rc = tl_exr_write(path, (int)pg.width, (int)pg.height, 3, RGB, ez, e->err) ? TL_GLTF_IO : 0;
        }
        if (!rc) {
            snprintf(path, sizeof path, "%s/%s.lightmap_%03u.ahd.exr", e->dir, e->stem, p);
            rc = tl_exr_write(path, (int)pg.width, (int)pg.height, 7, AHD, ahd, e->err) ? TL_GLTF_IO : 0;
        }
        if (!rc) {
            tl_tonemap(ez, n, 3, e->exposure, png);
            snprintf(path, sizeof path, "%s/%s.lightmap_%03u.png", e->dir, e->stem, p);
            rc = tl_png_write_rgb8(path, (int)pg.width, (int)pg.height, png, e->err) ? TL_GLTF_IO : 0;
        }
        if (!rc) {
            tl_tonemap(ez, n, 3, 1.0f / e->page_scale[p], png);
            snprintf(path, sizeof path, "%s/%s.lightmap_%03u.emissive.png", e->dir, e->stem, p);
            rc = tl_png_write_rgb8(path, (int)pg.width, (int)pg.height, png, e->err) ? TL_GLTF_IO : 0;
        }
        if (!rc) e->st->exr_files += 2, e->st->png_files += 2;
        free(ahd), free(png);
        first += n;
    }
    return rc;
}

/* Images and textures of the emissive pages (texture p = page p), one linear clamped sampler. */
static void add_textures(ex *e)
{
    cJSON *root = e->g.root;
    cJSON *samplers = cJSON_AddArrayToObject(root, "samplers"), *sm = cJSON_CreateObject();
    cJSON_AddNumberToObject(sm, "magFilter", SAMPLER_LINEAR);
    cJSON_AddNumberToObject(sm, "minFilter", SAMPLER_LINEAR); /* no mipmaps: they would mix charts */
    cJSON_AddNumberToObject(sm, "wrapS", WRAP_CLAMP);
    cJSON_AddNumberToObject(sm, "wrapT", WRAP_CLAMP);
    cJSON_AddItemToArray(samplers, sm);
    cJSON *images = cJSON_AddArrayToObject(root, "images"), *textures = cJSON_AddArrayToObject(root, "textures");
    for (uint32_t p = 0; p < e->pages; p++) {
        char uri[256];
        snprintf(uri, sizeof uri, "%s.lightmap_%03u.emissive.png", e->stem, p);
        cJSON *im = cJSON_CreateObject(), *tx = cJSON_CreateObject();
        cJSON_AddStringToObject(im, "uri", uri);
        cJSON_AddStringToObject(im, "mimeType", "image/png");
        cJSON_AddItemToArray(images, im);
        cJSON_AddNumberToObject(tx, "sampler", 0);
        cJSON_AddNumberToObject(tx, "source", p);
        cJSON_AddItemToArray(textures, tx);
    }
}

static void add_glg(ex *e, cJSON *lbk)
{
    const lbk_glg_view *v = &e->b->glg;
    const size_t np = v->probe_count, nt = v->tetra_count;
    float *pos = malloc(np * 3 * sizeof *pos), *sh = malloc(np * 27 * sizeof *sh);
    uint32_t *tet = malloc(nt * 4 * sizeof *tet), *adj = malloc(nt * 4 * sizeof *adj);
    if (!pos || !sh || !tet || !adj) {
        e->g.failed = 1;
    } else {
        for (size_t i = 0; i < np; i++) {
            lbk_sh9_rgb s;
            lbk_glg_probe_get(v, (uint32_t)i, pos + 3 * i, &s);
            memcpy(sh + 27 * i, s.c, sizeof s.c);
        }
        for (size_t i = 0; i < 4 * nt; i++) {
            const uint8_t *a = v->mesh.tetras + 4 * i, *b = v->mesh.adjacency + 4 * i;
            tet[i] = (uint32_t)a[0] | (uint32_t)a[1] << 8 | (uint32_t)a[2] << 16 | (uint32_t)a[3] << 24;
            adj[i] = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
        }
        cJSON *g = cJSON_AddObjectToObject(lbk, "glg");
        cJSON_AddNumberToObject(g, "probe_count", (double)np);
        cJSON_AddNumberToObject(g, "tetrahedron_count", (double)nt);
        cJSON_AddNumberToObject(g, "positions", tl_glb_accessor_f32(&e->g, pos, np, 3, 0, 0));
        cJSON_AddNumberToObject(g, "sh9", tl_glb_accessor_f32(&e->g, sh, 27 * np, 1, 0, 0));
        cJSON_AddNumberToObject(g, "tetrahedra", tl_glb_accessor_u32(&e->g, tet, 4 * nt, 0));
        cJSON_AddNumberToObject(g, "adjacency", tl_glb_accessor_u32(&e->g, adj, 4 * nt, 0));
        cJSON_AddNumberToObject(g, "visibility", tl_glb_accessor_unorm8(&e->g, v->visibility, 4 * nt));
    }
    free(pos), free(sh), free(tet), free(adj);
}

static const char DECODE_RULE[] =
    "Lightmap coordinate (X, Y) = TEXCOORD_1 * (page width, height), in page texels; texel (x, y) covers "
    "[x, x+1) x [y, y+1), its centre is at TEXCOORD_1 ((x + 0.5)/width, (y + 0.5)/height) (spec/container.md 16.1). "
    "The irradiance EXR holds R,G,B = Ez, the irradiance along the surface normal in lux (linear, physical). The ahd "
    "EXR holds plane0.R,G,B = Ez and plane1.R,G,B,A = the AHD bytes / 255: r = R, d = normalize(2G - 1, 2B - 1, A) "
    "(+Z when shorter than 1/2). Irradiance for a unit tangent-space normal n: E(n) = max(0, a + I (1/4 + n.d/2)) "
    "with a = r Ez, I = (1 - r) Ez / (1/4 + d.z/2) (spec 5.6). Tangent frame: N = the interpolated shading normal, "
    "T = dP/du for u = TEXCOORD_1.x made orthogonal to N, B = N x T (spec 5.6).";

static void add_root_extras(ex *e, const char *container)
{
    cJSON *x = cJSON_AddObjectToObject(e->g.root, "extras"), *l = cJSON_AddObjectToObject(x, "lbk");
    cJSON_AddStringToObject(l, "schema", "lbk-gltf/1");
    if (container) cJSON_AddStringToObject(l, "container", container);
    cJSON_AddStringToObject(l, "units", "irradiance in lux (lm/m^2); SH9 = radiance in nits (cd/m^2); metres");
    cJSON *rules = cJSON_AddObjectToObject(l, "decode_rules");
    cJSON_AddStringToObject(rules, "lbk-ahd/1", DECODE_RULE);
    cJSON *pages = cJSON_AddArrayToObject(l, "lightmap_pages");
    for (uint32_t p = 0; p < e->pages; p++) {
        cJSON *pg = cJSON_CreateObject();
        cJSON_AddNumberToObject(pg, "width", e->page_w[p]);
        cJSON_AddNumberToObject(pg, "height", e->page_h[p]);
        cJSON_AddNumberToObject(pg, "emissive_texture", p);
        cJSON_AddNumberToObject(pg, "emissive_scale", e->page_scale[p]);
        cJSON_AddItemToArray(pages, pg);
    }
    cJSON_AddNumberToObject(l, "preview_exposure", e->exposure);
    cJSON_AddNumberToObject(l, "radiance_scale", e->radiance_scale);
    cJSON_AddStringToObject(l, "sh9_layout",
                            "27 floats per probe: R0..R8, G0..G8, B0..B8, real SH basis of lbk/sh.h (spec 5.5)");
    if (e->b->has_glg) add_glg(e, l);
}

/* "dir/name.glb" → dir and a file-name stem that needs no URI escaping. */
static void split_output(const char *out, char *dir, size_t dn, char *stem, size_t sn)
{
    const char *slash = strrchr(out, '/');
    const char *base = slash ? slash + 1 : out;
    if (slash) snprintf(dir, dn, "%.*s", (int)(slash - out) ? (int)(slash - out) : 1, out);
    else snprintf(dir, dn, ".");
    size_t n = strlen(base);
    if (n > 4 && !strcmp(base + n - 4, ".glb")) n -= 4;
    size_t k = 0;
    for (size_t i = 0; i < n && k + 1 < sn; i++) {
        const char c = base[i];
        const int ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' ||
                       c == '_' || c == '-';
        stem[k++] = ok ? c : '_';
    }
    if (k == 0) stem[k++] = '_';
    stem[k] = '\0';
}

/* The quaternion [x, y, z, w] turning −Z (a glTF light's direction) onto unit d. */
static void rotation_to(const float d[3], float q[4])
{
    const double c = -d[2]; /* cos of the angle between −Z and d */
    if (c < -0.999999) {    /* d = +Z: half a turn about X */
        q[0] = 1, q[1] = q[2] = q[3] = 0;
        return;
    }
    double v[4] = {d[1], -d[0], 0, 1 + c}; /* (−Z × d, 1 + cos) */
    const double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[3] * v[3]);
    for (int k = 0; k < 4; k++) q[k] = (float)(v[k] / n);
}

/* The scene's punctual lights (KHR_lights_punctual, candela / lux as the source had them) and
 * its uniform sky (scene extras lbk_sky), so the export is a level that bakes again. */
static void add_lights(ex *e, cJSON *scene_nodes)
{
    const bk_scene *s = e->s;
    if (!s->light_count) return;
    cJSON *lights = cJSON_AddArrayToObject(cJSON_AddObjectToObject(cJSON_AddObjectToObject(e->g.root, "extensions"),
                                                                   "KHR_lights_punctual"), "lights");
    static const char *const types[3] = {"point", "spot", "directional"};
    for (size_t i = 0; i < s->light_count; i++) {
        const bk_light *l = &s->lights[i];
        const float k = fmaxf(l->color[0], fmaxf(l->color[1], l->color[2]));
        const float col[3] = {k > 0 ? l->color[0] / k : 1, k > 0 ? l->color[1] / k : 1, k > 0 ? l->color[2] / k : 1};
        cJSON *li = cJSON_CreateObject();
        cJSON_AddStringToObject(li, "name", l->name);
        cJSON_AddStringToObject(li, "type", types[l->type >= 0 && l->type <= 2 ? l->type : 0]);
        cJSON_AddItemToObject(li, "color", cJSON_CreateFloatArray(col, 3));
        cJSON_AddNumberToObject(li, "intensity", k);
        if (l->range > 0 && l->type != BK_LIGHT_DIRECTIONAL) cJSON_AddNumberToObject(li, "range", l->range);
        if (l->type == BK_LIGHT_SPOT) {
            cJSON *sp = cJSON_AddObjectToObject(li, "spot");
            /* the extension wants inner < outer; an equal pair becomes a hair softer */
            cJSON_AddNumberToObject(sp, "innerConeAngle", l->inner_cone < l->outer_cone ? l->inner_cone : 0.999f * l->outer_cone);
            cJSON_AddNumberToObject(sp, "outerConeAngle", l->outer_cone);
        }
        cJSON_AddItemToArray(lights, li);
        cJSON *n = cJSON_CreateObject();
        cJSON_AddStringToObject(n, "name", l->name);
        if (l->type != BK_LIGHT_DIRECTIONAL) cJSON_AddItemToObject(n, "translation", cJSON_CreateFloatArray(l->position, 3));
        if (l->type != BK_LIGHT_POINT) {
            float q[4];
            rotation_to(l->direction, q);
            cJSON_AddItemToObject(n, "rotation", cJSON_CreateFloatArray(q, 4));
        }
        cJSON_AddNumberToObject(cJSON_AddObjectToObject(cJSON_AddObjectToObject(n, "extensions"), "KHR_lights_punctual"),
                                "light", (double)i);
        if (l->light_set[0]) cJSON_AddStringToObject(cJSON_AddObjectToObject(n, "extras"), "lbk_light_set", l->light_set);
        cJSON_AddItemToArray(e->nodes, n);
        cJSON_AddItemToArray(scene_nodes, cJSON_CreateNumber(cJSON_GetArraySize(e->nodes) - 1));
    }
}

static int run(ex *e, const tl_gltf_options *o)
{
    int rc = check_objects(e);
    if (rc) return rc;
    e->pages = e->b->has_lmap ? e->b->lmap.page_count : 0;
    e->page_w = calloc(e->pages + 1, sizeof *e->page_w);
    e->page_h = calloc(e->pages + 1, sizeof *e->page_h);
    e->lm_material = malloc(((size_t)e->s->material_count * e->pages + 1) * sizeof *e->lm_material);
    e->plain_material = malloc((e->s->material_count + 1) * sizeof *e->plain_material);
    e->llg_material = malloc((e->s->material_count + 1) * sizeof *e->llg_material);
    if (!e->page_w || !e->page_h || !e->lm_material || !e->plain_material || !e->llg_material ||
        tl_glb_init(&e->g, "lbk export " LBK_LIBRARY_VERSION_STRING) ||
        tl_gltf_normals_init(&e->normals, e->s, e->pages, o->normal_texels))
        return tl_fail(e->err, TL_GLTF_INTERNAL, "out of memory");
    for (size_t i = 0; i < (size_t)e->s->material_count * e->pages; i++) e->lm_material[i] = -1;
    for (size_t i = 0; i < e->s->material_count; i++) e->plain_material[i] = e->llg_material[i] = -1;
    for (uint32_t p = 0; p < e->pages; p++) {
        lbk_lmap_planes pg;
        tl_bake_planes(e->b, p, &pg);
        e->page_w[p] = pg.width;
        e->page_h[p] = pg.height;
    }
    e->st->pages = e->pages;
    if ((rc = decode_texels(e)) || (rc = compute_exposure(e))) return rc;
    e->st->exposure = e->exposure;
    e->nodes = cJSON_AddArrayToObject(e->g.root, "nodes");
    e->meshes = cJSON_AddArrayToObject(e->g.root, "meshes");
    e->materials = cJSON_AddArrayToObject(e->g.root, "materials");
    for (size_t i = 0; i < e->s->object_count && !rc; i++) rc = emit_object(e, i);
    if (rc) return rc;
    if (e->pages && (rc = write_pages(e))) return rc;
    if (e->pages) add_textures(e);
    if (tl_gltf_normals_write(&e->normals, e->g.root, e->dir, e->stem, &e->st->png_files, e->err)) return TL_GLTF_IO;
    add_root_extras(e, o->container);
    cJSON_AddNumberToObject(e->g.root, "scene", 0);
    cJSON *scenes = cJSON_AddArrayToObject(e->g.root, "scenes"), *sc = cJSON_CreateObject(), *nodes = cJSON_AddArrayToObject(sc, "nodes");
    cJSON_AddStringToObject(sc, "name", "lbk level");
    for (uint32_t i = 0; i < e->st->nodes; i++) cJSON_AddItemToArray(nodes, cJSON_CreateNumber(i));
    add_lights(e, nodes);
    if (e->s->sky_image < 0 && (e->s->sky[0] > 0 || e->s->sky[1] > 0 || e->s->sky[2] > 0))
        cJSON_AddItemToObject(cJSON_AddObjectToObject(sc, "extras"), "lbk_sky", cJSON_CreateFloatArray(e->s->sky, 3));
    cJSON_AddItemToArray(scenes, sc);
    if (e->any_unlit || e->any_strength || e->s->light_count) {
        cJSON *used = cJSON_AddArrayToObject(e->g.root, "extensionsUsed");
        if (e->any_unlit) cJSON_AddItemToArray(used, cJSON_CreateString("KHR_materials_unlit"));
        if (e->any_strength) cJSON_AddItemToArray(used, cJSON_CreateString("KHR_materials_emissive_strength"));
        if (e->s->light_count) cJSON_AddItemToArray(used, cJSON_CreateString("KHR_lights_punctual"));
    }
    return tl_glb_write(&e->g, o->output, e->err) ? (e->g.failed ? TL_GLTF_INTERNAL : TL_GLTF_IO) : 0;
}

int tl_gltf_export(const tl_bake *b, const tl_gltf_options *o, tl_gltf_stats *st, char err[TL_ERR_LEN])
{
    tl_gltf_stats local;
    if (!st) st = &local;
    memset(st, 0, sizeof *st);
    if (!o || !o->output || !o->scene) return tl_fail(err, TL_GLTF_INPUT, "--gltf needs an output and --scene");
    bk_scene scene;
    bk_import_options io;
    memset(&io, 0, sizeof io);
    io.skip_textures = 1; /* materials export their factors only, */
    io.normal_maps = 1;   /* and their normal maps (gltf_normals.c) */
    char msg[512];
    if (bk_import_gltf(o->scene, &io, &scene, msg, sizeof msg)) return tl_fail(err, TL_GLTF_INPUT, "%.250s", msg);
    ex e;
    memset(&e, 0, sizeof e);
    e.b = b;
    e.s = &scene;
    e.st = st;
    e.err = err;
    split_output(o->output, e.dir, sizeof e.dir, e.stem, sizeof e.stem);
    int rc = scene.primitives ? run(&e, o) : tl_fail(err, TL_GLTF_INTERNAL, "the scene import gave no primitive table");
    tl_glb_free(&e.g);
    free(e.page_w), free(e.page_h), free(e.lm_material), free(e.plain_material), free(e.llg_material), free(e.texels);
    free(e.page_scale);
    tl_gltf_normals_free(&e.normals);
    bk_scene_free(&scene);
    return rc;
}
