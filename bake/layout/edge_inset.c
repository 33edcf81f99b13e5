/* Edge texels moved off the edges other surfaces meet; see edge_inset.h. */
#include "bake/layout/edge_inset.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/edge_key.h"
#include "bake/layout/uv_math.h"
#include "scene/weld.h"

/* Two triangles' normals within ~0.5°: one flat face (a quad's two halves). */
#define EI_COPLANAR_COS 0.99996
#define EI_MAX_EDGES 6 /* its own three, or two and its coplanar neighbours' outer ones */

typedef bk_edge_key ei_edge;

typedef struct ei_table {
    const bk_scene *scene;
    uint32_t *id;    /* welded id per vertex */
    ei_edge *edges;  /* sorted by (a, b, tri) */
    size_t count;
} ei_table;

static lbk_result table_build(const bk_scene *s, ei_table *t)
{
    memset(t, 0, sizeof *t);
    t->scene = s;
    if (s->tri_count > UINT32_MAX / 3) return LBK_ERR_LIMIT;
    t->id = bk_weld_vertices(s);
    t->edges = malloc((s->tri_count ? 3 * s->tri_count : 1) * sizeof *t->edges);
    if (!t->id || !t->edges) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < s->tri_count; i++) {
        const uint32_t *v = s->tris + 3 * i;
        if (v[0] >= s->vertex_count || v[1] >= s->vertex_count || v[2] >= s->vertex_count) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = t->id[v[k]], b = t->id[v[(k + 1) % 3]];
            if (a == b) continue;
            t->edges[t->count++] = (ei_edge){a < b ? a : b, a < b ? b : a, (uint32_t)i};
        }
    }
    qsort(t->edges, t->count, sizeof *t->edges, bk_edge_key_cmp);
    return LBK_OK;
}

static void table_free(ei_table *t)
{
    free(t->id);
    free(t->edges);
}

/* Unit geometric normal of triangle tri; 0 when degenerate. */
static int tri_normal(const bk_scene *s, uint32_t tri, double p[3][3], double n[3])
{
    if (!bk_tri_positions(s, tri, p)) return 0;
    bk_tri_cross(p, n);
    return bkv_normalize(n) > 0;
}

/* The lowest other triangle of the same object on the welded edge (a, b) of tri, in tri's plane
 * (normal n): a diagonal inside one flat face. -1 where there is none. */
static int64_t coplanar_neighbour(const ei_table *t, uint32_t tri, uint32_t a, uint32_t b, const double n[3])
{
    const bk_scene *s = t->scene;
    ei_edge key = {a < b ? a : b, a < b ? b : a, 0};
    size_t lo = 0, hi = t->count;
    while (lo < hi) { /* first entry >= (key.a, key.b, 0) */
        size_t mid = lo + (hi - lo) / 2;
        if (bk_edge_key_cmp(&t->edges[mid], &key) < 0) lo = mid + 1;
        else hi = mid;
    }
    uint32_t object = s->tri_object ? s->tri_object[tri] : 0;
    for (size_t i = lo; i < t->count && t->edges[i].a == key.a && t->edges[i].b == key.b; i++) {
        uint32_t o = t->edges[i].tri;
        if (o == tri || (s->tri_object && s->tri_object[o] != object)) continue;
        double q[3][3], m[3];
        if (tri_normal(s, o, q, m) && bkv_dot(m, n) > EI_COPLANAR_COS) return o;
    }
    return -1;
}

typedef struct ei_edges {
    double x[EI_MAX_EDGES][3], y[EI_MAX_EDGES][3];
    int count;
} ei_edges;

/* The edges of tri another surface may meet (see edge_inset.h), into ce; at depth 0 also those
 * of its coplanar neighbours (not back into skip). */
static void open_edges(const ei_table *t, uint32_t tri, int64_t skip, const double n[3], ei_edges *ce, int depth)
{
    double p[3][3], m[3];
    if (!tri_normal(t->scene, tri, p, m)) return;
    const uint32_t *v = t->scene->tris + 3 * (size_t)tri;
    for (int k = 0; k < 3; k++) {
        int64_t nb = coplanar_neighbour(t, tri, t->id[v[k]], t->id[v[(k + 1) % 3]], n);
        if (nb < 0 && ce->count < EI_MAX_EDGES) {
            memcpy(ce->x[ce->count], p[k], sizeof ce->x[0]);
            memcpy(ce->y[ce->count], p[(k + 1) % 3], sizeof ce->y[0]);
            ce->count++;
        } else if (nb >= 0 && nb != skip && depth == 0) {
            open_edges(t, (uint32_t)nb, tri, n, ce, 1);
        }
    }
}

static void inset_one(const ei_table *t, bk_texel *r)
{
    double p[3][3], n[3];
    if (!tri_normal(t->scene, r->tri, p, n)) return;
    double area2, perimeter = 0, cr[3];
    bk_tri_cross(p, cr);
    area2 = bkv_len(cr);
    for (int k = 0; k < 3; k++) {
        double e[3];
        bkv_sub(e, p[(k + 1) % 3], p[k]);
        perimeter += bkv_len(e);
    }
    const double step = fmin(0.01 * r->texel_size, 0.5 * area2 / perimeter); /* inradius = 2·area / perimeter */
    if (!(step > 0) || !isfinite(step)) return;
    ei_edges ce;
    ce.count = 0;
    open_edges(t, r->tri, -1, n, &ce, 0);
    double x[3];
    bkv_load(x, r->position);
    for (int pass = 0; pass < 2; pass++) /* twice: at a corner the second edge's move may undo the first's */
        for (int k = 0; k < ce.count; k++) {
            double e[3], m[3];
            bkv_sub(e, ce.y[k], ce.x[k]);
            bkv_cross(m, n, e); /* in the plane, towards the inside of a counter-clockwise edge */
            if (!(bkv_normalize(m) > 0)) continue;
            double rel[3];
            bkv_sub(rel, x, ce.x[k]);
            const double dist = bkv_dot(rel, m);
            if (dist < -step) continue; /* beyond that edge's line: a concave face's far edge */
            if (dist < step)
                for (int a = 0; a < 3; a++) x[a] += (step - dist) * m[a];
        }
    for (int a = 0; a < 3; a++) r->position[a] = (float)x[a];
}

lbk_result bk_texels_inset_edges(bk_texels *tx, const bk_scene *scene)
{
    if (!tx || !scene || (tx->count && !tx->receivers) || (scene->tri_count && !scene->tris))
        return LBK_ERR_INVALID_ARGUMENT;
    size_t edge = 0;
    for (size_t i = 0; i < tx->count; i++) edge += (tx->receivers[i].flags & BK_TEXEL_EDGE) != 0;
    if (!edge) return LBK_OK;
    ei_table t;
    lbk_result res = table_build(scene, &t);
    if (res == LBK_OK)
        for (size_t i = 0; i < tx->count; i++)
            if ((tx->receivers[i].flags & BK_TEXEL_EDGE) && tx->receivers[i].tri < scene->tri_count)
                inset_one(&t, &tx->receivers[i]);
    table_free(&t);
    return res;
}
