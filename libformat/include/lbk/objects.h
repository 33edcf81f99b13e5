/* OBJS: the object table — name, geometry hash and representation of every baked object, so
 * tools can match objects across revisions. Layout: spec/container.md §8.
 *
 * Thread safety: every function is safe to call from any thread; views are read-only. */
#ifndef LBK_OBJECTS_H
#define LBK_OBJECTS_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_OBJECTS_HEADER_SIZE 16u
#define LBK_OBJECTS_RECORD_SIZE 40u

typedef enum lbk_representation {
    LBK_REPRESENTATION_LIGHTMAP = 0, /* a rectangle of texels in an LMAP page */
    LBK_REPRESENTATION_LLG = 1,      /* a local light grid of the LLG section */
    LBK_REPRESENTATION_NONE = 2,     /* not lit by the bake (e.g. a hidden or emissive-only mesh) */
    LBK_REPRESENTATION_COUNT_
} lbk_representation;

/* Builder input and lbk_objects_get output (an array element: frozen). */
typedef struct lbk_object {
    lbk_string name;          /* unique within the file; UTF-8, no NUL, not empty */
    uint64_t geometry_hash;   /* lbk_objects_geometry_hash of its world-space triangles */
    uint32_t representation;  /* lbk_representation */
    uint32_t index;           /* LIGHTMAP: page index; LLG: grid index; NONE: 0 */
    uint32_t rect_x, rect_y;  /* LIGHTMAP: texel rectangle in the page; otherwise 0 */
    uint32_t rect_w, rect_h;
} lbk_object;

/* Builds OBJS bytes, objects in the given order. Rejects (LBK_ERR_INVALID_ARGUMENT) empty or
 * non-UTF-8 names, unknown representations, non-zero unused fields and empty rectangles.
 * Duplicate names are accepted (the validator warns). Free *out with lbk_free. */
LBK_API lbk_result lbk_objects_build(const lbk_object *objects, uint32_t count, const lbk_allocator *allocator,
                                     void **out, size_t *size);

typedef struct lbk_objects_view {
    const uint8_t *records; /* count × 40 bytes */
    const uint8_t *names;   /* the name blob */
    uint32_t count;
    uint32_t names_size;
} lbk_objects_view;

/* Checks the sizes and that every name lies inside the blob, then fills the view. */
LBK_API lbk_result lbk_objects_open(const void *data, size_t size, lbk_objects_view *out);
LBK_API lbk_result lbk_objects_get(const lbk_objects_view *view, uint32_t index, lbk_object *out);
/* First object with this name; LBK_ERR_NOT_FOUND if none. */
LBK_API lbk_result lbk_objects_find(const lbk_objects_view *view, lbk_string name, uint32_t *index);

/* The geometry hash of §8.3: XXH3-64 over the little-endian f32 world-space vertex positions of
 * the triangles in order (x0 y0 z0 x1 y1 z1 x2 y2 z2 per triangle), with -0 written as +0.
 * `xyz` holds 9 × triangle_count floats. */
LBK_API uint64_t lbk_objects_geometry_hash(const float *xyz, size_t triangle_count);

/* Whether OBJS object `object` is the geometry the caller loaded (liblbk 1.5): its geometry_hash
 * against lbk_objects_geometry_hash(xyz, triangle_count) of the node's world-space triangles in
 * the baker's order (§8.3). The check every reader that draws a level with its glTF makes
 * before using the object's lighting (lbk render, lbk export --gltf, lbk view). LBK_OK;
 * LBK_ERR_MISMATCH when they differ (another level's file, or an edited glTF); LBK_ERR_NOT_FOUND
 * past the table; LBK_ERR_INVALID_ARGUMENT for a NULL view, NULL xyz with triangles, or a
 * triangle count whose 9 floats per triangle do not fit in memory. */
LBK_API lbk_result lbk_objects_geometry_check(const lbk_objects_view *view, uint32_t object, const float *xyz,
                                              size_t triangle_count);

LBK_API const char *lbk_representation_name(uint32_t representation); /* "lightmap", "llg", "none", "unknown" */

#ifdef __cplusplus
}
#endif
#endif
