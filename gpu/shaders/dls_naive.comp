#version 450
// The naive per-target gather the seed rejects (seed 001 §3.3, "Naive solutions"), for the
// benchmark only: one dispatch per target space; every target reads its record — the entry
// count, then per entry the set index and the payload — from a per-target offset, and loops over
// its own number of entries (divergent). Same arithmetic as dls_apply.comp, same bytes.
#extension GL_GOOGLE_include_directive : require
#include "codecs.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Records { uint rec[]; };   // per target: n, then n × (set, payload words)
layout(std430, binding = 1) readonly buffer Offsets { uint offs[]; };  // per target: its record's first word
layout(std430, binding = 2) readonly buffer Weights { float weight[]; };
layout(std430, binding = 3) readonly buffer LmapBase { uint lmap_base[]; };
layout(std430, binding = 4) buffer LmapOut { uint lmap_out[]; };
layout(std430, binding = 5) readonly buffer GlgBase { uint glg_base[]; };
layout(std430, binding = 6) buffer GlgOut { uint glg_out[]; };
layout(std430, binding = 7) readonly buffer LlgBase { uint llg_base[]; };
layout(std430, binding = 8) buffer LlgOut { uint llg_out[]; };

layout(push_constant) uniform Push { uint space, count, offsets; } pc;

uvec2 texel_words(uint t)
{
    uint lo = 0u, hi = lmap_base[0];
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (lmap_base[4u + 8u * mid + 2u] <= t) lo = mid;
        else hi = mid;
    }
    uint e = 4u + 8u * lo, local = t - lmap_base[e + 2u];
    return uvec2(lmap_base[e + 4u] / 4u + local, lmap_base[e + 6u] / 4u + local);
}

void main()
{
    const uint t = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationID.x;
    if (t >= pc.count) return;
    const uint off = offs[pc.offsets + t], n = rec[off], stride = pc.space == 0u ? 3u : 8u;
    bool any = false;
    for (uint e = 0u; e < n; e++) any = any || weight[rec[off + 1u + stride * e]] != 0.0;
    if (pc.space == 0u) {
        uvec2 a = texel_words(t);
        if (!any) {
            lmap_out[a.x] = lmap_base[a.x];
            lmap_out[a.y] = lmap_base[a.y];
            return;
        }
        ahd_linear acc = ahd_to_linear(lmap_base[a.x], lmap_base[a.y]);
        for (uint e = 0u; e < n; e++) {
            uint r = off + 1u + stride * e;
            float w = weight[rec[r]];
            if (w != 0.0) ahd_add_scaled(acc, ahd_to_linear(rec[r + 1u], rec[r + 2u]), w);
        }
        uvec2 o = ahd_from_linear(acc);
        lmap_out[a.x] = o.x;
        lmap_out[a.y] = o.y;
        return;
    }
    uint words[7];
    for (int i = 0; i < 7; i++) words[i] = pc.space == 1u ? glg_base[7u * t + uint(i)] : llg_base[7u * t + uint(i)];
    if (any) {
        sh9 acc = sh9_unpack(words);
        for (uint e = 0u; e < n; e++) {
            uint r = off + 1u + stride * e, p[7];
            float w = weight[rec[r]];
            if (w == 0.0) continue;
            for (int i = 0; i < 7; i++) p[i] = rec[r + 1u + uint(i)];
            sh9_add_scaled(acc, sh9_unpack(p), w);
        }
        sh9_pack(acc, words);
    }
    for (int i = 0; i < 7; i++) {
        if (pc.space == 1u) glg_out[7u * t + uint(i)] = words[i];
        else llg_out[7u * t + uint(i)] = words[i];
    }
}
