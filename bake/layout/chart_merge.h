/* Merging small generated charts into a neighbour (part of the lightmap parametrisation,
 * uvgen.c; not a public API).
 *
 * A chart is small when its content (ceil of its extent) has at most SMALL_AREA = 16 texels
 * or is one texel thin: it is then mostly border, and its own margin ring costs more texels
 * than it holds. Small charts are visited smallest first (ties: chart order); each is unfolded
 * onto the neighbour chart it shares the longest edge with (then the next ones): starting at
 * that edge, every triangle is laid down across an edge of an already placed one by the
 * similarity that maps the edge's world segment onto its chart segment (a hinge: lengths and
 * angles kept, the scale of the hinge edge). So the shared edges stop being seams. A hinge
 * folded by more than 60° (a hard edge: filtering across it would mix the light of two faces)
 * is only crossed by a tiny chart (at most 4 texels of content: no texel of its own to lose);
 * so a bevel merges, a 90° door jamb one texel wide does not. The merge
 * is kept only when every laid triangle keeps the chart's orientation, no two triangles of the
 * merged chart overlap (separating axis test, tolerance 1e-4 texel), the hinge scale is within
 * a factor 2 of the chart's density, the merged chart stays within max_chart_texels, and the
 * merged chart's block (content plus a 1-texel ring) is smaller than the two blocks were.
 * The merged chart is moved to the origin and turned landscape like any chart. Deterministic. */
#ifndef BK_CHART_MERGE_H
#define BK_CHART_MERGE_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "bake/layout/uvgen.h"
#include "scene/scene.h"

typedef struct bk_chart_graph {
    uint32_t first, n;               /* the object's triangle range */
    const uint32_t *wid;             /* welded position id per corner (3n), UINT32_MAX: dead */
    const uint32_t *adj_start, *adj; /* triangles sharing an edge, CSR over local indices */
} bk_chart_graph;

/* Merges small charts of o (generated: every triangle counter-clockwise in chart
 * coordinates) in place; *merged receives how many charts went into another. */
lbk_result bk_merge_small_charts(const bk_scene *s, const bk_chart_graph *g, double density, int cap,
                                 bk_uv_object *o, size_t *merged);

#endif
