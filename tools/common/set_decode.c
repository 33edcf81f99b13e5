#include "tools/common/set_decode.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/lightmap.h"
#include "lbk/sh.h"

double tl_texel_lum(uint32_t irradiance_z, const uint8_t rgba[4])
{
    lbk_ahd_texel t;
    t.irradiance_z = irradiance_z;
    memcpy(t.rgba, rgba, 4);
    const float nz[3] = {0, 0, 1};
    float e[3];
    lbk_ahd_irradiance(&t, nz, e);
    return LBK_LUM_R * e[0] + LBK_LUM_G * e[1] + LBK_LUM_B * e[2];
}

double tl_rel_rms(const double *x, const double *y, uint64_t n)
{
    double num = 0, den = 0;
    for (uint64_t i = 0; i < n; i++) num += (x[i] - y[i]) * (x[i] - y[i]), den += y[i] * y[i];
    return den > 0 ? sqrt(num / den) : 0;
}

typedef struct set_decoder {
    lbk_dls_view *dv;
    uint64_t nt, ng, nl;
    uint32_t count;
    uint32_t *z, *oz;
    uint8_t *rgba, *orgba, *bg, *og, *bl, *ol;
    float *w;
} set_decoder;

/* out[i] = luminance of the output with sets on[0..n) at weight 1, the rest 0 */
static int decode_with(set_decoder *sd, const uint32_t *on, int n, double *out)
{
    lbk_dls_runtime_desc rd;
    memset(&rd, 0, sizeof rd);
    rd.dls = sd->dv, rd.base_irradiance_z = sd->z, rd.base_rgba = sd->rgba;
    rd.base_glg = sd->bg, rd.base_llg = sd->bl, rd.out_irradiance_z = sd->oz, rd.out_rgba = sd->orgba;
    rd.out_glg = sd->og, rd.out_llg = sd->ol;
    memset(sd->w, 0, (sd->count + 1) * sizeof *sd->w);
    for (int k = 0; k < n; k++) sd->w[on[k]] = 1;
    lbk_dls_runtime *rt;
    if (lbk_dls_runtime_open(&rd, &rt)) return -1;
    int bad = lbk_dls_apply(rt, sd->w, NULL, NULL) != LBK_OK;
    lbk_dls_runtime_close(rt);
    for (uint64_t i = 0; i < sd->nt && !bad; i++) out[i] = tl_texel_lum(sd->oz[i], &sd->orgba[4 * i]);
    return bad ? -1 : 0;
}

/* Decodes set j into sl (on success *kept = 1; a combination of more than two members: 0). */
static int decode_set(set_decoder *sd, uint32_t j, const double *none, double *part, tl_set_texels *sl, int *kept)
{
    lbk_dls_set_info si;
    *kept = 0;
    if (lbk_dls_set_get(sd->dv, j, &si)) return -1;
    uint32_t m[2];
    const int combo = si.kind == LBK_DLS_KIND_COMBINATION;
    if (combo && (si.member_count != 2 || lbk_dls_set_member_get(sd->dv, j, 0, &m[0]) ||
                  lbk_dls_set_member_get(sd->dv, j, 1, &m[1])))
        return 0;
    snprintf(sl->name, sizeof sl->name, "%.*s", (int)si.name_length, si.name);
    sl->set = j, sl->kind = si.kind;
    sl->lum = malloc(sd->nt * sizeof *sl->lum + 8);
    if (!sl->lum || decode_with(sd, combo ? m : &j, combo ? 2 : 1, sl->lum)) return free(sl->lum), sl->lum = NULL, -1;
    for (uint64_t i = 0; i < sd->nt; i++) sl->lum[i] -= none[i];
    for (int k = 0; combo && k < 2; k++) {
        if (decode_with(sd, &m[k], 1, part)) return free(sl->lum), sl->lum = NULL, -1;
        for (uint64_t i = 0; i < sd->nt; i++) sl->lum[i] -= part[i] - none[i];
    }
    *kept = 1;
    return 0;
}

int tl_set_texels_decode(const void *bytes, size_t size, tl_set_texels *sets, int max_sets, int *nsets, uint64_t *ntex)
{
    lbk_reader *rd;
    const void *d, *dd;
    size_t n, dn;
    lbk_lmap_view lm;
    set_decoder sd;
    memset(&sd, 0, sizeof sd);
    *nsets = 0;
    *ntex = 0;
    if (lbk_reader_open_memory(bytes, size, NULL, &rd)) return -1;
    int bad = lbk_reader_section_by_type(rd, LBK_SECTION_LMAP, &d, &n) || lbk_lmap_open(d, n, &lm) ||
              lbk_reader_section_by_type(rd, LBK_SECTION_DLS, &dd, &dn) || lbk_dls_open(dd, dn, NULL, &sd.dv);
    if (!bad) {
        sd.nt = lm.texel_count;
        sd.ng = lbk_dls_target_count(sd.dv, LBK_DLS_SPACE_GLG);
        sd.nl = lbk_dls_target_count(sd.dv, LBK_DLS_SPACE_LLG);
        sd.count = lbk_dls_set_count(sd.dv);
    }
    /* a black base: the output is the sets' contribution alone, encoded once */
    sd.z = calloc(sd.nt + 1, 4), sd.oz = malloc(sd.nt * 4 + 4), sd.rgba = calloc(sd.nt + 1, 4), sd.orgba = malloc(sd.nt * 4 + 4);
    sd.bg = calloc(sd.ng + 1, 28), sd.og = calloc(sd.ng + 1, 28), sd.bl = calloc(sd.nl + 1, 28), sd.ol = calloc(sd.nl + 1, 28);
    sd.w = calloc(sd.count + 1, sizeof *sd.w);
    double *none = calloc(sd.nt + 1, sizeof *none), *part = calloc(sd.nt + 1, sizeof *part);
    if (!sd.z || !sd.oz || !sd.rgba || !sd.orgba || !sd.bg || !sd.og || !sd.bl || !sd.ol || !sd.w || !none || !part) bad = 1;
    *ntex = sd.nt;
    if (!bad) bad = decode_with(&sd, NULL, 0, none) != 0;
    for (uint32_t j = 0; j < sd.count && *nsets < max_sets && !bad; j++) {
        int kept;
        bad = decode_set(&sd, j, none, part, &sets[*nsets], &kept) != 0;
        *nsets += kept;
    }
    free(none), free(part), free(sd.w), free(sd.z), free(sd.oz), free(sd.rgba), free(sd.orgba);
    free(sd.bg), free(sd.og), free(sd.bl), free(sd.ol);
    if (sd.dv) lbk_dls_close(sd.dv);
    lbk_reader_close(rd);
    if (bad) tl_set_texels_free(sets, *nsets), *nsets = 0;
    return bad ? -1 : 0;
}

void tl_set_texels_free(tl_set_texels *sets, int nsets)
{
    for (int j = 0; j < nsets; j++) free(sets[j].lum), sets[j].lum = NULL;
}
