/* lbk export's OCTP probe volume: per clip level an EXR atlas of the irradiance texels and one of
 * the depth moments (tools/convert/README.md "Export"). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/error_util.h"
#include "tools/common/image_io.h"
#include "tools/convert/export.h"

/* Level l's probe (x, y, z) is tile (x, y + dims1·z) of an atlas dims0 tiles wide and dims1·dims2
 * tall (z slices stacked downwards), each tile the probe's N×N interior (4: irradiance R,G,B in
 * lux; 12: depth m1, m2 in metres, m²). Inside probes (inactive) are 0. */
static int write_level(const tl_bake *b, const char *dir, uint32_t l, tl_export_stats *st, char err[TL_ERR_LEN])
{
    const lbk_octp_level *lv = &b->octp.levels[l];
    const uint32_t tw = lv->dims[0], th = lv->dims[1] * lv->dims[2];
    const size_t wi = (size_t)tw * 4, hi = (size_t)th * 4, wd = (size_t)tw * 12, hd = (size_t)th * 12;
    float *irr = calloc(wi * hi * 3 + 1, sizeof *irr), *dep = calloc(wd * hd * 2 + 1, sizeof *dep);
    lbk_octp_probe_desc *pd = malloc(sizeof *pd);
    int rc = irr && dep && pd ? 0 : tl_fail(err, -1, "out of memory");
    for (uint32_t k = 0; k < lv->dims[0] * lv->dims[1] * lv->dims[2] && !rc; k++) {
        if (lbk_octp_probe_get(&b->octp, lv->first_probe + k, pd) != LBK_OK) {
            rc = tl_fail(err, -1, "OCTP probe %u could not be read", lv->first_probe + k);
            break;
        }
        const uint32_t x = k % lv->dims[0], ty = k / lv->dims[0]; /* y + dims1·z */
        for (uint32_t j = 0; j < 4; j++)
            for (uint32_t i = 0; i < 4; i++)
                memcpy(irr + 3 * ((ty * 4 + j) * wi + x * 4 + i), pd->irradiance[j * 4 + i], 3 * sizeof(float));
        for (uint32_t j = 0; j < 12; j++)
            for (uint32_t i = 0; i < 12; i++)
                memcpy(dep + 2 * ((ty * 12 + j) * wd + x * 12 + i), pd->depth[j * 12 + i], 2 * sizeof(float));
    }
    static const char *const RGB[3] = {"R", "G", "B"}, *const M[2] = {"m1", "m2"};
    char path[4096];
    if (!rc) {
        snprintf(path, sizeof path, "%s/octp_level_%u.exr", dir, l);
        rc = tl_exr_write(path, (int)wi, (int)hi, 3, RGB, irr, err);
    }
    if (!rc) {
        snprintf(path, sizeof path, "%s/octp_level_%u.depth.exr", dir, l);
        rc = tl_exr_write(path, (int)wd, (int)hd, 2, M, dep, err);
    }
    if (!rc) st->exr_files += 2;
    free(irr), free(dep), free(pd);
    return rc;
}

int tl_export_octp(const tl_bake *b, const char *dir, tl_export_stats *st, char err[TL_ERR_LEN])
{
    if (!b->has_octp || !dir) return 0;
    for (uint32_t l = 0; l < b->octp.level_count; l++)
        if (write_level(b, dir, l, st, err)) return -1;
    return 0;
}
