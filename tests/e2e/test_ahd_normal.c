/* Plane 0 of an AHD texel holds the irradiance along the surface normal (spec §5.6). The AHD
 * model itself is band-1 irradiance, which for light arriving head-on is 3/4 of the truth; the
 * baker stores the transport's direct estimate along the normal instead
 * (bk_texel_match_irradiance), so a floor under a point light reads I/h² below it, not 0.75·I/h².
 * The point light's direct light is noise-free (shadow rays to a point), so the bound is the
 * texel's offset from the foot of the light plus R11G11B10F rounding, not noise. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/pixel.h"
#include "support/bake_file.h"
#include "support/gltf_writer.h"

#define DENSITY 8.0f   /* texels per metre */
#define HEIGHT 1.0     /* the light above the floor, metres */
#define CANDELA 50.0f

/* A 4 × 4 m floor (y up, facing +y) with authored lightmap UVs, a point light HEIGHT above its
 * centre, nothing else: the floor sees no other surface, so all its light is direct. */
static void write_floor(const char *path)
{
    gw_scene *sc = gw_create();
    const float grey[3] = {0.5f, 0.5f, 0.5f}, white[3] = {1, 1, 1};
    int m = gw_material(sc, grey, NULL, 0, 0);
    gw_geom floor = {0};
    const float p0[3] = {-2, 0, 2}, p1[3] = {2, 0, 2}, p2[3] = {2, 0, -2}, p3[3] = {-2, 0, -2};
    gw_geom_quad(&floor, p0, p1, p2, p3, 4);
    gw_mesh(sc, "floor", &floor, m, 1, NULL, "lightmap");
    const double lp[3] = {0, HEIGHT, 0};
    gw_point_light(sc, white, CANDELA, lp);
    assert_int_equal(gw_write(sc, path), 0);
    gw_geom_free(&floor);
    gw_free(sc);
}

/* The largest green irradiance along the normal over every texel, physical (lux). */
static double max_ez(const char *lbk)
{
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_file(lbk, NULL, &r), LBK_OK);
    const void *data;
    size_t size;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &data, &size), LBK_OK);
    lbk_lmap_view v;
    assert_int_equal(lbk_lmap_open(data, size, &v), LBK_OK);
    double best = 0;
    for (uint64_t t = 0; t < v.texel_count; t++) {
        lbk_ahd_texel tx;
        float ez[3];
        assert_int_equal(lbk_lmap_texel_get(&v, t, &tx, NULL), LBK_OK);
        lbk_r11g11b10f_unpack(tx.irradiance_z, ez);
        if (ez[1] * v.scale > best) best = ez[1] * v.scale;
    }
    lbk_reader_close(r);
    return best;
}

static void test_head_on_light_is_stored_exactly(void **state)
{
    (void)state;
    char dir[] = "/tmp/lbk-ahd-normal-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char gltf[256], out[256];
    snprintf(gltf, sizeof gltf, "%s/floor.gltf", dir);
    snprintf(out, sizeof out, "%s/floor.lbk", dir);
    write_floor(gltf);

    tb_job j;
    memset(&j, 0, sizeof j);
    j.in = gltf;
    j.out = out;
    j.d.preset = LBK_BAKE_PRESET_FAST;
    j.d.seed = 1;
    j.d.threads = 2;
    j.d.max_samples = 16;
    j.d.texel_density = DENSITY;
    j.d.no_glg = 1;
    char err[512];
    if (tb_bake(&j, NULL, err, sizeof err) != LBK_OK) fail_msg("bake: %s", err);

    /* The texel centre nearest the foot of the light is at most half a texel diagonal away:
     * ρ ≤ √2 / (2·DENSITY) = 0.088 m, where E = I·h/(h² + ρ²)^{3/2} ≥ 0.988·I/h². R11G11B10F
     * rounds G to 6 mantissa bits (relative error ≤ 2^-7). So the brightest texel lies in
     * [0.988·(1 − 2^-7), 1 + 2^-7]·I/h² = [0.980, 1.008]·I/h²; band-1 gives 0.75·I/h². */
    const double e = CANDELA / (HEIGHT * HEIGHT);
    const double got = max_ez(out) / e;
    print_message("brightest texel %.4f of I/h^2\n", got);
    assert_true(got >= 0.980 && got <= 1.008);

    unlink(gltf), unlink(out);
    char bin[256];
    snprintf(bin, sizeof bin, "%s/floor.bin", dir);
    unlink(bin);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_head_on_light_is_stored_exactly),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
