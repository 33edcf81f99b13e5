/* libFuzzer harness for the container reader, the validator and the section readers: whatever
 * the bytes, opening, validating, reading every section and running the samplers on what opens
 * (LMAP texels, the GLG walk and blend, LLG trilinear sampling and vertex irradiance, OCTP
 * lookups, DLS decoding and the reference runtime lbk_dls_apply, DOOR) must never crash, leak
 * or read out of bounds. Built and run by `make fuzz` (long) and `make test` (fixed runs).
 *
 * What aborts: a crash or sanitizer report, or the reader and the validator disagreeing where
 * the library promises they agree (a file the validator passes must open, give every known
 * section's bytes, open every section view and sample). The reverse is by design: the readers
 * check structure only and accept content the validator rejects (a META key ending in 0x7f, a
 * non-Delaunay mesh, ...), so validator-only findings are never treated as failures.
 *
 * Random bytes rarely get past the checksums, so every input is tried twice: as it is, and with
 * its file_size, section checksums, table and header checksums recomputed, which lets the
 * fuzzer mutate section contents and reach every section reader. A DLS section that opens
 * also goes through the runtime (the job planner and the kernels walk its runs, sub-groups and
 * prefix data): applies whole and split into jobs, and the dirty regions. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#define LBK_STATIC_LINKING_ONLY /* the DLS statistics (experimental API) */
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/error_map.h"
#include "lbk/lightmap_uv.h"
#include "lbk/llg.h"
#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/octa.h"
#include "lbk/report.h"
#include "lbk/validate.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum {
    DECODE_CAP = 16u << 20,  /* keep bombs cheap; the cap itself is what is being tested */
    ITEM_CAP = 256,          /* pages, grids, probes, sets, clusters, doors visited per section */
    DLS_BUFFER_CAP = 8u << 20 /* bytes of base + output buffers the DLS runtime gets */
};

/* Every byte the readers hand out is read into this sink, so ASan sees the reads. */
static volatile uint32_t sink;
static void touch(const void *p, size_t n)
{
    uint32_t s = 0;
    for (size_t i = 0; i < n; i++) s += ((const volatile uint8_t *)p)[i];
    sink += s;
}
static void touch_floats(const float *f, size_t n)
{
    for (size_t i = 0; i < n; i++) sink += f[i] > 0.0f; /* reads the value; NaN is fine */
}

static int count_issue(void *user, const lbk_issue *issue)
{
    (void)issue;
    ++*(size_t *)user;
    return 0;
}

/* Directions and points the samplers are tried at, relative to a frame given by the section. */
static const float DIRS[7][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}, {0.6f, 0.8f, 0}, {-0.48f, 0.6f, -0.64f}, {1e-20f, 0, 0}};

static void read_meta_objs_rept(uint32_t type, const void *d, size_t n)
{
    if (type == LBK_SECTION_META) {
        lbk_meta_view v;
        if (lbk_meta_open(d, n, &v) != LBK_OK) return;
        for (uint32_t i = 0; i < v.entry_count && i < 4096; i++) {
            lbk_string k, val;
            if (lbk_meta_entry_get(&v, i, &k, &val) == LBK_OK) touch(k.data, k.size), touch(val.data, val.size);
        }
        lbk_string val;
        lbk_meta_find(&v, "writer", &val);
    } else if (type == LBK_SECTION_REPT) {
        lbk_report_view v;
        if (lbk_report_open(d, n, &v) != LBK_OK) return;
        for (uint32_t i = 0; i < v.header.record_count && i < 4096; i++) {
            lbk_report_record r;
            lbk_report_record_get(&v, i, &r);
        }
    } else if (type == LBK_SECTION_OBJS) {
        lbk_objects_view v;
        if (lbk_objects_open(d, n, &v) != LBK_OK) return;
        for (uint32_t i = 0; i < v.count && i < 4096; i++) {
            lbk_object o;
            if (lbk_objects_get(&v, i, &o) == LBK_OK) touch(o.name.data, o.name.size);
        }
        uint32_t idx;
        lbk_objects_find(&v, (lbk_string){"a", 1}, &idx);
    }
}

static int sample_lmap(const void *d, size_t n)
{
    lbk_lmap_view v;
    lbk_result r = lbk_lmap_open(d, n, &v);
    if (r != LBK_OK) return r;
    for (uint32_t i = 0; i < v.page_count && i < ITEM_CAP; i++) {
        lbk_lmap_page pg;
        if (lbk_lmap_page_get(&v, i, &pg) != LBK_OK) continue;
        const uint32_t xs[3] = {0, pg.width / 2, pg.width ? pg.width - 1 : 0}, ys[3] = {0, pg.height / 2, pg.height ? pg.height - 1 : 0};
        for (int k = 0; k < 3; k++) {
            lbk_ahd_texel t;
            float rgb[3];
            if (lbk_lmap_page_texel_get(&pg, xs[k], ys[k], &t) == LBK_OK) touch(&t, sizeof t);
            if (lbk_lmap_page_irradiance(&pg, xs[k], ys[k], DIRS[k], rgb) == LBK_OK) touch_floats(rgb, 3);
        }
        lbk_ahd_texel t;
        lbk_lmap_page_texel_get(&pg, pg.width, 0, &t); /* out of range: must be refused, not read */
    }
    const uint64_t idx[4] = {0, v.texel_count / 2, v.texel_count ? v.texel_count - 1 : 0, v.texel_count};
    for (int k = 0; k < 4; k++) {
        lbk_ahd_texel t;
        uint32_t page;
        if (lbk_lmap_texel_get(&v, idx[k], &t, &page) == LBK_OK) touch(&t, sizeof t);
    }
    return LBK_OK;
}

/* The GLG: probes, then the walk from each probe position, the tetras' centroids and points far
 * outside, each walk starting from the last one's tetra. On a valid file every sample works. */
static int sample_glg(const void *d, size_t n, int valid)
{
    lbk_glg_view v;
    lbk_result r = lbk_glg_open(d, n, &v);
    if (r != LBK_OK) return r;
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (uint32_t i = 0; i < v.probe_count && i < ITEM_CAP; i++) {
        float p[3];
        lbk_sh9_rgb sh;
        if (lbk_glg_probe_get(&v, i, p, &sh) != LBK_OK) continue;
        touch_floats(sh.c[0], 27);
        for (int k = 0; k < 3; k++) {
            if (!(p[k] > -1e30f && p[k] < 1e30f)) continue; /* NaN and huge: lo/hi stay finite */
            if (i == 0 || p[k] < lo[k]) lo[k] = p[k];
            if (i == 0 || p[k] > hi[k]) hi[k] = p[k];
        }
    }
    uint32_t hint = 0;
    for (uint32_t i = 0; i < 24; i++) {
        float p[3] = {0, 0, 0};
        if (i < 8) { /* the box corners pushed outwards */
            for (int k = 0; k < 3; k++) p[k] = (i >> k & 1) ? hi[k] + 1.0f : lo[k] - 1.0f;
        } else if (i < 16 && v.probe_count) {
            lbk_glg_probe_get(&v, (i * 2654435761u) % v.probe_count, p, NULL);
        } else {
            for (int k = 0; k < 3; k++) p[k] = lo[k] + (hi[k] - lo[k]) * (float)((i * (k + 3)) % 7) / 6.0f;
        }
        for (int k = 0; k < 3; k++)
            if (!(p[k] > -1e30f && p[k] < 1e30f)) p[k] = 0.0f;
        lbk_sh9_rgb sh;
        lbk_glg_sample_info info;
        r = lbk_glg_sample(&v, p, i & 1 ? &hint : NULL, &sh, &info);
        if (r == LBK_OK) touch_floats(sh.c[0], 27), touch_floats(info.weights, 4);
        else if (valid) abort(); /* the validator checked this mesh */
    }
    return LBK_OK;
}

static int sample_llg(const void *d, size_t n, int valid)
{
    lbk_llg_view v;
    lbk_result r = lbk_llg_open(d, n, &v);
    if (r != LBK_OK) return r;
    for (uint32_t g = 0; g < v.grid_count && g < ITEM_CAP; g++) {
        lbk_llg_grid grid;
        if (lbk_llg_grid_get(&v, g, &grid) != LBK_OK) {
            if (valid) abort();
            continue;
        }
        float corner[3];
        lbk_llg_probe_position(&grid, grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1, corner);
        for (int s = 0; s < 4; s++) { /* the centre, a corner, outside, between */
            float p[3];
            for (int k = 0; k < 3; k++) {
                const float c = grid.centre[k], e = corner[k] - c;
                p[k] = s == 0 ? c : s == 1 ? corner[k] : s == 2 ? c + 3.0f * e : c + 0.37f * e;
                if (!(p[k] > -1e30f && p[k] < 1e30f)) p[k] = 0.0f;
            }
            lbk_sh9_rgb sh;
            r = lbk_llg_sample(&v, g, p, &sh);
            if (r == LBK_OK) touch_floats(sh.c[0], 27);
            else if (valid) abort();
            float rgb[3];
            const uint32_t vtx = s == 3 ? grid.vertex_count : (uint32_t)s; /* the last: out of range */
            if (lbk_llg_vertex_irradiance(&v, g, vtx, p, rgb) == LBK_OK) touch_floats(rgb, 3);
        }
    }
    lbk_sh9_rgb sh;
    const float origin[3] = {0, 0, 0};
    lbk_llg_sample(&v, v.grid_count, origin, &sh); /* no such grid */
    return LBK_OK;
}

static int sample_octp(const void *d, size_t n, int valid)
{
    lbk_octp_view v;
    lbk_result r = lbk_octp_open(d, n, &v);
    if (r != LBK_OK) return r;
    for (uint32_t i = 0; i < v.probe_count && i < ITEM_CAP; i++) {
        lbk_octp_probe_desc p;
        if (lbk_octp_probe_get(&v, i, &p) == LBK_OK) touch_floats(p.irradiance[0], 48), touch_floats(p.depth[0], 288);
        else if (valid) abort();
        for (int k = 0; k < 7; k++) {
            float rgb[3];
            r = lbk_octp_irradiance(&v, i, DIRS[k], rgb);
            if (r == LBK_OK) touch_floats(rgb, 3);
            else if (valid) abort();
        }
    }
    /* a volume: the sampler at points in, around and far outside the levels */
    for (uint32_t l = 0; l < v.level_count; l++)
        for (int k = 0; k < 7; k++) {
            lbk_octp_sample_desc sd = LBK_OCTP_SAMPLE_DESC_INIT;
            for (int a = 0; a < 3; a++) {
                sd.position[a] = v.levels[l].origin[a] + v.levels[l].spacing * (float)(k - 2) * 1.7f;
                sd.normal[a] = DIRS[k][a];
            }
            float rgb[3], w;
            r = lbk_octp_sample(&v, &sd, rgb, &w);
            if (r == LBK_OK) touch_floats(rgb, 3);
            else if (valid && r != LBK_ERR_INVALID_ARGUMENT) abort();
        }
    return LBK_OK;
}

static int touch_target(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    (void)target;
    const size_t payload = *(const size_t *)user;
    touch(sets, count * sizeof *sets);
    touch(payloads, count * payload);
    return 0;
}

/* Structure of the DLS view: sets, lights, members, clusters and every cluster's targets. */
static void read_dls(const lbk_dls_view *dv)
{
    for (uint32_t s = 0; s < lbk_dls_set_count(dv) && s < ITEM_CAP; s++) {
        lbk_dls_set_info si;
        if (lbk_dls_set_get(dv, s, &si) != LBK_OK) continue;
        touch(si.name, si.name_length);
        for (uint32_t i = 0; i < si.light_count && i < ITEM_CAP; i++) {
            const char *name;
            uint32_t len;
            if (lbk_dls_set_light_get(dv, s, i, &name, &len) == LBK_OK) touch(name, len);
        }
        for (uint32_t i = 0; i < si.member_count && i < ITEM_CAP; i++) {
            uint32_t m;
            lbk_dls_set_member_get(dv, s, i, &m);
        }
    }
    uint32_t found;
    lbk_dls_set_find(dv, "A", &found);
    for (uint32_t c = 0; c < lbk_dls_cluster_count(dv) && c < ITEM_CAP; c++) {
        lbk_dls_cluster_info ci;
        if (lbk_dls_cluster_get(dv, c, &ci) != LBK_OK) continue;
        for (uint32_t i = 0; i < ci.set_count && i < ITEM_CAP; i++) {
            uint32_t set;
            lbk_dls_cluster_set_get(dv, c, i, &set);
        }
        size_t payload = ci.space == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD;
        lbk_dls_cluster_decode(dv, c, touch_target, &payload);
    }
    lbk_dls_stats st;
    lbk_dls_stats_get(dv, &st);
}

/* The reference runtime over base buffers filled from the input, with doors when the DOOR
 * section agrees with the DLS: apply, change weights, apply again (the skip path), invalidate. */
static void apply_dls(const lbk_dls_view *dv, const lbk_door_view *doors, const uint8_t *fill, size_t fill_n, int valid)
{
    const uint64_t tx = lbk_dls_target_count(dv, LBK_DLS_SPACE_TEXEL), gp = lbk_dls_target_count(dv, LBK_DLS_SPACE_GLG),
                   lp = lbk_dls_target_count(dv, LBK_DLS_SPACE_LLG);
    if (tx > DLS_BUFFER_CAP / 16 || gp > DLS_BUFFER_CAP / 56 || lp > DLS_BUFFER_CAP / 56 ||
        16 * tx + 56 * (gp + lp) > DLS_BUFFER_CAP)
        return;
    /* exact-size buffers (at least 1 byte): ASan catches any write or read past a space's end */
    uint8_t *base_z = malloc(4 * tx + 1), *base_rgba = malloc(4 * tx + 1), *base_glg = malloc(28 * gp + 1),
            *base_llg = malloc(28 * lp + 1), *out_z = malloc(4 * tx + 1), *out_rgba = malloc(4 * tx + 1),
            *out_glg = malloc(28 * gp + 1), *out_llg = malloc(28 * lp + 1);
    const uint32_t sets = lbk_dls_set_count(dv), ndoors = doors ? lbk_door_count(doors) : 0;
    float *w = malloc(((size_t)sets + 1) * sizeof *w), *dw = malloc(((size_t)ndoors + 1) * sizeof *dw),
          *eff = malloc(((size_t)sets + 1) * sizeof *eff);
    if (!base_z || !base_rgba || !base_glg || !base_llg || !out_z || !out_rgba || !out_glg || !out_llg || !w || !dw || !eff)
        goto done;
    uint8_t *const bases[4] = {base_z, base_rgba, base_glg, base_llg};
    const uint64_t sizes[4] = {4 * tx, 4 * tx, 28 * gp, 28 * lp};
    for (int b = 0; b < 4; b++)
        for (uint64_t i = 0; i < sizes[b]; i++) bases[b][i] = fill_n ? fill[(i * 31 + (uint64_t)b) % fill_n] : 0;
    lbk_dls_runtime_desc rd;
    memset(&rd, 0, sizeof rd);
    rd.dls = dv, rd.doors = doors;
    rd.base_irradiance_z = (const uint32_t *)base_z, rd.base_rgba = base_rgba, rd.base_glg = base_glg, rd.base_llg = base_llg;
    rd.out_irradiance_z = (uint32_t *)out_z, rd.out_rgba = out_rgba, rd.out_glg = out_glg, rd.out_llg = out_llg;
    lbk_dls_runtime *rt;
    if (lbk_dls_runtime_open(&rd, &rt) != LBK_OK) {
        if (valid) abort();
        goto done;
    }
    for (uint32_t i = 0; i <= sets; i++) w[i] = 1.0f;
    for (uint32_t i = 0; i <= ndoors; i++) dw[i] = 0.75f;
    lbk_dls_apply_stats st;
    if (lbk_dls_apply(rt, w, dw, &st) != LBK_OK && valid) abort();
    for (uint32_t i = 0; i < sets; i += 2) w[i] = 0.5f;
    if (lbk_dls_apply(rt, w, NULL, &st) != LBK_OK && valid) abort();
    if (lbk_dls_apply(rt, w, NULL, &st) != LBK_OK && valid) abort();
    lbk_dls_effective_weights(rt, w, dw, eff);
    lbk_dls_runtime_invalidate(rt);
    if (lbk_dls_apply(rt, NULL, NULL, &st) != LBK_OK && valid) abort();
    /* the same apply split into jobs (run in reverse order), then the regions it reports */
    for (uint32_t i = 1; i < sets; i += 3) w[i] = 2.0f;
    uint32_t jobs;
    if (lbk_dls_apply_begin(rt, w, dw, &jobs) == LBK_OK) {
        for (uint32_t j = jobs; j-- > 0;) lbk_dls_apply_job(rt, j);
        if (lbk_dls_apply_end(rt, &st) != LBK_OK && valid) abort();
    } else if (valid) {
        abort();
    }
    for (uint32_t sp = 0; sp < 3; sp++)
        for (uint32_t i = 0; i < lbk_dls_dirty_range_count(rt, sp); i++) {
            lbk_dls_range rg;
            if (lbk_dls_dirty_range_get(rt, sp, i, &rg) != LBK_OK) abort();
        }
    touch(out_z, 4 * tx), touch(out_rgba, 4 * tx), touch(out_glg, 28 * gp), touch(out_llg, 28 * lp);
    lbk_dls_runtime_close(rt);
done:
    free(base_z), free(base_rgba), free(base_glg), free(base_llg);
    free(out_z), free(out_rgba), free(out_glg), free(out_llg);
    free(w), free(dw), free(eff);
}

static void read_doors(const lbk_door_view *dv)
{
    for (uint32_t i = 0; i < lbk_door_count(dv) && i < ITEM_CAP; i++) {
        lbk_door_info di;
        if (lbk_door_get(dv, i, &di) == LBK_OK) touch(di.name, di.name_length);
    }
    for (uint32_t s = 0; s < lbk_door_state_count(dv) && s < ITEM_CAP; s++) {
        uint32_t count, set;
        if (lbk_door_state_get(dv, s, &count, &set) != LBK_OK) continue;
        for (uint32_t i = 0; i < count && i < ITEM_CAP; i++) {
            uint32_t door;
            lbk_door_state_door_get(dv, s, i, &door);
        }
    }
}

/* DLS and DOOR together: the runtime takes the doors when they agree with the sets. */
static void exercise_sets(lbk_reader *r, const uint8_t *file, size_t file_n, int valid)
{
    const void *d;
    size_t n;
    lbk_door_view *doors = NULL;
    if (lbk_reader_section_by_type(r, LBK_SECTION_DOOR, &d, &n) == LBK_OK) {
        if (lbk_door_open(d, n, NULL, &doors) == LBK_OK) read_doors(doors);
        else if (valid) abort();
    }
    if (lbk_reader_section_by_type(r, LBK_SECTION_DLS, &d, &n) == LBK_OK) {
        lbk_dls_view *dv;
        if (lbk_dls_open(d, n, NULL, &dv) == LBK_OK) {
            read_dls(dv);
            int agree = doors && lbk_door_check_dls(doors, dv) == LBK_OK;
            if (doors && !agree && valid) abort();
            apply_dls(dv, agree ? doors : NULL, file, file_n, valid);
            lbk_dls_close(dv);
        } else if (valid) {
            abort();
        }
    }
    if (doors) lbk_door_close(doors);
}

/* TERR: whatever lbk_terr_open accepts, every code it promises is readable and decodes. */
static void read_terr(const void *d, size_t n)
{
    lbk_terr_view v;
    if (lbk_terr_open(d, n, &v) != LBK_OK) return;
    uint8_t c;
    if (lbk_terr_code_get(&v, v.texel_count - 1, &c) != LBK_OK || lbk_terr_code_get(&v, v.texel_count, &c) == LBK_OK) abort();
    if (lbk_terr_decode(v.codes[0]) != lbk_terr_decode(v.codes[0])) abort(); /* never NaN */
}

/* lbk_lmuv_object_check on a GENERATED record against the mesh the record itself describes
 * (corner i = remap[indices[i]]): every corner matches, so the only refusal can be the vertex
 * order; one corner moved to another source vertex is refused at that corner. */
static void check_record_against_itself(const lbk_lmuv_view *v, const lbk_lmuv_object *o)
{
    enum { MAX_PRIMS = 8, MAX_INDICES = 4096 };
    if (o->kind != LBK_LMUV_GENERATED || o->primitive_count > MAX_PRIMS) return;
    lbk_lmuv_mesh_primitive mp[MAX_PRIMS];
    uint32_t *corners[MAX_PRIMS] = {0};
    int ok = 1;
    for (uint32_t k = 0; k < o->primitive_count && ok; k++) {
        lbk_lmuv_primitive q;
        if (lbk_lmuv_get_primitive(v, o->primitive_first + k, &q) != LBK_OK) abort();
        ok = q.index_count <= MAX_INDICES && (corners[k] = malloc(4 * (size_t)q.index_count + 4)) != NULL;
        for (uint32_t i = 0; ok && i < q.index_count; i++) {
            uint32_t x;
            if (lbk_lmuv_index(v, &q, i, &x) != LBK_OK || lbk_lmuv_vertex(v, &q, x, &corners[k][i], NULL) != LBK_OK)
                abort();
        }
        mp[k] = (lbk_lmuv_mesh_primitive){.source_primitive = q.source_primitive,
                                          .source_vertex_count = q.source_vertex_count,
                                          .triangle_count = q.index_count / 3, .corners = corners[k]};
    }
    if (ok) {
        lbk_lmuv_mesh_desc mesh = LBK_LMUV_MESH_DESC_INIT;
        mesh.source_node = o->source_node;
        mesh.primitive_count = o->primitive_count;
        mesh.primitives = mp;
        lbk_lmuv_check_detail why;
        const lbk_result r = lbk_lmuv_object_check(v, o, &mesh, &why);
        if (r != LBK_OK && !(r == LBK_ERR_MISMATCH && why.code == LBK_LMUV_CHECK_VERTEX_ORDER)) abort();
        if (mp[0].source_vertex_count > 1) {
            corners[0][0] = (corners[0][0] + 1) % mp[0].source_vertex_count;
            if (lbk_lmuv_object_check(v, o, &mesh, &why) != LBK_ERR_MISMATCH || why.code != LBK_LMUV_CHECK_CORNER ||
                why.primitive != 0 || why.triangle != 0 || why.corner != 0)
                abort();
        }
    }
    for (uint32_t k = 0; k < o->primitive_count; k++) free(corners[k]);
}

/* LMUV: whatever lbk_lmuv_open accepts, every element it promises is readable and in range, and
 * lbk_lmuv_object_check agrees with what the records say. */
static void read_lmuv(const void *d, size_t n)
{
    lbk_lmuv_view v;
    if (lbk_lmuv_open(d, n, &v) != LBK_OK) return;
    for (uint32_t r = 0; r < v.record_count && r < 4096; r++) {
        lbk_lmuv_object o;
        uint32_t back;
        if (lbk_lmuv_get_object(&v, r, &o) != LBK_OK) abort();
        lbk_lmuv_find_object(&v, o.object, &back);
        if (r < 64) check_record_against_itself(&v, &o);
    }
    for (uint32_t p = 0; p < v.primitive_count && p < 4096; p++) {
        lbk_lmuv_primitive q;
        if (lbk_lmuv_get_primitive(&v, p, &q) != LBK_OK) abort();
        for (uint32_t i = 0; i < q.index_count && i < 65536; i++) {
            uint32_t x;
            if (lbk_lmuv_index(&v, &q, i, &x) != LBK_OK || x >= q.vertex_count) abort();
        }
        for (uint32_t k = 0; k < q.vertex_count && k < 65536; k++) {
            uint32_t src;
            float xy[2];
            if (lbk_lmuv_vertex(&v, &q, k, &src, xy) != LBK_OK || src >= q.source_vertex_count) abort();
        }
    }
}

/* LMAP, any page encoding (1.0 planes, BC6H, BC5/BC4, ASTC): whatever lbk_lmap_open accepts, every
 * page's planes lie inside the section and a few texels of each decode (or are refused cleanly). */
static void read_lmap(const void *d, size_t n)
{
    lbk_lmap_view v;
    lbk_lmap_required_features(d, n);
    if (lbk_lmap_open(d, n, &v) != LBK_OK) return;
    for (uint32_t p = 0; p < v.page_count && p < 64; p++) {
        lbk_lmap_planes pl;
        if (lbk_lmap_planes_get(&v, p, &pl) != LBK_OK) abort();
        for (int k = 0; k < 2; k++)
            if (pl.offset[k] > n || pl.bytes[k] > n - pl.offset[k]) abort();
        const uint32_t xs[3] = {0, pl.width / 2, pl.width - 1}, ys[3] = {0, pl.height / 2, pl.height - 1};
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                lbk_ahd_texel_f t;
                const lbk_result r = lbk_lmap_planes_texel_unpack(&pl, xs[i], ys[j], &t);
                if (r != LBK_OK && r != LBK_ERR_UNSUPPORTED_FEATURE) abort();
                float rgb[3];
                const float nz[3] = {0, 0, 1};
                lbk_lmap_planes_irradiance(&pl, xs[i], ys[j], nz, rgb);
            }
        lbk_lmap_planes_rect_bytes(&pl, 0, 0, pl.width, pl.height);
        lbk_lmap_page pg;
        const lbk_result r = lbk_lmap_page_get(&v, p, &pg);
        if (r != LBK_OK && !(r == LBK_ERR_UNSUPPORTED_FEATURE && pl.blocks_x)) abort();
    }
}

static int known_type(uint32_t t)
{
    static const uint32_t known[] = {LBK_SECTION_META, LBK_SECTION_REPT, LBK_SECTION_OBJS,
                                     LBK_SECTION_LMAP, LBK_SECTION_GLG,  LBK_SECTION_LLG,
                                     LBK_SECTION_DLS,  LBK_SECTION_DOOR, LBK_SECTION_OCTP,
                                     LBK_SECTION_LMUV, LBK_SECTION_TERR};
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
        if (known[i] == t) return 1;
    return 0;
}

static void exercise(const uint8_t *data, size_t size)
{
    lbk_validate_options vo = {.max_decoded_bytes = DECODE_CAP};
    lbk_validate_summary s;
    size_t issues = 0;
    lbk_validate_memory(data, size, &vo, count_issue, &issues, &s);
    if (issues != (size_t)s.fatal + s.errors + s.warnings) abort();

    /* The reader and the validator share the framing rules: a file the validator passes must
     * open and give every known section's bytes and views. */
    const int valid = s.fatal == 0 && s.errors == 0;
    lbk_read_options ro = {.max_decoded_bytes = DECODE_CAP};
    lbk_reader *r;
    if (lbk_reader_open_memory(data, size, &ro, &r) != LBK_OK) {
        if (valid) abort();
        return;
    }
    if (s.fatal) abort(); /* the reader accepted what the validator found unreadable */
    for (uint32_t i = 0; i < lbk_reader_section_count(r); i++) {
        lbk_section_info si;
        if (lbk_reader_section_get(r, i, &si) != LBK_OK) abort();
        const void *d;
        size_t n;
        if (lbk_reader_section_data(r, i, &d, &n) != LBK_OK) {
            if (valid && known_type(si.type)) abort();
            continue;
        }
        if (n != si.decoded_size) abort();
        int opened = LBK_OK;
        switch (si.type) {
        case LBK_SECTION_LMAP:
            read_lmap(d, n);
            opened = sample_lmap(d, n);
            break;
        case LBK_SECTION_GLG: opened = sample_glg(d, n, valid); break;
        case LBK_SECTION_LLG: opened = sample_llg(d, n, valid); break;
        case LBK_SECTION_OCTP: opened = sample_octp(d, n, valid); break;
        case LBK_SECTION_LMUV: read_lmuv(d, n); break;
        case LBK_SECTION_TERR: read_terr(d, n); break;
        default: read_meta_objs_rept(si.type, d, n); break;
        }
        if (opened != LBK_OK && valid) abort();
    }
    exercise_sets(r, data, size, valid);
    lbk_reader_close(r);
}

static uint32_t rd32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t rd64(const uint8_t *p) { return rd32(p) | (uint64_t)rd32(p + 4) << 32; }
static void wr64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i));
}

/* Recompute everything a checksum or file_size protects, so mutations inside sections survive. */
static void fix_up(uint8_t *f, size_t size)
{
    if (size < 64) return;
    wr64(f + 16, size);
    uint32_t n = rd32(f + 32);
    if (n >= 1 && n <= LBK_MAX_SECTIONS && 64 + 48 * (uint64_t)n <= size) {
        for (uint32_t i = 0; i < n; i++) {
            uint8_t *e = f + 64 + 48 * i;
            uint64_t off = rd64(e + 16), len = rd64(e + 24);
            if (off <= size && len <= size - off) wr64(e + 40, XXH3_64bits(f + off, (size_t)len));
        }
        wr64(f + 48, XXH3_64bits(f + 64, 48 * (size_t)n));
    }
    wr64(f + 56, XXH3_64bits(f, 56));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* An exact-size heap copy: any read past the end is caught by ASan. */
    uint8_t *copy = malloc(size ? size : 1);
    if (!copy) return 0;
    if (size) memcpy(copy, data, size);
    exercise(copy, size);
    fix_up(copy, size);
    exercise(copy, size);
    free(copy);
    return 0;
}
