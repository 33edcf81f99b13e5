#include "support/image_compare.h"

#include <math.h>
#include <stdlib.h>

float tic_srgb(float x)
{
    x = x < 0 ? 0 : x > 1 ? 1 : x;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
}

int tic_on_edge(const uint8_t *img, int w, int h, int x, int y)
{
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            const int X = x + dx, Y = y + dy;
            if (X < 0 || Y < 0 || X >= w || Y >= h) continue;
            for (int c = 0; c < 3; c++)
                if (abs(img[3 * (Y * w + X) + c] - img[3 * (y * w + x) + c]) > 8) return 1;
        }
    return 0;
}
