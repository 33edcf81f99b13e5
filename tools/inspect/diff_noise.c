/* The noise rule of diff_noise.h. */
#include "tools/inspect/diff_noise.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"

double tl_normal_quantile(double p)
{
    /* bisection on the upper tail 0.5·erfc(x/√2) = 1 − p: 200 halvings reach double precision */
    double lo = -40, hi = 40;
    for (int i = 0; i < 200; i++) {
        const double mid = 0.5 * (lo + hi);
        if (0.5 * erfc(mid / sqrt(2.0)) > 1 - p) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* The classes' factors, from the reseed study (bench/diff_reseed.py; docs/tools.md "lbk diff:
 * calibration and power"), fast preset: 6 scenes × 3 pairs and 4 scenes × 6 pairs. The RMS of
 * the samples' normalised deviation u was 0.70–0.78 (texels), 0.42–0.88 (GLG at ρ 3) and 1.0–2.4
 * (LLG at ρ 6: lights_punctual_lamp's probes), the share beyond k_sample 0.5–0.8 %, 0.2–0.8 %
 * and 0.8–4.6 % (p₀ 2 %, 5 %, 8 %), samples beyond 30σ at their darker side 7e-5, 0 and 0.8 %
 * (p_x 1e-4, 1e-5, 2 %). The largest |z|/k_mean was 0.26 (texels), 0.86 (GLG at κ 1, ν 4: κ 1.5
 * and ν 9 for probes) and 0.62 (LLG), chroma_z/k_chroma at most 0.34. LLG probes are fitted
 * together from the object's vertices and GLG probes interpolate each other, so their standard
 * error counts N/9 independent samples (ν 9). OCTP and the light-set classes had no item in the
 * shared scenes: they take the GLG's (probes) and the texels' (texel entries) factors, measured on
 * the generated light-set and door levels (bench/door_scene_write.c): extreme samples, fireflies
 * of light through a doorway, came at 3–5e-4 of the texels there (p_x 5e-4; 1e-4 before) and
 * 6–9e-4 of a light set's texel entries, a run of one lamp alone (1e-3); a door state's entries,
 * differences of runs clamped at 0, had 3 % of samples beyond k_sample and u RMS 2.2 (p₀ 8 %,
 * p_x 2 %).
 * χ_c 0.15 (texels) and 0.6 (probes), with each channel's share (chroma_end), from 20 reseed
 * pairs per scene at both presets: the largest chroma_z/k_chroma became 0.29 (texels, fast), 0.63
 * (texels, high) and 0.67 (cornell_box_bjs's GLG at the high preset; at χ_c 0.3 it was beyond
 * noise in 2 of 20). Before the share, χ_c was 0.3 for both, and the high preset's GLG was beyond
 * noise in 7 of 20 pairs, its texels in 2 of 180. Probes' common shift is the larger part of
 * theirs, as for the luminance (κ 1.5).
 * D: significant texels come in clumps (tl_count_critical): over 11 reseed pairs of
 * room_sets_doors_b at the fast preset the count's variance was 1.2–6.4× a binomial's on the
 * light-set and door texel items and 39× on its walls (one pair with a clump of ~400 texels
 * where their binomial critical value was 723): D 4 for texel classes. Probes' counts were
 * within 1–2× (GLG; the rest had no significant probe): D 1, so a lamp moved in one room of a
 * two-room level is still seen in the GLG by the count (tests/tools/test_diff_noise.c).
 * φ 0.1: a texel far darker than the bake's median level (a room lit only through a leak) has an
 * absolute noise floor of 0.1·r·level_ref; without it leak_rooms' texels were beyond 3.29σ in
 * 27 % of the samples and its dark LLG prop shifted by −88 %. */
static const tl_noise_class_params classes[TL_NOISE_CLASS_COUNT_] = {
    /* name          kind  κ    ρ    p₀    χ    χ_c  ν    φ    p_x   D */
    {"texels",       0,   1.0, 1.0, 0.02, 2.0, 0.15, 4.0, 0.1, 5e-4, 4},
    {"glg",          1,   1.5, 3.0, 0.05, 2.0, 0.60, 9.0, 0.1, 1e-5, 1},
    {"llg",          1,   1.5, 8.0, 0.08, 2.0, 0.60, 9.0, 0.1, 0.02, 1},
    {"octp",         1,   1.5, 3.0, 0.05, 2.0, 0.60, 9.0, 0.1, 1e-5, 1},
    {"set_texels",   0,   1.0, 1.0, 0.02, 2.0, 0.15, 4.0, 0.1, 1e-3, 4},
    {"set_probes",   1,   1.5, 3.0, 0.05, 2.0, 0.60, 9.0, 0.1, 1e-5, 1},
    {"door_texels",  0,   1.0, 1.0, 0.08, 2.0, 0.15, 4.0, 0.1, 0.02, 4},
    {"door_probes",  1,   1.5, 3.0, 0.05, 2.0, 0.60, 9.0, 0.1, 1e-5, 1},
};

const tl_noise_class_params *tl_noise_class_get(int cls)
{
    return &classes[cls >= 0 && cls < TL_NOISE_CLASS_COUNT_ ? cls : 0];
}

void tl_noise_model_init(tl_noise_model *m, double false_alarm, const double rept_a[2], const double rept_b[2])
{
    memset(m, 0, sizeof *m);
    m->false_alarm = false_alarm;
    m->k_mean = tl_normal_quantile(1 - false_alarm / 6);
    m->k_chroma = tl_normal_quantile(1 - false_alarm / 18);
    m->k_sample = TL_NOISE_K_SAMPLE;
    m->common = TL_NOISE_COMMON;
    m->texel_spread = 1;
    for (int k = 0; k < 2; k++) {
        m->rept[0][k] = rept_a[k];
        m->rept[1][k] = rept_b[k];
    }
}

void tl_noise_begin(tl_noise_stats *s, const tl_noise_model *m, int cls, double s_a, double s_b)
{
    memset(s, 0, sizeof *s);
    s->evaluated = 1;
    s->count_test = 1;
    s->cls = cls >= 0 && cls < TL_NOISE_CLASS_COUNT_ ? cls : 0;
    s->noise_a = s_a;
    s->noise_b = s_b;
    const tl_noise_class_params *c = tl_noise_class_get(s->cls);
    s->noise_common = m->common * hypot(m->rept[0][c->kind], m->rept[1][c->kind]);
    s->floor_a = c->floor_scale * m->rept[0][c->kind] * m->level_ref[0][c->kind];
    s->floor_b = c->floor_scale * m->rept[1][c->kind] * m->level_ref[1][c->kind];
}

static double lum(const float *c) { return LBK_LUM_R * c[0] + LBK_LUM_G * c[1] + LBK_LUM_B * c[2]; }

double tl_noise_texel_floor(const tl_noise_model *m, int side) { return m->denoised[side] ? m->rept[side][0] : 0; }

double tl_noise_level(const float *v, int kind, int n)
{
    if (kind == 0) return lum(v); /* texels: +Z, the first normal */
    double l = 0;
    for (int i = 0; i < n; i++) l += lum(v + 3 * i) / n;
    return l;
}

/* A sample's change over its noise, |b₀ − a₀| / σ (+∞ for NaN or a change without noise), the
 * relative noises t_a, t_b taken of the levels ref_a, ref_b (negative: the sample's own); and
 * into *extreme the same with the relative noise of the darker side for both (a sample 100×
 * brighter stays 100× beyond it, where σ relative to the brighter side caps u near 1/σ_B). */
static double sample_deviation(const tl_noise_model *m, int cls, double t_a, double t_b, const float *a,
                               const float *b, int n, double ref_a, double ref_b, double *extreme)
{
    const tl_noise_class_params *c = tl_noise_class_get(cls);
    const double ca = m->common * m->rept[0][c->kind], cb = m->common * m->rept[1][c->kind];
    const double spread = c->sample_spread * (m->texel_spread > 0 ? m->texel_spread : 1);
    const double ta = spread * t_a, tb = spread * t_b;
    const double la = tl_noise_level(a, c->kind, n), lb = tl_noise_level(b, c->kind, n), d = lb - la;
    const double fa = c->floor_scale * m->rept[0][c->kind] * m->level_ref[0][c->kind];
    const double fb = c->floor_scale * m->rept[1][c->kind] * m->level_ref[1][c->kind];
    const double ra = ref_a >= 0 ? ref_a : la, rb = ref_b >= 0 ? ref_b : lb;
    const double sa2 = ta * ta + ca * ca, sb2 = tb * tb + cb * cb, lo = fmin(ra, rb);
    const double sigma = sqrt(sa2 * ra * ra + sb2 * rb * rb + fa * fa + fb * fb);
    const double sigma_lo = sqrt((sa2 + sb2) * lo * lo + fa * fa + fb * fb);
    if (isnan(d)) {
        if (extreme) *extreme = INFINITY;
        return INFINITY;
    }
    if (extreme) *extreme = sigma_lo > 0 ? fabs(d) / sigma_lo : (d != 0 ? INFINITY : 0);
    return sigma > 0 ? fabs(d) / sigma : (d != 0 ? INFINITY : 0);
}

int tl_noise_sample_significant(const tl_noise_model *m, int cls, double t_a, double t_b, const float *a,
                                const float *b, int n)
{
    if (t_a < 0 || t_b < 0) return 0;
    return !(sample_deviation(m, cls, t_a, t_b, a, b, n, -1, -1, NULL) <= m->k_sample);
}

void tl_noise_add(tl_noise_stats *s, const tl_noise_model *m, const float *a, const float *b, int n, double t_a,
                  double t_b)
{
    tl_noise_add_ref(s, m, a, b, n, t_a, t_b, -1, -1);
}

void tl_noise_add_ref(tl_noise_stats *s, const tl_noise_model *m, const float *a, const float *b, int n, double t_a,
                      double t_b, double ref_a, double ref_b)
{
    double la_sum = 0, lb_sum = 0, ca[3] = {0}, cb[3] = {0};
    for (int i = 0; i < n; i++) {
        const double la = lum(a + 3 * i), lb = lum(b + 3 * i), d = lb - la;
        la_sum += la;
        lb_sum += lb;
        s->sum_d2 += d * d / n;
        for (int k = 0; k < 3; k++) ca[k] += a[3 * i + k], cb[k] += b[3 * i + k];
    }
    if (la_sum == 0 && lb_sum == 0) return; /* unlit on both sides: no evidence either way */
    s->count++;
    const double la = la_sum / n, d = (lb_sum - la_sum) / n;
    s->sum_a += la;
    s->sum_d += d;
    s->sum_dd += d * d, s->sum_da += d * la, s->sum_aa += la * la;
    for (int k = 0; k < 3; k++) {
        const double dc = (cb[k] - ca[k]) / n;
        s->sum_ca[k] += ca[k] / n, s->sum_cb[k] += cb[k] / n;
        s->sum_dcdc[k] += dc * dc, s->sum_dcdl[k] += dc * d;
    }
    if (t_a < 0 || t_b < 0) return; /* its noise not measured at its level: in the mean, not the count */
    s->tested++;
    double ux;
    const double u = sample_deviation(m, s->cls, t_a, t_b, a, b, n, ref_a, ref_b, &ux);
    s->significant += !(u <= m->k_sample);
    s->extreme += !(ux <= TL_NOISE_K_EXTREME);
    if (isfinite(u)) s->sum_u2 += u * u;
}

uint64_t tl_binomial_critical(uint64_t n, double p, double q)
{
    if (!(p > 0)) return 1;
    if (p >= 1) return n + 1;
    /* the upper tail summed downward from where the pmf is below 1e-300 of the whole (40 standard
     * deviations above the mean); each term from lgamma keeps every term in range */
    const double lp = log(p), lq = log1p(-p), dn = (double)n;
    const double top = dn * p + 40 * sqrt(dn * p * (1 - p)) + 50;
    double tail = 0;
    for (uint64_t c = top < dn ? (uint64_t)top : n;; c--) {
        const double dc = (double)c;
        tail += exp(lgamma(dn + 1) - lgamma(dc + 1) - lgamma(dn - dc + 1) + dc * lp + (dn - dc) * lq);
        if (tail > q) return c + 1;
        if (c == 0) return 0;
    }
}

uint64_t tl_count_critical(uint64_t n, double p, double dispersion, double q)
{
    if (!(dispersion > 1)) return tl_binomial_critical(n, p, q);
    const uint64_t clumps = (uint64_t)ceil((double)n / dispersion);
    return (uint64_t)ceil(dispersion * (double)tl_binomial_critical(clumps, p, q));
}

/* The chromaticity test of tl_noise_end: g_C with its noise, the model's or the samples' own,
 * and the common part, (χ_c·c)·√(1/λ_C − 1)·r: if each channel's whole-bake factor varies
 * independently, with a relative spread that grows as 1/√λ_C (its light comes from a λ_C share
 * of the paths), g_C = δ_C − Σλ_K·δ_K has variance ∝ 1/λ_C − 1. Measured on the reseed pairs
 * (bench/diff_reseed.py): the spread of g_C over this was the same for R, G and B, 0.15 × c·√(r_A² + r_B²)
 * on cornell_box_bjs's GLG at the fast preset, where a χ_c without the factor read blue (7 % of
 * the luminance under red and green walls) at 2.8× the luminance's common shift at the high
 * preset: 7 of 20 reseed pairs beyond noise. */
static void chroma_end(tl_noise_stats *s, const tl_noise_model *m, const tl_noise_class_params *c, double n)
{
    const double la = LBK_LUM_R * s->sum_ca[0] + LBK_LUM_G * s->sum_ca[1] + LBK_LUM_B * s->sum_ca[2];
    const double lb = LBK_LUM_R * s->sum_cb[0] + LBK_LUM_G * s->sum_cb[1] + LBK_LUM_B * s->sum_cb[2];
    const double model = c->chroma_scale * c->chroma_scale * (s->noise_a * s->noise_a + s->noise_b * s->noise_b) / n;
    const double weight[3] = {LBK_LUM_R, LBK_LUM_G, LBK_LUM_B};
    s->chroma_z = 0;
    s->chroma_noise = sqrt(model);
    for (int k = 0; k < 3; k++) {
        s->chroma_shift[k] = 0;
        if (!(la > 0) || !(lb > 0)) continue;
        const double qa = s->sum_ca[k] / la, qb = s->sum_cb[k] / lb;
        if (!(qa >= TL_NOISE_CHROMA_MIN_SHARE) || !(qb >= TL_NOISE_CHROMA_MIN_SHARE)) continue;
        s->chroma_shift[k] = qb / qa - 1;
        /* x = dC/ΣC_a − dL/ΣL_a per sample: Σx ≈ g_C, its standard error √(Σx² − (Σx)²/N) */
        const double sc = s->sum_ca[k], sx = (s->sum_cb[k] - sc) / sc - (lb - la) / la;
        const double sxx = s->sum_dcdc[k] / (sc * sc) - 2 * s->sum_dcdl[k] / (sc * la) + s->sum_dd / (la * la);
        const double emp = c->empirical_scale * fmax(sxx - sx * sx / n, 0);
        const double share = weight[k] * sc / la; /* λ_C ≥ w_C · TL_NOISE_CHROMA_MIN_SHARE > 0 */
        const double common = c->chroma_common * s->noise_common * sqrt(fmax(1 / share - 1, 0));
        const double sigma = sqrt(fmax(model, emp) + common * common);
        const double z = sigma > 0 ? fabs(s->chroma_shift[k]) / sigma : (s->chroma_shift[k] != 0 ? INFINITY : 0);
        if (k == 0 || z > s->chroma_z) s->chroma_z = z, s->chroma_noise = sigma;
    }
    s->chroma_significant = !(s->chroma_z <= m->k_chroma);
}

void tl_noise_end(tl_noise_stats *s, const tl_noise_model *m)
{
    if (s->count == 0) {
        s->within_noise = 1;
        return;
    }
    const tl_noise_class_params *c = tl_noise_class_get(s->cls);
    const double n = (double)s->count, k2 = c->mean_scale * c->mean_scale;
    s->mean_shift = s->sum_a > 0 ? s->sum_d / s->sum_a : (s->sum_d != 0 ? INFINITY : 0);
    s->rmse = sqrt(s->sum_d2 / n);
    /* relative per-sample noise, and the absolute floor relative to the item's mean level */
    const double level = s->sum_a / n, fl = level > 0 ? (s->floor_a * s->floor_a + s->floor_b * s->floor_b) / (level * level) : 0;
    s->noise_model = sqrt((k2 * (s->noise_a * s->noise_a + s->noise_b * s->noise_b) + c->empirical_scale * fl) / n);
    /* the ratio estimator's standard error: √Σ(d − m·a)² / Σa */
    const double mm = isfinite(s->mean_shift) ? s->mean_shift : 0;
    const double e2 = fmax(s->sum_dd - 2 * mm * s->sum_da + mm * mm * s->sum_aa, 0);
    s->noise_empirical = s->sum_a > 0 ? sqrt(c->empirical_scale * e2) / s->sum_a : 0;
    s->noise_mean = sqrt(fmax(s->noise_model, s->noise_empirical) * fmax(s->noise_model, s->noise_empirical) +
                         s->noise_common * s->noise_common);
    s->z = s->noise_mean > 0 ? s->mean_shift / s->noise_mean : (s->mean_shift != 0 ? INFINITY : 0);
    const double nt = s->tested > 0 ? (double)s->tested : 1;
    s->sample_rms = sqrt(s->sum_u2 / nt);
    s->significant_share = (double)s->significant / nt;
    const uint64_t critical = tl_count_critical(s->tested, c->sample_rate, c->count_dispersion, m->false_alarm / 6);
    const uint64_t critical_extreme = tl_binomial_critical(s->tested, c->extreme_rate, m->false_alarm / 6);
    s->share_limit = critical > 0 ? (double)(critical - 1) / nt : 0;
    s->shift_significant = !(fabs(s->z) <= m->k_mean);
    s->share_significant = s->count_test && (s->significant >= critical || s->extreme >= critical_extreme);
    chroma_end(s, m, c, n);
    s->within_noise = !s->shift_significant && !s->share_significant && !s->chroma_significant;
}

static int cmp_double(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* The k-th smallest of v[0, n) into v[k], with every smaller one before it (quickselect: the
 * median of every tile's residuals, twice per robust σ, was most of lbk diff's time sorted). */
static double select_kth(double *v, size_t n, size_t k)
{
    if (k >= n) return NAN;
    size_t lo = 0, hi = n - 1;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        double a = v[lo], b = v[mid], c = v[hi];
        const double pivot = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b));
        size_t i = lo, j = hi;
        while (i <= j) {
            while (v[i] < pivot) i++;
            while (v[j] > pivot) j--;
            if (i <= j) {
                const double t = v[i];
                v[i] = v[j], v[j] = t;
                i++;
                if (j == 0) break;
                j--;
            }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else break;
    }
    return v[k];
}

static double median(double *v, size_t n)
{
    const double upper = select_kth(v, n, n / 2);
    if (n % 2) return upper;
    double lower = v[0];
    for (size_t i = 1; i < n / 2; i++) lower = fmax(lower, v[i]);
    return 0.5 * (lower + upper);
}

/* Residuals (value − mean of its 4 neighbours) / level of the texels in [x0, x1) × [y0, y1), kept
 * two texels from the rectangle's edge (the border ring is dilated padding); into lv (unless NULL)
 * the level of each residual's texel. */
static size_t residuals(const float *values, const float *ref, uint32_t w, uint32_t h, uint32_t x0, uint32_t y0,
                        uint32_t x1, uint32_t y1, uint32_t d, double *r, double *lv)
{
    size_t n = 0;
    const uint32_t e = d > 2 ? d : 2;
    if (x0 < e) x0 = e;
    if (y0 < e) y0 = e;
    if (x1 + e > w) x1 = w > e ? w - e : 0;
    if (y1 + e > h) y1 = h > e ? h - e : 0;
    const size_t dy = (size_t)d * w;
    for (uint32_t y = y0; y < y1; y++)
        for (uint32_t x = x0; x < x1; x++) {
            const size_t i = (size_t)y * w + x;
            const double c = values[i], lev = ref[i];
            const double nb = 0.25 * ((double)values[i - d] + values[i + d] + values[i - dy] + values[i + dy]);
            const double nref = (double)ref[i - d] * ref[i + d] * ref[i - dy] * ref[i + dy];
            if (!(lev > 0) || !(nref > 0)) continue; /* unlit or outside the chart */
            if (lv) lv[n] = lev;
            r[n++] = (c - nb) / lev;
        }
    return n;
}

double tl_noise_robust_sigma(double *r, size_t n)
{
    if (n < 16) return -1;
    const double med = median(r, n);
    for (size_t i = 0; i < n; i++) r[i] = fabs(r[i] - med);
    return 1.4826 * median(r, n) / sqrt(1.25);
}

double tl_noise_highpass(const float *values, const float *ref, uint32_t w, uint32_t h)
{
    if (w < 5 || h < 5) return -1;
    double *r = malloc(sizeof *r * (size_t)w * h);
    if (!r) return -1;
    double out = -1;
    for (uint32_t d = 1; d <= TL_NOISE_HIGHPASS_REACH; d *= 2)
        out = fmax(out, tl_noise_robust_sigma(r, residuals(values, ref, w, h, 0, 0, w, h, d, r, NULL)));
    free(r);
    return out;
}

/* The residuals of one region at the distances d = 1, 2, … TL_NOISE_HIGHPASS_REACH (as
 * tl_noise_highpass), each distance's after the last's: n[k] of them for the k-th distance. */
typedef struct hp_region {
    double *r, *lv;
    size_t n[4], total;
    double lv_min, lv_max; /* the residuals' levels */
} hp_region;

static void region_residuals(const float *values, uint32_t w, uint32_t h, uint32_t x0, uint32_t y0, uint32_t x1,
                             uint32_t y1, hp_region *g)
{
    g->total = 0;
    int k = 0;
    for (uint32_t d = 1; d <= TL_NOISE_HIGHPASS_REACH; d *= 2, k++) {
        g->n[k] = w >= 5 && h >= 5 ? residuals(values, values, w, h, x0, y0, x1, y1, d, g->r + g->total, g->lv + g->total) : 0;
        g->total += g->n[k];
    }
    g->lv_min = INFINITY, g->lv_max = 0;
    for (size_t i = 0; i < g->total; i++) g->lv_min = fmin(g->lv_min, g->lv[i]), g->lv_max = fmax(g->lv_max, g->lv[i]);
}

/* The region's robust σ over the residuals whose texel level is within TL_NOISE_LEVEL_BAND of L
 * (every residual for L ≤ 0), the largest over the distances; -1 where none has 16. scratch
 * holds g->total (texel_local: twice that). */
static double band_sigma(const hp_region *g, double level, double *scratch)
{
    double out = -1;
    size_t first = 0;
    for (int k = 0; first < g->total; first += g->n[k++]) {
        size_t m = 0;
        for (size_t i = first; i < first + g->n[k]; i++)
            if (!(level > 0) || (g->lv[i] >= level / TL_NOISE_LEVEL_BAND && g->lv[i] <= level * TL_NOISE_LEVEL_BAND))
                scratch[m++] = g->r[i];
        out = fmax(out, tl_noise_robust_sigma(scratch, m));
    }
    return out;
}

/* A texel's band of residual levels, [L/band, L·band], as the range [lo, hi) of the region's
 * levels sorted: texels of one region with the same range share their band's σ (memo). */
typedef struct band_memo {
    double *sorted;         /* the region's levels, ascending; NULL until a texel needs them */
    size_t lo[16], hi[16];
    double value[16];
    int count;
} band_memo;

static size_t first_at_least(const double *v, size_t n, double x)
{
    size_t a = 0, b = n;
    while (a < b) {
        const size_t mid = a + (b - a) / 2;
        if (v[mid] < x) a = mid + 1;
        else b = mid;
    }
    return a;
}

/* A texel's local noise where its tile's residuals come from texels of other levels (a shadow's
 * edge, an object lit directly above and only by bounces below): the residuals at its own level
 * where 16 of them tell it (never under the tile's σ, which its neighbours' noise may carry);
 * else, where more of the other residuals lie above its band than below it (a dark texel among
 * bright ones), none (-1: its noise is not measured, it is not count-tested), and the tile's σ
 * where more lie below (relative noise falls with the level). */
static double texel_local(const hp_region *g, double sg, double level, double *scratch, band_memo *memo)
{
    /* the usual case, every residual at its level: the tile's σ, without sorting again */
    if (!(level > 0) || (g->lv_min >= level / TL_NOISE_LEVEL_BAND && g->lv_max <= level * TL_NOISE_LEVEL_BAND))
        return sg;
    if (!memo->sorted) {
        memo->sorted = scratch + g->total;
        memcpy(memo->sorted, g->lv, g->total * sizeof *g->lv);
        qsort(memo->sorted, g->total, sizeof *memo->sorted, cmp_double);
    }
    const size_t lo = first_at_least(memo->sorted, g->total, level / TL_NOISE_LEVEL_BAND);
    const size_t hi = first_at_least(memo->sorted, g->total, nextafter(level * TL_NOISE_LEVEL_BAND, INFINITY));
    for (int j = 0; j < memo->count; j++)
        if (memo->lo[j] == lo && memo->hi[j] == hi) return memo->value[j];
    /* some residual lies outside its band (the test above) */
    const double own = band_sigma(g, level, scratch);
    const double value = own >= 0 ? fmax(sg, own) : g->total - hi > lo ? -1 : sg; /* more above than below */
    if (memo->count < 16) {
        memo->lo[memo->count] = lo, memo->hi[memo->count] = hi;
        memo->value[memo->count++] = value;
    }
    return value;
}

void tl_noise_highpass_tiles(const float *values, uint32_t w, uint32_t h, double fallback, float *out)
{
    enum { TILE = 4, SURROUND = 2 + TL_NOISE_HIGHPASS_REACH, SIDE = TILE + 2 * SURROUND, REGION = 2 * SIDE * SIDE };
    double r[REGION], lv[REGION], scratch[2 * REGION]; /* a band's residuals, then the sorted levels */
    /* a tile with too few residuals of its own (a small or narrow rectangle) reads the levels of
     * the whole rectangle's, when it is small enough to hold them */
    const size_t whole_cap = (size_t)w * h <= TL_NOISE_SMALL_RECT ? 2 * (size_t)w * h + 1 : 0;
    double *whole = NULL;
    hp_region rect = {0};
    band_memo rect_memo = {0}; /* every tile that reads the rectangle's levels shares sg = fallback */
    for (uint32_t ty = 0; ty < h; ty += TILE)
        for (uint32_t tx = 0; tx < w; tx += TILE) {
            const uint32_t x0 = tx >= SURROUND ? tx - SURROUND : 0, y0 = ty >= SURROUND ? ty - SURROUND : 0;
            const uint32_t x1 = tx + TILE + SURROUND < w ? tx + TILE + SURROUND : w;
            const uint32_t y1 = ty + TILE + SURROUND < h ? ty + TILE + SURROUND : h;
            hp_region tile = {.r = r, .lv = lv}, *g = &tile;
            band_memo tile_memo = {0}, *memo = &tile_memo;
            region_residuals(values, w, h, x0, y0, x1, y1, &tile);
            double sg = band_sigma(&tile, 0, scratch), *sc = scratch;
            if (sg < 0) {
                sg = fallback;
                if (whole_cap && !whole && (whole = malloc(sizeof *whole * 4 * whole_cap))) {
                    rect = (hp_region){.r = whole, .lv = whole + whole_cap};
                    region_residuals(values, w, h, 0, 0, w, h, &rect);
                }
                g = whole ? &rect : NULL, sc = whole ? whole + 2 * whole_cap : NULL, memo = &rect_memo;
            }
            for (uint32_t y = ty; y < ty + TILE && y < h; y++)
                for (uint32_t x = tx; x < tx + TILE && x < w; x++) {
                    const size_t i = (size_t)y * w + x;
                    out[i] = (float)(g && g->total ? texel_local(g, sg, values[i], sc, memo) : sg);
                }
        }
    free(whole);
}
