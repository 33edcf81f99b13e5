/* The per-texel error map (TERR, spec §18) in the readers, through the lbk binary ($LBK, else
 * build/lbk-asan) on the corpus's bake_cornell_terr.lbk (`make fuzz-corpus`: the cornell bake of
 * bake_cornell.lbk with --error-map, same seed and options):
 *  - lbk validate: valid; lbk inspect: the TERR row and level.error_map in JSON (null without);
 *  - lbk export: page_NNN.error.exr holds the decoded codes (-1 where 0), .error.png is written;
 *  - lbk diff of a bake with and without the map (baked here): exit 0 (the lighting is the same),
 *    the text says the map is present in one only;
 *  - lbk convert: the shipped profiles drop the map; pc with it kept (widening pages to 256-byte
 *    rows): the map follows the texels (the pack validates, every code at its texel's new index). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "lbk/container.h"
#include "lbk/error_map.h"
#include "lbk/lightmap.h"
#include "tools/common/file_util.h"
#include "tools/common/image_io.h"

#define TERR_LEVEL "tests/fuzz/corpus/bake_cornell_terr.lbk"
#define PLAIN_LEVEL "tests/fuzz/corpus/bake_cornell.lbk"
#define DIR "build/tests/error_map_tools"

static const char *lbk(void) { return getenv("LBK") ? getenv("LBK") : "build/lbk-asan"; }

static int run(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static int run(const char *fmt, ...)
{
    char cmd[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    const int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static char *slurp(const char *path)
{
    void *d;
    size_t n;
    char err[TL_ERR_LEN];
    if (tl_read_file(path, &d, &n, err)) return NULL;
    char *s = realloc(d, n + 1);
    s[n] = 0;
    return s;
}

static void open_terr(lbk_reader **r, lbk_terr_view *v, lbk_lmap_view *lm, const char *path)
{
    assert_int_equal(lbk_reader_open_file(path, NULL, r), LBK_OK);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(*r, LBK_SECTION_TERR, &d, &n), LBK_OK);
    assert_int_equal(lbk_terr_open(d, n, v), LBK_OK);
    assert_int_equal(lbk_reader_section_by_type(*r, LBK_SECTION_LMAP, &d, &n), LBK_OK);
    assert_int_equal(lbk_lmap_open(d, n, lm), LBK_OK);
}

static void test_validate_and_inspect(void **state)
{
    (void)state;
    if (access(lbk(), X_OK)) skip();
    assert_int_equal(run("mkdir -p " DIR), 0);
    assert_int_equal(run("%s validate " TERR_LEVEL " >/dev/null", lbk()), 0);
    assert_int_equal(run("%s inspect " TERR_LEVEL " > " DIR "/inspect.txt", lbk()), 0);
    assert_int_equal(run("%s inspect --json " TERR_LEVEL " > " DIR "/inspect.json", lbk()), 0);
    assert_int_equal(run("%s inspect --json " PLAIN_LEVEL " > " DIR "/inspect_plain.json", lbk()), 0);
    char *t = slurp(DIR "/inspect.txt"), *j = slurp(DIR "/inspect.json"), *p = slurp(DIR "/inspect_plain.json");
    assert_true(t && j && p);
    assert_non_null(strstr(t, "TERR"));
    assert_non_null(strstr(t, "per-texel relative error of"));
    assert_non_null(strstr(j, "\"type\":\t\"TERR\""));
    assert_non_null(strstr(j, "\"texels_with_estimate\""));
    assert_non_null(strstr(j, "\"before_denoising\":\ttrue")); /* the corpus bake is denoised (auto) */
    assert_non_null(strstr(p, "\"error_map\":\tnull"));
    free(t), free(j), free(p);
}

static void test_export_writes_the_map(void **state)
{
    (void)state;
    if (access(lbk(), X_OK)) skip();
    assert_int_equal(run("rm -rf " DIR "/exr && %s export " TERR_LEVEL " --exr " DIR "/exr --png " DIR "/exr -q", lbk()), 0);
    lbk_reader *r;
    lbk_terr_view v;
    lbk_lmap_view lm;
    open_terr(&r, &v, &lm, TERR_LEVEL);
    static const char *const Y[1] = {"Y"};
    size_t checked = 0, none = 0;
    for (uint32_t p = 0; p < lm.page_count; p++) {
        char path[256], err[TL_ERR_LEN];
        snprintf(path, sizeof path, DIR "/exr/page_%03u.error.exr", (unsigned)p);
        int w, h;
        float *px;
        assert_int_equal(tl_exr_read(path, 1, Y, &w, &h, &px, err), 0);
        lbk_lmap_planes pl;
        assert_int_equal(lbk_lmap_planes_get(&lm, p, &pl), LBK_OK);
        assert_int_equal(w, pl.width);
        assert_int_equal(h, pl.height);
        for (int i = 0; i < w * h; i++, checked++) {
            const uint8_t c = v.codes[pl.first_texel + (uint64_t)i];
            none += c == 0;
            assert_true(px[i] == (float)lbk_terr_decode(c));
        }
        free(px);
        snprintf(path, sizeof path, DIR "/exr/page_%03u.error.png", (unsigned)p);
        assert_int_equal(access(path, R_OK), 0);
    }
    print_message("export: %zu texels of the error map as stored (%zu without an estimate)\n", checked, none);
    assert_true(checked == v.texel_count && none > 0 && none < checked);
    lbk_reader_close(r);
    /* without the map: no error files */
    assert_int_equal(run("rm -rf " DIR "/plain && %s export " PLAIN_LEVEL " --exr " DIR "/plain -q", lbk()), 0);
    assert_int_not_equal(access(DIR "/plain/page_000.error.exr", R_OK), 0);
    assert_int_equal(access(DIR "/plain/page_000.exr", R_OK), 0);
}

static void test_diff_reports_presence(void **state)
{
    (void)state;
    if (access(lbk(), X_OK)) skip();
    /* the pair baked here, with the same binary (the corpus files may come from older bakers) */
    const char *opts = "--threads 2 --texel-density 2 --samples 8 --glg-spacing 2.5 -q";
    assert_int_equal(run("mkdir -p " DIR " && %s bake scenes/cornell_box/CornellBox-Original.gltf -o " DIR "/plain.lbk %s", lbk(), opts), 0);
    assert_int_equal(run("%s bake scenes/cornell_box/CornellBox-Original.gltf -o " DIR "/terr.lbk %s --error-map", lbk(), opts), 0);
    assert_int_equal(run("%s diff " DIR "/plain.lbk " DIR "/terr.lbk > " DIR "/diff.txt", lbk()), 0);
    char *t = slurp(DIR "/diff.txt");
    assert_non_null(t);
    assert_non_null(strstr(t, "per-texel error map is present in B only"));
    free(t);
    assert_int_equal(run("%s diff " DIR "/terr.lbk " DIR "/plain.lbk > " DIR "/diff2.txt", lbk()), 0);
    t = slurp(DIR "/diff2.txt");
    assert_non_null(strstr(t, "present in A only"));
    free(t);
}

static void test_convert_moves_the_map(void **state)
{
    (void)state;
    if (access(lbk(), X_OK)) skip();
    /* the shipped profiles drop TERR (a diagnostic); pc with TERR kept widens pages to 256-byte rows */
    assert_int_equal(run("%s convert " TERR_LEVEL " -o " DIR "/pc_drop.lbk --profile pc >/dev/null", lbk()), 0);
    assert_int_equal(run("%s inspect " DIR "/pc_drop.lbk | grep -q TERR", lbk()), 1);
    assert_int_equal(run("sed 's/^TERR = drop/TERR = zstd:19/' tools/convert/profiles/pc.profile > " DIR "/pc_terr.profile"), 0);
    assert_int_equal(run("%s convert " TERR_LEVEL " -o " DIR "/pc.lbk --profile " DIR "/pc_terr.profile >/dev/null", lbk()), 0);
    assert_int_equal(run("%s validate " DIR "/pc.lbk >/dev/null", lbk()), 0);
    lbk_reader *a, *b;
    lbk_terr_view va, vb;
    lbk_lmap_view la, lb;
    open_terr(&a, &va, &la, TERR_LEVEL);
    open_terr(&b, &vb, &lb, DIR "/pc.lbk");
    assert_int_equal(la.page_count, lb.page_count);
    int widened = 0;
    for (uint32_t p = 0; p < la.page_count; p++) {
        lbk_lmap_planes pa, pb;
        lbk_lmap_planes_get(&la, p, &pa), lbk_lmap_planes_get(&lb, p, &pb);
        widened |= pb.width != pa.width;
        for (uint32_t y = 0; y < pa.height; y++)
            for (uint32_t x = 0; x < pa.width; x++)
                assert_int_equal(vb.codes[pb.first_texel + (uint64_t)y * pb.width + x], va.codes[pa.first_texel + (uint64_t)y * pa.width + x]);
        for (uint32_t y = 0; y < pb.height; y++) /* the new padding: no estimate */
            for (uint32_t x = pa.width; x < pb.width; x++) assert_int_equal(vb.codes[pb.first_texel + (uint64_t)y * pb.width + x], 0);
    }
    assert_true(widened); /* the profile did move texels */
    lbk_reader_close(a), lbk_reader_close(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validate_and_inspect),
        cmocka_unit_test(test_export_writes_the_map),
        cmocka_unit_test(test_diff_reports_presence),
        cmocka_unit_test(test_convert_moves_the_map),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
