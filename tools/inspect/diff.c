/* lbk diff: matching and comparing decoded lighting (spec/diff-json.md). */
#include "tools/inspect/diff.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/error_map.h"
#include "lbk/pixel.h"

const char *tl_diff_status_name(int s)
{
    switch (s) {
    case TL_DIFF_SAME: return "same";
    case TL_DIFF_CHANGED: return "changed";
    case TL_DIFF_ADDED: return "added";
    case TL_DIFF_REMOVED: return "removed";
    default: return "absent";
    }
}

const char *tl_diff_mode_name(int mode) { return mode == TL_DIFF_MODE_NOISE ? "noise" : "tolerance"; }

double tl_err_mean(const tl_err_stats *s) { return s->count ? s->sum_abs / (double)s->count : 0.0; }

double tl_err_rel_rmse(const tl_err_stats *s)
{
    if (s->sum_sq_diff == 0.0) return 0.0;
    if (s->sum_sq_ref == 0.0) return INFINITY;
    return sqrt(s->sum_sq_diff / s->sum_sq_ref);
}

/* ---- one sample ---------------------------------------------------------------------------- */

typedef struct tol {
    double abs_tol, rel_tol;
    const tl_noise_model *noise; /* NULL: tolerance mode */
} tol;

int tl_err_add(tl_err_stats *s, const float *a, const float *b, size_t values, double abs_tol, double rel_tol,
               uint32_t x, uint32_t y, float *err_out)
{
    double err = 0, ref = 0, sqd = 0, sqr = 0;
    int nan = 0;
    for (size_t i = 0; i < values; i++) {
        double d = (double)b[i] - (double)a[i];
        if (isnan(d)) nan = 1;
        double ad = fabs(d);
        if (ad > err) err = ad;
        if (fabs((double)a[i]) > ref) ref = fabs((double)a[i]);
        sqd += d * d;
        sqr += (double)a[i] * a[i];
    }
    if (nan) err = INFINITY;
    s->count++;
    s->sum_abs += err;
    s->sum_sq_diff += sqd;
    s->sum_sq_ref += sqr;
    if (err > s->max_abs || s->count == 1) {
        s->max_abs = err;
        s->max_x = x;
        s->max_y = y;
    }
    if (err_out) *err_out = (float)err;
    if (!(err > abs_tol + rel_tol * ref)) return 0;
    s->over++;
    if (!s->has_region) {
        s->has_region = 1;
        s->x0 = s->x1 = x;
        s->y0 = s->y1 = y;
    } else {
        if (x < s->x0) s->x0 = x;
        if (x > s->x1) s->x1 = x;
        if (y < s->y0) s->y0 = y;
        if (y > s->y1) s->y1 = y;
    }
    return 1;
}

/* a and b: n normals × 3 channels. Returns 1 when over tolerance. */
static int add_sample(tl_err_stats *s, const float *a, const float *b, int n, const tol *t, uint32_t x, uint32_t y,
                      float *err_out)
{
    return tl_err_add(s, a, b, 3 * (size_t)n, t->abs_tol, t->rel_tol, x, y, err_out);
}

/* ---- texel access ------------------------------------------------------------------------- */

/* A page of one side: its bake and index, and its planes (any encoding). */
typedef struct pageref {
    const tl_bake *b;
    uint32_t page;
    lbk_lmap_planes pl;
} pageref;

static int pageref_get(const tl_bake *b, uint32_t page, pageref *out)
{
    out->b = b;
    out->page = page;
    return tl_bake_planes(b, page, &out->pl);
}

static void texel_values(const pageref *pg, uint32_t x, uint32_t y, float out[TL_TEXEL_NORMALS][3])
{
    if (tl_bake_texel_eval(pg->b, pg->page, x, y, out)) memset(out, 0, sizeof(float) * 3 * TL_TEXEL_NORMALS);
}

/* A texel the baker never wrote (a rectangle's unused corner): on a 1.0 page all 8 bytes are zero
 * (a written black texel has plane 1 = FF 80 80 FF, spec §5.6). Block pages cannot tell: their
 * encoder was free to put anything there (§9.2), which is why such texels are not compared. */
static int texel_unwritten(const pageref *pg, uint32_t x, uint32_t y)
{
    const lbk_lmap_planes *pl = &pg->pl;
    if (pl->blocks_x || x >= pl->width || y >= pl->height) return 0;
    const size_t i = (size_t)y * pl->width + x;
    static const uint8_t zero[4] = {0, 0, 0, 0};
    return !memcmp(pl->plane[0] + 4 * i, zero, 4) && !memcmp(pl->plane[1] + 4 * i, zero, 4);
}

/* Bilinear sample of the evaluated values at rect-normalised (u, v) of a rect of page pg. */
static void texel_bilinear(const pageref *pg, const uint32_t rect[4], double u, double v,
                           float out[TL_TEXEL_NORMALS][3])
{
    double fx = u * rect[2] - 0.5, fy = v * rect[3] - 0.5;
    if (fx < 0) fx = 0;
    if (fy < 0) fy = 0;
    if (fx > rect[2] - 1) fx = rect[2] - 1;
    if (fy > rect[3] - 1) fy = rect[3] - 1;
    uint32_t x0 = (uint32_t)fx, y0 = (uint32_t)fy;
    uint32_t x1 = x0 + 1 < rect[2] ? x0 + 1 : x0, y1 = y0 + 1 < rect[3] ? y0 + 1 : y0;
    double tx = fx - x0, ty = fy - y0;
    float c[4][TL_TEXEL_NORMALS][3];
    texel_values(pg, rect[0] + x0, rect[1] + y0, c[0]);
    texel_values(pg, rect[0] + x1, rect[1] + y0, c[1]);
    texel_values(pg, rect[0] + x0, rect[1] + y1, c[2]);
    texel_values(pg, rect[0] + x1, rect[1] + y1, c[3]);
    for (int n = 0; n < TL_TEXEL_NORMALS; n++)
        for (int ch = 0; ch < 3; ch++)
            out[n][ch] = (float)((c[0][n][ch] * (1 - tx) + c[1][n][ch] * tx) * (1 - ty) +
                                 (c[2][n][ch] * (1 - tx) + c[3][n][ch] * tx) * ty);
}

static int bake_high_preset(const tl_bake *b)
{
    lbk_string v;
    return b->has_meta && lbk_meta_find(&b->meta, "bake.preset", &v) == LBK_OK && v.size == 4 &&
           memcmp(v.data, "high", 4) == 0;
}

static int bake_denoised(const tl_bake *b)
{
    lbk_string v;
    return b->has_meta && lbk_meta_find(&b->meta, "bake.denoise", &v) == LBK_OK && v.size == 4 &&
           memcmp(v.data, "auto", 4) == 0;
}

/* Relative noise of an object's lightmap (diff_noise.h): the high-pass of its own texels at each
 * of the five normals against the texel's level (its mean over them), the largest of the five, for
 * the mean test (REPT's estimate when the rectangle is too small to tell); and when `local` is not
 * NULL, per texel the high-pass of its 4×4 tile at +Z, for the texel test (malloc'ed, w × h). */
static double rect_noise(const pageref *pg, const uint32_t rect[4], double fallback, double floor_noise, float **local)
{
    const size_t n = (size_t)rect[2] * rect[3];
    if (local) *local = NULL;
    float *lum = malloc(sizeof *lum * (TL_TEXEL_NORMALS + 1) * (n + 1));
    if (!lum) return fallback;
    float *ref = lum + TL_TEXEL_NORMALS * (n + 1);
    for (uint32_t y = 0; y < rect[3]; y++)
        for (uint32_t x = 0; x < rect[2]; x++) {
            float v[TL_TEXEL_NORMALS][3];
            texel_values(pg, rect[0] + x, rect[1] + y, v);
            const size_t i = (size_t)y * rect[2] + x;
            ref[i] = 0;
            for (int k = 0; k < TL_TEXEL_NORMALS; k++) {
                lum[k * (n + 1) + i] = (float)tl_noise_level(v[k], 0, 1);
                ref[i] += lum[k * (n + 1) + i] / TL_TEXEL_NORMALS;
            }
        }
    double s = -1;
    for (int k = 0; k < TL_TEXEL_NORMALS; k++) s = fmax(s, tl_noise_highpass(lum + k * (n + 1), ref, rect[2], rect[3]));
    /* too few texels to measure: REPT's estimate, a bake-wide RMS, spread as for probes */
    if (s < 0) s = TL_NOISE_REPT_SPREAD * fallback;
    s = fmax(s, floor_noise);
    if (local && (*local = malloc(sizeof **local * (n + 1)))) {
        tl_noise_highpass_tiles(lum, rect[2], rect[3], s, *local);
        for (size_t i = 0; i < n; i++) /* -1: not measured at its level, and so not count-tested */
            if ((*local)[i] >= 0) (*local)[i] = fmaxf((*local)[i], (float)floor_noise);
    }
    free(lum);
    return s;
}

/* ---- sections and META ---------------------------------------------------------------------- */

static int diff_sections(const tl_bake *a, const tl_bake *b, tl_diff_result *r)
{
    r->sections = calloc(2 * LBK_MAX_SECTIONS, sizeof *r->sections);
    if (!r->sections) return -1;
    uint32_t types[2 * LBK_MAX_SECTIONS];
    size_t nt = 0;
    const tl_bake *both[2] = {a, b};
    for (int side = 0; side < 2; side++)
        for (uint32_t i = 0; i < lbk_reader_section_count(both[side]->reader); i++) {
            lbk_section_info si;
            lbk_reader_section_get(both[side]->reader, i, &si);
            int seen = 0;
            for (size_t k = 0; k < nt; k++) seen |= types[k] == si.type;
            if (!seen) types[nt++] = si.type;
        }
    for (size_t k = 0; k < nt; k++) {
        tl_diff_section *s = &r->sections[r->section_count++];
        s->type = types[k];
        const void *da = NULL, *db = NULL;
        size_t na = 0, nb = 0;
        int ina = lbk_reader_section_by_type(a->reader, types[k], &da, &na) == LBK_OK;
        int inb = lbk_reader_section_by_type(b->reader, types[k], &db, &nb) == LBK_OK;
        s->a_decoded = na;
        s->b_decoded = nb;
        s->status = !ina ? TL_DIFF_ADDED : !inb ? TL_DIFF_REMOVED
                  : (na == nb && memcmp(da, db, na) == 0) ? TL_DIFF_SAME : TL_DIFF_CHANGED;
        if (s->status != TL_DIFF_SAME) r->sections_changed++;
    }
    return 0;
}

static char *dup_string(lbk_string s)
{
    char *p = malloc(s.size + 1);
    if (p) {
        memcpy(p, s.data, s.size);
        p[s.size] = '\0';
    }
    return p;
}

static int diff_params(const tl_bake *a, const tl_bake *b, tl_diff_result *r)
{
    size_t na = a->has_meta ? a->meta.entry_count : 0, nb = b->has_meta ? b->meta.entry_count : 0;
    r->params = calloc(na + nb + 1, sizeof *r->params);
    if (!r->params) return -1;
    /* keys are sorted in both (lbk_meta_build sorts; the validator enforces it), so merge */
    size_t i = 0, j = 0;
    while (i < na || j < nb) {
        lbk_string ka = {0}, va = {0}, kb = {0}, vb = {0};
        if (i < na) lbk_meta_entry_get(&a->meta, (uint32_t)i, &ka, &va);
        if (j < nb) lbk_meta_entry_get(&b->meta, (uint32_t)j, &kb, &vb);
        int c;
        if (i >= na) c = 1;
        else if (j >= nb) c = -1;
        else {
            size_t m = ka.size < kb.size ? ka.size : kb.size;
            c = memcmp(ka.data, kb.data, m);
            if (!c) c = (ka.size > kb.size) - (ka.size < kb.size);
        }
        tl_diff_param p;
        memset(&p, 0, sizeof p);
        if (c < 0) {
            tl_string_copy(p.key, sizeof p.key, ka);
            p.a = dup_string(va);
            p.status = TL_DIFF_REMOVED;
            i++;
        } else if (c > 0) {
            tl_string_copy(p.key, sizeof p.key, kb);
            p.b = dup_string(vb);
            p.status = TL_DIFF_ADDED;
            j++;
        } else {
            tl_string_copy(p.key, sizeof p.key, ka);
            if (va.size == vb.size && !memcmp(va.data, vb.data, va.size)) {
                i++, j++;
                continue; /* only differences are listed */
            }
            p.a = dup_string(va);
            p.b = dup_string(vb);
            p.status = TL_DIFF_CHANGED;
            i++, j++;
        }
        r->params[r->param_count++] = p;
        r->params_changed++;
    }
    return 0;
}

/* ---- objects -------------------------------------------------------------------------------- */

static uint32_t object_count(const tl_bake *b) { return b->has_objs ? b->objs.count : 0; }

static int same_string(lbk_string x, lbk_string y) { return x.size == y.size && !memcmp(x.data, y.data, x.size); }

/* Compares the lighting of a matched object pair. */
static void compare_object(const tl_bake *a, const tl_bake *b, const lbk_object *oa, const lbk_object *ob,
                           const tol *t, tl_diff_object *d)
{
    if (oa->representation == LBK_REPRESENTATION_LIGHTMAP && ob->representation == LBK_REPRESENTATION_LIGHTMAP &&
        a->has_lmap && b->has_lmap) {
        pageref pa, pb;
        if (pageref_get(a, oa->index, &pa) || pageref_get(b, ob->index, &pb)) return;
        d->compared = 1;
        const int same_size = oa->rect_w == ob->rect_w && oa->rect_h == ob->rect_h;
        d->resampled = !same_size;
        float *local_a = NULL, *local_b = NULL;
        if (t->noise)
            tl_noise_begin(&d->noise, t->noise, TL_NOISE_TEXELS, rect_noise(&pa, d->rect_a, t->noise->rept[0][0], tl_noise_texel_floor(t->noise, 0), &local_a),
                           rect_noise(&pb, d->rect_b, t->noise->rept[1][0], tl_noise_texel_floor(t->noise, 1), same_size ? &local_b : NULL));
        /* no texel noise of its own (under 16 interior texels): no per-texel test either */
        if (t->noise && (oa->rect_w < 5 || oa->rect_h < 5 || (uint64_t)(oa->rect_w - 4) * (oa->rect_h - 4) < 16))
            d->noise.count_test = 0;
        for (uint32_t y = 0; y < oa->rect_h; y++)
            for (uint32_t x = 0; x < oa->rect_w; x++) {
                float va[TL_TEXEL_NORMALS][3], vb[TL_TEXEL_NORMALS][3];
                /* unwritten on one side while the other is a block page: nothing to compare */
                const int ua = texel_unwritten(&pa, oa->rect_x + x, oa->rect_y + y);
                const int ub = same_size && texel_unwritten(&pb, ob->rect_x + x, ob->rect_y + y);
                if ((ua && pb.pl.blocks_x) || (ub && pa.pl.blocks_x)) continue;
                texel_values(&pa, oa->rect_x + x, oa->rect_y + y, va);
                if (same_size) texel_values(&pb, ob->rect_x + x, ob->rect_y + y, vb);
                else texel_bilinear(&pb, d->rect_b, (x + 0.5) / oa->rect_w, (y + 0.5) / oa->rect_h, vb);
                add_sample(&d->lighting, &va[0][0], &vb[0][0], TL_TEXEL_NORMALS, t, x, y, NULL);
                if (t->noise) {
                    const size_t i = (size_t)y * oa->rect_w + x;
                    tl_noise_add(&d->noise, t->noise, &va[0][0], &vb[0][0], TL_TEXEL_NORMALS,
                                 local_a ? local_a[i] : d->noise.noise_a, local_b ? local_b[i] : d->noise.noise_b);
                }
            }
        if (t->noise) tl_noise_end(&d->noise, t->noise);
        free(local_a);
        free(local_b);
        return;
    }
    if (oa->representation == LBK_REPRESENTATION_LLG && ob->representation == LBK_REPRESENTATION_LLG && a->has_llg &&
        b->has_llg) {
        lbk_llg_grid ga, gb;
        if (lbk_llg_grid_get(&a->llg, oa->index, &ga) != LBK_OK || lbk_llg_grid_get(&b->llg, ob->index, &gb) != LBK_OK)
            return;
        d->compared = 1;
        const int same = ga.dims[0] == gb.dims[0] && ga.dims[1] == gb.dims[1] && ga.dims[2] == gb.dims[2];
        d->resampled = !same;
        if (t->noise) tl_noise_begin(&d->noise, t->noise, TL_NOISE_LLG, t->noise->rept[0][1], t->noise->rept[1][1]);
        const uint64_t n = (uint64_t)ga.dims[0] * ga.dims[1] * ga.dims[2];
        for (uint64_t i = 0; i < n; i++) {
            lbk_sh9_rgb sa, sb;
            tl_probe_unpack(a->llg.probes + (ga.probe_offset + i) * LBK_SH9_PACKED_SIZE, a->llg.scale, &sa);
            if (same) {
                tl_probe_unpack(b->llg.probes + (gb.probe_offset + i) * LBK_SH9_PACKED_SIZE, b->llg.scale, &sb);
            } else {
                float pos[3];
                uint32_t ii = (uint32_t)(i % ga.dims[0]), jj = (uint32_t)(i / ga.dims[0] % ga.dims[1]),
                         kk = (uint32_t)(i / ((uint64_t)ga.dims[0] * ga.dims[1]));
                lbk_llg_probe_position(&ga, ii, jj, kk, pos);
                if (lbk_llg_sample(&b->llg, ob->index, pos, &sb) != LBK_OK) memset(&sb, 0, sizeof sb);
            }
            float va[TL_PROBE_NORMALS][3], vb[TL_PROBE_NORMALS][3];
            tl_probe_eval(&sa, va);
            tl_probe_eval(&sb, vb);
            add_sample(&d->lighting, &va[0][0], &vb[0][0], TL_PROBE_NORMALS, t, (uint32_t)i, 0, NULL);
            if (t->noise)
                tl_noise_add(&d->noise, t->noise, &va[0][0], &vb[0][0], TL_PROBE_NORMALS, d->noise.noise_a,
                             d->noise.noise_b);
        }
        if (t->noise) tl_noise_end(&d->noise, t->noise);
    }
}

static void fill_side(tl_diff_object *d, const lbk_object *o, int side)
{
    uint32_t *rect = side ? d->rect_b : d->rect_a;
    rect[0] = o->rect_x, rect[1] = o->rect_y, rect[2] = o->rect_w, rect[3] = o->rect_h;
    if (side) d->repr_b = o->representation, d->page_b = o->index, d->hash_b = o->geometry_hash;
    else d->repr_a = o->representation, d->page_a = o->index, d->hash_a = o->geometry_hash;
}

static int diff_objects(const tl_bake *a, const tl_bake *b, const tol *t, tl_diff_result *r)
{
    const uint32_t na = object_count(a), nb = object_count(b);
    r->objects = calloc((size_t)na + nb + 1, sizeof *r->objects);
    int32_t *match_a = malloc(((size_t)na + 1) * sizeof *match_a);
    uint8_t *used_b = calloc((size_t)nb + 1, 1);
    if (!r->objects || !match_a || !used_b) {
        free(match_a);
        free(used_b);
        return -1;
    }
    lbk_object *oa = calloc((size_t)na + 1, sizeof *oa), *ob = calloc((size_t)nb + 1, sizeof *ob);
    if (!oa || !ob) {
        free(oa), free(ob), free(match_a), free(used_b);
        return -1;
    }
    for (uint32_t i = 0; i < na; i++) lbk_objects_get(&a->objs, i, &oa[i]), match_a[i] = -1;
    for (uint32_t j = 0; j < nb; j++) lbk_objects_get(&b->objs, j, &ob[j]);
    /* pass 1: same name and geometry; pass 2: same name; pass 3: same geometry (renamed) */
    for (int pass = 0; pass < 3; pass++)
        for (uint32_t i = 0; i < na; i++) {
            if (match_a[i] >= 0) continue;
            for (uint32_t j = 0; j < nb; j++) {
                if (used_b[j]) continue;
                const int name = same_string(oa[i].name, ob[j].name), geo = oa[i].geometry_hash == ob[j].geometry_hash;
                if ((pass == 0 && name && geo) || (pass == 1 && name) || (pass == 2 && geo)) {
                    match_a[i] = (int32_t)j;
                    used_b[j] = 1;
                    break;
                }
            }
        }
    for (uint32_t i = 0; i < na; i++) {
        tl_diff_object *d = &r->objects[r->object_count++];
        tl_string_copy(d->name, sizeof d->name, oa[i].name);
        fill_side(d, &oa[i], 0);
        d->index_a = i;
        d->repr_b = LBK_REPRESENTATION_COUNT_;
        if (match_a[i] < 0) {
            d->status = TL_DIFF_REMOVED;
            r->objects_removed++;
            continue;
        }
        const lbk_object *o2 = &ob[match_a[i]];
        fill_side(d, o2, 1);
        d->index_b = (uint32_t)match_a[i];
        d->renamed = !same_string(oa[i].name, o2->name);
        if (d->renamed) tl_string_copy(d->name_b, sizeof d->name_b, o2->name);
        d->geometry_changed = d->hash_a != d->hash_b;
        d->representation_changed = d->repr_a != d->repr_b;
        d->rect_changed = memcmp(d->rect_a, d->rect_b, sizeof d->rect_a) != 0 || d->page_a != d->page_b;
        compare_object(a, b, &oa[i], o2, t, d);
        const int lighting_differs = t->noise ? (d->compared && !d->noise.within_noise) : d->lighting.over > 0;
        d->status = (d->renamed || d->geometry_changed || d->representation_changed || lighting_differs ||
                     (d->rect_changed && d->resampled))
                        ? TL_DIFF_CHANGED
                        : TL_DIFF_SAME;
        if (d->status == TL_DIFF_CHANGED) r->objects_changed++;
    }
    for (uint32_t j = 0; j < nb; j++) {
        if (used_b[j]) continue;
        tl_diff_object *d = &r->objects[r->object_count++];
        tl_string_copy(d->name, sizeof d->name, ob[j].name);
        fill_side(d, &ob[j], 1);
        d->index_b = j;
        d->repr_a = LBK_REPRESENTATION_COUNT_;
        d->status = TL_DIFF_ADDED;
        r->objects_added++;
    }
    free(oa), free(ob), free(match_a), free(used_b);
    return 0;
}

/* ---- pages ---------------------------------------------------------------------------------- */

static int diff_pages(const tl_bake *a, const tl_bake *b, const tol *t, int keep_maps, tl_diff_result *r)
{
    const uint32_t na = a->has_lmap ? a->lmap.page_count : 0, nb = b->has_lmap ? b->lmap.page_count : 0;
    const uint32_t n = na > nb ? na : nb;
    r->pages = calloc((size_t)n + 1, sizeof *r->pages);
    if (!r->pages) return -1;
    for (uint32_t p = 0; p < n; p++) {
        tl_diff_page *d = &r->pages[r->page_count++];
        d->index = p;
        pageref ra, rb;
        lbk_lmap_planes pa = {0}, pb = {0};
        if (p < na) pageref_get(a, p, &ra), pa = ra.pl, d->wa = pa.width, d->ha = pa.height;
        if (p < nb) pageref_get(b, p, &rb), pb = rb.pl, d->wb = pb.width, d->hb = pb.height;
        if (p >= nb) {
            d->status = TL_DIFF_REMOVED;
            r->pages_changed++;
            continue;
        }
        if (p >= na) {
            d->status = TL_DIFF_ADDED;
            r->pages_changed++;
            continue;
        }
        d->resized = pa.width != pb.width || pa.height != pb.height;
        const uint32_t w = pa.width < pb.width ? pa.width : pb.width, h = pa.height < pb.height ? pa.height : pb.height;
        /* noise mode: which object (of A) each texel belongs to, for its noise and its verdict */
        int32_t *owner = NULL;
        float *local_a = NULL, *local_b = NULL;
        int objects_changed = 0;
        if (t->noise) {
            const uint32_t rect_a[4] = {0, 0, pa.width, pa.height}, rect_b[4] = {0, 0, pb.width, pb.height};
            rect_noise(&ra, rect_a, t->noise->rept[0][0], tl_noise_texel_floor(t->noise, 0), &local_a);
            rect_noise(&rb, rect_b, t->noise->rept[1][0], tl_noise_texel_floor(t->noise, 1), &local_b);
            owner = malloc(sizeof *owner * ((size_t)pa.width * pa.height + 1));
            if (!owner || !local_a || !local_b) {
                free(owner), free(local_a), free(local_b);
                return -1;
            }
            for (size_t i = 0; i < (size_t)pa.width * pa.height; i++) owner[i] = -1;
            for (size_t k = 0; k < r->object_count; k++) {
                const tl_diff_object *o = &r->objects[k];
                if (o->repr_a != LBK_REPRESENTATION_LIGHTMAP || o->page_a != p) continue;
                objects_changed |= o->status == TL_DIFF_CHANGED;
                for (uint32_t y = o->rect_a[1]; y < o->rect_a[1] + o->rect_a[3] && y < pa.height; y++)
                    for (uint32_t x = o->rect_a[0]; x < o->rect_a[0] + o->rect_a[2] && x < pa.width; x++)
                        owner[(size_t)y * pa.width + x] = (int32_t)k;
            }
        }
        if (keep_maps) {
            const size_t cnt = (size_t)pa.width * pa.height;
            d->error_map = malloc(cnt * sizeof(float));
            d->over_map = calloc(cnt, 1);
            if (!d->error_map || !d->over_map) return -1;
            for (size_t i = 0; i < cnt; i++) d->error_map[i] = NAN;
        }
        for (uint32_t y = 0; y < h; y++)
            for (uint32_t x = 0; x < w; x++) {
                float va[TL_TEXEL_NORMALS][3], vb[TL_TEXEL_NORMALS][3], e;
                texel_values(&ra, x, y, va);
                texel_values(&rb, x, y, vb);
                int over = add_sample(&d->lighting, &va[0][0], &vb[0][0], TL_TEXEL_NORMALS, t, x, y, &e);
                if (owner)
                    over = tl_noise_sample_significant(t->noise, TL_NOISE_TEXELS, local_a[(size_t)y * pa.width + x],
                                                       local_b[(size_t)y * pb.width + x], &va[0][0], &vb[0][0],
                                                       TL_TEXEL_NORMALS);
                if (keep_maps) {
                    d->error_map[(size_t)y * pa.width + x] = e;
                    d->over_map[(size_t)y * pa.width + x] = (uint8_t)over;
                }
            }
        free(owner), free(local_a), free(local_b);
        r->texels_over += d->lighting.over;
        /* a page only resized (e.g. widened by convert) with equal texels is the same lighting; in
         * noise mode a page changed when one of its objects did */
        d->status = (t->noise ? objects_changed : d->lighting.over > 0) ? TL_DIFF_CHANGED : TL_DIFF_SAME;
        if (d->status != TL_DIFF_SAME) r->pages_changed++;
    }
    return 0;
}

/* ---- GLG ------------------------------------------------------------------------------------ */

int tl_diff_glg_same_layout(const tl_bake *a, const tl_bake *b)
{
    if (a->glg.probe_count != b->glg.probe_count) return 0;
    for (uint32_t i = 0; i < a->glg.probe_count; i++) {
        float pa[3], pb[3];
        lbk_sh9_rgb s;
        lbk_glg_probe_get(&a->glg, i, pa, &s);
        lbk_glg_probe_get(&b->glg, i, pb, &s);
        if (pa[0] != pb[0] || pa[1] != pb[1] || pa[2] != pb[2]) return 0;
    }
    return 1;
}

static void diff_glg(const tl_bake *a, const tl_bake *b, const tol *t, tl_diff_result *r)
{
    tl_diff_probes *d = &r->glg;
    d->count_a = a->has_glg ? a->glg.probe_count : 0;
    d->count_b = b->has_glg ? b->glg.probe_count : 0;
    if (!a->has_glg && !b->has_glg) {
        d->status = -1;
        return;
    }
    if (!a->has_glg || !b->has_glg) {
        d->status = a->has_glg ? TL_DIFF_REMOVED : TL_DIFF_ADDED;
        return;
    }
    const int same = tl_diff_glg_same_layout(a, b);
    d->resampled = !same;
    if (t->noise) tl_noise_begin(&d->noise, t->noise, TL_NOISE_GLG, t->noise->rept[0][1], t->noise->rept[1][1]);
    uint32_t hint = 0;
    for (uint32_t i = 0; i < a->glg.probe_count; i++) {
        float pos[3], pb[3];
        lbk_sh9_rgb sa, sb;
        lbk_glg_probe_get(&a->glg, i, pos, &sa);
        if (same) lbk_glg_probe_get(&b->glg, i, pb, &sb);
        else if (lbk_glg_sample(&b->glg, pos, &hint, &sb, NULL) != LBK_OK) memset(&sb, 0, sizeof sb);
        float va[TL_PROBE_NORMALS][3], vb[TL_PROBE_NORMALS][3];
        tl_probe_eval(&sa, va);
        tl_probe_eval(&sb, vb);
        add_sample(&d->lighting, &va[0][0], &vb[0][0], TL_PROBE_NORMALS, t, i, 0, NULL);
        if (t->noise)
            tl_noise_add(&d->noise, t->noise, &va[0][0], &vb[0][0], TL_PROBE_NORMALS, d->noise.noise_a,
                         d->noise.noise_b);
    }
    r->probes_over += d->lighting.over;
    if (t->noise) {
        tl_noise_end(&d->noise, t->noise);
        if (!d->noise.within_noise) r->items_beyond_noise++;
    }
    const int differs = t->noise ? !d->noise.within_noise : d->lighting.over > 0;
    d->status = (differs || !same) ? TL_DIFF_CHANGED : TL_DIFF_SAME;
}

/* ---- driver -------------------------------------------------------------------------------- */

static int cmp_dbl(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* The median of n levels (sorts them); 0 when none. */
static double median_level(double *v, size_t n)
{
    if (!n) return 0;
    qsort(v, n, sizeof *v, cmp_dbl);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The median level of a bake's lit receivers (luminance; texels at +Z, probes the mean over the
 * six normals), [0] texels, [1] GLG and LLG probes: with REPT's relative estimate it gives the
 * absolute noise of a typical receiver (tl_noise_model.level_ref); 0 when out of memory. */
static void bake_levels(const tl_bake *b, double out[2])
{
    uint64_t texels = 0;
    for (uint32_t p = 0; b->has_lmap && p < b->lmap.page_count; p++) {
        pageref pg;
        if (!pageref_get(b, p, &pg)) texels += (uint64_t)pg.pl.width * pg.pl.height;
    }
    const uint64_t glg = b->has_glg ? b->glg.probe_count : 0, llg = b->has_llg ? b->llg.probe_count : 0;
    out[0] = out[1] = 0;
    if (texels > SIZE_MAX / sizeof(double) - 1 || glg + llg > SIZE_MAX / sizeof(double) - 1) return;
    double *v = malloc(sizeof *v * ((size_t)(texels > glg + llg ? texels : glg + llg) + 1));
    if (!v) return;
    size_t n = 0;
    for (uint32_t p = 0; b->has_lmap && p < b->lmap.page_count; p++) {
        pageref pg;
        if (pageref_get(b, p, &pg)) continue;
        for (uint32_t y = 0; y < pg.pl.height; y++)
            for (uint32_t x = 0; x < pg.pl.width; x++) {
                float t[TL_TEXEL_NORMALS][3];
                texel_values(&pg, x, y, t);
                const double l = tl_noise_level(t[0], 0, 1);
                if (l > 0) v[n++] = l;
            }
    }
    out[0] = median_level(v, n);
    n = 0;
    for (uint64_t i = 0; i < glg + llg; i++) {
        float pos[3], e[TL_PROBE_NORMALS][3];
        lbk_sh9_rgb sh;
        if (i < glg) lbk_glg_probe_get(&b->glg, (uint32_t)i, pos, &sh);
        else tl_probe_unpack(b->llg.probes + (i - glg) * LBK_SH9_PACKED_SIZE, b->llg.scale, &sh);
        tl_probe_eval(&sh, e);
        const double l = tl_noise_level(e[0], 1, TL_PROBE_NORMALS);
        if (l > 0) v[n++] = l;
    }
    out[1] = median_level(v, n);
    free(v);
}

static void choose_mode(const tl_bake *a, const tl_bake *b, const tl_diff_options *o, tl_diff_result *r,
                        tl_noise_model *model)
{
    const int have_rept = a->has_rept && b->has_rept;
    r->mode = TL_DIFF_MODE_TOLERANCE;
    if (o->mode == TL_DIFF_MODE_TOLERANCE) {
        r->mode_reason = "asked for";
    } else if (!have_rept) {
        r->mode_reason = o->mode == TL_DIFF_MODE_NOISE ? "noise mode asked for, but a bake has no REPT (no noise estimate)"
                                                       : "a bake has no REPT (no noise estimate)";
    } else {
        r->mode = TL_DIFF_MODE_NOISE;
        r->mode_reason = o->mode == TL_DIFF_MODE_NOISE ? "asked for" : "both bakes carry REPT";
    }
    /* the transport's estimate of the last sampling pass, on which the noise model (and its
     * per-texel floor for denoised bakes) was calibrated; a denoised bake's revised estimate
     * (REPT's last record) is of its whole error, bias included, not of how two seeds differ */
    const double ra[2] = {a->has_rept ? a->rept_sampled.texel_rel_rmse : 0, a->has_rept ? a->rept_sampled.probe_rel_rmse : 0};
    const double rb[2] = {b->has_rept ? b->rept_sampled.texel_rel_rmse : 0, b->has_rept ? b->rept_sampled.probe_rel_rmse : 0};
    tl_noise_model_init(model, o->false_alarm > 0 ? o->false_alarm : TL_NOISE_DEFAULT_FALSE_ALARM, ra, rb);
    model->denoised[0] = bake_denoised(a);
    model->denoised[1] = bake_denoised(b);
    if (bake_high_preset(a) || bake_high_preset(b)) model->texel_spread = TL_NOISE_HIGH_TEXEL_SPREAD;
    if (r->mode == TL_DIFF_MODE_NOISE) bake_levels(a, model->level_ref[0]), bake_levels(b, model->level_ref[1]);
}

int tl_diff_run(const tl_bake *a, const tl_bake *b, const tl_diff_options *o, tl_diff_result *r, char err[TL_ERR_LEN])
{
    memset(r, 0, sizeof *r);
    r->abs_tol = o->abs_tol;
    r->rel_tol = o->rel_tol;
    choose_mode(a, b, o, r, &r->noise);
    tol t = {o->abs_tol, o->rel_tol, r->mode == TL_DIFF_MODE_NOISE ? &r->noise : NULL};
    if (diff_sections(a, b, r) || diff_params(a, b, r) || diff_objects(a, b, &t, r) ||
        diff_pages(a, b, &t, o->keep_error_maps, r) || tl_diff_sets_run(a, b, o->abs_tol, o->rel_tol, t.noise, r) || tl_diff_doors_run(a, b, r) ||
        tl_diff_provenance(a, b, r)) {
        snprintf(err, TL_ERR_LEN, "out of memory");
        tl_diff_free(r);
        return -1;
    }
    diff_glg(a, b, &t, r);
    tl_diff_octp_run(a, b, o->abs_tol, o->rel_tol, t.noise, r);
    for (size_t i = 0; i < r->object_count; i++) {
        const tl_diff_object *d = &r->objects[i];
        if (d->repr_a == LBK_REPRESENTATION_LLG && d->compared) r->probes_over += d->lighting.over;
        if (d->compared && d->noise.evaluated && !d->noise.within_noise) r->items_beyond_noise++;
    }
    /* the exit decision: lighting and structure; META and REPT are provenance only, TERR (the
     * per-texel error map, a bake option) a diagnostic: present on one side only, it is reported */
    int structural_sections = 0;
    for (size_t i = 0; i < r->section_count; i++) {
        const tl_diff_section *s = &r->sections[i];
        if (s->type == LBK_SECTION_META || s->type == LBK_SECTION_REPT || s->type == LBK_SECTION_TERR) continue;
        if (s->status == TL_DIFF_ADDED || s->status == TL_DIFF_REMOVED) structural_sections = 1;
    }
    /* noise mode: samples over the (zero) tolerance are expected; the items' verdicts decide */
    const int samples_over = r->mode == TL_DIFF_MODE_NOISE ? 0 : r->texels_over || r->probes_over;
    r->differ = structural_sections || r->objects_added || r->objects_removed || r->objects_changed ||
                r->pages_changed || r->sets_changed || r->doors_changed || samples_over ||
                r->glg.status == TL_DIFF_CHANGED || r->glg.status == TL_DIFF_ADDED || r->glg.status == TL_DIFF_REMOVED ||
                r->octp.status == TL_DIFF_CHANGED || r->octp.status == TL_DIFF_ADDED || r->octp.status == TL_DIFF_REMOVED;
    return 0;
}

void tl_diff_free(tl_diff_result *r)
{
    for (size_t i = 0; i < r->param_count; i++) free(r->params[i].a), free(r->params[i].b);
    for (size_t i = 0; i < r->change_count; i++) free(r->changes[i].a), free(r->changes[i].b), free(r->changes[i].what);
    free(r->changes);
    for (size_t i = 0; i < r->page_count; i++) free(r->pages[i].error_map), free(r->pages[i].over_map);
    free(r->sections);
    free(r->params);
    free(r->objects);
    free(r->pages);
    free(r->sets);
    free(r->doors);
    memset(r, 0, sizeof *r);
}
