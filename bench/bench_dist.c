/* Distributed bakes (bake/dist/DIST.md): wall time of a bake cut into N = 1, 2, 4, 8 units and
 * run with `make -j2` through `lbk plan --makefile`, as ratios to the local `lbk bake` of the
 * same run (the ideal on 2 cores is 0.5 at N >= 2); the plan's and the merge's own time; what
 * every unit repeats (the slowest unit's time against local/N); bytes moved per unit (its part)
 * against its compute time; and a projection to 64 machines. Two scenes: the Cornell box (only
 * the base transport run: units cut its receivers and share its caches through the plan's cache
 * folder, so the first of the units run alone computes every bounce and the others read them;
 * bench/scale/dist_shared.py splits that work per unit and projects the critical path) and a scene
 * of light sets, a door and a combination (8 runs: units take whole runs); then the Cornell box
 * with the default preset's error target and the light-set scene with guided doors. Every merge
 * is checked byte-identical to the local bake.
 * Usage: bench_dist [lbk [scene "options"]]. Wall seconds (the machine is shared: run it alone). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double run(const char *cmd)
{
    double t = now();
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_dist: failed: %s\n", cmd);
        exit(1);
    }
    return now() - t;
}

static long file_size(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 ? (long)st.st_size : -1;
}

/* One scene: local, then N = 1, 2, 4, 8. Returns 0 when every merge equals the local bake. */
static int bench(const char *lbk, const char *scene, const char *opts)
{
    char dir[] = "/tmp/bench-dist-XXXXXX", cmd[4096];
    if (!mkdtemp(dir)) return 1;
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/local.lbk %s --threads 2 -q", lbk, scene, dir, opts);
    const double local = run(cmd);
    printf("\nscene %s, %s\nlocal lbk bake (2 threads): %.2f s\n\n", scene, opts, local);
    printf("%5s %9s %7s %7s %7s %11s %11s %11s %12s %10s\n", "units", "make -j2", "ratio", "plan s", "merge s",
           "slowest s", "sum units s", "repeated s", "part bytes", "B per s");
    const int counts[] = {1, 2, 4, 8};
    double unit1 = 0, sum8 = 0, slow8 = 0, merge8 = 0;
    for (int c = 0; c < 4; c++) {
        const int n = counts[c];
        snprintf(cmd, sizeof cmd, "%s plan %s -o %s/m%d.lbk --plan %s/p%d.json --units %d --makefile %s/mk%d %s >/dev/null", lbk,
                 scene, dir, n, dir, n, n, dir, n, opts);
        const double plan = run(cmd);
        snprintf(cmd, sizeof cmd, "make -s -j2 -f %s/mk%d LBK=%s 'UNIT_FLAGS=-q --threads 1' >/dev/null", dir, n, lbk);
        const double total = run(cmd);
        snprintf(cmd, sizeof cmd, "cmp -s %s/local.lbk %s/m%d.lbk", dir, dir, n);
        if (system(cmd) != 0) {
            printf("N=%d: the merge differs from the local bake\n", n);
            return 1;
        }
        /* every unit alone (2 threads, one after the other) and the merge alone: the split of the
         * time; the parts' bytes against the units' compute */
        double slowest = 0, sum = 0;
        long bytes = 0;
        for (int k = 0; k < n; k++) {
            snprintf(cmd, sizeof cmd, "%s bake-unit %s/p%d.json %d -o %s/u%d-%d.lbkpart --threads 2 -q", lbk, dir, n, k, dir, n, k);
            const double u = run(cmd);
            sum += u;
            if (u > slowest) slowest = u;
            char part[512];
            snprintf(part, sizeof part, "%s/u%d-%d.lbkpart", dir, n, k);
            bytes += file_size(part);
        }
        snprintf(cmd, sizeof cmd, "%s merge %s/p%d.json %s/m%d.lbk.parts/part-*.lbkpart -o %s/again%d.lbk --threads 2 -q", lbk,
                 dir, n, dir, n, dir, n);
        const double merge = run(cmd);
        printf("%5d %8.2fs %7.2f %7.3f %7.2f %11.2f %11.2f %11.2f %12ld %10.0f\n", n, total, total / local, plan, merge, slowest,
               sum, sum - local, bytes / n, bytes / sum);
        if (n == 1) unit1 = sum;
        if (n == 8) sum8 = sum, slow8 = slowest, merge8 = merge;
    }
    /* work(N) = Σ units = W + X·(N − 1): X is what each further unit repeats (import, layout
     * and, for the runs it shares, the caches of every pass) */
    const double X = (sum8 - unit1) / 7.0;
    printf("\nfit: sum of units = %.2f s + %.2f s per further unit (repeated work); slowest of 8 %.2f s (ideal %.2f);"
           " merge %.2f s\n", unit1, X, slow8, unit1 / 8, merge8);
    printf("64 machines, this scene: about %.2f s per unit (if the repeated work stays %.2f s) + %.2f s merge against %.2f s"
           " local (x%.1f)\n", unit1 / 64 + X, X, merge8, local, local / (unit1 / 64 + X + merge8));
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : 1;
}

int main(int argc, char **argv)
{
    const char *lbk = argc > 1 ? argv[1] : "build/lbk";
    if (argc > 3) return bench(lbk, argv[2], argv[3]);
    int r = bench(lbk, "scenes/cornell_box/CornellBox-Original.gltf", "--samples 992 --target-error none --texel-density 8 --seed 1");
    r |= bench(lbk, "tests/fuzz/sets_scene.gltf", "--samples 480 --target-error none --texel-density 4 --seed 1");
    /* the default preset's error target on the one-run Cornell box (every unit shares the run and
     * gathers its stop receivers: all of them here, so "repeated s" is the run's whole cost per
     * further unit), and guided doors (the merge makes their estimates: the merge column) */
    r |= bench(lbk, "scenes/cornell_box/CornellBox-Original.gltf", "--texel-density 8 --seed 1");
    r |= bench(lbk, "tests/fuzz/sets_scene.gltf", "--samples 64 --target-error none --texel-density 2 --door-method guided --seed 1");
    printf("\nESTATE-sized level (seed 001 Table 1: 133 min on 18 cores, up to 132 light sets, so 133+ transport runs):\n"
           "with units of whole runs (N <= runs) each unit bakes its runs alone and repeats only import and layout, so 64\n"
           "units approach runs/64 of the work each (bounded by the slowest run); a level with only its base run is cut by\n"
           "receivers and stays bounded by its caches' share of the work (the Cornell box's fit above).\n");
    return r;
}
