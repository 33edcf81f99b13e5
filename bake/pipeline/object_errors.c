/* Each lightmapped object's estimated error (lbk_bake_object_estimate): the bake's texel
 * estimate — the two halves' difference, through the denoiser's weights where the texels are
 * stored denoised — summed over one object's texels instead of the whole level's.
 *
 * Why: the level's figure is normalised by the RMS over every texel, so the large bright
 * surfaces (a sky-lit floor) set it, and a table, a sill or a dark room's walls can carry many
 * times the error the level reports (bench/levels measured 2.4 % on a bench seat of a level
 * whose bake reported 1.0 %). The object is what an artist looks at and what the Cycles
 * harness measures per row. */
#include <stdlib.h>

#include "bake/denoise/denoise.h"
#include "bake/pipeline/pipeline.h"

uint32_t *bk_texel_object_groups(const bk_pipeline *b)
{
    const size_t n = b->texel_receivers, no = b->scene.object_count;
    uint32_t *group = malloc((n ? n : 1) * sizeof *group);
    for (size_t i = 0; group && i < n; i++) {
        const uint32_t o = b->texels.receivers[b->texel_of_receiver[i]].object;
        group[i] = o < no ? o : UINT32_MAX;
    }
    return group;
}

lbk_result bk_object_estimates(bk_pipeline *b)
{
    const size_t n = b->texel_receivers, no = b->scene.object_count;
    if (!b->halves || !n || !no) return LBK_OK;
    b->object_est = calloc(no, sizeof *b->object_est);
    bk_denoise_group_error *e = b->object_filtered; /* from the denoised estimate's own pass */
    bk_denoise_group_error *own = NULL;
    uint32_t *group = NULL;
    lbk_result r = b->object_est ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    if (!r && !(b->have_denoised && b->denoised.texels_filtered && e)) { /* stored unfiltered */
        group = bk_texel_object_groups(b);
        e = own = calloc(no, sizeof *own);
        const bk_denoise_groups g = {n, group, no, own};
        r = group && own ? bk_denoise_groups_unfiltered(b->halves, &g) : LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t o = 0; o < no && !r; o++)
        b->object_est[o] = (lbk_bake_object_estimate){NULL, (uint32_t)o, (uint32_t)e[o].receivers, e[o].rel_rmse,
                                                      e[o].noise, e[o].bias, e[o].value2};
    free(group);
    free(own);
    return r ? bk_pipeline_failed(b, r, "estimating each object's error") : LBK_OK;
}
