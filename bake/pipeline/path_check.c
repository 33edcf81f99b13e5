/* The path check's two ends in the pipeline (TRANSPORT.md §Path check): which texels the base
 * run traces by unbiased paths, and, once the texels are as stored (after the denoiser), each
 * object's error measured against them.
 *
 * Why per object: the noise estimate cannot see what both halves get wrong alike (a slab thinner
 * than a cache cell, a cell straddling a shadow edge), and that error sits on particular
 * objects — a table top, a sill — not spread over the level. A few texels of every object,
 * traced without the cache, measure the stored value's whole error there: noise, denoiser
 * bias and the cache's systematic part together. */
#include <math.h>
#include <stdlib.h>

#include "bake/encode/encode.h"
#include "bake/pipeline/pipeline.h"
#include "bake/transport/shading.h"
#include "bake/util/rng.h"

lbk_result bk_check_plan(bk_pipeline *b)
{
    const size_t n = b->texel_receivers, no = b->scene.object_count;
    const int per = b->opt->path_check;
    if (per < 0 || b->dist || !n || !no || no > UINT32_MAX) return LBK_OK;
    const size_t k = per > 0 ? (size_t)per : BK_CHECK_PER_OBJECT, slots = no * k;
    uint32_t *group = bk_texel_object_groups(b);
    b->check_group = calloc(b->receiver_count, sizeof *b->check_group);
    b->check = malloc(slots * sizeof *b->check);
    b->check_weight = calloc(slots, sizeof *b->check_weight);
    b->check_irradiance = calloc(3 * slots, sizeof *b->check_irradiance);
    b->check_variance = calloc(slots, sizeof *b->check_variance);
    if (!group || !b->check_group || !b->check || !b->check_weight || !b->check_irradiance || !b->check_variance) {
        free(group);
        return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    }
    /* lightmap texels only: the LLG fit's targets and the probes are not checked */
    for (size_t i = 0; i < b->receiver_count; i++) b->check_group[i] = i < n ? group[i] : UINT32_MAX;
    free(group);
    b->check_per_object = k;
    b->check_count = slots;
    return LBK_OK;
}

/* The stored irradiance's luminance at texel receiver i: the AHD form's value along the texel's
 * normal (band-1 irradiance, which the transport's direct estimate set: bk_texel_match_irradiance),
 * after the denoiser, as the container gets it. */
static double stored_luminance(const bk_pipeline *b, size_t i)
{
    lbk_ahd_linear lin;
    bk_texel_linear(&b->texels.receivers[b->texel_of_receiver[i]], &b->radiance[i], &lin);
    double e[3];
    for (int c = 0; c < 3; c++) e[c] = (double)lin.c[c][0] + lin.c[c][3];
    return bk_lum(e);
}

/* Per object, over its slots: x_j = K·weight_j·d_j with d = (stored − path)² − var(path), each an
 * unbiased estimate of Σ_i (stored_i − true_i)² over the object's texels (the draw's weight
 * undoes its probability); their mean and standard error. */
typedef struct check_sums { double x, x2; size_t k; } check_sums;

static void fold_object(lbk_bake_object_estimate *e, lbk_bake_object_check *ck, const check_sums *s)
{
    const double k = (double)s->k, sum_sq = s->x / k;
    const double sd = s->k > 1 ? sqrt(fmax(0.0, (s->x2 - s->x * s->x / k) / (k - 1))) : fabs(sum_sq);
    const double se = sd / sqrt(k), den = e->value2;
    ck->receivers = (uint32_t)s->k;
    ck->rel_rmse = den > 0 ? sqrt(fmax(0.0, sum_sq) / den) : 0;
    ck->low = den > 0 ? sqrt(fmax(0.0, sum_sq - se) / den) : 0;
    ck->high = den > 0 ? sqrt(fmax(0.0, sum_sq + se) / den) : 0;
    /* what the noise estimate could not see; the object's figure the larger of the two */
    e->rel_rmse = fmax(e->rel_rmse, ck->rel_rmse);
}

lbk_result bk_check_compare(bk_pipeline *b)
{
    const size_t no = b->scene.object_count, K = b->check_per_object;
    if (!b->check_count || !b->object_est || !K) return LBK_OK;
    check_sums *s = calloc(no, sizeof *s);
    b->object_check = calloc(no, sizeof *b->object_check);
    if (!s || !b->object_check) {
        free(s);
        return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    }
    size_t checked = 0;
    for (size_t j = 0; j < b->check_count; j++) {
        const uint32_t i = b->check[j], o = (uint32_t)(j / K);
        if (i == UINT32_MAX || o >= no) continue;
        const double path = bk_lumf(&b->check_irradiance[3 * j]);
        const double diff = stored_luminance(b, i) - path, d = diff * diff - b->check_variance[j];
        const double x = (double)K * b->check_weight[j] * d;
        s[o].x += x;
        s[o].x2 += x * x;
        s[o].k++;
        checked++;
    }
    double num = 0, den = 0;
    for (size_t o = 0; o < no; o++) {
        if (!s[o].k || !b->object_est[o].texels) continue;
        fold_object(&b->object_est[o], &b->object_check[o], &s[o]);
        /* pooled like the noise estimate: Σ squared errors over Σ E² */
        num += b->object_check[o].rel_rmse * b->object_check[o].rel_rmse * b->object_est[o].value2;
        den += b->object_est[o].value2;
    }
    free(s);
    b->check_level = den > 0 ? sqrt(num / den) : 0;
    b->check_done = checked;
    return LBK_OK;
}
