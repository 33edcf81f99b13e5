/* Series-expansion light transport; see transport.h and TRANSPORT.md. */
#include "bake/transport/transport.h"

#include "scene/parallel.h"
#include "bake/transport/ggx.h"
#include "bake/transport/shading.h"
#include "bake/transport/slc.h"
#include "bake/transport/solid.h"
#include "bake/transport/vpl.h"
#include "lbk/octa.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define TP_PI 3.14159265358979323846
#define TP_Q_MAX 0.999      /* largest per-bounce ratio the tail formula trusts (factor ≤ 999) */
#define TP_MAX_SUB 1024     /* at most 1024² cells per triangle side (the cell budget binds first) */
#define TP_CELL_CAP ((size_t)1 << 22) /* cells in all (~0.5 GB with both halves' radiance) */
#define TP_LIGHT_POINTS 16  /* points per cell that test punctual lights in bounce 1 */
#define TP_BATCH 64         /* rays generated, then traced as one stream, then shaded */

/* ---- counter-based random numbers --------------------------------------------------------- */

static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

typedef struct { uint64_t s; } tp_rng;

enum { DOM_CELL = 1, DOM_RECV = 2, DOM_CELL_NEE = 3, DOM_RECV_NEE = 4, DOM_RECV_NEAR = 5, DOM_RECV_POS = 6,
       DOM_RECV_PROBE = 7, DOM_CELL_NEAR = 8, DOM_SLC_RECV = 9, DOM_SLC_CELL = 10,
       DOM_VPL_SHOOT = 11, DOM_VPL_XI = 12, DOM_VPL_POINT = 13 };

/* Keyed by everything that identifies one item's samples: never by thread or time. */
static tp_rng rng_make(uint64_t seed, uint64_t domain, uint64_t half, uint64_t pass, uint64_t bounce, uint64_t item)
{
    uint64_t h = mix64(seed ^ 0x6C626B7472616E73ull);
    h = mix64(h ^ (domain << 56) ^ (half << 48) ^ (pass << 32) ^ bounce);
    h = mix64(h ^ item * 0x9E3779B97F4A7C15ull);
    tp_rng r = {h};
    return r;
}

static double rng_next(tp_rng *r)
{
    r->s += 0x9E3779B97F4A7C15ull;
    return (double)(mix64(r->s) >> 11) * (1.0 / 9007199254740992.0);
}

/* Randomly shifted rank-1 lattice {(j/S, j·g/S) + shift} mod 1, g ≈ 0.618·S coprime with S
 * (Fibonacci-like): the first coordinate is an exactly stratified grid, which gives the
 * provable furnace bound of TRANSPORT.md; the random shift keeps every estimate unbiased, so the
 * two halves stay independent and the error estimate honest. */
static uint32_t lattice_generator(uint32_t S)
{
    uint32_t g = (uint32_t)(0.6180339887498949 * S) | 1u;
    for (;; g += 2) {
        uint32_t a = g, b = S;
        while (b) { uint32_t t = a % b; a = b; b = t; }
        if (a == 1 || S <= 1) return g;
    }
}

/* Sample j of the shifted lattice as u1 and the angle 2π·u2 given as (cos, sin): the angles of
 * the unshifted lattice are S-th roots of unity (a table per sample count), and the shift is
 * one rotation per item, so no trigonometry runs per ray. */
typedef struct tp_lattice {
    uint32_t S, g;
    double *cos_k, *sin_k; /* cos/sin(2π k/S) */
    uint32_t *k_of_j;      /* j·g mod S (a table: a 64-bit division per ray is not free) */
} tp_lattice;

static lbk_result lattice_init(tp_lattice *l, uint32_t S)
{
    if (l->S == S) return LBK_OK;
    free(l->cos_k);
    free(l->sin_k);
    free(l->k_of_j);
    l->cos_k = malloc(S * sizeof(double));
    l->sin_k = malloc(S * sizeof(double));
    l->k_of_j = malloc(S * sizeof(uint32_t));
    l->S = 0;
    if (!l->cos_k || !l->sin_k || !l->k_of_j) return LBK_ERR_OUT_OF_MEMORY;
    for (uint32_t k = 0; k < S; k++) {
        l->cos_k[k] = cos(2 * 3.14159265358979323846 * k / S);
        l->sin_k[k] = sin(2 * 3.14159265358979323846 * k / S);
    }
    l->S = S;
    l->g = lattice_generator(S);
    for (uint32_t j = 0; j < S; j++) l->k_of_j[j] = (uint32_t)(((uint64_t)j * l->g) % S);
    return LBK_OK;
}

static void lattice_free(tp_lattice *l) { free(l->cos_k); free(l->sin_k); free(l->k_of_j); }

typedef struct tp_shift { double s1, cs, sn; } tp_shift;

static tp_shift lattice_shift(double s1, double s2)
{
    tp_shift t = {s1, cos(2 * 3.14159265358979323846 * s2), sin(2 * 3.14159265358979323846 * s2)};
    return t;
}

static void lattice(const tp_lattice *l, uint32_t j, const tp_shift *sh, double *u1, double *cphi, double *sphi)
{
    double a = (double)j / l->S + sh->s1;
    *u1 = a - floor(a);
    uint32_t k = l->k_of_j[j];
    *cphi = l->cos_k[k] * sh->cs - l->sin_k[k] * sh->sn;
    *sphi = l->sin_k[k] * sh->cs + l->cos_k[k] * sh->sn;
}

/* Sample j of the same lattice as a point of [0,1)² with its own shift (light samples). */
static void lattice_uv(const tp_lattice *l, uint32_t j, double t1, double t2, double *a, double *b)
{
    double x = (double)j / l->S + t1;
    uint32_t k = l->k_of_j[j];
    double y = (double)k / l->S + t2;
    *a = x - floor(x);
    *b = y - floor(y);
}

/* ---- the run context ----------------------------------------------------------------------- */

typedef struct tp_cell {
    uint32_t tri;
    uint32_t sub;
    uint16_t m;
    uint8_t side;
    float n[3];        /* side normal, zero for degenerate triangles */
    float area;
    float albedo[3];
    float le[3];       /* emitted radiance at the centroid (after the light-set filter) */
    float nee_parea;   /* light-sampling density per unit area of points in this cell (both
                          sides alike), 0 when next-event estimation never picks it */
} tp_cell;

/* The glossy part of a cell (GGX.md): base colour (after the albedo hook), metallic and
 * roughness at its centroid; `on` = 0 for cells of Lambertian materials (and black ones). */
typedef struct tp_gloss {
    float base[3], metallic, roughness;
    uint8_t on;
} tp_gloss;

/* A sub-triangle of an emissive triangle that light samples pick (one per (tri, sub), shared
 * by both sides of a double-sided emitter). */
typedef struct tp_emitter {
    uint32_t tri;
    uint32_t cell;      /* its side-0 cell */
} tp_emitter;

/* One receiver class: its receivers [begin, end), the sum of its passes' weights and the samples
 * per receiver so far, whether it still samples, and why it stopped (enum bk_transport_stop). */
typedef struct tp_class {
    size_t begin, end;
    double weight_sum, spp;
    int active, stop;
} tp_class;

#define TP_NEAR_DEPTH 24    /* continuations in a row before the cache is read anyway (TRANSPORT.md: 3 left the Cornell light gap 15-25 % dark) */
#define TP_CACHE_DEPTH 2    /* the same in the cache's bounces (TRANSPORT.md, gap cells; bench_gap) */

typedef struct tp_ctx {
    const bk_scene *scene;
    const bk_tracer *tracer;
    const bk_transport_options *opt;
    uint64_t seed;
    int threads;
    /* cache */
    size_t cell_count;
    tp_cell *cells;
    uint32_t *tri_first;   /* first cell of each triangle */
    uint16_t *tri_m;
    uint8_t *tri_sides;
    uint8_t *tri_closed;   /* bounds a closed solid (solid.h): its back side is the inside */
    float *tri_edge_eps;   /* smallest barycentric a sample point may have: keeps points off edges */
    float *tri_cell_h;     /* size of the triangle's cells (metres): what "near" is measured in */
    float *tri_le;         /* 3 per triangle: emission factor after the light-set filter */
    int32_t *tri_le_tex;   /* emission texture per triangle, -1 none */
    /* glossy materials (GGX.md): per cell, NULL when the scene has none (then every path is
     * the Lambertian one, bytes as before), and the coupling's albedo table */
    tp_gloss *gloss;
    bk_ggx_table *ggx;
    /* next-event estimation: emitter sub-triangles picked by power through a CDF */
    int nee;
    size_t em_count;
    tp_emitter *em;
    double *em_cdf;        /* inclusive, em_cdf[em_count-1] = 1 */
    /* light selection */
    const bk_light **lights;
    size_t light_count;
    int use_sky;
    float scene_scale;
    /* stochastic light culling (slc.h, SLC.md): the receivers' and the cells' tiles, the
     * draws of the current pass (receivers: one per half; cells: the current chain's), δ of
     * pass 0 in irradiance units (each pass p uses δ/2^p), and per thread room for two tile
     * lists */
    int slc;
    double slc_delta;
    bk_slc *slc_recv, *slc_cell;
    bk_slc_draw *draw_recv[2], *draw_cell;
    uint32_t *slc_ids;
    uint64_t *thread_slc_tested;
    double *slc_cdf;           /* positional lights by intensity, for continued points */
    uint32_t *slc_pick_ids;
    size_t slc_pick_count;
    /* glossy VPLs (vpl.h; VPL.md "In the transport"): on; δ of pass 0 in irradiance units (pass
     * p: δ/2^p); photons per light and half in pass 0 (pass p: × 2^p); per light whether it
     * shoots (its light → glossy → receiver path is then the VPLs', and the receivers' glossy
     * continuations see it through the diffuse part only); the receivers' tiles; this pass's
     * VPLs and draws per half; per thread room for two tile lists; what auto measured */
    int vpl;
    double vpl_delta, vpl_share;
    size_t vpl_photons;
    uint8_t *light_vpl;
    bk_slc *vpl_tiles;
    bk_vpl *vpls[2];
    size_t vpl_n[2], vpl_cap;
    bk_vpl_draw *vpl_draw[2];
    uint32_t *vpl_ids;
    uint64_t *thread_vpl_tested, vpl_made;
    /* per chain (half) state; [h] */
    float *l_cur[2], *l_sum[2];
    /* the last bounces' cells, newest first: l_hist[h][0] is bounce k−1 (what bounce k reads),
     * l_hist[h][d] bounce k−1−d (what a near hit's d-th continuation in a row reads);
     * cache_depth + 1 of them (cache_depth_for) */
    float *l_hist[2][TP_CACHE_DEPTH + 1];
    int cache_depth;
    uint8_t *rough;        /* cells whose radiance changes sharply, from the last pass (mark_rough), and the gap cells */
    uint8_t *gap;          /* cells facing a surface much closer than their size (mark_gaps): TP_GAP_* */
    float *cell_lum, *cell_var; /* scratch for mark_rough */
    /* current job */
    int half, pass, bounce, rays;
    tp_lattice lat;        /* for `rays` samples */
    /* receivers */
    const bk_scene *fscene;  /* the scene footprints index (options.footprint_scene or scene) */
    const bk_receiver *recv;
    size_t recv_count;
    float *punct_lum;      /* luminance of punctual E per receiver (for the error estimate) */
    double *x_acc[2];      /* per receiver, per half: Σ_p w_p·bk_lum(E_p) */
    double *b_acc[2];      /* per receiver, per half: Σ_p w_p·bk_lum(cache bias probe of pass p) */
    const bk_transport_output *out;
    double pass_weight;
    /* octahedral probes (options.octa_*): gathered like sphere receivers, outside the outputs
     * and the error estimate of the receivers */
    size_t oct_count;
    int oct_rays;          /* this pass: rays per half */
    double oct_total;      /* rays per probe so far, both halves */
    double oct_weight;     /* Σ of the pass weights they were gathered in */
    tp_lattice oct_lat;
    double oct_dir[16][3]; /* texel directions, lbk_oct_texel_direction(4, i, j) */
    double *oct_acc[2];    /* per probe texel, per half: Σ_p w_p·bk_lum(E_p) */
    /* the run's settings and progress */
    double t0, max_samples, target, tail_tol, spp;
    /* receiver classes (options.class_end; one class of every receiver without it): each
     * samples until its own estimate reaches the target or its budget runs out */
    tp_class cls[BK_RECEIVER_CLASSES];
    int ncls;
    int max_bounces, s0;
    /* counters: per thread, summed after each parallel step */
    uint64_t *thread_rays, *thread_shadow, *thread_nonfinite;
    /* the receivers this run gathers ([0, recv_count) unless options.split cuts it) and what
     * the caches alone traced (a distributed run's global part) */
    size_t g_begin, g_end;
    uint64_t cache_rays, cache_shadow, cache_nonfinite;
    /* the stop rule's receivers (stop_init): stop_sub[k] = 1 when class k stops on the subset
     * stop_idx[stop_first[k], stop_first[k + 1]) rather than on all its receivers; extra: the
     * receivers the rule reads outside [g_begin, g_end) (a distributed run's unit gathers them
     * too, unrecorded), class k's at [extra_first[k], extra_first[k + 1]); what they traced is
     * left out of the unit's receiver counts */
    size_t *stop_idx, *extra;
    size_t stop_first[BK_RECEIVER_CLASSES + 1], extra_first[BK_RECEIVER_CLASSES + 1];
    int stop_sub[BK_RECEIVER_CLASSES];
    uint64_t extra_rays, extra_shadow, extra_nonfinite;
    /* adaptive sampling's blocks (TRANSPORT.md §Adaptive sampling), class k's
     * [blk_first[k], blk_first[k + 1]): per block the sum of the weights of the passes it sampled
     * in, whether it samples in this pass, and whether it would sample in the next (adapt_mark;
     * applied where its class may adapt, stop_after). Without adapt every block of a class
     * samples while the class does, so blk_w is the class's weight_sum. */
    int adapt;
    size_t blk_count, blk_first[BK_RECEIVER_CLASSES + 1];
    double *blk_w;
    uint8_t *blk_on, *blk_next;
    bk_transport_sample samples[BK_TRANSPORT_MAX_PASSES]; /* what each pass reported (checkpoints) */
} tp_ctx;

/* ---- parallel-for --------------------------------------------------------------------------- */

typedef void (*tp_fn)(tp_ctx *c, size_t begin, size_t end, int thread);

typedef struct tp_call { tp_ctx *c; tp_fn fn; } tp_call;

static void tp_call_run(void *user, size_t begin, size_t end, int thread)
{
    const tp_call *k = (const tp_call *)user;
    k->fn(k->c, begin, end, thread);
}

static void parallel_range(tp_ctx *c, size_t begin, size_t end, size_t chunk, tp_fn fn)
{
    tp_call k = {c, fn};
    bk_parallel_chunks(begin, end, chunk, c->threads, tp_call_run, &k);
}

static void parallel_for(tp_ctx *c, size_t n, size_t chunk, tp_fn fn) { parallel_range(c, 0, n, chunk, fn); }

/* ---- adaptive sampling's blocks: receiver index / BK_TRANSPORT_BLOCK, cut at the class bounds */

static int class_of(const tp_ctx *c, size_t i)
{
    int k = 0;
    while (k + 1 < c->ncls && i >= c->cls[k].end) k++;
    return k;
}

static size_t block_of(const tp_ctx *c, size_t i)
{
    const int k = class_of(c, i);
    return c->blk_first[k] + i / BK_TRANSPORT_BLOCK - c->cls[k].begin / BK_TRANSPORT_BLOCK;
}

/* The receivers [*lo, *hi) of block b of class k. */
static void block_range(const tp_ctx *c, int k, size_t b, size_t *lo, size_t *hi)
{
    const size_t chunk = c->cls[k].begin / BK_TRANSPORT_BLOCK + (b - c->blk_first[k]);
    *lo = chunk * BK_TRANSPORT_BLOCK > c->cls[k].begin ? chunk * BK_TRANSPORT_BLOCK : c->cls[k].begin;
    *hi = (chunk + 1) * BK_TRANSPORT_BLOCK < c->cls[k].end ? (chunk + 1) * BK_TRANSPORT_BLOCK : c->cls[k].end;
}

/* ---- scene lookups -------------------------------------------------------------------------- */

static void tri_vertices(const tp_ctx *c, uint32_t tri, double v[3][3])
{
    const uint32_t *ix = c->scene->tris + 3 * (size_t)tri;
    for (int i = 0; i < 3; i++) {
        uint32_t k = ix[i] < c->scene->vertex_count ? ix[i] : 0;
        for (int a = 0; a < 3; a++) v[i][a] = c->scene->positions[3 * (size_t)k + a];
    }
}

static void sky_radiance(const tp_ctx *c, const double d[3], double out[3])
{
    if (!c->use_sky) { out[0] = out[1] = out[2] = 0; return; }
    bk_sky_radiance(c->scene, d, out);
}

static int in_light_set(const tp_ctx *c, const char *set)
{
    const char *want = c->opt->light_set ? c->opt->light_set : "";
    return strncmp(set, want, 63) == 0;
}

/* What a hit reaches: its cell (>= 0), HIT_BLACK for the back of a one-sided open surface, or
 * HIT_INSIDE for the back of a closed solid: the ray started inside that solid (solid.h). */
enum { HIT_BLACK = -1, HIT_INSIDE = -2 };

static long hit_cell(const tp_ctx *c, const bk_hit *h)
{
    if (h->tri >= c->scene->tri_count) return HIT_BLACK;
    if (!h->front && c->tri_closed[h->tri]) return HIT_INSIDE;
    int side = h->front ? 0 : 1;
    if (side >= c->tri_sides[h->tri]) return HIT_BLACK;
    int m = c->tri_m[h->tri];
    float a = h->u * (float)m, b = h->v * (float)m;
    int i = (int)a, j = (int)b; /* truncation: u, v >= 0 up to rounding, and the clamps below */
    if (j < 0) j = 0;
    if (j > m - 1) j = m - 1;
    if (i < 0) i = 0;
    if (i > m - 1 - j) i = m - 1 - j;
    int upper = (a - i) + (b - j) > 1 && i + j < m - 1;
    long sub = (long)j * (2 * m - j) + 2 * i + upper;
    return (long)c->tri_first[h->tri] + (long)side * m * m + sub;
}

/* Row j of sub-triangle s in an m×m split: row r holds 2(m − r) − 1 cells, so rows before j
 * hold j(2m − j); the largest j with j(2m − j) <= s, from the quadratic and one correction. */
static int sub_row(int m, long s)
{
    double disc = (double)m * m - (double)s;
    int j = (int)(m - sqrt(disc > 0 ? disc : 0));
    if (j < 0) j = 0;
    if (j > m - 1) j = m - 1;
    while (j > 0 && (long)j * (2 * m - j) > s) j--;
    while (j < m - 1 && (long)(j + 1) * (2 * m - j - 1) <= s) j++;
    return j;
}

/* A cell's sub-triangle in world space, and the edge band of its triangle, fetched once per
 * cell and bounce rather than per ray. */
typedef struct tp_cell_geom {
    double b[3][2];     /* barycentric (u, v) corners of the sub-triangle */
    double v[3][3];     /* the triangle's vertices */
    double eps;
} tp_cell_geom;

static void cell_geom(const tp_ctx *c, const tp_cell *cell, tp_cell_geom *g)
{
    int m = cell->m;
    long s = (long)cell->sub;
    int j = sub_row(m, s);
    s -= (long)j * (2 * m - j);
    int i = (int)(s / 2), upper = (int)(s & 1);
    double c0[2], c1[2], c2[2];
    if (!upper) {
        c0[0] = i; c0[1] = j; c1[0] = i + 1; c1[1] = j; c2[0] = i; c2[1] = j + 1;
    } else {
        c0[0] = i + 1; c0[1] = j; c1[0] = i + 1; c1[1] = j + 1; c2[0] = i; c2[1] = j + 1;
    }
    for (int k = 0; k < 2; k++) {
        g->b[0][k] = c0[k] / m;
        g->b[1][k] = c1[k] / m;
        g->b[2][k] = c2[k] / m;
    }
    tri_vertices(c, cell->tri, g->v);
    g->eps = c->tri_edge_eps[cell->tri];
}

/* The point of a cell for (r1, r2) in [0,1)², uniform over its area, kept off the triangle's
 * edges; bu, bv (optional) get its barycentrics in the whole triangle. */
static void cell_point_at(const tp_cell_geom *g, double r1, double r2, double p[3], double *bu, double *bv)
{
    double sq = sqrt(r1);
    double w0 = 1 - sq, w1 = sq * (1 - r2), w2 = sq * r2;
    double u = w0 * g->b[0][0] + w1 * g->b[1][0] + w2 * g->b[2][0];
    double v = w0 * g->b[0][1] + w1 * g->b[1][1] + w2 * g->b[2][1];
    /* clamp into the band-free interior: only points within the band move, and only onto the
     * band's inner border, so the rest of the triangle is sampled exactly uniformly */
    double eps = g->eps;
    if (eps > 0) {
        double w = 1 - u - v;
        u = u < eps ? eps : u;
        v = v < eps ? eps : v;
        w = w < eps ? eps : w;
        double sum = u + v + w;
        u /= sum;
        v /= sum;
    }
    for (int a = 0; a < 3; a++) p[a] = (1 - u - v) * g->v[0][a] + u * g->v[1][a] + v * g->v[2][a];
    if (bu) *bu = u;
    if (bv) *bv = v;
}

/* Random point in a cell, kept off the triangle's edges. */
static void cell_point(const tp_cell_geom *g, tp_rng *r, double p[3])
{
    double r1 = rng_next(r), r2 = rng_next(r);
    cell_point_at(g, r1, r2, p, NULL, NULL);
}

/* ---- emitters: next-event estimation and its MIS weights ------------------------------------ */

/* Emitted radiance of triangle `tri` at barycentrics (u, v): the factor times the emission
 * texture at the point's uv0, for both strategies alike (gather hits and light samples must
 * see the same emitter or MIS would be biased). */
static void emission_at(const tp_ctx *c, uint32_t tri, double u, double v, double out[3])
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

/* Which gather pdf a light sample is weighed against. */
enum { PG_COSINE = 0, PG_HEMISPHERE = 1, PG_SPHERE = 2 };

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
static double mis_gather(const tp_ctx *c, const bk_hit *h, long hc, const double d[3], double pg)
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
/* A glossy point's BSDF in its frame (t, b, n): what light samples there are weighed against. */
typedef struct tp_lobe {
    bk_mr_lobe lb;
    double t[3], b[3], n[3];
} tp_lobe;

static void to_local(const tp_lobe *lf, const double d[3], double l[3])
{
    l[0] = d[0] * lf->t[0] + d[1] * lf->t[1] + d[2] * lf->t[2];
    l[1] = d[0] * lf->b[0] + d[1] * lf->b[1] + d[2] * lf->b[2];
    l[2] = d[0] * lf->n[0] + d[1] * lf->n[1] + d[2] * lf->n[2];
}

static int nee_sample_lobe(const tp_ctx *c, const float o[3], const double n[3], int kind, const tp_lobe *lf,
                           double u0, double u1, double *dist_out, double d[3], double *cos_p, double val[3],
                           uint64_t *shadow);

static int nee_sample(const tp_ctx *c, const float o[3], const double n[3], int kind, double u0, double u1,
                      double d[3], double *cos_p, double val[3], uint64_t *shadow)
{
    return nee_sample_lobe(c, o, n, kind, NULL, u0, u1, NULL, d, cos_p, val, shadow);
}

/* nee_sample weighed against the lobe lf's density instead of the gather pdf (lf NULL: that);
 * dist_out (or NULL): the distance to the emitter point of a sample it returns. */
static int nee_sample_lobe(const tp_ctx *c, const float o[3], const double n[3], int kind, const tp_lobe *lf,
                           double u0, double u1, double *dist_out, double d[3], double *cos_p, double val[3],
                           uint64_t *shadow)
{
    double rem;
    const tp_emitter *em = &c->em[em_pick(c, u0, &rem)];
    const tp_cell *cell = &c->cells[em->cell];
    tp_cell_geom g;
    cell_geom(c, cell, &g);
    double x[3], bu, bv;
    cell_point_at(&g, rem, u1, x, &bu, &bv);
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
    emission_at(c, em->tri, bu, bv, le);
    if (le[0] <= 0 && le[1] <= 0 && le[2] <= 0) return 0;
    double pl = cell->nee_parea * dist2 / cl;
    if (!(pl > 0) || !isfinite(pl)) return 0;
    double pg;
    if (lf) {
        double l[3];
        to_local(lf, d, l);
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

/* Per-thread counters of one parallel step. */
typedef struct tp_count { uint64_t rays, shadow, bad; } tp_count;

/* The tile lists of a thread (for the punctual lights' draws and for the VPLs' draws): for each
 * half the list of the tile it last cut (tile), in the thread's two slots of `ids` (cap each). */
typedef struct tp_tile_lists {
    uint32_t *ids[2];
    size_t n[2], tile[2];
} tp_tile_lists;

static void tile_lists_init(uint32_t *ids, size_t cap, int thread, tp_tile_lists *t)
{
    for (int h = 0; h < 2; h++) {
        t->ids[h] = ids ? ids + (2 * (size_t)thread + (size_t)h) * cap : NULL;
        t->n[h] = 0;
        t->tile[h] = SIZE_MAX;
    }
}

static void slc_lists_init(const tp_ctx *c, int thread, tp_tile_lists *t)
{
    tile_lists_init(c->slc_ids, c->light_count, thread, t);
}

/* A culling draw over `slc` for (half, pass): one ξ per light from its own stream. */
static lbk_result slc_draw(const tp_ctx *c, int dom, int h, int pass, const bk_slc *slc, bk_slc_draw **out)
{
    double *xi = malloc((c->light_count ? c->light_count : 1) * sizeof *xi);
    if (!xi) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t li = 0; li < c->light_count; li++) {
        tp_rng r = rng_make(c->seed, (uint64_t)dom, (uint64_t)h, (uint64_t)pass, 0, li);
        xi[li] = rng_next(&r);
    }
    lbk_result res = bk_slc_draw_create(slc, xi, ldexp(c->slc_delta, -(pass < 60 ? pass : 60)), c->threads, out);
    free(xi);
    return res;
}


/* ---- near-field continuation -------------------------------------------------------------- */

/* A cell holds one radiance for its whole area; read from closer than a few cell sizes (a
 * corner, a leg under a table top) that constant is biased, and more samples never remove it.
 * Such hits are evaluated at the exact hit point instead: one cosine-distributed gather from
 * there (sky, emission, and the cache one bounce further, or another continuation when that
 * hit is near too) plus one punctual light picked uniformly. An unbiased estimate of the
 * reflected radiance at the point given the cache beyond it (TRANSPORT.md §Bias). */
#define TP_NEAR_CELLS 1.5   /* continue when the hit is closer than this many cell sizes */
#define TP_NEAR_INSET 1e-4  /* barycentric inset of a continuation's point from its triangle's edges */

static int near_hit(const tp_ctx *c, const bk_hit *h, long hc, const uint8_t *rough)
{
    return hc >= 0 && (h->t < TP_NEAR_CELLS * c->tri_cell_h[h->tri] || (rough && rough[hc]) ||
                       (c->gloss && c->gloss[hc].on));
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
static void mark_rough(tp_ctx *c)
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
 * how much of it the gap covers: all (inside) or some (mouth; near_entry splits only hits
 * inside). Geometry only: the same marks in every half, pass, unit and resumed run. */
#define TP_GAP_RATIO 0.25
#define TP_GAP_CONTACT 0.02 /* closer is a contact (a rug on the floor, books side by side): no light gets in */
#define TP_GAP_PROBES 4
enum { TP_GAP_MOUTH = 1, TP_GAP_INSIDE = 2 }; /* some of the probes covered; all of them */

static void mark_gaps(tp_ctx *c, size_t begin, size_t end, int thread)
{
    static const double probe[TP_GAP_PROBES][2] = {{0.2, 0.5}, {0.7, 0.15}, {0.7, 0.85}, {0.45, 0.5}};
    (void)thread; /* uncounted: a fixed cost of the set-up, not of any pass */
    for (size_t ci = begin; ci < end; ci++) {
        const tp_cell *cell = &c->cells[ci];
        float h = c->tri_cell_h[cell->tri];
        if (!(h > 0) || (cell->n[0] == 0 && cell->n[1] == 0 && cell->n[2] == 0)) continue;
        tp_cell_geom g;
        cell_geom(c, cell, &g);
        float scale = bk_tracer_tri_scale(c->tracer, cell->tri);
        int covered = 0;
        for (int k = 0; k < TP_GAP_PROBES; k++) {
            double p[3];
            cell_point_at(&g, probe[k][0], probe[k][1], p, NULL, NULL);
            float pf[3] = {(float)p[0], (float)p[1], (float)p[2]}, o[3];
            bk_offset_ray_origin_scaled(pf, cell->n, scale, o);
            bk_hit hit;
            covered += bk_tracer_intersect(c->tracer, o, cell->n, 0.0f, (float)(TP_GAP_RATIO * h), &hit) != 0 &&
                       hit.t > TP_GAP_CONTACT * h;
        }
        c->gap[ci] = (uint8_t)(covered == TP_GAP_PROBES ? TP_GAP_INSIDE : covered ? TP_GAP_MOUTH : 0);
    }
}

/* Reflected radiance (all bounces, emission excluded) at the point of `hit` (cell hc, reached
 * along unit d) from one continuation sample. */
/* What a continuation sample gathers: the cells it reads at its hit (NULL: none) and whether
 * the light sources count (sky, emission, one punctual light). The final gather continues with
 * everything (read = the cache's sum); bounce k of the cache continues with the exact bounce
 * k−1 at its near hit: the sources for k = 2, bounce k−2's cells beyond. */
/* vpl: a receiver's gather with glossy VPLs on: at its first hit (depth 0) a glossy point takes
 * the lights that shoot photons through its diffuse part only (VPL.md: counted once). */
/* hist (the cache's bounce k, NULL in the final gather): the continuation at depth d evaluates
 * bounce b = k − 1 − d at its point, so it takes the sources where b = 1 and reads bounce b − 1
 * (hist[d + 1]) where b ≥ 2; read and sources are then per depth (mode_read, mode_sources). */
typedef struct tp_near_mode {
    const float *read;
    const uint8_t *rough;
    int sources, max_depth, vpl;
    const float *const *hist;
    int bounce;
} tp_near_mode;

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
        to_local(lf, ld, l);
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

static void near_radiance(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double din[3],
                          int depth, tp_rng *rng, tp_count *cnt, double out[3]);

/* The continued point of `hit` (on cell's side) and its offset ray origin o. */
static void cont_point(const tp_ctx *c, const bk_hit *hit, const tp_cell *cell, double x[3], float o[3])
{
    double v[3][3];
    tri_vertices(c, hit->tri, v);
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

/* What a continuation ray from o along unit d brings back: sky, emission (MIS-weighted against
 * the light samples with the continuation's own density pg) and the cache — or the exact
 * radiance where that hit is near, rough or glossy too (up to md->max_depth in a row). */
static void cont_trace(tp_ctx *c, const tp_near_mode *md, const float o[3], const double d[3], double pg, int depth,
                       tp_rng *rng, tp_count *cnt, double L[3])
{
    float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
    L[0] = L[1] = L[2] = 0;
    bk_hit h2;
    cnt->rays++;
    const int sources = mode_sources(md, depth);
    const float *read = mode_read(md, depth);
    if (!bk_tracer_intersect(c->tracer, o, df, 0.0f, INFINITY, &h2)) {
        if (sources) sky_radiance(c, d, L);
        return;
    }
    long h2c = hit_cell(c, &h2);
    if (h2c < 0) return;
    if (sources) {
        emission_at(c, h2.tri, h2.u, h2.v, L);
        if (L[0] > 0 || L[1] > 0 || L[2] > 0) {
            double w = mis_gather(c, &h2, h2c, d, pg);
            for (int a = 0; a < 3; a++) L[a] *= w;
        }
    }
    double r2[3] = {0, 0, 0};
    if (read && depth + 1 < md->max_depth && near_hit(c, &h2, h2c, md->rough)) {
        near_radiance(c, md, &h2, h2c, d, depth + 1, rng, cnt, r2);
    } else if (read) {
        for (int a = 0; a < 3; a++) r2[a] = read[3 * h2c + a];
    }
    for (int a = 0; a < 3; a++) L[a] += r2[a];
}

/* One punctual light (picked as near_radiance picks it) at a continued point x, into e:
 * E·(Lambertian: nothing more; glossy lf: × f(v, l) per channel). */
static void cont_punctual(const tp_ctx *c, const double x[3], const double n[3], const float o[3], const tp_lobe *lf,
                          int split, tp_rng *rng, double e[3], tp_count *cnt);

/* Reflected radiance (all bounces, emission excluded) at a glossy hit towards -din: one sample
 * of the coupled BSDF (GGX.md) traced like a Lambertian continuation, one light sample weighed
 * against the BSDF's density (MIS), one punctual light through the BSDF. */
static void gloss_radiance(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double din[3],
                           int depth, tp_rng *rng, tp_count *cnt, double out[3])
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
    to_local(&lf, vw, v);
    out[0] = out[1] = out[2] = 0;
    const double base[3] = {g->base[0], g->base[1], g->base[2]};
    if (!bk_mr_lobe_init(&lf.lb, c->ggx, base, g->metallic, g->roughness, v)) return;
    double u0 = rng_next(rng), u1 = rng_next(rng), u2 = rng_next(rng), l[3];
    double pdf = bk_mr_lobe_sample(&lf.lb, u0, u1, u2, l);
    if (pdf > 0 && l[2] > 0) {
        double d[3], f[3], L[3];
        for (int a = 0; a < 3; a++) d[a] = l[0] * lf.t[a] + l[1] * lf.b[a] + l[2] * lf.n[a];
        bk_mr_lobe_eval(&lf.lb, l, f);
        cont_trace(c, md, o, d, pdf, depth, rng, cnt, L);
        for (int a = 0; a < 3; a++) out[a] += f[a] * l[2] / pdf * L[a];
    }
    const int sources = mode_sources(md, depth);
    if (sources && c->nee) {
        double ld[3], cq, val[3];
        double a0 = rng_next(rng), a1 = rng_next(rng);
        if (nee_sample_lobe(c, o, lf.n, PG_COSINE, &lf, a0, a1, NULL, ld, &cq, val, &cnt->shadow) && bk_finite3(val)) {
            double ll[3], f[3];
            to_local(&lf, ld, ll);
            bk_mr_lobe_eval(&lf.lb, ll, f);
            for (int a = 0; a < 3; a++) out[a] += val[a] * f[a] * cq;
        }
    }
    if (sources && c->light_count) cont_punctual(c, x, lf.n, o, &lf, md->vpl && depth == 0, rng, out, cnt);
}

static void near_radiance(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double din[3],
                          int depth, tp_rng *rng, tp_count *cnt, double out[3])
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
    double u1 = rng_next(rng), ph = 2 * TP_PI * rng_next(rng), rr = sqrt(u1), lz = sqrt(fmax(0.0, 1 - u1));
    double d[3];
    for (int a = 0; a < 3; a++) d[a] = rr * cos(ph) * t[a] + rr * sin(ph) * b[a] + lz * n[a];
    double L[3];
    cont_trace(c, md, o, d, lz / TP_PI, depth, rng, cnt, L);
    double e[3] = {TP_PI * L[0], TP_PI * L[1], TP_PI * L[2]};
    const int sources = mode_sources(md, depth);
    if (sources && c->nee) {
        /* the light sample that pairs with the gather above (MIS): a point next to an emitter
         * (the ceiling by the Cornell light's 1 cm gap) sees it at grazing angles, which
         * gathering alone finds rarely and brightly */
        double ld[3], cq, val[3];
        double u0 = rng_next(rng), u1n = rng_next(rng);
        if (nee_sample(c, o, n, PG_COSINE, u0, u1n, ld, &cq, val, &cnt->shadow) && bk_finite3(val))
            for (int a = 0; a < 3; a++) e[a] += val[a] * cq;
    }
    if (sources && c->light_count) cont_punctual(c, x, n, o, NULL, 0, rng, e, cnt);
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
static void near_entry(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double d[3], tp_rng *rng,
                       tp_count *cnt, double out[3])
{
    const int far = hit->t >= TP_NEAR_CELLS * c->tri_cell_h[hit->tri];
    const int n = far && c->gap[hc] == TP_GAP_INSIDE ? TP_GAP_SPLIT : 1;
    near_radiance(c, md, hit, hc, d, 0, rng, cnt, out);
    for (int k = 1; k < n; k++) {
        double r[3];
        near_radiance(c, md, hit, hc, d, 0, rng, cnt, r);
        for (int a = 0; a < 3; a++) out[a] += r[a];
    }
    if (n > 1)
        for (int a = 0; a < 3; a++) out[a] /= n;
}

static void cont_punctual(const tp_ctx *c, const double x[3], const double n[3], const float o[3], const tp_lobe *lf,
                          int split, tp_rng *rng, double e[3], tp_count *cnt)
{
    /* one light: uniformly; with culling (many lights) a positional one in proportion to its
     * intensity (a uniform pick among thousands almost never finds the lamp that matters)
     * and every directional one */
    double u = rng_next(rng), scale = (double)c->light_count;
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

/* ---- cache: one bounce for a range of cells ------------------------------------------------ */

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
                        tp_rng *near_rng, tp_cell_sums *cs, tp_count *cnt)
{
    const int k = c->bounce, h = c->half;
    const float *prev = c->l_hist[h][0];
    double L[3] = {0, 0, 0};
    if (hit->tri != UINT32_MAX) {
        long hc = hit_cell(c, hit);
        if (hc == HIT_INSIDE) return;
        if (hc >= 0) {
            if (k == 1) {
                emission_at(c, hit->tri, hit->u, hit->v, L);
                if (L[0] > 0 || L[1] > 0 || L[2] > 0) {
                    double lz = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
                    double w = mis_gather(c, hit, hc, d, lz / TP_PI);
                    for (int a = 0; a < 3; a++) L[a] *= w;
                }
            } else if (near_hit(c, hit, hc, c->rough)) {
                /* bounce k−1 at the exact point (see near_radiance) */
                const tp_near_mode md = {NULL, NULL, 0, k - 1 < c->cache_depth ? k - 1 : c->cache_depth, 0,
                                         (const float *const *)c->l_hist[h], k};
                near_entry(c, &md, hit, hc, d, near_rng, cnt, L);
            } else {
                for (int a = 0; a < 3; a++) L[a] = prev[3 * hc + a];
            }
        }
    } else if (k == 1) {
        sky_radiance(c, d, L);
    }
    cs->valid++;
    if (!bk_finite3(L)) cnt->bad++;
    else for (int a = 0; a < 3; a++) cs->e[a] += L[a];
    if (k != 1) return;
    if (c->nee) {
        double u0, v0, ld[3], cq, val[3];
        lattice_uv(&c->lat, (uint32_t)j, nee_t[0], nee_t[1], &u0, &v0);
        if (nee_sample(c, o, n, PG_COSINE, u0, v0, ld, &cq, val, &cnt->shadow)) {
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
    tp_rng rng = rng_make(c->seed, DOM_CELL, (uint64_t)h, (uint64_t)c->pass, (uint64_t)k, ci);
    tp_rng near_rng = rng_make(c->seed, DOM_CELL_NEAR, (uint64_t)h, (uint64_t)c->pass, (uint64_t)k, ci);
    double n[3] = {cell->n[0], cell->n[1], cell->n[2]}, t[3], b[3];
    bk_onb(n, t, b);
    float nf[3] = {cell->n[0], cell->n[1], cell->n[2]};
    float scale = bk_tracer_tri_scale(c->tracer, cell->tri);
    double s1 = rng_next(&rng), s2 = rng_next(&rng);
    tp_shift shift = lattice_shift(s1, s2);
    tp_cell_geom geom;
    cell_geom(c, cell, &geom);
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
        tp_rng nr = rng_make(c->seed, DOM_CELL_NEE, (uint64_t)h, (uint64_t)c->pass, 0, ci);
        nee_t[0] = rng_next(&nr);
        nee_t[1] = rng_next(&nr);
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
            lattice(&c->lat, (uint32_t)(j0 + jj), &shift, &u1, &cp, &sp);
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
    slc_lists_init(c, thread, &lists);
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

static double cell_power(const tp_ctx *c, const float *l)
{
    double p = 0;
    for (size_t i = 0; i < c->cell_count; i++) {
        double v[3] = {l[3 * i], l[3 * i + 1], l[3 * i + 2]};
        p += c->cells[i].area * bk_lum(v);
    }
    return p;
}

typedef struct tp_chain_result { int bounces; double q, tail_energy, total_energy; } tp_chain_result;

/* Fills l_sum[h] with the reflected outgoing radiance per cell (all bounces + tail; emission is
 * added where a gather ray hits it, with its MIS weight). */
static tp_chain_result run_chain(tp_ctx *c, int h, int pass, int rays, double tol, int max_bounces)
{
    tp_chain_result res = {0, 0, 0, 0};
    size_t n = c->cell_count;
    float *sum = c->l_sum[h];
    memset(sum, 0, 3 * (n ? n : 1) * sizeof *sum);
    c->half = h;
    c->pass = pass;
    c->rays = rays;
    if (lattice_init(&c->lat, (uint32_t)rays) != LBK_OK) { res.bounces = -1; return res; }
    double pw[3] = {0, 0, 0}; /* energies of the last three bounces */
    double indirect = 0, q = 0;
    int k;
    for (k = 1; k <= max_bounces; k++) {
        c->bounce = k;
        if (k == 1 && c->slc && slc_draw(c, DOM_SLC_CELL, h, pass, c->slc_cell, &c->draw_cell) != LBK_OK) {
            res.bounces = -1;
            return res;
        }
        parallel_for(c, n, 64, cache_bounce);
        bk_slc_draw_destroy(c->draw_cell);
        c->draw_cell = NULL;
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
            if (unc <= tol) break;
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

/* ---- receivers ------------------------------------------------------------------------------- */

/* Where a receiver's ray leaves from: the point, its unit normal (zero vector: a probe, which
 * gathers over the sphere; n then holds +z for the frame), and the offset ray origin. */
typedef struct tp_origin {
    double p[3], n[3];
    float o[3];
    int sphere;
} tp_origin;

static void origin_from(const tp_ctx *c, const float p[3], const float nf[3], tp_origin *g)
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
static void recv_origin(const tp_ctx *c, const bk_receiver *r, tp_origin *g)
{
    origin_from(c, r->position, r->normal, g);
}

/* The point of receiver r's footprint at texel-local (s, t): on the footprint triangle that
 * covers it (position and interpolated shading normal from the footprint scene; returns 1),
 * else the receiver's own point (returns 0). */
static int footprint_origin(const tp_ctx *c, const bk_receiver *r, double s, double t, tp_origin *g)
{
    double p[3], n[3];
    if (r->footprint_count &&
        bk_footprint_point(c->fscene, c->opt->footprint + r->footprint_first, r->footprint_count, s, t, p, n)) {
        float pf[3] = {(float)p[0], (float)p[1], (float)p[2]}, nf[3] = {(float)n[0], (float)n[1], (float)n[2]};
        origin_from(c, pf, nf, g);
        return 1;
    }
    recv_origin(c, r, g);
    return 0;
}

/* A uniform point of the part of the texel's square that its footprint covers: rejection in the
 * footprint box, at most TP_FOOTPRINT_TRIES draws (a footprint covering 10 % of its box falls
 * back to the receiver's own point 18 % of the time, one covering 30 % 0.3 %; charts of
 * axis-aligned slivers fill their boxes). */
#define TP_FOOTPRINT_TRIES 16
static void footprint_sample(const tp_ctx *c, const bk_receiver *r, tp_rng *pos, tp_origin *g)
{
    const float *bx = r->footprint_box;
    int box = bx[2] > 0 && bx[3] > 0;
    for (int k = 0; k < TP_FOOTPRINT_TRIES; k++) {
        double ps = rng_next(pos), pt = rng_next(pos);
        if (box) {
            ps = bx[0] + ps * bx[2];
            pt = bx[1] + pt * bx[3];
        }
        if (footprint_origin(c, r, ps, pt, g)) return;
    }
}

/* One punctual light at one point, weighted w (1, or 1/p of an accepted culling draw):
 * irradiance (sphere: fluence) and the SH of its incident radiance. Returns the shadow rays. */
static uint64_t punctual_one(const tp_ctx *c, const tp_origin *g, size_t li, const bk_slc_draw *d, double delta,
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
        for (size_t li = 0; li < c->light_count; li++) rays += punctual_one(c, g, li, NULL, 1, e, sh);
        return rays;
    }
    const uint32_t *always;
    size_t na = bk_slc_always(c->slc_recv, &always);
    for (size_t k = 0; k < na; k++) rays += punctual_one(c, g, always[k], NULL, 1, e, sh);
    for (size_t k = 0; k < n; k++) rays += punctual_one(c, g, ids[k], d, delta, e, sh);
    return rays;
}

/* The points at which a receiver's punctual light is evaluated: a texel with a footprint
 * averages its four quarter centres (hard shadow edges resolve to a quarter of a texel). */
static int punctual_points(const tp_ctx *c, const bk_receiver *r, tp_origin g[4])
{
    if (!r->footprint_count) {
        recv_origin(c, r, &g[0]);
        return 1;
    }
    for (int q = 0; q < 4; q++) footprint_origin(c, r, 0.25 + 0.5 * (q & 1), 0.25 + 0.5 * (q >> 1), &g[q]);
    return 4;
}

static void recv_punctual(tp_ctx *c, size_t begin, size_t end, int thread)
{
    /* Without culling, punctual light is noise-free: computed once, then into the outputs /
     * error scalars. */
    uint64_t rays = 0;
    for (size_t i = begin; i < end; i++) {
        const bk_receiver *r = &c->recv[i];
        double e[3] = {0, 0, 0}, sh[3][9];
        memset(sh, 0, sizeof sh);
        tp_origin g[4];
        const int points = punctual_points(c, r, g);
        for (int q = 0; q < points; q++) rays += punctual_at(c, &g[q], NULL, NULL, 0, 1, e, sh);
        for (int a = 0; a < 3; a++) {
            e[a] /= points;
            for (int kk = 0; kk < 9; kk++) sh[a][kk] /= points;
        }
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
                       double solid, int vpl, tp_rng *cont, tp_count *cnt, double L[3], double Ld[3])
{
    for (int a = 0; a < 3; a++) L[a] = Ld[a] = 0;
    if (hit->tri == UINT32_MAX) {
        sky_radiance(c, d, L);
        memcpy(Ld, L, 3 * sizeof(double));
        return -1;
    }
    long hc = hit_cell(c, hit);
    if (hc < 0) return -1; /* black, or the inside of a solid: a receiver there is dark */
    emission_at(c, hit->tri, hit->u, hit->v, Ld);
    if (Ld[0] > 0 || Ld[1] > 0 || Ld[2] > 0) {
        double wg = mis_gather(c, hit, hc, d, 1 / solid);
        for (int a = 0; a < 3; a++) Ld[a] *= wg;
    }
    double r[3];
    int near = near_hit(c, hit, hc, rough);
    if (near) {
        const tp_near_mode md = {sum, rough, 1, TP_NEAR_DEPTH, vpl, NULL, 0};
        near_entry(c, &md, hit, hc, d, cont, cnt, r);
    } else {
        for (int a = 0; a < 3; a++) r[a] = sum[3 * hc + a];
    }
    for (int a = 0; a < 3; a++) L[a] = r[a] + Ld[a];
    return near ? -1 : hc;
}

/* One half of receiver i in this pass: S directions from the shifted lattice, uniform over the
 * hemisphere (texels) or the sphere (probes) — the SH projection needs a pdf that does not
 * vanish at the horizon — each with one light sample when NEE is on. A texel with a footprint
 * starts each ray from its own random point of the footprint. */
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

/* oct: NULL, or the 16 octahedral texels' Σ L·max(0, cos) (an octahedral probe). */
static void recv_half(tp_ctx *c, const bk_receiver *r, size_t i, int h, int S, const tp_lattice *lat,
                      tp_recv_sums *rs, double (*oct)[3], tp_count *cnt)
{
    const float *sum = c->l_sum[h];
    tp_rng rng = rng_make(c->seed, DOM_RECV, (uint64_t)h, (uint64_t)c->pass, 0, i);
    tp_rng cont = rng_make(c->seed, DOM_RECV_NEAR, (uint64_t)h, (uint64_t)c->pass, 0, i);
    tp_rng pos = rng_make(c->seed, DOM_RECV_POS, (uint64_t)h, (uint64_t)c->pass, 0, i);
    tp_rng probe = rng_make(c->seed, DOM_RECV_PROBE, (uint64_t)h, (uint64_t)c->pass, 0, i);
    double s1 = rng_next(&rng), s2 = rng_next(&rng);
    tp_shift shift = lattice_shift(s1, s2);
    tp_origin g0;
    recv_origin(c, r, &g0);
    const int sphere = g0.sphere;
    const double solid = sphere ? 4 * TP_PI : 2 * TP_PI;
    const int pg_kind = sphere ? PG_SPHERE : PG_HEMISPHERE;
    double t1 = 0, t2 = 0;
    if (c->nee) {
        tp_rng nr = rng_make(c->seed, DOM_RECV_NEE, (uint64_t)h, (uint64_t)c->pass, 0, i);
        t1 = rng_next(&nr);
        t2 = rng_next(&nr);
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
                footprint_sample(c, r, &pos, &g);
                bk_onb(g.n, t, b);
            }
            double u1, cp, sp;
            lattice(lat, (uint32_t)(j0 + jj), &shift, &u1, &cp, &sp);
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
                const tp_near_mode md = {sum, c->rough, 1, TP_NEAR_DEPTH, c->vpl && !sphere, NULL, 0};
                near_radiance(c, &md, &hits[jj], hc, dd[jj], 0, &probe, cnt, q);
                double cs = (sphere ? 1 : zz[jj]) * TP_PROBE_EVERY;
                if (bk_finite3(q))
                    for (int a = 0; a < 3; a++) rs->eb[a] += (q[a] - sum[3 * hc + a]) * cs;
            }
            if (!c->nee) continue;
            /* one light sample per gather ray; its value Le·w/p is turned into the gather's
             * units (radiance, later × solid/S) by 1/solid */
            double u0, uu1, ld[3], cl, val[3];
            lattice_uv(lat, (uint32_t)(j0 + jj), t1, t2, &u0, &uu1);
            double ndist = 0, skip[3];
            if (nee_sample_lobe(c, org + 3 * jj, nn[jj], pg_kind, NULL, u0, uu1, &ndist, ld, &cl, val, &cnt->shadow) &&
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
 * the pass) at the receiver's punctual points; an unbiased estimate of what recv_punctual
 * computes. */
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
    const int points = punctual_points(c, r, g);
    uint64_t rays = 0;
    for (int q = 0; q < points; q++) rays += punctual_at(c, &g[q], d, t->ids[h], t->n[h], delta, e, sh);
    *tested += (uint64_t)points * t->n[h];
    for (int a = 0; a < 3; a++) {
        e[a] /= points;
        for (int kk = 0; kk < 9; kk++) sh[a][kk] /= points;
    }
    return rays;
}

static void vpl_lists_init(const tp_ctx *c, int thread, tp_tile_lists *t)
{
    tile_lists_init(c->vpl_ids, c->vpl_cap, thread, t);
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
    const int points = punctual_points(c, r, g);
    tp_rng pr = rng_make(c->seed, DOM_VPL_POINT, (uint64_t)h, (uint64_t)c->pass, 0, i);
    const int q = points > 1 ? (int)(rng_next(&pr) * points) % points : 0;
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

static void recv_gather(tp_ctx *c, size_t begin, size_t end, int thread)
{
    const int S = c->rays;
    const double w = c->pass_weight;
    const bk_transport_output *out = c->out;
    tp_count cnt = {0, 0, 0};
    tp_tile_lists lists;
    slc_lists_init(c, thread, &lists);
    tp_tile_lists vlists;
    vpl_lists_init(c, thread, &vlists);
    uint64_t tested = 0, vtested = 0;
    for (size_t i = begin; i < end; i++) {
        if (!c->blk_on[block_of(c, i)]) continue; /* converged (adaptive sampling) */
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
static void octa_gather(tp_ctx *c, size_t begin, size_t end, int thread)
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
static double octa_finish(tp_ctx *c)
{
    float *out = c->out->octa_irradiance;
    const float inv = (float)(1.0 / c->oct_weight);
    double num = 0, den = 0;
    for (size_t k = 0; k < c->oct_count; k++) {
        tp_origin g;
        origin_from(c, &c->opt->octa_points[3 * k], (const float[3]){0, 0, 0}, &g);
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

/* ---- setup ------------------------------------------------------------------------------------ */

static int online_cores(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 256 ? 256 : (int)n;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void vpl_pass_end(tp_ctx *c);

static void free_ctx(tp_ctx *c)
{
    free(c->cells); free(c->tri_first); free(c->tri_m); free(c->tri_sides); free(c->tri_closed); free(c->tri_cell_h); free(c->tri_edge_eps);
    free(c->tri_le); free(c->tri_le_tex); free(c->em); free(c->em_cdf);
    free(c->gloss); free(c->ggx);
    free(c->thread_shadow);
    free(c->lights);
    for (int h = 0; h < 2; h++) {
        for (int d = 0; d <= TP_CACHE_DEPTH; d++) free(c->l_hist[h][d]);
        free(c->l_cur[h]); free(c->l_sum[h]); free(c->x_acc[h]);
        free(c->b_acc[h]);
    }
    free(c->rough); free(c->gap); free(c->cell_lum); free(c->cell_var);
    free(c->punct_lum);
    free(c->stop_idx);
    free(c->extra);
    free(c->blk_w); free(c->blk_on); free(c->blk_next);
    free(c->thread_rays); free(c->thread_nonfinite);
    lattice_free(&c->lat);
    lattice_free(&c->oct_lat);
    free(c->oct_acc[0]);
    free(c->oct_acc[1]);
    for (int h = 0; h < 2; h++) bk_slc_draw_destroy(c->draw_recv[h]);
    bk_slc_draw_destroy(c->draw_cell);
    bk_slc_destroy(c->slc_recv);
    bk_slc_destroy(c->slc_cell);
    free(c->slc_ids);
    free(c->thread_slc_tested);
    free(c->slc_cdf);
    free(c->slc_pick_ids);
    vpl_pass_end(c);
    bk_slc_destroy(c->vpl_tiles);
    free(c->vpl_ids);
    free(c->light_vpl);
    free(c->thread_vpl_tested);
}

/* Longest edge of triangle i. */
static double tri_longest(const tp_ctx *c, uint32_t i)
{
    double v[3][3], longest = 0;
    tri_vertices(c, i, v);
    for (int e = 0; e < 3; e++) {
        double l2 = 0;
        for (int k = 0; k < 3; k++) l2 += (v[(e + 1) % 3][k] - v[e][k]) * (v[(e + 1) % 3][k] - v[e][k]);
        longest = fmax(longest, sqrt(l2));
    }
    return longest;
}

/* Subdivision m of triangle i for cells of about `size` metres (sized), or of area cell_area
 * (automatic budget); m² sub-triangles per side. */
static int tri_subdivision(const tp_ctx *c, uint32_t i, double size, double cell_area)
{
    double a = bk_tracer_tri_area(c->tracer, i), m = 1;
    if (!(a > 0) || !isfinite(a)) return 1;
    if (size > 0) {
        /* square-ish cells of the wanted size; slivers split along their length too */
        m = fmax(ceil(sqrt(a) / size), ceil(tri_longest(c, i) / (2 * size)));
    } else if (cell_area > 0) {
        m = floor(sqrt(a / cell_area));
    }
    return m < 1 ? 1 : m > TP_MAX_SUB ? TP_MAX_SUB : (int)m;
}

/* Cells per triangle: sized triangles (options.cell_size, e.g. the lightmap's texel size: the
 * cache then resolves light as finely as the lightmap stores it) and the rest sharing max_cells
 * by area; if everything exceeds TP_CELL_CAP the sizes grow uniformly until it fits. */
static lbk_result size_cells(tp_ctx *c, size_t *count_out)
{
    const bk_scene *s = c->scene;
    const float *want = c->opt->cell_size;
    size_t nt = s->tri_count;
    size_t max_cells = c->opt->max_cells > 0 ? (size_t)c->opt->max_cells : 32768;
    double auto_area = 0;
    for (size_t i = 0; i < nt; i++) {
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        int ds = mi < s->material_count ? s->materials[mi].double_sided : 0;
        /* a closed solid's back side is its inside: never seen, no cells */
        c->tri_sides[i] = ds && !c->tri_closed[i] ? 2 : 1;
        if (!(want && want[i] > 0 && isfinite(want[i])))
            auto_area += (double)bk_tracer_tri_area(c->tracer, (uint32_t)i) * c->tri_sides[i];
    }
    double cell_area = auto_area > 0 ? auto_area / (double)max_cells : 0;
    for (double grow = 1;; grow *= 1.25) {
        size_t count = 0;
        for (size_t i = 0; i < nt; i++) {
            double size = want && want[i] > 0 && isfinite(want[i]) ? want[i] * grow : 0;
            int m = tri_subdivision(c, (uint32_t)i, size, cell_area * grow * grow);
            c->tri_m[i] = (uint16_t)m;
            c->tri_first[i] = (uint32_t)(count < UINT32_MAX ? count : UINT32_MAX);
            count += (size_t)c->tri_sides[i] * (size_t)m * (size_t)m;
        }
        if (count <= TP_CELL_CAP) { *count_out = count; return LBK_OK; }
        if (grow > 1e6) return LBK_ERR_LIMIT;
    }
}

/* The glossy cells' storage and the coupling's table, only when a triangle's material is glossy
 * (a scene without one runs exactly the Lambertian code). */
static lbk_result gloss_init(tp_ctx *c)
{
    const bk_scene *s = c->scene;
    int any = 0;
    for (size_t i = 0; i < s->tri_count && !any; i++) {
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        any = mi < s->material_count && bk_material_glossy(&s->materials[mi]);
    }
    if (!any) return LBK_OK;
    c->gloss = calloc(c->cell_count ? c->cell_count : 1, sizeof *c->gloss);
    c->ggx = malloc(sizeof *c->ggx);
    if (!c->gloss || !c->ggx) return LBK_ERR_OUT_OF_MEMORY;
    bk_ggx_table_init(c->ggx);
    return LBK_OK;
}

/* A glossy material's cell at uv: base colour = the (hooked) albedo, metallic and roughness =
 * factor × texture (B, G); the cell's Lambertian albedo (what a read of its cache reflects,
 * where a chain of continuations ends on it) becomes the coupled BSDF's mean albedo. A cell the
 * hook made black (a closed door in a set run) stays black and Lambertian. */
static void cell_gloss(const tp_ctx *c, const bk_material *mat, const double uv[2], float albedo[3], tp_gloss *gl)
{
    if (albedo[0] <= 0 && albedo[1] <= 0 && albedo[2] <= 0) return;
    double mr[3] = {1, 1, 1};
    if (mat->metal_rough_tex1 > 0)
        bk_sample_image(bk_scene_image(c->scene, mat->metal_rough_tex1 - 1), uv[0], uv[1], mr);
    double metal = mat->metallic * mr[2], rough = mat->roughness * mr[1];
    gl->metallic = (float)(isfinite(metal) ? fmin(fmax(metal, 0), 1) : 0);
    gl->roughness = (float)(isfinite(rough) ? fmin(fmax(rough, 0), 1) : 1);
    double base[3] = {albedo[0], albedo[1], albedo[2]}, mean[3];
    bk_mr_albedo_mean(c->ggx, base, gl->metallic, gl->roughness, mean);
    for (int k = 0; k < 3; k++) {
        gl->base[k] = albedo[k];
        albedo[k] = (float)fmin(fmax(mean[k], 0), 0.999);
    }
    gl->on = 1;
}

static lbk_result build_cells(tp_ctx *c)
{
    const bk_scene *s = c->scene;
    size_t nt = s->tri_count;
    c->tri_first = calloc(nt ? nt : 1, sizeof *c->tri_first);
    c->tri_m = calloc(nt ? nt : 1, sizeof *c->tri_m);
    c->tri_sides = calloc(nt ? nt : 1, 1);
    c->tri_closed = calloc(nt ? nt : 1, 1);
    c->tri_edge_eps = calloc(nt ? nt : 1, sizeof(float));
    c->tri_cell_h = calloc(nt ? nt : 1, sizeof(float));
    c->tri_le = calloc(3 * (nt ? nt : 1), sizeof(float));
    c->tri_le_tex = calloc(nt ? nt : 1, sizeof(int32_t));
    if (!c->tri_first || !c->tri_m || !c->tri_sides || !c->tri_closed || !c->tri_edge_eps || !c->tri_cell_h ||
        !c->tri_le || !c->tri_le_tex)
        return LBK_ERR_OUT_OF_MEMORY;
    lbk_result r = bk_closed_triangles(s, c->tri_closed);
    if (r != LBK_OK) return r;
    size_t count = 0;
    r = size_cells(c, &count);
    if (r != LBK_OK) return r;
    for (size_t i = 0; i < nt; i++) {
        /* keep sample points >= 8 ulps of the coordinates inside every edge (the tracer's edge
         * limitation, tracer.h): a barycentric floor of 8 ulp / altitude */
        double a = bk_tracer_tri_area(c->tracer, (uint32_t)i), longest = tri_longest(c, (uint32_t)i);
        double alt = longest > 0 ? 2 * a / longest : 0;
        double ulp = bk_tracer_tri_scale(c->tracer, (uint32_t)i) * 1.1920928955078125e-07;
        double eps = alt > 0 && isfinite(alt) ? 8 * ulp / alt : 0;
        c->tri_edge_eps[i] = (float)(eps > 0.3 ? 0.3 : eps);
        int m = c->tri_m[i];
        double h = fmax(longest / m, sqrt(2 * a) / m);
        c->tri_cell_h[i] = (float)(isfinite(h) ? h : 0);
    }
    c->cell_count = count;
    c->cells = calloc(count ? count : 1, sizeof *c->cells);
    if (!c->cells) return LBK_ERR_OUT_OF_MEMORY;
    r = gloss_init(c);
    if (r != LBK_OK) return r;
    for (size_t i = 0; i < nt; i++) {
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        const bk_material *mat = mi < s->material_count ? &s->materials[mi] : NULL;
        uint32_t oi = s->tri_object ? s->tri_object[i] : 0;
        const char *set = (oi < s->object_count) ? s->objects[oi].light_set : "";
        int emits = in_light_set(c, set);
        float n[3];
        bk_tracer_tri_normal(c->tracer, (uint32_t)i, n);
        float area = bk_tracer_tri_area(c->tracer, (uint32_t)i);
        int m = c->tri_m[i];
        c->tri_le_tex[i] = -1;
        if (mat && emits && area > 0) {
            for (int k = 0; k < 3; k++) {
                double em = mat->emission[k];
                c->tri_le[3 * i + k] = (float)(isfinite(em) && em > 0 ? em : 0);
            }
            if (mat->emission_tex >= 0 && bk_scene_image(s, mat->emission_tex)) c->tri_le_tex[i] = mat->emission_tex;
        }
        for (long sub = 0; sub < (long)m * m; sub++) {
            /* material values at the cell's centroid (uv0) */
            int j = sub_row(m, sub);
            long ss = sub - (long)j * (2 * m - j);
            int ii = (int)(ss / 2), up = (int)(ss & 1);
            double cu = up ? (3.0 * ii + 2) / (3.0 * m) : (3.0 * ii + 1) / (3.0 * m);
            double cv = up ? (3.0 * j + 2) / (3.0 * m) : (3.0 * j + 1) / (3.0 * m);
            double uv[2];
            bk_tri_uv0(s, (uint32_t)i, cu, cv, uv);
            float albedo[3] = {0, 0, 0}, le[3] = {0, 0, 0};
            if (mat) {
                double al[3], em[3];
                bk_material_albedo(s, mat, uv, al);
                bk_material_emission(s, mat, uv, em);
                for (int k = 0; k < 3; k++) {
                    albedo[k] = (float)al[k];
                    le[k] = emits ? (float)em[k] : 0;
                }
            }
            if (c->opt->albedo_hook) {
                c->opt->albedo_hook(c->opt->user, (uint32_t)i, albedo);
                for (int k = 0; k < 3; k++)
                    albedo[k] = isfinite(albedo[k]) ? (albedo[k] < 0 ? 0 : albedo[k] > 0.999f ? 0.999f : albedo[k]) : 0;
            }
            tp_gloss gl;
            memset(&gl, 0, sizeof gl);
            if (c->gloss && mat && bk_material_glossy(mat)) cell_gloss(c, mat, uv, albedo, &gl);
            for (int side = 0; side < c->tri_sides[i]; side++) {
                if (gl.on) c->gloss[c->tri_first[i] + (size_t)side * m * m + sub] = gl;
                tp_cell *cell = &c->cells[c->tri_first[i] + (size_t)side * m * m + sub];
                cell->tri = (uint32_t)i;
                cell->sub = (uint32_t)sub;
                cell->m = (uint16_t)m;
                cell->side = (uint8_t)side;
                for (int k = 0; k < 3; k++) cell->n[k] = side ? -n[k] : n[k];
                cell->area = area / (float)(m * m);
                memcpy(cell->albedo, albedo, sizeof albedo);
                memcpy(cell->le, le, sizeof le);
            }
        }
    }
    return LBK_OK;
}

/* The light-sampling distribution: every emitting sub-triangle with probability proportional
 * to its power area·bk_lum(Le) (Le at its centroid, as the cells carry it), a point uniform on it.
 * A point's density per unit area is then bk_lum(Le_cell)/P_total, stored in both side cells so a
 * gather hit can weigh itself against it. */
static lbk_result build_emitters(tp_ctx *c)
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

/* ---- the run ---------------------------------------------------------------------------------- */

/* Footprint ranges inside options.footprint, triangles and their vertices inside the footprint
 * scene, finite maps. */
static int footprints_valid(const bk_scene *scene, const bk_transport_options *opt, const bk_receiver *r, size_t n)
{
    const bk_scene *fs = opt->footprint_scene ? opt->footprint_scene : scene;
    for (size_t i = 0; i < n; i++) {
        if (!r[i].footprint_count) continue;
        if (!opt->footprint || r[i].footprint_first > opt->footprint_count ||
            r[i].footprint_count > opt->footprint_count - r[i].footprint_first)
            return 0;
    }
    for (size_t k = 0; k < (opt->footprint ? opt->footprint_count : 0); k++) {
        const bk_footprint_tri *f = &opt->footprint[k];
        if (f->tri >= fs->tri_count || !fs->tris || !fs->positions) return 0;
        for (int v = 0; v < 3; v++)
            if (fs->tris[3 * (size_t)f->tri + v] >= fs->vertex_count) return 0;
        for (int a = 0; a < 2; a++)
            for (int b = 0; b < 3; b++)
                if (!isfinite(f->uv[a][b])) return 0;
    }
    return 1;
}

static lbk_result check_inputs(const bk_scene *scene, const bk_tracer *tracer, const bk_receiver *receivers,
                               size_t count, const bk_transport_options *opt, const bk_transport_output *output)
{
    if (!scene || !tracer || !output || (count > 0 && (!receivers || !output->radiance))) return LBK_ERR_INVALID_ARGUMENT;
    if (bk_tracer_tri_count(tracer) != scene->tri_count) return LBK_ERR_INVALID_ARGUMENT;
    if (scene->tri_count > 0 && !scene->tris) return LBK_ERR_INVALID_ARGUMENT;
    for (size_t i = 0; i < count; i++) {
        const bk_receiver *r = &receivers[i];
        for (int k = 0; k < 3; k++)
            if (!isfinite(r->position[k]) || !isfinite(r->normal[k])) return LBK_ERR_INVALID_ARGUMENT;
    }
    const size_t *end = opt->class_end;
    if (end[BK_RECEIVER_CLASSES - 1] && (end[BK_RECEIVER_CLASSES - 1] != count || end[0] > end[1] || end[1] > end[2]))
        return LBK_ERR_INVALID_ARGUMENT;
    return footprints_valid(scene, opt, receivers, count) ? LBK_OK : LBK_ERR_INVALID_ARGUMENT;
}

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
            recv_origin(c, &c->recv[i], &g);
        } else {
            tp_cell_geom cg;
            double p[3];
            cell_geom(c, &c->cells[i], &cg);
            cell_point_at(&cg, 0.5, 0.5, p, NULL, NULL);
            float pf[3] = {(float)p[0], (float)p[1], (float)p[2]};
            origin_from(c, pf, c->cells[i].n, &g);
        }
        double e[3] = {0, 0, 0};
        for (size_t li = 0; li < c->light_count; li++)
            if (c->lights[li]->type != BK_LIGHT_DIRECTIONAL) punctual_one(c, &g, li, NULL, 1, e, sh);
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
        int points = punctual_points(c, &c->recv[i], g);
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
        cell_geom(c, &c->cells[ci], &g);
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
static lbk_result slc_init(tp_ctx *c)
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

/* ---- glossy VPLs (VPL.md "In the transport") ------------------------------------------------ */

/* The surface a photon lands on, as the transport sees it: the hit's cell; glossy cells give
 * their specular lobe only (F0 = lerp(0.04, base, metallic), α = roughness²: bk_mr_lobe's),
 * everything else (Lambertian, black, the inside of a solid) makes no VPL: diffuse bounces are
 * the cache's. */
static int vpl_material(void *user, const bk_hit *hit, const double x[3], bk_vpl_material *m)
{
    (void)x;
    const tp_ctx *c = (const tp_ctx *)user;
    const long hc = hit_cell(c, hit);
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
                                c->threads, mix64(((uint64_t)DOM_VPL_SHOOT << 56) ^ ((uint64_t)h << 48) ^
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
static lbk_result vpl_pass(tp_ctx *c, int pass)
{
    for (int h = 0; h < 2; h++) {
        lbk_result res = vpl_shoot_all(c, h, pass);
        if (res != LBK_OK) return res;
        c->vpl_made += c->vpl_n[h];
        double *xi = malloc((c->vpl_n[h] ? c->vpl_n[h] : 1) * sizeof *xi);
        if (!xi) return LBK_ERR_OUT_OF_MEMORY;
        for (size_t k = 0; k < c->vpl_n[h]; k++) {
            tp_rng r = rng_make(c->seed, DOM_VPL_XI, (uint64_t)h, (uint64_t)pass, 0, k);
            xi[k] = rng_next(&r);
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

static void vpl_pass_end(tp_ctx *c)
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
        const int points = punctual_points(c, r, g);
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
static lbk_result vpl_init(tp_ctx *c)
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
    vpl_pass_end(c);
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

/* How many continuations in a row a near hit in the cache's bounces may take: TP_CACHE_DEPTH
 * while the bounce history fits TP_CACHE_HIST_BYTES, fewer on caches of millions of cells (at
 * least 1, as before gap cells: TRANSPORT.md). It depends on the cell count only, so every unit of a
 * distributed bake and every resumed run picks the same. */
#define TP_CACHE_HIST_BYTES ((size_t)256 << 20)
static int cache_depth_for(size_t cells)
{
    size_t per = 2 * 3 * sizeof(float) * (cells ? cells : 1); /* one bounce, both halves */
    size_t fit = TP_CACHE_HIST_BYTES / per;
    if (fit < 2) return 1;
    return fit - 1 > TP_CACHE_DEPTH ? TP_CACHE_DEPTH : (int)(fit - 1);
}

/* Everything a run needs before its first pass: counters, the light selection, cells,
 * emitters, the per-half radiance arrays and the receivers' accumulators. */
static lbk_result ctx_init(tp_ctx *c)
{
    const bk_scene *scene = c->scene;
    const bk_transport_options *opt = c->opt;
    c->thread_rays = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_nonfinite = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_shadow = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_slc_tested = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_vpl_tested = calloc((size_t)c->threads, sizeof(uint64_t));
    if (!c->thread_rays || !c->thread_nonfinite || !c->thread_shadow || !c->thread_slc_tested || !c->thread_vpl_tested)
        return LBK_ERR_OUT_OF_MEMORY;
    /* scale of the coordinates: offsets for receivers, which carry no triangle */
    for (size_t i = 0; i < scene->tri_count; i++) {
        float sc = bk_tracer_tri_scale(c->tracer, (uint32_t)i);
        if (sc > c->scene_scale) c->scene_scale = sc;
    }
    const int base_bake = !(opt->light_set && opt->light_set[0]);
    c->use_sky = base_bake && !opt->no_sky;
    if (!opt->no_punctual && scene->light_count) {
        c->lights = calloc(scene->light_count, sizeof *c->lights);
        if (!c->lights) return LBK_ERR_OUT_OF_MEMORY;
        for (size_t i = 0; i < scene->light_count; i++)
            if (in_light_set(c, scene->lights[i].light_set)) c->lights[c->light_count++] = &scene->lights[i];
    }
    lbk_result res = build_cells(c);
    if (res == LBK_OK) res = build_emitters(c);
    if (res == LBK_OK) res = slc_init(c);
    if (res == LBK_OK) res = vpl_init(c);
    if (res != LBK_OK) return res;
    size_t nc = c->cell_count ? c->cell_count : 1, n = c->recv_count ? c->recv_count : 1;
    c->cache_depth = cache_depth_for(nc);
    for (int h = 0; h < 2; h++) {
        for (int d = 0; d <= c->cache_depth; d++)
            if (!(c->l_hist[h][d] = calloc(3 * nc, sizeof(float)))) return LBK_ERR_OUT_OF_MEMORY;
        c->l_cur[h] = calloc(3 * nc, sizeof(float));
        c->l_sum[h] = calloc(3 * nc, sizeof(float));
        c->x_acc[h] = calloc(n, sizeof(double));
        c->b_acc[h] = calloc(n, sizeof(double));
        if (!c->l_cur[h] || !c->l_sum[h] || !c->x_acc[h] || !c->b_acc[h])
            return LBK_ERR_OUT_OF_MEMORY;
    }
    c->rough = calloc(nc, 1);
    c->gap = calloc(nc, 1);
    c->cell_lum = calloc(nc, sizeof(float));
    c->cell_var = calloc(nc, sizeof(float));
    if (!c->rough || !c->gap || !c->cell_lum || !c->cell_var) return LBK_ERR_OUT_OF_MEMORY;
    parallel_for(c, c->cell_count, 256, mark_gaps);
    for (size_t i = 0; i < c->cell_count; i++) c->rough[i] = c->gap[i] != 0; /* pass 0's marks, as mark_rough's */
    for (int h = 0; h < 2 && c->oct_count; h++)
        if (!(c->oct_acc[h] = calloc(16 * c->oct_count, sizeof(double)))) return LBK_ERR_OUT_OF_MEMORY;
    for (uint32_t t = 0; t < 16; t++) {
        float d[3];
        lbk_oct_texel_direction(4, t % 4, t / 4, d);
        for (int a = 0; a < 3; a++) c->oct_dir[t][a] = d[a];
    }
    c->punct_lum = calloc(n, sizeof(float));
    return c->punct_lum ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
}

/* Non-zero when the caller's progress callback asks to stop (LBK_ERR_CANCELLED). */
static int report_progress(const tp_ctx *c, const char *phase, double done_spp)
{
    const bk_transport_options *opt = c->opt;
    if (!opt->progress) return 0;
    double f = fmax(done_spp / c->max_samples, opt->time_limit > 0 ? (now_seconds() - c->t0) / opt->time_limit : 0);
    return opt->progress(opt->user, phase, f > 1 ? 1 : f);
}

/* Cache rays per cell and bounce in pass p: about as many as the active receivers trace this pass
 * (over ~4 bounces), within [min(4·2^(p/2), cap), cap], cap = cache_rays·2^p; both estimates
 * shrink together. */
static int pass_cache_rays(const tp_ctx *c, int pass, size_t active)
{
    int sp = pass < 20 ? pass : 20;
    double nc = c->cell_count ? (double)c->cell_count : 1;
    double cap = fmin((double)(c->opt->cache_rays > 0 ? c->opt->cache_rays : 16) * ldexp(1.0, sp), 65536.0);
    double lo = fmin(cap, 4.0 * ldexp(1.0, sp / 2));
    double want = ceil((double)c->s0 * ldexp(1.0, sp) * (double)active / (4.0 * nc));
    return (int)fmax(lo, fmin(cap, want));
}

/* ---- the stop rule's receivers (TRANSPORT.md §Stop subset) -------------------------------- */

/* Class k's stop subset when it has more than `cap` blocks: one block per stratum of n/cap
 * consecutive ones, at an offset hashed from (class, stratum) (no seed: the subset is the
 * layout's, not the noise's). Receivers lie in atlas / probe order, so strata spread the subset
 * over the whole level and the hash keeps it off any row pattern. Whole blocks, so that a unit
 * of a distributed run that gathers them decides their adaptive stops as the whole run does.
 * Returns the block's offset in the class; n > cap. */
static size_t stop_pick(size_t n, size_t cap, int k, size_t j)
{
    const size_t q = n / cap, r = n % cap; /* strata of q + 1 blocks first, then of q */
    const size_t lo = j * q + (j < r ? j : r), len = q + (j < r);
    return lo + (size_t)(mix64(0x5707A11D00000000ull ^ ((uint64_t)k << 40) ^ (uint64_t)j) % len);
}

/* The subsets, and the receivers the rule reads outside [g_begin, g_end) (those of every class
 * only when the run has a target and is cut). */
static lbk_result stop_init(tp_ctx *c)
{
    const size_t cap = c->opt->stop_receivers > 0 ? c->opt->stop_receivers : BK_TRANSPORT_STOP_RECEIVERS;
    const size_t capb = cap / BK_TRANSPORT_BLOCK > 0 ? cap / BK_TRANSPORT_BLOCK : 1;
    const int cut = c->target > 0 && (c->g_begin != 0 || c->g_end != c->recv_count);
    size_t subs = 0, extras = 0;
    for (int k = 0; k < c->ncls; k++) {
        const size_t nb = c->blk_first[k + 1] - c->blk_first[k];
        c->stop_sub[k] = nb > capb;
        subs += nb > capb ? capb * BK_TRANSPORT_BLOCK : 0;
        extras += nb > capb ? capb * BK_TRANSPORT_BLOCK : c->cls[k].end - c->cls[k].begin;
    }
    c->stop_idx = malloc((subs ? subs : 1) * sizeof *c->stop_idx);
    c->extra = malloc((cut && extras ? extras : 1) * sizeof *c->extra);
    if (!c->stop_idx || !c->extra) return LBK_ERR_OUT_OF_MEMORY;
    size_t ns = 0, ne = 0;
    for (int k = 0; k < c->ncls; k++) {
        const size_t b0 = c->blk_first[k], nb = c->blk_first[k + 1] - b0;
        c->stop_first[k] = ns, c->extra_first[k] = ne;
        for (size_t j = 0; j < (c->stop_sub[k] ? capb : nb); j++) {
            size_t lo, hi;
            block_range(c, k, b0 + (c->stop_sub[k] ? stop_pick(nb, capb, k, j) : j), &lo, &hi);
            for (size_t i = lo; i < hi; i++) {
                if (c->stop_sub[k]) c->stop_idx[ns++] = i;
                if (cut && (i < c->g_begin || i >= c->g_end)) c->extra[ne++] = i;
            }
        }
    }
    for (int k = c->ncls; k <= BK_RECEIVER_CLASSES; k++) c->stop_first[k] = ns, c->extra_first[k] = ne;
    return LBK_OK;
}

/* Class k's receivers that sample in this pass (class_on) and, with adaptive sampling, their
 * mean samples so far (mean_samples): over its stop subset where it has one (scaled to the
 * class), so that every unit of a distributed run counts alike without the other units' blocks. */
static size_t class_on(const tp_ctx *c, int k)
{
    const size_t n = c->cls[k].end - c->cls[k].begin;
    if (c->stop_sub[k]) {
        const size_t all = c->stop_first[k + 1] - c->stop_first[k];
        size_t on = 0;
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++) on += c->blk_on[block_of(c, c->stop_idx[p])];
        return all ? (size_t)((uint64_t)n * on / all) : n;
    }
    size_t on = 0;
    for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
        size_t lo, hi;
        block_range(c, k, b, &lo, &hi);
        if (c->blk_on[b]) on += hi - lo;
    }
    return on;
}

/* (its spp scaled by its blocks' share of its weight: the samples of pass p are 2^p those of
 * pass 0, as its weight is) */
static double mean_samples(const tp_ctx *c, int k)
{
    const tp_class *cl = &c->cls[k];
    if (!c->adapt || k >= c->ncls || !(cl->weight_sum > 0)) return cl->spp;
    double sum = 0, n = 0;
    if (c->stop_sub[k])
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++) sum += c->blk_w[block_of(c, c->stop_idx[p])], n++;
    else
        for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
            size_t lo, hi;
            block_range(c, k, b, &lo, &hi);
            sum += (double)(hi - lo) * c->blk_w[b], n += (double)(hi - lo);
        }
    return n > 0 ? cl->spp * sum / (n * cl->weight_sum) : cl->spp;
}

static size_t active_receivers(const tp_ctx *c)
{
    size_t active = 0;
    for (int k = 0; k < c->ncls; k++)
        if (c->cls[k].active) active += class_on(c, k);
    return active;
}

static void extra_gather(tp_ctx *c, size_t begin, size_t end, int thread)
{
    for (size_t p = begin; p < end; p++) recv_gather(c, c->extra[p], c->extra[p] + 1, thread);
}

static void extra_punctual(tp_ctx *c, size_t begin, size_t end, int thread)
{
    for (size_t p = begin; p < end; p++) recv_punctual(c, c->extra[p], c->extra[p] + 1, thread);
}

static void count_totals(const tp_ctx *c, uint64_t t[3]);

/* fn over class k's extra receivers; what they trace goes to the extra counters. */
static void extra_run(tp_ctx *c, int k, tp_fn fn)
{
    const size_t b = c->extra_first[k], e = c->extra_first[k + 1];
    if (b == e) return;
    uint64_t before[3], after[3];
    count_totals(c, before);
    parallel_range(c, b, e, 16, fn);
    count_totals(c, after);
    c->extra_rays += after[0] - before[0];
    c->extra_shadow += after[1] - before[1];
    c->extra_nonfinite += after[2] - before[2];
}

/* One pass: both halves' caches, then the final gather at the receivers (in blocks, so
 * progress can be reported). */
static void count_totals(const tp_ctx *c, uint64_t t[3])
{
    t[0] = t[1] = t[2] = 0;
    for (int k = 0; k < c->threads; k++) {
        t[0] += c->thread_rays[k];
        t[1] += c->thread_shadow[k];
        t[2] += c->thread_nonfinite[k];
    }
}

/* After a pass of weight w: the blocks that sampled in it, of the classes that did. */
static void add_block_weights(tp_ctx *c, double w)
{
    for (int k = 0; k < c->ncls; k++)
        for (size_t b = c->blk_first[k]; c->cls[k].active && b < c->blk_first[k + 1]; b++)
            if (c->blk_on[b]) c->blk_w[b] += w;
}

static lbk_result run_pass(tp_ctx *c, int pass, tp_chain_result chain[2])
{
    const size_t active = active_receivers(c);
    int cache_rays = pass_cache_rays(c, pass, active);
    for (int h = 0; h < 2; h++) {
        uint64_t before[3], after[3];
        count_totals(c, before);
        chain[h] = run_chain(c, h, pass, cache_rays, c->tail_tol, c->max_bounces);
        count_totals(c, after);
        c->cache_rays += after[0] - before[0];
        c->cache_shadow += after[1] - before[1];
        c->cache_nonfinite += after[2] - before[2];
        if (chain[h].bounces < 0) return LBK_ERR_OUT_OF_MEMORY;
        if (report_progress(c, "cache", c->spp)) return LBK_ERR_CANCELLED;
    }
    c->pass = pass;
    c->rays = c->s0 << (pass < 20 ? pass : 20);
    if (lattice_init(&c->lat, (uint32_t)c->rays) != LBK_OK) return LBK_ERR_OUT_OF_MEMORY;
    c->pass_weight = ldexp(1.0, pass);
    for (int h = 0; h < 2 && c->slc; h++)
        if (slc_draw(c, DOM_SLC_RECV, h, pass, c->slc_recv, &c->draw_recv[h]) != LBK_OK) return LBK_ERR_OUT_OF_MEMORY;
    if (c->vpl) {
        lbk_result res = vpl_pass(c, pass);
        if (res != LBK_OK) return res;
    }
    size_t all = 0, done = 0;
    for (int k = 0; k < c->ncls; k++)
        if (c->cls[k].active) all += c->cls[k].end - c->cls[k].begin;
    const size_t block = all / 8 + 1;
    for (int k = 0; k < c->ncls; k++) {
        if (!c->cls[k].active) continue;
        for (size_t b = c->cls[k].begin; b < c->cls[k].end; b += block) {
            size_t e = b + block < c->cls[k].end ? b + block : c->cls[k].end;
            /* a distributed run gathers only its own receivers; each receiver's result depends
             * on nothing but its own streams, so the cut changes no value */
            size_t gb = b > c->g_begin ? b : c->g_begin, ge = e < c->g_end ? e : c->g_end;
            if (gb < ge) parallel_range(c, gb, ge, 16, recv_gather);
            done += e - b;
            if (report_progress(c, "gather", c->spp + 2.0 * c->rays * (double)done / (double)(all ? all : 1)))
                return LBK_ERR_CANCELLED;
        }
    }
    for (int k = 0; k < c->ncls; k++)
        if (c->cls[k].active) extra_run(c, k, extra_gather);
    for (int h = 0; h < 2; h++) {
        bk_slc_draw_destroy(c->draw_recv[h]);
        c->draw_recv[h] = NULL;
    }
    vpl_pass_end(c);
    if (c->oct_count) {
        const int f = c->opt->octa_ray_factor > 0 ? c->opt->octa_ray_factor : 4;
        c->oct_rays = c->rays * (f > 64 ? 64 : f);
        if (lattice_init(&c->oct_lat, (uint32_t)c->oct_rays) != LBK_OK) return LBK_ERR_OUT_OF_MEMORY;
        parallel_range(c, 0, c->oct_count, 1, octa_gather);
        c->oct_total += 2.0 * c->oct_rays;
    }
    c->oct_weight += c->pass_weight;
    for (int k = 0; k < c->ncls; k++) {
        if (!c->cls[k].active) continue;
        c->cls[k].weight_sum += c->pass_weight;
        c->cls[k].spp += 2.0 * c->rays;
        if (c->cls[k].spp > c->spp) c->spp = c->cls[k].spp;
    }
    add_block_weights(c, c->pass_weight);
    mark_rough(c);
    return LBK_OK;
}

/* The noise estimate per receiver class (options.class_end) and for the probes together. */
typedef struct tp_errors {
    double cls[BK_RECEIVER_CLASSES];
    double probe;
} tp_errors;

/* The error estimates after a pass (TRANSPORT.md): the noise from the two independent halves
 * (all receivers, and per class), and the cache's bias from the probes, whose two halves'
 * product is an unbiased estimate of each receiver's squared bias. Relative to the RMS of the
 * receivers' values. */

static void estimate_error_of(const tp_ctx *c, double *const x_acc[2], double *const b_acc[2], double *noise,
                              double *bias, tp_errors *ce)
{
    double num = 0, den = 0, bb = 0, cnum[BK_RECEIVER_CLASSES] = {0}, cden[BK_RECEIVER_CLASSES] = {0};
    for (int k = 0; k < c->ncls; k++) {
        for (size_t blk = c->blk_first[k]; blk < c->blk_first[k + 1]; blk++) {
            if (!(c->blk_w[blk] > 0)) continue;
            const double inv = 1 / c->blk_w[blk];
            size_t lo, hi;
            block_range(c, k, blk, &lo, &hi);
            for (size_t i = lo; i < hi; i++) {
                double a = x_acc[0][i] * inv, b = x_acc[1][i] * inv;
                double m = 0.5 * (a + b), v = 0.25 * (a - b) * (a - b);
                cnum[k] += v;
                cden[k] += m * m;
                bb += (b_acc[0][i] * inv) * (b_acc[1][i] * inv);
            }
        }
        num += cnum[k];
        den += cden[k];
    }
    *noise = den > 0 ? sqrt(num / den) : 0;
    *bias = den > 0 && bb > 0 ? sqrt(bb / den) : 0;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) ce->cls[k] = cden[k] > 0 ? sqrt(cnum[k] / cden[k]) : 0;
    ce->probe = cden[1] + cden[2] > 0 ? sqrt((cnum[1] + cnum[2]) / (cden[1] + cden[2])) : 0;
}

static void estimate_error(const tp_ctx *c, double *noise, double *bias, tp_errors *ce)
{
    estimate_error_of(c, c->x_acc, c->b_acc, noise, bias, ce);
}

/* The estimate the stop rule reads: the class's own (ce) where it stops on all its receivers,
 * else the same sums over its subset. */
static void stop_errors(const tp_ctx *c, const tp_errors *ce, tp_errors *sce)
{
    *sce = *ce;
    for (int k = 0; k < c->ncls; k++) {
        if (!c->stop_sub[k] || !(c->cls[k].weight_sum > 0)) continue;
        double num = 0, den = 0;
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++) {
            const size_t i = c->stop_idx[p];
            const double w = c->blk_w[block_of(c, i)], inv = w > 0 ? 1 / w : 0;
            double a = c->x_acc[0][i] * inv, b = c->x_acc[1][i] * inv, m = 0.5 * (a + b);
            num += 0.25 * (a - b) * (a - b);
            den += m * m;
        }
        sce->cls[k] = den > 0 ? sqrt(num / den) : 0;
    }
}

/* The mean over class k's receivers (its stop subset where it has one) of m², m the mean of a
 * receiver's two halves. */
static double class_mean_square(const tp_ctx *c, int k, double *const x_acc[2])
{
    double den = 0, n = 0;
    if (c->stop_sub[k])
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++) {
            const size_t i = c->stop_idx[p];
            const double w = c->blk_w[block_of(c, i)], m = w > 0 ? 0.5 * (x_acc[0][i] + x_acc[1][i]) / w : 0;
            den += m * m, n++;
        }
    else
        for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
            const double inv = c->blk_w[b] > 0 ? 1 / c->blk_w[b] : 0;
            size_t lo, hi;
            block_range(c, k, b, &lo, &hi);
            for (size_t i = lo; i < hi; i++) {
                const double m = 0.5 * (x_acc[0][i] + x_acc[1][i]) * inv;
                den += m * m, n++;
            }
        }
    return n > 0 ? den / n : 0;
}

/* Adaptive sampling, after pass `pass`: which blocks sample in the next one. A block goes on
 * while its noise per receiver (its halves' difference, v) exceeds what the target allows the
 * class's mean receiver, target² · S with S the class's mean square: once every block is below,
 * so is the class, and until then the samples go to the blocks that hold the error (in the
 * class's own metric, so dark blocks stop first; TRANSPORT.md §Adaptive sampling has what was
 * measured against a relative rule). A pure function of the accumulators, the weights and S
 * (over the stop subset where the class has one), so a unit of a distributed run, the merge's
 * replay and a resumed run decide alike; a block that falls behind as S changes comes back. A
 * block without light (or outside a unit's receivers: never gathered there) stops. */
static void adapt_mark(tp_ctx *c, int pass, double *const x_acc[2])
{
    if (!c->adapt) return;
    for (int k = 0; k < c->ncls; k++) {
        const size_t b0 = c->blk_first[k], nb = c->blk_first[k + 1] - b0;
        if (pass < BK_TRANSPORT_ADAPT_PASS) {
            memset(c->blk_next + b0, 1, nb);
            continue;
        }
        const double allow = c->target * c->target * class_mean_square(c, k, x_acc);
        for (size_t blk = b0; blk < b0 + nb; blk++) {
            const double inv = c->blk_w[blk] > 0 ? 1 / c->blk_w[blk] : 0;
            size_t lo, hi;
            block_range(c, k, blk, &lo, &hi);
            double num = 0;
            for (size_t i = lo; i < hi; i++) {
                const double d = (x_acc[0][i] - x_acc[1][i]) * inv;
                num += 0.25 * d * d;
            }
            c->blk_next[blk] = num > allow * (double)(hi - lo);
        }
    }
}

/* Class k's blocks that sample in the next pass (its probes' only once the texels have stopped,
 * as for the target below); 0 when none does: the class has reached its target. The merge's
 * replay calls it with the classes that sampled in the next pass active, as stop_after left them. */
static int adapt_apply(tp_ctx *c, int k)
{
    size_t on = 0;
    for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
        if (c->adapt && (k == 0 || !c->cls[0].active)) c->blk_on[b] = c->blk_next[b];
        on += c->blk_on[b];
    }
    return on > 0;
}

/* Which classes stop after this pass: a class whose estimate reached the target, or whose next
 * pass would pass the sample budget; every class when the next pass (about twice the cost of
 * this one) could not finish within the time limit. Returns 1 when none samples any more.
 * Probes stop on their target only once the texels have stopped: the estimate measures their
 * fluence, not the directions of their SH (in a furnace it is exactly 0 at any count while 32
 * directions leave the SH's bands 1–2 visibly wrong), so they get at least the texels' samples.
 * With adaptive sampling the converged blocks stop first, the budget is of the class's mean
 * samples per receiver (what the blocks that go on add to it), and a class none of whose blocks
 * goes on has reached its target. */
static int stop_after(tp_ctx *c, int pass, const tp_errors *ce, double pass_seconds)
{
    const bk_transport_options *opt = c->opt;
    const int late = opt->time_limit > 0 && now_seconds() - c->t0 + 2.1 * pass_seconds > opt->time_limit;
    int left = 0;
    for (int k = 0; k < c->ncls; k++) {
        tp_class *cl = &c->cls[k];
        if (!cl->active) continue;
        const double step = 2.0 * (c->s0 << (pass + 1 < 20 ? pass + 1 : 20));
        const int texels_sampling = k > 0 && c->cls[0].active, going = adapt_apply(c, k);
        const double next = c->adapt ? mean_samples(c, k) + step * (double)class_on(c, k) / (double)(cl->end - cl->begin)
                                     : cl->spp + step;
        if (!going || (c->target > 0 && ce->cls[k] <= c->target && !texels_sampling)) cl->stop = BK_STOP_TARGET;
        else if (next > c->max_samples || pass >= 24) cl->stop = BK_STOP_BUDGET;
        else if (late) cl->stop = BK_STOP_TIME;
        else { left++; continue; }
        cl->active = 0;
    }
    return left == 0;
}

/* The weight sum of receiver i's passes. */
static double recv_weight(const tp_ctx *c, size_t i) { return c->recv_count ? c->blk_w[block_of(c, i)] : 0; }

/* Each receiver's X of the two halves, normalised by its block's pass weights. */
static void write_halves(const tp_ctx *c, double *const x_acc[2], float *halves)
{
    for (size_t i = 0; i < c->recv_count; i++) {
        double w = recv_weight(c, i);
        halves[2 * i] = (float)(w > 0 ? x_acc[0][i] / w : 0);
        halves[2 * i + 1] = (float)(w > 0 ? x_acc[1][i] / w : 0);
    }
}

/* Normalises the pass-weighted sums, then adds the noise-free punctual light. */
static void finish_outputs(tp_ctx *c)
{
    const bk_transport_output *output = c->out;
    for (size_t i = 0; i < c->recv_count; i++) {
        double w = recv_weight(c, i);
        float inv = (float)(w > 0 ? 1.0 / w : 0.0);
        for (int a = 0; a < 3; a++) {
            for (int k = 0; k < 9; k++) {
                output->radiance[i].c[a][k] *= inv;
                if (output->direct) output->direct[i].c[a][k] *= inv;
            }
            if (output->irradiance) output->irradiance[3 * i + a] *= inv;
        }
    }
    /* per-receiver variance of X from the two halves (the denoiser's input) */
    if (output->variance)
        for (size_t i = 0; i < c->recv_count; i++) {
            double w = recv_weight(c, i), a = w > 0 ? c->x_acc[0][i] / w : 0, b = w > 0 ? c->x_acc[1][i] / w : 0;
            output->variance[i] = (float)(0.25 * (a - b) * (a - b));
        }
    if (output->halves) write_halves(c, c->x_acc, output->halves);
    if (c->light_count && !c->slc) { /* (culled light is in the passes' sums already) */
        float *pl = c->punct_lum;
        c->punct_lum = NULL; /* recv_punctual now writes into the outputs */
        parallel_range(c, c->g_begin, c->g_end, 64, recv_punctual);
        c->punct_lum = pl;
    }
}

/* The classes from options.class_end (validated by check_inputs; without it one class), and
 * their blocks. */
static lbk_result init_classes(tp_ctx *c)
{
    const size_t *end = c->opt->class_end;
    c->ncls = end[BK_RECEIVER_CLASSES - 1] ? BK_RECEIVER_CLASSES : 1;
    size_t nb = 0;
    for (int k = 0; k < c->ncls; k++) {
        tp_class *cl = &c->cls[k];
        cl->begin = k ? c->cls[k - 1].end : 0;
        cl->end = c->ncls == 1 ? c->recv_count : end[k];
        cl->active = cl->end > cl->begin;
        cl->stop = BK_STOP_BUDGET;
        c->blk_first[k] = nb;
        if (cl->active) nb += (cl->end - 1) / BK_TRANSPORT_BLOCK - cl->begin / BK_TRANSPORT_BLOCK + 1;
    }
    for (int k = c->ncls; k <= BK_RECEIVER_CLASSES; k++) c->blk_first[k] = nb;
    c->blk_count = nb;
    c->adapt = c->opt->adaptive > 0 && c->target > 0;
    c->blk_w = calloc(nb ? nb : 1, sizeof *c->blk_w);
    c->blk_on = malloc(nb ? nb : 1);
    c->blk_next = malloc(nb ? nb : 1);
    if (!c->blk_w || !c->blk_on || !c->blk_next) return LBK_ERR_OUT_OF_MEMORY;
    memset(c->blk_on, 1, nb);
    memset(c->blk_next, 1, nb);
    return LBK_OK;
}

/* What the run reports as its samples and its reason to stop: the texels' when there are any
 * (REPT's samples_per_texel and status are about lightmap texels, spec §7), else the class
 * that sampled longest. */
static const tp_class *lead_class(const tp_ctx *c)
{
    const tp_class *best = &c->cls[0];
    if (best->end > best->begin) return best;
    for (int k = 1; k < c->ncls; k++)
        if (c->cls[k].end > c->cls[k].begin && c->cls[k].spp > best->spp) best = &c->cls[k];
    return best;
}

/* The lead class's mean samples per receiver (its samples without adaptive sampling). */
static double lead_samples(const tp_ctx *c) { return mean_samples(c, (int)(lead_class(c) - c->cls)); }

static void fill_stats(const tp_ctx *c, int passes, double err, double bias, const tp_errors *ce,
                       const tp_chain_result chain[2], bk_transport_stats *stats)
{
    const tp_class *lead = lead_class(c);
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) stats->class_rel_rmse[k] = ce->cls[k];
    stats->probe_rel_rmse = ce->probe;
    stats->seconds = now_seconds() - c->t0;
    stats->passes = passes;
    stats->samples_per_receiver = lead_samples(c);
    for (int k = 0; k < c->ncls; k++) stats->class_samples[k] = c->cls[k].spp, stats->class_mean_samples[k] = mean_samples(c, k);
    stats->est_rel_rmse = err;
    stats->est_cache_bias = bias;
    stats->bounces = chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces;
    stats->q = 0.5 * (chain[0].q + chain[1].q);
    double tot = chain[0].total_energy + chain[1].total_energy;
    stats->tail_fraction = tot > 0 ? (chain[0].tail_energy + chain[1].tail_energy) / tot : 0;
    stats->cells = c->cell_count;
    uint64_t tested = 0, vt = 0;
    for (int t = 0; t < c->threads; t++) {
        stats->rays += c->thread_rays[t];
        stats->shadow_rays += c->thread_shadow[t];
        stats->nonfinite += c->thread_nonfinite[t];
        tested += c->thread_slc_tested[t];
        vt += c->thread_vpl_tested[t];
    }
    stats->stop = lead->stop;
    stats->nee = c->nee;
    stats->slc = c->slc;
    stats->slc_delta = c->slc_delta;
    double recv_spp = 0; /* receiver-draws: each receiver draws twice (halves) per pass it sampled */
    for (int k = 0; k < c->ncls; k++) recv_spp += (double)(c->cls[k].end - c->cls[k].begin);
    stats->slc_lights_tested = recv_spp > 0 ? (double)tested / recv_spp : 0;
    stats->vpl = c->vpl;
    stats->vpl_delta = c->vpl_delta;
    stats->vpl_share = c->vpl_share;
    stats->vpl_made = c->vpl_made;
    stats->vpl_tested = recv_spp > 0 ? (double)vt / recv_spp : 0;
}

/* ---- distributed runs (bk_transport_split) ------------------------------------------------ */

/* What a pass reports. */
static void sample_of(const tp_ctx *c, double spp, double err, int bounces, int pass, const tp_errors *ce,
                      bk_transport_sample *smp)
{
    memset(smp, 0, sizeof *smp);
    smp->seconds = now_seconds() - c->t0;
    smp->samples_per_receiver = spp;
    smp->est_rel_rmse = err;
    smp->bounces = bounces;
    smp->pass = pass;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) {
        smp->class_rel_rmse[k] = ce->cls[k];
        smp->class_samples[k] = c->cls[k].spp;
        smp->class_mean_samples[k] = mean_samples(c, k);
    }
    smp->probe_rel_rmse = ce->probe;
}

static lbk_result record_pass(const tp_ctx *c, int pass, const tp_chain_result chain[2])
{
    const bk_transport_split *sp = c->opt->split;
    bk_transport_pass_record pr;
    memset(&pr, 0, sizeof pr);
    pr.pass = pass;
    pr.bounces = chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces;
    pr.samples_per_receiver = lead_samples(c);
    for (int k = 0; k < c->ncls; k++) pr.weight_sum[k] = c->cls[k].weight_sum, pr.class_samples[k] = c->cls[k].spp;
    for (int h = 0; h < 2; h++) pr.x_acc[h] = c->x_acc[h], pr.b_acc[h] = c->b_acc[h];
    return sp->record_pass(sp->user, &pr);
}

static void totals_of(const tp_ctx *c, int passes, const tp_chain_result chain[2], bk_transport_totals *t)
{
    memset(t, 0, sizeof *t);
    uint64_t all[3];
    count_totals(c, all);
    t->passes = passes;
    t->stop = lead_class(c)->stop;
    t->nee = c->nee;
    t->bounces = chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces;
    t->q = 0.5 * (chain[0].q + chain[1].q);
    double tot = chain[0].total_energy + chain[1].total_energy;
    t->tail_fraction = tot > 0 ? (chain[0].tail_energy + chain[1].tail_energy) / tot : 0;
    t->cells = c->cell_count;
    t->cache_rays = c->cache_rays, t->cache_shadow = c->cache_shadow, t->cache_nonfinite = c->cache_nonfinite;
    t->recv_rays = all[0] - c->cache_rays - c->extra_rays, t->recv_shadow = all[1] - c->cache_shadow - c->extra_shadow;
    t->recv_nonfinite = all[2] - c->cache_nonfinite - c->extra_nonfinite;
}

/* The merge: every pass's estimate and report from the units' accumulators, then their outputs,
 * then the stats, as the run over all receivers computed them. */
/* What a replay is handed comes from part files, which may be corrupt or forged past their
 * checksums: numbers no run makes are refused before anything casts or indexes with them. */
static int replay_count_ok(double x) { return isfinite(x) && x >= 0 && x <= 0x1p50; }

static int replay_totals_ok(const bk_transport_totals *t)
{
    return t->passes >= 1 && t->passes <= BK_TRANSPORT_MAX_PASSES && t->stop >= BK_STOP_TARGET && t->stop <= BK_STOP_BUDGET &&
           (t->nee == 0 || t->nee == 1) && t->bounces >= 0 && t->bounces <= 1 << 16 && isfinite(t->q) && t->q >= 0 &&
           t->q <= 1 && replay_count_ok(t->tail_fraction);
}

static int replay_pass_ok(const bk_transport_pass_record *pr, size_t n)
{
    if (pr->bounces < 0 || pr->bounces > 1 << 16 || !replay_count_ok(pr->samples_per_receiver)) return 0;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++)
        if (!replay_count_ok(pr->weight_sum[k]) || !replay_count_ok(pr->class_samples[k])) return 0;
    for (int h = 0; h < 2; h++)
        for (size_t i = 0; i < n; i++)
            if (!isfinite(pr->x_acc[h][i]) || !isfinite(pr->b_acc[h][i])) return 0;
    return 1;
}

static int finite_floats(const float *a, size_t n)
{
    for (size_t i = 0; a && i < n; i++)
        if (!isfinite(a[i])) return 0;
    return 1;
}

/* The transport never writes a non-finite output (such samples are counted and dropped). */
static int replay_outputs_ok(const bk_transport_output *o, size_t n)
{
    return finite_floats((const float *)o->radiance, 27 * n) && finite_floats((const float *)o->direct, 27 * n) &&
           finite_floats(o->irradiance, 3 * n) && finite_floats(o->variance, n) && finite_floats(o->halves, 2 * n);
}

static lbk_result replay_run(tp_ctx *c, bk_transport_stats *stats)
{
    const bk_transport_options *opt = c->opt;
    const bk_transport_split *sp = opt->split;
    lbk_result res = init_classes(c);
    if (res == LBK_OK) res = stop_init(c); /* (the subsets adaptive sampling reads) */
    if (res) return res;
    bk_transport_totals t;
    memset(&t, 0, sizeof t);
    res = sp->replay_totals(sp->user, c->recv_count, &t);
    if (res) return res;
    if (!replay_totals_ok(&t)) return LBK_ERR_BAD_INPUT;
    bk_transport_pass_record pr;
    memset(&pr, 0, sizeof pr);
    const size_t n = c->recv_count ? c->recv_count : 1;
    for (int h = 0; h < 2; h++) {
        pr.x_acc[h] = calloc(n, sizeof(double));
        pr.b_acc[h] = calloc(n, sizeof(double));
        if (!pr.x_acc[h] || !pr.b_acc[h]) res = LBK_ERR_OUT_OF_MEMORY;
    }
    double err = 0, bias = 0;
    tp_errors ce = {{0}, 0};
    for (int pass = 0; !res && pass < t.passes; pass++) {
        pr.pass = pass;
        res = sp->replay_pass(sp->user, &pr);
        if (!res && !replay_pass_ok(&pr, c->recv_count)) res = LBK_ERR_BAD_INPUT;
        if (res) break;
        /* the classes that sampled in this pass are those whose weight grew; their marked
         * blocks stopped before it, as stop_after stopped them in the run */
        for (int k = 0; k < c->ncls; k++) {
            c->cls[k].active = pr.weight_sum[k] > c->cls[k].weight_sum;
            c->cls[k].weight_sum = pr.weight_sum[k], c->cls[k].spp = pr.class_samples[k];
        }
        for (int k = 0; k < c->ncls; k++)
            if (c->cls[k].active) adapt_apply(c, k);
        add_block_weights(c, ldexp(1.0, pass));
        estimate_error_of(c, pr.x_acc, pr.b_acc, &err, &bias, &ce);
        adapt_mark(c, pass, pr.x_acc);
        if (opt->report) {
            bk_transport_sample smp;
            sample_of(c, pr.samples_per_receiver, err, pr.bounces, pass, &ce, &smp);
            opt->report(opt->user, &smp);
        }
        if (opt->progress && opt->progress(opt->user, "gather", (double)(pass + 1) / t.passes)) res = LBK_ERR_CANCELLED;
    }
    /* the parts carry the accumulators of every pass, so the halves come from the last one */
    if (!res && c->out->halves) write_halves(c, pr.x_acc, c->out->halves);
    for (int h = 0; h < 2; h++) free(pr.x_acc[h]), free(pr.b_acc[h]);
    if (!res) res = sp->replay_outputs(sp->user, c->out);
    if (!res && !replay_outputs_ok(c->out, c->recv_count)) res = LBK_ERR_BAD_INPUT;
    if (res || !stats) return res;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) stats->class_rel_rmse[k] = ce.cls[k];
    stats->probe_rel_rmse = ce.probe;
    stats->seconds = now_seconds() - c->t0;
    stats->passes = t.passes;
    stats->samples_per_receiver = pr.samples_per_receiver;
    for (int k = 0; k < c->ncls; k++) stats->class_samples[k] = c->cls[k].spp, stats->class_mean_samples[k] = mean_samples(c, k);
    stats->est_rel_rmse = err;
    stats->est_cache_bias = bias;
    stats->bounces = t.bounces;
    stats->q = t.q;
    stats->tail_fraction = t.tail_fraction;
    stats->cells = (size_t)t.cells;
    stats->rays = t.cache_rays + t.recv_rays;
    stats->shadow_rays = t.cache_shadow + t.recv_shadow;
    stats->nonfinite = t.cache_nonfinite + t.recv_nonfinite;
    stats->stop = t.stop;
    stats->nee = t.nee;
    return LBK_OK;
}

/* A unit's run it has no share of (bk_transport_split.run_range): no cache, no gather; zero
 * outputs and the passes and samples the fixed schedule gives (run_pass, stop_after with no
 * target and no time limit), which later runs may depend on (door runs' budget). */
static lbk_result schedule_only(tp_ctx *c, bk_transport_stats *stats)
{
    lbk_result res = init_classes(c);
    if (res) return res;
    const tp_errors none = {{0}, 0};
    int pass = 0;
    for (;; pass++) {
        for (int k = 0; k < c->ncls; k++) {
            if (!c->cls[k].active) continue;
            c->cls[k].weight_sum += ldexp(1.0, pass);
            c->cls[k].spp += 2.0 * (c->s0 << (pass < 20 ? pass : 20));
        }
        if (stop_after(c, pass, &none, 0)) break;
    }
    const bk_transport_output *o = c->out;
    memset(o->radiance, 0, c->recv_count * sizeof *o->radiance);
    if (o->direct) memset(o->direct, 0, c->recv_count * sizeof *o->direct);
    if (o->irradiance) memset(o->irradiance, 0, c->recv_count * 3 * sizeof *o->irradiance);
    if (o->variance) memset(o->variance, 0, c->recv_count * sizeof *o->variance);
    if (o->halves) memset(o->halves, 0, c->recv_count * 2 * sizeof *o->halves);
    if (!stats) return LBK_OK;
    const tp_class *lead = lead_class(c);
    stats->passes = pass + 1;
    stats->samples_per_receiver = lead->spp;
    for (int k = 0; k < c->ncls; k++) stats->class_samples[k] = c->cls[k].spp, stats->class_mean_samples[k] = c->cls[k].spp;
    stats->stop = lead->stop;
    stats->seconds = now_seconds() - c->t0;
    return LBK_OK;
}

/* ---- checkpoints (bk_transport_checkpoint) ------------------------------------------------ */

/* A saved state holds a class as stopped when it stopped before the last saved pass (the texels
 * reach their target a pass before the probes). Such a class is put back to the stop rule with
 * the others: under the same options it stops again for the same reason (its estimate, blocks
 * and samples are what they were, and a later pass's step is larger), so a resumed bake is the
 * uninterrupted one; with --continue's lower target or larger budget it samples on. A class
 * stopped by the clock stays stopped: the rule's clock is not what it was. */
static void reopen_classes(tp_ctx *c)
{
    for (int k = 0; k < c->ncls; k++)
        if (!c->cls[k].active && c->cls[k].end > c->cls[k].begin &&
            (c->cls[k].stop == BK_STOP_TARGET || c->cls[k].stop == BK_STOP_BUDGET))
            c->cls[k].active = 1;
}

static void state_arrays(tp_ctx *c, bk_transport_state *st)
{
    st->count = c->recv_count;
    for (int h = 0; h < 2; h++) st->x_acc[h] = c->x_acc[h], st->b_acc[h] = c->b_acc[h];
    st->radiance = c->out->radiance;
    st->direct = c->out->direct;
    st->irradiance = c->out->irradiance;
    st->cells = c->cell_count;
    st->rough = c->rough;
    st->blocks = c->blk_count;
    st->block_weight = c->blk_w;
}

static lbk_result save_state(tp_ctx *c, int pass, const tp_chain_result chain[2])
{
    const bk_transport_checkpoint *ck = c->opt->checkpoint;
    bk_transport_state *st = calloc(1, sizeof *st);
    if (!st) return LBK_ERR_OUT_OF_MEMORY;
    state_arrays(c, st);
    st->passes = pass + 1;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) {
        st->weight_sum[k] = c->cls[k].weight_sum, st->spp[k] = c->cls[k].spp;
        st->active[k] = c->cls[k].active, st->stop[k] = c->cls[k].stop;
    }
    for (int h = 0; h < 2; h++) {
        st->chain_bounces[h] = chain[h].bounces;
        st->chain_q[h] = chain[h].q;
        st->chain_tail[h] = chain[h].tail_energy;
        st->chain_total[h] = chain[h].total_energy;
    }
    uint64_t all[3];
    count_totals(c, all);
    st->rays = all[0], st->shadow = all[1], st->nonfinite = all[2];
    st->cache_rays = c->cache_rays, st->cache_shadow = c->cache_shadow, st->cache_nonfinite = c->cache_nonfinite;
    memcpy(st->samples, c->samples, sizeof st->samples);
    lbk_result r = ck->save(ck->user, st);
    free(st);
    return r;
}

/* The run's last saved state, if any: *passes gets how many passes it holds (0: none). */
static lbk_result load_state(tp_ctx *c, tp_chain_result chain[2], int *passes)
{
    const bk_transport_checkpoint *ck = c->opt->checkpoint;
    *passes = 0;
    bk_transport_state *st = calloc(1, sizeof *st);
    if (!st) return LBK_ERR_OUT_OF_MEMORY;
    state_arrays(c, st);
    int got = ck->load(ck->user, st);
    lbk_result r = got < 0 ? (lbk_result)(-got) : LBK_OK;
    if (got == 1 && (st->passes < 1 || st->passes > BK_TRANSPORT_MAX_PASSES)) r = LBK_ERR_BAD_INPUT;
    if (got == 1 && !r) {
        *passes = st->passes;
        for (int k = 0; k < BK_RECEIVER_CLASSES; k++) {
            c->cls[k].weight_sum = st->weight_sum[k], c->cls[k].spp = st->spp[k];
            c->cls[k].active = st->active[k], c->cls[k].stop = st->stop[k];
            if (k < c->ncls && c->cls[k].spp > c->spp) c->spp = c->cls[k].spp;
        }
        for (int h = 0; h < 2; h++) {
            chain[h].bounces = st->chain_bounces[h];
            chain[h].q = st->chain_q[h];
            chain[h].tail_energy = st->chain_tail[h];
            chain[h].total_energy = st->chain_total[h];
        }
        /* the counters as they stood after that pass (the punctual pass before it, just redone,
         * is in them already) */
        for (int t = 0; t < c->threads; t++) c->thread_rays[t] = c->thread_shadow[t] = c->thread_nonfinite[t] = 0;
        c->thread_rays[0] = st->rays, c->thread_shadow[0] = st->shadow, c->thread_nonfinite[0] = st->nonfinite;
        c->cache_rays = st->cache_rays, c->cache_shadow = st->cache_shadow, c->cache_nonfinite = st->cache_nonfinite;
        memcpy(c->samples, st->samples, sizeof c->samples);
    }
    free(st);
    return r;
}

lbk_result bk_transport_run(const bk_scene *scene, const bk_tracer *tracer, const bk_receiver *receivers,
                            size_t count, const bk_transport_options *options,
                            const bk_transport_output *output, bk_transport_stats *stats)
{
    double t0 = now_seconds();
    bk_transport_options defaults;
    memset(&defaults, 0, sizeof defaults);
    const bk_transport_options *opt = options ? options : &defaults;
    if (stats) memset(stats, 0, sizeof *stats);
    lbk_result res = check_inputs(scene, tracer, receivers, count, opt, output);
    if (res != LBK_OK) return res;
    const bk_transport_split *split = opt->split;
    if (split && opt->time_limit > 0) return LBK_ERR_INVALID_ARGUMENT; /* the passes would depend on the machine */
    size_t g_begin = 0, g_end = count;
    int own = 1;
    if (split && !split->replay) {
        res = split->run_range(split->user, count, &own, &g_begin, &g_end);
        if (res != LBK_OK) return res;
        if (own && (g_begin > g_end || g_end > count)) return LBK_ERR_INVALID_ARGUMENT;
    }
    const int rec = split && !split->replay && own == 1; /* own == 2: baked whole, not recorded */

    tp_ctx c;
    memset(&c, 0, sizeof c);
    c.scene = scene;
    c.tracer = tracer;
    c.opt = opt;
    c.seed = opt->seed;
    c.threads = opt->threads > 0 ? (opt->threads > 256 ? 256 : opt->threads) : online_cores();
    c.recv = receivers;
    c.recv_count = count;
    c.fscene = opt->footprint_scene ? opt->footprint_scene : scene;
    c.out = output;
    c.oct_count = output->octa_irradiance && opt->octa_points ? opt->octa_count : 0;
    c.t0 = t0;
    c.max_bounces = opt->max_bounces > 0 ? opt->max_bounces : 64;
    c.max_samples = opt->max_samples > 0 ? opt->max_samples : 4096;
    c.target = opt->target_error == 0 ? 0.01 : opt->target_error;
    c.s0 = opt->first_pass_samples > 0 ? opt->first_pass_samples : 16;
    c.tail_tol = fmax(0.1 * (c.target > 0 ? c.target : 0.001), 1e-5);
    c.g_begin = g_begin;
    c.g_end = g_end;
    if (split && split->replay) {
        res = replay_run(&c, stats);
        goto done;
    }
    if (!own) {
        res = schedule_only(&c, stats);
        goto done;
    }
    res = init_classes(&c); /* (before ctx_init: culling's δ is measured per class) */
    if (res == LBK_OK) res = ctx_init(&c);
    if (res == LBK_OK) res = stop_init(&c);
    if (res != LBK_OK) goto done;

    for (size_t i = 0; i < count; i++) {
        memset(&output->radiance[i], 0, sizeof output->radiance[i]);
        if (output->direct) memset(&output->direct[i], 0, sizeof output->direct[i]);
        if (output->irradiance) output->irradiance[3 * i] = output->irradiance[3 * i + 1] = output->irradiance[3 * i + 2] = 0;
    }
    if (c.oct_count) memset(output->octa_irradiance, 0, c.oct_count * 48 * sizeof(float));
    if (c.light_count && !c.slc) { /* luminance only, for the error */
        parallel_range(&c, c.g_begin, c.g_end, 64, recv_punctual);
        for (int k = 0; k < c.ncls; k++) extra_run(&c, k, extra_punctual);
    }

    double err = 0, bias = 0;
    tp_errors ce = {{0}, 0}, sce;
    int pass = 0;
    tp_chain_result chain[2] = {{0, 0, 0, 0}, {0, 0, 0, 0}};
    if (opt->checkpoint && !split) {
        int done_passes = 0;
        res = load_state(&c, chain, &done_passes);
        if (res != LBK_OK) goto done;
        if (done_passes > 0) {
            /* resumed: the saved passes' reports again, then the stop rule after the last one */
            if (opt->report)
                for (int p = 0; p < done_passes; p++) opt->report(opt->user, &c.samples[p]);
            estimate_error(&c, &err, &bias, &ce);
            stop_errors(&c, &ce, &sce);
            pass = done_passes - 1;
            adapt_mark(&c, pass, c.x_acc);
            reopen_classes(&c);
            if (stop_after(&c, pass, &sce, 0)) goto finished;
            pass = done_passes;
        }
    }
    for (;; pass++) {
        double pass_start = now_seconds();
        res = run_pass(&c, pass, chain);
        if (res != LBK_OK) goto done;
        estimate_error(&c, &err, &bias, &ce);
        adapt_mark(&c, pass, c.x_acc);
        if (rec && (res = record_pass(&c, pass, chain)) != LBK_OK) goto done;
        bk_transport_sample smp;
        sample_of(&c, lead_samples(&c), err, chain[0].bounces > chain[1].bounces ? chain[0].bounces : chain[1].bounces,
                  pass, &ce, &smp);
        if (pass < BK_TRANSPORT_MAX_PASSES) c.samples[pass] = smp;
        if (opt->report) opt->report(opt->user, &smp);
        if (opt->checkpoint && !split && (res = save_state(&c, pass, chain)) != LBK_OK) goto done;
        stop_errors(&c, &ce, &sce);
        if (stop_after(&c, pass, &sce, now_seconds() - pass_start)) break;
    }
finished:
    finish_outputs(&c);
    const double oct_err = c.oct_count ? octa_finish(&c) : 0;
    if (stats) {
        fill_stats(&c, pass + 1, err, bias, &ce, chain, stats);
        stats->octa_rel_rmse = oct_err;
        stats->octa_rays = c.oct_total;
    }
    if (rec) {
        bk_transport_totals t;
        totals_of(&c, pass + 1, chain, &t);
        res = split->record_done(split->user, output, &t);
    }
done:
    free_ctx(&c);
    return res;
}
