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
 * leaves the section valid. CPU-only: an engine uses it when it builds meshes, after checking
 * that each record describes the mesh it loaded (lbk_lmuv_object_check, below).
 *
 * Thread safety: every function is safe to call from any thread (views are read only). */
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

/* ---- checking a record against the mesh it names (§16.4; liblbk 1.5) ----------------------
 * liblbk never reads glTF, so lbk_validate cannot tell whether a record describes the mesh the
 * engine loaded; a record that does not (another level's file, a re-exported glTF, damage with
 * repaired checksums) would put lightmap texels on the wrong triangles. Before using a record,
 * describe the node's mesh as your glTF loader decoded it and call lbk_lmuv_object_check: it is
 * the one check lbk render, lbk export --gltf and lbk view make, so they and an engine accept
 * and refuse the same files.
 *
 *     lbk_lmuv_mesh_primitive prims[n];   // per triangle primitive of the node's mesh, ascending:
 *     prims[k] = (lbk_lmuv_mesh_primitive){.source_primitive = index in mesh.primitives,
 *         .source_vertex_count = POSITION count, .triangle_count = triangles,
 *         .flags = has NORMAL ? 0 : LBK_LMUV_MESH_NO_NORMAL, .corners = 3 per triangle};
 *     lbk_lmuv_mesh_desc mesh = LBK_LMUV_MESH_DESC_INIT;
 *     mesh.source_node = node; mesh.primitive_count = n; mesh.primitives = prims;
 *     lbk_lmuv_check_detail why;
 *     if (lbk_lmuv_object_check(&view, &record, &mesh, &why) != LBK_OK) refuse(why.message);
 */

/* Set in lbk_lmuv_mesh_primitive.flags when the glTF primitive has no NORMAL attribute: glTF
 * shades it flat, so the baker gives every triangle corner its own new vertex (§16.4). */
#define LBK_LMUV_MESH_NO_NORMAL 1u

/* One triangle primitive of the node's mesh (mode 4, 5 or 6 with at least one triangle) as the
 * caller's loader decoded it. An array element: frozen. */
typedef struct lbk_lmuv_mesh_primitive {
    uint32_t source_primitive;    /* index in the glTF mesh's primitives array */
    uint32_t source_vertex_count; /* POSITION count (the decoded point count for Draco) */
    uint32_t triangle_count;      /* the triangles it defines: strips and fans expanded in glTF
                                     order, strip triangles with a repeated index dropped */
    uint32_t flags;               /* LBK_LMUV_MESH_NO_NORMAL or 0; other bits 0 */
    const uint32_t *corners;      /* 3 × triangle_count: the source vertex at each corner of
                                     triangle j, in the primitive's own winding (never the one a
                                     mirroring node transform gives) */
} lbk_lmuv_mesh_primitive;

/* Size-tagged (lbk.h): set size with LBK_LMUV_MESH_DESC_INIT; size 0 reads as this, its first
 * layout. */
typedef struct lbk_lmuv_mesh_desc {
    size_t size;
    uint32_t source_node;     /* the glTF node (index into nodes) the engine drew the mesh for */
    uint32_t primitive_count; /* the mesh's triangle primitives, ascending by source_primitive */
    const lbk_lmuv_mesh_primitive *primitives;
} lbk_lmuv_mesh_desc;
#define LBK_LMUV_MESH_DESC_INIT LBK_SIZED_INIT(lbk_lmuv_mesh_desc)

/* Why lbk_lmuv_object_check refused. Codes are never renumbered; new ones are appended. */
typedef enum lbk_lmuv_check_code {
    LBK_LMUV_CHECK_OK = 0,
    /* the record does not describe the mesh (LBK_ERR_MISMATCH) */
    LBK_LMUV_CHECK_NODE,                /* the record names another glTF node */
    LBK_LMUV_CHECK_PRIMITIVE_COUNT,     /* GENERATED: another number of triangle primitives */
    LBK_LMUV_CHECK_SOURCE_PRIMITIVE,    /* primitive k is another glTF primitive */
    LBK_LMUV_CHECK_SOURCE_VERTEX_COUNT, /* primitive k's glTF primitive has another vertex count */
    LBK_LMUV_CHECK_TRIANGLE_COUNT,      /* primitive k has another number of triangles */
    LBK_LMUV_CHECK_CORNER,              /* the new vertex at a corner copies another source vertex */
    LBK_LMUV_CHECK_VERTEX_ORDER,        /* the new vertices are not in §16.4's order */
    /* the caller's description is unusable (LBK_ERR_INVALID_ARGUMENT) */
    LBK_LMUV_CHECK_MESH_CORNER,         /* a corner names a vertex >= its source_vertex_count */
    LBK_LMUV_CHECK_MESH_FLAGS,          /* unknown flag bits */
    LBK_LMUV_CHECK_CODE_COUNT_          /* not part of the ABI */
} lbk_lmuv_check_code;

/* What lbk_lmuv_object_check found (filled by the library: frozen). */
typedef struct lbk_lmuv_check_detail {
    uint32_t code;          /* lbk_lmuv_check_code */
    uint32_t primitive;     /* position in desc->primitives (and in the record); 0 for NODE and
                               PRIMITIVE_COUNT */
    uint32_t triangle;      /* CORNER, MESH_CORNER: the triangle; VERTEX_ORDER: the new vertex
                               out of order (with NORMAL) or the corner (without; 0 when the
                               vertex count is not the corner count) */
    uint32_t corner;        /* CORNER, MESH_CORNER: 0..2 */
    uint64_t record_value;  /* what the record has (node, count, source vertex, ...) */
    uint64_t mesh_value;    /* what the mesh has */
    char message[160];      /* English, one line, with the values; "" when the check passed */
} lbk_lmuv_check_detail;

/* Checks that `record` (of `view`, from lbk_lmuv_get_object or _find_object) describes `mesh`:
 * the glTF node; for a GENERATED record also, per primitive in order, the source primitive,
 * source vertex count and triangle count (index_count = 3 × triangle_count); at every corner c
 * of every triangle j, that the new vertex indices[3j + c] copies source vertex corners[3j + c]
 * (remap); and the vertex order of §16.4: a primitive with NORMAL has its new vertices
 * ascending by source vertex (remap never decreases), one without (LBK_LMUV_MESH_NO_NORMAL) one
 * new vertex per corner, in corner order (indices[i] = i). An AUTHORED record has only its node
 * to check: the mesh's TEXCOORD_1 is the layout (§16.3), and its primitives may be left out.
 * Returns LBK_OK; LBK_ERR_MISMATCH when the record does not describe the mesh (refuse the file,
 * or the glTF: they are not a pair); LBK_ERR_INVALID_ARGUMENT for NULL pointers (detail may be
 * NULL), a record of unknown kind, a corner outside its primitive or unknown flags; LBK_ERR_RANGE
 * for a record or view whose ranges lbk_lmuv_open did not check; LBK_ERR_UNSUPPORTED_FEATURE as
 * for every size-tagged struct. The first difference found is reported in *detail (primitives
 * in order, corners in order); reads each corner once, allocates nothing. */
LBK_API lbk_result lbk_lmuv_object_check(const lbk_lmuv_view *view, const lbk_lmuv_object *record,
                                         const lbk_lmuv_mesh_desc *mesh, lbk_lmuv_check_detail *detail);
/* A stable upper-case identifier such as "LBK_LMUV_CHECK_CORNER"; never NULL. */
LBK_API const char *lbk_lmuv_check_code_name(uint32_t code);

#ifdef __cplusplus
}
#endif
#endif
