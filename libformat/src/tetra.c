/* Tetrahedral walk (rules: lbk/tetra.h). */
#include "lbk/tetra.h"

#include <math.h>

#include "internal.h"

#define BARY_EPS 1e-6

double lbk_tetra_orient(const float a[3], const float b[3], const float c[3], const float d[3])
{
    const double u[3] = {(double)b[0] - a[0], (double)b[1] - a[1], (double)b[2] - a[2]};
    const double v[3] = {(double)c[0] - a[0], (double)c[1] - a[1], (double)c[2] - a[2]};
    const double w[3] = {(double)d[0] - a[0], (double)d[1] - a[1], (double)d[2] - a[2]};
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static void vertex_pos(const lbk_tetra_mesh *m, uint32_t v, float out[3])
{
    const uint8_t *p = m->positions + (size_t)v * 12;
    out[0] = lbk_rdf32(p);
    out[1] = lbk_rdf32(p + 4);
    out[2] = lbk_rdf32(p + 8);
}

/* b[i] in double; false when an index is out of range or the volume is not positive. */
static bool bary_d(const lbk_tetra_mesh *m, uint32_t t, const float p[3], uint32_t vid[4], double b[4])
{
    float v[4][3];
    const uint8_t *tp = m->tetras + (size_t)t * 16;
    for (int i = 0; i < 4; i++) {
        vid[i] = lbk_rd32(tp + 4 * i);
        if (vid[i] >= m->vertex_count) return false;
        vertex_pos(m, vid[i], v[i]);
    }
    const double vol = lbk_tetra_orient(v[0], v[1], v[2], v[3]);
    if (!(vol > 0.0)) return false;
    b[0] = lbk_tetra_orient(p, v[1], v[2], v[3]) / vol;
    b[1] = lbk_tetra_orient(v[0], p, v[2], v[3]) / vol;
    b[2] = lbk_tetra_orient(v[0], v[1], p, v[3]) / vol;
    b[3] = 1.0 - b[0] - b[1] - b[2];
    return true;
}

lbk_result lbk_tetra_barycentric(const lbk_tetra_mesh *mesh, uint32_t tetra, const float p[3], float bary[4])
{
    if (!mesh || !p || !bary) return LBK_ERR_INVALID_ARGUMENT;
    if (tetra >= mesh->tetra_count) return LBK_ERR_NOT_FOUND;
    uint32_t vid[4];
    double b[4];
    if (!bary_d(mesh, tetra, p, vid, b)) return LBK_ERR_CORRUPT;
    for (int i = 0; i < 4; i++) bary[i] = (float)b[i];
    return LBK_OK;
}

static void finish(lbk_tetra_location *out, uint32_t t, const uint32_t vid[4], const double b[4])
{
    double c[4], s = 0.0, mn = b[0];
    for (int i = 0; i < 4; i++) {
        c[i] = b[i] > 0.0 ? b[i] : 0.0;
        s += c[i];
        if (b[i] < mn) mn = b[i];
    }
    out->tetra = t;
    out->inside = mn >= -BARY_EPS;
    for (int i = 0; i < 4; i++) {
        out->vertices[i] = vid[i];
        out->bary[i] = s > 0.0 ? (float)(c[i] / s) : 0.25f;
    }
}

lbk_result lbk_tetra_locate(const lbk_tetra_mesh *mesh, const float p[3], uint32_t hint, lbk_tetra_location *out)
{
    if (!mesh || !p || !out || mesh->tetra_count == 0) return LBK_ERR_INVALID_ARGUMENT;
    if (!(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    uint32_t t = hint < mesh->tetra_count ? hint : 0;
    const uint64_t cap = (uint64_t)mesh->tetra_count + 64;
    uint32_t vid[4];
    double b[4];
    for (uint64_t step = 0; step < cap; step++) {
        out->steps++;
        if (!bary_d(mesh, t, p, vid, b)) return LBK_ERR_CORRUPT;
        int best = -1;
        double worst = -BARY_EPS;
        bool negative = false;
        const uint8_t *adj = mesh->adjacency + (size_t)t * 16;
        for (int i = 0; i < 4; i++) {
            if (b[i] >= -BARY_EPS) continue;
            negative = true;
            if (lbk_rd32(adj + 4 * i) == LBK_TETRA_NONE) continue;
            if (b[i] < worst) {
                worst = b[i];
                best = i;
            }
        }
        if (!negative || best < 0) { /* inside, or outside across hull faces only */
            finish(out, t, vid, b);
            return LBK_OK;
        }
        const uint32_t n = lbk_rd32(adj + 4 * best);
        if (n >= mesh->tetra_count) return LBK_ERR_CORRUPT;
        t = n;
    }
    /* a cycle: scan */
    out->scanned = 1;
    double best_min = -INFINITY;
    uint32_t best_t = 0;
    for (uint32_t i = 0; i < mesh->tetra_count; i++) {
        uint32_t v2[4];
        double b2[4];
        if (!bary_d(mesh, i, p, v2, b2)) return LBK_ERR_CORRUPT;
        double mn = b2[0];
        for (int k = 1; k < 4; k++)
            if (b2[k] < mn) mn = b2[k];
        if (mn > best_min) {
            best_min = mn;
            best_t = i;
        }
    }
    bary_d(mesh, best_t, p, vid, b);
    finish(out, best_t, vid, b);
    return LBK_OK;
}
