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

void tl_noise_model_init(tl_noise_model *m, double false_alarm, const double rept_a[2], const double rept_b[2])
{
    memset(m, 0, sizeof *m);
    m->false_alarm = false_alarm;
    m->k_mean = m->k_sample = tl_normal_quantile(1 - false_alarm / 2);
    m->common = TL_NOISE_COMMON;
    for (int k = 0; k < 2; k++) {
        m->rept[0][k] = rept_a[k];
        m->rept[1][k] = rept_b[k];
    }
}

void tl_noise_begin(tl_noise_stats *s, const tl_noise_model *m, int kind, double s_a, double s_b)
{
    memset(s, 0, sizeof *s);
    s->evaluated = 1;
    s->noise_a = s_a;
    s->noise_b = s_b;
    s->noise_common = m->common * hypot(m->rept[0][kind], m->rept[1][kind]);
}

static double lum(const float *c) { return LBK_LUM_R * c[0] + LBK_LUM_G * c[1] + LBK_LUM_B * c[2]; }

static double level(const float *v, int kind, int n)
{
    if (kind == 0) return lum(v); /* texels: +Z, the first normal */
    double l = 0;
    for (int i = 0; i < n; i++) l += lum(v + 3 * i) / n;
    return l;
}

int tl_noise_sample_significant(const tl_noise_model *m, int kind, double t_a, double t_b, const float *a,
                                const float *b, int n)
{
    const double ca = m->common * m->rept[0][kind], cb = m->common * m->rept[1][kind];
    const double la = level(a, kind, n), lb = level(b, kind, n), d = lb - la;
    const double sigma = sqrt((t_a * t_a + ca * ca) * la * la + (t_b * t_b + cb * cb) * lb * lb);
    const double t = sigma > 0 ? fabs(d) / sigma : (d != 0 || isnan(d) ? INFINITY : 0);
    return !(t <= m->k_sample); /* NaN counts as significant */
}

void tl_noise_add(tl_noise_stats *s, const tl_noise_model *m, int kind, const float *a, const float *b, int n,
                  double t_a, double t_b)
{
    double la_sum = 0, lb_sum = 0;
    for (int i = 0; i < n; i++) {
        const double la = lum(a + 3 * i), lb = lum(b + 3 * i), d = lb - la;
        la_sum += la;
        lb_sum += lb;
        s->sum_d2 += d * d / n;
    }
    if (la_sum == 0 && lb_sum == 0) return; /* unlit on both sides: no evidence either way */
    s->count++;
    s->sum_a += la_sum / n;
    s->sum_d += (lb_sum - la_sum) / n;
    s->significant += (uint64_t)tl_noise_sample_significant(m, kind, t_a, t_b, a, b, n);
}

void tl_noise_end(tl_noise_stats *s, const tl_noise_model *m)
{
    if (s->count == 0) {
        s->within_noise = 1;
        return;
    }
    const double n = (double)s->count, alpha = m->false_alarm;
    s->mean_shift = s->sum_a > 0 ? s->sum_d / s->sum_a : (s->sum_d != 0 ? INFINITY : 0);
    s->rmse = sqrt(s->sum_d2 / n);
    s->noise_mean = sqrt((s->noise_a * s->noise_a + s->noise_b * s->noise_b) / n + s->noise_common * s->noise_common);
    s->z = s->noise_mean > 0 ? s->mean_shift / s->noise_mean : (s->mean_shift != 0 ? INFINITY : 0);
    s->significant_share = (double)s->significant / n;
    s->share_limit = fmax(TL_NOISE_SHARE_FACTOR * alpha, alpha + 4 * sqrt(alpha / n));
    s->shift_significant = !(fabs(s->z) <= m->k_mean);
    s->share_significant = s->significant_share > s->share_limit;
    s->within_noise = !s->shift_significant && !s->share_significant;
}

static int cmp_double(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

static double median(double *v, size_t n)
{
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Residuals (value − mean of its 4 neighbours) / level of the texels in [x0, x1) × [y0, y1), kept
 * two texels from the rectangle's edge (the border ring is dilated padding). */
static size_t residuals(const float *values, const float *ref, uint32_t w, uint32_t h, uint32_t x0, uint32_t y0,
                        uint32_t x1, uint32_t y1, double *r)
{
    size_t n = 0;
    if (x0 < 2) x0 = 2;
    if (y0 < 2) y0 = 2;
    if (x1 + 2 > w) x1 = w > 2 ? w - 2 : 0;
    if (y1 + 2 > h) y1 = h > 2 ? h - 2 : 0;
    for (uint32_t y = y0; y < y1; y++)
        for (uint32_t x = x0; x < x1; x++) {
            const size_t i = (size_t)y * w + x;
            const double c = values[i], lev = ref[i];
            const double nb = 0.25 * ((double)values[i - 1] + values[i + 1] + values[i - w] + values[i + w]);
            const double nref = (double)ref[i - 1] * ref[i + 1] * ref[i - w] * ref[i + w];
            if (!(lev > 0) || !(nref > 0)) continue; /* unlit or outside the chart */
            r[n++] = (c - nb) / lev;
        }
    return n;
}

/* The robust standard deviation of n residuals (scaled MAD), or -1 below 16. */
static double robust_sigma(double *r, size_t n)
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
    const double out = robust_sigma(r, residuals(values, ref, w, h, 0, 0, w, h, r));
    free(r);
    return out;
}

void tl_noise_highpass_tiles(const float *values, uint32_t w, uint32_t h, double fallback, float *out)
{
    enum { TILE = 4, SURROUND = 2 };
    double r[(TILE + 2 * SURROUND) * (TILE + 2 * SURROUND)];
    for (uint32_t ty = 0; ty < h; ty += TILE)
        for (uint32_t tx = 0; tx < w; tx += TILE) {
            const uint32_t x0 = tx >= SURROUND ? tx - SURROUND : 0, y0 = ty >= SURROUND ? ty - SURROUND : 0;
            const uint32_t x1 = tx + TILE + SURROUND < w ? tx + TILE + SURROUND : w;
            const uint32_t y1 = ty + TILE + SURROUND < h ? ty + TILE + SURROUND : h;
            double sg = w >= 5 && h >= 5 ? robust_sigma(r, residuals(values, values, w, h, x0, y0, x1, y1, r)) : -1;
            if (sg < 0) sg = fallback;
            for (uint32_t y = ty; y < ty + TILE && y < h; y++)
                for (uint32_t x = tx; x < tx + TILE && x < w; x++) out[(size_t)y * w + x] = (float)sg;
        }
}
