/* Lightmap parametrisation: charts per object (bake/layout/uvgen.h). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/uvgen.h"
#include "support/uv_scenes.h"

/* Every triangle of the object is in exactly one chart or counted degenerate; all chart
 * coordinates lie inside the chart's extent; no chart overlaps itself at texel resolution. */
static void check_invariants(const bk_scene *s, const bk_uv_object *u)
{
    const bk_object *o = &s->objects[u->object];
    uint8_t *seen = calloc(o->tri_count ? o->tri_count : 1, 1);
    assert_non_null(seen);
    size_t sum = 0;
    for (size_t c = 0; c < u->chart_count; c++) {
        const bk_uv_chart *ch = &u->charts[c];
        assert_true(ch->count > 0);
        assert_true(ch->width >= 0.0f && ch->height >= 0.0f);
        for (uint32_t i = 0; i < ch->count; i++) {
            uint32_t t = u->tris[ch->first + i];
            assert_true(t >= o->first_tri && t < o->first_tri + o->tri_count);
            assert_int_equal(seen[t - o->first_tri], 0);
            seen[t - o->first_tri] = 1;
            for (int k = 0; k < 3; k++) {
                float x = u->uv[6 * (ch->first + i) + 2 * (size_t)k], y = u->uv[6 * (ch->first + i) + 2 * (size_t)k + 1];
                assert_true(x >= 0.0f && x <= ch->width);
                assert_true(y >= 0.0f && y <= ch->height);
            }
        }
        sum += ch->count;
        size_t over = bk_uv_count_overlaps(u->uv + 6 * (size_t)ch->first, ch->count, (int)ceilf(ch->width) + 1,
                                           (int)ceilf(ch->height) + 1, NULL);
        if (u->source == BK_UV_GENERATED) assert_int_equal(over, 0);
    }
    assert_int_equal(sum, u->tri_count);
    assert_int_equal(u->tri_count + u->degenerate_count, o->tri_count);
    free(seen);
}

static double chart_uv_area(const bk_uv_object *u)
{
    double a = 0.0;
    for (size_t i = 0; i < u->tri_count; i++) {
        const float *q = u->uv + 6 * i;
        a += 0.5 * fabs(((double)q[2] - q[0]) * ((double)q[5] - q[1]) - ((double)q[3] - q[1]) * ((double)q[4] - q[0]));
    }
    return a;
}

static void test_overlap_counter(void **state)
{
    (void)state;
    /* two triangles tiling a 4×4 square: every centre covered exactly once */
    float two[12] = {0, 0, 4, 0, 4, 4, 0, 0, 4, 4, 0, 4};
    size_t cov = 0;
    assert_int_equal(bk_uv_count_overlaps(two, 2, 4, 4, &cov), 0);
    assert_int_equal(cov, 16);
    /* the same with a diagonal through texel centres (3×3 square from 0.5 to 3.5) */
    float diag[12] = {0.5f, 0.5f, 3.5f, 0.5f, 3.5f, 3.5f, 0.5f, 0.5f, 3.5f, 3.5f, 0.5f, 3.5f};
    assert_int_equal(bk_uv_count_overlaps(diag, 2, 4, 4, &cov), 0);
    /* top-left rule: of the 16 centres on the closed square, those on the right/bottom edges
     * of the square are excluded by one rule or the other, but never double counted */
    assert_true(cov >= 9 && cov <= 16);
    /* a duplicated triangle overlaps on every centre it covers */
    float dup[12] = {0, 0, 4, 0, 4, 4, 0, 0, 4, 0, 4, 4};
    size_t over = bk_uv_count_overlaps(dup, 2, 4, 4, &cov);
    assert_int_equal(over, cov);
    assert_true(cov >= 6);
}

static void test_unit_quad_density(void **state)
{
    (void)state;
    const float dens[] = {4.0f, 10.0f, 16.0f, 31.5f};
    for (size_t d = 0; d < sizeof dens / sizeof dens[0]; d++) {
        bk_scene s;
        uvs_init(&s);
        uvs_object(&s, "quad");
        float p0[3] = {0, 0, 0}, p1[3] = {1, 0, 0}, p2[3] = {1, 0, -1}, p3[3] = {0, 0, -1};
        uvs_quad(&s, p0, p1, p2, p3, 3, 0, NULL, 1.0f);
        bk_uv_object u;
        assert_int_equal(bk_uvgen_object(&s, 0, dens[d], NULL, &u), LBK_OK);
        assert_int_equal(u.source, BK_UV_GENERATED);
        assert_int_equal(u.chart_count, 1);
        assert_int_equal(u.tri_count, 18);
        assert_float_equal(u.charts[0].width, dens[d], 1e-3 * dens[d]);
        assert_float_equal(u.charts[0].height, dens[d], 1e-3 * dens[d]);
        assert_float_equal(chart_uv_area(&u), (double)dens[d] * dens[d], 1e-3 * dens[d] * dens[d]);
        check_invariants(&s, &u);
        bk_uv_object_free(&u);
        uvs_free(&s);
    }
}

/* A square turned by 30° in its plane still gets a d×d chart (minimum-area rectangle). */
static void test_rotated_quad_min_area(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "turned");
    double a = 30.0 * 3.14159265358979323846 / 180.0, c = cos(a), sn = sin(a);
    float p[4][3];
    const double corner[4][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
    for (int i = 0; i < 4; i++) {
        p[i][0] = (float)(c * corner[i][0] - sn * corner[i][1]);
        p[i][1] = 3.0f;
        p[i][2] = (float)-(sn * corner[i][0] + c * corner[i][1]);
    }
    uvs_quad(&s, p[0], p[1], p[2], p[3], 2, 0, NULL, 1.0f);
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
    assert_int_equal(u.chart_count, 1);
    assert_float_equal(u.charts[0].width, 16.0, 0.01);
    assert_float_equal(u.charts[0].height, 16.0, 0.01);
    check_invariants(&s, &u);
    bk_uv_object_free(&u);
    uvs_free(&s);
}

/* A cube: 6 faces at 90° never merge with a cone below 45°, so 6 charts of d×d. */
static void test_cube_six_charts(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "cube");
    float mn[3] = {-0.5f, 0, -0.5f}, mx[3] = {0.5f, 1, 0.5f};
    uvs_box(&s, mn, mx, 2, 0, 0);
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 12.0f, NULL, &u), LBK_OK);
    assert_int_equal(u.chart_count, 6);
    for (size_t c = 0; c < 6; c++) {
        assert_int_equal(u.charts[c].count, 8);
        assert_float_equal(u.charts[c].width, 12.0, 0.01);
        assert_float_equal(u.charts[c].height, 12.0, 0.01);
    }
    check_invariants(&s, &u);
    bk_uv_object_free(&u);
    uvs_free(&s);
}

/* A gently bent strip (10° between panels) stays one chart within the cone; a 90° fold does not. */
static void test_cone_threshold(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "bent");
    float x = 0, y = 0;
    double ang = 0;
    for (int i = 0; i < 3; i++) {
        float nx = x + (float)cos(ang), ny = y + (float)sin(ang);
        float p0[3] = {x, y, 0}, p1[3] = {nx, ny, 0}, p2[3] = {nx, ny, -1}, p3[3] = {x, y, -1};
        uvs_quad(&s, p0, p1, p2, p3, 1, 0, NULL, 1.0f);
        x = nx;
        y = ny;
        ang += 10.0 * 3.14159265358979323846 / 180.0;
    }
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
    assert_int_equal(u.chart_count, 1);
    /* the area is preserved: 3 m² at 8 texels/m */
    assert_float_equal(chart_uv_area(&u), 3.0 * 64.0, 0.5);
    check_invariants(&s, &u);
    bk_uv_object_free(&u);
    uvs_free(&s);
}

static void test_authored_uv1_kept(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "authored");
    s.objects[0].has_uv1 = 1;
    /* two 1 m quads, authored into islands at (0.1,0.1) and (0.6,0.3), each 0.25 wide */
    float a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, a2[3] = {1, 0, -1}, a3[3] = {0, 0, -1};
    float b0[3] = {0, 0, 0}, b1[3] = {0, 0, -1}, b2[3] = {0, 1, -1}, b3[3] = {0, 1, 0};
    float o1[2] = {0.1f, 0.1f}, o2[2] = {0.6f, 0.3f};
    uvs_quad(&s, a0, a1, a2, a3, 2, 0, o1, 0.25f);
    uvs_quad(&s, b0, b1, b2, b3, 2, 0, o2, 0.25f);
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 16.0f, NULL, &u), LBK_OK);
    assert_int_equal(u.source, BK_UV_AUTHORED);
    assert_string_equal(u.note, "");
    assert_int_equal(u.chart_count, 1);
    /* uniform scale: uv area 2·0.0625 m² maps to 2 m² → 4 texels per ... s = 16·sqrt(2/0.125) = 64 */
    double sc = 64.0;
    assert_float_equal(u.charts[0].width, (0.85 - 0.1) * sc, 1e-3);
    assert_float_equal(u.charts[0].height, (0.55 - 0.1) * sc, 1e-3);
    assert_float_equal(u.density, 16.0, 1e-3);
    /* every corner is the authored uv1 moved and scaled: layout kept */
    for (size_t i = 0; i < u.tri_count; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = s.tris[3 * (size_t)u.tris[i] + (size_t)k];
            assert_float_equal(u.uv[6 * i + 2 * (size_t)k], (s.uv1[2 * v] - 0.1) * sc, 1e-3);
            assert_float_equal(u.uv[6 * i + 2 * (size_t)k + 1], (s.uv1[2 * v + 1] - 0.1) * sc, 1e-3);
        }
    check_invariants(&s, &u);
    bk_uv_object_free(&u);
    /* the 48-texel layout over a 40-texel chart cap: the density is lowered to fit (one chart
     * that cannot be split), unless the one-chart cap (a maximum page) holds it */
    bk_uv_options o = {0};
    o.max_chart_texels = 40;
    assert_int_equal(bk_uvgen_object(&s, 0, 16.0f, &o, &u), LBK_OK);
    assert_int_equal(u.source, BK_UV_AUTHORED);
    assert_float_equal(u.charts[0].width, 40.0, 1e-3);
    assert_float_equal(u.density, 16.0 * 40.0 / 48.0, 1e-3);
    assert_non_null(strstr(u.note, "so the uv1 layout fits 40 texels"));
    bk_uv_object_free(&u);
    o.max_triangle_texels = 100;
    assert_int_equal(bk_uvgen_object(&s, 0, 16.0f, &o, &u), LBK_OK);
    assert_float_equal(u.charts[0].width, 48.0, 1e-3);
    assert_float_equal(u.density, 16.0, 1e-3);
    assert_string_equal(u.note, "");
    bk_uv_object_free(&u);
    uvs_free(&s);
}

static void test_authored_uv1_rejected(void **state)
{
    (void)state;
    float a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, a2[3] = {1, 0, -1}, a3[3] = {0, 0, -1};
    float b0[3] = {0, 0, 0}, b1[3] = {0, 0, -1}, b2[3] = {0, 1, -1}, b3[3] = {0, 1, 0};
    /* outside [0,1] */
    {
        bk_scene s;
        uvs_init(&s);
        uvs_object(&s, "tiled");
        s.objects[0].has_uv1 = 1;
        float o[2] = {0.5f, 0.0f};
        uvs_quad(&s, a0, a1, a2, a3, 1, 0, o, 2.0f);
        bk_uv_object u;
        assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
        assert_int_equal(u.source, BK_UV_GENERATED);
        assert_non_null(strstr(u.note, "outside [0,1]"));
        assert_int_equal(u.chart_count, 1);
        check_invariants(&s, &u);
        bk_uv_object_free(&u);
        uvs_free(&s);
    }
    /* both quads authored onto the same island: overlap */
    {
        bk_scene s;
        uvs_init(&s);
        uvs_object(&s, "stacked");
        s.objects[0].has_uv1 = 1;
        float o[2] = {0.2f, 0.2f};
        uvs_quad(&s, a0, a1, a2, a3, 2, 0, o, 0.5f);
        uvs_quad(&s, b0, b1, b2, b3, 2, 0, o, 0.5f);
        bk_uv_object u;
        assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
        assert_int_equal(u.source, BK_UV_GENERATED);
        assert_non_null(strstr(u.note, "overlap"));
        assert_int_equal(u.chart_count, 2);
        check_invariants(&s, &u);
        bk_uv_object_free(&u);
        uvs_free(&s);
    }
    /* all uv1 zero */
    {
        bk_scene s;
        uvs_init(&s);
        uvs_object(&s, "zero");
        s.objects[0].has_uv1 = 1;
        uvs_quad(&s, a0, a1, a2, a3, 1, 0, NULL, 0.0f);
        bk_uv_object u;
        assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
        assert_int_equal(u.source, BK_UV_GENERATED);
        assert_non_null(strstr(u.note, "zero uv area"));
        bk_uv_object_free(&u);
        uvs_free(&s);
    }
    /* a NaN uv1 */
    {
        bk_scene s;
        uvs_init(&s);
        uvs_object(&s, "nan");
        s.objects[0].has_uv1 = 1;
        uvs_quad(&s, a0, a1, a2, a3, 1, 0, NULL, 1.0f);
        s.uv1[1] = NAN;
        bk_uv_object u;
        assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
        assert_int_equal(u.source, BK_UV_GENERATED);
        assert_non_null(strstr(u.note, "outside"));
        bk_uv_object_free(&u);
        uvs_free(&s);
    }
}

static void test_degenerate_triangles(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "mixed");
    float p0[3] = {0, 0, 0}, p1[3] = {1, 0, 0}, p2[3] = {1, 0, -1}, p3[3] = {0, 0, -1};
    uvs_quad(&s, p0, p1, p2, p3, 1, 0, NULL, 1.0f);
    float c0[3] = {0, 1, 0}, c1[3] = {1, 1, 0}, c2[3] = {2, 1, 0};
    uvs_tri(&s, c0, c1, c2, 0);                  /* collinear */
    uvs_tri(&s, c0, c0, c1, 0);                  /* repeated vertex */
    uvs_tri(&s, c0, c1, c1, 0);
    float nan3[3] = {NAN, 0, 0};
    uvs_tri(&s, c0, nan3, c1, 0);                /* non-finite */
    uvs_tri_idx(&s, 0, 1, (uint32_t)s.vertex_count + 100, 0); /* index out of range */
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
    assert_int_equal(u.degenerate_count, 5);
    assert_int_equal(u.tri_count, 2);
    assert_int_equal(u.chart_count, 1);
    check_invariants(&s, &u);
    bk_uv_object_free(&u);

    /* an object of only degenerate triangles has nothing to lightmap */
    uvs_object(&s, "dust");
    uvs_tri(&s, c0, c1, c2, 0);
    uvs_tri(&s, c0, c0, c0, 0);
    assert_int_equal(bk_uvgen_object(&s, 1, 8.0f, NULL, &u), LBK_OK);
    assert_int_equal(u.source, BK_UV_EMPTY);
    assert_int_equal(u.chart_count, 0);
    assert_int_equal(u.degenerate_count, 2);
    bk_uv_object_free(&u);

    /* bad arguments */
    assert_int_equal(bk_uvgen_object(&s, 7, 8.0f, NULL, &u), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_uvgen_object(&s, 0, 0.0f, NULL, &u), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_uvgen_object(&s, 0, NAN, NULL, &u), LBK_ERR_INVALID_ARGUMENT);
    uvs_free(&s);
}

/* A long strip over the chart cap is split into charts that each fit, area preserved. */
static void test_oversize_split(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "long");
    float p0[3] = {0, 0, 0}, p1[3] = {40, 0, 0}, p2[3] = {40, 0, -40}, p3[3] = {0, 0, -40};
    uvs_quad(&s, p0, p1, p2, p3, 16, 0, NULL, 1.0f);
    bk_uv_options o = {0};
    o.max_chart_texels = 100;
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, &o, &u), LBK_OK);
    assert_true(u.chart_count >= 16); /* 320×320 texels in ≤ 100×100 pieces */
    for (size_t c = 0; c < u.chart_count; c++) {
        assert_true(u.charts[c].width <= 100.0f);
        assert_true(u.charts[c].height <= 100.0f);
    }
    assert_float_equal(chart_uv_area(&u), 320.0 * 320.0, 1.0);
    assert_string_equal(u.note, "");
    assert_float_equal(u.density, 8.0, 1e-6);
    check_invariants(&s, &u);
    bk_uv_object_free(&u);

    /* one triangle that cannot be split: only its own chart gets a lower density, the object
     * keeps the one asked for (reported) */
    uvs_object(&s, "huge");
    float t0[3] = {0, 5, 0}, t1[3] = {50, 5, 0}, t2[3] = {0, 5, -50};
    uvs_tri(&s, t0, t1, t2, 0);
    assert_int_equal(bk_uvgen_object(&s, 1, 8.0f, &o, &u), LBK_OK);
    assert_int_equal(u.chart_count, 1);
    assert_true(u.charts[0].width <= 100.0f && u.charts[0].height <= 100.0f);
    /* scaled to the cap exactly (its longer side), not further */
    assert_true(fmaxf(u.charts[0].width, u.charts[0].height) > 99.9f);
    assert_float_equal(u.density, 8.0, 1e-6);
    assert_int_equal(u.scaled_tris, 1);
    assert_int_equal(u.big_tris, 1);
    /* 400 texel legs (or a 566 texel hypotenuse) into 100: at most 2 texels/m */
    assert_true(u.scaled_density <= 8.0f * 100.0f / 399.0f);
    assert_float_equal(sqrt(chart_uv_area(&u) / 1250.0), u.scaled_density, 1e-3);
    assert_non_null(strstr(u.note, "1 triangle longer than 100 texels"));
    check_invariants(&s, &u);
    bk_uv_object_free(&u);

    /* the same triangle with a one-triangle cap of a large page: its chart keeps the density */
    o.max_triangle_texels = 1000;
    assert_int_equal(bk_uvgen_object(&s, 1, 8.0f, &o, &u), LBK_OK);
    assert_int_equal(u.chart_count, 1);
    assert_int_equal(u.scaled_tris, 0);
    assert_int_equal(u.big_tris, 1);
    assert_float_equal(sqrt(chart_uv_area(&u) / 1250.0), 8.0, 1e-3);
    assert_string_equal(u.note, "");
    bk_uv_object_free(&u);
    uvs_free(&s);
}

/* The world area of a chart's triangles, m². */
static double chart_world_area(const bk_scene *s, const bk_uv_object *u, size_t c)
{
    double a = 0.0;
    for (uint32_t i = 0; i < u->charts[c].count; i++) {
        const uint32_t *v = s->tris + 3 * (size_t)u->tris[u->charts[c].first + i];
        const float *p = s->positions + 3 * (size_t)v[0], *q = s->positions + 3 * (size_t)v[1],
                    *r = s->positions + 3 * (size_t)v[2];
        double e1[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, e2[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
        double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
        a += 0.5 * sqrt(x * x + y * y + z * z);
    }
    return a;
}

static double chart_texel_area(const bk_uv_object *u, size_t c)
{
    double a = 0.0;
    for (uint32_t i = 0; i < u->charts[c].count; i++) {
        const float *q = u->uv + 6 * ((size_t)u->charts[c].first + i);
        a += 0.5 * fabs(((double)q[2] - q[0]) * ((double)q[5] - q[1]) - ((double)q[3] - q[1]) * ((double)q[4] - q[0]));
    }
    return a;
}

/* One object: a huge triangle beside ordinary detail (a 4 × 4 m box). The huge triangle's chart
 * alone is scaled to the one-triangle cap; every other chart has the density asked for,
 * measured from its texel area against its world area. */
static void test_huge_triangle_keeps_object_density(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "ground_and_box");
    float t0[3] = {-500, 0, 500}, t1[3] = {500, 0, 500}, t2[3] = {-500, 0, -500};
    uvs_tri(&s, t0, t1, t2, 0);
    float mn[3] = {0, 0, 0}, mx[3] = {4, 4, 4};
    uvs_box(&s, mn, mx, 2, 0, 0);
    bk_uv_options o = {0};
    o.max_chart_texels = 250;
    o.max_triangle_texels = 1020;
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, &o, &u), LBK_OK);
    assert_float_equal(u.density, 8.0, 1e-6);
    assert_int_equal(u.scaled_tris, 1);
    size_t huge = 0, others = 0;
    for (size_t c = 0; c < u.chart_count; c++) {
        double d = sqrt(chart_texel_area(&u, c) / chart_world_area(&s, &u, c));
        if (u.charts[c].count == 1 && u.tris[u.charts[c].first] == s.objects[0].first_tri) {
            huge++;
            /* 8000 texel legs into 1020 (or its 11314 texel hypotenuse) */
            assert_true(d <= 8.0 * 1020.0 / 7999.0);
            assert_true(fmaxf(u.charts[c].width, u.charts[c].height) <= 1020.0f);
            assert_float_equal(d, u.scaled_density, 1e-3);
        } else {
            others++;
            assert_float_equal(d, 8.0, 8.0 * 1e-4);
            assert_true(fmaxf(u.charts[c].width, u.charts[c].height) <= 250.0f);
        }
    }
    assert_int_equal(huge, 1);
    assert_true(others >= 5); /* the box's five outward faces at least */
    check_invariants(&s, &u);
    bk_uv_object_free(&u);
    uvs_free(&s);
}

/* A sphere: charts cover it without overlap and the texel area matches the density
 * (projection within the cone shrinks at most by cos 40°, the per-chart area scale undoes
 * it on average). */
static void test_sphere_charts(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "sphere");
    float c[3] = {0, 0, 0};
    uvs_sphere(&s, c, 1.0f, 32, 16, 0);
    double area = 0;
    for (size_t t = 0; t < s.tri_count; t++) {
        const float *a = s.positions + 3 * s.tris[3 * t], *b = s.positions + 3 * s.tris[3 * t + 1],
                    *d = s.positions + 3 * s.tris[3 * t + 2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
        area += 0.5 * sqrt(x * x + y * y + z * z);
        /* outward winding */
        double cx = a[0] + b[0] + d[0], cy = a[1] + b[1] + d[1], cz = a[2] + b[2] + d[2];
        assert_true(x * cx + y * cy + z * cz > 0);
    }
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 10.0f, NULL, &u), LBK_OK);
    assert_int_equal(u.source, BK_UV_GENERATED);
    assert_true(u.chart_count >= 6 && u.chart_count <= 64);
    assert_float_equal(chart_uv_area(&u), area * 100.0, 1e-3 * area * 100.0);
    check_invariants(&s, &u);
    bk_uv_object_free(&u);
    uvs_free(&s);
}

/* A spiral ramp whose normals all point up overlaps itself in projection: it must be split. */
static void test_spiral_overlap_split(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "ramp");
    const int steps = 96;
    for (int i = 0; i < steps; i++) {
        double a0 = 2 * 3.14159265358979323846 * i / 24.0, a1 = 2 * 3.14159265358979323846 * (i + 1) / 24.0;
        float h0 = 0.05f * (float)i, h1 = 0.05f * (float)(i + 1);
        float in0[3] = {(float)cos(a0), h0, (float)-sin(a0)}, out0[3] = {3 * (float)cos(a0), h0, 3 * (float)-sin(a0)};
        float in1[3] = {(float)cos(a1), h1, (float)-sin(a1)}, out1[3] = {3 * (float)cos(a1), h1, 3 * (float)-sin(a1)};
        float n[3] = {0, 1, 0};
        uint32_t v0 = uvs_vertex(&s, in0, n), v1 = uvs_vertex(&s, out0, n), v2 = uvs_vertex(&s, out1, n),
                 v3 = uvs_vertex(&s, in1, n);
        uvs_tri_idx(&s, v0, v1, v2, 0);
        uvs_tri_idx(&s, v0, v2, v3, 0);
    }
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 8.0f, NULL, &u), LBK_OK);
    assert_true(u.chart_count >= 4); /* four turns cannot share one planar chart */
    check_invariants(&s, &u);
    bk_uv_object_free(&u);
    uvs_free(&s);
}

static void test_deterministic(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "sphere");
    float c[3] = {1, 2, 3};
    uvs_sphere(&s, c, 0.7f, 24, 12, 0);
    bk_uv_object a, b;
    assert_int_equal(bk_uvgen_object(&s, 0, 12.0f, NULL, &a), LBK_OK);
    assert_int_equal(bk_uvgen_object(&s, 0, 12.0f, NULL, &b), LBK_OK);
    assert_int_equal(a.chart_count, b.chart_count);
    assert_int_equal(a.tri_count, b.tri_count);
    assert_memory_equal(a.charts, b.charts, a.chart_count * sizeof *a.charts);
    assert_memory_equal(a.tris, b.tris, a.tri_count * sizeof *a.tris);
    assert_memory_equal(a.uv, b.uv, a.tri_count * 6 * sizeof *a.uv);
    bk_uv_object_free(&a);
    bk_uv_object_free(&b);
    uvs_free(&s);
}

/* Small charts go into a neighbour: a 50 cm panel (2×2 cells, 5 × 5 texels at 10 texels/m)
 * with a 10 cm strip bevelled at 45° along one side (5 × 1 texels) and a 25 × 10 cm tab folded
 * down 90° on one cell edge (3 × 1 texels) becomes one chart: each merge makes the chart's
 * block (content plus its ring) smaller than the two blocks were (7×7 + 7×3 → 8×7, then + 5×3
 * → 8×8). The hinge unfolding keeps every edge length (× density) and the merged chart has no
 * overlap. Two 1 m panels at 90° (10 × 10 texels each) stay two charts, and so does a 90° jamb
 * one texel wide (a hard edge is crossed by tiny charts only). */
static void test_merge_small_charts(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "panel+bevel+tab");
    float p0[3] = {0, 0, 0}, p1[3] = {0.5f, 0, 0}, p2[3] = {0.5f, 0, -0.5f}, p3[3] = {0, 0, -0.5f};
    uvs_quad(&s, p0, p1, p2, p3, 2, 0, NULL, 1.0f);
    const float b = 0.1f / sqrtf(2.0f);
    /* shares the panel's vertices along x = 0.5 (the same positions, welded exactly) */
    float q0[3] = {0.5f, 0, 0}, q1[3] = {0.5f + b, -b, 0}, q2[3] = {0.5f + b, -b, -0.5f}, q3[3] = {0.5f, 0, -0.5f};
    uvs_quad(&s, q0, q1, q2, q3, 2, 0, NULL, 1.0f);
    float t0[3] = {0.25f, 0, 0}, t1[3] = {0, 0, 0}, t2[3] = {0.125f, -0.1f, 0};
    uvs_tri(&s, t0, t1, t2, 0);
    uvs_update_bounds(&s);
    bk_uv_object u;
    assert_int_equal(bk_uvgen_object(&s, 0, 10.0f, NULL, &u), LBK_OK);
    check_invariants(&s, &u);
    assert_int_equal(u.chart_count, 1);
    assert_int_equal(u.tri_count, s.tri_count);
    for (size_t i = 0; i < u.tri_count; i++) {
        const float *q = u.uv + 6 * i;
        for (int k = 0; k < 3; k++) {
            const float *pa = s.positions + 3 * s.tris[3 * u.tris[i] + (size_t)k];
            const float *pb = s.positions + 3 * s.tris[3 * u.tris[i] + (size_t)((k + 1) % 3)];
            double wl = 0.0;
            for (int c = 0; c < 3; c++) wl += ((double)pb[c] - pa[c]) * ((double)pb[c] - pa[c]);
            double du = (double)q[2 * ((k + 1) % 3)] - q[2 * k], dv = (double)q[2 * ((k + 1) % 3) + 1] - q[2 * k + 1];
            assert_float_equal(sqrt(du * du + dv * dv), 10.0 * sqrt(wl), 1e-3);
        }
    }
    /* 0.25 m² + 0.05 m² + 0.0125 m² at 10 texels/m */
    assert_float_equal(chart_uv_area(&u), 100.0 * (0.25 + 0.05 + 0.0125), 0.02);
    bk_uv_object_free(&u);
    uvs_free(&s);

    uvs_init(&s);
    uvs_object(&s, "L");
    float f0[3] = {0, 0, 0}, f1[3] = {1, 0, 0}, f2[3] = {1, 0, -1}, f3[3] = {0, 0, -1};
    float w0[3] = {0, 0, 0}, w1[3] = {0, 0, -1}, w2[3] = {0, 1, -1}, w3[3] = {0, 1, 0};
    uvs_quad(&s, f0, f1, f2, f3, 1, 0, NULL, 1.0f);
    uvs_quad(&s, w0, w1, w2, w3, 1, 0, NULL, 1.0f);
    assert_int_equal(bk_uvgen_object(&s, 0, 10.0f, NULL, &u), LBK_OK);
    check_invariants(&s, &u);
    assert_int_equal(u.chart_count, 2);
    bk_uv_object_free(&u);
    uvs_free(&s);

    /* a 10 cm jamb at 90° along a 1 m panel: small (10 × 1 texels) but not tiny, and the fold is
     * a hard edge, so it keeps its own chart */
    uvs_init(&s);
    uvs_object(&s, "jamb");
    float j0[3] = {1, 0, 0}, j1[3] = {1, -0.1f, 0}, j2[3] = {1, -0.1f, -1}, j3[3] = {1, 0, -1};
    uvs_quad(&s, f0, f1, f2, f3, 1, 0, NULL, 1.0f);
    uvs_quad(&s, j0, j1, j2, j3, 1, 0, NULL, 1.0f);
    assert_int_equal(bk_uvgen_object(&s, 0, 10.0f, NULL, &u), LBK_OK);
    check_invariants(&s, &u);
    assert_int_equal(u.chart_count, 2);
    bk_uv_object_free(&u);
    uvs_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_overlap_counter),
        cmocka_unit_test(test_unit_quad_density),
        cmocka_unit_test(test_rotated_quad_min_area),
        cmocka_unit_test(test_cube_six_charts),
        cmocka_unit_test(test_cone_threshold),
        cmocka_unit_test(test_authored_uv1_kept),
        cmocka_unit_test(test_authored_uv1_rejected),
        cmocka_unit_test(test_degenerate_triangles),
        cmocka_unit_test(test_oversize_split),
        cmocka_unit_test(test_huge_triangle_keeps_object_density),
        cmocka_unit_test(test_sphere_charts),
        cmocka_unit_test(test_spiral_overlap_split),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_merge_small_charts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
