/* Lightmap seams: mesh edges that the atlas maps to two different places.
 *
 * A seam edge is an edge of one object's mesh (corners welded by exact position) shared by
 * exactly two triangles whose lightmap coordinates of the edge differ: the edge lies on the
 * border of two charts, or of two islands of an authored TEXCOORD_1 layout. A renderer
 * filters each side bilinearly in its own place, so unless the texels around both places
 * agree the edge shows as a line. Seams are "smooth" when the shading normals of the two
 * sides agree at both ends (the light is continuous there and must look so); across a crease
 * (different normals) the light differs by nature and seams are left alone.
 *
 * Point t ∈ [0, 1] of a seam maps to uv[s][0..1] + t·(uv[s][2..3] − uv[s][0..1]) on side s:
 * both sides describe the same world point. Bilinear filtering follows atlas.h: texel (x, y)
 * has its centre at (x + 0.5, y + 0.5), addressing clamps to the page.
 *
 * Score (bk_seams_score): along every smooth seam, points at t = (i + 0.5)/n with n = max(2,
 * ceil(2 × the longer side's length in texels)); at each the relative jump
 * |L0 − L1| / max((L0 + L1)/2, L̄/16) of the two sides' bilinearly filtered luminance, L̄ the
 * mean of (L0 + L1)/2 over all the points (so that near-black points, e.g. at a shadow
 * terminator, count by their absolute jump against 1/16 of the seams' light level instead of
 * blowing up); the mean weighted by world length (points where the denominator is 0 are
 * skipped).
 *
 * Stitching (bk_seams_stitch): least-squares seam optimisation after Iwanicki ("Lighting
 * Technology of The Last of Us", SIGGRAPH 2013; also S. Sylvan, "Fixing Texture Seams With
 * Linear Least-Squares", 2015, and ands/seamoptimizer, which likewise stitches only edges whose
 * normals agree; Unity's "Stitch Seams" is the same feature, also per object only): the texels
 * read by bilinear filtering at the score's points become unknowns x, and
 *     minimise Σ_points |R·f0(x) − f1(x)|² + λ Σ_texels |x − x0|²,   λ = 1/4096,
 * where f_s is side s's bilinear filter and R turns side 0's tangent-plane components into
 * side 1's frame (texels.h convention: the two frames share N and differ by a rotation about
 * it). Each object's system splits into its connected components (taps no point links are
 * independent); each is solved on its own by Jacobi-preconditioned conjugate gradients on the
 * normal equations, in double, in a fixed order — components in parallel, deterministic at any
 * thread count. The solve stops when it can no longer change what the encoder stores: the RMS
 * mismatch at the points below 2^-10 of the RMS light there (8× below R11G11B10F's rounding),
 * or four iterations gaining less than 1/16 of that in the objective (seams that cannot match
 * better), at the latest at 1e-4 of the first residual. The encoder stores the irradiance
 * along the normal clamped at 0, so a colour whose e0 + g.z comes out negative is then held at
 * 0 by a penalty row (weight² 16) and the system solved again (up to 4 rounds). The mismatch is
 * linear in the texels, so when the base bake and each dynamic set are stitched separately,
 * any weighted sum of them agrees across seams too (to the same precision). */
#ifndef BK_SEAMS_H
#define BK_SEAMS_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "bake/layout/atlas.h"
#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bk_seam {
    uint32_t entry[2];   /* atlas triangle entries (bk_atlas.tris) of side 0 and side 1 */
    uint32_t slot;       /* atlas object (bk_atlas.objects) */
    uint32_t page;       /* both sides: one object is on one page */
    float uv[2][4];      /* side s: the edge's ends (x0, y0, x1, y1), page texel coordinates */
    float rot[2];        /* cos, sin: side 0's tangent-plane (x, y) → side 1's frame */
    float length;        /* world metres */
    uint8_t smooth;      /* shading normals agree at both ends (dot ≥ 0.999) */
} bk_seam;

typedef struct bk_seams {
    size_t count, smooth_count;
    bk_seam *seams;      /* object by object (atlas order), then by edge: deterministic */
} bk_seams;

/* Finds the seams of every atlas object. Errors: LBK_ERR_INVALID_ARGUMENT,
 * LBK_ERR_OUT_OF_MEMORY. */
lbk_result bk_seams_find(const bk_scene *scene, const bk_atlas *atlas, bk_seams *out);
void bk_seams_free(bk_seams *seams);

/* The 4 texels (row-major page index) and weights bilinear filtering reads at page texel
 * coordinate (x, y), clamped to the page. */
void bk_bilinear_taps(double x, double y, int width, int height, int32_t idx[4], double w[4]);

/* Sample count along a seam (see the score above). */
int bk_seam_points(const bk_seam *seam);

typedef struct bk_seam_score {
    double mean;         /* length-weighted mean relative jump */
    double max;          /* largest relative jump */
    size_t points;       /* points that counted */
    size_t seams;        /* smooth seams */
    double length;       /* their world length, metres */
} bk_seam_score;

/* Score over the smooth seams from per-page luminance (lum[p]: width × height floats of page
 * p, pages as in the atlas). */
void bk_seams_score(const bk_seams *seams, const bk_atlas_page *pages, size_t page_count, const float *const *lum,
                    bk_seam_score *out);

/* Stitches the smooth seams of one page in place, object by object (objects own disjoint
 * texels: one system each, solved on up to `threads` threads, 0: all cores; the result does
 * not depend on the count). data: 12 floats per texel in lbk_ahd_linear order ({e0, g.x,
 * g.y, g.z} per colour, tangent space), row-major; mask: non-zero where a texel holds a value
 * (a point whose filter reads an empty texel is left out). Returns the number of texels
 * changed, or (size_t)-1 when out of memory (then objects may be partly stitched). */
size_t bk_seams_stitch(const bk_seams *seams, uint32_t page, int width, int height, float *data,
                       const uint8_t *mask, int threads);

#ifdef __cplusplus
}
#endif
#endif
