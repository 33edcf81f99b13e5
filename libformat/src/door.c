/* DOOR section: builder, checker (validator IDs 900–999 and the view), view. spec/container.md §13. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "dls_format.h"
#include "lbk/door.h"
#include "text.h"

/* What the cross-checks need to know about the DLS sets. */
typedef struct door_facts {
    uint32_t nsets;
    const uint8_t *kinds;
    const uint32_t *member_offset; /* nsets + 1 */
    const uint32_t *members;
} door_facts;

typedef struct door_layout {
    uint64_t elements, states, state_members, strings;
    uint64_t off_elements, off_states, off_members, off_strings, size;
} door_layout;

static bool door_layout_compute(const uint8_t *h, door_layout *l)
{
    l->elements = lbk_rd32(h + DOOR_H_ELEMENT_COUNT);
    l->states = lbk_rd32(h + DOOR_H_STATE_COUNT);
    l->state_members = lbk_rd32(h + DOOR_H_STATE_MEMBER_COUNT);
    l->strings = lbk_rd64(h + DOOR_H_STRING_BYTES);
    uint64_t at = DOOR_HEADER_SIZE;
    l->off_elements = at;
    at += l->elements * DOOR_ELEMENT_SIZE;
    l->off_states = lbk_align_up(at, 16);
    at = l->off_states + l->states * DOOR_STATE_SIZE;
    l->off_members = lbk_align_up(at, 16);
    at = l->off_members + l->state_members * 4;
    l->off_strings = lbk_align_up(at, 16);
    if (l->strings > UINT64_MAX - 32 - l->off_strings) return false;
    l->size = lbk_align_up(l->off_strings + l->strings, 16);
    return true;
}

typedef struct door_chk {
    lbk_vctx *ctx;
    const lbk_allocator *alloc;
    const uint8_t *d;
    uint64_t size;
    door_layout L;
    uint32_t errors;
    bool oom;
    uint16_t reported[100];
} door_chk;

static void rep(door_chk *c, uint32_t id, uint64_t off, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void rep(door_chk *c, uint32_t id, uint64_t off, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    lbk_vreport_capped(c->ctx, &c->errors, c->reported, 900, 16, id, off, fmt, ap);
    va_end(ap);
}

static const uint8_t *element(const door_chk *c, uint64_t i) { return c->d + c->L.off_elements + i * DOOR_ELEMENT_SIZE; }
static const uint8_t *state(const door_chk *c, uint64_t i) { return c->d + c->L.off_states + i * DOOR_STATE_SIZE; }

typedef struct name_key {
    const uint8_t *p;
    uint32_t len, index;
} name_key;

static int cmp_name(const void *a, const void *b)
{
    const name_key *x = a, *y = b;
    int r = lbk_bytes_cmp(x->p, x->len, y->p, y->len);
    return r ? r : (x->index < y->index ? -1 : x->index > y->index);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static bool obb_ok(const uint8_t *e)
{
    float v[15];
    for (int i = 0; i < 15; i++) {
        v[i] = lbk_rdf32(e + DOOR_E_CENTRE + 4 * i);
        if (!isfinite(v[i])) return false;
    }
    const float *ax = v + 3, *half = v + 12;
    for (int i = 0; i < 3; i++) {
        if (half[i] < 0.0f) return false;
        for (int j = 0; j < 3; j++) {
            float dot = ax[3 * i] * ax[3 * j] + ax[3 * i + 1] * ax[3 * j + 1] + ax[3 * i + 2] * ax[3 * j + 2];
            if (fabsf(dot - (i == j ? 1.0f : 0.0f)) > 1e-3f) return false;
        }
    }
    return true;
}

/* Structural rules; false when the layout itself is unusable. */
static bool check_structure(door_chk *c)
{
    if (c->size < DOOR_HEADER_SIZE) {
        rep(c, 900, 0, "DOOR is %llu bytes, shorter than its 32-byte header", (unsigned long long)c->size);
        return false;
    }
    if (!door_layout_compute(c->d, &c->L) || c->L.size != c->size) {
        rep(c, 901, 0, "DOOR is %llu bytes but its header counts imply %llu", (unsigned long long)c->size,
            (unsigned long long)c->L.size);
        return false;
    }
    if (lbk_rd32(c->d + DOOR_H_RESERVED0) || lbk_rd64(c->d + DOOR_H_RESERVED1))
        rep(c, 902, DOOR_H_RESERVED0, "DOOR header reserved fields are not zero");
    const uint64_t gaps[3][2] = {{c->L.off_elements + c->L.elements * DOOR_ELEMENT_SIZE, c->L.off_states},
                                 {c->L.off_states + c->L.states * DOOR_STATE_SIZE, c->L.off_members},
                                 {c->L.off_members + c->L.state_members * 4, c->L.off_strings}};
    for (int g = 0; g < 3; g++)
        for (uint64_t p = gaps[g][0]; p < gaps[g][1]; p++)
            if (c->d[p]) { rep(c, 902, p, "padding byte at %llu is not zero", (unsigned long long)p); break; }
    for (uint64_t p = c->L.off_strings + c->L.strings; p < c->L.size; p++)
        if (c->d[p]) { rep(c, 902, p, "padding byte at %llu is not zero", (unsigned long long)p); break; }
    if (c->L.elements == 0) rep(c, 926, DOOR_H_ELEMENT_COUNT, "DOOR has no elements");

    const uint8_t *blob = c->d + c->L.off_strings;
    for (uint64_t i = 0; i < c->L.elements; i++) {
        const uint8_t *e = element(c, i);
        uint64_t eo = c->L.off_elements + i * DOOR_ELEMENT_SIZE;
        uint32_t off = lbk_rd32(e + DOOR_E_NAME_OFF), len = lbk_rd32(e + DOOR_E_NAME_LEN);
        if (!lbk_dls_string_ok(blob, c->L.strings, off, len))
            rep(c, 910, eo, "door %llu name (offset %u, length %u) is empty, outside the blob or not UTF-8",
                (unsigned long long)i, off, len);
        if (!obb_ok(e))
            rep(c, 912, eo + DOOR_E_CENTRE, "door %llu OBB is not finite, has a negative half extent or non-orthonormal axes",
                (unsigned long long)i);
        if (lbk_rd32(e + DOOR_E_RESERVED)) rep(c, 902, eo + DOOR_E_RESERVED, "door %llu reserved field is not zero", (unsigned long long)i);
    }
    name_key *keys = lbk_calloc(c->alloc, c->L.elements ? c->L.elements : 1, sizeof *keys);
    if (!keys) { c->oom = true; return false; }
    uint64_t nk = 0;
    for (uint64_t i = 0; i < c->L.elements; i++) {
        const uint8_t *e = element(c, i);
        uint32_t off = lbk_rd32(e + DOOR_E_NAME_OFF), len = lbk_rd32(e + DOOR_E_NAME_LEN);
        if (lbk_range_ok(off, len, c->L.strings)) keys[nk++] = (name_key){blob + off, len, (uint32_t)i};
    }
    qsort(keys, nk, sizeof *keys, cmp_name);
    for (uint64_t i = 1; i < nk; i++)
        if (lbk_bytes_cmp(keys[i].p, keys[i].len, keys[i - 1].p, keys[i - 1].len) == 0)
            rep(c, 911, c->L.off_elements + (uint64_t)keys[i].index * DOOR_ELEMENT_SIZE, "doors %u and %u have the same name",
                keys[i - 1].index, keys[i].index);
    lbk_dealloc(c->alloc, keys);

    uint64_t msum = 0;
    for (uint64_t s = 0; s < c->L.states; s++) {
        const uint8_t *st = state(c, s);
        uint64_t so = c->L.off_states + s * DOOR_STATE_SIZE;
        uint32_t mf = lbk_rd32(st + DOOR_S_MEMBER_FIRST), mc = lbk_rd32(st + DOOR_S_MEMBER_COUNT);
        if (lbk_rd32(st + DOOR_S_RESERVED)) rep(c, 902, so + DOOR_S_RESERVED, "state %llu reserved field is not zero", (unsigned long long)s);
        if (mf != msum || mc == 0 || msum + mc > c->L.state_members) {
            rep(c, 920, so, "state %llu doors [%u, +%u) differ from the packed layout (first %llu, at least one)",
                (unsigned long long)s, mf, mc, (unsigned long long)msum);
            return false;
        }
        for (uint32_t j = 0; j < mc; j++) {
            const uint8_t *m = c->d + c->L.off_members + 4ull * (mf + j);
            uint32_t door = lbk_rd32(m);
            if (door >= c->L.elements || (j && door <= lbk_rd32(m - 4))) {
                rep(c, 921, c->L.off_members + 4ull * (mf + j), "state %llu door %u is %u: out of range or not ascending",
                    (unsigned long long)s, j, door);
                break;
            }
        }
        msum += mc;
    }
    if (msum != c->L.state_members) {
        rep(c, 920, DOOR_H_STATE_MEMBER_COUNT, "header declares %llu state doors, the states use %llu",
            (unsigned long long)c->L.state_members, (unsigned long long)msum);
        return false;
    }
    return true;
}

static bool facts_has_member(const door_facts *f, uint32_t set, uint32_t member)
{
    for (uint32_t q = f->member_offset[set]; q < f->member_offset[set + 1]; q++)
        if (f->members[q] == member) return true;
    return false;
}

static void check_sets(door_chk *c, const door_facts *f)
{
    uint64_t nref = 2 * c->L.elements + c->L.states;
    uint64_t *refs = lbk_alloc(c->alloc, (nref ? nref : 1) * sizeof *refs);
    uint8_t *referenced = lbk_calloc(c->alloc, f->nsets ? f->nsets : 1, 1);
    if (!refs || !referenced) {
        lbk_dealloc(c->alloc, refs);
        lbk_dealloc(c->alloc, referenced);
        c->oom = true;
        return;
    }
    uint64_t n = 0;
    for (uint64_t i = 0; i < c->L.elements; i++) {
        const uint8_t *e = element(c, i);
        uint64_t eo = c->L.off_elements + i * DOOR_ELEMENT_SIZE;
        uint32_t open = lbk_rd32(e + DOOR_E_OPEN_SET), closed = lbk_rd32(e + DOOR_E_CLOSED_SET);
        if (open >= f->nsets || f->kinds[open] != LBK_DLS_KIND_DOOR_OPEN)
            rep(c, 913, eo + DOOR_E_OPEN_SET, "door %llu open set %u is not a door-open set of the %u DLS sets",
                (unsigned long long)i, open, f->nsets);
        else {
            refs[n++] = (uint64_t)open << 32 | i;
            referenced[open] = 1;
        }
        if (closed != LBK_DLS_NO_SET) {
            if (closed >= f->nsets || f->kinds[closed] != LBK_DLS_KIND_DOOR_CLOSED)
                rep(c, 914, eo + DOOR_E_CLOSED_SET, "door %llu closed set %u is neither 0xFFFFFFFF nor a door-closed set",
                    (unsigned long long)i, closed);
            else {
                refs[n++] = (uint64_t)closed << 32 | i;
                referenced[closed] = 1;
            }
        }
    }
    qsort(refs, n, sizeof *refs, cmp_u64);
    for (uint64_t i = 1; i < n; i++)
        if (refs[i] >> 32 == refs[i - 1] >> 32)
            rep(c, 915, c->L.off_elements + (refs[i] & 0xFFFFFFFFu) * DOOR_ELEMENT_SIZE,
                "DLS set %u belongs to doors %u and %u", (uint32_t)(refs[i] >> 32), (uint32_t)(refs[i - 1] & 0xFFFFFFFFu),
                (uint32_t)(refs[i] & 0xFFFFFFFFu));
    n = 0;
    for (uint64_t s = 0; s < c->L.states; s++) {
        const uint8_t *st = state(c, s);
        uint64_t so = c->L.off_states + s * DOOR_STATE_SIZE;
        uint32_t set = lbk_rd32(st + DOOR_S_SET);
        if (set >= f->nsets || f->kinds[set] != LBK_DLS_KIND_COMBINATION) {
            rep(c, 922, so + DOOR_S_SET, "state %llu set %u is not a combination set", (unsigned long long)s, set);
            continue;
        }
        refs[n++] = (uint64_t)set << 32 | s;
        uint32_t mf = lbk_rd32(st + DOOR_S_MEMBER_FIRST), mc = lbk_rd32(st + DOOR_S_MEMBER_COUNT);
        for (uint32_t j = 0; j < mc; j++) {
            uint32_t door = lbk_rd32(c->d + c->L.off_members + 4ull * (mf + j));
            if (door >= c->L.elements) continue;
            uint32_t open = lbk_rd32(element(c, door) + DOOR_E_OPEN_SET);
            if (open >= f->nsets || !facts_has_member(f, set, open)) {
                rep(c, 923, so, "state %llu lists door %u but combination set %u does not contain its open set %u",
                    (unsigned long long)s, door, set, open);
                break;
            }
        }
    }
    qsort(refs, n, sizeof *refs, cmp_u64);
    for (uint64_t i = 1; i < n; i++)
        if (refs[i] >> 32 == refs[i - 1] >> 32)
            rep(c, 924, c->L.off_states + (refs[i] & 0xFFFFFFFFu) * DOOR_STATE_SIZE, "states %u and %u share combination set %u",
                (uint32_t)(refs[i - 1] & 0xFFFFFFFFu), (uint32_t)(refs[i] & 0xFFFFFFFFu), (uint32_t)(refs[i] >> 32));
    for (uint32_t s = 0; s < f->nsets; s++)
        if ((f->kinds[s] == LBK_DLS_KIND_DOOR_OPEN || f->kinds[s] == LBK_DLS_KIND_DOOR_CLOSED) && !referenced[s]) {
            rep(c, 925, 0, "DLS set %u is a door set but no door names it", s);
            break;
        }
    lbk_dealloc(c->alloc, refs);
    lbk_dealloc(c->alloc, referenced);
}

void lbk_validate_door(lbk_vctx *ctx, const uint8_t *data, size_t size)
{
    door_chk c;
    memset(&c, 0, sizeof c);
    c.ctx = ctx;
    c.alloc = ctx->allocator;
    c.d = data;
    c.size = size;
    bool ok = check_structure(&c);
    if (ok && !c.oom && !ctx->stop) {
        if (ctx->dls_ok && ctx->dls_facts) {
            door_facts f = {ctx->dls_set_count, ctx->dls_set_kind, ctx->dls_member_offset, ctx->dls_members};
            check_sets(&c, &f);
        } else if (!lbk_vctx_has_section(ctx, LBK_SECTION_DLS)) {
            rep(&c, 903, 0, "DOOR is present but there is no DLS section holding the doors' light");
        }
    }
    if (c.oom) lbk_vreport(ctx, 901, 0, "out of memory while checking the DOOR section");
}

/* ---- view ---------------------------------------------------------------------------------- */

struct lbk_door_view {
    lbk_allocator alloc_copy;
    const lbk_allocator *alloc;
    const uint8_t *d;
    uint64_t size;
    door_layout L;
};

lbk_result lbk_door_open(const void *data, size_t size, const lbk_allocator *allocator, lbk_door_view **out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    door_chk c;
    memset(&c, 0, sizeof c);
    c.alloc = allocator;
    c.d = data;
    c.size = size;
    bool ok = check_structure(&c);
    if (c.oom) return LBK_ERR_OUT_OF_MEMORY;
    if (!ok || c.errors) return size < DOOR_HEADER_SIZE ? LBK_ERR_TRUNCATED : LBK_ERR_CORRUPT;
    lbk_door_view *v = lbk_calloc(allocator, 1, sizeof *v);
    if (!v) return LBK_ERR_OUT_OF_MEMORY;
    if (allocator) v->alloc_copy = *allocator;
    v->alloc = allocator ? &v->alloc_copy : NULL;
    v->d = data;
    v->size = size;
    v->L = c.L;
    *out = v;
    return LBK_OK;
}

void lbk_door_close(lbk_door_view *view)
{
    if (view) lbk_dealloc(view->alloc, view);
}

lbk_result lbk_door_check_dls(const lbk_door_view *doors, const lbk_dls_view *dls)
{
    if (!doors || !dls) return LBK_ERR_INVALID_ARGUMENT;
    uint32_t nsets = lbk_dls_set_count(dls);
    uint64_t nmem = 0;
    for (uint32_t s = 0; s < nsets; s++) {
        lbk_dls_set_info info;
        lbk_dls_set_get(dls, s, &info);
        nmem += info.member_count;
    }
    uint8_t *kinds = lbk_alloc(doors->alloc, nsets ? nsets : 1);
    uint32_t *moff = lbk_alloc(doors->alloc, ((size_t)nsets + 1) * sizeof *moff);
    uint32_t *mem = lbk_alloc(doors->alloc, (nmem ? nmem : 1) * sizeof *mem);
    lbk_result r = LBK_OK;
    if (!kinds || !moff || !mem) {
        r = LBK_ERR_OUT_OF_MEMORY;
        goto out;
    }
    uint32_t at = 0;
    for (uint32_t s = 0; s < nsets; s++) {
        lbk_dls_set_info info;
        lbk_dls_set_get(dls, s, &info);
        kinds[s] = (uint8_t)info.kind;
        moff[s] = at;
        for (uint32_t j = 0; j < info.member_count; j++) lbk_dls_set_member_get(dls, s, j, &mem[at++]);
    }
    moff[nsets] = at;
    door_chk c;
    memset(&c, 0, sizeof c);
    c.alloc = doors->alloc;
    c.d = doors->d;
    c.size = doors->size;
    c.L = doors->L;
    door_facts f = {nsets, kinds, moff, mem};
    check_sets(&c, &f);
    r = c.oom ? LBK_ERR_OUT_OF_MEMORY : c.errors ? LBK_ERR_CORRUPT : LBK_OK;
out:
    lbk_dealloc(doors->alloc, kinds);
    lbk_dealloc(doors->alloc, moff);
    lbk_dealloc(doors->alloc, mem);
    return r;
}

uint32_t lbk_door_count(const lbk_door_view *view) { return view ? (uint32_t)view->L.elements : 0; }
uint32_t lbk_door_state_count(const lbk_door_view *view) { return view ? (uint32_t)view->L.states : 0; }

lbk_result lbk_door_get(const lbk_door_view *view, uint32_t door, lbk_door_info *out)
{
    if (!view || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (door >= view->L.elements) return LBK_ERR_NOT_FOUND;
    const uint8_t *e = view->d + view->L.off_elements + (uint64_t)door * DOOR_ELEMENT_SIZE;
    out->name = (const char *)view->d + view->L.off_strings + lbk_rd32(e + DOOR_E_NAME_OFF);
    out->name_length = lbk_rd32(e + DOOR_E_NAME_LEN);
    for (int i = 0; i < 3; i++) {
        out->centre[i] = lbk_rdf32(e + DOOR_E_CENTRE + 4 * i);
        out->half_extents[i] = lbk_rdf32(e + DOOR_E_HALF + 4 * i);
        for (int j = 0; j < 3; j++) out->axes[i][j] = lbk_rdf32(e + DOOR_E_AXES + 12 * i + 4 * j);
    }
    out->open_set = lbk_rd32(e + DOOR_E_OPEN_SET);
    out->closed_set = lbk_rd32(e + DOOR_E_CLOSED_SET);
    return LBK_OK;
}

lbk_result lbk_door_state_get(const lbk_door_view *view, uint32_t st, uint32_t *door_count, uint32_t *set)
{
    if (!view || !door_count || !set) return LBK_ERR_INVALID_ARGUMENT;
    if (st >= view->L.states) return LBK_ERR_NOT_FOUND;
    const uint8_t *s = view->d + view->L.off_states + (uint64_t)st * DOOR_STATE_SIZE;
    *door_count = lbk_rd32(s + DOOR_S_MEMBER_COUNT);
    *set = lbk_rd32(s + DOOR_S_SET);
    return LBK_OK;
}

lbk_result lbk_door_state_door_get(const lbk_door_view *view, uint32_t st, uint32_t i, uint32_t *door)
{
    if (!view || !door) return LBK_ERR_INVALID_ARGUMENT;
    if (st >= view->L.states) return LBK_ERR_NOT_FOUND;
    const uint8_t *s = view->d + view->L.off_states + (uint64_t)st * DOOR_STATE_SIZE;
    if (i >= lbk_rd32(s + DOOR_S_MEMBER_COUNT)) return LBK_ERR_NOT_FOUND;
    *door = lbk_rd32(view->d + view->L.off_members + 4ull * (lbk_rd32(s + DOOR_S_MEMBER_FIRST) + i));
    return LBK_OK;
}

/* ---- builder ------------------------------------------------------------------------------- */

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

lbk_result lbk_door_build(const lbk_door_build_desc *caller_desc, const lbk_allocator *a, void **out,
                          size_t *out_size)
{
    if (!caller_desc || !out || !out_size) return LBK_ERR_INVALID_ARGUMENT;
    lbk_door_build_desc in;
    lbk_result rc = LBK_SIZED_IN(&in, caller_desc, lbk_door_build_desc, states);
    if (rc != LBK_OK) return rc;
    const lbk_door_build_desc *desc = &in;
    if (!desc->door_count || !desc->doors || (desc->state_count && !desc->states)) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *out_size = 0;
    uint64_t strings = 0, members = 0;
    for (uint32_t i = 0; i < desc->door_count; i++) {
        if (!desc->doors[i].name) return LBK_ERR_INVALID_ARGUMENT;
        strings += strlen(desc->doors[i].name);
    }
    for (uint32_t s = 0; s < desc->state_count; s++) {
        if (!desc->states[s].door_count || !desc->states[s].doors) return LBK_ERR_INVALID_ARGUMENT;
        members += desc->states[s].door_count;
    }
    if (strings > UINT32_MAX || members > UINT32_MAX) return LBK_ERR_LIMIT;
    uint8_t hdr[DOOR_HEADER_SIZE] = {0};
    lbk_wr32(hdr + DOOR_H_ELEMENT_COUNT, desc->door_count);
    lbk_wr32(hdr + DOOR_H_STATE_COUNT, desc->state_count);
    lbk_wr32(hdr + DOOR_H_STATE_MEMBER_COUNT, (uint32_t)members);
    lbk_wr64(hdr + DOOR_H_STRING_BYTES, strings);
    door_layout L;
    door_layout_compute(hdr, &L);
    if (L.size > SIZE_MAX) return LBK_ERR_LIMIT;
    uint8_t *b = lbk_calloc(a, 1, (size_t)L.size);
    if (!b) return LBK_ERR_OUT_OF_MEMORY;
    memcpy(b, hdr, sizeof hdr);
    uint32_t at = 0;
    for (uint32_t i = 0; i < desc->door_count; i++) {
        const lbk_door_desc *d = &desc->doors[i];
        uint8_t *e = b + L.off_elements + (uint64_t)i * DOOR_ELEMENT_SIZE;
        size_t n = strlen(d->name);
        lbk_wr32(e + DOOR_E_NAME_OFF, at);
        lbk_wr32(e + DOOR_E_NAME_LEN, (uint32_t)n);
        memcpy(b + L.off_strings + at, d->name, n);
        at += (uint32_t)n;
        for (int q = 0; q < 3; q++) {
            lbk_wrf32(e + DOOR_E_CENTRE + 4 * q, d->centre[q]);
            lbk_wrf32(e + DOOR_E_HALF + 4 * q, d->half_extents[q]);
            for (int j = 0; j < 3; j++) lbk_wrf32(e + DOOR_E_AXES + 12 * q + 4 * j, d->axes[q][j]);
        }
        lbk_wr32(e + DOOR_E_OPEN_SET, d->open_set);
        lbk_wr32(e + DOOR_E_CLOSED_SET, d->closed_set);
    }
    uint32_t mat = 0;
    for (uint32_t s = 0; s < desc->state_count; s++) {
        const lbk_door_state_desc *sd = &desc->states[s];
        uint8_t *st = b + L.off_states + (uint64_t)s * DOOR_STATE_SIZE;
        lbk_wr32(st + DOOR_S_MEMBER_FIRST, mat);
        lbk_wr32(st + DOOR_S_MEMBER_COUNT, sd->door_count);
        lbk_wr32(st + DOOR_S_SET, sd->set);
        uint8_t *m = b + L.off_members + 4ull * mat;
        uint32_t *tmp = lbk_alloc(a, sd->door_count * sizeof *tmp);
        if (!tmp) {
            lbk_dealloc(a, b);
            return LBK_ERR_OUT_OF_MEMORY;
        }
        memcpy(tmp, sd->doors, sd->door_count * sizeof *tmp);
        qsort(tmp, sd->door_count, sizeof *tmp, cmp_u32);
        for (uint32_t j = 0; j < sd->door_count; j++) lbk_wr32(m + 4 * j, tmp[j]);
        lbk_dealloc(a, tmp);
        mat += sd->door_count;
    }
    /* The output must pass its own structural rules (names, OBBs, state doors). */
    door_chk c;
    memset(&c, 0, sizeof c);
    c.alloc = a;
    c.d = b;
    c.size = L.size;
    bool ok = check_structure(&c);
    if (c.oom || !ok || c.errors) {
        lbk_dealloc(a, b);
        return c.oom ? LBK_ERR_OUT_OF_MEMORY : LBK_ERR_INVALID_ARGUMENT;
    }
    *out = b;
    *out_size = (size_t)L.size;
    return LBK_OK;
}
