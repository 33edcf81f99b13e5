/* A mesh edge as the layout steps find shared edges: welded vertex ids a < b and the triangle it
 * belongs to, sorted by (a, b, tri) so that the triangles sharing an edge lie side by side. */
#ifndef BK_LAYOUT_EDGE_KEY_H
#define BK_LAYOUT_EDGE_KEY_H

#include <stdint.h>

typedef struct bk_edge_key {
    uint32_t a, b; /* welded vertex ids, a < b */
    uint32_t tri;
} bk_edge_key;

/* The (a, b, tri) order of two edges given by their fields. */
static inline int bk_edge_order(uint32_t a0, uint32_t b0, uint32_t t0, uint32_t a1, uint32_t b1, uint32_t t1)
{
    if (a0 != a1) return a0 < a1 ? -1 : 1;
    if (b0 != b1) return b0 < b1 ? -1 : 1;
    return (t0 > t1) - (t0 < t1);
}

/* qsort / bsearch comparator of bk_edge_key. */
static inline int bk_edge_key_cmp(const void *pa, const void *pb)
{
    const bk_edge_key *x = pa, *y = pb;
    return bk_edge_order(x->a, x->b, x->tri, y->a, y->b, y->tri);
}

#endif
