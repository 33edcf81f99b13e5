/* The ABI rules of lbk.h: the run-time version equals the headers' and lbk.pc's; size-tagged
 * structs read size 0 as the 1.0 layout, refuse a size below it, accept a newer caller's larger
 * struct whose unknown bytes are zero and refuse one that uses them; the experimental DLS tuning
 * reaches the builder; every _close takes NULL. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define LBK_STATIC_LINKING_ONLY /* lbk_dls_tuning, lbk_dls_stats */
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/lightmap.h"
#include "lbk/report.h"
#include "lbk/validate.h"
#include "support/container_fixture.h"
#include "support/dls_fixture.h"

static void test_version_functions(void **state)
{
    (void)state;
    assert_int_equal(lbk_version_number(), LBK_LIBRARY_VERSION_NUMBER);
    assert_int_equal(lbk_version_number(),
                     LBK_LIBRARY_VERSION_MAJOR * 10000 + LBK_LIBRARY_VERSION_MINOR * 100 + LBK_LIBRARY_VERSION_PATCH);
    char want[32];
    snprintf(want, sizeof want, "%d.%d.%d", LBK_LIBRARY_VERSION_MAJOR, LBK_LIBRARY_VERSION_MINOR,
             LBK_LIBRARY_VERSION_PATCH);
    assert_string_equal(lbk_version_string(), want);
    assert_string_equal(LBK_LIBRARY_VERSION_STRING, want);
    /* The format version is what the writer stamps into a file, whatever the library's is: the
     * lowest minor that defines every section in it (spec §1.3), so 0 for this file of 1.0
     * sections, while the library reads up to LBK_FORMAT_VERSION_MINOR. */
    void *bytes;
    size_t size;
    assert_int_equal(fixture_small_container(0, &bytes, &size), 0);
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_memory(bytes, size, NULL, &r), LBK_OK);
    assert_int_equal(lbk_reader_header(r)->version_major, LBK_FORMAT_VERSION_MAJOR);
    assert_int_equal(lbk_reader_header(r)->version_minor, 0);
    assert_true(LBK_FORMAT_VERSION_MINOR >= 1); /* 1.1: LMUV */
    lbk_reader_close(r);
    free(bytes);
}

/* `make` writes $(BUILD)/lbk.pc with the Version taken from lbk.h. */
static void test_pc_version_is_the_header_version(void **state)
{
    (void)state;
    const char *build = getenv("BUILD") ? getenv("BUILD") : "build";
    char path[512], line[256], want[64];
    snprintf(path, sizeof path, "%s/lbk.pc", build);
    FILE *f = fopen(path, "r");
    if (!f) skip(); /* the test binary was built without `make all` */
    snprintf(want, sizeof want, "Version: %s\n", lbk_version_string());
    int found = 0;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "Version:", 8)) {
            assert_string_equal(line, want);
            found++;
        }
    fclose(f);
    assert_int_equal(found, 1);
}

/* A caller compiled against a newer liblbk: its struct is the current one plus a field. */
#define NEWER(T) struct { T cur; uint64_t newer_field; }

static lbk_result open_writer(const lbk_write_options *o, uint32_t *alignment)
{
    lbk_writer *w;
    lbk_result r = lbk_writer_open(o, &w);
    if (r != LBK_OK) return r;
    static const uint8_t payload[16] = {1};
    void *bytes;
    size_t size;
    assert_int_equal(lbk_writer_section_add(w, LBK_FOURCC('X', 'T', 'R', 'A'), payload, sizeof payload, NULL), LBK_OK);
    assert_int_equal(lbk_writer_to_memory(w, &bytes, &size), LBK_OK);
    lbk_reader *rd;
    assert_int_equal(lbk_reader_open_memory(bytes, size, NULL, &rd), LBK_OK);
    *alignment = lbk_reader_header(rd)->section_alignment;
    lbk_reader_close(rd);
    lbk_free(NULL, bytes);
    lbk_writer_close(w);
    return LBK_OK;
}

static void test_size_tag_write_options(void **state)
{
    (void)state;
    uint32_t a = 0;
    assert_int_equal(open_writer(NULL, &a), LBK_OK);
    assert_int_equal(a, LBK_DEFAULT_ALIGNMENT);
    /* size 0 (a zero-initialised struct): the 1.0 layout, fields honoured */
    lbk_write_options zero = {.section_alignment = 16};
    assert_int_equal(open_writer(&zero, &a), LBK_OK);
    assert_int_equal(a, 16);
    lbk_write_options init = LBK_WRITE_OPTIONS_INIT;
    assert_int_equal(init.size, sizeof init);
    init.section_alignment = 256;
    assert_int_equal(open_writer(&init, &a), LBK_OK);
    assert_int_equal(a, 256);
    /* a size below the 1.0 layout */
    lbk_write_options small = {.size = offsetof(lbk_write_options, section_alignment), .section_alignment = 16};
    assert_int_equal(open_writer(&small, &a), LBK_ERR_INVALID_ARGUMENT);
    /* a newer caller: unknown bytes zero → accepted, set → refused */
    NEWER(lbk_write_options) big;
    memset(&big, 0, sizeof big);
    big.cur.size = sizeof big;
    big.cur.section_alignment = 32;
    assert_int_equal(open_writer(&big.cur, &a), LBK_OK);
    assert_int_equal(a, 32);
    big.newer_field = 1;
    assert_int_equal(open_writer(&big.cur, &a), LBK_ERR_UNSUPPORTED_FEATURE);
}

static void test_size_tag_other_structs(void **state)
{
    (void)state;
    void *bytes;
    size_t size;
    assert_int_equal(fixture_small_container(0, &bytes, &size), 0);
    lbk_reader *r;

    NEWER(lbk_read_options) ro;
    memset(&ro, 0, sizeof ro);
    ro.cur.size = 1;
    assert_int_equal(lbk_reader_open_memory(bytes, size, &ro.cur, &r), LBK_ERR_INVALID_ARGUMENT);
    ro.cur.size = sizeof ro;
    ro.cur.max_decoded_bytes = 1; /* honoured: the zstd REPT section no longer fits */
    assert_int_equal(lbk_reader_open_memory(bytes, size, &ro.cur, &r), LBK_OK);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_REPT, &d, &n), LBK_ERR_LIMIT);
    lbk_reader_close(r);
    ro.newer_field = 7;
    assert_int_equal(lbk_reader_open_memory(bytes, size, &ro.cur, &r), LBK_ERR_UNSUPPORTED_FEATURE);

    NEWER(lbk_validate_options) vo;
    memset(&vo, 0, sizeof vo);
    vo.cur.size = sizeof vo;
    lbk_validate_summary sum;
    assert_int_equal(lbk_validate_memory(bytes, size, &vo.cur, NULL, NULL, &sum), LBK_OK);
    assert_int_equal(sum.fatal + sum.errors, 0);
    vo.newer_field = 1;
    assert_int_equal(lbk_validate_memory(bytes, size, &vo.cur, NULL, NULL, &sum), LBK_ERR_UNSUPPORTED_FEATURE);
    vo.cur.size = 4;
    assert_int_equal(lbk_validate_memory(bytes, size, &vo.cur, NULL, NULL, &sum), LBK_ERR_INVALID_ARGUMENT);

    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    NEWER(lbk_section_options) so;
    memset(&so, 0, sizeof so);
    so.cur.size = sizeof so;
    so.newer_field = 1;
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, bytes, 16, &so.cur), LBK_ERR_UNSUPPORTED_FEATURE);
    so.cur.size = offsetof(lbk_section_options, zstd_level);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, bytes, 16, &so.cur), LBK_ERR_INVALID_ARGUMENT);
    lbk_writer_close(w);
    free(bytes);

    /* a build desc: the lightmap's, whose scale lives in it */
    const lbk_ahd_texel t = {0x3c00u, {255, 128, 128, 255}};
    const lbk_lmap_page_desc page = {1, 1, &t};
    NEWER(lbk_lmap_build_desc) lb;
    memset(&lb, 0, sizeof lb);
    lb.cur = (lbk_lmap_build_desc){.size = sizeof lb, .pages = &page, .page_count = 1, .scale = 0x1p-3f};
    void *lm;
    assert_int_equal(lbk_lmap_build(&lb.cur, NULL, &lm, &n), LBK_OK);
    lbk_lmap_view v;
    assert_int_equal(lbk_lmap_open(lm, n, &v), LBK_OK);
    assert_true(v.scale == 0x1p-3f);
    lbk_free(NULL, lm);
    lb.newer_field = 1;
    assert_int_equal(lbk_lmap_build(&lb.cur, NULL, &lm, &n), LBK_ERR_UNSUPPORTED_FEATURE);
    assert_null(lm);
    lb.cur.size = sizeof(size_t);
    assert_int_equal(lbk_lmap_build(&lb.cur, NULL, &lm, &n), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_lmap_build(NULL, NULL, &lm, &n), LBK_ERR_INVALID_ARGUMENT);

    /* the report: lbk_report_open hands back a header that builds again */
    const lbk_report_record rec = {0, 100, 4, 1, 0.5f, 0};
    lbk_report rep = LBK_REPORT_INIT;
    rep.status = LBK_BAKE_SAMPLE_LIMIT, rep.records = &rec, rep.record_count = 1;
    void *rb;
    assert_int_equal(lbk_report_build(&rep, NULL, &rb, &n), LBK_OK);
    lbk_report_view rv;
    assert_int_equal(lbk_report_open(rb, n, &rv), LBK_OK);
    assert_int_equal(rv.header.size, sizeof(lbk_report));
    assert_int_equal(rv.header.status, LBK_BAKE_SAMPLE_LIMIT);
    lbk_free(NULL, rb);
    rep.size = 2;
    assert_int_equal(lbk_report_build(&rep, NULL, &rb, &n), LBK_ERR_INVALID_ARGUMENT);
}

/* The experimental tuning reaches the builder through the stable options struct. */
static void test_dls_tuning_through_options(void **state)
{
    (void)state;
    dlsfx fx;
    dlsfx_init(&fx, 2, 1000, 0, 0);
    uint64_t rng = 1;
    dlsfx_add_range(&fx, &rng, 0, 0, 0, 100);
    dlsfx_add_range(&fx, &rng, 1, 0, 300, 100);
    void *a, *b;
    size_t na, nb;
    lbk_dls_stats sa, sb;
    assert_int_equal(lbk_dls_build(&fx.desc, NULL, &a, &na, &sa), LBK_OK);
    const lbk_dls_tuning tune = {.min_dispatch_targets = 1};
    const lbk_dls_build_options opt = {.size = sizeof opt, .tuning = &tune};
    assert_int_equal(lbk_dls_build(&fx.desc, &opt, &b, &nb, &sb), LBK_OK);
    /* by default the two small single-set combinations share one packed dispatch; with a
     * minimum of one target each stays its own */
    assert_int_equal(sa.cluster_count, 1);
    assert_int_equal(sb.cluster_count, 2);
    NEWER(lbk_dls_build_options) big;
    memset(&big, 0, sizeof big);
    big.cur.size = sizeof big;
    big.newer_field = 1;
    void *c;
    size_t nc;
    assert_int_equal(lbk_dls_build(&fx.desc, &big.cur, &c, &nc, NULL), LBK_ERR_UNSUPPORTED_FEATURE);
    lbk_free(NULL, a);
    lbk_free(NULL, b);
    dlsfx_free(&fx);
}

static void test_close_takes_null(void **state)
{
    (void)state;
    lbk_reader_close(NULL);
    lbk_writer_close(NULL);
    lbk_dls_close(NULL);
    lbk_door_close(NULL);
    lbk_dls_runtime_close(NULL);
    lbk_free(NULL, NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_version_functions),
        cmocka_unit_test(test_pc_version_is_the_header_version),
        cmocka_unit_test(test_size_tag_write_options),
        cmocka_unit_test(test_size_tag_other_structs),
        cmocka_unit_test(test_dls_tuning_through_options),
        cmocka_unit_test(test_close_takes_null),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
