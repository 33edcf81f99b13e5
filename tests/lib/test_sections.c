/* LMAP, GLG, LLG, OCTP sections: builder → view round trips, a clean container through
 * lbk_validate_memory, and every validator rule caught on a deliberately broken copy. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    c = dup_bytes(b, n); c[16 + 32 + 5] = 1; expect_only(lbk_validate_lmap, c, n, 501); free(c);
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

/* The radiometric scale (spec §5.7): every section round-trips physical values exactly through a
 * scale ≠ 1 (stored bytes are those of value / scale), builders refuse and validators report a
 * scale that is not a positive finite power of two. */
static void scaled_sections(void **state)
{
    (void)state;
    /* LMAP: texels are stored units; the view and lbk_lmap_page_irradiance apply 2^-20 */
    lbk_ahd_texel t0[6], t1[20];
    void *b1, *bs;
    size_t n1, ns;
    lmap_fixture(&b1, &n1, t0, t1);
    const lbk_lmap_page_desc pages[2] = {{3, 2, t0}, {5, 4, t1}};
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages, .page_count = 2,
        .scale = 0x1p-20f}, NULL, &bs, &ns), LBK_OK);
    assert_int_equal(ns, n1);
    assert_memory_equal((uint8_t *)bs + 8, (uint8_t *)b1 + 8, n1 - 8); /* only the scale differs */
    assert_true(lbk_rdf32((uint8_t *)bs + 4) == 0x1p-20f && lbk_rdf32((uint8_t *)b1 + 4) == 1.0f);
    lbk_lmap_view lv;
    lbk_lmap_page pg;
    assert_int_equal(lbk_lmap_open(bs, ns, &lv), LBK_OK);
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
    run(lbk_validate_lmap, bs, ns, &is, NULL);
    assert_int_equal(is.n, 0);
    void *none;
    size_t none_n;
    assert_int_equal(lbk_lmap_build(&(lbk_lmap_build_desc){.pages = pages, .page_count = 2,
        .scale = 3.0f}, NULL, &none, &none_n), LBK_ERR_INVALID_ARGUMENT);
    lbk_free(NULL, b1);

    /* GLG: physical SH in, physical out; the stored probe is value / scale */
    lbk_sh9_rgb sh[8], got;
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

    /* LLG: a uniform field sampled and applied to a vertex, physical values at scale 2^-30 */
    lbk_sh9_rgb lp[8];
    memset(lp, 0, sizeof lp);
    for (int i = 0; i < 8; i++)
        for (int c = 0; c < 3; c++) lp[i].c[c][0] = 1e-7f;
    const lbk_llg_vertex vert = {1.0f, {0, 0, 1}};
    lbk_llg_grid_desc g;
    memset(&g, 0, sizeof g);
    g.axes[0][0] = g.axes[1][1] = g.axes[2][2] = 1.0f;
    g.half_extents[0] = g.half_extents[1] = g.half_extents[2] = 1.0f;
    g.dims[0] = g.dims[1] = g.dims[2] = 2;
    g.probes = lp;
    g.vertices = &vert;
    g.vertex_count = 1;
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

    /* OCTP: irradiance 2^20 × the fixture's exact values round-trips exactly at scale 2^20 */
    lbk_octp_probe_desc pd[2], back;
    void *ob;
    size_t on;
    octp_fixture(pd, &ob, &on);
    lbk_free(NULL, ob);
    for (int p = 0; p < 2; p++)
        for (int i = 0; i < 16; i++)
            for (int k = 0; k < 3; k++) pd[p].irradiance[i][k] *= 0x1p20f;
    assert_int_equal(lbk_octp_build(&(lbk_octp_build_desc){.probes = pd, .probe_count = 2,
        .scale = 0x1p20f}, NULL, &ob, &on), LBK_OK);
    lbk_octp_view ov;
    assert_int_equal(lbk_octp_open(ob, on, &ov), LBK_OK);
    assert_true(ov.scale == 0x1p20f);
    assert_int_equal(lbk_octp_probe_get(&ov, 1, &back), LBK_OK);
    assert_memory_equal(back.irradiance, pd[1].irradiance, sizeof back.irradiance);
    float dir[3], rgb[3];
    lbk_oct_texel_direction(4, 2, 1, dir);
    assert_int_equal(lbk_octp_irradiance(&ov, 0, dir, rgb), LBK_OK);
    for (int k = 0; k < 3; k++) assert_true(fabsf(rgb[k] - pd[0].irradiance[1 * 4 + 2][k]) <= pd[0].irradiance[1 * 4 + 2][k] * 1e-6f);
    run(lbk_validate_octp, ob, on, &is, NULL);
    assert_int_equal(is.n, 0);

    /* invalid scales: zero, NaN, +Inf, negative, not a power of two, denormal — each is exactly
     * the section's scale issue, and the view refuses the bytes */
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
    lbk_free(NULL, gb), lbk_free(NULL, lb), lbk_free(NULL, ob), lbk_free(NULL, bs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lmap_round_trip_and_rules), cmocka_unit_test(glg_rules), cmocka_unit_test(llg_rules),
        cmocka_unit_test(octa_mapping),              cmocka_unit_test(octp_rules), cmocka_unit_test(container_clean),
        cmocka_unit_test(scaled_sections),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
