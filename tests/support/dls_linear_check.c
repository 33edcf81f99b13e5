/* The linear mode's exactness check (dls_linear_check.h). */
#include "dls_linear_check.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/sh.h"

int dlslin_open(dlslin *d, const lbk_dls_view *view, const lbk_door_view *doors, const uint32_t *base_z,
                const uint8_t *base_rgba, const uint8_t *base_glg, const uint8_t *base_llg)
{
    memset(d, 0, sizeof *d);
    d->view = view;
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) d->n[s] = lbk_dls_target_count(view, s);
    d->base_z = base_z, d->base_rgba = base_rgba, d->base_probe[0] = base_glg, d->base_probe[1] = base_llg;
    const uint64_t nt = d->n[0] + 1;
    d->out_z = calloc(nt, 4), d->out_rgba = calloc(nt, 4);
    for (int p = 0; p < 2; p++) d->out_probe[p] = calloc(d->n[1 + p] + 1, 28);
    for (int k = 0; k < 2; k++) {
        for (int c = 0; c < 3; c++) d->lin[k][c] = calloc(nt, 16);
        for (int p = 0; p < 2; p++) d->lin_probe[k][p] = calloc(d->n[1 + p] + 1, 27 * sizeof(float));
    }
    d->eff = calloc(lbk_dls_set_count(view) + 1, sizeof *d->eff);
    uint64_t most = d->n[0] > d->n[1] ? d->n[0] : d->n[1];
    most = most > d->n[2] ? most : d->n[2];
    d->seen = calloc(most + 1, 1);
    lbk_dls_runtime_desc rd = LBK_DLS_RUNTIME_DESC_INIT;
    rd.dls = view, rd.doors = doors;
    rd.base_irradiance_z = base_z, rd.base_rgba = base_rgba, rd.base_glg = base_glg, rd.base_llg = base_llg;
    rd.out_irradiance_z = d->out_z, rd.out_rgba = d->out_rgba;
    rd.out_glg = base_glg ? d->out_probe[0] : NULL, rd.out_llg = base_llg ? d->out_probe[1] : NULL;
    if (lbk_dls_runtime_open(&rd, &d->bytes) != LBK_OK) return 1;
    for (int k = 0; k < 2; k++) {
        lbk_dls_runtime_desc ld = LBK_DLS_RUNTIME_DESC_INIT;
        ld.dls = view, ld.doors = doors, ld.job_targets = k ? 100 : 0; /* another split too */
        ld.base_irradiance_z = base_z, ld.base_rgba = base_rgba, ld.base_glg = base_glg, ld.base_llg = base_llg;
        ld.flags = LBK_DLS_RUNTIME_LINEAR | (k ? LBK_DLS_RUNTIME_SCALAR : 0);
        for (int c = 0; c < 3; c++) ld.out_linear_texel[c] = d->lin[k][c];
        ld.out_linear_glg = base_glg ? d->lin_probe[k][0] : NULL, ld.out_linear_llg = base_llg ? d->lin_probe[k][1] : NULL;
        if (lbk_dls_runtime_open(&ld, &d->linear[k]) != LBK_OK) return 1;
    }
    return 0;
}

void dlslin_close(dlslin *d)
{
    lbk_dls_runtime_close(d->bytes);
    for (int k = 0; k < 2; k++) {
        lbk_dls_runtime_close(d->linear[k]);
        for (int c = 0; c < 3; c++) free(d->lin[k][c]);
        for (int p = 0; p < 2; p++) free(d->lin_probe[k][p]);
    }
    free(d->out_z), free(d->out_rgba), free(d->out_probe[0]), free(d->out_probe[1]);
    free(d->eff), free(d->seen);
    memset(d, 0, sizeof *d);
}

typedef struct check_ctx {
    dlslin *d;
    uint32_t space;
    dlslin_counts *n;
} check_ctx;

static void texel_base(const dlslin *d, uint64_t t, lbk_ahd_linear *out)
{
    lbk_ahd_texel b = {d->base_z[t], {0}};
    memcpy(b.rgba, d->base_rgba + 4 * t, 4);
    lbk_ahd_to_linear(&b, out);
}

/* Target t of a space against the accumulator; weighted: it had an entry of non-zero weight. */
static bool texel_ok(const dlslin *d, uint64_t t, const lbk_ahd_linear *acc, bool weighted, dlslin_counts *n)
{
    bool ok = true;
    for (int k = 0; k < 2; k++)
        for (int c = 0; c < 3; c++) ok &= !memcmp(d->lin[k][c] + 4 * t, acc->c[c], 16);
    if (weighted) {
        lbk_ahd_texel o;
        lbk_ahd_from_linear(acc, &o);
        ok &= o.irradiance_z == d->out_z[t] && !memcmp(o.rgba, d->out_rgba + 4 * t, 4);
    } else {
        ok &= d->out_z[t] == d->base_z[t] && !memcmp(d->out_rgba + 4 * t, d->base_rgba + 4 * t, 4);
        lbk_ahd_texel o;
        lbk_ahd_from_linear(acc, &o);
        n->reencode_differs += o.irradiance_z != d->base_z[t] || memcmp(o.rgba, d->base_rgba + 4 * t, 4);
    }
    return ok;
}

static bool probe_ok(const dlslin *d, uint32_t p, uint64_t t, const lbk_sh9_rgb *acc, bool weighted, dlslin_counts *n)
{
    bool ok = true;
    for (int k = 0; k < 2; k++) ok &= !memcmp(d->lin_probe[k][p] + 27 * t, acc, sizeof *acc);
    uint8_t o[28];
    lbk_sh9_pack(acc, o);
    if (weighted) ok &= !memcmp(o, d->out_probe[p] + 28 * t, 28);
    else {
        ok &= !memcmp(d->out_probe[p] + 28 * t, d->base_probe[p] + 28 * t, 28);
        n->reencode_differs += memcmp(o, d->base_probe[p] + 28 * t, 28) != 0;
    }
    return ok;
}

static int check_target(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    check_ctx *x = user;
    dlslin *d = x->d;
    bool weighted = false;
    d->seen[target] = 1;
    if (x->space == LBK_DLS_SPACE_TEXEL) {
        lbk_ahd_linear acc;
        texel_base(d, target, &acc);
        for (uint32_t e = 0; e < count; e++) {
            if (d->eff[sets[e]] == 0.0f) continue;
            lbk_ahd_texel tx;
            lbk_ahd_texel_unpack(payloads + 8 * (size_t)e, &tx);
            lbk_ahd_linear l;
            lbk_ahd_to_linear(&tx, &l);
            lbk_ahd_linear_add_scaled(&acc, &l, d->eff[sets[e]]);
            weighted = true;
        }
        x->n->mismatches += !texel_ok(d, target, &acc, weighted, x->n);
    } else {
        const uint32_t p = x->space - 1;
        lbk_sh9_rgb acc;
        lbk_sh9_unpack(d->base_probe[p] + 28 * (size_t)target, &acc);
        for (uint32_t e = 0; e < count; e++) {
            if (d->eff[sets[e]] == 0.0f) continue;
            lbk_sh9_rgb l;
            lbk_sh9_unpack(payloads + 28 * (size_t)e, &l);
            lbk_sh9_add_scaled(&acc, &l, d->eff[sets[e]]);
            weighted = true;
        }
        x->n->mismatches += !probe_ok(d, p, target, &acc, weighted, x->n);
    }
    x->n->weighted += weighted;
    return 0;
}

static bool same_dirty(const dlslin *d, const lbk_dls_runtime *r)
{
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        if (lbk_dls_dirty_range_count(r, s) != lbk_dls_dirty_range_count(d->bytes, s)) return false;
        for (uint32_t i = 0; i < lbk_dls_dirty_range_count(r, s); i++) {
            lbk_dls_range a, b;
            lbk_dls_dirty_range_get(r, s, i, &a);
            lbk_dls_dirty_range_get(d->bytes, s, i, &b);
            if (a.first != b.first || a.count != b.count) return false;
        }
    }
    return true;
}

int dlslin_apply_check(dlslin *d, const float *set_weights, const float *door_weights, dlslin_counts *out)
{
    memset(out, 0, sizeof *out);
    lbk_dls_apply_stats sb, sl;
    if (lbk_dls_apply(d->bytes, set_weights, door_weights, &sb) != LBK_OK) return 1;
    int bad = 0;
    for (int k = 0; k < 2; k++) {
        if (lbk_dls_apply(d->linear[k], set_weights, door_weights, &sl) != LBK_OK) return 1;
        bad |= sb.clusters_applied != sl.clusters_applied || sb.clusters_copied != sl.clusters_copied ||
               sb.clusters_skipped != sl.clusters_skipped || sb.targets_written != sl.targets_written;
        if (k == 0) bad |= !same_dirty(d, d->linear[k]); /* the same split: the same regions */
    }
    if (lbk_dls_effective_weights(d->bytes, set_weights, door_weights, d->eff) != LBK_OK) return 1;
    for (uint32_t s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
        if (s > 0 && !d->base_probe[s - 1]) continue;
        memset(d->seen, 0, d->n[s] + 1);
        check_ctx x = {d, s, out};
        for (uint32_t c = 0; c < lbk_dls_cluster_count(d->view); c++) {
            lbk_dls_cluster_info ci;
            lbk_dls_cluster_get(d->view, c, &ci);
            if (ci.space == s && lbk_dls_cluster_decode(d->view, c, check_target, &x) != LBK_OK) return 1;
        }
        for (uint64_t t = 0; t < d->n[s]; t++) { /* in no cluster: the base */
            if (d->seen[t]) continue;
            if (s == LBK_DLS_SPACE_TEXEL) {
                lbk_ahd_linear acc;
                texel_base(d, t, &acc);
                out->mismatches += !texel_ok(d, t, &acc, false, out);
            } else {
                lbk_sh9_rgb acc;
                lbk_sh9_unpack(d->base_probe[s - 1] + 28 * t, &acc);
                out->mismatches += !probe_ok(d, s - 1, t, &acc, false, out);
            }
        }
        out->targets += d->n[s];
    }
    return bad || out->mismatches != 0;
}
