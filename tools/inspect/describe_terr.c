/* TERR in `lbk inspect`: how many texels carry an estimate and the distribution of their relative
 * errors (median, 90th percentile, from the codes' histogram). CPU-only: a diagnostic map, not
 * something a renderer uploads. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/error_map.h"

/* The smallest code whose cumulative count reaches fraction q of the estimated texels. */
static int quantile_code(const uint64_t hist[256], uint64_t total, double q)
{
    uint64_t run = 0;
    for (int c = 1; c < 256; c++) {
        run += hist[c];
        if ((double)run >= q * (double)total) return c;
    }
    return 255;
}

void inspect_describe_terr(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_terr_view v;
    if (lbk_terr_open(data, size, &v) != LBK_OK) return;
    out->parsed = 1;
    uint64_t hist[256] = {0};
    for (uint64_t i = 0; i < v.texel_count; i++) hist[v.codes[i]]++;
    const uint64_t est = v.texel_count - hist[0];
    out->terr_present = 1;
    out->terr_denoised = (v.flags & LBK_TERR_DENOISED) != 0;
    out->terr_texels = v.texel_count;
    out->terr_estimated = est;
    out->terr_median = est ? lbk_terr_decode((uint8_t)quantile_code(hist, est, 0.5)) : 0;
    out->terr_p90 = est ? lbk_terr_decode((uint8_t)quantile_code(hist, est, 0.9)) : 0;
    snprintf(out->detail, sizeof out->detail,
             "per-texel relative error of %llu of %llu texels: median %.3g %%, 90th percentile %.3g %%%s",
             (unsigned long long)est, (unsigned long long)v.texel_count, 100 * out->terr_median, 100 * out->terr_p90,
             out->terr_denoised ? "; before denoising (the texels were denoised after it)" : "");
}
