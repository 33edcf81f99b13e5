/* The light transport's insides, shared by its files (transport.h is the interface the rest of
 * the baker uses; TRANSPORT.md the method): the run context, the types its parts hand each
 * other, the small lookups every part inlines, and what each file offers the others:
 *   transport.c        the run: bk_transport_run, the pass loop, outputs and stats
 *   transport_ctx.c    the run context: lattices, parallel-for, cells and their set-up
 *   emitters.c         emitters: next-event estimation and its MIS weights
 *   nearfield.c        near-field continuation (near, rough, gap and glossy hits)
 *   cache.c            the radiance cache: one bounce for cells, the chain, rough and gap cells
 *   gather.c           receivers and the final gather, octahedral probes
 *   culling_glue.c     stochastic light culling (slc.h) and glossy VPLs (vpl.h) in the run
 *   stop_rule.c        receiver classes, adaptive blocks, the error estimate and the stop rule
 *   replay.c           distributed runs (bk_transport_split): record, replay, schedule only
 *   checkpoint.c       checkpoints (bk_transport_checkpoint): save and resume
 * Everything here uses the bk_tr_ prefix (functions) and tp_ (types, TP_ constants). */
#ifndef BK_TRANSPORT_IMPL_H
#define BK_TRANSPORT_IMPL_H

#include "bake/transport/transport.h"

#include "bake/transport/ggx.h"
#include "bake/transport/shading.h"
#include "bake/transport/slc.h"
#include "bake/transport/solid.h"
#include "bake/transport/vpl.h"
#include "bake/util/rng.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define TP_PI 3.14159265358979323846
#define TP_LOCAL_SHARE 0.03  /* the tail's area-averaged share of the light that ends the bounces */
#define TP_LOCAL_TOL 0.01    /* or its regional error (cache.c, local_tail_converged) */
#define TP_LOCAL_FLOOR 0.01  /* cells below this share of the mean cell light are left out of it */
#define TP_LATE_RAYS_DIV 4   /* the bounces after the energy's rule trace 1/4 of the cache rays */
#define TP_Q_MAX 0.999      /* largest per-bounce ratio the tail formula trusts (factor ≤ 999) */
#define TP_MAX_SUB 1024     /* at most 1024² cells per triangle side (the cell budget binds first) */
#define TP_CELL_CAP ((size_t)1 << 22) /* cells in all (~0.5 GB with both halves' radiance) */
#define TP_LIGHT_POINTS 16  /* points per cell that test punctual lights in bounce 1 */
#define TP_BATCH 64         /* rays generated, then traced as one stream, then shaded */

/* ---- counter-based random numbers --------------------------------------------------------- */

#define TP_RNG_SALT 0x6C626B7472616E73ull /* "lbktrans": the transport's phase salt (rng.h) */

enum { DOM_CELL = 1, DOM_RECV = 2, DOM_CELL_NEE = 3, DOM_RECV_NEE = 4, DOM_RECV_NEAR = 5, DOM_RECV_POS = 6,
       DOM_RECV_PROBE = 7, DOM_CELL_NEAR = 8, DOM_SLC_RECV = 9, DOM_SLC_CELL = 10,
       DOM_VPL_SHOOT = 11, DOM_VPL_XI = 12, DOM_VPL_POINT = 13, DOM_CHECK = 14 };

/* Keyed by everything that identifies one item's samples: never by thread or time. */
static inline bk_rng bk_tr_rng(uint64_t seed, uint64_t domain, uint64_t half, uint64_t pass, uint64_t bounce,
                               uint64_t item)
{
    return bk_rng_stream(seed, TP_RNG_SALT, (domain << 56) ^ (half << 48) ^ (pass << 32) ^ bounce, item);
}

/* Sample j of the shifted lattice as u1 and the angle 2π·u2 given as (cos, sin): the angles of
 * the unshifted lattice are S-th roots of unity (a table per sample count), and the shift is
 * one rotation per item, so no trigonometry runs per ray. */
typedef struct tp_lattice {
    uint32_t S, g;
    double *cos_k, *sin_k; /* cos/sin(2π k/S) */
    uint32_t *k_of_j;      /* j·g mod S (a table: a 64-bit division per ray is not free) */
} tp_lattice;

lbk_result bk_tr_lattice_init(tp_lattice *l, uint32_t S); /* (for S samples; keeps the tables while S stays) */

typedef struct tp_shift { double s1, cs, sn; } tp_shift;

static inline tp_shift bk_tr_lattice_shift(double s1, double s2)
{
    tp_shift t = {s1, cos(2 * 3.14159265358979323846 * s2), sin(2 * 3.14159265358979323846 * s2)};
    return t;
}

static inline void bk_tr_lattice(const tp_lattice *l, uint32_t j, const tp_shift *sh, double *u1, double *cphi,
                                 double *sphi)
{
    double a = (double)j / l->S + sh->s1;
    *u1 = a - floor(a);
    uint32_t k = l->k_of_j[j];
    *cphi = l->cos_k[k] * sh->cs - l->sin_k[k] * sh->sn;
    *sphi = l->sin_k[k] * sh->cs + l->cos_k[k] * sh->sn;
}

/* Sample j of the same lattice as a point of [0,1)² with its own shift (light samples). */
static inline void bk_tr_lattice_uv(const tp_lattice *l, uint32_t j, double t1, double t2, double *a, double *b)
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
    uint8_t *rough;        /* cells whose radiance changes sharply, from the last pass (bk_tr_mark_rough), and the gap cells */
    uint8_t *gap;          /* cells facing a surface much closer than their size (bk_tr_mark_gaps): TP_GAP_* */
    float *cell_lum, *cell_var; /* scratch for bk_tr_mark_rough */
    /* current job */
    int half, pass, bounce, rays;
    tp_lattice lat;        /* for `rays` samples */
    lbk_result chain_err;  /* why the last chain failed (bounces < 0), LBK_OK: out of memory */
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
    /* the stop rule's receivers (bk_tr_stop_init): stop_sub[k] = 1 when class k stops on the subset
     * stop_idx[stop_first[k], stop_first[k + 1]) rather than on all its receivers; extra: the
     * receivers the rule reads outside [g_begin, g_end) (a distributed run's unit gathers them
     * too, unrecorded), class k's at [extra_first[k], extra_first[k + 1]); what they traced is
     * left out of the unit's receiver counts */
    size_t *stop_idx, *extra;
    size_t stop_first[BK_RECEIVER_CLASSES + 1], extra_first[BK_RECEIVER_CLASSES + 1];
    int stop_sub[BK_RECEIVER_CLASSES];
    uint64_t extra_rays, extra_shadow, extra_nonfinite;
    uint64_t check_rays;   /* the path check's (check.c) */
    int check_samples;     /* paths per checked receiver */
    tp_lattice check_lat;  /* a replicate's lattice */
    /* adaptive sampling's blocks (TRANSPORT.md §Adaptive sampling), class k's
     * [blk_first[k], blk_first[k + 1]): per block the sum of the weights of the passes it sampled
     * in, whether it samples in this pass, and whether it would sample in the next (bk_tr_adapt_mark;
     * applied where its class may adapt, bk_tr_stop_after). Without adapt every block of a class
     * samples while the class does, so blk_w is the class's weight_sum. */
    int adapt;
    size_t blk_count, blk_first[BK_RECEIVER_CLASSES + 1];
    double *blk_w;
    uint8_t *blk_on, *blk_next;
    bk_transport_sample samples[BK_TRANSPORT_MAX_PASSES]; /* what each pass reported (checkpoints) */
} tp_ctx;

/* ---- parallel-for (transport_ctx.c) -------------------------------------------------------- */

typedef void (*tp_fn)(tp_ctx *c, size_t begin, size_t end, int thread);

void bk_tr_parallel_range(tp_ctx *c, size_t begin, size_t end, size_t chunk, tp_fn fn);

static inline void bk_tr_parallel_for(tp_ctx *c, size_t n, size_t chunk, tp_fn fn)
{
    bk_tr_parallel_range(c, 0, n, chunk, fn);
}

/* ---- adaptive sampling's blocks: receiver index / BK_TRANSPORT_BLOCK, cut at the class bounds */

static inline int bk_tr_class_of(const tp_ctx *c, size_t i)
{
    int k = 0;
    while (k + 1 < c->ncls && i >= c->cls[k].end) k++;
    return k;
}

static inline size_t bk_tr_block_of(const tp_ctx *c, size_t i)
{
    const int k = bk_tr_class_of(c, i);
    return c->blk_first[k] + i / BK_TRANSPORT_BLOCK - c->cls[k].begin / BK_TRANSPORT_BLOCK;
}


/* ---- scene lookups ---------------------------------------------------------------------------- */

static inline void bk_tr_tri_vertices(const tp_ctx *c, uint32_t tri, double v[3][3])
{
    const uint32_t *ix = c->scene->tris + 3 * (size_t)tri;
    for (int i = 0; i < 3; i++) {
        uint32_t k = ix[i] < c->scene->vertex_count ? ix[i] : 0;
        for (int a = 0; a < 3; a++) v[i][a] = c->scene->positions[3 * (size_t)k + a];
    }
}

static inline void bk_tr_sky_radiance(const tp_ctx *c, const double d[3], double out[3])
{
    if (!c->use_sky) { out[0] = out[1] = out[2] = 0; return; }
    bk_sky_radiance(c->scene, d, out);
}

/* What a hit reaches: its cell (>= 0), HIT_BLACK for the back of a one-sided open surface, or
 * HIT_INSIDE for the back of a closed solid: the ray started inside that solid (solid.h). */
enum { HIT_BLACK = -1, HIT_INSIDE = -2 };

static inline long bk_tr_hit_cell(const tp_ctx *c, const bk_hit *h)
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

/* A cell's sub-triangle in world space, and the edge band of its triangle, fetched once per
 * cell and bounce rather than per ray. */
typedef struct tp_cell_geom {
    double b[3][2];     /* barycentric (u, v) corners of the sub-triangle */
    double v[3][3];     /* the triangle's vertices */
    double eps;
} tp_cell_geom;

void bk_tr_cell_geom(const tp_ctx *c, const tp_cell *cell, tp_cell_geom *g);
/* The point of a cell for (r1, r2) in [0,1)², uniform over its area, kept off the triangle's
 * edges; bu, bv (optional) get its barycentrics in the whole triangle. */
void bk_tr_cell_point_at(const tp_cell_geom *g, double r1, double r2, double p[3], double *bu, double *bv);

/* ---- emitters: next-event estimation and its MIS weights (emitters.c) ------------------------ */

/* Emitted radiance of triangle `tri` at barycentrics (u, v): the factor times the emission
 * texture at the point's uv0, for both strategies alike (gather hits and light samples must
 * see the same emitter or MIS would be biased). */
void bk_tr_emission_at(const tp_ctx *c, uint32_t tri, double u, double v, double out[3]);

/* Which gather pdf a light sample is weighed against. */
enum { PG_COSINE = 0, PG_HEMISPHERE = 1, PG_SPHERE = 2 };

/* MIS weight of a gather ray (unit direction d, gather pdf pg) that hit cell hc at distance t:
 * the light-sampling pdf of that point in solid angle is p_area·t²/|cos θ_light|. */
double bk_tr_mis_gather(const tp_ctx *c, const bk_hit *h, long hc, const double d[3], double pg);

/* A glossy point's BSDF in its frame (t, b, n): what light samples there are weighed against. */
typedef struct tp_lobe {
    bk_mr_lobe lb;
    double t[3], b[3], n[3];
} tp_lobe;

static inline void bk_tr_to_local(const tp_lobe *lf, const double d[3], double l[3])
{
    l[0] = d[0] * lf->t[0] + d[1] * lf->t[1] + d[2] * lf->t[2];
    l[1] = d[0] * lf->b[0] + d[1] * lf->b[1] + d[2] * lf->b[2];
    l[2] = d[0] * lf->n[0] + d[1] * lf->n[1] + d[2] * lf->n[2];
}

/* One light sample for origin o (unit normal n; ignored for PG_SPHERE) from (u0, u1) in
 * [0,1)²: picks an emitter sub-triangle by power, a uniform point on it, and traces a shadow
 * ray. Returns 1 and fills the unit direction d, cos_p = d·n and val = Le·w_L/p_L (radiance
 * over its solid-angle pdf, MIS-weighted) when the sample carries light. */
int bk_tr_nee_sample(const tp_ctx *c, const float o[3], const double n[3], int kind, double u0, double u1,
                     double d[3], double *cos_p, double val[3], uint64_t *shadow);
/* bk_tr_nee_sample weighed against the lobe lf's density instead of the gather pdf (lf NULL: that);
 * dist_out (or NULL): the distance to the emitter point of a sample it returns. */
int bk_tr_nee_sample_lobe(const tp_ctx *c, const float o[3], const double n[3], int kind, const tp_lobe *lf,
                          double u0, double u1, double *dist_out, double d[3], double *cos_p, double val[3],
                          uint64_t *shadow);

/* The light-sampling distribution (set-up); off (nee = 0) when the options or the scene want none. */
lbk_result bk_tr_build_emitters(tp_ctx *c);

/* Per-thread counters of one parallel step. */
typedef struct tp_count { uint64_t rays, shadow, bad; } tp_count;

/* The tile lists of a thread (for the punctual lights' draws and for the VPLs' draws): for each
 * half the list of the tile it last cut (tile), in the thread's two slots of `ids` (cap each). */
typedef struct tp_tile_lists {
    uint32_t *ids[2];
    size_t n[2], tile[2];
} tp_tile_lists;

/* ---- stochastic light culling and glossy VPLs in the run (culling_glue.c) -------------------- */

/* A thread's empty tile lists for the punctual lights' draws (slc) and for the VPLs' (vpl). */
void bk_tr_slc_lists_init(const tp_ctx *c, int thread, tp_tile_lists *t);
void bk_tr_vpl_lists_init(const tp_ctx *c, int thread, tp_tile_lists *t);
/* A culling draw over `slc` for (half, pass): one ξ per light from its own stream. */
lbk_result bk_tr_slc_draw(const tp_ctx *c, int dom, int h, int pass, const bk_slc *slc, bk_slc_draw **out);
/* Whether this run culls (options.slc; auto: more than BK_SLC_AUTO_LIGHTS positional lights),
 * and its δ in irradiance units. */
lbk_result bk_tr_slc_init(tp_ctx *c);
/* Whether this run adds glossy VPLs (options.glossy_vpl; auto: vpl_sharp_share ≥
 * BK_VPL_AUTO_SHARE), which lights shoot (positional ones with power), the receivers' tiles and
 * δ (relative to the smallest class mean of the punctual irradiance, as SLC's). Needs a glossy
 * cell, a light that shoots and a surface receiver; else off and nothing else changes. */
lbk_result bk_tr_vpl_init(tp_ctx *c);
/* This pass's VPLs and draws (one per half; ξ per VPL from the stream (seed, DOM_VPL_XI, half,
 * pass, the VPL's index: lights in order, photons in order), δ/2^pass) and the threads' room for tile lists. */
lbk_result bk_tr_vpl_pass(tp_ctx *c, int pass);
void bk_tr_vpl_pass_end(tp_ctx *c);

/* ---- near-field continuation -------------------------------------------------------------- */

/* A cell holds one radiance for its whole area; read from closer than a few cell sizes (a
 * corner, a leg under a table top) that constant is biased, and more samples never remove it.
 * Such hits are evaluated at the exact hit point instead: one cosine-distributed gather from
 * there (sky, emission, and the cache one bounce further, or another continuation when that
 * hit is near too) plus one punctual light picked uniformly. An unbiased estimate of the
 * reflected radiance at the point given the cache beyond it (TRANSPORT.md §Bias). */
#define TP_NEAR_CELLS 1.5   /* continue when the hit is closer than this many cell sizes */

static inline int bk_tr_near_hit(const tp_ctx *c, const bk_hit *h, long hc, const uint8_t *rough)
{
    return hc >= 0 && (h->t < TP_NEAR_CELLS * c->tri_cell_h[h->tri] || (rough && rough[hc]) ||
                       (c->gloss && c->gloss[hc].on));
}

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
    /* 1: a path with nothing cached (the path check, check.c): every hit is continued at its
     * exact point, past TP_EXACT_RR_DEPTH by Russian roulette, at most max_depth in a row; read,
     * rough and hist are unused */
    int exact;
} tp_near_mode;

#define TP_EXACT_RR_DEPTH 3

/* What a continuation ray from o along unit d brings back (sky, MIS-weighted emission, and the
 * cache or the exact radiance at its hit), with the ray's own density pg for the MIS weight. */
void bk_tr_cont_trace(tp_ctx *c, const tp_near_mode *md, const float o[3], const double d[3], double pg, int depth,
                      bk_rng *rng, tp_count *cnt, double L[3]);
/* One punctual light picked at random (uniformly; with culling by intensity, plus every
 * directional one) at point x (normal n, ray origin o), weighted by 1/its probability, into e
 * (through the BSDF lf at a glossy point; NULL: irradiance). */
void bk_tr_cont_punctual(const tp_ctx *c, const double x[3], const double n[3], const float o[3], const tp_lobe *lf,
                         int split, bk_rng *rng, double e[3], tp_count *cnt);

/* Reflected radiance (all bounces, emission excluded) at the point of `hit` (cell hc, reached
 * along unit d) from one continuation sample. */
void bk_tr_near_radiance(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double din[3],
                         int depth, bk_rng *rng, tp_count *cnt, double out[3]);
/* A gather ray's near hit (depth 0): bk_tr_near_radiance, or the mean of several on a cell inside a gap. */
void bk_tr_near_entry(tp_ctx *c, const tp_near_mode *md, const bk_hit *hit, long hc, const double d[3], bk_rng *rng,
                      tp_count *cnt, double out[3]);

/* ---- the cache (cache.c) ------------------------------------------------------------------------ */

enum { TP_GAP_MOUTH = 1, TP_GAP_INSIDE = 2 }; /* some of the probes covered; all of them */

/* Marks the rough cells from the two halves' sums of the pass that just ended. */
void bk_tr_mark_rough(tp_ctx *c);
/* Marks the gap cells (a tp_fn over cells; geometry only). */
void bk_tr_mark_gaps(tp_ctx *c, size_t begin, size_t end, int thread);

typedef struct tp_chain_result { int bounces; double q, tail_energy, total_energy; } tp_chain_result;

/* Fills l_sum[h] with the reflected outgoing radiance per cell (all bounces + tail; emission is
 * added where a gather ray hits it, with its MIS weight). */
tp_chain_result bk_tr_run_chain(tp_ctx *c, int h, int pass, int rays, double tol, int max_bounces);

/* ---- receivers and the final gather (gather.c) -------------------------------------------------- */

/* Where a receiver's ray leaves from: the point, its unit normal (zero vector: a probe, which
 * gathers over the sphere; n then holds +z for the frame), and the offset ray origin. */
typedef struct tp_origin {
    double p[3], n[3];
    float o[3];
    int sphere;
} tp_origin;

void bk_tr_origin_from(const tp_ctx *c, const float p[3], const float nf[3], tp_origin *g);
/* The receiver's own point (the whole texel where it has no footprint). */
void bk_tr_recv_origin(const tp_ctx *c, const bk_receiver *r, tp_origin *g);
/* One punctual light at one point, weighted w (1, or 1/p of an accepted culling draw):
 * irradiance (sphere: fluence) and the SH of its incident radiance. Returns the shadow rays. */
uint64_t bk_tr_punctual_one(const tp_ctx *c, const tp_origin *g, size_t li, const bk_slc_draw *d, double delta,
                            double e[3], double sh[3][9]);
/* The points at which a receiver's punctual light is evaluated: a texel with a footprint
 * averages its four quarter centres (hard shadow edges resolve to a quarter of a texel). */
int bk_tr_punctual_points(const tp_ctx *c, const bk_receiver *r, tp_origin g[4]);
/* A uniform point of the visible part of r's footprint into g (left as it is where none is found
 * in TP_FOOTPRINT_TRIES draws). */
void bk_tr_footprint_sample(const tp_ctx *c, const bk_receiver *r, bk_rng *pos, tp_origin *g);
/* Noise-free punctual light per receiver (a tp_fn): into punct_lum, or (punct_lum NULL) the outputs. */
void bk_tr_recv_punctual(tp_ctx *c, size_t begin, size_t end, int thread);
/* The final gather of this pass at receivers [begin, end) (a tp_fn). */
void bk_tr_recv_gather(tp_ctx *c, size_t begin, size_t end, int thread);
/* Octahedral probes [begin, end) in this pass (a tp_fn), and after the passes their finish (returns
 * their relative RMSE). */
void bk_tr_octa_gather(tp_ctx *c, size_t begin, size_t end, int thread);
double bk_tr_octa_finish(tp_ctx *c);

/* ---- classes, adaptive blocks and the stop rule (stop_rule.c) ---------------------------------- */

/* The noise estimate per receiver class (options.class_end) and for the probes together. */
typedef struct tp_errors {
    double cls[BK_RECEIVER_CLASSES];
    double probe;
} tp_errors;

lbk_result bk_tr_init_classes(tp_ctx *c);
lbk_result bk_tr_stop_init(tp_ctx *c);
double bk_tr_mean_samples(const tp_ctx *c, int k);
size_t bk_tr_active_receivers(const tp_ctx *c);
void bk_tr_add_block_weights(tp_ctx *c, double w);
void bk_tr_estimate_error_of(const tp_ctx *c, double *const x_acc[2], double *const b_acc[2], double *noise,
                             double *bias, tp_errors *ce);
void bk_tr_estimate_error(const tp_ctx *c, double *noise, double *bias, tp_errors *ce);
void bk_tr_stop_errors(const tp_ctx *c, const tp_errors *ce, tp_errors *sce);
void bk_tr_adapt_mark(tp_ctx *c, int pass, double *const x_acc[2]);
int bk_tr_adapt_apply(tp_ctx *c, int k);
int bk_tr_stop_after(tp_ctx *c, int pass, const tp_errors *ce, double pass_seconds);
const tp_class *bk_tr_lead_class(const tp_ctx *c);
double bk_tr_lead_samples(const tp_ctx *c);

/* ---- the run (transport.c) ---------------------------------------------------------------------- */

/* The per-thread counters summed: rays, shadow rays, non-finite samples. */
void bk_tr_count_totals(const tp_ctx *c, uint64_t t[3]);
/* What a pass reports. */
void bk_tr_sample_of(const tp_ctx *c, double spp, double err, int bounces, int pass, const tp_errors *ce,
                     bk_transport_sample *smp);
/* Receiver i's two halves' X (x_acc normalised by its block's pass weights), and the variance of
 * their mean from their difference, ¼(h₀ − h₁)²: the noise the denoiser and the path check read. */
void bk_tr_recv_halves(const tp_ctx *c, double *const x_acc[2], size_t i, double h[2]);
static inline double bk_tr_halves_variance(const double h[2]) { return 0.25 * (h[0] - h[1]) * (h[0] - h[1]); }
/* Each receiver's X of the two halves, normalised by its block's pass weights. */
void bk_tr_write_halves(const tp_ctx *c, double *const x_acc[2], float *halves);

/* ---- the path check (check.c) ---------------------------------------------------------------- */

/* The path check's receivers drawn and traced by unbiased paths into output.check_* (after the
 * passes and finish_outputs). */
lbk_result bk_tr_check_run(tp_ctx *c);

/* ---- the run context (transport_ctx.c) ---------------------------------------------------------- */

/* Everything a run needs before its first pass: counters, the light selection, cells,
 * emitters, the per-half radiance arrays and the receivers' accumulators. */
lbk_result bk_tr_ctx_init(tp_ctx *c);
void bk_tr_free_ctx(tp_ctx *c);

/* ---- distributed runs (replay.c) ------------------------------------------------------------- */

lbk_result bk_tr_record_pass(const tp_ctx *c, int pass, const tp_chain_result chain[2]);
void bk_tr_totals_of(const tp_ctx *c, int passes, const tp_chain_result chain[2], bk_transport_totals *t);
/* The merge: every pass's estimate and report from the units' accumulators, then their outputs,
 * then the stats, as the run over all receivers computed them. */
lbk_result bk_tr_replay_run(tp_ctx *c, bk_transport_stats *stats);
/* A unit's run it has no share of: the fixed schedule's passes and samples, zero outputs. */
lbk_result bk_tr_schedule_only(tp_ctx *c, bk_transport_stats *stats);

/* ---- checkpoints (checkpoint.c) ------------------------------------------------------------- */

void bk_tr_reopen_classes(tp_ctx *c);
lbk_result bk_tr_save_state(tp_ctx *c, int pass, const tp_chain_result chain[2]);
/* The run's last saved state, if any: *passes gets how many passes it holds (0: none). */
lbk_result bk_tr_load_state(tp_ctx *c, tp_chain_result chain[2], int *passes);

#endif
