/* EXR → linear float RGBA with the OpenEXRCore C API. */
#include "scene/exr_read.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <OpenEXR/openexr.h>

static void silent_error_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    /* OpenEXRCore prints to stderr by default; we report the code's message ourselves. */
    (void)ctxt; (void)code; (void)msg;
}

/* Which RGBA slot a channel name feeds (-1: ignored). `prefixed` accepts "layer.R". */
static int channel_slot(const char *name, int prefixed)
{
    const char *base = name;
    if (prefixed) {
        const char *dot = strrchr(name, '.');
        if (dot) base = dot + 1;
    } else if (strchr(name, '.')) {
        return -1;
    }
    if (!strcmp(base, "R")) return 0;
    if (!strcmp(base, "G")) return 1;
    if (!strcmp(base, "B")) return 2;
    if (!strcmp(base, "A")) return 3;
    if (!strcmp(base, "Y")) return 4; /* luminance: copied to R, G and B afterwards */
    return -1;
}

typedef struct exr_job {
    exr_context_t ctxt;
    const char *path;
    char *err;
    size_t err_len;
    int x0, y0, width, height;
    int prefixed;
    float *rgba;
    float *lum;  /* only when the file has Y */
    float *unused; /* where the channels we do not read are decoded to (see decode_chunk) */
} exr_job;

static int fail_code(exr_job *j, const char *what, exr_result_t rv)
{
    snprintf(j->err, j->err_len, "%s: EXR %s failed: %s", j->path, what,
             exr_get_default_error_message(rv));
    return 1;
}

/* Decodes one chunk (scanline block or tile) whose pixel origin is (px, py). */
static int decode_chunk(exr_job *j, const exr_chunk_info_t *ci, int px, int py)
{
    if (ci->width <= 0 || ci->height <= 0 || px < j->x0 || py < j->y0 ||
        (int64_t)px - j->x0 + ci->width > j->width || (int64_t)py - j->y0 + ci->height > j->height) {
        snprintf(j->err, j->err_len, "%s: EXR chunk at (%d, %d) size %dx%d lies outside the data window",
                 j->path, px, py, ci->width, ci->height);
        return 1;
    }
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    exr_result_t rv = exr_decoding_initialize(j->ctxt, 0, ci, &dec);
    if (rv != EXR_ERR_SUCCESS) return fail_code(j, "decoder set-up", rv);
    size_t ox = (size_t)(px - j->x0), oy = (size_t)(py - j->y0);
    for (int c = 0; c < dec.channel_count; c++) {
        exr_coding_channel_info_t *ch = &dec.channels[c];
        int slot = channel_slot(ch->channel_name, j->prefixed);
        if (slot == 4 && !j->lum) slot = -1; /* Y beside R, G, B: not read (fuzz_exr: it was written through NULL) */
        ch->user_bytes_per_element = 4;
        ch->user_data_type = EXR_PIXEL_FLOAT;
        if (slot < 0) {
            /* decoded and dropped: OpenEXRCore 3.1 documents a NULL decode_to_ptr as "skip this
             * channel", but its unpackers then write through the null pointer (a PIZ or B44 file
             * with one channel we do not use crashed the reader: fuzz_exr) */
            ch->user_data_type = ch->data_type; /* as stored: no conversion (UINT included) */
            ch->user_bytes_per_element = ch->bytes_per_element;
            ch->user_pixel_stride = 4;
            ch->user_line_stride = 4 * j->width;
            ch->decode_to_ptr = (uint8_t *)(j->unused + oy * (size_t)j->width + ox);
        } else if (slot == 4) {
            ch->user_pixel_stride = 4;
            ch->user_line_stride = 4 * j->width;
            ch->decode_to_ptr = (uint8_t *)(j->lum + oy * (size_t)j->width + ox);
        } else {
            ch->user_pixel_stride = 16;
            ch->user_line_stride = 16 * j->width;
            ch->decode_to_ptr = (uint8_t *)(j->rgba + 4 * (oy * (size_t)j->width + ox) + slot);
        }
    }
    rv = exr_decoding_choose_default_routines(j->ctxt, 0, &dec);
    if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(j->ctxt, 0, &dec);
    exr_decoding_destroy(j->ctxt, &dec);
    if (rv != EXR_ERR_SUCCESS) return fail_code(j, "pixel decoding", rv);
    return 0;
}

static int read_pixels(exr_job *j)
{
    exr_storage_t storage;
    exr_result_t rv = exr_get_storage(j->ctxt, 0, &storage);
    if (rv != EXR_ERR_SUCCESS) return fail_code(j, "storage query", rv);
    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lines = 0;
        rv = exr_get_scanlines_per_chunk(j->ctxt, 0, &lines);
        if (rv != EXR_ERR_SUCCESS || lines <= 0) return fail_code(j, "scanline layout query", rv);
        for (int64_t y = j->y0; y < (int64_t)j->y0 + j->height; y += lines) {
            exr_chunk_info_t ci;
            rv = exr_read_scanline_chunk_info(j->ctxt, 0, (int)y, &ci);
            if (rv != EXR_ERR_SUCCESS) return fail_code(j, "scanline chunk read", rv);
            if (decode_chunk(j, &ci, j->x0, ci.start_y)) return 1;
        }
        return 0;
    }
    if (storage == EXR_STORAGE_TILED) {
        int32_t tw = 0, th = 0, lw = 0, lh = 0;
        rv = exr_get_tile_sizes(j->ctxt, 0, 0, 0, &tw, &th);
        if (rv == EXR_ERR_SUCCESS) rv = exr_get_level_sizes(j->ctxt, 0, 0, 0, &lw, &lh);
        if (rv != EXR_ERR_SUCCESS) return fail_code(j, "tile layout query", rv);
        if (tw <= 0 || th <= 0 || lw != j->width || lh != j->height) {
            snprintf(j->err, j->err_len, "%s: EXR tile layout %dx%d / level %dx%d does not match the data window",
                     j->path, tw, th, lw, lh);
            return 1;
        }
        int nx = (lw + tw - 1) / tw, ny = (lh + th - 1) / th;
        for (int ty = 0; ty < ny; ty++)
            for (int tx = 0; tx < nx; tx++) {
                exr_chunk_info_t ci;
                rv = exr_read_tile_chunk_info(j->ctxt, 0, tx, ty, 0, 0, &ci);
                if (rv != EXR_ERR_SUCCESS) return fail_code(j, "tile chunk read", rv);
                if (decode_chunk(j, &ci, j->x0 + tx * tw, j->y0 + ty * th)) return 1;
            }
        return 0;
    }
    snprintf(j->err, j->err_len, "%s: deep EXR images are not supported", j->path);
    return 1;
}

int bk_exr_read(const char *path, size_t max_pixels, bk_image *out, char *err, size_t err_len)
{
    char dummy[1];
    if (!err || !err_len) { err = dummy; err_len = sizeof dummy; }
    memset(out, 0, sizeof *out);
    exr_job j;
    memset(&j, 0, sizeof j);
    j.path = path; j.err = err; j.err_len = err_len;

    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = silent_error_handler;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_result_t rv = exr_start_read(&j.ctxt, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        snprintf(err, err_len, "%s: cannot read as EXR: %s", path, exr_get_default_error_message(rv));
        if (j.ctxt) exr_finish(&j.ctxt);
        return 1;
    }
    int ret = 1;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *chl = NULL;
    rv = exr_get_data_window(j.ctxt, 0, &dw);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_channels(j.ctxt, 0, &chl);
    if (rv != EXR_ERR_SUCCESS || !chl) { fail_code(&j, "header query", rv); goto done; }
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w <= 0 || h <= 0 || w > INT32_MAX / 16 || h > INT32_MAX / 16 || (uint64_t)w * (uint64_t)h > max_pixels) {
        snprintf(err, err_len, "%s: EXR data window %lldx%lld is empty or larger than the %zu-pixel cap",
                 path, (long long)w, (long long)h, max_pixels);
        goto done;
    }
    j.x0 = dw.min.x; j.y0 = dw.min.y; j.width = (int)w; j.height = (int)h;

    /* Subsampled channels are not supported, used or not (the scratch plane of decode_chunk
     * has one value per pixel). */
    for (int c = 0; c < chl->num_channels; c++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[c];
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            snprintf(err, err_len, "%s: EXR channel \"%s\" is subsampled (not supported)", path,
                     e->name.str ? e->name.str : "");
            goto done;
        }
    }
    /* Plain R/G/B win over layered ones; fall back to the first layer that has them. */
    int have[5] = {0}, have_prefixed[5] = {0};
    for (int c = 0; c < chl->num_channels; c++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[c];
        const char *name = e->name.str ? e->name.str : "";
        for (int pass = 0; pass < 2; pass++) {
            int slot = channel_slot(name, pass);
            if (slot < 0) continue;
            if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT) {
                snprintf(err, err_len, "%s: EXR channel \"%s\" is not half or float", path, name);
                goto done;
            }
            (pass ? have_prefixed : have)[slot] = 1;
        }
    }
    int rgb = have[0] && have[1] && have[2], rgb_p = have_prefixed[0] && have_prefixed[1] && have_prefixed[2];
    int use_y = 0;
    if (rgb) j.prefixed = 0;
    else if (have[4]) { j.prefixed = 0; use_y = 1; }
    else if (rgb_p) j.prefixed = 1;
    else {
        snprintf(err, err_len, "%s: EXR has no R, G, B (or Y) channels", path);
        goto done;
    }
    size_t npix = (size_t)w * (size_t)h;
    j.rgba = calloc(npix, 4 * sizeof(float));
    if (use_y) j.lum = calloc(npix, sizeof(float));
    j.unused = malloc(npix * sizeof(float));
    if (!j.rgba || (use_y && !j.lum) || !j.unused) {
        snprintf(err, err_len, "%s: out of memory for a %dx%d EXR", path, j.width, j.height);
        goto done;
    }
    int has_alpha = j.prefixed ? have_prefixed[3] : have[3];
    if (!has_alpha)
        for (size_t i = 0; i < npix; i++) j.rgba[4 * i + 3] = 1.0f;
    if (read_pixels(&j)) goto done;

    double sum[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < npix; i++) {
        float *p = j.rgba + 4 * i;
        if (use_y) p[0] = p[1] = p[2] = j.lum[i];
        for (int k = 0; k < 4; k++) {
            if (!isfinite(p[k])) {
                snprintf(err, err_len, "%s: EXR pixel (%zu, %zu) is NaN or infinite", path,
                         i % (size_t)j.width, i / (size_t)j.width);
                goto done;
            }
            if (p[k] < 0.0f) p[k] = 0.0f;
            sum[k] += p[k];
        }
    }
    out->width = j.width;
    out->height = j.height;
    out->rgba = j.rgba;
    for (int k = 0; k < 4; k++) out->mean[k] = (float)(sum[k] / (double)npix);
    j.rgba = NULL;
    ret = 0;
done:
    free(j.rgba);
    free(j.lum);
    free(j.unused);
    exr_finish(&j.ctxt);
    return ret;
}
