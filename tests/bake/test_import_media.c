/* glTF import of images: the EXR sky (scanline and tiled, channels the reader does not use),
 * base colour and emissive textures (PNG files and GLB-embedded), and the metallicRoughness
 * texture and factors. */
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
#include "support/import_fixtures.h"

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
    imp_tmp_path(p, sizeof p, name);
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
    imp_tmp_path(p, sizeof p, name);
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
    imp_write_quad_bin();
    write_exr("sky.exr", 8, 4, 1.0f);
    imp_write_quad_gltf_scene_extras("sky_exr.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"sky.exr\"}");
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("sky_exr.gltf", &s, NULL, err, sizeof err);
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
    assert_int_equal(imp_import_tmp("sky_exr.gltf", &s, &opt, err, sizeof err), 0);
    assert_int_equal(s.images[0].width, 4);
    assert_int_equal(s.images[0].height, 2);
    assert_float_equal(s.images[0].rgba[0], 1.5f, 1e-6); /* R of (0..1, 0..1) = (1+2)/2 */
    assert_float_equal(s.images[0].rgba[1], 1.5f, 1e-6); /* G = (1+2)/2 */
    assert_float_equal(s.sky[0], 4.5f, 1e-5);
    bk_scene_free(&s);

    /* a pixel cap smaller than the image refuses it before allocating */
    opt.max_sky_size = 0;
    opt.max_image_pixels = 16;
    assert_int_not_equal(imp_import_tmp("sky_exr.gltf", &s, &opt, err, sizeof err), 0);
    assert_non_null(strstr(err, "cap"));

    /* tiled, half floats, 5×3 in 2×2 tiles (partial tiles on the right and bottom) */
    write_tiled_exr("tiled.exr", 5, 3, 2, 2);
    imp_write_quad_gltf_scene_extras("sky_tiled.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"tiled.exr\"}");
    rc = imp_import_tmp("sky_tiled.gltf", &s, NULL, err, sizeof err);
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
    imp_write_text("junk.exr", "this is not an EXR file at all, sorry");
    imp_write_quad_gltf_scene_extras("sky_junk.gltf", "{\"mesh\":0}", "0", "{\"lbk_sky\":\"junk.exr\"}");
    imp_expect_error("sky_junk.gltf", "junk.exr", NULL);
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
    imp_write_file(name, png, len);
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
    imp_write_file("embedded.glb", glb, total);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("embedded.glb", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    imp_assert_valid(&s);
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
    imp_write_file("embedded_bad.glb", glb, total);
    bk_import_report rep;
    bk_import_options opt = {0};
    opt.report = &rep;
    assert_int_equal(imp_import_tmp("embedded_bad.glb", &s, &opt, err, sizeof err), 0);
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
    imp_write_quad_bin();
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
    imp_write_text("tex2.gltf", json);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("tex2.gltf", &s, NULL, err, sizeof err);
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
    assert_int_equal(imp_import_tmp("tex2.gltf", &s, &opt, err, sizeof err), 0);
    assert_int_equal(s.images[0].width, 2);
    assert_int_equal(s.images[0].height, 1);
    assert_float_equal(s.images[0].rgba[0], (1.0f + 0.2158605f) / 2, 1e-6);
    assert_int_equal(rep.downsampled_images, 1);
    bk_scene_free(&s);

    /* a needed texture that cannot be read is an error naming it */
    char *t = strstr(json, "tex.png");
    char json2[4096];
    snprintf(json2, sizeof json2, "%.*s%s%s", (int)(t - json), json, "missing.png", t + strlen("tex.png"));
    imp_write_text("tex_missing.gltf", json2);
    imp_expect_error("tex_missing.gltf", "image 0", "missing.png");
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
    imp_write_quad_bin();
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
    imp_write_text("mr.gltf", json);
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp("mr.gltf", &s, NULL, err, sizeof err);
    if (rc) printf("%s\n", err);
    assert_int_equal(rc, 0);
    imp_assert_valid(&s);
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
    imp_write_text("mr_bad.gltf", json);
    rc = imp_import_tmp("mr_bad.gltf", &s, NULL, err, sizeof err);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(err, "metallicFactor"));
    assert_non_null(strstr(err, "bad"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sky_exr),
        cmocka_unit_test(test_exr_unused_channel),
        cmocka_unit_test(test_textures),
        cmocka_unit_test(test_metallic_roughness),
        cmocka_unit_test(test_glb_embedded_texture),
    };
    return cmocka_run_group_tests(tests, imp_setup_tmp, imp_teardown_tmp);
}
