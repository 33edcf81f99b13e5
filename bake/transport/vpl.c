/* VPLs: photon shooting, ranges and their bounding volumes, culling against bk_slc's tiles, the
 * gather; see vpl.h and VPL.md. */
#include "bake/transport/vpl.h"

#include "bake/transport/ggx.h"
#include "bake/transport/shading.h"
#include "scene/parallel.h"
#include "bake/util/rng.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define VPL_SALT 0x56504c73686f6f74ull /* "VPLshoot": the photons' streams */
#define INFLATE (1 + 1e-6)             /* radii: rounding never culls an accepted VPL */

static const double LUM[3] = {0.2126, 0.7152, 0.0722};

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static double clamp_alpha(double a) { return a > BK_GGX_ALPHA_MIN ? (a < 1 ? a : 1) : BK_GGX_ALPHA_MIN; }

static int nonzero3(const float v[3]) { return v[0] > 0 || v[1] > 0 || v[2] > 0; }

/* ---- photons ------------------------------------------------------------------------------ */

typedef struct shoot_job {
    const bk_vpl_shoot_desc *desc;
    const bk_light *light;
    double axis[3], t[3], b[3]; /* spot: the cone's frame */
    double cos_max, omega;      /* sampled directions: cos θ ∈ [cos_max, 1], solid angle Ω */
    bk_vpl *slot;               /* 2 per photon */
    uint8_t *made;              /* per photon: VPLs made (0–2) */
} shoot_job;

static void make_vpl(bk_vpl *v, const double pos[3], const double n[3], const double wi[3], const double flux[3],
                     const float refl[3], double alpha, int kind, uint32_t photon)
{
    memset(v, 0, sizeof *v);
    for (int k = 0; k < 3; k++) {
        v->pos[k] = pos[k];
        v->n[k] = n[k];
        v->wi[k] = wi[k];
        v->flux[k] = flux[k];
        v->refl[k] = isfinite(refl[k]) && refl[k] > 0 ? refl[k] : 0;
    }
    v->alpha = alpha;
    v->kind = kind;
    v->photon = photon;
}

/* Photon i: a direction, its first hit, and the VPLs of the hit's lobes. */
static int shoot_one(const shoot_job *j, size_t i, bk_vpl out[2])
{
    const bk_vpl_shoot_desc *d = j->desc;
    bk_rng r = bk_rng_stream(d->seed, VPL_SALT, d->key, i);
    double ct = 1 - bk_rng_next(&r) * (1 - j->cos_max), phi = 2 * BK_PI * bk_rng_next(&r);
    double st = sqrt(fmax(0.0, 1 - ct * ct)), dir[3];
    for (int k = 0; k < 3; k++) dir[k] = st * cos(phi) * j->t[k] + st * sin(phi) * j->b[k] + ct * j->axis[k];
    float org[3] = {j->light->position[0], j->light->position[1], j->light->position[2]};
    float df[3] = {(float)dir[0], (float)dir[1], (float)dir[2]};
    bk_hit h;
    if (!bk_tracer_intersect(d->tracer, org, df, 0.0f, INFINITY, &h)) return 0;
    double x[3], val[3], ld[3], dist;
    for (int k = 0; k < 3; k++) x[k] = (double)org[k] + (double)h.t * df[k];
    if (!bk_light_eval(j->light, x, val, ld, &dist)) return 0; /* outside the cone or the range */
    double flux[3], n[3], wi[3];
    for (int k = 0; k < 3; k++) {
        flux[k] = val[k] * dist * dist * j->omega / (double)d->photons; /* I(ω)·Ω/N */
        n[k] = h.front ? h.ng[k] : -h.ng[k];
        wi[k] = ld[k];
    }
    if (dot3(wi, n) <= 0) return 0; /* a grazing hit rounded to the back: no lobe faces the light */
    bk_vpl_material own;
    const bk_vpl_material *mat = &own;
    if (d->material_at) {
        if (!d->material_at(d->user, &h, x, &own)) return 0;
    } else {
        const uint32_t m = d->scene->tri_material[h.tri];
        if (m >= d->scene->material_count) return 0;
        mat = &d->materials[m];
    }
    float xf[3] = {(float)x[0], (float)x[1], (float)x[2]}, nf[3] = {(float)n[0], (float)n[1], (float)n[2]}, of[3];
    bk_offset_ray_origin_scaled(xf, nf, bk_tracer_tri_scale(d->tracer, h.tri), of);
    double pos[3] = {of[0], of[1], of[2]};
    int c = 0;
    if (nonzero3(mat->kd)) make_vpl(&out[c++], pos, n, wi, flux, mat->kd, 0, BK_VPL_DIFFUSE, (uint32_t)i);
    if (nonzero3(mat->f0) && isfinite(mat->alpha))
        make_vpl(&out[c++], pos, n, wi, flux, mat->f0, clamp_alpha(mat->alpha), BK_VPL_GLOSSY, (uint32_t)i);
    return c;
}

static void shoot_chunk(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    shoot_job *j = (shoot_job *)user;
    for (size_t i = begin; i < end; i++) j->made[i] = (uint8_t)shoot_one(j, i, &j->slot[2 * i]);
}

lbk_result bk_vpl_shoot(const bk_vpl_shoot_desc *desc, const bk_light *light, bk_vpl **out, size_t *count)
{
    if (!out || !count) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *count = 0;
    if (!desc || !light || !desc->scene || !desc->tracer ||
        (desc->scene->material_count && !desc->materials && !desc->material_at) ||
        desc->photons > BK_VPL_MAX_PHOTONS)
        return LBK_ERR_INVALID_ARGUMENT;
    if (light->type == BK_LIGHT_DIRECTIONAL) return LBK_ERR_UNSUPPORTED_FEATURE;
    shoot_job j = {desc, light, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, -1, 4 * BK_PI, NULL, NULL};
    if (light->type == BK_LIGHT_SPOT) {
        double a[3] = {light->direction[0], light->direction[1], light->direction[2]}, l = sqrt(dot3(a, a));
        if (!(l > 0) || !isfinite(l)) return LBK_ERR_INVALID_ARGUMENT;
        for (int k = 0; k < 3; k++) j.axis[k] = a[k] / l;
        bk_onb(j.axis, j.t, j.b);
        double outer = light->outer_cone > 0 && light->outer_cone < BK_PI ? light->outer_cone : BK_PI;
        j.cos_max = cos(outer);
        j.omega = 2 * BK_PI * (1 - j.cos_max);
    }
    const size_t n = desc->photons;
    j.slot = malloc((n ? 2 * n : 1) * sizeof *j.slot);
    j.made = calloc(n ? n : 1, 1);
    if (!j.slot || !j.made) {
        free(j.slot);
        free(j.made);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    bk_parallel_chunks(0, n, 256, bk_thread_count(desc->threads), shoot_chunk, &j);
    size_t c = 0;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < j.made[i]; k++) j.slot[c++] = j.slot[2 * i + k];
    free(j.made);
    bk_vpl *v = realloc(j.slot, (c ? c : 1) * sizeof *v);
    *out = v ? v : j.slot;
    *count = c;
    return LBK_OK;
}

/* ---- intensity and ranges ----------------------------------------------------------------- */

double bk_vpl_intensity(const bk_vpl *v, const double wo[3], double rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0;
    const double co = dot3(wo, v->n);
    if (!(co > 0)) return 0;
    double f[3];
    if (v->kind == BK_VPL_DIFFUSE) {
        for (int k = 0; k < 3; k++) f[k] = v->refl[k] / BK_PI;
    } else {
        double t[3], b[3];
        bk_onb(v->n, t, b);
        double lo[3] = {dot3(wo, t), dot3(wo, b), co}, li[3] = {dot3(v->wi, t), dot3(v->wi, b), dot3(v->wi, v->n)};
        double s = bk_ggx_spec(v->alpha, lo, li), h[3] = {wo[0] + v->wi[0], wo[1] + v->wi[1], wo[2] + v->wi[2]};
        double hl = sqrt(dot3(h, h));
        if (!(s > 0) || !(hl > 0)) return 0;
        const double ih = dot3(v->wi, h) / hl;
        for (int k = 0; k < 3; k++) f[k] = bk_ggx_fresnel(v->refl[k], ih) * s;
    }
    for (int k = 0; k < 3; k++) rgb[k] = v->flux[k] * f[k] * co;
    return dot3(LUM, rgb);
}

/* G1(ω_i)/cos θ_i of the seed's Eq. 8, finite at grazing incidence. */
static double g1_over_cos(double alpha, double c)
{
    return 2 / (c + sqrt(alpha * alpha + (1 - alpha * alpha) * c * c));
}

/* The largest Schlick Fresnel over every ω_o above the horizon: ω_i·h ≥ cos((θ_i + π/2)/2),
 * because the angle between ω_i and ω_o is at most θ_i + π/2, and F falls with ω_i·h. */
static double fresnel_max(double f0, double cos_i)
{
    const double ti = acos(cos_i < 1 ? cos_i : 1);
    return bk_ggx_fresnel(f0, cos(0.5 * ti + 0.25 * BK_PI));
}

void bk_vpl_volume_of(const bk_vpl *v, double xi, double delta, int bound, bk_vpl_volume *out)
{
    memset(out, 0, sizeof *out);
    for (int k = 0; k < 3; k++) out->c[k] = v->pos[k], out->u[k] = v->n[k];
    if (!(xi > 0) || bound == BK_VPL_BOUND_NONE) {
        out->infinite = 1;
        out->ru = out->rv = INFINITY;
        return;
    }
    if (v->kind == BK_VPL_DIFFUSE) {
        /* l_max = R√cos θ_o. Seed §6: it lies in the sphere of radius (4/27)^¼R at q + 3^-¾R·n;
         * the sphere at the VPL bounds it by the intensity's maximum, radius R. */
        const double R = sqrt(dot3(LUM, (double[3]){v->flux[0] * v->refl[0], v->flux[1] * v->refl[1],
                                                   v->flux[2] * v->refl[2]}) / (BK_PI * delta * xi));
        if (bound == BK_VPL_BOUND_SPHERE_AT_VPL) {
            out->ru = out->rv = R * INFLATE;
            return;
        }
        for (int k = 0; k < 3; k++) out->c[k] = v->pos[k] + pow(1.0 / 3, 0.75) * R * v->n[k];
        out->ru = out->rv = pow(4.0 / 27, 0.25) * R * INFLATE;
        return;
    }
    const double ci = fmax(dot3(v->wi, v->n), 0.0), a = clamp_alpha(v->alpha); /* as ggx.c's lobe */
    double pf = 0; /* Σ lum_c Φ_c F_max,c */
    for (int k = 0; k < 3; k++) pf += LUM[k] * v->flux[k] * fresnel_max(v->refl[k], ci);
    /* Eq. 12: r = √(Φ F_max G1/(4πδξ cos θ_i)) */
    const double r = sqrt(pf * g1_over_cos(a, ci) / (4 * BK_PI * delta * xi));
    double wu[3]; /* the mirror direction ω_u = 2(ω_i·n)n − ω_i */
    for (int k = 0; k < 3; k++) wu[k] = 2 * ci * v->n[k] - v->wi[k];
    const double wl = sqrt(dot3(wu, wu));
    for (int k = 0; k < 3; k++) out->u[k] = wl > 0 ? wu[k] / wl : v->n[k];
    const double ru = (1 + a * a) / (2 * a) * r, shift = (1 - a * a) / (2 * a) * r;
    if (bound == BK_VPL_BOUND_SPHERE_AT_VPL) {
        out->ru = out->rv = r / a * INFLATE;
        return;
    }
    for (int k = 0; k < 3; k++) out->c[k] = v->pos[k] + shift * out->u[k]; /* Eq. 15 */
    out->ru = ru * INFLATE;
    out->rv = bound == BK_VPL_BOUND_SPHERE_AROUND ? ru * INFLATE : r * INFLATE; /* Eq. 13 */
}

/* ---- the volume against a box ------------------------------------------------------------- */

/* x ↦ S x: the spheroid's stretch (Eq. 16) into the unit sphere. */
static void stretch(const bk_vpl_volume *vol, const double x[3], double out[3])
{
    const double xu = dot3(x, vol->u);
    for (int k = 0; k < 3; k++) out[k] = ((x[k] - xu * vol->u[k]) / vol->rv) + xu * vol->u[k] / vol->ru;
}

/* Solves the m × m system g x = rhs (m ≤ 3) by Cramer's rule; 0 when it is (near) singular. */
static int solve(int m, const double g[3][3], const double rhs[3], double x[3])
{
    if (m == 1) {
        if (!(g[0][0] > 1e-300)) return 0;
        x[0] = rhs[0] / g[0][0];
        return 1;
    }
    if (m == 2) {
        double det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
        if (!(fabs(det) > 1e-14 * g[0][0] * g[1][1]) || det == 0) return 0;
        x[0] = (rhs[0] * g[1][1] - g[0][1] * rhs[1]) / det;
        x[1] = (g[0][0] * rhs[1] - rhs[0] * g[1][0]) / det;
        return 1;
    }
    double c0 = g[1][1] * g[2][2] - g[1][2] * g[2][1], c1 = g[1][0] * g[2][2] - g[1][2] * g[2][0],
           c2 = g[1][0] * g[2][1] - g[1][1] * g[2][0];
    double det = g[0][0] * c0 - g[0][1] * c1 + g[0][2] * c2;
    if (!(fabs(det) > 1e-14 * g[0][0] * g[1][1] * g[2][2]) || det == 0) return 0;
    for (int col = 0; col < 3; col++) {
        double a[3][3];
        memcpy(a, g, sizeof a);
        for (int r = 0; r < 3; r++) a[r][col] = rhs[r];
        double d = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                   a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        x[col] = d / det;
    }
    return 1;
}

/* In the stretched space the box is the parallelepiped b + A·x, x ∈ [0,1]³, and |b + A x|² is a
 * convex quadratic. Its minimum over the box lies in the relative interior of one of the box's
 * 27 faces (the box, 6 faces, 12 edges, 8 corners), where it is the unconstrained minimum over
 * that face's span. Each face's candidate is clamped into the box and evaluated directly, so
 * every candidate is a value the box attains (never below the true minimum) and the right face
 * gives the minimum itself. Singular faces are skipped: the quadratic is flat along them, so
 * their minimum is also attained on their boundary, a smaller face. */
double bk_vpl_box_dist(const bk_vpl_volume *vol, const float box[6])
{
    for (int a = 0; a < 3; a++)
        if (!(box[a] <= box[3 + a])) return INFINITY;
    if (vol->infinite) return 0;
    double A[3][3], b[3], lo[3];
    for (int a = 0; a < 3; a++) lo[a] = (double)box[a] - vol->c[a];
    stretch(vol, lo, b);
    for (int a = 0; a < 3; a++) {
        double ea[3] = {0, 0, 0}, col[3];
        ea[a] = (double)box[3 + a] - box[a];
        stretch(vol, ea, col);
        for (int k = 0; k < 3; k++) A[k][a] = col[k];
    }
    double G[3][3], g[3];
    for (int i = 0; i < 3; i++) {
        g[i] = A[0][i] * b[0] + A[1][i] * b[1] + A[2][i] * b[2];
        for (int j = 0; j < 3; j++) G[i][j] = A[0][i] * A[0][j] + A[1][i] * A[1][j] + A[2][i] * A[2][j];
    }
    double best = INFINITY;
    for (int code = 0; code < 27; code++) {
        int st[3] = {code % 3, (code / 3) % 3, code / 9}; /* 0: x = 0, 1: x = 1, 2: free */
        int fr[3], m = 0;
        double x[3];
        for (int a = 0; a < 3; a++) {
            x[a] = st[a] == 1 ? 1 : 0;
            if (st[a] == 2) fr[m++] = a;
        }
        if (m) {
            double gg[3][3], rhs[3], sol[3];
            for (int i = 0; i < m; i++) {
                rhs[i] = -g[fr[i]];
                for (int a = 0; a < 3; a++)
                    if (st[a] != 2) rhs[i] -= G[fr[i]][a] * x[a];
                for (int j = 0; j < m; j++) gg[i][j] = G[fr[i]][fr[j]];
            }
            if (!solve(m, gg, rhs, sol)) continue;
            for (int i = 0; i < m; i++) x[fr[i]] = sol[i] < 0 ? 0 : sol[i] > 1 ? 1 : sol[i];
        }
        double q2 = 0;
        for (int k = 0; k < 3; k++) {
            double q = b[k] + A[k][0] * x[0] + A[k][1] * x[1] + A[k][2] * x[2];
            q2 += q * q;
        }
        if (q2 < best) best = q2;
    }
    return best;
}

/* The squared distance from c to the box, in double. */
static double box_dist2(const float *b, const double c[3])
{
    double d2 = 0;
    for (int a = 0; a < 3; a++) {
        double d = c[a] < b[a] ? b[a] - c[a] : c[a] > b[3 + a] ? c[a] - b[3 + a] : 0;
        d2 += d * d;
    }
    return d2;
}

int bk_vpl_volume_meets_box(const bk_vpl_volume *vol, const float box[6])
{
    for (int a = 0; a < 3; a++)
        if (!(box[a] <= box[3 + a])) return 0;
    if (vol->infinite) return 1;
    if (box_dist2(box, vol->c) > vol->ru * vol->ru) return 0; /* outside the enclosing sphere */
    if (vol->ru == vol->rv) return 1;                          /* a sphere: that test is exact */
    for (int a = 0; a < 3; a++) { /* the spheroid's box: half extent √(ru²u_a² + rv²(1 − u_a²)) */
        double h = sqrt(vol->ru * vol->ru * vol->u[a] * vol->u[a] + vol->rv * vol->rv * (1 - vol->u[a] * vol->u[a]));
        if (vol->c[a] + h < box[a] || vol->c[a] - h > box[3 + a]) return 0;
    }
    /* Stretched, the box's centre m and a ball of radius Σ|S e_a|/2 around it hold the whole
     * box: the centre inside the unit sphere meets it, the ball outside it misses it. Only what
     * lies between needs the exact minimum. */
    double m[3], sm[3], ball = 0;
    for (int a = 0; a < 3; a++) m[a] = 0.5 * ((double)box[a] + box[3 + a]) - vol->c[a];
    stretch(vol, m, sm);
    const double dm = sqrt(dot3(sm, sm));
    if (dm <= 1) return 1;
    for (int a = 0; a < 3; a++) {
        double e[3] = {0, 0, 0}, se[3];
        e[a] = 0.5 * ((double)box[3 + a] - box[a]);
        stretch(vol, e, se);
        ball += sqrt(dot3(se, se));
    }
    if (dm > 1 + ball * INFLATE) return 0;
    return bk_vpl_box_dist(vol, box) <= 1 + 1e-9;
}

/* ---- draws: block and tile lists ---------------------------------------------------------- */

struct bk_vpl_draw {
    const bk_vpl *vpls;
    size_t count;
    const bk_slc *tiles;
    double *xi, delta;
    bk_vpl_volume *vol;
    uint32_t **list, *list_n; /* per block */
};

static void draw_blocks(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    bk_vpl_draw *d = (bk_vpl_draw *)user;
    uint32_t *tmp = malloc((d->count ? d->count : 1) * sizeof *tmp);
    for (size_t k = begin; k < end; k++) {
        d->list_n[k] = UINT32_MAX; /* out of memory unless a list comes */
        if (!tmp) continue;
        const float *box = bk_slc_block_box(d->tiles, k);
        uint32_t n = 0;
        for (size_t i = 0; i < d->count; i++)
            if (bk_vpl_volume_meets_box(&d->vol[i], box)) tmp[n++] = (uint32_t)i;
        d->list[k] = malloc((n ? n : 1) * sizeof(uint32_t));
        if (!d->list[k]) continue;
        memcpy(d->list[k], tmp, n * sizeof(uint32_t));
        d->list_n[k] = n;
    }
    free(tmp);
}

lbk_result bk_vpl_draw_create(const bk_vpl *vpls, size_t count, const double *xi, double delta, int bound,
                              const bk_slc *tiles, int threads, bk_vpl_draw **out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if ((count && (!vpls || !xi)) || !tiles || !(delta > 0) || !isfinite(delta) || count > UINT32_MAX - 1 ||
        bound < BK_VPL_BOUND_ELLIPSOID || bound > BK_VPL_BOUND_NONE)
        return LBK_ERR_INVALID_ARGUMENT;
    bk_vpl_draw *d = calloc(1, sizeof *d);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    d->vpls = vpls;
    d->count = count;
    d->tiles = tiles;
    d->delta = delta;
    const size_t nb = bk_slc_block_count(tiles);
    d->xi = malloc((count ? count : 1) * sizeof *d->xi);
    d->vol = malloc((count ? count : 1) * sizeof *d->vol);
    d->list = calloc(nb ? nb : 1, sizeof *d->list);
    d->list_n = calloc(nb ? nb : 1, sizeof *d->list_n);
    if (!d->xi || !d->vol || !d->list || !d->list_n) {
        bk_vpl_draw_destroy(d);
        return LBK_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < count; i++) {
        d->xi[i] = xi[i] >= 0 && xi[i] < 1 ? xi[i] : 0; /* NaN or out of range: never culled */
        bk_vpl_volume_of(&vpls[i], d->xi[i], delta, bound, &d->vol[i]);
    }
    bk_parallel_chunks(0, nb, 1, bk_thread_count(threads), draw_blocks, d);
    for (size_t k = 0; k < nb; k++)
        if (d->list_n[k] == UINT32_MAX) {
            d->list_n[k] = 0;
            bk_vpl_draw_destroy(d);
            return LBK_ERR_OUT_OF_MEMORY;
        }
    *out = d;
    return LBK_OK;
}

void bk_vpl_draw_destroy(bk_vpl_draw *d)
{
    if (!d) return;
    if (d->list)
        for (size_t k = 0; k < bk_slc_block_count(d->tiles); k++) free(d->list[k]);
    free(d->list);
    free(d->list_n);
    free(d->xi);
    free(d->vol);
    free(d);
}

/* 1 when the whole box lies strictly behind v's surface plane ((x − q)·n < 0 everywhere, with a
 * margin for rounding): v's intensity is exactly 0 there (bk_vpl_intensity: ω_o·n ≤ 0), so the
 * tile needs no test of it. The spheroid itself reaches behind the plane near q, so without this
 * every receiver tile on the VPLs' own floor listed them (the transport's metal room: most of the
 * gather's work). */
static int box_behind(const bk_vpl *v, const float box[6])
{
    double m = 0, mag = 0;
    for (int k = 0; k < 3; k++) {
        const double a = v->n[k] * ((double)box[k] - v->pos[k]), b = v->n[k] * ((double)box[3 + k] - v->pos[k]);
        m += a > b ? a : b;
        mag += fabs(v->pos[k]) + fabs((double)box[3 + k]) + fabs((double)box[k]);
    }
    return m < -1e-9 * (mag + 1);
}

size_t bk_vpl_tile_list(const bk_vpl_draw *d, size_t item, uint32_t *ids)
{
    if (item >= bk_slc_item_count(d->tiles)) return 0;
    const size_t k = item / BK_SLC_BLOCK;
    const float *box = bk_slc_tile_box(d->tiles, item / BK_SLC_TILE);
    if (!(box[0] <= box[3] && box[1] <= box[4] && box[2] <= box[5])) return 0; /* an empty tile */
    size_t n = 0;
    for (uint32_t j = 0; j < d->list_n[k]; j++) {
        const uint32_t vi = d->list[k][j];
        if (!box_behind(&d->vpls[vi], box) && bk_vpl_volume_meets_box(&d->vol[vi], box)) ids[n++] = vi;
    }
    return n;
}

/* ---- the gather --------------------------------------------------------------------------- */

typedef struct gather_job {
    const bk_vpl *vpls;
    size_t count;
    const bk_vpl_draw *d;
    const bk_tracer *tracer;
    const bk_vpl_point *pts;
    size_t n;
    double *irr;
    uint64_t (*st)[3]; /* per tile: listed (UINT64_MAX: out of memory), accepted, rays */
} gather_job;

double bk_vpl_draw_xi(const bk_vpl_draw *d, uint32_t vi) { return vi < d->count ? d->xi[vi] : 0; }
double bk_vpl_draw_delta(const bk_vpl_draw *d) { return d->delta; }

int bk_vpl_eval(const bk_vpl *v, double xi, double delta, const bk_tracer *tracer, const bk_vpl_point *q,
                double rgb[3], double to[3], int *accepted, int *ray)
{
    *accepted = *ray = 0;
    double wo[3] = {q->p[0] - v->pos[0], q->p[1] - v->pos[1], q->p[2] - v->pos[2]};
    const double l2 = dot3(wo, wo), l = sqrt(l2);
    if (!(l > 0)) return 0;
    for (int k = 0; k < 3; k++) wo[k] /= l;
    double in[3];
    const double lum = bk_vpl_intensity(v, wo, in);
    if (!(lum > 0)) return 0;
    double w = 1;
    if (delta > 0) {
        w = bk_slc_weight(lum / l2, delta, xi);
        if (w == 0) return 0;
        *accepted = 1;
    }
    const int has_n = q->n[0] != 0 || q->n[1] != 0 || q->n[2] != 0;
    if (has_n && !(dot3(wo, q->n) < 0)) return 0;
    double t[3] = {v->pos[0] - q->org[0], v->pos[1] - q->org[1], v->pos[2] - q->org[2]};
    const double tl = sqrt(dot3(t, t));
    if (!(tl > 0)) return 0;
    for (int k = 0; k < 3; k++) to[k] = t[k] / tl;
    *ray = 1;
    if (!bk_light_visible(tracer, q->org, to, tl)) return 0;
    for (int k = 0; k < 3; k++) rgb[k] = in[k] / l2 * w;
    return 1;
}

/* VPL v at point q with weight 1/p (0: rejected). The cosine is the receiver's, −ω_o·n. */
static void gather_one(const gather_job *j, const bk_vpl *v, double xi, const bk_vpl_point *q, double acc[3],
                       uint64_t *accepted, uint64_t *rays)
{
    double rgb[3], to[3];
    int acc_one, ray;
    const int hit = bk_vpl_eval(v, xi, j->d ? j->d->delta : 0, j->tracer, q, rgb, to, &acc_one, &ray);
    *accepted += (uint64_t)acc_one;
    *rays += (uint64_t)ray;
    if (!hit) return;
    double wo[3] = {q->p[0] - v->pos[0], q->p[1] - v->pos[1], q->p[2] - v->pos[2]};
    const double l = sqrt(dot3(wo, wo));
    for (int k = 0; k < 3; k++) wo[k] /= l;
    const int has_n = q->n[0] != 0 || q->n[1] != 0 || q->n[2] != 0;
    const double cy = has_n ? -dot3(wo, q->n) : 1;
    for (int k = 0; k < 3; k++) acc[k] += rgb[k] * cy;
}

static void gather_tiles(void *user, size_t begin, size_t end, int thread)
{
    (void)thread;
    gather_job *j = (gather_job *)user;
    uint32_t *ids = j->d ? malloc((j->count ? j->count : 1) * sizeof *ids) : NULL;
    if (j->d && !ids) {
        for (size_t t = begin; t < end; t++) j->st[t][0] = UINT64_MAX; /* out of memory, seen after */
        return;
    }
    for (size_t t = begin; t < end; t++) {
        const size_t i0 = t * BK_SLC_TILE, i1 = i0 + BK_SLC_TILE < j->n ? i0 + BK_SLC_TILE : j->n;
        size_t m = j->count;
        if (j->d) m = bk_vpl_tile_list(j->d, i0, ids);
        uint64_t acc_n = 0, rays = 0;
        for (size_t i = i0; i < i1; i++) {
            double acc[3] = {0, 0, 0};
            for (size_t k = 0; k < m; k++) {
                const size_t vi = ids ? ids[k] : k;
                gather_one(j, &j->vpls[vi], j->d ? j->d->xi[vi] : 0, &j->pts[i], acc, &acc_n, &rays);
            }
            for (int k = 0; k < 3; k++) j->irr[3 * i + k] = acc[k];
        }
        j->st[t][0] = (uint64_t)m * (i1 - i0);
        j->st[t][1] = acc_n;
        j->st[t][2] = rays;
    }
    free(ids);
}

lbk_result bk_vpl_gather(const bk_vpl *vpls, size_t count, const bk_vpl_draw *d, const bk_tracer *tracer,
                         const bk_vpl_point *pts, size_t n, int threads, double *irr, bk_vpl_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    if ((count && !vpls) || !tracer || (n && (!pts || !irr))) return LBK_ERR_INVALID_ARGUMENT;
    if (d && (d->vpls != vpls || d->count != count || n > bk_slc_item_count(d->tiles))) return LBK_ERR_INVALID_ARGUMENT;
    const size_t tiles = (n + BK_SLC_TILE - 1) / BK_SLC_TILE;
    gather_job j = {vpls, count, d, tracer, pts, n, irr, calloc(tiles ? tiles : 1, sizeof *j.st)};
    if (!j.st) return LBK_ERR_OUT_OF_MEMORY;
    bk_parallel_chunks(0, tiles, 4, bk_thread_count(threads), gather_tiles, &j);
    for (size_t t = 0; t < tiles; t++)
        if (j.st[t][0] == UINT64_MAX) {
            free(j.st);
            return LBK_ERR_OUT_OF_MEMORY;
        }
    if (stats)
        for (size_t t = 0; t < tiles; t++) {
            stats->listed += j.st[t][0];
            stats->accepted += j.st[t][1];
            stats->rays += j.st[t][2];
        }
    free(j.st);
    return LBK_OK;
}
