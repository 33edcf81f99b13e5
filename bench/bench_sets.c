/* Light sets and doors as baked by `lbk bake` (bake/bake_sets.c) on the room_with_doors test
 * levels (tests/support/door_scenes.h): per level the DLS section's payload against its
 * ancillary bytes (cluster records, set lists, runs, prefix data, names), the share of texels
 * the sparse storage kept, and the bake time of the sets against the base bake, measured in
 * this run. The seed reports about 132 KB of ancillary data for its largest map. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bake/bake.h"
#include "lbk/container.h"
#include "lbk/dls.h"
/* The generator lives with the tests; benches link the tools only, so take its source. */
#include "tests/support/door_scenes.c"

typedef struct level {
    const char *name;
    ds_options opt;
    float threshold;
} level;

static int run(const level *lv, const char *dir)
{
    char gltf[256], out[256], err[512];
    snprintf(gltf, sizeof gltf, "%s/%s.gltf", dir, lv->name);
    snprintf(out, sizeof out, "%s/%s.lbk", dir, lv->name);
    if (ds_write_room_scene(DS_ROOM_GLB, gltf, &lv->opt, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", lv->name, err);
        return 1;
    }
    bk_bake_options bo;
    memset(&bo, 0, sizeof bo);
    bo.input = gltf;
    bo.output = out;
    bo.seed = 1;
    bo.target_error = -1;
    bo.dls_threshold = lv->threshold;
    bk_progress pr;
    bk_progress_init(&pr, 1);
    bk_bake_summary sum;
    double t0 = bk_now();
    int rc = bk_bake(&bo, &pr, &sum, err, sizeof err);
    double secs = bk_now() - t0;
    unlink(gltf);
    if (rc) {
        fprintf(stderr, "%s: bake failed: %s\n", lv->name, err);
        return 1;
    }
    lbk_reader *rd;
    const void *d;
    size_t n, lmap = 0;
    if (lbk_reader_open_file(out, NULL, &rd) != LBK_OK) return 1;
    if (lbk_reader_section_by_type(rd, LBK_SECTION_LMAP, &d, &n) == LBK_OK) lmap = n;
    lbk_dls_stats st;
    memset(&st, 0, sizeof st);
    if (lbk_reader_section_by_type(rd, LBK_SECTION_DLS, &d, &n) == LBK_OK) {
        lbk_dls_view *v;
        if (lbk_dls_view_open(d, n, NULL, &v) == LBK_OK) {
            lbk_dls_compute_stats(v, &st);
            lbk_dls_view_close(v);
        }
    }
    lbk_reader_close(rd);
    unlink(out);
    uint64_t tex = st.target_count[LBK_DLS_SPACE_TEXEL];
    printf("%-22s %6llu texels  %2u sets %u doors  LMAP %8zu B  DLS payload %8llu B  ancillary %6llu B (%5.2f%% of "
           "payload, %.2f index bits/touched texel)  touched %5.1f%% of texels  clusters %u  bake %.1f s\n",
           lv->name, (unsigned long long)sum.texels, sum.sets, sum.doors, lmap, (unsigned long long)st.payload_bytes,
           (unsigned long long)st.ancillary_bytes,
           st.payload_bytes ? 100.0 * (double)st.ancillary_bytes / (double)st.payload_bytes : 0.0,
           st.index_bits_per_target[LBK_DLS_SPACE_TEXEL], tex ? 100.0 * (double)st.touched[0] / (double)tex : 0.0,
           st.cluster_count, secs);
    return 0;
}

int main(void)
{
    char dir[] = "/tmp/lbk_bench_sets_XXXXXX";
    if (!mkdtemp(dir)) return 1;
    const level levels[] = {
        {"static (no sets)", {DS_DOOR_PLAIN, DS_INSIDE_STATIC, 0, 1, 0.5f, 4}, 0},
        {"sets A+B", {DS_DOOR_PLAIN, DS_INSIDE_SETS, 0, 1, 0.5f, 4}, 0},
        {"door", {DS_DOOR_TAGGED, DS_INSIDE_STATIC, 0, 1, 0.5f, 4}, 0},
        {"sets A+B+C0 + door", {DS_DOOR_TAGGED, DS_INSIDE_SETS, 1, 1, 0.5f, 4}, 0},
        {"same, threshold 10%", {DS_DOOR_TAGGED, DS_INSIDE_SETS, 1, 1, 0.5f, 4}, 0.1f},
        {"same, keep all", {DS_DOOR_TAGGED, DS_INSIDE_SETS, 1, 1, 0.5f, 4}, -1},
    };
    int bad = 0;
    for (size_t i = 0; i < sizeof levels / sizeof levels[0]; i++) bad |= run(&levels[i], dir);
    rmdir(dir);
    return bad;
}
