/* The lightmap half of the bake pipeline for a bk_scene built in C (tests and benches): every
 * object lightmapped at one texel density, atlas, texels, push-out, and the valid texels as
 * transport receivers (numbered as bake.c numbers them). Also the contact-shadow scene of the
 * denoiser tests with its independently integrated direct irradiance. Aborts on failure (tests
 * only). */
#ifndef LMF_LIGHTMAP_FIXTURE_H
#define LMF_LIGHTMAP_FIXTURE_H

#include <stddef.h>
#include <stdint.h>

#include "bake/layout/atlas.h"
#include "bake/layout/texels.h"
#include "scene/scene.h"
#include "scene/tracer.h"
#include "bake/transport/transport.h"

typedef struct lmf {
    bk_atlas atlas;
    bk_texels texels;
    bk_tracer *tracer;
    size_t count;                  /* valid texels = receivers */
    bk_receiver *receivers;
    uint32_t *texel_of_receiver;
} lmf;

void lmf_build(const bk_scene *s, float density, lmf *f);
void lmf_free(lmf *f);

/* The contact-shadow scene: a floor z = 0 over [-1, 1]² facing +z; a black slab standing on it,
 * x in [0, LMF_SLAB_T], y in [-LMF_SLAB_W, LMF_SLAB_W], z in [0, LMF_SLAB_H]; a one-sided square
 * emitter of side LMF_EM_SIDE facing down at height LMF_EM_Z, centred at (LMF_EM_X, 0), radiance
 * LMF_LE (grey). Every albedo is `albedo` (0: the floor's irradiance is the emitter's direct
 * light alone, which lmf_contact_irradiance integrates). No sky, no punctual light. */
#define LMF_SLAB_T 0.0625f
#define LMF_SLAB_W 0.5f
#define LMF_SLAB_H 0.25f
#define LMF_EM_SIDE 0.6f
#define LMF_EM_X (-0.3f)
#define LMF_EM_Z 1.0f
#define LMF_LE 10.0f
void lmf_contact_scene(bk_scene *s, float albedo);

/* Direct irradiance at floor point (x, y, 0) from the emitter, with the slab's occlusion when
 * `occluded` (else the open floor's), integrated on an m×m midpoint grid over the emitter with
 * an exact segment–box test: an estimator that shares nothing with the baker's. */
double lmf_contact_irradiance(double x, double y, int m, int occluded);

#endif
