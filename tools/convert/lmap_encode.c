/* BC6H and BC4/BC5 encoders (lmap_encode.h); ASTC through tools/common/astc_codec. The decoders
 * of lbk/bc.h are the reference: every candidate block is judged by what they return. */
#include "tools/convert/lmap_encode.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/astc_codec.h"
#include "lbk/bc.h"
#include "lbk/lightmap.h"
#include "lbk/pixel.h"

/* ---- BC6H, one-region modes ----------------------------------------------------------------- */

typedef struct mode1 {
    uint8_t code;      /* 5 mode bits */
    uint8_t w, d;      /* base bits, delta (or second endpoint) bits */
    uint8_t transformed;
    uint8_t hi_reversed; /* bits w-1..10 of the base stored reversed (modes 13, 14) */
} mode1;

/* Modes 11, 12, 13, 14 of the D3D specification. */
static const mode1 modes1[4] = {{0x03, 10, 10, 0, 0}, {0x07, 11, 9, 1, 0}, {0x0b, 12, 8, 1, 1}, {0x0f, 16, 4, 1, 1}};
static const int w4[16] = {0, 4, 9, 13, 17, 21, 26, 30, 34, 38, 43, 47, 51, 55, 60, 64};

static int unq(int q, int bits)
{
    if (bits >= 15) return q;
    if (q == 0) return 0;
    if (q == (1 << bits) - 1) return 0xffff;
    return ((q << 16) + 0x8000) >> bits;
}

/* The quantised value whose unquantisation is nearest u (0..65535). */
static int quant(double u, int bits)
{
    const int max = (1 << bits) - 1;
    int q = (int)floor(u * (double)(1 << bits) / 65536.0);
    int best = 0;
    double be = INFINITY;
    for (int c = q - 1; c <= q + 1; c++) {
        const int cc = c < 0 ? 0 : c > max ? max : c;
        const double e = fabs((double)unq(cc, bits) - u);
        if (e < be) be = e, best = cc;
    }
    return best;
}

/* The 16 palette entries (half bits) of endpoints (quantised) a, b. */
static void palette(const int a[3], const int b[3], int bits, uint16_t pal[16][3])
{
    for (int c = 0; c < 3; c++) {
        const int ua = unq(a[c], bits), ub = unq(b[c], bits);
        for (int i = 0; i < 16; i++) pal[i][c] = (uint16_t)((((ua * (64 - w4[i]) + ub * w4[i] + 32) >> 6) * 31) >> 6);
    }
}

static double sq(double x) { return x * x; }

/* Best index per texel and the weighted error, in half-bit space. */
static double assign(const int h[16][3], const float wt[16], const uint16_t pal[16][3], int idx[16])
{
    double total = 0;
    for (int t = 0; t < 16; t++) {
        double be = INFINITY;
        int bi = 0;
        for (int i = 0; i < 16; i++) {
            const double e = sq(pal[i][0] - h[t][0]) + sq(pal[i][1] - h[t][1]) + sq(pal[i][2] - h[t][2]);
            if (e < be) be = e, bi = i;
        }
        idx[t] = bi;
        total += wt[t] * be;
    }
    return total;
}

/* Quantises endpoints A, B (unquantised space) for mode m; false when the delta cannot be held. */
static int quantise_pair(const mode1 *m, const double A[3], const double B[3], int qa[3], int qb[3])
{
    for (int c = 0; c < 3; c++) {
        qa[c] = quant(A[c], m->w);
        qb[c] = quant(B[c], m->w);
        if (m->transformed) {
            const int lo = -(1 << (m->d - 1)), hi = (1 << (m->d - 1)) - 1;
            int d = qb[c] - qa[c];
            if (d < lo) d = lo;
            if (d > hi) d = hi;
            qb[c] = qa[c] + d;
            if (qb[c] < 0 || qb[c] > (1 << m->w) - 1) return 0;
        }
    }
    return 1;
}

static int fits_swapped(const mode1 *m, const int qa[3], const int qb[3])
{
    if (!m->transformed) return 1;
    for (int c = 0; c < 3; c++) {
        const int d = qa[c] - qb[c];
        if (d < -(1 << (m->d - 1)) || d > (1 << (m->d - 1)) - 1) return 0;
    }
    return 1;
}

static void pack_mode1(const mode1 *m, int qa[3], int qb[3], int idx[16], uint8_t out[16])
{
    if (idx[0] >= 8) { /* the anchor texel's index has no top bit: swap the endpoints */
        for (int c = 0; c < 3; c++) {
            const int t = qa[c];
            qa[c] = qb[c], qb[c] = t;
        }
        for (int t = 0; t < 16; t++) idx[t] = 15 - idx[t];
    }
    const int ep[4][3] = {{qa[0], qa[1], qa[2]}, {qb[0], qb[1], qb[2]}, {0, 0, 0}, {0, 0, 0}};
    uint8_t ix[16];
    for (int t = 0; t < 16; t++) ix[t] = (uint8_t)idx[t];
    const int mode = 11 + (int)(m - modes1); /* modes 11..14 of the specification */
    if (lbk_bc6h_pack(mode, 0, ep, ix, out) != LBK_OK) memset(out, 0, 16); /* checked by the caller */
}

/* Principal axis of the weighted points (power iteration on the covariance). */
static void principal_axis(const double u[16][3], const float wt[16], double mean[3], double axis[3])
{
    double sw = 0;
    mean[0] = mean[1] = mean[2] = 0;
    for (int t = 0; t < 16; t++) {
        sw += wt[t];
        for (int c = 0; c < 3; c++) mean[c] += wt[t] * u[t][c];
    }
    for (int c = 0; c < 3; c++) mean[c] /= sw;
    double cov[3][3] = {{0}};
    for (int t = 0; t < 16; t++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) cov[i][j] += wt[t] * (u[t][i] - mean[i]) * (u[t][j] - mean[j]);
    double v[3] = {1, 1, 1};
    for (int it = 0; it < 12; it++) {
        double nv[3] = {0, 0, 0};
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) nv[i] += cov[i][j] * v[j];
        const double len = sqrt(sq(nv[0]) + sq(nv[1]) + sq(nv[2]));
        if (!(len > 1e-12)) break;
        for (int i = 0; i < 3; i++) v[i] = nv[i] / len;
    }
    const double len = sqrt(sq(v[0]) + sq(v[1]) + sq(v[2]));
    for (int i = 0; i < 3; i++) axis[i] = len > 0 ? v[i] / len : 0.57735;
}

/* Least-squares endpoints for the given indices (unquantised space). */
static void refit(const double u[16][3], const float wt[16], const int idx[16], double A[3], double B[3])
{
    double aa = 0, ab = 0, bb = 0, ax[3] = {0, 0, 0}, bx[3] = {0, 0, 0};
    for (int t = 0; t < 16; t++) {
        const double b = w4[idx[t]] / 64.0, a = 1 - b, wgt = wt[t];
        aa += wgt * a * a, ab += wgt * a * b, bb += wgt * b * b;
        for (int c = 0; c < 3; c++) ax[c] += wgt * a * u[t][c], bx[c] += wgt * b * u[t][c];
    }
    const double det = aa * bb - ab * ab;
    if (fabs(det) < 1e-12) return;
    for (int c = 0; c < 3; c++) {
        A[c] = (ax[c] * bb - bx[c] * ab) / det;
        B[c] = (bx[c] * aa - ax[c] * ab) / det;
        A[c] = A[c] < 0 ? 0 : A[c] > 65535 ? 65535 : A[c];
        B[c] = B[c] < 0 ? 0 : B[c] > 65535 ? 65535 : B[c];
    }
}

/* ---- BC6H, any mode: evaluation and endpoint refinement ------------------------------------- */

static const int w3[8] = {0, 9, 18, 27, 37, 46, 55, 64};

/* The weighted error (half-bit space) of quantised endpoints ep of `mode` / `shape`, with the best
 * index per texel; the block in out. Endpoints whose anchor index would need its top bit are
 * swapped (on a copy) as the format requires; +Inf when the deltas cannot be stored. */
static double eval_ep(int mode, int shape, const int ep[4][3], const int h[16][3], const float wt[16],
                      uint8_t out[16])
{
    int regions, bits, db[3], transformed;
    lbk_bc6h_mode_info(mode, &regions, &bits, db, &transformed);
    const uint16_t sh = regions == 2 ? lbk_bc6h_shape(shape) : 0;
    const int anchors[2] = {0, regions == 2 ? lbk_bc6h_anchor(shape) : 0};
    const int n = regions == 2 ? 8 : 16;
    const int *wgt = regions == 2 ? w3 : w4;
    int e[4][3];
    memcpy(e, ep, sizeof e);
    uint8_t idx[16] = {0};
    double total = 0;
    for (int r = 0; r < regions; r++) {
        uint16_t pal[16][3];
        for (int c = 0; c < 3; c++) {
            const int ua = unq(e[2 * r][c], bits), ub = unq(e[2 * r + 1][c], bits);
            for (int i = 0; i < n; i++) pal[i][c] = (uint16_t)((((ua * (64 - wgt[i]) + ub * wgt[i] + 32) >> 6) * 31) >> 6);
        }
        for (int t = 0; t < 16; t++) {
            if ((int)((sh >> t) & 1u) != r) continue;
            double be = INFINITY;
            int bi = 0;
            for (int i = 0; i < n; i++) {
                const double d = sq(pal[i][0] - h[t][0]) + sq(pal[i][1] - h[t][1]) + sq(pal[i][2] - h[t][2]);
                if (d < be) be = d, bi = i;
            }
            idx[t] = (uint8_t)bi;
            total += wt[t] * be;
        }
        if (idx[anchors[r]] >= n / 2) { /* the anchor's index has no top bit */
            for (int c = 0; c < 3; c++) {
                const int tmp = e[2 * r][c];
                e[2 * r][c] = e[2 * r + 1][c], e[2 * r + 1][c] = tmp;
            }
            for (int t = 0; t < 16; t++)
                if ((int)((sh >> t) & 1u) == r) idx[t] = (uint8_t)(n - 1 - idx[t]);
        }
    }
    if (lbk_bc6h_pack(mode, shape, (const int(*)[3])e, idx, out) != LBK_OK) return INFINITY;
    return total;
}

/* Coordinate descent on the quantised endpoints: each endpoint channel one step up or down while
 * that lowers the error. Quantising each endpoint to its nearest value is not the best block:
 * moving one endpoint a step outward often lets the interpolated entries land on the texels (and
 * keeps a chart's colour where 6-bit endpoints would round all channels alike). */
static void refine_ep(int mode, int shape, int ep[4][3], const int h[16][3], const float wt[16], double *err,
                      uint8_t out[16])
{
    int regions, bits, db[3], transformed;
    lbk_bc6h_mode_info(mode, &regions, &bits, db, &transformed);
    const int max = (1 << bits) - 1;
    uint8_t tmp[16];
    for (int pass = 0; pass < 4; pass++) {
        int improved = 0;
        /* moves: one channel of one endpoint (c < 3), or all three together (c = 3: brightness,
         * which single-channel steps cannot reach when each alone would tint the texels) */
        for (int k = 0; k < 2 * regions; k++)
            for (int c = 0; c < 4; c++)
                for (int d = -1; d <= 1; d += 2) {
                    const int c0 = c < 3 ? c : 0, c1 = c < 3 ? c : 2;
                    int ok = 1;
                    for (int cc = c0; cc <= c1; cc++) ok &= ep[k][cc] + d >= 0 && ep[k][cc] + d <= max;
                    if (!ok) continue;
                    for (int cc = c0; cc <= c1; cc++) ep[k][cc] += d;
                    const double e = eval_ep(mode, shape, (const int(*)[3])ep, h, wt, tmp);
                    if (e < *err) {
                        *err = e;
                        memcpy(out, tmp, 16);
                        improved = 1;
                    } else {
                        for (int cc = c0; cc <= c1; cc++) ep[k][cc] -= d;
                    }
                }
        if (!improved) break;
    }
}

/* ---- BC6H, two-region modes ------------------------------------------------------------------- */

/* Indices (3 bits) and weighted error of region r's texels for endpoints qa, qb. */
static double assign3(const int h[16][3], const float wt[16], uint16_t sh, int r, const int qa[3], const int qb[3],
                      int bits, uint8_t idx[16])
{
    uint16_t pal[8][3];
    for (int c = 0; c < 3; c++) {
        const int ua = unq(qa[c], bits), ub = unq(qb[c], bits);
        for (int i = 0; i < 8; i++) pal[i][c] = (uint16_t)((((ua * (64 - w3[i]) + ub * w3[i] + 32) >> 6) * 31) >> 6);
    }
    double total = 0;
    for (int t = 0; t < 16; t++) {
        if ((int)((sh >> t) & 1u) != r) continue;
        double be = INFINITY;
        int bi = 0;
        for (int i = 0; i < 8; i++) {
            const double e = sq(pal[i][0] - h[t][0]) + sq(pal[i][1] - h[t][1]) + sq(pal[i][2] - h[t][2]);
            if (e < be) be = e, bi = i;
        }
        idx[t] = (uint8_t)bi;
        total += wt[t] * be;
    }
    return total;
}

/* Scatter of the texels about their region's mean: how well a shape splits the block. */
static double shape_scatter(const double u[16][3], const float wt[16], uint16_t sh)
{
    double total = 0;
    for (int r = 0; r < 2; r++) {
        double m[3] = {0, 0, 0}, sw = 0;
        for (int t = 0; t < 16; t++)
            if ((int)((sh >> t) & 1u) == r) {
                sw += wt[t];
                for (int c = 0; c < 3; c++) m[c] += wt[t] * u[t][c];
            }
        if (sw <= 0) continue;
        for (int c = 0; c < 3; c++) m[c] /= sw;
        for (int t = 0; t < 16; t++)
            if ((int)((sh >> t) & 1u) == r) total += wt[t] * (sq(u[t][0] - m[0]) + sq(u[t][1] - m[1]) + sq(u[t][2] - m[2]));
    }
    return total;
}

/* The best few (mode, shape, endpoints) of the search, refined at the end. */
#define TWO_REGION_KEEP 3
typedef struct candidate {
    int mode, shape;
    int ep[4][3];
    double err;
} candidate;
typedef struct candidates {
    candidate c[TWO_REGION_KEEP];
    int n;
} candidates;

static double cand_bar(const candidates *cl, double best)
{
    const double worst = cl->n < TWO_REGION_KEEP ? INFINITY : cl->c[cl->n - 1].err;
    return worst < best ? worst : best;
}

static void cand_push(candidates *cl, int mode, int shape, const int ep[4][3], double err)
{
    int i;
    if (cl->n < TWO_REGION_KEEP) i = cl->n++;
    else if (err >= cl->c[TWO_REGION_KEEP - 1].err) return;
    else i = TWO_REGION_KEEP - 1;
    for (; i > 0 && cl->c[i - 1].err > err; i--) cl->c[i] = cl->c[i - 1];
    cl->c[i].mode = mode, cl->c[i].shape = shape, cl->c[i].err = err;
    memcpy(cl->c[i].ep, ep, sizeof cl->c[i].ep);
}

/* Endpoints for mode (1..10) and shape from each region's principal axis; a candidate when it
 * beats the list's worst (and *best). */
static void try_two_region(const int h[16][3], const double u[16][3], const float wt[16], int mode, int shape,
                           double best, candidates *cl)
{
    int regions, bits, db[3], transformed;
    lbk_bc6h_mode_info(mode, &regions, &bits, db, &transformed);
    const uint16_t sh = lbk_bc6h_shape(shape);
    const int anchors[2] = {0, lbk_bc6h_anchor(shape)};
    int ep[4][3];
    uint8_t idx[16] = {0};
    for (int r = 0; r < 2; r++) {
        double ru[16][3];
        float rw[16];
        for (int t = 0; t < 16; t++) {
            memcpy(ru[t], u[t], sizeof ru[t]);
            rw[t] = (int)((sh >> t) & 1u) == r ? wt[t] : 0.0f;
        }
        double mean[3], axis[3], tmin = INFINITY, tmax = -INFINITY, sw = 0;
        for (int t = 0; t < 16; t++) sw += rw[t];
        if (sw <= 0) { /* nothing used in this region: any endpoints */
            for (int c = 0; c < 3; c++) mean[c] = u[anchors[r]][c], axis[c] = 0;
            tmin = tmax = 0;
        } else {
            principal_axis(ru, rw, mean, axis);
            for (int t = 0; t < 16; t++) {
                if (rw[t] <= 0) continue;
                const double p = (u[t][0] - mean[0]) * axis[0] + (u[t][1] - mean[1]) * axis[1] + (u[t][2] - mean[2]) * axis[2];
                if (p < tmin) tmin = p;
                if (p > tmax) tmax = p;
            }
        }
        for (int c = 0; c < 3; c++) {
            ep[2 * r][c] = quant(fmin(65535, fmax(0, mean[c] + tmin * axis[c])), bits);
            ep[2 * r + 1][c] = quant(fmin(65535, fmax(0, mean[c] + tmax * axis[c])), bits);
        }
    }
    /* anchors first (their index has no top bit), then deltas into range, then final indices */
    for (int pass = 0; pass < 2; pass++) {
        double err = 0;
        for (int r = 0; r < 2; r++) {
            err += assign3(h, wt, sh, r, ep[2 * r], ep[2 * r + 1], bits, idx);
            if (idx[anchors[r]] >= 4)
                for (int c = 0; c < 3; c++) {
                    const int t = ep[2 * r][c];
                    ep[2 * r][c] = ep[2 * r + 1][c], ep[2 * r + 1][c] = t;
                }
        }
        if (transformed)
            for (int k = 1; k < 4; k++)
                for (int c = 0; c < 3; c++) {
                    const int lo = ep[0][c] - (1 << (db[c] - 1)), hi = ep[0][c] + (1 << (db[c] - 1)) - 1;
                    if (ep[k][c] < lo) ep[k][c] = lo < 0 ? 0 : lo;
                    if (ep[k][c] > hi) ep[k][c] = hi > (1 << bits) - 1 ? (1 << bits) - 1 : hi;
                }
        if (pass == 1 || err >= cand_bar(cl, best)) {
            uint8_t tmp[16];
            err = eval_ep(mode, shape, (const int(*)[3])ep, h, wt, tmp);
            if (err < cand_bar(cl, best)) cand_push(cl, mode, shape, (const int(*)[3])ep, err);
            return;
        }
    }
}

#ifndef TWO_REGION_SHAPES
#define TWO_REGION_SHAPES 4
#endif

/* Blocks a single line fits badly (an edge, a chart next to another, a dark corner): the four
 * shapes that split the block best, with every two-region mode. */
static void two_region_search(const int h[16][3], const double u[16][3], const float wt[16], const int owner[16],
                              double *best, uint8_t out[16])
{
    /* two charts in one block split by a straight line: the shapes that separate them exactly come
     * first, so each chart gets its own endpoints (the seam between them stays a seam) */
    uint16_t split = 0;
    int other = -1, charts_ok = owner != NULL;
    for (int t = 0; charts_ok && t < 16; t++) {
        if (owner[t] < 0 || owner[t] == owner[0]) continue;
        if (other >= 0 && owner[t] != other) charts_ok = 0;
        other = owner[t];
        split |= (uint16_t)(1u << t);
    }
    int order[32];
    double sc[32];
    for (int s = 0; s < 32; s++) {
        const uint16_t sh = lbk_bc6h_shape(s);
        order[s] = s, sc[s] = shape_scatter(u, wt, sh);
        if (charts_ok && other >= 0) {
            uint16_t used = 0; /* the texels of the two charts (gaps are free) */
            for (int t = 0; t < 16; t++) used |= (uint16_t)((owner[t] >= 0) << t);
            if ((sh & used) == (split & used)) sc[s] = -1; /* an exact split */
        }
    }
    for (int i = 1; i < 32; i++) /* insertion sort by scatter */
        for (int j = i; j > 0 && sc[order[j]] < sc[order[j - 1]]; j--) {
            const int t = order[j];
            order[j] = order[j - 1], order[j - 1] = t;
        }
    candidates cl;
    cl.n = 0;
    for (int k = 0; k < TWO_REGION_SHAPES; k++)
        for (int mode = 1; mode <= 10; mode++) try_two_region(h, u, wt, mode, order[k], *best, &cl);
    for (int i = 0; i < cl.n; i++) {
        uint8_t tmp[16];
        double e = eval_ep(cl.c[i].mode, cl.c[i].shape, (const int(*)[3])cl.c[i].ep, h, wt, tmp);
        refine_ep(cl.c[i].mode, cl.c[i].shape, cl.c[i].ep, h, wt, &e, tmp);
        if (e < *best) {
            *best = e;
            memcpy(out, tmp, 16);
        }
    }
}

void tl_bc6h_encode_block(const float rgb[16][3], const float weight[16], const int owner[16], uint8_t out[16])
{
    int h[16][3];
    double u[16][3];
    float wt[16];
    double wsum = 0;
    for (int t = 0; t < 16; t++) {
        wt[t] = weight ? weight[t] : 1.0f;
        wsum += wt[t];
        for (int c = 0; c < 3; c++) {
            float v = rgb[t][c];
            if (!(v >= 0)) v = 0;
            if (v > 65504.0f) v = 65504.0f;
            h[t][c] = lbk_float_to_half(v);
            u[t][c] = h[t][c] * 64.0 / 31.0;
        }
    }
    if (wsum <= 0) { /* nothing here is used: black, mode 11 */
        for (int t = 0; t < 16; t++) wt[t] = 1;
    }
    double mean[3], axis[3];
    principal_axis(u, wt, mean, axis);
    double tmin = INFINITY, tmax = -INFINITY;
    for (int t = 0; t < 16; t++) {
        if (wt[t] <= 0) continue;
        const double s = (u[t][0] - mean[0]) * axis[0] + (u[t][1] - mean[1]) * axis[1] + (u[t][2] - mean[2]) * axis[2];
        if (s < tmin) tmin = s;
        if (s > tmax) tmax = s;
    }
    double best = INFINITY;
    int best_mode = 0, best_ep[4][3] = {{0}};
    for (int mi = 0; mi < 4; mi++) {
        const mode1 *m = &modes1[mi];
        double A[3], B[3];
        for (int c = 0; c < 3; c++) {
            A[c] = fmin(65535, fmax(0, mean[c] + tmin * axis[c]));
            B[c] = fmin(65535, fmax(0, mean[c] + tmax * axis[c]));
        }
        for (int it = 0; it < 3; it++) {
            int qa[3], qb[3], idx[16];
            if (!quantise_pair(m, A, B, qa, qb)) break;
            uint16_t pal[16][3];
            palette(qa, qb, m->w, pal);
            const double e = assign(h, wt, pal, idx);
            if (idx[0] >= 8 && !fits_swapped(m, qa, qb)) break;
            if (e < best) {
                best = e, best_mode = 11 + mi;
                memcpy(best_ep[0], qa, sizeof qa), memcpy(best_ep[1], qb, sizeof qb);
                pack_mode1(m, qa, qb, idx, out);
            }
            refit(u, wt, idx, A, B);
        }
    }
    /* endpoints a step off their nearest quantisation, where the fit is not already exact */
    double wsum1 = 0;
    for (int t = 0; t < 16; t++) wsum1 += wt[t];
    if (best_mode && best > 1.0 * wsum1) refine_ep(best_mode, 0, best_ep, h, wt, &best, out);
    /* a line in half-float space fits badly (more than ~1 % average error): try two regions */
    double wsum2 = 0;
    for (int t = 0; t < 16; t++) wsum2 += wt[t];
    if (isfinite(best) && best > 64.0 * wsum2) two_region_search(h, u, wt, owner, &best, out);
    if (!isfinite(best)) { /* cannot happen (mode 11 always fits); be safe: a constant black block */
        int z[3] = {0, 0, 0}, idx[16] = {0};
        pack_mode1(&modes1[0], z, z, idx, out);
    }
}

/* ---- BC4 ------------------------------------------------------------------------------------- */

static double bc4_try(const double t[16], const float wt[16], int a0, int a1, uint8_t out[8])
{
    double pal[8];
    pal[0] = a0, pal[1] = a1;
    for (int i = 1; i < 7; i++) pal[1 + i] = ((7 - i) * a0 + i * a1) / 7.0;
    uint64_t bitsv = 0;
    double e = 0;
    for (int k = 0; k < 16; k++) {
        int bi = 0;
        double be = INFINITY;
        for (int i = 0; i < 8; i++) {
            const double d = sq(pal[i] - t[k]);
            if (d < be) be = d, bi = i;
        }
        e += wt[k] * be;
        bitsv |= (uint64_t)bi << (3 * k);
    }
    out[0] = (uint8_t)a0, out[1] = (uint8_t)a1;
    for (int i = 0; i < 6; i++) out[2 + i] = (uint8_t)(bitsv >> (8 * i));
    return e;
}

void tl_bc4_encode_block(const float v[16], const float weight[16], uint8_t out[8])
{
    double t[16], lo = 255, hi = 0;
    float wt[16];
    int any = 0;
    for (int k = 0; k < 16; k++) {
        wt[k] = weight ? weight[k] : 1.0f;
        float x = v[k];
        if (!(x >= 0)) x = 0;
        if (x > 1) x = 1;
        t[k] = x * 255.0;
        if (wt[k] > 0) {
            any = 1;
            if (t[k] < lo) lo = t[k];
            if (t[k] > hi) hi = t[k];
        }
    }
    if (!any) lo = hi = 0;
    double best = INFINITY;
    uint8_t cand[8];
    const int H = (int)lround(hi), L = (int)lround(lo);
    for (int a0 = H - 2; a0 <= H + 2; a0++)
        for (int a1 = L - 2; a1 <= L + 2; a1++) {
            if (a0 < 0 || a0 > 255 || a1 < 0 || a1 > 255) continue;
            int x0 = a0, x1 = a1;
            if (x0 == x1) { /* a constant: the 8-value mode needs a0 > a1 */
                if (x0 < 255) x0++;
                else x1--;
            }
            if (x0 < x1) continue;
            const double e = bc4_try(t, wt, x0, x1, cand);
            if (e < best) best = e, memcpy(out, cand, 8);
        }
}

/* ---- pages --------------------------------------------------------------------------------- */

/* The stored direction as the decoder reads it (spec §5.6): normalised, +Z when shorter than 1/2. */
static void direction(const float rgba[4], float d[3])
{
    const float x = 2 * rgba[1] - 1, y = 2 * rgba[2] - 1, z = rgba[3];
    const float len = sqrtf(x * x + y * y + z * z);
    if (!(len >= 0.5f)) {
        d[0] = d[1] = 0, d[2] = 1;
        return;
    }
    d[0] = x / len, d[1] = y / len, d[2] = z / len;
}

static int encode_bc(const lbk_ahd_texel_f *tx, const float *wts, const int32_t *owners, uint32_t w, uint32_t h,
                     uint32_t f0, uint32_t f1, uint8_t *p0, uint8_t *p1)
{
    const uint32_t bw = w / 4, bh = h / 4;
    const uint64_t nb = (uint64_t)bw * bh;
    for (uint32_t by = 0; by < bh; by++)
        for (uint32_t bx = 0; bx < bw; bx++) {
            float rgb[16][3], wt[16], r[16], dx[16], dy[16];
            int own[16];
            for (int k = 0; k < 16; k++) {
                const size_t i = (size_t)(4 * by + (uint32_t)k / 4) * w + 4 * bx + (uint32_t)k % 4;
                memcpy(rgb[k], tx[i].ez, sizeof rgb[k]);
                wt[k] = wts ? wts[i] : 1.0f;
                own[k] = owners ? owners[i] : 0;
                float d[3];
                direction(tx[i].rgba, d);
                r[k] = tx[i].rgba[0];
                dx[k] = (d[0] + 1) / 2, dy[k] = (d[1] + 1) / 2;
            }
            const uint64_t b = (uint64_t)by * bw + bx;
            if (f0 == LBK_LMAP_BC6H) tl_bc6h_encode_block(rgb, wt, owners ? own : NULL, p0 + 16 * b);
            if (f1 == LBK_LMAP_BC5_BC4) {
                tl_bc4_encode_block(dx, wt, p1 + 16 * b);
                tl_bc4_encode_block(dy, wt, p1 + 16 * b + 8);
                tl_bc4_encode_block(r, wt, p1 + 16 * nb + 8 * b); /* 16·nb is a multiple of 16 */
            }
        }
    return 0;
}

int tl_lmap_encode_page(const lbk_ahd_texel_f *tx, const float *wts, const int32_t *owners, uint32_t w, uint32_t h,
                        uint32_t f0, uint32_t f1, void **plane0, void **plane1, char *err, size_t err_len)
{
    *plane0 = *plane1 = NULL;
    const uint64_t s0 = lbk_lmap_plane_size(0, f0, w, h), s1 = lbk_lmap_plane_size(1, f1, w, h);
    if (!s0 || !s1) {
        snprintf(err, err_len, "page %ux%u cannot hold plane formats %u/%u", w, h, f0, f1);
        return -1;
    }
    uint8_t *p0 = calloc(1, (size_t)s0), *p1 = calloc(1, (size_t)s1);
    if (!p0 || !p1) {
        free(p0), free(p1);
        snprintf(err, err_len, "out of memory");
        return -1;
    }
    const size_t n = (size_t)w * h;
    if (f0 == LBK_LMAP_R11G11B10F)
        for (size_t i = 0; i < n; i++) {
            const uint32_t v = lbk_r11g11b10f_pack(tx[i].ez);
            memcpy(p0 + 4 * i, &(uint8_t[4]){(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)}, 4);
        }
    if (f1 == LBK_LMAP_RGBA8)
        for (size_t i = 0; i < n; i++)
            for (int k = 0; k < 4; k++) p1[4 * i + (size_t)k] = lbk_float_to_unorm8(tx[i].rgba[k]);
    encode_bc(tx, wts, owners, w, h, f0, f1, p0, p1);
    int rc = 0;
    if (f0 == LBK_LMAP_ASTC4X4_HDR || f1 == LBK_LMAP_ASTC4X4_LDR) {
        float *buf = malloc(sizeof *buf * 4 * (n ? n : 1));
        if (!buf) rc = -1, snprintf(err, err_len, "out of memory");
        if (!rc && f0 == LBK_LMAP_ASTC4X4_HDR) {
            for (size_t i = 0; i < n; i++) memcpy(buf + 4 * i, tx[i].ez, 12), buf[4 * i + 3] = 1;
            rc = tl_astc_encode(buf, w, h, 1, p0, (size_t)s0, err, err_len);
        }
        if (!rc && f1 == LBK_LMAP_ASTC4X4_LDR) {
            for (size_t i = 0; i < n; i++) {
                float d[3];
                direction(tx[i].rgba, d);
                buf[4 * i] = tx[i].rgba[0], buf[4 * i + 1] = (d[0] + 1) / 2, buf[4 * i + 2] = (d[1] + 1) / 2;
                buf[4 * i + 3] = d[2];
            }
            rc = tl_astc_encode(buf, w, h, 0, p1, (size_t)s1, err, err_len);
        }
        free(buf);
    }
    if (rc) {
        free(p0), free(p1);
        return -1;
    }
    *plane0 = p0;
    *plane1 = p1;
    return 0;
}
