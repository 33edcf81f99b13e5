/* LMUV: build, view and validate (spec/container.md §16, spec/validation.md 1100–1199). */
#include <math.h>

#include "lbk/lightmap_uv.h"
#include "lbk/objects.h"

#include "section_util.h"
#include "text.h"

const char *lbk_lmuv_kind_name(uint32_t kind)
{
    switch (kind) {
    case LBK_LMUV_AUTHORED: return "authored";
    case LBK_LMUV_GENERATED: return "generated";
    default: return "unknown";
    }
}

/* ---- layout (§16.2) ------------------------------------------------------------------------ */

typedef struct lmuv_layout {
    uint64_t primitives, remap, indices, coords, end;
} lmuv_layout;

static bool align16_ok(uint64_t v, uint64_t *out)
{
    if (v > UINT64_MAX - 15) return false;
    *out = lbk_align_up(v, 16);
    return true;
}

/* Array offsets implied by the header counts; false when the arithmetic overflows. */
static bool layout_of(uint32_t records, uint32_t primitives, uint64_t vertices, uint64_t indices, lmuv_layout *l)
{
    uint64_t t;
    return lbk_madd_u64(LBK_LMUV_HEADER_SIZE, records, LBK_LMUV_RECORD_SIZE, &t) && align16_ok(t, &l->primitives) &&
           lbk_madd_u64(l->primitives, primitives, LBK_LMUV_PRIMITIVE_SIZE, &t) && align16_ok(t, &l->remap) &&
           lbk_madd_u64(l->remap, vertices, 4, &t) && align16_ok(t, &l->indices) &&
           lbk_madd_u64(l->indices, indices, 4, &t) && align16_ok(t, &l->coords) &&
           lbk_madd_u64(l->coords, vertices, 8, &l->end);
}

/* ---- building ------------------------------------------------------------------------------ */

static bool finite_pair(const float v[2]) { return isfinite(v[0]) && isfinite(v[1]); }

static bool authored_desc_ok(const lbk_lmuv_object_desc *o)
{
    if (o->primitive_count || o->primitives) return false;
    if (!finite_pair(o->scale) || !finite_pair(o->offset) || !finite_pair(o->uv_min) || !finite_pair(o->uv_max))
        return false;
    return o->scale[0] > 0 && o->scale[1] > 0 && o->uv_min[0] <= o->uv_max[0] && o->uv_min[1] <= o->uv_max[1];
}

static bool generated_desc_ok(const lbk_lmuv_object_desc *o)
{
    const float zero[8] = {0};
    if (memcmp(o->scale, zero, sizeof o->scale) || memcmp(o->offset, zero, sizeof o->offset) ||
        memcmp(o->uv_min, zero, sizeof o->uv_min) || memcmp(o->uv_max, zero, sizeof o->uv_max))
        return false;
    if (o->primitive_count == 0 || !o->primitives) return false;
    for (uint32_t p = 0; p < o->primitive_count; p++) {
        const lbk_lmuv_primitive_desc *d = &o->primitives[p];
        if (p > 0 && d->source_primitive <= o->primitives[p - 1].source_primitive) return false;
        if (d->vertex_count == 0 || d->index_count == 0 || d->index_count % 3) return false;
        if (!d->remap || !d->indices || !d->coords) return false;
        for (uint32_t v = 0; v < d->vertex_count; v++)
            if (d->remap[v] >= d->source_vertex_count || !finite_pair(d->coords + 2 * (size_t)v)) return false;
        for (uint32_t i = 0; i < d->index_count; i++)
            if (d->indices[i] >= d->vertex_count) return false;
    }
    return true;
}

static void write_pair(uint8_t *p, const float v[2])
{
    lbk_wrf32(p, v[0] + 0.0f); /* -0 → +0: one content, one encoding */
    lbk_wrf32(p + 4, v[1] + 0.0f);
}

lbk_result lbk_lmuv_build(const lbk_lmuv_object_desc *objects, uint32_t count, const lbk_allocator *allocator,
                          void **out, size_t *size)
{
    if (!out || !size) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (!objects || count == 0) return LBK_ERR_INVALID_ARGUMENT;
    uint64_t prims = 0, verts = 0, idx = 0;
    for (uint32_t r = 0; r < count; r++) {
        const lbk_lmuv_object_desc *o = &objects[r];
        if (r > 0 && o->object <= objects[r - 1].object) return LBK_ERR_INVALID_ARGUMENT;
        if (o->kind == LBK_LMUV_AUTHORED ? !authored_desc_ok(o)
                                         : o->kind != LBK_LMUV_GENERATED || !generated_desc_ok(o))
            return LBK_ERR_INVALID_ARGUMENT;
        prims += o->primitive_count;
        for (uint32_t p = 0; p < o->primitive_count; p++) {
            verts += o->primitives[p].vertex_count;
            idx += o->primitives[p].index_count;
        }
        if (prims > UINT32_MAX) return LBK_ERR_LIMIT;
    }
    lmuv_layout l;
    if (!layout_of(count, (uint32_t)prims, verts, idx, &l) || l.end > SIZE_MAX) return LBK_ERR_LIMIT;
    uint8_t *b = lbk_calloc(allocator, 1, (size_t)l.end);
    if (!b) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(b + 0, count);
    lbk_wr32(b + 4, (uint32_t)prims);
    lbk_wr64(b + 8, verts);
    lbk_wr64(b + 16, idx);
    uint32_t pf = 0;
    uint64_t vf = 0, xf = 0;
    for (uint32_t r = 0; r < count; r++) {
        const lbk_lmuv_object_desc *o = &objects[r];
        uint8_t *rec = b + LBK_LMUV_HEADER_SIZE + (size_t)LBK_LMUV_RECORD_SIZE * r;
        lbk_wr32(rec + 0, o->object);
        lbk_wr32(rec + 4, o->kind);
        lbk_wr32(rec + 8, o->source_node);
        lbk_wr32(rec + 12, o->primitive_count ? pf : 0);
        lbk_wr32(rec + 16, o->primitive_count);
        write_pair(rec + 24, o->scale);
        write_pair(rec + 32, o->offset);
        write_pair(rec + 40, o->uv_min);
        write_pair(rec + 48, o->uv_max);
        for (uint32_t p = 0; p < o->primitive_count; p++, pf++) {
            const lbk_lmuv_primitive_desc *d = &o->primitives[p];
            uint8_t *e = b + l.primitives + (size_t)LBK_LMUV_PRIMITIVE_SIZE * pf;
            lbk_wr32(e + 0, d->source_primitive);
            lbk_wr32(e + 4, d->source_vertex_count);
            lbk_wr32(e + 8, d->vertex_count);
            lbk_wr32(e + 12, d->index_count);
            lbk_wr64(e + 16, vf);
            lbk_wr64(e + 24, xf);
            for (uint32_t v = 0; v < d->vertex_count; v++, vf++) {
                lbk_wr32(b + l.remap + 4 * vf, d->remap[v]);
                write_pair(b + l.coords + 8 * vf, d->coords + 2 * (size_t)v);
            }
            for (uint32_t i = 0; i < d->index_count; i++, xf++) lbk_wr32(b + l.indices + 4 * xf, d->indices[i]);
        }
    }
    *out = b;
    *size = (size_t)l.end;
    return LBK_OK;
}

/* ---- reading ------------------------------------------------------------------------------- */

static void read_object(const uint8_t *r, lbk_lmuv_object *o)
{
    o->object = lbk_rd32(r + 0);
    o->kind = lbk_rd32(r + 4);
    o->source_node = lbk_rd32(r + 8);
    o->primitive_first = lbk_rd32(r + 12);
    o->primitive_count = lbk_rd32(r + 16);
    for (int k = 0; k < 2; k++) {
        o->scale[k] = lbk_rdf32(r + 24 + 4 * k);
        o->offset[k] = lbk_rdf32(r + 32 + 4 * k);
        o->uv_min[k] = lbk_rdf32(r + 40 + 4 * k);
        o->uv_max[k] = lbk_rdf32(r + 48 + 4 * k);
    }
}

static void read_primitive(const uint8_t *e, lbk_lmuv_primitive *p)
{
    p->source_primitive = lbk_rd32(e + 0);
    p->source_vertex_count = lbk_rd32(e + 4);
    p->vertex_count = lbk_rd32(e + 8);
    p->index_count = lbk_rd32(e + 12);
    p->vertex_first = lbk_rd64(e + 16);
    p->index_first = lbk_rd64(e + 24);
}

/* The packed-range rules shared by open and validate: every GENERATED record's primitives
 * follow the previous ones, every primitive's vertices and indices follow the previous ones, and
 * the sums equal the header. Returns false at the first break. */
static bool ranges_packed(const uint8_t *d, const lmuv_layout *l, uint32_t records, uint32_t prims, uint64_t verts,
                          uint64_t idx)
{
    uint32_t pf = 0;
    for (uint32_t r = 0; r < records; r++) {
        lbk_lmuv_object o;
        read_object(d + LBK_LMUV_HEADER_SIZE + (size_t)LBK_LMUV_RECORD_SIZE * r, &o);
        if (o.kind >= LBK_LMUV_KIND_COUNT_) return false;
        if (o.kind == LBK_LMUV_AUTHORED ? (o.primitive_first | o.primitive_count) != 0
                                        : o.primitive_count == 0 || o.primitive_first != pf)
            return false;
        if (o.primitive_count > prims - pf) return false;
        pf += o.primitive_count;
    }
    if (pf != prims) return false;
    uint64_t vf = 0, xf = 0;
    for (uint32_t p = 0; p < prims; p++) {
        lbk_lmuv_primitive q;
        read_primitive(d + l->primitives + (size_t)LBK_LMUV_PRIMITIVE_SIZE * p, &q);
        if (q.vertex_first != vf || q.index_first != xf || q.vertex_count == 0 || q.index_count == 0 ||
            q.index_count % 3)
            return false;
        if (q.vertex_count > verts - vf || q.index_count > idx - xf) return false;
        vf += q.vertex_count;
        xf += q.index_count;
    }
    return vf == verts && xf == idx;
}

lbk_result lbk_lmuv_open(const void *data, size_t size, lbk_lmuv_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_LMUV_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    const uint32_t records = lbk_rd32(d), prims = lbk_rd32(d + 4);
    const uint64_t verts = lbk_rd64(d + 8), idx = lbk_rd64(d + 16);
    lmuv_layout l;
    if (!layout_of(records, prims, verts, idx, &l) || l.end > size) return LBK_ERR_TRUNCATED;
    if (l.end != size || records == 0 || lbk_rd64(d + 24)) return LBK_ERR_CORRUPT;
    if (!ranges_packed(d, &l, records, prims, verts, idx)) return LBK_ERR_CORRUPT;
    for (uint32_t p = 0; p < prims; p++) {
        lbk_lmuv_primitive q;
        read_primitive(d + l.primitives + (size_t)LBK_LMUV_PRIMITIVE_SIZE * p, &q);
        for (uint32_t v = 0; v < q.vertex_count; v++)
            if (lbk_rd32(d + l.remap + 4 * (q.vertex_first + v)) >= q.source_vertex_count) return LBK_ERR_CORRUPT;
        for (uint32_t i = 0; i < q.index_count; i++)
            if (lbk_rd32(d + l.indices + 4 * (q.index_first + i)) >= q.vertex_count) return LBK_ERR_CORRUPT;
    }
    out->data = d;
    out->size = size;
    out->record_count = records;
    out->primitive_count = prims;
    out->vertex_count = verts;
    out->index_count = idx;
    out->records = d + LBK_LMUV_HEADER_SIZE;
    out->primitives = d + l.primitives;
    out->remap = d + l.remap;
    out->indices = d + l.indices;
    out->coords = d + l.coords;
    return LBK_OK;
}

lbk_result lbk_lmuv_get_object(const lbk_lmuv_view *v, uint32_t record, lbk_lmuv_object *out)
{
    if (!v || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (record >= v->record_count) return LBK_ERR_NOT_FOUND;
    read_object(v->records + (size_t)LBK_LMUV_RECORD_SIZE * record, out);
    return LBK_OK;
}

lbk_result lbk_lmuv_find_object(const lbk_lmuv_view *v, uint32_t object, uint32_t *record)
{
    if (!v || !record) return LBK_ERR_INVALID_ARGUMENT;
    uint32_t lo = 0, hi = v->record_count; /* records are strictly ascending by object (validated) */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2, o = lbk_rd32(v->records + (size_t)LBK_LMUV_RECORD_SIZE * mid);
        if (o == object) {
            *record = mid;
            return LBK_OK;
        }
        if (o < object) lo = mid + 1;
        else hi = mid;
    }
    return LBK_ERR_NOT_FOUND;
}

lbk_result lbk_lmuv_get_primitive(const lbk_lmuv_view *v, uint32_t primitive, lbk_lmuv_primitive *out)
{
    if (!v || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (primitive >= v->primitive_count) return LBK_ERR_NOT_FOUND;
    read_primitive(v->primitives + (size_t)LBK_LMUV_PRIMITIVE_SIZE * primitive, out);
    return LBK_OK;
}

/* A primitive whose ranges lie inside the view (callers may pass a hand-made one). */
static bool primitive_in_view(const lbk_lmuv_view *v, const lbk_lmuv_primitive *p)
{
    return lbk_range_ok(p->vertex_first, p->vertex_count, v->vertex_count) &&
           lbk_range_ok(p->index_first, p->index_count, v->index_count);
}

lbk_result lbk_lmuv_vertex(const lbk_lmuv_view *v, const lbk_lmuv_primitive *p, uint32_t i, uint32_t *source,
                           float coord[2])
{
    if (!v || !p) return LBK_ERR_INVALID_ARGUMENT;
    if (!primitive_in_view(v, p) || i >= p->vertex_count) return LBK_ERR_RANGE;
    const uint64_t k = p->vertex_first + i;
    if (source) *source = lbk_rd32(v->remap + 4 * k);
    if (coord) {
        coord[0] = lbk_rdf32(v->coords + 8 * k);
        coord[1] = lbk_rdf32(v->coords + 8 * k + 4);
    }
    return LBK_OK;
}

lbk_result lbk_lmuv_index(const lbk_lmuv_view *v, const lbk_lmuv_primitive *p, uint32_t i, uint32_t *index)
{
    if (!v || !p || !index) return LBK_ERR_INVALID_ARGUMENT;
    if (!primitive_in_view(v, p) || i >= p->index_count) return LBK_ERR_RANGE;
    *index = lbk_rd32(v->indices + 4 * (p->index_first + i));
    return LBK_OK;
}

void lbk_lmuv_authored_coord(const lbk_lmuv_object *o, const float uv1[2], float coord[2])
{
    for (int k = 0; k < 2; k++) {
        volatile float product = o->scale[k] * uv1[k]; /* two roundings, as §16.3 says: no FMA */
        coord[k] = o->offset[k] + product;
    }
}

static int64_t floor_clamped(float f)
{
    const double v = floor((double)f), cap = 4611686018427387904.0; /* 2^62: no overflow on conversion */
    if (!(v > -cap)) return -((int64_t)1 << 62); /* NaN too */
    return v < cap ? (int64_t)v : (int64_t)1 << 62;
}

void lbk_lmuv_texel_of(const float coord[2], int64_t *x, int64_t *y)
{
    if (x) *x = floor_clamped(coord[0]);
    if (y) *y = floor_clamped(coord[1]);
}

void lbk_lmuv_normalized(const float coord[2], uint32_t w, uint32_t h, float uv[2])
{
    uv[0] = w ? coord[0] / (float)w : 0.0f;
    uv[1] = h ? coord[1] / (float)h : 0.0f;
}

/* ---- validation ------------------------------------------------------------------------------ */

enum { RATE_INDEX, RATE_REMAP, RATE_COORD, RATE_UNUSED };
static const uint32_t rate_ids[LBK_RATE_KINDS] = {1114, 1115, 1116, 1117};

typedef struct lmuv_check {
    lbk_vctx *ctx;
    const uint8_t *d;
    lmuv_layout l;
    uint32_t records, prims;
    uint64_t verts, idx;
    const uint32_t *objs; /* OBJS facts (6 per object) when OBJS validated, else NULL */
    uint32_t object_count;
    lbk_rate rate;
} lmuv_check;

static uint64_t record_at(uint32_t r) { return LBK_LMUV_HEADER_SIZE + (uint64_t)LBK_LMUV_RECORD_SIZE * r; }

/* The OBJS rectangle of a record's object, when OBJS is known and the object is lightmapped. */
static const uint32_t *object_rect(const lmuv_check *c, uint32_t object)
{
    if (!c->objs || object >= c->object_count) return NULL;
    const uint32_t *f = c->objs + 6 * (size_t)object;
    return f[0] == LBK_REPRESENTATION_LIGHTMAP ? f + 2 : NULL;
}

static bool inside(double lo, double hi, uint32_t start, uint32_t extent)
{
    return lo >= (double)start && hi <= (double)start + (double)extent;
}

static void check_authored(lmuv_check *c, uint32_t r, const lbk_lmuv_object *o)
{
    const uint64_t ro = record_at(r);
    if (o->primitive_first | o->primitive_count)
        lbk_vreport(c->ctx, 1108, ro + 12, "LMUV record %u (authored) has primitive range %u+%u, must be 0", r,
                    o->primitive_first, o->primitive_count);
    if (!finite_pair(o->scale) || !finite_pair(o->offset) || !finite_pair(o->uv_min) || !finite_pair(o->uv_max) ||
        !(o->scale[0] > 0) || !(o->scale[1] > 0) || !(o->uv_min[0] <= o->uv_max[0]) || !(o->uv_min[1] <= o->uv_max[1])) {
        lbk_vreport(c->ctx, 1109, ro + 24,
                    "LMUV record %u: scale (%g, %g), offset (%g, %g), uv box (%g, %g)-(%g, %g) not finite, scale <= 0 "
                    "or box inverted",
                    r, (double)o->scale[0], (double)o->scale[1], (double)o->offset[0], (double)o->offset[1],
                    (double)o->uv_min[0], (double)o->uv_min[1], (double)o->uv_max[0], (double)o->uv_max[1]);
        return;
    }
    const uint32_t *rect = object_rect(c, o->object);
    if (!rect) return;
    double x0 = o->offset[0] + (double)o->scale[0] * o->uv_min[0], x1 = o->offset[0] + (double)o->scale[0] * o->uv_max[0];
    double y0 = o->offset[1] + (double)o->scale[1] * o->uv_min[1], y1 = o->offset[1] + (double)o->scale[1] * o->uv_max[1];
    if (!inside(x0, x1, rect[0], rect[2]) || !inside(y0, y1, rect[1], rect[3]))
        lbk_vreport(c->ctx, 1110, ro + 24,
                    "LMUV record %u: TEXCOORD_1 box maps to [%g, %g]x[%g, %g], outside object %u's rect [%u,%u %ux%u]",
                    r, x0, x1, y0, y1, o->object, rect[0], rect[1], rect[2], rect[3]);
}

/* Records (§16.2): order, OBJS cross-checks, kinds, unused fields. Returns whether the
 * primitive ranges are packed, so the primitive table can be walked. */
static bool check_records(lmuv_check *c)
{
    bool packed = true;
    uint32_t pf = 0;
    for (uint32_t r = 0; r < c->records && !c->ctx->stop; r++) {
        const uint64_t ro = record_at(r);
        lbk_lmuv_object o;
        read_object(c->d + ro, &o);
        if (lbk_rd32(c->d + ro + 20)) lbk_vreport(c->ctx, 1101, ro + 20, "LMUV record %u: reserved field is not 0", r);
        if (r > 0 && o.object <= lbk_rd32(c->d + record_at(r - 1)))
            lbk_vreport(c->ctx, 1105, ro, "LMUV record %u: object %u does not follow object %u", r, o.object,
                        lbk_rd32(c->d + record_at(r - 1)));
        if (c->objs && o.object >= c->object_count)
            lbk_vreport(c->ctx, 1105, ro, "LMUV record %u: object %u, OBJS has %u objects", r, o.object, c->object_count);
        else if (c->objs && !object_rect(c, o.object))
            lbk_vreport(c->ctx, 1106, ro, "LMUV record %u: object %u is not lightmapped", r, o.object);
        if (o.kind >= LBK_LMUV_KIND_COUNT_) {
            lbk_vreport(c->ctx, 1107, ro + 4, "LMUV record %u: kind %u is not 0..1", r, o.kind);
            packed = false;
            continue;
        }
        if (o.kind == LBK_LMUV_AUTHORED) {
            check_authored(c, r, &o);
            if (o.primitive_first | o.primitive_count) packed = false;
            continue;
        }
        lbk_check_zero(c->ctx, 1108, c->d, ro + 24, ro + LBK_LMUV_RECORD_SIZE, "LMUV generated record's authored field");
        if (o.primitive_count == 0 || o.primitive_first != pf) {
            lbk_vreport(c->ctx, 1112, ro + 12, "LMUV record %u: primitives %u+%u, the packed layout puts them at %u (>= 1)",
                        r, o.primitive_first, o.primitive_count, pf);
            packed = false;
        } else if (o.primitive_count > c->prims - pf) {
            lbk_vreport(c->ctx, 1104, ro + 16, "LMUV record %u: primitives %u+%u past the header's %u", r,
                        o.primitive_first, o.primitive_count, c->prims);
            packed = false;
        }
        if (packed) pf += o.primitive_count;
    }
    if (packed && pf != c->prims) {
        lbk_vreport(c->ctx, 1104, 4, "LMUV header has %u primitives, the records use %u", c->prims, pf);
        packed = false;
    }
    return packed;
}

typedef struct node_sort {
    const uint8_t *d;
} node_sort;

static int cmp_node(void *ctx, uint32_t a, uint32_t b)
{
    const node_sort *s = ctx;
    uint32_t na = lbk_rd32(s->d + record_at(a) + 8), nb = lbk_rd32(s->d + record_at(b) + 8);
    return na < nb ? -1 : na > nb;
}

/* Two objects cannot come from one glTF node: a node instantiates its mesh once (1111). */
static void check_nodes(lmuv_check *c)
{
    uint32_t *idx = lbk_calloc(c->ctx->allocator, 2 * (size_t)c->records, sizeof *idx);
    if (!idx) return; /* out of memory: the check is skipped, nothing else depends on it */
    for (uint32_t r = 0; r < c->records; r++) idx[r] = r;
    node_sort s = {c->d};
    lbk_sort_indices(idx, idx + c->records, c->records, cmp_node, &s);
    for (uint32_t i = 1; i < c->records && !c->ctx->stop; i++)
        if (cmp_node(&s, idx[i - 1], idx[i]) == 0)
            lbk_vreport(c->ctx, 1111, record_at(idx[i]) + 8, "LMUV records %u and %u both come from glTF node %u",
                        idx[i - 1], idx[i], lbk_rd32(c->d + record_at(idx[i]) + 8));
    lbk_dealloc(c->ctx->allocator, idx);
}

/* Primitive table: packed vertex and index ranges, counts, ascending source primitives.
 * Returns whether the ranges are trustworthy for the element checks. */
static bool check_primitives(lmuv_check *c)
{
    bool ok = true;
    uint64_t vf = 0, xf = 0;
    for (uint32_t r = 0; r < c->records && !c->ctx->stop; r++) {
        lbk_lmuv_object o;
        read_object(c->d + record_at(r), &o);
        for (uint32_t k = 0; k < o.primitive_count; k++) {
            const uint32_t p = o.primitive_first + k;
            const uint64_t po = c->l.primitives + (uint64_t)LBK_LMUV_PRIMITIVE_SIZE * p;
            lbk_lmuv_primitive q;
            read_primitive(c->d + po, &q);
            if (q.vertex_first != vf || q.index_first != xf) {
                lbk_vreport(c->ctx, 1112, po + 16,
                            "LMUV primitive %u: vertices at %llu, indices at %llu; the packed layout has %llu, %llu", p,
                            (unsigned long long)q.vertex_first, (unsigned long long)q.index_first,
                            (unsigned long long)vf, (unsigned long long)xf);
                return false;
            }
            if (q.vertex_count == 0 || q.index_count == 0 || q.index_count % 3) {
                lbk_vreport(c->ctx, 1113, po + 8, "LMUV primitive %u: %u vertices, %u indices (need >= 1, a multiple of 3)",
                            p, q.vertex_count, q.index_count);
                ok = false;
            }
            if (k > 0 && q.source_primitive <= lbk_rd32(c->d + po - LBK_LMUV_PRIMITIVE_SIZE))
                lbk_vreport(c->ctx, 1113, po, "LMUV record %u: source primitive %u does not follow %u", r,
                            q.source_primitive, lbk_rd32(c->d + po - LBK_LMUV_PRIMITIVE_SIZE));
            if (q.vertex_count > c->verts - vf || q.index_count > c->idx - xf) {
                lbk_vreport(c->ctx, 1104, po + 8, "LMUV primitive %u runs past the header's %llu vertices / %llu indices",
                            p, (unsigned long long)c->verts, (unsigned long long)c->idx);
                return false;
            }
            vf += q.vertex_count;
            xf += q.index_count;
        }
    }
    if (vf != c->verts || xf != c->idx) {
        lbk_vreport(c->ctx, 1104, 8, "LMUV header has %llu vertices and %llu indices, the primitives use %llu, %llu",
                    (unsigned long long)c->verts, (unsigned long long)c->idx, (unsigned long long)vf,
                    (unsigned long long)xf);
        return false;
    }
    return ok;
}

/* One primitive's arrays: remap, indices, coordinates inside the object's rectangle, and
 * vertices no index uses. used: vertex_count bytes of scratch. */
static void check_elements(lmuv_check *c, uint32_t p, const uint32_t *rect, uint8_t *used)
{
    lbk_lmuv_primitive q;
    read_primitive(c->d + c->l.primitives + (uint64_t)LBK_LMUV_PRIMITIVE_SIZE * p, &q);
    memset(used, 0, q.vertex_count);
    for (uint32_t i = 0; i < q.index_count; i++) {
        const uint64_t at = c->l.indices + 4 * (q.index_first + i);
        const uint32_t v = lbk_rd32(c->d + at);
        if (v < q.vertex_count) used[v] = 1;
        else if (lbk_rate_ok(&c->rate, RATE_INDEX))
            lbk_vreport(c->ctx, 1114, at, "LMUV primitive %u: index %u is %u, it has %u vertices", p, i, v, q.vertex_count);
    }
    for (uint32_t v = 0; v < q.vertex_count && !c->ctx->stop; v++) {
        const uint64_t k = q.vertex_first + v, ra = c->l.remap + 4 * k, ca = c->l.coords + 8 * k;
        const uint32_t src = lbk_rd32(c->d + ra);
        if (src >= q.source_vertex_count && lbk_rate_ok(&c->rate, RATE_REMAP))
            lbk_vreport(c->ctx, 1115, ra, "LMUV primitive %u: vertex %u comes from source vertex %u of %u", p, v, src,
                        q.source_vertex_count);
        const float xy[2] = {lbk_rdf32(c->d + ca), lbk_rdf32(c->d + ca + 4)};
        if ((!finite_pair(xy) || (rect && (!inside(xy[0], xy[0], rect[0], rect[2]) ||
                                           !inside(xy[1], xy[1], rect[1], rect[3])))) &&
            lbk_rate_ok(&c->rate, RATE_COORD))
            lbk_vreport(c->ctx, 1116, ca, "LMUV primitive %u: vertex %u at (%g, %g) is not finite or outside the rect", p,
                        v, (double)xy[0], (double)xy[1]);
        if (!used[v] && lbk_rate_ok(&c->rate, RATE_UNUSED))
            lbk_vreport(c->ctx, 1117, ra, "LMUV primitive %u: vertex %u is used by no triangle", p, v);
    }
}

static void check_all_elements(lmuv_check *c)
{
    uint32_t widest = 0;
    for (uint32_t p = 0; p < c->prims; p++) {
        uint32_t n = lbk_rd32(c->d + c->l.primitives + (uint64_t)LBK_LMUV_PRIMITIVE_SIZE * p + 8);
        if (n > widest) widest = n;
    }
    uint8_t *used = lbk_calloc(c->ctx->allocator, (size_t)widest + 1, 1); /* widest·12 <= section size */
    if (!used) return;
    for (uint32_t r = 0; r < c->records && !c->ctx->stop; r++) {
        lbk_lmuv_object o;
        read_object(c->d + record_at(r), &o);
        for (uint32_t k = 0; k < o.primitive_count && !c->ctx->stop; k++)
            check_elements(c, o.primitive_first + k, object_rect(c, o.object), used);
    }
    lbk_dealloc(c->ctx->allocator, used);
    lbk_rate_flush_ids(c->ctx, &c->rate, rate_ids, LBK_RATE_KINDS);
}

/* Every lightmapped OBJS object should have a record, or an engine cannot map it (1118). */
static void check_coverage(lmuv_check *c)
{
    uint32_t r = 0;
    for (uint32_t i = 0; i < c->object_count && !c->ctx->stop; i++) {
        while (r < c->records && lbk_rd32(c->d + record_at(r)) < i) r++;
        if (object_rect(c, i) && !(r < c->records && lbk_rd32(c->d + record_at(r)) == i))
            lbk_vreport(c->ctx, 1118, 0, "LMUV has no record for lightmapped object %u", i);
    }
}

void lbk_validate_lmuv(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_LMUV_HEADER_SIZE) {
        lbk_vreport(ctx, 1100, 0, "LMUV is %zu bytes, its header needs 32", size);
        return;
    }
    lmuv_check c;
    memset(&c, 0, sizeof c);
    c.ctx = ctx;
    c.d = d;
    c.records = lbk_rd32(d);
    c.prims = lbk_rd32(d + 4);
    c.verts = lbk_rd64(d + 8);
    c.idx = lbk_rd64(d + 16);
    lbk_rate_init(&c.rate);
    if (lbk_rd64(d + 24)) lbk_vreport(ctx, 1101, 24, "LMUV reserved header bytes are not zero");
    if (c.records == 0) lbk_vreport(ctx, 1102, 0, "LMUV record_count is 0");
    if (!layout_of(c.records, c.prims, c.verts, c.idx, &c.l) || c.l.end != size) {
        lbk_vreport(ctx, 1103, 0, "LMUV of %u records, %u primitives, %llu vertices, %llu indices does not fit %zu bytes",
                    c.records, c.prims, (unsigned long long)c.verts, (unsigned long long)c.idx, size);
        return;
    }
    if (!lbk_vctx_has_section(ctx, LBK_SECTION_OBJS))
        lbk_vreport(ctx, 1119, 0, "LMUV is present but the file has no OBJS section");
    if (ctx->objs_ok && ctx->objs_facts) {
        c.objs = ctx->objs_facts;
        c.object_count = ctx->object_count;
    }
    const uint64_t rec_end = record_at(c.records);
    lbk_check_zero(ctx, 1101, d, rec_end, c.l.primitives, "LMUV");
    lbk_check_zero(ctx, 1101, d, c.l.primitives + (uint64_t)LBK_LMUV_PRIMITIVE_SIZE * c.prims, c.l.remap, "LMUV");
    lbk_check_zero(ctx, 1101, d, c.l.remap + 4 * c.verts, c.l.indices, "LMUV");
    lbk_check_zero(ctx, 1101, d, c.l.indices + 4 * c.idx, c.l.coords, "LMUV");
    const bool packed = check_records(&c);
    if (!ctx->stop) check_nodes(&c);
    if (packed && !ctx->stop && check_primitives(&c) && !ctx->stop) check_all_elements(&c);
    if (!ctx->stop) check_coverage(&c);
}
