/* Console packs: per shipped conversion profile and shared scene, the GPU bytes per lightmap texel,
 * the block-encoding time, and the error of the pack's lightmaps against the uncompressed bake,
 * as lbk convert reports it (tools/convert/pack_error.h: every texel the baker wrote inside an
 * object's rectangle at the five normals lbk diff uses; luminance |ΔY| / max(Y, 1 % of the scene
 * mean), chroma |Δ(r, g)|; seam texels: gutters and texels within 2 of another chart), printed
 * against the goal mean <= 1 %, p99 <= 5 % (ratios: value / goal, <= 1 meets it) and the GPU
 * bytes per texel the goal allows (2.5 BC6H + BC5/BC4, 2 ASTC).
 * Bakes: preset fast (to its 3 % target error), seed 1; the block profiles also on a bake with
 * --block-align (+align). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene/clock.h"
#include "lbk/bake.h"
#include "tools/common/bake_data.h"
#include "tools/convert/convert.h"
#include "tools/convert/pack_error.h"
#include "tools/convert/profile.h"

static const char *const scenes[][2] = {
    {"cornell_box", "cornell_box/CornellBox-Original.gltf"},
    {"cornell_box_bjs", "cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf"},
    {"room_with_doors", "room_with_doors/room.glb"},
    {"lights_punctual_lamp", "lights_punctual_lamp/LightsPunctualLamp.gltf"},
    {"water_bottle_draco", "water_bottle_draco/WaterBottle.gltf"},
};
static const char *const profiles[] = {"console-current", "console-previous", "pc", "handheld", "archive"};

/* Converts one bake with each profile and prints a row per profile. base_texels: the texels of the
 * plain bake (block-aligned bakes are charged for their extra texels). */
static void run_profiles(const char *scene, const void *bytes, size_t size, uint64_t base_texels,
                         const char *const *names, size_t count, const char *suffix)
{
    char err[TL_ERR_LEN] = "";
    tl_bake a;
    if (tl_bake_open_memory(bytes, size, &a, err) != TL_OPEN_OK || !a.has_lmap) {
        printf("%-22s no lightmap%s%s%s\n", scene, *err ? " (" : "", err, *err ? ")" : "");
        if (a.bytes) tl_bake_close(&a);
        return;
    }
    for (size_t k = 0; k < count; k++) {
        char label[64];
        snprintf(label, sizeof label, "%s%s", names[k], suffix);
        tl_profile pr;
        if (tl_profile_resolve(names[k], NULL, &pr, err)) {
            printf("%-22s %-17s %s\n", scene, label, err);
            continue;
        }
        tl_convert_options co = {.profile = &pr};
        tl_convert_report rep;
        void *pack;
        size_t pack_size;
        if (tl_convert_memory(bytes, size, &co, &pack, &pack_size, &rep, err) != TL_CONVERT_OK) {
            printf("%-22s %-17s convert failed: %s\n", scene, label, err);
            continue;
        }
        tl_bake p;
        if (tl_bake_open_memory(pack, pack_size, &p, err) != TL_OPEN_OK) {
            printf("%-22s %-17s %s\n", scene, label, err);
            free(pack);
            continue;
        }
        uint64_t gpu = 0;
        for (uint32_t pg = 0; pg < p.lmap.page_count; pg++) {
            lbk_lmap_planes pl;
            tl_bake_planes(&p, pg, &pl);
            gpu += pl.bytes[0] + pl.bytes[1];
        }
        tl_pack_error pe;
        if (tl_pack_error_compute(&a, &p, &pe, err)) {
            printf("%-22s %-17s %s\n", scene, label, err);
        } else {
            char bpt[40];
            const double goal_bpt = pr.lmap_format[0] == LBK_LMAP_BC6H ? 2.5 : pr.lmap_format[0] ? 2.0 : 8.0;
            const double b_own = (double)gpu / (double)p.lmap.texel_count, b_base = (double)gpu / (double)base_texels;
            snprintf(bpt, sizeof bpt, "%.2f (%.2f)", b_base, b_own);
            const tl_pack_stats *l = &pe.all.lum, *c = &pe.all.colour;
            printf("%-22s %-17s %13s %6.2fs %5.2f %% %6.2f %% %6.1f %% %6.2f %%  %.4f %.4f  %4.2f %5.2f %4.2f  %s\n", scene,
                   label, bpt, rep.encode_seconds, 100 * l->mean, 100 * l->p99, 100 * l->max, 100 * pe.seam.lum.p99,
                   c->mean, c->p99, l->mean / TL_PACK_GOAL_MEAN, l->p99 / TL_PACK_GOAL_P99, b_base / goal_bpt,
                   !pr.lmap_format[0] ? "-" /* 1.0 texels: nothing to meet */
                   : tl_pack_error_meets(l, TL_PACK_GOAL_MEAN, TL_PACK_GOAL_P99) && b_base <= goal_bpt ? "yes" : "NO");
            tl_pack_error_free(&pe);
        }
        tl_bake_close(&p);
        free(pack);
    }
    tl_bake_close(&a);
}

static int bake(const char *path, const char *scene, int block_align, void **bytes, size_t *size)
{
    lbk_bake_desc d = {0};
    d.size = sizeof d;
    d.seed = 1; /* preset fast: stops at its 3 % target */
    d.block_align = block_align;
    if (!strcmp(scene, "room_with_doors")) { /* a level without a light of its own */
        d.sky_override = 1;
        d.sky[0] = d.sky[1] = d.sky[2] = 1;
    }
    lbk_bake_output *out;
    if (lbk_bake_from_file(path, &d, &out) != LBK_OK) return -1;
    lbk_result r = lbk_bake_output_container(out, bytes, size);
    lbk_bake_output_free(out);
    return r == LBK_OK ? 0 : -1;
}

static const char *scenes_dir(void)
{
    const char *d = getenv("LBK_SCENES");
    return d && *d ? d : "scenes";
}

/* bench_packs [PROFILE...]: the shipped profiles, or the named ones / profile files (then without
 * the --block-align bakes), e.g. to compare a variant of a profile. */
int main(int argc, char **argv)
{
    printf("lightmap packs per profile (preset fast, to its 3 %% target): GPU bytes per texel of the pack's LMAP over\n"
           "the bake's texels (the pack's own texels, padding included, in brackets), block-encoding seconds, the pack's\n"
           "error against the uncompressed bake as lbk convert reports it (luminance mean / p99 / max, seam texels' p99;\n"
           "chroma mean / p99), and against the goal mean <= 1 %%, p99 <= 5 %% at <= 2.5 (BC6H) / 2 (ASTC) GPU B/texel:\n"
           "ratios value / goal (<= 1 meets it)\n\n");
    printf("%-22s %-17s %13s %7s %7s %8s %8s %8s  %-13s  %-16s %s\n", "scene", "profile", "GPU B/texel", "encode", "mean",
           "p99", "max", "seam p99", "chroma m/p99", "goal mean/p99/B", "met");
    for (size_t s = 0; s < sizeof scenes / sizeof scenes[0]; s++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", scenes_dir(), scenes[s][1]);
        if (access(path, R_OK)) {
            printf("%-22s SKIPPED (%s missing)\n", scenes[s][0], path);
            continue;
        }
        void *bytes, *aligned;
        size_t size, aligned_size;
        if (bake(path, scenes[s][0], 0, &bytes, &size)) {
            printf("%-22s bake failed\n", scenes[s][0]);
            continue;
        }
        lbk_reader *r;
        uint64_t texels = 0;
        const void *d;
        size_t n;
        lbk_lmap_view v;
        if (lbk_reader_open_memory(bytes, size, NULL, &r) == LBK_OK) {
            if (lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &d, &n) == LBK_OK && lbk_lmap_open(d, n, &v) == LBK_OK)
                texels = v.texel_count;
            lbk_reader_close(r);
        }
        if (argc > 1) {
            run_profiles(scenes[s][0], bytes, size, texels ? texels : 1, (const char *const *)argv + 1, (size_t)argc - 1, "");
            lbk_free(NULL, bytes);
            continue;
        }
        run_profiles(scenes[s][0], bytes, size, texels ? texels : 1, profiles, sizeof profiles / sizeof profiles[0], "");
        /* the same level baked with --block-align: no block holds two charts */
        static const char *const block_profiles[] = {"console-current", "handheld"};
        if (texels && bake(path, scenes[s][0], 1, &aligned, &aligned_size) == 0) {
            run_profiles(scenes[s][0], aligned, aligned_size, texels, block_profiles, 2, " +align");
            lbk_free(NULL, aligned);
        }
        lbk_free(NULL, bytes);
    }
    return 0;
}
