#include "transport_scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_append.h"

void tsc_init(bk_scene *s)
{
    memset(s, 0, sizeof *s);
    s->sky_image = -1;
    tsc_object(s, "tsc", "", "");
}

void tsc_free(bk_scene *s) { bk_scene_free(s); }

uint32_t tsc_material(bk_scene *s, float ar, float ag, float ab, float er, float eg, float eb)
{
    s->materials = sa_grow(s->materials, s->material_count + 1, sizeof *s->materials);
    bk_material *m = &s->materials[s->material_count];
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "m%zu", s->material_count);
    m->albedo[0] = ar; m->albedo[1] = ag; m->albedo[2] = ab;
    m->emission[0] = er; m->emission[1] = eg; m->emission[2] = eb;
    m->albedo_tex = m->emission_tex = -1;
    m->double_sided = 1;
    return (uint32_t)s->material_count++;
}

uint32_t tsc_object(bk_scene *s, const char *name, const char *light_set, const char *door)
{
    bk_object *o = sa_object(s, name);
    snprintf(o->light_set, sizeof o->light_set, "%s", light_set ? light_set : "");
    snprintf(o->door, sizeof o->door, "%s", door ? door : "");
    return (uint32_t)s->object_count - 1;
}

void tsc_tri(bk_scene *s, const float a[3], const float b[3], const float c[3], uint32_t material)
{
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; k++) { e1[k] = (double)b[k] - a[k]; e2[k] = (double)c[k] - a[k]; }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    float nf[3] = {0, 0, 1};
    if (l > 0) for (int k = 0; k < 3; k++) nf[k] = (float)(n[k] / l);
    uint32_t ia = sa_vertex(s, a, nf), ib = sa_vertex(s, b, nf), ic = sa_vertex(s, c, nf);
    sa_tri(s, ia, ib, ic, material);
}

static void lerp_quad(const float p0[3], const float p1[3], const float p2[3], const float p3[3], double u, double v,
                      float out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = (float)((1 - u) * (1 - v) * p0[k] + u * (1 - v) * p1[k] + u * v * p2[k] + (1 - u) * v * p3[k]);
}

void tsc_quad(bk_scene *s, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n,
              uint32_t material)
{
    if (n < 1) n = 1;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            float a[3], b[3], c[3], d[3];
            lerp_quad(p0, p1, p2, p3, (double)i / n, (double)j / n, a);
            lerp_quad(p0, p1, p2, p3, (double)(i + 1) / n, (double)j / n, b);
            lerp_quad(p0, p1, p2, p3, (double)(i + 1) / n, (double)(j + 1) / n, c);
            lerp_quad(p0, p1, p2, p3, (double)i / n, (double)(j + 1) / n, d);
            tsc_tri(s, a, b, c, material);
            tsc_tri(s, a, c, d, material);
        }
}

void tsc_box(bk_scene *s, const float mn[3], const float mx[3], int n, int inward, uint32_t material)
{
    float c[8][3];
    sa_box_corners(mn, mx, c);
    const int(*f)[4] = sa_box_faces;
    for (int i = 0; i < 6; i++) {
        if (inward)
            tsc_quad(s, c[f[i][0]], c[f[i][3]], c[f[i][2]], c[f[i][1]], n, material);
        else
            tsc_quad(s, c[f[i][0]], c[f[i][1]], c[f[i][2]], c[f[i][3]], n, material);
    }
}

static bk_light *new_light(bk_scene *s)
{
    s->lights = sa_grow(s->lights, s->light_count + 1, sizeof *s->lights);
    bk_light *l = &s->lights[s->light_count];
    memset(l, 0, sizeof *l);
    snprintf(l->name, sizeof l->name, "l%zu", s->light_count);
    s->light_count++;
    return l;
}

uint32_t tsc_point_light(bk_scene *s, const float pos[3], float r, float g, float b, float range)
{
    bk_light *l = new_light(s);
    l->type = BK_LIGHT_POINT;
    l->color[0] = r; l->color[1] = g; l->color[2] = b;
    memcpy(l->position, pos, sizeof l->position);
    l->direction[2] = -1;
    l->range = range;
    return (uint32_t)(s->light_count - 1);
}

uint32_t tsc_spot_light(bk_scene *s, const float pos[3], const float dir[3], float intensity, float inner, float outer)
{
    bk_light *l = new_light(s);
    l->type = BK_LIGHT_SPOT;
    l->color[0] = l->color[1] = l->color[2] = intensity;
    memcpy(l->position, pos, sizeof l->position);
    memcpy(l->direction, dir, sizeof l->direction);
    l->inner_cone = inner;
    l->outer_cone = outer;
    return (uint32_t)(s->light_count - 1);
}

uint32_t tsc_dir_light(bk_scene *s, const float dir[3], float lux)
{
    bk_light *l = new_light(s);
    l->type = BK_LIGHT_DIRECTIONAL;
    l->color[0] = l->color[1] = l->color[2] = lux;
    memcpy(l->direction, dir, sizeof l->direction);
    return (uint32_t)(s->light_count - 1);
}

void tsc_ceiling_lamp_room(bk_scene *s, float wall, float lamp, float le, float x0, float x1, float z0, float z1)
{
    tsc_init(s);
    uint32_t grey = tsc_material(s, wall, wall, wall, 0, 0, 0);
    uint32_t light = tsc_material(s, lamp, lamp, lamp, le, le, le);
    const float mn[3] = {-1, 0, -1}, mx[3] = {1, 2, 1};
    tsc_box(s, mn, mx, 1, 1, grey);
    const float y = 1.99f;
    float q0[3] = {x0, y, z0}, q1[3] = {x1, y, z0}, q2[3] = {x1, y, z1}, q3[3] = {x0, y, z1};
    tsc_quad(s, q0, q1, q2, q3, 1, light); /* faces down */
    tsc_update_bounds(s);
}

void tsc_lamp_room(bk_scene *s) { tsc_ceiling_lamp_room(s, 0.5f, 0.5f, 4, -0.35f, 0.65f, -0.35f, 0.65f); }

void tsc_lamp_room_receivers(bk_receiver r[TSC_LAMP_ROOM_RECEIVERS])
{
    memset(r, 0, sizeof *r * TSC_LAMP_ROOM_RECEIVERS);
    for (int i = 0; i < TSC_LAMP_ROOM_RECEIVERS; i++) {
        float u = -0.75f + 0.5f * (float)(i % 4), v = -0.75f + 0.5f * (float)((i / 4) % 4);
        float *pp = r[i].position, *nn = r[i].normal;
        if (i < 16) { pp[0] = u; pp[1] = 0; pp[2] = v; nn[1] = 1; }
        else { pp[0] = -1; pp[1] = 0.3f + 0.2f * (float)(i - 16); pp[2] = 0.1f; nn[0] = 1; }
    }
}

void tsc_update_bounds(bk_scene *s)
{
    sa_vertex_bounds(s);
    if (s->vertex_count == 0)
        for (int k = 0; k < 3; k++) s->bounds_min[k] = s->bounds_max[k] = 0;
}

void tsc_transform(bk_scene *s, double scale, const double offset[3])
{
    for (size_t i = 0; i < s->vertex_count; i++)
        for (int k = 0; k < 3; k++)
            s->positions[3 * i + k] = (float)((double)s->positions[3 * i + k] * scale + offset[k]);
    for (size_t i = 0; i < s->light_count; i++) {
        for (int k = 0; k < 3; k++)
            s->lights[i].position[k] = (float)((double)s->lights[i].position[k] * scale + offset[k]);
        s->lights[i].range = (float)(s->lights[i].range * scale);
    }
    tsc_update_bounds(s);
}

static void rot3(const double m[3][3], float v[3])
{
    double r[3];
    for (int i = 0; i < 3; i++) r[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    for (int i = 0; i < 3; i++) v[i] = (float)r[i];
}

void tsc_rotate(bk_scene *s, double ax, double ay, double az)
{
    double cx = cos(ax), sx = sin(ax), cy = cos(ay), sy = sin(ay), cz = cos(az), sz = sin(az);
    double rx[3][3] = {{1, 0, 0}, {0, cx, -sx}, {0, sx, cx}};
    double ry[3][3] = {{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}};
    double rz[3][3] = {{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}};
    double t[3][3], m[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) t[i][j] = ry[i][0] * rx[0][j] + ry[i][1] * rx[1][j] + ry[i][2] * rx[2][j];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) m[i][j] = rz[i][0] * t[0][j] + rz[i][1] * t[1][j] + rz[i][2] * t[2][j];
    for (size_t i = 0; i < s->vertex_count; i++) {
        rot3(m, s->positions + 3 * i);
        rot3(m, s->normals + 3 * i);
    }
    for (size_t i = 0; i < s->light_count; i++) {
        rot3(m, s->lights[i].position);
        rot3(m, s->lights[i].direction);
    }
    tsc_update_bounds(s);
}

bk_transport_options tsc_fixed_passes(int passes, uint64_t seed)
{
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.seed = seed;
    o.threads = 2;
    o.target_error = -1;
    o.first_pass_samples = 16;
    o.max_samples = 2 * 16 * ((1 << passes) - 1);
    o.max_cells = 512;
    return o;
}
