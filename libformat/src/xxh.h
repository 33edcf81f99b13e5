/* xxHash for liblbk: XXH3-64 as in spec §1.1. Where the installed libxxhash was built with its x86
 * runtime dispatch (Debian's is), the checksums use it: the same hash, computed with AVX2 or
 * AVX-512 when the CPU has them (about 2.5x the SSE2 default on 50 MB: 30 vs 12 GB/s, so a
 * section's checksum costs well under a memcpy of it; bench/bench_container.c). The Makefile
 * defines LBK_HAVE_XXH_DISPATCH when the header and its symbols are there; otherwise the portable
 * functions. Include this instead of <xxhash.h> (after XXH_STATIC_LINKING_ONLY where needed). */
#ifndef LBK_XXH_H
#define LBK_XXH_H

#if defined(LBK_HAVE_XXH_DISPATCH)
#include <xxh_x86dispatch.h> /* maps XXH3_64bits and XXH3_64bits_update to their _dispatch forms */
#else
#include <xxhash.h>
#endif

#endif
