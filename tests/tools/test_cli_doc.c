/* The command line's documentation and the table of bake options (cli/bake_options.c):
 *  - docs/cli.md is what tools/dev/gen_cli_doc.sh writes from the built lbk ($LBK, else
 *    $BUILD/lbk, else build/lbk; skipped without one): a help text changed without running the
 *    script fails here;
 *  - the texel density's range is the library's (LBK_BAKE_TEXEL_DENSITY_MIN/MAX, lbk/bake.h)
 *    at both ends, with the table's message;
 *  - cli_bake_flag and cli_bake_plan_neutral answer from the table. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/bake_options.h"
#include "cli/cli.h"
#include "lbk/bake.h"

static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap + 1);
    assert_non_null(buf);
    size_t r;
    while ((r = fread(buf + n, 1, cap - n, f)) > 0) {
        n += r;
        if (n == cap) {
            cap *= 2;
            buf = realloc(buf, cap + 1);
            assert_non_null(buf);
        }
    }
    fclose(f);
    buf[n] = 0;
    *size = n;
    return buf;
}

static const char *find_lbk(char *buf, size_t size)
{
    const char *env = getenv("LBK");
    if (env && *env && access(env, X_OK) == 0) return env;
    const char *build = getenv("BUILD");
    snprintf(buf, size, "%s/lbk", build && *build ? build : "build");
    return access(buf, X_OK) == 0 ? buf : NULL;
}

static void test_cli_md_is_generated(void **state)
{
    (void)state;
    char path[4096];
    const char *lbk = find_lbk(path, sizeof path);
    if (!lbk) {
        printf("SKIPPED: no lbk binary (set LBK, or build $BUILD/lbk)\n");
        skip();
    }
    char tmp[] = "/tmp/lbk-cli-doc-XXXXXX";
    int fd = mkstemp(tmp);
    assert_true(fd >= 0);
    close(fd);
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "sh tools/dev/gen_cli_doc.sh '%s' '%s'", lbk, tmp);
    assert_int_equal(system(cmd), 0);
    size_t want_n = 0, have_n = 0;
    char *want = slurp(tmp, &want_n), *have = slurp("docs/cli.md", &have_n);
    assert_non_null(want);
    if (!have || want_n != have_n || memcmp(want, have, want_n)) {
        printf("docs/cli.md is not what `sh tools/dev/gen_cli_doc.sh %s` writes; run it (without the\n"
               "second argument) and commit docs/cli.md. The difference:\n", lbk);
        fflush(stdout);
        snprintf(cmd, sizeof cmd, "diff -u docs/cli.md '%s' | head -n 60", tmp);
        if (system(cmd)) { /* diff's status is the difference itself */ }
        unlink(tmp);
        fail_msg("docs/cli.md is out of date");
    }
    /* what the document must hold: every command's usage, the bake options from the table */
    assert_non_null(strstr(have, "## lbk bake\n"));
    assert_non_null(strstr(have, "## lbk view\n"));
    assert_non_null(strstr(have, "  --texel-density D "));
    free(want);
    free(have);
    unlink(tmp);
}

/* Runs lbk_cmd_bake on the arguments with stderr in a temporary file; the exit code, the text. */
static int bake_cmd(char *err, size_t err_size, int argc, const char **argv)
{
    char path[] = "/tmp/lbk-cli-doc-err-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    fflush(stderr);
    int saved = dup(2);
    dup2(fd, 2);
    int rc = lbk_cmd_bake(argc, (char **)argv);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    ssize_t n = pread(fd, err, err_size - 1, 0);
    err[n > 0 ? n : 0] = 0;
    close(fd);
    unlink(path);
    return rc;
}

static void test_texel_density_range(void **state)
{
    (void)state;
    char want[256], err[1024], max[64], above[64];
    snprintf(max, sizeof max, "%g", LBK_BAKE_TEXEL_DENSITY_MAX);
    snprintf(above, sizeof above, "%g", LBK_BAKE_TEXEL_DENSITY_MAX * 1.001);
    snprintf(want, sizeof want, "is not a number in (%g, %g]", LBK_BAKE_TEXEL_DENSITY_MIN, LBK_BAKE_TEXEL_DENSITY_MAX);
    const char *bad[] = {"0", "-1", above, "1e-50", "nan", "inf", "2x"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        int rc = bake_cmd(err, sizeof err, 4, (const char *[]){"bake", "s.gltf", "--texel-density", bad[i], NULL});
        assert_int_equal(rc, LBK_EXIT_USAGE);
        assert_non_null(strstr(err, "--texel-density"));
        assert_non_null(strstr(err, want));
    }
    /* the top of the range parses: what stops the bake is the missing -o */
    const char *good[] = {max, "0.001"};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        int rc = bake_cmd(err, sizeof err, 4, (const char *[]){"bake", "s.gltf", "--texel-density", good[i], NULL});
        assert_int_equal(rc, LBK_EXIT_USAGE);
        assert_non_null(strstr(err, "need a scene and -o OUT.lbk"));
    }
    bake_args o;
    int quiet = 0;
    assert_int_equal(cli_bake_parse(3, (char *[]){"bake", "--texel-density", max, NULL}, &o, &quiet), -1);
    assert_true(o.d.texel_density == (float)LBK_BAKE_TEXEL_DENSITY_MAX);
}

static void test_table_answers(void **state)
{
    (void)state;
    const char *flags[] = {"--no-glg", "--octahedral", "--glg-lighting", "--llg-connected", "--error-map",
                           "--block-align", "--timestamp", "-q", "--quiet", "-h", "--help"};
    for (size_t i = 0; i < sizeof flags / sizeof flags[0]; i++) assert_true(cli_bake_flag(flags[i]));
    const char *valued[] = {"-o", "--seed", "--texel-density", "--target-error", "--sky", "--resume", "--units", "--nonsense"};
    for (size_t i = 0; i < sizeof valued / sizeof valued[0]; i++) assert_false(cli_bake_flag(valued[i]));
    const char *neutral[] = {"-o", "--output", "--plan", "--units", "--makefile", "--sbatch", "--threads",
                             "--json-report", "-q", "--quiet"};
    for (size_t i = 0; i < sizeof neutral / sizeof neutral[0]; i++) assert_true(cli_bake_plan_neutral(neutral[i]));
    const char *kept[] = {"--seed", "--samples", "--texel-density", "--target-error", "--no-glg", "--preset"};
    for (size_t i = 0; i < sizeof kept / sizeof kept[0]; i++) assert_false(cli_bake_plan_neutral(kept[i]));
    /* the CLI's own default (the seed) and the library's (0) */
    bake_args o;
    int quiet = 0;
    assert_int_equal(cli_bake_parse(2, (char *[]){"bake", "s.gltf", NULL}, &o, &quiet), -1);
    assert_int_equal(o.d.seed, 1);
    assert_int_equal(o.d.max_samples, 0);
    assert_int_equal(cli_bake_parse(6, (char *[]){"bake", "s.gltf", "--dls-threshold", "0", "--target-error", "none", NULL}, &o,
                                    &quiet),
                     -1);
    assert_true(o.d.dls_threshold < 0 && o.d.target_error < 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cli_md_is_generated),
        cmocka_unit_test(test_texel_density_range),
        cmocka_unit_test(test_table_answers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
