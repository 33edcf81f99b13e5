/* The gap room (gap_scene.h). */
#include "gap_scene.h"

#include <string.h>

#include "transport_scenes.h"

const char *const gsc_group_names[GSC_GROUPS] = {"floor", "walls", "ceiling by the slit"};

void gsc_build(bk_scene *s) { tsc_ceiling_lamp_room(s, 0.725f, 0.999f, 8, -0.3f, 0.2f, -0.15f, 0.25f); }

static void ceiling_point(int k, float *pp, float *nn)
{
    static const float off[4] = {0.1f, 0.17f, 0.23f, 0.3f}; /* from the slit's mouth */
    float d = off[k / 4];
    pp[1] = 2;
    nn[1] = -1;
    switch (k % 4) {
    case 0: pp[0] = -0.3f - d; pp[2] = 0.05f; break;
    case 1: pp[0] = 0.2f + d; pp[2] = 0.05f; break;
    case 2: pp[2] = -0.15f - d; pp[0] = -0.05f; break;
    default: pp[2] = 0.25f + d; pp[0] = -0.05f; break;
    }
}

void gsc_receivers(bk_receiver r[GSC_N], float p[3 * GSC_N], float n[3 * GSC_N])
{
    memset(r, 0, GSC_N * sizeof *r);
    for (int i = 0; i < GSC_N; i++) {
        float *pp = r[i].position, *nn = r[i].normal;
        int k = i % GSC_PER;
        float u = -0.75f + 0.5f * (float)(k % 4), v = -0.75f + 0.5f * (float)(k / 4);
        float h = 0.4f + 0.5f * (float)(k / 4), w = -0.6f + 0.4f * (float)((k % 4) / 2);
        if (i < GSC_PER) { pp[0] = u; pp[2] = v; nn[1] = 1; }           /* floor */
        else if (i < 2 * GSC_PER && k % 2) { pp[0] = -1; pp[1] = h; pp[2] = w; nn[0] = 1; } /* left wall */
        else if (i < 2 * GSC_PER) { pp[2] = -1; pp[1] = h; pp[0] = w; nn[2] = 1; }         /* back wall */
        else ceiling_point(k, pp, nn);
        memcpy(p + 3 * i, pp, 12);
        memcpy(n + 3 * i, nn, 12);
    }
}
