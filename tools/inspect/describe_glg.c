/* GLG in `lbk inspect`: probes and tetrahedra. GPU: the 28-byte SH probes plus what a GPU lookup
 * walks — positions (12 B), tetrahedra (16 B), adjacency (16 B) and face visibility (4 B). */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/glg.h"

void inspect_describe_glg(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_glg_view v;
    if (lbk_glg_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    out->glg_probes = v.probe_count;
    out->glg_tetrahedra = v.tetra_count;
    out->gpu_bytes = (uint64_t)v.probe_count * (28 + 12) + (uint64_t)v.tetra_count * (16 + 16 + 4);
    snprintf(out->detail, sizeof out->detail, "%u probes, %u tetrahedra, scale 2^%d", v.probe_count, v.tetra_count,
             inspect_scale_log2(v.scale));
}
