/* Scene lookups shared by the transport and the guided door estimator; see shading.h. */
#include "bake/transport/shading.h"

#include <math.h>

const bk_image *bk_scene_image(const bk_scene *s, int idx)
{
    return (idx >= 0 && (size_t)idx < s->image_count) ? &s->images[idx] : NULL;
}

void bk_sample_image(const bk_image *img, double u, double v, double out[3])
{
    if (!img || !img->rgba || img->width <= 0 || img->height <= 0 || !isfinite(u) || !isfinite(v)) {
        out[0] = out[1] = out[2] = 1;
        return;
    }
    /* glTF default sampler: repeat; nearest texel is enough for cell-sized averages */
    double fu = u - floor(u), fv = v - floor(v);
    long x = (long)(fu * img->width), y = (long)(fv * img->height);
    if (x >= img->width) x = img->width - 1;
    if (y >= img->height) y = img->height - 1;
    const float *p = img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
    for (int k = 0; k < 3; k++) out[k] = isfinite(p[k]) && p[k] > 0 ? p[k] : 0;
}

void bk_tri_uv0(const bk_scene *s, uint32_t tri, double u, double v, double uv[2])
{
    uv[0] = uv[1] = 0;
    if (!s->uv0) return;
    const uint32_t *ix = s->tris + 3 * (size_t)tri;
    for (int k = 0; k < 2; k++) {
        double t0 = ix[0] < s->vertex_count ? s->uv0[2 * (size_t)ix[0] + k] : 0;
        double t1 = ix[1] < s->vertex_count ? s->uv0[2 * (size_t)ix[1] + k] : 0;
        double t2 = ix[2] < s->vertex_count ? s->uv0[2 * (size_t)ix[2] + k] : 0;
        uv[k] = (1 - u - v) * t0 + u * t1 + v * t2;
    }
}

void bk_material_albedo(const bk_scene *s, const bk_material *m, const double uv[2], double out[3])
{
    double ta[3] = {1, 1, 1};
    if (m->albedo_tex >= 0) bk_sample_image(bk_scene_image(s, m->albedo_tex), uv[0], uv[1], ta);
    for (int k = 0; k < 3; k++) {
        double a = m->albedo[k] * ta[k];
        out[k] = isfinite(a) ? (a < 0 ? 0 : a > 0.999 ? 0.999 : a) : 0;
    }
}

void bk_material_emission(const bk_scene *s, const bk_material *m, const double uv[2], double out[3])
{
    out[0] = out[1] = out[2] = 0;
    /* a texture cannot make a non-positive factor emit: skip the lookup */
    if (m->emission[0] <= 0 && m->emission[1] <= 0 && m->emission[2] <= 0) return;
    double te[3] = {1, 1, 1};
    if (m->emission_tex >= 0) bk_sample_image(bk_scene_image(s, m->emission_tex), uv[0], uv[1], te);
    for (int k = 0; k < 3; k++) {
        double e = m->emission[k] * te[k];
        out[k] = isfinite(e) && e > 0 ? e : 0;
    }
}

void bk_sky_radiance(const bk_scene *s, const double d[3], double out[3])
{
    const bk_image *img = bk_scene_image(s, s->sky_image);
    if (s->sky_image >= 0 && img && img->rgba) {
        double u = 0.5 + atan2(d[0], -d[2]) / (2 * BK_PI);
        double y = d[1] < -1 ? -1 : d[1] > 1 ? 1 : d[1];
        double v = acos(y) / BK_PI;
        bk_sample_image(img, u, v, out);
        return;
    }
    for (int k = 0; k < 3; k++) out[k] = isfinite(s->sky[k]) && s->sky[k] > 0 ? s->sky[k] : 0;
}

int bk_light_eval(const bk_light *l, const double p[3], double val[3], double dir[3], double *dist)
{
    double att;
    if (l->type == BK_LIGHT_DIRECTIONAL) {
        double n = sqrt((double)l->direction[0] * l->direction[0] + (double)l->direction[1] * l->direction[1] +
                        (double)l->direction[2] * l->direction[2]);
        if (!(n > 0) || !isfinite(n)) return 0;
        for (int k = 0; k < 3; k++) dir[k] = -l->direction[k] / n;
        *dist = INFINITY;
        att = 1;
    } else {
        double d[3] = {l->position[0] - p[0], l->position[1] - p[1], l->position[2] - p[2]};
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (!(d2 > 0) || !isfinite(d2)) return 0;
        double r = sqrt(d2);
        for (int k = 0; k < 3; k++) dir[k] = d[k] / r;
        *dist = r;
        att = 1.0 / d2;
        if (l->range > 0) {
            double q = r / l->range;
            double w = 1 - q * q * q * q;
            if (w <= 0) return 0;
            att *= w > 1 ? 1 : w;
        }
        if (l->type == BK_LIGHT_SPOT) {
            double ln = sqrt((double)l->direction[0] * l->direction[0] + (double)l->direction[1] * l->direction[1] +
                             (double)l->direction[2] * l->direction[2]);
            if (!(ln > 0)) return 0;
            double cd = -(dir[0] * l->direction[0] + dir[1] * l->direction[1] + dir[2] * l->direction[2]) / ln;
            double co = cos(l->outer_cone), ci = cos(l->inner_cone);
            double scale = 1.0 / fmax(0.001, ci - co);
            double t = (cd - co) * scale;
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            att *= t * t;
            if (att <= 0) return 0;
        }
    }
    for (int k = 0; k < 3; k++) val[k] = (isfinite(l->color[k]) && l->color[k] > 0 ? l->color[k] : 0) * att;
    if (!bk_finite3(val) || (val[0] <= 0 && val[1] <= 0 && val[2] <= 0)) return 0;
    return 1;
}

int bk_light_visible(const bk_tracer *t, const float org[3], const double dir[3], double dist)
{
    float d[3];
    float tmax;
    if (isinf(dist)) {
        for (int k = 0; k < 3; k++) d[k] = (float)dir[k];
        tmax = INFINITY;
    } else {
        for (int k = 0; k < 3; k++) d[k] = (float)(dir[k] * dist);
        tmax = 1.0f - 1e-5f;
    }
    return !bk_tracer_occluded(t, org, d, 0.0f, tmax);
}
