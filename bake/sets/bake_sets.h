/* Dynamic light sets and doors in the bake (seed 001 §3–§4): finding them in the scene,
 * leaving them out of the base bake, baking each one's contribution at the same receivers,
 * and writing the DLS and DOOR sections. With no sets and no doors every call is a no-op and
 * no section is written. */
#ifndef BK_BAKE_SETS_H
#define BK_BAKE_SETS_H

#include <stddef.h>
#include <stdint.h>

#include "bake/probes/llg_fit.h"
#include "bake/probes/llg_place.h"
#include "scene/scene.h"
#include "bake/layout/seams.h"
#include "bake/layout/texels.h"
#include "bake/denoise/denoise.h"
#include "bake/util/events.h"
#include "scene/tracer.h"
#include "bake/transport/transport.h"
#include "lbk/sh.h"

/* How a door's open contribution S_O is computed (bake/sets/SETS.md). */
enum bk_door_method {
    BK_DOOR_DIFFERENCE = 0, /* L(door removed) − L(doors closed, black): two correlated full runs */
    BK_DOOR_GUIDED = 1      /* the seed's guided estimator (bake/sets/door_guided.h), no full run */
};

typedef struct bk_set_bakes {
    uint32_t set_count;   /* DLS sets written (light sets, door open/closed sets, combinations) */
    uint32_t door_count;
    void *impl;           /* owned by bake/sets/ (sets_internal.h) */
} bk_set_bakes;

/* Everything the set bakes share with the base bake. */
typedef struct bk_set_inputs {
    const bk_scene *scene;
    const bk_tracer *tracer;          /* over the whole scene, doors closed */
    const bk_receiver *receivers;     /* valid texels, LLG fit targets, GLG probes, LLG probes */
    size_t receiver_count;
    size_t texel_receivers;           /* receivers [0, texel_receivers) are texels */
    size_t glg_first, glg_count;      /* receivers [glg_first, glg_first+glg_count) are GLG probes */
    size_t llg_first, llg_count;      /* then LLG probes, in LLG section order */
    const bk_llg_fit_plan *llg_fit;   /* the LLG fit's vertex targets (receivers after the texels,
                                         before the GLG probes); every run is fitted */
    const bk_llg *llgs;               /* the LLGs those probes belong to (their objects) */
    size_t llg_grids;
    const uint32_t *texel_of_receiver;/* receiver → index in texels->receivers */
    const bk_texels *texels;          /* page layout: DLS texel index = page_offset[page] + y·w + x */
    int atlas_margin;                 /* dilation passes for set pages */
    const bk_seams *seams;            /* stitched like the base pages (bk_finish_page); NULL: not */
    const lbk_sh9_rgb *base_radiance; /* the base bake, per receiver */
    bk_transport_options transport;   /* the base bake's options (seed, threads, budgets) */
    double base_samples_per_receiver; /* what the base bake reached: door bakes use this budget */
    double threshold;                 /* sparse storage: fraction of the mean indirect light of the
                                         texels a set lights directly (bake/sets/SETS.md); 0: 0.01;
                                         < 0: store every receiver with a non-zero contribution */
    const bk_events *events;          /* messages, progress over all set runs, cancellation */
    int door_method;                  /* enum bk_door_method */
    int skip_guided;                  /* a distributed bake's unit: the guided estimates (S_O,
                                         which read the base's final radiance at every receiver)
                                         are left zero; the merge, which has that radiance, makes
                                         them (bake/dist/DIST.md) */
    int denoise_always;               /* 1: every set filtered (--denoise on); 0: per set and class
                                         only where it lowers the estimate (auto) */
    const bk_denoiser *denoiser;      /* bk_set_bakes_emit: the denoiser built from the base + the
                                         guide (bk_set_bakes_guide), applied to every set with the
                                         same weights; NULL: not denoised */
    double deadline;                  /* bk_now() time by which the last run should end (the bake's
                                         one time budget, --time-limit); 0: none. Each run gets an
                                         equal share of what is left (at least one pass each) */
    float origin[3];                  /* the bake frame's origin in world space: add it to every
                                         position written (the scene is recentred, bake.c) */
    float scale[3];                   /* sections only: the LMAP, GLG and LLG scales (spec §5.7);
                                         DLS payloads are stored in them (0: 1) */
} bk_set_inputs;

/* Finds light sets (lights and emissive objects with lbk_light_set), doors (lbk_door) and the
 * combination states the scene asks for (bk_scene.combinations; input errors for unknown names,
 * two light sets, or a door paired with itself).
 * Returns LBK_OK, LBK_ERR_BAD_INPUT or LBK_ERR_OUT_OF_MEMORY with a message in err. */
lbk_result bk_set_bakes_prepare(bk_set_bakes *sets, const bk_scene *scene, const bk_events *events, char *err,
                                size_t err_len);
/* Sets what the base bake must leave out: the sets' lights (transport's light_set filter does
 * that already) and doors' reflection (albedo 0 in the base, seed §4.1). Returns 1 when the
 * base run needs an albedo hook that calls bk_set_bakes_base_albedo (the caller owns the
 * transport's user pointer, so it installs the hook), else 0. */
int bk_set_bakes_base_hooks(bk_set_bakes *sets, const bk_scene *scene, bk_transport_options *base);
/* The base bake's albedo rule: 0 on door triangles. */
void bk_set_bakes_base_albedo(const bk_set_bakes *sets, const bk_scene *scene, uint32_t tri, float albedo[3]);
/* Bakes every set's contribution at the receivers and keeps it (one radiance SH per receiver
 * per set) for bk_set_bakes_emit. LBK_OK, LBK_ERR_CANCELLED (in->events said stop), or
 * LBK_ERR_OUT_OF_MEMORY / LBK_ERR_INTERNAL with a message in err. */
lbk_result bk_set_bakes_run(bk_set_bakes *sets, const bk_set_inputs *in, char *err, size_t err_len);
/* After bk_set_bakes_run: the denoiser's guide, Σ of the light sets' and doors' contributions
 * per receiver and Σ of the light-set runs' variances (bake/denoise/DENOISE.md); both NULL
 * without sets. Valid until bk_set_bakes_emit. */
void bk_set_bakes_guide(const bk_set_bakes *sets, const lbk_sh9_rgb **sum, const float **variance);

/* How many transport runs bk_set_bakes_run will make (for the time budget's shares). */
int bk_set_bakes_planned_runs(const bk_set_bakes *sets);
/* Exactly how many bk_transport_run calls bk_set_bakes_run makes with door method `method`
 * (enum bk_door_method; a distributed bake's cut, bake/dist/DIST.md): a door pair reuses its
 * doors' open runs (guided: the first pair a door is in makes its open run) and a combination
 * with a black light set makes none; a guided estimate is no transport run. The first
 * *light_set_runs (may be NULL) are the light sets' own; every later one (door states,
 * combinations) has the base's final sample count as its budget. */
int bk_set_bakes_transport_runs(const bk_set_bakes *sets, int method, int *light_set_runs);

/* One transport run of bk_set_bakes_run (a light set, a door state, a reference): its label as in
 * the bake's messages and its final estimated error, pooled and per receiver class. */
typedef struct bk_set_run_error {
    char label[64];
    double est_rel_rmse;
    double class_rel_rmse[BK_RECEIVER_CLASSES];
    double probe_rel_rmse;
    double seconds;
} bk_set_run_error;

/* The runs so far, in the order they ran (owned by sets). */
const bk_set_run_error *bk_set_bakes_run_errors(const bk_set_bakes *sets, size_t *count);
/* What a stored set's contribution delivers (bk_set_bakes_emit): its two half estimates — the
 * run's, or for a door state or combination the same difference of the runs' halves as of
 * their results (the runs share a seed, so the correlation that makes a difference quiet is in
 * it) — through the base's denoising weights (denoised) or unfiltered. None for the guided
 * estimator's open sets (not a transport run). */
typedef struct bk_set_estimate {
    char name[144];
    uint32_t set;          /* index in the DLS section's set table */
    uint32_t kind;         /* lbk_dls_set_kind */
    int filtered[BK_RECEIVER_CLASSES]; /* 1: the class is stored filtered (texels, GLG) */
    bk_denoise_error error; /* of what is stored, relative to the RMS of the contribution itself */
} bk_set_estimate;

/* The stored sets' estimates, in set order (owned by sets; after bk_set_bakes_emit). */
const bk_set_estimate *bk_set_bakes_estimates(const bk_set_bakes *sets, size_t *count);
/* Denoises every kept contribution with in->denoiser (NULL: none) and chooses its sparse
 * entries (threshold, dilation); frees what bk_set_bakes_run kept. LBK_OK or an error with a
 * message in err. */
lbk_result bk_set_bakes_emit(bk_set_bakes *sets, const bk_set_inputs *in, char *err, size_t err_len);
/* Largest value of any set's entries per DLS space (texels: irradiance along the normal; probes:
 * SH DC), for choosing the base sections' scales. */
void bk_set_bakes_max(const bk_set_bakes *sets, double max[3]);
/* The DLS and DOOR section bytes (free with lbk_free); *door is NULL without doors. */
lbk_result bk_set_bakes_sections(bk_set_bakes *sets, const bk_set_inputs *in, void **dls, size_t *dls_size,
                                 void **door, size_t *door_size);
void bk_set_bakes_free(bk_set_bakes *sets);

#endif
