/* Ring texels (bake/layout/texels.h, Ring): which value makes the bilinearly filtered lightmap
 * closest to an independent reference at the chart points that read them (printed, not
 * asserted).
 *
 * A ring texel is read by bilinear filtering at chart points within a texel of the chart's
 * border, but no chart triangle covers its square. Two candidates:
 *   point:  bake it at its own sample point (the chart's closest point, pushed out of walls),
 *           with no footprint;
 *   dilate: leave it empty; bk_dilate fills it from its chart's baked neighbours.
 * Scene: the bias room (tests/support/bias_scene.h); every texel baked once by the transport
 * (the ring texels as point receivers), the two lightmaps built from the same run. Evaluation
 * points: uniform points of the chart triangles whose bilinear taps include a ring texel, not
 * inside a slab; the reference (tests/support/ref_path.h) is the irradiance at the point itself.
 * Printed: relative RMSE sqrt(Σ(lbk − ref)²/Σref²) and signed error Σ(lbk − ref)/Σref of the
 * filtered luminance, per candidate, and the reference's own noise on the same scale.
 *
 *   bench_ring [--density D] [--passes P] [--points N] [--ref-paths R] [--threads T] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/atlas.h"
#include "bake/layout/seams.h"
#include "bake/layout/texels.h"
#include "bake/transport/transport.h"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"
#include "tests/support/bias_scene.c"
#include "tests/support/ref_path.c"

static double lum3f(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }
static double lum3d(const double *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

typedef struct ev_pt {
    uint32_t page, tri;
    double x, y;       /* page coordinates (texels) */
    float p[3], n[3];  /* world point and shading normal */
} ev_pt;

/* Bilinear filtering of one page plane at page coordinates (x, y). */
static double filtered(const float *plane, int w, int h, double x, double y)
{
    int32_t idx[4];
    double wt[4], v = 0;
    bk_bilinear_taps(x, y, w, h, idx, wt);
    for (int k = 0; k < 4; k++) v += wt[k] * plane[idx[k]];
    return v;
}

/* Bakes every texel once (the ring texels as points, the others over their footprints) into
 * irr (3 per texel); returns the transport's result. */
static lbk_result bake_texels(const bk_scene *s, const bk_tracer *t, const bk_texels *tx, double density, int passes,
                              int threads, float *irr, bk_transport_stats *st, size_t *rings)
{
    bk_receiver *r = calloc(tx->count, sizeof *r);
    *rings = 0;
    for (size_t i = 0; i < tx->count; i++) {
        const bk_texel *x = &tx->receivers[i];
        bk_receiver_from_texel(x, &r[i]);
        *rings += (x->flags & BK_TEXEL_RING) != 0;
    }
    float *cell = malloc(s->tri_count * sizeof *cell);
    for (size_t i = 0; i < s->tri_count; i++) cell[i] = (float)(1.0 / density);
    lbk_sh9_rgb *rad = calloc(tx->count, sizeof *rad);
    bk_transport_options o;
    memset(&o, 0, sizeof o);
    o.seed = 3;
    o.threads = threads;
    o.target_error = -1;
    o.first_pass_samples = 16;
    o.max_samples = 2 * 16 * ((1 << passes) - 1);
    o.cell_size = cell;
    o.footprint = tx->footprint;
    o.footprint_count = tx->footprint_count;
    bk_transport_output out = {rad, NULL, irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    lbk_result res = bk_transport_run(s, t, r, tx->count, &o, &out, st);
    free(rad), free(r), free(cell);
    return res;
}

/* Per page, the luminance planes of both candidates: point (every texel as baked) and dilate
 * (the ring left empty, filled by bk_dilate). */
static void candidate_planes(const bk_texels *tx, const float *irr, int margin, float **pl_point, float **pl_dil)
{
    for (size_t p = 0; p < tx->page_count; p++) {
        int w = tx->pages[p].width, h = tx->pages[p].height;
        size_t n = (size_t)w * (size_t)h;
        pl_point[p] = calloc(n, sizeof(float));
        pl_dil[p] = calloc(n, sizeof(float));
        uint8_t *mask = calloc(n, 1), *mask2 = calloc(n, 1);
        for (size_t i = 0; i < n; i++) {
            int32_t ri = tx->index[tx->page_offset[p] + i];
            if (ri < 0) continue;
            float v = (float)lum3f(irr + 3 * (size_t)ri);
            pl_point[p][i] = v;
            mask2[i] = 1;
            if (!(tx->receivers[ri].flags & BK_TEXEL_RING)) { /* dilate: the ring left empty */
                pl_dil[p][i] = v;
                mask[i] = 1;
            }
        }
        bk_dilate(pl_dil[p], 1, mask, w, h, margin + 2);
        bk_dilate(pl_point[p], 1, mask2, w, h, margin + 2);
        free(mask);
        free(mask2);
    }
}

/* The world point and normal of triangle tri at barycentrics (1 − a − b, a, b). */
static void world_point(const bk_scene *s, uint32_t tri, double a, double b, float p[3], float n[3])
{
    const uint32_t *ix = s->tris + 3 * (size_t)tri;
    double wb[3] = {1 - a - b, a, b}, nn = 0;
    for (int d = 0; d < 3; d++) {
        double pp = 0, nv = 0;
        for (int m = 0; m < 3; m++) {
            pp += wb[m] * s->positions[3 * (size_t)ix[m] + d];
            nv += wb[m] * s->normals[3 * (size_t)ix[m] + d];
        }
        p[d] = (float)pp;
        n[d] = (float)nv;
        nn += nv * nv;
    }
    for (int d = 0; d < 3; d++) n[d] = (float)(n[d] / sqrt(nn));
}

/* Candidate points: uniform over the chart triangles (one per 0.25 texel² of uv area), those whose
 * bilinear taps include a ring texel and that lie in the room's air; *count of them. */
static ev_pt *ring_points(const bk_scene *s, const bk_atlas *at, const bk_texels *tx, size_t *count)
{
    size_t cap = 1024, n = 0;
    ev_pt *ev = malloc(cap * sizeof *ev);
    uint64_t rng = 0x9E3779B97F4A7C15ull;
    for (size_t c = 0; c < at->chart_count; c++) {
        const bk_atlas_chart *ch = &at->charts[c];
        if (ch->page < 0) continue;
        int w = tx->pages[ch->page].width, h = tx->pages[ch->page].height;
        for (uint32_t e = ch->first; e < ch->first + ch->count; e++) {
            const float *uv = at->tri_uv + 6 * (size_t)e;
            double area = 0.5 * fabs((uv[2] - uv[0]) * (uv[5] - uv[1]) - (uv[4] - uv[0]) * (uv[3] - uv[1]));
            int k = (int)ceil(area * 4);
            for (int q = 0; q < k; q++) {
                double a = rp_uniform(&rng), b = rp_uniform(&rng);
                if (a + b > 1) { a = 1 - a; b = 1 - b; }
                double x = uv[0] + a * (uv[2] - uv[0]) + b * (uv[4] - uv[0]);
                double y = uv[1] + a * (uv[3] - uv[1]) + b * (uv[5] - uv[1]);
                int32_t idx[4];
                double wt[4];
                bk_bilinear_taps(x, y, w, h, idx, wt);
                int ring = 0;
                for (int j = 0; j < 4; j++) {
                    int32_t ri = tx->index[tx->page_offset[ch->page] + (size_t)idx[j]];
                    if (wt[j] > 0 && ri >= 0 && (tx->receivers[ri].flags & BK_TEXEL_RING)) ring = 1;
                }
                if (!ring) continue;
                ev_pt v;
                v.page = (uint32_t)ch->page;
                v.tri = at->tris[e];
                v.x = x;
                v.y = y;
                world_point(s, v.tri, a, b, v.p, v.n);
                int g = bsc_group(s, v.tri, v.p, v.n);
                if (g == BSC_OUTSIDE || g == BSC_SEALED || bsc_solid_depth(v.p) > 0) continue;
                if (n == cap) ev = realloc(ev, (cap *= 2) * sizeof *ev);
                ev[n++] = v;
            }
        }
    }
    *count = n;
    return ev;
}

int main(int argc, char **argv)
{
    double density = 6;
    int passes = 5, want = 400, ref_paths = 4096, threads = 2;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--density")) density = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--passes")) passes = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--points")) want = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--ref-paths")) ref_paths = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--threads")) threads = atoi(argv[i + 1]);
        else { fprintf(stderr, "unknown argument %s\n", argv[i]); return 2; }
    }
    bk_scene s;
    bsc_build(&s, NULL);
    bk_atlas at;
    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.default_density = (float)density;
    bk_tracer *t = NULL;
    bk_texels tx;
    if (bk_atlas_build(&s, NULL, &ao, &at) != LBK_OK || bk_tracer_create(&s, 0, &t) != LBK_OK ||
        bk_texels_build(&s, &at, &tx) != LBK_OK) {
        fprintf(stderr, "setup failed\n");
        return 1;
    }
    bk_pushout_options po;
    memset(&po, 0, sizeof po);
    po.threads = threads;
    bk_texels_push_out(&tx, &s, t, &po, NULL);
    float *irr = calloc(3 * tx.count, sizeof *irr);
    bk_transport_stats st;
    size_t rings = 0;
    if (bake_texels(&s, t, &tx, density, passes, threads, irr, &st, &rings) != LBK_OK) {
        fprintf(stderr, "transport failed\n");
        return 1;
    }
    float **pl_point = calloc(tx.page_count, sizeof *pl_point), **pl_dil = calloc(tx.page_count, sizeof *pl_dil);
    candidate_planes(&tx, irr, at.margin, pl_point, pl_dil);
    size_t n = 0;
    ev_pt *ev = ring_points(&s, &at, &tx, &n);
    /* an even subset of `want` points */
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if ((i + 1) * (size_t)want / n > m) ev[m++] = ev[i];
    float *pp = malloc(3 * m * sizeof *pp), *nn = malloc(3 * m * sizeof *nn);
    for (size_t i = 0; i < m; i++) {
        memcpy(pp + 3 * i, ev[i].p, 12);
        memcpy(nn + 3 * i, ev[i].n, 12);
    }
    double *ref = calloc(3 * m, sizeof *ref), *se = calloc(m, sizeof *se);
    rp_irradiance(&s, t, pp, nn, m, ref_paths, 17, threads, ref, se);
    double d2[2] = {0, 0}, sg[2] = {0, 0}, r2 = 0, rs = 0, z2 = 0;
    for (size_t i = 0; i < m; i++) {
        int w = tx.pages[ev[i].page].width, h = tx.pages[ev[i].page].height;
        double b = lum3d(ref + 3 * i);
        double va[2] = {filtered(pl_point[ev[i].page], w, h, ev[i].x, ev[i].y),
                        filtered(pl_dil[ev[i].page], w, h, ev[i].x, ev[i].y)};
        for (int k = 0; k < 2; k++) {
            d2[k] += (va[k] - b) * (va[k] - b);
            sg[k] += va[k] - b;
        }
        r2 += b * b;
        rs += b;
        z2 += se[i] * se[i];
    }
    printf("bias room at %g texels/m: %zu texels, %zu ring; %.0f samples/receiver; %zu of %zu chart points "
           "that read a ring texel, %d reference paths each (reference noise %.2f %%)\n",
           density, tx.count, rings, st.samples_per_receiver, m, n, ref_paths, 100 * sqrt(z2 / r2));
    const char *name[2] = {"point (bake at its closest chart point)", "dilate (fill from its chart's texels)"};
    for (int k = 0; k < 2; k++)
        printf("  %-42s filtered rel. RMSE %6.2f %%  signed %+6.2f %%\n", name[k], 100 * sqrt(d2[k] / r2),
               100 * sg[k] / rs);
    for (size_t p = 0; p < tx.page_count; p++) free(pl_point[p]), free(pl_dil[p]);
    free(pl_point), free(pl_dil), free(ev), free(pp), free(nn), free(ref), free(se);
    free(irr);
    bk_texels_free(&tx);
    bk_tracer_destroy(t);
    bk_atlas_free(&at);
    bk_scene_free(&s);
    return 0;
}
