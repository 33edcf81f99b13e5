/* The SIMD paths of the DLS arithmetic give the bytes of the scalar definition
 * (libformat/src/dls_kernel_scalar.c, written with the public codecs): on random bytes (every
 * exponent-31 code, short and zero directions, denormal R11G11B10F and RGB9E5 codes included), on
 * weights from 1e-30 to 3e38 of both signs (so sums overflow to ±Inf and NaN and take the
 * encoder's sanitising branches), on every count of targets modulo 8, for the fixed and the
 * variable (prefix form) batches, and on every (G, B) direction byte pair for every fourth A byte. */
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fixed_batches),
        cmocka_unit_test(test_variable_batches),
        cmocka_unit_test(test_every_direction_byte),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
