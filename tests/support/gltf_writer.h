/* A tiny glTF 2.0 writer for baker tests and benches: builds a .gltf whose buffer is embedded as
 * a base64 data: URI, so a test can generate a level, run the whole pipeline
 * (lbk_bake_from_file) on it and delete it afterwards. Only what the stability tests need: one triangle primitive per mesh
 * node, POSITION (+ indices or not), materials with baseColorFactor / emissiveFactor /
 * KHR_materials_emissive_strength / doubleSided, KHR_lights_punctual point lights, node
 * translation, node extras lbk_lighting and scene extras lbk_sky.
 *
 * Positions are written as given, bit for bit: NaN, zero-area triangles and duplicate vertices
 * reach the importer unchanged (the writer is meant to produce bad input too). Builders abort
 * on allocation failure (tests only). */
#ifndef GW_GLTF_WRITER_H
#define GW_GLTF_WRITER_H

#include <stddef.h>
#include <stdint.h>

/* Triangle soup under construction: positions (3 floats per vertex) and indices. */
typedef struct gw_geom {
    float *pos;
    size_t vertex_count, vertex_cap;
    uint32_t *idx;
    size_t index_count, index_cap;
} gw_geom;

void gw_geom_free(gw_geom *g);
uint32_t gw_geom_vertex(gw_geom *g, float x, float y, float z);
void gw_geom_tri(gw_geom *g, uint32_t a, uint32_t b, uint32_t c);
/* Quad p0 p1 p2 p3 (counter-clockwise seen from the front), n×n cells, shared vertices. */
void gw_geom_quad(gw_geom *g, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n);
/* Axis-aligned box [mn, mx], each face n×n cells; inward = 1: faces look into the box (a room),
 * 0: outward (a solid block). */
void gw_geom_box(gw_geom *g, const float mn[3], const float mx[3], int n, int inward);
/* Every vertex p ← p·scale (per component, in float). */
void gw_geom_scale(gw_geom *g, float scale);

typedef struct gw_scene gw_scene;

gw_scene *gw_create(void);
void gw_free(gw_scene *s);
/* Returns the material index. emission is emissiveFactor (each ≤ 1 by glTF's schema) and
 * strength KHR_materials_emissive_strength (≤ 0: not written). */
int gw_material(gw_scene *s, const float albedo[3], const float emission[3], float strength, int double_sided);
/* One node with one mesh of one triangle primitive. indexed = 0 writes the triangles as a
 * non-indexed vertex list (each index expanded). translation may be NULL. lighting: value of
 * the node's lbk_lighting extras key, NULL for none. */
void gw_mesh(gw_scene *s, const char *name, const gw_geom *g, int material, int indexed, const double translation[3],
             const char *lighting);
/* KHR_lights_punctual point light (candela) on its own node. */
void gw_point_light(gw_scene *s, const float color[3], float intensity, const double position[3]);
/* Scene extras lbk_sky = [r, g, b]. */
void gw_sky(gw_scene *s, const float rgb[3]);
/* Writes the .gltf; 0 on success. */
int gw_write(const gw_scene *s, const char *path);

#endif
