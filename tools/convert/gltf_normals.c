/* Normal maps in lbk export --gltf (see gltf_normals.h). */
#include "tools/convert/gltf_normals.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/error_util.h"

#define SAMPLER_LINEAR 9729
#define SAMPLER_LINEAR_MIPMAP_LINEAR 9987
#define WRAP_REPEAT 10497

int tl_gltf_normals_init(tl_gltf_normals *n, const bk_scene *s, uint32_t first_texture, int texels)
{
    memset(n, 0, sizeof *n);
    n->s = s;
    n->first_texture = first_texture;
    n->texels = texels;
    const size_t m = s->material_count ? s->material_count : 1;
    n->texture = malloc(m * sizeof *n->texture);
    n->order = malloc(m * sizeof *n->order);
    if (!n->texture || !n->order) return tl_gltf_normals_free(n), -1;
    for (size_t i = 0; i < m; i++) n->texture[i] = -1;
    return 0;
}

void tl_gltf_normals_free(tl_gltf_normals *n)
{
    free(n->texture), free(n->order);
    memset(n, 0, sizeof *n);
}

int tl_gltf_normals_has(const tl_gltf_normals *n, uint32_t mi)
{
    const bk_scene *s = n->s;
    return s && s->tangents && mi < s->material_count && s->materials[mi].normal_tex1 > 0 &&
           (size_t)s->materials[mi].normal_tex1 - 1 < s->image_count;
}

/* The image's texels as RGB bytes (row 0 at the top), the importer's floats rounded back. */
static uint8_t *rgb8(const bk_image *im)
{
    const size_t n = (size_t)im->width * (size_t)im->height;
    uint8_t *out = malloc(3 * (n ? n : 1));
    if (!out) return NULL;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            const float v = im->rgba[4 * i + (size_t)c];
            out[3 * i + (size_t)c] = (uint8_t)lrintf(255.0f * (v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f));
        }
    return out;
}

void tl_gltf_normals_material(tl_gltf_normals *n, tl_glb *g, cJSON *mat, uint32_t mi)
{
    if (!tl_gltf_normals_has(n, mi)) return;
    const bk_material *m = &n->s->materials[mi];
    if (n->texture[mi] < 0) {
        n->texture[mi] = (int)(n->first_texture + n->count);
        n->order[n->count++] = mi;
    }
    cJSON *nt = cJSON_AddObjectToObject(mat, "normalTexture");
    cJSON_AddNumberToObject(nt, "index", n->texture[mi]);
    if (m->normal_scale != 1.0f) cJSON_AddNumberToObject(nt, "scale", m->normal_scale);
    cJSON *lbk = cJSON_GetObjectItem(cJSON_GetObjectItem(mat, "extras"), "lbk");
    if (!n->texels || !lbk) return;
    const bk_image *im = &n->s->images[m->normal_tex1 - 1];
    uint8_t *px = rgb8(im);
    if (!px) {
        g->failed = 1;
        return;
    }
    cJSON *x = cJSON_AddObjectToObject(lbk, "normal_map");
    cJSON_AddNumberToObject(x, "width", im->width);
    cJSON_AddNumberToObject(x, "height", im->height);
    cJSON_AddNumberToObject(x, "scale", m->normal_scale);
    cJSON_AddNumberToObject(x, "texels", tl_glb_accessor_unorm8(g, px, 3 * (size_t)im->width * (size_t)im->height));
    free(px);
}

int tl_gltf_normals_tangents(const tl_gltf_normals *n, tl_glb *g, cJSON *attributes, uint32_t mi, const uint32_t *sv,
                             size_t nv)
{
    if (!tl_gltf_normals_has(n, mi) || !nv) return 0;
    float *t = malloc(4 * nv * sizeof *t);
    if (!t) return -1;
    for (size_t v = 0; v < nv; v++) memcpy(&t[4 * v], &n->s->tangents[4 * (size_t)sv[v]], 4 * sizeof(float));
    cJSON_AddNumberToObject(attributes, "TANGENT", tl_glb_accessor_f32(g, t, nv, 4, TL_GLTF_ARRAY_BUFFER, 0));
    free(t);
    return 0;
}

int tl_gltf_normals_write(const tl_gltf_normals *n, cJSON *root, const char *dir, const char *stem, uint32_t *png_files,
                          char err[TL_ERR_LEN])
{
    if (!n->count) return 0;
    cJSON *samplers = cJSON_GetObjectItem(root, "samplers"), *images = cJSON_GetObjectItem(root, "images");
    cJSON *textures = cJSON_GetObjectItem(root, "textures");
    if (!samplers) samplers = cJSON_AddArrayToObject(root, "samplers");
    if (!images) images = cJSON_AddArrayToObject(root, "images");
    if (!textures) textures = cJSON_AddArrayToObject(root, "textures");
    if (!samplers || !images || !textures || (uint32_t)cJSON_GetArraySize(textures) != n->first_texture)
        return tl_fail(err, -1, "glTF export: the normal maps' textures do not follow the pages'");
    const int sampler = cJSON_GetArraySize(samplers);
    cJSON *sm = cJSON_CreateObject();
    cJSON_AddNumberToObject(sm, "magFilter", SAMPLER_LINEAR);
    cJSON_AddNumberToObject(sm, "minFilter", SAMPLER_LINEAR_MIPMAP_LINEAR);
    cJSON_AddNumberToObject(sm, "wrapS", WRAP_REPEAT);
    cJSON_AddNumberToObject(sm, "wrapT", WRAP_REPEAT);
    cJSON_AddItemToArray(samplers, sm);
    for (uint32_t k = 0; k < n->count; k++) {
        const bk_image *im = &n->s->images[n->s->materials[n->order[k]].normal_tex1 - 1];
        char uri[256], path[4608];
        snprintf(uri, sizeof uri, "%s.normal_%03u.png", stem, k);
        snprintf(path, sizeof path, "%s/%s", dir, uri);
        uint8_t *px = rgb8(im);
        if (!px) return tl_fail(err, -1, "out of memory");
        const int rc = tl_png_write_rgb8(path, im->width, im->height, px, err);
        free(px);
        if (rc) return -1;
        ++*png_files;
        cJSON *ji = cJSON_CreateObject(), *jt = cJSON_CreateObject();
        cJSON_AddStringToObject(ji, "uri", uri);
        cJSON_AddStringToObject(ji, "mimeType", "image/png");
        cJSON_AddItemToArray(images, ji);
        cJSON_AddNumberToObject(jt, "sampler", sampler);
        cJSON_AddNumberToObject(jt, "source", cJSON_GetArraySize(images) - 1);
        cJSON_AddItemToArray(textures, jt);
    }
    return 0;
}
