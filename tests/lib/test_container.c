/* Container framing: writer→reader round trips (raw and zstd), canonical order and determinism,
 * every alignment, the reader's rejections (magic, major, required feature, required section),
 * skipping of unknown optional sections, the decoded-bytes cap against a zstd bomb, allocator
 * hooks, the atomic file write, and framing issue IDs reported by the validator. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <xxhash.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/validate.h"
#include "support/container_fixture.h"

static uint32_t rd32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t rd64(const uint8_t *p) { return rd32(p) | (uint64_t)rd32(p + 4) << 32; }
static void wr32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i));
}
static void wr64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i));
}

/* Deterministic pseudo-random payload (xorshift), compressible only a little. */
static void fill(uint8_t *p, size_t n, uint32_t seed)
{
    uint32_t x = seed * 2654435761u + 1;
    for (size_t i = 0; i < n; i++) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        p[i] = (uint8_t)(i % 7 == 0 ? 0 : x);
    }
}

typedef struct built {
    void *bytes;
    size_t size;
} built;

/* LMAP-, GLG- and META-typed payloads (raw bytes: framing does not look inside), GLG in zstd. */
enum { N_LMAP = 5000, N_GLG = 3000, N_META = 77 };
static uint8_t lmap[N_LMAP], glg[N_GLG], meta[N_META];

static built build_three(uint32_t alignment, int reverse)
{
    fill(lmap, N_LMAP, 1);
    fill(glg, N_GLG, 2);
    fill(meta, N_META, 3);
    lbk_write_options wo = {.section_alignment = alignment};
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(&wo, &w), LBK_OK);
    lbk_section_options z = {.flags = LBK_SECTION_FLAG_REQUIRED, .compression = LBK_COMPRESSION_ZSTD,
        .zstd_level = 1};
    lbk_section_options req = {.flags = LBK_SECTION_FLAG_REQUIRED};
    if (reverse) {
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_GLG, glg, N_GLG, &z), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, lmap, N_LMAP, &req), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, meta, N_META, NULL), LBK_OK);
    } else {
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, meta, N_META, NULL), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, lmap, N_LMAP, &req), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_GLG, glg, N_GLG, &z), LBK_OK);
    }
    built b;
    assert_int_equal(lbk_writer_to_memory(w, &b.bytes, &b.size), LBK_OK);
    lbk_writer_close(w);
    return b;
}

static void test_round_trip(void **state)
{
    (void)state;
    built b = build_three(0, 1);
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_memory(b.bytes, b.size, NULL, &r), LBK_OK);
    const lbk_header_info *h = lbk_reader_header(r);
    assert_int_equal(h->version_major, 1);
    assert_int_equal(h->version_minor, 0);
    assert_int_equal(h->file_size, b.size);
    assert_int_equal(h->section_count, 3);
    assert_int_equal(h->section_alignment, 64);
    assert_int_equal(h->required_features, LBK_FEATURE_ZSTD);
    assert_int_equal(lbk_reader_section_count(r), 3);

    const uint32_t canonical[3] = {LBK_SECTION_META, LBK_SECTION_LMAP, LBK_SECTION_GLG};
    const uint8_t *payload[3] = {meta, lmap, glg};
    const size_t sizes[3] = {N_META, N_LMAP, N_GLG};
    uint64_t end = 64 + 3 * 48;
    for (uint32_t i = 0; i < 3; i++) {
        lbk_section_info si;
        assert_int_equal(lbk_reader_section_get(r, i, &si), LBK_OK);
        assert_int_equal(si.type, canonical[i]);
        assert_int_equal(si.offset, (end + 63) / 64 * 64);
        assert_int_equal(si.decoded_size, sizes[i]);
        assert_int_equal(si.compression, i == 2 ? LBK_COMPRESSION_ZSTD : LBK_COMPRESSION_NONE);
        assert_int_equal(si.flags, i == 0 ? 0 : LBK_SECTION_FLAG_REQUIRED);
        assert_int_equal(si.checksum, XXH3_64bits((const uint8_t *)b.bytes + si.offset, si.stored_size));
        if (i < 2) assert_int_equal(si.stored_size, sizes[i]);
        else assert_true(si.stored_size < sizes[i]); /* every 7th byte is 0: zstd gains a little */
        end = si.offset + si.stored_size;
        const void *d;
        size_t n;
        assert_int_equal(lbk_reader_section_data(r, i, &d, &n), LBK_OK);
        assert_int_equal(n, sizes[i]);
        assert_memory_equal(d, payload[i], n);
        if (i < 2) assert_ptr_equal(d, (const uint8_t *)b.bytes + si.offset); /* zero copy */
        const void *again;
        assert_int_equal(lbk_reader_section_data(r, i, &again, &n), LBK_OK);
        assert_ptr_equal(again, d); /* decoded once, cached */
    }
    assert_int_equal(end, b.size);
    uint32_t idx;
    assert_int_equal(lbk_reader_section_find(r, LBK_SECTION_GLG, &idx), LBK_OK);
    assert_int_equal(idx, 2);
    assert_int_equal(lbk_reader_section_find(r, LBK_SECTION_DLS, &idx), LBK_ERR_NOT_FOUND);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &d, &n), LBK_OK);
    assert_int_equal(n, N_LMAP);
    assert_int_equal(lbk_reader_section_data(r, 3, &d, &n), LBK_ERR_NOT_FOUND);
    lbk_reader_close(r);
    lbk_free(NULL, b.bytes);
}

static void test_deterministic_and_canonical(void **state)
{
    (void)state;
    built a = build_three(0, 0), b = build_three(0, 1), c = build_three(0, 0);
    assert_int_equal(a.size, b.size);
    assert_memory_equal(a.bytes, b.bytes, a.size); /* add order does not matter */
    assert_memory_equal(a.bytes, c.bytes, a.size);
    lbk_free(NULL, a.bytes);
    lbk_free(NULL, b.bytes);
    lbk_free(NULL, c.bytes);
}

static void test_every_alignment(void **state)
{
    (void)state;
    for (uint32_t a = 16; a <= 65536; a *= 2) {
        built b = build_three(a, a & 0x100);
        const uint8_t *f = b.bytes;
        assert_int_equal(rd32(f + 36), a);
        uint64_t end = 64 + 3 * 48;
        for (uint32_t i = 0; i < 3; i++) {
            const uint8_t *e = f + 64 + 48 * i;
            uint64_t off = rd64(e + 16), stored = rd64(e + 24);
            assert_int_equal(off % a, 0);
            assert_int_equal(off, (end + a - 1) / a * a);
            for (uint64_t p = end; p < off; p++) assert_int_equal(f[p], 0); /* zero padding */
            end = off + stored;
        }
        assert_int_equal(end, b.size);
        lbk_reader *r;
        assert_int_equal(lbk_reader_open_memory(b.bytes, b.size, NULL, &r), LBK_OK);
        const void *d;
        size_t n;
        assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_GLG, &d, &n), LBK_OK);
        assert_memory_equal(d, glg, N_GLG);
        lbk_reader_close(r);
        lbk_validate_summary s;
        assert_int_equal(lbk_validate_memory(b.bytes, b.size, NULL, NULL, NULL, &s), LBK_OK);
        assert_int_equal(s.fatal, 0); /* framing is fine; the random payloads are not real sections */
        lbk_free(NULL, b.bytes);
    }
    lbk_writer *w;
    lbk_write_options bad = {.section_alignment = 8};
    assert_int_equal(lbk_writer_open(&bad, &w), LBK_ERR_INVALID_ARGUMENT);
    bad.section_alignment = 96;
    assert_int_equal(lbk_writer_open(&bad, &w), LBK_ERR_INVALID_ARGUMENT);
    bad.section_alignment = 131072;
    assert_int_equal(lbk_writer_open(&bad, &w), LBK_ERR_INVALID_ARGUMENT);
}

static lbk_result open_copy(const uint8_t *bytes, size_t size)
{
    lbk_reader *r = NULL;
    lbk_result res = lbk_reader_open_memory(bytes, size, NULL, &r);
    if (res == LBK_OK) {
        /* Open only checks the framing; section checksums are checked on access. */
        for (uint32_t i = 0; i < lbk_reader_section_count(r) && res == LBK_OK; i++) {
            const void *d;
            size_t n;
            lbk_section_info si;
            lbk_reader_section_get(r, i, &si);
            res = lbk_reader_section_data(r, i, &d, &n);
        }
    }
    lbk_reader_close(r);
    return res;
}

static void test_reader_rejections(void **state)
{
    (void)state;
    built b = build_three(0, 0);
    uint8_t *f = malloc(b.size);
    assert_non_null(f);
    assert_int_equal(open_copy(b.bytes, b.size), LBK_OK);

    memcpy(f, b.bytes, b.size);
    f[1] = 'X';
    assert_int_equal(open_copy(f, b.size), LBK_ERR_NOT_LBK);
    memcpy(f, b.bytes, b.size);
    f[4] = '\n'; /* CRLF → LF conversion */
    assert_int_equal(open_copy(f, b.size), LBK_ERR_NOT_LBK);

    memcpy(f, b.bytes, b.size);
    f[8] = 2; /* major 2, checksum fixed: still rejected for the version */
    fixture_fix_checksums(f);
    assert_int_equal(open_copy(f, b.size), LBK_ERR_UNSUPPORTED_VERSION);

    memcpy(f, b.bytes, b.size);
    f[10] = 7; /* minor 7: accepted */
    fixture_fix_checksums(f);
    assert_int_equal(open_copy(f, b.size), LBK_OK);

    memcpy(f, b.bytes, b.size);
    wr32(f + 24, rd32(f + 24) | 0x4); /* unknown required feature */
    fixture_fix_checksums(f);
    assert_int_equal(open_copy(f, b.size), LBK_ERR_UNSUPPORTED_FEATURE);

    memcpy(f, b.bytes, b.size);
    wr32(f + 28, 0x80); /* unknown optional feature: ignored */
    fixture_fix_checksums(f);
    assert_int_equal(open_copy(f, b.size), LBK_OK);

    memcpy(f, b.bytes, b.size);
    f[20] ^= 1; /* file_size field, checksum not fixed */
    assert_int_equal(open_copy(f, b.size), LBK_ERR_CHECKSUM);

    assert_int_equal(open_copy(b.bytes, b.size - 1), LBK_ERR_TRUNCATED);
    assert_int_equal(open_copy(b.bytes, 63), LBK_ERR_TRUNCATED);
    assert_int_equal(open_copy(b.bytes, 0), LBK_ERR_TRUNCATED);

    memcpy(f, b.bytes, b.size);
    f[64 + 48 + 24] ^= 1; /* LMAP stored_size in the table, table checksum not fixed */
    assert_int_equal(open_copy(f, b.size), LBK_ERR_CHECKSUM);

    memcpy(f, b.bytes, b.size);
    uint64_t lmap_off = rd64(f + 64 + 48 + 16);
    f[lmap_off + 100] ^= 0x10; /* payload byte */
    assert_int_equal(open_copy(f, b.size), LBK_ERR_CHECKSUM);
    lbk_read_options skip = {.skip_checksums = 1};
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_memory(f, b.size, &skip, &r), LBK_OK);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &d, &n), LBK_OK); /* checksums skipped */
    lbk_reader_close(r);

    memcpy(f, b.bytes, b.size);
    f[64 + 3 * 48 + 2] = 1; /* padding between table and first section */
    assert_int_equal(open_copy(f, b.size), LBK_ERR_CORRUPT);

    free(f);
    lbk_free(NULL, b.bytes);
}

static void test_unknown_sections(void **state)
{
    (void)state;
    static const uint8_t x[100] = {1, 2, 3};
    for (int required = 0; required < 2; required++) {
        lbk_writer *w;
        assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
        lbk_section_options o = {.flags = required ? LBK_SECTION_FLAG_REQUIRED : 0};
        fill(lmap, N_LMAP, 9);
        assert_int_equal(lbk_writer_section_add(w, LBK_FOURCC('Z', 'Z', 'Z', 'Z'), x, sizeof x, &o), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_FOURCC('A', 'N', 'E', 'W'), x, 10, NULL), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, lmap, 100, NULL), LBK_OK);
        built b;
        assert_int_equal(lbk_writer_to_memory(w, &b.bytes, &b.size), LBK_OK);
        lbk_writer_close(w);
        const uint8_t *f = b.bytes;
        /* unknown types after the known ones, ascending by code */
        assert_int_equal(rd32(f + 64), LBK_SECTION_META);
        assert_int_equal(rd32(f + 64 + 48), LBK_FOURCC('A', 'N', 'E', 'W'));
        assert_int_equal(rd32(f + 64 + 96), LBK_FOURCC('Z', 'Z', 'Z', 'Z'));
        lbk_reader *r = NULL;
        lbk_result res = lbk_reader_open_memory(b.bytes, b.size, NULL, &r);
        if (required) {
            assert_int_equal(res, LBK_ERR_UNSUPPORTED_FEATURE);
            assert_null(r);
        } else {
            assert_int_equal(res, LBK_OK);
            const void *d;
            size_t n;
            assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_META, &d, &n), LBK_OK);
            assert_memory_equal(d, lmap, 100);
            lbk_reader_close(r);
        }
        lbk_free(NULL, b.bytes);
    }
}

typedef struct counting {
    size_t allocs, frees, live_bytes, peak_single;
} counting;

static void *c_alloc(void *user, size_t size)
{
    counting *c = user;
    c->allocs++;
    if (size > c->peak_single) c->peak_single = size;
    size_t *p = malloc(size + 16);
    if (!p) return NULL;
    p[0] = size;
    c->live_bytes += size;
    return (uint8_t *)p + 16;
}

static void c_free(void *user, void *ptr)
{
    counting *c = user;
    if (!ptr) return;
    size_t *p = (size_t *)((uint8_t *)ptr - 16);
    c->frees++;
    c->live_bytes -= p[0];
    free(p);
}

static built zeros_bomb(size_t decoded)
{
    uint8_t *z = calloc(1, decoded);
    assert_non_null(z);
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    lbk_section_options o = {.compression = LBK_COMPRESSION_ZSTD, .zstd_level = 1};
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, z, decoded, &o), LBK_OK);
    free(z);
    built b;
    assert_int_equal(lbk_writer_to_memory(w, &b.bytes, &b.size), LBK_OK);
    lbk_writer_close(w);
    return b;
}

static void test_decoded_cap_stops_bomb(void **state)
{
    (void)state;
    /* 8 MiB of zeros in a ~300-byte zstd frame, read with a 1 MiB cap. */
    built b = zeros_bomb((size_t)8 << 20);
    assert_true(b.size < 4096);
    counting c = {0};
    lbk_allocator a = {c_alloc, c_free, &c};
    lbk_read_options ro = {.allocator = &a, .max_decoded_bytes = (uint64_t)1 << 20};
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_memory(b.bytes, b.size, &ro, &r), LBK_OK);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &d, &n), LBK_ERR_LIMIT);
    assert_true(c.peak_single < ((size_t)1 << 20)); /* refused before allocating */
    lbk_reader_close(r);
    assert_int_equal(c.live_bytes, 0);
    lbk_validate_options vo = {.max_decoded_bytes = (uint64_t)1 << 20};
    lbk_validate_summary s;
    assert_int_equal(lbk_validate_memory(b.bytes, b.size, &vo, NULL, NULL, &s), LBK_OK);
    assert_int_equal(s.errors, 1); /* 217 */
    lbk_free(NULL, b.bytes);

    /* Default cap: min(4 GiB, 1024 × file size + 64 MiB). 96 MiB of zeros compress to a few
     * KiB, so the cap is far below 96 MiB and the reader refuses. */
    b = zeros_bomb((size_t)96 << 20);
    uint64_t cap = 1024 * (uint64_t)b.size + ((uint64_t)64 << 20);
    assert_true(cap < ((uint64_t)96 << 20));
    assert_int_equal(lbk_reader_open_memory(b.bytes, b.size, NULL, &r), LBK_OK);
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &d, &n), LBK_ERR_LIMIT);
    lbk_reader_close(r);
    /* A caller that raises the cap gets the bytes. */
    ro.allocator = NULL;
    ro.max_decoded_bytes = (uint64_t)96 << 20;
    assert_int_equal(lbk_reader_open_memory(b.bytes, b.size, &ro, &r), LBK_OK);
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &d, &n), LBK_OK);
    assert_int_equal(n, (size_t)96 << 20);
    assert_int_equal(((const uint8_t *)d)[n - 1], 0);
    lbk_reader_close(r);
    lbk_free(NULL, b.bytes);
}

static int count_issue(void *user, const lbk_issue *issue)
{
    (void)issue;
    ++*(int *)user;
    return 0;
}

/* lbk_reader_validate: the same verdict as lbk_validate_memory, through the reader's cache — the
 * zstd REPT of the fixture is decoded once (one allocation of its decoded size, kept until close),
 * and section_data afterwards allocates nothing. lbk_reader_section_unpack decodes into caller
 * memory with no allocation of the decoded size, and equals section_data byte for byte. */
static void test_reader_validate_decodes_once(void **state)
{
    (void)state;
    void *file;
    size_t size;
    assert_int_equal(fixture_small_container(0, &file, &size), 0);
    int n_mem = 0, n_rd = 0;
    lbk_validate_summary sm, sr;
    assert_int_equal(lbk_validate_memory(file, size, NULL, count_issue, &n_mem, &sm), LBK_OK);
    counting c = {0};
    lbk_allocator a = {c_alloc, c_free, &c};
    lbk_read_options ro = {.allocator = &a};
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_memory(file, size, &ro, &r), LBK_OK);
    uint32_t ri;
    lbk_section_info si;
    assert_int_equal(lbk_reader_section_find(r, LBK_SECTION_REPT, &ri), LBK_OK);
    assert_int_equal(lbk_reader_section_get(r, ri, &si), LBK_OK);
    assert_int_equal(si.compression, LBK_COMPRESSION_ZSTD);
    /* unpack first: nothing of the decoded size is allocated, nothing is cached */
    uint8_t *mine = malloc((size_t)si.decoded_size + 1);
    size_t live = c.live_bytes;
    assert_int_equal(lbk_reader_section_unpack(r, ri, mine, (size_t)si.decoded_size - 1), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_reader_section_unpack(r, ri, mine, (size_t)si.decoded_size + 1), LBK_OK);
    assert_int_equal(c.live_bytes, live); /* zstd's context came and went; nothing was kept */
    assert_int_equal(lbk_reader_validate(r, count_issue, &n_rd, &sr), LBK_OK);
    assert_int_equal(n_rd, n_mem);
    assert_int_equal(sr.fatal, sm.fatal);
    assert_int_equal(sr.errors, sm.errors);
    assert_int_equal(sr.warnings, sm.warnings);
    assert_int_equal(sr.errors + sr.fatal, 0);
    assert_int_equal(c.live_bytes - live, (size_t)si.decoded_size); /* REPT decoded once and kept */
    size_t allocs = c.allocs;
    const void *d;
    size_t dn;
    for (uint32_t i = 0; i < lbk_reader_section_count(r); i++) assert_int_equal(lbk_reader_section_data(r, i, &d, &dn), LBK_OK);
    assert_int_equal(c.allocs, allocs); /* every section already there */
    assert_int_equal(lbk_reader_section_data(r, ri, &d, &dn), LBK_OK);
    assert_memory_equal(d, mine, dn);
    /* a second validation through the same reader: same verdict, nothing decoded again */
    n_rd = 0;
    assert_int_equal(lbk_reader_validate(r, count_issue, &n_rd, &sr), LBK_OK);
    assert_int_equal(n_rd, n_mem);
    assert_int_equal(c.live_bytes - live, (size_t)si.decoded_size);
    lbk_reader_close(r);
    assert_int_equal(c.live_bytes, 0);

    /* a flipped byte in the zstd section: both validations report 214 for it */
    uint8_t *bad = malloc(size);
    memcpy(bad, file, size);
    bad[si.offset + si.stored_size / 2] ^= 0x10;
    n_mem = n_rd = 0;
    assert_int_equal(lbk_validate_memory(bad, size, NULL, count_issue, &n_mem, &sm), LBK_OK);
    assert_int_equal(lbk_reader_open_memory(bad, size, NULL, &r), LBK_OK);
    assert_int_equal(lbk_reader_validate(r, count_issue, &n_rd, &sr), LBK_OK);
    assert_true(sm.errors >= 1);
    assert_int_equal(sr.errors, sm.errors);
    assert_int_equal(n_rd, n_mem);
    assert_int_equal(lbk_reader_section_unpack(r, ri, mine, (size_t)si.decoded_size), LBK_ERR_CHECKSUM);
    lbk_reader_close(r);
    free(bad);
    free(mine);
    free(file);
}

static void test_allocator_hooks(void **state)
{
    (void)state;
    counting c = {0};
    lbk_allocator a = {c_alloc, c_free, &c};
    lbk_write_options wo = {.allocator = &a};
    lbk_writer *w;
    fill(glg, N_GLG, 4);
    assert_int_equal(lbk_writer_open(&wo, &w), LBK_OK);
    lbk_section_options z = {.compression = LBK_COMPRESSION_ZSTD, .zstd_level = 3};
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_GLG, glg, N_GLG, &z), LBK_OK);
    size_t after_add = c.allocs;
    assert_true(after_add >= 3); /* writer, zstd context (through the hook), stored bytes */
    void *bytes;
    size_t size;
    assert_int_equal(lbk_writer_to_memory(w, &bytes, &size), LBK_OK);
    lbk_writer_close(w);
    assert_true(c.allocs > after_add);
    assert_int_equal(c.live_bytes, size); /* only the returned buffer is still alive */

    lbk_read_options ro = {.allocator = &a};
    lbk_reader *r;
    size_t before_read = c.allocs;
    assert_int_equal(lbk_reader_open_memory(bytes, size, &ro, &r), LBK_OK);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_GLG, &d, &n), LBK_OK);
    assert_memory_equal(d, glg, N_GLG);
    assert_true(c.allocs >= before_read + 3); /* reader, decoded bytes, zstd context */
    lbk_reader_close(r);
    lbk_validate_options vo = {.allocator = &a};
    lbk_validate_summary s;
    size_t before_validate = c.allocs;
    assert_int_equal(lbk_validate_memory(bytes, size, &vo, NULL, NULL, &s), LBK_OK);
    assert_true(c.allocs > before_validate);
    lbk_free(&a, bytes);
    assert_int_equal(c.live_bytes, 0);
    assert_int_equal(c.allocs, c.frees);
}

static void test_writer_arguments(void **state)
{
    (void)state;
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    uint8_t x[4] = {1, 2, 3, 4};
    void *bytes;
    size_t size;
    assert_int_equal(lbk_writer_to_memory(w, &bytes, &size), LBK_ERR_INVALID_ARGUMENT); /* no sections */
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, x, 0, NULL), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_writer_section_add(w, LBK_FOURCC('A', 'B', '\n', 'D'), x, 4, NULL), LBK_ERR_INVALID_ARGUMENT);
    lbk_section_options bad_flags = {.flags = 0x2}, bad_comp = {.compression = 2};
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, x, 4, &bad_flags), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, x, 4, &bad_comp), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, x, 4, NULL), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, x, 4, NULL), LBK_ERR_INVALID_ARGUMENT); /* dup */
    for (uint32_t i = 1; i < LBK_MAX_SECTIONS; i++)
        assert_int_equal(lbk_writer_section_add(w, LBK_FOURCC('Q', 'A' + i / 26, 'A' + i % 26, '0'), x, 4, NULL),
                         LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_FOURCC('Z', 'Z', 'Z', 'Z'), x, 4, NULL), LBK_ERR_LIMIT);
    assert_int_equal(lbk_writer_to_memory(w, &bytes, &size), LBK_OK);
    assert_int_equal(rd32((uint8_t *)bytes + 32), 64);
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_memory(bytes, size, NULL, &r), LBK_OK);
    lbk_reader_close(r);
    lbk_free(NULL, bytes);
    lbk_writer_close(w);
}

static void test_atomic_file_write(void **state)
{
    (void)state;
    char dir[] = "/tmp/lbk-test-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/out.lbk", dir);
    built b = build_three(0, 0);
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    lbk_section_options z = {.flags = LBK_SECTION_FLAG_REQUIRED, .compression = LBK_COMPRESSION_ZSTD,
        .zstd_level = 1};
    lbk_section_options req = {.flags = LBK_SECTION_FLAG_REQUIRED};
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, meta, N_META, NULL), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, lmap, N_LMAP, &req), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_GLG, glg, N_GLG, &z), LBK_OK);
    assert_int_equal(lbk_writer_to_file(w, path), LBK_OK);
    assert_int_equal(lbk_writer_to_file(w, path), LBK_OK); /* replaces */
    lbk_writer_close(w);

    lbk_reader *r;
    assert_int_equal(lbk_reader_open_file(path, NULL, &r), LBK_OK);
    size_t n;
    const void *all = lbk_reader_bytes(r, &n);
    assert_int_equal(n, b.size);
    assert_memory_equal(all, b.bytes, n); /* the file holds exactly the to_memory bytes */
    const void *d;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_GLG, &d, &n), LBK_OK);
    assert_memory_equal(d, glg, N_GLG);
    lbk_reader_close(r);
    /* The payloads are random bytes under real section types, so only compare the verdicts. */
    lbk_validate_summary s, sm;
    assert_int_equal(lbk_validate_file(path, NULL, NULL, NULL, &s), LBK_OK);
    assert_int_equal(lbk_validate_memory(b.bytes, b.size, NULL, NULL, NULL, &sm), LBK_OK);
    assert_int_equal(s.fatal, 0);
    assert_memory_equal(&s, &sm, sizeof s);

    /* Only out.lbk is left: no temp files. */
    DIR *dd = opendir(dir);
    assert_non_null(dd);
    int entries = 0;
    struct dirent *de;
    while ((de = readdir(dd)))
        if (strcmp(de->d_name, ".") && strcmp(de->d_name, "..")) entries++;
    closedir(dd);
    assert_int_equal(entries, 1);

    char missing[300];
    snprintf(missing, sizeof missing, "%s/no/such/dir/x.lbk", dir);
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, meta, N_META, NULL), LBK_OK);
    assert_int_equal(lbk_writer_to_file(w, missing), LBK_ERR_IO);
    lbk_writer_close(w);
    assert_int_equal(lbk_reader_open_file(missing, NULL, &r), LBK_ERR_IO);
    assert_int_equal(lbk_validate_file(missing, NULL, NULL, NULL, &s), LBK_ERR_IO);
    unlink(path);
    rmdir(dir);
    lbk_free(NULL, b.bytes);
}

/* ---- validator framing IDs ------------------------------------------------------------------ */

typedef struct collected {
    uint32_t ids[64];
    uint64_t offsets[64];
    uint32_t count;
} collected;

static int collect(void *user, const lbk_issue *issue)
{
    collected *c = user;
    if (c->count < 64) {
        c->ids[c->count] = issue->id;
        c->offsets[c->count] = issue->offset;
        c->count++;
    }
    lbk_severity sev;
    assert_non_null(lbk_issue_template(issue->id, &sev)); /* every reported ID is registered */
    assert_int_equal(sev, issue->severity);
    assert_true(strlen(issue->message) > 0);
    return 0;
}

static collected validate(const uint8_t *f, size_t n, lbk_validate_summary *s)
{
    collected c = {0};
    assert_int_equal(lbk_validate_memory(f, n, NULL, collect, &c, s), LBK_OK);
    return c;
}

static int has_id(const collected *c, uint32_t id)
{
    for (uint32_t i = 0; i < c->count; i++)
        if (c->ids[i] == id) return 1;
    return 0;
}

static void test_validator_framing_ids(void **state)
{
    (void)state;
    void *v;
    size_t n;
    assert_int_equal(fixture_small_container(0, &v, &n), 0);
    uint8_t *good = v, *f = malloc(n + 16);
    lbk_validate_summary s;
    collected c = validate(good, n, &s);
    assert_int_equal(s.fatal + s.errors, 0);
    assert_int_equal(s.warnings, 1);
    assert_int_equal(c.ids[0], 213); /* the unknown optional 'XTRA' */

    struct {
        size_t at;
        uint8_t xor_mask;
        int fix;
        uint32_t id;
    } cases[] = {
        {0, 0xff, 0, 101}, {4, 0x07, 0, 102}, {8, 0x03, 0, 103}, {60, 0x01, 0, 104},
        {12, 0x01, 1, 105}, {24, 0x04, 1, 108}, {32, 0xff, 1, 110}, {36, 0x01, 1, 111},
        {40, 0x08, 1, 112}, {64 + 30, 0x01, 2, 114}, {28, 0x01, 1, 109}, {10, 0x08, 1, 115}, /* minor 8 > 4 */
        {64 + 12, 0x01, 1, 205}, {64 + 4, 0x02, 1, 203}, {64 + 8, 0x02, 1, 204},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        memcpy(f, good, n);
        f[cases[k].at] ^= cases[k].xor_mask;
        if (cases[k].fix == 1) fixture_fix_checksums(f);
        if (cases[k].fix == 2) wr64(f + 56, XXH3_64bits(f, 56)); /* header only: the table checksum is stale */
        c = validate(f, n, &s);
        if (!has_id(&c, cases[k].id)) fail_msg("byte %zu ^ 0x%02x: expected issue %u, first was %u", cases[k].at, cases[k].xor_mask,
                             cases[k].id, c.count ? c.ids[0] : 0);
    }
    /* truncation and appended bytes */
    c = validate(good, n - 1, &s);
    assert_int_equal(c.ids[0], 106);
    assert_int_equal(s.fatal, 1);
    memcpy(f, good, n);
    memset(f + n, 0, 16);
    c = validate(f, n + 16, &s);
    assert_int_equal(c.ids[0], 107);
    c = validate(good, 10, &s);
    assert_int_equal(c.ids[0], 100);
    /* a flipped payload bit: checksum of that section, at its offset */
    uint64_t objs_off = rd64(good + 64 + 2 * 48 + 16);
    memcpy(f, good, n);
    f[objs_off + 3] ^= 0x40;
    c = validate(f, n, &s);
    assert_int_equal(c.count, 2);
    assert_int_equal(c.ids[0], 213);
    assert_int_equal(c.ids[1], 214);
    assert_int_equal(c.offsets[1], objs_off);
    /* a flipped padding bit: the first gap between two sections */
    uint64_t gap = 0;
    for (uint32_t i = 1; i < 4 && !gap; i++) {
        const uint8_t *prev = good + 64 + 48 * (i - 1), *e = good + 64 + 48 * i;
        if (rd64(prev + 16) + rd64(prev + 24) < rd64(e + 16)) gap = rd64(e + 16) - 1;
    }
    assert_true(gap > 0);
    memcpy(f, good, n);
    f[gap] ^= 0x01;
    c = validate(f, n, &s);
    assert_int_equal(c.ids[0], 211);
    assert_int_equal(c.offsets[0], gap);
    /* sections out of canonical order (entries 0 and 1 swapped, placement kept consistent) */
    memcpy(f, good, n);
    uint8_t e0[48];
    memcpy(e0, f + 64, 48);
    memcpy(f + 64, f + 64 + 48, 48);
    memcpy(f + 64 + 48, e0, 48);
    fixture_fix_checksums(f);
    c = validate(f, n, &s);
    assert_true(has_id(&c, 202));
    assert_true(has_id(&c, 206));
    /* the ZSTD feature bit cleared although REPT is compressed */
    memcpy(f, good, n);
    f[24] &= (uint8_t)~1u;
    fixture_fix_checksums(f);
    c = validate(f, n, &s);
    assert_true(has_id(&c, 116));
    assert_int_equal(s.errors, 1);
    /* the LMAP_BLOCK feature bit set without an LMAP */
    memcpy(f, good, n);
    f[24] |= 2u;
    fixture_fix_checksums(f);
    c = validate(f, n, &s);
    assert_true(has_id(&c, 117));
    assert_int_equal(s.errors, 1);
    free(f);
    free(good);
}

/* The texel checks of an uncompressed LMAP run in the checksum's pass over memory (the block tests
 * while the bytes are in cache, lbk_lmap_hash_prescan): the same issues at the same offsets as the
 * zstd-compressed copy of the section, which takes the ordinary path; and a corrupted lightmap
 * still reports its checksum (214) and nothing else. */
static void test_lmap_fused_scan(void **state)
{
    (void)state;
    enum { W = 64, H = 40 }; /* 2560 texels: two full 1024-texel blocks and a partial one per plane */
    static lbk_ahd_texel tx[W * H];
    for (int i = 0; i < W * H; i++) {
        tx[i].irradiance_z = 0x3c003c00u;
        tx[i].rgba[0] = 255, tx[i].rgba[1] = 128, tx[i].rgba[2] = 128, tx[i].rgba[3] = 255;
    }
    tx[1500].irradiance_z = 0x7c0u;                         /* Inf in R: 509, block 1 */
    tx[2400].irradiance_z = 0xf8000000u;                    /* B: 509, the partial block */
    tx[10].rgba[1] = 128, tx[10].rgba[2] = 128, tx[10].rgba[3] = 20; /* short direction: 510, block 0 */
    const lbk_lmap_page_desc pg = {W, H, tx};
    lbk_lmap_build_desc bd = LBK_LMAP_BUILD_DESC_INIT;
    bd.pages = &pg;
    bd.page_count = 1;
    void *lm;
    size_t lm_n;
    assert_int_equal(lbk_lmap_build(&bd, NULL, &lm, &lm_n), LBK_OK);
    collected got[2];
    lbk_validate_summary sm[2];
    uint64_t lmap_offset[2];
    for (int z = 0; z < 2; z++) {
        lbk_writer *w;
        void *file;
        size_t n;
        const lbk_section_options zo = {.compression = LBK_COMPRESSION_ZSTD, .zstd_level = 3};
        assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, lm, lm_n, z ? &zo : NULL), LBK_OK);
        assert_int_equal(lbk_writer_to_memory(w, &file, &n), LBK_OK);
        lbk_writer_close(w);
        lmap_offset[z] = rd64((const uint8_t *)file + 64 + 16);
        got[z] = validate(file, n, &sm[z]);
        /* through a reader too: the same */
        lbk_reader *r;
        collected c = {0};
        lbk_validate_summary sr;
        assert_int_equal(lbk_reader_open_memory(file, n, NULL, &r), LBK_OK);
        assert_int_equal(lbk_reader_validate(r, collect, &c, &sr), LBK_OK);
        lbk_reader_close(r);
        assert_int_equal(c.count, got[z].count);
        assert_memory_equal(c.ids, got[z].ids, sizeof c.ids[0] * c.count);
        if (!z) { /* a flipped texel byte: the checksum, nothing from the texels */
            uint8_t *bad = malloc(n);
            memcpy(bad, file, n);
            bad[lmap_offset[0] + 200] ^= 0x01;
            lbk_validate_summary sb;
            collected cb = validate(bad, n, &sb);
            assert_true(has_id(&cb, 214));
            assert_false(has_id(&cb, 509) || has_id(&cb, 510));
            free(bad);
        }
        lbk_free(NULL, file);
    }
    lbk_free(NULL, lm);
    /* the 221 warning (no OBJS), 509 twice, 510 once; uncompressed offsets are file offsets */
    for (int z = 0; z < 2; z++) {
        assert_true(has_id(&got[z], 509) && has_id(&got[z], 510));
        assert_int_equal(sm[z].errors, got[0].count - sm[0].warnings);
    }
    assert_int_equal(got[0].count, got[1].count);
    assert_memory_equal(got[0].ids, got[1].ids, sizeof got[0].ids[0] * got[0].count);
    int n509 = 0;
    for (uint32_t i = 0; i < got[0].count; i++) {
        if (got[0].ids[i] == 509) {
            const uint64_t at = got[0].offsets[i] - lmap_offset[0];
            assert_true(at == 48 + 4 * 1500 || at == 48 + 4 * 2400);
            n509++;
        }
        if (got[0].ids[i] == 510) assert_int_equal(got[0].offsets[i] - lmap_offset[0], 48 + 4 * W * H + 4 * 10 + 0);
    }
    assert_int_equal(n509, 2);
}

/* Format 1.2: a file with a block-encoded LMAP page says so (minor 2, required feature
 * LMAP_BLOCK) and validates clean; a 1.0 LMAP keeps minor 0 and no feature bit. */
static void test_lmap_block_version(void **state)
{
    (void)state;
    uint8_t p0[16] = {0x03}, p1[24] = {0};
    lbk_ahd_texel tx[16];
    memset(tx, 0, sizeof tx);
    const lbk_lmap_encoded_page enc = {4, 4, {LBK_LMAP_BC6H, LBK_LMAP_BC5_BC4}, {p0, p1}};
    const lbk_lmap_page_desc plain = {4, 4, tx};
    for (int block = 0; block < 2; block++) {
        lbk_lmap_build_desc bd = LBK_LMAP_BUILD_DESC_INIT;
        bd.page_count = 1;
        if (block) bd.encoded = &enc;
        else bd.pages = &plain;
        void *lm, *file;
        size_t lm_n, n;
        assert_int_equal(lbk_lmap_build(&bd, NULL, &lm, &lm_n), LBK_OK);
        lbk_writer *w;
        assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, lm, lm_n, NULL), LBK_OK);
        assert_int_equal(lbk_writer_to_memory(w, &file, &n), LBK_OK);
        lbk_writer_close(w);
        lbk_free(NULL, lm);
        lbk_reader *r;
        assert_int_equal(lbk_reader_open_memory(file, n, NULL, &r), LBK_OK);
        const lbk_header_info *h = lbk_reader_header(r);
        assert_int_equal(h->version_minor, block ? 2 : 0);
        assert_int_equal(h->required_features & LBK_FEATURE_LMAP_BLOCK, block ? LBK_FEATURE_LMAP_BLOCK : 0);
        int issues = 0;
        lbk_validate_summary sm;
        assert_int_equal(lbk_reader_validate(r, count_issue, &issues, &sm), LBK_OK);
        assert_int_equal(sm.errors + sm.fatal, 0);
        lbk_reader_close(r);
        lbk_free(NULL, file);
    }
}

static void test_registry_sorted(void **state)
{
    (void)state;
    uint32_t n = lbk_issue_registry_count();
    assert_true(n >= 60);
    for (uint32_t i = 1; i < n; i++) assert_true(lbk_issue_registry_id(i - 1) < lbk_issue_registry_id(i));
    assert_int_equal(lbk_issue_registry_id(n), 0);
    lbk_severity sev;
    assert_null(lbk_issue_template(99999, &sev));
    assert_non_null(lbk_issue_template(104, &sev));
    assert_int_equal(sev, LBK_SEVERITY_FATAL);
    assert_int_equal(lbk_issue_section(300), LBK_SECTION_META);
    assert_int_equal(lbk_issue_section(104), 0);
    for (int r = 0; r < LBK_RESULT_COUNT_; r++) {
        assert_non_null(strstr(lbk_result_name((lbk_result)r), "LBK_"));
        assert_true(strlen(lbk_result_message((lbk_result)r)) > 3);
    }
    char cc[5];
    lbk_fourcc_string(LBK_SECTION_GLG, cc);
    assert_string_equal(cc, "GLG ");
    lbk_fourcc_string(0x01424140u, cc);
    assert_string_equal(cc, "@AB?");
}

/* spec/validation.md lists every registered ID with the same severity (tests run from the
 * repository root). */
static void test_registry_matches_spec(void **state)
{
    (void)state;
    FILE *f = fopen("spec/validation.md", "r");
    assert_non_null(f);
    static char seen[2000];
    memset(seen, 0, sizeof seen);
    char line[512];
    while (fgets(line, sizeof line, f)) {
        unsigned id;
        char sev[16];
        if (sscanf(line, "| %u | %15[a-z] |", &id, sev) != 2 || id >= sizeof seen) continue;
        lbk_severity expect;
        const char *msg = lbk_issue_template(id, &expect);
        if (!msg) fail_msg("spec/validation.md lists ID %u which the registry lacks", id);
        const char *names[] = {"warning", "error", "fatal"};
        if (strcmp(sev, names[expect])) fail_msg("ID %u: spec says %s, registry says %s", id, sev, names[expect]);
        seen[id] = 1;
    }
    fclose(f);
    for (uint32_t i = 0; i < lbk_issue_registry_count(); i++) {
        uint32_t id = lbk_issue_registry_id(i);
        if (id >= sizeof seen || !seen[id]) fail_msg("registry ID %u is missing from spec/validation.md", id);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_deterministic_and_canonical),
        cmocka_unit_test(test_every_alignment),
        cmocka_unit_test(test_reader_rejections),
        cmocka_unit_test(test_unknown_sections),
        cmocka_unit_test(test_decoded_cap_stops_bomb),
        cmocka_unit_test(test_reader_validate_decodes_once),
        cmocka_unit_test(test_allocator_hooks),
        cmocka_unit_test(test_writer_arguments),
        cmocka_unit_test(test_atomic_file_write),
        cmocka_unit_test(test_validator_framing_ids),
        cmocka_unit_test(test_lmap_block_version),
        cmocka_unit_test(test_lmap_fused_scan),
        cmocka_unit_test(test_registry_sorted),
        cmocka_unit_test(test_registry_matches_spec),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
