/* An LMUV record against the scene object it names (lmuv_match.h). */
#include "tools/common/lmuv_match.h"

#include "tools/common/error_util.h"

void tl_object_primitives(const bk_scene *s, size_t i, size_t *first, size_t *count)
{
    size_t p = 0;
    while (p < s->primitive_count && s->primitives[p].object < i) p++;
    *first = p;
    while (p < s->primitive_count && s->primitives[p].object == i) p++;
    *count = p - *first;
}

/* Every triangle corner of a generated primitive: the new vertex its index names comes from the
 * glTF vertex the scene has at that corner. The importer swapped corners 1 and 2 of a mirrored
 * node's triangles; LMUV keeps the glTF winding. */
static int match_corners(const bk_scene *s, size_t i, const bk_primitive *p, const lbk_lmuv_view *lv,
                         const lbk_lmuv_primitive *q, int status, char err[TL_ERR_LEN])
{
    static const uint32_t straight[3] = {0, 1, 2}, swapped[3] = {0, 2, 1};
    const uint32_t *order = s->objects[i].mirrored ? swapped : straight;
    for (uint32_t t = 0; t < p->tri_count; t++)
        for (uint32_t c = 0; c < 3; c++) {
            uint32_t nv, src;
            if (lbk_lmuv_index(lv, q, 3 * t + order[c], &nv) != LBK_OK ||
                lbk_lmuv_vertex(lv, q, nv, &src, NULL) != LBK_OK)
                return tl_fail(err, status, "object %zu primitive %u: LMUV triangle %u is out of range", i,
                               q->source_primitive, t);
            const uint32_t sv = s->tris[3 * ((size_t)p->first_tri + t) + c];
            if (s->vertex_source[sv] != src)
                return tl_fail(err, status,
                               "glTF primitive %u: LMUV vertex %u (source vertex %u) is not where the scene has it "
                               "(triangle %u has source vertex %u there)",
                               q->source_primitive, nv, src, t, s->vertex_source[sv]);
        }
    return 0;
}

int tl_lmuv_match_object(const bk_scene *s, size_t i, const lbk_lmuv_view *lv, const lbk_lmuv_object *r, int status,
                         char err[TL_ERR_LEN])
{
    if (r->source_node != (uint32_t)s->objects[i].node)
        return tl_fail(err, status, "object %zu: LMUV names glTF node %u, the scene node %d", i, r->source_node,
                       (int)s->objects[i].node);
    if (r->kind != LBK_LMUV_GENERATED) return 0;
    size_t pf, pn;
    tl_object_primitives(s, i, &pf, &pn);
    if (r->primitive_count != pn)
        return tl_fail(err, status, "object %zu: LMUV has %u primitives, the scene %zu", i, r->primitive_count, pn);
    for (size_t k = 0; k < pn; k++) {
        lbk_lmuv_primitive q;
        const bk_primitive *p = &s->primitives[pf + k];
        if (lbk_lmuv_get_primitive(lv, r->primitive_first + (uint32_t)k, &q) != LBK_OK)
            return tl_fail(err, status, "object %zu: LMUV primitive %u is out of range", i,
                           r->primitive_first + (uint32_t)k);
        if (q.source_primitive != p->gltf_primitive || q.source_vertex_count != p->source_vertex_count ||
            q.index_count != 3 * (uint64_t)p->tri_count)
            return tl_fail(err, status,
                           "object %zu primitive %u: LMUV (%u vertices, %u indices) does not match the scene's (%u, %u)",
                           i, q.source_primitive, q.source_vertex_count, q.index_count, p->source_vertex_count,
                           3 * p->tri_count);
        int rc = match_corners(s, i, p, lv, &q, status, err);
        if (rc) return rc;
    }
    return 0;
}
