/* The baker's parallel-for over item ranges (transport.c, door_guided.c): worker threads pull
 * fixed-size chunks from an atomic counter. Which thread runs an item never changes its result
 * as long as items are independent and write only their own outputs, so dynamic chunking stays
 * deterministic; `thread` (0 = the caller) is for per-thread counters only. */
#ifndef BK_PARALLEL_H
#define BK_PARALLEL_H

#include <stddef.h>

typedef void (*bk_chunk_fn)(void *user, size_t begin, size_t end, int thread);

/* Runs fn over [begin, end) in chunks of `chunk` items (0: 1) on up to `threads` threads (at
 * most 256, never more than there are chunks; the caller's thread is one of them). One pthread
 * per worker and call: callers hand over at least a whole bounce or block of receivers. */
void bk_parallel_chunks(size_t begin, size_t end, size_t chunk, int threads, bk_chunk_fn fn, void *user);

#endif
