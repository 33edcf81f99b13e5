/* LMAP: builder, zero-copy view and validator (spec/container.md §9). */
#include "lbk/lightmap.h"

#include "internal.h"
#include "lbk/bc.h"
#include "lbk/container.h"
#include "lbk/pixel.h"
#include "section_util.h"

#define XXH_STATIC_LINKING_ONLY /* XXH3_state_t on the stack: no allocation outside lbk_allocator */
#include "xxh.h"

/* Entry fields */
enum { PE_WIDTH = 0, PE_HEIGHT = 2, PE_ENCODING = 4, PE_FIRST = 8, PE_PLANE0 = 16, PE_PLANE1 = 24 };

/* ---- plane encodings (spec §9.2) ---------------------------------------------------------------- */

static bool is_block(uint32_t plane, uint32_t format) { return plane == 0 ? format != LBK_LMAP_R11G11B10F : format != LBK_LMAP_RGBA8; }

uint64_t lbk_lmap_plane_size(uint32_t plane, uint32_t format, uint32_t w, uint32_t h)
{
    if (plane > 1 || w < 1 || h < 1 || w > LBK_LMAP_MAX_DIM || h > LBK_LMAP_MAX_DIM) return 0;
    if (format >= (plane == 0 ? (uint32_t)LBK_LMAP_FORMAT0_COUNT_ : (uint32_t)LBK_LMAP_FORMAT1_COUNT_)) return 0;
    if (!is_block(plane, format)) return 4 * (uint64_t)w * h;
    if (w % LBK_LMAP_BLOCK || h % LBK_LMAP_BLOCK) return 0;
    const uint64_t blocks = (uint64_t)(w / LBK_LMAP_BLOCK) * (h / LBK_LMAP_BLOCK);
    if (plane == 1 && format == LBK_LMAP_BC5_BC4) return lbk_align_up(16 * blocks, 16) + 8 * blocks;
    return 16 * blocks; /* BC6H, ASTC 4×4 */
}

/* The two formats of an entry's encoding; false for unknown ones or non-zero high bits. */
static bool split_encoding(uint32_t enc, uint32_t f[2])
{
    f[0] = enc & 0xffu;
    f[1] = (enc >> 8) & 0xffu;
    return (enc >> 16) == 0 && f[0] < LBK_LMAP_FORMAT0_COUNT_ && f[1] < LBK_LMAP_FORMAT1_COUNT_;
}

/* The packed layout of pages [0, n): plane offsets and the section end. Returns false on overflow. */
typedef struct lmap_cursor {
    uint64_t pos;   /* end of the previous plane */
    uint64_t texel; /* running first_texel */
} lmap_cursor;

/* The next page's plane offsets in the packed layout; false for an encoding or size that has none. */
static bool lmap_next_page(lmap_cursor *c, uint32_t w, uint32_t h, const uint32_t f[2], uint64_t *plane0,
                           uint64_t *plane1)
{
    uint64_t end0, end1;
    const uint64_t b0 = lbk_lmap_plane_size(0, f[0], w, h), b1 = lbk_lmap_plane_size(1, f[1], w, h);
    if (!b0 || !b1) return false;
    *plane0 = lbk_align_up(c->pos, 16);
    if (!lbk_add_u64(*plane0, b0, &end0)) return false;
    *plane1 = lbk_align_up(end0, 16);
    if (!lbk_add_u64(*plane1, b1, &end1)) return false;
    c->pos = end1;
    c->texel += (uint64_t)w * h;
    return true;
}

static const uint32_t plain[2] = {LBK_LMAP_R11G11B10F, LBK_LMAP_RGBA8};

/* One page to lay out: its size, encoding and where its planes' bytes come from. */
typedef struct page_src {
    uint32_t w, h, f[2];
    const lbk_ahd_texel *texels; /* 1.0 pages */
    const void *plane[2];        /* encoded pages */
} page_src;

static lbk_result build_pages(const page_src *pages, uint32_t page_count, float scale, const lbk_allocator *allocator,
                              void **out, size_t *size)
{
    if (!lbk_scale_resolve(scale, &scale)) return LBK_ERR_INVALID_ARGUMENT;
    lmap_cursor c = {LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * page_count, 0};
    for (uint32_t p = 0; p < page_count; p++) {
        uint64_t a, b;
        if (!lmap_next_page(&c, pages[p].w, pages[p].h, pages[p].f, &a, &b)) return LBK_ERR_INVALID_ARGUMENT;
    }
    if (c.pos > SIZE_MAX) return LBK_ERR_LIMIT;
    uint8_t *d = lbk_calloc(allocator, 1, (size_t)c.pos);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(d, page_count);
    lbk_wrf32(d + 4, scale);
    lbk_wr64(d + 8, c.texel);
    c.pos = LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * page_count;
    c.texel = 0;
    for (uint32_t p = 0; p < page_count; p++) {
        const page_src *ps = &pages[p];
        uint8_t *e = d + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * p;
        const uint64_t first = c.texel;
        uint64_t o[2];
        lmap_next_page(&c, ps->w, ps->h, ps->f, &o[0], &o[1]);
        lbk_wr16(e + PE_WIDTH, (uint16_t)ps->w);
        lbk_wr16(e + PE_HEIGHT, (uint16_t)ps->h);
        lbk_wr32(e + PE_ENCODING, ps->f[0] | ps->f[1] << 8);
        lbk_wr64(e + PE_FIRST, first);
        lbk_wr64(e + PE_PLANE0, o[0]);
        lbk_wr64(e + PE_PLANE1, o[1]);
        if (ps->texels) {
            const size_t n = (size_t)ps->w * ps->h;
            for (size_t i = 0; i < n; i++) {
                lbk_wr32(d + o[0] + 4 * i, ps->texels[i].irradiance_z);
                memcpy(d + o[1] + 4 * i, ps->texels[i].rgba, 4);
            }
        } else {
            for (int k = 0; k < 2; k++)
                memcpy(d + o[k], ps->plane[k], (size_t)lbk_lmap_plane_size((uint32_t)k, ps->f[k], ps->w, ps->h));
        }
    }
    *out = d;
    *size = (size_t)c.pos;
    return LBK_OK;
}

lbk_result lbk_lmap_build(const lbk_lmap_build_desc *caller_desc, const lbk_allocator *allocator, void **out,
                          size_t *size)
{
    if (out) *out = NULL;
    if (size) *size = 0;
    if (!caller_desc || !out || !size) return LBK_ERR_INVALID_ARGUMENT;
    lbk_lmap_build_desc desc;
    lbk_result rc = LBK_SIZED_IN(&desc, caller_desc, lbk_lmap_build_desc, scale);
    if (rc != LBK_OK) return rc;
    if (desc.page_count == 0 || (!desc.pages && !desc.encoded)) return LBK_ERR_INVALID_ARGUMENT;
    page_src *ps = lbk_calloc(allocator, desc.page_count, sizeof *ps);
    if (!ps) return LBK_ERR_OUT_OF_MEMORY;
    rc = LBK_OK;
    for (uint32_t p = 0; p < desc.page_count && rc == LBK_OK; p++) {
        if (desc.encoded) {
            const lbk_lmap_encoded_page *ep = &desc.encoded[p];
            ps[p] = (page_src){ep->width, ep->height, {ep->format[0], ep->format[1]}, NULL, {ep->plane[0], ep->plane[1]}};
            if (!ep->plane[0] || !ep->plane[1]) rc = LBK_ERR_INVALID_ARGUMENT;
        } else {
            const lbk_lmap_page_desc *pd = &desc.pages[p];
            ps[p] = (page_src){pd->width, pd->height, {plain[0], plain[1]}, pd->texels, {NULL, NULL}};
            if (!pd->texels) rc = LBK_ERR_INVALID_ARGUMENT;
        }
    }
    if (rc == LBK_OK) rc = build_pages(ps, desc.page_count, desc.scale, allocator, out, size);
    lbk_dealloc(allocator, ps);
    return rc;
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
        uint32_t f[2];
        if (w < 1 || h < 1 || w > LBK_LMAP_MAX_DIM || h > LBK_LMAP_MAX_DIM) return LBK_ERR_CORRUPT;
        if (!split_encoding(lbk_rd32(e + PE_ENCODING), f) || lbk_rd64(e + PE_FIRST) != c.texel) return LBK_ERR_CORRUPT;
        uint64_t o0, o1;
        if (!lmap_next_page(&c, w, h, f, &o0, &o1)) return LBK_ERR_CORRUPT;
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

lbk_result lbk_lmap_planes_get(const lbk_lmap_view *view, uint32_t index, lbk_lmap_planes *out)
{
    if (!view || !out || !view->data) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->page_count) return LBK_ERR_NOT_FOUND;
    memset(out, 0, sizeof *out);
    const uint8_t *e = view->data + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * index;
    out->width = lbk_rd16(e + PE_WIDTH);
    out->height = lbk_rd16(e + PE_HEIGHT);
    out->first_texel = lbk_rd64(e + PE_FIRST);
    split_encoding(lbk_rd32(e + PE_ENCODING), out->format); /* checked by lbk_lmap_open */
    for (uint32_t k = 0; k < 2; k++) {
        out->offset[k] = lbk_rd64(e + (k ? PE_PLANE1 : PE_PLANE0));
        out->bytes[k] = lbk_lmap_plane_size(k, out->format[k], out->width, out->height);
        out->plane[k] = view->data + out->offset[k];
    }
    if (is_block(0, out->format[0]) || is_block(1, out->format[1]))
        out->blocks_x = out->width / LBK_LMAP_BLOCK, out->blocks_y = out->height / LBK_LMAP_BLOCK;
    out->scale = view->scale;
    return LBK_OK;
}

lbk_result lbk_lmap_page_get(const lbk_lmap_view *view, uint32_t index, lbk_lmap_page *out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    lbk_lmap_planes pl;
    lbk_result r = lbk_lmap_planes_get(view, index, &pl);
    if (r != LBK_OK) return r;
    if (pl.blocks_x) return LBK_ERR_UNSUPPORTED_FEATURE; /* the struct can describe 1.0 planes only */
    out->width = pl.width;
    out->height = pl.height;
    out->first_texel = pl.first_texel;
    out->irradiance_offset = pl.offset[0];
    out->rgba_offset = pl.offset[1];
    out->irradiance = pl.plane[0];
    out->rgba = pl.plane[1];
    out->scale = pl.scale;
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

/* The page holding a global texel index (binary search on first_texel, ascending by construction). */
static uint32_t page_of(const lbk_lmap_view *view, uint64_t texel_index)
{
    uint32_t lo = 0, hi = view->page_count;
    while (hi - lo > 1) {
        const uint32_t mid = lo + (hi - lo) / 2;
        const uint8_t *e = view->data + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * mid;
        if (lbk_rd64(e + PE_FIRST) <= texel_index) lo = mid;
        else hi = mid;
    }
    return lo;
}

lbk_result lbk_lmap_texel_get(const lbk_lmap_view *view, uint64_t texel_index, lbk_ahd_texel *out, uint32_t *page_out)
{
    if (!view || !out || !view->data) return LBK_ERR_INVALID_ARGUMENT;
    if (texel_index >= view->texel_count) return LBK_ERR_NOT_FOUND;
    const uint32_t p = page_of(view, texel_index);
    if (page_out) *page_out = p;
    lbk_lmap_page pg;
    lbk_result r = lbk_lmap_page_get(view, p, &pg);
    if (r != LBK_OK) return r;
    const uint64_t local = texel_index - pg.first_texel;
    return lbk_lmap_page_texel_get(&pg, (uint32_t)(local % pg.width), (uint32_t)(local / pg.width), out);
}

/* ---- decoding any encoding -------------------------------------------------------------------- */

lbk_result lbk_lmap_planes_texel_unpack(const lbk_lmap_planes *pl, uint32_t x, uint32_t y, lbk_ahd_texel_f *out)
{
    if (!pl || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (x >= pl->width || y >= pl->height) return LBK_ERR_NOT_FOUND;
    if (pl->format[0] == LBK_LMAP_ASTC4X4_HDR || pl->format[1] == LBK_LMAP_ASTC4X4_LDR) return LBK_ERR_UNSUPPORTED_FEATURE;
    const size_t i = (size_t)y * pl->width + x;
    const size_t blk = (size_t)(y / LBK_LMAP_BLOCK) * pl->blocks_x + x / LBK_LMAP_BLOCK;
    const unsigned in_blk = (y % LBK_LMAP_BLOCK) * LBK_LMAP_BLOCK + x % LBK_LMAP_BLOCK;
    lbk_ahd_texel t = {0, {0, 0, 0, 0}};
    if (pl->format[0] == LBK_LMAP_R11G11B10F) t.irradiance_z = lbk_rd32(pl->plane[0] + 4 * i);
    if (pl->format[1] == LBK_LMAP_RGBA8) memcpy(t.rgba, pl->plane[1] + 4 * i, 4);
    lbk_ahd_texel_f_from_texel(&t, out);
    if (pl->format[0] == LBK_LMAP_BC6H) {
        uint16_t h[16][3];
        lbk_bc6h_unpack(pl->plane[0] + LBK_BC6H_BLOCK_SIZE * blk, h);
        for (int c = 0; c < 3; c++) out->ez[c] = lbk_half_to_float(h[in_blk][c]);
    }
    if (pl->format[1] == LBK_LMAP_BC5_BC4) {
        const uint64_t nb = (uint64_t)pl->blocks_x * pl->blocks_y;
        float dir[16][2], ratio[16];
        lbk_bc5_unpack(pl->plane[1] + LBK_BC5_BLOCK_SIZE * blk, dir);
        lbk_bc4_unpack(pl->plane[1] + lbk_align_up(16 * nb, 16) + LBK_BC4_BLOCK_SIZE * blk, ratio);
        const float dx = 2 * dir[in_blk][0] - 1, dy = 2 * dir[in_blk][1] - 1, zz = 1 - dx * dx - dy * dy;
        out->rgba[0] = ratio[in_blk];
        out->rgba[1] = dir[in_blk][0];
        out->rgba[2] = dir[in_blk][1];
        out->rgba[3] = zz > 0 ? sqrtf(zz) : 0;
    }
    return LBK_OK;
}

lbk_result lbk_lmap_planes_irradiance(const lbk_lmap_planes *pl, uint32_t x, uint32_t y, const float n[3], float rgb[3])
{
    if (!pl || !n || !rgb) return LBK_ERR_INVALID_ARGUMENT;
    if (x >= pl->width || y >= pl->height) return LBK_ERR_NOT_FOUND;
    lbk_ahd_linear lin;
    if (!pl->blocks_x) { /* 1.0 page: the 1.0 decoder, bit for bit */
        const size_t i = (size_t)y * pl->width + x;
        lbk_ahd_texel t;
        t.irradiance_z = lbk_rd32(pl->plane[0] + 4 * i);
        memcpy(t.rgba, pl->plane[1] + 4 * i, 4);
        lbk_ahd_to_linear(&t, &lin);
    } else {
        lbk_ahd_texel_f tf;
        lbk_result r = lbk_lmap_planes_texel_unpack(pl, x, y, &tf);
        if (r != LBK_OK) return r;
        lbk_ahd_texel_f_to_linear(&tf, &lin);
    }
    lbk_ahd_linear_eval(&lin, n, rgb);
    for (int c = 0; c < 3; c++) rgb[c] *= pl->scale;
    return LBK_OK;
}

uint64_t lbk_lmap_planes_rect_bytes(const lbk_lmap_planes *pl, uint32_t x, uint32_t y, uint32_t w, uint32_t h)
{
    if (!pl || (uint64_t)x + w > pl->width || (uint64_t)y + h > pl->height || w == 0 || h == 0) return 0;
    uint64_t total = 0;
    for (uint32_t k = 0; k < 2; k++) {
        if (!is_block(k, pl->format[k])) {
            total += 4 * (uint64_t)w * h;
            continue;
        }
        const uint64_t bx = (x + w - 1) / LBK_LMAP_BLOCK - x / LBK_LMAP_BLOCK + 1;
        const uint64_t by = (y + h - 1) / LBK_LMAP_BLOCK - y / LBK_LMAP_BLOCK + 1;
        total += bx * by * (k == 1 && pl->format[1] == LBK_LMAP_BC5_BC4 ? 16 + 8 : 16);
    }
    return total;
}

uint32_t lbk_lmap_required_features(const void *data, size_t size)
{
    lbk_lmap_view v;
    if (lbk_lmap_open(data, size, &v) != LBK_OK) return 0;
    for (uint32_t p = 0; p < v.page_count; p++) {
        lbk_lmap_planes pl;
        lbk_lmap_planes_get(&v, p, &pl);
        if (pl.blocks_x) return LBK_FEATURE_LMAP_BLOCK;
    }
    return 0;
}

/* ---- validation ------------------------------------------------------------------------------ */

/* The texel checks run over blocks of texels with a branch-free test first, so the common case (a
 * valid plane) runs at memory speed (the fixed block length lets the compiler vectorise it); a
 * block with a hit is scanned again texel by texel to report it (bench/bench_container.c:
 * checksum + validation within 20 % of memcpy). */
enum { SCAN_BLOCK = 1024 };

static inline uint32_t word_at(const uint8_t *p)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    uint32_t v;
    memcpy(&v, p, 4);
    return v;
#else
    return lbk_rd32(p);
#endif
}

/* Exponent 31 in any channel of R11G11B10F (509): R bits 6–10, G bits 17–21, B bits 27–31. */
static inline uint32_t exp31_any(uint32_t v)
{
    return ((v & 0x7c0u) == 0x7c0u) | ((v & 0x3e0000u) == 0x3e0000u) | ((v & 0xf8000000u) == 0xf8000000u);
}

/* The direction (2G/255 − 1, 2B/255 − 1, A/255) of plane-1 word v (R, G, B, A = bytes 0..3)
 * shorter than 1/2 (510), in integers: (2G − 255)² + (2B − 255)² + A² < 255²/4 ⇔ ≤ 16256 — the
 * same answer as the float test of the decoder for every byte triple (tests/lib/test_ahd.c checks
 * all 2^24). */
static inline uint32_t short_direction(uint32_t v)
{
    const int32_t x = 2 * (int32_t)((v >> 8) & 255u) - 255, y = 2 * (int32_t)((v >> 16) & 255u) - 255,
                  z = (int32_t)(v >> 24);
    return (uint32_t)(x * x + y * y + z * z <= 16256);
}

/* A superset of short_direction without multiplies: a short direction has |2G − 255|, |2B − 255|
 * and A all ≤ 127, i.e. G, B in [64, 191] — bit 7 of the byte G + 64 (mod 256) set, added byte-wise
 * in SWAR — and A ≤ 127. Unit-length directions never pass it (|d.x|, |d.y| < 1/2 forces
 * d.z > 0.7, A > 127), so on a valid plane the exact test never runs. */
static inline uint32_t maybe_short(uint32_t v)
{
    const uint32_t sum = ((v & 0x7f7f7f7fu) + 0x00404000u) ^ (v & 0x80808080u);
    return ((sum & 0x00808000u) == 0x00808000u) & ((v & 0x80000000u) == 0);
}

/* With AVX2 where the CPU has it (GCC's function multiversioning picks at load time): twice the
 * texels per instruction of the SSE2 default, which is what keeps the fused checksum + texel pass
 * at memory speed. Not under the sanitizers (ifunc resolvers run before their runtime). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__) && \
    !defined(__SANITIZE_THREAD__) && defined(__ELF__)
#define LBK_BLOCK_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define LBK_BLOCK_CLONES
#endif

LBK_BLOCK_CLONES static uint32_t block_hits(const uint8_t *plane, int which)
{
    uint32_t hit = 0;
    if (which == 0)
        for (size_t i = 0; i < SCAN_BLOCK; i++) hit |= exp31_any(word_at(plane + 4 * i));
    else
        for (size_t i = 0; i < SCAN_BLOCK; i++) hit |= maybe_short(word_at(plane + 4 * i));
    return hit;
}

/* The block tests of the 1.0 planes, in the order the validator scans them. */
static uint64_t full_blocks(uint64_t count) { return count / SCAN_BLOCK; }

uint64_t lbk_lmap_hash_prescan(const uint8_t *d, size_t size, const lbk_allocator *allocator, uint8_t **hits,
                               uint64_t *bits)
{
    *hits = NULL;
    *bits = 0;
    lbk_lmap_view v;
    if (lbk_lmap_open(d, size, &v) != LBK_OK) return XXH3_64bits(d, size);
    uint64_t n = 0;
    for (uint32_t p = 0; p < v.page_count; p++) {
        lbk_lmap_planes pl;
        if (lbk_lmap_planes_get(&v, p, &pl) != LBK_OK) return XXH3_64bits(d, size);
        const uint64_t c = (uint64_t)pl.width * pl.height;
        n += (pl.format[0] == LBK_LMAP_R11G11B10F ? full_blocks(c) : 0) + (pl.format[1] == LBK_LMAP_RGBA8 ? full_blocks(c) : 0);
    }
    uint8_t *h = n ? lbk_calloc(allocator, 1, (size_t)((n + 7) / 8)) : NULL;
    if (n && !h) return XXH3_64bits(d, size);
    XXH3_state_t st;
    XXH3_64bits_reset(&st);
    size_t fed = 0;
    uint64_t bit = 0;
    for (uint32_t p = 0; p < v.page_count; p++) {
        lbk_lmap_planes pl;
        lbk_lmap_planes_get(&v, p, &pl);
        const uint64_t c = (uint64_t)pl.width * pl.height;
        for (int k = 0; k < 2; k++) {
            if (pl.format[k] != (k ? (uint32_t)LBK_LMAP_RGBA8 : (uint32_t)LBK_LMAP_R11G11B10F)) continue;
            for (uint64_t b = 0; b < full_blocks(c); b++, bit++) {
                const size_t start = (size_t)(pl.offset[k] + 4 * b * SCAN_BLOCK), end = start + 4 * SCAN_BLOCK;
                if (end > fed) { /* hash up to the block's end, then test it while it is in cache */
                    XXH3_64bits_update(&st, d + fed, end - fed);
                    fed = end;
                }
                if (block_hits(d + start, k)) h[bit / 8] |= (uint8_t)(1u << (bit % 8));
            }
        }
    }
    XXH3_64bits_update(&st, d + fed, size - fed);
    *hits = h;
    *bits = n;
    return XXH3_64bits_digest(&st);
}

/* which 0: plane 0 (509, content error: *ok = false); 1: plane 1 (510, a warning). hits: the
 * prescan's bits (NULL: test each block here), *bit the running index into them. */
static void scan_plane(lbk_vctx *ctx, lbk_rate *rate, int which, uint32_t page, uint32_t width, const uint8_t *plane,
                       uint64_t offset, uint64_t count, bool *ok, const uint8_t *hits, uint64_t *bit)
{
    for (uint64_t b = 0; b < count; b += SCAN_BLOCK) {
        const uint64_t e = count - b < SCAN_BLOCK ? count : b + SCAN_BLOCK;
        if (e - b == SCAN_BLOCK) {
            const uint64_t i = (*bit)++;
            if (!(hits ? (hits[i / 8] >> (i % 8)) & 1u : block_hits(plane + 4 * b, which))) continue;
        }
        for (uint64_t i = b; i < e; i++) {
            const uint32_t v = word_at(plane + 4 * i);
            if (which == 0 && exp31_any(v)) {
                *ok = false;
                if (lbk_rate_ok(rate, 0))
                    lbk_vreport(ctx, 509, offset + 4 * i,
                                "LMAP page %u texel (%llu, %llu) irradiance 0x%08x has an Inf/NaN channel", page,
                                (unsigned long long)(i % width), (unsigned long long)(i / width), v);
            }
            if (which == 1 && short_direction(v) && lbk_rate_ok(rate, 1))
                lbk_vreport(ctx, 510, offset + 4 * i,
                            "LMAP page %u texel (%llu, %llu) highlight direction (%u, %u, %u) is shorter than 1/2",
                            page, (unsigned long long)(i % width), (unsigned long long)(i / width),
                            (v >> 8) & 255u, (v >> 16) & 255u, v >> 24);
        }
    }
}

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
    bool layout_ok = true, any_block = false;
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
        const uint32_t enc = lbk_rd32(e + PE_ENCODING);
        uint32_t f[2];
        if (enc >> 16) {
            lbk_vreport(ctx, 501, eo + PE_ENCODING, "LMAP page %u encoding 0x%08x has reserved bits set", p, enc);
            ok = false;
        }
        if (!split_encoding(enc & 0xffffu, f)) {
            lbk_vreport(ctx, 512, eo + PE_ENCODING, "LMAP page %u plane formats %u/%u are not defined (spec 9.2)", p,
                        enc & 0xffu, (enc >> 8) & 0xffu);
            layout_ok = false;
            break;
        }
        if ((is_block(0, f[0]) || is_block(1, f[1])) && (w % LBK_LMAP_BLOCK || h % LBK_LMAP_BLOCK)) {
            lbk_vreport(ctx, 513, eo, "LMAP page %u is %u x %u, a block-encoded page needs multiples of 4", p, w, h);
            layout_ok = false;
            break;
        }
        any_block |= is_block(0, f[0]) || is_block(1, f[1]);
        if (lbk_rd64(e + PE_FIRST) != c.texel) {
            lbk_vreport(ctx, 505, eo + PE_FIRST, "LMAP page %u first_texel %llu, expected %llu", p,
                        (unsigned long long)lbk_rd64(e + PE_FIRST), (unsigned long long)c.texel);
            ok = false;
        }
        uint64_t o0, o1;
        lmap_next_page(&c, w, h, f, &o0, &o1); /* cannot overflow: ≤ 2^30 bytes per plane */
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
    /* the header's feature bit says whether block pages are here (spec §2, §9.2) */
    const bool bit = (ctx->required_features & LBK_FEATURE_LMAP_BLOCK) != 0;
    if (bit != any_block) {
        lbk_vreport(ctx, 515, 0, "LMAP %s block-encoded page but the header's required feature LMAP_BLOCK is %s",
                    any_block ? "has a" : "has no", bit ? "set" : "clear");
        ok = false;
    }
    /* padding and texels; the block tests from the checksum pass when it ran over these pages */
    uint64_t pos = LBK_LMAP_HEADER_SIZE + (uint64_t)LBK_LMAP_PAGE_ENTRY_SIZE * n, want_bits = 0, next_bit = 0;
    for (uint32_t p = 0; p < n; p++) {
        uint32_t fm[2];
        split_encoding(lbk_rd32(d + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * p + PE_ENCODING) & 0xffffu, fm);
        const uint64_t texels = (uint64_t)pw[p] * ph[p];
        want_bits += (fm[0] == LBK_LMAP_R11G11B10F ? full_blocks(texels) : 0) + (fm[1] == LBK_LMAP_RGBA8 ? full_blocks(texels) : 0);
    }
    const uint8_t *hits = ctx->lmap_hits && ctx->lmap_hit_bits == want_bits && !ctx->section_compressed ? ctx->lmap_hits : NULL;
    for (uint32_t p = 0; p < n; p++) {
        const uint8_t *e = d + LBK_LMAP_HEADER_SIZE + (size_t)LBK_LMAP_PAGE_ENTRY_SIZE * p;
        const uint64_t o0 = lbk_rd64(e + PE_PLANE0), o1 = lbk_rd64(e + PE_PLANE1);
        const uint64_t count = (uint64_t)pw[p] * ph[p];
        uint32_t f[2];
        split_encoding(lbk_rd32(e + PE_ENCODING) & 0xffffu, f);
        const uint64_t b0 = lbk_lmap_plane_size(0, f[0], pw[p], ph[p]), b1 = lbk_lmap_plane_size(1, f[1], pw[p], ph[p]);
        if (!lbk_check_zero(ctx, 508, d, pos, o0, "LMAP")) ok = false;
        if (!lbk_check_zero(ctx, 508, d, o0 + b0, o1, "LMAP")) ok = false;
        pos = o1 + b1;
        if (f[0] == LBK_LMAP_R11G11B10F) scan_plane(ctx, &rate, 0, p, pw[p], d + o0, o0, count, &ok, hits, &next_bit);
        if (f[1] == LBK_LMAP_RGBA8) scan_plane(ctx, &rate, 1, p, pw[p], d + o1, o1, count, &ok, hits, &next_bit);
        if (f[0] == LBK_LMAP_BC6H)
            for (uint64_t b = 0; b < b0 / LBK_BC6H_BLOCK_SIZE; b++)
                if (lbk_bc6h_mode(d + o0 + LBK_BC6H_BLOCK_SIZE * b) == 0) {
                    ok = false;
                    if (lbk_rate_ok(&rate, 2))
                        lbk_vreport(ctx, 514, o0 + LBK_BC6H_BLOCK_SIZE * b,
                                    "LMAP page %u BC6H block %llu uses a reserved mode (decodes as black)", p,
                                    (unsigned long long)b);
                }
    }
    const uint32_t ids[3] = {509, 510, 514};
    lbk_rate_flush_ids(ctx, &rate, ids, 3);
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

