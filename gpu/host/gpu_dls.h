/* lbk_dls_apply on a Vulkan device (gpu/shaders/dls_apply.comp): upload a level once — the DLS
 * section bytes as they are, the LMAP section as the base texels, the base probe arrays — then
 * apply weights as often as wanted and read the results back from mapped memory. The clusters
 * whose sets changed run as one dispatch (a table gives each workgroup of 64 its cluster and
 * first target, so a workgroup never mixes clusters), or, gpu_dls_per_cluster, one dispatch per
 * cluster as in the seed (whose per-dispatch overhead the batch avoids). The output has the layouts of the
 * inputs: an LMAP section's bytes (page planes at the page table's offsets, ready for
 * vkCmdCopyBufferToImage) and 28-byte probe arrays. The bytes equal lbk_dls_apply's.
 *
 * Also the naive per-target gather the seed rejects (dls_naive.comp), for the benchmark.
 *
 * Thread safety: one thread at a time per gpu_dls (and per context). */
#ifndef LBK_GPU_DLS_H
#define LBK_GPU_DLS_H

#include "gpu/host/vk_context.h"

typedef struct gpu_dls_level {
    const void *dls;               /* DLS section bytes (checked with lbk_dls_open) */
    size_t dls_size;
    const void *door;              /* DOOR section bytes, or NULL */
    size_t door_size;
    const void *lmap;              /* LMAP section bytes: the base texels; NULL when the DLS has none */
    size_t lmap_size;
    const uint8_t *glg, *llg;      /* base probes, 28 bytes each (counts: the DLS target counts) */
    int naive;                     /* 1: also build the naive gather's records */
} gpu_dls_level;

typedef struct gpu_dls_stats {
    uint32_t dispatches;           /* compute dispatches recorded */
    uint32_t copies;               /* whole-buffer base copies (the first apply) */
    uint32_t clusters_applied, clusters_copied, clusters_skipped;
    uint64_t invocations;          /* shader invocations (targets) */
    uint64_t bytes_moved;          /* payload bytes read and written: bases, entries with a non-zero weight, outputs */
    double gpu_ms;                 /* device timestamps around the commands (lavapipe: CPU time); −1: none */
    double wall_ms;                /* host time from recording to completion */
} gpu_dls_stats;

typedef struct gpu_dls gpu_dls;

int gpu_dls_open(gpu_ctx *c, const gpu_dls_level *level, gpu_dls **out, char *err, size_t err_len);
void gpu_dls_close(gpu_dls *g);
/* The next apply rewrites every target. */
void gpu_dls_invalidate(gpu_dls *g);
/* 1: one dispatch per cluster (the seed's); 0 (the default): one batched dispatch. */
void gpu_dls_per_cluster(gpu_dls *g, int on);
/* set_weights / door_weights as lbk_dls_apply (NULL: all 0 / all doors closed). 0 on success. */
int gpu_dls_apply(gpu_dls *g, const float *set_weights, const float *door_weights, gpu_dls_stats *stats);
/* Every target, gathered per target (needs level.naive). */
int gpu_dls_apply_naive(gpu_dls *g, const float *set_weights, const float *door_weights, gpu_dls_stats *stats);

/* The three base copies alone (base → output buffers, as the first apply starts): the device's
 * copy speed over the same bytes, the reference an apply's time is measured against. The outputs
 * are the bases afterwards; the next apply rewrites every target. */
int gpu_dls_copy_bases(gpu_dls *g, gpu_dls_stats *stats);

/* The outputs after the last apply (mapped device memory): the LMAP section's layout, and the
 * probe array of space 1 (GLG) or 2 (LLG). */
const uint8_t *gpu_dls_lmap(const gpu_dls *g);
const uint8_t *gpu_dls_probes(const gpu_dls *g, uint32_t space);

/* Divergence proxy, from the data alone: over waves of 32 consecutive invocations of a dispatch,
 * the share of lane-iterations of the entry loop that idle because another lane of the wave has
 * more entries — for the clustered dispatches and for the naive gather (every set on). */
void gpu_dls_divergence(const gpu_dls *g, double *clustered, double *naive);
uint32_t gpu_dls_cluster_count(const gpu_dls *g);

#endif
