/* The viewer's JavaScript reader of the container (viewer/lbk_reader.js, written from
 * spec/container.md alone) against liblbk: both decode the same files to the same text lines
 * (viewer/test/dump.js writes the reader's; this file writes liblbk's), floats as the hex of their
 * binary32 bits, and the lines must be identical — bit-exact texels (the AHD linear form of every
 * texel × scale), GLG/LLG probes (unpacked SH9 × scale), OCTP probes (irradiance, depth moments),
 * positions, objects, provenance and report. The files: the two real bakes of the fuzz corpus
 * (the shared cornell box and the light-set/door scene) and the containers with every section
 * type, raw and zstd, the cornell bake with its error map (TERR), and the cornell bake converted to BC6H + BC5/BC4 pages (the JS BC decoders
 * against libformat/src/bc.c) and to ASTC (which the JS reader declines: no decoder). The JS
 * reader must also reject a file with one flipped bit.
 * Needs node (Debian `nodejs`); without it the cases are SKIPPED. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/error_map.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/octa.h"
#include "lbk/report.h"
#include "lbk/sh.h"

#define OUT_DIR "build/tests/view_reader"

static const char *files[] = {"bake_cornell.lbk", "bake_sets.lbk", "every_raw.lbk", "every_zstd.lbk",
                              "dls.lbk",          "lmuv_raw.lbk",  "objects_zstd.lbk", "lmap_block.lbk",
                              "octp_volume.lbk", "bake_cornell_terr.lbk"};

/* The shared cornell bake converted by `lbk convert` ($LBK, else build/lbk-asan): console-current
 * gives BC6H + BC5/BC4 pages (decoded by both, bit-exact), handheld ASTC (the JS reader says it
 * cannot decode them). Made in OUT_DIR by the first test. */
static const char *converted[][2] = {{"cornell_bc.lbk", "console-current"}, {"cornell_astc.lbk", "handheld"}};

static int have_node(void) { return system("command -v node >/dev/null 2>&1") == 0; }

static void convert_corpus(void)
{
    const char *lbk = getenv("LBK") ? getenv("LBK") : "build/lbk-asan";
    for (size_t i = 0; i < sizeof converted / sizeof converted[0]; i++) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "%s convert tests/fuzz/corpus/bake_cornell.lbk -o " OUT_DIR "/%s --profile %s >/dev/null",
                 lbk, converted[i][0], converted[i][1]);
        assert_int_equal(system(cmd), 0);
    }
}

static void fx(FILE *f, float x)
{
    uint32_t u;
    memcpy(&u, &x, 4);
    fprintf(f, " %08x", (unsigned)u);
}
static void fxs(FILE *f, const float *x, size_t n)
{
    for (size_t i = 0; i < n; i++) fx(f, x[i]);
}
static void dx(FILE *f, double x)
{
    uint64_t u;
    memcpy(&u, &x, 8);
    fprintf(f, " %016llx", (unsigned long long)u);
}
static void hexs(FILE *f, const void *p, size_t n)
{
    fputc(' ', f);
    for (size_t i = 0; i < n; i++) fprintf(f, "%02x", ((const uint8_t *)p)[i]);
}

static int section(lbk_reader *r, uint32_t type, const void **data, size_t *size)
{
    return lbk_reader_section_by_type(r, type, data, size) == LBK_OK;
}

static void dump_head(FILE *f, lbk_reader *r)
{
    const lbk_header_info *h = lbk_reader_header(r);
    fprintf(f, "FILE %u.%u ", (unsigned)h->version_major, (unsigned)h->version_minor);
    for (uint32_t i = 0; i < lbk_reader_section_count(r); i++) {
        lbk_section_info s;
        assert_int_equal(lbk_reader_section_get(r, i, &s), LBK_OK);
        char cc[5] = {(char)(s.type & 255), (char)(s.type >> 8 & 255), (char)(s.type >> 16 & 255), (char)(s.type >> 24), 0};
        for (int k = 3; k > 0 && cc[k] == ' '; k--) cc[k] = 0;
        fprintf(f, "%s%s", i ? "," : "", cc);
    }
    fputc('\n', f);
}

static void dump_meta_report_objects(FILE *f, lbk_reader *r)
{
    const void *d;
    size_t n;
    if (section(r, LBK_SECTION_META, &d, &n)) {
        lbk_meta_view m;
        assert_int_equal(lbk_meta_open(d, n, &m), LBK_OK);
        lbk_string k, v;
        for (uint32_t i = 0; lbk_meta_entry_get(&m, i, &k, &v) == LBK_OK; i++) {
            fputs("META", f), hexs(f, k.data, k.size), hexs(f, v.data, v.size), fputc('\n', f);
        }
    }
    if (section(r, LBK_SECTION_REPT, &d, &n)) {
        lbk_report_view v;
        assert_int_equal(lbk_report_open(d, n, &v), LBK_OK);
        fprintf(f, "REPT %s %u %u", lbk_bake_status_name(v.header.status), (unsigned)v.header.record_count,
                (unsigned)v.header.max_samples_per_texel);
        dx(f, v.header.time_limit_seconds), fx(f, v.header.target_rel_rmse), fputc('\n', f);
        for (uint32_t i = 0; i < v.header.record_count; i++) {
            lbk_report_record rec;
            assert_int_equal(lbk_report_record_get(&v, i, &rec), LBK_OK);
            fputs("R", f), dx(f, rec.elapsed_seconds);
            fprintf(f, " %llu %u %u", (unsigned long long)rec.rays_traced, (unsigned)rec.samples_per_texel,
                    (unsigned)rec.bounces);
            fx(f, rec.texel_rel_rmse), fx(f, rec.probe_rel_rmse), fputc('\n', f);
        }
    }
    if (section(r, LBK_SECTION_OBJS, &d, &n)) {
        lbk_objects_view v;
        assert_int_equal(lbk_objects_open(d, n, &v), LBK_OK);
        for (uint32_t i = 0; i < v.count; i++) {
            lbk_object o;
            assert_int_equal(lbk_objects_get(&v, i, &o), LBK_OK);
            fprintf(f, "OBJ %u", (unsigned)i), hexs(f, o.name.data, o.name.size);
            fprintf(f, " %016llx %s %u %u %u %u %u\n", (unsigned long long)o.geometry_hash,
                    lbk_representation_name(o.representation), (unsigned)o.index, (unsigned)o.rect_x,
                    (unsigned)o.rect_y, (unsigned)o.rect_w, (unsigned)o.rect_h);
        }
    }
}

static void dump_lightmap(FILE *f, lbk_reader *r)
{
    const void *d;
    size_t n;
    if (!section(r, LBK_SECTION_LMAP, &d, &n)) return;
    lbk_lmap_view v;
    assert_int_equal(lbk_lmap_open(d, n, &v), LBK_OK);
    fputs("LMAP", f), fx(f, v.scale), fprintf(f, " %u %llu\n", (unsigned)v.page_count, (unsigned long long)v.texel_count);
    for (uint32_t i = 0; i < v.page_count; i++) {
        lbk_lmap_planes pl;
        assert_int_equal(lbk_lmap_planes_get(&v, i, &pl), LBK_OK);
        fprintf(f, "PAGE %u %u %u %u %u %llu\n", (unsigned)i, (unsigned)pl.width, (unsigned)pl.height,
                (unsigned)pl.format[0], (unsigned)pl.format[1], (unsigned long long)pl.first_texel);
        if (pl.format[0] == LBK_LMAP_ASTC4X4_HDR || pl.format[1] == LBK_LMAP_ASTC4X4_LDR) {
            fputs("ASTC\n", f); /* the JS reader has no ASTC decoder: the page says so */
            continue;
        }
        if (pl.format[0] || pl.format[1]) { /* BC6H, BC5 + BC4: lbk_lmap_planes_texel_unpack */
            for (uint32_t y = 0; y < pl.height; y++)
                for (uint32_t x = 0; x < pl.width; x++) {
                    lbk_ahd_texel_f tf;
                    lbk_ahd_linear lin;
                    assert_int_equal(lbk_lmap_planes_texel_unpack(&pl, x, y, &tf), LBK_OK);
                    lbk_ahd_texel_f_to_linear(&tf, &lin);
                    fputs("T", f);
                    for (int c = 0; c < 3; c++)
                        for (int k = 0; k < 4; k++) fx(f, lin.c[c][k] * v.scale);
                    fputc('\n', f);
                }
            continue;
        }
        lbk_lmap_page pg;
        assert_int_equal(lbk_lmap_page_get(&v, i, &pg), LBK_OK);
        for (uint32_t y = 0; y < pg.height; y++)
            for (uint32_t x = 0; x < pg.width; x++) {
                lbk_ahd_texel t;
                lbk_ahd_linear lin;
                assert_int_equal(lbk_lmap_page_texel_get(&pg, x, y, &t), LBK_OK);
                lbk_ahd_to_linear(&t, &lin);
                fputs("T", f);
                for (int c = 0; c < 3; c++)
                    for (int k = 0; k < 4; k++) fx(f, lin.c[c][k] * v.scale);
                fputc('\n', f);
            }
    }
}

/* TERR (§18): the codes as stored, 4096 texels a line */
static void dump_error_map(FILE *f, lbk_reader *r)
{
    const void *d;
    size_t n;
    if (!section(r, LBK_SECTION_TERR, &d, &n)) return;
    lbk_terr_view v;
    assert_int_equal(lbk_terr_open(d, n, &v), LBK_OK);
    fprintf(f, "TERR %llu %d\n", (unsigned long long)v.texel_count, (v.flags & LBK_TERR_DENOISED) ? 1 : 0);
    for (uint64_t o = 0; o < v.texel_count; o += 4096) {
        fputs("E", f);
        hexs(f, v.codes + o, (size_t)(v.texel_count - o < 4096 ? v.texel_count - o : 4096));
        fputc('\n', f);
    }
}

static void sh_line(FILE *f, const lbk_sh9_rgb *sh)
{
    for (int c = 0; c < 3; c++) fxs(f, sh->c[c], LBK_SH9_COUNT);
}

static void dump_probes(FILE *f, lbk_reader *r)
{
    const void *d;
    size_t n;
    if (section(r, LBK_SECTION_GLG, &d, &n)) {
        lbk_glg_view v;
        assert_int_equal(lbk_glg_open(d, n, &v), LBK_OK);
        fprintf(f, "GLG %u %u", (unsigned)v.probe_count, (unsigned)v.tetra_count), fx(f, v.scale), fputc('\n', f);
        for (uint32_t i = 0; i < v.probe_count; i++) {
            float pos[3];
            lbk_sh9_rgb sh;
            assert_int_equal(lbk_glg_probe_get(&v, i, pos, &sh), LBK_OK);
            fputs("G", f), fxs(f, pos, 3), sh_line(f, &sh), fputc('\n', f);
        }
        for (uint32_t t = 0; t < v.tetra_count; t++) {
            const uint8_t *q = v.mesh.tetras + 16 * (size_t)t, *vis = v.visibility + 4 * (size_t)t;
            fputs("GT", f);
            for (int k = 0; k < 4; k++)
                fprintf(f, " %u", (unsigned)(q[4 * k] | q[4 * k + 1] << 8 | q[4 * k + 2] << 16 | (uint32_t)q[4 * k + 3] << 24));
            fprintf(f, " %u %u %u %u\n", vis[0], vis[1], vis[2], vis[3]);
        }
    }
    if (section(r, LBK_SECTION_LLG, &d, &n)) {
        lbk_llg_view v;
        assert_int_equal(lbk_llg_open(d, n, &v), LBK_OK);
        fprintf(f, "LLG %u", (unsigned)v.grid_count), fx(f, v.scale), fputc('\n', f);
        for (uint32_t g = 0; g < v.grid_count; g++) {
            lbk_llg_grid gr;
            assert_int_equal(lbk_llg_grid_get(&v, g, &gr), LBK_OK);
            fprintf(f, "GRID %u", (unsigned)g), fxs(f, gr.centre, 3), fxs(f, &gr.axes[0][0], 9), fxs(f, gr.half_extents, 3);
            fprintf(f, " %u %u %u %u\n", (unsigned)gr.dims[0], (unsigned)gr.dims[1], (unsigned)gr.dims[2],
                    (unsigned)gr.vertex_count);
            const uint64_t np = (uint64_t)gr.dims[0] * gr.dims[1] * gr.dims[2];
            for (uint64_t p = 0; p < np; p++) {
                lbk_sh9_rgb stored, sh;
                lbk_sh9_unpack(v.probes + LBK_SH9_PACKED_SIZE * (gr.probe_offset + p), &stored);
                memset(&sh, 0, sizeof sh);
                lbk_sh9_add_scaled(&sh, &stored, v.scale);
                fputs("L", f), sh_line(f, &sh), fputc('\n', f);
            }
            fputs("V", f), hexs(f, v.vertices + 4 * gr.vertex_offset, 4 * (size_t)gr.vertex_count), fputc('\n', f);
        }
    }
    if (section(r, LBK_SECTION_OCTP, &d, &n)) {
        lbk_octp_view v;
        assert_int_equal(lbk_octp_open(d, n, &v), LBK_OK);
        fprintf(f, "OCTP %u", (unsigned)v.probe_count), fx(f, v.scale), fputc('\n', f);
        for (uint32_t l = 0; l < v.level_count; l++) {
            const lbk_octp_level *lv = &v.levels[l];
            fputs("OL", f), fxs(f, lv->origin, 3), fx(f, lv->spacing);
            fprintf(f, " %u %u %u %u", (unsigned)lv->dims[0], (unsigned)lv->dims[1], (unsigned)lv->dims[2], (unsigned)lv->first_probe);
            fx(f, lv->miss_distance), fputc('\n', f);
        }
        for (uint32_t i = 0; i < v.probe_count; i++) {
            lbk_octp_probe_desc p;
            assert_int_equal(lbk_octp_probe_get(&v, i, &p), LBK_OK);
            fputs("O", f), fxs(f, p.position, 3), fxs(f, &p.irradiance[0][0], 48), fxs(f, &p.depth[0][0], 288);
            fputc('\n', f);
            lbk_octp_probe_info pi;
            if (v.level_count && lbk_octp_probe_info_get(&v, i, &pi) == LBK_OK) {
                fputs("OI", f), fxs(f, pi.offset, 3);
                fprintf(f, " %u %u", (unsigned)pi.state, (unsigned)pi.rays);
                fx(f, pi.backface), fx(f, pi.nearest), fputc('\n', f);
            }
        }
    }
}

static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    if (b && fread(b, 1, (size_t)n, f) != (size_t)n) n = 0;
    fclose(f);
    if (b) b[n] = 0;
    *size = (size_t)n;
    return b;
}

/* Index of the first differing line, or -1 when the texts are equal. */
static long first_difference(const char *a, const char *b, const char **where)
{
    long line = 0;
    const char *start = a;
    for (; *a && *a == *b; a++, b++)
        if (*a == '\n') line++, start = a + 1;
    *where = start;
    return *a == *b ? -1 : line;
}

static void test_js_reader_matches_liblbk(void **state)
{
    (void)state;
    if (!have_node()) skip();
    mkdir("build/tests", 0755);
    mkdir(OUT_DIR, 0755);
    convert_corpus();
    long texel_lines = 0, probe_lines = 0, astc_pages = 0, error_codes = 0;
    const size_t nf = sizeof files / sizeof files[0], nc = sizeof converted / sizeof converted[0];
    for (size_t i = 0; i < nf + nc; i++) {
        char in[256], c_out[256], js_out[256], cmd[1024];
        const char *name = i < nf ? files[i] : converted[i - nf][0];
        snprintf(in, sizeof in, i < nf ? "tests/fuzz/corpus/%s" : OUT_DIR "/%s", name);
        snprintf(c_out, sizeof c_out, OUT_DIR "/%s.c.txt", name);
        snprintf(js_out, sizeof js_out, OUT_DIR "/%s.js.txt", name);
        lbk_reader *r;
        assert_int_equal(lbk_reader_open_file(in, NULL, &r), LBK_OK);
        FILE *f = fopen(c_out, "w");
        assert_non_null(f);
        dump_head(f, r);
        dump_meta_report_objects(f, r);
        dump_lightmap(f, r);
        dump_error_map(f, r);
        dump_probes(f, r);
        fclose(f);
        lbk_reader_close(r);
        snprintf(cmd, sizeof cmd, "node viewer/test/dump.js '%s' '%s'", in, js_out);
        assert_int_equal(system(cmd), 0);
        size_t na, nb;
        char *a = slurp(c_out, &na), *b = slurp(js_out, &nb);
        assert_non_null(a);
        assert_non_null(b);
        const char *where;
        const long line = first_difference(a, b, &where);
        if (line >= 0) print_error("%s: line %ld differs (liblbk: %.200s)\n", name, line + 1, where);
        assert_int_equal(line, -1);
        long block_texels = 0;
        for (const char *p = a; (p = strchr(p, '\n')) != NULL; p++) {
            if (p[1] == 'T' && p[2] == ' ') texel_lines++, block_texels++;
            if (!strncmp(p + 1, "ASTC\n", 5)) astc_pages++;
            if (!strncmp(p + 1, "TERR ", 5)) error_codes += atol(p + 6);
            if ((p[1] == 'G' || p[1] == 'L' || p[1] == 'O') && p[2] == ' ') probe_lines++;
        }
        /* the BC file's pages are all block pages: its texels are the BC decoders' */
        if (i == nf) {
            unsigned pages = 0, bc = 0;
            long page_texels = 0;
            for (const char *p = a; (p = strstr(p, "\nPAGE ")) != NULL; p++) {
                unsigned pi, w, h, f0, f1;
                assert_int_equal(sscanf(p + 6, "%u %u %u %u %u", &pi, &w, &h, &f0, &f1), 5);
                pages++, bc += f0 == LBK_LMAP_BC6H && f1 == LBK_LMAP_BC5_BC4;
                page_texels += (long)w * h;
            }
            print_message("%s: %u BC6H + BC5/BC4 pages, %ld texels decoded by both\n", name, pages, block_texels);
            assert_true(pages >= 1 && bc == pages && block_texels == page_texels && block_texels >= 384);
        }
        free(a);
        free(b);
    }
    print_message("JS reader = liblbk on %zu files: %ld texels, %ld error codes, %ld probes bit-exact; %ld ASTC pages "
                  "not decoded\n",
                  nf + nc, texel_lines, error_codes, probe_lines, astc_pages);
    assert_true(astc_pages >= 1);
    assert_true(error_codes >= 384); /* the cornell bake's TERR, every texel */
    /* the bakes hold real content: thousands of texels, probes of every kind */
    assert_true(texel_lines > 1000);
    assert_true(probe_lines > 50);
}

/* ---- DLS apply (§12.8): the page's dlsApply against lbk_dls_apply --------------------------- */

static void hex_line(FILE *f, const char *tag, const void *p, size_t n)
{
    fputs(tag, f), hexs(f, p, n), fputc('\n', f);
}

/* liblbk's outputs for the weights, in dump.js's --apply lines */
static void dump_apply(FILE *f, lbk_reader *r, const float *sw, size_t ns, const float *dw)
{
    const void *d, *dd = NULL, *lm = NULL, *gl = NULL, *ll = NULL;
    size_t n, ndd = 0, nlm = 0, ngl = 0, nll = 0;
    assert_true(section(r, LBK_SECTION_DLS, &d, &n));
    section(r, LBK_SECTION_DOOR, &dd, &ndd);
    section(r, LBK_SECTION_LMAP, &lm, &nlm);
    section(r, LBK_SECTION_GLG, &gl, &ngl);
    section(r, LBK_SECTION_LLG, &ll, &nll);
    lbk_dls_view *dls;
    lbk_door_view *doors = NULL;
    assert_int_equal(lbk_dls_open(d, n, NULL, &dls), LBK_OK);
    if (dd) assert_int_equal(lbk_door_open(dd, ndd, NULL, &doors), LBK_OK);
    lbk_dls_runtime_desc rd = LBK_DLS_RUNTIME_DESC_INIT;
    rd.dls = dls, rd.doors = doors;
    const uint64_t nt = lbk_dls_target_count(dls, 0), ng = lbk_dls_target_count(dls, 1), nl = lbk_dls_target_count(dls, 2);
    uint32_t *z = NULL, *oz = NULL;
    uint8_t *rgba = NULL, *orgba = NULL, *og = NULL, *ol = NULL;
    if (nt) {
        lbk_lmap_view v;
        assert_int_equal(lbk_lmap_open(lm, nlm, &v), LBK_OK);
        z = malloc(4 * nt), oz = malloc(4 * nt), rgba = malloc(4 * nt), orgba = malloc(4 * nt);
        for (uint64_t t = 0; t < nt; t++) {
            lbk_ahd_texel tx;
            assert_int_equal(lbk_lmap_texel_get(&v, t, &tx, NULL), LBK_OK);
            z[t] = tx.irradiance_z;
            memcpy(rgba + 4 * t, tx.rgba, 4);
        }
        rd.base_irradiance_z = z, rd.base_rgba = rgba, rd.out_irradiance_z = oz, rd.out_rgba = orgba;
    }
    if (ng) {
        lbk_glg_view v;
        assert_int_equal(lbk_glg_open(gl, ngl, &v), LBK_OK);
        rd.base_glg = v.probes, rd.out_glg = og = malloc(28 * ng);
    }
    if (nl) {
        lbk_llg_view v;
        assert_int_equal(lbk_llg_open(ll, nll, &v), LBK_OK);
        rd.base_llg = v.probes, rd.out_llg = ol = malloc(28 * nl);
    }
    lbk_dls_runtime *rt;
    assert_int_equal(lbk_dls_runtime_open(&rd, &rt), LBK_OK);
    assert_int_equal(lbk_dls_set_count(dls), ns);
    float w[64];
    assert_int_equal(lbk_dls_effective_weights(rt, sw, dw, w), LBK_OK);
    fputs("W", f), fxs(f, w, ns), fputc('\n', f);
    assert_int_equal(lbk_dls_apply(rt, sw, dw, NULL), LBK_OK);
    if (nt) {
        uint8_t *le = malloc(4 * nt);
        for (uint64_t t = 0; t < nt; t++)
            for (int k = 0; k < 4; k++) le[4 * t + k] = (uint8_t)(oz[t] >> (8 * k));
        hex_line(f, "AZ", le, 4 * nt), hex_line(f, "AR", orgba, 4 * nt);
        free(le);
    }
    if (ng) hex_line(f, "AG", og, 28 * ng);
    if (nl) hex_line(f, "AL", ol, 28 * nl);
    lbk_dls_runtime_close(rt);
    lbk_dls_close(dls);
    if (doors) lbk_door_close(doors);
    free(z), free(oz), free(rgba), free(orgba), free(og), free(ol);
}

/* The apply lines of both sides for the set weights and door openings; 0 when they are equal. */
static int compare_apply(const char *file, const float *sw, size_t ns, const float *dw, size_t nd)
{
    char in[256], c_out[256], js_out[256], cmd[2048], ws[512] = "", ds[256] = "";
    snprintf(in, sizeof in, "tests/fuzz/corpus/%s", file);
    snprintf(c_out, sizeof c_out, OUT_DIR "/%s.apply.c.txt", file);
    snprintf(js_out, sizeof js_out, OUT_DIR "/%s.apply.js.txt", file);
    for (size_t i = 0; i < ns; i++) snprintf(ws + strlen(ws), sizeof ws - strlen(ws), "%s%.9g", i ? "," : "", sw[i]);
    for (size_t i = 0; i < nd; i++) snprintf(ds + strlen(ds), sizeof ds - strlen(ds), "%s%.9g", i ? "," : "", dw[i]);
    lbk_reader *r;
    assert_int_equal(lbk_reader_open_file(in, NULL, &r), LBK_OK);
    FILE *f = fopen(c_out, "w");
    assert_non_null(f);
    dump_apply(f, r, sw, ns, nd ? dw : NULL);
    fclose(f);
    lbk_reader_close(r);
    snprintf(cmd, sizeof cmd, "node viewer/test/dump.js '%s' '%s' --apply '%s' '%s'", in, js_out, ws, ds);
    assert_int_equal(system(cmd), 0);
    size_t na, nb;
    char *a = slurp(c_out, &na), *b = slurp(js_out, &nb);
    assert_non_null(a);
    assert_non_null(b);
    /* the JS dump holds the full decode first: compare from its first apply line */
    const char *bw = strstr(b, "\nW ");
    assert_non_null(bw);
    const char *where;
    const long line = first_difference(a, bw + 1, &where);
    if (line >= 0) print_error("%s apply (%s | %s): line %ld differs (liblbk: %.120s)\n", file, ws, ds, line + 1, where);
    free(a), free(b);
    return line >= 0;
}

static void test_js_dls_apply_matches_liblbk(void **state)
{
    (void)state;
    if (!have_node()) skip();
    mkdir(OUT_DIR, 0755);
    /* bake_sets: lights A, B, door d1 (open/closed) and the combination d1+A */
    const float w0[5] = {1, 1, 0, 0, 0}, w1[5] = {0.25f, 0.7f, 0, 0, 0}, w2[5] = {0, 0, 0, 0, 0}, w3[5] = {1.5f, -0.5f, 0, 0, 0};
    const float d0[1] = {0.0f}, d1[1] = {0.3f}, d2[1] = {1.0f};
    assert_int_equal(compare_apply("bake_sets.lbk", w0, 5, d0, 1), 0);
    assert_int_equal(compare_apply("bake_sets.lbk", w1, 5, d1, 1), 0);
    size_t n1, n2;
    char *on = slurp(OUT_DIR "/bake_sets.lbk.apply.c.txt", &n1);
    assert_int_equal(compare_apply("bake_sets.lbk", w2, 5, d2, 1), 0);
    char *off = slurp(OUT_DIR "/bake_sets.lbk.apply.c.txt", &n2);
    assert_true(n1 == n2 && strcmp(on, off) != 0); /* the weights change the outputs */
    free(on), free(off);
    assert_int_equal(compare_apply("bake_sets.lbk", w3, 5, d1, 1), 0);
    /* dls.lbk (make_corpus): every cluster form */
    lbk_reader *r;
    const void *d;
    size_t n;
    assert_int_equal(lbk_reader_open_file("tests/fuzz/corpus/dls.lbk", NULL, &r), LBK_OK);
    assert_true(section(r, LBK_SECTION_DLS, &d, &n));
    lbk_dls_view *v;
    assert_int_equal(lbk_dls_open(d, n, NULL, &v), LBK_OK);
    const uint32_t ns = lbk_dls_set_count(v);
    uint32_t forms = 0;
    for (uint32_t c = 0; c < lbk_dls_cluster_count(v); c++) {
        lbk_dls_cluster_info ci;
        assert_int_equal(lbk_dls_cluster_get(v, c, &ci), LBK_OK);
        forms |= 1u << ci.form;
    }
    lbk_dls_close(v);
    lbk_reader_close(r);
    print_message("dls.lbk: %u sets, cluster forms mask 0x%x\n", (unsigned)ns, (unsigned)forms);
    assert_true(ns <= 64);
    float ws[64];
    for (uint32_t i = 0; i < ns; i++) ws[i] = (float)((i * 37) % 11) / 7.0f - 0.2f; /* some 0, some off the grid */
    const float dws[8] = {0.5f, 0.25f, 1, 0, 0.75f, 0.1f, 0.9f, 0.33f};
    assert_int_equal(compare_apply("dls.lbk", ws, ns, dws, 8), 0);
}

/* One flipped bit anywhere is detected (spec §4.2): the reader refuses the file. */
static void test_js_reader_rejects_a_flipped_bit(void **state)
{
    (void)state;
    if (!have_node()) skip();
    mkdir(OUT_DIR, 0755);
    size_t n;
    char *b = slurp("tests/fuzz/corpus/bake_cornell.lbk", &n);
    assert_non_null(b);
    const size_t at[] = {9, 70, n / 2, n - 1}; /* header, table, a section, the last byte */
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++) {
        b[at[i]] ^= 0x10;
        FILE *f = fopen(OUT_DIR "/flipped.lbk", "wb");
        assert_non_null(f);
        assert_int_equal(fwrite(b, 1, n, f), n);
        fclose(f);
        b[at[i]] ^= 0x10;
        int st = system("node viewer/test/dump.js " OUT_DIR "/flipped.lbk " OUT_DIR "/flipped.txt 2>/dev/null");
        assert_int_not_equal(st, 0);
    }
    free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_js_reader_matches_liblbk),
        cmocka_unit_test(test_js_reader_rejects_a_flipped_bit),
        cmocka_unit_test(test_js_dls_apply_matches_liblbk),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
