/* lbk diff of the OCTP octahedral probes (spec/diff-json.md "octp"): layout, per-probe
 * irradiance and depth moments, probe states. */
#include <string.h>

#include "tools/inspect/diff.h"

static int same_level(const lbk_octp_level *x, const lbk_octp_level *y)
{
    return !memcmp(x->origin, y->origin, sizeof x->origin) && x->spacing == y->spacing &&
           !memcmp(x->dims, y->dims, sizeof x->dims);
}

static int same_position(const lbk_octp_view *a, const lbk_octp_view *b, uint32_t i)
{
    lbk_octp_probe_desc pa, pb;
    if (lbk_octp_probe_get(a, i, &pa) != LBK_OK || lbk_octp_probe_get(b, i, &pb) != LBK_OK) return 0;
    return !memcmp(pa.position, pb.position, sizeof pa.position);
}

/* Probes line up by index when the layouts match: the same volume grids (relocation offsets may
 * differ, they are reported as moved), or lists with the same positions. */
static int octp_same_layout(const lbk_octp_view *a, const lbk_octp_view *b)
{
    if (a->level_count != b->level_count || a->probe_count != b->probe_count) return 0;
    for (uint32_t l = 0; l < a->level_count; l++)
        if (!same_level(&a->levels[l], &b->levels[l])) return 0;
    if (a->level_count) return 1;
    for (uint32_t i = 0; i < a->probe_count; i++)
        if (!same_position(a, b, i)) return 0;
    return 1;
}

static void count_states(const lbk_octp_view *v, uint32_t out[3])
{
    for (uint32_t i = 0; i < v->probe_count && v->level_count; i++) {
        lbk_octp_probe_info in;
        if (lbk_octp_probe_info_get(v, i, &in) == LBK_OK && in.state < 3) out[in.state]++;
    }
}

/* State of probe i (list form: active) and its info (zero in the list form). */
static uint32_t probe_state(const lbk_octp_view *v, uint32_t i, lbk_octp_probe_info *in)
{
    memset(in, 0, sizeof *in);
    if (!v->level_count || lbk_octp_probe_info_get(v, i, in) != LBK_OK) return LBK_OCTP_ACTIVE;
    return in->state;
}

/* One probe pair. Inside-geometry probes carry no light a sampler uses (it skips them), so their
 * texels are not compared; a probe that turns inside is a state change. */
static void compare_probe(const lbk_octp_view *va, const lbk_octp_view *vb, uint32_t i, double abs_tol, double rel_tol,
                          const tl_noise_model *noise, tl_diff_octp *d)
{
    lbk_octp_probe_info ia, ib;
    const uint32_t sa = probe_state(va, i, &ia), sb = probe_state(vb, i, &ib);
    d->state_changes += sa != sb;
    d->moved += memcmp(ia.offset, ib.offset, sizeof ia.offset) != 0;
    if (sa == LBK_OCTP_INSIDE || sb == LBK_OCTP_INSIDE) return;
    lbk_octp_probe_desc pa, pb;
    if (lbk_octp_probe_get(va, i, &pa) != LBK_OK || lbk_octp_probe_get(vb, i, &pb) != LBK_OK) return;
    const size_t texels = LBK_OCTP_IRR_N * LBK_OCTP_IRR_N;
    tl_err_add(&d->lighting, &pa.irradiance[0][0], &pb.irradiance[0][0], 3 * texels, abs_tol, rel_tol, i, 0, NULL);
    tl_err_add(&d->depth, &pa.depth[0][0], &pb.depth[0][0], 2 * LBK_OCTP_DEPTH_N * LBK_OCTP_DEPTH_N, abs_tol, rel_tol,
               i, 0, NULL);
    if (noise)
        tl_noise_add(&d->noise, noise, &pa.irradiance[0][0], &pb.irradiance[0][0], (int)texels, d->noise.noise_a,
                     d->noise.noise_b);
}

void tl_diff_octp_run(const tl_bake *a, const tl_bake *b, double abs_tol, double rel_tol, const tl_noise_model *noise,
                      tl_diff_result *r)
{
    tl_diff_octp *d = &r->octp;
    memset(d, 0, sizeof *d);
    d->count_a = a->has_octp ? a->octp.probe_count : 0;
    d->count_b = b->has_octp ? b->octp.probe_count : 0;
    d->levels_a = a->has_octp ? a->octp.level_count : 0;
    d->levels_b = b->has_octp ? b->octp.level_count : 0;
    if (a->has_octp) count_states(&a->octp, d->states_a);
    if (b->has_octp) count_states(&b->octp, d->states_b);
    if (!a->has_octp || !b->has_octp) {
        d->status = a->has_octp ? TL_DIFF_REMOVED : b->has_octp ? TL_DIFF_ADDED : -1;
        return;
    }
    d->comparable = octp_same_layout(&a->octp, &b->octp);
    if (!d->comparable) {
        d->status = TL_DIFF_CHANGED;
        return;
    }
    if (noise) tl_noise_begin(&d->noise, noise, TL_NOISE_OCTP, noise->rept[0][1], noise->rept[1][1]);
    for (uint32_t i = 0; i < a->octp.probe_count; i++) compare_probe(&a->octp, &b->octp, i, abs_tol, rel_tol, noise, d);
    r->probes_over += d->lighting.over;
    int differs;
    if (noise) {
        tl_noise_end(&d->noise, noise);
        r->items_beyond_noise += !d->noise.within_noise;
        differs = !d->noise.within_noise;
    } else {
        differs = d->lighting.over || d->depth.over || d->state_changes || d->moved;
    }
    d->status = differs ? TL_DIFF_CHANGED : TL_DIFF_SAME;
}
