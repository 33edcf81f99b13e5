/* A container opened for the tools (diff, export): validated, with a view on every section the
 * tools read, and the lighting sample points they compare and export. */
#ifndef LBK_TOOLS_BAKE_DATA_H
#define LBK_TOOLS_BAKE_DATA_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/image_io.h"
#include "lbk/error_map.h"
#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/lightmap_uv.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/octa.h"
#include "lbk/report.h"

typedef enum tl_open_status {
    TL_OPEN_OK = 0,
    TL_OPEN_IO,      /* the file could not be read */
    TL_OPEN_INVALID, /* not a valid container (lbk validate reports why) */
    TL_OPEN_INTERNAL
} tl_open_status;

typedef struct tl_bake {
    void *bytes; /* owned file bytes */
    size_t size;
    lbk_reader *reader;
    int has_meta, has_objs, has_lmap, has_glg, has_llg, has_octp, has_lmuv, has_rept, has_terr;
    lbk_meta_view meta;
    lbk_objects_view objs;
    lbk_lmap_view lmap;
    lbk_glg_view glg;
    lbk_llg_view llg;
    lbk_octp_view octp;
    lbk_lmuv_view lmuv;
    lbk_report_view rept;
    lbk_terr_view terr; /* the per-texel error map (format 1.4), when has_terr */
    lbk_report_record rept_last; /* the final estimate, when has_rept */
    lbk_dls_view *dls;   /* NULL when absent */
    lbk_door_view *door; /* NULL when absent */
    /* per LMAP page: its texels decoded when the page is block-encoded (spec §9.2), else NULL */
    lbk_ahd_texel_f **block_pages;
} tl_bake;

/* Reads and validates a file and opens every section view. */
tl_open_status tl_bake_open_file(const char *path, tl_bake *out, char err[TL_ERR_LEN]);
/* The same with a cap on the bytes decoded sections may take (lbk_read_options.max_decoded_bytes;
 * 0: liblbk's default, spec §4.3): a file that would need more is refused before it is
 * allocated (`--max-memory`). */
tl_open_status tl_bake_open_file_capped(const char *path, uint64_t max_decoded_bytes, tl_bake *out, char err[TL_ERR_LEN]);
/* Same over a copy of caller bytes. */
tl_open_status tl_bake_open_memory(const void *data, size_t size, tl_bake *out, char err[TL_ERR_LEN]);
void tl_bake_close(tl_bake *bake);

/* ---- how lighting is sampled for comparison (spec/diff-json.md "Error metric") -------------- */
#define TL_TEXEL_NORMALS 5 /* +Z and the four normals tilted 45° toward ±X, ±Y (tangent space) */
#define TL_PROBE_NORMALS 6 /* ±X, ±Y, ±Z (world space) */
extern const float tl_texel_normals[TL_TEXEL_NORMALS][3];
extern const float tl_probe_normals[TL_PROBE_NORMALS][3];
/* Physical irradiance of texel (x, y) of LMAP page `page` at the five normals, for any encoding:
 * the stored texel's (tl_texel_eval) on a 1.0 page, the decoded one's on a block page. 0, or -1
 * outside the page. */
int tl_bake_texel_eval(const tl_bake *b, uint32_t page, uint32_t x, uint32_t y, float out[TL_TEXEL_NORMALS][3]);
/* Texel (x, y) of page `page` as floats (stored units) with its linear form and its unit highlight
 * direction, any encoding: on a 1.0 page exactly the 1.0 decoder's (lbk_ahd_to_linear on the stored
 * bytes). Any output may be NULL. 0, or -1 outside the page. */
int tl_bake_texel_get(const tl_bake *b, uint32_t page, uint32_t x, uint32_t y, lbk_ahd_texel_f *texel,
                      lbk_ahd_linear *linear, float dir[3]);
/* Page p's planes (lbk_lmap_planes_get); 0 or -1. */
int tl_bake_planes(const tl_bake *b, uint32_t page, lbk_lmap_planes *out);

/* Physical irradiance of a stored texel at the five normals (decoded × the LMAP scale, or the
 * scale of the base section a DLS payload belongs to): out[n][channel]. */
void tl_texel_eval(const lbk_ahd_texel *texel, float scale, float out[TL_TEXEL_NORMALS][3]);
/* Irradiance of a (physical) radiance SH at the six axis normals. */
void tl_probe_eval(const lbk_sh9_rgb *sh, float out[TL_PROBE_NORMALS][3]);
/* Physical radiance SH of a packed probe stored in a section (or DLS space) of that scale. */
void tl_probe_unpack(const uint8_t packed[LBK_SH9_PACKED_SIZE], float scale, lbk_sh9_rgb *sh);

/* Object name as a NUL-terminated string (truncated to size-1 bytes). */
void tl_string_copy(char *dst, size_t size, lbk_string s);

#endif
