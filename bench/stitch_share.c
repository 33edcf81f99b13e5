/* Seam stitching's share of a bake's CPU, per level (printed, not asserted; goal ≤ 0.05), and
 * what it does to the seams.
 *
 * Every level is baked through liblbkbake as `lbk bake` does (fast preset, seed 1): the shared
 * scenes of scenes/ (LBK_SCENES overrides; room_with_doors and leak_rooms with --sky 1,1,1) and
 * the levels of each bench/levels manifest named on the command line (their own lbk_args:
 * --sky, --texel-density). The bench is linked with -Wl,--wrap=bk_seams_stitch (mk/bench.mk),
 * so every call the baker makes — the base pages and every light set's — comes through
 * stitch_wrap below, which runs it on the calling thread (the result does not depend on the
 * thread count) and adds that thread's CPU time: exactly the stitching's CPU, whatever else
 * runs beside it. The bake's CPU is the process's over the bake.
 *
 * Per level: bake CPU seconds, stitching CPU seconds, their ratio, and the seam score
 * (bake/layout/seams.h: length-weighted mean relative jump of the filtered luminance across
 * smooth seams) of the pages before and after stitching — measured on the float pages the
 * stitcher gets and returns (seam_raw, seam_st: the stitcher's own effect) and of the stitched
 * pages as the encoder stores them (seam_enc: AHD with R11G11B10F irradiance, read back).
 * Usage: stitch_share [MANIFEST.json ...]. LBK_STITCH_ONLY=NAME,... keeps the named levels. */
#include <cjson/cJSON.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bake/layout/seams.h"
#include "bench/bench_util.h"
#include "lbk/bake.h"
#include "lbk/ahd.h"

size_t __real_bk_seams_stitch(const bk_seams *seams, uint32_t page, int width, int height, float *data,
                              const uint8_t *mask, int threads);
size_t __wrap_bk_seams_stitch(const bk_seams *seams, uint32_t page, int width, int height, float *data,
                              const uint8_t *mask, int threads);

typedef struct stitch_acc {
    double cpu;                /* stitching CPU seconds */
    double raw_sum, st_sum, enc_sum; /* seam score × weight (smooth seam points): before, after,
                                        after as stored */
    double weight;
    size_t calls;
} stitch_acc;

static pthread_mutex_t acc_lock = PTHREAD_MUTEX_INITIALIZER;
static stitch_acc acc;

/* Seam score of one page of 12-float tangent-space texels: luminance of the irradiance along
 * the normal (e0 + g.z per colour); encoded: of the texels as the encoder stores them (AHD,
 * R11G11B10F), read back. */
static bk_seam_score page_score(const bk_seams *s, uint32_t page, int w, int h, const float *data, const uint8_t *mask,
                                int encoded)
{
    bk_seam_score sc;
    memset(&sc, 0, sizeof sc);
    size_t n = (size_t)w * (size_t)h;
    float *lum = malloc(n * sizeof *lum);
    const float **lp = calloc((size_t)page + 1, sizeof *lp);
    bk_atlas_page *pg = calloc((size_t)page + 1, sizeof *pg);
    if (lum && lp && pg) {
        for (size_t i = 0; i < n; i++) {
            lbk_ahd_linear l;
            memcpy(l.c, &data[12 * i], sizeof l.c);
            if (encoded && mask[i]) {
                lbk_ahd_texel t;
                lbk_ahd_from_linear(&l, &t);
                lbk_ahd_to_linear(&t, &l);
            }
            const float *t = &l.c[0][0];
            float e[3] = {t[0] + t[3], t[4] + t[7], t[8] + t[11]};
            lum[i] = mask[i] ? LBK_LUM_R * e[0] + LBK_LUM_G * e[1] + LBK_LUM_B * e[2] : 0.0f;
        }
        pg[page].width = w;
        pg[page].height = h;
        lp[page] = lum;
        bk_seams_score(s, pg, (size_t)page + 1, lp, &sc);
    }
    free(lum), free(lp), free(pg);
    return sc;
}

size_t __wrap_bk_seams_stitch(const bk_seams *seams, uint32_t page, int width, int height, float *data,
                              const uint8_t *mask, int threads)
{
    (void)threads;
    bk_seam_score before = page_score(seams, page, width, height, data, mask, 0);
    double t0 = bench_thread_cpu();
    size_t r = __real_bk_seams_stitch(seams, page, width, height, data, mask, 1);
    double t = bench_thread_cpu() - t0;
    bk_seam_score after = page_score(seams, page, width, height, data, mask, 0);
    bk_seam_score stored = page_score(seams, page, width, height, data, mask, 1);
    pthread_mutex_lock(&acc_lock);
    acc.cpu += t;
    acc.calls++;
    acc.raw_sum += before.mean * (double)before.points;
    acc.st_sum += after.mean * (double)after.points;
    acc.enc_sum += stored.mean * (double)stored.points;
    acc.weight += (double)before.points;
    pthread_mutex_unlock(&acc_lock);
    return r;
}

static int wanted(const char *name)
{
    const char *only = getenv("LBK_STITCH_ONLY");
    if (!only || !*only) return 1;
    size_t n = strlen(name);
    for (const char *p = only; *p;) {
        const char *e = strchr(p, ',');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (len == n && strncmp(p, name, n) == 0) return 1;
        if (!e) break;
        p = e + 1;
    }
    return 0;
}

static void on_message(void *user, lbk_bake_severity severity, const char *message)
{
    (void)user;
    if (severity == LBK_BAKE_SEVERITY_ERROR) fprintf(stderr, "stitch_share: %s\n", message);
}

static double worst = 0.0, sum_ratio = 0.0;
static int levels = 0, over = 0;

static void bake_level(const char *name, const char *path, const lbk_bake_desc *base)
{
    if (!wanted(name)) return;
    if (access(path, R_OK) != 0) {
        printf("%-28s %s missing, skipped\n", name, path);
        return;
    }
    lbk_bake_desc d = *base;
    d.size = sizeof d;
    d.seed = 1;
    d.message = on_message;
    memset(&acc, 0, sizeof acc);
    lbk_bake_output *o = NULL;
    double c0 = bench_process_cpu();
    lbk_result r = lbk_bake_from_file(path, &d, &o);
    double cpu = bench_process_cpu() - c0;
    lbk_bake_output_free(o);
    if (r != LBK_OK) {
        printf("%-28s bake failed: %s\n", name, lbk_result_message(r));
        return;
    }
    double ratio = cpu > 0.0 ? acc.cpu / cpu : 0.0;
    double wt = acc.weight > 0 ? 1.0 / acc.weight : 0.0;
    printf("%-28s %8.2f %8.3f %7.4f %8.4f %8.4f %8.4f %5zu\n", name, cpu, acc.cpu, ratio, acc.raw_sum * wt,
           acc.st_sum * wt, acc.enc_sum * wt, acc.calls);
    fflush(stdout);
    levels++;
    sum_ratio += ratio;
    over += ratio > 0.05;
    if (ratio > worst) worst = ratio;
}

static void shared_scenes(void)
{
    static const struct { const char *label, *rel; int sky; } cases[] = {
        {"cornell_box", "cornell_box/CornellBox-Original.gltf", 0},
        {"cornell_box_bjs", "cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf", 0},
        {"leak_rooms", "leak_rooms/leak_rooms.gltf", 1},
        {"lights_punctual_lamp", "lights_punctual_lamp/LightsPunctualLamp.gltf", 0},
        {"room_with_doors", "room_with_doors/room.glb", 1},
        {"water_bottle_draco", "water_bottle_draco/WaterBottle.gltf", 0},
    };
    const char *dir = getenv("LBK_SCENES");
    if (!dir || !*dir) dir = "scenes";
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, cases[i].rel);
        lbk_bake_desc d = {.size = sizeof d};
        if (cases[i].sky) {
            d.sky_override = 1;
            d.sky[0] = d.sky[1] = d.sky[2] = 1.0f;
        }
        bake_level(cases[i].label, path, &d);
    }
}

/* The lbk_args of a manifest scene (--sky R,G,B, --texel-density D) as a bake description. */
static void manifest_desc(const cJSON *args, lbk_bake_desc *d)
{
    memset(d, 0, sizeof *d);
    d->size = sizeof *d;
    int n = cJSON_GetArraySize(args);
    for (int i = 0; i + 1 < n; i++) {
        const char *k = cJSON_GetStringValue(cJSON_GetArrayItem(args, i));
        const char *v = cJSON_GetStringValue(cJSON_GetArrayItem(args, i + 1));
        if (!k || !v) continue;
        if (strcmp(k, "--sky") == 0 && sscanf(v, "%f,%f,%f", &d->sky[0], &d->sky[1], &d->sky[2]) == 3)
            d->sky_override = 1;
        if (strcmp(k, "--texel-density") == 0) d->texel_density = strtof(v, NULL);
    }
}

static int manifest_levels(const char *manifest)
{
    FILE *f = fopen(manifest, "rb");
    if (!f) return -1;
    char *text = NULL;
    long len = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (len > 0 && fseek(f, 0, SEEK_SET) == 0 && (text = malloc((size_t)len + 1)) &&
        fread(text, 1, (size_t)len, f) == (size_t)len)
        text[len] = 0;
    else
        free(text), text = NULL;
    fclose(f);
    cJSON *root = text ? cJSON_Parse(text) : NULL;
    free(text);
    if (!root) return -1;
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", manifest);
    char *slash = strrchr(dir, '/');
    if (slash) *slash = 0;
    else snprintf(dir, sizeof dir, ".");
    const cJSON *sc;
    cJSON_ArrayForEach(sc, cJSON_GetObjectItemCaseSensitive(root, "scenes")) {
        const char *name = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(sc, "name"));
        const char *gltf = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(sc, "gltf"));
        if (!name || !gltf) continue;
        char path[2100];
        snprintf(path, sizeof path, "%s/%s", dir, gltf);
        lbk_bake_desc d;
        manifest_desc(cJSON_GetObjectItemCaseSensitive(sc, "lbk_args"), &d);
        bake_level(name, path, &d);
    }
    cJSON_Delete(root);
    return 0;
}

int main(int argc, char **argv)
{
    printf("seam stitching's share of bake CPU (fast preset, seed 1; goal <= 0.05 per level)\n");
    printf("%-28s %8s %8s %7s %8s %8s %8s %5s\n", "level", "bake_s", "stitch_s", "share", "seam_raw", "seam_st",
           "seam_enc", "calls");
    shared_scenes();
    for (int i = 1; i < argc; i++)
        if (manifest_levels(argv[i]) != 0) fprintf(stderr, "stitch_share: %s: cannot read the manifest\n", argv[i]);
    printf("levels %d, share: max %.4f, mean %.4f, over 0.05: %d\n", levels, worst, levels ? sum_ratio / levels : 0.0,
           over);
    return 0;
}
