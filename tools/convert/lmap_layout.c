/* LMAP rewriting for convert: widening pages for a row pitch, EXR page import, DLS renumbering. */
#include "tools/convert/lmap_layout.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "tools/convert/convert.h"
#include "tools/common/error_util.h"
#include "tools/common/file_util.h"
#include "tools/convert/lmap_encode.h"
#include "lbk/objects.h"
#include "lbk/dls.h"
#include "lbk/lightmap.h"
#include "lbk/pixel.h"

void tl_page_exr_path(char *out, size_t size, const char *dir, uint32_t page, const char *suffix)
{
    snprintf(out, size, "%s/page_%03u%s", dir, page, suffix);
}

void tl_texel_remap_free(tl_texel_remap *r)
{
    free(r->old_width);
    free(r->new_width);
    free(r->height);
    free(r->old_first);
    free(r->new_first);
    memset(r, 0, sizeof *r);
}

int tl_texel_remap_apply(const tl_texel_remap *r, uint64_t old_index, uint64_t *new_index)
{
    if (old_index >= r->old_total) return -1;
    if (r->identity) {
        *new_index = old_index;
        return 0;
    }
    uint32_t lo = 0, hi = r->page_count;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (r->old_first[mid] <= old_index) lo = mid;
        else hi = mid;
    }
    uint64_t local = old_index - r->old_first[lo];
    uint64_t y = local / r->old_width[lo], x = local % r->old_width[lo];
    *new_index = r->new_first[lo] + y * r->new_width[lo] + x;
    return 0;
}

/* Replaces plane 0 (and plane 1 when the .ahd.exr exists) of page p from DIR. Returns 1 when
 * the page was imported, 0 when DIR has no file for it, or a negative tl_convert_status. */
static int import_page(const char *dir, uint32_t p, uint32_t w, uint32_t h, float scale, lbk_ahd_texel *tex,
                       char err[TL_ERR_LEN])
{
    char path[4096];
    tl_page_exr_path(path, sizeof path, dir, p, ".exr");
    if (access(path, F_OK) != 0) return 0;
    static const char *const rgb_names[3] = {"R", "G", "B"};
    int ew, eh;
    float *px = NULL;
    char e2[TL_ERR_LEN];
    if (tl_exr_read(path, 3, rgb_names, &ew, &eh, &px, e2)) return -tl_fail(err, TL_CONVERT_BAD_EXR, "%s", e2);
    if ((uint32_t)ew != w || (uint32_t)eh != h) {
        free(px);
        return -tl_fail(err, TL_CONVERT_BAD_EXR, "%s is %dx%d but page %u is %ux%u", path, ew, eh, p, w, h);
    }
    for (size_t i = 0; i < (size_t)w * h; i++) {
        float v[3];
        for (int c = 0; c < 3; c++) {
            v[c] = px[3 * i + (size_t)c];
            if (!isfinite(v[c])) {
                free(px);
                return -tl_fail(err, TL_CONVERT_BAD_EXR, "%s: pixel (%zu, %zu) %s is not finite", path, i % w, i / w,
                             rgb_names[c]);
            }
            if (v[c] < 0) v[c] = 0; /* irradiance cannot be negative; painting tools overshoot */
            v[c] /= scale;           /* the EXR is physical, the section stores value / scale (exact) */
        }
        tex[i].irradiance_z = lbk_r11g11b10f_pack(v);
    }
    free(px);
    tl_page_exr_path(path, sizeof path, dir, p, ".ahd.exr");
    if (access(path, F_OK) != 0) return 1;
    static const char *const p1_names[4] = {"plane1.R", "plane1.G", "plane1.B", "plane1.A"};
    if (tl_exr_read(path, 4, p1_names, &ew, &eh, &px, e2)) return -tl_fail(err, TL_CONVERT_BAD_EXR, "%s", e2);
    if ((uint32_t)ew != w || (uint32_t)eh != h) {
        free(px);
        return -tl_fail(err, TL_CONVERT_BAD_EXR, "%s is %dx%d but page %u is %ux%u", path, ew, eh, p, w, h);
    }
    for (size_t i = 0; i < (size_t)w * h; i++)
        for (int c = 0; c < 4; c++) {
            float v = px[4 * i + (size_t)c];
            if (!isfinite(v)) {
                free(px);
                return -tl_fail(err, TL_CONVERT_BAD_EXR, "%s: pixel (%zu, %zu) %s is not finite", path, i % w, i / w,
                             p1_names[c]);
            }
            tex[i].rgba[c] = lbk_float_to_unorm8(v);
        }
    free(px);
    return 1;
}

/* The smallest width ≥ w that suits the planes: a multiple of 4 for block encodings, and every
 * plane texture's row (4 bytes per texel-column, 2 for the BC4 ratio of BC5_BC4) a multiple of the
 * row pitch alignment. */
static uint32_t padded_width(uint32_t w, const uint32_t f[2], uint32_t pitch)
{
    const int block = f[0] != LBK_LMAP_R11G11B10F || f[1] != LBK_LMAP_RGBA8;
    const uint32_t step = block ? 4 : 1;
    uint32_t nw = (w + step - 1) / step * step;
    for (; nw <= LBK_LMAP_MAX_DIM; nw += step) {
        int ok = !pitch || (4 * nw) % pitch == 0;
        if (ok && pitch && f[1] == LBK_LMAP_BC5_BC4) ok = (2 * nw) % pitch == 0;
        if (ok) return nw;
    }
    return 0;
}

static int check_page_alignment(const lbk_lmap_view *v, uint32_t alignment, char err[TL_ERR_LEN])
{
    for (uint32_t p = 0; p < v->page_count && alignment; p++) {
        lbk_lmap_planes pg;
        lbk_lmap_planes_get(v, p, &pg);
        if (pg.offset[0] % alignment || pg.offset[1] % alignment)
            return tl_fail(err, TL_CONVERT_UNSUPPORTED,
                           "page %u planes start at LMAP bytes %llu and %llu, not multiples of page_alignment %u; "
                           "the format places planes packed at 16-byte alignment",
                           p, (unsigned long long)pg.offset[0], (unsigned long long)pg.offset[1], alignment);
    }
    return TL_CONVERT_OK;
}

/* Per texel of page p: 1 inside some object's lightmap rectangle, 0 elsewhere (atlas gaps, the
 * padding): what the block encoders may ignore; and which object it belongs to (-1 none). */
static float *used_texels(const lbk_objects_view *objs, uint32_t p, uint32_t w, uint32_t h, int32_t **owners)
{
    float *wt = calloc((size_t)w * h + 1, sizeof *wt);
    *owners = malloc(((size_t)w * h + 1) * sizeof **owners);
    if (!wt || !*owners) {
        free(wt), free(*owners), *owners = NULL;
        return NULL;
    }
    for (size_t i = 0; i < (size_t)w * h; i++) (*owners)[i] = -1, wt[i] = objs ? 0.0f : 1.0f;
    for (uint32_t i = 0; objs && i < objs->count; i++) {
        lbk_object o;
        lbk_objects_get(objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LIGHTMAP || o.index != p) continue;
        for (uint32_t y = o.rect_y; y < o.rect_y + o.rect_h && y < h; y++)
            for (uint32_t x = o.rect_x; x < o.rect_x + o.rect_w && x < w; x++)
                wt[(size_t)y * w + x] = 1, (*owners)[(size_t)y * w + x] = (int32_t)i;
    }
    return wt;
}

static int remap_alloc(tl_texel_remap *remap, uint32_t n, char err[TL_ERR_LEN])
{
    remap->page_count = n;
    remap->old_width = calloc(n + 1, sizeof(uint32_t));
    remap->new_width = calloc(n + 1, sizeof(uint32_t));
    remap->height = calloc(n + 1, sizeof(uint32_t));
    remap->old_first = calloc(n + 1, sizeof(uint64_t));
    remap->new_first = calloc(n + 1, sizeof(uint64_t));
    if (!remap->old_width || !remap->new_width || !remap->height || !remap->old_first || !remap->new_first)
        return tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
    return TL_CONVERT_OK;
}

/* Encodes the padded texel pages in the asked formats and builds the section. */
static int build_encoded(const lbk_lmap_view *v, lbk_ahd_texel **tex, const tl_texel_remap *remap, const uint32_t *new_h,
                         const tl_lmap_layout_options *o, void **built, size_t *built_size, char err[TL_ERR_LEN])
{
    const uint32_t n = v->page_count;
    lbk_lmap_encoded_page *ep = calloc(n + 1, sizeof *ep);
    void **planes = calloc(2 * (size_t)n + 1, sizeof *planes);
    int st = ep && planes ? TL_CONVERT_OK : tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
    lbk_objects_view objs;
    const int have_objs = o->objs && lbk_objects_open(o->objs, o->objs_size, &objs) == LBK_OK;
    const double t0 = tl_seconds();
    for (uint32_t p = 0; p < n && st == TL_CONVERT_OK; p++) {
        const uint32_t w = remap->new_width[p], h = new_h[p];
        lbk_ahd_texel_f *tf = malloc(sizeof *tf * (size_t)w * h + 1);
        int32_t *owners = NULL;
        float *wt = used_texels(have_objs ? &objs : NULL, p, w, h, &owners);
        if (!tf || !wt) st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
        for (size_t i = 0; st == TL_CONVERT_OK && i < (size_t)w * h; i++) {
            lbk_ahd_texel_f_from_texel(&tex[p][i], &tf[i]);
            /* a texel the baker never wrote (all 8 bytes zero; an unlit texel it did write has
             * plane 1 FF 80 80 FF, spec §5.6) is not drawn: it costs nothing */
            const lbk_ahd_texel *t = &tex[p][i];
            if (!t->irradiance_z && !t->rgba[0] && !t->rgba[1] && !t->rgba[2] && !t->rgba[3]) wt[i] = 0, owners[i] = -1;
        }
        char e2[TL_ERR_LEN];
        if (st == TL_CONVERT_OK &&
            tl_lmap_encode_page(tf, wt, have_objs ? owners : NULL, w, h, o->format[0], o->format[1], &planes[2 * p],
                                &planes[2 * p + 1], e2, sizeof e2))
            st = tl_fail(err, TL_CONVERT_INTERNAL, "encoding page %u: %s", p, e2);
        ep[p] = (lbk_lmap_encoded_page){w, h, {o->format[0], o->format[1]}, {planes[2 * p], planes[2 * p + 1]}};
        free(tf);
        free(wt);
        free(owners);
    }
    if (o->encode_seconds) *o->encode_seconds += tl_seconds() - t0;
    if (st == TL_CONVERT_OK) {
        const lbk_lmap_build_desc bd = {.size = sizeof bd, .page_count = n, .scale = v->scale, .encoded = ep};
        lbk_result r = lbk_lmap_build(&bd, NULL, built, built_size);
        if (r != LBK_OK) st = tl_fail(err, TL_CONVERT_INTERNAL, "rebuilding LMAP: %s", lbk_result_message(r));
    }
    for (size_t i = 0; planes && i < 2 * (size_t)n; i++) free(planes[i]);
    free(planes);
    free(ep);
    return st;
}

int tl_lmap_rewrite(const void *lmap, size_t size, const tl_lmap_layout_options *o, void **out, size_t *out_size,
                    uint32_t *pages_imported, tl_texel_remap *remap, char err[TL_ERR_LEN])
{
    *out = NULL;
    *out_size = 0;
    *pages_imported = 0;
    memset(remap, 0, sizeof *remap);
    lbk_lmap_view v;
    lbk_result r = lbk_lmap_open(lmap, size, &v);
    if (r != LBK_OK) return tl_fail(err, TL_CONVERT_BAD_INPUT, "LMAP: %s", lbk_result_message(r));
    const uint32_t n = v.page_count;
    int st = remap_alloc(remap, n, err);
    if (st != TL_CONVERT_OK) return st;
    const int block = o->format[0] != LBK_LMAP_R11G11B10F || o->format[1] != LBK_LMAP_RGBA8;
    uint32_t *new_h = calloc(n + 1, sizeof *new_h);
    if (!new_h) return tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
    int resize = 0, input_block = 0, same_formats = 1;
    uint64_t first = 0;
    for (uint32_t p = 0; p < n; p++) {
        lbk_lmap_planes pg;
        lbk_lmap_planes_get(&v, p, &pg);
        input_block |= pg.blocks_x != 0;
        same_formats &= pg.format[0] == o->format[0] && pg.format[1] == o->format[1];
        remap->old_width[p] = pg.width;
        remap->height[p] = pg.height;
        remap->old_first[p] = pg.first_texel;
        remap->new_width[p] = padded_width(pg.width, o->format, o->row_pitch_alignment);
        new_h[p] = block ? (pg.height + 3) / 4 * 4 : pg.height;
        if (!remap->new_width[p] || new_h[p] > LBK_LMAP_MAX_DIM) {
            free(new_h);
            return tl_fail(err, TL_CONVERT_UNSUPPORTED, "page %u (%ux%u) cannot be padded for the profile's layout", p,
                           pg.width, pg.height);
        }
        if (o->max_page && (remap->new_width[p] > o->max_page || new_h[p] > o->max_page)) {
            /* a page cannot be split here (its objects' rectangles are fixed): the bake must be redone */
            uint32_t w = remap->new_width[p], h = new_h[p];
            free(new_h);
            return tl_fail(err, TL_CONVERT_UNSUPPORTED,
                           "page %u is %ux%u texels%s, more than the profile's max_page %u: bake with "
                           "`lbk bake --max-page %u`",
                           p, w, h, w != pg.width || h != pg.height ? " after the profile's padding" : "", o->max_page,
                           o->max_page);
        }
        remap->new_first[p] = first;
        first += (uint64_t)remap->new_width[p] * new_h[p];
        resize |= remap->new_width[p] != pg.width || new_h[p] != pg.height;
    }
    remap->old_total = v.texel_count;
    remap->new_total = first;
    remap->identity = !resize;
    if (input_block) { /* block planes cannot be re-encoded without loss: ship them as they are or refuse */
        free(new_h);
        if (!same_formats || resize || o->from_exr_dir)
            return tl_fail(err, TL_CONVERT_UNSUPPORTED,
                           "the input's lightmap pages are already block-encoded; convert the original bake instead");
        return check_page_alignment(&v, o->page_alignment, err);
    }
    if (!resize && !o->from_exr_dir && !block) {
        free(new_h);
        return check_page_alignment(&v, o->page_alignment, err); /* nothing to rewrite */
    }
    /* decode every page into texel arrays of the new size (new texels: zero), import, rebuild */
    lbk_lmap_page_desc *descs = calloc(n + 1, sizeof *descs);
    lbk_ahd_texel **tex = calloc(n + 1, sizeof *tex);
    if (!descs || !tex) st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
    for (uint32_t p = 0; p < n && st == TL_CONVERT_OK; p++) {
        lbk_lmap_page pg;
        lbk_lmap_page_get(&v, p, &pg);
        const uint32_t w = pg.width, h = pg.height, nw = remap->new_width[p];
        lbk_ahd_texel *src = calloc((size_t)w * h, sizeof *src);
        tex[p] = calloc((size_t)nw * new_h[p], sizeof(lbk_ahd_texel));
        if (!src || !tex[p]) {
            free(src);
            st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
            break;
        }
        for (uint32_t y = 0; y < h; y++)
            for (uint32_t x = 0; x < w; x++) lbk_lmap_page_texel_get(&pg, x, y, &src[(size_t)y * w + x]);
        if (o->from_exr_dir) {
            int got = import_page(o->from_exr_dir, p, w, h, v.scale, src, err);
            if (got < 0) st = -got;
            else *pages_imported += (uint32_t)got;
        }
        for (uint32_t y = 0; y < h; y++) memcpy(&tex[p][(size_t)y * nw], &src[(size_t)y * w], (size_t)w * sizeof *src);
        free(src);
        descs[p] = (lbk_lmap_page_desc){nw, new_h[p], tex[p]};
    }
    void *built = NULL;
    size_t built_size = 0;
    if (st == TL_CONVERT_OK && block) {
        st = build_encoded(&v, tex, remap, new_h, o, &built, &built_size, err);
    } else if (st == TL_CONVERT_OK) {
        const lbk_lmap_build_desc bd = {.size = sizeof bd, .pages = descs, .page_count = n, .scale = v.scale};
        r = lbk_lmap_build(&bd, NULL, &built, &built_size);
        if (r != LBK_OK) st = tl_fail(err, TL_CONVERT_INTERNAL, "rebuilding LMAP: %s", lbk_result_message(r));
    }
    if (st == TL_CONVERT_OK) {
        lbk_lmap_view nv;
        lbk_lmap_open(built, built_size, &nv);
        st = check_page_alignment(&nv, o->page_alignment, err);
    }
    /* hand out malloc'ed memory (lbk_free(NULL) is free, but keep ownership rules simple) */
    if (st == TL_CONVERT_OK && !(*out = malloc(built_size ? built_size : 1)))
        st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
    if (st == TL_CONVERT_OK) {
        memcpy(*out, built, built_size);
        *out_size = built_size;
    }
    lbk_free(NULL, built);
    for (uint32_t p = 0; tex && p < n; p++) free(tex[p]);
    free(tex);
    free(descs);
    free(new_h);
    return st;
}

/* ---- DLS renumbering --------------------------------------------------------------------------- */

typedef struct entry_list {
    uint64_t count, cap;
    uint32_t *targets;
    uint8_t *payloads;
} entry_list;

typedef struct collect_ctx {
    entry_list *lists; /* set_count × space count */
    uint32_t space;
    uint32_t payload_size;
    const tl_texel_remap *remap;
    int failed;
} collect_ctx;

static int collect(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    collect_ctx *c = user;
    uint64_t t = target;
    if (c->space == LBK_DLS_SPACE_TEXEL && tl_texel_remap_apply(c->remap, target, &t) != 0) {
        c->failed = 1;
        return 1;
    }
    if (t > UINT32_MAX) {
        c->failed = 1;
        return 1;
    }
    for (uint32_t i = 0; i < count; i++) {
        entry_list *l = &c->lists[(size_t)sets[i] * LBK_DLS_SPACE_COUNT_ + c->space];
        if (l->count == l->cap) {
            uint64_t nc = l->cap ? l->cap * 2 : 64;
            uint32_t *nt = realloc(l->targets, (size_t)nc * sizeof *nt);
            if (nt) l->targets = nt;
            uint8_t *np = realloc(l->payloads, (size_t)nc * c->payload_size);
            if (np) l->payloads = np;
            if (!nt || !np) {
                c->failed = 2;
                return 1;
            }
            l->cap = nc;
        }
        l->targets[l->count] = (uint32_t)t;
        memcpy(l->payloads + (size_t)l->count * c->payload_size, payloads + (size_t)i * c->payload_size, c->payload_size);
        l->count++;
    }
    return 0;
}

int tl_dls_remap_texels(const void *dls, size_t size, const tl_texel_remap *remap, void **out, size_t *out_size,
                        char err[TL_ERR_LEN])
{
    *out = NULL;
    *out_size = 0;
    lbk_dls_view *view = NULL;
    lbk_result r = lbk_dls_open(dls, size, NULL, &view);
    if (r != LBK_OK) return tl_fail(err, TL_CONVERT_BAD_INPUT, "DLS: %s", lbk_result_message(r));
    const uint32_t ns = lbk_dls_set_count(view);
    int st = TL_CONVERT_OK;
    entry_list *lists = calloc((size_t)ns * LBK_DLS_SPACE_COUNT_ + 1, sizeof *lists);
    lbk_dls_set_desc *sets = calloc((size_t)ns + 1, sizeof *sets);
    char **names = calloc((size_t)ns + 1, sizeof *names);
    char ***lights = calloc((size_t)ns + 1, sizeof *lights);
    uint32_t **members = calloc((size_t)ns + 1, sizeof *members);
    if (!lists || !sets || !names || !lights || !members) st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
    for (uint32_t s = 0; s < ns && st == TL_CONVERT_OK; s++) {
        lbk_dls_set_info si;
        lbk_dls_set_get(view, s, &si);
        names[s] = calloc(si.name_length + 1, 1);
        lights[s] = calloc((size_t)si.light_count + 1, sizeof(char *));
        members[s] = calloc((size_t)si.member_count + 1, sizeof(uint32_t));
        if (!names[s] || !lights[s] || !members[s]) {
            st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
            break;
        }
        memcpy(names[s], si.name, si.name_length);
        for (uint32_t i = 0; i < si.light_count; i++) {
            const char *ln;
            uint32_t ll;
            lbk_dls_set_light_get(view, s, i, &ln, &ll);
            lights[s][i] = calloc(ll + 1, 1);
            if (!lights[s][i]) {
                st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
                break;
            }
            memcpy(lights[s][i], ln, ll);
        }
        for (uint32_t i = 0; i < si.member_count; i++) lbk_dls_set_member_get(view, s, i, &members[s][i]);
        sets[s].name = names[s];
        sets[s].kind = si.kind;
        sets[s].light_count = si.light_count;
        sets[s].light_names = (const char *const *)lights[s];
        sets[s].member_count = si.member_count;
        sets[s].members = members[s];
    }
    for (uint32_t c = 0; c < lbk_dls_cluster_count(view) && st == TL_CONVERT_OK; c++) {
        lbk_dls_cluster_info ci;
        lbk_dls_cluster_get(view, c, &ci);
        collect_ctx cc = {lists, ci.space, ci.space == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD,
                          remap, 0};
        r = lbk_dls_cluster_decode(view, c, collect, &cc);
        if (cc.failed == 1) st = tl_fail(err, TL_CONVERT_BAD_INPUT, "DLS cluster %u has a texel target outside LMAP", c);
        else if (cc.failed) st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
        else if (r != LBK_OK) st = tl_fail(err, TL_CONVERT_BAD_INPUT, "DLS cluster %u: %s", c, lbk_result_message(r));
    }
    if (st == TL_CONVERT_OK) {
        lbk_dls_build_desc bd = LBK_DLS_BUILD_DESC_INIT;
        bd.set_count = ns;
        bd.sets = sets;
        for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) bd.target_count[sp] = lbk_dls_target_count(view, sp);
        bd.target_count[LBK_DLS_SPACE_TEXEL] = remap->new_total;
        for (uint32_t s = 0; s < ns; s++)
            for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) {
                entry_list *l = &lists[(size_t)s * LBK_DLS_SPACE_COUNT_ + sp];
                sets[s].entries[sp] = (lbk_dls_sparse){l->count, l->targets, l->payloads};
            }
        void *built = NULL;
        size_t built_size = 0;
        r = lbk_dls_build(&bd, NULL, &built, &built_size, NULL);
        if (r != LBK_OK) st = tl_fail(err, TL_CONVERT_INTERNAL, "rebuilding DLS: %s", lbk_result_message(r));
        else if (!(*out = malloc(built_size ? built_size : 1))) st = tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
        else {
            memcpy(*out, built, built_size);
            *out_size = built_size;
        }
        lbk_free(NULL, built);
    }
    for (uint32_t s = 0; s < ns; s++) {
        if (lights && lights[s]) {
            for (uint32_t i = 0; lights[s][i]; i++) free(lights[s][i]);
            free(lights[s]);
        }
        if (names) free(names[s]);
        if (members) free(members[s]);
        for (uint32_t sp = 0; lists && sp < LBK_DLS_SPACE_COUNT_; sp++) {
            free(lists[(size_t)s * LBK_DLS_SPACE_COUNT_ + sp].targets);
            free(lists[(size_t)s * LBK_DLS_SPACE_COUNT_ + sp].payloads);
        }
    }
    free(lists);
    free(sets);
    free(names);
    free(lights);
    free(members);
    lbk_dls_close(view);
    return st;
}
