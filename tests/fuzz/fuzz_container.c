/* libFuzzer harness for the container reader and the validator: whatever the bytes, opening,
 * validating, and reading every section (and the META/REPT/OBJS views) must never crash, leak
 * or read out of bounds. Built and run by `make fuzz` (long) and `make test` (fixed runs).
 *
 * Random bytes rarely get past the checksums, so every input is tried twice: as it is, and with
 * its file_size, section checksums, table and header checksums recomputed, which lets the
 * fuzzer mutate section contents and reach every section validator. A DLS section that opens
 * also goes through the runtime (the job planner and the kernels walk its runs, sub-groups and
 * prefix data): two applies and the dirty regions. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "lbk/container.h"
#include "lbk/dls.h"
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

/* A DLS view that opened: apply it over zero bases (small target spaces only, to stay fast). */
static void run_dls(const void *d, size_t n)
{
    lbk_dls_view *v;
    if (lbk_dls_open(d, n, NULL, &v) != LBK_OK) return;
    const uint64_t t = lbk_dls_target_count(v, 0), g = lbk_dls_target_count(v, 1), l = lbk_dls_target_count(v, 2);
    const uint32_t sets = lbk_dls_set_count(v);
    if (t <= (1u << 16) && g <= (1u << 14) && l <= (1u << 14) && sets <= 4096) {
        uint8_t *b = calloc(8 * t + 56 * (g + l) + 16, 1), *o = calloc(8 * t + 56 * (g + l) + 16, 1);
        float *w = calloc(sets + 1, sizeof *w);
        if (b && o && w) {
            lbk_dls_runtime_desc rd = {.dls = v};
            if (t) rd.base_irradiance_z = (const uint32_t *)(void *)b, rd.base_rgba = b + 4 * t,
            rd.out_irradiance_z = (uint32_t *)(void *)o, rd.out_rgba = o + 4 * t;
            if (g) rd.base_glg = b + 8 * t, rd.out_glg = o + 8 * t;
            if (l) rd.base_llg = b + 8 * t + 28 * g, rd.out_llg = o + 8 * t + 28 * g;
            lbk_dls_runtime *r;
            if (lbk_dls_runtime_open(&rd, &r) == LBK_OK) {
                for (uint32_t i = 0; i < sets; i++) w[i] = i % 3 ? 0.5f : 0.0f;
                lbk_dls_apply(r, w, NULL, NULL);
                w[0] = 2.0f;
                lbk_dls_apply(r, w, NULL, NULL);
                for (uint32_t s = 0; s < 3; s++) {
                    lbk_dls_range rg;
                    for (uint32_t i = 0; i < lbk_dls_dirty_range_count(r, s); i++) lbk_dls_dirty_range_get(r, s, i, &rg);
                }
                lbk_dls_runtime_close(r);
            }
        }
        free(b), free(o), free(w);
    }
    lbk_dls_close(v);
}

static void read_views(uint32_t type, const void *d, size_t n)
{
    if (type == LBK_SECTION_DLS) {
        run_dls(d, n);
    } else if (type == LBK_SECTION_META) {
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

static int known_type(uint32_t t)
{
    static const uint32_t known[] = {LBK_SECTION_META, LBK_SECTION_REPT, LBK_SECTION_OBJS,
                                     LBK_SECTION_LMAP, LBK_SECTION_GLG,  LBK_SECTION_LLG,
                                     LBK_SECTION_DLS,  LBK_SECTION_DOOR, LBK_SECTION_OCTP};
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
