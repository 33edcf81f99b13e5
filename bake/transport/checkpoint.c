/* Checkpoints (bk_transport_checkpoint): the state saved after each pass and a resumed run's load. */
#include "bake/transport/transport_impl.h"

/* ---- checkpoints (bk_transport_checkpoint) ------------------------------------------------ */

/* A saved state holds a class as stopped when it stopped before the last saved pass (the texels
 * reach their target a pass before the probes). Such a class is put back to the stop rule with
 * the others: under the same options it stops again for the same reason (its estimate, blocks
 * and samples are what they were, and a later pass's step is larger), so a resumed bake is the
 * uninterrupted one; with --continue's lower target or larger budget it samples on. A class
 * stopped by the clock stays stopped: the rule's clock is not what it was. */
void bk_tr_reopen_classes(tp_ctx *c)
{
    for (int k = 0; k < c->ncls; k++)
        if (!c->cls[k].active && c->cls[k].end > c->cls[k].begin &&
            (c->cls[k].stop == BK_STOP_TARGET || c->cls[k].stop == BK_STOP_BUDGET))
            c->cls[k].active = 1;
}

static void state_arrays(tp_ctx *c, bk_transport_state *st)
{
    st->count = c->recv_count;
    for (int h = 0; h < 2; h++) st->x_acc[h] = c->x_acc[h], st->b_acc[h] = c->b_acc[h];
    st->radiance = c->out->radiance;
    st->direct = c->out->direct;
    st->irradiance = c->out->irradiance;
    st->cells = c->cell_count;
    st->rough = c->rough;
    st->blocks = c->blk_count;
    st->block_weight = c->blk_w;
}

lbk_result bk_tr_save_state(tp_ctx *c, int pass, const tp_chain_result chain[2])
{
    const bk_transport_checkpoint *ck = c->opt->checkpoint;
    bk_transport_state *st = calloc(1, sizeof *st);
    if (!st) return LBK_ERR_OUT_OF_MEMORY;
    state_arrays(c, st);
    st->passes = pass + 1;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) {
        st->weight_sum[k] = c->cls[k].weight_sum, st->spp[k] = c->cls[k].spp;
        st->active[k] = c->cls[k].active, st->stop[k] = c->cls[k].stop;
    }
    for (int h = 0; h < 2; h++) {
        st->chain_bounces[h] = chain[h].bounces;
        st->chain_q[h] = chain[h].q;
        st->chain_tail[h] = chain[h].tail_energy;
        st->chain_total[h] = chain[h].total_energy;
    }
    uint64_t all[3];
    bk_tr_count_totals(c, all);
    st->rays = all[0], st->shadow = all[1], st->nonfinite = all[2];
    st->cache_rays = c->cache_rays, st->cache_shadow = c->cache_shadow, st->cache_nonfinite = c->cache_nonfinite;
    memcpy(st->samples, c->samples, sizeof st->samples);
    lbk_result r = ck->save(ck->user, st);
    free(st);
    return r;
}

/* The run's last saved state, if any: *passes gets how many passes it holds (0: none). */
lbk_result bk_tr_load_state(tp_ctx *c, tp_chain_result chain[2], int *passes)
{
    const bk_transport_checkpoint *ck = c->opt->checkpoint;
    *passes = 0;
    bk_transport_state *st = calloc(1, sizeof *st);
    if (!st) return LBK_ERR_OUT_OF_MEMORY;
    state_arrays(c, st);
    int got = ck->load(ck->user, st);
    lbk_result r = got < 0 ? (lbk_result)(-got) : LBK_OK;
    if (got == 1 && (st->passes < 1 || st->passes > BK_TRANSPORT_MAX_PASSES)) r = LBK_ERR_BAD_INPUT;
    if (got == 1 && !r) {
        *passes = st->passes;
        for (int k = 0; k < BK_RECEIVER_CLASSES; k++) {
            c->cls[k].weight_sum = st->weight_sum[k], c->cls[k].spp = st->spp[k];
            c->cls[k].active = st->active[k], c->cls[k].stop = st->stop[k];
            if (k < c->ncls && c->cls[k].spp > c->spp) c->spp = c->cls[k].spp;
        }
        for (int h = 0; h < 2; h++) {
            chain[h].bounces = st->chain_bounces[h];
            chain[h].q = st->chain_q[h];
            chain[h].tail_energy = st->chain_tail[h];
            chain[h].total_energy = st->chain_total[h];
        }
        /* the counters as they stood after that pass (the punctual pass before it, just redone,
         * is in them already) */
        for (int t = 0; t < c->threads; t++) c->thread_rays[t] = c->thread_shadow[t] = c->thread_nonfinite[t] = 0;
        c->thread_rays[0] = st->rays, c->thread_shadow[0] = st->shadow, c->thread_nonfinite[0] = st->nonfinite;
        c->cache_rays = st->cache_rays, c->cache_shadow = st->cache_shadow, c->cache_nonfinite = st->cache_nonfinite;
        memcpy(c->samples, st->samples, sizeof c->samples);
    }
    free(st);
    return r;
}
