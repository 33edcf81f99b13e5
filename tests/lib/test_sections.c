/* LMAP, GLG, LLG, OCTP sections: builder → view round trips, a clean container through
 * lbk_validate_memory, and every validator rule caught on a deliberately broken copy. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/bc.h"
#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/octa.h"
#include "lbk/pixel.h"
#include "libformat/src/internal.h"

/* ---- issue collection -------------------------------------------------------------------- */
typedef struct issues {
    uint32_t id[256];
    lbk_severity sev[256];
    int n;
} issues;

static int collect(void *user, const lbk_issue *issue)
{
    issues *is = user;
    if (is->n < 256) {
        is->id[is->n] = issue->id;
        is->sev[is->n] = issue->severity;
        is->n++;
    }
    return 0;
}

static bool has(const issues *is, uint32_t id)
{
    for (int i = 0; i < is->n; i++)
        if (is->id[i] == id) return true;
    return false;
}

typedef void (*validator)(lbk_vctx *, const uint8_t *, size_t);

/* Runs one section validator on a copy (so ASan sees reads past the end). */
static uint32_t run_features; /* the header's required features the validator sees */

static void run(validator fn, const uint8_t *bytes, size_t size, issues *is, lbk_vctx *facts)
{
    memset(is, 0, sizeof *is);
    lbk_validate_summary sum;
    memset(&sum, 0, sizeof sum);
    lbk_allocator alloc = {0};
    lbk_vctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.callback = collect;
    ctx.user = is;
    ctx.summary = &sum;
    ctx.allocator = &alloc;
    ctx.section_type = LBK_SECTION_LMAP;
    ctx.required_features = run_features;
    uint8_t *copy = malloc(size ? size : 1);
    memcpy(copy, bytes, size);
    fn(&ctx, copy, size);
    free(copy);
    if (facts) *facts = ctx;
    else {
        lbk_dealloc(&alloc, (void *)ctx.lmap_page_width);
        lbk_dealloc(&alloc, (void *)ctx.lmap_page_height);
    }
}

/* Expects exactly the issue `id` (possibly repeated) from a corrupted copy. */
static void expect_only(validator fn, const uint8_t *bytes, size_t size, uint32_t id)
{
    issues is;
    run(fn, bytes, size, &is, NULL);
    if (is.n == 0) fail_msg("expected issue %u, got none", id);
    for (int i = 0; i < is.n; i++)
        if (is.id[i] != id) fail_msg("expected only issue %u, got %u", id, is.id[i]);
}

static void expect_has(validator fn, const uint8_t *bytes, size_t size, uint32_t id)
{
    issues is;
    run(fn, bytes, size, &is, NULL);
    if (!has(&is, id)) fail_msg("expected issue %u among %d issues", id, is.n);
}

static uint8_t *dup_bytes(const void *b, size_t n)
{
    uint8_t *d = malloc(n);
    memcpy(d, b, n);
    return d;
}

/* ---- fixtures --------------------------------------------------------------------------- */
static void lmap_fixture(void **out, size_t *size, lbk_ahd_texel *t0, lbk_ahd_texel *t1)
{
    uint32_t s = 7u;
    for (int i = 0; i < 6; i++) {
        lbk_ahd_linear lin;
        memset(&lin, 0, sizeof lin);
        const float amb[3] = {0.1f * (float)i, 0.2f, 0.3f}, dir[3] = {0.0f, 0.6f, 0.8f}, col[3] = {1.0f, 0.5f, 0.25f};
        lbk_ahd_linear_add_ambient(&lin, amb);
        lbk_ahd_linear_add_light(&lin, dir, col);
        lbk_ahd_from_linear(&lin, &t0[i]);
    }
    for (int i = 0; i < 20; i++) {
        s = s * 1664525u + 1013904223u;
        t1[i].irradiance_z = s & 0x7bdef7bfu; /* every exponent ≤ 30 */
        t1[i].rgba[0] = (uint8_t)i;
        t1[i].rgba[1] = 200;
        t1[i].rgba[2] = (uint8_t)(40 + i);
        t1[i].rgba[3] = 128;
    }
    const lbk_lmap_page_desc pages[2] = {{3, 2, t0}, {5, 4, t1}};
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages,
        .page_count = 2}, NULL, out, size), LBK_OK);
}

static void lmap_round_trip_and_rules(void **state)
{
    (void)state;
    lbk_ahd_texel t0[6], t1[20];
    void *b;
    size_t n;
    lmap_fixture(&b, &n, t0, t1);
    /* header 16 + 2×32 = 80; page 0 planes at 80 and 112 (24 B each → 104 → 112), ends 136;
     * page 1 at 144 and 224 (80 B each), ends 304 */
    assert_int_equal(n, 304);
    lbk_lmap_view v;
    assert_int_equal(lbk_lmap_open(b, n, &v), LBK_OK);
    assert_int_equal(v.page_count, 2);
    assert_int_equal(v.texel_count, 26);
    lbk_lmap_page pg;
    assert_int_equal(lbk_lmap_page_get(&v, 1, &pg), LBK_OK);
    assert_int_equal(pg.width, 5);
    assert_int_equal(pg.first_texel, 6);
    assert_int_equal(pg.irradiance_offset, 144);
    assert_int_equal(pg.rgba_offset, 224);
    for (uint64_t i = 0; i < 26; i++) {
        lbk_ahd_texel t;
        uint32_t page;
        assert_int_equal(lbk_lmap_texel_get(&v, i, &t, &page), LBK_OK);
        const lbk_ahd_texel *e = i < 6 ? &t0[i] : &t1[i - 6];
        assert_int_equal(page, i < 6 ? 0 : 1);
        assert_int_equal(t.irradiance_z, e->irradiance_z);
        assert_memory_equal(t.rgba, e->rgba, 4);
    }
    lbk_ahd_texel t;
    assert_int_equal(lbk_lmap_texel_get(&v, 26, &t, NULL), LBK_ERR_NOT_FOUND);
    assert_int_equal(lbk_lmap_page_texel_get(&pg, 5, 0, &t), LBK_ERR_NOT_FOUND);
    /* validator: clean, and the facts */
    issues is;
    lbk_vctx facts;
    run(lbk_validate_lmap, b, n, &is, &facts);
    assert_int_equal(is.n, 0);
    assert_true(facts.lmap_ok);
    assert_int_equal(facts.lmap_page_count, 2);
    assert_int_equal(facts.lmap_texel_count, 26);
    assert_int_equal(facts.lmap_page_width[1], 5);
    assert_int_equal(facts.lmap_page_height[1], 4);
    lbk_dealloc(NULL, (void *)facts.lmap_page_width);
    lbk_dealloc(NULL, (void *)facts.lmap_page_height);
    /* every rule */
    uint8_t *c;
    expect_only(lbk_validate_lmap, b, 10, 500);
    c = dup_bytes(b, n); c[5] = 1; expect_only(lbk_validate_lmap, c, n, 511); free(c); /* scale 1 + 2^-15 */
    c = dup_bytes(b, n); c[16 + 32 + 6] = 1; expect_only(lbk_validate_lmap, c, n, 501); free(c); /* encoding bit 16 */
    c = dup_bytes(b, n); lbk_wr32(c, 0); expect_only(lbk_validate_lmap, c, n, 502); free(c);
    c = dup_bytes(b, n); lbk_wr32(c, 100); expect_only(lbk_validate_lmap, c, n, 502); free(c);
    c = dup_bytes(b, n); lbk_wr16(c + 16, 0); expect_only(lbk_validate_lmap, c, n, 503); free(c);
    c = dup_bytes(b, n); lbk_wr16(c + 16 + 2, 16385); expect_only(lbk_validate_lmap, c, n, 503); free(c);
    c = dup_bytes(b, n); lbk_wr64(c + 8, 27); expect_only(lbk_validate_lmap, c, n, 504); free(c);
    c = dup_bytes(b, n); lbk_wr64(c + 16 + 32 + 8, 5); expect_only(lbk_validate_lmap, c, n, 505); free(c);
    c = dup_bytes(b, n); lbk_wr64(c + 16 + 16, 96); expect_only(lbk_validate_lmap, c, n, 506); free(c);
    expect_only(lbk_validate_lmap, b, n - 4, 507);
    c = dup_bytes(b, n); c[105] = 1; expect_only(lbk_validate_lmap, c, n, 508); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 144 + 8, 0x7c0u << 11); expect_only(lbk_validate_lmap, c, n, 509); free(c);
    c = dup_bytes(b, n); memcpy(c + 224 + 4, (const uint8_t[4]){0, 128, 128, 0}, 4); expect_only(lbk_validate_lmap, c, n, 510); free(c);
    /* a damaged page: Inf/NaN in every texel is reported 8 times plus one summary */
    c = dup_bytes(b, n);
    for (int i = 0; i < 20; i++) lbk_wr32(c + 144 + 4 * i, 0x7ffu);
    run(lbk_validate_lmap, c, n, &is, NULL);
    assert_int_equal(is.n, 9);
    free(c);
    lbk_free(NULL, b);
}

/* Counts issue `id` of a validation: listed ones plus the "... and N more" summary. */
typedef struct id_count {
    uint32_t id;
    unsigned long long n;
} id_count;

/* Format 1.2 block pages (spec §9.2): an 8×4 BC6H + BC5/BC4 page next to a 1.0 page, built,
 * opened, decoded by the planes API, and every new rule (512–515). */
static void lmap_block_pages(void **state)
{
    (void)state;
    /* plane 0: two BC6H mode-11 blocks; plane 1: BC5 (2 × 16 B), then BC4 at 16·2 (2 × 8 B) */
    uint8_t p0[32], p1[48];
    for (int b = 0; b < 2; b++) {
        const int ep[4][3] = {{100 + 50 * b, 200, 300}, {600, 500 - 100 * b, 400}, {0, 0, 0}, {0, 0, 0}};
        uint8_t idx[16];
        for (int t = 0; t < 16; t++) idx[t] = (uint8_t)(t == 0 ? 3 : (t * 5 + b) % 16);
        assert_int_equal(lbk_bc6h_pack(11, 0, ep, idx, p0 + 16 * b), LBK_OK);
    }
    for (int i = 0; i < 48; i++) p1[i] = (uint8_t)(i * 37 + 11);
    assert_int_equal(lbk_lmap_plane_size(0, LBK_LMAP_BC6H, 8, 4), 32);
    assert_int_equal(lbk_lmap_plane_size(1, LBK_LMAP_BC5_BC4, 8, 4), 48);
    assert_int_equal(lbk_lmap_plane_size(1, LBK_LMAP_BC5_BC4, 4, 4), 24); /* BC4 at 16 */
    assert_int_equal(lbk_lmap_plane_size(0, LBK_LMAP_BC6H, 6, 4), 0);
    assert_int_equal(lbk_lmap_plane_size(0, 7, 8, 4), 0);
    uint8_t r0[24], r1[24]; /* a 3×2 page as 1.0 planes */
    for (int i = 0; i < 6; i++) {
        lbk_wr32(r0 + 4 * i, lbk_r11g11b10f_pack((const float[3]){0.25f * (float)(i + 1), 0.5f, 1.0f}));
        memcpy(r1 + 4 * i, (const uint8_t[4]){128, 128, 128, 255}, 4);
    }
    const lbk_lmap_encoded_page enc[2] = {{8, 4, {LBK_LMAP_BC6H, LBK_LMAP_BC5_BC4}, {p0, p1}},
                                          {3, 2, {LBK_LMAP_R11G11B10F, LBK_LMAP_RGBA8}, {r0, r1}}};
    void *b;
    size_t n;
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.size = sizeof(lbk_lmap_build_desc), .page_count = 2,
                                                          .encoded = enc}, NULL, &b, &n), LBK_OK);
    /* header 80; page 0 plane 0 at 80 (32 B), plane 1 at 112 (48 B) → 160; page 1 at 160 and 192 */
    assert_int_equal(n, 216);
    assert_int_equal(lbk_lmap_required_features(b, n), LBK_FEATURE_LMAP_BLOCK);
    lbk_lmap_view v;
    assert_int_equal(lbk_lmap_open(b, n, &v), LBK_OK);
    assert_int_equal(v.texel_count, 38);
    lbk_lmap_page pg;
    assert_int_equal(lbk_lmap_page_get(&v, 0, &pg), LBK_ERR_UNSUPPORTED_FEATURE);
    assert_int_equal(lbk_lmap_page_get(&v, 1, &pg), LBK_OK);
    lbk_lmap_planes pl;
    assert_int_equal(lbk_lmap_planes_get(&v, 0, &pl), LBK_OK);
    assert_int_equal(pl.format[0], LBK_LMAP_BC6H);
    assert_int_equal(pl.format[1], LBK_LMAP_BC5_BC4);
    assert_int_equal(pl.blocks_x, 2);
    assert_int_equal(pl.blocks_y, 1);
    assert_int_equal(pl.offset[0], 80);
    assert_int_equal(pl.offset[1], 112);
    assert_int_equal(pl.bytes[1], 48);
    for (uint32_t y = 0; y < 4; y++)
        for (uint32_t x = 0; x < 8; x++) {
            lbk_ahd_texel_f t;
            assert_int_equal(lbk_lmap_planes_texel_unpack(&pl, x, y, &t), LBK_OK);
            uint16_t h[16][3];
            float dir[16][2], ratio[16];
            const int blk = (int)(x / 4), k = (int)(y * 4 + x % 4);
            lbk_bc6h_unpack(p0 + 16 * blk, h);
            lbk_bc5_unpack(p1 + 16 * blk, dir);
            lbk_bc4_unpack(p1 + 32 + 8 * blk, ratio);
            for (int c = 0; c < 3; c++) assert_true(t.ez[c] == lbk_half_to_float(h[k][c]));
            assert_true(t.rgba[0] == ratio[k] && t.rgba[1] == dir[k][0] && t.rgba[2] == dir[k][1]);
            const float dx = 2 * dir[k][0] - 1, dy = 2 * dir[k][1] - 1, zz = 1 - dx * dx - dy * dy;
            assert_true(t.rgba[3] == (zz > 0 ? sqrtf(zz) : 0.0f));
            float rgb[3];
            assert_int_equal(lbk_lmap_planes_irradiance(&pl, x, y, (const float[3]){0, 0, 1}, rgb), LBK_OK);
        }
    lbk_ahd_texel_f tf;
    assert_int_equal(lbk_lmap_planes_texel_unpack(&pl, 8, 0, &tf), LBK_ERR_NOT_FOUND);
    /* GPU bytes: whole blocks (16 + 16 + 8 per block touched), 8 per texel on a 1.0 page */
    assert_int_equal(lbk_lmap_planes_rect_bytes(&pl, 1, 1, 1, 1), 40);
    assert_int_equal(lbk_lmap_planes_rect_bytes(&pl, 3, 0, 2, 4), 80);
    assert_int_equal(lbk_lmap_planes_rect_bytes(&pl, 0, 0, 8, 4), 80);
    assert_int_equal(lbk_lmap_planes_rect_bytes(&pl, 7, 0, 2, 1), 0);
    lbk_lmap_planes pl1;
    assert_int_equal(lbk_lmap_planes_get(&v, 1, &pl1), LBK_OK);
    assert_int_equal(pl1.blocks_x, 0);
    assert_int_equal(lbk_lmap_planes_rect_bytes(&pl1, 0, 0, 2, 2), 32);
    for (uint32_t i = 0; i < 6; i++) { /* 1.0 planes decode bit for bit as the 1.0 API */
        float a[3], c[3];
        const float nn[3] = {0.0f, 0.6f, 0.8f};
        assert_int_equal(lbk_lmap_planes_irradiance(&pl1, i % 3, i / 3, nn, a), LBK_OK);
        assert_int_equal(lbk_lmap_page_irradiance(&pg, i % 3, i / 3, nn, c), LBK_OK);
        assert_memory_equal(a, c, sizeof a);
    }
    /* validator: clean with the feature bit, 515 without; 514, 512, 513 */
    issues is;
    run_features = LBK_FEATURE_LMAP_BLOCK;
    run(lbk_validate_lmap, b, n, &is, NULL);
    assert_int_equal(is.n, 0);
    uint8_t *c;
    c = dup_bytes(b, n); c[80] = 0x13; expect_only(lbk_validate_lmap, c, n, 514); free(c); /* reserved mode 10011 */
    c = dup_bytes(b, n); lbk_wr32(c + 16 + 4, 0x0303); expect_only(lbk_validate_lmap, c, n, 512); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 16 + 4, 0x0103); expect_only(lbk_validate_lmap, c, n, 512); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 16 + 4, 0x10101); expect_has(lbk_validate_lmap, c, n, 501); free(c);
    c = dup_bytes(b, n); lbk_wr16(c + 16, 6); expect_only(lbk_validate_lmap, c, n, 513); free(c);
    run_features = 0;
    expect_only(lbk_validate_lmap, b, n, 515);
    lbk_lmap_view cv;
    c = dup_bytes(b, n); lbk_wr16(c + 16, 6); assert_int_equal(lbk_lmap_open(c, n, &cv), LBK_ERR_CORRUPT); free(c);
    /* a 1.0 page with the feature bit set: 515 */
    void *b0;
    size_t n0;
    lbk_ahd_texel t0[6], t1[20];
    lmap_fixture(&b0, &n0, t0, t1);
    assert_int_equal(lbk_lmap_required_features(b0, n0), 0);
    run_features = LBK_FEATURE_LMAP_BLOCK;
    expect_only(lbk_validate_lmap, b0, n0, 515);
    run_features = 0;
    lbk_free(NULL, b0);
    /* ASTC planes: described, not decoded by liblbk */
    uint8_t a0[32] = {0}, a1[32] = {0};
    const lbk_lmap_encoded_page ea = {8, 4, {LBK_LMAP_ASTC4X4_HDR, LBK_LMAP_ASTC4X4_LDR}, {a0, a1}};
    void *ba;
    size_t na;
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.size = sizeof(lbk_lmap_build_desc), .page_count = 1,
                                                          .encoded = &ea}, NULL, &ba, &na), LBK_OK);
    assert_int_equal(lbk_lmap_open(ba, na, &v), LBK_OK);
    assert_int_equal(lbk_lmap_planes_get(&v, 0, &pl), LBK_OK);
    assert_int_equal(lbk_lmap_planes_texel_unpack(&pl, 0, 0, &tf), LBK_ERR_UNSUPPORTED_FEATURE);
    assert_int_equal(lbk_lmap_planes_rect_bytes(&pl, 0, 0, 1, 1), 32);
    lbk_free(NULL, ba);
    /* a block page whose side is not a multiple of 4 cannot be built */
    const lbk_lmap_encoded_page eb = {6, 4, {LBK_LMAP_BC6H, LBK_LMAP_RGBA8}, {p0, p1}};
    assert_int_not_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.size = sizeof(lbk_lmap_build_desc), .page_count = 1,
                                                              .encoded = &eb}, NULL, &ba, &na), LBK_OK);
    lbk_free(NULL, b);
}

static int count_id(void *user, const lbk_issue *issue)
{
    id_count *c = user;
    if (issue->id != c->id) return 0;
    unsigned long long more;
    if (sscanf(issue->message, "... and %llu more", &more) == 1) c->n += more;
    else c->n++;
    return 0;
}

/* The validator's fast texel scan (blocks of 1024 texels, integer tests) flags exactly the texels
 * the decoder's float rule calls short (510) — every (G, B) for every A that can be short
 * (A ≤ 127; A ≥ 128 gives z² > 1/4) — and every exponent-31 channel (509) anywhere in a page,
 * also in the last, partial block. */
static void lmap_fast_scan_exact(void **state)
{
    (void)state;
    lbk_ahd_texel *t = malloc(256 * 256 * sizeof *t);
    for (int a = 0; a < 128; a += 1) {
        unsigned long long want = 0;
        for (int y = 0; y < 256; y++)
            for (int x = 0; x < 256; x++) {
                t[y * 256 + x] = (lbk_ahd_texel){0, {0, (uint8_t)x, (uint8_t)y, (uint8_t)a}};
                const float dx = 2.0f * x / 255.0f - 1.0f, dy = 2.0f * y / 255.0f - 1.0f, dz = a / 255.0f;
                want += dx * dx + dy * dy + dz * dz < 0.25f;
            }
        void *b;
        size_t n;
        lbk_lmap_page_desc pd = {256, 256, t};
        assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = &pd, .page_count = 1}, NULL, &b, &n), LBK_OK);
        id_count c = {510, 0};
        lbk_validate_summary sum;
        memset(&sum, 0, sizeof sum);
        lbk_allocator alloc = {0};
        lbk_vctx ctx;
        memset(&ctx, 0, sizeof ctx);
        ctx.callback = count_id;
        ctx.user = &c;
        ctx.summary = &sum;
        ctx.allocator = &alloc;
        lbk_validate_lmap(&ctx, b, n);
        assert_int_equal(c.n, want);
        if (a == 0) assert_true(want > 10000);
        lbk_dealloc(NULL, (void *)ctx.lmap_page_width);
        lbk_dealloc(NULL, (void *)ctx.lmap_page_height);
        lbk_free(NULL, b);
    }
    /* 509: a 1000 x 3 page (two full blocks and a partial one), exponent 31 in R, G or B of texels
     * spread over all three blocks */
    for (int i = 0; i < 3000; i++) t[i] = (lbk_ahd_texel){0x3c0u | 0x3c0u << 11 | 0x1e0u << 22, {255, 128, 128, 255}};
    const uint32_t bad[5] = {0, 1023, 1024, 2047, 2999};
    for (int k = 0; k < 5; k++) t[bad[k]].irradiance_z |= k % 3 == 0 ? 0x7c0u : k % 3 == 1 ? 0x7c0u << 11 : 0x3e0u << 22;
    void *b;
    size_t n;
    lbk_lmap_page_desc pd = {1000, 3, t};
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = &pd, .page_count = 1}, NULL, &b, &n), LBK_OK);
    issues is;
    run(lbk_validate_lmap, b, n, &is, NULL);
    assert_int_equal(is.n, 5);
    for (int k = 0; k < 5; k++) assert_int_equal(is.id[k], 509);
    lbk_free(NULL, b);
    free(t);
}

/* One cube split in 6 tetras plus an unused ninth probe (optional). */
static const float cube_pos[9][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}, {5, 5, 5}};
static const uint32_t cube_tets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

static void glg_fixture(uint32_t probes, void **out, size_t *size)
{
    lbk_sh9_rgb sh[9];
    memset(sh, 0, sizeof sh);
    for (int i = 0; i < 9; i++)
        for (int c = 0; c < 3; c++) sh[i].c[c][0] = 1.0f + (float)i;
    lbk_glg_build_desc d = {.probe_count = probes, .tetra_count = 6, .positions = cube_pos, .probes = sh,
        .tetras = cube_tets};
    assert_int_equal(lbk_glg_build(&d, NULL, out, size), LBK_OK);
}

static void glg_rules(void **state)
{
    (void)state;
    void *b;
    size_t n;
    glg_fixture(8, &b, &n);
    /* 32 + 96 = 128; + 224 = 352; tetras at 352, adjacency 448, visibility 544, end 568 */
    assert_int_equal(n, 568);
    issues is;
    lbk_vctx facts;
    run(lbk_validate_glg, b, n, &is, &facts);
    assert_int_equal(is.n, 0);
    assert_true(facts.glg_ok);
    assert_int_equal(facts.glg_probe_count, 8);
    lbk_glg_view v;
    assert_int_equal(lbk_glg_open(b, n, &v), LBK_OK);
    float p[3];
    lbk_sh9_rgb sh;
    assert_int_equal(lbk_glg_probe_get(&v, 7, p, &sh), LBK_OK);
    assert_true(p[0] == 1.0f && p[1] == 1.0f && p[2] == 1.0f && sh.c[2][0] == 8.0f);
    assert_int_equal(lbk_glg_probe_get(&v, 8, p, &sh), LBK_ERR_NOT_FOUND);
    uint8_t *c;
    expect_only(lbk_validate_glg, b, 31, 600);
    c = dup_bytes(b, n); c[20] = 1; expect_only(lbk_validate_glg, c, n, 601); free(c);
    c = dup_bytes(b, n); c[9] = 1; expect_only(lbk_validate_glg, c, n, 611); free(c); /* scale 1 + 2^-15 */
    c = dup_bytes(b, n); lbk_wr32(c, 3); expect_has(lbk_validate_glg, c, n, 602); free(c);
    expect_only(lbk_validate_glg, b, n - 4, 603);
    c = dup_bytes(b, n); lbk_wrf32(c + 32 + 12 * 3 + 4, NAN); expect_only(lbk_validate_glg, c, n, 605); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 352 + 16 * 2 + 4, 8); expect_has(lbk_validate_glg, c, n, 606); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 352 + 16 * 2 + 4, lbk_rd32(c + 352 + 16 * 2)); expect_has(lbk_validate_glg, c, n, 606); free(c);
    { /* swap two vertices: negative orientation (and the adjacency no longer matches faces) */
        c = dup_bytes(b, n);
        const uint32_t a = lbk_rd32(c + 352 + 8), bb = lbk_rd32(c + 352 + 12);
        lbk_wr32(c + 352 + 8, bb);
        lbk_wr32(c + 352 + 12, a);
        expect_has(lbk_validate_glg, c, n, 607);
        free(c);
    }
    /* find an interior face and break it */
    int face = -1;
    for (int i = 0; i < 24 && face < 0; i++)
        if (lbk_rd32((uint8_t *)b + 448 + 4 * i) != LBK_TETRA_NONE) face = i;
    assert_true(face >= 0);
    c = dup_bytes(b, n); lbk_wr32(c + 448 + 4 * face, 6); expect_has(lbk_validate_glg, c, n, 608); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 448 + 4 * face, (uint32_t)(face / 4)); expect_has(lbk_validate_glg, c, n, 609); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 448 + 4 * face, LBK_TETRA_NONE); expect_only(lbk_validate_glg, c, n, 609); free(c);
    lbk_free(NULL, b);
    /* padding: 32 + 9·12 = 140 → 144 */
    glg_fixture(9, &b, &n);
    run(lbk_validate_glg, b, n, &is, NULL);
    assert_int_equal(is.n, 1);
    assert_int_equal(is.id[0], 610);
    assert_int_equal(is.sev[0], LBK_SEVERITY_WARNING);
    c = dup_bytes(b, n); c[141] = 1; expect_has(lbk_validate_glg, c, n, 604); free(c);
    lbk_free(NULL, b);
}

static void llg_fixture(void **out, size_t *size)
{
    static lbk_sh9_rgb probes[2 * 2 * 3 + 27];
    memset(probes, 0, sizeof probes);
    const lbk_llg_vertex verts[3] = {{1.0f, {0, 0, 1}}, {0.25f, {1, 0, 0}}, {0.0f, {0, -1, 0}}};
    lbk_llg_grid_desc g[2];
    memset(g, 0, sizeof g);
    for (int k = 0; k < 2; k++) {
        g[k].axes[0][0] = g[k].axes[1][1] = g[k].axes[2][2] = 1.0f;
        g[k].half_extents[0] = g[k].half_extents[1] = g[k].half_extents[2] = 1.0f + (float)k;
        g[k].dims[0] = g[k].dims[1] = k ? 3 : 2;
        g[k].dims[2] = 3;
        g[k].probes = probes + (k ? 12 : 0);
    }
    g[1].vertices = verts;
    g[1].vertex_count = 3;
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = g, .grid_count = 2}, NULL, out, size), LBK_OK);
}

static void llg_rules(void **state)
{
    (void)state;
    void *b;
    size_t n;
    llg_fixture(&b, &n);
    /* 32 + 2·96 = 224; 12 + 27 = 39 probes × 28 = 1092 → 1316 → 1328; 3 vertices → 1340 */
    assert_int_equal(n, 1340);
    issues is;
    lbk_vctx facts;
    run(lbk_validate_llg, b, n, &is, &facts);
    assert_int_equal(is.n, 0);
    assert_true(facts.llg_ok);
    assert_int_equal(facts.llg_count, 2);
    assert_int_equal(facts.llg_probe_count, 39);
    lbk_llg_view v;
    assert_int_equal(lbk_llg_open(b, n, &v), LBK_OK);
    lbk_llg_grid g;
    assert_int_equal(lbk_llg_grid_get(&v, 1, &g), LBK_OK);
    assert_int_equal(g.probe_offset, 12);
    assert_int_equal(g.vertex_offset, 0);
    assert_int_equal(g.vertex_count, 3);
    assert_true(g.half_extents[2] == 2.0f);
    const uint8_t *vx = v.vertices + 4;
    assert_int_equal(vx[0], 64); /* 0.25 · 255 = 63.75 → 64 */
    uint8_t *c;
    const size_t g1 = 32 + 96;
    expect_only(lbk_validate_llg, b, 20, 700);
    c = dup_bytes(b, n); c[5] = 1; expect_only(lbk_validate_llg, c, n, 713); free(c); /* scale 1 + 2^-15 */
    c = dup_bytes(b, n); c[24] = 1; expect_only(lbk_validate_llg, c, n, 701); free(c);
    c = dup_bytes(b, n); c[32 + 66] = 1; expect_only(lbk_validate_llg, c, n, 701); free(c);
    c = dup_bytes(b, n); lbk_wr32(c, 0); expect_only(lbk_validate_llg, c, n, 702); free(c);
    c = dup_bytes(b, n); lbk_wr32(c, 14); expect_only(lbk_validate_llg, c, n, 702); free(c); /* 32 + 14·96 > 1340 */
    expect_only(lbk_validate_llg, b, n - 1, 703);
    c = dup_bytes(b, n); c[1316 + 3] = 1; expect_only(lbk_validate_llg, c, n, 704); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + g1 + 4, INFINITY); expect_only(lbk_validate_llg, c, n, 705); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + g1 + 12 + 4, 0.1f); expect_only(lbk_validate_llg, c, n, 706); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + g1 + 48 + 8, -1.0f); expect_only(lbk_validate_llg, c, n, 707); free(c);
    c = dup_bytes(b, n); lbk_wr16(c + g1 + 60, 65); expect_has(lbk_validate_llg, c, n, 708); free(c);
    c = dup_bytes(b, n); lbk_wr64(c + g1 + 72, 11); expect_only(lbk_validate_llg, c, n, 709); free(c);
    c = dup_bytes(b, n); lbk_wr64(c + g1 + 80, 1); expect_only(lbk_validate_llg, c, n, 710); free(c);
    c = dup_bytes(b, n); lbk_wr64(c + 16, 4); expect_only(lbk_validate_llg, c, n, 711); free(c);
    c = dup_bytes(b, n); c[1328 + 4 * 2 + 3] = 9; expect_only(lbk_validate_llg, c, n, 712); free(c);
    lbk_free(NULL, b);
}

static void octp_fixture(lbk_octp_probe_desc *pd, void **out, size_t *size)
{
    for (int p = 0; p < 2; p++) {
        memset(&pd[p], 0, sizeof pd[p]);
        pd[p].position[0] = (float)p;
        pd[p].position[2] = -3.5f;
        for (int i = 0; i < 16; i++)
            for (int k = 0; k < 3; k++) pd[p].irradiance[i][k] = (float)(i + 1) * 0.25f + (float)k; /* exact in uf10/11 */
        for (int i = 0; i < 144; i++) {
            pd[p].depth[i][0] = 1.0f + (float)i / 16.0f;                /* exact in half */
            pd[p].depth[i][1] = pd[p].depth[i][0] * pd[p].depth[i][0]; /* rounds */
        }
    }
    assert_int_equal(lbk_octp_build(&(lbk_octp_build_desc){.probes = pd, .probe_count = 2}, NULL, out, size), LBK_OK);
}

static void octa_mapping(void **state)
{
    (void)state;
    for (int t = 0; t < 2000; t++) {
        const double z = -1.0 + 2.0 * (t + 0.5) / 2000.0, r = sqrt(1 - z * z), ph = t * 2.399963229728653;
        const float d[3] = {(float)(r * cos(ph)), (float)(r * sin(ph)), (float)z};
        float uv[2], e[3];
        lbk_oct_encode(d, uv);
        assert_true(fabsf(uv[0]) <= 1.0f && fabsf(uv[1]) <= 1.0f);
        lbk_oct_decode(uv, e);
        for (int k = 0; k < 3; k++) assert_true(fabsf(e[k] - d[k]) < 1e-5f);
    }
    /* borders: every border texel's source is interior; the seam is continuous: the direction at
     * a border texel centre (extrapolated) equals its source's direction */
    for (uint32_t y = 0; y < 6; y++)
        for (uint32_t x = 0; x < 6; x++) {
            uint32_t sx, sy;
            lbk_oct_border_source(4, x, y, &sx, &sy);
            assert_true(sx >= 1 && sx <= 4 && sy >= 1 && sy <= 4);
            if (x >= 1 && x <= 4 && y >= 1 && y <= 4) assert_true(sx == x && sy == y);
            else if (!((x == 0 || x == 5) && (y == 0 || y == 5))) {
                /* edge texel: its centre lies half a texel outside [−1,1]²; folding it back gives the source */
                const float u = ((float)x - 0.5f) / 4.0f * 2.0f - 1.0f, v = ((float)y - 0.5f) / 4.0f * 2.0f - 1.0f;
                float fu = u, fv = v;
                if (u < -1.0f) { fu = -2.0f - u; fv = -v; }
                if (u > 1.0f) { fu = 2.0f - u; fv = -v; }
                if (v < -1.0f) { fv = -2.0f - v; fu = -u; }
                if (v > 1.0f) { fv = 2.0f - v; fu = -u; }
                const float su = ((float)sx - 0.5f) / 4.0f * 2.0f - 1.0f, sv = ((float)sy - 0.5f) / 4.0f * 2.0f - 1.0f;
                assert_true(fabsf(fu - su) < 1e-6f && fabsf(fv - sv) < 1e-6f);
            }
        }
}

static void octp_rules(void **state)
{
    (void)state;
    lbk_octp_probe_desc pd[2], back;
    void *b;
    size_t n;
    octp_fixture(pd, &b, &n);
    assert_int_equal(n, 16 + 2048);
    lbk_octp_view v;
    assert_int_equal(lbk_octp_open(b, n, &v), LBK_OK);
    assert_int_equal(lbk_octp_probe_get(&v, 1, &back), LBK_OK);
    assert_memory_equal(back.irradiance, pd[1].irradiance, sizeof back.irradiance);
    assert_memory_equal(back.position, pd[1].position, sizeof back.position);
    for (int i = 0; i < 144; i++) {
        assert_true(back.depth[i][0] == pd[1].depth[i][0]);
        assert_true(fabsf(back.depth[i][1] - pd[1].depth[i][1]) <= pd[1].depth[i][1] / 2048.0f);
    }
    /* bilinear lookup at an interior texel centre returns that texel */
    float dir[3], rgb[3];
    lbk_oct_texel_direction(4, 2, 1, dir);
    assert_int_equal(lbk_octp_irradiance(&v, 0, dir, rgb), LBK_OK);
    for (int k = 0; k < 3; k++) assert_true(fabsf(rgb[k] - pd[0].irradiance[1 * 4 + 2][k]) < 1e-5f);
    issues is;
    run(lbk_validate_octp, b, n, &is, NULL);
    assert_int_equal(is.n, 0);
    uint8_t *c;
    const size_t p1 = 16 + 1024;
    expect_only(lbk_validate_octp, b, 8, 1000);
    c = dup_bytes(b, n); c[12] = 1; expect_only(lbk_validate_octp, c, n, 1001); free(c);
    c = dup_bytes(b, n); c[5] = 1; expect_only(lbk_validate_octp, c, n, 1009); free(c);
    c = dup_bytes(b, n); lbk_wr32(c, 0); expect_only(lbk_validate_octp, c, n, 1002); free(c);
    expect_only(lbk_validate_octp, b, n - 1024, 1003);
    /* interior texel (1,1) of probe 1 set to NaN: also its border copies now differ → 1006 */
    c = dup_bytes(b, n); lbk_wr32(c + p1 + 4 * (1 * 6 + 1), 0x7ffu); expect_has(lbk_validate_octp, c, n, 1004); expect_has(lbk_validate_octp, c, n, 1006); free(c);
    c = dup_bytes(b, n); lbk_wr16(c + p1 + 144 + 4 * (3 * 14 + 3) + 2, 0xbc00); expect_has(lbk_validate_octp, c, n, 1005); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + p1 + 4 * 2, 0); expect_only(lbk_validate_octp, c, n, 1006); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + p1 + 928 + 4, NAN); expect_only(lbk_validate_octp, c, n, 1007); free(c);
    c = dup_bytes(b, n); c[p1 + 1023] = 1; expect_only(lbk_validate_octp, c, n, 1008); free(c);
    lbk_free(NULL, b);
}

/* A 3×3×3 volume, spacing 1 from (0, 0, 0): every texel of probe (x, y, z) holds
 * 1 + x + 2y + 4z (exact in uf10/11), depth = the miss distance 8 (nothing near). */
static void octv_fixture(lbk_octp_probe_desc *pd, lbk_octp_probe_info *in, void **out, size_t *size)
{
    for (int i = 0; i < 27; i++) {
        memset(&pd[i], 0, sizeof pd[i]);
        memset(&in[i], 0, sizeof in[i]);
        const float v = (float)(1 + i % 3 + 2 * (i / 3 % 3) + 4 * (i / 9));
        for (int t = 0; t < 16; t++)
            for (int k = 0; k < 3; k++) pd[i].irradiance[t][k] = v;
        for (int t = 0; t < 144; t++) pd[i].depth[t][0] = 8, pd[i].depth[t][1] = 64;
        in[i].nearest = 8;
        in[i].rays = 64;
    }
    const lbk_octp_level lv = {{0, 0, 0}, 1.0f, {3, 3, 3}, 0, 8.0f};
    lbk_octp_build_desc d = LBK_OCTP_BUILD_DESC_INIT;
    d.probes = pd, d.probe_count = 27, d.levels = &lv, d.level_count = 1, d.info = in;
    assert_int_equal(lbk_octp_build(&d, NULL, out, size), LBK_OK);
}

static float sample_at(const lbk_octp_view *v, float x, float y, float z, uint32_t flags)
{
    lbk_octp_sample_desc sd = LBK_OCTP_SAMPLE_DESC_INIT;
    sd.position[0] = x, sd.position[1] = y, sd.position[2] = z;
    sd.flags = flags;
    float rgb[3], w;
    assert_int_equal(lbk_octp_sample(v, &sd, rgb, &w), LBK_OK);
    assert_true(rgb[0] == rgb[1] && rgb[1] == rgb[2] && w > 0);
    return rgb[0];
}

static void octp_volume_rules(void **state)
{
    (void)state;
    lbk_octp_probe_desc pd[27];
    lbk_octp_probe_info in[27];
    void *b;
    size_t n;
    octv_fixture(pd, in, &b, &n);
    assert_int_equal(n, 16 + 48 + 27 * 1024);
    issues is;
    run(lbk_validate_octp, b, n, &is, NULL);
    assert_int_equal(is.n, 0);
    lbk_octp_view v;
    assert_int_equal(lbk_octp_open(b, n, &v), LBK_OK);
    assert_int_equal(v.level_count, 1);
    {
        /* a miss distance no half holds (2√3, what the baker's diagonal gives): every probe at
         * it (all rays missed) still validates — m1 is rounded down, m2 up (1015) */
        lbk_octp_probe_desc pm[27];
        memcpy(pm, pd, sizeof pm);
        const float miss = 3.46410161f;
        for (int i = 0; i < 27; i++)
            for (int t = 0; t < 144; t++) pm[i].depth[t][0] = miss, pm[i].depth[t][1] = miss * miss;
        const lbk_octp_level lm = {{0, 0, 0}, 1.0f, {3, 3, 3}, 0, miss};
        lbk_octp_build_desc dm = LBK_OCTP_BUILD_DESC_INIT;
        dm.probes = pm, dm.probe_count = 27, dm.levels = &lm, dm.level_count = 1, dm.info = in;
        void *bm;
        size_t nm;
        assert_int_equal(lbk_octp_build(&dm, NULL, &bm, &nm), LBK_OK);
        issues im;
        run(lbk_validate_octp, bm, nm, &im, NULL);
        assert_int_equal(im.n, 0);
        lbk_free(NULL, bm);
    }
    assert_int_equal(v.levels[0].dims[2], 3);
    /* trilinear reproduces a linear field exactly (no normal: no back-face weight; depth =
     * miss: Chebyshev weight 1) */
    assert_float_equal(sample_at(&v, 0.5f, 0.25f, 1.75f, 0), 1 + 0.5 + 0.5 + 7, 1e-5);
    assert_float_equal(sample_at(&v, 2, 2, 2, 0), 1 + 2 + 4 + 8, 1e-5); /* the far corner probe */
    lbk_free(NULL, b);
    /* an inactive probe (inside geometry) is skipped: the cell's other 7 renormalised */
    in[13].state = LBK_OCTP_INSIDE; /* (1, 1, 1) */
    for (int t = 0; t < 16; t++) pd[13].irradiance[t][0] = pd[13].irradiance[t][1] = pd[13].irradiance[t][2] = 60000;
    const lbk_octp_level lv = {{0, 0, 0}, 1.0f, {3, 3, 3}, 0, 8.0f};
    lbk_octp_build_desc d = LBK_OCTP_BUILD_DESC_INIT;
    d.probes = pd, d.probe_count = 27, d.levels = &lv, d.level_count = 1, d.info = in;
    assert_int_equal(lbk_octp_build(&d, NULL, &b, &n), LBK_OK);
    assert_int_equal(lbk_octp_open(b, n, &v), LBK_OK);
    /* at (0.5, 0.5, 0.5) the 8 corners weigh 1/8 each; without (1,1,1) (value 8): the mean of
     * 1, 2, 3, 4, 5, 6, 7 (the others of the linear field) = 4 */
    assert_float_equal(sample_at(&v, 0.5f, 0.5f, 0.5f, 0), 4, 1e-5);
    lbk_free(NULL, b);
    in[13].state = LBK_OCTP_ACTIVE;
    for (int t = 0; t < 16; t++) pd[13].irradiance[t][0] = pd[13].irradiance[t][1] = pd[13].irradiance[t][2] = 8;
    /* Chebyshev: probe (1,1,1) has a wall 0.1 m away in every direction (variance 1e-4): from
     * (0.5, 0.5, 0.5), 0.87 m away, its weight is (1e-4/(1e-4 + 0.77²))³ → floored and crushed
     * (≤ 1e-6³/0.04), so the result is the other 7's mean within 1e-6 relative */
    for (int t = 0; t < 144; t++) pd[13].depth[t][0] = 0.1f, pd[13].depth[t][1] = 0.0101f;
    assert_int_equal(lbk_octp_build(&d, NULL, &b, &n), LBK_OK);
    assert_int_equal(lbk_octp_open(b, n, &v), LBK_OK);
    assert_float_equal(sample_at(&v, 0.5f, 0.5f, 0.5f, 0), 4, 4e-6);
    /* without the Chebyshev weight it counts again: 1..8 mean 4.5 */
    assert_float_equal(sample_at(&v, 0.5f, 0.5f, 0.5f, LBK_OCTP_SAMPLE_NO_CHEBYSHEV), 4.5f, 1e-5);
    /* the validator's volume rules */
    uint8_t *c;
    const size_t p0 = 16 + 48;
    c = dup_bytes(b, n); lbk_wr32(c + 8, 4); expect_only(lbk_validate_octp, c, n, 1010); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 16 + 16, 1); expect_only(lbk_validate_octp, c, n, 1011); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + 16 + 12, -1.0f); expect_only(lbk_validate_octp, c, n, 1011); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + 16 + 32, 300.0f); expect_only(lbk_validate_octp, c, n, 1011); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + 16 + 28, 1); expect_only(lbk_validate_octp, c, n, 1012); free(c);
    c = dup_bytes(b, n); lbk_wr32(c, 26); expect_has(lbk_validate_octp, c, n, 1012); free(c);
    c = dup_bytes(b, n); c[16 + 40] = 1; expect_only(lbk_validate_octp, c, n, 1001); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + p0 + 940, 0.6f); expect_only(lbk_validate_octp, c, n, 1013); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + p0 + 928, 0.01f); expect_only(lbk_validate_octp, c, n, 1013); free(c);
    c = dup_bytes(b, n); lbk_wr32(c + p0 + 952, 3); expect_only(lbk_validate_octp, c, n, 1014); free(c);
    c = dup_bytes(b, n); lbk_wrf32(c + p0 + 960, 1.5f); expect_only(lbk_validate_octp, c, n, 1014); free(c);
    /* m2 < m1²: texel (3, 3) of probe 0 (and its border copies, hence 1006 too) */
    c = dup_bytes(b, n); lbk_wr16(c + p0 + 144 + 4 * (3 * 14 + 3) + 2, 0x3c00); expect_has(lbk_validate_octp, c, n, 1015); free(c);
    c = dup_bytes(b, n); c[p0 + 1023] = 1; expect_only(lbk_validate_octp, c, n, 1008); free(c);
    expect_has(lbk_validate_octp, b, n - 1024, 1003);
    assert_int_equal(lbk_octp_open(b, 40, &v), LBK_ERR_TRUNCATED);
    lbk_free(NULL, b);
}

/* Two clip levels: level 0 (spacing 1 over [0, 2]³) holds 10 everywhere, level 1 (spacing 2 over
 * [−1, 3]³) 20: inside level 0 its value, blended linearly over its last cell (§14.3 step 7),
 * level 1 beyond it. */
static void octp_levels_blend(void **state)
{
    (void)state;
    static lbk_octp_probe_desc pd[54];
    lbk_octp_probe_info in[54];
    memset(in, 0, sizeof in);
    for (int i = 0; i < 54; i++) {
        memset(&pd[i], 0, sizeof pd[i]);
        for (int t = 0; t < 16; t++) pd[i].irradiance[t][0] = pd[i].irradiance[t][1] = pd[i].irradiance[t][2] = i < 27 ? 10.0f : 20.0f;
        for (int t = 0; t < 144; t++) pd[i].depth[t][0] = 16, pd[i].depth[t][1] = 256;
    }
    const lbk_octp_level lv[2] = {{{0, 0, 0}, 1.0f, {3, 3, 3}, 0, 16.0f}, {{-1, -1, -1}, 2.0f, {3, 3, 3}, 0, 16.0f}};
    lbk_octp_build_desc d = LBK_OCTP_BUILD_DESC_INIT;
    d.probes = pd, d.probe_count = 54, d.levels = lv, d.level_count = 2, d.info = in;
    void *b;
    size_t n;
    assert_int_equal(lbk_octp_build(&d, NULL, &b, &n), LBK_OK);
    issues is;
    run(lbk_validate_octp, b, n, &is, NULL);
    assert_int_equal(is.n, 0);
    lbk_octp_view v;
    assert_int_equal(lbk_octp_open(b, n, &v), LBK_OK);
    assert_int_equal(v.levels[1].first_probe, 27);
    assert_float_equal(sample_at(&v, 1, 1, 1, 0), 10, 1e-5);   /* one cell from every edge */
    assert_float_equal(sample_at(&v, 0.5f, 1, 1, 0), 15, 1e-5); /* half a cell: half and half */
    assert_float_equal(sample_at(&v, 0.5f, 1, 1, LBK_OCTP_SAMPLE_NO_BLEND), 10, 1e-5);
    assert_float_equal(sample_at(&v, 2, 1, 1, 0), 20, 1e-5);    /* on level 0's boundary */
    assert_float_equal(sample_at(&v, 2.5f, 1, 1, 0), 20, 1e-5); /* level 1 only */
    assert_float_equal(sample_at(&v, 9, 9, 9, 0), 20, 1e-5);    /* outside both: clamped coarsest */
    /* spacing must grow from level to level */
    const lbk_octp_level bad[2] = {lv[1], lv[0]};
    d.levels = bad;
    assert_int_equal(lbk_octp_build(&d, NULL, &b, &n), LBK_ERR_INVALID_ARGUMENT);
    lbk_free(NULL, (void *)v.data);
}

/* All four in one container through the public validator: valid, and the table IDs known. */
static void container_clean(void **state)
{
    (void)state;
    lbk_ahd_texel t0[6], t1[20];
    lbk_octp_probe_desc pd[2];
    void *s[4];
    size_t n[4];
    lmap_fixture(&s[0], &n[0], t0, t1);
    glg_fixture(8, &s[1], &n[1]);
    llg_fixture(&s[2], &n[2]);
    octp_fixture(pd, &s[3], &n[3]);
    const uint32_t types[4] = {LBK_SECTION_LMAP, LBK_SECTION_GLG, LBK_SECTION_LLG, LBK_SECTION_OCTP};
    lbk_writer *w;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    for (int i = 0; i < 4; i++) {
        lbk_section_options o = {.compression = i == 1 ? LBK_COMPRESSION_ZSTD : LBK_COMPRESSION_NONE,
            .zstd_level = 3};
        assert_int_equal(lbk_writer_section_add(w, types[i], s[i], n[i], &o), LBK_OK);
    }
    void *file;
    size_t fsize;
    assert_int_equal(lbk_writer_to_memory(w, &file, &fsize), LBK_OK);
    issues is;
    memset(&is, 0, sizeof is);
    lbk_validate_summary sum;
    assert_int_equal(lbk_validate_memory(file, fsize, NULL, collect, &is, &sum), LBK_OK);
    assert_int_equal(sum.fatal + sum.errors, 0);
    for (int i = 0; i < is.n; i++) assert_int_equal(is.id[i], 221); /* only: no OBJS section */
    for (uint32_t id = 500; id <= 511; id++) assert_non_null(lbk_issue_template(id, NULL));
    for (uint32_t id = 600; id <= 611; id++) assert_non_null(lbk_issue_template(id, NULL));
    for (uint32_t id = 700; id <= 713; id++) assert_non_null(lbk_issue_template(id, NULL));
    for (uint32_t id = 1000; id <= 1009; id++) assert_non_null(lbk_issue_template(id, NULL));
    lbk_free(NULL, file);
    lbk_writer_close(w);
    for (int i = 0; i < 4; i++) lbk_free(NULL, s[i]);
}

/* LMAP at scale 2^-20: texels are stored units; the view and lbk_lmap_page_irradiance apply
 * 2^-20. Its bytes go to *bytes (lbk_free). */
static void scaled_lmap(void **bytes, size_t *size)
{
    lbk_ahd_texel t0[6], t1[20];
    void *b1;
    size_t n1;
    lmap_fixture(&b1, &n1, t0, t1);
    const lbk_lmap_page_desc pages[2] = {{3, 2, t0}, {5, 4, t1}};
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages, .page_count = 2,
        .scale = 0x1p-20f}, NULL, bytes, size), LBK_OK);
    assert_int_equal(*size, n1);
    assert_memory_equal((uint8_t *)*bytes + 8, (uint8_t *)b1 + 8, n1 - 8); /* only the scale differs */
    assert_true(lbk_rdf32((uint8_t *)*bytes + 4) == 0x1p-20f && lbk_rdf32((uint8_t *)b1 + 4) == 1.0f);
    lbk_lmap_view lv;
    lbk_lmap_page pg;
    assert_int_equal(lbk_lmap_open(*bytes, *size, &lv), LBK_OK);
    assert_true(lv.scale == 0x1p-20f);
    assert_int_equal(lbk_lmap_page_get(&lv, 0, &pg), LBK_OK);
    assert_true(pg.scale == 0x1p-20f);
    const float nz[3] = {0, 0.6f, 0.8f};
    for (uint32_t i = 0; i < 6; i++) {
        float e[3], want[3];
        assert_int_equal(lbk_lmap_page_irradiance(&pg, i % 3, i / 3, nz, e), LBK_OK);
        lbk_ahd_irradiance(&t0[i], nz, want);
        for (int c = 0; c < 3; c++) assert_true(e[c] == want[c] * 0x1p-20f && want[c] > 0);
    }
    issues is;
    run(lbk_validate_lmap, *bytes, *size, &is, NULL);
    assert_int_equal(is.n, 0);
    void *none;
    size_t none_n;
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages, .page_count = 2,
        .scale = 3.0f}, NULL, &none, &none_n), LBK_ERR_INVALID_ARGUMENT);
    lbk_free(NULL, b1);
}

/* GLG: physical SH in, physical out; the stored probe is value / scale. */
static void scaled_glg(void)
{
    lbk_sh9_rgb sh[8], got;
    issues is;
    void *none;
    size_t none_n;
    memset(sh, 0, sizeof sh);
    for (int i = 0; i < 8; i++)
        for (int c = 0; c < 3; c++) {
            sh[i].c[c][0] = 3e5f * (float)(i + 1) * (float)(c + 1);
            sh[i].c[c][3] = 1e5f * (float)(i + 1); /* within √3·DC */
        }
    lbk_glg_build_desc d = {.probe_count = 8, .tetra_count = 6, .positions = cube_pos, .probes = sh,
        .tetras = cube_tets, .scale = 0x1p8f};
    void *gb;
    size_t gn;
    assert_int_equal(lbk_glg_build(&d, NULL, &gb, &gn), LBK_OK);
    lbk_glg_view gv;
    assert_int_equal(lbk_glg_open(gb, gn, &gv), LBK_OK);
    assert_true(gv.scale == 0x1p8f);
    for (uint32_t i = 0; i < 8; i++) {
        lbk_sh9_rgb stored, want;
        memset(&want, 0, sizeof want);
        lbk_sh9_add_scaled(&want, &sh[i], 0x1p-8f);
        uint8_t packed[LBK_SH9_PACKED_SIZE];
        lbk_sh9_pack(&want, packed);
        assert_memory_equal(gv.probes + LBK_SH9_PACKED_SIZE * i, packed, LBK_SH9_PACKED_SIZE);
        lbk_sh9_unpack(packed, &stored);
        assert_int_equal(lbk_glg_probe_get(&gv, i, NULL, &got), LBK_OK);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) assert_true(got.c[c][k] == stored.c[c][k] * 0x1p8f);
        /* RGB9E5 DC within 2^-9 of the largest channel (up to 7.2e6: far above 65408, the format maximum at scale 1) */
        for (int c = 0; c < 3; c++) assert_true(fabsf(got.c[c][0] - sh[i].c[c][0]) <= sh[i].c[2][0] * 0x1p-9f);
    }
    const float at7[3] = {1, 1, 1};
    assert_int_equal(lbk_glg_sample(&gv, at7, NULL, &got, NULL), LBK_OK);
    assert_true(fabsf(got.c[2][0] - 2.4e6f * 3) <= 2.4e6f * 3 * 0x1p-9f);
    run(lbk_validate_glg, gb, gn, &is, NULL);
    assert_int_equal(is.n, 0);
    lbk_free(NULL, gb);
    d.scale = -2.0f;
    assert_int_equal(lbk_glg_build(&d, NULL, &none, &none_n), LBK_ERR_INVALID_ARGUMENT);
}

/* A 2×2×2 LLG over the unit cube with a uniform field of 1e-7 (lp) and one vertex (vert). */
static void uniform_llg(lbk_sh9_rgb lp[8], const lbk_llg_vertex *vert, lbk_llg_grid_desc *g)
{
    memset(lp, 0, 8 * sizeof *lp);
    for (int i = 0; i < 8; i++)
        for (int c = 0; c < 3; c++) lp[i].c[c][0] = 1e-7f;
    memset(g, 0, sizeof *g);
    g->axes[0][0] = g->axes[1][1] = g->axes[2][2] = 1.0f;
    g->half_extents[0] = g->half_extents[1] = g->half_extents[2] = 1.0f;
    g->dims[0] = g->dims[1] = g->dims[2] = 2;
    g->probes = lp;
    g->vertices = vert;
    g->vertex_count = 1;
}

/* LLG: a uniform field sampled and applied to a vertex, physical values at scale 2^-30. */
static void scaled_llg(void)
{
    lbk_sh9_rgb lp[8], got;
    const lbk_llg_vertex vert = {1.0f, {0, 0, 1}};
    lbk_llg_grid_desc g;
    uniform_llg(lp, &vert, &g);
    issues is;
    void *lb;
    size_t ln;
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g, .grid_count = 1,
        .scale = 0x1p-30f}, NULL, &lb, &ln), LBK_OK);
    lbk_llg_view llv;
    assert_int_equal(lbk_llg_open(lb, ln, &llv), LBK_OK);
    assert_true(llv.scale == 0x1p-30f);
    const float origin[3] = {0.1f, -0.2f, 0.3f};
    assert_int_equal(lbk_llg_sample(&llv, 0, origin, &got), LBK_OK);
    for (int c = 0; c < 3; c++) assert_true(fabsf(got.c[c][0] - 1e-7f) <= 1e-7f * 0x1p-9f);
    float e[3];
    assert_int_equal(lbk_llg_vertex_irradiance(&llv, 0, 0, origin, e), LBK_OK);
    const float e_want = (float)(M_PI * 0.282094791773878) * 1e-7f; /* A0·Y0·L0 */
    for (int c = 0; c < 3; c++) assert_true(fabsf(e[c] - e_want) <= e_want * 0x1p-8f);
    run(lbk_validate_llg, lb, ln, &is, NULL);
    assert_int_equal(is.n, 0);
    lbk_free(NULL, lb);
}

/* OCTP: irradiance 2^20 × the fixture's exact values (pd) round-trips exactly at scale 2^20; its
 * bytes go to *bytes (lbk_free). */
static void scaled_octp(lbk_octp_probe_desc pd[2], void **bytes, size_t *size)
{
    lbk_octp_probe_desc back;
    issues is;
    octp_fixture(pd, bytes, size);
    lbk_free(NULL, *bytes);
    for (int p = 0; p < 2; p++)
        for (int i = 0; i < 16; i++)
            for (int k = 0; k < 3; k++) pd[p].irradiance[i][k] *= 0x1p20f;
    assert_int_equal(lbk_octp_build(&(lbk_octp_build_desc){.probes = pd, .probe_count = 2,
        .scale = 0x1p20f}, NULL, bytes, size), LBK_OK);
    lbk_octp_view ov;
    assert_int_equal(lbk_octp_open(*bytes, *size, &ov), LBK_OK);
    assert_true(ov.scale == 0x1p20f);
    assert_int_equal(lbk_octp_probe_get(&ov, 1, &back), LBK_OK);
    assert_memory_equal(back.irradiance, pd[1].irradiance, sizeof back.irradiance);
    float dir[3], rgb[3];
    lbk_oct_texel_direction(4, 2, 1, dir);
    assert_int_equal(lbk_octp_irradiance(&ov, 0, dir, rgb), LBK_OK);
    for (int k = 0; k < 3; k++) assert_true(fabsf(rgb[k] - pd[0].irradiance[1 * 4 + 2][k]) <= pd[0].irradiance[1 * 4 + 2][k] * 1e-6f);
    run(lbk_validate_octp, *bytes, *size, &is, NULL);
    assert_int_equal(is.n, 0);
}

/* Invalid scales: zero, NaN, +Inf, negative, not a power of two, denormal — each is exactly the
 * section's scale issue, and the view refuses the bytes (bs: a scaled LMAP, ob: a scaled OCTP of
 * pd). */
static void bad_scales(const void *bs, size_t ns, const void *ob, size_t on, const lbk_octp_probe_desc pd[2])
{
    void *gb, *lb, *none;
    size_t gn, ln, none_n;
    lbk_lmap_view lv;
    lbk_octp_view ov;
    lbk_glg_view gv;
    lbk_llg_view llv;
    lbk_sh9_rgb lp[8];
    const lbk_llg_vertex vert = {1.0f, {0, 0, 1}};
    lbk_llg_grid_desc g;
    uniform_llg(lp, &vert, &g);
    const uint32_t bad[6] = {0x00000000u, 0x7fc00000u, 0x7f800000u, 0xc0000000u, 0x40400000u /* 3 */, 0x00400000u};
    for (int k = 0; k < 6; k++) {
        uint8_t *c = dup_bytes(bs, ns);
        lbk_wr32(c + 4, bad[k]);
        expect_only(lbk_validate_lmap, c, ns, 511);
        assert_int_equal(lbk_lmap_open(c, ns, &lv), LBK_ERR_CORRUPT);
        free(c);
        c = dup_bytes(ob, on);
        lbk_wr32(c + 4, bad[k]);
        expect_only(lbk_validate_octp, c, on, 1009);
        assert_int_equal(lbk_octp_open(c, on, &ov), LBK_ERR_CORRUPT);
        free(c);
    }
    glg_fixture(8, &gb, &gn);
    assert_int_equal(lbk_llg_build(&(lbk_llg_build_desc){.grids = &g, .grid_count = 1}, NULL, &lb, &ln), LBK_OK);
    for (int k = 0; k < 6; k++) {
        uint8_t *c = dup_bytes(gb, gn);
        lbk_wr32(c + 8, bad[k]);
        expect_only(lbk_validate_glg, c, gn, 611);
        assert_int_equal(lbk_glg_open(c, gn, &gv), LBK_ERR_CORRUPT);
        free(c);
        c = dup_bytes(lb, ln);
        lbk_wr32(c + 4, bad[k]);
        expect_only(lbk_validate_llg, c, ln, 713);
        assert_int_equal(lbk_llg_open(c, ln, &llv), LBK_ERR_CORRUPT);
        free(c);
    }
    assert_int_equal(lbk_octp_build(&(lbk_octp_build_desc){.probes = pd, .probe_count = 2,
        .scale = NAN}, NULL, &none, &none_n), LBK_ERR_INVALID_ARGUMENT);
    lbk_free(NULL, gb), lbk_free(NULL, lb);
}

/* The radiometric scale (spec §5.7): every section round-trips physical values exactly through a
 * scale ≠ 1 (stored bytes are those of value / scale), builders refuse and validators report a
 * scale that is not a positive finite power of two. */
static void scaled_sections(void **state)
{
    (void)state;
    void *bs, *ob;
    size_t ns, on;
    lbk_octp_probe_desc pd[2];
    scaled_lmap(&bs, &ns);
    scaled_glg();
    scaled_llg();
    scaled_octp(pd, &ob, &on);
    bad_scales(bs, ns, ob, on, pd);
    lbk_free(NULL, ob), lbk_free(NULL, bs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lmap_round_trip_and_rules), cmocka_unit_test(glg_rules), cmocka_unit_test(llg_rules),
        cmocka_unit_test(octa_mapping),              cmocka_unit_test(octp_rules),
        cmocka_unit_test(octp_volume_rules),
        cmocka_unit_test(octp_levels_blend), cmocka_unit_test(container_clean),
        cmocka_unit_test(scaled_sections),      cmocka_unit_test(lmap_fast_scan_exact), cmocka_unit_test(lmap_block_pages),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
