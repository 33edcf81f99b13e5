/* One verdict for every reader of LMUV (spec/container.md §16): a container whose LMUV no longer
 * describes the glTF it was baked from (checksums repaired, so `lbk validate` still passes: the
 * validator never sees the glTF) is refused by lbk render and lbk view alike, exit code 4
 * (LBK_EXIT_INPUT), through the one check both make (tools/common/lmuv_match.h). Before, lbk
 * render drew such files and lbk view (its glTF export) refused them.
 *
 * The edits, on the Cornell box bake of the fuzz corpus, to its first GENERATED record:
 *  - the record's glTF node;
 *  - its first primitive's source vertex count (the remap entries stay below it);
 *  - the remap entry of the new vertex that primitive's first corner uses (still in range).
 * The processes are the lbk binary: $LBK, else build/lbk-asan (SKIPPED without it). */
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

#include <xxhash.h>

#include "lbk/lightmap_uv.h"
#include "support/container_fixture.h"
#include "tools/common/file_util.h"
#include "tools/common/image_io.h"

#define LEVEL "tests/fuzz/corpus/bake_cornell.lbk"
#define SCENE "scenes/cornell_box/CornellBox-Original.gltf"

static char tmpdir[64];

static uint32_t rd32(const uint8_t *p) { return p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t rd64(const uint8_t *p) { return rd32(p) | (uint64_t)rd32(p + 4) << 32; }
static void wr32(uint8_t *p, uint32_t v) { p[0] = (uint8_t)v, p[1] = (uint8_t)(v >> 8), p[2] = (uint8_t)(v >> 16), p[3] = (uint8_t)(v >> 24); }
static void wr64(uint8_t *p, uint64_t v) { wr32(p, (uint32_t)v), wr32(p + 4, (uint32_t)(v >> 32)); }

static const char *lbk_bin(void) { return getenv("LBK") ? getenv("LBK") : "build/lbk-asan"; }

static int run(const char *fmt, const char *a, const char *b)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, fmt, lbk_bin(), a, b);
    const int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The LMUV table entry of file f (uncompressed in this bake). */
static uint8_t *lmuv_entry(uint8_t *f)
{
    const uint32_t n = rd32(f + 32);
    for (uint32_t k = 0; k < n; k++)
        if (!memcmp(f + 64 + 48 * (size_t)k, "LMUV", 4)) return f + 64 + 48 * (size_t)k;
    return NULL;
}

/* An edit of the section through its view: the first GENERATED record, its first primitive. */
typedef void (*edit_fn)(const lbk_lmuv_view *v, uint8_t *record, uint8_t *primitive);

static void edit_node(const lbk_lmuv_view *v, uint8_t *rec, uint8_t *prim) { wr32(rec + 8, rd32(rec + 8) + 1000); }
static void edit_source_vertices(const lbk_lmuv_view *v, uint8_t *rec, uint8_t *prim) { wr32(prim + 4, rd32(prim + 4) + 1); }
static void edit_remap(const lbk_lmuv_view *v, uint8_t *rec, uint8_t *prim)
{
    const uint64_t vf = rd64(prim + 16), xf = rd64(prim + 24);
    const uint32_t nv = rd32(v->indices + 4 * xf), svc = rd32(prim + 4); /* the first corner's vertex */
    uint8_t *remap = (uint8_t *)v->remap + 4 * (vf + nv);
    wr32(remap, (rd32(remap) + 1) % svc);
}

/* LEVEL with its LMUV edited and every checksum repaired, written to path. */
static void write_edited(edit_fn edit, const char *path)
{
    void *buf;
    size_t n;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_read_file(LEVEL, &buf, &n, err), 0);
    uint8_t *f = buf, *e = lmuv_entry(f);
    assert_non_null(e);
    assert_int_equal(rd32(e + 8), 0); /* stored as is */
    uint8_t *d = f + rd64(e + 16);
    const size_t size = (size_t)rd64(e + 24);
    lbk_lmuv_view v;
    assert_int_equal(lbk_lmuv_open(d, size, &v), LBK_OK);
    uint32_t r = 0;
    lbk_lmuv_object o;
    while (r < v.record_count && lbk_lmuv_get_object(&v, r, &o) == LBK_OK && o.kind != LBK_LMUV_GENERATED) r++;
    assert_true(r < v.record_count);
    uint8_t *rec = (uint8_t *)v.records + (size_t)LBK_LMUV_RECORD_SIZE * r;
    uint8_t *prim = (uint8_t *)v.primitives + (size_t)LBK_LMUV_PRIMITIVE_SIZE * o.primitive_first;
    assert_true(rd32(prim + 4) > 1);
    edit(&v, rec, prim);
    assert_int_equal(lbk_lmuv_open(d, size, &v), LBK_OK); /* still a well-formed section */
    wr64(e + 40, XXH3_64bits(d, size));
    fixture_fix_checksums(f);
    assert_int_equal(tl_write_file_atomic(path, f, n, err), 0);
    free(buf);
}

static void readers_agree(void **state)
{
    (void)state;
    if (access(lbk_bin(), X_OK) || access(SCENE, R_OK)) skip();
    char exr[128], out[128];
    snprintf(exr, sizeof exr, "%s/view.exr", tmpdir);
    snprintf(out, sizeof out, "%s/page", tmpdir);
    const char *render = "%s render " SCENE " %s -o %s --size 16x12 -q >/dev/null 2>&1";
    const char *view = "%s view %s " SCENE " --out %s -q >/dev/null 2>&1";
    /* the bake as written: both readers take it */
    assert_int_equal(run(render, LEVEL, exr), 0);
    assert_int_equal(run(view, LEVEL, out), 0);
    static const struct {
        const char *what;
        edit_fn edit;
    } cases[] = {{"glTF node", edit_node}, {"source vertex count", edit_source_vertices}, {"remap entry", edit_remap}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char lbk[128];
        snprintf(lbk, sizeof lbk, "%s/edited%zu.lbk", tmpdir, k);
        write_edited(cases[k].edit, lbk);
        const int validate = run("%s validate %s%s >/dev/null 2>&1", lbk, ""), r = run(render, lbk, exr),
                  w = run(view, lbk, out);
        print_message("LMUV %s edited: lbk validate %d, lbk render %d, lbk view %d\n", cases[k].what, validate, r, w);
        assert_int_equal(validate, 0); /* nothing liblbk can see without the glTF */
        assert_int_equal(r, 4);
        assert_int_equal(w, 4);
    }
}

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk_test_lmuv_readers_XXXXXX");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(readers_agree),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
