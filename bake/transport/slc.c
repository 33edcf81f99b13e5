/* Stochastic light culling: ranges, block lists, tile lists; see slc.h and SLC.md. */
#include "bake/transport/slc.h"

#include "scene/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct slc_light {
    double pos[3];
    double intensity; /* luminance of the colour: E·l² ≤ this everywhere (windows only lower it) */
    double range2;    /* the light's own range squared (INFINITY: none) */
} slc_light;

struct bk_slc {
    size_t count, items, blocks;
    slc_light *lights;
    uint32_t *always, always_count;
    uint32_t *positional, positional_count;
    float *tile_box;  /* 6 per tile */
    float *block_box; /* 6 per block */
};

struct bk_slc_draw {
    const bk_slc *s;
    double *xi;
    double *r2;        /* per light: the range squared, min(I/(δξ), range²) */
    uint32_t **list;   /* per block: its lights in index order */
    uint32_t *list_n;
    int failed;
};

static double lum_of(const float c[3])
{
    double v[3];
    for (int k = 0; k < 3; k++) v[k] = isfinite(c[k]) && c[k] > 0 ? c[k] : 0;
    return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
}

static void box_empty(float *b)
{
    for (int a = 0; a < 3; a++) { b[a] = INFINITY; b[3 + a] = -INFINITY; }
}

static void box_add(float *b, const float *o)
{
    for (int a = 0; a < 3; a++) {
        if (o[a] < b[a]) b[a] = o[a];
        if (o[3 + a] > b[3 + a]) b[3 + a] = o[3 + a];
    }
}

/* The squared distance from p to box b (INFINITY for an empty box). */
static double box_dist2(const float *b, const double p[3])
{
    double d2 = 0;
    for (int a = 0; a < 3; a++) {
        if (!(b[a] <= b[3 + a])) return INFINITY;
        double lo = b[a], hi = b[3 + a];
        double d = p[a] < lo ? lo - p[a] : p[a] > hi ? p[a] - hi : 0;
        d2 += d * d;
    }
    return d2;
}

lbk_result bk_slc_create(const bk_light *const *lights, size_t count, const float *boxes, size_t items, bk_slc **out)
{
    if (!out || (count && !lights) || (items && !boxes) || count > UINT32_MAX) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    bk_slc *s = calloc(1, sizeof *s);
    if (!s) return LBK_ERR_OUT_OF_MEMORY;
    s->count = count;
    s->items = items;
    size_t tiles = (items + BK_SLC_TILE - 1) / BK_SLC_TILE;
    s->blocks = (items + BK_SLC_BLOCK - 1) / BK_SLC_BLOCK;
    s->lights = calloc(count ? count : 1, sizeof *s->lights);
    s->always = calloc(count ? count : 1, sizeof *s->always);
    s->positional = calloc(count ? count : 1, sizeof *s->positional);
    s->tile_box = malloc((tiles ? tiles : 1) * 6 * sizeof(float));
    s->block_box = malloc((s->blocks ? s->blocks : 1) * 6 * sizeof(float));
    if (!s->lights || !s->always || !s->positional || !s->tile_box || !s->block_box) {
        bk_slc_destroy(s);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < count; i++) {
        const bk_light *l = lights[i];
        slc_light *q = &s->lights[i];
        for (int a = 0; a < 3; a++) q->pos[a] = l->position[a];
        q->intensity = lum_of(l->color);
        q->range2 = l->range > 0 && isfinite(l->range) ? (double)l->range * l->range : INFINITY;
        int finite = isfinite(q->pos[0]) && isfinite(q->pos[1]) && isfinite(q->pos[2]);
        if (l->type == BK_LIGHT_DIRECTIONAL || !finite) s->always[s->always_count++] = (uint32_t)i;
        else s->positional[s->positional_count++] = (uint32_t)i;
    }
    for (size_t t = 0; t < tiles; t++) {
        float *b = s->tile_box + 6 * t;
        box_empty(b);
        size_t e = (t + 1) * BK_SLC_TILE < items ? (t + 1) * BK_SLC_TILE : items;
        for (size_t i = t * BK_SLC_TILE; i < e; i++) box_add(b, boxes + 6 * i);
    }
    for (size_t k = 0; k < s->blocks; k++) {
        float *b = s->block_box + 6 * k;
        box_empty(b);
        size_t t0 = k * (BK_SLC_BLOCK / BK_SLC_TILE), t1 = t0 + BK_SLC_BLOCK / BK_SLC_TILE;
        for (size_t t = t0; t < t1 && t < tiles; t++) box_add(b, s->tile_box + 6 * t);
    }
    *out = s;
    return LBK_OK;
}

void bk_slc_destroy(bk_slc *s)
{
    if (!s) return;
    free(s->lights);
    free(s->always);
    free(s->positional);
    free(s->tile_box);
    free(s->block_box);
    free(s);
}

size_t bk_slc_always(const bk_slc *s, const uint32_t **ids)
{
    *ids = s->always;
    return s->always_count;
}

size_t bk_slc_light_count(const bk_slc *s) { return s->count; }
size_t bk_slc_item_count(const bk_slc *s) { return s->items; }
size_t bk_slc_tile_count(const bk_slc *s) { return (s->items + BK_SLC_TILE - 1) / BK_SLC_TILE; }
size_t bk_slc_block_count(const bk_slc *s) { return s->blocks; }
const float *bk_slc_tile_box(const bk_slc *s, size_t tile) { return s->tile_box + 6 * tile; }
const float *bk_slc_block_box(const bk_slc *s, size_t block) { return s->block_box + 6 * block; }

double bk_slc_draw_xi(const bk_slc_draw *d, uint32_t light) { return d->xi[light]; }

/* A light reaches a box when the box comes within its range. The range is inflated by 1e-6
 * relative (and the test is in double) so that rounding never culls a light that the exact
 * point test would accept: the box holds every shaded point, so culling stays unbiased. */
static int reaches(const bk_slc_draw *d, uint32_t li, const float *box)
{
    return box_dist2(box, d->s->lights[li].pos) <= d->r2[li];
}

static void block_lists(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    bk_slc_draw *d = (bk_slc_draw *)user;
    const bk_slc *s = d->s;
    for (size_t k = begin; k < end; k++) {
        const float *box = s->block_box + 6 * k;
        uint32_t n = 0;
        for (uint32_t j = 0; j < s->positional_count; j++)
            n += (uint32_t)reaches(d, s->positional[j], box);
        d->list_n[k] = n;
        if (!n) continue;
        d->list[k] = malloc(n * sizeof(uint32_t));
        if (!d->list[k]) continue; /* list_n > 0 without a list: out of memory, seen after the loop */
        n = 0;
        for (uint32_t j = 0; j < s->positional_count; j++)
            if (reaches(d, s->positional[j], box)) d->list[k][n++] = s->positional[j];
    }
}

lbk_result bk_slc_draw_create(const bk_slc *s, const double *xi, double delta, int threads, bk_slc_draw **out)
{
    if (!s || !xi || !out || !(delta > 0)) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    bk_slc_draw *d = calloc(1, sizeof *d);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    d->s = s;
    size_t n = s->count ? s->count : 1, nb = s->blocks ? s->blocks : 1;
    d->xi = malloc(n * sizeof *d->xi);
    d->r2 = malloc(n * sizeof *d->r2);
    d->list = calloc(nb, sizeof *d->list);
    d->list_n = calloc(nb, sizeof *d->list_n);
    if (!d->xi || !d->r2 || !d->list || !d->list_n) {
        bk_slc_draw_destroy(d);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < s->count; i++) {
        d->xi[i] = xi[i];
        /* accepted ⇔ ξ < E/δ with E ≤ I/l²  ⇒  l² < I/(δξ) */
        double r2 = xi[i] > 0 ? s->lights[i].intensity / (delta * xi[i]) : INFINITY;
        r2 *= 1 + 1e-6;
        d->r2[i] = r2 < s->lights[i].range2 ? r2 : s->lights[i].range2;
    }
    bk_parallel_chunks(0, s->blocks, 1, threads, block_lists, d);
    for (size_t k = 0; k < s->blocks; k++)
        if (d->list_n[k] && !d->list[k]) d->failed = 1;
    if (d->failed) {
        bk_slc_draw_destroy(d);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    *out = d;
    return LBK_OK;
}

void bk_slc_draw_destroy(bk_slc_draw *d)
{
    if (!d) return;
    if (d->list)
        for (size_t k = 0; k < d->s->blocks; k++) free(d->list[k]);
    free(d->list);
    free(d->list_n);
    free(d->xi);
    free(d->r2);
    free(d);
}

size_t bk_slc_tile_lights(const bk_slc_draw *d, size_t item, uint32_t *ids)
{
    const bk_slc *s = d->s;
    if (item >= s->items) return 0;
    const size_t k = item / BK_SLC_BLOCK;
    const float *box = s->tile_box + 6 * (item / BK_SLC_TILE);
    size_t n = 0;
    for (uint32_t j = 0; j < d->list_n[k]; j++)
        if (reaches(d, d->list[k][j], box)) ids[n++] = d->list[k][j];
    return n;
}
