/* GIBS-style octahedral probes (seed 003) at the GLG probe positions: 4×4 irradiance texels
 * from each probe's baked SH9 radiance, and 12×12 depth moments (mean distance and mean squared
 * distance to the nearest surface in the texel's cone) traced with the scene's tracer. */
#ifndef BK_OCTA_BAKE_H
#define BK_OCTA_BAKE_H

#include <stddef.h>

#include "bake/transport/tracer.h"
#include "lbk/octa.h"
#include "lbk/sh.h"

/* Rays per depth texel (stratified over the texel); distances are capped at max_distance, the
 * value a miss records. Deterministic and independent of threads (single-threaded: cheap). */
#define BK_OCTA_DEPTH_RAYS 4

void bk_octa_probe(const bk_tracer *tracer, const float position[3], const lbk_sh9_rgb *radiance,
                   float max_distance, lbk_octp_probe_desc *out);

#endif
