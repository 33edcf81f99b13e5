/* Built by `make test` against an installed copy of liblbk (pkg-config, headers from
 * include/lbk/), once with liblbk.so and once with liblbk.a: proves that the install is usable
 * by an engine on its own — the headers are self-contained, the exported symbols are there and
 * the pkg-config flags link. Reads the committed golden container. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <lbk/container.h>
#include <lbk/meta.h>
#include <lbk/validate.h>

static void test_golden_opens_and_validates(void **state)
{
    (void)state;
    lbk_validate_summary s;
    assert_int_equal(lbk_validate_file("tests/golden/small.lbk", NULL, NULL, NULL, &s), LBK_OK);
    assert_int_equal(s.fatal + s.errors, 0);
    /* the installed library is the one the installed headers describe */
    assert_int_equal(lbk_version_number(), LBK_LIBRARY_VERSION_NUMBER);
    assert_string_equal(lbk_version_string(), LBK_LIBRARY_VERSION_STRING);
    lbk_reader *r;
    const lbk_read_options ro = LBK_READ_OPTIONS_INIT;
    assert_int_equal(lbk_reader_open_file("tests/golden/small.lbk", &ro, &r), LBK_OK);
    assert_true(lbk_reader_section_count(r) >= 1);
    assert_int_equal(lbk_reader_header(r)->version_major, LBK_FORMAT_VERSION_MAJOR);
    const void *data;
    size_t size;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_META, &data, &size), LBK_OK);
    lbk_meta_view v;
    assert_int_equal(lbk_meta_open(data, size, &v), LBK_OK);
    assert_true(v.entry_count > 0);
    lbk_reader_close(r);
    assert_string_equal(lbk_result_name(LBK_ERR_CHECKSUM), "LBK_ERR_CHECKSUM");
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_golden_opens_and_validates)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
