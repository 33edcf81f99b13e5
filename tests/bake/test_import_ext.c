/* glTF import as exporters write it (issue 37): EXT_texture_webp (a WebP image in a subfolder,
 * named by a percent-encoded UTF-8 URI, the extension required) imports and bakes;
 * KHR_texture_transform (scale, offset, rotation, texCoord override) is folded into the uv0 the
 * baker samples, checked through the transport's albedo lookup; KHR_texture_basisu is refused by
 * name when required and read through its fallback when only used (EXT_meshopt_compression is
 * decoded: test_import_meshopt.c); percent-encoded URIs stay confined to the scene's folder. */
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

#include <webp/encode.h>

#include "bake/transport/shading.h"
#include "scene/import.h"
#include "scene/scene.h"
#include "support/import_fixtures.h"

/* quaduv.bin: a unit floor quad in y = 0 facing +y (x right, -z away), uv0 = (x, -z), uv1 =
 * 0.5·uv0 + 0.25; 48 B positions, 12 B uint16 indices (0 1 2, 0 2 3), 32 B uv0, 32 B uv1. */
static void write_quaduv_bin(void)
{
    unsigned char buf[124];
    const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, -1};
    const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    const float uv0[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    float uv1[8];
    for (int i = 0; i < 8; i++) uv1[i] = 0.5f * uv0[i] + 0.25f;
    memcpy(buf, pos, 48);
    memcpy(buf + 48, idx, 12);
    memcpy(buf + 60, uv0, 32);
    memcpy(buf + 92, uv1, 32);
    imp_write_file("quaduv.bin", buf, sizeof buf);
}

/* A lossless 2×1 WebP: left texel black, right texel white (sRGB 0 and 255: linear 0 and 1). */
static void write_webp(const char *name)
{
    const uint8_t px[8] = {0, 0, 0, 255, 255, 255, 255, 255};
    uint8_t *out = NULL;
    size_t len = WebPEncodeLosslessRGBA(px, 2, 1, 8, &out);
    assert_true(len > 12);
    imp_write_file(name, out, len);
    WebPFree(out);
}

/* The floor glTF: `top` (extensionsUsed/Required), `images`, `textures` and the base colour
 * textureInfo `bct` spliced in; a second attribute set TEXCOORD_1 when uv1 is set. */
static void write_floor(const char *name, const char *top, const char *images, const char *textures,
                        const char *bct, int uv1)
{
    char json[8192];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},%s\"buffers\":[{\"uri\":\"quaduv.bin\",\"byteLength\":124}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},{\"buffer\":0,\"byteOffset\":60,\"byteLength\":32},"
             "{\"buffer\":0,\"byteOffset\":92,\"byteLength\":32}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
             "\"min\":[0,0,-1],\"max\":[1,0,0]},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
             "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
             "{\"bufferView\":3,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"}],"
             "\"images\":[%s],\"textures\":[%s],"
             "\"materials\":[{\"name\":\"floor\",\"pbrMetallicRoughness\":{\"metallicFactor\":0,"
             "\"baseColorTexture\":%s}}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":2%s},\"indices\":1,"
             "\"material\":0}]}],"
             "\"nodes\":[{\"name\":\"floor\",\"mesh\":0}],\"scenes\":[{\"nodes\":[0],\"extras\":{\"lbk_sky\":[1,1,1]}}],"
             "\"scene\":0}",
             top, images, textures, bct, uv1 ? ",\"TEXCOORD_1\":3" : "");
    imp_write_text(name, json);
}

static void mkdir_tmp(const char *name)
{
    char p[512];
    imp_tmp_path(p, sizeof p, name);
    assert_int_equal(mkdir(p, 0755), 0);
}

static const char *const kWebpTop = "\"extensionsUsed\":[\"EXT_texture_webp\",\"KHR_texture_transform\"],"
                                    "\"extensionsRequired\":[\"EXT_texture_webp\"],";
/* "textures/grass lossy ä.webp", percent-encoded as an engine exporter writes it */
static const char *const kWebpImage = "{\"uri\":\"textures%2Fgrass%20lossy%20%C3%A4.webp\",\"mimeType\":\"image/webp\"}";
static const char *const kWebpTexture = "{\"extensions\":{\"EXT_texture_webp\":{\"source\":0}}}";

static void setup_town(void)
{
    write_quaduv_bin();
    mkdir_tmp("textures");
    write_webp("textures/grass lossy \xc3\xa4.webp");
}

/* The albedo the transport samples at floor point x (z = -0.01: inside triangle 0, tex v = 0.01
 * or its transform), red channel. Triangle 0 is corners 0 1 2; at barycentrics (u, v) the point
 * is x = u + v, -z = v. */
static double albedo_at(const bk_scene *s, double x)
{
    const double v = 0.01, u = x - v;
    double uv[2], a[3];
    bk_tri_uv0(s, 0, u, v, uv);
    bk_material_albedo(s, &s->materials[s->tri_material[0]], uv, a);
    return a[0];
}

static void test_webp_percent_encoded_required(void **state)
{
    (void)state;
    setup_town();
    write_floor("town.gltf", kWebpTop, kWebpImage, kWebpTexture, "{\"index\":0}", 0);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("town.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.image_count, 1);
    assert_int_equal(s.materials[0].albedo_tex, 0);
    assert_int_equal(s.images[0].width, 2);
    assert_int_equal(s.images[0].height, 1);
    /* lossless: sRGB 0 → 0, sRGB 255 → 1 exactly */
    assert_float_equal(s.images[0].rgba[0], 0.0f, 0.0f);
    assert_float_equal(s.images[0].rgba[4], 1.0f, 0.0f);
    /* untransformed: x < 0.5 reads the black texel, x > 0.5 the white one (albedo clamped 0.999) */
    assert_float_equal(albedo_at(&s, 0.25), 0.0, 0.0);
    assert_float_equal(albedo_at(&s, 0.75), 0.999, 1e-12);
    bk_scene_free(&s);

    /* the WebP header's size is checked against the pixel cap before decoding: 2×1 > 1 */
    bk_import_options opt = {0};
    opt.max_image_pixels = 1;
    rc = imp_import_tmp("town.gltf", &s, &opt, err, sizeof err);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(err, "2x1 pixels exceeds the 1-pixel cap"));
    assert_null(s.positions);

    /* and it bakes (the whole pipeline, as `lbk bake`) */
    imp_bake_tmp("town.gltf", "town.lbk");
}

/* A file that says RIFF....WEBP but holds no valid bitstream: the texture is ignored (warned,
 * counted), the factor alone is used, as for an undecodable PNG. */
static void test_webp_corrupt_ignored(void **state)
{
    (void)state;
    setup_town();
    const char bad[32] = "RIFF\x18\0\0\0WEBPVP8 garbage-garbage";
    imp_write_file("textures/grass lossy \xc3\xa4.webp", bad, sizeof bad);
    write_floor("bad.gltf", kWebpTop, kWebpImage, kWebpTexture, "{\"index\":0}", 0);
    bk_scene s;
    char err[1024];
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    int rc = imp_import_tmp("bad.gltf", &s, &opt, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(rep.ignored_textures, 1);
    assert_int_equal(s.image_count, 0);
    assert_int_equal(s.materials[0].albedo_tex, -1);
    bk_scene_free(&s);

    /* a 26-byte lossless header claiming 16384×16384 (2^28 pixels, over the default 64 Mi cap):
     * refused from the header, before any decoding would allocate 1 GiB */
    const unsigned char huge[26] = {'R', 'I', 'F', 'F', 18, 0, 0, 0, 'W', 'E', 'B', 'P', 'V', 'P', '8', 'L',
                                    5, 0, 0, 0, 0x2f, 0xff, 0xff, 0xff, 0x0f, 0};
    imp_write_file("textures/grass lossy \xc3\xa4.webp", huge, sizeof huge);
    imp_expect_error("bad.gltf", "16384x16384 pixels exceeds the", "pixel cap");
}

/* A floor whose base colour is half black / half white, tiled 4× by KHR_texture_transform: the
 * albedo at x is white iff frac(4x) ≥ 0.5. 64 points at texel-cell centres (frac(4x) = 0.25 or
 * 0.75 ± 1/128) all agree; without the transform half of them would not. */
static void test_transform_scale_tiles_albedo(void **state)
{
    (void)state;
    setup_town();
    write_floor("tiled.gltf", kWebpTop, kWebpImage, kWebpTexture,
                "{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"scale\":[4,4]}}}", 0);
    bk_scene s;
    char err[1024];
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    int rc = imp_import_tmp("tiled.gltf", &s, &opt, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(rep.ignored_textures, 0);
    int white = 0, untiled_disagree = 0;
    for (int i = 0; i < 64; i++) {
        const double x = 0.0390625 + i / 64.0 * 0.9375; /* in (0.039, 0.98): inside triangle 0 */
        const double f = 4 * x - floor(4 * x);
        const double want = f >= 0.5 ? 0.999 : 0.0;
        assert_float_equal(albedo_at(&s, x), want, 1e-12);
        white += want > 0;
        untiled_disagree += (x >= 0.5) != (f >= 0.5);
    }
    assert_true(white >= 28 && white <= 36);
    assert_true(untiled_disagree >= 16); /* the check can tell tiled from untiled */
    bk_scene_free(&s);
}

/* offset [0.5, 0.25], rotation π/2, scale [2, 3] on TEXCOORD_1 (the override): uv' = T·R·S·uv1 with
 * R = [cos r, sin r; -sin r, cos r] (KhronosGroup/glTF#1563, as implementations and the sample
 * model): u' = 3·v1 + 0.5, v' = -2·u1 + 0.25, uv1 = 0.5·uv0 + 0.25. */
static void test_transform_offset_rotation_texcoord(void **state)
{
    (void)state;
    setup_town();
    write_floor("rot.gltf", kWebpTop, kWebpImage, kWebpTexture,
                "{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0.25],"
                "\"rotation\":1.5707963267948966,\"scale\":[2,3],\"texCoord\":1}}}", 1);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("rot.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    /* no NORMAL: flat shading gives every triangle corner its own vertex, corner c of triangle t
     * being glTF vertex {0 1 2, 0 2 3}[3t + c] */
    assert_int_equal(s.tri_count, 2);
    const float uv0[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const int src[6] = {0, 1, 2, 0, 2, 3};
    for (int c = 0; c < 6; c++) {
        const uint32_t vtx = s.tris[c];
        assert_true(vtx < s.vertex_count);
        const double u1 = 0.5 * uv0[2 * src[c]] + 0.25, v1 = 0.5 * uv0[2 * src[c] + 1] + 0.25;
        assert_float_equal(s.uv0[2 * vtx], 3 * v1 + 0.5, 1e-6);
        assert_float_equal(s.uv0[2 * vtx + 1], -2 * u1 + 0.25, 1e-6);
    }
    bk_scene_free(&s);

    /* a non-finite or malformed transform is refused, by material and slot */
    write_floor("rot_bad.gltf", kWebpTop, kWebpImage, kWebpTexture,
                "{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"scale\":[4]}}}", 0);
    imp_expect_error("rot_bad.gltf", "baseColor texture", "scale must be 2 finite numbers");
}

static void test_basisu(void **state)
{
    (void)state;
    setup_town();
    /* required, no fallback: refused by name (the extension, the texture and its image file) */
    write_floor("basis_req.gltf",
                "\"extensionsUsed\":[\"KHR_texture_basisu\"],\"extensionsRequired\":[\"KHR_texture_basisu\"],",
                "{\"uri\":\"textures/grass.ktx2\",\"mimeType\":\"image/ktx2\"}",
                "{\"name\":\"grass\",\"extensions\":{\"KHR_texture_basisu\":{\"source\":0}}}", "{\"index\":0}", 0);
    imp_expect_error("basis_req.gltf", "requires glTF extension KHR_texture_basisu (used by texture 0 \"grass\" "
                     "(image 0 \"textures/grass.ktx2\"))", "cannot decode");
    /* only used, a WebP fallback as the core source: the fallback is what is read */
    write_floor("basis_used.gltf", "\"extensionsUsed\":[\"KHR_texture_basisu\",\"EXT_texture_webp\"],",
                "{\"uri\":\"textures/grass.ktx2\",\"mimeType\":\"image/ktx2\"},"
                "{\"uri\":\"textures/grass%20lossy%20%C3%A4.webp\"}",
                "{\"source\":1,\"extensions\":{\"KHR_texture_basisu\":{\"source\":0}}}", "{\"index\":0}", 0);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("basis_used.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(s.image_count, 1);
    assert_int_equal(s.materials[0].albedo_tex, 0);
    assert_float_equal(albedo_at(&s, 0.75), 0.999, 1e-12);
    bk_scene_free(&s);
}

/* Percent-decoding cannot leave the scene's folder: an encoded "../" and an encoded NUL are
 * refused as before. */
static void test_percent_encoded_confined(void **state)
{
    (void)state;
    setup_town();
    write_floor("esc.gltf", kWebpTop, "{\"uri\":\"textures%2F..%2F..%2Flbk_import_ext_outside.webp\"}", kWebpTexture,
                "{\"index\":0}", 0);
    /* the file exists one folder above the scene's */
    char p[512];
    imp_tmp_path(p, sizeof p, "../lbk_import_ext_outside.webp");
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    fputs("RIFF", f);
    fclose(f);
    imp_expect_error("esc.gltf", "image 0", "outside");
    remove(p);
    write_floor("nul.gltf", kWebpTop, "{\"uri\":\"textures%2Fgrass%00.webp\"}", kWebpTexture, "{\"index\":0}", 0);
    imp_expect_error("nul.gltf", "NUL byte", NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_webp_percent_encoded_required, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_webp_corrupt_ignored, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_transform_scale_tiles_albedo, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_transform_offset_rotation_texcoord, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_basisu, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_percent_encoded_confined, imp_setup_tmp, imp_teardown_tmp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
