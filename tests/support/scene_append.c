#include "scene_append.h"

#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Called once per appended element: reallocating every time made building a 60k-triangle scene
 * quadratic under ASan (minutes). The block only moves when it is full, to twice the size. */
void *sa_grow(void *p, size_t count, size_t elem)
{
    if (p && malloc_usable_size(p) >= count * elem) return p;
    size_t cap = 16;
    while (cap < count) cap *= 2;
    void *q = realloc(p, cap * elem);
    if (!q) abort();
    return q;
}

uint32_t sa_vertex(bk_scene *s, const float p[3], const float n[3])
{
    size_t i = s->vertex_count;
    s->positions = sa_grow(s->positions, 3 * (i + 1), sizeof(float));
    s->normals = sa_grow(s->normals, 3 * (i + 1), sizeof(float));
    s->uv0 = sa_grow(s->uv0, 2 * (i + 1), sizeof(float));
    s->uv1 = sa_grow(s->uv1, 2 * (i + 1), sizeof(float));
    memcpy(s->positions + 3 * i, p, 3 * sizeof(float));
    memcpy(s->normals + 3 * i, n, 3 * sizeof(float));
    s->uv0[2 * i] = s->uv0[2 * i + 1] = 0;
    s->uv1[2 * i] = s->uv1[2 * i + 1] = 0;
    s->vertex_count++;
    return (uint32_t)i;
}

void sa_tri(bk_scene *s, uint32_t a, uint32_t b, uint32_t c, uint32_t material)
{
    size_t t = s->tri_count;
    s->tris = sa_grow(s->tris, 3 * (t + 1), sizeof(uint32_t));
    s->tri_material = sa_grow(s->tri_material, t + 1, sizeof(uint32_t));
    s->tri_object = sa_grow(s->tri_object, t + 1, sizeof(uint32_t));
    s->tris[3 * t] = a;
    s->tris[3 * t + 1] = b;
    s->tris[3 * t + 2] = c;
    s->tri_material[t] = material;
    s->tri_object[t] = (uint32_t)s->object_count - 1;
    s->objects[s->object_count - 1].tri_count++;
    s->tri_count++;
}

bk_object *sa_object(bk_scene *s, const char *name)
{
    s->objects = sa_grow(s->objects, s->object_count + 1, sizeof *s->objects);
    bk_object *o = &s->objects[s->object_count++];
    memset(o, 0, sizeof *o);
    snprintf(o->name, sizeof o->name, "%s", name);
    o->first_tri = (uint32_t)s->tri_count;
    for (int i = 0; i < 16; i++) o->local_to_world[i] = (i % 5 == 0) ? 1.0f : 0.0f;
    return o;
}

void sa_box_corners(const float mn[3], const float mx[3], float c[8][3])
{
    for (int i = 0; i < 8; i++) {
        c[i][0] = (i & 1) ? mx[0] : mn[0];
        c[i][1] = (i & 2) ? mx[1] : mn[1];
        c[i][2] = (i & 4) ? mx[2] : mn[2];
    }
}

const int sa_box_faces[6][4] = {
    {0, 4, 6, 2}, /* -x */ {1, 3, 7, 5}, /* +x */ {0, 1, 5, 4}, /* -y */
    {2, 6, 7, 3}, /* +y */ {0, 2, 3, 1}, /* -z */ {4, 5, 7, 6}, /* +z */
};

void sa_vertex_bounds(bk_scene *s)
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
