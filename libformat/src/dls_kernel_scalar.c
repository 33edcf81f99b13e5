/* The definition of the per-target DLS arithmetic (spec/container.md §12.8), one target at a
 * time, written with the public codecs themselves: the other paths must match it bit for bit. */
#include <string.h>

#include "dls_kernel.h"
#include "internal.h"
#include "lbk/ahd.h"
#include "lbk/pixel.h"
#include "lbk/sh.h"

static void texel_linear(const uint8_t *z, const uint8_t *rgba, lbk_ahd_linear *out)
{
    lbk_ahd_texel t;
    t.irradiance_z = lbk_rd32(z);
    memcpy(t.rgba, rgba, 4);
    lbk_ahd_to_linear(&t, out);
}

static void texel_add(lbk_ahd_linear *acc, const uint8_t *entry, float w)
{
    lbk_ahd_linear l;
    texel_linear(entry, entry + 4, &l);
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) acc->c[c][i] += w * l.c[c][i];
}

static void texel_store(const lbk_ahd_linear *acc, uint8_t *z, uint8_t *rgba)
{
    lbk_ahd_texel o;
    lbk_ahd_from_linear(acc, &o);
    lbk_wr32(z, o.irradiance_z);
    memcpy(rgba, o.rgba, 4);
}

static void probe_add(lbk_sh9_rgb *acc, const uint8_t *entry, float w)
{
    lbk_sh9_rgb l;
    lbk_sh9_unpack(entry, &l);
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < LBK_SH9_COUNT; k++) acc->c[c][k] += w * l.c[c][k];
}

static void texels(const dls_batch *b)
{
    for (uint32_t t = 0; t < b->count; t++) {
        const uint8_t *e = b->entries + (size_t)t * b->stride * LBK_DLS_TEXEL_PAYLOAD;
        lbk_ahd_linear acc;
        texel_linear(b->base0 + 4 * (size_t)t, b->base1 + 4 * (size_t)t, &acc);
        for (uint32_t j = 0; j < b->m; j++) texel_add(&acc, e + (size_t)b->idx[j] * LBK_DLS_TEXEL_PAYLOAD, b->w[j]);
        texel_store(&acc, b->out0 + 4 * (size_t)t, b->out1 + 4 * (size_t)t);
    }
}

static void probes(const dls_batch *b)
{
    for (uint32_t t = 0; t < b->count; t++) {
        const uint8_t *e = b->entries + (size_t)t * b->stride * LBK_DLS_PROBE_PAYLOAD;
        lbk_sh9_rgb acc;
        lbk_sh9_unpack(b->base0 + LBK_DLS_PROBE_PAYLOAD * (size_t)t, &acc);
        for (uint32_t j = 0; j < b->m; j++) probe_add(&acc, e + (size_t)b->idx[j] * LBK_DLS_PROBE_PAYLOAD, b->w[j]);
        lbk_sh9_pack(&acc, b->out0 + LBK_DLS_PROBE_PAYLOAD * (size_t)t);
    }
}

static bool any_weight(const float *w, uint32_t n)
{
    for (uint32_t j = 0; j < n; j++)
        if (w[j] != 0.0f) return true;
    return false;
}

static void texels_var(const dls_var_batch *b)
{
    for (uint32_t t = 0; t < b->count; t++) {
        const float *w = b->we + (b->off[t] - b->off[0]);
        uint8_t *oz = b->out0 + 4 * (size_t)t, *orgba = b->out1 + 4 * (size_t)t;
        const uint8_t *bz = b->base0 + 4 * (size_t)t, *brgba = b->base1 + 4 * (size_t)t;
        if (!any_weight(w, b->n[t])) { /* exactly the base, as for an all-zero dispatch */
            memcpy(oz, bz, 4);
            memcpy(orgba, brgba, 4);
            continue;
        }
        const uint8_t *e = b->entries + (size_t)b->off[t] * LBK_DLS_TEXEL_PAYLOAD;
        lbk_ahd_linear acc;
        texel_linear(bz, brgba, &acc);
        for (uint32_t j = 0; j < b->n[t]; j++)
            if (w[j] != 0.0f) texel_add(&acc, e + (size_t)j * LBK_DLS_TEXEL_PAYLOAD, w[j]);
        texel_store(&acc, oz, orgba);
    }
}

static void probes_var(const dls_var_batch *b)
{
    for (uint32_t t = 0; t < b->count; t++) {
        const float *w = b->we + (b->off[t] - b->off[0]);
        uint8_t *out = b->out0 + LBK_DLS_PROBE_PAYLOAD * (size_t)t;
        const uint8_t *base = b->base0 + LBK_DLS_PROBE_PAYLOAD * (size_t)t;
        if (!any_weight(w, b->n[t])) {
            memcpy(out, base, LBK_DLS_PROBE_PAYLOAD);
            continue;
        }
        const uint8_t *e = b->entries + (size_t)b->off[t] * LBK_DLS_PROBE_PAYLOAD;
        lbk_sh9_rgb acc;
        lbk_sh9_unpack(base, &acc);
        for (uint32_t j = 0; j < b->n[t]; j++)
            if (w[j] != 0.0f) probe_add(&acc, e + (size_t)j * LBK_DLS_PROBE_PAYLOAD, w[j]);
        lbk_sh9_pack(&acc, out);
    }
}

static void texel_decode(const uint32_t *z, const uint32_t *rgba, uint32_t count, lbk_ahd_linear *out)
{
    for (uint32_t t = 0; t < count; t++) {
        lbk_ahd_texel x = {.irradiance_z = z[t]};
        memcpy(x.rgba, &rgba[t], 4);
        lbk_ahd_to_linear(&x, &out[t]);
    }
}

static void texel_encode(const lbk_ahd_linear *in, uint32_t count, uint32_t *z, uint32_t *rgba)
{
    for (uint32_t t = 0; t < count; t++) {
        lbk_ahd_texel x;
        lbk_ahd_from_linear(&in[t], &x);
        z[t] = x.irradiance_z;
        memcpy(&rgba[t], x.rgba, 4);
    }
}

static void probe_decode(const uint8_t *p, uint32_t count, lbk_sh9_rgb *out)
{
    for (uint32_t t = 0; t < count; t++) lbk_sh9_unpack(p + LBK_DLS_PROBE_PAYLOAD * (size_t)t, &out[t]);
}

/* ---- the linear mode ---------------------------------------------------------------------- */

static void lin_sum(const float *base, const float *const *src, const float *w, uint32_t m, size_t n, float *out)
{
    for (size_t i = 0; i < n; i++) {
        float acc = base[i];
        for (uint32_t j = 0; j < m; j++) acc += w[j] * src[j][i];
        out[i] = acc;
    }
}

static void lin_var(const float *base, const float *entries, const float *we, const uint32_t *n, uint32_t count, uint32_t f,
                    float *out)
{
    for (uint32_t t = 0; t < count; t++) {
        for (uint32_t i = 0; i < f; i++) {
            float acc = base[i];
            for (uint32_t e = 0; e < n[t]; e++)
                if (we[e] != 0.0f) acc += we[e] * entries[(size_t)e * f + i];
            out[i] = acc;
        }
        base += f, out += f;
        entries += (size_t)n[t] * f, we += n[t];
    }
}

const dls_kernels *dls_kernels_scalar(void)
{
    static const dls_kernels k = {"scalar", texels, probes, texels_var, probes_var, texel_decode, texel_encode, probe_decode,
                                  lin_sum, lin_var, NULL, false};
    return &k;
}
