/* glTF import of malformed input: it must fail with a message naming the file, never crash
 * (required extensions, accessors, structure, node counts, external resources, GLB framing,
 * corrupt Draco). */
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
#include "support/scenes_dir.h"

/* ---- malformed input --------------------------------------------------------------------- */

static void test_required_extension(void **state)
{
    (void)state;
    imp_write_quad_bin();
    imp_write_quad_gltf("req.gltf", "{\"mesh\":0}", "0",
                    "\"extensionsUsed\":[\"KHR_materials_volume\",\"KHR_materials_transmission\"],"
                    "\"extensionsRequired\":[\"KHR_materials_volume\"],");
    imp_expect_error("req.gltf", "KHR_materials_volume", "not support");
    /* used but not required: fine */
    imp_write_quad_gltf("used.gltf", "{\"mesh\":0}", "0",
                    "\"extensionsUsed\":[\"KHR_materials_transmission\",\"EXT_whatever\"],");
    bk_scene s;
    char err[1024];
    assert_int_equal(imp_import_tmp("used.gltf", &s, NULL, err, sizeof err), 0);
    bk_scene_free(&s);
}

static void test_malformed_accessors(void **state)
{
    (void)state;
    imp_write_quad_bin();
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
        imp_write_text(cases[i].file, json);
        imp_expect_error(cases[i].file, cases[i].n1, cases[i].n2);
    }

    /* index values out of range: the 6 uint16 indices read from a view holding 0 1 2 0 2 9 */
    unsigned char buf[60];
    float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    uint16_t idx[6] = {0, 1, 2, 0, 2, 9};
    memcpy(buf, pos, 48);
    memcpy(buf + 48, idx, 12);
    imp_write_file("oob.bin", buf, sizeof buf);
    const char *oob =
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"oob.bin\",\"byteLength\":60}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"meshes\":[{\"name\":\"m\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}";
    imp_write_text("oob.gltf", oob);
    imp_expect_error("oob.gltf", "mesh 0 \"m\" primitive 0", "index 5 is 9");

    /* NaN position */
    float nan_pos[12] = {0, 0, 0, 1, 0, 0, 1, NAN, 0, 0, 1, 0};
    uint16_t good[6] = {0, 1, 2, 0, 2, 3};
    memcpy(buf, nan_pos, 48);
    memcpy(buf + 48, good, 12);
    imp_write_file("oob.bin", buf, sizeof buf);
    imp_expect_error("oob.gltf", "POSITION", "NaN");

    /* bufferView beyond the buffer */
    imp_write_text("view_oob.gltf",
               "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
               "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":100,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
               "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
               "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
               "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}");
    imp_expect_error("view_oob.gltf", "bufferView 0", "outside");

    /* image bufferView out of range (tinygltf would form a pointer past the buffer) */
    imp_write_text("img_view.gltf",
               "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
               "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":100,\"byteLength\":4000}],"
               "\"images\":[{\"bufferView\":0,\"mimeType\":\"image/png\"}],\"nodes\":[],\"scenes\":[{\"nodes\":[]}]}");
    imp_expect_error("img_view.gltf", "image 0", "outside");
}

static void test_malformed_structure(void **state)
{
    (void)state;
    imp_write_quad_bin();
    /* a cycle */
    imp_write_quad_gltf("cycle.gltf", "{\"name\":\"a\",\"mesh\":0,\"children\":[1]},{\"name\":\"b\",\"children\":[0]}", "0", NULL);
    imp_expect_error("cycle.gltf", "node 0 \"a\"", "twice");
    /* a child index out of range */
    imp_write_quad_gltf("child_oob.gltf", "{\"mesh\":0,\"children\":[7]}", "0", NULL);
    imp_expect_error("child_oob.gltf", "node index 7", NULL);
    /* mesh index out of range */
    imp_write_quad_gltf("mesh_oob.gltf", "{\"name\":\"n\",\"mesh\":9}", "0", NULL);
    imp_expect_error("mesh_oob.gltf", "node 0 \"n\"", "mesh 9");
    /* a transform whose floats would overflow: the scene-extent limit refuses it first */
    imp_write_quad_gltf("huge_scale.gltf", "{\"mesh\":0,\"scale\":[1e30,1e30,1e30],\"children\":[1]},{\"mesh\":0,\"scale\":[1e30,1,1]}", "0", NULL);
    imp_expect_error("huge_scale.gltf", "node 0", "beyond +-1e+09 m");
    /* a 300-deep node chain */
    {
        static char json[65536];
        size_t n = 0;
        n += (size_t)snprintf(json + n, sizeof json - n, "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[");
        for (int i = 0; i < 300; i++)
            n += (size_t)snprintf(json + n, sizeof json - n, "%s{\"children\":[%d]}", i ? "," : "", i + 1);
        n += (size_t)snprintf(json + n, sizeof json - n, ",{}],\"scenes\":[{\"nodes\":[0]}]}");
        imp_write_text("deep_nodes.gltf", json);
        imp_expect_error("deep_nodes.gltf", "deeper than", NULL);
    }
    /* deeply nested extras (JSON depth) */
    {
        static char json[65536];
        size_t n = 0;
        n += (size_t)snprintf(json + n, sizeof json - n, "{\"asset\":{\"version\":\"2.0\"},\"extras\":");
        for (int i = 0; i < 20000; i++) json[n++] = '[';
        for (int i = 0; i < 20000; i++) json[n++] = ']';
        n += (size_t)snprintf(json + n, sizeof json - n, "}");
        imp_write_text("deep_json.gltf", json);
        imp_expect_error("deep_json.gltf", "nested deeper", NULL);
    }
    imp_write_text("not_json.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
    imp_expect_error("not_json.gltf", "JSON", NULL);
    imp_write_text("empty.gltf", "");
    imp_expect_error("empty.gltf", "empty", NULL);
    /* bad spot cone, bad light type, light index out of range */
    imp_write_quad_gltf("bad_spot.gltf", "{\"name\":\"L\",\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}", "0",
                    "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\",\"spot\":{\"innerConeAngle\":1.0,\"outerConeAngle\":0.5}}]}},");
    imp_expect_error("bad_spot.gltf", "node 0 \"L\": light 0", "cone");
    imp_write_quad_gltf("bad_light_type.gltf", "{\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}", "0",
                    "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"area\"}]}},");
    imp_expect_error("bad_light_type.gltf", "light type", "area");
    imp_write_quad_gltf("light_oob.gltf", "{\"extensions\":{\"KHR_lights_punctual\":{\"light\":3}}}", "0", NULL);
    imp_expect_error("light_oob.gltf", "light 3", "out of range");
    /* points and lines are ignored with a count, strips and fans are converted */
    imp_write_text("modes.gltf",
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
    assert_int_equal(imp_import_tmp("modes.gltf", &s, &opt, err, sizeof err), 0);
    imp_assert_valid(&s);
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
    assert_int_not_equal(imp_import_tmp("modes.gltf", &s, &opt, err, sizeof err), 0);
    assert_non_null(strstr(err, "JSON cap"));
    opt.max_json_bytes = 0;
    /* the primitive count cap */
    opt.max_triangles = 3;
    assert_int_not_equal(imp_import_tmp("modes.gltf", &s, &opt, err, sizeof err), 0);
    assert_non_null(strstr(err, "cap"));
}

/* Import is linear in the JSON's size: 10^5 nodes (most of them empty, as a DoS file would have
 * them) import; with the callback depth check they took minutes (quadratic: 20 k 1.4 s, 80 k
 * 17 s). Brackets inside strings are not nesting. The time ratio 10^5 : 10^6 is in bench_import. */
static void test_many_nodes(void **state)
{
    (void)state;
    imp_write_quad_bin();
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
    imp_write_file("many_nodes.gltf", json, n);
    free(json);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("many_nodes.gltf", &s, NULL, err, sizeof err);
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
    imp_write_text(name, json);
}

static void test_resource_policy(void **state)
{
    (void)state;
    imp_write_quad_bin(); /* tmp/quad.bin, outside tmp/sub */
    char sub[512], link[600], abs_uri[600], target[600];
    imp_tmp_path(sub, sizeof sub, "sub");
    assert_int_equal(mkdir(sub, 0755), 0);
    write_buffer_gltf("sub/escape.gltf", "../quad.bin");
    imp_expect_error("sub/escape.gltf", "outside the scene's folder", "quad.bin");
    imp_tmp_path(target, sizeof target, "quad.bin");
    snprintf(abs_uri, sizeof abs_uri, "%s", target);
    write_buffer_gltf("sub/absolute.gltf", abs_uri);
    imp_expect_error("sub/absolute.gltf", "not a path relative", "buffer 0");
    write_buffer_gltf("sub/scheme.gltf", "file:///etc/passwd");
    imp_expect_error("sub/scheme.gltf", "not a path relative", NULL);
    snprintf(link, sizeof link, "%s/link.bin", sub);
    assert_int_equal(symlink(target, link), 0);
    write_buffer_gltf("sub/symlink.gltf", "link.bin");
    imp_expect_error("sub/symlink.gltf", "outside the scene's folder", NULL);
    /* the same files with the outside folder allowed */
    bk_import_options o;
    memset(&o, 0, sizeof o);
    char tmpdir[512];
    imp_tmp_path(tmpdir, sizeof tmpdir, "");
    o.allow_outside = tmpdir;
    const char *names[] = {"sub/escape.gltf", "sub/symlink.gltf"};
    for (int i = 0; i < 2; i++) {
        bk_scene s;
        char err[1024];
        int rc = imp_import_tmp(names[i], &s, &o, err, sizeof err);
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
    imp_expect_error("sub/inner.gltf", "outside the scene's folder", NULL);
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
        imp_write_file("trunc.glb", glb, (size_t)cuts[i]);
        imp_expect_error("trunc.glb", "truncated", NULL);
    }
    /* wrong version */
    unsigned char *copy = malloc((size_t)len);
    memcpy(copy, glb, (size_t)len);
    copy[4] = 1;
    imp_write_file("v1.glb", copy, (size_t)len);
    imp_expect_error("v1.glb", "version", NULL);
    /* BIN chunk length larger than the file says */
    memcpy(copy, glb, (size_t)len);
    uint32_t jlen;
    memcpy(&jlen, copy + 12, 4);
    uint32_t big = 0x7ffffff0u;
    memcpy(copy + 20 + jlen, &big, 4);
    imp_write_file("binlen.glb", copy, (size_t)len);
    imp_expect_error("binlen.glb", "BIN", NULL);
    /* flipped bytes in the middle of the BIN data: geometry changes but never crashes; the
     * import either succeeds or reports an error */
    memcpy(copy, glb, (size_t)len);
    for (long i = 20 + jlen + 8; i < len; i += 997) copy[i] ^= 0xff;
    imp_write_file("noise.glb", copy, (size_t)len);
    bk_scene s;
    char err[1024];
    if (imp_import_tmp("noise.glb", &s, NULL, err, sizeof err) == 0) bk_scene_free(&s);
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
    imp_write_file("WaterBottle.bin", bin, n);
    imp_write_text("bottle_noise.gltf", json);
    bk_scene s;
    char err[1024];
    bk_import_options opt = {0};
    opt.skip_textures = 1;
    if (imp_import_tmp("bottle_noise.gltf", &s, &opt, err, sizeof err) == 0) {
        imp_assert_valid(&s);
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
    imp_write_text("bottle_badid.gltf", json);
    assert_int_not_equal(imp_import_tmp("bottle_badid.gltf", &s, &opt, err, sizeof err), 0);
    assert_true(strstr(err, "Draco") != NULL || strstr(err, "KHR_draco") != NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_required_extension),
        cmocka_unit_test(test_malformed_accessors),
        cmocka_unit_test(test_malformed_structure),
        cmocka_unit_test(test_many_nodes),
        cmocka_unit_test(test_resource_policy),
        cmocka_unit_test(test_malformed_glb),
        cmocka_unit_test(test_draco_corrupt),
    };
    return cmocka_run_group_tests(tests, imp_setup_tmp, imp_teardown_tmp);
}
