/* Comparing an 8-bit sRGB picture with lbk render's radiance (the browser tests: the viewer and
 * stock engines against the renderer). */
#ifndef TIC_IMAGE_COMPARE_H
#define TIC_IMAGE_COMPARE_H

#include <stdint.h>

/* The sRGB transfer function of x clamped to [0, 1] (IEC 61966-2-1). */
float tic_srgb(float x);

/* Whether pixel (x, y) of the w × h RGB8 picture is on an edge: some 8-neighbour differs from it
 * by more than 8 codes in a channel (a silhouette, a crease or a stripe boundary, where
 * rasterisation and ray casting may see different surfaces). */
int tic_on_edge(const uint8_t *img, int w, int h, int x, int y);

#endif
