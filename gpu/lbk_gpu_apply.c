/* lbk-gpu-apply: uploads a container's dynamic light sets to a Vulkan device (the DLS section,
 * the LMAP section as the base texels, the GLG and LLG probes, the DOOR section), applies a
 * sequence of weights there, reads the results back and, with --check, compares them byte for
 * byte with lbk_dls_apply on the CPU. Prints dispatches, bytes moved and times per apply.
 *
 *   lbk-gpu-apply LEVEL.lbk [--weights W,W,… ]… [--doors D,…] [--check] [--naive]
 *
 * Each --weights gives every set's weight in set order (missing ones 0; `all=X` sets all to X);
 * without any, the sequence is: every set at 1, every set at 0.5, set 0 at 0.25, all off.
 * --doors gives the door openings (all applies). --naive also runs the naive per-target gather.
 * Exit codes: 0 done (and identical), 1 the GPU and CPU bytes differ, 2 usage, 3 I/O, 4 the file
 * cannot be used, 5 no Vulkan device or a Vulkan error. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gpu/host/gpu_dls.h"
#include "lbk/container.h"
#include "lbk/dls.h"
#include "lbk/door.h"
#include "lbk/glg.h"
#include "lbk/lightmap.h"
#include "lbk/llg.h"

#define MAX_STEPS 64

static int usage(void)
{
    fprintf(stderr, "usage: lbk-gpu-apply LEVEL.lbk [--weights W,W,...|all=X]... [--doors D,...] [--check] [--naive]\n");
    return 2;
}

/* "0.5,1,,0" or "all=0.5" into n floats (the rest 0). */
static int parse_weights(const char *s, float *w, uint32_t n)
{
    memset(w, 0, n * sizeof *w);
    if (!strncmp(s, "all=", 4)) {
        char *end;
        const float x = strtof(s + 4, &end);
        if (*end) return -1;
        for (uint32_t i = 0; i < n; i++) w[i] = x;
        return 0;
    }
    for (uint32_t i = 0; *s; i++) {
        char *end;
        const float x = strtof(s, &end);
        if (end == s && *s != ',') return -1;
        if (i < n) w[i] = x;
        s = *end == ',' ? end + 1 : end;
        if (*end && *end != ',') return -1;
    }
    return 0;
}

typedef struct level {
    lbk_reader *reader;
    const void *dls, *door, *lmap, *glg, *llg;
    size_t dls_size, door_size, lmap_size, glg_size, llg_size;
    lbk_glg_view gv;
    lbk_llg_view lv;
    lbk_lmap_view mv;
} level;

static int load(const char *path, level *lv)
{
    memset(lv, 0, sizeof *lv);
    lbk_result r = lbk_reader_open_file(path, NULL, &lv->reader);
    if (r != LBK_OK) {
        fprintf(stderr, "lbk-gpu-apply: %s: %s\n", path, lbk_result_message(r));
        return r == LBK_ERR_IO ? 3 : 4;
    }
    if (lbk_reader_section_by_type(lv->reader, LBK_SECTION_DLS, &lv->dls, &lv->dls_size) != LBK_OK) {
        fprintf(stderr, "lbk-gpu-apply: %s has no usable DLS section\n", path);
        return 4;
    }
    if (lbk_reader_section_by_type(lv->reader, LBK_SECTION_DOOR, &lv->door, &lv->door_size) != LBK_OK) lv->door = NULL;
    if (lbk_reader_section_by_type(lv->reader, LBK_SECTION_LMAP, &lv->lmap, &lv->lmap_size) != LBK_OK ||
        lbk_lmap_open(lv->lmap, lv->lmap_size, &lv->mv) != LBK_OK)
        lv->lmap = NULL;
    if (lbk_reader_section_by_type(lv->reader, LBK_SECTION_GLG, &lv->glg, &lv->glg_size) != LBK_OK ||
        lbk_glg_open(lv->glg, lv->glg_size, &lv->gv) != LBK_OK)
        lv->glg = NULL;
    if (lbk_reader_section_by_type(lv->reader, LBK_SECTION_LLG, &lv->llg, &lv->llg_size) != LBK_OK ||
        lbk_llg_open(lv->llg, lv->llg_size, &lv->lv) != LBK_OK)
        lv->llg = NULL;
    return 0;
}

/* The CPU reference over the same bases: pages in place, outputs of the same layout. */
typedef struct cpu_ref {
    lbk_dls_view *view;
    lbk_door_view *doors;
    lbk_dls_runtime *rt;
    uint8_t *lmap_out, *glg_out, *llg_out;
} cpu_ref;

static int cpu_open(const level *lv, cpu_ref *c)
{
    memset(c, 0, sizeof *c);
    if (lbk_dls_open(lv->dls, lv->dls_size, NULL, &c->view) != LBK_OK) return -1;
    if (lv->door && lbk_door_open(lv->door, lv->door_size, NULL, &c->doors) != LBK_OK) return -1;
    const uint64_t ng = lbk_dls_target_count(c->view, 1), nl = lbk_dls_target_count(c->view, 2);
    lbk_dls_page *pages = NULL;
    lbk_dls_runtime_desc d = {.size = sizeof d, .dls = c->view, .doors = c->doors};
    if (lv->lmap) {
        c->lmap_out = malloc(lv->lmap_size);
        pages = calloc(lv->mv.page_count, sizeof *pages);
        if (!c->lmap_out || !pages) return -1;
        memcpy(c->lmap_out, lv->lmap, lv->lmap_size); /* header and page table as the input's */
        for (uint32_t p = 0; p < lv->mv.page_count; p++) {
            lbk_lmap_page pg;
            lbk_lmap_page_get(&lv->mv, p, &pg);
            pages[p] = (lbk_dls_page){.width = pg.width, .height = pg.height, .base_irradiance = pg.irradiance,
                                      .base_rgba = pg.rgba, .out_irradiance = c->lmap_out + pg.irradiance_offset,
                                      .out_rgba = c->lmap_out + pg.rgba_offset};
        }
        d.page_count = lv->mv.page_count, d.pages = pages;
    }
    if (ng && lv->glg) c->glg_out = malloc(28 * ng), d.base_glg = lv->gv.probes, d.out_glg = c->glg_out;
    if (nl && lv->llg) c->llg_out = malloc(28 * nl), d.base_llg = lv->lv.probes, d.out_llg = c->llg_out;
    const lbk_result r = lbk_dls_runtime_open(&d, &c->rt);
    free(pages);
    if (r != LBK_OK) fprintf(stderr, "lbk-gpu-apply: CPU runtime: %s\n", lbk_result_message(r));
    return r == LBK_OK ? 0 : -1;
}

static void cpu_close(cpu_ref *c)
{
    lbk_dls_runtime_close(c->rt);
    if (c->doors) lbk_door_close(c->doors);
    lbk_dls_close(c->view);
    free(c->lmap_out), free(c->glg_out), free(c->llg_out);
}

static int same(const level *lv, const cpu_ref *c, const gpu_dls *g, uint64_t ng, uint64_t nl)
{
    if (lv->lmap && memcmp(gpu_dls_lmap(g), c->lmap_out, lv->lmap_size)) return 0;
    if (c->glg_out && memcmp(gpu_dls_probes(g, 1), c->glg_out, 28 * ng)) return 0;
    if (c->llg_out && memcmp(gpu_dls_probes(g, 2), c->llg_out, 28 * nl)) return 0;
    return 1;
}

int main(int argc, char **argv)
{
    const char *path = NULL, *steps[MAX_STEPS], *doors = NULL;
    int nsteps = 0, check = 0, naive = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--weights") && i + 1 < argc && nsteps < MAX_STEPS) steps[nsteps++] = argv[++i];
        else if (!strcmp(argv[i], "--doors") && i + 1 < argc) doors = argv[++i];
        else if (!strcmp(argv[i], "--check")) check = 1;
        else if (!strcmp(argv[i], "--naive")) naive = 1;
        else if (!strcmp(argv[i], "--help")) return usage() - 2;
        else if (argv[i][0] != '-' && !path) path = argv[i];
        else return usage();
    }
    if (!path) return usage();
    if (!nsteps) steps[0] = "all=1", steps[1] = "all=0.5", steps[2] = "0.25", steps[3] = "all=0", nsteps = 4;
    level lv;
    int rc = load(path, &lv);
    if (rc) return rc;
    lbk_dls_view *v;
    if (lbk_dls_open(lv.dls, lv.dls_size, NULL, &v) != LBK_OK) return 4;
    const uint32_t nsets = lbk_dls_set_count(v);
    const uint64_t ng = lbk_dls_target_count(v, 1), nl = lbk_dls_target_count(v, 2);
    lbk_dls_close(v);
    gpu_ctx ctx;
    char err[256];
    if (gpu_open(&ctx, err, sizeof err)) {
        fprintf(stderr, "lbk-gpu-apply: %s\n", err);
        lbk_reader_close(lv.reader);
        return 5;
    }
    printf("device: %s%s\n", ctx.device_name, ctx.cpu_device ? " (a CPU device: its times are not GPU times)" : "");
    gpu_dls_level gl = {.dls = lv.dls, .dls_size = lv.dls_size, .door = lv.door, .door_size = lv.door_size, .lmap = lv.lmap,
                        .lmap_size = lv.lmap_size, .glg = lv.glg ? lv.gv.probes : NULL, .llg = lv.llg ? lv.lv.probes : NULL,
                        .naive = naive};
    gpu_dls *g;
    if (gpu_dls_open(&ctx, &gl, &g, err, sizeof err)) {
        fprintf(stderr, "lbk-gpu-apply: %s\n", err);
        gpu_close(&ctx);
        lbk_reader_close(lv.reader);
        return 4;
    }
    cpu_ref cpu = {0};
    if (check && cpu_open(&lv, &cpu)) rc = 4;
    float *w = calloc(nsets + 1, sizeof *w), dw[64] = {0};
    if (doors && parse_weights(doors, dw, 64)) rc = 2;
    for (int s = 0; s < nsteps && !rc; s++) {
        if (parse_weights(steps[s], w, nsets)) {
            rc = 2;
            break;
        }
        gpu_dls_stats st;
        if (gpu_dls_apply(g, w, doors ? dw : NULL, &st)) {
            fprintf(stderr, "lbk-gpu-apply: apply failed (weights must be finite)\n");
            rc = 5;
            break;
        }
        printf("apply %d (%s): %u dispatches of %u clusters (%u skipped), %llu invocations, %.3f MB moved, %.3f ms device, "
               "%.3f ms wall\n",
               s, steps[s], st.dispatches, gpu_dls_cluster_count(g), st.clusters_skipped, (unsigned long long)st.invocations,
               st.bytes_moved / 1e6, st.gpu_ms, st.wall_ms);
        if (check) {
            if (lbk_dls_apply(cpu.rt, w, doors ? dw : NULL, NULL) != LBK_OK) rc = 4;
            else if (!same(&lv, &cpu, g, ng, nl)) {
                fprintf(stderr, "lbk-gpu-apply: apply %d: the GPU bytes differ from lbk_dls_apply's\n", s);
                rc = 1;
            } else {
                printf("  identical to lbk_dls_apply\n");
            }
        }
    }
    if (naive && !rc) {
        gpu_dls_stats st;
        double dc, dn;
        if (gpu_dls_apply_naive(g, w, doors ? dw : NULL, &st)) rc = 5;
        gpu_dls_divergence(g, &dc, &dn);
        if (!rc) {
            printf("naive gather: %u dispatches, %.3f MB moved, %.3f ms device; idle lanes of the entry loop (waves of 32): "
                   "clustered %.1f%%, naive %.1f%%\n", st.dispatches, st.bytes_moved / 1e6, st.gpu_ms, 100 * dc, 100 * dn);
            if (check && !same(&lv, &cpu, g, ng, nl)) {
                fprintf(stderr, "lbk-gpu-apply: the naive gather's bytes differ\n");
                rc = 1;
            }
        }
    }
    free(w);
    if (check) cpu_close(&cpu);
    gpu_dls_close(g);
    gpu_close(&ctx);
    lbk_reader_close(lv.reader);
    return rc;
}
