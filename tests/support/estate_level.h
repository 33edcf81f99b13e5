/* A synthetic level the size of seed 001's ESTATE (Table 1: 2,637,824 lightmap texels, 229,725 GLG
 * and 50,805 LLG probes, 132 light sets; 28 MB without and 77 MB with the sets) for the DLS
 * benchmarks: texels in three pages (2 × 1024², 1024 × 528); 116 "room" sets, each a cluster of
 * 10–16 charts (rectangles of 12–96 texels a side) around a centre, plus 16 "hall" sets
 * overlapping one region 12–16 deep (the seed's stealth level; its Fig. 5: most receivers see few
 * sets, a few see many); probes in intervals of the probe order around the room's place. The
 * overlaps come out Poisson-like, about 1.5 sets per target, which puts the DLS payload near the
 * seed's 49 MB. Deterministic. */
#ifndef LBK_TESTS_ESTATE_LEVEL_H
#define LBK_TESTS_ESTATE_LEVEL_H

#include <stddef.h>
#include <stdint.h>

#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats: experimental (lbk/dls.h) */
#include "lbk/dls.h"
#include "dls_fixture.h"

#define ESTATE_SETS 132
#define ESTATE_PAGES 3
#define ESTATE_TEXELS 2637824u
#define ESTATE_GLG 229725u
#define ESTATE_LLG 50805u

extern const uint32_t estate_page_w[ESTATE_PAGES], estate_page_h[ESTATE_PAGES];

typedef struct estate_level {
    dlsfx fx;
    void *bytes; /* the DLS section */
    size_t size;
    lbk_dls_view *view;
    lbk_dls_stats st;
    double build_seconds;
} estate_level;

/* 0 on success; prints nothing. */
int estate_build(estate_level *lv);
void estate_free(estate_level *lv);
uint64_t estate_page_first(uint32_t page);
/* One line per fact (sizes, clusters per form, the overlap histogram) on stdout. */
void estate_describe(const estate_level *lv);

#endif
