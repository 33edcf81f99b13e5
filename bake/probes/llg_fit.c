/* LLG probes fitted to their object's vertices: see llg_fit.h. */
#include "bake/probes/llg_fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/llg.h"

/* Regularisation towards the traced probes, relative to the mean diagonal of the normal equations:
 * small enough that the targets decide wherever they constrain a probe, large enough that an
 * unconstrained direction (a probe no vertex reads, a band no normal sees) keeps its traced value. */
#define FIT_REGULARISATION 1e-2
/* Smoothness between lattice neighbours, relative to the same diagonal: what fills the probes no
 * target reads and whose traced value is no prior (inside the object: black). */
#define FIT_SMOOTHNESS 1e-3

static const double band_a[9] = {LBK_SH_A0, LBK_SH_A1, LBK_SH_A1, LBK_SH_A1, LBK_SH_A2,
                                 LBK_SH_A2, LBK_SH_A2, LBK_SH_A2, LBK_SH_A2};

static size_t probe_count(const bk_llg *l)
{
    return (size_t)l->dims[0] * l->dims[1] * l->dims[2];
}

size_t bk_llg_fit_target_count(const bk_llg *l, const bk_scene *s, size_t usable)
{
    const size_t p = probe_count(l);
    if (!s->normals || p > BK_LLG_FIT_MAX_PROBES) return 0;
    /* two equations per unknown (9 per probe): on room_with_doors' spheres four gave the same
     * error against Cycles (PROBES.md §LLG fit) at twice the receivers */
    size_t want = 18 * p > 256 ? 18 * p : 256;
    return want < usable ? want : usable;
}

size_t bk_llg_fit_targets(const bk_llg *l, const uint32_t *usable, size_t n, uint32_t *out, size_t m)
{
    (void)l;
    if (m > n) m = n;
    for (size_t j = 0; j < m; j++) {
        const size_t k = (size_t)(((2 * (uint64_t)j + 1) * n) / (2 * (uint64_t)m));
        out[j] = usable ? usable[k] : (uint32_t)k;
    }
    return m;
}

/* The runtime's view of a vertex (lbk/llg.h "Apply"): its records as stored (quantised), the bent
 * normal in world axes, and the trilinear weights of the 8 probes around its position. */
typedef struct fit_row {
    double v, b[3];
    size_t probe[8];
    double w[8];
} fit_row;

static void row_of(const bk_llg *l, const bk_scene *s, size_t j, fit_row *r)
{
    lbk_llg_vertex rec, q;
    uint8_t packed[4];
    /* the record as stored, then through the file's bytes */
    bk_llg_vertex_record(l, j, &rec);
    lbk_llg_vertex_pack(&rec, packed);
    lbk_llg_vertex_unpack(packed, &q);
    r->v = q.visibility;
    for (int c = 0; c < 3; c++) {
        r->b[c] = 0;
        for (int a = 0; a < 3; a++) r->b[c] += q.bent_normal[a] * l->axes[a][c];
    }
    const float *p = s->positions + 3 * (size_t)l->vertices[j];
    size_t i0[3];
    double f[3];
    for (int a = 0; a < 3; a++) {
        double d = 0;
        for (int c = 0; c < 3; c++) d += ((double)p[c] - l->centre[c]) * l->axes[a][c];
        double t = d / l->half_extents[a];
        t = t < -1 ? -1 : t > 1 ? 1 : t;
        double x = (t + 1) / 2 * (double)(l->dims[a] - 1);
        size_t k = (size_t)floor(x);
        if (k > l->dims[a] - 2) k = l->dims[a] - 2;
        i0[a] = k;
        f[a] = x - (double)k;
    }
    for (int c = 0; c < 8; c++) {
        const size_t dx = c & 1, dy = (c >> 1) & 1, dz = c >> 2;
        r->probe[c] = (i0[0] + dx) + l->dims[0] * ((i0[1] + dy) + l->dims[1] * (i0[2] + dz));
        r->w[c] = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    }
}

/* The row's coefficient of unknown (probe c, band k) is w_c · V · A_k · Y_k(b). */
static void row_coeffs(const fit_row *r, double y[9])
{
    float bf[3] = {(float)r->b[0], (float)r->b[1], (float)r->b[2]}, yf[9];
    lbk_sh9_basis(bf, yf);
    for (int k = 0; k < 9; k++) y[k] = r->v * band_a[k] * yf[k];
}

static double lum3(const double e[3])
{
    return 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
}

static void model_at(const fit_row *r, const double y[9], const lbk_sh9_rgb *probes, double e[3])
{
    for (int ch = 0; ch < 3; ch++) {
        e[ch] = 0;
        for (int c = 0; c < 8; c++)
            for (int k = 0; k < 9; k++) e[ch] += r->w[c] * y[k] * probes[r->probe[c]].c[ch][k];
    }
}

/* In-place Cholesky of the n × n symmetric positive definite m (lower triangle); 0 if it is not. */
static int cholesky(double *m, size_t n)
{
    for (size_t j = 0; j < n; j++) {
        double d = m[j * n + j];
        for (size_t k = 0; k < j; k++) d -= m[j * n + k] * m[j * n + k];
        if (!(d > 0)) return 0;
        d = sqrt(d);
        m[j * n + j] = d;
        for (size_t i = j + 1; i < n; i++) {
            double s = m[i * n + j];
            for (size_t k = 0; k < j; k++) s -= m[i * n + k] * m[j * n + k];
            m[i * n + j] = s / d;
        }
    }
    return 1;
}

static void cholesky_solve(const double *l, size_t n, double *x)
{
    for (size_t i = 0; i < n; i++) {
        double s = x[i];
        for (size_t k = 0; k < i; k++) s -= l[i * n + k] * x[k];
        x[i] = s / l[i * n + i];
    }
    for (size_t i = n; i-- > 0;) {
        double s = x[i];
        for (size_t k = i + 1; k < n; k++) s -= l[k * n + i] * x[k];
        x[i] = s / l[i * n + i];
    }
}

/* μ Σ_edges ‖x_i − x_j‖² over the lattice's axis neighbours, into the normal equations. */
static void add_smoothness(const bk_llg *l, double mu, double *m, size_t u)
{
    const uint32_t *d = l->dims;
    for (uint32_t z = 0; z < d[2]; z++)
        for (uint32_t y = 0; y < d[1]; y++)
            for (uint32_t x = 0; x < d[0]; x++) {
                const size_t i = x + (size_t)d[0] * (y + (size_t)d[1] * z);
                const size_t nb[3] = {x + 1 < d[0] ? i + 1 : i, y + 1 < d[1] ? i + d[0] : i,
                                      z + 1 < d[2] ? i + (size_t)d[0] * d[1] : i};
                for (int a = 0; a < 3; a++) {
                    const size_t j = nb[a];
                    if (j == i) continue;
                    for (size_t k = 0; k < 9; k++) {
                        m[(9 * i + k) * u + 9 * i + k] += mu;
                        m[(9 * j + k) * u + 9 * j + k] += mu;
                        m[(9 * i + k) * u + 9 * j + k] -= mu;
                        m[(9 * j + k) * u + 9 * i + k] -= mu;
                    }
                }
            }
}

lbk_result bk_llg_fit(const bk_llg *l, const bk_scene *s, const uint32_t *targets, size_t target_count,
                      const float *irradiance, const uint8_t *inside, lbk_sh9_rgb *probes, bk_llg_fit_stats *stats)
{
    const size_t p = probe_count(l), u = 9 * p;
    if (!target_count || p > BK_LLG_FIT_MAX_PROBES) return LBK_OK;
    double *m = calloc(u * u, sizeof *m), *rhs = calloc(3 * u, sizeof *rhs);
    fit_row *rows = malloc(target_count * sizeof *rows);
    if (!m || !rhs || !rows) {
        free(m), free(rhs), free(rows);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t t = 0; t < target_count; t++) {
        fit_row *r = &rows[t];
        row_of(l, s, targets[t], r);
        double y[9];
        row_coeffs(r, y);
        for (int a = 0; a < 8; a++)
            for (int ka = 0; ka < 9; ka++) {
                const size_t ia = 9 * r->probe[a] + (size_t)ka;
                const double ca = r->w[a] * y[ka];
                for (int ch = 0; ch < 3; ch++) rhs[ch * u + ia] += ca * irradiance[3 * t + ch];
                for (int b = 0; b < 8; b++)
                    for (int kb = 0; kb < 9; kb++) m[ia * u + 9 * r->probe[b] + (size_t)kb] += ca * r->w[b] * y[kb];
            }
    }
    double trace = 0;
    for (size_t i = 0; i < u; i++) trace += m[i * u + i];
    const double lambda = FIT_REGULARISATION * trace / (double)u;
    for (size_t i = 0; i < u; i++) {
        if (inside && inside[i / 9]) continue;
        m[i * u + i] += lambda;
        for (int ch = 0; ch < 3; ch++) rhs[ch * u + i] += lambda * probes[i / 9].c[ch][i % 9];
    }
    add_smoothness(l, FIT_SMOOTHNESS * trace / (double)u, m, u);
    double traced_sq = 0, fitted_sq = 0, sum = 0;
    for (size_t t = 0; t < target_count; t++) {
        double y[9], e[3], tg[3] = {irradiance[3 * t], irradiance[3 * t + 1], irradiance[3 * t + 2]};
        row_coeffs(&rows[t], y);
        model_at(&rows[t], y, probes, e);
        traced_sq += (lum3(e) - lum3(tg)) * (lum3(e) - lum3(tg));
        sum += lum3(tg);
    }
    if (lambda > 0 && cholesky(m, u)) {
        for (int ch = 0; ch < 3; ch++) cholesky_solve(m, u, rhs + ch * u);
        for (size_t i = 0; i < u; i++)
            for (int ch = 0; ch < 3; ch++) probes[i / 9].c[ch][i % 9] = (float)rhs[ch * u + i];
    }
    for (size_t t = 0; t < target_count; t++) {
        double y[9], e[3], tg[3] = {irradiance[3 * t], irradiance[3 * t + 1], irradiance[3 * t + 2]};
        row_coeffs(&rows[t], y);
        model_at(&rows[t], y, probes, e);
        fitted_sq += (lum3(e) - lum3(tg)) * (lum3(e) - lum3(tg));
    }
    if (stats) {
        stats->target_sum += sum;
        stats->traced_sq += traced_sq;
        stats->fitted_sq += fitted_sq;
        stats->targets += target_count;
    }
    free(m), free(rhs), free(rows);
    return LBK_OK;
}

/* The grid's vertices that are not inside geometry, ascending; returns how many. */
static size_t usable_vertices(const bk_llg *l, const bk_scene *s, const bk_tracer *tr, uint32_t *out)
{
    double he = fmax(l->obb_half_extents[0], fmax(l->obb_half_extents[1], l->obb_half_extents[2]));
    const double offset = 1e-3 * (he > 0 ? he : 1);
    size_t n = 0;
    for (size_t j = 0; j < l->vertex_count; j++) {
        const size_t v = l->vertices[j];
        const float *p = s->positions + 3 * v, *nn = s->normals + 3 * v;
        if (!(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2] > 0.25f)) continue;
        if (tr && bk_tracer_enclosed(tr, (const double[3]){p[0], p[1], p[2]}, nn, offset)) continue;
        out[n++] = (uint32_t)j;
    }
    return n;
}

/* A probe is inside geometry when at least half of 32 rays over the sphere end on back faces
 * (the transport bakes it black, bake/transport/solid.h). */
static void mark_inside_probes(const bk_llg *llgs, size_t grids, const bk_tracer *tr, uint8_t *inside)
{
    size_t k = 0;
    for (size_t g = 0; g < grids; g++) {
        const bk_llg *l = &llgs[g];
        for (uint32_t z = 0; z < l->dims[2]; z++)
            for (uint32_t y = 0; y < l->dims[1]; y++)
                for (uint32_t x = 0; x < l->dims[0]; x++, k++) {
                    float p[3];
                    bk_llg_probe_position(l, x, y, z, p);
                    int back = 0;
                    for (int i = 0; i < 32; i++) {
                        double cz = 1 - (i + 0.5) / 16, r = sqrt(fmax(0, 1 - cz * cz)), ph = 2.399963229728653 * i;
                        float d[3] = {(float)(r * cos(ph)), (float)(r * sin(ph)), (float)cz};
                        bk_hit h;
                        if (bk_tracer_intersect(tr, p, d, 0.0f, INFINITY, &h) && !h.front) back++;
                    }
                    inside[k] = back >= 16;
                }
    }
}

lbk_result bk_llg_fit_plan_build(const bk_llg *llgs, size_t grids, const bk_scene *s, const bk_tracer *tracer,
                                 size_t first, bk_llg_fit_plan *out)
{
    memset(out, 0, sizeof *out);
    out->first = first;
    out->grids = grids;
    out->begin = calloc(grids + 1, sizeof *out->begin);
    size_t cap = 0;
    for (size_t g = 0; g < grids; g++) cap += bk_llg_fit_target_count(&llgs[g], s, llgs[g].vertex_count);
    out->vertex = malloc((cap ? cap : 1) * sizeof *out->vertex);
    size_t probes = 0;
    for (size_t g = 0; g < grids; g++) probes += probe_count(&llgs[g]);
    out->inside = calloc(probes ? probes : 1, 1);
    if (!out->begin || !out->vertex || !out->inside) {
        bk_llg_fit_plan_free(out);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t g = 0; g < grids; g++) {
        const bk_llg *l = &llgs[g];
        size_t m = bk_llg_fit_target_count(l, s, l->vertex_count), got = 0;
        if (m) {
            uint32_t *usable = malloc(l->vertex_count * sizeof *usable);
            if (!usable) {
                bk_llg_fit_plan_free(out);
                return LBK_ERR_OUT_OF_MEMORY;
            }
            const size_t n = usable_vertices(l, s, tracer, usable);
            got = bk_llg_fit_targets(l, usable, n, out->vertex + out->begin[g], bk_llg_fit_target_count(l, s, n));
            free(usable);
        }
        out->begin[g + 1] = out->begin[g] + got;
    }
    out->count = out->begin[grids];
    if (tracer) mark_inside_probes(llgs, grids, tracer, out->inside);
    return LBK_OK;
}

void bk_llg_fit_plan_free(bk_llg_fit_plan *plan)
{
    free(plan->vertex);
    free(plan->begin);
    free(plan->inside);
    memset(plan, 0, sizeof *plan);
}

void bk_llg_fit_receiver(const bk_llg_fit_plan *plan, const bk_llg *llgs, const bk_scene *s, size_t k,
                         float position[3], float normal[3])
{
    size_t g = 0;
    while (g + 1 < plan->grids && k >= plan->begin[g + 1]) g++;
    const size_t v = llgs[g].vertices[plan->vertex[k]];
    memcpy(position, s->positions + 3 * v, 3 * sizeof(float));
    memcpy(normal, s->normals + 3 * v, 3 * sizeof(float));
}

lbk_result bk_llg_fit_run(const bk_llg_fit_plan *plan, const bk_llg *llgs, const bk_scene *s,
                          const float *irradiance, lbk_sh9_rgb *radiance, size_t llg_first, bk_llg_fit_stats *stats,
                          bk_llg_fit_stats *per_grid)
{
    size_t probe = llg_first;
    for (size_t g = 0; g < plan->grids; g++) {
        const size_t b = plan->begin[g], n = plan->begin[g + 1] - b;
        bk_llg_fit_stats st = {0};
        lbk_result r = bk_llg_fit(&llgs[g], s, plan->vertex + b, n, irradiance + 3 * (plan->first + b),
                                  plan->inside ? plan->inside + (probe - llg_first) : NULL, radiance + probe, &st);
        if (r) return r;
        if (stats)
            stats->target_sum += st.target_sum, stats->traced_sq += st.traced_sq, stats->fitted_sq += st.fitted_sq,
                stats->targets += st.targets;
        if (per_grid) per_grid[g] = st;
        probe += probe_count(&llgs[g]);
    }
    return LBK_OK;
}

double bk_llg_fit_noise_grid(const bk_llg_fit_plan *plan, const bk_llg *llgs, const float *variance, size_t g)
{
    const size_t b = plan->begin[g], n = plan->begin[g + 1] - b;
    if (!n) return 0;
    const double keep = 1.0 - 9.0 * (double)probe_count(&llgs[g]) / (double)n;
    if (!(keep > 0)) return 0;
    double sum = 0;
    for (size_t t = 0; t < n; t++) {
        const float v = variance[plan->first + b + t];
        if (isfinite(v) && v > 0) sum += keep * v;
    }
    return sum;
}

double bk_llg_fit_noise(const bk_llg_fit_plan *plan, const bk_llg *llgs, const float *variance)
{
    double sum = 0;
    for (size_t g = 0; g < plan->grids; g++) sum += bk_llg_fit_noise_grid(plan, llgs, variance, g);
    return sum;
}
