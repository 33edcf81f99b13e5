/* REPT in `lbk inspect`: why the bake stopped and its final estimated error. CPU-only. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/report.h"

void inspect_describe_rept(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_report_view v;
    if (lbk_report_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    lbk_report_record last = {0};
    if (v.header.record_count) lbk_report_record_get(&v, v.header.record_count - 1, &last);
    snprintf(out->detail, sizeof out->detail, "%s; %u records; last: %u spp, texel rel. RMSE %.4g, probe %.4g",
             lbk_bake_status_name(v.header.status), v.header.record_count, last.samples_per_texel,
             (double)last.texel_rel_rmse, (double)last.probe_rel_rmse);
}
