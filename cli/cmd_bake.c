/* lbk bake: the CLI over bk_bake(). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/pipeline/bake.h"
#include "cli/cli.h"

static void help(FILE *f)
{
    fputs("usage: lbk bake SCENE.gltf|SCENE.glb -o OUT.lbk [options]\n"
          "\n"
          "Bakes global illumination for a glTF level into a container: AHD lightmaps, an SH9\n"
          "global light grid, local light grids for props, and dynamic light sets and doors when\n"
          "the scene has them. Same input, options and seed give byte-identical output at any\n"
          "thread count.\n"
          "\n"
          "options:\n"
          "  -o, --output FILE       container to write (atomically; nothing is written on error)\n"
          "  --preset fast|high      quality preset (default fast; see README \"Presets\")\n"
          "  --target-error X        stop when the estimated relative RMSE drops below X (e.g. 0.02)\n"
          "  --time-limit S          stop the transport after S seconds and write what converged\n"
          "  --samples N             sample budget per receiver (overrides the preset)\n"
          "  --max-bounces N         bounce cap before the analytic tail (overrides the preset)\n"
          "  --texel-density D       lightmap texels per metre (overrides the scene's lbk_texel_density)\n"
          "  --glg-spacing M         global light grid spacing in metres\n"
          "  --sky R,G,B | FILE.exr  sky radiance (overrides the scene's lbk_sky)\n"
          "  --no-glg                leave out the global light grid\n"
          "  --octahedral            also write GIBS-style octahedral probes (OCTP)\n"
          "  --dls-threshold X       light sets and doors store a texel/probe only where their light\n"
          "                          exceeds X times the mean indirect light of the texels they light\n"
          "                          directly (default 0.01; 0 keeps every lit receiver)\n"
          "  --door-method difference|guided\n"
          "                          how the light through an open door is baked: differences of\n"
          "                          full runs (default) or the seed's guided estimator (bake/sets/SETS.md)\n"
          "  --denoise auto|off      edge-aware denoising of lightmap texels and GLG probes, guided\n"
          "                          by the transport's own noise estimate (default auto: on in both\n"
          "                          presets; bake/transport/DENOISE.md)\n"
          "  --threads N             worker threads (default: all cores)\n"
          "  --seed N                random seed (default 1)\n"
          "  --json-report FILE      write the error-against-time report as JSON\n"
          "  --revision STR          revision string stored in the provenance\n"
          "  --timestamp             store the bake time in the provenance (output no longer\n"
          "                          byte-identical across runs)\n"
          "  -q, --quiet             no progress output\n"
          "  -h, --help              this text\n"
          "\n"
          "exit codes: 0 ok, 2 usage, 3 I/O error, 4 unusable scene, 5 internal error\n",
          f);
}

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end) return 0;
    *out = v;
    return 1;
}

int lbk_cmd_bake(int argc, char **argv)
{
    bk_bake_options o;
    memset(&o, 0, sizeof o);
    o.seed = 1;
    o.target_error = -1;
    int quiet = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        double d;
#define NEED_VALUE                                                         \
    do {                                                                   \
        if (!v) {                                                          \
            fprintf(stderr, "lbk bake: %s needs a value\n", a);            \
            return LBK_EXIT_USAGE;                                         \
        }                                                                  \
        i++;                                                               \
    } while (0)
#define NEED_NUMBER(lo, hi)                                                                       \
    do {                                                                                          \
        NEED_VALUE;                                                                               \
        if (!parse_double(v, &d) || !(d >= (lo) && d <= (hi))) {                                  \
            fprintf(stderr, "lbk bake: %s: '%s' is not a number in [%g, %g]\n", a, v, (double)(lo), \
                    (double)(hi));                                                                \
            return LBK_EXIT_USAGE;                                                                \
        }                                                                                         \
    } while (0)
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            help(stdout);
            return LBK_EXIT_OK;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            NEED_VALUE;
            o.output = v;
        } else if (!strcmp(a, "--preset")) {
            NEED_VALUE;
            if (strcmp(v, "fast") && strcmp(v, "high")) {
                fprintf(stderr, "lbk bake: unknown preset '%s' (fast, high)\n", v);
                return LBK_EXIT_USAGE;
            }
            o.preset = v;
        } else if (!strcmp(a, "--target-error")) {
            NEED_NUMBER(1e-6, 10);
            o.target_error = d;
        } else if (!strcmp(a, "--time-limit")) {
            NEED_NUMBER(0.001, 1e7);
            o.time_limit = d;
        } else if (!strcmp(a, "--samples")) {
            NEED_NUMBER(1, 1 << 24);
            o.max_samples = (int)d;
        } else if (!strcmp(a, "--max-bounces")) {
            NEED_NUMBER(1, 1000);
            o.max_bounces = (int)d;
        } else if (!strcmp(a, "--texel-density")) {
            NEED_NUMBER(1e-6, 1e7);
            o.texel_density = (float)d;
        } else if (!strcmp(a, "--glg-spacing")) {
            NEED_NUMBER(1e-6, 1e6);
            o.glg_spacing = (float)d;
        } else if (!strcmp(a, "--sky")) {
            NEED_VALUE;
            float r, g, b;
            char tail;
            if (sscanf(v, "%f,%f,%f%c", &r, &g, &b, &tail) == 3) {
                if (!(r >= 0 && g >= 0 && b >= 0 && r < 1e30f && g < 1e30f && b < 1e30f)) {
                    fprintf(stderr, "lbk bake: --sky: radiance must be finite and >= 0\n");
                    return LBK_EXIT_USAGE;
                }
                o.sky_set = 1;
                o.sky[0] = r, o.sky[1] = g, o.sky[2] = b;
            } else {
                o.sky_set = 1;
                o.sky_exr = v;
            }
        } else if (!strcmp(a, "--no-glg")) {
            o.no_glg = 1;
        } else if (!strcmp(a, "--octahedral")) {
            o.octahedral_probes = 1;
        } else if (!strcmp(a, "--dls-threshold")) {
            NEED_NUMBER(0, 1);
            o.dls_threshold = d > 0 ? d : -1;
        } else if (!strcmp(a, "--door-method")) {
            NEED_VALUE;
            if (!strcmp(v, "difference")) o.door_method = 0;
            else if (!strcmp(v, "guided")) o.door_method = 1;
            else {
                fprintf(stderr, "lbk bake: unknown door method '%s' (difference, guided)\n", v);
                return LBK_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--denoise")) {
            NEED_VALUE;
            if (!strcmp(v, "auto")) o.denoise = 0;
            else if (!strcmp(v, "off")) o.denoise = -1;
            else {
                fprintf(stderr, "lbk bake: unknown denoise mode '%s' (auto, off)\n", v);
                return LBK_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--threads")) {
            NEED_NUMBER(1, 1024);
            o.threads = (int)d;
        } else if (!strcmp(a, "--seed")) {
            NEED_VALUE;
            char *end;
            errno = 0;
            unsigned long long s = strtoull(v, &end, 0);
            if (errno || end == v || *end) {
                fprintf(stderr, "lbk bake: --seed: '%s' is not an unsigned integer\n", v);
                return LBK_EXIT_USAGE;
            }
            o.seed = s;
        } else if (!strcmp(a, "--json-report")) {
            NEED_VALUE;
            o.json_report = v;
        } else if (!strcmp(a, "--revision")) {
            NEED_VALUE;
            o.revision = v;
        } else if (!strcmp(a, "--timestamp")) {
            o.timestamp = 1;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            quiet = 1;
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk bake: unknown option '%s' (lbk bake --help)\n", a);
            return LBK_EXIT_USAGE;
        } else if (!o.input) {
            o.input = a;
        } else {
            fprintf(stderr, "lbk bake: more than one input scene ('%s', '%s')\n", o.input, a);
            return LBK_EXIT_USAGE;
        }
#undef NEED_VALUE
#undef NEED_NUMBER
    }
    if (!o.input || !o.output) {
        fprintf(stderr, "lbk bake: need a scene and -o OUT.lbk (lbk bake --help)\n");
        return LBK_EXIT_USAGE;
    }
    bk_progress progress;
    bk_progress_init(&progress, quiet);
    bk_bake_summary sum;
    char err[512] = "";
    int rc = bk_bake(&o, &progress, &sum, err, sizeof err);
    if (rc) {
        fprintf(stderr, "lbk bake: %s\n", err[0] ? err : "failed");
        return rc;
    }
    bk_progress_done(&progress);
    if (!quiet)
        printf("%s: %llu objects, %llu texels in %llu pages, %llu GLG probes, %llu LLG probes in %llu grids, "
               "%u dynamic sets (light sets and door states), %u doors; estimated error %.2f%%; %llu bytes\n",
               o.output, (unsigned long long)sum.objects, (unsigned long long)sum.texels,
               (unsigned long long)sum.pages, (unsigned long long)sum.glg_probes,
               (unsigned long long)sum.llg_probes, (unsigned long long)sum.llgs, sum.sets, sum.doors,
               100 * sum.final_error, (unsigned long long)sum.file_bytes);
    return LBK_EXIT_OK;
}
