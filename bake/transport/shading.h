/* Scene lookups shared by the light transport (transport_impl.h) and the guided door estimator
 * (door_sampling.c, door_guided.c): one definition of how an image, a material, the sky and a
 * punctual light are evaluated, so the two estimators can never disagree on what a light is.
 * Doubles throughout (the bake accumulates in double; libformat's lbk_sh9_basis is the float
 * runtime version). */
#ifndef BK_SHADING_H
#define BK_SHADING_H

#include <math.h>
#include <stdint.h>

#include "scene/scene.h"
#include "scene/tracer.h"

#define BK_PI 3.14159265358979323846

static inline double bk_lum(const double c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }
static inline double bk_lumf(const float c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

static inline int bk_finite3(const double v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

/* Orthonormal t, b completing unit n (Duff et al. 2017, branchless). */
static inline void bk_onb(const double n[3], double t[3], double b[3])
{
    double s = n[2] >= 0 ? 1.0 : -1.0;
    double a = -1.0 / (s + n[2]);
    double bb = n[0] * n[1] * a;
    t[0] = 1 + s * n[0] * n[0] * a, t[1] = s * bb, t[2] = -s * n[0];
    b[0] = bb, b[1] = s + n[1] * n[1] * a, b[2] = -n[1];
}

/* The 9 real SH basis values at unit d (the coefficient order of lbk/sh.h). */
static inline void bk_sh9_basis_d(const double d[3], double y[9])
{
    double x = d[0], yy = d[1], z = d[2];
    y[0] = 0.282094791773878;
    y[1] = 0.488602511902920 * yy;
    y[2] = 0.488602511902920 * z;
    y[3] = 0.488602511902920 * x;
    y[4] = 1.092548430592079 * x * yy;
    y[5] = 1.092548430592079 * yy * z;
    y[6] = 0.315391565252520 * (3 * z * z - 1);
    y[7] = 1.092548430592079 * x * z;
    y[8] = 0.546274215296040 * (x * x - yy * yy);
}

/* Image idx of the scene, or NULL when idx is out of range. */
const bk_image *bk_scene_image(const bk_scene *s, int idx);
/* Nearest texel at (u, v) with the glTF default sampler (repeat): finite, non-negative RGB.
 * A missing image (or non-finite uv) reads as white (1, 1, 1): the material factor alone. */
void bk_sample_image(const bk_image *img, double u, double v, double out[3]);
/* uv0 of triangle tri at barycentrics (u, v); (0, 0) when the scene has no uv0. */
void bk_tri_uv0(const bk_scene *s, uint32_t tri, double u, double v, double uv[2]);
/* Albedo of material m at uv (factor × texture), clamped to [0, 0.999] (albedo ≥ 1 would make
 * the series diverge); 0 where not finite. */
void bk_material_albedo(const bk_scene *s, const bk_material *m, const double uv[2], double out[3]);
/* Emitted radiance of material m at uv (factor × texture), ≥ 0; 0 where not finite. */
void bk_material_emission(const bk_scene *s, const bk_material *m, const double uv[2], double out[3]);
/* Sky radiance along unit d: the uniform sky, or the equirectangular image (+Y up,
 * u = 0.5 + atan2(x, −z)/2π, v = acos(y)/π: v = 0 at the zenith, the image's top row). */
void bk_sky_radiance(const bk_scene *s, const double d[3], double out[3]);
/* Irradiance at normal incidence val from one punctual light at p (KHR_lights_punctual inverse
 * square falloff, range window, smooth spot cone), the unit direction towards the light and its
 * distance (INFINITY for directional). Returns 0 when the light cannot contribute. */
int bk_light_eval(const bk_light *l, const double p[3], double val[3], double dir[3], double *dist);
/* 1 when nothing in t blocks the shadow ray from org towards a light that bk_light_eval placed
 * along unit dir at dist (INFINITY: directional). A point light is aimed at itself from the
 * offset origin and the ray stops just short of it. */
int bk_light_visible(const bk_tracer *t, const float org[3], const double dir[3], double dist);

#endif
