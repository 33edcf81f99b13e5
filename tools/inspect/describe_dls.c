/* DLS in `lbk inspect`: sets, clusters, payload and ancillary bytes. GPU: the entries' payloads
 * and the per-target index data the apply dispatches read; set names and tables stay on the CPU. */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats: experimental (lbk/dls.h) */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/dls.h"

void inspect_describe_dls(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_dls_view *v;
    if (lbk_dls_open(data, size, NULL, &v) != LBK_OK) return;
    lbk_dls_stats st;
    if (lbk_dls_stats_get(v, &st) == LBK_OK) {
        out->parsed = 1;
        out->dls_sets = st.set_count;
        out->dls_light_sets = st.sets_by_kind[LBK_DLS_KIND_LIGHTS];
        out->dls_clusters = st.cluster_count;
        out->dls_payload_bytes = st.payload_bytes;
        out->dls_ancillary_bytes = st.ancillary_bytes;
        uint64_t index = 0;
        for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) index += st.index_bytes[s];
        out->gpu_bytes = st.payload_bytes + index;
        /* overlap histogram over every space: targets touched by 1, 2, 3, 4-8, >8 sets */
        unsigned long long h[5] = {0, 0, 0, 0, 0};
        for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++)
            for (int k = 1; k < LBK_DLS_HISTOGRAM_BINS; k++) h[k <= 3 ? k - 1 : k <= 8 ? 3 : 4] += st.histogram[s][k];
        snprintf(out->detail, sizeof out->detail,
                 "%u sets (%u light sets), %u clusters; payload %llu B, ancillary %llu B; index %.2f bits/texel; "
                 "overlaps 1:%llu 2:%llu 3:%llu 4-8:%llu >8:%llu",
                 st.set_count, st.sets_by_kind[LBK_DLS_KIND_LIGHTS], st.cluster_count,
                 (unsigned long long)st.payload_bytes, (unsigned long long)st.ancillary_bytes,
                 st.index_bits_per_target[LBK_DLS_SPACE_TEXEL], h[0], h[1], h[2], h[3], h[4]);
    }
    lbk_dls_close(v);
}
