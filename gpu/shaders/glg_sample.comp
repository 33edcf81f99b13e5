#version 450
// Reference: lbk_glg_sample — the tetrahedral walk of lbk/tetra.h (barycentrics in double, step
// across the most negative face that has a neighbour, clamp outside the hull, scan on a cycle),
// then the visibility-weighted blend of the four probes — on the GLG section as it is
// (spec/container.md §10). Per query: the physical radiance SH and the tetra found.
#extension GL_GOOGLE_include_directive : require
#include "codecs.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Glg { uint glg[]; };
layout(std430, binding = 1) readonly buffer Queries { uint q[]; };  // per query: p.xyz (float bits), hint
layout(std430, binding = 2) writeonly buffer Out { uint o[]; };    // per query: 27 SH floats, tetra, 4 weights
layout(push_constant) uniform Push {
    uint positions, probes, tetras, adjacency, visibility; // word offsets in the section
    uint vertex_count, tetra_count, scale_bits, count;
} pc;

#define BARY_EPS packDouble2x32(uvec2(0xA0B5ED8Du, 0x3EB0C6F7u)) /* 1e-6 */
#define NONE 0xFFFFFFFFu

vec3 vpos(uint v) { return uintBitsToFloat(uvec3(glg[pc.positions + 3u * v], glg[pc.positions + 3u * v + 1u], glg[pc.positions + 3u * v + 2u])); }

double orient(vec3 a, vec3 b, vec3 c, vec3 d)
{
    precise double u0 = double(b.x) - double(a.x), u1 = double(b.y) - double(a.y), u2 = double(b.z) - double(a.z);
    precise double v0 = double(c.x) - double(a.x), v1 = double(c.y) - double(a.y), v2 = double(c.z) - double(a.z);
    precise double w0 = double(d.x) - double(a.x), w1 = double(d.y) - double(a.y), w2 = double(d.z) - double(a.z);
    precise double r = u0 * (v1 * w2 - v2 * w1) - u1 * (v0 * w2 - v2 * w0) + u2 * (v0 * w1 - v1 * w0);
    return r;
}

bool bary(uint t, vec3 p, out uint vid[4], out double b[4])
{
    vec3 v[4];
    for (int i = 0; i < 4; i++) {
        vid[i] = glg[pc.tetras + 4u * t + uint(i)];
        if (vid[i] >= pc.vertex_count) return false;
        v[i] = vpos(vid[i]);
    }
    precise double vol = orient(v[0], v[1], v[2], v[3]);
    if (!(vol > 0.0lf)) return false;
    precise double b0 = orient(p, v[1], v[2], v[3]) / vol, b1 = orient(v[0], p, v[2], v[3]) / vol;
    precise double b2 = orient(v[0], v[1], p, v[3]) / vol, b3 = 1.0lf - b0 - b1 - b2;
    b[0] = b0, b[1] = b1, b[2] = b2, b[3] = b3;
    return true;
}

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 p = uintBitsToFloat(uvec3(q[4u * i], q[4u * i + 1u], q[4u * i + 2u]));
    uint t = q[4u * i + 3u] < pc.tetra_count ? q[4u * i + 3u] : 0u;
    uint vid[4];
    double b[4];
    bool found = false;
    for (uint step = 0u; step < pc.tetra_count + 64u; step++) {
        if (!bary(t, p, vid, b)) return; // corrupt: the CPU returns LBK_ERR_CORRUPT (not in valid files)
        int best = -1;
        double worst = -BARY_EPS;
        bool negative = false;
        for (int k = 0; k < 4; k++) {
            if (b[k] >= -BARY_EPS) continue;
            negative = true;
            if (glg[pc.adjacency + 4u * t + uint(k)] == NONE) continue;
            if (b[k] < worst) worst = b[k], best = k;
        }
        if (!negative || best < 0) { found = true; break; }
        t = glg[pc.adjacency + 4u * t + uint(best)];
    }
    if (!found) { // a cycle: scan every tetra for the largest smallest barycentric
        double best_min = -1.0lf / 0.0lf;
        uint best_t = 0u;
        for (uint s = 0u; s < pc.tetra_count; s++) {
            uint v2[4];
            double c2[4];
            if (!bary(s, p, v2, c2)) return;
            double mn = c2[0];
            for (int k = 1; k < 4; k++) if (c2[k] < mn) mn = c2[k];
            if (mn > best_min) best_min = mn, best_t = s;
        }
        t = best_t;
        bary(t, p, vid, b);
    }
    // finish(): clamp, renormalise in double
    precise double c[4], s = 0.0lf;
    for (int k = 0; k < 4; k++) {
        c[k] = b[k] > 0.0lf ? b[k] : 0.0lf;
        s += c[k];
    }
    float bw[4];
    for (int k = 0; k < 4; k++) {
        precise double r = c[k] / s;
        bw[k] = s > 0.0lf ? float(r) : 0.25;
    }
    // visibility-weighted blend (glg.c)
    float w[4];
    precise float ws = 0.0;
    uint vis = glg[pc.visibility + t];
    for (int k = 0; k < 4; k++) {
        precise float x = fdiv(bw[k] * float(byte_of(vis, uint(k))), 255.0);
        w[k] = x;
        ws += x;
    }
    for (int k = 0; k < 4; k++) w[k] = ws > 0.0 ? fdiv(w[k], ws) : bw[k];
    sh9 acc;
    for (int ch = 0; ch < 3; ch++)
        for (int k = 0; k < 9; k++) acc.c[ch][k] = 0.0;
    for (int k = 0; k < 4; k++) {
        if (w[k] == 0.0) continue;
        uint words[7];
        for (int j = 0; j < 7; j++) words[j] = glg[pc.probes + 7u * vid[k] + uint(j)];
        precise float ww = w[k] * uintBitsToFloat(pc.scale_bits);
        sh9_add_scaled(acc, sh9_unpack(words), ww);
    }
    for (int ch = 0; ch < 3; ch++)
        for (int k = 0; k < 9; k++) o[32u * i + uint(9 * ch + k)] = floatBitsToUint(acc.c[ch][k]);
    o[32u * i + 27u] = t;
    for (int k = 0; k < 4; k++) o[32u * i + 28u + uint(k)] = floatBitsToUint(w[k]);
}
