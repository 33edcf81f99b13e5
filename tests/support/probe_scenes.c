#include "tests/support/probe_scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_append.h"

void psc_init(bk_scene *s)
{
    memset(s, 0, sizeof *s);
    s->sky_image = -1;
    s->material_count = 1;
    s->materials = calloc(1, sizeof *s->materials);
    if (!s->materials) abort();
    snprintf(s->materials[0].name, sizeof s->materials[0].name, "grey");
    for (int k = 0; k < 3; k++) s->materials[0].albedo[k] = 0.5f;
    s->materials[0].albedo_tex = s->materials[0].emission_tex = -1;
    psc_object(s, "psc", BK_LIGHTING_AUTO);
}

void psc_free(bk_scene *s) { bk_scene_free(s); }

uint32_t psc_object(bk_scene *s, const char *name, int lighting)
{
    sa_object(s, name)->lighting = lighting;
    return (uint32_t)s->object_count - 1;
}

static uint32_t vertex(bk_scene *s, const float p[3], const float n[3]) { return sa_vertex(s, p, n); }

static void tri_idx(bk_scene *s, uint32_t a, uint32_t b, uint32_t c) { sa_tri(s, a, b, c, 0); }

static void face_normal(const float a[3], const float b[3], const float c[3], float n[3])
{
    float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1]; n[1] = u[2] * v[0] - u[0] * v[2]; n[2] = u[0] * v[1] - u[1] * v[0];
    float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (l > 0) for (int k = 0; k < 3; k++) n[k] /= l;
}

void psc_tri(bk_scene *s, const float a[3], const float b[3], const float c[3])
{
    float n[3];
    face_normal(a, b, c, n);
    uint32_t ia = vertex(s, a, n), ib = vertex(s, b, n), ic = vertex(s, c, n);
    tri_idx(s, ia, ib, ic);
}

void psc_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n)
{
    float nrm[3];
    face_normal(p0, p1, p2, nrm);
    uint32_t base = (uint32_t)s->vertex_count;
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            float u = (float)i / n, v = (float)j / n, p[3];
            for (int k = 0; k < 3; k++)
                p[k] = (1 - u) * (1 - v) * p0[k] + u * (1 - v) * p1[k] + u * v * p2[k] + (1 - u) * v * p3[k];
            vertex(s, p, nrm);
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = base + (uint32_t)(j * (n + 1) + i), b = a + 1, d = a + (uint32_t)(n + 1), c = d + 1;
            tri_idx(s, a, b, c);
            tri_idx(s, a, c, d);
        }
}

void psc_box(bk_scene *s, const float mn[3], const float mx[3], int n, int inward)
{
    float c[8][3];
    sa_box_corners(mn, mx, c);
    const int(*f)[4] = sa_box_faces;
    for (int i = 0; i < 6; i++) {
        if (inward) psc_quad(s, c[f[i][3]], c[f[i][2]], c[f[i][1]], c[f[i][0]], n);
        else psc_quad(s, c[f[i][0]], c[f[i][1]], c[f[i][2]], c[f[i][3]], n);
    }
}

void psc_sphere(bk_scene *s, const float centre[3], float radius, int stacks, int slices)
{
    uint32_t base = (uint32_t)s->vertex_count;
    for (int i = 0; i <= stacks; i++)
        for (int j = 0; j < slices; j++) {
            double th = M_PI * i / stacks, ph = 2.0 * M_PI * j / slices;
            float n[3] = {(float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th)};
            float p[3] = {centre[0] + radius * n[0], centre[1] + radius * n[1], centre[2] + radius * n[2]};
            vertex(s, p, n);   /* poles repeat (zero-area triangles are skipped) */
        }
    for (int i = 0; i < stacks; i++)
        for (int j = 0; j < slices; j++) {
            uint32_t a = base + (uint32_t)(i * slices + j), b = base + (uint32_t)(i * slices + (j + 1) % slices);
            uint32_t c = a + (uint32_t)slices, d = b + (uint32_t)slices;
            if (i > 0) tri_idx(s, a, c, b);
            if (i < stacks - 1) tri_idx(s, b, c, d);
        }
}

void psc_rotate_tris(bk_scene *s, uint32_t first_tri, const double q[4], const float pivot[3])
{
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                      {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                      {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    uint32_t vmin = UINT32_MAX, vmax = 0;
    for (size_t t = first_tri; t < s->tri_count; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = s->tris[3 * t + (size_t)k];
            if (v < vmin) vmin = v;
            if (v > vmax) vmax = v;
        }
    for (uint32_t v = vmin; v <= vmax && vmin != UINT32_MAX; v++) {
        float *p = s->positions + 3 * (size_t)v, *n = s->normals + 3 * (size_t)v;
        double d[3] = {p[0] - pivot[0], p[1] - pivot[1], p[2] - pivot[2]}, m[3] = {n[0], n[1], n[2]};
        for (int r = 0; r < 3; r++) {
            p[r] = (float)(pivot[r] + R[r][0] * d[0] + R[r][1] * d[1] + R[r][2] * d[2]);
            n[r] = (float)(R[r][0] * m[0] + R[r][1] * m[1] + R[r][2] * m[2]);
        }
    }
}

void psc_update_bounds(bk_scene *s) { sa_vertex_bounds(s); }
