/* GLG probe placement: a cell-centred grid over the scene bounds, cells holding geometry split
 * into octants (denser probes near surfaces), candidates inside closed geometry rejected by a
 * back-face majority vote, candidates close to a surface pushed out, a cap reached by
 * coarsening. Every step is a pure function of the scene and the options. */
#include "bake/probes/glg_place.h"

#include "bake/probes/delaunay.h"
#include "bake/probes/probe_math.h"
#include "scene/clock.h"
#include "scene/parallel.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_REFINE 4

typedef struct candidates { float *p; size_t n, cap; int oom; } candidates;

static void cand_push(candidates *c, double x, double y, double z)
{
    if (c->oom) return;
    if (c->n == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 1024;
        float *p = realloc(c->p, 3 * cap * sizeof *p);
        if (!p) { c->oom = 1; return; }
        c->p = p; c->cap = cap;
    }
    c->p[3 * c->n] = (float)x; c->p[3 * c->n + 1] = (float)y; c->p[3 * c->n + 2] = (float)z;
    c->n++;
}

typedef struct place_ctx {
    const bk_scene *scene;
    const bk_tracer *tracer;
    const uint32_t *tris;      /* usable (finite, non-degenerate) triangle ids */
    size_t tri_count;
    int levels;                /* deepest refinement (scratch, clearance): geo_levels + max depth */
    int geo_levels;            /* near-geometry halvings below a cell's adaptive depth */
    /* adaptive density (bk_glg_options): 0 = off, the top grid at the spacing, no depths */
    int adaptive;
    int playable_levels, lighting_levels;
    float lighting_threshold;
    bk_glg_lighting_fn lighting;
    void *lighting_user;
    size_t coarse_points, cells_by_depth[4];
    double pad;                /* cells are grown by this before the overlap test */
    size_t max_candidates;     /* stop refining past this (the cap will coarsen anyway) */
    /* per-candidate test */
    const float *cand;
    float *out;                /* 3 per candidate: final position */
    uint8_t *verdict;          /* 0 keep, 1 solid, 2 too close; bit 4: pushed */
    int rays;
    float min_distance;
    float max_push;            /* a probe never moves farther than this from its cell centre */
    float user_min_distance;   /* option, 0: derived from the cell size */
} place_ctx;

static int tri_hits_box(const place_ctx *c, uint32_t t, const double centre[3], const double half[3])
{
    const uint32_t *v = c->scene->tris + 3 * (size_t)t;
    const float *P = c->scene->positions;
    double h[3] = {half[0] + c->pad, half[1] + c->pad, half[2] + c->pad};
    return bk_tri_box_overlap(centre, h, P + 3 * (size_t)v[0], P + 3 * (size_t)v[1], P + 3 * (size_t)v[2]);
}

/* Emits the centre of the cell, or of its octants: split while level < force (the adaptive
 * depth of its top cell), and while level < geo_end where the cell holds geometry. list holds the
 * triangles overlapping the parent; scratch has room for level-many filtered lists. */
static void refine(const place_ctx *c, candidates *out, const double centre[3], const double half[3],
                   const uint32_t *list, size_t n, int level, int force, int geo_end, uint32_t *scratch)
{
    size_t m = 0;
    int room = out->n < c->max_candidates;
    if (level < geo_end && room)
        for (size_t i = 0; i < n; i++)
            if (tri_hits_box(c, list[i], centre, half)) scratch[m++] = list[i];
    if (m == 0 && !(level < force && room)) {
        cand_push(out, centre[0], centre[1], centre[2]);
        return;
    }
    double h[3] = {0.5 * half[0], 0.5 * half[1], 0.5 * half[2]};
    for (int o = 0; o < 8; o++) {
        double cc[3] = {centre[0] + ((o & 1) ? h[0] : -h[0]), centre[1] + ((o & 2) ? h[1] : -h[1]),
                        centre[2] + ((o & 4) ? h[2] : -h[2])};
        refine(c, out, cc, h, scratch, m, level + 1, force, geo_end, scratch + m);
    }
}

static int tri_material_double_sided(const bk_scene *s, uint32_t tri)
{
    if (!s->tri_material || !s->materials) return 0;
    uint32_t m = s->tri_material[tri];
    return m < s->material_count ? s->materials[m].double_sided : 0;
}

/* Casts the test rays from p: counts front/back hits and finds the nearest surface. */
static void probe_rays(const place_ctx *c, const float p[3], int *front, int *back, float *nearest,
                       float away[3])
{
    *front = 0; *back = 0; *nearest = FLT_MAX;
    away[0] = away[1] = away[2] = 0.0f;
    for (int r = 0; r < c->rays; r++) {
        float d[3];
        bk_sphere_direction((size_t)r, (size_t)c->rays, d);
        bk_hit hit;
        if (!bk_tracer_intersect(c->tracer, p, d, 0.0f, FLT_MAX, &hit)) continue;
        int is_front = hit.front || tri_material_double_sided(c->scene, hit.tri);
        if (is_front) (*front)++; else (*back)++;
        if (hit.t < *nearest) {
            *nearest = hit.t;
            /* away from the surface: the side the ray came from */
            float s = (d[0] * hit.ng[0] + d[1] * hit.ng[1] + d[2] * hit.ng[2]) < 0.0f ? 1.0f : -1.0f;
            away[0] = s * hit.ng[0]; away[1] = s * hit.ng[1]; away[2] = s * hit.ng[2];
        }
    }
}

static void test_candidate(const place_ctx *c, size_t i)
{
    float p[3] = {c->cand[3 * i], c->cand[3 * i + 1], c->cand[3 * i + 2]};
    uint8_t verdict = 0;
    for (int iter = 0;; iter++) {
        int front, back; float nearest, away[3];
        probe_rays(c, p, &front, &back, &nearest, away);
        if (back > front) { verdict = (uint8_t)(verdict | 1); break; }
        if (nearest >= c->min_distance) break;
        if (iter == 3) { verdict = (uint8_t)(verdict | 2); break; }
        /* move out to the full clearance (plus a little: the nearest ray is approximate) */
        float step = 1.25f * c->min_distance - nearest;
        for (int k = 0; k < 3; k++) p[k] += step * away[k];
        verdict = (uint8_t)(verdict | 16);
        /* a probe pushed out of its cell would stand in someone else's (or outside the level) */
        float moved = 0.0f;
        for (int k = 0; k < 3; k++) moved += (p[k] - c->cand[3 * i + k]) * (p[k] - c->cand[3 * i + k]);
        if (moved > c->max_push * c->max_push) { verdict = (uint8_t)(verdict | 2); break; }
    }
    memcpy(c->out + 3 * i, p, sizeof p);
    c->verdict[i] = verdict;
}

static void test_candidates(void *vctx, size_t begin, size_t end, int thread)
{
    for (size_t i = begin; i < end; i++) test_candidate(vctx, i);
}

void bk_glg_probes_free(bk_glg_probes *p)
{
    if (!p) return;
    free(p->positions);
    memset(p, 0, sizeof *p);
}

/* ---- adaptive density (PROBES.md §Density by playable space and lighting) ------------------ */

static int box_overlaps(const double lo[3], const double hi[3], const bk_box *b)
{
    for (int k = 0; k < 3; k++)
        if (!(hi[k] > b->min[k] && lo[k] < b->max[k])) return 0;
    return 1;
}

static size_t cell_id(const int64_t dims[3], int64_t x, int64_t y, int64_t z)
{
    return (size_t)((z * dims[1] + y) * dims[0] + x);
}

/* The estimated relative interpolation error at a point of the coarse lattice, for a grid of
 * `step` lattice spacings: a linear interpolation between the points `step` away on either side
 * along an axis misses this one by |f(−) + f(+) − 2 f(c)| / 2, and the midpoints of such a grid,
 * where linear interpolation errs most, by about half of that. The largest over the three axes
 * and the six irradiance directions, relative to the point's own level (the mean of its six
 * values) plus `floor` (a share of the level's mean, so dark corners do not ask for probes for
 * differences nobody sees); 0 without free points on both sides along any axis (next to walls
 * the near-geometry refinement decides). The coarse pass's noise is taken off first: a second
 * difference only counts beyond 2 standard deviations of its own noise (the three points'
 * variances, the centre's four times), so few samples do not refine a smooth level. */
static double lattice_error(const int64_t dims[3], const int64_t *slot, const float *val, int64_t x, int64_t y,
                            int64_t z, int64_t step, double floor)
{
    int64_t me = slot[cell_id(dims, x, y, z)];
    if (me < 0) return 0.0;
    int64_t at[3] = {x, y, z};
    double e = 0.0, level = floor;
    for (int d = 0; d < 6; d++) level += val[7 * me + d] / 6.0;
    for (int a = 0; a < 3; a++) {
        if (at[a] < step || at[a] + step >= dims[a]) continue;
        int64_t m[3] = {x, y, z}, p[3] = {x, y, z};
        m[a] -= step; p[a] += step;
        int64_t sm = slot[cell_id(dims, m[0], m[1], m[2])], sp = slot[cell_id(dims, p[0], p[1], p[2])];
        if (sm < 0 || sp < 0) continue;
        double var = (double)val[7 * sm + 6] + val[7 * sp + 6] + 4.0 * val[7 * me + 6];
        double noise = 2.0 * sqrt(var > 0.0 ? var : 0.0);
        for (int d = 0; d < 6; d++) {
            double d2 = (double)val[7 * sm + d] + val[7 * sp + d] - 2.0 * val[7 * me + d];
            e = fmax(e, 0.25 * (fabs(d2) - noise));
        }
    }
    return level > 0.0 ? e / level : 0.0;
}

/* The lighting rule. The coarse pass lights a lattice twice as fine as the top grid (the centres
 * of the top cells' octants, solid-tested and pushed out like candidates). A top cell gets depth 1
 * where a grid of its own spacing (lattice step 2) would err by more than threshold × the mean
 * irradiance at one of its octant centres, depth 2 where a grid of half its spacing (step 1)
 * would, depth 3 where that one errs by more than 2 × the bar (a step's error only halves with
 * the spacing). */
static lbk_result lighting_depths(place_ctx *c, const double lo[3], const double cell[3], const int64_t top[3],
                                  int threads, uint8_t *depth)
{
    const int64_t dims[3] = {2 * top[0], 2 * top[1], 2 * top[2]};
    size_t ncell = (size_t)(dims[0] * dims[1] * dims[2]);
    lbk_result res = LBK_OK;
    float *pts = malloc(ncell * 3 * sizeof *pts), *moved = malloc(ncell * 3 * sizeof *moved), *val = NULL;
    uint8_t *verdict = malloc(ncell);
    int64_t *slot = malloc(ncell * sizeof *slot);
    if (!pts || !moved || !verdict || !slot) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }
    for (int64_t z = 0; z < dims[2]; z++) for (int64_t y = 0; y < dims[1]; y++) for (int64_t x = 0; x < dims[0]; x++) {
        float *p = pts + 3 * cell_id(dims, x, y, z);
        p[0] = (float)(lo[0] + (x + 0.5) * 0.5 * cell[0]); p[1] = (float)(lo[1] + (y + 0.5) * 0.5 * cell[1]);
        p[2] = (float)(lo[2] + (z + 0.5) * 0.5 * cell[2]);
    }
    c->cand = pts; c->out = moved; c->verdict = verdict;
    if (c->tracer) bk_parallel_chunks(0, ncell, 16, bk_thread_count(threads), test_candidates, c);
    else { memcpy(moved, pts, ncell * 3 * sizeof *pts); memset(verdict, 0, ncell); }
    c->cand = NULL; c->out = NULL; c->verdict = NULL;
    size_t nv = 0;
    for (size_t i = 0; i < ncell; i++) {
        if (verdict[i] & 3) { slot[i] = -1; continue; }
        memmove(moved + 3 * nv, moved + 3 * i, 3 * sizeof *moved);   /* compact: nv <= i */
        slot[i] = (int64_t)nv++;
    }
    c->coarse_points = nv;
    if (nv == 0) goto done;
    val = malloc(nv * 7 * sizeof *val);
    if (!val) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }
    res = c->lighting(c->lighting_user, moved, nv, val);
    if (res != LBK_OK) goto done;
    double mean = 0.0;
    for (size_t i = 0; i < 7 * nv; i++) {
        if (!isfinite(val[i]) || val[i] < 0.0f) val[i] = 0.0f;   /* a caller's NaN refines nothing */
        if (i % 7 != 6) mean += val[i];
    }
    mean /= (double)(6 * nv);
    if (!(mean > 0.0)) goto done;   /* a dark level: nothing to follow */
    const double bar = c->lighting_threshold, floor = 0.05 * mean;
    for (int64_t z = 0; z < top[2]; z++) for (int64_t y = 0; y < top[1]; y++) for (int64_t x = 0; x < top[0]; x++) {
        double e_top = 0.0, e_half = 0.0;
        for (int o = 0; o < 8; o++) {
            int64_t lx = 2 * x + (o & 1), ly = 2 * y + ((o >> 1) & 1), lz = 2 * z + ((o >> 2) & 1);
            e_top = fmax(e_top, lattice_error(dims, slot, val, lx, ly, lz, 2, floor));
            e_half = fmax(e_half, lattice_error(dims, slot, val, lx, ly, lz, 1, floor));
        }
        int k = e_half > 2.0 * bar ? 3 : e_half > bar ? 2 : e_top > bar ? 1 : 0;
        if (k > c->lighting_levels) k = c->lighting_levels;
        uint8_t *d = &depth[cell_id(top, x, y, z)];
        *d = (uint8_t)((*d & 0xF0) | k);
    }
done:
    free(pts); free(moved); free(verdict); free(slot); free(val);
    return res;
}

/* Per top cell, how many times it is split before the near-geometry rule: the playable rule's
 * depth in the high nibble, the lighting rule's in the low one. */
static lbk_result adaptive_depths(place_ctx *c, const double lo[3], const double cell[3], const int64_t dims[3],
                                  int threads, uint8_t *depth)
{
    const bk_scene *s = c->scene;
    if (c->playable_levels > 0)
        for (int64_t z = 0; z < dims[2]; z++) for (int64_t y = 0; y < dims[1]; y++) for (int64_t x = 0; x < dims[0]; x++) {
            double a[3] = {lo[0] + x * cell[0], lo[1] + y * cell[1], lo[2] + z * cell[2]};
            double b[3] = {a[0] + cell[0], a[1] + cell[1], a[2] + cell[2]};
            for (size_t i = 0; i < s->playable_count; i++)
                if (box_overlaps(a, b, &s->playable[i])) { depth[cell_id(dims, x, y, z)] = (uint8_t)(c->playable_levels << 4); break; }
        }
    lbk_result res = c->lighting ? lighting_depths(c, lo, cell, dims, threads, depth) : LBK_OK;
    size_t ncell = (size_t)(dims[0] * dims[1] * dims[2]);
    memset(c->cells_by_depth, 0, sizeof c->cells_by_depth);
    for (size_t i = 0; i < ncell; i++) {
        int pf = depth[i] >> 4, lf = depth[i] & 15, d = pf > lf ? pf : lf;
        c->cells_by_depth[d < 3 ? d : 3]++;
    }
    return res;
}

/* One placement attempt at a given spacing and refinement. */
static lbk_result place_once(place_ctx *c, const double lo[3], const double ext[3], double spacing,
                             int threads, bk_glg_probes *out)
{
    lbk_result res = LBK_OK;
    int64_t dims[3];
    double cell[3];
    for (int k = 0; k < 3; k++) {
        double d = ceil(ext[k] / spacing - 1e-9);
        dims[k] = d < 1.0 ? 1 : (int64_t)d;
        cell[k] = ext[k] / (double)dims[k];
    }
    /* clearance and overlap padding from the finest cell actually used, so tiny scenes scale */
    double finest = DBL_MAX;
    for (int k = 0; k < 3; k++) if (cell[k] > 0.0 && cell[k] < finest) finest = cell[k];
    if (finest == DBL_MAX) finest = spacing;
    finest /= (double)(1 << c->levels);
    c->min_distance = c->user_min_distance > 0 ? c->user_min_distance : (float)(0.25 * finest);
    c->pad = fmin((double)c->min_distance, 0.25 * finest);
    c->max_push = (float)fmax(0.5 * finest, 2.0 * c->min_distance);
    size_t ncell = (size_t)(dims[0] * dims[1] * dims[2]);
    /* bin usable triangles into top cells (CSR) by their padded bounding boxes */
    size_t *start = calloc(ncell + 1, sizeof *start);
    uint32_t *bins = NULL, *scratch = NULL;
    uint8_t *depth = NULL;
    candidates cand = {0};
    if (!start) return LBK_ERR_OUT_OF_MEMORY;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < c->tri_count; i++) {
            const uint32_t *v = c->scene->tris + 3 * (size_t)c->tris[i];
            int64_t a[3], b[3];
            for (int k = 0; k < 3; k++) {
                double mn = DBL_MAX, mx = -DBL_MAX;
                for (int j = 0; j < 3; j++) {
                    double x = c->scene->positions[3 * (size_t)v[j] + k];
                    mn = fmin(mn, x); mx = fmax(mx, x);
                }
                double fa = cell[k] > 0 ? floor((mn - c->pad - lo[k]) / cell[k]) : 0.0;
                double fb = cell[k] > 0 ? floor((mx + c->pad - lo[k]) / cell[k]) : 0.0;
                a[k] = fa < 0 ? 0 : fa > (double)(dims[k] - 1) ? dims[k] - 1 : (int64_t)fa;
                b[k] = fb < 0 ? 0 : fb > (double)(dims[k] - 1) ? dims[k] - 1 : (int64_t)fb;
            }
            for (int64_t z = a[2]; z <= b[2]; z++) for (int64_t y = a[1]; y <= b[1]; y++)
                for (int64_t x = a[0]; x <= b[0]; x++) {
                    size_t id = (size_t)((z * dims[1] + y) * dims[0] + x);
                    if (pass == 0) start[id + 1]++;
                    else bins[start[id]++] = c->tris[i];
                }
        }
        if (pass == 0) {
            for (size_t i = 0; i < ncell; i++) start[i + 1] += start[i];
            bins = malloc((start[ncell] ? start[ncell] : 1) * sizeof *bins);
            if (!bins) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }
        } else {
            for (size_t i = ncell; i > 0; i--) start[i] = start[i - 1];
            start[0] = 0;
        }
    }
    if (c->adaptive) {
        depth = calloc(ncell, 1);
        if (!depth) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }
        res = adaptive_depths(c, lo, cell, dims, threads, depth);
        if (res != LBK_OK) goto done;
    }
    size_t maxbin = 0;
    for (size_t i = 0; i < ncell; i++) if (start[i + 1] - start[i] > maxbin) maxbin = start[i + 1] - start[i];
    scratch = malloc(((size_t)(c->levels + 1) * maxbin + 1) * sizeof *scratch);
    if (!scratch) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }
    for (int64_t z = 0; z < dims[2]; z++) for (int64_t y = 0; y < dims[1]; y++) for (int64_t x = 0; x < dims[0]; x++) {
        size_t id = (size_t)((z * dims[1] + y) * dims[0] + x);
        double centre[3] = {lo[0] + (x + 0.5) * cell[0], lo[1] + (y + 0.5) * cell[1], lo[2] + (z + 0.5) * cell[2]};
        double half[3] = {0.5 * cell[0], 0.5 * cell[1], 0.5 * cell[2]};
        /* playable cells keep the near-geometry refinement below their depth (inside, the density
         * of the non-adaptive placement); lit cells get it only beyond their depth */
        int pf = depth ? depth[id] >> 4 : 0, lf = depth ? depth[id] & 15 : 0, force = pf > lf ? pf : lf;
        int geo_end = pf + c->geo_levels > force ? pf + c->geo_levels : force;
        refine(c, &cand, centre, half, bins + start[id], start[id + 1] - start[id], 0, force, geo_end, scratch);
    }
    if (cand.oom) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }

    out->candidates = cand.n;
    out->positions = malloc((cand.n ? cand.n : 1) * 3 * sizeof(float));
    c->verdict = malloc(cand.n ? cand.n : 1);
    if (!out->positions || !c->verdict) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }
    c->cand = cand.p;
    c->out = out->positions;
    if (c->tracer) bk_parallel_chunks(0, cand.n, 16, bk_thread_count(threads), test_candidates, c);
    else { memcpy(out->positions, cand.p, cand.n * 3 * sizeof(float)); memset(c->verdict, 0, cand.n); }
    size_t n = 0;
    for (size_t i = 0; i < cand.n; i++) {
        uint8_t v = c->verdict[i];
        if (v & 1) { out->rejected_solid++; continue; }
        if (v & 2) { out->rejected_close++; continue; }
        if (v & 16) out->pushed++;
        memmove(out->positions + 3 * n, out->positions + 3 * i, 3 * sizeof(float));
        n++;
    }
    out->count = n;
done:
    free(c->verdict); c->verdict = NULL;
    free(cand.p); free(scratch); free(bins); free(start); free(depth);
    return res;
}

lbk_result bk_glg_place(const bk_scene *scene, const bk_tracer *tracer,
                        const bk_glg_options *options, int threads, bk_glg_probes *out)
{
    if (!scene || !out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    bk_glg_options o = options ? *options : (bk_glg_options){0};
    double spacing = o.spacing > 0 && isfinite(o.spacing) ? o.spacing : 1.0;
    int levels = o.refine_levels < 0 ? 0 : o.refine_levels == 0 ? 1 : o.refine_levels;
    if (levels > MAX_REFINE) levels = MAX_REFINE;
    size_t cap = o.max_probes ? o.max_probes : BK_GLG_DEFAULT_MAX_PROBES;
    int rays = o.solid_rays > 0 ? o.solid_rays : 32;
    if (rays > 1024) rays = 1024;

    /* usable triangles and their bounds */
    uint32_t *tris = malloc((scene->tri_count ? scene->tri_count : 1) * sizeof *tris);
    if (!tris) return LBK_ERR_OUT_OF_MEMORY;
    size_t nt = 0;
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (size_t t = 0; t < scene->tri_count && t < UINT32_MAX; t++) {
        const uint32_t *v = scene->tris + 3 * t;
        if (v[0] >= scene->vertex_count || v[1] >= scene->vertex_count || v[2] >= scene->vertex_count) continue;
        const float *a = scene->positions + 3 * (size_t)v[0], *b = scene->positions + 3 * (size_t)v[1];
        const float *cc = scene->positions + 3 * (size_t)v[2];
        int ok = 1;
        for (int k = 0; k < 3; k++) ok &= isfinite(a[k]) && isfinite(b[k]) && isfinite(cc[k]);
        if (!ok) continue;
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]};
        double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        if (!(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2] > 0.0)) continue;
        tris[nt++] = (uint32_t)t;
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], fmin(a[k], fmin(b[k], cc[k])));
            hi[k] = fmax(hi[k], fmax(a[k], fmax(b[k], cc[k])));
        }
    }
    if (nt == 0) { free(tris); return LBK_OK; }
    double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    /* start no finer than the cap allows for the top grid alone */
    double vol = 1.0;
    for (int k = 0; k < 3; k++) vol *= fmax(ext[k], spacing);
    double s_cap = cbrt(vol / (double)cap);
    if (s_cap > spacing) spacing = s_cap;

    place_ctx c = {0};
    c.scene = scene; c.tracer = tracer; c.tris = tris; c.tri_count = nt; c.rays = rays;
    /* adaptive: a top grid twice as coarse, split where playable or where the lighting varies */
    c.playable_levels = o.playable_levels < 0 || !scene->playable_count || !scene->playable ? 0
                      : o.playable_levels == 0 ? 1 : o.playable_levels > 2 ? 2 : o.playable_levels;
    c.lighting = o.lighting;
    c.lighting_user = o.lighting_user;
    c.lighting_levels = !o.lighting ? 0 : o.lighting_levels <= 0 ? 2 : o.lighting_levels > 3 ? 3 : o.lighting_levels;
    c.lighting_threshold = o.lighting_threshold > 0 && isfinite(o.lighting_threshold) ? o.lighting_threshold : 0.4f;
    c.adaptive = c.playable_levels > 0 || c.lighting;
    const int max_depth = c.playable_levels > c.lighting_levels ? c.playable_levels : c.lighting_levels;
    if (c.adaptive) spacing *= 2.0;
    lbk_result res = LBK_OK;
    for (int attempt = 0; attempt < 200; attempt++) {
        c.geo_levels = levels;
        c.levels = levels + max_depth;
        c.user_min_distance = o.min_distance > 0 && isfinite(o.min_distance) ? o.min_distance : 0.0f;
        c.max_candidates = 8 * cap;
        bk_glg_probes_free(out);
        res = place_once(&c, lo, ext, spacing, threads, out);
        if (res != LBK_OK) break;
        out->spacing = (float)spacing;
        out->refine_levels = levels;
        out->coarse_points = c.coarse_points;
        memcpy(out->cells_by_depth, c.cells_by_depth, sizeof out->cells_by_depth);
        if (out->count <= cap) break;
        if (levels > 0) levels--;            /* coarsen near surfaces first */
        else spacing *= 1.25;                 /* then everywhere */
    }
    free(tris);
    if (res != LBK_OK) bk_glg_probes_free(out);
    return res;
}

/* ---- per-face visibility -------------------------------------------------------------------- */
typedef struct vis_ctx {
    const bk_tracer *tracer;
    const float *pos;
    const uint32_t *tets;
    int level;
    float *vis;
} vis_ctx;

/* Centroids of the 4^level triangles of the regular subdivision, as barycentrics. Strata:
 * sub-triangle (i, j) upward and downward of a level-n grid. */
static size_t face_samples(int level, float (*bary)[3])
{
    int n = 1 << level;
    size_t m = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n - i; j++) {
            /* upward triangle (i,j),(i+1,j),(i,j+1) */
            bary[m][0] = (float)((3 * i + 1) / (3.0 * n));
            bary[m][1] = (float)((3 * j + 1) / (3.0 * n));
            bary[m][2] = 1.0f - bary[m][0] - bary[m][1];
            m++;
            if (j < n - i - 1) {  /* downward (i+1,j),(i,j+1),(i+1,j+1) */
                bary[m][0] = (float)((3 * i + 2) / (3.0 * n));
                bary[m][1] = (float)((3 * j + 2) / (3.0 * n));
                bary[m][2] = 1.0f - bary[m][0] - bary[m][1];
                m++;
            }
        }
    return m;
}

static void face_vis_one(const vis_ctx *c, size_t t)
{
    float bary[256][3];
    size_t m = face_samples(c->level, bary);
    const uint32_t *v = c->tets + 4 * t;
    for (int i = 0; i < 4; i++) {
        const float *o = c->pos + 3 * (size_t)v[i];
        const float *f[3];
        int w = 0;
        for (int k = 0; k < 4; k++) if (k != i) f[w++] = c->pos + 3 * (size_t)v[k];
        size_t open = 0;
        for (size_t s = 0; s < m; s++) {
            float d[3];
            for (int k = 0; k < 3; k++)
                d[k] = bary[s][0] * f[0][k] + bary[s][1] * f[1][k] + bary[s][2] * f[2][k] - o[k];
            open += !bk_tracer_occluded(c->tracer, o, d, 1e-4f, 1.0f - 1e-4f);
        }
        c->vis[4 * t + (size_t)i] = (float)open / (float)m;
    }
}

static void face_vis_chunk(void *vctx, size_t begin, size_t end, int thread)
{
    for (size_t t = begin; t < end; t++) face_vis_one(vctx, t);
}

void bk_glg_face_visibility(const bk_tracer *tracer, const float *positions, size_t tet_count,
                            const uint32_t *tets, int level, int threads, float *vis)
{
    if (level <= 0) level = 1;
    if (level > 4) level = 4;
    vis_ctx c = {tracer, positions, tets, level, vis};
    bk_parallel_chunks(0, tet_count, 16, bk_thread_count(threads), face_vis_chunk, &c);
}

void bk_glg_free(bk_glg *g)
{
    if (!g) return;
    free(g->positions); free(g->tets); free(g->neighbours); free(g->face_visibility);
    memset(g, 0, sizeof *g);
}

lbk_result bk_glg_build(const bk_scene *scene, const bk_tracer *tracer,
                        const bk_glg_options *options, int threads, bk_glg *out)
{
    if (!scene || !tracer || !out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    bk_glg_probes probes;
    lbk_result res = bk_glg_place(scene, tracer, options, threads, &probes);
    if (res != LBK_OK) return res;
    out->spacing = probes.spacing;
    out->refine_levels = probes.refine_levels;
    if (probes.candidates == 0) { out->status = BK_GLG_EMPTY_SCENE; bk_glg_probes_free(&probes); return LBK_OK; }
    if (probes.count < 4) { out->status = BK_GLG_NO_FREE_SPACE; bk_glg_probes_free(&probes); return LBK_OK; }
    bk_tetmesh mesh;
    const double t0 = bk_now();
    int st = bk_delaunay(probes.positions, probes.count, NULL, &mesh);
    out->delaunay_seconds = bk_now() - t0;
    bk_glg_probes_free(&probes);
    if (st == BK_DELAUNAY_NO_MEMORY) { bk_tetmesh_free(&mesh); return LBK_ERR_OUT_OF_MEMORY; }
    if (st != BK_DELAUNAY_OK) {
        out->status = st == BK_DELAUNAY_FLAT ? BK_GLG_FLAT
                    : st == BK_DELAUNAY_FAILED ? BK_GLG_DELAUNAY_FAILED : BK_GLG_NO_FREE_SPACE;
        bk_tetmesh_free(&mesh);
        return LBK_OK;
    }
    out->probe_count = mesh.point_count;
    out->tet_count = mesh.tet_count;
    out->merged_cells = mesh.merged_cells;
    out->hull_ghosts = mesh.hull_ghosts;
    out->pocket_tets = mesh.pocket_tets;
    out->positions = mesh.points; mesh.points = NULL;
    out->tets = mesh.tets; mesh.tets = NULL;
    out->neighbours = mesh.neighbours; mesh.neighbours = NULL;
    bk_tetmesh_free(&mesh);
    out->face_visibility = malloc(4 * out->tet_count * sizeof *out->face_visibility);
    if (!out->face_visibility) { bk_glg_free(out); return LBK_ERR_OUT_OF_MEMORY; }
    int level = options && options->face_visibility_level > 0 ? options->face_visibility_level : 1;
    bk_glg_face_visibility(tracer, out->positions, out->tet_count, out->tets, level, threads,
                           out->face_visibility);
    out->status = BK_GLG_OK;
    return LBK_OK;
}

void bk_glg_visibility_unorm8(const bk_glg *g, uint8_t (*out)[4])
{
    for (size_t t = 0; t < g->tet_count; t++)
        for (int i = 0; i < 4; i++) {
            float v = g->face_visibility[4 * t + (size_t)i];
            v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;   /* NaN -> 0 */
            out[t][i] = (uint8_t)lrintf(v * 255.0f);
        }
}
