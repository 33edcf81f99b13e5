/* An independent reference for the light transport: a brute-force path tracer of irradiance at
 * points, written without any of bake/transport/transport.c (no cache, no lattices, no MIS, no
 * next-event estimation, its own random numbers and its own ray offsets). Only the ray casts go
 * through bk_tracer (the tracer is tested on its own, test_tracer.c).
 *
 * Model (the one the baker implements, TRANSPORT.md): Lambertian surfaces of the material's
 * albedo factor (untextured scenes only: rp_check says so), emission factor on the front side
 * (both sides when double sided), one-sided back faces absorb (black, opaque), uniform sky on
 * every escaping ray. No punctual lights (rp_check refuses them).
 *
 * Estimator: E(x, n) = π · mean over cosine-distributed paths of the incident radiance; each
 * vertex adds its emission and continues in a cosine direction with throughput × albedo;
 * Russian roulette from the 4th vertex on with survival max(albedo) (weight 1/survival). Unbiased
 * for any path length. Each point's paths use a private stream keyed by (seed, point), so results
 * are the same at any thread count. */
#ifndef RP_REF_PATH_H
#define RP_REF_PATH_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"
#include "scene/tracer.h"
#include "bake/transport/transport.h"

/* 0 when the scene is within the model above, else 1 with a reason in err. */
int rp_check(const bk_scene *s, char *err, size_t err_len);

/* Irradiance (RGB, 3 floats per point) at `count` points with unit normals n (3 floats each),
 * `paths` paths per point, on `threads` threads (0: 1). Also the per-point standard error of the
 * luminance if stderr_lum is not NULL. Positions are used as given: the first ray leaves from
 * p + offset·n. */
void rp_irradiance(const bk_scene *s, const bk_tracer *t, const float *p, const float *n, size_t count, int paths,
                   uint64_t seed, int threads, double *out_rgb, double *stderr_lum);

/* Irradiance averaged over the visible part of texel footprints: point k of texel i is uniform
 * over the part of texel-local [0,1]² that one of its footprint triangles covers (fp[first[i] ..
 * first[i] + count[i]), the bk_footprint_tri convention; scene `s` gives positions and shading
 * normals), by rejection, leaving out the 1/16-texel cells whose centre bk_tracer_enclosed finds
 * enclosed (inside a sill let into the wall: no surface anyone sees); `paths` points (one path
 * each) per texel. A texel whose visible footprint yields nothing in 1024 draws uses p/n. Same
 * outputs as rp_irradiance. */
void rp_footprint_irradiance(const bk_scene *s, const bk_tracer *t, const bk_footprint_tri *fp,
                             const uint32_t *first, const uint32_t *count, const float *p, const float *n, size_t texels,
                             int paths, uint64_t seed, int threads, double *out_rgb, double *stderr_lum);

/* One path's incident radiance along the unit direction d from origin o (already offset). Exposed
 * so the footprint reference (texel averages) can reuse the same estimator. state: the stream. */
void rp_radiance(const bk_scene *s, const bk_tracer *t, const double o[3], const double d[3], uint64_t *state,
                 double out[3]);

/* Cosine-distributed direction around unit n from the stream. */
void rp_cosine_dir(const double n[3], uint64_t *state, double d[3]);
double rp_uniform(uint64_t *state);
uint64_t rp_stream(uint64_t seed, uint64_t item);
/* p moved off the surface along n by a scale-aware distance (independent of bk_offset_ray_origin). */
void rp_offset(const double p[3], const double n[3], double o[3]);

#endif
