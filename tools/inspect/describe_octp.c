/* OCTP in `lbk inspect`: octahedral probes, 1024 bytes each, all GPU-resident; a probe volume
 * (1.3) also lists its levels and the probes' states. */
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
    int n = snprintf(out->detail, sizeof out->detail, "%u probes (1024 B each), scale 2^%d", v.probe_count,
                     inspect_scale_log2(v.scale));
    if (v.level_count == 0 || n < 0 || (size_t)n >= sizeof out->detail) return;
    uint32_t st[3] = {0, 0, 0}, moved = 0;
    for (uint32_t i = 0; i < v.probe_count; i++) {
        lbk_octp_probe_info in;
        if (lbk_octp_probe_info_get(&v, i, &in) != LBK_OK || in.state > 2) continue;
        st[in.state]++;
        moved += in.offset[0] != 0 || in.offset[1] != 0 || in.offset[2] != 0;
    }
    for (uint32_t l = 0; l < v.level_count && (size_t)n < sizeof out->detail; l++) {
        const lbk_octp_level *lv = &v.levels[l];
        int k = snprintf(out->detail + n, sizeof out->detail - (size_t)n, "; level %u: %u×%u×%u at %g m", l, lv->dims[0],
                         lv->dims[1], lv->dims[2], lv->spacing);
        if (k < 0) return;
        n += k;
    }
    if ((size_t)n < sizeof out->detail)
        snprintf(out->detail + n, sizeof out->detail - (size_t)n, "; %u active, %u inside (inactive), %u no nearby geometry, %u relocated",
                 st[0], st[1], st[2], moved);
}
