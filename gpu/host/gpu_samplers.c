/* Reference samplers on a Vulkan device (gpu_samplers.h). */
#include "gpu/host/gpu_samplers.h"

#include <stdlib.h>
#include <string.h>

#include "lbk/glg.h"
#include "lbk/llg.h"

#include "ahd_irradiance.spv.h"
#include "codec_pack.spv.h"
#include "glg_sample.spv.h"
#include "llg_sample.spv.h"
#include "sh9_irradiance.spv.h"

/* One dispatch of `spirv` over n invocations with three buffers (two inputs, one output). */
static int run3(gpu_ctx *c, const uint32_t *spirv, size_t spirv_bytes, const void *in0, size_t size0, const void *in1,
                size_t size1, void *out, size_t out_size, const void *push, uint32_t push_size, uint32_t n)
{
    gpu_buffer b[3];
    gpu_pipeline p;
    memset(b, 0, sizeof b);
    int bad = gpu_buffer_create(c, size0, in0, &b[0]) || gpu_buffer_create(c, size1, in1, &b[1]) ||
              gpu_buffer_create(c, out_size, NULL, &b[2]);
    bad = bad || gpu_pipeline_create(c, spirv, spirv_bytes, 3, push_size, &p);
    if (!bad) {
        const gpu_buffer *bind[3] = {&b[0], &b[1], &b[2]};
        gpu_pipeline_bind(c, &p, bind);
        bad = gpu_begin(c);
        if (!bad) {
            gpu_dispatch(c, &p, push, n);
            gpu_barrier(c);
            bad = gpu_submit(c);
        }
        if (!bad) memcpy(out, b[2].map, out_size);
        gpu_pipeline_destroy(c, &p);
    }
    for (int i = 0; i < 3; i++) gpu_buffer_destroy(c, &b[i]);
    return bad ? -1 : 0;
}

int gpu_ahd_irradiance(gpu_ctx *c, const uint32_t *texels, const float *normals, uint32_t n, float *rgb)
{
    return run3(c, ahd_irradiance_spv, sizeof ahd_irradiance_spv, texels, 8 * (size_t)n, normals, 12 * (size_t)n, rgb,
                12 * (size_t)n, &n, 4, n);
}

int gpu_sh9_irradiance(gpu_ctx *c, const uint8_t *probes, const float *normals, uint32_t n, float *rgb)
{
    return run3(c, sh9_irradiance_spv, sizeof sh9_irradiance_spv, probes, 28 * (size_t)n, normals, 12 * (size_t)n, rgb,
                12 * (size_t)n, &n, 4, n);
}

int gpu_sh9_pack(gpu_ctx *c, const float *sh, uint32_t n, uint8_t *probes)
{
    const uint32_t push[2] = {n, 0};
    return run3(c, codec_pack_spv, sizeof codec_pack_spv, sh, 108 * (size_t)n, NULL, 16, probes, 28 * (size_t)n, push,
                sizeof push, n);
}

int gpu_ahd_from_linear(gpu_ctx *c, const float *lin, uint32_t n, uint32_t *texels)
{
    const uint32_t push[2] = {n, 1};
    return run3(c, codec_pack_spv, sizeof codec_pack_spv, lin, 48 * (size_t)n, NULL, 16, texels, 8 * (size_t)n, push,
                sizeof push, n);
}

static uint32_t word_of(const void *base, const void *p) { return (uint32_t)(((const uint8_t *)p - (const uint8_t *)base) / 4); }

int gpu_glg_sample(gpu_ctx *c, const void *glg, size_t size, const float *points, const uint32_t *hints, uint32_t n,
                   float *sh, uint32_t *tetra, float *weights)
{
    lbk_glg_view v;
    if (lbk_glg_open(glg, size, &v) != LBK_OK) return -1;
    struct {
        uint32_t positions, probes, tetras, adjacency, visibility, vertex_count, tetra_count, scale_bits, count;
    } push = {word_of(glg, v.mesh.positions), word_of(glg, v.probes), word_of(glg, v.mesh.tetras),
              word_of(glg, v.mesh.adjacency), word_of(glg, v.visibility), v.mesh.vertex_count, v.mesh.tetra_count, 0, n};
    memcpy(&push.scale_bits, &v.scale, 4);
    uint32_t *q = malloc(16 * (size_t)n + 16), *o = malloc(128 * (size_t)n + 16);
    if (!q || !o) {
        free(q), free(o);
        return -1;
    }
    for (uint32_t i = 0; i < n; i++) memcpy(&q[4 * i], &points[3 * i], 12), q[4 * i + 3] = hints ? hints[i] : 0;
    int r = run3(c, glg_sample_spv, sizeof glg_sample_spv, glg, size, q, 16 * (size_t)n, o, 128 * (size_t)n, &push,
                 sizeof push, n);
    for (uint32_t i = 0; r == 0 && i < n; i++) {
        memcpy(&sh[27 * (size_t)i], &o[32 * i], 27 * 4);
        tetra[i] = o[32 * i + 27];
        memcpy(&weights[4 * (size_t)i], &o[32 * i + 28], 16);
    }
    free(q), free(o);
    return r;
}

int gpu_llg_sample(gpu_ctx *c, const void *llg, size_t size, const float *points, const uint32_t *grids,
                   const uint32_t *vertices, uint32_t n, float *sh, float *rgb)
{
    lbk_llg_view v;
    if (lbk_llg_open(llg, size, &v) != LBK_OK) return -1;
    struct {
        uint32_t probes, vertices, scale_bits, count;
    } push = {word_of(llg, v.probes), word_of(llg, v.vertices), 0, n};
    memcpy(&push.scale_bits, &v.scale, 4);
    uint32_t *q = malloc(20 * (size_t)n + 16), *o = malloc(120 * (size_t)n + 16);
    if (!q || !o) {
        free(q), free(o);
        return -1;
    }
    for (uint32_t i = 0; i < n; i++) memcpy(&q[5 * i], &points[3 * i], 12), q[5 * i + 3] = grids[i], q[5 * i + 4] = vertices[i];
    int r = run3(c, llg_sample_spv, sizeof llg_sample_spv, llg, size, q, 20 * (size_t)n, o, 120 * (size_t)n, &push,
                 sizeof push, n);
    for (uint32_t i = 0; r == 0 && i < n; i++) {
        memcpy(&sh[27 * (size_t)i], &o[30 * i], 27 * 4);
        memcpy(&rgb[3 * (size_t)i], &o[30 * i + 27], 12);
    }
    free(q), free(o);
    return r;
}
