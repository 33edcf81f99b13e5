/* lbk view --out: the page folder (view.h). */
#include "tools/view/view.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "tools/common/bake_data.h"
#include "tools/common/file_util.h"
#include "tools/convert/gltf_export.h"
#include "lbk/pixel.h"

static int set_err(char err[TL_ERR_LEN], int status, const char *what, const char *detail)
{
    snprintf(err, TL_ERR_LEN, "%s%s%s", what, detail ? ": " : "", detail ? detail : "");
    return status;
}

/* base64 (RFC 4648, padded) of data into a fresh NUL-terminated string, NULL on overflow or OOM */
static char *base64(const unsigned char *data, size_t size)
{
    static const char abc[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    if (size > (SIZE_MAX - 1) / 4 * 3 - 3) return NULL;
    char *out = malloc((size + 2) / 3 * 4 + 1), *o = out;
    if (!out) return NULL;
    for (size_t i = 0; i < size; i += 3) {
        const size_t n = size - i < 3 ? size - i : 3;
        const uint32_t v = (uint32_t)data[i] << 16 | (n > 1 ? (uint32_t)data[i + 1] << 8 : 0) | (n > 2 ? data[i + 2] : 0);
        *o++ = abc[v >> 18 & 63];
        *o++ = abc[v >> 12 & 63];
        *o++ = n > 1 ? abc[v >> 6 & 63] : '=';
        *o++ = n > 2 ? abc[v & 63] : '=';
    }
    *o = 0;
    return out;
}

/* The level's name as a JSON string body: the container's base name, bytes outside printable
 * ASCII and the JSON specials replaced by '_' (it is only a title). */
static void json_name(const char *path, char *out, size_t size)
{
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    size_t i = 0;
    for (; b[i] && i + 1 < size; i++) out[i] = (b[i] < 0x20 || b[i] > 0x7e || b[i] == '"' || b[i] == '\\') ? '_' : b[i];
    out[i] = 0;
}

/* JSON text re-printed by cJSON (so only a JSON value reaches data.js), or "null" when absent;
 * NULL with err when the text is not JSON. Free with cJSON_free (or free for "null" copies). */
static char *json_value(const char *text, size_t size, const char *what, char err[TL_ERR_LEN])
{
    if (!text) {
        char *n = cJSON_malloc(5);
        if (n) memcpy(n, "null", 5);
        return n;
    }
    const char *end = NULL;
    cJSON *doc = cJSON_ParseWithLengthOpts(text, size, &end, 0);
    /* one value and nothing after it but white space (cJSON stops after the first value) */
    while (doc && end && (size_t)(end - text) < size && (*end == ' ' || *end == '\n' || *end == '\r' || *end == '\t')) end++;
    if (doc && (!end || (size_t)(end - text) < size)) {
        cJSON_Delete(doc);
        doc = NULL;
    }
    if (!doc) {
        snprintf(err, TL_ERR_LEN, "%s is not JSON", what);
        return NULL;
    }
    char *out = cJSON_PrintUnformatted(doc);
    cJSON_Delete(doc);
    if (!out) snprintf(err, TL_ERR_LEN, "out of memory");
    return out;
}

static int write_data_js(const char *path, const char *name, const void *lbk, size_t lbk_size, const void *glb,
                         size_t glb_size, const char *inspect, const char *report, uint64_t *written,
                         char err[TL_ERR_LEN])
{
    char *a = base64(lbk, lbk_size), *b = base64(glb, glb_size);
    int rc = TL_VIEW_INTERNAL;
    char *text = NULL;
    if (a && b) {
        const size_t n = strlen(a) + strlen(b) + strlen(name) + strlen(inspect) + strlen(report) + 160;
        text = malloc(n);
        if (text) {
            snprintf(text, n,
                     "window.LBK_DATA = {\"name\": \"%s\",\n\"inspect\": %s,\n\"report\": %s,\n\"lbk\": \"%s\",\n"
                     "\"glb\": \"%s\"};\n",
                     name, inspect, report, a, b);
            *written = strlen(text);
            rc = tl_write_text(path, text, err) ? TL_VIEW_IO : TL_VIEW_OK;
        }
    }
    if (rc == TL_VIEW_INTERNAL) set_err(err, rc, "out of memory", NULL);
    free(a), free(b), free(text);
    return rc;
}

/* The page reads 1.0 and BC pages itself (viewer/lbk_reader.js) but has no ASTC decoder (a few
 * thousand lines of JS for one profile): a container with ASTC pages is handed to it with LMAP
 * rebuilt from the texels liblbk's tools decoded (astcenc), stored as 1.0 texels (R11G11B10F +
 * RGBA8: at most 2^-7 relative on top of the codec's error). Pages keep their size, so DLS and
 * TERR texel indices stay valid; every other section is copied as decoded. *out NULL: no ASTC. */
static int astc_to_texels(const tl_bake *b, const void *lbk, size_t size, void **out, size_t *out_size, uint32_t *pages,
                          char err[TL_ERR_LEN])
{
    *out = NULL, *out_size = 0, *pages = 0;
    const uint32_t np = b->has_lmap ? b->lmap.page_count : 0;
    for (uint32_t p = 0; p < np; p++) {
        lbk_lmap_planes pl;
        if (lbk_lmap_planes_get(&b->lmap, p, &pl) == LBK_OK &&
            (pl.format[0] == LBK_LMAP_ASTC4X4_HDR || pl.format[1] == LBK_LMAP_ASTC4X4_LDR))
            (*pages)++;
    }
    if (!*pages) return TL_VIEW_OK;
    lbk_lmap_page_desc *pd = calloc((size_t)np + 1, sizeof *pd);
    lbk_ahd_texel *tex = malloc(((size_t)b->lmap.texel_count + 1) * sizeof *tex);
    void *lmap = NULL;
    size_t lmap_size = 0;
    int rc = pd && tex ? TL_VIEW_OK : set_err(err, TL_VIEW_INTERNAL, "out of memory", NULL);
    for (uint32_t p = 0; p < np && !rc; p++) {
        lbk_lmap_planes pl;
        lbk_lmap_planes_get(&b->lmap, p, &pl);
        lbk_ahd_texel *t = tex + pl.first_texel;
        for (uint32_t y = 0; y < pl.height; y++)
            for (uint32_t x = 0; x < pl.width; x++) {
                lbk_ahd_texel_f f;
                if (tl_bake_texel_get(b, p, x, y, &f, NULL, NULL)) memset(&f, 0, sizeof f);
                lbk_ahd_texel *d = &t[(size_t)y * pl.width + x];
                d->irradiance_z = lbk_r11g11b10f_pack(f.ez);
                for (int k = 0; k < 4; k++) d->rgba[k] = lbk_float_to_unorm8(f.rgba[k]);
            }
        pd[p] = (lbk_lmap_page_desc){pl.width, pl.height, t};
    }
    const lbk_lmap_build_desc bd = {.size = sizeof bd, .pages = pd, .page_count = np, .scale = b->lmap.scale};
    if (!rc && lbk_lmap_build(&bd, NULL, &lmap, &lmap_size) != LBK_OK) rc = set_err(err, TL_VIEW_INTERNAL, "rebuilding LMAP", NULL);
    free(pd), free(tex);
    lbk_reader *rd = NULL;
    lbk_writer *w = NULL;
    if (!rc && (lbk_reader_open_memory(lbk, size, NULL, &rd) != LBK_OK || lbk_writer_open(NULL, &w) != LBK_OK))
        rc = set_err(err, TL_VIEW_INTERNAL, "re-reading the container", NULL);
    const uint32_t n = rd ? lbk_reader_section_count(rd) : 0;
    for (uint32_t i = 0; i < n && !rc; i++) {
        lbk_section_info si;
        const void *data;
        size_t ds;
        if (lbk_reader_section_get(rd, i, &si) != LBK_OK || lbk_reader_section_data(rd, i, &data, &ds) != LBK_OK) {
            rc = set_err(err, TL_VIEW_INTERNAL, "re-reading the container", NULL);
            break;
        }
        lbk_section_options so = LBK_SECTION_OPTIONS_INIT;
        so.flags = si.flags;
        if (si.type == LBK_SECTION_LMAP) data = lmap, ds = lmap_size;
        if (lbk_writer_section_add(w, si.type, data, ds, &so) != LBK_OK) rc = set_err(err, TL_VIEW_INTERNAL, "rewriting a section", NULL);
    }
    if (!rc && lbk_writer_to_memory(w, out, out_size) != LBK_OK) rc = set_err(err, TL_VIEW_INTERNAL, "rewriting the container", NULL);
    lbk_writer_close(w);
    lbk_reader_close(rd);
    lbk_free(NULL, lmap);
    return rc;
}

static int join(char *out, size_t size, const char *dir, const char *file, char err[TL_ERR_LEN])
{
    if ((size_t)snprintf(out, size, "%s/%s", dir, file) >= size) return set_err(err, TL_VIEW_IO, "path too long", dir);
    return TL_VIEW_OK;
}

static int write_assets(const char *dir, uint32_t *files, char err[TL_ERR_LEN])
{
    char path[4096];
    for (size_t i = 0; i < tl_view_asset_count; i++) {
        const tl_view_asset *a = &tl_view_assets[i];
        int rc = join(path, sizeof path, dir, a->path, err);
        if (rc) return rc;
        char *slash = strrchr(path, '/');
        if (slash && strchr(a->path, '/')) { /* a sub-folder (vendor/) */
            *slash = 0;
            if (tl_mkdirs(path, err)) return TL_VIEW_IO;
            *slash = '/';
        }
        if (tl_write_file_atomic(path, a->data, a->size, err)) return TL_VIEW_IO;
        (*files)++;
    }
    return TL_VIEW_OK;
}

int tl_view_write(const tl_view_options *o, tl_view_stats *stats, char err[TL_ERR_LEN])
{
    tl_view_stats s = {0, 0, 0};
    if (!o || !o->container || !o->scene || !o->out_dir) return set_err(err, TL_VIEW_INTERNAL, "missing option", NULL);
    tl_bake bake;
    tl_open_status st = tl_bake_open_file(o->container, &bake, err);
    if (st != TL_OPEN_OK) return st == TL_OPEN_IO ? TL_VIEW_IO : st == TL_OPEN_INVALID ? TL_VIEW_INPUT : TL_VIEW_INTERNAL;
    if (tl_mkdirs(o->out_dir, err)) {
        tl_bake_close(&bake);
        return TL_VIEW_IO;
    }
    char glb_path[4096], data_path[4096];
    int rc = join(glb_path, sizeof glb_path, o->out_dir, "level.glb", err);
    if (!rc) rc = join(data_path, sizeof data_path, o->out_dir, "data.js", err);
    if (!rc) {
        const char *base = strrchr(o->container, '/');
        tl_gltf_options g = {.output = glb_path, .scene = o->scene, .container = base ? base + 1 : o->container,
                             .normal_texels = 1}; /* the page's normal maps (viewer.js) */
        tl_gltf_stats gs;
        rc = tl_gltf_export(&bake, &g, &gs, err);
        if (rc) rc = rc == TL_GLTF_IO ? TL_VIEW_IO : rc == TL_GLTF_INPUT ? TL_VIEW_INPUT : TL_VIEW_INTERNAL;
        else s.files += 1 + gs.exr_files + gs.png_files;
    }
    void *lbk = NULL, *glb = NULL;
    size_t lbk_size = 0, glb_size = 0;
    if (!rc && (tl_read_file(o->container, &lbk, &lbk_size, err) || tl_read_file(glb_path, &glb, &glb_size, err))) rc = TL_VIEW_IO;
    if (!rc) {
        void *texels = NULL;
        size_t texels_size = 0;
        rc = astc_to_texels(&bake, lbk, lbk_size, &texels, &texels_size, &s.astc_pages, err);
        if (texels) { /* lbk_writer_to_memory without an allocator: malloc, so free() both */
            free(lbk);
            lbk = texels, lbk_size = texels_size;
        }
    }
    tl_bake_close(&bake);
    char *inspect = NULL, *report = NULL;
    if (!rc) {
        void *rep = NULL;
        size_t rep_size = 0;
        if (o->report_path && tl_read_file(o->report_path, &rep, &rep_size, err)) rc = TL_VIEW_IO;
        if (!rc && !(inspect = json_value(o->inspect_json, o->inspect_json ? strlen(o->inspect_json) : 0, "the inspect output", err))) rc = TL_VIEW_INPUT;
        if (!rc && !(report = json_value(rep, rep_size, o->report_path, err))) rc = TL_VIEW_INPUT;
        free(rep);
    }
    if (!rc) {
        char name[256];
        json_name(o->container, name, sizeof name);
        rc = write_data_js(data_path, name, lbk, lbk_size, glb, glb_size, inspect, report, &s.data_bytes, err);
        if (!rc) s.files++;
    }
    free(lbk), free(glb), cJSON_free(inspect), cJSON_free(report);
    if (!rc) rc = write_assets(o->out_dir, &s.files, err);
    if (stats) *stats = s;
    return rc;
}
