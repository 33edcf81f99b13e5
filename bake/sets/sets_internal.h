/* What the files of bake/sets/ share about the set bakes (bake_sets.h is the interface): the sets,
 * doors and combination states found in the scene, and the helpers more than one file calls.
 *   bake_sets.c     finding the sets, doors and combinations in the scene; the base bake's hooks
 *   set_entries.c   a set's sparse entries (threshold, dilated texels, probes), the contributions
 *                   kept for the denoiser, its guide, and each set's error estimate
 *   set_runs.c      the transport runs of the light sets, doors (difference or guided) and
 *                   combination states
 *   set_sections.c  the DLS and DOOR sections */
#ifndef BK_SETS_INTERNAL_H
#define BK_SETS_INTERNAL_H

#include "bake/sets/bake_sets.h"
#include "lbk/ahd.h"
#include "lbk/dls.h"

#define BS_DEFAULT_THRESHOLD 0.01
#define BS_PI 3.14159265358979323846

typedef struct bs_set {
    char name[144];
    uint32_t kind;                 /* lbk_dls_set_kind */
    int door;                      /* kinds 1/2: door index; else -1 */
    int zero;                      /* light set whose lights and emitters are all black */
    const char **light_names;      /* pointers into the scene */
    uint32_t light_count;
    /* results */
    uint64_t count[LBK_DLS_SPACE_COUNT_];
    uint32_t *targets[LBK_DLS_SPACE_COUNT_];
    /* physical values, encoded with the base section's scale in bk_set_bakes_sections (the scale
     * depends on every set, spec §12.2): texels lbk_ahd_linear, probes lbk_sh9_rgb */
    uint8_t *values[LBK_DLS_SPACE_COUNT_];
    double threshold;              /* absolute luminance threshold used (lux) */
    uint32_t members[2];           /* kind 3: the member sets */
    uint32_t member_count;
    /* the contribution kept from its run until bk_set_bakes_emit (the denoiser's weights need
     * every set first): radiance per receiver, direct luminance per texel receiver */
    lbk_sh9_rgb *stash;
    double *stash_direct;
    float *stash_halves;           /* its two half estimates, 2 per receiver (NULL: none known) */
    double stash_fraction;
    int stash_skip_doors;
} bs_set;

typedef struct bs_door {
    char name[64];
    float centre[3], axes[3][3], half[3];
    uint32_t open_set, closed_set;
} bs_door;

/* A combination state: two doors, or a door and a light set (seed §6.2). */
typedef struct bs_combo {
    int door[2];                   /* door indices, ascending; door[1] = -1 with a light set */
    int light_set;                 /* light set index or -1 */
    uint32_t set;
} bs_combo;

typedef struct bs_impl {
    bs_set *sets;
    size_t set_count;
    bs_door *doors;
    size_t door_count;
    size_t light_set_count;
    bs_combo *combos;
    size_t combo_count;
    /* the denoiser's guide (bake/denoise/DENOISE.md): Σ of the light sets' and doors'
     * contributions, and Σ of the light-set runs' variances (independent runs); NULL before any */
    lbk_sh9_rgb *guide;
    float *guide_var;
    bk_set_run_error *run_errors; /* every transport run's estimate, in order */
    size_t run_error_count;
    bk_set_estimate *estimates;   /* every stored set's, by bk_set_bakes_emit */
    size_t estimate_count;
} bs_impl;

/* 1 when triangle `tri` of `s` belongs to a door other than `keep` (NULL: any door). */
int bs_tri_door_black(const bk_scene *s, const char *keep, uint32_t tri);

/* 1 when texel receiver k lies on a door's object. */
int bs_is_door_texel(const bk_set_inputs *in, size_t k);

/* Keeps a set's contribution for bk_set_bakes_emit and adds it to the denoiser's guide
 * (combination sets are corrections of their members: not in the guide). `variance` is the
 * run's own (light sets) or NULL (differences of correlated runs: unknown). */
lbk_result bs_stash_set(const bk_set_inputs *in, bs_impl *im, bs_set *st, const lbk_sh9_rgb *contrib,
                        const lbk_sh9_rgb *direct, const float *halves, const float *variance, double fraction,
                        int skip_doors);

#endif
