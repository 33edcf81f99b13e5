/* The bake pipeline's shared state (internal to bake/pipeline/): one bk_pipeline per lbk_bake_*
 * call, filled phase by phase. bake.c runs the phases (phase_import.c, phase_layout.c,
 * phase_light.c), bake_dist.c makes the distributed bakes' calls, sections.c encodes the
 * container, report.c fills the report and writes its JSON, output.c owns what the caller gets
 * back. */
#ifndef BK_PIPELINE_H
#define BK_PIPELINE_H

#include <stddef.h>
#include <stdint.h>

#include "bake/layout/atlas.h"
#include "bake/layout/seams.h"
#include "bake/layout/classify.h"
#include "bake/layout/texels.h"
#include "bake/probes/glg_place.h"
#include "bake/probes/octa_bake.h"
#include "bake/probes/llg_fit.h"
#include "bake/probes/llg_place.h"
#include "scene/scene.h"
#include "bake/sets/bake_sets.h"
#include "scene/tracer.h"
#include "bake/transport/transport.h"
#include "bake/util/events.h"
#include "lbk/bake.h"
#include "lbk/sh.h"

/* What a preset sets; every field can be overridden in lbk_bake_desc. */
typedef struct bk_preset {
    const char *name;
    float texel_density;   /* texels per metre */
    float glg_spacing;     /* metres (halved once near geometry) */
    int max_samples;       /* gather rays per receiver, both halves, whole run */
    double target_error;   /* relative RMSE */
    int llg_visibility_rays;
} bk_preset;

extern const bk_preset bk_presets[LBK_BAKE_PRESET_COUNT_];

#define BK_MAX_PHASES 8

typedef struct bk_pipeline {
    lbk_bake_desc desc;             /* the caller's, at this library's size */
    const lbk_bake_desc *opt;       /* &desc */
    const bk_preset *pre;
    const char *input;              /* the path, or the description's name: messages and report */
    const char *scene_name;         /* META scene.name: the file's base name, or the description's name */
    char err[1024];                 /* why the call fails (sent as the ERROR message) */
    bk_events events;               /* to the desc's callbacks */
    double start;                   /* bk_now() at the call */
    double est;                     /* latest estimated relative RMSE of the base bake; < 0: none */
    int cancelled;
    bk_scene scene;
    bk_object_class *classes;
    bk_atlas atlas;
    bk_seams seams;                 /* stitched after transport unless opt->no_seam_stitch */
    bk_texels texels;
    bk_tracer *tracer;
    bk_glg glg;
    int have_glg;
    bk_llg *llgs;
    size_t llg_count;
    int32_t *object_llg;            /* per scene object: LLG index or -1 */
    /* receivers handed to transport: valid texels, the LLG fit's vertex targets (from
     * llg_fit.first = texel_receivers; bake/probes/llg_fit.h), then GLG probes, then LLG probes */
    bk_receiver *receivers;
    size_t receiver_count, texel_receivers, glg_first, llg_first;
    bk_llg_fit_plan llg_fit;
    bk_llg_fit_stats llg_fit_stats; /* the base run's fit */
    bk_llg_fit_stats *llg_fit_grid; /* the same per grid (llg_count) */
    lbk_bake_llg_estimate *llg_est; /* per grid: its LLG object's estimate (llg_fit_error) */
    uint32_t *texel_of_receiver;    /* receiver → index in texels.receivers */
    lbk_sh9_rgb *radiance;
    float *cell_size;               /* per scene triangle: the radiosity cache's cell size (texel size) */
    float *variance;                /* per receiver, from the transport: the denoiser's input */
    float *halves;                  /* 2 per receiver, the transport's two halves' X (local bakes) */
    lbk_bake_object_estimate *object_est; /* per scene object (texels 0: none), object_errors.c */
    struct bk_denoise_group_error *object_filtered; /* per scene object: the denoised texels' estimate,
                                                       from denoised_error's filter pass; NULL: none */
    /* the path check (path_check.c, bk_transport_options.check_*): per receiver its group (the
     * object of a lightmap texel, else UINT32_MAX); check_count = objects × check_per_object
     * slots: the receiver drawn, its weight, the paths' mean irradiance (3 each) and variance;
     * per scene object the measured error; pooled over the level; slots that were traced */
    uint32_t *check_group, *check;
    float *check_weight, *check_irradiance, *check_variance;
    size_t check_count, check_per_object, check_done;
    lbk_bake_object_check *object_check;
    double check_level;
    float *texel_rel_error;         /* per texel receiver with error_map: the TERR input (error_map.h) */
    struct bk_denoiser *denoiser;   /* weights of the base + every set (do_denoise), for all of them */
    lbk_bake_denoised denoised;     /* the estimate of the denoised base (report, REPT's last record) */
    int have_denoised;
    bk_transport_stats stats;
    bk_transport_sample *samples;
    size_t sample_count, sample_cap;
    double phase_seconds[BK_MAX_PHASES];
    uint64_t phase_peak_rss[BK_MAX_PHASES]; /* bytes, at each phase's end (bake.c close_phase) */
    lbk_bake_phase phases[BK_MAX_PHASES];
    int phase_count;
    double phase_start;
    bk_set_bakes sets;              /* dynamic light sets and doors (bake_sets.c) */
    float origin[3];                /* world position of the bake frame's origin (recentre()) */
    uint64_t saturated, flushed;    /* texel channels outside the R11G11B10F range (stored units) */
    float scale[3];                 /* LMAP, GLG, LLG scales (spec §5.7); DLS payloads use them */
    float octp_scale;
    bk_octa_volume octa;            /* OCTP probe volume (--octahedral), scene frame */
    float *octa_irradiance;         /* octa.count × 16 × 3, from the transport */
    double octa_rel_rmse, octa_rays;
    lbk_bake_output *out;           /* what the caller gets: the writer (sections.c), the report */
    struct bk_dist *dist;           /* a distributed bake's unit or merge (bake/dist/dist.h); NULL: local */
    struct bk_ckpt *ckpt;           /* checkpoints (desc.checkpoint_dir); NULL: none */
    void *part;                     /* a unit's part, once its runs are done */
    size_t part_size;
    int inputs_only;                /* lbk_bake_inputs_from_file: stop after the import, its files in */
    lbk_bake_input *inputs;         /* input_count entries (malloc'd) */
    size_t input_count;
    uint32_t transport_runs;        /* with inputs_only: the runs the bake would make */
    uint64_t container_bytes;
} bk_pipeline;

struct lbk_bake_output {
    lbk_allocator allocator;        /* all zero: malloc */
    lbk_writer *writer;
    uint64_t phase_peak_rss[BK_MAX_PHASES]; /* report.phase_peak_rss */
    lbk_bake_report report;
    lbk_bake_pass *passes;
    lbk_bake_class_errors *pass_errors;
    lbk_bake_set_run *set_runs;
    char *set_labels;               /* the set runs' labels, 64 bytes each */
    lbk_bake_set_estimate *set_estimates;
    char *set_names;                /* their names, 144 bytes each */
    lbk_bake_object_estimate *object_estimates; /* lightmapped objects, in scene order */
    char *object_names;             /* their names, 128 bytes each */
    lbk_bake_object_check *object_checks; /* parallel to them (the path check); NULL: none */
    lbk_bake_llg_estimate *llg_estimates; /* LLG props, in scene order */
    char *llg_names;                /* their names, 128 bytes each */
    lbk_bake_phase_time phases[BK_MAX_PHASES];
    char *input;
};

/* Formats the error text; returns code. */
lbk_result bk_pipeline_fail(bk_pipeline *b, lbk_result code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* A module's failure: out of memory and cancellation as they are, anything else internal;
 * the text is "<what>: <the result's message>". */
lbk_result bk_pipeline_failed(bk_pipeline *b, lbk_result r, const char *what);
/* A checkpoint: reports progress; non-zero when the caller cancelled. */
int bk_pipeline_progress(bk_pipeline *b, double fraction);
void bk_pipeline_to_world(const bk_pipeline *b, const float local[3], float world[3]);
/* Why the base transport stopped, as REPT and the report say it (an lbk_bake_status). */
uint32_t bk_pipeline_status(const bk_pipeline *b);
/* What the set bakes share with the base bake. */
void bk_pipeline_set_inputs(const bk_pipeline *b, bk_set_inputs *in);
/* Starts a phase: closes the previous one's time, then a checkpoint at 0. */
lbk_result bk_pipeline_phase(bk_pipeline *b, lbk_bake_phase ph);
/* A checkpoint as a result: LBK_ERR_CANCELLED when the caller cancelled. */
lbk_result bk_pipeline_checkpoint(bk_pipeline *b, double fraction);

/* One bake from a file or a scene description (bake.c): a whole one into *out, a unit's part
 * (dist a recorder: *part), a merge (dist a player), or only the inputs it reads (inputs). */
lbk_result bk_pipeline_bake(const char *path, const lbk_bake_scene *desc, const lbk_bake_desc *options,
                            lbk_bake_output **out, struct bk_dist *dist, void **part, size_t *part_size,
                            lbk_bake_input **inputs, size_t *input_count, uint32_t *runs);
/* The identity of the options that shape a bake's bytes; budgets 0 leaves out the budgets
 * (target error, time limit, samples) (bake_dist.c). */
uint64_t bk_pipeline_options_hash(const lbk_bake_desc *options, int budgets);
/* A distributed run that failed: the parts' fault as an error, or LBK_OK (phase_light.c). */
lbk_result bk_pipeline_replay_failure(bk_pipeline *b, lbk_result r);

/* The phases, in order: import (phase_import.c), layout (phase_layout.c), the base transport,
 * the sets' runs, denoising and the sets' entries (phase_light.c). */
lbk_result bk_phase_import(bk_pipeline *b, const char *path, const lbk_bake_scene *desc);
lbk_result bk_phase_layout(bk_pipeline *b);
lbk_result bk_phase_transport(bk_pipeline *b);
lbk_result bk_phase_sets(bk_pipeline *b);
lbk_result bk_phase_denoise(bk_pipeline *b);
lbk_result bk_phase_emit_sets(bk_pipeline *b);
/* Each lightmapped object's estimate into b->object_est (object_errors.c); after the denoiser. */
lbk_result bk_object_estimates(bk_pipeline *b);
/* The path check (path_check.c): the texels it traces, chosen before the base run (BK_CHECK_PER_OBJECT
 * per object unless the desc says), and after the denoiser each object's measured error folded
 * into b->object_est. */
#define BK_CHECK_PER_OBJECT 16
lbk_result bk_check_plan(bk_pipeline *b);
lbk_result bk_check_compare(bk_pipeline *b);
/* Each texel receiver's scene object (UINT32_MAX: none), malloc'd; NULL when out of memory. */
uint32_t *bk_texel_object_groups(const bk_pipeline *b);

/* The write phase: every section into b->writer (sections.c). */
lbk_result bk_pipeline_encode(bk_pipeline *b);
/* The report of a finished bake into out (report.c). */
lbk_result bk_pipeline_report(const bk_pipeline *b, lbk_bake_output *out);
/* Allocation through the output's allocator (output.c). */
void *bk_output_alloc(const lbk_bake_output *out, size_t size);
void bk_output_free_mem(const lbk_bake_output *out, void *p);

#endif
