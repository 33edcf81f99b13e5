/* Local Light Grids (seed 001 §2.2): per object an oriented bounding box from an area-weighted
 * PCA, a regular probe lattice slightly larger than the box (default one probe per 1.5 m, at
 * least 2 per axis, capped per grid), and per-vertex self-visibility (unoccluded fraction and
 * bent normal) against the object's OWN triangles only, so it stays valid for every instance.
 * Which objects get an LLG is the classifier's decision, not this module's. See bake/probes/PROBES.md. */
#ifndef BK_LLG_PLACE_H
#define BK_LLG_PLACE_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"
#include "lbk/lbk.h"
#include "lbk/llg.h"

#define BK_LLG_MAX_DIM 64u  /* lbk/llg.h: LBK_LLG_MAX_DIM */

typedef struct bk_llg_options {   /* zero-initialised = defaults */
    float spacing;                /* metres between probes; 0: 1.5. An object with
                                     lighting == BK_LIGHTING_LLG and texel_density > 0 uses
                                     1 / texel_density instead (density in probes per metre) */
    size_t max_probes;            /* per grid; the spacing grows until the lattice fits; 0: 512,
                                     never below 8 */
    float margin;                 /* the lattice box exceeds the OBB by this on every side;
                                     0: 10% of the OBB's largest half-extent */
    float min_half_extent;        /* floor for flat/line objects; 0: 5% of the largest
                                     half-extent (1 mm for a point-like object) */
    int visibility_rays;          /* cosine-distributed rays per vertex; 0: 64, at most 4096 */
    /* 1: the object connects to another (bk_llg_connections): its spacing is multiplied by
     * connected_scale, so the lighting gradient across the joint is sampled on both sides
     * (seed 001 §2.2 "extra probes for objects that can be connected"); the cap still applies */
    int connected;
    float connected_scale;        /* 0: 0.5 (twice the probes per axis) */
    int min_dim;                  /* probes per axis at least (2..64); 0: 2. The baker asks 3:
                                     fitted to the vertices, 3 × 3 × 3 resolves what 2 × 2 × 2
                                     cannot (PROBES.md §LLG fit) */
} bk_llg_options;

typedef struct bk_llg {
    uint32_t object;              /* index into bk_scene.objects */
    /* the tight OBB of the object: centre, unit axes (right-handed, axes[0] the direction of
     * largest spread, each axis' largest component positive except axes[2] = axes[0]×axes[1]) */
    float centre[3];
    float axes[3][3];
    float obb_half_extents[3];
    /* the lattice box: same centre/axes, half extents = OBB (floored) + margin */
    float half_extents[3];
    uint32_t dims[3];             /* probes per axis, 2..64 (the spacing grows to fit) */
    float spacing;                /* requested spacing after the cap (actual per-axis step is
                                     2·half_extents[a] / (dims[a] - 1) <= spacing) */
    /* per object vertex (ascending global vertex index among its triangles' corners) */
    size_t vertex_count;
    uint32_t *vertices;           /* global vertex indices */
    float *visibility;            /* unoccluded fraction of cosine-distributed rays, [0,1] */
    float *bent_normals;          /* 3 per vertex, unit: mean unoccluded direction */
} bk_llg;

/* Builds the OBB, lattice and self-visibility of scene->objects[object]. threads: 0 = all
 * cores; results do not depend on it. An object without usable triangles gives
 * LBK_ERR_INVALID_ARGUMENT. Uses its own Embree scene of the object's triangles. */
lbk_result bk_llg_place(const bk_scene *scene, uint32_t object, const bk_llg_options *options,
                        int threads, bk_llg *out);
void bk_llg_free(bk_llg *llg);

/* Probe (i, j, k) of the lattice, i fastest: centre + Σ_a axes[a]·(−h_a + 2·h_a·idx_a/(dims_a−1)). */
void bk_llg_probe_position(const bk_llg *llg, uint32_t i, uint32_t j, uint32_t k, float out[3]);
size_t bk_llg_probe_count(const bk_llg *llg);

/* The per-vertex records of the LLG section (lbk/llg.h): visibility and the bent normal in the
 * grid frame (components along axes[0..2]), in the order of llg->vertices. out: vertex_count. */
void bk_llg_vertex_records(const bk_llg *llg, lbk_llg_vertex *out);
/* The record of vertex v alone (what bk_llg_vertex_records writes at out[v]). */
void bk_llg_vertex_record(const bk_llg *llg, size_t v, lbk_llg_vertex *out);

/* The seed's connected-objects heuristic (PROBES.md): of the objects with candidate[i] != 0,
 * out[i] = 1 when the world-space bounding box of another candidate lies within `gap` of its
 * own (touching or overlapping) and neither box contains the other (a prop standing inside
 * another's box is not a joint); else 0. candidate and out: scene->object_count entries.
 * gap <= 0: 1 cm. O(n log n + touching pairs). */
lbk_result bk_llg_connections(const bk_scene *scene, const uint8_t *candidate, float gap, uint8_t *out);

/* OBB only (area-weighted PCA), exposed for tests: centre, axes, half extents (tight). */
lbk_result bk_obb_from_triangles(const bk_scene *scene, uint32_t first_tri, uint32_t tri_count,
                                 float centre[3], float axes[3][3], float half_extents[3]);

#endif
