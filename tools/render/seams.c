/* Chart-boundary mask of a rendered view (see seams.h). */
#include "tools/render/seams.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

rl_gbuffer *rl_gbuffer_create(size_t n)
{
    rl_gbuffer *g = calloc(1, sizeof *g);
    if (g && (!(g->hit = calloc(n + 1, sizeof *g->hit)) || !(g->valid = calloc(n + 1, 1)))) rl_gbuffer_free(g), g = NULL;
    return g;
}

void rl_gbuffer_free(rl_gbuffer *g)
{
    if (!g) return;
    free(g->hit), free(g->valid), free(g);
}

static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

typedef struct tri_frame {
    float p0[3], e1[3], e2[3], n[3]; /* corner 0, edges, unit normal */
    float c[3][2];                    /* corner lightmap coordinates */
} tri_frame;

static void frame_of(const rl_level *L, uint32_t tri, tri_frame *f)
{
    const bk_scene *s = &L->scene;
    const float *p[3];
    for (int c = 0; c < 3; c++) {
        p[c] = &s->positions[3 * (size_t)s->tris[3 * (size_t)tri + c]];
        memcpy(f->c[c], &L->corner_coord[6 * (size_t)tri + 2 * c], sizeof f->c[c]);
    }
    for (int k = 0; k < 3; k++) f->p0[k] = p[0][k], f->e1[k] = p[1][k] - p[0][k], f->e2[k] = p[2][k] - p[0][k];
    f->n[0] = f->e1[1] * f->e2[2] - f->e1[2] * f->e2[1];
    f->n[1] = f->e1[2] * f->e2[0] - f->e1[0] * f->e2[2];
    f->n[2] = f->e1[0] * f->e2[1] - f->e1[1] * f->e2[0];
    const float l = sqrtf(dot3(f->n, f->n));
    for (int k = 0; k < 3; k++) f->n[k] = l > 0 ? f->n[k] / l : 0.0f;
}

/* The triangle's lightmap mapping (affine over its plane) extrapolated to point q. */
static void extrapolate(const tri_frame *f, const float q[3], float out[2])
{
    const float d[3] = {q[0] - f->p0[0], q[1] - f->p0[1], q[2] - f->p0[2]};
    const double a = dot3(f->e1, f->e1), b = dot3(f->e1, f->e2), c = dot3(f->e2, f->e2);
    const double r1 = dot3(f->e1, d), r2 = dot3(f->e2, d), det = a * c - b * b;
    const double b1 = det != 0 ? (c * r1 - b * r2) / det : 0, b2 = det != 0 ? (a * r2 - b * r1) / det : 0;
    for (int k = 0; k < 2; k++)
        out[k] = (float)(f->c[0][k] + b1 * (f->c[1][k] - f->c[0][k]) + b2 * (f->c[2][k] - f->c[0][k]));
}

static float plane_distance(const tri_frame *f, const float q[3])
{
    const float d[3] = {q[0] - f->p0[0], q[1] - f->p0[1], q[2] - f->p0[2]};
    return fabsf(dot3(d, f->n));
}

static int is_seam(const rl_level *L, const rl_hit *a, const rl_hit *b, float fa, float fb)
{
    uint32_t pa, pb;
    float ca[2], cb[2], pred[2];
    if (!rl_hit_coord(L, a, &pa, ca) || !rl_hit_coord(L, b, &pb, cb) || a->tri == b->tri) return 0;
    tri_frame ta, tb;
    frame_of(L, a->tri, &ta);
    frame_of(L, b->tri, &tb);
    if (plane_distance(&ta, b->p) > 2.0f * fa || plane_distance(&tb, a->p) > 2.0f * fb) return 0; /* occlusion edge */
    const int flat = dot3(ta.n, tb.n) > 0.9998f ? 2 : 0; /* within about 1°: the true image is smooth here */
    if (pa != pb) return 1 | flat;
    extrapolate(&ta, b->p, pred);
    return fabsf(pred[0] - cb[0]) > 1.0f || fabsf(pred[1] - cb[1]) > 1.0f ? 1 | flat : 0;
}

int rl_seams(const rl_gbuffer *g, const rl_level *L, int w, int h, float footprint, const float from[3], tl_image *out)
{
    const size_t np = (size_t)w * (size_t)h;
    out->seam = calloc(np + 1, 1);
    out->lightmapped = calloc(np + 1, 1);
    if (!out->seam || !out->lightmapped) return -1;
    float *fp = malloc((np + 1) * sizeof *fp); /* pixel footprint in metres at each hit */
    if (!fp) return -1;
    for (size_t i = 0; i < np; i++) {
        const float d[3] = {g->hit[i].p[0] - from[0], g->hit[i].p[1] - from[1], g->hit[i].p[2] - from[2]};
        fp[i] = footprint * sqrtf(dot3(d, d));
        uint32_t page;
        float c[2];
        out->lightmapped[i] = g->valid[i] && rl_hit_coord(L, &g->hit[i], &page, c);
    }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const size_t i = (size_t)y * (size_t)w + (size_t)x;
            if (!out->lightmapped[i]) continue;
            if (x + 1 < w && out->lightmapped[i + 1])
                out->seam[i] |= (unsigned char)(is_seam(L, &g->hit[i], &g->hit[i + 1], fp[i], fp[i + 1]) * 1);
            if (y + 1 < h && out->lightmapped[i + (size_t)w])
                out->seam[i] |= (unsigned char)(is_seam(L, &g->hit[i], &g->hit[i + (size_t)w], fp[i], fp[i + (size_t)w]) * 4);
        }
    free(fp);
    return 0;
}
