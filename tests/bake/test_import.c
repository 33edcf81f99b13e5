/* glTF import: the shared scenes (counts from scenes/SOURCES.md), transforms, materials, extras,
 * playable boxes and the scene's sky extras, and the scene utilities. Textures and the EXR sky:
 * test_import_media.c; malformed input: test_import_malformed.c. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scene/import.h"
#include "scene/scene.h"
#include "support/import_fixtures.h"
#include "support/scene_builders.h"

/* ---- the shared scenes ------------------------------------------------------------------- */

static void test_cornell_box(void **state)
{
    (void)state;
    bk_scene s;
    assert_int_equal(imp_import_shared("cornell_box/CornellBox-Original.gltf", &s, NULL), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 32);
    assert_int_equal(s.light_count, 0);
    assert_int_equal(s.material_count, 8);
    assert_int_equal(imp_emissive_materials_used(&s), 1);
    const bk_material *light = imp_find_material(&s, "Light");
    assert_non_null(light);
    assert_float_equal(light->emission[0], 1.0f, 0.0f);
    assert_float_equal(light->emission[2], 1.0f, 0.0f);
    for (size_t i = 0; i < s.material_count; i++) assert_int_equal(s.materials[i].double_sided, 1);
    for (size_t i = 0; i < s.object_count; i++) assert_int_equal(s.objects[i].has_uv1, 0);
    assert_true(bk_scene_has_light(&s));
    /* The node's +90° X rotation turns the Blender Z-up box into Y-up: about 2 units tall,
     * the light quad at the top. */
    float h = s.bounds_max[1] - s.bounds_min[1];
    assert_true(h > 1.9f && h < 2.1f);
    float light_y = -1e9f;
    for (size_t t = 0; t < s.tri_count; t++)
        if (&s.materials[s.tri_material[t]] == light)
            for (int k = 0; k < 3; k++) light_y = fmaxf(light_y, s.positions[3 * s.tris[3 * t + k] + 1]);
    assert_true(light_y > s.bounds_max[1] - 0.05f);
    bk_scene_free(&s);
}

static void test_cornell_box_bjs(void **state)
{
    (void)state;
    bk_scene s;
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    assert_int_equal(imp_import_shared("cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf", &s, &opt), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 4410);
    assert_int_equal(s.light_count, 0);
    assert_int_equal(imp_emissive_materials_used(&s), 1);
    const bk_material *light = imp_find_material(&s, "light.000");
    assert_non_null(light);
    assert_float_equal(light->emission[1], 1.0f, 0.0f);
    /* TEXCOORD_1 on the walls, block and Suzanne, not on the lamp: a mixed case. */
    size_t with = 0, without = 0;
    for (size_t i = 0; i < s.object_count; i++) *(s.objects[i].has_uv1 ? &with : &without) += 1;
    assert_true(with >= 4);
    assert_true(without >= 2);
    size_t lamp_objects = 0;
    for (size_t i = 0; i < s.object_count; i++)
        for (uint32_t t = s.objects[i].first_tri; t < s.objects[i].first_tri + s.objects[i].tri_count; t++)
            if (&s.materials[s.tri_material[t]] == light) {
                assert_int_equal(s.objects[i].has_uv1, 0);
                lamp_objects++;
                break;
            }
    assert_int_equal(lamp_objects, 1);
    bk_scene_free(&s);
}

static void test_room_with_doors(void **state)
{
    (void)state;
    bk_scene s;
    assert_int_equal(imp_import_shared("room_with_doors/room.glb", &s, NULL), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 63720);
    assert_int_equal(s.light_count, 0);
    assert_int_equal(imp_emissive_materials_used(&s), 0);
    assert_false(bk_scene_has_light(&s));
    /* mesh y = -1..4 moved up by the node's translation (0, 1, 0): floor 0, ceiling 5 */
    assert_float_equal(s.bounds_min[1], 0.0f, 1e-4);
    assert_float_equal(s.bounds_max[1], 5.0f, 1e-4);
    assert_float_equal(s.bounds_max[0] - s.bounds_min[0], 10.0f, 0.05);
    assert_float_equal(s.bounds_max[2] - s.bounds_min[2], 10.0f, 0.05);
    assert_non_null(imp_find_material(&s, "Room"));
    assert_non_null(imp_find_material(&s, "Glass"));
    bk_scene_free(&s);
}

static void test_lights_punctual_lamp(void **state)
{
    (void)state;
    bk_scene s;
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    assert_int_equal(imp_import_shared("lights_punctual_lamp/LightsPunctualLamp.gltf", &s, &opt), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 6000);
    assert_int_equal(s.light_count, 5);
    static const struct { const char *name; float r, g, b; } expect[] = {
        {"Point", 15.0f, 15.0f * 0.6318749785423279f, 15.0f * 0.23909975588321689f},
        {"Point.002", 1.5f, 1.5f, 1.5f},
        {"Point.003", 80.0f * 0.21223080158233645f, 80.0f * 0.5906190276145935f, 80.0f * 0.5583405494689941f},
        {"Point.001", 80.0f * 0.21223080158233645f, 80.0f * 0.5906190276145935f, 80.0f * 0.5583405494689941f},
        {"Point.004", 180.0f, 180.0f * 0.6278365254402161f, 180.0f * 0.5012403726577759f},
    };
    for (size_t i = 0; i < 5; i++) {
        const bk_light *l = imp_find_light(&s, expect[i].name);
        assert_non_null(l);
        assert_int_equal(l->type, BK_LIGHT_POINT);
        assert_float_equal(l->color[0], expect[i].r, 1e-4);
        assert_float_equal(l->color[1], expect[i].g, 1e-4);
        assert_float_equal(l->color[2], expect[i].b, 1e-4);
        assert_float_equal(l->range, 0.0f, 0.0f);
    }
    /* Point_Orientation's matrix puts light 0 at (0.0462, 0.9078, 0.0067). */
    const bk_light *p0 = imp_find_light(&s, "Point");
    assert_float_equal(p0->position[0], 0.04622355f, 1e-5);
    assert_float_equal(p0->position[1], 0.90779734f, 1e-5);
    assert_float_equal(p0->position[2], 0.00669663f, 1e-5);
    /* two emissive materials, both with a decoded emissive texture; textures at most 1024² */
    size_t emissive_tex = 0;
    for (size_t m = 0; m < s.material_count; m++)
        if (s.materials[m].emission_tex >= 0 && s.materials[m].emission[0] > 0) emissive_tex++;
    assert_int_equal(emissive_tex, 2);
    assert_int_equal(imp_emissive_materials_used(&s), 2);
    assert_true(s.image_count >= 3); /* 2 base colours + the emissive map */
    for (size_t i = 0; i < s.image_count; i++) {
        assert_true(s.images[i].width <= 1024 && s.images[i].height <= 1024);
        for (int k = 0; k < 4; k++) assert_true(s.images[i].mean[k] >= 0.0f && s.images[i].mean[k] <= 1.0f);
    }
    assert_int_equal(rep.ignored_primitives, 0);
    bk_scene_free(&s);

    /* skip_textures: same geometry and lights, no images */
    opt.skip_textures = 1;
    assert_int_equal(imp_import_shared("lights_punctual_lamp/LightsPunctualLamp.gltf", &s, &opt), 0);
    assert_int_equal(s.tri_count, 6000);
    assert_int_equal(s.image_count, 0);
    for (size_t m = 0; m < s.material_count; m++) assert_int_equal(s.materials[m].albedo_tex, -1);
    bk_scene_free(&s);
}

static void test_water_bottle_draco(void **state)
{
    (void)state;
    bk_scene s;
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    assert_int_equal(imp_import_shared("water_bottle_draco/WaterBottle.gltf", &s, &opt), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 4510);
    assert_int_equal(s.vertex_count, 2549); /* has normals: vertices stay shared */
    assert_int_equal(s.object_count, 1);
    assert_int_equal(imp_emissive_materials_used(&s), 1);
    assert_true(s.materials[0].emission_tex >= 0);
    assert_true(s.materials[0].albedo_tex >= 0);
    /* accessor min/max: ±0.0546 × ±0.1303 × ±0.0546 (Draco quantisation keeps it within 1e-3) */
    assert_float_equal(s.bounds_min[1], -0.13034757f, 1e-3);
    assert_float_equal(s.bounds_max[1], 0.13034757f, 1e-3);
    assert_float_equal(s.bounds_max[0], 0.05458646f, 1e-3);
    assert_float_equal(s.bounds_min[2], -0.05457725f, 1e-3);
    /* the 2048² textures were box-filtered to 1024² */
    assert_true(rep.downsampled_images >= 2);
    assert_int_equal(s.images[s.materials[0].albedo_tex].width, 1024);
    /* uv0 came out of the Draco stream: not all zero, inside [0, 1] */
    int nonzero = 0;
    for (size_t v = 0; v < s.vertex_count; v++) {
        assert_true(s.uv0[2 * v] >= -0.01f && s.uv0[2 * v] <= 1.01f);
        nonzero |= s.uv0[2 * v] != 0.0f;
    }
    assert_true(nonzero);
    bk_scene_free(&s);
}

/* ---- hand-made glTF files ---------------------------------------------------------------- */

static void test_transforms(void **state)
{
    (void)state;
    imp_write_quad_bin();
    /* node 0: parent, translation (10, 0, 0); node 1: child with the quad, rotated 90° about Y
     * (x → -z), scaled 2, translated (0, 1, 0). World: p → (10, 1, 0) + R(2p). */
    imp_write_quad_gltf("trs.gltf",
                    "{\"name\":\"parent\",\"translation\":[10,0,0],\"children\":[1]},"
                    "{\"name\":\"child\",\"mesh\":0,\"translation\":[0,1,0],\"scale\":[2,2,2],"
                    "\"rotation\":[0,0.70710678,0,0.70710678]}",
                    "0", NULL);
    bk_scene s;
    char err[1024];
    assert_int_equal(imp_import_tmp("trs.gltf", &s, NULL, err, sizeof err), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 2);
    assert_int_equal(s.object_count, 1);
    assert_string_equal(s.objects[0].name, "child");
    /* local (1, 0, 0) → R: (0, 0, -2) → world (10, 1, -2); local (0, 1, 0) → (10, 3, 0) */
    const float *p1 = &s.positions[3 * 1], *p3 = &s.positions[3 * 3];
    assert_float_equal(p1[0], 10.0f, 1e-5); assert_float_equal(p1[1], 1.0f, 1e-5); assert_float_equal(p1[2], -2.0f, 1e-5);
    assert_float_equal(p3[0], 10.0f, 1e-5); assert_float_equal(p3[1], 3.0f, 1e-5); assert_float_equal(p3[2], 0.0f, 1e-5);
    /* +Z normal rotated 90° about Y → +X, still unit despite the scale */
    assert_float_equal(s.normals[0], 1.0f, 1e-5);
    assert_float_equal(s.normals[2], 0.0f, 1e-5);
    /* local_to_world translation column */
    assert_float_equal(s.objects[0].local_to_world[12], 10.0f, 1e-5);
    assert_float_equal(s.objects[0].local_to_world[13], 1.0f, 1e-5);
    uint64_t h = s.objects[0].geometry_hash;
    bk_scene_free(&s);

    /* Same mesh with a mirroring scale (-1 on x) and a non-uniform y scale given as a matrix:
     * winding flips so the geometric normal still agrees with the (inverse-transpose) normal,
     * and the geometry hash (local space) is unchanged. */
    imp_write_quad_gltf("mirror.gltf",
                    "{\"mesh\":0,\"matrix\":[-1,0,0,0, 0,3,0,0, 0,0,1,0, 0,0,0,1]}", "0", NULL);
    assert_int_equal(imp_import_tmp("mirror.gltf", &s, NULL, err, sizeof err), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.objects[0].geometry_hash, h);
    for (size_t t = 0; t < s.tri_count; t++) {
        const float *a = &s.positions[3 * s.tris[3 * t]], *b = &s.positions[3 * s.tris[3 * t + 1]],
                    *c = &s.positions[3 * s.tris[3 * t + 2]];
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float gz = e1[0] * e2[1] - e1[1] * e2[0];
        assert_true(gz > 0.0f); /* counter-clockwise seen from +Z */
        assert_float_equal(s.normals[3 * s.tris[3 * t] + 2], 1.0f, 1e-6);
    }
    assert_float_equal(s.positions[3 * 1 + 0], -1.0f, 1e-6);
    assert_float_equal(s.positions[3 * 2 + 1], 3.0f, 1e-6);
    bk_scene_free(&s);

    /* No normals, not indexed: flat normals from the winding; a zero scale node is skipped. */
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    imp_write_quad_gltf("flat.gltf", "{\"mesh\":1,\"rotation\":[-0.70710678,0,0,0.70710678]},{\"mesh\":0,\"scale\":[0,1,1]}",
                    "0,1", NULL);
    assert_int_equal(imp_import_tmp("flat.gltf", &s, &opt, err, sizeof err), 0);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 1);
    assert_int_equal(s.vertex_count, 3);
    assert_int_equal(rep.skipped_nodes, 1);
    /* the face normal (0, 0, 1) rotated -90° about X is (0, 1, 0) */
    assert_float_equal(s.normals[0], 0.0f, 1e-6);
    assert_float_equal(fabsf(s.normals[1]), 1.0f, 1e-6);
    float ny = s.normals[1];
    /* check against the transformed geometry: e1 × e2 along the normal */
    const float *a = &s.positions[0], *b = &s.positions[3], *c = &s.positions[6];
    float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float gy = e1[2] * e2[0] - e1[0] * e2[2];
    assert_true(gy * ny > 0.0f);
    assert_float_equal(ny, 1.0f, 1e-6);
    bk_scene_free(&s);
}

static void test_materials_and_emission(void **state)
{
    (void)state;
    imp_write_quad_bin();
    imp_write_quad_gltf("mat.gltf", "{\"mesh\":0},{\"mesh\":1}", "0,1", NULL);
    bk_scene s;
    char err[1024];
    assert_int_equal(imp_import_tmp("mat.gltf", &s, NULL, err, sizeof err), 0);
    const bk_material *lamp = imp_find_material(&s, "lamp"), *grey = imp_find_material(&s, "grey");
    assert_non_null(lamp);
    assert_non_null(grey);
    /* emissiveFactor (1, 0.5, 0) × KHR_materials_emissive_strength 10 */
    assert_float_equal(lamp->emission[0], 10.0f, 0.0f);
    assert_float_equal(lamp->emission[1], 5.0f, 0.0f);
    assert_float_equal(lamp->emission[2], 0.0f, 0.0f);
    assert_int_equal(lamp->double_sided, 0);
    assert_float_equal(grey->albedo[0], 0.5f, 0.0f);
    assert_float_equal(grey->albedo[2], 0.125f, 0.0f);
    assert_int_equal(grey->double_sided, 1);
    assert_int_equal(grey->albedo_tex, -1);
    assert_true(bk_scene_has_light(&s));
    bk_scene_free(&s);
}

static void test_extras(void **state)
{
    (void)state;
    imp_write_quad_bin();
    /* parent: lighting llg, density 20, light set "lamps", door "d1"; child inherits only the
     * set and the door; "other" overrides the set. A light on the child joins "lamps". */
    imp_write_quad_gltf("extras.gltf",
                    "{\"name\":\"parent\",\"mesh\":0,\"children\":[1,2],\"extras\":{\"lbk_lighting\":\"llg\","
                    "\"lbk_texel_density\":20,\"lbk_light_set\":\"lamps\",\"lbk_door\":\"d1\",\"unrelated\":[1,{}]}},"
                    "{\"name\":\"child\",\"mesh\":0,\"translation\":[0,0,1],"
                    "\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}},"
                    "{\"name\":\"other\",\"mesh\":0,\"translation\":[0,0,2],\"extras\":{\"lbk_light_set\":\"fire\","
                    "\"lbk_lighting\":\"none\"}}",
                    "0",
                    "\"extensionsUsed\":[\"KHR_lights_punctual\"],\"extensions\":{\"KHR_lights_punctual\":{\"lights\":"
                    "[{\"type\":\"spot\",\"intensity\":100,\"color\":[1,0.5,0.25],\"range\":7,"
                    "\"spot\":{\"innerConeAngle\":0.25,\"outerConeAngle\":0.5}}]}},");
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("extras.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    imp_assert_valid(&s);
    const bk_object *parent = imp_find_object(&s, "parent"), *child = imp_find_object(&s, "child"),
                    *other = imp_find_object(&s, "other");
    assert_non_null(parent); assert_non_null(child); assert_non_null(other);
    assert_int_equal(parent->lighting, BK_LIGHTING_LLG);
    assert_float_equal(parent->texel_density, 20.0f, 0.0f);
    assert_string_equal(parent->light_set, "lamps");
    assert_string_equal(parent->door, "d1");
    assert_int_equal(child->lighting, BK_LIGHTING_AUTO);
    assert_float_equal(child->texel_density, 0.0f, 0.0f);
    assert_string_equal(child->light_set, "lamps");
    assert_string_equal(child->door, "d1");
    assert_int_equal(other->lighting, BK_LIGHTING_NONE);
    assert_string_equal(other->light_set, "fire");
    assert_string_equal(other->door, "d1");
    assert_int_equal(s.light_count, 1);
    const bk_light *l = &s.lights[0];
    assert_int_equal(l->type, BK_LIGHT_SPOT);
    assert_string_equal(l->light_set, "lamps");
    assert_float_equal(l->color[0], 100.0f, 0.0f);
    assert_float_equal(l->color[1], 50.0f, 0.0f);
    assert_float_equal(l->range, 7.0f, 0.0f);
    assert_float_equal(l->inner_cone, 0.25f, 1e-7);
    assert_float_equal(l->outer_cone, 0.5f, 1e-7);
    assert_float_equal(l->position[2], 1.0f, 1e-6);
    assert_float_equal(l->direction[2], -1.0f, 1e-6); /* lights point down the node's -Z */
    bk_scene_free(&s);

    /* Invalid values name the node and the key. */
    static const struct { const char *file, *extras, *key; } bad[] = {
        {"bad_lighting.gltf", "{\"lbk_lighting\":\"bake\"}", "lbk_lighting"},
        {"bad_lighting_type.gltf", "{\"lbk_lighting\":3}", "lbk_lighting"},
        {"bad_density.gltf", "{\"lbk_texel_density\":-1}", "lbk_texel_density"},
        {"bad_density_str.gltf", "{\"lbk_texel_density\":\"20\"}", "lbk_texel_density"},
        {"bad_set.gltf", "{\"lbk_light_set\":5}", "lbk_light_set"},
        {"bad_door.gltf", "{\"lbk_door\":\"\"}", "lbk_door"},
        {"bad_door_long.gltf", "{\"lbk_door\":\"0123456789012345678901234567890123456789012345678901234567890123456789\"}", "lbk_door"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char nodes[512];
        snprintf(nodes, sizeof nodes, "{\"name\":\"Crate\",\"mesh\":0,\"extras\":%s}", bad[i].extras);
        imp_write_quad_gltf(bad[i].file, nodes, "0", NULL);
        imp_expect_error(bad[i].file, bad[i].key, "node 0 \"Crate\"");
    }
}

/* lbk_playable: true = the node-local [-1, 1]³ box, the object form a node-local box; the scene
 * keeps the world AABB of the transformed corners (a 90° turn about z swaps x and y extents). */
static void test_playable(void **state)
{
    (void)state;
    imp_write_quad_bin();
    imp_write_quad_gltf("playable.gltf",
                    "{\"name\":\"floor\",\"mesh\":0},"
                    "{\"name\":\"hall\",\"translation\":[10,2,0],\"scale\":[4,1,2],\"extras\":{\"lbk_playable\":true}},"
                    "{\"name\":\"nook\",\"translation\":[0,0,5],\"rotation\":[0,0,0.70710678,0.70710678],"
                    "\"extras\":{\"lbk_playable\":{\"min\":[0,0,0],\"max\":[3,1,2]}}},"
                    "{\"name\":\"off\",\"extras\":{\"lbk_playable\":false}}",
                    "0,1,2,3", NULL);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("playable.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.playable_count, 2);
    const float want[2][6] = {{6, 1, -2, 14, 3, 2}, {-1, 0, 5, 0, 3, 7}};
    for (int b = 0; b < 2; b++)
        for (int k = 0; k < 3; k++) {
            assert_float_equal(s.playable[b].min[k], want[b][k], 1e-5);
            assert_float_equal(s.playable[b].max[k], want[b][3 + k], 1e-5);
        }
    assert_int_equal(s.object_count, 1); /* playable nodes without a mesh add no geometry */
    bk_scene_free(&s);

    static const struct { const char *file, *extras; } bad[] = {
        {"pl_str.gltf", "{\"lbk_playable\":\"yes\"}"},
        {"pl_num.gltf", "{\"lbk_playable\":1}"},
        {"pl_nomax.gltf", "{\"lbk_playable\":{\"min\":[0,0,0]}}"},
        {"pl_short.gltf", "{\"lbk_playable\":{\"min\":[0,0],\"max\":[1,1,1]}}"},
        {"pl_strnum.gltf", "{\"lbk_playable\":{\"min\":[0,\"0\",0],\"max\":[1,1,1]}}"},
        {"pl_order.gltf", "{\"lbk_playable\":{\"min\":[0,0,0],\"max\":[1,0,1]}}"},
        {"pl_huge.gltf", "{\"lbk_playable\":{\"min\":[0,0,0],\"max\":[1e300,1,1]}}"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char nodes[512];
        snprintf(nodes, sizeof nodes, "{\"mesh\":0},{\"name\":\"Zone\",\"extras\":%s}", bad[i].extras);
        imp_write_quad_gltf(bad[i].file, nodes, "0,1", NULL);
        imp_expect_error(bad[i].file, "lbk_playable", "node 1 \"Zone\"");
    }
    /* a zero scale collapses the box */
    imp_write_quad_gltf("pl_flat.gltf", "{\"mesh\":0},{\"name\":\"Zone\",\"scale\":[1,0,1],\"extras\":{\"lbk_playable\":true}}",
                    "0,1", NULL);
    imp_expect_error("pl_flat.gltf", "lbk_playable", "node 1 \"Zone\"");
    /* the cap: BK_MAX_PLAYABLE + 1 boxes */
    size_t cap = 64 + (BK_MAX_PLAYABLE + 1) * 48;
    char *nodes = malloc(cap), *roots = malloc(8 * (BK_MAX_PLAYABLE + 2));
    assert_non_null(nodes); assert_non_null(roots);
    size_t o = (size_t)snprintf(nodes, cap, "{\"mesh\":0}"), ro = (size_t)snprintf(roots, 8, "0");
    for (int i = 1; i <= BK_MAX_PLAYABLE + 1; i++) {
        o += (size_t)snprintf(nodes + o, cap - o, ",{\"extras\":{\"lbk_playable\":true}}");
        ro += (size_t)snprintf(roots + ro, 8, ",%d", i);
    }
    size_t jl = o + ro + 4096;
    char *json = malloc(jl);
    assert_non_null(json);
    snprintf(json, jl,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
             "\"nodes\":[%s],\"scenes\":[{\"nodes\":[%s]}],\"scene\":0}", nodes, roots);
    imp_write_text("pl_cap.gltf", json);
    imp_expect_error("pl_cap.gltf", "lbk_playable", "the cap");
    free(json); free(nodes); free(roots);
}

static void test_sky_extras(void **state)
{
    (void)state;
    imp_write_quad_bin();
    imp_write_quad_gltf_scene_extras("sky_rgb.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":[0.25,0.5,1.5]}");
    bk_scene s;
    char err[1024];
    assert_int_equal(imp_import_tmp("sky_rgb.gltf", &s, NULL, err, sizeof err), 0);
    assert_float_equal(s.sky[0], 0.25f, 0.0f);
    assert_float_equal(s.sky[2], 1.5f, 0.0f);
    assert_int_equal(s.sky_image, -1);
    assert_true(bk_scene_has_light(&s));
    bk_scene_free(&s);

    /* asset extras are accepted too */
    imp_write_quad_bin();
    imp_write_quad_gltf("sky_asset.gltf", "{\"mesh\":0}", "0", "\"extras\":{\"lbk_sky\":[1,1,1]},");
    assert_int_equal(imp_import_tmp("sky_asset.gltf", &s, NULL, err, sizeof err), 0);
    assert_float_equal(s.sky[1], 1.0f, 0.0f);
    bk_scene_free(&s);

    /* no light, no emission, no sky */
    imp_write_quad_gltf_scene_extras("dark.gltf", "{\"mesh\":0}", "0", "{}");
    assert_int_equal(imp_import_tmp("dark.gltf", &s, NULL, err, sizeof err), 0);
    assert_false(bk_scene_has_light(&s));
    bk_scene_free(&s);

    imp_write_quad_gltf_scene_extras("sky_short.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":[1,2]}");
    imp_expect_error("sky_short.gltf", "lbk_sky", "scene 0 extras");
    imp_write_quad_gltf_scene_extras("sky_neg.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":[1,-2,0]}");
    imp_expect_error("sky_neg.gltf", "lbk_sky", NULL);
    imp_write_quad_gltf_scene_extras("sky_missing.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"nope.exr\"}");
    imp_expect_error("sky_missing.gltf", "lbk_sky", "nope.exr");
    imp_write_quad_gltf_scene_extras("sky_num.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":7}");
    imp_expect_error("sky_num.gltf", "lbk_sky", NULL);
}
/* ---- scene utilities and the C builders -------------------------------------------------- */

static void test_scene_utilities(void **state)
{
    (void)state;
    bk_scene s;
    sb_closed_box(&s, 2.0f, 0.5f, 1.0f, 3);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 6 * 2 * 9);
    for (int k = 0; k < 3; k++) {
        assert_float_equal(s.bounds_min[k], -1.0f, 0.0f);
        assert_float_equal(s.bounds_max[k], 1.0f, 0.0f);
    }
    /* every face looks at the centre, and its winding agrees with its normal */
    for (size_t t = 0; t < s.tri_count; t++) {
        const float *a = &s.positions[3 * s.tris[3 * t]], *b = &s.positions[3 * s.tris[3 * t + 1]],
                    *c = &s.positions[3 * s.tris[3 * t + 2]], *n = &s.normals[3 * s.tris[3 * t]];
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float g[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        float cx = (a[0] + b[0] + c[0]) / 3, cy = (a[1] + b[1] + c[1]) / 3, cz = (a[2] + b[2] + c[2]) / 3;
        assert_true(-(n[0] * cx + n[1] * cy + n[2] * cz) > 0.0f);
        assert_true(g[0] * n[0] + g[1] * n[1] + g[2] * n[2] > 0.0f);
    }
    assert_true(bk_scene_has_light(&s)); /* emissive walls */
    uint64_t h3 = s.objects[0].geometry_hash;
    bk_scene_free(&s);
    assert_int_equal(s.sky_image, -1);
    assert_null(s.positions);

    sb_closed_box(&s, 2.0f, 0.5f, 0.0f, 3);
    assert_int_equal(s.objects[0].geometry_hash, h3); /* same geometry, other material */
    assert_false(bk_scene_has_light(&s));
    s.sky[1] = 0.1f;
    assert_true(bk_scene_has_light(&s));
    s.sky[1] = 0.0f;
    /* bk_scene_check finds an index out of range and a non-unit normal */
    char err[256];
    s.tris[5] = (uint32_t)s.vertex_count;
    assert_int_not_equal(bk_scene_check(&s, err, sizeof err), 0);
    assert_non_null(strstr(err, "triangle 1"));
    s.tris[5] = 0;
    s.normals[0] = 2.0f;
    assert_int_not_equal(bk_scene_check(&s, err, sizeof err), 0);
    assert_non_null(strstr(err, "vertex 0"));
    bk_scene_free(&s);

    sb_closed_box(&s, 2.0f, 0.5f, 0.0f, 4);
    assert_true(s.objects[0].geometry_hash != h3);
    bk_scene_free(&s);

    sb_plane_point_light(&s, 5.0f, 2.0f, 100.0f, 0.8f, 2);
    imp_assert_valid(&s);
    assert_int_equal(s.tri_count, 8);
    assert_int_equal(s.light_count, 1);
    assert_float_equal(s.bounds_max[1], 2.0f, 0.0f); /* the light is inside the bounds */
    assert_float_equal(s.normals[1], 1.0f, 0.0f);
    assert_true(bk_scene_has_light(&s));
    s.lights[0].color[0] = s.lights[0].color[1] = s.lights[0].color[2] = 0.0f;
    assert_false(bk_scene_has_light(&s));
    bk_scene_free(&s);

    /* the hash is XXH3-64 of the raw position bytes then the index bytes */
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t idx[3] = {0, 1, 2}, idx2[3] = {0, 2, 1};
    assert_true(bk_geometry_hash(pos, 3, idx, 3) != bk_geometry_hash(pos, 3, idx2, 3));
    assert_int_equal(bk_geometry_hash(pos, 3, idx, 3), bk_geometry_hash(pos, 3, idx, 3));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_box),
        cmocka_unit_test(test_cornell_box_bjs),
        cmocka_unit_test(test_room_with_doors),
        cmocka_unit_test(test_lights_punctual_lamp),
        cmocka_unit_test(test_water_bottle_draco),
        cmocka_unit_test(test_transforms),
        cmocka_unit_test(test_materials_and_emission),
        cmocka_unit_test(test_extras),
        cmocka_unit_test(test_sky_extras),
        cmocka_unit_test(test_scene_utilities),
        cmocka_unit_test(test_playable),
    };
    return cmocka_run_group_tests(tests, imp_setup_tmp, imp_teardown_tmp);
}
