#include "scene_builders.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *must_realloc(void *p, size_t n, size_t elem)
{
    void *q = realloc(p, (n ? n : 1) * elem);
    if (!q) abort();
    return q;
}

static void begin(bk_scene *s, const char *object_name, float albedo, float emission)
{
    memset(s, 0, sizeof *s);
    s->sky_image = -1;
    s->materials = must_realloc(NULL, 1, sizeof *s->materials);
    memset(s->materials, 0, sizeof *s->materials);
    snprintf(s->materials[0].name, sizeof s->materials[0].name, "sb_material");
    for (int k = 0; k < 3; k++) {
        s->materials[0].albedo[k] = albedo;
        s->materials[0].emission[k] = emission;
    }
    s->materials[0].albedo_tex = s->materials[0].emission_tex = -1;
    s->materials[0].double_sided = 1;
    s->material_count = 1;
    s->objects = must_realloc(NULL, 1, sizeof *s->objects);
    memset(s->objects, 0, sizeof *s->objects);
    snprintf(s->objects[0].name, sizeof s->objects[0].name, "%s", object_name);
    for (int i = 0; i < 4; i++) s->objects[0].local_to_world[i * 5] = 1.0f;
    s->object_count = 1;
}

static void finish(bk_scene *s)
{
    /* geometry hash of object 0: world = local here */
    s->objects[0].first_tri = 0;
    s->objects[0].tri_count = (uint32_t)s->tri_count;
    s->objects[0].geometry_hash = bk_geometry_hash(s->positions, s->vertex_count, s->tris, s->tri_count * 3);
    bk_scene_compute_bounds(s);
}

void sb_add_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n,
                 uint32_t material, uint32_t object)
{
    if (n < 1) n = 1;
    size_t nv = (size_t)(n + 1) * (size_t)(n + 1), nt = 2 * (size_t)n * (size_t)n;
    size_t v0 = s->vertex_count, t0 = s->tri_count;
    s->positions = must_realloc(s->positions, (v0 + nv) * 3, sizeof(float));
    s->normals = must_realloc(s->normals, (v0 + nv) * 3, sizeof(float));
    s->uv0 = must_realloc(s->uv0, (v0 + nv) * 2, sizeof(float));
    s->uv1 = must_realloc(s->uv1, (v0 + nv) * 2, sizeof(float));
    s->tris = must_realloc(s->tris, (t0 + nt) * 3, sizeof(uint32_t));
    s->tri_material = must_realloc(s->tri_material, t0 + nt, sizeof(uint32_t));
    s->tri_object = must_realloc(s->tri_object, t0 + nt, sizeof(uint32_t));
    double e1[3], e2[3], fn[3];
    for (int k = 0; k < 3; k++) { e1[k] = p1[k] - p0[k]; e2[k] = p3[k] - p0[k]; }
    fn[0] = e1[1] * e2[2] - e1[2] * e2[1];
    fn[1] = e1[2] * e2[0] - e1[0] * e2[2];
    fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l = sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
    for (int k = 0; k < 3; k++) fn[k] = l > 0 ? fn[k] / l : (k == 1);
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            double u = (double)i / n, v = (double)j / n;
            size_t vi = v0 + (size_t)j * (size_t)(n + 1) + (size_t)i;
            for (int k = 0; k < 3; k++) {
                /* bilinear over the four corners */
                double x = (1 - u) * (1 - v) * p0[k] + u * (1 - v) * p1[k] + u * v * p2[k] + (1 - u) * v * p3[k];
                s->positions[vi * 3 + k] = (float)x;
                s->normals[vi * 3 + k] = (float)fn[k];
            }
            s->uv0[vi * 2] = s->uv1[vi * 2] = (float)u;
            s->uv0[vi * 2 + 1] = s->uv1[vi * 2 + 1] = (float)v;
        }
    size_t t = t0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(v0 + (size_t)j * (size_t)(n + 1) + (size_t)i), b = a + 1,
                     c = a + (uint32_t)(n + 1) + 1, d = a + (uint32_t)(n + 1);
            uint32_t q[6] = {a, b, c, a, c, d};
            for (int h = 0; h < 2; h++, t++) {
                memcpy(&s->tris[t * 3], &q[h * 3], 3 * sizeof(uint32_t));
                s->tri_material[t] = material;
                s->tri_object[t] = object;
            }
        }
    s->vertex_count = v0 + nv;
    s->tri_count = t0 + nt;
}

void sb_closed_box(bk_scene *s, float size, float albedo, float emission, int n)
{
    begin(s, "sb_closed_box", albedo, emission);
    float h = size / 2;
    /* corners named by sign: inward-facing faces (counter-clockwise seen from inside) */
    float P[8][3];
    for (int i = 0; i < 8; i++) {
        P[i][0] = (i & 1) ? h : -h;
        P[i][1] = (i & 2) ? h : -h;
        P[i][2] = (i & 4) ? h : -h;
    }
    static const int faces[6][4] = {
        {0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6},
    };
    for (int f = 0; f < 6; f++) {
        const float *a = P[faces[f][0]], *b = P[faces[f][1]], *c = P[faces[f][2]], *d = P[faces[f][3]];
        /* orient each face so its normal (b - a) × (d - a) points at the centre */
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        float nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2], nz = e1[0] * e2[1] - e1[1] * e2[0];
        if (nx * -a[0] + ny * -a[1] + nz * -a[2] < 0) sb_add_quad(s, a, d, c, b, n, 0, 0);
        else sb_add_quad(s, a, b, c, d, n, 0, 0);
    }
    finish(s);
}

void sb_plane_point_light(bk_scene *s, float half, float height, float candela, float albedo, int n)
{
    begin(s, "sb_floor", albedo, 0.0f);
    float p0[3] = {-half, 0, half}, p1[3] = {half, 0, half}, p2[3] = {half, 0, -half}, p3[3] = {-half, 0, -half};
    sb_add_quad(s, p0, p1, p2, p3, n, 0, 0);
    s->lights = must_realloc(NULL, 1, sizeof *s->lights);
    memset(s->lights, 0, sizeof *s->lights);
    snprintf(s->lights[0].name, sizeof s->lights[0].name, "sb_point");
    s->lights[0].type = BK_LIGHT_POINT;
    s->lights[0].color[0] = s->lights[0].color[1] = s->lights[0].color[2] = candela;
    s->lights[0].position[1] = height;
    s->lights[0].direction[1] = -1.0f;
    s->light_count = 1;
    finish(s);
}
