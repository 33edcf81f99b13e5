/* lbk diff's noise verdict, calibrated (tools/inspect/diff_noise.h):
 *   - the binomial critical count against a direct sum of the pmf;
 *   - synthetic items of Gaussian noise of known σ (texels and probes, per-channel noise): the
 *     false-alarm rate over many trials is at most α (within its binomial spread), and a mean
 *     shift, a chromaticity shift at equal luminance and a local change of a fifth of the samples
 *     are each detected;
 *   - a door state's texel entries judged against entry + base, their noise's reference level:
 *     no alarm, where against the entry's own level most samples are significant;
 *   - noise correlated over 2 × 2 texels read at its full σ by the texels' high-pass;
 *   - a small object of two levels (bright rows exact, dark rows noisy): no count alarm, the dark
 *     rows untested, a change of the bright rows seen;
 *   - real bakes of scenes/cornell_box (cheap: 256 samples): two reseeds are EQUAL, and the right
 *     wall changed from green (0.14, 0.45, 0.091) to a cyan-blue of the same luminance (0.14, 0.40,
 *     0.58) is DIFFERENT, through the chromaticity test (no item's luminance shift is significant). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lbk/ahd.h"
#include "support/bake_file.h"
#include "support/scenes_dir.h"
#include "tools/inspect/diff.h"

/* ---- the binomial tail ------------------------------------------------------------------------ */

static void test_binomial_critical(void **state)
{
    (void)state;
    const uint64_t ns[] = {1, 5, 27, 200};
    const double ps[] = {0.02, 0.1, 0.5};
    for (size_t i = 0; i < sizeof ns / sizeof *ns; i++)
        for (size_t j = 0; j < sizeof ps / sizeof *ps; j++) {
            const uint64_t n = ns[i];
            const double p = ps[j], q = 0.001 / 3;
            /* the smallest c with P(X ≥ c) ≤ q, by the pmf summed from the top */
            double tail = 0;
            uint64_t want = n + 1;
            for (uint64_t c = n + 1; c-- > 0;) {
                tail += exp(lgamma((double)n + 1) - lgamma((double)c + 1) - lgamma((double)(n - c) + 1) +
                            (double)c * log(p) + (double)(n - c) * log1p(-p));
                if (tail > q) break;
                want = c;
            }
            assert_int_equal(tl_binomial_critical(n, p, q), want);
        }
    /* 27 LLG probes at p₀ 0.02: one or two significant probes are within noise */
    assert_true(tl_binomial_critical(27, 0.02, 0.001 / 3) >= 4);
    /* independent samples: the binomial's own */
    assert_int_equal(tl_count_critical(200, 0.1, 1, 0.001), tl_binomial_critical(200, 0.1, 0.001));
}

/* ---- synthetic items ------------------------------------------------------------------------- */

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double uniform(void)
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return ((double)(rng >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(void) { return sqrt(-2 * log(uniform())) * cos(6.283185307179586 * uniform()); }

/* Significant samples in clumps of 4 (each clump significant together with probability p₀): the
 * plain binomial critical value is passed far more often than q; tl_count_critical with ν = 4
 * at most q (within 3 binomial standard deviations over the trials). */
static void test_count_critical_clumps(void **state)
{
    (void)state;
    enum { SAMPLES = 1024, CLUMP = 4, TRIALS = 20000 };
    const double p = 0.02, q = 0.01;
    const uint64_t plain = tl_binomial_critical(SAMPLES, p, q), clumped = tl_count_critical(SAMPLES, p, CLUMP, q);
    int over_plain = 0, over_clumped = 0;
    for (int t = 0; t < TRIALS; t++) {
        uint64_t count = 0;
        for (int k = 0; k < SAMPLES / CLUMP; k++) count += uniform() < p ? CLUMP : 0;
        over_plain += count >= plain, over_clumped += count >= clumped;
    }
    const double bound = q * TRIALS + 3 * sqrt(q * TRIALS) + 1;
    print_message("clumps of %d: critical %llu (binomial %llu); passed in %d (binomial %d) of %d, bound %.0f\n", CLUMP,
                  (unsigned long long)clumped, (unsigned long long)plain, over_clumped, over_plain, TRIALS, bound);
    assert_true(over_clumped <= bound);
    assert_true(over_plain > 3 * bound);
}

enum { N = 256, NORMALS = 5 };

typedef struct change {
    double shift;           /* every sample × (1 + shift) in B */
    double blue, red;       /* B's blue and red channels × (1 + x) with the green keeping the luminance */
    double local;           /* the first N/5 samples × (1 + local) */
} change;

/* One item of N samples, grey level 1..2 at each normal, each channel of each side with its own
 * relative Gaussian noise of σ; the model told σ exactly (s = t = σ, no REPT). Returns 1 when
 * beyond noise. */
static int trial(const tl_noise_model *m, int cls, double sigma, const change *c, tl_noise_stats *s)
{
    tl_noise_begin(s, m, cls, sigma, sigma);
    const int kind = tl_noise_class_get(cls)->kind;
    const int normals = kind ? 6 : NORMALS;
    const double lr = LBK_LUM_R, lg = LBK_LUM_G, lb = LBK_LUM_B;
    for (int i = 0; i < N; i++) {
        float a[6][3], b[6][3];
        const double level = 1 + (double)i / N;
        const double f = (1 + c->shift) * (i < N / 5 ? 1 + c->local : 1);
        const double fr = 1 + c->red, fb = 1 + c->blue, fg = (1 - lr * fr - lb * fb) / lg;
        for (int k = 0; k < normals; k++) {
            /* independent noise per normal and channel */
            const double ea[3] = {gauss(), gauss(), gauss()}, eb[3] = {gauss(), gauss(), gauss()};
            const double tilt = 1 - 0.1 * k;
            for (int ch = 0; ch < 3; ch++) {
                const double fc = ch == 0 ? fr : ch == 1 ? fg : fb;
                a[k][ch] = (float)(level * tilt * (1 + sigma * ea[ch]));
                b[k][ch] = (float)(level * tilt * f * fc * (1 + sigma * eb[ch]));
            }
            (void)lb;
        }
        tl_noise_add(s, m, &a[0][0], &b[0][0], normals, sigma, sigma);
    }
    tl_noise_end(s, m);
    return !s->within_noise;
}

static void test_synthetic_false_alarm_rate(void **state)
{
    (void)state;
    const double zero[2] = {0, 0};
    const double alphas[] = {0.05, 0.001};
    const int trials[] = {2000, 6000};
    const int classes[] = {TL_NOISE_TEXELS, TL_NOISE_GLG};
    for (int ai = 0; ai < 2; ai++)
        for (int ci = 0; ci < 2; ci++) {
            tl_noise_model m;
            tl_noise_model_init(&m, alphas[ai], zero, zero);
            const change none = {0};
            int alarms = 0, mean = 0, chroma = 0, share = 0;
            double z2 = 0, u2 = 0;
            for (int t = 0; t < trials[ai]; t++) {
                tl_noise_stats s;
                alarms += trial(&m, classes[ci], 0.05, &none, &s);
                mean += s.shift_significant, chroma += s.chroma_significant, share += s.share_significant;
                z2 += s.z * s.z / trials[ai];
                u2 += s.sample_rms * s.sample_rms / trials[ai];
            }
            /* calibrated, not blind: z's spread is that of the empirical term (ν = 4 doubles the
             * standard error: RMS z ½) for texels; the GLG's (κ 1.5, ν 9) about a third less; the
             * samples' deviation from their model σ is at most 1 (the +Z luminance of three
             * independent channels has 0.75 σ; probes are tested against ρ = 3 times it) */
            print_message("  RMS z %.3f, RMS u %.3f\n", sqrt(z2), sqrt(u2));
            assert_true(sqrt(z2) > 0.1 && sqrt(z2) < 0.8);
            assert_true(sqrt(u2) > 0.05 && sqrt(u2) < 1.0);
            /* at most α, within 3 binomial standard deviations of α·trials (+1 for α·trials < 1) */
            const double expect = alphas[ai] * trials[ai];
            const double bound = expect + 3 * sqrt(expect) + 1;
            print_message("α %g class %d: %d false alarms in %d trials (mean %d, chroma %d, count %d), bound %.1f\n",
                          alphas[ai], classes[ci], alarms, trials[ai], mean, chroma, share, bound);
            assert_true(alarms <= bound);
        }
}

static void test_synthetic_power(void **state)
{
    (void)state;
    const double zero[2] = {0, 0};
    tl_noise_model m;
    tl_noise_model_init(&m, 0.001, zero, zero);
    /* σ 5 % per channel and side over 256 samples: the noise of the mean is ~0.6 %; the
     * empirical term (ν 4) doubles it. A 6 % shift is ~5 of those, a 12 % blue/red hue change at
     * equal luminance likewise for the chromaticity, 20 % of the samples 50 % brighter for the
     * count (its critical value for texels, D = 4: 4 × 8 of 64 clumps, so a tenth, 26, is not
     * enough). */
    const change shift = {.shift = 0.06}, hue = {.blue = 0.12, .red = -0.12}, local = {.local = 0.5};
    int hit_shift = 0, hit_hue = 0, hit_local = 0, hue_by_lum = 0;
    for (int t = 0; t < 50; t++) {
        tl_noise_stats s;
        hit_shift += trial(&m, TL_NOISE_TEXELS, 0.05, &shift, &s) && s.shift_significant;
        hit_hue += trial(&m, TL_NOISE_TEXELS, 0.05, &hue, &s) && s.chroma_significant;
        hue_by_lum += s.shift_significant;
        hit_local += trial(&m, TL_NOISE_TEXELS, 0.05, &local, &s) && s.share_significant;
    }
    print_message("detected in 50: shift %d, hue %d (by luminance %d), local %d\n", hit_shift, hit_hue, hue_by_lum,
                  hit_local);
    assert_true(hit_shift >= 48);
    assert_true(hit_hue >= 48);
    assert_true(hue_by_lum <= 1); /* the same luminance: the luminance test alone was blind */
    assert_true(hit_local >= 48);
}

/* A door state's texel entries: a twentieth of the base light under them, with noise of σ
 * relative to entry + base (the runs they are differences of). Told that reference level, the
 * model's u per sample is N(0, 0.75²) (the +Z luminance of three independent channels has 0.75 σ),
 * so samples beyond k_sample = 3.29 are rarer than 0.001 and the count's critical value at α/6
 * (p₀ 8 %) is reached in none of 200 items; RMS u 0.75. Judged against the entry's own level, σ
 * is 21× too small: most samples are significant and every item's count is. */
static void test_synthetic_set_entries(void **state)
{
    (void)state;
    const double zero[2] = {0, 0}, sigma = 0.03;
    tl_noise_model m;
    tl_noise_model_init(&m, 0.001, zero, zero);
    int alarms = 0, own_alarms = 0;
    double u2 = 0, own_share = 0;
    for (int t = 0; t < 200; t++) {
        tl_noise_stats s, own;
        tl_noise_begin(&s, &m, TL_NOISE_DOOR_TEXELS, sigma * 21, sigma * 21);
        tl_noise_begin(&own, &m, TL_NOISE_DOOR_TEXELS, sigma * 21, sigma * 21);
        for (int i = 0; i < N; i++) {
            const double base = 1 + (double)i / N, entry = 0.05 * base, ref = entry + base;
            float a[NORMALS][3], b[NORMALS][3];
            for (int k = 0; k < NORMALS; k++)
                for (int ch = 0; ch < 3; ch++) {
                    a[k][ch] = (float)(entry + sigma * ref * gauss());
                    b[k][ch] = (float)(entry + sigma * ref * gauss());
                }
            const double la = LBK_LUM_R * a[0][0] + LBK_LUM_G * a[0][1] + LBK_LUM_B * a[0][2];
            const double lb = LBK_LUM_R * b[0][0] + LBK_LUM_G * b[0][1] + LBK_LUM_B * b[0][2];
            tl_noise_add_ref(&s, &m, &a[0][0], &b[0][0], NORMALS, sigma, sigma, la + base, lb + base);
            tl_noise_add(&own, &m, &a[0][0], &b[0][0], NORMALS, sigma, sigma);
        }
        tl_noise_end(&s, &m);
        tl_noise_end(&own, &m);
        alarms += s.share_significant;
        own_alarms += own.share_significant;
        u2 += s.sample_rms * s.sample_rms / 200;
        own_share += (double)own.significant / own.count / 200;
    }
    print_message("set entries: count alarms %d/200 against entry + base (RMS u %.3f), %d/200 against the "
                  "entry (%.0f %% significant)\n", alarms, sqrt(u2), own_alarms, 100 * own_share);
    assert_int_equal(alarms, 0);
    assert_true(sqrt(u2) > 0.6 && sqrt(u2) < 0.9);
    assert_true(own_alarms == 200 && own_share > 0.5);
}

/* Noise correlated over 2 × 2 texels (a radiosity cache's cells): against its nearest neighbours
 * a texel's residual has 0.375 σ² (two of the four share its block), which the 1.25 σ² scale
 * reads as 0.55 σ; against neighbours 2 texels away, all in other blocks, σ. The high-pass takes
 * the larger: σ within the robust spread's sampling error (60 × 60 texels: ~3 %; bound 15 %). */
static void test_highpass_correlated_noise(void **state)
{
    (void)state;
    enum { W = 64 };
    static float v[W * W], ref[W * W];
    const double sigma = 0.05;
    double block[W / 2][W / 2];
    for (int j = 0; j < W / 2; j++)
        for (int i = 0; i < W / 2; i++) block[j][i] = gauss();
    for (int y = 0; y < W; y++)
        for (int x = 0; x < W; x++) {
            ref[y * W + x] = 1;
            v[y * W + x] = (float)(1 + sigma * block[y / 2][x / 2]);
        }
    const double s = tl_noise_highpass(v, ref, W, W);
    print_message("2 x 2 correlated noise of sigma %.3f: high-pass %.4f\n", sigma, s);
    assert_true(fabs(s / sigma - 1) < 0.15);
}

/* A small object of two levels (lights_punctual_lamp's 6 × 12 node1 at the high preset, its
 * exported texels): its lower 8 rows lit directly, the same on every seed up to σ 0.2 %, its
 * upper 4 rows 100× darker and lit only by bounces, σ ~50 %. Most of the object's 16 interior
 * residuals are the bright rows', so their median reads 0.2 %: the dark rows' reseed changes
 * read ~100σ, and the count test was significant in 113 of 1000 trials (in 3 of 20 of the
 * lamp's reseed pairs). A texel is tested against residuals at its own level
 * (TL_NOISE_LEVEL_BAND): the dark rows have 4, too few to tell their noise, so they are not
 * count-tested. The bright rows keep the object's σ, which the residuals reaching across the
 * two levels inflate (~15 %): this object cannot tell a few percent, but its bright rows 25 %
 * brighter are DIFFERENT (the mean shift). */
static int two_level_trial(const tl_noise_model *m, double bright_change, int want_verdict, uint64_t *tested)
{
    enum { W = 6, H = 12, DARK_ROWS = 4 };
    float v[2][W * H], local[2][W * H];
    double s[2];
    for (int side = 0; side < 2; side++) {
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const int bright = y >= DARK_ROWS;
                const double f = side && bright ? 1 + bright_change : 1;
                /* the dark rows log-normal (σ of the log 0.5: a relative σ ~53 %, never unlit) */
                const double e = bright ? 1 + 0.002 * gauss() : exp(0.5 * gauss() - 0.125);
                v[side][y * W + x] = (float)((bright ? 2.3 : 0.023) * f * e);
            }
        s[side] = tl_noise_highpass(v[side], v[side], W, H);
        assert_true(s[side] >= 0); /* 16 interior residuals: the object has its own noise */
        tl_noise_highpass_tiles(v[side], W, H, s[side], local[side]);
    }
    tl_noise_stats st;
    tl_noise_begin(&st, m, TL_NOISE_TEXELS, s[0], s[1]);
    for (int i = 0; i < W * H; i++) {
        const float a[3] = {v[0][i], v[0][i], v[0][i]}, b[3] = {v[1][i], v[1][i], v[1][i]};
        tl_noise_add(&st, m, a, b, 1, local[0][i], local[1][i]);
    }
    tl_noise_end(&st, m);
    *tested = st.tested;
    return want_verdict ? !st.within_noise : st.share_significant;
}

static void test_two_level_object(void **state)
{
    (void)state;
    const double zero[2] = {0, 0};
    tl_noise_model m;
    tl_noise_model_init(&m, 0.001, zero, zero);
    int alarms = 0, seen = 0;
    uint64_t tested, most = 0;
    for (int t = 0; t < 1000; t++) {
        alarms += two_level_trial(&m, 0, 0, &tested);
        most = tested > most ? tested : most;
    }
    for (int t = 0; t < 50; t++) seen += two_level_trial(&m, 0.25, 1, &tested);
    print_message("two-level object: count alarms %d/1000 (at most %llu of 72 samples tested), the bright rows "
                  "25 %% brighter DIFFERENT %d/50\n", alarms, (unsigned long long)most, seen);
    assert_true(alarms <= 0.001 * 1000 + 3 * sqrt(0.001 * 1000) + 1);
    assert_true(most <= 8 * 6); /* the dark rows are never count-tested */
    assert_true(seen >= 48);
}

/* ---- real bakes: cornell_box -------------------------------------------------------------------- */

static char tmpdir[64];
enum { BASE, RESEED, RESEED2, HUE, BAKES };
static tl_bake bakes[BAKES];

/* The Cornell box with its right wall's base colour replaced (the glTF text edited). */
static void write_hue_scene(const char *src, const char *dst)
{
    FILE *f = fopen(src, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    const long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)size + 1);
    assert_non_null(text);
    assert_int_equal(fread(text, 1, (size_t)size, f), (size_t)size);
    text[size] = 0;
    fclose(f);
    /* rightWall's green and blue, each once in the file */
    const char *g = "0.44999998807907104", *b = "0.09099999815225601";
    char *pg = strstr(text, g), *pb = strstr(text, b);
    assert_non_null(pg);
    assert_non_null(pb);
    assert_null(strstr(pg + 1, g));
    assert_null(strstr(pb + 1, b));
    FILE *o = fopen(dst, "wb");
    assert_non_null(o);
    fwrite(text, 1, (size_t)(pg - text), o);
    fputs("0.40000000000000000", o); /* 0.2126·0.14 + 0.7152·0.45 + 0.0722·0.091 = 0.3583 */
    fwrite(pg + strlen(g), 1, (size_t)(pb - pg - (long)strlen(g)), o);
    fputs("0.58000000000000000", o); /* 0.2126·0.14 + 0.7152·0.40 + 0.0722·0.58 = 0.3577 */
    fputs(pb + strlen(b), o);
    fclose(o);
    free(text);
}

static void bake(const char *gltf, uint64_t seed, int which)
{
    char out[128], err[1024];
    snprintf(out, sizeof out, "%s/b%d.lbk", tmpdir, which);
    tb_job job = {gltf, out, NULL, {0}};
    job.d.seed = seed;
    job.d.max_samples = 256;
    assert_int_equal(tb_bake(&job, NULL, err, sizeof err), LBK_OK);
    if (tl_bake_open_file(out, &bakes[which], err) != TL_OPEN_OK) fail_msg("%s", err);
}

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk_diff_calib_XXXXXX");
    if (!mkdtemp(tmpdir)) return -1;
    char gltf[1024], hue[160];
    SD_REQUIRE(sd_path(gltf, sizeof gltf, "cornell_box/CornellBox-Original.gltf"));
    snprintf(hue, sizeof hue, "%s/cornell_hue.gltf", tmpdir);
    write_hue_scene(gltf, hue);
    bake(gltf, 1, BASE);
    bake(gltf, 2, RESEED);
    bake(gltf, 3, RESEED2);
    bake(hue, 4, HUE);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char p[160];
    for (int i = 0; i < BAKES; i++) {
        tl_bake_close(&bakes[i]);
        snprintf(p, sizeof p, "%s/b%d.lbk", tmpdir, i);
        unlink(p);
    }
    snprintf(p, sizeof p, "%s/cornell_hue.gltf", tmpdir);
    unlink(p);
    rmdir(tmpdir);
    return 0;
}

static void diff(int a, int b, tl_diff_result *r)
{
    tl_diff_options o = {0};
    o.mode = TL_DIFF_MODE_AUTO; /* lbk diff's default */
    char err[TL_ERR_LEN];
    assert_int_equal(tl_diff_run(&bakes[a], &bakes[b], &o, r, err), 0);
    assert_int_equal(r->mode, TL_DIFF_MODE_NOISE);
}

static void test_cornell_reseeds_equal(void **state)
{
    (void)state;
    const int pairs[][2] = {{BASE, RESEED}, {BASE, RESEED2}, {RESEED, RESEED2}};
    for (int p = 0; p < 3; p++) {
        tl_diff_result r;
        diff(pairs[p][0], pairs[p][1], &r);
        for (size_t i = 0; i < r.object_count; i++) {
            const tl_noise_stats *n = &r.objects[i].noise;
            if (!n->within_noise)
                fail_msg("seeds %d/%d %s: z %+.2f chroma z %.2f significant %llu/%llu", pairs[p][0] + 1,
                         pairs[p][1] + 1, r.objects[i].name, n->z, n->chroma_z, (unsigned long long)n->significant,
                         (unsigned long long)n->count);
        }
        assert_true(r.glg.noise.within_noise);
        assert_int_equal(r.items_beyond_noise, 0);
        assert_int_equal(r.differ, 0);
        tl_diff_free(&r);
    }
}

static void test_cornell_hue_change_differs(void **state)
{
    (void)state;
    tl_diff_result r;
    diff(BASE, HUE, &r);
    assert_int_equal(r.differ, 1);
    uint32_t chroma = 0, shifted = 0;
    double max_blue = 0;
    for (size_t i = 0; i < r.object_count; i++) {
        const tl_noise_stats *n = &r.objects[i].noise;
        chroma += n->chroma_significant;
        shifted += n->shift_significant;
        max_blue = fmax(max_blue, n->chroma_shift[2]);
    }
    print_message("hue: %u items by chromaticity, %u by luminance shift, largest blue shift %+.3f\n", chroma,
                  shifted, max_blue);
    assert_true(chroma >= 1);
    /* the bounce light of a bluer wall: blue up by several per cent where it lands */
    assert_true(max_blue > 0.03);
    tl_diff_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_binomial_critical),
        cmocka_unit_test(test_count_critical_clumps),
        cmocka_unit_test(test_synthetic_false_alarm_rate),
        cmocka_unit_test(test_synthetic_power),
        cmocka_unit_test(test_synthetic_set_entries),
        cmocka_unit_test(test_highpass_correlated_noise),
        cmocka_unit_test(test_two_level_object),
        cmocka_unit_test(test_cornell_reseeds_equal),
        cmocka_unit_test(test_cornell_hue_change_differs),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
