/* glTF import: the shared scenes (counts from scenes/SOURCES.md), transforms, extras,
 * lights, textures, the EXR sky, and malformed input (must fail with a message, never crash). */
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

#include <spng.h>

#include "scene/exr_read.h"
#include "scene/import.h"
#include "scene/scene.h"
#include "support/scene_builders.h"
#include "support/scenes_dir.h"

/* ---- helpers ----------------------------------------------------------------------------- */

/* A scene of scenes/ (or $LBK_SCENES): a missing file fails the test, naming it. */
static int import_shared(const char *rel, bk_scene *s, bk_import_options *opt)
{
    char path[1024], err[1024];
    sd_path(path, sizeof path, rel);
    SD_REQUIRE(path);
    int rc = bk_import_gltf(path, opt, s, err, sizeof err);
    if (rc) printf("import %s: %s\n", path, err);
    return rc;
}

static const bk_material *find_material(const bk_scene *s, const char *name)
{
    for (size_t i = 0; i < s->material_count; i++)
        if (!strcmp(s->materials[i].name, name)) return &s->materials[i];
    return NULL;
}

static const bk_object *find_object(const bk_scene *s, const char *name)
{
    for (size_t i = 0; i < s->object_count; i++)
        if (!strcmp(s->objects[i].name, name)) return &s->objects[i];
    return NULL;
}

static const bk_light *find_light(const bk_scene *s, const char *name)
{
    for (size_t i = 0; i < s->light_count; i++)
        if (!strcmp(s->lights[i].name, name)) return &s->lights[i];
    return NULL;
}

static size_t emissive_materials_used(const bk_scene *s)
{
    size_t n = 0;
    for (size_t m = 0; m < s->material_count; m++) {
        const bk_material *mt = &s->materials[m];
        if (mt->emission[0] <= 0 && mt->emission[1] <= 0 && mt->emission[2] <= 0) continue;
        for (size_t t = 0; t < s->tri_count; t++)
            if (s->tri_material[t] == m) { n++; break; }
    }
    return n;
}

static void assert_valid(const bk_scene *s)
{
    char err[512];
    int rc = bk_scene_check(s, err, sizeof err);
    if (rc) printf("bk_scene_check: %s\n", err);
    assert_int_equal(rc, 0);
}

/* A scratch directory per test binary run. */
static char g_tmp[256];

static void tmp_path(char *out, size_t n, const char *name)
{
    snprintf(out, n, "%s/%s", g_tmp, name);
}

static void write_file(const char *name, const void *data, size_t len)
{
    char p[512];
    tmp_path(p, sizeof p, name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    fclose(f);
}

static void write_text(const char *name, const char *text) { write_file(name, text, strlen(text)); }

/* Imports tmp/name; returns rc, error text in err. */
static int import_tmp(const char *name, bk_scene *s, const bk_import_options *opt, char *err, size_t n)
{
    char p[512];
    tmp_path(p, sizeof p, name);
    err[0] = 0;
    return bk_import_gltf(p, opt, s, err, n);
}

static void expect_error(const char *name, const char *needle1, const char *needle2)
{
    bk_scene s;
    char err[1024];
    int rc = import_tmp(name, &s, NULL, err, sizeof err);
    if (!rc || (needle1 && !strstr(err, needle1)) || (needle2 && !strstr(err, needle2)))
        printf("%s: rc %d, message: %s (expected \"%s\" and \"%s\")\n", name, rc, err, needle1 ? needle1 : "",
               needle2 ? needle2 : "");
    assert_int_not_equal(rc, 0);
    if (needle1) assert_non_null(strstr(err, needle1));
    if (needle2) assert_non_null(strstr(err, needle2));
    assert_non_null(strstr(err, name)); /* the message names the file */
    assert_int_equal(s.tri_count, 0);
    assert_null(s.positions);
}

static int setup_tmp(void **state)
{
    (void)state;
    snprintf(g_tmp, sizeof g_tmp, "/tmp/lbk_test_import_XXXXXX");
    return mkdtemp(g_tmp) ? 0 : -1;
}

static int teardown_tmp(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_tmp);
    return system(cmd) == 0 ? 0 : -1;
}

/* ---- the shared scenes ------------------------------------------------------------------- */

static void test_cornell_box(void **state)
{
    (void)state;
    bk_scene s;
    assert_int_equal(import_shared("cornell_box/CornellBox-Original.gltf", &s, NULL), 0);
    assert_valid(&s);
    assert_int_equal(s.tri_count, 32);
    assert_int_equal(s.light_count, 0);
    assert_int_equal(s.material_count, 8);
    assert_int_equal(emissive_materials_used(&s), 1);
    const bk_material *light = find_material(&s, "Light");
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
    assert_int_equal(import_shared("cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf", &s, &opt), 0);
    assert_valid(&s);
    assert_int_equal(s.tri_count, 4410);
    assert_int_equal(s.light_count, 0);
    assert_int_equal(emissive_materials_used(&s), 1);
    const bk_material *light = find_material(&s, "light.000");
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
    assert_int_equal(import_shared("room_with_doors/room.glb", &s, NULL), 0);
    assert_valid(&s);
    assert_int_equal(s.tri_count, 63720);
    assert_int_equal(s.light_count, 0);
    assert_int_equal(emissive_materials_used(&s), 0);
    assert_false(bk_scene_has_light(&s));
    /* mesh y = -1..4 moved up by the node's translation (0, 1, 0): floor 0, ceiling 5 */
    assert_float_equal(s.bounds_min[1], 0.0f, 1e-4);
    assert_float_equal(s.bounds_max[1], 5.0f, 1e-4);
    assert_float_equal(s.bounds_max[0] - s.bounds_min[0], 10.0f, 0.05);
    assert_float_equal(s.bounds_max[2] - s.bounds_min[2], 10.0f, 0.05);
    assert_non_null(find_material(&s, "Room"));
    assert_non_null(find_material(&s, "Glass"));
    bk_scene_free(&s);
}

static void test_lights_punctual_lamp(void **state)
{
    (void)state;
    bk_scene s;
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    assert_int_equal(import_shared("lights_punctual_lamp/LightsPunctualLamp.gltf", &s, &opt), 0);
    assert_valid(&s);
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
        const bk_light *l = find_light(&s, expect[i].name);
        assert_non_null(l);
        assert_int_equal(l->type, BK_LIGHT_POINT);
        assert_float_equal(l->color[0], expect[i].r, 1e-4);
        assert_float_equal(l->color[1], expect[i].g, 1e-4);
        assert_float_equal(l->color[2], expect[i].b, 1e-4);
        assert_float_equal(l->range, 0.0f, 0.0f);
    }
    /* Point_Orientation's matrix puts light 0 at (0.0462, 0.9078, 0.0067). */
    const bk_light *p0 = find_light(&s, "Point");
    assert_float_equal(p0->position[0], 0.04622355f, 1e-5);
    assert_float_equal(p0->position[1], 0.90779734f, 1e-5);
    assert_float_equal(p0->position[2], 0.00669663f, 1e-5);
    /* two emissive materials, both with a decoded emissive texture; textures at most 1024² */
    size_t emissive_tex = 0;
    for (size_t m = 0; m < s.material_count; m++)
        if (s.materials[m].emission_tex >= 0 && s.materials[m].emission[0] > 0) emissive_tex++;
    assert_int_equal(emissive_tex, 2);
    assert_int_equal(emissive_materials_used(&s), 2);
    assert_true(s.image_count >= 3); /* 2 base colours + the emissive map */
    for (size_t i = 0; i < s.image_count; i++) {
        assert_true(s.images[i].width <= 1024 && s.images[i].height <= 1024);
        for (int k = 0; k < 4; k++) assert_true(s.images[i].mean[k] >= 0.0f && s.images[i].mean[k] <= 1.0f);
    }
    assert_int_equal(rep.ignored_primitives, 0);
    bk_scene_free(&s);

    /* skip_textures: same geometry and lights, no images */
    opt.skip_textures = 1;
    assert_int_equal(import_shared("lights_punctual_lamp/LightsPunctualLamp.gltf", &s, &opt), 0);
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
    assert_int_equal(import_shared("water_bottle_draco/WaterBottle.gltf", &s, &opt), 0);
    assert_valid(&s);
    assert_int_equal(s.tri_count, 4510);
    assert_int_equal(s.vertex_count, 2549); /* has normals: vertices stay shared */
    assert_int_equal(s.object_count, 1);
    assert_int_equal(emissive_materials_used(&s), 1);
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

/* tri.bin: 4 positions of a unit quad in the XY plane (z = 0), then 6 uint16 indices
 * (0 1 2, 0 2 3), then 4 +Z normals. 48 + 12 + 48 = 108 bytes. */
static void write_quad_bin(void)
{
    unsigned char buf[108];
    float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    float nrm[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    memcpy(buf, pos, 48);
    memcpy(buf + 48, idx, 12);
    memcpy(buf + 60, nrm, 48);
    write_file("quad.bin", buf, sizeof buf);
}

/* A glTF with one quad mesh (mesh 0, indexed, with normals) and mesh 1 (same quad, no normals,
 * non-indexed: the first three positions). `nodes`, `extras`, `extensions` and `more` are spliced
 * in as JSON text. */
static void write_quad_gltf(const char *name, const char *nodes, const char *scene_nodes, const char *top)
{
    char json[8192];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},%s"
             "\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},"
             "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":48}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
             "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
             "\"materials\":[{\"name\":\"lamp\",\"emissiveFactor\":[1,0.5,0],"
             "\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":10}}},"
             "{\"name\":\"grey\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.25,0.125,1]},\"doubleSided\":true}],"
             "\"meshes\":[{\"name\":\"quad\",\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":2},\"indices\":1,\"material\":1}]},"
             "{\"name\":\"flat\",\"primitives\":[{\"attributes\":{\"POSITION\":3},\"material\":0}]}],"
             "\"nodes\":[%s],\"scenes\":[{\"nodes\":[%s]%s}],\"scene\":0}",
             top ? top : "", nodes, scene_nodes, "");
    write_text(name, json);
}

static void write_quad_gltf_scene_extras(const char *name, const char *nodes, const char *scene_nodes,
                                         const char *scene_extras)
{
    char json[8192];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},"
             "\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
             "\"nodes\":[%s],\"scenes\":[{\"nodes\":[%s],\"extras\":%s}]}",
             nodes, scene_nodes, scene_extras);
    write_text(name, json);
}

static void test_transforms(void **state)
{
    (void)state;
    write_quad_bin();
    /* node 0: parent, translation (10, 0, 0); node 1: child with the quad, rotated 90° about Y
     * (x → -z), scaled 2, translated (0, 1, 0). World: p → (10, 1, 0) + R(2p). */
    write_quad_gltf("trs.gltf",
                    "{\"name\":\"parent\",\"translation\":[10,0,0],\"children\":[1]},"
                    "{\"name\":\"child\",\"mesh\":0,\"translation\":[0,1,0],\"scale\":[2,2,2],"
                    "\"rotation\":[0,0.70710678,0,0.70710678]}",
                    "0", NULL);
    bk_scene s;
    char err[1024];
    assert_int_equal(import_tmp("trs.gltf", &s, NULL, err, sizeof err), 0);
    assert_valid(&s);
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
    write_quad_gltf("mirror.gltf",
                    "{\"mesh\":0,\"matrix\":[-1,0,0,0, 0,3,0,0, 0,0,1,0, 0,0,0,1]}", "0", NULL);
    assert_int_equal(import_tmp("mirror.gltf", &s, NULL, err, sizeof err), 0);
    assert_valid(&s);
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
    write_quad_gltf("flat.gltf", "{\"mesh\":1,\"rotation\":[-0.70710678,0,0,0.70710678]},{\"mesh\":0,\"scale\":[0,1,1]}",
                    "0,1", NULL);
    assert_int_equal(import_tmp("flat.gltf", &s, &opt, err, sizeof err), 0);
    assert_valid(&s);
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
    write_quad_bin();
    write_quad_gltf("mat.gltf", "{\"mesh\":0},{\"mesh\":1}", "0,1", NULL);
    bk_scene s;
    char err[1024];
    assert_int_equal(import_tmp("mat.gltf", &s, NULL, err, sizeof err), 0);
    const bk_material *lamp = find_material(&s, "lamp"), *grey = find_material(&s, "grey");
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
    write_quad_bin();
    /* parent: lighting llg, density 20, light set "lamps", door "d1"; child inherits only the
     * set and the door; "other" overrides the set. A light on the child joins "lamps". */
    write_quad_gltf("extras.gltf",
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
    int rc = import_tmp("extras.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_valid(&s);
    const bk_object *parent = find_object(&s, "parent"), *child = find_object(&s, "child"),
                    *other = find_object(&s, "other");
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
        write_quad_gltf(bad[i].file, nodes, "0", NULL);
        expect_error(bad[i].file, bad[i].key, "node 0 \"Crate\"");
    }
}

/* lbk_playable: true = the node-local [-1, 1]³ box, the object form a node-local box; the scene
 * keeps the world AABB of the transformed corners (a 90° turn about z swaps x and y extents). */
static void test_playable(void **state)
{
    (void)state;
    write_quad_bin();
    write_quad_gltf("playable.gltf",
                    "{\"name\":\"floor\",\"mesh\":0},"
                    "{\"name\":\"hall\",\"translation\":[10,2,0],\"scale\":[4,1,2],\"extras\":{\"lbk_playable\":true}},"
                    "{\"name\":\"nook\",\"translation\":[0,0,5],\"rotation\":[0,0,0.70710678,0.70710678],"
                    "\"extras\":{\"lbk_playable\":{\"min\":[0,0,0],\"max\":[3,1,2]}}},"
                    "{\"name\":\"off\",\"extras\":{\"lbk_playable\":false}}",
                    "0,1,2,3", NULL);
    bk_scene s;
    char err[1024];
    int rc = import_tmp("playable.gltf", &s, NULL, err, sizeof err);
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
        write_quad_gltf(bad[i].file, nodes, "0,1", NULL);
        expect_error(bad[i].file, "lbk_playable", "node 1 \"Zone\"");
    }
    /* a zero scale collapses the box */
    write_quad_gltf("pl_flat.gltf", "{\"mesh\":0},{\"name\":\"Zone\",\"scale\":[1,0,1],\"extras\":{\"lbk_playable\":true}}",
                    "0,1", NULL);
    expect_error("pl_flat.gltf", "lbk_playable", "node 1 \"Zone\"");
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
    write_text("pl_cap.gltf", json);
    expect_error("pl_cap.gltf", "lbk_playable", "the cap");
    free(json); free(nodes); free(roots);
}

static void test_sky_extras(void **state)
{
    (void)state;
    write_quad_bin();
    write_quad_gltf_scene_extras("sky_rgb.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":[0.25,0.5,1.5]}");
    bk_scene s;
    char err[1024];
    assert_int_equal(import_tmp("sky_rgb.gltf", &s, NULL, err, sizeof err), 0);
    assert_float_equal(s.sky[0], 0.25f, 0.0f);
    assert_float_equal(s.sky[2], 1.5f, 0.0f);
    assert_int_equal(s.sky_image, -1);
    assert_true(bk_scene_has_light(&s));
    bk_scene_free(&s);

    /* asset extras are accepted too */
    write_quad_bin();
    write_quad_gltf("sky_asset.gltf", "{\"mesh\":0}", "0", "\"extras\":{\"lbk_sky\":[1,1,1]},");
    assert_int_equal(import_tmp("sky_asset.gltf", &s, NULL, err, sizeof err), 0);
    assert_float_equal(s.sky[1], 1.0f, 0.0f);
    bk_scene_free(&s);

    /* no light, no emission, no sky */
    write_quad_gltf_scene_extras("dark.gltf", "{\"mesh\":0}", "0", "{}");
    assert_int_equal(import_tmp("dark.gltf", &s, NULL, err, sizeof err), 0);
    assert_false(bk_scene_has_light(&s));
    bk_scene_free(&s);

    write_quad_gltf_scene_extras("sky_short.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":[1,2]}");
    expect_error("sky_short.gltf", "lbk_sky", "scene 0 extras");
    write_quad_gltf_scene_extras("sky_neg.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":[1,-2,0]}");
    expect_error("sky_neg.gltf", "lbk_sky", NULL);
    write_quad_gltf_scene_extras("sky_missing.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"nope.exr\"}");
    expect_error("sky_missing.gltf", "lbk_sky", "nope.exr");
    write_quad_gltf_scene_extras("sky_num.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":7}");
    expect_error("sky_num.gltf", "lbk_sky", NULL);
}

static void put_u32(FILE *f, uint32_t v) { fwrite(&v, 4, 1, f); }
static void put_attr(FILE *f, const char *name, const char *type, uint32_t size)
{
    fwrite(name, 1, strlen(name) + 1, f);
    fwrite(type, 1, strlen(type) + 1, f);
    put_u32(f, size);
}

/* The header attributes both test EXRs share: channels B, G, R of `pixel_type` (1 HALF, 2 FLOAT),
 * no compression, data and display window w×h, increasing-y line order, unit pixel aspect. */
static void put_exr_attrs(FILE *f, int w, int h, uint32_t pixel_type)
{
    const char *chans[3] = {"B", "G", "R"};
    put_attr(f, "channels", "chlist", 3 * (2 + 16) + 1);
    for (int c = 0; c < 3; c++) {
        fwrite(chans[c], 1, 2, f);
        put_u32(f, pixel_type);
        unsigned char lin[4] = {0, 0, 0, 0};
        fwrite(lin, 1, 4, f);
        put_u32(f, 1);
        put_u32(f, 1);
    }
    fputc(0, f);
    put_attr(f, "compression", "compression", 1);
    fputc(0, f);
    int32_t box[4] = {0, 0, w - 1, h - 1};
    put_attr(f, "dataWindow", "box2i", 16);
    fwrite(box, 4, 4, f);
    put_attr(f, "displayWindow", "box2i", 16);
    fwrite(box, 4, 4, f);
    put_attr(f, "lineOrder", "lineOrder", 1);
    fputc(0, f);
    float one = 1.0f, zero2[2] = {0, 0};
    put_attr(f, "pixelAspectRatio", "float", 4);
    fwrite(&one, 4, 1, f);
    put_attr(f, "screenWindowCenter", "v2f", 8);
    fwrite(zero2, 4, 2, f);
    put_attr(f, "screenWindowWidth", "float", 4);
    fwrite(&one, 4, 1, f);
}

/* A minimal uncompressed scanline EXR with FLOAT channels B, G, R (alphabetical, as the format
 * requires), w×h, pixel (x, y) = (x + 1, y + 1, 0.5) · scale. */
static void write_exr(const char *name, int w, int h, float scale)
{
    char p[512];
    tmp_path(p, sizeof p, name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    put_u32(f, 20000630u);
    put_u32(f, 2);
    put_exr_attrs(f, w, h, 2); /* FLOAT */
    fputc(0, f);
    long table = ftell(f);
    uint64_t line_bytes = 8 + (uint64_t)w * 12;
    for (int y = 0; y < h; y++) {
        uint64_t off = (uint64_t)table + (uint64_t)h * 8 + (uint64_t)y * line_bytes;
        fwrite(&off, 8, 1, f);
    }
    for (int y = 0; y < h; y++) {
        put_u32(f, (uint32_t)y);
        put_u32(f, (uint32_t)w * 12);
        for (int c = 0; c < 3; c++)
            for (int x = 0; x < w; x++) {
                float v = (c == 2 ? (float)(x + 1) : c == 1 ? (float)(y + 1) : 0.5f) * scale;
                fwrite(&v, 4, 1, f);
            }
    }
    fclose(f);
}

/* float → half for the small exact values used here (normal numbers only). */
static uint16_t to_half(float f)
{
    uint32_t b;
    memcpy(&b, &f, 4);
    if (f == 0.0f) return 0;
    uint32_t sign = (b >> 16) & 0x8000u, exp = ((b >> 23) & 0xffu) - 127u + 15u, man = (b >> 13) & 0x3ffu;
    return (uint16_t)(sign | (exp << 10) | man);
}

/* A tiled (ONE_LEVEL, tw×th tiles), uncompressed EXR with HALF channels B, G, R, same pixel values
 * as write_exr; w, h need not be multiples of the tile size (partial edge tiles). */
static void write_tiled_exr(const char *name, int w, int h, int tw, int th)
{
    char p[512];
    tmp_path(p, sizeof p, name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    put_u32(f, 20000630u);
    put_u32(f, 2u | 0x200u); /* single-part tiled */
    put_exr_attrs(f, w, h, 1); /* HALF */
    put_attr(f, "tiles", "tiledesc", 9);
    put_u32(f, (uint32_t)tw);
    put_u32(f, (uint32_t)th);
    fputc(0, f); /* ONE_LEVEL, round down */
    fputc(0, f);
    int nx = (w + tw - 1) / tw, ny = (h + th - 1) / th;
    long table = ftell(f);
    uint64_t off = (uint64_t)table + (uint64_t)nx * ny * 8;
    for (int ty = 0; ty < ny; ty++)
        for (int tx = 0; tx < nx; tx++) {
            fwrite(&off, 8, 1, f);
            int cw = (tx + 1) * tw > w ? w - tx * tw : tw, ch = (ty + 1) * th > h ? h - ty * th : th;
            off += 20 + (uint64_t)cw * ch * 3 * 2;
        }
    for (int ty = 0; ty < ny; ty++)
        for (int tx = 0; tx < nx; tx++) {
            int cw = (tx + 1) * tw > w ? w - tx * tw : tw, ch = (ty + 1) * th > h ? h - ty * th : th;
            put_u32(f, (uint32_t)tx);
            put_u32(f, (uint32_t)ty);
            put_u32(f, 0);
            put_u32(f, 0);
            put_u32(f, (uint32_t)(cw * ch * 3 * 2));
            for (int y = ty * th; y < ty * th + ch; y++)
                for (int c = 0; c < 3; c++)
                    for (int x = tx * tw; x < tx * tw + cw; x++) {
                        uint16_t v = to_half(c == 2 ? (float)(x + 1) : c == 1 ? (float)(y + 1) : 0.5f);
                        fwrite(&v, 2, 1, f);
                    }
        }
    fclose(f);
}

static void test_sky_exr(void **state)
{
    (void)state;
    write_quad_bin();
    write_exr("sky.exr", 8, 4, 1.0f);
    write_quad_gltf_scene_extras("sky_exr.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"sky.exr\"}");
    bk_scene s;
    char err[1024];
    int rc = import_tmp("sky_exr.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.sky_image, 0);
    const bk_image *im = &s.images[0];
    assert_int_equal(im->width, 8);
    assert_int_equal(im->height, 4);
    /* pixel (3, 2): R = 4, G = 3, B = 0.5, A = 1 */
    const float *px = &im->rgba[4 * (2 * 8 + 3)];
    assert_float_equal(px[0], 4.0f, 0.0f);
    assert_float_equal(px[1], 3.0f, 0.0f);
    assert_float_equal(px[2], 0.5f, 0.0f);
    assert_float_equal(px[3], 1.0f, 0.0f);
    /* mean R = mean(1..8) = 4.5, G = mean(1..4) = 2.5 */
    assert_float_equal(s.sky[0], 4.5f, 1e-5);
    assert_float_equal(s.sky[1], 2.5f, 1e-5);
    assert_float_equal(s.sky[2], 0.5f, 1e-6);
    bk_scene_free(&s);

    /* max_sky_size 4: box-filtered to 4×2 with the same mean */
    bk_import_options opt = {0};
    opt.max_sky_size = 4;
    assert_int_equal(import_tmp("sky_exr.gltf", &s, &opt, err, sizeof err), 0);
    assert_int_equal(s.images[0].width, 4);
    assert_int_equal(s.images[0].height, 2);
    assert_float_equal(s.images[0].rgba[0], 1.5f, 1e-6); /* R of (0..1, 0..1) = (1+2)/2 */
    assert_float_equal(s.images[0].rgba[1], 1.5f, 1e-6); /* G = (1+2)/2 */
    assert_float_equal(s.sky[0], 4.5f, 1e-5);
    bk_scene_free(&s);

    /* a pixel cap smaller than the image refuses it before allocating */
    opt.max_sky_size = 0;
    opt.max_image_pixels = 16;
    assert_int_not_equal(import_tmp("sky_exr.gltf", &s, &opt, err, sizeof err), 0);
    assert_non_null(strstr(err, "cap"));

    /* tiled, half floats, 5×3 in 2×2 tiles (partial tiles on the right and bottom) */
    write_tiled_exr("tiled.exr", 5, 3, 2, 2);
    write_quad_gltf_scene_extras("sky_tiled.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"tiled.exr\"}");
    rc = import_tmp("sky_tiled.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.images[0].width, 5);
    assert_int_equal(s.images[0].height, 3);
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 5; x++) {
            const float *q = &s.images[0].rgba[4 * (y * 5 + x)];
            assert_float_equal(q[0], (float)(x + 1), 0.0f);
            assert_float_equal(q[1], (float)(y + 1), 0.0f);
            assert_float_equal(q[2], 0.5f, 0.0f);
            assert_float_equal(q[3], 1.0f, 0.0f);
        }
    assert_float_equal(s.sky[0], 3.0f, 1e-6);
    assert_float_equal(s.sky[1], 2.0f, 1e-6);
    bk_scene_free(&s);

    /* garbage in place of the EXR */
    write_text("junk.exr", "this is not an EXR file at all, sorry");
    write_quad_gltf_scene_extras("sky_junk.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"junk.exr\"}");
    expect_error("sky_junk.gltf", "junk.exr", NULL);
}

/* A w×h RGBA PNG in memory (free() it): top half sRGB 255, bottom half sRGB 128 (grey), alpha 255. */
static void *make_png(int w, int h, size_t *len)
{
    unsigned char *img = malloc((size_t)w * h * 4);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            unsigned char v = y < h / 2 ? 255 : 128;
            unsigned char *p = img + 4 * (y * w + x);
            p[0] = p[1] = p[2] = v;
            p[3] = 255;
        }
    spng_ctx *ctx = spng_ctx_new(SPNG_CTX_ENCODER);
    assert_non_null(ctx);
    spng_set_option(ctx, SPNG_ENCODE_TO_BUFFER, 1);
    struct spng_ihdr ihdr = {0};
    ihdr.width = (uint32_t)w;
    ihdr.height = (uint32_t)h;
    ihdr.bit_depth = 8;
    ihdr.color_type = SPNG_COLOR_TYPE_TRUECOLOR_ALPHA;
    spng_set_ihdr(ctx, &ihdr);
    assert_int_equal(spng_encode_image(ctx, img, (size_t)w * h * 4, SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE), 0);
    int e = 0;
    void *png = spng_get_png_buffer(ctx, len, &e);
    assert_int_equal(e, 0);
    spng_ctx_free(ctx);
    free(img);
    return png;
}

static void write_png(const char *name, int w, int h)
{
    size_t len = 0;
    void *png = make_png(w, h, &len);
    write_file(name, png, len);
    free(png);
}

static void put32le(unsigned char *p, uint32_t v) { memcpy(p, &v, 4); }

/* A .glb whose BIN chunk holds a quad (positions, uint16 indices, uv0) and a PNG that the
 * material's base colour texture reads through a bufferView. */
static void test_glb_embedded_texture(void **state)
{
    (void)state;
    size_t png_len = 0;
    void *png = make_png(4, 2, &png_len);
    size_t bin_len = 92 + ((png_len + 3) & ~(size_t)3);
    unsigned char *bin = calloc(1, bin_len);
    float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, uv[8] = {0, 1, 1, 1, 1, 0, 0, 0};
    uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    memcpy(bin, pos, 48);
    memcpy(bin + 48, idx, 12);
    memcpy(bin + 60, uv, 32);
    memcpy(bin + 92, png, png_len);
    char json[4096];
    int jl = snprintf(json, sizeof json,
                      "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":%zu}],"
                      "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},"
                      "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":32},{\"buffer\":0,\"byteOffset\":92,\"byteLength\":%zu}],"
                      "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
                      "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
                      "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"}],"
                      "\"images\":[{\"bufferView\":3,\"mimeType\":\"image/png\"}],\"textures\":[{\"source\":0}],"
                      "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],"
                      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":2},\"indices\":1,\"material\":0}]}],"
                      "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}",
                      bin_len, png_len);
    size_t jpad = ((size_t)jl + 3) & ~(size_t)3;
    size_t total = 12 + 8 + jpad + 8 + bin_len;
    unsigned char *glb = malloc(total);
    memcpy(glb, "glTF", 4);
    put32le(glb + 4, 2);
    put32le(glb + 8, (uint32_t)total);
    put32le(glb + 12, (uint32_t)jpad);
    memcpy(glb + 16, "JSON", 4);
    memset(glb + 20, ' ', jpad);
    memcpy(glb + 20, json, (size_t)jl);
    put32le(glb + 20 + jpad, (uint32_t)bin_len);
    memcpy(glb + 24 + jpad, "BIN", 4);
    memcpy(glb + 28 + jpad, bin, bin_len);
    write_file("embedded.glb", glb, total);
    bk_scene s;
    char err[1024];
    int rc = import_tmp("embedded.glb", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_valid(&s);
    assert_int_equal(s.image_count, 1);
    assert_int_equal(s.materials[0].albedo_tex, 0);
    assert_int_equal(s.images[0].width, 4);
    assert_float_equal(s.images[0].rgba[4 * 4], 0.2158605f, 1e-6);
    /* no NORMAL: flat shading unshares the vertices in triangle order (0 1 2, 0 2 3) */
    assert_int_equal(s.vertex_count, 6);
    assert_float_equal(s.uv0[2 * 1], 1.0f, 0.0f);
    assert_float_equal(s.uv0[2 * 1 + 1], 1.0f, 0.0f);
    assert_float_equal(s.uv0[2 * 5], 0.0f, 0.0f);
    assert_float_equal(s.uv0[2 * 5 + 1], 0.0f, 0.0f);
    assert_float_equal(s.uv0[2 * 3 + 1], 1.0f, 0.0f);
    bk_scene_free(&s);

    /* the PNG view damaged: a warning, the texture is dropped, the factor stays */
    memset(glb + 28 + jpad + 92, 0x42, 16);
    write_file("embedded_bad.glb", glb, total);
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    assert_int_equal(import_tmp("embedded_bad.glb", &s, &opt, err, sizeof err), 0);
    assert_int_equal(s.materials[0].albedo_tex, -1);
    assert_int_equal(rep.ignored_textures, 1);
    assert_int_equal(rep.warnings, 1);
    bk_scene_free(&s);
    free(glb);
    free(bin);
    free(png);
}

static void test_textures(void **state)
{
    (void)state;
    write_quad_bin();
    write_png("tex.png", 4, 2);
    /* base colour texture on a quad; the normal map's file is missing but never needed */
    char json[4096];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"images\":[{\"uri\":\"tex.png\"},{\"uri\":\"unused_missing.png\"}],\"textures\":[{\"source\":0},{\"source\":1}],"
             "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1],\"baseColorTexture\":{\"index\":0}},"
             "\"normalTexture\":{\"index\":1}}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]}],"
             "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}");
    write_text("tex2.gltf", json);
    bk_scene s;
    char err[1024];
    int rc = import_tmp("tex2.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.image_count, 1); /* the (missing) normal map is never needed */
    assert_int_equal(s.materials[0].albedo_tex, 0);
    assert_float_equal(s.materials[0].albedo[0], 0.5f, 0.0f);
    const bk_image *im = &s.images[0];
    assert_int_equal(im->width, 4);
    assert_int_equal(im->height, 2);
    /* sRGB 255 → 1, sRGB 128 → ((128/255 + 0.055)/1.055)^2.4 = 0.2158605 */
    assert_float_equal(im->rgba[0], 1.0f, 1e-6);
    assert_float_equal(im->rgba[4 * 4 + 1], 0.2158605f, 1e-6);
    assert_float_equal(im->rgba[4 * 4 + 3], 1.0f, 1e-6);
    assert_float_equal(im->mean[0], (1.0f + 0.2158605f) / 2, 1e-6);
    bk_scene_free(&s);

    /* max_texture_size 2: 4×2 → 2×1, each texel the average of a 2×2 block */
    bk_import_options opt = {0};
    bk_import_report rep;
    opt.max_texture_size = 2;
    opt.report = &rep;
    assert_int_equal(import_tmp("tex2.gltf", &s, &opt, err, sizeof err), 0);
    assert_int_equal(s.images[0].width, 2);
    assert_int_equal(s.images[0].height, 1);
    assert_float_equal(s.images[0].rgba[0], (1.0f + 0.2158605f) / 2, 1e-6);
    assert_int_equal(rep.downsampled_images, 1);
    bk_scene_free(&s);

    /* a needed texture that cannot be read is an error naming it */
    char *t = strstr(json, "tex.png");
    char json2[4096];
    snprintf(json2, sizeof json2, "%.*s%s%s", (int)(t - json), json, "missing.png", t + strlen("tex.png"));
    write_text("tex_missing.gltf", json2);
    expect_error("tex_missing.gltf", "image 0", "missing.png");
}

/* ---- malformed input --------------------------------------------------------------------- */

static void test_required_extension(void **state)
{
    (void)state;
    write_quad_bin();
    write_quad_gltf("req.gltf", "{\"mesh\":0}", "0",
                    "\"extensionsUsed\":[\"KHR_materials_volume\",\"KHR_materials_transmission\"],"
                    "\"extensionsRequired\":[\"KHR_materials_volume\"],");
    expect_error("req.gltf", "KHR_materials_volume", "not support");
    /* used but not required: fine */
    write_quad_gltf("used.gltf", "{\"mesh\":0}", "0",
                    "\"extensionsUsed\":[\"KHR_materials_transmission\",\"EXT_whatever\"],");
    bk_scene s;
    char err[1024];
    assert_int_equal(import_tmp("used.gltf", &s, NULL, err, sizeof err), 0);
    bk_scene_free(&s);
}

static void test_malformed_accessors(void **state)
{
    (void)state;
    write_quad_bin();
    static const struct { const char *file, *accessors, *n1, *n2; } cases[] = {
        /* count far beyond the bufferView */
        {"bogus_count.gltf", "{\"bufferView\":0,\"componentType\":5126,\"count\":1000000,\"type\":\"VEC3\"},"
                             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}", "accessor 0", "do not fit"},
        /* huge count (overflow bait) */
        {"huge_count.gltf", "{\"bufferView\":0,\"componentType\":5126,\"count\":4611686018427387904,\"type\":\"VEC3\"},"
                            "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}", "accessor 0", NULL},
        /* offset past the end */
        {"bad_offset.gltf", "{\"bufferView\":0,\"byteOffset\":40,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
                            "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}", "accessor 0", NULL},
        /* index accessor reads into the normals: indices 0..65535 out of range */
        {"bad_index_view.gltf", "{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
                                "{\"bufferView\":0,\"byteOffset\":12,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}", "index", "vertices"},
        /* wrong type for POSITION */
        {"bad_type.gltf", "{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
                          "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}", "POSITION", "components"},
        /* float indices */
        {"float_index.gltf", "{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
                             "{\"bufferView\":0,\"componentType\":5126,\"count\":6,\"type\":\"SCALAR\"}", "indices", "component type"},
        /* accessor without bufferView */
        {"no_view.gltf", "{\"componentType\":5126,\"count\":100000000,\"type\":\"VEC3\"},"
                         "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}", "accessor 0", "bufferView"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char json[4096];
        snprintf(json, sizeof json,
                 "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
                 "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
                 "\"accessors\":[%s],"
                 "\"meshes\":[{\"name\":\"m\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
                 "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}",
                 cases[i].accessors);
        write_text(cases[i].file, json);
        expect_error(cases[i].file, cases[i].n1, cases[i].n2);
    }

    /* index values out of range: the 6 uint16 indices read from a view holding 0 1 2 0 2 9 */
    unsigned char buf[60];
    float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    uint16_t idx[6] = {0, 1, 2, 0, 2, 9};
    memcpy(buf, pos, 48);
    memcpy(buf + 48, idx, 12);
    write_file("oob.bin", buf, sizeof buf);
    const char *oob =
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"oob.bin\",\"byteLength\":60}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"meshes\":[{\"name\":\"m\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}";
    write_text("oob.gltf", oob);
    expect_error("oob.gltf", "mesh 0 \"m\" primitive 0", "index 5 is 9");

    /* NaN position */
    float nan_pos[12] = {0, 0, 0, 1, 0, 0, 1, NAN, 0, 0, 1, 0};
    uint16_t good[6] = {0, 1, 2, 0, 2, 3};
    memcpy(buf, nan_pos, 48);
    memcpy(buf + 48, good, 12);
    write_file("oob.bin", buf, sizeof buf);
    expect_error("oob.gltf", "POSITION", "NaN");

    /* bufferView beyond the buffer */
    write_text("view_oob.gltf",
               "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
               "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":100,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
               "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
               "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
               "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}");
    expect_error("view_oob.gltf", "bufferView 0", "outside");

    /* image bufferView out of range (tinygltf would form a pointer past the buffer) */
    write_text("img_view.gltf",
               "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
               "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":100,\"byteLength\":4000}],"
               "\"images\":[{\"bufferView\":0,\"mimeType\":\"image/png\"}],\"nodes\":[],\"scenes\":[{\"nodes\":[]}]}");
    expect_error("img_view.gltf", "image 0", "outside");
}

static void test_malformed_structure(void **state)
{
    (void)state;
    write_quad_bin();
    /* a cycle */
    write_quad_gltf("cycle.gltf", "{\"name\":\"a\",\"mesh\":0,\"children\":[1]},{\"name\":\"b\",\"children\":[0]}", "0", NULL);
    expect_error("cycle.gltf", "node 0 \"a\"", "twice");
    /* a child index out of range */
    write_quad_gltf("child_oob.gltf", "{\"mesh\":0,\"children\":[7]}", "0", NULL);
    expect_error("child_oob.gltf", "node index 7", NULL);
    /* mesh index out of range */
    write_quad_gltf("mesh_oob.gltf", "{\"name\":\"n\",\"mesh\":9}", "0", NULL);
    expect_error("mesh_oob.gltf", "node 0 \"n\"", "mesh 9");
    /* non-finite-producing transform */
    write_quad_gltf("huge_scale.gltf", "{\"mesh\":0,\"scale\":[1e30,1e30,1e30],\"children\":[1]},{\"mesh\":0,\"scale\":[1e30,1,1]}", "0", NULL);
    expect_error("huge_scale.gltf", "node", "overflow");
    /* a 300-deep node chain */
    {
        static char json[65536];
        size_t n = 0;
        n += (size_t)snprintf(json + n, sizeof json - n, "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[");
        for (int i = 0; i < 300; i++)
            n += (size_t)snprintf(json + n, sizeof json - n, "%s{\"children\":[%d]}", i ? "," : "", i + 1);
        n += (size_t)snprintf(json + n, sizeof json - n, ",{}],\"scenes\":[{\"nodes\":[0]}]}");
        write_text("deep_nodes.gltf", json);
        expect_error("deep_nodes.gltf", "deeper than", NULL);
    }
    /* deeply nested extras (JSON depth) */
    {
        static char json[65536];
        size_t n = 0;
        n += (size_t)snprintf(json + n, sizeof json - n, "{\"asset\":{\"version\":\"2.0\"},\"extras\":");
        for (int i = 0; i < 20000; i++) json[n++] = '[';
        for (int i = 0; i < 20000; i++) json[n++] = ']';
        n += (size_t)snprintf(json + n, sizeof json - n, "}");
        write_text("deep_json.gltf", json);
        expect_error("deep_json.gltf", "nested deeper", NULL);
    }
    write_text("not_json.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
    expect_error("not_json.gltf", "JSON", NULL);
    write_text("empty.gltf", "");
    expect_error("empty.gltf", "empty", NULL);
    /* bad spot cone, bad light type, light index out of range */
    write_quad_gltf("bad_spot.gltf", "{\"name\":\"L\",\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}", "0",
                    "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\",\"spot\":{\"innerConeAngle\":1.0,\"outerConeAngle\":0.5}}]}},");
    expect_error("bad_spot.gltf", "node 0 \"L\": light 0", "cone");
    write_quad_gltf("bad_light_type.gltf", "{\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}", "0",
                    "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"area\"}]}},");
    expect_error("bad_light_type.gltf", "light type", "area");
    write_quad_gltf("light_oob.gltf", "{\"extensions\":{\"KHR_lights_punctual\":{\"light\":3}}}", "0", NULL);
    expect_error("light_oob.gltf", "light 3", "out of range");
    /* points and lines are ignored with a count, strips and fans are converted */
    write_text("modes.gltf",
               "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
               "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48}],"
               "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":0},{\"attributes\":{\"POSITION\":0},\"mode\":1},"
               "{\"attributes\":{\"POSITION\":0},\"mode\":5},{\"attributes\":{\"POSITION\":0},\"mode\":6}]}],"
               "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}");
    bk_scene s;
    char err[1024];
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    assert_int_equal(import_tmp("modes.gltf", &s, &opt, err, sizeof err), 0);
    assert_valid(&s);
    assert_int_equal(rep.ignored_primitives, 2);
    assert_int_equal(s.tri_count, 4); /* strip of 4 → 2, fan of 4 → 2 */
    /* strip vertices 0 1 2 3 = (0,0) (1,0) (1,1) (0,1): every triangle must face the same way
     * as the fan's (counter-clockwise from +Z for the fan 0 1 2, 0 2 3) */
    for (size_t t = 0; t < s.tri_count; t++) {
        const float *a = &s.positions[3 * s.tris[3 * t]], *b = &s.positions[3 * s.tris[3 * t + 1]],
                    *c = &s.positions[3 * s.tris[3 * t + 2]];
        float gz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        float nz = s.normals[3 * s.tris[3 * t] + 2];
        assert_true(gz * nz > 0.0f); /* flat normals agree with the winding */
    }
    bk_scene_free(&s);
    /* the JSON size cap */
    opt.max_json_bytes = 100;
    assert_int_not_equal(import_tmp("modes.gltf", &s, &opt, err, sizeof err), 0);
    assert_non_null(strstr(err, "JSON cap"));
    opt.max_json_bytes = 0;
    /* the primitive count cap */
    opt.max_triangles = 3;
    assert_int_not_equal(import_tmp("modes.gltf", &s, &opt, err, sizeof err), 0);
    assert_non_null(strstr(err, "cap"));
}

/* Import is linear in the JSON's size: 10^5 nodes (most of them empty, as a DoS file would have
 * them) import; with the callback depth check they took minutes (quadratic: 20 k 1.4 s, 80 k
 * 17 s). Brackets inside strings are not nesting. The time ratio 10^5 : 10^6 is in bench_import. */
static void test_many_nodes(void **state)
{
    (void)state;
    write_quad_bin();
    enum { N = 100000 };
    size_t cap = (size_t)N * 24 + 4096, n = 0;
    char *json = malloc(cap);
    assert_non_null(json);
    n += (size_t)snprintf(json + n, cap - n,
                          "{\"asset\":{\"version\":\"2.0\"},"
                          "\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
                          "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
                          "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
                          "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
                          "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
                          "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
                          "\"nodes\":[{\"mesh\":0,\"name\":\"");
    for (int i = 0; i < 300; i++) json[n++] = '['; /* deeper than the depth cap, but inside a string */
    n += (size_t)snprintf(json + n, cap - n, "\"}");
    for (int i = 0; i < N; i++) n += (size_t)snprintf(json + n, cap - n, ",{}");
    n += (size_t)snprintf(json + n, cap - n, "],\"scenes\":[{\"nodes\":[0");
    for (int i = 1; i <= N; i++) n += (size_t)snprintf(json + n, cap - n, ",%d", i);
    n += (size_t)snprintf(json + n, cap - n, "]}],\"scene\":0}");
    assert_true(n < cap);
    write_file("many_nodes.gltf", json, n);
    free(json);
    bk_scene s;
    char err[1024];
    int rc = import_tmp("many_nodes.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("many_nodes.gltf: %s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.object_count, 1);
    assert_int_equal(s.tri_count, 2);
    bk_scene_free(&s);
}

/* Resources resolve inside the scene's folder only: `..` escapes and symlinks pointing out are
 * refused with a message naming the cause unless allow_outside admits their folder; absolute
 * paths and URI schemes are always refused. */
static void write_buffer_gltf(const char *name, const char *uri)
{
    char json[1024];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"%s\",\"byteLength\":108}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
             "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
             uri);
    write_text(name, json);
}

static void test_resource_policy(void **state)
{
    (void)state;
    write_quad_bin(); /* tmp/quad.bin, outside tmp/sub */
    char sub[512], link[600], abs_uri[600], target[600];
    tmp_path(sub, sizeof sub, "sub");
    assert_int_equal(mkdir(sub, 0755), 0);
    write_buffer_gltf("sub/escape.gltf", "../quad.bin");
    expect_error("sub/escape.gltf", "outside the scene's folder", "quad.bin");
    tmp_path(target, sizeof target, "quad.bin");
    snprintf(abs_uri, sizeof abs_uri, "%s", target);
    write_buffer_gltf("sub/absolute.gltf", abs_uri);
    expect_error("sub/absolute.gltf", "not a path relative", "buffer 0");
    write_buffer_gltf("sub/scheme.gltf", "file:///etc/passwd");
    expect_error("sub/scheme.gltf", "not a path relative", NULL);
    snprintf(link, sizeof link, "%s/link.bin", sub);
    assert_int_equal(symlink(target, link), 0);
    write_buffer_gltf("sub/symlink.gltf", "link.bin");
    expect_error("sub/symlink.gltf", "outside the scene's folder", NULL);
    /* the same files with the outside folder allowed */
    bk_import_options o;
    memset(&o, 0, sizeof o);
    char tmpdir[512];
    tmp_path(tmpdir, sizeof tmpdir, "");
    o.allow_outside = tmpdir;
    const char *names[] = {"sub/escape.gltf", "sub/symlink.gltf"};
    for (int i = 0; i < 2; i++) {
        bk_scene s;
        char err[1024];
        int rc = import_tmp(names[i], &s, &o, err, sizeof err);
        if (rc) printf("%s: %s\n", names[i], err);
        assert_int_equal(rc, 0);
        assert_int_equal(s.tri_count, 2);
        bk_scene_free(&s);
    }
    /* a link that stays inside is fine without permission */
    char inner[600];
    snprintf(inner, sizeof inner, "%s/inner.bin", sub);
    assert_int_equal(symlink("link.bin", inner), 0); /* inner -> link -> outside: still outside */
    write_buffer_gltf("sub/inner.gltf", "inner.bin");
    expect_error("sub/inner.gltf", "outside the scene's folder", NULL);
}

static void test_malformed_glb(void **state)
{
    (void)state;
    char path[1024];
    SD_REQUIRE(sd_path(path, sizeof path, "room_with_doors/room.glb"));
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *glb = malloc((size_t)len);
    assert_int_equal(fread(glb, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    /* truncated at several points: header, inside JSON, inside BIN */
    long cuts[] = {10, 19, 100, len / 2, len - 4};
    for (size_t i = 0; i < sizeof cuts / sizeof cuts[0]; i++) {
        write_file("trunc.glb", glb, (size_t)cuts[i]);
        expect_error("trunc.glb", "truncated", NULL);
    }
    /* wrong version */
    unsigned char *copy = malloc((size_t)len);
    memcpy(copy, glb, (size_t)len);
    copy[4] = 1;
    write_file("v1.glb", copy, (size_t)len);
    expect_error("v1.glb", "version", NULL);
    /* BIN chunk length larger than the file says */
    memcpy(copy, glb, (size_t)len);
    uint32_t jlen;
    memcpy(&jlen, copy + 12, 4);
    uint32_t big = 0x7ffffff0u;
    memcpy(copy + 20 + jlen, &big, 4);
    write_file("binlen.glb", copy, (size_t)len);
    expect_error("binlen.glb", "BIN", NULL);
    /* flipped bytes in the middle of the BIN data: geometry changes but never crashes; the
     * import either succeeds or reports an error */
    memcpy(copy, glb, (size_t)len);
    for (long i = 20 + jlen + 8; i < len; i += 997) copy[i] ^= 0xff;
    write_file("noise.glb", copy, (size_t)len);
    bk_scene s;
    char err[1024];
    if (import_tmp("noise.glb", &s, NULL, err, sizeof err) == 0) bk_scene_free(&s);
    else assert_non_null(strstr(err, "noise.glb"));
    free(copy);
    free(glb);
}

static void test_draco_corrupt(void **state)
{
    (void)state;
    /* Copy the Draco bottle with a damaged Draco stream and with bogus attribute ids. */
    char src[1024];
    SD_REQUIRE(sd_path(src, sizeof src, "water_bottle_draco/WaterBottle.bin"));
    FILE *f = fopen(src, "rb");
    assert_non_null(f);
    static unsigned char bin[65536];
    size_t n = fread(bin, 1, sizeof bin, f);
    fclose(f);
    assert_int_equal(n, 49580);
    SD_REQUIRE(sd_path(src, sizeof src, "water_bottle_draco/WaterBottle.gltf"));
    f = fopen(src, "rb");
    assert_non_null(f);
    static char json[8192];
    size_t jn = fread(json, 1, sizeof json - 1, f);
    fclose(f);
    json[jn] = 0;
    for (size_t i = 100; i < n; i += 61) bin[i] ^= 0x5a;
    write_file("WaterBottle.bin", bin, n);
    write_text("bottle_noise.gltf", json);
    bk_scene s;
    char err[1024];
    bk_import_options opt = {0};
    opt.skip_textures = 1;
    if (import_tmp("bottle_noise.gltf", &s, &opt, err, sizeof err) == 0) {
        assert_valid(&s);
        bk_scene_free(&s);
    } else {
        assert_non_null(strstr(err, "bottle_noise.gltf"));
    }
    /* attribute id 9 does not exist in the stream */
    char *p = strstr(json, "\"POSITION\": 3");
    if (!p) p = strstr(json, "\"POSITION\":3");
    assert_non_null(p);
    char *digit = strchr(p + 10, '3');
    *digit = '9';
    write_text("bottle_badid.gltf", json);
    assert_int_not_equal(import_tmp("bottle_badid.gltf", &s, &opt, err, sizeof err), 0);
    assert_true(strstr(err, "Draco") != NULL || strstr(err, "KHR_draco") != NULL);
}

/* ---- scene utilities and the C builders -------------------------------------------------- */

static void test_scene_utilities(void **state)
{
    (void)state;
    bk_scene s;
    sb_closed_box(&s, 2.0f, 0.5f, 1.0f, 3);
    assert_valid(&s);
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
    assert_valid(&s);
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

/* EXRs with a channel the sky reader does not use, PIZ and B44 compressed: Blender 3.4's
 * half-float files of tests/fuzz/corpus_exr (pixel (x, y) = (x/8, y/4, 0.5, 1)) with the name of
 * the first channel, A, changed to Z. OpenEXRCore 3.1 wrote through a null pointer for a channel
 * left undecoded (fuzz_exr found it); the reader now decodes such channels into a scratch plane.
 * The data stay in the file's order while the list is read sorted (B, G, R, Z), so what the reader
 * gets is R = y/4, G = 0.5, B = 1 and no alpha (1); B44 is lossy. */
static void test_exr_unused_channel(void **state)
{
    (void)state;
    static const char *const files[] = {"tests/fuzz/corpus_exr/regress_piz_unused_channel.exr",
                                        "tests/fuzz/corpus_exr/regress_b44_unused_channel.exr"};
    for (int f = 0; f < 2; f++) {
        bk_image im;
        char err[512];
        int rc = bk_exr_read(files[f], 1 << 20, &im, err, sizeof err);
        if (rc) printf("%s\n", err);
        assert_int_equal(rc, 0);
        assert_int_equal(im.width, 8);
        assert_int_equal(im.height, 4);
        const float tol = f ? 0.02f : 0.0f;
        int seen[4] = {0, 0, 0, 0};
        for (int y = 0; y < 4; y++)
            for (int x = 0; x < 8; x++) {
                const float *p = &im.rgba[4 * (8 * y + x)];
                int row = (int)lrintf(4 * p[0]);
                assert_true(row >= 0 && row < 4);
                assert_float_equal(p[0], row / 4.0f, tol);
                seen[row] = 1;
                assert_float_equal(p[1], 0.5f, tol);
                assert_float_equal(p[2], 1.0f, tol);
                assert_float_equal(p[3], 1.0f, 0.0f);
            }
        assert_true(seen[0] && seen[1] && seen[2] && seen[3]);
        free(im.rgba);
    }
}

/* metallicFactor / roughnessFactor (glTF defaults 1, 1), the metallicRoughness texture (decoded
 * after the other textures), the default material of a primitive without one (a rough metal),
 * which materials are glossy, and factors outside [0, 1] refused. */
static void test_metallic_roughness(void **state)
{
    (void)state;
    write_quad_bin();
    write_png("mr.png", 2, 2);
    write_png("base.png", 4, 2);
    const char *head =
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"images\":[{\"uri\":\"mr.png\"},{\"uri\":\"base.png\"}],\"textures\":[{\"source\":0},{\"source\":1}],";
    char json[8192];
    snprintf(json, sizeof json,
             "%s\"materials\":[{\"name\":\"defaults\"},"
             "{\"name\":\"lambert\",\"pbrMetallicRoughness\":{\"metallicFactor\":0,\"roughnessFactor\":0.3}},"
             "{\"name\":\"textured\",\"pbrMetallicRoughness\":{\"metallicFactor\":0.25,\"roughnessFactor\":0.5,"
             "\"metallicRoughnessTexture\":{\"index\":0},\"baseColorTexture\":{\"index\":1}}}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0},"
             "{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":1},"
             "{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":2},"
             "{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
             "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}", head);
    write_text("mr.gltf", json);
    bk_scene s;
    char err[1024];
    int rc = import_tmp("mr.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_valid(&s);
    assert_int_equal(s.material_count, 4);
    const bk_material *m = s.materials;
    assert_float_equal(m[0].metallic, 1.0f, 0.0f);
    assert_float_equal(m[0].roughness, 1.0f, 0.0f);
    assert_int_equal(m[0].metal_rough_tex1, 0);
    assert_true(bk_material_glossy(&m[0]));
    assert_float_equal(m[1].metallic, 0.0f, 0.0f);
    assert_float_equal(m[1].roughness, 0.3f, 1e-7);
    assert_false(bk_material_glossy(&m[1]));
    assert_float_equal(m[2].metallic, 0.25f, 0.0f);
    assert_float_equal(m[2].roughness, 0.5f, 0.0f);
    assert_true(bk_material_glossy(&m[2]));
    /* base colour first (image 0 of the scene), the metallicRoughness texture after it */
    assert_int_equal(m[2].albedo_tex, 0);
    assert_int_equal(m[2].metal_rough_tex1, 2);
    assert_int_equal(s.images[m[2].metal_rough_tex1 - 1].width, 2);
    /* the primitive without a material: the spec's default material, white rough metal */
    assert_string_equal(m[3].name, "default");
    assert_float_equal(m[3].metallic, 1.0f, 0.0f);
    assert_float_equal(m[3].roughness, 1.0f, 0.0f);
    assert_float_equal(m[3].albedo[0], 1.0f, 0.0f);
    bk_scene_free(&s);
    /* out of [0, 1]: refused, with the material named */
    snprintf(json, sizeof json,
             "%s\"materials\":[{\"name\":\"bad\",\"pbrMetallicRoughness\":{\"metallicFactor\":1.5}}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]}],"
             "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}", head);
    write_text("mr_bad.gltf", json);
    rc = import_tmp("mr_bad.gltf", &s, NULL, err, sizeof err);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(err, "metallicFactor"));
    assert_non_null(strstr(err, "bad"));
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
        cmocka_unit_test(test_sky_exr),
        cmocka_unit_test(test_exr_unused_channel),
        cmocka_unit_test(test_textures),
        cmocka_unit_test(test_metallic_roughness),
        cmocka_unit_test(test_glb_embedded_texture),
        cmocka_unit_test(test_required_extension),
        cmocka_unit_test(test_malformed_accessors),
        cmocka_unit_test(test_malformed_structure),
        cmocka_unit_test(test_many_nodes),
        cmocka_unit_test(test_resource_policy),
        cmocka_unit_test(test_malformed_glb),
        cmocka_unit_test(test_draco_corrupt),
        cmocka_unit_test(test_scene_utilities),
        cmocka_unit_test(test_playable),
    };
    return cmocka_run_group_tests(tests, setup_tmp, teardown_tmp);
}
