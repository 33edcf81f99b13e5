/* Object classification (bake/layout/classify.h): lightmap vs LLG vs none. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bake/layout/classify.h"
#include "scene/import.h"
#include "support/scenes_dir.h"
#include "support/uv_scenes.h"

/* A wall in the plane x = x0 (facing +x when dir = 1) from z0..z1, 0..h, with a doorway of
 * width dw and height dh in its middle: three quads. */
static void wall_with_door(bk_scene *s, float x0, int dir, float z0, float z1, float h, float dw, float dh)
{
    float zm = 0.5f * (z0 + z1), a = zm - 0.5f * dw, b = zm + 0.5f * dw;
    const float zs[3][2] = {{z0, a}, {b, z1}, {a, b}};
    const float ys[3][2] = {{0, h}, {0, h}, {dh, h}};
    for (int i = 0; i < 3; i++) {
        float p0[3] = {x0, ys[i][0], zs[i][0]}, p1[3] = {x0, ys[i][0], zs[i][1]}, p2[3] = {x0, ys[i][1], zs[i][1]},
              p3[3] = {x0, ys[i][1], zs[i][0]};
        if (dir > 0)
            uvs_quad(s, p0, p3, p2, p1, 2, 0, NULL, 1.0f);
        else
            uvs_quad(s, p0, p1, p2, p3, 2, 0, NULL, 1.0f);
    }
}

/* room_with_doors rebuilt: a 10 × 5 × 10 m room (doorways in two walls) and 16 UV spheres
 * of radius 0.5 m with 64 × 32 segments (3,968 triangles each) at (±3, 1..4, ±3). */
static void room_with_spheres(bk_scene *s)
{
    uvs_init(s);
    uvs_object(s, "Cube");
    float f0[3] = {-5, 0, 5}, f1[3] = {5, 0, 5}, f2[3] = {5, 0, -5}, f3[3] = {-5, 0, -5};
    uvs_quad(s, f0, f1, f2, f3, 4, 0, NULL, 1.0f);
    float c0[3] = {-5, 5, 5}, c1[3] = {-5, 5, -5}, c2[3] = {5, 5, -5}, c3[3] = {5, 5, 5};
    uvs_quad(s, c0, c1, c2, c3, 4, 0, NULL, 1.0f);
    wall_with_door(s, -5, 1, -5, 5, 5, 1.5f, 2.5f);
    wall_with_door(s, 5, -1, -5, 5, 5, 1.5f, 2.5f);
    float b0[3] = {-5, 0, -5}, b1[3] = {5, 0, -5}, b2[3] = {5, 5, -5}, b3[3] = {-5, 5, -5};
    uvs_quad(s, b0, b1, b2, b3, 2, 0, NULL, 1.0f);
    float n0[3] = {5, 0, 5}, n1[3] = {-5, 0, 5}, n2[3] = {-5, 5, 5}, n3[3] = {5, 5, 5};
    uvs_quad(s, n0, n1, n2, n3, 2, 0, NULL, 1.0f);
    uint32_t glass = uvs_material(s, 0.3f, 0.0f);
    for (int h = 1; h <= 4; h++)
        for (int q = 0; q < 4; q++) {
            char name[32];
            snprintf(name, sizeof name, "Sphere.%03d", (h - 1) * 4 + q);
            uvs_object(s, name);
            float c[3] = {q & 1 ? 3.f : -3.f, (float)h, q & 2 ? 3.f : -3.f};
            uvs_sphere(s, c, 0.5f, 64, 32, glass);
        }
    uvs_update_bounds(s);
}

static void test_room_with_spheres(void **state)
{
    (void)state;
    bk_scene s;
    room_with_spheres(&s);
    assert_int_equal(s.object_count, 17);
    bk_object_class *c = calloc(s.object_count, sizeof *c);
    assert_non_null(c);
    assert_int_equal(bk_classify_objects(&s, NULL, c), LBK_OK);
    assert_int_equal(c[0].rep, BK_REP_LIGHTMAP);
    assert_int_equal(c[0].reason, BK_REASON_DEFAULT);
    assert_float_equal(c[0].diagonal, 15.0, 1e-3);
    for (size_t i = 1; i < s.object_count; i++) {
        assert_int_equal(s.objects[i].tri_count, 3968);
        assert_int_equal(c[i].rep, BK_REP_LLG);
        assert_int_equal(c[i].reason, BK_REASON_INTRICATE);
        assert_int_equal(c[i].live_tris, 3968);
        /* a tessellated unit-diameter sphere: area a little under π, diagonal √3 */
        assert_float_equal(c[i].area, 3.1416, 0.02);
        assert_float_equal(c[i].diagonal, sqrtf(3.0f), 1e-3);
    }
    /* with the density rule off, the size rule still makes them LLG */
    bk_classify_options o = {0};
    o.intricate_density = 1e9f;
    assert_int_equal(bk_classify_objects(&s, &o, c), LBK_OK);
    assert_int_equal(c[0].rep, BK_REP_LIGHTMAP);
    for (size_t i = 1; i < s.object_count; i++) {
        assert_int_equal(c[i].rep, BK_REP_LLG);
        assert_int_equal(c[i].reason, BK_REASON_SMALL);
    }
    free(c);
    uvs_free(&s);
}

/* The real file, through the importer: the same answer. */
static void test_room_with_doors_file(void **state)
{
    (void)state;
    char path[1024];
    SD_REQUIRE(sd_path(path, sizeof path, "room_with_doors/room.glb"));
    bk_scene s;
    char err[512];
    bk_import_options io = {0};
    io.skip_textures = 1;
    int rc = bk_import_gltf(path, &io, &s, err, sizeof err);
    if (rc != 0) fprintf(stderr, "import: %s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.object_count, 17);
    bk_object_class *c = calloc(s.object_count, sizeof *c);
    assert_non_null(c);
    assert_int_equal(bk_classify_objects(&s, NULL, c), LBK_OK);
    size_t llg = 0, lm = 0;
    for (size_t i = 0; i < s.object_count; i++) {
        if (strncmp(s.objects[i].name, "Sphere", 6) == 0) {
            assert_int_equal(c[i].rep, BK_REP_LLG);
            llg++;
        } else {
            assert_string_equal(s.objects[i].name, "Cube");
            assert_int_equal(c[i].rep, BK_REP_LIGHTMAP);
            lm++;
        }
    }
    assert_int_equal(llg, 16);
    assert_int_equal(lm, 1);
    free(c);
    bk_scene_free(&s);
}

static void test_authored_wins(void **state)
{
    (void)state;
    bk_scene s;
    room_with_spheres(&s);
    s.objects[0].lighting = BK_LIGHTING_LLG;
    s.objects[1].lighting = BK_LIGHTING_LIGHTMAP;
    s.objects[2].lighting = BK_LIGHTING_NONE;
    s.objects[3].lighting = 77; /* unknown value: treated as auto */
    bk_object_class c[17];
    assert_int_equal(bk_classify_objects(&s, NULL, c), LBK_OK);
    assert_int_equal(c[0].rep, BK_REP_LLG);
    assert_int_equal(c[0].reason, BK_REASON_AUTHORED);
    assert_int_equal(c[1].rep, BK_REP_LIGHTMAP);
    assert_int_equal(c[1].reason, BK_REASON_AUTHORED);
    assert_int_equal(c[2].rep, BK_REP_NONE);
    assert_int_equal(c[2].reason, BK_REASON_AUTHORED);
    assert_int_equal(c[3].rep, BK_REP_LLG);
    assert_int_equal(c[3].reason, BK_REASON_INTRICATE);
    uvs_free(&s);
}

static void test_emissive_door_small_empty(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uint32_t lamp = uvs_material(&s, 0.8f, 5.0f);
    float l0[3] = {-0.2f, 2, 0.2f}, l1[3] = {0.2f, 2, 0.2f}, l2[3] = {0.2f, 2, -0.2f}, l3[3] = {-0.2f, 2, -0.2f};
    /* 0: a static emissive panel → none */
    uvs_object(&s, "light");
    uvs_quad(&s, l0, l3, l2, l1, 1, lamp, NULL, 1.0f);
    /* 1: the same panel in a dynamic light set → lit like any small simple object */
    uint32_t o1 = uvs_object(&s, "switchable");
    uvs_quad(&s, l0, l3, l2, l1, 1, lamp, NULL, 1.0f);
    snprintf(s.objects[o1].light_set, sizeof s.objects[o1].light_set, "hall");
    /* 2: half emissive → not emissive-only */
    uvs_object(&s, "half");
    uvs_quad(&s, l0, l3, l2, l1, 1, lamp, NULL, 1.0f);
    uvs_quad(&s, l0, l1, l2, l3, 1, 0, NULL, 1.0f);
    /* 3: a door */
    uint32_t o3 = uvs_object(&s, "door");
    float d0[3] = {0, 0, 0}, d1[3] = {1, 0, 0}, d2[3] = {1, 2, 0}, d3[3] = {0, 2, 0};
    uvs_quad(&s, d0, d1, d2, d3, 1, 0, NULL, 1.0f);
    snprintf(s.objects[o3].door, sizeof s.objects[o3].door, "front");
    /* 4: a small simple box → lightmap */
    uvs_object(&s, "crate");
    float mn[3] = {0, 0, 0}, mx[3] = {0.6f, 0.6f, 0.6f};
    uvs_box(&s, mn, mx, 1, 0, 0);
    /* 5: a small detailed prop (224 triangles, ~200 per m²) → LLG by size */
    uvs_object(&s, "vase");
    float c[3] = {3, 0.3f, 0};
    uvs_sphere(&s, c, 0.3f, 16, 8, 0);
    /* 6: only degenerate triangles → none */
    uvs_object(&s, "dust");
    float p[3] = {0, 0, 0}, q[3] = {1, 1, 1}, r[3] = {2, 2, 2};
    uvs_tri(&s, p, q, r, 0);
    /* 7: a large emitter whose texture has a black texel → not emissive-only */
    s.images = calloc(2, sizeof *s.images);
    s.image_count = 2;
    for (int i = 0; i < 2; i++) {
        s.images[i].width = 2;
        s.images[i].height = 1;
        s.images[i].rgba = calloc(8, sizeof(float));
        for (int k = 0; k < 8; k++) s.images[i].rgba[k] = 1.0f;
    }
    s.images[0].rgba[4] = s.images[0].rgba[5] = s.images[0].rgba[6] = 0.0f; /* texel 1 black */
    uint32_t sign_dark = uvs_material(&s, 0.5f, 1.0f), sign_lit = uvs_material(&s, 0.5f, 1.0f);
    s.materials[sign_dark].emission_tex = 0;
    s.materials[sign_lit].emission_tex = 1;
    float w0[3] = {0, 0, -4}, w1[3] = {4, 0, -4}, w2[3] = {4, 3, -4}, w3[3] = {0, 3, -4};
    uvs_object(&s, "sign_partly_dark");
    uvs_quad(&s, w0, w1, w2, w3, 1, sign_dark, NULL, 1.0f);
    /* 8: the same with a fully lit texture → none */
    uvs_object(&s, "sign_lit");
    uvs_quad(&s, w0, w1, w2, w3, 1, sign_lit, NULL, 1.0f);
    bk_object_class cl[9];
    assert_int_equal(s.object_count, 9);
    assert_int_equal(bk_classify_objects(&s, NULL, cl), LBK_OK);
    const int want_rep[9] = {BK_REP_NONE, BK_REP_LIGHTMAP, BK_REP_LIGHTMAP, BK_REP_LLG, BK_REP_LIGHTMAP,
                             BK_REP_LLG, BK_REP_NONE, BK_REP_LIGHTMAP, BK_REP_NONE};
    const int want_reason[9] = {BK_REASON_EMISSIVE, BK_REASON_DEFAULT, BK_REASON_DEFAULT, BK_REASON_DOOR,
                                BK_REASON_DEFAULT, BK_REASON_SMALL, BK_REASON_EMPTY, BK_REASON_DEFAULT,
                                BK_REASON_EMISSIVE};
    for (int i = 0; i < 9; i++) {
        assert_int_equal(cl[i].rep, want_rep[i]);
        assert_int_equal(cl[i].reason, want_reason[i]);
    }
    assert_int_equal(cl[6].live_tris, 0);
    assert_float_equal(cl[4].area, 6 * 0.36, 1e-5);
    assert_string_equal(bk_rep_name(BK_REP_LLG), "llg");
    assert_string_equal(bk_rep_reason_name(BK_REASON_INTRICATE), "intricate");
    assert_string_equal(bk_rep_name(99), "unknown");
    assert_int_equal(bk_classify_objects(NULL, NULL, cl), LBK_ERR_INVALID_ARGUMENT);
    uvs_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_room_with_spheres),
        cmocka_unit_test(test_room_with_doors_file),
        cmocka_unit_test(test_authored_wins),
        cmocka_unit_test(test_emissive_door_small_empty),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
