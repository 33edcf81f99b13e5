/* Lightmap atlas quality on the shared scenes (printed, not asserted):
 *  - fill: covered texels (texel squares a chart triangle overlaps, bake/layout/atlas_stats.h)
 *    / page texels, and / object rectangles; goal ≥ 80 % of the page at the default padding 2;
 *  - charts, tiny charts (≤ 3 covered texels), charts turned by the packer;
 *  - seam score (bake/layout/seams.h): mean relative jump of the bilinearly filtered
 *    irradiance luminance between the two sides of every smooth seam, measured on a real
 *    bake (--preset fast --samples 16, room_with_doors with --sky 1,1,1), whose LMAP pages
 *    are read back from the container. The atlas is rebuilt here exactly as the baker builds
 *    it (import, classify, fast-preset density) and checked against the container's pages.
 * LBK_SCENES overrides scenes/. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bake/layout/atlas.h"
#include "bake/layout/atlas_stats.h"
#include "bake/layout/classify.h"
#include "bake/layout/seams.h"
#include "bake/layout/texels.h"
#include "lbk/bake.h"
#include "scene/import.h"
#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/pixel.h"

static const char *scenes_dir(void)
{
    const char *d = getenv("LBK_SCENES");
    return d && *d ? d : "scenes";
}

typedef struct scene_case {
    const char *label, *rel;
    int sky;
} scene_case;

static const scene_case cases[] = {
    {"cornell_box", "cornell_box/CornellBox-Original.gltf", 0},
    {"cornell_box_bjs", "cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf", 0},
    {"lights_punctual_lamp", "lights_punctual_lamp/LightsPunctualLamp.gltf", 0},
    {"room_with_doors", "room_with_doors/room.glb", 1},
    {"water_bottle_draco", "water_bottle_draco/WaterBottle.gltf", 0},
};

/* The atlas the baker builds for the scene (bake.c do_layout with the fast preset). */
static int build_atlas(const char *path, bk_scene *s, bk_atlas *a)
{
    bk_import_options io;
    memset(&io, 0, sizeof io);
    io.skip_textures = 1;
    char err[512];
    if (bk_import_gltf(path, &io, s, err, sizeof err)) {
        fprintf(stderr, "bench_atlas: %s\n", err);
        return -1;
    }
    bk_object_class *cls = calloc(s->object_count ? s->object_count : 1, sizeof *cls);
    uint8_t *lm = calloc(s->object_count ? s->object_count : 1, 1);
    int rc = -1;
    if (cls && lm && bk_classify_objects(s, NULL, cls) == LBK_OK) {
        for (size_t i = 0; i < s->object_count; i++) lm[i] = cls[i].rep == BK_REP_LIGHTMAP;
        bk_atlas_options ao;
        memset(&ao, 0, sizeof ao);
        ao.default_density = 8.0f;
        rc = bk_atlas_build(s, lm, &ao, a) == LBK_OK ? 0 : -1;
    }
    free(cls);
    free(lm);
    return rc;
}

/* Per page luminance of the stored irradiance along the normal; 0 unless the container's
 * pages match the atlas. */
static int load_lum(const char *path, const bk_atlas *a, float ***lum_out)
{
    lbk_reader *r;
    if (lbk_reader_open_file(path, NULL, &r)) return 0;
    const void *data;
    size_t size;
    lbk_lmap_view v;
    int ok = 0;
    float **lum = calloc(a->page_count ? a->page_count : 1, sizeof *lum);
    if (lum && lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &data, &size) == LBK_OK &&
        lbk_lmap_open(data, size, &v) == LBK_OK && v.page_count == a->page_count) {
        ok = 1;
        for (uint32_t p = 0; p < v.page_count && ok; p++) {
            lbk_lmap_page pg;
            ok = lbk_lmap_page_get(&v, p, &pg) == LBK_OK && (int)pg.width == a->pages[p].width &&
                 (int)pg.height == a->pages[p].height;
            if (!ok) break;
            lum[p] = malloc((size_t)pg.width * pg.height * sizeof **lum);
            ok = lum[p] != NULL;
            for (uint32_t y = 0; ok && y < pg.height; y++)
                for (uint32_t x = 0; x < pg.width; x++) {
                    lbk_ahd_texel t;
                    float rgb[3];
                    lbk_lmap_page_texel_get(&pg, x, y, &t);
                    lbk_r11g11b10f_unpack(t.irradiance_z, rgb);
                    lum[p][(size_t)y * pg.width + x] = LBK_LUM_R * rgb[0] + LBK_LUM_G * rgb[1] + LBK_LUM_B * rgb[2];
                }
        }
    }
    lbk_reader_close(r);
    *lum_out = lum;
    return ok;
}

/* Bakes the scene (stitched or not) into out; 1 on success. */
static int bake_scene(const scene_case *c, const char *in, const char *out, int no_stitch)
{
    lbk_bake_desc d = {.size = sizeof d, .seed = 1, .max_samples = 16, .no_seam_stitch = no_stitch};
    if (c->sky) {
        d.sky_override = 1;
        d.sky[0] = d.sky[1] = d.sky[2] = 1.0f;
    }
    lbk_bake_output *res = NULL;
    lbk_result r = lbk_bake_from_file(in, &d, &res);
    if (!r) r = lbk_bake_output_write_file(res, out);
    lbk_bake_output_free(res);
    if (r == LBK_OK) return 1;
    fprintf(stderr, "bench_atlas: %s: %s\n", in, lbk_result_message(r));
    return 0;
}

/* Seam score of a bake of the atlas a; 0 when it cannot be read back. */
static int score_bake(const char *path, const bk_atlas *a, const bk_seams *sm, bk_seam_score *sc)
{
    float **lum = NULL;
    int have = load_lum(path, a, &lum);
    if (have) bk_seams_score(sm, a->pages, a->page_count, (const float *const *)lum, sc);
    if (lum)
        for (size_t p = 0; p < a->page_count; p++) free(lum[p]);
    free(lum);
    return have;
}

static void run_case(const scene_case *c, const char *tmp)
{
    char in[512], raw[600], stitched[600];
    snprintf(in, sizeof in, "%s/%s", scenes_dir(), c->rel);
    if (access(in, R_OK) != 0) {
        printf("%-21s %s missing (set LBK_SCENES), skipped\n", c->label, in);
        return;
    }
    snprintf(raw, sizeof raw, "%s/%s.raw.lbk", tmp, c->label);
    snprintf(stitched, sizeof stitched, "%s/%s.lbk", tmp, c->label);
    int baked_raw = bake_scene(c, in, raw, 1), baked = bake_scene(c, in, stitched, 0);

    bk_scene s;
    bk_atlas a;
    memset(&s, 0, sizeof s);
    memset(&a, 0, sizeof a);
    if (build_atlas(in, &s, &a)) {
        bk_scene_free(&s);
        return;
    }
    bk_atlas_stats st;
    bk_texels tx;
    bk_seams sm;
    memset(&tx, 0, sizeof tx);
    memset(&sm, 0, sizeof sm);
    if (bk_atlas_stats_compute(&a, &st) || bk_texels_build(&s, &a, &tx) || bk_seams_find(&s, &a, &sm)) {
        fprintf(stderr, "bench_atlas: %s: statistics failed\n", c->label);
    } else {
        bk_seam_score sr, ss;
        memset(&sr, 0, sizeof sr);
        memset(&ss, 0, sizeof ss);
        int have_raw = baked_raw && score_bake(raw, &a, &sm, &sr), have = baked && score_bake(stitched, &a, &sm, &ss);
        printf("%-21s %5zu %8llu %8llu %8llu %8llu %8llu %6.1f%% %6.1f%% %6zu %5zu %5zu %6zu %5zu/%-5zu", c->label,
               a.page_count, (unsigned long long)st.page_texels, (unsigned long long)st.rect_texels,
               (unsigned long long)st.block_texels, (unsigned long long)st.covered_texels,
               (unsigned long long)tx.count, 100 * st.fill, 100 * st.fill_rects, st.charts, st.tiny_charts,
               st.rotated_charts, a.object_count, sm.smooth_count, sm.count);
        if (have_raw && have && sm.smooth_count)
            printf(" %7.2f%% %7.2f%% %7.1f%%\n", 100 * sr.mean, 100 * ss.mean, 100 * ss.max);
        else
            printf(" %8s %8s %8s\n", "-", "-", "-");
    }
    bk_seams_free(&sm);
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    bk_scene_free(&s);
    remove(raw);
    remove(stitched);
}

int main(void)
{
    char tmp[] = "/tmp/lbk-bench-atlas-XXXXXX";
    if (!mkdtemp(tmp)) {
        perror("mkdtemp");
        return 1;
    }
    printf("atlas fill and seams, fast preset (8 texels/m), padding 2; seam score on a --samples 16 bake\n");
    printf("%-21s %5s %8s %8s %8s %8s %8s %7s %7s %6s %5s %5s %6s %11s %8s %8s %8s\n", "scene", "pages", "texels",
           "rects", "blocks", "covered", "baked", "fill", "/rects", "charts", "tiny", "turned", "objs", "smooth/seams",
           "raw", "stitched", "max");
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) run_case(&cases[i], tmp);
    rmdir(tmp);
    return 0;
}
