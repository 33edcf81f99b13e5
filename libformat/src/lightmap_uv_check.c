/* LMUV: a record against the glTF mesh the caller loaded (lightmap_uv.h, spec/container.md §16.4).
 * The one place the check lives: lbk render, lbk export --gltf and lbk view call it through
 * tools/common/lmuv_match.c, an engine directly. */
#include <stdarg.h>
#include <stdio.h>

#include "lbk/lightmap_uv.h"

#include "internal.h"

static const char *const code_names[LBK_LMUV_CHECK_CODE_COUNT_] = {
    [LBK_LMUV_CHECK_OK] = "LBK_LMUV_CHECK_OK",
    [LBK_LMUV_CHECK_NODE] = "LBK_LMUV_CHECK_NODE",
    [LBK_LMUV_CHECK_PRIMITIVE_COUNT] = "LBK_LMUV_CHECK_PRIMITIVE_COUNT",
    [LBK_LMUV_CHECK_SOURCE_PRIMITIVE] = "LBK_LMUV_CHECK_SOURCE_PRIMITIVE",
    [LBK_LMUV_CHECK_SOURCE_VERTEX_COUNT] = "LBK_LMUV_CHECK_SOURCE_VERTEX_COUNT",
    [LBK_LMUV_CHECK_TRIANGLE_COUNT] = "LBK_LMUV_CHECK_TRIANGLE_COUNT",
    [LBK_LMUV_CHECK_CORNER] = "LBK_LMUV_CHECK_CORNER",
    [LBK_LMUV_CHECK_VERTEX_ORDER] = "LBK_LMUV_CHECK_VERTEX_ORDER",
    [LBK_LMUV_CHECK_MESH_CORNER] = "LBK_LMUV_CHECK_MESH_CORNER",
    [LBK_LMUV_CHECK_MESH_FLAGS] = "LBK_LMUV_CHECK_MESH_FLAGS",
};

const char *lbk_lmuv_check_code_name(uint32_t code)
{
    return code < LBK_LMUV_CHECK_CODE_COUNT_ && code_names[code] ? code_names[code] : "LBK_LMUV_CHECK_UNKNOWN";
}

/* Where a refusal is and what differs: the detail the caller gets. */
typedef struct where {
    uint32_t primitive, triangle, corner;
    uint64_t record_value, mesh_value;
} where;

#if defined(__GNUC__)
__attribute__((format(printf, 5, 6)))
#endif
static lbk_result refuse(lbk_lmuv_check_detail *d, lbk_result r, uint32_t code, where w, const char *fmt, ...)
{
    if (!d) return r;
    d->code = code;
    d->primitive = w.primitive;
    d->triangle = w.triangle;
    d->corner = w.corner;
    d->record_value = w.record_value;
    d->mesh_value = w.mesh_value;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(d->message, sizeof d->message, fmt, ap);
    va_end(ap);
    return r;
}

/* The counts of primitive k: the record's (q) against the mesh's (m). */
static lbk_result check_counts(const lbk_lmuv_primitive *q, const lbk_lmuv_mesh_primitive *m, uint32_t k,
                               lbk_lmuv_check_detail *d)
{
    if (m->flags & ~LBK_LMUV_MESH_NO_NORMAL)
        return refuse(d, LBK_ERR_INVALID_ARGUMENT, LBK_LMUV_CHECK_MESH_FLAGS, (where){k, 0, 0, 0, m->flags},
                      "mesh primitive %u: unknown flags 0x%x", k, m->flags);
    if (q->source_primitive != m->source_primitive)
        return refuse(d, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_SOURCE_PRIMITIVE,
                      (where){k, 0, 0, q->source_primitive, m->source_primitive},
                      "LMUV primitive %u is glTF primitive %u, the mesh's is %u", k, q->source_primitive,
                      m->source_primitive);
    if (q->source_vertex_count != m->source_vertex_count)
        return refuse(d, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_SOURCE_VERTEX_COUNT,
                      (where){k, 0, 0, q->source_vertex_count, m->source_vertex_count},
                      "glTF primitive %u: LMUV has %u source vertices, the mesh %u", q->source_primitive,
                      q->source_vertex_count, m->source_vertex_count);
    /* in 64 bits: a hostile triangle_count cannot wrap onto the record's index count */
    if ((uint64_t)q->index_count != 3 * (uint64_t)m->triangle_count)
        return refuse(d, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_TRIANGLE_COUNT,
                      (where){k, 0, 0, q->index_count / 3, m->triangle_count},
                      "glTF primitive %u: LMUV has %u indices (%u triangles), the mesh %u triangles",
                      q->source_primitive, q->index_count, q->index_count / 3, m->triangle_count);
    if (m->triangle_count && !m->corners)
        return refuse(d, LBK_ERR_INVALID_ARGUMENT, LBK_LMUV_CHECK_MESH_CORNER, (where){k, 0, 0, 0, 0},
                      "mesh primitive %u: %u triangles and no corners", k, m->triangle_count);
    return LBK_OK;
}

/* Every corner: the new vertex the record's index buffer names there copies the source vertex
 * the mesh has there. The view's ranges were checked (check_primitive), the indices are checked
 * here, so no read leaves the section whatever the record says. */
static lbk_result check_corners(const lbk_lmuv_view *v, const lbk_lmuv_primitive *q, const lbk_lmuv_mesh_primitive *m,
                                uint32_t k, lbk_lmuv_check_detail *d)
{
    for (uint32_t i = 0; i < q->index_count; i++) {
        const uint32_t t = i / 3, c = i % 3, sv = m->corners[i];
        if (sv >= m->source_vertex_count)
            return refuse(d, LBK_ERR_INVALID_ARGUMENT, LBK_LMUV_CHECK_MESH_CORNER, (where){k, t, c, 0, sv},
                          "mesh primitive %u triangle %u corner %u: vertex %u of %u", k, t, c, sv,
                          m->source_vertex_count);
        const uint32_t nv = lbk_rd32(v->indices + 4 * (q->index_first + i));
        if (nv >= q->vertex_count) return LBK_ERR_RANGE; /* a view lbk_lmuv_open did not check */
        const uint32_t src = lbk_rd32(v->remap + 4 * (q->vertex_first + nv));
        if (src != sv)
            return refuse(d, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_CORNER, (where){k, t, c, src, sv},
                          "glTF primitive %u triangle %u corner %u: LMUV vertex %u copies source vertex %u, the mesh "
                          "has %u there",
                          q->source_primitive, t, c, nv, src, sv);
    }
    return LBK_OK;
}

/* The vertex order of §16.4. With NORMAL: ascending by source vertex (the chart, which breaks
 * ties, is the baker's and not in the file). Without: the importer gave every corner its own
 * vertex, so new vertex i is corner i. */
static lbk_result check_order(const lbk_lmuv_view *v, const lbk_lmuv_primitive *q, const lbk_lmuv_mesh_primitive *m,
                              uint32_t k, lbk_lmuv_check_detail *d)
{
    if (m->flags & LBK_LMUV_MESH_NO_NORMAL) {
        if (q->vertex_count != q->index_count)
            return refuse(d, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER,
                          (where){k, 0, 0, q->vertex_count, q->index_count},
                          "glTF primitive %u has no NORMAL: LMUV has %u new vertices, not one per corner (%u)",
                          q->source_primitive, q->vertex_count, q->index_count);
        for (uint32_t i = 0; i < q->index_count; i++) {
            const uint32_t nv = lbk_rd32(v->indices + 4 * (q->index_first + i));
            if (nv != i)
                return refuse(d, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER, (where){k, i, 0, nv, i},
                              "glTF primitive %u has no NORMAL: corner %u uses new vertex %u, not %u",
                              q->source_primitive, i, nv, i);
        }
        return LBK_OK;
    }
    uint32_t prev = lbk_rd32(v->remap + 4 * q->vertex_first);
    for (uint32_t nv = 1; nv < q->vertex_count; nv++) {
        const uint32_t src = lbk_rd32(v->remap + 4 * (q->vertex_first + nv));
        if (src < prev)
            return refuse(d, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_VERTEX_ORDER, (where){k, nv, 0, src, prev},
                          "glTF primitive %u: LMUV vertex %u copies source vertex %u after vertex %u copied %u "
                          "(ascending by source vertex)",
                          q->source_primitive, nv, src, nv - 1, prev);
        prev = src;
    }
    return LBK_OK;
}

static lbk_result check_primitive(const lbk_lmuv_view *v, uint32_t p, const lbk_lmuv_mesh_primitive *m, uint32_t k,
                                  lbk_lmuv_check_detail *d)
{
    lbk_lmuv_primitive q;
    if (lbk_lmuv_get_primitive(v, p, &q) != LBK_OK || !lbk_range_ok(q.vertex_first, q.vertex_count, v->vertex_count) ||
        !lbk_range_ok(q.index_first, q.index_count, v->index_count) || q.vertex_count == 0)
        return LBK_ERR_RANGE; /* a record or view lbk_lmuv_open did not check */
    lbk_result r = check_counts(&q, m, k, d);
    if (r == LBK_OK) r = check_corners(v, &q, m, k, d);
    if (r == LBK_OK) r = check_order(v, &q, m, k, d);
    return r;
}

lbk_result lbk_lmuv_object_check(const lbk_lmuv_view *view, const lbk_lmuv_object *record,
                                 const lbk_lmuv_mesh_desc *mesh_in, lbk_lmuv_check_detail *detail)
{
    if (detail) memset(detail, 0, sizeof *detail);
    if (!view || !record || !mesh_in || record->kind >= LBK_LMUV_KIND_COUNT_) return LBK_ERR_INVALID_ARGUMENT;
    lbk_lmuv_mesh_desc mesh;
    lbk_result r = LBK_SIZED_IN(&mesh, mesh_in, lbk_lmuv_mesh_desc, primitives);
    if (r != LBK_OK) return r;
    if (record->source_node != mesh.source_node)
        return refuse(detail, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_NODE, (where){0, 0, 0, record->source_node, mesh.source_node},
                      "LMUV record of object %u names glTF node %u, the mesh is node %u", record->object,
                      record->source_node, mesh.source_node);
    if (record->kind == LBK_LMUV_AUTHORED) return LBK_OK; /* TEXCOORD_1 is the layout: nothing else to compare */
    if (mesh.primitive_count && !mesh.primitives) return LBK_ERR_INVALID_ARGUMENT;
    if (record->primitive_count != mesh.primitive_count)
        return refuse(detail, LBK_ERR_MISMATCH, LBK_LMUV_CHECK_PRIMITIVE_COUNT,
                      (where){0, 0, 0, record->primitive_count, mesh.primitive_count},
                      "glTF node %u: LMUV has %u triangle primitives, the mesh %u", record->source_node,
                      record->primitive_count, mesh.primitive_count);
    if (record->primitive_count == 0 ||
        !lbk_range_ok(record->primitive_first, record->primitive_count, view->primitive_count))
        return LBK_ERR_RANGE;
    for (uint32_t k = 0; k < mesh.primitive_count; k++) {
        r = check_primitive(view, record->primitive_first + k, &mesh.primitives[k], k, detail);
        if (r != LBK_OK) return r;
    }
    return LBK_OK;
}
