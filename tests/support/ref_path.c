#include "ref_path.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "scene/parallel.h"

#define RP_PI 3.14159265358979323846

/* splitmix64 stream: independent of the transport's hashing (different constants and layout) */
static uint64_t rp_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 33)) * 0xFF51AFD7ED558CCDull;
    z = (z ^ (z >> 33)) * 0xC4CEB9FE1A85EC53ull;
    return z ^ (z >> 33);
}

double rp_uniform(uint64_t *state) { return (double)(rp_next(state) >> 11) * (1.0 / 9007199254740992.0); }

uint64_t rp_stream(uint64_t seed, uint64_t item)
{
    uint64_t s = seed * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull;
    s ^= item * 0xAEF17502108EF2D9ull;
    rp_next(&s);
    return s;
}

int rp_check(const bk_scene *s, char *err, size_t err_len)
{
    if (s->light_count) { snprintf(err, err_len, "punctual lights are not modelled"); return 1; }
    if (s->sky_image >= 0) { snprintf(err, err_len, "sky images are not modelled"); return 1; }
    for (size_t i = 0; i < s->material_count; i++)
        if (s->materials[i].albedo_tex >= 0 || s->materials[i].emission_tex >= 0) {
            snprintf(err, err_len, "textures are not modelled");
            return 1;
        }
    for (size_t i = 0; i < s->object_count; i++)
        if (s->objects[i].light_set[0] || s->objects[i].door[0]) {
            snprintf(err, err_len, "light sets and doors are not modelled");
            return 1;
        }
    return 0;
}

void rp_cosine_dir(const double n[3], uint64_t *state, double d[3])
{
    double u1 = rp_uniform(state), u2 = rp_uniform(state);
    double r = sqrt(u1), phi = 2 * RP_PI * u2;
    double lx = r * cos(phi), ly = r * sin(phi), lz = sqrt(fmax(0.0, 1 - u1));
    /* any orthonormal frame: Gram-Schmidt against the axis least aligned with n */
    double a[3] = {0, 0, 0};
    int k = fabs(n[0]) < fabs(n[1]) ? (fabs(n[0]) < fabs(n[2]) ? 0 : 2) : (fabs(n[1]) < fabs(n[2]) ? 1 : 2);
    a[k] = 1;
    double dt = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
    double t[3] = {a[0] - dt * n[0], a[1] - dt * n[1], a[2] - dt * n[2]};
    double tl = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int i = 0; i < 3; i++) t[i] /= tl;
    double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
    for (int i = 0; i < 3; i++) d[i] = lx * t[i] + ly * b[i] + lz * n[i];
}

void rp_offset(const double p[3], const double n[3], double o[3])
{
    double m = fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2])));
    double eps = 2e-5 * fmax(1.0, m);
    for (int i = 0; i < 3; i++) o[i] = p[i] + eps * n[i];
}

void rp_radiance(const bk_scene *s, const bk_tracer *t, const double o_in[3], const double d_in[3], uint64_t *state,
                 double out[3])
{
    double o[3] = {o_in[0], o_in[1], o_in[2]}, d[3] = {d_in[0], d_in[1], d_in[2]};
    double beta[3] = {1, 1, 1};
    out[0] = out[1] = out[2] = 0;
    for (int depth = 0; depth < 1000; depth++) {
        float of[3] = {(float)o[0], (float)o[1], (float)o[2]}, df[3] = {(float)d[0], (float)d[1], (float)d[2]};
        bk_hit h;
        if (!bk_tracer_intersect(t, of, df, 0.0f, INFINITY, &h)) {
            for (int c = 0; c < 3; c++) out[c] += beta[c] * s->sky[c];
            return;
        }
        uint32_t mi = s->tri_material ? s->tri_material[h.tri] : 0;
        const bk_material *m = &s->materials[mi];
        if (!h.front && !m->double_sided) return; /* one-sided back face: black */
        for (int c = 0; c < 3; c++) out[c] += beta[c] * m->emission[c];
        double rho = fmax(m->albedo[0], fmax(m->albedo[1], m->albedo[2]));
        if (!(rho > 0)) return;
        if (depth >= 3) {
            double q = fmin(rho, 0.95);
            if (rp_uniform(state) >= q) return;
            for (int c = 0; c < 3; c++) beta[c] /= q;
        }
        for (int c = 0; c < 3; c++) beta[c] *= m->albedo[c];
        /* the hit point from the triangle in double, then off the side the ray arrived on */
        const uint32_t *ix = s->tris + 3 * (size_t)h.tri;
        double p[3], n[3];
        for (int c = 0; c < 3; c++) {
            double a = s->positions[3 * (size_t)ix[0] + c], b = s->positions[3 * (size_t)ix[1] + c],
                   cc = s->positions[3 * (size_t)ix[2] + c];
            p[c] = (1.0 - h.u - h.v) * a + h.u * b + h.v * cc;
            n[c] = h.front ? h.ng[c] : -h.ng[c];
        }
        rp_offset(p, n, o);
        rp_cosine_dir(n, state, d);
    }
}

typedef struct rp_job {
    const bk_scene *s;
    const bk_tracer *t;
    const float *p, *n;
    int paths;
    uint64_t seed;
    double *out, *se;
    const bk_footprint_tri *fp;   /* footprints (NULL: points) */
    const uint32_t *first, *count;
    const uint8_t *enclosed;      /* per texel RP_GRID² cells: 1 where the cell's centre is enclosed */
} rp_job;

/* The visible part of a footprint, resolved to RP_GRID² cells of the texel's square by the
 * tracer's enclosure test at each cell's centre (a point inside a sill let into a wall, under a
 * crate): the reference's own reading of "visible", not the baker's. */
#define RP_GRID 16

/* The footprint point of texel i at texel-local (a, b) (the reference's own reading of
 * bk_footprint_tri). Returns 0 where no footprint triangle covers it. */
static int rp_footprint_at(const rp_job *j, size_t i, double a, double b, double p[3], double n[3])
{
    const bk_scene *s = j->s;
    for (uint32_t k = 0; k < j->count[i]; k++) {
        const bk_footprint_tri *f = &j->fp[j->first[i] + k];
        double u = f->uv[0][0] + f->uv[0][1] * a + f->uv[0][2] * b;
        double v = f->uv[1][0] + f->uv[1][1] * a + f->uv[1][2] * b;
        if (u < 0 || v < 0 || u + v > 1) continue;
        const uint32_t *ix = s->tris + 3 * (size_t)f->tri;
        double w[3] = {1 - u - v, u, v};
        for (int c = 0; c < 3; c++) {
            p[c] = n[c] = 0;
            for (int q = 0; q < 3; q++) {
                p[c] += w[q] * s->positions[3 * (size_t)ix[q] + c];
                n[c] += w[q] * s->normals[3 * (size_t)ix[q] + c];
            }
        }
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int c = 0; c < 3; c++) n[c] /= l;
        return 1;
    }
    return 0;
}

/* A uniform point of the visible part of texel i's footprint, by rejection. */
static int rp_footprint_point(const rp_job *j, size_t i, uint64_t *st, double p[3], double n[3])
{
    const uint8_t *enc = j->enclosed ? j->enclosed + i * RP_GRID * RP_GRID : NULL;
    for (int tries = 0; tries < 1024; tries++) {
        double a = rp_uniform(st), b = rp_uniform(st);
        int cx = (int)(a * RP_GRID), cy = (int)(b * RP_GRID);
        if (enc && enc[(cy < RP_GRID ? cy : RP_GRID - 1) * RP_GRID + (cx < RP_GRID ? cx : RP_GRID - 1)]) continue;
        if (rp_footprint_at(j, i, a, b, p, n)) return 1;
    }
    return 0;
}

static void rp_enclosed_chunk(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    const rp_job *j = (const rp_job *)user;
    uint8_t *enc = (uint8_t *)j->enclosed;
    for (size_t i = begin; i < end; i++)
        for (int c = 0; c < RP_GRID * RP_GRID; c++) {
            double p[3], n[3];
            int e = 0;
            if (j->count[i] && rp_footprint_at(j, i, (c % RP_GRID + 0.5) / RP_GRID, (c / RP_GRID + 0.5) / RP_GRID, p, n)) {
                const float nf[3] = {(float)n[0], (float)n[1], (float)n[2]};
                e = bk_tracer_enclosed(j->t, p, nf, 1e-4);
            }
            enc[i * RP_GRID * RP_GRID + c] = (uint8_t)e;
        }
}

static void rp_chunk(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    const rp_job *j = (const rp_job *)user;
    for (size_t i = begin; i < end; i++) {
        uint64_t st = rp_stream(j->seed, i);
        double n[3] = {j->n[3 * i], j->n[3 * i + 1], j->n[3 * i + 2]};
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int c = 0; c < 3; c++) n[c] /= l;
        double p[3] = {j->p[3 * i], j->p[3 * i + 1], j->p[3 * i + 2]}, o[3];
        rp_offset(p, n, o);
        double sum[3] = {0, 0, 0}, s1 = 0, s2 = 0;
        const double p0[3] = {p[0], p[1], p[2]}, n0[3] = {n[0], n[1], n[2]};
        for (int k = 0; k < j->paths; k++) {
            double d[3], L[3];
            if (j->fp && j->count[i]) {
                if (!rp_footprint_point(j, i, &st, p, n)) {
                    memcpy(p, p0, sizeof p);
                    memcpy(n, n0, sizeof n);
                }
                rp_offset(p, n, o);
            }
            rp_cosine_dir(n, &st, d);
            rp_radiance(j->s, j->t, o, d, &st, L);
            for (int c = 0; c < 3; c++) sum[c] += L[c];
            double y = 0.2126 * L[0] + 0.7152 * L[1] + 0.0722 * L[2];
            s1 += y;
            s2 += y * y;
        }
        for (int c = 0; c < 3; c++) j->out[3 * i + c] = RP_PI * sum[c] / j->paths;
        if (j->se) {
            double mean = s1 / j->paths, var = fmax(0.0, s2 / j->paths - mean * mean);
            j->se[i] = RP_PI * sqrt(var / fmax(1.0, j->paths - 1.0));
        }
    }
}

void rp_irradiance(const bk_scene *s, const bk_tracer *t, const float *p, const float *n, size_t count, int paths,
                   uint64_t seed, int threads, double *out_rgb, double *stderr_lum)
{
    rp_job j = {s, t, p, n, paths, seed, out_rgb, stderr_lum, NULL, NULL, NULL, NULL};
    bk_parallel_chunks(0, count, 4, threads > 0 ? threads : 1, rp_chunk, &j);
}

void rp_footprint_irradiance(const bk_scene *s, const bk_tracer *t, const bk_footprint_tri *fp,
                             const uint32_t *first, const uint32_t *count, const float *p, const float *n, size_t texels,
                             int paths, uint64_t seed, int threads, double *out_rgb, double *stderr_lum)
{
    uint8_t *enclosed = calloc(texels ? texels * RP_GRID * RP_GRID : 1, 1);
    rp_job j = {s, t, p, n, paths, seed, out_rgb, stderr_lum, fp, first, count, enclosed};
    if (enclosed) bk_parallel_chunks(0, texels, 4, threads > 0 ? threads : 1, rp_enclosed_chunk, &j);
    bk_parallel_chunks(0, texels, 4, threads > 0 ? threads : 1, rp_chunk, &j);
    free(enclosed);
}
