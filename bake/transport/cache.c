/* The radiance cache: one bounce for a range of cells, the chain of bounces with its tail, and
 * the rough and gap cells whose hits are continued (TRANSPORT.md). */
#include "bake/transport/transport_impl.h"

/* ---- cache: one bounce for a range of cells ------------------------------------------------ */

/* Random point in a cell, kept off the triangle's edges. */
static void cell_point(const tp_cell_geom *g, bk_rng *r, double p[3])
{
    double r1 = bk_rng_next(r), r2 = bk_rng_next(r);
    bk_tr_cell_point_at(g, r1, r2, p, NULL, NULL);
}

/* One cell's sample sums for one bounce: gathered radiance, light samples and punctual light,
 * over the samples whose point can be seen (a sample whose gather ray reaches the inside of a
 * closed solid started inside it: it belongs to no visible part of the cell and is dropped, so
 * a cell that a wall cuts stands for its visible part only). */
typedef struct tp_cell_sums {
    double e[3], en[3], ep[3];
    int valid, lit_points;
    const uint32_t *ids; /* with culling: the cell's tile list of this chain's draw */
    size_t nids;
} tp_cell_sums;

/* One punctual light at cell point p (offset origin o), weighted by the draw d (NULL: 1). */
static void cell_light(const tp_ctx *c, size_t li, const double p[3], const float o[3], const double n[3],
                       const bk_slc_draw *d, double delta, tp_cell_sums *cs, tp_count *cnt)
{
    double val[3], ld[3], dist;
    if (!bk_light_eval(c->lights[li], p, val, ld, &dist)) return;
    double w = d ? bk_slc_weight(bk_lum(val), delta, bk_slc_draw_xi(d, (uint32_t)li)) : 1.0;
    if (w == 0) return;
    double cq = ld[0] * n[0] + ld[1] * n[1] + ld[2] * n[2];
    if (cq <= 0) return;
    cnt->shadow++;
    if (!bk_light_visible(c->tracer, o, ld, dist)) return;
    for (int a = 0; a < 3; a++) cs->ep[a] += val[a] * w * cq;
}

/* Shades sample j of a cell (point p, offset origin o, cosine direction d, hit) into the sums. */
static void cell_sample(tp_ctx *c, const double n[3], int j, const double p[3],
                        const float o[3], const double d[3], const bk_hit *hit, const double nee_t[2],
                        bk_rng *near_rng, tp_cell_sums *cs, tp_count *cnt)
{
    const int k = c->bounce, h = c->half;
    const float *prev = c->l_hist[h][0];
    double L[3] = {0, 0, 0};
    if (hit->tri != UINT32_MAX) {
        long hc = bk_tr_hit_cell(c, hit);
        if (hc == HIT_INSIDE) return;
        if (hc >= 0) {
            if (k == 1) {
                bk_tr_emission_at(c, hit->tri, hit->u, hit->v, L);
                if (L[0] > 0 || L[1] > 0 || L[2] > 0) {
                    double lz = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
                    double w = bk_tr_mis_gather(c, hit, hc, d, lz / TP_PI);
                    for (int a = 0; a < 3; a++) L[a] *= w;
                }
            } else if (bk_tr_near_hit(c, hit, hc, c->rough)) {
                /* bounce k−1 at the exact point (see bk_tr_near_radiance) */
                const tp_near_mode md = {NULL, NULL, 0, k - 1 < c->cache_depth ? k - 1 : c->cache_depth, 0,
                                         (const float *const *)c->l_hist[h], k, 0};
                bk_tr_near_entry(c, &md, hit, hc, d, near_rng, cnt, L);
            } else {
                for (int a = 0; a < 3; a++) L[a] = prev[3 * hc + a];
            }
        }
    } else if (k == 1) {
        bk_tr_sky_radiance(c, d, L);
    }
    cs->valid++;
    if (!bk_finite3(L)) cnt->bad++;
    else for (int a = 0; a < 3; a++) cs->e[a] += L[a];
    if (k != 1) return;
    if (c->nee) {
        double u0, v0, ld[3], cq, val[3];
        bk_tr_lattice_uv(&c->lat, (uint32_t)j, nee_t[0], nee_t[1], &u0, &v0);
        if (bk_tr_nee_sample(c, o, n, PG_COSINE, u0, v0, ld, &cq, val, &cnt->shadow)) {
            if (bk_finite3(val))
                for (int a = 0; a < 3; a++) cs->en[a] += val[a] * cq;
            else
                cnt->bad++;
        }
    }
    /* punctual lights at the first TP_LIGHT_POINTS visible points */
    if (c->light_count && cs->lit_points < TP_LIGHT_POINTS) {
        cs->lit_points++;
        if (!c->slc) {
            for (size_t li = 0; li < c->light_count; li++) cell_light(c, li, p, o, n, NULL, 1, cs, cnt);
            return;
        }
        const double delta = ldexp(c->slc_delta, -(c->pass < 60 ? c->pass : 60));
        const uint32_t *always;
        size_t na = bk_slc_always(c->slc_cell, &always);
        for (size_t q = 0; q < na; q++) cell_light(c, always[q], p, o, n, NULL, 1, cs, cnt);
        for (size_t q = 0; q < cs->nids; q++) cell_light(c, cs->ids[q], p, o, n, c->draw_cell, delta, cs, cnt);
    }
}

/* Bounce k at one cell: R points uniform over the cell, cosine directions from the shifted
 * lattice, traced 64 at a time; returns the reflected radiance albedo/π × irradiance. */
static void cell_bounce(tp_ctx *c, size_t ci, tp_tile_lists *lists, tp_count *cnt, double out[3])
{
    const int h = c->half, k = c->bounce, R = c->rays;
    const tp_cell *cell = &c->cells[ci];
    tp_cell_sums cs;
    memset(&cs, 0, sizeof cs);
    out[0] = out[1] = out[2] = 0;
    if (cell->n[0] == 0 && cell->n[1] == 0 && cell->n[2] == 0) return;
    if (cell->albedo[0] <= 0 && cell->albedo[1] <= 0 && cell->albedo[2] <= 0) return;
    bk_rng rng = bk_tr_rng(c->seed, DOM_CELL, (uint64_t)h, (uint64_t)c->pass, (uint64_t)k, ci);
    bk_rng near_rng = bk_tr_rng(c->seed, DOM_CELL_NEAR, (uint64_t)h, (uint64_t)c->pass, (uint64_t)k, ci);
    double n[3] = {cell->n[0], cell->n[1], cell->n[2]}, t[3], b[3];
    bk_onb(n, t, b);
    float nf[3] = {cell->n[0], cell->n[1], cell->n[2]};
    float scale = bk_tracer_tri_scale(c->tracer, cell->tri);
    double s1 = bk_rng_next(&rng), s2 = bk_rng_next(&rng);
    tp_shift shift = bk_tr_lattice_shift(s1, s2);
    tp_cell_geom geom;
    bk_tr_cell_geom(c, cell, &geom);
    if (k == 1 && c->slc) { /* the cell's tile list, cut once per tile (lists->*[0]) */
        if (lists->tile[0] != ci / BK_SLC_TILE) {
            lists->n[0] = bk_slc_tile_lights(c->draw_cell, ci, lists->ids[0]);
            lists->tile[0] = ci / BK_SLC_TILE;
        }
        cs.ids = lists->ids[0];
        cs.nids = lists->n[0];
    }
    double nee_t[2] = {0, 0}; /* the light samples' own lattice shift */
    if (k == 1 && c->nee) {
        bk_rng nr = bk_tr_rng(c->seed, DOM_CELL_NEE, (uint64_t)h, (uint64_t)c->pass, 0, ci);
        nee_t[0] = bk_rng_next(&nr);
        nee_t[1] = bk_rng_next(&nr);
    }
    for (int j0 = 0; j0 < R; j0 += TP_BATCH) {
        const int m = R - j0 < TP_BATCH ? R - j0 : TP_BATCH;
        float org[3 * TP_BATCH], dir[3 * TP_BATCH];
        double dd[TP_BATCH][3], pts[TP_BATCH][3];
        bk_hit hits[TP_BATCH];
        for (int jj = 0; jj < m; jj++) {
            double *p = pts[jj];
            cell_point(&geom, &rng, p);
            float pf[3] = {(float)p[0], (float)p[1], (float)p[2]};
            bk_offset_ray_origin_scaled(pf, nf, scale, org + 3 * jj);
            double u1, cp, sp;
            bk_tr_lattice(&c->lat, (uint32_t)(j0 + jj), &shift, &u1, &cp, &sp);
            double rr = sqrt(u1);
            double lx = rr * cp, ly = rr * sp, lz = sqrt(fmax(0.0, 1 - u1));
            for (int a = 0; a < 3; a++) {
                dd[jj][a] = lx * t[a] + ly * b[a] + lz * n[a];
                dir[3 * jj + a] = (float)dd[jj][a];
            }
        }
        bk_tracer_intersect_n(c->tracer, (size_t)m, org, dir, 0.0f, NULL, hits);
        cnt->rays += (uint64_t)m;
        for (int jj = 0; jj < m; jj++)
            cell_sample(c, n, j0 + jj, pts[jj], org + 3 * jj, dd[jj], &hits[jj], nee_t, &near_rng, &cs, cnt);
    }
    if (!cs.valid) return; /* the whole cell is inside solids: never seen */
    for (int a = 0; a < 3; a++) {
        double e = (cs.e[a] * TP_PI + cs.en[a]) / cs.valid;
        if (cs.lit_points) e += cs.ep[a] / cs.lit_points;
        out[a] = cell->albedo[a] / TP_PI * e;
    }
}

static void cache_bounce(tp_ctx *c, size_t begin, size_t end, int thread)
{
    float *cur = c->l_cur[c->half];
    tp_count cnt = {0, 0, 0};
    tp_tile_lists lists;
    bk_tr_slc_lists_init(c, thread, &lists);
    for (size_t ci = begin; ci < end; ci++) {
        double v[3];
        cell_bounce(c, ci, &lists, &cnt, v);
        for (int a = 0; a < 3; a++) {
            if (!isfinite(v[a]) || v[a] < 0) { cnt.bad++; v[a] = 0; }
            cur[3 * ci + a] = (float)v[a];
        }
    }
    c->thread_rays[thread] += cnt.rays + cnt.shadow;
    c->thread_shadow[thread] += cnt.shadow;
    c->thread_nonfinite[thread] += cnt.bad;
}

/* A range of cells of the current bounce, for a unit sharing the cache (bk_cache_bounce). */
static lbk_result compute_cells(void *ctx, size_t begin, size_t end, uint64_t counts[3])
{
    tp_ctx *c = ctx;
    uint64_t before[3], after[3];
    if (begin > end || end > c->cell_count) return LBK_ERR_INTERNAL;
    bk_tr_count_totals(c, before);
    bk_tr_parallel_range(c, begin, end, 64, cache_bounce);
    bk_tr_count_totals(c, after);
    for (int a = 0; a < 3; a++) counts[a] = after[a] - before[a];
    return LBK_OK;
}

static void add_counts(void *ctx, const uint64_t counts[3])
{
    tp_ctx *c = ctx;
    c->thread_rays[0] += counts[0];
    c->thread_shadow[0] += counts[1];
    c->thread_nonfinite[0] += counts[2];
}

/* Bounce c->bounce of every cell into l_cur: here, or shared with the other units of a
 * distributed run (bk_transport_split.cache_bounce). */
static lbk_result bounce_cells(tp_ctx *c)
{
    const bk_transport_split *sp = c->opt->split;
    if (!sp || sp->replay || !sp->cache_bounce) {
        bk_tr_parallel_for(c, c->cell_count, 64, cache_bounce);
        return LBK_OK;
    }
    const bk_cache_bounce b = {c->pass, c->half, c->bounce, c->rays, c->cell_count, c->l_cur[c->half],
                               compute_cells, add_counts, c};
    return sp->cache_bounce(sp->user, &b);
}

static double cell_power(const tp_ctx *c, const float *l)
{
    double p = 0;
    for (size_t i = 0; i < c->cell_count; i++) {
        double v[3] = {l[3 * i], l[3 * i + 1], l[3 * i + 2]};
        p += c->cells[i].area * bk_lum(v);
    }
    return p;
}

/* The tail's share of each cell's light, averaged over the cells by area (*share), and the
 * per-bounce ratio with every cell weighted by the inverse of its light so far (*q_rel). Where
 * a dim region's light is still arriving or decays more slowly than the level's energy (a room
 * lit through a doorway only), q_rel exceeds the energy's ratio and the tail, shaped by that
 * ratio, is too small there. */
static void local_tail(const tp_ctx *c, const float *last, const float *prev, const float *sum, double q, double *share,
                       double *q_rel)
{
    double acc = 0, area = 0, num = 0, den = 0, light = 0, lit_area = 0;
    const double f = q / (1 - q);
    for (size_t i = 0; i < c->cell_count; i++) {
        const double ls = bk_lumf(sum + 3 * i);
        if (ls > 0) light += c->cells[i].area * ls, lit_area += c->cells[i].area;
    }
    /* >= 0, so a cell above it has light */
    const double floor = lit_area > 0 ? TP_LOCAL_FLOOR * light / lit_area : 0;
    for (size_t i = 0; i < c->cell_count; i++) {
        const double ls = bk_lumf(sum + 3 * i), ll = bk_lumf(last + 3 * i), lp = bk_lumf(prev + 3 * i);
        if (!(ls > floor) || !(ll >= 0)) continue;
        const double a = c->cells[i].area;
        acc += a * ll * f / (ls + ll * f);
        area += a;
        num += a * ll / ls;
        den += a * lp / ls;
    }
    *share = area > 0 ? acc / area : 0;
    *q_rel = den > 0 ? num / den : q;
}

/* Whether the tail is good enough region by region, not only for the level's energy: the tail's
 * share of the light averaged over the surface by area is at most TP_LOCAL_SHARE, or its error
 * from shaping dim regions by the energy's ratio (share · |q_rel − q| / (q(1 − q)), as the
 * energy's rule) at most TP_LOCAL_TOL. Measured on a lit and a dark room parted by a wall with a
 * doorway (bench/levels thin_wall_00): stopping by the energy alone after 6 bounces left the
 * dark room 6–17 % darker than 40 bounces without a tail (TRANSPORT.md, item 4). */
static int local_tail_converged(const tp_ctx *c, int h, const float *sum, double q)
{
    double share, q_rel;
    local_tail(c, c->l_hist[h][0], c->l_hist[h][1], sum, q, &share, &q_rel);
    if (share <= TP_LOCAL_SHARE) return 1;
    return q > 1e-3 && share * fabs(q_rel - q) / (q * (1 - q)) <= TP_LOCAL_TOL;
}

/* Fills l_sum[h] with the reflected outgoing radiance per cell (all bounces + tail; emission is
 * added where a gather ray hits it, with its MIS weight). */
tp_chain_result bk_tr_run_chain(tp_ctx *c, int h, int pass, int rays, double tol, int max_bounces)
{
    tp_chain_result res = {0, 0, 0, 0};
    size_t n = c->cell_count;
    float *sum = c->l_sum[h];
    memset(sum, 0, 3 * (n ? n : 1) * sizeof *sum);
    c->half = h;
    c->pass = pass;
    c->rays = rays;
    if (bk_tr_lattice_init(&c->lat, (uint32_t)rays) != LBK_OK) { res.bounces = -1; return res; }
    double pw[3] = {0, 0, 0}; /* energies of the last three bounces */
    double indirect = 0, q = 0;
    int k, late = 0; /* past the energy's rule, bouncing on for the regions' tail */
    for (k = 1; k <= max_bounces; k++) {
        c->bounce = k;
        if (k == 1 && c->slc && bk_tr_slc_draw(c, DOM_SLC_CELL, h, pass, c->slc_cell, &c->draw_cell) != LBK_OK) {
            res.bounces = -1;
            return res;
        }
        c->chain_err = bounce_cells(c);
        bk_slc_draw_destroy(c->draw_cell);
        c->draw_cell = NULL;
        if (c->chain_err) { res.bounces = -1; return res; }
        double p = cell_power(c, c->l_cur[h]);
        for (size_t i = 0; i < 3 * n; i++) sum[i] += c->l_cur[h][i];
        indirect += p;
        pw[0] = pw[1]; pw[1] = pw[2]; pw[2] = p;
        /* rotate: k−1−d <- k−d, the oldest buffer is overwritten next */
        float *tmp = c->l_hist[h][c->cache_depth];
        for (int d = c->cache_depth; d > 0; d--) c->l_hist[h][d] = c->l_hist[h][d - 1];
        c->l_hist[h][0] = c->l_cur[h];
        c->l_cur[h] = tmp;
        if (k >= 2) q = pw[1] > 0 ? pw[2] / pw[1] : 0;
        if (!(p > 0) || p <= 1e-7 * indirect) break;
        if (k >= 4) {
            double q1 = pw[1] / pw[0], q2 = pw[2] / pw[1];
            double qq = fmin(q2, TP_Q_MAX);
            double sigma = fabs(q2 - q1);
            double tail = p * qq / (1 - qq);
            double frac = tail / (indirect + tail);
            /* relative error of the total caused by an error sigma in q (d tail / dq) */
            double unc = qq > 1e-3 ? frac * sigma / (qq * (1 - qq)) : frac;
            if (late || unc <= tol) {
                if (local_tail_converged(c, h, sum, qq)) break;
                /* the bounces the regions still need carry little of the light: fewer rays */
                if (!late && rays / TP_LATE_RAYS_DIV >= 1) {
                    c->rays = rays / TP_LATE_RAYS_DIV;
                    if (bk_tr_lattice_init(&c->lat, (uint32_t)c->rays) != LBK_OK) { res.bounces = -1; return res; }
                }
                late = 1;
            }
        }
    }
    if (k > max_bounces) k = max_bounces;
    q = q < 0 ? 0 : q > TP_Q_MAX ? TP_Q_MAX : q;
    if (!isfinite(q)) q = 0;
    /* tail of the Neumann series: L_K·(q + q² + ...) = L_K·q/(1−q), shaped like the last bounce */
    double f = q / (1 - q);
    const float *last = c->l_hist[h][0];
    for (size_t i = 0; i < 3 * n; i++) sum[i] += (float)(last[i] * f);
    res.bounces = k;
    res.q = q;
    res.tail_energy = pw[2] * f;
    res.total_energy = indirect + pw[2] * f;
    return res;
}

/* ---- rough cells ---------------------------------------------------------------------------- */

/* A cell's constant is also biased far away when the radiance changes sharply inside it: a
 * ceiling cell half over a light's 1 cm gap (the gap ~100x brighter than the room side) shines
 * its average into the room from its visible half, a cell across a hard shadow edge spreads the
 * lit part into the shadow. Hits on such "rough" cells are continued at the exact point like
 * near hits. A cell is rough when it differs from a neighbour in its triangle's m×m grid by
 * more than TP_ROUGH_RATIO of the brighter, more than TP_ROUGH_FLOOR of the mean cell radiance,
 * and more than TP_ROUGH_Z standard deviations of the difference (the variance of each cell's
 * mean from its two halves' difference), so that noise alone rarely marks a cell.
 * The flags of pass p come from pass p−1's caches (pass 0 has none): chosen from the same noisy
 * values that are then read, they would select cells by their noise — marking the ones noise
 * made brighter than their neighbours — and bias the rest (measured: −2 … −4 % in test_bias). */
#define TP_ROUGH_RATIO 0.5
#define TP_ROUGH_FLOOR 0.25
#define TP_ROUGH_Z 3.0

static void mark_pair(const tp_ctx *c, long a, long b, double floor_abs)
{
    double x = c->cell_lum[a], y = c->cell_lum[b], d = fabs(x - y);
    if (d > TP_ROUGH_RATIO * fmax(x, y) && d > floor_abs &&
        d * d > TP_ROUGH_Z * TP_ROUGH_Z * ((double)c->cell_var[a] + c->cell_var[b]))
        c->rough[a] = c->rough[b] = 1;
}

/* Marks the rough cells from the two halves' sums of the pass that just ended. */
void bk_tr_mark_rough(tp_ctx *c)
{
    size_t n = c->cell_count;
    const float *A = c->l_sum[0], *B = c->l_sum[1];
    double pa = 0, area = 0;
    for (size_t i = 0; i < n; i++) {
        double va[3] = {A[3 * i], A[3 * i + 1], A[3 * i + 2]}, vb[3] = {B[3 * i], B[3 * i + 1], B[3 * i + 2]};
        double la = bk_lum(va), lb = bk_lum(vb);
        c->cell_lum[i] = (float)(0.5 * (la + lb));
        c->cell_var[i] = (float)(0.25 * (la - lb) * (la - lb));
        c->rough[i] = c->gap[i] != 0;
        pa += c->cells[i].area * c->cell_lum[i];
        area += c->cells[i].area;
    }
    double floor_abs = area > 0 ? TP_ROUGH_FLOOR * pa / area : 0;
    for (uint32_t t = 0; t < c->scene->tri_count; t++) {
        long m = c->tri_m[t];
        for (int side = 0; side < c->tri_sides[t]; side++) {
            long base = (long)c->tri_first[t] + side * m * m;
            for (long j = 0; j + 1 < m; j++) {
                long row = base + j * (2 * m - j), next = base + (j + 1) * (2 * m - j - 1);
                for (long i = 0; i + j + 1 < m; i++) { /* each upper cell and its three lower neighbours */
                    long lower = row + 2 * i, upper = lower + 1;
                    mark_pair(c, lower, upper, floor_abs);      /* the diagonal */
                    mark_pair(c, upper, lower + 2, floor_abs);  /* edge u = i + 1 */
                    mark_pair(c, upper, next + 2 * i, floor_abs); /* edge v = j + 1 */
                }
            }
        }
    }
}

/* Gap cells: a cell that faces another surface much closer than its own size (the ceiling over
 * a light hung 1 cm under it, the light's top) holds light that changes across it far faster
 * than the cell resolves — bright deep in the gap, dim at its mouth — and the room sees only the
 * mouth. Read as one constant it leaks its average out of the gap (+2–3 % on a whole room,
 * bench_gap). Every hit on a gap cell is continued at the exact point, like a rough one, from
 * pass 0 on. Of TP_GAP_PROBES rays along its normal, from points spread over it, those that meet
 * a surface closer than TP_GAP_RATIO of its size, but not touching it (TP_GAP_CONTACT: the
 * furnished room's rug and books made 15-20 % more CPU time of contacts, for the same error), say
 * how much of it the gap covers: all (inside) or some (mouth; bk_tr_near_entry splits only hits
 * inside). Geometry only: the same marks in every half, pass, unit and resumed run. */
#define TP_GAP_RATIO 0.25
#define TP_GAP_CONTACT 0.02 /* closer is a contact (a rug on the floor, books side by side): no light gets in */
#define TP_GAP_PROBES 4

/* A cell split by a surface standing on it (a 2 cm wall on a floor quad that runs through both
 * rooms) holds the light of both sides, and a ray hitting its dark side reads the average: light
 * leaks through the wall (bench/levels thin_wall_00 with its doorway closed: the dark room at
 * 3–10 % of its light with the door open, at 12.5 cm cells; 9× less at 3 cm). Segments just
 * above the cell from its centre towards its corners find such a surface; the cell's hits are
 * then continued at the exact point, as a gap's mouth's are. */
#define TP_SPLIT_LIFT 0.02 /* above the cell, × its size */
static int cell_split(const tp_ctx *c, const tp_cell *cell, const tp_cell_geom *g, float h, float scale)
{
    static const double end[3][2] = {{0.02, 0.5}, {0.98, 0.02}, {0.98, 0.98}};
    double p0[3];
    bk_tr_cell_point_at(g, 0.45, 0.5, p0, NULL, NULL);
    float o[3], pf[3];
    for (int a = 0; a < 3; a++) pf[a] = (float)(p0[a] + TP_SPLIT_LIFT * h * cell->n[a]);
    bk_offset_ray_origin_scaled(pf, cell->n, scale, o);
    for (int k = 0; k < 3; k++) {
        double p[3];
        bk_tr_cell_point_at(g, end[k][0], end[k][1], p, NULL, NULL);
        float d[3];
        for (int a = 0; a < 3; a++) d[a] = (float)(p[a] + TP_SPLIT_LIFT * h * cell->n[a]) - o[a];
        if (bk_tracer_occluded(c->tracer, o, d, 0.0f, 1.0f)) return 1;
    }
    return 0;
}

void bk_tr_mark_gaps(tp_ctx *c, size_t begin, size_t end, int thread)
{
    static const double probe[TP_GAP_PROBES][2] = {{0.2, 0.5}, {0.7, 0.15}, {0.7, 0.85}, {0.45, 0.5}};
    (void)thread; /* uncounted: a fixed cost of the set-up, not of any pass */
    for (size_t ci = begin; ci < end; ci++) {
        const tp_cell *cell = &c->cells[ci];
        float h = c->tri_cell_h[cell->tri];
        if (!(h > 0) || (cell->n[0] == 0 && cell->n[1] == 0 && cell->n[2] == 0)) continue;
        tp_cell_geom g;
        bk_tr_cell_geom(c, cell, &g);
        float scale = bk_tracer_tri_scale(c->tracer, cell->tri);
        int covered = 0;
        for (int k = 0; k < TP_GAP_PROBES; k++) {
            double p[3];
            bk_tr_cell_point_at(&g, probe[k][0], probe[k][1], p, NULL, NULL);
            float pf[3] = {(float)p[0], (float)p[1], (float)p[2]}, o[3];
            bk_offset_ray_origin_scaled(pf, cell->n, scale, o);
            bk_hit hit;
            covered += bk_tracer_intersect(c->tracer, o, cell->n, 0.0f, (float)(TP_GAP_RATIO * h), &hit) != 0 &&
                       hit.t > TP_GAP_CONTACT * h;
        }
        c->gap[ci] = (uint8_t)(covered == TP_GAP_PROBES ? TP_GAP_INSIDE : covered ? TP_GAP_MOUTH : 0);
        if (!c->gap[ci] && cell_split(c, cell, &g, h, scale)) c->gap[ci] = TP_GAP_MOUTH;
    }
}
