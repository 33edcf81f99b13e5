/* Denoising of baked texels (lightmap space) and the API; probes are in denoise_probes.c.
 * Method and measurements: bake/denoise/DENOISE.md. */
#include "bake/denoise/denoise.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/denoise/denoise_impl.h"
#include "bake/transport/shading.h"
#include "scene/clock.h"
#include "scene/parallel.h"

#define SH_N DN_MAX_CH /* floats per lbk_sh9_rgb */

/* ---- the texels' geometry, charts and pages; the weights of one guide over them ------------- */

/* What every filter over the same texels shares: the base's and each half's (bk_denoiser_half_delta)
 * differ only in their guide, so they differ only in their dn_levels. */
typedef struct dn_texels {
    size_t n;                  /* texel receivers */
    int method;
    int levels;                /* à-trous levels (1 for NLM and BLUR) */
    int radius;                /* NLM half-window */
    float sigma_lum, sigma_normal, sigma_plane, sigma_albedo, clamp;
    /* per receiver */
    float (*pos)[3], (*nrm)[3], (*alb)[3];
    float *size;
    uint32_t *chart, *page;
    int32_t *x, *y;
    /* per page texel: receiver or -1 (pages laid out as texels->page_offset) */
    size_t page_count;
    int *pw, *ph;
    size_t *poff;
    int32_t *grid;
    int32_t *patch;            /* NLM: 9 per receiver, its 3×3 neighbours in its chart or -1 */
} dn_texels;

/* One guide's weights: its luminance and variance at the input of each level (levels × n), the
 * noise std of the input (smoothed variance, n) and the clamp blend (n). */
typedef struct dn_levels {
    float *lum, *var;
    float *sigma;
    float *alpha;
    size_t clamped;
} dn_levels;

struct bk_denoiser {
    size_t receiver_count;
    int threads;
    dn_texels tex;
    dn_levels lev;
    int have_tex;
    dn_probes probes;
    dn_probe_weights probe_w;
    int have_probes;
    bk_denoise_stats stats;
};

static float sh_irradiance_lum(const lbk_sh9_rgb *sh, const float n[3])
{
    float e[3];
    lbk_sh9_irradiance(sh, n, e);
    return DN_LR * e[0] + DN_LG * e[1] + DN_LB * e[2];
}

/* Receiver at offset (dx, dy) from receiver p on its page, or -1. */
static int32_t dn_at(const dn_texels *g, size_t p, int dx, int dy)
{
    int x = g->x[p] + dx, y = g->y[p] + dy;
    uint32_t pg = g->page[p];
    if (x < 0 || y < 0 || x >= g->pw[pg] || y >= g->ph[pg]) return -1;
    return g->grid[g->poff[pg] + (size_t)y * (size_t)g->pw[pg] + (size_t)x];
}

/* Geometry-only weight of neighbour q for p: 0 across charts; the distance off p's tangent
 * plane (texel sizes) and the normals' agreement; the albedo when asked. */
static float geo_weight(const dn_texels *g, size_t p, size_t q)
{
    if (g->chart[p] != g->chart[q]) return 0;
    if (p == q) return 1;
    const float *np = g->nrm[p], *nq = g->nrm[q];
    float nd = np[0] * nq[0] + np[1] * nq[1] + np[2] * nq[2];
    if (!(nd > 0)) return 0;
    float d[3] = {g->pos[q][0] - g->pos[p][0], g->pos[q][1] - g->pos[p][1], g->pos[q][2] - g->pos[p][2]};
    float off = fabsf(np[0] * d[0] + np[1] * d[1] + np[2] * d[2]) / (g->size[p] > 0 ? g->size[p] : 1);
    float w = 1;
    /* flat charts (the common case) skip both transcendental calls */
    if (off > 0) w = expf(-0.5f * (off / g->sigma_plane) * (off / g->sigma_plane));
    if (nd < 1) w *= powf(nd, g->sigma_normal);
    if (g->sigma_albedo > 0) {
        float a = 0;
        for (int c = 0; c < 3; c++) a += (g->alb[q][c] - g->alb[p][c]) * (g->alb[q][c] - g->alb[p][c]);
        w *= expf(-0.5f * a / (g->sigma_albedo * g->sigma_albedo));
    }
    return w;
}

/* Barycentrics of p in triangle tri (projected on its plane, clamped inside). */
static void tri_barycentrics(const bk_scene *s, uint32_t tri, const float p[3], double *u, double *v)
{
    const float *a = s->positions + 3 * (size_t)s->tris[3 * (size_t)tri];
    const float *b = s->positions + 3 * (size_t)s->tris[3 * (size_t)tri + 1];
    const float *c = s->positions + 3 * (size_t)s->tris[3 * (size_t)tri + 2];
    double e1[3], e2[3], d[3];
    for (int k = 0; k < 3; k++) e1[k] = (double)b[k] - a[k], e2[k] = (double)c[k] - a[k], d[k] = (double)p[k] - a[k];
    double d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2], d22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    double d12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
    double p1 = d[0] * e1[0] + d[1] * e1[1] + d[2] * e1[2], p2 = d[0] * e2[0] + d[1] * e2[1] + d[2] * e2[2];
    double det = d11 * d22 - d12 * d12;
    *u = *v = 1.0 / 3;
    if (!(fabs(det) > 0)) return;
    double uu = (d22 * p1 - d12 * p2) / det, vv = (d11 * p2 - d12 * p1) / det;
    if (!isfinite(uu) || !isfinite(vv)) return;
    uu = fmin(fmax(uu, 0), 1), vv = fmin(fmax(vv, 0), 1);
    if (uu + vv > 1) {
        double t = uu + vv;
        uu /= t, vv /= t;
    }
    *u = uu, *v = vv;
}

static void texel_albedo(const bk_scene *s, const bk_texel *t, float out[3])
{
    out[0] = out[1] = out[2] = 0;
    if (!s || t->tri >= s->tri_count || !s->tri_material) return;
    uint32_t m = s->tri_material[t->tri];
    if (m >= s->material_count) return;
    double u, v, uv[2], a[3];
    tri_barycentrics(s, t->tri, t->position, &u, &v);
    bk_tri_uv0(s, t->tri, u, v, uv);
    bk_material_albedo(s, &s->materials[m], uv, a);
    for (int c = 0; c < 3; c++) out[c] = (float)a[c];
}

static void texels_free(dn_texels *g)
{
    free(g->pos), free(g->nrm), free(g->alb), free(g->size), free(g->chart), free(g->page), free(g->x), free(g->y);
    free(g->pw), free(g->ph), free(g->poff), free(g->grid), free(g->patch);
    memset(g, 0, sizeof *g);
}

static void levels_free(dn_levels *lv)
{
    free(lv->lum), free(lv->var), free(lv->sigma), free(lv->alpha);
    memset(lv, 0, sizeof *lv);
}

static lbk_result texels_features(const bk_denoise_inputs *in, dn_texels *g)
{
    const bk_texels *tx = in->texels;
    const bk_atlas *at = in->atlas;
    size_t n = in->texel_count;
    g->n = n;
    g->pos = malloc(n * sizeof *g->pos), g->nrm = malloc(n * sizeof *g->nrm), g->alb = malloc(n * sizeof *g->alb);
    g->size = malloc(n * sizeof *g->size), g->chart = malloc(n * sizeof *g->chart);
    g->page = malloc(n * sizeof *g->page), g->x = malloc(n * sizeof *g->x), g->y = malloc(n * sizeof *g->y);
    g->page_count = tx->page_count;
    size_t pc = tx->page_count ? tx->page_count : 1;
    g->pw = malloc(pc * sizeof *g->pw), g->ph = malloc(pc * sizeof *g->ph), g->poff = malloc((pc + 1) * sizeof *g->poff);
    size_t total = tx->page_offset[tx->page_count];
    g->grid = malloc((total ? total : 1) * sizeof *g->grid);
    if (!g->pos || !g->nrm || !g->alb || !g->size || !g->chart || !g->page || !g->x || !g->y || !g->pw || !g->ph ||
        !g->poff || !g->grid)
        return LBK_ERR_OUT_OF_MEMORY;
    for (size_t p = 0; p < tx->page_count; p++) {
        g->pw[p] = tx->pages[p].width, g->ph[p] = tx->pages[p].height, g->poff[p] = tx->page_offset[p];
    }
    g->poff[tx->page_count] = total;
    for (size_t i = 0; i < total; i++) g->grid[i] = -1;
    for (size_t k = 0; k < n; k++) {
        uint32_t ti = in->texel_of_receiver[k];
        if (ti >= tx->count) return LBK_ERR_INVALID_ARGUMENT;
        const bk_texel *t = &tx->receivers[ti];
        if (t->page >= tx->page_count || t->x >= tx->pages[t->page].width || t->y >= tx->pages[t->page].height)
            return LBK_ERR_INVALID_ARGUMENT;
        memcpy(g->pos[k], t->position, sizeof g->pos[k]);
        memcpy(g->nrm[k], t->normal, sizeof g->nrm[k]);
        g->size[k] = t->texel_size;
        g->page[k] = t->page, g->x[k] = t->x, g->y[k] = t->y;
        /* chart of the texel's triangle; a texel without one is its own chart (never mixed) */
        int32_t e = t->tri < at->scene_tri_count ? at->scene_tri_entry[t->tri] : -1;
        g->chart[k] = e >= 0 && (size_t)e < at->tri_count ? at->tri_chart[e] : (uint32_t)(at->chart_count + k);
        texel_albedo(in->scene, t, g->alb[k]);
        g->grid[tx->page_offset[t->page] + (size_t)t->y * (size_t)tx->pages[t->page].width + t->x] = (int32_t)k;
    }
    if (g->method == BK_DENOISE_NLM) {
        g->patch = malloc(n * 9 * sizeof *g->patch);
        if (!g->patch) return LBK_ERR_OUT_OF_MEMORY;
        for (size_t k = 0; k < n; k++)
            for (int i = 0; i < 9; i++) {
                int32_t q = dn_at(g, k, i % 3 - 1, i / 3 - 1);
                g->patch[9 * k + (size_t)i] = q >= 0 && g->chart[q] == g->chart[k] ? q : -1;
            }
    }
    return LBK_OK;
}

/* ---- filters ------------------------------------------------------------------------------- */

/* B3-spline taps of the à-trous kernel, |offset| 0, 1, 2. */
static const float atrous_h[3] = {0.375f, 0.25f, 0.0625f};

/* The luminance stop of the à-trous filter: neighbours further from p's value than a few noise
 * standard deviations of p lose their weight (p noise-free: only equal values count). */
static float lum_stop(float lp, float lq, float var_p, float sigma_lum)
{
    float d = fabsf(lp - lq);
    if (d == 0) return 1;
    float s = sigma_lum * sqrtf(var_p);
    if (!(s > 0)) return 0;
    return expf(-d / s);
}

/* NLM weight of q for p: the mean over the 3×3 patch of the variance-cancelled squared
 * difference, normalised by the pair's variance (Rousselle et al. 2012), k = sigma_lum. */
static float nlm_weight(const dn_texels *g, const float *lum, const float *var, size_t p, size_t q)
{
    if (p == q) return 1;
    double sum = 0;
    int m = 0;
    const double k2 = (double)g->sigma_lum * g->sigma_lum;
    const int32_t *pa = g->patch + 9 * p, *pb = g->patch + 9 * q;
    for (int i = 0; i < 9; i++) {
        int32_t a = pa[i], b = pb[i];
        if (a < 0 || b < 0) continue;
        double va = var[a], vb = var[b], dl = (double)lum[a] - lum[b];
        double den = k2 * (va + vb);
        if (!(den > 0)) {
            if (dl != 0) return 0; /* both noise-free and different: never the same light */
            continue;
        }
        sum += (dl * dl - (va + fmin(va, vb))) / den;
        m++;
    }
    double d2 = m ? sum / m : 0;
    return d2 > 0 ? (float)exp(-d2) : 1.0f;
}

/* Weight of the neighbour at tap (dx, dy) of level `level` (step 2^level), or 0. */
static float tap_weight(const dn_texels *g, const dn_levels *lv, int level, size_t p, int32_t q, int dx, int dy)
{
    if (q < 0) return 0;
    float w = geo_weight(g, p, (size_t)q);
    if (!(w > 0)) return 0;
    const float *lum = lv->lum + (size_t)level * g->n, *var = lv->var + (size_t)level * g->n;
    switch (g->method) {
    case BK_DENOISE_ATROUS:
        w *= atrous_h[abs(dx)] * atrous_h[abs(dy)];
        if ((size_t)q != p) w *= lum_stop(lum[p], lum[q], var[p], g->sigma_lum);
        break;
    case BK_DENOISE_NLM: w *= nlm_weight(g, lum, var, p, (size_t)q); break;
    default: /* BLUR: geometry only, a Gaussian of the window */
        w *= expf(-0.5f * (float)(dx * dx + dy * dy) / (float)(g->radius * g->radius) * 4.0f);
        break;
    }
    return w;
}

/* The taps of a level: à-trous 5×5 at step 2^level, NLM and BLUR the (2r+1)² window. */
static void level_taps(const dn_texels *g, int level, int *r, int *step)
{
    if (g->method == BK_DENOISE_ATROUS) *r = 2, *step = 1 << level;
    else *r = g->radius, *step = 1;
}

typedef struct level_job {
    const dn_texels *g;
    const dn_levels *lv;
    int level;
    const float *in;          /* ch floats per receiver (apply), or NULL (build only) */
    float *out;
    int ch;
    float *lum_next, *var_next; /* build: the guide's luminance and variance after this level, or
                                   NULL (apply only); both at once share the pass's weights */
    const float *in2;         /* a second input riding on the same weights (ch2 floats per
                                 receiver), filtered into out2; NULL: none */
    float *out2;
    int ch2;
} level_job;

static void level_run(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    const level_job *j = user;
    const dn_texels *g = j->g;
    int r, step;
    level_taps(g, j->level, &r, &step);
    const float *lum = j->lv->lum + (size_t)j->level * g->n, *var = j->lv->var + (size_t)j->level * g->n;
    for (size_t p = begin; p < end; p++) {
        double acc[SH_N], acc2[SH_N], W = 0, wl = 0, wv = 0;
        if (j->in) memset(acc, 0, sizeof acc);
        if (j->in2) memset(acc2, 0, sizeof acc2);
        for (int dy = -r; dy <= r; dy++)
            for (int dx = -r; dx <= r; dx++) {
                int32_t q = dn_at(g, p, dx * step, dy * step);
                float w = tap_weight(g, j->lv, j->level, p, q, dx, dy);
                if (!(w > 0)) continue;
                W += w;
                if (j->in) {
                    const float *v = j->in + (size_t)q * j->ch;
                    for (int k = 0; k < j->ch; k++) acc[k] += w * (double)v[k];
                }
                if (j->in2) {
                    const float *v = j->in2 + (size_t)q * j->ch2;
                    for (int k = 0; k < j->ch2; k++) acc2[k] += w * (double)v[k];
                }
                if (j->lum_next) {
                    wl += w * (double)lum[q];
                    wv += (double)w * w * var[q];
                }
            }
        /* the centre always has a weight, so W > 0 */
        if (j->in) {
            float *o = j->out + p * j->ch;
            for (int k = 0; k < j->ch; k++) o[k] = (float)(acc[k] / W);
        }
        if (j->in2) {
            float *o = j->out2 + p * j->ch2;
            for (int k = 0; k < j->ch2; k++) o[k] = (float)(acc2[k] / W);
        }
        if (j->lum_next) {
            j->lum_next[p] = (float)(wl / W);
            j->var_next[p] = (float)(wv / (W * W));
        }
    }
}

/* Level-0 variance: the transport's one-degree-of-freedom estimate averaged over the 5×5
 * neighbours of the same chart (geometry weights), except that a texel whose own estimate is
 * exactly 0 keeps 0: both halves agreed to the bit, so no stochastic light reaches it (an
 * umbra lit by emitters only, punctual light only) and it is not filtered at all. */
typedef struct var_job {
    const dn_texels *g;
    const float *raw;
    float *out;
} var_job;

static void var_run(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    const var_job *j = user;
    const dn_texels *g = j->g;
    for (size_t p = begin; p < end; p++) {
        if (!(j->raw[p] > 0)) {
            j->out[p] = 0;
            continue;
        }
        double s = 0, W = 0;
        for (int dy = -2; dy <= 2; dy++)
            for (int dx = -2; dx <= 2; dx++) {
                int32_t q = dn_at(g, p, dx, dy);
                if (q < 0) continue;
                float w = geo_weight(g, p, (size_t)q) * atrous_h[abs(dx)] * atrous_h[abs(dy)];
                if (!(w > 0) || !isfinite(j->raw[q])) continue;
                s += w * (double)j->raw[q];
                W += w;
            }
        j->out[p] = W > 0 ? (float)(s / W) : 0;
    }
}

static void run_chunks(const bk_denoiser *d, size_t n, bk_chunk_fn fn, void *user)
{
    bk_parallel_chunks(0, n, 256, d->threads, fn, user);
}

/* The clamp: the filtered guide luminance may move at most clamp·σ from the input. */
static void levels_clamp(const dn_texels *g, dn_levels *lv)
{
    const size_t n = g->n;
    const float *lout = lv->lum + (size_t)g->levels * n;
    lv->clamped = 0;
    for (size_t p = 0; p < n; p++) {
        float dl = fabsf(lout[p] - lv->lum[p]);
        float lim = g->clamp >= 0 ? g->clamp * lv->sigma[p] : INFINITY;
        lv->alpha[p] = lv->sigma[p] > 0 || (g->method == BK_DENOISE_BLUR && g->clamp < 0) ? 1 : 0;
        if (lv->sigma[p] > 0 && dl > lim) {
            lv->alpha[p] = lim / dl;
            lv->clamped++;
        }
    }
}

/* vals (ch floats per texel) moved towards their filtered values f by the clamp's blend. */
static void texels_blend(const dn_texels *g, const dn_levels *lv, float *vals, const float *f, int ch)
{
    for (size_t p = 0; p < g->n; p++) {
        float *o = vals + p * ch;
        const float *fp = f + p * ch;
        float al = lv->alpha[p];
        if (al == 1) memcpy(o, fp, ch * sizeof *o);
        else if (al > 0)
            for (int k = 0; k < ch; k++) o[k] += al * (fp[k] - o[k]);
    }
}

/* Filters texel receivers [0, n) of `vals` (ch ≤ SH_N floats each) in place. Every channel is
 * filtered on its own with the same weights, so a channel's result does not depend on which
 * others ride along: the error estimates filter many two-channel inputs in one pass (the
 * weights, not the channels, are most of a pass's cost). With `build` (lv itself), the same
 * passes build lv's levels after the first and its clamp, which levels_build left undone: the
 * same numbers as building first and filtering after, in half the passes. */
static lbk_result texels_filter(const bk_denoiser *d, const dn_levels *lv, dn_levels *build, float *vals, int ch,
                                bk_denoise_ride *ride)
{
    const dn_texels *g = &d->tex;
    size_t n = g->n;
    /* level 0 reads vals itself (it changes only at the end), so one level (NLM, the default)
     * needs one buffer of n·ch floats, not two: at ch = 27 that is ~100 B per texel at the bake's
     * peak (DENOISE.md) */
    float *a = NULL, *b = malloc((n ? n : 1) * ch * sizeof *b);
    if (b && g->levels > 1) a = malloc((n ? n : 1) * ch * sizeof *a);
    if (!b || (g->levels > 1 && !a)) {
        free(a), free(b);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    const float *in = vals;
    /* a one-level filter (NLM, the default) carries the ride's channels in its one pass */
    const int riding = ride && ride->radiance && ride->filtered && g->levels == 1;
    for (int l = 0; l < g->levels; l++) {
        level_job j = {g, lv, l, in, b, ch, build ? build->lum + (size_t)(l + 1) * n : NULL,
                       build ? build->var + (size_t)(l + 1) * n : NULL,
                       riding ? (const float *)ride->radiance : NULL, riding ? ride->filtered : NULL, SH_N};
        run_chunks(d, n, level_run, &j);
        float *t = a;
        a = b, b = t;
        in = a;
    }
    if (build) levels_clamp(g, build);
    texels_blend(g, lv, vals, in, ch);
    if (riding) ride->done = 1;
    free(a), free(b);
    return LBK_OK;
}

static lbk_result texels_apply(const bk_denoiser *d, const dn_levels *lv, float *vals, int ch)
{
    return texels_filter(d, lv, NULL, vals, ch, NULL);
}

/* The per-level luminance and variance of a guide over the texels, then the clamp. With vals
 * (ch floats per texel), the same passes filter them in place as texels_apply would with the
 * finished levels (texels_filter). */
static lbk_result levels_build(const bk_denoiser *d, const dn_guide *gd, dn_levels *lv, float *vals, int ch)
{
    const dn_texels *g = &d->tex;
    size_t n = g->n;
    int L = g->levels;
    lv->lum = malloc(((size_t)L + 1) * n * sizeof *lv->lum);
    lv->var = malloc(((size_t)L + 1) * n * sizeof *lv->var);
    lv->sigma = malloc(n * sizeof *lv->sigma);
    lv->alpha = malloc(n * sizeof *lv->alpha);
    float *raw = malloc(n * sizeof *raw);
    if (!lv->lum || !lv->var || !lv->sigma || !lv->alpha || !raw) {
        free(raw);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t p = 0; p < n; p++) {
        lbk_sh9_rgb sh;
        float v;
        dn_guide_at(gd, p, &sh, &v);
        lv->lum[p] = sh_irradiance_lum(&sh, g->nrm[p]);
        if (!isfinite(lv->lum[p])) lv->lum[p] = 0;
        raw[p] = isfinite(v) && v > 0 ? v : 0;
    }
    var_job vj = {g, raw, lv->var};
    run_chunks(d, n, var_run, &vj);
    free(raw);
    for (size_t p = 0; p < n; p++) lv->sigma[p] = sqrtf(lv->var[p]);
    if (vals) return texels_filter(d, lv, lv, vals, ch, NULL);
    for (int l = 0; l < L; l++) {
        level_job j = {g, lv, l, NULL, NULL, 0, lv->lum + (size_t)(l + 1) * n, lv->var + (size_t)(l + 1) * n, NULL, NULL, 0};
        run_chunks(d, n, level_run, &j);
    }
    levels_clamp(g, lv);
    return LBK_OK;
}

/* ---- API ------------------------------------------------------------------------------------ */

static void resolve_options(const bk_denoise_options *o, dn_texels *g)
{
    bk_denoise_options z;
    memset(&z, 0, sizeof z);
    if (!o) o = &z;
    g->method = o->method == BK_DENOISE_AUTO ? BK_DENOISE_NLM : o->method; /* DENOISE.md */
    g->levels = g->method == BK_DENOISE_ATROUS ? (o->iterations > 0 ? o->iterations : 4) : 1;
    if (g->levels > 8) g->levels = 8;
    g->radius = o->radius > 0 ? (o->radius > 16 ? 16 : o->radius) : 5;
    g->sigma_lum = o->sigma_lum > 0 ? o->sigma_lum : g->method == BK_DENOISE_NLM ? 1.0f : 4.0f;
    g->sigma_normal = o->sigma_normal > 0 ? o->sigma_normal : 32;
    g->sigma_plane = o->sigma_plane > 0 ? o->sigma_plane : 0.5f;
    g->sigma_albedo = o->sigma_albedo > 0 ? o->sigma_albedo : 0;
    g->clamp = o->clamp == 0 ? 2.0f : o->clamp < 0 ? -1.0f : o->clamp;
}

lbk_result bk_denoiser_create(const bk_denoise_inputs *in, const bk_denoise_options *opt, bk_denoiser **out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!in || (in->receiver_count && (!in->radiance || !in->variance))) return LBK_ERR_INVALID_ARGUMENT;
    int want_tex = in->texels && in->texel_count > 0;
    if (want_tex && (!in->atlas || !in->texel_of_receiver || in->texel_count > in->receiver_count ||
                     in->texel_count > (size_t)INT32_MAX))
        return LBK_ERR_INVALID_ARGUMENT;
    int want_probes = in->glg && in->tracer && in->glg->probe_count > 0 && !(opt && opt->no_probes);
    if (want_probes && (in->glg_first > in->receiver_count || in->glg->probe_count > in->receiver_count - in->glg_first))
        return LBK_ERR_INVALID_ARGUMENT;
    double t0 = bk_now();
    bk_denoiser *d = calloc(1, sizeof *d);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    d->receiver_count = in->receiver_count;
    d->threads = bk_thread_count(opt ? opt->threads : 0);
    resolve_options(opt, &d->tex);
    const dn_guide gd = {in, NULL, NULL, NULL, 0};
    lbk_result r = LBK_OK;
    if (want_tex) {
        r = texels_features(in, &d->tex);
        if (!r) r = levels_build(d, &gd, &d->lev, NULL, 0);
        d->have_tex = !r;
    }
    if (!r && want_probes) {
        r = dn_probes_build(in, opt, d->threads, &d->probes);
        if (!r) r = dn_probe_weights_build(&d->probes, &gd, &d->probe_w);
        d->have_probes = !r;
    }
    if (r) {
        bk_denoiser_destroy(d);
        return r;
    }
    d->stats.texels = d->have_tex ? d->tex.n : 0;
    d->stats.probes = d->have_probes ? d->probes.count : 0;
    d->stats.probe_edges = d->probes.edges;
    d->stats.probe_edges_visible = d->probes.edges_visible;
    d->stats.clamped = d->lev.clamped + d->probe_w.clamped;
    d->stats.seconds = bk_now() - t0;
    *out = d;
    return LBK_OK;
}

lbk_result bk_denoiser_apply_classes(const bk_denoiser *d, lbk_sh9_rgb *radiance, const int filter[BK_RECEIVER_CLASSES])
{
    if (!d || !filter || (!radiance && d->receiver_count)) return LBK_ERR_INVALID_ARGUMENT;
    lbk_result r = LBK_OK;
    if (d->have_tex && filter[BK_CLASS_TEXEL]) r = texels_apply(d, &d->lev, (float *)radiance, SH_N);
    if (!r && d->have_probes && filter[BK_CLASS_GLG]) r = dn_probes_apply(&d->probes, &d->probe_w, (float *)radiance, SH_N);
    return r;
}

lbk_result bk_denoiser_apply(const bk_denoiser *d, lbk_sh9_rgb *radiance)
{
    static const int all[BK_RECEIVER_CLASSES] = {1, 1, 1};
    return bk_denoiser_apply_classes(d, radiance, all);
}

/* Per-class sums of bk_denoiser_error: noise², the bias term and the denoised values². */
typedef struct dn_error_sums {
    double noise, bias, den;
} dn_error_sums;

/* Receiver i's terms: the same floats the filter started from (x, δ), so that an unfiltered
 * receiver adds no bias, and its filtered channels (f NULL: unfiltered, the identity); its noise
 * from cross (bk_denoiser_half_delta) when not NULL, else the filtered δ. */
static void sums_add(dn_error_sums *s, const float *halves, const float *f, size_t stride, const float *cross, size_t i)
{
    const double x = 0.5f * (halves[2 * i] + halves[2 * i + 1]);
    const double dl = 0.5f * (halves[2 * i] - halves[2 * i + 1]);
    const double fx = f ? f[i * stride] : x, fd = f ? f[i * stride + 1] : dl, nd = cross ? cross[i] : fd;
    s->noise += nd * nd;
    s->bias += (fx - x) * (fx - x) - (fd - dl) * (fd - dl);
    s->den += fx * fx;
}

/* √(noise² + bias²), noise and bias relative to the RMS of the values; 0 when there are none. */
static void sums_finish(const dn_error_sums *s, double *rel, double *noise, double *bias)
{
    if (!(s->den > 0)) return;
    const double b2 = s->bias > 0 ? s->bias : 0;
    *noise = sqrt(s->noise / s->den);
    *bias = sqrt(b2 / s->den);
    *rel = sqrt((s->noise + b2) / s->den);
}

/* The estimate of one input from its filtered channels f (X then δ per receiver). */
static void error_from_filtered(const float *halves, const float *f, size_t stride, const float *cross,
                                const size_t class_end[BK_RECEIVER_CLASSES], bk_denoise_error *out)
{
    dn_error_sums sum[BK_RECEIVER_CLASSES];
    memset(sum, 0, sizeof sum);
    size_t i = 0;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++)
        for (; i < class_end[k]; i++) sums_add(&sum[k], halves, f, stride, cross, i);
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) sums_finish(&sum[k], &out->rel_rmse[k], &out->noise[k], &out->bias[k]);
    const double pn = sum[BK_CLASS_GLG].noise + sum[BK_CLASS_LLG].noise, pd = sum[BK_CLASS_GLG].den + sum[BK_CLASS_LLG].den;
    const double pb = sum[BK_CLASS_GLG].bias > 0 ? sum[BK_CLASS_GLG].bias : 0; /* LLG: not filtered */
    out->probe_rel_rmse = pd > 0 ? sqrt((pn + pb) / pd) : 0;
}

/* The same per group of the first g->count receivers (f NULL: unfiltered). */
static lbk_result groups_from_filtered(const float *halves, const float *f, size_t stride, const float *cross,
                                       const bk_denoise_groups *g)
{
    memset(g->out, 0, g->group_count * sizeof *g->out);
    dn_error_sums *sum = calloc(g->group_count ? g->group_count : 1, sizeof *sum);
    if (!sum) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < g->count; i++) {
        if (g->group[i] >= g->group_count) continue;
        sums_add(&sum[g->group[i]], halves, f, stride, cross, i);
        g->out[g->group[i]].receivers++;
    }
    for (size_t k = 0; k < g->group_count; k++) {
        bk_denoise_group_error *o = &g->out[k];
        o->noise2 = sum[k].noise;
        o->bias2 = sum[k].bias > 0 ? sum[k].bias : 0;
        o->value2 = sum[k].den;
        sums_finish(&sum[k], &o->rel_rmse, &o->noise, &o->bias);
    }
    free(sum);
    return LBK_OK;
}

/* Inputs per filter pass: X and δ of each ride as two channels, the filter being linear and the
 * same for every channel, so this is D applied to each. */
#define DN_ERROR_GROUP (DN_MAX_CH / 2)

/* bk_denoiser_errors, and with g the first input's groups from the same filter pass. */
static lbk_result errors_pass(const bk_denoiser *d, const float *const *halves, size_t count,
                              const size_t class_end[BK_RECEIVER_CLASSES], bk_denoise_error *out,
                              const bk_denoise_groups *g, const float *cross, bk_denoise_ride *ride)
{
    if (!out || !class_end || (count && !halves)) return LBK_ERR_INVALID_ARGUMENT;
    const size_t n = d ? d->receiver_count : class_end[BK_RECEIVER_CLASSES - 1];
    for (size_t j = 0; j < count; j++)
        if (!halves[j] && n) return LBK_ERR_INVALID_ARGUMENT;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++)
        if (class_end[k] > n || (k && class_end[k] < class_end[k - 1])) return LBK_ERR_INVALID_ARGUMENT;
    const double t0 = bk_now();
    memset(out, 0, count * sizeof *out);
    const size_t group = count < DN_ERROR_GROUP ? (count ? count : 1) : DN_ERROR_GROUP;
    float *f = malloc((n ? n : 1) * 2 * group * sizeof *f);
    if (!f) return LBK_ERR_OUT_OF_MEMORY;
    lbk_result r = LBK_OK;
    for (size_t j0 = 0; j0 < count && !r; j0 += DN_ERROR_GROUP) {
        const size_t m = count - j0 < DN_ERROR_GROUP ? count - j0 : DN_ERROR_GROUP;
        const int ch = (int)(2 * m);
        for (size_t i = 0; i < n; i++)
            for (size_t j = 0; j < m; j++) {
                const float *h = halves[j0 + j];
                f[i * ch + 2 * j] = 0.5f * (h[2 * i] + h[2 * i + 1]);
                f[i * ch + 2 * j + 1] = 0.5f * (h[2 * i] - h[2 * i + 1]);
            }
        if (d && d->have_tex) r = texels_filter(d, &d->lev, NULL, f, ch, j0 == 0 ? ride : NULL);
        if (!r && d && d->have_probes) r = dn_probes_apply(&d->probes, &d->probe_w, f, ch);
        for (size_t j = 0; j < m && !r; j++)
            error_from_filtered(halves[j0 + j], f + 2 * j, (size_t)ch, j0 + j ? NULL : cross, class_end, &out[j0 + j]);
        if (!r && g && j0 == 0) r = groups_from_filtered(halves[0], f, (size_t)ch, cross, g);
    }
    free(f);
    const double secs = (bk_now() - t0) / (count ? (double)count : 1);
    for (size_t j = 0; j < count; j++) out[j].seconds = secs;
    return r;
}

lbk_result bk_denoiser_errors(const bk_denoiser *d, const float *const *halves, size_t count,
                              const size_t class_end[BK_RECEIVER_CLASSES], bk_denoise_error *out)
{
    return errors_pass(d, halves, count, class_end, out, NULL, NULL, NULL);
}

lbk_result bk_denoiser_error(const bk_denoiser *d, const float *halves, const size_t class_end[BK_RECEIVER_CLASSES],
                             bk_denoise_error *out)
{
    return errors_pass(d, &halves, 1, class_end, out, NULL, NULL, NULL);
}

lbk_result bk_denoiser_error_groups(const bk_denoiser *d, const float *halves, const size_t class_end[BK_RECEIVER_CLASSES],
                                    bk_denoise_error *out, const bk_denoise_groups *groups, const float *cross,
                                    bk_denoise_ride *ride)
{
    if (!class_end || !groups || !groups->out || (groups->count && !groups->group) ||
        groups->count > class_end[BK_RECEIVER_CLASSES - 1])
        return LBK_ERR_INVALID_ARGUMENT;
    if (ride) ride->done = 0;
    return errors_pass(d, &halves, 1, class_end, out, groups, cross, ride);
}

lbk_result bk_denoiser_blend_texels(const bk_denoiser *d, lbk_sh9_rgb *radiance, const float *filtered)
{
    if (!d || (!radiance && d->receiver_count) || (!filtered && d->have_tex)) return LBK_ERR_INVALID_ARGUMENT;
    if (d->have_tex) texels_blend(&d->tex, &d->lev, (float *)radiance, filtered, SH_N);
    return LBK_OK;
}

lbk_result bk_denoise_groups_unfiltered(const float *halves, const bk_denoise_groups *groups)
{
    if (!groups || !groups->out || (groups->count && (!halves || !groups->group))) return LBK_ERR_INVALID_ARGUMENT;
    return groups_from_filtered(halves, NULL, 0, NULL, groups);
}

void dn_guide_at(const dn_guide *g, size_t i, lbk_sh9_rgb *sh, float *variance)
{
    *sh = g->in->radiance[i];
    *variance = g->in->variance[i];
    if (!g->base) return;
    const double x = 0.5 * ((double)g->halves[2 * i] + g->halves[2 * i + 1]);
    const double s = x != 0 ? fmin(fmax(g->halves[2 * i + g->half] / x, 0), 2) : 1;
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++) sh->c[c][k] = g->in->radiance[i].c[c][k] + (float)(s - 1) * g->base[i].c[c][k];
    *variance = g->in->variance[i] + g->base_variance[i];
}

lbk_result bk_denoiser_half_delta(const bk_denoiser *d, const bk_denoise_inputs *in, const lbk_sh9_rgb *base,
                                  const float *base_variance, const float *halves, float *out)
{
    if (!d || !in || !base || !base_variance || !halves || !out || !in->radiance || !in->variance ||
        in->receiver_count != d->receiver_count)
        return LBK_ERR_INVALID_ARGUMENT;
    const size_t n = in->receiver_count;
    float *fb = malloc((n ? n : 1) * sizeof *fb);
    lbk_result r = fb ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < n && !r; i++) out[i] = halves[2 * i], fb[i] = halves[2 * i + 1];
    float *f[2] = {out, fb};
    /* the base's geometry and probe graph, each half's own weights, one half at a time */
    for (int h = 0; h < 2 && !r; h++) {
        const dn_guide gd = {in, base, base_variance, halves, h};
        dn_levels lv = {0};
        dn_probe_weights pw = {0};
        if (d->have_tex) r = levels_build(d, &gd, &lv, f[h], 1); /* built and applied in the same passes */
        if (!r && d->have_probes) r = dn_probe_weights_build(&d->probes, &gd, &pw);
        if (!r && d->have_probes) r = dn_probes_apply(&d->probes, &pw, f[h], 1);
        levels_free(&lv);
        dn_probe_weights_free(&pw);
    }
    for (size_t i = 0; i < n && !r; i++) out[i] = 0.5f * (out[i] - fb[i]);
    free(fb);
    return r;
}

void bk_denoiser_stats(const bk_denoiser *d, bk_denoise_stats *stats)
{
    if (!stats) return;
    memset(stats, 0, sizeof *stats);
    if (d) *stats = d->stats;
}

void bk_denoiser_destroy(bk_denoiser *d)
{
    if (!d) return;
    texels_free(&d->tex);
    levels_free(&d->lev);
    dn_probes_free(&d->probes);
    dn_probe_weights_free(&d->probe_w);
    free(d);
}
