/* The bake pipeline: glTF → scene → representation per object → placement → transport →
 * encode → container. bk_bake() runs all phases; cmd_bake.c is the thin CLI over it. */
#ifndef BK_BAKE_H
#define BK_BAKE_H

#include <stdint.h>

#include "bake/util/progress.h"

typedef struct bk_bake_options {
    const char *input;            /* .gltf / .glb */
    const char *output;           /* .lbk */
    const char *json_report;      /* NULL: none */
    const char *preset;           /* "fast" (default) or "high" */
    int threads;                  /* 0: all cores */
    uint64_t seed;
    double target_error;          /* relative RMSE to stop at; <0: preset */
    double time_limit;            /* seconds; 0: none */
    int max_samples;              /* samples per receiver budget; 0: preset */
    int max_bounces;              /* 0: preset */
    float texel_density;          /* texels per metre; 0: scene extras, then preset */
    float glg_spacing;            /* metres; 0: preset */
    int sky_set;                  /* --sky given */
    float sky[3];
    const char *sky_exr;          /* --sky FILE.exr */
    int no_glg;                   /* --no-glg: movers are not lit by this level */
    const char *revision;         /* stored in META */
    int timestamp;                /* store a timestamp in META (breaks byte-identity) */
    int octahedral_probes;        /* also write OCTP probes at the GLG positions */
    double dls_threshold;         /* light sets/doors: store a receiver where the set's light exceeds
                                     this fraction of the mean indirect light of the texels it lights
                                     directly; 0: 0.01 (seed 001 §3.2); < 0: every non-zero receiver */
    int door_method;              /* how doors' open light is baked: 0 difference of full runs (default),
                                     1 the seed's guided estimator (enum bk_door_method, bake/sets/SETS.md) */
    int denoise;                  /* 0 auto: texels and GLG probes denoised (both presets), -1 off
                                     (bake/transport/DENOISE.md) */
} bk_bake_options;

typedef struct bk_bake_summary {
    uint64_t texels, pages, glg_probes, llg_probes, llgs, objects;
    uint32_t sets, doors;
    double seconds, final_error;
    uint64_t file_bytes;
    uint64_t texel_channels_saturated; /* above the largest R11G11B10F value (warned) */
    uint64_t texel_channels_flushed;   /* lit but below its smallest step: stored 0 (warned) */
} bk_bake_summary;

/* Exit-code style result: 0 ok, else an LBK_EXIT_* code; message in err. */
int bk_bake(const bk_bake_options *opt, bk_progress *progress, bk_bake_summary *summary, char *err,
            size_t err_len);

#endif
