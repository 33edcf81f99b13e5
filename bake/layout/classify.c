/* Object classification: lightmap / LLG / none (rules in classify.h). */
#include "bake/layout/classify.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/uv_math.h"

const char *bk_rep_name(int rep)
{
    switch (rep) {
    case BK_REP_NONE: return "none";
    case BK_REP_LIGHTMAP: return "lightmap";
    case BK_REP_LLG: return "llg";
    default: return "unknown";
    }
}

const char *bk_rep_reason_name(int reason)
{
    switch (reason) {
    case BK_REASON_AUTHORED: return "authored";
    case BK_REASON_EMPTY: return "empty";
    case BK_REASON_EMISSIVE: return "emissive";
    case BK_REASON_DOOR: return "door";
    case BK_REASON_INTRICATE: return "intricate";
    case BK_REASON_SMALL: return "small";
    case BK_REASON_DEFAULT: return "default";
    default: return "unknown";
    }
}

/* 1 when every point of the material emits: factor > 0 and no black texel in its texture. */
static int material_emits_everywhere(const bk_scene *s, const bk_material *m)
{
    float f = fmaxf(m->emission[0], fmaxf(m->emission[1], m->emission[2]));
    if (!(f > 0.0f)) return 0;
    if (m->emission_tex < 0) return 1;
    if ((size_t)m->emission_tex >= s->image_count) return 0;
    const bk_image *im = &s->images[m->emission_tex];
    if (!im->rgba || im->width <= 0 || im->height <= 0) return 0;
    size_t n = (size_t)im->width * (size_t)im->height;
    for (size_t i = 0; i < n; i++) {
        /* the emitted radiance is factor × texel, per channel: any channel lit counts */
        const float *p = im->rgba + 4 * i;
        if (!(m->emission[0] * p[0] > 0.0f || m->emission[1] * p[1] > 0.0f || m->emission[2] * p[2] > 0.0f))
            return 0;
    }
    return 1;
}

lbk_result bk_classify_objects(const bk_scene *s, const bk_classify_options *opt, bk_object_class *out)
{
    if (!s || (!out && s->object_count)) return LBK_ERR_INVALID_ARGUMENT;
    float small = opt && opt->small_diagonal > 0.0f ? opt->small_diagonal : 2.0f;
    uint32_t simple = opt && opt->simple_tris > 0 ? opt->simple_tris : 64;
    float intricate = opt && opt->intricate_density > 0.0f ? opt->intricate_density : 500.0f;
    /* per material: -1 unknown, 0 no, 1 emits everywhere (computed once; textures can be big) */
    signed char *emits = malloc(s->material_count ? s->material_count : 1);
    if (!emits) return LBK_ERR_OUT_OF_MEMORY;
    memset(emits, -1, s->material_count ? s->material_count : 1);
    for (size_t o = 0; o < s->object_count; o++) {
        const bk_object *ob = &s->objects[o];
        bk_object_class *c = &out[o];
        memset(c, 0, sizeof *c);
        double mn[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, mx[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, area = 0.0;
        uint32_t live = 0;
        int all_emit = 1;
        uint64_t end = (uint64_t)ob->first_tri + ob->tri_count;
        if (end > s->tri_count) end = s->tri_count;
        for (uint64_t t = ob->first_tri; t < end; t++) {
            double p[3][3], n[3];
            if (!bk_tri_positions(s, (size_t)t, p)) continue;
            bk_tri_cross(p, n);
            double a = 0.5 * bkv_len(n);
            if (!(a > 0.0) || !isfinite(a)) continue;
            live++;
            area += a;
            for (int k = 0; k < 3; k++)
                for (int q = 0; q < 3; q++) {
                    mn[q] = fmin(mn[q], p[k][q]);
                    mx[q] = fmax(mx[q], p[k][q]);
                }
            if (all_emit) {
                uint32_t m = s->tri_material ? s->tri_material[t] : UINT32_MAX;
                if (m >= s->material_count) {
                    all_emit = 0;
                } else {
                    if (emits[m] < 0) emits[m] = (signed char)material_emits_everywhere(s, &s->materials[m]);
                    all_emit = emits[m] == 1;
                }
            }
        }
        double diag = 0.0;
        if (live)
            for (int q = 0; q < 3; q++) diag += (mx[q] - mn[q]) * (mx[q] - mn[q]);
        c->diagonal = (float)sqrt(diag);
        c->area = (float)area;
        c->live_tris = live;
        if (ob->lighting == BK_LIGHTING_LIGHTMAP || ob->lighting == BK_LIGHTING_LLG || ob->lighting == BK_LIGHTING_NONE) {
            c->rep = ob->lighting == BK_LIGHTING_LIGHTMAP ? BK_REP_LIGHTMAP
                     : ob->lighting == BK_LIGHTING_LLG    ? BK_REP_LLG
                                                          : BK_REP_NONE;
            c->reason = BK_REASON_AUTHORED;
        } else if (live == 0) {
            c->rep = BK_REP_NONE;
            c->reason = BK_REASON_EMPTY;
        } else if (all_emit && ob->light_set[0] == '\0') {
            c->rep = BK_REP_NONE;
            c->reason = BK_REASON_EMISSIVE;
        } else if (ob->door[0] != '\0') {
            c->rep = BK_REP_LLG;
            c->reason = BK_REASON_DOOR;
        } else if ((double)live > intricate * area) {
            c->rep = BK_REP_LLG;
            c->reason = BK_REASON_INTRICATE;
        } else if (c->diagonal < small && live > simple) {
            c->rep = BK_REP_LLG;
            c->reason = BK_REASON_SMALL;
        } else {
            c->rep = BK_REP_LIGHTMAP;
            c->reason = BK_REASON_DEFAULT;
        }
    }
    free(emits);
    return LBK_OK;
}
