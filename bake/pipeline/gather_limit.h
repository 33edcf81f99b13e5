/* The final gather's ray-length limit with probe fallback (lbk_bake_desc.gather_limit; seed 003:
 * "sample probes when coverage is low", GIBS' short surfel rays that read the clipmap probes at
 * their end): the GLG's probes are gathered first, in a run of their own, and the base run's
 * surface rays that hit nothing within the limit read that GLG's SH9 (liblbk's own tetrahedral
 * walk, lbk_glg_sample) at their end point. Measured: bake/transport/TRANSPORT.md §Ray-length
 * limit. */
#ifndef BK_GATHER_LIMIT_H
#define BK_GATHER_LIMIT_H

#include "bake/pipeline/pipeline.h"
#include "bake/transport/transport.h"
#include "lbk/glg.h"

typedef struct bk_far_probes {
    void *bytes;          /* a GLG section in the scene's frame (lbk_glg_build) */
    lbk_glg_view view;
} bk_far_probes;

/* Gathers the pipeline's GLG probes (receivers [glg_first, llg_first)) with `base`'s options (one
 * receiver class, no octahedral points, no limit, the radiosity cache at its default budget of
 * cells rather than lightmap-fine) and builds the section. LBK_OK with
 * out->bytes NULL when the bake has no GLG. */
lbk_result bk_far_probes_bake(const bk_pipeline *b, const bk_transport_options *base, bk_far_probes *out);
/* bk_transport_options.far_radiance over a bk_far_probes (user): inside the GLG's hull the SH9 at
 * x evaluated towards d, clamped at 0 (SH9 rings below zero near bright sources), and 1; outside
 * it 0 (the GLG covers the level's free space only: a ray from an outer wall into the open sky
 * would read the clamped inside probes). */
int bk_far_probes_radiance(void *user, const double x[3], const double d[3], uint32_t *hint, double L[3]);
void bk_far_probes_free(bk_far_probes *f);

#endif
