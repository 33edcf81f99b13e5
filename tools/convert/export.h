/* lbk export: decoded pages, AHD planes, per-object images, probe listings and the GLG plot.
 * File names and contents: tools/convert/README.md "Export". */
#ifndef LBK_TOOLS_EXPORT_H
#define LBK_TOOLS_EXPORT_H

#include "tools/common/bake_data.h"

typedef struct tl_export_options {
    const char *exr_dir;  /* NULL: no EXR */
    const char *png_dir;  /* NULL: no PNG */
    int per_object;       /* also one image per lightmapped object */
} tl_export_options;

typedef struct tl_export_stats {
    uint32_t exr_files, png_files, text_files;
    float exposure;       /* the tone-map exposure used for the page previews */
} tl_export_stats;

/* Returns 0, or -1 with err (an I/O error: a file could not be written). */
int tl_export(const tl_bake *bake, const tl_export_options *options, tl_export_stats *stats, char err[TL_ERR_LEN]);

/* The OCTP probe volume's atlases (octp_level_L.exr, octp_level_L.depth.exr per clip level) into
 * dir; 0 without a volume (a list-form OCTP has no grid to lay out). Returns 0 or -1 with err. */
int tl_export_octp(const tl_bake *bake, const char *dir, tl_export_stats *stats, char err[TL_ERR_LEN]);

/* Object → file name stem "NNN_name": NNN is the object's index in OBJS (3+ digits, so stems
 * never clash), name with bytes outside [A-Za-z0-9._-] replaced by '_', cut at 64 bytes. */
void tl_export_object_stem(const char *name, uint32_t index, char *out, size_t size);

#endif
