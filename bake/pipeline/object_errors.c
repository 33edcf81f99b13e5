/* Each lightmapped object's estimated error (lbk_bake_object_estimate): the bake's texel
 * estimate — the two halves' difference, through the denoiser's weights where the texels are
 * stored denoised — summed over one object's texels instead of the whole level's.
 *
 * Why: the level's figure is normalised by the RMS over every texel, so the large bright
 * surfaces (a sky-lit floor) set it, and a table, a sill or a dark room's walls can carry many
 * times the error the level reports (bench/levels measured 2.4 % on a bench seat of a level
 * whose bake reported 1.0 %). The object is what an artist looks at and what the Cycles
 * harness measures per row. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/denoise/denoise.h"
#include "bake/pipeline/pipeline.h"

lbk_result bk_object_estimates(bk_pipeline *b)
{
    const size_t n = b->texel_receivers, no = b->scene.object_count;
    if (!b->halves || !n || !no) return LBK_OK;
    uint32_t *group = malloc(n * sizeof *group);
    bk_denoise_group_error *e = calloc(no, sizeof *e);
    b->object_est = calloc(no, sizeof *b->object_est);
    lbk_result r = group && e && b->object_est ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < n && !r; i++) {
        const bk_texel *t = &b->texels.receivers[b->texel_of_receiver[i]];
        group[i] = t->object < no ? t->object : UINT32_MAX;
    }
    const struct bk_denoiser *d = b->have_denoised && b->denoised.texels_filtered ? b->denoiser : NULL;
    if (!r) r = bk_denoiser_group_errors(d, b->halves, n, group, no, e);
    for (size_t o = 0; o < no && !r; o++) {
        lbk_bake_object_estimate *x = &b->object_est[o];
        x->name = b->scene.objects[o].name;
        x->object = (uint32_t)o;
        x->texels = (uint32_t)e[o].receivers;
        x->rel_rmse = e[o].rel_rmse;
        x->noise = e[o].noise;
        x->bias = e[o].bias;
        x->value2 = e[o].value2;
    }
    free(group);
    free(e);
    return r ? bk_pipeline_failed(b, r, "estimating each object's error") : LBK_OK;
}
