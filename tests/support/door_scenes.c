#include "tests/support/door_scenes.h"
#include "tests/support/scenes_dir.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

static int fail(char *err, size_t n, const char *msg)
{
    snprintf(err, n, "%s", msg);
    return 1;
}

static unsigned char *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *d = n > 0 ? malloc((size_t)n) : NULL;
    if (d && fread(d, 1, (size_t)n, f) != (size_t)n) {
        free(d);
        d = NULL;
    }
    fclose(f);
    *size = d ? (size_t)n : 0;
    return d;
}

static uint32_t rd32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static char *base64(const unsigned char *d, size_t n)
{
    static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char *prefix = "data:application/octet-stream;base64,";
    size_t pl = strlen(prefix);
    char *o = malloc(pl + 4 * ((n + 2) / 3) + 1);
    if (!o) return NULL;
    memcpy(o, prefix, pl);
    char *w = o + pl;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) | (i + 2 < n ? d[i + 2] : 0);
        *w++ = t[v >> 18 & 63];
        *w++ = t[v >> 12 & 63];
        *w++ = i + 1 < n ? t[v >> 6 & 63] : '=';
        *w++ = i + 2 < n ? t[v & 63] : '=';
    }
    *w = 0;
    return o;
}

static cJSON *num3(double a, double b, double c)
{
    double v[3] = {a, b, c};
    return cJSON_CreateDoubleArray(v, 3);
}

static void add_view(cJSON *views, size_t offset, size_t length)
{
    cJSON *v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", (double)offset);
    cJSON_AddNumberToObject(v, "byteLength", (double)length);
    cJSON_AddItemToArray(views, v);
}

static void add_accessor(cJSON *acc, int view, int ctype, size_t count, const char *type, const float *mn,
                         const float *mx)
{
    cJSON *a = cJSON_CreateObject();
    cJSON_AddNumberToObject(a, "bufferView", view);
    cJSON_AddNumberToObject(a, "componentType", ctype);
    cJSON_AddNumberToObject(a, "count", (double)count);
    cJSON_AddStringToObject(a, "type", type);
    if (mn) cJSON_AddItemToObject(a, "min", num3(mn[0], mn[1], mn[2]));
    if (mx) cJSON_AddItemToObject(a, "max", num3(mx[0], mx[1], mx[2]));
    cJSON_AddItemToArray(acc, a);
}

static cJSON *mesh_prim(int pos, int nrm, int uv, int idx, int material)
{
    cJSON *m = cJSON_CreateObject(), *prims = cJSON_AddArrayToObject(m, "primitives"), *p = cJSON_CreateObject();
    cJSON *at = cJSON_AddObjectToObject(p, "attributes");
    cJSON_AddNumberToObject(at, "POSITION", pos);
    cJSON_AddNumberToObject(at, "NORMAL", nrm);
    if (uv >= 0) cJSON_AddNumberToObject(at, "TEXCOORD_0", uv);
    cJSON_AddNumberToObject(p, "indices", idx);
    cJSON_AddNumberToObject(p, "material", material);
    cJSON_AddItemToArray(prims, p);
    return m;
}

static void add_light(cJSON *lights, cJSON *nodes, cJSON *scene_nodes, const char *name, float intensity,
                      double x, double y, double z, const char *set)
{
    cJSON *l = cJSON_CreateObject();
    cJSON_AddStringToObject(l, "name", name);
    cJSON_AddStringToObject(l, "type", "point");
    cJSON_AddItemToObject(l, "color", num3(1, 1, 1));
    cJSON_AddNumberToObject(l, "intensity", intensity);
    int li = cJSON_GetArraySize(lights);
    cJSON_AddItemToArray(lights, l);
    cJSON *n = cJSON_CreateObject();
    cJSON_AddStringToObject(n, "name", name);
    cJSON_AddItemToObject(n, "translation", num3(x, y, z));
    cJSON *ext = cJSON_AddObjectToObject(n, "extensions");
    cJSON_AddNumberToObject(cJSON_AddObjectToObject(ext, "KHR_lights_punctual"), "light", li);
    if (set) cJSON_AddStringToObject(cJSON_AddObjectToObject(n, "extras"), "lbk_light_set", set);
    cJSON_AddItemToArray(scene_nodes, cJSON_CreateNumber(cJSON_GetArraySize(nodes)));
    cJSON_AddItemToArray(nodes, n);
}

/* The door: a closed thin box over the north doorway (x ∈ ±1.25, y ∈ [0.067, 3.333] world,
 * wall between z = −5 and −4.95), overlapping the jambs so no light leaks around it. */
static void door_box(float pos[24][3], float nrm[24][3], uint16_t idx[36])
{
    const float mn[3] = {-1.32f, 0.03f, -4.99f}, mx[3] = {1.32f, 3.40f, -4.96f};
    static const int axis_of_face[6] = {0, 0, 1, 1, 2, 2};
    int v = 0, t = 0;
    for (int f = 0; f < 6; f++) {
        int a = axis_of_face[f], s = f & 1 ? 1 : -1; /* normal = s · e_a */
        int u = (a + 1) % 3, w = (a + 2) % 3;
        float c[4][3];
        static const int uu[4] = {0, 1, 1, 0}, ww[4] = {0, 0, 1, 1};
        for (int k = 0; k < 4; k++) {
            c[k][a] = s > 0 ? mx[a] : mn[a];
            c[k][u] = uu[k] ? mx[u] : mn[u];
            c[k][w] = ww[k] ? mx[w] : mn[w];
        }
        /* (u, w) corners go counter-clockwise around +e_a; reverse for −e_a */
        for (int k = 0; k < 4; k++) {
            int kk = s > 0 ? k : 3 - k;
            memcpy(pos[v + k], c[kk], sizeof c[kk]);
            nrm[v + k][0] = nrm[v + k][1] = nrm[v + k][2] = 0;
            nrm[v + k][a] = (float)s;
        }
        idx[t++] = (uint16_t)v, idx[t++] = (uint16_t)(v + 1), idx[t++] = (uint16_t)(v + 2);
        idx[t++] = (uint16_t)v, idx[t++] = (uint16_t)(v + 2), idx[t++] = (uint16_t)(v + 3);
        v += 4;
    }
}

/* The room mesh of room.glb: mesh 0, attributes in bufferViews 0..3 (positions, normals, uv0,
 * u16 indices): their offsets, lengths and counts, and their bytes padded to 4 each. */
typedef struct room_views {
    size_t off[4], len[4], cnt[4], bytes;
} room_views;

/* 1 when a view reaches past the GLB's size bytes (bin: where the BIN chunk's data starts). */
static int read_room_views(cJSON *src, size_t bin, size_t size, room_views *rv)
{
    cJSON *views = cJSON_GetObjectItem(src, "bufferViews"), *accs = cJSON_GetObjectItem(src, "accessors");
    rv->bytes = 0;
    for (int i = 0; i < 4; i++) {
        cJSON *v = cJSON_GetArrayItem(views, i), *a = cJSON_GetArrayItem(accs, i);
        cJSON *bo = cJSON_GetObjectItem(v, "byteOffset"), *bl = cJSON_GetObjectItem(v, "byteLength");
        rv->off[i] = bo ? (size_t)bo->valuedouble : 0;
        rv->len[i] = bl ? (size_t)bl->valuedouble : 0;
        rv->cnt[i] = (size_t)cJSON_GetObjectItem(a, "count")->valuedouble;
        if (bin + rv->off[i] + rv->len[i] > size) return 1;
        rv->bytes += (rv->len[i] + 3) & ~(size_t)3;
    }
    return 0;
}

/* bufferViews, accessors and the one buffer (base64): the room's four views copied from the GLB,
 * then the door box's positions, normals and indices. */
static void add_buffers(cJSON *root, cJSON *src, const unsigned char *glb, size_t bin, const room_views *rv)
{
    cJSON *accs = cJSON_GetObjectItem(src, "accessors");
    float dpos[24][3], dnrm[24][3];
    uint16_t didx[36];
    door_box(dpos, dnrm, didx);
    size_t total = rv->bytes + sizeof dpos + sizeof dnrm + sizeof didx;
    unsigned char *buf = calloc(total, 1);
    cJSON *ov = cJSON_AddArrayToObject(root, "bufferViews"), *oa = cJSON_AddArrayToObject(root, "accessors");
    size_t w = 0;
    for (int i = 0; i < 4; i++) {
        memcpy(buf + w, glb + bin + rv->off[i], rv->len[i]);
        add_view(ov, w, rv->len[i]);
        w += (rv->len[i] + 3) & ~(size_t)3;
    }
    cJSON *a0 = cJSON_GetArrayItem(accs, 0);
    float rmn[3], rmx[3];
    for (int k = 0; k < 3; k++) {
        rmn[k] = (float)cJSON_GetArrayItem(cJSON_GetObjectItem(a0, "min"), k)->valuedouble;
        rmx[k] = (float)cJSON_GetArrayItem(cJSON_GetObjectItem(a0, "max"), k)->valuedouble;
    }
    add_accessor(oa, 0, 5126, rv->cnt[0], "VEC3", rmn, rmx);
    add_accessor(oa, 1, 5126, rv->cnt[1], "VEC3", NULL, NULL);
    add_accessor(oa, 2, 5126, rv->cnt[2], "VEC2", NULL, NULL);
    add_accessor(oa, 3, 5123, rv->cnt[3], "SCALAR", NULL, NULL);
    memcpy(buf + w, dpos, sizeof dpos), add_view(ov, w, sizeof dpos), w += sizeof dpos;
    memcpy(buf + w, dnrm, sizeof dnrm), add_view(ov, w, sizeof dnrm), w += sizeof dnrm;
    memcpy(buf + w, didx, sizeof didx), add_view(ov, w, sizeof didx), w += sizeof didx;
    float dmn[3] = {1e30f, 1e30f, 1e30f}, dmx[3] = {-1e30f, -1e30f, -1e30f};
    for (int i = 0; i < 24; i++)
        for (int k = 0; k < 3; k++) dmn[k] = dpos[i][k] < dmn[k] ? dpos[i][k] : dmn[k], dmx[k] = dpos[i][k] > dmx[k] ? dpos[i][k] : dmx[k];
    add_accessor(oa, 4, 5126, 24, "VEC3", dmn, dmx);
    add_accessor(oa, 5, 5126, 24, "VEC3", NULL, NULL);
    add_accessor(oa, 6, 5123, 36, "SCALAR", NULL, NULL);
    char *uri = base64(buf, total);
    cJSON *b = cJSON_CreateObject();
    cJSON_AddNumberToObject(b, "byteLength", (double)total);
    cJSON_AddStringToObject(b, "uri", uri);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "buffers"), b);
    free(uri), free(buf);
}

/* The grey material, the room and door meshes, and the nodes: the room, then the door and the
 * outer door as o asks (their indices into scene_nodes); returns the nodes array. */
static cJSON *add_nodes(cJSON *root, const ds_options *o, cJSON *scene_nodes)
{
    cJSON *mats = cJSON_AddArrayToObject(root, "materials");
    cJSON *m = cJSON_CreateObject();
    cJSON_AddStringToObject(m, "name", "Room");
    double grey[4] = {0.8, 0.8, 0.8, 1};
    cJSON *pbr = cJSON_AddObjectToObject(m, "pbrMetallicRoughness");
    cJSON_AddItemToObject(pbr, "baseColorFactor", cJSON_CreateDoubleArray(grey, 4));
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0);
    cJSON_AddItemToArray(mats, m);
    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    cJSON_AddItemToArray(meshes, mesh_prim(0, 1, 2, 3, 0));
    cJSON_AddItemToArray(meshes, mesh_prim(4, 5, -1, 6, 0));

    cJSON *nodes = cJSON_AddArrayToObject(root, "nodes");
    cJSON *n = cJSON_CreateObject();
    cJSON_AddStringToObject(n, "name", "Room");
    cJSON_AddNumberToObject(n, "mesh", 0);
    cJSON_AddItemToObject(n, "translation", num3(0, 1, 0));
    if (o->texel_density > 0) cJSON_AddNumberToObject(cJSON_AddObjectToObject(n, "extras"), "lbk_texel_density", o->texel_density);
    cJSON_AddItemToArray(nodes, n);
    cJSON_AddItemToArray(scene_nodes, cJSON_CreateNumber(0));
    for (int which = 0; which < 2; which++) {
        int kind = which ? o->outer_door : o->door;
        if (kind == DS_NO_DOOR) continue;
        n = cJSON_CreateObject();
        cJSON_AddStringToObject(n, "name", which ? "OuterDoor" : "Door");
        cJSON_AddNumberToObject(n, "mesh", 1);
        if (which) cJSON_AddItemToObject(n, "translation", num3(0, 0, -1.51)); /* z from −6.50 to −6.47 */
        cJSON *ex = cJSON_AddObjectToObject(n, "extras");
        if (kind == DS_DOOR_TAGGED) cJSON_AddStringToObject(ex, "lbk_door", which ? "outer" : "north");
        if (o->texel_density > 0) cJSON_AddNumberToObject(ex, "lbk_texel_density", o->texel_density);
        cJSON_AddItemToArray(scene_nodes, cJSON_CreateNumber(cJSON_GetArraySize(nodes)));
        cJSON_AddItemToArray(nodes, n);
    }
    return nodes;
}

/* The sun: directional, the node's −Z is the direction of travel; rotate −Z onto (0, −1, 1)/√2,
 * i.e. −135° about +X (quaternion (−sin 67.5°, 0, 0, cos 67.5°)). */
static void add_sun(cJSON *lights, cJSON *nodes, cJSON *scene_nodes, double intensity)
{
    cJSON *l = cJSON_CreateObject();
    cJSON_AddStringToObject(l, "name", "Sun");
    cJSON_AddStringToObject(l, "type", "directional");
    cJSON_AddItemToObject(l, "color", num3(1, 1, 1));
    cJSON_AddNumberToObject(l, "intensity", intensity);
    int li = cJSON_GetArraySize(lights);
    cJSON_AddItemToArray(lights, l);
    cJSON *sn = cJSON_CreateObject();
    cJSON_AddStringToObject(sn, "name", "Sun");
    double q[4] = {-0.9238795325112867, 0, 0, 0.3826834323650898};
    cJSON_AddItemToObject(sn, "rotation", cJSON_CreateDoubleArray(q, 4));
    cJSON_AddNumberToObject(cJSON_AddObjectToObject(cJSON_AddObjectToObject(sn, "extensions"), "KHR_lights_punctual"),
                            "light", li);
    cJSON_AddItemToArray(scene_nodes, cJSON_CreateNumber(cJSON_GetArraySize(nodes)));
    cJSON_AddItemToArray(nodes, sn);
}

/* The lights o asks for (KHR_lights_punctual, when there is any). */
static void add_lights(cJSON *root, const ds_options *o, cJSON *nodes, cJSON *scene_nodes)
{
    cJSON *lights = cJSON_CreateArray();
    if (o->outside_light) add_light(lights, nodes, scene_nodes, "Outside", 300, 0, 2, -8, NULL);
    if (o->inside != DS_INSIDE_NONE) {
        int sets = o->inside == DS_INSIDE_SETS;
        add_light(lights, nodes, scene_nodes, "LampA", 20, -2.5, 3.5, 2.5, sets ? "A" : NULL);
        add_light(lights, nodes, scene_nodes, "LampB", 20, 2.5, 3.5, 2.5, sets ? "B" : NULL);
    }
    if (o->zero_set) add_light(lights, nodes, scene_nodes, "LampC", 0, 0, 3.5, -2.5, "C");
    if (o->sun > 0) add_sun(lights, nodes, scene_nodes, o->sun);
    if (cJSON_GetArraySize(lights)) {
        cJSON *ext = cJSON_AddObjectToObject(root, "extensions");
        cJSON_AddItemToObject(cJSON_AddObjectToObject(ext, "KHR_lights_punctual"), "lights", lights);
        cJSON *used = cJSON_AddArrayToObject(root, "extensionsUsed");
        cJSON_AddItemToArray(used, cJSON_CreateString("KHR_lights_punctual"));
    } else {
        cJSON_Delete(lights);
    }
}

int ds_write_room_scene(const char *room_glb, const char *out_path, const ds_options *o, char *err, size_t err_len)
{
    size_t size;
    if (!sd_present(room_glb)) {
        snprintf(err, err_len, "missing input %s", room_glb);
        return 1;
    }
    unsigned char *glb = read_file(room_glb, &size);
    if (!glb) {
        snprintf(err, err_len, "cannot read %s", room_glb);
        return 1;
    }
    if (size < 28 || rd32(glb) != 0x46546C67u) {
        free(glb);
        return fail(err, err_len, "room.glb: not a GLB");
    }
    uint32_t jlen = rd32(glb + 12);
    cJSON *src = 20 + (size_t)jlen <= size ? cJSON_ParseWithLength((const char *)glb + 20, jlen) : NULL;
    size_t bin = 20 + (size_t)jlen + 8;
    if (!src || bin > size) {
        cJSON_Delete(src);
        free(glb);
        return fail(err, err_len, "room.glb: bad JSON chunk");
    }
    room_views rv;
    if (read_room_views(src, bin, size, &rv)) {
        cJSON_Delete(src);
        free(glb);
        return fail(err, err_len, "room.glb: buffer view out of range");
    }
    cJSON *root = cJSON_CreateObject();
    cJSON *asset = cJSON_AddObjectToObject(root, "asset");
    cJSON_AddStringToObject(asset, "version", "2.0");
    cJSON_AddStringToObject(asset, "generator", "lbk tests/support/door_scenes.c from room_with_doors (MIT)");
    add_buffers(root, src, glb, bin, &rv);
    cJSON *scene = cJSON_CreateObject(), *scene_nodes = cJSON_AddArrayToObject(scene, "nodes");
    cJSON *nodes = add_nodes(root, o, scene_nodes);
    add_lights(root, o, nodes, scene_nodes);
    cJSON *sx = (o->sky > 0 || o->combinations) ? cJSON_AddObjectToObject(scene, "extras") : NULL;
    if (o->sky > 0) cJSON_AddItemToObject(sx, "lbk_sky", num3(o->sky, o->sky, o->sky));
    if (o->combinations) {
        cJSON *pairs = cJSON_AddArrayToObject(sx, "lbk_combinations"), *pr = cJSON_CreateArray();
        cJSON_AddItemToArray(pr, cJSON_CreateString("north"));
        cJSON_AddItemToArray(pr, cJSON_CreateString("outer"));
        cJSON_AddItemToArray(pairs, pr);
    }
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "scenes"), scene);
    cJSON_AddNumberToObject(root, "scene", 0);

    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    cJSON_Delete(src);
    free(glb);
    if (!text) return fail(err, err_len, "out of memory");
    FILE *f = fopen(out_path, "w");
    int ok = f && fputs(text, f) >= 0;
    if (f && fclose(f)) ok = 0;
    free(text);
    if (!ok) return fail(err, err_len, "cannot write the scene");
    return 0;
}

const char *ds_room_glb(void)
{
    static char path[1024]; /* test support: one thread */
    return sd_path(path, sizeof path, "room_with_doors/room.glb");
}
