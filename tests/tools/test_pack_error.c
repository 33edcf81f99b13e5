/* The pack error lbk convert reports (tools/convert/pack_error.h): bounds that follow from the
 * codecs, the seam and shared-block texels of a known layout, and zero where nothing is lost. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>
#include <unistd.h>

#include "cli/cli.h"
#include "tools/common/file_util.h"
#include "tools/convert/convert.h"
#include "tools/convert/pack_error.h"
#include "tools/convert/profile.h"
#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/objects.h"
#include "lbk/pixel.h"

/* One 16×16 page, two objects: "left" rect (0,0,6,16) and "right" rect (6,0,10,16), so the
 * blocks of columns 4..7 hold texels of both (a shared block column). */
#define W 16
#define H 16

typedef void (*texel_fn)(uint32_t x, uint32_t y, float rgb[3]);

static void add(lbk_writer *w, uint32_t type, void *data, size_t size)
{
    lbk_section_options so = LBK_SECTION_OPTIONS_INIT;
    so.flags = LBK_SECTION_FLAG_REQUIRED;
    assert_int_equal(lbk_writer_section_add(w, type, data, size, &so), LBK_OK);
    lbk_free(NULL, data);
}

/* Every texel pure ambient (ratio 1: the irradiance is plane 0 at every normal), plane 0 = f. */
static void build(texel_fn f, void **bytes, size_t *size)
{
    lbk_object objs[2];
    memset(objs, 0, sizeof objs);
    objs[0].name = (lbk_string){"left", 4};
    objs[1].name = (lbk_string){"right", 5};
    for (int i = 0; i < 2; i++) {
        objs[i].geometry_hash = 0x100u + (uint64_t)i;
        objs[i].representation = LBK_REPRESENTATION_LIGHTMAP;
        objs[i].rect_y = 0, objs[i].rect_h = H;
    }
    objs[0].rect_x = 0, objs[0].rect_w = 6;
    objs[1].rect_x = 6, objs[1].rect_w = W - 6;
    lbk_ahd_texel tex[W * H];
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            float rgb[3];
            f(x, y, rgb);
            tex[y * W + x] = (lbk_ahd_texel){lbk_r11g11b10f_pack(rgb), {255, 128, 128, 255}};
        }
    lbk_writer *w = NULL;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    void *data;
    size_t n;
    assert_int_equal(lbk_objects_build(objs, 2, NULL, &data, &n), LBK_OK);
    add(w, LBK_SECTION_OBJS, data, n);
    const lbk_lmap_page_desc page = {W, H, tex};
    const lbk_lmap_build_desc lb = {.pages = &page, .page_count = 1, .scale = 1.0f};
    assert_int_equal(lbk_lmap_build(&lb, NULL, &data, &n), LBK_OK);
    add(w, LBK_SECTION_LMAP, data, n);
    assert_int_equal(lbk_writer_to_memory(w, bytes, size), LBK_OK);
    lbk_writer_close(w);
}

/* Converts with planes p0 + p1 and returns the pack error. */
static tl_pack_error convert(texel_fn f, const char *p0, const char *p1)
{
    char text[256], err[TL_ERR_LEN] = "";
    snprintf(text, sizeof text, "name = t\nalignment = 16\n[sections]\ndefault = none\n[lmap]\nplane0 = %s\nplane1 = %s\n",
             p0, p1);
    tl_profile prof;
    assert_int_equal(tl_profile_parse(text, strlen(text), "t.profile", &prof, err), 0);
    void *in, *out;
    size_t in_size, out_size;
    build(f, &in, &in_size);
    tl_pack_error pe;
    tl_convert_report rep;
    tl_convert_options o = {.profile = &prof, .pack_error = &pe};
    const tl_convert_status st = tl_convert_memory(in, in_size, &o, &out, &out_size, &rep, err);
    if (st != TL_CONVERT_OK) fprintf(stderr, "convert: %s\n", err);
    assert_int_equal(st, TL_CONVERT_OK);
    assert_int_equal(rep.pack_error_computed, 1);
    lbk_free(NULL, in);
    free(out);
    return pe;
}

static void constant(uint32_t x, uint32_t y, float rgb[3])
{
    (void)x, (void)y;
    rgb[0] = 1.5f, rgb[1] = 2.0f, rgb[2] = 0.75f; /* exact in R11G11B10F and in half floats */
}

/* 2 % more per texel to the right, warm-tinted: the smooth HDR ramp lightmaps are made of. */
static void gradient(uint32_t x, uint32_t y, float rgb[3])
{
    const float v = 0.5f * powf(1.02f, (float)x) * (1.0f + 0.01f * (float)y);
    rgb[0] = 1.2f * v, rgb[1] = v, rgb[2] = 0.7f * v;
}

/* A dark left object next to a bright right one: they meet inside the shared block column. */
static void step(uint32_t x, uint32_t y, float rgb[3])
{
    (void)y;
    const float v = x < 6 ? 0.05f : 50.0f;
    rgb[0] = rgb[1] = rgb[2] = v;
}

/* Nothing is lost when the planes stay 1.0 texels: every error is exactly 0, over every texel at
 * the five normals; the seam and shared-block texels are those of the layout. */
static void test_layout_and_lossless(void **state)
{
    (void)state;
    tl_pack_error pe = convert(gradient, "r11g11b10f", "rgba8");
    assert_int_equal(pe.texels, W * H);
    assert_int_equal(pe.all.lum.samples, 5 * W * H);
    assert_true(pe.all.lum.max == 0 && pe.all.colour.max == 0 && pe.seam.lum.max == 0);
    /* columns 4..7: the blocks both rectangles touch */
    assert_int_equal(pe.shared_block_texels, 4 * H);
    assert_int_equal(pe.shared.lum.samples, 5 * 4 * H);
    assert_int_equal(pe.object_count, 2);
    assert_string_equal(pe.objects[0].name, "left");
    assert_string_equal(pe.objects[1].name, "right");
    assert_int_equal(pe.objects[0].texels, 6 * H);
    /* seams: within 2 texels of the other chart or the page's edge. left (6 wide): only x 2..3,
     * y 2..13 are farther (24 texels); right (10 wide): x 8..13, y 2..13 (72 texels) */
    assert_int_equal(pe.objects[0].seam.lum.samples, 5 * (6 * H - 24));
    assert_int_equal(pe.objects[1].seam.lum.samples, 5 * (10 * H - 72));
    assert_int_equal(pe.seam.lum.samples, 5 * (6 * H - 24 + 10 * H - 72));
    tl_pack_error_free(&pe);
}

/* A constant page: BC6H stores it within the half-float quantisation (10 mantissa bits; the
 * format's final ×31/64 scaling truncates, so 1 unit in the last place: relative 2^-10), BC4
 * holds the ratio 1 exactly; no chroma shift beyond that. ASTC HDR the same (FP16 endpoints). */
static void test_constant_page_within_half_quantisation(void **state)
{
    (void)state;
    static const char *const planes[][2] = {{"bc6h", "bc5_bc4"}, {"astc4x4_hdr", "astc4x4"}};
    for (int k = 0; k < 2; k++) {
        tl_pack_error pe = convert(constant, planes[k][0], planes[k][1]);
        assert_int_equal(pe.all.lum.samples, 5 * W * H);
        assert_true(pe.all.lum.max <= ldexp(1.0, -10));
        assert_true(pe.all.colour.max <= 1e-3);
        for (uint32_t i = 0; i < pe.object_count; i++) assert_true(pe.objects[i].all.lum.max <= ldexp(1.0, -10));
        tl_pack_error_free(&pe);
    }
}

/* A 2 %/texel ramp: the BC6H encoder's measured accuracy on such gradients is mean 0.0011, worst
 * 0.014 (tools/convert/profiles/README.md); the bounds leave room for the extra y slope only. */
static void test_gradient_within_encoder_bound(void **state)
{
    (void)state;
    tl_pack_error pe = convert(gradient, "bc6h", "bc5_bc4");
    assert_true(pe.all.lum.mean > 0); /* it is lossy: the measure sees it */
    assert_true(pe.all.lum.mean <= 0.003);
    assert_true(pe.all.lum.max <= 0.02);
    assert_true(pe.all.lum.p99 <= pe.all.lum.max);
    assert_true(pe.all.lum.p99 >= pe.all.lum.mean);
    tl_pack_error_free(&pe);
}

/* A 1000:1 step where two objects share blocks: each object gets its own BC6H region (the
 * encoder splits at the rectangles), so both sides stay within a few half-float steps even
 * though one line through the block could not hold both. */
static void test_step_between_objects(void **state)
{
    (void)state;
    tl_pack_error pe = convert(step, "bc6h", "bc5_bc4");
    assert_int_equal(pe.shared.lum.samples, 5 * 4 * H);
    assert_true(pe.all.lum.max <= 0.02);
    assert_true(pe.shared.lum.max <= 0.02);
    tl_pack_error_free(&pe);
}

/* lbk convert --json: the document (schema lbk-convert/1) carries the pack error the library
 * computes, per object too; a 1.0 profile has none (its texels are the input's). */
static void test_cli_json(void **state)
{
    (void)state;
    char dir[] = "/tmp/lbk_pack_error_XXXXXX", in[64], out[64], json[64], err[TL_ERR_LEN];
    assert_non_null(mkdtemp(dir));
    snprintf(in, sizeof in, "%s/in.lbk", dir);
    snprintf(out, sizeof out, "%s/out.lbk", dir);
    snprintf(json, sizeof json, "%s/out.json", dir);
    void *bytes;
    size_t size;
    build(gradient, &bytes, &size);
    assert_int_equal(tl_write_file_atomic(in, bytes, size, err), 0);
    lbk_free(NULL, bytes);
    tl_pack_error pe = convert(gradient, "bc6h", "bc5_bc4");
    static const char *const profiles[] = {"console-current", "pc"};
    for (int k = 0; k < 2; k++) {
        const char *argv[] = {"convert", in, "-o", out, "--profile", profiles[k], "--json", NULL};
        fflush(stdout);
        const int saved = dup(1);
        FILE *f = fopen(json, "w");
        assert_non_null(f);
        dup2(fileno(f), 1);
        const int rc = lbk_cmd_convert(7, (char **)argv);
        fflush(stdout);
        dup2(saved, 1);
        close(saved);
        fclose(f);
        assert_int_equal(rc, LBK_EXIT_OK);
        void *text;
        size_t n;
        assert_int_equal(tl_read_file(json, &text, &n, err), 0);
        char *t = realloc(text, n + 1);
        assert_non_null(t);
        t[n] = 0;
        cJSON *j = cJSON_Parse(t);
        free(t);
        assert_non_null(j);
        assert_string_equal(cJSON_GetObjectItem(j, "schema")->valuestring, "lbk-convert/1");
        const cJSON *e = cJSON_GetObjectItem(j, "pack_error");
        if (k) {
            assert_true(cJSON_IsNull(e));
        } else {
            /* console-current is BC6H + BC5/BC4 as convert() above: the same pack, the same error */
            const cJSON *lum = cJSON_GetObjectItem(cJSON_GetObjectItem(e, "all"), "luminance");
            assert_true(fabs(cJSON_GetObjectItem(lum, "mean")->valuedouble - pe.all.lum.mean) <= 1e-12);
            assert_true(fabs(cJSON_GetObjectItem(lum, "max")->valuedouble - pe.all.lum.max) <= 1e-12);
            const cJSON *objs = cJSON_GetObjectItem(e, "objects");
            assert_int_equal(cJSON_GetArraySize(objs), 2);
            assert_string_equal(cJSON_GetObjectItem(cJSON_GetArrayItem(objs, 1), "name")->valuestring, "right");
            assert_true(cJSON_IsBool(cJSON_GetObjectItem(cJSON_GetObjectItem(e, "goal"), "met")));
        }
        cJSON_Delete(j);
    }
    tl_pack_error_free(&pe);
    unlink(in), unlink(out), unlink(json), rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layout_and_lossless),
        cmocka_unit_test(test_constant_page_within_half_quantisation),
        cmocka_unit_test(test_gradient_within_encoder_bound),
        cmocka_unit_test(test_step_between_objects),
        cmocka_unit_test(test_cli_json),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
