/* Private helpers shared by the liblbk sources. Not installed. */
#ifndef LBK_INTERNAL_H
#define LBK_INTERNAL_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define LBK_STATIC_LINKING_ONLY /* the library implements its experimental declarations too */
#include "lbk/dls.h"
#include "lbk/validate.h"

/* little-endian access (the file is LE whatever the host is): lbk_rd32, lbk_wr32, ... */
#include "lbk/byteorder.h"

/* ---- overflow-checked size math: return false on overflow, *out untouched --------------- */
static inline bool lbk_add_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (a > UINT64_MAX - b) return false;
    *out = a + b;
    return true;
}
static inline bool lbk_mul_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (a != 0 && b > UINT64_MAX / a) return false;
    *out = a * b;
    return true;
}
/* a + b*c */
static inline bool lbk_madd_u64(uint64_t a, uint64_t b, uint64_t c, uint64_t *out)
{
    uint64_t t;
    return lbk_mul_u64(b, c, &t) && lbk_add_u64(a, t, out);
}
/* Does [off, off+len) lie inside [0, size)? */
static inline bool lbk_range_ok(uint64_t off, uint64_t len, uint64_t size)
{
    return off <= size && len <= size - off;
}
static inline uint64_t lbk_align_up(uint64_t v, uint64_t a) { return (v + a - 1) & ~(a - 1); }

/* ---- allocation through the optional caller allocator ------------------------------------ */
void *lbk_alloc(const lbk_allocator *a, size_t size);
void *lbk_calloc(const lbk_allocator *a, size_t count, size_t size); /* overflow-checked, zeroed */
void lbk_dealloc(const lbk_allocator *a, void *p);

/* ---- size-tagged structs (lbk.h) ----------------------------------------------------------
 * Reads the caller's struct *src (NULL: all defaults) into *dst, a zeroed struct of the current
 * layout with dst->size = sizeof *dst: the caller's size (0: v1_size, its layout in liblbk 1.0)
 * decides how many bytes are copied. LBK_ERR_INVALID_ARGUMENT for a size below v1_size,
 * LBK_ERR_UNSUPPORTED_FEATURE for non-zero bytes past the fields this library knows. */
lbk_result lbk_sized_in(void *dst, size_t dst_size, const void *src, size_t v1_size);
/* The layout of liblbk 1.0 ends at field `last_v1`; fields appended later leave the calls as
 * they are. */
#define LBK_SIZED_IN(dst, src, type, last_v1) lbk_sized_in((dst), sizeof(type), (src), LBK_V1_SIZE(type, last_v1))
#define LBK_V1_SIZE(type, last) (offsetof(type, last) + sizeof(((type *)0)->last))

/* ---- validation context ---------------------------------------------------------------------
 * validate.c walks the sections in dependency order (META, REPT, LMAP, GLG, LLG, OCTP, OBJS, LMUV,
 * DLS, DOOR, TERR) and hands each section validator this context. A validator reports through lbk_vreport,
 * and fills in the facts later sections cross-check against. A fact stays zero when its section is
 * absent or unusable; *_ok flags say whether the section parsed. */
typedef struct lbk_vctx {
    lbk_issue_callback callback;
    void *user;
    lbk_validate_summary *summary;
    int stop;                      /* set when the callback asked to stop */
    const lbk_allocator *allocator;
    uint32_t section_type;         /* section being validated */
    uint64_t section_offset;       /* its file offset, for issue offsets */
    int section_compressed;        /* offsets inside compressed sections report the section start */
    uint32_t present_types[64];    /* every type listed in the section table, usable or not */
    uint32_t present_count;
    uint32_t required_features;    /* the header's (LMAP checks LBK_FEATURE_LMAP_BLOCK against its pages) */
    /* the LMAP block tests already run while its checksum was computed (lbk_lmap_hash_prescan):
     * one bit per full 1024-texel block of each 1.0 plane, in page and plane order, set where the
     * block needs the texel-by-texel scan; NULL: not available. Freed by validate.c. */
    uint8_t *lmap_hits;
    uint64_t lmap_hit_bits;

    /* facts from earlier sections */
    int lmap_ok;
    uint32_t lmap_page_count;
    /* host-endian copies, lmap_page_count each: allocated by lbk_validate_lmap with ctx->allocator,
     * freed by validate.c with lbk_dealloc at the end */
    const uint16_t *lmap_page_width;
    const uint16_t *lmap_page_height;
    uint64_t lmap_texel_count;
    int glg_ok;
    uint32_t glg_probe_count;
    int llg_ok;
    uint32_t llg_count;
    uint64_t llg_probe_count;
    int objs_ok;
    uint32_t object_count;
    /* per OBJS object, 6 u32: representation, index, rect x, y, w, h; set by lbk_validate_objs when
     * objs_ok (allocated with ctx->allocator, freed by validate.c); NULL if the allocation failed */
    uint32_t *objs_facts;
    int dls_ok;
    uint32_t dls_set_count;
    /* DLS facts for DOOR, set by lbk_validate_dls when dls_ok: one allocation (dls_facts, freed by
     * validate.c) holding each set's kind, and the members of set s at
     * dls_members[dls_member_offset[s] .. dls_member_offset[s + 1]). */
    void *dls_facts;
    const uint8_t *dls_set_kind;
    const uint32_t *dls_member_offset;
    const uint32_t *dls_members;
} lbk_vctx;

/* Is a section of this type listed in the table (whether or not it turned out usable)? */
static inline bool lbk_vctx_has_section(const lbk_vctx *ctx, uint32_t type)
{
    for (uint32_t i = 0; i < ctx->present_count; i++)
        if (ctx->present_types[i] == type) return true;
    return false;
}

/* Reports issue `id` (its severity comes from the registry) at byte `offset_in_section` of the
 * current section (or at an absolute file offset when the section type is 0). printf-style. */
void lbk_vreport(lbk_vctx *ctx, uint32_t id, uint64_t offset_in_section, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* For a checker that also runs without a context, only counting (DLS, DOOR): counts issue `id` in
 * *errors unless the registry makes it a warning; with a context also reports it (message cut at
 * 159 bytes), but an ID in [first_id, first_id + 100) at most `cap` times (reported[] counts them),
 * since a damaged array can break one rule per element. */
void lbk_vreport_capped(lbk_vctx *ctx, uint32_t *errors, uint16_t reported[100], uint32_t first_id, uint16_t cap,
                        uint32_t id, uint64_t offset_in_section, const char *fmt, va_list ap)
    __attribute__((format(printf, 8, 0)));

/* Per-section validators: each checks every rule of its section in spec/validation.md.
 * `data` are the decoded bytes. They never read outside [data, data+size). */
void lbk_validate_meta(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_rept(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_lmap(lbk_vctx *ctx, const uint8_t *data, size_t size);
/* XXH3-64 of an uncompressed LMAP section's bytes, and, while each texel block is in cache, the
 * validator's block test (lbk_vctx.lmap_hits; *hits allocated with `allocator`, NULL when the
 * section does not parse): checksum and texel validation in one pass over memory. */
uint64_t lbk_lmap_hash_prescan(const uint8_t *d, size_t size, const lbk_allocator *allocator, uint8_t **hits,
                               uint64_t *bits);
void lbk_validate_glg(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_llg(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_octp(lbk_vctx *ctx, const uint8_t *data, size_t size);
/* Bilinear lookups in one stored OCTP probe (1024 bytes at q): stored irradiance units, metres. */
void lbk_octp_probe_irradiance(const uint8_t *q, const float dir[3], float rgb[3]);
void lbk_octp_probe_depth(const uint8_t *q, const float dir[3], float m[2]);
void lbk_validate_objs(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_lmuv(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_dls(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_door(lbk_vctx *ctx, const uint8_t *data, size_t size);
void lbk_validate_terr(lbk_vctx *ctx, const uint8_t *data, size_t size);

#endif
