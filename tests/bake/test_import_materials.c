/* The KHR_materials_* extensions the importer reads (spec/authoring.md "Material extensions"):
 * a KHR_materials_pbrSpecularGlossiness material's diffuse is looked up by the transport exactly
 * as the equivalent metallic-roughness base colour (factor x texture, texel by texel) and takes
 * the Lambertian path; transmission and diffuse_transmission scale the diffuse albedo by
 * 1 - factor; unlit keeps its base colour and emits nothing; the extensions that do not change
 * the diffuse albedo or the emission leave the material alone with one warning each, naming the
 * extension and the material (KHR_materials_variants: one for the file); required, only the
 * honoured or approximated ones are accepted. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/transport/shading.h"
#include "scene/import.h"
#include "scene/scene.h"
#include "support/import_fixtures.h"
#include "tools/common/image_io.h"

/* floor.bin: a unit floor quad in y = 0 facing +y, uv0 = (x, -z); 48 B positions, 12 B uint16
 * indices (0 1 2, 0 2 3), 32 B uv0. tex.png: 2x1, left texel black, right texel white. */
static void write_inputs(void)
{
    unsigned char buf[92];
    const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, -1};
    const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    const float uv0[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    memcpy(buf, pos, 48);
    memcpy(buf + 48, idx, 12);
    memcpy(buf + 60, uv0, 32);
    imp_write_file("floor.bin", buf, sizeof buf);
    const uint8_t px[6] = {0, 0, 0, 255, 255, 255};
    char p[512], err[TL_ERR_LEN];
    imp_tmp_path(p, sizeof p, "tex.png");
    assert_int_equal(tl_png_write_rgb8(p, 2, 1, px, err), 0);
}

/* The floor glTF with `top` (extensionsUsed/Required) and the one material `material` spliced in;
 * texture 0 reads tex.png. */
static void write_floor(const char *name, const char *top, const char *material)
{
    char json[8192];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},%s\"buffers\":[{\"uri\":\"floor.bin\",\"byteLength\":92}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},{\"buffer\":0,\"byteOffset\":60,\"byteLength\":32}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
             "\"min\":[0,0,-1],\"max\":[1,0,0]},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
             "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"}],"
             "\"images\":[{\"uri\":\"tex.png\"}],\"textures\":[{\"source\":0}],\"materials\":[%s],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":2},\"indices\":1,"
             "\"material\":0}]}],"
             "\"nodes\":[{\"name\":\"floor\",\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
             top, material);
    imp_write_text(name, json);
}

/* Warnings collected from an import. */
typedef struct {
    char text[8][512];
    int n;
} warnings;

static void on_warn(void *user, const char *message)
{
    warnings *w = user;
    if (w->n < 8) snprintf(w->text[w->n], sizeof w->text[0], "%s", message);
    w->n++;
}

static int import_floor(const char *name, bk_scene *s, warnings *w)
{
    bk_import_options opt = {0};
    opt.warn = on_warn;
    opt.warn_user = w;
    char err[1024];
    memset(w, 0, sizeof *w);
    int rc = imp_import_tmp(name, s, &opt, err, sizeof err);
    if (rc) printf("%s\n", err);
    return rc;
}

/* How many warnings hold both needles. */
static int count_warnings(const warnings *w, const char *a, const char *b)
{
    int n = 0;
    for (int i = 0; i < w->n && i < 8; i++) n += strstr(w->text[i], a) && strstr(w->text[i], b);
    return n;
}

/* The albedo the transport samples at floor point (x, z = -0.01), inside triangle 0. */
static void albedo_at(const bk_scene *s, double x, double a[3])
{
    const double v = 0.01, u = x - v;
    double uv[2];
    bk_tri_uv0(s, 0, u, v, uv);
    bk_material_albedo(s, &s->materials[s->tri_material[0]], uv, a);
}

static const double kFactor[3] = {0.8, 0.5, 0.25};

static void test_spec_gloss_diffuse_is_base_colour(void **state)
{
    (void)state;
    write_inputs();
    write_floor("mr.gltf", "",
                "{\"name\":\"mr\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.5,0.25,1],"
                "\"metallicFactor\":0,\"baseColorTexture\":{\"index\":0}}}");
    /* required: lbk honours the diffuse, so the file is accepted */
    write_floor("sg.gltf",
                "\"extensionsUsed\":[\"KHR_materials_pbrSpecularGlossiness\"],"
                "\"extensionsRequired\":[\"KHR_materials_pbrSpecularGlossiness\"],",
                "{\"name\":\"sg\",\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{"
                "\"diffuseFactor\":[0.8,0.5,0.25,1],\"specularFactor\":[0.9,0.9,0.9],\"glossinessFactor\":0.25,"
                "\"diffuseTexture\":{\"index\":0}}}}");
    bk_scene mr, sg;
    warnings w;
    assert_int_equal(import_floor("mr.gltf", &mr, &w), 0);
    assert_int_equal(import_floor("sg.gltf", &sg, &w), 0);
    assert_int_equal(w.n, 0);
    const bk_material *m = &sg.materials[sg.tri_material[0]];
    assert_int_equal(m->albedo_tex, 0);
    assert_false(bk_material_glossy(m)); /* a dielectric: the Lambertian path, as mr's */
    assert_float_equal(m->roughness, 0.75f, 1e-6f);
    for (int i = 0; i < 8; i++) {
        const double x = 0.05 + 0.9 * i / 7.0; /* across the black and the white texel */
        double a[3], b[3];
        albedo_at(&mr, x, a);
        albedo_at(&sg, x, b);
        for (int k = 0; k < 3; k++) assert_float_equal(b[k], a[k], 1e-9);
    }
    /* the lookups are the factor times the texture, not a constant */
    double a0[3], a1[3];
    albedo_at(&sg, 0.02, a0);
    albedo_at(&sg, 0.98, a1);
    for (int k = 0; k < 3; k++) {
        assert_true(a0[k] < 0.2 * kFactor[k]);
        assert_true(a1[k] > 0.8 * kFactor[k] && a1[k] <= kFactor[k] + 1e-6);
    }
    bk_scene_free(&mr);
    bk_scene_free(&sg);
}

static void test_transmission_scales_diffuse(void **state)
{
    (void)state;
    write_inputs();
    write_floor("glass.gltf", "\"extensionsUsed\":[\"KHR_materials_transmission\"],",
                "{\"name\":\"glass\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.5,0.25,1],"
                "\"metallicFactor\":0},\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.75}}}");
    write_floor("leaf.gltf", "\"extensionsUsed\":[\"KHR_materials_diffuse_transmission\"],",
                "{\"name\":\"leaf\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.5,0.25,1],"
                "\"metallicFactor\":0},\"extensions\":{\"KHR_materials_diffuse_transmission\":"
                "{\"diffuseTransmissionFactor\":0.5}}}");
    const char *files[2] = {"glass.gltf", "leaf.gltf"}, *names[2] = {"glass", "leaf"};
    const char *exts[2] = {"KHR_materials_transmission", "KHR_materials_diffuse_transmission"};
    const double keep[2] = {0.25, 0.5};
    for (int f = 0; f < 2; f++) {
        bk_scene s;
        warnings w;
        assert_int_equal(import_floor(files[f], &s, &w), 0);
        for (int k = 0; k < 3; k++) assert_float_equal(s.materials[0].albedo[k], kFactor[k] * keep[f], 1e-6);
        assert_int_equal(w.n, 1);
        assert_int_equal(count_warnings(&w, exts[f], names[f]), 1);
        bk_scene_free(&s);
    }
}

static void test_unlit_and_ignored(void **state)
{
    (void)state;
    write_inputs();
    write_floor("unlit.gltf",
                "\"extensionsUsed\":[\"KHR_materials_unlit\"],\"extensionsRequired\":[\"KHR_materials_unlit\"],",
                "{\"name\":\"flat\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.5,0.25,1],"
                "\"metallicFactor\":0},\"extensions\":{\"KHR_materials_unlit\":{}}}");
    bk_scene s;
    warnings w;
    assert_int_equal(import_floor("unlit.gltf", &s, &w), 0);
    for (int k = 0; k < 3; k++) {
        assert_float_equal(s.materials[0].albedo[k], kFactor[k], 1e-6);
        assert_float_equal(s.materials[0].emission[k], 0.0f, 0.0f);
    }
    assert_int_equal(w.n, 1);
    assert_int_equal(count_warnings(&w, "KHR_materials_unlit", "flat"), 1);
    bk_scene_free(&s);

    write_floor("coat.gltf",
                "\"extensionsUsed\":[\"KHR_materials_clearcoat\",\"KHR_materials_sheen\",\"KHR_materials_ior\","
                "\"KHR_materials_variants\"],",
                "{\"name\":\"coat\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.5,0.25,1],"
                "\"metallicFactor\":0},\"extensions\":{\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1},"
                "\"KHR_materials_sheen\":{\"sheenColorFactor\":[1,0,0]},\"KHR_materials_ior\":{\"ior\":1.2}}}");
    assert_int_equal(import_floor("coat.gltf", &s, &w), 0);
    for (int k = 0; k < 3; k++) assert_float_equal(s.materials[0].albedo[k], kFactor[k], 1e-6);
    assert_int_equal(w.n, 4);
    assert_int_equal(count_warnings(&w, "KHR_materials_variants", "default material"), 1);
    assert_int_equal(count_warnings(&w, "KHR_materials_clearcoat", "coat"), 1);
    assert_int_equal(count_warnings(&w, "KHR_materials_sheen", "coat"), 1);
    assert_int_equal(count_warnings(&w, "KHR_materials_ior", "coat"), 1);
    bk_scene_free(&s);
}

static void test_required_and_malformed(void **state)
{
    (void)state;
    write_inputs();
    write_floor("req.gltf",
                "\"extensionsUsed\":[\"KHR_materials_transmission\"],"
                "\"extensionsRequired\":[\"KHR_materials_transmission\"],",
                "{\"name\":\"glass\",\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":1}}}");
    imp_expect_error("req.gltf", "requires glTF extension KHR_materials_transmission", NULL);
    write_floor("bad.gltf", "\"extensionsUsed\":[\"KHR_materials_pbrSpecularGlossiness\"],",
                "{\"name\":\"odd\",\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{"
                "\"diffuseFactor\":[0.8,0.5,0.25]}}}");
    imp_expect_error("bad.gltf", "diffuseFactor", "\"odd\"");
    write_floor("badt.gltf", "\"extensionsUsed\":[\"KHR_materials_transmission\"],",
                "{\"name\":\"odd\",\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":2}}}");
    imp_expect_error("badt.gltf", "transmissionFactor", "\"odd\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_spec_gloss_diffuse_is_base_colour, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_transmission_scales_diffuse, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_unlit_and_ignored, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_required_and_malformed, imp_setup_tmp, imp_teardown_tmp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
