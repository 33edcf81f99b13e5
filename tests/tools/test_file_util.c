/* tl_remove_stale_temps: exactly the temporary files an interrupted write to a path can leave
 * (liblbk's PATH.tmp-XXXXXX older than the cut-off, the tools' PATH.tmp.PID of a dead process),
 * nothing else. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <utime.h>

#include <cmocka.h>

#include "tools/common/file_util.h"

static char dir[64];

static void touch(const char *name, time_t mtime)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    fputs("x", f);
    fclose(f);
    struct utimbuf t = {mtime, mtime};
    assert_int_equal(utime(p, &t), 0);
}

static int exists(const char *name)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    return access(p, F_OK) == 0;
}

static void count_removed(void *user, const char *file)
{
    (void)file;
    ++*(int *)user;
}

static void test_only_stale_temps_go(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/lbk-stale-XXXXXX");
    assert_non_null(mkdtemp(dir));
    const time_t now = time(NULL), old = now - 3600;
    /* a pid that is surely gone: a child we reaped */
    pid_t child = fork();
    if (child == 0) _exit(0);
    assert_true(child > 0);
    waitpid(child, NULL, 0);
    char dead[64], alive[64];
    snprintf(dead, sizeof dead, "out.lbk.tmp.%ld", (long)child);
    snprintf(alive, sizeof alive, "out.lbk.tmp.%ld", (long)getppid()); /* our parent: running */

    touch("out.lbk", old);              /* the output itself */
    touch("out.lbk.tmp-a1B2c3", old);   /* crashed lbk_writer_to_file: goes */
    touch("out.lbk.tmp-Z9y8x7", now);   /* newer than the cut-off: may be a running write */
    touch("out.lbk.tmp-abc", old);      /* not mkstemp's six characters */
    touch("out.lbk.tmp-abc12!", old);   /* not letters and digits */
    touch(dead, old);                   /* crashed tl_write_file_atomic: goes */
    touch(alive, old);                  /* its writer still runs */
    touch("other.lbk.tmp-a1B2c3", old); /* another output's */
    touch("out.lbk.bak", old);
    char sub[256];
    snprintf(sub, sizeof sub, "%s/out.lbk.tmp-d1r3ct", dir);
    assert_int_equal(mkdir(sub, 0755), 0); /* not a regular file */

    char path[256];
    snprintf(path, sizeof path, "%s/out.lbk", dir);
    int seen = 0;
    assert_int_equal(tl_remove_stale_temps(path, now - 60, count_removed, &seen), 2);
    assert_int_equal(seen, 2);
    assert_false(exists("out.lbk.tmp-a1B2c3"));
    assert_false(exists(dead));
    assert_true(exists("out.lbk"));
    assert_true(exists("out.lbk.tmp-Z9y8x7"));
    assert_true(exists("out.lbk.tmp-abc"));
    assert_true(exists("out.lbk.tmp-abc12!"));
    assert_true(exists(alive));
    assert_true(exists("other.lbk.tmp-a1B2c3"));
    assert_true(exists("out.lbk.bak"));
    assert_true(exists("out.lbk.tmp-d1r3ct"));
    /* nothing more on a second call */
    assert_int_equal(tl_remove_stale_temps(path, now - 60, NULL, NULL), 0);

    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_only_stale_temps_go),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
