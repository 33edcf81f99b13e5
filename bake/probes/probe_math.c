#include "bake/probes/probe_math.h"

#include <math.h>
#include <string.h>

void bk_sym3_eigen(const double a_in[9], double values[3], double vectors[3][3])
{
    double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    memcpy(a, a_in, sizeof a);
    for (int sweep = 0; sweep < 64; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (off <= 1e-300 || off <= 1e-17 * diag) break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                if (a[p][q] == 0.0) continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; k++) {   /* a = Jᵀ a J */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (a[order[j]][order[j]] > a[order[i]][order[i]]) { int t = order[i]; order[i] = order[j]; order[j] = t; }
    for (int k = 0; k < 3; k++) {
        values[k] = a[order[k]][order[k]];
        for (int r = 0; r < 3; r++) vectors[k][r] = v[r][order[k]];
        double len = sqrt(vectors[k][0] * vectors[k][0] + vectors[k][1] * vectors[k][1] + vectors[k][2] * vectors[k][2]);
        int big = 0;
        for (int r = 1; r < 3; r++) if (fabs(vectors[k][r]) > fabs(vectors[k][big]) * (1.0 + 1e-12)) big = r;
        double s = (vectors[k][big] < 0 ? -1.0 : 1.0) / (len > 0 ? len : 1.0);
        for (int r = 0; r < 3; r++) vectors[k][r] *= s;
    }
    const double *x = vectors[0], *y = vectors[1];
    vectors[2][0] = x[1] * y[2] - x[2] * y[1];
    vectors[2][1] = x[2] * y[0] - x[0] * y[2];
    vectors[2][2] = x[0] * y[1] - x[1] * y[0];
}

void bk_sphere_direction(size_t i, size_t n, float dir[3])
{
    /* offset the azimuth so no direction is axis-aligned (axis-aligned rays graze walls) */
    const double golden = 2.39996322972865332;
    double z = 1.0 - (2.0 * (double)i + 1.0) / (double)n;
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = golden * (double)i + 0.3183098861837907;
    dir[0] = (float)(r * cos(phi));
    dir[1] = (float)(r * sin(phi));
    dir[2] = (float)z;
}

static int axis_test(const double *e, const double v[3][3], const double half[3])
{
    /* separating axis e: project the triangle and the box on it */
    double p0 = e[0] * v[0][0] + e[1] * v[0][1] + e[2] * v[0][2];
    double p1 = e[0] * v[1][0] + e[1] * v[1][1] + e[2] * v[1][2];
    double p2 = e[0] * v[2][0] + e[1] * v[2][1] + e[2] * v[2][2];
    double mn = fmin(p0, fmin(p1, p2)), mx = fmax(p0, fmax(p1, p2));
    double r = half[0] * fabs(e[0]) + half[1] * fabs(e[1]) + half[2] * fabs(e[2]);
    return !(mn > r || mx < -r);
}

int bk_tri_box_overlap(const double centre[3], const double half[3], const float *a,
                       const float *b, const float *c)
{
    double v[3][3];
    for (int k = 0; k < 3; k++) {
        v[0][k] = a[k] - centre[k];
        v[1][k] = b[k] - centre[k];
        v[2][k] = c[k] - centre[k];
    }
    for (int k = 0; k < 3; k++) {  /* box face normals */
        double mn = fmin(v[0][k], fmin(v[1][k], v[2][k])), mx = fmax(v[0][k], fmax(v[1][k], v[2][k]));
        if (mn > half[k] || mx < -half[k]) return 0;
    }
    double e[3][3];
    for (int k = 0; k < 3; k++) {
        e[0][k] = v[1][k] - v[0][k];
        e[1][k] = v[2][k] - v[1][k];
        e[2][k] = v[0][k] - v[2][k];
    }
    double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                   e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    if (!axis_test(n, v, half)) return 0;
    for (int i = 0; i < 3; i++) {  /* edge × box axis */
        for (int k = 0; k < 3; k++) {
            double ax[3] = {0, 0, 0}, u[3] = {k == 0, k == 1, k == 2};
            ax[0] = e[i][1] * u[2] - e[i][2] * u[1];
            ax[1] = e[i][2] * u[0] - e[i][0] * u[2];
            ax[2] = e[i][0] * u[1] - e[i][1] * u[0];
            if (ax[0] == 0.0 && ax[1] == 0.0 && ax[2] == 0.0) continue;
            if (!axis_test(ax, v, half)) return 0;
        }
    }
    return 1;
}
