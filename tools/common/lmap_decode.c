/* Page decoding for the tools (lmap_decode.h). */
#include "tools/common/lmap_decode.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/astc_codec.h"
#include "lbk/bc.h"
#include "lbk/pixel.h"

static const char *const names0[] = {"r11g11b10f", "bc6h", "astc4x4_hdr"};
static const char *const names1[] = {"rgba8", "bc5_bc4", "astc4x4"};

const char *tl_lmap_format_name(int plane, uint32_t format)
{
    if (plane == 0) return format < 3 ? names0[format] : NULL;
    return format < 3 ? names1[format] : NULL;
}

int tl_lmap_format_parse(int plane, const char *name)
{
    for (int i = 0; i < 3; i++)
        if (!strcmp(name, plane == 0 ? names0[i] : names1[i])) return i;
    return -1;
}

static int plane0(const lbk_lmap_planes *pl, lbk_ahd_texel_f *out, float *buf, char *err, size_t err_len)
{
    const uint32_t w = pl->width, h = pl->height;
    if (pl->format[0] == LBK_LMAP_R11G11B10F) {
        for (size_t i = 0; i < (size_t)w * h; i++) {
            const uint8_t *b = pl->plane[0] + 4 * i;
            lbk_ahd_texel t = {(uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24, {0}};
            lbk_ahd_texel_f f;
            lbk_ahd_texel_f_from_texel(&t, &f);
            memcpy(out[i].ez, f.ez, sizeof f.ez);
        }
        return 0;
    }
    if (pl->format[0] == LBK_LMAP_BC6H) {
        for (uint32_t by = 0; by < h / 4; by++)
            for (uint32_t bx = 0; bx < w / 4; bx++) {
                uint16_t hv[16][3];
                lbk_bc6h_unpack(pl->plane[0] + 16 * ((size_t)by * (w / 4) + bx), hv);
                for (int k = 0; k < 16; k++)
                    for (int c = 0; c < 3; c++)
                        out[(size_t)(4 * by + (uint32_t)k / 4) * w + 4 * bx + (uint32_t)k % 4].ez[c] = lbk_half_to_float(hv[k][c]);
            }
        return 0;
    }
    if (tl_astc_decode(pl->plane[0], (size_t)pl->bytes[0], w, h, 1, buf, err, err_len)) return -1;
    for (size_t i = 0; i < (size_t)w * h; i++) memcpy(out[i].ez, buf + 4 * i, sizeof out[i].ez);
    return 0;
}

static int plane1(const lbk_lmap_planes *pl, lbk_ahd_texel_f *out, float *buf, char *err, size_t err_len)
{
    const uint32_t w = pl->width, h = pl->height;
    if (pl->format[1] == LBK_LMAP_RGBA8) {
        for (size_t i = 0; i < (size_t)w * h; i++)
            for (int k = 0; k < 4; k++) out[i].rgba[k] = lbk_unorm8_to_float(pl->plane[1][4 * i + (size_t)k]);
        return 0;
    }
    if (pl->format[1] == LBK_LMAP_BC5_BC4) {
        const size_t nb = (size_t)(w / 4) * (h / 4);
        for (uint32_t by = 0; by < h / 4; by++)
            for (uint32_t bx = 0; bx < w / 4; bx++) {
                const size_t b = (size_t)by * (w / 4) + bx;
                float d[16][2], r[16];
                lbk_bc5_unpack(pl->plane[1] + 16 * b, d);
                lbk_bc4_unpack(pl->plane[1] + 16 * nb + 8 * b, r);
                for (int k = 0; k < 16; k++) {
                    float *o = out[(size_t)(4 * by + (uint32_t)k / 4) * w + 4 * bx + (uint32_t)k % 4].rgba;
                    const float dx = 2 * d[k][0] - 1, dy = 2 * d[k][1] - 1, zz = 1 - dx * dx - dy * dy;
                    o[0] = r[k], o[1] = d[k][0], o[2] = d[k][1], o[3] = zz > 0 ? sqrtf(zz) : 0;
                }
            }
        return 0;
    }
    if (tl_astc_decode(pl->plane[1], (size_t)pl->bytes[1], w, h, 0, buf, err, err_len)) return -1;
    for (size_t i = 0; i < (size_t)w * h; i++) memcpy(out[i].rgba, buf + 4 * i, sizeof out[i].rgba);
    return 0;
}

int tl_lmap_page_decode(const lbk_lmap_planes *pl, lbk_ahd_texel_f *out, char *err, size_t err_len)
{
    const int astc = pl->format[0] == LBK_LMAP_ASTC4X4_HDR || pl->format[1] == LBK_LMAP_ASTC4X4_LDR;
    float *buf = astc ? malloc(sizeof *buf * 4 * (size_t)pl->width * pl->height) : NULL;
    if (astc && !buf) {
        snprintf(err, err_len, "out of memory");
        return -1;
    }
    const int rc = plane0(pl, out, buf, err, err_len) || plane1(pl, out, buf, err, err_len) ? -1 : 0;
    free(buf);
    return rc;
}
