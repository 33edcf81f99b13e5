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
#include "bake/pipeline/encode.h"
#include "cli/cli.h"
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

int bk_set_bakes_prepare(bk_set_bakes *sets, const bk_scene *scene, bk_progress *progress, char *err,
                         size_t err_len)
{
    memset(sets, 0, sizeof *sets);
    size_t n = scene->light_count + scene->object_count;
    const char **names = malloc((n ? n : 1) * sizeof *names);
    const char **doors = malloc((scene->object_count ? scene->object_count : 1) * sizeof *doors);
    bs_impl *im = calloc(1, sizeof *im);
    if (!names || !doors || !im) goto oom;
    size_t k = 0, nd = 0;
    for (size_t i = 0; i < scene->light_count; i++)
        if (scene->lights[i].light_set[0]) names[k++] = scene->lights[i].light_set;
    for (size_t i = 0; i < scene->object_count; i++) {
        if (scene->objects[i].light_set[0]) names[k++] = scene->objects[i].light_set;
        if (scene->objects[i].door[0]) doors[nd++] = scene->objects[i].door;
    }
    k = unique_sorted(names, k);
    nd = unique_sorted(doors, nd);
    size_t nc = scene->combination_count;
    if (nc && !nd) {
        snprintf(err, err_len, "lbk_combinations: the scene has no door (lbk_door); a combination state needs one");
        free(names), free(doors), free(im);
        return LBK_EXIT_INPUT;
    }
    if (k + 2 * nd == 0) {
        free(names), free(doors), free(im);
        return 0;
    }
    im->set_count = k + 2 * nd + nc;
    im->combo_count = nc;
    im->combos = calloc(nc ? nc : 1, sizeof *im->combos);
    if (!im->combos) goto oom;
    im->light_set_count = k;
    im->door_count = nd;
    im->sets = calloc(im->set_count, sizeof *im->sets);
    im->doors = calloc(nd ? nd : 1, sizeof *im->doors);
    if (!im->sets || !im->doors) goto oom;
    for (size_t j = 0; j < k; j++) {
        bs_set *st = &im->sets[j];
        snprintf(st->name, sizeof st->name, "%s", names[j]);
        st->kind = LBK_DLS_KIND_LIGHTS;
        st->door = -1;
        uint32_t lc = 0;
        int bright = 0;
        for (size_t i = 0; i < scene->light_count; i++)
            if (!strcmp(scene->lights[i].light_set, names[j])) lc++;
        for (size_t i = 0; i < scene->object_count; i++)
            if (!strcmp(scene->objects[i].light_set, names[j])) lc++;
        st->light_names = calloc(lc ? lc : 1, sizeof *st->light_names);
        if (!st->light_names) goto oom;
        for (size_t i = 0; i < scene->light_count; i++) {
            const bk_light *l = &scene->lights[i];
            if (strcmp(l->light_set, names[j])) continue;
            st->light_names[st->light_count++] = l->name;
            if (l->color[0] > 0 || l->color[1] > 0 || l->color[2] > 0) bright = 1;
        }
        for (size_t i = 0; i < scene->object_count; i++) {
            const bk_object *o = &scene->objects[i];
            if (strcmp(o->light_set, names[j])) continue;
            st->light_names[st->light_count++] = o->name;
            if (object_emits(scene, o)) bright = 1;
        }
        st->zero = !bright;
    }
    for (size_t p = 0; p < nd; p++) {
        bs_door *d = &im->doors[p];
        snprintf(d->name, sizeof d->name, "%s", doors[p]);
        door_obb(scene, doors[p], d);
        d->open_set = (uint32_t)(k + 2 * p);
        d->closed_set = (uint32_t)(k + 2 * p + 1);
        bs_set *so = &im->sets[d->open_set], *sc = &im->sets[d->closed_set];
        snprintf(so->name, sizeof so->name, "door/%s/open", doors[p]);
        snprintf(sc->name, sizeof sc->name, "door/%s/closed", doors[p]);
        so->kind = LBK_DLS_KIND_DOOR_OPEN;
        sc->kind = LBK_DLS_KIND_DOOR_CLOSED;
        so->door = sc->door = (int)p;
        for (size_t j = 0; j < k; j++)
            if (!strcmp(im->sets[j].name, so->name) || !strcmp(im->sets[j].name, sc->name)) {
                snprintf(err, err_len, "light set '%s' has the name lbk gives to door '%s': rename one",
                         im->sets[j].name, doors[p]);
                goto bad_input;
            }
    }
    for (size_t ci = 0; ci < nc; ci++) {
        const bk_combination *cb = &scene->combinations[ci];
        bs_combo *co = &im->combos[ci];
        co->door[0] = co->door[1] = co->light_set = -1;
        int ndoor = 0;
        for (int m = 0; m < 2; m++) {
            const char *nm = cb->members[m];
            int door = -1, ls = -1;
            for (size_t p = 0; p < nd; p++)
                if (!strcmp(im->doors[p].name, nm)) door = (int)p;
            for (size_t j = 0; j < k; j++)
                if (!strcmp(im->sets[j].name, nm)) ls = (int)j;
            if (door >= 0 && ls >= 0) {
                snprintf(err, err_len, "lbk_combinations[%zu]: '%s' names both a door and a light set: rename one", ci, nm);
                goto bad_input;
            }
            if (door < 0 && ls < 0) {
                snprintf(err, err_len, "lbk_combinations[%zu]: '%s' is neither a door (lbk_door) nor a light set (lbk_light_set)",
                         ci, nm);
                goto bad_input;
            }
            if (door >= 0) co->door[ndoor++] = door;
            else if (co->light_set >= 0) {
                snprintf(err, err_len, "lbk_combinations[%zu]: two light sets add up linearly and have no combination "
                         "state; pair a light set with a door", ci);
                goto bad_input;
            } else co->light_set = ls;
        }
        if (ndoor == 2 && co->door[0] == co->door[1]) {
            snprintf(err, err_len, "lbk_combinations[%zu]: door '%s' paired with itself", ci, cb->members[0]);
            goto bad_input;
        }
        if (ndoor == 2 && co->door[0] > co->door[1]) {
            int t = co->door[0];
            co->door[0] = co->door[1], co->door[1] = t;
        }
        for (size_t cj = 0; cj < ci; cj++)
            if (im->combos[cj].door[0] == co->door[0] && im->combos[cj].door[1] == co->door[1] &&
                im->combos[cj].light_set == co->light_set) {
                snprintf(err, err_len, "lbk_combinations[%zu]: the same pair as lbk_combinations[%zu]", ci, cj);
                goto bad_input;
            }
        co->set = (uint32_t)(k + 2 * nd + ci);
        bs_set *st = &im->sets[co->set];
        snprintf(st->name, sizeof st->name, "combo/%s+%s", cb->members[0], cb->members[1]);
        st->kind = LBK_DLS_KIND_COMBINATION;
        st->door = -1;
        st->members[0] = im->doors[co->door[0]].open_set;
        st->members[1] = co->door[1] >= 0 ? im->doors[co->door[1]].open_set : (uint32_t)co->light_set;
        st->member_count = 2;
        for (size_t j = 0; j < k; j++)
            if (!strcmp(im->sets[j].name, st->name)) {
                snprintf(err, err_len, "light set '%s' has the name lbk gives to a combination state: rename it", st->name);
                goto bad_input;
            }
    }
    free(names), free(doors);
    sets->impl = im;
    sets->set_count = (uint32_t)im->set_count;
    sets->door_count = (uint32_t)im->door_count;
    if (progress)
        bk_progress_note(progress, "lbk bake: %zu dynamic light sets, %zu doors, %zu combination states",
                         im->light_set_count, im->door_count, im->combo_count);
    return 0;
bad_input:
    free(names), free(doors);
    sets->impl = im;
    bk_set_bakes_free(sets);
    return LBK_EXIT_INPUT;
oom:
    free(names), free(doors);
    sets->impl = im;
    bk_set_bakes_free(sets);
    snprintf(err, err_len, "out of memory");
    return LBK_EXIT_INTERNAL;
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

/* Chooses and encodes a set's entries from its per-receiver contribution (radiance SH) and the
 * direct part of it. Rule (bake/sets/SETS.md): threshold = fraction × mean indirect irradiance
 * (luminance) of the texels the set lights directly; an entry is stored where the contribution
 * exceeds it. Door receivers are left out of door sets (when the door is open it is not there). */
static lbk_result emit_set(const bk_set_inputs *in, bs_set *st, const lbk_sh9_rgb *contrib, const lbk_sh9_rgb *direct,
                           double fraction, int skip_doors)
{
    const bk_texels *tx = in->texels;
    size_t nt = in->texel_receivers;
    lbk_ahd_linear *lin = calloc(nt ? nt : 1, sizeof *lin);
    double *lum = calloc(nt ? nt : 1, sizeof *lum);
    if (!lin || !lum) {
        free(lin), free(lum);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    /* threshold from the directly lit texels */
    double dmax = 0;
    double *dl = calloc(nt ? nt : 1, sizeof *dl);
    if (!dl) {
        free(lin), free(lum);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t k = 0; k < nt; k++) {
        const bk_texel *t = &tx->receivers[in->texel_of_receiver[k]];
        bk_texel_linear(t, &contrib[k], &lin[k]);
        lin_clamp(&lin[k]);
        if (skip_doors && is_door_texel(in, k)) memset(&lin[k], 0, sizeof lin[k]);
        float ez[3];
        lin_ez(&lin[k], ez);
        lum[k] = lum3(ez);
        lbk_ahd_linear dlin;
        bk_texel_linear(t, &direct[k], &dlin);
        lin_ez(&dlin, ez);
        dl[k] = lum3(ez);
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
            lbk_sh9_rgb s = contrib[k];
            sh_clamp(&s);
            double l = probe_lum(&s);
            if (l > 0) ps += l, pn++;
        }
        reference = pn ? ps / (double)pn : 0;
    }
    double thr = fraction * reference;
    st->threshold = thr;
    free(dl);

    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    bs_vec tv = {NULL, NULL, 0, 0, sizeof(lbk_ahd_linear)}, gv = {NULL, NULL, 0, 0, sizeof(lbk_sh9_rgb)},
           lv = {NULL, NULL, 0, 0, sizeof(lbk_sh9_rgb)};
    /* texels, page by page, dilated like the base (bk_encode_pages) so bilinear filtering at
     * chart borders sees the set's light in the gutter too */
    if (nt && tx->page_count) {
        int32_t *recv_of_texel = NULL;
        recv_of_texel = malloc((tx->count ? tx->count : 1) * sizeof *recv_of_texel);
        if (!recv_of_texel) goto done;
        for (size_t i = 0; i < tx->count; i++) recv_of_texel[i] = -1;
        for (size_t k = 0; k < nt; k++) recv_of_texel[in->texel_of_receiver[k]] = (int32_t)k;
        for (size_t p = 0; p < tx->page_count; p++) {
            int w = tx->pages[p].width, h = tx->pages[p].height;
            size_t n = (size_t)w * (size_t)h;
            float *data = calloc(n * 12 + 1, sizeof *data);
            uint8_t *mask = calloc(n + 1, 1);
            if (!data || !mask) {
                free(data), free(mask), free(recv_of_texel);
                goto done;
            }
            for (size_t i = 0; i < n; i++) {
                int32_t ti = tx->index[tx->page_offset[p] + i];
                if (ti < 0 || recv_of_texel[ti] < 0) continue;
                memcpy(&data[12 * i], lin[recv_of_texel[ti]].c, 12 * sizeof(float));
                mask[i] = 1;
            }
            bk_dilate(data, 12, mask, w, h, in->atlas_margin + 2);
            for (size_t i = 0; i < n && thr >= 0; i++) {
                if (!mask[i]) continue;
                lbk_ahd_linear l;
                memcpy(l.c, &data[12 * i], sizeof l.c);
                float ez[3];
                lin_ez(&l, ez);
                double li = lum3(ez);
                if (!(li > thr) || !(li > 0)) continue;
                if (vec_push(&tv, (uint32_t)(tx->page_offset[p] + i), &l)) {
                    free(data), free(mask), free(recv_of_texel);
                    goto done;
                }
            }
            free(data), free(mask);
        }
        free(recv_of_texel);
    }
    size_t grid = 0, grid_end = in->llg_first;
    int door_grid = 0;
    for (size_t k = nt; k < in->receiver_count; k++) {
        /* which LLG this probe belongs to: door props get no door-set entries */
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
            bad = vec_push(&gv, (uint32_t)(k - in->glg_first), &s);
        else if (k >= in->llg_first && k < in->llg_first + in->llg_count)
            bad = vec_push(&lv, (uint32_t)(k - in->llg_first), &s);
        else
            continue;
        if (bad) goto done;
    }
    st->count[LBK_DLS_SPACE_TEXEL] = tv.count, st->targets[LBK_DLS_SPACE_TEXEL] = tv.targets;
    st->values[LBK_DLS_SPACE_TEXEL] = tv.values;
    st->count[LBK_DLS_SPACE_GLG] = gv.count, st->targets[LBK_DLS_SPACE_GLG] = gv.targets;
    st->values[LBK_DLS_SPACE_GLG] = gv.values;
    st->count[LBK_DLS_SPACE_LLG] = lv.count, st->targets[LBK_DLS_SPACE_LLG] = lv.targets;
    st->values[LBK_DLS_SPACE_LLG] = lv.values;
    tv.targets = gv.targets = lv.targets = NULL;
    tv.values = gv.values = lv.values = NULL;
    r = LBK_OK;
done:
    free(tv.targets), free(tv.values), free(gv.targets), free(gv.values), free(lv.targets), free(lv.values);
    free(lin), free(lum);
    return r;
}

/* ---- runs ------------------------------------------------------------------------------ */

/* The user state of every set run: progress over all runs, and the door albedo hook. */
typedef struct run_ctx {
    const bk_set_inputs *in;
    int run, runs;
    const bk_scene *scene;   /* scene of the current run (the hook's triangle indices) */
    int black_doors;         /* 1: door triangles get albedo 0 ... */
    const char *keep;        /* ... except this door's */
} run_ctx;

static void run_progress(void *user, const char *phase, double fraction)
{
    (void)phase;
    run_ctx *rc = user;
    if (rc->in->progress) bk_progress_update(rc->in->progress, (rc->run + fraction) / (rc->runs ? rc->runs : 1));
}

static void run_albedo(void *user, uint32_t tri, float albedo[3])
{
    const run_ctx *rc = user;
    if (rc->black_doors && tri_door_black(rc->scene, rc->keep, tri)) albedo[0] = albedo[1] = albedo[2] = 0;
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

/* One transport run at the base receivers. */
static int run_one(run_ctx *rc, const bk_scene *scene, const bk_tracer *tracer, const bk_transport_options *base,
                   lbk_sh9_rgb *radiance, lbk_sh9_rgb *direct, const char *what, char *err, size_t err_len)
{
    const bk_set_inputs *in = rc->in;
    bk_transport_options opt = *base;
    opt.progress = run_progress;
    opt.report = NULL;
    opt.albedo_hook = rc->black_doors ? run_albedo : NULL;
    opt.user = rc;
    rc->scene = scene;
    bk_transport_output out;
    memset(&out, 0, sizeof out);
    out.radiance = radiance;
    out.direct = direct;
    bk_transport_stats st;
    lbk_result r = bk_transport_run(scene, tracer, in->receivers, in->receiver_count, &opt, &out, &st);
    rc->run++;
    if (r) {
        snprintf(err, err_len, "light transport for %s: %s", what, lbk_result_message(r));
        return LBK_EXIT_INTERNAL;
    }
    if (st.nonfinite && in->progress)
        bk_progress_note(in->progress, "lbk bake: warning: %s: %llu non-finite samples were dropped", what,
                         (unsigned long long)st.nonfinite);
    if (in->progress)
        bk_progress_note(in->progress, "  %-30s %2d passes %7.0f samples/receiver  est. error %6.2f%%  %6.1f s", what,
                         st.passes, st.samples_per_receiver, 100 * st.est_rel_rmse, st.seconds);
    return 0;
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
static int open_without(const bk_set_inputs *in, const char *door, const char *door2, filtered_scene *fs,
                        bk_tracer **tr, char *err, size_t err_len)
{
    if (scene_without_doors(in->scene, door, door2, in->transport.cell_size, fs)) {
        snprintf(err, err_len, "out of memory");
        return LBK_EXIT_INTERNAL;
    }
    lbk_result r = bk_tracer_create(&fs->scene, in->transport.threads, tr);
    if (r) {
        filtered_free(fs);
        snprintf(err, err_len, "ray tracer without door '%s': %s", door, lbk_result_message(r));
        return LBK_EXIT_INTERNAL;
    }
    return 0;
}

/* A run over the scene with one or two doors removed (its own tracer). */
static int run_without(run_ctx *rc, const char *door, const char *door2, const bk_transport_options *opt,
                       lbk_sh9_rgb *rad, lbk_sh9_rgb *dir, const char *what, char *err, size_t err_len)
{
    filtered_scene fs;
    bk_tracer *tr = NULL;
    int code = open_without(rc->in, door, door2, &fs, &tr, err, err_len);
    if (code) return code;
    bk_transport_options o = *opt;
    o.cell_size = fs.cell_size;
    code = run_one(rc, &fs.scene, tr, &o, rad, dir, what, err, err_len);
    bk_tracer_destroy(tr);
    filtered_free(&fs);
    return code;
}

/* S_O of door d by the guided estimator (bake/sets/door_guided.h) into rad/dir. */
static int guided_open(run_ctx *rc, const bs_door *d, const float *texel_size, const uint8_t *door_texel,
                       lbk_sh9_rgb *rad, lbk_sh9_rgb *dir, char *err, size_t err_len)
{
    const bk_set_inputs *in = rc->in;
    filtered_scene fs;
    bk_tracer *tr = NULL;
    int code = open_without(in, d->name, NULL, &fs, &tr, err, err_len);
    if (code) return code;
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
    bk_door_guided_stats st;
    lbk_result r = bk_door_guided_run(&gi, rad, dir, &st, NULL);
    bk_tracer_destroy(tr);
    filtered_free(&fs);
    rc->run++;
    if (r) {
        snprintf(err, err_len, "guided door estimator for '%s': %s", d->name, lbk_result_message(r));
        return LBK_EXIT_INTERNAL;
    }
    if (in->progress)
        bk_progress_note(in->progress,
                         "  door '%s' open (guided)        %zu photons → %d boxes, %.0f portal samples, %d bounces "
                         "(q %.2f); energy direct %.3g, 1st bounce %.3g, later %.3g; %6.1f s",
                         d->name, st.photons, st.boxes, st.portal_samples, st.bounces, st.q, st.stage_energy[0],
                         st.stage_energy[1], st.stage_energy[2], st.seconds);
    return 0;
}

int bk_set_bakes_run(bk_set_bakes *sets, const bk_set_inputs *in, char *err, size_t err_len)
{
    bs_impl *im = sets->impl;
    if (!im) return 0;
    size_t n = in->receiver_count ? in->receiver_count : 1;
    double fraction = in->threshold == 0 ? BS_DEFAULT_THRESHOLD : in->threshold < 0 ? 0 : in->threshold;
    const int guided = in->door_method == BK_DOOR_GUIDED;
    run_ctx rc;
    memset(&rc, 0, sizeof rc);
    rc.in = in;
    for (size_t j = 0; j < im->light_set_count; j++) rc.runs += !im->sets[j].zero;
    rc.runs += im->door_count ? 1 + 2 * (int)im->door_count : 0;
    for (size_t c = 0; c < im->combo_count; c++) rc.runs += im->combos[c].door[1] >= 0 ? 3 : 2;
    lbk_sh9_rgb *rad = malloc(n * sizeof *rad), *dir = malloc(n * sizeof *dir);
    lbk_sh9_rgb *ref = NULL, *ref_dir = NULL;
    lbk_sh9_rgb **keep = NULL, **keep_dir = NULL; /* open runs of doors in door–door combinations */
    float *texel_size = NULL;
    uint8_t *door_texel = NULL;
    int code = 0;
    char what[256];
    lbk_sh9_rgb *ls_closed = NULL, *ls_closed_dir = NULL;
    if (!rad || !dir) goto oom;

    /* Light sets: their lights alone (transport leaves out the sky and every other emitter);
     * doors stay closed with their albedo (seed §4.1: the other elements in their default
     * state, here including the bounce off them). */
    for (size_t j = 0; j < im->light_set_count; j++) {
        bs_set *st = &im->sets[j];
        if (st->zero) continue; /* no light: no entries and no run */
        bk_transport_options opt = in->transport;
        opt.light_set = st->name;
        rc.black_doors = 0;
        snprintf(what, sizeof what, "light set '%s'", st->name);
        code = run_one(&rc, in->scene, in->tracer, &opt, rad, dir, what, err, err_len);
        if (code) goto out;
        if (emit_set(in, st, rad, dir, fraction, 0)) goto oom;
    }

    if (im->door_count) {
        /* Doors: differences of runs with the same seed and the same passes (a fixed budget
         * equal to what the base reached, no error target, no time limit), so the receivers'
         * gather rays are the same and most of the noise cancels. */
        bk_transport_options fixed = in->transport;
        fixed.light_set = NULL;
        fixed.target_error = -1;
        fixed.time_limit = 0;
        if (in->base_samples_per_receiver > 0) fixed.max_samples = (int)fmin(in->base_samples_per_receiver, 1 << 24);
        ref = malloc(n * sizeof *ref), ref_dir = malloc(n * sizeof *ref_dir);
        keep = calloc(im->door_count, sizeof *keep);
        keep_dir = calloc(im->door_count, sizeof *keep_dir);
        if (!ref || !ref_dir || !keep || !keep_dir) goto oom;
        if (guided) {
            texel_size = calloc(in->texel_receivers ? in->texel_receivers : 1, sizeof *texel_size);
            door_texel = calloc(in->texel_receivers ? in->texel_receivers : 1, 1);
            if (!texel_size || !door_texel) goto oom;
            for (size_t k = 0; k < in->texel_receivers; k++) {
                texel_size[k] = in->texels->receivers[in->texel_of_receiver[k]].texel_size;
                door_texel[k] = (uint8_t)is_door_texel(in, k);
            }
        }
        /* reference: every door closed with albedo 0, the base's path space (seed §4.1) */
        rc.black_doors = 1;
        rc.keep = NULL;
        code = run_one(&rc, in->scene, in->tracer, &fixed, ref, ref_dir, "doors closed, black (reference)", err, err_len);
        if (code) goto out;
        for (size_t p = 0; p < im->door_count; p++) {
            bs_door *d = &im->doors[p];
            int keep_it = 0;
            for (size_t c = 0; c < im->combo_count; c++)
                keep_it |= im->combos[c].door[1] >= 0 && (im->combos[c].door[0] == (int)p || im->combos[c].door[1] == (int)p);
            if (guided) {
                /* S_O by the seed's guided estimator: no full run */
                code = guided_open(&rc, d, texel_size, door_texel, rad, dir, err, err_len);
                if (code) goto out;
            } else {
                /* S_O = L(door p removed, others closed and black) − reference */
                rc.keep = NULL;
                snprintf(what, sizeof what, "door '%s' open", d->name);
                code = run_without(&rc, d->name, NULL, &fixed, rad, dir, what, err, err_len);
                if (code) goto out;
                if (keep_it) {
                    keep[p] = malloc(n * sizeof **keep), keep_dir[p] = malloc(n * sizeof **keep_dir);
                    if (!keep[p] || !keep_dir[p]) goto oom;
                    memcpy(keep[p], rad, n * sizeof *rad);
                    memcpy(keep_dir[p], dir, n * sizeof *dir);
                }
                sh_sub(rad, ref, in->receiver_count);
                sh_sub(dir, ref_dir, in->receiver_count);
            }
            if (emit_set(in, &im->sets[d->open_set], rad, dir, fraction, 1)) goto oom;

            /* S_C = L(door p closed with its albedo, others black) − reference */
            rc.keep = d->name;
            snprintf(what, sizeof what, "door '%s' closed (bounce)", d->name);
            code = run_one(&rc, in->scene, in->tracer, &fixed, rad, dir, what, err, err_len);
            if (code) goto out;
            sh_sub(rad, ref, in->receiver_count);
            sh_sub(dir, ref_dir, in->receiver_count);
            if (emit_set(in, &im->sets[d->closed_set], rad, dir, fraction, 1)) goto oom;
        }

        /* Combination states (seed §6.2) by inclusion–exclusion of correlated runs:
         *   doors A, B:        S_AB = L(A, B open) − L(A open) − L(B open) + L(ref);
         *   door A, light set: S_AX = L_X(A open) − L_X(A closed) (the set's lights alone, other
         *                      doors closed with their albedo, as the set's own bake).
         * With both open the runtime then shows base + S_A + S_B + S_AB = L(A, B open). Clamped
         * like every difference (emit_set). */
        for (size_t c = 0; c < im->combo_count; c++) {
            const bs_combo *co = &im->combos[c];
            bs_set *st = &im->sets[co->set];
            const bs_door *da = &im->doors[co->door[0]];
            if (co->door[1] >= 0) {
                const bs_door *db = &im->doors[co->door[1]];
                rc.black_doors = 1;
                rc.keep = NULL;
                for (int m = 0; m < 2; m++) {
                    int p = co->door[m];
                    if (keep[p]) continue;
                    /* guided mode has no open run yet: the combination needs a correlated one */
                    keep[p] = malloc(n * sizeof **keep), keep_dir[p] = malloc(n * sizeof **keep_dir);
                    if (!keep[p] || !keep_dir[p]) goto oom;
                    snprintf(what, sizeof what, "door '%s' open (for a combination)", im->doors[p].name);
                    code = run_without(&rc, im->doors[p].name, NULL, &fixed, keep[p], keep_dir[p], what, err, err_len);
                    if (code) goto out;
                }
                snprintf(what, sizeof what, "doors '%s' and '%s' open", da->name, db->name);
                code = run_without(&rc, da->name, db->name, &fixed, rad, dir, what, err, err_len);
                if (code) goto out;
                sh_sub(rad, keep[co->door[0]], in->receiver_count);
                sh_sub(rad, keep[co->door[1]], in->receiver_count);
                sh_add(rad, ref, in->receiver_count);
                sh_sub(dir, keep_dir[co->door[0]], in->receiver_count);
                sh_sub(dir, keep_dir[co->door[1]], in->receiver_count);
                sh_add(dir, ref_dir, in->receiver_count);
            } else {
                const bs_set *ls = &im->sets[co->light_set];
                if (ls->zero) continue; /* a black set: nothing to combine, no entries */
                bk_transport_options opt = fixed;
                opt.light_set = ls->name;
                rc.black_doors = 0;
                snprintf(what, sizeof what, "light set '%s', door '%s' open", ls->name, da->name);
                code = run_without(&rc, da->name, NULL, &opt, rad, dir, what, err, err_len);
                if (code) goto out;
                snprintf(what, sizeof what, "light set '%s' (fixed budget)", ls->name);
                if (!ls_closed) ls_closed = malloc(n * sizeof *ls_closed), ls_closed_dir = malloc(n * sizeof *ls_closed_dir);
                if (!ls_closed || !ls_closed_dir) goto oom;
                code = run_one(&rc, in->scene, in->tracer, &opt, ls_closed, ls_closed_dir, what, err, err_len);
                if (code) goto out;
                sh_sub(rad, ls_closed, in->receiver_count);
                sh_sub(dir, ls_closed_dir, in->receiver_count);
            }
            if (emit_set(in, st, rad, dir, fraction, 1)) goto oom;
        }
    }
    goto out;
oom:
    snprintf(err, err_len, "out of memory");
    code = LBK_EXIT_INTERNAL;
out:
    if (keep)
        for (size_t p = 0; p < im->door_count; p++) free(keep[p]), free(keep_dir[p]);
    free(keep), free(keep_dir), free(texel_size), free(door_texel), free(ls_closed), free(ls_closed_dir);
    free(rad), free(dir), free(ref), free(ref_dir);
    return code;
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

lbk_result bk_set_bakes_sections(bk_set_bakes *sets, const bk_set_inputs *in, void **dls, size_t *dls_size,
                                 void **door, size_t *door_size)
{
    *dls = *door = NULL;
    *dls_size = *door_size = 0;
    bs_impl *im = sets->impl;
    if (!im || !im->set_count) return LBK_OK;
    lbk_dls_set_desc *sd = calloc(im->set_count, sizeof *sd);
    uint8_t **enc = calloc(im->set_count * LBK_DLS_SPACE_COUNT_, sizeof *enc); /* encoded payloads */
    if (!sd || !enc) {
        free(sd), free(enc);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    lbk_result r = LBK_OK;
    for (size_t j = 0; j < im->set_count && !r; j++)
        for (int s = 0; s < LBK_DLS_SPACE_COUNT_ && !r; s++) {
            const bs_set *st = &im->sets[j];
            const size_t n = st->count[s];
            if (!n) continue;
            const size_t stride = s == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD;
            uint8_t *e = enc[j * LBK_DLS_SPACE_COUNT_ + (size_t)s] = malloc(n * stride);
            if (!e) {
                r = LBK_ERR_OUT_OF_MEMORY;
                break;
            }
            /* stored in the scale of the target space's base section (spec §12.2); dividing by a
             * power of two is exact */
            const float inv = 1.0f / (in->scale[s] > 0 ? in->scale[s] : 1.0f);
            for (size_t i = 0; i < n; i++) {
                if (s == LBK_DLS_SPACE_TEXEL) {
                    lbk_ahd_linear l;
                    memset(&l, 0, sizeof l);
                    lbk_ahd_linear_add_scaled(&l, (const lbk_ahd_linear *)st->values[s] + i, inv);
                    lbk_ahd_texel t;
                    lbk_ahd_from_linear(&l, &t);
                    lbk_ahd_texel_store(&t, e + stride * i);
                } else {
                    lbk_sh9_rgb sh;
                    memset(&sh, 0, sizeof sh);
                    lbk_sh9_add_scaled(&sh, (const lbk_sh9_rgb *)st->values[s] + i, inv);
                    lbk_sh9_pack(&sh, e + stride * i);
                }
            }
        }
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
    lbk_dls_build_desc bd;
    memset(&bd, 0, sizeof bd);
    bd.set_count = (uint32_t)im->set_count;
    bd.sets = sd;
    const bk_texels *tx = in->texels;
    bd.target_count[LBK_DLS_SPACE_TEXEL] =
        tx && tx->page_count && in->texel_receivers ? (uint64_t)tx->page_offset[tx->page_count] : 0;
    bd.target_count[LBK_DLS_SPACE_GLG] = in->glg_count;
    bd.target_count[LBK_DLS_SPACE_LLG] = in->llg_count;
    if (!r) r = lbk_dls_build(&bd, NULL, dls, dls_size, NULL);
    for (size_t i = 0; i < im->set_count * LBK_DLS_SPACE_COUNT_; i++) free(enc[i]);
    free(enc), free(sd);
    if (r || !im->door_count) return r;
    lbk_door_desc *dd = calloc(im->door_count, sizeof *dd);
    if (!dd) {
        lbk_free(NULL, *dls);
        *dls = NULL;
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t p = 0; p < im->door_count; p++) {
        const bs_door *d = &im->doors[p];
        dd[p].name = d->name;
        for (int k = 0; k < 3; k++) dd[p].centre[k] = d->centre[k] + in->origin[k];
        memcpy(dd[p].axes, d->axes, sizeof d->axes);
        memcpy(dd[p].half_extents, d->half, sizeof d->half);
        dd[p].open_set = d->open_set;
        dd[p].closed_set = d->closed_set;
    }
    lbk_door_state_desc *states = calloc(im->combo_count ? im->combo_count : 1, sizeof *states);
    uint32_t *state_doors = calloc(2 * (im->combo_count ? im->combo_count : 1), sizeof *state_doors);
    if (!states || !state_doors) {
        free(dd), free(states), free(state_doors);
        lbk_free(NULL, *dls);
        *dls = NULL;
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t c = 0; c < im->combo_count; c++) {
        const bs_combo *co = &im->combos[c];
        state_doors[2 * c] = (uint32_t)co->door[0];
        state_doors[2 * c + 1] = (uint32_t)co->door[1];
        states[c].door_count = co->door[1] >= 0 ? 2 : 1;
        states[c].doors = &state_doors[2 * c];
        states[c].set = co->set;
    }
    lbk_door_build_desc db;
    memset(&db, 0, sizeof db);
    db.door_count = (uint32_t)im->door_count;
    db.doors = dd;
    db.state_count = (uint32_t)im->combo_count;
    db.states = states;
    r = lbk_door_build(&db, NULL, door, door_size);
    free(dd), free(states), free(state_doors);
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
            for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) free(im->sets[j].targets[s]), free(im->sets[j].values[s]);
        }
        free(im->sets), free(im->doors), free(im->combos), free(im);
    }
    memset(sets, 0, sizeof *sets);
}
