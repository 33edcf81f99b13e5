#include "bias_scene.h"

#include <math.h>
#include <string.h>

#include "scene_append.h"
#include "transport_scenes.h"

const char *const bsc_group_name[BSC_GROUPS] = {"outside", "floor", "ceiling", "window wall", "walls",
                                                "table top", "table under", "table legs", "pole", "shelf",
                                                "sealed cavity", "buried"};

/* Vertical cylinder (outward), `seg` sides of `rings` quads each, with a top cap. */
static void pole(bk_scene *s, float cx, float cy, float r, float z0, float z1, int seg, int rings, uint32_t m)
{
    tsc_object(s, "pole", "", "");
    for (int i = 0; i < seg; i++) {
        double a0 = 2 * M_PI * i / seg, a1 = 2 * M_PI * (i + 1) / seg;
        float x0 = cx + r * (float)cos(a0), y0 = cy + r * (float)sin(a0);
        float x1 = cx + r * (float)cos(a1), y1 = cy + r * (float)sin(a1);
        float p0[3] = {x0, y0, z0}, p1[3] = {x1, y1, z0}, p2[3] = {x1, y1, z1}, p3[3] = {x0, y0, z1};
        float h = (z1 - z0) / rings;
        for (int k = 0; k < rings; k++) {
            p0[2] = p1[2] = z0 + h * k;
            p2[2] = p3[2] = z0 + h * (k + 1);
            tsc_quad(s, p0, p1, p2, p3, 1, m);
        }
        float c[3] = {cx, cy, z1}, q0[3] = {x0, y0, z1}, q1[3] = {x1, y1, z1};
        tsc_tri(s, c, q0, q1, m);
    }
}

/* The closed slabs: name, corners, subdivision (× detail), material slot. */
typedef struct bsc_slab { const char *name; float mn[3], mx[3]; int n, mat, inward; } bsc_slab;
enum { M_WALL, M_FLOOR, M_CEIL, M_WOOD, M_METAL, M_GROUND, M_COUNT };
static const bsc_slab slabs[] = {
    {"floor", {-0.2f, -0.2f, -0.2f}, {5.2f, 4.2f, 0}, 8, M_FLOOR, 0},
    {"ceiling", {-0.2f, -0.2f, 2.8f}, {5.2f, 4.2f, 3.0f}, 8, M_CEIL, 0},
    {"wall_w", {-0.2f, -0.2f, -0.2f}, {0, 4.2f, 3.0f}, 5, M_WALL, 0},
    {"wall_e", {5, -0.2f, -0.2f}, {5.2f, 4.2f, 3.0f}, 5, M_WALL, 0},
    {"wall_s", {-0.2f, -0.2f, -0.2f}, {5.2f, 0, 3.0f}, 5, M_WALL, 0},
    {"win_left", {-0.2f, 4, -0.2f}, {1, 4.2f, 3.0f}, 4, M_WALL, 0},
    {"win_right", {4, 4, -0.2f}, {5.2f, 4.2f, 3.0f}, 4, M_WALL, 0},
    {"win_below", {0.9f, 4, -0.2f}, {4.1f, 4.2f, 0.8f}, 4, M_WALL, 0},
    {"win_above", {0.9f, 4, 2.3f}, {4.1f, 4.2f, 3.0f}, 4, M_WALL, 0},
    /* a cavity sealed inside the west wall (faces facing into it): not a solid */
    {"cavity", {-0.16f, 1.0f, 0.6f}, {-0.04f, 2.0f, 1.6f}, 2, M_WALL, 1},
    /* a 3 cm shelf let 10 cm into the east wall */
    {"shelf", {4.6f, 1.0f, 1.4f}, {5.1f, 2.2f, 1.43f}, 3, M_WOOD, 0},
    /* table: 4 cm top on 5 cm legs let 1 cm into the floor and the top */
    {"table_top", {1.6f, 1.2f, 0.72f}, {2.8f, 2.0f, 0.76f}, 4, M_WOOD, 0},
    {"table_leg", {1.65f, 1.25f, -0.01f}, {1.70f, 1.30f, 0.73f}, 2, M_WOOD, 0},
    {"table_leg", {2.70f, 1.25f, -0.01f}, {2.75f, 1.30f, 0.73f}, 2, M_WOOD, 0},
    {"table_leg", {1.65f, 1.90f, -0.01f}, {1.70f, 1.95f, 0.73f}, 2, M_WOOD, 0},
    {"table_leg", {2.70f, 1.90f, -0.01f}, {2.75f, 1.95f, 0.73f}, 2, M_WOOD, 0},
};
#define N_SLABS (sizeof slabs / sizeof slabs[0])

void bsc_build(bk_scene *s, const bsc_options *opt)
{
    bsc_options o = {0, 1};
    if (opt) o = *opt;
    int d = o.detail > 0 ? o.detail : 1;
    tsc_init(s);
    uint32_t m[M_COUNT];
    m[M_WALL] = tsc_material(s, 0.7f, 0.7f, 0.7f, 0, 0, 0);
    m[M_FLOOR] = tsc_material(s, 0.35f, 0.3f, 0.25f, 0, 0, 0);
    m[M_CEIL] = tsc_material(s, 0.8f, 0.8f, 0.8f, 0, 0, 0);
    m[M_WOOD] = tsc_material(s, 0.45f, 0.3f, 0.2f, 0, 0, 0);
    m[M_METAL] = tsc_material(s, 0.6f, 0.6f, 0.6f, 0, 0, 0);
    m[M_GROUND] = tsc_material(s, 0.25f, 0.25f, 0.25f, 0, 0, 0);
    s->sky[0] = s->sky[1] = s->sky[2] = 1.0f;
    for (size_t i = 0; i < N_SLABS; i++) {
        tsc_object(s, slabs[i].name, "", "");
        tsc_box(s, slabs[i].mn, slabs[i].mx, slabs[i].n * d, slabs[i].inward, m[slabs[i].mat]);
    }
    pole(s, 4.2f, 0.8f, 0.02f, -0.01f, 1.6f, 12, 8 * d, m[M_METAL]);
    if (o.ground) {
        tsc_object(s, "ground", "", "");
        float g0[3] = {-15, -15, -0.21f}, g1[3] = {20, -15, -0.21f}, g2[3] = {20, 20, -0.21f}, g3[3] = {-15, 20, -0.21f};
        tsc_quad(s, g0, g1, g2, g3, 8 * d, m[M_GROUND]);
    }
    tsc_update_bounds(s);
}

double bsc_solid_depth(const float p[3])
{
    double best = -INFINITY;
    for (size_t i = 0; i < N_SLABS; i++) {
        if (slabs[i].inward) continue;
        double d = INFINITY;
        for (int k = 0; k < 3; k++) d = fmin(d, fmin(p[k] - slabs[i].mn[k], slabs[i].mx[k] - p[k]));
        best = fmax(best, d);
    }
    return best;
}

static int inside_room(const float p[3])
{
    const float e = 1e-3f;
    return p[0] > -e && p[0] < 5 + e && p[1] > -e && p[1] < 4 + e && p[2] > -e && p[2] < 2.8f + e;
}

int bsc_group(const bk_scene *s, uint32_t tri, const float p[3], const float n[3])
{
    uint32_t oi = s->tri_object[tri];
    const char *name = s->objects[oi].name;
    if (!strcmp(name, "cavity")) return BSC_SEALED;
    if (!inside_room(p)) return BSC_OUTSIDE;
    if (!strcmp(name, "floor")) return n[2] > 0.9f && p[2] > -1e-3f ? BSC_FLOOR : BSC_OUTSIDE;
    if (!strcmp(name, "ceiling")) return n[2] < -0.9f && p[2] < 2.8f + 1e-3f ? BSC_CEILING : BSC_OUTSIDE;
    if (!strncmp(name, "win_", 4)) return n[1] < -0.9f ? BSC_WINDOW_WALL : BSC_OUTSIDE;
    if (!strncmp(name, "wall_", 5)) return BSC_WALLS;
    if (!strcmp(name, "table_top")) return n[2] > 0.9f ? BSC_TABLE_TOP : n[2] < -0.9f ? BSC_TABLE_UNDER : BSC_LEGS;
    if (!strcmp(name, "table_leg")) return BSC_LEGS;
    if (!strcmp(name, "pole")) return BSC_POLE;
    if (!strcmp(name, "shelf")) return BSC_SHELF;
    return BSC_OUTSIDE;
}
