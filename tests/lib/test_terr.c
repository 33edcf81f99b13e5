/* TERR (spec/container.md §18): the code scale (encode/decode against 2^((c − 161)/16)), builder →
 * view round trip inside a container (minor version 1.4, canonical place), every validation ID
 * 1200–1205 on a broken copy, a 1.3 reader's view of the file (an unknown optional type, skipped),
 * and the bytes of a file without TERR unchanged (minor version 0, no TERR entry). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/container.h"
#include "lbk/error_map.h"
#include "lbk/lightmap.h"
#include "lbk/objects.h"
#include "lbk/validate.h"

enum { W = 8, H = 4, N = W * H };

typedef struct issues {
    uint32_t id[256];
    int n;
} issues;

static int collect(void *user, const lbk_issue *issue)
{
    issues *is = user;
    if (is->n < 256) is->id[is->n++] = issue->id;
    return 0;
}

static int has(const issues *is, uint32_t id)
{
    for (int i = 0; i < is->n; i++)
        if (is->id[i] == id) return 1;
    return 0;
}

/* OBJS (one lightmapped object over the page), LMAP (one W×H page), and TERR bytes when given. */
static void container(const void *terr, size_t terr_size, int with_lmap, void **out, size_t *size)
{
    static lbk_ahd_texel texels[N];
    lbk_lmap_page_desc pg = {W, H, texels};
    lbk_object o = {0};
    o.name = (lbk_string){"a", 1};
    o.representation = LBK_REPRESENTATION_LIGHTMAP;
    o.rect_w = W, o.rect_h = H;
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    void *d;
    size_t n;
    lbk_section_options so = {0};
    if (with_lmap) {
        assert_int_equal(lbk_objects_build(&o, 1, NULL, &d, &n), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_OBJS, d, n, &so), LBK_OK);
        lbk_free(NULL, d);
        assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = &pg, .page_count = 1}, NULL, &d, &n), LBK_OK);
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_LMAP, d, n, &so), LBK_OK);
        lbk_free(NULL, d);
    }
    if (terr) assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_TERR, terr, terr_size, &so), LBK_OK);
    if (!with_lmap && !terr) {
        static const uint8_t meta[16] = {0};
        assert_int_equal(lbk_writer_section_add(w, LBK_SECTION_META, meta, 16, &so), LBK_OK);
    }
    assert_int_equal(lbk_writer_to_memory(w, out, size), LBK_OK);
    lbk_writer_close(w);
}

static void codes_fixture(uint8_t codes[N])
{
    for (int i = 0; i < N; i++) codes[i] = (uint8_t)(i * 8); /* 0 (no estimate) .. 248 */
}

static lbk_validate_summary validate(const void *terr, size_t terr_size, int with_lmap, issues *is)
{
    void *f;
    size_t n;
    container(terr, terr_size, with_lmap, &f, &n);
    memset(is, 0, sizeof *is);
    lbk_validate_summary sum;
    assert_int_equal(lbk_validate_memory(f, n, NULL, collect, is, &sum), LBK_OK);
    lbk_free(NULL, f);
    return sum;
}

/* The scale of §18.2: decode(c) = 2^((c − 161)/16); encode is the nearest code in log2, exact at
 * the codes themselves and switching half-way (in log2) between two codes. */
static void code_scale(void **state)
{
    (void)state;
    assert_true(lbk_terr_decode(0) == -1.0);
    assert_true(lbk_terr_decode(161) == 1.0);
    assert_true(lbk_terr_decode(177) == 2.0);
    assert_true(lbk_terr_decode(1) == ldexp(1.0, -10));
    assert_true(fabs(lbk_terr_decode(255) - exp2(94.0 / 16)) < 1e-12);
    int exact = 0;
    for (int c = 1; c < 256; c++) {
        const double s = lbk_terr_decode((uint8_t)c);
        exact += lbk_terr_encode((float)s) == c;
        if (c < 255) { /* just below / above the log-midpoint to the next code */
            const double mid = exp2(((c + 0.5) - 161) / 16);
            assert_int_equal(lbk_terr_encode((float)(mid * (1 - 1e-6))), c);
            assert_int_equal(lbk_terr_encode((float)(mid * (1 + 1e-6))), c + 1);
        }
    }
    assert_int_equal(exact, 255);
    assert_int_equal(lbk_terr_encode(0.0f), 1);         /* no noise: the smallest code */
    assert_int_equal(lbk_terr_encode(1e-30f), 1);
    assert_int_equal(lbk_terr_encode(1e30f), 255);
    assert_int_equal(lbk_terr_encode(-0.5f), 0);        /* no estimate */
    assert_int_equal(lbk_terr_encode(NAN), 0);
    assert_int_equal(lbk_terr_encode(INFINITY), 0);
    assert_int_equal(lbk_terr_encode(0.05f), 161 + (int)lrint(16 * log2(0.05))); /* 5 %: code 92 */
}

static void round_trip_and_version(void **state)
{
    (void)state;
    uint8_t codes[N];
    codes_fixture(codes);
    void *d;
    size_t n;
    assert_int_equal(lbk_terr_build(LBK_TERR_DENOISED, codes, N, NULL, &d, &n), LBK_OK);
    assert_int_equal(n, 16 + N);
    void *f;
    size_t fn;
    container(d, n, 1, &f, &fn);
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_memory(f, fn, NULL, &r), LBK_OK);
    assert_int_equal(lbk_reader_header(r)->version_minor, 4);
    /* canonical order (§3.2): OBJS, LMAP (ranked), then TERR by code */
    lbk_section_info si;
    assert_int_equal(lbk_reader_section_count(r), 3);
    assert_int_equal(lbk_reader_section_get(r, 2, &si), LBK_OK);
    assert_int_equal(si.type, LBK_SECTION_TERR);
    assert_int_equal(si.flags & LBK_SECTION_FLAG_REQUIRED, 0);
    const void *p;
    size_t pn;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_TERR, &p, &pn), LBK_OK);
    lbk_terr_view v;
    assert_int_equal(lbk_terr_open(p, pn, &v), LBK_OK);
    assert_int_equal(v.texel_count, N);
    assert_int_equal(v.flags, LBK_TERR_DENOISED);
    assert_memory_equal(v.codes, codes, N);
    uint8_t c;
    assert_int_equal(lbk_terr_code_get(&v, 5, &c), LBK_OK);
    assert_int_equal(c, 40);
    assert_int_equal(lbk_terr_code_get(&v, N, &c), LBK_ERR_NOT_FOUND);
    issues is = {0};
    lbk_validate_summary sum;
    assert_int_equal(lbk_reader_validate(r, collect, &is, &sum), LBK_OK);
    assert_int_equal(sum.errors + sum.fatal, 0);
    assert_false(has(&is, 213)); /* a known type: not "unknown optional section skipped" */
    lbk_reader_close(r);
    /* without TERR the same content is a 1.0 file (minor 0): the bytes of a 1.3 writer */
    void *g;
    size_t gn;
    container(NULL, 0, 1, &g, &gn);
    assert_int_equal(lbk_reader_open_memory(g, gn, NULL, &r), LBK_OK);
    assert_int_equal(lbk_reader_header(r)->version_minor, 0);
    assert_int_equal(lbk_reader_section_count(r), 2);
    lbk_reader_close(r);
    assert_true(fn > gn);
    lbk_free(NULL, g), lbk_free(NULL, f), lbk_free(NULL, d);
    /* the builder's refusals */
    assert_int_equal(lbk_terr_build(0, codes, 0, NULL, &d, &n), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_terr_build(2, codes, N, NULL, &d, &n), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_terr_build(0, NULL, N, NULL, &d, &n), LBK_ERR_INVALID_ARGUMENT);
}

/* Each ID of 1200–1205 on a copy broken for it, and only the clean copy passes. */
static void validation_ids(void **state)
{
    (void)state;
    uint8_t codes[N];
    codes_fixture(codes);
    uint8_t *d;
    size_t n;
    assert_int_equal(lbk_terr_build(0, codes, N, NULL, (void **)&d, &n), LBK_OK);
    issues is;
    lbk_validate_summary s = validate(d, n, 1, &is);
    assert_int_equal(s.errors + s.fatal, 0);
    s = validate(d, 10, 1, &is); /* 1200 */
    assert_true(has(&is, 1200) && s.errors == 1);
    uint8_t *b = malloc(n + 8);
    memcpy(b, d, n);
    b[0] = 1; /* 1201 */
    s = validate(b, n, 1, &is);
    assert_true(has(&is, 1201) && s.errors == 1);
    memcpy(b, d, n);
    b[4] = 2; /* 1202 */
    s = validate(b, n, 1, &is);
    assert_true(has(&is, 1202) && s.errors == 1);
    memcpy(b, d, n);
    s = validate(b, n - 1, 1, &is); /* 1203: one code short */
    assert_true(has(&is, 1203));
    memcpy(b, d, n);
    memset(b + 8, 0, 8); /* 1203: texel_count 0 */
    s = validate(b, n, 1, &is);
    assert_true(has(&is, 1203));
    s = validate(d, n, 0, &is); /* 1204: no LMAP */
    assert_true(has(&is, 1204) && s.errors == 1);
    /* 1205: a consistent section of the wrong length for the page */
    uint8_t more[N + 4] = {0};
    void *e;
    size_t en;
    assert_int_equal(lbk_terr_build(0, more, N + 4, NULL, &e, &en), LBK_OK);
    s = validate(e, en, 1, &is);
    assert_true(has(&is, 1205) && s.errors == 1);
    assert_int_equal(lbk_terr_open(e, en, &(lbk_terr_view){0}), LBK_OK); /* the section alone is fine */
    lbk_free(NULL, e);
    /* the view refuses what the validator reports */
    lbk_terr_view v;
    assert_int_equal(lbk_terr_open(d, 10, &v), LBK_ERR_TRUNCATED);
    assert_int_equal(lbk_terr_open(d, n - 1, &v), LBK_ERR_TRUNCATED);
    memcpy(b, d, n);
    b[0] = 1;
    assert_int_equal(lbk_terr_open(b, n, &v), LBK_ERR_UNSUPPORTED_FEATURE);
    free(b);
    lbk_free(NULL, d);
}

/* What a 1.3 reader sees: TERR is a type it does not know. Simulated by the rules of §15.3 on the
 * table: optional (no REQUIRED flag), sorted by code after the ranked types, so it is skipped;
 * liblbk itself knows it (no warning 213). A REQUIRED TERR would make an older reader reject the
 * file, which is why writers never set it. */
static void older_reader_skips(void **state)
{
    (void)state;
    uint8_t codes[N];
    codes_fixture(codes);
    void *d;
    size_t n;
    assert_int_equal(lbk_terr_build(0, codes, N, NULL, &d, &n), LBK_OK);
    void *f;
    size_t fn;
    container(d, n, 1, &f, &fn);
    const uint8_t *t = (const uint8_t *)f + 64 + 48 * 2; /* the third entry */
    assert_memory_equal(t, "TERR", 4);
    assert_int_equal(t[4], 0); /* flags: not REQUIRED */
    assert_true(LBK_SECTION_TERR < LBK_FOURCC('L', 'M', 'U', 'V')); /* sorts before LMUV by code */
    lbk_free(NULL, f), lbk_free(NULL, d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(code_scale),
        cmocka_unit_test(round_trip_and_version),
        cmocka_unit_test(validation_ids),
        cmocka_unit_test(older_reader_skips),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
