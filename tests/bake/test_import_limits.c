/* glTF import limits on hostile input (issue 39): every case of the hostile-glTF campaign
 * (tests/support/hostile_gltf.c) refused with the message that names its real cause, and the
 * memory a file may take bounded by its size: 2*10^7 empty nodes (57 MiB of JSON, under the
 * 64 MiB cap; 12.8 GB and more than 120 s before) refused within 1 GB and 30 s, measured in a
 * child process (peak RSS from wait4, wall time), as are 10^6 nodes, a 10^5-deep chain (refused by
 * the depth check on parent indices) and a 10^6-deep one (refused by the budget). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "scene/import.h"
#include "scene/scene.h"
#include "support/hostile_gltf.h"

static char g_dir[256];

static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/lbk_test_limits_XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* Every case in a folder of its own: the baseline imports, every other case is refused with its
 * needle and the file's name in the message, leaving the scene empty. */
static void test_hostile_cases(void **state)
{
    (void)state;
    size_t n;
    const hg_case *cases = hg_cases(&n);
    assert_true(n > 30);
    int bad = 0;
    for (size_t i = 0; i < n; i++) {
        char dir[512], path[1024], err[1024];
        snprintf(dir, sizeof dir, "%s/%s", g_dir, cases[i].name);
        assert_int_equal(mkdir(dir, 0700), 0);
        if (hg_write(dir, &cases[i], path, sizeof path) != 0) {
            printf("%s: could not be written\n", cases[i].name);
            bad++;
            continue;
        }
        bk_scene s;
        err[0] = 0;
        int rc = bk_import_gltf(path, NULL, &s, err, sizeof err);
        const char *base = strrchr(path, '/') + 1;
        int ok = cases[i].needle ? rc != 0 && strstr(err, cases[i].needle) && strstr(err, base) && !s.tri_count &&
                                       !s.positions
                                 : rc == 0 && s.tri_count == 2;
        if (!ok) {
            printf("%s: rc %d, message: %s (expected %s)\n", cases[i].name, rc, err,
                   cases[i].needle ? cases[i].needle : "an import of 2 triangles");
            bad++;
        }
        bk_scene_free(&s);
    }
    assert_int_equal(bad, 0);
}

typedef struct {
    int refused;    /* the child's import failed with the expected needle */
    double seconds; /* wall time of the import */
    long rss_kb;    /* the child's peak RSS */
} measure;

/* Imports path in a child process; its peak RSS (wait4) and wall time. */
static measure import_in_child(const char *path, const char *needle)
{
    measure m = {0, 0, 0};
    struct timespec t0, t1;
    fflush(stdout); /* the child must not print what the parent buffered */
    clock_gettime(CLOCK_MONOTONIC, &t0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        bk_scene s;
        char err[1024];
        int rc = bk_import_gltf(path, NULL, &s, err, sizeof err);
        if (rc == 0) bk_scene_free(&s);
        printf("  %s\n", rc ? err : "imported");
        fflush(stdout);
        _exit(rc != 0 && strstr(err, needle) ? 0 : 1);
    }
    int status = 0;
    struct rusage ru;
    assert_int_equal(wait4(pid, &status, 0, &ru), pid);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    m.refused = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    m.seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    m.rss_kb = ru.ru_maxrss;
    return m;
}

static void test_node_count_memory(void **state)
{
    (void)state;
    static const struct {
        const char *file, *needle;
        size_t count;
        int chain;
    } cases[] = {
        {"nodes_1e6.gltf", "1000000 nodes", 1000000, 0},
        {"chain_1e5.gltf", "node 257: node hierarchy deeper than 256", 100000, 1},
        {"chain_1e6.gltf", "1000000 nodes", 1000000, 1},
        {"nodes_2e7.gltf", "JSON objects", 20000000, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t bytes = hg_write_nodes(g_dir, cases[i].file, cases[i].count, cases[i].chain);
        assert_true(bytes > 0);
        assert_true(bytes < (size_t)64 << 20); /* under the JSON cap: the budget refuses it, not the cap */
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", g_dir, cases[i].file);
        measure m = import_in_child(path, cases[i].needle);
        printf("%s: %zu bytes of JSON, refused %d, %.2f s, peak RSS %.0f MB\n", cases[i].file, bytes, m.refused,
               m.seconds, m.rss_kb / 1024.0);
        unlink(path);
        assert_true(m.refused);
        assert_true(m.seconds < 30.0);
        assert_true(m.rss_kb < 1000L * 1000); /* 1 GB */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hostile_cases),
        cmocka_unit_test(test_node_count_memory),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
