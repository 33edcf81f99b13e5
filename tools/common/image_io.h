/* Image files for the tools (export, convert --from-exr, diff --heatmap): float EXR through the
 * OpenEXR Core C API, 8-bit PNG through libspng, and the tone map used for every preview.
 *
 * All images are row-major with row 0 at the top, channels interleaved. Functions return 0 on
 * success; on failure they return -1 and write a one-line English reason into err. */
#ifndef LBK_TOOLS_IMAGE_IO_H
#define LBK_TOOLS_IMAGE_IO_H

#include <stddef.h>
#include <stdint.h>

#define TL_ERR_LEN 256

/* Writes a scanline EXR (ZIP compression, 32-bit float channels) with `channel_count` channels
 * named `names`; `pixels` holds width × height × channel_count floats interleaved in the order of
 * `names` (the file stores channels sorted by name, as EXR requires; readers match by name). */
int tl_exr_write(const char *path, int width, int height, int channel_count, const char *const *names,
                 const float *pixels, char err[TL_ERR_LEN]);

/* Reads the named channels of a single-part scanline EXR into a malloc'ed interleaved float
 * buffer (*pixels, width × height × channel_count, in the order of `names`). A missing channel,
 * a tiled or deep file, or a data window not starting at (0,0) is an error. */
int tl_exr_read(const char *path, int channel_count, const char *const *names, int *width, int *height,
                float **pixels, char err[TL_ERR_LEN]);

/* Lists the channel names of an EXR file (for error messages and format detection): up to `max`
 * names of at most 31 bytes each; *count gets the number in the file. */
int tl_exr_channels(const char *path, char names[][32], int max, int *count, char err[TL_ERR_LEN]);

/* 8-bit sRGB-encoded RGB PNG. */
int tl_png_write_rgb8(const char *path, int width, int height, const uint8_t *rgb, char err[TL_ERR_LEN]);
/* Reads any PNG as RGB8 into a malloc'ed buffer (used by tests and tools that check previews). */
int tl_png_read_rgb8(const char *path, int *width, int *height, uint8_t **rgb, char err[TL_ERR_LEN]);

/* ---- the preview tone map (documented in tools/convert/README.md "Previews") ----------------------
 * exposure = 1 / L99, where L99 is the 99th percentile of the Rec.709 luminance of the finite,
 * positive pixels (1 when there are none); each channel becomes sRGB(clamp(exposure × c, 0, 1))
 * rounded to 8 bits. Negative, NaN and Inf components map to 0 (NaN) or clamp (±Inf). */
float tl_luminance(const float rgb[3]);
float tl_exposure_p99(const float *rgb, size_t pixel_count, size_t stride_floats);
uint8_t tl_srgb8(float linear); /* linear in [0,1] (clamped) → 8-bit sRGB, round to nearest */
/* rgb_out[3 × n] = tone-mapped rgb_in (stride_floats floats per pixel, first 3 are RGB). */
void tl_tonemap(const float *rgb_in, size_t pixel_count, size_t stride_floats, float exposure, uint8_t *rgb_out);

/* A perceptual false-colour ramp for heatmaps and probe plots: t in [0,1] → black, blue, cyan,
 * green, yellow, red, white. NaN maps to magenta so it stands out. */
void tl_heat_color(float t, uint8_t rgb[3]);

/* mkdir -p for an output directory. */
int tl_mkdirs(const char *dir, char err[TL_ERR_LEN]);
/* The same; `created` (created_len bytes, may be NULL) gets the outermost folder this call made
 * (the first missing prefix of `dir`), or "" when `dir` already existed. */
int tl_mkdirs_created(const char *dir, char *created, size_t created_len, char err[TL_ERR_LEN]);

#endif
