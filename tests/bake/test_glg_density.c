/* GLG density by playable space and lighting (bake/probes/PROBES.md §Density by playable space
 * and lighting): probes counted where a light boundary or a playable box is against a uniformly
 * lit or unplayable region of the same size, the uniform field's placement against the coarse
 * grid's exact count, and the same positions at 1 and 2 threads with the transport's coarse pass. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/probes/glg_coarse.h"
#include "bake/probes/glg_place.h"
#include "support/transport_scenes.h"

/* A closed 12 × 4 × 4 m room (inward faces), so every probe is in free space. */
static void build_room(bk_scene *s)
{
    tsc_init(s);
    uint32_t wall = tsc_material(s, 0.6f, 0.6f, 0.6f, 0, 0, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {12, 4, 4};
    tsc_box(s, mn, mx, 2, 1, wall);
    tsc_update_bounds(s);
}

/* Analytic lighting: 1 below x = 6.2, 0.1 above (a light boundary; 6.2 is off the lattice so no
 * point sits on it); flat when user is non-NULL. */
static lbk_result step_light(void *user, const float *p, size_t n, float *out)
{
    for (size_t i = 0; i < n; i++) {
        for (int d = 0; d < 6; d++) out[7 * i + d] = user ? 0.5f : p[3 * i] < 6.2f ? 1.0f : 0.1f;
        out[7 * i + 6] = 0;   /* exact */
    }
    return LBK_OK;
}

static size_t count_in_x(const bk_glg_probes *g, float x0, float x1)
{
    size_t n = 0;
    for (size_t i = 0; i < g->count; i++) n += g->positions[3 * i] >= x0 && g->positions[3 * i] < x1;
    return n;
}

static void test_lighting_boundary(void **state)
{
    (void)state;
    bk_scene s;
    build_room(&s);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &t), LBK_OK);
    bk_glg_options o = {0};
    o.refine_levels = -1;         /* the lighting rule alone */
    o.lighting = step_light;
    o.lighting_threshold = 0.1f;
    bk_glg_probes g;
    assert_int_equal(bk_glg_place(&s, t, &o, 1, &g), LBK_OK);
    /* top grid 2 m: 6 × 2 × 2 cells; the lattice (1 m) sees the step between x = 5.5 and 6.5,
     * so the top cells at x 4..6 and 6..8 are refined, the ones at x 0..2 and 10..12 are not */
    assert_float_equal(g.spacing, 2.0f, 0.0f);
    assert_int_equal(g.coarse_points, 12 * 4 * 4);
    size_t near = count_in_x(&g, 4, 8), far = count_in_x(&g, 0, 4) + count_in_x(&g, 8, 12);
    /* near: 8 top cells split to depth 2 (64 probes each) = 512; far: 16 cells of one probe */
    assert_int_equal(near, 8 * 64);
    assert_int_equal(far, 16);
    assert_int_equal(g.cells_by_depth[0], 16);
    assert_int_equal(g.cells_by_depth[2], 8);
    bk_glg_probes_free(&g);

    /* uniformly lit: nothing to refine, the 2 m grid is all there is */
    o.lighting_user = &o;
    assert_int_equal(bk_glg_place(&s, t, &o, 1, &g), LBK_OK);
    assert_int_equal(g.count, 6 * 2 * 2);
    assert_int_equal(g.cells_by_depth[0], 24);
    bk_glg_probes_free(&g);

    /* lighting_levels 1: the boundary cells stop at 1 m */
    o.lighting_user = NULL;
    o.lighting_levels = 1;
    assert_int_equal(bk_glg_place(&s, t, &o, 1, &g), LBK_OK);
    assert_int_equal(count_in_x(&g, 4, 8), 8 * 8);
    bk_glg_probes_free(&g);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static void test_playable_boxes(void **state)
{
    (void)state;
    bk_scene s;
    build_room(&s);
    bk_box box = {{0.5f, 0.5f, 0.5f}, {3.5f, 3.5f, 3.5f}};   /* inside the top cells x < 4 */
    s.playable = malloc(sizeof box);
    assert_non_null(s.playable);
    s.playable[0] = box;
    s.playable_count = 1;
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &t), LBK_OK);
    bk_glg_options o = {0};
    bk_glg_probes g, plain;
    assert_int_equal(bk_glg_place(&s, t, &o, 1, &g), LBK_OK);
    /* top grid 2 m (6 × 2 × 2 cells); the 8 top cells of x 0..4 overlap the box: split to 1 m,
     * and the 1 m octants that touch a wall to 0.5 m. The room is two top cells high and wide, so
     * every top cell touches a wall in y and in z: of its octants, the one away from both (and,
     * at x 0..2, from the end wall x = 0) stays whole: 7 × 8 + 1 = 57 probes per cell at x 0..2,
     * 6 × 8 + 2 = 50 at x 2..4. Outside: 2 m, split once where a wall is (every cell): 8 each.
     * Same-size regions: playable x 0..4 against x 8..12. */
    assert_float_equal(g.spacing, 2.0f, 0.0f);
    size_t in = count_in_x(&g, 0, 4), out = count_in_x(&g, 8, 12);
    assert_int_equal(out, 8 * 8);
    assert_int_equal(in, 4 * 57 + 4 * 50);
    assert_int_equal(g.cells_by_depth[1], 8);
    assert_int_equal(g.cells_by_depth[0], 16);
    bk_glg_probes_free(&g);
    /* ignoring the boxes gives the placement without them, byte for byte */
    o.playable_levels = -1;
    assert_int_equal(bk_glg_place(&s, t, &o, 1, &g), LBK_OK);
    free(s.playable); s.playable = NULL; s.playable_count = 0;
    bk_glg_options d = {0};
    assert_int_equal(bk_glg_place(&s, t, &d, 1, &plain), LBK_OK);
    assert_int_equal(g.count, plain.count);
    assert_memory_equal(g.positions, plain.positions, 3 * plain.count * sizeof(float));
    assert_float_equal(plain.spacing, 1.0f, 0.0f);
    bk_glg_probes_free(&g);
    bk_glg_probes_free(&plain);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

/* Places the GLG with the transport's coarse pass (32 samples, a small cache) at `threads`. */
static void place_coarse(const bk_scene *s, int threads, bk_glg_probes *g)
{
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(s, threads, &t), LBK_OK);
    bk_glg_coarse cp = {0};
    cp.scene = s; cp.tracer = t; cp.seed = 3; cp.threads = threads; cp.samples = 32; cp.max_cells = 512;
    bk_glg_options o = {0};
    o.lighting = bk_glg_coarse_lighting;
    o.lighting_user = &cp;
    o.lighting_threshold = 0.4f;
    assert_int_equal(bk_glg_place(s, t, &o, threads, g), LBK_OK);
    assert_true(cp.rays > 0);
    bk_tracer_destroy(t);
}

/* The transport's coarse pass: a furnace (every wall emits 1 nit, albedo 0.5: radiance 2
 * everywhere, so the lighting is exactly uniform and only noise varies) gets no refinement; the
 * same room lit by one lamp (inverse-square falloff, a bright spot on the ceiling) does; and the
 * positions do not depend on the thread count. */
static void test_coarse_pass_threads(void **state)
{
    (void)state;
    bk_scene furnace;
    tsc_init(&furnace);
    uint32_t glow = tsc_material(&furnace, 0.5f, 0.5f, 0.5f, 1, 1, 1);
    float mn[3] = {0, 0, 0}, mx[3] = {12, 4, 4};
    tsc_box(&furnace, mn, mx, 2, 1, glow);
    tsc_update_bounds(&furnace);
    bk_glg_probes f;
    place_coarse(&furnace, 1, &f);
    /* 2 m top cells, the near-geometry rule's one split each (every top cell touches a wall) */
    assert_int_equal(f.cells_by_depth[0], 24);
    assert_int_equal(f.count, 24 * 8);
    bk_glg_probes_free(&f);
    tsc_free(&furnace);

    bk_scene s;
    build_room(&s);
    float lp[3] = {2, 2, 3.5f};
    tsc_point_light(&s, lp, 50, 50, 50, 0);
    tsc_update_bounds(&s);
    bk_glg_probes g[2];
    place_coarse(&s, 1, &g[0]);
    place_coarse(&s, 2, &g[1]);
    assert_int_equal(g[0].count, g[1].count);
    assert_memory_equal(g[0].positions, g[1].positions, 3 * g[0].count * sizeof(float));
    assert_memory_equal(g[0].cells_by_depth, g[1].cells_by_depth, sizeof g[0].cells_by_depth);
    assert_true(g[0].count > 24 * 8);
    assert_true(g[0].cells_by_depth[0] < 24);
    bk_glg_probes_free(&g[0]);
    bk_glg_probes_free(&g[1]);
    tsc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lighting_boundary),
        cmocka_unit_test(test_playable_boxes),
        cmocka_unit_test(test_coarse_pass_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
