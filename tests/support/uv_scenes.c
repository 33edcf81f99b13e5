#include "uv_scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *uvs_grow(void *p, size_t count, size_t elem)
{
    size_t cap = 16;
    while (cap < count) cap *= 2;
    void *q = realloc(p, cap * elem);
    if (!q) abort();
    return q;
}

void uvs_init(bk_scene *s)
{
    memset(s, 0, sizeof *s);
    s->sky_image = -1;
    uvs_material(s, 0.5f, 0.0f);
}

void uvs_free(bk_scene *s)
{
    free(s->positions); free(s->normals); free(s->uv0); free(s->uv1);
    free(s->tris); free(s->tri_material); free(s->tri_object);
    free(s->materials); free(s->objects); free(s->lights);
    for (size_t i = 0; i < s->image_count; i++) free(s->images[i].rgba);
    free(s->images);
    memset(s, 0, sizeof *s);
}

uint32_t uvs_material(bk_scene *s, float albedo, float emission)
{
    s->materials = uvs_grow(s->materials, s->material_count + 1, sizeof *s->materials);
    bk_material *m = &s->materials[s->material_count];
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "uvs%zu", s->material_count);
    for (int k = 0; k < 3; k++) {
        m->albedo[k] = albedo;
        m->emission[k] = emission;
    }
    m->albedo_tex = m->emission_tex = -1;
    return (uint32_t)s->material_count++;
}

uint32_t uvs_object(bk_scene *s, const char *name)
{
    s->objects = uvs_grow(s->objects, s->object_count + 1, sizeof *s->objects);
    bk_object *o = &s->objects[s->object_count];
    memset(o, 0, sizeof *o);
    snprintf(o->name, sizeof o->name, "%s", name);
    o->first_tri = (uint32_t)s->tri_count;
    for (int i = 0; i < 16; i++) o->local_to_world[i] = (i % 5 == 0) ? 1.0f : 0.0f;
    return (uint32_t)s->object_count++;
}

uint32_t uvs_vertex(bk_scene *s, const float p[3], const float n[3])
{
    size_t i = s->vertex_count;
    s->positions = uvs_grow(s->positions, 3 * (i + 1), sizeof(float));
    s->normals = uvs_grow(s->normals, 3 * (i + 1), sizeof(float));
    s->uv0 = uvs_grow(s->uv0, 2 * (i + 1), sizeof(float));
    s->uv1 = uvs_grow(s->uv1, 2 * (i + 1), sizeof(float));
    memcpy(s->positions + 3 * i, p, 3 * sizeof(float));
    memcpy(s->normals + 3 * i, n, 3 * sizeof(float));
    s->uv0[2 * i] = s->uv0[2 * i + 1] = 0;
    s->uv1[2 * i] = s->uv1[2 * i + 1] = 0;
    s->vertex_count++;
    return (uint32_t)i;
}

void uvs_tri_idx(bk_scene *s, uint32_t a, uint32_t b, uint32_t c, uint32_t material)
{
    if (s->object_count == 0) uvs_object(s, "uvs");
    size_t t = s->tri_count;
    s->tris = uvs_grow(s->tris, 3 * (t + 1), sizeof(uint32_t));
    s->tri_material = uvs_grow(s->tri_material, t + 1, sizeof(uint32_t));
    s->tri_object = uvs_grow(s->tri_object, t + 1, sizeof(uint32_t));
    s->tris[3 * t] = a;
    s->tris[3 * t + 1] = b;
    s->tris[3 * t + 2] = c;
    s->tri_material[t] = material;
    s->tri_object[t] = (uint32_t)s->object_count - 1;
    s->objects[s->object_count - 1].tri_count++;
    s->tri_count++;
}

static void face_normal(const float a[3], const float b[3], const float c[3], float n[3])
{
    double e1[3], e2[3], m[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
    }
    m[0] = e1[1] * e2[2] - e1[2] * e2[1];
    m[1] = e1[2] * e2[0] - e1[0] * e2[2];
    m[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    for (int k = 0; k < 3; k++) n[k] = l > 0 ? (float)(m[k] / l) : 0.0f;
}

void uvs_tri(bk_scene *s, const float a[3], const float b[3], const float c[3], uint32_t material)
{
    float n[3];
    face_normal(a, b, c, n);
    uint32_t i0 = uvs_vertex(s, a, n), i1 = uvs_vertex(s, b, n), i2 = uvs_vertex(s, c, n);
    uvs_tri_idx(s, i0, i1, i2, material);
}

uint32_t uvs_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n,
                  uint32_t material, const float uv1_origin[2], float uv1_size)
{
    float nrm[3];
    face_normal(p0, p1, p2, nrm);
    uint32_t first = (uint32_t)s->vertex_count;
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            double u = (double)i / n, v = (double)j / n;
            float p[3];
            for (int k = 0; k < 3; k++)
                p[k] = (float)((1 - u) * (1 - v) * p0[k] + u * (1 - v) * p1[k] + u * v * p2[k] + (1 - u) * v * p3[k]);
            uint32_t id = uvs_vertex(s, p, nrm);
            float o0 = uv1_origin ? uv1_origin[0] : 0.0f, o1 = uv1_origin ? uv1_origin[1] : 0.0f;
            s->uv1[2 * id] = o0 + (float)u * uv1_size;
            s->uv1[2 * id + 1] = o1 + (float)v * uv1_size;
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = first + (uint32_t)(j * (n + 1) + i), b = a + 1, d = a + (uint32_t)(n + 1), c = d + 1;
            uvs_tri_idx(s, a, b, c, material);
            uvs_tri_idx(s, a, c, d, material);
        }
    return first;
}

void uvs_box(bk_scene *s, const float mn[3], const float mx[3], int n, int inward, uint32_t material)
{
    /* corners: bit 0 → x, bit 1 → y, bit 2 → z */
    float c[8][3];
    for (int i = 0; i < 8; i++) {
        c[i][0] = (i & 1) ? mx[0] : mn[0];
        c[i][1] = (i & 2) ? mx[1] : mn[1];
        c[i][2] = (i & 4) ? mx[2] : mn[2];
    }
    /* outward counter-clockwise faces */
    static const int f[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (int i = 0; i < 6; i++) {
        if (inward)
            uvs_quad(s, c[f[i][0]], c[f[i][3]], c[f[i][2]], c[f[i][1]], n, material, NULL, 1.0f);
        else
            uvs_quad(s, c[f[i][0]], c[f[i][1]], c[f[i][2]], c[f[i][3]], n, material, NULL, 1.0f);
    }
}

void uvs_sphere(bk_scene *s, const float c[3], float r, int segments, int rings, uint32_t material)
{
    const double pi = 3.14159265358979323846;
    uint32_t first = (uint32_t)s->vertex_count;
    float up[3] = {0, 1, 0}, down[3] = {0, -1, 0};
    float top[3] = {c[0], c[1] + r, c[2]}, bot[3] = {c[0], c[1] - r, c[2]};
    uint32_t vt = uvs_vertex(s, top, up);
    for (int j = 1; j < rings; j++) {
        double th = pi * j / rings;
        for (int i = 0; i < segments; i++) {
            double ph = 2 * pi * i / segments;
            float n[3] = {(float)(sin(th) * cos(ph)), (float)cos(th), (float)(sin(th) * sin(ph))};
            float p[3] = {c[0] + r * n[0], c[1] + r * n[1], c[2] + r * n[2]};
            uvs_vertex(s, p, n);
        }
    }
    uint32_t vb = uvs_vertex(s, bot, down);
    (void)first;
#define RING(j, i) (vt + 1 + (uint32_t)((j) - 1) * (uint32_t)segments + (uint32_t)((i) % segments))
    for (int i = 0; i < segments; i++) uvs_tri_idx(s, vt, RING(1, i + 1), RING(1, i), material);
    for (int j = 1; j + 1 < rings; j++)
        for (int i = 0; i < segments; i++) {
            uvs_tri_idx(s, RING(j, i), RING(j, i + 1), RING(j + 1, i + 1), material);
            uvs_tri_idx(s, RING(j, i), RING(j + 1, i + 1), RING(j + 1, i), material);
        }
    for (int i = 0; i < segments; i++) uvs_tri_idx(s, vb, RING(rings - 1, i), RING(rings - 1, i + 1), material);
#undef RING
}

void uvs_update_bounds(bk_scene *s)
{
    for (int k = 0; k < 3; k++) {
        s->bounds_min[k] = INFINITY;
        s->bounds_max[k] = -INFINITY;
    }
    for (size_t v = 0; v < s->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            float x = s->positions[3 * v + (size_t)k];
            if (x < s->bounds_min[k]) s->bounds_min[k] = x;
            if (x > s->bounds_max[k]) s->bounds_max[k] = x;
        }
}
