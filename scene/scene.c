/* Small utilities over bk_scene: freeing, bounds, hashing, the "is anything lit" test, a check. */
#include "scene/scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

void bk_scene_free(bk_scene *scene)
{
    if (!scene) return;
    free(scene->positions);
    free(scene->normals);
    free(scene->uv0);
    free(scene->uv1);
    free(scene->tangents);
    free(scene->tris);
    free(scene->tri_material);
    free(scene->tri_object);
    free(scene->vertex_source);
    free(scene->primitives);
    free(scene->materials);
    free(scene->objects);
    free(scene->lights);
    for (size_t i = 0; i < scene->image_count; i++) free(scene->images[i].rgba);
    free(scene->images);
    free(scene->combinations);
    free(scene->playable);
    free(scene->inputs);
    memset(scene, 0, sizeof *scene);
    scene->sky_image = -1;
}

void bk_scene_compute_bounds(bk_scene *scene)
{
    float mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    int any = 0;
    for (size_t v = 0; v < scene->vertex_count; v++) {
        for (int k = 0; k < 3; k++) {
            float x = scene->positions[3 * v + k];
            if (x < mn[k]) mn[k] = x;
            if (x > mx[k]) mx[k] = x;
        }
        any = 1;
    }
    for (size_t i = 0; i < scene->light_count; i++) {
        const bk_light *l = &scene->lights[i];
        if (l->type == BK_LIGHT_DIRECTIONAL) continue;
        for (int k = 0; k < 3; k++) {
            if (l->position[k] < mn[k]) mn[k] = l->position[k];
            if (l->position[k] > mx[k]) mx[k] = l->position[k];
        }
        any = 1;
    }
    for (int k = 0; k < 3; k++) {
        scene->bounds_min[k] = any ? mn[k] : 0.0f;
        scene->bounds_max[k] = any ? mx[k] : 0.0f;
    }
}

uint64_t bk_geometry_hash(const float *positions, size_t vertex_count, const uint32_t *indices,
                          size_t index_count)
{
    XXH3_state_t st;
    XXH3_INITSTATE(&st);
    XXH3_64bits_reset(&st);
    if (vertex_count) XXH3_64bits_update(&st, positions, vertex_count * 3 * sizeof(float));
    if (index_count) XXH3_64bits_update(&st, indices, index_count * sizeof(uint32_t));
    return XXH3_64bits_digest(&st);
}

static int rgb_positive(const float c[3])
{
    return c[0] > 0.0f || c[1] > 0.0f || c[2] > 0.0f;
}

int bk_scene_has_light(const bk_scene *scene)
{
    if (scene->sky_image >= 0 || rgb_positive(scene->sky)) return 1;
    for (size_t i = 0; i < scene->light_count; i++)
        if (rgb_positive(scene->lights[i].color)) return 1;
    for (size_t t = 0; t < scene->tri_count; t++) {
        uint32_t m = scene->tri_material[t];
        if (m < scene->material_count && rgb_positive(scene->materials[m].emission)) return 1;
    }
    return 0;
}

static int finite_n(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

int bk_scene_check(const bk_scene *s, char *err, size_t err_len)
{
#define FAIL(...) do { if (err && err_len) snprintf(err, err_len, __VA_ARGS__); return 1; } while (0)
    if (s->vertex_count && (!s->positions || !s->normals || !s->uv0 || !s->uv1))
        FAIL("scene has %zu vertices but a vertex array is missing", s->vertex_count);
    if (s->tri_count && (!s->tris || !s->tri_material || !s->tri_object))
        FAIL("scene has %zu triangles but a triangle array is missing", s->tri_count);
    for (size_t v = 0; v < s->vertex_count; v++) {
        if (!finite_n(s->positions + 3 * v, 3)) FAIL("vertex %zu: non-finite position", v);
        if (!finite_n(s->normals + 3 * v, 3)) FAIL("vertex %zu: non-finite normal", v);
        if (!finite_n(s->uv0 + 2 * v, 2) || !finite_n(s->uv1 + 2 * v, 2))
            FAIL("vertex %zu: non-finite uv", v);
        const float *n = s->normals + 3 * v;
        float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (fabsf(len - 1.0f) > 1e-3f) FAIL("vertex %zu: normal length %g, not unit", v, len);
        if (s->tangents && (!finite_n(s->tangents + 4 * v, 4) || fabsf(fabsf(s->tangents[4 * v + 3]) - 1.0f) > 0))
            FAIL("vertex %zu: tangent not finite or its sign not +-1", v);
    }
    for (size_t t = 0; t < s->tri_count; t++) {
        for (int k = 0; k < 3; k++)
            if (s->tris[3 * t + k] >= s->vertex_count)
                FAIL("triangle %zu: vertex index %u out of range (%zu vertices)", t,
                     s->tris[3 * t + k], s->vertex_count);
        if (s->tri_material[t] >= s->material_count)
            FAIL("triangle %zu: material %u out of range", t, s->tri_material[t]);
        if (s->tri_object[t] >= s->object_count)
            FAIL("triangle %zu: object %u out of range", t, s->tri_object[t]);
    }
    for (size_t i = 0; i < s->object_count; i++) {
        const bk_object *o = &s->objects[i];
        if ((size_t)o->first_tri + o->tri_count > s->tri_count)
            FAIL("object %zu (%s): triangle range out of bounds", i, o->name);
        for (uint32_t t = o->first_tri; t < o->first_tri + o->tri_count; t++)
            if (s->tri_object[t] != i) FAIL("object %zu (%s): triangle %u belongs to object %u", i,
                                             o->name, t, s->tri_object[t]);
        if (!(o->texel_density >= 0.0f) || !isfinite(o->texel_density))
            FAIL("object %zu (%s): bad texel density", i, o->name);
    }
    for (size_t i = 0; i < s->material_count; i++) {
        const bk_material *m = &s->materials[i];
        if (!finite_n(m->albedo, 3) || !finite_n(m->emission, 3))
            FAIL("material %zu (%s): non-finite colour", i, m->name);
        if ((m->albedo_tex >= 0 && (size_t)m->albedo_tex >= s->image_count) ||
            (m->emission_tex >= 0 && (size_t)m->emission_tex >= s->image_count))
            FAIL("material %zu (%s): texture index out of range", i, m->name);
        if (!(m->metallic >= 0 && m->metallic <= 1) || !(m->roughness >= 0 && m->roughness <= 1))
            FAIL("material %zu (%s): metallic and roughness must lie in [0, 1]", i, m->name);
        if (m->metal_rough_tex1 < 0 || (m->metal_rough_tex1 > 0 && (size_t)m->metal_rough_tex1 > s->image_count))
            FAIL("material %zu (%s): metallicRoughness texture index out of range", i, m->name);
    }
    for (size_t i = 0; i < s->light_count; i++) {
        const bk_light *l = &s->lights[i];
        if (!finite_n(l->color, 3) || !finite_n(l->position, 3) || !finite_n(l->direction, 3) ||
            !isfinite(l->range) || !isfinite(l->inner_cone) || !isfinite(l->outer_cone))
            FAIL("light %zu (%s): non-finite value", i, l->name);
        if (l->type < BK_LIGHT_POINT || l->type > BK_LIGHT_DIRECTIONAL)
            FAIL("light %zu (%s): unknown type %d", i, l->name, l->type);
    }
    for (size_t i = 0; i < s->image_count; i++) {
        const bk_image *im = &s->images[i];
        if (im->width <= 0 || im->height <= 0 || !im->rgba)
            FAIL("image %zu: empty (%dx%d)", i, im->width, im->height);
    }
    if (s->sky_image >= 0 && (size_t)s->sky_image >= s->image_count)
        FAIL("sky image %d out of range", s->sky_image);
    if (!finite_n(s->sky, 3)) FAIL("non-finite sky radiance");
    return 0;
#undef FAIL
}

/* ---- tangents ---------------------------------------------------------------------------- */

static void sub3d(const float a[3], const float b[3], double o[3])
{
    for (int k = 0; k < 3; k++) o[k] = (double)a[k] - (double)b[k];
}

static double dot3d(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross3d(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* Adds triangle t's +u and +v directions (dP/du, dP/dv, unit) to the sums of its corners whose
 * tangent is still open (w == 0), each weighted by the corner's angle (MikkTSpace's weight: a
 * vertex's frame does not depend on how its fan is split into triangles). acc holds 6 doubles
 * per open vertex (T sum, B sum) at the vertex's slot. */
static void accumulate_triangle(const bk_scene *s, size_t t, double *acc)
{
    const uint32_t *v = &s->tris[3 * t];
    double e1[3], e2[3], tu[3], tv[3];
    sub3d(&s->positions[3 * (size_t)v[1]], &s->positions[3 * (size_t)v[0]], e1);
    sub3d(&s->positions[3 * (size_t)v[2]], &s->positions[3 * (size_t)v[0]], e2);
    const float *a = &s->uv0[2 * (size_t)v[0]], *b = &s->uv0[2 * (size_t)v[1]], *c = &s->uv0[2 * (size_t)v[2]];
    const double du1 = (double)b[0] - a[0], dv1 = (double)b[1] - a[1], du2 = (double)c[0] - a[0], dv2 = (double)c[1] - a[1];
    const double det = du1 * dv2 - du2 * dv1;
    if (!(fabs(det) > 1e-20) || !isfinite(det)) return; /* uv0 spans no area: no direction */
    for (int k = 0; k < 3; k++) {
        tu[k] = (dv2 * e1[k] - dv1 * e2[k]) / det;
        tv[k] = (du1 * e2[k] - du2 * e1[k]) / det;
    }
    const double lu = sqrt(dot3d(tu, tu)), lv = sqrt(dot3d(tv, tv));
    if (!(lu > 0) || !(lv > 0) || !isfinite(lu) || !isfinite(lv)) return;
    for (int c3 = 0; c3 < 3; c3++) {
        const uint32_t vi = v[c3];
        if (s->tangents[4 * (size_t)vi + 3] != 0.0f) continue;
        double x[3], y[3];
        sub3d(&s->positions[3 * (size_t)v[(c3 + 1) % 3]], &s->positions[3 * (size_t)vi], x);
        sub3d(&s->positions[3 * (size_t)v[(c3 + 2) % 3]], &s->positions[3 * (size_t)vi], y);
        const double lx = sqrt(dot3d(x, x)), ly = sqrt(dot3d(y, y));
        if (!(lx > 0) || !(ly > 0)) continue;
        const double angle = acos(fmax(-1.0, fmin(1.0, dot3d(x, y) / (lx * ly))));
        double *dst = &acc[6 * (size_t)vi];
        for (int k = 0; k < 3; k++) dst[k] += angle * tu[k] / lu, dst[3 + k] += angle * tv[k] / lv;
    }
}

/* The tangent of open vertex vi from its sums: T made orthogonal to N; w such that B = w·(N × T)
 * points along −dP/dv, the normal map's +Y (glTF: +Y is up in the image, and uv (0, 0) is its
 * top left corner, so up is −v). */
static void finish_tangent(bk_scene *s, size_t vi, const double sums[6])
{
    const float *nf = &s->normals[3 * vi];
    const double n[3] = {nf[0], nf[1], nf[2]};
    double t[3] = {sums[0], sums[1], sums[2]}, b[3] = {sums[3], sums[4], sums[5]}, nt[3];
    const double d = dot3d(t, n);
    for (int k = 0; k < 3; k++) t[k] -= d * n[k];
    double l = sqrt(dot3d(t, t));
    if (!(l > 1e-12) || !isfinite(l)) { /* no usable triangle: any direction in the plane */
        const double ax[3] = {fabs(n[0]) < 0.9 ? 1.0 : 0.0, fabs(n[0]) < 0.9 ? 0.0 : 1.0, 0.0};
        const double e = dot3d(ax, n);
        for (int k = 0; k < 3; k++) t[k] = ax[k] - e * n[k];
        l = sqrt(dot3d(t, t));
    }
    cross3d(n, t, nt);
    float *out = &s->tangents[4 * vi];
    for (int k = 0; k < 3; k++) out[k] = (float)(t[k] / l);
    out[3] = dot3d(nt, b) > 0.0 ? -1.0f : 1.0f; /* B = w·(N × T) is the image's up: −v */
}

int bk_scene_derive_tangents(bk_scene *s)
{
    if (!s->tangents || !s->vertex_count) return 0;
    double *acc = calloc(s->vertex_count, 6 * sizeof *acc);
    if (!acc) return -1;
    for (size_t t = 0; t < s->tri_count; t++) accumulate_triangle(s, t, acc);
    for (size_t v = 0; v < s->vertex_count; v++)
        if (s->tangents[4 * v + 3] == 0.0f) finish_tangent(s, v, &acc[6 * v]);
    free(acc);
    return 0;
}
