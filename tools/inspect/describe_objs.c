/* OBJS in `lbk inspect`: objects by representation. CPU-only. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/objects.h"

void inspect_describe_objs(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_objects_view v;
    if (lbk_objects_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    out->objects = v.count;
    uint32_t by_rep[LBK_REPRESENTATION_COUNT_ + 1] = {0};
    for (uint32_t i = 0; i < v.count; i++) {
        lbk_object o;
        lbk_objects_get(&v, i, &o);
        by_rep[o.representation < LBK_REPRESENTATION_COUNT_ ? o.representation : LBK_REPRESENTATION_COUNT_]++;
    }
    snprintf(out->detail, sizeof out->detail, "%u objects: %u lightmapped, %u LLG, %u none", v.count,
             by_rep[LBK_REPRESENTATION_LIGHTMAP], by_rep[LBK_REPRESENTATION_LLG], by_rep[LBK_REPRESENTATION_NONE]);
}
