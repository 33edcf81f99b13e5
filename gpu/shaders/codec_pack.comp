#version 450
// The encoders of codecs.glsl on their own, over a list of inputs: lbk_sh9_pack (27 floats, channel-
// major → 28 bytes) and lbk_ahd_from_linear (12 floats {e0, g} per channel → Ez word, RGBA word).
// The apply runs them on sums; this runs them on inputs chosen to hit their rounding ties
// (tests/gpu/test_gpu.c: RGB9E5 mantissas at exactly k + 1/2, the case llvmpipe's roundEven got
// wrong without AVX-512, GPU.md "Exactness"), which a sum reaches only by chance.
#extension GL_GOOGLE_include_directive : require
#include "codecs.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer In { float v[]; };  // 27 floats per probe, or 12 per texel
layout(std430, binding = 1) readonly buffer Unused { uint unused[]; };
layout(std430, binding = 2) writeonly buffer Out { uint o[]; };  // 7 words per probe, or 2 per texel
layout(push_constant) uniform Push { uint count, texels; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    if (pc.texels != 0u) {
        ahd_linear l;
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 4; k++) l.c[c][k] = v[12u * i + uint(4 * c + k)];
        uvec2 t = ahd_from_linear(l);
        o[2u * i] = t.x, o[2u * i + 1u] = t.y;
        return;
    }
    sh9 s;
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 9; k++) s.c[c][k] = v[27u * i + uint(9 * c + k)];
    uint w[7];
    sh9_pack(s, w);
    for (int k = 0; k < 7; k++) o[7u * i + uint(k)] = w[k];
}
