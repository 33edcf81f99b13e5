/* A texel's punctual light is the average over its footprint, also across a hard shadow edge.
 *
 * A black floor (3 × 3 m, 8 texels per metre) under a sun straight down, half of it shadowed by a
 * black plate 0.5 m above whose edge runs diagonally (x + 0.37 z = 0.11): no indirect light, so a
 * texel's exact irradiance is the sun's times the lit share of its footprint, computed here from
 * the footprint itself (64 × 64 points of the texel's square, each lit when it lies past the
 * edge). The baker evaluates punctual light at its texels' quarter centres and, where those
 * disagree, over a 4 × 4 grid (bake/transport/gather.c). A K × K midpoint rule across a straight
 * edge errs in the ~1.3 K cells the edge cuts, each by up to 1/K² of the texel, about uniformly:
 * RMS ≈ √(1.3 K)/(K² √12), 0.116 at K = 2 and 0.041 at K = 4 of the sun's irradiance. Asserted:
 * RMS over the edge texels under 0.07 (measured 0.03; the four quarter centres alone: 0.12), and
 * the texels wholly lit or wholly in shadow within 0.5 % of 1 and 0. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/atlas.h"
#include "bake/layout/texels.h"
#include "bake/transport/transport.h"
#include "support/transport_scenes.h"

#define DENSITY 8.0f
#define SUN 1000.0f
#define EDGE_Z 0.37
#define EDGE_C 0.11
#define GRID 64

static int lit(const double p[3]) { return p[0] + EDGE_Z * p[2] >= EDGE_C; }

static void build(bk_scene *s)
{
    tsc_init(s);
    const uint32_t black = tsc_material(s, 0, 0, 0, 0, 0, 0);
    const float f0[3] = {-1.5f, 0, -1.5f}, f1[3] = {-1.5f, 0, 1.5f}, f2[3] = {1.5f, 0, 1.5f}, f3[3] = {1.5f, 0, -1.5f};
    tsc_quad(s, f0, f1, f2, f3, 1, black); /* faces up */
    /* the plate over x + 0.37 z < 0.11, facing down */
    const float y = 0.5f, e = 2.5f;
    const float q0[3] = {(float)(EDGE_C + EDGE_Z * e), y, -e}, q1[3] = {-3, y, -e}, q2[3] = {-3, y, e},
                q3[3] = {(float)(EDGE_C - EDGE_Z * e), y, e};
    tsc_quad(s, q0, q1, q2, q3, 1, black);
    const float down[3] = {0, -1, 0};
    tsc_dir_light(s, down, SUN);
    tsc_update_bounds(s);
}

/* The lit share of texel x's footprint (-1 when its square holds too few footprint points). */
static double exact_share(const bk_scene *s, const bk_texels *tx, const bk_texel *x)
{
    int covered = 0, lit_n = 0;
    for (int j = 0; j < GRID; j++)
        for (int i = 0; i < GRID; i++) {
            double p[3], n[3];
            if (!bk_footprint_point(s, tx->footprint + x->footprint_first, x->footprint_count, (i + 0.5) / GRID,
                                    (j + 0.5) / GRID, p, n))
                continue;
            covered++;
            lit_n += lit(p);
        }
    return covered >= GRID * GRID / 4 ? (double)lit_n / covered : -1;
}

static void test_shadow_edge_footprint_mean(void **state)
{
    (void)state;
    bk_scene s;
    build(&s);
    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.default_density = DENSITY;
    bk_atlas atlas;
    bk_texels tx;
    bk_tracer *tracer = NULL;
    assert_int_equal(bk_atlas_build(&s, NULL, &ao, &atlas), LBK_OK);
    assert_int_equal(bk_tracer_create(&s, 0, &tracer), LBK_OK);
    assert_int_equal(bk_texels_build(&s, &atlas, &tx), LBK_OK);
    bk_receiver *recv = calloc(tx.count, sizeof *recv);
    float *irr = calloc(3 * tx.count, sizeof *irr);
    lbk_sh9_rgb *rad = calloc(tx.count, sizeof *rad);
    assert_non_null(recv);
    assert_non_null(irr);
    assert_non_null(rad);
    for (size_t i = 0; i < tx.count; i++) bk_receiver_from_texel(&tx.receivers[i], &recv[i]);
    bk_transport_options o = tsc_fixed_passes(1, 3);
    o.footprint = tx.footprint;
    o.footprint_count = tx.footprint_count;
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = rad;
    out.irradiance = irr;
    bk_transport_stats st;
    assert_int_equal(bk_transport_run(&s, tracer, recv, tx.count, &o, &out, &st), LBK_OK);

    double se2 = 0, worst = 0, flat = 0;
    int edge = 0, whole = 0;
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *x = &tx.receivers[i];
        if (x->normal[1] < 0.9f || fabsf(x->position[1]) > 1e-3f || !x->footprint_count) continue; /* the floor */
        const double share = exact_share(&s, &tx, x);
        if (share < 0) continue;
        const double got = irr[3 * i + 1] / SUN, d = got - share;
        if (share > 0.02 && share < 0.98) {
            se2 += d * d;
            worst = fmax(worst, fabs(d));
            edge++;
        } else if (share == 0 || share == 1) {
            flat = fmax(flat, fabs(d));
            whole++;
        }
    }
    const double rms = edge ? sqrt(se2 / edge) : 0;
    print_message("shadow edge: %d edge texels, error RMS %.4f, worst %.4f of the sun; %d whole texels, worst %.5f\n",
                  edge, rms, worst, whole, flat);
    assert_true(edge >= 20);
    assert_true(whole >= 300);
    assert_true(rms < 0.07);
    assert_true(flat < 0.005);
    free(rad);
    free(irr);
    free(recv);
    bk_texels_free(&tx);
    bk_tracer_destroy(tracer);
    bk_atlas_free(&atlas);
    bk_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shadow_edge_footprint_mean),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
