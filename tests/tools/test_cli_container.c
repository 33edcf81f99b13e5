/* `lbk validate` and `lbk inspect`, run in-process with stdout captured: exit codes (0 valid,
 * 1 invalid, 2 usage, 3 I/O, 4 unreadable input), the JSON documents of spec/inspect-json.md,
 * and the inspect disk column adding up exactly to the file size. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cli/cli.h"

typedef struct run_result {
    int code;
    char *out; /* captured stdout, NUL-terminated */
} run_result;

/* Runs a subcommand with stdout (and stderr) redirected to temp files. */
static run_result run(int (*cmd)(int, char **), int argc, const char **argv)
{
    char out_path[] = "/tmp/lbk-cli-out-XXXXXX", err_path[] = "/tmp/lbk-cli-err-XXXXXX";
    int fd = mkstemp(out_path), efd = mkstemp(err_path);
    assert_true(fd >= 0 && efd >= 0);
    fflush(stdout);
    fflush(stderr);
    int saved = dup(1), saved_err = dup(2);
    dup2(fd, 1);
    dup2(efd, 2);
    run_result r;
    r.code = cmd(argc, (char **)argv);
    fflush(stdout);
    fflush(stderr);
    dup2(saved, 1);
    dup2(saved_err, 2);
    close(saved);
    close(saved_err);
    off_t n = lseek(fd, 0, SEEK_END);
    r.out = malloc((size_t)n + 1);
    assert_int_equal(pread(fd, r.out, (size_t)n, 0), n);
    r.out[n] = '\0';
    close(fd);
    close(efd);
    unlink(out_path);
    unlink(err_path);
    return r;
}

static const char *small = "tests/golden/small.lbk";
static const char *objects_raw = "tests/fuzz/corpus/objects_raw.lbk";

static char *copy_with(const char *src, long truncate_to, long flip_byte)
{
    FILE *f = fopen(src, "rb");
    assert_non_null(f);
    static unsigned char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    if (truncate_to >= 0) n = (size_t)truncate_to;
    if (flip_byte >= 0) buf[flip_byte] ^= 0x20;
    char *path = strdup("/tmp/lbk-cli-file-XXXXXX");
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, buf, n), (ssize_t)n);
    close(fd);
    return path;
}

static void test_validate_exit_codes(void **state)
{
    (void)state;
    run_result r = run(lbk_cmd_validate, 2, (const char *[]){"validate", small, NULL});
    assert_int_equal(r.code, LBK_EXIT_OK);
    assert_non_null(strstr(r.out, "valid (0 fatal, 0 errors, 1 warning)"));
    assert_non_null(strstr(r.out, "213"));
    free(r.out);

    char *bad = copy_with(small, 500, -1);
    r = run(lbk_cmd_validate, 2, (const char *[]){"validate", bad, NULL});
    assert_int_equal(r.code, LBK_EXIT_NEGATIVE);
    assert_non_null(strstr(r.out, "106"));
    assert_non_null(strstr(r.out, "INVALID"));
    free(r.out);
    r = run(lbk_cmd_validate, 3, (const char *[]){"validate", bad, "--quiet", NULL});
    assert_int_equal(r.code, LBK_EXIT_NEGATIVE);
    assert_string_equal(r.out, "");
    free(r.out);
    unlink(bad);
    free(bad);

    r = run(lbk_cmd_validate, 2, (const char *[]){"validate", "/nonexistent/x.lbk", NULL});
    assert_int_equal(r.code, LBK_EXIT_IO);
    free(r.out);
    r = run(lbk_cmd_validate, 1, (const char *[]){"validate", NULL});
    assert_int_equal(r.code, LBK_EXIT_USAGE);
    free(r.out);
    r = run(lbk_cmd_validate, 3, (const char *[]){"validate", small, "--bogus", NULL});
    assert_int_equal(r.code, LBK_EXIT_USAGE);
    free(r.out);
    r = run(lbk_cmd_validate, 3, (const char *[]){"validate", small, small, NULL});
    assert_int_equal(r.code, LBK_EXIT_USAGE);
    free(r.out);
    r = run(lbk_cmd_validate, 2, (const char *[]){"validate", "--help", NULL});
    assert_int_equal(r.code, LBK_EXIT_OK);
    assert_non_null(strstr(r.out, "usage: lbk validate"));
    free(r.out);
}

static void test_validate_json(void **state)
{
    (void)state;
    /* flip a bit in the OBJS payload (offset 592 in small.lbk, after META at 256 and REPT) */
    FILE *f = fopen(small, "rb");
    unsigned char head[64 + 4 * 48];
    assert_int_equal(fread(head, 1, sizeof head, f), sizeof head);
    fclose(f);
    long objs_off = 0;
    for (int i = 0; i < 8; i++) objs_off |= (long)head[64 + 2 * 48 + 16 + i] << (8 * i);
    char *bad = copy_with(small, -1, objs_off + 5);
    run_result r = run(lbk_cmd_validate, 3, (const char *[]){"validate", bad, "--json", NULL});
    assert_int_equal(r.code, LBK_EXIT_NEGATIVE);
    cJSON *doc = cJSON_Parse(r.out);
    assert_non_null(doc);
    assert_string_equal(cJSON_GetObjectItem(doc, "schema")->valuestring, "lbk-validate/1");
    assert_true(cJSON_IsFalse(cJSON_GetObjectItem(doc, "valid")));
    cJSON *issues = cJSON_GetObjectItem(doc, "issues");
    assert_int_equal(cJSON_GetArraySize(issues), 2);
    cJSON *second = cJSON_GetArrayItem(issues, 1);
    assert_int_equal(cJSON_GetObjectItem(second, "id")->valueint, 214);
    assert_string_equal(cJSON_GetObjectItem(second, "severity")->valuestring, "error");
    assert_string_equal(cJSON_GetObjectItem(second, "section")->valuestring, "OBJS");
    assert_int_equal((long)cJSON_GetObjectItem(second, "offset")->valuedouble, objs_off);
    cJSON *sum = cJSON_GetObjectItem(doc, "summary");
    assert_int_equal(cJSON_GetObjectItem(sum, "errors")->valueint, 1);
    assert_int_equal(cJSON_GetObjectItem(sum, "warnings")->valueint, 1);
    cJSON_Delete(doc);
    free(r.out);
    unlink(bad);
    free(bad);
}

static double num(cJSON *o, const char *k)
{
    cJSON *v = cJSON_GetObjectItem(o, k);
    if (!cJSON_IsNumber(v)) fail_msg("missing number '%s'", k);
    return v->valuedouble;
}

static void test_inspect_json_adds_up(void **state)
{
    (void)state;
    const char *files[] = {small, objects_raw, "tests/fuzz/corpus/objects_zstd.lbk", "tests/golden/align16.lbk"};
    for (int k = 0; k < 4; k++) {
        run_result r = run(lbk_cmd_inspect, 3, (const char *[]){"inspect", files[k], "--json", NULL});
        assert_int_equal(r.code, LBK_EXIT_OK);
        cJSON *doc = cJSON_Parse(r.out);
        assert_non_null(doc);
        assert_string_equal(cJSON_GetObjectItem(doc, "schema")->valuestring, "lbk-inspect/1");
        FILE *f = fopen(files[k], "rb");
        fseek(f, 0, SEEK_END);
        double real_size = (double)ftell(f);
        fclose(f);
        assert_true(num(doc, "file_size") == real_size);
        double sum = num(doc, "header_bytes") + num(doc, "table_bytes") + num(doc, "padding_bytes");
        cJSON *s;
        cJSON_ArrayForEach(s, cJSON_GetObjectItem(doc, "sections")) {
            sum += num(s, "disk_bytes");
            const char *t = cJSON_GetObjectItem(s, "type")->valuestring;
            if (!strcmp(t, "META") || !strcmp(t, "REPT") || !strcmp(t, "OBJS")) assert_true(num(s, "gpu_bytes") == 0);
            assert_true(cJSON_IsTrue(cJSON_GetObjectItem(s, "readable")));
        }
        assert_true(sum == real_size);
        cJSON *tot = cJSON_GetObjectItem(doc, "totals");
        assert_true(num(tot, "disk_bytes") == real_size);
        assert_true(cJSON_IsTrue(cJSON_GetObjectItem(tot, "disk_matches_file_size")));
        cJSON *level = cJSON_GetObjectItem(doc, "level");
        assert_true(num(level, "objects") == 3);
        if (k == 1 || k == 2) {
            /* make_corpus: pages 8×4 and 4×4, one 2×2×2 LLG with 3 vertices */
            assert_true(num(level, "lm_texels") == 48);
            assert_true(num(level, "lm_pages") == 2);
            assert_true(num(level, "llg_probes") == 8);
            assert_true(num(level, "memory_without_dls_bytes") == 48 * 8 + 8 * 28 + 3 * 4);
            assert_true(num(level, "memory_with_dls_bytes") == num(level, "memory_without_dls_bytes"));
        }
        cJSON_Delete(doc);
        free(r.out);
    }
}

static void test_inspect_text_and_errors(void **state)
{
    (void)state;
    run_result r = run(lbk_cmd_inspect, 2, (const char *[]){"inspect", objects_raw, NULL});
    assert_int_equal(r.code, LBK_EXIT_OK);
    assert_non_null(strstr(r.out, "# LM texels"));
    assert_non_null(strstr(r.out, "== file size"));
    assert_non_null(strstr(r.out, "2 pages, 48 texels"));
    free(r.out);
    char *bad = copy_with(small, 100, -1);
    r = run(lbk_cmd_inspect, 2, (const char *[]){"inspect", bad, NULL});
    assert_int_equal(r.code, LBK_EXIT_INPUT);
    free(r.out);
    unlink(bad);
    free(bad);
    r = run(lbk_cmd_inspect, 2, (const char *[]){"inspect", "/nonexistent/x.lbk", NULL});
    assert_int_equal(r.code, LBK_EXIT_IO);
    free(r.out);
    r = run(lbk_cmd_inspect, 1, (const char *[]){"inspect", NULL});
    assert_int_equal(r.code, LBK_EXIT_USAGE);
    free(r.out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validate_exit_codes),
        cmocka_unit_test(test_validate_json),
        cmocka_unit_test(test_inspect_json_adds_up),
        cmocka_unit_test(test_inspect_text_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
