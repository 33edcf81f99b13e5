#include "bake/probe_math.h"

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
