/* glTF import is linear in the file's size (printed, never asserted): a level of N nodes, most of
 * them empty as a denial-of-service file would have them, imported at N = 10^5 and 10^6. The
 * ratio of times is the measure (ideal 10; the callback depth check it replaced was quadratic:
 * 20 k nodes 1.4 s, 80 k 16.9 s, 10^6 never finished). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "scene/import.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* One emissive triangle (embedded buffer) on node 0, then `n` empty nodes in the scene. */
static int write_level(const char *path, long n)
{
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    fputs("{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/"
          "octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
          "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"accessors\":[{\"bufferView\":0,"
          "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]}],"
          "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}],"
          "\"materials\":[{\"emissiveFactor\":[1,1,1]}],\"nodes\":[{\"mesh\":0}",
          f);
    for (long i = 0; i < n; i++) fputs(",{}", f);
    fputs("],\"scenes\":[{\"nodes\":[0", f);
    for (long i = 1; i <= n; i++) fprintf(f, ",%ld", i);
    fputs("]}],\"scene\":0}", f);
    return fclose(f);
}

static double import_seconds(long n)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/bench_import_%ld_%d.gltf", n, (int)getpid());
    if (write_level(path, n)) {
        fprintf(stderr, "bench_import: cannot write %s\n", path);
        exit(1);
    }
    bk_scene s;
    char err[512];
    double t0 = now();
    int rc = bk_import_gltf(path, NULL, &s, err, sizeof err);
    double secs = now() - t0;
    remove(path);
    if (rc) {
        fprintf(stderr, "bench_import: %s\n", err);
        exit(1);
    }
    bk_scene_free(&s);
    return secs;
}

int main(void)
{
    double t5 = import_seconds(100000), t6 = import_seconds(1000000);
    printf("glTF import, empty nodes: 10^5 %.2f s, 10^6 %.2f s, ratio %.1f (linear: 10)\n", t5, t6, t6 / t5);
    return 0;
}
