/* The baker's random numbers: counter-based streams, so a sample depends only on what it is
 * (seed, the phase's salt, a key, an item index) and never on the thread that draws it or on
 * the order items run in. That is what keeps bakes byte-identical at any thread count. */
#ifndef BK_RNG_H
#define BK_RNG_H

#include <stdint.h>

#define BK_GOLDEN64 0x9E3779B97F4A7C15ull /* 2^64 / φ: the Weyl increment of splitmix64 */

/* The splitmix64 finaliser: a bijective 64-bit mix, also the baker's hash. */
static inline uint64_t bk_mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

typedef struct bk_rng { uint64_t s; } bk_rng;

/* The stream of one item. `salt` keeps the phases (transport, doors) apart for the same seed;
 * `key` packs whatever else names the stream (domain, pass, bounce...), each caller its own
 * layout; `item` is the receiver, cell or photon index. */
static inline bk_rng bk_rng_stream(uint64_t seed, uint64_t salt, uint64_t key, uint64_t item)
{
    uint64_t h = bk_mix64(seed ^ salt);
    h = bk_mix64(h ^ key);
    h = bk_mix64(h ^ item * BK_GOLDEN64);
    bk_rng r = {h};
    return r;
}

/* Next uniform double in [0, 1), 53 bits. */
static inline double bk_rng_next(bk_rng *r)
{
    r->s += BK_GOLDEN64;
    return (double)(bk_mix64(r->s) >> 11) * (1.0 / 9007199254740992.0);
}

#endif
