/* GLB builder (see glb.h). GLB layout: glTF 2.0 spec §4.4 "Binary glTF Layout". */
#include "tools/convert/glb.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/byteorder.h"
#include "tools/common/error_util.h"
#include "tools/common/file_util.h"

int tl_glb_init(tl_glb *g, const char *generator)
{
    memset(g, 0, sizeof *g);
    g->root = cJSON_CreateObject();
    cJSON *asset = g->root ? cJSON_AddObjectToObject(g->root, "asset") : NULL;
    if (!asset || !cJSON_AddStringToObject(asset, "version", "2.0") ||
        !cJSON_AddStringToObject(asset, "generator", generator)) {
        tl_glb_free(g);
        return -1;
    }
    g->buffer_views = cJSON_AddArrayToObject(g->root, "bufferViews");
    g->accessors = cJSON_AddArrayToObject(g->root, "accessors");
    if (!g->buffer_views || !g->accessors) {
        tl_glb_free(g);
        return -1;
    }
    return 0;
}

void tl_glb_free(tl_glb *g)
{
    cJSON_Delete(g->root);
    free(g->bin);
    memset(g, 0, sizeof *g);
}

/* Appends n bytes at a 4-byte aligned offset (zero padding); returns the offset or SIZE_MAX. */
static size_t bin_append(tl_glb *g, const void *data, size_t n)
{
    const size_t at = (g->bin_size + 3) & ~(size_t)3;
    if (g->failed || at < g->bin_size || n > SIZE_MAX - at || at + n > UINT32_MAX) {
        g->failed = 1; /* a GLB chunk length is a u32 */
        return SIZE_MAX;
    }
    if (at + n > g->bin_cap) {
        size_t cap = g->bin_cap ? g->bin_cap : 4096;
        while (cap < at + n) cap = cap > SIZE_MAX / 2 ? at + n : cap * 2;
        uint8_t *b = realloc(g->bin, cap);
        if (!b) {
            g->failed = 1;
            return SIZE_MAX;
        }
        g->bin = b;
        g->bin_cap = cap;
    }
    memset(g->bin + g->bin_size, 0, at - g->bin_size);
    if (n) memcpy(g->bin + at, data, n);
    g->bin_size = at + n;
    return at;
}

/* A bufferView over little-endian copies of 32-bit words, or plain bytes (word_size 1). */
static int add_view(tl_glb *g, const void *data, size_t count, size_t word_size, int target)
{
    if (g->failed || (word_size > 1 && count > SIZE_MAX / word_size)) return g->failed = 1, -1;
    const size_t n = count * word_size;
    uint8_t *le = NULL;
    const void *src = data;
    if (word_size == 4) {
        le = malloc(n ? n : 1);
        if (!le) return g->failed = 1, -1;
        const uint32_t *w = data;
        for (size_t i = 0; i < count; i++) lbk_wr32(le + 4 * i, w[i]);
        src = le;
    }
    const size_t at = bin_append(g, src, n);
    free(le);
    cJSON *v = cJSON_CreateObject();
    if (at == SIZE_MAX || !v) {
        cJSON_Delete(v);
        return g->failed = 1, -1;
    }
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", (double)at);
    cJSON_AddNumberToObject(v, "byteLength", (double)n);
    if (target) cJSON_AddNumberToObject(v, "target", target);
    cJSON_AddItemToArray(g->buffer_views, v);
    return cJSON_GetArraySize(g->buffer_views) - 1;
}

static const char *type_name(int components)
{
    static const char *const names[5] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    return components >= 1 && components <= 4 ? names[components] : "SCALAR";
}

static int add_accessor(tl_glb *g, int view, int component_type, size_t count, int components, int normalized,
                        const float *mn, const float *mx)
{
    cJSON *a = view >= 0 && !g->failed ? cJSON_CreateObject() : NULL;
    if (!a) return g->failed = 1, -1;
    cJSON_AddNumberToObject(a, "bufferView", view);
    cJSON_AddNumberToObject(a, "componentType", component_type);
    if (normalized) cJSON_AddBoolToObject(a, "normalized", 1);
    cJSON_AddNumberToObject(a, "count", (double)count);
    cJSON_AddStringToObject(a, "type", type_name(components));
    if (mn && mx) {
        cJSON_AddItemToObject(a, "min", cJSON_CreateFloatArray(mn, components));
        cJSON_AddItemToObject(a, "max", cJSON_CreateFloatArray(mx, components));
    }
    cJSON_AddItemToArray(g->accessors, a);
    return cJSON_GetArraySize(g->accessors) - 1;
}

int tl_glb_accessor_f32(tl_glb *g, const float *data, size_t count, int components, int target, int min_max)
{
    if (count == 0 || components < 1 || components > 4) return g->failed = 1, -1;
    float mn[4] = {FLT_MAX, FLT_MAX, FLT_MAX, FLT_MAX}, mx[4] = {-FLT_MAX, -FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (size_t i = 0; min_max && i < count; i++)
        for (int c = 0; c < components; c++) {
            const float v = data[i * (size_t)components + (size_t)c];
            if (v < mn[c]) mn[c] = v;
            if (v > mx[c]) mx[c] = v;
        }
    const int view = add_view(g, data, count * (size_t)components, 4, target);
    return add_accessor(g, view, TL_GLTF_FLOAT, count, components, 0, min_max ? mn : NULL, min_max ? mx : NULL);
}

int tl_glb_accessor_u32(tl_glb *g, const uint32_t *data, size_t count, int target)
{
    if (count == 0) return g->failed = 1, -1;
    return add_accessor(g, add_view(g, data, count, 4, target), TL_GLTF_UNSIGNED_INT, count, 1, 0, NULL, NULL);
}

int tl_glb_accessor_unorm8(tl_glb *g, const uint8_t *data, size_t count)
{
    if (count == 0) return g->failed = 1, -1;
    return add_accessor(g, add_view(g, data, count, 1, 0), TL_GLTF_UNSIGNED_BYTE, count, 1, 1, NULL, NULL);
}

int tl_glb_write(tl_glb *g, const char *path, char err[TL_ERR_LEN])
{
    if (g->failed) return tl_fail(err, -1, "out of memory while building the glTF");
    if (g->bin_size) { /* a buffer needs byteLength >= 1 */
        cJSON *buffers = cJSON_AddArrayToObject(g->root, "buffers"), *b = cJSON_CreateObject();
        if (!buffers || !b) {
            cJSON_Delete(b);
            return tl_fail(err, -1, "out of memory");
        }
        cJSON_AddNumberToObject(b, "byteLength", (double)g->bin_size);
        cJSON_AddItemToArray(buffers, b);
    }
    char *json = cJSON_PrintUnformatted(g->root);
    if (!json) return tl_fail(err, -1, "out of memory");
    const size_t jn = strlen(json), jpad = (jn + 3) & ~(size_t)3, bpad = (g->bin_size + 3) & ~(size_t)3;
    const size_t total = 12 + 8 + jpad + (g->bin_size ? 8 + bpad : 0);
    uint8_t *f = total <= UINT32_MAX ? calloc(total, 1) : NULL;
    if (!f) {
        free(json);
        return tl_fail(err, -1, total > UINT32_MAX ? "the glTF exceeds the 4 GiB GLB limit" : "out of memory");
    }
    lbk_wr32(f, 0x46546C67u); /* "glTF" */
    lbk_wr32(f + 4, 2);
    lbk_wr32(f + 8, (uint32_t)total);
    lbk_wr32(f + 12, (uint32_t)jpad);
    lbk_wr32(f + 16, 0x4E4F534Au); /* "JSON" */
    memcpy(f + 20, json, jn);
    memset(f + 20 + jn, ' ', jpad - jn);
    free(json);
    if (g->bin_size) {
        uint8_t *c = f + 20 + jpad;
        lbk_wr32(c, (uint32_t)bpad);
        lbk_wr32(c + 4, 0x004E4942u); /* "BIN\0" */
        memcpy(c + 8, g->bin, g->bin_size);
    }
    int rc = tl_write_file_atomic(path, f, total, err);
    free(f);
    return rc;
}
