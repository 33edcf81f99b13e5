/* Stochastic light culling (slc.h, SLC.md) and glossy VPLs (vpl.h, VPL.md "In the transport") as
 * the run uses them: their set-up, their draws per pass, the threads' tile lists. */
#include "bake/transport/transport_impl.h"

/* ---- stochastic light culling: setup ------------------------------------------------------ */

/* The float box holding the double box [lo, hi] (rounded outwards). */
static void box_out(const double lo[3], const double hi[3], float *b)
{
    for (int a = 0; a < 3; a++) {
        b[a] = nextafterf((float)lo[a], -INFINITY);
        b[3 + a] = nextafterf((float)hi[a], INFINITY);
    }
}

static void box_grow(double lo[3], double hi[3], const double p[3])
{
    for (int a = 0; a < 3; a++) {
        if (p[a] < lo[a]) lo[a] = p[a];
        if (p[a] > hi[a]) hi[a] = p[a];
    }
}

/* The mean punctual irradiance of the positional lights (shadowed and cosine-weighted as
 * received: the error scalar X of TRANSPORT.md, fluence/4 at probes) over `k` receivers spread
 * evenly over [begin, end), or cell centres when there are no receivers. */
static double slc_class_mean(const tp_ctx *c, size_t begin, size_t end, size_t k)
{
    const size_t n = end - begin;
    if (k > n) k = n;
    double sum = 0, sh[3][9] = {{0}};
    for (size_t q = 0; q < k; q++) {
        size_t i = begin + q * n / k;
        tp_origin g;
        if (c->recv_count) {
            bk_tr_recv_origin(c, &c->recv[i], &g);
        } else {
            tp_cell_geom cg;
            double p[3];
            bk_tr_cell_geom(c, &c->cells[i], &cg);
            bk_tr_cell_point_at(&cg, 0.5, 0.5, p, NULL, NULL);
            float pf[3] = {(float)p[0], (float)p[1], (float)p[2]};
            bk_tr_origin_from(c, pf, c->cells[i].n, &g);
        }
        double e[3] = {0, 0, 0};
        for (size_t li = 0; li < c->light_count; li++)
            if (c->lights[li]->type != BK_LIGHT_DIRECTIONAL) bk_tr_punctual_one(c, &g, li, NULL, 1, e, sh);
        sum += bk_lum(e) * (g.sphere ? 0.25 : 1.0);
    }
    return k ? sum / (double)k : 0;
}

/* What δ is relative to: the smallest positive class mean of slc_class_mean, each class
 * sampled at up to 256 receivers (fewer when the lights are many: at most 2^22 shadow rays in
 * all, at least 16 receivers). Then one draw's relative RMSE over any class is at most √(δ/2)
 * (SLC.md): a class of dim receivers (texels beside bright probes) gets the δ it needs. */
static double slc_mean_irradiance(const tp_ctx *c)
{
    size_t k = c->light_count ? ((size_t)1 << 22) / (c->light_count * (size_t)c->ncls) : 256;
    k = k < 16 ? 16 : k > 256 ? 256 : k;
    if (!c->recv_count) return slc_class_mean(c, 0, c->cell_count, k);
    double best = 0;
    for (int q = 0; q < c->ncls; q++) {
        double m = slc_class_mean(c, c->cls[q].begin, c->cls[q].end, k);
        if (m > 0 && (best == 0 || m < best)) best = m;
    }
    return best;
}

/* Boxes of the points whose punctual light is culled: every receiver's punctual points, and
 * every cell's sub-triangle (padded by its edge band: cell points are clamped into it). */
static void recv_boxes(const tp_ctx *c, float *boxes)
{
    for (size_t i = 0; i < c->recv_count; i++) {
        tp_origin g[4];
        int points = bk_tr_punctual_points(c, &c->recv[i], g);
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int q = 0; q < points; q++) box_grow(lo, hi, g[q].p);
        box_out(lo, hi, boxes + 6 * i);
    }
}

static lbk_result slc_build(tp_ctx *c)
{
    const size_t nr = c->recv_count, nc = c->cell_count;
    float *boxes = malloc(6 * (nr > nc ? nr : nc ? nc : 1) * sizeof(float));
    if (!boxes) return LBK_ERR_OUT_OF_MEMORY;
    recv_boxes(c, boxes);
    lbk_result res = bk_slc_create(c->lights, c->light_count, boxes, nr, &c->slc_recv);
    for (size_t ci = 0; ci < nc && res == LBK_OK; ci++) {
        tp_cell_geom g;
        bk_tr_cell_geom(c, &c->cells[ci], &g);
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, tl[3], th[3];
        for (int a = 0; a < 3; a++) tl[a] = INFINITY, th[a] = -INFINITY;
        for (int v = 0; v < 3; v++) {
            double p[3];
            for (int a = 0; a < 3; a++)
                p[a] = (1 - g.b[v][0] - g.b[v][1]) * g.v[0][a] + g.b[v][0] * g.v[1][a] + g.b[v][1] * g.v[2][a];
            box_grow(lo, hi, p);
            box_grow(tl, th, g.v[v]);
        }
        for (int a = 0; a < 3; a++) {
            double pad = 4 * g.eps * (th[a] - tl[a]);
            lo[a] -= pad, hi[a] += pad;
        }
        box_out(lo, hi, boxes + 6 * ci);
    }
    if (res == LBK_OK) res = bk_slc_create(c->lights, c->light_count, boxes, nc, &c->slc_cell);
    free(boxes);
    if (res != LBK_OK) return res;
    c->slc_ids = malloc(2 * (size_t)c->threads * (c->light_count ? c->light_count : 1) * sizeof(uint32_t));
    c->slc_cdf = malloc((c->light_count ? c->light_count : 1) * sizeof(double));
    c->slc_pick_ids = malloc((c->light_count ? c->light_count : 1) * sizeof(uint32_t));
    if (!c->slc_ids || !c->slc_cdf || !c->slc_pick_ids) return LBK_ERR_OUT_OF_MEMORY;
    double tot = 0;
    for (size_t li = 0; li < c->light_count; li++) {
        const float *col = c->lights[li]->color;
        double v[3] = {isfinite(col[0]) && col[0] > 0 ? col[0] : 0, isfinite(col[1]) && col[1] > 0 ? col[1] : 0,
                       isfinite(col[2]) && col[2] > 0 ? col[2] : 0};
        if (c->lights[li]->type == BK_LIGHT_DIRECTIONAL || !(bk_lum(v) > 0)) continue;
        tot += bk_lum(v);
        c->slc_cdf[c->slc_pick_count] = tot;
        c->slc_pick_ids[c->slc_pick_count++] = (uint32_t)li;
    }
    if (!c->slc_pick_count || !(tot > 0) || !isfinite(tot)) return LBK_ERR_UNSUPPORTED_FEATURE; /* (culling off) */
    for (size_t k = 0; k < c->slc_pick_count; k++) c->slc_cdf[k] /= tot;
    c->slc_cdf[c->slc_pick_count - 1] = 1;
    return LBK_OK;
}

/* Whether this run culls (options.slc; auto: more than BK_SLC_AUTO_LIGHTS positional lights),
 * and its δ in irradiance units. */
lbk_result bk_tr_slc_init(tp_ctx *c)
{
    const bk_transport_options *opt = c->opt;
    size_t positional = 0;
    for (size_t li = 0; li < c->light_count; li++) positional += c->lights[li]->type != BK_LIGHT_DIRECTIONAL;
    const int want = opt->slc > 0 ? 1 : opt->slc < 0 ? 0 : positional > BK_SLC_AUTO_LIGHTS;
    if (!want || !positional) return LBK_OK;
    const double mean = slc_mean_irradiance(c);
    if (!(mean > 0) || !isfinite(mean)) return LBK_OK; /* nothing measurable to be relative to */
    c->slc_delta = (opt->slc_delta > 0 && isfinite(opt->slc_delta) ? opt->slc_delta : BK_SLC_DEFAULT_DELTA) * mean;
    lbk_result res = slc_build(c);
    c->slc = res == LBK_OK;
    return res == LBK_ERR_UNSUPPORTED_FEATURE ? LBK_OK : res; /* no positional light with power: exact */
}

/* ---- culling in the passes ------------------------------------------------------------------ */

static void tile_lists_init(uint32_t *ids, size_t cap, int thread, tp_tile_lists *t)
{
    for (int h = 0; h < 2; h++) {
        t->ids[h] = ids ? ids + (2 * (size_t)thread + (size_t)h) * cap : NULL;
        t->n[h] = 0;
        t->tile[h] = SIZE_MAX;
    }
}

void bk_tr_slc_lists_init(const tp_ctx *c, int thread, tp_tile_lists *t)
{
    tile_lists_init(c->slc_ids, c->light_count, thread, t);
}

/* A culling draw over `slc` for (half, pass): one ξ per light from its own stream. */
lbk_result bk_tr_slc_draw(const tp_ctx *c, int dom, int h, int pass, const bk_slc *slc, bk_slc_draw **out)
{
    double *xi = malloc((c->light_count ? c->light_count : 1) * sizeof *xi);
    if (!xi) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t li = 0; li < c->light_count; li++) {
        bk_rng r = bk_tr_rng(c->seed, (uint64_t)dom, (uint64_t)h, (uint64_t)pass, 0, li);
        xi[li] = bk_rng_next(&r);
    }
    lbk_result res = bk_slc_draw_create(slc, xi, ldexp(c->slc_delta, -(pass < 60 ? pass : 60)), c->threads, out);
    free(xi);
    return res;
}

void bk_tr_vpl_lists_init(const tp_ctx *c, int thread, tp_tile_lists *t)
{
    tile_lists_init(c->vpl_ids, c->vpl_cap, thread, t);
}

/* ---- glossy VPLs (VPL.md "In the transport") ------------------------------------------------ */

/* The surface a photon lands on, as the transport sees it: the hit's cell; glossy cells give
 * their specular lobe only (F0 = lerp(0.04, base, metallic), α = roughness²: bk_mr_lobe's),
 * everything else (Lambertian, black, the inside of a solid) makes no VPL: diffuse bounces are
 * the cache's. */
static int vpl_material(void *user, const bk_hit *hit, const double x[3], bk_vpl_material *m)
{
    (void)x;
    const tp_ctx *c = (const tp_ctx *)user;
    const long hc = bk_tr_hit_cell(c, hit);
    if (hc < 0 || !c->gloss[hc].on) return 0;
    const tp_gloss *g = &c->gloss[hc];
    memset(m, 0, sizeof *m);
    for (int k = 0; k < 3; k++) m->f0[k] = (float)bk_mr_f0(g->base[k], g->metallic);
    m->alpha = g->roughness * g->roughness;
    return 1;
}

/* Half h's photons of `pass` from every light that shoots: c->vpls[h] (N·2^pass per light, at
 * most TP_VPL_PHOTON_CAP over all the lights, ~140 MB of VPLs per half: a level of many lamps
 * must not shoot N per lamp into gigabytes; each lamp then gets fewer photons, at least 16). */
#define TP_VPL_PHOTON_CAP ((size_t)1 << 20)
static lbk_result vpl_shoot_all(tp_ctx *c, int h, int pass)
{
    free(c->vpls[h]);
    c->vpls[h] = NULL;
    c->vpl_n[h] = 0;
    size_t shooters = 0;
    for (size_t li = 0; li < c->light_count; li++) shooters += c->light_vpl[li];
    size_t n = c->vpl_photons << (pass < 12 ? pass : 12);
    const size_t cap = TP_VPL_PHOTON_CAP / (shooters ? shooters : 1);
    if (n > cap) n = cap > 16 ? cap : 16;
    for (size_t li = 0; li < c->light_count; li++) {
        if (!c->light_vpl[li]) continue;
        bk_vpl_shoot_desc sd = {c->scene, c->tracer, NULL, c->seed, n,
                                c->threads, bk_mix64(((uint64_t)DOM_VPL_SHOOT << 56) ^ ((uint64_t)h << 48) ^
                                                  ((uint64_t)pass << 32) ^ (uint64_t)li),
                                vpl_material, c};
        bk_vpl *v;
        size_t cnt;
        lbk_result res = bk_vpl_shoot(&sd, c->lights[li], &v, &cnt);
        if (res != LBK_OK) return res;
        bk_vpl *all = realloc(c->vpls[h], (c->vpl_n[h] + cnt + 1) * sizeof *all);
        if (!all) {
            free(v);
            return LBK_ERR_OUT_OF_MEMORY;
        }
        memcpy(all + c->vpl_n[h], v, cnt * sizeof *v);
        c->vpls[h] = all;
        c->vpl_n[h] += cnt;
        free(v);
    }
    return LBK_OK;
}

/* This pass's VPLs and draws (one per half; ξ per VPL from the stream (seed, DOM_VPL_XI, half,
 * pass, the VPL's index: lights in order, photons in order), δ/2^pass) and the threads' room for tile lists. */
lbk_result bk_tr_vpl_pass(tp_ctx *c, int pass)
{
    for (int h = 0; h < 2; h++) {
        lbk_result res = vpl_shoot_all(c, h, pass);
        if (res != LBK_OK) return res;
        c->vpl_made += c->vpl_n[h];
        double *xi = malloc((c->vpl_n[h] ? c->vpl_n[h] : 1) * sizeof *xi);
        if (!xi) return LBK_ERR_OUT_OF_MEMORY;
        for (size_t k = 0; k < c->vpl_n[h]; k++) {
            bk_rng r = bk_tr_rng(c->seed, DOM_VPL_XI, (uint64_t)h, (uint64_t)pass, 0, k);
            xi[k] = bk_rng_next(&r);
        }
        res = bk_vpl_draw_create(c->vpls[h], c->vpl_n[h], xi, ldexp(c->vpl_delta, -(pass < 60 ? pass : 60)),
                                 BK_VPL_BOUND_ELLIPSOID, c->vpl_tiles, c->threads, &c->vpl_draw[h]);
        free(xi);
        if (res != LBK_OK) return res;
    }
    const size_t cap = c->vpl_n[0] > c->vpl_n[1] ? c->vpl_n[0] : c->vpl_n[1];
    if (cap > c->vpl_cap || !c->vpl_ids) {
        free(c->vpl_ids);
        c->vpl_cap = cap ? cap : 1;
        c->vpl_ids = malloc(2 * (size_t)c->threads * c->vpl_cap * sizeof(uint32_t));
        if (!c->vpl_ids) return LBK_ERR_OUT_OF_MEMORY;
    }
    return LBK_OK;
}

void bk_tr_vpl_pass_end(tp_ctx *c)
{
    for (int h = 0; h < 2; h++) {
        bk_vpl_draw_destroy(c->vpl_draw[h]);
        c->vpl_draw[h] = NULL;
        free(c->vpls[h]);
        c->vpls[h] = NULL;
        c->vpl_n[h] = 0;
    }
}

/* What the VPLs' δ is relative to: the mean irradiance that pass 0's VPLs (half 0, as vpl_sharp_
 * share leaves them) give the surface receivers, by brute force at up to 256 of them spread
 * evenly by index (their points, as the gather takes them). Then one draw's relative RMSE of the
 * VPL light over the receivers is at most √δ_rel (VPL.md), whatever the direct light. */
static double vpl_mean_irradiance(tp_ctx *c)
{
    enum { K = 256 };
    const size_t n = c->recv_count, k = n < K ? n : K;
    bk_vpl_point *pts = malloc(4 * K * sizeof *pts);
    double *irr = malloc(3 * 4 * K * sizeof *irr);
    size_t np = 0;
    for (size_t q = 0; q < k && pts && irr; q++) {
        const bk_receiver *r = &c->recv[q * n / k];
        if (!(r->normal[0] != 0 || r->normal[1] != 0 || r->normal[2] != 0)) continue;
        tp_origin g[4];
        const int points = bk_tr_punctual_points(c, r, g);
        for (int j = 0; j < points; j++, np++)
            for (int a = 0; a < 3; a++) pts[np].p[a] = g[j].p[a], pts[np].n[a] = g[j].n[a], pts[np].org[a] = g[j].o[a];
    }
    double sum = 0;
    int ok = pts && irr && np &&
             bk_vpl_gather(c->vpls[0], c->vpl_n[0], NULL, c->tracer, pts, np, c->threads, irr, NULL) == LBK_OK;
    for (size_t j = 0; ok && j < np; j++) sum += bk_lum(irr + 3 * j); /* (a texel's 4 points: its mean, × 4) */
    free(pts);
    free(irr);
    return ok ? sum / (double)np : 0;
}

/* What auto measures: the share of the shooting lights' flux (its upper bound lum(I)·Ω) that
 * pass 0's photons (half 0) put into sharp glossy VPLs (α ≤ BK_VPL_AUTO_ROUGHNESS², weighted by
 * lum(Φ·F0): what they reflect specularly). */
static double vpl_sharp_share(tp_ctx *c)
{
    if (vpl_shoot_all(c, 0, 0) != LBK_OK) return 0;
    double sharp = 0, emitted = 0;
    const double amax = BK_VPL_AUTO_ROUGHNESS * BK_VPL_AUTO_ROUGHNESS;
    for (size_t k = 0; k < c->vpl_n[0]; k++) {
        const bk_vpl *v = &c->vpls[0][k];
        double pf[3] = {v->flux[0] * v->refl[0], v->flux[1] * v->refl[1], v->flux[2] * v->refl[2]};
        if (v->alpha <= amax * (1 + 1e-5)) sharp += bk_lum(pf); /* (float roughness 0.3f counts as 0.3) */
    }
    for (size_t li = 0; li < c->light_count; li++) {
        if (!c->light_vpl[li]) continue;
        const bk_light *l = c->lights[li];
        double col[3] = {l->color[0], l->color[1], l->color[2]};
        const double outer = l->type == BK_LIGHT_SPOT && l->outer_cone > 0 && l->outer_cone < TP_PI ? l->outer_cone : TP_PI;
        emitted += bk_lum(col) * 2 * TP_PI * (1 - cos(outer));
    }
    return emitted > 0 ? sharp / emitted : 0;
}

/* Whether this run adds glossy VPLs (options.glossy_vpl; auto: vpl_sharp_share ≥
 * BK_VPL_AUTO_SHARE), which lights shoot (positional ones with power), the receivers' tiles and
 * δ (relative to the smallest class mean of the punctual irradiance, as SLC's). Needs a glossy
 * cell, a light that shoots and a surface receiver; else off and nothing else changes. */
lbk_result bk_tr_vpl_init(tp_ctx *c)
{
    const bk_transport_options *opt = c->opt;
    if (opt->glossy_vpl < 0 || !c->gloss || !c->light_count || !c->recv_count) return LBK_OK;
    int surface = 0;
    for (size_t i = 0; i < c->recv_count && !surface; i++) {
        const float *n = c->recv[i].normal;
        surface = n[0] != 0 || n[1] != 0 || n[2] != 0;
    }
    if (!surface) return LBK_OK;
    c->light_vpl = calloc(c->light_count, 1);
    if (!c->light_vpl) return LBK_ERR_OUT_OF_MEMORY;
    int shooters = 0;
    for (size_t li = 0; li < c->light_count; li++) {
        const float *col = c->lights[li]->color;
        double v[3] = {isfinite(col[0]) && col[0] > 0 ? col[0] : 0, isfinite(col[1]) && col[1] > 0 ? col[1] : 0,
                       isfinite(col[2]) && col[2] > 0 ? col[2] : 0};
        c->light_vpl[li] = c->lights[li]->type != BK_LIGHT_DIRECTIONAL && bk_lum(v) > 0;
        shooters += c->light_vpl[li];
    }
    if (!shooters) return LBK_OK;
    c->vpl_photons = opt->glossy_vpl_photons > 0 ? opt->glossy_vpl_photons : BK_VPL_DEFAULT_PHOTONS;
    c->vpl_share = vpl_sharp_share(c);
    const double mean = opt->glossy_vpl > 0 || c->vpl_share >= BK_VPL_AUTO_SHARE ? vpl_mean_irradiance(c) : 0;
    bk_tr_vpl_pass_end(c);
    if (!(mean > 0) || !isfinite(mean)) return LBK_OK; /* off, or no VPL light reaches a receiver */
    c->vpl_delta = (opt->glossy_vpl_delta > 0 && isfinite(opt->glossy_vpl_delta) ? opt->glossy_vpl_delta
                                                                                  : BK_VPL_DEFAULT_DELTA) * mean;
    float *boxes = malloc(6 * c->recv_count * sizeof(float));
    if (!boxes) return LBK_ERR_OUT_OF_MEMORY;
    recv_boxes(c, boxes);
    lbk_result res = bk_slc_create(NULL, 0, boxes, c->recv_count, &c->vpl_tiles);
    free(boxes);
    if (res != LBK_OK) return res;
    c->vpl = 1;
    return LBK_OK;
}
