#include "lightmap_fixture.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "transport_scenes.h"

static void check(lbk_result r, const char *what)
{
    if (r == LBK_OK) return;
    fprintf(stderr, "lightmap_fixture: %s: %s\n", what, lbk_result_message(r));
    abort();
}

void lmf_build(const bk_scene *s, float density, lmf *f)
{
    memset(f, 0, sizeof *f);
    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.density_override = density;
    check(bk_atlas_build(s, NULL, &ao, &f->atlas), "atlas");
    check(bk_tracer_create(s, 1, &f->tracer), "tracer");
    check(bk_texels_build(s, &f->atlas, &f->texels), "texels");
    bk_pushout_options po;
    memset(&po, 0, sizeof po);
    po.threads = 2;
    check(bk_texels_push_out(&f->texels, s, f->tracer, &po, NULL), "push-out");
    f->receivers = calloc(f->texels.count ? f->texels.count : 1, sizeof *f->receivers);
    f->texel_of_receiver = calloc(f->texels.count ? f->texels.count : 1, sizeof *f->texel_of_receiver);
    if (!f->receivers || !f->texel_of_receiver) abort();
    for (size_t i = 0; i < f->texels.count; i++) {
        const bk_texel *t = &f->texels.receivers[i];
        if (!(t->flags & BK_TEXEL_VALID)) continue;
        memcpy(f->receivers[f->count].position, t->position, sizeof t->position);
        memcpy(f->receivers[f->count].normal, t->normal, sizeof t->normal);
        f->texel_of_receiver[f->count++] = (uint32_t)i;
    }
}

void lmf_free(lmf *f)
{
    free(f->receivers);
    free(f->texel_of_receiver);
    bk_texels_free(&f->texels);
    if (f->tracer) bk_tracer_destroy(f->tracer);
    bk_atlas_free(&f->atlas);
    memset(f, 0, sizeof *f);
}

void lmf_contact_scene(bk_scene *s, float albedo)
{
    tsc_init(s);
    uint32_t grey = tsc_material(s, albedo, albedo, albedo, 0, 0, 0);
    float f0[3] = {-1, -1, 0}, f1[3] = {1, -1, 0}, f2[3] = {1, 1, 0}, f3[3] = {-1, 1, 0};
    tsc_quad(s, f0, f1, f2, f3, 4, grey);
    tsc_object(s, "slab", "", "");
    float mn[3] = {0, -LMF_SLAB_W, 0}, mx[3] = {LMF_SLAB_T, LMF_SLAB_W, LMF_SLAB_H};
    tsc_box(s, mn, mx, 1, 0, grey);
    tsc_object(s, "emitter", "", "");
    uint32_t em = tsc_material(s, 0, 0, 0, LMF_LE, LMF_LE, LMF_LE);
    s->materials[em].double_sided = 0;
    const float h = 0.5f * LMF_EM_SIDE;
    /* counter-clockwise seen from below: the front faces -z */
    float e0[3] = {LMF_EM_X - h, -h, LMF_EM_Z}, e1[3] = {LMF_EM_X - h, h, LMF_EM_Z}, e2[3] = {LMF_EM_X + h, h, LMF_EM_Z},
          e3[3] = {LMF_EM_X + h, -h, LMF_EM_Z};
    tsc_quad(s, e0, e1, e2, e3, 1, em);
    tsc_update_bounds(s);
}

/* 1 when the open segment p→q crosses the slab box (slab test). */
static int segment_hits_slab(const double p[3], const double q[3])
{
    const double mn[3] = {0, -LMF_SLAB_W, 0}, mx[3] = {LMF_SLAB_T, LMF_SLAB_W, LMF_SLAB_H};
    double t0 = 0, t1 = 1;
    for (int k = 0; k < 3; k++) {
        double d = q[k] - p[k];
        if (fabs(d) < 1e-300) {
            if (p[k] < mn[k] || p[k] > mx[k]) return 0;
            continue;
        }
        double a = (mn[k] - p[k]) / d, b = (mx[k] - p[k]) / d;
        if (a > b) {
            double t = a;
            a = b, b = t;
        }
        if (a > t0) t0 = a;
        if (b < t1) t1 = b;
        if (t0 >= t1) return 0;
    }
    return 1;
}

double lmf_contact_irradiance(double x, double y, int m, int occluded)
{
    const double h = 0.5 * LMF_EM_SIDE, dA = (LMF_EM_SIDE / m) * (LMF_EM_SIDE / m);
    const double p[3] = {x, y, 0};
    double sum = 0;
    for (int j = 0; j < m; j++)
        for (int i = 0; i < m; i++) {
            double q[3] = {LMF_EM_X - h + (i + 0.5) * LMF_EM_SIDE / m, -h + (j + 0.5) * LMF_EM_SIDE / m, LMF_EM_Z};
            if (occluded && segment_hits_slab(p, q)) continue;
            double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
            double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            double c = d[2] / sqrt(r2); /* cos at the floor = cos at the emitter (parallel planes) */
            sum += c * c / r2;
        }
    return LMF_LE * sum * dA;
}
