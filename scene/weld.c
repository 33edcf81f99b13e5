/* Vertices welded by exact position; see weld.h. */
#include "scene/weld.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct wd_vert { float p[3]; uint32_t i, nonfinite; } wd_vert;

static int cmp_pos(const void *a, const void *b)
{
    const wd_vert *u = a, *v = b;
    /* non-finite positions last and never equal (NaN would break the ordering) */
    if (u->nonfinite || v->nonfinite)
        return u->nonfinite != v->nonfinite ? (u->nonfinite ? 1 : -1) : (u->i < v->i ? -1 : u->i > v->i);
    for (int k = 0; k < 3; k++) {
        if (u->p[k] < v->p[k]) return -1;
        if (u->p[k] > v->p[k]) return 1;
    }
    return u->i < v->i ? -1 : u->i > v->i;
}

uint32_t *bk_weld_vertices(const bk_scene *s)
{
    size_t nv = s->vertex_count;
    wd_vert *order = malloc((nv ? nv : 1) * sizeof *order);
    uint32_t *id = malloc((nv ? nv : 1) * sizeof *id);
    if (!order || !id) {
        free(order);
        free(id);
        return NULL;
    }
    for (size_t i = 0; i < nv; i++) {
        memcpy(order[i].p, s->positions + 3 * i, sizeof order[i].p);
        order[i].i = (uint32_t)i;
        order[i].nonfinite = !isfinite(order[i].p[0]) || !isfinite(order[i].p[1]) || !isfinite(order[i].p[2]);
    }
    qsort(order, nv, sizeof *order, cmp_pos);
    for (size_t i = 0; i < nv;) {
        size_t j = i + 1;
        while (j < nv && !order[i].nonfinite && !order[j].nonfinite && order[j].p[0] == order[i].p[0] &&
               order[j].p[1] == order[i].p[1] && order[j].p[2] == order[i].p[2])
            j++;
        for (size_t k = i; k < j; k++) id[order[k].i] = order[i].i;
        i = j;
    }
    free(order);
    return id;
}
