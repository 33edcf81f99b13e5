/* Near-field continuation (transport_impl.h, TRANSPORT.md §Bias): hits that are near, rough, in a
 * gap or glossy are evaluated at the exact hit point instead of read from their cell. */
#include "bake/transport/transport_impl.h"

#define TP_NEAR_INSET 1e-4  /* barycentric inset of a continuation's point from its triangle's edges */

static const float *mode_read(const tp_near_mode *md, int depth)
{
    if (!md->hist) return md->read;
    return md->bounce - 1 - depth >= 2 ? md->hist[depth + 1] : NULL;
}

static int mode_sources(const tp_near_mode *md, int depth)
{
    return md->hist ? md->bounce - 1 - depth == 1 : md->sources;
}

/* Light li at the continued point x (normal n, ray origin o), weighted `scale`, into e (through
 * the BSDF lf at a glossy point; NULL: irradiance). */
static void near_light(const tp_ctx *c, size_t li, const double x[3], const double n[3], const float o[3], double scale,
                       const tp_lobe *lf, int split, double e[3], tp_count *cnt)
{
    double val[3], ld[3], dist;
    if (!bk_light_eval(c->lights[li], x, val, ld, &dist)) return;
    double cs = ld[0] * n[0] + ld[1] * n[1] + ld[2] * n[2];
    if (cs <= 0) return;
    double f[3] = {1, 1, 1};
    if (lf) { /* a glossy point: through its BSDF */
        double l[3];
        bk_tr_to_local(lf, ld, l);
        if (split && c->light_vpl[li]) bk_mr_lobe_eval_diffuse(&lf->lb, l, f); /* the VPLs carry the rest */
        else bk_mr_lobe_eval(&lf->lb, l, f);
        if (f[0] <= 0 && f[1] <= 0 && f[2] <= 0) return;
    }
    cnt->shadow++;
    if (!bk_light_visible(c->tracer, o, ld, dist)) return;
    if (lf)
        for (int a = 0; a < 3; a++) e[a] += scale * val[a] * cs * f[a];
    else
        for (int a = 0; a < 3; a++) e[a] += scale * val[a] * cs;
}

/* A positional light for u ∈ [0, 1) in proportion to its intensity (slc_cdf); *scale gets 1/P. */
static size_t slc_pick(const tp_ctx *c, double u, double *scale)
{
    size_t lo = 0, hi = c->slc_pick_count - 1;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (c->slc_cdf[mid] > u) hi = mid;
        else lo = mid + 1;
    }
    double p = c->slc_cdf[lo] - (lo ? c->slc_cdf[lo - 1] : 0);
    *scale = p > 0 ? 1 / p : 0;
    return c->slc_pick_ids[lo];
}

/* The continued point of `hit` (on cell's side) and its offset ray origin o. */
static void cont_point(const tp_ctx *c, const bk_hit *hit, const tp_cell *cell, double x[3], float o[3])
{
    double v[3][3];
    bk_tr_tri_vertices(c, hit->tri, v);
    /* the point a hair inside its triangle: a hit on an edge where another surface meets it (a
     * box's corner) rounds to either side, and from the far side of that surface the
     * continuation starts behind it (in a furnace box it then saw the walls' backs: black) */
    double hu = fmax(hit->u, TP_NEAR_INSET), hv = fmax(hit->v, TP_NEAR_INSET);
    if (hu + hv > 1 - TP_NEAR_INSET) {
        double k = (1 - TP_NEAR_INSET) / (hu + hv);
        hu *= k, hv *= k;
    }
    for (int a = 0; a < 3; a++) x[a] = (1.0 - hu - hv) * v[0][a] + hu * v[1][a] + hv * v[2][a];
    float xf[3] = {(float)x[0], (float)x[1], (float)x[2]}, nf[3] = {cell->n[0], cell->n[1], cell->n[2]};
    bk_offset_ray_origin_scaled(xf, nf, bk_tracer_tri_scale(c->tracer, hit->tri), o);
}

/* The chance that an exact path goes on from cell hc: its brightest albedo channel, within
 * [0.05, 0.99] (a path that carries weight a/p per bounce keeps a bounded variance for a ≤ p;
 * 0.99 bounds it by (a²/p)^k ≤ 1.008^k in the whitest rooms, where max_depth ends it). */
static double exact_survival(const tp_ctx *c, long hc)
{
    const tp_cell *cell = &c->cells[hc];
    double a = fmax(cell->albedo[0], fmax(cell->albedo[1], cell->albedo[2]));
    if (c->gloss && c->gloss[hc].on) a = fmax(a, fmax(c->gloss[hc].base[0], fmax(c->gloss[hc].base[1], c->gloss[hc].base[2])));
    return fmin(0.99, fmax(0.05, a));
}

/* An exact path's next vertex at h2 (the path check): continued, by Russian roulette past
 * TP_EXACT_RR_DEPTH, into r2. */
static void exact_next(tp_ctx *c, const tp_near_mode *md, const bk_hit *h2, long h2c, const double d[3], int depth,
                       bk_rng *rng, tp_count *cnt, double r2[3])
{
    if (depth + 1 >= md->max_depth) return;
    double p = depth + 1 < TP_EXACT_RR_DEPTH ? 1 : exact_survival(c, h2c);
    if (p < 1 && bk_rng_next(rng) >= p) return;
    bk_tr_near_radiance(c, md, h2, h2c, d, depth + 1, rng, cnt, r2);
    for (int a = 0; a < 3; a++) r2[a] /= p;
}

/* What a continuation ray from o along unit d brings back: sky, emission (MIS-weighted against
 * the light samples with the continuation's own density pg) and the cache — or the exact
 * radiance where that hit is near, rough or glossy too (up to md->max_depth in a row). */
void bk_tr_cont_trace(tp_ctx *c, const tp_near_mode *md, const float o[3], const double d[3], double pg, int depth,
                      bk_rng *rng, tp_count *cnt, double L[3])
{
    float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
    L[0] = L[1] = L[2] = 0;
    bk_hit h2;
    cnt->rays++;
    const int sources = mode_sources(md, depth);
    const float *read = mode_read(md, depth);
    if (!bk_tracer_intersect(c->tracer, o, df, 0.0f, INFINITY, &h2)) {
        if (sources) bk_tr_sky_radiance(c, d, L);
        return;
    }
    long h2c = bk_tr_hit_cell(c, &h2);
    if (h2c < 0) return;
    if (sources) {
        bk_tr_emission_at(c, h2.tri, h2.u, h2.v, L);
        if (L[0] > 0 || L[1] > 0 || L[2] > 0) {
            double w = bk_tr_mis_gather(c, &h2, h2c, d, pg);
            for (int a = 0; a < 3; a++) L[a] *= w;
        }
    }
    double r2[3] = {0, 0, 0};
    if (md->exact) {
        exact_next(c, md, &h2, h2c, d, depth, rng, cnt, r2);
    } else if (read && depth + 1 < md->max_depth && bk_tr_near_hit(c, &h2, h2c, md->rough)) {
        bk_tr_near_radiance(c, md, &h2, h2c, d, depth + 1, rng, cnt, r2);
    } else if (read) {
        for (int a = 0; a < 3; a++) r2[a] = read[3 * h2c + a];
    }
    for (int a = 0; a < 3; a++) L[a] += r2[a];
}

/* Reflected radiance (all bounces, emission excluded) at a glossy hit towards -din: one sample
 * of the coupled BSDF (GGX.md) traced like a Lambertian continuation, one light sample weighed
 * against the BSDF's density (MIS), one punctual light through the BSDF. */
static void gloss_radiance(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double din[3],
                           int depth, bk_rng *rng, tp_count *cnt, double out[3])
{
    const tp_cell *cell = &c->cells[hc];
    const tp_gloss *g = &c->gloss[hc];
    double x[3];
    float o[3];
    cont_point(c, hit, cell, x, o);
    tp_lobe lf;
    for (int a = 0; a < 3; a++) lf.n[a] = cell->n[a];
    bk_onb(lf.n, lf.t, lf.b);
    double vw[3] = {-din[0], -din[1], -din[2]}, v[3];
    bk_tr_to_local(&lf, vw, v);
    out[0] = out[1] = out[2] = 0;
    const double base[3] = {g->base[0], g->base[1], g->base[2]};
    if (!bk_mr_lobe_init(&lf.lb, c->ggx, base, g->metallic, g->roughness, v)) return;
    double u0 = bk_rng_next(rng), u1 = bk_rng_next(rng), u2 = bk_rng_next(rng), l[3];
    double pdf = bk_mr_lobe_sample(&lf.lb, u0, u1, u2, l);
    if (pdf > 0 && l[2] > 0) {
        double d[3], f[3], L[3];
        for (int a = 0; a < 3; a++) d[a] = l[0] * lf.t[a] + l[1] * lf.b[a] + l[2] * lf.n[a];
        bk_mr_lobe_eval(&lf.lb, l, f);
        bk_tr_cont_trace(c, md, o, d, pdf, depth, rng, cnt, L);
        for (int a = 0; a < 3; a++) out[a] += f[a] * l[2] / pdf * L[a];
    }
    const int sources = mode_sources(md, depth);
    if (sources && c->nee) {
        double ld[3], cq, val[3];
        double a0 = bk_rng_next(rng), a1 = bk_rng_next(rng);
        if (bk_tr_nee_sample_lobe(c, o, lf.n, PG_COSINE, &lf, a0, a1, NULL, ld, &cq, val, &cnt->shadow) &&
            bk_finite3(val)) {
            double ll[3], f[3];
            bk_tr_to_local(&lf, ld, ll);
            bk_mr_lobe_eval(&lf.lb, ll, f);
            for (int a = 0; a < 3; a++) out[a] += val[a] * f[a] * cq;
        }
    }
    if (sources && c->light_count) bk_tr_cont_punctual(c, x, lf.n, o, &lf, md->vpl && depth == 0, rng, out, cnt);
}

void bk_tr_near_radiance(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double din[3],
                         int depth, bk_rng *rng, tp_count *cnt, double out[3])
{
    if (c->gloss && c->gloss[hc].on) {
        gloss_radiance(c, md, hit, hc, din, depth, rng, cnt, out);
        return;
    }
    const tp_cell *cell = &c->cells[hc];
    double x[3];
    float o[3];
    cont_point(c, hit, cell, x, o);
    double n[3] = {cell->n[0], cell->n[1], cell->n[2]}, t[3], b[3];
    bk_onb(n, t, b);
    double u1 = bk_rng_next(rng), ph = 2 * TP_PI * bk_rng_next(rng), rr = sqrt(u1), lz = sqrt(fmax(0.0, 1 - u1));
    double d[3];
    for (int a = 0; a < 3; a++) d[a] = rr * cos(ph) * t[a] + rr * sin(ph) * b[a] + lz * n[a];
    double L[3];
    bk_tr_cont_trace(c, md, o, d, lz / TP_PI, depth, rng, cnt, L);
    double e[3] = {TP_PI * L[0], TP_PI * L[1], TP_PI * L[2]};
    const int sources = mode_sources(md, depth);
    if (sources && c->nee) {
        /* the light sample that pairs with the gather above (MIS): a point next to an emitter
         * (the ceiling by the Cornell light's 1 cm gap) sees it at grazing angles, which
         * gathering alone finds rarely and brightly */
        double ld[3], cq, val[3];
        double u0 = bk_rng_next(rng), u1n = bk_rng_next(rng);
        if (bk_tr_nee_sample(c, o, n, PG_COSINE, u0, u1n, ld, &cq, val, &cnt->shadow) && bk_finite3(val))
            for (int a = 0; a < 3; a++) e[a] += val[a] * cq;
    }
    if (sources && c->light_count) bk_tr_cont_punctual(c, x, n, o, NULL, 0, rng, e, cnt);
    for (int a = 0; a < 3; a++) out[a] = cell->albedo[a] / TP_PI * e[a];
}

/* A gather ray's near hit (depth 0): one continuation, or on a cell inside a gap the mean of
 * TP_GAP_SPLIT. Seen from the room, such a cell is the gap's mouth, whose exact radiance one
 * continuation estimates poorly (half its directions go deep into a gap ~25× brighter than the
 * room); such hits are rare (a 1 cm slit subtends little), so splitting them costs few rays and
 * brings the noise the cell's constant did not have back down (TRANSPORT.md, gap cells). Not
 * split: a cell only partly covered (the gap's mouth: hit from everywhere, its continuation
 * starts outside the gap), and hits from close by (the crevice where two of room_with_doors'
 * spheres touch, gathered from their own vertices: a fifth more time, nothing gained). */
#define TP_GAP_SPLIT 4
void bk_tr_near_entry(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double d[3], bk_rng *rng,
                      tp_count *cnt, double out[3])
{
    const int far = hit->t >= TP_NEAR_CELLS * c->tri_cell_h[hit->tri];
    const int n = far && c->gap[hc] == TP_GAP_INSIDE ? TP_GAP_SPLIT : 1;
    bk_tr_near_radiance(c, md, hit, hc, d, 0, rng, cnt, out);
    for (int k = 1; k < n; k++) {
        double r[3];
        bk_tr_near_radiance(c, md, hit, hc, d, 0, rng, cnt, r);
        for (int a = 0; a < 3; a++) out[a] += r[a];
    }
    if (n > 1)
        for (int a = 0; a < 3; a++) out[a] /= n;
}

void bk_tr_cont_punctual(const tp_ctx *c, const double x[3], const double n[3], const float o[3], const tp_lobe *lf,
                         int split, bk_rng *rng, double e[3], tp_count *cnt)
{
    /* one light: uniformly; with culling (many lights) a positional one in proportion to its
     * intensity (a uniform pick among thousands almost never finds the lamp that matters)
     * and every directional one */
    double u = bk_rng_next(rng), scale = (double)c->light_count;
    size_t li = (size_t)(u * (double)c->light_count);
    if (c->slc) {
        li = slc_pick(c, u, &scale);
        const uint32_t *always;
        size_t na = bk_slc_always(c->slc_recv, &always);
        for (size_t k = 0; k < na; k++) near_light(c, always[k], x, n, o, 1, lf, split, e, cnt);
    }
    if (li >= c->light_count) li = c->light_count - 1;
    near_light(c, li, x, n, o, scale, lf, split, e, cnt);
}
