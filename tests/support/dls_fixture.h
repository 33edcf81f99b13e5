/* Random dynamic-light-set content for the DLS tests and benchmark: sparse sets over the three
 * target spaces with valid 8-byte AHD and 28-byte SH9 payloads. */
#ifndef LBK_TESTS_DLS_FIXTURE_H
#define LBK_TESTS_DLS_FIXTURE_H

#include <stdint.h>

#include "lbk/dls.h"

uint64_t dlsfx_rand(uint64_t *state);               /* splitmix64 */
float dlsfx_uniform(uint64_t *state);               /* [0, 1) */
void dlsfx_random_texel(uint64_t *state, float scale, uint8_t out[8]);
void dlsfx_random_probe(uint64_t *state, float scale, uint8_t out[28]);

/* Owns the arrays behind an lbk_dls_build_desc. */
typedef struct dlsfx {
    lbk_dls_build_desc desc;
    lbk_dls_set_desc *sets;
    char (*names)[32];
    uint32_t *(*targets)[LBK_DLS_SPACE_COUNT_];
    uint8_t *(*payloads)[LBK_DLS_SPACE_COUNT_];
    uint32_t **members;
    uint32_t set_count;
} dlsfx;

/* set_count sets named "set<i>", all of kind LIGHTS with no entries. */
void dlsfx_init(dlsfx *fx, uint32_t set_count, uint64_t texels, uint64_t glg, uint64_t llg);
/* Adds entries of set s in space sp for targets [first, first+count) (step 1), random payloads. */
void dlsfx_add_range(dlsfx *fx, uint64_t *rng, uint32_t s, uint32_t sp, uint32_t first, uint32_t count);
/* Adds one entry. */
void dlsfx_add(dlsfx *fx, uint64_t *rng, uint32_t s, uint32_t sp, uint32_t target);
/* Makes set s a combination of the given members. */
void dlsfx_combination(dlsfx *fx, uint32_t s, uint32_t n, const uint32_t *members);
void dlsfx_free(dlsfx *fx);

/* target → 1 + entry index of set s in space sp (0: none); free() it. */
uint32_t *dlsfx_index(const dlsfx *fx, uint32_t s, uint32_t sp);
/* The payload set s holds for target t in space sp, or NULL (linear search). */
const uint8_t *dlsfx_find(const dlsfx *fx, uint32_t s, uint32_t sp, uint32_t t);

#endif
