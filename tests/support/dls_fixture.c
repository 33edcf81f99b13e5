#include "dls_fixture.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/sh.h"

uint64_t dlsfx_rand(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

float dlsfx_uniform(uint64_t *s) { return (float)(dlsfx_rand(s) >> 40) / 16777216.0f; }

void dlsfx_random_texel(uint64_t *rng, float scale, uint8_t out[8])
{
    lbk_ahd_linear lin;
    memset(&lin, 0, sizeof lin);
    float amb[3], dir[3], rgb[3];
    for (int c = 0; c < 3; c++) amb[c] = scale * dlsfx_uniform(rng);
    lbk_ahd_linear_add_ambient(&lin, amb);
    /* a light from the upper hemisphere */
    float x = 2 * dlsfx_uniform(rng) - 1, y = 2 * dlsfx_uniform(rng) - 1, z = 0.2f + dlsfx_uniform(rng);
    float n = 1.0f / sqrtf(x * x + y * y + z * z);
    dir[0] = x * n, dir[1] = y * n, dir[2] = z * n;
    for (int c = 0; c < 3; c++) rgb[c] = scale * dlsfx_uniform(rng);
    lbk_ahd_linear_add_light(&lin, dir, rgb);
    lbk_ahd_texel t;
    lbk_ahd_from_linear(&lin, &t);
    lbk_ahd_texel_pack(&t, out);
}

void dlsfx_random_probe(uint64_t *rng, float scale, uint8_t out[28])
{
    lbk_sh9_rgb sh;
    memset(&sh, 0, sizeof sh);
    for (int i = 0; i < 4; i++) {
        float d[3], rgb[3];
        float x = 2 * dlsfx_uniform(rng) - 1, y = 2 * dlsfx_uniform(rng) - 1, z = 2 * dlsfx_uniform(rng) - 1;
        float n = sqrtf(x * x + y * y + z * z) + 1e-6f;
        d[0] = x / n, d[1] = y / n, d[2] = z / n;
        for (int c = 0; c < 3; c++) rgb[c] = scale * dlsfx_uniform(rng);
        lbk_sh9_add_sample(&sh, d, rgb, 3.14159265f);
    }
    lbk_sh9_pack(&sh, out);
}

void dlsfx_init(dlsfx *fx, uint32_t set_count, uint64_t texels, uint64_t glg, uint64_t llg)
{
    memset(fx, 0, sizeof *fx);
    fx->set_count = set_count;
    fx->sets = calloc(set_count ? set_count : 1, sizeof *fx->sets);
    fx->names = calloc(set_count ? set_count : 1, sizeof *fx->names);
    fx->targets = calloc(set_count ? set_count : 1, sizeof *fx->targets);
    fx->payloads = calloc(set_count ? set_count : 1, sizeof *fx->payloads);
    fx->members = calloc(set_count ? set_count : 1, sizeof *fx->members);
    for (uint32_t s = 0; s < set_count; s++) {
        snprintf(fx->names[s], sizeof fx->names[s], "set%u", s);
        fx->sets[s].name = fx->names[s];
        fx->sets[s].kind = LBK_DLS_KIND_LIGHTS;
    }
    fx->desc.set_count = set_count;
    fx->desc.sets = fx->sets;
    fx->desc.target_count[0] = texels;
    fx->desc.target_count[1] = glg;
    fx->desc.target_count[2] = llg;
}

void dlsfx_add(dlsfx *fx, uint64_t *rng, uint32_t s, uint32_t sp, uint32_t target)
{
    lbk_dls_sparse *e = &fx->sets[s].entries[sp];
    uint32_t psize = sp == 0 ? 8 : 28;
    uint64_t n = e->count;
    if ((n & (n - 1)) == 0) { /* grow at powers of two */
        uint64_t cap = n ? 2 * n : 1;
        fx->targets[s][sp] = realloc(fx->targets[s][sp], cap * sizeof(uint32_t));
        fx->payloads[s][sp] = realloc(fx->payloads[s][sp], cap * psize);
    }
    fx->targets[s][sp][n] = target;
    if (sp == 0) dlsfx_random_texel(rng, 1.0f, fx->payloads[s][sp] + n * psize);
    else dlsfx_random_probe(rng, 1.0f, fx->payloads[s][sp] + n * psize);
    e->count = n + 1;
    e->targets = fx->targets[s][sp];
    e->payloads = fx->payloads[s][sp];
}

void dlsfx_add_range(dlsfx *fx, uint64_t *rng, uint32_t s, uint32_t sp, uint32_t first, uint32_t count)
{
    for (uint32_t i = 0; i < count; i++) dlsfx_add(fx, rng, s, sp, first + i);
}

void dlsfx_combination(dlsfx *fx, uint32_t s, uint32_t n, const uint32_t *members)
{
    fx->members[s] = realloc(fx->members[s], n * sizeof(uint32_t));
    memcpy(fx->members[s], members, n * sizeof(uint32_t));
    fx->sets[s].kind = LBK_DLS_KIND_COMBINATION;
    fx->sets[s].member_count = n;
    fx->sets[s].members = fx->members[s];
}

void dlsfx_free(dlsfx *fx)
{
    for (uint32_t s = 0; s < fx->set_count; s++) {
        for (int sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) {
            free(fx->targets[s][sp]);
            free(fx->payloads[s][sp]);
        }
        free(fx->members[s]);
    }
    free(fx->sets);
    free(fx->names);
    free(fx->targets);
    free(fx->payloads);
    free(fx->members);
    memset(fx, 0, sizeof *fx);
}

const uint8_t *dlsfx_find(const dlsfx *fx, uint32_t s, uint32_t sp, uint32_t t)
{
    const lbk_dls_sparse *e = &fx->sets[s].entries[sp];
    uint32_t psize = sp == 0 ? 8 : 28;
    for (uint64_t i = 0; i < e->count; i++)
        if (e->targets[i] == t) return (const uint8_t *)e->payloads + i * psize;
    return NULL;
}

uint32_t *dlsfx_index(const dlsfx *fx, uint32_t s, uint32_t sp)
{
    uint64_t n = fx->desc.target_count[sp];
    uint32_t *idx = calloc(n ? n : 1, sizeof *idx);
    const lbk_dls_sparse *e = &fx->sets[s].entries[sp];
    for (uint64_t i = 0; i < e->count; i++) idx[e->targets[i]] = (uint32_t)i + 1;
    return idx;
}
