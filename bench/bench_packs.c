/* Console packs: per shipped conversion profile and shared scene, the GPU bytes per lightmap texel,
 * the block-encoding time, and the error of the pack's lightmaps against the uncompressed bake in
 * the rendered irradiance (tools/convert/profiles/README.md "Block-compressed lightmaps"):
 *   - every texel inside an object's rectangle that the baker wrote (not the all-zero texels of a
 *     rectangle's unused corners), decoded at the five normals lbk diff uses (+Z and
 *     45° toward ±X, ±Y), physical irradiance;
 *   - seams: the texels within 2 of a chart's edge, in 4×4 blocks two charts share vs in blocks the
 *     chart has to itself (a block straddling two charts must not make the edge worse);
 *   - luminance error |ΔY| / max(Y, Y_floor), Y_floor = 1 % of the scene's mean Y (so the black
 *     corners do not dominate); chroma error |Δ(r, g)| of the chromaticity r = R/(R+G+B),
 *     g = G/(R+G+B), where Y > Y_floor;
 *   - mean and 99th percentile over all those samples; and the same for the texels of blocks that
 *     two objects' rectangles share (the chart seams a 4×4 block can straddle) next to blocks inside
 *     one rectangle.
 * Bakes: preset fast (to its 3 % target error), seed 1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene/clock.h"
#include "lbk/bake.h"
#include "tools/common/bake_data.h"
#include "tools/convert/convert.h"
#include "tools/convert/profile.h"

static const char *const scenes[][2] = {
    {"cornell_box", "cornell_box/CornellBox-Original.gltf"},
    {"cornell_box_bjs", "cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf"},
    {"room_with_doors", "room_with_doors/room.glb"},
    {"lights_punctual_lamp", "lights_punctual_lamp/LightsPunctualLamp.gltf"},
    {"water_bottle_draco", "water_bottle_draco/WaterBottle.gltf"},
};
static const char *const profiles[] = {"console-current", "console-previous", "pc", "handheld", "archive"};

typedef struct samples {
    double *v;
    size_t n, cap;
} samples;

static void push(samples *s, double x)
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 4096;
        s->v = realloc(s->v, s->cap * sizeof *s->v);
        if (!s->v) exit(1);
    }
    s->v[s->n++] = x;
}

static int cmp(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void stats(samples *s, double *mean, double *p99)
{
    *mean = *p99 = 0;
    if (!s->n) return;
    double sum = 0;
    for (size_t i = 0; i < s->n; i++) sum += s->v[i];
    *mean = sum / (double)s->n;
    qsort(s->v, s->n, sizeof *s->v, cmp);
    *p99 = s->v[(size_t)(0.99 * (double)(s->n - 1))];
}

static double lum(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

typedef struct errors {
    samples lum, chroma, lum_seam, lum_inside;
} errors;

/* Per page: how many objects' rectangles touch each 4×4 block. */
static uint8_t *block_owners(const tl_bake *b, uint32_t page, uint32_t w, uint32_t h)
{
    const uint32_t bw = (w + 3) / 4, bh = (h + 3) / 4;
    uint8_t *n = calloc((size_t)bw * bh + 1, 1);
    for (uint32_t i = 0; i < b->objs.count; i++) {
        lbk_object o;
        lbk_objects_get(&b->objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP || o.index != page) continue;
        for (uint32_t by = o.rect_y / 4; by <= (o.rect_y + o.rect_h - 1) / 4 && by < bh; by++)
            for (uint32_t bx = o.rect_x / 4; bx <= (o.rect_x + o.rect_w - 1) / 4 && bx < bw; bx++)
                if (n[(size_t)by * bw + bx] < 255) n[(size_t)by * bw + bx]++;
    }
    return n;
}

static void compare(const tl_bake *a, const tl_bake *p, errors *e)
{
    /* the floor: 1 % of the mean luminance at +Z over the objects' texels */
    double ysum = 0;
    size_t yn = 0;
    for (uint32_t i = 0; i < a->objs.count; i++) {
        lbk_object o;
        lbk_objects_get(&a->objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP) continue;
        for (uint32_t y = 0; y < o.rect_h; y++)
            for (uint32_t x = 0; x < o.rect_w; x++) {
                float v[TL_TEXEL_NORMALS][3];
                tl_bake_texel_eval(a, o.index, o.rect_x + x, o.rect_y + y, v);
                ysum += lum(v[0]), yn++;
            }
    }
    const double floor_y = yn ? 0.01 * ysum / (double)yn : 0;
    for (uint32_t i = 0; i < a->objs.count; i++) {
        lbk_object o;
        lbk_objects_get(&a->objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP) continue;
        lbk_lmap_planes pl;
        tl_bake_planes(p, o.index, &pl);
        uint8_t *owners = block_owners(p, o.index, pl.width, pl.height);
        for (uint32_t y = 0; y < o.rect_h; y++)
            for (uint32_t x = 0; x < o.rect_w; x++) {
                const uint32_t px = o.rect_x + x, py = o.rect_y + y;
                lbk_ahd_texel_f raw;
                tl_bake_texel_get(a, o.index, px, py, &raw, NULL, NULL);
                if (raw.ez[0] == 0 && raw.ez[1] == 0 && raw.ez[2] == 0 && raw.rgba[0] == 0 && raw.rgba[3] == 0)
                    continue; /* never written by the baker: not drawn */
                float va[TL_TEXEL_NORMALS][3], vp[TL_TEXEL_NORMALS][3];
                tl_bake_texel_eval(a, o.index, px, py, va);
                tl_bake_texel_eval(p, o.index, px, py, vp);
                const int seam = owners[(size_t)(py / 4) * ((pl.width + 3) / 4) + px / 4] > 1;
                /* the seam comparison is between texels near a chart's edge (within 2 texels), in
                 * blocks shared with another chart and in blocks the chart has to itself */
                const int edge = x < 2 || y < 2 || x + 2 >= o.rect_w || y + 2 >= o.rect_h;
                for (int n = 0; n < TL_TEXEL_NORMALS; n++) {
                    const double ya = lum(va[n]), yp = lum(vp[n]);
                    const double el = fabs(yp - ya) / fmax(ya, floor_y);
                    push(&e->lum, el);
                    if (edge) push(seam ? &e->lum_seam : &e->lum_inside, el);
                    const double sa = va[n][0] + va[n][1] + va[n][2], sp = vp[n][0] + vp[n][1] + vp[n][2];
                    if (ya > floor_y && sa > 0 && sp > 0)
                        push(&e->chroma, hypot(vp[n][0] / sp - va[n][0] / sa, vp[n][1] / sp - va[n][1] / sa));
                }
            }
        free(owners);
    }
}

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
        errors e;
        memset(&e, 0, sizeof e);
        compare(&a, &p, &e);
        double lm, lp, cm, cp, sm, sp, im, ip;
        stats(&e.lum, &lm, &lp);
        stats(&e.chroma, &cm, &cp);
        stats(&e.lum_seam, &sm, &sp);
        stats(&e.lum_inside, &im, &ip);
        char bpt[40], seam[40];
        snprintf(bpt, sizeof bpt, "%.2f (%.2f)", (double)gpu / (double)base_texels, (double)gpu / (double)p.lmap.texel_count);
        if (e.lum_seam.n) snprintf(seam, sizeof seam, "%.4f / %.4f", sp, ip);
        else snprintf(seam, sizeof seam, "- / %.4f", ip);
        printf("%-22s %-17s %16s %7.2fs   %.4f / %.4f   %.4f / %.4f %17s\n", scene, label, bpt, rep.encode_seconds, lm,
               lp, cm, cp, seam);
        free(e.lum.v), free(e.chroma.v), free(e.lum_seam.v), free(e.lum_inside.v);
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
           "the bake's texels (the pack's own texels, padding included, in brackets), block-encoding seconds,\n"
           "rendered-irradiance error against the uncompressed bake: luminance mean / p99, chroma mean / p99,\n"
           "luminance p99 of chart-edge texels in blocks two charts share vs in blocks of one chart\n\n");
    printf("%-22s %-17s %16s %8s %17s %17s %17s\n", "scene", "profile", "GPU B/texel", "encode", "lum mean / p99",
           "chroma mean / p99", "edge p99 shared/own");
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
