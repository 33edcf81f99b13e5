#version 450
// lbk_dls_apply on the GPU: one dispatch per cluster (seed 001 §3.3) — or, batched, one dispatch
// for every cluster to run, each workgroup of 64 taking its cluster and first target from a
// table (a workgroup never spans two clusters, so it stays as uniform as a dispatch) — one
// invocation per target of the cluster, reading the DLS section bytes as they are (spec/container.md §12) and the base
// lighting as the LMAP section / probe arrays as they are; every target is written by exactly one
// dispatch, so dispatches need no barriers between them. The arithmetic is codecs.glsl: the bytes
// are the CPU's (tests/gpu/test_gpu.c checks them on lavapipe).
//
// Per dispatch the set list is constant, so the weights are uniform across it: dedicated clusters
// never diverge; packed clusters only where a wave crosses a sub-group; prefix clusters loop 5–8,
// 9–16 or 17–255 entries per target, the seed's "minimal divergence".
#extension GL_GOOGLE_include_directive : require
#include "codecs.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Dls { uint dls[]; };
layout(std430, binding = 1) readonly buffer RunOrd { uint run_ord[]; };  // per run: cluster-order index of its first target
layout(std430, binding = 2) readonly buffer Weights { float weight[]; };  // effective weight per set
layout(std430, binding = 3) readonly buffer LmapBase { uint lmap_base[]; };
layout(std430, binding = 4) buffer LmapOut { uint lmap_out[]; };
layout(std430, binding = 5) readonly buffer GlgBase { uint glg_base[]; };
layout(std430, binding = 6) buffer GlgOut { uint glg_out[]; };
layout(std430, binding = 7) readonly buffer LlgBase { uint llg_base[]; };
layout(std430, binding = 8) buffer LlgOut { uint llg_out[]; };
// batched: per workgroup (cluster | copy << 31, its first target in cluster order, the run holding it)
layout(std430, binding = 9) readonly buffer Table { uint table[]; };

// Word offsets of the DLS arrays (lbk_dls_array_get / 4), the cluster, and what to do with it.
layout(push_constant) uniform Push {
    uint cluster, mode; // mode 0: L = L_B + Σ w S; 1: every weight is 0, copy the base; 2: batched (table)
    uint clusters, cluster_sets, runs, subgroups, prefix_words, base16, base32, slots, texel_entries, probe_entries;
} pc;

uint dls_byte(uint byte_index) { return (dls[byte_index >> 2] >> (8u * (byte_index & 3u))) & 0xffu; }
uint dls_u16(uint byte_index) { return (dls[byte_index >> 2] >> (8u * (byte_index & 3u))) & 0xffffu; }

// ---- targets ------------------------------------------------------------------------------------

// LMAP page table (spec §9): word 0 page_count; entry p at byte 16 + 32p: width|height, reserved,
// first_texel (u64), plane0_offset (u64), plane1_offset (u64).
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

void probe_load(uint space, uint t, out uint w[7])
{
    for (int i = 0; i < 7; i++) w[i] = space == 1u ? glg_base[7u * t + uint(i)] : llg_base[7u * t + uint(i)];
}

void probe_store(uint space, uint t, uint w[7])
{
    for (int i = 0; i < 7; i++) {
        if (space == 1u) glg_out[7u * t + uint(i)] = w[i];
        else llg_out[7u * t + uint(i)] = w[i];
    }
}

void copy_base(uint space, uint t)
{
    if (space == 0u) {
        uvec2 a = texel_words(t);
        lmap_out[a.x] = lmap_base[a.x];
        lmap_out[a.y] = lmap_base[a.y];
    } else {
        uint w[7];
        probe_load(space, t, w);
        probe_store(space, t, w);
    }
}

// ---- one target ---------------------------------------------------------------------------------

// A target's entries: entry e (< n) is entry first + e of the cluster's payload; its set is
// list[e] (dedicated), list[slot e of the sub-group] (packed) or list[slots[slot0 + e]] (prefix).
struct entries {
    uint form, first, n, set_first, slots, slot0;
};

float set_weight(uint set_first, uint slot) { return weight[dls[pc.cluster_sets + set_first + slot]]; }

float entry_weight(entries L, uint e)
{
    if (L.form == 0u) return set_weight(L.set_first, e);
    if (L.form == 1u) return set_weight(L.set_first, byte_of(L.slots, e));
    return set_weight(L.set_first, dls_byte(L.slot0 + e));
}

bool any_weight(entries L)
{
    bool any = false;
    for (uint e = 0u; e < L.n; e++) any = any || entry_weight(L, e) != 0.0;
    return any;
}

void apply_texel(uint t, entries L)
{
    const uvec2 a = texel_words(t);
    if (!any_weight(L)) { // exactly the base (a packed sub-group or prefix target whose sets are off)
        lmap_out[a.x] = lmap_base[a.x];
        lmap_out[a.y] = lmap_base[a.y];
        return;
    }
    ahd_linear acc = ahd_to_linear(lmap_base[a.x], lmap_base[a.y]);
    for (uint e = 0u; e < L.n; e++) {
        const float w = entry_weight(L, e);
        if (w == 0.0) continue;
        const uint d = pc.texel_entries + 2u * (L.first + e);
        ahd_add_scaled(acc, ahd_to_linear(dls[d], dls[d + 1u]), w);
    }
    const uvec2 o = ahd_from_linear(acc);
    lmap_out[a.x] = o.x;
    lmap_out[a.y] = o.y;
}

void apply_probe(uint space, uint t, entries L)
{
    uint words[7];
    probe_load(space, t, words);
    if (any_weight(L)) {
        sh9 acc = sh9_unpack(words);
        for (uint e = 0u; e < L.n; e++) {
            const float w = entry_weight(L, e);
            if (w == 0.0) continue;
            const uint d = pc.probe_entries + 7u * (L.first + e);
            uint p[7];
            for (int i = 0; i < 7; i++) p[i] = dls[d + uint(i)];
            sh9_add_scaled(acc, sh9_unpack(p), w);
        }
        sh9_pack(acc, words);
    }
    probe_store(space, t, words);
}

// ---- the forms ------------------------------------------------------------------------------------

void main()
{
    const uint wg = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    uint cluster = pc.cluster, ordinal = wg * 64u + gl_LocalInvocationID.x, run_hint = 0xffffffffu, mode = pc.mode;
    if (mode == 2u) {
        cluster = table[3u * wg] & 0x7fffffffu;
        mode = table[3u * wg] >> 31;
        ordinal = table[3u * wg + 1u] + gl_LocalInvocationID.x;
        run_hint = table[3u * wg + 2u];
    }
    const uint c = pc.clusters + 16u * cluster;
    const uint form = dls[c], space = dls[c + 1u], k = dls[c + 2u], set_first = dls[c + 3u];
    const uint run_first = dls[c + 5u], run_count = dls[c + 6u], target_count = dls[c + 7u];
    const uint aux_first = dls[c + 8u], aux_count = dls[c + 9u], base_first = dls[c + 10u];
    const uint entry_first = dls[c + 12u], slot_first = dls[c + 14u];
    if (ordinal >= target_count) return;

    uint lo = run_first, hi = run_first + run_count; // the run holding this cluster-order position
    if (run_hint != 0xffffffffu) { // batched: from the workgroup's first run, a few steps at most
        lo = run_hint;
        while (lo + 1u < hi && run_ord[lo + 1u] <= ordinal) lo++;
    } else {
        while (hi - lo > 1u) {
            uint mid = (lo + hi) / 2u;
            if (run_ord[mid] <= ordinal) lo = mid;
            else hi = mid;
        }
    }
    const uint t = dls[pc.runs + 2u * lo] + (ordinal - run_ord[lo]);
    if (mode == 1u) {
        copy_base(space, t);
        return;
    }

    entries L;
    L.form = form, L.set_first = set_first, L.slots = 0u, L.slot0 = 0u;
    if (form <= 1u) { // dedicated, packed: k entries per target
        L.first = entry_first + ordinal * k, L.n = k;
        if (form == 1u) {
            uint glo = aux_first, ghi = aux_first + aux_count;
            while (ghi - glo > 1u) {
                uint mid = (glo + ghi) / 2u;
                if (dls[pc.subgroups + 4u * mid + 2u] <= ordinal) glo = mid;
                else ghi = mid;
            }
            L.slots = dls[pc.subgroups + 4u * glo + 3u];
        }
    } else { // prefix forms: count = field + bias; entries of target i start at
             // base[i / B] + Σ_{q = B·⌊i/B⌋}^{i−1} count_q (spec §12.5)
        const uint bits = form == 2u ? 2u : (form == 3u ? 3u : 8u), per_word = 32u / bits;
        const uint bias = form == 2u ? 5u : (form == 3u ? 9u : 17u), batch = form == 3u ? 8u : 16u;
        const uint b = ordinal / batch;
        uint off = form == 4u ? dls[pc.base32 + base_first + b] : dls_u16(4u * pc.base16 + 2u * (base_first + b)), f = 0u;
        for (uint q = b * batch; q <= ordinal; q++) {
            f = (dls[pc.prefix_words + aux_first + q / per_word] >> (bits * (q % per_word))) & ((1u << bits) - 1u);
            if (q < ordinal) off += f + bias;
        }
        L.first = entry_first + off, L.n = f + bias, L.slot0 = 4u * pc.slots + slot_first + off;
    }
    if (space == 0u) apply_texel(t, L);
    else apply_probe(space, t, L);
}
