/* Compares the lighting of one object ("Room") between two bakes, texel by texel, in physical
 * units (stored × each file's LMAP scale): shared by test_sets and test_doors. */
#ifndef RC_ROOM_COMPARE_H
#define RC_ROOM_COMPARE_H

#include <stdint.h>

#include "lbk/lightmap.h"

typedef struct rc_side {
    const lbk_lmap_view *lmap;
    const uint32_t *rect;  /* page, x, y, w, h of the object in that file */
    const uint32_t *z;     /* plane 0 (R11G11B10F) over the global texel index */
    const uint8_t *rgba;   /* plane 1 (RGBA8) over the global texel index */
} rc_side;

typedef struct rc_result {
    double l1;             /* Σ|a − b| / Σ b over the object's texels */
    double ratio;          /* Σ a / Σ b */
    double sum_a, sum_b;
} rc_result;

/* Asserts (cmocka) that both rectangles have the same size and their pages exist. */
rc_result rc_compare_room(rc_side a, rc_side b);

#endif
