/* The baker's one parallel-for over item ranges (transport, doors, texel push-out, probes):
 * worker threads pull fixed-size chunks from an atomic counter. Which thread runs an item never
 * changes its result as long as items are independent and write only their own outputs, so
 * dynamic chunking stays deterministic; `thread` (0 = the caller) is for per-thread counters
 * only. The core count lives here too, so every phase means the same by "all cores". */
#ifndef BK_PARALLEL_H
#define BK_PARALLEL_H

#include <stddef.h>

#define BK_MAX_THREADS 256

/* Cores online, clamped to [1, BK_MAX_THREADS]. */
int bk_online_cores(void);

/* The thread count for a request: `requested` > 0 is taken as is (clamped to BK_MAX_THREADS),
 * anything else means every online core. */
int bk_thread_count(int requested);

typedef void (*bk_chunk_fn)(void *user, size_t begin, size_t end, int thread);

/* Runs fn over [begin, end) in chunks of `chunk` items (0: 1) on up to `threads` threads (at
 * most BK_MAX_THREADS, never more than there are chunks; the caller's thread is one of them;
 * chunks whose thread could not start run on the others). One pthread per worker and call:
 * callers hand over at least a whole bounce, pass or block of receivers. */
void bk_parallel_chunks(size_t begin, size_t end, size_t chunk, int threads, bk_chunk_fn fn, void *user);

#endif
