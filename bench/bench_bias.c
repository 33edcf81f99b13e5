/* Bias of the light transport against an independent reference (printed, not asserted; the
 * asserted version is tests/bake/test_bias.c).
 *
 * Scene: the bias room (tests/support/bias_scene.h): uniform sky through a window, slabs that
 * overlap, a thin table, a pole, a shelf, a sealed cavity. Receivers: the lightmap texels the
 * pipeline would bake (generated charts at --density texels/m, bk_texels_build, push-out).
 * Reference: the brute-force path tracer (tests/support/ref_path.h) at the same receiver points
 * (the transport's own error), cached in /tmp by a hash of everything it depends on.
 * Per surface group: signed mean relative error Σ(lbk − ref)/Σref, relative RMSE
 * sqrt(Σ(lbk − ref)²/Σref²) and the reference's own noise on the same scale.
 *
 *   bench_bias [--passes P]... [--density D] [--ref-paths N] [--per K] [--ground] [--detail d]
 *              [--threads T] [--cells C] [--cell-texels k] [--no-footprint] [--seed S] [--noise]
 *              [--worst K] [--ref-file F]
 * Defaults are the pipeline's: cells of one texel (--cell-texels 0: the old shared budget of
 * --cells), texel footprints for lbk and the reference (--no-footprint: one point per texel,
 * the reference at the same points: the transport's own error). --noise runs a second seed
 * (lbk's noise, and "excess": what neither noise explains). With no arguments (make bench):
 * 3 and 5 passes, 40 texels per group against 4096 paths each. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake/layout/atlas.h"
#include "bake/layout/texels.h"
#include "bake/transport/transport.h"
#include "tests/support/scene_append.c"
#include "tests/support/transport_scenes.c"
#include "tests/support/bias_scene.c"
#include "tests/support/ref_path.c"

typedef struct args {
    int passes[8], npasses;
    double density;
    int ref_paths, per, ground, detail, threads, cells, noise, worst, footprint;
    const char *ref_file;
    double cell_texels;
    uint64_t seed;
} args;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double lum3d(const double *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }
static double lum3f(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* lbk's value of eval point i: its receiver's irradiance; a texel that is not baked (not valid)
 * counts as 0 */
static double lbk_at(const float *irr, size_t recv)
{
    return recv == SIZE_MAX ? 0.0 : lum3f(irr + 3 * recv);
}

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 0x100000001B3ull;
    return h;
}

typedef struct eval_set {
    size_t n;
    size_t *recv;      /* receiver index */
    int *group;
    float *p, *nrm;
    uint32_t *fp_first, *fp_count; /* footprints (when the reference averages over them) */
    double *ref, *se;  /* reference irradiance (3 per point), stderr of its luminance */
} eval_set;

static void load_or_make_ref(const bk_scene *s, const bk_tracer *t, eval_set *e, int paths, int threads,
                             const bk_texels *tx, const char *file)
{
    uint64_t h = fnv(0xCBF29CE484222325ull, e->p, 3 * e->n * sizeof(float));
#ifndef BENCH_BIAS_ORIG
    if (tx) {
        for (size_t i = 0; i < e->n; i++)
            h = fnv(h, tx->footprint + e->fp_first[i], e->fp_count[i] * sizeof *tx->footprint);
        h = fnv(h, "footprint", 9);
    }
#endif
    h = fnv(h, e->nrm, 3 * e->n * sizeof(float));
    h = fnv(h, &paths, sizeof paths);
    h = fnv(h, s->positions, 3 * s->vertex_count * sizeof(float));
    char path[256];
    snprintf(path, sizeof path, "/tmp/lbk_bias_ref_%016llx.bin", (unsigned long long)h);
    if (file) snprintf(path, sizeof path, "%s", file);
    FILE *f = fopen(path, "rb");
    if (f) {
        size_t a = fread(e->ref, sizeof(double), 3 * e->n, f), b = fread(e->se, sizeof(double), e->n, f);
        fclose(f);
        if (a == 3 * e->n && b == e->n) { printf("reference: %s (cached)\n", path); return; }
    }
    double t0 = now_s();
#ifndef BENCH_BIAS_ORIG
    if (tx)
        rp_footprint_irradiance(s, t, tx->footprint, e->fp_first, e->fp_count, e->p, e->nrm, e->n, paths, 77, threads,
                                e->ref, e->se);
    else
#endif
        rp_irradiance(s, t, e->p, e->nrm, e->n, paths, 77, threads, e->ref, e->se);
    printf("reference: %d paths at %zu points, %.1f s -> %s\n", paths, e->n, now_s() - t0, path);
    f = fopen(path, "wb");
    if (f) {
        fwrite(e->ref, sizeof(double), 3 * e->n, f);
        fwrite(e->se, sizeof(double), e->n, f);
        fclose(f);
    }
}

/* irr2 (optional): a second run with another seed; its difference gives the lbk noise, and
 * what the noises of both sides do not explain is the per-point bias ("excess"). */
static void report(const eval_set *e, const float *irr, const float *irr2, const char *label)
{
    double num[BSC_GROUPS] = {0}, den[BSC_GROUPS] = {0}, sgn[BSC_GROUPS] = {0}, sum[BSC_GROUPS] = {0},
           noise[BSC_GROUPS] = {0}, own[BSC_GROUPS] = {0};
    size_t cnt[BSC_GROUPS] = {0};
    for (size_t i = 0; i < e->n; i++) {
        int g = e->group[i];
        double a = lbk_at(irr, e->recv[i]), b = lum3d(e->ref + 3 * i);
        num[g] += (a - b) * (a - b);
        den[g] += b * b;
        sgn[g] += a - b;
        sum[g] += b;
        noise[g] += e->se[i] * e->se[i];
        if (irr2) {
            double a2 = lbk_at(irr2, e->recv[i]);
            own[g] += 0.5 * (a - a2) * (a - a2);
        }
        cnt[g]++;
    }
    printf("%s\n  %-14s %5s %9s %9s %9s %9s %9s %9s\n", label, "group", "n", "mean E", "bias %", "rRMSE %",
           "ref.noise", "lbk.noise", "excess %");
    double tn = 0, td = 0, tz = 0, to = 0;
    for (int g = 1; g < BSC_GROUPS; g++) {
        if (!cnt[g]) continue;
        if (g == BSC_SEALED || g == BSC_BURIED) {
            double mx = 0;
            size_t lit = 0;
            for (size_t i = 0; i < e->n; i++)
                if (e->group[i] == g) {
                    double a = lbk_at(irr, e->recv[i]);
                    lit += a > 0;
                    mx = fmax(mx, a);
                }
            printf("  %-14s %5zu  lit %zu, max %.4g (must be 0)\n", bsc_group_name[g], cnt[g], lit, mx);
            continue;
        }
        double ex = sqrt(fmax(0.0, num[g] - noise[g] - own[g]) / den[g]);
        printf("  %-14s %5zu %9.4f %+9.2f %9.2f %9.2f %9.2f %9.2f\n", bsc_group_name[g], cnt[g], sum[g] / cnt[g],
               100 * sgn[g] / sum[g], 100 * sqrt(num[g] / den[g]), 100 * sqrt(noise[g] / den[g]),
               100 * sqrt(own[g] / den[g]), irr2 ? 100 * ex : NAN);
        tn += num[g];
        td += den[g];
        tz += noise[g];
        to += own[g];
    }
    printf("  %-14s %5s %9s %9s %9.2f %9.2f %9.2f %9.2f\n", "room", "", "", "", 100 * sqrt(tn / td),
           100 * sqrt(tz / td), 100 * sqrt(to / td), irr2 ? 100 * sqrt(fmax(0.0, tn - tz - to) / td) : NAN);
}

/* The k receivers whose error is the most standard deviations (both noises) away from 0. */
static void print_worst(const eval_set *e, const float *irr, const float *irr2, int k)
{
    double *z = calloc(e->n, sizeof *z);
    for (size_t i = 0; i < e->n; i++) {
        if (e->group[i] == BSC_SEALED || e->group[i] == BSC_BURIED) continue;
        double a = lbk_at(irr, e->recv[i]), a2 = lbk_at(irr2, e->recv[i]), b = lum3d(e->ref + 3 * i);
        double sd = sqrt(e->se[i] * e->se[i] + 0.5 * (a - a2) * (a - a2) + 1e-12);
        z[i] = (0.5 * (a + a2) - b) / sd;
    }
    printf("  worst receivers (mean of both runs vs reference):\n");
    for (int w = 0; w < k; w++) {
        size_t bi = 0;
        for (size_t i = 1; i < e->n; i++)
            if (fabs(z[i]) > fabs(z[bi])) bi = i;
        if (z[bi] == 0) break;
        size_t i = bi;
        double a = lbk_at(irr, e->recv[i]), a2 = lbk_at(irr2, e->recv[i]), b = lum3d(e->ref + 3 * i);
        printf("   %-12s p (%.3f %.3f %.3f) n (%.2f %.2f %.2f): lbk %.4f ref %.4f (%+.1f %%, z %.1f)\n",
               bsc_group_name[e->group[i]], e->p[3 * i], e->p[3 * i + 1], e->p[3 * i + 2], e->nrm[3 * i],
               e->nrm[3 * i + 1], e->nrm[3 * i + 2], 0.5 * (a + a2), b, 100 * (0.5 * (a + a2) / b - 1), z[i]);
        z[bi] = 0;
    }
    free(z);
}

static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    a->density = 10;
    a->ref_paths = 4096;
    a->per = 40;
    a->cell_texels = 1;  /* as the pipeline: cells of one texel, texel footprints */
    a->footprint = 1;
    a->detail = 1;
    a->threads = 2;
    a->seed = 1;
    for (int i = 1; i < argc; i++) {
        const char *k = argv[i], *v = i + 1 < argc ? argv[i + 1] : "0";
        if (!strcmp(k, "--passes") && a->npasses < 8) a->passes[a->npasses++] = atoi(v), i++;
        else if (!strcmp(k, "--density")) a->density = atof(v), i++;
        else if (!strcmp(k, "--ref-paths")) a->ref_paths = atoi(v), i++;
        else if (!strcmp(k, "--per")) a->per = atoi(v), i++;
        else if (!strcmp(k, "--detail")) a->detail = atoi(v), i++;
        else if (!strcmp(k, "--threads")) a->threads = atoi(v), i++;
        else if (!strcmp(k, "--cells")) a->cells = atoi(v), i++;
        else if (!strcmp(k, "--cell-texels")) a->cell_texels = atof(v), i++;
        else if (!strcmp(k, "--seed")) a->seed = (uint64_t)atoll(v), i++;
        else if (!strcmp(k, "--ground")) a->ground = 1;
        else if (!strcmp(k, "--noise")) a->noise = 1;
        else if (!strcmp(k, "--footprint")) a->footprint = 1;
        else if (!strcmp(k, "--no-footprint")) a->footprint = 0;
        else if (!strcmp(k, "--ref-file")) a->ref_file = v, i++;
        else if (!strcmp(k, "--worst")) a->worst = atoi(v), i++;
        else { fprintf(stderr, "unknown argument %s\n", k); return 1; }
    }
    if (!a->npasses) { a->passes[0] = 3; a->passes[1] = 5; a->npasses = 2; }
    return 0;
}

/* The evaluation subset: up to `per` texels of each group, evenly spread over the group (the groups
 * with a reference first, then every texel of the ones that must be 0). */
static void pick_eval(const bk_texels *tx, const int *tgroup, const size_t *recv_of, int per, eval_set *e)
{
    size_t gcount[BSC_GROUPS] = {0};
    for (size_t i = 0; i < tx->count; i++) gcount[tgroup[i]]++;
    e->recv = calloc(tx->count, sizeof *e->recv);
    e->group = calloc(tx->count, sizeof *e->group);
    e->p = calloc(3 * tx->count, sizeof *e->p);
    e->fp_first = calloc(tx->count, sizeof *e->fp_first);
    e->fp_count = calloc(tx->count, sizeof *e->fp_count);
    e->nrm = calloc(3 * tx->count, sizeof *e->nrm);
    /* the groups with a reference first, then the ones that must be 0 (no reference needed) */
    size_t seen[BSC_GROUPS] = {0}, took[BSC_GROUPS] = {0};
    for (int phase = 0; phase < 2; phase++)
        for (size_t i = 0; i < tx->count; i++) {
            int g = tgroup[i], zero = g == BSC_SEALED || g == BSC_BURIED;
            if (g == BSC_OUTSIDE || zero != phase) continue;
            size_t want = zero ? gcount[g] : (size_t)per;
            /* take texel i when the running quota crosses an integer */
            size_t q = (seen[g] + 1) * want / gcount[g];
            seen[g]++;
            if (q <= took[g]) continue;
            took[g]++;
            const bk_texel *x = &tx->receivers[i];
            e->recv[e->n] = recv_of[i];
            e->group[e->n] = g;
            memcpy(e->p + 3 * e->n, x->position, 12);
            memcpy(e->nrm + 3 * e->n, x->normal, 12);
#ifndef BENCH_BIAS_ORIG
            e->fp_first[e->n] = x->footprint_first;
            e->fp_count[e->n] = x->footprint_count;
#endif
            e->n++;
        }
}

/* The transport options of run rep (0, or 1: the second seed of --noise) at a->passes[k]. */
static void pass_options(const args *a, int k, int rep, float *cell_size, const bk_texels *tx, bk_transport_options *o)
{
    memset(o, 0, sizeof *o);
    o->seed = a->seed + 1000 * (uint64_t)rep;
    o->threads = a->threads;
    o->target_error = -1;
    o->first_pass_samples = 16;
    o->max_samples = 2 * 16 * ((1 << a->passes[k]) - 1);
    o->max_cells = a->cells;
#ifndef BENCH_BIAS_ORIG
    if (cell_size) o->cell_size = cell_size;
    if (a->footprint) {
        o->footprint = tx->footprint;
        o->footprint_count = tx->footprint_count;
    }
#endif
}

/* BENCH_BIAS_DEBUG: where each evaluated buried texel sits, before and after push-out. */
static void print_buried(const bk_scene *s, const bk_texels *tx, const eval_set *e, const size_t *texel_of,
                         const float *orig, const float *irr)
{
    for (size_t q = 0; q < e->n; q++)
        if (e->group[q] == BSC_BURIED) {
            if (e->recv[q] == SIZE_MAX) continue;
            size_t ti = texel_of[e->recv[q]];
            const bk_texel *x = &tx->receivers[ti];
            printf("   buried %s: orig (%.3f %.3f %.3f) now (%.3f %.3f %.3f) n (%.2f %.2f %.2f) flags %u E %.4f\n",
                   s->objects[s->tri_object[x->tri]].name, orig[3 * ti], orig[3 * ti + 1], orig[3 * ti + 2],
                   x->position[0], x->position[1], x->position[2], x->normal[0], x->normal[1], x->normal[2],
                   x->flags, lbk_at(irr, e->recv[q]));
        }
}

int main(int argc, char **argv)
{
    args a;
    if (parse(argc, argv, &a)) return 2;
    bk_scene s;
    bsc_options so = {a.ground, a.detail};
    bsc_build(&s, &so);
    char err[128];
    if (rp_check(&s, err, sizeof err)) { fprintf(stderr, "%s\n", err); return 1; }
    bk_atlas at;
    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.default_density = (float)a.density;
    if (bk_atlas_build(&s, NULL, &ao, &at) != LBK_OK) { fprintf(stderr, "atlas failed\n"); return 1; }
    bk_tracer *t = NULL;
    if (bk_tracer_create(&s, 0, &t) != LBK_OK) { fprintf(stderr, "tracer failed\n"); return 1; }
    bk_texels tx;
    if (bk_texels_build(&s, &at, &tx) != LBK_OK) { fprintf(stderr, "texels failed\n"); return 1; }
    bk_pushout_options po;
    memset(&po, 0, sizeof po);
    po.threads = a.threads;
    bk_pushout_stats ps;
    float *orig = malloc(3 * (tx.count ? tx.count : 1) * sizeof *orig); /* centres before push-out */
    for (size_t i = 0; i < tx.count; i++) memcpy(orig + 3 * i, tx.receivers[i].position, 12);
    bk_texels_push_out(&tx, &s, t, &po, &ps);
    /* receivers: every valid texel, as the pipeline builds them */
    bk_receiver *r = calloc(tx.count, sizeof *r);
    size_t *texel_of = calloc(tx.count, sizeof *texel_of), *recv_of = calloc(tx.count, sizeof *recv_of);
    size_t nr = 0, inside_sealed = 0, sealed_total = 0, buried_total = 0, buried_inside = 0;
    int *tgroup = calloc(tx.count ? tx.count : 1, sizeof *tgroup);
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *x = &tx.receivers[i];
        /* grouped by the texel's own centre (before push-out): the same texels in every version */
        int g = bsc_group(&s, x->tri, orig + 3 * i, x->normal);
        if (bsc_solid_depth(orig + 3 * i) > 0.75 * x->texel_size) g = BSC_BURIED;
        tgroup[i] = g;
        if (g == BSC_SEALED) { sealed_total++; inside_sealed += !!(x->flags & BK_TEXEL_INSIDE); }
        if (g == BSC_BURIED) { buried_total++; buried_inside += !!(x->flags & BK_TEXEL_INSIDE); }
        recv_of[i] = SIZE_MAX;
        if (!(x->flags & BK_TEXEL_VALID)) continue;
        memcpy(r[nr].position, x->position, 12);
        memcpy(r[nr].normal, x->normal, 12);
#ifndef BENCH_BIAS_ORIG
        if (a.footprint) bk_receiver_from_texel(x, &r[nr]);
#endif
        recv_of[i] = nr;
        texel_of[nr++] = i;
    }
    printf("scene: %zu triangles; %zu texels (density %.3g/m), %zu valid receivers; push-out: %zu pushed, %zu "
           "inside; cavity texels %zu (%zu inside), buried texels %zu (%zu inside)\n",
           s.tri_count, tx.count, a.density, nr, ps.pushed, ps.inside, sealed_total, inside_sealed, buried_total,
           buried_inside);
    eval_set e;
    memset(&e, 0, sizeof e);
    pick_eval(&tx, tgroup, recv_of, a.per, &e);
    e.ref = calloc(3 * e.n, sizeof *e.ref);
    e.se = calloc(e.n, sizeof *e.se);
    /* the zero groups need no reference (and keep the cached one valid) */
    size_t ne = e.n;
    e.n = 0;
    for (size_t i = 0; i < ne; i++)
        if (e.group[i] != BSC_SEALED && e.group[i] != BSC_BURIED) e.n++;
    load_or_make_ref(&s, t, &e, a.ref_paths, a.threads, a.footprint ? &tx : NULL, a.ref_file);
    e.n = ne;

    float *cell_size = NULL;
    if (a.cell_texels > 0) {
        cell_size = malloc(s.tri_count * sizeof *cell_size);
        for (size_t i = 0; i < s.tri_count; i++) cell_size[i] = (float)(a.cell_texels / a.density);
    }
    lbk_sh9_rgb *rad = calloc(nr, sizeof *rad);
    float *irr = calloc(3 * nr, sizeof *irr);
    float *irr2 = a.noise ? calloc(3 * nr, sizeof *irr2) : NULL;
    for (int k = 0; k < a.npasses; k++) {
        bk_transport_stats st;
        double cpu = 0;
        for (int rep = 0; rep < (a.noise ? 2 : 1); rep++) {
            bk_transport_options o;
            pass_options(&a, k, rep, cell_size, &tx, &o);
            bk_transport_output out = {rad, NULL, rep ? irr2 : irr, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
            bk_transport_stats st1;
            double c0 = cpu_s();
            bk_transport_run(&s, t, r, nr, &o, &out, rep ? &st1 : &st);
            if (!rep) cpu = cpu_s() - c0;
        }
        char label[256];
#ifndef BENCH_BIAS_ORIG
        double est_bias = st.est_cache_bias;
#else
        double est_bias = NAN;
#endif
        snprintf(label, sizeof label,
                 "lbk %d passes: %.0f samples/receiver, %.2f s (%.1f CPU s), %zu cells, %d bounces, %.3g rays, est. error %.2f %%, "
                 "est. cache bias %.2f %%",
                 a.passes[k], st.samples_per_receiver, st.seconds, cpu, st.cells, st.bounces, (double)st.rays,
                 100 * st.est_rel_rmse, 100 * est_bias);
        report(&e, irr, irr2, label);
        if (getenv("BENCH_BIAS_DEBUG")) print_buried(&s, &tx, &e, texel_of, orig, irr);
        if (a.worst && irr2) print_worst(&e, irr, irr2, a.worst);
    }
    free(irr2);
    free(rad); free(irr); free(r); free(texel_of); free(recv_of); free(tgroup); free(orig); free(cell_size);
    free(e.fp_first); free(e.fp_count);
    free(e.recv); free(e.group); free(e.p); free(e.nrm); free(e.ref); free(e.se);
    bk_texels_free(&tx);
    bk_tracer_destroy(t);
    bk_atlas_free(&at);
    bk_scene_free(&s);
    return 0;
}
