/* Chart maps of lightmap pages (charts.h). */
#include "tools/convert/charts.h"

#include <math.h>
#include <stdlib.h>

/* Marks with `id` the texels of page map m (w × h) whose centre lies in triangle a, b, c
 * (lightmap coordinates in texels; either winding). */
static void raster_triangle(int32_t *m, uint32_t w, uint32_t h, const float a[2], const float b[2], const float c[2],
                            int32_t id)
{
    const double area = (double)(b[0] - a[0]) * (c[1] - a[1]) - (double)(b[1] - a[1]) * (c[0] - a[0]);
    if (!(fabs(area) > 0)) return;
    const double x0 = fmin(a[0], fmin(b[0], c[0])), x1 = fmax(a[0], fmax(b[0], c[0]));
    const double y0 = fmin(a[1], fmin(b[1], c[1])), y1 = fmax(a[1], fmax(b[1], c[1]));
    const long tx0 = lround(fmax(0, floor(x0))), ty0 = lround(fmax(0, floor(y0)));
    const long tx1 = lround(fmin((double)w - 1, ceil(x1))), ty1 = lround(fmin((double)h - 1, ceil(y1)));
    const float *v[3] = {a, b, c};
    for (long y = ty0; y <= ty1; y++)
        for (long x = tx0; x <= tx1; x++) {
            const double px = (double)x + 0.5, py = (double)y + 0.5;
            int inside = 1;
            for (int k = 0; k < 3 && inside; k++) {
                const float *p0 = v[k], *p1 = v[(k + 1) % 3];
                const double e = ((double)p1[0] - p0[0]) * (py - p0[1]) - ((double)p1[1] - p0[1]) * (px - p0[0]);
                inside = area > 0 ? e >= 0 : e <= 0;
            }
            if (inside) m[(size_t)y * w + (size_t)x] = id;
        }
}

/* Union-find over a primitive's new vertices: a chart is a set of triangles sharing vertices (the
 * baker splits vertices where charts split, spec §16.4). */
static uint32_t uf_find(uint32_t *parent, uint32_t v)
{
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
}

int32_t *tl_chart_map(const lbk_objects_view *objs, const lbk_lmuv_view *lmuv, uint32_t page, uint32_t w, uint32_t h,
                      int32_t *next_id)
{
    int32_t *m = malloc(((size_t)w * h + 1) * sizeof *m);
    if (!m) return NULL;
    for (size_t i = 0; i < (size_t)w * h; i++) m[i] = -1;
    for (uint32_t i = 0; i < objs->count; i++) {
        lbk_object o;
        lbk_objects_get(objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP || o.index != page) continue;
        uint32_t rec;
        lbk_lmuv_object lo;
        if (!lmuv || lbk_lmuv_find_object(lmuv, i, &rec) != LBK_OK ||
            lbk_lmuv_get_object(lmuv, rec, &lo) != LBK_OK || lo.kind != LBK_LMUV_GENERATED) {
            const int32_t id = (*next_id)++;
            for (uint32_t y = o.rect_y; y < o.rect_y + o.rect_h && y < h; y++)
                for (uint32_t x = o.rect_x; x < o.rect_x + o.rect_w && x < w; x++) m[(size_t)y * w + x] = id;
            continue;
        }
        for (uint32_t k = 0; k < lo.primitive_count; k++) {
            lbk_lmuv_primitive pr;
            if (lbk_lmuv_get_primitive(lmuv, lo.primitive_first + k, &pr) != LBK_OK || !pr.vertex_count) continue;
            uint32_t *parent = malloc((size_t)pr.vertex_count * sizeof *parent);
            if (!parent) {
                free(m);
                return NULL;
            }
            for (uint32_t v = 0; v < pr.vertex_count; v++) parent[v] = v;
            for (uint32_t t = 0; t + 2 < pr.index_count; t += 3) {
                uint32_t ix[3] = {0, 0, 0};
                for (int c = 0; c < 3; c++) lbk_lmuv_index(lmuv, &pr, t + (uint32_t)c, &ix[c]);
                if (ix[0] >= pr.vertex_count || ix[1] >= pr.vertex_count || ix[2] >= pr.vertex_count) continue;
                parent[uf_find(parent, ix[1])] = uf_find(parent, ix[0]);
                parent[uf_find(parent, ix[2])] = uf_find(parent, ix[0]);
            }
            const int32_t base = *next_id;
            *next_id += (int32_t)pr.vertex_count; /* ids by root vertex: unique, not dense */
            for (uint32_t t = 0; t + 2 < pr.index_count; t += 3) {
                uint32_t ix[3] = {0, 0, 0}, src;
                float uv[3][2];
                for (int c = 0; c < 3; c++) {
                    lbk_lmuv_index(lmuv, &pr, t + (uint32_t)c, &ix[c]);
                    if (ix[c] >= pr.vertex_count || lbk_lmuv_vertex(lmuv, &pr, ix[c], &src, uv[c]) != LBK_OK) ix[0] = UINT32_MAX;
                }
                if (ix[0] == UINT32_MAX) continue;
                raster_triangle(m, w, h, uv[0], uv[1], uv[2], base + (int32_t)uf_find(parent, ix[0]));
            }
            free(parent);
        }
    }
    return m;
}

