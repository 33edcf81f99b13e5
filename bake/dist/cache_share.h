/* Shared radiosity caches (bake/dist/DIST.md §Shared caches): the units of a distributed run cut
 * every cache bounce into shares of cells; each unit computes the shares it claims, publishes
 * them as files in a folder every unit sees, and reads the others'. A bounce's floats depend only
 * on the scene, the options, the seed and the earlier bounces, so a share computed twice (a
 * claim taken over after its unit died) gives the same bytes, and any unit can compute any
 * share: units that run one after another (make -j2 of 16 units) compute what is not yet
 * published and read the rest, never wait on a unit that has not started. */
#ifndef BK_CACHE_SHARE_H
#define BK_CACHE_SHARE_H

#include <stddef.h>
#include <stdint.h>

#include "bake/transport/transport.h"
#include "lbk/bake_dist.h"
#include "lbk/lbk.h"

typedef struct bk_cache_share bk_cache_share;

/* Opens (and creates, one level) the folder dir for the plan plan_hash baked with the options
 * (and baker version) options_hash; lease: seconds a claim may stay unpublished before another
 * unit computes the share too (<= 0: 600). */
lbk_result bk_cache_share_open(const char *dir, uint64_t plan_hash, uint64_t options_hash, double lease,
                               bk_cache_share **out, char *err, size_t err_len);
void bk_cache_share_close(bk_cache_share *s);

/* Bounce b of run `run`, its cells cut into `shares` (>= 2) equal ranges; this unit takes share
 * `mine` first (>= shares: none of its own), then any unclaimed one, and reads the rest. Fills
 * b->out for every cell; a damaged share file is computed again. LBK_ERR_IO, or LBK_ERR_BAD_INPUT
 * for a share of another bake, with the reason in err. */
lbk_result bk_cache_share_bounce(bk_cache_share *s, uint32_t run, uint32_t shares, uint32_t mine,
                                 const bk_cache_bounce *b, char *err, size_t err_len);

/* What it did so far (the caller's size kept; s NULL: all zero). */
void bk_cache_share_get_stats(const bk_cache_share *s, lbk_bake_unit_stats *st);

/* Removes what units leave in dir (shares, claims, temporary files) and dir when it is then
 * empty; nothing else. 0 or an errno. */
int bk_cache_share_remove(const char *dir);

#endif
