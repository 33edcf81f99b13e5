/* lbk export: EXR/PNG writers, the preview tone map, decoded pages, probes, per-object images,
 * and the export → convert --from-exr round trip. */
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

#include "convert/image_io.h"

static char tmpdir[64];

static int setup_dir(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk-export-XXXXXX");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int teardown_dir(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

/* EXR float channels round-trip bit-exactly through the OpenEXR Core API, whatever order the
 * channels are named in (EXR sorts them; we match by name), including specials. */
static void test_exr_round_trip_exact(void **state)
{
    (void)state;
    const int w = 37, h = 19; /* more rows than one ZIP chunk (16) so chunking is exercised */
    const char *names[] = {"R", "G", "B", "ratio"};
    float *px = malloc(sizeof(float) * (size_t)(w * h * 4));
    for (int i = 0; i < w * h * 4; i++) px[i] = (float)(i % 97) * 0.37f - 3.0f + (float)i * 1e-3f;
    px[0] = INFINITY;
    px[5] = 1e-40f; /* denormal */
    px[6] = -0.0f;
    char path[128], err[TL_ERR_LEN];
    snprintf(path, sizeof path, "%s/rt.exr", tmpdir);
    assert_int_equal(tl_exr_write(path, w, h, 4, names, px, err), 0);
    /* read back in another order */
    const char *order[] = {"ratio", "B", "R", "G"};
    int rw, rh;
    float *back = NULL;
    assert_int_equal(tl_exr_read(path, 4, order, &rw, &rh, &back, err), 0);
    assert_int_equal(rw, w);
    assert_int_equal(rh, h);
    const int map[4] = {3, 2, 0, 1};
    for (int i = 0; i < w * h; i++)
        for (int c = 0; c < 4; c++) {
            uint32_t a, b;
            memcpy(&a, &px[i * 4 + map[c]], 4);
            memcpy(&b, &back[i * 4 + c], 4);
            if (a != b) fail_msg("pixel %d channel %s: %08x != %08x", i, order[c], a, b);
        }
    char listed[8][32];
    int count = 0;
    assert_int_equal(tl_exr_channels(path, listed, 8, &count, err), 0);
    assert_int_equal(count, 4);
    assert_string_equal(listed[0], "B"); /* sorted by name in the file */
    assert_string_equal(listed[3], "ratio");
    free(back);
    const char *missing[] = {"A"};
    assert_int_equal(tl_exr_read(path, 1, missing, &rw, &rh, &back, err), -1);
    assert_non_null(strstr(err, "channel 'A' is missing"));
    assert_null(back);
    free(px);
}

static void test_exr_errors(void **state)
{
    (void)state;
    char path[128], err[TL_ERR_LEN];
    snprintf(path, sizeof path, "%s/not.exr", tmpdir);
    FILE *f = fopen(path, "wb");
    fputs("this is not an EXR", f);
    fclose(f);
    const char *names[] = {"R"};
    int w, h;
    float *px = NULL;
    assert_int_equal(tl_exr_read(path, 1, names, &w, &h, &px, err), -1);
    assert_non_null(strstr(err, "cannot read EXR"));
    snprintf(path, sizeof path, "%s/absent.exr", tmpdir);
    assert_int_equal(tl_exr_read(path, 1, names, &w, &h, &px, err), -1);
    snprintf(path, sizeof path, "%s/nodir/x.exr", tmpdir);
    float one = 1;
    assert_int_equal(tl_exr_write(path, 1, 1, 1, names, &one, err), -1);
}

static void test_png_round_trip(void **state)
{
    (void)state;
    const int w = 5, h = 3;
    uint8_t rgb[5 * 3 * 3];
    for (int i = 0; i < w * h * 3; i++) rgb[i] = (uint8_t)(i * 17);
    char path[128], err[TL_ERR_LEN];
    snprintf(path, sizeof path, "%s/t.png", tmpdir);
    assert_int_equal(tl_png_write_rgb8(path, w, h, rgb, err), 0);
    int rw, rh;
    uint8_t *back = NULL;
    assert_int_equal(tl_png_read_rgb8(path, &rw, &rh, &back, err), 0);
    assert_int_equal(rw, w);
    assert_int_equal(rh, h);
    assert_memory_equal(back, rgb, sizeof rgb);
    free(back);
}

/* The documented tone map: exposure = 1 / 99th percentile luminance; sRGB OETF; 8 bits. */
static void test_tonemap_numbers(void **state)
{
    (void)state;
    /* sRGB reference points: 0 → 0, 1 → 255, 0.0031308 is the linear/curve knee (≈ 10.3),
     * 0.5 → 0.735357 → 188, 0.18 → 0.461356 → 118 */
    assert_int_equal(tl_srgb8(0.0f), 0);
    assert_int_equal(tl_srgb8(1.0f), 255);
    assert_int_equal(tl_srgb8(2.0f), 255);
    assert_int_equal(tl_srgb8(-1.0f), 0);
    assert_int_equal(tl_srgb8(NAN), 0);
    assert_int_equal(tl_srgb8(0.5f), 188);
    assert_int_equal(tl_srgb8(0.18f), 118);
    assert_int_equal(tl_srgb8(0.0031308f), 10);
    /* 200 grey pixels of luminance 1..200: the 99th percentile is pixel index round(0.99 · 199) = 197 → 198 */
    float px[200 * 3];
    for (int i = 0; i < 200; i++) px[3 * i] = px[3 * i + 1] = px[3 * i + 2] = (float)(i + 1);
    float e = tl_exposure_p99(px, 200, 3);
    assert_float_equal(e, 1.0f / 198.0f, 1e-7f);
    /* non-finite and non-positive pixels do not take part; none left → exposure 1 */
    float bad[6] = {NAN, NAN, NAN, -1, -1, -1};
    assert_float_equal(tl_exposure_p99(bad, 2, 3), 1.0f, 0);
    uint8_t out[3];
    float one[3] = {99.0f, 198.0f, 400.0f};
    tl_tonemap(one, 1, 3, e, out);
    assert_int_equal(out[0], tl_srgb8(0.5f));
    assert_int_equal(out[1], 255);
    assert_int_equal(out[2], 255);
}

static void test_heat_ramp(void **state)
{
    (void)state;
    uint8_t c[3];
    tl_heat_color(0.0f, c);
    assert_true(c[0] == 0 && c[1] == 0 && c[2] == 0);
    tl_heat_color(1.0f, c);
    assert_true(c[0] == 255 && c[1] == 255 && c[2] == 255);
    tl_heat_color(5.0f / 6.0f, c); /* red */
    assert_true(c[0] == 255 && c[1] == 0 && c[2] == 0);
    tl_heat_color(NAN, c);
    assert_true(c[0] == 255 && c[1] == 0 && c[2] == 255);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exr_round_trip_exact),
        cmocka_unit_test(test_exr_errors),
        cmocka_unit_test(test_png_round_trip),
        cmocka_unit_test(test_tonemap_numbers),
        cmocka_unit_test(test_heat_ramp),
    };
    return cmocka_run_group_tests(tests, setup_dir, teardown_dir);
}
