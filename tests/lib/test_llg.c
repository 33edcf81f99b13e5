/* LLG: lattice positions, trilinear sampling (exact for fields linear in the box frame),
 * clamping outside the box, per-vertex visibility encoding and apply. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/llg.h"
#include "lbk/octa.h"

/* A box rotated 30° about z, centred at (10, −2, 3), half extents (2, 1, 4), lattice 5×3×9. */
static const float C[3] = {10.0f, -2.0f, 3.0f};
static const float H[3] = {2.0f, 1.0f, 4.0f};
static float A[3][3];

static void init_axes(void)
{
    const float c = cosf(0.5235988f), s = sinf(0.5235988f);
    const float a[3][3] = {{c, s, 0}, {-s, c, 0}, {0, 0, 1}};
    memcpy(A, a, sizeof A);
}

/* DC exactly representable in RGB9E5 at lattice points: 8 + i + 2j + k (i, j, k lattice). */
static float lattice_field(float gi, float gj, float gk) { return 8.0f + gi + 2.0f * gj + gk; }

static void build(void **bytes, size_t *size, lbk_llg_vertex *verts, uint32_t nv)
{
    init_axes();
    static lbk_sh9_rgb probes[5 * 3 * 9];
    memset(probes, 0, sizeof probes);
    for (int k = 0; k < 9; k++)
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 5; i++) {
                lbk_sh9_rgb *p = &probes[i + 5 * (j + 3 * k)];
                for (int c = 0; c < 3; c++) p->c[c][0] = lattice_field((float)i, (float)j, (float)k);
                p->c[1][2] = 0.5f * p->c[1][0]; /* some band-1 content: L10 = 0.5 L00 */
            }
    lbk_llg_grid_desc g;
    memset(&g, 0, sizeof g);
    memcpy(g.centre, C, sizeof C);
    memcpy(g.axes, A, sizeof A);
    memcpy(g.half_extents, H, sizeof H);
    g.dims[0] = 5;
    g.dims[1] = 3;
    g.dims[2] = 9;
    g.probes = probes;
    g.vertices = verts;
    g.vertex_count = nv;
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g, .grid_count = 1}, NULL, bytes, size), LBK_OK);
}

static void to_world(const float l[3], float w[3])
{
    for (int c = 0; c < 3; c++) w[c] = C[c] + A[0][c] * l[0] * H[0] + A[1][c] * l[1] * H[1] + A[2][c] * l[2] * H[2];
}

static void lattice_and_trilinear(void **state)
{
    (void)state;
    void *bytes;
    size_t size;
    build(&bytes, &size, NULL, 0);
    /* 32 + 96 = 128; 135 probes × 28 = 3780 → 3908 → vertices at 3920, none */
    assert_int_equal(size, 3920);
    lbk_llg_view v;
    assert_int_equal(lbk_llg_open(bytes, size, &v), LBK_OK);
    assert_int_equal(v.probe_count, 135);
    lbk_llg_grid g;
    assert_int_equal(lbk_llg_grid_get(&v, 0, &g), LBK_OK);
    float p[3], expect[3];
    lbk_llg_probe_position(&g, 4, 0, 8, p);
    const float corner[3] = {1, -1, 1};
    to_world(corner, expect);
    for (int c = 0; c < 3; c++) assert_true(fabsf(p[c] - expect[c]) < 1e-5f);
    /* the field is trilinear (linear) in lattice coordinates, so sampling reproduces it */
    for (int t = 0; t < 200; t++) {
        const float l[3] = {-1.0f + 2.0f * (float)((t * 37) % 101) / 100.0f, -1.0f + 2.0f * (float)((t * 53) % 97) / 96.0f,
                            -1.0f + 2.0f * (float)((t * 71) % 89) / 88.0f};
        float w[3];
        to_world(l, w);
        lbk_sh9_rgb sh;
        assert_int_equal(lbk_llg_sample(&v, 0, w, &sh), LBK_OK);
        const float gi = (l[0] + 1) * 0.5f * 4, gj = (l[1] + 1) * 0.5f * 2, gk = (l[2] + 1) * 0.5f * 8;
        const float f = lattice_field(gi, gj, gk);
        assert_true(fabsf(sh.c[0][0] - f) < 1e-4f * f);
        assert_true(fabsf(sh.c[1][2] - 0.5f * f) < 0.01f * f); /* snorm8 band-1 ratio */
    }
    /* outside the box: clamped to the nearest box point */
    const float lo[3] = {1.0f, -1.0f, 0.25f}, lo_out[3] = {1.7f, -3.0f, 0.25f};
    float w0[3], w1[3];
    to_world(lo, w0);
    to_world(lo_out, w1);
    lbk_sh9_rgb s0, s1;
    lbk_llg_sample(&v, 0, w0, &s0);
    lbk_llg_sample(&v, 0, w1, &s1);
    assert_memory_equal(&s0, &s1, sizeof s0);
    assert_true(fabsf(s0.c[0][0] - lattice_field(4, 0, 5)) < 1e-4f);
    assert_int_equal(lbk_llg_sample(&v, 1, w0, &s0), LBK_ERR_NOT_FOUND);
    lbk_free(NULL, bytes);
}

static void vertex_visibility(void **state)
{
    (void)state;
    /* encoding: unorm8 visibility, octahedral bent normal, reserved 0 */
    uint32_t seed = 5u;
    double worst = 0.0;
    for (int t = 0; t < 5000; t++) {
        seed = seed * 1664525u + 1013904223u;
        const double z = ((seed >> 8) & 0xffff) / 32767.5 - 1.0;
        seed = seed * 1664525u + 1013904223u;
        const double ph = ((seed >> 8) & 0xffff) / 65536.0 * 6.283185307179586, r = sqrt(1 - z * z);
        lbk_llg_vertex in = {(float)(t % 256) / 255.0f, {(float)(r * cos(ph)), (float)(r * sin(ph)), (float)z}}, out;
        uint8_t b[4];
        lbk_llg_vertex_pack(&in, b);
        assert_int_equal(b[3], 0);
        assert_int_equal(b[0], t % 256);
        lbk_llg_vertex_unpack(b, &out);
        assert_true(out.visibility == in.visibility);
        const double dot = in.bent_normal[0] * out.bent_normal[0] + in.bent_normal[1] * out.bent_normal[1] +
                           in.bent_normal[2] * out.bent_normal[2];
        worst = fmax(worst, acos(fmin(1.0, dot)));
    }
    /* 8+8-bit octahedral: half a step of 2/255 in u and v, times the map's largest stretch (about
     * 2.8 rad per unit near the equator diagonals) gives < 1°, as Cigolle et al. 2014 report */
    printf("LLG bent normal: worst angular error %.3f deg\n", worst * 180.0 / 3.14159265);
    assert_true(worst < 1.0 * 3.14159265 / 180.0);
    assert_true(worst > 0.05 * 3.14159265 / 180.0);
    /* apply: E = V · E_sh(bent normal in world) */
    lbk_llg_vertex verts[2] = {{0.5f, {0, 0, 1}}, {1.0f, {1, 0, 0}}};
    void *bytes;
    size_t size;
    build(&bytes, &size, verts, 2);
    lbk_llg_view v;
    assert_int_equal(lbk_llg_open(bytes, size, &v), LBK_OK);
    const float l[3] = {0.0f, 0.0f, 0.0f};
    float w[3];
    to_world(l, w);
    float e0[3], e1[3];
    assert_int_equal(lbk_llg_vertex_irradiance(&v, 0, 0, w, e0), LBK_OK);
    assert_int_equal(lbk_llg_vertex_irradiance(&v, 0, 1, w, e1), LBK_OK);
    lbk_sh9_rgb sh;
    lbk_llg_sample(&v, 0, w, &sh);
    float ref0[3], ref1[3];
    const float up[3] = {0, 0, 1};
    lbk_sh9_irradiance(&sh, up, ref0);
    lbk_sh9_irradiance(&sh, A[0], ref1); /* vertex 1's bent normal is axis0 */
    for (int c = 0; c < 3; c++) {
        /* V = 128/255 after unorm8; the bent normal is off by < 1° */
        assert_true(fabsf(e0[c] - (128.0f / 255.0f) * ref0[c]) < 1e-2f * ref0[c]);
        assert_true(fabsf(e1[c] - ref1[c]) < 2e-2f * ref1[c]);
    }
    /* the band-1 z content (green) makes +Z brighter than the box's x axis */
    assert_true(e0[1] * (255.0f / 128.0f) > e1[1] * 1.05f);
    assert_int_equal(lbk_llg_vertex_irradiance(&v, 0, 2, w, e0), LBK_ERR_NOT_FOUND);
    lbk_free(NULL, bytes);
}

static void builder_rejects(void **state)
{
    (void)state;
    init_axes();
    lbk_sh9_rgb probes[8];
    memset(probes, 0, sizeof probes);
    lbk_llg_grid_desc g;
    memset(&g, 0, sizeof g);
    memcpy(g.axes, A, sizeof A);
    g.half_extents[0] = g.half_extents[1] = g.half_extents[2] = 1.0f;
    g.dims[0] = g.dims[1] = g.dims[2] = 2;
    g.probes = probes;
    void *out;
    size_t size;
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g, .grid_count = 1}, NULL, &out, &size), LBK_OK);
    lbk_free(NULL, out);
    g.dims[1] = 1;
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g,
        .grid_count = 1}, NULL, &out, &size), LBK_ERR_INVALID_ARGUMENT);
    g.dims[1] = 65;
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g,
        .grid_count = 1}, NULL, &out, &size), LBK_ERR_INVALID_ARGUMENT);
    g.dims[1] = 2;
    g.axes[0][0] *= 1.01f; /* not unit */
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g,
        .grid_count = 1}, NULL, &out, &size), LBK_ERR_INVALID_ARGUMENT);
    memcpy(g.axes, A, sizeof A);
    g.half_extents[2] = 0.0f;
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g,
        .grid_count = 1}, NULL, &out, &size), LBK_ERR_INVALID_ARGUMENT);
}

/* The vertex order of §11 on hand-made primitives: unused vertices get no record, flat
 * primitives one per corner, numbering runs on across primitives; bad input is refused. */
static void vertex_order(void **state)
{
    (void)state;
    const uint32_t tri_a[6] = {4, 1, 2, 2, 1, 4}; /* vertices 0 and 3 unused */
    const uint32_t tri_b[3] = {1, 0, 1};          /* flat: corners 0..2 */
    const uint32_t tri_c[3] = {2, 0, 1};
    const lbk_llg_source_primitive prim[3] = {
        {.vertex_count = 5, .index_count = 6, .indices = tri_a},
        {.vertex_count = 2, .index_count = 3, .indices = tri_b, .flat = 1},
        {.vertex_count = 3, .index_count = 3, .indices = tri_c},
    };
    uint32_t map[11], n = 0;
    assert_int_equal(lbk_llg_vertex_map(prim, 3, map, 11, &n), LBK_OK);
    const uint32_t X = LBK_LLG_NO_VERTEX;
    const uint32_t want[11] = {X, 0, 1, X, 2, /* flat */ 3, 4, 5, /* third */ 6, 7, 8};
    assert_memory_equal(map, want, sizeof want);
    assert_int_equal(n, 9);
    assert_int_equal(lbk_llg_vertex_map(prim, 3, map, 10, &n), LBK_ERR_INVALID_ARGUMENT); /* map_count */
    lbk_llg_source_primitive bad = prim[0];
    bad.vertex_count = 4; /* index 4 out of range */
    assert_int_equal(lbk_llg_vertex_map(&bad, 1, map, 4, &n), LBK_ERR_INVALID_ARGUMENT);
    bad = prim[0];
    bad.index_count = 5;
    assert_int_equal(lbk_llg_vertex_map(&bad, 1, map, 5, &n), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_llg_vertex_map(NULL, 0, NULL, 0, &n), LBK_OK);
    assert_int_equal(n, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lattice_and_trilinear),
        cmocka_unit_test(vertex_visibility),
        cmocka_unit_test(builder_rejects),
        cmocka_unit_test(vertex_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
