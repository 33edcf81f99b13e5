/* Container framing checks shared by the reader (stops at the first problem) and the validator
 * (reports every problem it can). One implementation of spec/container.md §2–§4, so the two can
 * never disagree about what a valid file is. Private. */
#ifndef LBK_FRAMING_H
#define LBK_FRAMING_H

#include <stdarg.h>

#include "internal.h"

/* Header field offsets (spec/container.md §2). */
enum {
    LBK_HDR_MAGIC = 0,
    LBK_HDR_VERSION_MAJOR = 8,
    LBK_HDR_VERSION_MINOR = 10,
    LBK_HDR_HEADER_SIZE = 12,
    LBK_HDR_FILE_SIZE = 16,
    LBK_HDR_REQUIRED_FEATURES = 24,
    LBK_HDR_OPTIONAL_FEATURES = 28,
    LBK_HDR_SECTION_COUNT = 32,
    LBK_HDR_SECTION_ALIGNMENT = 36,
    LBK_HDR_TABLE_OFFSET = 40,
    LBK_HDR_TABLE_CHECKSUM = 48,
    LBK_HDR_HEADER_CHECKSUM = 56
};
/* Section entry field offsets (§3.1). */
enum {
    LBK_ENT_TYPE = 0,
    LBK_ENT_FLAGS = 4,
    LBK_ENT_COMPRESSION = 8,
    LBK_ENT_RESERVED = 12,
    LBK_ENT_OFFSET = 16,
    LBK_ENT_STORED_SIZE = 24,
    LBK_ENT_DECODED_SIZE = 32,
    LBK_ENT_CHECKSUM = 40
};

extern const uint8_t lbk_magic[8];

/* Receives one problem: its registry ID, the lbk_result a reader returns for it, the section type
 * it concerns (0: header/table), the absolute file offset, and a printf-style message.
 * Returns non-zero to stop. */
typedef int (*lbk_framing_report_fn)(void *user, uint32_t id, lbk_result result, uint32_t section_type,
                                     uint64_t offset, const char *fmt, va_list ap);

typedef struct lbk_framing {
    lbk_header_info header;
    int header_ok;                               /* header and table can be trusted */
    uint32_t count;                              /* table entries read */
    lbk_section_info sections[LBK_MAX_SECTIONS];
    uint8_t usable[LBK_MAX_SECTIONS];            /* entry passed the table checks (known type or not) */
} lbk_framing;

/* Checks the header, the table, placement and padding, reporting every problem it can.
 * Returns non-zero when it stopped early (a fatal header problem, or report asked to stop);
 * out->header_ok says whether the header and the table can be trusted. */
int lbk_framing_parse(const uint8_t *data, size_t size, lbk_framing *out, lbk_framing_report_fn report,
                      void *user);

/* 1..9 for the v1.0 types in canonical order, 0 for unknown types. */
int lbk_section_rank(uint32_t type);
int lbk_section_known(uint32_t type); /* a 1.0 type or one a later minor version added */
/* Sort key of the canonical order (§3.2): 1.0 types by rank, then every other type by code. */
uint64_t lbk_section_order_key(uint32_t type);
/* Four printable ASCII characters (0x20..0x7e)? */
int lbk_fourcc_printable(uint32_t type);

/* Loads one section whose entry passed the table checks: verifies the stored checksum (unless
 * skip_checksum), and for zstd checks the frame, charges decoded_size against *budget_left and
 * decodes into memory from the allocator (*owned; caller frees with lbk_dealloc).
 * On failure returns the result and sets *issue_id (spec/validation.md). */
lbk_result lbk_section_load(const uint8_t *file, const lbk_section_info *s, const lbk_allocator *allocator,
                            int skip_checksum, uint64_t *budget_left, const uint8_t **data, void **owned,
                            uint32_t *issue_id);

/* Default cap on decoded bytes (§4.3). */
uint64_t lbk_default_decode_cap(uint64_t file_size);

/* Maps a whole file read-only. *size 0 gives *data NULL and no mapping. */
lbk_result lbk_map_file(const char *path, const uint8_t **data, size_t *size);
void lbk_unmap_file(const uint8_t *data, size_t size);

#endif
