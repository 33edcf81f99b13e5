/* The SIMD paths of the DLS arithmetic give the bytes of the scalar definition
 * (libformat/src/dls_kernel_scalar.c, written with the public codecs): on random bytes (every
 * exponent-31 code, short and zero directions, denormal R11G11B10F and RGB9E5 codes included), on
 * weights from 1e-30 to 3e38 of both signs (so sums overflow to ±Inf and NaN and take the
 * encoder's sanitising branches), on every count of targets modulo 8, for the fixed and the
 * variable (prefix form) batches, and on every (G, B) direction byte pair for every fourth A byte.
 * The codecs alone: the SIMD decode gives the scalar floats bit for bit on every (G, B, A) byte
 * triple (with every R byte and R11G11B10F code along), and every probe byte value; the SIMD
 * encode, whose fast path decides bytes from float approximations, gives the scalar bytes on
 * inputs placed at the exact points where a byte of the scalar encoder changes (found by
 * bisection), where an approximation that strayed past its bound would show. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/dls.h"
#include "lbk/sh.h"
#include "libformat/src/dls_kernel.h"
#include "support/dls_fixture.h"

static const dls_kernels *simd(void)
{
    const dls_kernels *k = dls_kernels_avx2();
    if (!k) {
        print_message("no AVX2 on this machine or compiler: nothing to compare\n");
        skip();
    }
    return k;
}

static void random_bytes(uint64_t *rng, uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++) p[i] = (uint8_t)dlsfx_rand(rng);
}

/* Payload bytes: half valid texels/probes (the common case), half random bytes. */
static void fill(uint64_t *rng, uint8_t *p, size_t n, uint32_t psize)
{
    for (size_t i = 0; i < n; i++) {
        if (dlsfx_rand(rng) & 1) random_bytes(rng, p + i * psize, psize);
        else if (psize == 8) dlsfx_random_texel(rng, ldexpf(1.0f, (int)(dlsfx_rand(rng) % 40) - 20), p + i * psize);
        else dlsfx_random_probe(rng, ldexpf(1.0f, (int)(dlsfx_rand(rng) % 40) - 20), p + i * psize);
    }
}

static float random_weight(uint64_t *rng)
{
    static const float pick[] = {1.0f, 0.5f, -0.25f, 1e-30f, -1e-30f, 3e38f, -3e38f, 1e20f, 7.0f, -1.0f};
    uint64_t r = dlsfx_rand(rng) % 16;
    return r < 10 ? pick[r] : 2.0f * dlsfx_uniform(rng) - 0.5f;
}

/* One fixed batch through both paths; the outputs must be byte-identical. */
static void fixed_case(const dls_kernels *v, uint64_t *rng, uint32_t space, uint32_t count, uint32_t stride)
{
    const uint32_t psize = space == 0 ? 8 : 28, bsize = space == 0 ? 4 : 28;
    uint8_t *entries = malloc((size_t)count * stride * psize);
    uint8_t *b0 = malloc((size_t)count * bsize), *b1 = malloc((size_t)count * 4);
    uint8_t *o0[2] = {malloc((size_t)count * bsize), malloc((size_t)count * bsize)};
    uint8_t *o1[2] = {malloc((size_t)count * 4), malloc((size_t)count * 4)};
    fill(rng, entries, (size_t)count * stride, psize);
    if (space == 0) {
        uint8_t *tmp = malloc((size_t)count * 8);
        fill(rng, tmp, count, 8);
        for (uint32_t t = 0; t < count; t++) memcpy(b0 + 4 * t, tmp + 8 * t, 4), memcpy(b1 + 4 * t, tmp + 8 * t + 4, 4);
        free(tmp);
    } else {
        fill(rng, b0, count, 28);
    }
    uint32_t idx[LBK_DLS_MAX_CLUSTER_SETS], m = 0;
    float w[LBK_DLS_MAX_CLUSTER_SETS];
    for (uint32_t j = 0; j < stride; j++)
        if (dlsfx_rand(rng) % 4) idx[m] = j, w[m++] = random_weight(rng);
    if (m == 0) idx[m] = 0, w[m++] = 1.0f;
    for (int p = 0; p < 2; p++) {
        dls_batch b = {.count = count, .stride = stride, .m = m, .idx = idx, .w = w, .entries = entries,
                       .base0 = b0, .base1 = b1, .out0 = o0[p], .out1 = o1[p]};
        const dls_kernels *k = p ? v : dls_kernels_scalar();
        (space == 0 ? k->texels : k->probes)(&b);
    }
    assert_memory_equal(o0[0], o0[1], (size_t)count * bsize);
    if (space == 0) assert_memory_equal(o1[0], o1[1], (size_t)count * 4);
    free(entries), free(b0), free(b1), free(o0[0]), free(o0[1]), free(o1[0]), free(o1[1]);
}

static void test_fixed_batches(void **state)
{
    (void)state;
    const dls_kernels *v = simd();
    uint64_t rng = 7;
    for (uint32_t space = 0; space < 2; space++)
        for (uint32_t count = 1; count <= 40; count++)
            for (uint32_t stride = 1; stride <= 9; stride += 2) fixed_case(v, &rng, space, count, stride);
    for (int i = 0; i < 6; i++) fixed_case(v, &rng, 0, 5000 + (uint32_t)i, 1 + (uint32_t)i);
    for (int i = 0; i < 6; i++) fixed_case(v, &rng, 1, 2000 + (uint32_t)i, 1 + (uint32_t)i);
}

static void var_case(const dls_kernels *v, uint64_t *rng, uint32_t space, uint32_t count)
{
    const uint32_t psize = space == 0 ? 8 : 28, bsize = space == 0 ? 4 : 28;
    uint32_t *n = malloc(count * 4), *off = malloc(count * 4), total = 0;
    for (uint32_t t = 0; t < count; t++) {
        n[t] = 5 + (uint32_t)(dlsfx_rand(rng) % 13);
        off[t] = total;
        total += n[t];
    }
    float *we = malloc(total * sizeof(float));
    for (uint32_t e = 0; e < total; e++) we[e] = dlsfx_rand(rng) % 3 ? 0.0f : random_weight(rng);
    for (uint32_t t = 0; t < count; t += 3) /* every third target entirely off: its base bytes */
        for (uint32_t j = 0; j < n[t]; j++) we[off[t] + j] = 0.0f;
    uint8_t *entries = malloc((size_t)total * psize), *b0 = malloc((size_t)count * bsize), *b1 = malloc((size_t)count * 4);
    uint8_t *o0[2] = {malloc((size_t)count * bsize), malloc((size_t)count * bsize)};
    uint8_t *o1[2] = {malloc((size_t)count * 4), malloc((size_t)count * 4)};
    fill(rng, entries, total, psize);
    random_bytes(rng, b0, (size_t)count * bsize);
    random_bytes(rng, b1, (size_t)count * 4);
    for (int p = 0; p < 2; p++) {
        dls_var_batch b = {.count = count, .n = n, .off = off, .we = we, .entries = entries, .base0 = b0, .base1 = b1,
                           .out0 = o0[p], .out1 = o1[p]};
        const dls_kernels *k = p ? v : dls_kernels_scalar();
        (space == 0 ? k->texels_var : k->probes_var)(&b);
    }
    assert_memory_equal(o0[0], o0[1], (size_t)count * bsize);
    if (space == 0) assert_memory_equal(o1[0], o1[1], (size_t)count * 4);
    for (uint32_t t = 0; t < count; t += 3) assert_memory_equal(o0[1] + (size_t)t * bsize, b0 + (size_t)t * bsize, bsize);
    free(n), free(off), free(we), free(entries), free(b0), free(b1), free(o0[0]), free(o0[1]), free(o1[0]), free(o1[1]);
}

static void test_variable_batches(void **state)
{
    (void)state;
    const dls_kernels *v = simd();
    uint64_t rng = 11;
    for (uint32_t space = 0; space < 2; space++)
        for (uint32_t count = 1; count <= 33; count++) var_case(v, &rng, space, count);
    var_case(v, &rng, 0, 3000);
    var_case(v, &rng, 1, 1000);
}

/* Every (G, B) direction byte pair for A = 0, 4, …, 252 and 255, with R and Ez varying along:
 * decoded, weighted with a second texel and re-encoded by both paths. */
static void test_every_direction_byte(void **state)
{
    (void)state;
    const dls_kernels *v = simd();
    const uint32_t chunk = 1u << 16;
    uint8_t *b0 = malloc(chunk * 4), *b1 = malloc(chunk * 4), *entries = malloc(chunk * 8);
    uint8_t *o0[2] = {malloc(chunk * 4), malloc(chunk * 4)}, *o1[2] = {malloc(chunk * 4), malloc(chunk * 4)};
    uint64_t rng = 99;
    uint32_t idx = 0;
    float w = 0.75f;
    for (uint32_t hi = 0; hi < 256; hi = hi == 252 ? 255 : hi + 4) { /* the A byte */
        for (uint32_t i = 0; i < chunk; i++) {
            const uint32_t rgba = (uint32_t)(dlsfx_rand(&rng) & 0xff) | (i << 8) | (hi << 24);
            const uint32_t z = (uint32_t)dlsfx_rand(&rng) & 0xF7DEF7DEu; /* no exponent 31 */
            memcpy(b0 + 4 * i, &z, 4);
            memcpy(b1 + 4 * i, &rgba, 4);
            const uint32_t ez = (uint32_t)dlsfx_rand(&rng) & 0xF7DEF7DEu, erg = (uint32_t)dlsfx_rand(&rng);
            memcpy(entries + 8 * i, &ez, 4);
            memcpy(entries + 8 * i + 4, &erg, 4);
        }
        for (int p = 0; p < 2; p++) {
            dls_batch b = {.count = chunk, .stride = 1, .m = 1, .idx = &idx, .w = &w, .entries = entries,
                           .base0 = b0, .base1 = b1, .out0 = o0[p], .out1 = o1[p]};
            (p ? v : dls_kernels_scalar())->texels(&b);
        }
        if (memcmp(o0[0], o0[1], chunk * 4) || memcmp(o1[0], o1[1], chunk * 4)) {
            for (uint32_t i = 0; i < chunk; i++)
                if (memcmp(o0[0] + 4 * i, o0[1] + 4 * i, 4) || memcmp(o1[0] + 4 * i, o1[1] + 4 * i, 4))
                    fail_msg("A=%u GB=%u: scalar %08x/%08x, %s %08x/%08x", hi, i, *(uint32_t *)(o0[0] + 4 * i),
                             *(uint32_t *)(o1[0] + 4 * i), v->name, *(uint32_t *)(o0[1] + 4 * i), *(uint32_t *)(o1[1] + 4 * i));
        }
    }
    free(b0), free(b1), free(entries), free(o0[0]), free(o0[1]), free(o1[0]), free(o1[1]);
}

/* Every (G, B, A) triple, R and each R11G11B10F channel's codes cycling along: the decoded floats. */
static void test_decode_every_direction(void **state)
{
    (void)state;
    const dls_kernels *v = simd();
    const uint32_t chunk = 1u << 16;
    uint32_t *z = malloc(chunk * 4), *rgba = malloc(chunk * 4);
    lbk_ahd_linear *l[2] = {malloc(chunk * sizeof(lbk_ahd_linear)), malloc(chunk * sizeof(lbk_ahd_linear))};
    for (uint32_t a = 0; a < 256; a++) {
        for (uint32_t i = 0; i < chunk; i++) {
            const uint32_t n = a * chunk + i;
            rgba[i] = (n * 37u & 0xff) | (i << 8) | (a << 24);
            z[i] = (n & 0x7ff) | ((n * 7u >> 3 & 0x7ff) << 11) | ((n * 13u >> 5 & 0x3ff) << 22);
        }
        dls_kernels_scalar()->texel_decode(z, rgba, chunk, l[0]);
        v->texel_decode(z, rgba, chunk, l[1]);
        if (memcmp(l[0], l[1], chunk * sizeof(lbk_ahd_linear))) {
            for (uint32_t i = 0; i < chunk; i++)
                if (memcmp(&l[0][i], &l[1][i], sizeof(lbk_ahd_linear)))
                    fail_msg("z %08x rgba %08x: scalar c0 %a %a, %s %a %a", z[i], rgba[i], l[0][i].c[0][0], l[0][i].c[0][1],
                             v->name, l[1][i].c[0][0], l[1][i].c[0][1]);
        }
    }
    free(z), free(rgba), free(l[0]), free(l[1]);
}

/* Every byte value in every SH byte of a probe, RGB9E5 words random (every exponent). */
static void test_probe_decode_every_byte(void **state)
{
    (void)state;
    const dls_kernels *v = simd();
    enum { N = 256 * 8 };
    uint8_t *p = malloc(N * 28);
    lbk_sh9_rgb *l[2] = {malloc(N * sizeof(lbk_sh9_rgb)), malloc(N * sizeof(lbk_sh9_rgb))};
    uint64_t rng = 5;
    for (uint32_t i = 0; i < N; i++) {
        random_bytes(&rng, p + 28 * i, 4);
        for (int b = 4; b < 28; b++) p[28 * i + b] = (uint8_t)(i / 8 + (uint32_t)b * (i % 8));
    }
    dls_kernels_scalar()->probe_decode(p, N, l[0]);
    v->probe_decode(p, N, l[1]);
    assert_memory_equal(l[0], l[1], N * sizeof(lbk_sh9_rgb));
    free(p), free(l[0]), free(l[1]);
}

static uint64_t encode1(const lbk_ahd_linear *in)
{
    uint32_t z, rgba;
    dls_kernels_scalar()->texel_encode(in, 1, &z, &rgba);
    return (uint64_t)z | (uint64_t)rgba << 32;
}

/* Float x moved by `ulps` representable values (through zero, skipping −0). */
static float step_float(float x, int ulps)
{
    int32_t i;
    memcpy(&i, &x, 4);
    int64_t o = i < 0 ? -(int64_t)(i & 0x7fffffff) : i; /* ordered */
    o += ulps;
    i = o < 0 ? (int32_t)(0x80000000u | (uint32_t)-o) : (int32_t)o;
    memcpy(&x, &i, 4);
    return x;
}

typedef struct probe_list {
    lbk_ahd_linear *v;
    size_t n, cap;
} probe_list;

static void push(probe_list *l, const lbk_ahd_linear *x)
{
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 4096;
        l->v = realloc(l->v, l->cap * sizeof *l->v);
    }
    l->v[l->n++] = *x;
}

/* Component `comp` (channel comp / 4, term comp % 4) of x swept over [lo, hi] on a grid; at each grid step where the scalar bytes
 * change, the two adjacent floats where they change (bisection), and 3 floats either side. */
static void boundaries(lbk_ahd_linear x, int comp, float lo, float hi, int grid, probe_list *out)
{
    float *p = &x.c[comp / 4][comp % 4];
    float prev = lo;
    *p = lo;
    uint64_t eprev = encode1(&x);
    for (int gi = 1; gi <= grid; gi++) {
        float cur = lo + (hi - lo) * (float)gi / (float)grid;
        *p = cur;
        const uint64_t ecur = encode1(&x);
        if (ecur != eprev) {
            float a = prev, b = cur; /* encode(a) != encode(b) */
            *p = a;
            const uint64_t ea = encode1(&x);
            for (int it = 0; it < 64 && step_float(a, 1) != b; it++) {
                const float m = a + (b - a) * 0.5f;
                if (m == a || m == b) break;
                *p = m;
                if (encode1(&x) == ea) a = m;
                else b = m;
            }
            for (int d = -3; d <= 3; d++) {
                *p = step_float(a, d);
                push(out, &x);
                *p = step_float(b, d);
                push(out, &x);
            }
        }
        prev = cur, eprev = ecur;
    }
}

static void test_encode_at_boundaries(void **state)
{
    (void)state;
    const dls_kernels *v = simd();
    uint64_t rng = 21;
    probe_list pl = {0};
    for (int trial = 0; trial < 40; trial++) {
        lbk_ahd_linear x;
        const float scale = ldexpf(1.0f, (int)(dlsfx_rand(&rng) % 30) - 15);
        for (int c = 0; c < 3; c++) {
            x.c[c][0] = scale * (0.2f + dlsfx_uniform(&rng));
            for (int i = 1; i < 4; i++) x.c[c][i] = scale * (dlsfx_uniform(&rng) - 0.5f) * 0.5f;
        }
        for (int comp = 0; comp < 12; comp++) { /* every component, every channel */
            const float lo = comp % 4 ? -scale : 0.0f, hi = comp % 4 ? scale : 2.0f * scale;
            boundaries(x, comp, lo, hi, 96, &pl);
        }
    }
    /* the encoder's special directions: s = 0 (no gradient), s.z exactly 0, s.z ∓ a denormal,
     * s below 1e-30, cancelling channels (the float sums' error bound fails) */
    static const float gz[] = {0.0f, 1e-45f, -1e-45f, 1e-38f, -1e-38f, 1e-31f, -1e-31f, 1e-3f, -1e-3f};
    for (int trial = 0; trial < 64; trial++) {
        lbk_ahd_linear x;
        const float e0 = ldexpf(1.0f, trial % 16 - 8) * (1.0f + dlsfx_uniform(&rng));
        const float gx = trial & 1 ? 0.0f : e0 * (dlsfx_uniform(&rng) - 0.5f);
        for (size_t q = 0; q < sizeof gz / sizeof gz[0]; q++) {
            for (int c = 0; c < 3; c++) {
                x.c[c][0] = e0;
                x.c[c][1] = c == 0 || !(trial & 2) ? gx : -gx * LBK_LUM_R / LBK_LUM_G; /* 2: R and G cancel */
                x.c[c][2] = trial & 4 ? gx : 0.0f;
                x.c[c][3] = gz[q];
            }
            push(&pl, &x);
        }
    }
    uint32_t *z[2] = {malloc(pl.n * 4), malloc(pl.n * 4)}, *rgba[2] = {malloc(pl.n * 4), malloc(pl.n * 4)};
    dls_kernels_scalar()->texel_encode(pl.v, (uint32_t)pl.n, z[0], rgba[0]);
    v->texel_encode(pl.v, (uint32_t)pl.n, z[1], rgba[1]);
    print_message("%zu inputs at byte boundaries\n", pl.n);
    assert_true(pl.n > 20000);
    for (size_t i = 0; i < pl.n; i++)
        if (z[0][i] != z[1][i] || rgba[0][i] != rgba[1][i])
            fail_msg("input %zu: scalar %08x/%08x, %s %08x/%08x", i, z[0][i], rgba[0][i], v->name, z[1][i], rgba[1][i]);
    free(pl.v), free(z[0]), free(z[1]), free(rgba[0]), free(rgba[1]);
}

/* The linear mode's lin_sum (AVX2: whole output lines non-temporal, the partial ones at either end
 * ordinary stores): every output offset within a 64-byte line, lengths across the 16- and 8-float
 * steps, 0 to 8 sources; the floats of the scalar definition bit for bit, and nothing written
 * outside the stretch (the guard floats around it keep their bytes). */
static void test_lin_sum_every_alignment(void **state)
{
    (void)state;
    const dls_kernels *v = simd();
    enum { MAXN = 200, GUARD = 36, SRC = 8 }; /* (MAXN + 2·GUARD)·4 bytes: whole 64-byte lines */
    uint64_t rng = 41;
    float *in = malloc((SRC + 1) * MAXN * sizeof(float)), *o[2];
    for (int p = 0; p < 2; p++) o[p] = aligned_alloc(64, (MAXN + 2 * GUARD) * sizeof(float));
    for (size_t i = 0; i < (SRC + 1) * (size_t)MAXN; i++) in[i] = random_weight(&rng) * (float)(i % 97 + 1);
    const float *src[SRC];
    float w[SRC];
    for (uint32_t j = 0; j < SRC; j++) src[j] = in + (1 + j) * MAXN, w[j] = random_weight(&rng);
    uint32_t cases = 0;
    for (uint32_t m = 0; m <= SRC; m++)
        for (uint32_t off = 0; off < 16; off++)
            for (uint32_t n = 0; n <= 100; n += n < 40 ? 1 : 7) {
                for (int p = 0; p < 2; p++) {
                    memset(o[p], 0x5a, (MAXN + 2 * GUARD) * sizeof(float));
                    (p ? v : dls_kernels_scalar())->lin_sum(in, src, w, m, n, o[p] + GUARD + off);
                    if (p && v->lin_end) v->lin_end();
                }
                if (memcmp(o[0], o[1], (MAXN + 2 * GUARD) * sizeof(float)))
                    fail_msg("lin_sum m %u, output offset %u floats, n %u: %s differs from scalar", m, off, n, v->name);
                cases++;
            }
    print_message("%u lin_sum stretches\n", cases);
    assert_true(v->lin_streams == (v->lin_end != NULL));
    free(in), free(o[0]), free(o[1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fixed_batches),
        cmocka_unit_test(test_variable_batches),
        cmocka_unit_test(test_every_direction_byte),
        cmocka_unit_test(test_decode_every_direction),
        cmocka_unit_test(test_probe_decode_every_byte),
        cmocka_unit_test(test_encode_at_boundaries),
        cmocka_unit_test(test_lin_sum_every_alignment),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
