/* DLS apply: the clustered reference runtime against a naive per-target gather over the same
 * data (seed 001 §3.3: 4-byte address per target, u8 count, per overlap u8 set index + payload),
 * both measured in this run, next to a memcpy of the output bytes; and the ancillary bytes of
 * the clustered layout against its payload. Synthetic level at about the size of the seed's
 * ESTATE: 1M texels, 50k GLG and 20k LLG probes, 64 light sets with local footprints plus a
 * dense region where up to 16 sets overlap. */
#define LBK_STATIC_LINKING_ONLY /* lbk_dls_stats: experimental (lbk/dls.h) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lbk/ahd.h"
#include "lbk/dls.h"
#include "lbk/sh.h"

#include "bake/util/clock.h"
#include "bake/util/rng.h"

#define NSETS 64

static uint64_t rng_next(uint64_t *s) { return bk_mix64(*s += BK_GOLDEN64); } /* splitmix64 */
static float uni(uint64_t *s) { return (float)(rng_next(s) >> 40) / 16777216.0f; }

static void random_texel(uint64_t *rng, float scale, uint8_t out[8])
{
    lbk_ahd_linear lin;
    memset(&lin, 0, sizeof lin);
    float amb[3] = {scale * uni(rng), scale * uni(rng), scale * uni(rng)};
    float x = 2 * uni(rng) - 1, y = 2 * uni(rng) - 1, z = 0.3f + uni(rng), n = 1 / sqrtf(x * x + y * y + z * z);
    float dir[3] = {x * n, y * n, z * n}, rgb[3] = {scale * uni(rng), scale * uni(rng), scale * uni(rng)};
    lbk_ahd_linear_add_ambient(&lin, amb);
    lbk_ahd_linear_add_light(&lin, dir, rgb);
    lbk_ahd_texel t;
    lbk_ahd_from_linear(&lin, &t);
    lbk_ahd_texel_pack(&t, out);
}

static void random_probe(uint64_t *rng, float scale, uint8_t out[28])
{
    lbk_sh9_rgb sh;
    memset(&sh, 0, sizeof sh);
    for (int i = 0; i < 3; i++) {
        float x = 2 * uni(rng) - 1, y = 2 * uni(rng) - 1, z = 2 * uni(rng) - 1, n = sqrtf(x * x + y * y + z * z) + 1e-6f;
        float d[3] = {x / n, y / n, z / n}, rgb[3] = {scale * uni(rng), scale * uni(rng), scale * uni(rng)};
        lbk_sh9_add_sample(&sh, d, rgb, 3.14159265f);
    }
    lbk_sh9_pack(&sh, out);
}

/* ---- naive per-target gather ---------------------------------------------------------------- */

typedef struct naive {
    uint64_t n;            /* targets */
    uint32_t psize;
    uint64_t *offset;      /* per target: record position (the seed counts 4 bytes; we need 8 here) */
    uint8_t *stream;       /* record: u8 count, then count × (u8 set, payload) */
    uint64_t bytes;
} naive;

typedef struct naive_fill {
    naive *nv;
    int pass;
    uint32_t *count;
} naive_fill;

static int naive_cb(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    naive_fill *f = user;
    if (f->pass == 0) {
        f->count[target] = count;
        return 0;
    }
    uint8_t *p = f->nv->stream + f->nv->offset[target];
    *p++ = (uint8_t)count;
    for (uint32_t j = 0; j < count; j++) {
        *p++ = (uint8_t)sets[j];
        memcpy(p, payloads + (size_t)j * f->nv->psize, f->nv->psize);
        p += f->nv->psize;
    }
    return 0;
}

static void naive_build(naive *nv, const lbk_dls_view *v, uint32_t space)
{
    nv->n = lbk_dls_target_count(v, space);
    nv->psize = space == 0 ? 8 : 28;
    uint32_t *count = calloc(nv->n, 4);
    naive_fill f = {nv, 0, count};
    for (int pass = 0; pass < 2; pass++) {
        f.pass = pass;
        if (pass == 1) {
            nv->offset = malloc(nv->n * 8);
            uint64_t at = 0;
            for (uint64_t t = 0; t < nv->n; t++) {
                nv->offset[t] = at;
                at += 1 + (uint64_t)count[t] * (1 + nv->psize);
            }
            nv->bytes = at;
            nv->stream = calloc(at, 1);
        }
        for (uint32_t c = 0; c < lbk_dls_cluster_count(v); c++) {
            lbk_dls_cluster_info info;
            lbk_dls_cluster_get(v, c, &info);
            if (info.space == space) lbk_dls_cluster_decode(v, c, naive_cb, &f);
        }
    }
    free(count);
}

static void naive_texels(const naive *nv, const float *w, const uint32_t *bz, const uint8_t *brgba, uint32_t *oz, uint8_t *orgba)
{
    for (uint64_t t = 0; t < nv->n; t++) {
        const uint8_t *p = nv->stream + nv->offset[t];
        uint32_t n = *p++;
        int active = 0;
        for (uint32_t j = 0; j < n; j++) active |= w[p[j * 9]] != 0.0f;
        if (!active) {
            oz[t] = bz[t];
            memcpy(orgba + 4 * t, brgba + 4 * t, 4);
            continue;
        }
        lbk_ahd_texel b = {bz[t], {0}};
        memcpy(b.rgba, brgba + 4 * t, 4);
        lbk_ahd_linear acc, l;
        lbk_ahd_to_linear(&b, &acc);
        for (uint32_t j = 0; j < n; j++, p += 9) {
            float wj = w[p[0]];
            if (wj == 0.0f) continue;
            lbk_ahd_texel e;
            lbk_ahd_texel_unpack(p + 1, &e);
            lbk_ahd_to_linear(&e, &l);
            lbk_ahd_linear_add_scaled(&acc, &l, wj);
        }
        lbk_ahd_texel o;
        lbk_ahd_from_linear(&acc, &o);
        oz[t] = o.irradiance_z;
        memcpy(orgba + 4 * t, o.rgba, 4);
    }
}

static void naive_probes(const naive *nv, const float *w, const uint8_t *base, uint8_t *out)
{
    for (uint64_t t = 0; t < nv->n; t++) {
        const uint8_t *p = nv->stream + nv->offset[t];
        uint32_t n = *p++;
        int active = 0;
        for (uint32_t j = 0; j < n; j++) active |= w[p[j * 29]] != 0.0f;
        if (!active) {
            memcpy(out + 28 * t, base + 28 * t, 28);
            continue;
        }
        lbk_sh9_rgb acc, l;
        lbk_sh9_unpack(base + 28 * t, &acc);
        for (uint32_t j = 0; j < n; j++, p += 29) {
            float wj = w[p[0]];
            if (wj == 0.0f) continue;
            lbk_sh9_unpack(p + 1, &l);
            lbk_sh9_add_scaled(&acc, &l, wj);
        }
        lbk_sh9_pack(&acc, out + 28 * t);
    }
}

/* ---- main ------------------------------------------------------------------------------------ */

int main(void)
{
    const uint64_t T = 1000000, G = 50000, L = 20000;
    const uint64_t counts[3] = {T, G, L};
    uint64_t rng = 12345;

    /* Sets: local footprints in index space (texel order follows the atlas, so nearby texels are
     * nearby in the level), sets 48..63 all overlapping one 4000-texel region (a room full of
     * individually switchable lights). */
    static lbk_dls_set_desc sets[NSETS];
    static char names[NSETS][16];
    uint32_t *tg[NSETS][3];
    uint8_t *pl[NSETS][3];
    uint64_t payload_total = 0;
    for (uint32_t s = 0; s < NSETS; s++) {
        snprintf(names[s], sizeof names[s], "lights%02u", s);
        sets[s].name = names[s];
        sets[s].kind = LBK_DLS_KIND_LIGHTS;
        for (uint32_t sp = 0; sp < 3; sp++) {
            uint64_t n = counts[sp];
            uint64_t radius, centre;
            if (s >= 48) {
                radius = sp == 0 ? 2000 : 100;
                centre = n / 2;
            } else {
                radius = (uint64_t)((sp == 0 ? 4000.0 : 200.0) * (0.5 + 4 * uni(&rng)));
                centre = radius + rng_next(&rng) % (n - 2 * radius);
            }
            uint64_t len = 2 * radius;
            tg[s][sp] = malloc(len * 4);
            pl[s][sp] = malloc(len * (sp == 0 ? 8 : 28));
            for (uint64_t i = 0; i < len; i++) {
                tg[s][sp][i] = (uint32_t)(centre - radius + i);
                if (sp == 0) random_texel(&rng, 0.5f, pl[s][sp] + 8 * i);
                else random_probe(&rng, 0.5f, pl[s][sp] + 28 * i);
            }
            sets[s].entries[sp] = (lbk_dls_sparse){len, tg[s][sp], pl[s][sp]};
            payload_total += len;
        }
    }
    lbk_dls_build_desc desc = {.set_count = NSETS, .sets = sets, .target_count = {T, G, L}};
    void *bytes;
    size_t size;
    lbk_dls_stats st;
    double t0 = bk_now();
    lbk_result r = lbk_dls_build(&desc, NULL, &bytes, &size, &st);
    double t_build = bk_now() - t0;
    if (r != LBK_OK) {
        fprintf(stderr, "build failed: %s\n", lbk_result_name(r));
        return 1;
    }
    lbk_dls_view *v;
    lbk_dls_open(bytes, size, NULL, &v);
    printf("level: %llu texels, %llu GLG, %llu LLG probes, %d sets, %llu entries; build %.2f s\n",
           (unsigned long long)T, (unsigned long long)G, (unsigned long long)L, NSETS, (unsigned long long)payload_total, t_build);
    printf("clusters: %u (dedicated %u, packed %u with %u sub-groups, prefix-2 %u, prefix-3 %u, prefix-8 %u)\n", st.cluster_count,
           st.clusters_by_form[0], st.clusters_by_form[1], st.packed_subgroups, st.clusters_by_form[2], st.clusters_by_form[3],
           st.clusters_by_form[4]);
    printf("texel overlap histogram:");
    for (int b = 0; b < LBK_DLS_HISTOGRAM_BINS; b++) printf(" %llu", (unsigned long long)st.histogram[0][b]);
    printf("\n");
    printf("DLS section %llu bytes: payload %llu, ancillary %llu (%.2f%% of payload); texel index data %llu bytes = %.2f bits per touched texel\n",
           (unsigned long long)st.section_bytes, (unsigned long long)st.payload_bytes, (unsigned long long)st.ancillary_bytes,
           100.0 * (double)st.ancillary_bytes / (double)st.payload_bytes, (unsigned long long)st.index_bytes[0],
           st.index_bits_per_target[0]);

    /* base and output buffers */
    uint32_t *bz = malloc(T * 4), *oz = malloc(T * 4), *nz = malloc(T * 4);
    uint8_t *brgba = malloc(T * 4), *orgba = malloc(T * 4), *nrgba = malloc(T * 4);
    uint8_t *bg = malloc(G * 28), *og = malloc(G * 28), *ng = malloc(G * 28);
    uint8_t *bl = malloc(L * 28), *ol = malloc(L * 28), *nl = malloc(L * 28);
    for (uint64_t t = 0; t < T; t++) {
        uint8_t b[8];
        random_texel(&rng, 1.0f, b);
        lbk_ahd_texel tx;
        lbk_ahd_texel_unpack(b, &tx);
        bz[t] = tx.irradiance_z;
        memcpy(brgba + 4 * t, tx.rgba, 4);
    }
    for (uint64_t t = 0; t < G; t++) random_probe(&rng, 1.0f, bg + 28 * t);
    for (uint64_t t = 0; t < L; t++) random_probe(&rng, 1.0f, bl + 28 * t);
    lbk_dls_runtime_desc rd = {.dls = v, .base_irradiance_z = bz, .base_rgba = brgba, .base_glg = bg, .base_llg = bl,
                               .out_irradiance_z = oz, .out_rgba = orgba, .out_glg = og, .out_llg = ol};
    lbk_dls_runtime *rt;
    if (lbk_dls_runtime_open(&rd, &rt) != LBK_OK) return 1;
    naive nv[3];
    for (uint32_t sp = 0; sp < 3; sp++) naive_build(&nv[sp], v, sp);
    uint64_t naive_index = 0;
    for (uint32_t sp = 0; sp < 3; sp++) /* 4-byte address + count byte per target, a set byte per entry */
        naive_index += nv[sp].n * 5 + (nv[sp].bytes - nv[sp].n) / (1 + nv[sp].psize);
    printf("naive gather layout: %.1f MB of addresses, counts and set indices (clustered: %.3f MB)\n", naive_index / 1e6,
           st.ancillary_bytes / 1e6);

    float w[NSETS], w2[NSETS];
    const int reps = 5;
    const uint64_t out_bytes = T * 8 + (G + L) * 28;

    /* memcpy of the output bytes */
    double best_copy = 1e9;
    for (int i = 0; i < reps; i++) {
        t0 = bk_now();
        memcpy(oz, bz, T * 4);
        memcpy(orgba, brgba, T * 4);
        memcpy(og, bg, G * 28);
        memcpy(ol, bl, L * 28);
        double dt = bk_now() - t0;
        if (dt < best_copy) best_copy = dt;
    }

    struct scenario {
        const char *name;
        int all_on, one_changed, half_off;
    } scen[] = {{"all sets on, all changed (seed's debug mode)", 1, 0, 0},
                {"half the sets off, all changed", 0, 0, 1},
                {"one set changed since the last frame", 1, 1, 0}};
    printf("memcpy of the %.1f MB output: %.3f ms (%.2f GB/s)\n", out_bytes / 1e6, best_copy * 1e3, out_bytes / best_copy / 1e9);
    for (size_t sc = 0; sc < sizeof scen / sizeof scen[0]; sc++) {
        double best_rt = 1e9, best_nv = 1e9;
        for (int i = 0; i < reps; i++) {
            for (int s = 0; s < NSETS; s++) {
                w[s] = scen[sc].half_off && (s & 1) ? 0.0f : 0.5f + 0.01f * (float)(i + 1);
                w2[s] = w[s];
            }
            if (scen[sc].one_changed) {
                for (int s = 0; s < NSETS; s++) w[s] = w2[s] = 0.7f;
                lbk_dls_apply(rt, w, NULL, NULL); /* previous frame */
                w2[5] = 0.3f + 0.01f * (float)i;
            } else {
                lbk_dls_apply(rt, NULL, NULL, NULL); /* previous frame: everything off */
            }
            t0 = bk_now();
            lbk_dls_apply(rt, w2, NULL, NULL);
            double dt = bk_now() - t0;
            if (dt < best_rt) best_rt = dt;
            t0 = bk_now();
            naive_texels(&nv[0], w2, bz, brgba, nz, nrgba);
            naive_probes(&nv[1], w2, bg, ng);
            naive_probes(&nv[2], w2, bl, nl);
            dt = bk_now() - t0;
            if (dt < best_nv) best_nv = dt;
        }
        int same = !memcmp(oz, nz, T * 4) && !memcmp(orgba, nrgba, T * 4) && !memcmp(og, ng, G * 28) && !memcmp(ol, nl, L * 28);
        printf("%s:\n  clustered %.3f ms, naive gather %.3f ms: %.1fx faster; clustered at %.3f of memcpy speed%s\n", scen[sc].name,
               best_rt * 1e3, best_nv * 1e3, best_nv / best_rt, best_copy / best_rt, same ? "" : " (OUTPUTS DIFFER)");
    }
    lbk_dls_runtime_close(rt);
    lbk_dls_close(v);
    free(bytes);
    for (uint32_t sp = 0; sp < 3; sp++) free(nv[sp].offset), free(nv[sp].stream);
    for (uint32_t s = 0; s < NSETS; s++)
        for (uint32_t sp = 0; sp < 3; sp++) free(tg[s][sp]), free(pl[s][sp]);
    free(bz), free(oz), free(nz), free(brgba), free(orgba), free(nrgba);
    free(bg), free(og), free(ng), free(bl), free(ol), free(nl);
    return 0;
}
