/* Receiver classes, adaptive sampling's blocks, the error estimate and the stop rule with its
 * receivers (TRANSPORT.md §Adaptive sampling, §Stop subset). */
#include "bake/transport/transport_impl.h"

#include "scene/clock.h"

/* ---- adaptive sampling's blocks: receiver index / BK_TRANSPORT_BLOCK, cut at the class bounds */

/* The receivers [*lo, *hi) of block b of class k. */
static void block_range(const tp_ctx *c, int k, size_t b, size_t *lo, size_t *hi)
{
    const size_t chunk = c->cls[k].begin / BK_TRANSPORT_BLOCK + (b - c->blk_first[k]);
    *lo = chunk * BK_TRANSPORT_BLOCK > c->cls[k].begin ? chunk * BK_TRANSPORT_BLOCK : c->cls[k].begin;
    *hi = (chunk + 1) * BK_TRANSPORT_BLOCK < c->cls[k].end ? (chunk + 1) * BK_TRANSPORT_BLOCK : c->cls[k].end;
}

/* The classes from options.class_end (validated by check_inputs; without it one class), and
 * their blocks. */
lbk_result bk_tr_init_classes(tp_ctx *c)
{
    const size_t *end = c->opt->class_end;
    c->ncls = end[BK_RECEIVER_CLASSES - 1] ? BK_RECEIVER_CLASSES : 1;
    size_t nb = 0;
    for (int k = 0; k < c->ncls; k++) {
        tp_class *cl = &c->cls[k];
        cl->begin = k ? c->cls[k - 1].end : 0;
        cl->end = c->ncls == 1 ? c->recv_count : end[k];
        cl->active = cl->end > cl->begin;
        cl->stop = BK_STOP_BUDGET;
        c->blk_first[k] = nb;
        if (cl->active) nb += (cl->end - 1) / BK_TRANSPORT_BLOCK - cl->begin / BK_TRANSPORT_BLOCK + 1;
    }
    for (int k = c->ncls; k <= BK_RECEIVER_CLASSES; k++) c->blk_first[k] = nb;
    c->blk_count = nb;
    c->adapt = c->opt->adaptive > 0 && c->target > 0;
    c->blk_w = calloc(nb ? nb : 1, sizeof *c->blk_w);
    c->blk_on = malloc(nb ? nb : 1);
    c->blk_next = malloc(nb ? nb : 1);
    if (!c->blk_w || !c->blk_on || !c->blk_next) return LBK_ERR_OUT_OF_MEMORY;
    memset(c->blk_on, 1, nb);
    memset(c->blk_next, 1, nb);
    return LBK_OK;
}

/* What the run reports as its samples and its reason to stop: the texels' when there are any
 * (REPT's samples_per_texel and status are about lightmap texels, spec §7), else the class
 * that sampled longest. */
const tp_class *bk_tr_lead_class(const tp_ctx *c)
{
    const tp_class *best = &c->cls[0];
    if (best->end > best->begin) return best;
    for (int k = 1; k < c->ncls; k++)
        if (c->cls[k].end > c->cls[k].begin && c->cls[k].spp > best->spp) best = &c->cls[k];
    return best;
}

/* The lead class's mean samples per receiver (its samples without adaptive sampling). */
double bk_tr_lead_samples(const tp_ctx *c) { return bk_tr_mean_samples(c, (int)(bk_tr_lead_class(c) - c->cls)); }

/* ---- the stop rule's receivers (TRANSPORT.md §Stop subset) -------------------------------- */

/* Class k's stop subset when it has more than `cap` blocks: one block per stratum of n/cap
 * consecutive ones, at an offset hashed from (class, stratum) (no seed: the subset is the
 * layout's, not the noise's). Receivers lie in atlas / probe order, so strata spread the subset
 * over the whole level and the hash keeps it off any row pattern. Whole blocks, so that a unit
 * of a distributed run that gathers them decides their adaptive stops as the whole run does.
 * Returns the block's offset in the class; n > cap. */
static size_t stop_pick(size_t n, size_t cap, int k, size_t j)
{
    const size_t q = n / cap, r = n % cap; /* strata of q + 1 blocks first, then of q */
    const size_t lo = j * q + (j < r ? j : r), len = q + (j < r);
    return lo + (size_t)(bk_mix64(0x5707A11D00000000ull ^ ((uint64_t)k << 40) ^ (uint64_t)j) % len);
}

/* The subsets, and the receivers the rule reads outside [g_begin, g_end) (those of every class
 * only when the run has a target and is cut). */
lbk_result bk_tr_stop_init(tp_ctx *c)
{
    const size_t cap = c->opt->stop_receivers > 0 ? c->opt->stop_receivers : BK_TRANSPORT_STOP_RECEIVERS;
    const size_t capb = cap / BK_TRANSPORT_BLOCK > 0 ? cap / BK_TRANSPORT_BLOCK : 1;
    const int cut = c->target > 0 && (c->g_begin != 0 || c->g_end != c->recv_count);
    size_t subs = 0, extras = 0;
    for (int k = 0; k < c->ncls; k++) {
        const size_t nb = c->blk_first[k + 1] - c->blk_first[k];
        c->stop_sub[k] = nb > capb;
        subs += nb > capb ? capb * BK_TRANSPORT_BLOCK : 0;
        extras += nb > capb ? capb * BK_TRANSPORT_BLOCK : c->cls[k].end - c->cls[k].begin;
    }
    c->stop_idx = malloc((subs ? subs : 1) * sizeof *c->stop_idx);
    c->extra = malloc((cut && extras ? extras : 1) * sizeof *c->extra);
    if (!c->stop_idx || !c->extra) return LBK_ERR_OUT_OF_MEMORY;
    size_t ns = 0, ne = 0;
    for (int k = 0; k < c->ncls; k++) {
        const size_t b0 = c->blk_first[k], nb = c->blk_first[k + 1] - b0;
        c->stop_first[k] = ns, c->extra_first[k] = ne;
        for (size_t j = 0; j < (c->stop_sub[k] ? capb : nb); j++) {
            size_t lo, hi;
            block_range(c, k, b0 + (c->stop_sub[k] ? stop_pick(nb, capb, k, j) : j), &lo, &hi);
            for (size_t i = lo; i < hi; i++) {
                if (c->stop_sub[k]) c->stop_idx[ns++] = i;
                if (cut && (i < c->g_begin || i >= c->g_end)) c->extra[ne++] = i;
            }
        }
    }
    for (int k = c->ncls; k <= BK_RECEIVER_CLASSES; k++) c->stop_first[k] = ns, c->extra_first[k] = ne;
    return LBK_OK;
}

/* Class k's receivers that sample in this pass (class_on) and, with adaptive sampling, their
 * mean samples so far (bk_tr_mean_samples): over its stop subset where it has one (scaled to the
 * class), so that every unit of a distributed run counts alike without the other units' blocks. */
static size_t class_on(const tp_ctx *c, int k)
{
    const size_t n = c->cls[k].end - c->cls[k].begin;
    if (c->stop_sub[k]) {
        const size_t all = c->stop_first[k + 1] - c->stop_first[k];
        size_t on = 0;
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++)
            on += c->blk_on[bk_tr_block_of(c, c->stop_idx[p])];
        return all ? (size_t)((uint64_t)n * on / all) : n;
    }
    size_t on = 0;
    for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
        size_t lo, hi;
        block_range(c, k, b, &lo, &hi);
        if (c->blk_on[b]) on += hi - lo;
    }
    return on;
}

/* (its spp scaled by its blocks' share of its weight: the samples of pass p are 2^p those of
 * pass 0, as its weight is) */
double bk_tr_mean_samples(const tp_ctx *c, int k)
{
    const tp_class *cl = &c->cls[k];
    if (!c->adapt || k >= c->ncls || !(cl->weight_sum > 0)) return cl->spp;
    double sum = 0, n = 0;
    if (c->stop_sub[k])
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++)
            sum += c->blk_w[bk_tr_block_of(c, c->stop_idx[p])], n++;
    else
        for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
            size_t lo, hi;
            block_range(c, k, b, &lo, &hi);
            sum += (double)(hi - lo) * c->blk_w[b], n += (double)(hi - lo);
        }
    return n > 0 ? cl->spp * sum / (n * cl->weight_sum) : cl->spp;
}

size_t bk_tr_active_receivers(const tp_ctx *c)
{
    size_t active = 0;
    for (int k = 0; k < c->ncls; k++)
        if (c->cls[k].active) active += class_on(c, k);
    return active;
}

/* After a pass of weight w: the blocks that sampled in it, of the classes that did. */
void bk_tr_add_block_weights(tp_ctx *c, double w)
{
    for (int k = 0; k < c->ncls; k++)
        for (size_t b = c->blk_first[k]; c->cls[k].active && b < c->blk_first[k + 1]; b++)
            if (c->blk_on[b]) c->blk_w[b] += w;
}

/* The error estimates after a pass (TRANSPORT.md): the noise from the two independent halves
 * (all receivers, and per class), and the cache's bias from the probes, whose two halves'
 * product is an unbiased estimate of each receiver's squared bias. Relative to the RMS of the
 * receivers' values. */

void bk_tr_estimate_error_of(const tp_ctx *c, double *const x_acc[2], double *const b_acc[2], double *noise,
                             double *bias, tp_errors *ce)
{
    double num = 0, den = 0, bb = 0, cnum[BK_RECEIVER_CLASSES] = {0}, cden[BK_RECEIVER_CLASSES] = {0};
    for (int k = 0; k < c->ncls; k++) {
        for (size_t blk = c->blk_first[k]; blk < c->blk_first[k + 1]; blk++) {
            if (!(c->blk_w[blk] > 0)) continue;
            const double inv = 1 / c->blk_w[blk];
            size_t lo, hi;
            block_range(c, k, blk, &lo, &hi);
            for (size_t i = lo; i < hi; i++) {
                double a = x_acc[0][i] * inv, b = x_acc[1][i] * inv;
                double m = 0.5 * (a + b), v = 0.25 * (a - b) * (a - b);
                cnum[k] += v;
                cden[k] += m * m;
                bb += (b_acc[0][i] * inv) * (b_acc[1][i] * inv);
            }
        }
        num += cnum[k];
        den += cden[k];
    }
    *noise = den > 0 ? sqrt(num / den) : 0;
    *bias = den > 0 && bb > 0 ? sqrt(bb / den) : 0;
    for (int k = 0; k < BK_RECEIVER_CLASSES; k++) ce->cls[k] = cden[k] > 0 ? sqrt(cnum[k] / cden[k]) : 0;
    ce->probe = cden[1] + cden[2] > 0 ? sqrt((cnum[1] + cnum[2]) / (cden[1] + cden[2])) : 0;
}

void bk_tr_estimate_error(const tp_ctx *c, double *noise, double *bias, tp_errors *ce)
{
    bk_tr_estimate_error_of(c, c->x_acc, c->b_acc, noise, bias, ce);
}

/* The estimate the stop rule reads: the class's own (ce) where it stops on all its receivers,
 * else the same sums over its subset. */
void bk_tr_stop_errors(const tp_ctx *c, const tp_errors *ce, tp_errors *sce)
{
    *sce = *ce;
    for (int k = 0; k < c->ncls; k++) {
        if (!c->stop_sub[k] || !(c->cls[k].weight_sum > 0)) continue;
        double num = 0, den = 0;
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++) {
            const size_t i = c->stop_idx[p];
            const double w = c->blk_w[bk_tr_block_of(c, i)], inv = w > 0 ? 1 / w : 0;
            double a = c->x_acc[0][i] * inv, b = c->x_acc[1][i] * inv, m = 0.5 * (a + b);
            num += 0.25 * (a - b) * (a - b);
            den += m * m;
        }
        sce->cls[k] = den > 0 ? sqrt(num / den) : 0;
    }
}

/* The mean over class k's receivers (its stop subset where it has one) of m², m the mean of a
 * receiver's two halves. */
static double class_mean_square(const tp_ctx *c, int k, double *const x_acc[2])
{
    double den = 0, n = 0;
    if (c->stop_sub[k])
        for (size_t p = c->stop_first[k]; p < c->stop_first[k + 1]; p++) {
            const size_t i = c->stop_idx[p];
            const double w = c->blk_w[bk_tr_block_of(c, i)], m = w > 0 ? 0.5 * (x_acc[0][i] + x_acc[1][i]) / w : 0;
            den += m * m, n++;
        }
    else
        for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
            const double inv = c->blk_w[b] > 0 ? 1 / c->blk_w[b] : 0;
            size_t lo, hi;
            block_range(c, k, b, &lo, &hi);
            for (size_t i = lo; i < hi; i++) {
                const double m = 0.5 * (x_acc[0][i] + x_acc[1][i]) * inv;
                den += m * m, n++;
            }
        }
    return n > 0 ? den / n : 0;
}

/* Adaptive sampling, after pass `pass`: which blocks sample in the next one. A block goes on
 * while its noise per receiver (its halves' difference, v) exceeds what the target allows the
 * class's mean receiver, target² · S with S the class's mean square: once every block is below,
 * so is the class, and until then the samples go to the blocks that hold the error (in the
 * class's own metric, so dark blocks stop first; TRANSPORT.md §Adaptive sampling has what was
 * measured against a relative rule). A pure function of the accumulators, the weights and S
 * (over the stop subset where the class has one), so a unit of a distributed run, the merge's
 * replay and a resumed run decide alike; a block that falls behind as S changes comes back. A
 * block without light (or outside a unit's receivers: never gathered there) stops. */
void bk_tr_adapt_mark(tp_ctx *c, int pass, double *const x_acc[2])
{
    if (!c->adapt) return;
    for (int k = 0; k < c->ncls; k++) {
        const size_t b0 = c->blk_first[k], nb = c->blk_first[k + 1] - b0;
        if (pass < BK_TRANSPORT_ADAPT_PASS) {
            memset(c->blk_next + b0, 1, nb);
            continue;
        }
        const double allow = c->target * c->target * class_mean_square(c, k, x_acc);
        for (size_t blk = b0; blk < b0 + nb; blk++) {
            const double inv = c->blk_w[blk] > 0 ? 1 / c->blk_w[blk] : 0;
            size_t lo, hi;
            block_range(c, k, blk, &lo, &hi);
            double num = 0;
            for (size_t i = lo; i < hi; i++) {
                const double d = (x_acc[0][i] - x_acc[1][i]) * inv;
                num += 0.25 * d * d;
            }
            c->blk_next[blk] = num > allow * (double)(hi - lo);
        }
    }
}

/* Class k's blocks that sample in the next pass (its probes' only once the texels have stopped,
 * as for the target below); 0 when none does: the class has reached its target. The merge's
 * replay calls it with the classes that sampled in the next pass active, as bk_tr_stop_after left them. */
int bk_tr_adapt_apply(tp_ctx *c, int k)
{
    size_t on = 0;
    for (size_t b = c->blk_first[k]; b < c->blk_first[k + 1]; b++) {
        if (c->adapt && (k == 0 || !c->cls[0].active)) c->blk_on[b] = c->blk_next[b];
        on += c->blk_on[b];
    }
    return on > 0;
}

/* Which classes stop after this pass: a class whose estimate reached the target, or whose next
 * pass would pass the sample budget; every class when the next pass (about twice the cost of
 * this one) could not finish within the time limit. Returns 1 when none samples any more.
 * Probes stop on their target only once the texels have stopped: the estimate measures their
 * fluence, not the directions of their SH (in a furnace it is exactly 0 at any count while 32
 * directions leave the SH's bands 1–2 visibly wrong), so they get at least the texels' samples.
 * With adaptive sampling the converged blocks stop first, the budget is of the class's mean
 * samples per receiver (what the blocks that go on add to it), and a class none of whose blocks
 * goes on has reached its target. */
int bk_tr_stop_after(tp_ctx *c, int pass, const tp_errors *ce, double pass_seconds)
{
    const bk_transport_options *opt = c->opt;
    const int late = opt->time_limit > 0 && bk_now() - c->t0 + 2.1 * pass_seconds > opt->time_limit;
    int left = 0;
    for (int k = 0; k < c->ncls; k++) {
        tp_class *cl = &c->cls[k];
        if (!cl->active) continue;
        const double step = 2.0 * (c->s0 << (pass + 1 < 20 ? pass + 1 : 20));
        const int texels_sampling = k > 0 && c->cls[0].active, going = bk_tr_adapt_apply(c, k);
        const double next = c->adapt ? bk_tr_mean_samples(c, k) +
                                           step * (double)class_on(c, k) / (double)(cl->end - cl->begin)
                                     : cl->spp + step;
        if (!going || (c->target > 0 && ce->cls[k] <= c->target && !texels_sampling)) cl->stop = BK_STOP_TARGET;
        else if (next > c->max_samples || pass >= 24) cl->stop = BK_STOP_BUDGET;
        else if (late) cl->stop = BK_STOP_TIME;
        else { left++; continue; }
        cl->active = 0;
    }
    return left == 0;
}
