/* Stability suite through the whole pipeline: each test writes a small glTF level
 * (tests/support/gltf_writer), bakes it through liblbkbake (lbk/bake.h), validates the container with
 * lbk_validate_file, decodes every lightmap texel and every GLG/LLG probe (finite, non-negative
 * irradiance and fluence), and compares the lighting with what it must be:
 *
 *  - light intensity 1e-6 and 1e6 (and 1e-4, 1e4): the stored texels and probes are the
 *    decoded unit-intensity bake × k, within the codecs' rounding, saturating at the
 *    R11G11B10F / RGB9E5 maxima and flushing below their smallest steps (the container has no
 *    exposure field: that is its range; see bake/pipeline/STABILITY.md);
 *  - the level scaled to 1 mm and 10 km (texel density and GLG spacing scaled with it): same
 *    texels, same lighting as the 1 m level within the estimated error;
 *  - the level moved 1e5 m from the origin: same lighting within the estimated error; a 1 mm
 *    object in it (node translation) bakes and lights the same;
 *  - zero-area / degenerate triangles and duplicate vertices mixed in: valid, same lighting;
 *  - probes on a perfect regular grid (cospherical Delaunay): a valid GLG whose tetrahedra
 *    fill the probes' box exactly; all probes on one plane (a floor quad under a sky): no GLG,
 *    no error, and the analytic E = π·L on the floor;
 *  - albedo 0.99 closed furnace (the stiff case): every texel and probe within the furnace
 *    bound of TRANSPORT.md plus the codec rounding;
 *  - unusable input (all triangles degenerate, NaN positions): LBK_ERR_BAD_INPUT, nothing written.
 *
 * Budgets are small (fast preset, 64 samples, a few hundred texels) so the binary stays well
 * under a minute with ASan. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lbk/bake.h"
#include "tests/support/bake_file.h"
#include "lbk/container.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/pixel.h"
#include "lbk/report.h"
#include "lbk/sh.h"
#include "lbk/validate.h"
#include "support/gltf_writer.h"

static char tmpdir[256];

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk-extremes-%d", (int)getpid());
    char cmd[300];
    snprintf(cmd, sizeof cmd, "mkdir -p %s", tmpdir);
    return system(cmd);
}

static int teardown(void **state)
{
    (void)state;
    if (getenv("LBK_KEEP_TMP")) return 0; /* debugging: keep the generated levels */
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
    return system(cmd);
}

static void path_in_tmp(char *out, size_t n, const char *name)
{
    snprintf(out, n, "%s/%s", tmpdir, name);
}

/* ---- decoding a baked container ---------------------------------------------------------- */

typedef struct baked {
    lbk_bake_report sum;
    double est;                 /* estimated relative RMSE of the bake */
    uint32_t passes;            /* REPT records = transport passes */
    int has_lmap, has_glg, has_llg;
    size_t texel_count;
    float (*ez)[3];             /* physical irradiance along the normal (plane 0 × LMAP scale), every texel */
    float lmap_scale, glg_scale, llg_scale; /* the sections' radiometric scales (spec §5.7) */
    size_t glg_count, tet_count;
    float (*glg_pos)[3];
    float (*glg_dc)[3];         /* L00 of every GLG probe */
    double glg_volume;          /* Σ tetrahedron volumes */
    size_t llg_count;
    float (*llg_dc)[3];
} baked;

static void baked_free(baked *b)
{
    free(b->ez), free(b->glg_pos), free(b->glg_dc), free(b->llg_dc);
    memset(b, 0, sizeof *b);
}

static float lum(const float c[3]) { return LBK_LUM_R * c[0] + LBK_LUM_G * c[1] + LBK_LUM_B * c[2]; }

static int count_issue(void *user, const lbk_issue *issue)
{
    if (issue->severity != LBK_SEVERITY_WARNING) {
        print_message("issue %u: %s\n", issue->id, issue->message);
        (*(int *)user)++;
    }
    return 0;
}

static void assert_sh_clean(const lbk_sh9_rgb *sh)
{
    for (int c = 0; c < 3; c++) {
        for (int k = 0; k < LBK_SH9_COUNT; k++) assert_true(isfinite(sh->c[c][k]));
        assert_true(sh->c[c][0] >= 0); /* fluence is never negative */
    }
    static const float axes[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int a = 0; a < 6; a++) {
        float e[3];
        lbk_sh9_irradiance(sh, axes[a], e);
        for (int c = 0; c < 3; c++) assert_true(isfinite(e[c]));
    }
}

/* Validates `path` (no error, no fatal issue) and decodes everything lighting-related. */
static void decode(const char *path, baked *b)
{
    int bad = 0;
    lbk_validate_summary vs;
    assert_int_equal(lbk_validate_file(path, NULL, count_issue, &bad, &vs), LBK_OK);
    assert_int_equal(vs.fatal + vs.errors, 0);
    assert_int_equal(bad, 0);

    lbk_reader *r;
    assert_int_equal(lbk_reader_open_file(path, NULL, &r), LBK_OK);
    const void *data;
    size_t size;
    if (lbk_reader_section_by_type(r, LBK_SECTION_REPT, &data, &size) == LBK_OK) {
        lbk_report_view v;
        assert_int_equal(lbk_report_open(data, size, &v), LBK_OK);
        b->passes = v.header.record_count;
        lbk_report_record rec;
        assert_int_equal(lbk_report_record_get(&v, v.header.record_count - 1, &rec), LBK_OK);
        assert_true(isfinite(rec.texel_rel_rmse) && rec.texel_rel_rmse >= 0);
        assert_true(isfinite(rec.probe_rel_rmse) && rec.probe_rel_rmse >= 0);
    }
    if (lbk_reader_section_by_type(r, LBK_SECTION_LMAP, &data, &size) == LBK_OK) {
        b->has_lmap = 1;
        lbk_lmap_view v;
        assert_int_equal(lbk_lmap_open(data, size, &v), LBK_OK);
        b->texel_count = (size_t)v.texel_count;
        b->lmap_scale = v.scale;
        b->ez = calloc(b->texel_count ? b->texel_count : 1, sizeof *b->ez);
        assert_non_null(b->ez);
        static const float normals[5][3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, -0.6f, 0.8f}, {1, 0, 0}, {0, 0, -1}};
        for (uint64_t t = 0; t < v.texel_count; t++) {
            lbk_ahd_texel tx;
            assert_int_equal(lbk_lmap_texel_get(&v, t, &tx, NULL), LBK_OK);
            lbk_r11g11b10f_unpack(tx.irradiance_z, b->ez[t]);
            for (int c = 0; c < 3; c++) b->ez[t][c] *= v.scale;
            for (int n = 0; n < 5; n++) {
                float e[3];
                lbk_ahd_irradiance(&tx, normals[n], e);
                for (int c = 0; c < 3; c++) assert_true(isfinite(e[c]) && e[c] >= 0);
            }
            for (int c = 0; c < 3; c++) assert_true(isfinite(b->ez[t][c]) && b->ez[t][c] >= 0);
        }
    }
    if (lbk_reader_section_by_type(r, LBK_SECTION_GLG, &data, &size) == LBK_OK) {
        b->has_glg = 1;
        lbk_glg_view v;
        assert_int_equal(lbk_glg_open(data, size, &v), LBK_OK);
        b->glg_count = v.probe_count;
        b->glg_scale = v.scale;
        b->tet_count = v.tetra_count;
        b->glg_pos = calloc(v.probe_count, sizeof *b->glg_pos);
        b->glg_dc = calloc(v.probe_count, sizeof *b->glg_dc);
        assert_non_null(b->glg_pos);
        assert_non_null(b->glg_dc);
        for (uint32_t p = 0; p < v.probe_count; p++) {
            lbk_sh9_rgb sh;
            assert_int_equal(lbk_glg_probe_get(&v, p, b->glg_pos[p], &sh), LBK_OK);
            assert_sh_clean(&sh);
            for (int c = 0; c < 3; c++) b->glg_dc[p][c] = sh.c[c][0];
        }
        for (uint32_t t = 0; t < v.tetra_count; t++) {
            uint32_t q[4];
            for (int i = 0; i < 4; i++) {
                const uint8_t *s = v.mesh.tetras + 16 * (size_t)t + 4 * (size_t)i;
                q[i] = (uint32_t)s[0] | (uint32_t)s[1] << 8 | (uint32_t)s[2] << 16 | (uint32_t)s[3] << 24;
                assert_true(q[i] < v.probe_count);
            }
            double o = lbk_tetra_orient(b->glg_pos[q[0]], b->glg_pos[q[1]], b->glg_pos[q[2]], b->glg_pos[q[3]]);
            assert_true(o > 0);
            b->glg_volume += o / 6;
        }
    }
    if (lbk_reader_section_by_type(r, LBK_SECTION_LLG, &data, &size) == LBK_OK) {
        b->has_llg = 1;
        lbk_llg_view v;
        assert_int_equal(lbk_llg_open(data, size, &v), LBK_OK);
        b->llg_count = (size_t)v.probe_count;
        b->llg_scale = v.scale;
        b->llg_dc = calloc(b->llg_count ? b->llg_count : 1, sizeof *b->llg_dc);
        assert_non_null(b->llg_dc);
        for (uint64_t p = 0; p < v.probe_count; p++) {
            lbk_sh9_rgb sh;
            lbk_sh9_unpack(v.probes + LBK_SH9_PACKED_SIZE * p, &sh);
            assert_sh_clean(&sh);
            for (int c = 0; c < 3; c++) b->llg_dc[p][c] = sh.c[c][0] * v.scale;
        }
    }
    lbk_reader_close(r);
}

/* ---- baking ------------------------------------------------------------------------------- */

static void test_options(tb_job *o, const char *in, const char *out)
{
    memset(o, 0, sizeof *o);
    o->in = in;
    o->out = out;
    o->d.preset = LBK_BAKE_PRESET_FAST;
    o->d.seed = 1;
    /* only the sample budget stops the bake, so equal scenes run equal passes */
    o->d.target_error = 1e-6;
    o->d.max_samples = 64;
    o->d.threads = 2;
}

static lbk_result run_bake(const tb_job *o, lbk_bake_report *sum, char *err, size_t n)
{
    return tb_bake(o, sum, err, n);
}

/* Bakes, asserts success, decodes. */
static void bake_ok(const tb_job *o, baked *b)
{
    char err[512] = "";
    memset(b, 0, sizeof *b);
    int rc = run_bake(o, &b->sum, err, sizeof err);
    if (rc) print_message("bake %s: %s\n", o->in, err);
    assert_int_equal(rc, 0);
    assert_true(isfinite(b->sum.transport.est_rel_rmse) && b->sum.transport.est_rel_rmse >= 0);
    b->est = b->sum.transport.est_rel_rmse;
    decode(o->out, b);
}

/* ---- the levels --------------------------------------------------------------------------- */

/* A 2 × 1.2 × 1.6 closed room (y up) with a block on the floor, lit by a 0.5 m emissive panel
 * under the ceiling (scale-invariant: radiance does not care about size) or by a point light
 * (light_cd > 0). Every coordinate is × scale, then the nodes are translated by offset. */
typedef struct room_spec {
    double scale;
    double offset[3];
    float light_cd;       /* > 0: a point light of this intensity instead of the panel */
    int degenerate;       /* mix zero-area triangles and duplicate vertices in */
    int pebble;           /* a 1 mm cube on the floor (its own object, lightmapped) */
} room_spec;

static void add_degenerate(gw_geom *g)
{
    /* repeated index, collinear, and a zero-length triangle on existing vertices, and a new
     * collinear triple: none has area */
    gw_geom_tri(g, 0, 0, 1);
    gw_geom_tri(g, 1, 2, 2);
    gw_geom_tri(g, 3, 3, 3);
    float *p = &g->pos[0], *q = &g->pos[3];
    uint32_t a = gw_geom_vertex(g, p[0], p[1], p[2]);
    uint32_t b = gw_geom_vertex(g, 0.5f * (p[0] + q[0]), 0.5f * (p[1] + q[1]), 0.5f * (p[2] + q[2]));
    uint32_t c = gw_geom_vertex(g, q[0], q[1], q[2]);
    gw_geom_tri(g, a, b, c);
}

/* Duplicate vertices: the second half of the triangles gets fresh copies of its vertices. */
static void duplicate_vertices(gw_geom *g)
{
    size_t half = g->index_count / 6 * 3;
    for (size_t i = half; i < g->index_count; i++) {
        uint32_t v = g->idx[i];
        float x = g->pos[3 * v], y = g->pos[3 * v + 1], z = g->pos[3 * v + 2];
        g->idx[i] = gw_geom_vertex(g, x, y, z);
    }
}

static void write_room(const char *path, const room_spec *rs)
{
    float s = (float)rs->scale;
    gw_scene *sc = gw_create();
    float grey[3] = {0.6f, 0.6f, 0.6f}, red[3] = {0.7f, 0.3f, 0.2f}, black[3] = {0, 0, 0}, white[3] = {1, 1, 1};
    int wall = gw_material(sc, grey, NULL, 0, 0);
    int block = gw_material(sc, red, NULL, 0, 0);
    const double *off = rs->offset;

    gw_geom room = {0};
    float mn[3] = {0, 0, 0}, mx[3] = {2, 1.2f, 1.6f};
    gw_geom_box(&room, mn, mx, 2, 1);
    gw_geom box = {0};
    float b0[3] = {0.3f, 0, 0.4f}, b1[3] = {0.8f, 0.5f, 0.9f};
    gw_geom_box(&box, b0, b1, 1, 0);
    if (rs->degenerate) {
        add_degenerate(&room);
        add_degenerate(&box);
        duplicate_vertices(&room);
        duplicate_vertices(&box);
    }
    gw_geom_scale(&room, s);
    gw_geom_scale(&box, s);
    /* authored lightmaps: the classifier's size rules are in metres, and a 1 mm level is not
     * a pile of tiny props */
    gw_mesh(sc, "room", &room, wall, 1, off, "lightmap");
    gw_mesh(sc, "block", &box, block, !rs->degenerate, off, "lightmap");
    if (rs->pebble) {
        gw_geom peb = {0};
        float q0[3] = {1.4f, 0, 0.3f}, q1[3] = {1.401f, 0.001f, 0.301f};
        gw_geom_box(&peb, q0, q1, 1, 0);
        gw_geom_scale(&peb, s);
        gw_mesh(sc, "pebble", &peb, block, 1, off, "lightmap");
        gw_geom_free(&peb);
    }
    if (rs->light_cd > 0) {
        double lp[3] = {1.5 * s + off[0], 0.9 * s + off[1], 1.1 * s + off[2]};
        gw_point_light(sc, white, rs->light_cd, lp);
    } else {
        int em = gw_material(sc, black, white, 10, 0);
        gw_geom panel = {0};
        float y = 1.15f;
        float p0[3] = {1.1f, y, 0.55f}, p1[3] = {1.6f, y, 0.55f}, p2[3] = {1.6f, y, 1.05f}, p3[3] = {1.1f, y, 1.05f};
        gw_geom_quad(&panel, p0, p1, p2, p3, 1); /* faces −y */
        gw_geom_scale(&panel, s);
        gw_mesh(sc, "panel", &panel, em, 1, off, NULL);
        gw_geom_free(&panel);
    }
    assert_int_equal(gw_write(sc, path), 0);
    gw_geom_free(&room);
    gw_geom_free(&box);
    gw_free(sc);
}

#define ROOM_DENSITY 8.0f  /* texels per metre at scale 1 */
#define ROOM_SPACING 2.0f  /* GLG spacing in metres at scale 1 */

static void bake_room(const room_spec *rs, const char *name, baked *b)
{
    char in[512], out[512];
    snprintf(in, sizeof in, "%s/%s.gltf", tmpdir, name);
    snprintf(out, sizeof out, "%s/%s.lbk", tmpdir, name);
    write_room(in, rs);
    tb_job o;
    test_options(&o, in, out);
    o.d.texel_density = (float)(ROOM_DENSITY / rs->scale);
    o.d.glg_spacing = (float)(ROOM_SPACING * rs->scale);
    bake_ok(&o, b);
    assert_true(b->has_lmap);
    assert_true(b->texel_count > 0);
}

/* ---- comparisons -------------------------------------------------------------------------- */

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Sorted luminances of the lit texels. */
static float *sorted_lums(const baked *b, size_t *n)
{
    float *v = malloc((b->texel_count ? b->texel_count : 1) * sizeof *v);
    assert_non_null(v);
    *n = 0;
    for (size_t t = 0; t < b->texel_count; t++) {
        float l = lum(b->ez[t]);
        if (l > 0) v[(*n)++] = l;
    }
    qsort(v, *n, sizeof *v, cmp_float);
    return v;
}

/* Relative RMS difference between the two bakes' distributions of texel irradiance (quantile
 * against quantile, normalised like the error estimate). The atlas packs charts in an order
 * that can change with scale or offset, so texel i of one bake need not be texel i of the
 * other; the distribution over the level's surfaces does not depend on that order. */
static double distribution_rel_rms(const baked *a, const baked *b)
{
    size_t na, nb;
    float *va = sorted_lums(a, &na), *vb = sorted_lums(b, &nb);
    assert_true(na > 0 && nb > 0);
    size_t n = na < nb ? na : nb;
    double d2 = 0, v2 = 0;
    for (size_t i = 0; i < n; i++) {
        double q = (i + 0.5) / (double)n;
        double x = va[(size_t)(q * (double)na)], y = vb[(size_t)(q * (double)nb)];
        d2 += (x - y) * (x - y);
        v2 += 0.25 * (x + y) * (x + y);
    }
    free(va), free(vb);
    return sqrt(d2 / v2);
}

static double mean_texel_lum(const baked *b)
{
    double s = 0;
    size_t n = 0;
    for (size_t t = 0; t < b->texel_count; t++) {
        double l = lum(b->ez[t]);
        if (l > 0) s += l, n++;
    }
    return n ? s / (double)n : 0;
}

static double mean_probe_lum(const float (*dc)[3], size_t n)
{
    double s = 0;
    for (size_t i = 0; i < n; i++) s += lum(dc[i]);
    return n ? s / (double)n : 0;
}

/* The lighting of `b` equals that of `a` (same level at another scale, offset or with bad
 * triangles mixed in): mean texel irradiance and mean GLG probe radiance within the combined
 * estimated error, and the distribution of texel irradiance within twice that. Returns the
 * relative difference of the texel means. */
static double compare_lighting(const baked *a, const baked *b, const char *what, int probes_may_move)
{
    double tol = hypot(a->est, b->est);
    double ma = mean_texel_lum(a), mb = mean_texel_lum(b);
    double dm = fabs(mb - ma) / ma, dd = distribution_rel_rms(a, b), dp = 0;
    assert_true(ma > 0);
    assert_int_equal(a->has_glg, b->has_glg);
    if (!probes_may_move) assert_int_equal(a->glg_count, b->glg_count);
    if (a->has_glg && a->glg_count == b->glg_count) {
        double pa = mean_probe_lum(a->glg_dc, a->glg_count), pb = mean_probe_lum(b->glg_dc, b->glg_count);
        dp = fabs(pb - pa) / pa;
    }
    print_message("  %-18s texels %zu/%zu: mean %+.2f%%, distribution %.2f%%; GLG %zu probes: mean %+.2f%%; "
                  "est. %.2f%% / %.2f%%\n",
                  what, a->texel_count, b->texel_count, 100 * (mb / ma - 1), 100 * dd, b->glg_count, 100 * dp,
                  100 * a->est, 100 * b->est);
    assert_true(dm <= tol);
    assert_true(dd <= 2 * tol);
    assert_true(dp <= tol);
    return dm;
}

/* ---- baseline (baked once, shared by the comparison tests) -------------------------------- */

static baked base_room;
static int base_ready;

static const baked *base(void)
{
    if (!base_ready) {
        room_spec rs = {1, {0, 0, 0}, 0, 0, 0};
        bake_room(&rs, "base", &base_room);
        base_ready = 1;
        /* the room's lighting is non-trivial: a panel, a block, a GLG */
        assert_true(base_room.has_glg);
        assert_true(base_room.glg_count >= 4);
        assert_true(base_room.est > 0 && base_room.est < 0.3);
    }
    return &base_room;
}

/* ---- 1. light intensity 1e-6 … 1e6 ------------------------------------------------------- */

/* Each decoded physical channel equals k × the unit bake's decoded physical value, within the
 * relative rounding of both (uf10: 2^-6 each, 2^-5 together) plus, absolutely, `floor` (half the
 * smallest step of each file, times its scale; for RGB9E5 also the shared-exponent step of the
 * probe's largest channel). There is no saturation and no flush to zero: each section's scale
 * (spec §5.7) puts its largest value at 2^13..2^14 stored. */
static void assert_scaled_channel(double unit, double k, double got, double floor)
{
    double want = k * unit;
    double tol = 0x1p-5 * want + floor;
    if (fabs(got - want) > tol) print_message("channel: unit %g × %g = %g, got %g (tol %g)\n", unit, k, want, got, tol);
    assert_true(fabs(got - want) <= tol);
}

static double log2_of(float scale) { return log2((double)scale); }

static void test_intensity_extremes(void **state)
{
    (void)state;
    room_spec rs = {1, {0, 0, 0}, 1.0f, 0, 0};
    baked unit;
    bake_room(&rs, "light1", &unit);
    double m1 = mean_texel_lum(&unit);
    assert_true(m1 > 0.01 && m1 < 10); /* 1 cd at ~1 m */
    static const double ks[] = {1e-6, 1e-4, 1e4, 1e6};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; i++) {
        baked b;
        rs.light_cd = (float)ks[i];
        char name[32];
        snprintf(name, sizeof name, "light%zu", i);
        bake_room(&rs, name, &b);
        assert_int_equal(b.texel_count, unit.texel_count);
        assert_int_equal(b.glg_count, unit.glg_count);
        assert_int_equal(b.passes, unit.passes);
        /* the estimate is scale-free */
        assert_float_equal(b.est, unit.est, 1e-3 * unit.est + 1e-6);
        /* the scales follow k: 2^k apart up to one octave (k is not a power of two) */
        assert_true(fabs(log2_of(b.lmap_scale) - log2_of(unit.lmap_scale) - log2(ks[i])) <= 1.0);
        assert_true(fabs(log2_of(b.glg_scale) - log2_of(unit.glg_scale) - log2(ks[i])) <= 1.0);
        size_t zero = 0, top = 0;
        float peak = 0;
        const double tfloor = 0x1p-20 * (b.lmap_scale + ks[i] * unit.lmap_scale);
        for (size_t t = 0; t < b.texel_count; t++)
            for (int c = 0; c < 3; c++) {
                assert_scaled_channel(unit.ez[t][c], ks[i], b.ez[t][c], tfloor);
                zero += b.ez[t][c] == 0 && unit.ez[t][c] > 0;
                top += b.ez[t][c] >= (c == 2 ? LBK_UF10_MAX : LBK_UF11_MAX) * b.lmap_scale;
                if (b.ez[t][c] / b.lmap_scale > peak) peak = b.ez[t][c] / b.lmap_scale;
            }
        for (size_t p = 0; p < b.glg_count; p++) {
            double mx = fmax(unit.glg_dc[p][0], fmax(unit.glg_dc[p][1], unit.glg_dc[p][2]));
            const double pfloor = 0x1p-9 * ks[i] * mx + 0x1p-25 * (b.glg_scale + ks[i] * unit.glg_scale);
            for (int c = 0; c < 3; c++) assert_scaled_channel(unit.glg_dc[p][c], ks[i], b.glg_dc[p][c], pfloor);
        }
        /* the whole chain is linear: mean ratio = k */
        double ratio = mean_texel_lum(&b) / m1;
        print_message("  intensity %g: mean ratio %.6g (k = %g), LMAP scale 2^%.0f, GLG scale 2^%.0f, largest stored "
                      "texel %g, %zu saturated and %zu flushed channels of %zu\n",
                      ks[i], ratio, ks[i], log2_of(b.lmap_scale), log2_of(b.glg_scale), (double)peak, top, zero,
                      3 * b.texel_count);
        assert_float_equal(ratio / ks[i], 1, 0.01);
        assert_true(peak >= 0x1p13f && peak < 0x1p14f * (1 + 0x1p-6f)); /* the scale rule */
        assert_int_equal(top, 0);
        assert_int_equal(zero, 0);
        assert_int_equal(b.sum.transport.texel_channels_saturated, 0);
        assert_int_equal(b.sum.transport.texel_channels_flushed, 0);
        baked_free(&b);
    }
    baked_free(&unit);
}

/* ---- 2. scene scale 1 mm … 10 km --------------------------------------------------------- */

static void test_scale_extremes(void **state)
{
    (void)state;
    const baked *ref = base();
    static const double scales[] = {1e-3, 1e4};
    for (size_t i = 0; i < 2; i++) {
        room_spec rs = {scales[i], {0, 0, 0}, 0, 0, 0};
        baked b;
        bake_room(&rs, i ? "scale10km" : "scale1mm", &b);
        compare_lighting(ref, &b, i ? "10 km" : "1 mm", 0);
        /* GLG probes sit at the scaled positions */
        for (size_t p = 0; p < b.glg_count; p++)
            for (int c = 0; c < 3; c++)
                assert_float_equal(b.glg_pos[p][c] / scales[i], ref->glg_pos[p][c], 1e-3);
        baked_free(&b);
    }
}

/* ---- 3. far from the origin -------------------------------------------------------------- */

/* The moved level matches the centred one within the estimate, at 1e4 m and at 1e5 m. The baker
 * works in a level-centred frame, chosen by the importer in double precision before positions
 * become floats (bk_scene.origin); before it did, ray offsets of 8 ulps (6 cm at 1e5 m)
 * brightened this room by 20 %, and the walls, quantised to 7.8 mm floats, moved by up to 4 mm.
 * Now the level is the centred one to the bit in its frame: the same probes, stored at their
 * positions plus the offset (one float step there). */
static void test_far_from_origin(void **state)
{
    (void)state;
    const baked *ref = base();
    static const double offsets[] = {1e4, 1e5};
    for (int i = 0; i < 2; i++) {
        room_spec rs = {1, {offsets[i], 0, -offsets[i]}, 0, 0, 0};
        baked b;
        bake_room(&rs, i ? "far1e5" : "far1e4", &b);
        compare_lighting(ref, &b, i ? "1e5 m off origin" : "1e4 m off origin", 0);
        double step = offsets[i] * 0x1p-23; /* one float ulp at that distance */
        for (size_t p = 0; p < b.glg_count; p++) {
            assert_float_equal(b.glg_pos[p][0] - offsets[i], ref->glg_pos[p][0], 2 * step + 1e-5);
            assert_float_equal(b.glg_pos[p][1], ref->glg_pos[p][1], 1e-5);
            assert_float_equal(b.glg_pos[p][2] + offsets[i], ref->glg_pos[p][2], 2 * step + 1e-5);
        }
        baked_free(&b);
    }
}

/* A 1 mm object (a pebble on the floor) in the room 1e5 m away, placed there by its node's
 * translation (a JSON double): floats are 7.8 mm apart at 1e5 m, so world-space float positions
 * collapse every triangle of it to a point (before the importer re-centred the level in double
 * precision, the pebble came out degenerate and was dropped). It bakes as it does at the origin:
 * the same texels, the pebble's own texels lit alike within the estimate, the room's lighting
 * unchanged. */
static void test_tiny_object_far(void **state)
{
    (void)state;
    room_spec near_rs = {1, {0, 0, 0}, 0, 0, 1}, far_rs = {1, {1e5, 0, -1e5}, 0, 0, 1};
    baked a, b;
    bake_room(&near_rs, "pebble_near", &a);
    bake_room(&far_rs, "pebble_far", &b);
    compare_lighting(&a, &b, "1 mm at 1e5 m", 0);
    print_message("  objects %llu / %llu, texels %zu / %zu\n", (unsigned long long)a.sum.counts.objects,
                  (unsigned long long)b.sum.counts.objects, a.texel_count, b.texel_count);
    assert_true(a.sum.counts.objects == 4 && b.sum.counts.objects == 4); /* room, block, pebble, panel */
    assert_int_equal(a.texel_count, b.texel_count);
    baked_free(&a);
    baked_free(&b);
}

/* ---- 4. degenerate triangles and duplicate vertices -------------------------------------- */

static void test_degenerate_and_duplicates(void **state)
{
    (void)state;
    const baked *ref = base();
    room_spec rs = {1, {0, 0, 0}, 0, 1, 0};
    baked b;
    bake_room(&rs, "degenerate", &b);
    compare_lighting(ref, &b, "degenerate + dups", 0);
    /* and no texel budget blow-up from split charts */
    assert_true(b.texel_count <= 2 * ref->texel_count);
    baked_free(&b);
}

/* ---- 5. GLG on a perfect regular grid ----------------------------------------------------- */

static void test_regular_grid_glg(void **state)
{
    (void)state;
    /* a 4 m cube room lit by a point light at its centre, GLG spacing 1 m: cell centres form a
     * regular lattice (every cube's 8 corners cospherical), halved next to the walls */
    char in[512], out[512];
    path_in_tmp(in, sizeof in, "grid.gltf");
    path_in_tmp(out, sizeof out, "grid.lbk");
    gw_scene *sc = gw_create();
    float grey[3] = {0.5f, 0.5f, 0.5f}, white[3] = {1, 1, 1};
    int wall = gw_material(sc, grey, NULL, 0, 0);
    gw_geom room = {0};
    float mn[3] = {0, 0, 0}, mx[3] = {4, 4, 4};
    gw_geom_box(&room, mn, mx, 2, 1);
    gw_mesh(sc, "room", &room, wall, 1, NULL, NULL);
    double lp[3] = {2, 2, 2};
    gw_point_light(sc, white, 10, lp);
    assert_int_equal(gw_write(sc, in), 0);
    gw_geom_free(&room);
    gw_free(sc);

    tb_job o;
    test_options(&o, in, out);
    o.d.texel_density = 2;
    o.d.glg_spacing = 1;
    baked b;
    bake_ok(&o, &b);
    assert_true(b.has_glg);
    /* 64 cells of 1 m; the 56 touching a wall are split into 8: 8 + 56·8 probes on two
     * nested lattices, all kept (the nearest wall is 0.25 m away, clearance 0.125 m) */
    assert_int_equal(b.glg_count, 8 + 56 * 8);
    /* the tetrahedra tile the probes' box [0.25, 3.75]³ exactly: no gaps, no overlaps, no
     * flat tetrahedra (decode() asserted every orientation > 0) */
    print_message("  regular grid: %zu probes, %zu tetrahedra, volume %.6f (box 42.875)\n", b.glg_count, b.tet_count,
                  b.glg_volume);
    assert_float_equal(b.glg_volume, 3.5 * 3.5 * 3.5, 1e-3);
    /* the lighting is symmetric about the centre: mirror probes agree within the estimate */
    double mean = mean_probe_lum(b.glg_dc, b.glg_count), d2 = 0;
    size_t pairs = 0;
    for (size_t p = 0; p < b.glg_count; p++)
        for (size_t q = p + 1; q < b.glg_count; q++) {
            int mirror = 1;
            for (int c = 0; c < 3; c++) mirror &= fabsf(b.glg_pos[p][c] + b.glg_pos[q][c] - 4) < 1e-4f;
            if (!mirror) continue;
            double d = lum(b.glg_dc[p]) - lum(b.glg_dc[q]);
            d2 += d * d, pairs++;
        }
    assert_int_equal(pairs, b.glg_count / 2);
    double rms = sqrt(d2 / (double)pairs) / mean;
    print_message("  mirror-pair RMS difference %.2f%% (est %.2f%%)\n", 100 * rms, 100 * b.est);
    assert_true(rms <= 2 * M_SQRT2 * b.est + 0.01);
    baked_free(&b);
}

/* ---- 6. all probes on one plane ---------------------------------------------------------- */

static void test_flat_level_has_no_glg(void **state)
{
    (void)state;
    /* a single 4 m floor quad under a uniform sky given by the scene's lbk_sky: the free space
     * is flat, so no GLG (documented in PROBES.md) — not an error. An open plane under a
     * uniform sky L receives E = π·L everywhere. */
    char in[512], out[512];
    path_in_tmp(in, sizeof in, "floor.gltf");
    path_in_tmp(out, sizeof out, "floor.lbk");
    gw_scene *sc = gw_create();
    float grey[3] = {0.5f, 0.5f, 0.5f}, sky[3] = {0.5f, 0.75f, 1.0f};
    int m = gw_material(sc, grey, NULL, 0, 0);
    gw_geom g = {0};
    float p0[3] = {-2, 0, 2}, p1[3] = {2, 0, 2}, p2[3] = {2, 0, -2}, p3[3] = {-2, 0, -2}; /* faces +y */
    gw_geom_quad(&g, p0, p1, p2, p3, 2);
    gw_mesh(sc, "floor", &g, m, 1, NULL, NULL);
    gw_sky(sc, sky);
    assert_int_equal(gw_write(sc, in), 0);
    gw_geom_free(&g);
    gw_free(sc);

    tb_job o;
    test_options(&o, in, out);
    o.d.texel_density = 4;
    baked b;
    bake_ok(&o, &b);
    assert_false(b.has_glg);
    assert_int_equal(b.sum.counts.glg_probes, 0);
    assert_true(b.has_lmap);
    double want = M_PI * lum(sky), d2 = 0, sum = 0;
    size_t n = 0;
    for (size_t t = 0; t < b.texel_count; t++) {
        double l = lum(b.ez[t]);
        if (l <= 0) continue; /* atlas texels outside the chart */
        d2 += (l - want) * (l - want), sum += l, n++;
    }
    assert_true(n >= 16 * 16 * 8 / 10);
    double rms = sqrt(d2 / (double)n) / want, mean = sum / (double)n / want - 1;
    print_message("  floor under sky: %zu texels, mean %+.2f%%, RMS %.2f%% of pi*L (est %.2f%%)\n", n, 100 * mean,
                  100 * rms, 100 * b.est);
    /* the estimate within 2× of the true RMS error (plus the uf11/uf10 rounding, < 1%) */
    assert_true(fabs(mean) <= b.est);
    assert_true(rms <= 2 * b.est + 0.01);
    assert_true(rms >= 0.5 * b.est - 0.01);
    baked_free(&b);
}

/* ---- 7. stiff: albedo 0.99 furnace ------------------------------------------------------ */

static void test_albedo_099_furnace(void **state)
{
    (void)state;
    /* closed 1 m box, every face emits Le = 1 and reflects 99 %: E = π·Le/(1 − ρ) = 100π */
    char in[512], out[512];
    path_in_tmp(in, sizeof in, "furnace.gltf");
    path_in_tmp(out, sizeof out, "furnace.lbk");
    gw_scene *sc = gw_create();
    float alb[3] = {0.99f, 0.99f, 0.99f}, em[3] = {1, 1, 1};
    int m = gw_material(sc, alb, em, 0, 0);
    gw_geom g = {0};
    float mn[3] = {0, 0, 0}, mx[3] = {1, 1, 1};
    gw_geom_box(&g, mn, mx, 1, 1);
    /* emissive objects get no lightmap unless asked (classify.h rule 2) */
    gw_mesh(sc, "box", &g, m, 1, NULL, "lightmap");
    assert_int_equal(gw_write(sc, in), 0);
    gw_geom_free(&g);
    gw_free(sc);

    tb_job o;
    test_options(&o, in, out);
    o.d.max_samples = 512;
    o.d.texel_density = 8;
    o.d.glg_spacing = 0.5f;
    baked b;
    bake_ok(&o, &b);
    assert_true(b.has_glg);
    /* TRANSPORT.md: after P passes every texel is within P/(16·(2^P − 1)) of E; the AHD
     * encoding keeps the irradiance along the normal, rounded by uf11/uf10 (≤ 2^-6) */
    uint32_t P = b.passes;
    assert_true(P >= 3);
    double bound = P / (16.0 * (ldexp(1, (int)P) - 1)) + 0x1p-6 + 1e-4;
    double E = M_PI / (1 - 0.99), worst = 0, d2 = 0;
    size_t n = 0;
    for (size_t t = 0; t < b.texel_count; t++) {
        if (lum(b.ez[t]) <= 0) continue;
        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(b.ez[t][c] - E) / E);
        double l = lum(b.ez[t]) - E;
        d2 += l * l, n++;
    }
    assert_true(n >= 6 * 8 * 8 / 2);
    /* probes see Le/(1 − ρ) in every direction: L00 = √(4π)·L, exact but for RGB9E5 (2^-9) */
    double l00 = sqrt(4 * M_PI) / (1 - 0.99), pworst = 0;
    for (size_t p = 0; p < b.glg_count; p++)
        for (int c = 0; c < 3; c++) pworst = fmax(pworst, fabs(b.glg_dc[p][c] - l00) / l00);
    print_message("  furnace rho=0.99: %u passes, texels worst %.3f%% (bound %.3f%%), RMS %.3f%% (est %.3f%%); "
                  "%zu probes worst %.4f%%\n",
                  P, 100 * worst, 100 * bound, 100 * sqrt(d2 / (double)n) / E, 100 * b.est, b.glg_count, 100 * pworst);
    assert_true(worst <= bound);
    assert_true(pworst <= 0x1p-9 + 1e-4);
    baked_free(&b);
}

/* ---- 8. unusable input ------------------------------------------------------------------- */

static void assert_refused(const char *name, const gw_scene *sc, const char *needle)
{
    char in[512], out[512], err[512] = "";
    snprintf(in, sizeof in, "%s/%s.gltf", tmpdir, name);
    snprintf(out, sizeof out, "%s/%s.lbk", tmpdir, name);
    assert_int_equal(gw_write(sc, in), 0);
    tb_job o;
    test_options(&o, in, out);
    float sky[3] = {1, 1, 1};
    o.d.sky_override = 1;
    memcpy(o.d.sky, sky, sizeof sky);
    lbk_bake_report sum;
    int rc = run_bake(&o, &sum, err, sizeof err);
    print_message("  %s: exit %d: %s\n", name, rc, err);
    assert_int_equal(rc, LBK_ERR_BAD_INPUT);
    assert_non_null(strstr(err, needle));
    assert_int_not_equal(access(out, F_OK), 0);
}

static void test_unusable_input_is_refused(void **state)
{
    (void)state;
    float grey[3] = {0.5f, 0.5f, 0.5f};
    /* every triangle has zero area: nothing to light */
    gw_scene *sc = gw_create();
    int m = gw_material(sc, grey, NULL, 0, 0);
    gw_geom g = {0};
    uint32_t a = gw_geom_vertex(&g, 0, 0, 0), b = gw_geom_vertex(&g, 1, 0, 0), c = gw_geom_vertex(&g, 2, 0, 0);
    uint32_t d = gw_geom_vertex(&g, 0, 0, 0);
    gw_geom_tri(&g, a, b, c); /* collinear */
    gw_geom_tri(&g, a, a, b); /* repeated index */
    gw_geom_tri(&g, a, d, a); /* coincident vertices */
    gw_mesh(sc, "flat", &g, m, 1, NULL, NULL);
    gw_geom_free(&g);
    assert_refused("degenerate_only", sc, "triangle");
    gw_free(sc);

    /* NaN positions: the importer names the accessor */
    sc = gw_create();
    m = gw_material(sc, grey, NULL, 0, 0);
    memset(&g, 0, sizeof g);
    float p0[3] = {0, 0, 0}, p1[3] = {1, 0, 0}, p2[3] = {1, 0, -1}, p3[3] = {0, 0, -1};
    gw_geom_quad(&g, p0, p1, p2, p3, 2);
    g.pos[4] = NAN;
    gw_mesh(sc, "nan", &g, m, 1, NULL, NULL);
    gw_geom_free(&g);
    assert_refused("nan_positions", sc, "NaN");
    gw_free(sc);
}

static int free_base(void **state)
{
    (void)state;
    baked_free(&base_room);
    base_ready = 0;
    return teardown(state);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_intensity_extremes),
        cmocka_unit_test(test_scale_extremes),
        cmocka_unit_test(test_far_from_origin),
        cmocka_unit_test(test_tiny_object_far),
        cmocka_unit_test(test_degenerate_and_duplicates),
        cmocka_unit_test(test_regular_grid_glg),
        cmocka_unit_test(test_flat_level_has_no_glg),
        cmocka_unit_test(test_albedo_099_furnace),
        cmocka_unit_test(test_unusable_input_is_refused),
    };
    return cmocka_run_group_tests(tests, setup, free_base);
}
