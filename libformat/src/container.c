/* The container reader (mmap or caller buffer, lazy decode) and writer (canonical layout,
 * deterministic bytes, atomic file write). Layout rules: spec/container.md §2–§4; the checks
 * themselves live in framing.c so the reader and the validator share them. */
#define ZSTD_STATIC_LINKING_ONLY /* ZSTD_createCCtx_advanced: route zstd's memory through the caller */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>
#include "xxh.h"
#include <zstd.h>
#include <zstd_errors.h>

#include "framing.h"
#include "lbk/error_map.h"
#include "lbk/lightmap.h"

#define LBK_DEFAULT_ZSTD_LEVEL 19

static lbk_allocator copy_allocator(const lbk_allocator *a)
{
    lbk_allocator out = {0};
    if (a && a->alloc && a->free) out = *a;
    return out;
}

/* ---- reader ------------------------------------------------------------------------------ */

struct lbk_reader {
    lbk_allocator alloc;
    const uint8_t *bytes;
    size_t size;
    int mapped;
    int skip_checksums;
    uint64_t budget_left; /* decoded bytes the reader may still allocate */
    lbk_framing fr;
    const uint8_t *data[LBK_MAX_SECTIONS]; /* decoded (or in-place) bytes once accessed */
    void *owned[LBK_MAX_SECTIONS];
    uint8_t verified[LBK_MAX_SECTIONS];    /* stored checksum checked (or skip_checksums) */
};

typedef struct open_state {
    lbk_result result;
} open_state;

static int reader_report(void *user, uint32_t id, lbk_result r, uint32_t type, uint64_t offset, const char *fmt,
                         va_list ap)
{
    (void)id; (void)type; (void)offset; (void)fmt; (void)ap;
    if (r == LBK_OK) return 0; /* a warning: the file is still readable */
    ((open_state *)user)->result = r;
    return 1;
}

static lbk_result open_common(const uint8_t *data, size_t size, int mapped, const lbk_read_options *caller_options,
                              lbk_reader **out)
{
    lbk_read_options options;
    lbk_result rc = LBK_SIZED_IN(&options, caller_options, lbk_read_options, skip_checksums);
    if (rc != LBK_OK) return rc;
    lbk_allocator alloc = copy_allocator(options.allocator);
    open_state st = {LBK_OK};
    lbk_reader *r = lbk_calloc(&alloc, 1, sizeof *r);
    if (!r) return LBK_ERR_OUT_OF_MEMORY;
    lbk_framing_parse(data, size, &r->fr, reader_report, &st);
    if (st.result == LBK_OK && !r->fr.header_ok) st.result = LBK_ERR_CORRUPT; /* cannot happen; be safe */
    if (st.result != LBK_OK) {
        lbk_dealloc(&alloc, r);
        return st.result;
    }
    r->alloc = alloc;
    r->bytes = data;
    r->size = size;
    r->mapped = mapped;
    r->skip_checksums = options.skip_checksums;
    r->budget_left = options.max_decoded_bytes ? options.max_decoded_bytes : lbk_default_decode_cap(size);
    *out = r;
    return LBK_OK;
}

lbk_result lbk_reader_open_memory(const void *data, size_t size, const lbk_read_options *options, lbk_reader **out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    return open_common(data, size, 0, options, out);
}

lbk_result lbk_reader_open_file(const char *path, const lbk_read_options *options, lbk_reader **out)
{
    if (!out || !path) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    const uint8_t *data;
    size_t size;
    lbk_result res = lbk_map_file(path, &data, &size);
    if (res != LBK_OK) return res;
    res = open_common(data, size, 1, options, out);
    if (res != LBK_OK) lbk_unmap_file(data, size);
    return res;
}

void lbk_reader_close(lbk_reader *r)
{
    if (!r) return;
    for (uint32_t i = 0; i < LBK_MAX_SECTIONS; i++) lbk_dealloc(&r->alloc, r->owned[i]);
    if (r->mapped) lbk_unmap_file(r->bytes, r->size);
    lbk_allocator alloc = r->alloc;
    lbk_dealloc(&alloc, r);
}

const lbk_header_info *lbk_reader_header(const lbk_reader *r) { return r ? &r->fr.header : NULL; }

const void *lbk_reader_bytes(const lbk_reader *r, size_t *size)
{
    if (!r) return NULL;
    if (size) *size = r->size;
    return r->bytes;
}

uint32_t lbk_reader_section_count(const lbk_reader *r) { return r ? r->fr.count : 0; }

lbk_result lbk_reader_section_get(const lbk_reader *r, uint32_t index, lbk_section_info *out)
{
    if (!r || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= r->fr.count) return LBK_ERR_NOT_FOUND;
    *out = r->fr.sections[index];
    return LBK_OK;
}

lbk_result lbk_reader_section_find(const lbk_reader *r, uint32_t type, uint32_t *index)
{
    if (!r || !index) return LBK_ERR_INVALID_ARGUMENT;
    for (uint32_t i = 0; i < r->fr.count; i++)
        if (r->fr.sections[i].type == type) {
            *index = i;
            return LBK_OK;
        }
    return LBK_ERR_NOT_FOUND;
}

/* ---- loading: each section's checksum verified once, each zstd section decoded once -------- */

const lbk_framing *lbk_reader_framing(const lbk_reader *r) { return &r->fr; }
const lbk_allocator *lbk_reader_allocator(const lbk_reader *r) { return &r->alloc; }
uint64_t lbk_reader_budget_left(const lbk_reader *r) { return r->budget_left; }

lbk_result lbk_reader_verify(lbk_reader *r, uint32_t index, uint32_t *issue_id)
{
    *issue_id = 0;
    if (index >= r->fr.count) return LBK_ERR_NOT_FOUND;
    if (!r->fr.usable[index]) return LBK_ERR_CORRUPT;
    if (r->verified[index] || r->skip_checksums) return LBK_OK;
    const lbk_section_info *s = &r->fr.sections[index];
    if (XXH3_64bits(r->bytes + s->offset, (size_t)s->stored_size) != s->checksum) {
        *issue_id = 214;
        return LBK_ERR_CHECKSUM;
    }
    r->verified[index] = 1;
    return LBK_OK;
}

int lbk_reader_checksum_pending(const lbk_reader *r, uint32_t index)
{
    return index < r->fr.count && r->fr.usable[index] && !r->verified[index] && !r->skip_checksums;
}

void lbk_reader_set_verified(lbk_reader *r, uint32_t index)
{
    if (index < r->fr.count) r->verified[index] = 1;
}

lbk_result lbk_reader_load(lbk_reader *r, uint32_t index, const uint8_t **data, uint32_t *issue_id)
{
    *data = NULL;
    lbk_result res = lbk_reader_verify(r, index, issue_id);
    if (res != LBK_OK) return res;
    if (!r->data[index]) {
        const uint8_t *d;
        void *owned;
        res = lbk_section_load(r->bytes, &r->fr.sections[index], &r->alloc, 1, &r->budget_left, &d, &owned, issue_id);
        if (res != LBK_OK) return res;
        r->data[index] = d;
        r->owned[index] = owned;
    }
    *data = r->data[index];
    return LBK_OK;
}

lbk_result lbk_reader_section_data(lbk_reader *r, uint32_t index, const void **data, size_t *size)
{
    if (!r || !data || !size) return LBK_ERR_INVALID_ARGUMENT;
    *data = NULL;
    *size = 0;
    uint32_t issue;
    const uint8_t *d;
    lbk_result res = lbk_reader_load(r, index, &d, &issue);
    if (res != LBK_OK) return res;
    *data = d;
    *size = (size_t)r->fr.sections[index].decoded_size;
    return LBK_OK;
}

lbk_result lbk_reader_section_unpack(lbk_reader *r, uint32_t index, void *dst, size_t dst_size)
{
    if (!r || (!dst && dst_size)) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= r->fr.count) return LBK_ERR_NOT_FOUND;
    const lbk_section_info *s = &r->fr.sections[index];
    if (dst_size < s->decoded_size) return LBK_ERR_INVALID_ARGUMENT;
    uint32_t issue;
    lbk_result res = lbk_reader_verify(r, index, &issue);
    if (res != LBK_OK) return res;
    if (r->data[index] || s->compression == LBK_COMPRESSION_NONE) {
        memcpy(dst, r->data[index] ? r->data[index] : r->bytes + s->offset, (size_t)s->decoded_size);
        return LBK_OK;
    }
    /* caller memory: nothing is allocated but zstd's context, so the decoded-bytes cap does not apply */
    res = lbk_section_frame_check(r->bytes, s, &issue);
    if (res == LBK_OK) res = lbk_section_decode_into(r->bytes, s, &r->alloc, dst, &issue);
    return res;
}

lbk_result lbk_reader_section_by_type(lbk_reader *r, uint32_t type, const void **data, size_t *size)
{
    uint32_t index;
    if (data) *data = NULL;
    if (size) *size = 0;
    lbk_result res = lbk_reader_section_find(r, type, &index);
    if (res != LBK_OK) return res;
    return lbk_reader_section_data(r, index, data, size);
}

/* ---- writer ------------------------------------------------------------------------------ */

typedef struct writer_section {
    uint32_t type, flags, compression;
    uint32_t features; /* required features the payload needs (LMAP: block pages) */
    uint16_t minor;    /* the lowest minor version defining the payload (§1.3) */
    uint8_t *stored;
    uint64_t stored_size, decoded_size, checksum;
} writer_section;

struct lbk_writer {
    lbk_allocator alloc;
    uint32_t alignment;
    uint32_t count;
    writer_section s[LBK_MAX_SECTIONS];
};

lbk_result lbk_writer_open(const lbk_write_options *caller_options, lbk_writer **out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    lbk_write_options options;
    lbk_result rc = LBK_SIZED_IN(&options, caller_options, lbk_write_options, section_alignment);
    if (rc != LBK_OK) return rc;
    uint32_t a = options.section_alignment ? options.section_alignment : LBK_DEFAULT_ALIGNMENT;
    if (a < LBK_MIN_ALIGNMENT || a > LBK_MAX_ALIGNMENT || (a & (a - 1))) return LBK_ERR_INVALID_ARGUMENT;
    lbk_allocator alloc = copy_allocator(options.allocator);
    lbk_writer *w = lbk_calloc(&alloc, 1, sizeof *w);
    if (!w) return LBK_ERR_OUT_OF_MEMORY;
    w->alloc = alloc;
    w->alignment = a;
    *out = w;
    return LBK_OK;
}

void lbk_writer_close(lbk_writer *w)
{
    if (!w) return;
    for (uint32_t i = 0; i < w->count; i++) lbk_dealloc(&w->alloc, w->s[i].stored);
    lbk_allocator alloc = w->alloc;
    lbk_dealloc(&alloc, w);
}

static void *zstd_alloc(void *user, size_t size) { return lbk_alloc((const lbk_allocator *)user, size); }
static void zstd_free(void *user, void *p) { lbk_dealloc((const lbk_allocator *)user, p); }

static lbk_result compress(lbk_writer *w, const void *data, size_t size, int level, uint8_t **out, size_t *out_size)
{
    ZSTD_customMem mem = {zstd_alloc, zstd_free, &w->alloc};
    size_t bound = ZSTD_compressBound(size);
    if (ZSTD_isError(bound)) return LBK_ERR_LIMIT;
    uint8_t *tmp = lbk_alloc(&w->alloc, bound);
    if (!tmp) return LBK_ERR_OUT_OF_MEMORY;
    ZSTD_CCtx *cctx = ZSTD_createCCtx_advanced(mem);
    if (!cctx) {
        lbk_dealloc(&w->alloc, tmp);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    /* One frame with the content size and no zstd checksum (the section checksum covers it). */
    size_t n = ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, level);
    if (!ZSTD_isError(n)) n = ZSTD_CCtx_setParameter(cctx, ZSTD_c_contentSizeFlag, 1);
    if (!ZSTD_isError(n)) n = ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 0);
    if (!ZSTD_isError(n)) n = ZSTD_compress2(cctx, tmp, bound, data, size);
    ZSTD_freeCCtx(cctx);
    if (ZSTD_isError(n)) {
        lbk_dealloc(&w->alloc, tmp);
        return ZSTD_getErrorCode(n) == ZSTD_error_memory_allocation ? LBK_ERR_OUT_OF_MEMORY : LBK_ERR_INVALID_ARGUMENT;
    }
    /* Keep only the bytes used: the bound can be much larger than the frame. */
    uint8_t *exact = lbk_alloc(&w->alloc, n);
    if (!exact) {
        lbk_dealloc(&w->alloc, tmp);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    memcpy(exact, tmp, n);
    lbk_dealloc(&w->alloc, tmp);
    *out = exact;
    *out_size = n;
    return LBK_OK;
}

lbk_result lbk_writer_section_add(lbk_writer *w, uint32_t type, const void *data, size_t size,
                                  const lbk_section_options *caller_options)
{
    if (!w || !data || size == 0 || !lbk_fourcc_printable(type)) return LBK_ERR_INVALID_ARGUMENT;
    lbk_section_options options;
    lbk_result rc = LBK_SIZED_IN(&options, caller_options, lbk_section_options, zstd_level);
    if (rc != LBK_OK) return rc;
    uint32_t flags = options.flags;
    uint32_t compression = options.compression;
    int level = options.zstd_level ? options.zstd_level : LBK_DEFAULT_ZSTD_LEVEL;
    if ((flags & ~LBK_SECTION_FLAG_REQUIRED) || compression > LBK_COMPRESSION_ZSTD) return LBK_ERR_INVALID_ARGUMENT;
    if (level > ZSTD_maxCLevel() || level < ZSTD_minCLevel()) return LBK_ERR_INVALID_ARGUMENT;
    for (uint32_t i = 0; i < w->count; i++)
        if (w->s[i].type == type) return LBK_ERR_INVALID_ARGUMENT;
    if (w->count >= LBK_MAX_SECTIONS) return LBK_ERR_LIMIT;

    writer_section *s = &w->s[w->count];
    uint8_t *stored;
    size_t stored_size;
    if (compression == LBK_COMPRESSION_ZSTD) {
        lbk_result r = compress(w, data, size, level, &stored, &stored_size);
        if (r != LBK_OK) return r;
    } else {
        stored = lbk_alloc(&w->alloc, size);
        if (!stored) return LBK_ERR_OUT_OF_MEMORY;
        memcpy(stored, data, size);
        stored_size = size;
    }
    s->type = type;
    s->flags = flags;
    s->compression = compression;
    s->features = type == LBK_SECTION_LMAP ? lbk_lmap_required_features(data, size) : 0;
    /* an OCTP probe volume (level_count ≠ 0 at byte 8) is 1.3 content, §14 */
    s->minor = type == LBK_SECTION_OCTP && size >= 12 && lbk_rd32((const uint8_t *)data + 8) != 0 ? 3 : 0;
    if (type == LBK_SECTION_TERR) s->minor = 4; /* the per-texel error map is 1.4 content, §18 */
    s->stored = stored;
    s->stored_size = stored_size;
    s->decoded_size = size;
    s->checksum = XXH3_64bits(stored, stored_size);
    w->count++;
    return LBK_OK;
}

/* Sections in canonical order, and the file size their placement gives (§3.3). */
static lbk_result layout(const lbk_writer *w, uint32_t order[LBK_MAX_SECTIONS], uint64_t offsets[LBK_MAX_SECTIONS],
                         uint64_t *file_size)
{
    for (uint32_t i = 0; i < w->count; i++) order[i] = i;
    for (uint32_t i = 1; i < w->count; i++) /* insertion sort: at most 64 entries */
        for (uint32_t j = i; j > 0 && lbk_section_order_key(w->s[order[j - 1]].type) >
                                          lbk_section_order_key(w->s[order[j]].type);
             j--) {
            uint32_t t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    uint64_t end = LBK_HEADER_SIZE + (uint64_t)LBK_SECTION_ENTRY_SIZE * w->count;
    for (uint32_t i = 0; i < w->count; i++) {
        offsets[i] = lbk_align_up(end, w->alignment);
        if (offsets[i] < end || !lbk_add_u64(offsets[i], w->s[order[i]].stored_size, &end)) return LBK_ERR_LIMIT;
    }
    if (end > SIZE_MAX) return LBK_ERR_LIMIT;
    *file_size = end;
    return LBK_OK;
}

lbk_result lbk_writer_to_memory(lbk_writer *w, void **out, size_t *size)
{
    if (!w || !out || !size) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (w->count == 0) return LBK_ERR_INVALID_ARGUMENT; /* §2: section_count >= 1 */
    uint32_t order[LBK_MAX_SECTIONS];
    uint64_t offsets[LBK_MAX_SECTIONS], file_size;
    lbk_result r = layout(w, order, offsets, &file_size);
    if (r != LBK_OK) return r;
    uint8_t *f = lbk_calloc(&w->alloc, 1, (size_t)file_size); /* zero: padding and reserved bytes */
    if (!f) return LBK_ERR_OUT_OF_MEMORY;

    uint32_t required = 0;
    uint16_t minor = 0; /* §1.3: the lowest minor version that defines everything in the file */
    for (uint32_t i = 0; i < w->count; i++) {
        const writer_section *s = &w->s[order[i]];
        if (s->type == LBK_SECTION_LMUV && minor < 1) minor = 1;
        if ((s->features & LBK_FEATURE_LMAP_BLOCK) && minor < 2) minor = 2;
        if (s->minor > minor) minor = s->minor;
        required |= s->features;
        uint8_t *e = f + LBK_HEADER_SIZE + (size_t)LBK_SECTION_ENTRY_SIZE * i;
        lbk_wr32(e + LBK_ENT_TYPE, s->type);
        lbk_wr32(e + LBK_ENT_FLAGS, s->flags);
        lbk_wr32(e + LBK_ENT_COMPRESSION, s->compression);
        lbk_wr64(e + LBK_ENT_OFFSET, offsets[i]);
        lbk_wr64(e + LBK_ENT_STORED_SIZE, s->stored_size);
        lbk_wr64(e + LBK_ENT_DECODED_SIZE, s->decoded_size);
        lbk_wr64(e + LBK_ENT_CHECKSUM, s->checksum);
        memcpy(f + offsets[i], s->stored, (size_t)s->stored_size);
        if (s->compression == LBK_COMPRESSION_ZSTD) required |= LBK_FEATURE_ZSTD;
    }
    memcpy(f, lbk_magic, 8);
    lbk_wr16(f + LBK_HDR_VERSION_MAJOR, LBK_FORMAT_VERSION_MAJOR);
    lbk_wr16(f + LBK_HDR_VERSION_MINOR, minor);
    lbk_wr32(f + LBK_HDR_HEADER_SIZE, LBK_HEADER_SIZE);
    lbk_wr64(f + LBK_HDR_FILE_SIZE, file_size);
    lbk_wr32(f + LBK_HDR_REQUIRED_FEATURES, required);
    lbk_wr32(f + LBK_HDR_OPTIONAL_FEATURES, 0);
    lbk_wr32(f + LBK_HDR_SECTION_COUNT, w->count);
    lbk_wr32(f + LBK_HDR_SECTION_ALIGNMENT, w->alignment);
    lbk_wr64(f + LBK_HDR_TABLE_OFFSET, LBK_HEADER_SIZE);
    lbk_wr64(f + LBK_HDR_TABLE_CHECKSUM,
             XXH3_64bits(f + LBK_HEADER_SIZE, (size_t)LBK_SECTION_ENTRY_SIZE * w->count));
    lbk_wr64(f + LBK_HDR_HEADER_CHECKSUM, XXH3_64bits(f, LBK_HDR_HEADER_CHECKSUM));
    *out = f;
    *size = (size_t)file_size;
    return LBK_OK;
}

static int write_all(int fd, const uint8_t *p, size_t n)
{
    while (n) {
        ssize_t k = write(fd, p, n > ((size_t)1 << 30) ? ((size_t)1 << 30) : n);
        if (k < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        p += k;
        n -= (size_t)k;
    }
    return 0;
}

/* fsync of the directory makes the rename itself durable. */
static int sync_parent_dir(const char *path, const lbk_allocator *alloc)
{
    const char *slash = strrchr(path, '/');
    size_t len = slash ? (size_t)(slash - path) : 1;
    if (slash && len == 0) len = 1; /* "/name": the root */
    char *dir = lbk_alloc(alloc, len + 1);
    if (!dir) return -1;
    if (slash) memcpy(dir, path, len);
    else dir[0] = '.';
    dir[len] = '\0';
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    lbk_dealloc(alloc, dir);
    if (fd < 0) return -1;
    int rc = fsync(fd);
    /* Some file systems cannot fsync a directory; the data itself is already durable. */
    if (rc != 0 && (errno == EINVAL || errno == EROFS)) rc = 0;
    close(fd);
    return rc;
}

/* Only a regular file, a symlink (the rename replaces the link, never its target) or nothing may
 * stand at the path: renaming over /dev/null as root would replace the device with a file. */
static int replaceable(const char *path)
{
    struct stat st;
    return lstat(path, &st) != 0 || S_ISREG(st.st_mode) || S_ISLNK(st.st_mode);
}

lbk_result lbk_writer_to_file(lbk_writer *w, const char *path)
{
    if (!w || !path || !*path || !replaceable(path)) return LBK_ERR_INVALID_ARGUMENT;
    void *bytes;
    size_t size;
    lbk_result r = lbk_writer_to_memory(w, &bytes, &size);
    if (r != LBK_OK) return r;

    static const char suffix[] = ".tmp-XXXXXX"; /* same directory: rename stays atomic */
    size_t plen = strlen(path);
    char *tmp = lbk_alloc(&w->alloc, plen + sizeof suffix);
    if (!tmp) {
        lbk_dealloc(&w->alloc, bytes);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    memcpy(tmp, path, plen);
    memcpy(tmp + plen, suffix, sizeof suffix);
    r = LBK_ERR_IO;
    int fd = mkstemp(tmp);
    if (fd >= 0) {
        int ok = write_all(fd, bytes, size) == 0 && fchmod(fd, 0644) == 0 && fsync(fd) == 0;
        int saved = errno;
        if (close(fd) != 0 && ok) {
            ok = 0;
            saved = errno;
        }
        if (ok && !replaceable(path)) {
            unlink(tmp);
            r = LBK_ERR_INVALID_ARGUMENT;
        } else if (ok && rename(tmp, path) == 0) {
            r = sync_parent_dir(path, &w->alloc) == 0 ? LBK_OK : LBK_ERR_IO;
        } else {
            if (ok) saved = errno;
            unlink(tmp);
            errno = saved;
        }
    }
    lbk_dealloc(&w->alloc, tmp);
    lbk_dealloc(&w->alloc, bytes);
    return r;
}
