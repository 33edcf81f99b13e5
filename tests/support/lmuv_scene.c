/* The LMUV test level (see lmuv_scene.h). */
#include "support/lmuv_scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

/* mesh 0, primitive 0: a 2 m square, 2×2 cells, normals +z */
static const float grid_pos[9 * 3] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 0, 2, 0, 1, 2, 0, 2, 2, 0};
static const uint32_t grid_idx[8 * 3] = {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 3, 4, 7, 3, 7, 6, 4, 5, 8, 4, 8, 7};
/* primitive 1: points */
static const float points_pos[3 * 3] = {0, 0, 3, 1, 0, 3, 2, 0, 3};
/* primitive 2: a pyramid without normals */
static const float pyr_pos[5 * 3] = {0.5f, 0.5f, 0.5f, 1.5f, 0.5f, 0.5f, 1.5f, 1.5f, 0.5f, 0.5f, 1.5f, 0.5f, 1, 1, 1.5f};
static const uint32_t pyr_idx[6 * 3] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4, 0, 2, 1, 0, 3, 2};
/* primitive 3: a vertical ribbon at y = 3 as a strip with a restart (index 3 and 4 repeated) */
static const float strip_pos[8 * 3] = {0, 3, 0, 0, 3, 1, 1, 3, 0, 1, 3, 1, 2, 3, 0, 2, 3, 1, 3, 3, 0, 3, 3, 1};
static const uint32_t strip_idx[10] = {0, 1, 2, 3, 3, 4, 4, 5, 6, 7};
static const uint32_t strip_tris[4 * 3] = {0, 1, 2, 2, 1, 3, 4, 5, 6, 6, 5, 7};
/* mesh 1: a quad at y = −3 whose TEXCOORD_1 runs backwards in u */
static const float decal_pos[4 * 3] = {0, -3, 0, 2, -3, 0, 2, -3, 2, 0, -3, 2};
static const float decal_uv1[4 * 2] = {0.9f, 0.1f, 0.1f, 0.1f, 0.1f, 0.9f, 0.9f, 0.9f};
static const uint32_t decal_idx[6] = {0, 1, 2, 0, 2, 3};

const uint32_t *lmuv_scene_triangles(uint32_t primitive, size_t *count)
{
    switch (primitive) {
    case 0: *count = 8; return grid_idx;
    case 2: *count = 6; return pyr_idx;
    case 3: *count = 4; return strip_tris;
    default: *count = 0; return NULL;
    }
}

typedef struct builder {
    unsigned char bin[4096];
    size_t size;
    cJSON *views, *accessors;
} builder;

/* A bufferView + accessor over n elements of `type` ("SCALAR", "VEC2", "VEC3"). */
static int accessor(builder *b, const void *data, size_t bytes, size_t n, int component, const char *type, int vec3_bounds)
{
    size_t at = (b->size + 3) & ~(size_t)3;
    if (at + bytes > sizeof b->bin) abort();
    memcpy(b->bin + at, data, bytes);
    b->size = at + bytes;
    cJSON *v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", (double)at);
    cJSON_AddNumberToObject(v, "byteLength", (double)bytes);
    cJSON_AddItemToArray(b->views, v);
    cJSON *a = cJSON_CreateObject();
    cJSON_AddNumberToObject(a, "bufferView", cJSON_GetArraySize(b->views) - 1);
    cJSON_AddNumberToObject(a, "componentType", component);
    cJSON_AddNumberToObject(a, "count", (double)n);
    cJSON_AddStringToObject(a, "type", type);
    if (vec3_bounds) {
        float mn[3] = {1e30f, 1e30f, 1e30f}, mx[3] = {-1e30f, -1e30f, -1e30f};
        const float *p = data;
        for (size_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++) {
                if (p[3 * i + c] < mn[c]) mn[c] = p[3 * i + c];
                if (p[3 * i + c] > mx[c]) mx[c] = p[3 * i + c];
            }
        cJSON_AddItemToObject(a, "min", cJSON_CreateFloatArray(mn, 3));
        cJSON_AddItemToObject(a, "max", cJSON_CreateFloatArray(mx, 3));
    }
    cJSON_AddItemToArray(b->accessors, a);
    return cJSON_GetArraySize(b->accessors) - 1;
}

static int positions(builder *b, const float *p, size_t n) { return accessor(b, p, n * 12, n, 5126, "VEC3", 1); }
static int indices(builder *b, const uint32_t *i, size_t n) { return accessor(b, i, n * 4, n, 5125, "SCALAR", 0); }
static int normals(builder *b, size_t n, float x, float y, float z)
{
    float v[16 * 3];
    for (size_t i = 0; i < n; i++) v[3 * i] = x, v[3 * i + 1] = y, v[3 * i + 2] = z;
    return accessor(b, v, n * 12, n, 5126, "VEC3", 0);
}

static cJSON *primitive(int mode, int pos, int nrm, int uv1, int idx)
{
    cJSON *p = cJSON_CreateObject(), *at = cJSON_AddObjectToObject(p, "attributes");
    cJSON_AddNumberToObject(at, "POSITION", pos);
    if (nrm >= 0) cJSON_AddNumberToObject(at, "NORMAL", nrm);
    if (uv1 >= 0) cJSON_AddNumberToObject(at, "TEXCOORD_1", uv1);
    if (idx >= 0) cJSON_AddNumberToObject(p, "indices", idx);
    cJSON_AddNumberToObject(p, "mode", mode);
    cJSON_AddNumberToObject(p, "material", 0);
    return p;
}

static cJSON *node(const char *name, int mesh, const float scale[3], const float translation[3])
{
    cJSON *n = cJSON_CreateObject();
    cJSON_AddStringToObject(n, "name", name);
    cJSON_AddNumberToObject(n, "mesh", mesh);
    if (scale) cJSON_AddItemToObject(n, "scale", cJSON_CreateFloatArray(scale, 3));
    if (translation) cJSON_AddItemToObject(n, "translation", cJSON_CreateFloatArray(translation, 3));
    cJSON_AddStringToObject(cJSON_AddObjectToObject(n, "extras"), "lbk_lighting", "lightmap");
    return n;
}

static char *base64(const unsigned char *d, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * ((n + 2) / 3) + 64);
    if (!out) abort();
    size_t o = (size_t)sprintf(out, "data:application/octet-stream;base64,");
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) | (i + 2 < n ? d[i + 2] : 0);
        out[o++] = tab[v >> 18 & 63];
        out[o++] = tab[v >> 12 & 63];
        out[o++] = i + 1 < n ? tab[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? tab[v & 63] : '=';
    }
    out[o] = 0;
    return out;
}

int lmuv_scene_write(const char *path)
{
    static builder b;
    memset(&b, 0, sizeof b);
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(cJSON_AddObjectToObject(root, "asset"), "version", "2.0");
    b.views = cJSON_AddArrayToObject(root, "bufferViews");
    b.accessors = cJSON_AddArrayToObject(root, "accessors");
    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    cJSON *m0 = cJSON_CreateObject(), *p0 = cJSON_AddArrayToObject(m0, "primitives");
    cJSON_AddStringToObject(m0, "name", "parts");
    cJSON_AddItemToArray(p0, primitive(4, positions(&b, grid_pos, 9), normals(&b, 9, 0, 0, 1), -1, indices(&b, grid_idx, 24)));
    cJSON_AddItemToArray(p0, primitive(0, positions(&b, points_pos, 3), -1, -1, -1));
    cJSON_AddItemToArray(p0, primitive(4, positions(&b, pyr_pos, 5), -1, -1, indices(&b, pyr_idx, 18)));
    cJSON_AddItemToArray(p0, primitive(5, positions(&b, strip_pos, 8), normals(&b, 8, 0, -1, 0), -1, indices(&b, strip_idx, 10)));
    cJSON_AddItemToArray(meshes, m0);
    cJSON *m1 = cJSON_CreateObject(), *p1 = cJSON_AddArrayToObject(m1, "primitives");
    cJSON_AddStringToObject(m1, "name", "decal");
    cJSON_AddItemToArray(p1, primitive(4, positions(&b, decal_pos, 4), normals(&b, 4, 0, -1, 0),
                                       accessor(&b, decal_uv1, sizeof decal_uv1, 4, 5126, "VEC2", 0),
                                       indices(&b, decal_idx, 6)));
    cJSON_AddItemToArray(meshes, m1);
    cJSON *nodes = cJSON_AddArrayToObject(root, "nodes");
    const float mirror[3] = {-1, 1, 1}, right[3] = {6, 0, 0};
    cJSON_AddItemToArray(nodes, node("parts", 0, NULL, NULL));
    cJSON_AddItemToArray(nodes, node("parts_mirror", 0, mirror, right));
    cJSON_AddItemToArray(nodes, node("decal", 1, NULL, NULL));
    cJSON *mat = cJSON_CreateObject(), *pbr = cJSON_AddObjectToObject(mat, "pbrMetallicRoughness");
    const float grey[4] = {0.5f, 0.5f, 0.5f, 1};
    cJSON_AddItemToObject(pbr, "baseColorFactor", cJSON_CreateFloatArray(grey, 4));
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0); /* Lambertian (glTF's default is a metal) */
    cJSON_AddBoolToObject(mat, "doubleSided", 1);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "materials"), mat);
    cJSON *sc = cJSON_CreateObject(), *sn = cJSON_AddArrayToObject(sc, "nodes");
    for (int i = 0; i < LMUV_SCENE_NODES; i++) cJSON_AddItemToArray(sn, cJSON_CreateNumber(i));
    const float sky[3] = {1, 1, 1};
    cJSON_AddItemToObject(cJSON_AddObjectToObject(sc, "extras"), "lbk_sky", cJSON_CreateFloatArray(sky, 3));
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "scenes"), sc);
    cJSON_AddNumberToObject(root, "scene", 0);
    size_t padded = (b.size + 3) & ~(size_t)3;
    char *uri = base64(b.bin, padded);
    cJSON *buf = cJSON_CreateObject();
    cJSON_AddNumberToObject(buf, "byteLength", (double)padded);
    cJSON_AddStringToObject(buf, "uri", uri);
    free(uri);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "buffers"), buf);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    FILE *f = text ? fopen(path, "w") : NULL;
    int ok = f && fputs(text, f) >= 0;
    if (f && fclose(f)) ok = 0;
    free(text);
    return ok ? 0 : -1;
}
