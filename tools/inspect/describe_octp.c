/* OCTP in `lbk inspect`: octahedral probes, 1024 bytes each, all GPU-resident. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/octa.h"

void inspect_describe_octp(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_octp_view v;
    if (lbk_octp_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    out->octp_probes = v.probe_count;
    out->gpu_bytes = (uint64_t)v.probe_count * 1024;
    snprintf(out->detail, sizeof out->detail, "%u probes (1024 B each), scale 2^%d", v.probe_count,
             inspect_scale_log2(v.scale));
}
