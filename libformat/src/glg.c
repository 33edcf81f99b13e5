/* GLG: builder, view, visibility-weighted sampling and validator (spec/container.md §10). */
#include "lbk/glg.h"

#include <stdlib.h>

#include "internal.h"
#include "section_util.h"

typedef struct glg_layout {
    uint64_t pos, sh, tet, adj, vis, end;
} glg_layout;

static bool glg_layout_of(uint64_t probes, uint64_t tetras, glg_layout *l)
{
    uint64_t t;
    l->pos = LBK_GLG_HEADER_SIZE;
    if (!lbk_madd_u64(l->pos, probes, 12, &t)) return false;
    l->sh = lbk_align_up(t, 16);
    if (!lbk_madd_u64(l->sh, probes, LBK_SH9_PACKED_SIZE, &t)) return false;
    l->tet = lbk_align_up(t, 16);
    if (!lbk_madd_u64(l->tet, tetras, 16, &l->adj)) return false;
    if (!lbk_madd_u64(l->adj, tetras, 16, &l->vis)) return false;
    if (!lbk_madd_u64(l->vis, tetras, 4, &l->end)) return false;
    return l->end < (UINT64_MAX >> 1);
}

/* ---- builder ------------------------------------------------------------------------------- */

typedef struct face_key {
    uint32_t v[3];
    uint32_t tetra, face;
} face_key;

static int face_cmp(const void *a, const void *b)
{
    const face_key *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x->v[i] != y->v[i]) return x->v[i] < y->v[i] ? -1 : 1;
    if (x->tetra != y->tetra) return x->tetra < y->tetra ? -1 : 1;
    return x->face < y->face ? -1 : (x->face > y->face);
}

static void sort3(uint32_t v[3])
{
    uint32_t t;
    if (v[0] > v[1]) { t = v[0]; v[0] = v[1]; v[1] = t; }
    if (v[1] > v[2]) { t = v[1]; v[1] = v[2]; v[2] = t; }
    if (v[0] > v[1]) { t = v[0]; v[0] = v[1]; v[1] = t; }
}

static void face_vertices(const uint32_t tet[4], int face, uint32_t out[3])
{
    int k = 0;
    for (int i = 0; i < 4; i++)
        if (i != face) out[k++] = tet[i];
}

/* Neighbour across every face from shared vertex triples. */
static lbk_result derive_adjacency(const lbk_allocator *a, const uint32_t (*tets)[4], uint32_t n, uint32_t (*adj)[4])
{
    face_key *keys = lbk_calloc(a, (size_t)n * 4, sizeof *keys);
    if (!keys) return LBK_ERR_OUT_OF_MEMORY;
    for (uint32_t t = 0; t < n; t++)
        for (int f = 0; f < 4; f++) {
            face_key *k = &keys[(size_t)t * 4 + f];
            face_vertices(tets[t], f, k->v);
            sort3(k->v);
            k->tetra = t;
            k->face = (uint32_t)f;
            adj[t][f] = LBK_TETRA_NONE;
        }
    qsort(keys, (size_t)n * 4, sizeof *keys, face_cmp);
    lbk_result r = LBK_OK;
    for (size_t i = 0; i + 1 < (size_t)n * 4; i++) {
        if (memcmp(keys[i].v, keys[i + 1].v, sizeof keys[i].v) != 0) continue;
        if (i + 2 < (size_t)n * 4 && memcmp(keys[i].v, keys[i + 2].v, sizeof keys[i].v) == 0) {
            r = LBK_ERR_INVALID_ARGUMENT; /* a face shared by three tetras */
            break;
        }
        adj[keys[i].tetra][keys[i].face] = keys[i + 1].tetra;
        adj[keys[i + 1].tetra][keys[i + 1].face] = keys[i].tetra;
        i++;
    }
    lbk_dealloc(a, keys);
    return r;
}

lbk_result lbk_glg_build(const lbk_glg_build_desc *caller_desc, const lbk_allocator *allocator, void **out,
                         size_t *size)
{
    if (!caller_desc || !out || !size) return LBK_ERR_INVALID_ARGUMENT;
    lbk_glg_build_desc in;
    lbk_result rc = LBK_SIZED_IN(&in, caller_desc, lbk_glg_build_desc, scale);
    if (rc != LBK_OK) return rc;
    const lbk_glg_build_desc *desc = &in;
    if (desc->probe_count < 4 || desc->tetra_count == 0 || !desc->positions || !desc->probes || !desc->tetras)
        return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    const uint32_t P = desc->probe_count, T = desc->tetra_count;
    float scale;
    if (!lbk_scale_resolve(desc->scale, &scale)) return LBK_ERR_INVALID_ARGUMENT;
    const float inv = 1.0f / scale; /* exact: a power of two */
    glg_layout L;
    if (!glg_layout_of(P, T, &L) || L.end > SIZE_MAX) return LBK_ERR_LIMIT;
    for (uint32_t i = 0; i < P; i++)
        if (!lbk_finite3(desc->positions[i])) return LBK_ERR_INVALID_ARGUMENT;
    uint32_t(*tets)[4] = lbk_calloc(allocator, T, sizeof *tets);
    uint32_t(*adj)[4] = lbk_calloc(allocator, T, sizeof *adj);
    uint8_t(*vis)[4] = lbk_calloc(allocator, T, sizeof *vis);
    uint8_t *d = NULL;
    lbk_result r = LBK_OK;
    if (!tets || !adj || !vis) {
        r = LBK_ERR_OUT_OF_MEMORY;
        goto done;
    }
    for (uint32_t t = 0; t < T; t++) {
        for (int i = 0; i < 4; i++) {
            tets[t][i] = desc->tetras[t][i];
            if (tets[t][i] >= P) {
                r = LBK_ERR_INVALID_ARGUMENT;
                goto done;
            }
            adj[t][i] = desc->adjacency ? desc->adjacency[t][i] : LBK_TETRA_NONE;
            vis[t][i] = desc->visibility ? desc->visibility[t][i] : 255;
        }
        const double o = lbk_tetra_orient(desc->positions[tets[t][0]], desc->positions[tets[t][1]],
                                          desc->positions[tets[t][2]], desc->positions[tets[t][3]]);
        if (o == 0.0 || o != o) {
            r = LBK_ERR_INVALID_ARGUMENT;
            goto done;
        }
        if (o < 0.0) {
            uint32_t s = tets[t][2];
            tets[t][2] = tets[t][3];
            tets[t][3] = s;
            s = adj[t][2];
            adj[t][2] = adj[t][3];
            adj[t][3] = s;
            const uint8_t v = vis[t][2];
            vis[t][2] = vis[t][3];
            vis[t][3] = v;
        }
    }
    if (!desc->adjacency) {
        r = derive_adjacency(allocator, (const uint32_t(*)[4])tets, T, adj);
        if (r != LBK_OK) goto done;
    }
    d = lbk_calloc(allocator, 1, (size_t)L.end);
    if (!d) {
        r = LBK_ERR_OUT_OF_MEMORY;
        goto done;
    }
    lbk_wr32(d, P);
    lbk_wr32(d + 4, T);
    lbk_wrf32(d + 8, scale);
    for (uint32_t i = 0; i < P; i++) {
        for (int k = 0; k < 3; k++) lbk_wrf32(d + L.pos + 12 * (size_t)i + 4 * k, desc->positions[i][k]);
        lbk_sh9_rgb stored;
        memset(&stored, 0, sizeof stored);
        lbk_sh9_add_scaled(&stored, &desc->probes[i], inv);
        lbk_sh9_pack(&stored, d + L.sh + (size_t)LBK_SH9_PACKED_SIZE * i);
    }
    for (uint32_t t = 0; t < T; t++)
        for (int k = 0; k < 4; k++) {
            lbk_wr32(d + L.tet + 16 * (size_t)t + 4 * k, tets[t][k]);
            lbk_wr32(d + L.adj + 16 * (size_t)t + 4 * k, adj[t][k]);
            d[L.vis + 4 * (size_t)t + k] = vis[t][k];
        }
    *out = d;
    *size = (size_t)L.end;
done:
    lbk_dealloc(allocator, tets);
    lbk_dealloc(allocator, adj);
    lbk_dealloc(allocator, vis);
    return r;
}

/* ---- view ---------------------------------------------------------------------------------- */

static bool zero_range(const uint8_t *d, uint64_t from, uint64_t to)
{
    for (uint64_t i = from; i < to; i++)
        if (d[i]) return false;
    return true;
}

lbk_result lbk_glg_open(const void *data, size_t size, lbk_glg_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_GLG_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    const uint32_t P = lbk_rd32(d), T = lbk_rd32(d + 4);
    if (P < 4 || T == 0 || !lbk_scale_bits_ok(lbk_rd32(d + 8)) || !zero_range(d, 12, LBK_GLG_HEADER_SIZE))
        return LBK_ERR_CORRUPT;
    glg_layout L;
    if (!glg_layout_of(P, T, &L)) return LBK_ERR_CORRUPT;
    if (L.end > size) return LBK_ERR_TRUNCATED;
    if (L.end != size) return LBK_ERR_CORRUPT;
    if (!zero_range(d, L.pos + 12 * (uint64_t)P, L.sh) || !zero_range(d, L.sh + 28 * (uint64_t)P, L.tet))
        return LBK_ERR_CORRUPT;
    out->data = d;
    out->size = size;
    out->probe_count = P;
    out->tetra_count = T;
    out->mesh.positions = d + L.pos;
    out->mesh.tetras = d + L.tet;
    out->mesh.adjacency = d + L.adj;
    out->mesh.vertex_count = P;
    out->mesh.tetra_count = T;
    out->probes = d + L.sh;
    out->visibility = d + L.vis;
    out->scale = lbk_rdf32(d + 8);
    return LBK_OK;
}

lbk_result lbk_glg_probe_get(const lbk_glg_view *view, uint32_t index, float position[3], lbk_sh9_rgb *sh)
{
    if (!view || !view->data) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= view->probe_count) return LBK_ERR_NOT_FOUND;
    if (position)
        for (int k = 0; k < 3; k++) position[k] = lbk_rdf32(view->mesh.positions + 12 * (size_t)index + 4 * k);
    if (sh) {
        lbk_sh9_rgb stored;
        lbk_sh9_unpack(view->probes + (size_t)LBK_SH9_PACKED_SIZE * index, &stored);
        memset(sh, 0, sizeof *sh);
        lbk_sh9_add_scaled(sh, &stored, view->scale);
    }
    return LBK_OK;
}

lbk_result lbk_glg_sample(const lbk_glg_view *view, const float p[3], uint32_t *hint, lbk_sh9_rgb *out,
                          lbk_glg_sample_info *info)
{
    if (!view || !view->data || !p || !out) return LBK_ERR_INVALID_ARGUMENT;
    lbk_tetra_location loc;
    lbk_result r = lbk_tetra_locate(&view->mesh, p, hint ? *hint : 0, &loc);
    if (r != LBK_OK) return r;
    if (hint) *hint = loc.tetra;
    const uint8_t *vis = view->visibility + 4 * (size_t)loc.tetra;
    float w[4], s = 0.0f;
    for (int i = 0; i < 4; i++) {
        w[i] = loc.bary[i] * (float)vis[i] / 255.0f;
        s += w[i];
    }
    for (int i = 0; i < 4; i++) w[i] = s > 0.0f ? w[i] / s : loc.bary[i];
    memset(out, 0, sizeof *out);
    for (int i = 0; i < 4; i++) {
        if (w[i] == 0.0f) continue;
        lbk_sh9_rgb sh;
        lbk_sh9_unpack(view->probes + (size_t)LBK_SH9_PACKED_SIZE * loc.vertices[i], &sh);
        lbk_sh9_add_scaled(out, &sh, w[i] * view->scale); /* exact: the scale is a power of two */
    }
    if (info) {
        info->location = loc;
        memcpy(info->weights, w, sizeof w);
    }
    return LBK_OK;
}

/* ---- validation ------------------------------------------------------------------------------ */

void lbk_validate_glg(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_GLG_HEADER_SIZE) {
        lbk_vreport(ctx, 600, 0, "GLG is %zu bytes, shorter than its 32-byte header", size);
        return;
    }
    const uint32_t P = lbk_rd32(d), T = lbk_rd32(d + 4);
    lbk_check_scale(ctx, 611, d, 8, "GLG");
    lbk_check_zero(ctx, 601, d, 12, LBK_GLG_HEADER_SIZE, "GLG header");
    if (P < 4 || T == 0) {
        lbk_vreport(ctx, 602, 0, "GLG has %u probes and %u tetrahedra (needs >= 4 and >= 1)", P, T);
        return;
    }
    glg_layout L;
    if (!glg_layout_of(P, T, &L) || L.end != size) {
        lbk_vreport(ctx, 603, 0, "GLG is %zu bytes; %u probes and %u tetrahedra need %llu", size, P, T,
                    (unsigned long long)(glg_layout_of(P, T, &L) ? L.end : 0));
        return;
    }
    lbk_check_zero(ctx, 604, d, L.pos + 12 * (uint64_t)P, L.sh, "GLG");
    lbk_check_zero(ctx, 604, d, L.sh + 28 * (uint64_t)P, L.tet, "GLG");
    lbk_rate rate;
    lbk_rate_init(&rate);
    for (uint32_t i = 0; i < P; i++) {
        float v[3];
        for (int k = 0; k < 3; k++) v[k] = lbk_rdf32(d + L.pos + 12 * (size_t)i + 4 * k);
        if (!lbk_finite3(v) && lbk_rate_ok(&rate, 0))
            lbk_vreport(ctx, 605, L.pos + 12 * (uint64_t)i, "GLG probe %u position is not finite", i);
    }
    uint8_t *used = lbk_calloc(ctx->allocator, P, 1);
    bool mesh_ok = rate.seen[0] == 0;
    for (uint32_t t = 0; t < T; t++) {
        const uint64_t to = L.tet + 16 * (uint64_t)t;
        uint32_t v[4];
        bool idx_ok = true;
        for (int k = 0; k < 4; k++) {
            v[k] = lbk_rd32(d + to + 4 * k);
            if (v[k] >= P) idx_ok = false;
            for (int j = 0; j < k; j++)
                if (v[j] == v[k]) idx_ok = false;
        }
        if (!idx_ok) {
            if (lbk_rate_ok(&rate, 1))
                lbk_vreport(ctx, 606, to, "GLG tetra %u vertices (%u, %u, %u, %u): out of range or repeated", t, v[0], v[1],
                            v[2], v[3]);
            mesh_ok = false;
            continue;
        }
        for (int k = 0; k < 4 && used; k++) used[v[k]] = 1;
        if (mesh_ok) {
            float pv[4][3];
            for (int k = 0; k < 4; k++)
                for (int c = 0; c < 3; c++) pv[k][c] = lbk_rdf32(d + L.pos + 12 * (size_t)v[k] + 4 * c);
            const double o = lbk_tetra_orient(pv[0], pv[1], pv[2], pv[3]);
            if (!(o > 0.0) && lbk_rate_ok(&rate, 2))
                lbk_vreport(ctx, 607, to, "GLG tetra %u has volume %g (must be positive)", t, o / 6.0);
        }
    }
    lbk_rate_flush(ctx, &rate, 605, 606);
    {
        const uint32_t ids[3] = {0, 0, 607};
        lbk_rate_flush_ids(ctx, &rate, ids, 3);
    }
    /* adjacency: in range, symmetric, across the shared face */
    lbk_rate_init(&rate);
    for (uint32_t t = 0; t < T; t++)
        for (int f = 0; f < 4; f++) {
            const uint64_t ao = L.adj + 16 * (uint64_t)t + 4 * (uint64_t)f;
            const uint32_t n = lbk_rd32(d + ao);
            if (n == LBK_TETRA_NONE) continue;
            if (n >= T) {
                if (lbk_rate_ok(&rate, 0))
                    lbk_vreport(ctx, 608, ao, "GLG tetra %u face %d neighbour %u is out of range", t, f, n);
                continue;
            }
            uint32_t tv[4], nv[4];
            for (int k = 0; k < 4; k++) {
                tv[k] = lbk_rd32(d + L.tet + 16 * (size_t)t + 4 * k);
                nv[k] = lbk_rd32(d + L.tet + 16 * (size_t)n + 4 * k);
            }
            /* the vertex of n not on face f of t; exactly one must exist */
            int apex = -1, missing = 0;
            for (int k = 0; k < 4; k++) {
                bool on_face = false;
                for (int j = 0; j < 4; j++)
                    if (j != f && tv[j] == nv[k]) on_face = true;
                if (!on_face) {
                    apex = k;
                    missing++;
                }
            }
            const bool ok = n != t && missing == 1 && lbk_rd32(d + L.adj + 16 * (size_t)n + 4 * (size_t)apex) == t;
            if (!ok && lbk_rate_ok(&rate, 1))
                lbk_vreport(ctx, 609, ao, "GLG tetra %u face %d names neighbour %u, which does not share that face back", t,
                            f, n);
        }
    lbk_rate_flush(ctx, &rate, 608, 609);
    if (used) {
        lbk_rate_init(&rate);
        for (uint32_t i = 0; i < P; i++)
            if (!used[i] && lbk_rate_ok(&rate, 0))
                lbk_vreport(ctx, 610, L.pos + 12 * (uint64_t)i, "GLG probe %u belongs to no tetrahedron", i);
        lbk_rate_flush(ctx, &rate, 610, 0);
        lbk_dealloc(ctx->allocator, used);
    }
    ctx->glg_ok = 1;
    ctx->glg_probe_count = P;
}
