/* Normal maps in lbk view's page (viewer/viewer.js), in headless Chromium (SwiftShader WebGL;
 * SKIPPED without Debian's `chromium`): the normal-mapped floor of support/normal_scene.h (four
 * stripes under one directional light), baked, drawn by the page from straight above and by lbk
 * render from the same camera: as 8-bit sRGB of radiance × 2^STOPS the two agree within one code
 * except where the two ways of finding the surface disagree (pixels on an edge of the reference,
 * at most 1 %; test_view.c gives the argument). The page's stripes differ as the closed form says
 * (the render's are checked against it by test_normal_maps.c), so a page that ignores the normal
 * map (the flat floor: all four stripes alike, 10 % to 26 % off) fails, and one that turns the
 * map in the wrong frame (the lightmap's instead of the map's, or B's sign) fails on the
 * stripes it turns. The export behind the page (lbk export --gltf) is checked too: TANGENT on the
 * primitive, the normalTexture with its PNG beside the GLB. */
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

#include "support/bake_file.h"
#include "support/image_compare.h"
#include "support/normal_scene.h"
#include "support/tmp_dir.h"
#include "tools/common/file_util.h"
#include "tools/render/render.h"
#include "tools/view/view.h"

#define W 160
#define H 120
#define STOPS 1.0
#define CAM_H 6.0
#define FOV_DEG 50.0

static char tmpdir[64];

static int setup(void **state)
{
    (void)state;
    return td_make(tmpdir, sizeof tmpdir, "lbk_test_view_normal");
}

static int teardown(void **state)
{
    (void)state;
    return td_remove(tmpdir); /* kept under $LBK_TEST_KEEP, for a look with lbk inspect */
}

static int have_chromium(void) { return system("command -v chromium >/dev/null 2>&1") == 0; }

/* The pixel column of world x at the floor (image right = +x). */
static int column(double x)
{
    const double half_w = CAM_H * tan(FOV_DEG * 3.14159265358979 / 360.0) * W / H;
    return (int)floor(W / 2.0 + x / half_w * (W / 2.0));
}

static void bake_floor(const char *gltf, const char *lbk)
{
    tb_job j;
    memset(&j, 0, sizeof j);
    j.in = gltf, j.out = lbk;
    j.d.threads = 2;
    j.d.seed = 1;
    j.d.texel_density = 4;
    char err[512];
    const lbk_result r = tb_bake(&j, NULL, err, sizeof err);
    if (r != LBK_OK) fprintf(stderr, "bake: %s\n", err);
    assert_int_equal(r, LBK_OK);
}

/* The export the page draws: TANGENT and the normalTexture (its PNG written beside the GLB). */
static void check_export(const char *view_dir)
{
    char p[512], err[TL_ERR_LEN];
    void *glb;
    size_t n;
    snprintf(p, sizeof p, "%s/level.glb", view_dir);
    assert_int_equal(tl_read_file(p, &glb, &n, err), 0);
    assert_true(n > 20);
    const char *json = (const char *)glb + 20; /* the JSON chunk; not NUL-terminated: search within it */
    uint32_t jn;
    memcpy(&jn, (const char *)glb + 12, 4);
    assert_true(jn <= n - 20);
    char *text = malloc(jn + 1);
    assert_non_null(text);
    memcpy(text, json, jn), text[jn] = 0;
    assert_non_null(strstr(text, "\"TANGENT\""));
    assert_non_null(strstr(text, "\"normalTexture\""));
    assert_non_null(strstr(text, "\"normal_map\""));
    assert_non_null(strstr(text, "level.normal_000.png"));
    free(text), free(glb);
    snprintf(p, sizeof p, "%s/level.normal_000.png", view_dir);
    int w, h;
    uint8_t *px;
    assert_int_equal(tl_png_read_rgb8(p, &w, &h, &px, err), 0);
    assert_int_equal(w, 8), assert_int_equal(h, 2);
    double n1[3];
    ns_stripe_normal(1, n1);
    assert_int_equal(px[3 * 2], ns_to_byte(n1[0])); /* the importer's bytes, back unchanged */
    free(px);
}

/* The page's W × H screenshot from straight above (8-bit sRGB, malloc'ed). */
static uint8_t *page_shot(const char *view_dir)
{
    char cmd[4096], shot[256], err[TL_ERR_LEN];
    snprintf(shot, sizeof shot, "%s/shot.png", tmpdir);
    snprintf(cmd, sizeof cmd,
             "timeout 120 chromium --headless=new --no-sandbox --disable-gpu-sandbox --use-gl=angle "
             "--use-angle=swiftshader --enable-unsafe-swiftshader --hide-scrollbars --force-device-scale-factor=1 "
             "--virtual-time-budget=20000 --user-data-dir=%s/chromium --window-size=%d,%d --screenshot=%s "
             "'file://%s/index.html#cam=0,%g,0,0,0,0,0,0,-1,%g&stops=%g&size=%dx%d' >/dev/null 2>&1",
             tmpdir, 3 * W, 3 * H, shot, view_dir, CAM_H, FOV_DEG, STOPS, W, H);
    assert_int_equal(system(cmd), 0);
    int w, h;
    uint8_t *img;
    assert_int_equal(tl_png_read_rgb8(shot, &w, &h, &img, err), 0);
    assert_int_equal(w, 3 * W), assert_int_equal(h, 3 * H);
    for (int y = 0; y < H; y++) memmove(img + 3 * W * y, img + 3 * w * y, 3 * W);
    return img;
}

static void page_matches_lbk_render(void **state)
{
    (void)state;
    if (!have_chromium()) skip();
    assert_int_equal(ns_write_all(tmpdir, 1.0f), 0);
    char gltf[256], lbk[256], view_dir[256], err[TL_ERR_LEN];
    snprintf(gltf, sizeof gltf, "%s/derived.gltf", tmpdir);
    snprintf(lbk, sizeof lbk, "%s/floor.lbk", tmpdir);
    snprintf(view_dir, sizeof view_dir, "%s/view", tmpdir);
    bake_floor(gltf, lbk);
    tl_view_options vo = {.container = lbk, .scene = gltf, .out_dir = view_dir};
    assert_int_equal(tl_view_write(&vo, NULL, err), TL_VIEW_OK);
    check_export(view_dir);
    uint8_t *shot = page_shot(view_dir);

    tl_render_options o;
    memset(&o, 0, sizeof o);
    o.width = W, o.height = H, o.samples = 1, o.threads = 2;
    o.camera = (tl_camera){{0, (float)CAM_H, 0}, {0, 0, 0}, {0, 0, -1}, (float)(FOV_DEG * 3.14159265358979 / 180.0)};
    o.sky_override = 1; /* the page's background is black */
    tl_image img;
    assert_int_equal(tl_render(gltf, lbk, &o, &img, err), TL_RENDER_OK);
    static uint8_t ref[W * H * 3];
    const float k = powf(2.0f, (float)STOPS);
    for (int i = 0; i < 3 * W * H; i++) ref[i] = (uint8_t)lrintf(tic_srgb(img.rgb[i] * k) * 255.0f);
    int over = 0, interior = 0, max_diff = 0;
    for (int i = 0; i < W * H; i++) {
        int d = 0;
        for (int c = 0; c < 3; c++) d = abs(ref[3 * i + c] - shot[3 * i + c]) > d ? abs(ref[3 * i + c] - shot[3 * i + c]) : d;
        if (d > 1) over++, interior += !tic_on_edge(ref, W, H, i % W, i / W);
        max_diff = d > max_diff ? d : max_diff;
    }
    /* the page's stripes at their centres (a row off the floor's middle) against the closed form */
    double page[4];
    for (int s = 0; s < 4; s++) {
        const int i = 3 * ((H / 2 + 15) * W + column(-1.5 + s));
        const double want = ns_closed_form(s, 1, NULL) * k;
        page[s] = shot[i + 1];
        print_message("stripe %d: page %d, lbk render %d, closed form %.1f (codes)\n", s, shot[i + 1], ref[i + 1],
                      255.0 * tic_srgb((float)want));
    }
    print_message("page vs lbk render %dx%d: %d pixels over 1 code (%d not on an edge), max %d\n", W, H, over, interior,
                  max_diff);
    char p[512];
    snprintf(p, sizeof p, "%s/ref.png", tmpdir);
    tl_png_write_rgb8(p, W, H, ref, err); /* with LBK_TEST_KEEP, to look at */
    tl_image_free(&img);
    free(shot);
    assert_true(over <= W * H / 100);
    assert_int_equal(interior, 0);
    /* the map is drawn: +X brighter than flat, −X darker (the closed form: +10 %, −26 % in radiance) */
    assert_true(page[1] > page[0] + 5 && page[2] < page[0] - 15 && fabs(page[3] - page[1]) <= 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(page_matches_lbk_render),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
