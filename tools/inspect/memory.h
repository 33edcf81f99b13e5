/* GPU memory per object and per light set of a level (lbk inspect --json, --budget): what a
 * pipeline charts per revision and a build gate checks against a platform's budget
 * (spec/inspect-json.md "objects", "light_sets"; tools/inspect/budget.h). */
#ifndef LBK_INSPECT_MEMORY_H
#define LBK_INSPECT_MEMORY_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/bake_data.h"

typedef struct tl_object_memory {
    char name[128];
    uint32_t representation;   /* lbk_representation */
    uint64_t texels;           /* lightmap: rect_w × rect_h */
    uint64_t lightmap_bytes;   /* GPU bytes of those texels in their page's encoding */
    uint64_t llg_probes, llg_vertices;
    uint64_t llg_bytes;        /* probes × 28 + vertices × 4 */
    uint64_t dls_entries;      /* light-set entries whose target is one of its texels or LLG probes */
    uint64_t dls_bytes;        /* their payload bytes (8 per texel entry, 28 per probe entry) */
    uint64_t total_bytes;      /* lightmap + LLG + DLS */
} tl_object_memory;

typedef struct tl_set_memory {
    char name[128];
    uint32_t kind;             /* lbk_dls_kind */
    uint64_t entries[3];       /* per target space: texels, GLG probes, LLG probes */
    uint64_t payload_bytes;    /* Σ entries × payload size */
} tl_set_memory;

typedef struct tl_level_memory {
    tl_object_memory *objects; size_t object_count;   /* OBJS order */
    tl_set_memory *sets; size_t set_count;            /* DLS order */
    uint64_t dls_unowned_bytes; /* entries on texels no object's rectangle covers (gutters) and GLG probes */
} tl_level_memory;

/* Fills m from an opened bake. Returns 0, or -1 when out of memory. */
int tl_level_memory_get(const tl_bake *b, tl_level_memory *m);
void tl_level_memory_free(tl_level_memory *m);

#endif
