/* Per-object and per-set GPU memory (memory.h): rectangles and grids from OBJS/LMAP/LLG, and every
 * DLS entry charged to the object whose texel or LLG probe it targets. */
#include "tools/inspect/memory.h"

#include <stdlib.h>
#include <string.h>

/* GPU bytes of a rectangle of a page: its texels in the page's encoding (for block-compressed
 * planes, every block the rectangle touches). */
static uint64_t rect_bytes(const lbk_lmap_view *v, uint32_t page, const lbk_object *o)
{
    lbk_lmap_planes pl;
    if (lbk_lmap_planes_get(v, page, &pl) != LBK_OK) return 0;
    return lbk_lmap_planes_rect_bytes(&pl, o->rect_x, o->rect_y, o->rect_w, o->rect_h);
}

typedef struct owner_maps {
    const tl_bake *b;
    int32_t **texel_owner;  /* per page: object index per texel, -1 none */
    int32_t *llg_owner;     /* per LLG grid: object index */
    tl_level_memory *m;
    uint32_t space;
    int failed;
} owner_maps;

static int charge(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    (void)payloads;
    owner_maps *om = user;
    const uint64_t payload = om->space == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD;
    for (uint32_t i = 0; i < count; i++)
        if (sets[i] < om->m->set_count) {
            om->m->sets[sets[i]].entries[om->space]++;
            om->m->sets[sets[i]].payload_bytes += payload;
        }
    int32_t owner = -1;
    if (om->space == LBK_DLS_SPACE_TEXEL && om->b->has_lmap) {
        for (uint32_t page = om->b->lmap.page_count; page-- > 0;) {
            lbk_lmap_planes pg;
            lbk_lmap_planes_get(&om->b->lmap, page, &pg);
            if (pg.first_texel > target) continue;
            if (om->texel_owner[page] && target - pg.first_texel < (uint64_t)pg.width * pg.height)
                owner = om->texel_owner[page][target - pg.first_texel];
            break;
        }
    } else if (om->space == LBK_DLS_SPACE_LLG && om->b->has_llg) {
        for (uint32_t g = 0; g < om->b->llg.grid_count; g++) {
            lbk_llg_grid grid;
            lbk_llg_grid_get(&om->b->llg, g, &grid);
            const uint64_t n = (uint64_t)grid.dims[0] * grid.dims[1] * grid.dims[2];
            if (target >= grid.probe_offset && target < grid.probe_offset + n) {
                owner = om->llg_owner[g];
                break;
            }
        }
    }
    if (owner >= 0) {
        om->m->objects[owner].dls_entries += count;
        om->m->objects[owner].dls_bytes += payload * count;
    } else {
        om->m->dls_unowned_bytes += payload * count;
    }
    return 0;
}

static int owner_maps_build(const tl_bake *b, tl_level_memory *m, owner_maps *om)
{
    memset(om, 0, sizeof *om);
    om->b = b;
    om->m = m;
    const uint32_t pages = b->has_lmap ? b->lmap.page_count : 0, grids = b->has_llg ? b->llg.grid_count : 0;
    om->texel_owner = calloc(pages + 1, sizeof *om->texel_owner);
    om->llg_owner = malloc((grids + 1) * sizeof *om->llg_owner);
    if (!om->texel_owner || !om->llg_owner) return -1;
    for (uint32_t g = 0; g < grids; g++) om->llg_owner[g] = -1;
    for (uint32_t p = 0; p < pages; p++) {
        lbk_lmap_planes pg;
        lbk_lmap_planes_get(&b->lmap, p, &pg);
        om->texel_owner[p] = malloc(((size_t)pg.width * pg.height + 1) * sizeof **om->texel_owner);
        if (!om->texel_owner[p]) return -1;
        for (size_t i = 0; i < (size_t)pg.width * pg.height; i++) om->texel_owner[p][i] = -1;
    }
    for (uint32_t i = 0; i < m->object_count; i++) {
        lbk_object o;
        lbk_objects_get(&b->objs, i, &o);
        if (o.representation == LBK_REPRESENTATION_LIGHTMAP && o.index < pages) {
            lbk_lmap_planes pg;
            lbk_lmap_planes_get(&b->lmap, o.index, &pg);
            for (uint32_t y = o.rect_y; y < o.rect_y + o.rect_h && y < pg.height; y++)
                for (uint32_t x = o.rect_x; x < o.rect_x + o.rect_w && x < pg.width; x++)
                    om->texel_owner[o.index][(size_t)y * pg.width + x] = (int32_t)i;
        } else if (o.representation == LBK_REPRESENTATION_LLG && o.index < grids) {
            om->llg_owner[o.index] = (int32_t)i;
        }
    }
    return 0;
}

static void owner_maps_free(owner_maps *om, uint32_t pages)
{
    for (uint32_t p = 0; om->texel_owner && p < pages; p++) free(om->texel_owner[p]);
    free(om->texel_owner);
    free(om->llg_owner);
}

int tl_level_memory_get(const tl_bake *b, tl_level_memory *m)
{
    memset(m, 0, sizeof *m);
    m->object_count = b->has_objs ? b->objs.count : 0;
    m->set_count = b->dls ? lbk_dls_set_count(b->dls) : 0;
    m->objects = calloc(m->object_count + 1, sizeof *m->objects);
    m->sets = calloc(m->set_count + 1, sizeof *m->sets);
    if (!m->objects || !m->sets) return tl_level_memory_free(m), -1;
    for (uint32_t i = 0; i < m->object_count; i++) {
        lbk_object o;
        lbk_objects_get(&b->objs, i, &o);
        tl_object_memory *om = &m->objects[i];
        tl_string_copy(om->name, sizeof om->name, o.name);
        om->representation = o.representation;
        if (o.representation == LBK_REPRESENTATION_LIGHTMAP && b->has_lmap) {
            om->texels = (uint64_t)o.rect_w * o.rect_h;
            om->lightmap_bytes = rect_bytes(&b->lmap, o.index, &o);
        } else if (o.representation == LBK_REPRESENTATION_LLG && b->has_llg) {
            lbk_llg_grid g;
            if (lbk_llg_grid_get(&b->llg, o.index, &g) == LBK_OK) {
                om->llg_probes = (uint64_t)g.dims[0] * g.dims[1] * g.dims[2];
                om->llg_vertices = g.vertex_count;
                om->llg_bytes = om->llg_probes * 28 + om->llg_vertices * 4;
            }
        }
    }
    for (uint32_t s = 0; s < m->set_count; s++) {
        lbk_dls_set_info si;
        lbk_dls_set_get(b->dls, s, &si);
        tl_string_copy(m->sets[s].name, sizeof m->sets[s].name, (lbk_string){si.name, si.name_length});
        m->sets[s].kind = si.kind;
    }
    int rc = 0;
    if (b->dls) {
        owner_maps om;
        rc = owner_maps_build(b, m, &om);
        for (uint32_t c = 0; !rc && c < lbk_dls_cluster_count(b->dls); c++) {
            lbk_dls_cluster_info ci;
            lbk_dls_cluster_get(b->dls, c, &ci);
            om.space = ci.space;
            if (lbk_dls_cluster_decode(b->dls, c, charge, &om) != LBK_OK) rc = -1;
        }
        owner_maps_free(&om, b->has_lmap ? b->lmap.page_count : 0);
    }
    for (size_t i = 0; i < m->object_count; i++) {
        tl_object_memory *o = &m->objects[i];
        o->total_bytes = o->lightmap_bytes + o->llg_bytes + o->dls_bytes;
    }
    if (rc) tl_level_memory_free(m);
    return rc;
}

void tl_level_memory_free(tl_level_memory *m)
{
    free(m->objects);
    free(m->sets);
    memset(m, 0, sizeof *m);
}
