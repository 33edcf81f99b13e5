/* Container framing: header, section table, per-section compression and checksums.
 * Layout: spec/container.md §2–§4. Payload layouts live in the per-concept headers.
 *
 * Thread safety: a reader's const functions (header, bytes, section count/get/find) may run
 * concurrently; lbk_reader_section_data, lbk_reader_section_by_type, lbk_reader_section_unpack and
 * lbk_reader_validate (lbk/validate.h) verify, decode and cache on first access, so they need
 * the reader to themselves until every section they return was accessed once (or a lock around
 * them). A writer is used by one thread at a time. Distinct readers and
 * writers are independent. */
#ifndef LBK_CONTAINER_H
#define LBK_CONTAINER_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_HEADER_SIZE 64u
#define LBK_SECTION_ENTRY_SIZE 48u
#define LBK_DEFAULT_ALIGNMENT 64u
#define LBK_MIN_ALIGNMENT 16u
#define LBK_MAX_ALIGNMENT 65536u
#define LBK_MAX_SECTIONS 64u

/* Header required_features bits. A reader rejects any bit it does not know. */
#define LBK_FEATURE_ZSTD 0x1u       /* at least one section is zstd-compressed */
#define LBK_FEATURE_LMAP_BLOCK 0x2u /* 1.2: some LMAP page stores a plane block-compressed (spec §9.2) */
#define LBK_KNOWN_REQUIRED_FEATURES (LBK_FEATURE_ZSTD | LBK_FEATURE_LMAP_BLOCK)

/* Section entry flags. */
#define LBK_SECTION_FLAG_REQUIRED 0x1u /* a reader that does not know the type must reject the file */

typedef enum lbk_compression {
    LBK_COMPRESSION_NONE = 0,
    LBK_COMPRESSION_ZSTD = 1
} lbk_compression;

typedef struct lbk_header_info {
    uint16_t version_major, version_minor;
    uint64_t file_size;
    uint32_t required_features, optional_features;
    uint32_t section_count;
    uint32_t section_alignment;
    uint64_t section_table_offset;
} lbk_header_info;

typedef struct lbk_section_info {
    uint32_t type;
    uint32_t flags;
    uint32_t compression;      /* lbk_compression */
    uint64_t offset;           /* from the start of the file */
    uint64_t stored_size;      /* bytes in the file */
    uint64_t decoded_size;     /* bytes after decompression (== stored_size when uncompressed) */
    uint64_t checksum;         /* XXH3-64 of the stored bytes */
} lbk_section_info;

/* ---- reading ---------------------------------------------------------------------------- */

typedef struct lbk_reader lbk_reader;

/* Size-tagged (lbk.h): set size with LBK_READ_OPTIONS_INIT; NULL options mean defaults. */
typedef struct lbk_read_options {
    size_t size;
    const lbk_allocator *allocator; /* NULL: malloc/free */
    /* Cap on the total bytes the reader may allocate for decoded sections.
     * 0: min(4 GiB, 1024 × file size + 64 MiB) — see spec/container.md §4.3. */
    uint64_t max_decoded_bytes;
    /* Non-zero: do not verify section checksums in lbk_reader_section_data
     * (a console loader that verified the file once at install time). */
    int skip_checksums;
} lbk_read_options;
#define LBK_READ_OPTIONS_INIT LBK_SIZED_INIT(lbk_read_options)

/* Maps the file read-only and checks the header and section table (magic, version, features,
 * header and table checksums, ordering, alignment, bounds). Payload bytes are not touched. */
LBK_API lbk_result lbk_reader_open_file(const char *path, const lbk_read_options *options, lbk_reader **out);
/* Same over a caller buffer, which must outlive the reader (it is not copied). */
LBK_API lbk_result lbk_reader_open_memory(const void *data, size_t size, const lbk_read_options *options,
                                          lbk_reader **out);
LBK_API void lbk_reader_close(lbk_reader *reader);

LBK_API const lbk_header_info *lbk_reader_header(const lbk_reader *reader);
/* The whole file as mapped / passed in. */
LBK_API const void *lbk_reader_bytes(const lbk_reader *reader, size_t *size);
LBK_API uint32_t lbk_reader_section_count(const lbk_reader *reader);
LBK_API lbk_result lbk_reader_section_get(const lbk_reader *reader, uint32_t index, lbk_section_info *out);
/* Index of the section of a given type; LBK_ERR_NOT_FOUND if absent. */
LBK_API lbk_result lbk_reader_section_find(const lbk_reader *reader, uint32_t type, uint32_t *index);
/* The decoded bytes of a section. Uncompressed sections are returned in place (zero copy, aligned
 * as the header says); zstd sections are decoded once and cached. Verifies the checksum of the
 * stored bytes on first access unless options->skip_checksums. The pointer lives as long as the
 * reader. */
LBK_API lbk_result lbk_reader_section_data(lbk_reader *reader, uint32_t index, const void **data, size_t *size);
/* The decoded bytes of a section copied or decoded straight into caller memory (dst_size ≥ the
 * section's decoded_size, else LBK_ERR_INVALID_ARGUMENT): a loader decodes into its upload or
 * staging buffer without a second copy. Verifies the checksum once, like section_data; nothing is
 * cached and the decoded-bytes cap does not apply (the memory is the caller's). */
LBK_API lbk_result lbk_reader_section_unpack(lbk_reader *reader, uint32_t index, void *dst, size_t dst_size);
/* Convenience: find + data. */
LBK_API lbk_result lbk_reader_section_by_type(lbk_reader *reader, uint32_t type, const void **data, size_t *size);

/* ---- writing ---------------------------------------------------------------------------- */

typedef struct lbk_writer lbk_writer;

/* Size-tagged (lbk.h), both; NULL options mean defaults. */
typedef struct lbk_write_options {
    size_t size;
    const lbk_allocator *allocator; /* NULL: malloc/free */
    uint32_t section_alignment;     /* power of two in [16, 65536]; 0: 64 */
} lbk_write_options;
#define LBK_WRITE_OPTIONS_INIT LBK_SIZED_INIT(lbk_write_options)

typedef struct lbk_section_options {
    size_t size;
    uint32_t flags;        /* LBK_SECTION_FLAG_*; 0: optional */
    uint32_t compression;  /* lbk_compression; 0: none */
    int zstd_level;        /* 0: 19 */
} lbk_section_options;
#define LBK_SECTION_OPTIONS_INIT LBK_SIZED_INIT(lbk_section_options)

LBK_API lbk_result lbk_writer_open(const lbk_write_options *options, lbk_writer **out);
LBK_API void lbk_writer_close(lbk_writer *writer);
/* Copies the bytes. Each type may be added once. Sections are written in the canonical order of
 * spec/container.md §3 regardless of the order they are added in, so output is deterministic. */
LBK_API lbk_result lbk_writer_section_add(lbk_writer *writer, uint32_t type, const void *data, size_t size,
                                          const lbk_section_options *options);
/* Serialises into one buffer allocated with the writer's allocator; free it with lbk_free. */
LBK_API lbk_result lbk_writer_to_memory(lbk_writer *writer, void **out, size_t *size);
/* Writes atomically: a temp file beside path, fsync, rename, fsync of the directory. Only a
 * regular file, a symlink (the rename replaces the link, not its target) or nothing is ever
 * replaced: a device, FIFO, socket or directory at path gives LBK_ERR_INVALID_ARGUMENT. */
LBK_API lbk_result lbk_writer_to_file(lbk_writer *writer, const char *path);

#ifdef __cplusplus
}
#endif
#endif
