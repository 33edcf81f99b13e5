/* The OCTP volume sampler (spec/container.md §14.3): trilinear over the 8 probes of a cell,
 * weighted by a back-face term and the Chebyshev visibility bound of the probes' depth moments
 * (Majercik et al. 2019, DDGI; seed 003's "variance depth attenuation"), inactive probes skipped,
 * blended between clip levels near a finer level's edge. */
#include <math.h>
#include <string.h>

#include "internal.h"
#include "lbk/octa.h"
#include "section_util.h"

static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Weights below this are crushed (w³/0.04): a probe that the moments say is hidden fades fast,
 * while 1e-6 keeps the result defined when every probe is hidden (DDGI's rule). */
#define OCTP_CRUSH 0.2f
#define OCTP_FLOOR 1e-6f

/* Grid coordinates of q in level l (in cells). */
static void level_coords(const lbk_octp_level *l, const float q[3], float g[3])
{
    for (int a = 0; a < 3; a++) g[a] = (q[a] - l->origin[a]) / l->spacing;
}

static bool level_contains(const lbk_octp_level *l, const float g[3])
{
    for (int a = 0; a < 3; a++)
        if (!(g[a] >= 0.0f && g[a] <= (float)(l->dims[a] - 1))) return false;
    return true;
}

/* Visibility weight of one probe (before trilinear): back-face × Chebyshev, floored and crushed. */
static float probe_weight(const uint8_t *q, const float p[3], const float pb[3], const float n[3], bool has_n,
                          uint32_t flags)
{
    float P[3], w = 1.0f;
    for (int a = 0; a < 3; a++) P[a] = lbk_rdf32(q + LBK_OCTP_POSITION_OFFSET + 4 * a);
    if (has_n && !(flags & LBK_OCTP_SAMPLE_NO_BACKFACE)) {
        float d[3] = {P[0] - p[0], P[1] - p[1], P[2] - p[2]};
        const float len = sqrtf(dot3(d, d));
        const float c = len > 0.0f ? dot3(d, n) / len : 1.0f;
        const float h = 0.5f * (c + 1.0f);
        w *= h * h + 0.2f;
    }
    if (!(flags & LBK_OCTP_SAMPLE_NO_CHEBYSHEV)) {
        float r[3] = {pb[0] - P[0], pb[1] - P[1], pb[2] - P[2]};
        const float dist = sqrtf(dot3(r, r));
        if (dist > 0.0f) {
            for (int a = 0; a < 3; a++) r[a] /= dist;
            float m[2];
            lbk_octp_probe_depth(q, r, m);
            if (dist > m[0]) {
                const float var = fmaxf(m[1] - m[0] * m[0], 0.0f);
                const float e = dist - m[0];
                const float c = var + e * e > 0.0f ? var / (var + e * e) : 0.0f;
                w *= c * c * c;
            }
        }
    }
    if (w < OCTP_FLOOR) w = OCTP_FLOOR;
    if (w < OCTP_CRUSH) w *= w * w / (OCTP_CRUSH * OCTP_CRUSH);
    return w;
}

/* One level: Σ w·E / Σ w over the 8 probes of pb's cell (clamped to the grid). */
static float sample_level(const lbk_octp_view *v, const lbk_octp_level *l, const float p[3], const float pb[3],
                          const float n[3], bool has_n, const float edir[3], uint32_t flags, float rgb[3])
{
    float g[3], f[3];
    uint32_t b[3];
    level_coords(l, pb, g);
    for (int a = 0; a < 3; a++) {
        float fl = floorf(g[a]);
        if (!(fl >= 0.0f)) fl = 0.0f;
        if (fl > (float)(l->dims[a] - 2)) fl = (float)(l->dims[a] - 2);
        b[a] = (uint32_t)fl;
        f[a] = fminf(fmaxf(g[a] - fl, 0.0f), 1.0f);
    }
    float sum = 0.0f, acc[3] = {0, 0, 0};
    for (uint32_t c = 0; c < 8; c++) {
        const uint32_t x = b[0] + (c & 1), y = b[1] + (c >> 1 & 1), z = b[2] + (c >> 2);
        const uint32_t i = l->first_probe + x + l->dims[0] * (y + l->dims[1] * z);
        const uint8_t *q = v->probes + (size_t)LBK_OCTP_PROBE_SIZE * i;
        if (lbk_rd32(q + LBK_OCTP_INFO_OFFSET + 12) == LBK_OCTP_INSIDE) continue;
        const float tri = ((c & 1) ? f[0] : 1.0f - f[0]) * ((c >> 1 & 1) ? f[1] : 1.0f - f[1]) * ((c >> 2) ? f[2] : 1.0f - f[2]);
        if (!(tri > 0.0f)) continue;
        const float w = tri * probe_weight(q, p, pb, n, has_n, flags);
        float e[3];
        lbk_octp_probe_irradiance(q, edir, e);
        for (int k = 0; k < 3; k++) acc[k] += w * e[k];
        sum += w;
    }
    for (int k = 0; k < 3; k++) rgb[k] = sum > 0.0f ? acc[k] / sum * v->scale : 0.0f;
    return sum;
}

lbk_result lbk_octp_sample(const lbk_octp_view *view, const lbk_octp_sample_desc *caller_desc, float rgb[3],
                           float *weight_sum)
{
    if (weight_sum) *weight_sum = 0.0f;
    if (!view || !view->data || !caller_desc || !rgb) return LBK_ERR_INVALID_ARGUMENT;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    lbk_octp_sample_desc d;
    lbk_result rc = LBK_SIZED_IN(&d, caller_desc, lbk_octp_sample_desc, flags);
    if (rc != LBK_OK) return rc;
    if (!lbk_finite3(d.position) || !lbk_finite3(d.normal) || !lbk_finite3(d.view)) return LBK_ERR_INVALID_ARGUMENT;
    if (view->level_count == 0) return LBK_ERR_UNSUPPORTED_FEATURE;
    const bool has_n = dot3(d.normal, d.normal) > 0.0f, has_v = dot3(d.view, d.view) > 0.0f;
    const float nb = d.normal_bias == 0.0f ? 0.2f : fmaxf(d.normal_bias, 0.0f);
    const float vb = d.view_bias == 0.0f ? 0.1f : fmaxf(d.view_bias, 0.0f);
    const float up[3] = {0, 0, 1};
    const float *edir = has_n ? d.normal : has_v ? d.view : up;
    /* the finest level whose grid box holds the biased point (biased by that level's spacing) */
    uint32_t L = view->level_count, use = L - 1;
    float pb[LBK_OCTP_MAX_LEVELS][3], edge = 0.0f;
    for (uint32_t l = 0; l < L; l++) {
        const float s = view->levels[l].spacing;
        for (int a = 0; a < 3; a++)
            pb[l][a] = d.position[a] + (has_n ? nb * s * d.normal[a] : 0.0f) + (has_v ? vb * s * d.view[a] : 0.0f);
    }
    for (uint32_t l = 0; l < L; l++) {
        float g[3];
        level_coords(&view->levels[l], pb[l], g);
        if (!level_contains(&view->levels[l], g)) continue;
        use = l;
        edge = INFINITY; /* distance to the level's box in cells: blend over the last cell */
        for (int a = 0; a < 3; a++) edge = fminf(edge, fminf(g[a], (float)(view->levels[l].dims[a] - 1) - g[a]));
        break;
    }
    const float w = sample_level(view, &view->levels[use], d.position, pb[use], d.normal, has_n, edir, d.flags, rgb);
    if (weight_sum) *weight_sum = w;
    if (use + 1 < L && edge < 1.0f && !(d.flags & LBK_OCTP_SAMPLE_NO_BLEND)) {
        float c[3];
        sample_level(view, &view->levels[use + 1], d.position, pb[use + 1], d.normal, has_n, edir, d.flags, c);
        for (int k = 0; k < 3; k++) rgb[k] = edge * rgb[k] + (1.0f - edge) * c[k];
    }
    return LBK_OK;
}
