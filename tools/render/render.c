/* lbk render: the camera, the pixel loop and the output (see render.h). */
#include "tools/render/render.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/parallel.h"
#include "tools/common/error_util.h"
#include "tools/render/level.h"
#include "tools/render/seams.h"

typedef struct view {
    float from[3], right[3], up[3], forward[3]; /* orthonormal camera frame */
    float half_h, half_w;                      /* tan of the half angles */
} view;

static void cross3(const float a[3], const float b[3], float o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1], o[1] = a[2] * b[0] - a[0] * b[2], o[2] = a[0] * b[1] - a[1] * b[0];
}

static int unit3(float v[3])
{
    const float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 1e-20f) || !isfinite(l)) return -1;
    v[0] /= l, v[1] /= l, v[2] /= l;
    return 0;
}

static int make_view(const tl_camera *c, int w, int h, view *v)
{
    for (int k = 0; k < 3; k++) v->from[k] = c->from[k], v->forward[k] = c->at[k] - c->from[k];
    if (unit3(v->forward)) return -1;
    cross3(v->forward, c->up, v->right);
    if (unit3(v->right)) return -1;
    cross3(v->right, v->forward, v->up);
    v->half_h = tanf(0.5f * c->yfov);
    v->half_w = v->half_h * (float)w / (float)h;
    return 0;
}

/* The default camera: inside the level's bounds, near their +z side at mid height, looking at
 * the centre (an interior); when that spot is inside a closed object (the first surface towards
 * the centre shows its back), outside the bounds at +z instead, far enough to see them whole.
 * 60° vertical field of view. */
static void default_camera(const rl_level *L, tl_camera *c)
{
    const bk_scene *s = &L->scene;
    float ext[3], r = 0.0f;
    for (int k = 0; k < 3; k++) {
        c->at[k] = 0.5f * (s->bounds_min[k] + s->bounds_max[k]);
        ext[k] = s->bounds_max[k] - s->bounds_min[k];
        r += 0.25f * ext[k] * ext[k];
    }
    memcpy(c->from, c->at, sizeof c->from);
    c->from[2] += 0.45f * ext[2];
    c->up[0] = 0, c->up[1] = 1, c->up[2] = 0;
    c->yfov = 60.0f * 3.14159265f / 180.0f;
    const float d[3] = {0, 0, -1};
    bk_hit h;
    if (bk_tracer_intersect(L->tracer, c->from, d, 0.0f, INFINITY, &h) && !h.front)
        c->from[2] = c->at[2] + 2.0f * sqrtf(r); /* the bounding sphere fills about 60° */
}

/* Closest test sphere along the ray before tmax; -1 if none. */
static int hit_spheres(const tl_render_options *o, const float org[3], const float d[3], float *tmax)
{
    int best = -1;
    for (size_t i = 0; i < o->sphere_count; i++) {
        const tl_sphere *s = &o->spheres[i];
        const float oc[3] = {org[0] - s->centre[0], org[1] - s->centre[1], org[2] - s->centre[2]};
        const float b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
        const float disc = b * b - (oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - s->radius * s->radius);
        if (disc < 0) continue;
        const float t = -b - sqrtf(disc);
        if (t > 0 && t < *tmax) *tmax = t, best = (int)i;
    }
    return best;
}

/* The first visible surface along a primary ray: the scene (skipping hidden objects: open doors)
 * or a test sphere. 0 when the ray leaves the level. */
static int trace(const rl_level *L, const tl_render_options *o, const float org[3], const float d[3], rl_hit *h)
{
    float tmin = 0.0f, tmax = INFINITY;
    bk_hit bh;
    int scene_hit;
    while ((scene_hit = bk_tracer_intersect(L->tracer, org, d, tmin, INFINITY, &bh)) &&
           L->hidden[L->scene.tri_object[bh.tri]])
        tmin = bh.t * (1.0f + 1e-6f) + 1e-6f;
    if (scene_hit) tmax = bh.t;
    h->sphere = hit_spheres(o, org, d, &tmax);
    if (!scene_hit && h->sphere < 0) return 0;
    if (h->sphere < 0) h->tri = bh.tri, h->u = bh.u, h->v = bh.v, h->front = bh.front;
    for (int k = 0; k < 3; k++) h->p[k] = org[k] + tmax * d[k], h->dir[k] = d[k];
    return 1;
}

typedef struct job {
    const rl_level *L;
    const tl_render_options *o;
    view v;
    tl_image *img;
    rl_gbuffer *gbuf;
    uint32_t hints[BK_MAX_THREADS]; /* one GLG walk hint per thread */
} job;

/* The unit direction through image point (px, py) in pixels, (0, 0) the top-left corner. */
static void ray_dir(const view *v, int w, int h, float px, float py, float d[3])
{
    const float sx = (2.0f * px / (float)w - 1.0f) * v->half_w, sy = (1.0f - 2.0f * py / (float)h) * v->half_h;
    for (int k = 0; k < 3; k++) d[k] = v->forward[k] + sx * v->right[k] + sy * v->up[k];
    unit3(d);
}

/* Rows [y0, y1): n × n stratified rays per pixel (stratum centres: deterministic), box filter. */
static void render_rows(void *user, size_t y0, size_t y1, int thread)
{
    job *j = user;
    const int w = j->img->width, h = j->img->height, n = j->o->samples;
    for (size_t y = y0; y < y1; y++)
        for (int x = 0; x < w; x++) {
            float sum[3] = {0, 0, 0};
            for (int s = 0; s < n * n; s++) {
                float d[3], rgb[3];
                ray_dir(&j->v, w, h, (float)x + ((float)(s % n) + 0.5f) / (float)n,
                        (float)y + ((float)(s / n) + 0.5f) / (float)n, d);
                rl_hit hit;
                if (trace(j->L, j->o, j->v.from, d, &hit)) rl_shade(j->L, j->o, &hit, &j->hints[thread], rgb);
                else rl_sky(j->L, d, rgb);
                for (int c = 0; c < 3; c++) sum[c] += rgb[c];
            }
            for (int c = 0; c < 3; c++) j->img->rgb[3 * ((size_t)y * (size_t)w + (size_t)x) + (size_t)c] = sum[c] / (float)(n * n);
            if (j->gbuf) { /* the pixel centre's hit, for the seam mask */
                const size_t i = y * (size_t)w + (size_t)x;
                float d[3];
                ray_dir(&j->v, w, h, (float)x + 0.5f, (float)y + 0.5f, d);
                j->gbuf->valid[i] = (unsigned char)trace(j->L, j->o, j->v.from, d, &j->gbuf->hit[i]);
            }
        }
}

int tl_render(const char *scene_path, const char *lbk_path, const tl_render_options *options, tl_image *out,
              char err[TL_ERR_LEN])
{
    memset(out, 0, sizeof *out);
    tl_render_options o = *options;
    o.width = o.width > 0 ? o.width : 160;
    o.height = o.height > 0 ? o.height : 120;
    o.samples = o.samples > 0 ? o.samples : 2;
    if (o.width > 16384 || o.height > 16384 || o.samples > 64)
        return tl_fail(err, TL_RENDER_USAGE, "image or samples too large (16384 pixels a side, 64 samples per axis)");
    for (size_t i = 0; i < o.sphere_count; i++)
        if (!(o.spheres[i].radius > 0)) return tl_fail(err, TL_RENDER_USAGE, "probe sphere %zu: radius must be > 0", i);
    rl_level L;
    int rc = rl_level_load(scene_path, lbk_path, &o, &L, err);
    if (rc) return rc;
    if (!(o.camera.yfov > 0)) default_camera(&L, &o.camera);
    job *j = calloc(1, sizeof *j);
    const size_t np = (size_t)o.width * (size_t)o.height;
    out->width = o.width, out->height = o.height;
    out->rgb = malloc(3 * np * sizeof *out->rgb);
    if (!j || !out->rgb || (o.seams && !(j->gbuf = rl_gbuffer_create(np))))
        rc = tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    if (!rc && (!(o.camera.yfov < 3.1f) || make_view(&o.camera, o.width, o.height, &j->v)))
        rc = tl_fail(err, TL_RENDER_USAGE, "degenerate camera: from = at, up along the view, or a field of view outside (0, 178°)");
    if (!rc) {
        j->L = &L, j->o = &o, j->img = out;
        bk_parallel_chunks(0, (size_t)o.height, 1, bk_thread_count(o.threads), render_rows, j);
        if (j->gbuf && rl_seams(j->gbuf, &L, o.width, o.height, 2.0f * j->v.half_h / (float)o.height, j->v.from, out))
            rc = tl_fail(err, TL_RENDER_INTERNAL, "out of memory");
    }
    if (j) rl_gbuffer_free(j->gbuf);
    free(j);
    rl_level_free(&L);
    if (rc) tl_image_free(out);
    return rc;
}

void tl_image_free(tl_image *image)
{
    free(image->rgb), free(image->seam), free(image->lightmapped);
    memset(image, 0, sizeof *image);
}

int tl_image_write(const tl_image *im, const char *exr_path, const char *png_path, char err[TL_ERR_LEN])
{
    static const char *const names[3] = {"R", "G", "B"};
    const size_t np = (size_t)im->width * (size_t)im->height;
    if (exr_path && tl_exr_write(exr_path, im->width, im->height, 3, names, im->rgb, err)) return -1;
    if (!png_path) return 0;
    uint8_t *rgb8 = malloc(3 * np + 1);
    if (!rgb8) return tl_fail(err, -1, "out of memory");
    tl_tonemap(im->rgb, np, 3, tl_exposure_p99(im->rgb, np, 3), rgb8);
    int rc = tl_png_write_rgb8(png_path, im->width, im->height, rgb8, err);
    free(rgb8);
    return rc;
}

int tl_image_write_seams(const tl_image *im, const char *exr_path, char err[TL_ERR_LEN])
{
    static const char *const names[2] = {"lightmapped", "seam"};
    const size_t np = (size_t)im->width * (size_t)im->height;
    if (!im->seam || !im->lightmapped) return tl_fail(err, -1, "the image was rendered without seams");
    float *px = malloc(2 * np * sizeof *px + 1);
    if (!px) return tl_fail(err, -1, "out of memory");
    for (size_t i = 0; i < np; i++) px[2 * i] = im->lightmapped[i], px[2 * i + 1] = im->seam[i];
    int rc = tl_exr_write(exr_path, im->width, im->height, 2, names, px, err);
    free(px);
    return rc;
}
