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
 * of the same transport code (bake/transport/transport.h).
 *
 * This file finds the sets, doors and combination states in the scene and holds the base bake's
 * hooks; the entries, runs and sections are in the files sets_internal.h lists. */
#include "bake/sets/bake_sets.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/sets/sets_internal.h"

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
int bs_tri_door_black(const bk_scene *s, const char *keep, uint32_t tri)
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
    if (sets->impl && bs_tri_door_black(scene, NULL, tri)) albedo[0] = albedo[1] = albedo[2] = 0;
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
