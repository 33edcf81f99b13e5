/* Dynamic light sets and doors through the whole bake (bake/sets/bake_sets.c, bake/sets/SETS.md), on the
 * room_with_doors level (tests/support/door_scenes.h): the baked DLS/DOOR sections applied by
 * the reference runtime (lbk_dls_apply) must match independent full bakes.
 *
 *   S  : lights A, B in sets, a black light in set C, the north door tagged lbk_door, a light
 *        outside the door, sky 0.5;
 *   R1 : the same with A and B static and the door plain geometry: S applied with A = B = 1 and
 *        the door closed (ω = 0: base + S_A + S_B + S_C) must equal it (linearity + S_C);
 *   R3 : no door panel, no A/B, another seed: S applied with A = B = 0 and the door open
 *        (base + S_O) must equal it (light through the opening).
 * Tolerances come from the bakes' own noise: the same comparison between two independent full
 * bakes (R1 with seeds 1 and 2) measures it in the same run. The runtime's linear mode gives the
 * byte mode's accumulators bit for bit on S (support/dls_linear_check.h). */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats: experimental (lbk/dls.h) */
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

#include "lbk/bake.h"
#include "tests/support/bake_file.h"
#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/objects.h"
#include "lbk/validate.h"
#include "support/dls_linear_check.h"
#include "support/door_scenes.h"
#include "support/room_compare.h"

#define SAMPLES 96
#define DENSITY 2.0f

typedef struct baked {
    char path[256];
    lbk_reader *rd;
    lbk_lmap_view lmap;
    uint64_t texels;
    uint32_t *base_z;
    uint8_t *base_rgba;
    uint32_t glg_count;
    uint8_t *base_glg;      /* stored units, as a runtime uploads them */
    float glg_scale;
    uint32_t llg_count;
    uint8_t *base_llg;
    const void *dls_data, *door_data;
    size_t dls_size, door_size;
    lbk_dls_view *dls;
    lbk_door_view *door;
    uint32_t room_rect[5]; /* page, x, y, w, h of object "Room" */
    lbk_bake_report sum;
} baked;

static char tmpdir[128];
static baked S, R1, R1b, R3;

static void bake_one(baked *b, const char *name, const ds_options *o, uint64_t seed)
{
    memset(b, 0, sizeof *b);
    char gltf[256], err[512];
    snprintf(gltf, sizeof gltf, "%s/%s.gltf", tmpdir, name);
    snprintf(b->path, sizeof b->path, "%s/%s.lbk", tmpdir, name);
    assert_int_equal(ds_write_room_scene(DS_ROOM_GLB, gltf, o, err, sizeof err), 0);
    tb_job bo;
    memset(&bo, 0, sizeof bo);
    bo.in = gltf;
    bo.out = b->path;
    bo.d.threads = 2;
    bo.d.seed = seed;
    bo.d.target_error = 1e-6; /* never reached: every bake runs its full sample budget */
    bo.d.max_samples = SAMPLES;
    bo.d.no_glg = 0;
    bo.d.glg_spacing = 2.5f;
    lbk_result rc = tb_bake(&bo, &b->sum, err, sizeof err);
    if (rc) fprintf(stderr, "bake %s: %s\n", name, err);
    assert_int_equal(rc, 0);
    unlink(gltf);

    assert_int_equal(lbk_reader_open_file(b->path, NULL, &b->rd), LBK_OK);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(b->rd, LBK_SECTION_LMAP, &d, &n), LBK_OK);
    assert_int_equal(lbk_lmap_open(d, n, &b->lmap), LBK_OK);
    b->texels = b->lmap.texel_count;
    b->base_z = malloc(b->texels * 4);
    b->base_rgba = malloc(b->texels * 4);
    assert_non_null(b->base_z);
    assert_non_null(b->base_rgba);
    for (uint64_t i = 0; i < b->texels; i++) {
        lbk_ahd_texel t;
        assert_int_equal(lbk_lmap_texel_get(&b->lmap, i, &t, NULL), LBK_OK);
        b->base_z[i] = t.irradiance_z;
        memcpy(&b->base_rgba[4 * i], t.rgba, 4);
    }
    if (lbk_reader_section_by_type(b->rd, LBK_SECTION_GLG, &d, &n) == LBK_OK) {
        lbk_glg_view g;
        assert_int_equal(lbk_glg_open(d, n, &g), LBK_OK);
        b->glg_count = g.probe_count;
        b->glg_scale = g.scale;
        b->base_glg = calloc(b->glg_count + 1, 28);
        memcpy(b->base_glg, g.probes, 28 * (size_t)b->glg_count);
    }
    lbk_objects_view ov;
    assert_int_equal(lbk_reader_section_by_type(b->rd, LBK_SECTION_OBJS, &d, &n), LBK_OK);
    assert_int_equal(lbk_objects_open(d, n, &ov), LBK_OK);
    uint32_t idx;
    lbk_string room = {"Room", 4};
    assert_int_equal(lbk_objects_find(&ov, room, &idx), LBK_OK);
    lbk_object ob;
    assert_int_equal(lbk_objects_get(&ov, idx, &ob), LBK_OK);
    assert_int_equal(ob.representation, LBK_REPRESENTATION_LIGHTMAP);
    b->room_rect[0] = ob.index, b->room_rect[1] = ob.rect_x, b->room_rect[2] = ob.rect_y;
    b->room_rect[3] = ob.rect_w, b->room_rect[4] = ob.rect_h;
    if (lbk_reader_section_by_type(b->rd, LBK_SECTION_DLS, &b->dls_data, &b->dls_size) == LBK_OK) {
        assert_int_equal(lbk_dls_open(b->dls_data, b->dls_size, NULL, &b->dls), LBK_OK);
        b->llg_count = (uint32_t)lbk_dls_target_count(b->dls, LBK_DLS_SPACE_LLG);
        b->base_llg = calloc(b->llg_count + 1, 28);
    }
    if (lbk_reader_section_by_type(b->rd, LBK_SECTION_DOOR, &b->door_data, &b->door_size) == LBK_OK)
        assert_int_equal(lbk_door_open(b->door_data, b->door_size, NULL, &b->door), LBK_OK);
}

static void baked_free(baked *b)
{
    if (b->door) lbk_door_close(b->door);
    if (b->dls) lbk_dls_close(b->dls);
    if (b->rd) lbk_reader_close(b->rd);
    free(b->base_z), free(b->base_rgba), free(b->base_glg), free(b->base_llg);
    if (b->path[0]) unlink(b->path);
    memset(b, 0, sizeof *b);
}

/* Final texels (and GLG probes) for the given weights: set weights by name, the door's ω. */
typedef struct applied {
    uint32_t *z;
    uint8_t *rgba;
    uint8_t *glg;
} applied;

static void apply_weights(const baked *b, float wa, float wb, float wc, float door, applied *out)
{
    out->z = malloc(b->texels * 4);
    out->rgba = malloc(b->texels * 4);
    out->glg = calloc(b->glg_count + 1, 28);
    uint8_t *llg = calloc(b->llg_count + 1, 28);
    lbk_dls_runtime_desc d;
    memset(&d, 0, sizeof d);
    d.dls = b->dls;
    d.doors = b->door;
    d.base_irradiance_z = b->base_z, d.base_rgba = b->base_rgba;
    d.base_glg = b->base_glg, d.base_llg = b->base_llg;
    d.out_irradiance_z = out->z, d.out_rgba = out->rgba;
    d.out_glg = out->glg, d.out_llg = llg;
    lbk_dls_runtime *rt;
    assert_int_equal(lbk_dls_runtime_open(&d, &rt), LBK_OK);
    uint32_t ns = lbk_dls_set_count(b->dls);
    float *w = calloc(ns, sizeof *w);
    const char *names[3] = {"A", "B", "C"};
    float vals[3] = {wa, wb, wc};
    for (int i = 0; i < 3; i++) {
        uint32_t s;
        if (lbk_dls_set_find(b->dls, names[i], &s) == LBK_OK) w[s] = vals[i];
    }
    float dw = door;
    assert_int_equal(lbk_dls_apply(rt, w, b->door ? &dw : NULL, NULL), LBK_OK);
    lbk_dls_runtime_close(rt);
    free(w), free(llg);
}

static void applied_free(applied *a)
{
    free(a->z), free(a->rgba), free(a->glg);
}

typedef rc_result cmp;

static cmp compare_room(const baked *ba, const uint32_t *za, const uint8_t *ra, const baked *bb, const uint32_t *zb,
                        const uint8_t *rb)
{
    return rc_compare_room((rc_side){&ba->lmap, ba->room_rect, za, ra}, (rc_side){&bb->lmap, bb->room_rect, zb, rb});
}

static double glg_sum(const uint8_t *probes, uint32_t n, float scale)
{
    double s = 0;
    for (uint32_t i = 0; i < n; i++) {
        lbk_sh9_rgb sh;
        lbk_sh9_unpack(&probes[28 * (size_t)i], &sh);
        s += (LBK_LUM_R * sh.c[0][0] + LBK_LUM_G * sh.c[1][0] + LBK_LUM_B * sh.c[2][0]) * scale;
    }
    return s;
}

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk_test_sets_XXXXXX");
    if (!mkdtemp(tmpdir)) return -1;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    baked_free(&S), baked_free(&R1), baked_free(&R1b), baked_free(&R3);
    rmdir(tmpdir);
    return 0;
}

static void test_bakes(void **state)
{
    (void)state;
    ds_options o = {DS_DOOR_TAGGED, DS_INSIDE_SETS, 1, 1, 0.5f, DENSITY, 0, 0, 0};
    bake_one(&S, "sets", &o, 1);
    ds_options o1 = {DS_DOOR_PLAIN, DS_INSIDE_STATIC, 0, 1, 0.5f, DENSITY, 0, 0, 0};
    bake_one(&R1, "static", &o1, 1);
    bake_one(&R1b, "static_seed2", &o1, 2);
    ds_options o3 = {DS_NO_DOOR, DS_INSIDE_NONE, 0, 1, 0.5f, DENSITY, 0, 0, 0};
    bake_one(&R3, "nodoor", &o3, 2); /* another seed: independent noise */
    assert_int_equal(S.sum.counts.light_sets, 5); /* A, B, C, door/north/open, door/north/closed */
    assert_int_equal(S.sum.counts.doors, 1);
    assert_int_equal(R1.sum.counts.light_sets, 0);
    assert_null(R1.dls);
    assert_non_null(S.dls);
    assert_non_null(S.door);
}

static int print_issue(void *user, const lbk_issue *issue)
{
    (void)user;
    print_message("issue %u: %s\n", issue->id, issue->message);
    return 0;
}

/* The container with DLS and DOOR passes lbk_validate with no issue at all. */
static void test_validates(void **state)
{
    (void)state;
    lbk_validate_options vo;
    memset(&vo, 0, sizeof vo);
    lbk_validate_summary sum;
    assert_int_equal(lbk_validate_file(S.path, &vo, print_issue, NULL, &sum), LBK_OK);
    assert_int_equal(sum.fatal + sum.errors + sum.warnings, 0);
    assert_int_equal(lbk_door_check_dls(S.door, S.dls), LBK_OK);
}

/* Set order and kinds: light sets by name, then the door's open/closed sets, named by the door. */
static void test_sets_and_door(void **state)
{
    (void)state;
    static const char *names[5] = {"A", "B", "C", "door/north/open", "door/north/closed"};
    static const uint32_t kinds[5] = {0, 0, 0, 1, 2};
    assert_int_equal(lbk_dls_set_count(S.dls), 5);
    for (uint32_t i = 0; i < 5; i++) {
        lbk_dls_set_info si;
        assert_int_equal(lbk_dls_set_get(S.dls, i, &si), LBK_OK);
        assert_int_equal(si.name_length, strlen(names[i]));
        assert_memory_equal(si.name, names[i], si.name_length);
        assert_int_equal(si.kind, kinds[i]);
    }
    lbk_door_info di;
    assert_int_equal(lbk_door_count(S.door), 1);
    assert_int_equal(lbk_door_get(S.door, 0, &di), LBK_OK);
    assert_int_equal(di.open_set, 3);
    assert_int_equal(di.closed_set, 4);
    /* the OBB is the generator's box: x ±1.32, y [0.03, 3.40], z [−4.99, −4.96] */
    assert_float_equal(di.centre[0], 0.0, 1e-4);
    assert_float_equal(di.centre[1], 1.715, 1e-4);
    assert_float_equal(di.centre[2], -4.975, 1e-4);
    float he[3] = {fabsf(di.half_extents[0]), fabsf(di.half_extents[1]), fabsf(di.half_extents[2])};
    assert_float_equal(he[0], 1.32, 1e-4);
    assert_float_equal(he[1], 1.685, 1e-4);
    assert_float_equal(he[2], 0.015, 1e-4);
}

typedef struct count_ctx {
    uint32_t set;
    uint64_t hits, entries;
} count_ctx;

static int count_fn(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    (void)target, (void)payloads;
    count_ctx *c = user;
    for (uint32_t i = 0; i < count; i++) c->hits += sets[i] == c->set;
    c->entries += count;
    return 0;
}

static uint64_t set_entries(const baked *b, const char *name, uint64_t *all)
{
    count_ctx c = {0, 0, 0};
    assert_int_equal(lbk_dls_set_find(b->dls, name, &c.set), LBK_OK);
    for (uint32_t k = 0; k < lbk_dls_cluster_count(b->dls); k++)
        assert_int_equal(lbk_dls_cluster_decode(b->dls, k, count_fn, &c), LBK_OK);
    if (all) *all = c.entries;
    return c.hits;
}

/* A set whose only light is black is listed (so a runtime can address it) but has no entry in
 * any cluster; the lit sets do have entries, and the sparse storage left some texels out. */
static void test_zero_set_no_data(void **state)
{
    (void)state;
    uint64_t all;
    assert_int_equal(set_entries(&S, "C", &all), 0);
    uint64_t a = set_entries(&S, "A", NULL), b = set_entries(&S, "B", NULL);
    assert_true(a > 100);
    assert_true(b > 100);
    assert_true(set_entries(&S, "door/north/open", NULL) > 100);
    assert_true(set_entries(&S, "door/north/closed", NULL) > 10);
    lbk_dls_stats st;
    assert_int_equal(lbk_dls_stats_get(S.dls, &st), LBK_OK);
    assert_int_equal(st.entries[0] + st.entries[1] + st.entries[2], all);
    /* no cluster lists set C */
    uint32_t c;
    assert_int_equal(lbk_dls_set_find(S.dls, "C", &c), LBK_OK);
    for (uint32_t k = 0; k < lbk_dls_cluster_count(S.dls); k++) {
        lbk_dls_cluster_info ci;
        assert_int_equal(lbk_dls_cluster_get(S.dls, k, &ci), LBK_OK);
        for (uint32_t i = 0; i < ci.set_count; i++) {
            uint32_t s;
            assert_int_equal(lbk_dls_cluster_set_get(S.dls, k, i, &s), LBK_OK);
            assert_int_not_equal(s, c);
        }
    }
    print_message("entries: A %llu, B %llu, total %llu; sparse: %.1f%% of %llu texels touched\n",
                  (unsigned long long)a, (unsigned long long)b, (unsigned long long)all,
                  100.0 * (double)st.touched[0] / (double)(st.target_count[0] ? st.target_count[0] : 1),
                  (unsigned long long)st.target_count[0]);
}

/* Linearity: base + S_A + S_B (+ S_C, door closed) equals a bake with A and B static, within
 * the noise two independent full bakes show against each other. */
static void test_linearity(void **state)
{
    (void)state;
    applied on, off;
    apply_weights(&S, 1, 1, 1, 0, &on);
    apply_weights(&S, 0, 0, 0, 0, &off);
    cmp c = compare_room(&S, on.z, on.rgba, &R1, R1.base_z, R1.base_rgba);
    cmp noise = compare_room(&R1b, R1b.base_z, R1b.base_rgba, &R1, R1.base_z, R1.base_rgba);
    cmp without = compare_room(&S, off.z, off.rgba, &R1, R1.base_z, R1.base_rgba);
    double ga = glg_sum(on.glg, S.glg_count, S.glg_scale), gr = glg_sum(R1.base_glg, R1.glg_count, R1.glg_scale);
    print_message("sets on vs static: L1 %.4f ratio %.4f | seed noise L1 %.4f ratio %.4f | sets off L1 %.4f | "
                  "GLG ratio %.4f\n",
                  c.l1, c.ratio, noise.l1, noise.ratio, without.l1, ga / gr);
    assert_int_equal(S.glg_count, R1.glg_count);
    /* the sets carry most of the room's light: without them the difference is large */
    assert_true(without.l1 > 0.5);
    assert_true(c.l1 < 1.5 * noise.l1 + 0.02);
    assert_true(fabs(c.ratio - 1) < 0.03);
    assert_true(fabs(ga / gr - 1) < 0.05);
    applied_free(&on), applied_free(&off);
}

/* Doors: opening the door (ω = 1) brightens the room as an independent bake without the door
 * does, within the bake's noise (measured between two full bakes with different seeds). */
static void test_door_opening(void **state)
{
    (void)state;
    applied open, closed;
    apply_weights(&S, 0, 0, 0, 1, &open);
    apply_weights(&S, 0, 0, 0, 0, &closed);
    cmp c = compare_room(&S, open.z, open.rgba, &R3, R3.base_z, R3.base_rgba);
    cmp shut = compare_room(&S, closed.z, closed.rgba, &R3, R3.base_z, R3.base_rgba);
    cmp noise = compare_room(&R1b, R1b.base_z, R1b.base_rgba, &R1, R1.base_z, R1.base_rgba);
    print_message("door open vs no-door bake: L1 %.4f ratio %.4f | closed vs no-door: L1 %.4f ratio %.4f | "
                  "seed noise L1 %.4f\n",
                  c.l1, c.ratio, shut.l1, shut.ratio, noise.l1);
    /* opening brightens the room a lot ... */
    assert_true(shut.ratio < 0.8);
    /* ... and by as much as removing the door does */
    assert_true(fabs(c.ratio - 1) < 0.04);
    assert_true(c.l1 < 2 * noise.l1 + 0.03);
    assert_true(c.l1 < 0.3 * shut.l1);
    applied_free(&open), applied_free(&closed);
}

/* The linear mode on the baked sets and door: every target's floats are the byte mode's
 * accumulator (re-encoded: its bytes), for door openings and set weights in turn. */
static void test_linear_mode(void **state)
{
    (void)state;
    dlslin d;
    assert_int_equal(dlslin_open(&d, S.dls, S.door, S.base_z, S.base_rgba, S.base_glg, S.base_llg), 0);
    const uint32_t ns = lbk_dls_set_count(S.dls);
    float w[8] = {0};
    static const float steps[5][4] = {{1, 1, 1, 0}, {0.5f, 0, 1, 0.25f}, {0.3f, 0.7f, 0, 1}, {0, 0, 0, 0.6f}, {2, 0.1f, 1, 0}};
    uint64_t weighted = 0;
    for (int i = 0; i < 5; i++) {
        for (uint32_t s = 0; s < ns && s < 3; s++) w[s] = steps[i][s];
        const float dw = steps[i][3];
        dlslin_counts n;
        assert_int_equal(dlslin_apply_check(&d, w, &dw, &n), 0);
        assert_int_equal(n.mismatches, 0);
        weighted += n.weighted;
    }
    assert_true(weighted > 0);
    dlslin_close(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bakes),
        cmocka_unit_test(test_validates),
        cmocka_unit_test(test_sets_and_door),
        cmocka_unit_test(test_zero_set_no_data),
        cmocka_unit_test(test_linearity),
        cmocka_unit_test(test_door_opening),
        cmocka_unit_test(test_linear_mode),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
