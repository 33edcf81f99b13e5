/* Parts forged past their checksums (spec/part.md): a part comes from another machine, and its
 * checksums only catch accidents. A part whose checksums and identity are right but whose numbers
 * no bake makes (a negative sample count, a NaN accumulator or output) is refused by the merge with
 * a message, instead of being cast or encoded (fuzz_part found the negative count: UB in the
 * report's cast). The genuine part merges, so every refusal below is the forged number's. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include "lbk/bake.h"
#include "lbk/bake_dist.h"
#include "lbk/byteorder.h"

#define SCENE "tests/fuzz/part_scene.gltf"
#define PLAN_HASH 0x70617274666f7267ull
/* spec/part.md (format 2): header 96 bytes, then per run a 112-byte header, its passes (a 64-byte
 * header and 32 bytes per receiver each), then its outputs */
#define HEADER 96
#define RUN_HEADER 112

static char last_error[1024];

static void on_message(void *user, lbk_bake_severity s, const char *m)
{
    (void)user;
    if (s == LBK_BAKE_SEVERITY_ERROR) snprintf(last_error, sizeof last_error, "%s", m);
}

static lbk_bake_desc desc(void)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.threads = 1;
    d.target_error = -1;
    d.max_samples = 4;
    d.texel_density = 2;
    d.glg_spacing = 8;
    d.message = on_message;
    return d;
}

/* What a forger does after changing the payload: the checksums made right again. */
static void reseal(uint8_t *p, size_t n)
{
    lbk_wr64(p + 72, XXH64(p + HEADER, n - HEADER, 0));
    lbk_wr64(p + 88, XXH64(p, 88, 0));
}

static lbk_result merge(const void *part, size_t n)
{
    lbk_bake_desc d = desc();
    const void *parts[1] = {part};
    size_t sizes[1] = {n};
    lbk_bake_output *out = NULL;
    last_error[0] = 0;
    lbk_result r = lbk_bake_merge_from_file(SCENE, &d, PLAN_HASH, 1, parts, sizes, 1, &out);
    lbk_bake_output_free(out);
    return r;
}

typedef struct unit {
    uint8_t *p;
    size_t n;
} unit;

static int setup(void **state)
{
    lbk_bake_desc d = desc();
    void *part = NULL;
    size_t n = 0;
    if (lbk_bake_unit_from_file(SCENE, &d, PLAN_HASH, 1, 0, &part, &n) != LBK_OK) return -1;
    unit *u = malloc(sizeof *u);
    u->p = malloc(n);
    memcpy(u->p, part, n);
    u->n = n;
    lbk_bake_part_free(part);
    *state = u;
    return 0;
}

static int teardown(void **state)
{
    unit *u = *state;
    free(u->p);
    free(u);
    return 0;
}

static uint8_t *forged(const unit *u)
{
    uint8_t *p = malloc(u->n);
    memcpy(p, u->p, u->n);
    return p;
}

static void expect_refused(uint8_t *p, size_t n)
{
    reseal(p, n);
    lbk_result r = merge(p, n);
    if (r != LBK_ERR_BAD_INPUT) print_message("merge: %d, %s\n", (int)r, last_error);
    assert_int_equal(r, LBK_ERR_BAD_INPUT);
    assert_non_null(strstr(last_error, "corrupt or forged"));
    free(p);
}

static void test_genuine_part_merges(void **state)
{
    unit *u = *state;
    assert_int_equal(merge(u->p, u->n), LBK_OK);
}

static void test_negative_sample_count_refused(void **state)
{
    unit *u = *state;
    uint8_t *p = forged(u);
    lbk_wrf64(p + HEADER + RUN_HEADER + 8, -2.2e295); /* run 0, pass 0: samples_per_receiver */
    expect_refused(p, u->n);
}

static void test_nan_accumulator_refused(void **state)
{
    unit *u = *state;
    uint8_t *p = forged(u);
    lbk_wrf64(p + HEADER + RUN_HEADER + 64 + 8, NAN); /* run 0, pass 0, receiver 0: x_acc of half 1 */
    expect_refused(p, u->n);
}

static void test_infinite_output_refused(void **state)
{
    unit *u = *state;
    uint8_t *p = forged(u);
    lbk_wrf32(p + u->n - 4, INFINITY); /* the last run's last output value */
    expect_refused(p, u->n);
}

static void test_unknown_stop_reason_refused(void **state)
{
    unit *u = *state;
    uint8_t *p = forged(u);
    p[HEADER + 8] = 7; /* run 0's stop reason: no such reason (it indexes the names' table) */
    expect_refused(p, u->n);
}

/* Octahedral probes in a bake that has none (spec/part.md §2.1: a block of one probe after the
 * run records, finite values, the count at header offset 48): refused, not encoded. */
static void test_octahedral_block_forged_refused(void **state)
{
    unit *u = *state;
    const size_t n = u->n + 16 + 48 * 4;
    uint8_t *p = calloc(1, n);
    assert_non_null(p);
    memcpy(p, u->p, u->n);
    lbk_wr64(p + 48, 1);
    lbk_wr64(p + 64, n - HEADER);
    for (int i = 0; i < 48; i++) lbk_wrf32(p + u->n + 16 + 4 * i, 0.5f);
    expect_refused(p, n);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_genuine_part_merges),
        cmocka_unit_test(test_negative_sample_count_refused),
        cmocka_unit_test(test_nan_accumulator_refused),
        cmocka_unit_test(test_octahedral_block_forged_refused),
        cmocka_unit_test(test_infinite_output_refused),
        cmocka_unit_test(test_unknown_stop_reason_refused),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
