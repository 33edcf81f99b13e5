/* lbk convert: profiles as data, repacking rules visible in the output, determinism. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "tools/convert/convert.h"
#include "tools/common/file_util.h"
#include "tools/convert/profile.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/lightmap.h"
#include "lbk/validate.h"
#include "support/tools_fixtures.h"

/* ---- profile parsing ---------------------------------------------------------------------- */

static int parse(const char *text, tl_profile *p, char err[TL_ERR_LEN])
{
    return tl_profile_parse(text, strlen(text), "t.profile", p, err);
}

static void test_profile_parse_full(void **state)
{
    (void)state;
    tl_profile p;
    char err[TL_ERR_LEN] = "";
    const char *text = "# comment\n"
                       "name = my-hand_held.1\n"
                       "description = small  # trailing comment\n"
                       "alignment = 256\n"
                       "\n"
                       "[sections]\n"
                       "default = zstd:12\n"
                       "META = drop\n"
                       "GLG = none\n"
                       "LMAP = zstd\n"
                       "[lmap]\n"
                       "row_pitch_alignment = 64\r\n";
    assert_int_equal(parse(text, &p, err), 0);
    assert_string_equal(p.name, "my-hand_held.1");
    assert_string_equal(p.description, "small");
    assert_int_equal(p.alignment, 256);
    assert_int_equal(p.defaults.compression, LBK_COMPRESSION_ZSTD);
    assert_int_equal(p.defaults.zstd_level, 12);
    assert_int_equal(p.lmap_row_pitch_alignment, 64);
    assert_int_equal(p.lmap_page_alignment, 0);
    tl_section_rule r = tl_profile_rule(&p, LBK_SECTION_META);
    assert_int_equal(r.ship, TL_SHIP_DROP);
    r = tl_profile_rule(&p, LBK_SECTION_GLG); /* "GLG" means "GLG " */
    assert_int_equal(r.ship, TL_SHIP_KEEP);
    assert_int_equal(r.compression, LBK_COMPRESSION_NONE);
    r = tl_profile_rule(&p, LBK_SECTION_LMAP);
    assert_int_equal(r.compression, LBK_COMPRESSION_ZSTD);
    assert_int_equal(r.zstd_level, 19);
    r = tl_profile_rule(&p, LBK_SECTION_OBJS); /* default */
    assert_int_equal(r.type, LBK_SECTION_OBJS);
    assert_int_equal(r.zstd_level, 12);
}

static void expect_error(const char *text, const char *needle)
{
    tl_profile p;
    char err[TL_ERR_LEN] = "";
    assert_int_equal(parse(text, &p, err), -1);
    if (!strstr(err, needle)) fail_msg("error '%s' does not contain '%s'", err, needle);
}

static void test_profile_errors_name_the_line(void **state)
{
    (void)state;
    const char *head = "name = x\nalignment = 64\n[sections]\ndefault = none\n";
    char buf[512];
    expect_error("alignment = 64\n[sections]\ndefault = none\n", "missing 'name'");
    expect_error("name = x\n[sections]\ndefault = none\n", "missing 'alignment'");
    expect_error("name = x\nalignment = 64\n", "missing 'default'");
    expect_error("name = x\nalignment = 48\n[sections]\ndefault = none\n", "t.profile:2: alignment '48'");
    expect_error("name = x\nalignment = 8\n[sections]\ndefault = none\n", "power of two in [16, 65536]");
    expect_error("name = x\nalignment = 131072\n[sections]\ndefault = none\n", "t.profile:2:");
    expect_error("name = x\nalign = 64\n", "t.profile:2: unknown key 'align'");
    expect_error("name = x y\n", "t.profile:1: name may contain only");
    expect_error("name = x\nname = y\n", "t.profile:2: duplicate key 'name'");
    expect_error("name = x\n[bogus]\n", "t.profile:2: unknown group [bogus]");
    snprintf(buf, sizeof buf, "%sLMAP = zstd:23\n", head);
    expect_error(buf, "t.profile:5: 'zstd:23' is not drop, none, zstd or zstd:LEVEL");
    snprintf(buf, sizeof buf, "%sLMAP = gzip\n", head);
    expect_error(buf, "t.profile:5:");
    snprintf(buf, sizeof buf, "%sLMAP = none\nLMAP = drop\n", head);
    expect_error(buf, "t.profile:6: duplicate rule for section LMAP");
    snprintf(buf, sizeof buf, "%sTOOLONG = none\n", head);
    expect_error(buf, "t.profile:5: 'TOOLONG' is not a section type");
    snprintf(buf, sizeof buf, "%s[lmap]\nrow_pitch_alignment = 100\n", head);
    expect_error(buf, "t.profile:6: row_pitch_alignment '100' must be 0 or a power of two");
    snprintf(buf, sizeof buf, "%s[lmap]\nmax_page = 32\n", head);
    expect_error(buf, "t.profile:6: max_page '32' must be 0 or in [64, 16384]");
    snprintf(buf, sizeof buf, "%s[lmap]\npitch = 64\n", head);
    expect_error(buf, "t.profile:6: unknown key 'pitch' in [lmap]");
    expect_error("name = x\nno equals sign\n", "t.profile:2: expected 'key = value'");
}

/* Every shipped profile parses and states the rules its README table promises. */
static void test_shipped_profiles(void **state)
{
    (void)state;
    char err[TL_ERR_LEN] = "";
    tl_profile p;
    assert_int_equal(tl_profile_resolve("console-current", "tools/convert/profiles", &p, err), 0);
    assert_int_equal(p.alignment, 65536);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_META).ship, TL_SHIP_DROP);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_REPT).ship, TL_SHIP_DROP);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_LMAP).compression, LBK_COMPRESSION_NONE);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_OBJS).compression, LBK_COMPRESSION_ZSTD);
    assert_int_equal(p.lmap_row_pitch_alignment, 0);
    assert_int_equal(p.lmap_format[0], LBK_LMAP_BC6H);
    assert_int_equal(p.lmap_format[1], LBK_LMAP_BC5_BC4);

    assert_int_equal(tl_profile_resolve("handheld", "tools/convert/profiles", &p, err), 0);
    assert_int_equal(p.alignment, 4096);
    assert_int_equal(p.lmap_row_pitch_alignment, 0);
    assert_int_equal(p.lmap_format[0], LBK_LMAP_ASTC4X4_HDR);
    assert_int_equal(p.lmap_format[1], LBK_LMAP_ASTC4X4_LDR);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_LMAP).compression, LBK_COMPRESSION_ZSTD);

    assert_int_equal(tl_profile_resolve("console-previous", "tools/convert/profiles", &p, err), 0);
    assert_int_equal(p.alignment, 2048);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_LMAP).compression, LBK_COMPRESSION_ZSTD);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_META).ship, TL_SHIP_DROP);

    assert_int_equal(tl_profile_resolve("pc", "tools/convert/profiles", &p, err), 0);
    assert_int_equal(p.alignment, 4096);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_GLG).compression, LBK_COMPRESSION_ZSTD);

    assert_int_equal(tl_profile_resolve("archive", "tools/convert/profiles", &p, err), 0);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_META).ship, TL_SHIP_KEEP);
    assert_int_equal(tl_profile_rule(&p, LBK_SECTION_META).zstd_level, 22);

    assert_int_equal(tl_profile_resolve("no-such-profile", "tools/convert/profiles", &p, err), -1);
    assert_non_null(strstr(err, "unknown profile 'no-such-profile'"));
    assert_non_null(strstr(err, "console-current")); /* the error lists what exists */
    assert_int_equal(tl_profile_resolve("./missing.profile", NULL, &p, err), -1);
    assert_non_null(strstr(err, "cannot open profile ./missing.profile"));
}

/* ---- repacking ------------------------------------------------------------------------------ */

static const uint8_t *section_bytes(const void *file, size_t size, uint32_t type, lbk_section_info *info)
{
    lbk_reader *rd = NULL;
    assert_int_equal(lbk_reader_open_memory(file, size, NULL, &rd), LBK_OK);
    uint32_t idx;
    if (lbk_reader_section_find(rd, type, &idx) != LBK_OK) {
        lbk_reader_close(rd);
        return NULL;
    }
    assert_int_equal(lbk_reader_section_get(rd, idx, info), LBK_OK);
    lbk_reader_close(rd);
    return (const uint8_t *)file + info->offset;
}

static tl_profile profile_from(const char *text)
{
    tl_profile p;
    char err[TL_ERR_LEN] = "";
    if (tl_profile_parse(text, strlen(text), "test", &p, err)) fail_msg("%s", err);
    return p;
}

static void convert_ok(const void *in, size_t in_size, const tl_profile *p, void **out, size_t *out_size)
{
    char err[TL_ERR_LEN] = "";
    tl_convert_options o = {.profile = p};
    tl_convert_status st = tl_convert_memory(in, in_size, &o, out, out_size, NULL, err);
    if (st != TL_CONVERT_OK) fail_msg("convert failed (%d): %s", (int)st, err);
}

/* The profile's alignment, compression and drop rules are visible in the output's table. */
static void test_profile_rules_visible(void **state)
{
    (void)state;
    tf_blob in = tf_build_scene(TF_SCENE_FULL, NULL);
    tl_profile p = profile_from("name = t\nalignment = 1024\n[sections]\ndefault = zstd:3\nMETA = drop\nREPT = drop\n"
                                "LMAP = none\nGLG = none\n");
    void *out;
    size_t out_size;
    convert_ok(in.data, in.size, &p, &out, &out_size);
    lbk_reader *rd = NULL;
    assert_int_equal(lbk_reader_open_memory(out, out_size, NULL, &rd), LBK_OK);
    assert_int_equal(lbk_reader_header(rd)->section_alignment, 1024);
    uint32_t idx;
    assert_int_equal(lbk_reader_section_find(rd, LBK_SECTION_META, &idx), LBK_ERR_NOT_FOUND);
    assert_int_equal(lbk_reader_section_find(rd, LBK_SECTION_REPT, &idx), LBK_ERR_NOT_FOUND);
    for (uint32_t i = 0; i < lbk_reader_section_count(rd); i++) {
        lbk_section_info si;
        assert_int_equal(lbk_reader_section_get(rd, i, &si), LBK_OK);
        assert_int_equal(si.offset % 1024, 0);
        uint32_t want = (si.type == LBK_SECTION_LMAP || si.type == LBK_SECTION_GLG) ? LBK_COMPRESSION_NONE
                                                                                     : LBK_COMPRESSION_ZSTD;
        assert_int_equal(si.compression, want);
    }
    lbk_reader_close(rd);
    lbk_validate_summary sum;
    assert_int_equal(lbk_validate_memory(out, out_size, NULL, NULL, NULL, &sum), LBK_OK);
    assert_int_equal(sum.fatal + sum.errors, 0);
    free(out);
    tf_blob_free(&in);
}

/* Same input + profile → same bytes; and a pack converted again with its profile is unchanged. */
static void test_convert_deterministic_and_idempotent(void **state)
{
    (void)state;
    tf_blob in = tf_build_scene(TF_SCENE_FULL, NULL);
    const char *names[] = {"console-current", "console-previous", "pc", "archive"};
    for (size_t k = 0; k < 4; k++) {
        char err[TL_ERR_LEN];
        tl_profile p;
        assert_int_equal(tl_profile_resolve(names[k], "tools/convert/profiles", &p, err), 0);
        void *a, *b, *c;
        size_t as, bs, cs;
        convert_ok(in.data, in.size, &p, &a, &as);
        convert_ok(in.data, in.size, &p, &b, &bs);
        assert_int_equal(as, bs);
        assert_memory_equal(a, b, as);
        convert_ok(a, as, &p, &c, &cs);
        assert_int_equal(as, cs);
        assert_memory_equal(a, c, as);
        free(a), free(b), free(c);
    }
    tf_blob_free(&in);
}

/* Every section that ships decodes to the same bytes as the input's, apart from LMAP and DLS whose
 * layout the row pitch may change (test_row_pitch_widening checks those decode the same). */
static void test_round_trip_same_content(void **state)
{
    (void)state;
    tf_blob in = tf_build_scene(TF_SCENE_FULL, NULL);
    char err[TL_ERR_LEN];
    tl_profile p;
    assert_int_equal(tl_profile_resolve("console-current", "tools/convert/profiles", &p, err), 0);
    void *out;
    size_t out_size;
    convert_ok(in.data, in.size, &p, &out, &out_size);
    lbk_reader *ri = NULL, *ro = NULL;
    assert_int_equal(lbk_reader_open_memory(in.data, in.size, NULL, &ri), LBK_OK);
    assert_int_equal(lbk_reader_open_memory(out, out_size, NULL, &ro), LBK_OK);
    uint32_t shipped = 0;
    for (uint32_t i = 0; i < lbk_reader_section_count(ri); i++) {
        lbk_section_info si;
        assert_int_equal(lbk_reader_section_get(ri, i, &si), LBK_OK);
        uint32_t j;
        if (si.type == LBK_SECTION_META || si.type == LBK_SECTION_REPT) {
            assert_int_equal(lbk_reader_section_find(ro, si.type, &j), LBK_ERR_NOT_FOUND);
            continue;
        }
        assert_int_equal(lbk_reader_section_find(ro, si.type, &j), LBK_OK);
        shipped++;
        if (si.type == LBK_SECTION_LMAP || si.type == LBK_SECTION_DLS) continue;
        const void *a, *b;
        size_t an, bn;
        assert_int_equal(lbk_reader_section_data(ri, i, &a, &an), LBK_OK);
        assert_int_equal(lbk_reader_section_data(ro, j, &b, &bn), LBK_OK);
        assert_int_equal(an, bn);
        assert_memory_equal(a, b, an);
    }
    assert_true(shipped >= 2);
    lbk_reader_close(ri);
    lbk_reader_close(ro);
    free(out);
    tf_blob_free(&in);
}

/* A user profile file through the same resolver the CLI uses. */
static void test_user_profile_file(void **state)
{
    (void)state;
    char path[] = "/tmp/lbk-test-profile-XXXXXX.profile";
    int fd = mkstemps(path, 8);
    assert_true(fd >= 0);
    const char *text = "name = user\nalignment = 32\n[sections]\ndefault = none\nREPT = drop\n";
    assert_int_equal(write(fd, text, strlen(text)), (ssize_t)strlen(text));
    close(fd);
    tl_profile p;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_profile_resolve(path, NULL, &p, err), 0);
    assert_string_equal(p.name, "user");
    tf_blob in = tf_build_scene(TF_SCENE_FULL, NULL);
    void *out;
    size_t out_size;
    convert_ok(in.data, in.size, &p, &out, &out_size);
    lbk_section_info si;
    assert_null(section_bytes(out, out_size, LBK_SECTION_REPT, &si));
    assert_non_null(section_bytes(out, out_size, LBK_SECTION_META, &si));
    assert_int_equal(si.compression, LBK_COMPRESSION_NONE);
    assert_int_equal(si.offset % 32, 0);
    free(out);
    tf_blob_free(&in);
    unlink(path);
}

/* Invalid input is refused with the validator's first error; so is a profile whose drops make
 * the pack invalid. */
static void test_bad_input_and_invalid_pack(void **state)
{
    (void)state;
    tf_blob in = tf_build_scene(TF_SCENE_FULL, NULL);
    tl_profile p = profile_from("name = t\nalignment = 64\n[sections]\ndefault = none\n");
    char err[TL_ERR_LEN] = "";
    void *out = NULL;
    size_t out_size = 0;
    tl_convert_options o = {.profile = &p};
    uint8_t *bad = malloc(in.size);
    memcpy(bad, in.data, in.size);
    bad[in.size - 1] ^= 0x10; /* inside the last section: its checksum fails */
    assert_int_equal(tl_convert_memory(bad, in.size, &o, &out, &out_size, NULL, err), TL_CONVERT_BAD_INPUT);
    assert_non_null(strstr(err, "input is invalid"));
    assert_null(out);
    free(bad);

    tl_profile drop_lmap = profile_from("name = t\nalignment = 64\n[sections]\ndefault = none\nLMAP = drop\n");
    o.profile = &drop_lmap;
    assert_int_equal(tl_convert_memory(in.data, in.size, &o, &out, &out_size, NULL, err), TL_CONVERT_INTERNAL);
    assert_non_null(strstr(err, "output is invalid"));
    assert_null(out);
    tf_blob_free(&in);
}

typedef struct dls_entries {
    uint64_t targets[1024];
    uint8_t payload[1024][8];
    uint32_t count;
} dls_entries;

static int grab(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    dls_entries *e = user;
    (void)sets;
    assert_int_equal(count, 1);
    assert_true(e->count < 1024);
    e->targets[e->count] = target;
    memcpy(e->payload[e->count], payloads, 8);
    e->count++;
    return 0;
}

static void texel_entries(const void *file, size_t size, dls_entries *out)
{
    memset(out, 0, sizeof *out);
    lbk_reader *rd = NULL;
    assert_int_equal(lbk_reader_open_memory(file, size, NULL, &rd), LBK_OK);
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_section_by_type(rd, LBK_SECTION_DLS, &d, &n), LBK_OK);
    lbk_dls_view *v = NULL;
    assert_int_equal(lbk_dls_open(d, n, NULL, &v), LBK_OK);
    for (uint32_t c = 0; c < lbk_dls_cluster_count(v); c++) {
        lbk_dls_cluster_info ci;
        assert_int_equal(lbk_dls_cluster_get(v, c, &ci), LBK_OK);
        if (ci.space == LBK_DLS_SPACE_TEXEL) assert_int_equal(lbk_dls_cluster_decode(v, c, grab, out), LBK_OK);
    }
    lbk_dls_close(v);
    lbk_reader_close(rd);
}

/* row_pitch_alignment 256 widens the 16-texel page to 64 texels: zero texels on the right, the
 * original texels in place, later-page texel indices and DLS targets renumbered with them. */
static void test_row_pitch_widening(void **state)
{
    (void)state;
    tf_options fo = {0};
    fo.page0_width = 40; /* page 0 40 wide → 64; page 1 16 → 64 */
    tf_blob in = tf_build_scene(TF_SCENE_FULL, &fo);
    tl_profile p = profile_from("name = t\nalignment = 64\n[sections]\ndefault = none\n[lmap]\nrow_pitch_alignment = 256\n");
    void *out;
    size_t out_size;
    convert_ok(in.data, in.size, &p, &out, &out_size);
    lbk_reader *ri = NULL, *ro = NULL;
    assert_int_equal(lbk_reader_open_memory(in.data, in.size, NULL, &ri), LBK_OK);
    assert_int_equal(lbk_reader_open_memory(out, out_size, NULL, &ro), LBK_OK);
    const void *a, *b;
    size_t an, bn;
    assert_int_equal(lbk_reader_section_by_type(ri, LBK_SECTION_LMAP, &a, &an), LBK_OK);
    assert_int_equal(lbk_reader_section_by_type(ro, LBK_SECTION_LMAP, &b, &bn), LBK_OK);
    lbk_lmap_view va, vb;
    assert_int_equal(lbk_lmap_open(a, an, &va), LBK_OK);
    assert_int_equal(lbk_lmap_open(b, bn, &vb), LBK_OK);
    assert_int_equal(vb.page_count, 2);
    assert_int_equal(vb.texel_count, 64 * 32 + 64 * 16);
    for (uint32_t pg = 0; pg < 2; pg++) {
        lbk_lmap_page pa, pb;
        assert_int_equal(lbk_lmap_page_get(&va, pg, &pa), LBK_OK);
        assert_int_equal(lbk_lmap_page_get(&vb, pg, &pb), LBK_OK);
        assert_int_equal(pb.width, 64);
        assert_int_equal((4 * pb.width) % 256, 0);
        assert_int_equal(pb.height, pa.height);
        for (uint32_t y = 0; y < pb.height; y++)
            for (uint32_t x = 0; x < pb.width; x++) {
                lbk_ahd_texel ta, tb;
                assert_int_equal(lbk_lmap_page_texel_get(&pb, x, y, &tb), LBK_OK);
                if (x < pa.width) {
                    assert_int_equal(lbk_lmap_page_texel_get(&pa, x, y, &ta), LBK_OK);
                    assert_int_equal(ta.irradiance_z, tb.irradiance_z);
                    assert_memory_equal(ta.rgba, tb.rgba, 4);
                } else {
                    assert_int_equal(tb.irradiance_z, 0);
                }
            }
    }
    static dls_entries ea, eb;
    texel_entries(in.data, in.size, &ea);
    texel_entries(out, out_size, &eb);
    assert_int_equal(ea.count, 256);
    assert_int_equal(eb.count, 256);
    for (uint32_t i = 0; i < ea.count; i++) {
        /* old index on page 1 (16 wide, first texel 40·32) → new (64 wide, first texel 64·32) */
        uint64_t local = ea.targets[i] - 40 * 32, want = 64 * 32 + (local / 16) * 64 + local % 16;
        int found = 0;
        for (uint32_t j = 0; j < eb.count; j++)
            if (eb.targets[j] == want) {
                assert_memory_equal(ea.payload[i], eb.payload[j], 8);
                found = 1;
            }
        assert_true(found);
    }
    lbk_reader_close(ri);
    lbk_reader_close(ro);
    free(out);
    tf_blob_free(&in);
}

/* page_alignment can only be checked (format 1.0 packs planes at 16 bytes): a clear error. */
static void test_page_alignment_checked(void **state)
{
    (void)state;
    tf_blob in = tf_build_scene(TF_SCENE_LMAP_ONLY, NULL);
    tl_profile p = profile_from("name = t\nalignment = 64\n[sections]\ndefault = none\n[lmap]\npage_alignment = 4096\n");
    char err[TL_ERR_LEN] = "";
    void *out = NULL;
    size_t out_size;
    tl_convert_options o = {.profile = &p};
    assert_int_equal(tl_convert_memory(in.data, in.size, &o, &out, &out_size, NULL, err), TL_CONVERT_UNSUPPORTED);
    assert_non_null(strstr(err, "not multiples of page_alignment 4096"));
    tf_blob_free(&in);
}

/* A profile's max_page refuses a bake with a larger page (convert cannot move objects between
 * pages) and names the bake option that fixes it; the profile's padding counts. */
static void test_max_page_refused(void **state)
{
    (void)state;
    tf_options fo = {0};
    fo.page0_width = 100; /* page 0 is 100 × 32, page 1 16 × 16 */
    tf_blob in = tf_build_scene(TF_SCENE_FULL, &fo);
    char err[TL_ERR_LEN] = "";
    void *out = NULL;
    size_t out_size = 0;
    tl_profile p = profile_from("name = t\nalignment = 64\n[sections]\ndefault = none\n[lmap]\nmax_page = 64\n");
    assert_int_equal(p.lmap_max_page, 64);
    tl_convert_options o = {.profile = &p};
    assert_int_equal(tl_convert_memory(in.data, in.size, &o, &out, &out_size, NULL, err), TL_CONVERT_UNSUPPORTED);
    assert_non_null(strstr(err, "page 0 is 100x32 texels, more than the profile's max_page 64: bake with `lbk bake --max-page 64`"));
    assert_null(out);
    /* 100 fits 128; padded to a 1024-byte pitch (256 texels) it no longer does */
    p = profile_from("name = t\nalignment = 64\n[sections]\ndefault = none\n[lmap]\nmax_page = 128\n");
    convert_ok(in.data, in.size, &p, &out, &out_size);
    free(out);
    out = NULL;
    p = profile_from("name = t\nalignment = 64\n[sections]\ndefault = none\n[lmap]\nmax_page = 128\nrow_pitch_alignment = 1024\n");
    assert_int_equal(tl_convert_memory(in.data, in.size, &o, &out, &out_size, NULL, err), TL_CONVERT_UNSUPPORTED);
    assert_non_null(strstr(err, "page 0 is 256x32 texels after the profile's padding"));
    tf_blob_free(&in);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profile_parse_full),
        cmocka_unit_test(test_profile_errors_name_the_line),
        cmocka_unit_test(test_shipped_profiles),
        cmocka_unit_test(test_profile_rules_visible),
        cmocka_unit_test(test_convert_deterministic_and_idempotent),
        cmocka_unit_test(test_round_trip_same_content),
        cmocka_unit_test(test_user_profile_file),
        cmocka_unit_test(test_bad_input_and_invalid_pack),
        cmocka_unit_test(test_row_pitch_widening),
        cmocka_unit_test(test_page_alignment_checked),
        cmocka_unit_test(test_max_page_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
