/* The per-target arithmetic of lbk_dls_apply (spec/container.md §12.8), behind one table of
 * functions so that the scalar definition and the SIMD paths are interchangeable. Private.
 *
 * The definition, per target: decode base and entries with lbk_ahd_to_linear / lbk_sh9_unpack,
 * acc = base; acc += w_j·S_j for the active entries in ascending set order (a multiply, then an
 * add: never fused), encode once with lbk_ahd_from_linear / lbk_sh9_pack. Every path gives the
 * bytes of the scalar one (tests/lib/test_dls_kernels.c checks it lane by lane): the sums are the
 * same operations in the same order and precision; a path may compute a value of the codecs
 * another way only where it is provably the same value (AVX2: a correctly rounded quotient by
 * Markstein's correction instead of a division instruction) or the same byte (AVX2: the
 * encoder's direction and ratio bytes from float approximations with a derived error bound,
 * falling back to the operation-by-operation encoder near a rounding boundary). The files that
 * implement a path are compiled without contraction into fused multiply-adds (-ffp-contract=off
 * and the pragma below); the only FMAs are explicit ones that compute exact residuals. */
#ifndef LBK_DLS_KERNEL_H
#define LBK_DLS_KERNEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF /* GCC: -std=c11 (or -ffp-contract=off) keeps contraction off */
#endif

/* `count` targets that are consecutive in cluster order and contiguous in memory: bases at
 * base0/base1 (texels: the Ez and RGBA planes) or base0 (28-byte probes), outputs likewise. Target t's entries
 * start at entries + t·stride·payload; the m active ones are entry idx[j] of the target with
 * weight w[j] ≠ 0, idx ascending. */
typedef struct dls_batch {
    uint32_t count, stride, m;
    const uint32_t *idx;
    const float *w;
    const uint8_t *entries;
    const uint8_t *base0, *base1; /* texels: plane 0 (Ez) and plane 1 (RGBA); probes: base0 */
    uint8_t *out0, *out1;
} dls_batch;

/* Variable entries per target (prefix forms): target t has n[t] entries starting at
 * entries + off[t]·payload, entry e of it with weight we[off[t] + e − off[0]] (0 for a set that
 * is off). A target whose entries all weigh 0 gets exactly its base bytes. */
typedef struct dls_var_batch {
    uint32_t count;
    const uint32_t *n, *off;
    const float *we;
    const uint8_t *entries;
    const uint8_t *base0, *base1;
    uint8_t *out0, *out1;
} dls_var_batch;

typedef struct lbk_ahd_linear lbk_ahd_linear;
typedef struct lbk_sh9_rgb lbk_sh9_rgb;

typedef struct dls_kernels {
    const char *name;
    void (*texels)(const dls_batch *b);
    void (*probes)(const dls_batch *b);
    void (*texels_var)(const dls_var_batch *b);
    void (*probes_var)(const dls_var_batch *b);
    /* The codecs the kernels are made of, on `count` targets, for the tests: lbk_ahd_to_linear of
     * the plane words z[t], rgba[t]; lbk_ahd_from_linear into them; lbk_sh9_unpack of 28-byte probes. */
    void (*texel_decode)(const uint32_t *z, const uint32_t *rgba, uint32_t count, lbk_ahd_linear *out);
    void (*texel_encode)(const lbk_ahd_linear *in, uint32_t count, uint32_t *z, uint32_t *rgba);
    void (*probe_decode)(const uint8_t *probes, uint32_t count, lbk_sh9_rgb *out);
    /* The linear mode (LBK_DLS_RUNTIME_LINEAR) on prepared floats, element by element:
     * out[i] = base[i] + w[0]·src[0][i] + … + w[m−1]·src[m−1][i], summed left to right, each
     * term a multiply then an add (the byte kernels' accumulation, applied to n floats). */
    void (*lin_sum)(const float *base, const float *const *src, const float *w, uint32_t m, size_t n, float *out);
    /* Variable entries: `count` targets of f floats each, target t with n[t] entries (f floats
     * each, consecutive from `entries`) and their weights (consecutive from `we`); entries of
     * weight 0 are left out, as in the byte kernels. */
    void (*lin_var)(const float *base, const float *entries, const float *we, const uint32_t *n, uint32_t count,
                    uint32_t f, float *out);
    /* NULL, or what a job of the linear mode calls last: a path whose lin_sum writes with
     * non-temporal stores fences them here, so the job's outputs are ordered like ordinary
     * stores before the job reports done. */
    void (*lin_end)(void);
    /* lin_sum writes its outputs' whole lines without reading them first (non-temporal): the
     * runtime then does not prefetch the outputs of the linear mode, which would read them. */
    bool lin_streams;
} dls_kernels;

/* The definition, one target at a time; always available. */
const dls_kernels *dls_kernels_scalar(void);
/* 8 targets per step with AVX2 and FMA (x86-64, chosen at run time); NULL where the compiler or
 * the CPU lacks either. */
const dls_kernels *dls_kernels_avx2(void);

#endif
