/* Small vector helpers shared by the lightmap parametrisation, atlas and texel code
 * (uvgen.c, atlas.c, texels.c, classify.c). Doubles inside: charts are built from world
 * positions that may sit 1e5 m from the origin, where float differences lose the texel. */
#ifndef BK_UV_MATH_H
#define BK_UV_MATH_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"

static inline void bkv_load(double out[3], const float *p)
{
    out[0] = p[0];
    out[1] = p[1];
    out[2] = p[2];
}
static inline void bkv_sub(double o[3], const double a[3], const double b[3])
{
    o[0] = a[0] - b[0];
    o[1] = a[1] - b[1];
    o[2] = a[2] - b[2];
}
static inline double bkv_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void bkv_cross(double o[3], const double a[3], const double b[3])
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    o[0] = x;
    o[1] = y;
    o[2] = z;
}
static inline double bkv_len(const double a[3]) { return sqrt(bkv_dot(a, a)); }
/* Normalises in place; returns the old length (0 leaves a zero vector). */
static inline double bkv_normalize(double a[3])
{
    double l = bkv_len(a);
    if (l > 0.0 && isfinite(l)) {
        a[0] /= l;
        a[1] /= l;
        a[2] /= l;
    } else {
        a[0] = a[1] = a[2] = 0.0;
        l = 0.0;
    }
    return l;
}
/* An orthonormal basis around unit n (Duff et al. 2017, branchless ONB): deterministic and
 * continuous except across n.z = 0 sign flips. */
static inline void bkv_basis(const double n[3], double t[3], double b[3])
{
    double sign = n[2] >= 0.0 ? 1.0 : -1.0;
    double a = -1.0 / (sign + n[2]);
    double bb = n[0] * n[1] * a;
    t[0] = 1.0 + sign * n[0] * n[0] * a;
    t[1] = sign * bb;
    t[2] = -sign * n[0];
    b[0] = bb;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

/* Triangle i of the scene: its three positions as doubles. Returns 0 when an index is out
 * of range or a coordinate is not finite (treated as degenerate by every caller). */
static inline int bk_tri_positions(const bk_scene *s, size_t tri, double p[3][3])
{
    if (tri >= s->tri_count) return 0;
    for (int k = 0; k < 3; k++) {
        uint32_t v = s->tris[3 * tri + (size_t)k];
        if (v >= s->vertex_count) return 0;
        bkv_load(p[k], s->positions + 3 * (size_t)v);
        if (!isfinite(p[k][0]) || !isfinite(p[k][1]) || !isfinite(p[k][2])) return 0;
    }
    return 1;
}

/* Unnormalised face normal (length = 2 × area) of a triangle given by positions. */
static inline void bk_tri_cross(const double p[3][3], double n[3])
{
    double e1[3], e2[3];
    bkv_sub(e1, p[1], p[0]);
    bkv_sub(e2, p[2], p[0]);
    bkv_cross(n, e1, e2);
}

#endif
