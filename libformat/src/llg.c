/* LLG: builder, view, trilinear sampling, per-vertex visibility and validator (spec §11). */
#include "lbk/llg.h"

#include <math.h>

#include "internal.h"
#include "lbk/octa.h"
#include "lbk/pixel.h"
#include "section_util.h"

/* Grid record fields */
enum {
    GR_CENTRE = 0,
    GR_AXES = 12,
    GR_HALF = 48,
    GR_DIMS = 60, /* u16 × 3 */
    GR_RES16 = 66,
    GR_RES32 = 68,
    GR_PROBE_OFFSET = 72,
    GR_VERTEX_OFFSET = 80,
    GR_VERTEX_COUNT = 88,
    GR_RES_END = 92
};

typedef struct llg_layout {
    uint64_t probes, vertices, end;
} llg_layout;

static bool llg_layout_of(uint64_t grids, uint64_t probes, uint64_t vertices, llg_layout *l)
{
    uint64_t t;
    if (!lbk_madd_u64(LBK_LLG_HEADER_SIZE, grids, LBK_LLG_GRID_SIZE, &t)) return false;
    l->probes = lbk_align_up(t, 16);
    if (!lbk_madd_u64(l->probes, probes, LBK_SH9_PACKED_SIZE, &t) || t > (UINT64_MAX >> 1)) return false;
    l->vertices = lbk_align_up(t, 16);
    if (!lbk_madd_u64(l->vertices, vertices, 4, &l->end)) return false;
    return true;
}

void lbk_llg_vertex_pack(const lbk_llg_vertex *v, uint8_t out[4])
{
    float uv[2];
    lbk_oct_encode(v->bent_normal, uv);
    out[0] = lbk_float_to_unorm8(v->visibility);
    out[1] = lbk_float_to_unorm8((uv[0] + 1.0f) * 0.5f);
    out[2] = lbk_float_to_unorm8((uv[1] + 1.0f) * 0.5f);
    out[3] = 0;
}

void lbk_llg_vertex_unpack(const uint8_t in[4], lbk_llg_vertex *v)
{
    v->visibility = lbk_unorm8_to_float(in[0]);
    const float uv[2] = {lbk_unorm8_to_float(in[1]) * 2.0f - 1.0f, lbk_unorm8_to_float(in[2]) * 2.0f - 1.0f};
    lbk_oct_decode(uv, v->bent_normal);
}

static bool grid_desc_ok(const lbk_llg_grid_desc *g)
{
    if (!lbk_finite3(g->centre) || !lbk_finite3(g->half_extents)) return false;
    for (int a = 0; a < 3; a++) {
        if (!lbk_finite3(g->axes[a]) || !(g->half_extents[a] > 0.0f)) return false;
        if (g->dims[a] < LBK_LLG_MIN_DIM || g->dims[a] > LBK_LLG_MAX_DIM) return false;
        for (int b = 0; b < 3; b++) {
            const double dot = (double)g->axes[a][0] * g->axes[b][0] + (double)g->axes[a][1] * g->axes[b][1] +
                               (double)g->axes[a][2] * g->axes[b][2];
            if (fabs(dot - (a == b ? 1.0 : 0.0)) > 1e-3) return false;
        }
    }
    return g->probes && (g->vertex_count == 0 || g->vertices);
}

static lbk_result build_grids(const lbk_llg_grid_desc *grids, uint32_t grid_count, float scale,
                              const lbk_allocator *allocator, void **out, size_t *size)
{
    if (!grids || !out || !size || grid_count == 0) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (!lbk_scale_resolve(scale, &scale)) return LBK_ERR_INVALID_ARGUMENT;
    const float inv = 1.0f / scale; /* exact: a power of two */
    uint64_t probes = 0, vertices = 0;
    for (uint32_t g = 0; g < grid_count; g++) {
        if (!grid_desc_ok(&grids[g])) return LBK_ERR_INVALID_ARGUMENT;
        probes += (uint64_t)grids[g].dims[0] * grids[g].dims[1] * grids[g].dims[2];
        vertices += grids[g].vertex_count;
    }
    llg_layout L;
    if (!llg_layout_of(grid_count, probes, vertices, &L) || L.end > SIZE_MAX) return LBK_ERR_LIMIT;
    uint8_t *d = lbk_calloc(allocator, 1, (size_t)L.end);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(d, grid_count);
    lbk_wrf32(d + 4, scale);
    lbk_wr64(d + 8, probes);
    lbk_wr64(d + 16, vertices);
    uint64_t po = 0, vo = 0;
    for (uint32_t g = 0; g < grid_count; g++) {
        const lbk_llg_grid_desc *gd = &grids[g];
        uint8_t *r = d + LBK_LLG_HEADER_SIZE + (size_t)LBK_LLG_GRID_SIZE * g;
        for (int k = 0; k < 3; k++) {
            lbk_wrf32(r + GR_CENTRE + 4 * k, gd->centre[k]);
            lbk_wrf32(r + GR_HALF + 4 * k, gd->half_extents[k]);
            lbk_wr16(r + GR_DIMS + 2 * k, (uint16_t)gd->dims[k]);
            for (int c = 0; c < 3; c++) lbk_wrf32(r + GR_AXES + 12 * k + 4 * c, gd->axes[k][c]);
        }
        lbk_wr64(r + GR_PROBE_OFFSET, po);
        lbk_wr64(r + GR_VERTEX_OFFSET, vo);
        lbk_wr32(r + GR_VERTEX_COUNT, gd->vertex_count);
        const uint64_t np = (uint64_t)gd->dims[0] * gd->dims[1] * gd->dims[2];
        for (uint64_t i = 0; i < np; i++) {
            lbk_sh9_rgb stored;
            memset(&stored, 0, sizeof stored);
            lbk_sh9_add_scaled(&stored, &gd->probes[i], inv);
            lbk_sh9_pack(&stored, d + L.probes + (po + i) * LBK_SH9_PACKED_SIZE);
        }
        for (uint32_t i = 0; i < gd->vertex_count; i++) lbk_llg_vertex_pack(&gd->vertices[i], d + L.vertices + (vo + i) * 4);
        po += np;
        vo += gd->vertex_count;
    }
    *out = d;
    *size = (size_t)L.end;
    return LBK_OK;
}

lbk_result lbk_llg_build(const lbk_llg_build_desc *caller_desc, const lbk_allocator *allocator, void **out,
                         size_t *size)
{
    if (out) *out = NULL;
    if (size) *size = 0;
    if (!caller_desc) return LBK_ERR_INVALID_ARGUMENT;
    lbk_llg_build_desc desc;
    lbk_result rc = LBK_SIZED_IN(&desc, caller_desc, lbk_llg_build_desc, scale);
    if (rc != LBK_OK) return rc;
    return build_grids(desc.grids, desc.grid_count, desc.scale, allocator, out, size);
}

static void read_grid(const uint8_t *r, lbk_llg_grid *g)
{
    for (int k = 0; k < 3; k++) {
        g->centre[k] = lbk_rdf32(r + GR_CENTRE + 4 * k);
        g->half_extents[k] = lbk_rdf32(r + GR_HALF + 4 * k);
        g->dims[k] = lbk_rd16(r + GR_DIMS + 2 * k);
        for (int c = 0; c < 3; c++) g->axes[k][c] = lbk_rdf32(r + GR_AXES + 12 * k + 4 * c);
    }
    g->probe_offset = lbk_rd64(r + GR_PROBE_OFFSET);
    g->vertex_offset = lbk_rd64(r + GR_VERTEX_OFFSET);
    g->vertex_count = lbk_rd32(r + GR_VERTEX_COUNT);
}

static bool grid_reserved_zero(const uint8_t *r)
{
    return lbk_rd16(r + GR_RES16) == 0 && lbk_rd32(r + GR_RES32) == 0 && lbk_rd32(r + GR_RES_END) == 0;
}

lbk_result lbk_llg_open(const void *data, size_t size, lbk_llg_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_LLG_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    const uint32_t G = lbk_rd32(d);
    const uint64_t P = lbk_rd64(d + 8), V = lbk_rd64(d + 16);
    if (G == 0 || !lbk_scale_bits_ok(lbk_rd32(d + 4)) || lbk_rd64(d + 24) != 0) return LBK_ERR_CORRUPT;
    llg_layout L;
    if (!llg_layout_of(G, P, V, &L)) return LBK_ERR_CORRUPT;
    if (L.end > size) return LBK_ERR_TRUNCATED;
    if (L.end != size) return LBK_ERR_CORRUPT;
    uint64_t po = 0, vo = 0;
    for (uint32_t g = 0; g < G; g++) {
        const uint8_t *r = d + LBK_LLG_HEADER_SIZE + (size_t)LBK_LLG_GRID_SIZE * g;
        lbk_llg_grid gr;
        read_grid(r, &gr);
        for (int k = 0; k < 3; k++)
            if (gr.dims[k] < LBK_LLG_MIN_DIM || gr.dims[k] > LBK_LLG_MAX_DIM) return LBK_ERR_CORRUPT;
        if (!grid_reserved_zero(r) || gr.probe_offset != po || gr.vertex_offset != vo) return LBK_ERR_CORRUPT;
        po += (uint64_t)gr.dims[0] * gr.dims[1] * gr.dims[2];
        vo += gr.vertex_count;
    }
    if (po != P || vo != V) return LBK_ERR_CORRUPT;
    out->data = d;
    out->size = size;
    out->grid_count = G;
    out->probe_count = P;
    out->vertex_count = V;
    out->probes = d + L.probes;
    out->vertices = d + L.vertices;
    out->scale = lbk_rdf32(d + 4);
    return LBK_OK;
}

lbk_result lbk_llg_grid_get(const lbk_llg_view *view, uint32_t index, lbk_llg_grid *out)
{
    if (!view || !view->data || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->grid_count) return LBK_ERR_NOT_FOUND;
    read_grid(view->data + LBK_LLG_HEADER_SIZE + (size_t)LBK_LLG_GRID_SIZE * index, out);
    return LBK_OK;
}

void lbk_llg_probe_position(const lbk_llg_grid *g, uint32_t i, uint32_t j, uint32_t k, float out[3])
{
    const uint32_t idx[3] = {i, j, k};
    for (int c = 0; c < 3; c++) out[c] = g->centre[c];
    for (int a = 0; a < 3; a++) {
        const float t = g->half_extents[a] * (2.0f * (float)idx[a] / (float)(g->dims[a] - 1) - 1.0f);
        for (int c = 0; c < 3; c++) out[c] += g->axes[a][c] * t;
    }
}

lbk_result lbk_llg_sample(const lbk_llg_view *view, uint32_t grid, const float p[3], lbk_sh9_rgb *out)
{
    if (!view || !view->data || !p || !out) return LBK_ERR_INVALID_ARGUMENT;
    lbk_llg_grid g;
    lbk_result r = lbk_llg_grid_get(view, grid, &g);
    if (r != LBK_OK) return r;
    uint32_t i0[3];
    float f[3];
    for (int a = 0; a < 3; a++) {
        const float rel = (p[0] - g.centre[0]) * g.axes[a][0] + (p[1] - g.centre[1]) * g.axes[a][1] +
                          (p[2] - g.centre[2]) * g.axes[a][2];
        float l = rel / g.half_extents[a];
        if (!(l > -1.0f)) l = -1.0f; /* also NaN (degenerate frames in unvalidated data) */
        if (l > 1.0f) l = 1.0f;
        const float gc = (l + 1.0f) * 0.5f * (float)(g.dims[a] - 1);
        uint32_t i = (uint32_t)gc;
        if (i > g.dims[a] - 2) i = g.dims[a] - 2;
        i0[a] = i;
        f[a] = gc - (float)i;
    }
    memset(out, 0, sizeof *out);
    for (int c = 0; c < 8; c++) {
        const uint32_t di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
        const float w = (di ? f[0] : 1.0f - f[0]) * (dj ? f[1] : 1.0f - f[1]) * (dk ? f[2] : 1.0f - f[2]);
        if (w == 0.0f) continue;
        const uint64_t idx = g.probe_offset + (i0[0] + di) + (uint64_t)g.dims[0] * ((i0[1] + dj) + (uint64_t)g.dims[1] * (i0[2] + dk));
        lbk_sh9_rgb sh;
        lbk_sh9_unpack(view->probes + idx * LBK_SH9_PACKED_SIZE, &sh);
        lbk_sh9_add_scaled(out, &sh, w * view->scale); /* exact: the scale is a power of two */
    }
    return LBK_OK;
}

lbk_result lbk_llg_vertex_irradiance(const lbk_llg_view *view, uint32_t grid, uint32_t vertex, const float p[3], float rgb[3])
{
    if (!view || !view->data || !p || !rgb) return LBK_ERR_INVALID_ARGUMENT;
    lbk_llg_grid g;
    lbk_result r = lbk_llg_grid_get(view, grid, &g);
    if (r != LBK_OK) return r;
    if (vertex >= g.vertex_count) return LBK_ERR_NOT_FOUND;
    lbk_llg_vertex v;
    lbk_llg_vertex_unpack(view->vertices + (g.vertex_offset + vertex) * 4, &v);
    float n[3] = {0, 0, 0};
    for (int a = 0; a < 3; a++)
        for (int c = 0; c < 3; c++) n[c] += v.bent_normal[a] * g.axes[a][c];
    lbk_sh9_rgb sh;
    r = lbk_llg_sample(view, grid, p, &sh);
    if (r != LBK_OK) return r;
    lbk_sh9_irradiance(&sh, n, rgb);
    for (int c = 0; c < 3; c++) rgb[c] = rgb[c] > 0.0f ? v.visibility * rgb[c] : 0.0f;
    return LBK_OK;
}

/* §11 "Vertex order": mark the used vertices of each primitive in map, then number them. */
lbk_result lbk_llg_vertex_map(const lbk_llg_source_primitive *primitives, uint32_t primitive_count, uint32_t *map,
                              uint64_t map_count, uint32_t *record_count)
{
    if ((!primitives && primitive_count) || (!map && map_count) || !record_count) return LBK_ERR_INVALID_ARGUMENT;
    uint64_t need = 0;
    for (uint32_t p = 0; p < primitive_count; p++) {
        const lbk_llg_source_primitive *q = &primitives[p];
        if (q->index_count % 3 || (q->index_count && !q->indices)) return LBK_ERR_INVALID_ARGUMENT;
        for (uint32_t i = 0; i < q->index_count; i++)
            if (q->indices[i] >= q->vertex_count) return LBK_ERR_INVALID_ARGUMENT;
        need += q->flat ? q->index_count : q->vertex_count;
    }
    if (need != map_count) return LBK_ERR_INVALID_ARGUMENT;
    uint64_t n = 0;
    uint32_t *m = map;
    for (uint32_t p = 0; p < primitive_count; p++) {
        const lbk_llg_source_primitive *q = &primitives[p];
        const uint32_t count = q->flat ? q->index_count : q->vertex_count;
        for (uint32_t v = 0; v < count; v++) m[v] = q->flat ? 0 : LBK_LLG_NO_VERTEX;
        if (!q->flat)
            for (uint32_t i = 0; i < q->index_count; i++) m[q->indices[i]] = 0;
        for (uint32_t v = 0; v < count; v++)
            if (m[v] == 0) {
                if (n >= LBK_LLG_NO_VERTEX - 1) return LBK_ERR_LIMIT;
                m[v] = (uint32_t)n++;
            }
        m += count;
    }
    *record_count = (uint32_t)n;
    return LBK_OK;
}

void lbk_validate_llg(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_LLG_HEADER_SIZE) {
        lbk_vreport(ctx, 700, 0, "LLG is %zu bytes, shorter than its 32-byte header", size);
        return;
    }
    const uint32_t G = lbk_rd32(d);
    const uint64_t P = lbk_rd64(d + 8), V = lbk_rd64(d + 16);
    lbk_check_scale(ctx, 713, d, 4, "LLG");
    if (lbk_rd64(d + 24) != 0) lbk_vreport(ctx, 701, 24, "LLG header reserved field is not zero");
    if (G == 0 || !lbk_range_ok(LBK_LLG_HEADER_SIZE, (uint64_t)LBK_LLG_GRID_SIZE * G, size)) {
        lbk_vreport(ctx, 702, 0, "LLG grid_count %u does not fit a %zu-byte section", G, size);
        return;
    }
    lbk_rate rate;
    lbk_rate_init(&rate);
    uint64_t po = 0, vo = 0;
    bool counts_ok = true;
    for (uint32_t gi = 0; gi < G; gi++) {
        const uint64_t ro = LBK_LLG_HEADER_SIZE + (uint64_t)LBK_LLG_GRID_SIZE * gi;
        const uint8_t *r = d + ro;
        lbk_llg_grid g;
        read_grid(r, &g);
        if (!grid_reserved_zero(r)) lbk_vreport(ctx, 701, ro + GR_RES16, "LLG grid %u reserved field is not zero", gi);
        bool finite = lbk_finite3(g.centre) && lbk_finite3(g.half_extents);
        for (int a = 0; a < 3; a++) finite = finite && lbk_finite3(g.axes[a]);
        if (!finite) {
            lbk_vreport(ctx, 705, ro, "LLG grid %u box has a non-finite value", gi);
        } else {
            double worst = 0.0;
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++) {
                    const double dot = (double)g.axes[a][0] * g.axes[b][0] + (double)g.axes[a][1] * g.axes[b][1] +
                                       (double)g.axes[a][2] * g.axes[b][2];
                    worst = fmax(worst, fabs(dot - (a == b ? 1.0 : 0.0)));
                }
            if (worst > 1e-3)
                lbk_vreport(ctx, 706, ro + GR_AXES, "LLG grid %u axes are not orthonormal (error %g)", gi, worst);
            for (int a = 0; a < 3; a++)
                if (!(g.half_extents[a] > 0.0f)) {
                    lbk_vreport(ctx, 707, ro + GR_HALF + 4 * (uint64_t)a, "LLG grid %u half extent %d is %g", gi, a,
                                (double)g.half_extents[a]);
                    break;
                }
        }
        bool dims_ok = true;
        for (int a = 0; a < 3; a++)
            if (g.dims[a] < LBK_LLG_MIN_DIM || g.dims[a] > LBK_LLG_MAX_DIM) dims_ok = false;
        if (!dims_ok) {
            lbk_vreport(ctx, 708, ro + GR_DIMS, "LLG grid %u lattice %u x %u x %u (each must be 2..64)", gi, g.dims[0],
                        g.dims[1], g.dims[2]);
            counts_ok = false;
        }
        if (g.probe_offset != po) {
            lbk_vreport(ctx, 709, ro + GR_PROBE_OFFSET, "LLG grid %u probe_offset %llu, expected %llu", gi,
                        (unsigned long long)g.probe_offset, (unsigned long long)po);
            counts_ok = false;
        }
        if (g.vertex_offset != vo) {
            lbk_vreport(ctx, 710, ro + GR_VERTEX_OFFSET, "LLG grid %u vertex_offset %llu, expected %llu", gi,
                        (unsigned long long)g.vertex_offset, (unsigned long long)vo);
            counts_ok = false;
        }
        po += (uint64_t)g.dims[0] * g.dims[1] * g.dims[2]; /* ≤ 2^48 per grid: no overflow for 2^32 grids */
        vo += g.vertex_count;
    }
    if (!counts_ok) return;
    if (po != P || vo != V) {
        lbk_vreport(ctx, 711, 8, "LLG header counts %llu probes / %llu vertices, grids hold %llu / %llu",
                    (unsigned long long)P, (unsigned long long)V, (unsigned long long)po, (unsigned long long)vo);
        return;
    }
    llg_layout L;
    if (!llg_layout_of(G, P, V, &L) || L.end != size) {
        lbk_vreport(ctx, 703, 0, "LLG is %zu bytes; its grids need %llu", size,
                    (unsigned long long)(llg_layout_of(G, P, V, &L) ? L.end : 0));
        return;
    }
    lbk_check_zero(ctx, 704, d, LBK_LLG_HEADER_SIZE + (uint64_t)LBK_LLG_GRID_SIZE * G, L.probes, "LLG");
    lbk_check_zero(ctx, 704, d, L.probes + P * LBK_SH9_PACKED_SIZE, L.vertices, "LLG");
    for (uint64_t i = 0; i < V; i++)
        if (d[L.vertices + 4 * i + 3] != 0 && lbk_rate_ok(&rate, 0))
            lbk_vreport(ctx, 712, L.vertices + 4 * i + 3, "LLG vertex %llu reserved byte is 0x%02x", (unsigned long long)i,
                        d[L.vertices + 4 * i + 3]);
    lbk_rate_flush(ctx, &rate, 712, 0);
    ctx->llg_ok = 1;
    ctx->llg_count = G;
    ctx->llg_probe_count = P;
}
