/* A point of a texel's footprint (bk_footprint_tri): shared by the transport, which starts gather
 * rays there, and by the Cycles bench's footprint sensors, which must measure the same points. */
#include "bake/transport/transport.h"

#include <math.h>

int bk_footprint_point(const bk_scene *scene, const bk_footprint_tri *tris, uint32_t count, double s, double t,
                       double p[3], double n[3])
{
    for (uint32_t k = 0; k < count; k++) {
        const bk_footprint_tri *f = &tris[k];
        double u = f->uv[0][0] + f->uv[0][1] * s + f->uv[0][2] * t;
        double v = f->uv[1][0] + f->uv[1][1] * s + f->uv[1][2] * t;
        if (!(u >= 0 && v >= 0 && u + v <= 1)) continue;
        const uint32_t *ix = scene->tris + 3 * (size_t)f->tri;
        double w[3] = {1 - u - v, u, v}, q[3][3];
        for (int a = 0; a < 3; a++) p[a] = n[a] = 0;
        for (int i = 0; i < 3; i++)
            for (int a = 0; a < 3; a++) {
                q[i][a] = scene->positions[3 * (size_t)ix[i] + a];
                p[a] += w[i] * q[i][a];
                if (scene->normals) n[a] += w[i] * scene->normals[3 * (size_t)ix[i] + a];
            }
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0) || !isfinite(l)) { /* no shading normal: the geometric one */
            double e1[3], e2[3];
            for (int a = 0; a < 3; a++) { e1[a] = q[1][a] - q[0][a]; e2[a] = q[2][a] - q[0][a]; }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            /* a degenerate triangle ends the search: the point would be wherever it is */
            if (!(l > 0) || !isfinite(l)) return 0;
        }
        for (int a = 0; a < 3; a++) n[a] /= l;
        return 1;
    }
    return 0;
}
