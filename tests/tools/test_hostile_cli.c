/* The hostile-glTF campaign through the CLI (issue 39): `lbk bake` ($LBK, the ASan+UBSan build
 * in make test) on every case of tests/support/hostile_gltf.c must exit 4 (LBK_EXIT_INPUT, bad
 * input) with the case's message on stderr, never crash (a signal, exit 134/139) and never print
 * a sanitizer report; the baseline, the template the cases break, must bake (exit 0), so the
 * harness cannot pass by refusing everything. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli/cli.h"
#include "support/hostile_gltf.h"

static char g_dir[256];
static char g_lbk[PATH_MAX];

static int setup(void **state)
{
    (void)state;
    const char *l = getenv("LBK");
    if (!l || !realpath(l, g_lbk)) {
        const char *b = getenv("BUILD");
        char rel[PATH_MAX];
        snprintf(rel, sizeof rel, "%s/lbk-asan", b && *b ? b : "build");
        if (!realpath(rel, g_lbk)) snprintf(g_lbk, sizeof g_lbk, "%s", rel); /* the cases then fail naming it */
    }
    snprintf(g_dir, sizeof g_dir, "/tmp/lbk_test_hostile_cli_XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* Runs `lbk bake scene -o out -q ...` with stderr into errfile; the raw wait status. */
static int bake(const char *scene, const char *out, const char *errfile)
{
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int fd = open(errfile, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        int nul = open("/dev/null", O_RDWR);
        if (fd < 0 || nul < 0) _exit(127);
        dup2(nul, 0);
        dup2(nul, 1);
        dup2(fd, 2);
        execl(g_lbk, g_lbk, "bake", scene, "-o", out, "-q", "--threads", "2", "--samples", "4", "--texel-density",
              "4", (char *)NULL);
        _exit(127);
    }
    int st = 0;
    assert_int_equal(waitpid(pid, &st, 0), pid);
    return st;
}

static int file_holds(const char *path, const char *needle)
{
    static char buf[1 << 16];
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    return strstr(buf, needle) != NULL;
}

static void test_hostile_cli(void **state)
{
    (void)state;
    size_t n;
    const hg_case *cases = hg_cases(&n);
    int bad = 0;
    for (size_t i = 0; i < n; i++) {
        char dir[512], path[1024], out[1024], errf[1024];
        snprintf(dir, sizeof dir, "%s/%s", g_dir, cases[i].name);
        assert_int_equal(mkdir(dir, 0700), 0);
        assert_int_equal(hg_write(dir, &cases[i], path, sizeof path), 0);
        snprintf(out, sizeof out, "%s/out.lbk", dir);
        snprintf(errf, sizeof errf, "%s/stderr.txt", dir);
        int st = bake(path, out, errf);
        const int want = cases[i].needle ? LBK_EXIT_INPUT : 0;
        const char *why = NULL;
        if (WIFSIGNALED(st)) why = "killed by a signal";
        else if (WEXITSTATUS(st) != want) why = "wrong exit code";
        else if (file_holds(errf, "Sanitizer") || file_holds(errf, "runtime error:")) why = "a sanitizer report";
        else if (cases[i].needle && !file_holds(errf, cases[i].needle)) why = "the message lacks the case's cause";
        if (why) {
            printf("%s: %s (status %d, exit %d, want %d); stderr in %s:\n", cases[i].name, why, st,
                   WIFEXITED(st) ? WEXITSTATUS(st) : -1, want, errf);
            char cmd[1200];
            snprintf(cmd, sizeof cmd, "head -c 2000 '%s'", errf);
            if (system(cmd) != 0) printf("(unreadable)\n");
            bad++;
        }
    }
    assert_int_equal(bad, 0);
}

/* An output path ending in '/' is refused as a folder (exit 2, LBK_EXIT_USAGE), not "Not a directory". */
static void test_output_folder(void **state)
{
    (void)state;
    size_t n;
    const hg_case *cases = hg_cases(&n);
    char dir[512], path[1024], out[1024], errf[1024];
    snprintf(dir, sizeof dir, "%s/out_folder", g_dir);
    assert_int_equal(mkdir(dir, 0700), 0);
    assert_int_equal(hg_write(dir, &cases[0], path, sizeof path), 0);
    snprintf(errf, sizeof errf, "%s/stderr.txt", dir);
    for (int i = 0; i < 2; i++) {
        snprintf(out, sizeof out, i ? "%s/" : "%s/missing/", dir); /* an existing folder and a missing one */
        int st = bake(path, out, errf);
        assert_true(WIFEXITED(st));
        assert_int_equal(WEXITSTATUS(st), LBK_EXIT_USAGE);
        assert_true(file_holds(errf, "names a folder: give a file name"));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hostile_cli),
        cmocka_unit_test(test_output_folder),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
