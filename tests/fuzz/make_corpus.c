/* Writes the hand-built part of the seed corpus of fuzz_container into tests/fuzz/corpus
 * (`make fuzz-corpus`; the files are committed, tests/fuzz/README.md lists them all):
 *   objects_raw.lbk, objects_zstd.lbk  META, REPT, OBJS, LMAP, LLG: an object table that
 *                                      references a real LMAP and LLG;
 *   every_raw.lbk, every_zstd.lbk      every section type (META, REPT, OBJS, LMAP, GLG, LLG,
 *                                      OCTP, DLS, DOOR), consistent across sections, so the
 *                                      fuzzer starts from inputs that reach every section
 *                                      reader, sampler and cross-section check;
 *   dls.lbk                            META, OBJS, LMAP, GLG, LLG, DLS, DOOR: 24 sets over 600 texels and 64 + 64 probes,
 *                                      clusters of every form (dedicated, packed, prefix-2, -3,
 *                                      -8), so the runtime's planner and kernels see them all.
 * Each file must pass lbk_validate with no finding; the program fails otherwise. */
#include <stdio.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/octa.h"
#include "lbk/report.h"
#include "lbk/validate.h"

typedef struct section {
    uint32_t type;
    void *data;
    size_t size;
} section;

static int write_file(const char *path, const void *d, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(d, 1, n, f) != n) return 1;
    return fclose(f) != 0;
}

static int print_issue(void *user, const lbk_issue *issue)
{
    fprintf(stderr, "%s: issue %u: %s\n", (const char *)user, issue->id, issue->message);
    return 0;
}

/* Writes the sections (META uncompressed, the rest zstd when asked), validates the result. */
static int write_container(const char *path, const section *s, int count, int zstd)
{
    lbk_writer *w;
    lbk_write_options wo = {.section_alignment = zstd ? 16 : 64};
    lbk_section_options o = {.flags = LBK_SECTION_FLAG_REQUIRED, .compression = zstd ? LBK_COMPRESSION_ZSTD : 0, .zstd_level = 3};
    if (lbk_writer_open(&wo, &w)) return 1;
    for (int i = 0; i < count; i++)
        if (lbk_writer_section_add(w, s[i].type, s[i].data, s[i].size, s[i].type == LBK_SECTION_META ? NULL : &o))
            return 1;
    void *bytes;
    size_t n;
    if (lbk_writer_to_memory(w, &bytes, &n)) return 1;
    lbk_writer_close(w);
    lbk_validate_summary vs;
    int rc = lbk_validate_memory(bytes, n, NULL, print_issue, (void *)path, &vs) != LBK_OK ||
             vs.fatal + vs.errors + vs.warnings != 0 || write_file(path, bytes, n);
    lbk_free(NULL, bytes);
    return rc;
}

/* R11G11B10F irradiance near 1 with varying mantissas (exponent 31 would be Inf/NaN). */
static lbk_ahd_texel texel(int i)
{
    const uint32_t m = (uint32_t)i, r = 15u << 6 | (m & 63), g = 14u << 6 | ((3 * m) & 63), b = 15u << 5 | (m & 31);
    return (lbk_ahd_texel){r | g << 11 | b << 22, {(uint8_t)(200 - i), 128, (uint8_t)(100 + i), 255}};
}

static void probe_sh(int i, lbk_sh9_rgb *sh)
{
    memset(sh, 0, sizeof *sh);
    for (int c = 0; c < 3; c++) {
        sh->c[c][0] = 1.0f + 0.25f * (float)i + 0.1f * (float)c;
        sh->c[c][1 + i % 3] = 0.3f;
    }
}

/* A 2 × 2 × 2 m cube of 8 probes, cut into 5 tetrahedra (a central one and four corners). */
static int build_glg(void **out, size_t *size)
{
    float pos[8][3];
    lbk_sh9_rgb sh[8];
    for (int i = 0; i < 8; i++) {
        pos[i][0] = 2.0f * (float)(i & 1), pos[i][1] = 2.0f * (float)(i >> 1 & 1), pos[i][2] = 2.0f * (float)(i >> 2 & 1);
        probe_sh(i, &sh[i]);
    }
    const uint32_t tets[5][4] = {{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}};
    const uint8_t vis[5][4] = {{255, 255, 255, 255}, {255, 128, 64, 0}, {10, 255, 255, 200}, {255, 0, 255, 0}, {1, 2, 3, 4}};
    lbk_glg_build_desc d = {.probe_count = 8, .tetra_count = 5, .positions = (const float (*)[3])pos, .probes = sh, .tetras = tets, .visibility = vis, .scale = 0.25f};
    return lbk_glg_build(&d, NULL, out, size) != LBK_OK;
}

static int build_octp(void **out, size_t *size)
{
    static lbk_octp_probe_desc p[2];
    for (int k = 0; k < 2; k++) {
        p[k].position[0] = 1.0f, p[k].position[1] = 0.5f + (float)k, p[k].position[2] = 1.0f;
        for (int i = 0; i < 16; i++)
            for (int c = 0; c < 3; c++) p[k].irradiance[i][c] = 0.5f + 0.1f * (float)i + 0.2f * (float)c + (float)k;
        for (int i = 0; i < 144; i++) p[k].depth[i][0] = 1.0f + 0.01f * (float)i, p[k].depth[i][1] = p[k].depth[i][0] * p[k].depth[i][0] + 0.1f;
    }
    return lbk_octp_build(&(lbk_octp_build_desc){.probes = p, .probe_count = 2, .scale = 0.5f}, NULL, out, size) != LBK_OK;
}

/* The volume form (1.3): one 2 x 2 x 2 level, probes of every state, relocated ones among them. */
static int build_octp_volume(void **out, size_t *size)
{
    static lbk_octp_probe_desc p[8];
    static lbk_octp_probe_info info[8];
    const uint32_t states[8] = {LBK_OCTP_ACTIVE, LBK_OCTP_ACTIVE, LBK_OCTP_INSIDE, LBK_OCTP_NO_NEARBY,
                                LBK_OCTP_ACTIVE, LBK_OCTP_ACTIVE, LBK_OCTP_ACTIVE, LBK_OCTP_NO_NEARBY};
    for (int k = 0; k < 8; k++) {
        for (int i = 0; i < 16; i++)
            for (int c = 0; c < 3; c++) p[k].irradiance[i][c] = 0.25f + 0.05f * (float)i + 0.1f * (float)c + 0.5f * (float)k;
        for (int i = 0; i < 144; i++) p[k].depth[i][0] = 0.5f + 0.01f * (float)i, p[k].depth[i][1] = p[k].depth[i][0] * p[k].depth[i][0] + 0.05f;
        info[k] = (lbk_octp_probe_info){.offset = {k == 1 ? 0.25f : 0.0f, 0.0f, k == 5 ? -0.125f : 0.0f}, .state = states[k],
                                        .rays = 64, .backface = k == 2 ? 0.75f : 0.0f, .nearest = 0.5f + 0.125f * (float)k};
    }
    const lbk_octp_level level = {.origin = {0.5f, 0.25f, 0.5f}, .spacing = 1.0f, .dims = {2, 2, 2}, .miss_distance = 8.0f};
    lbk_octp_build_desc d = LBK_OCTP_BUILD_DESC_INIT;
    d.probes = p, d.probe_count = 8, d.scale = 0.5f, d.levels = &level, d.level_count = 1, d.info = info;
    return lbk_octp_build(&d, NULL, out, size) != LBK_OK;
}

/* DLS over 48 texels (the LMAP), 8 GLG and 8 LLG probes: two light sets, a door's open and
 * closed sets and one combination (A with the door open); the DOOR section names them. */
enum { TEXELS = 48, GLG_PROBES = 8, LLG_PROBES = 8 };
static int build_dls_door(void **dls, size_t *dls_n, void **door, size_t *door_n)
{
    static uint32_t targets[5][3][TEXELS];
    static uint8_t payloads[5][3][TEXELS * 28];
    /* per set and space: first target and count */
    const uint32_t span[5][3][2] = {
        {{0, 20}, {0, 4}, {2, 4}}, {{10, 20}, {2, 6}, {0, 0}}, {{5, 10}, {0, 0}, {4, 4}}, {{30, 6}, {1, 1}, {0, 0}},
        {{8, 4}, {0, 0}, {0, 0}}};
    static const char *names[5] = {"A", "B", "door/d1/open", "door/d1/closed", "combo/A+d1"};
    static const char *lights_a[1] = {"lamp_a"}, *lights_b[2] = {"lamp_b", "lamp_c"};
    static const uint32_t combo_members[2] = {0, 2};
    lbk_dls_set_desc sets[5];
    memset(sets, 0, sizeof sets);
    for (int s = 0; s < 5; s++) {
        sets[s].name = names[s];
        sets[s].kind = s < 2 ? LBK_DLS_KIND_LIGHTS : (uint32_t)s - 1;
        for (int sp = 0; sp < 3; sp++) {
            const uint32_t first = span[s][sp][0], n = span[s][sp][1];
            for (uint32_t i = 0; i < n; i++) {
                targets[s][sp][i] = first + i;
                if (sp == LBK_DLS_SPACE_TEXEL) {
                    lbk_ahd_texel t = texel((int)(first + i) + 7 * s);
                    lbk_ahd_texel_pack(&t, &payloads[s][sp][8 * i]);
                } else {
                    lbk_sh9_rgb sh;
                    probe_sh((int)i + s, &sh);
                    lbk_sh9_pack(&sh, &payloads[s][sp][28 * i]);
                }
            }
            sets[s].entries[sp] = (lbk_dls_sparse){n, targets[s][sp], payloads[s][sp]};
        }
    }
    sets[0].light_count = 1, sets[0].light_names = lights_a;
    sets[1].light_count = 2, sets[1].light_names = lights_b;
    sets[4].member_count = 2, sets[4].members = combo_members;
    lbk_dls_build_desc dd = {.set_count = 5, .sets = sets, .target_count = {TEXELS, GLG_PROBES, LLG_PROBES}};
    lbk_result r = lbk_dls_build(&dd, NULL, dls, dls_n, NULL);
    if (r != LBK_OK) {
        fprintf(stderr, "make_corpus: DLS: %s\n", lbk_result_message(r));
        return 1;
    }
    const lbk_door_desc d1 = {"d1", {1, 1, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0.5f, 1.0f, 0.05f}, 2, 3};
    const uint32_t door0 = 0;
    const lbk_door_state_desc state = {1, &door0, 4};
    const lbk_door_build_desc doors = {.door_count = 1, .doors = &d1, .state_count = 1, .states = &state};
    r = lbk_door_build(&doors, NULL, door, door_n);
    if (r != LBK_OK) fprintf(stderr, "make_corpus: DOOR: %s\n", lbk_result_message(r));
    return r != LBK_OK;
}

/* dls.lbk: DLS + DOOR with clusters of every form, for the runtime (job planner, kernels). 24 sets
 * over 600 texels and 64 + 64 probes: a wide single-set region (dedicated), small
 * combinations of 1–4 sets (packed), and a corner where 6, 12 and 20 sets overlap (prefix-2, -3,
 * -8); set 1 a door's open set, 2 its bounce, 23 the combination {0, 1}. */
static int write_dls(void)
{
    enum { NSETS = 24, T = 600, G = 64, L = 64 };
    static uint32_t targets[NSETS][3][T];
    static uint8_t payloads[NSETS][3][T * 28];
    static lbk_dls_set_desc sets[NSETS];
    static char names[NSETS][8];
    const uint32_t count[3] = {T, G, L};
    uint32_t rng = 12345;
    for (uint32_t s = 0; s < NSETS; s++) {
        snprintf(names[s], sizeof names[s], "s%u", s);
        sets[s].name = names[s];
        for (uint32_t sp = 0; sp < 3; sp++) {
            uint32_t n = 0;
            for (uint32_t t = 0; t < count[sp]; t++) {
                rng = rng * 1664525u + 1013904223u;
                const int wide = s == 0 && t < count[sp] / 2;              /* set 0 alone: dedicated */
                const int small = s < 8 && (rng >> 28) == s % 4 + 1;       /* scattered small combinations */
                const int deep = t >= count[sp] - 20 && (s < 6 + (count[sp] - t) % 3 * 7); /* 6, 13, 20 deep */
                if (!(wide || small || deep)) continue;
                targets[s][sp][n] = t;
                uint8_t *p = payloads[s][sp] + (size_t)n * (sp ? 28 : 8);
                for (uint32_t b = 0; b < (sp ? 28u : 8u); b++) p[b] = (uint8_t)(rng >> (b % 24));
                if (sp == 0) p[1] &= 0xfb, p[2] &= 0xdf, p[3] &= 0x7f; /* no exponent-31 channel in Ez (rule 850) */
                n++;
            }
            sets[s].entries[sp] = (lbk_dls_sparse){n, targets[s][sp], payloads[s][sp]};
        }
    }
    sets[1].kind = LBK_DLS_KIND_DOOR_OPEN;
    sets[2].kind = LBK_DLS_KIND_DOOR_CLOSED;
    static const uint32_t members[2] = {0, 1};
    sets[NSETS - 1].kind = LBK_DLS_KIND_COMBINATION, sets[NSETS - 1].member_count = 2, sets[NSETS - 1].members = members;
    lbk_dls_build_desc dd = {.set_count = NSETS, .sets = sets, .target_count = {T, G, L}};
    const lbk_door_desc door = {.name = "door", .axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, .half_extents = {1, 1, 0.1f},
                                .open_set = 1, .closed_set = 2};
    const uint32_t door0 = 0;
    const lbk_door_state_desc state = {1, &door0, NSETS - 1};
    const lbk_door_build_desc od = {.door_count = 1, .doors = &door, .state_count = 1, .states = &state};
    /* the spaces the sets light: a 30 × 20 page, a 4 × 4 × 4 GLG lattice cut into Kuhn tetrahedra
     * (6 per cube around its main diagonal, conforming across cubes) and a 4 × 4 × 4 LLG grid */
    static lbk_ahd_texel page[T];
    for (int i = 0; i < T; i++) page[i] = texel(i % 64);
    const lbk_lmap_page_desc pd = {30, 20, page};
    static float pos[G][3];
    static lbk_sh9_rgb sh[G];
    for (int i = 0; i < G; i++) {
        pos[i][0] = (float)(i & 3), pos[i][1] = (float)(i >> 2 & 3), pos[i][2] = (float)(i >> 4 & 3);
        probe_sh(i % 8, &sh[i]);
    }
    static uint32_t tets[27 * 6][4];
    static const int kuhn[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
    uint32_t nt = 0;
    for (int z = 0; z < 3; z++)
        for (int y = 0; y < 3; y++)
            for (int x = 0; x < 3; x++)
                for (int k = 0; k < 6; k++) {
                    const int c0 = x + 4 * y + 16 * z;
                    int c = c0, bits = 0;
                    tets[nt][0] = (uint32_t)c0;
                    for (int j = 0; j < 3; j++) {
                        bits |= kuhn[k][j];
                        c = c0 + (bits & 1) + 4 * (bits >> 1 & 1) + 16 * (bits >> 2 & 1);
                        tets[nt][j + 1] = (uint32_t)c;
                    }
                    nt++;
                }
    const lbk_glg_build_desc gd = {.probe_count = G, .tetra_count = nt, .positions = (const float (*)[3])pos, .probes = sh, .tetras = (const uint32_t (*)[4])tets};
    const lbk_llg_grid_desc grid = {{1.5f, 1.5f, 1.5f}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {2, 2, 2}, {4, 4, 4}, sh, NULL, 0};
    const lbk_object objs[2] = {{{"room", 4}, 1, LBK_REPRESENTATION_LIGHTMAP, 0, 0, 0, 30, 20},
                                {{"prop", 4}, 2, LBK_REPRESENTATION_LLG, 0, 0, 0, 0, 0}};
    const lbk_meta_pair meta = {"writer", "make_corpus"};
    section sec[7] = {{LBK_SECTION_LMAP, 0, 0}, {LBK_SECTION_GLG, 0, 0}, {LBK_SECTION_LLG, 0, 0}, {LBK_SECTION_DLS, 0, 0},
                      {LBK_SECTION_DOOR, 0, 0}, {LBK_SECTION_META, 0, 0}, {LBK_SECTION_OBJS, 0, 0}};
    int r = lbk_meta_build(&meta, 1, NULL, &sec[5].data, &sec[5].size) || lbk_objects_build(objs, 2, NULL, &sec[6].data, &sec[6].size) ||
            lbk_lmap_build(&(lbk_lmap_build_desc){.pages = &pd, .page_count = 1}, NULL, &sec[0].data, &sec[0].size) ||
            lbk_glg_build(&gd, NULL, &sec[1].data, &sec[1].size) ||
            lbk_llg_build(&(lbk_llg_build_desc){.grids = &grid, .grid_count = 1}, NULL, &sec[2].data, &sec[2].size) ||
            lbk_dls_build(&dd, NULL, &sec[3].data, &sec[3].size, NULL) || lbk_door_build(&od, NULL, &sec[4].data, &sec[4].size);
    if (r) fprintf(stderr, "make_corpus: dls.lbk: a section builder failed\n");
    else r = write_container("tests/fuzz/corpus/dls.lbk", sec, 7, 1);
    for (int i = 0; i < 7; i++) lbk_free(NULL, sec[i].data);
    return r;
}

int main(void)
{
    static lbk_ahd_texel texels[8 * 4];
    for (int i = 0; i < 8 * 4; i++) texels[i] = (lbk_ahd_texel){0x3c00u + (uint32_t)i, {200, 128, 128, 255}};
    lbk_lmap_page_desc pages[2] = {{8, 4, texels}, {4, 4, texels}};
    static lbk_sh9_rgb probes[8];
    for (int i = 0; i < 8; i++) probes[i].c[0][0] = probes[i].c[1][0] = probes[i].c[2][0] = 1.0f + (float)i;
    lbk_llg_vertex verts[3] = {{1, {0, 0, 1}}, {0.5f, {0, 1, 0}}, {0.25f, {1, 0, 0}}};
    lbk_llg_grid_desc grid = {{0, 1, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {1, 2, 1}, {2, 2, 2}, probes, verts, 3};
    const lbk_object objs[3] = {
        {{"floor", 5}, 11, LBK_REPRESENTATION_LIGHTMAP, 0, 0, 0, 8, 4},
        {{"wall", 4}, 12, LBK_REPRESENTATION_LIGHTMAP, 1, 0, 0, 4, 2},
        {{"chair", 5}, 13, LBK_REPRESENTATION_LLG, 0, 0, 0, 0, 0},
    };
    const lbk_meta_pair meta[2] = {{"writer", "make_corpus"}, {"writer.version", "1"}};
    const lbk_report_record rec[2] = {{0, 10, 1, 1, 0.5f, 0.5f}, {0, 20, 2, 1, 0.25f, 0.3f}};
    const lbk_report rep = {.status = LBK_BAKE_SAMPLE_LIMIT, .max_samples_per_texel = 2, .records = rec, .record_count = 2};
    section s[9] = {{LBK_SECTION_META, 0, 0}, {LBK_SECTION_REPT, 0, 0}, {LBK_SECTION_OBJS, 0, 0},
                    {LBK_SECTION_LMAP, 0, 0}, {LBK_SECTION_LLG, 0, 0},  {LBK_SECTION_GLG, 0, 0},
                    {LBK_SECTION_OCTP, 0, 0}, {LBK_SECTION_DLS, 0, 0},  {LBK_SECTION_DOOR, 0, 0}};
    if (lbk_meta_build(meta, 2, NULL, &s[0].data, &s[0].size) || lbk_report_build(&rep, NULL, &s[1].data, &s[1].size) ||
        lbk_objects_build(objs, 3, NULL, &s[2].data, &s[2].size) ||
        lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages, .page_count = 2}, NULL, &s[3].data, &s[3].size) ||
        lbk_llg_build(&(lbk_llg_build_desc){.grids = &grid, .grid_count = 1}, NULL, &s[4].data, &s[4].size) || build_glg(&s[5].data, &s[5].size) ||
        build_octp(&s[6].data, &s[6].size) || build_dls_door(&s[7].data, &s[7].size, &s[8].data, &s[8].size)) {
        fprintf(stderr, "make_corpus: a section builder failed\n");
        return 1;
    }
    int rc = write_container("tests/fuzz/corpus/objects_raw.lbk", s, 5, 0) ||
             write_container("tests/fuzz/corpus/objects_zstd.lbk", s, 5, 1) ||
             write_container("tests/fuzz/corpus/every_raw.lbk", s, 9, 0) ||
             write_container("tests/fuzz/corpus/every_zstd.lbk", s, 9, 1);
    for (int i = 0; i < 9; i++) lbk_free(NULL, s[i].data);
    section vol[2] = {{LBK_SECTION_META, 0, 0}, {LBK_SECTION_OCTP, 0, 0}};
    if (!rc && (lbk_meta_build(meta, 2, NULL, &vol[0].data, &vol[0].size) || build_octp_volume(&vol[1].data, &vol[1].size))) {
        fprintf(stderr, "make_corpus: the OCTP volume failed to build\n");
        rc = 1;
    }
    if (!rc) rc = write_container("tests/fuzz/corpus/octp_volume.lbk", vol, 2, 1);
    for (int i = 0; i < 2; i++) lbk_free(NULL, vol[i].data);
    if (rc) fprintf(stderr, "make_corpus: a container failed to build or validate\n");
    return rc || write_dls();
}
