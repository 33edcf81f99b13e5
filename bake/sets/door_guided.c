/* The guided door estimator; see door_guided.h and bake/sets/SETS.md. */
#include "bake/sets/door_guided.h"

#include "scene/clock.h"
#include "scene/parallel.h"
#include "bake/transport/shading.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DG_PI 3.14159265358979323846

enum { DOM_STAGE0 = 1, DOM_STAGE1 = 2, DOM_BOUNCE = 3 };

typedef struct dg_grid {
    double h;
    size_t n;
    uint64_t *keys;   /* sorted */
    uint32_t *texel;  /* texel receiver per key */
} dg_grid;

typedef struct dg_ctx {
    const bk_door_guided_inputs *in;
    const bk_guide_boxes *boxes;
    int S, Nu, Ng, Nb;
    float scene_scale;
    uint32_t *lights;
    size_t nl;
    dg_grid grid;
    float *base_e;     /* 3 per texel receiver: the base's irradiance along its normal */
    float *prev_e;     /* 3 per texel receiver: the previous bounce's irradiance (the cache) */
    float *cur_e;      /* 3 per receiver: this stage's irradiance (texels) or fluence (probes) */
    lbk_sh9_rgb *stage_sh, *stage_direct;
    int stage, bounce;
    int threads;
    uint64_t *thread_rays;
    double *thread_portal; /* Σ portal samples, and receivers that saw the portal, per thread */
    uint64_t *thread_portal_n;
} dg_ctx;

/* ---- helpers ----------------------------------------------------------------------------------- */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double lumf(const float c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* Irradiance along unit n of the radiance an SH9 projection holds (Ramamoorthi & Hanrahan). */
static void sh_irradiance(const lbk_sh9_rgb *s, const double n[3], double e[3])
{
    static const double A[9] = {DG_PI, 2 * DG_PI / 3, 2 * DG_PI / 3, 2 * DG_PI / 3, DG_PI / 4,
                                DG_PI / 4, DG_PI / 4, DG_PI / 4, DG_PI / 4};
    double y[9];
    bk_sh9_basis_d(n, y);
    for (int c = 0; c < 3; c++) {
        double v = 0;
        for (int k = 0; k < 9; k++) v += A[k] * s->c[c][k] * y[k];
        e[c] = v > 0 && isfinite(v) ? v : 0;
    }
}

typedef struct dg_recv {
    double p[3], n[3], t[3], b[3];
    int sphere;
    float o[3];
} dg_recv;

static void recv_setup(const dg_ctx *c, size_t i, dg_recv *r)
{
    const bk_receiver *rc = &c->in->receivers[i];
    double l = sqrt((double)rc->normal[0] * rc->normal[0] + (double)rc->normal[1] * rc->normal[1] +
                    (double)rc->normal[2] * rc->normal[2]);
    r->sphere = !(l > 0);
    for (int k = 0; k < 3; k++) {
        r->p[k] = rc->position[k];
        r->n[k] = r->sphere ? (k == 2) : rc->normal[k] / l;
    }
    bk_onb(r->n, r->t, r->b);
    if (r->sphere) memcpy(r->o, rc->position, sizeof r->o);
    else bk_offset_ray_origin_scaled(rc->position, rc->normal, c->scene_scale, r->o);
}

/* One sample of radiance L (direct part Ld) arriving along d with Monte Carlo weight w (per
 * unit solid angle) into the SH projections and the irradiance (cos = 1 for probes). */
typedef struct dg_acc {
    double sh[3][9], shd[3][9], e[3];
} dg_acc;

static void acc_add(dg_acc *a, const double d[3], double cs, const double L[3], const double Ld[3], double w)
{
    double y[9];
    bk_sh9_basis_d(d, y);
    for (int c = 0; c < 3; c++) {
        a->e[c] += L[c] * w * cs;
        for (int k = 0; k < 9; k++) a->sh[c][k] += L[c] * w * y[k];
        if (Ld && Ld[c] != 0)
            for (int k = 0; k < 9; k++) a->shd[c][k] += Ld[c] * w * y[k];
    }
}

static void acc_store(const dg_ctx *c, size_t i, const dg_acc *a)
{
    for (int ch = 0; ch < 3; ch++) {
        for (int k = 0; k < 9; k++) {
            c->stage_sh[i].c[ch][k] = (float)a->sh[ch][k];
            if (c->stage_direct) c->stage_direct[i].c[ch][k] = (float)a->shd[ch][k];
        }
        c->cur_e[3 * i + ch] = (float)a->e[ch];
    }
}

/* ---- the cache: nearest texel receiver with a compatible normal ------------------------------- */

static uint64_t cell_key(int64_t x, int64_t y, int64_t z)
{
    return bk_mix64((uint64_t)x * BK_GOLDEN64 ^ bk_mix64((uint64_t)y + 0x632BE59BD9B4E019ull) ^
                    bk_mix64(bk_mix64((uint64_t)z) + 0x85157AF5ull));
}

typedef struct key_idx { uint64_t key; uint32_t texel; } key_idx;

static int cmp_key(const void *a, const void *b)
{
    const key_idx *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->texel < y->texel ? -1 : x->texel > y->texel;
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

static lbk_result grid_build(dg_ctx *c)
{
    const bk_door_guided_inputs *in = c->in;
    size_t nt = in->texel_receivers;
    float *sz = malloc((nt ? nt : 1) * sizeof *sz);
    key_idx *ki = malloc((nt ? nt : 1) * sizeof *ki);
    if (!sz || !ki) {
        free(sz), free(ki);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t m = 0;
    for (size_t i = 0; i < nt; i++)
        if (in->texel_size && in->texel_size[i] > 0 && isfinite(in->texel_size[i])) sz[m++] = in->texel_size[i];
    double med = 0.25;
    if (m) {
        qsort(sz, m, sizeof *sz, cmp_float);
        med = sz[m / 2];
    }
    /* a hit reads the nearest texel within two texel sizes: the texel sample points of one
     * surface are about one texel apart, pushed-out ones a little more */
    c->grid.h = 2 * med;
    size_t n = 0;
    for (size_t i = 0; i < nt; i++) {
        if (in->not_cache && in->not_cache[i]) continue;
        const float *p = in->receivers[i].position;
        int64_t x = (int64_t)floor(p[0] / c->grid.h), y = (int64_t)floor(p[1] / c->grid.h),
                z = (int64_t)floor(p[2] / c->grid.h);
        ki[n].key = cell_key(x, y, z);
        ki[n].texel = (uint32_t)i;
        n++;
    }
    qsort(ki, n, sizeof *ki, cmp_key);
    c->grid.n = n;
    c->grid.keys = malloc((n ? n : 1) * sizeof *c->grid.keys);
    c->grid.texel = malloc((n ? n : 1) * sizeof *c->grid.texel);
    if (!c->grid.keys || !c->grid.texel) {
        free(sz), free(ki);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < n; i++) c->grid.keys[i] = ki[i].key, c->grid.texel[i] = ki[i].texel;
    free(sz), free(ki);
    return LBK_OK;
}

static long cache_lookup(const dg_ctx *c, const double y[3], const double ny[3])
{
    const dg_grid *g = &c->grid;
    if (!g->n) return -1;
    int64_t cx = (int64_t)floor(y[0] / g->h), cy = (int64_t)floor(y[1] / g->h), cz = (int64_t)floor(y[2] / g->h);
    long best = -1;
    double bd = g->h * g->h;
    for (int dx = -1; dx <= 1; dx++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dz = -1; dz <= 1; dz++) {
                uint64_t key = cell_key(cx + dx, cy + dy, cz + dz);
                size_t lo = 0, hi = g->n;
                while (lo < hi) {
                    size_t mid = lo + (hi - lo) / 2;
                    if (g->keys[mid] < key) lo = mid + 1;
                    else hi = mid;
                }
                for (size_t k = lo; k < g->n && g->keys[k] == key; k++) {
                    const bk_receiver *r = &c->in->receivers[g->texel[k]];
                    double dn = r->normal[0] * ny[0] + r->normal[1] * ny[1] + r->normal[2] * ny[2];
                    if (dn < 0.5) continue;
                    double v[3] = {r->position[0] - y[0], r->position[1] - y[1], r->position[2] - y[2]};
                    double d2 = dot3(v, v);
                    if (d2 < bd || (d2 == bd && best >= 0 && g->texel[k] < (uint32_t)best)) bd = d2, best = g->texel[k];
                }
            }
    return best;
}

/* ---- what rays find ------------------------------------------------------------------------------ */

/* The surface a ray hit, seen from the ray's side: point, normal towards the ray, albedo and
 * emission. 0 for the back of a one-sided surface (black, as in transport). */
typedef struct dg_surf {
    double y[3], n[3], albedo[3], le[3];
    float yo[3]; /* offset origin for rays leaving it */
} dg_surf;

static int surface_at(const dg_ctx *c, const float o[3], const double d[3], const bk_hit *h, dg_surf *s)
{
    const bk_scene *sc = c->in->scene;
    uint32_t mi = sc->tri_material && h->tri < sc->tri_count ? sc->tri_material[h->tri] : 0;
    int ds = mi < sc->material_count && sc->materials[mi].double_sided;
    if (!h->front && !ds) return 0;
    for (int k = 0; k < 3; k++) {
        s->y[k] = o[k] + (double)h->t * d[k];
        s->n[k] = h->front ? h->ng[k] : -h->ng[k];
    }
    bk_door_surface(sc, h->tri, h->u, h->v, "", s->albedo, s->le);
    float yf[3] = {(float)s->y[0], (float)s->y[1], (float)s->y[2]}, nf[3] = {(float)s->n[0], (float)s->n[1], (float)s->n[2]};
    bk_offset_ray_origin_scaled(yf, nf, bk_tracer_tri_scale(c->in->tracer, h->tri), s->yo);
    return 1;
}

/* Radiance arriving along a ray that went through the doorway: what the base bake knows about
 * the far side (emission + albedo/π × the base irradiance at the nearest texel, or the sky).
 * Ld gets the part that comes straight from a source. */
static void beyond(const dg_ctx *c, const float o[3], const double d[3], int hit, const bk_hit *h, double L[3],
                   double Ld[3])
{
    L[0] = L[1] = L[2] = Ld[0] = Ld[1] = Ld[2] = 0;
    if (!hit) {
        if (c->in->use_sky) bk_sky_radiance(c->in->scene, d, L);
        memcpy(Ld, L, 3 * sizeof *L);
        return;
    }
    dg_surf s;
    if (!surface_at(c, o, d, h, &s)) return;
    long k = cache_lookup(c, s.y, s.n);
    for (int a = 0; a < 3; a++) {
        double e = k >= 0 ? c->base_e[3 * k + a] : 0;
        L[a] = s.albedo[a] / DG_PI * e + s.le[a];
        Ld[a] = s.le[a];
    }
}

/* One portal sample from origin o (point p, normal n; sphere: no horizon) at portal (a, b):
 * returns 1 and the radiance through the doorway, the unit direction and the solid-angle
 * weight A·cos_q/dist² when the ray reaches the portal unblocked and above the horizon. */
static int portal_sample(const dg_ctx *c, const float o[3], const double n[3], int sphere, double a, double b,
                         double d[3], double *w, double L[3], double Ld[3], uint64_t *rays)
{
    const bk_portal *pt = &c->in->portal;
    double q[3];
    bk_portal_point(pt, a, b, q);
    double v[3] = {q[0] - o[0], q[1] - o[1], q[2] - o[2]};
    double dist = sqrt(dot3(v, v));
    if (!(dist > 0)) return 0;
    for (int k = 0; k < 3; k++) d[k] = v[k] / dist;
    if (!sphere && !(dot3(d, n) > 0)) return 0;
    double cq = fabs(dot3(d, pt->n));
    if (!(cq > 0)) return 0;
    float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
    bk_hit h;
    (*rays)++;
    int hit = bk_tracer_intersect(c->in->tracer, o, df, 0.0f, INFINITY, &h);
    if (hit && h.t < dist * (1 - 1e-6)) return 0; /* blocked before the doorway */
    beyond(c, o, d, hit, &h, L, Ld);
    *w = pt->area * cq / (dist * dist);
    return 1;
}

/* Punctual light at point p (normal n, origin o) that passes through the doorway. */
static int punctual_through(const dg_ctx *c, uint32_t li, const double p[3], const double n[3], int sphere,
                            const float o[3], double val[3], double dir[3], double *cs, uint64_t *rays)
{
    double dist;
    if (!bk_light_eval(&c->in->scene->lights[li], p, val, dir, &dist)) return 0;
    *cs = sphere ? 1 : dot3(dir, n);
    if (!(*cs > 0)) return 0;
    if (!bk_portal_crosses(&c->in->portal, p, dir, isinf(dist) ? 1e30 : dist, NULL)) return 0;
    (*rays)++;
    return bk_light_visible(c->in->tracer, o, dir, dist);
}

/* ---- stage 0: light straight through the door --------------------------------------------------- */

static void stage0(dg_ctx *c, size_t begin, size_t end, int thread)
{
    uint64_t rays = 0;
    for (size_t i = begin; i < end; i++) {
        dg_recv r;
        recv_setup(c, i, &r);
        dg_acc a;
        memset(&a, 0, sizeof a);
        for (size_t l = 0; l < c->nl; l++) {
            double val[3], dir[3], cs;
            if (!punctual_through(c, c->lights[l], r.p, r.n, r.sphere, r.o, val, dir, &cs, &rays)) continue;
            acc_add(&a, dir, cs, val, val, 1.0);
        }
        /* the door as an area light: stratified portal samples, more where it looks larger */
        double om = bk_portal_solid_angle(&c->in->portal, r.p);
        int seen = r.sphere;
        if (!seen) {
            static const double cr[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5}};
            for (int k = 0; k < 5 && !seen; k++) {
                double q[3];
                bk_portal_point(&c->in->portal, cr[k][0], cr[k][1], q);
                double v[3] = {q[0] - r.p[0], q[1] - r.p[1], q[2] - r.p[2]};
                seen = dot3(v, r.n) > 0;
            }
        }
        if (seen && om > 0 && isfinite(om)) {
            int want = (int)ceil(c->S * sqrt(om / (2 * DG_PI)));
            want = want < 8 ? 8 : want > c->S ? c->S : want;
            int side = (int)ceil(sqrt((double)want)), N = side * side;
            bk_rng rng = bk_door_rng_make(c->in->seed, DOM_STAGE0, 0, i);
            for (int j = 0; j < N; j++) {
                double pa = ((j % side) + bk_rng_next(&rng)) / side;
                double pb = ((j / side) + bk_rng_next(&rng)) / side;
                double d[3], w, L[3], Ld[3];
                if (!portal_sample(c, r.o, r.n, r.sphere, pa, pb, d, &w, L, Ld, &rays)) continue;
                if (!bk_finite3(L)) continue;
                acc_add(&a, d, r.sphere ? 1 : dot3(d, r.n), L, Ld, w / N);
            }
            c->thread_portal[thread] += N;
            c->thread_portal_n[thread]++;
        }
        acc_store(c, i, &a);
    }
    c->thread_rays[thread] += rays;
}

/* ---- stage 1: one bounce, gather rays guided by the photon boxes ------------------------------ */

/* Door-direct radiance leaving the surface a gather ray hit (seed §4.2): the punctual lights of
 * the box the point lies in (direct light culling) and one portal sample. */
static void door_bounce(const dg_ctx *c, const dg_surf *s, bk_rng *rng, double L[3], uint64_t *rays)
{
    L[0] = L[1] = L[2] = 0;
    if (s->albedo[0] <= 0 && s->albedo[1] <= 0 && s->albedo[2] <= 0) return;
    double e[3] = {0, 0, 0};
    int b = bk_guide_box_containing(c->boxes, s->y);
    if (b >= 0) {
        const bk_guide_box *bx = &c->boxes->box[b];
        for (uint32_t k = 0; k < bx->light_count; k++) {
            double val[3], dir[3], cs;
            if (!punctual_through(c, c->boxes->lights[bx->light_first + k], s->y, s->n, 0, s->yo, val, dir, &cs, rays))
                continue;
            for (int a = 0; a < 3; a++) e[a] += val[a] * cs;
        }
    }
    double d[3], w, Lp[3], Ld[3];
    double pa = bk_rng_next(rng), pb = bk_rng_next(rng);
    if (portal_sample(c, s->yo, s->n, 0, pa, pb, d, &w, Lp, Ld, rays) && bk_finite3(Lp)) {
        double cs = dot3(d, s->n);
        for (int a = 0; a < 3; a++) e[a] += Lp[a] * w * cs;
    }
    for (int a = 0; a < 3; a++) L[a] = s->albedo[a] / DG_PI * e[a];
}

static void uniform_dir(const dg_recv *r, double u1, double u2, double d[3])
{
    double z = r->sphere ? 1 - 2 * u1 : u1;
    double rr = sqrt(fmax(0.0, 1 - z * z)), phi = 2 * DG_PI * u2;
    double lx = rr * cos(phi), ly = rr * sin(phi);
    for (int k = 0; k < 3; k++) d[k] = lx * r->t[k] + ly * r->b[k] + z * r->n[k];
}

static void stage1(dg_ctx *c, size_t begin, size_t end, int thread)
{
    uint64_t rays = 0;
    const int Nu = c->Nu, Ng = c->Ng;
    for (size_t i = begin; i < end; i++) {
        dg_recv r;
        recv_setup(c, i, &r);
        dg_acc a;
        memset(&a, 0, sizeof a);
        const double pu = r.sphere ? 1 / (4 * DG_PI) : 1 / (2 * DG_PI);
        bk_rng rng = bk_door_rng_make(c->in->seed, DOM_STAGE1, 0, i);
        double s1 = bk_rng_next(&rng), s2 = bk_rng_next(&rng);
        for (int j = 0; j < Nu + Ng; j++) {
            double d[3];
            if (j < Nu) {
                /* shifted lattice: exactly stratified in the first coordinate */
                double u1 = (double)j / Nu + s1, u2 = (double)j * 0.6180339887498949 + s2;
                uniform_dir(&r, u1 - floor(u1), u2 - floor(u2), d);
            } else {
                double g0 = bk_rng_next(&rng), g1 = bk_rng_next(&rng), g2 = bk_rng_next(&rng);
                if (!bk_guide_sample(c->boxes, r.p, g0, g1, g2, d)) continue;
                if (!r.sphere && !(dot3(d, r.n) > 0)) continue; /* below the horizon: contributes 0 */
            }
            double pg = Ng ? bk_guide_pdf(c->boxes, r.p, d) : 0;
            double wgt = 1.0 / (Nu * pu + Ng * pg); /* balance heuristic, both strategies */
            float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
            bk_hit h;
            rays++;
            if (!bk_tracer_intersect(c->in->tracer, r.o, df, 0.0f, INFINITY, &h)) continue;
            dg_surf s;
            if (!surface_at(c, r.o, d, &h, &s)) continue;
            double L[3];
            door_bounce(c, &s, &rng, L, &rays);
            if (!bk_finite3(L) || !isfinite(wgt)) continue;
            acc_add(&a, d, r.sphere ? 1 : dot3(d, r.n), L, NULL, wgt);
        }
        acc_store(c, i, &a);
    }
    c->thread_rays[thread] += rays;
}

/* ---- stages 2+: further bounces through the texel cache ---------------------------------------- */

static void stage_bounce(dg_ctx *c, size_t begin, size_t end, int thread)
{
    uint64_t rays = 0;
    const int N = c->Nb;
    for (size_t i = begin; i < end; i++) {
        dg_recv r;
        recv_setup(c, i, &r);
        dg_acc a;
        memset(&a, 0, sizeof a);
        const double w = (r.sphere ? 4 * DG_PI : 2 * DG_PI) / N;
        bk_rng rng = bk_door_rng_make(c->in->seed, DOM_BOUNCE, (uint64_t)c->bounce, i);
        double s1 = bk_rng_next(&rng), s2 = bk_rng_next(&rng);
        for (int j = 0; j < N; j++) {
            double d[3], u1 = (double)j / N + s1, u2 = (double)j * 0.6180339887498949 + s2;
            uniform_dir(&r, u1 - floor(u1), u2 - floor(u2), d);
            float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
            bk_hit h;
            rays++;
            if (!bk_tracer_intersect(c->in->tracer, r.o, df, 0.0f, INFINITY, &h)) continue;
            dg_surf s;
            if (!surface_at(c, r.o, d, &h, &s)) continue;
            long k = cache_lookup(c, s.y, s.n);
            if (k < 0) continue;
            double L[3];
            for (int ch = 0; ch < 3; ch++) L[ch] = s.albedo[ch] / DG_PI * c->prev_e[3 * k + ch];
            acc_add(&a, d, r.sphere ? 1 : dot3(d, r.n), L, NULL, w);
        }
        acc_store(c, i, &a);
    }
    c->thread_rays[thread] += rays;
}

/* ---- parallel-for (scene/parallel.h: items independent, results independent of threads) ----- */

typedef void (*dg_fn)(dg_ctx *c, size_t begin, size_t end, int thread);
typedef struct dg_call { dg_ctx *c; dg_fn fn; } dg_call;

static void dg_call_run(void *user, size_t begin, size_t end, int thread)
{
    const dg_call *k = user;
    k->fn(k->c, begin, end, thread);
}

static void parallel_for(dg_ctx *c, size_t n, dg_fn fn)
{
    dg_call k = {c, fn};
    bk_parallel_chunks(0, n, 16, c->threads, dg_call_run, &k);
}


/* ---- the run ------------------------------------------------------------------------------------ */

static void add_stage(const dg_ctx *c, lbk_sh9_rgb *radiance, lbk_sh9_rgb *direct, double f)
{
    for (size_t i = 0; i < c->in->receiver_count; i++)
        for (int ch = 0; ch < 3; ch++) {
            if (c->in->irradiance) c->in->irradiance[3 * i + ch] += (float)(f * c->cur_e[3 * i + ch]);
            for (int k = 0; k < 9; k++) {
                radiance[i].c[ch][k] += (float)(f * c->stage_sh[i].c[ch][k]);
                if (direct && c->stage_direct) direct[i].c[ch][k] += (float)(f * c->stage_direct[i].c[ch][k]);
            }
        }
}

static double texel_energy(const dg_ctx *c)
{
    double s = 0;
    for (size_t i = 0; i < c->in->texel_receivers; i++)
        if (!(c->in->not_cache && c->in->not_cache[i])) s += lumf(&c->cur_e[3 * i]);
    return s;
}

/* The run's buffers, the base lights (those in no light set) and the base irradiance of every
 * texel receiver (the cache the first bounce gathers against). */
static lbk_result ctx_setup(dg_ctx *c, const bk_door_guided_inputs *in, int want_direct)
{
    size_t n = in->receiver_count, nt = in->texel_receivers;
    c->in = in;
    c->S = in->samples > 0 ? in->samples : 64;
    c->threads = bk_thread_count(in->threads);
    for (size_t i = 0; i < in->scene->tri_count; i++) {
        float sc = bk_tracer_tri_scale(in->tracer, (uint32_t)i);
        if (sc > c->scene_scale) c->scene_scale = sc;
    }
    c->lights = malloc((in->scene->light_count ? in->scene->light_count : 1) * sizeof *c->lights);
    c->base_e = calloc(3 * (nt ? nt : 1), sizeof(float));
    c->prev_e = calloc(3 * (nt ? nt : 1), sizeof(float));
    c->cur_e = calloc(3 * (n ? n : 1), sizeof(float));
    c->stage_sh = calloc(n ? n : 1, sizeof *c->stage_sh);
    c->stage_direct = want_direct ? calloc(n ? n : 1, sizeof *c->stage_direct) : NULL;
    c->thread_rays = calloc((size_t)c->threads, sizeof *c->thread_rays);
    c->thread_portal = calloc((size_t)c->threads, sizeof *c->thread_portal);
    c->thread_portal_n = calloc((size_t)c->threads, sizeof *c->thread_portal_n);
    if (!c->lights || !c->base_e || !c->prev_e || !c->cur_e || !c->stage_sh || (want_direct && !c->stage_direct) ||
        !c->thread_rays || !c->thread_portal || !c->thread_portal_n)
        return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < in->scene->light_count; i++)
        if (!in->scene->lights[i].light_set[0]) c->lights[c->nl++] = (uint32_t)i;
    for (size_t i = 0; i < nt; i++) {
        const float *nf = in->receivers[i].normal;
        double nn[3] = {nf[0], nf[1], nf[2]}, e[3];
        sh_irradiance(&in->base_radiance[i], nn, e);
        for (int k = 0; k < 3; k++) c->base_e[3 * i + k] = (float)e[k];
    }
    return grid_build(c);
}

static void ctx_free(dg_ctx *c)
{
    free(c->lights), free(c->base_e), free(c->prev_e), free(c->cur_e), free(c->stage_sh), free(c->stage_direct);
    free(c->thread_rays), free(c->thread_portal), free(c->thread_portal_n);
    free(c->grid.keys), free(c->grid.texel);
}

/* The guide boxes (seed §4.2): the caller's, or shadow photons shot from the portal clustered
 * into `own`. *photons gets how many were shot. */
static lbk_result guide_boxes(dg_ctx *c, bk_guide_boxes *own, size_t *photons)
{
    const bk_door_guided_inputs *in = c->in;
    *photons = 0;
    if (in->boxes) {
        c->boxes = in->boxes;
        return LBK_OK;
    }
    bk_photon_options po;
    memset(&po, 0, sizeof po);
    po.seed = in->seed;
    po.count = in->photons;
    po.use_sky = in->use_sky;
    bk_photon *ph = NULL;
    lbk_result res = bk_shoot_shadow_photons(in->scene, in->tracer, &in->portal, &po, &ph, photons);
    if (res == LBK_OK) {
        double diag = 2 * sqrt(in->portal.hu * in->portal.hu + in->portal.hv * in->portal.hv);
        res = bk_cluster_photons(ph, *photons, BK_GUIDE_MAX_BOXES, 0.1, 0.05 * diag, own);
    }
    free(ph);
    if (res == LBK_OK) c->boxes = own;
    return res;
}

/* Stage 0 (door-direct light: portal samples) and stage 1 (the first bounce off it: half
 * uniform, half guided gathers; all uniform without boxes). Returns stage 1's texel energy. */
static double direct_and_first_bounce(dg_ctx *c, lbk_sh9_rgb *radiance, lbk_sh9_rgb *direct, bk_door_guided_stats *st)
{
    size_t n = c->in->receiver_count;
    c->stage = 0;
    parallel_for(c, n, stage0);
    add_stage(c, radiance, direct, 1.0);
    st->stage_energy[0] = texel_energy(c);
    if (c->stage_direct) {
        free(c->stage_direct);
        c->stage_direct = NULL;
    }
    c->Ng = c->boxes->count > 0 ? c->S / 2 : 0;
    c->Nu = c->S - c->Ng;
    c->stage = 1;
    parallel_for(c, n, stage1);
    add_stage(c, radiance, NULL, 1.0);
    st->stage_energy[1] = texel_energy(c);
    st->bounces = 1;
    return st->stage_energy[1];
}

/* Stages 2+: uniform gathers of the previous bounce at the texels until a bounce adds under
 * 1 % of the total, then the rest of the series shaped like the last bounce (ratio q). */
static void later_bounces(dg_ctx *c, lbk_sh9_rgb *radiance, double p_prev, bk_door_guided_stats *st)
{
    size_t n = c->in->receiver_count, nt = c->in->texel_receivers;
    double total = st->stage_energy[0] + p_prev;
    int max_b = c->in->max_bounces > 0 ? c->in->max_bounces : 4;
    /* later bounces are smooth: a quarter of the budget each */
    c->Nb = c->S / 4 > 8 ? c->S / 4 : 8;
    double q = 0, rest = 0;
    for (int k = 2; k <= max_b + 1 && p_prev > 0; k++) {
        memcpy(c->prev_e, c->cur_e, 3 * nt * sizeof(float));
        c->bounce = k;
        parallel_for(c, n, stage_bounce);
        add_stage(c, radiance, NULL, 1.0);
        double p = texel_energy(c);
        q = p_prev > 0 ? p / p_prev : 0;
        rest += p;
        total += p;
        p_prev = p;
        st->bounces = k;
        if (!(p > 1e-2 * total)) break;
    }
    q = q < 0 ? 0 : q > 0.95 ? 0.95 : q;
    if (st->bounces >= 2 && q > 0) {
        add_stage(c, radiance, NULL, q / (1 - q));
        rest += p_prev * q / (1 - q);
    }
    st->q = q;
    st->stage_energy[2] = rest;
}

static void sum_thread_counters(const dg_ctx *c, bk_door_guided_stats *st)
{
    for (int t = 0; t < c->threads; t++) {
        st->rays += c->thread_rays[t];
        st->portal_samples += c->thread_portal[t];
    }
    uint64_t seen = 0;
    for (int t = 0; t < c->threads; t++) seen += c->thread_portal_n[t];
    st->portal_samples = seen ? st->portal_samples / (double)seen : 0;
}

lbk_result bk_door_guided_run(const bk_door_guided_inputs *in, lbk_sh9_rgb *radiance, lbk_sh9_rgb *direct,
                              bk_door_guided_stats *stats, bk_guide_boxes *boxes_out)
{
    double t0 = bk_now();
    bk_door_guided_stats st;
    memset(&st, 0, sizeof st);
    if (boxes_out) memset(boxes_out, 0, sizeof *boxes_out);
    if (!in || !in->scene || !in->tracer || !radiance || (in->receiver_count && (!in->receivers || !in->base_radiance)) ||
        in->texel_receivers > in->receiver_count)
        return LBK_ERR_INVALID_ARGUMENT;
    size_t n = in->receiver_count;
    memset(radiance, 0, n * sizeof *radiance);
    if (direct) memset(direct, 0, n * sizeof *direct);
    if (in->irradiance) memset(in->irradiance, 0, 3 * n * sizeof *in->irradiance);
    dg_ctx c;
    memset(&c, 0, sizeof c);
    bk_guide_boxes own;
    memset(&own, 0, sizeof own);
    lbk_result res = ctx_setup(&c, in, direct != NULL);
    if (res == LBK_OK) res = guide_boxes(&c, &own, &st.photons);
    if (res == LBK_OK) {
        st.boxes = c.boxes->count;
        later_bounces(&c, radiance, direct_and_first_bounce(&c, radiance, direct, &st), &st);
        sum_thread_counters(&c, &st);
        if (boxes_out && c.boxes == &own) {
            *boxes_out = own;
            memset(&own, 0, sizeof own);
        }
    }
    bk_guide_boxes_free(&own);
    ctx_free(&c);
    st.seconds = bk_now() - t0;
    if (stats) *stats = st;
    return res;
}
