/* LMUV section (format 1.1): where every point of a lightmapped object lies in its LMAP page,
 * from the source glTF plus this section. Layout and rules: spec/container.md §16.
 *
 * Lightmap coordinates (normative, §16.1) are page texels: X to the right, Y down, (0, 0) the
 * page's top-left corner. Texel (x, y) covers [x, x+1) × [y, y+1) and its centre is
 * (x + 1/2, y + 1/2); a point at (X, Y) belongs to texel (floor X, floor Y). A renderer samples
 * the page at (u, v) = (X / width, Y / height), so texel centres sit at ((x + 1/2)/width,
 * (y + 1/2)/height), the glTF / Vulkan / D3D convention.
 *
 * One record per lightmapped object (by its OBJS index, ascending), of one of two kinds:
 *   AUTHORED  the mesh's own TEXCOORD_1 is the layout: X = offset[0] + scale[0]·u1,
 *             Y = offset[1] + scale[1]·v1 (binary32: product, then sum, each rounded);
 *   GENERATED the baker made charts; per triangle primitive of the mesh: a vertex remap (new
 *             vertex → vertex of the glTF primitive), a triangle-list index buffer over the new
 *             vertices, and the lightmap coordinate of every new vertex. An engine rebuilds the
 *             primitive: new vertex i copies all attributes of source vertex remap[i].
 * Coordinates are in texels, not normalised, so widening a page (lbk convert's row pitch)
 * leaves the section valid. CPU-only: an engine uses it when it builds meshes. */
#ifndef LBK_LIGHTMAP_UV_H
#define LBK_LIGHTMAP_UV_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_LMUV_HEADER_SIZE 32u
#define LBK_LMUV_RECORD_SIZE 56u
#define LBK_LMUV_PRIMITIVE_SIZE 32u

typedef enum lbk_lmuv_kind {
    LBK_LMUV_AUTHORED = 0,  /* TEXCOORD_1 mapped by scale and offset */
    LBK_LMUV_GENERATED = 1, /* vertex remap + index buffer + coordinates per primitive */
    LBK_LMUV_KIND_COUNT_
} lbk_lmuv_kind;

/* ---- building ------------------------------------------------------------------------------ */

typedef struct lbk_lmuv_primitive_desc {
    uint32_t source_primitive;    /* index in the glTF mesh's primitives array */
    uint32_t source_vertex_count; /* vertices of that glTF primitive */
    uint32_t vertex_count;        /* new vertices, >= 1 */
    uint32_t index_count;         /* triangle-list indices, a positive multiple of 3 */
    const uint32_t *remap;        /* vertex_count: the source vertex of each new vertex */
    const uint32_t *indices;      /* index_count: into the new vertices */
    const float *coords;          /* 2 × vertex_count: lightmap coordinate (X, Y) in page texels */
} lbk_lmuv_primitive_desc;

typedef struct lbk_lmuv_object_desc {
    uint32_t object;      /* OBJS index; records are written in the given order (ascending) */
    uint32_t kind;        /* lbk_lmuv_kind */
    uint32_t source_node; /* the glTF node whose mesh the object is */
    /* AUTHORED only (0 otherwise) */
    float scale[2], offset[2]; /* X = offset + scale · TEXCOORD_1, per axis; scale > 0 */
    float uv_min[2], uv_max[2]; /* bounding box of the object's TEXCOORD_1 */
    /* GENERATED only (0 / NULL otherwise) */
    uint32_t primitive_count;
    const lbk_lmuv_primitive_desc *primitives; /* source_primitive strictly ascending */
} lbk_lmuv_object_desc;

/* Serialises the records (deterministic; padding zero, -0 stored as +0). Rejects
 * (LBK_ERR_INVALID_ARGUMENT) count 0, objects not strictly ascending, unknown kinds, fields the
 * kind does not use that are not zero, non-finite floats, scale <= 0, uv_min > uv_max, empty
 * primitives, index counts that are not a positive multiple of 3, indices >= vertex_count and
 * remap entries >= source_vertex_count; LBK_ERR_LIMIT when the section would exceed SIZE_MAX.
 * The rectangle rules need OBJS and are checked by lbk_validate. Free *out with lbk_free. */
LBK_API lbk_result lbk_lmuv_build(const lbk_lmuv_object_desc *objects, uint32_t count, const lbk_allocator *allocator,
                                  void **out, size_t *size);

/* ---- reading ------------------------------------------------------------------------------- */

/* A read-only view into section bytes. lbk_lmuv_open checks the structure: header and layout
 * size, kinds, the packed primitive/vertex/index ranges, every index below its primitive's vertex
 * count and every remap entry below its source vertex count, so the getters below never read
 * outside the section and an engine can use the indices as they are. It does not check
 * coordinates against OBJS rectangles (lbk_validate does). */
typedef struct lbk_lmuv_view {
    const uint8_t *data;
    size_t size;
    uint32_t record_count, primitive_count;
    uint64_t vertex_count, index_count;
    const uint8_t *records, *primitives, *remap, *indices, *coords;
} lbk_lmuv_view;

typedef struct lbk_lmuv_object {
    uint32_t object, kind, source_node;
    uint32_t primitive_first, primitive_count; /* GENERATED: range in the primitive table */
    float scale[2], offset[2], uv_min[2], uv_max[2];
} lbk_lmuv_object;

typedef struct lbk_lmuv_primitive {
    uint32_t source_primitive, source_vertex_count, vertex_count, index_count;
    uint64_t vertex_first, index_first; /* into the section's remap/coords and index arrays */
} lbk_lmuv_primitive;

LBK_API lbk_result lbk_lmuv_open(const void *data, size_t size, lbk_lmuv_view *out);
LBK_API lbk_result lbk_lmuv_get_object(const lbk_lmuv_view *view, uint32_t record, lbk_lmuv_object *out);
/* The record of OBJS object `object` (binary search); LBK_ERR_NOT_FOUND when it has none. */
LBK_API lbk_result lbk_lmuv_find_object(const lbk_lmuv_view *view, uint32_t object, uint32_t *record);
LBK_API lbk_result lbk_lmuv_get_primitive(const lbk_lmuv_view *view, uint32_t primitive, lbk_lmuv_primitive *out);
/* New vertex v (< vertex_count) of a primitive: its source vertex and lightmap coordinate. */
LBK_API lbk_result lbk_lmuv_vertex(const lbk_lmuv_view *view, const lbk_lmuv_primitive *primitive, uint32_t v,
                                   uint32_t *source, float coord[2]);
/* Index i (< index_count) of a primitive's new triangle list. */
LBK_API lbk_result lbk_lmuv_index(const lbk_lmuv_view *view, const lbk_lmuv_primitive *primitive, uint32_t i,
                                  uint32_t *index);

/* ---- the rule (§16.1, §16.3) --------------------------------------------------------------- */

/* AUTHORED: the lightmap coordinate of a TEXCOORD_1 value, in binary32 as the spec evaluates it. */
LBK_API void lbk_lmuv_authored_coord(const lbk_lmuv_object *object, const float uv1[2], float coord[2]);
/* The texel a lightmap coordinate belongs to: (floor X, floor Y). */
LBK_API void lbk_lmuv_texel_of(const float coord[2], int64_t *x, int64_t *y);
/* Normalised sampling uv of a coordinate on a page of that size: (X / width, Y / height). */
LBK_API void lbk_lmuv_normalized(const float coord[2], uint32_t page_width, uint32_t page_height, float uv[2]);

LBK_API const char *lbk_lmuv_kind_name(uint32_t kind); /* "authored", "generated", "unknown" */

#ifdef __cplusplus
}
#endif
#endif
