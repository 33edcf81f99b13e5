/* Lightmap atlas packing (see atlas.h for the layout rules). */
#include "bake/layout/atlas.h"

#include "bake/layout/pack.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_DENSITY 8.0f
#define DEFAULT_PAGE 1024
#define DEFAULT_MAX_PAGE 4096
#define DEFAULT_PADDING 2
#define DEFAULT_BUDGET (16ull * 1024ull * 1024ull)

static int round4(int v) { return (v + 3) & ~3; }

/* ---------------------------------------------------------------------------------------- */
/* Per object: charts → object rectangle                                                    */

typedef struct obj_pack {
    bk_uv_object uv;
    int w, h;                /* object rectangle, before its own turn */
    int *chart_x, *chart_y;  /* block position of each chart inside the rectangle */
    uint8_t *chart_turned;   /* chart placed a quarter turn (generated charts only) */
    int turned;              /* the whole rectangle placed a quarter turn in its page */
    float requested;         /* density asked for */
    float fit_scale;         /* extra factor so the object fits one max page */
    int tri_cap;             /* longest one-triangle chart (bk_uv_options.max_triangle_texels) */
} obj_pack;

static void obj_pack_free(obj_pack *p)
{
    bk_uv_object_free(&p->uv);
    free(p->chart_x);
    free(p->chart_y);
    free(p->chart_turned);
    p->chart_x = p->chart_y = NULL;
    p->chart_turned = NULL;
}

static int content_size(float extent)
{
    double c = ceil((double)extent);
    return c < 1.0 ? 1 : (int)c;
}

/* Authored layouts keep their orientation: the runtime maps TEXCOORD_1 into the rectangle. */
static int may_turn(const bk_uv_object *uv) { return uv->source == BK_UV_GENERATED; }

/* Generates charts at `density` and packs them; returns LBK_OK with *fits = 0 when the
 * result exceeds max_page (the caller shrinks its large triangles, then lowers the density). */
static lbk_result pack_object(const bk_scene *scene, uint32_t object, double density, const bk_uv_options *uvo,
                              int margin, int align, int max_page, int score_align, obj_pack *p, int *fits)
{
    *fits = 1;
    obj_pack_free(p);
    bk_uv_options o = *uvo;
    o.max_triangle_texels = p->tri_cap;
    lbk_result r = bk_uvgen_object(scene, object, (float)density, &o, &p->uv);
    if (r != LBK_OK) return r;
    size_t n = p->uv.chart_count;
    p->w = p->h = 0;
    if (n == 0) return LBK_OK;
    if (n > (size_t)INT32_MAX / 2) return LBK_ERR_LIMIT;
    bk_pack_rect *rc = malloc(n * sizeof *rc);
    p->chart_x = malloc(n * sizeof *p->chart_x);
    p->chart_y = malloc(n * sizeof *p->chart_y);
    p->chart_turned = malloc(n * sizeof *p->chart_turned);
    if (!rc || !p->chart_x || !p->chart_y || !p->chart_turned) {
        free(rc);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < n; i++) {
        double bw = (double)content_size(p->uv.charts[i].width) + 2.0 * margin;
        double bh = (double)content_size(p->uv.charts[i].height) + 2.0 * margin;
        if (bw > max_page || bh > max_page) {
            free(rc);
            *fits = 0;
            return LBK_OK;
        }
        memset(&rc[i], 0, sizeof rc[i]);
        rc[i].w = ((int)bw + align - 1) / align * align; /* block_align: whole 4×4 blocks per chart */
        rc[i].h = ((int)bh + align - 1) / align * align;
        if (rc[i].w > max_page || rc[i].h > max_page) {
            free(rc);
            *fits = 0;
            return LBK_OK;
        }
        rc[i].id = (uint32_t)i;
        rc[i].turnable = (uint8_t)may_turn(&p->uv);
    }
    int ow, oh;
    int ok = bk_pack_tight(rc, (int)n, max_page, max_page, 1, score_align, &ow, &oh);
    if (ok < 0) {
        free(rc);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    if (ok == 0) {
        free(rc);
        *fits = 0;
        return LBK_OK;
    }
    for (size_t i = 0; i < n; i++) {
        p->chart_x[rc[i].id] = rc[i].x;
        p->chart_y[rc[i].id] = rc[i].y;
        p->chart_turned[rc[i].id] = rc[i].turned;
    }
    free(rc);
    p->w = ow;
    p->h = oh;
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */

float bk_atlas_requested_density(const bk_scene *scene, uint32_t object, const bk_atlas_options *opt)
{
    if (opt && opt->density_override > 0.0f && isfinite(opt->density_override)) return opt->density_override;
    if (scene && object < scene->object_count) {
        float d = scene->objects[object].texel_density;
        if (d > 0.0f && isfinite(d)) return d;
    }
    if (opt && opt->default_density > 0.0f && isfinite(opt->default_density)) return opt->default_density;
    return DEFAULT_DENSITY;
}

void bk_atlas_free(bk_atlas *a)
{
    if (!a) return;
    free(a->pages);
    free(a->objects);
    free(a->object_slot);
    free(a->charts);
    free(a->tris);
    free(a->tri_chart);
    free(a->tri_uv);
    free(a->scene_tri_entry);
    free(a->vertex_source);
    free(a->vertex_slot);
    free(a->vertex_uv);
    free(a->scene_tri_vertices);
    memset(a, 0, sizeof *a);
}

/* ---------------------------------------------------------------------------------------- */
/* Lightmap vertices                                                                        */

typedef struct vkey {
    uint32_t vertex, chart;  /* chart UINT32_MAX: corner of a zero-area triangle */
    float u, v;              /* normalised page uv */
    uint32_t slot;
    uint32_t corner;         /* 3 × scene triangle + k */
} vkey;

static int cmp_vkey(const void *pa, const void *pb)
{
    const vkey *a = pa, *b = pb;
    if (a->vertex != b->vertex) return a->vertex < b->vertex ? -1 : 1;
    if (a->chart != b->chart) return a->chart < b->chart ? -1 : 1;
    if (a->u != b->u) return a->u < b->u ? -1 : 1;
    if (a->v != b->v) return a->v < b->v ? -1 : 1;
    return (a->corner > b->corner) - (a->corner < b->corner);
}

static lbk_result build_vertices(const bk_scene *scene, bk_atlas *a)
{
    size_t corners = 0;
    for (size_t s = 0; s < a->object_count; s++) corners += 3 * (size_t)scene->objects[a->objects[s].object].tri_count;
    a->scene_tri_vertices = malloc((scene->tri_count ? 3 * scene->tri_count : 1) * sizeof *a->scene_tri_vertices);
    vkey *k = malloc((corners ? corners : 1) * sizeof *k);
    if (!a->scene_tri_vertices || !k) {
        free(k);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < 3 * scene->tri_count; i++) a->scene_tri_vertices[i] = UINT32_MAX;
    size_t m = 0;
    for (size_t s = 0; s < a->object_count; s++) {
        const bk_object *ob = &scene->objects[a->objects[s].object];
        for (uint32_t i = 0; i < ob->tri_count; i++) {
            size_t tri = (size_t)ob->first_tri + i;
            int32_t e = a->scene_tri_entry[tri];
            for (int c = 0; c < 3; c++) {
                vkey *q = &k[m++];
                q->vertex = scene->tris[3 * tri + (size_t)c];
                q->slot = (uint32_t)s;
                q->corner = (uint32_t)(3 * tri + (size_t)c);
                if (e >= 0) {
                    uint32_t ch = a->tri_chart[e];
                    const bk_atlas_page *pg = &a->pages[a->charts[ch].page];
                    q->chart = ch;
                    q->u = a->tri_uv[6 * (size_t)e + 2 * (size_t)c] / (float)pg->width;
                    q->v = a->tri_uv[6 * (size_t)e + 2 * (size_t)c + 1] / (float)pg->height;
                } else {
                    q->chart = UINT32_MAX;
                    q->u = q->v = 0.0f;
                }
            }
        }
    }
    qsort(k, m, sizeof *k, cmp_vkey);
    a->vertex_source = malloc((m ? m : 1) * sizeof *a->vertex_source);
    a->vertex_slot = malloc((m ? m : 1) * sizeof *a->vertex_slot);
    a->vertex_uv = malloc((m ? m : 1) * 2 * sizeof *a->vertex_uv);
    if (!a->vertex_source || !a->vertex_slot || !a->vertex_uv) {
        free(k);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    size_t nv = 0;
    for (size_t i = 0; i < m; i++) {
        const vkey *q = &k[i];
        uint32_t id = UINT32_MAX;
        if (q->chart != UINT32_MAX) {
            if (nv > 0 && i > 0 && k[i - 1].vertex == q->vertex && k[i - 1].chart == q->chart && k[i - 1].u == q->u &&
                k[i - 1].v == q->v)
                id = (uint32_t)nv - 1;
        } else {
            /* a zero-area triangle's corner: reuse a vertex of the same scene vertex and object */
            for (size_t j = i; j-- > 0 && k[j].vertex == q->vertex;)
                if (k[j].chart != UINT32_MAX && k[j].slot == q->slot) {
                    id = a->scene_tri_vertices[k[j].corner];
                    break;
                }
        }
        if (id == UINT32_MAX) {
            id = (uint32_t)nv++;
            a->vertex_source[id] = q->vertex;
            a->vertex_slot[id] = q->slot;
            if (q->chart != UINT32_MAX) {
                a->vertex_uv[2 * id] = q->u;
                a->vertex_uv[2 * id + 1] = q->v;
            } else {
                /* the centre of the object's first texel (or 0 if it has none) */
                const bk_atlas_object *o = &a->objects[q->slot];
                float u = 0.0f, v = 0.0f;
                if (o->page >= 0) {
                    u = ((float)o->x + 0.5f) / (float)a->pages[o->page].width;
                    v = ((float)o->y + 0.5f) / (float)a->pages[o->page].height;
                }
                a->vertex_uv[2 * id] = u;
                a->vertex_uv[2 * id + 1] = v;
            }
        }
        a->scene_tri_vertices[q->corner] = id;
    }
    a->vertex_count = nv;
    free(k);
    return LBK_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* The atlas: objects → rectangles within the budget → pages → charts in page coordinates    */

/* The options with their defaults and caps applied. */
typedef struct atlas_limits {
    int page, max_page;  /* default and largest page side, multiples of 4 (no page is wider) */
    int margin;          /* ceil(padding / 2) */
    int align;           /* 1, or 4 with block_align */
    int lone;            /* one object only: its rectangle becomes the page (sides multiples of 4) */
    uint64_t budget;     /* texels */
    bk_uv_options uv;
} atlas_limits;

static lbk_result resolve_limits(const bk_atlas_options *opt, atlas_limits *l)
{
    int page = opt && opt->page_size > 0 ? opt->page_size : DEFAULT_PAGE;
    int max_page = opt && opt->max_page_size > 0 ? opt->max_page_size : DEFAULT_MAX_PAGE;
    if (max_page > 16384) max_page = 16384;
    max_page &= ~3;
    if (max_page < 8) max_page = 8;
    page = round4(page);
    if (page > max_page) page = max_page;
    int padding = opt && opt->padding > 0 ? opt->padding : DEFAULT_PADDING;
    if (padding > 64) padding = 64;
    l->page = page;
    l->max_page = max_page;
    l->margin = (padding + 1) / 2;
    l->align = opt && opt->block_align ? 4 : 1;
    l->budget = opt && opt->texel_budget > 0 ? opt->texel_budget : DEFAULT_BUDGET;
    memset(&l->uv, 0, sizeof l->uv);
    if (opt) l->uv = opt->uv;
    int room = page - 2 * l->margin;
    if (l->uv.max_chart_texels <= 0 || l->uv.max_chart_texels > room) l->uv.max_chart_texels = room;
    /* a triangle cannot be split: its chart may take a whole maximum page */
    int max_room = max_page - 2 * l->margin;
    if (l->uv.max_triangle_texels <= 0 || l->uv.max_triangle_texels > max_room) l->uv.max_triangle_texels = max_room;
    if (l->uv.max_triangle_texels < l->uv.max_chart_texels) l->uv.max_triangle_texels = l->uv.max_chart_texels;
    return l->uv.max_chart_texels < 1 ? LBK_ERR_INVALID_ARGUMENT : LBK_OK;
}

/* One slot per lightmapped object (out->objects, out->object_slot) with the density it asks
 * for; *op_out gets the matching packing state, zeroed. */
static lbk_result select_objects(const bk_scene *scene, const uint8_t *lightmapped, const bk_atlas_options *opt,
                                 bk_atlas *out, obj_pack **op_out)
{
    size_t nobj = 0;
    for (size_t i = 0; i < scene->object_count; i++)
        if (!lightmapped || lightmapped[i]) nobj++;
    obj_pack *op = calloc(nobj ? nobj : 1, sizeof *op);
    *op_out = op;
    out->object_slot = malloc((scene->object_count ? scene->object_count : 1) * sizeof *out->object_slot);
    out->objects = calloc(nobj ? nobj : 1, sizeof *out->objects);
    if (!op || !out->object_slot || !out->objects) return LBK_ERR_OUT_OF_MEMORY;
    out->object_count = nobj;
    size_t slot = 0;
    for (size_t i = 0; i < scene->object_count; i++) {
        out->object_slot[i] = -1;
        if (lightmapped && !lightmapped[i]) continue;
        const bk_object *ob = &scene->objects[i];
        if ((uint64_t)ob->first_tri + ob->tri_count > scene->tri_count) return LBK_ERR_INVALID_ARGUMENT;
        out->object_slot[i] = (int32_t)slot;
        out->objects[slot].object = (uint32_t)i;
        op[slot].requested = bk_atlas_requested_density(scene, (uint32_t)i, opt);
        op[slot].fit_scale = 1.0f;
        slot++;
    }
    return LBK_OK;
}

/* Charts of one object at its density × scale until its rectangle fits one max page (an
 * object's charts share one page, spec/container.md §8): first the charts of its lone large
 * triangles shrink (their cap lowered step by step, down to MIN_TRI_CAP texels), and only then
 * the object's own fit_scale is lowered, so a few large triangles never cost the rest of the
 * object its density. */
#define MIN_TRI_CAP 16
static lbk_result pack_object_to_fit(const bk_scene *scene, uint32_t object, double scale, const atlas_limits *l,
                                     obj_pack *p)
{
    p->tri_cap = l->uv.max_triangle_texels;
    for (int attempt = 0; attempt < 64; attempt++) {
        int fits;
        double d = p->requested * scale * p->fit_scale;
        lbk_result r = pack_object(scene, object, d, &l->uv, l->margin, l->align, l->max_page, l->lone ? 4 : 1, p, &fits);
        if (r != LBK_OK || fits) return r;
        int smaller = (int)(p->tri_cap * 0.8);
        if ((p->uv.big_tris > 0 || p->uv.scaled_tris > 0) && smaller >= MIN_TRI_CAP)
            p->tri_cap = smaller;
        else
            p->fit_scale *= 0.8f;
    }
    return LBK_ERR_LIMIT;
}

/* Charts and object rectangles of every object; when their texels exceed the budget, first the
 * charts of lone triangles larger than a default page shrink (their cap, down to the default
 * chart cap: a ground quad of a few huge triangles must not cost every other object its
 * density), then every density is scaled by the same factor and all are packed again (noted in
 * out->note). */
static lbk_result pack_objects_within_budget(const bk_scene *scene, bk_atlas *out, obj_pack *op, const atlas_limits *l)
{
    double scale = 1.0;
    atlas_limits lim = *l;
    for (int round = 0;; round++) {
        double total = 0.0;
        size_t big = 0;
        for (size_t s = 0; s < out->object_count; s++) {
            lbk_result r = pack_object_to_fit(scene, out->objects[s].object, scale, &lim, &op[s]);
            if (r != LBK_OK) return r;
            total += (double)op[s].w * op[s].h;
            big += op[s].uv.big_tris;
        }
        if (total <= (double)l->budget) break;
        if (round == 31) return LBK_ERR_LIMIT;
        if (big > 0 && lim.uv.max_triangle_texels > lim.uv.max_chart_texels) {
            int c = (int)(lim.uv.max_triangle_texels * 0.8);
            lim.uv.max_triangle_texels = c > lim.uv.max_chart_texels ? c : lim.uv.max_chart_texels;
            continue;
        }
        scale *= sqrt((double)l->budget / total) * 0.98;
    }
    if (scale < 1.0) {
        out->density_scale = (float)scale;
        snprintf(out->note, sizeof out->note, "texel budget %llu exceeded: every density scaled by %.4f",
                 (unsigned long long)l->budget, scale);
    }
    return LBK_OK;
}

/* The page side: the default, or more when one object rectangle needs it (at most max_page). */
static int page_side(const obj_pack *op, size_t nobj, const atlas_limits *l)
{
    int psize = l->page;
    for (size_t s = 0; s < nobj; s++) {
        int m = op[s].w > op[s].h ? op[s].w : op[s].h;
        if (m > psize) psize = round4(m) > l->max_page ? l->max_page : round4(m);
    }
    return psize;
}

/* Fills the object records from their packing (uv source, densities, notes) and returns the
 * rectangles of the objects that have charts, sorted for the packer. */
static lbk_result object_rects(bk_atlas *out, const obj_pack *op, int max_page, bk_pack_rect **rc_out, int *nrect_out)
{
    size_t nobj = out->object_count;
    bk_pack_rect *rc = malloc((nobj ? nobj : 1) * sizeof *rc);
    *rc_out = rc;
    if (!rc) return LBK_ERR_OUT_OF_MEMORY;
    int nrect = 0;
    for (size_t s = 0; s < nobj; s++) {
        bk_atlas_object *o = &out->objects[s];
        o->page = -1;
        o->uv_source = op[s].uv.source;
        o->requested_density = op[s].requested;
        o->density = op[s].uv.density;
        o->degenerate_tris = (uint32_t)op[s].uv.degenerate_count;
        snprintf(o->note, sizeof o->note, "%s", op[s].uv.note);
        if (op[s].fit_scale < 1.0f) {
            size_t len = strlen(o->note);
            snprintf(o->note + len, sizeof o->note - len, "%sdensity lowered to %g texels/m to fit a %d page",
                     len ? "; " : "", o->density, max_page);
        }
        if (op[s].uv.chart_count == 0) continue;
        memset(&rc[nrect], 0, sizeof rc[nrect]);
        rc[nrect].w = op[s].w;
        rc[nrect].h = op[s].h;
        rc[nrect].id = (uint32_t)s;
        rc[nrect].turnable = (uint8_t)may_turn(&op[s].uv);
        nrect++;
    }
    bk_pack_sort(rc, nrect);
    *nrect_out = nrect;
    return LBK_OK;
}

/* Fills psize × psize pages one after the other with the sorted rectangles (out->pages);
 * rect_page[i] gets the page of rc[i]. */
static lbk_result fill_pages(bk_atlas *out, bk_pack_rect *rc, int nrect, int psize, int *rect_page)
{
    out->pages = malloc((size_t)(nrect ? nrect : 1) * sizeof *out->pages);
    if (!out->pages) return LBK_ERR_OUT_OF_MEMORY;
    size_t npages = 0;
    for (int remaining = nrect; remaining > 0;) {
        int uw, uh;
        int placed = bk_pack_into(rc, nrect, psize, psize, &uw, &uh);
        if (placed < 0) return LBK_ERR_OUT_OF_MEMORY;
        if (placed == 0) return LBK_ERR_LIMIT; /* cannot happen: every rectangle fits an empty page */
        for (int i = 0; i < nrect; i++)
            if (rc[i].placed == 1) {
                rect_page[i] = (int)npages;
                rc[i].placed = 2;
            }
        out->pages[npages].width = psize;
        out->pages[npages].height = psize;
        out->page_count = ++npages;
        remaining -= placed;
    }
    return LBK_OK;
}

/* The last page is usually part full: repack its rectangles as tightly as possible, or, when
 * that finds nothing, keep the first packing and crop the page to its extent. */
static lbk_result shrink_last_page(bk_atlas *out, bk_pack_rect *rc, int nrect, const int *rect_page, int psize)
{
    if (out->page_count == 0) return LBK_OK;
    int last = (int)out->page_count - 1, cnt = 0;
    bk_pack_rect *lr = malloc((size_t)nrect * sizeof *lr);
    if (!lr) return LBK_ERR_OUT_OF_MEMORY;
    for (int i = 0; i < nrect; i++)
        if (rect_page[i] == last) {
            lr[cnt] = rc[i];
            lr[cnt].id = (uint32_t)i;
            lr[cnt].placed = 0;
            cnt++;
        }
    int pw = 0, ph = 0;
    int ok = bk_pack_tight(lr, cnt, psize, psize, 4, 4, &pw, &ph);
    if (ok == 1) {
        for (int i = 0; i < cnt; i++) {
            rc[lr[i].id].x = lr[i].x;
            rc[lr[i].id].y = lr[i].y;
            rc[lr[i].id].turned = lr[i].turned;
        }
        out->pages[last].width = pw;
        out->pages[last].height = ph;
    } else if (ok == 0) {
        int uw = 0, uh = 0;
        for (int i = 0; i < nrect; i++)
            if (rect_page[i] == last) {
                int fw = rc[i].turned ? rc[i].h : rc[i].w, fh = rc[i].turned ? rc[i].w : rc[i].h;
                if (rc[i].x + fw > uw) uw = rc[i].x + fw;
                if (rc[i].y + fh > uh) uh = rc[i].y + fh;
            }
        out->pages[last].width = round4(uw);
        out->pages[last].height = round4(uh);
    }
    free(lr);
    return ok < 0 ? LBK_ERR_OUT_OF_MEMORY : LBK_OK;
}

/* Object rectangles → pages: out->pages, out->texels and each object's page and rectangle. */
static lbk_result pack_pages(bk_atlas *out, obj_pack *op, const atlas_limits *l)
{
    int psize = page_side(op, out->object_count, l);
    bk_pack_rect *rc = NULL;
    int nrect = 0;
    lbk_result r = object_rects(out, op, l->max_page, &rc, &nrect);
    int *rect_page = r == LBK_OK ? malloc((size_t)(nrect ? nrect : 1) * sizeof *rect_page) : NULL;
    if (r == LBK_OK && !rect_page) r = LBK_ERR_OUT_OF_MEMORY;
    if (r == LBK_OK) r = fill_pages(out, rc, nrect, psize, rect_page);
    if (r == LBK_OK) r = shrink_last_page(out, rc, nrect, rect_page, psize);
    if (r == LBK_OK) {
        for (size_t p = 0; p < out->page_count; p++)
            out->texels += (uint64_t)out->pages[p].width * (uint64_t)out->pages[p].height;
        for (int i = 0; i < nrect; i++) {
            bk_atlas_object *o = &out->objects[rc[i].id];
            o->page = rect_page[i];
            o->x = rc[i].x;
            o->y = rc[i].y;
            o->w = rc[i].turned ? rc[i].h : rc[i].w;
            o->h = rc[i].turned ? rc[i].w : rc[i].h;
            op[rc[i].id].turned = rc[i].turned;
        }
    }
    free(rc);
    free(rect_page);
    return r;
}

/* A quarter turn of point (x, y) of a rectangle w wide: (y, w − x), a rotation (not a
 * mirror) that maps [0, w] × [0, h] onto [0, h] × [0, w]. */
static void quarter_turn(double *x, double *y, double w)
{
    double nx = *y;
    *y = w - *x;
    *x = nx;
}

/* Chart k of object s in page coordinates: its content rectangle, and its triangles appended
 * from entry t. A chart turned inside its object and an object turned in its page compose. */
static void place_chart(const bk_scene *scene, bk_atlas *out, const obj_pack *op, size_t s, size_t k, uint32_t c,
                        size_t t, int margin)
{
    const bk_atlas_object *o = &out->objects[s];
    const bk_uv_object *u = &op[s].uv;
    bk_atlas_chart *ch = &out->charts[c];
    int cw = content_size(u->charts[k].width), chh = content_size(u->charts[k].height);
    int tc = op[s].chart_turned[k] != 0, to = op[s].turned != 0;
    /* content rectangle inside the object's rectangle as packed, then in the page */
    int cx = op[s].chart_x[k] + margin, cy = op[s].chart_y[k] + margin;
    int cwt = tc ? chh : cw, cht = tc ? cw : chh;
    ch->slot = (uint32_t)s;
    ch->page = o->page;
    ch->x = o->x + (to ? cy : cx);
    ch->y = o->y + (to ? op[s].w - cx - cwt : cy);
    ch->w = to ? cht : cwt;
    ch->h = to ? cwt : cht;
    ch->quarter_turns = (uint8_t)(tc + to);
    ch->first = (uint32_t)t;
    ch->count = u->charts[k].count;
    if (u->source == BK_UV_AUTHORED) { /* one chart, never turned: its origin is uv1_min (LMUV) */
        bk_atlas_object *ao = &out->objects[s];
        ao->uv1_scale = u->uv1_scale;
        for (int q = 0; q < 2; q++) {
            ao->uv1_offset[q] = (q ? ch->y : ch->x) - u->uv1_min[q] * u->uv1_scale;
            ao->uv1_min[q] = u->uv1_min[q];
            ao->uv1_max[q] = u->uv1_max[q];
        }
    }
    for (uint32_t j = 0; j < u->charts[k].count; j++, t++) {
        size_t src = (size_t)u->charts[k].first + j;
        out->tris[t] = u->tris[src];
        out->tri_chart[t] = c;
        out->scene_tri_entry[u->tris[src]] = (int32_t)t;
        for (int q = 0; q < 3; q++) {
            double x = u->uv[6 * src + 2 * (size_t)q], y = u->uv[6 * src + 2 * (size_t)q + 1];
            if (tc) quarter_turn(&x, &y, cw);
            x += cx;
            y += cy;
            if (to) quarter_turn(&x, &y, op[s].w);
            out->tri_uv[6 * t + 2 * (size_t)q] = (float)(o->x + x);
            out->tri_uv[6 * t + 2 * (size_t)q + 1] = (float)(o->y + y);
        }
    }
    (void)scene;
}

/* Charts and triangles in page coordinates: every chart's block sits at its object's
 * rectangle plus its offset inside it, its content one margin further in. */
static lbk_result place_charts(const bk_scene *scene, bk_atlas *out, const obj_pack *op, int margin)
{
    size_t nobj = out->object_count, nchart = 0, ntri = 0;
    for (size_t s = 0; s < nobj; s++) {
        nchart += op[s].uv.chart_count;
        ntri += op[s].uv.tri_count;
    }
    if (nchart > (size_t)INT32_MAX || ntri > (size_t)INT32_MAX) return LBK_ERR_LIMIT;
    out->charts = malloc((nchart ? nchart : 1) * sizeof *out->charts);
    out->tris = malloc((ntri ? ntri : 1) * sizeof *out->tris);
    out->tri_chart = malloc((ntri ? ntri : 1) * sizeof *out->tri_chart);
    out->tri_uv = malloc((ntri ? ntri : 1) * 6 * sizeof *out->tri_uv);
    out->scene_tri_entry = malloc((scene->tri_count ? scene->tri_count : 1) * sizeof *out->scene_tri_entry);
    if (!out->charts || !out->tris || !out->tri_chart || !out->tri_uv || !out->scene_tri_entry)
        return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < scene->tri_count; i++) out->scene_tri_entry[i] = -1;
    size_t c = 0, t = 0;
    for (size_t s = 0; s < nobj; s++) {
        bk_atlas_object *o = &out->objects[s];
        o->first_chart = (uint32_t)c;
        o->chart_count = (uint32_t)op[s].uv.chart_count;
        for (size_t k = 0; k < op[s].uv.chart_count; k++, c++) {
            place_chart(scene, out, op, s, k, (uint32_t)c, t, margin);
            t += op[s].uv.charts[k].count;
        }
    }
    out->chart_count = nchart;
    out->tri_count = ntri;
    return LBK_OK;
}

lbk_result bk_atlas_build(const bk_scene *scene, const uint8_t *lightmapped, const bk_atlas_options *opt,
                          bk_atlas *out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!scene || (scene->object_count && !scene->objects) || (scene->tri_count && !scene->tris))
        return LBK_ERR_INVALID_ARGUMENT;
    if (scene->tri_count > (size_t)INT32_MAX || scene->object_count > (size_t)INT32_MAX) return LBK_ERR_LIMIT;
    atlas_limits lim;
    lbk_result r = resolve_limits(opt, &lim);
    if (r != LBK_OK) return r;

    out->padding = 2 * lim.margin;
    out->margin = lim.margin;
    out->density_scale = 1.0f;
    out->scene_object_count = scene->object_count;
    out->scene_tri_count = scene->tri_count;
    obj_pack *op = NULL;
    r = select_objects(scene, lightmapped, opt, out, &op);
    lim.lone = out->object_count == 1;
    if (r == LBK_OK) r = pack_objects_within_budget(scene, out, op, &lim);
    if (r == LBK_OK) r = pack_pages(out, op, &lim);
    if (r == LBK_OK) r = place_charts(scene, out, op, lim.margin);
    if (r == LBK_OK) r = build_vertices(scene, out);
    if (op)
        for (size_t s = 0; s < out->object_count; s++) obj_pack_free(&op[s]);
    free(op);
    if (r != LBK_OK) bk_atlas_free(out);
    return r;
}
