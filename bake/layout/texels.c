/* Texel receivers, push-out, tangent frames and dilation (see texels.h). */
#include "bake/layout/texels.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/uv_math.h"
#include "bake/layout/uv_raster.h"
#include "bake/util/parallel.h"

/* ---------------------------------------------------------------------------------------- */
/* Tangent frame                                                                            */

static void frame_d(const double n[3], const double dpdu[3], double t[3], double b[3])
{
    double d = bkv_dot(n, dpdu);
    t[0] = dpdu[0] - n[0] * d;
    t[1] = dpdu[1] - n[1] * d;
    t[2] = dpdu[2] - n[2] * d;
    /* dP/du nearly parallel to N (or zero): no usable direction, take the fixed basis */
    if (!(bkv_len(t) > 1e-6 * bkv_len(dpdu)) || bkv_normalize(t) == 0.0) {
        double tb[3];
        bkv_basis(n, t, tb);
    }
    bkv_cross(b, n, t);
    bkv_normalize(b);
}

void bk_tangent_frame(const float n[3], const float dpdu[3], float t[3], float b[3])
{
    double nn[3], du[3], tt[3], bb[3];
    bkv_load(nn, n);
    bkv_load(du, dpdu);
    if (bkv_normalize(nn) == 0.0) {
        nn[0] = 0;
        nn[1] = 0;
        nn[2] = 1;
    }
    frame_d(nn, du, tt, bb);
    for (int k = 0; k < 3; k++) {
        t[k] = (float)tt[k];
        b[k] = (float)bb[k];
    }
}

/* ---------------------------------------------------------------------------------------- */
/* Coverage                                                                                 */

void bk_texels_free(bk_texels *tx)
{
    if (!tx) return;
    free(tx->pages);
    free(tx->page_offset);
    free(tx->index);
    free(tx->receivers);
    memset(tx, 0, sizeof *tx);
}

const bk_texel *bk_texels_at(const bk_texels *tx, uint32_t page, int x, int y)
{
    if (!tx || page >= tx->page_count) return NULL;
    const bk_atlas_page *p = &tx->pages[page];
    if (x < 0 || y < 0 || x >= p->width || y >= p->height) return NULL;
    int32_t r = tx->index[tx->page_offset[page] + (size_t)y * (size_t)p->width + (size_t)x];
    return r >= 0 ? &tx->receivers[r] : NULL;
}

void bk_texels_valid_mask(const bk_texels *tx, uint32_t page, uint8_t *mask)
{
    if (!tx || !mask || page >= tx->page_count) return;
    size_t n = (size_t)tx->pages[page].width * (size_t)tx->pages[page].height;
    const int32_t *idx = tx->index + tx->page_offset[page];
    for (size_t i = 0; i < n; i++) mask[i] = idx[i] >= 0 && (tx->receivers[idx[i]].flags & BK_TEXEL_VALID);
}

/* Fills a receiver from triangle entry e at texel (x, y); w are barycentric weights. */
static void make_receiver(const bk_scene *s, const bk_atlas *a, uint32_t e, const double w[3], bk_texel *r)
{
    uint32_t tri = a->tris[e];
    const float *uv = a->tri_uv + 6 * (size_t)e;
    double p[3][3];
    memset(r, 0, sizeof *r);
    r->tri = tri;
    r->object = s->tri_object ? s->tri_object[tri] : a->objects[a->charts[a->tri_chart[e]].slot].object;
    bk_tri_positions(s, tri, p); /* atlas triangles passed this check in uvgen */
    double pos[3] = {0, 0, 0}, nrm[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        uint32_t v = s->tris[3 * (size_t)tri + (size_t)k];
        for (int c = 0; c < 3; c++) {
            pos[c] += w[k] * p[k][c];
            if (s->normals) nrm[c] += w[k] * (double)s->normals[3 * (size_t)v + (size_t)c];
        }
    }
    double ng[3];
    bk_tri_cross(p, ng);
    double area2 = bkv_normalize(ng);
    if (!(bkv_normalize(nrm) > 0.0) || !isfinite(nrm[0] + nrm[1] + nrm[2])) memcpy(nrm, ng, sizeof nrm);
    /* dP/du and the world size of a texel from the triangle's uv mapping */
    double e1[3], e2[3];
    bkv_sub(e1, p[1], p[0]);
    bkv_sub(e2, p[2], p[0]);
    double du1 = (double)uv[2] - uv[0], dv1 = (double)uv[3] - uv[1];
    double du2 = (double)uv[4] - uv[0], dv2 = (double)uv[5] - uv[1];
    double det = du1 * dv2 - du2 * dv1;
    double dpdu[3] = {0, 0, 0};
    double size = 0.0;
    if (fabs(det) > 0.0 && isfinite(det)) {
        for (int c = 0; c < 3; c++) dpdu[c] = (e1[c] * dv2 - e2[c] * dv1) / det;
        size = sqrt(0.5 * area2 / (0.5 * fabs(det)));
    }
    if (!(size > 0.0) || !isfinite(size)) {
        const bk_atlas_object *o = &a->objects[a->charts[a->tri_chart[e]].slot];
        size = o->density > 0.0f ? 1.0 / o->density : 1.0;
    }
    double t[3], b[3];
    frame_d(nrm, dpdu, t, b);
    for (int c = 0; c < 3; c++) {
        r->position[c] = (float)pos[c];
        r->normal[c] = (float)nrm[c];
        r->tangent[c] = (float)t[c];
    }
    r->texel_size = (float)size;
    r->flags = BK_TEXEL_VALID;
}

/* Claims for each triangle of the chart the texels whose centre it covers (distance -1) or
 * that bilinear filtering reads somewhere on it (squared distance to its closest point); the
 * nearest claim wins, the first on ties. idx / bst: the chart's page in index / best. */
static void rasterise_chart(const bk_atlas *a, const bk_atlas_chart *ch, int32_t *idx, float *bst)
{
    int pw = a->pages[ch->page].width, ph = a->pages[ch->page].height;
    for (uint32_t e = ch->first; e < ch->first + ch->count; e++) {
        bk_rtri t;
        if (!bk_rtri_setup(a->tri_uv + 6 * (size_t)e, &t)) continue;
        double mnx = fmin(t.x[0], fmin(t.x[1], t.x[2])), mxx = fmax(t.x[0], fmax(t.x[1], t.x[2]));
        double mny = fmin(t.y[0], fmin(t.y[1], t.y[2])), mxy = fmax(t.y[0], fmax(t.y[1], t.y[2]));
        int x0 = (int)fmax(0.0, floor(mnx) - 1), x1 = (int)fmin((double)pw - 1, floor(mxx) + 1);
        int y0 = (int)fmax(0.0, floor(mny) - 1), y1 = (int)fmin((double)ph - 1, floor(mxy) + 1);
        for (int y = y0; y <= y1; y++)
            for (int x = x0; x <= x1; x++) {
                double cx = x + 0.5, cy = y + 0.5;
                float d;
                if (bk_rtri_inside(&t, cx, cy, NULL)) {
                    d = -1.0f;
                } else {
                    /* the bilinear footprint: filtering at some point of the triangle reads it */
                    if (!bk_rtri_meets_square(&t, cx, cy, 1.0)) continue;
                    d = (float)bk_rtri_closest(&t, cx, cy, NULL, NULL, NULL);
                }
                size_t i = (size_t)y * (size_t)pw + (size_t)x;
                if (d < bst[i]) {
                    bst[i] = d;
                    idx[i] = (int32_t)e;
                }
            }
    }
}

/* One receiver per claimed texel, pages in order and rows top to bottom; index switches from
 * the owning triangle entry to the receiver. A texel whose centre lies outside its triangle
 * samples the triangle's closest point and is marked BK_TEXEL_EDGE. */
static lbk_result emit_receivers(const bk_scene *s, const bk_atlas *a, const float *best, bk_texels *out)
{
    size_t total = out->page_offset[out->page_count], count = 0;
    for (size_t i = 0; i < total; i++) count += out->index[i] >= 0;
    out->receivers = malloc((count ? count : 1) * sizeof *out->receivers);
    if (!out->receivers) return LBK_ERR_OUT_OF_MEMORY;
    size_t r = 0;
    for (size_t p = 0; p < out->page_count; p++) {
        int pw = a->pages[p].width, ph = a->pages[p].height;
        int32_t *idx = out->index + out->page_offset[p];
        const float *bst = best + out->page_offset[p];
        for (int y = 0; y < ph; y++)
            for (int x = 0; x < pw; x++) {
                size_t i = (size_t)y * (size_t)pw + (size_t)x;
                if (idx[i] < 0) continue;
                uint32_t e = (uint32_t)idx[i];
                bk_rtri t;
                bk_rtri_setup(a->tri_uv + 6 * (size_t)e, &t);
                double w[3];
                int edge = 0;
                if (!(bst[i] < 0.0f) || !bk_rtri_inside(&t, x + 0.5, y + 0.5, w)) {
                    bk_rtri_closest(&t, x + 0.5, y + 0.5, w, NULL, NULL);
                    edge = 1;
                }
                bk_texel *rc = &out->receivers[r];
                make_receiver(s, a, e, w, rc);
                if (edge) rc->flags |= BK_TEXEL_EDGE;
                rc->page = (uint32_t)p;
                rc->x = (uint16_t)x;
                rc->y = (uint16_t)y;
                idx[i] = (int32_t)r;
                r++;
            }
    }
    out->count = count;
    return LBK_OK;
}

lbk_result bk_texels_build(const bk_scene *s, const bk_atlas *a, bk_texels *out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!s || !a || (a->tri_count && (!a->tris || !a->tri_uv))) return LBK_ERR_INVALID_ARGUMENT;
    size_t np = a->page_count, total = 0;
    for (size_t p = 0; p < np; p++) {
        if (a->pages[p].width <= 0 || a->pages[p].height <= 0 || a->pages[p].width > 65535 ||
            a->pages[p].height > 65535)
            return LBK_ERR_LIMIT;
        total += (size_t)a->pages[p].width * (size_t)a->pages[p].height;
    }
    if (total > (size_t)INT32_MAX) return LBK_ERR_LIMIT;
    out->page_count = np;
    out->pages = malloc((np ? np : 1) * sizeof *out->pages);
    out->page_offset = malloc((np + 1) * sizeof *out->page_offset);
    out->index = malloc((total ? total : 1) * sizeof *out->index);
    float *best = malloc((total ? total : 1) * sizeof *best);
    if (!out->pages || !out->page_offset || !out->index || !best) {
        free(best);
        bk_texels_free(out);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t off = 0;
    for (size_t p = 0; p < np; p++) {
        out->pages[p] = a->pages[p];
        out->page_offset[p] = off;
        off += (size_t)a->pages[p].width * (size_t)a->pages[p].height;
    }
    out->page_offset[np] = off;
    /* index holds the owning triangle entry during rasterisation; best its squared
     * distance (-1: centre inside) */
    for (size_t i = 0; i < total; i++) {
        out->index[i] = -1;
        best[i] = INFINITY;
    }
    for (size_t c = 0; c < a->chart_count; c++) {
        const bk_atlas_chart *ch = &a->charts[c];
        if (ch->page < 0 || (size_t)ch->page >= np) continue;
        rasterise_chart(a, ch, out->index + out->page_offset[ch->page], best + out->page_offset[ch->page]);
    }
    lbk_result res = emit_receivers(s, a, best, out);
    free(best);
    if (res != LBK_OK) bk_texels_free(out);
    return res;
}

/* ---------------------------------------------------------------------------------------- */
/* Push-out                                                                                 */

typedef struct push_job {
    bk_texels *tx;
    const bk_scene *scene;
    const bk_tracer *tracer;
    float reach;
    float far_dist;
    bk_pushout_stats *thread_stats; /* one per thread, summed at the end */
} push_job;

/* Fixed hemisphere directions (local frame, z up): a Fibonacci spiral, deterministic. */
#define LONG_RAYS 16
static void hemisphere_dir(int i, int n, double d[3])
{
    const double golden = 2.39996322972865332; /* π(3 − √5) */
    double z = 1.0 - (i + 0.5) / n;            /* uniform in solid angle over z ∈ (0, 1] */
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = r * cos(golden * i);
    d[1] = r * sin(golden * i);
    d[2] = z;
}

static void to_world(const double t[3], const double b[3], const double n[3], const double l[3], float out[3])
{
    for (int c = 0; c < 3; c++) out[c] = (float)(l[0] * t[c] + l[1] * b[c] + l[2] * n[c]);
}

/* Geometric normal of triangle tri, oriented to agree with the shading normal sn. */
static void oriented_geo_normal(const bk_scene *s, uint32_t tri, const float sn[3], double ng[3])
{
    double p[3][3];
    if (!bk_tri_positions(s, tri, p)) {
        bkv_load(ng, sn);
        return;
    }
    bk_tri_cross(p, ng);
    if (bkv_normalize(ng) == 0.0) {
        bkv_load(ng, sn);
        return;
    }
    double sd[3];
    bkv_load(sd, sn);
    if (bkv_dot(ng, sd) < 0.0) {
        ng[0] = -ng[0];
        ng[1] = -ng[1];
        ng[2] = -ng[2];
    }
}

static void hit_point(const bk_scene *s, const bk_hit *h, float out[3])
{
    double p[3][3];
    if (!bk_tri_positions(s, h->tri, p)) return;
    double w0 = 1.0 - h->u - h->v;
    for (int c = 0; c < 3; c++) out[c] = (float)(w0 * p[0][c] + h->u * p[1][c] + h->v * p[2][c]);
}

static void push_one(const push_job *j, bk_texel *r, bk_pushout_stats *st)
{
    const bk_scene *s = j->scene;
    double ng[3], t[3], b[3];
    oriented_geo_normal(s, r->tri, r->normal, ng);
    bkv_basis(ng, t, b);
    float ngf[3] = {(float)ng[0], (float)ng[1], (float)ng[2]};
    float reach = j->reach * r->texel_size;
    uint32_t cur_tri = r->tri;
    float cur_n[3] = {ngf[0], ngf[1], ngf[2]};
    /* short rays: 8 along the tangent plane (raised ~3°), 5 over the hemisphere */
    double local[13][3];
    for (int i = 0; i < 8; i++) {
        double a = i * (3.14159265358979323846 / 4.0);
        local[i][0] = cos(a) * 0.9986;
        local[i][1] = sin(a) * 0.9986;
        local[i][2] = 0.0523;
    }
    for (int i = 0; i < 4; i++) {
        double a = (i + 0.5) * (3.14159265358979323846 / 2.0);
        local[8 + i][0] = cos(a) * 0.7071;
        local[8 + i][1] = sin(a) * 0.7071;
        local[8 + i][2] = 0.7071;
    }
    local[12][0] = local[12][1] = 0.0;
    local[12][2] = 1.0;
    for (int iter = 0; iter < 3; iter++) {
        float org[3];
        bk_offset_ray_origin_scaled(r->position, cur_n, bk_tracer_tri_scale(j->tracer, cur_tri), org);
        bk_hit best;
        int found = 0;
        for (int i = 0; i < 13; i++) {
            float d[3];
            to_world(t, b, ng, local[i], d);
            bk_hit h;
            if (!bk_tracer_intersect(j->tracer, org, d, 0.0f, reach, &h)) continue;
            if (h.front) continue;
            if (!found || h.t < best.t) {
                best = h;
                found = 1;
            }
        }
        if (!found) break;
        float q[3] = {r->position[0], r->position[1], r->position[2]};
        hit_point(s, &best, q);
        /* just in front of the surface we were behind: its front side is along ng */
        bk_offset_ray_origin_scaled(q, best.ng, bk_tracer_tri_scale(j->tracer, best.tri), r->position);
        cur_tri = best.tri;
        memcpy(cur_n, best.ng, sizeof cur_n);
        r->flags |= BK_TEXEL_PUSHED;
    }
    if (r->flags & BK_TEXEL_PUSHED) st->pushed++;
    /* inside closed geometry? */
    float org[3];
    bk_offset_ray_origin_scaled(r->position, cur_n, bk_tracer_tri_scale(j->tracer, cur_tri), org);
    int back = 0;
    for (int i = 0; i < LONG_RAYS; i++) {
        double l[3];
        hemisphere_dir(i, LONG_RAYS, l);
        float d[3];
        to_world(t, b, ng, l, d);
        bk_hit h;
        if (bk_tracer_intersect(j->tracer, org, d, 0.0f, j->far_dist, &h) && !h.front) back++;
        /* early out once the answer cannot change */
        if (2 * back >= LONG_RAYS || 2 * (back + LONG_RAYS - 1 - i) < LONG_RAYS) break;
    }
    if (2 * back >= LONG_RAYS) {
        r->flags &= ~(uint32_t)BK_TEXEL_VALID;
        r->flags |= BK_TEXEL_INSIDE;
        st->inside++;
    }
    st->tested++;
}

static void push_chunk(void *user, size_t begin, size_t end, int thread)
{
    const push_job *j = user;
    for (size_t i = begin; i < end; i++) push_one(j, &j->tx->receivers[i], &j->thread_stats[thread]);
}

lbk_result bk_texels_push_out(bk_texels *tx, const bk_scene *scene, const bk_tracer *tracer,
                              const bk_pushout_options *opt, bk_pushout_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    if (!tx || !scene || !tracer) return LBK_ERR_INVALID_ARGUMENT;
    float reach = opt && opt->reach > 0.0f && isfinite(opt->reach) ? opt->reach : 1.5f;
    int threads = bk_thread_count(opt ? opt->threads : 0);
    /* long rays: beyond the scene's extent */
    double diag = 0.0;
    for (int c = 0; c < 3; c++) {
        double d = (double)scene->bounds_max[c] - scene->bounds_min[c];
        if (isfinite(d) && d > 0) diag += d * d;
    }
    float far_dist = diag > 0.0 ? (float)(2.0 * sqrt(diag)) : FLT_MAX;
    if (!isfinite(far_dist) || far_dist <= 0.0f) far_dist = FLT_MAX;
    push_job job = {tx, scene, tracer, reach, far_dist, calloc((size_t)threads, sizeof(bk_pushout_stats))};
    if (!job.thread_stats) return LBK_ERR_OUT_OF_MEMORY;
    /* 64 receivers a chunk (up to 3·13 short and 16 long rays each): coarse enough to hide the
     * shared counter, fine enough to balance walls against cluttered corners */
    bk_parallel_chunks(0, tx->count, 64, threads, push_chunk, &job);
    if (stats)
        for (int k = 0; k < threads; k++) {
            stats->tested += job.thread_stats[k].tested;
            stats->pushed += job.thread_stats[k].pushed;
            stats->inside += job.thread_stats[k].inside;
        }
    free(job.thread_stats);
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Dilation                                                                                 */

#define DILATE_NEW 0xFFu /* filled during the current pass */

size_t bk_dilate(float *data, int channels, uint8_t *mask, int width, int height, int passes)
{
    if (!data || !mask || channels <= 0 || width <= 0 || height <= 0 || passes <= 0) return 0;
    size_t n = (size_t)width * (size_t)height;
    for (size_t i = 0; i < n; i++)
        if (mask[i] == DILATE_NEW) mask[i] = 1;
    size_t filled = 0;
    static const int d4[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    static const int dd[4][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
    for (int pass = 0; pass < passes; pass++) {
        size_t this_pass = 0;
        for (int y = 0; y < height; y++)
            for (int x = 0; x < width; x++) {
                size_t i = (size_t)y * (size_t)width + (size_t)x;
                if (mask[i]) continue;
                for (int set = 0; set < 2; set++) {
                    const int(*d)[2] = set ? dd : d4;
                    int cnt = 0;
                    for (int k = 0; k < 4; k++) {
                        int nx = x + d[k][0], ny = y + d[k][1];
                        if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
                        uint8_t m = mask[(size_t)ny * (size_t)width + (size_t)nx];
                        if (m && m != DILATE_NEW) cnt++;
                    }
                    if (!cnt) continue;
                    float *dst = data + i * (size_t)channels;
                    for (int c = 0; c < channels; c++) {
                        double acc = 0.0;
                        for (int k = 0; k < 4; k++) {
                            int nx = x + d[k][0], ny = y + d[k][1];
                            if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
                            size_t j = (size_t)ny * (size_t)width + (size_t)nx;
                            if (mask[j] && mask[j] != DILATE_NEW) acc += data[j * (size_t)channels + (size_t)c];
                        }
                        dst[c] = (float)(acc / cnt);
                    }
                    mask[i] = DILATE_NEW;
                    this_pass++;
                    break;
                }
            }
        for (size_t i = 0; i < n; i++)
            if (mask[i] == DILATE_NEW) mask[i] = 2;
        filled += this_pass;
        if (this_pass == 0) break;
    }
    return filled;
}
