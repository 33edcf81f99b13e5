#version 450
// Reference: lbk_llg_sample (trilinear blend of the 8 lattice probes around the point, in the
// grid's box frame) and lbk_llg_vertex_irradiance (V · E_sh(bent normal)), on the LLG section as
// it is (spec/container.md §11). Per query: the physical radiance SH and the vertex irradiance.
#extension GL_GOOGLE_include_directive : require
#include "codecs.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Llg { uint llg[]; };
layout(std430, binding = 1) readonly buffer Queries { uint q[]; }; // per query: p.xyz (float bits), grid, vertex
layout(std430, binding = 2) writeonly buffer Out { uint o[]; };   // per query: 27 SH floats, 3 irradiance floats
layout(push_constant) uniform Push { uint probes, vertices, scale_bits, count; } pc;

float gf(uint w) { return uintBitsToFloat(llg[w]); }

float sign_nz(float x) { return x >= 0.0 ? 1.0 : -1.0; }

vec3 oct_decode(float u, float v)
{
    precise float x = u, y = v;
    precise float z = 1.0 - abs(x) - abs(y);
    if (z < 0.0) {
        precise float ox = x;
        x = (1.0 - abs(y)) * sign_nz(ox);
        y = (1.0 - abs(ox)) * sign_nz(y);
    }
    precise float len = fsqrt(x * x + y * y + z * z);
    return vec3(fdiv(x, len), fdiv(y, len), fdiv(z, len));
}

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 p = uintBitsToFloat(uvec3(q[5u * i], q[5u * i + 1u], q[5u * i + 2u]));
    const uint g = 8u + 24u * q[5u * i + 3u], vertex = q[5u * i + 4u]; // grid record: byte 32 + 96·grid
    vec3 centre = vec3(gf(g), gf(g + 1u), gf(g + 2u)), half_ext = vec3(gf(g + 12u), gf(g + 13u), gf(g + 14u));
    uvec3 dims = uvec3(llg[g + 15u] & 0xffffu, llg[g + 15u] >> 16, llg[g + 16u] & 0xffffu);
    vec3 axes[3];
    for (int a = 0; a < 3; a++) axes[a] = vec3(gf(g + 3u + 3u * uint(a)), gf(g + 4u + 3u * uint(a)), gf(g + 5u + 3u * uint(a)));
    uint i0[3];
    float f[3];
    for (int a = 0; a < 3; a++) {
        precise float rel = (p.x - centre.x) * axes[a].x + (p.y - centre.y) * axes[a].y + (p.z - centre.z) * axes[a].z;
        precise float l = fdiv(rel, half_ext[a]);
        if (!(l > -1.0)) l = -1.0;
        if (l > 1.0) l = 1.0;
        precise float gc = (l + 1.0) * 0.5 * float(dims[a] - 1u);
        uint ii = uint(gc);
        if (ii > dims[a] - 2u) ii = dims[a] - 2u;
        i0[a] = ii;
        precise float fr = gc - float(ii);
        f[a] = fr;
    }
    sh9 acc;
    for (int ch = 0; ch < 3; ch++)
        for (int k = 0; k < 9; k++) acc.c[ch][k] = 0.0;
    const uint probe_offset = llg[g + 18u];
    for (uint c = 0u; c < 8u; c++) {
        uint di = c & 1u, dj = (c >> 1) & 1u, dk = (c >> 2) & 1u;
        precise float w = (di != 0u ? f[0] : 1.0 - f[0]) * (dj != 0u ? f[1] : 1.0 - f[1]) * (dk != 0u ? f[2] : 1.0 - f[2]);
        if (w == 0.0) continue;
        uint idx = probe_offset + (i0[0] + di) + dims.x * ((i0[1] + dj) + dims.y * (i0[2] + dk)), words[7];
        for (int j = 0; j < 7; j++) words[j] = llg[pc.probes + 7u * idx + uint(j)];
        precise float ww = w * uintBitsToFloat(pc.scale_bits);
        sh9_add_scaled(acc, sh9_unpack(words), ww);
    }
    for (int ch = 0; ch < 3; ch++)
        for (int k = 0; k < 9; k++) o[30u * i + uint(9 * ch + k)] = floatBitsToUint(acc.c[ch][k]);
    // the vertex: visibility, bent normal (octahedral, grid frame) to world, SH irradiance
    uint vw = llg[pc.vertices + llg[g + 20u] + vertex];
    precise float vis = unorm8_decode(byte_of(vw, 0u));
    precise float u = unorm8_decode(byte_of(vw, 1u)) * 2.0 - 1.0, v = unorm8_decode(byte_of(vw, 2u)) * 2.0 - 1.0;
    vec3 bent = oct_decode(u, v);
    precise vec3 n = vec3(0.0);
    for (int a = 0; a < 3; a++)
        for (int c = 0; c < 3; c++) n[c] = n[c] + bent[a] * axes[a][c];
    vec3 e = sh9_irradiance(acc, n);
    for (int c = 0; c < 3; c++) {
        precise float r = e[c] > 0.0 ? vis * e[c] : 0.0;
        o[30u * i + 27u + uint(c)] = floatBitsToUint(r);
    }
}
