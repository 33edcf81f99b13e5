/* An LMUV record against the scene object it names (lmuv_match.h): the scene described as an
 * engine's glTF loader would, and liblbk's check (lbk_lmuv_object_check) does the rest. */
#include "tools/common/lmuv_match.h"

#include <stdlib.h>

#include "tools/common/error_util.h"

void tl_object_primitives(const bk_scene *s, size_t i, size_t *first, size_t *count)
{
    size_t p = 0;
    while (p < s->primitive_count && s->primitives[p].object < i) p++;
    *first = p;
    while (p < s->primitive_count && s->primitives[p].object == i) p++;
    *count = p - *first;
}

/* The importer gives a primitive without NORMAL one vertex per triangle corner (flat shading),
 * so its vertices are not the glTF's; with NORMAL they are, in order. An unindexed primitive
 * without NORMAL comes out in order too, and there the two vertex orders of §16.4 coincide. */
static int imported_flat(const bk_scene *s, const bk_primitive *p)
{
    if (p->vertex_count != p->source_vertex_count) return 1;
    for (uint32_t v = 0; v < p->vertex_count; v++)
        if (s->vertex_source[(size_t)p->first_vertex + v] != v) return 1;
    return 0;
}

/* The object's primitives as lbk_lmuv_mesh_primitive: corners in the glTF winding (the importer
 * swapped corners 1 and 2 of a mirrored node's triangles). corners: 3 × the object's triangles. */
static void describe(const bk_scene *s, size_t i, size_t pf, size_t pn, uint32_t *corners, lbk_lmuv_mesh_primitive *mp)
{
    static const uint32_t straight[3] = {0, 1, 2}, swapped[3] = {0, 2, 1};
    const uint32_t *order = s->objects[i].mirrored ? swapped : straight;
    for (size_t k = 0; k < pn; k++) {
        const bk_primitive *p = &s->primitives[pf + k];
        for (size_t t = 0; t < p->tri_count; t++)
            for (size_t c = 0; c < 3; c++)
                corners[3 * t + c] = s->vertex_source[s->tris[3 * ((size_t)p->first_tri + t) + order[c]]];
        mp[k] = (lbk_lmuv_mesh_primitive){.source_primitive = p->gltf_primitive,
                                          .source_vertex_count = p->source_vertex_count,
                                          .triangle_count = p->tri_count,
                                          .flags = imported_flat(s, p) ? LBK_LMUV_MESH_NO_NORMAL : 0,
                                          .corners = corners};
        corners += 3 * (size_t)p->tri_count;
    }
}

int tl_lmuv_match_object(const bk_scene *s, size_t i, const lbk_lmuv_view *lv, const lbk_lmuv_object *r, int status,
                         char err[TL_ERR_LEN])
{
    if (!s->vertex_source) return tl_fail(err, status, "object %zu: the scene import gave no vertex provenance", i);
    size_t pf, pn, corners = 0;
    tl_object_primitives(s, i, &pf, &pn);
    const int generated = r->kind == LBK_LMUV_GENERATED;
    for (size_t k = 0; generated && k < pn; k++) corners += 3 * (size_t)s->primitives[pf + k].tri_count;
    lbk_lmuv_mesh_primitive *mp = calloc(pn ? pn : 1, sizeof *mp);
    uint32_t *cv = malloc((corners ? corners : 1) * sizeof *cv);
    if (!mp || !cv || pn > UINT32_MAX) {
        free(mp), free(cv);
        return tl_fail(err, status, "object %zu: out of memory", i);
    }
    if (generated) describe(s, i, pf, pn, cv, mp);
    lbk_lmuv_mesh_desc mesh = LBK_LMUV_MESH_DESC_INIT;
    mesh.source_node = (uint32_t)s->objects[i].node;
    mesh.primitive_count = (uint32_t)pn;
    mesh.primitives = mp;
    lbk_lmuv_check_detail why;
    const lbk_result rc = lbk_lmuv_object_check(lv, r, &mesh, &why);
    free(mp), free(cv);
    if (rc == LBK_OK) return 0;
    return rc == LBK_ERR_MISMATCH ? tl_fail(err, status, "object %zu: %s", i, why.message)
                                  : tl_fail(err, status, "object %zu: LMUV record: %s (%s)", i, lbk_result_message(rc),
                                            why.message);
}
