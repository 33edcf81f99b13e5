#version 450
// Reference: lbk_sh9_unpack + lbk_sh9_irradiance (E(n) = Σ A_l L_k Y_k(n)) for a list of packed
// probes and unit normals, times the section's scale (a power of two: exact).
#extension GL_GOOGLE_include_directive : require
#include "codecs.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer In { uint probe[]; };     // 7 words per query
layout(std430, binding = 1) readonly buffer Normals { float nrm[]; }; // per query: x, y, z
layout(std430, binding = 2) writeonly buffer Out { float rgb[]; };
layout(push_constant) uniform Push { uint count; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    uint w[7];
    for (int k = 0; k < 7; k++) w[k] = probe[7u * i + uint(k)];
    vec3 e = sh9_irradiance(sh9_unpack(w), vec3(nrm[3u * i], nrm[3u * i + 1u], nrm[3u * i + 2u]));
    for (int c = 0; c < 3; c++) rgb[3u * i + uint(c)] = e[c];
}
