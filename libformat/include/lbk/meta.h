/* META: provenance key/value pairs. Layout: spec/container.md §6.
 *
 * Thread safety: every function is safe to call from any thread; views are read-only. */
#ifndef LBK_META_H
#define LBK_META_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_META_HEADER_SIZE 16u
#define LBK_META_ENTRY_SIZE 16u
#define LBK_META_MAX_KEY 64u /* bytes; keys are [a-z0-9._-]+ */

/* Well-known keys (§6.2). Bake parameters use "bake.<name>". */
#define LBK_META_WRITER "writer"                 /* program that wrote the file, e.g. "lbk" */
#define LBK_META_WRITER_VERSION "writer.version" /* its version, e.g. "1.0.0" */
#define LBK_META_SCENE_HASH "scene.hash"         /* 16 lowercase hex digits: XXH3-64 of the source scene bytes */
#define LBK_META_REVISION "revision"             /* optional free text, e.g. a VCS revision */
#define LBK_META_TIMESTAMP "timestamp"           /* only when asked for: "YYYY-MM-DDTHH:MM:SSZ" (UTC) */

/* Builder input (an array element: frozen). */
typedef struct lbk_meta_pair {
    const char *key;   /* NUL-terminated */
    const char *value; /* NUL-terminated UTF-8; may be empty */
} lbk_meta_pair;

/* Builds META bytes from pairs in any order: sorted by key, packed, deterministic. Keys must be
 * unique and 1..64 bytes of [a-z0-9._-], values valid UTF-8; otherwise LBK_ERR_INVALID_ARGUMENT.
 * *out is allocated with the allocator; free it with lbk_free. */
LBK_API lbk_result lbk_meta_build(const lbk_meta_pair *pairs, size_t count, const lbk_allocator *allocator,
                                  void **out, size_t *size);

/* A read-only view over META bytes (it points into them). */
typedef struct lbk_meta_view {
    const uint8_t *entries; /* entry_count × 16 bytes */
    const uint8_t *strings; /* the string blob */
    uint32_t entry_count;
    uint32_t strings_size;
} lbk_meta_view;

/* Checks the sizes and that every string lies inside the blob (not the key rules: that is
 * lbk_validate's job), then fills the view. LBK_ERR_TRUNCATED / LBK_ERR_CORRUPT otherwise. */
LBK_API lbk_result lbk_meta_open(const void *data, size_t size, lbk_meta_view *out);
LBK_API lbk_result lbk_meta_entry_get(const lbk_meta_view *view, uint32_t index, lbk_string *key, lbk_string *value);
/* The value of a key; LBK_ERR_NOT_FOUND if absent. */
LBK_API lbk_result lbk_meta_find(const lbk_meta_view *view, const char *key, lbk_string *value);

/* Formats a 64-bit hash as the 16 lowercase hex digits of scene.hash, plus a NUL. */
LBK_API void lbk_meta_hash_hex(uint64_t hash, char out[17]);

#ifdef __cplusplus
}
#endif
#endif
