/* The transport runs of the set bakes (bk_set_bakes_run): each light set alone; per door the
 * reference (every door closed and black), its open contribution (a difference of correlated
 * runs, or the guided estimator) and its closed bounce; the combination states by
 * inclusion–exclusion. Each run's contribution goes to bs_stash_set. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/sets/sets_internal.h"
#include "bake/sets/door_guided.h"
#include "bake/encode/encode.h"
#include "scene/clock.h"

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
    if (rc->black_doors && bs_tri_door_black(rc->scene, rc->keep, tri)) albedo[0] = albedo[1] = albedo[2] = 0;
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
    if (!r && in->llg_fit) r = bk_llg_fit_run(in->llg_fit, in->llgs, in->scene, irradiance, radiance, in->llg_first, NULL,
                                                   NULL);
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
    if (!r && in->llg_fit) r = bk_llg_fit_run(in->llg_fit, in->llgs, in->scene, gi.irradiance, rad, in->llg_first, NULL,
                                                   NULL);
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

/* Keeps the current run's contribution for bk_set_bakes_emit (bs_stash_set); halves: 1 when
 * s->halves holds the contribution's half estimates (0: the guided estimator's, none). */
static lbk_result emit(set_run *s, bs_set *st, const float *variance, int skip_doors, int halves)
{
    return bs_stash_set(s->in, s->im, st, s->rad, s->dir, halves ? s->halves : NULL, variance, s->fraction, skip_doors)
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
            s->door_texel[k] = (uint8_t)bs_is_door_texel(in, k);
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
