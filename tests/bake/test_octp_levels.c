/* The OCTP volume's clip levels (seed 003: up to 3 clips of 32³, each coarser level doubling the
 * spacing around the same centre; bake/probes/PROBES.md §OCTP): the level rule on known bounds,
 * and a baked two-level volume sampled in the blend band of the finer level (spec §14.3 step 7:
 * δ·E_0 + (1 − δ)·E_1), outside it (the coarser level alone) and deep inside it (the finer
 * level alone), each against the sampler run on one level of the same file. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "bake/probes/octa_bake.h"
#include "lbk/bake.h"
#include "lbk/container.h"
#include "lbk/octa.h"
#include "lbk/validate.h"
#include "support/transport_scenes.h"
#include "tools/common/bake_data.h"
#include "tools/common/image_io.h"
#include "tools/convert/export.h"

static void assert_level(const lbk_octp_level *l, float spacing, uint32_t dx, uint32_t dy, uint32_t dz, float ox,
                         float oy, float oz, uint32_t first)
{
    assert_float_equal(l->spacing, spacing, 1e-6);
    assert_int_equal(l->dims[0], dx);
    assert_int_equal(l->dims[1], dy);
    assert_int_equal(l->dims[2], dz);
    assert_float_equal(l->origin[0], ox, 1e-5);
    assert_float_equal(l->origin[1], oy, 1e-5);
    assert_float_equal(l->origin[2], oz, 1e-5);
    assert_int_equal(l->first_probe, first);
}

/* A 40 × 4 × 40 m floor at 1 m with clips of 8: level 0 is the 8 m around the centre (y clipped
 * to the 4 m of the bounds), level 1 the 16 m at 2 m, and level 2, the last allowed, the whole
 * bounds: 4 m would need 10 probes, so its spacing grows by 1.25 to 5 m (8 probes). One level
 * allowed: the old rule (1 m × 1.25⁸ = 5.96 m, 7 probes). Small bounds: one level whatever is
 * allowed. A centre outside the bounds is clamped into them. */
static void level_rule(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    const uint32_t m = tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    const float f0[3] = {-20, 0, -20}, f1[3] = {-20, 0, 20}, f2[3] = {20, 0, 20}, f3[3] = {20, 0, -20};
    tsc_quad(&s, f0, f1, f2, f3, 1, m);
    tsc_update_bounds(&s);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &t), LBK_OK);
    const float bmin[3] = {-20, 0, -20}, bmax[3] = {20, 4, 20};
    bk_octa_options o = {.spacing = 1, .clip = 8};
    bk_octa_volume v;
    assert_int_equal(bk_octa_place(&s, t, bmin, bmax, &o, &v), LBK_OK);
    assert_int_equal(v.level_count, 3);
    assert_level(&v.levels[0], 1, 8, 4, 8, -3.5f, 0.5f, -3.5f, 0);
    assert_level(&v.levels[1], 2, 8, 2, 8, -7, 1, -7, 256);
    assert_level(&v.levels[2], 5, 8, 2, 8, -17.5f, -0.5f, -17.5f, 384);
    assert_int_equal(v.count, 512);
    assert_int_equal(bk_octa_probe_level(&v, 255), 0);
    assert_int_equal(bk_octa_probe_level(&v, 256), 1);
    assert_int_equal(bk_octa_probe_level(&v, 511), 2);
    /* grid points: probe 256 is level 1's (0, 0, 0) */
    for (int a = 0; a < 3; a++)
        assert_float_equal(v.positions[3 * 256 + a] - v.info[256].offset[a], v.levels[1].origin[a], 1e-6);
    bk_octa_volume_free(&v);

    o.levels = 1;
    assert_int_equal(bk_octa_place(&s, t, bmin, bmax, &o, &v), LBK_OK);
    assert_int_equal(v.level_count, 1);
    assert_level(&v.levels[0], 5.9604645f, 7, 2, 7, -17.881393f, 2 - 0.5f * 5.9604645f, -17.881393f, 0);
    bk_octa_volume_free(&v);

    const float smin[3] = {-3, 0, -3}, smax[3] = {3, 4, 3}; /* 6 spacings: fits one clip */
    o.levels = 0;
    assert_int_equal(bk_octa_place(&s, t, smin, smax, &o, &v), LBK_OK);
    assert_int_equal(v.level_count, 1);
    assert_level(&v.levels[0], 1, 6, 4, 6, -2.5f, 0.5f, -2.5f, 0);
    bk_octa_volume_free(&v);

    o.has_centre = 1;
    o.centre[0] = 100, o.centre[1] = 2, o.centre[2] = 100; /* clamped to (20, 2, 20) */
    assert_int_equal(bk_octa_place(&s, t, bmin, bmax, &o, &v), LBK_OK);
    assert_int_equal(v.level_count, 3);
    assert_level(&v.levels[0], 1, 4, 4, 4, 16.5f, 0.5f, 16.5f, 0); /* [16, 20]: 4 probes */
    assert_level(&v.levels[1], 2, 4, 2, 4, 13, 1, 13, 64);
    bk_octa_volume_free(&v);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static float lum3(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

static void sample(const lbk_octp_view *v, const float p[3], const float n[3], uint32_t flags, float rgb[3])
{
    lbk_octp_sample_desc d = LBK_OCTP_SAMPLE_DESC_INIT;
    memcpy(d.position, p, 12);
    memcpy(d.normal, n, 12);
    d.flags = flags;
    assert_int_equal(lbk_octp_sample(v, &d, rgb, NULL), LBK_OK);
}

/* δ of spec §14.3 step 7 for level l of v at p (normal n, default biases), or -1 when the
 * biased point is outside the level's box. */
static float blend_delta(const lbk_octp_view *v, uint32_t l, const float p[3], const float n[3])
{
    const lbk_octp_level *lv = &v->levels[l];
    float d = INFINITY;
    for (int a = 0; a < 3; a++) {
        const float g = (p[a] + 0.2f * lv->spacing * n[a] - lv->origin[a]) / lv->spacing;
        if (g < 0 || g > (float)(lv->dims[a] - 1)) return -1;
        d = fminf(d, fminf(g, (float)(lv->dims[a] - 1) - g));
    }
    return d;
}

/* lbk export's atlases of every level (tools/convert/export_octp.c): each probe's tile holds its
 * interior texels exactly (EXR float), at tile (x, y + dims_y·z) of its level's image. */
static void export_levels(const void *bytes, size_t size, const lbk_octp_view *ov)
{
    tl_bake tb;
    char err[TL_ERR_LEN], dir[] = "/tmp/test_octp_levels_XXXXXX";
    assert_int_equal(tl_bake_open_memory(bytes, size, &tb, err), TL_OPEN_OK);
    assert_non_null(mkdtemp(dir));
    tl_export_stats st;
    memset(&st, 0, sizeof st);
    assert_int_equal(tl_export_octp(&tb, dir, &st, err), 0);
    assert_int_equal(st.exr_files, 2 * ov->level_count);
    static const char *const RGB[3] = {"R", "G", "B"}, *const M[2] = {"m1", "m2"};
    for (uint32_t l = 0; l < ov->level_count; l++) {
        const lbk_octp_level *lv = &ov->levels[l];
        char path[256];
        int w, h, wd, hd;
        float *irr, *dep;
        snprintf(path, sizeof path, "%s/octp_level_%u.exr", dir, l);
        assert_int_equal(tl_exr_read(path, 3, RGB, &w, &h, &irr, err), 0);
        remove(path);
        snprintf(path, sizeof path, "%s/octp_level_%u.depth.exr", dir, l);
        assert_int_equal(tl_exr_read(path, 2, M, &wd, &hd, &dep, err), 0);
        remove(path);
        assert_int_equal(w, 4 * (int)lv->dims[0]);
        assert_int_equal(h, 4 * (int)(lv->dims[1] * lv->dims[2]));
        assert_int_equal(wd, 12 * (int)lv->dims[0]);
        /* the last probe of the level: tile (dims0 − 1, dims1·dims2 − 1); texel (i, j) = (3, 1) */
        lbk_octp_probe_desc pd;
        const uint32_t k = lv->dims[0] * lv->dims[1] * lv->dims[2] - 1;
        assert_int_equal(lbk_octp_probe_get(ov, lv->first_probe + k, &pd), LBK_OK);
        const int x0 = 4 * ((int)lv->dims[0] - 1), y0 = h - 4;
        for (int c = 0; c < 3; c++) assert_float_equal(irr[3 * ((y0 + 1) * w + x0 + 3) + c], pd.irradiance[1 * 4 + 3][c], 0);
        const int xd = 12 * ((int)lv->dims[0] - 1), yd = hd - 12;
        for (int c = 0; c < 2; c++) assert_float_equal(dep[2 * ((yd + 5) * wd + xd + 7) + c], pd.depth[5 * 12 + 7][c], 0);
        free(irr), free(dep);
    }
    rmdir(dir);
    tl_bake_close(&tb);
}

/* A closed 6 × 3 × 2.5 m room (grey, faces inward), a 20 cd lamp off-centre, baked through the
 * library with --octp-spacing 0.5 --octp-clip 6: level 0 is the 3 m around the centre at 0.5 m
 * (6 × 6 × 5 probes), level 1 the whole room at 1 m (6 × 3 × 3), the last since it holds it. */
static void blend_on_baked_volume(void **state)
{
    (void)state;
    float pos[8 * 3];
    for (int i = 0; i < 8; i++) {
        pos[3 * i] = i & 1 ? 3.0f : -3.0f;
        pos[3 * i + 1] = i & 2 ? 3.0f : 0.0f;
        pos[3 * i + 2] = i & 4 ? 2.5f : 0.0f;
    }
    /* inward faces: the outward quads of a box, reversed */
    static const uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    uint32_t idx[36];
    for (int k = 0; k < 6; k++) {
        const uint32_t q[4] = {f[k][3], f[k][2], f[k][1], f[k][0]};
        const uint32_t tr[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
        memcpy(&idx[6 * k], tr, sizeof tr);
    }
    lbk_bake_material mat = {"grey", {0.5f, 0.5f, 0.5f}, {0, 0, 0}, 0};
    lbk_bake_object obj = {"room", 0, 12, 0, LBK_BAKE_LIGHTING_NONE, 0, NULL, NULL};
    lbk_bake_light light = {"lamp", LBK_BAKE_LIGHT_POINT, {20, 20, 20}, {-2.0f, 1.5f, 1.25f}, {0, 0, 0}, 0, 0, 0, NULL};
    lbk_bake_scene sc = {0};
    sc.name = "clip_room";
    sc.vertex_count = 8;
    sc.positions = pos;
    sc.triangle_count = 12;
    sc.indices = idx;
    sc.material_count = 1;
    sc.materials = &mat;
    sc.object_count = 1;
    sc.objects = &obj;
    sc.light_count = 1;
    sc.lights = &light;
    lbk_bake_desc d = {0};
    d.size = sizeof d;
    d.seed = 3;
    d.threads = 2;
    d.max_samples = 128;
    d.octahedral_probes = 1;
    d.octp_spacing = 0.5f;
    d.octp_clip = 6;
    d.denoise = LBK_BAKE_DENOISE_OFF;
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&sc, &d, &out), LBK_OK);
    assert_int_equal(lbk_bake_output_report(out)->octp_levels, 2);
    void *bytes;
    size_t size;
    assert_int_equal(lbk_bake_output_container(out, &bytes, &size), LBK_OK);
    lbk_validate_summary vs;
    assert_int_equal(lbk_validate_memory(bytes, size, NULL, NULL, NULL, &vs), LBK_OK);
    assert_int_equal(vs.fatal + vs.errors, 0);
    lbk_reader *rd;
    assert_int_equal(lbk_reader_open_memory(bytes, size, NULL, &rd), LBK_OK);
    const void *od;
    size_t on;
    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_OCTP, &od, &on), LBK_OK);
    lbk_octp_view ov;
    assert_int_equal(lbk_octp_open(od, on, &ov), LBK_OK);
    assert_int_equal(ov.level_count, 2);
    assert_level(&ov.levels[0], 0.5f, 6, 6, 5, -1.25f, 0.25f, 0.25f, 0);
    assert_level(&ov.levels[1], 1.0f, 6, 3, 3, -2.5f, 0.5f, 0.25f, 180);
    assert_int_equal(ov.probe_count, 180 + 54);
    /* both levels carry light: every active probe of each sees the lamp's room */
    for (uint32_t i = 0; i < ov.probe_count; i++) {
        lbk_octp_probe_info in;
        lbk_octp_probe_desc pd;
        assert_int_equal(lbk_octp_probe_info_get(&ov, i, &in), LBK_OK);
        assert_int_equal(in.state == LBK_OCTP_INSIDE, 0);
        assert_int_equal(lbk_octp_probe_get(&ov, i, &pd), LBK_OK);
        float mx = 0;
        for (int k = 0; k < 16; k++) mx = fmaxf(mx, lum3(pd.irradiance[k]));
        assert_true(mx > 0.05f);
    }
    /* one-level views of the same bytes: level 0 alone, level 1 alone */
    lbk_octp_view v0 = ov, v1 = ov;
    v0.level_count = 1;
    v1.levels[0] = ov.levels[1];
    v1.level_count = 1;
    const float nx[3] = {1, 0, 0}, nz[3] = {0, 0, 1};
    float e[3], e0[3], e1[3];
    /* in the band: biased x = 1.1, 0.3 cells inside level 0's last cell (x ≤ 1.25) */
    const float pb[3] = {1.0f, 1.5f, 1.25f};
    const float delta = blend_delta(&ov, 0, pb, nx);
    assert_float_equal(delta, 0.3f, 1e-5);
    sample(&ov, pb, nx, 0, e);
    sample(&v0, pb, nx, 0, e0);
    sample(&v1, pb, nx, 0, e1);
    print_message("band: E %.5f, level 0 %.5f, level 1 %.5f, delta %.3f\n", lum3(e), lum3(e0), lum3(e1), delta);
    for (int k = 0; k < 3; k++) assert_float_equal(e[k], delta * e0[k] + (1 - delta) * e1[k], 1e-5 * e1[k] + 1e-7);
    assert_true(fabsf(lum3(e0) - lum3(e1)) > 1e-3f * lum3(e1)); /* the blend is visible: the levels differ */
    /* NO_BLEND: level 0 only */
    sample(&ov, pb, nx, LBK_OCTP_SAMPLE_NO_BLEND, e);
    for (int k = 0; k < 3; k++) assert_float_equal(e[k], e0[k], 0);
    /* outside level 0 (biased x = 2.3 > 1.25): level 1 alone, no blend */
    const float po[3] = {2.2f, 1.5f, 1.25f};
    assert_true(blend_delta(&ov, 0, po, nx) < 0);
    sample(&ov, po, nx, 0, e);
    sample(&v1, po, nx, 0, e1);
    for (int k = 0; k < 3; k++) assert_float_equal(e[k], e1[k], 0);
    /* deep inside level 0 (δ = 2.2 ≥ 1): level 0 alone */
    const float pi[3] = {0, 1.5f, 1.25f};
    assert_true(blend_delta(&ov, 0, pi, nz) >= 1);
    sample(&ov, pi, nz, 0, e);
    sample(&v0, pi, nz, 0, e0);
    for (int k = 0; k < 3; k++) assert_float_equal(e[k], e0[k], 0);
    /* continuity at the band's outer edge: just inside level 0's box the blend is all level 1 */
    const float pe[3] = {1.25f - 0.1f - 1e-4f, 1.5f, 1.25f};
    sample(&ov, pe, nx, 0, e);
    sample(&v1, pe, nx, 0, e1);
    for (int k = 0; k < 3; k++) assert_float_equal(e[k], e1[k], 1e-3 * e1[k]);
    export_levels(bytes, size, &ov);
    lbk_reader_close(rd);
    lbk_free(NULL, bytes);
    lbk_bake_output_free(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(level_rule),
        cmocka_unit_test(blend_on_baked_volume),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
