/* Normal maps: the importer's normalTexture and tangents (scene/, bk_import_options.normal_maps)
 * and lbk render shading with them, against a closed form.
 *
 * The closed form. A 4 × 4 m floor (albedo ρ) lit only by one directional light of illuminance
 * E☉ from the unit direction l (towards the light), a black sky, nothing else: every texel's
 * light is direct and noise-free (one shadow ray along l). Its AHD texel (spec §5.6) holds
 * Ez = E☉ (N·l) along the normal, the highlight direction d = l and no ambient part (r = 0), so
 * the encoding's irradiance for a shading normal n is the band-1 form scaled to Ez:
 *     E(n) = Ez · (1 + 2 n·l) / (1 + 2 N·l),      L(n) = ρ/π · E(n).
 * The normal map has four stripes along u: flat, tilted by α towards +X (+u), towards −X, and
 * towards +Y (the image's up, −v: this one checks the bitangent's sign). Each stripe's rendered
 * radiance must be L(n') with n' the stripe's normal in world space, within the storage's
 * error: R11G11B10F rounds Ez to 2^-7 relative and the direction bytes move n·d by < 1/255,
 * under 1.5 % together; the test allows 2 % (measured: 0.5 % to 0.8 %, R11G11B10F's rounding of
 * Ez). The tilted stripes differ from the flat one by +10 % and −26 % (α = 30°), so a renderer
 * that ignores the map fails, and one that gets the bitangent's sign wrong fails on the +Y stripe. The band-1 form is not
 * Lambert's max(0, n·l) (for one light its error is what AHD trades for 8 bytes a texel); the
 * test prints both. */
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

#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/llg.h"
#include "lbk/sh.h"
#include "scene/import.h"
#include "support/bake_file.h"
#include "support/normal_scene.h"
#include "support/tmp_dir.h"
#include "tools/render/render.h"

#define PI 3.14159265358979323846

static char tmpdir[64];

static int setup(void **state)
{
    (void)state;
    return td_make(tmpdir, sizeof tmpdir, "lbk_test_normal");
}

static int teardown(void **state)
{
    (void)state;
    return td_remove(tmpdir); /* kept under $LBK_TEST_KEEP, for a look with lbk inspect */
}

static void path_of(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", tmpdir, name); }

static void write_bytes(const char *name, const void *data, size_t len)
{
    char p[256];
    path_of(p, sizeof p, name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
}

static void write_all(float tangent_w) { assert_int_equal(ns_write_all(tmpdir, tangent_w), 0); }

static void write_gltf(const char *name, int tangent, const char *material_extra, const char *node_extra)
{
    assert_int_equal(ns_write_gltf(tmpdir, name, tangent, material_extra, node_extra), 0);
}

static int import(const char *name, int normal_maps, bk_scene *s, char *err, size_t n)
{
    char p[256];
    path_of(p, sizeof p, name);
    const bk_import_options o = {.normal_maps = normal_maps};
    return bk_import_gltf(p, &o, s, err, n);
}

/* ---- import ----------------------------------------------------------------------------------- */

/* Derived and authored tangents give the same frame: T = +x, B = w (N × T) = −z (the image's up,
 * −v), so w = +1; the normal map is read as data (byte / 255, no sRGB decode). Without
 * normal_maps nothing of it is read (the bake's import). */
static void import_frame(void **state)
{
    (void)state;
    write_all(1.0f);
    const char *names[2] = {"derived.gltf", "authored.gltf"};
    for (int i = 0; i < 2; i++) {
        bk_scene s;
        char err[512];
        int rc = import(names[i], 1, &s, err, sizeof err);
        if (rc) fprintf(stderr, "%s\n", err);
        assert_int_equal(rc, 0);
        assert_int_equal(bk_scene_check(&s, err, sizeof err), 0);
        assert_non_null(s.tangents);
        for (size_t v = 0; v < s.vertex_count; v++) {
            assert_float_equal(s.tangents[4 * v + 0], 1.0f, 1e-6f);
            assert_float_equal(s.tangents[4 * v + 1], 0.0f, 1e-6f);
            assert_float_equal(s.tangents[4 * v + 2], 0.0f, 1e-6f);
            assert_float_equal(s.tangents[4 * v + 3], 1.0f, 0.0f);
        }
        const bk_material *m = &s.materials[0];
        assert_int_equal(m->normal_tex1, 1);
        assert_float_equal(m->normal_scale, 1.0f, 0.0f);
        const bk_image *im = &s.images[0];
        double n1[3];
        ns_stripe_normal(1, n1);
        assert_float_equal(im->rgba[4 * 2 + 0], ns_to_byte(n1[0]) / 255.0f, 1e-6f); /* texel (2, 0): stripe 1 */
        bk_scene_free(&s);
        assert_int_equal(import(names[i], 0, &s, err, sizeof err), 0);
        assert_null(s.tangents);
        assert_int_equal(s.materials[0].normal_tex1, 0);
        assert_int_equal((int)s.image_count, 0);
        bk_scene_free(&s);
    }
}

/* A mirroring node (scale x by −1) mirrors the frame: the authored tangent becomes −x and, as
 * the derived one, keeps B on the image's up (−z), so w turns −1 in both. */
static void import_mirrored(void **state)
{
    (void)state;
    write_all(1.0f);
    const char *node = ",\"scale\":[-1,1,1]";
    write_gltf("mirror_derived.gltf", 0, NS_NORMAL_TEX, node);
    write_gltf("mirror_authored.gltf", 1, NS_NORMAL_TEX, node);
    const char *names[2] = {"mirror_derived.gltf", "mirror_authored.gltf"};
    for (int i = 0; i < 2; i++) {
        bk_scene s;
        char err[512];
        assert_int_equal(import(names[i], 1, &s, err, sizeof err), 0);
        for (size_t v = 0; v < s.vertex_count; v++) {
            const float *t = &s.tangents[4 * v], *n = &s.normals[3 * v];
            assert_float_equal(n[1], 1.0f, 1e-6f);
            assert_float_equal(t[0], -1.0f, 1e-6f);
            /* B = w (N × T) = w · (0, 0, 1) for T = −x: −z needs w = −1 */
            assert_float_equal(t[3], -1.0f, 0.0f);
        }
        bk_scene_free(&s);
    }
}

/* KHR_texture_transform on the normal texture (the material's only texture, so its uv wins):
 * uv0 is the transformed one, and the derived tangent follows it (a mirrored u turns T to −x). */
static void import_transform(void **state)
{
    (void)state;
    write_all(1.0f);
    write_gltf("xf.gltf", 0,
               ",\"normalTexture\":{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"scale\":[-2,1]}}}", "");
    bk_scene s;
    char err[512];
    int rc = import("xf.gltf", 1, &s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    for (size_t v = 0; v < s.vertex_count; v++) {
        const float x = s.positions[3 * v];
        assert_float_equal(s.uv0[2 * v], -2.0f * (x + 2.0f) / 4.0f, 1e-6f); /* u' = −2 u */
        assert_float_equal(s.tangents[4 * v], -1.0f, 1e-6f);
        assert_float_equal(s.tangents[4 * v + 3], -1.0f, 0.0f); /* B = w (N × T) = −z still: w = −1 */
    }
    bk_scene_free(&s);
}

/* Hostile input: a TANGENT of the wrong type or count, a normalTexture out of range or with a
 * non-finite or absurd scale, is refused with a message naming it; nothing is read past a buffer. */
static void import_hostile(void **state)
{
    (void)state;
    write_all(1.0f);
    struct { const char *material, *needle; } bad[] = {
        {",\"normalTexture\":{\"index\":7}", "normal texture 7 out of range"},
        {",\"normalTexture\":{\"index\":0,\"scale\":1e300}", "normalTexture scale"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        write_gltf("bad.gltf", 0, bad[i].material, "");
        bk_scene s;
        char err[512];
        assert_int_not_equal(import("bad.gltf", 1, &s, err, sizeof err), 0);
        if (!strstr(err, bad[i].needle)) fail_msg("'%s' lacks '%s'", err, bad[i].needle);
        assert_null(s.tangents);
    }
    /* TANGENT pointing at the VEC2 uv accessor, then at a VEC4 running past its view */
    write_gltf("bad.gltf", 1, NS_NORMAL_TEX, "");
    char p[256], json[4096];
    path_of(p, sizeof p, "bad.gltf");
    FILE *f = fopen(p, "rb");
    assert_non_null(f);
    size_t n = fread(json, 1, sizeof json - 1, f);
    fclose(f);
    json[n] = '\0';
    char *t = strstr(json, "\"TANGENT\":3");
    assert_non_null(t);
    t[10] = '2';
    write_bytes("bad.gltf", json, n);
    bk_scene s;
    char err[512];
    assert_int_not_equal(import("bad.gltf", 1, &s, err, sizeof err), 0);
    if (!strstr(err, "TANGENT")) fail_msg("'%s' does not name TANGENT", err);
    t[10] = '3';
    char *c = strstr(json, "\"byteOffset\":128,\"componentType\":5126,\"count\":4");
    assert_non_null(c);
    c[strlen("\"byteOffset\":128,\"componentType\":5126,\"count\":")] = '5';
    write_bytes("bad.gltf", json, n);
    assert_int_not_equal(import("bad.gltf", 1, &s, err, sizeof err), 0);
    if (!strstr(err, "TANGENT")) fail_msg("'%s' does not name TANGENT", err);
    /* the bake's import ignores TANGENT: the same file imports without normal maps */
    assert_int_equal(import("bad.gltf", 0, &s, err, sizeof err), 0);
    bk_scene_free(&s);
}

/* ---- render ----------------------------------------------------------------------------------- */

static void bake(const char *gltf, const char *out, float glg_spacing)
{
    tb_job j;
    memset(&j, 0, sizeof j);
    j.in = gltf, j.out = out;
    j.d.threads = 2;
    j.d.seed = 1;
    j.d.texel_density = 4;
    j.d.glg_spacing = glg_spacing; /* 0: the preset's */
    char err[512];
    lbk_result r = tb_bake(&j, NULL, err, sizeof err);
    if (r != LBK_OK) fprintf(stderr, "bake %s: %s\n", gltf, err);
    assert_int_equal(r, LBK_OK);
}

#define W 160
#define H 120
#define CAM_H 6.0
#define FOV_DEG 50.0

static tl_image render(const char *gltf, const char *lbk)
{
    tl_render_options o;
    memset(&o, 0, sizeof o);
    o.width = W, o.height = H, o.samples = 1, o.threads = 2;
    /* straight down, image right = +x, image up = −z */
    o.camera = (tl_camera){{0, (float)CAM_H, 0}, {0, 0, 0}, {0, 0, -1}, (float)(FOV_DEG * PI / 180.0)};
    tl_image im;
    char err[TL_ERR_LEN];
    int rc = tl_render(gltf, lbk, &o, &im, err);
    if (rc) fprintf(stderr, "render: %s\n", err);
    assert_int_equal(rc, TL_RENDER_OK);
    return im;
}

/* The pixel column of world x at the floor (x grows to the right). */
static int column(double x)
{
    const double half_w = CAM_H * tan(FOV_DEG * PI / 360.0) * W / H;
    return (int)floor(W / 2.0 + x / half_w * (W / 2.0));
}

/* Every pixel of a 7 × 7 block at stripe k's centre (rows at z = ±0.75 m) against the closed form. */
static double check_stripe(const tl_image *im, int k, int normal_mapped, const char *what)
{
    double lambert;
    const double want = ns_closed_form(k, normal_mapped, &lambert);
    const int x0 = column(-1.5 + k);
    double worst = 0, mean = 0;
    int count = 0;
    for (int r = 0; r < 2; r++) {
        const int y0 = r ? H / 2 - 15 : H / 2 + 15;
        for (int dy = -3; dy <= 3; dy++)
            for (int dx = -3; dx <= 3; dx++)
                for (int c = 0; c < 3; c++) {
                    const double got = im->rgb[3 * ((size_t)(y0 + dy) * W + (size_t)(x0 + dx)) + (size_t)c];
                    worst = fmax(worst, fabs(got / want - 1));
                    mean += got, count++;
                }
    }
    mean /= count;
    printf("%s stripe %d: L %.5f  closed form %.5f (%+.2f %%)  Lambert %.5f (band-1 %+.1f %%)  worst %.2f %%\n",
           what, k, mean, want, 100 * (mean / want - 1), lambert, 100 * (want / lambert - 1), 100 * worst);
    if (worst > 0.02) fail_msg("%s stripe %d: %.2f %% from the closed form (bound 2 %%)", what, k, 100 * worst);
    return mean;
}

static void render_closed_form(void **state)
{
    (void)state;
    write_all(1.0f);
    char gltf[256], lbk[256];
    path_of(gltf, sizeof gltf, "derived.gltf");
    path_of(lbk, sizeof lbk, "floor.lbk");
    bake(gltf, lbk, 0);
    tl_image im = render(gltf, lbk);
    double got[4];
    for (int k = 0; k < 4; k++) got[k] = check_stripe(&im, k, 1, "derived");
    /* the map is not ignored: every tilted stripe is far (> 5x the bound) from the flat one */
    for (int k = 1; k < 4; k++) assert_true(fabs(got[k] / got[0] - 1) > 0.08);
    tl_image_free(&im);

    /* authored TANGENT (the same frame): the same image, pixel for pixel */
    path_of(gltf, sizeof gltf, "authored.gltf");
    tl_image au = render(gltf, lbk);
    for (int k = 0; k < 4; k++) check_stripe(&au, k, 1, "authored");
    tl_image_free(&au);

    /* the same bake drawn without the normal map: flat everywhere (its geometry is the same) */
    path_of(gltf, sizeof gltf, "flat.gltf");
    tl_image fl = render(gltf, lbk);
    for (int k = 0; k < 4; k++) check_stripe(&fl, k, 0, "no map");
    tl_image_free(&fl);

    /* an authored TANGENT with w = −1 puts the map's +Y on +z: the +Y stripe turns away */
    assert_int_equal(ns_write_floor_bin(tmpdir, -1.0f), 0);
    path_of(gltf, sizeof gltf, "authored.gltf");
    tl_image fw = render(gltf, lbk);
    const double y_stripe = fw.rgb[3 * ((size_t)(H / 2 + 15) * W + (size_t)column(1.5))];
    printf("w = -1: +Y stripe %.5f against %.5f\n", y_stripe, got[3]);
    assert_true(y_stripe < 0.9 * got[3]);
    tl_image_free(&fw);
}

/* A probe-lit floor (lbk_lighting "none": the GLG, as any dynamic object) with the same map: each
 * stripe's pixel is ρ/π · E_sh(n') of the GLG's SH9 sampled at the hit point (lbk_glg_sample,
 * lbk_sh9_irradiance), n' the stripe's world normal, within float rounding (1e-3); and the tilted
 * stripes differ from E_sh(N) at the same point (> 3 %), so the renderer passes n', not N. */
static void render_probe_lit(void **state)
{
    (void)state;
    write_all(1.0f);
    assert_int_equal(ns_write_gltf_lit(tmpdir, "dynamic.gltf", 0, NS_NORMAL_TEX, "", "none"), 0);
    char gltf[256], lbk[256];
    path_of(gltf, sizeof gltf, "dynamic.gltf");
    path_of(lbk, sizeof lbk, "dynamic.lbk");
    bake(gltf, lbk, 0.3f); /* probe layers between the ground and above the floor, none at y = 0 */
    tl_image im = render(gltf, lbk);
    lbk_reader *rd;
    assert_int_equal(lbk_reader_open_file(lbk, NULL, &rd), LBK_OK);
    const void *gd;
    size_t gn;
    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_GLG, &gd, &gn), LBK_OK);
    lbk_glg_view gv;
    assert_int_equal(lbk_glg_open(gd, gn, &gv), LBK_OK);
    const double half_h = CAM_H * tan(FOV_DEG * PI / 360.0), half_w = half_h * W / H;
    double got[4], flat[4];
    for (int k = 0; k < 4; k++) {
        const int x0 = column(-1.5 + k), y0 = H / 2 + 15;
        /* the centre ray's hit: image right = +x, image down = +z */
        const float p[3] = {(float)(((x0 + 0.5) - W / 2.0) / (W / 2.0) * half_w), 0.0f,
                            (float)(((y0 + 0.5) - H / 2.0) / (H / 2.0) * half_h)};
        double nd[3];
        ns_world_normal(k, nd);
        const float n[3] = {(float)nd[0], (float)nd[1], (float)nd[2]};
        lbk_sh9_rgb sh;
        uint32_t hint = 0;
        assert_int_equal(lbk_glg_sample(&gv, p, &hint, &sh, NULL), LBK_OK);
        float E[3];
        lbk_sh9_irradiance(&sh, n, E);
        const double want = NS_RHO / PI * fmax(E[1], 0.0f);
        const float up[3] = {0, 1, 0};
        lbk_sh9_irradiance(&sh, up, E); /* the same point without the map */
        flat[k] = NS_RHO / PI * fmax(E[1], 0.0f);
        got[k] = im.rgb[3 * ((size_t)y0 * W + (size_t)x0) + 1];
        printf("probe-lit stripe %d: L %.5f  GLG at n' %.5f (%+.3f %%), at N %.5f\n", k, got[k], want,
               100 * (got[k] / want - 1), flat[k]);
        assert_true(fabs(got[k] / want - 1) < 1e-3);
    }
    for (int k = 1; k < 4; k++) assert_true(fabs(got[k] / flat[k] - 1) > 0.03); /* the map is not ignored */
    lbk_reader_close(rd);
    tl_image_free(&im);
}

/* v turned by the smallest rotation taking unit a to unit b (Rodrigues): a normal map turns an
 * LLG vertex's bent normal as it turns N. */
static void turn(const double a[3], const double b[3], const double v[3], double out[3])
{
    const double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const double k[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const double kv[3] = {k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
    const double f = (k[0] * v[0] + k[1] * v[1] + k[2] * v[2]) / (1 + c);
    for (int i = 0; i < 3; i++) out[i] = v[i] * c + kv[i] + k[i] * f;
}

/* The floor as an LLG object: its four vertex records are alike (a flat, unoccluded floor), so
 * every pixel's interpolated V and bent normal are theirs; each stripe's pixel is
 * ρ/π · V · E_sh(grid SH at the hit, bent turned by N → n') within float rounding (1e-3), and the
 * tilted ones differ from the unturned bent normal's (> 3 %). */
static void render_llg(void **state)
{
    (void)state;
    write_all(1.0f);
    assert_int_equal(ns_write_gltf_lit(tmpdir, "llg.gltf", 0, NS_NORMAL_TEX, "", "llg"), 0);
    char gltf[256], lbk[256];
    path_of(gltf, sizeof gltf, "llg.gltf");
    path_of(lbk, sizeof lbk, "llg.lbk");
    bake(gltf, lbk, 0.3f);
    tl_image im = render(gltf, lbk);
    lbk_reader *rd;
    assert_int_equal(lbk_reader_open_file(lbk, NULL, &rd), LBK_OK);
    const void *ld;
    size_t ln;
    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_LLG, &ld, &ln), LBK_OK);
    lbk_llg_view lv;
    lbk_llg_grid g;
    assert_int_equal(lbk_llg_open(ld, ln, &lv), LBK_OK);
    assert_int_equal(lbk_llg_grid_get(&lv, 0, &g), LBK_OK);
    assert_int_equal(g.vertex_count, 4);
    lbk_llg_vertex v0;
    lbk_llg_vertex_unpack(lv.vertices + 4 * g.vertex_offset, &v0);
    for (uint32_t r = 1; r < 4; r++)
        assert_memory_equal(lv.vertices + 4 * (g.vertex_offset + r), lv.vertices + 4 * g.vertex_offset, 4);
    double bent[3] = {0, 0, 0}, l = 0;
    for (int a = 0; a < 3; a++)
        for (int k = 0; k < 3; k++) bent[k] += v0.bent_normal[a] * g.axes[a][k]; /* box -> world */
    l = sqrt(bent[0] * bent[0] + bent[1] * bent[1] + bent[2] * bent[2]);
    for (int k = 0; k < 3; k++) bent[k] /= l;
    const double half_h = CAM_H * tan(FOV_DEG * PI / 360.0), half_w = half_h * W / H, N[3] = {0, 1, 0};
    double got[4], flat[4];
    for (int k = 0; k < 4; k++) {
        const int x0 = column(-1.5 + k), y0 = H / 2 + 15;
        const float p[3] = {(float)(((x0 + 0.5) - W / 2.0) / (W / 2.0) * half_w), 0.0f,
                            (float)(((y0 + 0.5) - H / 2.0) / (H / 2.0) * half_h)};
        double n[3], b[3];
        ns_world_normal(k, n);
        turn(N, n, bent, b);
        const double bl = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        const float bf[3] = {(float)(b[0] / bl), (float)(b[1] / bl), (float)(b[2] / bl)};
        lbk_sh9_rgb sh;
        assert_int_equal(lbk_llg_sample(&lv, 0, p, &sh), LBK_OK);
        float E[3];
        lbk_sh9_irradiance(&sh, bf, E);
        const double want = NS_RHO / PI * v0.visibility * fmax(E[1], 0.0f);
        const float bn[3] = {(float)bent[0], (float)bent[1], (float)bent[2]};
        lbk_sh9_irradiance(&sh, bn, E); /* the same point without the map */
        flat[k] = NS_RHO / PI * v0.visibility * fmax(E[1], 0.0f);
        got[k] = im.rgb[3 * ((size_t)y0 * W + (size_t)x0) + 1];
        printf("LLG stripe %d: V %.3f  L %.5f  V E_sh(turned bent) %.5f (%+.3f %%), unturned %.5f\n", k, v0.visibility,
               got[k], want, 100 * (got[k] / want - 1), flat[k]);
        assert_true(fabs(got[k] / want - 1) < 1e-3);
    }
    for (int k = 1; k < 4; k++) assert_true(fabs(got[k] / flat[k] - 1) > 0.03); /* the map is not ignored */
    lbk_reader_close(rd);
    tl_image_free(&im);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(import_frame),
        cmocka_unit_test(import_mirrored),
        cmocka_unit_test(import_transform),
        cmocka_unit_test(import_hostile),
        cmocka_unit_test(render_closed_form),
        cmocka_unit_test(render_probe_lit),
        cmocka_unit_test(render_llg),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
