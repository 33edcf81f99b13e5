/* Linked into the ThreadSanitizer test binaries (`make tsan`) with
 * -Wl,--wrap=_cmocka_run_group_tests: runs only the cases whose name matches LBK_TEST_FILTER
 * (a cmocka glob), so tests/run.sh can pick the determinism cases listed in
 * tests/tsan/determinism.list out of the ordinary test binaries without touching their mains. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>

int __real__cmocka_run_group_tests(const char *group_name, const struct CMUnitTest *const tests, const size_t num_tests,
                                   CMFixtureFunction group_setup, CMFixtureFunction group_teardown);
int __wrap__cmocka_run_group_tests(const char *group_name, const struct CMUnitTest *const tests, const size_t num_tests,
                                   CMFixtureFunction group_setup, CMFixtureFunction group_teardown);

int __wrap__cmocka_run_group_tests(const char *group_name, const struct CMUnitTest *const tests, const size_t num_tests,
                                   CMFixtureFunction group_setup, CMFixtureFunction group_teardown)
{
    const char *filter = getenv("LBK_TEST_FILTER");
    if (filter && *filter) cmocka_set_test_filter(filter);
    return __real__cmocka_run_group_tests(group_name, tests, num_tests, group_setup, group_teardown);
}
