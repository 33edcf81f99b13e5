/* DLS packing: builder → bytes → view → decode round trips for every overlap count 1…16 (and
 * beyond), cluster sizes at and around the 16- and 8-target base boundaries, an independent
 * decoder of the prefix bits written from spec/container.md §12, determinism, the clustering
 * rule and the statistics numbers. */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_tuning: experimental (lbk/dls.h) */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/dls.h"
#include "support/dls_fixture.h"

/* ---- round trip ---------------------------------------------------------------------------- */

typedef struct rt_check {
    const dlsfx *fx;
    uint32_t space;
    uint32_t **idx;  /* per set: target → 1 + entry */
    uint8_t *seen;
    uint32_t max_count;
    uint64_t bad;
} rt_check;

static int check_target(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    rt_check *c = user;
    uint32_t psize = c->space == 0 ? 8 : 28;
    if (target >= c->fx->desc.target_count[c->space] || c->seen[target]) { c->bad++; return 0; }
    c->seen[target] = 1;
    uint32_t expect = 0;
    for (uint32_t s = 0; s < c->fx->set_count; s++) expect += c->idx[s][target] != 0;
    if (expect != count) c->bad++;
    if (count > c->max_count) c->max_count = count;
    for (uint32_t j = 0; j < count; j++) {
        uint32_t s = sets[j];
        if (s >= c->fx->set_count || (j && s <= sets[j - 1]) || !c->idx[s][target]) { c->bad++; continue; }
        const uint8_t *want = (const uint8_t *)c->fx->sets[s].entries[c->space].payloads + (uint64_t)(c->idx[s][target] - 1) * psize;
        if (memcmp(want, payloads + (size_t)j * psize, psize)) c->bad++;
    }
    return 0;
}

/* Decodes every cluster of `space` and checks each (target, set) payload against the input and
 * that every touched target is in exactly one cluster. Returns the number of mismatches. */
static uint64_t verify_space(const dlsfx *fx, const lbk_dls_view *v, uint32_t space)
{
    rt_check c = {fx, space, calloc(fx->set_count, sizeof(uint32_t *)), calloc(fx->desc.target_count[space] + 1, 1), 0, 0};
    for (uint32_t s = 0; s < fx->set_count; s++) c.idx[s] = dlsfx_index(fx, s, space);
    for (uint32_t ci = 0; ci < lbk_dls_cluster_count(v); ci++) {
        lbk_dls_cluster_info info;
        assert_int_equal(lbk_dls_cluster_get(v, ci, &info), LBK_OK);
        if (info.space == space) assert_int_equal(lbk_dls_cluster_decode(v, ci, check_target, &c), LBK_OK);
    }
    for (uint64_t t = 0; t < fx->desc.target_count[space]; t++) {
        bool touched = false;
        for (uint32_t s = 0; s < fx->set_count; s++) touched |= c.idx[s][t] != 0;
        if (touched != (c.seen[t] != 0)) c.bad++;
    }
    for (uint32_t s = 0; s < fx->set_count; s++) free(c.idx[s]);
    free(c.idx);
    free(c.seen);
    return c.bad;
}

/* ---- an independent reader of the prefix forms, written from the spec text ---------------- */

static uint32_t rd32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t rd64(const uint8_t *p) { return rd32(p) | (uint64_t)rd32(p + 4) << 32; }

typedef struct spec_arrays {
    uint64_t off[14];
} spec_arrays;

/* §12.2: arrays follow the 96-byte header in a fixed order, each at the next multiple of 16. */
static void spec_layout(const uint8_t *d, spec_arrays *a)
{
    const uint64_t count[14] = {rd32(d + 0), rd32(d + 4), rd32(d + 8), rd32(d + 12), rd32(d + 16), rd32(d + 20),
                                rd32(d + 24), rd32(d + 28), rd32(d + 32), rd32(d + 36), rd64(d + 40), rd64(d + 48),
                                rd64(d + 56), rd64(d + 64)};
    const uint64_t elem[14] = {32, 8, 4, 64, 4, 8, 16, 4, 2, 4, 1, 8, 28, 1};
    uint64_t at = 96;
    for (int i = 0; i < 14; i++) {
        at = (at + 15) & ~15ull;
        a->off[i] = at;
        at += count[i] * elem[i];
    }
}

/* For each prefix cluster: field i of a b-bit form sits in word i / floor(32/b) at bit
 * b·(i mod floor(32/b)); the entry offset of target i is base[i / B] + Σ (field + bias) over
 * the earlier targets of its batch, and must equal the running sum. Returns mismatches. */
static uint64_t verify_prefix_bits(const uint8_t *d, uint32_t *clusters_checked)
{
    spec_arrays a;
    spec_layout(d, &a);
    uint64_t bad = 0;
    uint32_t ncl = rd32(d + 12);
    for (uint32_t ci = 0; ci < ncl; ci++) {
        const uint8_t *c = d + a.off[3] + 64ull * ci;
        uint32_t form = rd32(c);
        if (form < 2) continue;
        uint32_t bits = form == 2 ? 2 : form == 3 ? 3 : 8, bias = form == 2 ? 5 : form == 3 ? 9 : 17;
        uint32_t batch = form == 3 ? 8 : 16, per_word = 32 / bits;
        uint32_t T = rd32(c + 28), E = rd32(c + 44);
        const uint8_t *words = d + a.off[7] + 4ull * rd32(c + 32);
        const uint8_t *bases = d + a.off[form == 4 ? 9 : 8] + (form == 4 ? 4ull : 2ull) * rd32(c + 40);
        uint64_t running = 0;
        for (uint32_t i = 0; i < T; i++) {
            uint32_t field = (rd32(words + 4 * (i / per_word)) >> (bits * (i % per_word))) & ((1u << bits) - 1);
            uint64_t base = form == 4 ? rd32(bases + 4 * (i / batch)) : (uint64_t)(bases[2 * (i / batch)] | bases[2 * (i / batch) + 1] << 8);
            uint64_t off = base;
            for (uint32_t j = i - i % batch; j < i; j++)
                off += ((rd32(words + 4 * (j / per_word)) >> (bits * (j % per_word))) & ((1u << bits) - 1)) + bias;
            if (off != running) bad++;
            running += field + bias;
        }
        if (running != E) bad++;
        if (form == 3) /* 3-bit words: bits 30–31 are zero */
            for (uint32_t w = 0; w < (T + 9) / 10; w++) bad += (rd32(words + 4 * w) >> 30) != 0;
        (*clusters_checked)++;
    }
    return bad;
}

static void build_ok(const dlsfx *fx, const lbk_dls_build_options *opt, void **bytes, size_t *size, lbk_dls_stats *st,
                     lbk_dls_view **v)
{
    assert_int_equal(lbk_dls_build(&fx->desc, opt, bytes, size, st), LBK_OK);
    assert_int_equal(lbk_dls_open(*bytes, *size, NULL, v), LBK_OK);
}

/* ---- tests ----------------------------------------------------------------------------------- */

static uint32_t expected_form(uint32_t k, uint32_t n)
{
    if (k <= 8 && n > 128) return LBK_DLS_FORM_DEDICATED;
    if (k <= 4) return LBK_DLS_FORM_PACKED;
    if (k <= 8) return LBK_DLS_FORM_PREFIX2;
    if (k <= 16) return LBK_DLS_FORM_PREFIX3;
    return LBK_DLS_FORM_PREFIX8;
}

/* One combination of k sets over N consecutive texels, for every k and sizes around the bases. */
static void test_every_overlap_count(void **state)
{
    (void)state;
    static const uint32_t sizes[] = {1, 7, 8, 9, 15, 16, 17, 31, 32, 33, 128, 129, 300};
    uint64_t rng = 1;
    for (uint32_t k = 1; k <= 16; k++)
        for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; si++) {
            uint32_t n = sizes[si];
            dlsfx fx;
            dlsfx_init(&fx, k, 1000, 0, 0);
            for (uint32_t s = 0; s < k; s++) dlsfx_add_range(&fx, &rng, s, 0, 5, n);
            void *bytes;
            size_t size;
            lbk_dls_stats st;
            lbk_dls_view *v;
            build_ok(&fx, NULL, &bytes, &size, &st, &v);
            assert_int_equal(lbk_dls_cluster_count(v), 1);
            lbk_dls_cluster_info info;
            lbk_dls_cluster_get(v, 0, &info);
            assert_int_equal(info.form, expected_form(k, n));
            assert_int_equal(info.target_count, n);
            assert_int_equal(info.entry_count, n * k);
            assert_int_equal(info.set_count, k);
            assert_int_equal(info.run_count, 1);
            assert_int_equal(verify_space(&fx, v, 0), 0);
            uint32_t checked = 0;
            assert_int_equal(verify_prefix_bits(bytes, &checked), 0);
            assert_int_equal(checked, info.form >= LBK_DLS_FORM_PREFIX2 ? 1 : 0);
            assert_int_equal(st.histogram[0][k], n);
            assert_int_equal(st.histogram[0][0], 1000 - n);
            lbk_dls_close(v);
            free(bytes);
            dlsfx_free(&fx);
        }
}

/* Prefix clusters whose targets have different counts, with sizes at the 16/8 base boundaries:
 * target i is touched by sets 0..c_i−1, c_i cycling through the form's count range. */
static void mixed_counts(uint32_t lo, uint32_t hi, uint32_t space, uint32_t form)
{
    static const uint32_t sizes[] = {1, 7, 8, 9, 15, 16, 17, 23, 24, 25, 31, 32, 33, 64, 65};
    uint64_t rng = 7;
    for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; si++) {
        uint32_t n = sizes[si];
        dlsfx fx;
        uint64_t tc[3] = {0, 0, 0};
        tc[space] = 200;
        dlsfx_init(&fx, hi, tc[0], tc[1], tc[2]);
        uint64_t total = 0;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t c = lo + (i * 5 + i / 3) % (hi - lo + 1);
            total += c;
            for (uint32_t s = 0; s < c; s++) dlsfx_add(&fx, &rng, s, space, 2 * i + 1); /* gaps: one run per target */
        }
        void *bytes;
        size_t size;
        lbk_dls_stats st;
        lbk_dls_view *v;
        build_ok(&fx, NULL, &bytes, &size, &st, &v);
        assert_int_equal(lbk_dls_cluster_count(v), 1);
        lbk_dls_cluster_info info;
        lbk_dls_cluster_get(v, 0, &info);
        assert_int_equal(info.form, form);
        assert_int_equal(info.target_count, n);
        assert_int_equal(info.run_count, n);
        assert_int_equal(info.entry_count, total);
        assert_int_equal(verify_space(&fx, v, space), 0);
        uint32_t checked = 0;
        assert_int_equal(verify_prefix_bits(bytes, &checked), 0);
        assert_int_equal(checked, 1);
        lbk_dls_close(v);
        free(bytes);
        dlsfx_free(&fx);
    }
}

static void test_prefix2_boundaries(void **state)
{
    (void)state;
    mixed_counts(5, 8, LBK_DLS_SPACE_TEXEL, LBK_DLS_FORM_PREFIX2);
    mixed_counts(5, 8, LBK_DLS_SPACE_GLG, LBK_DLS_FORM_PREFIX2);
}

static void test_prefix3_boundaries(void **state)
{
    (void)state;
    mixed_counts(9, 16, LBK_DLS_SPACE_TEXEL, LBK_DLS_FORM_PREFIX3);
    mixed_counts(9, 16, LBK_DLS_SPACE_LLG, LBK_DLS_FORM_PREFIX3);
}

/* More than 16 overlaps: the 8-bit class (3) form up to 255; 256 is refused. */
static void test_more_than_16_overlaps(void **state)
{
    (void)state;
    static const uint32_t ks[] = {17, 24, 40, 255};
    uint64_t rng = 3;
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; i++) {
        uint32_t k = ks[i];
        dlsfx fx;
        dlsfx_init(&fx, k, 40, 0, 0);
        for (uint32_t s = 0; s < k; s++) dlsfx_add_range(&fx, &rng, s, 0, 0, s < 17 ? 21 : 17); /* 17 or k sets */
        void *bytes;
        size_t size;
        lbk_dls_stats st;
        lbk_dls_view *v;
        build_ok(&fx, NULL, &bytes, &size, &st, &v);
        assert_int_equal(st.clusters_by_form[LBK_DLS_FORM_PREFIX8], 1);
        assert_int_equal(st.histogram[0][17], 21); /* every touched target has > 16 */
        assert_int_equal(verify_space(&fx, v, 0), 0);
        uint32_t checked = 0;
        assert_int_equal(verify_prefix_bits(bytes, &checked), 0);
        assert_int_equal(checked, 1);
        lbk_dls_close(v);
        free(bytes);
        dlsfx_free(&fx);
    }
    dlsfx fx;
    dlsfx_init(&fx, 256, 4, 0, 0);
    for (uint32_t s = 0; s < 256; s++) dlsfx_add(&fx, &rng, s, 0, 2);
    void *bytes = (void *)1;
    size_t size = 1;
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_ERR_OVERLAPS);
    assert_null(bytes);
    dlsfx_free(&fx);
}

/* 16 overlaps on 5000 targets = 80000 entries: split into clusters of ≤ 65535 entries. */
static void test_prefix_entry_cap_splits(void **state)
{
    (void)state;
    uint64_t rng = 5;
    dlsfx fx;
    dlsfx_init(&fx, 16, 6000, 0, 0);
    for (uint32_t s = 0; s < 16; s++) dlsfx_add_range(&fx, &rng, s, 0, 100, 5000);
    void *bytes;
    size_t size;
    lbk_dls_stats st;
    lbk_dls_view *v;
    build_ok(&fx, NULL, &bytes, &size, &st, &v);
    assert_int_equal(lbk_dls_cluster_count(v), 2);
    uint32_t total = 0;
    for (uint32_t ci = 0; ci < 2; ci++) {
        lbk_dls_cluster_info info;
        lbk_dls_cluster_get(v, ci, &info);
        assert_int_equal(info.form, LBK_DLS_FORM_PREFIX3);
        assert_true(info.entry_count <= 65535);
        total += info.target_count;
    }
    assert_int_equal(total, 5000);
    lbk_dls_cluster_info first;
    lbk_dls_cluster_get(v, 0, &first);
    assert_int_equal(first.target_count, 65535 / 16); /* 4095 */
    assert_int_equal(verify_space(&fx, v, 0), 0);
    uint32_t checked = 0;
    assert_int_equal(verify_prefix_bits(bytes, &checked), 0);
    assert_int_equal(checked, 2);
    lbk_dls_close(v);
    free(bytes);
    dlsfx_free(&fx);
}

/* Random sets over the three spaces with overlaps of every count up to ~20. */
static void random_fixture(dlsfx *fx, uint64_t seed, uint32_t nsets)
{
    uint64_t rng = seed;
    dlsfx_init(fx, nsets, 4000, 600, 400);
    for (uint32_t s = 0; s < nsets; s++)
        for (uint32_t sp = 0; sp < 3; sp++) {
            uint32_t span = (uint32_t)fx->desc.target_count[sp];
            uint32_t blobs = 1 + (uint32_t)(dlsfx_rand(&rng) % 3);
            for (uint32_t b = 0; b < blobs; b++) {
                uint32_t len = 5 + (uint32_t)(dlsfx_rand(&rng) % (span / 6));
                uint32_t start = (uint32_t)(dlsfx_rand(&rng) % (span - len));
                for (uint32_t t = start; t < start + len; t++) {
                    if (dlsfx_find(fx, s, sp, t)) continue;
                    if (dlsfx_rand(&rng) % 8 == 0) continue; /* holes → many runs */
                    dlsfx_add(fx, &rng, s, sp, t);
                }
            }
        }
}

static void test_random_all_spaces(void **state)
{
    (void)state;
    for (uint64_t seed = 1; seed <= 3; seed++) {
        dlsfx fx;
        random_fixture(&fx, seed, 24);
        void *bytes;
        size_t size;
        lbk_dls_stats st;
        lbk_dls_view *v;
        build_ok(&fx, NULL, &bytes, &size, &st, &v);
        for (uint32_t sp = 0; sp < 3; sp++) assert_int_equal(verify_space(&fx, v, sp), 0);
        uint32_t checked = 0;
        assert_int_equal(verify_prefix_bits(bytes, &checked), 0);
        uint64_t entries = 0;
        for (uint32_t s = 0; s < fx.set_count; s++) entries += fx.sets[s].entries[0].count;
        assert_int_equal(st.entries[0], entries);
        lbk_dls_close(v);
        free(bytes);
        dlsfx_free(&fx);
    }
}

/* The output depends on content only: entry order within a set does not matter. */
static void test_determinism(void **state)
{
    (void)state;
    dlsfx fx;
    random_fixture(&fx, 11, 20);
    void *a, *b;
    size_t na, nb;
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &a, &na, NULL), LBK_OK);
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &b, &nb, NULL), LBK_OK);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    free(b);
    /* Reverse every set's entry order (targets with payloads). */
    uint64_t rng = 99;
    (void)rng;
    for (uint32_t s = 0; s < fx.set_count; s++)
        for (uint32_t sp = 0; sp < 3; sp++) {
            uint64_t n = fx.sets[s].entries[sp].count;
            uint32_t psize = sp == 0 ? 8 : 28;
            uint32_t *t = fx.targets[s][sp];
            uint8_t *p = fx.payloads[s][sp];
            uint8_t tmp[28];
            for (uint64_t i = 0; i < n / 2; i++) {
                uint32_t x = t[i];
                t[i] = t[n - 1 - i];
                t[n - 1 - i] = x;
                memcpy(tmp, p + i * psize, psize);
                memcpy(p + i * psize, p + (n - 1 - i) * psize, psize);
                memcpy(p + (n - 1 - i) * psize, tmp, psize);
            }
        }
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &b, &nb, NULL), LBK_OK);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    free(a);
    free(b);
    dlsfx_free(&fx);
}

/* A: texels 0..299, B: 200..399 → {A} 200 targets (dedicated), {A,B} 100 (packed k=2),
 * {B} 100 (packed k=1). Every number of the statistics follows from the layout of §12. */
static void test_stats_numbers(void **state)
{
    (void)state;
    uint64_t rng = 2;
    dlsfx fx;
    dlsfx_init(&fx, 2, 1000, 0, 0);
    dlsfx_add_range(&fx, &rng, 0, 0, 0, 300);
    dlsfx_add_range(&fx, &rng, 1, 0, 200, 200);
    void *bytes;
    size_t size;
    lbk_dls_stats st;
    lbk_dls_view *v;
    build_ok(&fx, NULL, &bytes, &size, &st, &v);
    assert_int_equal(st.set_count, 2);
    assert_int_equal(st.sets_by_kind[LBK_DLS_KIND_LIGHTS], 2);
    assert_int_equal(st.cluster_count, 3);
    assert_int_equal(st.clusters_by_form[LBK_DLS_FORM_DEDICATED], 1);
    assert_int_equal(st.clusters_by_form[LBK_DLS_FORM_PACKED], 2);
    assert_int_equal(st.packed_subgroups, 2);
    assert_int_equal(st.touched[0], 400);
    assert_int_equal(st.targets_by_form[LBK_DLS_FORM_DEDICATED], 200);
    assert_int_equal(st.targets_by_form[LBK_DLS_FORM_PACKED], 200);
    assert_int_equal(st.entries[0], 500);
    assert_int_equal(st.histogram[0][0], 600);
    assert_int_equal(st.histogram[0][1], 300);
    assert_int_equal(st.histogram[0][2], 100);
    assert_int_equal(st.payload_bytes, 500 * 8);
    /* index: dedicated 64 + 4 + 8; packed k=1: 64 + 4 + 8 + 16; packed k=2: 64 + 8 + 8 + 16 */
    assert_int_equal(st.index_bytes[0], 76 + 92 + 96);
    assert_true(st.index_bits_per_target[0] > 5.279 && st.index_bits_per_target[0] < 5.281);
    /* section: header 96, sets 64 @96, clusters 192 @160, cluster sets 16 @352, runs 24 @368,
     * sub-groups 32 @400 (392 → 400), texel entries 4000 @432, strings "set0set1" 8 @4432,
     * end 4440 → 4448 */
    assert_int_equal(size, 4448);
    assert_int_equal(st.section_bytes, 4448);
    assert_int_equal(st.ancillary_bytes, 4448 - 4000);
    lbk_dls_close(v);
    free(bytes);
    dlsfx_free(&fx);
}

/* Two families of small 5-set combinations over disjoint set ranges go to two prefix clusters of
 * 6 sets each, not one of 12: a dispatch lists few sets. */
static void test_clustering_keeps_set_lists_small(void **state)
{
    (void)state;
    uint64_t rng = 4;
    dlsfx fx;
    dlsfx_init(&fx, 16, 2000, 0, 0);
    static const uint32_t fam[3][5] = {{0, 1, 2, 3, 4}, {0, 1, 2, 3, 5}, {0, 1, 2, 4, 5}};
    uint32_t at = 0;
    for (uint32_t f = 0; f < 2; f++)
        for (uint32_t c = 0; c < 3; c++) {
            for (uint32_t j = 0; j < 5; j++) dlsfx_add_range(&fx, &rng, fam[c][j] + 10 * f, 0, at, 100);
            at += 150;
        }
    void *bytes;
    size_t size;
    lbk_dls_stats st;
    lbk_dls_view *v;
    build_ok(&fx, NULL, &bytes, &size, &st, &v);
    assert_int_equal(lbk_dls_cluster_count(v), 2);
    for (uint32_t ci = 0; ci < 2; ci++) {
        lbk_dls_cluster_info info;
        lbk_dls_cluster_get(v, ci, &info);
        assert_int_equal(info.form, LBK_DLS_FORM_PREFIX2);
        assert_int_equal(info.set_count, 6);
        assert_int_equal(info.target_count, 300);
        uint32_t s0;
        lbk_dls_cluster_set_get(v, ci, 0, &s0);
        assert_int_equal(s0, 10 * ci);
    }
    assert_int_equal(verify_space(&fx, v, 0), 0);
    lbk_dls_close(v);
    free(bytes);

    /* With a dispatch minimum of 1000 targets the two families share one cluster of 12 sets. */
    const lbk_dls_tuning tune = {.min_dispatch_targets = 1000};
    const lbk_dls_build_options opt = {.size = sizeof opt, .tuning = &tune};
    build_ok(&fx, &opt, &bytes, &size, &st, &v);
    assert_int_equal(lbk_dls_cluster_count(v), 1);
    lbk_dls_cluster_info info;
    lbk_dls_cluster_get(v, 0, &info);
    assert_int_equal(info.set_count, 12);
    assert_int_equal(verify_space(&fx, v, 0), 0);
    lbk_dls_close(v);
    free(bytes);
    dlsfx_free(&fx);
}

/* Small single-set combinations pack into class (1) clusters capped by packed_max_targets. */
static void test_packed_cap(void **state)
{
    (void)state;
    uint64_t rng = 8;
    dlsfx fx;
    dlsfx_init(&fx, 10, 2000, 0, 0);
    for (uint32_t s = 0; s < 10; s++) dlsfx_add_range(&fx, &rng, s, 0, 150 * s, 100);
    const lbk_dls_tuning tune = {.min_dispatch_targets = 10000, .packed_max_targets = 300};
    const lbk_dls_build_options opt = {.size = sizeof opt, .tuning = &tune};
    void *bytes;
    size_t size;
    lbk_dls_stats st;
    lbk_dls_view *v;
    build_ok(&fx, &opt, &bytes, &size, &st, &v);
    assert_int_equal(st.clusters_by_form[LBK_DLS_FORM_PACKED], 4); /* 3 + 3 + 3 + 1 sub-groups */
    assert_int_equal(st.packed_subgroups, 10);
    for (uint32_t ci = 0; ci < lbk_dls_cluster_count(v); ci++) {
        lbk_dls_cluster_info info;
        lbk_dls_cluster_get(v, ci, &info);
        assert_true(info.target_count <= 300);
        assert_int_equal(info.overlaps, 1);
    }
    assert_int_equal(verify_space(&fx, v, 0), 0);
    lbk_dls_close(v);
    free(bytes);
    dlsfx_free(&fx);
}

static void test_invalid_inputs(void **state)
{
    (void)state;
    uint64_t rng = 9;
    void *bytes;
    size_t size;
    dlsfx fx;
    dlsfx_init(&fx, 3, 100, 10, 0);
    dlsfx_add_range(&fx, &rng, 0, 0, 0, 10);
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_OK);
    free(bytes);
    dlsfx_add(&fx, &rng, 0, 0, 3); /* target 3 twice in set 0 */
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_ERR_INVALID_ARGUMENT);
    dlsfx_free(&fx);

    dlsfx_init(&fx, 3, 100, 10, 0);
    dlsfx_add(&fx, &rng, 1, 1, 10); /* GLG has 10 probes */
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_ERR_RANGE);
    dlsfx_free(&fx);

    dlsfx_init(&fx, 3, 100, 10, 0);
    fx.sets[2].name = "set0";
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_ERR_INVALID_ARGUMENT);
    fx.sets[2].name = "";
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_ERR_INVALID_ARGUMENT);
    fx.sets[2].name = fx.names[2];
    uint32_t self[2] = {0, 2};
    dlsfx_combination(&fx, 2, 2, self);
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_ERR_INVALID_ARGUMENT);
    uint32_t ok[2] = {1, 0};
    dlsfx_combination(&fx, 2, 2, ok);
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_OK);
    lbk_dls_view *v;
    assert_int_equal(lbk_dls_open(bytes, size, NULL, &v), LBK_OK);
    uint32_t m0, m1;
    assert_int_equal(lbk_dls_set_member_get(v, 2, 0, &m0), LBK_OK);
    assert_int_equal(lbk_dls_set_member_get(v, 2, 1, &m1), LBK_OK);
    assert_int_equal(m0, 0); /* stored ascending */
    assert_int_equal(m1, 1);
    uint32_t found;
    assert_int_equal(lbk_dls_set_find(v, "set1", &found), LBK_OK);
    assert_int_equal(found, 1);
    assert_int_equal(lbk_dls_set_find(v, "nope", &found), LBK_ERR_NOT_FOUND);
    lbk_dls_close(v);
    free(bytes);
    fx.sets[1].kind = LBK_DLS_KIND_COMBINATION; /* members must not be combinations (and need ≥ 2) */
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &bytes, &size, NULL), LBK_ERR_INVALID_ARGUMENT);
    dlsfx_free(&fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_overlap_count),
        cmocka_unit_test(test_prefix2_boundaries),
        cmocka_unit_test(test_prefix3_boundaries),
        cmocka_unit_test(test_more_than_16_overlaps),
        cmocka_unit_test(test_prefix_entry_cap_splits),
        cmocka_unit_test(test_random_all_spaces),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_stats_numbers),
        cmocka_unit_test(test_clustering_keeps_set_lists_small),
        cmocka_unit_test(test_packed_cap),
        cmocka_unit_test(test_invalid_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
