/* --llg-connected through the pipeline (lbk_bake_desc.llg_connected; bake/probes/PROBES.md
 * "Connected objects"): two 3 m bars meeting end to end get half the LLG spacing, a third bar
 * 3 m away keeps it, and the flag off gives the grids of before. And each LLG prop's estimate
 * (lbk_bake_report.llg_estimates) on the same bars. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lbk/bake.h"

/* box [mn, mx] as 12 outward triangles appended at pos/idx */
static void box(float *pos, uint32_t *idx, uint32_t base, const float mn[3], const float mx[3])
{
    for (int i = 0; i < 8; i++) {
        pos[3 * i] = i & 1 ? mx[0] : mn[0];
        pos[3 * i + 1] = i & 2 ? mx[1] : mn[1];
        pos[3 * i + 2] = i & 4 ? mx[2] : mn[2];
    }
    static const uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (int k = 0; k < 6; k++) {
        const uint32_t t[6] = {f[k][0], f[k][1], f[k][2], f[k][0], f[k][2], f[k][3]};
        for (int j = 0; j < 6; j++) idx[6 * k + j] = base + t[j];
    }
}

/* The floor and the first `bars` bars, baked under a white sky; free with lbk_bake_output_free. */
static lbk_bake_output *bake_bars(int connected, int bars)
{
    float pos[4 * 24];
    uint32_t idx[4 * 36];
    /* a floor under everything (not lit by the bake), then three bars 0.2 m thick at y = 1 */
    const float fmn[3] = {-8, -0.1f, -2}, fmx[3] = {8, 0, 2};
    box(pos, idx, 0, fmn, fmx);
    const float x0[3] = {-3, 0, 6}, x1[3] = {0, 3, 9}; /* bars 0 and 1 meet at x = 0; bar 2 apart */
    for (int k = 0; k < 3; k++) {
        const float mn[3] = {x0[k], 0.9f, -0.1f}, mx[3] = {x1[k], 1.1f, 0.1f};
        box(pos + 24 * (k + 1), idx + 36 * (k + 1), (uint32_t)(8 * (k + 1)), mn, mx);
    }
    lbk_bake_material mat = {"grey", {0.5f, 0.5f, 0.5f}, {0, 0, 0}, 0};
    lbk_bake_object obj[4] = {{"floor", 0, 12, 0, LBK_BAKE_LIGHTING_NONE, 0, NULL, NULL},
                              {"bar0", 12, 12, 0, LBK_BAKE_LIGHTING_LLG, 0, NULL, NULL},
                              {"bar1", 24, 12, 0, LBK_BAKE_LIGHTING_LLG, 0, NULL, NULL},
                              {"bar2", 36, 12, 0, LBK_BAKE_LIGHTING_LLG, 0, NULL, NULL}};
    lbk_bake_scene sc = {0};
    sc.name = "bars";
    sc.vertex_count = 32;
    sc.positions = pos;
    sc.triangle_count = 12 + 12 * (uint32_t)bars;
    sc.indices = idx;
    sc.material_count = 1;
    sc.materials = &mat;
    sc.object_count = 1 + (uint32_t)bars;
    sc.objects = obj;
    lbk_bake_desc d = {0};
    d.size = sizeof d;
    d.seed = 1;
    d.threads = 2;
    d.max_samples = 32;
    d.sky_override = 1;
    d.sky[0] = d.sky[1] = d.sky[2] = 1;
    d.no_glg = 1;
    d.llg_connected = connected;
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&sc, &d, &out), LBK_OK);
    return out;
}

static uint64_t llg_probes(int connected)
{
    lbk_bake_output *out = bake_bars(connected, 3);
    const lbk_bake_report *r = lbk_bake_output_report(out);
    assert_int_equal(r->counts.llgs, 3);
    const uint64_t n = r->counts.llg_probes;
    lbk_bake_output_free(out);
    return n;
}

/* A 3 × 0.2 × 0.2 m bar: lattice half extents 1.5 + 0.15 margin and 0.1 + 0.15 (PROBES.md);
 * at 1.5 m ceil(3.3/1.5) + 1 = 4 probes along it, 3 across (the baker's minimum): 36; at the
 * connected 0.75 m ceil(3.3/0.75) + 1 = 6 along it: 54. */
static void connected_bars(void **state)
{
    (void)state;
    const uint64_t off = llg_probes(0), on = llg_probes(1);
    print_message("LLG probes: %llu without, %llu with --llg-connected\n", (unsigned long long)off,
                  (unsigned long long)on);
    assert_int_equal(off, 3 * 36);
    assert_int_equal(on, 54 + 54 + 36);
}

/* Each LLG prop's estimate is the LLG class estimate over its own grid: with one prop it is the
 * class's (errors.llg, the same two terms over the same receivers), and each is √(noise² +
 * fit²) of its own terms, in scene order. */
static void llg_estimates(void **state)
{
    (void)state;
    lbk_bake_output *out = bake_bars(0, 1);
    const lbk_bake_report *r = lbk_bake_output_report(out);
    assert_true(r->size >= offsetof(lbk_bake_report, llg_estimate_count) + sizeof r->llg_estimate_count);
    assert_int_equal(r->llg_estimate_count, 1);
    const lbk_bake_llg_estimate *e = &r->llg_estimates[0];
    print_message("one bar: %.4f (noise %.4f, fit %.4f, %u targets), class %.4f\n", e->rel_rmse, e->noise, e->fit,
                  e->targets, r->errors.llg);
    assert_string_equal(e->name, "bar0");
    assert_int_equal(e->object, 1);
    assert_true(e->targets > 0 && e->noise > 0 && e->rel_rmse > 0);
    assert_true(fabs(e->rel_rmse - r->errors.llg) <= 1e-6 * r->errors.llg);
    lbk_bake_output_free(out);

    out = bake_bars(0, 3);
    r = lbk_bake_output_report(out);
    assert_int_equal(r->llg_estimate_count, 3);
    double lo = INFINITY, hi = 0;
    for (size_t i = 0; i < 3; i++) {
        e = &r->llg_estimates[i];
        char want[8];
        snprintf(want, sizeof want, "bar%zu", i);
        assert_string_equal(e->name, want);
        assert_int_equal(e->object, i + 1);
        assert_true(fabs(e->rel_rmse - hypot(e->noise, e->fit)) <= 1e-12 + 1e-9 * e->rel_rmse);
        assert_true(e->targets > 0 && isfinite(e->rel_rmse) && e->rel_rmse > 0);
        lo = fmin(lo, e->noise), hi = fmax(hi, e->noise);
    }
    print_message("three bars: noise %.4f .. %.4f\n", lo, hi);
    char *json = NULL;
    size_t n = 0;
    assert_int_equal(lbk_bake_report_json(r, "bars.lbk", NULL, &json, &n), LBK_OK);
    const char *llg = strstr(json, "\"llg_objects\"");
    assert_non_null(llg);
    assert_non_null(strstr(llg, "\"bar2\""));
    lbk_free(NULL, json);
    lbk_bake_output_free(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(connected_bars), cmocka_unit_test(llg_estimates)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
