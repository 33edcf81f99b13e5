/* The import phase: the glTF file (scene/import.h) or the caller's scene description
 * (scene_desc.c), the desc's sky, the inputs a distributed plan expects, what every scene must
 * have, and the frame centred on the level. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/pipeline/pipeline.h"
#include "bake/pipeline/provenance.h"
#include "bake/pipeline/scene_desc.h"
#include "scene/exr_read.h"
#include "scene/import.h"

static void import_warning(void *user, const char *message)
{
    bk_pipeline *b = user;
    bk_events_say(&b->events, LBK_BAKE_SEVERITY_WARNING, "%s", message);
}

static lbk_result import_file(bk_pipeline *b, const char *path)
{
    bk_import_options io;
    memset(&io, 0, sizeof io);
    io.warn = import_warning;
    io.warn_user = b;
    io.allow_outside = b->opt->allow_outside;
    io.recentre = 1;
    FILE *probe = fopen(path, "rb");
    if (!probe) return bk_pipeline_fail(b, LBK_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    fclose(probe);
    char msg[512];
    if (bk_import_gltf(path, &io, &b->scene, msg, sizeof msg)) return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s", msg);
    return LBK_OK;
}

/* The desc's sky, when it overrides the scene's: a uniform radiance or an EXR. */
static lbk_result apply_sky(bk_pipeline *b)
{
    if (!b->opt->sky_override) return LBK_OK;
    if (!b->opt->sky_exr) {
        memcpy(b->scene.sky, b->opt->sky, sizeof b->scene.sky);
        b->scene.sky_image = -1;
        return LBK_OK;
    }
    char msg[512];
    bk_image im;
    memset(&im, 0, sizeof im);
    if (bk_exr_read(b->opt->sky_exr, (size_t)64 << 20, &im, msg, sizeof msg))
        return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "sky: %s", msg);
    if (bk_provenance_add_file(&b->scene, b->opt->sky_exr, "sky")) {
        free(im.rgba);
        return bk_pipeline_fail(b, LBK_ERR_IO, "sky: %s: cannot read it again to hash it", b->opt->sky_exr);
    }
    bk_image *n = realloc(b->scene.images, (b->scene.image_count + 1) * sizeof *n);
    if (!n) {
        free(im.rgba);
        return bk_pipeline_fail(b, LBK_ERR_OUT_OF_MEMORY, "out of memory");
    }
    b->scene.images = n;
    b->scene.images[b->scene.image_count] = im;
    b->scene.sky_image = (int)b->scene.image_count++;
    b->scene.sky[0] = b->scene.sky[1] = b->scene.sky[2] = 0;
    return LBK_OK;
}

/* A scene whose every triangle has zero area would bake to an empty container: refuse it. */
static int has_triangle_with_area(const bk_scene *s)
{
    for (size_t t = 0; t < s->tri_count; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++) p[k] = s->positions + 3 * (size_t)s->tris[3 * t + k];
        double e1[3], e2[3];
        for (int c = 0; c < 3; c++) e1[c] = (double)p[1][c] - p[0][c], e2[c] = (double)p[2][c] - p[0][c];
        double n0 = e1[1] * e2[2] - e1[2] * e2[1], n1 = e1[2] * e2[0] - e1[0] * e2[2], n2 = e1[0] * e2[1] - e1[1] * e2[0];
        if (n0 * n0 + n1 * n1 + n2 * n2 > 0) return 1;
    }
    return 0;
}

/* A level far from the origin (1e5 m) leaves floats a 7.8 mm step there, and ray offsets scale
 * with coordinate magnitude (~6 cm), which brightened such a level by 20 % (test_extremes).
 * So the bake runs in a frame centred on the level, and every stored position gets the origin
 * added back. The importer already chose the frame in double precision (bk_scene.origin); this
 * is for scenes given as floats (lbk_bake_from_scene). The shift is an integer number of metres, along each axis where the level lies
 * farther from the origin than twice its extent: then every p − c is exact in float (Sterbenz),
 * and so is p − c + c, so geometry hashes and written positions are unchanged. */
static void recentre(bk_pipeline *b)
{
    bk_scene *s = &b->scene;
    double extent = 0, c[3];
    int any = 0;
    for (int k = 0; k < 3; k++) extent = fmax(extent, (double)s->bounds_max[k] - s->bounds_min[k]);
    for (int k = 0; k < 3; k++) {
        /* per axis, so a level near the origin along an axis keeps its coordinates there */
        double mid = 0.5 * ((double)s->bounds_min[k] + s->bounds_max[k]);
        c[k] = isfinite(mid) && fabs(mid) > 2 * extent ? nearbyint(mid) : 0;
        any |= c[k] != 0;
    }
    for (int k = 0; k < 3; k++) b->origin[k] = (float)(s->origin[k] + c[k]); /* integers below 2^24: exact */
    if (!any) return;
    for (size_t v = 0; v < s->vertex_count; v++)
        for (int k = 0; k < 3; k++) s->positions[3 * v + k] = (float)((double)s->positions[3 * v + k] - c[k]);
    for (size_t i = 0; i < s->light_count; i++)
        for (int k = 0; k < 3; k++) s->lights[i].position[k] = (float)((double)s->lights[i].position[k] - c[k]);
    for (size_t i = 0; i < s->playable_count; i++)
        for (int k = 0; k < 3; k++) {
            s->playable[i].min[k] = (float)((double)s->playable[i].min[k] - c[k]);
            s->playable[i].max[k] = (float)((double)s->playable[i].max[k] - c[k]);
        }
    for (int k = 0; k < 3; k++) {
        s->bounds_min[k] = (float)((double)s->bounds_min[k] - c[k]);
        s->bounds_max[k] = (float)((double)s->bounds_max[k] - c[k]);
        s->origin[k] += c[k];
    }
}

void bk_pipeline_to_world(const bk_pipeline *b, const float local[3], float world[3])
{
    for (int k = 0; k < 3; k++) world[k] = local[k] + b->origin[k];
}

/* What every scene must have, however it came in. */
static lbk_result check_scene(bk_pipeline *b)
{
    if (b->scene.tri_count == 0) return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s: the scene has no triangles", b->input);
    if (!has_triangle_with_area(&b->scene))
        return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s: all %zu triangles are degenerate (zero area): nothing to light",
                                b->input, b->scene.tri_count);
    recentre(b);
    if (!bk_scene_has_light(&b->scene))
        return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT,
                                "%s: the scene has no light: no KHR_lights_punctual light, no emissive material "
                                "and no sky (add one, or give the bake a sky: lbk bake --sky R,G,B)",
                                b->input);
    return bk_pipeline_checkpoint(b, 1);
}

/* desc.expect_inputs: the files must be the ones listed, byte for byte (a distributed bake's
 * units and merge against the plan). Only what the import itself read is compared: no path of
 * the list is ever opened. */
static lbk_result check_inputs(bk_pipeline *b)
{
    const lbk_bake_input *want = b->opt->expect_inputs;
    if (!want) return LBK_OK;
    const size_t n = b->opt->expect_input_count, got = b->scene.input_count;
    for (size_t i = 0; i < n || i < got; i++) {
        const bk_input_file *f = i < got ? &b->scene.inputs[i] : NULL;
        const lbk_bake_input *w = i < n ? &want[i] : NULL;
        if (!f)
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "the bake read %zu files, the plan lists %zu (%s '%.200s' was not "
                                    "read): the scene changed since the plan was made; make a new plan", got, n, w->role,
                                    w->path);
        if (!w)
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s '%.200s' is not among the %zu files the plan lists: the scene "
                                    "changed since the plan was made; make a new plan", f->role, f->path, n);
        if (strncmp(f->path, w->path, sizeof w->path) || strncmp(f->role, w->role, sizeof w->role))
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "file %zu read is %s '%.200s', the plan lists %s '%.200s': the scene "
                                    "changed since the plan was made; make a new plan", i + 1, f->role, f->path, w->role,
                                    w->path);
        if (f->bytes != w->bytes || f->hash != w->xxh3)
            return bk_pipeline_fail(b, LBK_ERR_BAD_INPUT, "%s '%.200s' changed since the plan was made (%llu bytes, XXH3 "
                                    "%016llx; the plan's: %llu bytes, %016llx): make a new plan", f->role, f->path,
                                    (unsigned long long)f->bytes, (unsigned long long)f->hash,
                                    (unsigned long long)w->bytes, (unsigned long long)w->xxh3);
    }
    return LBK_OK;
}

lbk_result bk_phase_import(bk_pipeline *b, const char *path, const lbk_bake_scene *desc)
{
    lbk_result r = bk_pipeline_phase(b, LBK_BAKE_PHASE_IMPORT);
    if (r) return r;
    if (path) {
        r = import_file(b, path);
    } else {
        r = bk_scene_from_desc(desc, &b->events, &b->scene, b->err, sizeof b->err);
        if (r == LBK_ERR_OUT_OF_MEMORY) bk_pipeline_fail(b, r, "out of memory");
    }
    if (!r) r = apply_sky(b);
    if (!r) r = check_inputs(b);
    if (!r) r = check_scene(b);
    return r;
}
