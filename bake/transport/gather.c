/* Receivers and the final gather: ray origins and footprints, punctual light, the gather of one
 * half of one pass, the culled lights' and glossy VPLs' share, octahedral probes. */
#include "bake/transport/transport_impl.h"

/* ---- receivers ------------------------------------------------------------------------------- */

void bk_tr_origin_from(const tp_ctx *c, const float p[3], const float nf[3], tp_origin *g)
{
    double l = sqrt((double)nf[0] * nf[0] + (double)nf[1] * nf[1] + (double)nf[2] * nf[2]);
    g->sphere = !(l > 0) || !isfinite(l);
    for (int k = 0; k < 3; k++) {
        g->p[k] = p[k];
        g->n[k] = g->sphere ? 0 : nf[k] / l;
    }
    if (g->sphere) {
        g->n[2] = 1;
        memcpy(g->o, p, 3 * sizeof(float));
        return;
    }
    bk_offset_ray_origin_scaled(p, nf, c->scene_scale, g->o);
}

/* The receiver's own point (the whole texel where it has no footprint). */
void bk_tr_recv_origin(const tp_ctx *c, const bk_receiver *r, tp_origin *g)
{
    bk_tr_origin_from(c, r->position, r->normal, g);
}

/* The origin at texel-local (s, t) of receiver r's footprint: the footprint triangle's point that
 * covers it (position and interpolated shading normal from the footprint scene; returns 1), else
 * the receiver's own point (returns 0); or, where r marks hidden cells, -1 (g untouched) when the
 * point lies beyond another surface (bk_footprint_sample_hidden). Door runs trace a scene without
 * the door, whose triangles are not the ones footprints index: there the cell marks alone decide.
 * One footprint lookup serves both. */
static int footprint_at(const tp_ctx *c, const bk_receiver *r, double s, double t, tp_origin *g)
{
    double p[3], n[3];
    const int on = r->footprint_count && bk_footprint_point(c->fscene, c->opt->footprint + r->footprint_first,
                                                             r->footprint_count, s, t, p, n);
    if (r->footprint_hidden) {
        const int hidden = c->fscene != c->scene
                               ? bk_footprint_cell_hidden(r->footprint_hidden, s, t)
                               : on && bk_footprint_sample_hidden(c->tracer, c->scene, c->opt->footprint, r, s, t, p, n);
        if (hidden) return -1;
    }
    if (!on) {
        bk_tr_recv_origin(c, r, g);
        return 0;
    }
    float pf[3] = {(float)p[0], (float)p[1], (float)p[2]}, nf[3] = {(float)n[0], (float)n[1], (float)n[2]};
    bk_tr_origin_from(c, pf, nf, g);
    return 1;
}

/* A uniform point of the part of the texel's square that its footprint covers: rejection in the
 * footprint box, at most TP_FOOTPRINT_TRIES draws (a footprint covering 10 % of its box falls
 * back to the receiver's own point 18 % of the time, one covering 30 % 0.3 %; charts of
 * axis-aligned slivers fill their boxes). */
#define TP_FOOTPRINT_TRIES 16
void bk_tr_footprint_sample(const tp_ctx *c, const bk_receiver *r, bk_rng *pos, tp_origin *g)
{
    const float *bx = r->footprint_box;
    int box = bx[2] > 0 && bx[3] > 0;
    for (int k = 0; k < TP_FOOTPRINT_TRIES; k++) {
        double ps = bk_rng_next(pos), pt = bk_rng_next(pos);
        if (box) {
            ps = bx[0] + ps * bx[2];
            pt = bx[1] + pt * bx[3];
        }
        if (footprint_at(c, r, ps, pt, g) > 0) return;
    }
}

/* One punctual light at one point, weighted w (1, or 1/p of an accepted culling draw):
 * irradiance (sphere: fluence) and the SH of its incident radiance. Returns the shadow rays. */
uint64_t bk_tr_punctual_one(const tp_ctx *c, const tp_origin *g, size_t li, const bk_slc_draw *d, double delta,
                            double e[3], double sh[3][9])
{
    double val[3], ld[3], dist;
    if (!bk_light_eval(c->lights[li], g->p, val, ld, &dist)) return 0;
    double w = d ? bk_slc_weight(bk_lum(val), delta, bk_slc_draw_xi(d, (uint32_t)li)) : 1.0;
    if (w == 0) return 0;
    double cs = ld[0] * g->n[0] + ld[1] * g->n[1] + ld[2] * g->n[2];
    if (!g->sphere && cs <= 0) return 0;
    if (!bk_light_visible(c->tracer, g->o, ld, dist)) return 1;
    double y[9];
    bk_sh9_basis_d(ld, y);
    for (int a = 0; a < 3; a++) {
        double v = val[a] * w;
        e[a] += g->sphere ? v : v * cs;
        for (int kk = 0; kk < 9; kk++) sh[a][kk] += v * y[kk];
    }
    return 1;
}

/* Punctual light at one point. d NULL: every light, exactly. Else a culling draw: the lights
 * that are never culled plus those of ids (the point's tile list), each by the draw's ξ. */
static uint64_t punctual_at(const tp_ctx *c, const tp_origin *g, const bk_slc_draw *d, const uint32_t *ids, size_t n,
                            double delta, double e[3], double sh[3][9])
{
    uint64_t rays = 0;
    if (!d) {
        for (size_t li = 0; li < c->light_count; li++) rays += bk_tr_punctual_one(c, g, li, NULL, 1, e, sh);
        return rays;
    }
    const uint32_t *always;
    size_t na = bk_slc_always(c->slc_recv, &always);
    for (size_t k = 0; k < na; k++) rays += bk_tr_punctual_one(c, g, always[k], NULL, 1, e, sh);
    for (size_t k = 0; k < n; k++) rays += bk_tr_punctual_one(c, g, ids[k], d, delta, e, sh);
    return rays;
}

/* The points at which a receiver's punctual light is evaluated where one draw stands for it
 * (culling, VPLs; bk_tr_recv_punctual, exact, takes a finer grid): a texel with a footprint
 * averages its four quarter centres, but
 * those beyond another surface (footprint_hidden): a floor texel half under a crate read the
 * sun at half its strength (dev level overlap_01). None left: the texel's own point. (The
 * quarter centres of the footprint box instead of the square lit a chart's sliver where it
 * lies, but moved door-closed bakes 5 % against the guided door runs, which gather at the
 * texel's point: tests/bake/test_doors.c; not kept.) */
int bk_tr_punctual_points(const tp_ctx *c, const bk_receiver *r, tp_origin g[4])
{
    int n = 0, on = 0;
    for (int q = 0; q < 4 && r->footprint_count; q++) {
        const int k = footprint_at(c, r, 0.25 + 0.5 * (q & 1), 0.25 + 0.5 * (q >> 1), &g[n]);
        if (k < 0) continue;
        on += k;
        n++;
    }
    /* A sliver (a chart's corner in the texel) holds no quarter centre, and all four read the
     * texel's own point, which can lie in the light where the sliver is in shadow: 10.8 lux
     * there against 7.3 traced over the sliver (a doorway's jamb, room_sets_doors). Its box's
     * quarter centres, those on the footprint, instead. */
    const float *bx = r->footprint_box;
    if (n && !on && bx[2] > 0 && bx[3] > 0) {
        int m = 0;
        for (int q = 0; q < 4; q++) {
            const double s = bx[0] + (0.25 + 0.5 * (q & 1)) * bx[2], t = bx[1] + (0.25 + 0.5 * (q >> 1)) * bx[3];
            tp_origin o;
            if (footprint_at(c, r, s, t, &o) > 0) g[m++] = o;
        }
        if (m) n = m;
    }
    if (!n) bk_tr_recv_origin(c, r, &g[n++]);
    return n;
}

/* A texel with a footprint takes its punctual light over a TP_PUNCT_GRID² grid of its footprint's
 * box. Four quarter centres put a hard shadow edge anywhere in a quarter at that quarter's value,
 * and miss an edge that cuts a corner: across a sun's diagonal edge they left the texels 0.084 of
 * the sun off (RMS; 0.024 with the grid, tests/bake/test_shadow_edges.c). A sliver (a chart's
 * corner in the texel) holds no quarter centre at all, and read its own point, lit where the
 * sliver is in shadow: a doorway jamb's texel stored 13.7 lux against 7.3 traced by the path check
 * (the light-set level of bench/diff_reseed.py), overlap_01's block on a block read 24 % off
 * against Cycles. Punctual light is noise-free and computed once, so the 16 points cost 16 shadow
 * rays per light and texel, once. */
#define TP_PUNCT_GRID 4

/* The punctual light of a texel with a footprint over the TP_PUNCT_GRID² grid of its footprint's
 * box (points off the footprint or beyond another surface left out); 0 when none is left. */
static int punctual_grid(const tp_ctx *c, const bk_receiver *r, double e[3], double sh[3][9], uint64_t *rays)
{
    const float *bx = r->footprint_box;
    const int box = bx[2] > 0 && bx[3] > 0;
    int n = 0;
    for (int q = 0; q < TP_PUNCT_GRID * TP_PUNCT_GRID; q++) {
        double s = (q % TP_PUNCT_GRID + 0.5) / TP_PUNCT_GRID, t = (q / TP_PUNCT_GRID + 0.5) / TP_PUNCT_GRID;
        if (box) s = bx[0] + s * bx[2], t = bx[1] + t * bx[3];
        tp_origin g;
        if (footprint_at(c, r, s, t, &g) <= 0) continue; /* beyond another surface, or off the footprint */
        *rays += punctual_at(c, &g, NULL, NULL, 0, 1, e, sh);
        n++;
    }
    return n;
}

/* The exact punctual light of receiver i (every light, no culling): the mean over its footprint's
 * grid, or where it has none (a probe, a texel without a footprint) over its punctual points. */
static uint64_t punctual_exact(const tp_ctx *c, const bk_receiver *r, double e[3], double sh[3][9])
{
    uint64_t rays = 0;
    int n = r->footprint_count ? punctual_grid(c, r, e, sh, &rays) : 0;
    if (!n) { /* (a grid of no points added nothing) */
        tp_origin g[4];
        n = bk_tr_punctual_points(c, r, g);
        for (int q = 0; q < n; q++) rays += punctual_at(c, &g[q], NULL, NULL, 0, 1, e, sh);
    }
    for (int a = 0; a < 3; a++) {
        e[a] /= n;
        for (int kk = 0; kk < 9; kk++) sh[a][kk] /= n;
    }
    return rays;
}

void bk_tr_recv_punctual(tp_ctx *c, size_t begin, size_t end, int thread)
{
    /* Without culling, punctual light is noise-free: computed once, then into the outputs /
     * error scalars. */
    uint64_t rays = 0;
    for (size_t i = begin; i < end; i++) {
        const bk_receiver *r = &c->recv[i];
        double e[3] = {0, 0, 0}, sh[3][9];
        memset(sh, 0, sizeof sh);
        rays += punctual_exact(c, r, e, sh);
        if (c->punct_lum) {
            c->punct_lum[i] = (float)bk_lum(e);
            continue;
        }
        const bk_transport_output *out = c->out;
        for (int a = 0; a < 3; a++) {
            for (int kk = 0; kk < 9; kk++) {
                out->radiance[i].c[a][kk] += (float)sh[a][kk];
                if (out->direct) out->direct[i].c[a][kk] += (float)sh[a][kk];
            }
            if (out->irradiance) out->irradiance[3 * i + a] += (float)e[a];
        }
    }
    c->thread_rays[thread] += rays;
    c->thread_shadow[thread] += rays;
}

/* One sample of a receiver's estimate: radiance L (direct part Ld) from unit direction d with
 * cosine factor cs (1 for probes) into the irradiance and the SH projections. */
static void accumulate(const double d[3], double cs, const double L[3], const double Ld[3], double e[3],
                       double sh_t[3][9], double sh_d[3][9])
{
    double y[9];
    bk_sh9_basis_d(d, y);
    int has_d = Ld[0] != 0 || Ld[1] != 0 || Ld[2] != 0;
    for (int a = 0; a < 3; a++) {
        e[a] += L[a] * cs;
        for (int kk = 0; kk < 9; kk++) sh_t[a][kk] += L[a] * y[kk];
        if (has_d)
            for (int kk = 0; kk < 9; kk++) sh_d[a][kk] += Ld[a] * y[kk];
    }
}

/* ---- final gather ---------------------------------------------------------------------------- */

/* A receiver's sums over one half of one pass. */
typedef struct tp_recv_sums {
    double e[3];          /* Σ L·cos (irradiance, before × solid/S) */
    double eb[3];         /* Σ (continuation − cell)·cos over the probed rays, × TP_PROBE_EVERY */
    double sh_t[3][9], sh_d[3][9];
} tp_recv_sums;

/* The cache's bias probe: every TP_PROBE_EVERY-th gather ray that reads a cell (a far hit) is
 * also continued at its exact hit point; the mean difference (continuation − cell), scaled
 * back up, estimates what the cells' constancy adds to the receiver: the first-hit cache bias,
 * which the two halves cannot see (both read equally coarse cells). Costs 1/16 more rays. */
#define TP_PROBE_EVERY 16

/* Radiance L (direct part Ld) that gather ray d (pdf 1/solid) brings back from `hit`. Returns
 * the cell it read (a far hit), else -1. */
static long gather_hit(tp_ctx *c, const float *sum, const uint8_t *rough, const bk_hit *hit, const double d[3],
                       double solid, int vpl, bk_rng *cont, tp_count *cnt, double L[3], double Ld[3])
{
    for (int a = 0; a < 3; a++) L[a] = Ld[a] = 0;
    if (hit->tri == UINT32_MAX) {
        bk_tr_sky_radiance(c, d, L);
        memcpy(Ld, L, 3 * sizeof(double));
        return -1;
    }
    long hc = bk_tr_hit_cell(c, hit);
    if (hc < 0) return -1; /* black, or the inside of a solid: a receiver there is dark */
    bk_tr_emission_at(c, hit->tri, hit->u, hit->v, Ld);
    if (Ld[0] > 0 || Ld[1] > 0 || Ld[2] > 0) {
        double wg = bk_tr_mis_gather(c, hit, hc, d, 1 / solid);
        for (int a = 0; a < 3; a++) Ld[a] *= wg;
    }
    double r[3];
    int near = bk_tr_near_hit(c, hit, hc, rough);
    if (near) {
        const tp_near_mode md = {sum, rough, 1, TP_NEAR_DEPTH, vpl, NULL, 0, 0};
        bk_tr_near_entry(c, &md, hit, hc, d, cont, cnt, r);
    } else {
        for (int a = 0; a < 3; a++) r[a] = sum[3 * hc + a];
    }
    for (int a = 0; a < 3; a++) L[a] = r[a] + Ld[a];
    return near ? -1 : hc;
}

static void oct_add(const tp_ctx *c, double (*oct)[3], const double d[3], const double L[3])
{
    for (int t = 0; t < 16; t++) {
        const double cs = d[0] * c->oct_dir[t][0] + d[1] * c->oct_dir[t][1] + d[2] * c->oct_dir[t][2];
        if (cs > 0)
            for (int a = 0; a < 3; a++) oct[t][a] += L[a] * cs;
    }
}

/* The ray-length limit (options.gather_limit): the probes' radiance at o + lim·d towards d; 0
 * where they do not cover that point (outside the probe volume: the ray goes on). */
static int far_lookup(const tp_ctx *c, const float o[3], const double d[3], double lim, uint32_t *hint, double L[3])
{
    const double x[3] = {o[0] + lim * d[0], o[1] + lim * d[1], o[2] + lim * d[2]};
    return c->opt->far_radiance(c->opt->far_user, x, d, hint, L);
}

/* A limited ray whose end the probes do not cover: traced on from there; *hit gets the result
 * with its distance from the original origin. */
static void far_continue(const tp_ctx *c, const float o[3], const double d[3], double lim, bk_hit *hit, tp_count *cnt)
{
    const float x[3] = {(float)(o[0] + lim * d[0]), (float)(o[1] + lim * d[1]), (float)(o[2] + lim * d[2])};
    const float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
    cnt->rays++;
    if (bk_tracer_intersect(c->tracer, x, df, 0.0f, INFINITY, hit)) hit->t += (float)lim;
    else hit->tri = UINT32_MAX;
}

/* One half of receiver i in this pass: S directions from the shifted lattice, uniform over the
 * hemisphere (texels) or the sphere (probes) — the SH projection needs a pdf that does not
 * vanish at the horizon — each with one light sample when NEE is on. A texel with a footprint
 * starts each ray from its own random point of the footprint. */
/* oct: NULL, or the 16 octahedral texels' Σ L·max(0, cos) (an octahedral probe). */
static void recv_half(tp_ctx *c, const bk_receiver *r, size_t i, int h, int S, const tp_lattice *lat,
                      tp_recv_sums *rs, double (*oct)[3], tp_count *cnt)
{
    const float *sum = c->l_sum[h];
    bk_rng rng = bk_tr_rng(c->seed, DOM_RECV, (uint64_t)h, (uint64_t)c->pass, 0, i);
    bk_rng cont = bk_tr_rng(c->seed, DOM_RECV_NEAR, (uint64_t)h, (uint64_t)c->pass, 0, i);
    bk_rng pos = bk_tr_rng(c->seed, DOM_RECV_POS, (uint64_t)h, (uint64_t)c->pass, 0, i);
    bk_rng probe = bk_tr_rng(c->seed, DOM_RECV_PROBE, (uint64_t)h, (uint64_t)c->pass, 0, i);
    double s1 = bk_rng_next(&rng), s2 = bk_rng_next(&rng);
    tp_shift shift = bk_tr_lattice_shift(s1, s2);
    tp_origin g0;
    bk_tr_recv_origin(c, r, &g0);
    const int sphere = g0.sphere;
    const double solid = sphere ? 4 * TP_PI : 2 * TP_PI;
    const int pg_kind = sphere ? PG_SPHERE : PG_HEMISPHERE;
    double t1 = 0, t2 = 0;
    if (c->nee) {
        bk_rng nr = bk_tr_rng(c->seed, DOM_RECV_NEE, (uint64_t)h, (uint64_t)c->pass, 0, i);
        t1 = bk_rng_next(&nr);
        t2 = bk_rng_next(&nr);
    }
    double t0[3], b0[3];
    bk_onb(g0.n, t0, b0);
    /* the ray-length limit (options.gather_limit): surface receivers' rays end at lim and read
     * the probes there */
    const bk_transport_options *o = c->opt;
    const double lim = !sphere && o->gather_limit > 0 && o->far_radiance ? o->gather_limit : INFINITY;
    uint32_t far_hint = 0;
    float tmax[TP_BATCH];
    for (int jj = 0; jj < TP_BATCH; jj++) tmax[jj] = (float)lim;
    for (int j0 = 0; j0 < S; j0 += TP_BATCH) {
        const int m = S - j0 < TP_BATCH ? S - j0 : TP_BATCH;
        float org[3 * TP_BATCH], dir[3 * TP_BATCH];
        double dd[TP_BATCH][3], zz[TP_BATCH], nn[TP_BATCH][3];
        bk_hit hits[TP_BATCH];
        for (int jj = 0; jj < m; jj++) {
            tp_origin g = g0;
            double t[3] = {t0[0], t0[1], t0[2]}, b[3] = {b0[0], b0[1], b0[2]};
            if (r->footprint_count) {
                bk_tr_footprint_sample(c, r, &pos, &g);
                bk_onb(g.n, t, b);
            }
            double u1, cp, sp;
            bk_tr_lattice(lat, (uint32_t)(j0 + jj), &shift, &u1, &cp, &sp);
            double z = sphere ? 1 - 2 * u1 : u1;
            double rr = sqrt(fmax(0.0, 1 - z * z));
            zz[jj] = z;
            for (int a = 0; a < 3; a++) {
                dd[jj][a] = rr * cp * t[a] + rr * sp * b[a] + z * g.n[a];
                dir[3 * jj + a] = (float)dd[jj][a];
                org[3 * jj + a] = g.o[a];
                nn[jj][a] = g.n[a];
            }
        }
        bk_tracer_intersect_n(c->tracer, (size_t)m, org, dir, 0.0f, isfinite(lim) ? tmax : NULL, hits);
        cnt->rays += (uint64_t)m;
        for (int jj = 0; jj < m; jj++) {
            double L[3], Ld[3];
            long hc = -1;
            if (isfinite(lim) && hits[jj].tri == UINT32_MAX && far_lookup(c, org + 3 * jj, dd[jj], lim, &far_hint, L)) {
                Ld[0] = Ld[1] = Ld[2] = 0; /* no hit within lim: the probes' light, as indirect */
            } else {
                if (isfinite(lim) && hits[jj].tri == UINT32_MAX) far_continue(c, org + 3 * jj, dd[jj], lim, &hits[jj], cnt);
                hc = gather_hit(c, sum, c->rough, &hits[jj], dd[jj], solid, c->vpl && !sphere, &cont, cnt, L, Ld);
            }
            if (!bk_finite3(L) || !bk_finite3(Ld)) cnt->bad++;
            else {
                accumulate(dd[jj], sphere ? 1 : zz[jj], L, Ld, rs->e, rs->sh_t, rs->sh_d);
                if (oct) oct_add(c, oct, dd[jj], L);
            }
            if (hc >= 0 && (j0 + jj) % TP_PROBE_EVERY == 0) {
                double q[3];
                const tp_near_mode md = {sum, c->rough, 1, TP_NEAR_DEPTH, c->vpl && !sphere, NULL, 0, 0};
                bk_tr_near_radiance(c, &md, &hits[jj], hc, dd[jj], 0, &probe, cnt, q);
                double cs = (sphere ? 1 : zz[jj]) * TP_PROBE_EVERY;
                if (bk_finite3(q))
                    for (int a = 0; a < 3; a++) rs->eb[a] += (q[a] - sum[3 * hc + a]) * cs;
            }
            if (!c->nee) continue;
            /* one light sample per gather ray; its value Le·w/p is turned into the gather's
             * units (radiance, later × solid/S) by 1/solid */
            double u0, uu1, ld[3], cl, val[3];
            bk_tr_lattice_uv(lat, (uint32_t)(j0 + jj), t1, t2, &u0, &uu1);
            double ndist = 0, skip[3];
            if (bk_tr_nee_sample_lobe(c, org + 3 * jj, nn[jj], pg_kind, NULL, u0, uu1, &ndist, ld, &cl, val,
                                      &cnt->shadow) &&
                !(ndist > lim && far_lookup(c, org + 3 * jj, ld, lim, &far_hint, skip))) {
                for (int a = 0; a < 3; a++) val[a] /= solid;
                if (!bk_finite3(val)) cnt->bad++;
                else {
                    accumulate(ld, cl, val, val, rs->e, rs->sh_t, rs->sh_d);
                    if (oct) oct_add(c, oct, ld, val);
                }
            }
        }
    }
}

/* The culled punctual light of receiver i in half h of this pass: one draw (the half's ξ, δ of
 * the pass) at the receiver's punctual points; an unbiased estimate of their mean (bk_tr_recv_punctual,
 * exact, takes a finer grid: a level with culling's many lights has few hard edges one light
 * alone casts). */
static uint64_t recv_slc(tp_ctx *c, const bk_receiver *r, size_t i, int h, tp_tile_lists *t, double e[3],
                         double sh[3][9], uint64_t *tested)
{
    const bk_slc_draw *d = c->draw_recv[h];
    if (t->tile[h] != i / BK_SLC_TILE) {
        t->n[h] = bk_slc_tile_lights(d, i, t->ids[h]);
        t->tile[h] = i / BK_SLC_TILE;
    }
    const double delta = ldexp(c->slc_delta, -(c->pass < 60 ? c->pass : 60));
    tp_origin g[4];
    const int points = bk_tr_punctual_points(c, r, g);
    uint64_t rays = 0;
    for (int q = 0; q < points; q++) rays += punctual_at(c, &g[q], d, t->ids[h], t->n[h], delta, e, sh);
    *tested += (uint64_t)points * t->n[h];
    for (int a = 0; a < 3; a++) {
        e[a] /= points;
        for (int kk = 0; kk < 9; kk++) sh[a][kk] /= points;
    }
    return rays;
}

/* The glossy VPLs of half h at surface receiver i: the half's draw at one of the receiver's
 * punctual points (a texel with a footprint: one of its four quarter centres, uniformly at random
 * per half and pass, an unbiased estimate of their average at a quarter of the work; the VPLs
 * were most of the gather's CPU at four), irradiance into e and the SH of the incident radiance
 * into sh (indirect light: not in `direct`). An unbiased estimate of the light that punctual
 * lights send to the receiver over one specular bounce (VPL.md). Returns shadow rays. */
static uint64_t recv_vpl(tp_ctx *c, const bk_receiver *r, size_t i, int h, tp_tile_lists *t, double e[3],
                         double sh[3][9], uint64_t *tested)
{
    const bk_vpl_draw *d = c->vpl_draw[h];
    if (!d) return 0;
    if (t->tile[h] != i / BK_SLC_TILE) {
        t->n[h] = bk_vpl_tile_list(d, i, t->ids[h]);
        t->tile[h] = i / BK_SLC_TILE;
    }
    const double delta = bk_vpl_draw_delta(d);
    tp_origin g[4];
    const int points = bk_tr_punctual_points(c, r, g);
    bk_rng pr = bk_tr_rng(c->seed, DOM_VPL_POINT, (uint64_t)h, (uint64_t)c->pass, 0, i);
    const int q = points > 1 ? (int)(bk_rng_next(&pr) * points) % points : 0;
    bk_vpl_point pt;
    for (int a = 0; a < 3; a++) pt.p[a] = g[q].p[a], pt.n[a] = g[q].n[a], pt.org[a] = g[q].o[a];
    uint64_t rays = 0;
    for (size_t k = 0; k < t->n[h]; k++) {
        const uint32_t vi = t->ids[h][k];
        double rgb[3], to[3];
        int acc, ray;
        const int hit = bk_vpl_eval(&c->vpls[h][vi], bk_vpl_draw_xi(d, vi), delta, c->tracer, &pt, rgb, to, &acc, &ray);
        rays += (uint64_t)ray;
        if (!hit || !bk_finite3(rgb)) continue;
        const double cs = to[0] * g[q].n[0] + to[1] * g[q].n[1] + to[2] * g[q].n[2];
        if (!(cs > 0)) continue;
        double y[9];
        bk_sh9_basis_d(to, y);
        for (int a = 0; a < 3; a++) {
            e[a] += rgb[a] * cs;
            for (int kk = 0; kk < 9; kk++) sh[a][kk] += rgb[a] * y[kk];
        }
    }
    *tested += t->n[h];
    return rays;
}

void bk_tr_recv_gather(tp_ctx *c, size_t begin, size_t end, int thread)
{
    const int S = c->rays;
    const double w = c->pass_weight;
    const bk_transport_output *out = c->out;
    tp_count cnt = {0, 0, 0};
    tp_tile_lists lists;
    bk_tr_slc_lists_init(c, thread, &lists);
    tp_tile_lists vlists;
    bk_tr_vpl_lists_init(c, thread, &vlists);
    uint64_t tested = 0, vtested = 0;
    for (size_t i = begin; i < end; i++) {
        if (!c->blk_on[bk_tr_block_of(c, i)]) continue; /* converged (adaptive sampling) */
        const bk_receiver *r = &c->recv[i];
        const int sphere = !(r->normal[0] != 0 || r->normal[1] != 0 || r->normal[2] != 0);
        const double solid = sphere ? 4 * TP_PI : 2 * TP_PI;
        tp_recv_sums tot;
        memset(&tot, 0, sizeof tot);
        double psh_tot[3][9], vsh_tot[3][9];
        memset(psh_tot, 0, sizeof psh_tot);
        memset(vsh_tot, 0, sizeof vsh_tot);
        for (int h = 0; h < 2; h++) {
            tp_recv_sums rs;
            memset(&rs, 0, sizeof rs);
            recv_half(c, r, i, h, S, &c->lat, &rs, NULL, &cnt);
            double pe[3] = {0, 0, 0}, psh[3][9];
            memset(psh, 0, sizeof psh);
            if (c->slc) cnt.shadow += recv_slc(c, r, i, h, &lists, pe, psh, &tested);
            double ve[3] = {0, 0, 0}, vsh[3][9];
            memset(vsh, 0, sizeof vsh);
            if (c->vpl && !sphere) cnt.shadow += recv_vpl(c, r, i, h, &vlists, ve, vsh, &vtested);
            double e[3], eb[3];
            for (int a = 0; a < 3; a++) {
                e[a] = rs.e[a] * solid / S + pe[a] + ve[a];
                eb[a] = rs.eb[a] * solid / S;
                for (int kk = 0; kk < 9; kk++) psh_tot[a][kk] += psh[a][kk], vsh_tot[a][kk] += vsh[a][kk];
            }
            /* error scalar: irradiance for texels, fluence/4 for probes (equal under uniform
             * radiance, so texels and probes weigh alike in the relative RMSE) */
            c->x_acc[h][i] += w * (bk_lum(e) + c->punct_lum[i]) * (sphere ? 0.25 : 1.0);
            c->b_acc[h][i] += w * bk_lum(eb) * (sphere ? 0.25 : 1.0);
            for (int a = 0; a < 3; a++) {
                tot.e[a] += e[a];
                for (int kk = 0; kk < 9; kk++) {
                    tot.sh_t[a][kk] += rs.sh_t[a][kk];
                    tot.sh_d[a][kk] += rs.sh_d[a][kk];
                }
            }
        }
        /* both halves: 2S samples of pdf 1/solid; weight w for this pass */
        const double ws = w * solid / (2.0 * S);
        for (int a = 0; a < 3; a++) {
            for (int kk = 0; kk < 9; kk++) {
                out->radiance[i].c[a][kk] += (float)(tot.sh_t[a][kk] * ws);
                if (out->direct) out->direct[i].c[a][kk] += (float)(tot.sh_d[a][kk] * ws);
            }
            if (out->irradiance) out->irradiance[3 * i + a] += (float)(tot.e[a] * w * 0.5);
        }
        if (c->slc) /* culled punctual light: both halves' draws, weight w */
            for (int a = 0; a < 3; a++) {
                for (int kk = 0; kk < 9; kk++) {
                    out->radiance[i].c[a][kk] += (float)(psh_tot[a][kk] * w * 0.5);
                    if (out->direct) out->direct[i].c[a][kk] += (float)(psh_tot[a][kk] * w * 0.5);
                }
            } /* (the irradiance has it already: e above, in tot.e) */
        if (c->vpl && !sphere) /* glossy VPLs: both halves' draws, weight w; indirect light */
            for (int a = 0; a < 3; a++)
                for (int kk = 0; kk < 9; kk++) out->radiance[i].c[a][kk] += (float)(vsh_tot[a][kk] * w * 0.5);
    }
    c->thread_slc_tested[thread] += tested;
    c->thread_vpl_tested[thread] += vtested;
    c->thread_rays[thread] += cnt.rays + cnt.shadow;
    c->thread_shadow[thread] += cnt.shadow;
    c->thread_nonfinite[thread] += cnt.bad;
}

/* Octahedral probe k: both halves of this pass, oct_rays each, on its own random streams (item
 * recv_count + k); the texels' irradiance E_t = 4π/S·Σ L·max(0, n_t·d). */
void bk_tr_octa_gather(tp_ctx *c, size_t begin, size_t end, int thread)
{
    const int S = c->oct_rays;
    const double w = c->pass_weight;
    tp_count cnt = {0, 0, 0};
    for (size_t k = begin; k < end; k++) {
        bk_receiver r;
        memset(&r, 0, sizeof r);
        memcpy(r.position, &c->opt->octa_points[3 * k], sizeof r.position);
        double both[16][3];
        memset(both, 0, sizeof both);
        for (int h = 0; h < 2; h++) {
            tp_recv_sums rs;
            double oct[16][3];
            memset(&rs, 0, sizeof rs);
            memset(oct, 0, sizeof oct);
            recv_half(c, &r, c->recv_count + k, h, S, &c->oct_lat, &rs, oct, &cnt);
            for (int t = 0; t < 16; t++) {
                double e[3];
                for (int a = 0; a < 3; a++) {
                    e[a] = oct[t][a] * 4 * TP_PI / S;
                    both[t][a] += 0.5 * e[a];
                }
                c->oct_acc[h][16 * k + (size_t)t] += w * bk_lum(e);
            }
        }
        for (int t = 0; t < 16; t++)
            for (int a = 0; a < 3; a++) c->out->octa_irradiance[(16 * k + (size_t)t) * 3 + (size_t)a] += (float)(w * both[t][a]);
    }
    c->thread_rays[thread] += cnt.rays + cnt.shadow;
    c->thread_shadow[thread] += cnt.shadow;
    c->thread_nonfinite[thread] += cnt.bad;
}

/* After the passes: the weighted mean, punctual light (noise-free, one shadow ray per light),
 * and the texels' relative RMSE from the two halves (as TRANSPORT.md's estimate, over every
 * texel of every octahedral probe). */
double bk_tr_octa_finish(tp_ctx *c)
{
    float *out = c->out->octa_irradiance;
    const float inv = (float)(1.0 / c->oct_weight);
    double num = 0, den = 0;
    for (size_t k = 0; k < c->oct_count; k++) {
        tp_origin g;
        bk_tr_origin_from(c, &c->opt->octa_points[3 * k], (const float[3]){0, 0, 0}, &g);
        double pe[16][3];
        memset(pe, 0, sizeof pe);
        for (size_t li = 0; li < c->light_count; li++) {
            double val[3], ld[3], dist;
            if (!bk_light_eval(c->lights[li], g.p, val, ld, &dist)) continue;
            if (!bk_light_visible(c->tracer, g.o, ld, dist)) continue;
            oct_add(c, pe, ld, val);
        }
        for (int t = 0; t < 16; t++) {
            float *e = &out[(16 * k + (size_t)t) * 3];
            for (int a = 0; a < 3; a++) e[a] = e[a] * inv + (float)pe[t][a];
            const double A = c->oct_acc[0][16 * k + (size_t)t] / c->oct_weight, B = c->oct_acc[1][16 * k + (size_t)t] / c->oct_weight;
            const double m = 0.5 * (A + B) + bk_lum(pe[t]);
            num += 0.25 * (A - B) * (A - B);
            den += m * m;
        }
    }
    return den > 0 ? sqrt(num / den) : 0;
}
