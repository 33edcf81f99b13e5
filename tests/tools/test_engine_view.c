/* The bake in an engine with no code of the user's: `lbk export --gltf` writes the lightmap as
 * emission (emissiveTexture on TEXCOORD_1 × emissiveFactor = albedo × KHR_materials_emissive_strength,
 * tools/convert/README.md "In engines"), and stock Babylon.js (npm babylonjs + babylonjs-loaders)
 * and three.js (npm three) show it (pinned in mk/deps.mk, installed under $BUILD/npm-engines by
 * `make test`):
 *  - the emissive PNG holds the EXR's irradiance to within its 8-bit sRGB steps (measured here);
 *  - headless Chromium (Debian `chromium`, SwiftShader WebGL) loads the export with each engine's
 *    own glTF loader (tests/tools/babylon_page.html, three_page.html: canvas, camera, exposure,
 *    nothing about materials), and the screenshot matches lbk render of the same view (bound
 *    below), for the lightmapped surfaces of the cornell bake and for the probe-lit (LLG) props of
 *    cornell_box_bjs. Without Chromium or the npm packages those cases are SKIPPED (counted so,
 *    saying why); a page that draws no lightmap FAILS. */
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

#include "support/image_compare.h"
#include "support/bake_file.h"
#include "tools/common/bake_data.h"
#include "tools/common/file_util.h"
#include "tools/common/image_io.h"
#include "tools/convert/gltf_export.h"
#include "tools/render/render.h"

#define W 160
#define H 120

/* A level, its view and what the engines must show of it. */
typedef struct view {
    const char *level, *scene;
    float from[3], at[3], fov_deg, stops;
    const char *title; /* the page's title when it loaded: the lightmapped materials it found */
    int llg;           /* compare the pixels of LLG props (not lightmapped) instead of the lightmapped ones */
} view;

/* the cornell bake in the view of test_view.c (lbk view's comparison), so the numbers compare;
 * every lightmapped material (7 of the 8: the light keeps its own emission) */
static const view CORNELL = {"tests/fuzz/corpus/bake_cornell.lbk", "scenes/cornell_box/CornellBox-Original.gltf",
                             {0.1f, 1.05f, 3.0f}, {0.0f, 1.0f, 0.0f}, 45.0f, 4.0f, "ready: 7 emissive textures", 0};
/* cornell_box_bjs, baked here: its props are LLG objects (COLOR_0 of an unlit material) */
static const view BJS = {NULL, "scenes/cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf", {0.5f, 1.2f, 2.5f},
                         {0.0f, 1.0f, 0.0f}, 40.0f, 3.0f, "ready: 11 emissive textures", 1};
static const view *V = &CORNELL;
static char bjs_level[1100];
static const float cam_up[3] = {0.0f, 1.0f, 0.0f};

static char out_dir[1024];

static const char *out(const char *name)
{
    static char path[4][1400];
    static int k;
    k = (k + 1) % 4;
    snprintf(path[k], sizeof path[k], "%s/%s", out_dir, name);
    return path[k];
}

/* out_dir = $BUILD/tests/engine_view (BUILD as tests/run.sh has it, default build), absolute: the
 * browser gets file:// URLs of it. */
static int setup(void **state)
{
    (void)state;
    const char *b = getenv("BUILD");
    char dir[1024], cmd[1200];
    snprintf(dir, sizeof dir, "%s/tests/engine_view", b && *b ? b : "build");
    snprintf(cmd, sizeof cmd, "mkdir -p '%s'", dir);
    if (system(cmd) != 0 || !realpath(dir, out_dir)) return -1;
    return 0;
}

static void export_level(void)
{
    char err[TL_ERR_LEN];
    tl_bake b;
    assert_int_equal(tl_bake_open_file(V->level ? V->level : bjs_level, &b, err), TL_OPEN_OK);
    tl_gltf_options g = {.output = out("level.glb"), .scene = V->scene, .container = "level.lbk"};
    tl_gltf_stats st;
    const int rc = tl_gltf_export(&b, &g, &st, err);
    tl_bake_close(&b);
    if (rc) print_error("tl_gltf_export: %s\n", err);
    assert_int_equal(rc, TL_GLTF_OK);
    assert_true(st.png_files >= 2 * st.pages); /* a preview and an emissive page each */
}

static double srgb_to_linear(double s) { return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4); }

/* The emissive PNG against the EXR beside it. Each channel is code = round(255 sRGB(E / scale)), so
 * the decoded value is off by at most half a code step of the sRGB curve: relatively
 * 0.5 · d ln(x) / d code = 0.5 · 2.4 / (255 · (s + 0.055) / 1.055) at s = code / 255 above the
 * linear toe — 0.49 % at full scale, 2.3 % at s = 0.2 (x = 3.3 % of the scale), 4.7 % at
 * s = 0.1 (1 %). Measured on the cornell bake (12 × 32, scale 0.2246 lux): all 1152 channels at or
 * above 1 % of the scale within the bound, mean 0.53 %, max 2.28 % relative. */
static void test_emissive_png_holds_the_exr(void **state)
{
    (void)state;
    export_level();
    char err[TL_ERR_LEN];
    static const char *const RGB[3] = {"R", "G", "B"};
    int w, h, pw, ph;
    float *exr;
    uint8_t *png;
    assert_int_equal(tl_exr_read(out("level.lightmap_000.exr"), 3, RGB, &w, &h, &exr, err), 0);
    assert_int_equal(tl_png_read_rgb8(out("level.lightmap_000.emissive.png"), &pw, &ph, &png, err), 0);
    assert_int_equal(pw, w);
    assert_int_equal(ph, h);
    float scale = 0.0f;
    for (int i = 0; i < 3 * w * h; i++) scale = exr[i] > scale ? exr[i] : scale;
    int n = 0, at_top = 0, over = 0;
    double sum = 0, worst = 0;
    for (int i = 0; i < 3 * w * h; i++) {
        const double x = exr[i] / scale, s = png[i] / 255.0;
        at_top += png[i] == 255;
        if (x < 0.01) continue;
        const double rel = fabs(srgb_to_linear(s) - x) / x;
        const double bound = s <= 0.04045 ? 0.5 / png[i] : 0.5 * 2.4 * 1.055 / (255.0 * (s + 0.055));
        over += rel > bound * 1.0001 + 1e-6;
        sum += rel, n++;
        worst = rel > worst ? rel : worst;
    }
    print_message("emissive PNG against the EXR (scale %.6g lux): %d channels >= 1 %% of the scale, mean %.3f %%, max %.3f %% "
                  "relative, %d over the half-step bound\n",
                  scale, n, 100.0 * sum / (n ? n : 1), 100.0 * worst, over);
    free(exr), free(png);
    assert_true(n > w * h); /* the page is lit */
    assert_true(at_top >= 1);  /* the page's largest value is code 255: nothing clips below it */
    assert_int_equal(over, 0);
    assert_true(sum / n < 0.01);
}

/* ---- stock Babylon.js in headless Chromium ------------------------------------------------- */

static int have_chromium(void) { return system("command -v chromium >/dev/null 2>&1") == 0; }

/* The npm packages' folder (mk/deps.mk: engine-npm) when `file` is in it, else "". */
static const char *npm_dir(const char *file)
{
    static char dir[1100];
    snprintf(dir, sizeof dir, "%s/../../npm-engines/node_modules", out_dir);
    char f[1200];
    snprintf(f, sizeof f, "%s/%s", dir, file);
    return access(f, R_OK) ? "" : dir;
}

/* --no-sandbox: the tests may run as root; SwiftShader gives WebGL 2 without a GPU; file access
 * from files: Babylon reads the GLB and its PNGs with XHR from file:// URLs; timeout: a hung
 * browser fails the case instead of stopping the suite. */
#define CHROMIUM "timeout 120 chromium --headless=new --no-sandbox --disable-gpu-sandbox --use-gl=angle --use-angle=swiftshader " \
                 "--enable-unsafe-swiftshader --hide-scrollbars --force-device-scale-factor=1 --allow-file-access-from-files " \
                 "--virtual-time-budget=20000"

/* The engine's page (copied into out_dir as NAME_page.html, beside the export) with the view's
 * hash parameters; lib: the node_modules folder. */
static void page_url(char *url, size_t size, const char *name, const char *lib)
{
    snprintf(url, size,
             "file://%s/%s_page.html#lib=%s&glb=level.glb&size=%dx%d&stops=%g&cam=%g,%g,%g,%g,%g,%g,%g,%g,%g,%g", out_dir,
             name, lib, W, H, V->stops, V->from[0], V->from[1], V->from[2], V->at[0], V->at[1], V->at[2], cam_up[0],
             cam_up[1], cam_up[2], V->fov_deg);
}

/* The page's title after it ran: "ready: N emissive textures" or "error: ..." (malloc'ed). */
static char *page_title(const char *url)
{
    char cmd[8192], err[TL_ERR_LEN];
    snprintf(cmd, sizeof cmd, CHROMIUM " --user-data-dir=%s --dump-dom '%s' > %s 2>/dev/null", out("profile"), url, out("dom.html"));
    assert_int_equal(system(cmd), 0);
    void *dom;
    size_t n;
    assert_int_equal(tl_read_file(out("dom.html"), &dom, &n, err), 0);
    char *s = realloc(dom, n + 1);
    assert_non_null(s);
    s[n] = 0;
    const char *a = strstr(s, "<title>"), *b = a ? strstr(a, "</title>") : NULL;
    char *t = strdup(a && b ? a + 7 : "(no title)");
    if (a && b) t[b - a - 7] = 0;
    free(s);
    return t;
}

/* lbk render's view as 8-bit sRGB of radiance × 2^STOPS (the page's exposure), with a black sky
 * (the page clears to black); *covered: pixels whose centre ray hit geometry with light on it. */
static void reference(uint8_t *ref8, uint8_t *covered)
{
    char err[TL_ERR_LEN];
    tl_render_options o;
    memset(&o, 0, sizeof o);
    o.width = W, o.height = H, o.samples = 1, o.threads = 1;
    memcpy(o.camera.from, V->from, sizeof V->from);
    memcpy(o.camera.at, V->at, sizeof V->at);
    memcpy(o.camera.up, cam_up, sizeof cam_up);
    o.camera.yfov = V->fov_deg * 3.14159265358979f / 180.0f;
    o.sky_override = 1;
    o.seams = 1; /* for img.lightmapped */
    tl_image img;
    assert_int_equal(tl_render(V->scene, V->level ? V->level : bjs_level, &o, &img, err), TL_RENDER_OK);
    const float k = powf(2.0f, V->stops);
    for (int i = 0; i < W * H; i++) {
        const int lit = img.rgb[3 * i] > 0 || img.rgb[3 * i + 1] > 0 || img.rgb[3 * i + 2] > 0;
        covered[i] = V->llg ? lit && !img.lightmapped[i] : lit;
        for (int c = 0; c < 3; c++) ref8[3 * i + c] = (uint8_t)lrintf(tic_srgb(img.rgb[3 * i + c] * k) * 255.0f);
    }
    tl_image_free(&img);
}

/* The screenshot against lbk render, per pixel the largest channel difference in 8-bit sRGB codes
 * after the same exposure (2^4) and the same transfer function (babylon_page.html asks Babylon for
 * the exact sRGB curves; three.js has them). What may differ, inside surfaces:
 *  - the emissive PNG's 8-bit sRGB step (test above): half a code of the texture; the view maps
 *    texture value t to display sRGB(2^4 · albedo · scale / π · t), at most 0.83 · t here (cornell:
 *    albedo ≤ 0.725, scale 0.2246 lux), so under half a display code;
 *  - the filter: the engine blends the four texels of the sRGB texture after decoding (WebGL sRGB
 *    texture), lbk render in AHD's linear form: the same for plane 0 along the normal, up to the
 *    GPU's 8-bit filter weights (1/256: under a code where neighbours differ by less than 64 codes);
 *  - the rounding to 8 bits on each side: one code.
 * So interior pixels differ by at most 2 codes. Pixels where rasterisation and ray casting see
 * different surfaces (silhouettes, creases: on_edge of the reference) may differ more: at most 3 %
 * of the covered pixels differ by more than 2 codes, and the mean over the covered pixels stays
 * ≤ 1 code. The same bound for both engines. Measured (cornell bake, 160 × 120, Chromium 156
 * SwiftShader), Babylon.js 9.28.0: mean
 * 0.42 codes over 17 391 covered pixels; 67.2 % equal, 32.6 % one code, 8 pixels two codes apart,
 * 26 (0.15 %) more, all on an edge; three.js 0.187.0: mean 0.41 codes, 67.4 % equal, 32.4 % one
 * code, 24 pixels (0.14 %) more than two, all on an edge. With Babylon's default pow(2.2) curves
 * instead of the exact ones: mean 3.08 codes, 47.7 % over 2 codes (fails). With the emissive
 * strength zeroed after loading (the surfaces drawn without the lightmap), either engine: 129 of
 * 17 391 pixels lit (the light), mean 105 codes (fails). */
static void compare(const char *name, const uint8_t *shot, const uint8_t *ref8, const uint8_t *covered)
{
    int n = 0, over = 0, interior = 0, n_in = 0, shot_lit = 0, max_d = 0, hist[3] = {0, 0, 0};
    double sum = 0, sum_in = 0;
    for (int i = 0; i < W * H; i++) {
        if (!covered[i]) continue;
        int d = 0;
        for (int c = 0; c < 3; c++) {
            const int e = abs(ref8[3 * i + c] - shot[3 * i + c]);
            d = e > d ? e : d;
        }
        shot_lit += shot[3 * i] + shot[3 * i + 1] + shot[3 * i + 2] > 24;
        n++, sum += d;
        max_d = d > max_d ? d : max_d;
        if (d <= 2) hist[d]++;
        const int edge = tic_on_edge(ref8, W, H, i % W, i / W);
        if (!edge) n_in++, sum_in += d;
        if (d > 2) {
            over++;
            if (!edge) interior++;
        }
    }
    print_message("%s vs lbk render %dx%d%s: %d covered pixels (%d lit in the shot), mean %.3f codes; %d equal, %d one "
                  "code, %d two codes apart, %d more (%.2f %%, %d not on an edge), max %d; off edges mean %.3f\n",
                  name, W, H, V->llg ? " (LLG props)" : "", n, shot_lit, sum / (n ? n : 1), hist[0], hist[1], hist[2], over,
                  100.0 * over / (n ? n : 1), interior, max_d, sum_in / (n_in ? n_in : 1));
    assert_true(n > (V->llg ? 1000 : W * H / 2)); /* the view shows what it is for */
    if (shot_lit <= n * 9 / 10)
        print_error("%s drew the level without its lightmap: %d of %d covered pixels lit (see %s/%s.png)\n", name,
                    shot_lit, n, out_dir, name);
    assert_true(shot_lit > n * 9 / 10);
    /* LLG props: the bound holds off edges (their albedo textures are not exported, and lbk
     * render draws them: the dots of bjs's tall box are edges of the reference) */
    const double mean = V->llg ? sum_in / n_in : sum / n;
    const int bad = V->llg ? interior : over, allowed = V->llg ? n_in / 100 : n * 3 / 100;
    if (mean > 1.0 || bad > allowed)
        print_error("%s's picture is not lbk render's: mean %.3f codes (bound 1), %d pixels over 2 codes (bound %d): see "
                    "%s/%s.png and lbk.png\n",
                    name, mean, bad, allowed, out_dir, name);
    assert_true(mean <= 1.0);
    assert_true(bad <= allowed);
}

static void engine_matches(const char *name, const char *page_src, const char *lib)
{
    export_level();
    char err[TL_ERR_LEN], url[4096], cmd[8192], file[64];
    void *html;
    size_t hn;
    assert_int_equal(tl_read_file(page_src, &html, &hn, err), 0);
    /* three_page.html names the modules in its import map: @LIB@ is the folder */
    size_t libn = strlen(lib), n = 0, cap = hn + 8 * libn + 1;
    char *page = malloc(cap);
    assert_non_null(page);
    for (size_t i = 0; i < hn;) {
        if (i + 5 <= hn && !memcmp((char *)html + i, "@LIB@", 5)) {
            assert_true(n + libn < cap);
            memcpy(page + n, lib, libn), n += libn, i += 5;
        } else {
            assert_true(n + 1 < cap);
            page[n++] = ((char *)html)[i++];
        }
    }
    snprintf(file, sizeof file, "%s_page.html", name);
    assert_int_equal(tl_write_file_atomic(out(file), page, n, err), 0);
    free(html), free(page);
    page_url(url, sizeof url, name, lib);
    char *title = page_title(url);
    print_message("%s page: %s\n", name, title);
    assert_string_equal(title, V->title);
    free(title);
    char shot_png[64];
    snprintf(shot_png, sizeof shot_png, "%s_shot.png", name);
    unlink(out(shot_png));
    /* headless Chromium keeps a minimum window size: the canvas is the top-left W × H of a larger shot */
    snprintf(cmd, sizeof cmd, CHROMIUM " --user-data-dir=%s --window-size=%d,%d --screenshot=%s '%s' >/dev/null 2>&1",
             out("profile"), 3 * W, 3 * H, out(shot_png), url);
    assert_int_equal(system(cmd), 0);
    int w, h;
    uint8_t *shot;
    assert_int_equal(tl_png_read_rgb8(out(shot_png), &w, &h, &shot, err), 0);
    assert_int_equal(w, 3 * W);
    assert_int_equal(h, 3 * H);
    for (int y = 0; y < H; y++) memmove(shot + 3 * W * y, shot + 3 * w * y, 3 * W);
    static uint8_t ref8[W * H * 3], covered[W * H];
    reference(ref8, covered);
    /* the pictures, to look at when it fails (docs/images/engine_NAME.png are these) */
    snprintf(file, sizeof file, "%s.png", name);
    tl_png_write_rgb8(out("lbk.png"), W, H, ref8, err);
    tl_png_write_rgb8(out(file), W, H, shot, err);
    compare(name, shot, ref8, covered);
    free(shot);
}

static void test_babylon_shows_the_lightmap(void **state)
{
    (void)state;
    if (!have_chromium()) {
        print_message("SKIPPED: no chromium (make deps installs it)\n");
        skip();
    }
    const char *lib = npm_dir("babylonjs-loaders/babylonjs.loaders.js");
    if (!*lib) {
        print_message("SKIPPED: npm babylonjs-loaders not under %s/../../npm-engines (make engine-npm)\n", out_dir);
        skip();
    }
    V = &CORNELL;
    engine_matches("babylon", "tests/tools/babylon_page.html", lib);
}

/* three.js's own GLTFLoader (examples/jsm). The three.js vendored for lbk view (r147) cannot be
 * used: its GLTFLoader reads TEXCOORD_1 for occlusion maps only (texture channels came in r151). */
static void test_three_shows_the_lightmap(void **state)
{
    (void)state;
    if (!have_chromium()) {
        print_message("SKIPPED: no chromium (make deps installs it)\n");
        skip();
    }
    const char *lib = npm_dir("three/examples/jsm/loaders/GLTFLoader.js");
    if (!*lib) {
        print_message("SKIPPED: npm three not under %s/../../npm-engines (make engine-npm)\n", out_dir);
        skip();
    }
    V = &CORNELL;
    engine_matches("three", "tests/tools/three_page.html", lib);
}

/* LLG props: COLOR_0 = V · E(bent normal) / π × radiance_scale per vertex on an unlit material
 * (albedo), against lbk render's per-pixel V and bent normal with the grid's SH9 at the pixel. Both
 * engines draw the same vertex colours; they differ from lbk render by the interpolation of a
 * smooth field across a triangle, on top of the 8-bit steps of the cases above, so the same bound
 * holds off edges. Measured (cornell_box_bjs, 16 samples, 160 × 120, +3 stops): 1716 LLG pixels,
 * mean 1.48 codes over all of them (the tall box's texture dots, which the export does not carry,
 * are the rest), off edges mean 0.66 codes, 2 pixels over 2 codes, in both engines. With COLOR_0
 * the preview as it was (V · E × the p99 exposure, clamped) the props are near white: off edges
 * mean 114 codes (fails). */
static void test_llg_props_in_both_engines(void **state)
{
    (void)state;
    if (!have_chromium()) {
        print_message("SKIPPED: no chromium (make deps installs it)\n");
        skip();
    }
    const char *bab = npm_dir("babylonjs-loaders/babylonjs.loaders.js"), *three = npm_dir("three/build/three.module.js");
    if (!*bab || !*three) {
        print_message("SKIPPED: npm babylonjs-loaders or three not under %s/../../npm-engines (make engine-npm)\n", out_dir);
        skip();
    }
    char libs[2][1100];
    snprintf(libs[0], sizeof libs[0], "%s", bab);
    snprintf(libs[1], sizeof libs[1], "%s", three);
    snprintf(bjs_level, sizeof bjs_level, "%s/bjs.lbk", out_dir);
    tb_job job;
    memset(&job, 0, sizeof job);
    job.in = BJS.scene;
    job.out = bjs_level;
    job.d.preset = LBK_BAKE_PRESET_FAST;
    job.d.seed = 1;
    job.d.max_samples = 16;
    job.d.threads = 2;
    char err[512];
    if (tb_bake(&job, NULL, err, sizeof err)) fail_msg("bake %s: %s", BJS.scene, err);
    V = &BJS;
    engine_matches("babylon", "tests/tools/babylon_page.html", libs[0]);
    engine_matches("three", "tests/tools/three_page.html", libs[1]);
    V = &CORNELL;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_emissive_png_holds_the_exr),
        cmocka_unit_test(test_babylon_shows_the_lightmap),
        cmocka_unit_test(test_three_shows_the_lightmap),
        cmocka_unit_test(test_llg_props_in_both_engines),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
