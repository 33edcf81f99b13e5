/* The noise-aware verdict of lbk diff (spec/diff-json.md "Noise mode"): is the difference between
 * two bakes of an item larger than the Monte Carlo noise the two bakes carry? Each bake's noise
 * comes from two places: its own estimate (REPT: the transport's half estimates, one RMS for the
 * texels and one for the probes) and the texels themselves (a robust high-pass of the lightmap, per
 * object and per 4×4 tile). Each receiver class (tl_noise_class) scales them by its own factors,
 * measured by the reseed study (bench/diff_reseed.py). Per item, with α the false-alarm rate, three
 * tests each at α/3 (so the item's false-alarm rate is at most α):
 *
 *   luminance mean shift  m = Σ(b − a) / Σa over every sample and normal;
 *   its noise   σ_m² = max(κ²·(s_A² + s_B²)/N + ν·(f_A² + f_B²)/(N·ā²), ν·SE²) + c²·(r_A² + r_B²)
 *               s = relative per-sample noise (texels: high-pass of the object; probes: REPT),
 *               r = REPT's estimate, c = TL_NOISE_COMMON, κ the class's mean_scale, SE the
 *               ratio estimator's own standard error from the samples, ν its empirical_scale;
 *               significant when |m| > k_mean·σ_m, k_mean = Φ⁻¹(1 − α/6);
 *   chromaticity shift, per channel C of R, G, B: g_C = (ΣC_b/ΣL_b) / (ΣC_a/ΣL_a) − 1 (L the
 *               luminance; a channel below TL_NOISE_CHROMA_MIN_SHARE of the luminance on either
 *               side is not tested); its noise σ_g² = max(χ²·(s_A² + s_B²)/N, ν·SE_g²) +
 *               (χ_c·c)²·(1/λ_C − 1)·(r_A² + r_B²), λ_C = w_C·ΣC_a/ΣL_a the channel's share of
 *               A's luminance (w_C its luminance weight): a channel's common shift relative to
 *               the luminance's grows as its share falls (diff_noise.c, chroma_end);
 *               χ, χ_c the class's; significant when max |g_C|/σ_g > k_chroma = Φ⁻¹(1 − α/18);
 *   significant samples: a sample is significant when |b₀ − a₀| > k_sample·σ (k_sample =
 *               3.29 whatever α), b₀, a₀ its level (texels: luminance at +Z; probes: the mean over
 *               the normals), σ² = (σ_A·a₀)² + (σ_B·b₀)² + f_A² + f_B², σ_X² = (ρ·t_X)² + c²·r_X²,
 *               t the local noise
 *               (texels: the high-pass of the sample's 4×4 tile and its 2-texel surround; probes:
 *               REPT), ρ the class's sample_spread; f = φ·r·level_ref the absolute floor of a
 *               receiver lit by rare paths (added to σ²). Reseeds make a sample significant with
 *               the class's rate p₀ (measured); the count is significant when a Binomial(N, p₀)
 *               count reaches it with probability at most α/6; likewise the count of extreme
 *               samples (beyond TL_NOISE_K_EXTREME σ at their darker side) at the class's
 *               extreme_rate, α/6. An object too small for its own texel noise has no count test.
 *               The significant samples are correlated (tl_count_critical): their count is
 *               taken as D × a Binomial(N/D, p₀) count, D the class's count_dispersion.
 * The item is within noise when none is significant. */
#ifndef LBK_TOOLS_DIFF_NOISE_H
#define LBK_TOOLS_DIFF_NOISE_H

#include <stddef.h>
#include <stdint.h>

/* Share of the REPT estimate that is common to every receiver of a bake (a global factor: the
 * bounce ratio of the analytic tail, the radiosity cache), so that it does not average out over an
 * object: the spread of object means over reseeds was 0.05–0.27 × REPT on two_rooms,
 * cornell_box and cornell_box_bjs (spec/diff-json.md). */
#define TL_NOISE_COMMON 0.3
#define TL_NOISE_DEFAULT_FALSE_ALARM 0.001
/* A lightmapped object too small for its own high-pass (under 16 usable texels) takes REPT's
 * texel estimate × this, as probes do (lights_punctual_lamp's 6×5-texel object: 13 of 30 texels
 * beyond 3.29σ at 1×). */
#define TL_NOISE_REPT_SPREAD 3.0
/* At the high preset (16384 samples, denoised) the texels' reseed noise is spatially correlated
 * and their own high-pass reads it low: over cornell_box's reseeds at high the samples' normalised
 * deviation had RMS 2.65 (0.70 at fast) and 14 % of texels were beyond 3.29σ; probes likewise
 * (lights_punctual_lamp at high: GLG 2.47, LLG 7.8 at the classes' ρ). Every class's local noise
 * takes this factor at high. */
#define TL_NOISE_HIGH_TEXEL_SPREAD 3.0
/* The sample test's threshold, Φ⁻¹(1 − 0.0005), whatever α: each class's rate p₀ is measured at it. */
#define TL_NOISE_K_SAMPLE 3.2905267314918945
/* A sample beyond this many σ, its relative noise taken at its darker side, is extreme (a probe
 * 100× brighter): reseeds make one at the class's extreme_rate (bench/diff_reseed.py), and the
 * count of extreme samples is a second binomial test; the two counts share the count test's α/3. */
#define TL_NOISE_K_EXTREME 30.0
/* The texels' high-pass takes the larger spread of the residuals against neighbours 1, 2, …,
 * this many texels away: noise correlated over a few texels (the radiosity cache) reads low
 * against the nearest ones only. */
#define TL_NOISE_HIGHPASS_REACH 2
/* A texel's local noise is read from residuals of texels within this factor of its level
 * (tl_noise_highpass_tiles): a tile holding a shadow's edge, or a small object lit directly in its
 * upper rows and only by bounces below (lights_punctual_lamp's 6 × 12 node1 at the high preset,
 * whose dark rows read the bright rows' zero noise and came out 5–18σ), has two noises. */
#define TL_NOISE_LEVEL_BAND 4.0
/* A rectangle of at most this many texels lends its residuals to tiles with too few of their own. */
#define TL_NOISE_SMALL_RECT 4096
/* A channel that carries less than this share of the luminance (C/L, both sides) has too few
 * paths to compare its chromaticity. */
#define TL_NOISE_CHROMA_MIN_SHARE 0.05

/* Receiver classes: each has its own noise factors (diff_noise.c, measured by bench/diff_reseed.py). */
typedef enum tl_noise_class {
    TL_NOISE_TEXELS = 0,    /* a lightmapped object */
    TL_NOISE_GLG,           /* the global light grid */
    TL_NOISE_LLG,           /* an LLG object */
    TL_NOISE_OCTP,          /* the octahedral probes */
    TL_NOISE_SET_TEXELS,    /* a light set, texel entries */
    TL_NOISE_SET_PROBES,    /* a light set, GLG or LLG entries */
    TL_NOISE_DOOR_TEXELS,   /* a door state or combination (differences of runs), texel entries */
    TL_NOISE_DOOR_PROBES,   /* the same, GLG or LLG entries */
    TL_NOISE_CLASS_COUNT_
} tl_noise_class;

typedef struct tl_noise_class_params {
    const char *name;       /* "texels", "glg", "llg", "octp", "set_texels", "set_probes", "door_texels",
                               "door_probes" */
    int kind;               /* 0 texels (REPT's texel estimate, level at +Z), 1 probes */
    double mean_scale;      /* κ */
    double sample_spread;   /* ρ */
    double sample_rate;     /* p₀ */
    double chroma_scale;    /* χ */
    double chroma_common;   /* χ_c */
    double empirical_scale; /* ν: variance factor of the samples' own standard errors (correlated samples) */
    double floor_scale;     /* φ: a sample's absolute noise is at least φ·r·level_ref */
    double extreme_rate;    /* p_x: reseeds' rate of extreme samples (TL_NOISE_K_EXTREME) */
    double count_dispersion; /* D: the significant count's variance over a binomial's (clumps) */
} tl_noise_class_params;
const tl_noise_class_params *tl_noise_class_get(int cls);

typedef struct tl_noise_model {
    double false_alarm;     /* α */
    double k_mean, k_sample, k_chroma;
    double common;          /* c */
    /* REPT's final estimates: [side][0 texels, 1 probes]; 0 when REPT is absent */
    double rept[2][2];
    /* per side: the bake was denoised (META bake.denoise = auto). The denoiser removes the high
     * frequencies a texel's own high-pass measures, and what noise remains is smooth, so for a
     * denoised bake the texel noise is at least REPT's (the undenoised estimate, an upper side) */
    int denoised[2];
    /* [side][kind]: the median level of the bake's lit texels / probes. r × level_ref is the
     * absolute noise of a typical receiver: one far darker is lit by rare paths (a leak), whose
     * noise is absolute, not relative to its own level. */
    double level_ref[2][2];
    /* the preset's factor on every sample's local noise (1; TL_NOISE_HIGH_TEXEL_SPREAD when a
     * bake is of the high preset, META bake.preset) */
    double texel_spread;
} tl_noise_model;

/* A denoised bake's texels are at least REPT's noise (tl_noise_model.denoised): the floor of one
 * side's texel noise, 0 when that side was not denoised. */
double tl_noise_texel_floor(const tl_noise_model *m, int side);
/* The level a sample is judged at: luminance at +Z (the first normal) for texels (kind 0), the
 * mean luminance over the n normals for probes (kind 1). */
double tl_noise_level(const float *v, int kind, int n);

/* α → the model's thresholds; rept from the two bakes. */
void tl_noise_model_init(tl_noise_model *m, double false_alarm, const double rept_a[2], const double rept_b[2]);
/* Φ⁻¹(p) for 0 < p < 1. */
double tl_normal_quantile(double p);

typedef struct tl_noise_stats {
    int evaluated;
    int cls;                 /* tl_noise_class */
    uint64_t count;          /* samples with light on either side */
    uint64_t tested;         /* of them, those with local noise on both sides: the count test's N */
    double sum_a, sum_d, sum_d2;
    /* the moments of the empirical standard errors: luminance d = b − a and a (means over the
     * normals), and per channel its change dc */
    double sum_dd, sum_da, sum_aa;
    double sum_ca[3], sum_cb[3]; /* channel sums (mean over normals) */
    double sum_dcdc[3], sum_dcdl[3];
    double mean_shift;       /* m */
    double rmse;             /* √(mean (b − a)²), luminance */
    double noise_a, noise_b; /* s_A, s_B */
    double noise_common;     /* c·√(r_A² + r_B²) */
    double floor_a, floor_b; /* φ·r·level_ref per side: absolute */
    double noise_model;      /* κ·√((s_A² + s_B²)/N): the model's independent noise of m */
    double noise_empirical;  /* √ν × the ratio estimator's standard error of m from the samples */
    double noise_mean;       /* σ_m */
    double z;                /* m / σ_m */
    uint64_t significant;    /* samples over k_sample */
    uint64_t extreme;        /* samples over TL_NOISE_K_EXTREME (σ at the darker side) */
    int count_test;          /* the count decides (begin sets 1; 0: no local noise to test samples against) */
    double sample_rms;       /* √(mean u²) over the finite u: 1 when σ is the samples' noise */
    double sum_u2;
    double significant_share, share_limit; /* share_limit: the largest share within noise */
    double chroma_shift[3];  /* g_C; 0 for a channel not tested */
    double chroma_noise;     /* σ_g of the channel with the largest |g_C|/σ_g */
    double chroma_z;         /* max |g_C| / σ_g over the channels tested */
    int shift_significant, share_significant, chroma_significant;
    int within_noise;
} tl_noise_stats;

/* Starts an item of class cls (tl_noise_class); s_a, s_b its relative per-sample noise. */
void tl_noise_begin(tl_noise_stats *s, const tl_noise_model *m, int cls, double s_a, double s_b);
/* One sample: n normals × 3 channels of irradiance, A and B; t_a, t_b its local relative noise
 * (before the class's sample_spread), negative where it is not measured (the sample then counts
 * in the mean and chromaticity tests only). */
void tl_noise_add(tl_noise_stats *s, const tl_noise_model *m, const float *a, const float *b, int n, double t_a,
                  double t_b);
/* The same with t_a, t_b relative to the levels ref_a, ref_b (≥ 0) instead of the sample's own
 * (negative: its own): a light set's texel entry, whose noise is that of the full runs it came
 * from, so relative to the entry plus the base texel under it (compare_set_space). */
void tl_noise_add_ref(tl_noise_stats *s, const tl_noise_model *m, const float *a, const float *b, int n, double t_a,
                      double t_b, double ref_a, double ref_b);
void tl_noise_end(tl_noise_stats *s, const tl_noise_model *m);
/* The sample test alone (1: significant), for heatmaps. */
int tl_noise_sample_significant(const tl_noise_model *m, int cls, double t_a, double t_b, const float *a,
                                const float *b, int n);
/* The smallest count c with P(Binomial(n, p) ≥ c) ≤ q (n + 1 when none). */
uint64_t tl_binomial_critical(uint64_t n, double p, double q);
/* The count test's critical value for n samples significant in clumps of D (the class's
 * count_dispersion): D · tl_binomial_critical(⌈n/D⌉, p, q) (a radiosity cache's cell, a region's
 * bounce tail change many neighbouring texels together). */
uint64_t tl_count_critical(uint64_t n, double p, double dispersion, double q);

/* The robust standard deviation of n residuals (the median absolute deviation × 1.4826 / √1.25:
 * a residual against the mean of 4 neighbours has 1.25 × a texel's variance), or -1 below 16.
 * Reorders r. */
double tl_noise_robust_sigma(double *r, size_t n);
/* Relative noise of a lightmap from its own texels: the median absolute deviation of the
 * residual of each texel's value against the mean of its 4 neighbours d texels away, relative to
 * the texel's level ref, inside the rectangle less its 2-texel border (dilated padding), scaled to
 * a standard deviation (1.4826 / √1.25), the largest for d = 1, 2, … TL_NOISE_HIGHPASS_REACH.
 * values and ref are w × h, row-major. Returns < 0 when fewer than 16 texels are usable (the
 * caller falls back on REPT). */
double tl_noise_highpass(const float *values, const float *ref, uint32_t w, uint32_t h);
/* The same per 4×4 tile from the tile and a (2 + reach)-texel surround (values relative to themselves),
 * into out (w × h); fallback where too few are usable. A texel whose tile's residuals come from
 * texels of other levels (beyond TL_NOISE_LEVEL_BAND) gets the σ of those at its own level where
 * 16 tell it (at least the tile's), else -1 (not measured) when more of the others lie above its
 * band than below it, else the tile's σ. A tile with too few residuals reads the levels of the
 * whole rectangle's when it has at most TL_NOISE_SMALL_RECT texels. */
void tl_noise_highpass_tiles(const float *values, uint32_t w, uint32_t h, double fallback, float *out);

#endif
