/* Emitters: the light-sampling distribution over emissive sub-triangles, next-event estimation
 * and its MIS weights against the gathers (TRANSPORT.md). */
#include "bake/transport/transport_impl.h"

/* ---- emitters: next-event estimation and its MIS weights ------------------------------------ */

/* Emitted radiance of triangle `tri` at barycentrics (u, v): the factor times the emission
 * texture at the point's uv0, for both strategies alike (gather hits and light samples must
 * see the same emitter or MIS would be biased). */
void bk_tr_emission_at(const tp_ctx *c, uint32_t tri, double u, double v, double out[3])
{
    const float *f = c->tri_le + 3 * (size_t)tri;
    if (f[0] == 0 && f[1] == 0 && f[2] == 0) { out[0] = out[1] = out[2] = 0; return; }
    int32_t tex = c->tri_le_tex[tri];
    if (tex < 0) {
        for (int k = 0; k < 3; k++) out[k] = f[k];
        return;
    }
    double uv[2], te[3];
    bk_tri_uv0(c->scene, tri, u, v, uv);
    bk_sample_image(bk_scene_image(c->scene, tex), uv[0], uv[1], te);
    for (int k = 0; k < 3; k++) {
        double em = f[k] * te[k];
        out[k] = isfinite(em) && em > 0 ? em : 0;
    }
}

static double gather_pdf(int kind, double cos_p)
{
    return kind == PG_COSINE ? cos_p / TP_PI : kind == PG_HEMISPHERE ? 1 / (2 * TP_PI) : 1 / (4 * TP_PI);
}

/* Power heuristic (β = 2), one sample of each strategy per gather ray. */
static double mis_power(double mine, double other)
{
    double a = mine * mine, b = other * other;
    return a + b > 0 ? a / (a + b) : 0;
}

/* MIS weight of a gather ray (unit direction d, gather pdf pg) that hit cell hc at distance t:
 * the light-sampling pdf of that point in solid angle is p_area·t²/|cos θ_light|. */
double bk_tr_mis_gather(const tp_ctx *c, const bk_hit *h, long hc, const double d[3], double pg)
{
    if (!c->nee) return 1;
    double pa = c->cells[hc].nee_parea;
    if (!(pa > 0)) return 1;
    double cl = fabs(d[0] * h->ng[0] + d[1] * h->ng[1] + d[2] * h->ng[2]);
    if (!(cl > 0)) return 1;
    double t = h->t, pl = pa * t * t / cl;
    return mis_power(pg, pl);
}

/* The emitter whose CDF interval holds u, and u's relative position inside it (which then
 * places the point, so stratified u stay stratified over the emitter's area). */
static size_t em_pick(const tp_ctx *c, double u, double *rem)
{
    size_t lo = 0, hi = c->em_count - 1;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (c->em_cdf[mid] > u) hi = mid;
        else lo = mid + 1;
    }
    double a = lo ? c->em_cdf[lo - 1] : 0, b = c->em_cdf[lo];
    double r = b > a ? (u - a) / (b - a) : 0.5;
    *rem = r < 0 ? 0 : r > 0.9999999999999999 ? 0.9999999999999999 : r;
    return lo;
}

/* One light sample for origin o (unit normal n; ignored for PG_SPHERE) from (u0, u1) in
 * [0,1)²: picks an emitter sub-triangle by power, a uniform point on it, and traces a shadow
 * ray. Returns 1 and fills the unit direction d, cos_p = d·n and val = Le·w_L/p_L (radiance
 * over its solid-angle pdf, MIS-weighted) when the sample carries light. */
int bk_tr_nee_sample(const tp_ctx *c, const float o[3], const double n[3], int kind, double u0, double u1,
                     double d[3], double *cos_p, double val[3], uint64_t *shadow)
{
    return bk_tr_nee_sample_lobe(c, o, n, kind, NULL, u0, u1, NULL, d, cos_p, val, shadow);
}

/* bk_tr_nee_sample weighed against the lobe lf's density instead of the gather pdf (lf NULL: that);
 * dist_out (or NULL): the distance to the emitter point of a sample it returns. */
int bk_tr_nee_sample_lobe(const tp_ctx *c, const float o[3], const double n[3], int kind, const tp_lobe *lf,
                          double u0, double u1, double *dist_out, double d[3], double *cos_p, double val[3],
                          uint64_t *shadow)
{
    double rem;
    const tp_emitter *em = &c->em[em_pick(c, u0, &rem)];
    const tp_cell *cell = &c->cells[em->cell];
    tp_cell_geom g;
    bk_tr_cell_geom(c, cell, &g);
    double x[3], bu, bv;
    bk_tr_cell_point_at(&g, rem, u1, x, &bu, &bv);
    double dv[3] = {x[0] - o[0], x[1] - o[1], x[2] - o[2]};
    double dist2 = dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2];
    if (!(dist2 > 0) || !isfinite(dist2)) return 0;
    double dist = sqrt(dist2);
    if (dist_out) *dist_out = dist;
    for (int a = 0; a < 3; a++) d[a] = dv[a] / dist;
    double cp = kind == PG_SPHERE ? 1 : d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
    if (!(cp > 0)) return 0;
    float ng[3];
    bk_tracer_tri_normal(c->tracer, em->tri, ng);
    double cl = -(d[0] * ng[0] + d[1] * ng[1] + d[2] * ng[2]);
    int side = cl > 0 ? 0 : 1; /* the side facing the origin */
    if (side >= c->tri_sides[em->tri]) return 0;
    cl = fabs(cl);
    if (!(cl > 1e-12)) return 0;
    double le[3];
    bk_tr_emission_at(c, em->tri, bu, bv, le);
    if (le[0] <= 0 && le[1] <= 0 && le[2] <= 0) return 0;
    double pl = cell->nee_parea * dist2 / cl;
    if (!(pl > 0) || !isfinite(pl)) return 0;
    double pg;
    if (lf) {
        double l[3];
        bk_tr_to_local(lf, d, l);
        pg = bk_mr_lobe_pdf(&lf->lb, l);
    } else {
        pg = gather_pdf(kind, cp);
    }
    double w = mis_power(pl, pg);
    /* shadow ray to the point moved off the emitter toward the origin, stopped just short */
    float xf[3] = {(float)x[0], (float)x[1], (float)x[2]}, xo[3];
    float ns[3] = {side ? -ng[0] : ng[0], side ? -ng[1] : ng[1], side ? -ng[2] : ng[2]};
    bk_offset_ray_origin_scaled(xf, ns, bk_tracer_tri_scale(c->tracer, em->tri), xo);
    float sd[3] = {xo[0] - o[0], xo[1] - o[1], xo[2] - o[2]};
    (*shadow)++;
    if (bk_tracer_occluded(c->tracer, o, sd, 0.0f, 1.0f - 1e-5f)) return 0;
    *cos_p = cp;
    for (int a = 0; a < 3; a++) val[a] = le[a] * w / pl;
    return 1;
}

/* The light-sampling distribution: every emitting sub-triangle with probability proportional
 * to its power area·bk_lum(Le) (Le at its centroid, as the cells carry it), a point uniform on it.
 * A point's density per unit area is then bk_lum(Le_cell)/P_total, stored in both side cells so a
 * gather hit can weigh itself against it. */
lbk_result bk_tr_build_emitters(tp_ctx *c)
{
    const bk_transport_options *opt = c->opt;
    c->nee = 0;
    if (opt->nee < 0) return LBK_OK;
    size_t n = 0;
    double power = 0, em_area = 0, total_area = 0;
    for (size_t i = 0; i < c->scene->tri_count; i++) total_area += bk_tracer_tri_area(c->tracer, (uint32_t)i);
    for (size_t ci = 0; ci < c->cell_count; ci++) {
        const tp_cell *cell = &c->cells[ci];
        if (cell->side != 0 || !(cell->area > 0)) continue;
        double le[3] = {cell->le[0], cell->le[1], cell->le[2]};
        double p = cell->area * bk_lum(le);
        if (!(p > 0) || !isfinite(p)) continue;
        n++;
        power += p;
        em_area += cell->area;
    }
    if (n == 0 || !(power > 0) || !isfinite(power)) return LBK_OK;
    /* auto: emitters covering half the surface are hit by gather rays about as often as light
     * samples would find them; gathering alone keeps the furnace exact (TRANSPORT.md) */
    if (opt->nee == 0 && em_area >= 0.5 * total_area) return LBK_OK;
    c->em = malloc(n * sizeof *c->em);
    c->em_cdf = malloc(n * sizeof *c->em_cdf);
    if (!c->em || !c->em_cdf) return LBK_ERR_OUT_OF_MEMORY;
    double run = 0;
    size_t k = 0;
    for (size_t ci = 0; ci < c->cell_count; ci++) {
        tp_cell *cell = &c->cells[ci];
        if (cell->side != 0 || !(cell->area > 0)) continue;
        double le[3] = {cell->le[0], cell->le[1], cell->le[2]};
        double p = cell->area * bk_lum(le);
        if (!(p > 0) || !isfinite(p)) continue;
        run += p;
        c->em[k].tri = cell->tri;
        c->em[k].cell = (uint32_t)ci;
        c->em_cdf[k] = run / power;
        float pa = (float)(bk_lum(le) / power);
        cell->nee_parea = pa;
        if (c->tri_sides[cell->tri] > 1) c->cells[ci + (size_t)cell->m * cell->m].nee_parea = pa;
        k++;
    }
    c->em_cdf[n - 1] = 1.0;
    c->em_count = n;
    c->nee = 1;
    return LBK_OK;
}
