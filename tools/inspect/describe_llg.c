/* LLG in `lbk inspect`: grids, probes, vertices. GPU: the 28-byte SH probes and the 4-byte
 * per-vertex self-visibility; the per-grid boxes stay on the CPU. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/llg.h"

void inspect_describe_llg(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_llg_view v;
    if (lbk_llg_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    out->llg_grids = v.grid_count;
    out->llg_probes = v.probe_count;
    out->llg_vertices = v.vertex_count;
    out->gpu_bytes = v.probe_count * 28 + v.vertex_count * 4;
    snprintf(out->detail, sizeof out->detail, "%u grids, %llu probes, %llu vertices, scale 2^%d", v.grid_count,
             (unsigned long long)v.probe_count, (unsigned long long)v.vertex_count, inspect_scale_log2(v.scale));
}
