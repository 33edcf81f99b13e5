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
 * And the same for LLG objects: a prop baked with shared vertices and read with a glTF that
 * lists the same triangles per corner (same geometry hash, another number of LLG vertex records)
 * is refused by both (lbk view drew it without its LLG data before).
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

/* ---- LLG: the grid's vertex records against the mesh ---------------------------------------- */

/* A ground quad (lightmap, no NORMAL) and a prop quad with NORMAL (llg) under a sky, the prop's
 * two triangles over 4 shared vertices (indexed) or 6 (the same triangles as a vertex list): the
 * same geometry hash, but 4 or 6 LLG vertex records (spec §11 "Vertex order"). */
static void write_llg_level(const char *dir, const char *name, int indexed)
{
    static const float ground[12] = {-2, 0, -2, -2, 0, 2, 2, 0, 2, 2, 0, -2};
    static const uint32_t quad_idx[6] = {0, 1, 2, 0, 2, 3};
    static const float prop[12] = {-0.5f, 0.5f, 0, 0.5f, 0.5f, 0, 0.5f, 1.5f, 0, -0.5f, 1.5f, 0};
    float pp[18], nn[18];
    const uint32_t pv = indexed ? 4 : 6;
    for (uint32_t k = 0; k < pv; k++) {
        const uint32_t v = indexed ? k : quad_idx[k];
        memcpy(&pp[3 * k], &prop[3 * v], 3 * sizeof(float));
        nn[3 * k] = 0, nn[3 * k + 1] = 0, nn[3 * k + 2] = 1;
    }
    uint8_t bin[256];
    size_t n = 0;
    memcpy(bin + n, ground, 48), n += 48;
    memcpy(bin + n, quad_idx, 24), n += 24;
    const size_t prop_pos = n;
    memcpy(bin + n, pp, 12 * pv), n += 12 * pv;
    const size_t prop_nrm = n;
    memcpy(bin + n, nn, 12 * pv), n += 12 * pv;
    char path[256], json[4096];
    snprintf(path, sizeof path, "%s/%s.bin", dir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bin, 1, n, f), n);
    fclose(f);
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,"
             "\"scenes\":[{\"nodes\":[0,1],\"extras\":{\"lbk_sky\":[1,1,1]}}],"
             "\"nodes\":[{\"name\":\"ground\",\"mesh\":0,\"extras\":{\"lbk_lighting\":\"lightmap\"}},"
             "{\"name\":\"prop\",\"mesh\":1,\"extras\":{\"lbk_lighting\":\"llg\"}}],"
             "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.8,0.8,1]}}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]},"
             "{\"primitives\":[{\"attributes\":{\"POSITION\":2,\"NORMAL\":3}%s,\"material\":0}]}],"
             "\"buffers\":[{\"uri\":\"%s.bin\",\"byteLength\":%zu}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":24},"
             "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%u},{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%u}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
             "\"min\":[-2,0,-2],\"max\":[2,0,2]},"
             "{\"bufferView\":1,\"componentType\":5125,\"count\":6,\"type\":\"SCALAR\"},"
             "{\"bufferView\":2,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\","
             "\"min\":[-0.5,0.5,0],\"max\":[0.5,1.5,0]},"
             "{\"bufferView\":3,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"}]}",
             indexed ? ",\"indices\":1" : "", name, n, prop_pos, 12 * pv, prop_nrm, 12 * pv, pv, pv);
    snprintf(path, sizeof path, "%s/%s.gltf", dir, name);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(json, f);
    fclose(f);
}

/* The prop baked with shared vertices, then read with the glTF that lists them per corner: the
 * geometry hash matches, the LLG grid's 4 vertex records do not describe the 6 vertices. lbk
 * render refused it; lbk view (its glTF export) drew the prop without its LLG data. Both refuse
 * now (exit 4); the level as baked is taken by both. */
static void llg_readers_agree(void **state)
{
    (void)state;
    if (access(lbk_bin(), X_OK)) skip();
    char gl[160], split[160], lbk[160], exr[160], out[160];
    write_llg_level(tmpdir, "shared", 1);
    write_llg_level(tmpdir, "split", 0);
    snprintf(gl, sizeof gl, "%s/shared.gltf", tmpdir);
    snprintf(split, sizeof split, "%s/split.gltf", tmpdir);
    snprintf(lbk, sizeof lbk, "%s/llg.lbk", tmpdir);
    snprintf(exr, sizeof exr, "%s/llg.exr", tmpdir);
    snprintf(out, sizeof out, "%s/llg_page", tmpdir);
    assert_int_equal(run("%s bake %s -o %s --samples 4 --max-bounces 1 --no-glg -q >/dev/null 2>&1", gl, lbk), 0);
    char r_cmd[512], v_cmd[512]; /* run() fills in the binary, then the scene and level (view: level, scene) */
    snprintf(r_cmd, sizeof r_cmd, "%%s render %%s %%s -o %s --size 16x12 -q >/dev/null 2>&1", exr);
    snprintf(v_cmd, sizeof v_cmd, "%%s view %%s %%s --out %s -q >/dev/null 2>&1", out);
    assert_int_equal(run(r_cmd, gl, lbk), 0);
    assert_int_equal(run(v_cmd, lbk, gl), 0);
    const int r = run(r_cmd, split, lbk), w = run(v_cmd, lbk, split);
    print_message("prop baked with 4 shared vertices, read with 6: lbk render %d, lbk view %d\n", r, w);
    assert_int_equal(r, 4);
    assert_int_equal(w, 4);
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
        cmocka_unit_test(llg_readers_agree),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
