#include "bake/encode/encode.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Tangent-space band-1 irradiance of a texel receiver. */
void bk_texel_linear(const bk_texel *t, const lbk_sh9_rgb *radiance_world, lbk_ahd_linear *out)
{
    float rows[3][3];
    memcpy(rows[0], t->tangent, 12);
    rows[1][0] = t->normal[1] * t->tangent[2] - t->normal[2] * t->tangent[1];
    rows[1][1] = t->normal[2] * t->tangent[0] - t->normal[0] * t->tangent[2];
    rows[1][2] = t->normal[0] * t->tangent[1] - t->normal[1] * t->tangent[0];
    memcpy(rows[2], t->normal, 12);
    lbk_sh9_rgb local;
    lbk_sh9_rotate(radiance_world, rows, &local);
    lbk_ahd_linear_from_sh9(&local, out);
}

double bk_texel_match_irradiance(const bk_texel *t, lbk_sh9_rgb *radiance_world, const float e[3])
{
    lbk_ahd_linear lin;
    bk_texel_linear(t, radiance_world, &lin);
    double worst = 0;
    for (int c = 0; c < 3; c++) {
        const double band1 = (double)lin.c[c][0] + lin.c[c][3];
        if (!(band1 > 1e-30) || !isfinite(e[c])) continue;
        const double f = fmin(fmax((double)e[c] / band1, 0.0), 4.0 / 3.0);
        for (int k = 0; k < 9; k++) radiance_world->c[c][k] = (float)(radiance_world->c[c][k] * f);
        worst = fmax(worst, fabs(f - 1));
    }
    return worst;
}

void bk_texels_match_irradiance(const bk_texels *tx, const uint32_t *texel_of_receiver, size_t n,
                                lbk_sh9_rgb *radiance, const float *irradiance)
{
    for (size_t k = 0; k < n; k++)
        bk_texel_match_irradiance(&tx->receivers[texel_of_receiver[k]], &radiance[k], &irradiance[3 * k]);
}

lbk_result bk_finish_page(float *data, uint8_t *mask, int width, int height, int margin, const bk_seams *seams,
                          uint32_t page, int threads)
{
    bk_dilate(data, 12, mask, width, height, margin + 2);
    if (seams && bk_seams_stitch(seams, page, width, height, data, mask, threads) == (size_t)-1)
        return LBK_ERR_OUT_OF_MEMORY;
    return LBK_OK;
}

/* AHD pages from per-texel linear forms: dilate, stitch, then encode. `lin` is indexed by
 * texel receiver (texels.receivers), `has` says which ones hold a value. */
lbk_result bk_encode_pages(const bk_texels *tx, int margin, const bk_seams *seams, int threads,
                           const lbk_ahd_linear *lin, const uint8_t *has, float inv_scale, lbk_ahd_texel **pages_out)
{
    for (size_t p = 0; p < tx->page_count; p++) {
        int w = tx->pages[p].width, h = tx->pages[p].height;
        size_t n = (size_t)w * (size_t)h;
        float *data = calloc(n * 12, sizeof *data);
        uint8_t *mask = calloc(n, 1);
        lbk_ahd_texel *page = calloc(n ? n : 1, sizeof *page);
        if (!data || !mask || !page) {
            free(data), free(mask), free(page);
            return LBK_ERR_OUT_OF_MEMORY;
        }
        for (size_t i = 0; i < n; i++) {
            int32_t ri = tx->index[tx->page_offset[p] + i];
            if (ri < 0 || !has[ri]) continue;
            const float *c = &lin[ri].c[0][0];
            for (int k = 0; k < 12; k++) data[12 * i + k] = c[k] * inv_scale;
            mask[i] = 1;
        }
        lbk_result r = bk_finish_page(data, mask, w, h, margin, seams, (uint32_t)p, threads);
        if (r != LBK_OK) {
            free(data), free(mask), free(page);
            return r;
        }
        for (size_t i = 0; i < n; i++) {
            if (!mask[i]) continue;
            lbk_ahd_linear l;
            memcpy(l.c, &data[12 * i], sizeof l.c);
            lbk_ahd_from_linear(&l, &page[i]);
        }
        free(data), free(mask);
        pages_out[p] = page;
    }
    return LBK_OK;
}

float bk_scale_for(double max_value)
{
    if (!(max_value > 0) || !isfinite(max_value)) return 1.0f;
    int e;
    frexp(max_value, &e); /* max_value = f·2^e, f in [1/2, 1): floor(log2 max_value) = e − 1 */
    int k = e - 1 - 13;
    if (k < -126) k = -126;
    if (k > 127) k = 127;
    return ldexpf(1.0f, k);
}

double bk_texel_max(const lbk_ahd_linear *lin, const uint8_t *has, size_t n)
{
    double m = 0;
    for (size_t i = 0; i < n; i++) {
        if (has && !has[i]) continue;
        for (int c = 0; c < 3; c++) {
            double ez = (double)lin[i].c[c][0] + lin[i].c[c][3];
            if (ez > m && isfinite(ez)) m = ez;
        }
    }
    return m;
}

double bk_probe_max(const lbk_sh9_rgb *sh, size_t n)
{
    double m = 0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            if (sh[i].c[c][0] > m && isfinite(sh[i].c[c][0])) m = sh[i].c[c][0];
    return m;
}

void bk_count_out_of_range(const lbk_ahd_linear *lin, const uint8_t *has, size_t n, float inv_scale,
                           uint64_t *saturated, uint64_t *flushed)
{
    uint64_t sat = 0, low = 0;
    for (size_t i = 0; i < n; i++) {
        if (!has[i]) continue;
        for (int c = 0; c < 3; c++) {
            float ez = (lin[i].c[c][0] + lin[i].c[c][3]) * inv_scale;
            sat += ez > 65024.0f;
            low += ez > 0 && ez < 0x1p-21f;
        }
    }
    *saturated = sat;
    *flushed = low;
}
