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

/* Whether triangle tri is one of the footprint's (the texel's own surface) or `own`, or belongs
 * to a door: a door moves, and its set's runs trace the level without it, so what it covers must
 * not depend on its state (else the open state's light misses the part it uncovers). */
static int footprint_own(const bk_scene *scene, const bk_footprint_tri *tris, uint32_t count, uint32_t own,
                         uint32_t tri)
{
    if (tri == own) return 1;
    if (scene && scene->tri_object && tri < scene->tri_count) {
        uint32_t o = scene->tri_object[tri];
        if (o < scene->object_count && scene->objects[o].door[0]) return 1;
    }
    for (uint32_t k = 0; k < count; k++)
        if (tris[k].tri == tri) return 1;
    return 0;
}

#define FP_SEGMENT_STEPS 4
int bk_footprint_segment_blocked(const bk_tracer *tracer, const bk_scene *scene, const bk_footprint_tri *tris,
                                 uint32_t count, uint32_t own, const double a[3], const double na[3], const double b[3],
                                 const double nb[3])
{
    double d[3], len2 = 0;
    for (int c = 0; c < 3; c++) {
        d[c] = b[c] - a[c];
        len2 += d[c] * d[c];
    }
    const double len = sqrt(len2);
    if (!(len > 0) || !isfinite(len)) return 0;
    /* both ends raised alike, so the segment runs parallel to a flat surface and never meets a
     * coplanar duplicate of it; relative to the segment, so the test means the same at any scale */
    const double lift = 1e-3 * len;
    float org[3], dir[3];
    double e[3], l2 = 0;
    for (int c = 0; c < 3; c++) {
        org[c] = (float)(a[c] + lift * na[c]);
        e[c] = b[c] + lift * nb[c] - org[c];
        l2 += e[c] * e[c];
    }
    const double l = sqrt(l2);
    if (!(l > 0)) return 0;
    for (int c = 0; c < 3; c++) dir[c] = (float)(e[c] / l);
    float tmin = 0.0f;
    for (int step = 0; step < FP_SEGMENT_STEPS; step++) {
        bk_hit h;
        if (!bk_tracer_intersect(tracer, org, dir, tmin, (float)l, &h)) return 0;
        /* a chord of a curved surface runs beneath the surface: step over its own triangles */
        if (!footprint_own(scene, tris, count, own, h.tri)) return 1;
        tmin = h.t * 1.0001f + 1e-7f;
    }
    return 0;
}

/* Whether some cell of the 3 x 3 block around (cx, cy) differs in state from the others: the
 * covering surface's edge runs near, and the cell's mark is not the answer for every point. */
static int cell_mixed(uint64_t hidden, int cx, int cy)
{
    int h = 0, v = 0;
    for (int y = cy - 1; y <= cy + 1; y++)
        for (int x = cx - 1; x <= cx + 1; x++) {
            if (x < 0 || y < 0 || x >= BK_FOOTPRINT_GRID || y >= BK_FOOTPRINT_GRID) continue;
            if ((hidden >> (y * BK_FOOTPRINT_GRID + x)) & 1u)
                h = 1;
            else
                v = 1;
        }
    return h && v;
}

int bk_footprint_sample_hidden(const bk_tracer *tracer, const bk_scene *scene, const bk_footprint_tri *tris,
                               const bk_receiver *r, double s, double t, const double p[3], const double n[3])
{
    if (!r->footprint_hidden) return 0;
    int cx = (int)(s * BK_FOOTPRINT_GRID), cy = (int)(t * BK_FOOTPRINT_GRID);
    cx = cx < 0 ? 0 : cx >= BK_FOOTPRINT_GRID ? BK_FOOTPRINT_GRID - 1 : cx;
    cy = cy < 0 ? 0 : cy >= BK_FOOTPRINT_GRID ? BK_FOOTPRINT_GRID - 1 : cy;
    if (!cell_mixed(r->footprint_hidden, cx, cy)) return bk_footprint_cell_hidden(r->footprint_hidden, s, t);
    /* from the receiver's point brought onto the surface's plane at p, as the push-out's marks
     * (it may have carried the point onto a surface just above its own) */
    const double na[3] = {r->normal[0], r->normal[1], r->normal[2]};
    double a[3] = {r->position[0], r->position[1], r->position[2]};
    const double h = (a[0] - p[0]) * n[0] + (a[1] - p[1]) * n[1] + (a[2] - p[2]) * n[2];
    for (int c = 0; c < 3; c++) a[c] -= h * n[c];
    return bk_footprint_segment_blocked(tracer, scene, tris + r->footprint_first, r->footprint_count, UINT32_MAX, a,
                                        na, p, n);
}
