/* LLG construction: OBB by area-weighted PCA, a capped lattice, per-vertex self-visibility
 * against the object's own triangles. */
#include "bake/probes/llg_place.h"

#include "bake/probes/probe_math.h"
#include "scene/tracer.h"
#include "scene/parallel.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static int tri_usable(const bk_scene *s, size_t t)
{
    const uint32_t *v = s->tris + 3 * t;
    for (int k = 0; k < 3; k++) {
        if (v[k] >= s->vertex_count) return 0;
        const float *p = s->positions + 3 * (size_t)v[k];
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) return 0;
    }
    return 1;
}

lbk_result bk_obb_from_triangles(const bk_scene *s, uint32_t first_tri, uint32_t tri_count,
                                 float centre[3], float axes[3][3], float half_extents[3])
{
    if (!s || (size_t)first_tri + tri_count > s->tri_count) return LBK_ERR_INVALID_ARGUMENT;
    /* moments relative to a reference corner, so a prop 1e5 m from the origin keeps precision */
    double ref[3] = {0, 0, 0};
    int have_ref = 0;
    double area = 0.0, m1[3] = {0, 0, 0}, m2[9] = {0};
    double vcount = 0.0, vm1[3] = {0, 0, 0}, vm2[9] = {0};   /* vertex fallback (zero area) */
    for (size_t t = first_tri; t < (size_t)first_tri + tri_count; t++) {
        if (!tri_usable(s, t)) continue;
        const uint32_t *v = s->tris + 3 * t;
        if (!have_ref) {
            for (int k = 0; k < 3; k++) ref[k] = s->positions[3 * (size_t)v[0] + k];
            have_ref = 1;
        }
        double p[3][3];
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) p[j][k] = s->positions[3 * (size_t)v[j] + k] - ref[k];
        double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double a = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        double sum[3] = {p[0][0] + p[1][0] + p[2][0], p[0][1] + p[1][1] + p[2][1], p[0][2] + p[1][2] + p[2][2]};
        area += a;
        for (int r = 0; r < 3; r++) {
            m1[r] += a * sum[r] / 3.0;
            for (int c = 0; c < 3; c++) {
                /* ∫ x xᵀ dA over a triangle = A/12 (Σ vᵢvᵢᵀ + (Σvᵢ)(Σvᵢ)ᵀ) */
                double q = p[0][r] * p[0][c] + p[1][r] * p[1][c] + p[2][r] * p[2][c];
                m2[3 * r + c] += a / 12.0 * (q + sum[r] * sum[c]);
                vm2[3 * r + c] += q;
            }
            vm1[r] += sum[r];
        }
        vcount += 3.0;
    }
    if (!have_ref) return LBK_ERR_INVALID_ARGUMENT;
    double mean[3], cov[9];
    double w = area > 0.0 ? area : vcount;
    const double *M1 = area > 0.0 ? m1 : vm1, *M2 = area > 0.0 ? m2 : vm2;
    for (int r = 0; r < 3; r++) mean[r] = M1[r] / w;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) cov[3 * r + c] = M2[3 * r + c] / w - mean[r] * mean[c];
    double val[3], vec[3][3];
    bk_sym3_eigen(cov, val, vec);
    /* tight extents along the axes over all corners */
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (size_t t = first_tri; t < (size_t)first_tri + tri_count; t++) {
        if (!tri_usable(s, t)) continue;
        for (int j = 0; j < 3; j++) {
            const float *q = s->positions + 3 * (size_t)s->tris[3 * t + (size_t)j];
            double d[3] = {q[0] - ref[0], q[1] - ref[1], q[2] - ref[2]};
            for (int a = 0; a < 3; a++) {
                double x = d[0] * vec[a][0] + d[1] * vec[a][1] + d[2] * vec[a][2];
                lo[a] = fmin(lo[a], x);
                hi[a] = fmax(hi[a], x);
            }
        }
    }
    for (int k = 0; k < 3; k++) {
        double c = ref[k];
        for (int a = 0; a < 3; a++) c += vec[a][k] * 0.5 * (lo[a] + hi[a]);
        centre[k] = (float)c;
    }
    for (int a = 0; a < 3; a++) {
        half_extents[a] = (float)(0.5 * (hi[a] - lo[a]));
        for (int k = 0; k < 3; k++) axes[a][k] = (float)vec[a][k];
    }
    return LBK_OK;
}

void bk_llg_free(bk_llg *l)
{
    if (!l) return;
    free(l->vertices); free(l->visibility); free(l->bent_normals);
    memset(l, 0, sizeof *l);
}

size_t bk_llg_probe_count(const bk_llg *l)
{
    return (size_t)l->dims[0] * l->dims[1] * l->dims[2];
}

void bk_llg_probe_position(const bk_llg *l, uint32_t i, uint32_t j, uint32_t k, float out[3])
{
    uint32_t idx[3] = {i, j, k};
    double p[3] = {l->centre[0], l->centre[1], l->centre[2]};
    for (int a = 0; a < 3; a++) {
        double f = l->dims[a] > 1 ? (double)idx[a] / (double)(l->dims[a] - 1) : 0.5;
        double x = -l->half_extents[a] + 2.0 * l->half_extents[a] * f;
        for (int c = 0; c < 3; c++) p[c] += l->axes[a][c] * x;
    }
    for (int c = 0; c < 3; c++) out[c] = (float)p[c];
}

/* ---- self-visibility ------------------------------------------------------------------------ */
typedef struct vis_ctx {
    const bk_tracer *tracer;
    const float *pos;          /* compact object vertices */
    const float *nrm;          /* compact unit normals */
    const float *toward;       /* compact: area-weighted centroid of the incident triangles */
    int rays;
    float *vis, *bent;
} vis_ctx;

static void vertex_visibility(const vis_ctx *c, size_t v)
{
    const float *n = c->nrm + 3 * v, *p = c->pos + 3 * v;
    /* orthonormal basis (Duff et al. 2017) */
    float sign = n[2] >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n[2]), b = n[0] * n[1] * a;
    float t[3] = {1.0f + sign * n[0] * n[0] * a, sign * b, -sign * n[0]};
    float bt[3] = {b, sign + n[1] * n[1] * a, -n[1]};
    /* Start a little inside the incident triangles (1% of the way to their centroid) and
     * lifted by as much along the normal: at an inside corner the vertex position lies on the
     * other wall's plane, so rays from the vertex itself would slip past that wall; the lift
     * keeps the origin above the vertex's tangent plane, so a convex surface, which lies
     * entirely below that plane, can never occlude its own vertex. */
    const float *cen = c->toward + 3 * v;
    float shifted[3], org[3];
    float dc[3] = {cen[0] - p[0], cen[1] - p[1], cen[2] - p[2]};
    float lift = 0.01f * sqrtf(dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2]);
    for (int k = 0; k < 3; k++) shifted[k] = p[k] + 0.01f * dc[k] + lift * n[k];
    bk_offset_ray_origin(shifted, n, org);
    double sum[3] = {0, 0, 0};
    int open = 0;
    const double golden = 2.39996322972865332;
    for (int r = 0; r < c->rays; r++) {
        /* cosine-distributed, stratified in cos²θ, golden-angle azimuth: deterministic */
        double u = ((double)r + 0.5) / (double)c->rays, rad = sqrt(u), phi = golden * r;
        double lx = rad * cos(phi), ly = rad * sin(phi), lz = sqrt(fmax(0.0, 1.0 - u));
        float d[3];
        for (int k = 0; k < 3; k++) d[k] = (float)(lx * t[k] + ly * bt[k] + lz * n[k]);
        if (bk_tracer_occluded(c->tracer, org, d, 0.0f, FLT_MAX)) continue;
        open++;
        for (int k = 0; k < 3; k++) sum[k] += d[k];
    }
    c->vis[v] = (float)open / (float)c->rays;
    double l = sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    for (int k = 0; k < 3; k++) c->bent[3 * v + k] = l > 0.0 ? (float)(sum[k] / l) : n[k];
}

static void vertex_visibility_chunk(void *vctx, size_t begin, size_t end, int thread)
{
    for (size_t v = begin; v < end; v++) vertex_visibility(vctx, v);
}

static int cmp_u32(const void *pa, const void *pb)
{
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    return (a > b) - (a < b);
}

/* The lattice box (the OBB with thin axes floored, plus the margin) and the probe counts per
 * axis, the spacing grown until the lattice fits the probe cap. */
static void lattice_dims(const bk_object *obj, const bk_llg_options *o, bk_llg *out)
{
    float big = fmaxf(out->obb_half_extents[0], fmaxf(out->obb_half_extents[1], out->obb_half_extents[2]));
    float floor_he = o->min_half_extent > 0 ? o->min_half_extent : (big > 0 ? 0.05f * big : 1e-3f);
    float margin = o->margin > 0 ? o->margin : 0.1f * fmaxf(big, floor_he);
    for (int a = 0; a < 3; a++) out->half_extents[a] = fmaxf(out->obb_half_extents[a], floor_he) + margin;
    double spacing = o->spacing > 0 && isfinite(o->spacing) ? o->spacing : 1.5;
    if (obj->lighting == BK_LIGHTING_LLG && obj->texel_density > 0 && isfinite(obj->texel_density))
        spacing = 1.0 / obj->texel_density;
    if (o->connected) {
        double k = o->connected_scale > 0 && o->connected_scale <= 1 ? o->connected_scale : 0.5;
        spacing *= k;
    }
    const double min_dim = o->min_dim >= 2 && o->min_dim <= (int)BK_LLG_MAX_DIM ? o->min_dim : 2;
    size_t cap = o->max_probes ? o->max_probes : 512;
    if (cap < 8) cap = 8;
    if (cap < (size_t)(min_dim * min_dim * min_dim)) cap = (size_t)(min_dim * min_dim * min_dim);
    for (;;) {
        size_t total = 1;
        int too_long = 0;
        for (int a = 0; a < 3; a++) {
            double d = ceil(2.0 * out->half_extents[a] / spacing - 1e-9) + 1.0;
            if (d < min_dim) d = min_dim;
            if (d > 65535.0) d = 65535.0;
            out->dims[a] = (uint32_t)d;
            too_long |= out->dims[a] > BK_LLG_MAX_DIM;
            total *= out->dims[a];
        }
        if (total <= cap && !too_long) break;
        spacing *= 1.1;  /* lower the resolution until the grid fits */
    }
    out->spacing = (float)spacing;
}

/* The global indices of the vertices of obj's usable triangles, ascending, each once. */
static uint32_t *object_vertex_ids(const bk_scene *scene, const bk_object *obj, size_t *count)
{
    size_t nt = obj->tri_count, nv = 0;
    uint32_t *ids = malloc((nt ? 3 * nt : 1) * sizeof *ids);
    if (!ids) return NULL;
    for (size_t t = obj->first_tri; t < (size_t)obj->first_tri + nt; t++)
        if (tri_usable(scene, t))
            for (int k = 0; k < 3; k++) ids[nv++] = scene->tris[3 * t + (size_t)k];
    qsort(ids, nv, sizeof *ids, cmp_u32);
    size_t u = 0;
    for (size_t i = 0; i < nv; i++) if (u == 0 || ids[u - 1] != ids[i]) ids[u++] = ids[i];
    *count = u;
    return ids;
}

/* The object's triangles on its compact vertices (sub->tris), with per vertex the area-weighted
 * sum of face normals (nrm, the fallback for missing vertex normals) and Σ area·centroid,
 * Σ area of the incident triangles (acc). */
static void accumulate_faces(const bk_scene *scene, const bk_object *obj, const uint32_t *ids, bk_scene *sub,
                             float *nrm, double *acc)
{
    size_t nv = sub->vertex_count;
    for (size_t t = obj->first_tri; t < (size_t)obj->first_tri + obj->tri_count; t++) {
        if (!tri_usable(scene, t)) continue;
        uint32_t *dst = sub->tris + 3 * sub->tri_count++;
        for (int k = 0; k < 3; k++) {
            uint32_t g = scene->tris[3 * t + (size_t)k];
            const uint32_t *hit = bsearch(&g, ids, nv, sizeof *ids, cmp_u32);
            dst[k] = (uint32_t)(hit - ids);
        }
        const float *a = sub->positions + 3 * (size_t)dst[0], *b = sub->positions + 3 * (size_t)dst[1];
        const float *c = sub->positions + 3 * (size_t)dst[2];
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++) for (int j = 0; j < 3; j++) nrm[3 * (size_t)dst[k] + j] += cr[j];
        double area = 0.5 * sqrt((double)cr[0] * cr[0] + (double)cr[1] * cr[1] + (double)cr[2] * cr[2]);
        for (int k = 0; k < 3; k++) {
            double *q = acc + 4 * (size_t)dst[k];
            for (int j = 0; j < 3; j++) q[j] += area * ((double)a[j] + b[j] + c[j]) / 3.0;
            q[3] += area;
        }
    }
}

/* Unit vertex normals: the scene's where it has a usable one, else the accumulated face
 * normal, else +z. */
static void vertex_normals(const bk_scene *scene, const uint32_t *ids, size_t nv, float *nrm)
{
    for (size_t i = 0; i < nv; i++) {
        float *n = nrm + 3 * i;
        if (scene->normals) {
            const float *sn = scene->normals + 3 * (size_t)ids[i];
            float l = sqrtf(sn[0] * sn[0] + sn[1] * sn[1] + sn[2] * sn[2]);
            if (isfinite(l) && l > 1e-6f) { for (int k = 0; k < 3; k++) n[k] = sn[k] / l; continue; }
        }
        float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (isfinite(l) && l > 0.0f) for (int k = 0; k < 3; k++) n[k] /= l;
        else { n[0] = 0; n[1] = 0; n[2] = 1; }
    }
}

/* The object alone as a scene on its nv compact vertices (ids), with unit vertex normals and,
 * per vertex, the area-weighted centroid of its triangles (toward) for the visibility rays. */
static lbk_result compact_object_mesh(const bk_scene *scene, const bk_object *obj, const uint32_t *ids, size_t nv,
                                      bk_scene *sub, float **nrm_out, float **toward_out)
{
    sub->vertex_count = nv;
    sub->positions = malloc((nv ? nv : 1) * 3 * sizeof(float));
    sub->tris = malloc((obj->tri_count ? obj->tri_count : 1) * 3 * sizeof(uint32_t));
    float *nrm = *nrm_out = calloc(nv ? nv : 1, 3 * sizeof(float));
    float *toward = *toward_out = malloc((nv ? nv : 1) * 3 * sizeof(float));
    double *acc = calloc(nv ? nv : 1, 4 * sizeof(double));
    if (!sub->positions || !sub->tris || !nrm || !toward || !acc) {
        free(acc);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < nv; i++) memcpy(sub->positions + 3 * i, scene->positions + 3 * (size_t)ids[i], 3 * sizeof(float));
    accumulate_faces(scene, obj, ids, sub, nrm, acc);
    for (size_t i = 0; i < nv; i++)
        for (int j = 0; j < 3; j++)
            toward[3 * i + j] = acc[4 * i + 3] > 0.0 ? (float)(acc[4 * i + j] / acc[4 * i + 3]) : sub->positions[3 * i + j];
    free(acc);
    vertex_normals(scene, ids, nv, nrm);
    return LBK_OK;
}

/* Visibility and bent normal of every vertex against the object alone (its own Embree scene). */
static lbk_result self_visibility(const bk_scene *sub, const float *nrm, const float *toward, int rays, int threads,
                                  bk_llg *out)
{
    bk_tracer *tracer = NULL;
    lbk_result res = bk_tracer_create(sub, 1, &tracer);
    if (res != LBK_OK) return res;
    vis_ctx vc = {tracer, sub->positions, nrm, toward, rays, out->visibility, out->bent_normals};
    bk_parallel_chunks(0, sub->vertex_count, 64, bk_thread_count(threads), vertex_visibility_chunk, &vc);
    bk_tracer_destroy(tracer);
    return LBK_OK;
}

lbk_result bk_llg_place(const bk_scene *scene, uint32_t object, const bk_llg_options *options,
                        int threads, bk_llg *out)
{
    if (!scene || !out || object >= scene->object_count) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const bk_object *obj = &scene->objects[object];
    bk_llg_options o = options ? *options : (bk_llg_options){0};
    out->object = object;
    lbk_result res = bk_obb_from_triangles(scene, obj->first_tri, obj->tri_count, out->centre,
                                           out->axes, out->obb_half_extents);
    if (res != LBK_OK) return res;
    lattice_dims(obj, &o, out);

    size_t nv = 0;
    out->vertices = object_vertex_ids(scene, obj, &nv);
    if (!out->vertices) return LBK_ERR_OUT_OF_MEMORY;
    out->vertex_count = nv;
    out->visibility = malloc((nv ? nv : 1) * sizeof(float));
    out->bent_normals = malloc((nv ? nv : 1) * 3 * sizeof(float));
    bk_scene sub = {0};
    float *nrm = NULL, *toward = NULL;
    res = compact_object_mesh(scene, obj, out->vertices, nv, &sub, &nrm, &toward);
    if (res == LBK_OK && (!out->visibility || !out->bent_normals)) res = LBK_ERR_OUT_OF_MEMORY;
    int rays = o.visibility_rays > 0 ? o.visibility_rays : 64;
    if (rays > 4096) rays = 4096;
    if (res == LBK_OK) res = self_visibility(&sub, nrm, toward, rays, threads, out);
    free(sub.positions); free(sub.tris); free(nrm); free(toward);
    if (res != LBK_OK) bk_llg_free(out);
    return res;
}

void bk_llg_vertex_record(const bk_llg *l, size_t v, lbk_llg_vertex *out)
{
    const float *b = l->bent_normals + 3 * v;
    float g[3], len = 0.0f;
    for (int a = 0; a < 3; a++) {
        g[a] = b[0] * l->axes[a][0] + b[1] * l->axes[a][1] + b[2] * l->axes[a][2];
        len += g[a] * g[a];
    }
    len = sqrtf(len);
    for (int a = 0; a < 3; a++) out->bent_normal[a] = len > 0.0f ? g[a] / len : (a == 2 ? 1.0f : 0.0f);
    out->visibility = l->visibility[v];
}

void bk_llg_vertex_records(const bk_llg *l, lbk_llg_vertex *out)
{
    for (size_t v = 0; v < l->vertex_count; v++) bk_llg_vertex_record(l, v, &out[v]);
}

/* ---- connected objects ----------------------------------------------------------------------- */

typedef struct obj_box { double lo[3], hi[3]; uint32_t id; int ok; } obj_box;

static int box_by_lo_x(const void *pa, const void *pb)
{
    const obj_box *a = pa, *b = pb;
    if (a->lo[0] != b->lo[0]) return a->lo[0] < b->lo[0] ? -1 : 1;
    return (a->id > b->id) - (a->id < b->id);
}

static int box_contains(const obj_box *a, const obj_box *b)
{
    for (int k = 0; k < 3; k++)
        if (b->lo[k] < a->lo[k] || b->hi[k] > a->hi[k]) return 0;
    return 1;
}

lbk_result bk_llg_connections(const bk_scene *scene, const uint8_t *candidate, float gap, uint8_t *out)
{
    if (!scene || !candidate || !out) return LBK_ERR_INVALID_ARGUMENT;
    size_t n = scene->object_count;
    memset(out, 0, n);
    double g = gap > 0 && isfinite(gap) ? gap : 0.01;
    obj_box *b = malloc((n ? n : 1) * sizeof *b);
    if (!b) return LBK_ERR_OUT_OF_MEMORY;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (!candidate[i]) continue;
        const bk_object *o = &scene->objects[i];
        obj_box x = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}, (uint32_t)i, 0};
        for (size_t t = o->first_tri; t < (size_t)o->first_tri + o->tri_count && t < scene->tri_count; t++)
            for (int c = 0; c < 3; c++) {
                uint32_t v = scene->tris[3 * t + (size_t)c];
                if (v >= scene->vertex_count) continue;
                for (int k = 0; k < 3; k++) {
                    double p = scene->positions[3 * (size_t)v + (size_t)k];
                    if (!isfinite(p)) continue;
                    x.lo[k] = fmin(x.lo[k], p); x.hi[k] = fmax(x.hi[k], p);
                    x.ok = 1;
                }
            }
        if (x.ok) b[m++] = x;
    }
    qsort(b, m, sizeof *b, box_by_lo_x);
    for (size_t i = 0; i < m; i++)
        for (size_t j = i + 1; j < m && b[j].lo[0] <= b[i].hi[0] + g; j++) {
            int near = 1;
            for (int k = 0; k < 3 && near; k++) near = b[j].lo[k] <= b[i].hi[k] + g && b[i].lo[k] <= b[j].hi[k] + g;
            if (!near || box_contains(&b[i], &b[j]) || box_contains(&b[j], &b[i])) continue;
            out[b[i].id] = 1;
            out[b[j].id] = 1;
        }
    free(b);
    return LBK_OK;
}
