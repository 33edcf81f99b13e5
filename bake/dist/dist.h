/* Distributed bakes (bake/dist/DIST.md, spec/part.md): one bake cut into units by receivers.
 * A unit runs the whole pipeline up to the light transport (import, layout, caches: global but
 * deterministic, so every unit rebuilds them alike), gathers only its receivers' share of every
 * transport run (base, light sets, doors) and records what it computed into a part. The merge
 * runs the same pipeline, replays the parts instead of tracing, and then denoises, encodes and
 * writes as a local bake does: the container is byte-identical to `lbk bake`. */
#ifndef BK_DIST_H
#define BK_DIST_H

#include <stddef.h>
#include <stdint.h>

#include "bake/transport/transport.h"
#include "lbk/lbk.h"

#define BK_PART_MAGIC "LBKPART\0"
#define BK_PART_VERSION 1u
#define BK_PART_HEADER_SIZE 96u
#define BK_PART_RUN_HEADER_SIZE 96u
#define BK_PART_PASS_HEADER_SIZE 64u
#define BK_PART_MAX_UNITS 65536u
#define BK_PART_MAX_RUNS 65536u
#define BK_PART_MAX_PASSES 32u

/* Output arrays a run record holds (bk_transport_output's non-NULL members). */
enum { BK_PART_RADIANCE = 1, BK_PART_DIRECT = 2, BK_PART_IRRADIANCE = 4, BK_PART_VARIANCE = 8 };

/* A validated part, its runs indexed (pointers into the caller's bytes). */
typedef struct bk_part_view {
    uint64_t plan_hash, options_hash, receiver_count, begin, end;
    uint32_t units, unit, run_count;
    const uint8_t **runs;     /* run_count run records */
} bk_part_view;

/* The receivers of unit k of n: [count·k/n, count·(k+1)/n). */
void bk_dist_range(uint64_t count, uint32_t units, uint32_t unit, uint64_t *begin, uint64_t *end);

/* Checks a part's bytes (sizes, checksums, every run record's length) and indexes its runs;
 * LBK_ERR_BAD_INPUT with the reason in err. Free view->runs with free(). */
lbk_result bk_part_parse(const void *bytes, size_t size, bk_part_view *view, char *err, size_t err_len);

typedef struct bk_dist bk_dist;

/* A unit's recorder (replay 0) or the merge's player over n part views (replay 1, one per unit,
 * in unit order, validated by the caller against each other). */
/* options_hash: the bake options' identity (bake.c), stamped into the part (record) or
 * checked against every part (replay). */
lbk_result bk_dist_create(int replay, uint64_t plan_hash, uint64_t options_hash, uint32_t units, uint32_t unit,
                          const bk_part_view *parts, bk_dist **out);
void bk_dist_destroy(bk_dist *d);
/* The bake's receiver count, once known: fixes the unit's range (record) or checks the parts
 * against it (replay). LBK_ERR_BAD_INPUT with a message when they disagree. */
lbk_result bk_dist_set_receivers(bk_dist *d, uint64_t count, char *err, size_t err_len);
/* What every transport run is handed (bk_transport_options.split). */
const bk_transport_split *bk_dist_split(const bk_dist *d);
/* After the bake (record): the part's bytes (malloc'd, the caller frees). Replay: LBK_OK when
 * every run of the parts was replayed. */
lbk_result bk_dist_finish(bk_dist *d, void **bytes, size_t *size, char *err, size_t err_len);
/* The first replay error's text ("" none). */
const char *bk_dist_error(const bk_dist *d);

#endif
