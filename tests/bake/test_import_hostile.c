/* glTF import of hostile input the tracer cannot take: the scene-extent limits (what float rays
 * can trace, checked once in the importer before Embree: spec/authoring.md "Scene extent"), the
 * tracer itself fed extreme values (no Embree assertion may fire), and extensionsRequired that
 * is not a subset of extensionsUsed. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/import.h"
#include "scene/scene.h"
#include "scene/tracer.h"
#include "support/import_fixtures.h"

static void expect_imports(const char *name)
{
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp(name, &s, NULL, err, sizeof err);
    if (rc) printf("%s: %s\n", name, err);
    assert_int_equal(rc, 0);
    imp_assert_valid(&s);
    bk_scene_free(&s);
}

/* A node scale of 1e18 (Embree's ray.valid() assertion in lbk bake before), 1e12 (the light
 * grid's "out of memory" before) and 1e7 (a 1e7 m level): refused, naming the node and extent. */
static void test_extent_scale(void **state)
{
    (void)state;
    imp_write_quad_bin();
    static const struct { const char *file, *scale, *needle; } cases[] = {
        {"scale1e18.gltf", "1e18", "beyond +-1e+09 m"},
        {"scale1e12.gltf", "1e12", "beyond +-1e+09 m"},
        {"scale1e7.gltf", "1e7", "extent reaches 1e+07 m"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char nodes[256];
        snprintf(nodes, sizeof nodes, "{\"name\":\"wall\",\"mesh\":0},{\"name\":\"giant\",\"mesh\":0,\"scale\":[%s,%s,%s]}",
                 cases[i].scale, cases[i].scale, cases[i].scale);
        imp_write_quad_gltf(cases[i].file, nodes, "0,1", NULL);
        imp_expect_error(cases[i].file, "node 1 \"giant\"", cases[i].needle);
    }
    /* the far side of the limit and everything the tests bake: 1e5 m, 1e5 m off the origin */
    imp_write_quad_gltf("scale1e5.gltf", "{\"name\":\"big\",\"mesh\":0,\"scale\":[1e5,1e5,1e5]}", "0", NULL);
    expect_imports("scale1e5.gltf");
    imp_write_quad_gltf("far1e8.gltf", "{\"name\":\"far\",\"mesh\":0,\"translation\":[1e8,0,-1e8]}", "0", NULL);
    expect_imports("far1e8.gltf");
}

/* Finite float positions near +-3e38 in the buffer: refused naming the node, not overflowing
 * (nor reaching Embree as 3e38-wide triangles). */
static void test_extent_positions(void **state)
{
    (void)state;
    static const float far_x[12] = {3e38f, 0, 0, 3e38f, 1, 0, 3e38f, 1, 1, 3e38f, 0, 1};
    static const float wide[12] = {-3e38f, 0, 0, 3e38f, 0, 0, 3e38f, 1, 0, -3e38f, 1, 0};
    imp_write_quad_bin_at(far_x);
    imp_write_quad_gltf("pos3e38.gltf", "{\"name\":\"edge\",\"mesh\":0}", "0", NULL);
    imp_expect_error("pos3e38.gltf", "node 0 \"edge\"", "3e+38 m");
    imp_write_quad_bin_at(wide);
    imp_write_quad_gltf("wide3e38.gltf", "{\"name\":\"span\",\"mesh\":0}", "0", NULL);
    imp_expect_error("wide3e38.gltf", "node 0 \"span\"", "beyond");
    imp_write_quad_bin();
}

/* An object too small for the level's float coordinates: 1e-4 m in a level reaching 1e3 m is a
 * ratio of 1e7 > 2^20; 1e-2 m (1e5) imports. */
static void test_extent_feature(void **state)
{
    (void)state;
    imp_write_quad_bin();
    imp_write_quad_gltf("speck.gltf",
                        "{\"name\":\"floor\",\"mesh\":0,\"scale\":[1000,1000,1]},"
                        "{\"name\":\"speck\",\"mesh\":0,\"scale\":[1e-4,1e-4,1e-4]}", "0,1", NULL);
    imp_expect_error("speck.gltf", "node 1 \"speck\"", "ratio");
    imp_write_quad_gltf("pebble.gltf",
                        "{\"name\":\"floor\",\"mesh\":0,\"scale\":[1000,1000,1]},"
                        "{\"name\":\"pebble\",\"mesh\":0,\"scale\":[1e-2,1e-2,1e-2]}", "0,1", NULL);
    expect_imports("pebble.gltf");
}

/* The tracer built over extreme (finite and non-finite) positions and asked extreme rays: every
 * call returns, no Embree assertion (ray.valid(): |org|, |dir| <= FLT_LARGE = 1.844e18). */
static void test_tracer_extremes(void **state)
{
    (void)state;
    static const float big[] = {3e38f, -3e38f, FLT_MAX, 1e18f, 2e18f, 1e30f, 1e-40f, 0.0f};
    const size_t nb = sizeof big / sizeof big[0];
    size_t nv = 3 * nb + 3, nt = nb + 1;
    float *pos = calloc(nv * 3, sizeof(float));
    uint32_t *tris = calloc(nt * 3, sizeof(uint32_t));
    assert_non_null(pos);
    assert_non_null(tris);
    for (size_t i = 0; i < nb; i++) { /* one triangle per value, at it and spanning it */
        float *p = pos + 9 * i;
        p[0] = big[i]; p[1] = 0; p[2] = 0;
        p[3] = big[i]; p[4] = big[i]; p[5] = 0;
        p[6] = 0; p[7] = big[i]; p[8] = big[i];
        tris[3 * i] = (uint32_t)(3 * i); tris[3 * i + 1] = (uint32_t)(3 * i + 1); tris[3 * i + 2] = (uint32_t)(3 * i + 2);
    }
    float *q = pos + 9 * nb; /* an ordinary triangle at z = 5 */
    q[0] = -1; q[1] = -1; q[2] = 5; q[3] = 1; q[4] = -1; q[5] = 5; q[6] = 0; q[7] = 1; q[8] = 5;
    tris[3 * nb] = (uint32_t)(3 * nb); tris[3 * nb + 1] = (uint32_t)(3 * nb + 1); tris[3 * nb + 2] = (uint32_t)(3 * nb + 2);
    bk_scene s;
    memset(&s, 0, sizeof s);
    s.positions = pos;
    s.tris = tris;
    s.vertex_count = nv;
    s.tri_count = nt;
    bk_tracer *t = NULL;
    lbk_result r = bk_tracer_create(&s, 1, &t);
    if (r != LBK_OK) { /* refusing is fine; asserting is not */
        free(pos);
        free(tris);
        return;
    }
    static const float vals[] = {0.0f, 1.0f, -1.0f, 1e18f, 1.9e18f, -2e18f, 1e30f, 3e38f, -FLT_MAX, 1e-40f, INFINITY, NAN};
    const size_t nval = sizeof vals / sizeof vals[0];
    static const float tmaxs[] = {INFINITY, FLT_MAX, 1e20f, 1.0f};
    size_t calls = 0;
    for (size_t a = 0; a < nval; a++)
        for (size_t b = 0; b < nval; b++)
            for (size_t m = 0; m < sizeof tmaxs / sizeof tmaxs[0]; m++) {
                float org[3] = {vals[a], 0.0f, vals[a]}, dir[3] = {vals[b], 0.5f, vals[b] == 0 ? 1.0f : vals[b]};
                bk_hit h;
                (void)bk_tracer_intersect(t, org, dir, 0.0f, tmaxs[m], &h);
                (void)bk_tracer_occluded(t, org, dir, 0.0f, tmaxs[m]);
                bk_hit hn[1];
                bk_tracer_intersect_n(t, 1, org, dir, 0.0f, &tmaxs[m], hn);
                calls++;
            }
    assert_true(calls > 0);
    /* the ordinary triangle still answers */
    float org[3] = {0, 0, 0}, dir[3] = {0, 0, 1};
    bk_hit h;
    assert_int_equal(bk_tracer_intersect(t, org, dir, 0.0f, INFINITY, &h), 1);
    assert_int_equal(h.tri, (uint32_t)nb);
    bk_tracer_destroy(t);
    free(pos);
    free(tris);
}

/* extensionsRequired must be a subset of extensionsUsed (glTF 2.0 §3.12). */
static void test_required_not_used(void **state)
{
    (void)state;
    imp_write_quad_bin();
    imp_write_quad_gltf("req_unused.gltf", "{\"mesh\":0}", "0",
                        "\"extensionsUsed\":[\"KHR_lights_punctual\"],"
                        "\"extensionsRequired\":[\"KHR_mesh_quantization\"],");
    imp_expect_error("req_unused.gltf", "\"KHR_mesh_quantization\"", "extensionsUsed");
    imp_write_quad_gltf("req_nothing_used.gltf", "{\"mesh\":0}", "0",
                        "\"extensionsRequired\":[\"KHR_lights_punctual\"],");
    imp_expect_error("req_nothing_used.gltf", "\"KHR_lights_punctual\"", "extensionsUsed");
    imp_write_quad_gltf("req_used.gltf", "{\"mesh\":0}", "0",
                        "\"extensionsUsed\":[\"KHR_lights_punctual\",\"KHR_mesh_quantization\"],"
                        "\"extensionsRequired\":[\"KHR_mesh_quantization\"],");
    expect_imports("req_used.gltf");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_extent_scale),
        cmocka_unit_test(test_extent_positions),
        cmocka_unit_test(test_extent_feature),
        cmocka_unit_test(test_tracer_extremes),
        cmocka_unit_test(test_required_not_used),
    };
    return cmocka_run_group_tests(tests, imp_setup_tmp, imp_teardown_tmp);
}
