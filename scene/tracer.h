/* Ray casting for the baker: a thin Embree 3 wrapper over the triangles of a bk_scene.
 *
 * One Embree geometry holds every scene triangle, so a hit's `tri` is the index into
 * bk_scene.tris. Triangles whose vertices are non-finite or whose indices are out of range
 * are replaced by a degenerate (zero-area) triangle that no ray can hit; zero-area input
 * triangles are kept (Embree never reports them: their determinant is zero).
 *
 * Thread safety: bk_tracer_intersect / bk_tracer_occluded may be called from any number of
 * threads at once on one tracer. Create/destroy are not concurrent with anything.
 *
 * Determinism: the BVH is built single-threaded, so the structure and therefore the winner
 * of exact ties (coincident triangles, rays through shared edges) do not depend on the
 * caller's thread count. */
#ifndef BK_TRACER_H
#define BK_TRACER_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bk_tracer bk_tracer;

typedef struct bk_hit {
    float t;          /* distance along dir in units of |dir| */
    uint32_t tri;     /* index into bk_scene triangles */
    float u, v;       /* barycentrics: p = (1-u-v)·v0 + u·v1 + v·v2 */
    float ng[3];      /* unit geometric normal, cross(v1-v0, v2-v0) (glTF front side, CCW) */
    int front;        /* 1 when the ray arrived on the front side (dot(dir, ng) < 0) */
} bk_hit;

/* Builds the acceleration structure over `scene` (copied; the scene may be freed afterwards).
 * build_threads is accepted for API stability but the build always runs on one thread (see
 * Determinism above). Errors: LBK_ERR_INVALID_ARGUMENT (NULL args, > 2^32-1 triangles),
 * LBK_ERR_OUT_OF_MEMORY, LBK_ERR_UNSUPPORTED_FEATURE (Embree cannot run on this CPU or
 * reported another device error; bk_tracer_embree_error() tells which). */
lbk_result bk_tracer_create(const bk_scene *scene, int build_threads, bk_tracer **out);
void bk_tracer_destroy(bk_tracer *tracer);

/* Closest hit in [tmin, tmax] along org + t·dir (dir need not be unit). Returns 1 and fills
 * *hit on a hit, 0 on a miss (also for non-finite input rays and for rays with a |org| or |dir|
 * coordinate above 1.844e18, which Embree cannot take). */
int bk_tracer_intersect(const bk_tracer *tracer, const float org[3], const float dir[3],
                        float tmin, float tmax, bk_hit *hit);
/* 1 when anything blocks org + t·dir for t in [tmin, tmax], else 0 (non-finite ray: 0). */
int bk_tracer_occluded(const bk_tracer *tracer, const float org[3], const float dir[3],
                       float tmin, float tmax);

/* Stream variant: n independent rays (org/dir are 3 floats per ray, tmax one per ray or NULL
 * for infinity, tmin shared); hits[i].tri = UINT32_MAX marks a miss. Traced in chunks through
 * rtcIntersect1M (incoherent), which costs less per ray than single calls; same results as n
 * single calls (tested). */
void bk_tracer_intersect_n(const bk_tracer *tracer, size_t n, const float *org, const float *dir,
                           float tmin, const float *tmax, bk_hit *hits);

/* The first Embree error raised on this tracer's device (RTCError value, 0 = none) and its
 * message (never NULL). Hot-path calls never print; they only record this. */
int bk_tracer_embree_error(const bk_tracer *tracer, const char **message);

/* Per-triangle data the tracer keeps anyway: unit geometric normal (zero for degenerate
 * triangles), area, and the largest |coordinate| of its vertices (the scale for ray offsets). */
void bk_tracer_tri_normal(const bk_tracer *tracer, uint32_t tri, float n[3]);
float bk_tracer_tri_area(const bk_tracer *tracer, uint32_t tri);
float bk_tracer_tri_scale(const bk_tracer *tracer, uint32_t tri);
size_t bk_tracer_tri_count(const bk_tracer *tracer);

/* Self-intersection avoidance after Wächter & Binder, "A Fast and Robust Method for Avoiding
 * Self-Intersection" (Ray Tracing Gems, ch. 6): moves p along the unit normal n (which must
 * point to the side the new ray leaves into) by 8·n_k float ulps of each coordinate k (the
 * paper's 256 ulps suit GPU hit points; ours are interpolated in double and rounded once, and
 * 256 ulps would be 2 m at 1e5 m from the origin). Coordinates closer to zero than scale/32
 * (where ulps vanish but the error of a computed point does not) move by a fixed 2^-19·scale
 * instead. Exact integer ulp steps: the result is the same on every machine.
 * bk_offset_ray_origin uses scale 1; the _scaled variant uses `scale`, the
 * magnitude of the coordinates the point was computed from (e.g. bk_tracer_tri_scale), so a
 * 1 mm level near the origin gets 2e-9 m rather than 2e-6 m offsets. scale <= 0 or
 * non-finite means 1.
 * Limitation (tested): a point within ~2 ulps of an edge where its triangle meets another wall
 * can round to the far side of that wall; keep sample points >= 8 ulps inside their triangle. */
void bk_offset_ray_origin(const float p[3], const float n[3], float out[3]);
void bk_offset_ray_origin_scaled(const float p[3], const float n[3], float scale, float out[3]);

/* Whether a surface point is enclosed by geometry: at least half of 16 rays over the hemisphere
 * of unit n (golden spiral), from `offset` above p, end on back faces (the pole of a sphere that
 * dips into the next, a face sealed in a wall). lbk's rule for points no one sees: the LLG fit
 * leaves such vertices out, the Cycles bench such sensors. */
int bk_tracer_enclosed(const bk_tracer *tracer, const double p[3], const float n[3], double offset);

#ifdef __cplusplus
}
#endif
#endif
