/* Point-in-triangle with a top-left fill rule, shared by the overlap checks (uvgen.c) and
 * texel coverage (texels.c) so both agree on which triangle owns a texel centre.
 *
 * The edge function of an edge is always evaluated with its endpoints in lexicographic
 * order and negated for the other direction, so two triangles sharing an edge compute
 * bit-identical values of opposite sign: a centre exactly on the shared edge goes to exactly
 * one of them. */
#ifndef BK_UV_RASTER_H
#define BK_UV_RASTER_H

#include <math.h>

typedef struct bk_rtri {
    double x[3], y[3];  /* counter-clockwise in a y-up sense (orient > 0) */
    double area2;       /* twice the area, > 0 when usable */
    int flipped;        /* corners 1 and 2 were swapped to make the orientation positive */
} bk_rtri;

static inline double bk_orient_raw(double ax, double ay, double bx, double by, double px, double py)
{
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}
/* The edge function of a→b at p, evaluated the same way for a→b and b→a (negated). */
static inline double bk_edge_fn(double ax, double ay, double bx, double by, double px, double py)
{
    if (ax < bx || (ax == bx && ay < by)) return bk_orient_raw(ax, ay, bx, by, px, py);
    return -bk_orient_raw(bx, by, ax, ay, px, py);
}
/* Whether a point exactly on edge a→b belongs to the triangle on its left. Exactly one of
 * the two directions of an edge says yes. */
static inline int bk_edge_owns(double ax, double ay, double bx, double by)
{
    double dy = by - ay, dx = bx - ax;
    return dy > 0.0 || (dy == 0.0 && dx < 0.0);
}

/* Sets up a triangle from 6 coordinates; returns 0 when it has no area (or is not finite). */
static inline int bk_rtri_setup(const float *uv, bk_rtri *t)
{
    double x0 = uv[0], y0 = uv[1], x1 = uv[2], y1 = uv[3], x2 = uv[4], y2 = uv[5];
    double a = bk_edge_fn(x0, y0, x1, y1, x2, y2);
    t->flipped = 0;
    if (!(isfinite(a)) || a == 0.0) {
        t->area2 = 0.0;
        return 0;
    }
    if (a < 0.0) {
        double tx = x1, ty = y1;
        x1 = x2;
        y1 = y2;
        x2 = tx;
        y2 = ty;
        a = -a;
        t->flipped = 1;
    }
    t->x[0] = x0; t->y[0] = y0;
    t->x[1] = x1; t->y[1] = y1;
    t->x[2] = x2; t->y[2] = y2;
    t->area2 = a;
    return 1;
}

/* The texels of a width × height page whose square may touch the triangle: its bounding box grown
 * by one texel (the conservative rasteriser's reach), clamped to the page; empty when x0 > x1. */
static inline void bk_rtri_texel_box(const bk_rtri *t, int width, int height, int *x0, int *x1, int *y0, int *y1)
{
    double mnx = fmin(t->x[0], fmin(t->x[1], t->x[2])), mxx = fmax(t->x[0], fmax(t->x[1], t->x[2]));
    double mny = fmin(t->y[0], fmin(t->y[1], t->y[2])), mxy = fmax(t->y[0], fmax(t->y[1], t->y[2]));
    *x0 = (int)fmax(0.0, floor(mnx) - 1), *x1 = (int)fmin((double)width - 1, floor(mxx) + 1);
    *y0 = (int)fmax(0.0, floor(mny) - 1), *y1 = (int)fmin((double)height - 1, floor(mxy) + 1);
}

/* 1 when (px, py) is inside under the fill rule; w receives barycentric weights of the
 * triangle's ORIGINAL corner order (before any flip) when non-NULL. */
static inline int bk_rtri_inside(const bk_rtri *t, double px, double py, double w[3])
{
    double e[3];
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;  /* e[k]: the edge opposite corner k */
        e[k] = bk_edge_fn(t->x[a], t->y[a], t->x[b], t->y[b], px, py);
        if (e[k] < 0.0) return 0;
        if (e[k] == 0.0 && !bk_edge_owns(t->x[a], t->y[a], t->x[b], t->y[b])) return 0;
    }
    if (w) {
        double b0 = e[0] / t->area2, b1 = e[1] / t->area2, b2 = e[2] / t->area2;
        w[0] = b0;
        w[1] = t->flipped ? b2 : b1;
        w[2] = t->flipped ? b1 : b2;
    }
    return 1;
}

/* Closest point of the triangle to p, as barycentric weights of the ORIGINAL corner order;
 * returns the squared distance. (Ericson, Real-Time Collision Detection, 5.1.5, in 2D.) */
static inline double bk_rtri_closest(const bk_rtri *t, double px, double py, double w[3], double *cx,
                                     double *cy)
{
    double ax = t->x[0], ay = t->y[0], bx = t->x[1], by = t->y[1], qx = t->x[2], qy = t->y[2];
    double abx = bx - ax, aby = by - ay, acx = qx - ax, acy = qy - ay;
    double apx = px - ax, apy = py - ay;
    double d1 = abx * apx + aby * apy, d2 = acx * apx + acy * apy;
    double u, v, ww; /* weights of corners 0,1,2 in the flipped-normalised order */
    if (d1 <= 0.0 && d2 <= 0.0) {
        u = 1; v = 0; ww = 0;
    } else {
        double bpx = px - bx, bpy = py - by;
        double d3 = abx * bpx + aby * bpy, d4 = acx * bpx + acy * bpy;
        double cpx = px - qx, cpy = py - qy;
        double d5 = abx * cpx + aby * cpy, d6 = acx * cpx + acy * cpy;
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0.0 && d4 <= d3) {
            u = 0; v = 1; ww = 0;
        } else if (d6 >= 0.0 && d5 <= d6) {
            u = 0; v = 0; ww = 1;
        } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
            double s = d1 / (d1 - d3);
            u = 1 - s; v = s; ww = 0;
        } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
            double s = d2 / (d2 - d6);
            u = 1 - s; v = 0; ww = s;
        } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
            double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            u = 0; v = 1 - s; ww = s;
        } else {
            double den = 1.0 / (va + vb + vc);
            v = vb * den;
            ww = vc * den;
            u = 1.0 - v - ww;
        }
    }
    double x = u * ax + v * bx + ww * qx, y = u * ay + v * by + ww * qy;
    /* the exact closest point lies in the triangle's bounding box; rounding must not move it
     * out (a point on a vertical edge at x = 53 must not come back as 52.999999999999993) */
    x = fmin(fmax(x, fmin(ax, fmin(bx, qx))), fmax(ax, fmax(bx, qx)));
    y = fmin(fmax(y, fmin(ay, fmin(by, qy))), fmax(ay, fmax(by, qy)));
    if (w) {
        w[0] = u;
        w[1] = t->flipped ? ww : v;
        w[2] = t->flipped ? v : ww;
    }
    if (cx) *cx = x;
    if (cy) *cy = y;
    return (x - px) * (x - px) + (y - py) * (y - py);
}

/* 1 when the (closed) triangle meets the open square |x − cx| < r, |y − cy| < r: separating
 * axes are the square's two and the triangle's three edge normals. With r = 1 around a texel
 * centre this is "bilinear filtering at some point of the triangle reads this texel". */
static inline int bk_rtri_meets_square(const bk_rtri *t, double cx, double cy, double r)
{
    double mnx = fmin(t->x[0], fmin(t->x[1], t->x[2])), mxx = fmax(t->x[0], fmax(t->x[1], t->x[2]));
    double mny = fmin(t->y[0], fmin(t->y[1], t->y[2])), mxy = fmax(t->y[0], fmax(t->y[1], t->y[2]));
    if (mxx <= cx - r || mnx >= cx + r || mxy <= cy - r || mny >= cy + r) return 0;
    for (int k = 0; k < 3; k++) {
        int a = k, b = (k + 1) % 3;
        /* outward normal of edge a→b (the triangle is counter-clockwise): the whole triangle
         * projects at or below the edge, so the square must reach below it */
        double nx = t->y[b] - t->y[a], ny = t->x[a] - t->x[b];
        double edge = nx * t->x[a] + ny * t->y[a];
        double sq_min = nx * cx + ny * cy - r * (fabs(nx) + fabs(ny));
        if (sq_min >= edge) return 0;
    }
    return 1;
}

#endif
