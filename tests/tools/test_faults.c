/* Fault injection into the CLI's writers: every file-writing call of
 * `lbk bake` (with --json-report), `lbk convert` and `lbk export` — open, write, fsync, rename,
 * mkdir — is made to fail once in turn (ENOSPC, EIO or EXDEV: tests/faults/fault_shim.c, an
 * LD_PRELOAD library), and the process is killed (SIGKILL) at each of those points. After each:
 *  - a failure exits non-zero and its message names the cause (the errno's text);
 *  - the outputs are the old ones (bake, convert: the container and its report as a pair; export:
 *    every file is either its old or its new version, never partial) — or, where the error came
 *    after the commit point (the folder's fsync after the rename), the new ones as a pair;
 *  - no temporary file is left after a failure, nor a folder export created;
 *  - after a kill the files are old or new (never partial), and the next run removes what the
 *    killed one left and writes the new outputs.
 * Needs LBK (the CLI) and LBK_FAULT_SHIM (the library); skipped without them. The ASan CLI
 * accepts a preloaded library with verify_asan_link_order=0. */
#define _GNU_SOURCE /* memmem */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <utime.h>

#include "tools/common/file_util.h"

enum { OP_COUNT = 5 };
static const char *const ops[OP_COUNT] = {"open", "write", "fsync", "rename", "mkdir"};
static const char *const causes[OP_COUNT] = {"No space left on device", "No space left on device",
                                             "Input/output error", "Invalid cross-device link",
                                             "No space left on device"};
static char dir[64];
static char lbk[1024], shim[1024];
/* a small bake: the writers are what is tested */
#define SCENE "CornellBox-Original.gltf"
#define QUICK "--samples 16 --threads 2 --texel-density 2"

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/lbk_test_faults_XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* Runs `args` (a shell command line after the CLI's path) with the shim: fault at call `at` of
 * op (NULL: none), killing there if `kill`, the counts appended to `counts` if not NULL. The
 * exit status, 137 for a kill; stderr into dir/err.txt. */
static int run(const char *op, unsigned long at, int kill, const char *counts, const char *fmt, ...)
{
    char args[2048], cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    char fault[128] = "";
    if (op) snprintf(fault, sizeof fault, "LBK_FAULT_OP=%s LBK_FAULT_AT=%lu%s", op, at, kill ? " LBK_FAULT_KILL=1" : "");
    int n = snprintf(cmd, sizeof cmd,
                     "cd %s && env ASAN_OPTIONS=verify_asan_link_order=0:detect_leaks=0 LD_PRELOAD=%s %s %s%s %s %s "
                     "2>err.txt >/dev/null",
                     dir, shim, fault, counts ? "LBK_FAULT_COUNTS=" : "", counts ? counts : "", lbk, args);
    assert_true(n > 0 && (size_t)n < sizeof cmd);
    int st = system(cmd);
    if (st == -1) return -1;
    if (WIFSIGNALED(st)) return 128 + WTERMSIG(st);
    return WEXITSTATUS(st);
}

static char *slurp(const char *name, size_t *size)
{
    char path[256], err[TL_ERR_LEN];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    void *data = NULL;
    *size = 0;
    if (tl_read_file(path, &data, size, err)) return NULL;
    return data;
}

typedef struct blob { char *data; size_t size; } blob;

static blob take(const char *name) { blob b; b.data = slurp(name, &b.size); return b; }
static int same(const blob *b, const char *name)
{
    size_t n;
    char *d = slurp(name, &n);
    int eq = d && b->data && n == b->size && memcmp(d, b->data, n) == 0;
    free(d);
    return eq;
}
/* The bake seed a JSON report names (-1: none): reports carry timings, so two reports of the
 * same bake differ in bytes; the seed tells an old report from a new one. */
static long seed_of(const char *text, size_t n)
{
    const char key[] = "\"seed\":";
    const char *p = text ? memmem(text, n, key, sizeof key - 1) : NULL;
    return p ? strtol(p + sizeof key - 1, NULL, 10) : -1;
}

/* Is file `name` the report b is (same seed)? */
static int same_report(const blob *b, const char *name)
{
    size_t n;
    char *d = slurp(name, &n);
    long want = seed_of(b->data, b->size), have = seed_of(d, n);
    free(d);
    return want >= 0 && want == have;
}

static void put(const blob *b, const char *name)
{
    char path[256], err[TL_ERR_LEN];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    assert_int_equal(tl_write_file_atomic(path, b->data, b->size, err), 0);
}

/* The calls of each operation that one clean run of `args` makes. */
static void count_calls(unsigned long n[OP_COUNT], const char *args)
{
    char counts[128];
    snprintf(counts, sizeof counts, "%s/counts.txt", dir);
    remove(counts);
    assert_int_equal(run(NULL, 0, 0, counts, "%s", args), 0);
    FILE *f = fopen(counts, "r");
    assert_non_null(f);
    char name[16];
    unsigned long v;
    memset(n, 0, OP_COUNT * sizeof *n);
    while (fscanf(f, "%15s %lu", name, &v) == 2)
        for (int i = 0; i < OP_COUNT; i++)
            if (!strcmp(name, ops[i])) n[i] = v;
    fclose(f);
    remove(counts);
}

/* Which calls to hit: all of a few, else the first three, the quarters and the last two. */
static int points(unsigned long n, unsigned long *at)
{
    if (n <= 10) {
        for (unsigned long i = 0; i < n; i++) at[i] = i + 1;
        return (int)n;
    }
    unsigned long p[9] = {1, 2, 3, n / 4, n / 2, 3 * n / 4, n - 1, n, 0};
    int k = 0;
    for (int i = 0; i < 8; i++)
        if (k == 0 || p[i] > at[k - 1]) at[k++] = p[i];
    return k;
}

/* Number of leftover temporary files (of any writer) under dir/sub, recursively. */
static int temps_under(const char *sub)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd,
             "find %s/%s \\( -name '*.tmp-*' -o -name '*.tmp.*' -o -name 'tmp.*' \\) 2>/dev/null | wc -l", dir, sub);
    FILE *p = popen(cmd, "r");
    int n = -1;
    if (p && fscanf(p, "%d", &n) != 1) n = -1;
    if (p) pclose(p);
    return n;
}

/* Makes what a killed run left look a few minutes old: the writers keep fresh temporaries of
 * a concurrent run of theirs, and remove the old ones. */
static void age_leftovers(void)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "find %s \\( -name '*.tmp-*' -o -name '*.tmp.*' -o -name 'tmp.*' \\) -exec touch -d "
             "'-5 minutes' {} +", dir);
    assert_int_equal(system(cmd), 0);
}

static int message_names(const char *cause)
{
    size_t n;
    char *e = slurp("err.txt", &n);
    int ok = e && memmem(e, n, cause, strlen(cause)) != NULL;
    if (!ok) fprintf(stderr, "message: %.*s\n", e ? (int)n : 0, e ? e : "");
    free(e);
    return ok;
}

static void skip_without_tools(void)
{
    /* absolute: the commands run in the scratch folder */
    const char *l = getenv("LBK"), *f = getenv("LBK_FAULT_SHIM");
    char a[PATH_MAX], b[PATH_MAX];
    if (!l || !f || !realpath(l, a) || !realpath(f, b) || strlen(a) >= sizeof lbk || strlen(b) >= sizeof shim) {
        print_message("SKIPPED: LBK and LBK_FAULT_SHIM are needed (make test sets them)\n");
        skip();
    }
    strcpy(lbk, a);
    strcpy(shim, b);
}

/* One writer with a pair of outputs (a, and its JSON report b, told apart by seed; b may be
 * NULL): old and new versions of both are known; every fault either leaves the old pair, or —
 * after the commit point — the new pair. */
static void pair_case(const char *what, const char *args, const char *a, const char *b, const blob *olda,
                      const blob *oldb, const blob *newa, const blob *newb)
{
    unsigned long n[OP_COUNT], at[16];
    put(olda, a);
    if (b) put(oldb, b);
    count_calls(n, args);
    int runs = 0;
    for (int op = 0; op < OP_COUNT; op++) {
        int np = points(n[op], at);
        for (int p = 0; p < np; p++)
            for (int kill = 0; kill < 2; kill++) {
                put(olda, a);
                if (b) put(oldb, b);
                int rc = run(ops[op], at[p], kill, NULL, "%s", args);
                int old = same(olda, a) && (!b || same_report(oldb, b));
                int fresh = same(newa, a) && (!b || same_report(newb, b));
                if (kill) {
                    /* each file old or new; then the next run cleans up and writes */
                    assert_true(rc == 137 || rc == 0);
                    assert_true(same(olda, a) || same(newa, a));
                    if (b) assert_true(same_report(oldb, b) || same_report(newb, b));
                    age_leftovers();
                    assert_int_equal(run(NULL, 0, 0, NULL, "%s", args), 0);
                    if (!same(newa, a) || (b && !same_report(newb, b)))
                        fail_msg("%s: after a kill at %s #%lu and a rerun: %s %s", what, ops[op], at[p],
                                 same(newa, a) ? "new" : same(olda, a) ? "OLD" : "OTHER",
                                 !b ? "" : same_report(newb, b) ? "new" : same_report(oldb, b) ? "OLD" : "OTHER");
                } else {
                    if (rc == 0) {
                        /* a call whose failure does not matter (e.g. a write of a message) */
                        assert_true(fresh);
                    } else {
                        if (!old && !fresh) fprintf(stderr, "%s: %s #%lu left a mixed pair\n", what, ops[op], at[p]);
                        assert_true(old || fresh);
                        assert_true(message_names(causes[op]));
                    }
                }
                assert_int_equal(temps_under("."), 0);
                runs++;
            }
    }
    print_message("%s: %d faulted runs (calls: open %lu, write %lu, fsync %lu, rename %lu, mkdir %lu)\n", what, runs,
                  n[0], n[1], n[2], n[3], n[4]);
}

static void bake_and_convert(void **state)
{
    (void)state;
    skip_without_tools();
    char cmd[512];
    snprintf(cmd, sizeof cmd, "cp scenes/cornell_box/* %s/", dir);
    assert_int_equal(system(cmd), 0);
    const char *args = "bake " SCENE " -o level.lbk --json-report level.json -q " QUICK;
    /* the new outputs, and old ones that differ from them (another seed) */
    assert_int_equal(run(NULL, 0, 0, NULL, "%s", args), 0);
    blob newl = take("level.lbk"), newj = take("level.json");
    assert_int_equal(run(NULL, 0, 0, NULL, "%s --seed 7", args), 0);
    blob oldl = take("level.lbk"), oldj = take("level.json");
    assert_true(newl.data && newj.data && oldl.data && oldj.data && newl.size > 1000);
    pair_case("bake", args, "level.lbk", "level.json", &oldl, &oldj, &newl, &newj);

    put(&newl, "level.lbk");
    put(&oldl, "old.lbk");
    const char *conv = "convert level.lbk -o pack.lbk --profile pc -q";
    assert_int_equal(run(NULL, 0, 0, NULL, "convert old.lbk -o pack.lbk --profile pc -q"), 0);
    blob oldp = take("pack.lbk");
    assert_int_equal(run(NULL, 0, 0, NULL, "%s", conv), 0);
    blob newp = take("pack.lbk");
    pair_case("convert", conv, "pack.lbk", NULL, &oldp, NULL, &newp, NULL);
    /* the inputs were never touched */
    assert_true(same(&newl, "level.lbk"));
    free(newl.data), free(newj.data), free(oldl.data), free(oldj.data), free(oldp.data), free(newp.data);
}

/* Every regular file under dir/sub, as names relative to it, sorted, one per line. */
static char *listing(const char *sub)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "cd %s/%s && find . -type f | sort", dir, sub);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t cap = 1 << 16;
    char *s = calloc(cap, 1);
    size_t n = fread(s, 1, cap - 1, p);
    s[n] = 0;
    pclose(p);
    return s;
}

/* Export into a folder that holds an older export (each file must stay old or become new,
 * never partial; folders it creates are removed on failure) and into a new folder (gone after a
 * failure). */
static void export_folders(void **state)
{
    (void)state;
    skip_without_tools();
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "cp scenes/cornell_box/* %s/", dir);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(run(NULL, 0, 0, NULL, "bake " SCENE " -o level.lbk -q " QUICK), 0);
    assert_int_equal(run(NULL, 0, 0, NULL, "bake " SCENE " -o old.lbk -q " QUICK " --seed 7"), 0);
    const char *args = "export level.lbk --exr out/exr --png out/png --per-object -q";
    assert_int_equal(run(NULL, 0, 0, NULL, "%s", args), 0);
    /* new/: the clean export; old/: an older one (another bake, no per-object files) */
    snprintf(cmd, sizeof cmd, "cd %s && rm -rf new && mv out new && mkdir out", dir);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(run(NULL, 0, 0, NULL, "export old.lbk --exr out/exr --png out/png -q"), 0);
    snprintf(cmd, sizeof cmd, "cd %s && rm -rf old && cp -a out old", dir);
    assert_int_equal(system(cmd), 0);
    unsigned long n[OP_COUNT], at[16];
    count_calls(n, args);
    int runs = 0;
    for (int op = 0; op < OP_COUNT; op++) {
        int np = points(n[op], at);
        for (int p = 0; p < np; p++)
            for (int kill = 0; kill < 2; kill++) {
                snprintf(cmd, sizeof cmd, "cd %s && rm -rf out && cp -a old out", dir);
                assert_int_equal(system(cmd), 0);
                int rc = run(ops[op], at[p], kill, NULL, "%s", args);
                if (!kill && rc != 0) assert_true(message_names(causes[op]));
                /* every file now in out/ is the old or the new version of itself */
                char *now = listing("out");
                for (char *line = strtok(now, "\n"); line; line = strtok(NULL, "\n")) {
                    char here[512], o[512], w[512];
                    snprintf(here, sizeof here, "out/%s", line + 2); /* after "./" */
                    snprintf(o, sizeof o, "old/%s", line + 2);
                    snprintf(w, sizeof w, "new/%s", line + 2);
                    if (strstr(line, "tmp")) continue; /* a kill's leftover: counted below */
                    blob have = take(here);
                    int is_old = same(&have, o), is_new = same(&have, w);
                    if (!is_old && !is_new) fprintf(stderr, "export: %s #%lu: %s is partial\n", ops[op], at[p], here);
                    assert_true(is_old || is_new);
                    free(have.data);
                }
                free(now);
                if (!kill) {
                    assert_int_equal(temps_under("out"), 0);
                    /* a failure removes the folders it made: out/exr/objects, out/png/objects */
                    if (rc != 0) {
                        snprintf(cmd, sizeof cmd, "test ! -e %s/out/exr/objects -a ! -e %s/out/png/objects", dir, dir);
                        assert_int_equal(system(cmd), 0);
                    }
                } else {
                    age_leftovers();
                    assert_int_equal(run(NULL, 0, 0, NULL, "%s", args), 0);
                    assert_int_equal(temps_under("out"), 0);
                    char *after = listing("out"), *want = listing("new");
                    if (strcmp(after, want)) fail_msg("export after a kill and a rerun: other files than a clean export");
                    free(after), free(want);
                }
                /* into a folder that does not exist: a failure leaves none */
                if (!kill && op != 4) {
                    snprintf(cmd, sizeof cmd, "rm -rf %s/fresh", dir);
                    assert_int_equal(system(cmd), 0);
                    rc = run(ops[op], at[p], 0, NULL, "export level.lbk --exr fresh/exr --png fresh/png --per-object -q");
                    if (rc != 0) {
                        snprintf(cmd, sizeof cmd, "test ! -e %s/fresh", dir);
                        assert_int_equal(system(cmd), 0);
                    }
                }
                runs++;
            }
    }
    print_message("export: %d faulted runs (calls: open %lu, write %lu, fsync %lu, rename %lu, mkdir %lu)\n", runs,
                  n[0], n[1], n[2], n[3], n[4]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(bake_and_convert, setup, teardown),
        cmocka_unit_test_setup_teardown(export_folders, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
