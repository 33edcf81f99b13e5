/* What the glTF import tests share (see import_fixtures.h). */
#include "tests/support/import_fixtures.h"

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tests/support/bake_file.h"
#include "tests/support/scenes_dir.h"

/* A scene of scenes/ (or $LBK_SCENES): a missing file fails the test, naming it. */
int imp_import_shared(const char *rel, bk_scene *s, bk_import_options *opt)
{
    char path[1024], err[1024];
    sd_path(path, sizeof path, rel);
    SD_REQUIRE(path);
    int rc = bk_import_gltf(path, opt, s, err, sizeof err);
    if (rc) printf("import %s: %s\n", path, err);
    return rc;
}

const bk_material *imp_find_material(const bk_scene *s, const char *name)
{
    for (size_t i = 0; i < s->material_count; i++)
        if (!strcmp(s->materials[i].name, name)) return &s->materials[i];
    return NULL;
}

const bk_object *imp_find_object(const bk_scene *s, const char *name)
{
    for (size_t i = 0; i < s->object_count; i++)
        if (!strcmp(s->objects[i].name, name)) return &s->objects[i];
    return NULL;
}

const bk_light *imp_find_light(const bk_scene *s, const char *name)
{
    for (size_t i = 0; i < s->light_count; i++)
        if (!strcmp(s->lights[i].name, name)) return &s->lights[i];
    return NULL;
}

size_t imp_emissive_materials_used(const bk_scene *s)
{
    size_t n = 0;
    for (size_t m = 0; m < s->material_count; m++) {
        const bk_material *mt = &s->materials[m];
        if (mt->emission[0] <= 0 && mt->emission[1] <= 0 && mt->emission[2] <= 0) continue;
        for (size_t t = 0; t < s->tri_count; t++)
            if (s->tri_material[t] == m) { n++; break; }
    }
    return n;
}

void imp_assert_valid(const bk_scene *s)
{
    char err[512];
    int rc = bk_scene_check(s, err, sizeof err);
    if (rc) printf("bk_scene_check: %s\n", err);
    assert_int_equal(rc, 0);
}

/* A scratch directory per test binary run. */
static char g_tmp[256];

void imp_tmp_path(char *out, size_t n, const char *name)
{
    snprintf(out, n, "%s/%s", g_tmp, name);
}

void imp_write_file(const char *name, const void *data, size_t len)
{
    char p[512];
    imp_tmp_path(p, sizeof p, name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    fclose(f);
}

void imp_write_text(const char *name, const char *text) { imp_write_file(name, text, strlen(text)); }

/* Imports tmp/name; returns rc, error text in err. */
int imp_import_tmp(const char *name, bk_scene *s, const bk_import_options *opt, char *err, size_t n)
{
    char p[512];
    imp_tmp_path(p, sizeof p, name);
    err[0] = 0;
    return bk_import_gltf(p, opt, s, err, n);
}

void imp_expect_error(const char *name, const char *needle1, const char *needle2)
{
    bk_scene s;
    char err[1024];
    int rc = imp_import_tmp(name, &s, NULL, err, sizeof err);
    if (!rc || (needle1 && !strstr(err, needle1)) || (needle2 && !strstr(err, needle2)))
        printf("%s: rc %d, message: %s (expected \"%s\" and \"%s\")\n", name, rc, err, needle1 ? needle1 : "",
               needle2 ? needle2 : "");
    assert_int_not_equal(rc, 0);
    if (needle1) assert_non_null(strstr(err, needle1));
    if (needle2) assert_non_null(strstr(err, needle2));
    assert_non_null(strstr(err, name)); /* the message names the file */
    assert_int_equal(s.tri_count, 0);
    assert_null(s.positions);
}

int imp_setup_tmp(void **state)
{
    (void)state;
    snprintf(g_tmp, sizeof g_tmp, "/tmp/lbk_test_import_XXXXXX");
    return mkdtemp(g_tmp) ? 0 : -1;
}

int imp_teardown_tmp(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_tmp);
    return system(cmd) == 0 ? 0 : -1;
}

/* tri.bin: 4 positions of a unit quad in the XY plane (z = 0), then 6 uint16 indices
 * (0 1 2, 0 2 3), then 4 +Z normals. 48 + 12 + 48 = 108 bytes. */
void imp_write_quad_bin(void)
{
    static const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    imp_write_quad_bin_at(pos);
}

void imp_write_quad_bin_at(const float pos[12])
{
    unsigned char buf[108];
    uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    float nrm[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    memcpy(buf, pos, 48);
    memcpy(buf + 48, idx, 12);
    memcpy(buf + 60, nrm, 48);
    imp_write_file("quad.bin", buf, sizeof buf);
}

/* A glTF with one quad mesh (mesh 0, indexed, with normals) and mesh 1 (same quad, no normals,
 * non-indexed: the first three positions). `nodes`, `extras`, `extensions` and `more` are spliced
 * in as JSON text. */
void imp_write_quad_gltf(const char *name, const char *nodes, const char *scene_nodes, const char *top)
{
    char json[8192];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},%s"
             "\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},"
             "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":48}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
             "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
             "\"materials\":[{\"name\":\"lamp\",\"emissiveFactor\":[1,0.5,0],"
             "\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":10}}},"
             "{\"name\":\"grey\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.25,0.125,1]},\"doubleSided\":true}],"
             "\"meshes\":[{\"name\":\"quad\",\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":2},\"indices\":1,\"material\":1}]},"
             "{\"name\":\"flat\",\"primitives\":[{\"attributes\":{\"POSITION\":3},\"material\":0}]}],"
             "\"nodes\":[%s],\"scenes\":[{\"nodes\":[%s]%s}],\"scene\":0}",
             top ? top : "", nodes, scene_nodes, "");
    imp_write_text(name, json);
}

void imp_write_quad_gltf_scene_extras(const char *name, const char *nodes, const char *scene_nodes,
                                         const char *scene_extras)
{
    char json[8192];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},"
             "\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
             "\"nodes\":[%s],\"scenes\":[{\"nodes\":[%s],\"extras\":%s}]}",
             nodes, scene_nodes, scene_extras);
    imp_write_text(name, json);
}

void imp_bake_tmp(const char *name, const char *out)
{
    char in[512], path[512], err[512];
    imp_tmp_path(in, sizeof in, name);
    imp_tmp_path(path, sizeof path, out);
    tb_job j;
    memset(&j, 0, sizeof j);
    j.in = in;
    j.out = path;
    j.d.preset = LBK_BAKE_PRESET_FAST;
    j.d.seed = 1;
    j.d.threads = 1;
    j.d.max_samples = 8;
    j.d.texel_density = 4;
    j.d.no_glg = 1;
    if (tb_bake(&j, NULL, err, sizeof err) != LBK_OK) fail_msg("bake %s: %s", name, err);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_true(st.st_size > 0);
}
