/* VPLs with stochastic light culling (bake/transport/vpl.h, VPL.md): the photons carry the
 * light's flux and their gather converges to the floor's single-bounce integral; the seed's bounding volumes enclose the range isosurface and the spheroid is
 * tight; the box test is the exact minimum; tiles never lose an accepted VPL (brute force over
 * every pair); the gather matches the analytic one-VPL answer, is unbiased against the gather
 * of every VPL (and an injected bias fails the same test), the same for every bound, and
 * byte-identical at any thread count. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/transport/ggx.h"
#include "bake/transport/shading.h"
#include "bake/transport/vpl.h"
#include "support/transport_scenes.h"

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 11;
}
static double unit(uint64_t *s) { return (double)lcg(s) / 9007199254740992.0; }

static double lum3(const double *v) { return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]; }

/* A 6 × 6 × 3 m room (inward box): a metal floor (material 0), grey walls and ceiling; a spot light
 * 2.8 m up aimed down and sideways, so the floor's lobe lights a wall. */
typedef struct room {
    bk_scene s;
    bk_tracer *t;
    bk_vpl_material mats[2];
} room;

static void room_make(room *R, double alpha, int photons_spot)
{
    (void)photons_spot;
    tsc_init(&R->s);
    uint32_t floor_m = tsc_material(&R->s, 0.9f, 0.9f, 0.9f, 0, 0, 0);
    uint32_t wall_m = tsc_material(&R->s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float f0[3] = {0, 0, 0}, f1[3] = {6, 0, 0}, f2[3] = {6, 6, 0}, f3[3] = {0, 6, 0};
    tsc_quad(&R->s, f0, f1, f2, f3, 4, floor_m);
    float c0[3] = {0, 0, 3}, c1[3] = {6, 0, 3}, c2[3] = {6, 6, 3}, c3[3] = {0, 6, 3};
    tsc_quad(&R->s, c0, c3, c2, c1, 4, wall_m);
    tsc_quad(&R->s, f0, c0, c1, f1, 4, wall_m); /* y = 0 */
    tsc_quad(&R->s, f1, c1, c2, f2, 4, wall_m); /* x = 6 */
    tsc_quad(&R->s, f2, c2, c3, f3, 4, wall_m); /* y = 6 */
    tsc_quad(&R->s, f3, c3, c0, f0, 4, wall_m); /* x = 0 */
    float lp[3] = {1.5f, 3, 2.8f}, ld[3] = {0.5f, 0, -1};
    tsc_spot_light(&R->s, lp, ld, 50, 0.3f, 0.5f);
    tsc_update_bounds(&R->s);
    assert_int_equal(bk_tracer_create(&R->s, 1, &R->t), LBK_OK);
    memset(R->mats, 0, sizeof R->mats);
    for (int k = 0; k < 3; k++) R->mats[floor_m].f0[k] = 0.9f, R->mats[wall_m].kd[k] = 0.5f;
    R->mats[floor_m].alpha = (float)alpha;
    (void)wall_m;
}

static void room_free(room *R)
{
    bk_tracer_destroy(R->t);
    tsc_free(&R->s);
}

static bk_vpl *room_vpls(const room *R, size_t photons, uint64_t seed, int threads, size_t *count)
{
    bk_vpl_shoot_desc d = {.scene = &R->s, .tracer = R->t, .materials = R->mats, .seed = seed, .photons = photons, .threads = threads, .key = 0};
    bk_vpl *v = NULL;
    assert_int_equal(bk_vpl_shoot(&d, &R->s.lights[0], &v, count), LBK_OK);
    return v;
}

/* Receivers in 4 × 4 patches of 25 cm (one tile each) on the walls x = 6 and y = 0/6 and the
 * ceiling; returns the count (a multiple of 16). */
static size_t receivers(const room *R, bk_vpl_point *pts, size_t cap, float **boxes_out)
{
    size_t n = 0;
    uint64_t r = 5;
    while (n + 16 <= cap) {
        int face = (int)(n / 16) % 4;
        double o[3], ax[3] = {0}, ay[3] = {0}, nn[3] = {0};
        double a = 0.2 + 4.6 * unit(&r), b = 0.2 + 1.8 * unit(&r);
        if (face == 0) { o[0] = 6, o[1] = a, o[2] = b; ax[1] = 1; ay[2] = 1; nn[0] = -1; }
        else if (face == 1) { o[0] = a, o[1] = 0, o[2] = b; ax[0] = 1; ay[2] = 1; nn[1] = 1; }
        else if (face == 2) { o[0] = a, o[1] = 6, o[2] = b; ax[0] = 1; ay[2] = 1; nn[1] = -1; }
        else { o[0] = a, o[1] = 0.2 + 4.6 * unit(&r), o[2] = 3; ax[0] = 1; ay[1] = 1; nn[2] = -1; }
        for (int j = 0; j < 16; j++) {
            bk_vpl_point *q = &pts[n + (size_t)j];
            for (int k = 0; k < 3; k++) {
                q->p[k] = o[k] + (0.25 * (j % 4) + 0.125) * ax[k] + (0.25 * (j / 4) + 0.125) * ay[k];
                q->n[k] = nn[k];
            }
            float pf[3] = {(float)q->p[0], (float)q->p[1], (float)q->p[2]}, nf[3] = {(float)nn[0], (float)nn[1], (float)nn[2]};
            bk_offset_ray_origin_scaled(pf, nf, 6, q->org);
        }
        n += 16;
    }
    float *boxes = malloc(n * 6 * sizeof *boxes);
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) boxes[6 * i + a] = boxes[6 * i + 3 + a] = (float)pts[i].p[a];
    *boxes_out = boxes;
    (void)R;
    return n;
}

static void random_unit(uint64_t *r, double v[3])
{
    double z = 2 * unit(r) - 1, ph = 2 * BK_PI * unit(r), s = sqrt(1 - z * z);
    v[0] = s * cos(ph), v[1] = s * sin(ph), v[2] = z;
}

/* The inside value |S(x − c)|² of a point (a degenerate box). */
static double inside_value(const bk_vpl_volume *vol, const double x[3])
{
    double d[3] = {x[0] - vol->c[0], x[1] - vol->c[1], x[2] - vol->c[2]};
    double du = d[0] * vol->u[0] + d[1] * vol->u[1] + d[2] * vol->u[2], d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    return (d2 - du * du) / (vol->rv * vol->rv) + du * du / (vol->ru * vol->ru);
}

/* Every point of the range isosurface l_max(ω_o) = √(I(ω_o)/(δξ)) (Eq. 5) lies in each volume;
 * the spheroid touches it (largest inside value ≥ 0.6; so does the sphere of radius r/α, which
 * the spheroid's far end reaches along ω_u), and the §6 sphere of a diffuse VPL holds its
 * isosurface too. */
static void test_volumes_enclose_the_range(void **state)
{
    (void)state;
    uint64_t r = 11;
    double worst[4] = {0}, tight_e = 1, tight_d = 1;
    for (int c = 0; c < 60; c++) {
        bk_vpl v;
        memset(&v, 0, sizeof v);
        v.kind = c % 6 == 5 ? BK_VPL_DIFFUSE : BK_VPL_GLOSSY;
        const double alphas[5] = {0.02, 0.05, 0.1, 0.2, 0.4};
        v.alpha = v.kind == BK_VPL_GLOSSY ? (c % 7 == 6 ? 1.0 : alphas[c % 5]) : 0;
        random_unit(&r, v.n);
        double ti = acos(0.02 + 0.98 * unit(&r)), t[3], b[3];
        bk_onb(v.n, t, b);
        for (int k = 0; k < 3; k++) {
            v.wi[k] = sin(ti) * t[k] + cos(ti) * v.n[k];
            v.pos[k] = 10 * unit(&r) - 5;
            v.flux[k] = 0.5 + unit(&r);
            v.refl[k] = c % 2 ? 0.04 + 0.1 * k : 0.95 - 0.2 * k;
        }
        const double xi = 0.01 + 0.99 * unit(&r), delta = 0.3;
        bk_vpl_volume vol[3];
        for (int m = 0; m < 3; m++) bk_vpl_volume_of(&v, xi, delta, m, &vol[m]);
        double mx[3] = {0};
        double wu[3];
        for (int k = 0; k < 3; k++) wu[k] = 2 * cos(ti) * v.n[k] - v.wi[k];
        for (int s = 0; s < 4000; s++) {
            double wo[3], rgb[3];
            random_unit(&r, wo);
            if (s % 2) { /* half near the mirror direction */
                double w[3], spread = 3 * v.alpha + 0.01;
                random_unit(&r, w);
                for (int k = 0; k < 3; k++) wo[k] = wu[k] + spread * w[k];
                double l = sqrt(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
                for (int k = 0; k < 3; k++) wo[k] /= l;
            }
            double I = bk_vpl_intensity(&v, wo, rgb);
            if (!(I > 0)) continue;
            double l = sqrt(I / (delta * xi)), x[3];
            for (int k = 0; k < 3; k++) x[k] = v.pos[k] + l * wo[k];
            for (int m = 0; m < 3; m++) mx[m] = fmax(mx[m], inside_value(&vol[m], x));
        }
        for (int m = 0; m < 3; m++) worst[m] = fmax(worst[m], mx[m]);
        if (v.kind == BK_VPL_GLOSSY && v.alpha < 1) tight_e = fmin(tight_e, mx[BK_VPL_BOUND_ELLIPSOID]);
        if (v.kind == BK_VPL_DIFFUSE) tight_d = fmin(tight_d, mx[0]);
    }
    print_message("largest inside value: ellipsoid %.6f, sphere at VPL %.6f, sphere around %.6f; tightest "
                  "spheroid touch %.3f, diffuse sphere %.3f\n", worst[0], worst[1], worst[2], tight_e, tight_d);
    for (int m = 0; m < 3; m++) assert_true(worst[m] <= 1);
    assert_true(tight_e >= 0.6);
    assert_true(tight_d >= 0.999); /* the §6 sphere touches R√cos θ at cos θ = 3^-½ */
}

/* bk_vpl_box_dist against a 41³ grid of the box (flat boxes too): never above a value the box
 * attains, and within the grid's resolution of the grid's minimum. */
static void test_box_dist_is_the_minimum(void **state)
{
    (void)state;
    uint64_t r = 3;
    int met = 0, missed = 0;
    for (int c = 0; c < 150; c++) {
        bk_vpl_volume vol;
        memset(&vol, 0, sizeof vol);
        random_unit(&r, vol.u);
        vol.rv = 0.2 + unit(&r);
        vol.ru = c % 3 == 0 ? vol.rv : vol.rv * (1 + 10 * unit(&r));
        float box[6];
        for (int a = 0; a < 3; a++) {
            vol.c[a] = 0;
            double lo = -3 + 4 * unit(&r), ext = (c % 4 == 1 && a == 2) ? 0 : 2.5 * unit(&r);
            box[a] = (float)lo;
            box[3 + a] = (float)(lo + ext);
        }
        const double got = bk_vpl_box_dist(&vol, box);
        double grid = INFINITY, step_len = 0;
        for (int a = 0; a < 3; a++) {
            double e[3] = {0, 0, 0};
            e[a] = ((double)box[3 + a] - box[a]) / 80; /* half a grid step along axis a */
            double eu = e[0] * vol.u[0] + e[1] * vol.u[1] + e[2] * vol.u[2], e2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
            step_len += sqrt((e2 - eu * eu) / (vol.rv * vol.rv) + eu * eu / (vol.ru * vol.ru));
        }
        for (int i = 0; i <= 40; i++)
            for (int j = 0; j <= 40; j++)
                for (int k = 0; k <= 40; k++) {
                    double x[3] = {box[0] + (box[3] - (double)box[0]) * i / 40, box[1] + (box[4] - (double)box[1]) * j / 40,
                                   box[2] + (box[5] - (double)box[2]) * k / 40};
                    grid = fmin(grid, inside_value(&vol, x));
                }
        assert_true(got <= grid * (1 + 1e-12) + 1e-15);
        assert_true(sqrt(grid) <= sqrt(got) + step_len + 1e-12);
        const int meets = bk_vpl_volume_meets_box(&vol, box);
        if (grid <= 1) assert_true(meets);
        if (got > 1 + 1e-6) assert_false(meets);
        met += meets;
        missed += !meets;
    }
    assert_true(met > 20 && missed > 20); /* both outcomes tested */
}

/* Every VPL a receiver accepts (ξ < p, the gather's own rule) is in its tile's list, for every
 * bound, by brute force over every pair; the lists shrink from the sphere at the VPL to the
 * spheroid. */
static void test_tiles_conservative(void **state)
{
    (void)state;
    room R;
    room_make(&R, 0.1, 0);
    size_t nv = 0;
    bk_vpl *v = room_vpls(&R, 3000, 1, 2, &nv);
    bk_vpl_point *pts = calloc(640, sizeof *pts);
    float *boxes = NULL;
    size_t n = receivers(&R, pts, 640, &boxes);
    bk_slc *tiles = NULL;
    assert_int_equal(bk_slc_create(NULL, 0, boxes, n, &tiles), LBK_OK);
    double *xi = malloc(nv * sizeof *xi);
    uint64_t r = 17;
    for (size_t i = 0; i < nv; i++) xi[i] = unit(&r);
    uint32_t *ids = malloc(nv * sizeof *ids);
    size_t listed[3] = {0}, accepted = 0;
    const double delta = 0.02;
    for (int m = 0; m < 3; m++) {
        bk_vpl_draw *d = NULL;
        assert_int_equal(bk_vpl_draw_create(v, nv, xi, delta, m, tiles, 2, &d), LBK_OK);
        for (size_t i = 0; i < n; i++) {
            size_t k = bk_vpl_tile_list(d, i, ids);
            listed[m] += k;
            char *in = calloc(nv, 1);
            for (size_t j = 0; j < k; j++) in[ids[j]] = 1;
            for (size_t j = 0; j < nv; j++) {
                double wo[3], rgb[3];
                for (int a = 0; a < 3; a++) wo[a] = pts[i].p[a] - v[j].pos[a];
                double l2 = wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2], l = sqrt(l2);
                for (int a = 0; a < 3; a++) wo[a] /= l;
                double I = bk_vpl_intensity(&v[j], wo, rgb);
                if (bk_slc_weight(I / l2, delta, xi[j]) == 0) continue;
                if (m == 0) accepted++;
                assert_true(in[j]);
            }
            free(in);
        }
        bk_vpl_draw_destroy(d);
    }
    print_message("%zu VPLs, %zu receivers: listed per receiver %.1f (ellipsoid) %.1f (sphere at VPL) %.1f "
                  "(sphere around), accepted %.2f\n", nv, n, (double)listed[0] / n, (double)listed[1] / n,
                  (double)listed[2] / n, (double)accepted / n);
    assert_true(accepted > n);                    /* the test sees accepted VPLs at all */
    assert_true(listed[0] < listed[2] && listed[2] < listed[1]);
    assert_true(listed[0] < nv * n / 4);          /* and the spheroid culls */
    free(ids);
    free(xi);
    bk_vpl_draw_destroy(NULL);
    bk_slc_destroy(tiles);
    free(boxes);
    free(pts);
    free(v);
    room_free(&R);
}

/* One VPL, nothing in the way, δ so small that p = 1: the irradiance is Φ·f·cos θ_o·cos θ_y/l²
 * with f from ggx.h's pieces (glossy) or k/π (diffuse). */
static void test_gather_one_vpl(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 0.5f, 0.5f, 0.5f, 0, 0, 0);
    float a[3] = {50, 50, 50}, b[3] = {51, 50, 50}, c[3] = {50, 51, 50};
    tsc_tri(&s, a, b, c, m); /* far away: a tracer needs a triangle */
    tsc_update_bounds(&s);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &t), LBK_OK);
    bk_vpl v[2];
    memset(v, 0, sizeof v);
    for (int i = 0; i < 2; i++) {
        v[i].n[2] = 1;
        v[i].wi[0] = sin(0.6), v[i].wi[2] = cos(0.6);
        for (int k = 0; k < 3; k++) v[i].flux[k] = 2 + k, v[i].refl[k] = 0.3 + 0.2 * k;
    }
    v[0].kind = BK_VPL_DIFFUSE;
    v[1].kind = BK_VPL_GLOSSY;
    v[1].alpha = 0.3;
    bk_vpl_point q;
    memset(&q, 0, sizeof q);
    q.p[0] = -1.2, q.p[1] = 0.3, q.p[2] = 1.5;
    q.n[0] = 0.6, q.n[2] = -0.8;
    for (int k = 0; k < 3; k++) q.org[k] = (float)q.p[k];
    float box[6] = {(float)q.p[0], (float)q.p[1], (float)q.p[2], (float)q.p[0], (float)q.p[1], (float)q.p[2]};
    bk_slc *tiles = NULL;
    assert_int_equal(bk_slc_create(NULL, 0, box, 1, &tiles), LBK_OK);
    double l2 = q.p[0] * q.p[0] + q.p[1] * q.p[1] + q.p[2] * q.p[2], l = sqrt(l2), wo[3];
    for (int k = 0; k < 3; k++) wo[k] = q.p[k] / l;
    const double co = wo[2], cy = -(wo[0] * q.n[0] + wo[2] * q.n[2]);
    double h[3] = {wo[0] + v[1].wi[0], wo[1], wo[2] + v[1].wi[2]}, hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int k = 0; k < 3; k++) h[k] /= hl;
    const double ci = v[1].wi[2], ih = h[0] * v[1].wi[0] + h[2] * v[1].wi[2];
    const double spec = bk_ggx_d(0.3, h[2]) * bk_ggx_g2(0.3, co, ci) / (4 * co * ci);
    for (int i = 0; i < 2; i++) {
        double xi = 0.5, irr[3], irr_bf[3];
        bk_vpl_draw *d = NULL;
        assert_int_equal(bk_vpl_draw_create(&v[i], 1, &xi, 1e-12, BK_VPL_BOUND_ELLIPSOID, tiles, 1, &d), LBK_OK);
        bk_vpl_stats st;
        assert_int_equal(bk_vpl_gather(&v[i], 1, d, t, &q, 1, 1, irr, &st), LBK_OK);
        assert_int_equal(bk_vpl_gather(&v[i], 1, NULL, t, &q, 1, 1, irr_bf, NULL), LBK_OK);
        assert_true(st.listed == 1 && st.accepted == 1 && st.rays == 1);
        for (int k = 0; k < 3; k++) {
            double f = i == 0 ? v[0].refl[k] / BK_PI : bk_ggx_fresnel(v[1].refl[k], ih) * spec;
            double want = v[i].flux[k] * f * co * cy / l2;
            assert_true(want > 0);
            assert_true(fabs(irr[k] - want) <= 1e-12 * want);
            assert_true(irr_bf[k] == irr[k]);
        }
        bk_vpl_draw_destroy(d);
    }
    bk_slc_destroy(tiles);
    bk_tracer_destroy(t);
    tsc_free(&s);
}

/* A point light inside a closed box: every photon lands and Σ Φ = 4πI; a spot light: Σ Φ is
 * the cone's integral of I·t² (t the smooth cone ramp), 2πI((c_i − c_o)/3 + 1 − c_i), within
 * the photons' noise. One VPL per lobe, facing the light. */
static void test_shoot_flux(void **state)
{
    (void)state;
    room R;
    room_make(&R, 0.2, 0);
    R.mats[0].kd[0] = R.mats[0].kd[1] = R.mats[0].kd[2] = 0.1f; /* the floor gets both lobes */
    const size_t N = 20000;
    size_t nv = 0;
    bk_vpl *v = room_vpls(&R, N, 4, 2, &nv);
    const bk_light *L = &R.s.lights[0];
    double sum = 0, sq = 0, dsum = 0;
    size_t glossy = 0, photons = 0;
    uint32_t last = UINT32_MAX;
    for (size_t i = 0; i < nv; i++) {
        assert_true(v[i].wi[0] * v[i].n[0] + v[i].wi[1] * v[i].n[1] + v[i].wi[2] * v[i].n[2] > 0);
        double to[3] = {L->position[0] - v[i].pos[0], L->position[1] - v[i].pos[1], L->position[2] - v[i].pos[2]};
        double tl = sqrt(to[0] * to[0] + to[1] * to[1] + to[2] * to[2]);
        for (int k = 0; k < 3; k++) assert_true(fabs(to[k] / tl - v[i].wi[k]) < 1e-5);
        if (v[i].kind == BK_VPL_GLOSSY) {
            glossy++;
            assert_true(v[i].alpha == (double)0.2f && v[i].refl[0] == (double)0.9f);
        }
        if (v[i].photon != last) { /* the first VPL of a photon carries its flux */
            sum += v[i].flux[1];
            sq += v[i].flux[1] * v[i].flux[1];
            photons++;
            last = v[i].photon;
        } else {
            assert_true(v[i].flux[1] == v[i - 1].flux[1] && v[i].kind == BK_VPL_GLOSSY);
        }
        dsum += v[i].kind == BK_VPL_DIFFUSE;
    }
    const double ci = cos(L->inner_cone), co = cos(L->outer_cone);
    const double want = 2 * BK_PI * 50 * ((ci - co) / 3 + 1 - ci);
    const double sd = sqrt(sq - sum * sum / N); /* std of the sum of N photons (misses count 0) */
    print_message("spot: sum of flux %.4f, expected %.4f (sd %.4f); %zu VPLs of %zu photons, %zu glossy\n", sum, want, sd,
                  nv, photons, glossy);
    assert_true(fabs(sum - want) < 4 * sd);
    assert_true(photons > N / 2 && glossy > 0 && dsum > 0);
    free(v);
    /* a point light: every direction hits the room */
    R.s.lights[0].type = BK_LIGHT_POINT;
    v = room_vpls(&R, 5000, 9, 2, &nv);
    double total[3] = {0};
    for (size_t i = 0; i < nv; i++)
        if (i == 0 || v[i].photon != v[i - 1].photon)
            for (int k = 0; k < 3; k++) total[k] += v[i].flux[k];
    for (int k = 0; k < 3; k++) assert_true(fabs(total[k] - 4 * BK_PI * 50) < 1e-9 * 4 * BK_PI * 50);
    free(v);
    room_free(&R);
}

/* K draws of one VPL set against the gather of every VPL: per draw Var ≤ δ·E (VPL.md), so the
 * per-run sum of relative deviations and each receiver's mean stay within a few bound-sigmas;
 * the same statistics with ξ' = 0.05 + 0.95ξ (an injected bias: acceptance (p − 0.05)/0.95
 * instead of p) must fail. One draw gives the same bytes for every bound and for no culling. */
static void test_unbiased_against_every_vpl(void **state)
{
    (void)state;
    room R;
    room_make(&R, 0.1, 0);
    size_t nv = 0;
    bk_vpl *v = room_vpls(&R, 4000, 2, 2, &nv);
    enum { NP = 320 };
    bk_vpl_point *pts = calloc(NP, sizeof *pts);
    float *boxes = NULL;
    size_t n = receivers(&R, pts, NP, &boxes);
    bk_slc *tiles = NULL;
    assert_int_equal(bk_slc_create(NULL, 0, boxes, n, &tiles), LBK_OK);
    double *bf = malloc(3 * n * sizeof *bf), *irr = malloc(3 * n * sizeof *irr), *irr2 = malloc(3 * n * sizeof *irr2);
    assert_int_equal(bk_vpl_gather(v, nv, NULL, R.t, pts, n, 2, bf, NULL), LBK_OK);
    double mean_e = 0;
    for (size_t i = 0; i < n; i++) mean_e += lum3(&bf[3 * i]) / n;
    const double delta = 0.05 * mean_e;
    double *xi = malloc(nv * sizeof *xi);
    enum { K = 40 };
    double z[2] = {0}, bmax[2] = {0};
    size_t tested = 0;
    for (int bias = 0; bias < 2; bias++) {
        double *mean = calloc(n, sizeof *mean), lv = 0, lv2 = 0;
        for (int k = 0; k < K; k++) {
            uint64_t r = 1000 + (uint64_t)k;
            for (size_t i = 0; i < nv; i++) xi[i] = bias ? 0.05 + 0.95 * unit(&r) : unit(&r);
            bk_vpl_draw *d = NULL;
            assert_int_equal(bk_vpl_draw_create(v, nv, xi, delta, BK_VPL_BOUND_ELLIPSOID, tiles, 2, &d), LBK_OK);
            bk_vpl_stats st;
            assert_int_equal(bk_vpl_gather(v, nv, d, R.t, pts, n, 2, irr, &st), LBK_OK);
            if (!bias) tested += st.listed;
            if (k == 0 && !bias)
                for (int m = 1; m <= BK_VPL_BOUND_NONE; m++) { /* the bound changes the cost only */
                    bk_vpl_draw *d2 = NULL;
                    assert_int_equal(bk_vpl_draw_create(v, nv, xi, delta, m, tiles, 1, &d2), LBK_OK);
                    assert_int_equal(bk_vpl_gather(v, nv, d2, R.t, pts, n, 1, irr2, NULL), LBK_OK);
                    assert_memory_equal(irr, irr2, 3 * n * sizeof *irr);
                    bk_vpl_draw_destroy(d2);
                }
            double dev = 0;
            for (size_t i = 0; i < n; i++) {
                double e = lum3(&bf[3 * i]), x = lum3(&irr[3 * i]);
                if (e > 0) dev += (x - e) / e;
                mean[i] += x / K;
            }
            lv += dev / K;
            lv2 += dev * dev / K;
            bk_vpl_draw_destroy(d);
        }
        z[bias] = lv / sqrt((lv2 - lv * lv) / (K - 1));
        for (size_t i = 0; i < n; i++) {
            double e = lum3(&bf[3 * i]);
            if (e > 0) bmax[bias] = fmax(bmax[bias], fabs(mean[i] - e) / sqrt(delta * e / K));
        }
        free(mean);
    }
    print_message("%zu VPLs, %zu receivers, delta %.4g: VPLs listed per receiver %.1f; mean relative deviation "
                  "%.2f sigma, max |z| against the bound %.2f; with the injected bias %.2f sigma, %.2f\n",
                  nv, n, delta, (double)tested / K / n, z[0], bmax[0], z[1], bmax[1]);
    assert_true(fabs(z[0]) < 4 && bmax[0] < 5);
    assert_true(fabs(z[1]) > 4 || bmax[1] > 5);
    assert_true((double)tested / K / n < 0.5 * nv); /* the draws cull */
    free(xi);
    free(bf);
    free(irr);
    free(irr2);
    bk_slc_destroy(tiles);
    free(boxes);
    free(pts);
    free(v);
    room_free(&R);
}

/* Photons and gathers: the same bytes on 1 and 3 threads (and another key draws other photons). */
static void test_threads_identical(void **state)
{
    (void)state;
    room R;
    room_make(&R, 0.05, 0);
    size_t n1 = 0, n3 = 0;
    bk_vpl *v1 = room_vpls(&R, 3000, 8, 1, &n1), *v3 = room_vpls(&R, 3000, 8, 3, &n3);
    assert_int_equal(n1, n3);
    assert_memory_equal(v1, v3, n1 * sizeof *v1);
    { /* another key, another stream */
        bk_vpl_shoot_desc d = {.scene = &R.s, .tracer = R.t, .materials = R.mats, .seed = 8, .photons = 3000, .threads = 1, .key = 1};
        bk_vpl *vk = NULL;
        size_t nk = 0;
        assert_int_equal(bk_vpl_shoot(&d, &R.s.lights[0], &vk, &nk), LBK_OK);
        assert_true(nk > 0 && memcmp(vk, v1, sizeof *vk) != 0);
        free(vk);
    }
    bk_vpl_point *pts = calloc(320, sizeof *pts);
    float *boxes = NULL;
    size_t n = receivers(&R, pts, 320, &boxes);
    bk_slc *tiles = NULL;
    assert_int_equal(bk_slc_create(NULL, 0, boxes, n, &tiles), LBK_OK);
    double *xi = malloc(n1 * sizeof *xi), *a = malloc(3 * n * sizeof *a), *b = malloc(3 * n * sizeof *b);
    uint64_t r = 1;
    for (size_t i = 0; i < n1; i++) xi[i] = unit(&r);
    bk_vpl_draw *d1 = NULL, *d3 = NULL;
    assert_int_equal(bk_vpl_draw_create(v1, n1, xi, 0.01, BK_VPL_BOUND_ELLIPSOID, tiles, 1, &d1), LBK_OK);
    assert_int_equal(bk_vpl_draw_create(v1, n1, xi, 0.01, BK_VPL_BOUND_ELLIPSOID, tiles, 3, &d3), LBK_OK);
    bk_vpl_stats s1, s3;
    assert_int_equal(bk_vpl_gather(v1, n1, d1, R.t, pts, n, 1, a, &s1), LBK_OK);
    assert_int_equal(bk_vpl_gather(v1, n1, d3, R.t, pts, n, 3, b, &s3), LBK_OK);
    assert_memory_equal(a, b, 3 * n * sizeof *a);
    assert_memory_equal(&s1, &s3, sizeof s1);
    double sum = 0;
    for (size_t i = 0; i < 3 * n; i++) sum += a[i];
    assert_true(sum > 0 && s1.rays > 0);
    bk_vpl_draw_destroy(d1);
    bk_vpl_draw_destroy(d3);
    free(xi);
    free(a);
    free(b);
    bk_slc_destroy(tiles);
    free(boxes);
    free(pts);
    free(v1);
    free(v3);
    room_free(&R);
}

/* Bad arguments are refused with the documented results; no photons is no VPLs. */
static void test_arguments(void **state)
{
    (void)state;
    room R;
    room_make(&R, 0.1, 0);
    bk_vpl_shoot_desc d = {.scene = &R.s, .tracer = R.t, .materials = R.mats, .seed = 1, .photons = 0, .threads = 1, .key = 0};
    bk_vpl *v = NULL;
    size_t nv = 7;
    assert_int_equal(bk_vpl_shoot(&d, &R.s.lights[0], &v, &nv), LBK_OK);
    assert_true(nv == 0 && v != NULL);
    free(v);
    d.photons = BK_VPL_MAX_PHOTONS + 1;
    assert_int_equal(bk_vpl_shoot(&d, &R.s.lights[0], &v, &nv), LBK_ERR_INVALID_ARGUMENT);
    assert_null(v);
    d.photons = 10;
    bk_light sun = R.s.lights[0];
    sun.type = BK_LIGHT_DIRECTIONAL;
    assert_int_equal(bk_vpl_shoot(&d, &sun, &v, &nv), LBK_ERR_UNSUPPORTED_FEATURE);
    d.materials = NULL;
    assert_int_equal(bk_vpl_shoot(&d, &R.s.lights[0], &v, &nv), LBK_ERR_INVALID_ARGUMENT);
    d.materials = R.mats;
    v = room_vpls(&R, 100, 1, 1, &nv);
    assert_true(nv > 50);
    float box[6] = {0, 0, 0, 1, 1, 1};
    bk_slc *tiles = NULL;
    assert_int_equal(bk_slc_create(NULL, 0, box, 1, &tiles), LBK_OK);
    double *xi = calloc(nv, sizeof *xi);
    bk_vpl_draw *dr = NULL;
    assert_int_equal(bk_vpl_draw_create(v, nv, xi, 0, BK_VPL_BOUND_ELLIPSOID, tiles, 1, &dr), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_vpl_draw_create(v, nv, xi, NAN, BK_VPL_BOUND_ELLIPSOID, tiles, 1, &dr), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_vpl_draw_create(v, nv, xi, 1, 9, tiles, 1, &dr), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(bk_vpl_draw_create(v, nv, xi, 1, BK_VPL_BOUND_ELLIPSOID, NULL, 1, &dr), LBK_ERR_INVALID_ARGUMENT);
    assert_null(dr);
    assert_int_equal(bk_vpl_draw_create(v, nv, xi, 1, BK_VPL_BOUND_ELLIPSOID, tiles, 1, &dr), LBK_OK);
    bk_vpl_point q;
    memset(&q, 0, sizeof q);
    double irr[6];
    assert_int_equal(bk_vpl_gather(v, nv - 1, dr, R.t, &q, 1, 1, irr, NULL), LBK_ERR_INVALID_ARGUMENT);
    bk_vpl_point two[2];
    memset(two, 0, sizeof two);
    assert_int_equal(bk_vpl_gather(v, nv, dr, R.t, two, 2, 1, irr, NULL), LBK_ERR_INVALID_ARGUMENT); /* > items */
    /* ξ = 0 (and out-of-range ξ, read as 0) never culls: the tile lists every VPL */
    uint32_t *ids = malloc(nv * sizeof *ids);
    assert_int_equal(bk_vpl_tile_list(dr, 0, ids), nv);
    free(ids);
    bk_vpl_draw_destroy(dr);
    free(xi);
    bk_slc_destroy(tiles);
    free(v);
    room_free(&R);
}

/* The whole chain against an independent answer: a spot light over an open GGX floor (α 0.3,
 * F0 0.9) and receivers above it. The single-bounce irradiance at y is the floor integral
 * ∫ E_light(x)·f(ω_i, ω_o)·cos θ_o·cos θ_y/l² dA (midpoint rule, 5 mm cells over the cone's
 * footprint); the mean of M photon sets' brute-force gathers must match it within 4 standard
 * errors of the sets' spread and 3 %. */
static void test_gather_matches_the_floor_integral(void **state)
{
    (void)state;
    bk_scene s;
    tsc_init(&s);
    uint32_t m = tsc_material(&s, 1, 1, 1, 0, 0, 0);
    float p0[3] = {-3, -3, 0}, p1[3] = {3, -3, 0}, p2[3] = {3, 3, 0}, p3[3] = {-3, 3, 0};
    tsc_quad(&s, p0, p1, p2, p3, 2, m);
    float lp[3] = {0, 0, 2}, ld[3] = {0, 0, -1};
    tsc_spot_light(&s, lp, ld, 40, 0.4f, 0.6f);
    tsc_update_bounds(&s);
    bk_tracer *t = NULL;
    assert_int_equal(bk_tracer_create(&s, 1, &t), LBK_OK);
    bk_vpl_material mat;
    memset(&mat, 0, sizeof mat);
    mat.f0[0] = mat.f0[1] = mat.f0[2] = 0.9f;
    mat.alpha = 0.3f;
    enum { NQ = 6, M = 8 };
    bk_vpl_point q[NQ];
    memset(q, 0, sizeof q);
    const double xs[NQ] = {-1, 0, 0.5, 1, 1.5, 2.5};
    for (int i = 0; i < NQ; i++) {
        q[i].p[0] = xs[i], q[i].p[1] = 0.2 * i, q[i].p[2] = i == NQ - 1 ? 1.0 : 1.5;
        if (i == NQ - 1) q[i].n[0] = -1; /* a wall-like receiver facing the light's side */
        else q[i].n[2] = -1;
        for (int k = 0; k < 3; k++) q[i].org[k] = (float)q[i].p[k];
    }
    double ref[NQ] = {0};
    const double h = 0.005, R = 2 * tan(0.6) + 0.01;
    for (double x = -R + h / 2; x < R; x += h)
        for (double y = -R + h / 2; y < R; y += h) {
            double pt[3] = {x, y, 0}, val[3], wi[3], dist;
            if (!bk_light_eval(&s.lights[0], pt, val, wi, &dist)) continue;
            const double e = val[1] * wi[2]; /* the floor's irradiance, green */
            for (int i = 0; i < NQ; i++) {
                double wo[3] = {q[i].p[0] - x, q[i].p[1] - y, q[i].p[2]};
                double l2 = wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2], l = sqrt(l2);
                for (int k = 0; k < 3; k++) wo[k] /= l;
                double hv[3] = {wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]}, hl = sqrt(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]);
                const double f = bk_ggx_fresnel(0.9f, (hv[0] * wi[0] + hv[1] * wi[1] + hv[2] * wi[2]) / hl) * bk_ggx_spec(0.3f, wo, wi);
                const double cy = -(wo[0] * q[i].n[0] + wo[1] * q[i].n[1] + wo[2] * q[i].n[2]);
                if (cy > 0) ref[i] += e * f * wo[2] * cy / l2 * h * h;
            }
        }
    double mean[NQ] = {0}, sq[NQ] = {0};
    for (int k = 0; k < M; k++) {
        bk_vpl_shoot_desc d = {.scene = &s, .tracer = t, .materials = &mat, .seed = 50 + (uint64_t)k, .photons = 20000, .threads = 2, .key = 0};
        bk_vpl *v = NULL;
        size_t nv = 0;
        assert_int_equal(bk_vpl_shoot(&d, &s.lights[0], &v, &nv), LBK_OK);
        double irr[3 * NQ];
        assert_int_equal(bk_vpl_gather(v, nv, NULL, t, q, NQ, 2, irr, NULL), LBK_OK);
        for (int i = 0; i < NQ; i++) {
            mean[i] += irr[3 * i + 1] / M;
            sq[i] += irr[3 * i + 1] * irr[3 * i + 1] / M;
        }
        free(v);
    }
    for (int i = 0; i < NQ; i++) {
        const double se = sqrt(fmax(0.0, sq[i] - mean[i] * mean[i]) / (M - 1));
        print_message("receiver %d: integral %.6f, VPL mean %.6f (se %.6f, %.2f %%)\n", i, ref[i], mean[i], se,
                      100 * (mean[i] / ref[i] - 1));
        assert_true(ref[i] > 0);
        assert_true(fabs(mean[i] - ref[i]) < 4 * se + 1e-3 * ref[i]);
        assert_true(fabs(mean[i] - ref[i]) < 0.03 * ref[i]);
    }
    bk_tracer_destroy(t);
    tsc_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_volumes_enclose_the_range),
        cmocka_unit_test(test_box_dist_is_the_minimum),
        cmocka_unit_test(test_gather_one_vpl),
        cmocka_unit_test(test_shoot_flux),
        cmocka_unit_test(test_gather_matches_the_floor_integral),
        cmocka_unit_test(test_tiles_conservative),
        cmocka_unit_test(test_unbiased_against_every_vpl),
        cmocka_unit_test(test_threads_identical),
        cmocka_unit_test(test_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
