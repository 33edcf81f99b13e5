#include "bake/probes/octa_bake.h"

#include <math.h>
#include <string.h>

void bk_octa_probe(const bk_tracer *tracer, const float position[3], const lbk_sh9_rgb *radiance,
                   float max_distance, lbk_octp_probe_desc *out)
{
    memset(out, 0, sizeof *out);
    memcpy(out->position, position, sizeof out->position);
    for (uint32_t j = 0; j < LBK_OCTP_IRR_N; j++)
        for (uint32_t i = 0; i < LBK_OCTP_IRR_N; i++) {
            float dir[3], rgb[3];
            lbk_oct_texel_direction(LBK_OCTP_IRR_N, i, j, dir);
            lbk_sh9_irradiance(radiance, dir, rgb);
            for (int c = 0; c < 3; c++) out->irradiance[j * LBK_OCTP_IRR_N + i][c] = rgb[c] > 0 && isfinite(rgb[c]) ? rgb[c] : 0;
        }
    /* 2×2 stratified sub-texel directions: the octahedral map is not equal-area, but the
     * moments only need to be consistent with how a runtime filters them. */
    const float n = (float)LBK_OCTP_DEPTH_N;
    for (uint32_t j = 0; j < LBK_OCTP_DEPTH_N; j++)
        for (uint32_t i = 0; i < LBK_OCTP_DEPTH_N; i++) {
            double m1 = 0, m2 = 0;
            for (int s = 0; s < BK_OCTA_DEPTH_RAYS; s++) {
                float uv[2] = {((float)i + 0.25f + 0.5f * (float)(s & 1)) / n * 2 - 1,
                               ((float)j + 0.25f + 0.5f * (float)(s >> 1)) / n * 2 - 1};
                float dir[3];
                lbk_oct_decode(uv, dir);
                bk_hit hit;
                float d = max_distance;
                if (bk_tracer_intersect(tracer, position, dir, 0.0f, max_distance, &hit) && hit.t < d) d = hit.t;
                m1 += d;
                m2 += (double)d * d;
            }
            out->depth[j * LBK_OCTP_DEPTH_N + i][0] = (float)(m1 / BK_OCTA_DEPTH_RAYS);
            out->depth[j * LBK_OCTP_DEPTH_N + i][1] = (float)(m2 / BK_OCTA_DEPTH_RAYS);
        }
}
