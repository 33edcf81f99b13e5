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

/* Level table checks shared by the builder, the reader and (with reports) the validator:
 * 1 ≤ L ≤ 3, finite origin, spacing finite > 0 and increasing, dims 2…256, miss distance in
 * (0, 255]; the probe count the levels imply (≤ 3·256³, no overflow). */
static bool level_ok(const lbk_octp_level *l, float prev_spacing)
{
    if (!lbk_finite3(l->origin) || !isfinite(l->spacing) || !(l->spacing > 0.0f) || !(l->spacing > prev_spacing))
        return false;
    if (!isfinite(l->miss_distance) || !(l->miss_distance > 0.0f) || l->miss_distance > LBK_OCTP_MAX_MISS) return false;
    for (int a = 0; a < 3; a++)
        if (l->dims[a] < 2 || l->dims[a] > LBK_OCTP_MAX_DIM) return false;
    return true;
}

static uint64_t level_probes(const lbk_octp_level *l) { return (uint64_t)l->dims[0] * l->dims[1] * l->dims[2]; }

static void level_read(const uint8_t *q, lbk_octp_level *l)
{
    for (int a = 0; a < 3; a++) l->origin[a] = lbk_rdf32(q + 4 * a);
    l->spacing = lbk_rdf32(q + 12);
    for (int a = 0; a < 3; a++) l->dims[a] = lbk_rd32(q + 16 + 4 * a);
    l->first_probe = lbk_rd32(q + 28);
    l->miss_distance = lbk_rdf32(q + 32);
}

/* Grid point of probe `index` within level l (index relative to the level's first probe). */
static void grid_point(const lbk_octp_level *l, uint32_t index, float g[3])
{
    const uint32_t x = index % l->dims[0], y = index / l->dims[0] % l->dims[1], z = index / l->dims[0] / l->dims[1];
    const uint32_t c[3] = {x, y, z};
    for (int a = 0; a < 3; a++) g[a] = l->origin[a] + l->spacing * (float)c[a];
}

/* The half encoding of the second moment, rounded up where rounding to nearest would make the
 * decoded m2 smaller than the decoded m1² (§14: decoded m2 ≥ m1² in a volume). */
static uint16_t m2_half(float m1h, float m2)
{
    uint16_t h = lbk_float_to_half(m2);
    while (lbk_half_to_float(h) < m1h * m1h && h < 0x7bffu) h++;
    return h;
}

static void write_probe(uint8_t *q, const lbk_octp_probe_desc *pd, float inv, float miss, bool volume)
{
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
            float m0 = m[0] > 0.0f ? m[0] : 0.0f, m1 = m[1] > 0.0f ? m[1] : 0.0f;
            if (volume) { /* a volume's mean is at most the miss distance */
                if (m0 > miss) m0 = miss;
                if (m1 > miss * miss) m1 = miss * miss;
            }
            uint8_t *t = q + LBK_OCTP_DEPTH_OFFSET + 4 * (y * DEPTH_S + x);
            uint16_t h0 = lbk_float_to_half(m0);
            /* rounding to nearest may land above the miss distance: take the half below it */
            while (volume && h0 > 0 && lbk_half_to_float(h0) > miss) h0--;
            lbk_wr16(t, h0);
            lbk_wr16(t + 2, volume ? m2_half(lbk_half_to_float(h0), m1) : lbk_float_to_half(m1));
        }
}

static bool info_ok(const lbk_octp_probe_info *in, float spacing)
{
    if (!lbk_finite3(in->offset) || in->state > LBK_OCTP_NO_NEARBY) return false;
    for (int a = 0; a < 3; a++)
        if (!(fabsf(in->offset[a]) <= 0.5f * spacing)) return false;
    return isfinite(in->backface) && in->backface >= 0.0f && in->backface <= 1.0f && isfinite(in->nearest) &&
           in->nearest >= 0.0f;
}

static lbk_result build_probes(const lbk_octp_build_desc *desc, const lbk_allocator *allocator, void **out,
                               size_t *size)
{
    const lbk_octp_probe_desc *probes = desc->probes;
    const uint32_t count = desc->probe_count, L = desc->level_count;
    float scale = desc->scale;
    if (!probes || !out || !size || count == 0 || L > LBK_OCTP_MAX_LEVELS) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (!lbk_scale_resolve(scale, &scale)) return LBK_ERR_INVALID_ARGUMENT;
    const float inv = 1.0f / scale; /* exact: a power of two */
    lbk_octp_level lv[LBK_OCTP_MAX_LEVELS];
    uint64_t implied = 0;
    for (uint32_t l = 0; l < L; l++) {
        lv[l] = desc->levels[l];
        if (!level_ok(&lv[l], l ? lv[l - 1].spacing : 0.0f)) return LBK_ERR_INVALID_ARGUMENT;
        lv[l].first_probe = (uint32_t)implied;
        implied += level_probes(&lv[l]);
    }
    if (L && (implied != count || !desc->info)) return LBK_ERR_INVALID_ARGUMENT;
    const uint64_t head = LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_LEVEL_SIZE * L;
    uint64_t total;
    if (!lbk_madd_u64(head, count, LBK_OCTP_PROBE_SIZE, &total) || total > SIZE_MAX) return LBK_ERR_LIMIT;
    for (uint32_t p = 0; p < count; p++)
        if (!L && !lbk_finite3(probes[p].position)) return LBK_ERR_INVALID_ARGUMENT;
    for (uint32_t l = 0; l < L; l++)
        for (uint32_t p = lv[l].first_probe; p < lv[l].first_probe + level_probes(&lv[l]); p++)
            if (!info_ok(&desc->info[p], lv[l].spacing)) return LBK_ERR_INVALID_ARGUMENT;
    uint8_t *d = lbk_calloc(allocator, 1, (size_t)total);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(d, count);
    lbk_wrf32(d + 4, scale);
    lbk_wr32(d + 8, L);
    for (uint32_t l = 0; l < L; l++) {
        uint8_t *q = d + LBK_OCTP_HEADER_SIZE + LBK_OCTP_LEVEL_SIZE * l;
        for (int a = 0; a < 3; a++) lbk_wrf32(q + 4 * a, lv[l].origin[a]);
        lbk_wrf32(q + 12, lv[l].spacing);
        for (int a = 0; a < 3; a++) lbk_wr32(q + 16 + 4 * a, lv[l].dims[a]);
        lbk_wr32(q + 28, lv[l].first_probe);
        lbk_wrf32(q + 32, lv[l].miss_distance);
    }
    uint32_t l = 0;
    for (uint32_t p = 0; p < count; p++) {
        uint8_t *q = d + head + (size_t)LBK_OCTP_PROBE_SIZE * p;
        while (L && p >= lv[l].first_probe + level_probes(&lv[l])) l++;
        write_probe(q, &probes[p], inv, L ? lv[l].miss_distance : 0.0f, L != 0);
        if (!L) {
            for (int k = 0; k < 3; k++) lbk_wrf32(q + LBK_OCTP_POSITION_OFFSET + 4 * k, probes[p].position[k]);
            continue;
        }
        const lbk_octp_probe_info *in = &desc->info[p];
        float g[3];
        grid_point(&lv[l], p - lv[l].first_probe, g);
        for (int k = 0; k < 3; k++) {
            lbk_wrf32(q + LBK_OCTP_POSITION_OFFSET + 4 * k, g[k] + in->offset[k]);
            lbk_wrf32(q + LBK_OCTP_INFO_OFFSET + 4 * k, in->offset[k]);
        }
        lbk_wr32(q + LBK_OCTP_INFO_OFFSET + 12, in->state);
        lbk_wr32(q + LBK_OCTP_INFO_OFFSET + 16, in->rays);
        lbk_wrf32(q + LBK_OCTP_INFO_OFFSET + 20, in->backface);
        lbk_wrf32(q + LBK_OCTP_INFO_OFFSET + 24, in->nearest);
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
    return build_probes(&desc, allocator, out, size);
}

lbk_result lbk_octp_open(const void *data, size_t size, lbk_octp_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_OCTP_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    const uint32_t n = lbk_rd32(d), L = lbk_rd32(d + 8);
    if (n == 0 || !lbk_scale_bits_ok(lbk_rd32(d + 4)) || L > LBK_OCTP_MAX_LEVELS || lbk_rd32(d + 12) != 0)
        return LBK_ERR_CORRUPT;
    const uint64_t head = LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_LEVEL_SIZE * L;
    if (head > size) return LBK_ERR_TRUNCATED;
    uint64_t implied = 0;
    for (uint32_t l = 0; l < L; l++) {
        lbk_octp_level *lv = &out->levels[l];
        level_read(d + LBK_OCTP_HEADER_SIZE + LBK_OCTP_LEVEL_SIZE * l, lv);
        if (!level_ok(lv, l ? out->levels[l - 1].spacing : 0.0f) || lv->first_probe != implied) return LBK_ERR_CORRUPT;
        for (uint32_t k = 36; k < LBK_OCTP_LEVEL_SIZE; k++)
            if (d[LBK_OCTP_HEADER_SIZE + LBK_OCTP_LEVEL_SIZE * l + k]) return LBK_ERR_CORRUPT;
        implied += level_probes(lv);
    }
    if (L && implied != n) return LBK_ERR_CORRUPT;
    const uint64_t need = head + (uint64_t)LBK_OCTP_PROBE_SIZE * n;
    if (need > size) return LBK_ERR_TRUNCATED;
    if (need != size) return LBK_ERR_CORRUPT;
    out->data = d;
    out->size = size;
    out->probe_count = n;
    out->probes = d + head;
    out->scale = lbk_rdf32(d + 4);
    out->level_count = L;
    return LBK_OK;
}

lbk_result lbk_octp_probe_info_get(const lbk_octp_view *view, uint32_t index, lbk_octp_probe_info *out)
{
    if (!view || !view->data || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->probe_count || view->level_count == 0) return LBK_ERR_NOT_FOUND;
    const uint8_t *q = view->probes + (size_t)LBK_OCTP_PROBE_SIZE * index + LBK_OCTP_INFO_OFFSET;
    for (int k = 0; k < 3; k++) out->offset[k] = lbk_rdf32(q + 4 * k);
    out->state = lbk_rd32(q + 12);
    out->rays = lbk_rd32(q + 16);
    out->backface = lbk_rdf32(q + 20);
    out->nearest = lbk_rdf32(q + 24);
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

/* Bilinear weights of direction dir on an (N+2)² bordered octahedral map: texel centres at
 * integers of s = (u+1)/2·N + ½, so the 2×2 footprint never leaves the map (§14). */
static void oct_footprint(uint32_t n, const float dir[3], int i0[2], float f[2])
{
    float uv[2];
    lbk_oct_encode(dir, uv);
    for (int a = 0; a < 2; a++) {
        float s = (uv[a] + 1.0f) * 0.5f * (float)n + 0.5f;
        if (!(s >= 0.0f)) s = 0.0f;
        if (s > (float)(n + 1)) s = (float)(n + 1);
        i0[a] = (int)floorf(s);
        if (i0[a] > (int)n) i0[a] = (int)n;
        f[a] = s - (float)i0[a];
    }
}

void lbk_octp_probe_irradiance(const uint8_t *q, const float dir[3], float rgb[3])
{
    int i0[2];
    float f[2];
    oct_footprint(LBK_OCTP_IRR_N, dir, i0, f);
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    for (int dy = 0; dy < 2; dy++)
        for (int dx = 0; dx < 2; dx++) {
            const float w = (dx ? f[0] : 1.0f - f[0]) * (dy ? f[1] : 1.0f - f[1]);
            float c[3];
            lbk_r11g11b10f_unpack(lbk_rd32(q + LBK_OCTP_IRR_OFFSET + 4 * ((size_t)(i0[1] + dy) * IRR_S + (size_t)(i0[0] + dx))), c);
            for (int k = 0; k < 3; k++) rgb[k] += w * c[k];
        }
}

void lbk_octp_probe_depth(const uint8_t *q, const float dir[3], float m[2])
{
    int i0[2];
    float f[2];
    oct_footprint(LBK_OCTP_DEPTH_N, dir, i0, f);
    m[0] = m[1] = 0.0f;
    for (int dy = 0; dy < 2; dy++)
        for (int dx = 0; dx < 2; dx++) {
            const float w = (dx ? f[0] : 1.0f - f[0]) * (dy ? f[1] : 1.0f - f[1]);
            const uint8_t *t = q + LBK_OCTP_DEPTH_OFFSET + 4 * ((size_t)(i0[1] + dy) * DEPTH_S + (size_t)(i0[0] + dx));
            m[0] += w * lbk_half_to_float(lbk_rd16(t));
            m[1] += w * lbk_half_to_float(lbk_rd16(t + 2));
        }
}

lbk_result lbk_octp_irradiance(const lbk_octp_view *view, uint32_t index, const float dir[3], float rgb[3])
{
    if (!view || !view->data || !dir || !rgb) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->probe_count) return LBK_ERR_NOT_FOUND;
    lbk_octp_probe_irradiance(view->probes + (size_t)LBK_OCTP_PROBE_SIZE * index, dir, rgb);
    for (int k = 0; k < 3; k++) rgb[k] *= view->scale;
    return LBK_OK;
}

lbk_result lbk_octp_depth(const lbk_octp_view *view, uint32_t index, const float dir[3], float m[2])
{
    if (!view || !view->data || !dir || !m) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->probe_count) return LBK_ERR_NOT_FOUND;
    lbk_octp_probe_depth(view->probes + (size_t)LBK_OCTP_PROBE_SIZE * index, dir, m);
    return LBK_OK;
}

/* Level table of a volume (§14.1): 1010 count, 1011 a level's fields, 1012 the probe count and
 * first_probe chain. Returns false when the probes cannot be located. */
static bool validate_levels(lbk_vctx *ctx, const uint8_t *d, size_t size, uint32_t n, uint32_t L, lbk_octp_level *lv)
{
    if (L > LBK_OCTP_MAX_LEVELS) {
        lbk_vreport(ctx, 1010, 8, "OCTP has %u levels; at most 3", L);
        return false;
    }
    if ((uint64_t)LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_LEVEL_SIZE * L > size) {
        lbk_vreport(ctx, 1003, 0, "OCTP is %zu bytes, shorter than its level table", size);
        return false;
    }
    uint64_t implied = 0;
    bool ok = true;
    for (uint32_t l = 0; l < L; l++) {
        const uint64_t o = LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_LEVEL_SIZE * l;
        level_read(d + o, &lv[l]);
        if (!level_ok(&lv[l], l ? lv[l - 1].spacing : 0.0f)) {
            lbk_vreport(ctx, 1011, o, "OCTP level %u: origin, spacing (finite, > 0, increasing), dims (2..256) or miss distance ((0, 255]) invalid", l);
            return false;
        }
        lbk_check_zero(ctx, 1001, d, o + 36, o + LBK_OCTP_LEVEL_SIZE, "OCTP level");
        if (lv[l].first_probe != implied) {
            lbk_vreport(ctx, 1012, o + 28, "OCTP level %u first_probe %u; the levels before it hold %llu", l, lv[l].first_probe,
                        (unsigned long long)implied);
            ok = false;
        }
        implied += level_probes(&lv[l]);
    }
    if (implied != n) {
        lbk_vreport(ctx, 1012, 0, "OCTP probe_count %u; its levels hold %llu probes", n, (unsigned long long)implied);
        ok = false;
    }
    return ok;
}

/* The volume form's per-probe data (§14.2): 1013 offset / position, 1014 state and statistics,
 * 1015 moments against the miss distance and m2 ≥ m1². */
static void validate_volume_probe(lbk_vctx *ctx, lbk_rate *rate, const uint8_t *d, uint64_t po, uint32_t p,
                                  const lbk_octp_level *l)
{
    const uint8_t *q = d + po;
    lbk_octp_view v1 = {.data = q, .probes = q, .probe_count = 1, .level_count = 1};
    lbk_octp_probe_info in;
    lbk_octp_probe_info_get(&v1, 0, &in);
    float g[3], pos[3];
    grid_point(l, p - l->first_probe, g);
    bool off_ok = lbk_finite3(in.offset);
    for (int k = 0; k < 3; k++) {
        pos[k] = lbk_rdf32(q + LBK_OCTP_POSITION_OFFSET + 4 * k);
        off_ok = off_ok && fabsf(in.offset[k]) <= 0.5f * l->spacing && pos[k] == g[k] + in.offset[k];
    }
    if (!off_ok && lbk_rate_ok(rate, 4))
        lbk_vreport(ctx, 1013, po + LBK_OCTP_INFO_OFFSET, "OCTP probe %u: offset beyond half a spacing, or position is not grid point + offset", p);
    const bool stats_ok = in.state <= LBK_OCTP_NO_NEARBY && isfinite(in.backface) && in.backface >= 0.0f &&
                          in.backface <= 1.0f && isfinite(in.nearest) && in.nearest >= 0.0f;
    if (!stats_ok && lbk_rate_ok(rate, 5))
        lbk_vreport(ctx, 1014, po + LBK_OCTP_INFO_OFFSET + 12, "OCTP probe %u: state %u unknown, or statistics out of range", p, in.state);
    bool m_ok = true;
    for (uint32_t t = 0; t < DEPTH_S * DEPTH_S; t++) {
        const float m1 = lbk_half_to_float(lbk_rd16(q + LBK_OCTP_DEPTH_OFFSET + 4 * t));
        const float m2 = lbk_half_to_float(lbk_rd16(q + LBK_OCTP_DEPTH_OFFSET + 4 * t + 2));
        if (!(m1 <= l->miss_distance) || !(m2 >= m1 * m1)) m_ok = false; /* m1² exact: 11-bit halves */
    }
    if (!m_ok && lbk_rate_ok(rate, 6))
        lbk_vreport(ctx, 1015, po + LBK_OCTP_DEPTH_OFFSET, "OCTP probe %u: a depth mean beyond the miss distance, or m2 < m1²", p);
    lbk_check_zero(ctx, 1008, d, po + LBK_OCTP_INFO_OFFSET + 28, po + LBK_OCTP_PROBE_SIZE, "OCTP probe");
}

void lbk_validate_octp(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_OCTP_HEADER_SIZE) {
        lbk_vreport(ctx, 1000, 0, "OCTP is %zu bytes, shorter than its 16-byte header", size);
        return;
    }
    const uint32_t n = lbk_rd32(d), L = lbk_rd32(d + 8);
    lbk_check_scale(ctx, 1009, d, 4, "OCTP");
    lbk_check_zero(ctx, 1001, d, 12, LBK_OCTP_HEADER_SIZE, "OCTP header");
    if (n == 0) {
        lbk_vreport(ctx, 1002, 0, "OCTP has no probes");
        return;
    }
    lbk_octp_level lv[LBK_OCTP_MAX_LEVELS];
    if (L && !validate_levels(ctx, d, size, n, L, lv)) return;
    const uint64_t head = LBK_OCTP_HEADER_SIZE + (uint64_t)LBK_OCTP_LEVEL_SIZE * L;
    const uint64_t need = head + (uint64_t)LBK_OCTP_PROBE_SIZE * n;
    if (need != size) {
        lbk_vreport(ctx, 1003, 0, "OCTP is %zu bytes; %u levels and %u probes need %llu", size, L, n, (unsigned long long)need);
        return;
    }
    lbk_rate rate;
    lbk_rate_init(&rate);
    uint32_t l = 0;
    for (uint32_t p = 0; p < n; p++) {
        const uint64_t po = head + (uint64_t)LBK_OCTP_PROBE_SIZE * p;
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
        if (!L) {
            lbk_check_zero(ctx, 1008, d, po + LBK_OCTP_POSITION_OFFSET + 12, po + LBK_OCTP_PROBE_SIZE, "OCTP probe");
            continue;
        }
        while (p >= lv[l].first_probe + level_probes(&lv[l])) l++;
        validate_volume_probe(ctx, &rate, d, po, p, &lv[l]);
    }
    const uint32_t ids[7] = {1004, 1005, 1006, 1007, 1013, 1014, 1015};
    lbk_rate_flush_ids(ctx, &rate, ids, 7);
}
