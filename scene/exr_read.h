/* Reads an OpenEXR image (untrusted) into linear float RGBA, for the lbk_sky environment map. */
#ifndef BK_EXR_READ_H
#define BK_EXR_READ_H

#include <stddef.h>

#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads part 0 of `path`: scanline or tiled (level 0), any compression OpenEXRCore supports, with
 * channels R, G, B (half or float; "Y" alone is read as grey; A optional, else 1; a layer prefix
 * such as "sky.R" is accepted when there is no plain "R"). Negative values become 0; NaN or Inf is
 * an error. Images with more than `max_pixels` pixels are refused before any pixel allocation.
 * On success fills out->width/height/rgba (malloc'ed, row 0 = top of the data window) and
 * out->mean, and returns 0; otherwise returns non-zero with a message naming the file. */
int bk_exr_read(const char *path, size_t max_pixels, bk_image *out, char *err, size_t err_len);

#ifdef __cplusplus
}
#endif
#endif
