#include "uv_scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_append.h"

void uvs_init(bk_scene *s)
{
    memset(s, 0, sizeof *s);
    s->sky_image = -1;
    uvs_material(s, 0.5f, 0.0f);
}

void uvs_free(bk_scene *s) { bk_scene_free(s); }

uint32_t uvs_material(bk_scene *s, float albedo, float emission)
{
    s->materials = sa_grow(s->materials, s->material_count + 1, sizeof *s->materials);
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
    sa_object(s, name);
    return (uint32_t)s->object_count - 1;
}

uint32_t uvs_vertex(bk_scene *s, const float p[3], const float n[3]) { return sa_vertex(s, p, n); }

void uvs_tri_idx(bk_scene *s, uint32_t a, uint32_t b, uint32_t c, uint32_t material)
{
    if (s->object_count == 0) uvs_object(s, "uvs");
    sa_tri(s, a, b, c, material);
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
    float c[8][3];
    sa_box_corners(mn, mx, c);
    const int(*f)[4] = sa_box_faces;
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

void uvs_update_bounds(bk_scene *s) { sa_vertex_bounds(s); }
