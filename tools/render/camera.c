/* glTF cameras (glTF 2.0 §3.10): camera k is the k-th node with a "camera" in the default scene,
 * depth first; it looks down its node's −Z with +Y up. The scene importer does not read
 * cameras, so the JSON is read here (cJSON). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "tools/common/error_util.h"
#include "tools/common/file_util.h"
#include "tools/render/render.h"

/* The JSON text of a .gltf, or the JSON chunk of a .glb (glTF 2.0 §4.4). */
static cJSON *parse_gltf(const char *path, char err[TL_ERR_LEN])
{
    void *data;
    size_t size;
    if (tl_read_file(path, &data, &size, err)) return NULL;
    const unsigned char *b = data;
    cJSON *root = NULL;
    if (size >= 20 && !memcmp(b, "glTF", 4)) {
        const uint32_t len = (uint32_t)b[12] | (uint32_t)b[13] << 8 | (uint32_t)b[14] << 16 | (uint32_t)b[15] << 24;
        if (len <= size - 20 && !memcmp(b + 16, "JSON", 4)) root = cJSON_ParseWithLength((const char *)b + 20, len);
    } else {
        root = cJSON_ParseWithLength(data, size);
    }
    free(data);
    if (!root) tl_fail(err, TL_RENDER_INPUT, "%s: not a glTF file", path);
    return root;
}

static double num(const cJSON *a, int i, double fallback)
{
    const cJSON *x = cJSON_GetArrayItem(a, i);
    return cJSON_IsNumber(x) ? x->valuedouble : fallback;
}

/* Column-major 4×4 local matrix of a node: its "matrix", else T · R · S. */
static void node_matrix(const cJSON *node, double m[16])
{
    const cJSON *mat = cJSON_GetObjectItem(node, "matrix");
    if (cJSON_GetArraySize(mat) == 16) {
        for (int i = 0; i < 16; i++) m[i] = num(mat, i, 0);
        return;
    }
    const cJSON *t = cJSON_GetObjectItem(node, "translation"), *r = cJSON_GetObjectItem(node, "rotation"),
                *s = cJSON_GetObjectItem(node, "scale");
    const double x = num(r, 0, 0), y = num(r, 1, 0), z = num(r, 2, 0), w = num(r, 3, 1);
    const double R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                         2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    memset(m, 0, 16 * sizeof *m);
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 3; k++) m[4 * c + k] = R[3 * c + k] * num(s, c, 1);
    for (int k = 0; k < 3; k++) m[12 + k] = num(t, k, 0);
    m[15] = 1;
}

static void mul(const double a[16], const double b[16], double out[16])
{
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++) {
            double v = 0;
            for (int k = 0; k < 4; k++) v += a[4 * k + r] * b[4 * c + k];
            out[4 * c + r] = v;
        }
}

typedef struct walk {
    const cJSON *nodes;
    int want, seen, depth;
    double world[16];
    int found, camera;
} walk;

static void visit(walk *w, int n, const double parent[16])
{
    const cJSON *node = cJSON_GetArrayItem(w->nodes, n);
    if (!node || w->found || w->depth > 64) return;
    double local[16], world[16];
    node_matrix(node, local);
    mul(parent, local, world);
    const cJSON *cam = cJSON_GetObjectItem(node, "camera");
    if (cJSON_IsNumber(cam) && w->seen++ == w->want) {
        memcpy(w->world, world, sizeof world);
        w->camera = cam->valueint;
        w->found = 1;
        return;
    }
    w->depth++;
    const cJSON *c;
    cJSON_ArrayForEach(c, cJSON_GetObjectItem(node, "children")) if (cJSON_IsNumber(c)) visit(w, c->valueint, world);
    w->depth--;
}

int tl_gltf_camera(const char *path, int index, tl_camera *out, char err[TL_ERR_LEN])
{
    cJSON *root = parse_gltf(path, err);
    if (!root) return TL_RENDER_INPUT;
    const cJSON *scenes = cJSON_GetObjectItem(root, "scenes");
    const cJSON *sc = cJSON_GetArrayItem(scenes, cJSON_IsNumber(cJSON_GetObjectItem(root, "scene"))
                                                     ? cJSON_GetObjectItem(root, "scene")->valueint : 0);
    walk w = {cJSON_GetObjectItem(root, "nodes"), index, 0, 0, {0}, 0, -1};
    const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const cJSON *n;
    cJSON_ArrayForEach(n, cJSON_GetObjectItem(sc, "nodes")) if (cJSON_IsNumber(n)) visit(&w, n->valueint, id);
    const cJSON *cam = w.found ? cJSON_GetArrayItem(cJSON_GetObjectItem(root, "cameras"), w.camera) : NULL;
    const cJSON *persp = cJSON_GetObjectItem(cam, "perspective");
    const cJSON *yfov = cJSON_GetObjectItem(persp, "yfov");
    int rc = 0;
    if (!w.found) rc = tl_fail(err, TL_RENDER_USAGE, "%s has %d camera nodes, no camera %d", path, w.seen, index);
    else if (!cJSON_IsNumber(yfov) || !(yfov->valuedouble > 0 && yfov->valuedouble < 3.14))
        rc = tl_fail(err, TL_RENDER_INPUT, "%s: camera %d is not a perspective camera with a yfov", path, index);
    if (!rc) {
        const double *m = w.world;
        for (int k = 0; k < 3; k++) {
            out->from[k] = (float)m[12 + k];
            out->at[k] = (float)(m[12 + k] - m[8 + k]); /* −Z */
            out->up[k] = (float)m[4 + k];               /* +Y */
        }
        out->yfov = (float)yfov->valuedouble;
    }
    cJSON_Delete(root);
    return rc;
}
