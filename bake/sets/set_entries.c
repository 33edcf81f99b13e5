/* A set's sparse entries: its threshold (bake/sets/SETS.md), its texels dilated like the base's
 * pages and its probes above it; the contributions kept from the runs until the denoiser's
 * guide is complete (bk_set_bakes_emit), the guide, and each stored set's error estimate. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/sets/sets_internal.h"
#include "bake/encode/encode.h"

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

int bs_is_door_texel(const bk_set_inputs *in, size_t k)
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
        if (skip_doors && bs_is_door_texel(in, k)) memset(&lin[k], 0, sizeof lin[k]);
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
lbk_result bs_stash_set(const bk_set_inputs *in, bs_impl *im, bs_set *st, const lbk_sh9_rgb *contrib,
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
