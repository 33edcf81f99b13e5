/* lbk export: EXR/PNG/CSV/JSON views of a bake (tools/convert/README.md "Export"). */
#define _XOPEN_SOURCE 700 /* nftw, for removing a folder this run created (tl_export) */
#include "tools/convert/export.h"

#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "tools/common/error_util.h"
#include "tools/common/file_util.h"
#include "tools/convert/lmap_layout.h"
#include "lbk/pixel.h"

void tl_export_object_stem(const char *name, uint32_t index, char *out, size_t size)
{
    char clean[65];
    size_t n = 0;
    for (const char *p = name; *p && n < 64; p++) {
        char c = *p;
        int ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
        clean[n++] = ok ? c : '_';
    }
    clean[n] = '\0';
    snprintf(out, size, "%03u_%s", index, clean);
}

/* Decoded planes of one page: ez (+Z irradiance), dom (irradiance at the highlight direction),
 * p0 (plane 0 decoded exactly × the LMAP scale: physical), p1 (plane 1 bytes / 255), 3/3/3/4 floats per texel. */
typedef struct page_images {
    uint32_t w, h;
    float *ez, *dom, *p1;
} page_images;

static int decode_page(const tl_bake *b, uint32_t p, page_images *im)
{
    lbk_lmap_planes pg;
    if (tl_bake_planes(b, p, &pg)) return -1;
    const size_t n = (size_t)pg.width * pg.height;
    im->w = pg.width;
    im->h = pg.height;
    im->ez = malloc(n * 3 * sizeof(float));
    im->dom = malloc(n * 3 * sizeof(float));
    im->p1 = malloc(n * 4 * sizeof(float));
    if (!im->ez || !im->dom || !im->p1) return -1;
    for (uint32_t y = 0; y < pg.height; y++)
        for (uint32_t x = 0; x < pg.width; x++) {
            const size_t i = (size_t)y * pg.width + x;
            lbk_ahd_texel_f t;
            lbk_ahd_linear lin;
            float d[3];
            tl_bake_texel_get(b, p, x, y, &t, &lin, d); /* any encoding (spec §9.2) */
            memcpy(im->ez + 3 * i, t.ez, sizeof t.ez);
            /* the irradiance at the stored highlight direction, decoded as lbk/ahd.h does */
            lbk_ahd_linear_eval(&lin, d, im->dom + 3 * i);
            /* physical values: stored × the section's scale (a power of two: exact) */
            for (int c = 0; c < 3; c++) im->ez[3 * i + (size_t)c] *= pg.scale, im->dom[3 * i + (size_t)c] *= pg.scale;
            memcpy(im->p1 + 4 * i, t.rgba, sizeof t.rgba);
        }
    return 0;
}

static void free_page(page_images *im)
{
    free(im->ez);
    free(im->dom);
    free(im->p1);
    memset(im, 0, sizeof *im);
}

static const char *const RGB[3] = {"R", "G", "B"};
static const char *const AHD[7] = {"plane0.R", "plane0.G", "plane0.B", "plane1.R", "plane1.G", "plane1.B", "plane1.A"};

static int write_page_exrs(const char *dir, uint32_t p, const page_images *im, tl_export_stats *st, char err[TL_ERR_LEN])
{
    char path[4096];
    tl_page_exr_path(path, sizeof path, dir, p, ".exr");
    if (tl_exr_write(path, (int)im->w, (int)im->h, 3, RGB, im->ez, err)) return -1;
    tl_page_exr_path(path, sizeof path, dir, p, ".dominant.exr");
    if (tl_exr_write(path, (int)im->w, (int)im->h, 3, RGB, im->dom, err)) return -1;
    const size_t n = (size_t)im->w * im->h;
    float *ahd = malloc(n * 7 * sizeof(float));
    if (!ahd) return tl_fail(err, -1, "out of memory");
    for (size_t i = 0; i < n; i++) {
        memcpy(ahd + 7 * i, im->ez + 3 * i, 3 * sizeof(float));
        memcpy(ahd + 7 * i + 3, im->p1 + 4 * i, 4 * sizeof(float));
    }
    tl_page_exr_path(path, sizeof path, dir, p, ".ahd.exr");
    int rc = tl_exr_write(path, (int)im->w, (int)im->h, 7, AHD, ahd, err);
    free(ahd);
    if (!rc) st->exr_files += 3;
    return rc;
}

static int write_png(const char *path, uint32_t w, uint32_t h, const float *rgb, float exposure, char err[TL_ERR_LEN])
{
    uint8_t *px = malloc((size_t)w * h * 3);
    if (!px) return tl_fail(err, -1, "out of memory");
    tl_tonemap(rgb, (size_t)w * h, 3, exposure, px);
    int rc = tl_png_write_rgb8(path, (int)w, (int)h, px, err);
    free(px);
    return rc;
}

/* The rectangle of an object cut out of its decoded page. */
static float *crop(const page_images *im, const lbk_object *o)
{
    float *out = malloc((size_t)o->rect_w * o->rect_h * 3 * sizeof(float));
    if (!out) return NULL;
    for (uint32_t y = 0; y < o->rect_h; y++)
        memcpy(out + (size_t)y * o->rect_w * 3, im->ez + ((size_t)(o->rect_y + y) * im->w + o->rect_x) * 3,
               (size_t)o->rect_w * 3 * sizeof(float));
    return out;
}

/* ---- probes -------------------------------------------------------------------------------- */

typedef struct probe_row {
    int grid;        /* -1: GLG */
    uint32_t index;
    float pos[3];
    lbk_sh9_rgb sh;
    float irr[TL_PROBE_NORMALS][3];
} probe_row;

static int gather_probes(const tl_bake *b, probe_row **rows, size_t *count)
{
    uint64_t n = (b->has_glg ? b->glg.probe_count : 0) + (b->has_llg ? b->llg.probe_count : 0);
    *rows = calloc((size_t)n + 1, sizeof **rows);
    *count = 0;
    if (!*rows) return -1;
    for (uint32_t i = 0; b->has_glg && i < b->glg.probe_count; i++) {
        probe_row *r = &(*rows)[(*count)++];
        r->grid = -1;
        r->index = i;
        lbk_glg_probe_get(&b->glg, i, r->pos, &r->sh);
        tl_probe_eval(&r->sh, r->irr);
    }
    for (uint32_t g = 0; b->has_llg && g < b->llg.grid_count; g++) {
        lbk_llg_grid grid;
        lbk_llg_grid_get(&b->llg, g, &grid);
        for (uint32_t k = 0; k < grid.dims[2]; k++)
            for (uint32_t j = 0; j < grid.dims[1]; j++)
                for (uint32_t i = 0; i < grid.dims[0]; i++) {
                    const uint32_t li = (k * grid.dims[1] + j) * grid.dims[0] + i;
                    probe_row *r = &(*rows)[(*count)++];
                    r->grid = (int)g;
                    r->index = li;
                    lbk_llg_probe_position(&grid, i, j, k, r->pos);
                    tl_probe_unpack(b->llg.probes + (grid.probe_offset + li) * LBK_SH9_PACKED_SIZE, b->llg.scale, &r->sh);
                    tl_probe_eval(&r->sh, r->irr);
                }
    }
    return 0;
}

static const char *const AXIS[TL_PROBE_NORMALS] = {"px", "nx", "py", "ny", "pz", "nz"};

static int write_probe_listings(const char *dir, const probe_row *rows, size_t n, tl_export_stats *st,
                                char err[TL_ERR_LEN])
{
    /* CSV: one line per probe; %.9g round-trips every float */
    size_t cap = 1024 + n * 1200, len = 0;
    char *csv = malloc(cap);
    if (!csv) return tl_fail(err, -1, "out of memory");
    len += (size_t)snprintf(csv + len, cap - len, "source,grid,index,x,y,z");
    for (int a = 0; a < TL_PROBE_NORMALS; a++)
        len += (size_t)snprintf(csv + len, cap - len, ",E_%s_r,E_%s_g,E_%s_b", AXIS[a], AXIS[a], AXIS[a]);
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++) len += (size_t)snprintf(csv + len, cap - len, ",sh_%c%d", "rgb"[c], k);
    len += (size_t)snprintf(csv + len, cap - len, "\n");
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "schema", "lbk-probes");
    cJSON_AddNumberToObject(root, "schema_version", 1);
    cJSON_AddStringToObject(root, "units", "irradiance in lm/m^2 (lux-like); sh = radiance SH9 in cd/m^2 (nits)");
    cJSON *arr = cJSON_AddArrayToObject(root, "probes");
    for (size_t i = 0; i < n; i++) {
        const probe_row *r = &rows[i];
        len += (size_t)snprintf(csv + len, cap - len, "%s,%d,%u,%.9g,%.9g,%.9g", r->grid < 0 ? "glg" : "llg", r->grid,
                                r->index, r->pos[0], r->pos[1], r->pos[2]);
        for (int a = 0; a < TL_PROBE_NORMALS; a++)
            for (int c = 0; c < 3; c++) len += (size_t)snprintf(csv + len, cap - len, ",%.9g", r->irr[a][c]);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) len += (size_t)snprintf(csv + len, cap - len, ",%.9g", r->sh.c[c][k]);
        len += (size_t)snprintf(csv + len, cap - len, "\n");
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "source", r->grid < 0 ? "glg" : "llg");
        cJSON_AddNumberToObject(o, "grid", r->grid);
        cJSON_AddNumberToObject(o, "index", r->index);
        cJSON_AddItemToObject(o, "position", cJSON_CreateFloatArray(r->pos, 3));
        cJSON *irr = cJSON_AddObjectToObject(o, "irradiance");
        for (int a = 0; a < TL_PROBE_NORMALS; a++) cJSON_AddItemToObject(irr, AXIS[a], cJSON_CreateFloatArray(r->irr[a], 3));
        cJSON *sh = cJSON_AddArrayToObject(o, "sh9");
        for (int c = 0; c < 3; c++) cJSON_AddItemToArray(sh, cJSON_CreateFloatArray(r->sh.c[c], 9));
        cJSON_AddItemToArray(arr, o);
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/probes.csv", dir);
    int rc = tl_write_text(path, csv, err);
    free(csv);
    char *json = rc ? NULL : cJSON_Print(root);
    cJSON_Delete(root);
    if (rc) return -1;
    if (!json) return tl_fail(err, -1, "out of memory");
    snprintf(path, sizeof path, "%s/probes.json", dir);
    rc = tl_write_text(path, json, err);
    free(json);
    if (!rc) st->text_files += 2;
    return rc;
}

static void plot_dot(uint8_t *img, int w, int h, int cx, int cy, int radius, const uint8_t c[3])
{
    for (int y = cy - radius; y <= cy + radius; y++)
        for (int x = cx - radius; x <= cx + radius; x++) {
            if (x < 0 || y < 0 || x >= w || y >= h || (x - cx) * (x - cx) + (y - cy) * (y - cy) > radius * radius) continue;
            memcpy(img + 3 * ((size_t)y * w + x), c, 3);
        }
}

static void plot_line(uint8_t *img, int w, int h, int x0, int y0, int x1, int y1, uint8_t grey)
{
    int steps = abs(x1 - x0) > abs(y1 - y0) ? abs(x1 - x0) : abs(y1 - y0);
    for (int s = 0; s <= steps; s++) {
        int x = steps ? x0 + (x1 - x0) * s / steps : x0, y = steps ? y0 + (y1 - y0) * s / steps : y0;
        if (x < 0 || y < 0 || x >= w || y >= h) continue;
        uint8_t *p = img + 3 * ((size_t)y * w + x);
        if (p[0] < grey) p[0] = p[1] = p[2] = grey;
    }
}

/* Top view of the GLG: looking down −Y (glTF is Y-up): image x = world x, image y = world z.
 * Tetra edges in grey, probes as dots coloured by the heat ramp of the luminance of their mean
 * irradiance over the six axis normals, normalised to the 99th percentile. */
static int write_glg_plot(const char *dir, const tl_bake *b, const probe_row *rows, size_t n, tl_export_stats *st,
                          char err[TL_ERR_LEN])
{
    if (!b->has_glg || b->glg.probe_count == 0) return 0;
    const int W = 512, H = 512, M = 16;
    float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++) {
        if (rows[i].grid >= 0) continue;
        const float q[2] = {rows[i].pos[0], rows[i].pos[2]};
        for (int a = 0; a < 2; a++) lo[a] = fminf(lo[a], q[a]), hi[a] = fmaxf(hi[a], q[a]);
    }
    float span = fmaxf(hi[0] - lo[0], hi[1] - lo[1]);
    if (!(span > 0)) span = 1;
    const float scale = (float)(W - 2 * M) / span;
#define PX(p) ((int)lroundf(M + ((p)[0] - lo[0]) * scale))
#define PY(p) ((int)lroundf(M + ((p)[2] - lo[1]) * scale))
    uint8_t *img = calloc((size_t)W * H * 3, 1);
    float *lum = malloc((n + 1) * 3 * sizeof(float));
    if (!img || !lum) {
        free(img), free(lum);
        return tl_fail(err, -1, "out of memory");
    }
    for (uint32_t t = 0; t < b->glg.tetra_count; t++) {
        uint32_t v[4];
        for (int k = 0; k < 4; k++) {
            const uint8_t *q = b->glg.mesh.tetras + ((size_t)t * 4 + k) * 4;
            v[k] = (uint32_t)q[0] | (uint32_t)q[1] << 8 | (uint32_t)q[2] << 16 | (uint32_t)q[3] << 24;
        }
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++) {
                if (v[i] >= b->glg.probe_count || v[j] >= b->glg.probe_count) continue; /* GLG rows come first */
                plot_line(img, W, H, PX(rows[v[i]].pos), PY(rows[v[i]].pos), PX(rows[v[j]].pos), PY(rows[v[j]].pos), 70);
            }
    }
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (rows[i].grid >= 0) continue;
        float mean[3] = {0, 0, 0};
        for (int a = 0; a < TL_PROBE_NORMALS; a++)
            for (int c = 0; c < 3; c++) mean[c] += rows[i].irr[a][c] / TL_PROBE_NORMALS;
        lum[3 * m] = lum[3 * m + 1] = lum[3 * m + 2] = tl_luminance(mean);
        m++;
    }
    const float exposure = tl_exposure_p99(lum, m, 3);
    for (size_t i = 0, k = 0; i < n; i++) {
        if (rows[i].grid >= 0) continue;
        uint8_t c[3];
        tl_heat_color(lum[3 * k++] * exposure * (5.0f / 6.0f), c); /* p99 → red; brighter → white */
        plot_dot(img, W, H, PX(rows[i].pos), PY(rows[i].pos), 4, c);
    }
#undef PX
#undef PY
    char path[4096];
    snprintf(path, sizeof path, "%s/glg_top.png", dir);
    int rc = tl_png_write_rgb8(path, W, H, img, err);
    free(img);
    free(lum);
    if (!rc) st->png_files++;
    return rc;
}

/* ---- the per-texel error map (TERR, spec/container.md §18) ---------------------------------- */

/* The colour scale of lbk view's error mode (viewer/viewer.js errColour): log10 of the relative
 * error from 0.1 % (0) to 100 % (1), dark blue, blue, green, yellow, red; grey: no estimate. */
static void error_colour(double rel, uint8_t out[3])
{
    static const float stops[5][3] = {{0.05f, 0.15f, 0.6f}, {0.0f, 0.55f, 0.9f}, {0.1f, 0.8f, 0.3f},
                                      {0.95f, 0.85f, 0.1f}, {0.85f, 0.1f, 0.1f}};
    if (rel < 0) {
        out[0] = out[1] = out[2] = 64;
        return;
    }
    double t = (log10(rel > 1e-12 ? rel : 1e-12) + 3.0) / 3.0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    const int i = t >= 1 ? 3 : (int)(t * 4);
    const double f = t * 4 - i;
    for (int c = 0; c < 3; c++) out[c] = (uint8_t)lrint(255.0 * ((1 - f) * stops[i][c] + f * stops[i + 1][c]));
}

/* Page p's error map: PAGE.error.exr (channel Y: the relative error, -1 where there is no
 * estimate) and PAGE.error.png (the colour scale above). */
static int write_error_map(const tl_bake *b, const tl_export_options *o, uint32_t p, tl_export_stats *st,
                           char err[TL_ERR_LEN])
{
    lbk_lmap_planes pg;
    tl_bake_planes(b, p, &pg);
    const size_t n = (size_t)pg.width * pg.height;
    float *rel = malloc(n * sizeof *rel + 1);
    uint8_t *rgb = malloc(3 * n + 1);
    if (!rel || !rgb) {
        free(rel), free(rgb);
        return tl_fail(err, -1, "out of memory");
    }
    for (size_t i = 0; i < n; i++) {
        const double e = lbk_terr_decode(b->terr.codes[pg.first_texel + i]);
        rel[i] = (float)e;
        error_colour(e, rgb + 3 * i);
    }
    static const char *const Y[1] = {"Y"};
    char path[4096];
    int rc = 0;
    if (o->exr_dir) {
        tl_page_exr_path(path, sizeof path, o->exr_dir, p, ".error.exr");
        rc = tl_exr_write(path, (int)pg.width, (int)pg.height, 1, Y, rel, err);
        if (!rc) st->exr_files++;
    }
    if (!rc && o->png_dir) {
        tl_page_exr_path(path, sizeof path, o->png_dir, p, ".error.png");
        rc = tl_png_write_rgb8(path, (int)pg.width, (int)pg.height, rgb, err);
        if (!rc) st->png_files++;
    }
    free(rel), free(rgb);
    return rc;
}

/* ---- driver -------------------------------------------------------------------------------- */

static int export_run(const tl_bake *b, const tl_export_options *o, tl_export_stats *st, char err[TL_ERR_LEN])
{
    const uint32_t np = b->has_lmap ? b->lmap.page_count : 0;
    /* one exposure for every preview so pages compare by eye: the p99 over all texels */
    st->exposure = 1.0f;
    if (o->png_dir && np) {
        uint64_t total = b->lmap.texel_count;
        float *all = malloc((size_t)total * 3 * sizeof(float) + 1);
        if (!all) return tl_fail(err, -1, "out of memory");
        uint64_t k = 0;
        for (uint32_t p = 0; p < np; p++) {
            lbk_lmap_planes pg;
            tl_bake_planes(b, p, &pg);
            for (uint32_t y = 0; y < pg.height; y++)
                for (uint32_t x = 0; x < pg.width; x++, k++) {
                    lbk_ahd_texel_f t;
                    tl_bake_texel_get(b, p, x, y, &t, NULL, NULL);
                    memcpy(all + 3 * k, t.ez, sizeof t.ez);
                }
        }
        for (uint64_t i = 0; i < 3 * total; i++) all[i] *= b->lmap.scale;
        st->exposure = tl_exposure_p99(all, (size_t)total, 3);
        free(all);
    }
    lbk_object *objs = NULL;
    uint32_t no = b->has_objs ? b->objs.count : 0;
    if (o->per_object && no) {
        objs = calloc(no, sizeof *objs);
        if (!objs) return tl_fail(err, -1, "out of memory");
        for (uint32_t i = 0; i < no; i++) lbk_objects_get(&b->objs, i, &objs[i]);
    }
    int rc = 0;
    for (uint32_t p = 0; p < np && !rc; p++) {
        page_images im;
        memset(&im, 0, sizeof im);
        if (decode_page(b, p, &im)) {
            free_page(&im);
            rc = tl_fail(err, -1, "out of memory");
            break;
        }
        if (o->exr_dir) rc = write_page_exrs(o->exr_dir, p, &im, st, err);
        if (!rc && b->has_terr) rc = write_error_map(b, o, p, st, err);
        if (!rc && o->png_dir) {
            char path[4096];
            tl_page_exr_path(path, sizeof path, o->png_dir, p, ".png");
            rc = write_png(path, im.w, im.h, im.ez, st->exposure, err);
            if (!rc) st->png_files++;
        }
        for (uint32_t i = 0; i < no && o->per_object && !rc; i++) {
            if (objs[i].representation != LBK_REPRESENTATION_LIGHTMAP || objs[i].index != p) continue;
            float *rect = crop(&im, &objs[i]);
            if (!rect) {
                rc = tl_fail(err, -1, "out of memory");
                break;
            }
            char name[129], stem[160], path[4096];
            tl_string_copy(name, sizeof name, objs[i].name);
            tl_export_object_stem(name, i, stem, sizeof stem);
            if (o->exr_dir) {
                snprintf(path, sizeof path, "%s/objects/%s.exr", o->exr_dir, stem);
                rc = tl_exr_write(path, (int)objs[i].rect_w, (int)objs[i].rect_h, 3, RGB, rect, err);
                if (!rc) st->exr_files++;
            }
            if (!rc && o->png_dir) {
                snprintf(path, sizeof path, "%s/objects/%s.png", o->png_dir, stem);
                rc = write_png(path, objs[i].rect_w, objs[i].rect_h, rect, st->exposure, err);
                if (!rc) st->png_files++;
            }
            free(rect);
        }
        free_page(&im);
    }
    free(objs);
    if (rc) return rc;
    probe_row *rows = NULL;
    size_t nrows = 0;
    if (gather_probes(b, &rows, &nrows)) return tl_fail(err, -1, "out of memory");
    const char *dirs[2] = {o->exr_dir, o->png_dir};
    for (int d = 0; d < 2 && !rc; d++) {
        if (!dirs[d] || nrows == 0) continue;
        if (d == 1 && o->exr_dir && !strcmp(o->exr_dir, o->png_dir)) continue; /* same directory: once */
        rc = write_probe_listings(dirs[d], rows, nrows, st, err);
        if (!rc) rc = write_glg_plot(dirs[d], b, rows, nrows, st, err);
    }
    free(rows);
    if (!rc && o->exr_dir) rc = tl_export_octp(b, o->exr_dir, st, err);
    return rc;
}

static int remove_entry(const char *path, const struct stat *sb, int type, struct FTW *ftw)
{
    (void)sb, (void)type, (void)ftw;
    return remove(path);
}

/* Nothing on error: a folder this run created is removed again with what was written into it
 * (everything in it is ours); a folder that existed before keeps what it had, plus whatever of
 * this run's files were complete (each is written atomically). */
int tl_export(const tl_bake *b, const tl_export_options *o, tl_export_stats *st, char err[TL_ERR_LEN])
{
    tl_export_stats local;
    if (!st) st = &local;
    memset(st, 0, sizeof *st);
    const char *dirs[2] = {o->exr_dir, o->png_dir};
    char created[4][4096] = {"", "", "", ""}; /* per folder and its objects/ */
    int rc = 0;
    for (int d = 0; d < 2 && !rc; d++) {
        if (!dirs[d]) continue;
        rc = tl_mkdirs_created(dirs[d], created[2 * d], sizeof created[2 * d], err);
        if (!rc && o->per_object) {
            char sub[4096];
            snprintf(sub, sizeof sub, "%s/objects", dirs[d]);
            rc = tl_mkdirs_created(sub, created[2 * d + 1], sizeof created[2 * d + 1], err);
        }
    }
    if (!rc) rc = export_run(b, o, st, err);
    if (rc)
        for (int k = 0; k < 4; k++)
            if (created[k][0]) nftw(created[k], remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    return rc;
}
