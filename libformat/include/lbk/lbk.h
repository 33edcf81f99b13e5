/* liblbk — the light bake kit container library.
 *
 * Conventions (the style of zstd and OpenEXRCore):
 *   - every fallible call returns lbk_result; lbk_result_name() names it;
 *   - no printing, no exit(), no globals; all memory through an optional lbk_allocator;
 *   - every options struct is valid when zero-initialised ("defaults");
 *   - handles are opaque.
 * The library depends on libzstd and libxxhash only. */
#ifndef LBK_LBK_H
#define LBK_LBK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(LBK_BUILDING_SHARED) && defined(__GNUC__)
#define LBK_API __attribute__((visibility("default")))
#else
#define LBK_API
#endif

#define LBK_FORMAT_VERSION_MAJOR 1 /* container format major version written by this library */
#define LBK_FORMAT_VERSION_MINOR 0 /* container format minor version written by this library */
#define LBK_LIBRARY_VERSION_STRING "1.0.0"

typedef enum lbk_result {
    LBK_OK = 0,
    LBK_ERR_INVALID_ARGUMENT,   /* caller passed something the API forbids */
    LBK_ERR_OUT_OF_MEMORY,
    LBK_ERR_IO,                 /* open/read/write/fsync/rename failed; see errno */
    LBK_ERR_NOT_LBK,            /* magic mismatch: not a container, or text-mode damaged */
    LBK_ERR_TRUNCATED,          /* the bytes end before the structure they describe */
    LBK_ERR_UNSUPPORTED_VERSION,/* unknown major version */
    LBK_ERR_UNSUPPORTED_FEATURE,/* unknown required feature flag or required section */
    LBK_ERR_CORRUPT,            /* a structural rule of spec/container.md is broken */
    LBK_ERR_CHECKSUM,           /* a stored checksum does not match */
    LBK_ERR_DECOMPRESS,         /* zstd failed or decoded to the wrong length */
    LBK_ERR_NOT_FOUND,          /* asked-for section or entry does not exist */
    LBK_ERR_LIMIT,              /* a size exceeds a cap (caller's or the file's) */
    LBK_ERR_RANGE,              /* a value is outside what the encoding can hold */
    LBK_ERR_OVERLAPS,           /* more dynamic-set overlaps than the DLS forms allow */
    LBK_RESULT_COUNT_
} lbk_result;

/* A stable upper-case identifier such as "LBK_ERR_CHECKSUM"; never NULL. */
LBK_API const char *lbk_result_name(lbk_result r);
/* A one-line English description; never NULL. */
LBK_API const char *lbk_result_message(lbk_result r);

/* Optional caller allocator. A NULL pointer or an all-zero struct means malloc/free.
 * alloc must return memory aligned to at least 16 bytes. */
typedef struct lbk_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} lbk_allocator;

/* Four-character section type codes, stored little-endian (first char in the lowest byte). */
#define LBK_FOURCC(a, b, c, d) \
    ((uint32_t)(uint8_t)(a) | ((uint32_t)(uint8_t)(b) << 8) | ((uint32_t)(uint8_t)(c) << 16) | ((uint32_t)(uint8_t)(d) << 24))

#define LBK_SECTION_META LBK_FOURCC('M', 'E', 'T', 'A') /* provenance key/values */
#define LBK_SECTION_REPT LBK_FOURCC('R', 'E', 'P', 'T') /* bake report: error vs time */
#define LBK_SECTION_OBJS LBK_FOURCC('O', 'B', 'J', 'S') /* object table */
#define LBK_SECTION_LMAP LBK_FOURCC('L', 'M', 'A', 'P') /* AHD lightmap atlas pages */
#define LBK_SECTION_GLG  LBK_FOURCC('G', 'L', 'G', ' ') /* global light grid */
#define LBK_SECTION_LLG  LBK_FOURCC('L', 'L', 'G', ' ') /* local light grids */
#define LBK_SECTION_DLS  LBK_FOURCC('D', 'L', 'S', ' ') /* dynamic light sets + clusters */
#define LBK_SECTION_DOOR LBK_FOURCC('D', 'O', 'O', 'R') /* interactive elements */
#define LBK_SECTION_OCTP LBK_FOURCC('O', 'C', 'T', 'P') /* octahedral probes (GIBS style) */

/* Writes the 4 characters of a type code plus a NUL into out[5]; non-printable bytes become '?'. */
LBK_API void lbk_fourcc_string(uint32_t type, char out[5]);

/* A byte string that is not NUL-terminated: views into a container point at its string blobs. */
typedef struct lbk_string {
    const char *data;
    size_t size;
} lbk_string;

/* XXH3-64 (seed 0) of a byte range: the hash the format uses for checksums and provenance. */
LBK_API uint64_t lbk_hash64(const void *data, size_t size);

#ifdef __cplusplus
}
#endif
#endif
