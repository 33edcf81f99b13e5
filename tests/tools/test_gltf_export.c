/* lbk export --gltf (tools/convert/gltf_export.c): a bake of a level whose lightmap UVs were
 * generated, exported and imported again with tinygltf (bake/scene's importer) has the same
 * objects, triangles and world geometry (geometry hashes of OBJS), TEXCOORD_1 on every
 * lightmapped primitive with every value in [0, 1] and inside its object's rectangle, equal to
 * the LMUV coordinates divided by the page size; the sidecar EXR/PNG files exist and the extras
 * name each primitive's page and the decode rule. A scene that is not the one baked, and a
 * container without LMUV, are refused. The exported level bakes again, its lightmap UVs now
 * authored. (gltf-validator runs on the shared scenes' exports in tests/tools/gltf_validator.sh.) */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "support/bake_file.h"
#include "scene/import.h"
#include "tools/common/bake_data.h"
#include "tools/common/file_util.h"
#include "tools/convert/gltf_export.h"
#include "lbk/container.h"
#include "support/bake_file.h"
#include "support/lmuv_scene.h"
#include "support/scenes_dir.h"

static char tmpdir[64];

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk-gltf-XXXXXX");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

static void bake(const char *in, const char *out, float density)
{
    tb_job o;
    memset(&o, 0, sizeof o);
    o.in = in;
    o.out = out;
    o.d.preset = LBK_BAKE_PRESET_FAST;
    o.d.seed = 1;
    o.d.max_samples = 16;
    o.d.threads = 2;
    o.d.texel_density = density;
    o.d.no_glg = 1;
    char err[512];
    if (tb_bake(&o, NULL, err, sizeof err)) fail_msg("bake %s: %s", in, err);
}

static void import(const char *path, bk_scene *s)
{
    char err[512];
    if (bk_import_gltf(path, NULL, s, err, sizeof err)) fail_msg("import %s: %s", path, err);
}

static uint64_t world_hash(const bk_scene *s, size_t i)
{
    const bk_object *o = &s->objects[i];
    float *xyz = malloc((size_t)o->tri_count * 9 * sizeof *xyz);
    assert_non_null(xyz);
    for (uint32_t t = 0; t < o->tri_count; t++)
        for (int c = 0; c < 3; c++)
            memcpy(&xyz[9 * t + 3 * c], &s->positions[3 * (size_t)s->tris[3 * ((size_t)o->first_tri + t) + c]], 12);
    uint64_t h = lbk_objects_geometry_hash(xyz, o->tri_count);
    free(xyz);
    return h;
}

typedef struct export_stats {
    size_t lightmapped_vertices, generated_vertices;
    double max_coord_dev; /* |TEXCOORD_1 · page size − LMUV coordinate|, texels */
} export_stats;

/* The re-imported export against the bake it came from. */
static export_stats check_reimport(const tl_bake *b, const bk_scene *src, const bk_scene *re)
{
    export_stats st;
    memset(&st, 0, sizeof st);
    assert_int_equal(re->object_count, b->objs.count);
    assert_int_equal(re->tri_count, src->tri_count);
    for (size_t i = 0; i < re->object_count; i++) {
        lbk_object ob;
        lbk_objects_get(&b->objs, (uint32_t)i, &ob);
        char name[129];
        tl_string_copy(name, sizeof name, ob.name);
        assert_string_equal(re->objects[i].name, name);
        assert_int_equal(re->objects[i].tri_count, src->objects[i].tri_count);
        assert_true(world_hash(re, i) == ob.geometry_hash); /* the same triangles at the same place */
        if (ob.representation != LBK_REPRESENTATION_LIGHTMAP) continue;
        assert_int_equal(re->objects[i].has_uv1, 1);
        lbk_lmap_page pg;
        lbk_lmap_page_get(&b->lmap, ob.index, &pg);
        uint32_t r;
        assert_int_equal(lbk_lmuv_find_object(&b->lmuv, (uint32_t)i, &r), LBK_OK);
        lbk_lmuv_object rec;
        lbk_lmuv_get_object(&b->lmuv, r, &rec);
        uint32_t k = 0, q_first = rec.primitive_first;
        for (size_t p = 0; p < re->primitive_count; p++) {
            const bk_primitive *pr = &re->primitives[p];
            if (pr->object != i) continue;
            lbk_lmuv_primitive q;
            if (rec.kind == LBK_LMUV_GENERATED) {
                lbk_lmuv_get_primitive(&b->lmuv, q_first + k, &q);
                assert_int_equal(pr->vertex_count, q.vertex_count); /* vertices split where charts split */
            }
            for (uint32_t v = 0; v < pr->vertex_count; v++) {
                const float *uv = &re->uv1[2 * ((size_t)pr->first_vertex + v)];
                assert_true(uv[0] >= 0 && uv[0] <= 1 && uv[1] >= 0 && uv[1] <= 1);
                const double X = (double)uv[0] * pg.width, Y = (double)uv[1] * pg.height, eps = 1e-3;
                if (X < ob.rect_x - eps || X > ob.rect_x + ob.rect_w + eps || Y < ob.rect_y - eps || Y > ob.rect_y + ob.rect_h + eps)
                    fail_msg("object %zu vertex %u: TEXCOORD_1 (%g, %g) outside its rect", i, v, uv[0], uv[1]);
                st.lightmapped_vertices++;
                if (rec.kind != LBK_LMUV_GENERATED) continue;
                float xy[2];
                lbk_lmuv_vertex(&b->lmuv, &q, v, NULL, xy);
                st.max_coord_dev = fmax(st.max_coord_dev, fmax(fabs(X - xy[0]), fabs(Y - xy[1])));
                st.generated_vertices++;
            }
            k++;
        }
    }
    assert_true(st.max_coord_dev < 1e-3);
    return st;
}

/* Every triangle of the re-imported export has its source triangle's albedo and emission: the
 * export's materials carry the baked light as emission over a black base colour, and the
 * importer takes a material lbk export wrote from its extras.lbk (scene/gltf_materials.cc), so the
 * export bakes as the source did. Triangles are in the same order (check_reimport's hashes). */
static void check_reimport_materials(const bk_scene *src, const bk_scene *re)
{
    assert_int_equal(re->tri_count, src->tri_count);
    for (size_t t = 0; t < re->tri_count; t++) {
        const bk_material *a = &src->materials[src->tri_material[t]], *b = &re->materials[re->tri_material[t]];
        for (int c = 0; c < 3; c++) {
            if (a->albedo[c] != b->albedo[c] || a->emission[c] != b->emission[c])
                fail_msg("triangle %zu: material %s albedo %g emission %g, re-imported %s %g %g", t, a->name, a->albedo[c],
                         a->emission[c], b->name, b->albedo[c], b->emission[c]);
        }
        assert_int_equal(b->albedo_tex, -1);
        assert_int_equal(b->emission_tex, -1);
    }
}

/* The JSON chunk of a GLB (tests only: trusts the file it just wrote). */
static cJSON *glb_json(const char *path)
{
    void *d;
    size_t n;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_read_file(path, &d, &n, err), 0);
    const uint8_t *b = d;
    assert_true(n > 20 && !memcmp(b, "glTF", 4));
    const uint32_t len = (uint32_t)b[12] | (uint32_t)b[13] << 8 | (uint32_t)b[14] << 16 | (uint32_t)b[15] << 24;
    cJSON *j = cJSON_ParseWithLength((const char *)b + 20, len);
    free(d);
    assert_non_null(j);
    return j;
}

static void check_extras(const char *glb, const tl_bake *b)
{
    cJSON *j = glb_json(glb);
    cJSON *meshes = cJSON_GetObjectItem(j, "meshes");
    int lightmapped = 0;
    for (int m = 0; m < cJSON_GetArraySize(meshes); m++) {
        cJSON *prims = cJSON_GetObjectItem(cJSON_GetArrayItem(meshes, m), "primitives");
        for (int p = 0; p < cJSON_GetArraySize(prims); p++) {
            cJSON *pr = cJSON_GetArrayItem(prims, p);
            cJSON *lm = cJSON_GetObjectItem(cJSON_GetObjectItem(cJSON_GetObjectItem(pr, "extras"), "lbk"), "lightmap");
            if (!lm) continue;
            lightmapped++;
            assert_non_null(cJSON_GetObjectItem(cJSON_GetObjectItem(pr, "attributes"), "TEXCOORD_1"));
            const int page = cJSON_GetObjectItem(lm, "page")->valueint;
            assert_true(page >= 0 && (uint32_t)page < b->lmap.page_count);
            assert_string_equal(cJSON_GetObjectItem(lm, "decode")->valuestring, "lbk-ahd/1");
            const char *files[3] = {"irradiance", "ahd", "preview"};
            for (int f = 0; f < 3; f++) {
                char path[512];
                snprintf(path, sizeof path, "%s/%s", tmpdir, cJSON_GetObjectItem(lm, files[f])->valuestring);
                if (access(path, R_OK)) fail_msg("%s is missing", path);
            }
        }
    }
    assert_true(lightmapped > 0);
    cJSON *rule = cJSON_GetObjectItem(cJSON_GetObjectItem(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "extras"), "lbk"), "decode_rules"), "lbk-ahd/1");
    assert_true(cJSON_IsString(rule) && strstr(rule->valuestring, "(x + 0.5)/width"));
    cJSON_Delete(j);
}

static void export_and_reimport(const char *scene, const char *stem, float density)
{
    char lbk[256], glb[256];
    snprintf(lbk, sizeof lbk, "%s/%s.lbk", tmpdir, stem);
    snprintf(glb, sizeof glb, "%s/%s.glb", tmpdir, stem);
    bake(scene, lbk, density);
    tl_bake b;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_bake_open_file(lbk, &b, err), TL_OPEN_OK); /* validated on open */
    assert_true(b.has_lmuv);
    tl_gltf_options o = {.output = glb, .scene = scene, .container = "x.lbk"};
    tl_gltf_stats gs;
    if (tl_gltf_export(&b, &o, &gs, err)) fail_msg("export: %s", err);
    assert_true(gs.generated > 0);
    bk_scene src, re;
    import(scene, &src);
    import(glb, &re);
    export_stats st = check_reimport(&b, &src, &re);
    check_reimport_materials(&src, &re);
    print_message("%s: %u nodes, %u primitives (%u generated, %u authored), %llu triangles; %zu lightmapped vertices "
                  "re-imported, TEXCOORD_1 within %.1e texel of LMUV\n",
                  stem, gs.nodes, gs.primitives, gs.generated, gs.authored, (unsigned long long)gs.triangles,
                  st.lightmapped_vertices, st.max_coord_dev);
    check_extras(glb, &b);
    bk_scene_free(&src);
    bk_scene_free(&re);
    tl_bake_close(&b);
}

static void hand_made_level(void **state)
{
    (void)state;
    char scene[256];
    snprintf(scene, sizeof scene, "%s/level.gltf", tmpdir);
    assert_int_equal(lmuv_scene_write(scene), 0);
    export_and_reimport(scene, "level", 16);
}

static void cornell_box(void **state)
{
    (void)state;
    char scene[1024];
    SD_REQUIRE(sd_path(scene, sizeof scene, "cornell_box/CornellBox-Original.gltf"));
    export_and_reimport(scene, "cornell", 16);
}

/* The exported level is a level: it bakes, and its lightmapped objects come back authored. */
static void export_bakes_again(void **state)
{
    (void)state;
    char glb[256], lbk[256];
    snprintf(glb, sizeof glb, "%s/level.glb", tmpdir);
    snprintf(lbk, sizeof lbk, "%s/again.lbk", tmpdir);
    if (access(glb, R_OK)) hand_made_level(state);
    bake(glb, lbk, 16);
    tl_bake b;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_bake_open_file(lbk, &b, err), TL_OPEN_OK);
    assert_int_equal(b.lmuv.record_count, LMUV_SCENE_NODES);
    for (uint32_t r = 0; r < b.lmuv.record_count; r++) {
        lbk_lmuv_object o;
        lbk_lmuv_get_object(&b.lmuv, r, &o);
        assert_int_equal(o.kind, LBK_LMUV_AUTHORED);
    }
    tl_bake_close(&b);
}

static void refuses_other_inputs(void **state)
{
    (void)state;
    char scene[256], lbk[256], glb[256], other[256], err[TL_ERR_LEN];
    snprintf(scene, sizeof scene, "%s/level.gltf", tmpdir);
    snprintf(lbk, sizeof lbk, "%s/level.lbk", tmpdir);
    snprintf(glb, sizeof glb, "%s/refused.glb", tmpdir);
    snprintf(other, sizeof other, "%s/other.gltf", tmpdir);
    if (access(lbk, R_OK)) hand_made_level(state);
    tl_bake b;
    assert_int_equal(tl_bake_open_file(lbk, &b, err), TL_OPEN_OK);
    /* another scene: the same file with one vertex moved changes a geometry hash */
    void *text;
    size_t n;
    assert_int_equal(tl_read_file(scene, &text, &n, err), 0);
    cJSON *j = cJSON_ParseWithLength(text, n);
    free(text);
    cJSON *nodes = cJSON_GetObjectItem(j, "nodes");
    cJSON_AddItemToObject(cJSON_GetArrayItem(nodes, 2), "translation", cJSON_CreateFloatArray((const float[3]){0, 0, 0.5f}, 3));
    char *moved = cJSON_Print(j);
    cJSON_Delete(j);
    assert_int_equal(tl_write_text(other, moved, err), 0);
    free(moved);
    tl_gltf_options o = {.output = glb, .scene = other};
    assert_int_equal(tl_gltf_export(&b, &o, NULL, err), TL_GLTF_INPUT);
    assert_non_null(strstr(err, "geometry"));
    o.scene = "/nonexistent/level.gltf";
    assert_int_equal(tl_gltf_export(&b, &o, NULL, err), TL_GLTF_INPUT);
    /* the same bake without its LMUV section (as a 1.0 baker wrote it) */
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    for (uint32_t i = 0; i < lbk_reader_section_count(b.reader); i++) {
        lbk_section_info si;
        lbk_reader_section_get(b.reader, i, &si);
        if (si.type == LBK_SECTION_LMUV) continue;
        const void *d;
        size_t sz;
        assert_int_equal(lbk_reader_section_data(b.reader, i, &d, &sz), LBK_OK);
        lbk_section_options so = {.flags = si.flags};
        assert_int_equal(lbk_writer_section_add(w, si.type, d, sz, &so), LBK_OK);
    }
    void *old;
    size_t old_size;
    assert_int_equal(lbk_writer_to_memory(w, &old, &old_size), LBK_OK);
    lbk_writer_close(w);
    assert_int_equal(((const uint8_t *)old)[10], 0); /* a 1.0 file again */
    tl_bake ob;
    assert_int_equal(tl_bake_open_memory(old, old_size, &ob, err), TL_OPEN_OK);
    lbk_free(NULL, old);
    o.scene = scene;
    assert_int_equal(tl_gltf_export(&ob, &o, NULL, err), TL_GLTF_INPUT);
    assert_non_null(strstr(err, "re-bake"));
    tl_bake_close(&ob);
    tl_bake_close(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(hand_made_level),
        cmocka_unit_test(cornell_box),
        cmocka_unit_test(export_bakes_again),
        cmocka_unit_test(refuses_other_inputs),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
