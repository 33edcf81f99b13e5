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

/* Probe filter: weights built from the base probes, applied to any probe SH. */
typedef struct dn_probes {
    size_t count;              /* GLG probes */
    size_t first;              /* their first receiver */
    uint32_t *adj_first;       /* count + 1: visible neighbours of probe i are adj[adj_first[i]..) */
    uint32_t *adj;
    float *w;                  /* weight per adjacency entry (unnormalised; self weight 1) */
    float *w_sum;              /* 1 + Σ w per probe */
    float *alpha;              /* clamp blend per probe (1: the filtered value, 0: the input) */
    size_t edges, edges_visible, clamped;
} dn_probes;

lbk_result dn_probes_build(const bk_denoise_inputs *in, const bk_denoise_options *opt, int threads, dn_probes *out);
/* Filters the GLG probes' receivers of `vals` (ch ≤ DN_MAX_CH floats per receiver, each
 * channel on its own with the same weights) in place. */
lbk_result dn_probes_apply(const dn_probes *p, float *vals, int ch);
void dn_probes_free(dn_probes *p);

/* Fluence/4 luminance of a probe's SH (the transport's probe error scalar: π·L00·Y00·4/4). */
float dn_probe_lum(const lbk_sh9_rgb *sh);

#endif
