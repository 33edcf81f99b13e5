/* Rectangle packing for the lightmap atlas (charts into object rectangles, object rectangles
 * into pages): MaxRects (Jylänki 2010, "A Thousand Ways to Pack the Bin") with the best
 * short side fit rule and optional quarter turns.
 *
 * The bin keeps the list of maximal free rectangles. Each rectangle, in the caller's order,
 * goes to the free rectangle and orientation that leave the smallest leftover on the short
 * side, then on the long side; ties go to the lower y, then the lower x, then unturned. The
 * free rectangles it overlaps are split into their maximal remainders and the ones contained
 * in another are dropped. Every decision is integer arithmetic on the input: the result is
 * deterministic and independent of threads.
 *
 * Order (bk_pack_sort): longer side descending, then shorter side, then id. */
#ifndef BK_PACK_H
#define BK_PACK_H

#include <stddef.h>
#include <stdint.h>

typedef struct bk_pack_rect {
    int w, h;            /* size as given; placed turned its footprint is h × w */
    uint32_t id;         /* the caller's index: the final tie-break of the order */
    uint8_t turnable;    /* may be placed turned by a quarter */
    uint8_t turned;      /* result: placed turned */
    uint8_t placed;      /* 0: to place; bk_pack_into sets 1 on the ones it placed and skips
                            any other non-zero value (already placed elsewhere) */
    int x, y;            /* result: top-left corner of the footprint */
} bk_pack_rect;

void bk_pack_sort(bk_pack_rect *r, int n);

/* Places the rectangles with placed == 0 that fit into a width × height bin, in array order.
 * Returns how many were placed (-1: out of memory) and the extent they use. */
int bk_pack_into(bk_pack_rect *r, int n, int width, int height, int *used_w, int *used_h);

/* Packs all n rectangles (sorted here) into the smallest bin of width <= max_w and height
 * <= max_h found among candidate widths around sqrt(total area), each with the least height
 * that holds everything (bisection). The bin's sides are the extent used rounded up to
 * `align`; "smallest" compares the areas with both sides rounded up to score_align (an
 * object alone on a page gets a page of multiples of 4), then the longer side. Returns 1
 * with positions set, 0 when no candidate holds them all, -1 when out of memory. */
int bk_pack_tight(bk_pack_rect *r, int n, int max_w, int max_h, int align, int score_align, int *out_w,
                  int *out_h);

#endif
