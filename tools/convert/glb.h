/* A small glTF 2.0 binary (.glb) builder over cJSON: one buffer (the GLB BIN chunk), typed
 * accessors appended to it, and the file writer. Data are written little-endian. */
#ifndef LBK_TOOLS_GLB_H
#define LBK_TOOLS_GLB_H

#include <stddef.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */

/* glTF enums used here */
#define TL_GLTF_UNSIGNED_BYTE 5121
#define TL_GLTF_UNSIGNED_INT 5125
#define TL_GLTF_FLOAT 5126
#define TL_GLTF_ARRAY_BUFFER 34962
#define TL_GLTF_ELEMENT_ARRAY_BUFFER 34963

typedef struct tl_glb {
    cJSON *root;        /* the glTF JSON; the arrays below live in it */
    cJSON *buffer_views, *accessors;
    uint8_t *bin;       /* the BIN chunk */
    size_t bin_size, bin_cap;
    int failed;         /* an allocation failed: every later call is a no-op, write reports it */
} tl_glb;

/* root gets "asset" (version 2.0, generator) and empty bufferViews/accessors arrays. Returns -1
 * when out of memory. */
int tl_glb_init(tl_glb *g, const char *generator);
void tl_glb_free(tl_glb *g);

/* An accessor over `count` elements of `components` (1 SCALAR, 2 VEC2, 3 VEC3, 4 VEC4) of
 * `component_type`, copied from host data into a bufferView of its own (4-byte aligned).
 * target: 0 (data only), TL_GLTF_ARRAY_BUFFER or TL_GLTF_ELEMENT_ARRAY_BUFFER. min_max: write the
 * per-component min and max (required for POSITION). Returns the accessor index, -1 on failure. */
int tl_glb_accessor_f32(tl_glb *g, const float *data, size_t count, int components, int target, int min_max);
int tl_glb_accessor_u32(tl_glb *g, const uint32_t *data, size_t count, int target);
/* unsigned bytes read as normalised values in [0, 1] */
int tl_glb_accessor_unorm8(tl_glb *g, const uint8_t *data, size_t count);

/* Writes the GLB (header, JSON chunk padded with spaces, BIN chunk padded with zeros) through a
 * temporary file and rename. Sets root "buffers" first. Returns 0, or -1 with err. */
int tl_glb_write(tl_glb *g, const char *path, char err[TL_ERR_LEN]);

#endif
