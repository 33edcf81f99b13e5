/* libFuzzer harness for the container reader and the validator: whatever the bytes, opening,
 * validating, and reading every section (and the META/REPT/OBJS views) must never crash, leak
 * or read out of bounds. Built and run by `make fuzz` (long) and `make test` (fixed runs).
 *
 * Random bytes rarely get past the checksums, so every input is tried twice: as it is, and with
 * its file_size, section checksums, table and header checksums recomputed, which lets the
 * fuzzer mutate section contents and reach every section validator. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/lightmap_uv.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/report.h"
#include "lbk/validate.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { DECODE_CAP = 16u << 20 }; /* keep bombs cheap; the cap itself is what is being tested */

static int count_issue(void *user, const lbk_issue *issue)
{
    (void)issue;
    ++*(size_t *)user;
    return 0;
}

static void read_views(uint32_t type, const void *d, size_t n)
{
    if (type == LBK_SECTION_META) {
        lbk_meta_view v;
        if (lbk_meta_open(d, n, &v) == LBK_OK) {
            for (uint32_t i = 0; i < v.entry_count && i < 4096; i++) {
                lbk_string k, val;
                lbk_meta_entry_get(&v, i, &k, &val);
                if (k.size && ((const volatile char *)k.data)[k.size - 1] == 0x7f) abort(); /* touch the bytes */
            }
            lbk_string val;
            lbk_meta_find(&v, "writer", &val);
        }
    } else if (type == LBK_SECTION_REPT) {
        lbk_report_view v;
        if (lbk_report_open(d, n, &v) == LBK_OK)
            for (uint32_t i = 0; i < v.header.record_count && i < 4096; i++) {
                lbk_report_record r;
                lbk_report_record_get(&v, i, &r);
            }
    } else if (type == LBK_SECTION_OBJS) {
        lbk_objects_view v;
        if (lbk_objects_open(d, n, &v) == LBK_OK) {
            for (uint32_t i = 0; i < v.count && i < 4096; i++) {
                lbk_object o;
                lbk_objects_get(&v, i, &o);
                if (o.name.size && ((const volatile char *)o.name.data)[o.name.size - 1] == 0x7f) abort();
            }
            uint32_t idx;
            lbk_objects_find(&v, (lbk_string){"a", 1}, &idx);
        }
    }
}

/* LMUV: whatever lbk_lmuv_open accepts, every element it promises is readable and in range. */
static void read_lmuv(const void *d, size_t n)
{
    lbk_lmuv_view v;
    if (lbk_lmuv_open(d, n, &v) != LBK_OK) return;
    for (uint32_t r = 0; r < v.record_count && r < 4096; r++) {
        lbk_lmuv_object o;
        uint32_t back;
        if (lbk_lmuv_get_object(&v, r, &o) != LBK_OK) abort();
        lbk_lmuv_find_object(&v, o.object, &back);
    }
    for (uint32_t p = 0; p < v.primitive_count && p < 4096; p++) {
        lbk_lmuv_primitive q;
        if (lbk_lmuv_get_primitive(&v, p, &q) != LBK_OK) abort();
        for (uint32_t i = 0; i < q.index_count && i < 65536; i++) {
            uint32_t x;
            if (lbk_lmuv_index(&v, &q, i, &x) != LBK_OK || x >= q.vertex_count) abort();
        }
        for (uint32_t k = 0; k < q.vertex_count && k < 65536; k++) {
            uint32_t src;
            float xy[2];
            if (lbk_lmuv_vertex(&v, &q, k, &src, xy) != LBK_OK || src >= q.source_vertex_count) abort();
        }
    }
}

/* LMAP, any page encoding (1.0 planes, BC6H, BC5/BC4, ASTC): whatever lbk_lmap_open accepts, every
 * page's planes lie inside the section and a few texels of each decode (or are refused cleanly). */
static void read_lmap(const void *d, size_t n)
{
    lbk_lmap_view v;
    lbk_lmap_required_features(d, n);
    if (lbk_lmap_open(d, n, &v) != LBK_OK) return;
    for (uint32_t p = 0; p < v.page_count && p < 64; p++) {
        lbk_lmap_planes pl;
        if (lbk_lmap_planes_get(&v, p, &pl) != LBK_OK) abort();
        for (int k = 0; k < 2; k++)
            if (pl.offset[k] > n || pl.bytes[k] > n - pl.offset[k]) abort();
        const uint32_t xs[3] = {0, pl.width / 2, pl.width - 1}, ys[3] = {0, pl.height / 2, pl.height - 1};
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                lbk_ahd_texel_f t;
                const lbk_result r = lbk_lmap_planes_texel_unpack(&pl, xs[i], ys[j], &t);
                if (r != LBK_OK && r != LBK_ERR_UNSUPPORTED_FEATURE) abort();
                float rgb[3];
                const float nz[3] = {0, 0, 1};
                lbk_lmap_planes_irradiance(&pl, xs[i], ys[j], nz, rgb);
            }
        lbk_lmap_planes_rect_bytes(&pl, 0, 0, pl.width, pl.height);
        lbk_lmap_page pg;
        const lbk_result r = lbk_lmap_page_get(&v, p, &pg);
        if (r != LBK_OK && !(r == LBK_ERR_UNSUPPORTED_FEATURE && pl.blocks_x)) abort();
    }
}

static int known_type(uint32_t t)
{
    static const uint32_t known[] = {LBK_SECTION_META, LBK_SECTION_REPT, LBK_SECTION_OBJS,
                                     LBK_SECTION_LMAP, LBK_SECTION_GLG,  LBK_SECTION_LLG,
                                     LBK_SECTION_DLS,  LBK_SECTION_DOOR, LBK_SECTION_OCTP,
                                     LBK_SECTION_LMUV};
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
        if (known[i] == t) return 1;
    return 0;
}

static void exercise(const uint8_t *data, size_t size)
{
    lbk_validate_options vo = {.max_decoded_bytes = DECODE_CAP};
    lbk_validate_summary s;
    size_t issues = 0;
    lbk_validate_memory(data, size, &vo, count_issue, &issues, &s);
    if (issues != (size_t)s.fatal + s.errors + s.warnings) abort();

    /* The reader and the validator share the framing rules: a file the validator passes must
     * open and give every known section's bytes. */
    const int valid = s.fatal == 0 && s.errors == 0;
    lbk_read_options ro = {.max_decoded_bytes = DECODE_CAP};
    lbk_reader *r;
    if (lbk_reader_open_memory(data, size, &ro, &r) != LBK_OK) {
        if (valid) abort();
        return;
    }
    if (s.fatal) abort(); /* the reader accepted what the validator found unreadable */
    for (uint32_t i = 0; i < lbk_reader_section_count(r); i++) {
        lbk_section_info si;
        if (lbk_reader_section_get(r, i, &si) != LBK_OK) abort();
        const void *d;
        size_t n;
        if (lbk_reader_section_data(r, i, &d, &n) == LBK_OK) {
            if (n != si.decoded_size) abort();
            read_views(si.type, d, n);
            if (si.type == LBK_SECTION_LMUV) read_lmuv(d, n);
            if (si.type == LBK_SECTION_LMAP) read_lmap(d, n);
        } else if (valid && known_type(si.type)) {
            abort();
        }
    }
    lbk_reader_close(r);
}

static uint32_t rd32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t rd64(const uint8_t *p) { return rd32(p) | (uint64_t)rd32(p + 4) << 32; }
static void wr64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i));
}

/* Recompute everything a checksum or file_size protects, so mutations inside sections survive. */
static void fix_up(uint8_t *f, size_t size)
{
    if (size < 64) return;
    wr64(f + 16, size);
    uint32_t n = rd32(f + 32);
    if (n >= 1 && n <= LBK_MAX_SECTIONS && 64 + 48 * (uint64_t)n <= size) {
        for (uint32_t i = 0; i < n; i++) {
            uint8_t *e = f + 64 + 48 * i;
            uint64_t off = rd64(e + 16), len = rd64(e + 24);
            if (off <= size && len <= size - off) wr64(e + 40, XXH3_64bits(f + off, (size_t)len));
        }
        wr64(f + 48, XXH3_64bits(f + 64, 48 * (size_t)n));
    }
    wr64(f + 56, XXH3_64bits(f, 56));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* An exact-size heap copy: any read past the end is caught by ASan. */
    uint8_t *copy = malloc(size ? size : 1);
    if (!copy) return 0;
    if (size) memcpy(copy, data, size);
    exercise(copy, size);
    fix_up(copy, size);
    exercise(copy, size);
    free(copy);
    return 0;
}
