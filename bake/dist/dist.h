/* Distributed bakes (bake/dist/DIST.md, spec/part.md): one bake cut into units by transport runs
 * and, with more units than runs, by receivers. A unit runs the whole pipeline up to the light
 * transport (import, layout), bakes its runs (their caches are global but deterministic, so
 * units sharing a run rebuild them alike) gathering only its receivers' share, skips the other
 * runs, and records what it computed into a part. The merge
 * runs the same pipeline, replays the parts instead of tracing, and then denoises, encodes and
 * writes as a local bake does: the container is byte-identical to `lbk bake`. */
#ifndef BK_DIST_H
#define BK_DIST_H

#include <stddef.h>
#include <stdint.h>

#include "bake/transport/transport.h"
#include "lbk/lbk.h"

#define BK_PART_MAGIC "LBKPART\0"
#define BK_PART_VERSION 4u /* 3: shared runs cut at multiples of 64 receivers; 4: octahedral probes */
#define BK_PART_HEADER_SIZE 96u
#define BK_PART_RUN_HEADER_SIZE 112u
#define BK_PART_PASS_HEADER_SIZE 64u
#define BK_PART_MAX_UNITS 65536u
#define BK_PART_MAX_RUNS 65536u
#define BK_PART_MAX_PASSES 32u
#define BK_PART_MAX_OCTA ((uint64_t)1 << 28) /* octahedral probes in a part */

/* Bytes of a run record of n receivers with `passes` pass headers and the output planes of
 * `mask` (spec/part.md); 0 on overflow. */
size_t bk_part_run_size(uint64_t n, uint32_t passes, uint32_t mask);

/* Output arrays a run record holds (bk_transport_output's non-NULL members). */
enum { BK_PART_RADIANCE = 1, BK_PART_DIRECT = 2, BK_PART_IRRADIANCE = 4, BK_PART_VARIANCE = 8 };

/* A validated part, its runs indexed (pointers into the caller's bytes). */
typedef struct bk_part_view {
    uint64_t plan_hash, options_hash, receiver_count;
    uint32_t units, unit, total_runs, first_run, run_count;
    const uint8_t **runs;     /* run_count run records: runs first_run, first_run + 1, ... */
    uint64_t octa_count;      /* the octahedral probes this part holds (spec/part.md §2.1), 0 none */
    const uint8_t *octa;      /* their block */
} bk_part_view;

/* The cut of a bake of `runs` transport runs and `count` receivers into `units` units
 * (DIST.md): with units <= runs, unit k bakes runs [runs·k/units, runs·(k+1)/units) whole;
 * with more units than runs, run r is shared by units [units·r/runs, units·(r+1)/runs), each
 * gathering an equal slice of its receivers. Every unit then computes the caches of its own
 * runs only: max(runs, units) cache sets in all, not runs × units. */
void bk_dist_unit_runs(uint32_t runs, uint32_t units, uint32_t unit, uint32_t *first, uint32_t *end);
void bk_dist_run_units(uint32_t runs, uint32_t units, uint32_t run, uint32_t *first, uint32_t *end);
/* The receivers [begin, end) unit `unit` gathers in run `run` (one of its runs). */
void bk_dist_range(uint64_t count, uint32_t runs, uint32_t units, uint32_t unit, uint32_t run, uint64_t *begin,
                   uint64_t *end);

/* Checks a part's bytes (sizes, checksums, its runs and every run record's length and range)
 * and indexes its runs; LBK_ERR_BAD_INPUT with the reason in err. Free view->runs with free(). */
lbk_result bk_part_parse(const void *bytes, size_t size, bk_part_view *view, char *err, size_t err_len);

typedef struct bk_dist bk_dist;

/* A unit's recorder (replay 0) or the merge's player over n part views (replay 1, one per unit,
 * in unit order, validated by the caller against each other). */
/* options_hash: the bake options' identity (bake.c), stamped into the part (record) or
 * checked against every part (replay). */
lbk_result bk_dist_create(int replay, uint64_t plan_hash, uint64_t options_hash, uint32_t units, uint32_t unit,
                          const bk_part_view *parts, bk_dist **out);
void bk_dist_destroy(bk_dist *d);
/* The bake's receiver count and its transport runs, once known: fixes the unit's cut (record) or
 * checks the parts against them (replay). Runs from base_dependent on take the base's final
 * sample count as their budget (door states). targeted: the runs stop on an error target (each
 * unit of a shared run evaluates the stop on the run's stop receivers, which it gathers too:
 * bk_transport_options.stop_receivers), and a unit with any door run but not the base bakes the
 * base's stop receivers too, unrecorded, to learn its sample count. LBK_ERR_BAD_INPUT with a
 * message when they disagree or the cut is impossible. */
lbk_result bk_dist_set_cut(bk_dist *d, uint64_t count, uint32_t runs, uint32_t base_dependent, int targeted, char *err,
                           size_t err_len);
/* Record: share the caches of runs cut between units through this folder (cache_share.h;
 * NULL: every unit computes its runs' caches whole). The caller keeps it open until the end. */
struct bk_cache_share;
void bk_dist_set_cache_share(bk_dist *d, struct bk_cache_share *share);
/* What every transport run is handed (bk_transport_options.split). */
const bk_transport_split *bk_dist_split(const bk_dist *d);
/* After the bake (record): the part's bytes (malloc'd, the caller frees). Replay: LBK_OK when
 * every run of the parts was replayed. */
lbk_result bk_dist_finish(bk_dist *d, void **bytes, size_t *size, char *err, size_t err_len);
/* The first replay error's text ("" none). */
const char *bk_dist_error(const bk_dist *d);

#endif
