/* Distributed bakes (lbk/bake_dist.h, bake/dist/DIST.md): the merge of N units' parts is the
 * container a local bake writes, byte for byte, at N = 1, 3, 7, on the Cornell box, a scene of
 * light sets, a door and a combination (tests/fuzz/sets_scene.gltf) and the shared room; and a
 * missing, duplicated, corrupt, truncated or foreign part is refused with a message and no
 * output (the library's; the CLI's "nothing written" with $LBK). Units of one transport run share
 * its caches (test_shared_*): each bounce computed once in all, the merge the local bake's bytes
 * whether the units run one after another or together, after a unit was killed holding claims,
 * and when a unit elsewhere never publishes what it claimed. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "bake/dist/dist.h"
#include "lbk/bake.h"
#include "lbk/bake_dist.h"
#include "support/scenes_dir.h"

#define PLAN_HASH 0x1234abcd5678ef01ull

typedef struct bytes {
    void *p;
    size_t n;
} bytes;

static char last_error[1024];

static void on_message(void *user, lbk_bake_severity s, const char *m)
{
    (void)user;
    if (s == LBK_BAKE_SEVERITY_ERROR) snprintf(last_error, sizeof last_error, "%s", m);
}

static lbk_bake_desc desc_of(int samples, float density, uint64_t seed)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.seed = seed;
    d.threads = 2;
    d.max_samples = samples;
    d.target_error = -1; /* a fixed schedule: what a distributed bake needs */
    d.texel_density = density;
    d.message = on_message;
    return d;
}

static bytes local_bake(const char *scene, const lbk_bake_desc *d)
{
    lbk_bake_output *out = NULL;
    last_error[0] = 0;
    lbk_result r = lbk_bake_from_file(scene, d, &out);
    if (r) fail_msg("bake %s: %s", scene, last_error);
    bytes b = {NULL, 0};
    assert_int_equal(lbk_bake_output_container(out, &b.p, &b.n), LBK_OK);
    lbk_bake_output_free(out);
    return b;
}

static void bake_parts(const char *scene, const lbk_bake_desc *d, uint64_t hash, uint32_t units, bytes *parts)
{
    for (uint32_t k = 0; k < units; k++) {
        last_error[0] = 0;
        lbk_result r = lbk_bake_unit_from_file(scene, d, hash, units, k, &parts[k].p, &parts[k].n);
        if (r) fail_msg("unit %u of %u: %s (%s)", k, units, lbk_result_message(r), last_error);
        lbk_bake_part_info info;
        char err[256];
        assert_int_equal(lbk_bake_part_check(parts[k].p, parts[k].n, hash, units, &info, err, sizeof err), LBK_OK);
        assert_int_equal(info.unit, k);
        assert_true(info.end >= info.first);
    }
}

/* The merge's container, or NULL bytes with the result in *res (and the message in last_error). */
static bytes merge(const char *scene, const lbk_bake_desc *d, uint64_t hash, uint32_t units, const bytes *parts, size_t n,
                   lbk_result *res)
{
    const void *p[16];
    size_t s[16];
    for (size_t k = 0; k < n; k++) p[k] = parts[k].p, s[k] = parts[k].n;
    lbk_bake_output *out = NULL;
    last_error[0] = 0;
    bytes b = {NULL, 0};
    *res = lbk_bake_merge_from_file(scene, d, hash, units, p, s, n, &out);
    if (*res == LBK_OK) {
        assert_non_null(out);
        assert_int_equal(lbk_bake_output_container(out, &b.p, &b.n), LBK_OK);
        lbk_bake_output_free(out);
    } else {
        assert_null(out);
    }
    return b;
}

static void free_parts(bytes *parts, size_t n)
{
    for (size_t k = 0; k < n; k++) lbk_bake_part_free(parts[k].p);
}

/* Merges of n units (each count of counts[]) against the local bake, byte for byte; the parts'
 * sizes printed (what moves over the network per unit). */
static void check_scene(const char *scene, int samples, float density, const uint32_t *counts, size_t ncounts)
{
    lbk_bake_desc d = desc_of(samples, density, 7);
    bytes local = local_bake(scene, &d);
    for (size_t c = 0; c < ncounts; c++) {
        assert_true(counts[c] <= 16);
        bytes parts[16];
        memset(parts, 0, sizeof parts);
        bake_parts(scene, &d, PLAN_HASH, counts[c], parts);
        size_t part_bytes = 0;
        for (uint32_t k = 0; k < counts[c]; k++) part_bytes += parts[k].n;
        lbk_result r;
        bytes m = merge(scene, &d, PLAN_HASH, counts[c], parts, counts[c], &r);
        if (r) fail_msg("merge of %u units: %s", counts[c], last_error);
        printf("%s: %u units, %zu part bytes in all, container %zu bytes\n", scene, counts[c], part_bytes, m.n);
        assert_int_equal(m.n, local.n);
        assert_memory_equal(m.p, local.p, local.n);
        lbk_free(NULL, m.p);
        free_parts(parts, counts[c]);
    }
    lbk_free(NULL, local.p);
}

static void test_merge_equals_local_cornell(void **state)
{
    (void)state;
    /* one transport run: every count cuts its receivers */
    const uint32_t counts[] = {1, 3, 7};
    check_scene("scenes/cornell_box/CornellBox-Original.gltf", 64, 4, counts, 3);
}

static void test_merge_equals_local_sets_doors(void **state)
{
    (void)state;
    /* 8 transport runs (base, 2 light sets, the door's reference, open and closed, the door–set
     * combination's two): 1, 3 and 7 units take whole runs, 8 one each, 11 share 3 runs by 2 */
    const uint32_t counts[] = {1, 3, 7, 8, 11};
    check_scene("tests/fuzz/sets_scene.gltf", 32, 2, counts, 5);
}

/* Merges of n units (each count of counts[]) of a bake with options d against its local bake. */
static void check_desc(const char *scene, const lbk_bake_desc *d, const uint32_t *counts, size_t ncounts)
{
    bytes local = local_bake(scene, d);
    for (size_t c = 0; c < ncounts; c++) {
        assert_true(counts[c] <= 16);
        bytes parts[16];
        memset(parts, 0, sizeof parts);
        bake_parts(scene, d, PLAN_HASH, counts[c], parts);
        size_t part_bytes = 0;
        for (uint32_t k = 0; k < counts[c]; k++) part_bytes += parts[k].n;
        lbk_result r;
        bytes m = merge(scene, d, PLAN_HASH, counts[c], parts, counts[c], &r);
        if (r) fail_msg("merge of %u units: %s", counts[c], last_error);
        printf("%s: %u units, %zu part bytes in all, container %zu bytes\n", scene, counts[c], part_bytes, m.n);
        assert_int_equal(m.n, local.n);
        assert_memory_equal(m.p, local.p, local.n);
        lbk_free(NULL, m.p);
        free_parts(parts, counts[c]);
    }
    lbk_free(NULL, local.p);
}

/* An error target: every run stops on its own estimate, evaluated on its stop receivers
 * (bk_transport_options.stop_receivers: all of a class this small), which every unit of a
 * shared run gathers too; a unit with door runs but not the base bakes the base's stop
 * receivers, unrecorded (their budget is its final sample count). The merge equals the local
 * bake with the same target at 1, 3 and 8 units (whole runs) and 11 (3 runs shared by 2). */
static void test_merge_equals_local_error_target(void **state)
{
    (void)state;
    lbk_bake_desc d = desc_of(64, 2, 7);
    d.target_error = 0.05;
    const uint32_t counts[] = {1, 3, 8, 11};
    check_desc("tests/fuzz/sets_scene.gltf", &d, counts, 4);
}

/* The Cornell box's one run with the default preset and its error target (no --samples, no
 * --target-error): shared by 3 and 7 units. */
static void test_merge_equals_local_cornell_default_target(void **state)
{
    (void)state;
    lbk_bake_desc d = desc_of(0, 4, 7);
    d.target_error = 0; /* the preset's */
    const uint32_t counts[] = {1, 3, 7};
    check_desc("scenes/cornell_box/CornellBox-Original.gltf", &d, counts, 3);
}

/* --door-method guided: the units leave the guided estimates (S_O) to the merge, which has the
 * base's final radiance they read; the door's closed run, the combination's runs and the light
 * sets are cut as usual (7 transport runs: 9 units share two). With a fixed schedule and with
 * an error target. */
static void test_merge_equals_local_guided_doors(void **state)
{
    (void)state;
    lbk_bake_desc d = desc_of(32, 2, 7);
    d.door_method = LBK_BAKE_DOOR_GUIDED;
    const uint32_t counts[] = {1, 3, 9};
    check_desc("tests/fuzz/sets_scene.gltf", &d, counts, 3);
    d = desc_of(64, 2, 7);
    d.door_method = LBK_BAKE_DOOR_GUIDED;
    d.target_error = 0.05;
    const uint32_t counts_t[] = {3};
    check_desc("tests/fuzz/sets_scene.gltf", &d, counts_t, 1);
}

/* The cut (bk_dist_*): every receiver of every run baked by exactly one unit, each unit with at
 * least one run, and no run's caches computed by more units than needed: with units <= runs each
 * run has one unit, with more units each unit has one run. */
static void test_cut_tiles(void **state)
{
    (void)state;
    const uint64_t counts[] = {0, 1, 5, 1000};
    for (uint32_t runs = 1; runs <= 12; runs++)
        for (uint32_t units = 1; units <= 20; units++)
            for (size_t c = 0; c < 4; c++) {
                const uint64_t count = counts[c];
                for (uint32_t r = 0; r < runs; r++) {
                    uint32_t u0, u1;
                    bk_dist_run_units(runs, units, r, &u0, &u1);
                    assert_true(u0 < u1 && u1 <= units);
                    assert_int_equal(u1 - u0, units <= runs ? 1 : u1 - u0);
                    uint64_t next = 0;
                    for (uint32_t u = u0; u < u1; u++) {
                        uint32_t r0, r1;
                        bk_dist_unit_runs(runs, units, u, &r0, &r1);
                        assert_true(r0 <= r && r < r1);
                        uint64_t b, e;
                        bk_dist_range(count, runs, units, u, r, &b, &e);
                        assert_int_equal(b, next);
                        assert_true(e >= b);
                        next = e;
                    }
                    assert_int_equal(next, count);
                }
                for (uint32_t u = 0; u < units; u++) {
                    uint32_t r0, r1;
                    bk_dist_unit_runs(runs, units, u, &r0, &r1);
                    assert_true(r0 < r1 && r1 <= runs);
                    if (units > runs) assert_int_equal(r1 - r0, 1);
                    for (uint32_t r = r0; r < r1; r++) {
                        uint32_t u0, u1;
                        bk_dist_run_units(runs, units, r, &u0, &u1);
                        assert_true(u0 <= u && u < u1);
                    }
                }
            }
}

static void test_merge_equals_local_room(void **state)
{
    (void)state;
    char path[512];
    SD_REQUIRE(sd_path(path, sizeof path, "room_with_doors/room.glb"));
    lbk_bake_desc d = desc_of(32, 2, 7);
    d.sky_override = 1;
    d.sky[0] = d.sky[1] = d.sky[2] = 1;
    bytes local = local_bake(path, &d);
    bytes parts[3];
    bake_parts(path, &d, PLAN_HASH, 3, parts);
    lbk_result r;
    bytes m = merge(path, &d, PLAN_HASH, 3, parts, 3, &r);
    if (r) fail_msg("merge: %s", last_error);
    assert_int_equal(m.n, local.n);
    assert_memory_equal(m.p, local.p, local.n);
    lbk_free(NULL, m.p);
    lbk_free(NULL, local.p);
    free_parts(parts, 3);
}

static void expect_refused(const char *scene, const lbk_bake_desc *d, uint64_t hash, uint32_t units, const bytes *parts,
                           size_t n, const char *why)
{
    lbk_result r;
    bytes m = merge(scene, d, hash, units, parts, n, &r);
    if (m.p) lbk_free(NULL, m.p);
    assert_int_equal(r, LBK_ERR_BAD_INPUT);
    if (!strstr(last_error, why)) fail_msg("expected a message with '%s', got '%s'", why, last_error);
}

static void test_bad_parts_refused(void **state)
{
    (void)state;
    const char *scene = "scenes/cornell_box/CornellBox-Original.gltf";
    lbk_bake_desc d = desc_of(32, 2, 7);
    bytes parts[3];
    bake_parts(scene, &d, PLAN_HASH, 3, parts);
    /* missing: units 0 and 2 only */
    bytes two[2] = {parts[0], parts[2]};
    expect_refused(scene, &d, PLAN_HASH, 3, two, 2, "1 of 3 units missing: 1");
    /* duplicated */
    bytes dup[3] = {parts[0], parts[1], parts[1]};
    expect_refused(scene, &d, PLAN_HASH, 3, dup, 3, "unit 1 is given twice");
    /* foreign: another plan's hash, another cut */
    expect_refused(scene, &d, PLAN_HASH + 1, 3, parts, 3, "belongs to another plan");
    expect_refused(scene, &d, PLAN_HASH, 4, parts, 3, "this plan has 4 units");
    /* corrupt: one flipped payload byte, then one in the header; truncated */
    unsigned char *c = malloc(parts[1].n);
    assert_non_null(c);
    memcpy(c, parts[1].p, parts[1].n);
    c[parts[1].n / 2] ^= 0x10;
    bytes bad[3] = {parts[0], {c, parts[1].n}, parts[2]};
    expect_refused(scene, &d, PLAN_HASH, 3, bad, 3, "payload checksum");
    c[parts[1].n / 2] ^= 0x10;
    c[20] ^= 1;
    expect_refused(scene, &d, PLAN_HASH, 3, bad, 3, "checksum");
    c[20] ^= 1;
    bad[1].n = parts[1].n - 4;
    expect_refused(scene, &d, PLAN_HASH, 3, bad, 3, "truncated");
    bad[1].n = 7;
    expect_refused(scene, &d, PLAN_HASH, 3, bad, 3, "not a part file");
    free(c);
    /* parts of the same plan hash but other options (a changed seed or sample count): the units
     * disagree on the runs, or the merge's own bake does */
    lbk_bake_desc d2 = desc_of(32, 2, 8);
    bytes other[3];
    bake_parts(scene, &d2, PLAN_HASH, 3, other);
    bytes mixed[3] = {parts[0], other[1], parts[2]};
    expect_refused(scene, &d, PLAN_HASH, 3, mixed, 3, "other bake options");
    lbk_bake_desc d3 = desc_of(16, 2, 7);
    expect_refused(scene, &d3, PLAN_HASH, 3, parts, 3, "other bake options");
    /* threads do not change a byte: a merge on another thread count takes the parts */
    lbk_bake_desc d4 = desc_of(32, 2, 7);
    d4.threads = 1;
    lbk_result r4;
    bytes m4 = merge(scene, &d4, PLAN_HASH, 3, parts, 3, &r4);
    assert_int_equal(r4, LBK_OK);
    lbk_free(NULL, m4.p);
    free_parts(other, 3);
    /* the whole set merges */
    lbk_result r;
    bytes m = merge(scene, &d, PLAN_HASH, 3, parts, 3, &r);
    assert_int_equal(r, LBK_OK);
    lbk_free(NULL, m.p);
    free_parts(parts, 3);
}

/* Octahedral probes (OCTP): the unit whose receivers start at 0 gathers them in the base run
 * and its part carries them; the merge is the local bake at any N, whole runs or shared. */
static void test_merge_equals_local_octahedral(void **state)
{
    (void)state;
    lbk_bake_desc d = desc_of(64, 4, 7);
    d.octahedral_probes = 1;
    const uint32_t box[] = {1, 3};
    check_desc("scenes/cornell_box/CornellBox-Original.gltf", &d, box, 2);
    d = desc_of(32, 2, 7);
    d.octahedral_probes = 1;
    const uint32_t sets[] = {3, 11};
    check_desc("tests/fuzz/sets_scene.gltf", &d, sets, 2);
}

/* What cannot be cut is refused before anything is baked. */
static void test_unsplittable_refused(void **state)
{
    (void)state;
    const char *scene = "scenes/cornell_box/CornellBox-Original.gltf";
    bytes p = {NULL, 0};
    lbk_bake_desc d = desc_of(32, 2, 7);
    d.time_limit = 10;
    assert_int_equal(lbk_bake_unit_from_file(scene, &d, PLAN_HASH, 2, 0, &p.p, &p.n), LBK_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(last_error, "time limit"));
    assert_null(p.p);
    d = desc_of(32, 2, 7);
    assert_int_equal(lbk_bake_unit_from_file(scene, &d, PLAN_HASH, 2, 2, &p.p, &p.n), LBK_ERR_INVALID_ARGUMENT);
}

/* The CLI: plan, units, merge equal to lbk bake; a bad part leaves no container. */
static int sh(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static int sh(const char *fmt, ...)
{
    char cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void test_cli_plan_units_merge(void **state)
{
    (void)state;
    const char *lbk = getenv("LBK");
    if (!lbk || !*lbk) {
        printf("SKIPPED: set LBK to the lbk binary (make test does)\n");
        skip();
    }
    char dir[] = "/tmp/lbk-dist-XXXXXX";
    assert_non_null(mkdtemp(dir));
    const char *scene = "tests/fuzz/sets_scene.gltf";
    const char *opts = "--samples 32 --target-error none --texel-density 2 --seed 3";
    assert_int_equal(sh("%s bake %s -o %s/local.lbk %s --threads 2 -q", lbk, scene, dir, opts), 0);
    assert_int_equal(sh("%s plan %s -o %s/out.lbk --plan %s/plan.json --units 3 --makefile %s/Makefile %s >/dev/null", lbk,
                        scene, dir, dir, dir, opts), 0);
    /* xargs -P: the documented line */
    assert_int_equal(sh("mkdir -p %s/parts && seq 0 2 | xargs -P 2 -I {} %s bake-unit %s/plan.json {} -o %s/parts/part-{}.lbkpart "
                        "--threads 1 -q", dir, lbk, dir, dir), 0);
    assert_int_equal(sh("%s merge %s/plan.json %s/parts/part-2.lbkpart %s/parts/part-0.lbkpart %s/parts/part-1.lbkpart -o "
                        "%s/xargs.lbk -q", lbk, dir, dir, dir, dir, dir), 0);
    assert_int_equal(sh("cmp %s/local.lbk %s/xargs.lbk", dir, dir), 0);
    /* make -j2 through the generated Makefile */
    assert_int_equal(sh("make -s -j2 -f %s/Makefile LBK=%s >/dev/null", dir, lbk), 0);
    assert_int_equal(sh("cmp %s/local.lbk %s/out.lbk", dir, dir), 0);
    /* refusals: nothing written, a message naming the problem */
    assert_int_equal(sh("%s merge %s/plan.json %s/parts/part-0.lbkpart %s/parts/part-1.lbkpart -o %s/bad.lbk -q 2>%s/err",
                        lbk, dir, dir, dir, dir, dir), 4);
    assert_int_equal(sh("grep -q 'units missing: 2' %s/err && test ! -e %s/bad.lbk", dir, dir), 0);
    assert_int_equal(sh("cp %s/parts/part-1.lbkpart %s/c.lbkpart && printf 'X' | dd of=%s/c.lbkpart bs=1 seek=200 conv=notrunc "
                        "2>/dev/null", dir, dir, dir), 0);
    assert_int_equal(sh("%s merge %s/plan.json %s/parts/part-0.lbkpart %s/c.lbkpart %s/parts/part-2.lbkpart -o %s/bad.lbk "
                        "-q 2>%s/err", lbk, dir, dir, dir, dir, dir, dir), 4);
    assert_int_equal(sh("grep -q 'corrupt' %s/err && test ! -e %s/bad.lbk", dir, dir), 0);
    /* a plan of a different seed: its parts are foreign */
    assert_int_equal(sh("%s plan %s -o %s/o2.lbk --plan %s/plan2.json --units 3 --samples 32 --target-error none "
                        "--texel-density 2 --seed 4 >/dev/null", lbk, scene, dir, dir), 0);
    assert_int_equal(sh("%s merge %s/plan2.json %s/parts/part-0.lbkpart %s/parts/part-1.lbkpart %s/parts/part-2.lbkpart "
                        "-o %s/bad.lbk -q 2>%s/err", lbk, dir, dir, dir, dir, dir, dir), 4);
    assert_int_equal(sh("grep -q 'another plan' %s/err && test ! -e %s/bad.lbk", dir, dir), 0);
    /* an edited plan, a time limit: refused */
    assert_int_equal(sh("sed 's/\"units\":.*3/\"units\": 4/' %s/plan.json > %s/edited.json && ! %s bake-unit %s/edited.json 0 "
                        "-o %s/x.lbkpart 2>%s/err && grep -q edited %s/err", dir, dir, lbk, dir, dir, dir, dir), 0);
    /* an error target with more units than runs (8): a plan like any other */
    assert_int_equal(sh("%s plan %s -o %s/o3.lbk --plan %s/p3.json --units 9 --samples 32 >/dev/null && test -e %s/p3.json && "
                        "rm %s/p3.json", lbk, scene, dir, dir, dir, dir), 0);
    assert_int_equal(sh("%s plan %s -o %s/o3.lbk --plan %s/p3.json --units 2 --samples 32 --target-error none --time-limit 5 "
                        "2>%s/err", lbk, scene, dir, dir, dir), 2);
    assert_int_equal(sh("grep -q 'time-limit' %s/err && test ! -e %s/p3.json", dir, dir), 0);
    sh("rm -rf %s", dir);
}

/* Every file the bake reads is in the plan (lbk_bake_inputs_from_file): a changed sky EXR, image
 * or buffer is refused by the units and the merge, naming the file, before anything is traced. */
static void test_changed_inputs_refused(void **state)
{
    (void)state;
    char dir[] = "/tmp/lbk-dist-in-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char sky[600], cmd[2048];
    snprintf(sky, sizeof sky, "%s/sky.exr", dir);
    snprintf(cmd, sizeof cmd, "cp tests/fuzz/corpus_exr/blender_none_32.exr %s", sky);
    assert_int_equal(system(cmd), 0);
    const char *scene = "scenes/cornell_box/CornellBox-Original.gltf";
    lbk_bake_desc d = desc_of(16, 1, 7);
    d.sky_override = 1;
    d.sky_exr = sky;
    lbk_bake_input *in = NULL;
    size_t n = 0;
    uint32_t runs = 0;
    assert_int_equal(lbk_bake_inputs_from_file(scene, &d, &in, &n, &runs), LBK_OK);
    assert_int_equal(runs, 1);
    assert_int_equal(n, 2);
    assert_string_equal(in[0].role, "scene");
    assert_string_equal(in[0].path, "CornellBox-Original.gltf");
    struct stat st;
    assert_int_equal(stat(scene, &st), 0);
    assert_int_equal(in[0].bytes, (uint64_t)st.st_size);
    assert_string_equal(in[1].role, "sky");
    assert_string_equal(in[1].path, "sky.exr");
    assert_int_equal(in[1].bytes, 784);
    /* the same files: the unit bakes; another sky with other bytes: refused */
    d.expect_inputs = in;
    d.expect_input_count = n;
    bytes p = {NULL, 0};
    last_error[0] = 0;
    assert_int_equal(lbk_bake_unit_from_file(scene, &d, PLAN_HASH, 2, 1, &p.p, &p.n), LBK_OK);
    lbk_bake_part_free(p.p);
    snprintf(cmd, sizeof cmd, "cp tests/fuzz/corpus_exr/blender_zips_32.exr %s", sky);
    assert_int_equal(system(cmd), 0);
    p.p = NULL;
    assert_int_equal(lbk_bake_unit_from_file(scene, &d, PLAN_HASH, 2, 1, &p.p, &p.n), LBK_ERR_BAD_INPUT);
    assert_null(p.p);
    if (!strstr(last_error, "sky 'sky.exr' changed since the plan was made (581 bytes"))
        fail_msg("unexpected message '%s'", last_error);
    /* a file the plan does not list */
    d.expect_input_count = 1;
    assert_int_equal(lbk_bake_unit_from_file(scene, &d, PLAN_HASH, 2, 1, &p.p, &p.n), LBK_ERR_BAD_INPUT);
    if (!strstr(last_error, "sky 'sky.exr' is not among the 1 files the plan lists")) fail_msg("unexpected message '%s'", last_error);
    lbk_bake_inputs_free(in);

    /* the CLI (when LBK is set), with a scene of a .bin buffer and textures (the shared lamp) */
    const char *lbk = getenv("LBK");
    char lamp[512], lamp_gltf[600];
    sd_path(lamp, sizeof lamp, "lights_punctual_lamp");
    if (lbk && *lbk) {
        snprintf(lamp_gltf, sizeof lamp_gltf, "%s/LightsPunctualLamp.gltf", lamp);
        SD_REQUIRE(lamp_gltf);
        const char *o = "--samples 16 --target-error none --texel-density 1";
        assert_int_equal(sh("cp -r %s %s/lamp && %s plan %s/lamp/LightsPunctualLamp.gltf -o %s/o.lbk --plan %s/p.json --units 2 "
                            "%s >/dev/null", lamp, dir, lbk, dir, dir, dir, o), 0);
        assert_int_equal(sh("grep -q '\"buffer\"' %s/p.json && grep -q 'material1_basecolor.png' %s/p.json", dir,
                            dir), 0);
        /* an image's bytes change (trailing bytes: its colours decode the same) */
        assert_int_equal(sh("printf X >> %s/lamp/material1_basecolor.png && %s bake-unit %s/p.json 0 -o %s/u.lbkpart -q 2>%s/err",
                            dir, lbk, dir, dir, dir), 4);
        assert_int_equal(sh("grep -q \"image 'material1_basecolor.png' changed since the plan\" %s/err && test ! -e %s/u.lbkpart",
                            dir, dir), 0);
        /* a buffer's, one byte, same size (read before the images, so it is the one named) */
        assert_int_equal(sh("printf '\\001' | dd of=%s/lamp/LightsPunctualLamp.data.bin bs=1 seek=100 conv=notrunc 2>/dev/null && "
                            "%s bake-unit %s/p.json 1 -o %s/u.lbkpart -q 2>%s/err", dir, lbk, dir, dir, dir), 4);
        assert_int_equal(sh("grep -q \"buffer 'LightsPunctualLamp.data.bin' changed since the plan\" %s/err", dir), 0);
    } else {
        printf("(the CLI part needs LBK)\n");
    }
    sh("rm -rf %s", dir);
}

/* The Cornell box cut into units that share its caches (DIST.md §Shared caches). */
#define SHARED_PLAN_HASH 0x5eed5a7e0ddba11ull
#define CORNELL "scenes/cornell_box/CornellBox-Original.gltf"

static size_t files_in(const char *dir)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "ls %s | grep -c '\\.lbkcache$'", dir);
    FILE *f = popen(cmd, "r");
    size_t n = 0;
    if (f) {
        if (fscanf(f, "%zu", &n) != 1) n = 0;
        pclose(f);
    }
    return n;
}

/* Units one after another: the first computes every share, the others read them all; every
 * part equals the part of a unit that shares nothing, so the merge is the local bake. */
static void test_shared_sequential_units(void **state)
{
    (void)state;
    char dir[] = "/tmp/lbk-shared-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char cache[64];
    snprintf(cache, sizeof cache, "%s/cache", dir);
    lbk_bake_desc d = desc_of(64, 4, 11);
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_file(CORNELL, &d, &out), LBK_OK);
    bytes local;
    assert_int_equal(lbk_bake_output_container(out, &local.p, &local.n), LBK_OK);
    lbk_bake_output_free(out);
    enum { N = 5 };
    bytes parts[N];
    const lbk_bake_unit_desc sd = {sizeof sd, cache, 0};
    uint64_t computed = 0;
    for (uint32_t k = 0; k < N; k++) {
        lbk_bake_unit_stats st;
        memset(&st, 0, sizeof st);
        st.size = sizeof st;
        last_error[0] = 0;
        lbk_result r = lbk_bake_unit_shared(CORNELL, &d, SHARED_PLAN_HASH, N, k, &sd, &st, &parts[k].p, &parts[k].n);
        if (r) fail_msg("unit %u: %s (%s)", k, lbk_result_message(r), last_error);
        if (k == 0) {
            assert_true(st.shares_computed > 0);
            assert_int_equal(st.shares_read, 0);
            assert_int_equal(st.shares_computed % N, 0); /* whole bounces, every share of each */
            computed = st.shares_computed;
        } else {
            assert_int_equal(st.shares_computed, 0);
            assert_int_equal(st.shares_read, computed);
        }
        bytes alone;
        assert_int_equal(lbk_bake_unit_from_file(CORNELL, &d, SHARED_PLAN_HASH, N, k, &alone.p, &alone.n), LBK_OK);
        assert_int_equal(alone.n, parts[k].n);
        assert_memory_equal(alone.p, parts[k].p, alone.n);
        lbk_bake_part_free(alone.p);
    }
    assert_int_equal(files_in(cache), computed);
    const void *p[N];
    size_t s[N];
    for (int k = 0; k < N; k++) p[k] = parts[k].p, s[k] = parts[k].n;
    assert_int_equal(lbk_bake_merge_from_file(CORNELL, &d, SHARED_PLAN_HASH, N, p, s, N, &out), LBK_OK);
    bytes m;
    assert_int_equal(lbk_bake_output_container(out, &m.p, &m.n), LBK_OK);
    lbk_bake_output_free(out);
    assert_int_equal(m.n, local.n);
    assert_memory_equal(m.p, local.p, m.n);
    printf("%u units: %llu shares computed once, read by the other %u units\n", N, (unsigned long long)computed, N - 1);
    /* a damaged share (a crash while it was written) is computed again, the part the same */
    assert_int_equal(sh("f=$(ls %s/*-s1of5.lbkcache | head -n 1) && printf 'XXXX' | dd of=$f bs=1 seek=150 conv=notrunc "
                        "2>/dev/null", cache), 0);
    lbk_bake_unit_stats st;
    memset(&st, 0, sizeof st);
    st.size = sizeof st;
    bytes again;
    assert_int_equal(lbk_bake_unit_shared(CORNELL, &d, SHARED_PLAN_HASH, N, 2, &sd, &st, &again.p, &again.n), LBK_OK);
    assert_int_equal(st.shares_computed, 1);
    assert_int_equal(st.shares_read, computed - 1);
    assert_int_equal(again.n, parts[2].n);
    assert_memory_equal(again.p, parts[2].p, again.n);
    lbk_bake_part_free(again.p);
    /* a share of another bake (other options under the same plan hash) is refused by name */
    lbk_bake_desc other = d;
    other.seed = 12;
    bytes bad = {NULL, 0};
    last_error[0] = 0;
    assert_int_equal(lbk_bake_unit_shared(CORNELL, &other, SHARED_PLAN_HASH, N, 2, &sd, NULL, &bad.p, &bad.n), LBK_ERR_BAD_INPUT);
    assert_non_null(strstr(last_error, ".lbkcache"));
    assert_non_null(strstr(last_error, "another bake"));
    assert_null(bad.p);
    assert_int_equal(lbk_bake_cache_dir_remove(cache), LBK_OK);
    assert_int_equal(sh("test ! -e %s", cache), 0);
    for (int k = 0; k < N; k++) lbk_bake_part_free(parts[k].p);
    lbk_free(NULL, m.p);
    lbk_free(NULL, local.p);
    sh("rm -rf %s", dir);
}

/* Through the CLI: units together (xargs -P 3 of 6), units after one was killed holding claims,
 * and a claim a live unit elsewhere holds past its lease; every merge is the local bake and
 * removes the cache folder. */
static void test_shared_cli_units(void **state)
{
    (void)state;
    const char *lbk = getenv("LBK");
    if (!lbk || !*lbk) {
        printf("SKIPPED: set LBK to the lbk binary (make test does)\n");
        skip();
    }
    char dir[] = "/tmp/lbk-shared-XXXXXX";
    assert_non_null(mkdtemp(dir));
    const char *opts = "--samples 128 --target-error none --texel-density 6 --seed 2";
    assert_int_equal(sh("%s bake %s -o %s/local.lbk %s --threads 2 -q", lbk, CORNELL, dir, opts), 0);
    assert_int_equal(sh("%s plan %s -o %s/out.lbk --plan %s/plan.json --units 6 %s >/dev/null", lbk, CORNELL, dir, dir, opts), 0);
    assert_int_equal(sh("seq 0 5 | xargs -P 3 -I {} %s bake-unit %s/plan.json {} -o %s/part-{}.lbkpart --threads 1 > %s/log",
                        lbk, dir, dir, dir), 0);
    /* every share computed once (one file each), and every unit holds every share: its own
     * computed, the rest read */
    assert_int_equal(sh("n=$(ls %s/out.lbk.cache-*/ | grep -c 'lbkcache$') && awk -v n=$n '/cache shares computed/ "
                        "{c += $6; u++; if ($6 + $10 != n) bad = 1} END {exit !(u == 6 && c == n && !bad)}' %s/log", dir, dir), 0);
    assert_int_equal(sh("%s merge %s/plan.json %s/part-*.lbkpart -q && cmp %s/local.lbk %s/out.lbk", lbk, dir, dir, dir, dir), 0);
    assert_int_equal(sh("! ls -d %s/out.lbk.cache-* 2>/dev/null", dir), 0);
    /* claims left behind by a unit killed with kill -9 (a process gone from this host: taken at
     * once, under the default lease of 600 s) with its temporary file */
    assert_int_equal(sh("rm -f %s/part-* %s/out.lbk && mkdir %s/cache && dead=$(sh -c 'echo $$') && "
                        "echo \"LBKCLAIM $(hostname) $dead\" > %s/cache/r0-p0-h0-b1-s0of6.lbkcache.claim && "
                        "echo x > %s/cache/r0-p0-h0-b1-s1of6.lbkcache.tmp.gone.1", dir, dir, dir, dir, dir), 0);
    assert_int_equal(sh("timeout 120 %s bake-unit %s/plan.json 0 -o %s/part-0.lbkpart --threads 2 -q --cache-dir %s/cache && "
                        "test -e %s/cache/r0-p0-h0-b1-s0of6.lbkcache", lbk, dir, dir, dir, dir), 0);
    /* a fresh claim of a unit on another machine that never publishes: taken after the lease */
    assert_int_equal(sh("rm -rf %s/cache && mkdir %s/cache && echo 'LBKCLAIM elsewhere 1' > %s/cache/r0-p1-h1-b2-s4of6.lbkcache.claim",
                        dir, dir, dir), 0);
    assert_int_equal(sh("for k in 0 1 2 3 4 5; do timeout 120 %s bake-unit %s/plan.json $k -o %s/part-$k.lbkpart --threads 2 "
                        "-q --cache-dir %s/cache --cache-lease 2 || exit 1; done && test -e %s/cache/r0-p1-h1-b2-s4of6.lbkcache",
                        lbk, dir, dir, dir, dir), 0);
    assert_int_equal(sh("%s merge %s/plan.json %s/part-*.lbkpart --cache-dir %s/cache -q && cmp %s/local.lbk %s/out.lbk && "
                        "test ! -e %s/cache", lbk, dir, dir, dir, dir, dir, dir), 0);
    /* no sharing at all: the same container */
    assert_int_equal(sh("rm -f %s/part-* && for k in 0 1 2 3 4 5; do %s bake-unit %s/plan.json $k -o %s/part-$k.lbkpart "
                        "--no-shared-cache -q || exit 1; done && test ! -e %s/out.lbk.cache-* && %s merge %s/plan.json "
                        "%s/part-*.lbkpart -o %s/plain.lbk -q && cmp %s/local.lbk %s/plain.lbk", dir, lbk, dir, dir, dir, lbk,
                        dir, dir, dir, dir, dir), 0);
    sh("rm -rf %s", dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cut_tiles),
        cmocka_unit_test(test_merge_equals_local_cornell),
        cmocka_unit_test(test_merge_equals_local_sets_doors),
        cmocka_unit_test(test_merge_equals_local_room),
        cmocka_unit_test(test_merge_equals_local_error_target),
        cmocka_unit_test(test_merge_equals_local_cornell_default_target),
        cmocka_unit_test(test_merge_equals_local_guided_doors),
        cmocka_unit_test(test_merge_equals_local_octahedral),
        cmocka_unit_test(test_bad_parts_refused),
        cmocka_unit_test(test_unsplittable_refused),
        cmocka_unit_test(test_cli_plan_units_merge),
        cmocka_unit_test(test_changed_inputs_refused),
        cmocka_unit_test(test_shared_sequential_units),
        cmocka_unit_test(test_shared_cli_units),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
