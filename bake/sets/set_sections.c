/* The set bakes' sections: every set's entries encoded in the scale of the base sections into
 * DLS (spec §12.2), and the doors' boxes, sets and combination states into DOOR. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/sets/sets_internal.h"
#include "bake/encode/encode.h"
#include "lbk/container.h"
#include "lbk/door.h"

/* ---- sections -------------------------------------------------------------------------- */

void bk_set_bakes_max(const bk_set_bakes *sets, double max[LBK_DLS_SPACE_COUNT_])
{
    for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) max[s] = 0;
    const bs_impl *im = sets->impl;
    if (!im) return;
    for (size_t j = 0; j < im->set_count; j++) {
        const bs_set *st = &im->sets[j];
        double m = bk_texel_max((const lbk_ahd_linear *)st->values[LBK_DLS_SPACE_TEXEL], NULL,
                                st->count[LBK_DLS_SPACE_TEXEL]);
        if (m > max[LBK_DLS_SPACE_TEXEL]) max[LBK_DLS_SPACE_TEXEL] = m;
        for (int s = LBK_DLS_SPACE_GLG; s < LBK_DLS_SPACE_COUNT_; s++) {
            m = bk_probe_max((const lbk_sh9_rgb *)st->values[s], st->count[s]);
            if (m > max[s]) max[s] = m;
        }
    }
}

/* Every set's entries as DLS payloads, enc[set · spaces + space] (malloc'ed), stored in the
 * scale of the target space's base section (spec §12.2; dividing by a power of two is exact). */
static lbk_result encode_payloads(const bs_impl *im, const bk_set_inputs *in, uint8_t **enc)
{
    for (size_t j = 0; j < im->set_count; j++)
        for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
            const bs_set *st = &im->sets[j];
            const size_t n = st->count[s];
            if (!n) continue;
            const size_t stride = s == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD;
            uint8_t *e = enc[j * LBK_DLS_SPACE_COUNT_ + (size_t)s] = malloc(n * stride);
            if (!e) return LBK_ERR_OUT_OF_MEMORY;
            const float inv = 1.0f / (in->scale[s] > 0 ? in->scale[s] : 1.0f);
            for (size_t i = 0; i < n; i++) {
                if (s == LBK_DLS_SPACE_TEXEL) {
                    lbk_ahd_linear l;
                    memset(&l, 0, sizeof l);
                    lbk_ahd_linear_add_scaled(&l, (const lbk_ahd_linear *)st->values[s] + i, inv);
                    lbk_ahd_texel t;
                    lbk_ahd_from_linear(&l, &t);
                    lbk_ahd_texel_pack(&t, e + stride * i);
                } else {
                    lbk_sh9_rgb sh;
                    memset(&sh, 0, sizeof sh);
                    lbk_sh9_add_scaled(&sh, (const lbk_sh9_rgb *)st->values[s] + i, inv);
                    lbk_sh9_pack(&sh, e + stride * i);
                }
            }
        }
    return LBK_OK;
}

static lbk_result build_dls(const bs_impl *im, const bk_set_inputs *in, uint8_t *const *enc, void **dls, size_t *dls_size)
{
    lbk_dls_set_desc *sd = calloc(im->set_count, sizeof *sd);
    if (!sd) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t j = 0; j < im->set_count; j++) {
        const bs_set *st = &im->sets[j];
        sd[j].name = st->name;
        sd[j].kind = st->kind;
        sd[j].light_count = st->light_count;
        sd[j].light_names = st->light_names;
        sd[j].member_count = st->member_count;
        sd[j].members = st->member_count ? st->members : NULL;
        for (int s = 0; s < LBK_DLS_SPACE_COUNT_; s++) {
            sd[j].entries[s].count = st->count[s];
            sd[j].entries[s].targets = st->targets[s];
            sd[j].entries[s].payloads = enc[j * LBK_DLS_SPACE_COUNT_ + (size_t)s];
        }
    }
    lbk_dls_build_desc bd = LBK_DLS_BUILD_DESC_INIT;
    bd.set_count = (uint32_t)im->set_count;
    bd.sets = sd;
    const bk_texels *tx = in->texels;
    bd.target_count[LBK_DLS_SPACE_TEXEL] =
        tx && tx->page_count && in->texel_receivers ? (uint64_t)tx->page_offset[tx->page_count] : 0;
    bd.target_count[LBK_DLS_SPACE_GLG] = in->glg_count;
    bd.target_count[LBK_DLS_SPACE_LLG] = in->llg_count;
    lbk_result r = lbk_dls_build(&bd, NULL, dls, dls_size, NULL);
    free(sd);
    return r;
}

/* The DOOR section: each door's box (in world space) and sets, and the combination states. */
static lbk_result build_door(const bs_impl *im, const bk_set_inputs *in, void **door, size_t *door_size)
{
    size_t nc = im->combo_count ? im->combo_count : 1;
    lbk_door_desc *dd = calloc(im->door_count, sizeof *dd);
    lbk_door_state_desc *states = calloc(nc, sizeof *states);
    uint32_t *state_doors = calloc(2 * nc, sizeof *state_doors);
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (dd && states && state_doors) {
        for (size_t p = 0; p < im->door_count; p++) {
            const bs_door *d = &im->doors[p];
            dd[p].name = d->name;
            for (int k = 0; k < 3; k++) dd[p].centre[k] = d->centre[k] + in->origin[k];
            memcpy(dd[p].axes, d->axes, sizeof d->axes);
            memcpy(dd[p].half_extents, d->half, sizeof d->half);
            dd[p].open_set = d->open_set;
            dd[p].closed_set = d->closed_set;
        }
        for (size_t c = 0; c < im->combo_count; c++) {
            const bs_combo *co = &im->combos[c];
            state_doors[2 * c] = (uint32_t)co->door[0];
            state_doors[2 * c + 1] = (uint32_t)co->door[1];
            states[c].door_count = co->door[1] >= 0 ? 2 : 1;
            states[c].doors = &state_doors[2 * c];
            states[c].set = co->set;
        }
        lbk_door_build_desc db = LBK_DOOR_BUILD_DESC_INIT;
        db.door_count = (uint32_t)im->door_count;
        db.doors = dd;
        db.state_count = (uint32_t)im->combo_count;
        db.states = states;
        r = lbk_door_build(&db, NULL, door, door_size);
    }
    free(dd), free(states), free(state_doors);
    return r;
}

lbk_result bk_set_bakes_sections(bk_set_bakes *sets, const bk_set_inputs *in, void **dls, size_t *dls_size,
                                 void **door, size_t *door_size)
{
    *dls = *door = NULL;
    *dls_size = *door_size = 0;
    bs_impl *im = sets->impl;
    if (!im || !im->set_count) return LBK_OK;
    uint8_t **enc = calloc(im->set_count * LBK_DLS_SPACE_COUNT_, sizeof *enc); /* encoded payloads */
    if (!enc) return LBK_ERR_OUT_OF_MEMORY;
    lbk_result r = encode_payloads(im, in, enc);
    if (!r) r = build_dls(im, in, enc, dls, dls_size);
    for (size_t i = 0; i < im->set_count * LBK_DLS_SPACE_COUNT_; i++) free(enc[i]);
    free(enc);
    if (r || !im->door_count) return r;
    r = build_door(im, in, door, door_size);
    if (r) {
        lbk_free(NULL, *dls);
        *dls = NULL;
        *dls_size = 0;
    }
    return r;
}
