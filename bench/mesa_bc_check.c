/* The BC codecs of liblbk and lbk convert against an independent implementation: Mesa's (llvmpipe,
 * through a surfaceless EGL context; no GPU needed). `make mesa-bc-check` (needs libegl-dev,
 * libgl-dev and Mesa's EGL driver; not part of make test, whose test_bc carries the result as a
 * golden hash).
 *   1. BC6H decode: random blocks of all 14 modes, Mesa vs lbk_bc6h_unpack, bit for bit; prints the
 *      hash tests/lib/test_bc.c expects;
 *   2. BC4 decode: Mesa decodes BC4 in 8-bit arithmetic, liblbk with the D3D float formulas:
 *      prints the largest difference (at most 1.6/255 is expected);
 *   3. BC6H encode: smooth HDR gradients encoded by tl_bc6h_encode_block and by Mesa's encoder
 *      (glTexImage2D into GL_COMPRESSED_RGB_BPTC_UNSIGNED_FLOAT), both decoded by Mesa: mean and
 *      worst relative error per gradient strength.
 * Exit 1 when a BC6H block decodes differently. */
#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "lbk/bc.h"
#include "lbk/pixel.h"
#include "tools/convert/lmap_encode.h"

enum { W = 256, NB = (W / 4) * (W / 4) };

static unsigned rng = 1;
static unsigned rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

static size_t at(int block, int k, int ch, int nch)
{
    return (size_t)nch * ((size_t)(block / (W / 4) * 4 + k / 4) * W + (size_t)(block % (W / 4) * 4 + k % 4)) + (size_t)ch;
}

static void mesa_decode(GLenum format, const uint8_t *blocks, size_t size, GLenum fmt, float *px)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glCompressedTexImage2D(GL_TEXTURE_2D, 0, format, W, W, 0, (GLsizei)size, blocks);
    glGetTexImage(GL_TEXTURE_2D, 0, fmt, GL_FLOAT, px);
    glDeleteTextures(1, &t);
}

int main(void)
{
    PFNEGLGETPLATFORMDISPLAYEXTPROC gpd = (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    EGLDisplay d = gpd ? gpd(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL) : EGL_NO_DISPLAY;
    EGLint maj, min;
    if (d == EGL_NO_DISPLAY || !eglInitialize(d, &maj, &min) || !eglBindAPI(EGL_OPENGL_API)) {
        fprintf(stderr, "mesa_bc_check: no surfaceless EGL display (Mesa's EGL driver missing?)\n");
        return 2;
    }
    const EGLint ca[] = {EGL_NONE};
    EGLContext c = eglCreateContext(d, NULL, EGL_NO_CONTEXT, ca);
    if (c == EGL_NO_CONTEXT || !eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, c)) {
        fprintf(stderr, "mesa_bc_check: no GL context\n");
        return 2;
    }
    printf("GL %s, %s\n", (const char *)glGetString(GL_VERSION), (const char *)glGetString(GL_RENDERER));
    uint8_t *blk = malloc(16 * NB);
    float *px = malloc(sizeof(float) * 3 * 16 * NB);
    if (!blk || !px) return 2;

    /* 1. BC6H decode, 4 rounds of 4096 blocks, the modes in turn */
    static const uint8_t codes[14] = {0x00, 0x01, 0x02, 0x06, 0x0a, 0x0e, 0x12, 0x16, 0x1a, 0x1e, 0x03, 0x07, 0x0b, 0x0f};
    int bad[15] = {0}, count[15] = {0};
    XXH3_state_t *hs = XXH3_createState();
    XXH3_64bits_reset(hs);
    for (int round = 0; round < 4; round++) {
        for (int i = 0; i < 16 * NB; i++) blk[i] = (uint8_t)(rnd() >> 7);
        for (int i = 0; i < NB; i++) {
            const int m = i % 14;
            blk[16 * i] = m < 2 ? (uint8_t)((blk[16 * i] & ~3u) | codes[m]) : (uint8_t)((blk[16 * i] & ~31u) | codes[m]);
        }
        mesa_decode(GL_COMPRESSED_RGB_BPTC_UNSIGNED_FLOAT, blk, 16 * NB, GL_RGB, px);
        for (int i = 0; i < NB; i++) {
            uint16_t h[16][3];
            lbk_bc6h_unpack(blk + 16 * i, h);
            const int m = lbk_bc6h_mode(blk + 16 * i);
            int differs = 0;
            count[m]++;
            for (int k = 0; k < 16; k++)
                for (int ch = 0; ch < 3; ch++) {
                    const float g = px[at(i, k, ch, 3)];
                    if (g != lbk_half_to_float(h[k][ch])) differs = 1;
                    const uint16_t hv = lbk_float_to_half(g);
                    XXH3_64bits_update(hs, &hv, 2);
                }
            bad[m] += differs;
        }
    }
    int total_bad = 0;
    printf("BC6H decode, Mesa vs liblbk: hash of Mesa's output %016llx\n", (unsigned long long)XXH3_64bits_digest(hs));
    for (int m = 1; m < 15; m++) {
        printf("  mode %2d: %5d blocks, %d differ\n", m, count[m], bad[m]);
        total_bad += bad[m];
    }
    XXH3_freeState(hs);

    /* 2. BC4 decode */
    {
        for (int i = 0; i < 8 * NB; i++) blk[i] = (uint8_t)(rnd() >> 7);
        mesa_decode(GL_COMPRESSED_RED_RGTC1, blk, 8 * NB, GL_RED, px);
        double maxd = 0;
        for (int i = 0; i < NB; i++) {
            float v[16];
            lbk_bc4_unpack(blk + 8 * i, v);
            for (int k = 0; k < 16; k++) maxd = fmax(maxd, fabs(px[at(i, k, 0, 1)] - v[k]));
        }
        printf("BC4 decode, Mesa (8-bit) vs liblbk (D3D formulas): largest difference %.2f/255\n", maxd * 255);
    }

    /* 3. BC6H encoders on smooth gradients */
    static const double gs[] = {0.005, 0.02, 0.05, 0.2};
    uint8_t *mesa = malloc(16 * NB);
    float *ref = malloc(sizeof(float) * 3 * 16 * NB);
    if (!mesa || !ref) return 2;
    printf("BC6H encode, relative error per texel and channel (both decoded by Mesa):\n");
    for (size_t s = 0; s < sizeof gs / sizeof gs[0]; s++) {
        rng = 11;
        for (int i = 0; i < NB; i++) {
            float rgb[16][3], wt[16];
            const double base = pow(2.0, (double)(rnd() % 2400) / 100.0 - 10.0);
            const double gx = gs[s] * (rnd() % 10) / 9.0, gy = gs[s] * (rnd() % 10) / 9.0;
            const double tint[3] = {1.0, 0.6 + 0.1 * (rnd() % 8), 0.3 + 0.1 * (rnd() % 8)};
            for (int k = 0; k < 16; k++) {
                for (int ch = 0; ch < 3; ch++) ref[at(i, k, ch, 3)] = rgb[k][ch] = (float)(base * tint[ch] * (1 + gx * (k % 4) + gy * (k / 4)));
                wt[k] = 1;
            }
            tl_bc6h_encode_block(rgb, wt, NULL, blk + 16 * i);
        }
        GLuint t;
        glGenTextures(1, &t);
        glBindTexture(GL_TEXTURE_2D, t);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_COMPRESSED_RGB_BPTC_UNSIGNED_FLOAT, W, W, 0, GL_RGB, GL_FLOAT, ref);
        glGetCompressedTexImage(GL_TEXTURE_2D, 0, mesa);
        glDeleteTextures(1, &t);
        printf("  gradient %.3f/texel:", gs[s]);
        for (int e = 0; e < 2; e++) {
            mesa_decode(GL_COMPRESSED_RGB_BPTC_UNSIGNED_FLOAT, e ? mesa : blk, 16 * NB, GL_RGB, px);
            double sum = 0, worst = 0;
            for (size_t j = 0; j < (size_t)3 * 16 * NB; j++) {
                const double r = fabs(px[j] - ref[j]) / ref[j];
                sum += r, worst = fmax(worst, r);
            }
            printf("  %s mean %.4f worst %.4f", e ? "Mesa" : "lbk convert", sum / (3.0 * 16 * NB), worst);
        }
        printf("\n");
    }
    free(mesa), free(ref), free(blk), free(px);
    if (total_bad) printf("FAIL: %d BC6H blocks decode differently\n", total_bad);
    return total_bad ? 1 : 0;
}
