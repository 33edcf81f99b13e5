/* META in `lbk inspect`: key count and the writer. CPU-only. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/meta.h"

void inspect_describe_meta(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_meta_view v;
    if (lbk_meta_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    lbk_string writer = {"?", 1}, version = {"", 0}, scene = {"", 0};
    lbk_meta_find(&v, LBK_META_WRITER, &writer);
    lbk_meta_find(&v, LBK_META_WRITER_VERSION, &version);
    lbk_meta_find(&v, LBK_META_SCENE_HASH, &scene);
    snprintf(out->detail, sizeof out->detail, "%u keys; writer %.*s %.*s%s%.*s", v.entry_count,
             (int)(writer.size > 40 ? 40 : writer.size), writer.data, (int)(version.size > 20 ? 20 : version.size),
             version.data, scene.size ? "; scene " : "", (int)(scene.size > 16 ? 16 : scene.size), scene.data);
}
