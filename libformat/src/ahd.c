/* AHD texel encode/decode through the band-1 linear form (model: lbk/ahd.h). */
#include "lbk/ahd.h"

#include <math.h>

#include "lbk/pixel.h"

static const float lum_w[3] = {LBK_LUM_R, LBK_LUM_G, LBK_LUM_B};

static float sanitize(float x)
{
    if (x != x) return 0.0f;
    if (x > 1e30f) return 1e30f;
    if (x < -1e30f) return -1e30f;
    return x;
}

static void decode_direction(const uint8_t rgba[4], float d[3])
{
    const float x = 2.0f * (float)rgba[1] / 255.0f - 1.0f;
    const float y = 2.0f * (float)rgba[2] / 255.0f - 1.0f;
    const float z = (float)rgba[3] / 255.0f;
    const float len = sqrtf(x * x + y * y + z * z);
    if (len < 0.5f) {
        d[0] = 0.0f;
        d[1] = 0.0f;
        d[2] = 1.0f;
        return;
    }
    d[0] = x / len;
    d[1] = y / len;
    d[2] = z / len;
}

void lbk_ahd_from_linear(const lbk_ahd_linear *lin, lbk_ahd_texel *out)
{
    float e0[3], g[3][3];
    for (int c = 0; c < 3; c++) {
        e0[c] = sanitize(lin->c[c][0]);
        for (int i = 0; i < 3; i++) g[c][i] = sanitize(lin->c[c][1 + i]);
    }
    /* direction: luminance-weighted gradient, kept in the upper hemisphere */
    double s[3] = {0, 0, 0};
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 3; i++) s[i] += (double)lum_w[c] * g[c][i];
    double dir[3] = {0.0, 0.0, 1.0};
    const double len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    if (len >= 1e-30) {
        if (s[2] >= 0.0) {
            for (int i = 0; i < 3; i++) dir[i] = s[i] / len;
        } else {
            const double lxy = sqrt(s[0] * s[0] + s[1] * s[1]);
            if (lxy >= 1e-30) {
                dir[0] = s[0] / lxy;
                dir[1] = s[1] / lxy;
                dir[2] = 0.0;
            }
        }
    }
    out->rgba[1] = lbk_float_to_unorm8((float)((dir[0] + 1.0) * 0.5));
    out->rgba[2] = lbk_float_to_unorm8((float)((dir[1] + 1.0) * 0.5));
    out->rgba[3] = lbk_float_to_unorm8((float)dir[2]);
    float d[3];
    decode_direction(out->rgba, d);
    const float k = 0.25f + 0.5f * d[2];

    float a[3], ez[3];
    double lum_a = 0.0, lum_ez = 0.0;
    for (int c = 0; c < 3; c++) {
        float gd = g[c][0] * d[0] + g[c][1] * d[1] + g[c][2] * d[2];
        const float inten = gd > 0.0f ? 2.0f * gd : 0.0f;
        const float amb = e0[c] - 0.25f * inten;
        a[c] = amb > 0.0f ? amb : 0.0f;
        ez[c] = a[c] + inten * k;
        lum_a += (double)lum_w[c] * a[c];
        lum_ez += (double)lum_w[c] * ez[c];
    }
    out->irradiance_z = lbk_r11g11b10f_pack(ez);
    out->rgba[0] = lum_ez > 0.0 ? lbk_float_to_unorm8((float)(lum_a / lum_ez)) : 255;
}

void lbk_ahd_to_linear(const lbk_ahd_texel *texel, lbk_ahd_linear *out)
{
    float ez[3], d[3];
    lbk_r11g11b10f_unpack(texel->irradiance_z, ez);
    decode_direction(texel->rgba, d);
    const float r = lbk_unorm8_to_float(texel->rgba[0]);
    const float k = 0.25f + 0.5f * d[2];
    for (int c = 0; c < 3; c++) {
        float e = ez[c];
        if (e != e) e = 0.0f;              /* NaN code: invalid in files, decoded as black */
        if (e > LBK_UF11_MAX) e = LBK_UF11_MAX; /* Inf code */
        const float amb = r * e;
        const float inten = (1.0f - r) * e / k;
        out->c[c][0] = amb + 0.25f * inten;
        for (int i = 0; i < 3; i++) out->c[c][1 + i] = 0.5f * inten * d[i];
    }
}

void lbk_ahd_linear_eval(const lbk_ahd_linear *lin, const float n[3], float rgb[3])
{
    for (int c = 0; c < 3; c++) {
        const float e = lin->c[c][0] + lin->c[c][1] * n[0] + lin->c[c][2] * n[1] + lin->c[c][3] * n[2];
        rgb[c] = e > 0.0f ? e : 0.0f;
    }
}

void lbk_ahd_irradiance(const lbk_ahd_texel *texel, const float n[3], float rgb[3])
{
    lbk_ahd_linear lin;
    lbk_ahd_to_linear(texel, &lin);
    lbk_ahd_linear_eval(&lin, n, rgb);
}

void lbk_ahd_linear_from_sh9(const lbk_sh9_rgb *radiance, lbk_ahd_linear *out)
{
    const float s0 = LBK_SH_A0 * LBK_SH_Y00, s1 = LBK_SH_A1 * LBK_SH_Y1;
    for (int c = 0; c < 3; c++) {
        const float *l = radiance->c[c];
        out->c[c][0] = s0 * l[0];
        out->c[c][1] = s1 * l[3];
        out->c[c][2] = s1 * l[1];
        out->c[c][3] = s1 * l[2];
    }
}

void lbk_ahd_linear_add_ambient(lbk_ahd_linear *lin, const float rgb[3])
{
    for (int c = 0; c < 3; c++) lin->c[c][0] += rgb[c];
}

void lbk_ahd_linear_add_light(lbk_ahd_linear *lin, const float dir[3], const float rgb[3])
{
    for (int c = 0; c < 3; c++) {
        lin->c[c][0] += 0.25f * rgb[c];
        for (int i = 0; i < 3; i++) lin->c[c][1 + i] += 0.5f * rgb[c] * dir[i];
    }
}

void lbk_ahd_linear_add_scaled(lbk_ahd_linear *dst, const lbk_ahd_linear *src, float w)
{
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) dst->c[c][i] += w * src->c[c][i];
}

void lbk_ahd_texel_pack(const lbk_ahd_texel *texel, uint8_t out[LBK_AHD_TEXEL_SIZE])
{
    const uint32_t v = texel->irradiance_z;
    out[0] = (uint8_t)v;
    out[1] = (uint8_t)(v >> 8);
    out[2] = (uint8_t)(v >> 16);
    out[3] = (uint8_t)(v >> 24);
    for (int i = 0; i < 4; i++) out[4 + i] = texel->rgba[i];
}

void lbk_ahd_texel_unpack(const uint8_t in[LBK_AHD_TEXEL_SIZE], lbk_ahd_texel *texel)
{
    texel->irradiance_z = (uint32_t)in[0] | ((uint32_t)in[1] << 8) | ((uint32_t)in[2] << 16) | ((uint32_t)in[3] << 24);
    for (int i = 0; i < 4; i++) texel->rgba[i] = in[4 + i];
}
