/* LMAP section: AHD lightmap atlas pages. Layout: spec/container.md §9; texel codec: lbk/ahd.h.
 *
 * Each page has two planes that a GPU can use as they are (zero copy): plane 0 is
 * R11G11B10_FLOAT (u32 per texel), plane 1 is R8G8B8A8_UNORM; both row-major, tightly packed
 * (row pitch = 4·width bytes), each starting 16-byte aligned within the section.
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

/* Builder input: one page (an array element: frozen). texels: width·height texels, row-major,
 * in stored units (the caller encodes physical irradiance / scale). */
typedef struct lbk_lmap_page_desc {
    uint32_t width, height; /* 1..16384 */
    const lbk_ahd_texel *texels;
} lbk_lmap_page_desc;

/* Size-tagged (lbk.h): set size with LBK_LMAP_BUILD_DESC_INIT. */
typedef struct lbk_lmap_build_desc {
    size_t size;
    const lbk_lmap_page_desc *pages;
    uint32_t page_count;
    float scale; /* 0: 1; else a positive normal power of two */
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

#ifdef __cplusplus
}
#endif
#endif
