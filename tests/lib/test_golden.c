/* Golden containers (the .lbk files in tests/golden, see tests/golden/README.md):
 *  (a) rebuilt from the fixed content of tests/support/container_fixture.c they must equal the
 *      committed bytes exactly — a difference is a format change and needs a version decision;
 *  (b) read by a minimal reader written here from the text of spec/container.md alone (field
 *      offsets from the §2/§3/§6–§8 tables; only xxhash and zstd from outside), which proves the
 *      documented layout is the real one.
 * LBK_GOLDEN_WRITE=1 rewrites the files instead of comparing (only on a deliberate change). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>
#include <zstd.h>

#include "lbk/container.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/validate.h"
#include "support/container_fixture.h"

/* ---- building the golden content ----------------------------------------------------------- */

/* small.lbk: the 4-section fixture (META, REPT zstd, OBJS, XTRA), alignment 64.
 * align16.lbk: META and OBJS, uncompressed, alignment 16 (independent of the zstd version). */
static int build_golden(const char *name, void **out, size_t *size)
{
    if (!strcmp(name, "small.lbk")) return fixture_small_container(0, out, size);
    void *meta, *objs, *bytes;
    size_t mn, on;
    if (fixture_meta(&meta, &mn) || fixture_objects(&objs, &on)) return 1;
    lbk_write_options wo = {.section_alignment = 16};
    lbk_writer *w;
    int rc = lbk_writer_open(&wo, &w) != LBK_OK || lbk_writer_section_add(w, LBK_SECTION_OBJS, objs, on, NULL) ||
             lbk_writer_section_add(w, LBK_SECTION_META, meta, mn, NULL) ||
             lbk_writer_to_memory(w, &bytes, size) != LBK_OK;
    if (!rc) {
        *out = malloc(*size);
        memcpy(*out, bytes, *size);
        lbk_free(NULL, bytes);
    }
    lbk_writer_close(w);
    lbk_free(NULL, meta);
    lbk_free(NULL, objs);
    return rc;
}

static const char *golden_names[] = {"small.lbk", "align16.lbk"};

static uint8_t *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc(n > 0 ? (size_t)n : 1);
    *size = fread(b, 1, (size_t)n, f);
    fclose(f);
    return b;
}

static void test_rebuild_matches_golden(void **state)
{
    (void)state;
    const char *write = getenv("LBK_GOLDEN_WRITE");
    for (size_t g = 0; g < sizeof golden_names / sizeof golden_names[0]; g++) {
        char path[256];
        snprintf(path, sizeof path, "tests/golden/%s", golden_names[g]);
        void *built;
        size_t n;
        assert_int_equal(build_golden(golden_names[g], &built, &n), 0);
        if (write && !strcmp(write, "1")) {
            FILE *f = fopen(path, "wb");
            assert_non_null(f);
            assert_int_equal(fwrite(built, 1, n, f), n);
            fclose(f);
            print_message("wrote %s (%zu bytes)\n", path, n);
        }
        size_t gn = 0;
        uint8_t *golden = read_file(path, &gn);
        if (!golden) fail_msg("%s missing (run with LBK_GOLDEN_WRITE=1 once)", path);
        if (gn != n || memcmp(golden, built, n)) {
            size_t first = 0;
            while (first < n && first < gn && golden[first] == ((uint8_t *)built)[first]) first++;
            fail_msg("%s: rebuilt bytes differ from the golden file (sizes %zu/%zu, first difference at %zu). "
                     "A format change needs a version decision (spec/container.md §1.3).",
                     path, n, gn, first);
        }
        lbk_validate_summary s;
        assert_int_equal(lbk_validate_memory(golden, gn, NULL, NULL, NULL, &s), LBK_OK);
        assert_int_equal(s.fatal + s.errors, 0);
        free(golden);
        free(built);
    }
}

/* ---- an independent reader, from the spec text ---------------------------------------------- */

static uint16_t u16(const uint8_t *p) { return (uint16_t)(p[0] | p[1] << 8); }
static uint32_t u32(const uint8_t *p) { return u16(p) | (uint32_t)u16(p + 2) << 16; }
static uint64_t u64(const uint8_t *p) { return u32(p) | (uint64_t)u32(p + 4) << 32; }
static float f32(const uint8_t *p)
{
    uint32_t u = u32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}
static double f64(const uint8_t *p)
{
    uint64_t u = u64(p);
    double d;
    memcpy(&d, &u, 8);
    return d;
}

typedef struct spec_section {
    char type[5];
    uint32_t flags, compression;
    uint64_t offset, stored, decoded;
    uint8_t *data; /* decoded copy */
} spec_section;

typedef struct spec_file {
    uint32_t count, alignment, required;
    spec_section s[8];
} spec_file;

/* §2, §3, §4 as written: header fields, table entries, placement, zero padding, checksums, zstd. */
static void spec_read(const uint8_t *f, size_t size, spec_file *out)
{
    static const uint8_t magic[8] = {0x89, 'L', 'B', 'K', 0x0d, 0x0a, 0x1a, 0x0a};
    assert_true(size >= 64);
    assert_memory_equal(f, magic, 8);
    assert_int_equal(u16(f + 8), 1);                      /* version_major */
    assert_int_equal(u16(f + 10), 0);                     /* version_minor */
    assert_int_equal(u32(f + 12), 64);                    /* header_size */
    assert_int_equal(u64(f + 16), size);                  /* file_size */
    out->required = u32(f + 24);                          /* required_features */
    assert_int_equal(u32(f + 28), 0);                     /* optional_features */
    out->count = u32(f + 32);                             /* section_count */
    out->alignment = u32(f + 36);                         /* section_alignment */
    assert_int_equal(u64(f + 40), 64);                    /* section_table_offset */
    assert_int_equal(u64(f + 48), XXH3_64bits(f + 64, 48 * (size_t)out->count)); /* table_checksum */
    assert_int_equal(u64(f + 56), XXH3_64bits(f, 56));    /* header_checksum */
    assert_true(out->count >= 1 && out->count <= 8);
    uint64_t end = 64 + 48 * (uint64_t)out->count;
    int any_zstd = 0;
    for (uint32_t i = 0; i < out->count; i++) {
        const uint8_t *e = f + 64 + 48 * i;
        spec_section *s = &out->s[i];
        memcpy(s->type, e, 4);
        s->type[4] = 0;
        s->flags = u32(e + 4);
        s->compression = u32(e + 8);
        assert_int_equal(u32(e + 12), 0);
        s->offset = u64(e + 16);
        s->stored = u64(e + 24);
        s->decoded = u64(e + 32);
        uint64_t expect = (end + out->alignment - 1) / out->alignment * out->alignment; /* §3.3 */
        assert_int_equal(s->offset, expect);
        for (uint64_t p = end; p < s->offset; p++) assert_int_equal(f[p], 0);
        assert_true(s->offset + s->stored <= size);
        assert_int_equal(u64(e + 40), XXH3_64bits(f + s->offset, s->stored));
        s->data = malloc(s->decoded);
        if (s->compression == 0) {
            assert_int_equal(s->decoded, s->stored);
            memcpy(s->data, f + s->offset, s->stored);
        } else {
            assert_int_equal(s->compression, 1);
            any_zstd = 1;
            assert_int_equal(ZSTD_getFrameContentSize(f + s->offset, s->stored), s->decoded);
            assert_int_equal(ZSTD_decompress(s->data, s->decoded, f + s->offset, s->stored), s->decoded);
        }
        end = s->offset + s->stored;
    }
    assert_int_equal(end, size);
    assert_int_equal(out->required, any_zstd ? 1u : 0u);
}

static void spec_free(spec_file *sf)
{
    for (uint32_t i = 0; i < sf->count; i++) free(sf->s[i].data);
}

/* §6.1: META entries → check the fixture's pairs, sorted and packed. */
static void spec_check_meta(const spec_section *s)
{
    const uint8_t *d = s->data;
    uint32_t n = u32(d), strings = u32(d + 4);
    assert_int_equal(u32(d + 8) | u32(d + 12), 0);
    assert_int_equal(s->decoded, 16 + 16 * (uint64_t)n + strings);
    const char *keys[] = {"bake.preset", "bake.seed", "revision", "scene.hash", "writer", "writer.version"};
    const char *vals[] = {"fast", "1", "r42 \xc3\xa9t\xc3\xa9", "0123456789abcdef", "lbk", "1.0.0"};
    assert_int_equal(n, 6);
    const uint8_t *blob = d + 16 + 16 * n;
    uint32_t at = 0;
    for (uint32_t i = 0; i < n; i++) {
        const uint8_t *e = d + 16 + 16 * i;
        assert_int_equal(u32(e), at);
        assert_int_equal(u32(e + 4), strlen(keys[i]));
        assert_memory_equal(blob + at, keys[i], strlen(keys[i]));
        at += u32(e + 4);
        assert_int_equal(u32(e + 8), at);
        assert_int_equal(u32(e + 12), strlen(vals[i]));
        assert_memory_equal(blob + at, vals[i], strlen(vals[i]));
        at += u32(e + 12);
    }
    assert_int_equal(at, strings);
}

/* §7.1: REPT header and the four records of the fixture. */
static void spec_check_rept(const spec_section *s)
{
    const uint8_t *d = s->data;
    assert_int_equal(u32(d + 0), 1); /* target reached */
    assert_int_equal(u32(d + 4), 0); /* no HAS_TIMES */
    assert_int_equal(u32(d + 8), 4);
    assert_int_equal(u32(d + 12), 256);
    assert_true(f64(d + 16) == 0.0);
    assert_true(f32(d + 24) == 0.15f);
    assert_int_equal(u32(d + 28), 0);
    assert_int_equal(s->decoded, 32 + 4 * 32);
    const uint32_t spt[4] = {4, 8, 16, 32};
    const float err[4] = {0.5f, 0.35f, 0.25f, 0.125f}, probe_err[4] = {0.25f, 0.18f, 0.125f, 0.0625f};
    for (int i = 0; i < 4; i++) {
        const uint8_t *r = d + 32 + 32 * i;
        assert_true(f64(r) == 0.0);
        assert_int_equal(u64(r + 8), 1000000ull << i);
        assert_int_equal(u32(r + 16), spt[i]);
        assert_int_equal(u32(r + 20), 2);
        assert_true(f32(r + 24) == err[i]);
        assert_true(f32(r + 28) == probe_err[i]);
    }
}

/* §8.1: OBJS records and names of the fixture. */
static void spec_check_objs(const spec_section *s)
{
    const uint8_t *d = s->data;
    uint32_t n = u32(d), names = u32(d + 4);
    assert_int_equal(u64(d + 8), 0);
    assert_int_equal(n, 3);
    assert_int_equal(s->decoded, 16 + 40 * (uint64_t)n + names);
    const char *nm[] = {"floor", "wall_north", "lamp"};
    const uint64_t hash[] = {0x1111222233334444ull, 0x5555666677778888ull, 0x99990000aaaabbbbull};
    const uint8_t *blob = d + 16 + 40 * n;
    for (uint32_t i = 0; i < n; i++) {
        const uint8_t *r = d + 16 + 40 * i;
        assert_int_equal(u32(r + 4), strlen(nm[i]));
        assert_memory_equal(blob + u32(r), nm[i], strlen(nm[i]));
        assert_int_equal(u64(r + 8), hash[i]);
        assert_int_equal(u32(r + 16), 2); /* representation none */
        for (int k = 20; k < 40; k += 4) assert_int_equal(u32(r + k), 0);
    }
}

static void test_spec_reader_small(void **state)
{
    (void)state;
    size_t n;
    uint8_t *f = read_file("tests/golden/small.lbk", &n);
    assert_non_null(f);
    spec_file sf;
    spec_read(f, n, &sf);
    assert_int_equal(sf.count, 4);
    assert_int_equal(sf.alignment, 64);
    const char *order[] = {"META", "REPT", "OBJS", "XTRA"}; /* §3.2: canonical, unknown last */
    for (int i = 0; i < 4; i++) assert_string_equal(sf.s[i].type, order[i]);
    assert_int_equal(sf.s[1].compression, 1);
    spec_check_meta(&sf.s[0]);
    spec_check_rept(&sf.s[1]);
    spec_check_objs(&sf.s[2]);
    assert_int_equal(sf.s[3].decoded, sizeof fixture_xtra);
    assert_memory_equal(sf.s[3].data, fixture_xtra, sizeof fixture_xtra);
    spec_free(&sf);
    free(f);
}

static void test_spec_reader_align16(void **state)
{
    (void)state;
    size_t n;
    uint8_t *f = read_file("tests/golden/align16.lbk", &n);
    assert_non_null(f);
    spec_file sf;
    spec_read(f, n, &sf);
    assert_int_equal(sf.count, 2);
    assert_int_equal(sf.alignment, 16);
    assert_string_equal(sf.s[0].type, "META");
    assert_string_equal(sf.s[1].type, "OBJS");
    assert_int_equal(sf.s[0].offset, 160); /* 64 + 2·48 = 160, already 16-aligned */
    spec_check_meta(&sf.s[0]);
    spec_check_objs(&sf.s[1]);
    spec_free(&sf);
    free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rebuild_matches_golden),
        cmocka_unit_test(test_spec_reader_small),
        cmocka_unit_test(test_spec_reader_align16),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
