/* Closed solids by edge balance; see solid.h. */
#include "bake/transport/solid.h"
#include "scene/weld.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct sd_edge {
    uint32_t lo, hi;  /* welded vertex ids, lo < hi */
    uint32_t tri;
    int32_t dir;      /* +1: the triangle runs lo -> hi, -1: hi -> lo */
} sd_edge;

static int cmp_edge(const void *a, const void *b)
{
    const sd_edge *e = a, *f = b;
    if (e->lo != f->lo) return e->lo < f->lo ? -1 : 1;
    if (e->hi != f->hi) return e->hi < f->hi ? -1 : 1;
    if (e->tri != f->tri) return e->tri < f->tri ? -1 : 1;
    return (e->dir > f->dir) - (e->dir < f->dir);
}

static uint32_t find(uint32_t *parent, uint32_t x)
{
    uint32_t r = x;
    while (parent[r] != r) r = parent[r];
    while (parent[x] != r) {
        uint32_t n = parent[x];
        parent[x] = r;
        x = n;
    }
    return r;
}

static void unite(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = find(parent, a);
    b = find(parent, b);
    if (a == b) return;
    if (a < b) parent[b] = a;
    else parent[a] = b;
}

static int usable(const bk_scene *s, const uint32_t *id, size_t t, uint32_t w[3])
{
    double p[3][3];
    for (int k = 0; k < 3; k++) {
        uint32_t v = s->tris[3 * t + (size_t)k];
        if (v >= s->vertex_count) return 0;
        w[k] = id[v];
        for (int c = 0; c < 3; c++) {
            p[k][c] = s->positions[3 * (size_t)v + (size_t)c];
            if (!isfinite(p[k][c])) return 0;
        }
    }
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) return 0;
    double e1[3], e2[3];
    for (int c = 0; c < 3; c++) { e1[c] = p[1][c] - p[0][c]; e2[c] = p[2][c] - p[0][c]; }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    return n[0] != 0 || n[1] != 0 || n[2] != 0;
}

lbk_result bk_closed_triangles(const bk_scene *s, uint8_t *closed)
{
    if (!s || !closed || (s->tri_count && !s->tris)) return LBK_ERR_INVALID_ARGUMENT;
    size_t nt = s->tri_count;
    memset(closed, 0, nt);
    if (nt == 0) return LBK_OK;
    if (nt > UINT32_MAX / 3) return LBK_ERR_LIMIT;
    uint32_t *id = bk_weld_vertices(s);
    sd_edge *e = malloc(3 * nt * sizeof *e);
    uint32_t *parent = malloc(nt * sizeof *parent);
    uint8_t *bad = calloc(nt, 1), *ok = calloc(nt, 1);
    lbk_result res = LBK_ERR_OUT_OF_MEMORY;
    if (!id || !e || !parent || !bad || !ok) goto done;
    size_t ne = 0;
    for (size_t t = 0; t < nt; t++) {
        parent[t] = (uint32_t)t;
        uint32_t w[3];
        if (!usable(s, id, t, w)) continue;
        ok[t] = 1;
        for (int k = 0; k < 3; k++) {
            uint32_t a = w[k], b = w[(k + 1) % 3];
            sd_edge *x = &e[ne++];
            x->lo = a < b ? a : b;
            x->hi = a < b ? b : a;
            x->tri = (uint32_t)t;
            x->dir = a < b ? 1 : -1;
        }
    }
    qsort(e, ne, sizeof *e, cmp_edge);
    for (size_t i = 0; i < ne;) {
        size_t j = i;
        int32_t balance = 0;
        while (j < ne && e[j].lo == e[i].lo && e[j].hi == e[i].hi) {
            balance += e[j].dir;
            unite(parent, e[i].tri, e[j].tri);
            j++;
        }
        if (balance != 0) bad[e[i].tri] = 1; /* a boundary or inconsistently wound edge */
        i = j;
    }
    for (size_t t = 0; t < nt; t++)
        if (bad[t]) bad[find(parent, (uint32_t)t)] = 1;
    for (size_t t = 0; t < nt; t++) closed[t] = ok[t] && !bad[find(parent, (uint32_t)t)];
    res = LBK_OK;
done:
    free(id);
    free(e);
    free(parent);
    free(bad);
    free(ok);
    return res;
}
