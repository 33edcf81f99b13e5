/* GLG probe placement: a cell-centred grid over the scene bounds, cells holding geometry split
 * into octants (denser probes near surfaces), candidates inside closed geometry rejected by a
 * back-face majority vote, candidates close to a surface pushed out, a cap reached by
 * coarsening. Every step is a pure function of the scene and the options. */
#include "bake/probes/glg_place.h"

#include "bake/probes/delaunay.h"
#include "bake/probes/probe_math.h"
#include "bake/util/parallel.h"

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
    int levels;
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

/* Emits the centre of the cell, or of its octants where the cell holds geometry. list holds the
 * triangles overlapping the parent; scratch has room for level-many filtered lists. */
static void refine(const place_ctx *c, candidates *out, const double centre[3], const double half[3],
                   const uint32_t *list, size_t n, int level, uint32_t *scratch)
{
    size_t m = 0;
    if (level < c->levels && out->n < c->max_candidates)
        for (size_t i = 0; i < n; i++)
            if (tri_hits_box(c, list[i], centre, half)) scratch[m++] = list[i];
    if (m == 0) {
        cand_push(out, centre[0], centre[1], centre[2]);
        return;
    }
    double h[3] = {0.5 * half[0], 0.5 * half[1], 0.5 * half[2]};
    for (int o = 0; o < 8; o++) {
        double cc[3] = {centre[0] + ((o & 1) ? h[0] : -h[0]), centre[1] + ((o & 2) ? h[1] : -h[1]),
                        centre[2] + ((o & 4) ? h[2] : -h[2])};
        refine(c, out, cc, h, scratch, m, level + 1, scratch + m);
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
    size_t maxbin = 0;
    for (size_t i = 0; i < ncell; i++) if (start[i + 1] - start[i] > maxbin) maxbin = start[i + 1] - start[i];
    scratch = malloc(((size_t)(c->levels + 1) * maxbin + 1) * sizeof *scratch);
    if (!scratch) { res = LBK_ERR_OUT_OF_MEMORY; goto done; }
    for (int64_t z = 0; z < dims[2]; z++) for (int64_t y = 0; y < dims[1]; y++) for (int64_t x = 0; x < dims[0]; x++) {
        size_t id = (size_t)((z * dims[1] + y) * dims[0] + x);
        double centre[3] = {lo[0] + (x + 0.5) * cell[0], lo[1] + (y + 0.5) * cell[1], lo[2] + (z + 0.5) * cell[2]};
        double half[3] = {0.5 * cell[0], 0.5 * cell[1], 0.5 * cell[2]};
        refine(c, &cand, centre, half, bins + start[id], start[id + 1] - start[id], 0, scratch);
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
    free(cand.p); free(scratch); free(bins); free(start);
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
    size_t cap = o.max_probes ? o.max_probes : 16384;
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
    lbk_result res = LBK_OK;
    for (int attempt = 0; attempt < 200; attempt++) {
        c.levels = levels;
        c.user_min_distance = o.min_distance > 0 && isfinite(o.min_distance) ? o.min_distance : 0.0f;
        c.max_candidates = 8 * cap;
        bk_glg_probes_free(out);
        res = place_once(&c, lo, ext, spacing, threads, out);
        if (res != LBK_OK) break;
        out->spacing = (float)spacing;
        out->refine_levels = levels;
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
    int st = bk_delaunay(probes.positions, probes.count, NULL, &mesh);
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
