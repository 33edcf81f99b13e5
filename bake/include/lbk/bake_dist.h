/* liblbkbake: distributed bakes (bake/dist/DIST.md). One bake cut into `units` units by
 * transport runs and, with more units than runs, by receivers; every unit needs only the scene files and the same options, and returns a part
 * (spec/part.md); the merge of all parts is byte-identical to lbk_bake_from_file with the same
 * scene, options and seed, at any number of units.
 *
 * An error target (desc->target_error >= 0) cuts at any number too: a run's stop reads only its
 * stop receivers, which every unit sharing the run also gathers (DIST.md §Error targets). Guided
 * doors (LBK_BAKE_DOOR_GUIDED): the merge makes their estimates. No time_limit (the passes it
 * allows depend on the machine): LBK_ERR_INVALID_ARGUMENT with the reason sent as the ERROR
 * message. */
#ifndef LBK_BAKE_DIST_H
#define LBK_BAKE_DIST_H

#include "lbk/bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bakes unit `unit` of `units` of the scene at path; *part (malloc'd: free it with
 * lbk_bake_part_free) holds the part's bytes, stamped with plan_hash (the caller's identity of
 * the plan: scene, options, units). */
LBK_BAKE_API lbk_result lbk_bake_unit_from_file(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash,
                                                uint32_t units, uint32_t unit, void **part, size_t *part_size);
LBK_BAKE_API void lbk_bake_part_free(void *part);

/* Shared caches (DIST.md §Shared caches): the units of a run cut between several units (more
 * units than transport runs: a level without light sets) split every bounce of its radiosity
 * caches into shares, publish the shares they compute in cache_dir, a folder every unit of the
 * plan sees, and read the others'. Units need not run at the same time: a unit computes any
 * share nobody has claimed and waits only for shares a running unit is computing. The part's
 * bytes are the same with or without sharing. Zero value: no sharing. */
typedef struct lbk_bake_unit_desc {
    size_t size;              /* sizeof(lbk_bake_unit_desc) */
    const char *cache_dir;    /* NULL: each unit computes its runs' caches whole */
    double lease;             /* seconds a claimed share may stay unpublished before another unit
                                 computes it too; 0: 600. A claim of a process gone from this
                                 host is taken at once */
} lbk_bake_unit_desc;

/* What sharing did in one unit (lbk_bake_unit_shared). */
typedef struct lbk_bake_unit_stats {
    size_t size;              /* sizeof(lbk_bake_unit_stats), set by the caller */
    uint64_t shares_computed, shares_read, bytes_written, bytes_read;
    double compute_seconds, read_seconds, wait_seconds;
    double publish_seconds;   /* claiming, writing and renaming the shares it computed */
} lbk_bake_unit_stats;

/* lbk_bake_unit_from_file with shared caches (unit NULL: none); stats may be NULL. */
LBK_BAKE_API lbk_result lbk_bake_unit_shared(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash,
                                             uint32_t units, uint32_t unit, const lbk_bake_unit_desc *shared,
                                             lbk_bake_unit_stats *stats, void **part, size_t *part_size);

/* Removes what the units left in a shared cache folder (share, claim and temporary files) and the
 * folder if it is then empty; nothing else. LBK_ERR_IO when something could not be removed. */
LBK_BAKE_API lbk_result lbk_bake_cache_dir_remove(const char *cache_dir);

/* The files a bake of the scene at path with desc reads (the import's, in the order read, then
 * a sky EXR), with their sizes and hashes: what a plan records, so that units and the merge
 * (desc->expect_inputs) refuse a changed buffer, texture or sky. Imports the scene (no layout, no
 * light). *inputs: free with lbk_bake_inputs_free. runs (may be NULL): the transport runs the
 * bake makes (the base, each light set, each door state), which the units are cut by. */
LBK_BAKE_API lbk_result lbk_bake_inputs_from_file(const char *path, const lbk_bake_desc *desc, lbk_bake_input **inputs,
                                                  size_t *count, uint32_t *runs);
LBK_BAKE_API void lbk_bake_inputs_free(lbk_bake_input *inputs);

/* What a part says about itself (lbk_bake_part_check). */
/* Filled by the library, so frozen from now on (lbk.h): this is the layout of 1.3 (units by whole
 * transport runs); 1.2's, without the run fields, was never in a release. */
typedef struct lbk_bake_part_info {
    uint64_t plan_hash;
    uint32_t units, unit;
    uint32_t total_runs;              /* the bake's transport runs (base, light sets, doors) */
    uint32_t first_run, runs;         /* this unit's runs [first_run, first_run + runs) */
    uint64_t receivers, first, end;   /* the bake's receivers; this unit's [first, end) in its
                                         first run (all of them unless units > total_runs) */
} lbk_bake_part_info;

/* Checks a part's bytes (format, checksums); with plan_hash != 0 also that it belongs to that
 * plan and with units != 0 to a cut into that many units. LBK_ERR_BAD_INPUT with the reason
 * in err (err_len bytes, may be 0). */
LBK_BAKE_API lbk_result lbk_bake_part_check(const void *part, size_t size, uint64_t plan_hash, uint32_t units,
                                            lbk_bake_part_info *info, char *err, size_t err_len);

/* Merges the parts of all `units` units (any order; each exactly once) into the container of
 * the same bake, as lbk_bake_from_file returns it. A missing, duplicated, corrupt or foreign part
 * (another plan_hash, another cut, another scene or options): LBK_ERR_BAD_INPUT with the reason
 * as the ERROR message, nothing returned. */
LBK_BAKE_API lbk_result lbk_bake_merge_from_file(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash,
                                                 uint32_t units, const void *const *parts, const size_t *part_sizes,
                                                 size_t part_count, lbk_bake_output **out);

#ifdef __cplusplus
}
#endif
#endif
