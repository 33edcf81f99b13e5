/* Small synthetic containers for the diff/convert/export tests, built with the library builders
 * (no baker needed). Everything is deterministic: the same options give the same bytes.
 *
 * The scene (TF_SCENE_FULL):
 *   META   writer=lbk-test, bake.samples=64 (or opt->samples), scene.hash
 *   REPT   two records
 *   OBJS   "floor" page 0 rect (0,0,32,32); "wall" page 0 rect (32,0,32,16);
 *          "crate" page 1 rect (0,0,16,16); "lamp-shade" representation none
 *   LMAP   page 0 64×32, page 1 16×16; texel lighting tf_texel_linear()
 *   GLG    8 probes on the corners of the box [0,4]×[0,2]×[0,3], 5 tetras; probe SH tf_probe_sh()
 *   DLS    set "lamp" (lights "lamp.bulb"): entries on the texels of the crate and on GLG probes
 *          0 and 7
 *   OCTP   only when opt->octp_dims: a one-level volume octp_dims × 2 × 2, origin 0, spacing 1,
 *          every probe active; irradiance tf_octp_irradiance(), depth mean m = 1 + (t mod 64)/256,
 *          mean² m² */
#ifndef LBK_TESTS_TOOLS_FIXTURES_H
#define LBK_TESTS_TOOLS_FIXTURES_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/ahd.h"
#include "lbk/sh.h"

enum { TF_SCENE_FULL = 0, TF_SCENE_LMAP_ONLY = 1 /* OBJS + LMAP only */ };

typedef struct tf_options {
    /* Multiply irradiance of texel (page, x, y) by texel_factor when texel_factor != 0. */
    float texel_factor;
    uint32_t texel_page, texel_x, texel_y;
    /* Add texel_delta to the R, G and B of plane 0 of that texel instead, when non-zero
     * (re-encoded: the decoded change is the R11G11B10F-rounded delta). */
    float texel_delta;
    uint32_t samples;          /* bake.samples in META; 0: 64 */
    int drop_crate;            /* leave "crate" out of OBJS (its texels stay) */
    int rename_wall;           /* "wall" becomes "wall-renamed" (same geometry hash) */
    int move_crate_geometry;   /* "crate" gets another geometry hash */
    float probe_scale;         /* multiply GLG probe 3's SH by this when != 0 */
    uint32_t page0_width;      /* 0: 64 */
    int scale_log2;            /* LMAP and GLG scale 2^scale_log2 (spec §5.7), DLS payloads stored in
                                  it: the same physical lighting in other stored units */
    uint32_t octp_dims;        /* OCTP volume octp_dims × 2 × 2 when != 0 (2 … 256) */
    float octp_factor;         /* multiply OCTP probe octp_probe's irradiance by this when != 0 */
    uint32_t octp_probe;
    float octp_depth_delta;    /* add to probe octp_probe's depth mean (mean² stays its square) */
    uint32_t octp_inside;      /* 1 + index of an OCTP probe marked inside geometry; 0: none */
} tf_options;

typedef struct tf_blob {
    void *data;
    size_t size;
} tf_blob;

tf_blob tf_build_scene(int kind, const tf_options *options);
void tf_blob_free(tf_blob *blob);

/* The lighting the scene encodes, for tests that compare with what they decode. */
void tf_texel_linear(uint32_t page, uint32_t x, uint32_t y, lbk_ahd_linear *out);
void tf_probe_sh(uint32_t probe, lbk_sh9_rgb *out);
extern const float tf_probe_positions[8][3];
/* OCTP interior texel t (0 … 15) of probe p, channel c. */
float tf_octp_irradiance(uint32_t p, uint32_t t, int c);

#endif
