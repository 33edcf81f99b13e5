/* REPT: the bake report — estimated error against time/samples. Layout: spec/container.md §7.
 *
 * Thread safety: every function is safe to call from any thread; views are read-only. */
#ifndef LBK_REPORT_H
#define LBK_REPORT_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LBK_REPORT_HEADER_SIZE 32u
#define LBK_REPORT_RECORD_SIZE 32u

/* Why the bake stopped. */
typedef enum lbk_bake_status {
    LBK_BAKE_CONVERGED = 0,      /* adaptive sampling left no texel or probe above its own noise threshold */
    LBK_BAKE_TARGET_REACHED = 1, /* the estimated relative RMSE fell to target_rel_rmse */
    LBK_BAKE_TIME_LIMIT = 2,     /* time_limit_seconds ran out */
    LBK_BAKE_SAMPLE_LIMIT = 3,   /* max_samples_per_texel was reached */
    LBK_BAKE_STATUS_COUNT_
} lbk_bake_status;

/* Header flag: elapsed_seconds hold measured wall-clock time. Clear, every elapsed_seconds is 0
 * and the section is byte-reproducible (§1.2); a writer promising identical bytes clears it. */
#define LBK_REPORT_HAS_TIMES 0x1u

/* One progress sample, taken after a sampling pass; all cumulative values never decrease.
 * An array element (frozen). */
typedef struct lbk_report_record {
    double elapsed_seconds;     /* since the start of transport; 0 without LBK_REPORT_HAS_TIMES */
    uint64_t rays_traced;       /* cumulative rays (a machine-independent measure of work) */
    uint32_t samples_per_texel; /* cumulative samples per lightmap texel (mean when adaptive) */
    uint32_t bounces;           /* indirect bounces simulated */
    float texel_rel_rmse;       /* estimated relative RMSE of lightmap irradiance, ≥ 0 */
    float probe_rel_rmse;       /* estimated relative RMSE of probe SH (GLG/LLG), ≥ 0; 0 without probes */
} lbk_report_record;

/* Builder input, and the header of a view. Size-tagged (lbk.h): set size with LBK_REPORT_INIT;
 * lbk_report_open sets it to sizeof(lbk_report). */
typedef struct lbk_report {
    size_t size;
    uint32_t status;               /* lbk_bake_status */
    uint32_t flags;                /* LBK_REPORT_HAS_TIMES */
    uint32_t max_samples_per_texel;/* sample limit; 0: none */
    double time_limit_seconds;     /* time limit; 0: none */
    float target_rel_rmse;         /* target error; 0: none */
    const lbk_report_record *records;
    uint32_t record_count;         /* ≥ 1 */
} lbk_report;
#define LBK_REPORT_INIT LBK_SIZED_INIT(lbk_report)

/* Builds REPT bytes. Rejects (LBK_ERR_RANGE) NaN/Inf/negative values, decreasing cumulative
 * values, non-zero times without HAS_TIMES, unknown status or flags, zero records.
 * *out is allocated with the allocator; free it with lbk_free. */
LBK_API lbk_result lbk_report_build(const lbk_report *report, const lbk_allocator *allocator, void **out,
                                    size_t *size);

/* A read-only view: the header fields decoded, records read on demand. */
typedef struct lbk_report_view {
    lbk_report header;        /* records == NULL: use lbk_report_record_get */
    const uint8_t *record_bytes;
} lbk_report_view;

/* Checks the sizes (LBK_ERR_TRUNCATED / LBK_ERR_CORRUPT) and fills the view. */
LBK_API lbk_result lbk_report_open(const void *data, size_t size, lbk_report_view *out);
LBK_API lbk_result lbk_report_record_get(const lbk_report_view *view, uint32_t index, lbk_report_record *out);

/* "converged", "target reached", "time limit", "sample limit", or "unknown". */
LBK_API const char *lbk_bake_status_name(uint32_t status);

#ifdef __cplusplus
}
#endif
#endif
