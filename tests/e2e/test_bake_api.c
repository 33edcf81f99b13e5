/* liblbkbake's contract (lbk/bake.h) under ASan/UBSan, on in-memory scenes: the rules of the
 * desc (size field, enums, numbers) and of the scene description (indices, tiling, names,
 * lights) give the documented result with one ERROR message naming the fault; a cancelled
 * bake frees everything at every phase (ASan would see a leak); given normals and the implicit
 * single object bake to a valid container; a caller allocator sees every byte of the output.
 * Byte identity with `lbk bake` is tests/install/bake_check.c. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/bake.h"
#include "lbk/objects.h"
#include "lbk/validate.h"

/* ---- a small level: a 3 m room, a block, a lamp panel in a light set, a door, a bulb --------- */

typedef struct level {
    float pos[3 * 128], nrm[3 * 128];
    uint32_t idx[3 * 128];
    size_t nv, nt;
    lbk_bake_object obj[4];
    size_t n_obj;
    lbk_bake_light bulb;
    lbk_bake_scene scene;
} level;

static const lbk_bake_material mats[] = {
    {NULL, {0.6f, 0.6f, 0.6f}, {0, 0, 0}, 0},
    {NULL, {0.5f, 0.5f, 0.5f}, {2, 2, 2}, 1},
};

static void quad(level *l, const float p[4][3])
{
    uint32_t b = (uint32_t)l->nv;
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; k++) e1[k] = p[1][k] - p[0][k], e2[k] = p[2][k] - p[0][k];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int v = 0; v < 4; v++, l->nv++)
        for (int k = 0; k < 3; k++) {
            l->pos[3 * l->nv + k] = p[v][k];
            l->nrm[3 * l->nv + k] = (float)(n[k] / len);
        }
    uint32_t t[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
    memcpy(&l->idx[3 * l->nt], t, sizeof t);
    l->nt += 2;
}

static void box(level *l, const float mn[3], const float mx[3], int inward)
{
    static const int f[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (int k = 0; k < 6; k++) {
        float q[4][3];
        for (int v = 0; v < 4; v++) {
            int c = f[k][inward ? (4 - v) % 4 : v];
            q[v][0] = c & 1 ? mx[0] : mn[0], q[v][1] = c & 2 ? mx[1] : mn[1], q[v][2] = c & 4 ? mx[2] : mn[2];
        }
        quad(l, (const float(*)[3])q);
    }
}

static lbk_bake_object *object(level *l, const char *name, uint32_t material)
{
    lbk_bake_object *o = &l->obj[l->n_obj++];
    memset(o, 0, sizeof *o);
    o->name = name;
    o->first_triangle = (uint32_t)l->nt;
    o->material = material;
    return o;
}

/* with_sets: the lamp panel in light set "lamp" and the door "d1" (phase "sets" runs) */
static void level_init(level *l, int with_sets)
{
    memset(l, 0, sizeof *l);
    lbk_bake_object *o = object(l, "room", 0);
    o->lighting = LBK_BAKE_LIGHTING_LIGHTMAP;
    box(l, (const float[3]){-1.5f, 0, -1.5f}, (const float[3]){1.5f, 3, 1.5f}, 1);
    o->triangle_count = (uint32_t)l->nt - o->first_triangle;
    o = object(l, "block", 0);
    o->texel_density = 3;
    box(l, (const float[3]){-0.5f, 0, -0.5f}, (const float[3]){0.5f, 1, 0.5f}, 0);
    o->triangle_count = (uint32_t)l->nt - o->first_triangle;
    if (with_sets) {
        o = object(l, "panel", 1);
        o->light_set = "lamp";
        quad(l, (const float[4][3]){{0.5f, 2.9f, -1}, {0.5f, 2.9f, -0.5f}, {1, 2.9f, -0.5f}, {1, 2.9f, -1}});
        o->triangle_count = (uint32_t)l->nt - o->first_triangle;
        o = object(l, "door", 0);
        o->door = "d1";
        quad(l, (const float[4][3]){{-1.5f, 0, 0.5f}, {-1, 0, 0.5f}, {-1, 2, 0.5f}, {-1.5f, 2, 0.5f}});
        o->triangle_count = (uint32_t)l->nt - o->first_triangle;
    }
    l->bulb = (lbk_bake_light){"bulb", LBK_BAKE_LIGHT_POINT, {10, 10, 10}, {0, 2.5f, 1}, {0, 0, 0}, 0, 0, 0, NULL};
    lbk_bake_scene *s = &l->scene;
    s->name = "api";
    s->vertex_count = l->nv;
    s->positions = l->pos;
    s->triangle_count = l->nt;
    s->indices = l->idx;
    s->material_count = 2;
    s->materials = mats;
    s->object_count = l->n_obj;
    s->objects = l->obj;
    s->light_count = 1;
    s->lights = &l->bulb;
}

/* ---- running it ------------------------------------------------------------------------------ */

typedef struct seen {
    int errors, cancel_phase, last_phase;
    char error[1024];
} seen;

static void on_message(void *user, lbk_bake_severity severity, const char *message)
{
    seen *s = user;
    if (severity != LBK_BAKE_SEVERITY_ERROR) return;
    s->errors++;
    snprintf(s->error, sizeof s->error, "%s", message);
}

static int on_progress(void *user, const lbk_bake_progress *p)
{
    seen *s = user;
    s->last_phase = (int)p->phase;
    return (int)p->phase == s->cancel_phase;
}

static lbk_bake_desc quick(seen *s)
{
    memset(s, 0, sizeof *s);
    s->cancel_phase = -1;
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.seed = 1;
    d.max_samples = 16;
    d.threads = 2;
    d.texel_density = 2;
    d.message = on_message;
    d.progress = on_progress;
    d.user = s;
    return d;
}

/* Expects result `want` with one ERROR message containing `needle`. */
static void expect_fail(const lbk_bake_scene *scene, const lbk_bake_desc *d, seen *s, lbk_result want, const char *needle)
{
    lbk_bake_output *out = (lbk_bake_output *)s;
    lbk_result r = lbk_bake_from_scene(scene, d, &out);
    print_message("  %s: %s\n", lbk_result_name(r), s->error);
    assert_int_equal(r, want);
    assert_null(out);
    assert_int_equal(s->errors, 1);
    assert_non_null(strstr(s->error, needle));
}

/* ---- tests ----------------------------------------------------------------------------------- */

static void test_desc_rules(void **state)
{
    (void)state;
    level l;
    level_init(&l, 0);
    seen s;
    /* a newer caller's larger desc: accepted when the unknown tail is zero (the bake then fails
     * on the scene, not on the desc) */
    struct {
        lbk_bake_desc d;
        uint64_t future[2];
    } big;
    memset(&big, 0, sizeof big);
    big.d = quick(&s);
    big.d.size = sizeof big;
    lbk_bake_scene empty = l.scene;
    empty.triangle_count = 0, empty.object_count = 0;
    expect_fail(&empty, &big.d, &s, LBK_ERR_BAD_INPUT, "no triangles");
    big.d = quick(&s);
    big.d.size = sizeof big;
    big.future[1] = 1;
    expect_fail(&l.scene, &big.d, &s, LBK_ERR_INVALID_ARGUMENT, "does not know");
    lbk_bake_desc d = quick(&s);
    d.preset = (lbk_bake_preset)7;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "preset");
    d = quick(&s);
    d.texel_density = NAN;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "texel_density");
    d = quick(&s);
    d.sky_override = 1;
    d.sky[1] = -1;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "sky");
    d = quick(&s);
    d.size = sizeof d; /* (size 0 is version 1, which has no culling fields) */
    d.light_culling = 2;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "light_culling: 2");
    d = quick(&s);
    d.size = sizeof d;
    d.light_culling_delta = NAN;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "light_culling_delta");
    d = quick(&s);
    d.size = sizeof d; /* (the glossy VPL fields: added in 1.7) */
    d.glossy_vpl = -2;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "glossy_vpl: -2");
    d = quick(&s);
    d.size = sizeof d;
    d.glossy_vpl_photons = -1;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "glossy_vpl_photons");
    d = quick(&s);
    d.size = sizeof d;
    d.glossy_vpl_delta = INFINITY;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "glossy_vpl_delta");
    d = quick(&s);
    d.size = sizeof d; /* (added in 1.8) */
    d.adaptive = 1;
    expect_fail(&l.scene, &d, &s, LBK_ERR_INVALID_ARGUMENT, "adaptive: 1");
    d = quick(&s);
    d.size = 2; /* not even its own size field: nothing in it can be read, no message */
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&l.scene, &d, &out), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(s.errors, 0);
    assert_int_equal(lbk_bake_from_scene(NULL, NULL, &out), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_bake_from_file(NULL, NULL, &out), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_bake_from_scene(&l.scene, NULL, NULL), LBK_ERR_INVALID_ARGUMENT);
    assert_null(out);
}

static void test_scene_rules(void **state)
{
    (void)state;
    level l;
    level_init(&l, 1);
    seen s;
    lbk_bake_desc d = quick(&s);
    uint32_t idx[3 * 128];
    memcpy(idx, l.idx, sizeof idx);
    lbk_bake_scene bad = l.scene;
    idx[5] = (uint32_t)l.nv;
    bad.indices = idx;
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "triangle 1: vertex index");

    bad = l.scene;
    lbk_bake_object obj[4];
    memcpy(obj, l.obj, sizeof obj);
    bad.objects = obj;
    obj[1].first_triangle++;
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "tile");
    memcpy(obj, l.obj, sizeof obj);
    obj[3].triangle_count--;
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "every triangle needs an object");
    memcpy(obj, l.obj, sizeof obj);
    obj[2].material = 9;
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "object 2: material 9");
    memcpy(obj, l.obj, sizeof obj);
    obj[2].light_set = "a name that is much longer than the sixty-three bytes a set name may have";
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "63 printable bytes");

    float pos[3 * 128];
    memcpy(pos, l.pos, sizeof pos);
    pos[4] = NAN;
    bad = l.scene;
    bad.positions = pos;
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "vertex 1: NaN");

    lbk_bake_light spot = l.bulb;
    spot.type = LBK_BAKE_LIGHT_SPOT;
    spot.inner_cone = 1, spot.outer_cone = 0.5f;
    bad = l.scene;
    bad.lights = &spot;
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "spot cone");

    static const char *const pairs[][2] = {{"d1", "nowhere"}};
    bad = l.scene;
    bad.combinations = pairs;
    bad.combination_count = 1;
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_BAD_INPUT, "'nowhere' is neither a door");

    level dark;
    level_init(&dark, 0);
    dark.scene.light_count = 0;
    d = quick(&s);
    expect_fail(&dark.scene, &d, &s, LBK_ERR_BAD_INPUT, "no light");

    bad = l.scene;
    bad.positions = NULL;
    d = quick(&s);
    expect_fail(&bad, &d, &s, LBK_ERR_INVALID_ARGUMENT, "NULL");
}

/* A cancel at each phase's first checkpoint: LBK_ERR_CANCELLED, no output, no message; any
 * leak on those paths fails the binary under ASan. */
static void test_cancel_every_phase(void **state)
{
    (void)state;
    level l;
    level_init(&l, 1);
    for (int ph = 0; ph < LBK_BAKE_PHASE_COUNT_; ph++) {
        seen s;
        lbk_bake_desc d = quick(&s);
        s.cancel_phase = ph;
        lbk_bake_output *out = (lbk_bake_output *)&s;
        assert_int_equal(lbk_bake_from_scene(&l.scene, &d, &out), LBK_ERR_CANCELLED);
        assert_null(out);
        assert_int_equal(s.errors, 0);
        assert_int_equal(s.last_phase, ph);
    }
}

/* Given normals, no object table (one object named after the scene), no triangle materials:
 * a valid container whose OBJS has that one object. */
static void test_normals_and_one_object(void **state)
{
    (void)state;
    level l;
    level_init(&l, 0);
    l.scene.normals = l.nrm;
    l.scene.object_count = 0;
    l.scene.objects = NULL;
    seen s;
    lbk_bake_desc d = quick(&s);
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&l.scene, &d, &out), LBK_OK);
    const lbk_bake_report *r = lbk_bake_output_report(out);
    assert_int_equal(r->counts.objects, 1);
    assert_true(r->counts.texels > 0);
    assert_int_equal(r->counts.light_sets, 0);
    assert_int_equal(r->phase_count, 4); /* no "sets" phase */
    void *bytes;
    size_t size;
    assert_int_equal(lbk_bake_output_container(out, &bytes, &size), LBK_OK);
    assert_int_equal(size, r->counts.file_bytes);
    lbk_validate_summary vs;
    assert_int_equal(lbk_validate_memory(bytes, size, NULL, NULL, NULL, &vs), LBK_OK);
    assert_int_equal(vs.fatal + vs.errors, 0);
    lbk_reader *rd;
    assert_int_equal(lbk_reader_open_memory(bytes, size, NULL, &rd), LBK_OK);
    const void *objs;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_OBJS, &objs, &n), LBK_OK);
    lbk_objects_view v;
    assert_int_equal(lbk_objects_open(objs, n, &v), LBK_OK);
    assert_int_equal(v.count, 1);
    lbk_object o;
    assert_int_equal(lbk_objects_get(&v, 0, &o), LBK_OK);
    assert_int_equal(o.name.size, 3);
    assert_memory_equal(o.name.data, "api", 3);
    lbk_reader_close(rd);
    lbk_free(NULL, bytes);
    lbk_bake_output_free(out);
}

/* Each lightmapped object's estimate (report.object_estimates, 1.9): one per object with texels,
 * named as in the scene, and — unfiltered (--denoise off), where each is the texel class's sum
 * taken over the object's texels alone — pooling them with their weights gives back the
 * class's estimate exactly: Σ_o rel_o²·value2_o / Σ_o value2_o = errors.texels². Denoised, the
 * noise parts pool to the denoised figure's noise part (the bias clamp is per object). */
static void test_object_estimates(void **state)
{
    (void)state;
    for (int denoise = 0; denoise < 2; denoise++) {
        level l;
        level_init(&l, 0);
        seen s;
        lbk_bake_desc d = quick(&s);
        d.max_samples = 64;
        d.denoise = denoise ? LBK_BAKE_DENOISE_ON : LBK_BAKE_DENOISE_OFF;
        /* the noise estimate's pooling: without the path check, which takes the larger figure
         * per object (test_path_check) */
        d.size = sizeof d;
        d.path_check = -1;
        lbk_bake_output *out = NULL;
        assert_int_equal(lbk_bake_from_scene(&l.scene, &d, &out), LBK_OK);
        const lbk_bake_report *r = lbk_bake_output_report(out);
        assert_int_equal(r->object_estimate_count, 2); /* room and block */
        assert_string_equal(r->object_estimates[0].name, "room");
        assert_string_equal(r->object_estimates[1].name, "block");
        double num = 0, noise = 0, den = 0;
        uint64_t texels = 0;
        for (size_t k = 0; k < r->object_estimate_count; k++) {
            const lbk_bake_object_estimate *e = &r->object_estimates[k];
            assert_true(e->texels > 0 && e->rel_rmse > 0 && e->value2 > 0);
            assert_true(fabs(e->rel_rmse * e->rel_rmse - e->noise * e->noise - e->bias * e->bias) <=
                        1e-9 * e->rel_rmse * e->rel_rmse);
            num += e->rel_rmse * e->rel_rmse * e->value2;
            noise += e->noise * e->noise * e->value2;
            den += e->value2;
            texels += e->texels;
        }
        const double pooled = sqrt(num / den), pooled_noise = sqrt(noise / den);
        const double want = denoise ? r->denoised.errors.texels : r->errors.texels;
        print_message("  denoise %s: %zu objects, %llu texels; pooled %.5f, the bake's texel estimate %.5f "
                      "(noise %.5f / %.5f)\n", denoise ? "on" : "off", r->object_estimate_count,
                      (unsigned long long)texels, pooled, want, pooled_noise,
                      denoise ? r->denoised.texel_noise : r->errors.texels);
        if (!denoise) assert_true(fabs(pooled - want) <= 1e-5 * want);
        else assert_true(fabs(pooled_noise - r->denoised.texel_noise) <= 1e-5 * r->denoised.texel_noise);
        lbk_bake_output_free(out);
    }
}

typedef struct counting {
    long live, calls;
} counting;

static void *count_alloc(void *user, size_t size)
{
    counting *c = user;
    c->live++, c->calls++;
    return malloc(size);
}

static void count_free(void *user, void *p)
{
    counting *c = user;
    if (p) c->live--;
    free(p);
}

/* The output, its report and the container bytes come from the caller's allocator. */
static void test_allocator_sees_the_output(void **state)
{
    (void)state;
    level l;
    level_init(&l, 0);
    counting c = {0, 0};
    lbk_allocator a = {count_alloc, count_free, &c};
    seen s;
    lbk_bake_desc d = quick(&s);
    d.allocator = &a;
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&l.scene, &d, &out), LBK_OK);
    long after_bake = c.live;
    assert_true(after_bake >= 3); /* the output, its passes, its input name, the writer's sections */
    void *bytes;
    size_t size;
    assert_int_equal(lbk_bake_output_container(out, &bytes, &size), LBK_OK);
    assert_int_equal(c.live, after_bake + 1);
    lbk_free(&a, bytes);
    char *json;
    size_t jn;
    assert_int_equal(lbk_bake_report_json(lbk_bake_output_report(out), "x.lbk", &a, &json, &jn), LBK_OK);
    assert_int_equal(strlen(json), jn);
    assert_non_null(strstr(json, "\"output\":\t\"x.lbk\""));
    lbk_free(&a, json);
    lbk_bake_output_free(out);
    assert_int_equal(c.live, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_desc_rules),
        cmocka_unit_test(test_scene_rules),
        cmocka_unit_test(test_cancel_every_phase),
        cmocka_unit_test(test_normals_and_one_object),
        cmocka_unit_test(test_object_estimates),
        cmocka_unit_test(test_allocator_sees_the_output),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
