/* Shading one hit: what a pixel shader does with lbk's data (see render.h). Irradiance E comes
 * from the object's representation; a Lambert surface sends L = albedo · E / π + emission. */
#include <math.h>
#include <string.h>

#include "tools/render/level.h"

#define PI_F 3.14159265358979f

static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void normalize3(float v[3])
{
    const float l = sqrtf(dot3(v, v));
    if (l > 0.0f) v[0] /= l, v[1] /= l, v[2] /= l;
}

/* The hit's barycentric weight of corner c. */
static float bary(const rl_hit *h, int c) { return c == 0 ? 1.0f - h->u - h->v : c == 1 ? h->u : h->v; }

/* Nearest texel of a texture at uv (repeat), as the bake sampled it. */
static void texture(const bk_scene *s, int image, const float uv[2], float rgb[3])
{
    const bk_image *im = &s->images[image];
    const float fu = uv[0] - floorf(uv[0]), fv = uv[1] - floorf(uv[1]);
    int x = (int)(fu * (float)im->width), y = (int)(fv * (float)im->height);
    x = x < 0 ? 0 : x >= im->width ? im->width - 1 : x;
    y = y < 0 ? 0 : y >= im->height ? im->height - 1 : y;
    for (int c = 0; c < 3; c++) rgb[c] *= im->rgba[4 * ((size_t)y * (size_t)im->width + (size_t)x) + (size_t)c];
}

/* A texture at uv filtered bilinearly between the four nearest texel centres, wrapping (repeat),
 * as a GPU samples a normal map: nearest texels would turn every bump into flat facets. */
static void texture_bilinear(const bk_scene *s, int image, const float uv[2], float rgb[3])
{
    const bk_image *im = &s->images[image];
    const float fx = (uv[0] - floorf(uv[0])) * (float)im->width - 0.5f, fy = (uv[1] - floorf(uv[1])) * (float)im->height - 0.5f;
    const float x0 = floorf(fx), y0 = floorf(fy), ax = fx - x0, ay = fy - y0;
    float acc[3] = {0, 0, 0};
    for (int k = 0; k < 4; k++) {
        const float w = (k & 1 ? ax : 1.0f - ax) * (k & 2 ? ay : 1.0f - ay);
        long x = (long)x0 + (k & 1), y = (long)y0 + ((k >> 1) & 1);
        x = ((x % im->width) + im->width) % im->width;
        y = ((y % im->height) + im->height) % im->height;
        const float *t = &im->rgba[4 * ((size_t)y * (size_t)im->width + (size_t)x)];
        for (int c = 0; c < 3; c++) acc[c] += w * t[c];
    }
    for (int c = 0; c < 3; c++) rgb[c] *= acc[c];
}

void rl_sky(const rl_level *L, const float d[3], float rgb[3])
{
    if (L->scene.sky_image < 0) {
        memcpy(rgb, L->sky, 3 * sizeof(float));
        return;
    }
    /* the equirectangular mapping of scene/scene.h */
    const float uv[2] = {0.5f + atan2f(d[0], -d[2]) / (2.0f * PI_F), acosf(fmaxf(-1.0f, fminf(1.0f, d[1]))) / PI_F};
    rgb[0] = rgb[1] = rgb[2] = 1.0f;
    texture(&L->scene, L->scene.sky_image, uv, rgb);
}

/* ---- normal maps --------------------------------------------------------------------------- */

static void cross3(const float a[3], const float b[3], float o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* The shading normal of a normal-mapped material at the hit (glTF 2.0 §3.9.3): the normal
 * texture at uv0 (bilinear, repeat: texture_bilinear) read as a tangent-space normal
 * t = ((2r − 1)·scale, (2g − 1)·scale, 2b − 1) and taken to world space in the interpolated frame
 * T (made orthogonal to N), B = w·(N × T), N. Where the material has no normal map, or the result
 * is degenerate, ns = N. */
static void shading_normal(const bk_scene *s, const bk_material *m, const rl_hit *h, const float N[3],
                           const float uv0[2], float ns[3])
{
    memcpy(ns, N, 3 * sizeof(float));
    if (!m->normal_tex1 || !s->tangents) return;
    const uint32_t *v = &s->tris[3 * (size_t)h->tri];
    float T[3] = {0, 0, 0}, B[3], w = 0.0f, rgb[3] = {1, 1, 1};
    for (int c = 0; c < 3; c++) {
        const float *t = &s->tangents[4 * (size_t)v[c]];
        for (int k = 0; k < 3; k++) T[k] += bary(h, c) * t[k];
        w += bary(h, c) * t[3];
    }
    const float d = dot3(T, N);
    for (int k = 0; k < 3; k++) T[k] -= d * N[k];
    normalize3(T);
    cross3(N, T, B);
    for (int k = 0; k < 3; k++) B[k] *= w < 0.0f ? -1.0f : 1.0f;
    texture_bilinear(s, m->normal_tex1 - 1, uv0, rgb);
    const float x = (2.0f * rgb[0] - 1.0f) * m->normal_scale, y = (2.0f * rgb[1] - 1.0f) * m->normal_scale,
                z = 2.0f * rgb[2] - 1.0f;
    float n[3];
    for (int k = 0; k < 3; k++) n[k] = x * T[k] + y * B[k] + z * N[k];
    if (!(dot3(n, n) > 1e-12f) || !(dot3(T, T) > 0.5f)) return;
    normalize3(n);
    memcpy(ns, n, sizeof n);
}

/* v turned by the rotation that takes unit a to unit b (the smallest one, about a × b): what a
 * normal map does to the direction an LLG vertex record's bent normal gives for N. */
static void rotate_like(const float a[3], const float b[3], const float v[3], float out[3])
{
    const float c = dot3(a, b);
    if (c <= -0.999f) { /* a normal map pointing against N: no defined turn, use ns itself */
        memcpy(out, b, 3 * sizeof(float));
        return;
    }
    float k[3], kv[3];
    cross3(a, b, k);
    cross3(k, v, kv);
    const float f = dot3(k, v) / (1.0f + c);
    for (int i = 0; i < 3; i++) out[i] = v[i] * c + kv[i] + k[i] * f;
}

/* ---- lightmaps ------------------------------------------------------------------------------ */

int rl_hit_coord(const rl_level *L, const rl_hit *h, uint32_t *page, float coord[2])
{
    if (h->sphere >= 0) return 0;
    const lbk_object *ob = &L->objects[L->scene.tri_object[h->tri]];
    if (ob->representation != LBK_REPRESENTATION_LIGHTMAP) return 0;
    const float *cc = &L->corner_coord[6 * (size_t)h->tri];
    for (int a = 0; a < 2; a++) coord[a] = bary(h, 0) * cc[a] + bary(h, 1) * cc[2 + a] + bary(h, 2) * cc[4 + a];
    *page = ob->index;
    return 1;
}

/* The page at lightmap coordinate (X, Y), filtered bilinearly between the four nearest texel
 * centres (x + ½, y + ½: spec §16.1). The blend is done in AHD's linear form, where it is exact
 * (lbk/ahd.h); a GPU filters the two planes as textures instead, which differs slightly where the
 * four texels' directions differ. Charts carry a dilated margin, so the filter never reads another
 * object's texels. Physical units: × the section's scale. */
static void sample_page(const rl_level *L, uint32_t page, const float coord[2], lbk_ahd_linear *out)
{
    const lbk_lmap_page *pg = &L->pages[page];
    const float fx = coord[0] - 0.5f, fy = coord[1] - 0.5f;
    const float x0 = floorf(fx), y0 = floorf(fy), ax = fx - x0, ay = fy - y0;
    memset(out, 0, sizeof *out);
    for (int k = 0; k < 4; k++) {
        const float w = (k & 1 ? ax : 1.0f - ax) * (k & 2 ? ay : 1.0f - ay);
        if (w == 0.0f) continue;
        const float xf = fminf(fmaxf(x0 + (float)(k & 1), 0.0f), (float)pg->width - 1.0f);
        const float yf = fminf(fmaxf(y0 + (float)((k >> 1) & 1), 0.0f), (float)pg->height - 1.0f);
        const uint64_t i = pg->first_texel + (uint64_t)yf * pg->width + (uint64_t)xf;
        lbk_ahd_linear lin;
        if (L->texel_f) {
            lbk_ahd_texel_f_to_linear(&L->texel_f[i], &lin);
        } else {
            lbk_ahd_texel t = {L->texel_ez[i], {0}};
            memcpy(t.rgba, &L->texel_rgba[4 * i], 4);
            lbk_ahd_to_linear(&t, &lin);
        }
        lbk_ahd_linear_add_scaled(out, &lin, w * L->bake.lmap.scale);
    }
}

/* Irradiance of a lightmapped surface for the shading normal ns. The texel's highlight direction
 * lives in the tangent frame of spec §5.6: N = the interpolated normal, T = dP/dX of the triangle's
 * lightmap coordinates made orthogonal to N, B = N × T (not the normal map's frame: that one is
 * along uv0). A normal-mapped surface passes its perturbed normal as ns, expressed in this frame;
 * without a normal map ns = N, whose coordinates are (0, 0, 1). */
static void lightmap_irradiance(const rl_level *L, const rl_hit *h, const float N[3], const float ns[3], float E[3])
{
    const bk_scene *s = &L->scene;
    float p[3][3], cc[3][2], dpdx[3], T[3], B[3];
    for (int c = 0; c < 3; c++) {
        memcpy(p[c], &s->positions[3 * (size_t)s->tris[3 * (size_t)h->tri + c]], sizeof p[c]);
        memcpy(cc[c], &L->corner_coord[6 * (size_t)h->tri + 2 * c], sizeof cc[c]);
    }
    lbk_ahd_triangle_dpdx(p, cc, dpdx);
    lbk_ahd_tangent_frame(N, dpdx, T, B);
    const float n_tangent[3] = {dot3(ns, T), dot3(ns, B), dot3(ns, N)};
    uint32_t page;
    float coord[2];
    rl_hit_coord(L, h, &page, coord);
    lbk_ahd_linear lin;
    sample_page(L, page, coord, &lin);
    lbk_ahd_linear_eval(&lin, n_tangent, E);
}

/* ---- probes --------------------------------------------------------------------------------- */

/* An LLG object: its grid's SH at the hit point, seen along the bent normal and scaled by the
 * self-visibility V (spec §11), both interpolated from the triangle's vertex records. */
static void llg_irradiance(const rl_level *L, const rl_hit *h, const float N[3], const float ns[3], float E[3])
{
    const bk_scene *s = &L->scene;
    const uint32_t grid = L->objects[s->tri_object[h->tri]].index;
    lbk_llg_grid g;
    lbk_llg_grid_get(&L->llg, grid, &g);
    float V = 0.0f, bent[3] = {0, 0, 0};
    for (int c = 0; c < 3; c++) {
        const uint32_t rec = L->vertex_record[s->tris[3 * (size_t)h->tri + c]];
        lbk_llg_vertex lv;
        lbk_llg_vertex_unpack(L->llg.vertices + 4 * (g.vertex_offset + rec), &lv);
        V += bary(h, c) * lv.visibility;
        for (int a = 0; a < 3; a++)
            for (int k = 0; k < 3; k++) bent[k] += bary(h, c) * lv.bent_normal[a] * g.axes[a][k]; /* box → world */
    }
    normalize3(bent);
    if (ns != N) { /* a normal map turns the bent normal as it turns N (occlusion kept) */
        float turned[3];
        rotate_like(N, ns, bent, turned);
        memcpy(bent, turned, sizeof bent);
        normalize3(bent);
    }
    lbk_sh9_rgb sh;
    lbk_llg_sample(&L->llg, grid, h->p, &sh);
    lbk_sh9_irradiance(&sh, bent, E);
    for (int c = 0; c < 3; c++) E[c] *= V;
}

/* Anything the bake did not light (dynamic objects, test spheres, back faces): the global grid
 * at the point, irradiance along the normal. hint speeds up the tetrahedron walk (coherent rays). */
static void glg_irradiance(const rl_level *L, const float p[3], const float n[3], uint32_t *hint, float E[3])
{
    lbk_sh9_rgb sh;
    if (!L->has_glg || lbk_glg_sample(&L->glg, p, hint, &sh, NULL) != LBK_OK) {
        E[0] = E[1] = E[2] = 0.0f;
        return;
    }
    lbk_sh9_irradiance(&sh, n, E);
}

void rl_shade(const rl_level *L, const tl_render_options *o, const rl_hit *h, uint32_t *hint, float rgb[3])
{
    float E[3];
    if (h->sphere >= 0) { /* a white test sphere */
        const tl_sphere *sp = &o->spheres[h->sphere];
        float n[3] = {h->p[0] - sp->centre[0], h->p[1] - sp->centre[1], h->p[2] - sp->centre[2]};
        normalize3(n);
        glg_irradiance(L, h->p, n, hint, E);
        for (int c = 0; c < 3; c++) rgb[c] = fmaxf(E[c], 0.0f) / PI_F;
        return;
    }
    const bk_scene *s = &L->scene;
    const uint32_t *v = &s->tris[3 * (size_t)h->tri];
    const bk_material *m = &s->materials[s->tri_material[h->tri]];
    float N[3] = {0, 0, 0}, uv0[2] = {0, 0};
    for (int c = 0; c < 3; c++) {
        for (int k = 0; k < 3; k++) N[k] += bary(h, c) * s->normals[3 * (size_t)v[c] + k];
        for (int k = 0; k < 2; k++) uv0[k] += bary(h, c) * s->uv0[2 * (size_t)v[c] + k];
    }
    normalize3(N);
    if (!h->front && !m->double_sided) { /* the back of a one-sided surface carries no light */
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    float albedo[3], emission[3];
    memcpy(albedo, m->albedo, sizeof albedo);
    memcpy(emission, m->emission, sizeof emission);
    if (m->albedo_tex >= 0) texture(s, m->albedo_tex, uv0, albedo);
    if (m->emission_tex >= 0) texture(s, m->emission_tex, uv0, emission);
    float ns[3];
    shading_normal(s, m, h, N, uv0, ns);
    const float *n = m->normal_tex1 && s->tangents ? ns : N; /* ns == N: no normal map */
    const uint32_t rep = L->objects[s->tri_object[h->tri]].representation;
    if (!h->front) { /* the bake lit the front only: the other side of a double-sided surface
                      * (glTF: a back face's normal, normal-mapped one included, is reversed) */
        const float back[3] = {-n[0], -n[1], -n[2]};
        glg_irradiance(L, h->p, back, hint, E);
    } else if (rep == LBK_REPRESENTATION_LIGHTMAP) {
        lightmap_irradiance(L, h, N, n, E);
    } else if (rep == LBK_REPRESENTATION_LLG) {
        llg_irradiance(L, h, N, n, E);
    } else { /* representation none: a dynamic object */
        glg_irradiance(L, h->p, n, hint, E);
    }
    for (int c = 0; c < 3; c++) rgb[c] = albedo[c] * fmaxf(E[c], 0.0f) / PI_F + emission[c];
}
