/* The hostile-glTF campaign's generator (see hostile_gltf.h). */
#include "tests/support/hostile_gltf.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tests/support/scenes_dir.h"

static int put(const char *dir, const char *file, const void *data, size_t len)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, file);
    FILE *f = fopen(p, "wb");
    if (!f) return -1;
    size_t w = len ? fwrite(data, 1, len, f) : 0;
    return (fclose(f) == 0 && w == len) ? 0 : -1;
}

/* A 108-byte quad buffer: 4 positions, 6 uint16 indices, 4 normals (as tests/support/import_fixtures.c). */
static int quad_bin(const char *dir, const char *file, const float *pos, const uint16_t *idx)
{
    static const float dpos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    static const uint16_t didx[6] = {0, 1, 2, 0, 2, 3};
    static const float nrm[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    unsigned char b[108];
    memcpy(b, pos ? pos : dpos, 48);
    memcpy(b + 48, idx ? idx : didx, 12);
    memcpy(b + 60, nrm, 48);
    return put(dir, file, b, sizeof b);
}

/* The template: one emissive quad on node 0. NULL fields take the defaults. */
typedef struct {
    const char *top, *uri, *views, *accessors, *material, *nodes;
    long long byte_length; /* 0: 108 */
} spec;

static const char *const kViews = "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
                                  "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},"
                                  "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":48}";
static const char *const kAccessors = "{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
                                      "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
                                      "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}";

static int scene(const char *dir, const char *name, char *path, size_t n, const spec *s)
{
    char json[16384];
    int len = snprintf(json, sizeof json,
                       "{\"asset\":{\"version\":\"2.0\"},%s"
                       "\"buffers\":[{\"uri\":\"%s\",\"byteLength\":%lld}],\"bufferViews\":[%s],\"accessors\":[%s],"
                       "\"materials\":[{\"name\":\"lamp\",\"emissiveFactor\":[1,1,1],\"doubleSided\":true%s}],"
                       "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":2},\"indices\":1,"
                       "\"material\":0}]}],\"nodes\":[%s],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
                       s->top ? s->top : "", s->uri ? s->uri : "quad.bin", s->byte_length ? s->byte_length : 108,
                       s->views ? s->views : kViews, s->accessors ? s->accessors : kAccessors,
                       s->material ? s->material : "", s->nodes ? s->nodes : "{\"mesh\":0}");
    if (len <= 0 || (size_t)len >= sizeof json) return -1;
    char file[256];
    snprintf(file, sizeof file, "%s.gltf", name);
    snprintf(path, n, "%s/%s", dir, file);
    if (!s->uri && quad_bin(dir, "quad.bin", NULL, NULL)) return -1;
    return put(dir, file, json, (size_t)len);
}

#define SPEC_CASE(fn, ...)                                            \
    static int fn(const char *dir, const char *name, char *path, size_t n) \
    {                                                                 \
        spec s = {__VA_ARGS__};                                       \
        return scene(dir, name, path, n, &s);                         \
    }

SPEC_CASE(w_baseline, 0)
SPEC_CASE(w_scale_1e18, .nodes = "{\"mesh\":0,\"scale\":[1e18,1e18,1e18]}")
SPEC_CASE(w_scale_inf, .nodes = "{\"mesh\":0,\"scale\":[1e999,1,1]}")
SPEC_CASE(w_translation_huge, .nodes = "{\"mesh\":0,\"translation\":[3e38,-3e38,0]}")
SPEC_CASE(w_count_huge, .accessors = "{\"bufferView\":0,\"componentType\":5126,\"count\":4294967295,\"type\":\"VEC3\"},"
                                     "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
                                     "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}")
SPEC_CASE(w_count_negative, .accessors = "{\"bufferView\":0,\"componentType\":5126,\"count\":-1,\"type\":\"VEC3\"},"
                                         "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
                                         "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}")
SPEC_CASE(w_accessor_past_view, .accessors = "{\"bufferView\":0,\"byteOffset\":40,\"componentType\":5126,\"count\":4,"
                                             "\"type\":\"VEC3\"},"
                                             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
                                             "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}")
SPEC_CASE(w_view_past_buffer, .views = "{\"buffer\":0,\"byteOffset\":100,\"byteLength\":48},"
                                       "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},"
                                       "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":48}")
SPEC_CASE(w_view_offset_wraps, .views = "{\"buffer\":0,\"byteOffset\":18446744073709551600,\"byteLength\":48},"
                                        "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12},"
                                        "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":48}")
SPEC_CASE(w_bad_view_index, .accessors = "{\"bufferView\":7,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
                                         "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
                                         "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}")
SPEC_CASE(w_cycle, .nodes = "{\"mesh\":0,\"children\":[1]},{\"children\":[0]}")
SPEC_CASE(w_self_child, .nodes = "{\"mesh\":0,\"children\":[0]}")
SPEC_CASE(w_two_parents, .nodes = "{\"mesh\":0,\"children\":[1,2]},{\"children\":[2]},{}")
SPEC_CASE(w_child_out_of_range, .nodes = "{\"mesh\":0,\"children\":[99]}")
SPEC_CASE(w_mesh_out_of_range, .nodes = "{\"mesh\":5}")
SPEC_CASE(w_ext_required_unused, .top = "\"extensionsRequired\":[\"KHR_lights_punctual\"],")
SPEC_CASE(w_uri_absolute, .uri = "/etc/passwd")
SPEC_CASE(w_uri_escape, .uri = "../../../../../../etc/passwd")
SPEC_CASE(w_uri_nul, .uri = "quad.bin%00.png")
SPEC_CASE(w_uri_nul_bad_hex, .uri = "quad.bin%zz.png")
SPEC_CASE(w_data_uri_short, .uri = "data:application/octet-stream;base64,AAAAAAAA")

static int w_nan_position(const char *dir, const char *name, char *path, size_t n)
{
    float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    pos[4] = NAN;
    spec s = {.uri = "nan.bin"};
    return quad_bin(dir, "nan.bin", pos, NULL) || scene(dir, name, path, n, &s);
}

static int w_position_inf(const char *dir, const char *name, char *path, size_t n)
{
    float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    pos[6] = -INFINITY;
    spec s = {.uri = "inf.bin"};
    return quad_bin(dir, "inf.bin", pos, NULL) || scene(dir, name, path, n, &s);
}

static int w_position_3e38(const char *dir, const char *name, char *path, size_t n)
{
    const float pos[12] = {-3e38f, -3e38f, 0, 3e38f, -3e38f, 0, 3e38f, 3e38f, 0, -3e38f, 3e38f, 0};
    spec s = {.uri = "far.bin"};
    return quad_bin(dir, "far.bin", pos, NULL) || scene(dir, name, path, n, &s);
}

static int w_index_out_of_range(const char *dir, const char *name, char *path, size_t n)
{
    const uint16_t idx[6] = {0, 1, 60000, 0, 2, 3};
    spec s = {.uri = "idx.bin"};
    return quad_bin(dir, "idx.bin", NULL, idx) || scene(dir, name, path, n, &s);
}

static int w_short_buffer(const char *dir, const char *name, char *path, size_t n)
{
    unsigned char b[100] = {0};
    spec s = {.uri = "short.bin"};
    return put(dir, "short.bin", b, sizeof b) || scene(dir, name, path, n, &s);
}

/* a buffer or image URI naming something that is not a regular file */
static int special(const char *dir, const char *what, const char *file)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, file);
    unlink(p);
    if (!strcmp(what, "fifo")) return mkfifo(p, 0600);
    if (!strcmp(what, "dir")) return mkdir(p, 0700);
    return symlink("/dev/null", p);
}

static int w_fifo_buffer(const char *dir, const char *name, char *path, size_t n)
{
    spec s = {.uri = "pipe.bin"};
    return special(dir, "fifo", "pipe.bin") || scene(dir, name, path, n, &s);
}

static int w_device_buffer(const char *dir, const char *name, char *path, size_t n)
{
    spec s = {.uri = "null.bin"};
    return special(dir, "dev", "null.bin") || scene(dir, name, path, n, &s);
}

#define TEXTURED(img_uri)                                                                              \
    .top = "\"images\":[{\"uri\":\"" img_uri "\"}],\"textures\":[{\"source\":0}],",                  \
    .material = ",\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}"

static int w_dir_image(const char *dir, const char *name, char *path, size_t n)
{
    spec s = {TEXTURED("folder.png")};
    return special(dir, "dir", "folder.png") || scene(dir, name, path, n, &s);
}

static int w_fifo_image(const char *dir, const char *name, char *path, size_t n)
{
    spec s = {TEXTURED("pipe.png")};
    return special(dir, "fifo", "pipe.png") || scene(dir, name, path, n, &s);
}

/* A PNG of signature and IHDR alone, claiming w x h pixels (stb_image's probe refuses past 2^30 bytes). */
static int huge_png(const char *dir, const char *file, uint32_t w, uint32_t h)
{
    unsigned char b[33] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
    for (int i = 0; i < 4; i++) {
        b[16 + i] = (unsigned char)(w >> (24 - 8 * i));
        b[20 + i] = (unsigned char)(h >> (24 - 8 * i));
    }
    b[24] = 8; /* bit depth */
    b[25] = 6; /* RGBA */
    return put(dir, file, b, sizeof b);
}

static int w_png_65535(const char *dir, const char *name, char *path, size_t n)
{
    spec s = {TEXTURED("huge.png")};
    return huge_png(dir, "huge.png", 65535, 65535) || scene(dir, name, path, n, &s);
}

static int w_png_2p31(const char *dir, const char *name, char *path, size_t n)
{
    spec s = {TEXTURED("huger.png")};
    return huge_png(dir, "huger.png", 1u << 31, 1u << 31) || scene(dir, name, path, n, &s);
}

static int w_json_deep(const char *dir, const char *name, char *path, size_t n)
{
    char deep[512] = "{\"mesh\":0,\"extras\":";
    for (int i = 0; i < 100; i++) strcat(deep, "[");
    for (int i = 0; i < 100; i++) strcat(deep, "]");
    strcat(deep, "}");
    spec s = {.nodes = deep};
    return scene(dir, name, path, n, &s);
}

static int w_json_truncated(const char *dir, const char *name, char *path, size_t n)
{
    snprintf(path, n, "%s/%s.gltf", dir, name);
    char file[256];
    snprintf(file, sizeof file, "%s.gltf", name);
    const char *j = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{},{},{";
    return put(dir, file, j, strlen(j));
}

static int w_glb_truncated(const char *dir, const char *name, char *path, size_t n)
{
    /* header says 1000 bytes, the file has 28 */
    const unsigned char g[28] = {'g', 'l', 'T', 'F', 2, 0, 0, 0, 0xe8, 3, 0, 0, 8, 0, 0, 0, 'J', 'S', 'O', 'N',
                                 '{', '}', ' ', ' ', ' ', ' ', ' ', ' '};
    snprintf(path, n, "%s/%s.glb", dir, name);
    char file[256];
    snprintf(file, sizeof file, "%s.glb", name);
    return put(dir, file, g, sizeof g);
}

/* NAME.gltf of `count` empty nodes, a parent chain when `chain` (hg_write_nodes). */
static int write_nodes_case(const char *dir, const char *name, char *path, size_t n, size_t count, int chain)
{
    char file[256];
    snprintf(file, sizeof file, "%s.gltf", name);
    snprintf(path, n, "%s/%s", dir, file);
    return hg_write_nodes(dir, file, count, chain) ? 0 : -1;
}

static int w_chain_300(const char *dir, const char *name, char *path, size_t n)
{
    return write_nodes_case(dir, name, path, n, 300, 1);
}

static int w_chain_1e5(const char *dir, const char *name, char *path, size_t n)
{
    return write_nodes_case(dir, name, path, n, 100000, 1);
}

static int w_chain_1e6(const char *dir, const char *name, char *path, size_t n)
{
    return write_nodes_case(dir, name, path, n, 1000000, 1);
}

static int w_nodes_1e6(const char *dir, const char *name, char *path, size_t n)
{
    return write_nodes_case(dir, name, path, n, 1000000, 0);
}

/* The Draco water bottle (scenes/water_bottle_draco) with one accessor count changed (`from` ->
 * `to`, of equal length) and its textures unused (the keys renamed), so only WaterBottle.bin is copied. */
static int draco_edit(const char *dir, const char *name, char *path, size_t n, const char *from, const char *to)
{
    char src[1024];
    sd_path(src, sizeof src, "water_bottle_draco/WaterBottle.gltf");
    FILE *f = fopen(src, "rb");
    if (!f) return -1;
    static char json[16384];
    size_t len = fread(json, 1, sizeof json - 1, f);
    fclose(f);
    json[len] = 0;
    char *at = strstr(json, from);
    if (!at || strlen(to) != strlen(from)) return -1;
    memcpy(at, to, strlen(to));
    static const char *const tex[] = {"\"baseColorTexture\"", "\"metallicRoughnessTexture\"", "\"emissiveTexture\""};
    for (size_t i = 0; i < sizeof tex / sizeof tex[0]; i++) {
        char *t = strstr(json, tex[i]);
        if (!t) return -1;
        t[strlen(tex[i]) - 2] = '_'; /* "baseColorTextur_": a key glTF does not know */
    }
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "cp '%s/water_bottle_draco/WaterBottle.bin' '%s/'", sd_dir(), dir);
    if (system(cmd) != 0) return -1;
    char file[256];
    snprintf(file, sizeof file, "%s.gltf", name);
    snprintf(path, n, "%s/%s", dir, file);
    return put(dir, file, json, len);
}

static int w_draco_position_count(const char *dir, const char *name, char *path, size_t n)
{
    /* accessor 4, POSITION: the VEC3 of 2549 that has a "max" */
    return draco_edit(dir, name, path, n, "\"count\": 2549,\n      \"type\": \"VEC3\",\n      \"max\"",
                      "\"count\": 2548,\n      \"type\": \"VEC3\",\n      \"max\"");
}

static int w_draco_index_count(const char *dir, const char *name, char *path, size_t n)
{
    return draco_edit(dir, name, path, n, "\"count\": 13530", "\"count\": 13527");
}

static const hg_case kCases[] = {
    {"baseline", NULL, w_baseline},
    {"scale_1e18", "beyond +-1e+09 m", w_scale_1e18},
    {"scale_inf", "number overflow parsing '1e999'", w_scale_inf},
    {"translation_3e38", "beyond +-1e+09 m", w_translation_huge},
    {"position_3e38", "beyond +-1e+09 m", w_position_3e38},
    {"position_nan", "NaN or infinite", w_nan_position},
    {"position_inf", "NaN or infinite", w_position_inf},
    {"count_huge", "accessor 0", w_count_huge},
    {"count_negative", "count", w_count_negative},
    {"accessor_past_view", "accessor 0", w_accessor_past_view},
    {"view_past_buffer", "outside", w_view_past_buffer},
    {"view_offset_wraps", "bufferView", w_view_offset_wraps},
    {"bad_view_index", "bufferView", w_bad_view_index},
    {"index_out_of_range", "index", w_index_out_of_range},
    {"cycle", "reached twice", w_cycle},
    {"self_child", "reached twice", w_self_child},
    {"two_parents", "reached twice", w_two_parents},
    {"child_out_of_range", "out of range", w_child_out_of_range},
    {"mesh_out_of_range", "out of range", w_mesh_out_of_range},
    {"ext_required_unused", "extensionsUsed does not list", w_ext_required_unused},
    {"uri_absolute", "not a path relative", w_uri_absolute},
    {"uri_escape", "outside the scene's folder", w_uri_escape},
    {"uri_nul", "NUL byte", w_uri_nul},
    {"uri_nul_bad_hex", "NUL byte", w_uri_nul_bad_hex},
    {"data_uri_short", "holds 6 bytes, byteLength says 108", w_data_uri_short},
    {"short_buffer", "is 100 bytes, byteLength says 108", w_short_buffer},
    {"fifo_buffer", "names a FIFO, not a regular file", w_fifo_buffer},
    {"device_buffer", "names a character device, not a regular file", w_device_buffer},
    {"dir_image", "names a directory, not a regular file", w_dir_image},
    {"fifo_image", "names a FIFO, not a regular file", w_fifo_image},
    {"png_65535", "65535x65535 pixels exceeds", w_png_65535},
    {"png_2p31", "2147483648x2147483648 pixels exceeds", w_png_2p31},
    {"json_deep", "nested deeper than 64", w_json_deep},
    {"json_truncated", "invalid JSON", w_json_truncated},
    {"glb_truncated", "truncated GLB", w_glb_truncated},
    {"chain_300", "node 257: node hierarchy deeper than 256", w_chain_300},
    {"chain_1e5", "node 257: node hierarchy deeper than 256", w_chain_1e5},
    {"chain_1e6", "1000000 nodes", w_chain_1e6},
    {"nodes_1e6", "1000000 nodes", w_nodes_1e6},
    {"draco_position_count", "POSITION accessor 4 has count 2548, the decoded stream 2549", w_draco_position_count},
    {"draco_index_count", "indices accessor 0 has count 13527, the decoded stream 13530", w_draco_index_count},
};

const hg_case *hg_cases(size_t *count)
{
    *count = sizeof kCases / sizeof kCases[0];
    return kCases;
}

int hg_write(const char *dir, const hg_case *c, char *path, size_t n)
{
    return c->write(dir, c->name, path, n);
}

size_t hg_write_nodes(const char *dir, const char *name, size_t count, int chain)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    if (quad_bin(dir, "quad.bin", NULL, NULL)) return 0;
    FILE *f = fopen(p, "wb");
    if (!f) return 0;
    fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"quad.bin\",\"byteLength\":108}],"
               "\"bufferViews\":[%s],\"accessors\":[%s],\"materials\":[{\"emissiveFactor\":[1,1,1]}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]}],"
               "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[",
            kViews, kAccessors);
    for (size_t i = 0; i < count; i++) {
        const char *sep = i + 1 < count ? "," : "";
        if (i == 0) fprintf(f, chain && count > 1 ? "{\"mesh\":0,\"children\":[1]}%s" : "{\"mesh\":0}%s", sep);
        else if (chain && i + 1 < count) fprintf(f, "{\"children\":[%zu]}%s", i + 1, sep);
        else fprintf(f, "{}%s", sep);
    }
    fputs("]}", f);
    long size = ftell(f);
    return (fclose(f) == 0 && size > 0) ? (size_t)size : 0;
}
