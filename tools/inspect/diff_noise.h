/* The noise-aware verdict of lbk diff (spec/diff-json.md "Noise mode"): is the difference between
 * two bakes of an object larger than the Monte Carlo noise the two bakes carry? Each bake's noise
 * comes from two places: its own estimate (REPT, one number per bake) and the texels themselves
 * (a robust high-pass of the lightmap, per object and per 4×4 tile). The rule, per object, light
 * grid and light set, with α the false-alarm rate:
 *
 *   mean shift  m = Σ(b − a) / Σa over every sample and normal (luminance);
 *   its noise   σ_m² = (s_A² + s_B²)/N + c²·(r_A² + r_B²)
 *               s = relative per-sample noise (texels: high-pass of the object; probes: REPT),
 *               r = REPT's final estimate, c = TL_NOISE_COMMON (the common-mode share, measured);
 *   a sample is significant when |b₀ − a₀| > k_sample·σ, b₀, a₀ its level (texels: luminance at
 *               +Z; probes: the mean over the six axis normals), σ² = (σ_A·a₀)² + (σ_B·b₀)²,
 *               σ_X² = t_X² + c²·r_X², t = the local noise (texels: the high-pass of the sample's
 *               4×4 tile and its 2-texel surround; probes: TL_NOISE_PROBE_SPREAD × REPT);
 *   the item is within noise when |m| ≤ k_mean·σ_m and the share of significant samples is at most
 *               max(TL_NOISE_SHARE_FACTOR·α, α + 4·√(α/N)),
 * with k_mean = k_sample = Φ⁻¹(1 − α/2). */
#ifndef LBK_TOOLS_DIFF_NOISE_H
#define LBK_TOOLS_DIFF_NOISE_H

#include <stddef.h>
#include <stdint.h>

/* Share of the REPT estimate that is common to every receiver of a bake (a global factor: the
 * bounce ratio of the analytic tail, the radiosity cache), so that it does not average out over an
 * object: the spread of object means over reseeds was 0.05–0.27 × REPT on two_rooms,
 * cornell_box and cornell_box_bjs (spec/diff-json.md). */
#define TL_NOISE_COMMON 0.3
/* Monte Carlo noise of a texel has heavier tails than a normal distribution and the high-pass
 * reads it 10–20 % low: over 58 reseed pairs of two_rooms, cornell_box and cornell_box_bjs the
 * share of texels beyond k_sample reached 16 α (α = 0.001). A share of significant samples counts
 * only above this many α. */
#define TL_NOISE_SHARE_FACTOR 25.0
#define TL_NOISE_DEFAULT_FALSE_ALARM 0.001
/* Probes have no neighbourhood to measure their own noise in, and REPT's estimate is one RMS over
 * all of them: single probes were up to 1.85 × REPT over 8 reseeds of two_rooms. A probe's sample
 * test takes twice REPT's noise. */
#define TL_NOISE_PROBE_SPREAD 2.0

typedef struct tl_noise_model {
    double false_alarm;     /* α */
    double k_mean, k_sample;
    double common;          /* c */
    /* REPT's final estimates: [side][0 texels, 1 probes]; 0 when REPT is absent */
    double rept[2][2];
    /* per side: the bake was denoised (META bake.denoise = auto). The denoiser removes the high
     * frequencies a texel's own high-pass measures, and what noise remains is smooth, so for a
     * denoised bake the texel noise is at least REPT's (the undenoised estimate, an upper side) */
    int denoised[2];
} tl_noise_model;

/* α → the model's thresholds; rept from the two bakes. */
void tl_noise_model_init(tl_noise_model *m, double false_alarm, const double rept_a[2], const double rept_b[2]);
/* Φ⁻¹(p) for 0 < p < 1. */
double tl_normal_quantile(double p);

typedef struct tl_noise_stats {
    int evaluated;
    uint64_t count;          /* samples with light on either side */
    double sum_a, sum_d, sum_d2;
    double mean_shift;       /* m */
    double rmse;             /* √(mean (b − a)²), luminance */
    double noise_a, noise_b; /* s_A, s_B */
    double noise_common;     /* c·√(r_A² + r_B²) */
    double noise_mean;       /* σ_m */
    double z;                /* m / σ_m */
    uint64_t significant;    /* samples over k_sample */
    double significant_share, share_limit;
    int shift_significant, share_significant;
    int within_noise;
} tl_noise_stats;

/* Starts an item: kind 0 texels, 1 probes; s_a, s_b its relative per-sample noise. */
void tl_noise_begin(tl_noise_stats *s, const tl_noise_model *m, int kind, double s_a, double s_b);
/* One sample: n normals × 3 channels of irradiance, A and B; t_a, t_b its local relative noise. */
void tl_noise_add(tl_noise_stats *s, const tl_noise_model *m, int kind, const float *a, const float *b, int n,
                  double t_a, double t_b);
void tl_noise_end(tl_noise_stats *s, const tl_noise_model *m);
/* The sample test alone (1: significant), for heatmaps. */
int tl_noise_sample_significant(const tl_noise_model *m, int kind, double t_a, double t_b, const float *a,
                                const float *b, int n);

/* Relative noise of a lightmap from its own texels: the median absolute deviation of the
 * residual of each texel's value against the mean of its 4 neighbours, relative to the texel's
 * level ref, inside the rectangle less its 1-texel border (dilated padding), scaled to a standard
 * deviation (1.4826 / √1.25). values and ref are w × h, row-major. Returns < 0 when fewer than 16
 * texels are usable (the caller falls back on REPT). */
double tl_noise_highpass(const float *values, const float *ref, uint32_t w, uint32_t h);
/* The same per 4×4 tile from the tile and a 2-texel surround (values relative to themselves),
 * into out (w × h, every texel of a tile gets its tile's); fallback where too few are usable. */
void tl_noise_highpass_tiles(const float *values, uint32_t w, uint32_t h, double fallback, float *out);

#endif
