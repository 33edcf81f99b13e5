/* Portal sampling, shadow photons, box clustering and MIS for the guided door estimator; see
 * door_sampling.h and bake/sets/SETS.md. */
#include "bake/sets/door_sampling.h"

#include "bake/transport/shading.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DS_PI 3.14159265358979323846

/* ---- random numbers ------------------------------------------------------------------------ */

#define DS_RNG_SALT 0x646F6F7273616D70ull /* "doorsamp": door streams differ from the transport's */

bk_rng bk_door_rng_make(uint64_t seed, uint64_t domain, uint64_t a, uint64_t b)
{
    return bk_rng_stream(seed, DS_RNG_SALT, (domain << 48) ^ a, b);
}

/* ---- small vector helpers ------------------------------------------------------------------ */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}
static double len3(const double a[3]) { return sqrt(dot3(a, a)); }

/* ---- portal -------------------------------------------------------------------------------- */

void bk_portal_from_obb(const float centre[3], const float axes[3][3], const float half[3], bk_portal *out)
{
    memset(out, 0, sizeof *out);
    int thin = 0;
    for (int a = 1; a < 3; a++)
        if (fabsf(half[a]) < fabsf(half[thin])) thin = a;
    int ia = (thin + 1) % 3, ib = (thin + 2) % 3;
    for (int k = 0; k < 3; k++) {
        out->centre[k] = centre[k];
        out->u[k] = axes[ia][k];
        out->v[k] = axes[ib][k];
    }
    double lu = len3(out->u), lv = len3(out->v);
    for (int k = 0; k < 3; k++) {
        out->u[k] = lu > 0 ? out->u[k] / lu : (k == 0);
        out->v[k] = lv > 0 ? out->v[k] / lv : (k == 1);
    }
    cross3(out->u, out->v, out->n);
    double ln = len3(out->n);
    for (int k = 0; k < 3; k++) out->n[k] = ln > 0 ? out->n[k] / ln : (k == 2);
    out->hu = fabs((double)half[ia]);
    out->hv = fabs((double)half[ib]);
    out->area = 4 * out->hu * out->hv;
}

void bk_portal_point(const bk_portal *p, double a, double b, double out[3])
{
    double su = (2 * a - 1) * p->hu, sv = (2 * b - 1) * p->hv;
    for (int k = 0; k < 3; k++) out[k] = p->centre[k] + su * p->u[k] + sv * p->v[k];
}

int bk_portal_crosses(const bk_portal *p, const double o[3], const double d[3], double tmax, double *t)
{
    double dn = dot3(d, p->n);
    if (dn == 0 || !isfinite(dn)) return 0;
    double w[3] = {p->centre[0] - o[0], p->centre[1] - o[1], p->centre[2] - o[2]};
    double tt = dot3(w, p->n) / dn;
    if (!(tt > 0) || !(tt < tmax)) return 0;
    double q[3] = {o[0] + tt * d[0] - p->centre[0], o[1] + tt * d[1] - p->centre[1], o[2] + tt * d[2] - p->centre[2]};
    if (fabs(dot3(q, p->u)) > p->hu || fabs(dot3(q, p->v)) > p->hv) return 0;
    if (t) *t = tt;
    return 1;
}

static double tri_solid_angle(const double a[3], const double b[3], const double c[3])
{
    double la = len3(a), lb = len3(b), lc = len3(c);
    double bc[3];
    cross3(b, c, bc);
    double num = fabs(dot3(a, bc));
    double den = la * lb * lc + dot3(a, b) * lc + dot3(a, c) * lb + dot3(b, c) * la;
    double om = 2 * atan2(num, den);
    return om < 0 ? om + 2 * DS_PI : om;
}

double bk_portal_solid_angle(const bk_portal *p, const double x[3])
{
    double c[4][3];
    static const double s[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; i++) {
        bk_portal_point(p, s[i][0], s[i][1], c[i]);
        for (int k = 0; k < 3; k++) c[i][k] -= x[k];
    }
    return tri_solid_angle(c[0], c[1], c[2]) + tri_solid_angle(c[0], c[2], c[3]);
}

/* ---- scene lookups ------------------------------------------------------------------------- */

void bk_door_surface(const bk_scene *s, uint32_t tri, double u, double v, const char *light_set, double albedo[3],
                     double emission[3])
{
    for (int k = 0; k < 3; k++) albedo[k] = emission[k] = 0;
    if (tri >= s->tri_count) return;
    uint32_t mi = s->tri_material ? s->tri_material[tri] : 0;
    if (mi >= s->material_count) return;
    const bk_material *m = &s->materials[mi];
    double uv[2];
    bk_tri_uv0(s, tri, u, v, uv);
    bk_material_albedo(s, m, uv, albedo);
    uint32_t oi = s->tri_object ? s->tri_object[tri] : UINT32_MAX;
    const char *set = oi < s->object_count ? s->objects[oi].light_set : "";
    if (strncmp(set, light_set ? light_set : "", 63)) return;
    bk_material_emission(s, m, uv, emission);
}

lbk_result bk_door_emitters_build(const bk_scene *s, const bk_tracer *t, const char *light_set, bk_door_emitters *out)
{
    memset(out, 0, sizeof *out);
    size_t n = 0;
    for (size_t i = 0; i < s->tri_count; i++) {
        double a[3], e[3];
        bk_door_surface(s, (uint32_t)i, 1.0 / 3, 1.0 / 3, light_set, a, e);
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        if (mi >= s->material_count) continue;
        double f[3] = {s->materials[mi].emission[0], s->materials[mi].emission[1], s->materials[mi].emission[2]};
        if ((e[0] > 0 || e[1] > 0 || e[2] > 0 || s->materials[mi].emission_tex >= 0) && bk_lum(f) > 0 &&
            bk_tracer_tri_area(t, (uint32_t)i) > 0) {
            /* in the set (e is non-zero only then, unless the texture is black at the centroid) */
            uint32_t oi = s->tri_object ? s->tri_object[i] : UINT32_MAX;
            const char *set = oi < s->object_count ? s->objects[oi].light_set : "";
            if (!strncmp(set, light_set ? light_set : "", 63)) n++;
        }
    }
    if (!n) return LBK_OK;
    out->tri = malloc(n * sizeof *out->tri);
    out->cdf = malloc(n * sizeof *out->cdf);
    if (!out->tri || !out->cdf) {
        bk_door_emitters_free(out);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    double run = 0;
    for (size_t i = 0; i < s->tri_count; i++) {
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        if (mi >= s->material_count) continue;
        uint32_t oi = s->tri_object ? s->tri_object[i] : UINT32_MAX;
        const char *set = oi < s->object_count ? s->objects[oi].light_set : "";
        if (strncmp(set, light_set ? light_set : "", 63)) continue;
        double f[3] = {s->materials[mi].emission[0], s->materials[mi].emission[1], s->materials[mi].emission[2]};
        double p = bk_tracer_tri_area(t, (uint32_t)i) * bk_lum(f);
        if (!(p > 0) || !isfinite(p)) continue;
        run += p;
        out->tri[out->count] = (uint32_t)i;
        out->cdf[out->count++] = run;
    }
    for (size_t i = 0; i < out->count; i++) out->cdf[i] /= run;
    if (out->count) out->cdf[out->count - 1] = 1;
    out->power = run;
    return LBK_OK;
}

void bk_door_emitters_free(bk_door_emitters *e)
{
    free(e->tri), free(e->cdf);
    memset(e, 0, sizeof *e);
}

/* ---- shadow photons ------------------------------------------------------------------------ */

static void tri_point(const bk_scene *s, uint32_t tri, double r1, double r2, double p[3], double *bu, double *bv)
{
    double sq = sqrt(r1), u = sq * (1 - r2), v = sq * r2;
    const uint32_t *ix = s->tris + 3 * (size_t)tri;
    for (int k = 0; k < 3; k++) {
        double a = s->positions[3 * (size_t)ix[0] + k], b = s->positions[3 * (size_t)ix[1] + k],
               c = s->positions[3 * (size_t)ix[2] + k];
        p[k] = (1 - u - v) * a + u * b + v * c;
    }
    *bu = u, *bv = v;
}

/* Continues a photon from portal point q along unit c; stores it where it lands (front side, or
 * either side of a double-sided material). */
static int land(const bk_scene *s, const bk_tracer *t, const double q[3], const double c[3], float w, uint32_t source,
                bk_photon *ph)
{
    float o[3] = {(float)q[0], (float)q[1], (float)q[2]}, d[3] = {(float)c[0], (float)c[1], (float)c[2]};
    bk_hit h;
    if (!bk_tracer_intersect(t, o, d, 0.0f, INFINITY, &h)) return 0;
    if (!h.front) {
        uint32_t mi = s->tri_material ? s->tri_material[h.tri] : 0;
        if (mi >= s->material_count || !s->materials[mi].double_sided) return 0;
    }
    for (int k = 0; k < 3; k++) ph->p[k] = (float)(q[k] + h.t * c[k]);
    ph->w = w;
    ph->source = source;
    return isfinite(ph->p[0]) && isfinite(ph->p[1]) && isfinite(ph->p[2]) && w > 0 && isfinite(w);
}

lbk_result bk_shoot_shadow_photons(const bk_scene *scene, const bk_tracer *tracer, const bk_portal *portal,
                                   const bk_photon_options *opt, bk_photon **out, size_t *n)
{
    *out = NULL;
    *n = 0;
    size_t count = opt->count ? opt->count : 4096;
    const char *set = opt->light_set ? opt->light_set : "";
    uint32_t *lights = malloc((scene->light_count ? scene->light_count : 1) * sizeof *lights);
    bk_photon *ph = malloc(count * sizeof *ph);
    bk_door_emitters em;
    lbk_result r = bk_door_emitters_build(scene, tracer, set, &em);
    if (!lights || !ph || r) {
        free(lights), free(ph);
        bk_door_emitters_free(&em);
        return r ? r : LBK_ERR_OUT_OF_MEMORY;
    }
    size_t nl = 0;
    for (size_t i = 0; i < scene->light_count; i++)
        if (!strncmp(scene->lights[i].light_set, set, 63)) lights[nl++] = (uint32_t)i;
    int sky = opt->use_sky && (scene->sky_image >= 0 || scene->sky[0] > 0 || scene->sky[1] > 0 || scene->sky[2] > 0);
    size_t sources = nl + (size_t)sky + (em.count ? 1 : 0);
    size_t k = 0;
    for (size_t i = 0; i < count && sources; i++) {
        bk_rng rng = bk_door_rng_make(opt->seed, 7, 0, i);
        /* stratified over the portal: a jittered grid of about √count × √count cells */
        size_t side = (size_t)ceil(sqrt((double)count));
        double a = ((double)(i % side) + bk_rng_next(&rng)) / (double)side;
        double b = ((double)((i / side) % side) + bk_rng_next(&rng)) / (double)side;
        double q[3];
        bk_portal_point(portal, a, b, q);
        size_t pick = (size_t)(bk_rng_next(&rng) * (double)sources);
        if (pick >= sources) pick = sources - 1;
        float qf[3] = {(float)q[0], (float)q[1], (float)q[2]};
        double scale = (double)sources * portal->area / (double)count; /* 1 / (p_source · p_point · N) */
        if (pick < nl) {
            double val[3], dir[3], dist;
            if (!bk_light_eval(&scene->lights[lights[pick]], q, val, dir, &dist)) continue;
            if (!bk_light_visible(tracer, qf, dir, dist)) continue;
            double back[3] = {-dir[0], -dir[1], -dir[2]};
            float w = (float)(bk_lum(val) * fabs(dot3(dir, portal->n)) * scale);
            if (land(scene, tracer, q, back, w, lights[pick], &ph[k])) k++;
        } else if (pick == nl && sky) {
            /* a uniform direction on the sphere, the sky seen along it */
            double z = 1 - 2 * bk_rng_next(&rng), phi = 2 * DS_PI * bk_rng_next(&rng);
            double rr = sqrt(fmax(0, 1 - z * z)), d[3] = {rr * cos(phi), rr * sin(phi), z};
            float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
            if (bk_tracer_occluded(tracer, qf, df, 0.0f, INFINITY)) continue;
            double L[3];
            bk_sky_radiance(scene, d, L);
            double back[3] = {-d[0], -d[1], -d[2]};
            float w = (float)(bk_lum(L) * fabs(dot3(d, portal->n)) * 4 * DS_PI * scale);
            if (land(scene, tracer, q, back, w, BK_SOURCE_SKY, &ph[k])) k++;
        } else {
            double u = bk_rng_next(&rng);
            size_t lo = 0, hi = em.count - 1;
            while (lo < hi) {
                size_t mid = lo + (hi - lo) / 2;
                if (em.cdf[mid] > u) hi = mid;
                else lo = mid + 1;
            }
            uint32_t tri = em.tri[lo];
            double x[3], bu, bv, alb[3], le[3];
            tri_point(scene, tri, bk_rng_next(&rng), bk_rng_next(&rng), x, &bu, &bv);
            bk_door_surface(scene, tri, bu, bv, set, alb, le);
            double dv[3] = {x[0] - q[0], x[1] - q[1], x[2] - q[2]}, dist = len3(dv);
            if (!(dist > 0)) continue;
            double dir[3] = {dv[0] / dist, dv[1] / dist, dv[2] / dist};
            float ng[3];
            bk_tracer_tri_normal(tracer, tri, ng);
            double ce = -(dir[0] * ng[0] + dir[1] * ng[1] + dir[2] * ng[2]);
            uint32_t mi = scene->tri_material ? scene->tri_material[tri] : 0;
            int ds = mi < scene->material_count && scene->materials[mi].double_sided;
            if (!(ce > 0) && !ds) continue;
            float df[3] = {(float)dv[0], (float)dv[1], (float)dv[2]};
            if (bk_tracer_occluded(tracer, qf, df, 0.0f, 1.0f - 1e-4f)) continue;
            double f[3] = {scene->materials[mi].emission[0], scene->materials[mi].emission[1],
                           scene->materials[mi].emission[2]};
            double parea = bk_lum(f) / em.power; /* density per unit area of the point */
            if (!(parea > 0)) continue;
            double back[3] = {-dir[0], -dir[1], -dir[2]};
            float w = (float)(bk_lum(le) * fabs(ce) * fabs(dot3(dir, portal->n)) / (dist * dist) / parea * scale);
            if (land(scene, tracer, q, back, w, BK_SOURCE_EMITTERS, &ph[k])) k++;
        }
    }
    free(lights);
    bk_door_emitters_free(&em);
    *out = ph;
    *n = k;
    return LBK_OK;
}

/* ---- clustering ---------------------------------------------------------------------------- */

static double d2f(const float a[3], const double c[3])
{
    double x = a[0] - c[0], y = a[1] - c[1], z = a[2] - c[2];
    return x * x + y * y + z * z;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Deterministic k-means++-like seeding: the heaviest photon, then repeatedly the one with the
 * largest w·D² (D: distance to the nearest centre so far). Returns the number of centres, less
 * than K when every photon already sits on one. */
static int seed_centres(const bk_photon *ph, size_t n, int K, double c[][3], double *dmin)
{
    size_t best = 0;
    for (size_t i = 1; i < n; i++)
        if (ph[i].w > ph[best].w) best = i;
    for (int k = 0; k < 3; k++) c[0][k] = ph[best].p[k];
    for (size_t i = 0; i < n; i++) dmin[i] = d2f(ph[i].p, c[0]);
    int used = 1;
    for (; used < K; used++) {
        size_t far = 0;
        double fv = -1;
        for (size_t i = 0; i < n; i++)
            if (ph[i].w * dmin[i] > fv) fv = ph[i].w * dmin[i], far = i;
        if (!(fv > 0)) break; /* every photon sits on a centre already */
        for (int k = 0; k < 3; k++) c[used][k] = ph[far].p[k];
        for (size_t i = 0; i < n; i++) {
            double d = d2f(ph[i].p, c[used]);
            if (d < dmin[i]) dmin[i] = d;
        }
    }
    return used;
}

/* Weighted Lloyd iterations (at most 16, until no photon changes cluster); as[i] gets photon
 * i's cluster. */
static void lloyd_iterations(const bk_photon *ph, size_t n, int K, double c[][3], int *as)
{
    for (int it = 0; it < 16; it++) {
        double acc[BK_GUIDE_MAX_BOXES][4];
        memset(acc, 0, sizeof acc);
        int moved = 0;
        for (size_t i = 0; i < n; i++) {
            int bi = 0;
            double bd = d2f(ph[i].p, c[0]);
            for (int k = 1; k < K; k++) {
                double d = d2f(ph[i].p, c[k]);
                if (d < bd) bd = d, bi = k;
            }
            if (it == 0 || as[i] != bi) moved = 1;
            as[i] = bi;
            double w = ph[i].w > 0 ? ph[i].w : 0;
            for (int k = 0; k < 3; k++) acc[bi][k] += w * ph[i].p[k];
            acc[bi][3] += w;
        }
        for (int k = 0; k < K; k++)
            if (acc[k][3] > 0)
                for (int a = 0; a < 3; a++) c[k][a] = acc[k][a] / acc[k][3];
        if (!moved) break;
    }
}

/* The inflated box of cluster k: extent, weight, photon count, and its distinct lights sorted
 * into lights[0..*light_count); sky and emitter photons set bits of *source_mask instead.
 * 0 when the cluster has no weight or the box no area (no box then). */
static int cluster_box(const bk_photon *ph, size_t n, const int *as, int k, double inflate_rel, double inflate_abs,
                       bk_guide_box *box, uint32_t *lights, size_t *light_count, uint32_t *source_mask)
{
    bk_guide_box b;
    memset(&b, 0, sizeof b);
    for (int a = 0; a < 3; a++) b.lo[a] = INFINITY, b.hi[a] = -INFINITY;
    size_t nl = 0;
    for (size_t i = 0; i < n; i++) {
        if (as[i] != k) continue;
        for (int a = 0; a < 3; a++) b.lo[a] = fmin(b.lo[a], ph[i].p[a]), b.hi[a] = fmax(b.hi[a], ph[i].p[a]);
        b.weight += ph[i].w;
        b.photons++;
        if (ph[i].source == BK_SOURCE_SKY) *source_mask |= 1u;
        else if (ph[i].source == BK_SOURCE_EMITTERS) *source_mask |= 2u;
        else lights[nl++] = ph[i].source;
    }
    if (!b.photons || !(b.weight > 0)) return 0;
    qsort(lights, nl, sizeof *lights, cmp_u32);
    size_t u = 0;
    for (size_t i = 0; i < nl; i++)
        if (!u || lights[i] != lights[u - 1]) lights[u++] = lights[i];
    double ext = 0;
    for (int a = 0; a < 3; a++) ext = fmax(ext, b.hi[a] - b.lo[a]);
    double m = inflate_rel * ext + inflate_abs;
    for (int a = 0; a < 3; a++) b.lo[a] -= m, b.hi[a] += m;
    double e[3] = {b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]};
    b.area = 2 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]);
    if (!(b.area > 0)) return 0;
    b.light_count = (uint32_t)u;
    *box = b;
    *light_count = u;
    return 1;
}

/* The nb boxes into out heaviest first (stable: ties keep cluster order), their light lists
 * concatenated into out->lights. */
static lbk_result store_boxes(const bk_guide_box *boxes, uint32_t *const *lists, int nb, size_t total_lights,
                              bk_guide_boxes *out)
{
    int order[BK_GUIDE_MAX_BOXES];
    for (int i = 0; i < nb; i++) order[i] = i;
    for (int i = 1; i < nb; i++)
        for (int j = i; j > 0 && boxes[order[j]].weight > boxes[order[j - 1]].weight; j--) {
            int t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    out->lights = malloc((total_lights ? total_lights : 1) * sizeof *out->lights);
    if (!out->lights) return LBK_ERR_OUT_OF_MEMORY;
    size_t w = 0;
    for (int i = 0; i < nb; i++) {
        bk_guide_box b = boxes[order[i]];
        b.light_first = (uint32_t)w;
        memcpy(out->lights + w, lists[order[i]], b.light_count * sizeof(uint32_t));
        w += b.light_count;
        out->box[i] = b;
        out->weight_sum += b.weight;
    }
    out->count = nb;
    out->light_total = w;
    return LBK_OK;
}

lbk_result bk_cluster_photons(const bk_photon *ph, size_t n, int max_boxes, double inflate_rel, double inflate_abs,
                              bk_guide_boxes *out)
{
    memset(out, 0, sizeof *out);
    if (max_boxes > BK_GUIDE_MAX_BOXES) max_boxes = BK_GUIDE_MAX_BOXES;
    if (!n || max_boxes <= 0) return LBK_OK;
    int K = (size_t)max_boxes < n ? max_boxes : (int)n;
    double c[BK_GUIDE_MAX_BOXES][3];
    int *as = malloc(n * sizeof *as);
    double *dmin = malloc(n * sizeof *dmin);
    uint32_t *tmp = malloc(n * sizeof *tmp);
    if (!as || !dmin || !tmp) {
        free(as), free(dmin), free(tmp);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    K = seed_centres(ph, n, K, c, dmin);
    lloyd_iterations(ph, n, K, c, as);
    bk_guide_box boxes[BK_GUIDE_MAX_BOXES];
    uint32_t *lists[BK_GUIDE_MAX_BOXES];
    size_t total_lights = 0;
    int nb = 0;
    lbk_result res = LBK_OK;
    for (int k = 0; k < K; k++) {
        size_t nl;
        if (!cluster_box(ph, n, as, k, inflate_rel, inflate_abs, &boxes[nb], tmp, &nl, &out->source_mask)) continue;
        lists[nb] = malloc((nl ? nl : 1) * sizeof(uint32_t));
        if (!lists[nb]) {
            res = LBK_ERR_OUT_OF_MEMORY;
            break;
        }
        memcpy(lists[nb], tmp, nl * sizeof(uint32_t));
        total_lights += nl;
        nb++;
    }
    free(as), free(dmin), free(tmp);
    if (res == LBK_OK) res = store_boxes(boxes, lists, nb, total_lights, out);
    for (int i = 0; i < nb; i++) free(lists[i]);
    return res;
}

void bk_guide_boxes_free(bk_guide_boxes *b)
{
    free(b->lights);
    memset(b, 0, sizeof *b);
}

int bk_guide_box_containing(const bk_guide_boxes *b, const double x[3])
{
    for (int i = 0; i < b->count; i++) {
        const bk_guide_box *q = &b->box[i];
        if (x[0] >= q->lo[0] && x[0] <= q->hi[0] && x[1] >= q->lo[1] && x[1] <= q->hi[1] && x[2] >= q->lo[2] &&
            x[2] <= q->hi[2])
            return i;
    }
    return -1;
}

/* ---- guided directions and their pdf -------------------------------------------------------- */

int bk_guide_sample(const bk_guide_boxes *b, const double x[3], double u0, double u1, double u2, double d[3])
{
    if (b->count <= 0 || !(b->weight_sum > 0)) return 0;
    double t = u0 * b->weight_sum, run = 0;
    int bi = b->count - 1;
    for (int i = 0; i < b->count; i++) {
        run += b->box[i].weight;
        if (t < run) {
            bi = i;
            break;
        }
    }
    const bk_guide_box *q = &b->box[bi];
    double e[3] = {q->hi[0] - q->lo[0], q->hi[1] - q->lo[1], q->hi[2] - q->lo[2]};
    double fa[3] = {e[1] * e[2], e[2] * e[0], e[0] * e[1]}; /* face area per axis (two faces each) */
    /* six faces, two per axis, picked by area; u1's position inside the face's interval is
     * reused as the first coordinate on it */
    double s = u1 * 2 * (fa[0] + fa[1] + fa[2]), acc = 0, rem = 1;
    int face = 5;
    for (int f = 0; f < 6; f++) {
        double a = fa[f / 2];
        if (s < acc + a) {
            face = f;
            rem = a > 0 ? (s - acc) / a : 0.5;
            break;
        }
        acc += a;
    }
    int axis = face / 2, side = face & 1;
    rem = rem < 0 ? 0 : rem > 1 ? 1 : rem;
    double p[3];
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    p[axis] = side ? q->hi[axis] : q->lo[axis];
    p[ua] = q->lo[ua] + rem * e[ua];
    p[va] = q->lo[va] + u2 * e[va];
    double v[3] = {p[0] - x[0], p[1] - x[1], p[2] - x[2]}, l = len3(v);
    if (!(l > 0) || !isfinite(l)) return 0;
    for (int k = 0; k < 3; k++) d[k] = v[k] / l;
    return 1;
}

double bk_guide_pdf(const bk_guide_boxes *b, const double x[3], const double d[3])
{
    if (b->count <= 0 || !(b->weight_sum > 0)) return 0;
    double pdf = 0;
    for (int i = 0; i < b->count; i++) {
        const bk_guide_box *q = &b->box[i];
        double t0 = -INFINITY, t1 = INFINITY;
        int a0 = -1, a1 = -1;
        int miss = 0;
        for (int a = 0; a < 3 && !miss; a++) {
            if (d[a] == 0) {
                if (x[a] < q->lo[a] || x[a] > q->hi[a]) miss = 1;
                continue;
            }
            double ta = (q->lo[a] - x[a]) / d[a], tb = (q->hi[a] - x[a]) / d[a];
            if (ta > tb) {
                double t = ta;
                ta = tb;
                tb = t;
            }
            if (ta > t0) t0 = ta, a0 = a;
            if (tb < t1) t1 = tb, a1 = a;
        }
        if (miss || !(t0 <= t1) || !(t1 > 0)) continue;
        double s = 0;
        if (t0 > 0 && a0 >= 0) s += t0 * t0 / fabs(d[a0]);
        if (a1 >= 0) s += t1 * t1 / fabs(d[a1]);
        pdf += q->weight / b->weight_sum / q->area * s;
    }
    return pdf;
}

double bk_mis_balance(double n_a, double p_a, double n_b, double p_b)
{
    double a = n_a * p_a, den = a + n_b * p_b;
    return den > 0 ? a / den : 0;
}
