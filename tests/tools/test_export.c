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
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cli/cli.h"
#include "tools/convert/convert.h"
#include "tools/convert/export.h"
#include "tools/common/file_util.h"
#include "tools/common/image_io.h"
#include "tools/convert/lmap_layout.h"
#include "lbk/container.h"
#include "lbk/pixel.h"
#include "support/tools_fixtures.h"

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


/* ---- export of a bake ---------------------------------------------------------------------- */

static void export_fixture(const char *sub, int per_object, int png, tl_bake *b, char *dir, size_t dir_size)
{
    tf_blob blob = tf_build_scene(TF_SCENE_FULL, NULL);
    char err[TL_ERR_LEN];
    if (tl_bake_open_memory(blob.data, blob.size, b, err) != TL_OPEN_OK) fail_msg("%s", err);
    tf_blob_free(&blob);
    snprintf(dir, dir_size, "%s/%s", tmpdir, sub);
    tl_export_options o = {dir, png ? dir : NULL, per_object};
    tl_export_stats st;
    if (tl_export(b, &o, &st, err)) fail_msg("%s", err);
    assert_int_equal(st.exr_files, 2 * 3 + (per_object ? 3 : 0));
}

static uint32_t rd32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

/* page_NNN.exr holds exactly the decoded R11G11B10F plane; .ahd.exr exactly plane 1 / 255;
 * .dominant.exr the irradiance at the stored direction (never below the +Z irradiance). */
static void test_export_pages_equal_decoded(void **state)
{
    (void)state;
    tl_bake b;
    char dir[128], path[256], err[TL_ERR_LEN];
    export_fixture("pages", 0, 0, &b, dir, sizeof dir);
    for (uint32_t p = 0; p < 2; p++) {
        lbk_lmap_page pg;
        assert_int_equal(lbk_lmap_page_get(&b.lmap, p, &pg), LBK_OK);
        const char *rgb[] = {"R", "G", "B"};
        const char *ahd[] = {"plane0.R", "plane0.G", "plane0.B", "plane1.R", "plane1.G", "plane1.B", "plane1.A"};
        int w, h;
        float *ez, *planes, *dom;
        tl_page_exr_path(path, sizeof path, dir, p, ".exr");
        assert_int_equal(tl_exr_read(path, 3, rgb, &w, &h, &ez, err), 0);
        assert_int_equal(w, (int)pg.width);
        assert_int_equal(h, (int)pg.height);
        tl_page_exr_path(path, sizeof path, dir, p, ".ahd.exr");
        assert_int_equal(tl_exr_read(path, 7, ahd, &w, &h, &planes, err), 0);
        tl_page_exr_path(path, sizeof path, dir, p, ".dominant.exr");
        assert_int_equal(tl_exr_read(path, 3, rgb, &w, &h, &dom, err), 0);
        for (uint32_t i = 0; i < pg.width * pg.height; i++) {
            float want[3];
            lbk_r11g11b10f_unpack(rd32(pg.irradiance + 4 * i), want);
            for (int c = 0; c < 3; c++) {
                assert_true(ez[3 * i + c] == want[c]);
                assert_true(planes[7 * i + c] == want[c]);
                assert_true(dom[3 * i + c] >= want[c] * (1 - 1e-6f));
            }
            for (int c = 0; c < 4; c++) assert_true(planes[7 * i + 3 + c] == pg.rgba[4 * i + c] / 255.0f);
        }
        free(ez), free(planes), free(dom);
    }
    tl_bake_close(&b);
}

/* Nothing on error: a write that fails (here a folder sits where page_000.png must go) removes
 * the folders this run created (new/exr and its new parent), and leaves a folder that existed
 * before as it was. */
static void test_export_failure_leaves_no_new_folder(void **state)
{
    (void)state;
    tl_bake b;
    tf_blob blob = tf_build_scene(TF_SCENE_FULL, NULL);
    char err[TL_ERR_LEN], exr[160], png[160], blocker[200], parent[160];
    if (tl_bake_open_memory(blob.data, blob.size, &b, err) != TL_OPEN_OK) fail_msg("%s", err);
    tf_blob_free(&blob);
    snprintf(parent, sizeof parent, "%s/new", tmpdir);
    snprintf(exr, sizeof exr, "%s/new/exr", tmpdir);
    snprintf(png, sizeof png, "%s/old_png", tmpdir);
    snprintf(blocker, sizeof blocker, "%s/page_000.png", png);
    assert_int_equal(mkdir(png, 0755), 0);
    assert_int_equal(mkdir(blocker, 0755), 0);
    tl_export_options o = {exr, png, 0};
    tl_export_stats st;
    assert_int_equal(tl_export(&b, &o, &st, err), -1);
    assert_non_null(strstr(err, "page_000.png"));
    struct stat sb;
    assert_int_not_equal(stat(parent, &sb), 0); /* new/ and new/exr are gone */
    assert_int_equal(stat(blocker, &sb), 0);    /* the old folder keeps what it had */
    tl_bake_close(&b);
}

/* --per-object: the crate (object 2, page 1 rect 0,0 16×16) at its rectangle's resolution. */
static void test_export_per_object(void **state)
{
    (void)state;
    tl_bake b;
    char dir[128], path[256], err[TL_ERR_LEN];
    export_fixture("objects", 1, 1, &b, dir, sizeof dir);
    const char *rgb[] = {"R", "G", "B"};
    int w, h;
    float *px;
    snprintf(path, sizeof path, "%s/objects/001_wall.exr", dir);
    assert_int_equal(tl_exr_read(path, 3, rgb, &w, &h, &px, err), 0);
    assert_int_equal(w, 32);
    assert_int_equal(h, 16);
    lbk_lmap_page pg;
    lbk_lmap_page_get(&b.lmap, 0, &pg);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float want[3];
            lbk_r11g11b10f_unpack(rd32(pg.irradiance + 4 * ((size_t)y * 64 + 32 + x)), want);
            for (int c = 0; c < 3; c++) assert_true(px[3 * (y * w + x) + c] == want[c]);
        }
    free(px);
    snprintf(path, sizeof path, "%s/objects/002_crate.exr", dir);
    assert_int_equal(tl_exr_read(path, 3, rgb, &w, &h, &px, err), 0);
    assert_int_equal(w, 16);
    free(px);
    snprintf(path, sizeof path, "%s/objects/003_lamp-shade.exr", dir); /* not lightmapped: no image */
    assert_int_not_equal(access(path, F_OK), 0);
    snprintf(path, sizeof path, "%s/objects/002_crate.png", dir);
    uint8_t *png;
    assert_int_equal(tl_png_read_rgb8(path, &w, &h, &png, err), 0);
    assert_int_equal(w, 16);
    free(png);
    char stem[64];
    tl_export_object_stem("a/b c", 7, stem, sizeof stem);
    assert_string_equal(stem, "007_a_b_c");
    tl_bake_close(&b);
}

/* Previews: readable with spng, and each pixel is the documented tone map of page_NNN.exr. */
static void test_png_previews_follow_tonemap(void **state)
{
    (void)state;
    tl_bake b;
    char dir[128], path[256], err[TL_ERR_LEN];
    export_fixture("png", 0, 1, &b, dir, sizeof dir);
    /* the exposure over all texels of both pages */
    const char *rgb[] = {"R", "G", "B"};
    int w0, h0, w1, h1;
    float *p0, *p1;
    tl_page_exr_path(path, sizeof path, dir, 0, ".exr");
    assert_int_equal(tl_exr_read(path, 3, rgb, &w0, &h0, &p0, err), 0);
    tl_page_exr_path(path, sizeof path, dir, 1, ".exr");
    assert_int_equal(tl_exr_read(path, 3, rgb, &w1, &h1, &p1, err), 0);
    size_t n0 = (size_t)w0 * h0, n1 = (size_t)w1 * h1;
    float *all = malloc((n0 + n1) * 3 * sizeof(float));
    memcpy(all, p0, n0 * 3 * sizeof(float));
    memcpy(all + n0 * 3, p1, n1 * 3 * sizeof(float));
    float e = tl_exposure_p99(all, n0 + n1, 3);
    free(all);
    int w, h;
    uint8_t *png;
    tl_page_exr_path(path, sizeof path, dir, 0, ".png");
    assert_int_equal(tl_png_read_rgb8(path, &w, &h, &png, err), 0);
    assert_int_equal(w, w0);
    assert_int_equal(h, h0);
    for (size_t i = 0; i < n0; i++)
        for (int c = 0; c < 3; c++) assert_int_equal(png[3 * i + c], tl_srgb8(p0[3 * i + c] * e));
    free(png), free(p0), free(p1);
    snprintf(path, sizeof path, "%s/glg_top.png", dir);
    assert_int_equal(tl_png_read_rgb8(path, &w, &h, &png, err), 0);
    assert_int_equal(w, 512);
    free(png);
    tl_bake_close(&b);
}

static void test_probe_listings(void **state)
{
    (void)state;
    tl_bake b;
    char dir[128], path[256], err[TL_ERR_LEN];
    export_fixture("probes", 0, 0, &b, dir, sizeof dir);
    void *text;
    size_t size;
    snprintf(path, sizeof path, "%s/probes.csv", dir);
    assert_int_equal(tl_read_file(path, &text, &size, err), 0);
    int lines = 0;
    for (size_t i = 0; i < size; i++) lines += ((char *)text)[i] == '\n';
    assert_int_equal(lines, 1 + 8);
    assert_true(strncmp(text, "source,grid,index,x,y,z,E_px_r", 30) == 0);
    free(text);
    snprintf(path, sizeof path, "%s/probes.json", dir);
    assert_int_equal(tl_read_file(path, &text, &size, err), 0);
    cJSON *j = cJSON_ParseWithLength(text, size);
    free(text);
    assert_non_null(j);
    const cJSON *arr = cJSON_GetObjectItem(j, "probes");
    assert_int_equal(cJSON_GetArraySize(arr), 8);
    for (int i = 0; i < 8; i++) {
        const cJSON *p = cJSON_GetArrayItem(arr, i);
        const cJSON *pos = cJSON_GetObjectItem(p, "position");
        for (int k = 0; k < 3; k++) assert_true(cJSON_GetArrayItem(pos, k)->valuedouble == tf_probe_positions[i][k]);
        /* +Z irradiance of the listing equals the SH9 of the file evaluated at +Z */
        float pz[3], want[3];
        lbk_sh9_rgb sh;
        lbk_glg_probe_get(&b.glg, (uint32_t)i, pz, &sh);
        const float up[3] = {0, 0, 1};
        lbk_sh9_irradiance(&sh, up, want);
        const cJSON *e = cJSON_GetObjectItem(cJSON_GetObjectItem(p, "irradiance"), "pz");
        for (int c = 0; c < 3; c++) assert_true(fabs(cJSON_GetArrayItem(e, c)->valuedouble - want[c]) <= 1e-6 * fabs(want[c]));
    }
    cJSON_Delete(j);
    tl_bake_close(&b);
}

/* export → convert --from-exr: unedited pages come back bit-identical; a page edited ×2 decodes
 * to the R11G11B10F encoding of twice the original (exact: doubling only changes exponents). */
static void test_export_import_round_trip(void **state)
{
    (void)state;
    tl_bake b;
    char dir[128], path[256], err[TL_ERR_LEN];
    export_fixture("rt", 0, 0, &b, dir, sizeof dir);
    tl_profile keep;
    const char *text = "name = keep\nalignment = 64\n[sections]\ndefault = none\n";
    assert_int_equal(tl_profile_parse(text, strlen(text), "keep", &keep, err), 0);
    tl_convert_options co = {.profile = &keep, .from_exr_dir = dir};
    void *out;
    size_t out_size;
    tl_convert_report rep;
    assert_int_equal(tl_convert_memory(b.bytes, b.size, &co, &out, &out_size, &rep, err), TL_CONVERT_OK);
    assert_int_equal(rep.pages_imported, 2);
    /* every section as it was; META only gains the profile convert applied (spec §6.2) */
    lbk_reader *ro, *rn;
    assert_int_equal(lbk_reader_open_memory(b.bytes, b.size, NULL, &ro), LBK_OK);
    assert_int_equal(lbk_reader_open_memory(out, out_size, NULL, &rn), LBK_OK);
    assert_int_equal(lbk_reader_section_count(rn), lbk_reader_section_count(ro));
    for (uint32_t i = 0; i < lbk_reader_section_count(ro); i++) {
        lbk_section_info si, sn;
        lbk_reader_section_get(ro, i, &si);
        lbk_reader_section_get(rn, i, &sn);
        assert_int_equal(si.type, sn.type);
        const void *d0, *d1;
        size_t n0, n1;
        assert_int_equal(lbk_reader_section_data(ro, i, &d0, &n0), LBK_OK);
        assert_int_equal(lbk_reader_section_data(rn, i, &d1, &n1), LBK_OK);
        if (si.type == LBK_SECTION_META) continue;
        assert_int_equal(n0, n1);
        assert_memory_equal(d0, d1, n0);
    }
    lbk_reader_close(ro);
    lbk_reader_close(rn);
    free(out);
    /* edit page 1: ×2 */
    const char *rgb[] = {"R", "G", "B"};
    int w, h;
    float *px;
    tl_page_exr_path(path, sizeof path, dir, 1, ".exr");
    assert_int_equal(tl_exr_read(path, 3, rgb, &w, &h, &px, err), 0);
    for (int i = 0; i < w * h * 3; i++) px[i] *= 2.0f;
    assert_int_equal(tl_exr_write(path, w, h, 3, rgb, px, err), 0);
    assert_int_equal(tl_convert_memory(b.bytes, b.size, &co, &out, &out_size, &rep, err), TL_CONVERT_OK);
    tl_bake nb;
    assert_int_equal(tl_bake_open_memory(out, out_size, &nb, err), TL_OPEN_OK);
    lbk_lmap_page po, pn;
    lbk_lmap_page_get(&b.lmap, 1, &po);
    lbk_lmap_page_get(&nb.lmap, 1, &pn);
    for (int i = 0; i < w * h; i++) {
        float was[3], now[3];
        lbk_r11g11b10f_unpack(rd32(po.irradiance + 4 * i), was);
        lbk_r11g11b10f_unpack(rd32(pn.irradiance + 4 * i), now);
        for (int c = 0; c < 3; c++) assert_true(now[c] == 2.0f * was[c]);
        assert_memory_equal(po.rgba + 4 * i, pn.rgba + 4 * i, 4); /* plane 1 from the .ahd.exr, unchanged */
    }
    lbk_lmap_page_get(&b.lmap, 0, &po);
    lbk_lmap_page_get(&nb.lmap, 0, &pn);
    assert_memory_equal(po.irradiance, pn.irradiance, 4 * 64 * 32);
    free(px);
    tl_bake_close(&nb);
    free(out);
    tl_bake_close(&b);
}

/* Import errors are clear: wrong size, non-finite values, nothing to import. */
static void test_import_errors(void **state)
{
    (void)state;
    tf_blob blob = tf_build_scene(TF_SCENE_FULL, NULL);
    char dir[128], path[256], err[TL_ERR_LEN];
    snprintf(dir, sizeof dir, "%s/bad-import", tmpdir);
    assert_int_equal(tl_mkdirs(dir, err), 0);
    tl_profile keep;
    const char *text = "name = keep\nalignment = 64\n[sections]\ndefault = none\n";
    assert_int_equal(tl_profile_parse(text, strlen(text), "keep", &keep, err), 0);
    tl_convert_options co = {.profile = &keep, .from_exr_dir = dir};
    void *out = NULL;
    size_t out_size;
    assert_int_equal(tl_convert_memory(blob.data, blob.size, &co, &out, &out_size, NULL, err), TL_CONVERT_BAD_EXR);
    assert_non_null(strstr(err, "no page_NNN.exr"));
    const char *rgb[] = {"R", "G", "B"};
    float px[4 * 4 * 3];
    for (int i = 0; i < 48; i++) px[i] = 1.0f;
    tl_page_exr_path(path, sizeof path, dir, 1, ".exr");
    assert_int_equal(tl_exr_write(path, 4, 4, 3, rgb, px, err), 0);
    assert_int_equal(tl_convert_memory(blob.data, blob.size, &co, &out, &out_size, NULL, err), TL_CONVERT_BAD_EXR);
    assert_non_null(strstr(err, "is 4x4 but page 1 is 16x16"));
    float big[16 * 16 * 3];
    for (int i = 0; i < 16 * 16 * 3; i++) big[i] = 1.0f;
    big[3 * (16 * 2 + 5) + 1] = NAN;
    assert_int_equal(tl_exr_write(path, 16, 16, 3, rgb, big, err), 0);
    assert_int_equal(tl_convert_memory(blob.data, blob.size, &co, &out, &out_size, NULL, err), TL_CONVERT_BAD_EXR);
    assert_non_null(strstr(err, "pixel (5, 2) G is not finite"));
    assert_null(out);
    tf_blob_free(&blob);
}

static int run_export(int n, const char **args)
{
    char *argv[16];
    for (int i = 0; i < n; i++) argv[i] = (char *)args[i];
    fflush(stdout);
    return lbk_cmd_export(n, argv);
}

static void test_export_cli(void **state)
{
    (void)state;
    char in[128], dir[128], err[TL_ERR_LEN];
    snprintf(in, sizeof in, "%s/cli.lbk", tmpdir);
    snprintf(dir, sizeof dir, "%s/cli-out", tmpdir);
    tf_blob blob = tf_build_scene(TF_SCENE_FULL, NULL);
    assert_int_equal(tl_write_file_atomic(in, blob.data, blob.size, err), 0);
    tf_blob_free(&blob);
    const char *ok[] = {"export", in, "--png", dir, "-q"};
    assert_int_equal(run_export(5, ok), LBK_EXIT_OK);
    const char *none[] = {"export", in};
    assert_int_equal(run_export(2, none), LBK_EXIT_USAGE);
    const char *missing[] = {"export", "/nonexistent/x.lbk", "--exr", dir};
    assert_int_equal(run_export(4, missing), LBK_EXIT_IO);
    const char *badopt[] = {"export", in, "--exr"};
    assert_int_equal(run_export(3, badopt), LBK_EXIT_USAGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exr_round_trip_exact),
        cmocka_unit_test(test_exr_errors),
        cmocka_unit_test(test_png_round_trip),
        cmocka_unit_test(test_tonemap_numbers),
        cmocka_unit_test(test_heat_ramp),
        cmocka_unit_test(test_export_pages_equal_decoded),
        cmocka_unit_test(test_export_per_object),
        cmocka_unit_test(test_png_previews_follow_tonemap),
        cmocka_unit_test(test_probe_listings),
        cmocka_unit_test(test_export_import_round_trip),
        cmocka_unit_test(test_import_errors),
        cmocka_unit_test(test_export_cli),
        cmocka_unit_test(test_export_failure_leaves_no_new_folder),
    };
    return cmocka_run_group_tests(tests, setup_dir, teardown_dir);
}
