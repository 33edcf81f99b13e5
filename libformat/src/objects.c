/* OBJS: build, view and validate (spec/container.md §8, spec/validation.md 400–499). */
#define XXH_STATIC_LINKING_ONLY /* XXH3_state_t on the stack */
#include "xxh.h"

#include "lbk/objects.h"

#include "text.h"

const char *lbk_representation_name(uint32_t r)
{
    switch (r) {
    case LBK_REPRESENTATION_LIGHTMAP: return "lightmap";
    case LBK_REPRESENTATION_LLG: return "llg";
    case LBK_REPRESENTATION_NONE: return "none";
    default: return "unknown";
    }
}

uint64_t lbk_objects_geometry_hash(const float *xyz, size_t triangle_count)
{
    XXH3_state_t st;
    XXH3_64bits_reset(&st); /* a stack state: the library holds no heap or global state */
    uint8_t buf[9 * 4 * 64];
    size_t floats = triangle_count * 9, done = 0;
    while (done < floats) {
        size_t n = floats - done < sizeof buf / 4 ? floats - done : sizeof buf / 4;
        for (size_t i = 0; i < n; i++) lbk_wrf32(buf + 4 * i, xyz[done + i] + 0.0f);
        XXH3_64bits_update(&st, buf, 4 * n);
        done += n;
    }
    return XXH3_64bits_digest(&st);
}

lbk_result lbk_objects_geometry_check(const lbk_objects_view *view, uint32_t object, const float *xyz,
                                      size_t triangle_count)
{
    if (!view || (triangle_count && !xyz) || triangle_count > SIZE_MAX / (9 * sizeof(float)))
        return LBK_ERR_INVALID_ARGUMENT;
    if (object >= view->count) return LBK_ERR_NOT_FOUND;
    const uint64_t stored = lbk_rd64(view->records + (size_t)LBK_OBJECTS_RECORD_SIZE * object + 8);
    return lbk_objects_geometry_hash(xyz, triangle_count) == stored ? LBK_OK : LBK_ERR_MISMATCH;
}

static void read_object(const uint8_t *r, const uint8_t *names, lbk_object *o)
{
    o->name.data = (const char *)names + lbk_rd32(r + 0);
    o->name.size = lbk_rd32(r + 4);
    o->geometry_hash = lbk_rd64(r + 8);
    o->representation = lbk_rd32(r + 16);
    o->index = lbk_rd32(r + 20);
    o->rect_x = lbk_rd32(r + 24);
    o->rect_y = lbk_rd32(r + 28);
    o->rect_w = lbk_rd32(r + 32);
    o->rect_h = lbk_rd32(r + 36);
}

/* Rule of §8.2: fields the representation does not use are zero, rectangles are not empty. */
static bool fields_consistent(const lbk_object *o)
{
    switch (o->representation) {
    case LBK_REPRESENTATION_LIGHTMAP: return o->rect_w > 0 && o->rect_h > 0;
    case LBK_REPRESENTATION_LLG: return !(o->rect_x | o->rect_y | o->rect_w | o->rect_h);
    case LBK_REPRESENTATION_NONE: return !(o->index | o->rect_x | o->rect_y | o->rect_w | o->rect_h);
    default: return false;
    }
}

lbk_result lbk_objects_build(const lbk_object *objects, uint32_t count, const lbk_allocator *allocator, void **out,
                             size_t *size)
{
    if (!out || !size || (!objects && count)) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (count == 0) return LBK_ERR_INVALID_ARGUMENT;
    uint64_t names = 0;
    for (uint32_t i = 0; i < count; i++) {
        const lbk_object *o = &objects[i];
        if (!o->name.data || o->name.size == 0 || !lbk_utf8_valid((const uint8_t *)o->name.data, o->name.size))
            return LBK_ERR_INVALID_ARGUMENT;
        if (o->representation >= LBK_REPRESENTATION_COUNT_ || !fields_consistent(o)) return LBK_ERR_INVALID_ARGUMENT;
        if (o->rect_x > UINT32_MAX - o->rect_w || o->rect_y > UINT32_MAX - o->rect_h) return LBK_ERR_RANGE;
        names += o->name.size;
        if (names > UINT32_MAX) return LBK_ERR_LIMIT;
    }
    uint64_t total = LBK_OBJECTS_HEADER_SIZE + (uint64_t)LBK_OBJECTS_RECORD_SIZE * count + names;
    uint8_t *b = total <= SIZE_MAX ? lbk_calloc(allocator, 1, (size_t)total) : NULL;
    if (!b) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(b + 0, count);
    lbk_wr32(b + 4, (uint32_t)names);
    uint8_t *blob = b + LBK_OBJECTS_HEADER_SIZE + (size_t)LBK_OBJECTS_RECORD_SIZE * count;
    uint32_t at = 0;
    for (uint32_t i = 0; i < count; i++) {
        const lbk_object *o = &objects[i];
        uint8_t *r = b + LBK_OBJECTS_HEADER_SIZE + (size_t)LBK_OBJECTS_RECORD_SIZE * i;
        lbk_wr32(r + 0, at);
        lbk_wr32(r + 4, (uint32_t)o->name.size);
        lbk_wr64(r + 8, o->geometry_hash);
        lbk_wr32(r + 16, o->representation);
        lbk_wr32(r + 20, o->index);
        lbk_wr32(r + 24, o->rect_x);
        lbk_wr32(r + 28, o->rect_y);
        lbk_wr32(r + 32, o->rect_w);
        lbk_wr32(r + 36, o->rect_h);
        memcpy(blob + at, o->name.data, o->name.size);
        at += (uint32_t)o->name.size;
    }
    *out = b;
    *size = (size_t)total;
    return LBK_OK;
}

lbk_result lbk_objects_open(const void *data, size_t size, lbk_objects_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_OBJECTS_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    uint32_t n = lbk_rd32(d), names = lbk_rd32(d + 4);
    uint64_t need = LBK_OBJECTS_HEADER_SIZE + (uint64_t)LBK_OBJECTS_RECORD_SIZE * n + names;
    if (need > size) return LBK_ERR_TRUNCATED;
    if (need != size || lbk_rd64(d + 8)) return LBK_ERR_CORRUPT;
    const uint8_t *records = d + LBK_OBJECTS_HEADER_SIZE;
    for (uint32_t i = 0; i < n; i++) {
        const uint8_t *r = records + (size_t)LBK_OBJECTS_RECORD_SIZE * i;
        if (!lbk_range_ok(lbk_rd32(r), lbk_rd32(r + 4), names)) return LBK_ERR_CORRUPT;
    }
    out->records = records;
    out->names = records + (size_t)LBK_OBJECTS_RECORD_SIZE * n;
    out->count = n;
    out->names_size = names;
    return LBK_OK;
}

lbk_result lbk_objects_get(const lbk_objects_view *v, uint32_t index, lbk_object *out)
{
    if (!v || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= v->count) return LBK_ERR_NOT_FOUND;
    read_object(v->records + (size_t)LBK_OBJECTS_RECORD_SIZE * index, v->names, out);
    return LBK_OK;
}

lbk_result lbk_objects_find(const lbk_objects_view *v, lbk_string name, uint32_t *index)
{
    if (!v || !index || (!name.data && name.size)) return LBK_ERR_INVALID_ARGUMENT;
    for (uint32_t i = 0; i < v->count; i++) {
        lbk_object o;
        lbk_objects_get(v, i, &o);
        if (o.name.size == name.size && (name.size == 0 || !memcmp(o.name.data, name.data, name.size))) {
            *index = i;
            return LBK_OK;
        }
    }
    return LBK_ERR_NOT_FOUND;
}

/* ---- validation -------------------------------------------------------------------------- */

typedef struct objs_sort {
    const lbk_objects_view *v;
} objs_sort;

static int cmp_names(void *c, uint32_t a, uint32_t b)
{
    lbk_object oa, ob;
    lbk_objects_get(((objs_sort *)c)->v, a, &oa);
    lbk_objects_get(((objs_sort *)c)->v, b, &ob);
    return lbk_bytes_cmp((const uint8_t *)oa.name.data, oa.name.size, (const uint8_t *)ob.name.data, ob.name.size);
}

/* Lightmapped objects by (page, rect_x). */
static int cmp_rects(void *c, uint32_t a, uint32_t b)
{
    lbk_object oa, ob;
    lbk_objects_get(((objs_sort *)c)->v, a, &oa);
    lbk_objects_get(((objs_sort *)c)->v, b, &ob);
    if (oa.index != ob.index) return oa.index < ob.index ? -1 : 1;
    return oa.rect_x < ob.rect_x ? -1 : oa.rect_x > ob.rect_x ? 1 : 0;
}

static uint64_t record_offset(uint32_t i) { return LBK_OBJECTS_HEADER_SIZE + (uint64_t)LBK_OBJECTS_RECORD_SIZE * i; }

/* Duplicate names (405) and overlapping lightmap rectangles (414): both need a sort. `placed`
 * lists the lightmapped objects whose rectangle lies inside its page. */
static void check_pairs(lbk_vctx *ctx, const lbk_objects_view *v, uint32_t *idx, uint32_t *scratch, uint32_t *placed,
                        uint32_t placed_count)
{
    objs_sort c = {v};
    for (uint32_t i = 0; i < v->count; i++) idx[i] = i;
    lbk_sort_indices(idx, scratch, v->count, cmp_names, &c);
    for (uint32_t i = 1; i < v->count && !ctx->stop; i++)
        if (cmp_names(&c, idx[i - 1], idx[i]) == 0) {
            lbk_object o;
            lbk_objects_get(v, idx[i], &o);
            lbk_vreport(ctx, 405, record_offset(idx[i]), "OBJS objects %u and %u are both named '%.*s'", idx[i - 1],
                        idx[i], (int)(o.name.size > 60 ? 60 : o.name.size), o.name.data);
        }
    lbk_sort_indices(placed, scratch, placed_count, cmp_rects, &c);
    /* Sweep along x: an object can only overlap later ones that start before it ends. */
    for (uint32_t i = 0; i < placed_count && !ctx->stop; i++) {
        lbk_object a, b;
        lbk_objects_get(v, placed[i], &a);
        for (uint32_t j = i + 1; j < placed_count; j++) {
            lbk_objects_get(v, placed[j], &b);
            if (b.index != a.index || b.rect_x >= (uint64_t)a.rect_x + a.rect_w) break;
            if (b.rect_y < (uint64_t)a.rect_y + a.rect_h && a.rect_y < (uint64_t)b.rect_y + b.rect_h) {
                lbk_vreport(ctx, 414, record_offset(placed[j]),
                            "OBJS objects %u and %u overlap in lightmap page %u ([%u,%u %ux%u] and [%u,%u %ux%u])",
                            placed[i], placed[j], a.index, a.rect_x, a.rect_y, a.rect_w, a.rect_h, b.rect_x, b.rect_y,
                            b.rect_w, b.rect_h);
                break; /* one report per object keeps the output readable */
            }
        }
    }
}

void lbk_validate_objs(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_OBJECTS_HEADER_SIZE) {
        lbk_vreport(ctx, 400, 0, "OBJS is %zu bytes, its header needs 16", size);
        return;
    }
    uint32_t n = lbk_rd32(d), names = lbk_rd32(d + 4);
    if (lbk_rd64(d + 8)) lbk_vreport(ctx, 401, 8, "OBJS reserved header bytes are not zero");
    if (n == 0) lbk_vreport(ctx, 413, 0, "OBJS object_count is 0");
    uint64_t need = LBK_OBJECTS_HEADER_SIZE + (uint64_t)LBK_OBJECTS_RECORD_SIZE * n + names;
    if (need != size) {
        lbk_vreport(ctx, 402, 0, "OBJS of %u objects and %u name bytes needs %llu bytes, section has %zu", n, names,
                    (unsigned long long)need, size);
        return;
    }
    /* Packed names first: after this every name lies inside the blob and the view is safe. */
    uint64_t at = 0;
    for (uint32_t i = 0; i < n; i++) {
        const uint8_t *r = d + record_offset(i);
        uint32_t off = lbk_rd32(r), len = lbk_rd32(r + 4);
        if (off != at || at + len > names) {
            lbk_vreport(ctx, 403, record_offset(i),
                        "OBJS object %u: name at %u+%u, the packed layout puts it at %llu within %u bytes", i, off, len,
                        (unsigned long long)at, names);
            return;
        }
        at += len;
    }
    if (at != names) {
        lbk_vreport(ctx, 403, 4, "OBJS names use %llu of %u blob bytes", (unsigned long long)at, names);
        return;
    }
    lbk_objects_view v;
    if (lbk_objects_open(d, size, &v) != LBK_OK) return; /* unreachable after the checks above */

    const int has_lmap = lbk_vctx_has_section(ctx, LBK_SECTION_LMAP);
    const int has_llg = lbk_vctx_has_section(ctx, LBK_SECTION_LLG);
    uint32_t *idx = lbk_calloc(ctx->allocator, (size_t)n * 3 + 1, sizeof *idx);
    uint32_t placed_count = 0;
    int valid = 1;
    for (uint32_t i = 0; i < n && !ctx->stop; i++) {
        const uint64_t ro = record_offset(i);
        lbk_object o;
        lbk_objects_get(&v, i, &o);
        if (o.name.size == 0 || !lbk_utf8_valid((const uint8_t *)o.name.data, o.name.size)) {
            lbk_vreport(ctx, 404, ro, "OBJS object %u: name is empty, not valid UTF-8 or contains NUL", i);
            valid = 0;
        }
        if (o.representation >= LBK_REPRESENTATION_COUNT_) {
            lbk_vreport(ctx, 406, ro + 16, "OBJS object %u: representation %u is not 0..2", i, o.representation);
            valid = 0;
            continue;
        }
        if (!fields_consistent(&o)) {
            lbk_vreport(ctx, 407, ro + 20,
                        "OBJS object %u (%s): index %u, rect [%u,%u %ux%u] break the field rules of its representation",
                        i, lbk_representation_name(o.representation), o.index, o.rect_x, o.rect_y, o.rect_w, o.rect_h);
            valid = 0;
            continue;
        }
        if (o.representation == LBK_REPRESENTATION_LIGHTMAP) {
            if (!has_lmap) {
                lbk_vreport(ctx, 408, ro + 16, "OBJS object %u is lightmapped but the file has no LMAP section", i);
                valid = 0;
            } else if (ctx->lmap_ok) {
                if (o.index >= ctx->lmap_page_count) {
                    lbk_vreport(ctx, 409, ro + 20, "OBJS object %u: lightmap page %u, LMAP has %u pages", i, o.index,
                                ctx->lmap_page_count);
                    valid = 0;
                } else {
                    uint64_t w = ctx->lmap_page_width ? ctx->lmap_page_width[o.index] : 0;
                    uint64_t h = ctx->lmap_page_height ? ctx->lmap_page_height[o.index] : 0;
                    if ((uint64_t)o.rect_x + o.rect_w > w || (uint64_t)o.rect_y + o.rect_h > h) {
                        lbk_vreport(ctx, 410, ro + 24, "OBJS object %u: rect [%u,%u %ux%u] outside page %u (%llux%llu)",
                                    i, o.rect_x, o.rect_y, o.rect_w, o.rect_h, o.index, (unsigned long long)w,
                                    (unsigned long long)h);
                        valid = 0;
                    } else if (idx) {
                        idx[2 * (size_t)n + placed_count++] = i;
                    }
                }
            }
        } else if (o.representation == LBK_REPRESENTATION_LLG) {
            if (!has_llg) {
                lbk_vreport(ctx, 411, ro + 16, "OBJS object %u uses an LLG but the file has no LLG section", i);
                valid = 0;
            } else if (ctx->llg_ok && o.index >= ctx->llg_count) {
                lbk_vreport(ctx, 412, ro + 20, "OBJS object %u: LLG %u, the LLG section has %u grids", i, o.index,
                            ctx->llg_count);
                valid = 0;
            }
        }
    }
    if (idx && !ctx->stop) check_pairs(ctx, &v, idx, idx + n, idx + 2 * (size_t)n, placed_count);
    lbk_dealloc(ctx->allocator, idx);
    ctx->objs_ok = valid && n > 0;
    ctx->object_count = ctx->objs_ok ? n : 0;
    /* facts for LMUV's rectangle checks */
    ctx->objs_facts = ctx->objs_ok ? lbk_calloc(ctx->allocator, (size_t)n * 6, sizeof *ctx->objs_facts) : NULL;
    for (uint32_t i = 0; ctx->objs_facts && i < n; i++) {
        lbk_object o;
        lbk_objects_get(&v, i, &o);
        const uint32_t f[6] = {o.representation, o.index, o.rect_x, o.rect_y, o.rect_w, o.rect_h};
        memcpy(ctx->objs_facts + 6 * (size_t)i, f, sizeof f);
    }
}
