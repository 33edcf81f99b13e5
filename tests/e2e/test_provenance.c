/* Provenance (META, spec/container.md §6.2) of real bakes of cornell_box_bjs (a .gltf with a .bin
 * buffer and two PNG textures) with a sky EXR given to the baker:
 *   - input.files lists every file the bake read — the .gltf, the .bin, both PNGs and the EXR —
 *     each with its XXH3-64 and size as the test computes them from the files, paths relative to
 *     the scene's folder; input.hash is the XXH3-64 of that list;
 *   - every option that changes bytes has its key (sky, dls threshold, door method, octahedral
 *     probes, no-GLG, seed, …) with the value used;
 *   - scene.objects has one line per OBJS record, scene.materials one per material;
 *   - a copy of the level with one PNG repainted: lbk diff names that file, the material that
 *     samples it and the objects that use that material, and no geometry change. */
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
#include <xxhash.h>

#include "lbk/meta.h"
#include "support/bake_file.h"
#include "support/scenes_dir.h"
#include "tools/common/file_util.h"
#include "tools/common/image_io.h"
#include "tools/inspect/diff.h"

static char dir[64];
static char scene_dir[1024];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/lbk-prov-XXXXXX");
    if (!mkdtemp(dir)) return -1;
    sd_path(scene_dir, sizeof scene_dir, "cornell_box_bjs");
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* The scene must be there (scenes/ or $LBK_SCENES): a missing file fails, naming it. */
static void require_scene(void)
{
    char gltf[1200];
    snprintf(gltf, sizeof gltf, "%s/cornellBox-2.80-Eevee-gltf.gltf", scene_dir);
    SD_REQUIRE(gltf);
}

static void file_hash(const char *path, uint64_t *hash, uint64_t *bytes)
{
    void *d;
    size_t n;
    char err[TL_ERR_LEN];
    if (tl_read_file(path, &d, &n, err)) fail_msg("%s", err);
    *hash = XXH3_64bits(d, n);
    *bytes = n;
    free(d);
}

/* A 4×2 equirectangular sky of radiance (1, 0.9, 0.8). */
static void write_sky(const char *path)
{
    float px[4 * 2 * 3];
    for (int i = 0; i < 8; i++) px[3 * i] = 1.0f, px[3 * i + 1] = 0.9f, px[3 * i + 2] = 0.8f;
    const char *names[3] = {"R", "G", "B"};
    char err[TL_ERR_LEN];
    if (tl_exr_write(path, 4, 2, 3, names, px, err)) fail_msg("%s", err);
}

static void bake(const char *gltf, const char *sky, const char *out, tl_bake *b)
{
    tb_job job = {gltf, out, NULL, {0}};
    job.d.seed = 1;
    job.d.max_samples = 16;
    job.d.sky_override = 1;
    job.d.sky_exr = sky;
    job.d.dls_threshold = 0.05;
    job.d.door_method = LBK_BAKE_DOOR_GUIDED;
    job.d.octahedral_probes = 1;
    job.d.octp_levels = 2;
    job.d.octp_clip = 8;
    job.d.gather_limit = 3;
    job.d.llg_connected = 1;
    job.d.adaptive = -1;
    char err[1024];
    assert_int_equal(tb_bake(&job, NULL, err, sizeof err), LBK_OK);
    if (tl_bake_open_file(out, b, err) != TL_OPEN_OK) fail_msg("%s", err);
}

static char *meta(const tl_bake *b, const char *key)
{
    lbk_string v;
    if (lbk_meta_find(&b->meta, key, &v) != LBK_OK) fail_msg("META has no %s", key);
    char *s = malloc(v.size + 1);
    memcpy(s, v.data, v.size);
    s[v.size] = 0;
    return s;
}

static size_t lines(const char *s)
{
    size_t n = 0;
    for (; *s; s++) n += *s == '\n';
    return n;
}

static void test_every_input_and_option(void **state)
{
    (void)state;
    require_scene();
    char gltf[1200], sky[128], out[128];
    snprintf(gltf, sizeof gltf, "%s/cornellBox-2.80-Eevee-gltf.gltf", scene_dir);
    snprintf(sky, sizeof sky, "%s/sky.exr", dir);
    snprintf(out, sizeof out, "%s/a.lbk", dir);
    write_sky(sky);
    tl_bake b;
    bake(gltf, sky, out, &b);

    /* every file, hashed as the test hashes it */
    static const char *const files[5][2] = {{"scene", "cornellBox-2.80-Eevee-gltf.gltf"},
                                            {"buffer", "cornellBox-2.80-Eevee-gltf.bin"},
                                            {"image", "checkerBJS.png"},
                                            {"image", "checker-meter.png"},
                                            {"sky", "sky.exr"}};
    char *list = meta(&b, "input.files");
    if (lines(list) != 5) fail_msg("input.files has %zu lines, expected 5:\n%s", lines(list), list);
    for (int i = 0; i < 5; i++) {
        char path[1300], want[1400];
        uint64_t h, n;
        snprintf(path, sizeof path, "%s/%s", i == 4 ? dir : scene_dir, files[i][1]);
        file_hash(path, &h, &n);
        snprintf(want, sizeof want, "%016llx %llu %s %s\n", (unsigned long long)h, (unsigned long long)n, files[i][0],
                 files[i][1]);
        if (!strstr(list, want)) fail_msg("input.files lacks \"%s\":\n%s", want, list);
    }
    char *ih = meta(&b, "input.hash"), want_hash[17];
    lbk_meta_hash_hex(XXH3_64bits(list, strlen(list)), want_hash);
    assert_string_equal(ih, want_hash);
    free(ih);
    free(list);

    /* the options that change bytes */
    static const char *const opts[][2] = {{"bake.seed", "1"}, {"bake.max_samples", "16"}, {"bake.dls_threshold", "0.05"},
                                          {"bake.door_method", "guided"}, {"bake.octahedral", "1"}, {"bake.no_glg", "0"},
                                          {"bake.preset", "fast"}, {"bake.texel_density", "8"}, {"bake.glg_spacing", "2"},
                                          {"bake.target_error", "0.03"}, {"bake.max_bounces", "0"}, {"bake.time_limit", "0"},
                                          {"bake.octp_levels", "2"}, {"bake.octp_clip", "8"}, {"bake.gather_limit", "3"},
                                          {"bake.llg_connected", "1"}, {"bake.adaptive", "off"}};
    for (size_t i = 0; i < sizeof opts / sizeof opts[0]; i++) {
        char *v = meta(&b, opts[i][0]);
        if (strcmp(v, opts[i][1])) fail_msg("%s = %s, expected %s", opts[i][0], v, opts[i][1]);
        free(v);
    }
    char *skyv = meta(&b, "bake.sky");
    assert_int_equal(strncmp(skyv, "exr sky.exr ", 12), 0);
    free(skyv);
    char *objs = meta(&b, "scene.objects"), *mats = meta(&b, "scene.materials");
    assert_int_equal(lines(objs), b.objs.count);
    assert_int_equal(lines(mats), 13); /* SOURCES.md: 13 materials */
    free(objs);
    free(mats);
    tl_bake_close(&b);
}

/* Copies the level into the temp folder with checkerBJS.png repainted (another valid PNG). */
static void copy_with_new_texture(const char *to)
{
    char cmd[4600]; /* four 1023-byte paths */
    snprintf(cmd, sizeof cmd, "mkdir -p '%s' && cp '%s'/*.gltf '%s'/*.bin '%s'/*.png '%s'/", to, scene_dir, scene_dir,
             scene_dir, to);
    assert_int_equal(system(cmd), 0);
    uint8_t rgb[8 * 8 * 3];
    for (int i = 0; i < 64; i++) rgb[3 * i] = (uint8_t)(i * 4), rgb[3 * i + 1] = 40, rgb[3 * i + 2] = 200;
    char path[1100], err[TL_ERR_LEN];
    snprintf(path, sizeof path, "%s/checkerBJS.png", to);
    assert_int_equal(tl_png_write_rgb8(path, 8, 8, rgb, err), 0);
}

static void test_diff_names_the_changed_texture(void **state)
{
    (void)state;
    require_scene();
    char a_dir[128], b_dir[128], sky[128], ga[256], gb[256], oa[128], ob[128];
    snprintf(a_dir, sizeof a_dir, "%s/level_a", dir);
    snprintf(b_dir, sizeof b_dir, "%s/level_b", dir);
    snprintf(sky, sizeof sky, "%s/sky.exr", dir);
    write_sky(sky);
    char cmd[4600];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s' && cp '%s'/*.gltf '%s'/*.bin '%s'/*.png '%s'/", a_dir, scene_dir, scene_dir,
             scene_dir, a_dir);
    assert_int_equal(system(cmd), 0);
    copy_with_new_texture(b_dir);
    snprintf(ga, sizeof ga, "%s/cornellBox-2.80-Eevee-gltf.gltf", a_dir);
    snprintf(gb, sizeof gb, "%s/cornellBox-2.80-Eevee-gltf.gltf", b_dir);
    snprintf(oa, sizeof oa, "%s/a.lbk", dir);
    snprintf(ob, sizeof ob, "%s/b.lbk", dir);
    tl_bake a, b;
    bake(ga, sky, oa, &a);
    bake(gb, sky, ob, &b);
    tl_diff_options o = {0};
    tl_diff_result r;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_diff_run(&a, &b, &o, &r, err), 0);
    int file = 0, material = 0, objects = 0;
    for (size_t i = 0; i < r.change_count; i++) {
        const tl_diff_change *c = &r.changes[i];
        if (c->kind == TL_CHANGE_FILE) {
            assert_string_equal(c->name, "checkerBJS.png"); /* only that file */
            assert_int_equal(c->status, TL_DIFF_CHANGED);
            file++;
        }
        if (c->kind == TL_CHANGE_MATERIAL) {
            assert_non_null(strstr(c->what, "albedo_tex")); /* the texture, not the colours */
            material++;
        }
        if (c->kind == TL_CHANGE_OBJECT) {
            assert_non_null(strstr(c->what, " material changed"));
            objects++;
        }
        assert_true(c->kind != TL_CHANGE_OPTION && c->kind != TL_CHANGE_LIGHT);
    }
    assert_int_equal(file, 1);
    assert_int_equal(material, 1);
    assert_true(objects >= 1);
    for (size_t i = 0; i < r.object_count; i++) assert_int_equal(r.objects[i].inputs_changed & ~TL_INPUT_MATERIAL, 0);
    tl_diff_free(&r);
    tl_bake_close(&a);
    tl_bake_close(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_input_and_option),
        cmocka_unit_test(test_diff_names_the_changed_texture),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
