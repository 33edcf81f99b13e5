// ASTC 4x4 encode/decode through astcenc (astc_codec.h).
#include "tools/common/astc_codec.h"

#define ASTCENC_DYNAMIC_LIBRARY 1 /* Debian ships astcenc as a shared library with C symbols */
#include <astcenc.h>

#include <cstdio>

namespace {

bool make(int hdr, bool decode_only, astcenc_context **ctx, char *err, size_t err_len)
{
    astcenc_config cfg;
    const astcenc_profile profile = hdr ? ASTCENC_PRF_HDR_RGB_LDR_A : ASTCENC_PRF_LDR;
    /* thorough: on the shared scenes' packs 0.02-0.13 points lower mean error and up to 2.6 points
     * lower p99 than medium at 1.6-2x the encode time (room_with_doors 0.42 -> 0.67 s);
     * exhaustive would cut the lamp's p99 further but costs 8-13x (tools/convert/profiles/README.md) */
    astcenc_error e = astcenc_config_init(profile, 4, 4, 1, ASTCENC_PRE_THOROUGH,
                                          decode_only ? ASTCENC_FLG_DECOMPRESS_ONLY : 0, &cfg);
    if (e == ASTCENC_SUCCESS) e = astcenc_context_alloc(&cfg, 1, ctx);
    if (e != ASTCENC_SUCCESS) {
        std::snprintf(err, err_len, "astcenc: %s", astcenc_get_error_string(e));
        return false;
    }
    return true;
}

bool shape_ok(uint32_t width, uint32_t height, size_t size, char *err, size_t err_len)
{
    if (width == 0 || height == 0 || width % 4 || height % 4) {
        std::snprintf(err, err_len, "astc: %ux%u is not whole 4x4 blocks", width, height);
        return false;
    }
    if (size / 16 < (size_t)(width / 4) * (height / 4)) {
        std::snprintf(err, err_len, "astc: %zu bytes for %ux%u texels", size, width, height);
        return false;
    }
    return true;
}

}  // namespace

extern "C" int tl_astc_encode(const float *rgba, uint32_t width, uint32_t height, int hdr, uint8_t *out,
                              size_t out_size, char *err, size_t err_len)
{
    astcenc_context *ctx = nullptr;
    if (!shape_ok(width, height, out_size, err, err_len) || !make(hdr, false, &ctx, err, err_len)) return -1;
    void *slice = const_cast<float *>(rgba);
    astcenc_image img{width, height, 1, ASTCENC_TYPE_F32, &slice};
    const astcenc_swizzle swz{ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_A};
    const astcenc_error e = astcenc_compress_image(ctx, &img, &swz, out, out_size, 0);
    astcenc_context_free(ctx);
    if (e != ASTCENC_SUCCESS) {
        std::snprintf(err, err_len, "astcenc: %s", astcenc_get_error_string(e));
        return -1;
    }
    return 0;
}

extern "C" int tl_astc_decode(const uint8_t *blocks, size_t size, uint32_t width, uint32_t height, int hdr,
                              float *rgba, char *err, size_t err_len)
{
    astcenc_context *ctx = nullptr;
    if (!shape_ok(width, height, size, err, err_len) || !make(hdr, true, &ctx, err, err_len)) return -1;
    void *slice = rgba;
    astcenc_image img{width, height, 1, ASTCENC_TYPE_F32, &slice};
    const astcenc_swizzle swz{ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_A};
    const astcenc_error e = astcenc_decompress_image(ctx, blocks, size, &img, &swz, 0);
    astcenc_context_free(ctx);
    if (e != ASTCENC_SUCCESS) {
        std::snprintf(err, err_len, "astcenc: %s", astcenc_get_error_string(e));
        return -1;
    }
    return 0;
}
