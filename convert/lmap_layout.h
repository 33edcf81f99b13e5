/* LMAP payload rewriting for convert: page layout the runtime needs (row pitch, page alignment)
 * and importing edited pages from EXR files written by `lbk export`. */
#ifndef LBK_TOOLS_LMAP_LAYOUT_H
#define LBK_TOOLS_LMAP_LAYOUT_H

#include <stddef.h>
#include <stdint.h>

#include "convert/image_io.h"

typedef struct tl_lmap_layout_options {
    uint32_t row_pitch_alignment; /* 0: as baked */
    uint32_t page_alignment;      /* 0: as baked */
    const char *from_exr_dir;     /* NULL: no import */
} tl_lmap_layout_options;

/* Rewrites an LMAP payload. *out stays NULL when nothing needs to change (the caller ships the
 * original bytes); otherwise it is malloc'ed. Returns a tl_convert_status. */
int tl_lmap_rewrite(const void *lmap, size_t size, const tl_lmap_layout_options *options, void **out, size_t *out_size,
                    uint32_t *pages_imported, char err[TL_ERR_LEN]);

#endif
