/* Internals shared by denoise.c (the API and the texel filters) and denoise_probes.c. */
#ifndef BK_DENOISE_IMPL_H
#define BK_DENOISE_IMPL_H

#include <stddef.h>
#include <stdint.h>

#include "bake/denoise/denoise.h"

/* Luminance weights (ITU-R BT.709, as bk_lum). */
#define DN_LR 0.2126f
#define DN_LG 0.7152f
#define DN_LB 0.0722f

/* Floats per lbk_sh9_rgb: the most channels one filter pass carries. */
#define DN_MAX_CH 27

/* The guide a filter's weights come from, per receiver: `in`'s radiance and variance, or, with
 * base set, half `half`'s (bk_denoiser_half_delta): the base part at that half's level (scaled by
 * A/X, resp. B/X, within [0, 2]) and the base's variance added once more (a half has half the
 * samples). */
typedef struct dn_guide {
    const bk_denoise_inputs *in;
    const lbk_sh9_rgb *base;         /* NULL: in's own radiance and variance */
    const float *base_variance, *halves;
    int half;                        /* 0: A, 1: B */
} dn_guide;
void dn_guide_at(const dn_guide *g, size_t receiver, lbk_sh9_rgb *sh, float *variance);

/* The probes' filter graph: the tetrahedron edges a probe can see along, the same for every
 * guide (the base's and each half's). */
typedef struct dn_probes {
    size_t count;              /* GLG probes */
    size_t first;              /* their first receiver */
    uint32_t *adj_first;       /* count + 1: visible neighbours of probe i are adj[adj_first[i]..) */
    uint32_t *adj;
    float sigma_lum, clamp;    /* resolved options */
    size_t edges, edges_visible;
} dn_probes;

/* One guide's weights over that graph. */
typedef struct dn_probe_weights {
    float *w;                  /* weight per adjacency entry (unnormalised; self weight 1) */
    float *w_sum;              /* 1 + Σ w per probe */
    float *alpha;              /* clamp blend per probe (1: the filtered value, 0: the input) */
    size_t clamped;
} dn_probe_weights;

lbk_result dn_probes_build(const bk_denoise_inputs *in, const bk_denoise_options *opt, int threads, dn_probes *out);
lbk_result dn_probe_weights_build(const dn_probes *p, const dn_guide *guide, dn_probe_weights *out);
/* Filters the GLG probes' receivers of `vals` (ch ≤ DN_MAX_CH floats per receiver, each
 * channel on its own with the same weights) in place. */
lbk_result dn_probes_apply(const dn_probes *p, const dn_probe_weights *w, float *vals, int ch);
void dn_probes_free(dn_probes *p);
void dn_probe_weights_free(dn_probe_weights *w);

/* Fluence/4 luminance of a probe's SH (the transport's probe error scalar: π·L00·Y00·4/4). */
float dn_probe_lum(const lbk_sh9_rgb *sh);

#endif
