/* GLG and the tetrahedral walk: barycentric exactness on a Kuhn-split 2×2×2 block of cubes,
 * hints, outside-hull clamping, visibility weighting, orientation fixing, and termination on
 * malicious adjacency. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/tetra.h"

/* 3×3×3 lattice points (0..2 on each axis), 8 unit cubes, each split into 6 tetras along its
 * main diagonal (Kuhn): {c, c+e_a, c+e_a+e_b, c+(1,1,1)} for every permutation (a, b, c). */
#define NP 27
#define NT 48
static float pos[NP][3];
static uint32_t tets[NT][4];

static uint32_t vidx(int x, int y, int z) { return (uint32_t)(x + 3 * (y + 3 * z)); }

static void make_mesh(void)
{
    for (int z = 0; z < 3; z++)
        for (int y = 0; y < 3; y++)
            for (int x = 0; x < 3; x++) {
                pos[vidx(x, y, z)][0] = (float)x;
                pos[vidx(x, y, z)][1] = (float)y;
                pos[vidx(x, y, z)][2] = (float)z;
            }
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    int t = 0;
    for (int cz = 0; cz < 2; cz++)
        for (int cy = 0; cy < 2; cy++)
            for (int cx = 0; cx < 2; cx++)
                for (int p = 0; p < 6; p++) {
                    int c[3] = {cx, cy, cz};
                    tets[t][0] = vidx(c[0], c[1], c[2]);
                    c[perms[p][0]]++;
                    tets[t][1] = vidx(c[0], c[1], c[2]);
                    c[perms[p][1]]++;
                    tets[t][2] = vidx(c[0], c[1], c[2]);
                    c[perms[p][2]]++;
                    tets[t][3] = vidx(c[0], c[1], c[2]);
                    t++;
                }
}

/* A linear field with values exactly representable in RGB9E5: 1 + x + 2y + 4z ∈ [1, 15]. */
static float field(const float p[3]) { return 1.0f + p[0] + 2.0f * p[1] + 4.0f * p[2]; }

typedef struct fixture {
    void *bytes;
    size_t size;
    lbk_glg_view view;
    uint8_t vis[NT][4];
} fixture;

static void build(fixture *f, const uint8_t (*vis)[4])
{
    make_mesh();
    lbk_sh9_rgb probes[NP];
    memset(probes, 0, sizeof probes);
    for (int i = 0; i < NP; i++)
        for (int c = 0; c < 3; c++) probes[i].c[c][0] = field(pos[i]) * (float)(c + 1);
    lbk_glg_build_desc desc = {.probe_count = NP, .tetra_count = NT, .positions = (const float(*)[3])pos,
        .probes = probes, .tetras = (const uint32_t(*)[4])tets, .visibility = vis};
    assert_int_equal(lbk_glg_build(&desc, NULL, &f->bytes, &f->size), LBK_OK);
    assert_int_equal(lbk_glg_open(f->bytes, f->size, &f->view), LBK_OK);
}

static uint32_t rng_next(uint32_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    return *s;
}
static float rndf(uint32_t *s) { return (float)((rng_next(s) >> 8) * (1.0 / 16777216.0)); }

static void barycentric_exact_for_linear_fields(void **state)
{
    (void)state;
    fixture f;
    build(&f, NULL);
    /* the builder oriented every tetra positively */
    for (uint32_t t = 0; t < NT; t++) {
        float p[4][3];
        for (int k = 0; k < 4; k++) {
            const uint32_t v = (uint32_t)f.view.mesh.tetras[16 * t + 4 * k] | ((uint32_t)f.view.mesh.tetras[16 * t + 4 * k + 1] << 8);
            memcpy(p[k], pos[v], sizeof p[k]);
        }
        assert_true(lbk_tetra_orient(p[0], p[1], p[2], p[3]) > 0.0);
    }
    uint32_t seed = 2024u, hint = 0;
    for (int i = 0; i < 2000; i++) {
        const float p[3] = {2.0f * rndf(&seed), 2.0f * rndf(&seed), 2.0f * rndf(&seed)};
        lbk_tetra_location loc, loc2;
        assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, 0, &loc), LBK_OK);
        assert_true(loc.inside);
        assert_false(loc.scanned);
        float s = 0.0f, q[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++) {
            assert_true(loc.bary[k] >= 0.0f);
            s += loc.bary[k];
            for (int c = 0; c < 3; c++) q[c] += loc.bary[k] * pos[loc.vertices[k]][c];
        }
        assert_true(fabsf(s - 1.0f) < 1e-6f);
        for (int c = 0; c < 3; c++) assert_true(fabsf(q[c] - p[c]) < 1e-5f);
        /* a walk started in the right tetra takes one step and agrees */
        assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, loc.tetra, &loc2), LBK_OK);
        assert_int_equal(loc2.tetra, loc.tetra);
        assert_int_equal(loc2.steps, 1);
        /* sampling reproduces the linear field in every channel */
        lbk_sh9_rgb sh;
        lbk_glg_sample_info info;
        assert_int_equal(lbk_glg_sample(&f.view, p, &hint, &sh, &info), LBK_OK);
        assert_int_equal(hint, info.location.tetra);
        for (int c = 0; c < 3; c++) assert_true(fabsf(sh.c[c][0] - field(p) * (float)(c + 1)) < 1e-4f * field(p) * (c + 1));
    }
    /* a walk across the block: from the tetra at the origin corner to the far corner */
    const float far[3] = {1.9f, 1.95f, 1.99f};
    lbk_tetra_location loc;
    assert_int_equal(lbk_tetra_locate(&f.view.mesh, far, 0, &loc), LBK_OK);
    assert_true(loc.inside && loc.steps > 3 && loc.steps <= NT);
    lbk_free(NULL, f.bytes);
}

static void outside_hull_clamps(void **state)
{
    (void)state;
    fixture f;
    build(&f, NULL);
    const float p[3] = {2.6f, 0.7f, 1.3f};
    for (uint32_t start = 0; start < NT; start += 7) {
        lbk_tetra_location loc;
        assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, start, &loc), LBK_OK);
        assert_false(loc.inside);
        float s = 0.0f, q[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++) {
            assert_true(loc.bary[k] >= 0.0f);
            s += loc.bary[k];
            for (int c = 0; c < 3; c++) q[c] += loc.bary[k] * pos[loc.vertices[k]][c];
        }
        assert_true(fabsf(s - 1.0f) < 1e-6f);
        /* the blended point lies on the hull face x = 2 */
        assert_true(fabsf(q[0] - 2.0f) < 1e-5f);
        assert_true(q[1] >= 0.0f && q[1] <= 2.0f && q[2] >= 0.0f && q[2] <= 2.0f);
    }
    lbk_free(NULL, f.bytes);
}

static void visibility_weights(void **state)
{
    (void)state;
    fixture f0;
    build(&f0, NULL);
    const float p[3] = {0.3f, 0.55f, 0.8f};
    lbk_tetra_location loc;
    assert_int_equal(lbk_tetra_locate(&f0.view.mesh, p, 0, &loc), LBK_OK);
    const uint32_t t = loc.tetra;
    /* the view's vertex order of t after building, for mapping vis entries */
    static uint8_t vis[NT][4];
    memset(vis, 255, sizeof vis);
    vis[t][0] = 255;
    vis[t][1] = 0;
    vis[t][2] = 51; /* 0.2 */
    vis[t][3] = 255;
    lbk_free(NULL, f0.bytes);
    fixture f;
    build(&f, (const uint8_t(*)[4])vis);
    lbk_glg_sample_info info;
    lbk_sh9_rgb sh;
    assert_int_equal(lbk_glg_sample(&f.view, p, NULL, &sh, &info), LBK_OK);
    assert_int_equal(info.location.tetra, t);
    const float *b = info.location.bary;
    const float w0 = b[0], w1 = 0.0f, w2 = b[2] * 0.2f, w3 = b[3], s = w0 + w1 + w2 + w3;
    /* the orientation swap (if any) moved entries 2↔3 together with their vis values */
    const uint8_t *sv = f.view.visibility + 4 * t;
    float expect[4];
    for (int k = 0; k < 4; k++) expect[k] = b[k] * (float)sv[k] / 255.0f;
    float es = expect[0] + expect[1] + expect[2] + expect[3];
    for (int k = 0; k < 4; k++) assert_true(fabsf(info.weights[k] - expect[k] / es) < 1e-6f);
    assert_true(fabsf(es - s) < 1e-6f || fabsf(es - (w0 + b[3] * 0.2f + b[2])) < 1e-6f);
    float z = 0.0f;
    for (int k = 0; k < 4; k++) if (sv[k] == 0) z += info.weights[k];
    assert_true(z == 0.0f);
    lbk_free(NULL, f.bytes);
    /* all zero: plain barycentrics */
    memset(vis, 255, sizeof vis);
    memset(vis[t], 0, 4);
    build(&f, (const uint8_t(*)[4])vis);
    assert_int_equal(lbk_glg_sample(&f.view, p, NULL, &sh, &info), LBK_OK);
    for (int k = 0; k < 4; k++) assert_true(info.weights[k] == info.location.bary[k]);
    lbk_free(NULL, f.bytes);
}

static void malicious_adjacency_terminates(void **state)
{
    (void)state;
    fixture f;
    build(&f, NULL);
    uint8_t *bytes = f.bytes;
    /* every neighbour link points to the next tetra: the walk cycles, hits the cap, scans */
    uint8_t *adj = (uint8_t *)f.view.mesh.adjacency;
    for (uint32_t t = 0; t < NT; t++)
        for (int k = 0; k < 4; k++) {
            const uint32_t n = (t + 1) % NT;
            adj[16 * t + 4 * k] = (uint8_t)n;
            adj[16 * t + 4 * k + 1] = adj[16 * t + 4 * k + 2] = adj[16 * t + 4 * k + 3] = 0;
        }
    const float p[3] = {1.7f, 0.2f, 1.4f};
    lbk_tetra_location loc;
    assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, 5, &loc), LBK_OK);
    assert_true(loc.inside);
    assert_true(loc.steps <= NT + 64);
    float q[3] = {0, 0, 0};
    for (int k = 0; k < 4; k++)
        for (int c = 0; c < 3; c++) q[c] += loc.bary[k] * pos[loc.vertices[k]][c];
    for (int c = 0; c < 3; c++) assert_true(fabsf(q[c] - p[c]) < 1e-5f);
    /* a self-loop across every face */
    for (uint32_t t = 0; t < NT; t++)
        for (int k = 0; k < 4; k++) {
            adj[16 * t + 4 * k] = (uint8_t)t;
        }
    assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, 0, &loc), LBK_OK);
    assert_true(loc.scanned || loc.tetra == 0);
    /* out-of-range neighbour and vertex indices are reported, never followed */
    adj[16 * 0 + 0] = 200;
    for (int k = 0; k < 4; k++) adj[16 * 0 + 4 * k] = 200;
    assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, 0, &loc), LBK_ERR_CORRUPT);
    uint8_t *tv = (uint8_t *)f.view.mesh.tetras;
    tv[0] = 99; /* vertex 99 of 27 */
    assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, 0, &loc), LBK_ERR_CORRUPT);
    /* a degenerate tetra (two equal vertices) */
    tv[0] = tv[4];
    assert_int_equal(lbk_tetra_locate(&f.view.mesh, p, 0, &loc), LBK_ERR_CORRUPT);
    const float nanp[3] = {NAN, 0, 0};
    assert_int_equal(lbk_tetra_locate(&f.view.mesh, nanp, 0, &loc), LBK_ERR_INVALID_ARGUMENT);
    lbk_free(NULL, bytes);
}

static void builder_rejects_bad_meshes(void **state)
{
    (void)state;
    make_mesh();
    lbk_sh9_rgb probes[NP];
    memset(probes, 0, sizeof probes);
    void *out;
    size_t size;
    uint32_t bad[NT][4];
    memcpy(bad, tets, sizeof bad);
    bad[3][2] = bad[3][1]; /* zero volume */
    lbk_glg_build_desc d = {.probe_count = NP, .tetra_count = NT, .positions = (const float(*)[3])pos,
        .probes = probes, .tetras = (const uint32_t(*)[4])bad};
    assert_int_equal(lbk_glg_build(&d, NULL, &out, &size), LBK_ERR_INVALID_ARGUMENT);
    memcpy(bad, tets, sizeof bad);
    bad[3][2] = NP; /* out of range */
    assert_int_equal(lbk_glg_build(&d, NULL, &out, &size), LBK_ERR_INVALID_ARGUMENT);
    /* a tetra listed twice: its faces are shared three ways */
    memcpy(bad, tets, sizeof bad);
    memcpy(bad[1], bad[0], sizeof bad[0]);
    assert_int_equal(lbk_glg_build(&d, NULL, &out, &size), LBK_ERR_INVALID_ARGUMENT);
    /* derived adjacency: 8 cubes × 6 tetras have 6·2·4 = 48 hull faces (2 per cube face on the
     * surface: 6 sides × 4 squares × 2 triangles) */
    lbk_glg_build_desc good = {.probe_count = NP, .tetra_count = NT, .positions = (const float(*)[3])pos,
        .probes = probes, .tetras = (const uint32_t(*)[4])tets};
    assert_int_equal(lbk_glg_build(&good, NULL, &out, &size), LBK_OK);
    lbk_glg_view v;
    assert_int_equal(lbk_glg_open(out, size, &v), LBK_OK);
    int hull = 0;
    for (uint32_t i = 0; i < NT * 4; i++) {
        const uint8_t *a = v.mesh.adjacency + 4 * i;
        if (a[0] == 0xff && a[1] == 0xff && a[2] == 0xff && a[3] == 0xff) hull++;
    }
    assert_int_equal(hull, 48);
    /* size: 32 + 27·12 → 356 → 368, + 27·28 = 1124 → 1136, + 48·16·2 + 48·4 = 1728 */
    assert_int_equal(size, 1136 + 48 * 36);
    lbk_free(NULL, out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(barycentric_exact_for_linear_fields), cmocka_unit_test(outside_hull_clamps),
        cmocka_unit_test(visibility_weights),                  cmocka_unit_test(malicious_adjacency_terminates),
        cmocka_unit_test(builder_rejects_bad_meshes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
