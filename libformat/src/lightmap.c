/* LMAP: builder, zero-copy view and validator (spec/container.md §9). */
#include "lbk/lightmap.h"

#include "internal.h"
#include "lbk/pixel.h"
#include "section_util.h"

/* Entry fields */
enum { PE_WIDTH = 0, PE_HEIGHT = 2, PE_RESERVED = 4, PE_FIRST = 8, PE_PLANE0 = 16, PE_PLANE1 = 24 };

/* The packed layout of pages [0, n): plane offsets and the section end. Returns false on overflow. */
typedef struct lmap_cursor {
    uint64_t pos;   /* end of the previous plane */
    uint64_t texel; /* running first_texel */
} lmap_cursor;

static bool lmap_next_page(lmap_cursor *c, uint32_t w, uint32_t h, uint64_t *plane0, uint64_t *plane1)
{
    uint64_t bytes, end0, end1;
    if (!lbk_mul_u64((uint64_t)w * h, 4, &bytes)) return false;
    *plane0 = lbk_align_up(c->pos, 16);
    if (!lbk_add_u64(*plane0, bytes, &end0)) return false;
    *plane1 = lbk_align_up(end0, 16);
    if (!lbk_add_u64(*plane1, bytes, &end1)) return false;
    c->pos = end1;
    c->texel += (uint64_t)w * h;
    return true;
}

static lbk_result build_pages(const lbk_lmap_page_desc *pages, uint32_t page_count, float scale,
                              const lbk_allocator *allocator, void **out, size_t *size)
{
    if (!out || !size || !pages || page_count == 0) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (!lbk_scale_resolve(scale, &scale)) return LBK_ERR_INVALID_ARGUMENT;
    lmap_cursor c = {LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * page_count, 0};
    for (uint32_t p = 0; p < page_count; p++) {
        const lbk_lmap_page_desc *pd = &pages[p];
        if (pd->width < 1 || pd->height < 1 || pd->width > LBK_LMAP_MAX_DIM || pd->height > LBK_LMAP_MAX_DIM || !pd->texels)
            return LBK_ERR_INVALID_ARGUMENT;
        uint64_t a, b;
        if (!lmap_next_page(&c, pd->width, pd->height, &a, &b)) return LBK_ERR_LIMIT;
    }
    if (c.pos > SIZE_MAX) return LBK_ERR_LIMIT;
    uint8_t *d = lbk_calloc(allocator, 1, (size_t)c.pos);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(d, page_count);
    lbk_wrf32(d + 4, scale);
    lbk_wr64(d + 8, c.texel);
    const uint64_t total = c.texel;
    c.pos = LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * page_count;
    c.texel = 0;
    for (uint32_t p = 0; p < page_count; p++) {
        const lbk_lmap_page_desc *pd = &pages[p];
        uint8_t *e = d + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * p;
        const uint64_t first = c.texel;
        uint64_t o0, o1;
        lmap_next_page(&c, pd->width, pd->height, &o0, &o1);
        lbk_wr16(e + PE_WIDTH, (uint16_t)pd->width);
        lbk_wr16(e + PE_HEIGHT, (uint16_t)pd->height);
        lbk_wr64(e + PE_FIRST, first);
        lbk_wr64(e + PE_PLANE0, o0);
        lbk_wr64(e + PE_PLANE1, o1);
        const size_t n = (size_t)pd->width * pd->height;
        for (size_t i = 0; i < n; i++) {
            lbk_wr32(d + o0 + 4 * i, pd->texels[i].irradiance_z);
            memcpy(d + o1 + 4 * i, pd->texels[i].rgba, 4);
        }
    }
    (void)total;
    *out = d;
    *size = (size_t)c.pos;
    return LBK_OK;
}

lbk_result lbk_lmap_build(const lbk_lmap_build_desc *caller_desc, const lbk_allocator *allocator, void **out,
                          size_t *size)
{
    if (out) *out = NULL;
    if (size) *size = 0;
    if (!caller_desc) return LBK_ERR_INVALID_ARGUMENT;
    lbk_lmap_build_desc desc;
    lbk_result rc = LBK_SIZED_IN(&desc, caller_desc, lbk_lmap_build_desc, scale);
    if (rc != LBK_OK) return rc;
    return build_pages(desc.pages, desc.page_count, desc.scale, allocator, out, size);
}

lbk_result lbk_lmap_open(const void *data, size_t size, lbk_lmap_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_LMAP_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    const uint32_t n = lbk_rd32(d);
    if (!lbk_scale_bits_ok(lbk_rd32(d + 4))) return LBK_ERR_CORRUPT;
    if (n == 0) return LBK_ERR_CORRUPT;
    if (!lbk_range_ok(LBK_LMAP_HEADER_SIZE, (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * n, size)) return LBK_ERR_TRUNCATED;
    lmap_cursor c = {LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * n, 0};
    for (uint32_t p = 0; p < n; p++) {
        const uint8_t *e = d + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * p;
        const uint32_t w = lbk_rd16(e + PE_WIDTH), h = lbk_rd16(e + PE_HEIGHT);
        if (w < 1 || h < 1 || w > LBK_LMAP_MAX_DIM || h > LBK_LMAP_MAX_DIM) return LBK_ERR_CORRUPT;
        if (lbk_rd32(e + PE_RESERVED) != 0 || lbk_rd64(e + PE_FIRST) != c.texel) return LBK_ERR_CORRUPT;
        uint64_t o0, o1;
        if (!lmap_next_page(&c, w, h, &o0, &o1)) return LBK_ERR_CORRUPT;
        if (lbk_rd64(e + PE_PLANE0) != o0 || lbk_rd64(e + PE_PLANE1) != o1) return LBK_ERR_CORRUPT;
    }
    if (c.pos > size) return LBK_ERR_TRUNCATED;
    if (c.pos != size) return LBK_ERR_CORRUPT;
    if (lbk_rd64(d + 8) != c.texel) return LBK_ERR_CORRUPT;
    out->data = d;
    out->size = size;
    out->page_count = n;
    out->texel_count = c.texel;
    out->scale = lbk_rdf32(d + 4);
    return LBK_OK;
}

lbk_result lbk_lmap_page_get(const lbk_lmap_view *view, uint32_t index, lbk_lmap_page *out)
{
    if (!view || !out || !view->data) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->page_count) return LBK_ERR_NOT_FOUND;
    const uint8_t *e = view->data + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * index;
    out->width = lbk_rd16(e + PE_WIDTH);
    out->height = lbk_rd16(e + PE_HEIGHT);
    out->first_texel = lbk_rd64(e + PE_FIRST);
    out->irradiance_offset = lbk_rd64(e + PE_PLANE0);
    out->rgba_offset = lbk_rd64(e + PE_PLANE1);
    out->irradiance = view->data + out->irradiance_offset;
    out->rgba = view->data + out->rgba_offset;
    out->scale = view->scale;
    return LBK_OK;
}

lbk_result lbk_lmap_page_texel_get(const lbk_lmap_page *page, uint32_t x, uint32_t y, lbk_ahd_texel *out)
{
    if (!page || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (x >= page->width || y >= page->height) return LBK_ERR_NOT_FOUND;
    const size_t i = (size_t)y * page->width + x;
    out->irradiance_z = lbk_rd32(page->irradiance + 4 * i);
    memcpy(out->rgba, page->rgba + 4 * i, 4);
    return LBK_OK;
}

lbk_result lbk_lmap_page_irradiance(const lbk_lmap_page *page, uint32_t x, uint32_t y, const float n[3], float rgb[3])
{
    if (!n || !rgb) return LBK_ERR_INVALID_ARGUMENT;
    lbk_ahd_texel t;
    lbk_result r = lbk_lmap_page_texel_get(page, x, y, &t);
    if (r != LBK_OK) return r;
    lbk_ahd_irradiance(&t, n, rgb);
    for (int c = 0; c < 3; c++) rgb[c] *= page->scale;
    return LBK_OK;
}

lbk_result lbk_lmap_texel_get(const lbk_lmap_view *view, uint64_t texel_index, lbk_ahd_texel *out, uint32_t *page_out)
{
    if (!view || !out || !view->data) return LBK_ERR_INVALID_ARGUMENT;
    if (texel_index >= view->texel_count) return LBK_ERR_NOT_FOUND;
    /* binary search on first_texel (ascending by construction) */
    uint32_t lo = 0, hi = view->page_count;
    while (hi - lo > 1) {
        const uint32_t mid = lo + (hi - lo) / 2;
        const uint8_t *e = view->data + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * mid;
        if (lbk_rd64(e + PE_FIRST) <= texel_index) lo = mid;
        else hi = mid;
    }
    lbk_lmap_page pg;
    lbk_lmap_page_get(view, lo, &pg);
    const uint64_t local = texel_index - pg.first_texel;
    if (page_out) *page_out = lo;
    return lbk_lmap_page_texel_get(&pg, (uint32_t)(local % pg.width), (uint32_t)(local / pg.width), out);
}

/* ---- validation ------------------------------------------------------------------------------ */

void lbk_validate_lmap(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    lbk_rate rate;
    lbk_rate_init(&rate);
    if (size < LBK_LMAP_HEADER_SIZE) {
        lbk_vreport(ctx, 500, 0, "LMAP is %zu bytes, shorter than its 16-byte header", size);
        return;
    }
    const uint32_t n = lbk_rd32(d);
    bool ok = true;
    if (!lbk_check_scale(ctx, 511, d, 4, "LMAP")) ok = false;
    if (n == 0 || !lbk_range_ok(LBK_LMAP_HEADER_SIZE, (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * n, size)) {
        lbk_vreport(ctx, 502, 0, "LMAP page_count %u does not fit a %zu-byte section", n, size);
        return;
    }
    uint16_t *pw = lbk_calloc(ctx->allocator, n, sizeof *pw);
    uint16_t *ph = lbk_calloc(ctx->allocator, n, sizeof *ph);
    if (!pw || !ph) {
        lbk_dealloc(ctx->allocator, pw);
        lbk_dealloc(ctx->allocator, ph);
        return;
    }
    lmap_cursor c = {LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * n, 0};
    bool layout_ok = true;
    for (uint32_t p = 0; p < n && layout_ok; p++) {
        const uint64_t eo = LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * p;
        const uint8_t *e = d + eo;
        const uint32_t w = lbk_rd16(e + PE_WIDTH), h = lbk_rd16(e + PE_HEIGHT);
        pw[p] = (uint16_t)w;
        ph[p] = (uint16_t)h;
        if (w < 1 || h < 1 || w > LBK_LMAP_MAX_DIM || h > LBK_LMAP_MAX_DIM) {
            lbk_vreport(ctx, 503, eo, "LMAP page %u is %u x %u (each must be 1..16384)", p, w, h);
            layout_ok = false;
            break;
        }
        if (lbk_rd32(e + PE_RESERVED) != 0) {
            lbk_vreport(ctx, 501, eo + PE_RESERVED, "LMAP page %u reserved field is 0x%08x", p, lbk_rd32(e + PE_RESERVED));
            ok = false;
        }
        if (lbk_rd64(e + PE_FIRST) != c.texel) {
            lbk_vreport(ctx, 505, eo + PE_FIRST, "LMAP page %u first_texel %llu, expected %llu", p,
                        (unsigned long long)lbk_rd64(e + PE_FIRST), (unsigned long long)c.texel);
            ok = false;
        }
        uint64_t o0, o1;
        lmap_next_page(&c, w, h, &o0, &o1); /* cannot overflow: ≤ 2^30 bytes per plane */
        if (lbk_rd64(e + PE_PLANE0) != o0 || lbk_rd64(e + PE_PLANE1) != o1) {
            lbk_vreport(ctx, 506, eo + PE_PLANE0, "LMAP page %u plane offsets %llu/%llu, layout gives %llu/%llu", p,
                        (unsigned long long)lbk_rd64(e + PE_PLANE0), (unsigned long long)lbk_rd64(e + PE_PLANE1),
                        (unsigned long long)o0, (unsigned long long)o1);
            layout_ok = false;
        }
    }
    if (layout_ok && c.pos != size) {
        lbk_vreport(ctx, 507, 0, "LMAP is %zu bytes but its pages end at %llu", size, (unsigned long long)c.pos);
        layout_ok = false;
    }
    if (layout_ok && lbk_rd64(d + 8) != c.texel) {
        lbk_vreport(ctx, 504, 8, "LMAP texel_count %llu, pages hold %llu", (unsigned long long)lbk_rd64(d + 8),
                    (unsigned long long)c.texel);
        ok = false;
    }
    if (!layout_ok) {
        lbk_dealloc(ctx->allocator, pw);
        lbk_dealloc(ctx->allocator, ph);
        return;
    }
    /* padding and texels */
    uint64_t pos = LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * n;
    for (uint32_t p = 0; p < n; p++) {
        const uint8_t *e = d + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * p;
        const uint64_t o0 = lbk_rd64(e + PE_PLANE0), o1 = lbk_rd64(e + PE_PLANE1);
        const uint64_t count = (uint64_t)pw[p] * ph[p];
        if (!lbk_check_zero(ctx, 508, d, pos, o0, "LMAP")) ok = false;
        if (!lbk_check_zero(ctx, 508, d, o0 + 4 * count, o1, "LMAP")) ok = false;
        pos = o1 + 4 * count;
        for (uint64_t i = 0; i < count; i++) {
            const uint32_t v = lbk_rd32(d + o0 + 4 * i);
            if (lbk_r11g11b10f_special(v)) {
                if (lbk_rate_ok(&rate, 0))
                    lbk_vreport(ctx, 509, o0 + 4 * i, "LMAP page %u texel (%llu, %llu) irradiance 0x%08x has an Inf/NaN channel", p,
                                (unsigned long long)(i % pw[p]), (unsigned long long)(i / pw[p]), v);
                ok = false;
            }
            const uint8_t *q = d + o1 + 4 * i;
            const float x = 2.0f * q[1] / 255.0f - 1.0f, y = 2.0f * q[2] / 255.0f - 1.0f, z = q[3] / 255.0f;
            if (x * x + y * y + z * z < 0.25f && lbk_rate_ok(&rate, 1))
                lbk_vreport(ctx, 510, o1 + 4 * i, "LMAP page %u texel (%llu, %llu) highlight direction (%u, %u, %u) is shorter than 1/2", p,
                            (unsigned long long)(i % pw[p]), (unsigned long long)(i / pw[p]), q[1], q[2], q[3]);
        }
    }
    lbk_rate_flush(ctx, &rate, 509, 510);
    /* facts: validate.c frees the page arrays */
    lbk_dealloc(ctx->allocator, (void *)ctx->lmap_page_width);
    lbk_dealloc(ctx->allocator, (void *)ctx->lmap_page_height);
    ctx->lmap_page_width = pw;
    ctx->lmap_page_height = ph;
    ctx->lmap_page_count = n;
    ctx->lmap_texel_count = c.texel;
    ctx->lmap_ok = 1; /* the layout parsed; content errors above still make the file invalid */
    (void)ok;
}
