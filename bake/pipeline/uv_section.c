/* LMUV from the atlas (see uv_section.h; layout: spec/container.md §16). */
#include "bake/pipeline/uv_section.h"

#include <stdlib.h>
#include <string.h>

#include "lbk/lightmap_uv.h"

int bk_uv_section_lightmapped(const bk_atlas *a, const bk_object_class *classes, size_t i)
{
    if (!classes || classes[i].rep != BK_REP_LIGHTMAP || !a->object_slot || i >= a->scene_object_count) return 0;
    const int32_t slot = a->object_slot[i];
    return slot >= 0 && a->objects[slot].page >= 0;
}

/* Lightmap coordinate of every lightmap vertex: a charted corner's page texel coordinate, else
 * (zero-area triangles only) the centre of its object's first texel, as atlas.c places it. */
static float *vertex_coords(const bk_atlas *a)
{
    float *xy = malloc((a->vertex_count ? a->vertex_count : 1) * 2 * sizeof *xy);
    uint8_t *set = calloc(a->vertex_count ? a->vertex_count : 1, 1);
    if (!xy || !set) {
        free(xy), free(set);
        return NULL;
    }
    for (size_t e = 0; e < a->tri_count; e++)
        for (int c = 0; c < 3; c++) {
            const uint32_t id = a->scene_tri_vertices[3 * (size_t)a->tris[e] + (size_t)c];
            if (id >= a->vertex_count || set[id]) continue;
            xy[2 * (size_t)id] = a->tri_uv[6 * e + 2 * (size_t)c];
            xy[2 * (size_t)id + 1] = a->tri_uv[6 * e + 2 * (size_t)c + 1];
            set[id] = 1;
        }
    for (size_t id = 0; id < a->vertex_count; id++) {
        if (set[id]) continue;
        const bk_atlas_object *o = &a->objects[a->vertex_slot[id]];
        xy[2 * id] = (float)o->x + 0.5f;
        xy[2 * id + 1] = (float)o->y + 0.5f;
    }
    free(set);
    return xy;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

typedef struct build_ctx {
    const bk_scene *s;
    const bk_atlas *a;
    const float *xy;    /* per lightmap vertex */
    uint32_t *local;    /* per lightmap vertex: index in the primitive being built, or UINT32_MAX */
} build_ctx;

/* New vertices (the primitive's lightmap vertices, ascending id), remap, coordinates and the
 * triangle list in the glTF primitive's own winding. */
static lbk_result build_primitive(build_ctx *b, const bk_primitive *p, int mirrored, lbk_lmuv_primitive_desc *d)
{
    const bk_atlas *a = b->a;
    const size_t n3 = 3 * (size_t)p->tri_count;
    uint32_t *ids = malloc(n3 * sizeof *ids);
    uint32_t *idx = malloc(n3 * sizeof *idx);
    if (!ids || !idx) {
        free(ids), free(idx);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t k = 0; k < n3; k++) {
        ids[k] = a->scene_tri_vertices[3 * (size_t)p->first_tri + k];
        if (ids[k] >= a->vertex_count) {
            free(ids), free(idx);
            return LBK_ERR_INVALID_ARGUMENT;
        }
    }
    qsort(ids, n3, sizeof *ids, cmp_u32);
    size_t n = 0;
    for (size_t k = 0; k < n3; k++)
        if (n == 0 || ids[k] != ids[n - 1]) ids[n++] = ids[k];
    uint32_t *remap = malloc(n * sizeof *remap);
    float *coords = malloc(n * 2 * sizeof *coords);
    lbk_result r = remap && coords ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    for (size_t k = 0; r == LBK_OK && k < n; k++) {
        const uint32_t v = a->vertex_source[ids[k]];
        if (v < p->first_vertex || v - p->first_vertex >= p->vertex_count) r = LBK_ERR_INVALID_ARGUMENT;
        else remap[k] = b->s->vertex_source[v];
        coords[2 * k] = b->xy[2 * (size_t)ids[k]];
        coords[2 * k + 1] = b->xy[2 * (size_t)ids[k] + 1];
        b->local[ids[k]] = (uint32_t)k;
    }
    /* import swapped corners 1 and 2 under a mirroring transform; the glTF primitive has the
     * original order, and the engine's node transform mirrors it again */
    static const int straight[3] = {0, 1, 2}, swapped[3] = {0, 2, 1};
    const int *order = mirrored ? swapped : straight;
    for (size_t t = 0; r == LBK_OK && t < p->tri_count; t++)
        for (int k = 0; k < 3; k++)
            idx[3 * t + (size_t)k] = b->local[a->scene_tri_vertices[3 * ((size_t)p->first_tri + t) + (size_t)order[k]]];
    for (size_t k = 0; k < n; k++) b->local[ids[k]] = UINT32_MAX;
    free(ids);
    if (r != LBK_OK) {
        free(remap), free(coords), free(idx);
        return r;
    }
    d->source_primitive = p->gltf_primitive;
    d->source_vertex_count = p->source_vertex_count;
    d->vertex_count = (uint32_t)n;
    d->index_count = (uint32_t)n3;
    d->remap = remap;
    d->indices = idx;
    d->coords = coords;
    return LBK_OK;
}

static void authored_record(const bk_atlas_object *o, lbk_lmuv_object_desc *d)
{
    d->kind = LBK_LMUV_AUTHORED;
    for (int q = 0; q < 2; q++) {
        d->scale[q] = (float)o->uv1_scale;
        d->offset[q] = (float)o->uv1_offset[q];
        d->uv_min[q] = (float)o->uv1_min[q];
        d->uv_max[q] = (float)o->uv1_max[q];
    }
}

static void free_records(lbk_lmuv_object_desc *rec, size_t n)
{
    for (size_t i = 0; rec && i < n; i++) {
        for (uint32_t p = 0; p < rec[i].primitive_count; p++) {
            free((void *)rec[i].primitives[p].remap);
            free((void *)rec[i].primitives[p].indices);
            free((void *)rec[i].primitives[p].coords);
        }
        free((void *)rec[i].primitives);
    }
    free(rec);
}

lbk_result bk_uv_section_build(const bk_scene *s, const bk_atlas *a, const bk_object_class *classes, void **out,
                               size_t *size)
{
    if (!out || !size) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (!s || !a || !s->primitives || !s->vertex_source || !a->scene_tri_vertices) return LBK_OK;
    size_t n = 0;
    for (size_t i = 0; i < s->object_count; i++) n += (size_t)bk_uv_section_lightmapped(a, classes, i);
    if (n == 0) return LBK_OK;
    if (n > UINT32_MAX) return LBK_ERR_LIMIT;
    build_ctx b = {s, a, vertex_coords(a), malloc((a->vertex_count ? a->vertex_count : 1) * sizeof(uint32_t))};
    lbk_lmuv_object_desc *rec = calloc(n, sizeof *rec);
    lbk_result r = b.xy && b.local && rec ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    if (b.local) memset(b.local, 0xff, (a->vertex_count ? a->vertex_count : 1) * sizeof(uint32_t));
    size_t k = 0, p0 = 0; /* primitives are in object order */
    for (size_t i = 0; r == LBK_OK && i < s->object_count; i++) {
        while (p0 < s->primitive_count && s->primitives[p0].object < i) p0++;
        if (!bk_uv_section_lightmapped(a, classes, i)) continue;
        lbk_lmuv_object_desc *d = &rec[k++];
        const bk_atlas_object *o = &a->objects[a->object_slot[i]];
        d->object = (uint32_t)i;
        d->source_node = (uint32_t)s->objects[i].node;
        if (o->uv_source == BK_UV_AUTHORED) {
            authored_record(o, d);
            continue;
        }
        d->kind = LBK_LMUV_GENERATED;
        size_t np = 0;
        while (p0 + np < s->primitive_count && s->primitives[p0 + np].object == i) np++;
        lbk_lmuv_primitive_desc *pd = calloc(np ? np : 1, sizeof *pd);
        if (!pd) {
            r = LBK_ERR_OUT_OF_MEMORY;
            break;
        }
        d->primitives = pd;
        for (size_t q = 0; r == LBK_OK && q < np; q++) {
            r = build_primitive(&b, &s->primitives[p0 + q], s->objects[i].mirrored, &pd[q]);
            if (r == LBK_OK) d->primitive_count++;
        }
        if (r == LBK_OK && np == 0) r = LBK_ERR_INVALID_ARGUMENT;
    }
    if (r == LBK_OK) r = lbk_lmuv_build(rec, (uint32_t)n, NULL, out, size);
    free_records(rec, n);
    free((void *)b.xy);
    free(b.local);
    return r;
}
