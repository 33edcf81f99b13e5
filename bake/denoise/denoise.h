/* Denoising of the transport's result: lightmap texels in lightmap space, GLG probes along their
 * tetrahedral edges. Method, parameters, what was measured and the guarantees:
 * bake/denoise/DENOISE.md.
 *
 * The filter lives with the transport because it finishes the transport's estimate: it uses the
 * transport's own per-receiver variance (bk_transport_output.variance) to decide how far apart
 * two receivers' values may be before they are no longer "the same light seen through noise",
 * and runs on the transport's output (incident radiance SH9 per receiver) before anything
 * encodes it.
 *
 * Linearity (light sets and doors): the weights are computed once, from a guide (its
 * luminance, its variance and the geometry; the pipeline passes base + every light set and
 * door contribution), and kept in a bk_denoiser; bk_denoiser_apply then filters any
 * per-receiver SH with those same weights, so denoise(base + set) = denoise(base) +
 * denoise(set) up to float rounding and a light set toggled at run time adds exactly what it
 * would have added to a denoised sum. Every weight is >= 0 and each output is a normalised
 * combination (weights sum to 1), so an output never leaves the range of the inputs it
 * averages: the furnace (every input within its bound) stays within its bound.
 *
 * Texels are averaged only with texels of the same chart (never across a chart border) on the
 * same page; probes only with tetrahedral neighbours they can see (an unoccluded segment
 * between the two). LLG probes are not filtered.
 *
 * Determinism: every output is computed by one thread from inputs that do not change during
 * the step (ping-pong buffers), in a fixed order; results do not depend on the thread count. */
#ifndef BK_DENOISE_H
#define BK_DENOISE_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "lbk/sh.h"
#include "bake/layout/atlas.h"
#include "bake/layout/texels.h"
#include "bake/probes/glg_place.h"
#include "scene/scene.h"
#include "scene/tracer.h"
#include "bake/transport/transport.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The texel filters compared in DENOISE.md. */
enum bk_denoise_method {
    BK_DENOISE_AUTO = 0,    /* the measured choice (DENOISE.md) */
    BK_DENOISE_ATROUS,      /* variance-guided à-trous (edge-avoiding wavelets, SVGF-style) */
    BK_DENOISE_NLM,         /* joint non-local means with variance-normalised patch distances */
    BK_DENOISE_BLUR         /* geometry-only cross-bilateral (no luminance stop): a control
                               that must fail the contact-shadow test */
};

typedef struct bk_denoise_options {   /* zero = defaults */
    int method;              /* enum bk_denoise_method */
    int threads;             /* 0: all online cores (results do not depend on it) */
    int iterations;          /* à-trous levels (steps 1, 2, 4, ...); 0: 4 */
    int radius;              /* NLM search half-window (BLUR: its window); 0: 5, at most 16 */
    float sigma_lum;         /* NLM: k of the patch distance, 0: 1; à-trous and probes: the stop
                                in noise standard deviations, 0: 4 */
    float sigma_normal;      /* normal stop exponent, max(0, n·n')^s; 0: 32 */
    float sigma_plane;       /* distance off the tangent plane, texel sizes; 0: 0.5 */
    float sigma_albedo;      /* albedo stop (Euclidean RGB distance); 0: no albedo stop (DENOISE.md) */
    float clamp;             /* an output moves at most clamp × its noise std from its input;
                                0: 2; < 0: no clamp */
    int no_probes;           /* 1: leave GLG probes as they are */
} bk_denoise_options;

/* Everything the weights are built from. Receivers are numbered as in the bake (bake.c): texel
 * receivers [0, texel_count) map to texels->receivers[texel_of_receiver[k]], GLG probes are
 * receivers [glg_first, glg_first + glg->probe_count). */
typedef struct bk_denoise_inputs {
    const bk_scene *scene;            /* albedo guide (materials, uv0); NULL: no albedo */
    const bk_tracer *tracer;          /* probe edge visibility; NULL: no probe filtering */
    const bk_atlas *atlas;            /* chart of each texel's triangle */
    const bk_texels *texels;          /* NULL or texel_count 0: no texel filtering */
    const uint32_t *texel_of_receiver;
    size_t texel_count;
    const bk_glg *glg;                /* NULL: no probe filtering */
    size_t glg_first;
    size_t receiver_count;            /* size of the radiance and variance arrays */
    const lbk_sh9_rgb *radiance;      /* the guide, per receiver: the base bake (+ the sets) */
    const float *variance;            /* per receiver (bk_transport_output.variance, summed) */
} bk_denoise_inputs;

typedef struct bk_denoise_stats {
    double seconds;                   /* building the weights (bk_denoiser_create) */
    size_t texels, probes;            /* receivers filtered */
    size_t probe_edges, probe_edges_visible;
    size_t clamped;                   /* texels and probes whose move was limited by the clamp */
} bk_denoise_stats;

typedef struct bk_denoiser bk_denoiser;

/* Builds the weights from the guide in `in`. *out must be destroyed with bk_denoiser_destroy.
 * Errors: LBK_ERR_INVALID_ARGUMENT (NULL in/out/radiance/variance, texels without atlas or
 * mapping, receiver ranges outside receiver_count), LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_denoiser_create(const bk_denoise_inputs *in, const bk_denoise_options *opt, bk_denoiser **out);

/* Filters `radiance` (receiver_count entries, numbered like the inputs) in place with the
 * stored weights: texel and GLG receivers change, every other receiver is left as it is. */
lbk_result bk_denoiser_apply(const bk_denoiser *d, lbk_sh9_rgb *radiance);
/* The same for the classes with filter[k] set only (BK_CLASS_TEXEL: the texel receivers,
 * BK_CLASS_GLG: the GLG probes; the two filters are independent, so a class left out keeps its
 * input exactly and the other gets what bk_denoiser_apply gives it). */
lbk_result bk_denoiser_apply_classes(const bk_denoiser *d, lbk_sh9_rgb *radiance, const int filter[BK_RECEIVER_CLASSES]);

/* The estimated error of the denoised result per receiver class, relative to the RMS of the
 * denoised values as the transport's estimate is (TRANSPORT.md §Error estimate; DENOISE.md
 * §What the report says). With A, B the two halves' X per receiver, X = (A + B)/2,
 * δ = (A − B)/2 and D the filter (these weights and clamp):
 *   noise² = Σ (Dδ)²                      — the noise the filter leaves, with its correlation
 *                                           between receivers (the cache's), which Σ w²σ² misses;
 *   bias²  = max(0, Σ ((D − I)X)² − Σ ((D − I)δ)²) — what the filter moved beyond its noise;
 * both unbiased for fixed weights (δ has X's variance and no mean). Receivers the filter does
 * not touch contribute δ² (the transport's own estimate); with D = I every class gets exactly
 * the transport's estimate. */
typedef struct bk_denoise_error {
    double rel_rmse[BK_RECEIVER_CLASSES]; /* √(noise² + bias²) / RMS of the denoised X */
    double noise[BK_RECEIVER_CLASSES];    /* √noise² / RMS, and the bias part alone */
    double bias[BK_RECEIVER_CLASSES];
    double probe_rel_rmse;                /* GLG and LLG probes together (REPT's probe figure) */
    double seconds;
} bk_denoise_error;

/* halves: 2 per receiver (bk_transport_output.halves, A then B); class_end as the transport's
 * (bk_transport_options.class_end: the end of the texel, GLG and LLG classes). d NULL: the
 * identity filter (the transport's own two-halves estimate, bias 0), over class_end's last
 * receivers, for contributions that were not denoised. Errors: LBK_ERR_INVALID_ARGUMENT,
 * LBK_ERR_OUT_OF_MEMORY. */
/* The same estimate per group of receivers (a group: an object's texels), over the first
 * `count` receivers (group[i] its group, >= group_count for none): sums kept so that groups pool
 * to the class figure, noise2 + bias2 over value2 (the bias clamp is per group). */
typedef struct bk_denoise_group_error {
    size_t receivers;
    double rel_rmse, noise, bias;  /* relative to the RMS of the group's (denoised) values */
    double noise2, bias2, value2;  /* the sums they come from */
} bk_denoise_group_error;
typedef struct bk_denoise_groups {
    size_t count;                  /* receivers 0 .. count − 1 belong to groups */
    const uint32_t *group;
    size_t group_count;
    bk_denoise_group_error *out;   /* group_count entries */
} bk_denoise_groups;
lbk_result bk_denoiser_error(const bk_denoiser *d, const float *halves, const size_t class_end[BK_RECEIVER_CLASSES],
                             bk_denoise_error *out);
/* Radiance riding on the estimate's filter pass (a pass's cost is its weights, not its
 * channels): `filtered` (27 floats per texel receiver) gets the filter's output for the texel
 * receivers of `radiance`, before the clamp's blend (bk_denoiser_blend_texels), and `done` says
 * whether it did (the one-level filter, NLM, the default, carries it; else filter as usual). */
typedef struct bk_denoise_ride {
    const lbk_sh9_rgb *radiance;
    float *filtered;
    int done;
} bk_denoise_ride;
/* bk_denoiser_error, and each group's estimate from the same filter pass; with `cross` (NULL:
 * none) the noise term is Σ cross², cross from bk_denoiser_half_delta, in place of Σ (Dδ)²; with
 * `ride` (NULL: none) the radiance it names filtered in the same pass. Errors as above, and
 * LBK_ERR_INVALID_ARGUMENT for groups past the receivers. */
lbk_result bk_denoiser_error_groups(const bk_denoiser *d, const float *halves, const size_t class_end[BK_RECEIVER_CLASSES],
                                    bk_denoise_error *out, const bk_denoise_groups *groups, const float *cross,
                                    bk_denoise_ride *ride);
/* The texel receivers of `radiance` moved to a ride's `filtered` by the clamp's blend: what
 * bk_denoiser_apply_classes gives the texels (the GLG probes are left as they are). */
lbk_result bk_denoiser_blend_texels(const bk_denoiser *d, lbk_sh9_rgb *radiance, const float *filtered);
/* The same for `count` inputs (halves[j], each as above) into out[j], in one filter pass per 13
 * inputs; out[j].seconds is the pass time shared equally. */
lbk_result bk_denoiser_errors(const bk_denoiser *d, const float *const *halves, size_t count,
                              const size_t class_end[BK_RECEIVER_CLASSES], bk_denoise_error *out);

/* The noise the filter leaves, measured as the transport measures its own: each half filtered by
 * weights built from that half alone (D_A from the guide `in` with its base part — base, per
 * receiver — at half A's level and the base's variance doubled, D_B likewise from B),
 * out[i] = (D_A·A − D_B·B)_i / 2 per receiver (in->receiver_count floats), for
 * bk_denoiser_error_groups' `cross`. Why: Σ (Dδ)² is unbiased for fixed weights, but the filter's
 * weights follow the very noise they filter (a texel that reads bright finds its like among its
 * neighbours), so what a denoised bake differs by from another seed's is more than Σ (Dδ)² says
 * (DENOISE.md, "What the report says"). A half's filter sees its own noise as the full run's
 * filter sees the full run's. d: the filter bk_denoiser_create built from the same `in`, whose
 * geometry, charts and probe visibility the halves' filters share (only their weights are their
 * own). Errors: LBK_ERR_INVALID_ARGUMENT (NULLs, in->receiver_count not d's),
 * LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_denoiser_half_delta(const bk_denoiser *d, const bk_denoise_inputs *in, const lbk_sh9_rgb *base,
                                  const float *base_variance, const float *halves, float *out);
/* Unfiltered (the transport's own estimate per group): the same sums with D = I. */
lbk_result bk_denoise_groups_unfiltered(const float *halves, const bk_denoise_groups *groups);
void bk_denoiser_stats(const bk_denoiser *d, bk_denoise_stats *stats);
void bk_denoiser_destroy(bk_denoiser *d);

#ifdef __cplusplus
}
#endif
#endif
