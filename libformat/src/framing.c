/* Header, section table, placement and padding checks (spec/container.md §2–§4), section loading
 * (checksum, zstd frame checks, decoded-bytes budget) and file mapping. */
#define ZSTD_STATIC_LINKING_ONLY /* ZSTD_createDCtx_advanced: route zstd's memory through the caller */
#include <errno.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include "xxh.h"
#include <zstd.h>
#include <zstd_errors.h>

#include "framing.h"
#include "lbk/error_map.h"

const uint8_t lbk_magic[8] = {0x89, 'L', 'B', 'K', 0x0d, 0x0a, 0x1a, 0x0a};

static const uint32_t canonical_order[] = {
    LBK_SECTION_META, LBK_SECTION_REPT, LBK_SECTION_OBJS, LBK_SECTION_LMAP, LBK_SECTION_GLG,
    LBK_SECTION_LLG,  LBK_SECTION_DLS,  LBK_SECTION_DOOR, LBK_SECTION_OCTP,
};

int lbk_section_rank(uint32_t type)
{
    for (int i = 0; i < (int)(sizeof canonical_order / sizeof canonical_order[0]); i++)
        if (canonical_order[i] == type) return i + 1;
    return 0;
}

/* Types added by a minor version have no rank: they sort after the 1.0 types by ascending code,
 * exactly where a 1.0 reader expects a type it does not know (§3.2), so it accepts the order. */
int lbk_section_known(uint32_t type)
{
    return lbk_section_rank(type) != 0 || type == LBK_SECTION_LMUV || type == LBK_SECTION_TERR;
}

uint64_t lbk_default_decode_cap(uint64_t file_size)
{
    const uint64_t four_gib = (uint64_t)4 << 30;
    uint64_t cap;
    if (!lbk_madd_u64((uint64_t)64 << 20, 1024, file_size, &cap) || cap > four_gib) cap = four_gib;
    return cap;
}

static int report(lbk_framing_report_fn fn, void *user, uint32_t id, lbk_result r, uint32_t type, uint64_t off,
                  const char *fmt, ...) __attribute__((format(printf, 7, 8)));
static int report(lbk_framing_report_fn fn, void *user, uint32_t id, lbk_result r, uint32_t type, uint64_t off,
                  const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int stop = fn(user, id, r, type, off, fmt, ap);
    va_end(ap);
    return stop;
}
#define REPORT(...)                                          \
    do {                                                     \
        if (report(fn, user, __VA_ARGS__)) return 1;         \
    } while (0)

int lbk_fourcc_printable(uint32_t t)
{
    for (int i = 0; i < 4; i++) {
        unsigned c = (t >> (8 * i)) & 0xffu;
        if (c < 0x20 || c > 0x7e) return 0;
    }
    return 1;
}

/* Sort key of §3.2: known types by rank, then unknown types by ascending code. */
uint64_t lbk_section_order_key(uint32_t type)
{
    int rank = lbk_section_rank(type);
    return rank ? (uint64_t)rank : ((uint64_t)1 << 32) + type;
}

/* Offset of the first non-zero byte in [from, to), or `to` if all zero. */
static uint64_t first_nonzero(const uint8_t *d, uint64_t from, uint64_t to)
{
    for (uint64_t i = from; i < to; i++)
        if (d[i]) return i;
    return to;
}

static int check_header(const uint8_t *d, size_t size, lbk_framing *out, lbk_framing_report_fn fn, void *user)
{
    if (size < LBK_HEADER_SIZE) {
        report(fn, user, 100, LBK_ERR_TRUNCATED, 0, 0, "file is %zu bytes, shorter than the 64-byte header%s", size,
               size >= 4 && !memcmp(d, lbk_magic, 4) ? " (a truncated lbk file)" : "");
        return 1;
    }
    if (memcmp(d, lbk_magic, 8)) {
        if (!memcmp(d + 1, "LBK", 3) && (d[0] == 0x09 || d[0] == 0x89))
            report(fn, user, 102, LBK_ERR_NOT_LBK, 0, 0,
                   "magic %02x %02x %02x %02x %02x %02x %02x %02x: an lbk file damaged by a text-mode or 7-bit "
                   "transfer",
                   d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]);
        else
            report(fn, user, 101, LBK_ERR_NOT_LBK, 0, 0,
                   "magic %02x %02x %02x %02x %02x %02x %02x %02x is not an lbk container", d[0], d[1], d[2], d[3],
                   d[4], d[5], d[6], d[7]);
        return 1;
    }
    lbk_header_info *h = &out->header;
    h->version_major = lbk_rd16(d + LBK_HDR_VERSION_MAJOR);
    h->version_minor = lbk_rd16(d + LBK_HDR_VERSION_MINOR);
    if (h->version_major != LBK_FORMAT_VERSION_MAJOR) {
        REPORT(103, LBK_ERR_UNSUPPORTED_VERSION, 0, LBK_HDR_VERSION_MAJOR,
               "major version %u is not supported (this reader knows %u)", h->version_major, LBK_FORMAT_VERSION_MAJOR);
        return 1;
    }
    uint64_t stored_hc = lbk_rd64(d + LBK_HDR_HEADER_CHECKSUM), hc = XXH3_64bits(d, LBK_HDR_HEADER_CHECKSUM);
    if (stored_hc != hc) {
        REPORT(104, LBK_ERR_CHECKSUM, 0, LBK_HDR_HEADER_CHECKSUM,
               "header checksum %016llx does not match the header bytes (%016llx)", (unsigned long long)stored_hc,
               (unsigned long long)hc);
        return 1;
    }
    uint32_t header_size = lbk_rd32(d + LBK_HDR_HEADER_SIZE);
    if (header_size != LBK_HEADER_SIZE) {
        REPORT(105, LBK_ERR_CORRUPT, 0, LBK_HDR_HEADER_SIZE, "header_size is %u, must be 64", header_size);
        return 1;
    }
    h->file_size = lbk_rd64(d + LBK_HDR_FILE_SIZE);
    if (h->file_size > size) {
        REPORT(106, LBK_ERR_TRUNCATED, 0, LBK_HDR_FILE_SIZE,
               "file is truncated: header says %llu bytes, only %zu present", (unsigned long long)h->file_size, size);
        return 1;
    }
    if (h->file_size < size) {
        REPORT(107, LBK_ERR_CORRUPT, 0, LBK_HDR_FILE_SIZE,
               "%llu bytes follow the end of the container (header says %llu bytes, file has %zu)",
               (unsigned long long)(size - h->file_size), (unsigned long long)h->file_size, size);
        return 1;
    }
    if (h->version_minor > LBK_FORMAT_VERSION_MINOR)
        REPORT(115, LBK_OK, 0, LBK_HDR_VERSION_MINOR,
               "minor version %u is newer than this reader's %u; newer optional content is skipped",
               h->version_minor, LBK_FORMAT_VERSION_MINOR);
    h->required_features = lbk_rd32(d + LBK_HDR_REQUIRED_FEATURES);
    h->optional_features = lbk_rd32(d + LBK_HDR_OPTIONAL_FEATURES);
    if (h->required_features & ~LBK_KNOWN_REQUIRED_FEATURES) {
        REPORT(108, LBK_ERR_UNSUPPORTED_FEATURE, 0, LBK_HDR_REQUIRED_FEATURES,
               "unknown required feature bits 0x%08x", h->required_features & ~LBK_KNOWN_REQUIRED_FEATURES);
        return 1;
    }
    if (h->optional_features)
        REPORT(109, LBK_OK, 0, LBK_HDR_OPTIONAL_FEATURES, "unknown optional feature bits 0x%08x ignored",
               h->optional_features);
    h->section_count = lbk_rd32(d + LBK_HDR_SECTION_COUNT);
    if (h->section_count < 1 || h->section_count > LBK_MAX_SECTIONS) {
        REPORT(110, LBK_ERR_CORRUPT, 0, LBK_HDR_SECTION_COUNT, "section_count %u is outside 1..%u",
               h->section_count, LBK_MAX_SECTIONS);
        return 1;
    }
    h->section_alignment = lbk_rd32(d + LBK_HDR_SECTION_ALIGNMENT);
    uint32_t a = h->section_alignment;
    if (a < LBK_MIN_ALIGNMENT || a > LBK_MAX_ALIGNMENT || (a & (a - 1))) {
        REPORT(111, LBK_ERR_CORRUPT, 0, LBK_HDR_SECTION_ALIGNMENT,
               "section_alignment %u is not a power of two in 16..65536", a);
        return 1;
    }
    h->section_table_offset = lbk_rd64(d + LBK_HDR_TABLE_OFFSET);
    if (h->section_table_offset != LBK_HEADER_SIZE) {
        REPORT(112, LBK_ERR_CORRUPT, 0, LBK_HDR_TABLE_OFFSET, "section_table_offset is %llu, must be 64",
               (unsigned long long)h->section_table_offset);
        return 1;
    }
    uint64_t table_bytes = (uint64_t)LBK_SECTION_ENTRY_SIZE * h->section_count;
    if (!lbk_range_ok(LBK_HEADER_SIZE, table_bytes, h->file_size)) {
        REPORT(113, LBK_ERR_TRUNCATED, 0, LBK_HDR_SECTION_COUNT,
               "the table of %u sections (%llu bytes) runs past the end of the %llu-byte file", h->section_count,
               (unsigned long long)table_bytes, (unsigned long long)h->file_size);
        return 1;
    }
    uint64_t stored_tc = lbk_rd64(d + LBK_HDR_TABLE_CHECKSUM), tc = XXH3_64bits(d + LBK_HEADER_SIZE, table_bytes);
    if (stored_tc != tc) {
        REPORT(114, LBK_ERR_CHECKSUM, 0, LBK_HDR_TABLE_CHECKSUM,
               "section table checksum %016llx does not match the table bytes (%016llx)",
               (unsigned long long)stored_tc, (unsigned long long)tc);
        return 1;
    }
    return 0;
}

int lbk_framing_parse(const uint8_t *d, size_t size, lbk_framing *out, lbk_framing_report_fn fn, void *user)
{
    memset(out, 0, sizeof *out);
    if (!d) size = 0;
    if (check_header(d, size, out, fn, user)) return 1; /* fatal: reported, nothing further can be read */
    out->header_ok = 1;

    const lbk_header_info *h = &out->header;
    const uint64_t file_size = h->file_size, align = h->section_alignment;
    uint64_t prev_end = LBK_HEADER_SIZE + (uint64_t)LBK_SECTION_ENTRY_SIZE * h->section_count;
    uint64_t prev_key = 0;
    int placement_broken = 0, any_zstd = 0;
    out->count = h->section_count;

    for (uint32_t i = 0; i < h->section_count; i++) {
        const uint64_t eo = LBK_HEADER_SIZE + (uint64_t)LBK_SECTION_ENTRY_SIZE * i;
        const uint8_t *e = d + eo;
        lbk_section_info *s = &out->sections[i];
        s->type = lbk_rd32(e + LBK_ENT_TYPE);
        s->flags = lbk_rd32(e + LBK_ENT_FLAGS);
        s->compression = lbk_rd32(e + LBK_ENT_COMPRESSION);
        s->offset = lbk_rd64(e + LBK_ENT_OFFSET);
        s->stored_size = lbk_rd64(e + LBK_ENT_STORED_SIZE);
        s->decoded_size = lbk_rd64(e + LBK_ENT_DECODED_SIZE);
        s->checksum = lbk_rd64(e + LBK_ENT_CHECKSUM);
        uint32_t reserved = lbk_rd32(e + LBK_ENT_RESERVED);
        char cc[5];
        lbk_fourcc_string(s->type, cc);
        int usable = 1;

        if (!lbk_fourcc_printable(s->type)) {
            REPORT(200, LBK_ERR_CORRUPT, 0, eo + LBK_ENT_TYPE,
                   "section %u: type 0x%08x is not four printable ASCII characters", i, s->type);
            usable = 0;
        }
        int duplicate = 0;
        for (uint32_t j = 0; j < i; j++)
            if (out->sections[j].type == s->type) duplicate = 1;
        if (duplicate) {
            REPORT(201, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_TYPE, "section %u: type '%s' appears more than once",
                   i, cc);
            usable = 0;
        } else {
            uint64_t key = lbk_section_order_key(s->type);
            if (key <= prev_key)
                REPORT(202, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_TYPE,
                       "section %u: type '%s' is out of the canonical order", i, cc);
            else
                prev_key = key;
        }
        if (s->flags & ~LBK_SECTION_FLAG_REQUIRED)
            REPORT(203, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_FLAGS, "section %u ('%s'): unknown flag bits 0x%08x", i,
                   cc, s->flags & ~LBK_SECTION_FLAG_REQUIRED);
        if (s->compression > LBK_COMPRESSION_ZSTD) {
            REPORT(204, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_COMPRESSION,
                   "section %u ('%s'): unknown compression method %u", i, cc, s->compression);
            usable = 0;
        }
        if (s->compression == LBK_COMPRESSION_ZSTD) any_zstd = 1;
        if (reserved)
            REPORT(205, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_RESERVED,
                   "section %u ('%s'): reserved field is 0x%08x, must be 0", i, cc, reserved);
        if (s->stored_size == 0) {
            REPORT(207, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_STORED_SIZE, "section %u ('%s'): stored_size is 0", i,
                   cc);
            usable = 0;
        }
        if (s->compression == LBK_COMPRESSION_NONE && s->decoded_size != s->stored_size) {
            REPORT(209, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_DECODED_SIZE,
                   "section %u ('%s'): uncompressed but decoded_size %llu != stored_size %llu", i, cc,
                   (unsigned long long)s->decoded_size, (unsigned long long)s->stored_size);
            usable = 0;
        }
        if (s->compression == LBK_COMPRESSION_ZSTD && s->decoded_size == 0) {
            REPORT(220, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_DECODED_SIZE,
                   "section %u ('%s'): compressed section with decoded_size 0", i, cc);
            usable = 0;
        }
        int in_file = lbk_range_ok(s->offset, s->stored_size, file_size);
        if (!in_file) {
            REPORT(208, LBK_ERR_TRUNCATED, s->type, eo + LBK_ENT_OFFSET,
                   "section %u ('%s'): bytes %llu..+%llu run past the end of the %llu-byte file", i, cc,
                   (unsigned long long)s->offset, (unsigned long long)s->stored_size, (unsigned long long)file_size);
            usable = 0;
        }
        if (!placement_broken) {
            uint64_t expected = lbk_align_up(prev_end, align);
            if (s->offset != expected) {
                REPORT(206, LBK_ERR_CORRUPT, s->type, eo + LBK_ENT_OFFSET,
                       "section %u ('%s'): offset %llu, the layout rule of §3.3 puts it at %llu", i, cc,
                       (unsigned long long)s->offset, (unsigned long long)expected);
                usable = 0;
            }
            if (in_file && s->offset >= prev_end) {
                uint64_t nz = first_nonzero(d, prev_end, s->offset);
                if (nz != s->offset)
                    REPORT(211, LBK_ERR_CORRUPT, 0, nz, "padding byte at offset %llu is 0x%02x, must be 0",
                           (unsigned long long)nz, d[nz]);
                prev_end = s->offset + s->stored_size;
            } else {
                placement_broken = 1;
            }
        }
        if (usable && !lbk_section_known(s->type)) {
            if (s->flags & LBK_SECTION_FLAG_REQUIRED) {
                REPORT(212, LBK_ERR_UNSUPPORTED_FEATURE, s->type, eo + LBK_ENT_TYPE,
                       "section %u: unknown section type '%s' is marked required", i, cc);
                usable = 0;
            } else {
                REPORT(213, LBK_OK, s->type, eo + LBK_ENT_TYPE, "section %u: unknown optional section '%s' skipped",
                       i, cc);
            }
        }
        out->usable[i] = (uint8_t)usable;
    }
    if (!placement_broken && prev_end != file_size)
        REPORT(210, LBK_ERR_CORRUPT, 0, prev_end,
               "the last section ends at %llu but the file is %llu bytes (bytes after the last section)",
               (unsigned long long)prev_end, (unsigned long long)file_size);
    if (((h->required_features & LBK_FEATURE_ZSTD) != 0) != any_zstd)
        REPORT(116, LBK_ERR_CORRUPT, 0, LBK_HDR_REQUIRED_FEATURES,
               "required feature ZSTD is %s but %s section is zstd-compressed",
               (h->required_features & LBK_FEATURE_ZSTD) ? "set" : "clear", any_zstd ? "a" : "no");
    return 0;
}

/* ---- section loading --------------------------------------------------------------------- */

static void *zstd_alloc(void *user, size_t size) { return lbk_alloc((const lbk_allocator *)user, size); }
static void zstd_free(void *user, void *p) { lbk_dealloc((const lbk_allocator *)user, p); }

lbk_result lbk_section_frame_check(const uint8_t *file, const lbk_section_info *s, uint32_t *issue_id)
{
    const uint8_t *stored = file + s->offset;
    unsigned long long content = ZSTD_getFrameContentSize(stored, (size_t)s->stored_size);
    if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN) {
        *issue_id = 215;
        return LBK_ERR_DECOMPRESS;
    }
    if (content != s->decoded_size) {
        *issue_id = 216;
        return LBK_ERR_DECOMPRESS;
    }
    size_t frame = ZSTD_findFrameCompressedSize(stored, (size_t)s->stored_size);
    if (ZSTD_isError(frame) || frame != s->stored_size) {
        *issue_id = ZSTD_isError(frame) ? 218 : 219;
        return LBK_ERR_DECOMPRESS;
    }
    if (s->decoded_size > SIZE_MAX) {
        *issue_id = 217;
        return LBK_ERR_LIMIT;
    }
    return LBK_OK;
}

lbk_result lbk_section_decode_into(const uint8_t *file, const lbk_section_info *s, const lbk_allocator *allocator,
                                   void *dst, uint32_t *issue_id)
{
    ZSTD_customMem mem = {zstd_alloc, zstd_free, (void *)allocator};
    ZSTD_DCtx *dctx = ZSTD_createDCtx_advanced(mem);
    if (!dctx) return LBK_ERR_OUT_OF_MEMORY;
    size_t got = ZSTD_decompressDCtx(dctx, dst, (size_t)s->decoded_size, file + s->offset, (size_t)s->stored_size);
    ZSTD_freeDCtx(dctx);
    if (ZSTD_isError(got) || got != s->decoded_size) {
        if (ZSTD_isError(got) && ZSTD_getErrorCode(got) == ZSTD_error_memory_allocation) return LBK_ERR_OUT_OF_MEMORY;
        *issue_id = 218;
        return LBK_ERR_DECOMPRESS;
    }
    return LBK_OK;
}

lbk_result lbk_section_load(const uint8_t *file, const lbk_section_info *s, const lbk_allocator *allocator,
                            int skip_checksum, uint64_t *budget_left, const uint8_t **data, void **owned,
                            uint32_t *issue_id)
{
    const uint8_t *stored = file + s->offset;
    *data = NULL;
    *owned = NULL;
    *issue_id = 0;
    if (!skip_checksum && XXH3_64bits(stored, (size_t)s->stored_size) != s->checksum) {
        *issue_id = 214;
        return LBK_ERR_CHECKSUM;
    }
    if (s->compression == LBK_COMPRESSION_NONE) {
        *data = stored;
        return LBK_OK;
    }
    lbk_result r = lbk_section_frame_check(file, s, issue_id);
    if (r != LBK_OK) return r;
    if (s->decoded_size > *budget_left) {
        *issue_id = 217;
        return LBK_ERR_LIMIT;
    }
    void *buf = lbk_alloc(allocator, (size_t)s->decoded_size);
    if (!buf) return LBK_ERR_OUT_OF_MEMORY;
    r = lbk_section_decode_into(file, s, allocator, buf, issue_id);
    if (r != LBK_OK) {
        lbk_dealloc(allocator, buf);
        return r;
    }
    *budget_left -= s->decoded_size;
    *data = buf;
    *owned = buf;
    return LBK_OK;
}

/* ---- file mapping ------------------------------------------------------------------------ */

lbk_result lbk_map_file(const char *path, const uint8_t **data, size_t *size)
{
    *data = NULL;
    *size = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return LBK_ERR_IO;
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        if (errno == 0) errno = EINVAL;
        close(fd);
        return LBK_ERR_IO;
    }
    if ((uint64_t)st.st_size > SIZE_MAX) {
        close(fd);
        return LBK_ERR_LIMIT;
    }
    if (st.st_size == 0) {
        close(fd);
        return LBK_OK;
    }
    void *p = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_PRIVATE, fd, 0);
    int saved = errno;
    close(fd);
    if (p == MAP_FAILED) {
        errno = saved;
        return LBK_ERR_IO;
    }
    *data = p;
    *size = (size_t)st.st_size;
    return LBK_OK;
}

void lbk_unmap_file(const uint8_t *data, size_t size)
{
    if (data && size) munmap((void *)data, size);
}
