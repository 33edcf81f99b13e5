/* The global light grid at production probe counts (seed 001's levels hold 150–230 k probes; the
 * baker's default cap is BK_GLG_DEFAULT_MAX_PROBES): the Delaunay tetrahedralisation (qhull,
 * bake/probes/delaunay.c) and the runtime walk (lbk_glg_sample, spec/container.md §10), timed at
 * about 16 k, 64 k and 250 k probes in the same run, printed with their ratios to the 16 k case.
 *
 * Two point sets per size, in a 4:4:1 box:
 *  - "grid":    a perfect regular lattice (every cell cospherical: Delaunay's hard case, what the
 *               placement's top grid is far from geometry);
 *  - "refined": a lattice plus a twice as fine one in the bottom quarter (the placement's
 *               refinement near a floor), jittered by 1e-3 of the spacing.
 * The walk: 1 M lookups along a smooth path through the level, each starting from the last
 * one's tetrahedron (what a moving object does at run time), and 1 M at random points, each
 * starting from the previous one's (the worst case a renderer meets); ns per lookup and the mean
 * tetrahedra visited. CPU time of this thread; qhull is single-threaded. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/probes/delaunay.h"
#include "bench/bench_util.h"
#include "lbk/glg.h"
#include "lbk/sh.h"

#define LOOKUPS 1000000

typedef struct result {
    size_t points, tets;
    double delaunay_s, merged_s, path_ns, random_ns, path_steps, random_steps;
    int fell_back;
} result;

/* nx × ny × nz lattice of spacing 1 in [0, n−1]; with `refined`, the bottom quarter again at
 * spacing 0.5 (points not on the coarse lattice), all jittered. */
static float *make_points(int n, int refined, size_t *count)
{
    int nx = 4 * n, ny = n, nz = 4 * n;
    size_t cap = (size_t)nx * ny * nz + (refined ? (size_t)(2 * nx) * (2 * (ny / 4) + 1) * (2 * nz) : 0);
    float *p = malloc(3 * cap * sizeof *p);
    if (!p) return NULL;
    bench_rng rng = {0x6c626b67 + (uint64_t)n};
    double jit = refined ? 1e-3 : 0.0;
    size_t m = 0;
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++)
            for (int x = 0; x < nx; x++) {
                p[3 * m] = (float)(x + jit * (bench_next(&rng) - 0.5));
                p[3 * m + 1] = (float)(y + jit * (bench_next(&rng) - 0.5));
                p[3 * m + 2] = (float)(z + jit * (bench_next(&rng) - 0.5));
                m++;
            }
    if (refined)
        for (int z = 0; z < 2 * nz - 1; z++)
            for (int y = 0; y <= 2 * (ny / 4); y++)
                for (int x = 0; x < 2 * nx - 1; x++) {
                    if (!(x & 1) && !(y & 1) && !(z & 1)) continue; /* on the coarse lattice */
                    p[3 * m] = (float)(0.5 * x + jit * (bench_next(&rng) - 0.5));
                    p[3 * m + 1] = (float)(0.5 * y + jit * (bench_next(&rng) - 0.5));
                    p[3 * m + 2] = (float)(0.5 * z + jit * (bench_next(&rng) - 0.5));
                    m++;
                }
    *count = m;
    return p;
}

static int walk(const lbk_glg_view *v, int n, int random, double *ns, double *steps)
{
    bench_rng rng = {12345};
    uint32_t hint = 0;
    double ext[3] = {4.0 * n - 1, n - 1, 4.0 * n - 1}, sum_steps = 0.0, acc = 0.0;
    double t0 = bench_thread_cpu();
    for (int i = 0; i < LOOKUPS; i++) {
        float q[3];
        if (random) {
            for (int a = 0; a < 3; a++) q[a] = (float)(bench_next(&rng) * ext[a]);
        } else { /* a slow loop around the level at mid height: ~0.01 spacing per lookup */
            double t = (double)i / LOOKUPS * 2.0 * 3.14159265358979;
            q[0] = (float)(0.5 * ext[0] * (1.0 + 0.8 * cos(t)));
            q[1] = (float)(0.5 * ext[1] * (1.0 + 0.5 * sin(7 * t)));
            q[2] = (float)(0.5 * ext[2] * (1.0 + 0.8 * sin(t)));
        }
        lbk_sh9_rgb sh;
        lbk_glg_sample_info info;
        if (lbk_glg_sample(v, q, &hint, &sh, &info) != LBK_OK) return -1;
        sum_steps += info.location.steps;
        acc += sh.c[0][0];
    }
    double t1 = bench_thread_cpu();
    *ns = (t1 - t0) / LOOKUPS * 1e9;
    *steps = sum_steps / LOOKUPS;
    return acc >= 0.0 ? 0 : -1; /* keeps the lookups from being optimised away */
}

static int run(int n, int refined, result *r)
{
    memset(r, 0, sizeof *r);
    float *pts = make_points(n, refined, &r->points);
    if (!pts) return -1;
    bk_tetmesh mesh;
    memset(&mesh, 0, sizeof mesh);
    /* the merged-cells path first (bk_delaunay's fallback, its only path before 2026-12-07) */
    bk_delaunay_options merged = {.merged_cells = 1};
    double t0 = bench_thread_cpu();
    int st = bk_delaunay(pts, r->points, &merged, &mesh);
    r->merged_s = bench_thread_cpu() - t0;
    bk_tetmesh_free(&mesh);
    t0 = bench_thread_cpu();
    if (st == BK_DELAUNAY_OK) st = bk_delaunay(pts, r->points, NULL, &mesh);
    r->delaunay_s = bench_thread_cpu() - t0;
    r->fell_back = mesh.merged_cells;
    free(pts);
    if (st != BK_DELAUNAY_OK) {
        fprintf(stderr, "delaunay: %s\n", bk_delaunay_status_name(st));
        bk_tetmesh_free(&mesh);
        return -1;
    }
    r->tets = mesh.tet_count;
    lbk_sh9_rgb *sh = calloc(mesh.point_count, sizeof *sh);
    int rc = sh ? 0 : -1;
    for (size_t i = 0; sh && i < mesh.point_count; i++) sh[i].c[0][0] = sh[i].c[1][0] = sh[i].c[2][0] = 1.0f;
    lbk_glg_build_desc d = LBK_GLG_BUILD_DESC_INIT;
    d.probe_count = (uint32_t)mesh.point_count;
    d.tetra_count = (uint32_t)mesh.tet_count;
    d.positions = (const float(*)[3])mesh.points;
    d.probes = sh;
    d.tetras = (const uint32_t(*)[4])mesh.tets;
    d.adjacency = (const uint32_t(*)[4])mesh.neighbours;
    void *bytes = NULL;
    size_t size = 0;
    lbk_glg_view v;
    if (!rc && lbk_glg_build(&d, NULL, &bytes, &size) != LBK_OK) rc = -1;
    if (!rc && lbk_glg_open(bytes, size, &v) != LBK_OK) rc = -1;
    if (!rc) rc = walk(&v, n, 0, &r->path_ns, &r->path_steps);
    if (!rc) rc = walk(&v, n, 1, &r->random_ns, &r->random_steps);
    lbk_free(NULL, bytes);
    free(sh);
    bk_tetmesh_free(&mesh);
    return rc;
}

int main(void)
{
    /* n: the lattice is 4n × n × 4n = 16 n³ points (10: 16 k, 16: 64 k, 25: 250 k); the refined
     * set adds about 1.75× that in its fine layer (7: 15 k, 11: 58 k, 18: 256 k in all) */
    static const int sizes[2][3] = {{10, 16, 25}, {7, 11, 18}};
    printf("GLG at scale: Delaunay (qhull) and the runtime walk, CPU of one thread. 'merged s': the same\n"
           "points through qhull's merged cells (the fallback; bk_delaunay_options.merged_cells), 'x faster' its\n"
           "time over bk_delaunay's, 'fallback' 1 where bk_delaunay itself had to take that path\n");
    printf("%-8s %8s %9s %11s %8s %9s %9s %9s %12s %7s %12s %7s\n", "points", "probes", "tetras", "delaunay s",
           "x first", "merged s", "x faster", "fallback", "path ns/q", "steps", "random ns/q", "steps");
    for (int refined = 0; refined < 2; refined++) {
        result base = {0};
        for (size_t i = 0; i < 3; i++) {
            result r;
            if (run(sizes[refined][i], refined, &r) != 0) {
                fprintf(stderr, "bench_glg_scale: failed at n=%d\n", sizes[refined][i]);
                return 1;
            }
            if (i == 0) base = r;
            printf("%-8s %8zu %9zu %11.2f %8.1f %9.2f %9.1f %9d %12.0f %7.2f %12.0f %7.1f\n",
                   refined ? "refined" : "grid", r.points, r.tets, r.delaunay_s, r.delaunay_s / base.delaunay_s,
                   r.merged_s, r.merged_s / r.delaunay_s, r.fell_back, r.path_ns, r.path_steps, r.random_ns,
                   r.random_steps);
            fflush(stdout);
        }
    }
    return 0;
}
