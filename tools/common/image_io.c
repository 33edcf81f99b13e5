/* EXR (OpenEXR Core C API), PNG (libspng) and the preview tone map. */
#include "tools/common/image_io.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <OpenEXR/openexr.h>
#include <spng.h>

#include "tools/common/error_util.h"
#include "tools/common/file_util.h"

static int find_name(const char *const *names, int count, const char *name)
{
    for (int i = 0; i < count; i++)
        if (!strcmp(names[i], name)) return i;
    return -1;
}

/* ---- EXR ---------------------------------------------------------------------------------- */

static void exr_silent(exr_const_context_t ctx, int code, const char *msg)
{
    (void)ctx; (void)code; (void)msg; /* errors are reported through the return value */
}


/* The EXR is encoded into memory (OpenEXRCore's custom stream) and written with
 * tl_write_file_atomic: a failure names the OS's cause and leaves the old file. */
typedef struct exr_mem { unsigned char *data; size_t size, cap; int failed; } exr_mem;

static int64_t exr_mem_write(exr_const_context_t ctx, void *user, const void *buf, uint64_t sz, uint64_t offset,
                             exr_stream_error_func_ptr_t error_cb)
{
    exr_mem *m = user;
    if (offset > SIZE_MAX - sz || offset + sz > ((uint64_t)1 << 34)) {
        m->failed = 1;
        if (error_cb) error_cb(ctx, EXR_ERR_OUT_OF_MEMORY, "EXR larger than 16 GiB");
        return -1;
    }
    size_t end = (size_t)(offset + sz);
    if (end > m->cap) {
        size_t cap = m->cap ? m->cap : (size_t)1 << 16;
        while (cap < end) cap *= 2;
        unsigned char *d = realloc(m->data, cap);
        if (!d) {
            m->failed = 1;
            if (error_cb) error_cb(ctx, EXR_ERR_OUT_OF_MEMORY, "out of memory");
            return -1;
        }
        memset(d + m->cap, 0, cap - m->cap);
        m->data = d, m->cap = cap;
    }
    memcpy(m->data + offset, buf, (size_t)sz);
    if (end > m->size) m->size = end;
    return (int64_t)sz;
}

static int exr_encode(const char *path, int width, int height, int channel_count, const char *const *names,
                      const float *pixels, exr_mem *mem, char err[TL_ERR_LEN]);

int tl_exr_write(const char *path, int width, int height, int channel_count, const char *const *names,
                 const float *pixels, char err[TL_ERR_LEN])
{
    exr_mem mem = {NULL, 0, 0, 0};
    int rc = exr_encode(path, width, height, channel_count, names, pixels, &mem, err);
    if (!rc) rc = tl_write_file_atomic(path, mem.data, mem.size, err);
    free(mem.data);
    return rc;
}

static int exr_encode(const char *path, int width, int height, int channel_count, const char *const *names,
                      const float *pixels, exr_mem *mem, char err[TL_ERR_LEN])
{
    if (width <= 0 || height <= 0 || channel_count <= 0 || !names || !pixels)
        return tl_fail(err, -1, "%s: nothing to write (%dx%d, %d channels)", path, width, height, channel_count);
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_silent;
    init.user_data = mem;
    init.write_fn = exr_mem_write;
    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS) return tl_fail(err, -1, "%s: cannot encode EXR (%s)", path, exr_get_default_error_message(rv));
    int part = 0;
    rv = exr_add_part(ctx, "lbk", EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS) rv = exr_initialize_required_attr_simple(ctx, part, width, height, EXR_COMPRESSION_ZIP);
    for (int c = 0; c < channel_count && rv == EXR_ERR_SUCCESS; c++)
        rv = exr_add_channel(ctx, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
    int32_t lines = 1;
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
    const int32_t pixel_stride = (int32_t)(sizeof(float) * (size_t)channel_count);
    const int32_t line_stride = pixel_stride * width;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int enc_live = 0;
    for (int y = 0; y < height && rv == EXR_ERR_SUCCESS; y += lines) {
        exr_chunk_info_t cinfo;
        rv = exr_write_scanline_chunk_info(ctx, part, y, &cinfo);
        if (rv != EXR_ERR_SUCCESS) break;
        rv = enc_live ? exr_encoding_update(ctx, part, &cinfo, &enc) : exr_encoding_initialize(ctx, part, &cinfo, &enc);
        if (rv != EXR_ERR_SUCCESS) break;
        for (int c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int src = find_name(names, channel_count, ch->channel_name);
            if (src < 0) { rv = EXR_ERR_INVALID_ARGUMENT; break; }
            ch->user_pixel_stride = pixel_stride;
            ch->user_line_stride = line_stride;
            ch->user_bytes_per_element = 4;
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->encode_from_ptr = (const uint8_t *)(pixels + ((size_t)cinfo.start_y * (size_t)width) * (size_t)channel_count + src);
        }
        if (rv != EXR_ERR_SUCCESS) break;
        if (!enc_live) {
            rv = exr_encoding_choose_default_routines(ctx, part, &enc);
            enc_live = 1;
            if (rv != EXR_ERR_SUCCESS) break;
        }
        rv = exr_encoding_run(ctx, part, &enc);
    }
    if (enc_live || enc.channels) exr_encoding_destroy(ctx, &enc);
    exr_result_t fin = exr_finish(&ctx);
    if (rv == EXR_ERR_SUCCESS) rv = fin;
    if (rv != EXR_ERR_SUCCESS || mem->failed)
        return tl_fail(err, -1, "%s: EXR encode failed (%s)", path, exr_get_default_error_message(rv));
    return 0;
}

static int exr_open_read(const char *path, exr_context_t *ctx, char err[TL_ERR_LEN])
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_silent;
    exr_result_t rv = exr_start_read(ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(ctx);
        return tl_fail(err, -1, "%s: cannot read EXR (%s)", path, exr_get_default_error_message(rv));
    }
    return 0;
}

int tl_exr_channels(const char *path, char names[][32], int max, int *count, char err[TL_ERR_LEN])
{
    exr_context_t ctx = NULL;
    if (exr_open_read(path, &ctx, err)) return -1;
    const exr_attr_chlist_t *cl = NULL;
    exr_result_t rv = exr_get_channels(ctx, 0, &cl);
    if (rv != EXR_ERR_SUCCESS || !cl) {
        exr_finish(&ctx);
        return tl_fail(err, -1, "%s: EXR has no channel list", path);
    }
    *count = cl->num_channels;
    for (int i = 0; i < cl->num_channels && i < max; i++) snprintf(names[i], 32, "%s", cl->entries[i].name.str);
    exr_finish(&ctx);
    return 0;
}

int tl_exr_read(const char *path, int channel_count, const char *const *names, int *width, int *height,
                float **pixels, char err[TL_ERR_LEN])
{
    *pixels = NULL;
    exr_context_t ctx = NULL;
    if (exr_open_read(path, &ctx, err)) return -1;
    int ret = -1;
    exr_storage_t st;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *cl = NULL;
    float *buf = NULL;
    if (exr_get_storage(ctx, 0, &st) != EXR_ERR_SUCCESS || st != EXR_STORAGE_SCANLINE) {
        tl_fail(err, -1, "%s: only flat scanline EXR files are supported", path);
        goto out;
    }
    if (exr_get_data_window(ctx, 0, &dw) != EXR_ERR_SUCCESS || dw.min.x != 0 || dw.min.y != 0 || dw.max.x < 0 ||
        dw.max.y < 0 || dw.max.x >= 65536 || dw.max.y >= 65536) {
        tl_fail(err, -1, "%s: data window must start at (0,0) and be at most 65536 wide and high", path);
        goto out;
    }
    if (exr_get_channels(ctx, 0, &cl) != EXR_ERR_SUCCESS) {
        tl_fail(err, -1, "%s: EXR has no channel list", path);
        goto out;
    }
    for (int c = 0; c < channel_count; c++) {
        int found = 0;
        for (int i = 0; i < cl->num_channels; i++)
            if (!strcmp(cl->entries[i].name.str, names[c])) {
                found = 1;
                if (cl->entries[i].x_sampling != 1 || cl->entries[i].y_sampling != 1) {
                    tl_fail(err, -1, "%s: channel '%s' is subsampled", path, names[c]);
                    goto out;
                }
            }
        if (!found) {
            tl_fail(err, -1, "%s: channel '%s' is missing", path, names[c]);
            goto out;
        }
    }
    const int w = dw.max.x + 1, h = dw.max.y + 1;
    buf = calloc((size_t)w * (size_t)h * (size_t)channel_count, sizeof(float));
    if (!buf) {
        tl_fail(err, -1, "%s: out of memory for %dx%d pixels", path, w, h);
        goto out;
    }
    int32_t lines = 1;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int dec_live = 0;
    const int32_t pixel_stride = (int32_t)(sizeof(float) * (size_t)channel_count);
    for (int y = 0; y < h && rv == EXR_ERR_SUCCESS; y += lines) {
        exr_chunk_info_t cinfo;
        rv = exr_read_scanline_chunk_info(ctx, 0, y, &cinfo);
        if (rv != EXR_ERR_SUCCESS) break;
        rv = dec_live ? exr_decoding_update(ctx, 0, &cinfo, &dec) : exr_decoding_initialize(ctx, 0, &cinfo, &dec);
        if (rv != EXR_ERR_SUCCESS) break;
        for (int c = 0; c < dec.channel_count; c++) {
            exr_coding_channel_info_t *ch = &dec.channels[c];
            int dst = find_name(names, channel_count, ch->channel_name);
            if (dst < 0) {
                ch->decode_to_ptr = NULL; /* skipped */
                continue;
            }
            ch->user_pixel_stride = pixel_stride;
            ch->user_line_stride = pixel_stride * w;
            ch->user_bytes_per_element = 4;
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->decode_to_ptr = (uint8_t *)(buf + ((size_t)cinfo.start_y * (size_t)w) * (size_t)channel_count + dst);
        }
        if (!dec_live) {
            rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
            dec_live = 1;
            if (rv != EXR_ERR_SUCCESS) break;
        }
        rv = exr_decoding_run(ctx, 0, &dec);
    }
    if (dec_live || dec.channels) exr_decoding_destroy(ctx, &dec);
    if (rv != EXR_ERR_SUCCESS) {
        tl_fail(err, -1, "%s: EXR read failed (%s)", path, exr_get_default_error_message(rv));
        goto out;
    }
    *width = w;
    *height = h;
    *pixels = buf;
    buf = NULL;
    ret = 0;
out:
    free(buf);
    exr_finish(&ctx);
    return ret;
}

/* ---- PNG ---------------------------------------------------------------------------------- */

/* Encoded in memory, then written atomically: a failed write leaves the old file. */
int tl_png_write_rgb8(const char *path, int width, int height, const uint8_t *rgb, char err[TL_ERR_LEN])
{
    if (width <= 0 || height <= 0) return tl_fail(err, -1, "%s: empty image", path);
    spng_ctx *ctx = spng_ctx_new(SPNG_CTX_ENCODER);
    int rc = ctx ? 0 : SPNG_EMEM;
    if (!rc) rc = spng_set_option(ctx, SPNG_ENCODE_TO_BUFFER, 1);
    struct spng_ihdr ihdr = {0};
    ihdr.width = (uint32_t)width;
    ihdr.height = (uint32_t)height;
    ihdr.bit_depth = 8;
    ihdr.color_type = SPNG_COLOR_TYPE_TRUECOLOR;
    if (!rc) rc = spng_set_ihdr(ctx, &ihdr);
    if (!rc) rc = spng_encode_image(ctx, rgb, (size_t)width * (size_t)height * 3, SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE);
    size_t size = 0;
    void *png = NULL;
    if (!rc) png = spng_get_png_buffer(ctx, &size, &rc);
    spng_ctx_free(ctx);
    if (rc || !png) {
        free(png);
        return tl_fail(err, -1, "%s: PNG encode failed (%s)", path, spng_strerror(rc ? rc : SPNG_EMEM));
    }
    int w = tl_write_file_atomic(path, png, size, err);
    free(png);
    return w;
}

int tl_png_read_rgb8(const char *path, int *width, int *height, uint8_t **rgb, char err[TL_ERR_LEN])
{
    *rgb = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return tl_fail(err, -1, "%s: %s", path, strerror(errno));
    spng_ctx *ctx = spng_ctx_new(0);
    int rc = ctx ? 0 : SPNG_EMEM;
    if (!rc) rc = spng_set_png_file(ctx, f);
    struct spng_ihdr ihdr;
    size_t len = 0;
    uint8_t *buf = NULL;
    if (!rc) rc = spng_get_ihdr(ctx, &ihdr);
    if (!rc) rc = spng_decoded_image_size(ctx, SPNG_FMT_RGB8, &len);
    if (!rc && !(buf = malloc(len ? len : 1))) rc = SPNG_EMEM;
    if (!rc) rc = spng_decode_image(ctx, buf, len, SPNG_FMT_RGB8, 0);
    spng_ctx_free(ctx);
    fclose(f);
    if (rc) {
        free(buf);
        return tl_fail(err, -1, "%s: PNG decode failed (%s)", path, spng_strerror(rc));
    }
    *width = (int)ihdr.width;
    *height = (int)ihdr.height;
    *rgb = buf;
    return 0;
}

/* ---- tone map ------------------------------------------------------------------------------ */

float tl_luminance(const float rgb[3]) { return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2]; }

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

float tl_exposure_p99(const float *rgb, size_t pixel_count, size_t stride_floats)
{
    float *lum = malloc((pixel_count ? pixel_count : 1) * sizeof(float));
    if (!lum) return 1.0f;
    size_t n = 0;
    for (size_t i = 0; i < pixel_count; i++) {
        float l = tl_luminance(rgb + i * stride_floats);
        if (isfinite(l) && l > 0.0f) lum[n++] = l;
    }
    float exposure = 1.0f;
    if (n) {
        qsort(lum, n, sizeof(float), cmp_float);
        size_t k = (size_t)floor(0.99 * (double)(n - 1) + 0.5);
        if (lum[k] > 0.0f) exposure = 1.0f / lum[k];
    }
    free(lum);
    return exposure;
}

uint8_t tl_srgb8(float x)
{
    if (!(x > 0.0f)) return 0; /* also NaN */
    if (x >= 1.0f) return 255;
    double s = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    return (uint8_t)floor(s * 255.0 + 0.5);
}

void tl_tonemap(const float *rgb_in, size_t pixel_count, size_t stride_floats, float exposure, uint8_t *rgb_out)
{
    for (size_t i = 0; i < pixel_count; i++)
        for (int c = 0; c < 3; c++) rgb_out[3 * i + (size_t)c] = tl_srgb8(rgb_in[i * stride_floats + (size_t)c] * exposure);
}

void tl_heat_color(float t, uint8_t rgb[3])
{
    static const float ramp[7][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}, {1, 1, 1}};
    if (isnan(t)) {
        rgb[0] = 255, rgb[1] = 0, rgb[2] = 255;
        return;
    }
    if (t < 0) t = 0;
    if (t > 1) t = 1;
    float x = t * 6.0f;
    int i = (int)x;
    if (i >= 6) i = 5;
    float f = x - (float)i;
    for (int c = 0; c < 3; c++) {
        float v = ramp[i][c] + (ramp[i + 1][c] - ramp[i][c]) * f;
        rgb[c] = (uint8_t)(v * 255.0f + 0.5f);
    }
}

int tl_mkdirs(const char *dir, char err[TL_ERR_LEN]) { return tl_mkdirs_created(dir, NULL, 0, err); }

int tl_mkdirs_created(const char *dir, char *created, size_t created_len, char err[TL_ERR_LEN])
{
    if (created && created_len) created[0] = 0;
    char buf[4096];
    size_t n = strlen(dir);
    if (n == 0 || n >= sizeof buf) return tl_fail(err, -1, "bad output directory '%s'", dir);
    memcpy(buf, dir, n + 1);
    for (size_t i = 1; i <= n; i++) {
        if (buf[i] == '/' || buf[i] == '\0') {
            char saved = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0777) == 0) {
                if (created && created_len && !created[0]) snprintf(created, created_len, "%s", buf);
            } else if (errno != EEXIST) {
                return tl_fail(err, -1, "cannot create directory %s: %s", buf, strerror(errno));
            }
            buf[i] = saved;
        }
    }
    struct stat sb;
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) return tl_fail(err, -1, "%s is not a directory", dir);
    return 0;
}
