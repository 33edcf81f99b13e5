/* Octahedral mapping and the OCTP section (spec/container.md §14). */
#include "lbk/octa.h"

#include <math.h>

#include "internal.h"
#include "lbk/pixel.h"
#include "section_util.h"

static float sign_nz(float x) { return x >= 0.0f ? 1.0f : -1.0f; }

void lbk_oct_encode(const float d[3], float uv[2])
{
    const float s = fabsf(d[0]) + fabsf(d[1]) + fabsf(d[2]);
    if (!(s > 0.0f)) {
        uv[0] = uv[1] = 0.0f;
        return;
    }
    const float x = d[0] / s, y = d[1] / s;
    if (d[2] >= 0.0f) {
        uv[0] = x;
        uv[1] = y;
    } else {
        uv[0] = (1.0f - fabsf(y)) * sign_nz(x);
        uv[1] = (1.0f - fabsf(x)) * sign_nz(y);
    }
}

void lbk_oct_decode(const float uv[2], float d[3])
{
    float x = uv[0], y = uv[1];
    const float z = 1.0f - fabsf(x) - fabsf(y);
    if (z < 0.0f) {
        const float ox = x;
        x = (1.0f - fabsf(y)) * sign_nz(ox);
        y = (1.0f - fabsf(ox)) * sign_nz(y);
    }
    const float len = sqrtf(x * x + y * y + z * z);
    d[0] = x / len;
    d[1] = y / len;
    d[2] = z / len;
}

void lbk_oct_border_source(uint32_t n, uint32_t x, uint32_t y, uint32_t *sx, uint32_t *sy)
{
    const uint32_t s = n + 1;
    const bool bx = x == 0 || x == s, by = y == 0 || y == s;
    if (bx && by) { /* corners: the diagonally opposite interior corner */
        *sx = x == 0 ? n : 1;
        *sy = y == 0 ? n : 1;
    } else if (by) {
        *sx = s - x;
        *sy = y == 0 ? 1 : n;
    } else if (bx) {
        *sx = x == 0 ? 1 : n;
        *sy = s - y;
    } else {
        *sx = x;
        *sy = y;
    }
}

void lbk_oct_texel_direction(uint32_t n, uint32_t i, uint32_t j, float dir[3])
{
    const float uv[2] = {((float)i + 0.5f) / (float)n * 2.0f - 1.0f, ((float)j + 0.5f) / (float)n * 2.0f - 1.0f};
    lbk_oct_decode(uv, dir);
}

/* ---- OCTP ----------------------------------------------------------------------------------- */

#define IRR_S (LBK_OCTP_IRR_N + 2u)
#define DEPTH_S (LBK_OCTP_DEPTH_N + 2u)

static lbk_result build_probes(const lbk_octp_probe_desc *probes, uint32_t count, float scale,
                               const lbk_allocator *allocator, void **out, size_t *size)
{
    if (!probes || !out || !size || count == 0) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (!lbk_scale_resolve(scale, &scale)) return LBK_ERR_INVALID_ARGUMENT;
    const float inv = 1.0f / scale; /* exact: a power of two */
    uint64_t total;
    if (!lbk_madd_u64(LBK_OCTP_HEADER_SIZE, count, LBK_OCTP_PROBE_SIZE, &total) || total > SIZE_MAX) return LBK_ERR_LIMIT;
    for (uint32_t p = 0; p < count; p++)
        if (!lbk_finite3(probes[p].position)) return LBK_ERR_INVALID_ARGUMENT;
    uint8_t *d = lbk_calloc(allocator, 1, (size_t)total);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(d, count);
    lbk_wrf32(d + 4, scale);
    for (uint32_t p = 0; p < count; p++) {
        uint8_t *q = d + LBK_OCTP_HEADER_SIZE + (size_t)LBK_OCTP_PROBE_SIZE * p;
        const lbk_octp_probe_desc *pd = &probes[p];
        for (uint32_t y = 0; y < IRR_S; y++)
            for (uint32_t x = 0; x < IRR_S; x++) {
                uint32_t sx, sy;
                lbk_oct_border_source(LBK_OCTP_IRR_N, x, y, &sx, &sy);
                const float *c = pd->irradiance[(sy - 1) * LBK_OCTP_IRR_N + (sx - 1)];
                const float st[3] = {c[0] * inv, c[1] * inv, c[2] * inv};
                lbk_wr32(q + LBK_OCTP_IRR_OFFSET + 4 * (y * IRR_S + x), lbk_r11g11b10f_pack(st));
            }
        for (uint32_t y = 0; y < DEPTH_S; y++)
            for (uint32_t x = 0; x < DEPTH_S; x++) {
                uint32_t sx, sy;
                lbk_oct_border_source(LBK_OCTP_DEPTH_N, x, y, &sx, &sy);
                const float *m = pd->depth[(sy - 1) * LBK_OCTP_DEPTH_N + (sx - 1)];
                /* moments are non-negative: NaN and negatives become 0 */
                const float m0 = m[0] > 0.0f ? m[0] : 0.0f, m1 = m[1] > 0.0f ? m[1] : 0.0f;
                uint8_t *t = q + LBK_OCTP_DEPTH_OFFSET + 4 * (y * DEPTH_S + x);
                lbk_wr16(t, lbk_float_to_half(m0));
                lbk_wr16(t + 2, lbk_float_to_half(m1));
            }
        for (int k = 0; k < 3; k++) lbk_wrf32(q + LBK_OCTP_POSITION_OFFSET + 4 * k, pd->position[k]);
    }
    *out = d;
    *size = (size_t)total;
    return LBK_OK;
}

lbk_result lbk_octp_build(const lbk_octp_build_desc *caller_desc, const lbk_allocator *allocator, void **out,
                          size_t *size)
{
    if (out) *out = NULL;
    if (size) *size = 0;
    if (!caller_desc) return LBK_ERR_INVALID_ARGUMENT;
    lbk_octp_build_desc desc;
    lbk_result rc = LBK_SIZED_IN(&desc, caller_desc, lbk_octp_build_desc, scale);
    if (rc != LBK_OK) return rc;
    return build_probes(desc.probes, desc.probe_count, desc.scale, allocator, out, size);
}

lbk_result lbk_octp_open(const void *data, size_t size, lbk_octp_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_OCTP_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    const uint32_t n = lbk_rd32(d);
    if (n == 0 || !lbk_scale_bits_ok(lbk_rd32(d + 4)) || lbk_rd64(d + 8) != 0) return LBK_ERR_CORRUPT;
    const uint64_t need = LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_PROBE_SIZE * n;
    if (need > size) return LBK_ERR_TRUNCATED;
    if (need != size) return LBK_ERR_CORRUPT;
    out->data = d;
    out->size = size;
    out->probe_count = n;
    out->probes = d + LBK_OCTP_HEADER_SIZE;
    out->scale = lbk_rdf32(d + 4);
    return LBK_OK;
}

lbk_result lbk_octp_probe_get(const lbk_octp_view *view, uint32_t index, lbk_octp_probe_desc *out)
{
    if (!view || !view->data || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->probe_count) return LBK_ERR_NOT_FOUND;
    const uint8_t *q = view->probes + (size_t)LBK_OCTP_PROBE_SIZE * index;
    for (uint32_t j = 0; j < LBK_OCTP_IRR_N; j++)
        for (uint32_t i = 0; i < LBK_OCTP_IRR_N; i++) {
            float *c = out->irradiance[j * LBK_OCTP_IRR_N + i];
            lbk_r11g11b10f_unpack(lbk_rd32(q + LBK_OCTP_IRR_OFFSET + 4 * ((j + 1) * IRR_S + i + 1)), c);
            for (int k = 0; k < 3; k++) c[k] *= view->scale;
        }
    for (uint32_t j = 0; j < LBK_OCTP_DEPTH_N; j++)
        for (uint32_t i = 0; i < LBK_OCTP_DEPTH_N; i++) {
            const uint8_t *t = q + LBK_OCTP_DEPTH_OFFSET + 4 * ((j + 1) * DEPTH_S + i + 1);
            out->depth[j * LBK_OCTP_DEPTH_N + i][0] = lbk_half_to_float(lbk_rd16(t));
            out->depth[j * LBK_OCTP_DEPTH_N + i][1] = lbk_half_to_float(lbk_rd16(t + 2));
        }
    for (int k = 0; k < 3; k++) out->position[k] = lbk_rdf32(q + LBK_OCTP_POSITION_OFFSET + 4 * k);
    return LBK_OK;
}

lbk_result lbk_octp_irradiance(const lbk_octp_view *view, uint32_t index, const float dir[3], float rgb[3])
{
    if (!view || !view->data || !dir || !rgb) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->probe_count) return LBK_ERR_NOT_FOUND;
    const uint8_t *q = view->probes + (size_t)LBK_OCTP_PROBE_SIZE * index;
    float uv[2];
    lbk_oct_encode(dir, uv);
    float s[2];
    int i0[2];
    float f[2];
    for (int a = 0; a < 2; a++) {
        s[a] = (uv[a] + 1.0f) * 0.5f * (float)LBK_OCTP_IRR_N + 0.5f; /* texel centres at integers */
        if (s[a] < 0.0f) s[a] = 0.0f;
        if (s[a] > (float)(IRR_S - 1)) s[a] = (float)(IRR_S - 1);
        i0[a] = (int)floorf(s[a]);
        if (i0[a] > (int)IRR_S - 2) i0[a] = (int)IRR_S - 2;
        f[a] = s[a] - (float)i0[a];
    }
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    for (int dy = 0; dy < 2; dy++)
        for (int dx = 0; dx < 2; dx++) {
            const float w = (dx ? f[0] : 1.0f - f[0]) * (dy ? f[1] : 1.0f - f[1]);
            float c[3];
            lbk_r11g11b10f_unpack(lbk_rd32(q + 4 * ((size_t)(i0[1] + dy) * IRR_S + (size_t)(i0[0] + dx))), c);
            for (int k = 0; k < 3; k++) rgb[k] += w * c[k];
        }
    for (int k = 0; k < 3; k++) rgb[k] *= view->scale;
    return LBK_OK;
}

void lbk_validate_octp(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_OCTP_HEADER_SIZE) {
        lbk_vreport(ctx, 1000, 0, "OCTP is %zu bytes, shorter than its 16-byte header", size);
        return;
    }
    const uint32_t n = lbk_rd32(d);
    lbk_check_scale(ctx, 1009, d, 4, "OCTP");
    lbk_check_zero(ctx, 1001, d, 8, LBK_OCTP_HEADER_SIZE, "OCTP header");
    if (n == 0) {
        lbk_vreport(ctx, 1002, 0, "OCTP has no probes");
        return;
    }
    const uint64_t need = LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_PROBE_SIZE * n;
    if (need != size) {
        lbk_vreport(ctx, 1003, 0, "OCTP is %zu bytes; %u probes need %llu", size, n, (unsigned long long)need);
        return;
    }
    lbk_rate rate;
    lbk_rate_init(&rate);
    for (uint32_t p = 0; p < n; p++) {
        const uint64_t po = LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_PROBE_SIZE * p;
        const uint8_t *q = d + po;
        bool border_ok = true;
        for (uint32_t y = 0; y < IRR_S; y++)
            for (uint32_t x = 0; x < IRR_S; x++) {
                const uint64_t o = LBK_OCTP_IRR_OFFSET + 4 * (uint64_t)(y * IRR_S + x);
                const uint32_t v = lbk_rd32(q + o);
                if (lbk_r11g11b10f_special(v) && lbk_rate_ok(&rate, 0))
                    lbk_vreport(ctx, 1004, po + o, "OCTP probe %u irradiance texel (%u, %u) 0x%08x has an Inf/NaN channel", p,
                                x, y, v);
                uint32_t sx, sy;
                lbk_oct_border_source(LBK_OCTP_IRR_N, x, y, &sx, &sy);
                if (lbk_rd32(q + 4 * (sy * IRR_S + sx)) != v) border_ok = false;
            }
        for (uint32_t y = 0; y < DEPTH_S; y++)
            for (uint32_t x = 0; x < DEPTH_S; x++) {
                const uint64_t o = LBK_OCTP_DEPTH_OFFSET + 4 * (uint64_t)(y * DEPTH_S + x);
                const uint16_t m0 = lbk_rd16(q + o), m1 = lbk_rd16(q + o + 2);
                /* finite and non-negative (−0 allowed) */
                const bool bad = (m0 & 0x7c00u) == 0x7c00u || (m1 & 0x7c00u) == 0x7c00u || (m0 > 0x8000u) || (m1 > 0x8000u);
                if (bad && lbk_rate_ok(&rate, 1))
                    lbk_vreport(ctx, 1005, po + o, "OCTP probe %u depth texel (%u, %u) moments 0x%04x 0x%04x are not finite and non-negative",
                                p, x, y, m0, m1);
                uint32_t sx, sy;
                lbk_oct_border_source(LBK_OCTP_DEPTH_N, x, y, &sx, &sy);
                if (lbk_rd32(q + LBK_OCTP_DEPTH_OFFSET + 4 * (sy * DEPTH_S + sx)) != lbk_rd32(q + o)) border_ok = false;
            }
        if (!border_ok && lbk_rate_ok(&rate, 2))
            lbk_vreport(ctx, 1006, po, "OCTP probe %u has a border texel that differs from its source", p);
        float pos[3];
        for (int k = 0; k < 3; k++) pos[k] = lbk_rdf32(q + LBK_OCTP_POSITION_OFFSET + 4 * k);
        if (!lbk_finite3(pos) && lbk_rate_ok(&rate, 3))
            lbk_vreport(ctx, 1007, po + LBK_OCTP_POSITION_OFFSET, "OCTP probe %u position is not finite", p);
        lbk_check_zero(ctx, 1008, d, po + LBK_OCTP_POSITION_OFFSET + 12, po + LBK_OCTP_PROBE_SIZE, "OCTP probe");
    }
    const uint32_t ids[4] = {1004, 1005, 1006, 1007};
    lbk_rate_flush_ids(ctx, &rate, ids, 4);
}
