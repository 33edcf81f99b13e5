/* LLG probes fitted to their object's vertices (bake/probes/llg_fit.h): the fitted probes give
 * the runtime's apply formula (liblbk's lbk_llg_vertex_irradiance on the built section, not the
 * fit's own model) the targets' irradiance; the fit is linear (light sets rely on it); vertices
 * inside other geometry are no targets. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/probes/llg_fit.h"
#include "bake/probes/llg_place.h"
#include "scene/tracer.h"
#include "lbk/llg.h"
#include "tests/support/probe_scenes.h"

typedef struct fixture {
    bk_scene s;
    bk_tracer *tr;
    bk_llg l;
    bk_llg_fit_plan plan;
    uint32_t sphere;
} fixture;

/* A unit sphere (the LLG object) at the origin and a second one at (0, 0, 1.9) that swallows
 * its top pole. */
static void setup(fixture *f)
{
    memset(f, 0, sizeof *f);
    psc_init(&f->s);
    f->sphere = psc_object(&f->s, "prop", BK_LIGHTING_LLG);
    const float c0[3] = {0, 0, 0}, c1[3] = {0, 0, 1.9f};
    psc_sphere(&f->s, c0, 1.0f, 12, 16);
    psc_object(&f->s, "next", BK_LIGHTING_LIGHTMAP);
    psc_sphere(&f->s, c1, 1.0f, 12, 16);
    psc_update_bounds(&f->s);
    assert_int_equal(bk_tracer_create(&f->s, 1, &f->tr), LBK_OK);
    bk_llg_options o = {0};
    o.spacing = 4; /* a 2 × 2 × 2 lattice, as a 1 m prop gets at the default 1.5 m spacing */
    assert_int_equal(bk_llg_place(&f->s, f->sphere, &o, 1, &f->l), LBK_OK);
    assert_int_equal(bk_llg_fit_plan_build(&f->l, 1, &f->s, f->tr, 0, &f->plan), LBK_OK);
}

static void teardown(fixture *f)
{
    bk_llg_fit_plan_free(&f->plan);
    bk_llg_free(&f->l);
    bk_tracer_destroy(f->tr);
    psc_free(&f->s);
}

static uint64_t lcg = 12345;
static double uniform(void)
{
    lcg = lcg * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(lcg >> 11) * 0x1p-53;
}

/* Positive radiance fields: a large DC and bounded higher bands (irradiance stays > 0). */
static void random_probes(lbk_sh9_rgb *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) p[i].c[c][k] = (float)(k == 0 ? 1.0 + uniform() : 0.3 * (uniform() - 0.5));
}

/* The grid as a section, evaluated by liblbk at each target: what a runtime shades with. */
static void runtime_at_targets(const fixture *f, const lbk_sh9_rgb *probes, float *e)
{
    lbk_llg_vertex *rec = malloc(f->l.vertex_count * sizeof *rec);
    assert_non_null(rec);
    bk_llg_vertex_records(&f->l, rec);
    lbk_llg_grid_desc g;
    memset(&g, 0, sizeof g);
    memcpy(g.centre, f->l.centre, sizeof g.centre);
    memcpy(g.axes, f->l.axes, sizeof g.axes);
    memcpy(g.half_extents, f->l.half_extents, sizeof g.half_extents);
    memcpy(g.dims, f->l.dims, sizeof g.dims);
    g.probes = probes;
    g.vertices = rec;
    g.vertex_count = (uint32_t)f->l.vertex_count;
    lbk_llg_build_desc d = LBK_LLG_BUILD_DESC_INIT;
    d.grids = &g;
    d.grid_count = 1;
    void *data = NULL;
    size_t size = 0;
    assert_int_equal(lbk_llg_build(&d, NULL, &data, &size), LBK_OK);
    lbk_llg_view v;
    assert_int_equal(lbk_llg_open(data, size, &v), LBK_OK);
    for (size_t t = 0; t < f->plan.count; t++) {
        const float *p = f->s.positions + 3 * (size_t)f->l.vertices[f->plan.vertex[t]];
        assert_int_equal(lbk_llg_vertex_irradiance(&v, 0, f->plan.vertex[t], p, e + 3 * t), LBK_OK);
    }
    lbk_free(NULL, data);
    free(rec);
}

static double rel_rms(const float *a, const float *b, size_t n)
{
    double s = 0, m = 0;
    for (size_t i = 0; i < n; i++) s += (a[i] - b[i]) * (double)(a[i] - b[i]), m += b[i];
    return sqrt(s / (double)n) / (m / (double)n);
}

static void test_fit_reproduces_the_runtime(void **state)
{
    (void)state;
    fixture f;
    setup(&f);
    const size_t np = bk_llg_probe_count(&f.l), nt = f.plan.count;
    assert_int_equal(np, 8);
    assert_true(nt > 150);
    lbk_sh9_rgb *truth = calloc(np, sizeof *truth), *probes = calloc(np, sizeof *probes);
    float *e = malloc(3 * nt * sizeof *e), *got = malloc(3 * nt * sizeof *got);
    assert_true(truth && probes && e && got);
    random_probes(truth, np);
    runtime_at_targets(&f, truth, e);
    /* the traced probes: the truth with 30 % errors in every coefficient */
    for (size_t i = 0; i < np; i++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) probes[i].c[c][k] = truth[i].c[c][k] * (float)(0.7 + 0.6 * uniform());
    runtime_at_targets(&f, probes, got);
    const double before = rel_rms(got, e, 3 * nt);
    bk_llg_fit_stats st = {0};
    assert_int_equal(bk_llg_fit_run(&f.plan, &f.l, &f.s, e, probes, 0, &st, NULL), LBK_OK);
    runtime_at_targets(&f, probes, got);
    const double after = rel_rms(got, e, 3 * nt);
    /* the targets are exactly representable: what remains is the regularisation's pull towards
     * the traced probes and the section's 8-bit quantisation of the bands (~0.4 % of DC) */
    assert_true(before > 0.05);
    assert_true(after < 0.01);
    assert_int_equal(st.targets, nt);
    assert_true(st.fitted_sq < 0.01 * st.traced_sq);
    free(truth), free(probes), free(e), free(got);
    teardown(&f);
}

static void test_fit_is_linear(void **state)
{
    (void)state;
    fixture f;
    setup(&f);
    const size_t np = bk_llg_probe_count(&f.l), nt = f.plan.count;
    lbk_sh9_rgb *a = calloc(np, sizeof *a), *b = calloc(np, sizeof *b), *ab = calloc(np, sizeof *ab);
    float *ea = malloc(3 * nt * sizeof *ea), *eb = malloc(3 * nt * sizeof *eb), *eab = malloc(3 * nt * sizeof *eab);
    assert_true(a && b && ab && ea && eb && eab);
    random_probes(a, np);
    random_probes(b, np);
    for (size_t t = 0; t < 3 * nt; t++) {
        ea[t] = (float)(4 * uniform()), eb[t] = (float)(4 * uniform());
        eab[t] = ea[t] + eb[t];
    }
    for (size_t i = 0; i < np; i++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) ab[i].c[c][k] = a[i].c[c][k] + b[i].c[c][k];
    assert_int_equal(bk_llg_fit_run(&f.plan, &f.l, &f.s, ea, a, 0, NULL, NULL), LBK_OK);
    assert_int_equal(bk_llg_fit_run(&f.plan, &f.l, &f.s, eb, b, 0, NULL, NULL), LBK_OK);
    assert_int_equal(bk_llg_fit_run(&f.plan, &f.l, &f.s, eab, ab, 0, NULL, NULL), LBK_OK);
    double worst = 0, scale = 0;
    for (size_t i = 0; i < np; i++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) {
                worst = fmax(worst, fabs(a[i].c[c][k] + b[i].c[c][k] - ab[i].c[c][k]));
                scale = fmax(scale, fabs(ab[i].c[c][k]));
            }
    assert_true(scale > 0.1);
    assert_true(worst < 1e-5 * scale); /* float rounding of the stored coefficients only */
    free(a), free(b), free(ab), free(ea), free(eb), free(eab);
    teardown(&f);
}

static void test_vertices_inside_other_geometry_are_no_targets(void **state)
{
    (void)state;
    fixture f;
    setup(&f);
    size_t inside = 0;
    for (size_t j = 0; j < f.l.vertex_count; j++) {
        const float *p = f.s.positions + 3 * (size_t)f.l.vertices[j];
        inside += p[0] * p[0] + p[1] * p[1] + (p[2] - 1.9f) * (p[2] - 1.9f) < 0.95f;
    }
    assert_true(inside >= 16); /* the pole ring and more: the test can fail */
    for (size_t t = 0; t < f.plan.count; t++) {
        const float *p = f.s.positions + 3 * (size_t)f.l.vertices[f.plan.vertex[t]];
        assert_true(p[0] * p[0] + p[1] * p[1] + (p[2] - 1.9f) * (p[2] - 1.9f) > 0.95f);
    }
    assert_true(f.plan.count + inside <= f.l.vertex_count);
    assert_true(f.plan.count >= f.l.vertex_count - inside - 40); /* only the vertices near the rim go */
    teardown(&f);
}

/* A probe inside the object (the centre of a 3 × 3 × 3 lattice in a box whose only vertices are
 * its corners) is traced black; the targets weight it by 0.09³, so without the smoothness term a
 * renderer sampling the grid inside the box (per pixel, between vertices) would see it
 * (test_render's furnace did: 12.5 %). In a uniform field it must come out like its neighbours. */
static void test_inside_probe_takes_its_neighbours(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    uint32_t obj = psc_object(&s, "prop", BK_LIGHTING_LLG);
    const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    psc_box(&s, lo, hi, 1, 0);
    psc_update_bounds(&s);
    bk_tracer *tr = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &tr), LBK_OK);
    bk_llg_options o = {0};
    o.spacing = 4;
    o.min_dim = 3;
    bk_llg l;
    assert_int_equal(bk_llg_place(&s, obj, &o, 1, &l), LBK_OK);
    bk_llg_fit_plan plan;
    assert_int_equal(bk_llg_fit_plan_build(&l, 1, &s, tr, 0, &plan), LBK_OK);
    assert_int_equal(bk_llg_probe_count(&l), 27);
    for (size_t i = 0; i < 27; i++) assert_int_equal(plan.inside[i], i == 13); /* the centre only */
    /* uniform radiance L = 1: DC = 1 / Y00, irradiance π at every target */
    lbk_sh9_rgb probes[27];
    memset(probes, 0, sizeof probes);
    for (size_t i = 0; i < 27; i++)
        for (int ch = 0; ch < 3; ch++) probes[i].c[ch][0] = i == 13 ? 0.0f : 1.0f / LBK_SH_Y00;
    float *e = malloc(3 * plan.count * sizeof *e);
    assert_non_null(e);
    for (size_t t = 0; t < 3 * plan.count; t++) e[t] = (float)M_PI;
    assert_int_equal(bk_llg_fit_run(&plan, &l, &s, e, probes, 0, NULL, NULL), LBK_OK);
    for (int ch = 0; ch < 3; ch++) assert_float_equal(probes[13].c[ch][0] * LBK_SH_Y00, 1.0, 0.02);
    free(e);
    bk_llg_fit_plan_free(&plan);
    bk_llg_free(&l);
    bk_tracer_destroy(tr);
    psc_free(&s);
}

/* The baker's lattices have at least 3 probes per axis (a 2 × 2 × 2 lattice has no probe inside
 * the object to fit); the option's default stays 2. */
static void test_min_dim(void **state)
{
    (void)state;
    bk_scene s;
    psc_init(&s);
    uint32_t obj = psc_object(&s, "small", BK_LIGHTING_LLG);
    const float c[3] = {0, 0, 0};
    psc_sphere(&s, c, 0.5f, 8, 12);
    psc_update_bounds(&s);
    bk_llg_options o = {0};
    bk_llg l;
    assert_int_equal(bk_llg_place(&s, obj, &o, 1, &l), LBK_OK);
    for (int a = 0; a < 3; a++) assert_int_equal(l.dims[a], 2);
    bk_llg_free(&l);
    o.min_dim = 3;
    o.max_probes = 8; /* raised to 27 by the minimum */
    assert_int_equal(bk_llg_place(&s, obj, &o, 1, &l), LBK_OK);
    for (int a = 0; a < 3; a++) assert_int_equal(l.dims[a], 3);
    bk_llg_free(&l);
    psc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fit_reproduces_the_runtime),
        cmocka_unit_test(test_fit_is_linear),
        cmocka_unit_test(test_vertices_inside_other_geometry_are_no_targets),
        cmocka_unit_test(test_min_dim),
        cmocka_unit_test(test_inside_probe_takes_its_neighbours),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
