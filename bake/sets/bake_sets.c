/* Dynamic light sets and doors in the bake (seed 001 §3–§4, §6.2). Method, thresholds and what
 * is left of the seed's door sampling: bake/sets/SETS.md.
 *
 * Sets written, in this order (the DLS set index order):
 *   1. light sets (kind 0), sorted by name: lights and emissive objects with lbk_light_set;
 *   2. per door, sorted by name: "door/<name>/open" (kind 1, S_O) and "door/<name>/closed"
 *      (kind 2, S_C). Objects sharing an lbk_door name form one door;
 *   3. per authored combination state (scene extras lbk_combinations), in authored order:
 *      "combo/<a>+<b>" (kind 3, the pair's extra light, weight = product of the members').
 * Every set bake uses the base bake's receivers; contributions are differences or separate runs
 * of the same transport code (bake/transport/transport.h). */
#include "bake/sets/bake_sets.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/sets/door_guided.h"
#include "scene/clock.h"
#include "bake/encode/encode.h"
#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"

#define BS_DEFAULT_THRESHOLD 0.01
#define BS_PI 3.14159265358979323846

typedef struct bs_set {
    char name[144];
    uint32_t kind;                 /* lbk_dls_set_kind */
    int door;                      /* kinds 1/2: door index; else -1 */
    int zero;                      /* light set whose lights and emitters are all black */
    const char **light_names;      /* pointers into the scene */
    uint32_t light_count;
    /* results */
    uint64_t count[LBK_DLS_SPACE_COUNT_];
    uint32_t *targets[LBK_DLS_SPACE_COUNT_];
    /* physical values, encoded with the base section's scale in bk_set_bakes_sections (the scale
     * depends on every set, spec §12.2): texels lbk_ahd_linear, probes lbk_sh9_rgb */
    uint8_t *values[LBK_DLS_SPACE_COUNT_];
    double threshold;              /* absolute luminance threshold used (lux) */
    uint32_t members[2];           /* kind 3: the member sets */
    uint32_t member_count;
    /* the contribution kept from its run until bk_set_bakes_emit (the denoiser's weights need
     * every set first): radiance per receiver, direct luminance per texel receiver */
    lbk_sh9_rgb *stash;
    double *stash_direct;
    float *stash_halves;           /* its two half estimates, 2 per receiver (NULL: none known) */
    double stash_fraction;
    int stash_skip_doors;
} bs_set;

typedef struct bs_door {
    char name[64];
    float centre[3], axes[3][3], half[3];
    uint32_t open_set, closed_set;
} bs_door;

/* A combination state: two doors, or a door and a light set (seed §6.2). */
typedef struct bs_combo {
    int door[2];                   /* door indices, ascending; door[1] = -1 with a light set */
    int light_set;                 /* light set index or -1 */
    uint32_t set;
} bs_combo;

typedef struct bs_impl {
    bs_set *sets;
    size_t set_count;
    bs_door *doors;
    size_t door_count;
    size_t light_set_count;
    bs_combo *combos;
    size_t combo_count;
    /* the denoiser's guide (bake/denoise/DENOISE.md): Σ of the light sets' and doors'
     * contributions, and Σ of the light-set runs' variances (independent runs); NULL before any */
    lbk_sh9_rgb *guide;
    float *guide_var;
    bk_set_run_error *run_errors; /* every transport run's estimate, in order */
    size_t run_error_count;
    bk_set_estimate *estimates;   /* every stored set's, by bk_set_bakes_emit */
    size_t estimate_count;
} bs_impl;

/* ---- prepare --------------------------------------------------------------------------- */

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* Distinct non-empty names, sorted; returns the count. names has room for n. */
static size_t unique_sorted(const char **names, size_t n)
{
    if (!n) return 0;
    qsort(names, n, sizeof *names, cmp_str);
    size_t k = 1;
    for (size_t i = 1; i < n; i++)
        if (strcmp(names[i], names[k - 1])) names[k++] = names[i];
    return k;
}

static int object_emits(const bk_scene *s, const bk_object *o)
{
    for (uint32_t t = 0; t < o->tri_count; t++) {
        size_t tri = (size_t)o->first_tri + t;
        uint32_t m = s->tri_material ? s->tri_material[tri] : 0;
        if (m >= s->material_count) continue;
        const float *e = s->materials[m].emission;
        if (e[0] > 0 || e[1] > 0 || e[2] > 0) return 1;
    }
    return 0;
}

/* OBB of a door: the axes of its first object's node frame (orthonormalised; world axes when
 * the frame is degenerate), extents over every vertex of the door's objects. */
static void door_obb(const bk_scene *s, const char *door, bs_door *d)
{
    float ax[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (size_t i = 0; i < s->object_count; i++) {
        if (strcmp(s->objects[i].door, door)) continue;
        const float *m = s->objects[i].local_to_world;
        double a[3][3];
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++) a[c][k] = m[4 * c + k];
        int ok = 1;
        for (int c = 0; c < 3 && ok; c++) {
            for (int p = 0; p < c; p++) {
                double dot = a[c][0] * a[p][0] + a[c][1] * a[p][1] + a[c][2] * a[p][2];
                for (int k = 0; k < 3; k++) a[c][k] -= dot * a[p][k];
            }
            double l = sqrt(a[c][0] * a[c][0] + a[c][1] * a[c][1] + a[c][2] * a[c][2]);
            if (!(l > 1e-12) || !isfinite(l)) ok = 0;
            else
                for (int k = 0; k < 3; k++) a[c][k] /= l;
        }
        if (ok)
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 3; k++) ax[c][k] = (float)a[c][k];
        break;
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->object_count; i++) {
        const bk_object *o = &s->objects[i];
        if (strcmp(o->door, door)) continue;
        for (uint32_t t = 0; t < o->tri_count; t++)
            for (int c = 0; c < 3; c++) {
                uint32_t v = s->tris[3 * ((size_t)o->first_tri + t) + c];
                if (v >= s->vertex_count) continue;
                const float *p = &s->positions[3 * (size_t)v];
                for (int a = 0; a < 3; a++) {
                    double q = (double)p[0] * ax[a][0] + (double)p[1] * ax[a][1] + (double)p[2] * ax[a][2];
                    lo[a] = fmin(lo[a], q), hi[a] = fmax(hi[a], q);
                }
            }
    }
    memset(d->centre, 0, sizeof d->centre);
    for (int a = 0; a < 3; a++) {
        if (!(hi[a] >= lo[a])) lo[a] = hi[a] = 0;
        double mid = 0.5 * (lo[a] + hi[a]);
        d->half[a] = (float)(0.5 * (hi[a] - lo[a]));
        for (int k = 0; k < 3; k++) d->centre[k] += (float)(mid * ax[a][k]);
    }
    memcpy(d->axes, ax, sizeof ax);
}

/* Light set j of the `k` sorted names: its lights and emissive objects (names point into the
 * scene), and whether any of them emits at all. */
static lbk_result fill_light_set(bs_set *st, const bk_scene *scene, const char *name)
{
    snprintf(st->name, sizeof st->name, "%s", name);
    st->kind = LBK_DLS_KIND_LIGHTS;
    st->door = -1;
    uint32_t lc = 0;
    int bright = 0;
    for (size_t i = 0; i < scene->light_count; i++)
        if (!strcmp(scene->lights[i].light_set, name)) lc++;
    for (size_t i = 0; i < scene->object_count; i++)
        if (!strcmp(scene->objects[i].light_set, name)) lc++;
    st->light_names = calloc(lc ? lc : 1, sizeof *st->light_names);
    if (!st->light_names) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < scene->light_count; i++) {
        const bk_light *l = &scene->lights[i];
        if (strcmp(l->light_set, name)) continue;
        st->light_names[st->light_count++] = l->name;
        if (l->color[0] > 0 || l->color[1] > 0 || l->color[2] > 0) bright = 1;
    }
    for (size_t i = 0; i < scene->object_count; i++) {
        const bk_object *o = &scene->objects[i];
        if (strcmp(o->light_set, name)) continue;
        st->light_names[st->light_count++] = o->name;
        if (object_emits(scene, o)) bright = 1;
    }
    st->zero = !bright;
    return LBK_OK;
}

/* Door p (sorted name `name`) and its open and closed sets, after the light sets. */
static lbk_result fill_door(bs_impl *im, const bk_scene *scene, size_t p, const char *name, char *err, size_t err_len)
{
    const size_t k = im->light_set_count;
    bs_door *d = &im->doors[p];
    snprintf(d->name, sizeof d->name, "%s", name);
    door_obb(scene, name, d);
    d->open_set = (uint32_t)(k + 2 * p);
    d->closed_set = (uint32_t)(k + 2 * p + 1);
    bs_set *so = &im->sets[d->open_set], *sc = &im->sets[d->closed_set];
    snprintf(so->name, sizeof so->name, "door/%s/open", name);
    snprintf(sc->name, sizeof sc->name, "door/%s/closed", name);
    so->kind = LBK_DLS_KIND_DOOR_OPEN;
    sc->kind = LBK_DLS_KIND_DOOR_CLOSED;
    so->door = sc->door = (int)p;
    for (size_t j = 0; j < k; j++)
        if (!strcmp(im->sets[j].name, so->name) || !strcmp(im->sets[j].name, sc->name)) {
            snprintf(err, err_len, "light set '%s' has the name lbk gives to door '%s': rename one", im->sets[j].name,
                     name);
            return LBK_ERR_BAD_INPUT;
        }
    return LBK_OK;
}

/* Member m of combination ci: a door (co->door) or a light set (co->light_set). */
static lbk_result combination_member(bs_impl *im, size_t ci, const char *nm, bs_combo *co, int *ndoor, char *err,
                                     size_t err_len)
{
    int door = -1, ls = -1;
    for (size_t p = 0; p < im->door_count; p++)
        if (!strcmp(im->doors[p].name, nm)) door = (int)p;
    for (size_t j = 0; j < im->light_set_count; j++)
        if (!strcmp(im->sets[j].name, nm)) ls = (int)j;
    if (door >= 0 && ls >= 0) {
        snprintf(err, err_len, "lbk_combinations[%zu]: '%s' names both a door and a light set: rename one", ci, nm);
        return LBK_ERR_BAD_INPUT;
    }
    if (door < 0 && ls < 0) {
        snprintf(err, err_len, "lbk_combinations[%zu]: '%s' is neither a door (lbk_door) nor a light set (lbk_light_set)",
                 ci, nm);
        return LBK_ERR_BAD_INPUT;
    }
    if (door >= 0) {
        co->door[(*ndoor)++] = door;
    } else if (co->light_set >= 0) {
        snprintf(err, err_len, "lbk_combinations[%zu]: two light sets add up linearly and have no combination "
                 "state; pair a light set with a door", ci);
        return LBK_ERR_BAD_INPUT;
    } else {
        co->light_set = ls;
    }
    return LBK_OK;
}

/* Combination state ci (seed §6.2) and its set, after the door sets. */
static lbk_result fill_combination(bs_impl *im, const bk_scene *scene, size_t ci, char *err, size_t err_len)
{
    const bk_combination *cb = &scene->combinations[ci];
    bs_combo *co = &im->combos[ci];
    co->door[0] = co->door[1] = co->light_set = -1;
    int ndoor = 0;
    for (int m = 0; m < 2; m++) {
        lbk_result r = combination_member(im, ci, cb->members[m], co, &ndoor, err, err_len);
        if (r) return r;
    }
    if (ndoor == 2 && co->door[0] == co->door[1]) {
        snprintf(err, err_len, "lbk_combinations[%zu]: door '%s' paired with itself", ci, cb->members[0]);
        return LBK_ERR_BAD_INPUT;
    }
    if (ndoor == 2 && co->door[0] > co->door[1]) {
        int t = co->door[0];
        co->door[0] = co->door[1], co->door[1] = t;
    }
    for (size_t cj = 0; cj < ci; cj++)
        if (im->combos[cj].door[0] == co->door[0] && im->combos[cj].door[1] == co->door[1] &&
            im->combos[cj].light_set == co->light_set) {
            snprintf(err, err_len, "lbk_combinations[%zu]: the same pair as lbk_combinations[%zu]", ci, cj);
            return LBK_ERR_BAD_INPUT;
        }
    co->set = (uint32_t)(im->light_set_count + 2 * im->door_count + ci);
    bs_set *st = &im->sets[co->set];
    snprintf(st->name, sizeof st->name, "combo/%s+%s", cb->members[0], cb->members[1]);
    st->kind = LBK_DLS_KIND_COMBINATION;
    st->door = -1;
    st->members[0] = im->doors[co->door[0]].open_set;
    st->members[1] = co->door[1] >= 0 ? im->doors[co->door[1]].open_set : (uint32_t)co->light_set;
    st->member_count = 2;
    for (size_t j = 0; j < im->light_set_count; j++)
        if (!strcmp(im->sets[j].name, st->name)) {
            snprintf(err, err_len, "light set '%s' has the name lbk gives to a combination state: rename it", st->name);
            return LBK_ERR_BAD_INPUT;
        }
    return LBK_OK;
}

/* The sets of a scene with k light set names and nd door names (both sorted, distinct). */
static lbk_result fill_sets(bs_impl *im, const bk_scene *scene, const char **names, size_t k, const char **doors,
                            size_t nd, char *err, size_t err_len)
{
    size_t nc = scene->combination_count;
    im->combos = calloc(nc ? nc : 1, sizeof *im->combos);
    im->sets = calloc(k + 2 * nd + nc, sizeof *im->sets);
    im->doors = calloc(nd ? nd : 1, sizeof *im->doors);
    if (!im->combos || !im->sets || !im->doors) return LBK_ERR_OUT_OF_MEMORY;
    im->set_count = k + 2 * nd + nc;
    im->combo_count = nc;
    im->light_set_count = k;
    im->door_count = nd;
    lbk_result r = LBK_OK;
    for (size_t j = 0; !r && j < k; j++) r = fill_light_set(&im->sets[j], scene, names[j]);
    for (size_t p = 0; !r && p < nd; p++) r = fill_door(im, scene, p, doors[p], err, err_len);
    for (size_t ci = 0; !r && ci < nc; ci++) r = fill_combination(im, scene, ci, err, err_len);
    return r;
}

lbk_result bk_set_bakes_prepare(bk_set_bakes *sets, const bk_scene *scene, const bk_events *events, char *err,
                                size_t err_len)
{
    memset(sets, 0, sizeof *sets);
    size_t n = scene->light_count + scene->object_count;
    const char **names = malloc((n ? n : 1) * sizeof *names);
    const char **doors = malloc((scene->object_count ? scene->object_count : 1) * sizeof *doors);
    bs_impl *im = calloc(1, sizeof *im);
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (!names || !doors || !im) goto fail;
    size_t k = 0, nd = 0;
    for (size_t i = 0; i < scene->light_count; i++)
        if (scene->lights[i].light_set[0]) names[k++] = scene->lights[i].light_set;
    for (size_t i = 0; i < scene->object_count; i++) {
        if (scene->objects[i].light_set[0]) names[k++] = scene->objects[i].light_set;
        if (scene->objects[i].door[0]) doors[nd++] = scene->objects[i].door;
    }
    k = unique_sorted(names, k);
    nd = unique_sorted(doors, nd);
    if (scene->combination_count && !nd) {
        snprintf(err, err_len, "lbk_combinations: the scene has no door (lbk_door); a combination state needs one");
        r = LBK_ERR_BAD_INPUT;
        goto fail;
    }
    if (k + 2 * nd == 0) {
        free(names), free(doors), free(im);
        return LBK_OK;
    }
    r = fill_sets(im, scene, names, k, doors, nd, err, err_len);
    if (r) goto fail;
    free(names), free(doors);
    sets->impl = im;
    sets->set_count = (uint32_t)im->set_count;
    sets->door_count = (uint32_t)im->door_count;
    bk_events_say(events, LBK_BAKE_SEVERITY_NOTE, "%zu dynamic light sets, %zu doors, %zu combination states",
                  im->light_set_count, im->door_count, im->combo_count);
    return LBK_OK;
fail:
    if (r == LBK_ERR_OUT_OF_MEMORY) snprintf(err, err_len, "out of memory");
    free(names), free(doors);
    sets->impl = im;
    bk_set_bakes_free(sets);
    return r;
}

/* ---- hooks ----------------------------------------------------------------------------- */

/* 1 when triangle `tri` of `s` belongs to a door other than `keep` (NULL: any door). */
static int tri_door_black(const bk_scene *s, const char *keep, uint32_t tri)
{
    uint32_t o = s->tri_object && tri < s->tri_count ? s->tri_object[tri] : UINT32_MAX;
    if (o >= s->object_count || !s->objects[o].door[0]) return 0;
    return !(keep && !strcmp(keep, s->objects[o].door));
}

int bk_set_bakes_base_hooks(bk_set_bakes *sets, const bk_scene *scene, bk_transport_options *base)
{
    (void)scene;
    base->light_set = NULL; /* the base: lights and emitters of no set, plus the sky */
    bs_impl *im = sets->impl;
    return im && im->door_count;
}

void bk_set_bakes_base_albedo(const bk_set_bakes *sets, const bk_scene *scene, uint32_t tri, float albedo[3])
{
    if (sets->impl && tri_door_black(scene, NULL, tri)) albedo[0] = albedo[1] = albedo[2] = 0;
}

/* ---- selection and encoding ------------------------------------------------------------ */

static double lum3(const float c[3])
{
    return LBK_LUM_R * c[0] + LBK_LUM_G * c[1] + LBK_LUM_B * c[2];
}

/* Irradiance along the texel normal of a linear form (+Z in tangent space), per channel. */
static void lin_ez(const lbk_ahd_linear *l, float out[3])
{
    for (int c = 0; c < 3; c++) out[c] = l->c[c][0] + l->c[c][3];
}

/* A contribution is light: a channel whose irradiance along the normal is not positive (noise
 * of a difference) contributes nothing. */
static void lin_clamp(lbk_ahd_linear *l)
{
    for (int c = 0; c < 3; c++)
        if (!(l->c[c][0] + l->c[c][3] > 0)) memset(l->c[c], 0, sizeof l->c[c]);
}

static void sh_clamp(lbk_sh9_rgb *s)
{
    for (int c = 0; c < 3; c++)
        if (!(s->c[c][0] > 0)) memset(s->c[c], 0, sizeof s->c[c]);
}

/* Probe luminance comparable with texel irradiance: fluence / 4 (a uniform field L gives πL
 * on a surface and 4πL of fluence). */
static double probe_lum(const lbk_sh9_rgb *s)
{
    float dc[3] = {s->c[0][0], s->c[1][0], s->c[2][0]};
    return lum3(dc) * sqrt(4 * BS_PI) / 4;
}

typedef struct bs_vec {
    uint32_t *targets;
    uint8_t *values;
    size_t count, cap, stride;
} bs_vec;

static int vec_push(bs_vec *v, uint32_t target, const void *payload)
{
    if (v->count == v->cap) {
        size_t cap = v->cap ? 2 * v->cap : 256;
        uint32_t *t = realloc(v->targets, cap * sizeof *t);
        if (!t) return -1;
        v->targets = t;
        uint8_t *p = realloc(v->values, cap * v->stride);
        if (!p) return -1;
        v->values = p;
        v->cap = cap;
    }
    v->targets[v->count] = target;
    memcpy(v->values + v->count * v->stride, payload, v->stride);
    v->count++;
    return 0;
}

static int is_door_texel(const bk_set_inputs *in, size_t k)
{
    const bk_texel *t = &in->texels->receivers[in->texel_of_receiver[k]];
    return t->object < in->scene->object_count && in->scene->objects[t->object].door[0];
}

/* The set's texels as clamped linear AHD (lin, door texels zeroed in door sets) and its
 * absolute threshold (bake/sets/SETS.md): fraction × mean indirect irradiance (luminance) of
 * the texels the set lights directly; with no direct light the mean contribution; with no texel
 * lit the mean over the probes. */
static lbk_result set_threshold(const bk_set_inputs *in, const lbk_sh9_rgb *contrib, const double *dl,
                                double fraction, int skip_doors, lbk_ahd_linear *lin, double *thr)
{
    const bk_texels *tx = in->texels;
    size_t nt = in->texel_receivers;
    double *lum = calloc(nt ? nt : 1, sizeof *lum);
    if (!lum) return LBK_ERR_OUT_OF_MEMORY;
    double dmax = 0;
    for (size_t k = 0; k < nt; k++) {
        const bk_texel *t = &tx->receivers[in->texel_of_receiver[k]];
        bk_texel_linear(t, &contrib[k], &lin[k]);
        lin_clamp(&lin[k]);
        if (skip_doors && is_door_texel(in, k)) memset(&lin[k], 0, sizeof lin[k]);
        float ez[3];
        lin_ez(&lin[k], ez);
        lum[k] = lum3(ez);
        if (lum[k] > 0 && dl[k] > dmax) dmax = dl[k];
    }
    double sum = 0, all = 0;
    size_t lit = 0, pos = 0;
    for (size_t k = 0; k < nt; k++) {
        if (!(lum[k] > 0)) continue;
        all += lum[k], pos++;
        if (dmax > 0 && dl[k] > 1e-4 * dmax) {
            sum += fmax(0, lum[k] - dl[k]);
            lit++;
        }
    }
    double reference = lit ? sum / (double)lit : 0;
    if (!(reference > 0) && pos) reference = all / (double)pos; /* no direct light: mean contribution */
    if (!(reference > 0)) {
        /* no texel sees the set: probes decide */
        double ps = 0;
        size_t pn = 0;
        for (size_t k = nt; k < in->receiver_count; k++) {
            lbk_sh9_rgb sh = contrib[k];
            sh_clamp(&sh);
            double l = probe_lum(&sh);
            if (l > 0) ps += l, pn++;
        }
        reference = pn ? ps / (double)pn : 0;
    }
    *thr = fraction * reference;
    free(lum);
    return LBK_OK;
}

/* Texel entries above thr, page by page, dilated like the base (bk_encode_pages) so bilinear
 * filtering at chart borders sees the set's light in the gutter too. */
static lbk_result emit_texels(const bk_set_inputs *in, const lbk_ahd_linear *lin, double thr, bs_vec *tv)
{
    const bk_texels *tx = in->texels;
    size_t nt = in->texel_receivers;
    if (!nt || !tx->page_count) return LBK_OK;
    int32_t *recv_of_texel = malloc((tx->count ? tx->count : 1) * sizeof *recv_of_texel);
    if (!recv_of_texel) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < tx->count; i++) recv_of_texel[i] = -1;
    for (size_t k = 0; k < nt; k++) recv_of_texel[in->texel_of_receiver[k]] = (int32_t)k;
    lbk_result r = LBK_OK;
    for (size_t p = 0; !r && p < tx->page_count; p++) {
        int w = tx->pages[p].width, h = tx->pages[p].height;
        size_t n = (size_t)w * (size_t)h;
        float *data = calloc(n * 12 + 1, sizeof *data);
        uint8_t *mask = calloc(n + 1, 1);
        if (!data || !mask) r = LBK_ERR_OUT_OF_MEMORY;
        for (size_t i = 0; !r && i < n; i++) {
            int32_t ti = tx->index[tx->page_offset[p] + i];
            if (ti < 0 || recv_of_texel[ti] < 0) continue;
            memcpy(&data[12 * i], lin[recv_of_texel[ti]].c, 12 * sizeof(float));
            mask[i] = 1;
        }
        if (!r) r = bk_finish_page(data, mask, w, h, in->atlas_margin, in->seams, (uint32_t)p, in->transport.threads);
        for (size_t i = 0; !r && i < n && thr >= 0; i++) {
            if (!mask[i]) continue;
            lbk_ahd_linear l;
            memcpy(l.c, &data[12 * i], sizeof l.c);
            float ez[3];
            lin_ez(&l, ez);
            double li = lum3(ez);
            if (!(li > thr) || !(li > 0)) continue;
            if (vec_push(tv, (uint32_t)(tx->page_offset[p] + i), &l)) r = LBK_ERR_OUT_OF_MEMORY;
        }
        free(data), free(mask);
    }
    free(recv_of_texel);
    return r;
}

/* GLG and LLG probe entries above thr; door props get no door-set entries. */
static lbk_result emit_probes(const bk_set_inputs *in, const lbk_sh9_rgb *contrib, double thr, int skip_doors,
                              bs_vec *gv, bs_vec *lv)
{
    size_t grid = 0, grid_end = in->llg_first;
    int door_grid = 0;
    for (size_t k = in->texel_receivers; k < in->receiver_count; k++) {
        /* which LLG this probe belongs to */
        while (k >= in->llg_first && k >= grid_end && grid < in->llg_grids) {
            const bk_llg *g = &in->llgs[grid++];
            grid_end += bk_llg_probe_count(g);
            door_grid = g->object < in->scene->object_count && in->scene->objects[g->object].door[0];
        }
        if (skip_doors && k >= in->llg_first && door_grid) continue;
        lbk_sh9_rgb s = contrib[k];
        sh_clamp(&s);
        double l = probe_lum(&s);
        if (!(l > thr) || !(l > 0)) continue;
        int bad;
        if (k >= in->glg_first && k < in->glg_first + in->glg_count)
            bad = vec_push(gv, (uint32_t)(k - in->glg_first), &s);
        else if (k >= in->llg_first && k < in->llg_first + in->llg_count)
            bad = vec_push(lv, (uint32_t)(k - in->llg_first), &s);
        else
            continue;
        if (bad) return LBK_ERR_OUT_OF_MEMORY;
    }
    return LBK_OK;
}

/* Chooses a set's entries from its per-receiver contribution (radiance SH) and the luminance
 * of its direct part per texel receiver (dl): where the contribution exceeds the set's threshold
 * (set_threshold). Door receivers are left out of door sets (when the door is open it is not
 * there). */
static lbk_result emit_set(const bk_set_inputs *in, bs_set *st, const lbk_sh9_rgb *contrib, const double *dl,
                           double fraction, int skip_doors)
{
    size_t nt = in->texel_receivers;
    lbk_ahd_linear *lin = calloc(nt ? nt : 1, sizeof *lin);
    if (!lin) return LBK_ERR_OUT_OF_MEMORY;
    double thr = 0;
    lbk_result r = set_threshold(in, contrib, dl, fraction, skip_doors, lin, &thr);
    st->threshold = thr;
    bs_vec tv = {NULL, NULL, 0, 0, sizeof(lbk_ahd_linear)}, gv = {NULL, NULL, 0, 0, sizeof(lbk_sh9_rgb)},
           lv = {NULL, NULL, 0, 0, sizeof(lbk_sh9_rgb)};
    if (!r) r = emit_texels(in, lin, thr, &tv);
    if (!r) r = emit_probes(in, contrib, thr, skip_doors, &gv, &lv);
    if (!r) {
        st->count[LBK_DLS_SPACE_TEXEL] = tv.count, st->targets[LBK_DLS_SPACE_TEXEL] = tv.targets;
        st->values[LBK_DLS_SPACE_TEXEL] = tv.values;
        st->count[LBK_DLS_SPACE_GLG] = gv.count, st->targets[LBK_DLS_SPACE_GLG] = gv.targets;
        st->values[LBK_DLS_SPACE_GLG] = gv.values;
        st->count[LBK_DLS_SPACE_LLG] = lv.count, st->targets[LBK_DLS_SPACE_LLG] = lv.targets;
        st->values[LBK_DLS_SPACE_LLG] = lv.values;
        tv.targets = gv.targets = lv.targets = NULL;
        tv.values = gv.values = lv.values = NULL;
    }
    free(tv.targets), free(tv.values), free(gv.targets), free(gv.values), free(lv.targets), free(lv.values);
    free(lin);
    return r;
}

/* Keeps a set's contribution for bk_set_bakes_emit and adds it to the denoiser's guide
 * (combination sets are corrections of their members: not in the guide). `variance` is the
 * run's own (light sets) or NULL (differences of correlated runs: unknown). */
static lbk_result stash_set(const bk_set_inputs *in, bs_impl *im, bs_set *st, const lbk_sh9_rgb *contrib,
                            const lbk_sh9_rgb *direct, const float *halves, const float *variance, double fraction,
                            int skip_doors)
{
    size_t n = in->receiver_count, nt = in->texel_receivers;
    free(st->stash), free(st->stash_direct), free(st->stash_halves);
    st->stash = malloc((n ? n : 1) * sizeof *st->stash);
    st->stash_direct = malloc((nt ? nt : 1) * sizeof *st->stash_direct);
    st->stash_halves = halves ? malloc((n ? n : 1) * 2 * sizeof *st->stash_halves) : NULL;
    if (!st->stash || !st->stash_direct || (halves && !st->stash_halves)) return LBK_ERR_OUT_OF_MEMORY;
    memcpy(st->stash, contrib, n * sizeof *st->stash);
    if (halves) memcpy(st->stash_halves, halves, n * 2 * sizeof *st->stash_halves);
    for (size_t k = 0; k < nt; k++) {
        lbk_ahd_linear dlin;
        float ez[3];
        bk_texel_linear(&in->texels->receivers[in->texel_of_receiver[k]], &direct[k], &dlin);
        lin_ez(&dlin, ez);
        st->stash_direct[k] = lum3(ez);
    }
    st->stash_fraction = fraction;
    st->stash_skip_doors = skip_doors;
    if (st->kind == LBK_DLS_KIND_COMBINATION) return LBK_OK;
    if (!im->guide) {
        im->guide = calloc(n ? n : 1, sizeof *im->guide);
        im->guide_var = calloc(n ? n : 1, sizeof *im->guide_var);
        if (!im->guide || !im->guide_var) return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) im->guide[i].c[c][k] += contrib[i].c[c][k];
        if (variance && isfinite(variance[i])) im->guide_var[i] += variance[i];
    }
    return LBK_OK;
}

void bk_set_bakes_guide(const bk_set_bakes *sets, const lbk_sh9_rgb **sum, const float **variance)
{
    const bs_impl *im = sets->impl;
    *sum = im ? im->guide : NULL;
    *variance = im ? im->guide_var : NULL;
}

/* One class of a set's estimate: the filtered one where it is kept, else the unfiltered. */
static void choose_class(bk_set_estimate *o, const bk_denoise_error *f, const bk_denoise_error *u, int k, int have_filter,
                         int always)
{
    o->filtered[k] = have_filter && (always || f->rel_rmse[k] < u->rel_rmse[k]);
    const bk_denoise_error *x = o->filtered[k] ? f : u;
    o->error.rel_rmse[k] = x->rel_rmse[k], o->error.noise[k] = x->noise[k], o->error.bias[k] = x->bias[k];
}

/* What each stored set's contribution delivers as stored (bk_denoiser_errors: one filter pass
 * per 13 sets): its two halves through the base's denoising weights and unfiltered; with
 * --denoise auto each class (texels, GLG probes) is kept filtered only where that estimate is
 * the lower (bk_set_bakes_emit then stores it so). */
static lbk_result estimate_sets(bs_impl *im, const bk_set_inputs *in)
{
    const size_t cap = im->set_count ? im->set_count : 1;
    const float **h = malloc(cap * sizeof *h);
    bk_denoise_error *e = malloc(cap * sizeof *e), *u = malloc(cap * sizeof *u);
    im->estimates = calloc(cap, sizeof *im->estimates);
    lbk_result r = h && e && u && im->estimates ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    size_t m = 0;
    for (size_t j = 0; j < im->set_count && !r; j++)
        if (im->sets[j].stash && im->sets[j].stash_halves) h[m++] = im->sets[j].stash_halves;
    if (!r) r = bk_denoiser_errors(NULL, h, m, in->transport.class_end, u);
    if (!r && in->denoiser) r = bk_denoiser_errors(in->denoiser, h, m, in->transport.class_end, e);
    for (size_t j = 0, next = 0; j < im->set_count && !r; j++) {
        const bs_set *st = &im->sets[j];
        if (!st->stash || !st->stash_halves) continue;
        const size_t k = next++; /* its place in h, e and u */
        bk_set_estimate *o = &im->estimates[im->estimate_count++];
        snprintf(o->name, sizeof o->name, "%s", st->name);
        o->set = (uint32_t)j;
        o->kind = st->kind;
        o->error = u[k]; /* the LLG class is never filtered */
        const bk_denoise_error *f = in->denoiser ? &e[k] : &u[k];
        choose_class(o, f, &u[k], BK_CLASS_TEXEL, in->denoiser != NULL, in->denoise_always);
        choose_class(o, f, &u[k], BK_CLASS_GLG, in->denoiser != NULL, in->denoise_always);
        o->error.probe_rel_rmse = o->filtered[BK_CLASS_GLG] ? f->probe_rel_rmse : u[k].probe_rel_rmse;
        o->error.seconds = f->seconds + (in->denoiser ? u[k].seconds : 0);
        static const char *const kinds[LBK_DLS_KIND_COUNT_] = {"light set", "door open", "door closed", "combination"};
        bk_events_say(in->events, LBK_BAKE_SEVERITY_INFO,
                      "%-11s %-22s as stored: texels %.2f%% (bias %.2f%%%s), GLG %.2f%%%s",
                      o->kind < LBK_DLS_KIND_COUNT_ ? kinds[o->kind] : "set", o->name,
                      100 * o->error.rel_rmse[BK_CLASS_TEXEL], 100 * o->error.bias[BK_CLASS_TEXEL],
                      o->filtered[BK_CLASS_TEXEL] ? ", denoised" : "", 100 * o->error.rel_rmse[BK_CLASS_GLG],
                      o->filtered[BK_CLASS_GLG] ? " (denoised)" : "");
    }
    free(h), free(e), free(u);
    return r;
}

/* Filters a kept contribution with the base's weights in the classes its estimate keeps
 * filtered (est NULL: none known, every class filtered). */
static lbk_result filter_set(const bk_set_inputs *in, bs_set *st, const bk_set_estimate *est)
{
    static const int all[BK_RECEIVER_CLASSES] = {1, 1, 1};
    return bk_denoiser_apply_classes(in->denoiser, st->stash, est ? est->filtered : all);
}

const bk_set_estimate *bk_set_bakes_estimates(const bk_set_bakes *sets, size_t *count)
{
    const bs_impl *im = sets ? sets->impl : NULL;
    *count = im ? im->estimate_count : 0;
    return im ? im->estimates : NULL;
}

lbk_result bk_set_bakes_emit(bk_set_bakes *sets, const bk_set_inputs *in, char *err, size_t err_len)
{
    bs_impl *im = sets->impl;
    if (!im) return LBK_OK;
    lbk_result r = estimate_sets(im, in);
    for (size_t j = 0; j < im->set_count && !r; j++) {
        bs_set *st = &im->sets[j];
        if (!st->stash) continue;
        /* every set with the same weights, so sets toggled at run time add up to what a
         * denoised bake of the sum would be */
        const bk_set_estimate *est = NULL;
        for (size_t i = 0; i < im->estimate_count; i++)
            if (im->estimates[i].set == j) est = &im->estimates[i];
        if (in->denoiser) r = filter_set(in, st, est);
        if (!r) r = emit_set(in, st, st->stash, st->stash_direct, st->stash_fraction, st->stash_skip_doors);
        free(st->stash), free(st->stash_direct), free(st->stash_halves);
        st->stash = NULL, st->stash_direct = NULL, st->stash_halves = NULL;
    }
    free(im->guide), free(im->guide_var);
    im->guide = NULL, im->guide_var = NULL;
    if (r) snprintf(err, err_len, "light sets: %s", lbk_result_message(r));
    return r;
}

/* ---- runs ------------------------------------------------------------------------------ */

/* The user state of every set run: progress over all runs, the door albedo hook, and where an
 * error's text goes. */
typedef struct run_ctx {
    const bk_set_inputs *in;
    bs_impl *im;             /* where run_one logs each run's estimate */
    double t_start;          /* bk_now() when the runs began, and the transport's share of the */
    double transport_secs;   /* time since: the rest (scenes without doors, tracers) is overhead */
    int run, runs;
    const bk_scene *scene;   /* scene of the current run (the hook's triangle indices) */
    float *variance;         /* NULL, or where run_one writes the run's per-receiver variance */
    int black_doors;         /* 1: door triangles get albedo 0 ... */
    const char *keep;        /* ... except this door's */
    char *err;
    size_t err_len;
} run_ctx;

static int run_progress(void *user, const char *phase, double fraction)
{
    (void)phase;
    run_ctx *rc = user;
    return bk_events_progress(rc->in->events, (rc->run + fraction) / (rc->runs ? rc->runs : 1));
}

static void run_albedo(void *user, uint32_t tri, float albedo[3])
{
    const run_ctx *rc = user;
    if (rc->black_doors && tri_door_black(rc->scene, rc->keep, tri)) albedo[0] = albedo[1] = albedo[2] = 0;
}

/* What a failed step returns: cancellation and out of memory as they are, else internal. */
static lbk_result failure(run_ctx *rc, lbk_result r, const char *fmt, const char *name)
{
    if (r == LBK_ERR_CANCELLED) return r;
    snprintf(rc->err, rc->err_len, fmt, name, lbk_result_message(r));
    /* bad input stays bad input: a merge's replay refusing a part (the exit code says whose fault) */
    return r == LBK_ERR_OUT_OF_MEMORY || r == LBK_ERR_BAD_INPUT ? r : LBK_ERR_INTERNAL;
}

/* A scene without the triangles of one or two doors (arrays are shared with `s` except the triangle
 * lists; never bk_scene_free it). */
typedef struct filtered_scene {
    bk_scene scene;
    uint32_t *tris, *tri_material, *tri_object;
    float *cell_size;  /* the transport's per-triangle cell sizes, filtered alike (NULL: none) */
} filtered_scene;

static lbk_result scene_without_doors(const bk_scene *s, const char *door, const char *door2, const float *cell_size,
                                      filtered_scene *out)
{
    memset(out, 0, sizeof *out);
    out->scene = *s;
    size_t n = s->tri_count ? s->tri_count : 1;
    out->tris = malloc(3 * n * sizeof *out->tris);
    out->tri_material = malloc(n * sizeof *out->tri_material);
    out->tri_object = malloc(n * sizeof *out->tri_object);
    out->cell_size = cell_size ? malloc(n * sizeof *out->cell_size) : NULL;
    if (!out->tris || !out->tri_material || !out->tri_object || (cell_size && !out->cell_size)) {
        free(out->tris), free(out->tri_material), free(out->tri_object), free(out->cell_size);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t k = 0;
    for (size_t i = 0; i < s->tri_count; i++) {
        uint32_t o = s->tri_object ? s->tri_object[i] : UINT32_MAX;
        if (o < s->object_count && (!strcmp(s->objects[o].door, door) || (door2 && !strcmp(s->objects[o].door, door2))))
            continue;
        memcpy(&out->tris[3 * k], &s->tris[3 * i], 3 * sizeof *out->tris);
        out->tri_material[k] = s->tri_material ? s->tri_material[i] : 0;
        out->tri_object[k] = o;
        if (cell_size) out->cell_size[k] = cell_size[i];
        k++;
    }
    out->scene.tri_count = k;
    out->scene.tris = out->tris;
    out->scene.tri_material = out->tri_material;
    out->scene.tri_object = out->tri_object;
    return LBK_OK;
}

static void filtered_free(filtered_scene *f)
{
    free(f->tris), free(f->tri_material), free(f->tri_object), free(f->cell_size);
}

static lbk_result log_run(run_ctx *rc, const char *what, const bk_transport_stats *st)
{
    bs_impl *im = rc->im;
    if (!im) return LBK_OK;
    bk_set_run_error *n = realloc(im->run_errors, (im->run_error_count + 1) * sizeof *n);
    if (!n) return LBK_ERR_OUT_OF_MEMORY;
    im->run_errors = n;
    bk_set_run_error *e = &n[im->run_error_count++];
    memset(e, 0, sizeof *e);
    snprintf(e->label, sizeof e->label, "%s", what);
    e->est_rel_rmse = st->est_rel_rmse;
    memcpy(e->class_rel_rmse, st->class_rel_rmse, sizeof e->class_rel_rmse);
    e->probe_rel_rmse = st->probe_rel_rmse;
    e->seconds = st->seconds;
    return LBK_OK;
}

const bk_set_run_error *bk_set_bakes_run_errors(const bk_set_bakes *sets, size_t *count)
{
    const bs_impl *im = sets ? sets->impl : NULL;
    *count = im ? im->run_error_count : 0;
    return im ? im->run_errors : NULL;
}

/* One transport run at the base receivers. */
static lbk_result run_one(run_ctx *rc, const bk_scene *scene, const bk_tracer *tracer, const bk_transport_options *base,
                          lbk_sh9_rgb *radiance, lbk_sh9_rgb *direct, float *halves, const char *what)
{
    const bk_set_inputs *in = rc->in;
    bk_transport_options opt = *base;
    if (in->deadline > 0) {
        /* the bake's one budget: an equal share of what is left per remaining run (door runs
         * too: their differences stay unbiased, only noisier, if their passes differ) */
        const int left = rc->runs - rc->run > 0 ? rc->runs - rc->run : 1;
        const double now = bk_now();
        /* what each run costs besides its transport (a scene without a door, its tracer), so far */
        const double overhead = rc->run > 0 ? fmax(0, (now - rc->t_start - rc->transport_secs) / rc->run) : 0;
        opt.time_limit = fmax(1e-3, (in->deadline - now) / left - overhead);
    }
    opt.progress = run_progress;
    opt.report = NULL;
    opt.albedo_hook = rc->black_doors ? run_albedo : NULL;
    opt.user = rc;
    rc->scene = scene;
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = radiance;
    out.direct = direct;
    out.halves = halves;
    out.variance = rc->variance;
    bk_transport_stats st;
    /* every run stores the direct irradiance estimate along texel normals like the base
     * (bk_texels_match_irradiance), so base + contributions stay exact along the normal */
    float *irradiance = malloc((in->receiver_count ? in->receiver_count : 1) * 3 * sizeof *irradiance);
    if (!irradiance) return failure(rc, LBK_ERR_OUT_OF_MEMORY, "light transport for %s: %s", what);
    out.irradiance = irradiance;
    lbk_result r = bk_transport_run(scene, tracer, in->receivers, in->receiver_count, &opt, &out, &st);
    if (!r) bk_texels_match_irradiance(in->texels, in->texel_of_receiver, in->texel_receivers, radiance, irradiance);
    if (!r && in->llg_fit) r = bk_llg_fit_run(in->llg_fit, in->llgs, in->scene, irradiance, radiance, in->llg_first, NULL);
    free(irradiance);
    rc->run++;
    rc->transport_secs += st.seconds;
    if (r) return failure(rc, r, "light transport for %s: %s", what);
    if (st.nonfinite)
        bk_events_say(in->events, LBK_BAKE_SEVERITY_WARNING, "%s: %llu non-finite samples were dropped", what,
                      (unsigned long long)st.nonfinite);
    bk_events_say(in->events, LBK_BAKE_SEVERITY_INFO, "%-30s %2d passes %7.0f samples/receiver  est. error %6.2f%%  %6.1f s",
                  what, st.passes, st.samples_per_receiver, 100 * st.est_rel_rmse, st.seconds);
    return log_run(rc, what, &st);
}

static void sh_sub(lbk_sh9_rgb *dst, const lbk_sh9_rgb *b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) dst[i].c[c][k] -= b[i].c[c][k];
}

static void sh_add(lbk_sh9_rgb *dst, const lbk_sh9_rgb *b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 9; k++) dst[i].c[c][k] += b[i].c[c][k];
}

/* The scene with one or two doors removed (door2 may be NULL) and its own tracer; on success the
 * caller destroys *tr and frees *fs. */
static lbk_result open_without(run_ctx *rc, const char *door, const char *door2, filtered_scene *fs, bk_tracer **tr)
{
    lbk_result r = scene_without_doors(rc->in->scene, door, door2, rc->in->transport.cell_size, fs);
    if (r) return failure(rc, r, "scene without door '%s': %s", door);
    r = bk_tracer_create(&fs->scene, rc->in->transport.threads, tr);
    if (r) {
        filtered_free(fs);
        return failure(rc, r, "ray tracer without door '%s': %s", door);
    }
    return LBK_OK;
}

/* A run over the scene with one or two doors removed (its own tracer). */
static lbk_result run_without(run_ctx *rc, const char *door, const char *door2, const bk_transport_options *opt,
                              lbk_sh9_rgb *rad, lbk_sh9_rgb *dir, float *halves, const char *what)
{
    filtered_scene fs;
    bk_tracer *tr = NULL;
    lbk_result r = open_without(rc, door, door2, &fs, &tr);
    if (r) return r;
    bk_transport_options o = *opt;
    o.cell_size = fs.cell_size;
    r = run_one(rc, &fs.scene, tr, &o, rad, dir, halves, what);
    bk_tracer_destroy(tr);
    filtered_free(&fs);
    return r;
}

/* S_O of door d by the guided estimator (bake/sets/door_guided.h) into rad/dir. */
static lbk_result guided_open(run_ctx *rc, const bs_door *d, const float *texel_size, const uint8_t *door_texel,
                              lbk_sh9_rgb *rad, lbk_sh9_rgb *dir)
{
    const bk_set_inputs *in = rc->in;
    if (in->skip_guided) { /* a unit: the merge makes it (the unit's base radiance is partial) */
        memset(rad, 0, in->receiver_count * sizeof *rad);
        memset(dir, 0, in->receiver_count * sizeof *dir);
        rc->run++;
        return LBK_OK;
    }
    filtered_scene fs;
    bk_tracer *tr = NULL;
    lbk_result r = open_without(rc, d->name, NULL, &fs, &tr);
    if (r) return r;
    bk_door_guided_inputs gi;
    memset(&gi, 0, sizeof gi);
    gi.scene = &fs.scene;
    gi.tracer = tr;
    bk_portal_from_obb(d->centre, (const float (*)[3])d->axes, d->half, &gi.portal);
    gi.receivers = in->receivers;
    gi.receiver_count = in->receiver_count;
    gi.texel_receivers = in->texel_receivers;
    gi.texel_size = texel_size;
    gi.not_cache = door_texel;
    gi.base_radiance = in->base_radiance;
    gi.seed = in->transport.seed;
    gi.threads = in->transport.threads;
    /* the same per-receiver budget the difference runs get */
    double spp = in->base_samples_per_receiver > 0 ? in->base_samples_per_receiver : 64;
    gi.samples = (int)fmin(fmax(spp, 16), 4096);
    gi.use_sky = !in->transport.no_sky;
    gi.irradiance = malloc((in->receiver_count ? in->receiver_count : 1) * 3 * sizeof *gi.irradiance);
    bk_door_guided_stats st;
    r = gi.irradiance ? bk_door_guided_run(&gi, rad, dir, &st, NULL) : LBK_ERR_OUT_OF_MEMORY;
    if (!r) bk_texels_match_irradiance(in->texels, in->texel_of_receiver, in->texel_receivers, rad, gi.irradiance);
    if (!r && in->llg_fit) r = bk_llg_fit_run(in->llg_fit, in->llgs, in->scene, gi.irradiance, rad, in->llg_first, NULL);
    free(gi.irradiance);
    bk_tracer_destroy(tr);
    filtered_free(&fs);
    rc->run++;
    if (r) return failure(rc, r, "guided door estimator for '%s': %s", d->name);
    bk_events_say(in->events, LBK_BAKE_SEVERITY_INFO,
                  "door '%s' open (guided)        %zu photons → %d boxes, %.0f portal samples, %d bounces "
                  "(q %.2f); energy direct %.3g, 1st bounce %.3g, later %.3g; %6.1f s",
                  d->name, st.photons, st.boxes, st.portal_samples, st.bounces, st.q, st.stage_energy[0],
                  st.stage_energy[1], st.stage_energy[2], st.seconds);
    /* the estimator has no checkpoint of its own */
    return bk_events_progress(in->events, (double)rc->run / (rc->runs ? rc->runs : 1)) ? LBK_ERR_CANCELLED : LBK_OK;
}

/* Everything bk_set_bakes_run's steps share: the runs' state and their buffers, n receivers each. */
typedef struct set_run {
    run_ctx rc;
    bs_impl *im;
    const bk_set_inputs *in;
    size_t n;                       /* receivers (at least 1: the buffer sizes) */
    double fraction;                /* sparse storage threshold (emit_set) */
    bk_transport_options fixed;     /* the door runs' fixed budget */
    lbk_sh9_rgb *rad, *dir;         /* the current run */
    float *halves;                  /* its two half estimates (2 per receiver; differences alike) */
    float *var;                     /* its variance (light-set runs: the denoiser's guide) */
    lbk_sh9_rgb *ref, *ref_dir;     /* every door closed and black */
    float *ref_halves;
    lbk_sh9_rgb **keep, **keep_dir; /* open runs of doors in door–door combinations */
    float **keep_halves;
    float *texel_size;              /* guided: per texel receiver */
    uint8_t *door_texel;
    lbk_sh9_rgb *ls_closed, *ls_closed_dir; /* door–light set combinations: the set, doors closed */
    float *ls_closed_halves;
    char what[256];
} set_run;

static lbk_result out_of_memory(set_run *s)
{
    snprintf(s->rc.err, s->rc.err_len, "out of memory");
    return LBK_ERR_OUT_OF_MEMORY;
}

/* Keeps the current run's contribution for bk_set_bakes_emit (stash_set); halves: 1 when
 * s->halves holds the contribution's half estimates (0: the guided estimator's, none). */
static lbk_result emit(set_run *s, bs_set *st, const float *variance, int skip_doors, int halves)
{
    return stash_set(s->in, s->im, st, s->rad, s->dir, halves ? s->halves : NULL, variance, s->fraction, skip_doors)
               ? out_of_memory(s)
               : LBK_OK;
}

/* dst −= b (or += b), two half estimates per receiver */
static void halves_sub(float *dst, const float *b, size_t n)
{
    for (size_t i = 0; i < 2 * n; i++) dst[i] -= b[i];
}

static void halves_add(float *dst, const float *b, size_t n)
{
    for (size_t i = 0; i < 2 * n; i++) dst[i] += b[i];
}

/* Light sets: their lights alone (transport leaves out the sky and every other emitter); doors
 * stay closed with their albedo (seed §4.1: the other elements in their default state, here
 * including the bounce off them). */
static lbk_result bake_light_sets(set_run *s)
{
    for (size_t j = 0; j < s->im->light_set_count; j++) {
        bs_set *st = &s->im->sets[j];
        if (st->zero) continue; /* no light: no entries and no run */
        bk_transport_options opt = s->in->transport;
        opt.light_set = st->name;
        s->rc.black_doors = 0;
        snprintf(s->what, sizeof s->what, "light set '%s'", st->name);
        s->rc.variance = s->var;
        lbk_result r = run_one(&s->rc, s->in->scene, s->in->tracer, &opt, s->rad, s->dir, s->halves, s->what);
        s->rc.variance = NULL;
        if (r) return r;
        r = emit(s, st, s->var, 0, 1);
        if (r) return r;
    }
    return LBK_OK;
}

/* Doors are differences of runs with the same seed and the same passes (a fixed budget equal to
 * what the base reached, no error target, no time limit), so the receivers' gather rays are the
 * same and most of the noise cancels. This sets up those runs and bakes their reference: every
 * door closed with albedo 0, the base's path space (seed §4.1). */
static lbk_result bake_door_reference(set_run *s, int guided)
{
    const bk_set_inputs *in = s->in;
    s->fixed = in->transport;
    s->fixed.light_set = NULL;
    s->fixed.target_error = -1;
    s->fixed.time_limit = 0;
    if (in->base_samples_per_receiver > 0) s->fixed.max_samples = (int)fmin(in->base_samples_per_receiver, 1 << 24);
    s->ref = malloc(s->n * sizeof *s->ref), s->ref_dir = malloc(s->n * sizeof *s->ref_dir);
    s->ref_halves = malloc(s->n * 2 * sizeof *s->ref_halves);
    s->keep = calloc(s->im->door_count, sizeof *s->keep);
    s->keep_dir = calloc(s->im->door_count, sizeof *s->keep_dir);
    s->keep_halves = calloc(s->im->door_count, sizeof *s->keep_halves);
    if (!s->ref || !s->ref_dir || !s->ref_halves || !s->keep || !s->keep_dir || !s->keep_halves) return out_of_memory(s);
    if (guided) {
        s->texel_size = calloc(in->texel_receivers ? in->texel_receivers : 1, sizeof *s->texel_size);
        s->door_texel = calloc(in->texel_receivers ? in->texel_receivers : 1, 1);
        if (!s->texel_size || !s->door_texel) return out_of_memory(s);
        for (size_t k = 0; k < in->texel_receivers; k++) {
            s->texel_size[k] = in->texels->receivers[in->texel_of_receiver[k]].texel_size;
            s->door_texel[k] = (uint8_t)is_door_texel(in, k);
        }
    }
    s->rc.black_doors = 1;
    s->rc.keep = NULL;
    return run_one(&s->rc, in->scene, in->tracer, &s->fixed, s->ref, s->ref_dir, s->ref_halves,
                   "doors closed, black (reference)");
}

/* Door p's two sets: S_O (open: the light through the opening) and S_C (closed: its bounce). */
static lbk_result bake_door(set_run *s, size_t p, int guided)
{
    const bs_impl *im = s->im;
    const bs_door *d = &im->doors[p];
    const size_t count = s->in->receiver_count;
    int keep_it = 0;
    for (size_t c = 0; c < im->combo_count; c++)
        keep_it |= im->combos[c].door[1] >= 0 && (im->combos[c].door[0] == (int)p || im->combos[c].door[1] == (int)p);
    lbk_result r;
    if (guided) {
        /* S_O by the seed's guided estimator: no full run */
        r = guided_open(&s->rc, d, s->texel_size, s->door_texel, s->rad, s->dir);
        if (r) return r;
    } else {
        /* S_O = L(door p removed, others closed and black) − reference */
        s->rc.keep = NULL;
        snprintf(s->what, sizeof s->what, "door '%s' open", d->name);
        r = run_without(&s->rc, d->name, NULL, &s->fixed, s->rad, s->dir, s->halves, s->what);
        if (r) return r;
        if (keep_it) {
            s->keep[p] = malloc(s->n * sizeof **s->keep), s->keep_dir[p] = malloc(s->n * sizeof **s->keep_dir);
            s->keep_halves[p] = malloc(s->n * 2 * sizeof **s->keep_halves);
            if (!s->keep[p] || !s->keep_dir[p] || !s->keep_halves[p]) return out_of_memory(s);
            memcpy(s->keep[p], s->rad, s->n * sizeof *s->rad);
            memcpy(s->keep_dir[p], s->dir, s->n * sizeof *s->dir);
            memcpy(s->keep_halves[p], s->halves, s->n * 2 * sizeof *s->halves);
        }
        sh_sub(s->rad, s->ref, count);
        sh_sub(s->dir, s->ref_dir, count);
        halves_sub(s->halves, s->ref_halves, count);
    }
    r = emit(s, &s->im->sets[d->open_set], NULL, 1, !guided);
    if (r) return r;

    /* S_C = L(door p closed with its albedo, others black) − reference */
    s->rc.keep = d->name;
    snprintf(s->what, sizeof s->what, "door '%s' closed (bounce)", d->name);
    r = run_one(&s->rc, s->in->scene, s->in->tracer, &s->fixed, s->rad, s->dir, s->halves, s->what);
    if (r) return r;
    sh_sub(s->rad, s->ref, count);
    sh_sub(s->dir, s->ref_dir, count);
    halves_sub(s->halves, s->ref_halves, count);
    return emit(s, &s->im->sets[d->closed_set], NULL, 1, 1);
}

/* Doors A, B: S_AB = L(A, B open) − L(A open) − L(B open) + L(ref), into rad/dir. */
static lbk_result bake_door_pair(set_run *s, const bs_combo *co)
{
    const bs_door *da = &s->im->doors[co->door[0]], *db = &s->im->doors[co->door[1]];
    const size_t count = s->in->receiver_count;
    s->rc.black_doors = 1;
    s->rc.keep = NULL;
    for (int m = 0; m < 2; m++) {
        int p = co->door[m];
        if (s->keep[p]) continue;
        /* guided mode has no open run yet: the combination needs a correlated one */
        s->keep[p] = malloc(s->n * sizeof **s->keep), s->keep_dir[p] = malloc(s->n * sizeof **s->keep_dir);
        s->keep_halves[p] = malloc(s->n * 2 * sizeof **s->keep_halves);
        if (!s->keep[p] || !s->keep_dir[p] || !s->keep_halves[p]) return out_of_memory(s);
        snprintf(s->what, sizeof s->what, "door '%s' open (for a combination)", s->im->doors[p].name);
        lbk_result r = run_without(&s->rc, s->im->doors[p].name, NULL, &s->fixed, s->keep[p], s->keep_dir[p],
                                   s->keep_halves[p], s->what);
        if (r) return r;
    }
    snprintf(s->what, sizeof s->what, "doors '%s' and '%s' open", da->name, db->name);
    lbk_result r = run_without(&s->rc, da->name, db->name, &s->fixed, s->rad, s->dir, s->halves, s->what);
    if (r) return r;
    sh_sub(s->rad, s->keep[co->door[0]], count);
    sh_sub(s->rad, s->keep[co->door[1]], count);
    sh_add(s->rad, s->ref, count);
    halves_sub(s->halves, s->keep_halves[co->door[0]], count);
    halves_sub(s->halves, s->keep_halves[co->door[1]], count);
    halves_add(s->halves, s->ref_halves, count);
    sh_sub(s->dir, s->keep_dir[co->door[0]], count);
    sh_sub(s->dir, s->keep_dir[co->door[1]], count);
    sh_add(s->dir, s->ref_dir, count);
    return LBK_OK;
}

/* Door A, light set X: S_AX = L_X(A open) − L_X(A closed) (the set's lights alone, other doors
 * closed with their albedo, as the set's own bake), into rad/dir. */
static lbk_result bake_door_light_set(set_run *s, const bs_combo *co)
{
    const bs_set *ls = &s->im->sets[co->light_set];
    const bs_door *da = &s->im->doors[co->door[0]];
    bk_transport_options opt = s->fixed;
    opt.light_set = ls->name;
    s->rc.black_doors = 0;
    snprintf(s->what, sizeof s->what, "light set '%s', door '%s' open", ls->name, da->name);
    lbk_result r = run_without(&s->rc, da->name, NULL, &opt, s->rad, s->dir, s->halves, s->what);
    if (r) return r;
    snprintf(s->what, sizeof s->what, "light set '%s' (fixed budget)", ls->name);
    if (!s->ls_closed) {
        s->ls_closed = malloc(s->n * sizeof *s->ls_closed), s->ls_closed_dir = malloc(s->n * sizeof *s->ls_closed_dir);
        s->ls_closed_halves = malloc(s->n * 2 * sizeof *s->ls_closed_halves);
    }
    if (!s->ls_closed || !s->ls_closed_dir || !s->ls_closed_halves) return out_of_memory(s);
    r = run_one(&s->rc, s->in->scene, s->in->tracer, &opt, s->ls_closed, s->ls_closed_dir, s->ls_closed_halves, s->what);
    if (r) return r;
    sh_sub(s->rad, s->ls_closed, s->in->receiver_count);
    sh_sub(s->dir, s->ls_closed_dir, s->in->receiver_count);
    halves_sub(s->halves, s->ls_closed_halves, s->in->receiver_count);
    return LBK_OK;
}

/* Combination states (seed §6.2) by inclusion–exclusion of correlated runs. With both open the
 * runtime then shows base + S_A + S_B + S_AB = L(A, B open). Clamped like every difference
 * (emit_set). */
static lbk_result bake_combinations(set_run *s)
{
    for (size_t c = 0; c < s->im->combo_count; c++) {
        const bs_combo *co = &s->im->combos[c];
        lbk_result r;
        if (co->door[1] >= 0) {
            r = bake_door_pair(s, co);
        } else {
            if (s->im->sets[co->light_set].zero) continue; /* a black set: nothing to combine, no entries */
            r = bake_door_light_set(s, co);
        }
        if (!r) r = emit(s, &s->im->sets[co->set], NULL, 1, 1);
        if (r) return r;
    }
    return LBK_OK;
}

static void set_run_free(set_run *s)
{
    if (s->keep)
        for (size_t p = 0; p < s->im->door_count; p++) free(s->keep[p]), free(s->keep_dir[p]);
    if (s->keep_halves)
        for (size_t p = 0; p < s->im->door_count; p++) free(s->keep_halves[p]);
    free(s->keep), free(s->keep_dir), free(s->keep_halves), free(s->texel_size), free(s->door_texel), free(s->ls_closed),
        free(s->ls_closed_dir), free(s->ls_closed_halves);
    free(s->rad), free(s->dir), free(s->halves), free(s->ref), free(s->ref_dir), free(s->ref_halves), free(s->var);
}

int bk_set_bakes_planned_runs(const bk_set_bakes *sets)
{
    const bs_impl *im = sets ? sets->impl : NULL;
    if (!im) return 0;
    int runs = 0;
    for (size_t j = 0; j < im->light_set_count; j++) runs += !im->sets[j].zero;
    runs += im->door_count ? 1 + 2 * (int)im->door_count : 0;
    for (size_t c = 0; c < im->combo_count; c++) runs += im->combos[c].door[1] >= 0 ? 3 : 2;
    return runs;
}

/* Whether a door pair before combination c has door p (guided: its open run is kept). */
static int door_in_pair_before(const bs_impl *im, size_t c, int p)
{
    for (size_t e = 0; e < c; e++)
        if (im->combos[e].door[1] >= 0 && (im->combos[e].door[0] == p || im->combos[e].door[1] == p)) return 1;
    return 0;
}

int bk_set_bakes_transport_runs(const bk_set_bakes *sets, int method, int *light_set_runs)
{
    const bs_impl *im = sets ? sets->impl : NULL;
    if (light_set_runs) *light_set_runs = 0;
    if (!im) return 0;
    int runs = 0;
    for (size_t j = 0; j < im->light_set_count; j++) runs += !im->sets[j].zero;
    if (light_set_runs) *light_set_runs = runs;
    if (!im->door_count) return runs;
    const int guided = method == BK_DOOR_GUIDED;
    runs += 1 + (guided ? 1 : 2) * (int)im->door_count; /* the reference, then each door (open and) closed */
    for (size_t c = 0; c < im->combo_count; c++) {
        const bs_combo *co = &im->combos[c];
        if (co->door[1] < 0) {
            runs += im->sets[co->light_set].zero ? 0 : 2; /* the set with the door open and closed */
            continue;
        }
        runs += 1; /* both open (difference: bake_door kept each open run) */
        for (int m = 0; m < 2 && guided; m++) /* a door's first pair makes its open run */
            runs += !door_in_pair_before(im, c, co->door[m]);
    }
    return runs;
}

lbk_result bk_set_bakes_run(bk_set_bakes *sets, const bk_set_inputs *in, char *err, size_t err_len)
{
    bs_impl *im = sets->impl;
    if (!im) return LBK_OK;
    set_run s;
    memset(&s, 0, sizeof s);
    s.im = im;
    s.in = in;
    s.n = in->receiver_count ? in->receiver_count : 1;
    s.fraction = in->threshold == 0 ? BS_DEFAULT_THRESHOLD : in->threshold < 0 ? 0 : in->threshold;
    s.rc.in = in;
    s.rc.im = im;
    s.rc.err = err;
    s.rc.err_len = err_len;
    s.rc.runs = bk_set_bakes_planned_runs(sets);
    s.rc.t_start = bk_now();
    const int guided = in->door_method == BK_DOOR_GUIDED;
    s.rad = malloc(s.n * sizeof *s.rad), s.dir = malloc(s.n * sizeof *s.dir), s.var = malloc(s.n * sizeof *s.var);
    s.halves = malloc(s.n * 2 * sizeof *s.halves);
    lbk_result r = s.rad && s.dir && s.var && s.halves ? LBK_OK : out_of_memory(&s);
    if (!r) r = bake_light_sets(&s);
    if (!r && im->door_count) {
        r = bake_door_reference(&s, guided);
        for (size_t p = 0; !r && p < im->door_count; p++) r = bake_door(&s, p, guided);
        if (!r) r = bake_combinations(&s);
    }
    set_run_free(&s);
    return r;
}

/* ---- sections -------------------------------------------------------------------------- */

void bk_set_bakes_max(const bk_set_bakes *sets, double max[LBK_DLS_SPACE_COUNT_])
{
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) max[s] = 0;
    const bs_impl *im = sets->impl;
    if (!im) return;
    for (size_t j = 0; j < im->set_count; j++) {
        const bs_set *st = &im->sets[j];
        double m = bk_texel_max((const lbk_ahd_linear *)st->values[LBK_DLS_SPACE_TEXEL], NULL,
                                st->count[LBK_DLS_SPACE_TEXEL]);
        if (m > max[LBK_DLS_SPACE_TEXEL]) max[LBK_DLS_SPACE_TEXEL] = m;
        for (int s = LBK_DLS_SPACE_GLG; s < LBK_DLS_SPACE_COUNT_; s++) {
            m = bk_probe_max((const lbk_sh9_rgb *)st->values[s], st->count[s]);
            if (m > max[s]) max[s] = m;
        }
    }
}

/* Every set's entries as DLS payloads, enc[set · spaces + space] (malloc'ed), stored in the
 * scale of the target space's base section (spec §12.2; dividing by a power of two is exact). */
static lbk_result encode_payloads(const bs_impl *im, const bk_set_inputs *in, uint8_t **enc)
{
    for (size_t j = 0; j < im->set_count; j++)
        for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
            const bs_set *st = &im->sets[j];
            const size_t n = st->count[s];
            if (!n) continue;
            const size_t stride = s == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD;
            uint8_t *e = enc[j * LBK_DLS_SPACE_COUNT_ + (size_t)s] = malloc(n * stride);
            if (!e) return LBK_ERR_OUT_OF_MEMORY;
            const float inv = 1.0f / (in->scale[s] > 0 ? in->scale[s] : 1.0f);
            for (size_t i = 0; i < n; i++) {
                if (s == LBK_DLS_SPACE_TEXEL) {
                    lbk_ahd_linear l;
                    memset(&l, 0, sizeof l);
                    lbk_ahd_linear_add_scaled(&l, (const lbk_ahd_linear *)st->values[s] + i, inv);
                    lbk_ahd_texel t;
                    lbk_ahd_from_linear(&l, &t);
                    lbk_ahd_texel_pack(&t, e + stride * i);
                } else {
                    lbk_sh9_rgb sh;
                    memset(&sh, 0, sizeof sh);
                    lbk_sh9_add_scaled(&sh, (const lbk_sh9_rgb *)st->values[s] + i, inv);
                    lbk_sh9_pack(&sh, e + stride * i);
                }
            }
        }
    return LBK_OK;
}

static lbk_result build_dls(const bs_impl *im, const bk_set_inputs *in, uint8_t *const *enc, void **dls, size_t *dls_size)
{
    lbk_dls_set_desc *sd = calloc(im->set_count, sizeof *sd);
    if (!sd) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t j = 0; j < im->set_count; j++) {
        const bs_set *st = &im->sets[j];
        sd[j].name = st->name;
        sd[j].kind = st->kind;
        sd[j].light_count = st->light_count;
        sd[j].light_names = st->light_names;
        sd[j].member_count = st->member_count;
        sd[j].members = st->member_count ? st->members : NULL;
        for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
            sd[j].entries[s].count = st->count[s];
            sd[j].entries[s].targets = st->targets[s];
            sd[j].entries[s].payloads = enc[j * LBK_DLS_SPACE_COUNT_ + (size_t)s];
        }
    }
    lbk_dls_build_desc bd = LBK_DLS_BUILD_DESC_INIT;
    bd.set_count = (uint32_t)im->set_count;
    bd.sets = sd;
    const bk_texels *tx = in->texels;
    bd.target_count[LBK_DLS_SPACE_TEXEL] =
        tx && tx->page_count && in->texel_receivers ? (uint64_t)tx->page_offset[tx->page_count] : 0;
    bd.target_count[LBK_DLS_SPACE_GLG] = in->glg_count;
    bd.target_count[LBK_DLS_SPACE_LLG] = in->llg_count;
    lbk_result r = lbk_dls_build(&bd, NULL, dls, dls_size, NULL);
    free(sd);
    return r;
}

/* The DOOR section: each door's box (in world space) and sets, and the combination states. */
static lbk_result build_door(const bs_impl *im, const bk_set_inputs *in, void **door, size_t *door_size)
{
    size_t nc = im->combo_count ? im->combo_count : 1;
    lbk_door_desc *dd = calloc(im->door_count, sizeof *dd);
    lbk_door_state_desc *states = calloc(nc, sizeof *states);
    uint32_t *state_doors = calloc(2 * nc, sizeof *state_doors);
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (dd && states && state_doors) {
        for (size_t p = 0; p < im->door_count; p++) {
            const bs_door *d = &im->doors[p];
            dd[p].name = d->name;
            for (int k = 0; k < 3; k++) dd[p].centre[k] = d->centre[k] + in->origin[k];
            memcpy(dd[p].axes, d->axes, sizeof d->axes);
            memcpy(dd[p].half_extents, d->half, sizeof d->half);
            dd[p].open_set = d->open_set;
            dd[p].closed_set = d->closed_set;
        }
        for (size_t c = 0; c < im->combo_count; c++) {
            const bs_combo *co = &im->combos[c];
            state_doors[2 * c] = (uint32_t)co->door[0];
            state_doors[2 * c + 1] = (uint32_t)co->door[1];
            states[c].door_count = co->door[1] >= 0 ? 2 : 1;
            states[c].doors = &state_doors[2 * c];
            states[c].set = co->set;
        }
        lbk_door_build_desc db = LBK_DOOR_BUILD_DESC_INIT;
        db.door_count = (uint32_t)im->door_count;
        db.doors = dd;
        db.state_count = (uint32_t)im->combo_count;
        db.states = states;
        r = lbk_door_build(&db, NULL, door, door_size);
    }
    free(dd), free(states), free(state_doors);
    return r;
}

lbk_result bk_set_bakes_sections(bk_set_bakes *sets, const bk_set_inputs *in, void **dls, size_t *dls_size,
                                 void **door, size_t *door_size)
{
    *dls = *door = NULL;
    *dls_size = *door_size = 0;
    bs_impl *im = sets->impl;
    if (!im || !im->set_count) return LBK_OK;
    uint8_t **enc = calloc(im->set_count * LBK_DLS_SPACE_COUNT_, sizeof *enc); /* encoded payloads */
    if (!enc) return LBK_ERR_OUT_OF_MEMORY;
    lbk_result r = encode_payloads(im, in, enc);
    if (!r) r = build_dls(im, in, enc, dls, dls_size);
    for (size_t i = 0; i < im->set_count * LBK_DLS_SPACE_COUNT_; i++) free(enc[i]);
    free(enc);
    if (r || !im->door_count) return r;
    r = build_door(im, in, door, door_size);
    if (r) {
        lbk_free(NULL, *dls);
        *dls = NULL;
        *dls_size = 0;
    }
    return r;
}

void bk_set_bakes_free(bk_set_bakes *sets)
{
    bs_impl *im = sets->impl;
    if (im) {
        for (size_t j = 0; j < im->set_count; j++) {
            free(im->sets[j].light_names);
            free(im->sets[j].stash), free(im->sets[j].stash_direct), free(im->sets[j].stash_halves);
            for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) free(im->sets[j].targets[s]), free(im->sets[j].values[s]);
        }
        free(im->sets), free(im->doors), free(im->combos), free(im->guide), free(im->guide_var), free(im->run_errors), free(im->estimates), free(im);
    }
    memset(sets, 0, sizeof *sets);
}
