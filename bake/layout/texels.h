/* Texel sample points ("receivers") of the lightmap atlas, their push-out from behind
 * walls, the per-texel tangent frame, and dilation.
 *
 * Coverage (bk_texels_build): every chart triangle is rasterised into its page. A texel is
 * covered when its centre lies inside a triangle (top-left fill rule, uv_raster.h) or, for
 * the texels along chart borders, when bilinear filtering at some point of a triangle reads
 * it: the triangle meets the open square of half-size 1 around the texel centre
 * (bk_rtri_meets_square). So every texel a renderer filters for a point of a chart holds a
 * baked sample of that chart (conservative rasterisation of the bilinear footprint: a ring of
 * one texel around the texels the chart overlaps, inside the chart's own margin, atlas.h).
 * A centre inside wins over a nearest point; among nearest points the closest wins; ties go
 * to the lower triangle entry. The sample point is the world point at the centre (or at the
 * triangle's closest point), its normal the interpolated shading normal (the geometric
 * normal where that is zero).
 *
 * TANGENT FRAME CONVENTION (the AHD encoder and the runtime must use the same; normative in
 * spec/container.md §5.6, lbk_ahd_tangent_frame in lbk/ahd.h computes it for renderers):
 *   N = the unit interpolated shading normal of the receiver (+Z of the local frame);
 *   T = dP/du of the triangle, P the world position and u the lightmap texel x coordinate
 *       (to the right on the page; uv.x), made orthogonal to N and unit length (+X);
 *   B = N × T (+Y), always right-handed: no handedness sign is stored, even for mirrored
 *       authored uv1 (for generated charts B points along +v, down the page).
 *   A world direction d has local coordinates (d·T, d·B, d·N). At runtime T is rebuilt
 *   from the lightmap uv derivatives (or a per-vertex tangent computed the same way) and
 *   B = cross(N, T). Where dP/du is undefined (zero uv area) T is the first vector of the
 *   branchless orthonormal basis of N (Duff et al. 2017, see bk_tangent_frame).
 *
 * Footprint: every triangle of the texel's own UV island that overlaps its square (exact
 * triangle/square overlap; an island: the chart's triangles joined to the texel's own by shared
 * UV edges where the surface has no crease, face normals within 40° — an authored layout is one
 * chart of many islands, often less than a texel apart, and a floor texel must not average in
 * the island next to it, perhaps the floor's underside; a generated chart may fold a table top's
 * thin rim beside the top, and the top's texels must not average in the rim), as the affine map from texel-local (s, t) to the triangle's
 * barycentrics (bk_footprint_tri). The light transport starts each gather ray from a random
 * point of the square that one of them covers, so a texel's value is the irradiance averaged
 * over the part of its square its chart covers, as a renderer's bake of the texel is (a chart
 * of many small triangles is not sampled at one point each; TRANSPORT.md §Footprint).
 *
 * Ring: a texel that bilinear filtering reads for points of its chart within a texel of the
 * chart's border, but whose own square the chart does not cover (no area; triangles that only
 * touch it do not count) has no footprint and is flagged BK_TEXEL_RING. It is baked at its
 * sample point, the chart's closest point to its centre (pushed out like any other), not left
 * to dilation: filtered at the chart points that read ring texels, the bias room
 * (bench/bench_ring.c) is 7.6 % from the reference with ring texels baked this way and 10.0 %
 * with them dilated from their chart's texels (14.9 / 18.5 % at 6 texels/m, 24.9 / 28.5 % at
 * 4): the border point extrapolates the chart's light to the ring's centre better than the
 * texels inside the chart do.
 *
 * Edge inset (edge_inset.h): an edge texel's point (the closest point of its triangle, on the
 * triangle's border) is moved 1 % of a texel inside the edges another surface may meet (a box
 * side standing on a floor, a crease), so its gather rays do not start on two surfaces at once.
 *
 * Push-out (bk_texels_push_out): the single sample point (which the transport still uses for
 * punctual lights where no footprint triangle covers a quarter centre, and for parts of the
 * square no triangle covers) is moved out from behind surfaces: from it, 8 rays along the
 * geometric tangent plane (raised by ~3°) and 5 over the hemisphere search `reach` texels
 * (default 1.5 texel sizes) for a BACK face (a ray arriving at the back of a triangle means
 * the point is behind that surface: under a wall, inside a box). The sample is moved just in
 * front of the closest such hit (bk_offset_ray_origin_scaled along that triangle's normal),
 * up to 3 times (corners) — but only to a hit within a tenth of a texel of its own plane and
 * onto its own face (its triangle, a footprint triangle, or for a point on a triangle's border
 * a coplanar triangle of its object under the new point): the point must stay on its texel,
 * never be carried through a wall to its far side (a shelf's end let into a wall is not moved
 * out of the wall's outer face into the sky). A texel whose square is partly hidden behind a
 * surface in front of it (a back face within the tenth of a texel along its normal, probed at
 * 4 × 4 points: a light panel hung just under a ceiling) loses its footprint and keeps its
 * pushed point: filtering would spread the hidden part's light over the visible surface beside
 * it (TRANSPORT.md, After the atlas merge). A texel whose square runs beyond another surface
 * seen from its point (a wall's square running into a sill set into the wall, a floor's under a
 * crate) keeps its footprint on its own side only: the cells (8 × 8) whose points lie beyond
 * are marked (footprint_hidden), the transport draws no sample there, and near the covering
 * surface's edge tests each sample itself (bk_footprint_sample_hidden). Then 16 long
 * hemisphere rays: when at least half of them end on back faces the point is inside closed
 * geometry: BK_TEXEL_INSIDE is set (information only: the texel is still baked, and the
 * transport makes the inside of closed solids black, so a face sealed inside a wall bakes to
 * 0 as it does in a path tracer, instead of being dilated from lit neighbours). Orientation
 * is the triangle winding (glTF front = counter-clockwise), also for double-sided materials:
 * a closed mesh's interior is its back side either way.
 *
 * Dilation (bk_dilate): works on any per-texel payload (N floats per texel). */
#ifndef BK_TEXELS_H
#define BK_TEXELS_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "bake/layout/atlas.h"
#include "scene/scene.h"
#include "scene/tracer.h"
#include "bake/transport/transport.h"

#ifdef __cplusplus
extern "C" {
#endif

enum bk_texel_flag {
    BK_TEXEL_VALID = 1u,   /* light this sample */
    BK_TEXEL_EDGE = 2u,    /* centre outside every triangle: sample at the nearest point,
                              moved 1 % of a texel inside (Edge inset above) */
    BK_TEXEL_PUSHED = 4u,  /* moved out from behind a surface */
    BK_TEXEL_INSIDE = 8u,  /* its point is inside closed geometry (information; still valid) */
    BK_TEXEL_RING = 16u    /* read only by bilinear filtering (its chart does not cover its square):
                              baked at its point, no footprint (see Ring above; still valid) */
};

typedef struct bk_texel {
    float position[3];     /* world sample point */
    float normal[3];       /* unit shading normal (+Z of the tangent frame) */
    float tangent[3];      /* unit, ⟂ normal, along +u (see the convention above) */
    float texel_size;      /* metres spanned by one texel here */
    uint32_t object;       /* scene object */
    uint32_t tri;          /* scene triangle */
    uint32_t page;
    uint16_t x, y;         /* texel in the page */
    uint32_t flags;        /* enum bk_texel_flag */
    uint32_t footprint_first, footprint_count; /* its chart's triangles over its square, in
                                                  bk_texels.footprint (see Footprint above) */
    float footprint_box[4];  /* s0, t0, width, height: the part of its square they cover lies in
                                it (bk_receiver.footprint_box) */
    uint64_t footprint_hidden; /* cells of the square behind another surface (bk_receiver) */
} bk_texel;

typedef struct bk_texels {
    size_t page_count;
    bk_atlas_page *pages;  /* copy of the atlas page sizes */
    size_t *page_offset;   /* page_count + 1: start of each page in index */
    int32_t *index;        /* per texel of every page (row-major): receiver, or -1 */
    size_t count;
    bk_texel *receivers;/* page-major, then row-major: deterministic order */
    size_t footprint_count;
    bk_footprint_tri *footprint; /* grouped by texel, in receiver order */
} bk_texels;

/* Rasterises every chart of the atlas. Errors: LBK_ERR_INVALID_ARGUMENT,
 * LBK_ERR_OUT_OF_MEMORY, LBK_ERR_LIMIT (page side > 65535). */
lbk_result bk_texels_build(const bk_scene *scene, const bk_atlas *atlas, bk_texels *out);
void bk_texels_free(bk_texels *tx);

/* The receiver at texel (x, y) of a page, or NULL when the texel is empty. */
const bk_texel *bk_texels_at(const bk_texels *tx, uint32_t page, int x, int y);

typedef struct bk_pushout_options {
    float reach;           /* search distance in texel sizes; 0: 1.5 */
    int threads;           /* 0: all online cores (the result is the same for any count) */
} bk_pushout_options;

typedef struct bk_pushout_stats {
    size_t tested, pushed, inside;
} bk_pushout_stats;

/* Moves sample points out from behind surfaces and marks those inside geometry (see
 * above). The result does not depend on the thread count. stats may be NULL. */
lbk_result bk_texels_push_out(bk_texels *tx, const bk_scene *scene, const bk_tracer *tracer,
                              const bk_pushout_options *opt, bk_pushout_stats *stats);

/* Fills mask (width × height of the page) with 1 for valid receivers, 0 elsewhere. */
void bk_texels_valid_mask(const bk_texels *tx, uint32_t page, uint8_t *mask);

/* The transport's receiver for texel t: its point, normal and footprint (box and hidden cells). */
void bk_receiver_from_texel(const bk_texel *t, bk_receiver *r);

/* T and B from unit N and dP/du per the convention above (t, b unit, b = n × t). */
void bk_tangent_frame(const float n[3], const float dpdu[3], float t[3], float b[3]);

/* Dilation of a page-sized payload: data has `channels` floats per texel, row-major; mask
 * has one byte per texel, non-zero = holds a value. Each pass fills every empty texel that
 * has a filled 4-neighbour with the mean of those 4-neighbours, or else, with a filled
 * diagonal neighbour, the mean of those (neighbours filled before this pass only, so the
 * result does not depend on the scan order). After `passes` passes every empty texel within
 * Chebyshev distance `passes` of a filled one is filled (mask set to 2), none further.
 * Returns the number of texels filled. Use passes >= the atlas margin (padding / 2) so
 * bilinear filtering never reads an empty texel; more passes also fill the gaps between
 * charts, which helps block compression. */
size_t bk_dilate(float *data, int channels, uint8_t *mask, int width, int height, int passes);

#ifdef __cplusplus
}
#endif
#endif
