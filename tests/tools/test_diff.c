/* lbk diff: matching, decoded-lighting metrics, tolerance boundaries, JSON schema, exit codes. */
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

#include "cli/cli.h"
#include "tools/convert/convert.h"
#include "tools/common/file_util.h"
#include "tools/inspect/diff.h"
#include "lbk/lightmap.h"
#include "lbk/octa.h"
#include "lbk/validate.h"
#include "support/bake_file.h"
#include "support/scenes_dir.h"
#include "support/tools_fixtures.h"

static char tmpdir[64];

static int setup_dir(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk-diff-XXXXXX");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int teardown_dir(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

static void open_blob(const tf_blob *b, tl_bake *out)
{
    char err[TL_ERR_LEN];
    if (tl_bake_open_memory(b->data, b->size, out, err) != TL_OPEN_OK) fail_msg("%s", err);
}

/* Runs a diff of two fixture scenes. */
static void run_diff(const tf_options *oa, const tf_options *ob, double abs_tol, double rel_tol, int maps,
                     tl_diff_result *r)
{
    tf_blob a = tf_build_scene(TF_SCENE_FULL, oa), b = tf_build_scene(TF_SCENE_FULL, ob);
    tl_bake ba, bb;
    open_blob(&a, &ba);
    open_blob(&b, &bb);
    tl_diff_options o = {.abs_tol = abs_tol, .rel_tol = rel_tol, .keep_error_maps = maps};
    char err[TL_ERR_LEN];
    assert_int_equal(tl_diff_run(&ba, &bb, &o, r, err), 0);
    tl_bake_close(&ba);
    tl_bake_close(&bb);
    tf_blob_free(&a);
    tf_blob_free(&b);
}

static const tl_diff_object *find_object(const tl_diff_result *r, const char *name)
{
    for (size_t i = 0; i < r->object_count; i++)
        if (!strcmp(r->objects[i].name, name)) return &r->objects[i];
    fail_msg("object %s not in the diff", name);
    return NULL;
}

static void test_self_is_equal(void **state)
{
    (void)state;
    tl_diff_result r;
    run_diff(NULL, NULL, 0, 0, 0, &r);
    assert_int_equal(r.differ, 0);
    assert_int_equal(r.object_count, 4);
    for (size_t i = 0; i < r.object_count; i++) assert_int_equal(r.objects[i].status, TL_DIFF_SAME);
    const tl_diff_object *floor_ = find_object(&r, "floor");
    assert_int_equal(floor_->compared, 1);
    assert_int_equal(floor_->lighting.count, 32 * 32);
    assert_true(floor_->lighting.max_abs == 0.0);
    assert_true(tl_err_rel_rmse(&floor_->lighting) == 0.0);
    assert_int_equal(r.page_count, 2);
    assert_int_equal(r.pages[0].lighting.count, 64 * 32);
    assert_int_equal(r.glg.status, TL_DIFF_SAME);
    assert_int_equal(r.glg.lighting.count, 8);
    assert_int_equal(r.set_count, 1);
    assert_int_equal(r.sets[0].status, TL_DIFF_SAME);
    assert_int_equal(r.sets[0].lighting[LBK_DLS_SPACE_TEXEL].count, 256);
    assert_int_equal(r.sets[0].lighting[LBK_DLS_SPACE_GLG].count, 2);
    assert_int_equal(r.param_count, 0);
    for (size_t i = 0; i < r.section_count; i++) assert_int_equal(r.sections[i].status, TL_DIFF_SAME);
    tl_diff_free(&r);
}

/* The same physical lighting stored with other scales (LMAP and GLG 2^-6 and 2^5, DLS payloads in
 * them): the diff compares physical values, so the bakes are equal, exactly — dividing by a power
 * of two before encoding changes no rounding. The section bytes do differ. */
static void test_other_scale_is_equal(void **state)
{
    (void)state;
    static const int scales[2] = {-6, 5};
    for (int i = 0; i < 2; i++) {
        tf_options o;
        memset(&o, 0, sizeof o);
        o.scale_log2 = scales[i];
        tl_diff_result r;
        run_diff(NULL, &o, 0, 0, 0, &r);
        assert_int_equal(r.differ, 0);
        for (size_t k = 0; k < r.object_count; k++) assert_int_equal(r.objects[k].status, TL_DIFF_SAME);
        const tl_diff_object *floor_ = find_object(&r, "floor");
        assert_int_equal(floor_->lighting.count, 32 * 32);
        assert_true(floor_->lighting.max_abs == 0.0);
        assert_true(r.pages[0].lighting.max_abs == 0.0 && r.pages[1].lighting.max_abs == 0.0);
        assert_int_equal(r.glg.status, TL_DIFF_SAME);
        assert_true(r.glg.lighting.max_abs == 0.0);
        assert_int_equal(r.sets[0].status, TL_DIFF_SAME);
        assert_int_equal(r.sets[0].lighting[LBK_DLS_SPACE_TEXEL].count, 256);
        assert_true(r.sets[0].lighting[LBK_DLS_SPACE_TEXEL].max_abs == 0.0);
        assert_true(r.sets[0].lighting[LBK_DLS_SPACE_GLG].max_abs == 0.0);
        int lmap_bytes_differ = 0;
        for (size_t k = 0; k < r.section_count; k++)
            if (r.sections[k].type == LBK_SECTION_LMAP) lmap_bytes_differ = r.sections[k].status == TL_DIFF_CHANGED;
        assert_true(lmap_bytes_differ);
        tl_diff_free(&r);
        /* and a real change under the other scale is still seen */
        o.texel_factor = 2.0f, o.texel_page = 1, o.texel_x = 3, o.texel_y = 4;
        run_diff(NULL, &o, 0, 0, 0, &r);
        assert_int_equal(r.differ, 1);
        assert_int_equal(find_object(&r, "crate")->status, TL_DIFF_CHANGED);
        tl_diff_free(&r);
    }
}

/* One texel of the crate (page 1, rect at 0,0) doubled: exactly that object, that page, that
 * texel region; nothing else. */
static void test_one_texel_changed(void **state)
{
    (void)state;
    tf_options ob = {0};
    ob.texel_factor = 2.0f;
    ob.texel_page = 1, ob.texel_x = 5, ob.texel_y = 7;
    tl_diff_result r;
    run_diff(NULL, &ob, 0, 0, 0, &r);
    assert_int_equal(r.differ, 1);
    assert_int_equal(r.objects_changed, 1);
    assert_int_equal(r.objects_added + r.objects_removed, 0);
    const tl_diff_object *crate = find_object(&r, "crate");
    assert_int_equal(crate->status, TL_DIFF_CHANGED);
    assert_int_equal(crate->lighting.over, 1);
    assert_int_equal(crate->lighting.count, 256);
    assert_true(crate->lighting.has_region);
    assert_int_equal(crate->lighting.x0, 5);
    assert_int_equal(crate->lighting.x1, 5);
    assert_int_equal(crate->lighting.y0, 7);
    assert_int_equal(crate->lighting.y1, 7);
    assert_int_equal(crate->lighting.max_x, 5);
    assert_int_equal(crate->lighting.max_y, 7);
    assert_int_equal(find_object(&r, "floor")->status, TL_DIFF_SAME);
    assert_int_equal(find_object(&r, "wall")->status, TL_DIFF_SAME);
    assert_int_equal(r.pages[0].status, TL_DIFF_SAME);
    assert_int_equal(r.pages[1].status, TL_DIFF_CHANGED);
    assert_int_equal(r.pages[1].lighting.over, 1);
    assert_int_equal(r.pages[1].lighting.x0, 5);
    assert_int_equal(r.pages[1].lighting.y0, 7);
    assert_int_equal(r.texels_over, 1);
    assert_int_equal(r.probes_over, 0);
    /* mean = max / count since a single texel differs */
    assert_true(fabs(tl_err_mean(&crate->lighting) - crate->lighting.max_abs / 256.0) < 1e-12);
    tl_diff_free(&r);
}

/* The largest decoded difference of the changed texel, computed the way spec/diff-json.md says. */
static double expected_texel_error(const tf_options *ob, double *ref)
{
    tf_blob a = tf_build_scene(TF_SCENE_FULL, NULL), b = tf_build_scene(TF_SCENE_FULL, ob);
    tl_bake ba, bb;
    open_blob(&a, &ba);
    open_blob(&b, &bb);
    lbk_lmap_page pa, pb;
    assert_int_equal(lbk_lmap_page_get(&ba.lmap, ob->texel_page, &pa), LBK_OK);
    assert_int_equal(lbk_lmap_page_get(&bb.lmap, ob->texel_page, &pb), LBK_OK);
    lbk_ahd_texel ta, tb;
    lbk_lmap_page_texel_get(&pa, ob->texel_x, ob->texel_y, &ta);
    lbk_lmap_page_texel_get(&pb, ob->texel_x, ob->texel_y, &tb);
    float va[TL_TEXEL_NORMALS][3], vb[TL_TEXEL_NORMALS][3];
    tl_texel_eval(&ta, pa.scale, va);
    tl_texel_eval(&tb, pb.scale, vb);
    double e = 0;
    *ref = 0;
    for (int n = 0; n < TL_TEXEL_NORMALS; n++)
        for (int c = 0; c < 3; c++) {
            e = fmax(e, fabs((double)vb[n][c] - (double)va[n][c]));
            *ref = fmax(*ref, fabs((double)va[n][c]));
        }
    tl_bake_close(&ba);
    tl_bake_close(&bb);
    tf_blob_free(&a);
    tf_blob_free(&b);
    return e;
}

/* error == abs-tol is within tolerance; one ulp less is over. Same for rel-tol. */
static void test_tolerance_boundaries(void **state)
{
    (void)state;
    tf_options ob = {0};
    ob.texel_delta = 0.25f;
    ob.texel_page = 0, ob.texel_x = 10, ob.texel_y = 3;
    double ref;
    const double e = expected_texel_error(&ob, &ref);
    assert_true(e > 0.1 && e < 1.0);
    tl_diff_result r;
    run_diff(NULL, &ob, e, 0, 0, &r);
    assert_int_equal(r.texels_over, 0);
    assert_int_equal(r.differ, 0);
    assert_true(find_object(&r, "floor")->lighting.max_abs == e);
    tl_diff_free(&r);
    run_diff(NULL, &ob, nextafter(e, 0), 0, 0, &r);
    assert_int_equal(r.texels_over, 1);
    assert_int_equal(r.differ, 1);
    assert_int_equal(find_object(&r, "floor")->lighting.over, 1);
    tl_diff_free(&r);
    /* relative: error ≤ rel × max|A| */
    run_diff(NULL, &ob, 0, e / ref * (1 + 1e-12), 0, &r);
    assert_int_equal(r.texels_over, 0);
    tl_diff_free(&r);
    run_diff(NULL, &ob, 0, e / ref * (1 - 1e-9), 0, &r);
    assert_int_equal(r.texels_over, 1);
    tl_diff_free(&r);
}

static void test_objects_matched_by_name_and_hash(void **state)
{
    (void)state;
    tf_options ob = {0};
    ob.drop_crate = 1;
    ob.rename_wall = 1;
    ob.samples = 128;
    tl_diff_result r;
    run_diff(NULL, &ob, 0, 0, 0, &r);
    assert_int_equal(r.objects_removed, 1);
    assert_int_equal(find_object(&r, "crate")->status, TL_DIFF_REMOVED);
    const tl_diff_object *wall = find_object(&r, "wall");
    assert_int_equal(wall->status, TL_DIFF_CHANGED);
    assert_int_equal(wall->renamed, 1);
    assert_string_equal(wall->name_b, "wall-renamed");
    assert_int_equal(wall->lighting.over, 0); /* same texels: only the name changed */
    assert_int_equal(r.param_count, 1);
    assert_string_equal(r.params[0].key, "bake.samples");
    assert_string_equal(r.params[0].a, "64");
    assert_string_equal(r.params[0].b, "128");
    assert_int_equal(r.params[0].status, TL_DIFF_CHANGED);
    tl_diff_free(&r);

    memset(&ob, 0, sizeof ob);
    ob.move_crate_geometry = 1;
    run_diff(NULL, &ob, 0, 0, 0, &r);
    const tl_diff_object *crate = find_object(&r, "crate");
    assert_int_equal(crate->status, TL_DIFF_CHANGED);
    assert_int_equal(crate->geometry_changed, 1);
    assert_int_equal(crate->renamed, 0);
    tl_diff_free(&r);

    /* only META differs: reported, but the lighting is equal → exit 0 */
    memset(&ob, 0, sizeof ob);
    ob.samples = 65;
    run_diff(NULL, &ob, 0, 0, 0, &r);
    assert_int_equal(r.params_changed, 1);
    assert_int_equal(r.differ, 0);
    tl_diff_free(&r);
}

static void test_probe_change(void **state)
{
    (void)state;
    tf_options ob = {0};
    ob.probe_scale = 1.5f;
    tl_diff_result r;
    run_diff(NULL, &ob, 0, 0, 0, &r);
    assert_int_equal(r.glg.status, TL_DIFF_CHANGED);
    assert_int_equal(r.glg.lighting.over, 1);
    assert_int_equal(r.glg.lighting.x0, 3);
    assert_int_equal(r.glg.lighting.x1, 3);
    assert_int_equal(r.probes_over, 1);
    assert_int_equal(r.objects_changed, 0);
    assert_int_equal(r.differ, 1);
    /* rel-RMSE of a 1.5× probe among 8: sqrt(Σ(0.5 A3)² / Σ A²) is strictly between 0 and 0.5 */
    double rr = tl_err_rel_rmse(&r.glg.lighting);
    assert_true(rr > 0.05 && rr < 0.5);
    tl_diff_free(&r);
}

/* A pc pack widens pages (row pitch) and drops META/REPT: the lighting is the same. A
 * console-current pack block-compresses the lightmaps (BC6H + BC5/BC4): diff reads it, matches
 * every object and finds only the encoding's small error. */
static void test_pack_equals_source(void **state)
{
    (void)state;
    tf_blob a = tf_build_scene(TF_SCENE_FULL, NULL);
    char err[TL_ERR_LEN];
    tl_bake ba, bb;
    open_blob(&a, &ba);
    for (int k = 0; k < 2; k++) {
        tl_profile p;
        assert_int_equal(tl_profile_resolve(k ? "console-current" : "pc", "tools/convert/profiles", &p, err), 0);
        tl_convert_options co = {.profile = &p};
        void *pack;
        size_t pack_size;
        assert_int_equal(tl_convert_memory(a.data, a.size, &co, &pack, &pack_size, NULL, err), TL_CONVERT_OK);
        assert_int_equal(tl_bake_open_memory(pack, pack_size, &bb, err), TL_OPEN_OK);
        tl_diff_options o = {0};
        tl_diff_result r;
        assert_int_equal(tl_diff_run(&ba, &bb, &o, &r, err), 0);
        if (!k) {
            assert_int_equal(r.pages[1].resized, 1); /* 16 → 64 texels wide */
            assert_int_equal(r.objects_changed, 0);
            assert_int_equal(r.sets[0].status, TL_DIFF_SAME);
            assert_int_equal(r.sets[0].lighting[LBK_DLS_SPACE_TEXEL].count, 256);
            assert_int_equal(r.differ, 0);
        } else {
            /* block pages: padded to whole blocks only; every lightmapped object compared */
            size_t compared = 0;
            for (size_t i = 0; i < r.object_count; i++) {
                const tl_diff_object *ob = &r.objects[i];
                assert_int_equal(ob->geometry_changed, 0);
                if (!ob->compared || ob->repr_a != LBK_REPRESENTATION_LIGHTMAP) continue;
                compared++;
                const double rr = tl_err_rel_rmse(&ob->lighting);
                if (!(rr < 0.1)) fail_msg("object %s: relative RMSE %g after BC6H + BC5/BC4", ob->name, rr);
            }
            assert_true(compared > 0);
        }
        tl_diff_free(&r);
        tl_bake_close(&bb);
        free(pack);
    }
    tl_bake_close(&ba);
    tf_blob_free(&a);
}

static void require_key(const cJSON *o, const char *key)
{
    if (!cJSON_HasObjectItem(o, key)) fail_msg("JSON key '%s' missing", key);
}

static void test_json_schema(void **state)
{
    (void)state;
    tf_options ob = {0};
    ob.texel_factor = 3.0f;
    ob.texel_page = 1, ob.texel_x = 2, ob.texel_y = 4;
    tl_diff_result r;
    run_diff(NULL, &ob, 0.001, 0, 0, &r);
    char *text = tl_diff_json(&r, "a.lbk", "b.lbk");
    tl_diff_free(&r);
    cJSON *j = cJSON_Parse(text);
    assert_non_null(j);
    free(text);
    assert_string_equal(cJSON_GetObjectItem(j, "schema")->valuestring, "lbk-diff");
    assert_int_equal(cJSON_GetObjectItem(j, "schema_version")->valueint, 3);
    const char *top[] = {"a", "b", "tolerance", "equal", "mode", "mode_reason", "noise_model", "inputs", "summary",
                         "sections", "params", "objects", "pages", "glg", "octp", "light_sets", "doors"};
    for (size_t i = 0; i < sizeof top / sizeof top[0]; i++) require_key(j, top[i]);
    assert_true(cJSON_IsFalse(cJSON_GetObjectItem(j, "equal")));
    assert_string_equal(cJSON_GetObjectItem(j, "mode")->valuestring, "tolerance");
    assert_true(cJSON_IsNull(cJSON_GetObjectItem(j, "noise_model")));
    const char *sum[] = {"objects_added", "objects_removed", "objects_changed", "pages_changed", "light_sets_changed",
                         "doors_changed", "sections_changed", "params_changed", "texels_over_tolerance",
                         "probes_over_tolerance", "beyond_noise", "inputs_changed"};
    for (size_t i = 0; i < sizeof sum / sizeof sum[0]; i++) require_key(cJSON_GetObjectItem(j, "summary"), sum[i]);
    const cJSON *objs = cJSON_GetObjectItem(j, "objects");
    assert_int_equal(cJSON_GetArraySize(objs), 4);
    const cJSON *o;
    int found = 0;
    cJSON_ArrayForEach(o, objs)
    {
        const char *keys[] = {"name", "b_name", "status", "changes", "inputs_changed", "a", "b", "resampled", "lighting",
                              "noise"};
        for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) require_key(o, keys[i]);
        if (strcmp(cJSON_GetObjectItem(o, "name")->valuestring, "crate")) continue;
        found = 1;
        assert_string_equal(cJSON_GetObjectItem(o, "status")->valuestring, "changed");
        const cJSON *l = cJSON_GetObjectItem(o, "lighting");
        const char *lk[] = {"count", "over_tolerance", "over_share", "max_abs", "mean_abs", "rel_rmse", "max_at",
                            "over_region"};
        for (size_t i = 0; i < sizeof lk / sizeof lk[0]; i++) require_key(l, lk[i]);
        assert_int_equal(cJSON_GetObjectItem(l, "over_tolerance")->valueint, 1);
        const cJSON *reg = cJSON_GetObjectItem(l, "over_region");
        assert_int_equal(cJSON_GetObjectItem(reg, "x0")->valueint, 2);
        assert_int_equal(cJSON_GetObjectItem(reg, "y1")->valueint, 4);
        const cJSON *side = cJSON_GetObjectItem(o, "a");
        assert_string_equal(cJSON_GetObjectItem(side, "geometry_hash")->valuestring, "0000000000003333");
        assert_string_equal(cJSON_GetObjectItem(side, "representation")->valuestring, "lightmap");
        assert_int_equal(cJSON_GetObjectItem(cJSON_GetObjectItem(side, "rect"), "page")->valueint, 1);
    }
    assert_true(found);
    require_key(cJSON_GetObjectItem(j, "glg"), "lighting");
    const cJSON *set = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "light_sets"), 0);
    assert_string_equal(cJSON_GetObjectItem(set, "name")->valuestring, "lamp");
    require_key(set, "texels");
    require_key(set, "glg");
    require_key(set, "llg");
    cJSON_Delete(j);
}

static void test_heatmap_png(void **state)
{
    (void)state;
    tf_options ob = {0};
    ob.texel_factor = 2.0f;
    ob.texel_page = 0, ob.texel_x = 9, ob.texel_y = 11;
    tl_diff_result r;
    run_diff(NULL, &ob, 0, 0, 1, &r);
    char err[TL_ERR_LEN], dir[128], path[192];
    snprintf(dir, sizeof dir, "%s/heat", tmpdir);
    assert_int_equal(tl_diff_heatmaps(&r, dir, err), 0);
    tl_diff_free(&r);
    snprintf(path, sizeof path, "%s/page_000.diff.png", dir);
    int w, h;
    uint8_t *rgb;
    assert_int_equal(tl_png_read_rgb8(path, &w, &h, &rgb, err), 0);
    assert_int_equal(w, 64);
    assert_int_equal(h, 32);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const uint8_t *c = rgb + 3 * (y * w + x);
            int black = c[0] == 0 && c[1] == 0 && c[2] == 0;
            if (x == 9 && y == 11) assert_false(black);
            else assert_true(black);
        }
    free(rgb);
    snprintf(path, sizeof path, "%s/page_001.diff.png", dir);
    assert_int_equal(access(path, R_OK), 0);
}

/* ---- OCTP ------------------------------------------------------------------------------------ */

static tf_options octp_options(uint32_t dims)
{
    tf_options o;
    memset(&o, 0, sizeof o);
    o.octp_dims = dims;
    return o;
}

static int print_issue(void *user, const lbk_issue *issue)
{
    (void)user;
    fprintf(stderr, "fixture issue: %s\n", issue->message);
    return 0;
}

/* Decoded probes of a fixture's OCTP, for the direct computation the diff is checked against; the
 * fixture must be a valid container (depth moments m2 ≥ m1², states, offsets). */
static void octp_decode(const tf_options *o, lbk_octp_probe_desc *out, uint32_t n)
{
    tf_blob b = tf_build_scene(TF_SCENE_FULL, o);
    lbk_validate_summary vs;
    assert_int_equal(lbk_validate_memory(b.data, b.size, NULL, print_issue, NULL, &vs), LBK_OK);
    assert_int_equal(vs.fatal + vs.errors, 0);
    tl_bake bk;
    open_blob(&b, &bk);
    assert_true(bk.has_octp);
    assert_int_equal(bk.octp.probe_count, n);
    for (uint32_t i = 0; i < n; i++) assert_int_equal(lbk_octp_probe_get(&bk.octp, i, &out[i]), LBK_OK);
    tl_bake_close(&bk);
    tf_blob_free(&b);
}

static char *diff_text(const tl_diff_result *r)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    tl_diff_print(f, r, 1);
    fclose(f);
    return buf;
}

static void test_octp_self_is_equal(void **state)
{
    (void)state;
    tf_options o = octp_options(3);
    tl_diff_result r;
    run_diff(&o, &o, 0, 0, 0, &r);
    assert_int_equal(r.differ, 0);
    assert_int_equal(r.octp.status, TL_DIFF_SAME);
    assert_int_equal(r.octp.comparable, 1);
    assert_int_equal(r.octp.count_a, 12);
    assert_int_equal(r.octp.levels_a, 1);
    assert_int_equal(r.octp.lighting.count, 12);
    assert_int_equal(r.octp.depth.count, 12);
    assert_true(r.octp.lighting.max_abs == 0.0 && tl_err_rel_rmse(&r.octp.lighting) == 0.0);
    assert_true(r.octp.depth.max_abs == 0.0);
    assert_int_equal(r.octp.state_changes, 0);
    assert_int_equal(r.octp.moved, 0);
    assert_int_equal(r.octp.states_a[LBK_OCTP_ACTIVE], 12);
    tl_diff_free(&r);
    /* a bake without OCTP on either side: absent, and not in the text */
    run_diff(NULL, NULL, 0, 0, 0, &r);
    assert_int_equal(r.octp.status, -1);
    char *text = diff_text(&r);
    assert_null(strstr(text, "octp"));
    free(text);
    tl_diff_free(&r);
}

/* Probe 5's irradiance doubled: the diff's numbers are the direct computation over A's decoded
 * texels (B = 2A exactly, a power of two): max |B − A| = max A of probe 5, rel-RMSE =
 * √(Σ_probe5 A² / Σ_all A²). */
static void test_octp_irradiance_change(void **state)
{
    (void)state;
    tf_options oa = octp_options(3), ob = octp_options(3);
    ob.octp_factor = 2.0f, ob.octp_probe = 5;
    lbk_octp_probe_desc pa[12];
    octp_decode(&oa, pa, 12);
    double max5 = 0, sq5 = 0, sq = 0;
    for (uint32_t p = 0; p < 12; p++)
        for (int t = 0; t < 16; t++)
            for (int c = 0; c < 3; c++) {
                const double v = pa[p].irradiance[t][c];
                sq += v * v;
                if (p != 5) continue;
                sq5 += v * v;
                if (v > max5) max5 = v;
            }
    tl_diff_result r;
    run_diff(&oa, &ob, 0, 0, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_CHANGED);
    assert_int_equal(r.differ, 1);
    assert_int_equal(r.octp.lighting.count, 12);
    assert_int_equal(r.octp.lighting.over, 1);
    assert_int_equal(r.octp.lighting.max_x, 5);
    assert_int_equal(r.octp.lighting.x0, 5);
    assert_int_equal(r.octp.lighting.x1, 5);
    assert_true(r.octp.lighting.max_abs == max5);
    assert_float_equal(tl_err_rel_rmse(&r.octp.lighting), sqrt(sq5 / sq), 1e-12);
    assert_true(max5 > 1.0 && sqrt(sq5 / sq) > 0.2 && sqrt(sq5 / sq) < 0.5); /* the fixture's values: not trivial */
    assert_int_equal(r.probes_over, 1); /* GLG unchanged */
    assert_true(r.octp.depth.max_abs == 0.0);
    assert_int_equal(r.octp.state_changes, 0);
    tl_diff_free(&r);
    /* a tolerance of 1 × A accepts a doubling; 0.99 × A does not */
    run_diff(&oa, &ob, 0, 1.0, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_SAME);
    assert_int_equal(r.differ, 0);
    tl_diff_free(&r);
    run_diff(&oa, &ob, 0, 0.99, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_CHANGED);
    tl_diff_free(&r);
}

/* Probe 2's depth mean + 0.5 m (exact in half: means in [1, 1.25)), mean² its square: the diff's
 * depth statistics are the direct computation over the decoded moments; irradiance 0. */
static void test_octp_depth_change(void **state)
{
    (void)state;
    tf_options oa = octp_options(3), ob = octp_options(3);
    ob.octp_depth_delta = 0.5f, ob.octp_probe = 2;
    lbk_octp_probe_desc pa[12], pb[12];
    octp_decode(&oa, pa, 12);
    octp_decode(&ob, pb, 12);
    double max = 0, sqd = 0, sqr = 0;
    for (uint32_t p = 0; p < 12; p++)
        for (int t = 0; t < 144; t++)
            for (int m = 0; m < 2; m++) {
                const double d = (double)pb[p].depth[t][m] - pa[p].depth[t][m];
                max = fmax(max, fabs(d));
                sqd += d * d;
                sqr += (double)pa[p].depth[t][m] * pa[p].depth[t][m];
            }
    assert_true(max > 0.5 && max < 2.0); /* mean + 0.5 exactly, mean² by (m + 0.5)² − m² = m + 0.25 */
    tl_diff_result r;
    run_diff(&oa, &ob, 0, 0, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_CHANGED);
    assert_true(r.octp.lighting.max_abs == 0.0);
    assert_true(r.octp.depth.max_abs == max);
    assert_int_equal(r.octp.depth.max_x, 2);
    assert_int_equal(r.octp.depth.over, 1);
    assert_float_equal(tl_err_rel_rmse(&r.octp.depth), sqrt(sqd / sqr), 1e-12);
    char *text = diff_text(&r);
    assert_non_null(strstr(text, "octp changed 12 -> 12 probes, 1 -> 1 levels"));
    assert_non_null(strstr(text, "depth moments: max "));
    assert_non_null(strstr(text, "over 1/12"));
    free(text);
    tl_diff_free(&r);
}

/* Probe 3 marked inside geometry in B: one state change, counts 12/0 -> 11/1, and the probe's
 * texels are not compared (a sampler skips it). */
static void test_octp_state_change(void **state)
{
    (void)state;
    tf_options oa = octp_options(3), ob = octp_options(3);
    ob.octp_inside = 4;
    tl_diff_result r;
    run_diff(&oa, &ob, 0, 0, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_CHANGED);
    assert_int_equal(r.differ, 1);
    assert_int_equal(r.octp.state_changes, 1);
    assert_int_equal(r.octp.states_a[LBK_OCTP_ACTIVE], 12);
    assert_int_equal(r.octp.states_a[LBK_OCTP_INSIDE], 0);
    assert_int_equal(r.octp.states_b[LBK_OCTP_ACTIVE], 11);
    assert_int_equal(r.octp.states_b[LBK_OCTP_INSIDE], 1);
    assert_int_equal(r.octp.lighting.count, 11);
    assert_true(r.octp.lighting.max_abs == 0.0);
    char *json = tl_diff_json(&r, "a", "b");
    cJSON *j = cJSON_Parse(json);
    free(json);
    const cJSON *oc = cJSON_GetObjectItem(j, "octp");
    assert_non_null(oc);
    assert_string_equal(cJSON_GetObjectItem(oc, "status")->valuestring, "changed");
    assert_true(cJSON_IsTrue(cJSON_GetObjectItem(oc, "comparable")));
    assert_int_equal(cJSON_GetObjectItem(oc, "state_changes")->valueint, 1);
    assert_int_equal(cJSON_GetObjectItem(cJSON_GetObjectItem(oc, "states_b"), "inside")->valueint, 1);
    assert_int_equal(cJSON_GetObjectItem(cJSON_GetObjectItem(oc, "lighting"), "count")->valueint, 11);
    assert_true(cJSON_GetObjectItem(cJSON_GetObjectItem(oc, "depth"), "max_abs")->valuedouble == 0.0);
    cJSON_Delete(j);
    tl_diff_free(&r);
}

/* Other grid dims: not comparable, said so; OCTP on one side only: removed / added. */
static void test_octp_layout_and_presence(void **state)
{
    (void)state;
    tf_options oa = octp_options(3), ob = octp_options(4);
    tl_diff_result r;
    run_diff(&oa, &ob, 0, 0, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_CHANGED);
    assert_int_equal(r.octp.comparable, 0);
    assert_int_equal(r.octp.count_b, 16);
    assert_int_equal(r.octp.lighting.count, 0);
    assert_int_equal(r.differ, 1);
    char *text = diff_text(&r);
    assert_non_null(strstr(text, "octp changed 12 -> 16 probes"));
    assert_non_null(strstr(text, "not comparable (volume layout changed"));
    free(text);
    char *json = tl_diff_json(&r, "a", "b");
    cJSON *j = cJSON_Parse(json);
    free(json);
    const cJSON *oc = cJSON_GetObjectItem(j, "octp");
    assert_true(cJSON_IsFalse(cJSON_GetObjectItem(oc, "comparable")));
    assert_true(cJSON_IsNull(cJSON_GetObjectItem(oc, "lighting")));
    cJSON_Delete(j);
    tl_diff_free(&r);

    run_diff(&oa, NULL, 0, 0, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_REMOVED);
    assert_int_equal(r.differ, 1);
    text = diff_text(&r);
    assert_non_null(strstr(text, "octp removed 12 -> 0 probes, 1 -> 0 levels (only in A)"));
    free(text);
    tl_diff_free(&r);
    run_diff(NULL, &oa, 0, 0, 0, &r);
    assert_int_equal(r.octp.status, TL_DIFF_ADDED);
    assert_int_equal(r.differ, 1);
    tl_diff_free(&r);
}

/* Noise mode (both fixtures carry REPT): identical volumes are within noise; one probe at 100×
 * is beyond it. */
static void test_octp_noise_mode(void **state)
{
    (void)state;
    tf_options oa = octp_options(3), ob = octp_options(3);
    ob.octp_factor = 100.0f, ob.octp_probe = 7;
    tl_diff_result r;
    for (int k = 0; k < 2; k++) {
        tf_blob a = tf_build_scene(TF_SCENE_FULL, &oa), b = tf_build_scene(TF_SCENE_FULL, k ? &ob : &oa);
        tl_bake ba, bb;
        open_blob(&a, &ba);
        open_blob(&b, &bb);
        tl_diff_options o = {.mode = TL_DIFF_MODE_NOISE};
        char err[TL_ERR_LEN];
        assert_int_equal(tl_diff_run(&ba, &bb, &o, &r, err), 0);
        assert_int_equal(r.mode, TL_DIFF_MODE_NOISE);
        assert_int_equal(r.octp.noise.evaluated, 1);
        assert_int_equal(r.octp.noise.count, 12);
        assert_int_equal(r.octp.noise.within_noise, !k);
        assert_int_equal(r.octp.status, k ? TL_DIFF_CHANGED : TL_DIFF_SAME);
        assert_int_equal(r.items_beyond_noise, (uint32_t)k);
        tl_diff_free(&r);
        tl_bake_close(&ba);
        tl_bake_close(&bb);
        tf_blob_free(&a);
        tf_blob_free(&b);
    }
}

/* Real bakes: cornell_box with --octahedral at seeds 1 and 2 (16 samples). The volumes have the
 * same layout; the diff's irradiance and depth statistics are the direct computation over the
 * decoded probes active on both sides, and the state counts are the files'. A bake against
 * itself is zero. */
static void octp_bake(const char *gltf, uint64_t seed, const char *out, tl_bake *b)
{
    tb_job job = {gltf, out, NULL, {0}};
    job.d.seed = seed;
    job.d.max_samples = 16;
    job.d.octahedral_probes = 1;
    char err[1024];
    assert_int_equal(tb_bake(&job, NULL, err, sizeof err), LBK_OK);
    if (tl_bake_open_file(out, b, err) != TL_OPEN_OK) fail_msg("%s", err);
}

static void test_octp_real_bakes(void **state)
{
    (void)state;
    char gltf[1024], pa[128], pb[128];
    SD_REQUIRE(sd_path(gltf, sizeof gltf, "cornell_box/CornellBox-Original.gltf"));
    snprintf(pa, sizeof pa, "%s/octp1.lbk", tmpdir);
    snprintf(pb, sizeof pb, "%s/octp2.lbk", tmpdir);
    tl_bake a, b;
    octp_bake(gltf, 1, pa, &a);
    octp_bake(gltf, 2, pb, &b);
    assert_true(a.has_octp && b.has_octp);
    const uint32_t n = a.octp.probe_count;
    double sqd = 0, sqr = 0, max = 0, dmax = 0;
    uint64_t compared = 0;
    uint32_t changes = 0, inside_b = 0;
    for (uint32_t i = 0; i < n; i++) {
        lbk_octp_probe_info ia, ib;
        assert_int_equal(lbk_octp_probe_info_get(&a.octp, i, &ia), LBK_OK);
        assert_int_equal(lbk_octp_probe_info_get(&b.octp, i, &ib), LBK_OK);
        changes += ia.state != ib.state;
        inside_b += ib.state == LBK_OCTP_INSIDE;
        if (ia.state == LBK_OCTP_INSIDE || ib.state == LBK_OCTP_INSIDE) continue;
        lbk_octp_probe_desc da, db;
        assert_int_equal(lbk_octp_probe_get(&a.octp, i, &da), LBK_OK);
        assert_int_equal(lbk_octp_probe_get(&b.octp, i, &db), LBK_OK);
        compared++;
        for (int t = 0; t < 16; t++)
            for (int c = 0; c < 3; c++) {
                const double d = (double)db.irradiance[t][c] - da.irradiance[t][c];
                sqd += d * d;
                sqr += (double)da.irradiance[t][c] * da.irradiance[t][c];
                max = fmax(max, fabs(d));
            }
        for (int t = 0; t < 144; t++)
            for (int m = 0; m < 2; m++) dmax = fmax(dmax, fabs((double)db.depth[t][m] - da.depth[t][m]));
    }
    tl_diff_options o = {.mode = TL_DIFF_MODE_TOLERANCE};
    tl_diff_result r;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_diff_run(&a, &b, &o, &r, err), 0);
    assert_int_equal(r.octp.comparable, 1);
    assert_int_equal(r.octp.count_a, n);
    assert_int_equal(r.octp.lighting.count, compared);
    assert_true(compared > 0);
    assert_true(r.octp.lighting.max_abs == max);
    assert_true(max > 0); /* another seed: other noise */
    assert_float_equal(tl_err_rel_rmse(&r.octp.lighting), sqrt(sqd / sqr), 1e-9);
    assert_true(r.octp.depth.max_abs == dmax);
    assert_int_equal(r.octp.state_changes, changes);
    assert_int_equal(r.octp.states_b[LBK_OCTP_INSIDE], inside_b);
    printf("cornell_box seeds 1/2: %u probes, %llu compared, irradiance rel-RMSE %.4f max %.4g, depth max %.4g, "
           "%u state changes\n", n, (unsigned long long)compared, tl_err_rel_rmse(&r.octp.lighting), max, dmax, changes);
    tl_diff_free(&r);
    assert_int_equal(tl_diff_run(&a, &a, &o, &r, err), 0);
    assert_int_equal(r.octp.status, TL_DIFF_SAME);
    assert_true(r.octp.lighting.max_abs == 0.0 && r.octp.depth.max_abs == 0.0);
    assert_int_equal(r.differ, 0);
    tl_diff_free(&r);
    tl_bake_close(&a);
    tl_bake_close(&b);
}

static int run_cli(int n, const char **args)
{
    char *argv[16];
    for (int i = 0; i < n; i++) argv[i] = (char *)args[i];
    fflush(stdout);
    return lbk_cmd_diff(n, argv);
}

/* Documented exit codes: 0 equal, 1 differ, 2 usage, 3 I/O, 4 invalid input. */
static void test_cli_exit_codes(void **state)
{
    (void)state;
    char pa[128], pb[128], bad[128], missing[128], err[TL_ERR_LEN];
    snprintf(pa, sizeof pa, "%s/a.lbk", tmpdir);
    snprintf(pb, sizeof pb, "%s/b.lbk", tmpdir);
    snprintf(bad, sizeof bad, "%s/bad.lbk", tmpdir);
    snprintf(missing, sizeof missing, "%s/missing.lbk", tmpdir);
    tf_options ob = {0};
    ob.texel_factor = 2.0f;
    tf_blob a = tf_build_scene(TF_SCENE_FULL, NULL), b = tf_build_scene(TF_SCENE_FULL, &ob);
    assert_int_equal(tl_write_file_atomic(pa, a.data, a.size, err), 0);
    assert_int_equal(tl_write_file_atomic(pb, b.data, b.size, err), 0);
    ((uint8_t *)a.data)[a.size / 2] ^= 1;
    assert_int_equal(tl_write_file_atomic(bad, a.data, a.size, err), 0);
    tf_blob_free(&a);
    tf_blob_free(&b);
    const char *same[] = {"diff", pa, pa, "--json"};
    assert_int_equal(run_cli(4, same), LBK_EXIT_OK);
    /* exact: the one texel doubled differs (the default for these files is noise mode: both carry REPT) */
    const char *differ[] = {"diff", pa, pb, "--mode", "tolerance"};
    assert_int_equal(run_cli(5, differ), LBK_EXIT_NEGATIVE);
    const char *bad_mode[] = {"diff", pa, pb, "--mode", "fuzzy"};
    assert_int_equal(run_cli(5, bad_mode), LBK_EXIT_USAGE);
    const char *bad_alpha[] = {"diff", pa, pb, "--false-alarm", "0.7"};
    assert_int_equal(run_cli(5, bad_alpha), LBK_EXIT_USAGE);
    const char *loose[] = {"diff", pa, pb, "--rel-tol", "1.5"}; /* 2× texel: error = 1 × A ≤ 1.5 × A */
    assert_int_equal(run_cli(5, loose), LBK_EXIT_OK);
    const char *usage1[] = {"diff", pa};
    assert_int_equal(run_cli(2, usage1), LBK_EXIT_USAGE);
    const char *usage2[] = {"diff", pa, pb, "--abs-tol", "-1"};
    assert_int_equal(run_cli(5, usage2), LBK_EXIT_USAGE);
    const char *usage3[] = {"diff", pa, pb, "--frobnicate"};
    assert_int_equal(run_cli(4, usage3), LBK_EXIT_USAGE);
    const char *io[] = {"diff", pa, missing};
    assert_int_equal(run_cli(3, io), LBK_EXIT_IO);
    const char *inv[] = {"diff", bad, pa};
    assert_int_equal(run_cli(3, inv), LBK_EXIT_INPUT);
}

/* lbk diff --json's document, stdout captured into a file (malloc'ed text). */
static char *cli_json(int n, const char **args, int expect)
{
    char path[160], err[TL_ERR_LEN];
    snprintf(path, sizeof path, "%s/diff_out.json", tmpdir);
    fflush(stdout);
    const int saved = dup(1);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    dup2(fileno(f), 1);
    const int rc = run_cli(n, args);
    fflush(stdout);
    dup2(saved, 1);
    close(saved);
    fclose(f);
    assert_int_equal(rc, expect);
    void *text;
    size_t size;
    assert_int_equal(tl_read_file(path, &text, &size, err), 0);
    char *t = realloc(text, size + 1);
    assert_non_null(t);
    t[size] = 0;
    return t;
}

/* SOURCE against its block-compressed pack: lbk diff says the lightmap differences are the
 * encoding's error, with the numbers lbk convert reports (the same measure, pack_error.h); a bake
 * against itself has no such entry. */
static void test_cli_pack_reports_compression(void **state)
{
    (void)state;
    char pa[128], pp[128], err[TL_ERR_LEN];
    snprintf(pa, sizeof pa, "%s/src.lbk", tmpdir);
    snprintf(pp, sizeof pp, "%s/src.pack.lbk", tmpdir);
    tf_blob a = tf_build_scene(TF_SCENE_FULL, NULL);
    tl_profile p;
    assert_int_equal(tl_profile_resolve("console-current", "tools/convert/profiles", &p, err), 0);
    tl_pack_error pe;
    tl_convert_report rep;
    tl_convert_options co = {.profile = &p, .pack_error = &pe};
    void *pack;
    size_t pack_size;
    assert_int_equal(tl_convert_memory(a.data, a.size, &co, &pack, &pack_size, &rep, err), TL_CONVERT_OK);
    assert_int_equal(rep.pack_error_computed, 1);
    assert_int_equal(tl_write_file_atomic(pa, a.data, a.size, err), 0);
    assert_int_equal(tl_write_file_atomic(pp, pack, pack_size, err), 0);
    free(pack);
    tf_blob_free(&a);
    const char *args[] = {"diff", pa, pp, "--json", "--mode", "tolerance"};
    char *text = cli_json(6, args, LBK_EXIT_NEGATIVE); /* lossy: it differs, and says why */
    cJSON *j = cJSON_Parse(text);
    assert_non_null(j);
    const cJSON *c = cJSON_GetObjectItem(j, "compression");
    assert_true(cJSON_IsObject(c));
    assert_string_equal(cJSON_GetObjectItem(c, "pack")->valuestring, "b");
    assert_string_equal(cJSON_GetObjectItem(c, "plane0")->valuestring, "bc6h");
    assert_int_equal((uint64_t)cJSON_GetObjectItem(c, "texels")->valuedouble, pe.texels);
    const cJSON *lum = cJSON_GetObjectItem(c, "luminance");
    assert_true(pe.all.lum.mean > 0);
    assert_true(fabs(cJSON_GetObjectItem(lum, "mean")->valuedouble - pe.all.lum.mean) <= 1e-12 * pe.all.lum.mean);
    assert_true(fabs(cJSON_GetObjectItem(lum, "p99")->valuedouble - pe.all.lum.p99) <= 1e-12 * pe.all.lum.p99);
    cJSON_Delete(j);
    free(text);
    tl_pack_error_free(&pe);
    const char *self[] = {"diff", pa, pa, "--json"};
    text = cli_json(4, self, LBK_EXIT_OK);
    j = cJSON_Parse(text);
    assert_non_null(j);
    assert_true(cJSON_IsNull(cJSON_GetObjectItem(j, "compression")));
    cJSON_Delete(j);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cli_pack_reports_compression),
        cmocka_unit_test(test_self_is_equal),
        cmocka_unit_test(test_other_scale_is_equal),
        cmocka_unit_test(test_one_texel_changed),
        cmocka_unit_test(test_tolerance_boundaries),
        cmocka_unit_test(test_objects_matched_by_name_and_hash),
        cmocka_unit_test(test_probe_change),
        cmocka_unit_test(test_pack_equals_source),
        cmocka_unit_test(test_json_schema),
        cmocka_unit_test(test_heatmap_png),
        cmocka_unit_test(test_cli_exit_codes),
        cmocka_unit_test(test_octp_self_is_equal),
        cmocka_unit_test(test_octp_irradiance_change),
        cmocka_unit_test(test_octp_depth_change),
        cmocka_unit_test(test_octp_state_change),
        cmocka_unit_test(test_octp_layout_and_presence),
        cmocka_unit_test(test_octp_noise_mode),
        cmocka_unit_test(test_octp_real_bakes),
    };
    return cmocka_run_group_tests(tests, setup_dir, teardown_dir);
}
