/* LMUV in `lbk inspect`: records by kind and the bytes of each array. CPU-only: an engine reads
 * it when it builds meshes (the coordinates end up in its own vertex buffers). */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/lightmap_uv.h"

void inspect_describe_lmuv(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_lmuv_view v;
    if (lbk_lmuv_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    uint32_t authored = 0;
    for (uint32_t r = 0; r < v.record_count; r++) {
        lbk_lmuv_object o;
        lbk_lmuv_get_object(&v, r, &o);
        authored += o.kind == LBK_LMUV_AUTHORED;
    }
    snprintf(out->detail, sizeof out->detail,
             "%u objects (%u authored, %u generated), %u primitives, %llu vertices, %llu triangles; "
             "bytes: records %llu, primitives %llu, remap %llu, indices %llu, coords %llu",
             v.record_count, authored, v.record_count - authored, v.primitive_count,
             (unsigned long long)v.vertex_count, (unsigned long long)(v.index_count / 3),
             (unsigned long long)v.record_count * LBK_LMUV_RECORD_SIZE,
             (unsigned long long)v.primitive_count * LBK_LMUV_PRIMITIVE_SIZE, (unsigned long long)v.vertex_count * 4,
             (unsigned long long)v.index_count * 4, (unsigned long long)v.vertex_count * 8);
}
