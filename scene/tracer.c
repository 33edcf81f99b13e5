/* Embree 3 wrapper; see tracer.h. */
#include "scene/tracer.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct bk_tracer {
    RTCDevice device;
    RTCScene rtc_scene;
    size_t tri_count;
    float *tri_normal;   /* 3 per triangle, unit or zero */
    float *tri_area;
    float *tri_scale;
    atomic_int error;    /* first RTCError seen, 0 none */
    char error_message[160];
};

static void on_embree_error(void *user, enum RTCError code, const char *str)
{
    /* Never prints: the first error is kept for bk_tracer_embree_error(). */
    bk_tracer *t = (bk_tracer *)user;
    int expected = 0;
    if (code != RTC_ERROR_NONE && atomic_compare_exchange_strong(&t->error, &expected, (int)code)) {
        /* only the first reporter writes; readers look after the failing call returned */
        snprintf(t->error_message, sizeof t->error_message, "%s", str ? str : "embree error");
    }
}

static lbk_result map_error(int code)
{
    switch (code) {
    case RTC_ERROR_NONE: return LBK_OK;
    case RTC_ERROR_OUT_OF_MEMORY: return LBK_ERR_OUT_OF_MEMORY;
    case RTC_ERROR_INVALID_ARGUMENT: return LBK_ERR_INVALID_ARGUMENT;
    default: return LBK_ERR_UNSUPPORTED_FEATURE;
    }
}

static int finite3(const float *v) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

void bk_tracer_destroy(bk_tracer *t)
{
    if (!t) return;
    if (t->rtc_scene) rtcReleaseScene(t->rtc_scene);
    if (t->device) rtcReleaseDevice(t->device);
    free(t->tri_normal);
    free(t->tri_area);
    free(t->tri_scale);
    free(t);
}

lbk_result bk_tracer_create(const bk_scene *scene, int build_threads, bk_tracer **out)
{
    (void)build_threads;
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!scene) return LBK_ERR_INVALID_ARGUMENT;
    if (scene->tri_count > 0 && (!scene->tris || !scene->positions)) return LBK_ERR_INVALID_ARGUMENT;
    if (scene->tri_count >= UINT32_MAX || scene->vertex_count >= UINT32_MAX) return LBK_ERR_INVALID_ARGUMENT;
    if (scene->tri_count > SIZE_MAX / (3 * sizeof(float))) return LBK_ERR_INVALID_ARGUMENT;

    bk_tracer *t = calloc(1, sizeof *t);
    if (!t) return LBK_ERR_OUT_OF_MEMORY;
    atomic_init(&t->error, 0);
    size_t nt = scene->tri_count, nv = scene->vertex_count;
    t->tri_count = nt;
    t->tri_normal = calloc(nt ? nt * 3 : 1, sizeof(float));
    t->tri_area = calloc(nt ? nt : 1, sizeof(float));
    t->tri_scale = calloc(nt ? nt : 1, sizeof(float));
    if (!t->tri_normal || !t->tri_area || !t->tri_scale) { bk_tracer_destroy(t); return LBK_ERR_OUT_OF_MEMORY; }

    /* One BVH build thread: the same tree (hence the same tie breaking) for every caller. */
    t->device = rtcNewDevice("threads=1");
    if (!t->device) {
        int code = (int)rtcGetDeviceError(NULL);
        bk_tracer_destroy(t);
        return code == RTC_ERROR_OUT_OF_MEMORY ? LBK_ERR_OUT_OF_MEMORY : LBK_ERR_UNSUPPORTED_FEATURE;
    }
    rtcSetDeviceErrorFunction(t->device, on_embree_error, t);

    t->rtc_scene = rtcNewScene(t->device);
    if (!t->rtc_scene) { lbk_result r = map_error(atomic_load(&t->error)); bk_tracer_destroy(t); return r ? r : LBK_ERR_OUT_OF_MEMORY; }
    rtcSetSceneFlags(t->rtc_scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(t->rtc_scene, RTC_BUILD_QUALITY_HIGH);

    if (nt > 0 && nv > 0) {
        RTCGeometry g = rtcNewGeometry(t->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (!g) { lbk_result r = map_error(atomic_load(&t->error)); bk_tracer_destroy(t); return r ? r : LBK_ERR_OUT_OF_MEMORY; }
        rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv);
        unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt);
        if (!vb || !ib) {
            rtcReleaseGeometry(g);
            lbk_result r = map_error(atomic_load(&t->error));
            bk_tracer_destroy(t);
            return r ? r : LBK_ERR_OUT_OF_MEMORY;
        }
        for (size_t i = 0; i < nv; i++) {
            const float *p = scene->positions + 3 * i;
            int ok = finite3(p);
            for (int k = 0; k < 3; k++) vb[3 * i + k] = ok ? p[k] : 0.0f;
        }
        for (size_t i = 0; i < nt; i++) {
            const uint32_t *tri = scene->tris + 3 * i;
            int ok = tri[0] < nv && tri[1] < nv && tri[2] < nv;
            if (ok) ok = finite3(scene->positions + 3 * (size_t)tri[0]) && finite3(scene->positions + 3 * (size_t)tri[1]) &&
                         finite3(scene->positions + 3 * (size_t)tri[2]);
            if (!ok) {
                /* Unusable triangle: collapse onto vertex 0, which no ray can hit. */
                ib[3 * i + 0] = ib[3 * i + 1] = ib[3 * i + 2] = 0;
                continue;
            }
            ib[3 * i + 0] = tri[0]; ib[3 * i + 1] = tri[1]; ib[3 * i + 2] = tri[2];
            const float *a = scene->positions + 3 * (size_t)tri[0];
            const float *b = scene->positions + 3 * (size_t)tri[1];
            const float *c = scene->positions + 3 * (size_t)tri[2];
            double e1[3], e2[3], n[3];
            double s = 0;
            for (int k = 0; k < 3; k++) {
                e1[k] = (double)b[k] - a[k];
                e2[k] = (double)c[k] - a[k];
                double m = fmax(fabs(a[k]), fmax(fabs(b[k]), fabs(c[k])));
                if (m > s) s = m;
            }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            t->tri_scale[i] = (float)s;
            /* Areas below what float coordinates of this magnitude can resolve count as zero:
             * their normals would be noise. */
            double ulp = s * 1.1920928955078125e-07;
            if (len > 0 && isfinite(len) && len > ulp * ulp) {
                for (int k = 0; k < 3; k++) t->tri_normal[3 * i + k] = (float)(n[k] / len);
                t->tri_area[i] = (float)(0.5 * len);
            }
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(t->rtc_scene, g, 0);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(t->rtc_scene);
    int code = atomic_load(&t->error);
    if (code != RTC_ERROR_NONE) {
        lbk_result r = map_error(code);
        bk_tracer_destroy(t);
        return r;
    }
    *out = t;
    return LBK_OK;
}

/* Embree's ray.valid() (asserted in its intersectors) wants |org| and |dir| <= FLT_LARGE,
 * 1.844e18; a ray beyond that is a miss here, like a non-finite one. The importer keeps levels
 * far inside (spec/authoring.md, scene extent); this guards scenes made otherwise. */
#define RAY_LARGE 1.844e18f

static int small3(const float *v) { return fabsf(v[0]) <= RAY_LARGE && fabsf(v[1]) <= RAY_LARGE && fabsf(v[2]) <= RAY_LARGE; }

static int ray_ok(const float org[3], const float dir[3], float tmin, float tmax)
{
    return small3(org) && small3(dir) && (dir[0] != 0 || dir[1] != 0 || dir[2] != 0) && tmin >= 0 &&
           !(tmax < tmin) && !isnan(tmax);
}

static void setup_ray(struct RTCRay *r, const float org[3], const float dir[3], float tmin, float tmax)
{
    r->org_x = org[0]; r->org_y = org[1]; r->org_z = org[2];
    r->dir_x = dir[0]; r->dir_y = dir[1]; r->dir_z = dir[2];
    r->tnear = tmin;
    r->tfar = tmax;
    r->time = 0;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

static void fill_hit(const bk_tracer *t, const struct RTCRayHit *rh, const float dir[3], bk_hit *hit)
{
    uint32_t tri = rh->hit.primID;
    hit->t = rh->ray.tfar;
    hit->tri = tri;
    hit->u = rh->hit.u;
    hit->v = rh->hit.v;
    const float *n = t->tri_normal + 3 * (size_t)tri;
    float ng[3] = {n[0], n[1], n[2]};
    if (ng[0] == 0 && ng[1] == 0 && ng[2] == 0) {
        /* A sliver too thin for our normal but hit by Embree: its own normal, or face the ray. */
        float m = sqrtf(rh->hit.Ng_x * rh->hit.Ng_x + rh->hit.Ng_y * rh->hit.Ng_y + rh->hit.Ng_z * rh->hit.Ng_z);
        if (m > 0 && isfinite(m)) {
            /* Embree's Ng is cross(v0-v1, v2-v0) = -cross(v1-v0, v2-v0). */
            ng[0] = -rh->hit.Ng_x / m; ng[1] = -rh->hit.Ng_y / m; ng[2] = -rh->hit.Ng_z / m;
        } else {
            float d = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            ng[0] = -dir[0] / d; ng[1] = -dir[1] / d; ng[2] = -dir[2] / d;
        }
    }
    hit->ng[0] = ng[0]; hit->ng[1] = ng[1]; hit->ng[2] = ng[2];
    hit->front = dir[0] * ng[0] + dir[1] * ng[1] + dir[2] * ng[2] < 0;
}

int bk_tracer_intersect(const bk_tracer *t, const float org[3], const float dir[3], float tmin, float tmax,
                        bk_hit *hit)
{
    if (!ray_ok(org, dir, tmin, tmax)) return 0;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    setup_ray(&rh.ray, org, dir, tmin, tmax);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(t->rtc_scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.primID >= t->tri_count) return 0;
    fill_hit(t, &rh, dir, hit);
    return 1;
}

int bk_tracer_occluded(const bk_tracer *t, const float org[3], const float dir[3], float tmin, float tmax)
{
    if (!ray_ok(org, dir, tmin, tmax)) return 0;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r;
    setup_ray(&r, org, dir, tmin, tmax);
    rtcOccluded1(t->rtc_scene, &ctx, &r);
    return r.tfar < 0; /* Embree sets tfar to -inf on occlusion */
}

void bk_tracer_intersect_n(const bk_tracer *t, size_t n, const float *org, const float *dir, float tmin,
                           const float *tmax, bk_hit *hits)
{
    /* Embree's stream entry point, incoherent mode: one call per chunk instead of per ray */
    enum { CHUNK = 64 };
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    struct RTCRayHit rh[CHUNK];
    uint32_t map[CHUNK];
    for (size_t b = 0; b < n; b += CHUNK) {
        size_t m = n - b < CHUNK ? n - b : CHUNK, k = 0;
        for (size_t i = b; i < b + m; i++) {
            float tm = tmax ? tmax[i] : INFINITY;
            hits[i].tri = UINT32_MAX;
            if (!ray_ok(org + 3 * i, dir + 3 * i, tmin, tm)) continue;
            setup_ray(&rh[k].ray, org + 3 * i, dir + 3 * i, tmin, tm);
            rh[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh[k].hit.primID = RTC_INVALID_GEOMETRY_ID;
            rh[k].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            map[k++] = (uint32_t)i;
        }
        if (k) rtcIntersect1M(t->rtc_scene, &ctx, rh, (unsigned)k, sizeof rh[0]);
        for (size_t j = 0; j < k; j++) {
            if (rh[j].hit.geomID == RTC_INVALID_GEOMETRY_ID || rh[j].hit.primID >= t->tri_count) continue;
            fill_hit(t, &rh[j], dir + 3 * (size_t)map[j], &hits[map[j]]);
        }
        for (size_t i = b; i < b + m; i++)
            if (hits[i].tri == UINT32_MAX) {
                memset(&hits[i], 0, sizeof hits[i]);
                hits[i].tri = UINT32_MAX;
            }
    }
}

int bk_tracer_embree_error(const bk_tracer *t, const char **message)
{
    int code = t ? atomic_load(&((bk_tracer *)t)->error) : 0;
    if (message) *message = code ? t->error_message : "no error";
    return code;
}

void bk_tracer_tri_normal(const bk_tracer *t, uint32_t tri, float n[3])
{
    if (tri >= t->tri_count) { n[0] = n[1] = n[2] = 0; return; }
    memcpy(n, t->tri_normal + 3 * (size_t)tri, 3 * sizeof(float));
}
float bk_tracer_tri_area(const bk_tracer *t, uint32_t tri) { return tri < t->tri_count ? t->tri_area[tri] : 0.0f; }
float bk_tracer_tri_scale(const bk_tracer *t, uint32_t tri) { return tri < t->tri_count ? t->tri_scale[tri] : 0.0f; }
size_t bk_tracer_tri_count(const bk_tracer *t) { return t->tri_count; }

/* Moves x by k ulps toward +infinity (k > 0) or -infinity (k < 0), on the integer
 * representation as in the paper; clamped to the finite range, never crossing zero (callers
 * only use it where |x| spans far more than k ulps). */
static float step_ulps(float x, int32_t k)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    int64_t mag = (int64_t)(bits & 0x7fffffffu);
    mag += (x < 0) ? -(int64_t)k : (int64_t)k;
    if (mag < 0) mag = 0;
    if (mag > 0x7f7fffff) mag = 0x7f7fffff;
    uint32_t out = (uint32_t)mag | (bits & 0x80000000u);
    float r;
    memcpy(&r, &out, sizeof r);
    return r;
}

void bk_offset_ray_origin_scaled(const float p[3], const float n[3], float scale, float out[3])
{
    if (!(scale > 0) || !isfinite(scale)) scale = 1.0f;
    const float origin = scale * (1.0f / 32.0f);
    const float float_scale = scale * (1.0f / 524288.0f); /* 16·2^-23·scale: ~16 ulps of scale */
    const float int_scale = 8.0f;
    for (int k = 0; k < 3; k++) {
        float nk = isfinite(n[k]) ? fmaxf(-1.0f, fminf(1.0f, n[k])) : 0.0f;
        if (!isfinite(p[k]) || fabsf(p[k]) < origin)
            out[k] = p[k] + float_scale * nk;
        else
            out[k] = step_ulps(p[k], (int32_t)(int_scale * nk));
    }
}

void bk_offset_ray_origin(const float p[3], const float n[3], float out[3])
{
    bk_offset_ray_origin_scaled(p, n, 1.0f, out);
}

int bk_tracer_enclosed(const bk_tracer *tr, const double p[3], const float n[3], double offset)
{
    float org[3], t[3], b[3];
    for (int a = 0; a < 3; a++) org[a] = (float)(p[a] + offset * n[a]);
    /* orthonormal basis (Duff et al. 2017) */
    float sg = n[2] >= 0 ? 1.0f : -1.0f, q = -1.0f / (sg + n[2]), w = n[0] * n[1] * q;
    t[0] = 1 + sg * n[0] * n[0] * q, t[1] = sg * w, t[2] = -sg * n[0];
    b[0] = w, b[1] = sg + n[1] * n[1] * q, b[2] = -n[1];
    int back = 0;
    for (int i = 0; i < 16; i++) {
        double z = 1 - (i + 0.5) / 16, r = sqrt(fmax(0, 1 - z * z)), ph = 2.399963229728653 * i;
        float d[3];
        for (int a = 0; a < 3; a++) d[a] = (float)(r * cos(ph) * t[a] + r * sin(ph) * b[a] + z * n[a]);
        bk_hit h;
        if (bk_tracer_intersect(tr, org, d, 0.0f, INFINITY, &h) && !h.front) back++;
    }
    return back >= 8;
}
