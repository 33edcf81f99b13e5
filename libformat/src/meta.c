/* META: build, view and validate (spec/container.md §6, spec/validation.md 300–349). */
#include "lbk/meta.h"

#include "text.h"

static bool key_valid(const uint8_t *k, size_t n)
{
    if (n < 1 || n > LBK_META_MAX_KEY) return false;
    for (size_t i = 0; i < n; i++) {
        uint8_t c = k[i];
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-')) return false;
    }
    return true;
}

typedef struct pair_sort {
    const lbk_meta_pair *pairs;
} pair_sort;

static int cmp_pairs(void *ctx, uint32_t a, uint32_t b)
{
    const lbk_meta_pair *p = ((pair_sort *)ctx)->pairs;
    return lbk_bytes_cmp((const uint8_t *)p[a].key, strlen(p[a].key), (const uint8_t *)p[b].key, strlen(p[b].key));
}

lbk_result lbk_meta_build(const lbk_meta_pair *pairs, size_t count, const lbk_allocator *allocator, void **out,
                          size_t *size)
{
    if (!out || !size || (!pairs && count)) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (count == 0 || count > UINT32_MAX / LBK_META_ENTRY_SIZE) return LBK_ERR_INVALID_ARGUMENT;
    uint64_t strings = 0;
    for (size_t i = 0; i < count; i++) {
        if (!pairs[i].key || !pairs[i].value) return LBK_ERR_INVALID_ARGUMENT;
        size_t kn = strlen(pairs[i].key), vn = strlen(pairs[i].value);
        if (!key_valid((const uint8_t *)pairs[i].key, kn) || !lbk_utf8_valid((const uint8_t *)pairs[i].value, vn))
            return LBK_ERR_INVALID_ARGUMENT;
        strings += (uint64_t)kn + vn;
        if (strings > UINT32_MAX) return LBK_ERR_LIMIT;
    }
    uint32_t *order = lbk_calloc(allocator, count * 2, sizeof *order);
    if (!order) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < count; i++) order[i] = (uint32_t)i;
    pair_sort ps = {pairs};
    lbk_sort_indices(order, order + count, count, cmp_pairs, &ps);
    for (size_t i = 1; i < count; i++)
        if (cmp_pairs(&ps, order[i - 1], order[i]) == 0) {
            lbk_dealloc(allocator, order);
            return LBK_ERR_INVALID_ARGUMENT; /* duplicate key */
        }
    uint64_t total = LBK_META_HEADER_SIZE + (uint64_t)LBK_META_ENTRY_SIZE * count + strings;
    uint8_t *b = total <= SIZE_MAX ? lbk_calloc(allocator, 1, (size_t)total) : NULL;
    if (!b) {
        lbk_dealloc(allocator, order);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    lbk_wr32(b + 0, (uint32_t)count);
    lbk_wr32(b + 4, (uint32_t)strings);
    uint8_t *blob = b + LBK_META_HEADER_SIZE + (size_t)LBK_META_ENTRY_SIZE * count;
    uint32_t at = 0;
    for (size_t i = 0; i < count; i++) {
        const lbk_meta_pair *p = &pairs[order[i]];
        uint32_t kn = (uint32_t)strlen(p->key), vn = (uint32_t)strlen(p->value);
        uint8_t *e = b + LBK_META_HEADER_SIZE + (size_t)LBK_META_ENTRY_SIZE * i;
        lbk_wr32(e + 0, at);
        lbk_wr32(e + 4, kn);
        memcpy(blob + at, p->key, kn);
        at += kn;
        lbk_wr32(e + 8, at);
        lbk_wr32(e + 12, vn);
        memcpy(blob + at, p->value, vn);
        at += vn;
    }
    lbk_dealloc(allocator, order);
    *out = b;
    *size = (size_t)total;
    return LBK_OK;
}

lbk_result lbk_meta_open(const void *data, size_t size, lbk_meta_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_META_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    uint32_t n = lbk_rd32(d), strings = lbk_rd32(d + 4);
    uint64_t need = LBK_META_HEADER_SIZE + (uint64_t)LBK_META_ENTRY_SIZE * n + strings;
    if (need > size) return LBK_ERR_TRUNCATED;
    if (need != size || lbk_rd32(d + 8) || lbk_rd32(d + 12)) return LBK_ERR_CORRUPT;
    const uint8_t *entries = d + LBK_META_HEADER_SIZE;
    for (uint32_t i = 0; i < n; i++) {
        const uint8_t *e = entries + (size_t)LBK_META_ENTRY_SIZE * i;
        if (!lbk_range_ok(lbk_rd32(e), lbk_rd32(e + 4), strings) || !lbk_range_ok(lbk_rd32(e + 8), lbk_rd32(e + 12), strings))
            return LBK_ERR_CORRUPT;
    }
    out->entries = entries;
    out->strings = entries + (size_t)LBK_META_ENTRY_SIZE * n;
    out->entry_count = n;
    out->strings_size = strings;
    return LBK_OK;
}

lbk_result lbk_meta_entry_get(const lbk_meta_view *v, uint32_t index, lbk_string *key, lbk_string *value)
{
    if (!v) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= v->entry_count) return LBK_ERR_NOT_FOUND;
    const uint8_t *e = v->entries + (size_t)LBK_META_ENTRY_SIZE * index;
    if (key) *key = (lbk_string){(const char *)v->strings + lbk_rd32(e), lbk_rd32(e + 4)};
    if (value) *value = (lbk_string){(const char *)v->strings + lbk_rd32(e + 8), lbk_rd32(e + 12)};
    return LBK_OK;
}

lbk_result lbk_meta_find(const lbk_meta_view *v, const char *key, lbk_string *value)
{
    if (!v || !key) return LBK_ERR_INVALID_ARGUMENT;
    size_t kn = strlen(key);
    for (uint32_t i = 0; i < v->entry_count; i++) {
        lbk_string k;
        lbk_meta_entry_get(v, i, &k, value);
        if (k.size == kn && !memcmp(k.data, key, kn)) return LBK_OK;
    }
    if (value) *value = (lbk_string){NULL, 0};
    return LBK_ERR_NOT_FOUND;
}

void lbk_meta_hash_hex(uint64_t hash, char out[17])
{
    static const char hex[] = "0123456789abcdef";
    for (int i = 0; i < 16; i++) out[i] = hex[(hash >> (60 - 4 * i)) & 0xf];
    out[16] = '\0';
}

/* ---- validation -------------------------------------------------------------------------- */

static bool is_digits(const uint8_t *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (s[i] < '0' || s[i] > '9') return false;
    return true;
}

/* Values of well-known keys whose form §6.2 fixes; NULL when fine. */
static const char *well_known_problem(const uint8_t *k, size_t kn, const uint8_t *v, size_t vn)
{
#define KEY_IS(lit) (kn == sizeof(lit) - 1 && !memcmp(k, lit, kn))
    if (KEY_IS(LBK_META_SCENE_HASH)) {
        if (vn != 16) return "must be 16 lowercase hex digits";
        for (size_t i = 0; i < vn; i++)
            if (!((v[i] >= '0' && v[i] <= '9') || (v[i] >= 'a' && v[i] <= 'f'))) return "must be 16 lowercase hex digits";
    } else if (KEY_IS(LBK_META_TIMESTAMP)) {
        /* YYYY-MM-DDTHH:MM:SSZ */
        if (vn != 20 || !is_digits(v, 4) || v[4] != '-' || !is_digits(v + 5, 2) || v[7] != '-' ||
            !is_digits(v + 8, 2) || v[10] != 'T' || !is_digits(v + 11, 2) || v[13] != ':' || !is_digits(v + 14, 2) ||
            v[16] != ':' || !is_digits(v + 17, 2) || v[19] != 'Z')
            return "must be YYYY-MM-DDTHH:MM:SSZ";
    } else if (KEY_IS(LBK_META_WRITER) || KEY_IS(LBK_META_WRITER_VERSION)) {
        if (vn == 0) return "must not be empty";
    }
#undef KEY_IS
    return NULL;
}

void lbk_validate_meta(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_META_HEADER_SIZE) {
        lbk_vreport(ctx, 300, 0, "META is %zu bytes, its header needs 16", size);
        return;
    }
    uint32_t n = lbk_rd32(d), strings = lbk_rd32(d + 4);
    if (lbk_rd32(d + 8) || lbk_rd32(d + 12))
        lbk_vreport(ctx, 301, 8, "META reserved header bytes are not zero");
    if (n == 0) lbk_vreport(ctx, 308, 0, "META entry_count is 0");
    uint64_t need = LBK_META_HEADER_SIZE + (uint64_t)LBK_META_ENTRY_SIZE * n + strings;
    if (need != size) {
        lbk_vreport(ctx, 302, 0, "META of %u entries and %u string bytes needs %llu bytes, section has %zu", n, strings,
                    (unsigned long long)need, size);
        return;
    }
    const uint8_t *blob = d + LBK_META_HEADER_SIZE + (size_t)LBK_META_ENTRY_SIZE * n;
    uint64_t at = 0;
    const uint8_t *prev_key = NULL;
    size_t prev_len = 0;
    int has_writer = 0;
    for (uint32_t i = 0; i < n && !ctx->stop; i++) {
        uint64_t eo = LBK_META_HEADER_SIZE + (uint64_t)LBK_META_ENTRY_SIZE * i;
        const uint8_t *e = d + eo;
        uint32_t ko = lbk_rd32(e), kn = lbk_rd32(e + 4), vo = lbk_rd32(e + 8), vn = lbk_rd32(e + 12);
        /* Packed layout: key then value, entry after entry, no gaps; this also bounds every string. */
        uint64_t key_at = at, value_at = at + kn, end = value_at + vn;
        if (ko != key_at || vo != value_at || end > strings) {
            lbk_vreport(ctx, 303, eo,
                        "META entry %u: key %u+%u, value %u+%u; the packed layout needs key at %llu, value at %llu, "
                        "within %u bytes",
                        i, ko, kn, vo, vn, (unsigned long long)key_at, (unsigned long long)value_at, strings);
            return;
        }
        at = end;
        const uint8_t *k = blob + ko, *v = blob + vo;
        if (!key_valid(k, kn)) {
            lbk_vreport(ctx, 304, eo, "META entry %u: key of %u bytes is empty, longer than 64 or not [a-z0-9._-]", i,
                        kn);
        } else {
            if (prev_key && lbk_bytes_cmp(prev_key, prev_len, k, kn) >= 0)
                lbk_vreport(ctx, 305, eo, "META entry %u: key '%.*s' does not sort after '%.*s'", i, (int)kn, k,
                            (int)prev_len, prev_key);
            prev_key = k;
            prev_len = kn;
            if (kn == 6 && !memcmp(k, LBK_META_WRITER, 6)) has_writer = 1;
        }
        if (!lbk_utf8_valid(v, vn)) {
            lbk_vreport(ctx, 306, eo + 8, "META entry %u: value is not valid UTF-8 or contains NUL", i);
        } else if (key_valid(k, kn)) {
            const char *problem = well_known_problem(k, kn, v, vn);
            if (problem) lbk_vreport(ctx, 309, eo + 8, "META '%.*s' %s", (int)kn, k, problem);
        }
    }
    if (at != strings)
        lbk_vreport(ctx, 303, 4, "META strings use %llu of %u blob bytes", (unsigned long long)at, strings);
    else if (n && !has_writer)
        lbk_vreport(ctx, 307, 0, "META has no 'writer' key");
}
