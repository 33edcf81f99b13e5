/* Block codecs (lbk/bc.h) and the encoders of lbk convert (tools/convert/lmap_encode.h):
 *   - BC6H decoding against an independent decoder: 16 384 random blocks covering all 14 modes,
 *     decoded by Mesa 22.3 llvmpipe (glCompressedTexImage2D + glGetTexImage; `make mesa-bc-check`
 *     re-runs that comparison live, bench/mesa_bc_check.c) hash to the value below, and so must ours;
 *   - lbk_bc6h_pack: random fields of every mode pack into a block that decodes to exactly the
 *     palette the specification's formulas give, and unrepresentable deltas or anchor indices are
 *     refused;
 *   - BC4/BC5: the D3D palette formulas in both modes;
 *   - the encoders: smooth HDR gradients (mean and worst relative error per gradient strength,
 *     against Mesa's encoder for scale), two charts in a block (two-region modes), texels of
 *     weight 0 ignored, deterministic; BC4 within 1/255 + a palette step; ASTC 4×4 HDR and LDR
 *     through astcenc round trip. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "lbk/bc.h"
#include "lbk/pixel.h"
#include "tools/common/astc_codec.h"
#include "tools/convert/lmap_encode.h"

static unsigned rng = 1;
static unsigned rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

/* What Mesa decodes the blocks below to (XXH3-64 of the halves, block by block, texel, channel,
 * little-endian): measured with Mesa 22.3.6 llvmpipe. */
#define MESA_BC6H_HASH 0x906ed0f65acfa109ull

static void test_bc6h_matches_mesa(void **state)
{
    (void)state;
    static const uint8_t codes[14] = {0x00, 0x01, 0x02, 0x06, 0x0a, 0x0e, 0x12, 0x16, 0x1a, 0x1e, 0x03, 0x07, 0x0b, 0x0f};
    enum { NB = 4096 };
    uint8_t *blk = malloc(16 * NB);
    XXH3_state_t *h = XXH3_createState();
    XXH3_64bits_reset(h);
    rng = 1;
    int seen[15] = {0};
    for (int round = 0; round < 4; round++) {
        for (int i = 0; i < 16 * NB; i++) blk[i] = (uint8_t)(rnd() >> 7);
        for (int i = 0; i < NB; i++) {
            const int m = i % 14;
            blk[16 * i] = (uint8_t)(m < 2 ? (blk[16 * i] & ~3u) | codes[m] : (blk[16 * i] & ~31u) | codes[m]);
        }
        for (int i = 0; i < NB; i++) {
            uint16_t out[16][3];
            lbk_bc6h_unpack(blk + 16 * i, out);
            seen[lbk_bc6h_mode(blk + 16 * i)]++;
            for (int k = 0; k < 16; k++)
                for (int c = 0; c < 3; c++) {
                    const uint8_t le[2] = {(uint8_t)out[k][c], (uint8_t)(out[k][c] >> 8)};
                    XXH3_64bits_update(h, le, 2);
                    assert_true(out[k][c] <= 0x7bff); /* never Inf/NaN */
                }
        }
    }
    assert_int_equal(XXH3_64bits_digest(h), MESA_BC6H_HASH);
    for (int m = 1; m <= 14; m++) assert_true(seen[m] > 1000);
    XXH3_freeState(h);
    /* the four reserved modes decode to zero and report mode 0 */
    static const uint8_t reserved[4] = {0x13, 0x17, 0x1b, 0x1f};
    for (int r = 0; r < 4; r++) {
        uint8_t b[16];
        for (int i = 0; i < 16; i++) b[i] = 0xff;
        b[0] = (uint8_t)((0xe0u) | reserved[r]);
        uint16_t out[16][3];
        lbk_bc6h_unpack(b, out);
        assert_int_equal(lbk_bc6h_mode(b), 0);
        for (int k = 0; k < 16; k++) assert_int_equal(out[k][0] | out[k][1] | out[k][2], 0);
    }
    free(blk);
}

static int unq(int q, int bits)
{
    if (bits >= 15) return q;
    if (q == 0) return 0;
    if (q == (1 << bits) - 1) return 0xffff;
    return ((q << 16) + 0x8000) >> bits;
}

static void test_bc6h_pack_round_trip(void **state)
{
    (void)state;
    static const int w3[8] = {0, 9, 18, 27, 37, 46, 55, 64};
    static const int w4[16] = {0, 4, 9, 13, 17, 21, 26, 30, 34, 38, 43, 47, 51, 55, 60, 64};
    rng = 7;
    for (int mode = 1; mode <= 14; mode++) {
        int regions, bits, db[3], tr;
        lbk_bc6h_mode_info(mode, &regions, &bits, db, &tr);
        assert_true(regions == 1 || regions == 2);
        for (int trial = 0; trial < 300; trial++) {
            int ep[4][3];
            uint8_t idx[16];
            const int shape = regions == 2 ? (int)(rnd() % 32) : 0;
            for (int c = 0; c < 3; c++) {
                ep[0][c] = (int)(rnd() % (1u << bits));
                for (int k = 1; k < 2 * regions; k++) {
                    if (tr) { /* a delta that fits, and stays inside the endpoint range */
                        const int span = 1 << (db[c] - 1);
                        int v = ep[0][c] + (int)(rnd() % (unsigned)(2 * span)) - span;
                        ep[k][c] = v < 0 ? 0 : v > (1 << bits) - 1 ? (1 << bits) - 1 : v;
                    } else {
                        ep[k][c] = (int)(rnd() % (1u << bits));
                    }
                }
            }
            const int ib = regions == 2 ? 3 : 4, anchor = regions == 2 ? lbk_bc6h_anchor(shape) : 0;
            for (int t = 0; t < 16; t++) {
                idx[t] = (uint8_t)(rnd() % (1u << ib));
                if (t == 0 || t == anchor) idx[t] &= (uint8_t)((1u << (ib - 1)) - 1);
            }
            uint8_t b[16];
            assert_int_equal(lbk_bc6h_pack(mode, shape, ep, idx, b), LBK_OK);
            assert_int_equal(lbk_bc6h_mode(b), mode);
            uint16_t out[16][3];
            lbk_bc6h_unpack(b, out);
            const uint16_t sh = regions == 2 ? lbk_bc6h_shape(shape) : 0;
            for (int t = 0; t < 16; t++) {
                const int r = (sh >> t) & 1, wgt = regions == 2 ? w3[idx[t]] : w4[idx[t]];
                for (int c = 0; c < 3; c++) {
                    const int a = unq(ep[2 * r][c], bits), z = unq(ep[2 * r + 1][c], bits);
                    const int want = (((a * (64 - wgt) + z * wgt + 32) >> 6) * 31) >> 6;
                    if (out[t][c] != want) fail_msg("mode %d shape %d texel %d channel %d: %u != %d", mode, shape, t, c,
                                                    out[t][c], want);
                }
            }
        }
    }
    /* refusals: a delta too large for mode 1 (5-bit deltas), an anchor index with its top bit */
    int ep[4][3] = {{0, 0, 0}, {100, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    uint8_t idx[16] = {0}, b[16];
    assert_int_equal(lbk_bc6h_pack(1, 0, ep, idx, b), LBK_ERR_RANGE);
    ep[1][0] = 3;
    assert_int_equal(lbk_bc6h_pack(1, 0, ep, idx, b), LBK_OK);
    idx[0] = 4;
    assert_int_equal(lbk_bc6h_pack(1, 0, ep, idx, b), LBK_ERR_RANGE);
    idx[0] = 0, idx[15] = 4; /* shape 0's region-1 anchor is texel 15 */
    assert_int_equal(lbk_bc6h_pack(1, 0, ep, idx, b), LBK_ERR_RANGE);
    assert_int_equal(lbk_bc6h_pack(15, 0, ep, idx, b), LBK_ERR_INVALID_ARGUMENT);
}

static void test_bc4_bc5_formulas(void **state)
{
    (void)state;
    /* a0 > a1: 8 values; a0 ≤ a1: 6 values plus 0 and 1 */
    uint8_t b[8] = {200, 60, 0, 0, 0, 0, 0, 0};
    uint64_t bits = 0;
    for (int t = 0; t < 16; t++) bits |= (uint64_t)(t % 8) << (3 * t);
    for (int i = 0; i < 6; i++) b[2 + i] = (uint8_t)(bits >> (8 * i));
    float v[16];
    lbk_bc4_unpack(b, v);
    for (int t = 0; t < 16; t++) {
        const int i = t % 8;
        const double want = i == 0 ? 200 : i == 1 ? 60 : ((8 - i) * 200.0 + (i - 1) * 60.0) / 7.0;
        assert_float_equal(v[t] * 255.0, want, 1e-3);
    }
    b[0] = 60, b[1] = 200;
    lbk_bc4_unpack(b, v);
    for (int t = 0; t < 16; t++) {
        const int i = t % 8;
        const double want = i == 0 ? 60 : i == 1 ? 200 : i == 6 ? 0 : i == 7 ? 255 : ((6 - i) * 60.0 + (i - 1) * 200.0) / 5.0;
        assert_float_equal(v[t] * 255.0, want, 1e-3);
    }
    uint8_t b5[16];
    memcpy(b5, b, 8);
    b5[8] = 255, b5[9] = 0;
    memset(b5 + 10, 0, 6);
    float v2[16][2];
    lbk_bc5_unpack(b5, v2);
    for (int t = 0; t < 16; t++) assert_float_equal(v2[t][0], v[t], 0), assert_float_equal(v2[t][1], 1.0f, 0);
}

static void test_encoders(void **state)
{
    (void)state;
    /* smooth HDR lighting: a gradient over the block (up to g per texel in x and y), any brightness
     * 2^-10 .. 2^14, coloured. Bounds: the relative error per texel and channel, mean and worst.
     * For scale, Mesa's own BC6H encoder (glTexImage2D into GL_COMPRESSED_RGB_BPTC_UNSIGNED_FLOAT
     * on llvmpipe, mode 11 only) measured on the same blocks: g 0.02 mean 0.0069 worst 0.051,
     * g 0.2 mean 0.038 worst 0.42; this encoder: 0.0011 / 0.014 and 0.0081 / 0.075. */
    static const struct { double g, mean, worst; } sets[] = {{0.005, 0.0015, 0.01}, {0.02, 0.0025, 0.02}, {0.2, 0.012, 0.1}};
    for (size_t s = 0; s < sizeof sets / sizeof sets[0]; s++) {
        rng = 11;
        double worst = 0, sum = 0;
        int n = 0;
        for (int trial = 0; trial < 1000; trial++) {
            float rgb[16][3], wt[16];
            const double base = pow(2.0, (double)(rnd() % 2400) / 100.0 - 10.0);
            const double gx = sets[s].g * (double)(rnd() % 10) / 9.0, gy = sets[s].g * (double)(rnd() % 10) / 9.0;
            const double tint[3] = {1.0, 0.6 + 0.1 * (rnd() % 8), 0.3 + 0.1 * (rnd() % 8)};
            for (int k = 0; k < 16; k++) {
                for (int c = 0; c < 3; c++) rgb[k][c] = (float)(base * tint[c] * (1 + gx * (k % 4) + gy * (k / 4)));
                wt[k] = 1;
            }
            uint8_t b[16], b2[16];
            tl_bc6h_encode_block(rgb, wt, NULL, b);
            tl_bc6h_encode_block(rgb, wt, NULL, b2);
            assert_memory_equal(b, b2, 16); /* deterministic */
            uint16_t out[16][3];
            lbk_bc6h_unpack(b, out);
            for (int k = 0; k < 16; k++)
                for (int c = 0; c < 3; c++) {
                    const double e = fabs(lbk_half_to_float(out[k][c]) - rgb[k][c]) / rgb[k][c];
                    sum += e, n++;
                    if (e > worst) worst = e;
                }
        }
        if (!(sum / n < sets[s].mean && worst < sets[s].worst))
            fail_msg("gradient %g: mean relative error %g, worst %g", sets[s].g, sum / n, worst);
    }
    /* weight 0 texels are free: a block half black, half bright, weighted to the bright half, fits it */
    float rgb[16][3], wt[16];
    for (int k = 0; k < 16; k++) {
        const int bright = k % 4 >= 2;
        for (int c = 0; c < 3; c++) rgb[k][c] = bright ? 1000.0f + 10.0f * (float)k : 0.0f;
        wt[k] = bright ? 1.0f : 0.0f;
    }
    uint8_t b[16];
    tl_bc6h_encode_block(rgb, wt, NULL, b);
    uint16_t out[16][3];
    lbk_bc6h_unpack(b, out);
    for (int k = 0; k < 16; k++)
        if (k % 4 >= 2)
            for (int c = 0; c < 3; c++) assert_true(fabs(lbk_half_to_float(out[k][c]) - rgb[k][c]) / rgb[k][c] < 0.01);
    /* with both halves weighted, the black half stays black (index 0 of a line from black) */
    for (int k = 0; k < 16; k++) wt[k] = 1;
    tl_bc6h_encode_block(rgb, wt, NULL, b);
    lbk_bc6h_unpack(b, out);
    for (int k = 0; k < 16; k++)
        for (int c = 0; c < 3; c++)
            if (k % 4 < 2) assert_true(lbk_half_to_float(out[k][c]) == 0.0f);
    /* two charts of different colour in one block (red left, blue right, each with a gradient) no
     * line through colour space fits: a two-region mode, within 10 % everywhere */
    for (int k = 0; k < 16; k++) {
        static const double red[3] = {1, 0.3, 0.1}, blue[3] = {0.1, 0.3, 1};
        const double g = 1 + 0.1 * (k / 4) + 0.05 * (k % 4);
        for (int c = 0; c < 3; c++) rgb[k][c] = (float)(g * (k % 4 >= 2 ? blue[c] : red[c]));
    }
    int owner[16];
    for (int k = 0; k < 16; k++) owner[k] = k % 4 >= 2;
    for (int pass = 0; pass < 2; pass++) {
        tl_bc6h_encode_block(rgb, wt, pass ? owner : NULL, b);
        assert_true(lbk_bc6h_mode(b) >= 1 && lbk_bc6h_mode(b) <= 10);
        lbk_bc6h_unpack(b, out);
        for (int k = 0; k < 16; k++)
            for (int c = 0; c < 3; c++) assert_true(fabs(lbk_half_to_float(out[k][c]) - rgb[k][c]) / rgb[k][c] < 0.1);
    }
    /* BC4: any values, within a palette step of the range plus rounding */
    for (int trial = 0; trial < 2000; trial++) {
        float v[16], w1[16];
        const float lo = (float)(rnd() % 200) / 255.0f, span = (float)(rnd() % 56) / 255.0f;
        for (int k = 0; k < 16; k++) v[k] = lo + span * (float)(rnd() % 1000) / 1000.0f, w1[k] = 1;
        uint8_t b4[8];
        tl_bc4_encode_block(v, w1, b4);
        float d[16];
        lbk_bc4_unpack(b4, d);
        for (int k = 0; k < 16; k++) assert_true(fabs(d[k] - v[k]) <= span / 14.0f + 1.5f / 255.0f);
    }
}

static void test_astc_round_trip(void **state)
{
    (void)state;
    enum { W = 16, H = 8 };
    float in[W * H * 4], out[W * H * 4];
    uint8_t blocks[W / 4 * H / 4 * 16];
    char err[256];
    for (int hdr = 1; hdr >= 0; hdr--) {
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                float *p = &in[4 * (y * W + x)];
                const float s = hdr ? 40.0f * (1.0f + 0.05f * (float)x + 0.03f * (float)y) : 0.3f + 0.02f * (float)x;
                p[0] = s, p[1] = 0.8f * s, p[2] = 0.5f * s, p[3] = hdr ? 1.0f : 0.5f + 0.01f * (float)y;
            }
        assert_int_equal(tl_astc_encode(in, W, H, hdr, blocks, sizeof blocks, err, sizeof err), 0);
        assert_int_equal(tl_astc_decode(blocks, sizeof blocks, W, H, hdr, out, err, sizeof err), 0);
        for (int i = 0; i < W * H * 4; i++) {
            if (hdr && i % 4 == 3) continue;
            const double e = fabs(out[i] - in[i]) / (hdr ? in[i] : 1.0f);
            if (!(e < (hdr ? 0.03 : 2.0 / 255))) fail_msg("hdr %d value %d: %g for %g", hdr, i, out[i], in[i]);
        }
    }
    /* not a multiple of 4, or too small a buffer: refused */
    assert_int_equal(tl_astc_encode(in, 6, 4, 1, blocks, sizeof blocks, err, sizeof err), -1);
    assert_int_equal(tl_astc_encode(in, W, H, 1, blocks, 16, err, sizeof err), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bc6h_matches_mesa),
        cmocka_unit_test(test_bc6h_pack_round_trip),
        cmocka_unit_test(test_bc4_bc5_formulas),
        cmocka_unit_test(test_encoders),
        cmocka_unit_test(test_astc_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
