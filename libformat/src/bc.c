/* BC6H (unsigned), BC4 and BC5 decoding (lbk/bc.h): the D3D11 functional specification §19.5.10
 * and §19.5.13, written from its tables: a mode's fields are a list of (endpoint component, first
 * bit, bit count) in the order the block stores them, LSB first. */
#include "lbk/bc.h"

#include <string.h>

typedef struct bitreader {
    const uint8_t *p;
    unsigned pos;
} bitreader;

static unsigned take(bitreader *b, unsigned n)
{
    unsigned v = 0;
    for (unsigned i = 0; i < n; i++, b->pos++) v |= (unsigned)((b->p[b->pos >> 3] >> (b->pos & 7)) & 1u) << i;
    return v;
}

/* ---- BC6H -------------------------------------------------------------------------------- */

/* Endpoint components: w (base of region 0), x, y, z, for R, G, B; D is the partition. */
enum { RW, GW, BW, RX, GX, BX, RY, GY, BY, RZ, GZ, BZ, D, END };

typedef struct field {
    uint8_t what, first, count, reversed;
} field;

typedef struct bc6h_mode {
    uint8_t code, code_bits; /* the mode bits as read (LSB first) */
    uint8_t regions, transformed;
    uint8_t w, dr, dg, db;   /* endpoint precision: base, deltas (or the other endpoints) */
    field f[25];
} bc6h_mode;

#define F(w, a, n) {w, a, n, 0}
#define R(w, a, n) {w, a, n, 1}
static const bc6h_mode modes[14] = {
    {0x00, 2, 2, 1, 10, 5, 5, 5,
     {F(GY, 4, 1), F(BY, 4, 1), F(BZ, 4, 1), F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 5), F(GZ, 4, 1),
      F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 5),
      F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x01, 2, 2, 1, 7, 6, 6, 6,
     {F(GY, 5, 1), F(GZ, 4, 1), F(GZ, 5, 1), F(RW, 0, 7), F(BZ, 0, 1), F(BZ, 1, 1), F(BY, 4, 1), F(GW, 0, 7),
      F(BY, 5, 1), F(BZ, 2, 1), F(GY, 4, 1), F(BW, 0, 7), F(BZ, 3, 1), F(BZ, 5, 1), F(BZ, 4, 1), F(RX, 0, 6),
      F(GY, 0, 4), F(GX, 0, 6), F(GZ, 0, 4), F(BX, 0, 6), F(BY, 0, 4), F(RY, 0, 6), F(RZ, 0, 6), F(D, 0, 5),
      {END, 0, 0, 0}}},
    {0x02, 5, 2, 1, 11, 5, 4, 4,
     {F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 5), F(RW, 10, 1), F(GY, 0, 4), F(GX, 0, 4), F(GW, 10, 1),
      F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 4), F(BW, 10, 1), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 5), F(BZ, 2, 1),
      F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x06, 5, 2, 1, 11, 4, 5, 4,
     {F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 4), F(RW, 10, 1), F(GZ, 4, 1), F(GY, 0, 4), F(GX, 0, 5),
      F(GW, 10, 1), F(GZ, 0, 4), F(BX, 0, 4), F(BW, 10, 1), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 4), F(BZ, 0, 1),
      F(BZ, 2, 1), F(RZ, 0, 4), F(GY, 4, 1), F(BZ, 3, 1), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x0a, 5, 2, 1, 11, 4, 4, 5,
     {F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 4), F(RW, 10, 1), F(BY, 4, 1), F(GY, 0, 4), F(GX, 0, 4),
      F(GW, 10, 1), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BW, 10, 1), F(BY, 0, 4), F(RY, 0, 4), F(BZ, 1, 1),
      F(BZ, 2, 1), F(RZ, 0, 4), F(BZ, 4, 1), F(BZ, 3, 1), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x0e, 5, 2, 1, 9, 5, 5, 5,
     {F(RW, 0, 9), F(BY, 4, 1), F(GW, 0, 9), F(GY, 4, 1), F(BW, 0, 9), F(BZ, 4, 1), F(RX, 0, 5), F(GZ, 4, 1),
      F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 5),
      F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x12, 5, 2, 1, 8, 6, 5, 5,
     {F(RW, 0, 8), F(GZ, 4, 1), F(BY, 4, 1), F(GW, 0, 8), F(BZ, 2, 1), F(GY, 4, 1), F(BW, 0, 8), F(BZ, 3, 1),
      F(BZ, 4, 1), F(RX, 0, 6), F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1),
      F(BY, 0, 4), F(RY, 0, 6), F(RZ, 0, 6), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x16, 5, 2, 1, 8, 5, 6, 5,
     {F(RW, 0, 8), F(BZ, 0, 1), F(BY, 4, 1), F(GW, 0, 8), F(GY, 5, 1), F(GY, 4, 1), F(BW, 0, 8), F(GZ, 5, 1),
      F(BZ, 4, 1), F(RX, 0, 5), F(GZ, 4, 1), F(GY, 0, 4), F(GX, 0, 6), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1),
      F(BY, 0, 4), F(RY, 0, 5), F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x1a, 5, 2, 1, 8, 5, 5, 6,
     {F(RW, 0, 8), F(BZ, 1, 1), F(BY, 4, 1), F(GW, 0, 8), F(BY, 5, 1), F(GY, 4, 1), F(BW, 0, 8), F(BZ, 5, 1),
      F(BZ, 4, 1), F(RX, 0, 5), F(GZ, 4, 1), F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 6),
      F(BY, 0, 4), F(RY, 0, 5), F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5), {END, 0, 0, 0}}},
    {0x1e, 5, 2, 0, 6, 6, 6, 6,
     {F(RW, 0, 6), F(GZ, 4, 1), F(BZ, 0, 1), F(BZ, 1, 1), F(BY, 4, 1), F(GW, 0, 6), F(GY, 5, 1), F(BY, 5, 1),
      F(BZ, 2, 1), F(GY, 4, 1), F(BW, 0, 6), F(GZ, 5, 1), F(BZ, 3, 1), F(BZ, 5, 1), F(BZ, 4, 1), F(RX, 0, 6),
      F(GY, 0, 4), F(GX, 0, 6), F(GZ, 0, 4), F(BX, 0, 6), F(BY, 0, 4), F(RY, 0, 6), F(RZ, 0, 6), F(D, 0, 5),
      {END, 0, 0, 0}}},
    {0x03, 5, 1, 0, 10, 10, 10, 10,
     {F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 10), F(GX, 0, 10), F(BX, 0, 10), {END, 0, 0, 0}}},
    {0x07, 5, 1, 1, 11, 9, 9, 9,
     {F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 9), F(RW, 10, 1), F(GX, 0, 9), F(GW, 10, 1), F(BX, 0, 9),
      F(BW, 10, 1), {END, 0, 0, 0}}},
    {0x0b, 5, 1, 1, 12, 8, 8, 8,
     {F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 8), R(RW, 10, 2), F(GX, 0, 8), R(GW, 10, 2), F(BX, 0, 8),
      R(BW, 10, 2), {END, 0, 0, 0}}},
    {0x0f, 5, 1, 1, 16, 4, 4, 4,
     {F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 4), R(RW, 10, 6), F(GX, 0, 4), R(GW, 10, 6), F(BX, 0, 4),
      R(BW, 10, 6), {END, 0, 0, 0}}},
};
#undef F
#undef R

/* Two-region shapes (also BC7's first 32 two-subset partitions): bit i set = texel i in region 1. */
static const uint16_t shapes[32] = {
    0xcccc, 0x8888, 0xeeee, 0xecc8, 0xc880, 0xfeec, 0xfec8, 0xec80, 0xc800, 0xffec, 0xfe80,
    0xe800, 0xffe8, 0xff00, 0xfff0, 0xf000, 0xf710, 0x008e, 0x7100, 0x08ce, 0x008c, 0x7310,
    0x3100, 0x8cce, 0x088c, 0x3110, 0x6666, 0x366c, 0x17e8, 0x0ff0, 0x718e, 0x399c,
};
/* The texel of region 1 whose index is stored with one bit less (the anchor); region 0's is 0. */
static const uint8_t anchor2[32] = {15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15,
                                    15, 2,  8,  2,  2,  8,  8,  15, 2,  8,  2,  2,  8,  8,  2,  2};

static const int weights3[8] = {0, 9, 18, 27, 37, 46, 55, 64};
static const int weights4[16] = {0, 4, 9, 13, 17, 21, 26, 30, 34, 38, 43, 47, 51, 55, 60, 64};

static int find_mode(const uint8_t *block, unsigned *consumed)
{
    const unsigned two = block[0] & 3u;
    if (two < 2) {
        *consumed = 2;
        return (int)two;
    }
    const unsigned five = block[0] & 31u;
    for (int m = 2; m < 14; m++)
        if (modes[m].code == five) {
            *consumed = 5;
            return m;
        }
    return -1;
}

int lbk_bc6h_mode(const uint8_t block[LBK_BC6H_BLOCK_SIZE])
{
    unsigned n;
    const int m = find_mode(block, &n);
    return m < 0 ? 0 : m + 1;
}

static int sign_extend(unsigned v, unsigned bits) { return (int)(v << (32 - bits)) >> (32 - bits); }

/* Quantised endpoint → 16-bit unquantised value (unsigned format). */
static int unquantize(int v, int bits)
{
    if (bits >= 15) return v;
    if (v == 0) return 0;
    if (v == (1 << bits) - 1) return 0xffff;
    return ((v << 16) + 0x8000) >> bits;
}

void lbk_bc6h_unpack(const uint8_t block[LBK_BC6H_BLOCK_SIZE], uint16_t out[16][3])
{
    unsigned consumed;
    const int mi = find_mode(block, &consumed);
    if (mi < 0) {
        memset(out, 0, 16 * 3 * sizeof(uint16_t));
        return;
    }
    const bc6h_mode *m = &modes[mi];
    bitreader b = {block, consumed};
    unsigned comp[13] = {0};
    for (const field *f = m->f; f->what != END; f++) {
        const unsigned v = take(&b, f->count);
        for (unsigned i = 0; i < f->count; i++) {
            const unsigned bit = (v >> i) & 1u;
            const unsigned at = f->reversed ? f->first + f->count - 1 - i : f->first + i;
            comp[f->what] |= bit << at;
        }
    }
    const int nep = 2 * m->regions;
    const int delta_bits[3] = {m->dr, m->dg, m->db};
    int e[4][3]; /* endpoints: region 0 (w, x), region 1 (y, z); per channel */
    for (int c = 0; c < 3; c++) {
        e[0][c] = (int)comp[RW + c];
        for (int k = 1; k < nep; k++) {
            const unsigned raw = comp[RW + 3 * k + c];
            if (m->transformed) {
                const int d = sign_extend(raw, (unsigned)delta_bits[c]);
                e[k][c] = (e[0][c] + d) & ((1 << m->w) - 1);
            } else {
                e[k][c] = (int)raw;
            }
        }
        for (int k = 0; k < nep; k++) e[k][c] = unquantize(e[k][c], m->w);
    }
    const unsigned shape = m->regions == 2 ? shapes[comp[D]] : 0;
    const unsigned anchor = m->regions == 2 ? anchor2[comp[D]] : 16;
    const int ib = m->regions == 2 ? 3 : 4;
    const int *w = m->regions == 2 ? weights3 : weights4;
    for (unsigned t = 0; t < 16; t++) {
        const unsigned region = (shape >> t) & 1u;
        const unsigned n = (t == 0 || t == anchor) ? (unsigned)ib - 1 : (unsigned)ib;
        const unsigned idx = take(&b, n);
        for (int c = 0; c < 3; c++) {
            const int a = e[2 * region][c], z = e[2 * region + 1][c];
            const int v = (a * (64 - w[idx]) + z * w[idx] + 32) >> 6;
            out[t][c] = (uint16_t)((v * 31) >> 6); /* 0..0x7bff: never Inf/NaN */
        }
    }
}

/* The inverse of lbk_bc6h_unpack for one block: quantised endpoints (mode precision, absolute) and
 * indices → bytes. Deltas of the transformed modes and the anchor texels' missing index bit are
 * checked, not repaired (LBK_ERR_RANGE). */
lbk_result lbk_bc6h_pack(int mode, int shape, const int endpoints[4][3], const uint8_t index[16],
                         uint8_t out[LBK_BC6H_BLOCK_SIZE])
{
    if (mode < 1 || mode > 14 || !endpoints || !index || !out) return LBK_ERR_INVALID_ARGUMENT;
    const bc6h_mode *m = &modes[mode - 1];
    if (m->regions == 2 && (shape < 0 || shape > 31)) return LBK_ERR_INVALID_ARGUMENT;
    const int nep = 2 * m->regions, ib = m->regions == 2 ? 3 : 4;
    const int delta_bits[3] = {m->dr, m->dg, m->db};
    unsigned comp[13] = {0};
    for (int c = 0; c < 3; c++) {
        for (int k = 0; k < nep; k++)
            if (endpoints[k][c] < 0 || endpoints[k][c] > (1 << m->w) - 1) return LBK_ERR_RANGE;
        comp[RW + c] = (unsigned)endpoints[0][c];
        for (int k = 1; k < nep; k++) {
            int v = endpoints[k][c];
            if (m->transformed) {
                v -= endpoints[0][c];
                if (v < -(1 << (delta_bits[c] - 1)) || v > (1 << (delta_bits[c] - 1)) - 1) return LBK_ERR_RANGE;
            }
            comp[RW + 3 * k + c] = (unsigned)v & ((1u << delta_bits[c]) - 1);
        }
    }
    comp[D] = m->regions == 2 ? (unsigned)shape : 0;
    const unsigned anchor = m->regions == 2 ? anchor2[shape] : 16;
    for (unsigned t = 0; t < 16; t++) {
        if (index[t] >= (1u << ib)) return LBK_ERR_RANGE;
        if ((t == 0 || t == anchor) && index[t] >= (1u << (ib - 1))) return LBK_ERR_RANGE;
    }
    memset(out, 0, LBK_BC6H_BLOCK_SIZE);
    unsigned pos = 0;
#define PUT(v, n)                                                                                   \
    for (unsigned i_ = 0; i_ < (unsigned)(n); i_++, pos++)                                          \
        if (((v) >> i_) & 1u) out[pos >> 3] |= (uint8_t)(1u << (pos & 7));
    PUT((unsigned)m->code, m->code_bits);
    for (const field *f = m->f; f->what != END; f++) {
        unsigned v = 0;
        for (unsigned i = 0; i < f->count; i++) {
            const unsigned at = f->reversed ? f->first + f->count - 1 - i : f->first + i;
            v |= ((comp[f->what] >> at) & 1u) << i;
        }
        PUT(v, f->count);
    }
    for (unsigned t = 0; t < 16; t++) {
        const unsigned n = (t == 0 || t == anchor) ? (unsigned)ib - 1 : (unsigned)ib;
        PUT((unsigned)index[t], n);
    }
#undef PUT
    return LBK_OK;
}

void lbk_bc6h_mode_info(int mode, int *regions, int *endpoint_bits, int delta_bits[3], int *transformed)
{
    if (mode < 1 || mode > 14) {
        *regions = 0;
        return;
    }
    const bc6h_mode *m = &modes[mode - 1];
    *regions = m->regions, *endpoint_bits = m->w, *transformed = m->transformed;
    delta_bits[0] = m->dr, delta_bits[1] = m->dg, delta_bits[2] = m->db;
}

uint16_t lbk_bc6h_shape(int shape) { return shape >= 0 && shape < 32 ? shapes[shape] : 0; }
int lbk_bc6h_anchor(int shape) { return shape >= 0 && shape < 32 ? anchor2[shape] : 0; }

/* ---- BC4 / BC5 ----------------------------------------------------------------------------- */

void lbk_bc4_unpack(const uint8_t block[LBK_BC4_BLOCK_SIZE], float out[16])
{
    const int a = block[0], b = block[1];
    float pal[8];
    pal[0] = (float)a / 255.0f;
    pal[1] = (float)b / 255.0f;
    if (a > b) {
        for (int i = 1; i < 7; i++) pal[1 + i] = (float)((7 - i) * a + i * b) / (7.0f * 255.0f);
    } else {
        for (int i = 1; i < 5; i++) pal[1 + i] = (float)((5 - i) * a + i * b) / (5.0f * 255.0f);
        pal[6] = 0.0f;
        pal[7] = 1.0f;
    }
    uint64_t idx = 0;
    for (int i = 0; i < 6; i++) idx |= (uint64_t)block[2 + i] << (8 * i);
    for (int t = 0; t < 16; t++) out[t] = pal[(idx >> (3 * t)) & 7u];
}

void lbk_bc5_unpack(const uint8_t block[LBK_BC5_BLOCK_SIZE], float out[16][2])
{
    float r[16], g[16];
    lbk_bc4_unpack(block, r);
    lbk_bc4_unpack(block + 8, g);
    for (int t = 0; t < 16; t++) out[t][0] = r[t], out[t][1] = g[t];
}
