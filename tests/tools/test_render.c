/* lbk render (tools/render) against answers known without it. Every bound is derived here:
 *
 * Furnace: a closed box whose every surface (the walls, an LLG prop inside) emits Le with albedo
 * ρ holds radiance L* = Le/(1−ρ) everywhere, irradiance E* = π·L*; a Lambert surface sends
 * ρ·E/π + Le and a white test sphere E/π, both L* when E = E*. Errors of E:
 *   lightmap  the bake's texel bound after P = 6 passes (16·2^p samples a half, fixed schedule:
 *             tests/bake/test_furnace.c) B = P/(16·(2^P − 1)) = 0.595 %, times the R11G11B10F
 *             rounding of Ez, ≤ 2^−7 (R, G: 6-bit mantissas) or 2^−6 (B: 5 bits); decoding at the
 *             interpolated normal returns Ez (tangent normal +Z) and bilinear weights sum to one;
 *   GLG, LLG  probes under uniform radiance are exact (< 1e−5, test_furnace) up to the RGB9E5
 *             rounding of their DC term, ≤ 2^−9; an LLG prop that is convex sees all of its
 *             hemisphere (V = 1, stored exactly) and a uniform SH has the same irradiance for any
 *             bent normal.
 * A lit surface's L − L* = ρ·(E − E*)/π = ρ·L*·δ for a relative error δ of E; a sphere's is L*·δ.
 * Plus 1e−5 for float arithmetic.
 *
 * Leak: scenes/leak_rooms/leak_rooms_split.gltf, a lit room and a closed dark room on either side
 * of a solid wall, no triangle shared. The true radiance in the dark room is 0, and so is lbk's
 * estimate, exactly: every sample a dark receiver takes comes from a dark surface whose cache
 * value is itself such a sum (no emitter, no sky reachable), 0 encodes to 0 (R11G11B10F, RGB9E5)
 * and every filter of zeros is 0. The codec's smallest step would hide a leak below it, never
 * create one: the bound is 0 for every pixel (walls, floor, the LLG prop, GLG-lit spheres).
 *
 * Light sets and doors: room_with_doors (tests/support/door_scenes.h) with two lights in sets A
 * and B rendered with A = B = 1 through lbk_dls_apply, against full bakes with both lights
 * static; and with the north door tagged and open, against the room without the panel. Both are
 * unbiased estimates of the same image, so the difference of two with different seeds has mean
 * square σ_S² + σ_R², each σ measured from two seeds (rmse(X1 − X2)² = 2σ²). Asserted:
 * rmse(S − R)² ≤ 2 (σ_S² + σ_R²) + (2^−6 · mean)² — the factor 2 covers the spread of a mean
 * over the view's few hundred independent texels (its standard deviation is ~5 %), the last
 * term the one extra R11G11B10F rounding of the applied texels. And the weights matter: lights
 * off, or the door closed, must be far off. */
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

#include "cli/cli.h"
#include "support/bake_file.h"
#include "support/door_scenes.h"
#include "support/gltf_writer.h"
#include "support/tmp_dir.h"
#include "tools/render/render.h"

#define RHO 0.5f
#define LE 1.0f
#define PASSES 6
#define LEAK_SCENE "scenes/leak_rooms/leak_rooms_split.gltf"

static char tmpdir[64];

static int setup(void **state)
{
    (void)state;
    return td_make(tmpdir, sizeof tmpdir, "lbk_test_render");
}

static int teardown(void **state)
{
    (void)state;
    return td_remove(tmpdir); /* kept under $LBK_TEST_KEEP, for a look with lbk inspect */
}

static void bake(const char *gltf, const char *out, uint64_t seed, int max_samples, float density, float glg_spacing)
{
    tb_job j;
    memset(&j, 0, sizeof j);
    j.in = gltf, j.out = out;
    j.d.threads = 2;
    j.d.seed = seed;
    if (max_samples) j.d.target_error = 1e-6, j.d.max_samples = max_samples; /* fixed schedule */
    j.d.texel_density = density;
    j.d.glg_spacing = glg_spacing;
    j.d.dls_threshold = -1; /* every non-zero receiver of a light set: no threshold bias */
    char err[512];
    lbk_result r = tb_bake(&j, NULL, err, sizeof err);
    if (r != LBK_OK) fprintf(stderr, "bake %s: %s\n", gltf, err);
    assert_int_equal(r, LBK_OK);
}

static tl_image render(const char *gltf, const char *lbk, const tl_render_options *o)
{
    tl_image im;
    char err[TL_ERR_LEN];
    int rc = tl_render(gltf, lbk, o, &im, err);
    if (rc) fprintf(stderr, "render: %s\n", err);
    assert_int_equal(rc, TL_RENDER_OK);
    return im;
}

static tl_camera look(float fx, float fy, float fz, float ax, float ay, float az, float fov_deg)
{
    return (tl_camera){{fx, fy, fz}, {ax, ay, az}, {0, 1, 0}, fov_deg * 3.14159265f / 180.0f};
}

/* max over pixels and channels of |L − want| / want, against a bound per channel */
static void assert_uniform(const tl_image *im, float want, const double bound[3], const char *what)
{
    double worst[3] = {0, 0, 0};
    for (size_t i = 0; i < (size_t)im->width * (size_t)im->height; i++)
        for (int c = 0; c < 3; c++) worst[c] = fmax(worst[c], fabs(im->rgb[3 * i + (size_t)c] - want) / want);
    printf("furnace %s: max relative error R %.5f G %.5f B %.5f (bounds %.5f %.5f %.5f)\n", what, worst[0], worst[1],
           worst[2], bound[0], bound[1], bound[2]);
    for (int c = 0; c < 3; c++) assert_true(worst[c] <= bound[c]);
}

static void furnace(void **state)
{
    (void)state;
    char gltf[128], lbk[128];
    snprintf(gltf, sizeof gltf, "%s/furnace.gltf", tmpdir);
    snprintf(lbk, sizeof lbk, "%s/furnace.lbk", tmpdir);
    gw_scene *sc = gw_create();
    const float albedo[3] = {RHO, RHO, RHO}, le[3] = {LE, LE, LE};
    int m = gw_material(sc, albedo, le, 0, 0);
    gw_geom room = {0}, prop = {0};
    const float r0[3] = {0, 0, 0}, r1[3] = {2, 2, 2}, p0[3] = {0.8f, 0.6f, 0.8f}, p1[3] = {1.2f, 1.0f, 1.2f};
    gw_geom_box(&room, r0, r1, 2, 1);
    gw_geom_box(&prop, p0, p1, 1, 0);
    gw_mesh(sc, "room", &room, m, 1, NULL, "lightmap");
    gw_mesh(sc, "prop", &prop, m, 1, NULL, "llg");
    assert_int_equal(gw_write(sc, gltf), 0);
    gw_free(sc), gw_geom_free(&room), gw_geom_free(&prop);
    bake(gltf, lbk, 1, 2 * 16 * ((1 << PASSES) - 1), 0, 0);

    const double B = PASSES / (16.0 * ((1 << PASSES) - 1)), want = LE / (1 - RHO);
    const double q[3] = {ldexp(1, -7), ldexp(1, -7), ldexp(1, -6)}, probe = ldexp(1, -9) + 1e-5;
    double lm[3], sphere[3], llg[3];
    for (int c = 0; c < 3; c++) {
        lm[c] = RHO * ((1 + B) * (1 + q[c]) - 1) + 1e-5;
        sphere[c] = probe + 1e-5;
        llg[c] = RHO * probe + 1e-5;
    }
    /* the whole room: walls (generated charts: the mesh has no TEXCOORD_1), the prop, a sphere */
    const tl_sphere sp = {{1.5f, 1.5f, 0.5f}, 0.15f};
    tl_render_options o = {.width = 48, .height = 36, .samples = 2, .threads = 2, .spheres = &sp, .sphere_count = 1};
    o.camera = look(0.3f, 1.4f, 1.7f, 1.4f, 0.9f, 0.6f, 100);
    tl_image im = render(gltf, lbk, &o);
    assert_uniform(&im, (float)want, lm, "view (lightmap bound)");
    tl_image_free(&im);
    /* close-ups where every ray hits one representation */
    o.width = o.height = 8;
    o.camera = look(1.5f, 1.5f, 0.9f, 1.5f, 1.5f, 0.5f, 10);
    im = render(gltf, lbk, &o);
    assert_uniform(&im, (float)want, sphere, "GLG sphere");
    tl_image_free(&im);
    o.sphere_count = 0;
    o.camera = look(1.0f, 0.8f, 1.8f, 1.0f, 0.8f, 1.0f, 10);
    im = render(gltf, lbk, &o);
    assert_uniform(&im, (float)want, llg, "LLG prop");
    tl_image_free(&im);
}

static double mean_luminance(const tl_image *im)
{
    double s = 0;
    for (size_t i = 0; i < (size_t)im->width * (size_t)im->height; i++)
        s += 0.2126 * im->rgb[3 * i] + 0.7152 * im->rgb[3 * i + 1] + 0.0722 * im->rgb[3 * i + 2];
    return s / ((double)im->width * im->height);
}

static void leak(void **state)
{
    (void)state;
    if (access(LEAK_SCENE, R_OK)) fail_msg("%s missing (tests run from the repository root)", LEAK_SCENE);
    char lbk[128];
    snprintf(lbk, sizeof lbk, "%s/leak.lbk", tmpdir);
    bake(LEAK_SCENE, lbk, 1, 0, 0, 0);
    /* spheres 0.3 m from the wall, where GLG tetrahedra reach across it */
    const tl_sphere sp[2] = {{{6.8f, 1.5f, 1.2f}, 0.3f}, {{4.5f, 1.5f, 3.0f}, 0.25f}};
    tl_render_options o = {.width = 64, .height = 48, .threads = 2, .spheres = sp, .sphere_count = 2};
    char err[TL_ERR_LEN];
    assert_int_equal(tl_gltf_camera(LEAK_SCENE, 1, &o.camera, err), TL_RENDER_OK); /* in the dark room */
    tl_image dark = render(LEAK_SCENE, lbk, &o);
    size_t lit = 0;
    float worst = 0;
    for (size_t i = 0; i < 3 * (size_t)dark.width * (size_t)dark.height; i++) lit += dark.rgb[i] != 0.0f, worst = fmaxf(worst, dark.rgb[i]);
    printf("leak: %zu non-zero channels in the dark room, largest %g nits\n", lit, worst);
    assert_int_equal(lit, 0);
    tl_image_free(&dark);
    assert_int_equal(tl_gltf_camera(LEAK_SCENE, 0, &o.camera, err), TL_RENDER_OK); /* the lit room */
    tl_image bright = render(LEAK_SCENE, lbk, &o);
    printf("leak: the lit room's mean luminance %.3f nits\n", mean_luminance(&bright));
    assert_true(mean_luminance(&bright) > 1.0);
    tl_image_free(&bright);
    assert_int_equal(tl_gltf_camera(LEAK_SCENE, 2, &o.camera, err), TL_RENDER_USAGE); /* it has two */
}

static double rmse(const tl_image *a, const tl_image *b)
{
    double s = 0;
    const size_t n = (size_t)a->width * (size_t)a->height;
    for (size_t i = 0; i < n; i++) {
        double d = 0;
        for (int c = 0; c < 3; c++) d += (c == 0 ? 0.2126 : c == 1 ? 0.7152 : 0.0722) * (a->rgb[3 * i + (size_t)c] - b->rgb[3 * i + (size_t)c]);
        s += d * d;
    }
    return sqrt(s / (double)n);
}

/* Writes a room level and bakes it with seeds 1 and 2 into lbk[0], lbk[1]. */
static void room_pair(const char *name, const ds_options *ds, char gltf[160], char lbk[2][160])
{
    snprintf(gltf, 160, "%s/%s.gltf", tmpdir, name);
    char err[256];
    assert_int_equal(ds_write_room_scene(DS_ROOM_GLB, gltf, ds, err, sizeof err), 0);
    for (int k = 0; k < 2; k++) {
        snprintf(lbk[k], 160, "%s/%s%d.lbk", tmpdir, name, k + 1);
        bake(gltf, lbk[k], (uint64_t)k + 1, 96, 2.0f, 2.5f);
    }
}

/* S (two seeds, with weights `on`) against R (two seeds, plain): the bound of the header; S with
 * weights `off` must be far from R. */
static void agree(const char *what, const char *gs, char ls[2][160], const tl_render_options *on,
                  const tl_render_options *off, const char *gr, char lr[2][160])
{
    tl_render_options plain = *on;
    plain.set_count = plain.door_count = 0;
    tl_image s1 = render(gs, ls[0], on), s2 = render(gs, ls[1], on), base = render(gs, ls[0], off);
    tl_image r1 = render(gr, lr[0], &plain), r2 = render(gr, lr[1], &plain);
    const double mean = mean_luminance(&r1), sig_s = rmse(&s1, &s2) / sqrt(2.0), sig_r = rmse(&r1, &r2) / sqrt(2.0);
    /* seeds 1 against 2: independent estimates (the same seed correlates the two bakes' samples) */
    const double d = rmse(&s1, &r2), bound = sqrt(2 * (sig_s * sig_s + sig_r * sig_r) + pow(ldexp(mean, -6), 2));
    printf("%s: rmse(S seed 1 - R seed 2) %.4f%% of the mean (same seed %.4f%%), noise %.4f%% (S) %.4f%% (R), "
           "bound %.4f%%; off %.2f%%\n", what, 100 * d / mean, 100 * rmse(&s1, &r1) / mean, 100 * sig_s / mean,
           100 * sig_r / mean, 100 * bound / mean, 100 * rmse(&base, &r1) / mean);
    assert_true(d <= bound);
    assert_true(rmse(&base, &r1) > 5 * bound);
    tl_image_free(&s1), tl_image_free(&s2), tl_image_free(&r1), tl_image_free(&r2), tl_image_free(&base);
}

/* Lights A and B in sets, on (weight 1), against the same lights static. No door: see below. */
static void light_sets(void **state)
{
    (void)state;
    char gs[160], gr[160], ls[2][160], lr[2][160];
    const ds_options ds = {.inside = DS_INSIDE_SETS, .sky = 0.5f}, dr = {.inside = DS_INSIDE_STATIC, .sky = 0.5f};
    room_pair("sets", &ds, gs, ls);
    room_pair("sets_static", &dr, gr, lr);
    const tl_weight on[2] = {{"A", 1.0f}, {"B", 1.0f}}, off[2] = {{"A", 0.0f}, {"B", 0.0f}};
    tl_render_options o = {.width = 80, .height = 60, .threads = 2, .sets = on, .set_count = 2};
    o.camera = look(0.0f, 2.0f, 4.5f, 0.0f, 1.5f, -3.0f, 75);
    tl_render_options o_off = o;
    o_off.sets = off;
    agree("light sets", gs, ls, &o, &o_off, gr, lr);
    /* a block-compressed pack of the same bake: its decoded texels go through lbk_dls_apply as 1.0
     * texels; within the pack goal's mean of 1 % of the bake (summed over the view), and the
     * weights still act on it (sets off is far darker, as above) */
    char pack[200];
    snprintf(pack, sizeof pack, "%s.pack.lbk", ls[0]);
    const char *conv[] = {"convert", ls[0], "-o", pack, "--profile", "console-current", "-q", NULL};
    assert_int_equal(lbk_cmd_convert(7, (char **)conv), LBK_EXIT_OK);
    tl_image ref = render(gs, ls[0], &o), im = render(gs, pack, &o), dark = render(gs, pack, &o_off);
    double diff = 0, sum = 0, sum_off = 0;
    for (size_t i = 0; i < 3 * (size_t)o.width * (size_t)o.height; i++)
        diff += fabs((double)im.rgb[i] - ref.rgb[i]), sum += ref.rgb[i], sum_off += dark.rgb[i];
    print_message("light sets, console-current pack: summed |difference| / summed radiance %.5f; sets off %.3f\n",
                  diff / sum, sum_off / sum);
    assert_true(diff > 0 && diff <= 0.01 * sum);
    assert_true(sum_off < 0.5 * sum);
    tl_image_free(&ref), tl_image_free(&im), tl_image_free(&dark);
}

/* The north door open (ω = 1: its open set at full weight, the panel not drawn) against the room
 * without the panel; a light outside reaches the room only through that doorway. Closed must be
 * far off.
 *
 * Not tested, because the bake gets them wrong (found here; the renderer applies what is stored):
 *  - lights in sets with the door open: a set's bake keeps its light's bounce off the closed door
 *    (bake/sets/SETS.md), which opening the door must take away again; the combination state
 *    meant for it (lbk_combinations north+A) is a difference clamped at 0, so it cannot: this
 *    view was 3.5 % too bright against the lights static without the panel, with and without
 *    the combination states;
 *  - the closed door itself: tagged, it becomes an LLG object whose room side renders 20–37 %
 *    brighter than the same panel as plain (lightmapped) geometry. */
static void door(void **state)
{
    (void)state;
    char gs[160], gr[160], ls[2][160], lr[2][160];
    const ds_options ds = {.door = DS_DOOR_TAGGED, .outside_light = 1}, dr = {.outside_light = 1};
    room_pair("door", &ds, gs, ls);
    room_pair("door_removed", &dr, gr, lr);
    const tl_weight open = {"north", 1.0f}, closed = {"north", 0.0f};
    tl_render_options o = {.width = 80, .height = 60, .threads = 2, .doors = &open, .door_count = 1};
    o.camera = look(0.0f, 2.0f, 4.5f, 0.0f, 1.5f, -3.0f, 75); /* the north doorway in the middle */
    tl_render_options o_off = o;
    o_off.doors = &closed;
    agree("door", gs, ls, &o, &o_off, gr, lr);
}

/* Names the level does not have are usage errors; the renderer never guesses. */
static void refusals(void **state)
{
    (void)state;
    char lbk[128];
    snprintf(lbk, sizeof lbk, "%s/leak.lbk", tmpdir);
    if (access(lbk, R_OK)) bake(LEAK_SCENE, lbk, 1, 0, 0, 0);
    tl_image im;
    char err[TL_ERR_LEN];
    const tl_weight w = {"nope", 1.0f};
    tl_render_options o = {.width = 4, .height = 4, .sets = &w, .set_count = 1};
    assert_int_equal(tl_render(LEAK_SCENE, lbk, &o, &im, err), TL_RENDER_USAGE); /* no DLS at all */
    o.set_count = 0;
    assert_int_equal(tl_render("scenes/leak_rooms/leak_rooms.gltf", lbk, &o, &im, err), TL_RENDER_INPUT); /* other scene */
    assert_int_equal(tl_render(LEAK_SCENE, "/nonexistent.lbk", &o, &im, err), TL_RENDER_IO);
}

/* The command line is thin: the EXR it writes holds what tl_render returns, the PNG exists, and
 * every failure has its exit code. */
static int cmd(int n, const char **argv)
{
    return lbk_cmd_render(n, (char **)argv);
}

static void command_line(void **state)
{
    (void)state;
    char lbk[128], exr[128], png[128];
    snprintf(lbk, sizeof lbk, "%s/leak.lbk", tmpdir);
    snprintf(exr, sizeof exr, "%s/view.exr", tmpdir);
    snprintf(png, sizeof png, "%s/view.png", tmpdir);
    if (access(lbk, R_OK)) bake(LEAK_SCENE, lbk, 1, 0, 0, 0);
    const char *ok[] = {"render", LEAK_SCENE, lbk, "-o", exr, "--png", png, "--camera", "0", "--size", "32x24",
                        "--samples", "1", "--threads", "1", "-q", NULL};
    assert_int_equal(cmd(16, ok), LBK_EXIT_OK);
    static const char *const names[3] = {"R", "G", "B"};
    int w, h;
    float *px;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_exr_read(exr, 3, names, &w, &h, &px, err), 0);
    tl_render_options o = {.width = 32, .height = 24, .samples = 1, .threads = 1};
    assert_int_equal(tl_gltf_camera(LEAK_SCENE, 0, &o.camera, err), TL_RENDER_OK);
    tl_image im = render(LEAK_SCENE, lbk, &o);
    assert_int_equal(w, 32), assert_int_equal(h, 24);
    assert_memory_equal(px, im.rgb, sizeof(float) * 3 * 32 * 24);
    free(px), tl_image_free(&im);
    uint8_t *rgb8;
    assert_int_equal(tl_png_read_rgb8(png, &w, &h, &rgb8, err), 0);
    free(rgb8);
    const char *unknown_set[] = {"render", LEAK_SCENE, lbk, "-o", exr, "--set", "lamp=0", NULL};
    assert_int_equal(cmd(7, unknown_set), LBK_EXIT_USAGE); /* the level has no DLS */
    const char *other[] = {"render", "scenes/leak_rooms/leak_rooms.gltf", lbk, "-o", exr, NULL};
    assert_int_equal(cmd(5, other), LBK_EXIT_INPUT);
    const char *missing[] = {"render", LEAK_SCENE, "/nonexistent.lbk", "-o", exr, NULL};
    assert_int_equal(cmd(5, missing), LBK_EXIT_IO);
    const char *bad_size[] = {"render", LEAK_SCENE, lbk, "-o", exr, "--size", "0x3", NULL};
    assert_int_equal(cmd(7, bad_size), LBK_EXIT_USAGE);
    const char *no_output[] = {"render", LEAK_SCENE, lbk, NULL};
    assert_int_equal(cmd(3, no_output), LBK_EXIT_USAGE);
    /* strict numbers: atoi took "1.5" as 1 */
    const char *bad_threads[] = {"render", LEAK_SCENE, lbk, "-o", exr, "--threads", "1.5", NULL};
    assert_int_equal(cmd(7, bad_threads), LBK_EXIT_USAGE);
    const char *bad_samples[] = {"render", LEAK_SCENE, lbk, "-o", exr, "--samples", "-1", NULL};
    assert_int_equal(cmd(7, bad_samples), LBK_EXIT_USAGE);
    /* --max-memory: a zstd pack whose sections decode past the cap is refused before they are
     * allocated; the default cap renders it */
    char pack[128];
    snprintf(pack, sizeof pack, "%s/leak_zstd.lbk", tmpdir);
    const char *conv[] = {"convert", lbk, "-o", pack, "--profile", "archive", "-q", NULL};
    assert_int_equal(lbk_cmd_convert(7, (char **)conv), LBK_EXIT_OK);
    const char *capped[] = {"render", LEAK_SCENE, pack, "-o", exr, "--size", "8x6", "-q", "--max-memory", "1kB", NULL};
    assert_int_equal(cmd(10, capped), LBK_EXIT_INPUT);
    const char *uncapped[] = {"render", LEAK_SCENE, pack, "-o", exr, "--size", "8x6", "-q", NULL};
    assert_int_equal(cmd(8, uncapped), LBK_EXIT_OK);
}

/* Block-compressed packs render from their decoded texels (they were refused before). Every
 * pixel is a bilinear blend of texels (weights summing to one), each within the pack's error of
 * the source's, so the image's summed difference over its summed radiance is the texels' mean
 * error weighted by what the view sees: asserted against the pack goal's mean of 1 %, which the
 * leak scene's smooth walls meet (measured 0.27 % BC6H, 0.22 % ASTC); and it is lossy (not the
 * same image: the pack was drawn, not the bake). */
static void block_packs(void **state)
{
    (void)state;
    char lbk[128], pack[128];
    snprintf(lbk, sizeof lbk, "%s/leak.lbk", tmpdir);
    if (access(lbk, R_OK)) bake(LEAK_SCENE, lbk, 1, 0, 0, 0);
    tl_render_options o = {.width = 40, .height = 30, .samples = 1, .threads = 1};
    char err[TL_ERR_LEN];
    assert_int_equal(tl_gltf_camera(LEAK_SCENE, 0, &o.camera, err), TL_RENDER_OK);
    tl_image ref = render(LEAK_SCENE, lbk, &o);
    static const char *const profiles[] = {"console-current", "handheld"};
    for (int k = 0; k < 2; k++) {
        snprintf(pack, sizeof pack, "%s/leak_%s.lbk", tmpdir, profiles[k]);
        const char *conv[] = {"convert", lbk, "-o", pack, "--profile", profiles[k], "-q", NULL};
        assert_int_equal(lbk_cmd_convert(7, (char **)conv), LBK_EXIT_OK);
        tl_image im = render(LEAK_SCENE, pack, &o);
        double diff = 0, sum = 0;
        for (size_t i = 0; i < 3 * (size_t)o.width * (size_t)o.height; i++)
            diff += fabs((double)im.rgb[i] - ref.rgb[i]), sum += ref.rgb[i];
        print_message("%s: summed |difference| / summed radiance %.5f\n", profiles[k], diff / sum);
        assert_true(sum > 0);
        assert_true(diff > 0);
        assert_true(diff <= 0.01 * sum);
        tl_image_free(&im);
    }
    tl_image_free(&ref);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(furnace),
        cmocka_unit_test(leak),
        cmocka_unit_test(refusals),
        cmocka_unit_test(command_line),
        cmocka_unit_test(block_packs),
        cmocka_unit_test(light_sets),
        cmocka_unit_test(door),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
