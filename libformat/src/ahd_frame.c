/* The tangent frame an AHD direction is stored in (spec/container.md §5.6 "Tangent frame"). In
 * double, step for step as the baker computes it (bake/layout/texels.c): equal bit for bit to
 * bk_tangent_frame, and within 3e-8 of the baker's receivers when rebuilt from LMUV coordinates
 * (tests/bake/test_uv_section.c checks both). */
#include "lbk/ahd.h"

#include <math.h>

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Normalises in place; returns the old length (a zero or non-finite vector becomes 0). */
static double normalize3(double a[3])
{
    double l = sqrt(dot3(a, a));
    if (l > 0.0 && isfinite(l)) {
        a[0] /= l;
        a[1] /= l;
        a[2] /= l;
        return l;
    }
    a[0] = a[1] = a[2] = 0.0;
    return 0.0;
}

/* First vector of the branchless orthonormal basis of unit n (Duff et al. 2017). */
static void basis_t(const double n[3], double t[3])
{
    const double sign = n[2] >= 0.0 ? 1.0 : -1.0;
    const double a = -1.0 / (sign + n[2]);
    t[0] = 1.0 + sign * n[0] * n[0] * a;
    t[1] = sign * (n[0] * n[1] * a);
    t[2] = -sign * n[0];
}

void lbk_ahd_tangent_frame(const float n[3], const float dpdx[3], float t[3], float b[3])
{
    double nn[3] = {n[0], n[1], n[2]}, du[3] = {dpdx[0], dpdx[1], dpdx[2]}, tt[3], bb[3];
    if (normalize3(nn) == 0.0) {
        nn[0] = 0.0;
        nn[1] = 0.0;
        nn[2] = 1.0;
    }
    const double d = dot3(nn, du);
    for (int k = 0; k < 3; k++) tt[k] = du[k] - nn[k] * d;
    /* dP/dX (nearly) parallel to N, or zero: no usable direction, take the fixed basis */
    if (!(sqrt(dot3(tt, tt)) > 1e-6 * sqrt(dot3(du, du))) || normalize3(tt) == 0.0) basis_t(nn, tt);
    bb[0] = nn[1] * tt[2] - nn[2] * tt[1];
    bb[1] = nn[2] * tt[0] - nn[0] * tt[2];
    bb[2] = nn[0] * tt[1] - nn[1] * tt[0];
    normalize3(bb);
    for (int k = 0; k < 3; k++) {
        t[k] = (float)tt[k];
        b[k] = (float)bb[k];
    }
}

void lbk_ahd_triangle_dpdx(const float p[3][3], const float coord[3][2], float dpdx[3])
{
    const double du1 = (double)coord[1][0] - coord[0][0], dv1 = (double)coord[1][1] - coord[0][1];
    const double du2 = (double)coord[2][0] - coord[0][0], dv2 = (double)coord[2][1] - coord[0][1];
    const double det = du1 * dv2 - du2 * dv1;
    for (int k = 0; k < 3; k++) {
        const double e1 = (double)p[1][k] - p[0][k], e2 = (double)p[2][k] - p[0][k];
        dpdx[k] = fabs(det) > 0.0 && isfinite(det) ? (float)((e1 * dv2 - e2 * dv1) / det) : 0.0f;
    }
}
