/* The run context (transport_impl.h): the lattices, the parallel-for, the cells and their
 * geometry, and the set-up and teardown of a run. */
#include "bake/transport/transport_impl.h"

#include "scene/parallel.h"
#include "lbk/octa.h"

/* ---- lattices --------------------------------------------------------------------------------- */

/* Randomly shifted rank-1 lattice {(j/S, j·g/S) + shift} mod 1, g ≈ 0.618·S coprime with S
 * (Fibonacci-like): the first coordinate is an exactly stratified grid, which gives the
 * provable furnace bound of TRANSPORT.md; the random shift keeps every estimate unbiased, so the
 * two halves stay independent and the error estimate honest. */
static uint32_t lattice_generator(uint32_t S)
{
    uint32_t g = (uint32_t)(0.6180339887498949 * S) | 1u;
    for (;; g += 2) {
        uint32_t a = g, b = S;
        while (b) { uint32_t t = a % b; a = b; b = t; }
        if (a == 1 || S <= 1) return g;
    }
}

lbk_result bk_tr_lattice_init(tp_lattice *l, uint32_t S)
{
    if (l->S == S) return LBK_OK;
    free(l->cos_k);
    free(l->sin_k);
    free(l->k_of_j);
    l->cos_k = malloc(S * sizeof(double));
    l->sin_k = malloc(S * sizeof(double));
    l->k_of_j = malloc(S * sizeof(uint32_t));
    l->S = 0;
    if (!l->cos_k || !l->sin_k || !l->k_of_j) return LBK_ERR_OUT_OF_MEMORY;
    for (uint32_t k = 0; k < S; k++) {
        l->cos_k[k] = cos(2 * 3.14159265358979323846 * k / S);
        l->sin_k[k] = sin(2 * 3.14159265358979323846 * k / S);
    }
    l->S = S;
    l->g = lattice_generator(S);
    for (uint32_t j = 0; j < S; j++) l->k_of_j[j] = (uint32_t)(((uint64_t)j * l->g) % S);
    return LBK_OK;
}

static void lattice_free(tp_lattice *l) { free(l->cos_k); free(l->sin_k); free(l->k_of_j); }

/* ---- parallel-for --------------------------------------------------------------------------- */

typedef struct tp_call { tp_ctx *c; tp_fn fn; } tp_call;

static void tp_call_run(void *user, size_t begin, size_t end, int thread)
{
    const tp_call *k = (const tp_call *)user;
    k->fn(k->c, begin, end, thread);
}

void bk_tr_parallel_range(tp_ctx *c, size_t begin, size_t end, size_t chunk, tp_fn fn)
{
    tp_call k = {c, fn};
    bk_parallel_chunks(begin, end, chunk, c->threads, tp_call_run, &k);
}

/* ---- scene lookups -------------------------------------------------------------------------- */

static int in_light_set(const tp_ctx *c, const char *set)
{
    const char *want = c->opt->light_set ? c->opt->light_set : "";
    return strncmp(set, want, 63) == 0;
}

/* Row j of sub-triangle s in an m×m split: row r holds 2(m − r) − 1 cells, so rows before j
 * hold j(2m − j); the largest j with j(2m − j) <= s, from the quadratic and one correction. */
static int sub_row(int m, long s)
{
    double disc = (double)m * m - (double)s;
    int j = (int)(m - sqrt(disc > 0 ? disc : 0));
    if (j < 0) j = 0;
    if (j > m - 1) j = m - 1;
    while (j > 0 && (long)j * (2 * m - j) > s) j--;
    while (j < m - 1 && (long)(j + 1) * (2 * m - j - 1) <= s) j++;
    return j;
}

void bk_tr_cell_geom(const tp_ctx *c, const tp_cell *cell, tp_cell_geom *g)
{
    int m = cell->m;
    long s = (long)cell->sub;
    int j = sub_row(m, s);
    s -= (long)j * (2 * m - j);
    int i = (int)(s / 2), upper = (int)(s & 1);
    double c0[2], c1[2], c2[2];
    if (!upper) {
        c0[0] = i; c0[1] = j; c1[0] = i + 1; c1[1] = j; c2[0] = i; c2[1] = j + 1;
    } else {
        c0[0] = i + 1; c0[1] = j; c1[0] = i + 1; c1[1] = j + 1; c2[0] = i; c2[1] = j + 1;
    }
    for (int k = 0; k < 2; k++) {
        g->b[0][k] = c0[k] / m;
        g->b[1][k] = c1[k] / m;
        g->b[2][k] = c2[k] / m;
    }
    bk_tr_tri_vertices(c, cell->tri, g->v);
    g->eps = c->tri_edge_eps[cell->tri];
}

/* The point of a cell for (r1, r2) in [0,1)², uniform over its area, kept off the triangle's
 * edges; bu, bv (optional) get its barycentrics in the whole triangle. */
void bk_tr_cell_point_at(const tp_cell_geom *g, double r1, double r2, double p[3], double *bu, double *bv)
{
    double sq = sqrt(r1);
    double w0 = 1 - sq, w1 = sq * (1 - r2), w2 = sq * r2;
    double u = w0 * g->b[0][0] + w1 * g->b[1][0] + w2 * g->b[2][0];
    double v = w0 * g->b[0][1] + w1 * g->b[1][1] + w2 * g->b[2][1];
    /* clamp into the band-free interior: only points within the band move, and only onto the
     * band's inner border, so the rest of the triangle is sampled exactly uniformly */
    double eps = g->eps;
    if (eps > 0) {
        double w = 1 - u - v;
        u = u < eps ? eps : u;
        v = v < eps ? eps : v;
        w = w < eps ? eps : w;
        double sum = u + v + w;
        u /= sum;
        v /= sum;
    }
    for (int a = 0; a < 3; a++) p[a] = (1 - u - v) * g->v[0][a] + u * g->v[1][a] + v * g->v[2][a];
    if (bu) *bu = u;
    if (bv) *bv = v;
}

/* ---- setup ------------------------------------------------------------------------------------ */

void bk_tr_free_ctx(tp_ctx *c)
{
    free(c->cells); free(c->tri_first); free(c->tri_m); free(c->tri_sides); free(c->tri_closed); free(c->tri_cell_h); free(c->tri_edge_eps);
    free(c->tri_le); free(c->tri_le_tex); free(c->em); free(c->em_cdf);
    free(c->gloss); free(c->ggx);
    free(c->thread_shadow);
    free(c->lights);
    for (int h = 0; h < 2; h++) {
        for (int d = 0; d <= TP_CACHE_DEPTH; d++) free(c->l_hist[h][d]);
        free(c->l_cur[h]); free(c->l_sum[h]); free(c->x_acc[h]);
        free(c->b_acc[h]);
    }
    free(c->rough); free(c->gap); free(c->cell_lum); free(c->cell_var);
    free(c->punct_lum);
    free(c->stop_idx);
    free(c->extra);
    free(c->blk_w); free(c->blk_on); free(c->blk_next);
    free(c->thread_rays); free(c->thread_nonfinite);
    lattice_free(&c->lat);
    lattice_free(&c->oct_lat);
    lattice_free(&c->check_lat);
    free(c->oct_acc[0]);
    free(c->oct_acc[1]);
    for (int h = 0; h < 2; h++) bk_slc_draw_destroy(c->draw_recv[h]);
    bk_slc_draw_destroy(c->draw_cell);
    bk_slc_destroy(c->slc_recv);
    bk_slc_destroy(c->slc_cell);
    free(c->slc_ids);
    free(c->thread_slc_tested);
    free(c->slc_cdf);
    free(c->slc_pick_ids);
    bk_tr_vpl_pass_end(c);
    bk_slc_destroy(c->vpl_tiles);
    free(c->vpl_ids);
    free(c->light_vpl);
    free(c->thread_vpl_tested);
}

/* Longest edge of triangle i. */
static double tri_longest(const tp_ctx *c, uint32_t i)
{
    double v[3][3], longest = 0;
    bk_tr_tri_vertices(c, i, v);
    for (int e = 0; e < 3; e++) {
        double l2 = 0;
        for (int k = 0; k < 3; k++) l2 += (v[(e + 1) % 3][k] - v[e][k]) * (v[(e + 1) % 3][k] - v[e][k]);
        longest = fmax(longest, sqrt(l2));
    }
    return longest;
}

/* Subdivision m of triangle i for cells of about `size` metres (sized), or of area cell_area
 * (automatic budget); m² sub-triangles per side. */
static int tri_subdivision(const tp_ctx *c, uint32_t i, double size, double cell_area)
{
    double a = bk_tracer_tri_area(c->tracer, i), m = 1;
    if (!(a > 0) || !isfinite(a)) return 1;
    if (size > 0) {
        /* square-ish cells of the wanted size; slivers split along their length too */
        m = fmax(ceil(sqrt(a) / size), ceil(tri_longest(c, i) / (2 * size)));
    } else if (cell_area > 0) {
        m = floor(sqrt(a / cell_area));
    }
    return m < 1 ? 1 : m > TP_MAX_SUB ? TP_MAX_SUB : (int)m;
}

/* Cells per triangle: sized triangles (options.cell_size, e.g. the lightmap's texel size: the
 * cache then resolves light as finely as the lightmap stores it) and the rest sharing max_cells
 * by area; if everything exceeds TP_CELL_CAP the sizes grow uniformly until it fits. */
static lbk_result size_cells(tp_ctx *c, size_t *count_out)
{
    const bk_scene *s = c->scene;
    const float *want = c->opt->cell_size;
    size_t nt = s->tri_count;
    size_t max_cells = c->opt->max_cells > 0 ? (size_t)c->opt->max_cells : 32768;
    double auto_area = 0;
    for (size_t i = 0; i < nt; i++) {
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        int ds = mi < s->material_count ? s->materials[mi].double_sided : 0;
        /* a closed solid's back side is its inside: never seen, no cells */
        c->tri_sides[i] = ds && !c->tri_closed[i] ? 2 : 1;
        if (!(want && want[i] > 0 && isfinite(want[i])))
            auto_area += (double)bk_tracer_tri_area(c->tracer, (uint32_t)i) * c->tri_sides[i];
    }
    double cell_area = auto_area > 0 ? auto_area / (double)max_cells : 0;
    for (double grow = 1;; grow *= 1.25) {
        size_t count = 0;
        for (size_t i = 0; i < nt; i++) {
            double size = want && want[i] > 0 && isfinite(want[i]) ? want[i] * grow : 0;
            int m = tri_subdivision(c, (uint32_t)i, size, cell_area * grow * grow);
            c->tri_m[i] = (uint16_t)m;
            c->tri_first[i] = (uint32_t)(count < UINT32_MAX ? count : UINT32_MAX);
            count += (size_t)c->tri_sides[i] * (size_t)m * (size_t)m;
        }
        if (count <= TP_CELL_CAP) { *count_out = count; return LBK_OK; }
        if (grow > 1e6) return LBK_ERR_LIMIT;
    }
}

/* The glossy cells' storage and the coupling's table, only when a triangle's material is glossy
 * (a scene without one runs exactly the Lambertian code). */
static lbk_result gloss_init(tp_ctx *c)
{
    const bk_scene *s = c->scene;
    int any = 0;
    for (size_t i = 0; i < s->tri_count && !any; i++) {
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        any = mi < s->material_count && bk_material_glossy(&s->materials[mi]);
    }
    if (!any) return LBK_OK;
    c->gloss = calloc(c->cell_count ? c->cell_count : 1, sizeof *c->gloss);
    c->ggx = malloc(sizeof *c->ggx);
    if (!c->gloss || !c->ggx) return LBK_ERR_OUT_OF_MEMORY;
    bk_ggx_table_init(c->ggx);
    return LBK_OK;
}

/* A glossy material's cell at uv: base colour = the (hooked) albedo, metallic and roughness =
 * factor × texture (B, G); the cell's Lambertian albedo (what a read of its cache reflects,
 * where a chain of continuations ends on it) becomes the coupled BSDF's mean albedo. A cell the
 * hook made black (a closed door in a set run) stays black and Lambertian. */
static void cell_gloss(const tp_ctx *c, const bk_material *mat, const double uv[2], float albedo[3], tp_gloss *gl)
{
    if (albedo[0] <= 0 && albedo[1] <= 0 && albedo[2] <= 0) return;
    double mr[3] = {1, 1, 1};
    if (mat->metal_rough_tex1 > 0)
        bk_sample_image(bk_scene_image(c->scene, mat->metal_rough_tex1 - 1), uv[0], uv[1], mr);
    double metal = mat->metallic * mr[2], rough = mat->roughness * mr[1];
    gl->metallic = (float)(isfinite(metal) ? fmin(fmax(metal, 0), 1) : 0);
    gl->roughness = (float)(isfinite(rough) ? fmin(fmax(rough, 0), 1) : 1);
    double base[3] = {albedo[0], albedo[1], albedo[2]}, mean[3];
    bk_mr_albedo_mean(c->ggx, base, gl->metallic, gl->roughness, mean);
    for (int k = 0; k < 3; k++) {
        gl->base[k] = albedo[k];
        albedo[k] = (float)fmin(fmax(mean[k], 0), 0.999);
    }
    gl->on = 1;
}

static lbk_result build_cells(tp_ctx *c)
{
    const bk_scene *s = c->scene;
    size_t nt = s->tri_count;
    c->tri_first = calloc(nt ? nt : 1, sizeof *c->tri_first);
    c->tri_m = calloc(nt ? nt : 1, sizeof *c->tri_m);
    c->tri_sides = calloc(nt ? nt : 1, 1);
    c->tri_closed = calloc(nt ? nt : 1, 1);
    c->tri_edge_eps = calloc(nt ? nt : 1, sizeof(float));
    c->tri_cell_h = calloc(nt ? nt : 1, sizeof(float));
    c->tri_le = calloc(3 * (nt ? nt : 1), sizeof(float));
    c->tri_le_tex = calloc(nt ? nt : 1, sizeof(int32_t));
    if (!c->tri_first || !c->tri_m || !c->tri_sides || !c->tri_closed || !c->tri_edge_eps || !c->tri_cell_h ||
        !c->tri_le || !c->tri_le_tex)
        return LBK_ERR_OUT_OF_MEMORY;
    lbk_result r = bk_closed_triangles(s, c->tri_closed);
    if (r != LBK_OK) return r;
    size_t count = 0;
    r = size_cells(c, &count);
    if (r != LBK_OK) return r;
    for (size_t i = 0; i < nt; i++) {
        /* keep sample points >= 8 ulps of the coordinates inside every edge (the tracer's edge
         * limitation, tracer.h): a barycentric floor of 8 ulp / altitude */
        double a = bk_tracer_tri_area(c->tracer, (uint32_t)i), longest = tri_longest(c, (uint32_t)i);
        double alt = longest > 0 ? 2 * a / longest : 0;
        double ulp = bk_tracer_tri_scale(c->tracer, (uint32_t)i) * 1.1920928955078125e-07;
        double eps = alt > 0 && isfinite(alt) ? 8 * ulp / alt : 0;
        c->tri_edge_eps[i] = (float)(eps > 0.3 ? 0.3 : eps);
        int m = c->tri_m[i];
        double h = fmax(longest / m, sqrt(2 * a) / m);
        c->tri_cell_h[i] = (float)(isfinite(h) ? h : 0);
    }
    c->cell_count = count;
    c->cells = calloc(count ? count : 1, sizeof *c->cells);
    if (!c->cells) return LBK_ERR_OUT_OF_MEMORY;
    r = gloss_init(c);
    if (r != LBK_OK) return r;
    for (size_t i = 0; i < nt; i++) {
        uint32_t mi = s->tri_material ? s->tri_material[i] : 0;
        const bk_material *mat = mi < s->material_count ? &s->materials[mi] : NULL;
        uint32_t oi = s->tri_object ? s->tri_object[i] : 0;
        const char *set = (oi < s->object_count) ? s->objects[oi].light_set : "";
        int emits = in_light_set(c, set);
        float n[3];
        bk_tracer_tri_normal(c->tracer, (uint32_t)i, n);
        float area = bk_tracer_tri_area(c->tracer, (uint32_t)i);
        int m = c->tri_m[i];
        c->tri_le_tex[i] = -1;
        if (mat && emits && area > 0) {
            for (int k = 0; k < 3; k++) {
                double em = mat->emission[k];
                c->tri_le[3 * i + k] = (float)(isfinite(em) && em > 0 ? em : 0);
            }
            if (mat->emission_tex >= 0 && bk_scene_image(s, mat->emission_tex)) c->tri_le_tex[i] = mat->emission_tex;
        }
        for (long sub = 0; sub < (long)m * m; sub++) {
            /* material values at the cell's centroid (uv0) */
            int j = sub_row(m, sub);
            long ss = sub - (long)j * (2 * m - j);
            int ii = (int)(ss / 2), up = (int)(ss & 1);
            double cu = up ? (3.0 * ii + 2) / (3.0 * m) : (3.0 * ii + 1) / (3.0 * m);
            double cv = up ? (3.0 * j + 2) / (3.0 * m) : (3.0 * j + 1) / (3.0 * m);
            double uv[2];
            bk_tri_uv0(s, (uint32_t)i, cu, cv, uv);
            float albedo[3] = {0, 0, 0}, le[3] = {0, 0, 0};
            if (mat) {
                double al[3], em[3];
                bk_material_albedo(s, mat, uv, al);
                bk_material_emission(s, mat, uv, em);
                for (int k = 0; k < 3; k++) {
                    albedo[k] = (float)al[k];
                    le[k] = emits ? (float)em[k] : 0;
                }
            }
            if (c->opt->albedo_hook) {
                c->opt->albedo_hook(c->opt->user, (uint32_t)i, albedo);
                for (int k = 0; k < 3; k++)
                    albedo[k] = isfinite(albedo[k]) ? (albedo[k] < 0 ? 0 : albedo[k] > 0.999f ? 0.999f : albedo[k]) : 0;
            }
            tp_gloss gl;
            memset(&gl, 0, sizeof gl);
            if (c->gloss && mat && bk_material_glossy(mat)) cell_gloss(c, mat, uv, albedo, &gl);
            for (int side = 0; side < c->tri_sides[i]; side++) {
                if (gl.on) c->gloss[c->tri_first[i] + (size_t)side * m * m + sub] = gl;
                tp_cell *cell = &c->cells[c->tri_first[i] + (size_t)side * m * m + sub];
                cell->tri = (uint32_t)i;
                cell->sub = (uint32_t)sub;
                cell->m = (uint16_t)m;
                cell->side = (uint8_t)side;
                for (int k = 0; k < 3; k++) cell->n[k] = side ? -n[k] : n[k];
                cell->area = area / (float)(m * m);
                memcpy(cell->albedo, albedo, sizeof albedo);
                memcpy(cell->le, le, sizeof le);
            }
        }
    }
    return LBK_OK;
}

/* How many continuations in a row a near hit in the cache's bounces may take: TP_CACHE_DEPTH
 * while the bounce history fits TP_CACHE_HIST_BYTES, fewer on caches of millions of cells (at
 * least 1, as before gap cells: TRANSPORT.md). It depends on the cell count only, so every unit of a
 * distributed bake and every resumed run picks the same. */
#define TP_CACHE_HIST_BYTES ((size_t)256 << 20)
static int cache_depth_for(size_t cells)
{
    size_t per = 2 * 3 * sizeof(float) * (cells ? cells : 1); /* one bounce, both halves */
    size_t fit = TP_CACHE_HIST_BYTES / per;
    if (fit < 2) return 1;
    return fit - 1 > TP_CACHE_DEPTH ? TP_CACHE_DEPTH : (int)(fit - 1);
}

/* Everything a run needs before its first pass: counters, the light selection, cells,
 * emitters, the per-half radiance arrays and the receivers' accumulators. */
lbk_result bk_tr_ctx_init(tp_ctx *c)
{
    const bk_scene *scene = c->scene;
    const bk_transport_options *opt = c->opt;
    c->thread_rays = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_nonfinite = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_shadow = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_slc_tested = calloc((size_t)c->threads, sizeof(uint64_t));
    c->thread_vpl_tested = calloc((size_t)c->threads, sizeof(uint64_t));
    if (!c->thread_rays || !c->thread_nonfinite || !c->thread_shadow || !c->thread_slc_tested || !c->thread_vpl_tested)
        return LBK_ERR_OUT_OF_MEMORY;
    /* scale of the coordinates: offsets for receivers, which carry no triangle */
    for (size_t i = 0; i < scene->tri_count; i++) {
        float sc = bk_tracer_tri_scale(c->tracer, (uint32_t)i);
        if (sc > c->scene_scale) c->scene_scale = sc;
    }
    const int base_bake = !(opt->light_set && opt->light_set[0]);
    c->use_sky = base_bake && !opt->no_sky;
    if (!opt->no_punctual && scene->light_count) {
        c->lights = calloc(scene->light_count, sizeof *c->lights);
        if (!c->lights) return LBK_ERR_OUT_OF_MEMORY;
        for (size_t i = 0; i < scene->light_count; i++)
            if (in_light_set(c, scene->lights[i].light_set)) c->lights[c->light_count++] = &scene->lights[i];
    }
    lbk_result res = build_cells(c);
    if (res == LBK_OK) res = bk_tr_build_emitters(c);
    if (res == LBK_OK) res = bk_tr_slc_init(c);
    if (res == LBK_OK) res = bk_tr_vpl_init(c);
    if (res != LBK_OK) return res;
    size_t nc = c->cell_count ? c->cell_count : 1, n = c->recv_count ? c->recv_count : 1;
    c->cache_depth = cache_depth_for(nc);
    for (int h = 0; h < 2; h++) {
        for (int d = 0; d <= c->cache_depth; d++)
            if (!(c->l_hist[h][d] = calloc(3 * nc, sizeof(float)))) return LBK_ERR_OUT_OF_MEMORY;
        c->l_cur[h] = calloc(3 * nc, sizeof(float));
        c->l_sum[h] = calloc(3 * nc, sizeof(float));
        c->x_acc[h] = calloc(n, sizeof(double));
        c->b_acc[h] = calloc(n, sizeof(double));
        if (!c->l_cur[h] || !c->l_sum[h] || !c->x_acc[h] || !c->b_acc[h])
            return LBK_ERR_OUT_OF_MEMORY;
    }
    c->rough = calloc(nc, 1);
    c->gap = calloc(nc, 1);
    c->cell_lum = calloc(nc, sizeof(float));
    c->cell_var = calloc(nc, sizeof(float));
    if (!c->rough || !c->gap || !c->cell_lum || !c->cell_var) return LBK_ERR_OUT_OF_MEMORY;
    bk_tr_parallel_for(c, c->cell_count, 256, bk_tr_mark_gaps);
    for (size_t i = 0; i < c->cell_count; i++) c->rough[i] = c->gap[i] != 0; /* pass 0's marks, as bk_tr_mark_rough's */
    for (int h = 0; h < 2 && c->oct_count; h++)
        if (!(c->oct_acc[h] = calloc(16 * c->oct_count, sizeof(double)))) return LBK_ERR_OUT_OF_MEMORY;
    for (uint32_t t = 0; t < 16; t++) {
        float d[3];
        lbk_oct_texel_direction(4, t % 4, t / 4, d);
        for (int a = 0; a < 3; a++) c->oct_dir[t][a] = d[a];
    }
    c->punct_lum = calloc(n, sizeof(float));
    return c->punct_lum ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
}
