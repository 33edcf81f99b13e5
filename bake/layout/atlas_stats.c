/* Atlas fill and chart statistics (see atlas_stats.h). */
#include "bake/layout/atlas_stats.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/uv_raster.h"

/* Marks in cov (the chart's content rectangle plus one texel around, cw × chh, origin
 * (ox, oy) in page texels) the texels the chart's triangles overlap; returns how many. */
static size_t chart_coverage(const bk_atlas *a, const bk_atlas_chart *ch, uint8_t *cov, int ox, int oy, int cw,
                             int chh)
{
    size_t n = 0;
    memset(cov, 0, (size_t)cw * (size_t)chh);
    for (uint32_t e = ch->first; e < ch->first + ch->count; e++) {
        bk_rtri t;
        if (!bk_rtri_setup(a->tri_uv + 6 * (size_t)e, &t)) continue;
        double mnx = fmin(t.x[0], fmin(t.x[1], t.x[2])), mxx = fmax(t.x[0], fmax(t.x[1], t.x[2]));
        double mny = fmin(t.y[0], fmin(t.y[1], t.y[2])), mxy = fmax(t.y[0], fmax(t.y[1], t.y[2]));
        int x0 = (int)floor(mnx) - 1, x1 = (int)floor(mxx) + 1, y0 = (int)floor(mny) - 1, y1 = (int)floor(mxy) + 1;
        if (x0 < ox) x0 = ox;
        if (y0 < oy) y0 = oy;
        if (x1 >= ox + cw) x1 = ox + cw - 1;
        if (y1 >= oy + chh) y1 = oy + chh - 1;
        for (int y = y0; y <= y1; y++)
            for (int x = x0; x <= x1; x++) {
                uint8_t *c = &cov[(size_t)(y - oy) * (size_t)cw + (size_t)(x - ox)];
                if (*c) continue;
                double cx = x + 0.5, cy = y + 0.5, qx, qy;
                if (!bk_rtri_inside(&t, cx, cy, NULL)) {
                    bk_rtri_closest(&t, cx, cy, NULL, &qx, &qy);
                    if (!(fabs(qx - cx) < 0.5 && fabs(qy - cy) < 0.5)) continue;
                }
                *c = 1;
                n++;
            }
    }
    return n;
}

lbk_result bk_atlas_stats_compute(const bk_atlas *a, bk_atlas_stats *out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!a) return LBK_ERR_INVALID_ARGUMENT;
    for (size_t p = 0; p < a->page_count; p++)
        out->page_texels += (uint64_t)a->pages[p].width * (uint64_t)a->pages[p].height;
    for (size_t o = 0; o < a->object_count; o++)
        if (a->objects[o].page >= 0) out->rect_texels += (uint64_t)a->objects[o].w * (uint64_t)a->objects[o].h;
    size_t cap = 0;
    for (size_t c = 0; c < a->chart_count; c++) {
        size_t need = (size_t)(a->charts[c].w + 2) * (size_t)(a->charts[c].h + 2);
        if (need > cap) cap = need;
    }
    uint8_t *cov = malloc(cap ? cap : 1);
    if (!cov) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t c = 0; c < a->chart_count; c++) {
        const bk_atlas_chart *ch = &a->charts[c];
        if (ch->page < 0) continue;
        out->charts++;
        out->rotated_charts += (ch->quarter_turns & 1) != 0;
        out->block_texels += (uint64_t)(ch->w + 2 * a->margin) * (uint64_t)(ch->h + 2 * a->margin);
        size_t n = chart_coverage(a, ch, cov, ch->x - 1, ch->y - 1, ch->w + 2, ch->h + 2);
        out->covered_texels += n;
        out->tiny_charts += n <= 3;
    }
    free(cov);
    out->fill = out->page_texels ? (double)out->covered_texels / (double)out->page_texels : 0.0;
    out->fill_rects = out->rect_texels ? (double)out->covered_texels / (double)out->rect_texels : 0.0;
    return LBK_OK;
}
