/* LMAP payload rewriting for convert: page layout the runtime needs (row pitch, page alignment),
 * importing edited pages from EXR files written by `lbk export`, and renumbering the DLS texel
 * targets when pages are widened. */
#ifndef LBK_TOOLS_LMAP_LAYOUT_H
#define LBK_TOOLS_LMAP_LAYOUT_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/image_io.h"

typedef struct tl_lmap_layout_options {
    uint32_t row_pitch_alignment; /* 0: no requirement */
    uint32_t page_alignment;      /* 0: no requirement (checked only; the format fixes placement) */
    const char *from_exr_dir;     /* NULL: no import */
    uint32_t format[2];           /* plane encodings of the output (lbk_lmap_format0/1); 0, 0: 1.0 planes */
    const void *objs;             /* the OBJS payload (which texels objects use, for the block encoders), or NULL */
    size_t objs_size;
    double *encode_seconds;       /* when non-NULL, += the time spent block-encoding */
    uint32_t max_page;            /* a page wider or taller than this after padding is refused; 0: none */
} tl_lmap_layout_options;

/* How texel indices move when pages are widened (identity when no page changed width). */
typedef struct tl_texel_remap {
    uint32_t page_count;
    uint32_t *old_width, *new_width, *height;
    uint64_t *old_first, *new_first;
    uint64_t old_total, new_total;
    int identity;
} tl_texel_remap;

void tl_texel_remap_free(tl_texel_remap *remap);
/* Maps an old global texel index to the new one; returns -1 if it is out of range. */
int tl_texel_remap_apply(const tl_texel_remap *remap, uint64_t old_index, uint64_t *new_index);

/* File names shared by export and import: "<dir>/page_NNN.exr" (NNN = 3+ digits, zero padded). */
void tl_page_exr_path(char *out, size_t size, const char *dir, uint32_t page, const char *suffix);

/* Rewrites an LMAP payload. *out stays NULL when nothing needs to change (the caller ships the
 * original bytes); otherwise it is malloc'ed. remap is always filled in (free it).
 * Returns a tl_convert_status. */
int tl_lmap_rewrite(const void *lmap, size_t size, const tl_lmap_layout_options *options, void **out, size_t *out_size,
                    uint32_t *pages_imported, tl_texel_remap *remap, char err[TL_ERR_LEN]);

/* Rebuilds a DLS payload with texel targets renumbered by remap (sets, kinds, lights, members
 * and every entry kept). *out is malloc'ed. Returns a tl_convert_status. */
int tl_dls_remap_texels(const void *dls, size_t size, const tl_texel_remap *remap, void **out, size_t *out_size,
                        char err[TL_ERR_LEN]);

#endif
