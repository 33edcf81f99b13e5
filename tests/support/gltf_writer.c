/* Tiny glTF 2.0 writer (tests/benches): see gltf_writer.h. */
#include "support/gltf_writer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

static void *grow(void *p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return p;
    size_t c = *cap ? *cap : 64;
    while (c < need) c *= 2;
    void *n = realloc(p, c * elem);
    if (!n) abort();
    *cap = c;
    return n;
}

void gw_geom_free(gw_geom *g)
{
    free(g->pos);
    free(g->idx);
    memset(g, 0, sizeof *g);
}

uint32_t gw_geom_vertex(gw_geom *g, float x, float y, float z)
{
    g->pos = grow(g->pos, &g->vertex_cap, g->vertex_count + 1, 3 * sizeof(float));
    float *p = &g->pos[3 * g->vertex_count];
    p[0] = x, p[1] = y, p[2] = z;
    return (uint32_t)g->vertex_count++;
}

void gw_geom_tri(gw_geom *g, uint32_t a, uint32_t b, uint32_t c)
{
    g->idx = grow(g->idx, &g->index_cap, g->index_count + 3, sizeof(uint32_t));
    g->idx[g->index_count++] = a;
    g->idx[g->index_count++] = b;
    g->idx[g->index_count++] = c;
}

void gw_geom_quad(gw_geom *g, const float p0[3], const float p1[3], const float p2[3], const float p3[3], int n)
{
    uint32_t base = (uint32_t)g->vertex_count;
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            float u = (float)i / n, v = (float)j / n, q[3];
            for (int k = 0; k < 3; k++)
                q[k] = (1 - u) * (1 - v) * p0[k] + u * (1 - v) * p1[k] + u * v * p2[k] + (1 - u) * v * p3[k];
            gw_geom_vertex(g, q[0], q[1], q[2]);
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = base + (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)n + 2, d = a + (uint32_t)n + 1;
            gw_geom_tri(g, a, b, c);
            gw_geom_tri(g, a, c, d);
        }
}

void gw_geom_box(gw_geom *g, const float mn[3], const float mx[3], int n, int inward)
{
    /* corners: bit 0 = x, bit 1 = y, bit 2 = z */
    float c[8][3];
    for (int i = 0; i < 8; i++) {
        c[i][0] = i & 1 ? mx[0] : mn[0];
        c[i][1] = i & 2 ? mx[1] : mn[1];
        c[i][2] = i & 4 ? mx[2] : mn[2];
    }
    /* outward-facing, counter-clockwise seen from outside */
    static const int f[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (int k = 0; k < 6; k++) {
        if (inward)
            gw_geom_quad(g, c[f[k][0]], c[f[k][3]], c[f[k][2]], c[f[k][1]], n);
        else
            gw_geom_quad(g, c[f[k][0]], c[f[k][1]], c[f[k][2]], c[f[k][3]], n);
    }
}

void gw_geom_scale(gw_geom *g, float scale)
{
    for (size_t i = 0; i < 3 * g->vertex_count; i++) g->pos[i] *= scale;
}

/* ---- the document ------------------------------------------------------------------------- */

struct gw_scene {
    cJSON *root, *nodes, *meshes, *materials, *accessors, *views, *lights, *scene_nodes;
    unsigned char *bin;
    size_t bin_size, bin_cap;
    int sky_set;
    float sky[3];
};

gw_scene *gw_create(void)
{
    gw_scene *s = calloc(1, sizeof *s);
    if (!s) abort();
    s->root = cJSON_CreateObject();
    cJSON *asset = cJSON_AddObjectToObject(s->root, "asset");
    cJSON_AddStringToObject(asset, "version", "2.0");
    cJSON_AddStringToObject(asset, "generator", "lbk tests gltf_writer");
    s->nodes = cJSON_CreateArray();
    s->meshes = cJSON_CreateArray();
    s->materials = cJSON_CreateArray();
    s->accessors = cJSON_CreateArray();
    s->views = cJSON_CreateArray();
    s->lights = cJSON_CreateArray();
    s->scene_nodes = cJSON_CreateArray();
    return s;
}

void gw_free(gw_scene *s)
{
    if (!s) return;
    cJSON_Delete(s->root);
    cJSON_Delete(s->nodes);
    cJSON_Delete(s->meshes);
    cJSON_Delete(s->materials);
    cJSON_Delete(s->accessors);
    cJSON_Delete(s->views);
    cJSON_Delete(s->lights);
    cJSON_Delete(s->scene_nodes);
    free(s->bin);
    free(s);
}

static cJSON *numbers(const double *v, int n)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < n; i++) cJSON_AddItemToArray(a, cJSON_CreateNumber(v[i]));
    return a;
}

int gw_material(gw_scene *s, const float albedo[3], const float emission[3], float strength, int double_sided)
{
    cJSON *m = cJSON_CreateObject();
    cJSON *pbr = cJSON_AddObjectToObject(m, "pbrMetallicRoughness");
    double bc[4] = {albedo[0], albedo[1], albedo[2], 1};
    cJSON_AddItemToObject(pbr, "baseColorFactor", numbers(bc, 4));
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0);
    if (emission) {
        double e[3] = {emission[0], emission[1], emission[2]};
        cJSON_AddItemToObject(m, "emissiveFactor", numbers(e, 3));
    }
    if (strength > 0) {
        cJSON *ext = cJSON_AddObjectToObject(m, "extensions");
        cJSON *es = cJSON_AddObjectToObject(ext, "KHR_materials_emissive_strength");
        cJSON_AddNumberToObject(es, "emissiveStrength", strength);
    }
    if (double_sided) cJSON_AddTrueToObject(m, "doubleSided");
    cJSON_AddItemToArray(s->materials, m);
    return cJSON_GetArraySize(s->materials) - 1;
}

/* Appends bytes (4-byte aligned) as a bufferView; returns its index. */
static int add_view(gw_scene *s, const void *data, size_t size, int target)
{
    size_t off = (s->bin_size + 3) & ~(size_t)3;
    s->bin = grow(s->bin, &s->bin_cap, off + size, 1);
    memset(s->bin + s->bin_size, 0, off - s->bin_size);
    memcpy(s->bin + off, data, size);
    s->bin_size = off + size;
    cJSON *v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", (double)off);
    cJSON_AddNumberToObject(v, "byteLength", (double)size);
    cJSON_AddNumberToObject(v, "target", target);
    cJSON_AddItemToArray(s->views, v);
    return cJSON_GetArraySize(s->views) - 1;
}

static int add_accessor(gw_scene *s, int view, int component, size_t count, const char *type)
{
    cJSON *a = cJSON_CreateObject();
    cJSON_AddNumberToObject(a, "bufferView", view);
    cJSON_AddNumberToObject(a, "componentType", component);
    cJSON_AddNumberToObject(a, "count", (double)count);
    cJSON_AddStringToObject(a, "type", type);
    cJSON_AddItemToArray(s->accessors, a);
    return cJSON_GetArraySize(s->accessors) - 1;
}

void gw_mesh(gw_scene *s, const char *name, const gw_geom *g, int material, int indexed, const double translation[3],
             const char *lighting)
{
    int pos_acc, idx_acc = -1;
    size_t nv;
    float *flat = NULL;
    const float *pos = g->pos;
    if (indexed) {
        nv = g->vertex_count;
        uint32_t *idx = malloc(g->index_count * sizeof *idx + 1);
        if (!idx) abort();
        memcpy(idx, g->idx, g->index_count * sizeof *idx);
        int iv = add_view(s, idx, g->index_count * sizeof *idx, 34963);
        free(idx);
        idx_acc = add_accessor(s, iv, 5125, g->index_count, "SCALAR");
    } else {
        nv = g->index_count;
        flat = calloc(nv * 3 + 1, sizeof *flat);
        if (!flat) abort();
        for (size_t i = 0; i < nv; i++) memcpy(&flat[3 * i], &g->pos[3 * (size_t)g->idx[i]], 3 * sizeof *flat);
        pos = flat;
    }
    int pv = add_view(s, pos, nv * 3 * sizeof *pos, 34962);
    pos_acc = add_accessor(s, pv, 5126, nv, "VEC3");
    /* min/max over the finite values (the spec requires them; NaN has no JSON spelling) */
    double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            double v = pos[3 * i + k];
            if (!isfinite(v)) continue;
            mn[k] = fmin(mn[k], v);
            mx[k] = fmax(mx[k], v);
        }
    for (int k = 0; k < 3; k++)
        if (mn[k] > mx[k]) mn[k] = mx[k] = 0;
    cJSON *acc = cJSON_GetArrayItem(s->accessors, pos_acc);
    cJSON_AddItemToObject(acc, "min", numbers(mn, 3));
    cJSON_AddItemToObject(acc, "max", numbers(mx, 3));
    free(flat);

    cJSON *prim = cJSON_CreateObject();
    cJSON *attr = cJSON_AddObjectToObject(prim, "attributes");
    cJSON_AddNumberToObject(attr, "POSITION", pos_acc);
    if (idx_acc >= 0) cJSON_AddNumberToObject(prim, "indices", idx_acc);
    cJSON_AddNumberToObject(prim, "material", material);
    cJSON_AddNumberToObject(prim, "mode", 4);
    cJSON *mesh = cJSON_CreateObject();
    cJSON_AddStringToObject(mesh, "name", name);
    cJSON *prims = cJSON_AddArrayToObject(mesh, "primitives");
    cJSON_AddItemToArray(prims, prim);
    cJSON_AddItemToArray(s->meshes, mesh);

    cJSON *node = cJSON_CreateObject();
    cJSON_AddStringToObject(node, "name", name);
    cJSON_AddNumberToObject(node, "mesh", cJSON_GetArraySize(s->meshes) - 1);
    if (translation) cJSON_AddItemToObject(node, "translation", numbers(translation, 3));
    if (lighting) {
        cJSON *ex = cJSON_AddObjectToObject(node, "extras");
        cJSON_AddStringToObject(ex, "lbk_lighting", lighting);
    }
    cJSON_AddItemToArray(s->nodes, node);
    cJSON_AddItemToArray(s->scene_nodes, cJSON_CreateNumber(cJSON_GetArraySize(s->nodes) - 1));
}

void gw_point_light(gw_scene *s, const float color[3], float intensity, const double position[3])
{
    cJSON *l = cJSON_CreateObject();
    double c[3] = {color[0], color[1], color[2]};
    cJSON_AddItemToObject(l, "color", numbers(c, 3));
    cJSON_AddNumberToObject(l, "intensity", intensity);
    cJSON_AddStringToObject(l, "type", "point");
    cJSON_AddItemToArray(s->lights, l);
    cJSON *node = cJSON_CreateObject();
    cJSON_AddStringToObject(node, "name", "light");
    cJSON_AddItemToObject(node, "translation", numbers(position, 3));
    cJSON *ext = cJSON_AddObjectToObject(node, "extensions");
    cJSON *lp = cJSON_AddObjectToObject(ext, "KHR_lights_punctual");
    cJSON_AddNumberToObject(lp, "light", cJSON_GetArraySize(s->lights) - 1);
    cJSON_AddItemToArray(s->nodes, node);
    cJSON_AddItemToArray(s->scene_nodes, cJSON_CreateNumber(cJSON_GetArraySize(s->nodes) - 1));
}

void gw_sky(gw_scene *s, const float rgb[3])
{
    s->sky_set = 1;
    memcpy(s->sky, rgb, sizeof s->sky);
}

static char *base64(const unsigned char *d, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * ((n + 2) / 3) + 1);
    if (!out) abort();
    size_t o = 0;
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

int gw_write(const gw_scene *s, const char *path)
{
    cJSON *root = cJSON_Duplicate(s->root, 1);
    cJSON *used = NULL;
    if (cJSON_GetArraySize(s->lights) > 0) {
        used = cJSON_AddArrayToObject(root, "extensionsUsed");
        cJSON_AddItemToArray(used, cJSON_CreateString("KHR_lights_punctual"));
        cJSON *ext = cJSON_AddObjectToObject(root, "extensions");
        cJSON *lp = cJSON_AddObjectToObject(ext, "KHR_lights_punctual");
        cJSON_AddItemToObject(lp, "lights", cJSON_Duplicate(s->lights, 1));
    }
    int strength = 0;
    for (int i = 0; i < cJSON_GetArraySize(s->materials); i++)
        strength |= cJSON_GetObjectItem(cJSON_GetArrayItem(s->materials, i), "extensions") != NULL;
    if (strength) {
        if (!used) used = cJSON_AddArrayToObject(root, "extensionsUsed");
        cJSON_AddItemToArray(used, cJSON_CreateString("KHR_materials_emissive_strength"));
    }
    cJSON_AddNumberToObject(root, "scene", 0);
    cJSON *scenes = cJSON_AddArrayToObject(root, "scenes");
    cJSON *sc = cJSON_CreateObject();
    cJSON_AddItemToObject(sc, "nodes", cJSON_Duplicate(s->scene_nodes, 1));
    if (s->sky_set) {
        cJSON *ex = cJSON_AddObjectToObject(sc, "extras");
        double k[3] = {s->sky[0], s->sky[1], s->sky[2]};
        cJSON_AddItemToObject(ex, "lbk_sky", numbers(k, 3));
    }
    cJSON_AddItemToArray(scenes, sc);
    cJSON_AddItemToObject(root, "nodes", cJSON_Duplicate(s->nodes, 1));
    cJSON_AddItemToObject(root, "meshes", cJSON_Duplicate(s->meshes, 1));
    cJSON_AddItemToObject(root, "materials", cJSON_Duplicate(s->materials, 1));
    cJSON_AddItemToObject(root, "accessors", cJSON_Duplicate(s->accessors, 1));
    cJSON_AddItemToObject(root, "bufferViews", cJSON_Duplicate(s->views, 1));
    cJSON *buffers = cJSON_AddArrayToObject(root, "buffers");
    cJSON *b = cJSON_CreateObject();
    size_t total = (s->bin_size + 3) & ~(size_t)3;
    unsigned char *padded = calloc(total ? total : 1, 1);
    if (!padded) abort();
    if (s->bin_size) memcpy(padded, s->bin, s->bin_size);
    char *b64 = base64(padded, total);
    free(padded);
    const char *prefix = "data:application/octet-stream;base64,";
    char *uri = malloc(strlen(prefix) + strlen(b64) + 1);
    if (!uri) abort();
    strcpy(uri, prefix);
    strcat(uri, b64);
    free(b64);
    cJSON_AddNumberToObject(b, "byteLength", (double)total);
    cJSON_AddStringToObject(b, "uri", uri);
    free(uri);
    cJSON_AddItemToArray(buffers, b);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) return -1;
    FILE *f = fopen(path, "w");
    int ok = f && fputs(text, f) >= 0;
    if (f && fclose(f)) ok = 0;
    free(text);
    return ok ? 0 : -1;
}
