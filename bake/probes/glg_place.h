/* Global Light Grid: automatic probe placement over the level's empty space, its Delaunay
 * tetrahedralisation and per-face visibility (seed 001 §2.2; Iwanicki & Sloan 2017).
 * The rules (refinement, solid test, push-out, cap, when there is no GLG) are in bake/probes/PROBES.md. */
#ifndef BK_GLG_PLACE_H
#define BK_GLG_PLACE_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"
#include "scene/tracer.h"
#include "lbk/lbk.h"

/* Lighting at n points for the GLG's density rule: 7 floats per point, the luminance of the
 * irradiance towards +x, −x, +y, −y, +z, −z, then the variance of the estimate's noise (one
 * number for the six; 0 when exact or unknown). Must be deterministic (same points, same numbers).
 * bk_glg_coarse_lighting (bake/probes/glg_coarse.h) is the transport's. */
typedef lbk_result (*bk_glg_lighting_fn)(void *user, const float *points, size_t n, float *out);

/* The probe cap when none is given: seed 001's production levels hold 150–230 k probes;
 * Delaunay and the runtime walk at this count are measured by bench/bench_glg_scale.c. */
#define BK_GLG_DEFAULT_MAX_PROBES 262144u

typedef struct bk_glg_options {   /* zero-initialised = defaults */
    float spacing;                /* largest probe spacing, metres; 0: 1.0 */
    int refine_levels;            /* halvings of the spacing in cells that hold geometry;
                                     0: 1 (half spacing near surfaces); -1: none; at most 4 */
    float min_distance;           /* probes closer to a surface are pushed out (or dropped);
                                     0: a quarter of the finest spacing */
    size_t max_probes;            /* cap; reached by coarsening; 0: BK_GLG_DEFAULT_MAX_PROBES */
    int solid_rays;               /* rays of the inside-solid / distance test; 0: 32 */
    int face_visibility_level;    /* each face is split into 4^level triangles, one ray to the
                                     centroid of each; 0: 1 (4 rays per face), at most 4 */
    /* Adaptive density (PROBES.md §Density by playable space and lighting). With playable boxes
     * in the scene or a lighting function, the top grid is 2 × spacing (coarser) and a top cell is
     * split unconditionally `depth` times before the near-geometry refinement, depth the larger
     * of the playable and the lighting rule's. Neither: the placement above, unchanged. */
    int playable_levels;          /* depth of a top cell overlapping a playable box; 0: 1;
                                     -1: ignore the scene's playable boxes; at most 2 */
    bk_glg_lighting_fn lighting;  /* NULL: no lighting rule */
    void *lighting_user;
    float lighting_threshold;     /* relative interpolation error (of the mean irradiance) that
                                     asks for a finer grid (PROBES.md); 0: 0.4 (bench_glg) */
    int lighting_levels;          /* most depth the lighting rule gives; 0: 2; at most 3 */
} bk_glg_options;

/* Why a scene gets no GLG (bk_glg.status). */
enum bk_glg_status {
    BK_GLG_OK = 0,
    BK_GLG_EMPTY_SCENE,           /* no geometry: no bounds to fill */
    BK_GLG_NO_FREE_SPACE,         /* fewer than 4 probes survived the solid/clearance tests */
    BK_GLG_FLAT,                  /* the surviving probes lie on one plane (e.g. a 1-layer level) */
    BK_GLG_DELAUNAY_FAILED        /* qhull gave up (not seen in testing): warn, write no GLG */
};

typedef struct bk_glg_probes {    /* placement only */
    size_t count;
    float *positions;             /* 3 per probe, world space */
    float spacing;                /* top-level spacing actually used (after coarsening) */
    int refine_levels;            /* refinement actually used */
    size_t candidates;            /* cell centres considered */
    size_t rejected_solid;        /* inside closed geometry (more back- than front-face hits) */
    size_t rejected_close;        /* still within min_distance after push-out */
    size_t pushed;                /* moved away from a surface */
    size_t coarse_points;         /* lighting rule: top-cell centres whose lighting was evaluated */
    size_t cells_by_depth[4];     /* adaptive: top cells given depth 0..3 */
} bk_glg_probes;

typedef struct bk_glg {
    int status;                   /* enum bk_glg_status; anything but OK: write no GLG */
    size_t probe_count;
    float *positions;             /* 3 per probe */
    size_t tet_count;
    uint32_t *tets;               /* 4 per tetrahedron, positively oriented (bake/probes/delaunay.h) */
    uint32_t *neighbours;         /* 4 per tetrahedron: across the face opposite vertex i, or
                                     0xFFFFFFFF on the hull */
    float *face_visibility;       /* 4 per tetrahedron: fraction in [0,1] of unoccluded rays
                                     from vertex i to stratified points of the opposite face */
    float spacing;                /* placement diagnostics */
    int refine_levels;
    /* the tetrahedralisation's path (bk_tetmesh, PROBES.md) and its seconds */
    int merged_cells, hull_ghosts;
    size_t pocket_tets;
    double delaunay_seconds;
} bk_glg;

/* Places probes. On success out->count may be 0 (see PROBES.md). Errors: invalid argument,
 * out of memory. threads: 0 = all cores; results do not depend on it. */
lbk_result bk_glg_place(const bk_scene *scene, const bk_tracer *tracer,
                        const bk_glg_options *options, int threads, bk_glg_probes *out);
void bk_glg_probes_free(bk_glg_probes *probes);

/* Placement + tetrahedralisation + per-face visibility: everything the GLG section needs
 * except the lighting. out->status tells whether the scene gets a GLG. */
lbk_result bk_glg_build(const bk_scene *scene, const bk_tracer *tracer,
                        const bk_glg_options *options, int threads, bk_glg *out);
void bk_glg_free(bk_glg *glg);

/* Per-face visibility of an existing tetrahedral mesh (used by bk_glg_build; exposed for tests
 * and for re-running after positions change). vis receives 4 floats per tetrahedron. */
void bk_glg_face_visibility(const bk_tracer *tracer, const float *positions, size_t tet_count,
                            const uint32_t *tets, int level, int threads, float *vis);

/* Face visibility in the GLG section's encoding (lbk/glg.h): unorm8, round(v · 255). */
void bk_glg_visibility_unorm8(const bk_glg *glg, uint8_t (*out)[4]);

#endif
