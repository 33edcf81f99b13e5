/* META, REPT and OBJS: exact bytes of small builds, round trips through the views, builder
 * rejections, and every validator rule (IDs 300–414), including OBJS cross-checks against
 * real LMAP and LLG sections. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/report.h"
#include "lbk/validate.h"

static uint32_t rd32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static void wr32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i));
}
static void wrf32(uint8_t *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    wr32(p, u);
}
static void wrf64(uint8_t *p, double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    for (int i = 0; i < 8; i++) p[i] = (uint8_t)(u >> (8 * i));
}

/* ---- running the validator over sections ------------------------------------------------ */

typedef struct issues {
    uint32_t ids[256];
    uint32_t count;
} issues;

static int collect(void *user, const lbk_issue *issue)
{
    issues *c = user;
    if (c->count < 256) c->ids[c->count++] = issue->id;
    return 0;
}

static int has(const issues *c, uint32_t id)
{
    for (uint32_t i = 0; i < c->count; i++)
        if (c->ids[i] == id) return 1;
    return 0;
}

/* IDs in [lo, hi] reported. */
static uint32_t count_in(const issues *c, uint32_t lo, uint32_t hi)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < c->count; i++) n += c->ids[i] >= lo && c->ids[i] <= hi;
    return n;
}

typedef struct section {
    uint32_t type;
    const void *data;
    size_t size;
} section;

static issues validate_sections(const section *s, size_t n, int zstd)
{
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    lbk_section_options o = {.compression = zstd ? LBK_COMPRESSION_ZSTD : 0, .zstd_level = 1};
    for (size_t i = 0; i < n; i++) assert_int_equal(lbk_writer_section_add(w, s[i].type, s[i].data, s[i].size, &o), LBK_OK);
    void *bytes;
    size_t size;
    assert_int_equal(lbk_writer_to_memory(w, &bytes, &size), LBK_OK);
    lbk_writer_close(w);
    issues c = {{0}, 0};
    lbk_validate_summary sum;
    assert_int_equal(lbk_validate_memory(bytes, size, NULL, collect, &c, &sum), LBK_OK);
    assert_int_equal(sum.fatal + sum.errors + sum.warnings, c.count);
    lbk_free(NULL, bytes);
    return c;
}

static issues validate_one(uint32_t type, const void *data, size_t size)
{
    section s = {type, data, size};
    return validate_sections(&s, 1, 0);
}

/* ---- META ---------------------------------------------------------------------------------- */

static void test_meta_exact_bytes(void **state)
{
    (void)state;
    const lbk_meta_pair pairs[] = {{"writer", "lbk"}, {"a", ""}};
    void *b;
    size_t n;
    assert_int_equal(lbk_meta_build(pairs, 2, NULL, &b, &n), LBK_OK);
    /* header 16 + 2 entries × 16 + blob "a" + "" + "writer" + "lbk" (10 bytes) */
    static const uint8_t expect[58] = {
        2, 0, 0, 0, 10, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, /* count, strings_size, reserved */
        0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, /* "a" at 0+1, "" at 1+0 */
        1, 0, 0, 0, 6, 0, 0, 0, 7, 0, 0, 0, 3, 0, 0, 0, /* "writer" at 1+6, "lbk" at 7+3 */
        'a', 'w', 'r', 'i', 't', 'e', 'r', 'l', 'b', 'k',
    };
    assert_int_equal(n, sizeof expect);
    assert_memory_equal(b, expect, n);
    lbk_free(NULL, b);
}

static void test_meta_round_trip(void **state)
{
    (void)state;
    char hex[17];
    lbk_meta_hash_hex(0x0123456789abcdefull, hex);
    assert_string_equal(hex, "0123456789abcdef");
    const lbk_meta_pair pairs[] = {
        {"writer.version", "1.0.0"}, {"writer", "lbk"}, {"scene.hash", hex}, {"bake.seed", "7"},
        {"revision", "caf\xc3\xa9 \xf0\x9f\x92\xa1"}, {"timestamp", "2024-01-02T03:04:05Z"},
    };
    void *b;
    size_t n;
    assert_int_equal(lbk_meta_build(pairs, 6, NULL, &b, &n), LBK_OK);
    lbk_meta_view v;
    assert_int_equal(lbk_meta_open(b, n, &v), LBK_OK);
    assert_int_equal(v.entry_count, 6);
    const char *sorted[] = {"bake.seed", "revision", "scene.hash", "timestamp", "writer", "writer.version"};
    for (uint32_t i = 0; i < 6; i++) {
        lbk_string k, val;
        assert_int_equal(lbk_meta_entry_get(&v, i, &k, &val), LBK_OK);
        assert_int_equal(k.size, strlen(sorted[i]));
        assert_memory_equal(k.data, sorted[i], k.size);
    }
    lbk_string val;
    assert_int_equal(lbk_meta_find(&v, "revision", &val), LBK_OK);
    assert_int_equal(val.size, strlen(pairs[4].value));
    assert_memory_equal(val.data, pairs[4].value, val.size);
    assert_int_equal(lbk_meta_find(&v, "writer.versio", &val), LBK_ERR_NOT_FOUND);
    assert_int_equal(lbk_meta_entry_get(&v, 6, NULL, NULL), LBK_ERR_NOT_FOUND);
    issues c = validate_one(LBK_SECTION_META, b, n);
    assert_int_equal(c.count, 0);
    /* parse rejects what would be unsafe to view */
    assert_int_equal(lbk_meta_open(b, n - 1, &v), LBK_ERR_TRUNCATED);
    assert_int_equal(lbk_meta_open(b, 15, &v), LBK_ERR_TRUNCATED);
    uint8_t *m = malloc(n + 1);
    memcpy(m, b, n);
    m[n] = 0;
    assert_int_equal(lbk_meta_open(m, n + 1, &v), LBK_ERR_CORRUPT);
    wr32(m + 16 + 4, 0x7fffffff); /* key length past the blob */
    assert_int_equal(lbk_meta_open(m, n, &v), LBK_ERR_CORRUPT);
    free(m);
    lbk_free(NULL, b);
}

static void test_meta_builder_rejects(void **state)
{
    (void)state;
    void *b;
    size_t n;
    const char *bad_keys[] = {"", "Writer", "a b", "caf\xc3\xa9",
                              "kxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx"};
    for (size_t i = 0; i < 5; i++) {
        lbk_meta_pair p = {bad_keys[i], "x"};
        assert_int_equal(lbk_meta_build(&p, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    }
    lbk_meta_pair ok64 = {"kxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx", "x"};
    assert_int_equal(strlen(ok64.key), 64);
    assert_int_equal(lbk_meta_build(&ok64, 1, NULL, &b, &n), LBK_OK);
    lbk_free(NULL, b);
    const char *bad_values[] = {"\xc0\xaf" /* overlong '/' */, "\xed\xa0\x80" /* surrogate */, "\xe2\x82" /* cut */,
                                "\xf4\x90\x80\x80" /* > U+10FFFF */, "\x80"};
    for (size_t i = 0; i < 5; i++) {
        lbk_meta_pair p = {"writer", bad_values[i]};
        assert_int_equal(lbk_meta_build(&p, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    }
    lbk_meta_pair dup[] = {{"writer", "a"}, {"bake.x", "1"}, {"writer", "b"}};
    assert_int_equal(lbk_meta_build(dup, 3, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_meta_build(dup, 0, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
}

static void test_meta_validator_rules(void **state)
{
    (void)state;
    const lbk_meta_pair pairs[] = {{"bake.seed", "1"}, {"scene.hash", "00000000000000ff"}, {"writer", "lbk"}};
    void *b;
    size_t n;
    assert_int_equal(lbk_meta_build(pairs, 3, NULL, &b, &n), LBK_OK);
    uint8_t *m = malloc(n + 8);
    const uint8_t *blob = (const uint8_t *)b + 16 + 48;
    size_t writer_key = 9 + 1 + 10 + 16; /* "bake.seed" "1" "scene.hash" <16 hex> */
    assert_memory_equal(blob + writer_key, "writer", 6);
    issues c;
#define MUTATE(stmt, id)                                                    \
    do {                                                                    \
        memcpy(m, b, n);                                                    \
        stmt;                                                               \
        c = validate_one(LBK_SECTION_META, m, n);                           \
        if (!has(&c, id)) fail_msg("expected META issue %d (%s)", id, #stmt); \
    } while (0)

    c = validate_one(LBK_SECTION_META, b, 12);
    assert_true(has(&c, 300));
    MUTATE(m[8] = 1, 301);
    c = validate_one(LBK_SECTION_META, b, n - 1);
    assert_true(has(&c, 302));
    MUTATE(wr32(m + 16 + 16 + 0, 11), 303);          /* second key not at its packed offset */
    MUTATE(m[64 + 10] = 'S', 304);                    /* "Scene.hash" */
    MUTATE(memcpy(m + 64, "zzzz", 4), 305);           /* "zzzz.seed" sorts after "scene.hash" */
    MUTATE(m[64 + 9] = 0xff, 306);                    /* value of bake.seed */
    MUTATE(memcpy(m + 64 + writer_key, "wruter", 6), 307);
    MUTATE(wr32(m, 0); wr32(m + 4, 0), 302);          /* counts say empty but bytes follow */
    MUTATE(m[64 + 20 + 3] = 'X', 309);                /* scene.hash not lowercase hex */
    {
        uint8_t empty[16] = {0};
        c = validate_one(LBK_SECTION_META, empty, 16);
        assert_true(has(&c, 308));
        assert_false(has(&c, 302));
    }
    const lbk_meta_pair bad_time[] = {{"timestamp", "2024-01-02 03:04:05Z"}, {"writer", "lbk"}};
    void *t;
    size_t tn;
    assert_int_equal(lbk_meta_build(bad_time, 2, NULL, &t, &tn), LBK_OK); /* form is the validator's rule */
    c = validate_one(LBK_SECTION_META, t, tn);
    assert_int_equal(c.count, 1);
    assert_int_equal(c.ids[0], 309);
    lbk_free(NULL, t);
#undef MUTATE
    free(m);
    lbk_free(NULL, b);
}

/* ---- REPT ---------------------------------------------------------------------------------- */

static const lbk_report_record records[3] = {
    {1.5, 1000, 8, 3, 0.4f, 0.2f},
    {3.0, 2000, 16, 3, 0.2f, 0.1f},
    {6.25, 4000, 32, 3, 0.09f, 0.05f},
};

static void test_report_round_trip(void **state)
{
    (void)state;
    lbk_report rep = {.status = LBK_BAKE_TARGET_REACHED, .flags = LBK_REPORT_HAS_TIMES, .max_samples_per_texel = 64,
        .time_limit_seconds = 600.0, .target_rel_rmse = 0.1f, .records = records, .record_count = 3};
    void *b;
    size_t n;
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_OK);
    assert_int_equal(n, 32 + 3 * 32);
    const uint8_t *d = b;
    assert_int_equal(rd32(d), 1);
    assert_int_equal(rd32(d + 4), 1);
    assert_int_equal(rd32(d + 8), 3);
    assert_int_equal(rd32(d + 12), 64);
    assert_int_equal(rd32(d + 28), 0);
    lbk_report_view v;
    assert_int_equal(lbk_report_open(b, n, &v), LBK_OK);
    assert_int_equal(v.header.status, LBK_BAKE_TARGET_REACHED);
    assert_true(v.header.time_limit_seconds == 600.0);
    assert_true(v.header.target_rel_rmse == 0.1f);
    for (uint32_t i = 0; i < 3; i++) {
        lbk_report_record r;
        assert_int_equal(lbk_report_record_get(&v, i, &r), LBK_OK);
        assert_memory_equal(&r, &records[i], sizeof r);
    }
    lbk_report_record r;
    assert_int_equal(lbk_report_record_get(&v, 3, &r), LBK_ERR_NOT_FOUND);
    assert_string_equal(lbk_bake_status_name(2), "time limit");
    assert_string_equal(lbk_bake_status_name(9), "unknown");
    issues c = validate_one(LBK_SECTION_REPT, b, n);
    assert_int_equal(c.count, 0);
    c = validate_sections(&(section){LBK_SECTION_REPT, b, n}, 1, 1); /* zstd */
    assert_int_equal(c.count, 0);
    assert_int_equal(lbk_report_open(b, n - 1, &v), LBK_ERR_TRUNCATED);
    lbk_free(NULL, b);
}

static void test_report_builder_rejects(void **state)
{
    (void)state;
    void *b;
    size_t n;
    lbk_report_record rr[2] = {records[0], records[1]};
    lbk_report rep = {.status = LBK_BAKE_CONVERGED, .flags = LBK_REPORT_HAS_TIMES, .records = rr, .record_count = 2};
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_OK);
    lbk_free(NULL, b);
    rep.flags = 0; /* times present but not declared */
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_ERR_RANGE);
    rep.flags = LBK_REPORT_HAS_TIMES;
    rr[1].texel_rel_rmse = NAN;
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_ERR_RANGE);
    rr[1].texel_rel_rmse = INFINITY;
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_ERR_RANGE);
    rr[1] = records[1];
    rr[1].rays_traced = 10; /* goes backwards */
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_ERR_RANGE);
    rr[1] = records[1];
    rep.time_limit_seconds = -1;
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_ERR_RANGE);
    rep.time_limit_seconds = 0;
    rep.status = 4;
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    rep.status = 0;
    rep.record_count = 0;
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    /* -0 is written as +0: one encoding per value */
    lbk_report_record z = {-0.0, 0, 0, 0, -0.0f, 0};
    lbk_report rz = {.status = LBK_BAKE_CONVERGED, .time_limit_seconds = -0.0, .records = &z, .record_count = 1};
    assert_int_equal(lbk_report_build(&rz, NULL, &b, &n), LBK_OK);
    for (size_t i = 0; i < n; i++)
        if (i != 8) assert_int_equal(((uint8_t *)b)[i], 0); /* byte 8: record_count = 1 */
    lbk_free(NULL, b);
}

static void test_report_validator_rules(void **state)
{
    (void)state;
    lbk_report rep = {.status = LBK_BAKE_TARGET_REACHED, .flags = LBK_REPORT_HAS_TIMES, .max_samples_per_texel = 64,
        .time_limit_seconds = 600.0, .target_rel_rmse = 0.1f, .records = records, .record_count = 3};
    void *b;
    size_t n;
    assert_int_equal(lbk_report_build(&rep, NULL, &b, &n), LBK_OK);
    uint8_t *m = malloc(n);
    issues c;
#define MUTATE(stmt, id)                                                    \
    do {                                                                    \
        memcpy(m, b, n);                                                    \
        stmt;                                                               \
        c = validate_one(LBK_SECTION_REPT, m, n);                           \
        if (!has(&c, id)) fail_msg("expected REPT issue %d (%s)", id, #stmt); \
    } while (0)
    c = validate_one(LBK_SECTION_REPT, b, 31);
    assert_true(has(&c, 350));
    c = validate_one(LBK_SECTION_REPT, b, n - 32);
    assert_true(has(&c, 351));
    MUTATE(wr32(m, 4), 352);
    MUTATE(wr32(m + 4, 3), 353);
    MUTATE(wr32(m + 28, 1), 353);
    MUTATE(wrf64(m + 16, NAN), 354);
    MUTATE(wrf32(m + 24, -1.0f), 354);
    MUTATE(wrf32(m + 32 + 32 + 24, INFINITY), 354);
    MUTATE(wrf64(m + 32 + 64, 1.0), 355);               /* record 2 earlier than record 1 */
    MUTATE(wr32(m + 32 + 64 + 16, 1), 355);             /* fewer samples */
    MUTATE(wr32(m + 4, 0), 356);                        /* times without HAS_TIMES */
    MUTATE(wrf32(m + 24, 0.05f), 357);                  /* target 0.05 not reached by 0.09 */
    MUTATE(wr32(m, LBK_BAKE_SAMPLE_LIMIT), 357);        /* 32 samples < limit 64 */
    MUTATE(wr32(m, LBK_BAKE_TIME_LIMIT); wrf64(m + 16, 0.0), 357);
    {
        uint8_t h[32] = {0};
        c = validate_one(LBK_SECTION_REPT, h, 32);
        assert_true(has(&c, 358));
    }
    /* 357 is a warning: the file stays valid */
    memcpy(m, b, n);
    wr32(m, LBK_BAKE_SAMPLE_LIMIT);
    c = validate_one(LBK_SECTION_REPT, m, n);
    assert_int_equal(c.count, 1);
    lbk_severity sev;
    lbk_issue_template(357, &sev);
    assert_int_equal(sev, LBK_SEVERITY_WARNING);
#undef MUTATE
    free(m);
    lbk_free(NULL, b);
}

/* ---- OBJS ---------------------------------------------------------------------------------- */

static void test_objects_round_trip(void **state)
{
    (void)state;
    const lbk_object objs[] = {
        {{"crate", 5}, 0xabcdef0123456789ull, LBK_REPRESENTATION_LIGHTMAP, 1, 2, 3, 4, 5},
        {{"statue \xe2\x98\x83", 10}, 42, LBK_REPRESENTATION_LLG, 0, 0, 0, 0, 0},
        {{"sky", 3}, 7, LBK_REPRESENTATION_NONE, 0, 0, 0, 0, 0},
    };
    void *b;
    size_t n;
    assert_int_equal(lbk_objects_build(objs, 3, NULL, &b, &n), LBK_OK);
    assert_int_equal(n, 16 + 3 * 40 + 18);
    const uint8_t *d = b;
    assert_int_equal(rd32(d), 3);
    assert_int_equal(rd32(d + 4), 18);
    assert_int_equal(rd32(d + 16 + 40 + 0), 5); /* packed: second name after "crate" */
    assert_memory_equal(d + 16 + 120, "cratestatue \xe2\x98\x83sky", 18);
    lbk_objects_view v;
    assert_int_equal(lbk_objects_open(b, n, &v), LBK_OK);
    assert_int_equal(v.count, 3);
    for (uint32_t i = 0; i < 3; i++) {
        lbk_object o;
        assert_int_equal(lbk_objects_get(&v, i, &o), LBK_OK);
        assert_int_equal(o.name.size, objs[i].name.size);
        assert_memory_equal(o.name.data, objs[i].name.data, o.name.size);
        assert_int_equal(o.geometry_hash, objs[i].geometry_hash);
        assert_int_equal(o.representation, objs[i].representation);
        assert_int_equal(o.index, objs[i].index);
        assert_int_equal(o.rect_x, objs[i].rect_x);
        assert_int_equal(o.rect_h, objs[i].rect_h);
    }
    uint32_t idx;
    assert_int_equal(lbk_objects_find(&v, (lbk_string){"sky", 3}, &idx), LBK_OK);
    assert_int_equal(idx, 2);
    assert_int_equal(lbk_objects_find(&v, (lbk_string){"sk", 2}, &idx), LBK_ERR_NOT_FOUND);
    assert_string_equal(lbk_representation_name(1), "llg");
    assert_int_equal(lbk_objects_open(b, n - 1, &v), LBK_ERR_TRUNCATED);
    lbk_free(NULL, b);

    /* builder rejections */
    lbk_object bad = objs[0];
    bad.rect_w = 0;
    assert_int_equal(lbk_objects_build(&bad, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    bad = objs[1];
    bad.rect_x = 1;
    assert_int_equal(lbk_objects_build(&bad, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    bad = objs[2];
    bad.index = 1;
    assert_int_equal(lbk_objects_build(&bad, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    bad.index = 0;
    bad.representation = 3;
    assert_int_equal(lbk_objects_build(&bad, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    bad = objs[2];
    bad.name = (lbk_string){"", 0};
    assert_int_equal(lbk_objects_build(&bad, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    bad.name = (lbk_string){"a\0b", 3};
    assert_int_equal(lbk_objects_build(&bad, 1, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_objects_build(objs, 0, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
}

static void test_geometry_hash(void **state)
{
    (void)state;
    const float tri[9] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    float neg[9];
    memcpy(neg, tri, sizeof tri);
    neg[0] = -0.0f;
    uint8_t le[36];
    for (int i = 0; i < 9; i++) wrf32(le + 4 * i, tri[i]);
    assert_int_equal(lbk_objects_geometry_hash(tri, 1), XXH3_64bits(le, 36));
    assert_int_equal(lbk_objects_geometry_hash(neg, 1), lbk_objects_geometry_hash(tri, 1));
    /* longer than the internal chunk: equals the one-shot hash of all bytes */
    enum { T = 1000 };
    float *many = malloc(sizeof(float) * 9 * T);
    uint8_t *bytes = malloc(36 * T);
    for (int i = 0; i < 9 * T; i++) {
        many[i] = (float)i * 0.25f - 100.0f;
        wrf32(bytes + 4 * i, many[i]);
    }
    assert_int_equal(lbk_objects_geometry_hash(many, T), XXH3_64bits(bytes, 36 * T));
    assert_true(lbk_objects_geometry_hash(many, T) != lbk_objects_geometry_hash(many, T - 1));
    free(many);
    free(bytes);
}

/* A real LMAP with pages 16×8 and 4×4, and a real LLG with 2 grids, for the cross-checks. */
static void build_lmap_llg(void **lmap, size_t *lmap_n, void **llg, size_t *llg_n)
{
    static lbk_ahd_texel texels[16 * 8];
    for (int i = 0; i < 16 * 8; i++) texels[i] = (lbk_ahd_texel){0, {255, 128, 128, 255}};
    lbk_lmap_page_desc pages[2] = {{16, 8, texels}, {4, 4, texels}};
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages,
        .page_count = 2}, NULL, lmap, lmap_n), LBK_OK);
    static lbk_sh9_rgb probes[8];
    memset(probes, 0, sizeof probes);
    lbk_llg_grid_desc g = {{0, 0, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {1, 1, 1}, {2, 2, 2}, probes, NULL, 0};
    lbk_llg_grid_desc grids[2] = {g, g};
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = grids, .grid_count = 2}, NULL, llg, llg_n), LBK_OK);
}

static void test_objects_validator_rules(void **state)
{
    (void)state;
    void *lmap, *llg;
    size_t lmap_n, llg_n;
    build_lmap_llg(&lmap, &lmap_n, &llg, &llg_n);
    lbk_object objs[4] = {
        {{"a", 1}, 1, LBK_REPRESENTATION_LIGHTMAP, 0, 0, 0, 8, 8},
        {{"b", 1}, 2, LBK_REPRESENTATION_LIGHTMAP, 0, 8, 0, 8, 8},
        {{"c", 1}, 3, LBK_REPRESENTATION_LIGHTMAP, 1, 0, 0, 4, 4},
        {{"d", 1}, 4, LBK_REPRESENTATION_LLG, 1, 0, 0, 0, 0},
    };
    void *b;
    size_t n;
    assert_int_equal(lbk_objects_build(objs, 4, NULL, &b, &n), LBK_OK);
    section all[3] = {{LBK_SECTION_OBJS, b, n}, {LBK_SECTION_LMAP, lmap, lmap_n}, {LBK_SECTION_LLG, llg, llg_n}};
    issues c = validate_sections(all, 3, 0);
    assert_int_equal(count_in(&c, 200, 499), 0); /* the consistent file: no framing or OBJS issue */
    c = validate_sections(all, 3, 1);
    assert_int_equal(count_in(&c, 200, 499), 0);

    uint8_t *m = malloc(n);
    all[0].data = m;
#define MUTATE(stmt, id)                                                     \
    do {                                                                     \
        memcpy(m, b, n);                                                     \
        stmt;                                                                \
        c = validate_sections(all, 3, 0);                                    \
        if (!has(&c, id)) fail_msg("expected OBJS issue %d (%s)", id, #stmt); \
    } while (0)
    const size_t r0 = 16, r1 = 56, r2 = 96, r3 = 136; /* record offsets */
    MUTATE(m[12] = 1, 401);
    MUTATE(wr32(m + r1, 0), 403);                   /* name "b" not at offset 1 */
    MUTATE(m[176 + 1] = 0xff, 404);                 /* name "b" → invalid UTF-8 */
    MUTATE(m[176 + 1] = 'a', 405);                  /* two objects named "a" */
    MUTATE(wr32(m + r3 + 16, 3), 406);
    MUTATE(wr32(m + r3 + 24, 1), 407);              /* LLG with a rect */
    MUTATE(wr32(m + r0 + 20, 2), 409);              /* page 2 of 2 */
    MUTATE(wr32(m + r2 + 32, 5), 410);              /* 5 wide in a 4-wide page */
    MUTATE(wr32(m + r1 + 28, 1), 410);              /* y 1 + 8 > 8 */
    MUTATE(wr32(m + r3 + 20, 2), 412);              /* LLG 2 of 2 */
    MUTATE(wr32(m + r1 + 24, 4), 414);              /* b moves left onto a */
    c = validate_sections(all, 1, 0);               /* OBJS alone */
    assert_true(has(&c, 408));
    assert_true(has(&c, 411));
    /* LMAP present but corrupt: no cross-check, no 408 */
    uint8_t *bad_lmap = malloc(lmap_n);
    memcpy(bad_lmap, lmap, lmap_n);
    memset(bad_lmap, 0xee, 16);
    section broken[2] = {{LBK_SECTION_OBJS, b, n}, {LBK_SECTION_LMAP, bad_lmap, lmap_n}};
    c = validate_sections(broken, 2, 0);
    assert_false(has(&c, 408));
    assert_false(has(&c, 409));
    assert_true(has(&c, 411));
    assert_true(count_in(&c, 500, 599) > 0);
    free(bad_lmap);
    c = validate_one(LBK_SECTION_OBJS, b, 15);
    assert_true(has(&c, 400));
    c = validate_one(LBK_SECTION_OBJS, b, n - 1);
    assert_true(has(&c, 402));
    uint8_t empty[16] = {0};
    c = validate_one(LBK_SECTION_OBJS, empty, 16);
    assert_true(has(&c, 413));
    /* 221: LMAP without OBJS */
    c = validate_sections(all + 1, 1, 0);
    assert_true(has(&c, 221));
#undef MUTATE
    free(m);
    lbk_free(NULL, b);
    lbk_free(NULL, lmap);
    lbk_free(NULL, llg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_meta_exact_bytes),      cmocka_unit_test(test_meta_round_trip),
        cmocka_unit_test(test_meta_builder_rejects),  cmocka_unit_test(test_meta_validator_rules),
        cmocka_unit_test(test_report_round_trip),     cmocka_unit_test(test_report_builder_rejects),
        cmocka_unit_test(test_report_validator_rules), cmocka_unit_test(test_objects_round_trip),
        cmocka_unit_test(test_geometry_hash),         cmocka_unit_test(test_objects_validator_rules),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
