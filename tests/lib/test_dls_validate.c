/* DLS and DOOR validators: a section with every cluster form validates clean; targeted
 * corruptions of prefix bits, bases, slots, runs, sub-groups, header counts, padding, set
 * records and payloads are reported with the right IDs of spec/validation.md; every truncation
 * and every single-bit flip of the index data is handled without a crash and nearly all flips
 * are caught; DOOR set kinds are cross-checked against the DLS facts. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "libformat/src/dls_format.h"
#include "lbk/door.h"
#include "support/dls_fixture.h"

typedef struct issues {
    uint32_t ids[512];
    uint32_t n;
} issues;

static int collect(void *user, const lbk_issue *is)
{
    issues *x = user;
    if (x->n < 512) x->ids[x->n++] = is->id;
    return 0;
}

static bool has(const issues *x, uint32_t id)
{
    for (uint32_t i = 0; i < x->n; i++)
        if (x->ids[i] == id) return true;
    return false;
}

typedef struct facts {
    uint64_t texels, glg, llg;
} facts;

/* Runs lbk_validate_dls over bytes; returns the issues and the error count. */
static uint32_t validate_dls(const uint8_t *d, size_t n, facts f, issues *out, lbk_vctx *keep)
{
    memset(out, 0, sizeof *out);
    lbk_validate_summary sum = {0};
    lbk_vctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.callback = collect;
    ctx.user = out;
    ctx.summary = &sum;
    ctx.section_type = LBK_SECTION_DLS;
    ctx.lmap_ok = 1, ctx.lmap_texel_count = f.texels;
    ctx.glg_ok = 1, ctx.glg_probe_count = (uint32_t)f.glg;
    ctx.llg_ok = 1, ctx.llg_probe_count = f.llg;
    ctx.present_types[ctx.present_count++] = LBK_SECTION_DLS;
    lbk_validate_dls(&ctx, d, n);
    if (keep) *keep = ctx;
    else free(ctx.dls_facts);
    return sum.errors + sum.fatal;
}

/* Every form: dedicated {0}, packed {1}, prefix-2 {2..7}, prefix-3 {2..13}, prefix-8 {0..19},
 * and GLG probes. */
static void fixture(dlsfx *fx)
{
    uint64_t rng = 77;
    dlsfx_init(fx, 20, 3000, 40, 0);
    dlsfx_add_range(fx, &rng, 0, 0, 0, 300);
    dlsfx_add_range(fx, &rng, 1, 0, 400, 50);
    for (uint32_t s = 2; s <= 7; s++) dlsfx_add_range(fx, &rng, s, 0, 500, 40);
    for (uint32_t s = 2; s <= 13; s++) dlsfx_add_range(fx, &rng, s, 0, 600, 40);
    for (uint32_t s = 0; s < 20; s++) dlsfx_add_range(fx, &rng, s, 0, 700, 20);
    dlsfx_add_range(fx, &rng, 3, 1, 0, 10);
}

typedef struct built {
    uint8_t *d;
    size_t n;
    dls_layout L;
    uint32_t cl[LBK_DLS_FORM_COUNT_]; /* first cluster of each form */
} built;

static void build(built *b)
{
    dlsfx fx;
    fixture(&fx);
    void *bytes;
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &b->n, NULL), LBK_OK);
    b->d = bytes;
    dlsfx_free(&fx);
    dls_layout_from_header(b->d, &b->L);
    assert_true(dls_layout_compute(&b->L));
    for (int f = 0; f < LBK_DLS_FORM_COUNT_; f++) b->cl[f] = UINT32_MAX;
    for (uint32_t c = 0; c < b->L.count[DLS_A_CLUSTERS]; c++) {
        uint32_t form = lbk_rd32(b->d + b->L.offset[DLS_A_CLUSTERS] + 64ull * c);
        if (b->cl[form] == UINT32_MAX) b->cl[form] = c;
    }
    for (int f = 0; f < LBK_DLS_FORM_COUNT_; f++) assert_int_not_equal(b->cl[f], UINT32_MAX);
}

static uint8_t *cluster(const built *b, uint32_t form) { return b->d + b->L.offset[DLS_A_CLUSTERS] + 64ull * b->cl[form]; }
static uint8_t *array_at(const built *b, int a, uint64_t index, uint64_t elem) { return b->d + b->L.offset[a] + index * elem; }

static const facts F = {3000, 40, 0};

/* Applies `mutate` to a fresh copy and checks `id` is reported. */
typedef void (*mutator)(built *b);
static void expect(mutator m, uint32_t id, facts f)
{
    built b;
    build(&b);
    m(&b);
    issues is;
    uint32_t errors = validate_dls(b.d, b.n, f, &is, NULL);
    if (!has(&is, id)) {
        print_error("expected issue %u, got %u issues:", id, is.n);
        for (uint32_t i = 0; i < is.n; i++) print_error(" %u", is.ids[i]);
        print_error("\n");
    }
    assert_true(has(&is, id));
    lbk_severity sev;
    assert_non_null(lbk_issue_template(id, &sev));
    if (sev != LBK_SEVERITY_WARNING) assert_true(errors > 0);
    lbk_dls_view *v;
    if (sev != LBK_SEVERITY_WARNING && id != 803) assert_int_not_equal(lbk_dls_open(b.d, b.n, NULL, &v), LBK_OK);
    free(b.d);
}

static void test_clean(void **state)
{
    (void)state;
    built b;
    build(&b);
    issues is;
    assert_int_equal(validate_dls(b.d, b.n, F, &is, NULL), 0);
    assert_int_equal(is.n, 0);
    free(b.d);
}

/* prefix-2 cluster: 40 targets of 6 sets, 3 batches of 16 */
static void m_prefix2_first_field(built *b)
{
    uint8_t *w = array_at(b, DLS_A_PREFIX_WORDS, lbk_rd32(cluster(b, 2) + DLS_C_AUX_FIRST), 4);
    w[0] ^= 0x1; /* target 0: count 6 → 5 or 7: base[1] no longer follows */
}
static void m_prefix2_last_field(built *b)
{
    /* target 39 = word 2, field 7 (bits 14–15) — in the last batch: only the entry count disagrees */
    uint8_t *w = array_at(b, DLS_A_PREFIX_WORDS, lbk_rd32(cluster(b, 2) + DLS_C_AUX_FIRST) + 2, 4);
    lbk_wr32(w, lbk_rd32(w) ^ (1u << 14));
}
static void m_prefix2_past_last(built *b)
{
    uint8_t *w = array_at(b, DLS_A_PREFIX_WORDS, lbk_rd32(cluster(b, 2) + DLS_C_AUX_FIRST) + 2, 4);
    lbk_wr32(w, lbk_rd32(w) | (1u << 20)); /* field 10 of the last word: target 42 does not exist */
}
static void m_prefix3_top_bits(built *b)
{
    uint8_t *w = array_at(b, DLS_A_PREFIX_WORDS, lbk_rd32(cluster(b, 3) + DLS_C_AUX_FIRST), 4);
    lbk_wr32(w, lbk_rd32(w) | 0x80000000u);
}
static void m_prefix3_base(built *b)
{
    uint8_t *p = array_at(b, DLS_A_BASE16, lbk_rd32(cluster(b, 3) + DLS_C_BASE_FIRST) + 1, 2);
    lbk_wr16(p, (uint16_t)(lbk_rd16(p) + 1));
}
static void m_prefix8_base(built *b)
{
    uint8_t *p = array_at(b, DLS_A_BASE32, lbk_rd32(cluster(b, 4) + DLS_C_BASE_FIRST), 4);
    lbk_wr32(p, 3); /* base[0] must be 0 */
}
static void m_slot_range(built *b)
{
    *array_at(b, DLS_A_SLOTS, lbk_rd64(cluster(b, 2) + DLS_C_SLOT_FIRST), 1) = 200;
}
static void m_slot_order(built *b)
{
    uint8_t *s = array_at(b, DLS_A_SLOTS, lbk_rd64(cluster(b, 3) + DLS_C_SLOT_FIRST), 1);
    uint8_t t = s[0];
    s[0] = s[1];
    s[1] = t;
}
static void m_run_past_end(built *b)
{
    lbk_wr32(array_at(b, DLS_A_RUNS, lbk_rd32(cluster(b, 0) + DLS_C_RUN_FIRST), 8), 2900); /* 2900 + 300 > 3000 */
}
static void m_run_overlap(built *b)
{
    lbk_wr32(array_at(b, DLS_A_RUNS, lbk_rd32(cluster(b, 1) + DLS_C_RUN_FIRST), 8), 250); /* inside the dedicated 0..299 */
}
static void m_subgroup_slot(built *b)
{
    uint8_t *g = array_at(b, DLS_A_SUBGROUPS, lbk_rd32(cluster(b, 1) + DLS_C_AUX_FIRST), 16);
    g[DLS_G_SLOTS + 1] = 1; /* k = 1: slots 1..3 must be 0 */
}
static void m_subgroup_chain(built *b)
{
    uint8_t *g = array_at(b, DLS_A_SUBGROUPS, lbk_rd32(cluster(b, 1) + DLS_C_AUX_FIRST), 16);
    lbk_wr32(g + DLS_G_TARGET_FIRST, 5);
}
static void m_header_count(built *b) { lbk_wr32(b->d + DLS_H_RUN_COUNT, lbk_rd32(b->d + DLS_H_RUN_COUNT) + 1); }
static void m_padding(built *b)
{
    static const uint32_t elem[DLS_A_COUNT] = {32, 8, 4, 64, 4, 8, 16, 4, 2, 4, 1, 8, 28, 1};
    for (int a = 0; a + 1 < DLS_A_COUNT; a++) {
        uint64_t end = b->L.offset[a] + b->L.count[a] * elem[a];
        if (end < b->L.offset[a + 1]) {
            b->d[end] = 0x20;
            return;
        }
    }
    fail_msg("fixture has no padding gap");
}
static void m_set_kind(built *b) { lbk_wr32(array_at(b, DLS_A_SETS, 4, 32) + DLS_S_KIND, 9); }
static void m_set_dup_name(built *b)
{
    uint8_t *s0 = array_at(b, DLS_A_SETS, 0, 32), *s1 = array_at(b, DLS_A_SETS, 1, 32);
    memcpy(s1, s0, 8); /* same name offset and length */
}
static void m_set_reserved(built *b) { array_at(b, DLS_A_SETS, 2, 32)[DLS_S_RESERVED] = 1; }
static void m_texel_inf(built *b)
{
    uint8_t *e = array_at(b, DLS_A_TEXEL_ENTRIES, 17, 8);
    lbk_wr32(e, lbk_rd32(e) | (31u << 6)); /* R exponent 31 */
}
static void m_form(built *b) { lbk_wr32(cluster(b, 1) + DLS_C_FORM, 7); }
static void m_entry_count(built *b) { lbk_wr32(cluster(b, 0) + DLS_C_ENTRY_COUNT, 301); }
static void m_cluster_set_order(built *b)
{
    uint8_t *s = array_at(b, DLS_A_CLUSTER_SETS, lbk_rd32(cluster(b, 2) + DLS_C_SET_FIRST), 4);
    uint32_t t = lbk_rd32(s);
    lbk_wr32(s, lbk_rd32(s + 4));
    lbk_wr32(s + 4, t);
}
static void m_nothing(built *b) { (void)b; }

static void test_prefix_corruptions(void **state)
{
    (void)state;
    expect(m_prefix2_first_field, 842, F);
    expect(m_prefix2_last_field, 843, F);
    expect(m_prefix2_past_last, 841, F);
    expect(m_prefix3_top_bits, 841, F);
    expect(m_prefix3_base, 842, F);
    expect(m_prefix8_base, 842, F);
    expect(m_slot_range, 844, F);
    expect(m_slot_order, 845, F);
}

static void test_structure_corruptions(void **state)
{
    (void)state;
    expect(m_run_past_end, 826, F);
    expect(m_run_overlap, 829, F);
    expect(m_subgroup_slot, 831, F);
    expect(m_subgroup_chain, 830, F);
    expect(m_header_count, 801, F);
    expect(m_padding, 802, F);
    expect(m_set_kind, 812, F);
    expect(m_set_dup_name, 811, F);
    expect(m_set_reserved, 816, F);
    expect(m_texel_inf, 850, F);
    expect(m_form, 820, F);
    expect(m_entry_count, 828, F);
    expect(m_cluster_set_order, 824, F);
    facts wrong = F;
    wrong.texels = 2999;
    expect(m_nothing, 803, wrong); /* LMAP disagrees: 300..2999 of the targets are fine, count is not */
    facts no_llg = F;
    no_llg.glg = 41;
    expect(m_nothing, 803, no_llg);
}

/* Every truncation is an error; every bit flip is survived and nearly every flip of the index
 * arrays (cluster records through slots) is caught — payload bits are free by design. */
static void test_truncation_and_bit_flips(void **state)
{
    (void)state;
    built b;
    build(&b);
    issues is;
    for (size_t n = 0; n < b.n; n += (n < 200 ? 1 : 7)) assert_true(validate_dls(b.d, n, F, &is, NULL) > 0);
    uint64_t lo = b.L.offset[DLS_A_CLUSTERS], hi = b.L.offset[DLS_A_SLOTS] + b.L.count[DLS_A_SLOTS];
    uint64_t flips = 0, caught = 0;
    for (uint64_t i = 0; i < b.n; i++)
        for (int bit = 0; bit < 8; bit++) {
            b.d[i] ^= (uint8_t)(1u << bit);
            uint32_t errors = validate_dls(b.d, b.n, F, &is, NULL);
            b.d[i] ^= (uint8_t)(1u << bit);
            if (i >= lo && i < hi) {
                flips++;
                caught += errors > 0;
            }
        }
    print_message("index-data bit flips caught: %llu of %llu\n", (unsigned long long)caught, (unsigned long long)flips);
    assert_true(flips > 1000);
    assert_true(caught * 100 >= flips * 95);
    free(b.d);
}

/* ---- DOOR -------------------------------------------------------------------------------- */

/* DLS: 0 lights, 1 open(A), 2 closed(A), 3 combination {0, 1}, 4 open(B). */
static void door_dls(uint8_t **d, size_t *n)
{
    uint64_t rng = 5;
    dlsfx fx;
    dlsfx_init(&fx, 5, 100, 0, 0);
    for (uint32_t s = 0; s < 5; s++) dlsfx_add_range(&fx, &rng, s, 0, 10 * s, 15);
    fx.sets[1].kind = LBK_DLS_KIND_DOOR_OPEN;
    fx.sets[2].kind = LBK_DLS_KIND_DOOR_CLOSED;
    fx.sets[4].kind = LBK_DLS_KIND_DOOR_OPEN;
    uint32_t m[2] = {0, 1};
    dlsfx_combination(&fx, 3, 2, m);
    void *bytes;
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, n, NULL), LBK_OK);
    *d = bytes;
    dlsfx_free(&fx);
}

typedef struct door_case {
    lbk_door_desc doors[2];
    uint32_t state_door;
    uint32_t state_set;
} door_case;

static void door_default(door_case *c)
{
    memset(c, 0, sizeof *c);
    lbk_door_desc a = {"door_a", {0, 0, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {1, 1, 0.1f}, 1, 2};
    lbk_door_desc b = {"door_b", {5, 0, 0}, {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}}, {1, 1, 0.1f}, 4, LBK_DLS_NO_SET};
    c->doors[0] = a;
    c->doors[1] = b;
    c->state_door = 0;
    c->state_set = 3;
}

/* Validates DLS then DOOR in one context; returns the DOOR issues. */
static uint32_t validate_door_case(const door_case *c, bool with_dls, issues *out)
{
    uint8_t *dls;
    size_t dn;
    door_dls(&dls, &dn);
    lbk_door_state_desc st = {1, &c->state_door, c->state_set};
    lbk_door_build_desc dd = {.door_count = 2, .doors = c->doors, .state_count = 1, .states = &st};
    void *door;
    size_t n;
    lbk_result r = lbk_door_build(&dd, NULL, &door, &n);
    assert_int_equal(r, LBK_OK);
    issues dls_issues;
    lbk_vctx ctx;
    facts f = {100, 0, 0};
    assert_int_equal(validate_dls(dls, dn, f, &dls_issues, &ctx), 0);
    lbk_validate_summary sum = {0};
    memset(out, 0, sizeof *out);
    ctx.summary = &sum;
    ctx.user = out;
    ctx.section_type = LBK_SECTION_DOOR;
    if (!with_dls) {
        free(ctx.dls_facts);
        ctx.dls_facts = NULL;
        ctx.dls_ok = 0;
        ctx.present_count = 0;
    }
    lbk_validate_door(&ctx, door, n);
    free(ctx.dls_facts);
    free(door);
    free(dls);
    return sum.errors;
}

static void test_door_validation(void **state)
{
    (void)state;
    door_case c;
    issues is;
    door_default(&c);
    assert_int_equal(validate_door_case(&c, true, &is), 0);
    assert_int_equal(is.n, 0);
    assert_true(validate_door_case(&c, false, &is) > 0);
    assert_true(has(&is, 903));

    door_default(&c);
    c.doors[0].open_set = 0; /* a light set */
    validate_door_case(&c, true, &is);
    assert_true(has(&is, 913));
    assert_true(has(&is, 925)); /* set 1 is now named by no door (warning) */

    door_default(&c);
    c.doors[0].closed_set = 4; /* kind 1, not 2 */
    validate_door_case(&c, true, &is);
    assert_true(has(&is, 914));

    door_default(&c);
    c.doors[1].open_set = 1; /* shared with door A */
    validate_door_case(&c, true, &is);
    assert_true(has(&is, 915));

    door_default(&c);
    c.state_set = 0;
    validate_door_case(&c, true, &is);
    assert_true(has(&is, 922));

    door_default(&c);
    c.state_door = 1; /* door B's open set 4 is not in combination {0, 1} */
    validate_door_case(&c, true, &is);
    assert_true(has(&is, 923));

    /* Structural rules are enforced by the builder (and the validator on raw bytes). */
    door_default(&c);
    c.doors[0].centre[1] = NAN;
    lbk_door_state_desc st = {1, &c.state_door, 3};
    lbk_door_build_desc dd = {.door_count = 2, .doors = c.doors, .state_count = 1, .states = &st};
    void *out;
    size_t n;
    assert_int_equal(lbk_door_build(&dd, NULL, &out, &n), LBK_ERR_INVALID_ARGUMENT);
    c.doors[0].centre[1] = 0;
    c.doors[0].axes[0][0] = 2;
    assert_int_equal(lbk_door_build(&dd, NULL, &out, &n), LBK_ERR_INVALID_ARGUMENT);
    c.doors[0].axes[0][0] = 1;
    c.doors[1].name = "door_a";
    assert_int_equal(lbk_door_build(&dd, NULL, &out, &n), LBK_ERR_INVALID_ARGUMENT);
    c.doors[1].name = "door_b";
    assert_int_equal(lbk_door_build(&dd, NULL, &out, &n), LBK_OK);
    /* raw corruptions */
    lbk_vctx ctx;
    memset(&ctx, 0, sizeof ctx);
    lbk_validate_summary sum = {0};
    issues raw = {0};
    ctx.callback = collect, ctx.user = &raw, ctx.summary = &sum, ctx.section_type = LBK_SECTION_DOOR;
    uint8_t *d = out;
    lbk_wrf32(d + DOOR_HEADER_SIZE + DOOR_E_HALF, -1.0f);
    d[DOOR_H_RESERVED0] = 1;
    lbk_validate_door(&ctx, d, n);
    assert_true(has(&raw, 912));
    assert_true(has(&raw, 902));
    lbk_door_view *v;
    assert_int_equal(lbk_door_open(d, n, NULL, &v), LBK_ERR_CORRUPT);
    for (size_t t = 0; t < n; t++) assert_int_not_equal(lbk_door_open(d, t, NULL, &v), LBK_OK);
    free(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clean),
        cmocka_unit_test(test_prefix_corruptions),
        cmocka_unit_test(test_structure_corruptions),
        cmocka_unit_test(test_truncation_and_bit_flips),
        cmocka_unit_test(test_door_validation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
