/* Opening a container for the tools: validate once, then trust the section views. */
#include "tools/common/bake_data.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/file_util.h"
#include "tools/common/lmap_decode.h"
#include "lbk/validate.h"

#define S45 0.70710678118654752f
const float tl_texel_normals[TL_TEXEL_NORMALS][3] = {{0, 0, 1}, {S45, 0, S45}, {-S45, 0, S45}, {0, S45, S45}, {0, -S45, S45}};
const float tl_probe_normals[TL_PROBE_NORMALS][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

void tl_texel_eval(const lbk_ahd_texel *t, float scale, float out[TL_TEXEL_NORMALS][3])
{
    for (int n = 0; n < TL_TEXEL_NORMALS; n++) {
        lbk_ahd_irradiance(t, tl_texel_normals[n], out[n]);
        for (int c = 0; c < 3; c++) out[n][c] *= scale;
    }
}

void tl_probe_unpack(const uint8_t packed[LBK_SH9_PACKED_SIZE], float scale, lbk_sh9_rgb *sh)
{
    lbk_sh9_rgb stored;
    lbk_sh9_unpack(packed, &stored);
    memset(sh, 0, sizeof *sh);
    lbk_sh9_add_scaled(sh, &stored, scale);
}

void tl_probe_eval(const lbk_sh9_rgb *sh, float out[TL_PROBE_NORMALS][3])
{
    for (int n = 0; n < TL_PROBE_NORMALS; n++) lbk_sh9_irradiance(sh, tl_probe_normals[n], out[n]);
}

void tl_string_copy(char *dst, size_t size, lbk_string s)
{
    size_t n = s.size < size - 1 ? s.size : size - 1;
    memcpy(dst, s.data, n);
    dst[n] = '\0';
}

typedef struct first_issue {
    int have;
    lbk_issue issue;
} first_issue;

static int keep_first(void *user, const lbk_issue *issue)
{
    first_issue *f = user;
    if (!f->have && issue->severity != LBK_SEVERITY_WARNING) f->issue = *issue, f->have = 1;
    return 0;
}

/* Block-encoded pages are decoded once at open, so texel access stays cheap and const. */
static tl_open_status decode_block_pages(tl_bake *b, char err[TL_ERR_LEN])
{
    if (!b->has_lmap) return TL_OPEN_OK;
    b->block_pages = calloc(b->lmap.page_count + 1, sizeof *b->block_pages);
    if (!b->block_pages) {
        snprintf(err, TL_ERR_LEN, "out of memory");
        return TL_OPEN_INTERNAL;
    }
    for (uint32_t p = 0; p < b->lmap.page_count; p++) {
        lbk_lmap_planes pl;
        lbk_lmap_planes_get(&b->lmap, p, &pl);
        if (!pl.blocks_x) continue;
        b->block_pages[p] = malloc(sizeof **b->block_pages * (size_t)pl.width * pl.height);
        char e2[TL_ERR_LEN];
        if (!b->block_pages[p] || tl_lmap_page_decode(&pl, b->block_pages[p], e2, sizeof e2)) {
            snprintf(err, TL_ERR_LEN, "LMAP page %u: %.200s", p, b->block_pages[p] ? e2 : "out of memory");
            return TL_OPEN_INTERNAL;
        }
    }
    return TL_OPEN_OK;
}

int tl_bake_planes(const tl_bake *b, uint32_t page, lbk_lmap_planes *out)
{
    return b->has_lmap && lbk_lmap_planes_get(&b->lmap, page, out) == LBK_OK ? 0 : -1;
}

static void unit_direction(const float x, const float y, const float z, float d[3])
{
    const float len = sqrtf(x * x + y * y + z * z);
    if (!(len >= 0.5f)) d[0] = 0, d[1] = 0, d[2] = 1;
    else d[0] = x / len, d[1] = y / len, d[2] = z / len;
}

int tl_bake_texel_get(const tl_bake *b, uint32_t page, uint32_t x, uint32_t y, lbk_ahd_texel_f *texel,
                      lbk_ahd_linear *linear, float dir[3])
{
    lbk_lmap_planes pl;
    if (tl_bake_planes(b, page, &pl) || x >= pl.width || y >= pl.height) return -1;
    const size_t i = (size_t)y * pl.width + x;
    if (!b->block_pages[page]) {
        const uint8_t *z = pl.plane[0] + 4 * i;
        lbk_ahd_texel t = {(uint32_t)z[0] | (uint32_t)z[1] << 8 | (uint32_t)z[2] << 16 | (uint32_t)z[3] << 24, {0}};
        memcpy(t.rgba, pl.plane[1] + 4 * i, 4);
        if (texel) lbk_ahd_texel_f_from_texel(&t, texel);
        if (linear) lbk_ahd_to_linear(&t, linear);
        if (dir) unit_direction(2.0f * t.rgba[1] / 255.0f - 1.0f, 2.0f * t.rgba[2] / 255.0f - 1.0f, t.rgba[3] / 255.0f, dir);
        return 0;
    }
    const lbk_ahd_texel_f *tf = &b->block_pages[page][i];
    if (texel) *texel = *tf;
    if (linear) lbk_ahd_texel_f_to_linear(tf, linear);
    if (dir) unit_direction(2.0f * tf->rgba[1] - 1.0f, 2.0f * tf->rgba[2] - 1.0f, tf->rgba[3], dir);
    return 0;
}

int tl_bake_texel_eval(const tl_bake *b, uint32_t page, uint32_t x, uint32_t y, float out[TL_TEXEL_NORMALS][3])
{
    lbk_lmap_planes pl;
    if (tl_bake_planes(b, page, &pl) || x >= pl.width || y >= pl.height) return -1;
    if (!b->block_pages[page]) {
        const size_t i = (size_t)y * pl.width + x;
        const uint8_t *z = pl.plane[0] + 4 * i;
        lbk_ahd_texel t = {(uint32_t)z[0] | (uint32_t)z[1] << 8 | (uint32_t)z[2] << 16 | (uint32_t)z[3] << 24, {0}};
        memcpy(t.rgba, pl.plane[1] + 4 * i, 4);
        tl_texel_eval(&t, pl.scale, out);
        return 0;
    }
    lbk_ahd_linear lin;
    lbk_ahd_texel_f_to_linear(&b->block_pages[page][(size_t)y * pl.width + x], &lin);
    for (int n = 0; n < TL_TEXEL_NORMALS; n++) {
        lbk_ahd_linear_eval(&lin, tl_texel_normals[n], out[n]);
        for (int c = 0; c < 3; c++) out[n][c] *= pl.scale;
    }
    return 0;
}

static tl_open_status open_views(tl_bake *b, uint64_t max_decoded_bytes, char err[TL_ERR_LEN])
{
    first_issue f = {0};
    lbk_validate_summary sum = {0};
    lbk_read_options ro = LBK_READ_OPTIONS_INIT;
    ro.max_decoded_bytes = max_decoded_bytes;
    lbk_validate_options vo = LBK_VALIDATE_OPTIONS_INIT;
    vo.max_decoded_bytes = max_decoded_bytes;
    /* open first, then validate through the reader: every section is checksummed and decoded
     * once, and the views below use those bytes */
    lbk_result r = lbk_reader_open_memory(b->bytes, b->size, &ro, &b->reader);
    if (r == LBK_OK) r = lbk_reader_validate(b->reader, keep_first, &f, &sum);
    else if (r != LBK_ERR_OUT_OF_MEMORY) r = lbk_validate_memory(b->bytes, b->size, &vo, keep_first, &f, &sum);
    if (r == LBK_ERR_LIMIT) {
        snprintf(err, TL_ERR_LEN, "its sections would decode to more than the memory cap (%llu bytes; --max-memory)",
                 (unsigned long long)max_decoded_bytes);
        return TL_OPEN_INVALID;
    }
    if (r != LBK_OK) {
        snprintf(err, TL_ERR_LEN, "validation could not run: %s", lbk_result_message(r));
        return TL_OPEN_INTERNAL;
    }
    if (sum.fatal || sum.errors || !b->reader) {
        snprintf(err, TL_ERR_LEN, "not a valid container (%u errors; first #%u at byte %llu: %s); run lbk validate",
                 sum.fatal + sum.errors, f.issue.id, (unsigned long long)f.issue.offset, f.issue.message);
        return TL_OPEN_INVALID;
    }
    const void *d;
    size_t n;
#define VIEW(type, flag, call)                                                                        \
    if (lbk_reader_section_by_type(b->reader, type, &d, &n) == LBK_OK) {                             \
        if ((r = (call)) != LBK_OK) {                                                                 \
            char t_[5];                                                                               \
            lbk_fourcc_string(type, t_);                                                              \
            snprintf(err, TL_ERR_LEN, "section %s: %s", t_, lbk_result_message(r));                   \
            return TL_OPEN_INVALID;                                                                   \
        }                                                                                             \
        flag = 1;                                                                                     \
    }
    int dls = 0, door = 0;
    (void)dls;
    (void)door;
    VIEW(LBK_SECTION_META, b->has_meta, lbk_meta_open(d, n, &b->meta));
    VIEW(LBK_SECTION_OBJS, b->has_objs, lbk_objects_open(d, n, &b->objs));
    VIEW(LBK_SECTION_LMAP, b->has_lmap, lbk_lmap_open(d, n, &b->lmap));
    VIEW(LBK_SECTION_GLG, b->has_glg, lbk_glg_open(d, n, &b->glg));
    VIEW(LBK_SECTION_LLG, b->has_llg, lbk_llg_open(d, n, &b->llg));
    VIEW(LBK_SECTION_OCTP, b->has_octp, lbk_octp_open(d, n, &b->octp));
    VIEW(LBK_SECTION_LMUV, b->has_lmuv, lbk_lmuv_open(d, n, &b->lmuv));
    VIEW(LBK_SECTION_REPT, b->has_rept, lbk_report_open(d, n, &b->rept));
    VIEW(LBK_SECTION_TERR, b->has_terr, lbk_terr_open(d, n, &b->terr));
    if (b->has_rept && lbk_report_record_get(&b->rept, b->rept.header.record_count - 1, &b->rept_last) != LBK_OK)
        b->has_rept = 0;
    VIEW(LBK_SECTION_DLS, dls, lbk_dls_open(d, n, NULL, &b->dls));
    VIEW(LBK_SECTION_DOOR, door, lbk_door_open(d, n, NULL, &b->door));
#undef VIEW
    return decode_block_pages(b, err);
}

tl_open_status tl_bake_open_memory(const void *data, size_t size, tl_bake *b, char err[TL_ERR_LEN])
{
    memset(b, 0, sizeof *b);
    b->bytes = malloc(size ? size : 1);
    if (!b->bytes) {
        snprintf(err, TL_ERR_LEN, "out of memory");
        return TL_OPEN_INTERNAL;
    }
    memcpy(b->bytes, data, size);
    b->size = size;
    tl_open_status st = open_views(b, 0, err);
    if (st != TL_OPEN_OK) tl_bake_close(b);
    return st;
}

tl_open_status tl_bake_open_file(const char *path, tl_bake *b, char err[TL_ERR_LEN])
{
    return tl_bake_open_file_capped(path, 0, b, err);
}

tl_open_status tl_bake_open_file_capped(const char *path, uint64_t max_decoded_bytes, tl_bake *b, char err[TL_ERR_LEN])
{
    memset(b, 0, sizeof *b);
    char e2[TL_ERR_LEN];
    if (tl_read_file(path, &b->bytes, &b->size, e2)) {
        snprintf(err, TL_ERR_LEN, "%s", e2);
        return TL_OPEN_IO;
    }
    tl_open_status st = open_views(b, max_decoded_bytes, e2);
    if (st != TL_OPEN_OK) {
        snprintf(err, TL_ERR_LEN, "%.80s: %.170s", path, e2);
        tl_bake_close(b);
    }
    return st;
}

void tl_bake_close(tl_bake *b)
{
    for (uint32_t p = 0; b->block_pages && p < b->lmap.page_count; p++) free(b->block_pages[p]);
    free(b->block_pages);
    if (b->door) lbk_door_close(b->door);
    if (b->dls) lbk_dls_close(b->dls);
    if (b->reader) lbk_reader_close(b->reader);
    free(b->bytes);
    memset(b, 0, sizeof *b);
}
