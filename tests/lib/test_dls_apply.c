/* Reference runtime apply: equals a dense per-target sum L_B + Σ w_j S_j (decode, weight, sum,
 * encode) within the codecs' quantisation on random sets and random weights; incremental applies
 * that skip unchanged clusters give the bytes of a full apply; all-zero weights give exactly the
 * base; a set without entries adds no data; door weights drive kinds 1–3; pages with padded
 * pitches, the scalar path, jobs in any order and on two threads all give the same bytes; the
 * dirty regions cover every target an apply writes. The linear mode (LBK_DLS_RUNTIME_LINEAR) writes
 * the byte mode's accumulators bit for bit (support/dls_linear_check.h) on every path, split
 * and page layout. */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats: experimental (lbk/dls.h) */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/dls.h"
#include "lbk/pixel.h"
#include "lbk/door.h"
#include "lbk/sh.h"
#include "support/dls_fixture.h"
#include "support/dls_linear_check.h"

typedef struct scene {
    dlsfx fx;
    void *bytes;
    size_t size;
    lbk_dls_view *view;
    uint32_t *base_z, *out_z, *ref_z;
    uint8_t *base_rgba, *out_rgba, *ref_rgba;
    uint8_t *base_probe[2], *out_probe[2], *ref_probe[2];
} scene;

static void random_sets(dlsfx *fx, uint64_t seed, uint32_t nsets)
{
    uint64_t rng = seed;
    dlsfx_init(fx, nsets, 3000, 400, 300);
    for (uint32_t s = 0; s < nsets; s++)
        for (uint32_t sp = 0; sp < 3; sp++) {
            uint32_t span = (uint32_t)fx->desc.target_count[sp];
            uint32_t len = 10 + (uint32_t)(dlsfx_rand(&rng) % (span / 3));
            uint32_t start = (uint32_t)(dlsfx_rand(&rng) % (span - len));
            for (uint32_t t = start; t < start + len; t++)
                if (dlsfx_rand(&rng) % 6) dlsfx_add(fx, &rng, s, sp, t);
        }
}

static void scene_build(scene *sc, uint64_t seed)
{
    assert_int_equal(lbk_dls_build(&sc->fx.desc, NULL, &sc->bytes, &sc->size, NULL), LBK_OK);
    assert_int_equal(lbk_dls_open(sc->bytes, sc->size, NULL, &sc->view), LBK_OK);
    uint64_t rng = seed * 977 + 1;
    uint64_t nt = sc->fx.desc.target_count[0];
    sc->base_z = malloc(nt * 4), sc->out_z = calloc(nt, 4), sc->ref_z = calloc(nt, 4);
    sc->base_rgba = malloc(nt * 4), sc->out_rgba = calloc(nt, 4), sc->ref_rgba = calloc(nt, 4);
    for (uint64_t t = 0; t < nt; t++) {
        uint8_t b[8];
        dlsfx_random_texel(&rng, 2.0f, b);
        lbk_ahd_texel tx;
        lbk_ahd_texel_unpack(b, &tx);
        sc->base_z[t] = tx.irradiance_z;
        memcpy(sc->base_rgba + 4 * t, tx.rgba, 4);
    }
    for (int p = 0; p < 2; p++) {
        uint64_t np = sc->fx.desc.target_count[1 + p];
        sc->base_probe[p] = malloc(np * 28), sc->out_probe[p] = calloc(np, 28), sc->ref_probe[p] = calloc(np, 28);
        for (uint64_t t = 0; t < np; t++) dlsfx_random_probe(&rng, 2.0f, sc->base_probe[p] + 28 * t);
    }
}

static void scene_free(scene *sc)
{
    lbk_dls_close(sc->view);
    free(sc->bytes);
    free(sc->base_z), free(sc->out_z), free(sc->ref_z);
    free(sc->base_rgba), free(sc->out_rgba), free(sc->ref_rgba);
    for (int p = 0; p < 2; p++) free(sc->base_probe[p]), free(sc->out_probe[p]), free(sc->ref_probe[p]);
    dlsfx_free(&sc->fx);
}

/* the paged cases */
#define PAGE_W 40u
#define PAGE_H 25u
#define PAGES 3u /* 3 × 40 × 25 = the 3000 texels of random_sets */

/* The desc of a runtime over the scene's bases, shared by the byte and the linear cases: texels
 * as the four arrays (pages NULL) or as PAGES pages; with flags LBK_DLS_RUNTIME_LINEAR no byte
 * outputs (the caller adds the linear ones), else the scene's probe outputs, and in the array
 * form its texel outputs. */
static lbk_dls_runtime_desc scene_desc(scene *sc, uint32_t flags, const lbk_dls_page *pages)
{
    const bool linear = flags & LBK_DLS_RUNTIME_LINEAR;
    lbk_dls_runtime_desc d = {.size = sizeof d, .dls = sc->view, .base_glg = sc->base_probe[0], .base_llg = sc->base_probe[1],
                              .flags = flags};
    if (pages) {
        d.page_count = PAGES, d.pages = pages;
    } else {
        d.base_irradiance_z = sc->base_z, d.base_rgba = sc->base_rgba;
        if (!linear) d.out_irradiance_z = sc->out_z, d.out_rgba = sc->out_rgba;
    }
    if (!linear) d.out_glg = sc->out_probe[0], d.out_llg = sc->out_probe[1];
    return d;
}

static lbk_dls_runtime *runtime(scene *sc, const lbk_door_view *doors)
{
    lbk_dls_runtime_desc d = scene_desc(sc, 0, NULL);
    d.doors = doors;
    lbk_dls_runtime *r;
    assert_int_equal(lbk_dls_runtime_open(&d, &r), LBK_OK);
    return r;
}

/* The dense reference: every target, every set, straight from the builder's input. */
static void dense_sum(scene *sc, const float *w)
{
    const dlsfx *fx = &sc->fx;
    for (uint32_t sp = 0; sp < 3; sp++) {
        uint32_t **idx = calloc(fx->set_count, sizeof *idx);
        for (uint32_t s = 0; s < fx->set_count; s++) idx[s] = dlsfx_index(fx, s, sp);
        for (uint64_t t = 0; t < fx->desc.target_count[sp]; t++) {
            bool active = false; /* no weighted contribution: exactly the base bytes */
            for (uint32_t s = 0; s < fx->set_count; s++) active |= idx[s][t] && w[s] != 0.0f;
            if (!active) {
                if (sp == 0) {
                    sc->ref_z[t] = sc->base_z[t];
                    memcpy(sc->ref_rgba + 4 * t, sc->base_rgba + 4 * t, 4);
                } else {
                    memcpy(sc->ref_probe[sp - 1] + 28 * t, sc->base_probe[sp - 1] + 28 * t, 28);
                }
            } else if (sp == 0) {
                lbk_ahd_texel b = {sc->base_z[t], {0}};
                memcpy(b.rgba, sc->base_rgba + 4 * t, 4);
                lbk_ahd_linear acc;
                lbk_ahd_to_linear(&b, &acc);
                for (uint32_t s = 0; s < fx->set_count; s++) {
                    if (!idx[s][t] || w[s] == 0.0f) continue;
                    lbk_ahd_texel e;
                    lbk_ahd_texel_unpack((const uint8_t *)fx->sets[s].entries[0].payloads + 8ull * (idx[s][t] - 1), &e);
                    lbk_ahd_linear l;
                    lbk_ahd_to_linear(&e, &l);
                    lbk_ahd_linear_add_scaled(&acc, &l, w[s]);
                }
                lbk_ahd_texel o;
                lbk_ahd_from_linear(&acc, &o);
                sc->ref_z[t] = o.irradiance_z;
                memcpy(sc->ref_rgba + 4 * t, o.rgba, 4);
            } else {
                lbk_sh9_rgb acc;
                lbk_sh9_unpack(sc->base_probe[sp - 1] + 28 * t, &acc);
                for (uint32_t s = 0; s < fx->set_count; s++) {
                    if (!idx[s][t] || w[s] == 0.0f) continue;
                    lbk_sh9_rgb l;
                    lbk_sh9_unpack((const uint8_t *)fx->sets[s].entries[sp].payloads + 28ull * (idx[s][t] - 1), &l);
                    lbk_sh9_add_scaled(&acc, &l, w[s]);
                }
                lbk_sh9_pack(&acc, sc->ref_probe[sp - 1] + 28 * t);
            }
        }
        for (uint32_t s = 0; s < fx->set_count; s++) free(idx[s]);
        free(idx);
    }
}

/* Output vs reference: byte-identical targets counted; the others must agree within one
 * quantisation step of the codecs (R11G11B10F: 1/32 relative; snorm8/unorm8: 1/127 of the DC
 * or irradiance scale). Returns the number of targets outside that bound. */
static uint64_t compare(const scene *sc, uint64_t *identical, uint64_t *total)
{
    uint64_t bad = 0;
    *identical = *total = 0;
    static const float normals[4][3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, -0.6f, 0.8f}, {0.57735f, 0.57735f, 0.57735f}};
    for (uint64_t t = 0; t < sc->fx.desc.target_count[0]; t++) {
        (*total)++;
        if (sc->out_z[t] == sc->ref_z[t] && !memcmp(sc->out_rgba + 4 * t, sc->ref_rgba + 4 * t, 4)) {
            (*identical)++;
            continue;
        }
        lbk_ahd_texel a = {sc->out_z[t], {0}}, b = {sc->ref_z[t], {0}};
        memcpy(a.rgba, sc->out_rgba + 4 * t, 4);
        memcpy(b.rgba, sc->ref_rgba + 4 * t, 4);
        for (int n = 0; n < 4; n++) {
            float ea[3], eb[3];
            lbk_ahd_irradiance(&a, normals[n], ea);
            lbk_ahd_irradiance(&b, normals[n], eb);
            for (int c = 0; c < 3; c++)
                if (fabsf(ea[c] - eb[c]) > 0.04f * fabsf(eb[c]) + 1e-4f) { bad++; n = 4; break; }
        }
    }
    for (int p = 0; p < 2; p++)
        for (uint64_t t = 0; t < sc->fx.desc.target_count[1 + p]; t++) {
            (*total)++;
            if (!memcmp(sc->out_probe[p] + 28 * t, sc->ref_probe[p] + 28 * t, 28)) {
                (*identical)++;
                continue;
            }
            lbk_sh9_rgb a, b;
            lbk_sh9_unpack(sc->out_probe[p] + 28 * t, &a);
            lbk_sh9_unpack(sc->ref_probe[p] + 28 * t, &b);
            for (int c = 0; c < 3; c++) {
                float scale = fabsf(b.c[c][0]) * 2.3f; /* √5 · DC bounds every coefficient */
                bool off = false;
                for (int k = 0; k < 9; k++) off |= fabsf(a.c[c][k] - b.c[c][k]) > 0.02f * scale + 1e-5f;
                if (off) { bad++; break; }
            }
        }
    return bad;
}

static void random_weights(uint64_t *rng, float *w, uint32_t n)
{
    for (uint32_t s = 0; s < n; s++) {
        uint64_t r = dlsfx_rand(rng) % 4;
        w[s] = r == 0 ? 0.0f : r == 1 ? 1.0f : 1.5f * dlsfx_uniform(rng);
    }
}

static void test_apply_matches_dense_sum(void **state)
{
    (void)state;
    for (uint64_t seed = 1; seed <= 2; seed++) {
        scene sc;
        memset(&sc, 0, sizeof sc);
        random_sets(&sc.fx, seed, 22);
        scene_build(&sc, seed);
        lbk_dls_stats st;
        lbk_dls_stats_get(sc.view, &st);
        /* the random sets reach the dedicated, packed and both class (2) forms */
        assert_true(st.clusters_by_form[LBK_DLS_FORM_DEDICATED] > 0);
        assert_true(st.clusters_by_form[LBK_DLS_FORM_PACKED] > 0);
        assert_true(st.clusters_by_form[LBK_DLS_FORM_PREFIX2] > 0);
        assert_true(st.clusters_by_form[LBK_DLS_FORM_PREFIX3] > 0);
        lbk_dls_runtime *r = runtime(&sc, NULL);
        uint64_t rng = seed;
        float w[22];
        for (int round = 0; round < 3; round++) { /* later rounds are incremental applies */
            random_weights(&rng, w, 22);
            assert_int_equal(lbk_dls_apply(r, w, NULL, NULL), LBK_OK);
            dense_sum(&sc, w);
            uint64_t same, total;
            assert_int_equal(compare(&sc, &same, &total), 0);
            assert_int_equal(same, total);
        }
        lbk_dls_runtime_close(r);
        scene_free(&sc);
    }
}

static uint32_t clusters_touching(const lbk_dls_view *v, const bool *changed)
{
    uint32_t n = 0;
    for (uint32_t ci = 0; ci < lbk_dls_cluster_count(v); ci++) {
        lbk_dls_cluster_info info;
        lbk_dls_cluster_get(v, ci, &info);
        bool any = false;
        for (uint32_t j = 0; j < info.set_count; j++) {
            uint32_t s;
            lbk_dls_cluster_set_get(v, ci, j, &s);
            any |= changed[s];
        }
        n += any;
    }
    return n;
}

static void test_skipping_equals_full_apply(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 5, 22);
    scene_build(&sc, 5);
    lbk_dls_runtime *r = runtime(&sc, NULL);
    uint64_t rng = 42;
    float w1[22], w2[22];
    random_weights(&rng, w1, 22);
    lbk_dls_apply_stats st;
    assert_int_equal(lbk_dls_apply(r, w1, NULL, &st), LBK_OK);
    assert_int_equal(st.clusters_skipped, 0);
    uint64_t all = sc.fx.desc.target_count[0] + sc.fx.desc.target_count[1] + sc.fx.desc.target_count[2];
    assert_int_equal(st.targets_written, all); /* each target exactly once */
    memcpy(w2, w1, sizeof w1);
    bool changed[22] = {0};
    w2[3] = w1[3] + 0.5f, changed[3] = true;
    w2[17] = 0.0f, changed[17] = w1[17] != 0.0f;
    assert_int_equal(lbk_dls_apply(r, w2, NULL, &st), LBK_OK);
    uint32_t expect = clusters_touching(sc.view, changed);
    assert_true(expect > 0 && expect < lbk_dls_cluster_count(sc.view));
    assert_int_equal(st.clusters_applied + st.clusters_copied, expect);
    assert_int_equal(st.clusters_skipped, lbk_dls_cluster_count(sc.view) - expect);
    /* the same weights again: everything skipped */
    assert_int_equal(lbk_dls_apply(r, w2, NULL, &st), LBK_OK);
    assert_int_equal(st.clusters_skipped, lbk_dls_cluster_count(sc.view));
    assert_int_equal(st.targets_written, 0);

    uint32_t *inc_z = malloc(sc.fx.desc.target_count[0] * 4);
    memcpy(inc_z, sc.out_z, sc.fx.desc.target_count[0] * 4);
    uint8_t *inc_rgba = malloc(sc.fx.desc.target_count[0] * 4);
    memcpy(inc_rgba, sc.out_rgba, sc.fx.desc.target_count[0] * 4);
    uint8_t *inc_glg = malloc(sc.fx.desc.target_count[1] * 28);
    memcpy(inc_glg, sc.out_probe[0], sc.fx.desc.target_count[1] * 28);
    lbk_dls_runtime_close(r);
    memset(sc.out_z, 0xAB, sc.fx.desc.target_count[0] * 4);
    r = runtime(&sc, NULL);
    assert_int_equal(lbk_dls_apply(r, w2, NULL, NULL), LBK_OK);
    assert_memory_equal(inc_z, sc.out_z, sc.fx.desc.target_count[0] * 4);
    assert_memory_equal(inc_rgba, sc.out_rgba, sc.fx.desc.target_count[0] * 4);
    assert_memory_equal(inc_glg, sc.out_probe[0], sc.fx.desc.target_count[1] * 28);
    /* invalidate: the next apply rewrites every target */
    lbk_dls_runtime_invalidate(r);
    assert_int_equal(lbk_dls_apply(r, w2, NULL, &st), LBK_OK);
    assert_int_equal(st.targets_written, all);
    free(inc_z), free(inc_rgba), free(inc_glg);
    lbk_dls_runtime_close(r);
    scene_free(&sc);
}

static void test_zero_weights_give_exact_base(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 9, 22);
    scene_build(&sc, 9);
    lbk_dls_runtime *r = runtime(&sc, NULL);
    float w[22];
    uint64_t rng = 1;
    random_weights(&rng, w, 22);
    assert_int_equal(lbk_dls_apply(r, w, NULL, NULL), LBK_OK);
    lbk_dls_apply_stats st;
    assert_int_equal(lbk_dls_apply(r, NULL, NULL, &st), LBK_OK); /* NULL: all 0 */
    assert_int_equal(st.clusters_applied, 0);
    assert_memory_equal(sc.out_z, sc.base_z, sc.fx.desc.target_count[0] * 4);
    assert_memory_equal(sc.out_rgba, sc.base_rgba, sc.fx.desc.target_count[0] * 4);
    assert_memory_equal(sc.out_probe[0], sc.base_probe[0], sc.fx.desc.target_count[1] * 28);
    assert_memory_equal(sc.out_probe[1], sc.base_probe[1], sc.fx.desc.target_count[2] * 28);
    lbk_dls_runtime_close(r);
    scene_free(&sc);
}

/* A set with no entries: same clusters, payload and index bytes; applying it at weight 1 changes
 * nothing. */
static void test_empty_set_adds_no_data(void **state)
{
    (void)state;
    scene a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    random_sets(&a.fx, 13, 10);
    random_sets(&b.fx, 13, 11); /* same first 10 sets (same seed), plus set 10 ... */
    for (uint32_t sp = 0; sp < 3; sp++) b.fx.sets[10].entries[sp].count = 0; /* ... emptied */
    scene_build(&a, 13);
    scene_build(&b, 13);
    lbk_dls_stats sa, sb;
    lbk_dls_stats_get(a.view, &sa);
    lbk_dls_stats_get(b.view, &sb);
    assert_int_equal(sb.set_count, sa.set_count + 1);
    assert_int_equal(sb.cluster_count, sa.cluster_count);
    assert_int_equal(sb.payload_bytes, sa.payload_bytes);
    for (int sp = 0; sp < 3; sp++) assert_int_equal(sb.index_bytes[sp], sa.index_bytes[sp]);
    for (uint32_t ci = 0; ci < lbk_dls_cluster_count(b.view); ci++) {
        for (uint32_t j = 0;; j++) {
            uint32_t s;
            if (lbk_dls_cluster_set_get(b.view, ci, j, &s) != LBK_OK) break;
            assert_int_not_equal(s, 10);
        }
    }
    float wa[10], wb[11];
    uint64_t rng = 3;
    random_weights(&rng, wa, 10);
    memcpy(wb, wa, sizeof wa);
    wb[10] = 1.0f;
    lbk_dls_runtime *ra = runtime(&a, NULL), *rb = runtime(&b, NULL);
    assert_int_equal(lbk_dls_apply(ra, wa, NULL, NULL), LBK_OK);
    assert_int_equal(lbk_dls_apply(rb, wb, NULL, NULL), LBK_OK);
    assert_memory_equal(a.out_z, b.out_z, a.fx.desc.target_count[0] * 4);
    assert_memory_equal(a.out_probe[1], b.out_probe[1], a.fx.desc.target_count[2] * 28);
    lbk_dls_runtime_close(ra);
    lbk_dls_runtime_close(rb);
    scene_free(&a);
    scene_free(&b);
}

/* Sets: 0 lights, 1 door open, 2 door closed (bounce), 3 = {0, 1} combination, 4 lights. */
static void test_door_weights(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 21, 5);
    sc.fx.sets[1].kind = LBK_DLS_KIND_DOOR_OPEN;
    sc.fx.sets[2].kind = LBK_DLS_KIND_DOOR_CLOSED;
    uint32_t mem[2] = {1, 0};
    dlsfx_combination(&sc.fx, 3, 2, mem);
    scene_build(&sc, 21);

    lbk_door_desc door = {.name = "front_door",
                          .centre = {1, 2, 3},
                          .axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                          .half_extents = {0.5f, 1.0f, 0.05f},
                          .open_set = 1,
                          .closed_set = 2};
    uint32_t door0 = 0;
    lbk_door_state_desc state0 = {1, &door0, 3};
    lbk_door_build_desc dd = {.door_count = 1, .doors = &door, .state_count = 1, .states = &state0};
    void *db;
    size_t dsize;
    assert_int_equal(lbk_door_build(&dd, NULL, &db, &dsize), LBK_OK);
    lbk_door_view *dv;
    assert_int_equal(lbk_door_open(db, dsize, NULL, &dv), LBK_OK);
    assert_int_equal(lbk_door_check_dls(dv, sc.view), LBK_OK);
    lbk_door_info di;
    assert_int_equal(lbk_door_get(dv, 0, &di), LBK_OK);
    assert_int_equal(di.name_length, 10);
    assert_memory_equal(di.name, "front_door", 10);
    assert_true(di.centre[2] == 3.0f && di.half_extents[2] == 0.05f && di.axes[1][1] == 1.0f);
    assert_int_equal(di.open_set, 1);
    assert_int_equal(di.closed_set, 2);

    lbk_dls_runtime *r = runtime(&sc, dv);
    const float sw[5] = {0.5f, 9.0f, 9.0f, 9.0f, 0.75f}; /* door-driven entries are ignored */
    const float omega = 0.25f;
    float eff[5];
    assert_int_equal(lbk_dls_effective_weights(r, sw, &omega, eff), LBK_OK);
    assert_true(eff[0] == 0.5f && eff[1] == 0.25f && eff[2] == 0.75f && eff[3] == 0.125f && eff[4] == 0.75f);
    assert_int_equal(lbk_dls_effective_weights(r, NULL, NULL, eff), LBK_OK); /* closed: bounce at 1 */
    assert_true(eff[0] == 0.0f && eff[1] == 0.0f && eff[2] == 1.0f && eff[3] == 0.0f);
    assert_int_equal(lbk_dls_effective_weights(r, sw, &omega, eff), LBK_OK);
    assert_int_equal(lbk_dls_apply(r, sw, &omega, NULL), LBK_OK);
    dense_sum(&sc, eff);
    uint64_t same, total;
    assert_int_equal(compare(&sc, &same, &total), 0);
    assert_int_equal(same, total);
    const float bad_w = NAN;
    assert_int_equal(lbk_dls_apply(r, sw, &bad_w, NULL), LBK_ERR_INVALID_ARGUMENT);
    lbk_dls_runtime_close(r);

    /* A door whose open set is a plain light set disagrees with the DLS. */
    door.open_set = 0;
    void *db2;
    assert_int_equal(lbk_door_build(&dd, NULL, &db2, &dsize), LBK_OK);
    lbk_door_view *dv2;
    assert_int_equal(lbk_door_open(db2, dsize, NULL, &dv2), LBK_OK);
    assert_int_equal(lbk_door_check_dls(dv2, sc.view), LBK_ERR_CORRUPT);
    lbk_dls_runtime_desc rd = {.dls = sc.view, .doors = dv2};
    lbk_dls_runtime *r2;
    assert_int_equal(lbk_dls_runtime_open(&rd, &r2), LBK_ERR_CORRUPT);
    lbk_door_close(dv2);
    free(db2);
    lbk_door_close(dv);
    free(db);
    scene_free(&sc);
}

static void test_missing_buffers_rejected(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 2, 4);
    scene_build(&sc, 2);
    lbk_dls_runtime_desc d = {.dls = sc.view, .base_irradiance_z = sc.base_z, .base_rgba = sc.base_rgba,
                              .out_irradiance_z = sc.out_z, .out_rgba = sc.out_rgba};
    lbk_dls_runtime *r;
    assert_int_equal(lbk_dls_runtime_open(&d, &r), LBK_ERR_INVALID_ARGUMENT); /* probes have clusters */
    scene_free(&sc);
}

/* Multiplies stored texel/probe bytes by 2^e: the same physical lighting in a section of scale
 * 2^-e (spec §5.7, §12.2). */
static void rescale_texel(uint8_t b[8], int e)
{
    lbk_ahd_texel t;
    lbk_ahd_texel_unpack(b, &t);
    float v[3];
    lbk_r11g11b10f_unpack(t.irradiance_z, v);
    for (int c = 0; c < 3; c++) v[c] = ldexpf(v[c], e);
    t.irradiance_z = lbk_r11g11b10f_pack(v);
    lbk_ahd_texel_pack(&t, b);
}

static void rescale_probe(uint8_t b[28], int e)
{
    lbk_sh9_rgb sh;
    lbk_sh9_unpack(b, &sh);
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++) sh.c[c][k] = ldexpf(sh.c[c][k], e);
    lbk_sh9_pack(&sh, b);
}

/* DLS payloads live in the scale of their base section, so L = L_B + Σ w S on stored values is
 * the physical sum in stored units: the same lighting stored 2^8 larger (scale 2^-8) applies to
 * outputs that are exactly 2^8 × the unscaled apply's, texel for texel and probe for probe. */
static void test_apply_in_another_scale(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 3, 22);
    scene_build(&sc, 3);
    const uint64_t nt = sc.fx.desc.target_count[0], np[2] = {sc.fx.desc.target_count[1], sc.fx.desc.target_count[2]};
    uint64_t rng = 3;
    float w[22];
    random_weights(&rng, w, 22);
    lbk_dls_runtime *r = runtime(&sc, NULL);
    assert_int_equal(lbk_dls_apply(r, w, NULL, NULL), LBK_OK);
    lbk_dls_runtime_close(r);
    uint32_t *z1 = malloc(nt * 4);
    uint8_t *rgba1 = malloc(nt * 4), *p1[2] = {malloc(np[0] * 28), malloc(np[1] * 28)};
    memcpy(z1, sc.out_z, nt * 4), memcpy(rgba1, sc.out_rgba, nt * 4);
    for (int p = 0; p < 2; p++) memcpy(p1[p], sc.out_probe[p], np[p] * 28);
    /* the same lighting stored ×2^8: bases and every payload */
    for (uint64_t t = 0; t < nt; t++) {
        uint8_t b[8];
        lbk_ahd_texel tx = {sc.base_z[t], {0}};
        memcpy(tx.rgba, sc.base_rgba + 4 * t, 4);
        lbk_ahd_texel_pack(&tx, b);
        rescale_texel(b, 8);
        lbk_ahd_texel_unpack(b, &tx);
        sc.base_z[t] = tx.irradiance_z;
    }
    for (int p = 0; p < 2; p++)
        for (uint64_t t = 0; t < np[p]; t++) rescale_probe(sc.base_probe[p] + 28 * t, 8);
    for (uint32_t s = 0; s < sc.fx.set_count; s++)
        for (uint32_t sp = 0; sp < 3; sp++)
            for (uint64_t i = 0; i < sc.fx.sets[s].entries[sp].count; i++) {
                if (sp == 0) rescale_texel(sc.fx.payloads[s][sp] + 8 * i, 8);
                else rescale_probe(sc.fx.payloads[s][sp] + 28 * i, 8);
            }
    lbk_dls_close(sc.view);
    free(sc.bytes);
    assert_int_equal(lbk_dls_build(&sc.fx.desc, NULL, &sc.bytes, &sc.size, NULL), LBK_OK);
    assert_int_equal(lbk_dls_open(sc.bytes, sc.size, NULL, &sc.view), LBK_OK);
    r = runtime(&sc, NULL);
    assert_int_equal(lbk_dls_apply(r, w, NULL, NULL), LBK_OK);
    lbk_dls_runtime_close(r);
    uint64_t lit = 0;
    for (uint64_t t = 0; t < nt; t++) {
        float a[3], b[3];
        lbk_r11g11b10f_unpack(z1[t], a);
        lbk_r11g11b10f_unpack(sc.out_z[t], b);
        for (int c = 0; c < 3; c++) assert_true(ldexpf(a[c], 8) == b[c]);
        assert_memory_equal(rgba1 + 4 * t, sc.out_rgba + 4 * t, 4);
        lit += a[0] > 0;
    }
    assert_true(lit > nt / 2);
    for (int p = 0; p < 2; p++)
        for (uint64_t t = 0; t < np[p]; t++) {
            lbk_sh9_rgb a, b;
            lbk_sh9_unpack(p1[p] + 28 * t, &a);
            lbk_sh9_unpack(sc.out_probe[p] + 28 * t, &b);
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 9; k++) assert_true(ldexpf(a.c[c][k], 8) == b.c[c][k]);
        }
    free(z1), free(rgba1), free(p1[0]), free(p1[1]);
    scene_free(&sc);
}

/* ---- pages, paths, jobs, dirty regions ------------------------------------------------------ */

#define PAD 12u  /* bytes after each output row */

typedef struct paged {
    uint8_t *z, *rgba; /* PAGES × PAGE_H rows of 4·PAGE_W + PAD bytes */
    lbk_dls_page pages[PAGES];
} paged;

static void paged_init(paged *pg, scene *sc)
{
    const size_t pitch = 4 * PAGE_W + PAD, plane = pitch * PAGE_H;
    pg->z = malloc(PAGES * plane), pg->rgba = malloc(PAGES * plane);
    memset(pg->z, 0x5A, PAGES * plane), memset(pg->rgba, 0x5A, PAGES * plane);
    for (uint32_t p = 0; p < PAGES; p++)
        pg->pages[p] = (lbk_dls_page){.width = PAGE_W, .height = PAGE_H,
                                      .base_irradiance = (const uint8_t *)(sc->base_z + p * PAGE_W * PAGE_H),
                                      .base_rgba = sc->base_rgba + 4 * p * PAGE_W * PAGE_H,
                                      .out_irradiance = pg->z + p * plane, .out_rgba = pg->rgba + p * plane,
                                      .out_irradiance_pitch = pitch, .out_rgba_pitch = pitch};
}

/* The paged output equals the array output texel for texel; the row padding is untouched. */
static void paged_check(const paged *pg, const scene *sc)
{
    const size_t pitch = 4 * PAGE_W + PAD;
    for (uint32_t p = 0; p < PAGES; p++)
        for (uint32_t y = 0; y < PAGE_H; y++) {
            const size_t row = (size_t)p * PAGE_H * pitch + y * pitch, t = (size_t)p * PAGE_W * PAGE_H + y * PAGE_W;
            assert_memory_equal(pg->z + row, sc->out_z + t, 4 * PAGE_W);
            assert_memory_equal(pg->rgba + row, sc->out_rgba + 4 * t, 4 * PAGE_W);
            for (uint32_t b = 0; b < PAD; b++) assert_int_equal(pg->z[row + 4 * PAGE_W + b], 0x5A);
        }
}

static lbk_dls_runtime *paged_runtime(scene *sc, paged *pg, uint32_t flags, uint32_t job_targets)
{
    lbk_dls_runtime_desc d = scene_desc(sc, flags, pg->pages);
    d.job_targets = job_targets;
    lbk_dls_runtime *r;
    assert_int_equal(lbk_dls_runtime_open(&d, &r), LBK_OK);
    return r;
}

typedef struct job_pool {
    lbk_dls_runtime *r;
    uint32_t n;
    atomic_uint next;
} job_pool;

static void *job_worker(void *arg)
{
    job_pool *p = arg;
    for (uint32_t j; (j = atomic_fetch_add(&p->next, 1)) < p->n;) lbk_dls_apply_job(p->r, j);
    return NULL;
}

static void test_paths_pages_and_jobs_agree(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 7, 22);
    scene_build(&sc, 7);
    const uint64_t nt = sc.fx.desc.target_count[0], np[2] = {sc.fx.desc.target_count[1], sc.fx.desc.target_count[2]};
    assert_int_equal(nt, PAGES * PAGE_W * PAGE_H);
    uint64_t rng = 77;
    float w[2][22];
    random_weights(&rng, w[0], 22);
    memcpy(w[1], w[0], sizeof w[0]);
    w[1][4] += 0.25f, w[1][9] = 0.0f; /* the second apply is incremental */
    /* the reference: the array form, one job per default chunk */
    lbk_dls_runtime *ref = runtime(&sc, NULL);
    uint8_t *ref_probe[2][2];
    uint32_t *ref_z[2];
    uint8_t *ref_rgba[2];
    for (int a = 0; a < 2; a++) {
        assert_int_equal(lbk_dls_apply(ref, w[a], NULL, NULL), LBK_OK);
        ref_z[a] = malloc(nt * 4), ref_rgba[a] = malloc(nt * 4);
        memcpy(ref_z[a], sc.out_z, nt * 4), memcpy(ref_rgba[a], sc.out_rgba, nt * 4);
        for (int p = 0; p < 2; p++) ref_probe[a][p] = malloc(np[p] * 28), memcpy(ref_probe[a][p], sc.out_probe[p], np[p] * 28);
    }
    lbk_dls_runtime_close(ref);
    for (int variant = 0; variant < 4; variant++) {
        paged pg;
        paged_init(&pg, &sc);
        for (int p = 0; p < 2; p++) memset(sc.out_probe[p], 0, np[p] * 28);
        lbk_dls_runtime *r = paged_runtime(&sc, &pg, variant == 1 ? LBK_DLS_RUNTIME_SCALAR : 0, variant >= 2 ? 100 : 0);
        if (variant == 1) assert_string_equal(lbk_dls_runtime_path(r), "scalar");
        for (int a = 0; a < 2; a++) {
            uint32_t n;
            assert_int_equal(lbk_dls_apply_begin(r, w[a], NULL, &n), LBK_OK);
            uint32_t again;
            assert_int_equal(lbk_dls_apply_begin(r, w[a], NULL, &again), LBK_ERR_INVALID_ARGUMENT);
            if (variant == 2) { /* small jobs, last to first */
                assert_true(n > 30);
                for (uint32_t j = n; j-- > 0;) lbk_dls_apply_job(r, j);
            } else if (variant == 3) { /* two threads take jobs as they come */
                job_pool pool = {.r = r, .n = n};
                atomic_init(&pool.next, 0);
                pthread_t th[2];
                for (int i = 0; i < 2; i++) assert_int_equal(pthread_create(&th[i], NULL, job_worker, &pool), 0);
                for (int i = 0; i < 2; i++) pthread_join(th[i], NULL);
            } else {
                for (uint32_t j = 0; j < n; j++) lbk_dls_apply_job(r, j);
            }
            assert_int_equal(lbk_dls_apply_end(r, NULL), LBK_OK);
            memcpy(sc.out_z, ref_z[a], nt * 4), memcpy(sc.out_rgba, ref_rgba[a], nt * 4);
            paged_check(&pg, &sc);
            for (int p = 0; p < 2; p++) assert_memory_equal(sc.out_probe[p], ref_probe[a][p], np[p] * 28);
        }
        assert_int_equal(lbk_dls_apply_end(r, NULL), LBK_ERR_INVALID_ARGUMENT); /* no begin */
        lbk_dls_runtime_close(r);
        free(pg.z), free(pg.rgba);
    }
    for (int a = 0; a < 2; a++) {
        free(ref_z[a]), free(ref_rgba[a]);
        for (int p = 0; p < 2; p++) free(ref_probe[a][p]);
    }
    /* pages must cover the texels exactly and pitches hold a row */
    paged pg;
    paged_init(&pg, &sc);
    lbk_dls_runtime_desc d = scene_desc(&sc, 0, pg.pages);
    d.page_count = PAGES - 1;
    lbk_dls_runtime *bad;
    assert_int_equal(lbk_dls_runtime_open(&d, &bad), LBK_ERR_INVALID_ARGUMENT);
    d.page_count = PAGES;
    pg.pages[1].out_rgba_pitch = 4 * PAGE_W - 4;
    assert_int_equal(lbk_dls_runtime_open(&d, &bad), LBK_ERR_INVALID_ARGUMENT);
    free(pg.z), free(pg.rgba);
    scene_free(&sc);
}

/* Poison every output, apply, and check that each target the apply wrote (no longer poison:
 * the encoders never write an exponent-31 Ez or a −128 snorm byte) lies in a dirty range and,
 * for texels, a dirty rectangle of its page. */
static uint64_t check_dirty(const lbk_dls_runtime *r, const paged *pg, scene *sc, uint64_t *covered)
{
    const size_t pitch = 4 * PAGE_W + PAD;
    uint64_t written = 0;
    *covered = 0;
    for (uint32_t sp = 0; sp < 3; sp++)
        for (uint32_t i = 0; i < lbk_dls_dirty_range_count(r, sp); i++) {
            lbk_dls_range rg;
            assert_int_equal(lbk_dls_dirty_range_get(r, sp, i, &rg), LBK_OK);
            *covered += rg.count;
            if (i > 0) { /* sorted, disjoint, not touching */
                lbk_dls_range prev;
                lbk_dls_dirty_range_get(r, sp, i - 1, &prev);
                assert_true(prev.first + prev.count < rg.first);
            }
        }
    for (uint64_t t = 0; t < sc->fx.desc.target_count[0]; t++) {
        const uint32_t p = (uint32_t)(t / (PAGE_W * PAGE_H)), x = (uint32_t)(t % PAGE_W), y = (uint32_t)(t / PAGE_W % PAGE_H);
        uint32_t z;
        memcpy(&z, pg->z + (size_t)p * PAGE_H * pitch + y * pitch + 4 * x, 4);
        if (z == 0xFFFFFFFFu) continue;
        written++;
        bool in_range = false, in_rect = false;
        for (uint32_t i = 0; i < lbk_dls_dirty_range_count(r, 0); i++) {
            lbk_dls_range rg;
            lbk_dls_dirty_range_get(r, 0, i, &rg);
            in_range |= t >= rg.first && t < rg.first + rg.count;
        }
        for (uint32_t i = 0; i < lbk_dls_dirty_rect_count(r, p); i++) {
            lbk_dls_rect rc;
            lbk_dls_dirty_rect_get(r, p, i, &rc);
            in_rect |= x >= rc.x && x < rc.x + rc.width && y >= rc.y && y < rc.y + rc.height;
        }
        assert_true(in_range && in_rect);
    }
    for (int p = 0; p < 2; p++)
        for (uint64_t t = 0; t < sc->fx.desc.target_count[1 + p]; t++) {
            if (sc->out_probe[p][28 * t + 27] == 0x80) continue;
            written++;
            bool in_range = false;
            for (uint32_t i = 0; i < lbk_dls_dirty_range_count(r, 1 + p); i++) {
                lbk_dls_range rg;
                lbk_dls_dirty_range_get(r, 1 + p, i, &rg);
                in_range |= t >= rg.first && t < rg.first + rg.count;
            }
            assert_true(in_range);
        }
    return written;
}

static void poison(paged *pg, scene *sc)
{
    const size_t plane = (4 * PAGE_W + PAD) * PAGE_H * PAGES;
    memset(pg->z, 0xFF, plane);
    for (int p = 0; p < 2; p++) memset(sc->out_probe[p], 0x80, sc->fx.desc.target_count[1 + p] * 28);
}

static void test_dirty_regions_cover_writes(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 8, 22);
    scene_build(&sc, 8);
    paged pg;
    paged_init(&pg, &sc);
    lbk_dls_runtime *r = paged_runtime(&sc, &pg, 0, 64);
    const uint64_t all = sc.fx.desc.target_count[0] + sc.fx.desc.target_count[1] + sc.fx.desc.target_count[2];
    uint64_t rng = 8, covered;
    float w[22];
    random_weights(&rng, w, 22);
    /* the first apply writes everything: one range per space, one full rectangle per page */
    poison(&pg, &sc);
    assert_int_equal(lbk_dls_apply(r, w, NULL, NULL), LBK_OK);
    assert_int_equal(check_dirty(r, &pg, &sc, &covered), all);
    assert_int_equal(covered, all);
    for (uint32_t p = 0; p < PAGES; p++) {
        lbk_dls_rect rc;
        assert_int_equal(lbk_dls_dirty_rect_count(r, p), 1);
        assert_int_equal(lbk_dls_dirty_rect_get(r, p, 0, &rc), LBK_OK);
        assert_true(rc.x == 0 && rc.y == 0 && rc.width == PAGE_W && rc.height == PAGE_H);
    }
    assert_int_equal(lbk_dls_dirty_rect_get(r, 0, 1, &(lbk_dls_rect){0}), LBK_ERR_NOT_FOUND);
    /* one set changes: what is written is covered, and less than everything is */
    for (uint32_t s = 0; s < 22; s += 5) {
        w[s] = w[s] == 0.0f ? 0.5f : 0.0f;
        poison(&pg, &sc);
        lbk_dls_apply_stats st;
        assert_int_equal(lbk_dls_apply(r, w, NULL, &st), LBK_OK);
        const uint64_t written = check_dirty(r, &pg, &sc, &covered);
        assert_int_equal(written, st.targets_written);
        assert_true(written > 0 && covered >= written && covered < all);
    }
    /* the same weights again: nothing written, nothing dirty */
    assert_int_equal(lbk_dls_apply(r, w, NULL, NULL), LBK_OK);
    for (uint32_t sp = 0; sp < 3; sp++) assert_int_equal(lbk_dls_dirty_range_count(r, sp), 0);
    for (uint32_t p = 0; p < PAGES; p++) assert_int_equal(lbk_dls_dirty_rect_count(r, p), 0);
    lbk_dls_runtime_close(r);
    free(pg.z), free(pg.rgba);
    scene_free(&sc);
}

/* ---- the linear mode ------------------------------------------------------------------------ */

static void linear_rounds(scene *sc, const lbk_door_view *doors, uint64_t seed, uint32_t nsets, const float *door_w)
{
    dlslin d;
    assert_int_equal(dlslin_open(&d, sc->view, doors, sc->base_z, sc->base_rgba, sc->base_probe[0], sc->base_probe[1]), 0);
    uint64_t rng = seed;
    float w[32];
    dlslin_counts n;
    for (int round = 0; round < 4; round++) { /* later rounds are incremental; the last one all 0 */
        if (round < 3) random_weights(&rng, w, nsets);
        else memset(w, 0, sizeof w);
        if (round == 2) w[1] = w[2] = 0.0f; /* zero weights inside clusters that still apply */
        assert_int_equal(dlslin_apply_check(&d, w, door_w, &n), 0);
        assert_int_equal(n.mismatches, 0);
        const uint64_t all = sc->fx.desc.target_count[0] + sc->fx.desc.target_count[1] + sc->fx.desc.target_count[2];
        assert_int_equal(n.targets, all);
        if (round < 3) assert_true(n.weighted > 0 && n.weighted < all);
        else if (!doors) assert_int_equal(n.weighted, 0); /* with a door the closed set stays lit */
    }
    /* the re-encoded decoded base is not always the base bytes: the rule for unweighted targets
     * (decoded base, not "encode = bytes") is needed */
    assert_true(n.reencode_differs > 0);
    dlslin_close(&d);
}

/* Random sets of every form and door-driven sets: linear outputs are the byte mode's
 * accumulators bit for bit, on the SIMD and the scalar path. */
static void test_linear_equals_byte_accumulators(void **state)
{
    (void)state;
    for (uint64_t seed = 1; seed <= 2; seed++) {
        scene sc;
        memset(&sc, 0, sizeof sc);
        random_sets(&sc.fx, seed, 22);
        scene_build(&sc, seed);
        linear_rounds(&sc, NULL, seed * 11, 22, NULL);
        scene_free(&sc);
    }
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 21, 5);
    sc.fx.sets[1].kind = LBK_DLS_KIND_DOOR_OPEN;
    sc.fx.sets[2].kind = LBK_DLS_KIND_DOOR_CLOSED;
    uint32_t mem[2] = {1, 0};
    dlsfx_combination(&sc.fx, 3, 2, mem);
    scene_build(&sc, 21);
    lbk_door_desc door = {.name = "d", .axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, .half_extents = {1, 1, 1},
                          .open_set = 1, .closed_set = 2};
    lbk_door_build_desc dd = {.door_count = 1, .doors = &door};
    void *db;
    size_t dsize;
    assert_int_equal(lbk_door_build(&dd, NULL, &db, &dsize), LBK_OK);
    lbk_door_view *dv;
    assert_int_equal(lbk_door_open(db, dsize, NULL, &dv), LBK_OK);
    const float omega = 0.375f;
    linear_rounds(&sc, dv, 5, 5, &omega);
    linear_rounds(&sc, dv, 6, 5, NULL); /* closed: the bounce set at weight 1 */
    lbk_door_close(dv);
    free(db);
    scene_free(&sc);
}

/* Linear pages with padded pitches, jobs in reverse order and on two threads: the floats of the
 * array form; padding untouched; the dirty rectangles of the byte mode on the same pages. */
static void test_linear_pages_and_jobs(void **state)
{
    (void)state;
    scene sc;
    memset(&sc, 0, sizeof sc);
    random_sets(&sc.fx, 7, 22);
    scene_build(&sc, 7);
    const uint64_t nt = sc.fx.desc.target_count[0], np[2] = {sc.fx.desc.target_count[1], sc.fx.desc.target_count[2]};
    float *ref[3], *refp[2];
    for (int c = 0; c < 3; c++) ref[c] = calloc(nt, 16);
    for (int p = 0; p < 2; p++) refp[p] = calloc(np[p], 108);
    lbk_dls_runtime_desc ad = scene_desc(&sc, LBK_DLS_RUNTIME_LINEAR, NULL);
    for (int c = 0; c < 3; c++) ad.out_linear_texel[c] = ref[c];
    ad.out_linear_glg = refp[0], ad.out_linear_llg = refp[1];
    lbk_dls_runtime *ra;
    assert_int_equal(lbk_dls_runtime_open(&ad, &ra), LBK_OK);
    /* the prepared data: 12 floats per clustered texel and texel entry, 27 per probe ones */
    lbk_dls_stats st;
    lbk_dls_stats_get(sc.view, &st);
    const uint64_t floats = 12 * (st.touched[0] + st.entries[0]) + 27 * (st.touched[1] + st.entries[1] + st.touched[2] + st.entries[2]);
    const uint64_t arrays = 4 * (uint64_t)st.cluster_count * 32; /* ≤ 3 planes × (1 + 8 slots) per cluster */
    assert_true(lbk_dls_runtime_linear_bytes(ra) >= 4 * floats && lbk_dls_runtime_linear_bytes(ra) <= 4 * floats + 64 * arrays + 64);
    const size_t lpitch = 16 * PAGE_W + 32, lplane = lpitch * PAGE_H;
    float *lin = malloc(3 * PAGES * lplane);
    float *linp[2] = {calloc(np[0], 108), calloc(np[1], 108)};
    uint8_t *bz = malloc(PAGES * (4 * PAGE_W + PAD) * PAGE_H), *brgba = malloc(PAGES * (4 * PAGE_W + PAD) * PAGE_H);
    lbk_dls_page pages[PAGES];
    lbk_dls_linear_page lpages[PAGES];
    for (uint32_t p = 0; p < PAGES; p++) {
        pages[p] = (lbk_dls_page){.width = PAGE_W, .height = PAGE_H, .base_irradiance = (const uint8_t *)(sc.base_z + p * PAGE_W * PAGE_H),
                                  .base_rgba = sc.base_rgba + 4 * p * PAGE_W * PAGE_H};
        for (int c = 0; c < 3; c++) {
            lpages[p].out[c] = (float *)((uint8_t *)lin + (3 * p + c) * lplane);
            lpages[p].out_pitch[c] = lpitch;
        }
    }
    memset(lin, 0x5A, 3 * PAGES * lplane);
    lbk_dls_runtime_desc pd = scene_desc(&sc, LBK_DLS_RUNTIME_LINEAR, pages);
    pd.job_targets = 50, pd.linear_pages = lpages, pd.out_linear_glg = linp[0], pd.out_linear_llg = linp[1];
    lbk_dls_runtime *rp;
    assert_int_equal(lbk_dls_runtime_open(&pd, &rp), LBK_OK);
    /* the byte mode on the same pages, for its rectangles */
    paged pg;
    paged_init(&pg, &sc);
    lbk_dls_runtime *rb = paged_runtime(&sc, &pg, 0, 50);
    uint64_t rng = 17;
    float w[22];
    for (int a = 0; a < 3; a++) {
        random_weights(&rng, w, 22);
        assert_int_equal(lbk_dls_apply(ra, w, NULL, NULL), LBK_OK);
        assert_int_equal(lbk_dls_apply(rb, w, NULL, NULL), LBK_OK);
        uint32_t n;
        assert_int_equal(lbk_dls_apply_begin(rp, w, NULL, &n), LBK_OK);
        if (a == 1) {
            job_pool pool = {.r = rp, .n = n};
            atomic_init(&pool.next, 0);
            pthread_t th[2];
            for (int i = 0; i < 2; i++) assert_int_equal(pthread_create(&th[i], NULL, job_worker, &pool), 0);
            for (int i = 0; i < 2; i++) pthread_join(th[i], NULL);
        } else {
            for (uint32_t j = n; j-- > 0;) lbk_dls_apply_job(rp, j);
        }
        assert_int_equal(lbk_dls_apply_end(rp, NULL), LBK_OK);
        for (uint32_t p = 0; p < PAGES; p++)
            for (int c = 0; c < 3; c++)
                for (uint32_t y = 0; y < PAGE_H; y++) {
                    const uint8_t *row = (const uint8_t *)lpages[p].out[c] + y * lpitch;
                    assert_memory_equal(row, ref[c] + 4 * ((size_t)p * PAGE_W * PAGE_H + y * PAGE_W), 16 * PAGE_W);
                    for (uint32_t b = 16 * PAGE_W; b < lpitch; b++) assert_int_equal(row[b], 0x5A);
                }
        for (int p = 0; p < 2; p++) assert_memory_equal(linp[p], refp[p], np[p] * 108);
        for (uint32_t p = 0; p < PAGES; p++) {
            assert_int_equal(lbk_dls_dirty_rect_count(rp, p), lbk_dls_dirty_rect_count(rb, p));
            for (uint32_t i = 0; i < lbk_dls_dirty_rect_count(rp, p); i++) {
                lbk_dls_rect x, y;
                lbk_dls_dirty_rect_get(rp, p, i, &x), lbk_dls_dirty_rect_get(rb, p, i, &y);
                assert_memory_equal(&x, &y, sizeof x);
            }
        }
    }
    /* linear outputs are required; pitches hold a row of float4 */
    lbk_dls_runtime *bad;
    pd.linear_pages = NULL;
    assert_int_equal(lbk_dls_runtime_open(&pd, &bad), LBK_ERR_INVALID_ARGUMENT);
    pd.linear_pages = lpages;
    lpages[1].out_pitch[2] = 16 * PAGE_W - 4;
    assert_int_equal(lbk_dls_runtime_open(&pd, &bad), LBK_ERR_INVALID_ARGUMENT);
    lpages[1].out_pitch[2] = lpitch;
    pd.out_linear_llg = NULL;
    assert_int_equal(lbk_dls_runtime_open(&pd, &bad), LBK_ERR_INVALID_ARGUMENT);
    ad.out_linear_texel[1] = NULL;
    assert_int_equal(lbk_dls_runtime_open(&ad, &bad), LBK_ERR_INVALID_ARGUMENT);
    lbk_dls_runtime_close(ra), lbk_dls_runtime_close(rp), lbk_dls_runtime_close(rb);
    for (int c = 0; c < 3; c++) free(ref[c]);
    for (int p = 0; p < 2; p++) free(refp[p]), free(linp[p]);
    free(lin), free(bz), free(brgba), free(pg.z), free(pg.rgba);
    scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_apply_matches_dense_sum),
        cmocka_unit_test(test_skipping_equals_full_apply),
        cmocka_unit_test(test_zero_weights_give_exact_base),
        cmocka_unit_test(test_empty_set_adds_no_data),
        cmocka_unit_test(test_door_weights),
        cmocka_unit_test(test_missing_buffers_rejected),
        cmocka_unit_test(test_apply_in_another_scale),
        cmocka_unit_test(test_paths_pages_and_jobs_agree),
        cmocka_unit_test(test_dirty_regions_cover_writes),
        cmocka_unit_test(test_linear_equals_byte_accumulators),
        cmocka_unit_test(test_linear_pages_and_jobs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
