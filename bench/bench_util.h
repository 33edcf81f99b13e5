/* What several benches share: CPU clocks (benches compare CPU time side by side in one run, so
 * that other jobs on a shared machine do not enter the ratio) and a small seeded generator for
 * the synthetic levels (SplitMix64: the same numbers on every machine and compiler). */
#ifndef LBK_BENCH_UTIL_H
#define LBK_BENCH_UTIL_H

#include <stdint.h>
#include <time.h>

/* CPU seconds of the calling thread (single-threaded measurements). */
static inline double bench_thread_cpu(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* CPU seconds of the whole process (work spread over the baker's threads). */
static inline double bench_process_cpu(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static inline uint64_t bench_mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

typedef struct bench_rng { uint64_t s; } bench_rng;

/* Uniform in [0, 1). */
static inline double bench_next(bench_rng *r)
{
    r->s += 0x9E3779B97F4A7C15ull;
    return (double)(bench_mix(r->s) >> 11) * (1.0 / 9007199254740992.0);
}

#endif
