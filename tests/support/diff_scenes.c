/* The two rooms of diff_scenes.h: 4 m × 2 m × 4 m each, 4 m apart along x. */
#include "support/diff_scenes.h"

#include <stdlib.h>
#include <string.h>

enum { QUAD_VERTICES = 4, QUAD_INDICES = 6 };

typedef struct quad {
    const char *name;
    float c[3], u[3], v[3]; /* centre and half axes; the face looks along u × v */
} quad;

/* Room A at x 0..4 (no ceiling), room B at x 8..12; y 0..2, z 0..4. */
static const quad quads[DS_OBJECTS] = {
    {"A_floor", {2, 0, 2}, {0, 0, 2}, {2, 0, 0}},
    {"A_wall_west", {0, 1, 2}, {0, 1, 0}, {0, 0, 2}},
    {"A_wall_east", {4, 1, 2}, {0, 0, 2}, {0, 1, 0}},
    {"A_wall_north", {2, 1, 0}, {2, 0, 0}, {0, 1, 0}},
    {"A_wall_south", {2, 1, 4}, {0, 1, 0}, {2, 0, 0}},
    {"B_floor", {10, 0, 2}, {0, 0, 2}, {2, 0, 0}},
    {"B_ceiling", {10, 2, 2}, {2, 0, 0}, {0, 0, 2}},
    {"B_wall_west", {8, 1, 2}, {0, 1, 0}, {0, 0, 2}},
    {"B_wall_east", {12, 1, 2}, {0, 0, 2}, {0, 1, 0}},
    {"B_wall_north", {10, 1, 0}, {2, 0, 0}, {0, 1, 0}},
    {"B_wall_south", {10, 1, 4}, {0, 1, 0}, {2, 0, 0}},
};

int ds_in_room_a(const char *name) { return name[0] == 'A'; }

void ds_build(const ds_variant *v, ds_store *st, lbk_bake_scene *scene)
{
    memset(st, 0, sizeof *st);
    st->pos = malloc(sizeof(float) * 3 * QUAD_VERTICES * DS_OBJECTS);
    st->nrm = malloc(sizeof(float) * 3 * QUAD_VERTICES * DS_OBJECTS);
    st->idx = malloc(sizeof(uint32_t) * QUAD_INDICES * DS_OBJECTS);
    if (!st->pos || !st->nrm || !st->idx) abort();
    static const float corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int q = 0; q < DS_OBJECTS; q++) {
        const quad *Q = &quads[q];
        const float n[3] = {Q->u[1] * Q->v[2] - Q->u[2] * Q->v[1], Q->u[2] * Q->v[0] - Q->u[0] * Q->v[2],
                            Q->u[0] * Q->v[1] - Q->u[1] * Q->v[0]};
        float len = 0;
        for (int k = 0; k < 3; k++) len += n[k] * n[k];
        for (int c = 0; c < 4; c++)
            for (int k = 0; k < 3; k++) {
                st->pos[3 * (4 * q + c) + k] = Q->c[k] + corner[c][0] * Q->u[k] + corner[c][1] * Q->v[k];
                st->nrm[3 * (4 * q + c) + k] = n[k] / (len > 0 ? __builtin_sqrtf(len) : 1);
            }
        const uint32_t b = 4u * (uint32_t)q, tri[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        memcpy(st->idx + 6 * q, tri, sizeof tri);
        const float albedo = !strcmp(Q->name, "B_wall_east") ? v->wall_albedo : 0.7f;
        st->materials[q] = (lbk_bake_material){Q->name, {albedo, albedo, albedo}, {0, 0, 0}, 0};
        st->objects[q] = (lbk_bake_object){.name = Q->name, .first_triangle = 2u * (uint32_t)q, .triangle_count = 2,
                                           .material = (uint32_t)q, .lighting = LBK_BAKE_LIGHTING_LIGHTMAP};
    }
    st->light = (lbk_bake_light){.name = "lamp_B", .type = LBK_BAKE_LIGHT_POINT, .color = {30, 30, 30},
                                 .position = {10 + v->lamp_offset[0], 1.5f + v->lamp_offset[1], 2 + v->lamp_offset[2]},
                                 .light_set = v->lamp_set};
    memset(scene, 0, sizeof *scene);
    scene->name = "two_rooms";
    scene->vertex_count = QUAD_VERTICES * DS_OBJECTS;
    scene->positions = st->pos;
    scene->normals = st->nrm;
    scene->triangle_count = 2 * DS_OBJECTS;
    scene->indices = st->idx;
    scene->material_count = DS_OBJECTS;
    scene->materials = st->materials;
    scene->object_count = DS_OBJECTS;
    scene->objects = st->objects;
    scene->light_count = 1;
    scene->lights = &st->light;
    scene->sky[0] = scene->sky[1] = scene->sky[2] = v->sky;
}

void ds_free(ds_store *st)
{
    free(st->pos);
    free(st->nrm);
    free(st->idx);
    memset(st, 0, sizeof *st);
}
