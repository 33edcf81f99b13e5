/* The OCTP probe volume: grid placement, classification and relocation, depth moments. */
#include "bake/probes/octa_bake.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define OCTA_PI 3.14159265358979323846
#define OCTA_MOVES 3

static int double_sided(const bk_scene *s, uint32_t tri)
{
    if (!s->tri_material || !s->materials) return 0;
    uint32_t m = s->tri_material[tri];
    return m < s->material_count ? s->materials[m].double_sided : 0;
}

/* Ray k of n spherical Fibonacci directions. */
static void fib_dir(int k, int n, float d[3])
{
    const double z = 1.0 - (2.0 * k + 1.0) / n, r = sqrt(fmax(0.0, 1.0 - z * z));
    const double phi = k * OCTA_PI * (3.0 - sqrt(5.0)) + 0.5;
    d[0] = (float)(r * cos(phi));
    d[1] = (float)(r * sin(phi));
    d[2] = (float)z;
}

typedef struct octa_probe_rays {
    int back;
    float nearest_front, nearest_back, nearest;
    float front_dir[3], back_dir[3];
} octa_probe_rays;

static void classify(const bk_scene *s, const bk_tracer *t, const float p[3], float tmax, octa_probe_rays *o)
{
    memset(o, 0, sizeof *o);
    o->nearest_front = o->nearest_back = o->nearest = tmax;
    for (int k = 0; k < BK_OCTA_CLASSIFY_RAYS; k++) {
        float d[3];
        fib_dir(k, BK_OCTA_CLASSIFY_RAYS, d);
        bk_hit h;
        if (!bk_tracer_intersect(t, p, d, 0.0f, tmax, &h)) continue;
        if (h.t < o->nearest) o->nearest = h.t;
        if (h.front || double_sided(s, h.tri)) {
            if (h.t < o->nearest_front) o->nearest_front = h.t, memcpy(o->front_dir, d, sizeof d);
        } else {
            o->back++;
            if (h.t < o->nearest_back) o->nearest_back = h.t, memcpy(o->back_dir, d, sizeof d);
        }
    }
}

/* Adds step·dir to the offset; false when an axis would pass the bound. */
static int move(float off[3], const float dir[3], float step, float bound)
{
    float n[3];
    for (int a = 0; a < 3; a++) {
        n[a] = off[a] + step * dir[a];
        if (!(fabsf(n[a]) <= bound)) return 0;
    }
    memcpy(off, n, sizeof n);
    return 1;
}

static void place_probe(const bk_scene *s, const bk_tracer *t, const float g[3], float spacing, float miss,
                        float pos[3], lbk_octp_probe_info *in)
{
    const float clear = 0.1f * spacing, bound = 0.45f * spacing;
    float off[3] = {0, 0, 0};
    octa_probe_rays r;
    int inside = 1;
    for (int m = 0; m <= OCTA_MOVES; m++) {
        float p[3] = {g[0] + off[0], g[1] + off[1], g[2] + off[2]};
        classify(s, t, p, miss, &r);
        inside = (float)r.back > BK_OCTA_INSIDE_FRACTION * BK_OCTA_CLASSIFY_RAYS;
        if (m == OCTA_MOVES) break;
        if (inside) {
            if (!move(off, r.back_dir, r.nearest_back + clear, bound)) break;
        } else if (r.nearest_front < clear) {
            if (!move(off, r.front_dir, r.nearest_front - clear, bound)) break; /* negative: away */
        } else {
            break;
        }
    }
    memset(in, 0, sizeof *in);
    in->backface = (float)r.back / BK_OCTA_CLASSIFY_RAYS;
    in->nearest = r.nearest;
    if (inside) {
        in->state = LBK_OCTP_INSIDE;
        memcpy(pos, g, 3 * sizeof(float));
        return;
    }
    memcpy(in->offset, off, sizeof off);
    in->state = r.nearest > spacing * 1.7320508f ? LBK_OCTP_NO_NEARBY : LBK_OCTP_ACTIVE;
    for (int a = 0; a < 3; a++) pos[a] = g[a] + off[a];
}

/* Dims per axis over a box of extent e at spacing s: max(2, ceil(e/s)), clip + 1 when it does
 * not fit in clip; the probe count (or UINT64_MAX when an axis does not fit). */
static uint64_t grid_dims(const float e[3], float s, uint32_t clip, uint32_t dims[3])
{
    uint64_t n = 1;
    for (int a = 0; a < 3; a++) {
        double d = ceil((double)e[a] / s); /* outermost probes half a spacing inside */
        if (!(d >= 2)) d = 2;
        dims[a] = d > clip ? clip + 1 : (uint32_t)d;
        n *= dims[a];
    }
    return dims[0] > clip || dims[1] > clip || dims[2] > clip ? UINT64_MAX : n;
}

/* The grid of one level centred in [lo, hi] at spacing s, miss distance from its diagonal. */
static void level_grid(lbk_octp_level *l, const float lo[3], const float hi[3], float s)
{
    double diag = 0;
    for (int a = 0; a < 3; a++) {
        l->origin[a] = 0.5f * (lo[a] + hi[a]) - 0.5f * s * (float)(l->dims[a] - 1);
        diag += (double)(s * (float)(l->dims[a] - 1)) * (s * (float)(l->dims[a] - 1));
    }
    l->spacing = s;
    l->miss_distance = (float)fmin(sqrt(diag), LBK_OCTP_MAX_MISS);
}

/* The clip levels (bk_octa_place's rule), first_probe set; returns the level count. */
static uint32_t plan_levels(const float bmin[3], const float bmax[3], const bk_octa_options *o, lbk_octp_level *lv)
{
    const float s0 = o && o->spacing > 0 ? o->spacing : 1.0f;
    const uint32_t cap = o && o->max_probes ? o->max_probes : 32768u;
    const uint32_t maxl = o && o->levels >= 1 && o->levels <= LBK_OCTP_MAX_LEVELS ? o->levels : LBK_OCTP_MAX_LEVELS;
    const uint32_t clip = o && o->clip >= 2 && o->clip <= BK_OCTA_CLIP ? o->clip : BK_OCTA_CLIP;
    float c[3], ext[3];
    for (int a = 0; a < 3; a++) {
        c[a] = 0.5f * (bmin[a] + bmax[a]);
        if (o && o->has_centre && isfinite(o->centre[a])) c[a] = fminf(fmaxf(o->centre[a], bmin[a]), bmax[a]);
        ext[a] = bmax[a] - bmin[a];
    }
    uint32_t L = 0, first = 0;
    float s = s0;
    for (; L + 1 < maxl; L++, s *= 2) {
        lbk_octp_level *l = &lv[L];
        memset(l, 0, sizeof *l);
        const uint64_t whole = grid_dims(ext, s, clip, l->dims);
        if (whole <= cap) break; /* this level holds the whole bounds: the last one */
        float lo[3], hi[3], e[3];
        for (int a = 0; a < 3; a++) {
            const float half = 0.5f * s * (float)clip;
            lo[a] = fmaxf(bmin[a], c[a] - half);
            hi[a] = fminf(bmax[a], c[a] + half);
            e[a] = hi[a] - lo[a];
        }
        grid_dims(e, s, clip, l->dims);
        for (int a = 0; a < 3; a++)
            if (l->dims[a] > clip) l->dims[a] = clip; /* rounding of c ± half */
        level_grid(l, lo, hi, s);
        l->first_probe = first;
        first += l->dims[0] * l->dims[1] * l->dims[2];
    }
    lbk_octp_level *l = &lv[L];
    memset(l, 0, sizeof *l);
    while (grid_dims(ext, s, clip, l->dims) > cap) s *= 1.25f;
    level_grid(l, bmin, bmax, s);
    l->first_probe = first;
    return L + 1;
}

lbk_result bk_octa_place(const bk_scene *scene, const bk_tracer *tracer, const float bmin[3], const float bmax[3],
                         const bk_octa_options *options, bk_octa_volume *out)
{
    memset(out, 0, sizeof *out);
    out->level_count = plan_levels(bmin, bmax, options, out->levels);
    const lbk_octp_level *last = &out->levels[out->level_count - 1];
    out->count = last->first_probe + last->dims[0] * last->dims[1] * last->dims[2];
    out->positions = malloc((size_t)out->count * 3 * sizeof(float));
    out->info = calloc(out->count, sizeof *out->info);
    if (!out->positions || !out->info) {
        bk_octa_volume_free(out);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (uint32_t i = 0; i < out->count; i++) {
        const lbk_octp_level *l = &out->levels[bk_octa_probe_level(out, i)];
        const uint32_t k = i - l->first_probe;
        const uint32_t c[3] = {k % l->dims[0], k / l->dims[0] % l->dims[1], k / l->dims[0] / l->dims[1]};
        float g[3];
        for (int a = 0; a < 3; a++) g[a] = l->origin[a] + l->spacing * (float)c[a];
        place_probe(scene, tracer, g, l->spacing, l->miss_distance, &out->positions[3 * i], &out->info[i]);
    }
    return LBK_OK;
}

uint32_t bk_octa_probe_level(const bk_octa_volume *v, uint32_t i)
{
    uint32_t l = 0;
    while (l + 1 < v->level_count && i >= v->levels[l + 1].first_probe) l++;
    return l;
}

void bk_octa_volume_free(bk_octa_volume *v)
{
    free(v->positions);
    free(v->info);
    memset(v, 0, sizeof *v);
}

void bk_octa_depth(const bk_tracer *tracer, const float p[3], float miss, float depth[12 * 12][2])
{
    const int K = BK_OCTA_DEPTH_SIDE, n = (int)LBK_OCTP_DEPTH_N;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double m1 = 0, m2 = 0;
            for (int s = 0; s < K * K; s++) {
                const float uv[2] = {((float)i + ((float)(s % K) + 0.5f) / (float)K) / (float)n * 2 - 1,
                                     ((float)j + ((float)(s / K) + 0.5f) / (float)K) / (float)n * 2 - 1};
                float dir[3];
                lbk_oct_decode(uv, dir);
                bk_hit hit;
                float d = miss;
                if (bk_tracer_intersect(tracer, p, dir, 0.0f, miss, &hit) && hit.t < d) d = hit.t;
                m1 += d;
                m2 += (double)d * d;
            }
            depth[j * n + i][0] = (float)(m1 / (K * K));
            depth[j * n + i][1] = (float)(m2 / (K * K));
        }
}
