/* lbk diff's noise mode and provenance on real bakes of two rooms that cannot see each other
 * (support/diff_scenes.h: room A lit by the sky only, room B by a lamp only), each variant with
 * its own seed:
 *   - a reseed is equal within noise (every object, the GLG);
 *   - a 5 % brighter sky is detected on every object of A and on none of B;
 *   - the lamp moved 0.5 m, or one wall of B at half its albedo, is detected on B's objects and on
 *     none of A's;
 *   - the same pairs in exact tolerance mode all differ (tolerance cannot tell noise from change);
 *   - the inputs that changed are named: "seed 1 -> 2", "sky 1,1,1 -> 1.05…", the lamp's position,
 *     the wall's material and "object B_wall_east material changed". */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/bake.h"
#include "support/diff_scenes.h"
#include "tools/inspect/diff.h"

enum { BASE, RESEED, SKY, LAMP, ALBEDO, BAKES };
static tl_bake bakes[BAKES];

static void bake_variant(int which, ds_variant v, uint64_t seed)
{
    ds_store st;
    lbk_bake_scene sc;
    ds_build(&v, &st, &sc);
    lbk_bake_desc d = {0};
    d.seed = seed;
    d.max_samples = 1024;
    d.target_error = 0.02; /* ~1.5 %: the 5 % sky is then several times the noise of an object's mean */
    lbk_bake_output *out;
    assert_int_equal(lbk_bake_from_scene(&sc, &d, &out), LBK_OK);
    void *bytes;
    size_t size;
    assert_int_equal(lbk_bake_output_container(out, &bytes, &size), LBK_OK);
    char err[TL_ERR_LEN];
    if (tl_bake_open_memory(bytes, size, &bakes[which], err) != TL_OPEN_OK) fail_msg("%s", err);
    lbk_free(NULL, bytes);
    lbk_bake_output_free(out);
    ds_free(&st);
}

static int setup(void **state)
{
    (void)state;
    ds_variant v = DS_BASE;
    bake_variant(BASE, v, 1);
    bake_variant(RESEED, v, 2);
    v = DS_BASE;
    v.sky = 1.05f;
    bake_variant(SKY, v, 3);
    v = DS_BASE;
    v.lamp_offset[0] = 0.5f;
    bake_variant(LAMP, v, 4);
    v = DS_BASE;
    v.wall_albedo = 0.35f;
    bake_variant(ALBEDO, v, 5);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    for (int i = 0; i < BAKES; i++) tl_bake_close(&bakes[i]);
    return 0;
}

static void run(int b, int mode, tl_diff_result *r)
{
    tl_diff_options o = {0};
    o.mode = mode;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_diff_run(&bakes[BASE], &bakes[b], &o, r, err), 0);
}

static const tl_diff_change *find_change(const tl_diff_result *r, int kind, const char *name)
{
    for (size_t i = 0; i < r->change_count; i++)
        if (r->changes[i].kind == kind && !strcmp(r->changes[i].name, name)) return &r->changes[i];
    return NULL;
}

/* Every object of room A (want_a) and of room B (want_b) beyond noise or within it, as asked. */
static void expect_rooms(const tl_diff_result *r, int a_changed, int b_changed)
{
    assert_int_equal(r->mode, TL_DIFF_MODE_NOISE);
    assert_int_equal(r->object_count, DS_OBJECTS);
    int seen_a = 0, seen_b = 0;
    for (size_t i = 0; i < r->object_count; i++) {
        const tl_diff_object *o = &r->objects[i];
        assert_true(o->compared);
        assert_true(o->noise.evaluated);
        const int in_a = ds_in_room_a(o->name);
        const int want = in_a ? a_changed : b_changed;
        if (want != !o->noise.within_noise)
            fail_msg("%s: shift %+.4f z %+.2f significant %llu/%llu: expected %s", o->name, o->noise.mean_shift,
                     o->noise.z, (unsigned long long)o->noise.significant, (unsigned long long)o->noise.count,
                     want ? "beyond noise" : "within noise");
        assert_int_equal(o->status, want ? TL_DIFF_CHANGED : TL_DIFF_SAME);
        seen_a += in_a, seen_b += !in_a;
    }
    assert_int_equal(seen_a, 5);
    assert_int_equal(seen_b, 6);
}

static void test_reseed_is_equal(void **state)
{
    (void)state;
    tl_diff_result r;
    run(RESEED, TL_DIFF_MODE_AUTO, &r);
    expect_rooms(&r, 0, 0);
    assert_int_equal(r.differ, 0);
    assert_true(r.glg.noise.within_noise);
    /* the noise model is REPT's: both bakes reached ~1.5 % */
    assert_true(r.noise.rept[0][0] > 0.005 && r.noise.rept[0][0] < 0.02);
    /* what changed: the seed, and nothing else of the inputs */
    const tl_diff_change *seed = find_change(&r, TL_CHANGE_OPTION, "bake.seed");
    assert_non_null(seed);
    assert_string_equal(seed->what, "seed 1 -> 2");
    assert_int_equal(r.change_count, 1);
    tl_diff_free(&r);
    /* the same pair compared exactly: every object differs */
    run(RESEED, TL_DIFF_MODE_TOLERANCE, &r);
    assert_int_equal(r.differ, 1);
    assert_int_equal(r.objects_changed, DS_OBJECTS);
    tl_diff_free(&r);
}

static void test_brighter_sky_only_in_room_a(void **state)
{
    (void)state;
    tl_diff_result r;
    run(SKY, TL_DIFF_MODE_AUTO, &r);
    expect_rooms(&r, 1, 0);
    assert_int_equal(r.differ, 1);
    for (size_t i = 0; i < r.object_count; i++) {
        const tl_diff_object *o = &r.objects[i];
        if (!ds_in_room_a(o->name)) continue;
        /* room A is lit by the sky alone: +5 % within the reseed noise of its mean */
        assert_true(fabs(o->noise.mean_shift - 0.05) < 0.02);
        assert_true(o->noise.shift_significant);
    }
    const tl_diff_change *sky = find_change(&r, TL_CHANGE_OPTION, "bake.sky");
    assert_non_null(sky);
    assert_string_equal(sky->a, "1,1,1");
    assert_string_equal(sky->b, "1.04999995,1.04999995,1.04999995");
    assert_string_equal(sky->what, "sky 1,1,1 -> 1.04999995,1.04999995,1.04999995");
    assert_null(find_change(&r, TL_CHANGE_MATERIAL, "B_wall_east"));
    tl_diff_free(&r);
}

static void test_moved_lamp_only_in_room_b(void **state)
{
    (void)state;
    tl_diff_result r;
    run(LAMP, TL_DIFF_MODE_AUTO, &r);
    expect_rooms(&r, 0, 1);
    /* the lamp moved towards the east wall: brighter there, darker on the west wall */
    for (size_t i = 0; i < r.object_count; i++) {
        const tl_diff_object *o = &r.objects[i];
        if (!strcmp(o->name, "B_wall_east")) assert_true(o->noise.mean_shift > 0.1);
        if (!strcmp(o->name, "B_wall_west")) assert_true(o->noise.mean_shift < -0.1);
    }
    assert_false(r.glg.noise.within_noise);
    const tl_diff_change *lamp = find_change(&r, TL_CHANGE_LIGHT, "lamp_B");
    assert_non_null(lamp);
    assert_int_equal(lamp->status, TL_DIFF_CHANGED);
    assert_non_null(strstr(lamp->what, "position 10,1.5,2 -> 10.5,1.5,2"));
    tl_diff_free(&r);
}

static void test_wall_albedo_only_in_room_b(void **state)
{
    (void)state;
    tl_diff_result r;
    run(ALBEDO, TL_DIFF_MODE_AUTO, &r);
    expect_rooms(&r, 0, 1);
    const tl_diff_change *m = find_change(&r, TL_CHANGE_MATERIAL, "B_wall_east");
    assert_non_null(m);
    assert_non_null(strstr(m->what, "albedo 0.699999988,0.699999988,0.699999988 -> 0.349999994,0.349999994,0.349999994"));
    const tl_diff_change *o = find_change(&r, TL_CHANGE_OBJECT, "B_wall_east");
    assert_non_null(o);
    assert_string_equal(o->what, "object B_wall_east material changed");
    for (size_t i = 0; i < r.object_count; i++)
        assert_int_equal(r.objects[i].inputs_changed, strcmp(r.objects[i].name, "B_wall_east") ? 0 : TL_INPUT_MATERIAL);
    tl_diff_free(&r);
}

/* A bake without REPT (a console pack drops it) cannot be judged by noise: tolerance, and why. */
static void test_without_rept_falls_back(void **state)
{
    (void)state;
    tl_bake copy = bakes[RESEED];
    copy.has_rept = 0;
    tl_diff_options o = {0};
    o.mode = TL_DIFF_MODE_NOISE;
    tl_diff_result r;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_diff_run(&bakes[BASE], &copy, &o, &r, err), 0);
    assert_int_equal(r.mode, TL_DIFF_MODE_TOLERANCE);
    assert_non_null(strstr(r.mode_reason, "no REPT"));
    assert_int_equal(r.differ, 1);
    tl_diff_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reseed_is_equal),
        cmocka_unit_test(test_brighter_sky_only_in_room_a),
        cmocka_unit_test(test_moved_lamp_only_in_room_b),
        cmocka_unit_test(test_wall_albedo_only_in_room_b),
        cmocka_unit_test(test_without_rept_falls_back),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
