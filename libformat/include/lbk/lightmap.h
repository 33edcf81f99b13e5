/* LMAP section: AHD lightmap atlas pages. Layout: spec/container.md §9; texel codec: lbk/ahd.h.
 *
 * Each page has two planes that a GPU can use as they are (zero copy). In format 1.0/1.1 plane 0
 * is R11G11B10_FLOAT (u32 per texel) and plane 1 R8G8B8A8_UNORM, row-major, tightly packed (row
 * pitch = 4·width bytes), each starting 16-byte aligned within the section. Format 1.2 lets a
 * page store a plane block-compressed (spec §9.2, the page's `encoding`): plane 0 as BC6H_UF16 or
 * ASTC 4×4 HDR, plane 1 as BC5 (direction) + BC4 (ratio) or ASTC 4×4 LDR, 4×4 blocks row-major,
 * the page's width and height multiples of 4; a file with such a page sets the header's required
 * feature LBK_FEATURE_LMAP_BLOCK. lbk_lmap_page_get and the functions on lbk_lmap_page read
 * 1.0 pages only (LBK_ERR_UNSUPPORTED_FEATURE for a block page, whose planes they cannot
 * describe); lbk_lmap_planes_get and the lbk_lmap_planes_* functions read every page.
 *
 * Texel index space (used by DLS and the object table): pages in table order, each row-major:
 *     texel_index = first_texel(page) + y·width + x,   first_texel(p) = Σ_{q<p} width_q·height_q.
 *
 * Scale: one f32 power of two in the section header, stored texel × scale = irradiance in lux
 * (the rule for every lighting section: lbk.h, "radiometric scale").
 *
 * Thread safety: every function is safe to call from any thread; views are read-only. */
#ifndef LBK_LIGHTMAP_H
#define LBK_LIGHTMAP_H

#include "lbk/ahd.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_LMAP_HEADER_SIZE 16u
#define LBK_LMAP_PAGE_ENTRY_SIZE 32u
#define LBK_LMAP_MAX_DIM 16384u

/* Plane encodings (spec §9.2): a page entry's `encoding` is format0 | format1 << 8. */
typedef enum lbk_lmap_format0 {
    LBK_LMAP_R11G11B10F = 0,   /* 4 bytes per texel */
    LBK_LMAP_BC6H = 1,         /* BC6H_UF16: 16 bytes per 4×4 block */
    LBK_LMAP_ASTC4X4_HDR = 2,  /* ASTC 4×4, HDR RGB (alpha 1): 16 bytes per block */
    LBK_LMAP_FORMAT0_COUNT_
} lbk_lmap_format0;
typedef enum lbk_lmap_format1 {
    LBK_LMAP_RGBA8 = 0,        /* 4 bytes per texel: ratio, direction x, y, z */
    LBK_LMAP_BC5_BC4 = 1,      /* BC5 of the direction (x, y) (16 B/block), then at the next multiple
                                  of 16 BC4 of the ratio (8 B/block); d.z = √(max(0, 1 − x² − y²)) */
    LBK_LMAP_ASTC4X4_LDR = 2,  /* ASTC 4×4 LDR RGBA with the RGBA8 meaning: 16 bytes per block */
    LBK_LMAP_FORMAT1_COUNT_
} lbk_lmap_format1;
#define LBK_LMAP_BLOCK 4u      /* texels per side of every block encoding */

/* Bytes of a plane (0 or 1) of a width × height page in `format`; 0 when the format is unknown,
 * or a block format and a side is not a multiple of 4. */
LBK_API uint64_t lbk_lmap_plane_size(uint32_t plane, uint32_t format, uint32_t width, uint32_t height);

/* Builder input: one page (an array element: frozen). texels: width·height texels, row-major,
 * in stored units (the caller encodes physical irradiance / scale). */
typedef struct lbk_lmap_page_desc {
    uint32_t width, height; /* 1..16384 */
    const lbk_ahd_texel *texels;
} lbk_lmap_page_desc;

/* Builder input for a page with encoded planes (an array element: frozen; 1.2). plane[i] holds
 * lbk_lmap_plane_size(i, format[i], width, height) bytes, already encoded (the encoders are the
 * tools': tools/convert/lmap_encode.h). */
typedef struct lbk_lmap_encoded_page {
    uint32_t width, height;
    uint32_t format[2];  /* lbk_lmap_format0, lbk_lmap_format1 */
    const void *plane[2];
} lbk_lmap_encoded_page;

/* Size-tagged (lbk.h): set size with LBK_LMAP_BUILD_DESC_INIT. */
typedef struct lbk_lmap_build_desc {
    size_t size;
    const lbk_lmap_page_desc *pages;
    uint32_t page_count;
    float scale; /* 0: 1; else a positive normal power of two */
    /* 1.2: when non-NULL, the pages come from here (page_count of them) and `pages` is unused */
    const lbk_lmap_encoded_page *encoded;
} lbk_lmap_build_desc;
#define LBK_LMAP_BUILD_DESC_INIT LBK_SIZED_INIT(lbk_lmap_build_desc)

/* Serialises the pages into section bytes (deterministic; padding zero). The buffer is allocated
 * with `allocator` (NULL: malloc); free it with lbk_free. */
LBK_API lbk_result lbk_lmap_build(const lbk_lmap_build_desc *desc, const lbk_allocator *allocator, void **out,
                                  size_t *size);

/* A read-only view into section bytes (nothing is copied). lbk_lmap_open checks the structure
 * (header, page table, plane layout, size); it does not scan texels — lbk_validate does. */
typedef struct lbk_lmap_view {
    const uint8_t *data;
    size_t size;
    uint32_t page_count;
    uint64_t texel_count;
    float scale; /* stored × scale = physical; a power of two */
} lbk_lmap_view;

typedef struct lbk_lmap_page {
    uint32_t width, height;
    uint64_t first_texel;
    const uint8_t *irradiance; /* plane 0: width·height u32 little-endian R11G11B10F */
    const uint8_t *rgba;       /* plane 1: width·height × 4 bytes */
    uint64_t irradiance_offset, rgba_offset; /* byte offsets within the section */
    float scale; /* the section's scale, so that lbk_lmap_page_irradiance needs only the page */
} lbk_lmap_page;

LBK_API lbk_result lbk_lmap_open(const void *data, size_t size, lbk_lmap_view *out);
/* A 1.0 page (R11G11B10F + RGBA8); LBK_ERR_UNSUPPORTED_FEATURE for a block-encoded page. */
LBK_API lbk_result lbk_lmap_page_get(const lbk_lmap_view *view, uint32_t index, lbk_lmap_page *out);
/* One texel of a page, encoded in stored units; x < width, y < height (LBK_ERR_NOT_FOUND otherwise). */
LBK_API lbk_result lbk_lmap_page_texel_get(const lbk_lmap_page *page, uint32_t x, uint32_t y,
                                           lbk_ahd_texel *out);
/* A texel by its global index; also returns its page (optional). */
LBK_API lbk_result lbk_lmap_texel_get(const lbk_lmap_view *view, uint64_t texel_index, lbk_ahd_texel *out,
                                      uint32_t *page_out);
/* Physical irradiance of texel (x, y) for the tangent-space unit normal n (lbk_ahd_irradiance
 * of the stored texel × the section's scale). */
LBK_API lbk_result lbk_lmap_page_irradiance(const lbk_lmap_page *page, uint32_t x, uint32_t y, const float n[3],
                                            float rgb[3]);

/* ---- every page, any encoding (1.2) ----------------------------------------------------------- */

/* A page's planes as stored (a view into the section's bytes). */
typedef struct lbk_lmap_planes {
    uint32_t width, height;
    uint64_t first_texel;
    uint32_t format[2];         /* lbk_lmap_format0, lbk_lmap_format1 */
    const uint8_t *plane[2];    /* the bytes of each plane */
    uint64_t offset[2], bytes[2]; /* within the section */
    uint32_t blocks_x, blocks_y;  /* 4×4 blocks per row and column (width/4, height/4) when a plane
                                     is block-encoded, else 0 */
    float scale;                /* the section's */
} lbk_lmap_planes;

LBK_API lbk_result lbk_lmap_planes_get(const lbk_lmap_view *view, uint32_t index, lbk_lmap_planes *out);
/* Texel (x, y) decoded to floats as a GPU samples it (lbk/ahd.h lbk_ahd_texel_f), in stored units:
 * exactly lbk_ahd_texel_f_from_texel of the stored texel for a 1.0 page; the BC6H / BC4 / BC5
 * decoders of lbk/bc.h for block planes. LBK_ERR_UNSUPPORTED_FEATURE for ASTC planes (decoded by the
 * tools, tools/common/lmap_decode.h), LBK_ERR_NOT_FOUND outside the page. */
LBK_API lbk_result lbk_lmap_planes_texel_unpack(const lbk_lmap_planes *planes, uint32_t x, uint32_t y,
                                                lbk_ahd_texel_f *out);
/* Physical irradiance of texel (x, y) for the tangent-space unit normal n: for a 1.0 page the same
 * bits as lbk_lmap_page_irradiance. */
LBK_API lbk_result lbk_lmap_planes_irradiance(const lbk_lmap_planes *planes, uint32_t x, uint32_t y, const float n[3],
                                              float rgb[3]);
/* GPU bytes of the texels [x, x + w) × [y, y + h): 8 per texel for R11G11B10F + RGBA8; for block
 * planes every block the rectangle touches (whole blocks are what a GPU holds). 0 when the
 * rectangle is not inside the page. */
LBK_API uint64_t lbk_lmap_planes_rect_bytes(const lbk_lmap_planes *planes, uint32_t x, uint32_t y, uint32_t w,
                                            uint32_t h);
/* The header's required features an LMAP payload needs: LBK_FEATURE_LMAP_BLOCK when some page is
 * block-encoded (the writer sets it; spec §2). 0 for bytes that do not parse. */
LBK_API uint32_t lbk_lmap_required_features(const void *data, size_t size);

#ifdef __cplusplus
}
#endif
#endif
