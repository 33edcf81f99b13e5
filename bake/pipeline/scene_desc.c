/* lbk_bake_scene → bk_scene (scene_desc.h). Each rule mirrors the glTF importer's, so that a
 * description and a glTF file of the same scene give the same bk_scene up to the provenance
 * hash; where the importer works in double through a node transform, the identity transform's
 * arithmetic is reproduced (it turns -0 into +0). */
#include "bake/pipeline/scene_desc.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

/* One range for the texel density: the scene library's importer checks the one lbk/bake.h states. */
/* (long): clang takes floating constants in a static assertion only as the operands of casts */
_Static_assert((long)BK_TEXEL_DENSITY_MAX == (long)LBK_BAKE_TEXEL_DENSITY_MAX, "one texel density range");

#define SD_MAX_TRIANGLES ((size_t)1 << 24) /* the importer's default cap */
#define SD_PI 3.14159265358979323846

/* The size of version 1 of lbk_bake_scene, what size 0 means (see BK_DESC_SIZE_V1). */
#define SD_SIZE_V1 sizeof(lbk_bake_scene)

typedef struct sd_ctx {
    const lbk_bake_scene *d;
    const bk_events *ev;
    const char *name;
    char *err;
    size_t err_len;
} sd_ctx;

static lbk_result sd_fail(sd_ctx *c, lbk_result r, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static lbk_result sd_fail(sd_ctx *c, lbk_result r, const char *fmt, ...)
{
    char what[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    snprintf(c->err, c->err_len, "scene '%s': %s", c->name, what);
    return r;
}

/* The importer's normalize3. */
static int normalize3(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 1e-30) || !isfinite(l)) return 0;
    v[0] /= l, v[1] /= l, v[2] /= l;
    return 1;
}

/* What the identity transform does to a coordinate in double: x + 0 (so -0 becomes +0). */
static float through_identity(float x) { return (float)((double)x + 0.0); }

static int finite_n(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static int rgb_ok(const float c[3]) { return finite_n(c, 3) && c[0] >= 0 && c[1] >= 0 && c[2] >= 0; }

/* lbk_light_set / lbk_door names: 1 to 63 printable bytes, as the importer requires. */
static int valid_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > 63) return 0;
    for (size_t i = 0; i < n; i++)
        if ((unsigned char)s[i] < 32 || s[i] == 127) return 0;
    return 1;
}

static const char *opt_str(const char *s) { return s ? s : ""; }

/* ---- checks ------------------------------------------------------------------------------ */

static lbk_result check_arrays(sd_ctx *c)
{
    const lbk_bake_scene *d = c->d;
    if ((d->vertex_count && !d->positions) || (d->triangle_count && !d->indices) ||
        (d->material_count && !d->materials) || (d->object_count && !d->objects) || (d->light_count && !d->lights) ||
        (d->combination_count && !d->combinations))
        return sd_fail(c, LBK_ERR_INVALID_ARGUMENT, "a count is non-zero but its array is NULL");
    if (d->triangle_count > SD_MAX_TRIANGLES || d->vertex_count > 3 * SD_MAX_TRIANGLES)
        return sd_fail(c, LBK_ERR_BAD_INPUT, "more than %zu triangles or %zu vertices (the caps)", SD_MAX_TRIANGLES,
                       3 * SD_MAX_TRIANGLES);
    if (d->triangle_count && !d->material_count) return sd_fail(c, LBK_ERR_BAD_INPUT, "triangles but no material");
    for (size_t v = 0; v < d->vertex_count; v++) {
        if (!finite_n(d->positions + 3 * v, 3)) return sd_fail(c, LBK_ERR_BAD_INPUT, "vertex %zu: NaN or infinite position", v);
        if (d->normals && !finite_n(d->normals + 3 * v, 3))
            return sd_fail(c, LBK_ERR_BAD_INPUT, "vertex %zu: NaN or infinite normal", v);
        if (d->uv1 && !finite_n(d->uv1 + 2 * v, 2)) return sd_fail(c, LBK_ERR_BAD_INPUT, "vertex %zu: NaN or infinite uv1", v);
    }
    for (size_t t = 0; t < d->triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            if (d->indices[3 * t + k] >= d->vertex_count)
                return sd_fail(c, LBK_ERR_BAD_INPUT, "triangle %zu: vertex index %u out of range (%zu vertices)", t,
                               d->indices[3 * t + k], d->vertex_count);
        if (d->triangle_materials && d->triangle_materials[t] >= d->material_count)
            return sd_fail(c, LBK_ERR_BAD_INPUT, "triangle %zu: material %u out of range (%zu materials)", t,
                           d->triangle_materials[t], d->material_count);
    }
    return LBK_OK;
}

static lbk_result check_objects(sd_ctx *c)
{
    const lbk_bake_scene *d = c->d;
    uint64_t next = 0;
    for (size_t i = 0; i < d->object_count; i++) {
        const lbk_bake_object *o = &d->objects[i];
        if (o->first_triangle != next)
            return sd_fail(c, LBK_ERR_BAD_INPUT, "object %zu starts at triangle %u, not %llu: objects must tile the triangles in order",
                           i, o->first_triangle, (unsigned long long)next);
        next += o->triangle_count;
        if (next > d->triangle_count)
            return sd_fail(c, LBK_ERR_BAD_INPUT, "object %zu: triangles up to %llu, but there are %zu", i,
                           (unsigned long long)next, d->triangle_count);
        if (!d->triangle_materials && o->material >= d->material_count)
            return sd_fail(c, LBK_ERR_BAD_INPUT, "object %zu: material %u out of range", i, o->material);
        if ((unsigned)o->lighting > LBK_BAKE_LIGHTING_NONE)
            return sd_fail(c, LBK_ERR_BAD_INPUT, "object %zu: unknown lighting %d", i, (int)o->lighting);
        if (!(o->texel_density >= 0 && o->texel_density <= LBK_BAKE_TEXEL_DENSITY_MAX))
            return sd_fail(c, LBK_ERR_BAD_INPUT, "object %zu: texel density must be in [0, %g] texels per metre", i,
                           LBK_BAKE_TEXEL_DENSITY_MAX);
        if ((o->light_set && o->light_set[0] && !valid_name(o->light_set)) || (o->door && o->door[0] && !valid_name(o->door)))
            return sd_fail(c, LBK_ERR_BAD_INPUT, "object %zu: a light set or door name must be 1 to 63 printable bytes", i);
    }
    if (d->object_count && next != d->triangle_count)
        return sd_fail(c, LBK_ERR_BAD_INPUT, "the objects end at triangle %llu of %zu: every triangle needs an object",
                       (unsigned long long)next, d->triangle_count);
    return LBK_OK;
}

static lbk_result check_tables(sd_ctx *c)
{
    const lbk_bake_scene *d = c->d;
    for (size_t i = 0; i < d->material_count; i++)
        if (!rgb_ok(d->materials[i].base_color) || !rgb_ok(d->materials[i].emission))
            return sd_fail(c, LBK_ERR_BAD_INPUT, "material %zu: colours must be finite and >= 0", i);
    for (size_t i = 0; i < d->light_count; i++) {
        const lbk_bake_light *l = &d->lights[i];
        if ((unsigned)l->type > LBK_BAKE_LIGHT_DIRECTIONAL)
            return sd_fail(c, LBK_ERR_BAD_INPUT, "light %zu: unknown type %d", i, (int)l->type);
        if (!rgb_ok(l->color) || !finite_n(l->position, 3) || !finite_n(l->direction, 3) ||
            !(isfinite(l->range) && l->range >= 0))
            return sd_fail(c, LBK_ERR_BAD_INPUT, "light %zu: colour, position, direction and range must be finite (colour, range >= 0)", i);
        if (l->type == LBK_BAKE_LIGHT_SPOT &&
            !(l->inner_cone >= 0 && l->outer_cone > 0 && l->inner_cone <= l->outer_cone && l->outer_cone <= SD_PI / 2 + 1e-6))
            return sd_fail(c, LBK_ERR_BAD_INPUT, "light %zu: spot cone angles must satisfy 0 <= inner <= outer <= pi/2 (got %g, %g)",
                           i, l->inner_cone, l->outer_cone);
        if (l->light_set && l->light_set[0] && !valid_name(l->light_set))
            return sd_fail(c, LBK_ERR_BAD_INPUT, "light %zu: a light set name must be 1 to 63 printable bytes", i);
    }
    if (!rgb_ok(d->sky) || !(d->sky[0] < 1e30f && d->sky[1] < 1e30f && d->sky[2] < 1e30f))
        return sd_fail(c, LBK_ERR_BAD_INPUT, "sky radiance must be finite and >= 0");
    for (size_t i = 0; i < d->combination_count; i++)
        for (int k = 0; k < 2; k++) {
            const char *m = d->combinations[i][k];
            if (!m || !m[0] || strlen(m) > 63)
                return sd_fail(c, LBK_ERR_BAD_INPUT, "combination %zu: names must be 1 to 63 bytes", i);
        }
    return LBK_OK;
}

/* ---- conversion ---------------------------------------------------------------------------- */

static lbk_result fill_materials(sd_ctx *c, bk_scene *s)
{
    const lbk_bake_scene *d = c->d;
    s->materials = calloc(d->material_count ? d->material_count : 1, sizeof *s->materials);
    if (!s->materials) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < d->material_count; i++) {
        const lbk_bake_material *m = &d->materials[i];
        bk_material *bm = &s->materials[i];
        if (m->name) snprintf(bm->name, sizeof bm->name, "%s", m->name);
        else snprintf(bm->name, sizeof bm->name, "material%zu", i);
        for (int k = 0; k < 3; k++) {
            bm->albedo[k] = fminf(m->base_color[k], 1.0f);
            bm->emission[k] = m->emission[k];
        }
        if (m->base_color[0] > 1 || m->base_color[1] > 1 || m->base_color[2] > 1)
            bk_events_say(c->ev, LBK_BAKE_SEVERITY_WARNING, "material %zu '%s': base colour above 1 clamped", i, bm->name);
        bm->albedo_tex = bm->emission_tex = -1;
        bm->double_sided = m->double_sided ? 1 : 0;
    }
    s->material_count = d->material_count;
    return LBK_OK;
}

static void fill_object(sd_ctx *c, size_t i, bk_object *ob)
{
    const lbk_bake_scene *d = c->d;
    memset(ob, 0, sizeof *ob);
    for (int k = 0; k < 4; k++) ob->local_to_world[5 * k] = 1.0f;
    ob->has_uv1 = d->uv1 != NULL;
    if (!d->object_count) {
        snprintf(ob->name, sizeof ob->name, "%s", c->name);
        ob->tri_count = (uint32_t)d->triangle_count;
        return;
    }
    const lbk_bake_object *o = &d->objects[i];
    if (o->name) snprintf(ob->name, sizeof ob->name, "%s", o->name);
    else snprintf(ob->name, sizeof ob->name, "object%zu", i);
    ob->first_tri = o->first_triangle;
    ob->tri_count = o->triangle_count;
    ob->lighting = (int)o->lighting;
    ob->texel_density = o->texel_density;
    snprintf(ob->light_set, sizeof ob->light_set, "%s", opt_str(o->light_set));
    snprintf(ob->door, sizeof ob->door, "%s", opt_str(o->door));
}

/* The face normal of triangle t of s, as the importer repairs a missing normal. */
static void face_normal(const bk_scene *s, size_t t, float out[3])
{
    const uint32_t *v = &s->tris[3 * t];
    const float *P0 = &s->positions[3 * (size_t)v[0]], *P1 = &s->positions[3 * (size_t)v[1]],
                *P2 = &s->positions[3 * (size_t)v[2]];
    double e1[3], e2[3], fn[3];
    for (int q = 0; q < 3; q++) e1[q] = (double)P1[q] - P0[q], e2[q] = (double)P2[q] - P0[q];
    fn[0] = e1[1] * e2[2] - e1[2] * e2[1];
    fn[1] = e1[2] * e2[0] - e1[0] * e2[2];
    fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
    if (!normalize3(fn)) fn[0] = 0, fn[1] = 1, fn[2] = 0; /* zero-area triangle */
    for (int q = 0; q < 3; q++) out[q] = (float)fn[q];
}

/* Vertex `src` of the description as scene vertex `dst` (normal left zero when absent or unusable). */
static void copy_vertex(const lbk_bake_scene *d, uint32_t src, size_t dst, bk_scene *s)
{
    for (int k = 0; k < 3; k++) s->positions[3 * dst + k] = through_identity(d->positions[3 * (size_t)src + k]);
    float *nrm = &s->normals[3 * dst];
    nrm[0] = nrm[1] = nrm[2] = 0.0f;
    if (d->normals) {
        double n[3];
        for (int k = 0; k < 3; k++) n[k] = (double)d->normals[3 * (size_t)src + k] + 0.0;
        if (normalize3(n))
            for (int k = 0; k < 3; k++) nrm[k] = (float)n[k];
    }
    s->uv0[2 * dst] = s->uv0[2 * dst + 1] = 0.0f;
    s->uv1[2 * dst] = d->uv1 ? d->uv1[2 * (size_t)src] : 0.0f;
    s->uv1[2 * dst + 1] = d->uv1 ? d->uv1[2 * (size_t)src + 1] : 0.0f;
}

/* The distinct vertices object ob uses, ascending, into used[] (room for 3 per triangle);
 * returns their count. map: vertex_count entries, UINT32_MAX on entry and on return. */
static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static size_t used_vertices(const lbk_bake_scene *d, const bk_object *ob, uint32_t *map, uint32_t *used)
{
    size_t n = 0;
    for (size_t t = ob->first_tri; t < (size_t)ob->first_tri + ob->tri_count; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = d->indices[3 * t + k];
            if (map[v] == UINT32_MAX) map[v] = 0, used[n++] = v;
        }
    for (size_t i = 0; i < n; i++) map[used[i]] = UINT32_MAX;
    qsort(used, n, sizeof *used, cmp_u32);
    return n;
}

/* Object ob's vertices (from *v0 on) and triangles. Without normals every triangle gets its own
 * three vertices (flat shading, as the importer does); with normals the object gets its own copy
 * of the vertices it uses, in their order. map as for used_vertices; scratch: 3 per triangle. */
static void fill_geometry(const lbk_bake_scene *d, bk_object *ob, uint32_t obj, uint32_t material, uint32_t *map,
                          uint32_t *scratch, size_t *v0, bk_scene *s)
{
    const size_t first = ob->first_tri, n = ob->tri_count, base = *v0;
    if (!d->normals) {
        for (size_t t = first; t < first + n; t++)
            for (int k = 0; k < 3; k++) {
                copy_vertex(d, d->indices[3 * t + k], *v0, s);
                s->tris[3 * t + k] = (uint32_t)(*v0)++;
            }
    } else {
        size_t nu = used_vertices(d, ob, map, scratch);
        for (size_t i = 0; i < nu; i++) {
            copy_vertex(d, scratch[i], *v0, s);
            map[scratch[i]] = (uint32_t)(*v0)++;
        }
        for (size_t t = first; t < first + n; t++)
            for (int k = 0; k < 3; k++) s->tris[3 * t + k] = map[d->indices[3 * t + k]];
        for (size_t i = 0; i < nu; i++) map[scratch[i]] = UINT32_MAX;
    }
    for (size_t t = first; t < first + n; t++) {
        s->tri_material[t] = d->triangle_materials ? d->triangle_materials[t] : material;
        s->tri_object[t] = obj;
        /* a missing or unusable normal becomes the face normal of the first triangle using it */
        for (int k = 0; k < 3; k++) {
            float *nrm = &s->normals[3 * (size_t)s->tris[3 * t + k]];
            if (nrm[0] == 0.0f && nrm[1] == 0.0f && nrm[2] == 0.0f) face_normal(s, t, nrm);
        }
    }
    /* the object's local geometry, as import hashes a mesh: its positions and local indices */
    for (size_t i = 0; i < 3 * n; i++) scratch[i] = s->tris[3 * first + i] - (uint32_t)base;
    ob->geometry_hash = bk_geometry_hash(&s->positions[3 * base], *v0 - base, scratch, 3 * n);
}

static lbk_result fill_objects(sd_ctx *c, bk_scene *s)
{
    const lbk_bake_scene *d = c->d;
    const size_t no = d->object_count ? d->object_count : 1, nt = d->triangle_count;
    s->objects = calloc(no, sizeof *s->objects);
    s->tris = malloc(3 * (nt ? nt : 1) * sizeof *s->tris);
    s->tri_material = malloc((nt ? nt : 1) * sizeof *s->tri_material);
    s->tri_object = malloc((nt ? nt : 1) * sizeof *s->tri_object);
    uint32_t *map = malloc((d->vertex_count ? d->vertex_count : 1) * sizeof *map);
    uint32_t *scratch = malloc(3 * (nt ? nt : 1) * sizeof *scratch);
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (!s->objects || !s->tris || !s->tri_material || !s->tri_object || !map || !scratch) goto done;
    for (size_t v = 0; v < d->vertex_count; v++) map[v] = UINT32_MAX;
    for (size_t i = 0; i < no; i++) fill_object(c, i, &s->objects[i]);
    size_t nv = 3 * nt; /* flat: three per triangle; else each object's own copies */
    if (d->normals) {
        nv = 0;
        for (size_t i = 0; i < no; i++) nv += used_vertices(d, &s->objects[i], map, scratch);
    }
    s->positions = malloc(3 * (nv ? nv : 1) * sizeof(float));
    s->normals = malloc(3 * (nv ? nv : 1) * sizeof(float));
    s->uv0 = malloc(2 * (nv ? nv : 1) * sizeof(float));
    s->uv1 = malloc(2 * (nv ? nv : 1) * sizeof(float));
    if (!s->positions || !s->normals || !s->uv0 || !s->uv1) goto done;
    size_t v0 = 0;
    for (size_t i = 0; i < no; i++) {
        uint32_t material = d->object_count ? d->objects[i].material : 0;
        fill_geometry(d, &s->objects[i], (uint32_t)i, material, map, scratch, &v0, s);
    }
    s->object_count = no;
    s->tri_count = nt;
    s->vertex_count = v0;
    r = LBK_OK;
done:
    free(map), free(scratch);
    return r;
}

static lbk_result fill_lights(sd_ctx *c, bk_scene *s)
{
    const lbk_bake_scene *d = c->d;
    s->lights = calloc(d->light_count ? d->light_count : 1, sizeof *s->lights);
    if (!s->lights) return LBK_ERR_OUT_OF_MEMORY;
    size_t n = 0;
    for (size_t i = 0; i < d->light_count; i++) {
        const lbk_bake_light *l = &d->lights[i];
        bk_light *bl = &s->lights[n];
        memset(bl, 0, sizeof *bl);
        if (l->name) snprintf(bl->name, sizeof bl->name, "%s", l->name);
        else snprintf(bl->name, sizeof bl->name, "light%zu", i);
        bl->type = l->type == LBK_BAKE_LIGHT_SPOT ? BK_LIGHT_SPOT
                   : l->type == LBK_BAKE_LIGHT_DIRECTIONAL ? BK_LIGHT_DIRECTIONAL : BK_LIGHT_POINT;
        memcpy(bl->color, l->color, sizeof bl->color);
        bl->range = l->range;
        if (bl->type == BK_LIGHT_SPOT) {
            bl->inner_cone = l->inner_cone;
            bl->outer_cone = (float)fmin(l->outer_cone, SD_PI / 2);
        }
        double dir[3];
        for (int k = 0; k < 3; k++) bl->position[k] = through_identity(l->position[k]), dir[k] = (double)l->direction[k] + 0.0;
        if (!normalize3(dir)) {
            if (bl->type != BK_LIGHT_POINT) {
                bk_events_say(c->ev, LBK_BAKE_SEVERITY_WARNING, "light %zu '%s': no direction; light skipped", i, bl->name);
                continue;
            }
            dir[0] = 0, dir[1] = 0, dir[2] = -1; /* what a point light's identity node frame gives */
        }
        for (int k = 0; k < 3; k++) bl->direction[k] = (float)dir[k];
        snprintf(bl->light_set, sizeof bl->light_set, "%s", opt_str(l->light_set));
        n++;
    }
    s->light_count = n;
    return LBK_OK;
}

static lbk_result fill_combinations(sd_ctx *c, bk_scene *s)
{
    const lbk_bake_scene *d = c->d;
    s->combinations = calloc(d->combination_count ? d->combination_count : 1, sizeof *s->combinations);
    if (!s->combinations) return LBK_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < d->combination_count; i++)
        for (int k = 0; k < 2; k++)
            snprintf(s->combinations[i].members[k], sizeof s->combinations[i].members[k], "%s", d->combinations[i][k]);
    s->combination_count = d->combination_count;
    return LBK_OK;
}

static void hash_str(XXH3_state_t *h, const char *s)
{
    s = opt_str(s);
    XXH3_64bits_update(h, s, strlen(s) + 1);
}

/* The provenance hash: XXH3-64 over every array and field of the description, in order. */
static uint64_t desc_hash(const lbk_bake_scene *d)
{
    XXH3_state_t h;
    XXH3_INITSTATE(&h);
    XXH3_64bits_reset(&h);
    XXH3_64bits_update(&h, d->positions, 3 * d->vertex_count * sizeof(float));
    if (d->normals) XXH3_64bits_update(&h, d->normals, 3 * d->vertex_count * sizeof(float));
    if (d->uv1) XXH3_64bits_update(&h, d->uv1, 2 * d->vertex_count * sizeof(float));
    XXH3_64bits_update(&h, d->indices, 3 * d->triangle_count * sizeof(uint32_t));
    if (d->triangle_materials) XXH3_64bits_update(&h, d->triangle_materials, d->triangle_count * sizeof(uint32_t));
    for (size_t i = 0; i < d->material_count; i++) {
        const lbk_bake_material *m = &d->materials[i];
        int32_t ds = m->double_sided != 0;
        hash_str(&h, m->name);
        XXH3_64bits_update(&h, m->base_color, sizeof m->base_color);
        XXH3_64bits_update(&h, m->emission, sizeof m->emission);
        XXH3_64bits_update(&h, &ds, sizeof ds);
    }
    for (size_t i = 0; i < d->object_count; i++) {
        const lbk_bake_object *o = &d->objects[i];
        uint32_t u[4] = {o->first_triangle, o->triangle_count, o->material, (uint32_t)o->lighting};
        hash_str(&h, o->name);
        XXH3_64bits_update(&h, u, sizeof u);
        XXH3_64bits_update(&h, &o->texel_density, sizeof o->texel_density);
        hash_str(&h, o->light_set);
        hash_str(&h, o->door);
    }
    for (size_t i = 0; i < d->light_count; i++) {
        const lbk_bake_light *l = &d->lights[i];
        float f[12] = {l->color[0], l->color[1], l->color[2], l->position[0], l->position[1], l->position[2],
                       l->direction[0], l->direction[1], l->direction[2], l->range, l->inner_cone, l->outer_cone};
        uint32_t type = (uint32_t)l->type;
        hash_str(&h, l->name);
        XXH3_64bits_update(&h, &type, sizeof type);
        XXH3_64bits_update(&h, f, sizeof f);
        hash_str(&h, l->light_set);
    }
    XXH3_64bits_update(&h, d->sky, sizeof d->sky);
    for (size_t i = 0; i < d->combination_count; i++) hash_str(&h, d->combinations[i][0]), hash_str(&h, d->combinations[i][1]);
    return XXH3_64bits_digest(&h);
}

lbk_result bk_scene_from_desc(const lbk_bake_scene *desc, const bk_events *ev, bk_scene *out, char *err, size_t err_len)
{
    memset(out, 0, sizeof *out);
    out->sky_image = -1;
    lbk_bake_scene d;
    memset(&d, 0, sizeof d);
    size_t n = desc->size ? desc->size : SD_SIZE_V1;
    sd_ctx c = {&d, ev, desc->name && desc->name[0] ? desc->name : "scene", err, err_len};
    if (n < sizeof desc->size) return sd_fail(&c, LBK_ERR_INVALID_ARGUMENT, "lbk_bake_scene.size %zu is too small", n);
    memcpy(&d, desc, n < sizeof d ? n : sizeof d);
    for (size_t i = sizeof d; i < n; i++)
        if (((const unsigned char *)desc)[i])
            return sd_fail(&c, LBK_ERR_INVALID_ARGUMENT, "lbk_bake_scene: a field this library does not know is set");
    lbk_result r = check_arrays(&c);
    if (!r) r = check_objects(&c);
    if (!r) r = check_tables(&c);
    if (!r) r = fill_materials(&c, out);
    if (!r) r = fill_objects(&c, out);
    if (!r) r = fill_lights(&c, out);
    if (!r) r = fill_combinations(&c, out);
    if (r) {
        bk_scene_free(out);
        return r;
    }
    memcpy(out->sky, d.sky, sizeof out->sky);
    out->source_hash = desc_hash(&d);
    bk_scene_compute_bounds(out);
    return LBK_OK;
}
