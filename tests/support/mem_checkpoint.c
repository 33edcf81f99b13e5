/* Transport checkpoints in memory (tests/support/mem_checkpoint.h). */
#include "support/mem_checkpoint.h"

#include <stdlib.h>
#include <string.h>

static void *dup_or_null(const void *p, size_t size)
{
    if (!p) return NULL;
    void *q = malloc(size ? size : 1);
    if (q) memcpy(q, p, size);
    return q;
}

static lbk_result mem_save(void *user, const bk_transport_state *st)
{
    mem_ckpt *m = user;
    if (m->saved >= BK_TRANSPORT_MAX_PASSES || st->passes != m->saved + 1) return LBK_ERR_INTERNAL;
    bk_transport_state *d = &m->st[m->saved++];
    *d = *st;
    const size_t n = st->count;
    for (int h = 0; h < 2; h++) d->x_acc[h] = dup_or_null(st->x_acc[h], 8 * n), d->b_acc[h] = dup_or_null(st->b_acc[h], 8 * n);
    d->radiance = dup_or_null(st->radiance, n * sizeof(lbk_sh9_rgb));
    d->direct = dup_or_null(st->direct, n * sizeof(lbk_sh9_rgb));
    d->irradiance = dup_or_null(st->irradiance, 12 * n);
    d->rough = dup_or_null(st->rough, st->cells);
    d->block_weight = dup_or_null(st->block_weight, 8 * st->blocks);
    return LBK_OK;
}

/* Fills the run's own arrays from the saved state of pass `at`. */
static int mem_load(void *user, bk_transport_state *st)
{
    mem_ckpt *m = user;
    if (m->at < 0) return 0;
    if (m->at >= m->saved) return -(int)LBK_ERR_INTERNAL;
    const bk_transport_state *sv = &m->st[m->at];
    const size_t n = st->count;
    if (sv->count != n || sv->cells != st->cells || sv->blocks != st->blocks || !sv->direct != !st->direct ||
        !sv->irradiance != !st->irradiance)
        return -(int)LBK_ERR_BAD_INPUT;
    const bk_transport_state mine = *st;
    *st = *sv;
    for (int h = 0; h < 2; h++) {
        st->x_acc[h] = mine.x_acc[h], st->b_acc[h] = mine.b_acc[h];
        memcpy(st->x_acc[h], sv->x_acc[h], 8 * n), memcpy(st->b_acc[h], sv->b_acc[h], 8 * n);
    }
    st->radiance = mine.radiance, st->direct = mine.direct, st->irradiance = mine.irradiance;
    st->rough = mine.rough, st->block_weight = mine.block_weight;
    memcpy(st->radiance, sv->radiance, n * sizeof(lbk_sh9_rgb));
    if (st->direct) memcpy(st->direct, sv->direct, n * sizeof(lbk_sh9_rgb));
    if (st->irradiance) memcpy(st->irradiance, sv->irradiance, 12 * n);
    if (st->cells) memcpy(st->rough, sv->rough, st->cells);
    if (st->blocks) memcpy(st->block_weight, sv->block_weight, 8 * st->blocks);
    return 1;
}

void mem_ckpt_init(mem_ckpt *m, bk_transport_checkpoint *ck)
{
    memset(m, 0, sizeof *m);
    m->at = -1;
    ck->user = m;
    ck->save = mem_save;
    ck->load = mem_load;
}

void mem_ckpt_drop(mem_ckpt *m, int keep)
{
    for (int p = keep; p < m->saved; p++) {
        bk_transport_state *d = &m->st[p];
        for (int h = 0; h < 2; h++) free(d->x_acc[h]), free(d->b_acc[h]);
        free(d->radiance), free(d->direct), free(d->irradiance), free(d->rough), free(d->block_weight);
    }
    if (keep < m->saved) m->saved = keep;
}
