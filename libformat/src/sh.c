/* Band-2 real SH: basis, projection, irradiance, rotation, and the 28-byte probe. */
#include "lbk/sh.h"

#include <string.h>

#include "lbk/pixel.h"

static const float band_scale[LBK_SH9_COUNT] = {
    1.0f, 1.7320508075688772f, 1.7320508075688772f, 1.7320508075688772f, /* √3 */
    2.2360679774997897f, 2.2360679774997897f, 2.2360679774997897f, 2.2360679774997897f,
    2.2360679774997897f /* √5 */
};

static const float band_a[LBK_SH9_COUNT] = {LBK_SH_A0, LBK_SH_A1, LBK_SH_A1, LBK_SH_A1, LBK_SH_A2,
                                            LBK_SH_A2, LBK_SH_A2, LBK_SH_A2, LBK_SH_A2};

void lbk_sh9_basis(const float d[3], float out[LBK_SH9_COUNT])
{
    const float x = d[0], y = d[1], z = d[2];
    out[0] = LBK_SH_Y00;
    out[1] = LBK_SH_Y1 * y;
    out[2] = LBK_SH_Y1 * z;
    out[3] = LBK_SH_Y1 * x;
    out[4] = LBK_SH_Y2 * x * y;
    out[5] = LBK_SH_Y2 * y * z;
    out[6] = LBK_SH_Y20 * (3.0f * z * z - 1.0f);
    out[7] = LBK_SH_Y2 * x * z;
    out[8] = LBK_SH_Y22 * (x * x - y * y);
}

void lbk_sh9_add_sample(lbk_sh9_rgb *sh, const float dir[3], const float rgb[3], float weight)
{
    float y[LBK_SH9_COUNT];
    lbk_sh9_basis(dir, y);
    for (int c = 0; c < 3; c++) {
        const float w = rgb[c] * weight;
        for (int k = 0; k < LBK_SH9_COUNT; k++) sh->c[c][k] += w * y[k];
    }
}

void lbk_sh9_add_scaled(lbk_sh9_rgb *dst, const lbk_sh9_rgb *src, float w)
{
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < LBK_SH9_COUNT; k++) dst->c[c][k] += w * src->c[c][k];
}

void lbk_sh9_eval(const lbk_sh9_rgb *sh, const float dir[3], float rgb[3])
{
    float y[LBK_SH9_COUNT];
    lbk_sh9_basis(dir, y);
    for (int c = 0; c < 3; c++) {
        float s = 0.0f;
        for (int k = 0; k < LBK_SH9_COUNT; k++) s += sh->c[c][k] * y[k];
        rgb[c] = s;
    }
}

void lbk_sh9_irradiance(const lbk_sh9_rgb *sh, const float n[3], float rgb[3])
{
    float y[LBK_SH9_COUNT];
    lbk_sh9_basis(n, y);
    for (int c = 0; c < 3; c++) {
        float s = 0.0f;
        for (int k = 0; k < LBK_SH9_COUNT; k++) s += band_a[k] * sh->c[c][k] * y[k];
        rgb[c] = s;
    }
}

/* Band 2 as a symmetric traceless quadratic form: Σ_m L2m Y2m(ω) = ωᵀ Q ω. */
static void band2_to_quadratic(const float *l, double q[3][3])
{
    const double c2 = LBK_SH_Y2, c20 = LBK_SH_Y20, c22 = LBK_SH_Y22;
    /* ωᵀQω = c2 l4 xy + c2 l5 yz + c20 l6 (3z² − 1) + c2 l7 xz + c22 l8 (x² − y²); with
     * x²+y²+z² = 1, −1 = −(x²+y²+z²), so the form is traceless. */
    q[0][0] = c22 * l[8] - c20 * l[6];
    q[1][1] = -c22 * l[8] - c20 * l[6];
    q[2][2] = 2.0 * c20 * l[6];
    q[0][1] = q[1][0] = 0.5 * c2 * l[4];
    q[1][2] = q[2][1] = 0.5 * c2 * l[5];
    q[0][2] = q[2][0] = 0.5 * c2 * l[7];
}

static void quadratic_to_band2(double q[3][3], float *l)
{
    l[4] = (float)(2.0 * q[0][1] / LBK_SH_Y2);
    l[5] = (float)(2.0 * q[1][2] / LBK_SH_Y2);
    l[7] = (float)(2.0 * q[0][2] / LBK_SH_Y2);
    l[6] = (float)(q[2][2] / (2.0 * LBK_SH_Y20));
    l[8] = (float)((q[0][0] - q[1][1]) / (2.0 * LBK_SH_Y22));
}

void lbk_sh9_rotate(const lbk_sh9_rgb *sh, const float r[3][3], lbk_sh9_rgb *out)
{
    lbk_sh9_rgb tmp;
    for (int c = 0; c < 3; c++) {
        const float *l = sh->c[c];
        float *o = tmp.c[c];
        o[0] = l[0];
        /* band 1 is Y1 · (L11, L1−1, L10)·ω: a vector g; in the new frame g' = R g */
        const float g[3] = {l[3], l[1], l[2]};
        float gp[3];
        for (int i = 0; i < 3; i++) gp[i] = r[i][0] * g[0] + r[i][1] * g[1] + r[i][2] * g[2];
        o[3] = gp[0];
        o[1] = gp[1];
        o[2] = gp[2];
        /* band 2: Q' = R Q Rᵀ */
        double q[3][3], rq[3][3], qp[3][3];
        band2_to_quadratic(l, q);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double s = 0.0;
                for (int k = 0; k < 3; k++) s += (double)r[i][k] * q[k][j];
                rq[i][j] = s;
            }
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double s = 0.0;
                for (int k = 0; k < 3; k++) s += rq[i][k] * (double)r[j][k];
                qp[i][j] = s;
            }
        quadratic_to_band2(qp, o);
    }
    *out = tmp;
}

void lbk_sh9_pack(const lbk_sh9_rgb *sh, uint8_t out[LBK_SH9_PACKED_SIZE])
{
    const float dc[3] = {sh->c[0][0], sh->c[1][0], sh->c[2][0]};
    const uint32_t packed_dc = lbk_rgb9e5_pack(dc);
    float dq[3];
    lbk_rgb9e5_unpack(packed_dc, dq);
    out[0] = (uint8_t)packed_dc;
    out[1] = (uint8_t)(packed_dc >> 8);
    out[2] = (uint8_t)(packed_dc >> 16);
    out[3] = (uint8_t)(packed_dc >> 24);
    for (int k = 1; k < LBK_SH9_COUNT; k++)
        for (int c = 0; c < 3; c++) {
            uint8_t q = 0;
            if (dq[c] > 0.0f) q = lbk_float_to_snorm8(sh->c[c][k] / (band_scale[k] * dq[c]));
            out[4 + 3 * (k - 1) + c] = q;
        }
}

void lbk_sh9_unpack(const uint8_t in[LBK_SH9_PACKED_SIZE], lbk_sh9_rgb *sh)
{
    const uint32_t packed_dc = (uint32_t)in[0] | ((uint32_t)in[1] << 8) | ((uint32_t)in[2] << 16) |
                               ((uint32_t)in[3] << 24);
    float dq[3];
    lbk_rgb9e5_unpack(packed_dc, dq);
    for (int c = 0; c < 3; c++) {
        sh->c[c][0] = dq[c];
        for (int k = 1; k < LBK_SH9_COUNT; k++)
            sh->c[c][k] = lbk_snorm8_to_float(in[4 + 3 * (k - 1) + c]) * band_scale[k] * dq[c];
    }
}
