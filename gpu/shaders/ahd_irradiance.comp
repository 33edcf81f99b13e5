#version 450
// Reference: lbk_ahd_irradiance (decode an AHD texel, evaluate max(0, e0 + g·n) per channel) for
// a list of texels and tangent-space normals. The engine's lightmap shader is this with the two
// planes read from images.
#extension GL_GOOGLE_include_directive : require
#include "codecs.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer In { uint texel[]; };   // per query: Ez word, RGBA word
layout(std430, binding = 1) readonly buffer Normals { float nrm[]; }; // per query: x, y, z
layout(std430, binding = 2) writeonly buffer Out { float rgb[]; };
layout(push_constant) uniform Push { uint count; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    ahd_linear l = ahd_to_linear(texel[2u * i], texel[2u * i + 1u]);
    vec3 n = vec3(nrm[3u * i], nrm[3u * i + 1u], nrm[3u * i + 2u]);
    for (int c = 0; c < 3; c++) {
        precise float e = l.c[c][0] + l.c[c][1] * n.x + l.c[c][2] * n.y + l.c[c][3] * n.z;
        rgb[3u * i + uint(c)] = e > 0.0 ? e : 0.0;
    }
}
