/* GLG density (printed, not asserted; bake/probes/PROBES.md §Density by playable space and
 * lighting): probe count against interpolation error for the uniform grid, the default
 * (geometry-refined) placement and the lighting rule, on room_with_doors (uniform sky 1 nit, as
 * /work/tools/baseline.sh bakes it, plus one 40 cd lamp) and a generated 36 × 24 m level of six
 * rooms with doorways (four lamps, one spot, two dark rooms).
 *
 * Error: at quasi-random points of free space, the GLG's interpolation (barycentric SH9 in the
 * containing tetrahedron) against a probe baked at the point itself, as irradiance towards the six
 * axis directions, over the points inside every configuration's hull: "rel.error" is the RMS of
 * the per-point relative error (each difference over the point's own mean irradiance plus 5 % of
 * the level's RMS, what the density rule targets and what a viewer sees), "rms/rms" the
 * level-wide RMS difference over the RMS irradiance (dominated by the few points next to a lamp).
 * "raw" is rel.error with the transport's noise in it; rel.error takes the expected noise
 * ("noise": Σ w² var of the four probes plus the reference's variance, the transport's own
 * estimate) off its square, so what is left is interpolation error. All probes
 * and reference points are gathered in one transport run (one cache), so the cache's bias is the
 * same on both sides; the noise of the run is printed as the floor. "equal error" gives, per
 * adaptive configuration, the probe count the uniform grid needs for the same error (log-log
 * interpolation between the uniform points) and the saving. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake/probes/delaunay.h"
#include "bake/probes/glg_coarse.h"
#include "bake/probes/glg_place.h"
#include "bake/probes/probe_math.h"
#include "scene/import.h"
#include "bake/transport/transport.h"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"

#define MAX_CONFIGS 16
#ifndef GATHER_SAMPLES
#define GATHER_SAMPLES 1024
#endif

typedef struct config {
    const char *name;
    int kind;              /* 0 uniform, 1 default (geometry-refined), 2 lighting rule */
    float spacing, threshold;
    int refine;            /* bk_glg_options.refine_levels */
    bk_glg_probes probes;
    bk_tetmesh mesh;
    size_t first;          /* its probes' first receiver */
    double error, raw_error, noise, rel_error, seconds;
    size_t coarse_points;
} config;

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double halton(size_t i, int base)
{
    double f = 1, r = 0;
    for (size_t n = i + 1; n > 0; n /= (size_t)base) { f /= base; r += f * (double)(n % (size_t)base); }
    return r;
}

/* Free space as the GLG sees it: no majority of back faces over 32 rays, nearest surface >= d. */
static int free_point(const bk_scene *s, const bk_tracer *t, const float p[3], float d)
{
    int front = 0, back = 0;
    for (int r = 0; r < 32; r++) {
        float dir[3];
        bk_sphere_direction((size_t)r, 32, dir);
        bk_hit h;
        if (!bk_tracer_intersect(t, p, dir, 0.0f, 1e30f, &h)) continue;
        if (h.t < d) return 0;
        uint32_t m = s->tri_material ? s->tri_material[h.tri] : 0;
        int ds = s->materials && m < s->material_count ? s->materials[m].double_sided : 0;
        if (h.front || ds) front++; else back++;
    }
    return front >= back;
}

static void irr6(const lbk_sh9_rgb *sh, double out[6])
{
    static const float dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int d = 0; d < 6; d++) {
        float e[3];
        lbk_sh9_irradiance(sh, dirs[d], e);
        out[d] = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
    }
}

/* Barycentrics of p in tetrahedron t, or 0 when outside (small tolerance). */
static int tet_bary(const bk_tetmesh *m, size_t t, const float p[3], double w[4])
{
    const float *v[4];
    for (int i = 0; i < 4; i++) v[i] = m->points + 3 * (size_t)m->tets[4 * t + (size_t)i];
    double a[3][3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k][0] = v[1][k] - v[0][k]; a[k][1] = v[2][k] - v[0][k]; a[k][2] = v[3][k] - v[0][k];
        b[k] = p[k] - v[0][k];
    }
    double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                 a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if (!(fabs(det) > 0)) return 0;
    double x[3];
    for (int c = 0; c < 3; c++) {
        double m2[3][3];
        memcpy(m2, a, sizeof m2);
        for (int k = 0; k < 3; k++) m2[k][c] = b[k];
        x[c] = (m2[0][0] * (m2[1][1] * m2[2][2] - m2[1][2] * m2[2][1]) - m2[0][1] * (m2[1][0] * m2[2][2] - m2[1][2] * m2[2][0]) +
                m2[0][2] * (m2[1][0] * m2[2][1] - m2[1][1] * m2[2][0])) / det;
    }
    w[1] = x[0]; w[2] = x[1]; w[3] = x[2]; w[0] = 1 - x[0] - x[1] - x[2];
    for (int i = 0; i < 4; i++) if (w[i] < -1e-6) return 0;
    return 1;
}

/* Interpolated irradiance at p, or 0 outside the mesh; *noise: the interpolation's noise variance
 * (Σ w² var of its probes). Brute force over tetrahedra: a bench. */
static int interpolate(const config *c, const lbk_sh9_rgb *radiance, const float *var, const float p[3], double out[6],
                       double *noise)
{
    const bk_tetmesh *m = &c->mesh;
    for (size_t t = 0; t < m->tet_count; t++) {
        const uint32_t *v = m->tets + 4 * t;
        int out_box = 0;
        for (int k = 0; k < 3 && !out_box; k++) {
            float lo = m->points[3 * v[0] + k], hi = lo;
            for (int i = 1; i < 4; i++) { float x = m->points[3 * v[i] + k]; lo = fminf(lo, x); hi = fmaxf(hi, x); }
            out_box = p[k] < lo - 1e-5f || p[k] > hi + 1e-5f;
        }
        double w[4];
        if (out_box || !tet_bary(m, t, p, w)) continue;
        lbk_sh9_rgb sh;
        memset(&sh, 0, sizeof sh);
        *noise = 0;
        for (int i = 0; i < 4; i++) {
            size_t r = c->first + m->point_source[v[i]];
            lbk_sh9_add_scaled(&sh, &radiance[r], (float)w[i]);
            *noise += w[i] * w[i] * var[r];
        }
        irr6(&sh, out);
        return 1;
    }
    return 0;
}

static double uniform_count_at(const config *cf, int n, double err)
{
    /* uniform configs sorted by count; log-log interpolation of count over error */
    for (int i = 0; i + 1 < n; i++) {
        const config *a = &cf[i], *b = &cf[i + 1];
        if (a->kind || b->kind) continue;
        double e0 = a->error, e1 = b->error; /* a coarser (fewer, larger error) */
        if ((err <= e0 && err >= e1) || (err >= e0 && err <= e1)) {
            double t = (log(err) - log(e0)) / (log(e1) - log(e0));
            return exp(log((double)a->probes.count) + t * (log((double)b->probes.count) - log((double)a->probes.count)));
        }
    }
    return -1;
}

static void run_level(const char *title, const bk_scene *s, const float *uniform_spacings, int nu, float base_spacing)
{
    bk_tracer *tr = NULL;
    if (bk_tracer_create(s, 0, &tr) != LBK_OK) { printf("  tracer failed\n"); return; }
    config cf[MAX_CONFIGS];
    int n = 0;
    memset(cf, 0, sizeof cf);
    for (int i = 0; i < nu; i++) cf[n++] = (config){.name = "uniform", .kind = 0, .spacing = uniform_spacings[i], .refine = -1};
    cf[n++] = (config){.name = "default (geometry)", .kind = 1, .spacing = base_spacing};
    const float thr[] = {0.8f, 0.4f, 0.2f};
    for (int i = 0; i < 3; i++) cf[n++] = (config){.name = "lighting", .kind = 2, .spacing = base_spacing, .threshold = thr[i], .refine = -1};
    for (int i = 0; i < 2; i++) cf[n++] = (config){.name = "lighting+geometry", .kind = 2, .spacing = base_spacing, .threshold = thr[i]};
    bk_glg_coarse coarse = {0};
    coarse.scene = s; coarse.tracer = tr; coarse.seed = 1;
    size_t total = 0;
    for (int i = 0; i < n; i++) {
        bk_glg_options o = {0};
        o.spacing = cf[i].spacing;
        o.refine_levels = cf[i].refine;
        o.max_probes = 200000;
        if (cf[i].kind == 2) { o.lighting = bk_glg_coarse_lighting; o.lighting_user = &coarse; o.lighting_threshold = cf[i].threshold; }
        double t0 = wall_now();
        if (bk_glg_place(s, tr, &o, 0, &cf[i].probes) != LBK_OK || bk_delaunay(cf[i].probes.positions, cf[i].probes.count, NULL, &cf[i].mesh) != BK_DELAUNAY_OK) {
            printf("  %s: placement failed\n", cf[i].name);
            n = i;
            break;
        }
        cf[i].seconds = wall_now() - t0;
        cf[i].coarse_points = cf[i].probes.coarse_points;
        cf[i].first = total;
        total += cf[i].probes.count;
        fprintf(stderr, "  [%s %.2f %.3f: %zu probes, %.1f s]\n", cf[i].name, cf[i].spacing, cf[i].threshold,
                cf[i].probes.count, cf[i].seconds);
    }
    /* reference points */
    size_t want = 800, nref = 0;
    float *ref = malloc(want * 3 * sizeof *ref);
    float ext[3];
    for (int k = 0; k < 3; k++) ext[k] = s->bounds_max[k] - s->bounds_min[k];
    for (size_t i = 0; nref < want && i < 40 * want; i++) {
        float p[3];
        for (int k = 0; k < 3; k++) p[k] = s->bounds_min[k] + (float)halton(i, k == 0 ? 2 : k == 1 ? 3 : 5) * ext[k];
        if (free_point(s, tr, p, 0.1f)) memcpy(ref + 3 * nref++, p, sizeof p);
    }
    size_t count = total + nref;
    bk_receiver *r = calloc(count, sizeof *r);
    lbk_sh9_rgb *rad = calloc(count, sizeof *rad);
    float *var = calloc(count, sizeof *var), *irr = calloc(3 * count, sizeof *irr);
    for (int i = 0; i < n; i++)
        for (size_t j = 0; j < cf[i].probes.count; j++) memcpy(r[cf[i].first + j].position, cf[i].probes.positions + 3 * j, 12);
    for (size_t j = 0; j < nref; j++) memcpy(r[total + j].position, ref + 3 * j, 12);
    bk_transport_options to = {0};
    to.seed = 7; to.max_samples = GATHER_SAMPLES; to.target_error = -1;
    bk_transport_output out = {0};
    out.radiance = rad; out.variance = var; out.irradiance = irr;
    bk_transport_stats st;
    double t0 = wall_now();
    lbk_result res = bk_transport_run(s, tr, r, count, &to, &out, &st);
    double gather_s = wall_now() - t0;
    if (res != LBK_OK) { printf("  transport failed\n"); goto done; }
    /* which reference points every configuration covers */
    double *vals = malloc((size_t)n * nref * 6 * sizeof *vals), *nvar = malloc((size_t)n * nref * sizeof *nvar);
    unsigned char *ok = malloc(nref);
    size_t used = 0;
    for (size_t j = 0; j < nref; j++) {
        ok[j] = 1;
        for (int i = 0; i < n && ok[j]; i++) ok[j] = (unsigned char)interpolate(&cf[i], rad, var, ref + 3 * j, vals + ((size_t)i * nref + j) * 6,
                                                                   nvar + (size_t)i * nref + j);
        used += ok[j];
    }
    double noise = 0, scale = 0;
    for (size_t j = 0; j < nref; j++) {
        if (!ok[j]) continue;
        double e[6];
        irr6(&rad[total + j], e);
        for (int d = 0; d < 6; d++) scale += e[d] * e[d];
        noise += 6.0 * 4.0 * var[total + j] * 0.25;  /* X is fluence/4, irradiance ~ fluence/4: one unit each */
    }
    double mean_level = sqrt(scale / (6.0 * (double)(used ? used : 1)));
    for (int i = 0; i < n; i++) {
        double num = 0, rel = 0, relnoise = 0;
        for (size_t j = 0; j < nref; j++) {
            if (!ok[j]) continue;
            double e[6], level = 0.05 * mean_level;
            irr6(&rad[total + j], e);
            for (int d = 0; d < 6; d++) level += e[d] / 6.0;
            for (int d = 0; d < 6; d++) {
                double df = vals[((size_t)i * nref + j) * 6 + d] - e[d];
                num += df * df;
                rel += df * df / (level * level);
                /* the transport's variance of fluence/4, taken for each direction's irradiance */
                relnoise += (nvar[(size_t)i * nref + j] + var[total + j]) / (level * level);
            }
        }
        cf[i].raw_error = sqrt(rel / (6.0 * (double)(used ? used : 1)));
        cf[i].error = sqrt(fmax(0.0, rel - relnoise) / (6.0 * (double)(used ? used : 1)));
        cf[i].noise = sqrt(relnoise / (6.0 * (double)(used ? used : 1)));
        cf[i].rel_error = sqrt(num / scale);
    }
    printf("== %s: %zu reference points (%zu inside every hull), gather %d samples, %.1f s, noise floor ~%.4f (per-probe estimate, x sqrt2 for probe + reference)\n",
           title, nref, used, GATHER_SAMPLES, gather_s, sqrt(2.0 * noise / scale));
    printf("  %-20s %7s %9s %8s %10s %10s %10s %10s %10s %16s\n", "placement", "spacing", "threshold", "probes", "rel.error",
           "raw", "noise", "rms/rms", "coarse pts", "uniform@same err");
    for (int i = 0; i < n; i++) {
        double u = cf[i].kind ? uniform_count_at(cf, nu, cf[i].error) : -1;
        char us[32] = "";
        if (u > 0) snprintf(us, sizeof us, "%.0f (%.0f%%)", u, 100.0 * (double)cf[i].probes.count / u);
        else if (cf[i].kind) snprintf(us, sizeof us, "out of range");
        printf("  %-20s %7.2f %9.3f %8zu %10.4f %10.4f %10.4f %10.4f %10zu %16s\n", cf[i].name, cf[i].spacing, cf[i].threshold,
               cf[i].probes.count, cf[i].error, cf[i].raw_error, cf[i].noise, cf[i].rel_error, cf[i].coarse_points, us);
    }
    printf("  coarse pass: %.2f s, %.2f Mrays over all lighting configurations\n", coarse.seconds, coarse.rays * 1e-6);
    free(vals); free(ok); free(nvar);
done:
    for (int i = 0; i < n; i++) { bk_glg_probes_free(&cf[i].probes); bk_tetmesh_free(&cf[i].mesh); }
    free(ref); free(r); free(rad); free(var); free(irr);
    bk_tracer_destroy(tr);
}

/* Six rooms in a 3 × 2 block, 12 × 12 × 3.5 m each, walls 0.2 m thick with 1.2 m doorways; four
 * lit by lamps (one warm, one bright), one by a spot on the floor, one dark. */
static void build_level(bk_scene *s)
{
    tsc_init(s);
    uint32_t wall = tsc_material(s, 0.7f, 0.7f, 0.7f, 0, 0, 0);
    const float W = 36, D = 24, H = 3.5f;
    float mn[3] = {0, 0, 0}, mx[3] = {W, D, H};
    tsc_box(s, mn, mx, 12, 1, wall);
    /* walls along y at x = 12, 24 (doorways at y 5.4..6.6 and 17.4..18.6) */
    for (int i = 1; i <= 2; i++) {
        float x = 12.0f * (float)i;
        float segs[3][2] = {{0, 5.4f}, {6.6f, 17.4f}, {18.6f, D}};
        for (int k = 0; k < 3; k++) {
            float a[3] = {x - 0.1f, segs[k][0], 0}, b[3] = {x + 0.1f, segs[k][1], H};
            tsc_box(s, a, b, 4, 0, wall);
        }
    }
    /* wall along x at y = 12 with a doorway per room */
    for (int i = 0; i < 3; i++) {
        float x0 = 12.0f * (float)i;
        float segs[2][2] = {{x0 + (i ? 0.1f : 0), x0 + 5.4f}, {x0 + 6.6f, x0 + 12 - (i < 2 ? 0.1f : 0)}};
        for (int k = 0; k < 2; k++) {
            float a[3] = {segs[k][0], 11.9f, 0}, b[3] = {segs[k][1], 12.1f, H};
            tsc_box(s, a, b, 4, 0, wall);
        }
    }
    float l0[3] = {6, 6, 3.0f}, l1[3] = {18, 6, 3.0f}, l2[3] = {6, 18, 3.0f}, l3[3] = {30, 18, 2.0f};
    tsc_point_light(s, l0, 60, 55, 45, 0);
    tsc_point_light(s, l1, 20, 20, 25, 0);
    tsc_point_light(s, l2, 150, 140, 120, 0);
    tsc_point_light(s, l3, 40, 40, 40, 0);
    float sp[3] = {18, 18, 3.3f}, sd[3] = {0, 0, -1};
    tsc_spot_light(s, sp, sd, 400, 0.3f, 0.4f);
    tsc_update_bounds(s);
}

int main(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    bk_scene room;
    char err[512];
    bk_import_options io = {0};
    io.recentre = 1;
    /* LBK_SCENES overrides scenes/, as in bench_atlas */
    const char *dir = getenv("LBK_SCENES");
    char path[1024];
    snprintf(path, sizeof path, "%s/room_with_doors/room.glb", dir && *dir ? dir : "scenes");
    if (bk_import_gltf(path, &io, &room, err, sizeof err)) {
        printf("room_with_doors: %s (skipped)\n", err);
    } else {
        room.sky[0] = room.sky[1] = room.sky[2] = 1.0f;
        float lp[3] = {-2.0f, 2.5f, 1.0f};
        tsc_point_light(&room, lp, 40, 40, 40, 0);
        const float us[] = {2.0f, 1.5f, 1.0f, 0.75f, 0.5f, 0.4f};
        run_level("room_with_doors (sky 1 nit + 40 cd lamp)", &room, us, 6, 1.0f);
        bk_scene_free(&room);
    }
    bk_scene lvl;
    build_level(&lvl);
    const float ul[] = {3.0f, 2.0f, 1.5f, 1.0f, 0.75f};
    run_level("generated level 36 x 24 x 3.5 m, 6 rooms", &lvl, ul, 5, 1.5f);
    tsc_free(&lvl);
    return 0;
}
