/* lbk view (tools/view): the page folder, the 127.0.0.1 server, and the page itself in headless
 * Chromium (Debian `chromium`, SwiftShader WebGL; those cases are SKIPPED without it):
 *  - the folder holds the page files byte for byte as in viewer/, data.js, level.glb;
 *  - invalid containers and foreign scenes are refused (TL_VIEW_INPUT);
 *  - the server answers GET of the folder's files only: other methods 405, traversal and hidden
 *    names 403, symbolic links and missing files 404, oversized requests dropped;
 *  - the page opens from disk without a console error and draws;
 *  - a screenshot from a fixed camera equals lbk render's view of the same camera (bound below). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <arpa/inet.h>
#include <math.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "tools/common/file_util.h"
#include "tools/common/image_io.h"
#include "tools/render/render.h"
#include "tools/view/view.h"
#include "support/image_compare.h"

#define OUT "build/tests/view_out"
#define LEVEL "tests/fuzz/corpus/bake_cornell.lbk"
#define SCENE "scenes/cornell_box/CornellBox-Original.gltf"

static int write_page(void)
{
    char err[TL_ERR_LEN];
    tl_view_options o = {.container = LEVEL, .scene = SCENE, .out_dir = OUT};
    tl_view_stats s;
    const int rc = tl_view_write(&o, &s, err);
    if (rc) print_error("tl_view_write: %s\n", err);
    return rc;
}

static int same_file(const char *a, const char *b)
{
    void *x = NULL, *y = NULL;
    size_t nx = 0, ny = 0;
    char err[TL_ERR_LEN];
    const int ok = !tl_read_file(a, &x, &nx, err) && !tl_read_file(b, &y, &ny, err) && nx == ny && !memcmp(x, y, nx);
    free(x), free(y);
    return ok;
}

static void test_view_out_folder(void **state)
{
    (void)state;
    assert_int_equal(write_page(), TL_VIEW_OK);
    assert_true(tl_view_asset_count >= 10);
    for (size_t i = 0; i < tl_view_asset_count; i++) {
        char a[512], b[512];
        snprintf(a, sizeof a, OUT "/%s", tl_view_assets[i].path);
        snprintf(b, sizeof b, "viewer/%s", tl_view_assets[i].path);
        if (!same_file(a, b)) print_error("%s differs from %s\n", a, b);
        assert_true(same_file(a, b));
    }
    void *d;
    size_t n;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_read_file(OUT "/data.js", &d, &n, err), 0);
    assert_memory_equal(d, "window.LBK_DATA = {\"name\": \"bake_cornell.lbk\",\n\"inspect\": null,\n\"report\": null,", 79);
    free(d);
    /* with inspect's JSON (re-printed compactly) and a bake report file */
    assert_int_equal(tl_write_text("build/tests/view_report.json", "{ \"schema\": \"lbk-bake-report/1\",\n \"samples\": [] }", err), 0);
    tl_view_options o = {.container = LEVEL, .scene = SCENE, .out_dir = OUT, .inspect_json = "{ \"schema\" : \"lbk-inspect/1\" }",
                         .report_path = "build/tests/view_report.json"};
    assert_int_equal(tl_view_write(&o, NULL, err), TL_VIEW_OK);
    assert_int_equal(tl_read_file(OUT "/data.js", &d, &n, err), 0);
    const char *want = "\"inspect\": {\"schema\":\"lbk-inspect/1\"},\n\"report\": {\"schema\":\"lbk-bake-report/1\",\"samples\":[]},";
    assert_true(n > 200);
    char head[201];
    memcpy(head, d, 200);
    head[200] = 0;
    if (!strstr(head, want)) print_error("data.js starts: %s\n", head);
    assert_non_null(strstr(head, want));
    free(d);
    struct stat st;
    assert_int_equal(stat(OUT "/level.glb", &st), 0);
    assert_true(st.st_size > 1000);
    assert_int_equal(stat(OUT "/vendor/LICENSE.three", &st), 0);
}

static void test_view_refuses_bad_inputs(void **state)
{
    (void)state;
    char err[TL_ERR_LEN];
    void *d;
    size_t n;
    assert_int_equal(tl_read_file(LEVEL, &d, &n, err), 0);
    ((unsigned char *)d)[n / 2] ^= 1;
    assert_int_equal(tl_write_file_atomic("build/tests/view_bad.lbk", d, n, err), 0);
    free(d);
    tl_view_options o = {.container = "build/tests/view_bad.lbk", .scene = SCENE, .out_dir = "build/tests/view_bad"};
    assert_int_equal(tl_view_write(&o, NULL, err), TL_VIEW_INPUT);
    tl_view_options foreign = {.container = LEVEL, .scene = "tests/fuzz/sets_scene.gltf", .out_dir = "build/tests/view_bad"};
    assert_int_equal(tl_view_write(&foreign, NULL, err), TL_VIEW_INPUT);
    /* the panel's JSON inputs must be JSON: they go into data.js as values */
    tl_view_options not_json = {.container = LEVEL, .scene = SCENE, .out_dir = "build/tests/view_bad", .inspect_json = "{\"a\": 1} </script>"};
    assert_int_equal(tl_view_write(&not_json, NULL, err), TL_VIEW_INPUT);
    tl_view_options missing = {.container = "build/tests/no_such.lbk", .scene = SCENE, .out_dir = "build/tests/view_bad"};
    assert_int_equal(tl_view_write(&missing, NULL, err), TL_VIEW_IO);
}

/* ---- the server ------------------------------------------------------------------------------ */

/* Sends `request` to 127.0.0.1:port and returns the status code of the answer (0: none), the body
 * length in *body_len (when not NULL). */
static int http(uint16_t port, const char *request, size_t request_len, size_t *body_len, char *first, size_t first_len)
{
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd < 0 || connect(fd, (struct sockaddr *)&a, sizeof a)) return -1;
    send(fd, request, request_len, MSG_NOSIGNAL);
    static char buf[1 << 22];
    size_t n = 0;
    ssize_t r;
    while (n < sizeof buf - 1 && (r = recv(fd, buf + n, sizeof buf - 1 - n, 0)) > 0) n += (size_t)r;
    close(fd);
    buf[n] = 0;
    int code = 0;
    if (sscanf(buf, "HTTP/1.0 %d", &code) != 1) code = 0;
    const char *body = strstr(buf, "\r\n\r\n");
    if (body_len) *body_len = body ? n - (size_t)(body + 4 - buf) : 0;
    if (first && body) snprintf(first, first_len, "%s", body + 4);
    return code;
}

static void test_view_server(void **state)
{
    (void)state;
    assert_int_equal(write_page(), TL_VIEW_OK);
    unlink(OUT "/link.js");
    assert_int_equal(symlink("/etc/passwd", OUT "/link.js"), 0);
    char err[TL_ERR_LEN];
    uint16_t port = 0;
    const int fd = tl_view_listen(0, &port, err);
    assert_true(fd >= 0);
    struct sockaddr_in a;
    socklen_t al = sizeof a;
    assert_int_equal(getsockname(fd, (struct sockaddr *)&a, &al), 0);
    assert_int_equal(ntohl(a.sin_addr.s_addr), INADDR_LOOPBACK); /* this machine only */
    struct {
        const char *request;
        int code;
    } cases[] = {
        {"GET / HTTP/1.1\r\nHost: x\r\n\r\n", 200},
        {"GET /vendor/three.min.js HTTP/1.1\r\n\r\n", 200},
        {"GET /index.html?x=1#cam HTTP/1.0\r\n\r\n", 200},
        {"HEAD /data.js HTTP/1.1\r\n\r\n", 200},
        {"POST /index.html HTTP/1.1\r\nContent-Length: 0\r\n\r\n", 405},
        {"GET /../../etc/passwd HTTP/1.1\r\n\r\n", 403},
        {"GET /vendor/../index.html HTTP/1.1\r\n\r\n", 403},
        {"GET /%2e%2e/etc/passwd HTTP/1.1\r\n\r\n", 403},
        {"GET //etc/passwd HTTP/1.1\r\n\r\n", 403},
        {"GET /.hidden HTTP/1.1\r\n\r\n", 403},
        {"GET /link.js HTTP/1.1\r\n\r\n", 404},
        {"GET /vendor HTTP/1.1\r\n\r\n", 404},
        {"GET /nothing.html HTTP/1.1\r\n\r\n", 404},
        {"GET index.html HTTP/1.1\r\n\r\n", 403},
        {"BREW /\r\n\r\n", 400},
    };
    const size_t n = sizeof cases / sizeof cases[0];
    const unsigned total = (unsigned)n + 1; /* + the oversized request */
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        char e[TL_ERR_LEN];
        _exit(tl_view_serve(fd, OUT, NULL, total, e) ? 1 : 0);
    }
    close(fd);
    void *index;
    size_t index_size;
    assert_int_equal(tl_read_file(OUT "/index.html", &index, &index_size, err), 0);
    for (size_t i = 0; i < n; i++) {
        size_t body = 0;
        const int code = http(port, cases[i].request, strlen(cases[i].request), &body, NULL, 0);
        if (code != cases[i].code) print_error("%s-> %d, expected %d\n", cases[i].request, code, cases[i].code);
        assert_int_equal(code, cases[i].code);
        if (i == 0) assert_int_equal(body, index_size);
        if (i == 3) assert_int_equal(body, 0); /* HEAD: headers only */
    }
    free(index);
    /* an endless header block is dropped without an answer */
    static char big[20000];
    memset(big, 'a', sizeof big);
    memcpy(big, "GET / HTTP/1.1\r\nX: ", 19);
    assert_int_equal(http(port, big, sizeof big, NULL, NULL, 0), 0);
    int st = 0;
    assert_int_equal(waitpid(pid, &st, 0), pid);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    unlink(OUT "/link.js");
}

/* ---- the page in headless Chromium ----------------------------------------------------------- */

static int have_chromium(void) { return system("command -v chromium >/dev/null 2>&1") == 0; }

/* --no-sandbox: the tests may run as root; SwiftShader gives WebGL 2 without a GPU; timeout: a hung
 * browser fails the case instead of stopping the suite. */
#define CHROMIUM "timeout 120 chromium --headless=new --no-sandbox --disable-gpu-sandbox --use-gl=angle --use-angle=swiftshader " \
                 "--enable-unsafe-swiftshader --hide-scrollbars --force-device-scale-factor=1 " \
                 "--virtual-time-budget=20000 --user-data-dir=build/tests/view_chromium_profile"

/* the camera and exposure of the comparison; lbk render gets the same */
#define W 160
#define H 120
#define STOPS 4.0
#define SETS_STOPS (-1.0)
static const float cam_from[3] = {0.1f, 1.05f, 3.0f}, cam_at[3] = {0.0f, 1.0f, 0.0f}, cam_up[3] = {0.0f, 1.0f, 0.0f};
#define FOV_DEG 45.0f

static void page_url(char *out, size_t size)
{
    char cwd[1024];
    assert_non_null(getcwd(cwd, sizeof cwd));
    snprintf(out, size, "file://%s/" OUT "/index.html#cam=%g,%g,%g,%g,%g,%g,%g,%g,%g,%g&stops=%g&size=%dx%d", cwd,
             cam_from[0], cam_from[1], cam_from[2], cam_at[0], cam_at[1], cam_at[2], cam_up[0], cam_up[1], cam_up[2],
             FOV_DEG, STOPS, W, H);
}

static void test_view_page_loads_without_errors(void **state)
{
    (void)state;
    if (!have_chromium()) skip();
    assert_int_equal(write_page(), TL_VIEW_OK);
    char url[2048], cmd[4096];
    page_url(url, sizeof url);
    snprintf(cmd, sizeof cmd, CHROMIUM " --dump-dom '%s' > build/tests/view_dom.html 2>/dev/null", url);
    assert_int_equal(system(cmd), 0);
    void *dom;
    size_t n;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_read_file("build/tests/view_dom.html", &dom, &n, err), 0);
    ((char *)dom)[n - 1] = 0;
    const char *title = strstr(dom, "<title>");
    if (title) print_message("%.120s\n", title);
    assert_non_null(strstr(dom, "<title>lbk view: ready, 0 errors</title>"));
    free(dom);
}

/* The page's pixel against lbk render's radiance at the same pixel centre, both as 8-bit sRGB of
 * radiance × 2^STOPS. The bound: the page decodes the same stored texels with the same bilinear
 * blend in the linear form (viewer.js FRAG = tools/render/shade.c sample_page), in GPU binary32
 * instead of CPU binary32 — relative differences of order 1e-6, far below one 8-bit step (≥ 1/255
 * of full scale ≈ 4e-3) — so a pixel whose centre sees the same surface point differs by at most
 * one code (the rounding of the float to 8 bits, done by the GPU on one side and here on the
 * other). Pixels where rasterisation and ray casting see different surfaces — centres within float
 * error of a triangle edge, silhouettes — may differ more: they must lie on an edge of the reference
 * (on_edge) and be at most 1 % of the pixels. Measured (cornell bake, 160 × 120): 95.4 % of the
 * pixels identical, 4.5 % one code apart, 25 pixels (0.13 %) more, all on silhouettes. */
static void screenshot_matches_lbk_render(const char *level)
{
    char url[2048], cmd[4096], err[TL_ERR_LEN];
    tl_view_options vo = {.container = level, .scene = SCENE, .out_dir = OUT};
    assert_int_equal(tl_view_write(&vo, NULL, err), TL_VIEW_OK);
    page_url(url, sizeof url);
    unlink("build/tests/view_shot.png");
    /* headless Chromium keeps a minimum window size: the canvas is the top-left W × H of a larger shot */
    snprintf(cmd, sizeof cmd, CHROMIUM " --window-size=%d,%d --screenshot=build/tests/view_shot.png '%s' >/dev/null 2>&1",
             3 * W, 3 * H, url);
    assert_int_equal(system(cmd), 0);
    int w, h;
    uint8_t *shot;
    assert_int_equal(tl_png_read_rgb8("build/tests/view_shot.png", &w, &h, &shot, err), 0);
    assert_int_equal(w, 3 * W);
    assert_int_equal(h, 3 * H);
    for (int y = 0; y < H; y++) memmove(shot + 3 * W * y, shot + 3 * w * y, 3 * W);

    tl_render_options o;
    memset(&o, 0, sizeof o);
    o.width = W, o.height = H, o.samples = 1, o.threads = 1;
    memcpy(o.camera.from, cam_from, sizeof cam_from);
    memcpy(o.camera.at, cam_at, sizeof cam_at);
    memcpy(o.camera.up, cam_up, sizeof cam_up);
    o.camera.yfov = FOV_DEG * 3.14159265358979f / 180.0f;
    o.sky_override = 1; /* the page's background is black */
    tl_image img;
    assert_int_equal(tl_render(SCENE, level, &o, &img, err), TL_RENDER_OK);
    const float k = powf(2.0f, (float)STOPS);
    int over = 0, interior = 0, max_diff = 0, lit = 0;
    double sum = 0;
    static uint8_t ref8[W * H * 3];
    for (int i = 0; i < 3 * W * H; i++) ref8[i] = (uint8_t)lrintf(tic_srgb(img.rgb[i] * k) * 255.0f);
    for (int i = 0; i < W * H; i++) {
        int d = 0;
        for (int c = 0; c < 3; c++) {
            const int ref = ref8[3 * i + c];
            const int e = abs(ref - shot[3 * i + c]);
            d = e > d ? e : d;
            if (ref > 8) lit++;
        }
        sum += d;
        if (d > 1) {
            over++;
            if (!tic_on_edge(ref8, W, H, i % W, i / W)) interior++;
        }
        if (d > max_diff) max_diff = d;
    }
    print_message("%s: page vs lbk render %dx%d: %d pixels over 1 code (%.2f %%, %d not on an edge), max %d, mean %.3f codes, "
                  "%d lit channels\n",
                  level, W, H, over, 100.0 * over / (W * H), interior, max_diff, sum / (W * H), lit);
    tl_png_write_rgb8("build/tests/view_ref.png", W, H, ref8, err); /* to look at when it fails */
    tl_image_free(&img);
    free(shot);
    assert_true(lit > W * H); /* the view shows the lit level, not a black frame */
    assert_true(over <= W * H / 100);
    assert_int_equal(interior, 0);
}

static void test_view_screenshot_matches_lbk_render(void **state)
{
    (void)state;
    if (!have_chromium()) skip();
    screenshot_matches_lbk_render(LEVEL);
}

/* ---- block-compressed packs, the error view ------------------------------------------------- */

/* The cornell bake converted by `lbk convert` ($LBK, else build/lbk-asan) with a profile. */
static void convert_level(const char *profile, const char *out)
{
    const char *lbk = getenv("LBK") ? getenv("LBK") : "build/lbk-asan";
    if (access(lbk, X_OK)) skip();
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s convert " LEVEL " -o %s --profile %s >/dev/null", lbk, out, profile);
    assert_int_equal(system(cmd), 0);
}

/* Block-compressed pages: BC6H + BC5/BC4 (console-current) the page decodes in JS (bit-exact with
 * liblbk: test_view_reader); ASTC 4×4 (handheld) lbk view decodes (astcenc) and hands to the page as
 * 1.0 texels (R11G11B10F: 2^-7 relative more, under a tenth of an sRGB code per percent). The
 * reference is lbk render of the uncompressed bake, and the bound is the pack's own error:
 * bench_packs measures the cornell packs' irradiance against the bake at a mean 1.9 % (BC) / 2.0 %
 * (ASTC) and p99 13.1 % / 13.2 % in luminance (tools/convert/profiles/README.md). A relative error
 * e moves an sRGB code by at most about 255·e/2.4 (d log srgb / d log x ≤ 1/2.4 above the linear
 * toe), i.e. a mean ≤ 2 and a p99 ≤ 14 codes, + 1 for the 8-bit rounding on each side: mean ≤ 4,
 * 99th percentile of the pixels off silhouettes ≤ 16 codes. The pixels must be lit (the page draws
 * the block pages). */
static void pack_page_matches_lbk_render(const char *profile, const char *pack)
{
    if (!have_chromium()) skip();
    convert_level(profile, pack);
    char url[2048], cmd[4096], err[TL_ERR_LEN];
    tl_view_options vo = {.container = pack, .scene = SCENE, .out_dir = OUT};
    tl_view_stats vs;
    assert_int_equal(tl_view_write(&vo, &vs, err), TL_VIEW_OK);
    assert_int_equal(vs.astc_pages > 0, !strcmp(profile, "handheld"));
    page_url(url, sizeof url);
    unlink("build/tests/view_bc_shot.png");
    snprintf(cmd, sizeof cmd, CHROMIUM " --window-size=%d,%d --screenshot=build/tests/view_bc_shot.png '%s' >/dev/null 2>&1",
             3 * W, 3 * H, url);
    assert_int_equal(system(cmd), 0);
    int w, h;
    uint8_t *shot;
    assert_int_equal(tl_png_read_rgb8("build/tests/view_bc_shot.png", &w, &h, &shot, err), 0);
    assert_int_equal(w, 3 * W);
    for (int y = 0; y < H; y++) memmove(shot + 3 * W * y, shot + 3 * w * y, 3 * W);
    tl_render_options o;
    memset(&o, 0, sizeof o);
    o.width = W, o.height = H, o.samples = 1, o.threads = 1;
    memcpy(o.camera.from, cam_from, sizeof cam_from);
    memcpy(o.camera.at, cam_at, sizeof cam_at);
    memcpy(o.camera.up, cam_up, sizeof cam_up);
    o.camera.yfov = FOV_DEG * 3.14159265358979f / 180.0f;
    o.sky_override = 1;
    tl_image img;
    assert_int_equal(tl_render(SCENE, LEVEL, &o, &img, err), TL_RENDER_OK);
    const float k = powf(2.0f, (float)STOPS);
    static uint8_t ref8[W * H * 3];
    for (int i = 0; i < 3 * W * H; i++) ref8[i] = (uint8_t)lrintf(tic_srgb(img.rgb[i] * k) * 255.0f);
    tl_image_free(&img);
    int hist[256] = {0}, n = 0, lit = 0;
    double sum = 0;
    for (int i = 0; i < W * H; i++) {
        int d = 0;
        for (int c = 0; c < 3; c++) {
            const int e = abs(ref8[3 * i + c] - shot[3 * i + c]);
            d = e > d ? e : d;
            lit += shot[3 * i + c] > 8;
        }
        sum += d;
        if (!tic_on_edge(ref8, W, H, i % W, i / W)) hist[d]++, n++;
    }
    int p99 = 0;
    for (int run = 0; p99 < 255 && (run += hist[p99]) < n * 99 / 100; p99++) {}
    print_message("%s pack page vs lbk render of the bake: mean %.3f codes, p99 off edges %d codes, %d lit channels\n",
                  profile, sum / (W * H), p99, lit);
    free(shot);
    assert_true(lit > W * H);
    assert_true(sum / (W * H) <= 4.0);
    assert_true(p99 <= 16);
}

static void test_view_bc_pages_match_lbk_render(void **state)
{
    (void)state;
    pack_page_matches_lbk_render("console-current", "build/tests/view_bc.lbk");
}

static void test_view_astc_pages_match_lbk_render(void **state)
{
    (void)state;
    pack_page_matches_lbk_render("handheld", "build/tests/view_astc.lbk");
}

/* The page's DOM after it loaded with these hash parameters (malloc'ed, NUL-terminated). */
static char *page_dom(const char *level, const char *hash)
{
    char err[TL_ERR_LEN], cwd[1024], cmd[4096];
    tl_view_options vo = {.container = level, .scene = SCENE, .out_dir = "build/tests/view_dom_out"};
    assert_int_equal(tl_view_write(&vo, NULL, err), TL_VIEW_OK);
    assert_non_null(getcwd(cwd, sizeof cwd));
    snprintf(cmd, sizeof cmd, CHROMIUM " --dump-dom 'file://%s/build/tests/view_dom_out/index.html#%s' > build/tests/view_dom2.html 2>/dev/null",
             cwd, hash);
    assert_int_equal(system(cmd), 0);
    void *dom;
    size_t n;
    assert_int_equal(tl_read_file("build/tests/view_dom2.html", &dom, &n, err), 0);
    char *s = realloc(dom, n + 1);
    assert_non_null(s);
    s[n] = 0;
    return s;
}

/* ASTC pages (handheld): lbk view hands them to the page decoded, so it draws them with no note
 * and no error. */
static void test_view_astc_pages_are_drawn(void **state)
{
    (void)state;
    if (!have_chromium()) skip();
    convert_level("handheld", "build/tests/view_astc.lbk");
    char *dom = page_dom("build/tests/view_astc.lbk", "stops=4");
    assert_non_null(strstr(dom, "<title>lbk view: ready, 0 errors</title>"));
    assert_null(strstr(dom, "ASTC pages cannot be shown"));
    free(dom);
}

/* The error view (mode 5): a file without TERR says how to get one; a bake with --error-map (the
 * corpus's bake_cornell_terr.lbk) shows the legend in % and how many texels carry an estimate. */
static void test_view_error_mode(void **state)
{
    (void)state;
    if (!have_chromium()) skip();
    char *dom = page_dom(LEVEL, "mode=5");
    assert_non_null(strstr(dom, "<title>lbk view: ready, 0 errors</title>"));
    assert_non_null(strstr(dom, "no per-texel error map in this file</b>: bake with --error-map"));
    free(dom);
    dom = page_dom("tests/fuzz/corpus/bake_cornell_terr.lbk", "mode=5");
    assert_non_null(strstr(dom, "<title>lbk view: ready, 0 errors</title>"));
    assert_null(strstr(dom, "no per-texel error map"));
    assert_non_null(strstr(dom, "relative standard error of the irradiance, per texel"));
    assert_non_null(strstr(dom, "0.1 %"));
    assert_non_null(strstr(dom, "texels estimated"));
    free(dom);
}

/* ---- light-set slider: the page changes the pixels lbk render --set changes ------------------ */

#define SETS_LEVEL "tests/fuzz/corpus/bake_sets.lbk"
#define SETS_SCENE "tests/fuzz/sets_scene.gltf"
#define SETS_OUT "build/tests/view_sets"

/* A W × H screenshot of the sets page with extra hash parameters, as 8-bit RGB (malloc'ed). */
static uint8_t *sets_shot(const char *extra, const char *png)
{
    char cwd[1024], cmd[4096], err[TL_ERR_LEN];
    assert_non_null(getcwd(cwd, sizeof cwd));
    unlink(png);
    snprintf(cmd, sizeof cmd,
             CHROMIUM " --window-size=%d,%d --screenshot=%s 'file://%s/" SETS_OUT
                      "/index.html#cam=%g,%g,%g,%g,%g,%g,%g,%g,%g,%g&stops=%g&size=%dx%d%s' >/dev/null 2>&1",
             3 * W, 3 * H, png, cwd, cam_from[0], cam_from[1], cam_from[2], cam_at[0], cam_at[1], cam_at[2], cam_up[0],
             cam_up[1], cam_up[2], FOV_DEG, SETS_STOPS, W, H, extra);
    assert_int_equal(system(cmd), 0);
    int w, h;
    uint8_t *shot;
    assert_int_equal(tl_png_read_rgb8(png, &w, &h, &shot, err), 0);
    assert_int_equal(w, 3 * W);
    for (int y = 0; y < H; y++) memmove(shot + 3 * W * y, shot + 3 * w * y, 3 * W);
    return shot;
}

static float *sets_render(const tl_weight *sets, size_t n)
{
    char err[TL_ERR_LEN];
    tl_render_options o;
    memset(&o, 0, sizeof o);
    o.width = W, o.height = H, o.samples = 1, o.threads = 1;
    memcpy(o.camera.from, cam_from, sizeof cam_from);
    memcpy(o.camera.at, cam_at, sizeof cam_at);
    memcpy(o.camera.up, cam_up, sizeof cam_up);
    o.camera.yfov = FOV_DEG * 3.14159265358979f / 180.0f;
    o.sky_override = 1;
    o.sets = sets, o.set_count = n;
    tl_image img;
    const int rc = tl_render(SETS_SCENE, SETS_LEVEL, &o, &img, err);
    if (rc) print_error("tl_render: %s\n", err);
    assert_int_equal(rc, TL_RENDER_OK);
    float *rgb = img.rgb;
    img.rgb = NULL;
    tl_image_free(&img);
    return rgb;
}

/* Set B from on (1, lbk render's default) to 0.25. lbk render applies it through lbk_dls_apply,
 * the page through its own apply (bit-identical texels and probes: test_view_reader). So:
 *  - a pixel lbk render leaves bit-identical (its surface's texels or probes untouched by B) the
 *    page leaves identical: the page decodes the same unchanged bytes;
 *  - a pixel whose 8-bit sRGB value lbk render changes by 2 codes or more, the page changes too
 *    (a change of less may vanish in either side's rounding to 8 bits);
 * except on silhouettes (on_edge), where rasterisation and ray casting may see different surfaces.
 * Also: the slider changes a real part of the view. */
static void test_view_set_slider_changes_what_lbk_render_changes(void **state)
{
    (void)state;
    if (!have_chromium()) skip();
    char err[TL_ERR_LEN];
    tl_view_options vo = {.container = SETS_LEVEL, .scene = SETS_SCENE, .out_dir = SETS_OUT};
    assert_int_equal(tl_view_write(&vo, NULL, err), TL_VIEW_OK);
    uint8_t *p0 = sets_shot("", "build/tests/view_sets_on.png");
    uint8_t *p1 = sets_shot("&sets=B:0.25", "build/tests/view_sets_dim.png");
    const tl_weight dim = {"B", 0.25f};
    float *r0 = sets_render(NULL, 0), *r1 = sets_render(&dim, 1);
    const float k = powf(2.0f, (float)SETS_STOPS);
    static uint8_t ref0[W * H * 3];
    for (int i = 0; i < 3 * W * H; i++) ref0[i] = (uint8_t)lrintf(tic_srgb(r0[i] * k) * 255.0f);
    int render_same = 0, render_changed = 0, page_changed = 0, wrong_same = 0, wrong_changed = 0, edge = 0;
    for (int i = 0; i < W * H; i++) {
        int same = 1, big = 0, pch = 0;
        for (int c = 0; c < 3; c++) {
            same &= r0[3 * i + c] == r1[3 * i + c];
            const int a = (int)lrintf(tic_srgb(r0[3 * i + c] * k) * 255.0f);
            const int b = (int)lrintf(tic_srgb(r1[3 * i + c] * k) * 255.0f);
            big |= abs(a - b) >= 2;
            pch |= p0[3 * i + c] != p1[3 * i + c];
        }
        render_same += same, render_changed += big, page_changed += pch;
        const int bad_same = same && pch, bad_changed = big && !pch;
        if ((bad_same || bad_changed) && tic_on_edge(ref0, W, H, i % W, i / W)) {
            edge++;
            continue;
        }
        wrong_same += bad_same, wrong_changed += bad_changed;
    }
    print_message("set B 1 -> 0.25: lbk render leaves %d pixels identical, changes %d by >= 2 codes; the page changes %d; "
                  "disagreements: %d off edges (%d unchanged-but-changed, %d changed-but-unchanged), %d on edges\n",
                  render_same, render_changed, page_changed, wrong_same + wrong_changed, wrong_same, wrong_changed, edge);
    free(p0), free(p1), free(r0), free(r1);
    assert_true(render_changed > W * H / 20); /* B lights a real part of the view */
    assert_true(render_same > W * H / 20);    /* and leaves a real part alone */
    assert_int_equal(wrong_same, 0);
    assert_int_equal(wrong_changed, 0);
    assert_true(edge <= W * H / 100);
}

/* ---- the command --------------------------------------------------------------------------- */

/* lbk view through the lbk binary ($LBK, else build/lbk-asan, which make test-build builds): the
 * command runs `lbk inspect --json` of its own binary for the panel, so it is tested as a process. */
static void test_view_command(void **state)
{
    (void)state;
    const char *lbk = getenv("LBK") ? getenv("LBK") : "build/lbk-asan";
    if (access(lbk, X_OK)) skip();
    char cmd[2048], err[TL_ERR_LEN];
    snprintf(cmd, sizeof cmd, "%s view >/dev/null 2>&1", lbk);
    assert_int_equal(WEXITSTATUS(system(cmd)), 2); /* usage */
    snprintf(cmd, sizeof cmd, "%s view " LEVEL " " SCENE " --port 70000 >/dev/null 2>&1", lbk);
    assert_int_equal(WEXITSTATUS(system(cmd)), 2);
    snprintf(cmd, sizeof cmd, "%s view " LEVEL " " SCENE " --frobnicate >/dev/null 2>&1", lbk);
    assert_int_equal(WEXITSTATUS(system(cmd)), 2);
    snprintf(cmd, sizeof cmd, "%s view " LEVEL " tests/fuzz/sets_scene.gltf --out build/tests/view_cmd_bad >/dev/null 2>&1", lbk);
    assert_int_equal(WEXITSTATUS(system(cmd)), 4); /* not the scene it was baked from */
    snprintf(cmd, sizeof cmd, "%s view --help | grep -q 127.0.0.1", lbk);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "%s view " LEVEL " " SCENE " --out build/tests/view_cmd -q", lbk);
    assert_int_equal(system(cmd), 0);
    void *d;
    size_t n;
    assert_int_equal(tl_read_file("build/tests/view_cmd/data.js", &d, &n, err), 0);
    char head[160];
    memcpy(head, d, sizeof head - 1);
    head[sizeof head - 1] = 0;
    free(d);
    assert_non_null(strstr(head, "\"inspect\": {\"schema\":\"lbk-inspect/1\""));
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_view_out_folder),
        cmocka_unit_test(test_view_refuses_bad_inputs),
        cmocka_unit_test(test_view_server),
        cmocka_unit_test(test_view_command),
        cmocka_unit_test(test_view_page_loads_without_errors),
        cmocka_unit_test(test_view_screenshot_matches_lbk_render),
        cmocka_unit_test(test_view_set_slider_changes_what_lbk_render_changes),
        cmocka_unit_test(test_view_bc_pages_match_lbk_render),
        cmocka_unit_test(test_view_astc_pages_are_drawn),
        cmocka_unit_test(test_view_astc_pages_match_lbk_render),
        cmocka_unit_test(test_view_error_mode),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
