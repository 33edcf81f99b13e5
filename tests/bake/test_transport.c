/* Transport against analytic answers: punctual lights over a plane (falloff, range window,
 * spot cone, directional), a uniform sky, a closed box (no leaks), light sets, extremes
 * (intensity 1e-6…1e6, scale 1 mm…10 km, 1e5 m from the origin, degenerate triangles,
 * duplicate vertices), determinism over thread counts, the error estimate, stop rules. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/transport/transport.h"
#include "support/mem_checkpoint.h"
#include "support/transport_scenes.h"

#define Y00 0.282094791773878

static void plane(bk_scene *s, float half, float z, int n, uint32_t mat)
{
    float p0[3] = {-half, -half, z}, p1[3] = {half, -half, z}, p2[3] = {half, half, z}, p3[3] = {-half, half, z};
    tsc_quad(s, p0, p1, p2, p3, n, mat);
}

static void texel(bk_receiver *r, float x, float y, float z)
{
    memset(r, 0, sizeof *r);
    r->position[0] = x; r->position[1] = y; r->position[2] = z;
    r->normal[2] = 1;
}

typedef struct run_out {
    lbk_sh9_rgb *rad, *dir;
    float *irr;
    bk_transport_stats st;
} run_out;

static run_out run(const bk_scene *s, const bk_receiver *r, size_t n, const bk_transport_options *o)
{
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(s, 0, &t), LBK_OK);
    run_out ro;
    ro.rad = calloc(n ? n : 1, sizeof *ro.rad);
    ro.dir = calloc(n ? n : 1, sizeof *ro.dir);
    ro.irr = calloc(3 * (n ? n : 1), sizeof *ro.irr);
    bk_transport_output out = {ro.rad, ro.dir, ro.irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    assert_int_equal(bk_transport_run(s, t, r, n, o, &out, &ro.st), LBK_OK);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            assert_true(isfinite(ro.irr[3 * i + c]));
            for (int k = 0; k < 9; k++) assert_true(isfinite(ro.rad[i].c[c][k]) && isfinite(ro.dir[i].c[c][k]));
        }
    assert_int_equal(ro.st.nonfinite, 0);
    bk_tracer_destroy(t);
    return ro;
}

static void run_free(run_out *ro) { free(ro->rad); free(ro->dir); free(ro->irr); }

static double rel(double a, double b) { return fabs(a - b) / fmax(fabs(b), 1e-300); }

/* ---- punctual lights ------------------------------------------------------------------------- */

static void test_point_light_plane(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    plane(&s, 20, 0, 4, tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0));
    float lp[3] = {0, 0, 2};
    tsc_point_light(&s, lp, 100, 50, 25, 0);
    float lp2[3] = {10, 0, 1};
    tsc_point_light(&s, lp2, 7, 7, 7, 2.5f); /* range window 2.5 m */
    const float xs[6] = {0.05f, 0.5f, 1, 2, 5, 9.3f};
    bk_receiver r[6];
    for (int i = 0; i < 6; i++) texel(&r[i], xs[i], 0, 0);
    bk_transport_options o = tsc_fixed_passes(1, 3);
    run_out ro = run(&s, r, 6, &o);
    for (int i = 0; i < 6; i++) {
        double d = sqrt(xs[i] * xs[i] + 4.0), cs = 2 / d;
        double d2 = sqrt((10 - xs[i]) * (10 - xs[i]) + 1.0), cs2 = 1 / d2;
        double w2 = fmax(fmin(1 - pow(d2 / 2.5, 4), 1), 0);
        double e[3] = {100 * cs / (d * d), 50 * cs / (d * d), 25 * cs / (d * d)};
        for (int c = 0; c < 3; c++) {
            double expect = e[c] + 7 * cs2 / (d2 * d2) * w2;
            assert_true(rel(ro.irr[3 * i + c], expect) < 1e-5);
        }
        /* a flat plane under no sky sees nothing: radiance is all direct */
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) assert_true(ro.rad[i].c[c][k] == ro.dir[i].c[c][k]);
        /* SH of a delta light: L00 = (I/d²)·Y00 (+ the ranged light) */
        double l00 = 100 / (d * d) * Y00 + 7 / (d2 * d2) * w2 * Y00;
        assert_true(rel(ro.rad[i].c[0][0], l00) < 1e-5);
    }
    assert_true(ro.irr[3 * 5] > 0); /* 9.3 m: inside the 2.5 m range of the second light */
    run_free(&ro);
    tsc_free(&s);
}

static void test_spot_cone(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    plane(&s, 20, 0, 2, tsc_material(&s, 0, 0, 0, 0, 0, 0));
    float lp[3] = {0, 0, 3}, ld[3] = {0, 0, -1};
    const double inner = 0.2, outer = 0.4, I = 500;
    tsc_spot_light(&s, lp, ld, (float)I, (float)inner, (float)outer);
    const double th[5] = {0, 0.1, 0.3, 0.39, 0.5};
    bk_receiver r[5];
    for (int i = 0; i < 5; i++) texel(&r[i], (float)(3 * tan(th[i])), 0, 0);
    bk_transport_options o = tsc_fixed_passes(1, 3);
    run_out ro = run(&s, r, 5, &o);
    for (int i = 0; i < 5; i++) {
        double x = r[i].position[0], d = sqrt(x * x + 9), cs = 3 / d;
        double t = (cs - cos(outer)) / (cos(inner) - cos(outer));
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double expect = I * t * t * cs / (d * d);
        if (expect == 0) assert_true(ro.irr[3 * i] == 0);
        else assert_true(rel(ro.irr[3 * i], expect) < 1e-4);
    }
    assert_true(ro.irr[3 * 4] == 0);                 /* outside the cone */
    assert_true(ro.irr[3 * 2] < ro.irr[3 * 1] * 0.9); /* in the smooth falloff */
    run_free(&ro);
    tsc_free(&s);
}

static void test_directional_and_shadow(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    uint32_t black = tsc_material(&s, 0, 0, 0, 0, 0, 0);
    plane(&s, 20, 0, 2, black);
    /* a 1 m blocker at height 1 above (0, 0), one-sided, facing up */
    float b0[3] = {-0.5f, -0.5f, 1}, b1[3] = {0.5f, -0.5f, 1}, b2[3] = {0.5f, 0.5f, 1}, b3[3] = {-0.5f, 0.5f, 1};
    tsc_quad(&s, b0, b1, b2, b3, 1, black);
    float d[3] = {0.6f, 0, -0.8f};
    tsc_dir_light(&s, d, 1000);
    bk_receiver r[3];
    texel(&r[0], 5, 5, 0);      /* lit */
    texel(&r[1], 0.75f, 0, 0); /* in the blocker's shadow (light travels +x: shifted by +0.75) */
    texel(&r[2], -0.6f, 0, 0); /* beside it: lit */
    bk_transport_options o = tsc_fixed_passes(1, 3);
    run_out ro = run(&s, r, 3, &o);
    assert_true(rel(ro.irr[0], 800) < 1e-5);
    assert_true(ro.irr[3] == 0);
    assert_true(rel(ro.irr[6], 800) < 1e-5);
    /* the SH of the direct light points at the light: L1 ∝ −direction */
    assert_true(ro.rad[0].c[0][3] < 0 && ro.rad[0].c[0][2] > 0);
    run_free(&ro);
    tsc_free(&s);
}

/* ---- sky ----------------------------------------------------------------------------------- */

static double lattice_bound(int passes)
{
    /* TRANSPORT.md §Furnace: a texel's uniform-radiance estimate errs by at most 1/S per pass */
    double num = 0, w = 0;
    for (int p = 0; p < passes; p++) { num += 1.0 / 16; w += ldexp(1, p); }
    return num / w + 1e-5;
}

static void test_sky_open_plane(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    plane(&s, 50, 0, 4, tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0));
    s.sky[0] = 0.5f; s.sky[1] = 1.0f; s.sky[2] = 1.5f;
    enum { N = 64 };
    bk_receiver r[N];
    for (int i = 0; i < N; i++) texel(&r[i], (float)(i % 8) - 4, (float)(i / 8) - 4, 0);
    bk_transport_options o = tsc_fixed_passes(5, 3);
    run_out ro = run(&s, r, N, &o);
    double num = 0, den = 0, maxe = 0;
    for (int i = 0; i < N; i++) {
        for (int c = 0; c < 3; c++) {
            double expect = M_PI * s.sky[c];
            maxe = fmax(maxe, rel(ro.irr[3 * i + c], expect));
        }
        double lum = 0.2126 * ro.irr[3 * i] + 0.7152 * ro.irr[3 * i + 1] + 0.0722 * ro.irr[3 * i + 2];
        double lt = M_PI * (0.2126 * 0.5 + 0.7152 + 0.0722 * 1.5);
        num += (lum - lt) * (lum - lt);
        den += lt * lt;
        /* the sky is direct light */
        for (int c = 0; c < 3; c++) assert_true(rel(ro.dir[i].c[c][0], ro.rad[i].c[c][0]) < 1e-6);
    }
    double true_rmse = sqrt(num / den);
    print_message("sky plane: max err %.5f (bound %.5f), true rmse %.5f, est %.5f\n", maxe, lattice_bound(5), true_rmse,
                  ro.st.est_rel_rmse);
    assert_true(maxe <= lattice_bound(5));
    assert_true(ro.st.est_rel_rmse <= 2 * true_rmse && ro.st.est_rel_rmse >= 0.5 * true_rmse);
    run_free(&ro);
    tsc_free(&s);
}

/* ---- leaks ----------------------------------------------------------------------------------- */

static void closed_box_case(double scale, const double offset[3])
{
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 0.8f, 0.8f, 0.8f, 0, 0, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {2, 3, 2.5f};
    tsc_box(&s, mn, mx, 3, 1, m); /* double sided: the outside is lit too */
    s.sky[0] = s.sky[1] = s.sky[2] = 10;
    float lp[3] = {1, 1.5f, 4};
    tsc_point_light(&s, lp, 1e4f, 1e4f, 1e4f, 0);
    float dd[3] = {0.3f, 0.2f, -0.93f};
    tsc_dir_light(&s, dd, 1e5f);
    tsc_transform(&s, scale, offset);
    enum { N = 40 };
    bk_receiver r[N];
    memset(r, 0, sizeof r);
    for (int i = 0; i < N; i++) {
        double a = (i * 0.618033988749895) - floor(i * 0.618033988749895);
        double b = (i * 0.754877666246693) - floor(i * 0.754877666246693);
        double p[3];
        if (i % 2) { p[0] = 0.01 + 1.98 * a; p[1] = 0.01 + 2.98 * b; p[2] = 0; r[i].normal[2] = 1; }
        else if (i % 4 == 0) { p[0] = 2; p[1] = 0.01 + 2.98 * a; p[2] = 0.01 + 2.48 * b; r[i].normal[0] = -1; }
        else { p[0] = 0.2 + 1.6 * a; p[1] = 0.2 + 2.6 * b; p[2] = 1.25; }
        for (int k = 0; k < 3; k++) r[i].position[k] = (float)(p[k] * scale + offset[k]);
    }
    bk_transport_options o = tsc_fixed_passes(2, 3);
    run_out ro = run(&s, r, N, &o);
    for (int i = 0; i < N; i++)
        for (int c = 0; c < 3; c++) {
            assert_true(ro.irr[3 * i + c] == 0);
            for (int k = 0; k < 9; k++) assert_true(ro.rad[i].c[c][k] == 0);
        }
    run_free(&ro);
    tsc_free(&s);
}

static void test_closed_box_no_leak(void **state)
{
    (void)state;
    const double zero[3] = {0, 0, 0}, far[3] = {1e5, -1e5, 3e4};
    closed_box_case(1, zero);
    closed_box_case(1e-3, zero);
    closed_box_case(1e4, zero);
    closed_box_case(4, far);
}

/* ---- light sets -------------------------------------------------------------------------------- */

static void test_light_sets(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    plane(&s, 20, 0, 2, tsc_material(&s, 0, 0, 0, 0, 0, 0));
    float p1[3] = {0, 0, 1}, p2[3] = {0, 0, 2};
    tsc_point_light(&s, p1, 10, 10, 10, 0);
    tsc_point_light(&s, p2, 40, 40, 40, 0);
    strcpy(s.lights[1].light_set, "A");
    s.sky[0] = s.sky[1] = s.sky[2] = 1;
    /* an emissive panel of set A facing down at height 3 over x = 5 */
    tsc_object(&s, "panel", "A", "");
    uint32_t em = tsc_material(&s, 0, 0, 0, 2, 2, 2);
    s.materials[em].double_sided = 0;
    float e0[3] = {4, -1, 3}, e1[3] = {4, 1, 3}, e2[3] = {6, 1, 3}, e3[3] = {6, -1, 3};
    tsc_quad(&s, e0, e1, e2, e3, 1, em);
    bk_receiver r[2];
    texel(&r[0], 0, 0, 0);
    texel(&r[1], 5, 0, 0);
    bk_transport_options o = tsc_fixed_passes(2, 3);
    run_out base = run(&s, r, 2, &o);
    o.light_set = "A";
    run_out a = run(&s, r, 2, &o);
    o.light_set = "B"; /* no such set: nothing */
    run_out b = run(&s, r, 2, &o);
    /* base: light 1 + the sky minus what the panel hides (black to the base); the panel's
     * form factor from (0,0) is ~cos²·A/(pi·d²) = 0.0099 (point approximation, 0.5 % of it) */
    double f_panel = (9.0 / 34) * 4 / (M_PI * 34);
    assert_true(base.irr[0] > 10 && base.irr[0] < 10 + M_PI + 1e-3);
    assert_true(rel(base.irr[0] - 10, M_PI * (1 - f_panel)) <= lattice_bound(2) + 0.005);
    /* set A at (0,0): light 2 only (40/4) plus a little of the panel; no sky */
    assert_true(a.irr[0] >= 10 - 1e-4 && a.irr[0] < 10.2);
    /* set A under the panel: the 2x2 panel at height 3 seen from below: E = Le·F·pi with
     * the unit-square-at-distance form factor; 40/29 from the light */
    double panel_e = 0;
    {
        /* exact irradiance from a rectangle parallel to the receiver plane, corner formula */
        double h = 3;
        double aa = 1 / h, bb = 1 / h;
        double f = 4 * (1 / (2 * M_PI)) * (aa / sqrt(1 + aa * aa) * atan(bb / sqrt(1 + aa * aa)) +
                                           bb / sqrt(1 + bb * bb) * atan(aa / sqrt(1 + bb * bb)));
        panel_e = 2 * M_PI * f;
    }
    double light2 = 40 * 2 / pow(sqrt(25 + 4.0), 3);
    print_message("set A under panel: %.5f expect %.5f (est. error %.4f)\n", a.irr[3], panel_e + light2, a.st.est_rel_rmse);
    /* the panel is light-sampled (next-event estimation with MIS): 0.5 %, was 5 % gathering alone */
    assert_int_equal(a.st.nee, 1);
    assert_int_equal(base.st.nee, 0); /* the panel is not the base's */
    assert_true(rel(a.irr[3], panel_e + light2) < 0.005);
    for (int i = 0; i < 6; i++) assert_true(b.irr[i] == 0);
    run_free(&base);
    run_free(&a);
    run_free(&b);
    tsc_free(&s);
}

/* ---- extremes -------------------------------------------------------------------------------- */

/* A room with a point light, bounces, a ceiling emitter and receivers: the workhorse below. */
static void room(bk_scene *s, double intensity, double scale, const double offset[3])
{
    tsc_init(s);
    uint32_t wall = tsc_material(s, 0.7f, 0.6f, 0.5f, 0, 0, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {4, 3, 2.5f};
    tsc_box(s, mn, mx, 2, 1, wall);
    uint32_t em = tsc_material(s, 0, 0, 0, (float)(2 * intensity), (float)(2 * intensity), (float)(2 * intensity));
    s->materials[em].double_sided = 0;
    float e0[3] = {1.5f, 1, 2.4f}, e1[3] = {1.5f, 2, 2.4f}, e2[3] = {2.5f, 2, 2.4f}, e3[3] = {2.5f, 1, 2.4f};
    tsc_quad(s, e0, e1, e2, e3, 1, em);
    float lp[3] = {1, 1, 1.5f};
    tsc_point_light(s, lp, (float)(30 * intensity), (float)(20 * intensity), (float)(10 * intensity), 0);
    /* punctual E ∝ I/d²: scaling the scene by k needs I·k² for the same irradiance */
    for (size_t i = 0; i < s->light_count; i++)
        for (int c = 0; c < 3; c++) s->lights[i].color[c] = (float)(s->lights[i].color[c] * scale * scale);
    tsc_transform(s, scale, offset);
}

#define ROOM_N 24
static void room_receivers(bk_receiver *r, double scale, const double offset[3])
{
    memset(r, 0, sizeof *r * ROOM_N);
    for (int i = 0; i < ROOM_N; i++) {
        double a = (i * 0.618033988749895) - floor(i * 0.618033988749895);
        double b = (i * 0.754877666246693) - floor(i * 0.754877666246693);
        double p[3] = {0.1 + 3.8 * a, 0.1 + 2.8 * b, i % 2 ? 0 : 1.2};
        if (i % 2) r[i].normal[2] = 1;
        for (int k = 0; k < 3; k++) r[i].position[k] = (float)(p[k] * scale + offset[k]);
    }
}

static run_out room_run(double intensity, double scale, const double offset[3], int threads, uint64_t seed)
{
    bk_scene s;
    room(&s, intensity, scale, offset);
    bk_receiver r[ROOM_N];
    room_receivers(r, scale, offset);
    bk_transport_options o = tsc_fixed_passes(2, 3);
    o.threads = threads;
    o.seed = seed;
    run_out ro = run(&s, r, ROOM_N, &o);
    tsc_free(&s);
    return ro;
}

static const double ORIGIN[3] = {0, 0, 0};

static void test_intensity_extremes(void **state)
{
    (void)state;
    run_out one = room_run(1, 1, ORIGIN, 2, 5);
    const double scales[2] = {1e-6, 1e6};
    for (int j = 0; j < 2; j++) {
        run_out x = room_run(scales[j], 1, ORIGIN, 2, 5);
        for (int i = 0; i < ROOM_N; i++)
            for (int c = 0; c < 3; c++) {
                assert_true(one.irr[3 * i + c] > 0);
                assert_true(rel(x.irr[3 * i + c] / scales[j], one.irr[3 * i + c]) < 1e-4);
                assert_true(rel(x.rad[i].c[c][0] / scales[j], one.rad[i].c[c][0]) < 1e-4);
            }
        assert_true(rel(x.st.est_rel_rmse, one.st.est_rel_rmse) < 1e-3);
        run_free(&x);
    }
    run_free(&one);
}

static void test_scale_and_offset_extremes(void **state)
{
    (void)state;
    run_out one = room_run(1, 1, ORIGIN, 2, 5);
    const double far[3] = {1e5, 1e5, -1e5};
    struct { double scale; const double *off; double tol; } cases[3] = {
        {1e-3, ORIGIN, 1e-3}, {1e4, ORIGIN, 1e-3},
        /* at 1e5 m floats step by 7.8 mm: the 4 m room moves by up to 0.2 % per vertex and
         * rays find slightly different cells; compare the average and the noise level */
        {1, far, 0},
    };
    for (int j = 0; j < 3; j++) {
        run_out x = room_run(1, cases[j].scale, cases[j].off, 2, 5);
        double sa = 0, sb = 0;
        for (int i = 0; i < ROOM_N; i++)
            for (int c = 0; c < 3; c++) {
                if (cases[j].tol > 0) assert_true(rel(x.irr[3 * i + c], one.irr[3 * i + c]) < cases[j].tol);
                sa += x.irr[3 * i + c];
                sb += one.irr[3 * i + c];
            }
        print_message("scale %g offset %g: mean ratio %.5f (est err %.4f)\n", cases[j].scale, cases[j].off[0], sa / sb,
                      one.st.est_rel_rmse);
        assert_true(rel(sa, sb) < fmax(0.01, 3 * one.st.est_rel_rmse));
        run_free(&x);
    }
    run_free(&one);
}

static void test_degenerate_triangles_and_duplicate_vertices(void **state)
{
    (void)state;
    bk_scene s;
    room(&s, 1, 1, ORIGIN);
    bk_receiver r[ROOM_N];
    room_receivers(r, 1, ORIGIN);
    bk_transport_options o = tsc_fixed_passes(2, 3);
    run_out ref = run(&s, r, ROOM_N, &o);

    /* duplicate vertices merged: the same geometry through shared indices */
    bk_scene d = s;
    d.tris = malloc(3 * s.tri_count * sizeof *d.tris);
    for (size_t i = 0; i < 3 * s.tri_count; i++) {
        uint32_t v = s.tris[i];
        for (uint32_t k = 0; k < v; k++)
            if (memcmp(s.positions + 3 * k, s.positions + 3 * v, 3 * sizeof(float)) == 0) { v = k; break; }
        d.tris[i] = v;
    }
    run_out dup = run(&d, r, ROOM_N, &o);
    assert_memory_equal(dup.irr, ref.irr, 3 * ROOM_N * sizeof(float));
    assert_memory_equal(dup.rad, ref.rad, ROOM_N * sizeof(lbk_sh9_rgb));
    free(d.tris);
    run_free(&dup);

    /* zero-area, collinear, repeated-index, NaN and out-of-range triangles appended */
    uint32_t m = s.tri_material[0];
    float a[3] = {1, 1, 1}, b[3] = {2, 1, 1}, c[3] = {3, 1, 1}, nanp[3] = {NAN, 1, 1};
    tsc_tri(&s, a, a, a, m);
    tsc_tri(&s, a, b, c, m);
    tsc_tri(&s, a, b, b, m);
    tsc_tri(&s, nanp, b, c, m);
    float big[3] = {INFINITY, 0, 0};
    tsc_tri(&s, big, a, b, m);
    tsc_tri(&s, a, b, c, m);
    s.tris[3 * (s.tri_count - 1)] = 0xFFFFFFF0u;
    run_out deg = run(&s, r, ROOM_N, &o);
    for (int i = 0; i < ROOM_N; i++)
        for (int k = 0; k < 3; k++) assert_true(rel(deg.irr[3 * i + k], ref.irr[3 * i + k]) < 1e-6);
    run_free(&deg);
    run_free(&ref);
    tsc_free(&s);
}

/* ---- determinism ------------------------------------------------------------------------------ */

static void test_determinism(void **state)
{
    (void)state;
    run_out t1 = room_run(1, 1, ORIGIN, 1, 11);
    run_out t2 = room_run(1, 1, ORIGIN, 2, 11);
    run_out t3 = room_run(1, 1, ORIGIN, 3, 11);
    run_out other = room_run(1, 1, ORIGIN, 2, 12);
    assert_memory_equal(t1.rad, t2.rad, ROOM_N * sizeof(lbk_sh9_rgb));
    assert_memory_equal(t1.dir, t2.dir, ROOM_N * sizeof(lbk_sh9_rgb));
    assert_memory_equal(t1.irr, t2.irr, 3 * ROOM_N * sizeof(float));
    assert_memory_equal(t1.rad, t3.rad, ROOM_N * sizeof(lbk_sh9_rgb));
    assert_true(memcmp(&t1.st.est_rel_rmse, &t2.st.est_rel_rmse, sizeof(double)) == 0);
    assert_true(memcmp(t1.rad, other.rad, ROOM_N * sizeof(lbk_sh9_rgb)) != 0);
    /* different seeds agree within the noise they claim */
    double num = 0, den = 0;
    for (int i = 0; i < 3 * ROOM_N; i++) { num += pow(t1.irr[i] - other.irr[i], 2); den += pow(t1.irr[i], 2); }
    assert_true(sqrt(num / den) < 4 * sqrt(2.0) * t1.st.est_rel_rmse + 1e-6);
    run_free(&t1); run_free(&t2); run_free(&t3); run_free(&other);
}

/* ---- stop rules and the report ----------------------------------------------------------------- */

typedef struct rec { int n; bk_transport_sample s[32]; } rec;
static void on_report(void *user, const bk_transport_sample *s)
{
    rec *r = (rec *)user;
    if (r->n < 32) r->s[r->n++] = *s;
}
static int on_progress(void *user, const char *phase, double f)
{
    (void)user;
    assert_true(strcmp(phase, "cache") == 0 || strcmp(phase, "gather") == 0);
    assert_true(f >= 0 && f <= 1);
    return 0;
}

typedef struct cancel_at {
    int calls, stop_at;
    rec reports;
} cancel_at;
static int cancel_progress(void *user, const char *phase, double f)
{
    (void)phase, (void)f;
    cancel_at *c = user;
    return ++c->calls >= c->stop_at;
}
static void cancel_report(void *user, const bk_transport_sample *s)
{
    on_report(&((cancel_at *)user)->reports, s);
}

static void test_stop_rules_and_report(void **state)
{
    (void)state;
    bk_scene s;
    room(&s, 1, 1, ORIGIN);
    bk_receiver r[ROOM_N];
    room_receivers(r, 1, ORIGIN);
    rec rp;
    memset(&rp, 0, sizeof rp);
    bk_transport_options o = tsc_fixed_passes(4, 3);
    o.report = on_report;
    o.progress = on_progress;
    o.user = &rp;
    run_out a = run(&s, r, ROOM_N, &o);
    assert_int_equal(a.st.stop, BK_STOP_BUDGET);
    assert_int_equal(a.st.passes, 4);
    assert_int_equal(rp.n, 4);
    for (int i = 0; i < rp.n; i++) {
        assert_int_equal(rp.s[i].pass, i);
        assert_true(rp.s[i].samples_per_receiver == 32.0 * ((1 << (i + 1)) - 1));
        assert_true(rp.s[i].bounces >= 1 && rp.s[i].est_rel_rmse > 0);
        if (i) assert_true(rp.s[i].seconds >= rp.s[i - 1].seconds);
    }
    /* noise falls with samples: the last estimate is well below the first */
    assert_true(rp.s[3].est_rel_rmse < 0.7 * rp.s[0].est_rel_rmse);
    run_free(&a);
    /* a target the first pass meets stops there */
    o = tsc_fixed_passes(4, 3);
    o.target_error = 0.9;
    run_out b = run(&s, r, ROOM_N, &o);
    assert_int_equal(b.st.stop, BK_STOP_TARGET);
    assert_int_equal(b.st.passes, 1);
    run_free(&b);
    /* an impossible time limit still completes one pass */
    o = tsc_fixed_passes(4, 3);
    o.time_limit = 1e-9;
    run_out c = run(&s, r, ROOM_N, &o);
    assert_int_equal(c.st.stop, BK_STOP_TIME);
    assert_int_equal(c.st.passes, 1);
    run_free(&c);
    /* a progress callback that says stop: the run returns at that checkpoint, before any pass
     * completes (the third checkpoint is inside pass 0's gather) */
    o = tsc_fixed_passes(4, 3);
    cancel_at ca = {0, 3, {0}};
    o.progress = cancel_progress;
    o.report = cancel_report;
    o.user = &ca;
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    lbk_sh9_rgb *rad = calloc(ROOM_N, sizeof *rad);
    bk_transport_output out = {rad, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    bk_transport_stats st;
    assert_int_equal(bk_transport_run(&s, t, r, ROOM_N, &o, &out, &st), LBK_ERR_CANCELLED);
    assert_int_equal(ca.calls, 3);
    assert_int_equal(ca.reports.n, 0);
    free(rad);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

/* ---- next-event estimation ------------------------------------------------------------------ */

/* A closed room lit only by small emitters: a one-sided ceiling panel with a 2x2 checker
 * emission texture (uv0-sampled by both strategies) and a double-sided panel hanging in the
 * room. Light sampling + gather hits (MIS) must agree with gathering alone (unbiased) and be
 * much quieter at the same sample count. */
static void nee_room(bk_scene *s)
{
    tsc_init(s);
    uint32_t wall = tsc_material(s, 0.6f, 0.55f, 0.5f, 0, 0, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {4, 3, 2.5f};
    tsc_box(s, mn, mx, 2, 1, wall);
    /* ceiling panel 0.4 m square facing down, checker 1 / 0.2 over its uv */
    uint32_t em = tsc_material(s, 0.5f, 0.5f, 0.5f, 20, 20, 20);
    s->materials[em].double_sided = 0;
    s->images = calloc(1, sizeof *s->images);
    s->image_count = 1;
    s->images[0].width = s->images[0].height = 2;
    s->images[0].rgba = calloc(16, sizeof(float));
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 4; k++) s->images[0].rgba[4 * i + k] = (i == 0 || i == 3) ? 1.0f : 0.2f;
    s->materials[em].emission_tex = 0;
    size_t v0 = s->vertex_count;
    float e0[3] = {1.8f, 1.3f, 2.45f}, e1[3] = {1.8f, 1.7f, 2.45f}, e2[3] = {2.2f, 1.7f, 2.45f}, e3[3] = {2.2f, 1.3f, 2.45f};
    tsc_quad(s, e0, e1, e2, e3, 1, em);
    for (size_t v = v0; v < s->vertex_count; v++) {
        s->uv0[2 * v] = (s->positions[3 * v] - 1.8f) / 0.4f;
        s->uv0[2 * v + 1] = (s->positions[3 * v + 1] - 1.3f) / 0.4f;
    }
    /* a double-sided 0.3 m panel standing in the room */
    uint32_t em2 = tsc_material(s, 0.3f, 0.3f, 0.3f, 4, 6, 8);
    float f0[3] = {1, 2, 1}, f1[3] = {1.3f, 2, 1}, f2[3] = {1.3f, 2, 1.3f}, f3[3] = {1, 2, 1.3f};
    tsc_quad(s, f0, f1, f2, f3, 1, em2);
    tsc_update_bounds(s);
}

static size_t nee_receivers(bk_receiver *r, size_t n)
{
    memset(r, 0, sizeof *r * n);
    for (size_t i = 0; i < n; i++) {
        double a = fmod(i * 0.618033988749895, 1.0), b = fmod(i * 0.754877666246693, 1.0);
        switch (i % 4) {
        case 0: texel(&r[i], (float)(0.05 + 3.9 * a), (float)(0.05 + 2.9 * b), 0); break;
        case 1: r[i].position[0] = 3.999f; r[i].position[1] = (float)(0.05 + 2.9 * a);
                r[i].position[2] = (float)(0.05 + 2.4 * b); r[i].normal[0] = -1; break;
        case 2: r[i].position[0] = (float)(0.05 + 3.9 * a); r[i].position[1] = (float)(0.05 + 2.9 * b);
                r[i].position[2] = 2.499f; r[i].normal[2] = -1; break;
        default: r[i].position[0] = (float)(0.3 + 3.4 * a); r[i].position[1] = (float)(0.3 + 2.4 * b);
                 r[i].position[2] = (float)(0.3 + 1.9 * fmod(i * 0.5698402909980532, 1.0));
        }
    }
    return n;
}

static double lum_of(const float *irr, const bk_receiver *r)
{
    double sc = (r->normal[0] == 0 && r->normal[1] == 0 && r->normal[2] == 0) ? 0.25 : 1.0;
    return sc * (0.2126 * irr[0] + 0.7152 * irr[1] + 0.0722 * irr[2]);
}

/* relative RMS difference of the error scalars (the estimate's own metric, TRANSPORT.md) */
static double rel_rms_diff(const float *a, const float *b, const bk_receiver *r, size_t n)
{
    double num = 0, den = 0;
    for (size_t i = 0; i < n; i++) {
        double x = lum_of(a + 3 * i, &r[i]), y = lum_of(b + 3 * i, &r[i]);
        num += (x - y) * (x - y);
        den += 0.25 * (x + y) * (x + y);
    }
    return sqrt(num / den);
}

static void test_nee_unbiased_and_quieter(void **state)
{
    (void)state;
    bk_scene s;
    nee_room(&s);
    enum { N = 160 };
    bk_receiver r[N];
    nee_receivers(r, N);
    bk_transport_options o = tsc_fixed_passes(4, 3);
    o.max_cells = 1024;
    o.nee = -1;
    run_out off = run(&s, r, N, &o);
    o.nee = 1;
    run_out on = run(&s, r, N, &o);
    o.nee = 0; /* auto: small emitters are light-sampled */
    o.seed = 11;
    o.max_samples = 2 * 16 * ((1 << 7) - 1); /* the reference: 7 passes, NEE */
    run_out ref = run(&s, r, N, &o);
    assert_int_equal(off.st.nee, 0);
    assert_int_equal(on.st.nee, 1);
    assert_int_equal(ref.st.nee, 1);
    assert_true(on.st.shadow_rays > 0 && on.st.shadow_rays < on.st.rays);
    double d_onoff = rel_rms_diff(on.irr, off.irr, r, N);
    double t_on = rel_rms_diff(on.irr, ref.irr, r, N), t_off = rel_rms_diff(off.irr, ref.irr, r, N);
    print_message("nee: est on %.4f off %.4f ref %.4f | on-off %.4f, on-ref %.4f, off-ref %.4f\n", on.st.est_rel_rmse,
                  off.st.est_rel_rmse, ref.st.est_rel_rmse, d_onoff, t_on, t_off);
    /* unbiased: the two strategies differ only by their noise */
    double both = sqrt(on.st.est_rel_rmse * on.st.est_rel_rmse + off.st.est_rel_rmse * off.st.est_rel_rmse);
    assert_true(d_onoff <= 3 * both);
    /* quieter at the same samples: at least 2x less estimated error (variance 4x) */
    assert_true(on.st.est_rel_rmse <= 0.5 * off.st.est_rel_rmse);
    /* the estimate stays honest (within 2x of the error against the reference, whose own noise
     * is removed in quadrature) */
    double t_on_c = sqrt(fmax(t_on * t_on - ref.st.est_rel_rmse * ref.st.est_rel_rmse, 0));
    assert_true(on.st.est_rel_rmse <= 2 * t_on_c && on.st.est_rel_rmse >= 0.5 * t_on_c);
    run_free(&off);
    run_free(&on);
    run_free(&ref);
    tsc_free(&s);
}

/* ---- adaptive sampling (TRANSPORT.md §Adaptive sampling) ----------------------------------- */

/* nee_room with a spot light down onto the middle of the floor, and its surface texels in
 * blocks of one surface each: the floor by distance from the spot's axis (the first block in
 * its noise-free light: quiet), then the x = 4 wall and the ceiling (mostly indirect: noisy). */
enum { AD_PER = 192, AD_N = 3 * AD_PER };
static void adaptive_scene(bk_scene *s, bk_receiver *r)
{
    nee_room(s);
    const float lp[3] = {2, 1.5f, 2.3f}, ld[3] = {0, 0, -1};
    tsc_spot_light(s, lp, ld, 300, 0.5f, 0.6f);
    bk_receiver all[4 * AD_PER];
    nee_receivers(all, 4 * AD_PER);
    for (int g = 0; g < 3; g++)
        for (int j = 0; j < AD_PER; j++) r[g * AD_PER + j] = all[4 * j + g];
    for (int i = 1; i < AD_PER; i++) /* insertion sort of the floor by distance from (2, 1.5) */
        for (int j = i; j > 0; j--) {
            bk_receiver *x = &r[j - 1], *y = &r[j];
            const double dx = hypot(x->position[0] - 2, x->position[1] - 1.5), dy = hypot(y->position[0] - 2, y->position[1] - 1.5);
            if (dx <= dy) break;
            bk_receiver t = *x;
            *x = *y, *y = t;
        }
}

/* Up to 8 passes, a 1 % target, adaptive sampling on. */
static bk_transport_options adaptive_options(void)
{
    bk_transport_options o = tsc_fixed_passes(8, 3);
    o.max_cells = 1024;
    o.target_error = 0.01;
    o.adaptive = 1;
    return o;
}

/* The per-surface relative RMS difference of a against b (the estimate's metric). */
static double group_diff(const run_out *a, const run_out *b, const bk_receiver *r, int g)
{
    return rel_rms_diff(a->irr + 3 * g * AD_PER, b->irr + 3 * g * AD_PER, r + g * AD_PER, AD_PER);
}

/* Blocks whose noise is below what the target allows the class's mean receiver stop, the rest
 * sample on past the class's mean: the floor's blocks in the spot's light stop first. Each block is normalised by its own
 * passes, so against a long non-adaptive reference every surface is within 3x of the noise the
 * two bakes estimate (a block divided by its class's weights instead of its own would be off by
 * 2x or more); the class estimate stays within 2x of the measured error; it reaches the target
 * with less work than sampling every block; and the bytes do not depend on the thread count. */
static void test_adaptive_sampling(void **state)
{
    (void)state;
    bk_scene s;
    bk_receiver r[AD_N];
    adaptive_scene(&s, r);
    bk_transport_options o = adaptive_options();
    rec rp;
    memset(&rp, 0, sizeof rp);
    o.report = on_report;
    o.user = &rp;
    run_out ad = run(&s, r, AD_N, &o);
    o.report = NULL;
    o.threads = 1;
    run_out ad1 = run(&s, r, AD_N, &o);
    o.threads = 2;
    o.adaptive = 0;
    run_out off = run(&s, r, AD_N, &o);
    o.target_error = -1;
    o.seed = 11;
    o.max_samples = 2 * 16 * ((1 << 9) - 1); /* the reference: 9 passes, every receiver */
    run_out ref = run(&s, r, AD_N, &o);
    const bk_transport_stats *st = &ad.st;
    print_message("adaptive: %.2f %% at mean %.0f / max %.0f samples, %d passes, %.3g rays; off: %.2f %% at %.0f, %.3g rays\n",
                  100 * st->est_rel_rmse, st->class_mean_samples[0], st->class_samples[0], st->passes, (double)st->rays,
                  100 * off.st.est_rel_rmse, off.st.class_samples[0], (double)off.st.rays);
    assert_memory_equal(ad.irr, ad1.irr, 3 * AD_N * sizeof *ad.irr);
    assert_memory_equal(ad.rad, ad1.rad, AD_N * sizeof *ad.rad);
    /* some blocks stopped early, others sampled longer than the class's mean */
    assert_true(st->class_mean_samples[0] < 0.9 * st->class_samples[0]);
    assert_true(st->samples_per_receiver == st->class_mean_samples[0]);
    assert_true(rp.n == st->passes && rp.s[rp.n - 1].class_mean_samples[0] == st->class_mean_samples[0]);
    for (int i = 1; i < rp.n; i++) assert_true(rp.s[i].samples_per_receiver >= rp.s[i - 1].samples_per_receiver);
    /* the mean stays within the budget the run was given */
    assert_true(st->class_mean_samples[0] <= o.max_samples);
    for (int g = 0; g < 3; g++) {
        const double d = group_diff(&ad, &ref, r, g), d_off = group_diff(&off, &ref, r, g);
        print_message("  surface %d: adaptive vs reference %.2f %%, off vs reference %.2f %%\n", g, 100 * d, 100 * d_off);
        assert_true(d <= 3 * sqrt(st->est_rel_rmse * st->est_rel_rmse + 4 * ref.st.est_rel_rmse * ref.st.est_rel_rmse) + 0.01);
    }
    const double all = rel_rms_diff(ad.irr, ref.irr, r, AD_N);
    const double measured = sqrt(fmax(all * all - ref.st.est_rel_rmse * ref.st.est_rel_rmse, 0));
    print_message("  all: estimated %.2f %%, measured %.2f %% (reference %.2f %%)\n", 100 * st->est_rel_rmse, 100 * measured,
                  100 * ref.st.est_rel_rmse);
    assert_true(st->est_rel_rmse <= 2 * measured && st->est_rel_rmse >= 0.5 * measured);
    /* both reach the target, the adaptive run with less work */
    assert_int_equal(st->stop, BK_STOP_TARGET);
    assert_int_equal(off.st.stop, BK_STOP_TARGET);
    assert_true(st->rays < 0.95 * off.st.rays);
    run_free(&ad);
    run_free(&ad1);
    run_free(&off);
    run_free(&ref);
    tsc_free(&s);
}

/* The stream path (rtcIntersect1M in chunks) returns exactly what single calls return. */
/* Receiver classes sample to their own target: probes gather over the whole sphere and are
 * noisier than texels at equal samples, so when the texels reach the target the probes have
 * not; they go on alone. Both classes end at or below the target, the probes with more samples,
 * the run's samples and stop reason are the texels', and the probes' error measured between
 * two seeds is within 2x of their estimate (the estimate is what the probes get). */
static void class_run(const bk_scene *s, const bk_receiver *r, size_t nt, size_t n, uint64_t seed, rec *rp,
                      run_out *ro)
{
    bk_transport_options o = tsc_fixed_passes(10, 3);
    o.seed = seed;
    o.target_error = 0.04;
    o.class_end[BK_CLASS_TEXEL] = nt;
    o.class_end[BK_CLASS_GLG] = n;
    o.class_end[BK_CLASS_LLG] = n;
    o.report = on_report;
    o.user = rp;
    *ro = run(s, r, n, &o);
}

static void test_classes_sample_to_their_own_target(void **state)
{
    (void)state;
    bk_scene s;
    nee_room(&s);
    enum { ALL = 256, NT = 48, NP = 32 };
    bk_receiver all[ALL], r[NT + NP];
    nee_receivers(all, ALL);
    size_t nt = 0, np = 0;
    for (size_t i = 0; i < ALL; i++) {
        int probe = all[i].normal[0] == 0 && all[i].normal[1] == 0 && all[i].normal[2] == 0;
        if (!probe && nt < NT) r[nt++] = all[i];
    }
    for (size_t i = 0; i < ALL && np < NP; i++)
        if (all[i].normal[0] == 0 && all[i].normal[1] == 0 && all[i].normal[2] == 0) r[NT + np++] = all[i];
    assert_int_equal(nt, NT);
    assert_int_equal(np, NP);
    rec ra, rb;
    memset(&ra, 0, sizeof ra);
    memset(&rb, 0, sizeof rb);
    run_out a, b;
    class_run(&s, r, NT, NT + NP, 3, &ra, &a);
    class_run(&s, r, NT, NT + NP, 4, &rb, &b);
    const bk_transport_stats *st = &a.st;
    print_message("texels %.2f %% at %.0f samples, probes %.2f %% at %.0f samples, %d passes\n",
                  100 * st->class_rel_rmse[BK_CLASS_TEXEL], st->class_samples[BK_CLASS_TEXEL],
                  100 * st->class_rel_rmse[BK_CLASS_GLG], st->class_samples[BK_CLASS_GLG], st->passes);
    assert_int_equal(st->stop, BK_STOP_TARGET);
    assert_true(st->class_rel_rmse[BK_CLASS_TEXEL] <= 0.04 && st->class_rel_rmse[BK_CLASS_GLG] <= 0.04);
    assert_true(st->class_samples[BK_CLASS_GLG] > st->class_samples[BK_CLASS_TEXEL]);
    assert_true(st->samples_per_receiver == st->class_samples[BK_CLASS_TEXEL]);
    assert_true(st->class_samples[BK_CLASS_LLG] == 0 && st->class_rel_rmse[BK_CLASS_LLG] == 0);
    /* the case is one where it matters: at the pass the texels stopped, the probes were above */
    int texel_stop = -1;
    for (int i = 0; i < ra.n && texel_stop < 0; i++)
        if (ra.s[i].class_rel_rmse[BK_CLASS_TEXEL] <= 0.04) texel_stop = i;
    assert_true(texel_stop >= 0 && texel_stop < ra.n - 1);
    assert_true(ra.s[texel_stop].class_rel_rmse[BK_CLASS_GLG] > 0.04);
    /* the records after it keep the texels' samples and estimate */
    for (int i = texel_stop + 1; i < ra.n; i++) {
        assert_true(ra.s[i].samples_per_receiver == ra.s[texel_stop].samples_per_receiver);
        assert_true(ra.s[i].class_rel_rmse[BK_CLASS_TEXEL] == ra.s[texel_stop].class_rel_rmse[BK_CLASS_TEXEL]);
    }
    /* measured: the difference of two seeds has twice one bake's variance */
    double measured = rel_rms_diff(a.irr + 3 * NT, b.irr + 3 * NT, r + NT, NP) / sqrt(2.0);
    print_message("probes: estimated %.2f %%, measured between seeds %.2f %%\n", 100 * st->class_rel_rmse[BK_CLASS_GLG],
                  100 * measured);
    assert_true(measured <= 2 * st->class_rel_rmse[BK_CLASS_GLG] && measured >= 0.5 * st->class_rel_rmse[BK_CLASS_GLG]);
    run_free(&a);
    run_free(&b);
    tsc_free(&s);
}

/* A run cut by receivers with an error target (bk_transport_split, DIST.md): each unit gathers
 * its range plus the stop receivers (stop_receivers 24: one block; the 48 texels, one block,
 * stop on all of them, the 32 probes, in two blocks, on a hashed one), so every unit stops where
 * the whole run stops —
 * the texels before the probes, after which the caches follow the probes alone — and its
 * recorded passes, accumulators and outputs are the whole run's, bit for bit; the units'
 * receiver rays add up to the whole run's (what the stop receivers cost is left out). */
typedef struct cut_rec {
    size_t begin, end, n;
    int passes;
    double weight_sum[32][BK_RECEIVER_CLASSES];
    double *x[32];
    bk_transport_totals t;
} cut_rec;

static lbk_result cut_range(void *user, size_t count, int *own, size_t *begin, size_t *end)
{
    cut_rec *c = user;
    c->n = count;
    *own = 1, *begin = c->begin, *end = c->end;
    return LBK_OK;
}

static lbk_result cut_pass(void *user, const bk_transport_pass_record *pr)
{
    cut_rec *c = user;
    assert_true(c->passes < 32 && pr->pass == c->passes);
    memcpy(c->weight_sum[c->passes], pr->weight_sum, sizeof pr->weight_sum);
    c->x[c->passes] = malloc(2 * c->n * sizeof(double));
    memcpy(c->x[c->passes], pr->x_acc[0], c->n * sizeof(double));
    memcpy(c->x[c->passes] + c->n, pr->x_acc[1], c->n * sizeof(double));
    c->passes++;
    return LBK_OK;
}

static lbk_result cut_done(void *user, const struct bk_transport_output *out, const bk_transport_totals *t)
{
    (void)out;
    ((cut_rec *)user)->t = *t;
    return LBK_OK;
}

/* One run through a recording split of receivers [begin, end). */
static run_out cut_run(const bk_scene *s, const bk_receiver *r, size_t n, const bk_transport_options *o, size_t begin,
                       size_t end, cut_rec *c)
{
    memset(c, 0, sizeof *c);
    c->begin = begin, c->end = end;
    bk_transport_split sp;
    memset(&sp, 0, sizeof sp);
    sp.user = c;
    sp.run_range = cut_range;
    sp.record_pass = cut_pass;
    sp.record_done = cut_done;
    bk_transport_options ou = *o;
    ou.split = &sp;
    ou.report = NULL;
    return run(s, r, n, &ou);
}

static void cut_free(cut_rec *c)
{
    for (int p = 0; p < c->passes; p++) free(c->x[p]);
}

/* A run resumed from any of its passes' checkpoints ends with the uninterrupted run's bytes,
 * also across adaptive stops: the blocks' weights are saved and which blocks sample next is
 * recomputed from the saved sums. */
static void test_resume_adaptive(void **state)
{
    (void)state;
    bk_scene s;
    bk_receiver r[AD_N];
    adaptive_scene(&s, r);
    bk_transport_options o = adaptive_options();
    mem_ckpt m;
    bk_transport_checkpoint ck;
    mem_ckpt_init(&m, &ck);
    o.checkpoint = &ck;
    run_out whole = run(&s, r, AD_N, &o);
    assert_true(whole.st.class_mean_samples[0] < whole.st.class_samples[0]);
    assert_int_equal(m.saved, whole.st.passes);
    /* latest first: each resumed run saves the passes after `at` again */
    for (int at = whole.st.passes - 2; at >= 0; at--) {
        mem_ckpt_drop(&m, at + 1);
        m.at = at;
        run_out res = run(&s, r, AD_N, &o);
        assert_int_equal(m.saved, whole.st.passes);
        assert_memory_equal(res.irr, whole.irr, 3 * AD_N * sizeof *whole.irr);
        assert_memory_equal(res.rad, whole.rad, AD_N * sizeof *whole.rad);
        assert_true(res.st.class_mean_samples[0] == whole.st.class_mean_samples[0] && res.st.rays == whole.st.rays);
        run_free(&res);
    }
    mem_ckpt_drop(&m, 0);
    run_free(&whole);
    tsc_free(&s);
}

/* The units [cuts[u], cuts[u + 1]) of a cut run each record the whole run's passes, class
 * weights and accumulators over their range, and its outputs; their receiver rays add up. */
static void check_cuts(const bk_scene *s, const bk_receiver *r, size_t n, const bk_transport_options *o,
                       const run_out *whole, const size_t *cuts, int units)
{
    cut_rec ref;
    run_out w = cut_run(s, r, n, o, 0, n, &ref);
    assert_int_equal(ref.passes, whole->st.passes);
    assert_memory_equal(w.rad, whole->rad, n * sizeof *whole->rad);
    assert_true(ref.t.cache_rays + ref.t.recv_rays == w.st.rays);
    uint64_t recv_rays = 0;
    for (int u = 0; u < units; u++) {
        cut_rec c;
        run_out part = cut_run(s, r, n, o, cuts[u], cuts[u + 1], &c);
        const size_t b = c.begin, m = c.end - c.begin;
        assert_int_equal(c.passes, ref.passes);
        assert_int_equal(c.t.stop, ref.t.stop);
        assert_true(c.t.cache_rays == ref.t.cache_rays); /* the caches followed the same classes */
        for (int p = 0; p < c.passes; p++) {
            assert_memory_equal(c.weight_sum[p], ref.weight_sum[p], sizeof ref.weight_sum[p]);
            assert_memory_equal(c.x[p] + b, ref.x[p] + b, m * sizeof(double));
            assert_memory_equal(c.x[p] + n + b, ref.x[p] + n + b, m * sizeof(double));
        }
        assert_memory_equal(part.rad + b, whole->rad + b, m * sizeof *whole->rad);
        assert_memory_equal(part.irr + 3 * b, whole->irr + 3 * b, 3 * m * sizeof *whole->irr);
        /* it traced the stop receivers outside its range too, and left them out of its count */
        assert_true(c.t.cache_rays + c.t.recv_rays < part.st.rays);
        recv_rays += c.t.recv_rays;
        cut_free(&c);
        run_free(&part);
    }
    assert_true(recv_rays == ref.t.recv_rays);
    cut_free(&ref);
    run_free(&w);
}

static void test_cut_run_with_target(void **state)
{
    (void)state;
    bk_scene s;
    nee_room(&s);
    enum { ALL = 256, NT = 48, NP = 32, N = NT + NP };
    bk_receiver all[ALL], r[N];
    nee_receivers(all, ALL);
    size_t nt = 0, np = 0;
    for (size_t i = 0; i < ALL; i++) {
        int probe = all[i].normal[0] == 0 && all[i].normal[1] == 0 && all[i].normal[2] == 0;
        if (!probe && nt < NT) r[nt++] = all[i];
        else if (probe && np < NP) r[NT + np++] = all[i];
    }
    assert_int_equal(nt, NT);
    assert_int_equal(np, NP);
    bk_transport_options o = tsc_fixed_passes(10, 3);
    o.target_error = 0.04;
    o.class_end[BK_CLASS_TEXEL] = NT;
    o.class_end[BK_CLASS_GLG] = N;
    o.class_end[BK_CLASS_LLG] = N;
    o.stop_receivers = 24;
    run_out whole = run(&s, r, N, &o);
    assert_int_equal(whole.st.stop, BK_STOP_TARGET);
    /* the case is one where the cut matters: the texels stopped passes before the probes */
    assert_true(whole.st.class_samples[BK_CLASS_GLG] > whole.st.class_samples[BK_CLASS_TEXEL]);
    print_message("whole run: %d passes, texels %.0f samples (%.2f %%), probes %.0f (%.2f %%)\n", whole.st.passes,
                  whole.st.class_samples[BK_CLASS_TEXEL], 100 * whole.st.class_rel_rmse[BK_CLASS_TEXEL],
                  whole.st.class_samples[BK_CLASS_GLG], 100 * whole.st.class_rel_rmse[BK_CLASS_GLG]);
    const size_t cuts[4] = {0, 27, 54, N};
    check_cuts(&s, r, N, &o, &whole, cuts, 3);
    run_free(&whole);
    tsc_free(&s);
}

/* The same with adaptive sampling, cut at whole blocks (spec/part.md §1.1): both classes stop
 * on subsets of two of their blocks (6 and 3), so each unit decides the blocks it gathers and
 * those of the subsets as the whole run does, and the second class adapts only once the first
 * has stopped; then without subsets. */
static void test_cut_run_adaptive(void **state)
{
    (void)state;
    bk_scene s;
    bk_receiver r[AD_N];
    adaptive_scene(&s, r);
    bk_transport_options o = adaptive_options();
    o.class_end[BK_CLASS_TEXEL] = 2 * AD_PER;
    o.class_end[BK_CLASS_GLG] = AD_N;
    o.class_end[BK_CLASS_LLG] = AD_N;
    o.stop_receivers = 2 * BK_TRANSPORT_BLOCK;
    run_out whole = run(&s, r, AD_N, &o);
    o.adaptive = 0;
    run_out off = run(&s, r, AD_N, &o);
    o.adaptive = 1;
    print_message("whole run: %d passes, %.3g rays (%.3g without adaptive sampling); the subsets' mean samples: "
                  "texels %.0f / max %.0f, class 1 %.0f / max %.0f\n", whole.st.passes, (double)whole.st.rays,
                  (double)off.st.rays, whole.st.class_mean_samples[0], whole.st.class_samples[0],
                  whole.st.class_mean_samples[1], whole.st.class_samples[1]);
    /* blocks stopped early (the classes' means are their subsets', which need not show it) */
    assert_true(whole.st.passes == off.st.passes && whole.st.rays < off.st.rays);
    run_free(&off);
    const size_t cuts[4] = {0, 3 * BK_TRANSPORT_BLOCK, 5 * BK_TRANSPORT_BLOCK, AD_N};
    check_cuts(&s, r, AD_N, &o, &whole, cuts, 3);
    run_free(&whole);
    /* and without subsets (every unit gathers both classes whole), where the means show it */
    o.stop_receivers = 0;
    whole = run(&s, r, AD_N, &o);
    assert_true(whole.st.class_mean_samples[0] < whole.st.class_samples[0]);
    check_cuts(&s, r, AD_N, &o, &whole, cuts, 3);
    run_free(&whole);
    tsc_free(&s);
}

static void test_stream_equals_single(void **state)
{
    (void)state;
    bk_scene s;
    nee_room(&s);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    enum { N = 1000 };
    float *org = malloc(3 * N * sizeof(float)), *dir = malloc(3 * N * sizeof(float)), *tmax = malloc(N * sizeof(float));
    bk_hit *hs = malloc(N * sizeof *hs);
    for (int i = 0; i < N; i++) {
        double a = fmod(i * 0.618033988749895, 1.0), b = fmod(i * 0.754877666246693, 1.0);
        double ph = 2 * M_PI * fmod(i * 0.5698402909980532, 1.0), z = 2 * b - 1, rr = sqrt(1 - z * z);
        org[3 * i] = (float)(0.1 + 3.8 * a); org[3 * i + 1] = (float)(0.1 + 2.8 * b); org[3 * i + 2] = (float)(0.1 + 2.3 * a * b);
        dir[3 * i] = (float)(rr * cos(ph)); dir[3 * i + 1] = (float)(rr * sin(ph)); dir[3 * i + 2] = (float)z;
        tmax[i] = i % 7 == 0 ? 0.5f : INFINITY;
    }
    dir[3 * 5] = NAN; /* a bad ray misses in both */
    bk_tracer_intersect_n(t, N, org, dir, 0.0f, tmax, hs);
    int hits = 0;
    for (int i = 0; i < N; i++) {
        bk_hit h;
        int hit = bk_tracer_intersect(t, org + 3 * i, dir + 3 * i, 0.0f, tmax[i], &h);
        assert_int_equal(hit, hs[i].tri != UINT32_MAX);
        if (!hit) continue;
        hits++;
        assert_true(h.tri == hs[i].tri && h.t == hs[i].t && h.u == hs[i].u && h.v == hs[i].v && h.front == hs[i].front);
    }
    assert_true(hits > N / 2);
    free(org); free(dir); free(tmax); free(hs);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

static void test_invalid_arguments(void **state)
{
    (void)state;
    bk_scene s;
    room(&s, 1, 1, ORIGIN);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 0, &t), LBK_OK);
    bk_receiver r[1];
    texel(&r[0], 1, 1, 0);
    lbk_sh9_rgb rad[1];
    bk_transport_output out = {rad, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    assert_int_equal(bk_transport_run(NULL, t, r, 1, NULL, &out, NULL), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_transport_run(&s, NULL, r, 1, NULL, &out, NULL), LBK_ERR_INVALID_ARGUMENT);
    bk_transport_output none = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    assert_int_equal(bk_transport_run(&s, t, r, 1, NULL, &none, NULL), LBK_ERR_INVALID_ARGUMENT);
    /* class ranges must be ordered and end at the receiver count */
    bk_transport_options co;
    memset(&co, 0, sizeof co);
    co.max_samples = 32;
    co.class_end[0] = 1; co.class_end[1] = 0; co.class_end[2] = 1;
    assert_int_equal(bk_transport_run(&s, t, r, 1, &co, &out, NULL), LBK_ERR_INVALID_ARGUMENT);
    co.class_end[1] = 1; co.class_end[2] = 2;
    assert_int_equal(bk_transport_run(&s, t, r, 1, &co, &out, NULL), LBK_ERR_INVALID_ARGUMENT);
    co.class_end[2] = 1;
    assert_int_equal(bk_transport_run(&s, t, r, 1, &co, &out, NULL), LBK_OK);
    r[0].position[1] = NAN;
    assert_int_equal(bk_transport_run(&s, t, r, 1, NULL, &out, NULL), LBK_ERR_INVALID_ARGUMENT);
    /* zero receivers is fine */
    assert_int_equal(bk_transport_run(&s, t, r, 0, NULL, &none, NULL), LBK_OK);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_light_plane),
        cmocka_unit_test(test_spot_cone),
        cmocka_unit_test(test_directional_and_shadow),
        cmocka_unit_test(test_sky_open_plane),
        cmocka_unit_test(test_closed_box_no_leak),
        cmocka_unit_test(test_light_sets),
        cmocka_unit_test(test_nee_unbiased_and_quieter),
        cmocka_unit_test(test_classes_sample_to_their_own_target),
        cmocka_unit_test(test_cut_run_with_target),
        cmocka_unit_test(test_adaptive_sampling),
        cmocka_unit_test(test_cut_run_adaptive),
        cmocka_unit_test(test_resume_adaptive),
        cmocka_unit_test(test_stream_equals_single),
        cmocka_unit_test(test_intensity_extremes),
        cmocka_unit_test(test_scale_and_offset_extremes),
        cmocka_unit_test(test_degenerate_triangles_and_duplicate_vertices),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_stop_rules_and_report),
        cmocka_unit_test(test_invalid_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
