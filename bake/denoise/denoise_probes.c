/* Denoising of GLG probes along the edges of their tetrahedra (bake/denoise/DENOISE.md):
 * a probe is averaged with the neighbours it shares a tetrahedron edge with and can see (the
 * segment between the two is unoccluded), each weighted by how far its value is from the
 * probe's in noise standard deviations. A probe behind a wall therefore never takes light from
 * the lit side, even where the tetrahedra cross the wall. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/denoise/denoise_impl.h"
#include "scene/parallel.h"

#define SH_N 27
#define NEIGHBOUR_WEIGHT 0.5f /* a neighbour's weight at equal value; the probe's own is 1 */

float dn_probe_lum(const lbk_sh9_rgb *sh)
{
    const float k = 3.14159265358979f * 0.282094791773878f; /* fluence/4 = π·Y00·L00 */
    return k * (DN_LR * sh->c[0][0] + DN_LG * sh->c[1][0] + DN_LB * sh->c[2][0]);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Sorted unique probe pairs (lo << 32 | hi) of every tetrahedron edge. */
static lbk_result tet_edges(const bk_glg *glg, uint64_t **edges, size_t *count)
{
    *edges = NULL, *count = 0;
    if (glg->tet_count > SIZE_MAX / 6 / sizeof(uint64_t)) return LBK_ERR_OUT_OF_MEMORY;
    uint64_t *e = malloc((glg->tet_count ? glg->tet_count * 6 : 1) * sizeof *e);
    if (!e) return LBK_ERR_OUT_OF_MEMORY;
    size_t n = 0;
    for (size_t t = 0; t < glg->tet_count; t++) {
        const uint32_t *v = glg->tets + 4 * t;
        for (int a = 0; a < 4; a++)
            for (int b = a + 1; b < 4; b++) {
                uint32_t lo = v[a] < v[b] ? v[a] : v[b], hi = v[a] < v[b] ? v[b] : v[a];
                if (lo == hi || hi >= glg->probe_count) continue;
                e[n++] = (uint64_t)lo << 32 | hi;
            }
    }
    qsort(e, n, sizeof *e, cmp_u64);
    size_t u = 0;
    for (size_t i = 0; i < n; i++)
        if (u == 0 || e[i] != e[u - 1]) e[u++] = e[i];
    *edges = e, *count = u;
    return LBK_OK;
}

typedef struct vis_job {
    const bk_tracer *tracer;
    const float *pos;
    const uint64_t *edges;
    uint8_t *visible;
} vis_job;

static void vis_run(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    const vis_job *j = user;
    for (size_t e = begin; e < end; e++) {
        uint32_t a = (uint32_t)(j->edges[e] >> 32), b = (uint32_t)j->edges[e];
        const float *pa = j->pos + 3 * (size_t)a, *pb = j->pos + 3 * (size_t)b;
        float dir[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        j->visible[e] = !bk_tracer_occluded(j->tracer, pa, dir, 0.0f, 1.0f);
    }
}

void dn_probes_free(dn_probes *p)
{
    free(p->adj_first), free(p->adj);
    memset(p, 0, sizeof *p);
}

void dn_probe_weights_free(dn_probe_weights *w)
{
    free(w->w), free(w->w_sum), free(w->alpha);
    memset(w, 0, sizeof *w);
}

/* Visible edges as per-probe adjacency lists (both directions, in edge order). */
static lbk_result build_adjacency(dn_probes *p, const uint64_t *edges, const uint8_t *visible, size_t ne)
{
    p->adj_first = calloc(p->count + 1, sizeof *p->adj_first);
    if (!p->adj_first) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t e = 0; e < ne; e++)
        if (visible[e]) p->adj_first[(edges[e] >> 32) + 1]++, p->adj_first[(uint32_t)edges[e] + 1]++;
    for (size_t i = 0; i < p->count; i++) p->adj_first[i + 1] += p->adj_first[i];
    size_t na = p->adj_first[p->count];
    p->adj = malloc((na ? na : 1) * sizeof *p->adj);
    uint32_t *fill = malloc((p->count ? p->count : 1) * sizeof *fill);
    if (!p->adj || !fill) {
        free(fill);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    memcpy(fill, p->adj_first, p->count * sizeof *fill);
    for (size_t e = 0; e < ne; e++) {
        if (!visible[e]) continue;
        uint32_t a = (uint32_t)(edges[e] >> 32), b = (uint32_t)edges[e];
        p->adj[fill[a]++] = b;
        p->adj[fill[b]++] = a;
    }
    free(fill);
    return LBK_OK;
}

/* Weights and clamp from the guide's probes (luminance and variance per probe): σ_i from the
 * transport's variance averaged over the probe and its visible neighbours (0 when the probe's own
 * estimate is 0: noise-free). */
static void probe_weights(const dn_probes *p, const float *lum, const float *variance, dn_probe_weights *out)
{
    out->clamped = 0;
    for (size_t i = 0; i < p->count; i++) {
        float li = lum[i];
        double v = isfinite(variance[i]) && variance[i] > 0 ? variance[i] : 0;
        int m = 1;
        for (uint32_t k = p->adj_first[i]; k < p->adj_first[i + 1] && v > 0; k++) {
            float vj = variance[p->adj[k]];
            if (isfinite(vj) && vj > 0) v += vj;
            m++;
        }
        float sigma = (float)sqrt(v / m);
        double W = 1, acc = li;
        for (uint32_t k = p->adj_first[i]; k < p->adj_first[i + 1]; k++) {
            float lj = lum[p->adj[k]], d = fabsf(lj - li);
            float w = d == 0 ? NEIGHBOUR_WEIGHT : sigma > 0 ? NEIGHBOUR_WEIGHT * expf(-d / (p->sigma_lum * sigma)) : 0;
            out->w[k] = w;
            W += w;
            acc += w * (double)lj;
        }
        out->w_sum[i] = (float)W;
        float dl = fabsf((float)(acc / W) - li), lim = p->clamp >= 0 ? p->clamp * sigma : INFINITY;
        out->alpha[i] = sigma > 0 ? 1 : 0;
        if (sigma > 0 && dl > lim) out->alpha[i] = lim / dl, out->clamped++;
    }
}

lbk_result dn_probe_weights_build(const dn_probes *p, const dn_guide *guide, dn_probe_weights *out)
{
    memset(out, 0, sizeof *out);
    const size_t na = p->adj_first[p->count], n = p->count ? p->count : 1;
    out->w = malloc((na ? na : 1) * sizeof *out->w);
    out->w_sum = malloc(n * sizeof *out->w_sum);
    out->alpha = malloc(n * sizeof *out->alpha);
    float *lum = malloc(n * sizeof *lum), *var = malloc(n * sizeof *var);
    lbk_result r = out->w && out->w_sum && out->alpha && lum && var ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < p->count && !r; i++) {
        lbk_sh9_rgb sh;
        dn_guide_at(guide, p->first + i, &sh, &var[i]);
        lum[i] = dn_probe_lum(&sh);
    }
    if (!r) probe_weights(p, lum, var, out);
    free(lum), free(var);
    if (r) dn_probe_weights_free(out);
    return r;
}

lbk_result dn_probes_build(const bk_denoise_inputs *in, const bk_denoise_options *opt, int threads, dn_probes *out)
{
    memset(out, 0, sizeof *out);
    const bk_glg *glg = in->glg;
    out->count = glg->probe_count;
    out->first = in->glg_first;
    uint64_t *edges = NULL;
    size_t ne = 0;
    lbk_result r = tet_edges(glg, &edges, &ne);
    if (r) return r;
    uint8_t *vis = malloc(ne ? ne : 1);
    if (!vis) {
        free(edges), free(vis);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    vis_job vj = {in->tracer, glg->positions, edges, vis};
    bk_parallel_chunks(0, ne, 256, threads, vis_run, &vj);
    out->edges = ne;
    for (size_t e = 0; e < ne; e++) out->edges_visible += vis[e];
    r = build_adjacency(out, edges, vis, ne);
    free(edges), free(vis);
    if (r) return r;
    out->sigma_lum = opt && opt->sigma_lum > 0 && opt->method != BK_DENOISE_NLM ? opt->sigma_lum : 4.0f;
    out->clamp = !opt || opt->clamp == 0 ? 2.0f : opt->clamp < 0 ? -1.0f : opt->clamp;
    return LBK_OK;
}

lbk_result dn_probes_apply(const dn_probes *p, const dn_probe_weights *w, float *vals, int ch)
{
    float *x = vals + p->first * ch;
    float *copy = malloc((p->count ? p->count : 1) * ch * sizeof *copy);
    if (!copy) return LBK_ERR_OUT_OF_MEMORY;
    memcpy(copy, x, p->count * ch * sizeof *copy);
    for (size_t i = 0; i < p->count; i++) {
        if (!(w->alpha[i] > 0)) continue;
        double acc[DN_MAX_CH];
        const float *s = copy + i * ch;
        for (int k = 0; k < ch; k++) acc[k] = s[k];
        for (uint32_t e = p->adj_first[i]; e < p->adj_first[i + 1]; e++) {
            const float *v = copy + (size_t)p->adj[e] * ch;
            for (int k = 0; k < ch; k++) acc[k] += w->w[e] * (double)v[k];
        }
        float *o = x + i * ch;
        for (int k = 0; k < ch; k++) o[k] = s[k] + w->alpha[i] * ((float)(acc[k] / w->w_sum[i]) - s[k]);
    }
    free(copy);
    return LBK_OK;
}
