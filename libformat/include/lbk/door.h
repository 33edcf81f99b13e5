/* Interactive elements (doors, seed 001 §4 and §6.2): per door its closed geometry as an OBB, the
 * DLS set holding the light that flows through it when open (weight ω) and the DLS set holding
 * the light that bounces off it when closed (weight 1 − ω), plus combination states whose extra
 * light lives in DLS combination sets. Normative layout: spec/container.md §13.
 *
 * Thread safety: every function is safe to call from any thread; a view may be shared once open
 * (it is read-only). */
#ifndef LBK_DOOR_H
#define LBK_DOOR_H

#include "lbk/dls.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One door (an array element: frozen). */
typedef struct lbk_door_desc {
    const char *name;         /* UTF-8, non-empty, unique among the doors */
    float centre[3];          /* OBB of the closed door, world space */
    float axes[3][3];         /* orthonormal rows */
    float half_extents[3];    /* ≥ 0, along each axis */
    uint32_t open_set;        /* DLS set of kind LBK_DLS_KIND_DOOR_OPEN */
    uint32_t closed_set;      /* DLS set of kind LBK_DLS_KIND_DOOR_CLOSED, or LBK_DLS_NO_SET */
} lbk_door_desc;

/* A combination state: these doors open (and the combination set's other members, light sets,
 * on) give extra light, held by the DLS combination set `set`. */
typedef struct lbk_door_state_desc {
    uint32_t door_count;
    const uint32_t *doors;    /* door indices, distinct */
    uint32_t set;             /* DLS set of kind LBK_DLS_KIND_COMBINATION */
} lbk_door_state_desc;

/* Size-tagged (lbk.h): set size with LBK_DOOR_BUILD_DESC_INIT. */
typedef struct lbk_door_build_desc {
    size_t size;
    uint32_t door_count;
    const lbk_door_desc *doors;
    uint32_t state_count;
    const lbk_door_state_desc *states;
} lbk_door_build_desc;
#define LBK_DOOR_BUILD_DESC_INIT LBK_SIZED_INIT(lbk_door_build_desc)

/* Builds the DOOR section (deterministic; state door lists are sorted). Checks the structural
 * rules; the set kinds are checked against the DLS by lbk_door_check_dls. Free *out with lbk_free. */
LBK_API lbk_result lbk_door_build(const lbk_door_build_desc *desc, const lbk_allocator *allocator, void **out,
                                  size_t *out_size);

typedef struct lbk_door_view lbk_door_view;

/* Checks the structural rules of §13 (LBK_ERR_CORRUPT / LBK_ERR_TRUNCATED). The bytes must outlive
 * the view. */
LBK_API lbk_result lbk_door_open(const void *data, size_t size, const lbk_allocator *allocator,
                                 lbk_door_view **out);
LBK_API void lbk_door_close(lbk_door_view *view);
/* Cross-checks set indices and kinds against a DLS view (LBK_ERR_CORRUPT if they disagree). */
LBK_API lbk_result lbk_door_check_dls(const lbk_door_view *doors, const lbk_dls_view *dls);

typedef struct lbk_door_info {
    const char *name; /* not NUL-terminated */
    uint32_t name_length;
    float centre[3], axes[3][3], half_extents[3];
    uint32_t open_set, closed_set;
} lbk_door_info;

LBK_API uint32_t lbk_door_count(const lbk_door_view *view);
LBK_API lbk_result lbk_door_get(const lbk_door_view *view, uint32_t door, lbk_door_info *out);
LBK_API uint32_t lbk_door_state_count(const lbk_door_view *view);
/* The state's doors (ascending) and its combination set. */
LBK_API lbk_result lbk_door_state_get(const lbk_door_view *view, uint32_t state, uint32_t *door_count, uint32_t *set);
LBK_API lbk_result lbk_door_state_door_get(const lbk_door_view *view, uint32_t state, uint32_t i,
                                           uint32_t *door);

#ifdef __cplusplus
}
#endif
#endif
