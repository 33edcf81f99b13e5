// liblbk's codecs in GLSL (spec/container.md §5): R11G11B10F, RGB9E5, unorm8/snorm8, the AHD texel
// (lbk_ahd_to_linear / lbk_ahd_from_linear) and the 28-byte SH9 probe (lbk_sh9_unpack / _pack),
// written operation for operation as libformat/src/{pixel,ahd,sh}.c so that a shader gives the
// CPU's bits:
//   - every float expression is `precise` (no contraction into fma, no reassociation);
//   - float division and square root go through double, then round once to float: the exact
//     quotient or root of two floats is never within 2^-48 (relative) of a point halfway between
//     two floats, so any double result within a few ulp rounds to the correctly rounded float —
//     the IEEE result the CPU computes — on every device with shaderFloat64;
//   - the CPU's double steps are double here;
//   - NaN and sign tests look at bits, so no optimiser can fold them away;
//   - constants are given as bit patterns (a decimal literal would be rounded twice);
//   - rounding to an integer is rne_d (integer truncation and an exact remainder), never roundEven.
// Needs shaderFloat64. Assumes round-to-nearest-even (every Vulkan desktop driver and lavapipe) and
// no float denormal flushing on the (rare) paths where a float denormal can arise: weights below
// about 2^-100 or SH coefficients of that size.

#define LUM_R uintBitsToFloat(0x3E59B3D0u)    /* LBK_LUM_R 0.2126 */
#define LUM_G uintBitsToFloat(0x3F371759u)    /* LBK_LUM_G 0.7152 */
#define LUM_B uintBitsToFloat(0x3D93DD98u)    /* LBK_LUM_B 0.0722 */
#define BS1 uintBitsToFloat(0x3FDDB3D7u)      /* sh.c band_scale √3 */
#define BS2 uintBitsToFloat(0x400F1BBDu)      /* √5 */
#define SH_Y00 uintBitsToFloat(0x3E906EBBu)
#define SH_Y1 uintBitsToFloat(0x3EFA2A1Cu)
#define SH_Y2 uintBitsToFloat(0x3F8BD8A1u)
#define SH_Y20 uintBitsToFloat(0x3EA17B01u)
#define SH_Y22 uintBitsToFloat(0x3F0BD8A1u)
#define SH_A0 uintBitsToFloat(0x40490FDBu)
#define SH_A1 uintBitsToFloat(0x40060A92u)
#define SH_A2 uintBitsToFloat(0x3F490FDBu)
#define F_1E30 uintBitsToFloat(0x7149F2CAu)   /* 1e30f */
#define D_1E_30 packDouble2x32(uvec2(0xFEEBC2A0u, 0x39B4484Bu)) /* 1e-30 */
#define UF11_MAX 65024.0
#define RGB9E5_MAX 65408.0

float fdiv(float a, float b)
{
    precise double q = double(a) / double(b);
    return float(q);
}

float fsqrt(float x)
{
    precise double r = sqrt(double(x));
    return float(r);
}

// Round to nearest, ties to even, of a double |t| < 2^31 (pixel.c's rne), from integer truncation
// and an exact remainder instead of roundEven: llvmpipe without AVX-512 rounds a double vector
// of 512 bits (8 lanes) by adding ±nextafter(0.5, 0) and truncating, so every tie goes toward
// zero (GPU.md, "Exactness": half of 66,713 ties off). Truncation and a − trunc(a) are exact on
// every IEEE device, so this is too.
int rne_d(double t)
{
    bool neg = t < 0.0lf;
    precise double a = neg ? -t : t;
    int i = int(a);                  // truncation toward zero (OpConvertFToS): exact
    precise double d = a - double(i); // the fraction of a: exact (Sterbenz)
    if (d > 0.5lf || (d == 0.5lf && (i & 1) != 0)) i++;
    return neg ? -i : i;
}

bool is_nan(float x) { return (floatBitsToUint(x) & 0x7fffffffu) > 0x7f800000u; }

// ---- pixel.c ----------------------------------------------------------------------------------

// small_decode for a 5-bit exponent and M mantissa bits (code already masked).
float small_decode(uint code, uint M)
{
    uint e = code >> M, m = code & ((1u << M) - 1u);
    if (e == 0u) return ldexp(float(m), -14 - int(M));
    if (e == 31u) return m != 0u ? uintBitsToFloat(0x7fc00000u) : uintBitsToFloat(0x7f800000u);
    return uintBitsToFloat(((e + 112u) << 23) | (m << (23u - M)));
}

// small_from_magnitude: the bits `a` of a finite non-negative float.
uint small_from_magnitude(uint a, uint mbits)
{
    uint max_code = (30u << mbits) | ((1u << mbits) - 1u);
    uint ex = a >> 23;
    if (ex >= 113u) {
        if (ex > 142u) return max_code;
        uint shift = 23u - mbits;
        uint t = a - (112u << 23);
        uint r = (t + ((1u << (shift - 1u)) - 1u) + ((t >> shift) & 1u)) >> shift;
        return r > max_code ? max_code : r;
    }
    uint sig = ex == 0u ? (a & 0x7fffffu) : ((a & 0x7fffffu) | 0x800000u);
    int e = ex == 0u ? -126 : int(ex) - 127;
    int rshift = 23 - 14 - int(mbits) - e;
    if (rshift > 24) return 0u;
    uint q = sig >> uint(rshift);
    uint rem = sig & ((1u << uint(rshift)) - 1u), half_ = 1u << uint(rshift - 1);
    if (rem > half_ || (rem == half_ && (q & 1u) != 0u)) q++;
    return q;
}

uint small_unsigned_encode(float x, uint mbits)
{
    uint u = floatBitsToUint(x);
    if ((u & 0x7fffffffu) > 0x7f800000u) return 0u;
    if ((u >> 31) != 0u) return 0u;
    if (u == 0x7f800000u) return (30u << mbits) | ((1u << mbits) - 1u);
    return small_from_magnitude(u, mbits);
}

uint r11g11b10f_pack(vec3 v)
{
    return small_unsigned_encode(v.x, 6u) | (small_unsigned_encode(v.y, 6u) << 11) | (small_unsigned_encode(v.z, 5u) << 22);
}

vec3 r11g11b10f_unpack(uint p)
{
    return vec3(small_decode(p & 0x7ffu, 6u), small_decode((p >> 11) & 0x7ffu, 6u), small_decode(p >> 22, 5u));
}

float unorm8_decode(uint c) { return fdiv(float(c), 255.0); }

uint unorm8_encode(float x)
{
    if (!(x > 0.0)) return 0u;
    if (x >= 1.0) return 255u;
    precise double t = double(x) * 255.0lf;
    return uint(rne_d(t));
}

float snorm8_decode(uint c)
{
    int v = int(c << 24) >> 24;
    precise float f = fdiv(float(v), 127.0);
    return f < -1.0 ? -1.0 : f;
}

uint snorm8_encode(float x)
{
    if (is_nan(x)) return 0u;
    if (x >= 1.0) return 127u;
    if (x <= -1.0) return uint(-127) & 0xffu;
    precise double t = double(x) * 127.0lf;
    return uint(rne_d(t)) & 0xffu;
}

// lbk_rgb9e5_pack in double, as pixel.c.
uint rgb9e5_pack(vec3 rgb)
{
    double c[3];
    for (int i = 0; i < 3; i++) c[i] = !(rgb[i] > 0.0) ? 0.0lf : (double(rgb[i]) > RGB9E5_MAX ? double(RGB9E5_MAX) : double(rgb[i]));
    double maxc = c[0] > c[1] ? c[0] : c[1];
    if (c[2] > maxc) maxc = c[2];
    int exp_shared = 0;
    if (maxc > 0.0lf) {
        int e2;
        frexp(maxc, e2);
        exp_shared = (e2 - 1 < -16 ? -16 : e2 - 1) + 16;
        if (rne_d(ldexp(maxc, 24 - exp_shared)) >= 512) exp_shared++;
    }
    uint outw = uint(exp_shared) << 27;
    for (int i = 0; i < 3; i++) outw |= uint(rne_d(ldexp(c[i], 24 - exp_shared))) << (9 * i);
    return outw;
}

vec3 rgb9e5_unpack(uint p)
{
    int e = int(p >> 27) - 24;
    return vec3(ldexp(float(p & 0x1ffu), e), ldexp(float((p >> 9) & 0x1ffu), e), ldexp(float((p >> 18) & 0x1ffu), e));
}

// ---- AHD texels (ahd.c) -------------------------------------------------------------------------

struct ahd_linear {
    vec4 c[3]; // per channel {e0, g.x, g.y, g.z}
};

uint byte_of(uint w, uint i) { return (w >> (8u * i)) & 0xffu; }

vec3 decode_direction(uint rgba)
{
    precise float x = fdiv(2.0 * float(byte_of(rgba, 1u)), 255.0) - 1.0;
    precise float y = fdiv(2.0 * float(byte_of(rgba, 2u)), 255.0) - 1.0;
    precise float z = fdiv(float(byte_of(rgba, 3u)), 255.0);
    precise float len = fsqrt(x * x + y * y + z * z);
    if (len < 0.5) return vec3(0.0, 0.0, 1.0);
    return vec3(fdiv(x, len), fdiv(y, len), fdiv(z, len));
}

ahd_linear ahd_to_linear(uint z, uint rgba)
{
    vec3 ez = r11g11b10f_unpack(z);
    vec3 d = decode_direction(rgba);
    precise float r = unorm8_decode(byte_of(rgba, 0u));
    precise float k = 0.25 + 0.5 * d.z;
    ahd_linear o;
    for (int c = 0; c < 3; c++) {
        precise float e = ez[c];
        if (is_nan(e)) e = 0.0;
        if (e > UF11_MAX) e = UF11_MAX;
        precise float amb = r * e;
        precise float inten = fdiv((1.0 - r) * e, k);
        precise float e0 = amb + 0.25 * inten;
        precise float h = 0.5 * inten;
        precise vec3 g = vec3(h * d.x, h * d.y, h * d.z);
        o.c[c] = vec4(e0, g);
    }
    return o;
}

void ahd_add_scaled(inout ahd_linear acc, ahd_linear l, float w)
{
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++) {
            precise float p = w * l.c[c][i];
            precise float s = acc.c[c][i] + p;
            acc.c[c][i] = s;
        }
}

float sanitize(float x)
{
    if (is_nan(x)) return 0.0;
    if (x > F_1E30) return F_1E30;
    if (x < -F_1E30) return -F_1E30;
    return x;
}

// lbk_ahd_from_linear: returns (Ez word, RGBA word).
uvec2 ahd_from_linear(ahd_linear lin)
{
    float e0[3];
    vec3 g[3];
    for (int c = 0; c < 3; c++) {
        e0[c] = sanitize(lin.c[c][0]);
        g[c] = vec3(sanitize(lin.c[c][1]), sanitize(lin.c[c][2]), sanitize(lin.c[c][3]));
    }
    const float lum_w[3] = float[3](LUM_R, LUM_G, LUM_B);
    precise double s0 = 0.0lf, s1 = 0.0lf, s2 = 0.0lf;
    for (int c = 0; c < 3; c++) {
        s0 += double(lum_w[c]) * double(g[c].x);
        s1 += double(lum_w[c]) * double(g[c].y);
        s2 += double(lum_w[c]) * double(g[c].z);
    }
    precise double dir0 = 0.0lf, dir1 = 0.0lf, dir2 = 1.0lf;
    precise double len = sqrt(s0 * s0 + s1 * s1 + s2 * s2);
    if (len >= D_1E_30) {
        if (s2 >= 0.0lf) {
            dir0 = s0 / len, dir1 = s1 / len, dir2 = s2 / len;
        } else {
            precise double lxy = sqrt(s0 * s0 + s1 * s1);
            if (lxy >= D_1E_30) dir0 = s0 / lxy, dir1 = s1 / lxy, dir2 = 0.0lf;
        }
    }
    precise double qx = (dir0 + 1.0lf) * 0.5lf, qy = (dir1 + 1.0lf) * 0.5lf;
    uint G = unorm8_encode(float(qx)), B = unorm8_encode(float(qy)), A = unorm8_encode(float(dir2));
    uint rgba = (G << 8) | (B << 16) | (A << 24);
    vec3 d = decode_direction(rgba);
    precise float k = 0.25 + 0.5 * d.z;
    vec3 a, ez;
    precise double lum_a = 0.0lf, lum_ez = 0.0lf;
    for (int c = 0; c < 3; c++) {
        precise float gd = g[c].x * d.x + g[c].y * d.y + g[c].z * d.z;
        precise float inten = gd > 0.0 ? 2.0 * gd : 0.0;
        precise float amb = e0[c] - 0.25 * inten;
        a[c] = amb > 0.0 ? amb : 0.0;
        precise float e = a[c] + inten * k;
        ez[c] = e;
        lum_a += double(lum_w[c]) * double(a[c]);
        lum_ez += double(lum_w[c]) * double(ez[c]);
    }
    precise double ratio = lum_a / lum_ez;
    uint R = lum_ez > 0.0lf ? unorm8_encode(float(ratio)) : 255u;
    return uvec2(r11g11b10f_pack(ez), rgba | R);
}

// ---- SH9 probes (sh.c) --------------------------------------------------------------------------

struct sh9 {
    float c[3][9];
};

float band_scale(int k) { return k == 0 ? 1.0 : (k < 4 ? BS1 : BS2); }

// words[0..6]: the 28 bytes.
uint probe_byte(uint words[7], int b) { return byte_of(words[b >> 2], uint(b & 3)); }

sh9 sh9_unpack(uint words[7])
{
    vec3 dq = rgb9e5_unpack(words[0]);
    sh9 s;
    for (int c = 0; c < 3; c++) {
        s.c[c][0] = dq[c];
        for (int k = 1; k < 9; k++) {
            precise float v = snorm8_decode(probe_byte(words, 4 + 3 * (k - 1) + c)) * band_scale(k) * dq[c];
            s.c[c][k] = v;
        }
    }
    return s;
}

void sh9_add_scaled(inout sh9 acc, sh9 l, float w)
{
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++) {
            precise float p = w * l.c[c][k];
            precise float s = acc.c[c][k] + p;
            acc.c[c][k] = s;
        }
}

void sh9_pack(sh9 s, out uint words[7])
{
    words[0] = rgb9e5_pack(vec3(s.c[0][0], s.c[1][0], s.c[2][0]));
    vec3 dq = rgb9e5_unpack(words[0]);
    for (int i = 1; i < 7; i++) words[i] = 0u;
    for (int k = 1; k < 9; k++)
        for (int c = 0; c < 3; c++) {
            uint q = 0u;
            if (dq[c] > 0.0) {
                precise float div = band_scale(k) * dq[c];
                q = snorm8_encode(fdiv(s.c[c][k], div));
            }
            int b = 4 + 3 * (k - 1) + c;
            words[b >> 2] |= q << (8u * uint(b & 3));
        }
}

// lbk_sh9_basis and lbk_sh9_irradiance.
void sh9_basis(vec3 d, out float y[9])
{
    precise float x = d.x, yy = d.y, z = d.z;
    y[0] = SH_Y00;
    y[1] = SH_Y1 * yy;
    y[2] = SH_Y1 * z;
    y[3] = SH_Y1 * x;
    precise float y4 = SH_Y2 * x * yy, y5 = SH_Y2 * yy * z, y6 = SH_Y20 * (3.0 * z * z - 1.0);
    precise float y7 = SH_Y2 * x * z, y8 = SH_Y22 * (x * x - yy * yy);
    y[4] = y4, y[5] = y5, y[6] = y6, y[7] = y7, y[8] = y8;
}

vec3 sh9_irradiance(sh9 s, vec3 n)
{
    float y[9];
    sh9_basis(n, y);
    const float band_a[9] = float[9](SH_A0, SH_A1, SH_A1, SH_A1, SH_A2, SH_A2, SH_A2, SH_A2, SH_A2);
    vec3 rgb;
    for (int c = 0; c < 3; c++) {
        precise float acc = 0.0;
        for (int k = 0; k < 9; k++) {
            precise float t = band_a[k] * s.c[c][k] * y[k];
            acc = acc + t;
        }
        rgb[c] = acc;
    }
    return rgb;
}
