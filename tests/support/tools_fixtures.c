/* Synthetic containers for the tools tests (see tools_fixtures.h). */
#include "tools_fixtures.h"

#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/octa.h"
#include "lbk/pixel.h"
#include "lbk/report.h"

#define CHECK(x)                                                                                     \
    do {                                                                                             \
        lbk_result r_ = (x);                                                                         \
        if (r_ != LBK_OK) {                                                                          \
            fprintf(stderr, "tools_fixtures: %s failed: %s\n", #x, lbk_result_name(r_));             \
            abort();                                                                                 \
        }                                                                                            \
    } while (0)

const float tf_probe_positions[8][3] = {{0, 0, 0}, {4, 0, 0}, {0, 2, 0}, {4, 2, 0},
                                        {0, 0, 3}, {4, 0, 3}, {0, 2, 3}, {4, 2, 3}};

void tf_texel_linear(uint32_t page, uint32_t x, uint32_t y, lbk_ahd_linear *out)
{
    memset(out, 0, sizeof *out);
    /* smooth, positive, with a directional part that leans toward +x */
    const float base = 0.5f + 0.02f * (float)x + 0.03f * (float)y + 0.7f * (float)page;
    const float amb[3] = {base, 0.8f * base, 0.6f * base};
    lbk_ahd_linear_add_ambient(out, amb);
    const float dir[3] = {0.6f, 0.0f, 0.8f};
    const float light[3] = {2.0f, 1.8f, 1.5f};
    lbk_ahd_linear_add_light(out, dir, light);
}

void tf_probe_sh(uint32_t probe, lbk_sh9_rgb *out)
{
    memset(out, 0, sizeof *out);
    for (int c = 0; c < 3; c++) {
        out->c[c][0] = 1.0f + 0.25f * (float)probe + 0.1f * (float)c;
        out->c[c][1] = 0.1f * out->c[c][0];
        out->c[c][2] = 0.3f * out->c[c][0];
        out->c[c][3] = -0.05f * out->c[c][0];
        out->c[c][6] = 0.02f * out->c[c][0];
    }
}

float tf_octp_irradiance(uint32_t p, uint32_t t, int c)
{
    return (0.5f + 0.125f * (float)(p % 5) + 0.0625f * (float)t) * (1.0f - 0.25f * (float)c);
}

static void add_octp(lbk_writer *w, const tf_options *opt)
{
    const uint32_t n = opt->octp_dims * 4;
    lbk_octp_probe_desc *pr = calloc(n, sizeof *pr);
    lbk_octp_probe_info *info = calloc(n, sizeof *info);
    if (!pr || !info) abort();
    for (uint32_t p = 0; p < n; p++) {
        const float f = p == opt->octp_probe && opt->octp_factor != 0.0f ? opt->octp_factor : 1.0f;
        for (uint32_t t = 0; t < 16; t++)
            for (int c = 0; c < 3; c++) pr[p].irradiance[t][c] = f * tf_octp_irradiance(p, t, c);
        for (uint32_t t = 0; t < 144; t++) {
            const float m = 1.0f + (float)(t % 64) / 256.0f + (p == opt->octp_probe ? opt->octp_depth_delta : 0.0f);
            pr[p].depth[t][0] = m;
            pr[p].depth[t][1] = m * m;
        }
        info[p].state = opt->octp_inside == p + 1 ? LBK_OCTP_INSIDE : LBK_OCTP_ACTIVE;
        info[p].rays = 64;
        info[p].nearest = 1.0f;
    }
    lbk_octp_level lv;
    memset(&lv, 0, sizeof lv);
    lv.spacing = 1.0f;
    lv.dims[0] = opt->octp_dims, lv.dims[1] = 2, lv.dims[2] = 2;
    lv.miss_distance = 10.0f;
    lbk_octp_build_desc d = LBK_OCTP_BUILD_DESC_INIT;
    d.probes = pr;
    d.probe_count = n;
    d.levels = &lv;
    d.level_count = 1;
    d.info = info;
    void *data;
    size_t size;
    CHECK(lbk_octp_build(&d, NULL, &data, &size));
    lbk_section_options so = {0};
    CHECK(lbk_writer_section_add(w, LBK_SECTION_OCTP, data, size, &so));
    lbk_free(NULL, data);
    free(pr);
    free(info);
}

void tf_blob_free(tf_blob *b)
{
    lbk_free(NULL, b->data);
    b->data = NULL;
    b->size = 0;
}

static void add(lbk_writer *w, uint32_t type, void *data, size_t size, uint32_t flags)
{
    lbk_section_options so = {0};
    so.flags = flags;
    CHECK(lbk_writer_section_add(w, type, data, size, &so));
    lbk_free(NULL, data);
}

/* META and REPT of the full scene. */
static void add_meta_rept(lbk_writer *w, const tf_options *opt)
{
    void *data;
    size_t size;
    char samples[16], hash[17];
    snprintf(samples, sizeof samples, "%u", opt->samples ? opt->samples : 64u);
    lbk_meta_hash_hex(0x0123456789abcdefull, hash);
    const lbk_meta_pair meta[] = {{LBK_META_WRITER, "lbk-test"},
                                  {LBK_META_WRITER_VERSION, "1.0.0"},
                                  {LBK_META_SCENE_HASH, hash},
                                  {"bake.samples", samples}};
    CHECK(lbk_meta_build(meta, 4, NULL, &data, &size));
    add(w, LBK_SECTION_META, data, size, 0);

    const lbk_report_record recs[2] = {{0, 1000, 16, 2, 0.2f, 0.3f}, {0, 4000, 64, 2, 0.1f, 0.15f}};
    lbk_report rep = {0};
    rep.status = LBK_BAKE_SAMPLE_LIMIT;
    rep.max_samples_per_texel = 64;
    rep.records = recs;
    rep.record_count = 2;
    CHECK(lbk_report_build(&rep, NULL, &data, &size));
    add(w, LBK_SECTION_REPT, data, size, 0);
}

/* OBJS: floor, wall and crate lightmapped, the lamp shade unlit. */
static void add_objects(lbk_writer *w, const tf_options *opt)
{
    void *data;
    size_t size;
    lbk_object objs[4];
    uint32_t nobj = 0;
    const uint32_t w0 = opt->page0_width ? opt->page0_width : 64;
    const char *wall = opt->rename_wall ? "wall-renamed" : "wall";
    lbk_object o;
    memset(&o, 0, sizeof o);
    o.name = (lbk_string){"floor", 5};
    o.geometry_hash = 0x1111;
    o.representation = LBK_REPRESENTATION_LIGHTMAP;
    o.index = 0, o.rect_x = 0, o.rect_y = 0, o.rect_w = 32, o.rect_h = 32;
    objs[nobj++] = o;
    o.name = (lbk_string){wall, strlen(wall)};
    o.geometry_hash = 0x2222;
    o.rect_x = 32, o.rect_y = 0, o.rect_w = w0 - 32, o.rect_h = 16;
    objs[nobj++] = o;
    if (!opt->drop_crate) {
        o.name = (lbk_string){"crate", 5};
        o.geometry_hash = opt->move_crate_geometry ? 0x3334 : 0x3333;
        o.index = 1, o.rect_x = 0, o.rect_y = 0, o.rect_w = 16, o.rect_h = 16;
        objs[nobj++] = o;
    }
    memset(&o, 0, sizeof o);
    o.name = (lbk_string){"lamp-shade", 10};
    o.geometry_hash = 0x4444;
    o.representation = LBK_REPRESENTATION_NONE;
    objs[nobj++] = o;
    CHECK(lbk_objects_build(objs, nobj, NULL, &data, &size));
    add(w, LBK_SECTION_OBJS, data, size, LBK_SECTION_FLAG_REQUIRED);
}

/* LMAP: two pages of tf_texel_linear, one texel changed as opt asks. */
static void add_pages(lbk_writer *w, const tf_options *opt)
{
    void *data;
    size_t size;
    const uint32_t w0 = opt->page0_width ? opt->page0_width : 64;
    const uint32_t pw[2] = {w0, 16}, ph[2] = {32, 16};
    lbk_ahd_texel *tex[2];
    lbk_lmap_page_desc pages[2];
    for (uint32_t p = 0; p < 2; p++) {
        tex[p] = calloc((size_t)pw[p] * ph[p], sizeof(lbk_ahd_texel));
        for (uint32_t y = 0; y < ph[p]; y++)
            for (uint32_t x = 0; x < pw[p]; x++) {
                lbk_ahd_linear lin, stored;
                tf_texel_linear(p, x, y, &lin);
                memset(&stored, 0, sizeof stored);
                lbk_ahd_linear_add_scaled(&stored, &lin, ldexpf(1.0f, -opt->scale_log2));
                lin = stored;
                lbk_ahd_texel *t = &tex[p][(size_t)y * pw[p] + x];
                lbk_ahd_from_linear(&lin, t);
                if (p == opt->texel_page && x == opt->texel_x && y == opt->texel_y) {
                    float rgb[3];
                    lbk_r11g11b10f_unpack(t->irradiance_z, rgb);
                    for (int c = 0; c < 3; c++) {
                        if (opt->texel_factor != 0.0f) rgb[c] *= opt->texel_factor;
                        rgb[c] += opt->texel_delta;
                    }
                    t->irradiance_z = lbk_r11g11b10f_pack(rgb);
                }
            }
        pages[p] = (lbk_lmap_page_desc){pw[p], ph[p], tex[p]};
    }
    const lbk_lmap_build_desc lb = {.pages = pages, .page_count = 2, .scale = ldexpf(1.0f, opt->scale_log2)};
    CHECK(lbk_lmap_build(&lb, NULL, &data, &size));
    add(w, LBK_SECTION_LMAP, data, size, LBK_SECTION_FLAG_REQUIRED);
    free(tex[0]);
    free(tex[1]);
}

/* GLG: 8 probes, 5 tetrahedra. */
static void add_glg(lbk_writer *w, const tf_options *opt)
{
    void *data;
    size_t size;
    lbk_sh9_rgb sh[8];
    for (uint32_t i = 0; i < 8; i++) {
        tf_probe_sh(i, &sh[i]);
        if (i == 3 && opt->probe_scale != 0.0f)
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 9; k++) sh[i].c[c][k] *= opt->probe_scale;
    }
    static const uint32_t tetras[5][4] = {{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}};
    lbk_glg_build_desc g = {0};
    g.probe_count = 8;
    g.tetra_count = 5;
    g.positions = tf_probe_positions;
    g.probes = sh;
    g.tetras = tetras;
    g.scale = ldexpf(1.0f, opt->scale_log2);
    CHECK(lbk_glg_build(&g, NULL, &data, &size));
    add(w, LBK_SECTION_GLG, data, size, 0);
}

/* DLS: one dynamic light set over the crate's texels (page 1, after page 0's page0_texels) and
 * two probes; texel_count targets in all. */
static void add_dls(lbk_writer *w, const tf_options *opt, uint64_t page0_texels, uint64_t texel_count)
{
    void *data;
    size_t size;
        const uint32_t ntex = 16 * 16;
    uint32_t *targets = malloc(ntex * sizeof *targets);
    uint8_t *payload = malloc((size_t)ntex * LBK_DLS_TEXEL_PAYLOAD);
    for (uint32_t i = 0; i < ntex; i++) {
        targets[i] = (uint32_t)page0_texels + i;
        lbk_ahd_linear lin;
        memset(&lin, 0, sizeof lin);
        const float up[3] = {0, 0, 1}, c[3] = {0.5f, 0.4f, 0.1f * (float)(i % 7)};
        lbk_ahd_linear_add_light(&lin, up, c);
        for (int ch = 0; ch < 3; ch++)
            for (int k = 0; k < 4; k++) lin.c[ch][k] = ldexpf(lin.c[ch][k], -opt->scale_log2);
        lbk_ahd_texel t;
        lbk_ahd_from_linear(&lin, &t);
        lbk_ahd_texel_pack(&t, payload + (size_t)i * LBK_DLS_TEXEL_PAYLOAD);
    }
    const uint32_t ptargets[2] = {0, 7};
    uint8_t ppay[2 * LBK_DLS_PROBE_PAYLOAD];
    for (int i = 0; i < 2; i++) {
        lbk_sh9_rgb s;
        tf_probe_sh(10 + (uint32_t)i, &s);
        for (int ch = 0; ch < 3; ch++)
            for (int k = 0; k < 9; k++) s.c[ch][k] = ldexpf(s.c[ch][k], -opt->scale_log2);
        lbk_sh9_pack(&s, ppay + i * LBK_DLS_PROBE_PAYLOAD);
    }
    const char *lights[] = {"lamp.bulb"};
    lbk_dls_set_desc set;
    memset(&set, 0, sizeof set);
    set.name = "lamp";
    set.kind = LBK_DLS_KIND_LIGHTS;
    set.light_count = 1;
    set.light_names = lights;
    set.entries[LBK_DLS_SPACE_TEXEL] = (lbk_dls_sparse){ntex, targets, payload};
    set.entries[LBK_DLS_SPACE_GLG] = (lbk_dls_sparse){2, ptargets, ppay};
    lbk_dls_build_desc bd;
    memset(&bd, 0, sizeof bd);
    bd.set_count = 1;
    bd.sets = &set;
    bd.target_count[LBK_DLS_SPACE_TEXEL] = texel_count;
    bd.target_count[LBK_DLS_SPACE_GLG] = 8;
    CHECK(lbk_dls_build(&bd, NULL, &data, &size, NULL));
    add(w, LBK_SECTION_DLS, data, size, 0);
    free(targets);
    free(payload);
}

tf_blob tf_build_scene(int kind, const tf_options *opt_in)
{
    tf_options opt;
    memset(&opt, 0, sizeof opt);
    if (opt_in) opt = *opt_in;
    lbk_writer *w = NULL;
    CHECK(lbk_writer_open(NULL, &w));
    if (kind == TF_SCENE_FULL) add_meta_rept(w, &opt);
    add_objects(w, &opt);
    add_pages(w, &opt);
    const uint64_t page0_texels = (uint64_t)(opt.page0_width ? opt.page0_width : 64) * 32;
    const uint64_t texel_count = page0_texels + 16 * 16;
    if (kind == TF_SCENE_FULL) {
        add_glg(w, &opt);
        add_dls(w, &opt, page0_texels, texel_count);
    }
    if (opt.octp_dims) add_octp(w, &opt);

    tf_blob b = {NULL, 0};
    CHECK(lbk_writer_to_memory(w, &b.data, &b.size));
    lbk_writer_close(w);
    return b;
}
