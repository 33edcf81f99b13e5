/* Which lighting representation each object gets: a lightmap, a local light grid (LLG), or
 * nothing.
 *
 * bk_object.lighting (glTF extras lbk_lighting) is always honoured. For AUTO, the first rule
 * that applies decides (thresholds are options; defaults in brackets):
 *   1. EMPTY      no triangle with area                                  → none
 *   2. EMISSIVE   every triangle emits (emission factor > 0 in some channel, and when an
 *                 emission texture is used, no texel of it is black), and the object is not
 *                 in a dynamic light set                                  → none
 *                 Why: its look is its own emission; the light it receives is not stored
 *                 (the runtime shades it emissive). An emitter in a dynamic light set can be
 *                 switched off, and then it must be lit like anything else, so rule 2 skips it.
 *                 A weak emitter that should still be lit: set lbk_lighting = "lightmap".
 *   3. DOOR       it is a door (lbk_door): it moves, so a lightmap would be wrong once it
 *                 opens                                                   → LLG
 *   4. INTRICATE  more than intricate_density [500] triangles per m² of surface: charts
 *                 would shatter into hundreds of texel-sized islands      → LLG
 *   5. SMALL      bounding-box diagonal below small_diagonal [2 m] and more than
 *                 simple_tris [64] triangles (a small but detailed prop: a few texels per
 *                 chart, most of them padding)                          → LLG
 *                 A small simple object (a box, a plank: <= 64 triangles) keeps a lightmap:
 *                 it costs a few texels and resolves contact shadows better than a grid.
 *   6. DEFAULT    otherwise                                               → lightmap
 * E.g. room_with_doors: each sphere (r 0.5 m, 3,968 triangles, ~1,260 per m²) → LLG by
 * rule 4; the room (232 triangles, 15 m diagonal) → lightmap. */
#ifndef BK_CLASSIFY_H
#define BK_CLASSIFY_H

#include <stdint.h>

#include "lbk/lbk.h"
#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

enum bk_representation { BK_REP_NONE = 0, BK_REP_LIGHTMAP = 1, BK_REP_LLG = 2 };

enum bk_rep_reason {
    BK_REASON_AUTHORED = 0,  /* lbk_lighting set on the node */
    BK_REASON_EMPTY,
    BK_REASON_EMISSIVE,
    BK_REASON_DOOR,
    BK_REASON_INTRICATE,
    BK_REASON_SMALL,
    BK_REASON_DEFAULT
};

typedef struct bk_classify_options {
    float small_diagonal;     /* metres; 0: 2 */
    uint32_t simple_tris;     /* 0: 64 */
    float intricate_density;  /* triangles per m²; 0: 500 */
} bk_classify_options;

typedef struct bk_object_class {
    int rep;                  /* enum bk_representation */
    int reason;               /* enum bk_rep_reason */
    float diagonal;           /* world bounding-box diagonal of its triangles with area, m */
    float area;               /* world surface area, m² */
    uint32_t live_tris;       /* triangles with area */
} bk_object_class;

/* out: scene->object_count entries. opt may be NULL. Errors: LBK_ERR_INVALID_ARGUMENT,
 * LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_classify_objects(const bk_scene *scene, const bk_classify_options *opt, bk_object_class *out);

/* "none", "lightmap", "llg"; and "authored", "empty", "emissive", "door", "intricate",
 * "small", "default". Never NULL. */
const char *bk_rep_name(int rep);
const char *bk_rep_reason_name(int reason);

#ifdef __cplusplus
}
#endif
#endif
