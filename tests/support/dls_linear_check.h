/* The linear mode's exactness check (lbk/dls.h, LBK_DLS_RUNTIME_LINEAR), for the DLS tests on
 * synthetic and baked levels: one byte-mode runtime and two linear ones (the default path and
 * the scalar one) over the same bases; each apply runs on all three and is checked target by
 * target against an independent accumulation written here with the public codecs (decode base,
 * += w·S in the cluster's set order for the non-zero effective weights, unfused):
 *   - both linear outputs are that accumulator bit for bit (so scalar = SIMD);
 *   - targets with an entry of non-zero weight: lbk_ahd_from_linear / lbk_sh9_pack of the linear
 *     output are the byte mode's bytes;
 *   - the others: the linear output is the decoded base and the byte output the base bytes;
 *   - both modes report the same stats, and the same dirty ranges for the same job size (the
 *     scalar linear runtime runs jobs of 100 targets: another split). */
#ifndef LBK_TESTS_DLS_LINEAR_CHECK_H
#define LBK_TESTS_DLS_LINEAR_CHECK_H

#include <stdint.h>

#include "lbk/dls.h"
#include "lbk/door.h"

typedef struct dlslin {
    const lbk_dls_view *view;
    uint64_t n[LBK_DLS_SPACE_COUNT_];
    const uint32_t *base_z;
    const uint8_t *base_rgba, *base_probe[2];
    uint32_t *out_z;
    uint8_t *out_rgba, *out_probe[2];
    float *lin[2][3], *lin_probe[2][2]; /* [path: default, scalar][plane / probe space] */
    lbk_dls_runtime *bytes, *linear[2];
    float *eff;
    uint8_t *seen;
} dlslin;

/* Counts of the last check. */
typedef struct dlslin_counts {
    uint64_t targets;       /* all targets of all spaces */
    uint64_t weighted;      /* with an entry of non-zero weight: linear re-encoded = byte output */
    uint64_t mismatches;    /* targets failing any rule above (0 is a pass) */
    uint64_t reencode_differs; /* unweighted targets whose base does not survive decode + encode */
} dlslin_counts;

/* Bases in the array form (probe bases may be NULL for a space with no clusters); 0 on success. */
int dlslin_open(dlslin *d, const lbk_dls_view *view, const lbk_door_view *doors, const uint32_t *base_z,
                const uint8_t *base_rgba, const uint8_t *base_glg, const uint8_t *base_llg);
/* Applies the weights in all three runtimes and checks; 0 when every rule holds. */
int dlslin_apply_check(dlslin *d, const float *set_weights, const float *door_weights, dlslin_counts *out);
void dlslin_close(dlslin *d);

#endif
