/* TERR: build, view and validate (spec/container.md §18, spec/validation.md 1200–1299). */
#include <math.h>

#include "lbk/error_map.h"

#include "section_util.h"

/* The 23 fraction bits of the binary32 nearest to 2^((k + ½)/16), k = 0..15: the boundaries
 * between two codes inside one octave. */
static const uint32_t half_steps[16] = {0x2cd87,  0x8980f,  0xea43a,  0x14f4f0, 0x1b8d3a, 0x227043, 0x29a15b, 0x3123f6,
                                        0x38fbaf, 0x412c4d, 0x49b9be, 0x52a81e, 0x5bfbb8, 0x65b907, 0x6fe4ba, 0x7a83b3};

uint8_t lbk_terr_encode(float rel)
{
    if (!(rel >= 0.0f) || isinf(rel)) return LBK_TERR_NO_ESTIMATE;
    uint32_t bits;
    memcpy(&bits, &rel, 4);
    const int e = (int)(bits >> 23) - 127; /* 0 and subnormals: e = -127, far below the range */
    if (e < -11) return 1;
    if (e >= 6) return 255;
    int q = 0;
    while (q < 16 && (bits & 0x7fffffu) >= half_steps[q]) q++;
    const int c = LBK_TERR_CODE_ONE + LBK_TERR_STEPS_PER_OCTAVE * e + q;
    return (uint8_t)(c < 1 ? 1 : c > 255 ? 255 : c);
}

double lbk_terr_decode(uint8_t code)
{
    if (code == LBK_TERR_NO_ESTIMATE) return -1.0;
    return exp2((double)((int)code - LBK_TERR_CODE_ONE) / LBK_TERR_STEPS_PER_OCTAVE);
}

lbk_result lbk_terr_build(uint32_t flags, const uint8_t *codes, uint64_t texel_count, const lbk_allocator *allocator,
                          void **out, size_t *size)
{
    if (!out || !size) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (!codes || texel_count == 0 || (flags & ~LBK_TERR_DENOISED)) return LBK_ERR_INVALID_ARGUMENT;
    if (texel_count > SIZE_MAX - LBK_TERR_HEADER_SIZE) return LBK_ERR_LIMIT;
    const size_t n = LBK_TERR_HEADER_SIZE + (size_t)texel_count;
    uint8_t *d = lbk_calloc(allocator, 1, n);
    if (!d) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(d + 0, LBK_TERR_LOG2_U8);
    lbk_wr32(d + 4, flags);
    lbk_wr64(d + 8, texel_count);
    memcpy(d + LBK_TERR_HEADER_SIZE, codes, (size_t)texel_count);
    *out = d;
    *size = n;
    return LBK_OK;
}

lbk_result lbk_terr_open(const void *data, size_t size, lbk_terr_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_TERR_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    const uint64_t n = lbk_rd64(d + 8);
    if (n > size - LBK_TERR_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    if (n == 0 || n != size - LBK_TERR_HEADER_SIZE) return LBK_ERR_CORRUPT;
    out->encoding = lbk_rd32(d + 0);
    out->flags = lbk_rd32(d + 4);
    if (out->encoding != LBK_TERR_LOG2_U8 || (out->flags & ~LBK_TERR_DENOISED)) return LBK_ERR_UNSUPPORTED_FEATURE;
    out->texel_count = n;
    out->codes = d + LBK_TERR_HEADER_SIZE;
    return LBK_OK;
}

lbk_result lbk_terr_code_get(const lbk_terr_view *v, uint64_t index, uint8_t *code)
{
    if (!v || !code) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= v->texel_count) return LBK_ERR_NOT_FOUND;
    *code = v->codes[index];
    return LBK_OK;
}

/* ---- validation -------------------------------------------------------------------------- */

void lbk_validate_terr(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_TERR_HEADER_SIZE) {
        lbk_vreport(ctx, 1200, 0, "TERR is %zu bytes, its header needs 16", size);
        return;
    }
    const uint32_t enc = lbk_rd32(d), flags = lbk_rd32(d + 4);
    const uint64_t n = lbk_rd64(d + 8);
    if (enc != LBK_TERR_LOG2_U8) lbk_vreport(ctx, 1201, 0, "TERR encoding %u is not defined (0: log2 u8)", enc);
    if (flags & ~LBK_TERR_DENOISED) lbk_vreport(ctx, 1202, 4, "TERR unknown flag bits 0x%08x", flags & ~LBK_TERR_DENOISED);
    if (n == 0) lbk_vreport(ctx, 1203, 8, "TERR texel_count is 0");
    else if (n != size - LBK_TERR_HEADER_SIZE)
        lbk_vreport(ctx, 1203, 8, "TERR of %llu texels needs %llu bytes, section has %zu", (unsigned long long)n,
                    (unsigned long long)(n + LBK_TERR_HEADER_SIZE), size);
    if (!lbk_vctx_has_section(ctx, LBK_SECTION_LMAP))
        lbk_vreport(ctx, 1204, 0, "TERR is present but there is no LMAP section");
    else if (ctx->lmap_ok && n != ctx->lmap_texel_count)
        lbk_vreport(ctx, 1205, 8, "TERR texel_count %llu differs from LMAP's %llu", (unsigned long long)n,
                    (unsigned long long)ctx->lmap_texel_count);
}
