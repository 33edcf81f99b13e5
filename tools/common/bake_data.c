/* Opening a container for the tools: validate once, then trust the section views. */
#include "tools/common/bake_data.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/file_util.h"
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

static tl_open_status open_views(tl_bake *b, char err[TL_ERR_LEN])
{
    first_issue f = {0};
    lbk_validate_summary sum = {0};
    lbk_result r = lbk_validate_memory(b->bytes, b->size, NULL, keep_first, &f, &sum);
    if (r != LBK_OK) {
        snprintf(err, TL_ERR_LEN, "validation could not run: %s", lbk_result_message(r));
        return TL_OPEN_INTERNAL;
    }
    if (sum.fatal || sum.errors) {
        snprintf(err, TL_ERR_LEN, "not a valid container (%u errors; first #%u at byte %llu: %s); run lbk validate",
                 sum.fatal + sum.errors, f.issue.id, (unsigned long long)f.issue.offset, f.issue.message);
        return TL_OPEN_INVALID;
    }
    r = lbk_reader_open_memory(b->bytes, b->size, NULL, &b->reader);
    if (r != LBK_OK) {
        snprintf(err, TL_ERR_LEN, "%s", lbk_result_message(r));
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
    VIEW(LBK_SECTION_DLS, dls, lbk_dls_open(d, n, NULL, &b->dls));
    VIEW(LBK_SECTION_DOOR, door, lbk_door_open(d, n, NULL, &b->door));
#undef VIEW
    return TL_OPEN_OK;
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
    tl_open_status st = open_views(b, err);
    if (st != TL_OPEN_OK) tl_bake_close(b);
    return st;
}

tl_open_status tl_bake_open_file(const char *path, tl_bake *b, char err[TL_ERR_LEN])
{
    memset(b, 0, sizeof *b);
    char e2[TL_ERR_LEN];
    if (tl_read_file(path, &b->bytes, &b->size, e2)) {
        snprintf(err, TL_ERR_LEN, "%s", e2);
        return TL_OPEN_IO;
    }
    tl_open_status st = open_views(b, e2);
    if (st != TL_OPEN_OK) {
        snprintf(err, TL_ERR_LEN, "%.80s: %.170s", path, e2);
        tl_bake_close(b);
    }
    return st;
}

void tl_bake_close(tl_bake *b)
{
    if (b->door) lbk_door_close(b->door);
    if (b->dls) lbk_dls_close(b->dls);
    if (b->reader) lbk_reader_close(b->reader);
    free(b->bytes);
    memset(b, 0, sizeof *b);
}
