/* Shared caches of distributed runs (lbk_bake_unit_shared, bake/dist/DIST.md §Shared caches): a
 * level with one transport run cut into N units computes each cache bounce once in all, not N
 * times, and the merge stays the local bake's container byte for byte at any N, whether the
 * units run one after another or together, after a unit was killed holding claims, and when a
 * unit elsewhere never publishes what it claimed. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "lbk/bake.h"
#include "lbk/bake_dist.h"

#define PLAN_HASH 0x5eed5a7e0ddba11ull
#define SCENE "scenes/cornell_box/CornellBox-Original.gltf"

typedef struct bytes {
    void *p;
    size_t n;
} bytes;

static char last_error[1024];

static void on_message(void *user, lbk_bake_severity s, const char *m)
{
    (void)user;
    if (s == LBK_BAKE_SEVERITY_ERROR) snprintf(last_error, sizeof last_error, "%s", m);
}

static lbk_bake_desc desc_of(void)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.seed = 11;
    d.threads = 2;
    d.max_samples = 64;
    d.target_error = -1;
    d.texel_density = 4;
    d.message = on_message;
    return d;
}

static int sh(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static int sh(const char *fmt, ...)
{
    char cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static size_t files_in(const char *dir)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "ls %s | grep -c '\\.lbkcache$'", dir);
    FILE *f = popen(cmd, "r");
    size_t n = 0;
    if (f) {
        if (fscanf(f, "%zu", &n) != 1) n = 0;
        pclose(f);
    }
    return n;
}

/* Units one after another: the first computes every share, the others read them all; every
 * part equals the part of a unit that shares nothing, so the merge is the local bake. */
static void test_sequential_units(void **state)
{
    (void)state;
    char dir[] = "/tmp/lbk-shared-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char cache[64];
    snprintf(cache, sizeof cache, "%s/cache", dir);
    lbk_bake_desc d = desc_of();
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_file(SCENE, &d, &out), LBK_OK);
    bytes local;
    assert_int_equal(lbk_bake_output_container(out, &local.p, &local.n), LBK_OK);
    lbk_bake_output_free(out);
    enum { N = 5 };
    bytes parts[N];
    const lbk_bake_unit_desc sd = {sizeof sd, cache, 0};
    uint64_t computed = 0;
    for (uint32_t k = 0; k < N; k++) {
        lbk_bake_unit_stats st;
        memset(&st, 0, sizeof st);
        st.size = sizeof st;
        last_error[0] = 0;
        lbk_result r = lbk_bake_unit_shared(SCENE, &d, PLAN_HASH, N, k, &sd, &st, &parts[k].p, &parts[k].n);
        if (r) fail_msg("unit %u: %s (%s)", k, lbk_result_message(r), last_error);
        if (k == 0) {
            assert_true(st.shares_computed > 0);
            assert_int_equal(st.shares_read, 0);
            assert_int_equal(st.shares_computed % N, 0); /* whole bounces, every share of each */
            computed = st.shares_computed;
        } else {
            assert_int_equal(st.shares_computed, 0);
            assert_int_equal(st.shares_read, computed);
        }
        bytes alone;
        assert_int_equal(lbk_bake_unit_from_file(SCENE, &d, PLAN_HASH, N, k, &alone.p, &alone.n), LBK_OK);
        assert_int_equal(alone.n, parts[k].n);
        assert_memory_equal(alone.p, parts[k].p, alone.n);
        lbk_bake_part_free(alone.p);
    }
    assert_int_equal(files_in(cache), computed);
    const void *p[N];
    size_t s[N];
    for (int k = 0; k < N; k++) p[k] = parts[k].p, s[k] = parts[k].n;
    assert_int_equal(lbk_bake_merge_from_file(SCENE, &d, PLAN_HASH, N, p, s, N, &out), LBK_OK);
    bytes m;
    assert_int_equal(lbk_bake_output_container(out, &m.p, &m.n), LBK_OK);
    lbk_bake_output_free(out);
    assert_int_equal(m.n, local.n);
    assert_memory_equal(m.p, local.p, m.n);
    printf("%u units: %llu shares computed once, read by the other %u units\n", N, (unsigned long long)computed, N - 1);
    /* a damaged share (a crash while it was written) is computed again, the part the same */
    assert_int_equal(sh("f=$(ls %s/*-s1of5.lbkcache | head -n 1) && printf 'XXXX' | dd of=$f bs=1 seek=150 conv=notrunc "
                        "2>/dev/null", cache), 0);
    lbk_bake_unit_stats st;
    memset(&st, 0, sizeof st);
    st.size = sizeof st;
    bytes again;
    assert_int_equal(lbk_bake_unit_shared(SCENE, &d, PLAN_HASH, N, 2, &sd, &st, &again.p, &again.n), LBK_OK);
    assert_int_equal(st.shares_computed, 1);
    assert_int_equal(st.shares_read, computed - 1);
    assert_int_equal(again.n, parts[2].n);
    assert_memory_equal(again.p, parts[2].p, again.n);
    lbk_bake_part_free(again.p);
    /* a share of another bake (other options under the same plan hash) is refused by name */
    lbk_bake_desc other = d;
    other.seed = 12;
    bytes bad = {NULL, 0};
    last_error[0] = 0;
    assert_int_equal(lbk_bake_unit_shared(SCENE, &other, PLAN_HASH, N, 2, &sd, NULL, &bad.p, &bad.n), LBK_ERR_BAD_INPUT);
    assert_non_null(strstr(last_error, ".lbkcache"));
    assert_non_null(strstr(last_error, "another bake"));
    assert_null(bad.p);
    assert_int_equal(lbk_bake_cache_dir_remove(cache), LBK_OK);
    assert_int_equal(sh("test ! -e %s", cache), 0);
    for (int k = 0; k < N; k++) lbk_bake_part_free(parts[k].p);
    lbk_free(NULL, m.p);
    lbk_free(NULL, local.p);
    sh("rm -rf %s", dir);
}

/* Through the CLI: units together (xargs -P 3 of 6), units after one was killed holding claims,
 * and a claim a live unit elsewhere holds past its lease; every merge is the local bake and
 * removes the cache folder. */
static void test_cli_units(void **state)
{
    (void)state;
    const char *lbk = getenv("LBK");
    if (!lbk || !*lbk) {
        printf("SKIPPED: set LBK to the lbk binary (make test does)\n");
        skip();
    }
    char dir[] = "/tmp/lbk-shared-XXXXXX";
    assert_non_null(mkdtemp(dir));
    const char *opts = "--samples 128 --target-error none --texel-density 6 --seed 2";
    assert_int_equal(sh("%s bake %s -o %s/local.lbk %s --threads 2 -q", lbk, SCENE, dir, opts), 0);
    assert_int_equal(sh("%s plan %s -o %s/out.lbk --plan %s/plan.json --units 6 %s >/dev/null", lbk, SCENE, dir, dir, opts), 0);
    assert_int_equal(sh("seq 0 5 | xargs -P 3 -I {} %s bake-unit %s/plan.json {} -o %s/part-{}.lbkpart --threads 1 > %s/log",
                        lbk, dir, dir, dir), 0);
    /* every share computed once (one file each), and every unit holds every share: its own
     * computed, the rest read */
    assert_int_equal(sh("n=$(ls %s/out.lbk.cache-*/ | grep -c 'lbkcache$') && awk -v n=$n '/cache shares computed/ "
                        "{c += $6; u++; if ($6 + $10 != n) bad = 1} END {exit !(u == 6 && c == n && !bad)}' %s/log", dir, dir), 0);
    assert_int_equal(sh("%s merge %s/plan.json %s/part-*.lbkpart -q && cmp %s/local.lbk %s/out.lbk", lbk, dir, dir, dir, dir), 0);
    assert_int_equal(sh("! ls -d %s/out.lbk.cache-* 2>/dev/null", dir), 0);
    /* claims left behind by a unit killed with kill -9 (a process gone from this host: taken at
     * once, under the default lease of 600 s) with its temporary file */
    assert_int_equal(sh("rm -f %s/part-* %s/out.lbk && mkdir %s/cache && dead=$(sh -c 'echo $$') && "
                        "echo \"LBKCLAIM $(hostname) $dead\" > %s/cache/r0-p0-h0-b1-s0of6.lbkcache.claim && "
                        "echo x > %s/cache/r0-p0-h0-b1-s1of6.lbkcache.tmp.gone.1", dir, dir, dir, dir, dir), 0);
    assert_int_equal(sh("timeout 120 %s bake-unit %s/plan.json 0 -o %s/part-0.lbkpart --threads 2 -q --cache-dir %s/cache && "
                        "test -e %s/cache/r0-p0-h0-b1-s0of6.lbkcache", lbk, dir, dir, dir, dir), 0);
    /* a fresh claim of a unit on another machine that never publishes: taken after the lease */
    assert_int_equal(sh("rm -rf %s/cache && mkdir %s/cache && echo 'LBKCLAIM elsewhere 1' > %s/cache/r0-p1-h1-b2-s4of6.lbkcache.claim",
                        dir, dir, dir), 0);
    assert_int_equal(sh("for k in 0 1 2 3 4 5; do timeout 120 %s bake-unit %s/plan.json $k -o %s/part-$k.lbkpart --threads 2 "
                        "-q --cache-dir %s/cache --cache-lease 2 || exit 1; done && test -e %s/cache/r0-p1-h1-b2-s4of6.lbkcache",
                        lbk, dir, dir, dir, dir), 0);
    assert_int_equal(sh("%s merge %s/plan.json %s/part-*.lbkpart --cache-dir %s/cache -q && cmp %s/local.lbk %s/out.lbk && "
                        "test ! -e %s/cache", lbk, dir, dir, dir, dir, dir, dir), 0);
    /* no sharing at all: the same container */
    assert_int_equal(sh("rm -f %s/part-* && for k in 0 1 2 3 4 5; do %s bake-unit %s/plan.json $k -o %s/part-$k.lbkpart "
                        "--no-shared-cache -q || exit 1; done && test ! -e %s/out.lbk.cache-* && %s merge %s/plan.json "
                        "%s/part-*.lbkpart -o %s/plain.lbk -q && cmp %s/local.lbk %s/plain.lbk", dir, lbk, dir, dir, dir, lbk,
                        dir, dir, dir, dir, dir), 0);
    sh("rm -rf %s", dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sequential_units),
        cmocka_unit_test(test_cli_units),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
