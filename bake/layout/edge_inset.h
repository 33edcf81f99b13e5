/* Edge texels' sample points, moved just inside their triangle.
 *
 * An edge texel (BK_TEXEL_EDGE: a ring texel, a texel of a face thinner than a texel, a texel
 * whose centre falls in a gap of its chart) is sampled at its triangle's closest point to the
 * texel centre: a point ON the triangle's border. Where another surface meets that border the
 * point lies on that surface too: the Cornell tall box's side faces stand on the floor and meet
 * its top along a crease. A gather ray from there grazes the other surface at t ≈ 10⁻¹³ and
 * whether it hits depends on the last bit of the origin: measured on the tall box (preset
 * fast), a ring texel on the floor contact read 0 (every upward ray hit the floor's underside,
 * every downward one left beneath it) where Cycles reads 0.023, and one on the top crease read
 * 0.082 (rays hit the bright top at t ≈ 0) beside 0.028; the other ring texels of the same
 * crease were right. So each edge texel's point moves, in its triangle's plane, 1 % of a texel
 * (at most half the triangle's inradius) in from every edge where another surface may meet it:
 * every edge but a diagonal inside a flat face (a coplanar triangle of the same object on the
 * same welded edge), whose coplanar neighbour's outer edges count instead (the bottom edge of a
 * quad, for a point in the quad's other triangle at the corner). 1 % of a texel changes nothing
 * a texel resolves; the point is now on one surface only. Not towards the centroid: on a sliver
 * (a rug's 12 mm side face, 2.2 m long) the centroid lies along the face, 0.01 mm above the floor
 * it stands on. Runs before the push-out (texels.h), which still moves points from behind walls. */
#ifndef BK_EDGE_INSET_H
#define BK_EDGE_INSET_H

#include "lbk/lbk.h"
#include "bake/layout/texels.h"
#include "scene/scene.h"

/* Moves the point of every BK_TEXEL_EDGE receiver of tx (see above); deterministic.
 * Errors: LBK_ERR_INVALID_ARGUMENT, LBK_ERR_OUT_OF_MEMORY, LBK_ERR_LIMIT (over 2^32/3 triangles). */
lbk_result bk_texels_inset_edges(bk_texels *tx, const bk_scene *scene);

#endif
