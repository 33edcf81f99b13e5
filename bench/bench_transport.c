/* Transport benchmarks (printed, not asserted):
 *  1. baker rays/second (bk_transport_run, one thread, all its overhead included) next to a raw
 *     Embree rtcIntersect1 loop over the same triangles and the same kind of rays (cache gather
 *     rays: points on the surfaces, cosine directions), one thread, in the same run; goal >= 70 %;
 *  2. estimated vs measured relative RMSE at several time budgets on a closed room with a
 *     light, an emitter and furniture, against a long reference bake of the same scene. */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench/bench_util.h"
#include "bake/transport/transport.h"
#include "tests/support/scene_append.c"     /* what the scene builders below build on */
#include "tests/support/transport_scenes.c" /* the C scene builders the tests use */

/* CPU time of the calling thread: the rays/s comparison runs both sides on this one thread,
 * and on a shared machine wall time would mostly measure the other tenants. */
static void build_room(bk_scene *s)
{
    tsc_init(s);
    uint32_t wall = tsc_material(s, 0.75f, 0.75f, 0.75f, 0, 0, 0);
    uint32_t red = tsc_material(s, 0.7f, 0.15f, 0.1f, 0, 0, 0);
    uint32_t green = tsc_material(s, 0.1f, 0.6f, 0.15f, 0, 0, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {6, 5, 3};
    tsc_box(s, mn, mx, 8, 1, wall);
    float r0[3] = {0.01f, 0.01f, 0.01f}, r1[3] = {0.01f, 4.99f, 0.01f}, r2[3] = {0.01f, 4.99f, 2.99f}, r3[3] = {0.01f, 0.01f, 2.99f};
    tsc_quad(s, r0, r3, r2, r1, 6, red);
    for (int i = 0; i < 6; i++) { /* furniture: boxes */
        float a[3] = {0.6f + i * 0.9f, 1 + (i % 3) * 1.1f, 0}, b[3] = {a[0] + 0.6f, a[1] + 0.7f, 0.4f + 0.25f * i};
        tsc_box(s, a, b, 3, 0, i % 2 ? green : wall);
    }
    uint32_t em = tsc_material(s, 0, 0, 0, 20, 18, 15);
    s->materials[em].double_sided = 0;
    float e0[3] = {2.5f, 2, 2.95f}, e1[3] = {2.5f, 3, 2.95f}, e2[3] = {3.5f, 3, 2.95f}, e3[3] = {3.5f, 2, 2.95f};
    tsc_quad(s, e0, e1, e2, e3, 1, em);
    float lp[3] = {5, 4, 2.5f};
    tsc_point_light(s, lp, 60, 50, 40, 0);
    tsc_update_bounds(s);
}

static size_t make_receivers(bk_receiver **out)
{
    size_t n = 4000;
    bk_receiver *r = calloc(n, sizeof *r);
    for (size_t i = 0; i < n; i++) {
        double a = fmod(i * 0.618033988749895, 1.0), b = fmod(i * 0.754877666246693, 1.0);
        if (i % 3 == 0) { r[i].position[0] = (float)(0.05 + 5.9 * a); r[i].position[1] = (float)(0.05 + 4.9 * b); r[i].normal[2] = 1; }
        else if (i % 3 == 1) { r[i].position[0] = 5.999f; r[i].position[1] = (float)(0.05 + 4.9 * a); r[i].position[2] = (float)(0.05 + 2.9 * b); r[i].normal[0] = -1; }
        else { r[i].position[0] = (float)(0.3 + 5.4 * a); r[i].position[1] = (float)(0.3 + 4.4 * b); r[i].position[2] = (float)(1.2 + 1.5 * fmod(i * 0.5698402909980532, 1.0)); }
    }
    *out = r;
    return n;
}

/* ---- 1. rays per second ------------------------------------------------------------------------ */

static double raw_embree_rays_per_second(const bk_scene *s, size_t nrays)
{
    RTCDevice dev = rtcNewDevice("threads=1");
    RTCScene sc = rtcNewScene(dev);
    rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, s->vertex_count);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, s->tri_count);
    memcpy(vb, s->positions, 12 * s->vertex_count);
    memcpy(ib, s->tris, 12 * s->tri_count);
    rtcCommitGeometry(g);
    rtcAttachGeometry(sc, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(sc);
    /* rays as the cache gathers them: a point on a random triangle, cosine around its normal */
    float *rays = malloc(nrays * 6 * sizeof(float));
    uint64_t x = 88172645463325252ull;
    for (size_t i = 0; i < nrays; i++) {
        x ^= x << 13; x ^= x >> 7; x ^= x << 17;
        size_t t = x % s->tri_count;
        const float *v0 = s->positions + 3 * s->tris[3 * t], *v1 = s->positions + 3 * s->tris[3 * t + 1],
                    *v2 = s->positions + 3 * s->tris[3 * t + 2];
        double a = (double)((x >> 11) & 0xFFFF) / 65536, b = (double)((x >> 27) & 0xFFFF) / 65536;
        if (a + b > 1) { a = 1 - a; b = 1 - b; }
        double e1[3], e2[3], n[3];
        for (int k = 0; k < 3; k++) { e1[k] = v1[k] - v0[k]; e2[k] = v2[k] - v0[k]; }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1]; n[1] = e1[2] * e2[0] - e1[0] * e2[2]; n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) + 1e-30;
        double u1 = (double)((x >> 43) & 0xFFFF) / 65536, u2 = fmod(i * 0.618033988749895, 1.0);
        double r = sqrt(u1), ph = 2 * M_PI * u2;
        double d[3] = {r * cos(ph), r * sin(ph), sqrt(1 - u1)};
        /* cosine lobe around the front normal (Duff et al. frame), like the cache's rays */
        double nn[3] = {n[0] / l, n[1] / l, n[2] / l};
        double sg = nn[2] >= 0 ? 1.0 : -1.0, q = -1.0 / (sg + nn[2]), w = nn[0] * nn[1] * q;
        double tt[3] = {1 + sg * nn[0] * nn[0] * q, sg * w, -sg * nn[0]}, bb[3] = {w, sg + nn[1] * nn[1] * q, -nn[1]};
        for (int k = 0; k < 3; k++) {
            rays[6 * i + k] = (float)((1 - a - b) * v0[k] + a * v1[k] + b * v2[k] + 1e-4 * nn[k]);
            rays[6 * i + 3 + k] = (float)(d[0] * tt[k] + d[1] * bb[k] + d[2] * nn[k]);
        }
    }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    size_t hits = 0;
    double t0 = bench_thread_cpu();
    for (size_t i = 0; i < nrays; i++) {
        struct RTCRayHit rh;
        rh.ray.org_x = rays[6 * i]; rh.ray.org_y = rays[6 * i + 1]; rh.ray.org_z = rays[6 * i + 2];
        rh.ray.dir_x = rays[6 * i + 3]; rh.ray.dir_y = rays[6 * i + 4]; rh.ray.dir_z = rays[6 * i + 5];
        rh.ray.tnear = 0; rh.ray.tfar = INFINITY; rh.ray.mask = ~0u; rh.ray.flags = 0; rh.ray.time = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(sc, &ctx, &rh);
        hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    double dt = bench_thread_cpu() - t0;
    if (hits == 0) printf("  (raw loop hit nothing?)\n");
    free(rays);
    rtcReleaseScene(sc);
    rtcReleaseDevice(dev);
    return (double)nrays / dt;
}

/* ---- 2. error vs time ---------------------------------------------------------------------------- */

static double measured_rmse(const float *irr, const float *ref, const bk_receiver *r, size_t n)
{
    double num = 0, den = 0;
    for (size_t i = 0; i < n; i++) {
        double sc = (r[i].normal[0] == 0 && r[i].normal[1] == 0 && r[i].normal[2] == 0) ? 0.25 : 1.0;
        double a = sc * (0.2126 * irr[3 * i] + 0.7152 * irr[3 * i + 1] + 0.0722 * irr[3 * i + 2]);
        double b = sc * (0.2126 * ref[3 * i] + 0.7152 * ref[3 * i + 1] + 0.0722 * ref[3 * i + 2]);
        num += (a - b) * (a - b);
        den += b * b;
    }
    return sqrt(num / den);
}

int main(int argc, char **argv)
{
    /* --rays: only part 1 (for profiling the baker's per-ray overhead with perf) */
    const int rays_only = argc > 1 && !strcmp(argv[1], "--rays");
    bk_scene s;
    build_room(&s);
    bk_tracer *t = NULL;
    if (bk_tracer_create(&s, 0, &t) != LBK_OK) { fprintf(stderr, "tracer failed\n"); return 1; }
    bk_receiver *r;
    size_t n = make_receivers(&r);
    lbk_sh9_rgb *rad = calloc(n, sizeof *rad);
    float *irr = calloc(3 * n, sizeof *irr), *ref = calloc(3 * n, sizeof *ref);
    bk_transport_output out = {rad, NULL, irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    printf("scene: %zu triangles, %zu receivers\n", s.tri_count, n);

    /* 1 */
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.threads = 1;
    o.target_error = -1;
    o.max_samples = 2 * 16 * 7; /* 3 passes */
    o.max_cells = 8192;
    bk_transport_stats st;
    /* gather rays only (no light sampling): the same kind of rays as the raw loop */
    o.nee = -1;
    double c0 = bench_thread_cpu();
    bk_transport_run(&s, t, r, n, &o, &out, &st);
    double cpu = bench_thread_cpu() - c0;
    double baker = (double)st.rays / cpu;
    double raw = raw_embree_rays_per_second(&s, st.rays < 4000000 ? (size_t)st.rays : 4000000);
    printf("rays/s per CPU second, 1 thread, NEE off: baker %.3g (all transport work included, %llu rays of which "
           "%llu punctual shadow rays, %.2f s CPU, %.2f s wall), raw rtcIntersect1 %.3g: ratio %.0f %% (goal >= 70 %%)\n",
           baker, (unsigned long long)st.rays, (unsigned long long)st.shadow_rays, cpu, st.seconds, raw, 100 * baker / raw);
    /* the default (NEE on here): shadow rays to sampled emitter points are cheaper than
     * closest-hit rays, so this ratio flatters; shown for completeness */
    o.nee = 0;
    c0 = bench_thread_cpu();
    bk_transport_run(&s, t, r, n, &o, &out, &st);
    cpu = bench_thread_cpu() - c0;
    printf("rays/s per CPU second, 1 thread, NEE on:  baker %.3g (%llu rays, %llu shadow, %.2f s CPU): ratio %.0f %% of raw "
           "closest-hit\n",
           (double)st.rays / cpu, (unsigned long long)st.rays, (unsigned long long)st.shadow_rays, cpu,
           100 * ((double)st.rays / cpu) / raw);
    if (rays_only) {
        free(rad); free(irr); free(ref); free(r);
        bk_tracer_destroy(t);
        tsc_free(&s);
        return 0;
    }

    /* 2: reference */
    memset(&o, 0, sizeof o);
    o.seed = 1000;
    o.target_error = -1;
    o.max_samples = 2 * 16 * 255; /* 8 passes */
    o.max_cells = 8192;
    bk_transport_output rout = {rad, NULL, ref, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    bk_transport_run(&s, t, r, n, &o, &rout, &st);
    double ref_err = st.est_rel_rmse;
    printf("reference: %.1f s, %.0f samples/receiver, its own estimated error %.4f\n", st.seconds,
           st.samples_per_receiver, ref_err);
    printf("%8s %8s %10s %10s %10s %8s\n", "budget_s", "spp", "estimated", "measured", "meas_corr", "est/meas");
    const double budgets[4] = {0.5, 1, 2, 4};
    for (int b = 0; b < 4; b++) {
        memset(&o, 0, sizeof o);
        o.seed = 7 + b;
        o.target_error = -1;
        o.time_limit = budgets[b];
        o.max_samples = 1 << 20;
        o.max_cells = 8192;
        bk_transport_run(&s, t, r, n, &o, &out, &st);
        double m = measured_rmse(irr, ref, r, n);
        /* the reference is noisy too: remove its (estimated) share in quadrature */
        double mc = sqrt(fmax(m * m - ref_err * ref_err, 0));
        printf("%8.2f %8.0f %10.4f %10.4f %10.4f %8.2f\n", budgets[b], st.samples_per_receiver, st.est_rel_rmse, m, mc,
               mc > 0 ? st.est_rel_rmse / mc : 0);
    }
    free(rad); free(irr); free(ref); free(r);
    bk_tracer_destroy(t);
    tsc_free(&s);
    return 0;
}
