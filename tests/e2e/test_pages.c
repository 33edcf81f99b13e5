/* Lightmap pages under a maximum size (lbk_bake_desc.max_page, `lbk bake --max-page`), through
 * the whole pipeline on a generated glTF level: six 30 × 30 m floor tiles and one object made of a
 * 200 m triangle and a 4 m box, at 2 texels/m with pages of at most 128 texels.
 *
 * What must hold, derived from the layout rules (bake/layout/atlas.h):
 *  - a tile is one 60 × 60 texel chart, a 62 × 62 rectangle with its margins; two fit across a
 *    128 page, three do not, so a page holds at most four tiles and the level needs at least
 *    two pages; no page side exceeds 128;
 *  - every tile keeps 2 texels/m: its triangles' area in lightmap texels (LMUV, the coordinates
 *    an engine draws with) is 900 m² × 2² = 3600;
 *  - the 200 m triangle (400 texels at 2 texels/m) cannot fit a page: only its own chart gets a
 *    lower density (noted), the box of the same object keeps 2 texels/m (96 m² × 4 = 384);
 *  - the container validates, and the bytes are the same at 1 and 2 threads;
 *  - the report's peak RSS per phase is a high-water mark: between the process's before and after
 *    the call, never falling, and in the JSON report. */
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
#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/lightmap_uv.h"
#include "lbk/objects.h"
#include "lbk/validate.h"
#include "support/gltf_writer.h"
#include <sys/resource.h>
#include <unistd.h>

#define TILES 6
#define MAX_PAGE 128
#define DENSITY 2.0f

/* The level as a .gltf (LMUV, where the density is measured, is written for glTF levels). */
static void write_level(const char *path)
{
    gw_scene *sc = gw_create();
    float grey[3] = {0.5f, 0.5f, 0.5f}, sky[3] = {1, 1, 1};
    int mat = gw_material(sc, grey, NULL, 0, 0);
    for (int i = 0; i < TILES; i++) {
        gw_geom g = {0};
        float x = 32.0f * (float)i;
        float p0[3] = {x, 0, 0}, p1[3] = {x + 30, 0, 0}, p2[3] = {x + 30, 0, -30}, p3[3] = {x, 0, -30};
        gw_geom_quad(&g, p0, p1, p2, p3, 1);
        char name[16];
        snprintf(name, sizeof name, "tile%d", i);
        gw_mesh(sc, name, &g, mat, 1, NULL, "lightmap");
        gw_geom_free(&g);
    }
    gw_geom g = {0};
    uint32_t a = gw_geom_vertex(&g, 0, -1, 40), b = gw_geom_vertex(&g, 200, -1, 40), c = gw_geom_vertex(&g, 0, -1, -160);
    gw_geom_tri(&g, a, b, c);
    float mn[3] = {10, -1, 10}, mx[3] = {14, 3, 14};
    gw_geom_box(&g, mn, mx, 1, 0);
    gw_mesh(sc, "ground_and_box", &g, mat, 1, NULL, "lightmap");
    gw_geom_free(&g);
    gw_sky(sc, sky);
    assert_int_equal(gw_write(sc, path), 0);
    gw_free(sc);
}

typedef struct notes {
    int big_triangle_note;
} notes;

static void on_message(void *user, lbk_bake_severity severity, const char *message)
{
    notes *n = user;
    if (severity == LBK_BAKE_SEVERITY_NOTE && strstr(message, "object 'ground_and_box'") &&
        strstr(message, "1 triangle longer than"))
        n->big_triangle_note = 1;
}

/* The process's peak resident set so far, bytes (as the baker measures it). */
static uint64_t peak_rss(void)
{
    struct rusage ru;
    assert_int_equal(getrusage(RUSAGE_SELF, &ru), 0);
    return (uint64_t)ru.ru_maxrss * 1024u;
}

static void bake(const char *path, int threads, notes *n, void **bytes, size_t *size)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.seed = 7;
    d.max_samples = 8;
    d.target_error = -1;
    d.threads = threads;
    d.texel_density = DENSITY;
    d.no_glg = 1;
    d.max_page = MAX_PAGE;
    d.message = on_message;
    d.user = n;
    lbk_bake_output *out = NULL;
    uint64_t before = peak_rss();
    assert_int_equal(lbk_bake_from_file(path, &d, &out), LBK_OK);
    uint64_t after = peak_rss();
    assert_int_equal(lbk_bake_output_container(out, bytes, size), LBK_OK);
    /* the report's peak RSS per phase: a high-water mark, so it lies between what the process
     * had reached before the call and after it, and never falls from one phase to the next */
    const lbk_bake_report *r = lbk_bake_output_report(out);
    assert_non_null(r->phase_peak_rss);
    assert_true(r->phase_count >= 4);
    for (size_t i = 0; i < r->phase_count; i++) {
        assert_true(r->phase_peak_rss[i] >= before && r->phase_peak_rss[i] <= after);
        if (i) assert_true(r->phase_peak_rss[i] >= r->phase_peak_rss[i - 1]);
    }
    char *json = NULL;
    size_t jn = 0;
    assert_int_equal(lbk_bake_report_json(r, "x.lbk", NULL, &json, &jn), LBK_OK);
    char want[96];
    snprintf(want, sizeof want, "\"peak_rss_bytes\":\t%llu", (unsigned long long)r->phase_peak_rss[0]);
    if (!strstr(json, want)) fail_msg("%s not in the JSON report", want);
    assert_non_null(strstr(json, "\"peak_rss_bytes_per_texel\":"));
    lbk_free(NULL, json);
    lbk_bake_output_free(out);
}

/* Σ |area| of a GENERATED record's triangles in lightmap texels; *largest gets the largest one's. */
static double lmuv_texel_area(const lbk_lmuv_view *v, const lbk_lmuv_object *rec, double *largest)
{
    double sum = 0.0;
    *largest = 0.0;
    for (uint32_t p = 0; p < rec->primitive_count; p++) {
        lbk_lmuv_primitive pr;
        assert_int_equal(lbk_lmuv_get_primitive(v, rec->primitive_first + p, &pr), LBK_OK);
        for (uint32_t i = 0; i + 2 < pr.index_count; i += 3) {
            float c[3][2];
            for (int k = 0; k < 3; k++) {
                uint32_t idx, src;
                assert_int_equal(lbk_lmuv_index(v, &pr, i + (uint32_t)k, &idx), LBK_OK);
                assert_int_equal(lbk_lmuv_vertex(v, &pr, idx, &src, c[k]), LBK_OK);
            }
            double a = 0.5 * fabs(((double)c[1][0] - c[0][0]) * ((double)c[2][1] - c[0][1]) -
                                  ((double)c[2][0] - c[0][0]) * ((double)c[1][1] - c[0][1]));
            sum += a;
            if (a > *largest) *largest = a;
        }
    }
    return sum;
}

static void test_pages_under_the_maximum(void **state)
{
    (void)state;
    char path[64];
    snprintf(path, sizeof path, "/tmp/lbk-pages-%d.gltf", (int)getpid());
    write_level(path);
    notes n1 = {0}, n2 = {0};
    void *b1 = NULL, *b2 = NULL;
    size_t s1 = 0, s2 = 0;
    bake(path, 1, &n1, &b1, &s1);
    bake(path, 2, &n2, &b2, &s2);
    unlink(path);
    assert_int_equal(s1, s2);
    assert_memory_equal(b1, b2, s1);
    assert_true(n1.big_triangle_note);

    lbk_validate_summary vs;
    assert_int_equal(lbk_validate_memory(b1, s1, NULL, NULL, NULL, &vs), LBK_OK);
    assert_int_equal(vs.fatal + vs.errors, 0);

    lbk_reader *rd;
    assert_int_equal(lbk_reader_open_memory(b1, s1, NULL, &rd), LBK_OK);
    const void *sec;
    size_t len;
    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_LMAP, &sec, &len), LBK_OK);
    lbk_lmap_view lm;
    assert_int_equal(lbk_lmap_open(sec, len, &lm), LBK_OK);
    /* at most four 62-texel tiles per 128 page: six need two pages, the big object a third or
     * a place beside two tiles */
    assert_true(lm.page_count >= (TILES + 3) / 4);
    for (uint32_t p = 0; p < lm.page_count; p++) {
        lbk_lmap_page pg;
        assert_int_equal(lbk_lmap_page_get(&lm, p, &pg), LBK_OK);
        assert_true(pg.width <= MAX_PAGE && pg.height <= MAX_PAGE);
    }

    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_OBJS, &sec, &len), LBK_OK);
    lbk_objects_view ov;
    assert_int_equal(lbk_objects_open(sec, len, &ov), LBK_OK);
    assert_int_equal(ov.count, TILES + 1);
    uint32_t pages_used = 0;
    for (uint32_t i = 0; i < ov.count; i++) {
        lbk_object o;
        assert_int_equal(lbk_objects_get(&ov, i, &o), LBK_OK);
        assert_int_equal(o.representation, LBK_REPRESENTATION_LIGHTMAP);
        assert_true(o.index < lm.page_count);
        assert_true(o.rect_w <= MAX_PAGE && o.rect_h <= MAX_PAGE);
        pages_used |= 1u << o.index;
    }
    assert_int_equal(pages_used, (1u << lm.page_count) - 1); /* no empty page */

    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_LMUV, &sec, &len), LBK_OK);
    lbk_lmuv_view uv;
    assert_int_equal(lbk_lmuv_open(sec, len, &uv), LBK_OK);
    const double d2 = (double)DENSITY * DENSITY;
    for (uint32_t i = 0; i <= TILES; i++) {
        uint32_t rec;
        assert_int_equal(lbk_lmuv_find_object(&uv, i, &rec), LBK_OK);
        lbk_lmuv_object r;
        assert_int_equal(lbk_lmuv_get_object(&uv, rec, &r), LBK_OK);
        assert_int_equal(r.kind, LBK_LMUV_GENERATED);
        double largest, area = lmuv_texel_area(&uv, &r, &largest);
        if (i < TILES) {
            assert_float_equal(area, 900.0 * d2, 900.0 * d2 * 1e-4);
        } else {
            /* the box at the density asked for; the 20000 m² triangle well below it */
            assert_float_equal(area - largest, 96.0 * d2, 96.0 * d2 * 1e-3);
            assert_true(largest < 20000.0 * d2 * 0.25);
            assert_true(largest > 0.0);
        }
    }
    lbk_reader_close(rd);
    lbk_free(NULL, b1);
    lbk_free(NULL, b2);
}

/* The desc's ranges: a page below LBK_BAKE_MAX_PAGE_MIN or above the spec's 16384, a probe cap
 * below one tetrahedron's 4, are refused before anything is read. */
static void test_limits_refused(void **state)
{
    (void)state;
    const struct { int max_page; uint32_t max_probes; } bad[] = {{32, 0}, {16388, 0}, {0, 3}, {0, (1u << 28) + 1}};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        lbk_bake_desc d;
        memset(&d, 0, sizeof d);
        d.size = sizeof d;
        d.max_page = bad[i].max_page;
        d.max_probes = bad[i].max_probes;
        lbk_bake_output *out = NULL;
        assert_int_equal(lbk_bake_from_file("/nonexistent.gltf", &d, &out), LBK_ERR_INVALID_ARGUMENT);
        assert_null(out);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pages_under_the_maximum),
        cmocka_unit_test(test_limits_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
