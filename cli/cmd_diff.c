/* lbk diff: compare the lighting of two bakes. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/options.h"
#include <cJSON.h>

#include "tools/common/lmap_decode.h"
#include "tools/common/output_guard.h"
#include "tools/convert/pack_error.h"
#include "tools/inspect/diff.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lbk diff A.lbk B.lbk [--mode noise|tolerance] [--false-alarm P] [--abs-tol X] [--rel-tol Y]\n"
            "                [--json] [--heatmap DIR] [--max-memory SIZE] [-v]\n"
            "\n"
            "Compares decoded lighting, not bytes. Objects are matched by name and geometry hash (then by\n"
            "name alone, then by hash alone = renamed), never by position in the file; pages by index;\n"
            "GLG probes by index when both grids have the same probe positions, otherwise B is sampled at A's\n"
            "probes; OCTP probes by index when both volumes have the same layout (else \"not comparable\"):\n"
            "irradiance of the 4x4 interior texels, depth moments, probe state changes; LLG probes through\n"
            "their object; light sets and doors by name.\n"
            "Two verdicts (spec/diff-json.md):\n"
            "  noise mode (the default when both bakes carry REPT): an object, the GLG, OCTP or a light set differs\n"
            "    when its change exceeds the Monte Carlo noise of the two bakes: its luminance mean shift or\n"
            "    its chromaticity (per channel, at equal luminance) beyond k x their noise (REPT's estimate,\n"
            "    the object's own texel noise, per receiver class), or more samples changing beyond their\n"
            "    noise than a binomial count allows. A reseed is equal.\n"
            "  tolerance mode (--abs-tol/--rel-tol, or --mode tolerance; exact with 0): a texel's (probe's)\n"
            "    error is the largest |B - A| of the decoded irradiance over R, G, B and over 5 tangent-space\n"
            "    normals (+Z and 45 degrees toward +-X, +-Y) (6 axis normals for probes); it is over\n"
            "    tolerance when error > abs-tol + rel-tol * max|A| over the same values.\n"
            "What changed in the inputs and options (META provenance: options, files, lights, materials,\n"
            "per-object geometry/material/options) is listed first. When one side is a block-compressed\n"
            "pack of the other (lbk convert, BC6H / ASTC), the lightmap differences are reported as its\n"
            "compression error too (luminance and colour mean / p99 / max, seams; as lbk convert does).\n"
            "Reported per object, page, grid, OCTP volume and light set: max and mean absolute error, relative RMSE,\n"
            "share of samples over tolerance and their bounding region; plus added/removed/changed\n"
            "objects, sections and META bake parameters. Units: irradiance as baked (lux-like, lm/m^2).\n"
            "\n"
            "  --mode M        noise or tolerance (default: noise when both bakes carry REPT)\n"
            "  --false-alarm P noise mode: false-alarm rate per item, 0 < P < 0.5 (default 0.001)\n"
            "  --abs-tol X     absolute tolerance (default 0); implies tolerance mode unless --mode noise\n"
            "  --rel-tol Y     relative tolerance (default 0); implies tolerance mode unless --mode noise\n"
            "  --json          JSON on stdout (schema spec/diff-json.md, schema_version %d)\n"
            "  --heatmap DIR   DIR/page_NNN.diff.png per page: black = within tolerance, blue..white = error\n"
            "                  over tolerance relative to the page's largest, grey = not compared\n"
            "  -v, --verbose   list unchanged items too\n"
            CLI_MAX_MEMORY_HELP
            "  -h, --help      this text\n"
            "\n"
            "exit codes: 0 equal (within noise / tolerance), 1 the bakes differ (lighting, objects, pages, probes,\n"
            "            light sets, doors or lighting sections; META/REPT differences alone do not count),\n"
            "            2 usage, 3 I/O error, 4 an input is not a valid container, 5 internal error\n",
            TL_DIFF_SCHEMA_VERSION);
}

/* The plane formats of a bake's first block-encoded page; 0 when every page has 1.0 planes. */
static int block_formats(const tl_bake *b, uint32_t f[2])
{
    for (uint32_t p = 0; b->has_lmap && p < b->lmap.page_count; p++) {
        lbk_lmap_planes pl;
        if (lbk_lmap_planes_get(&b->lmap, p, &pl) == LBK_OK &&
            (pl.format[0] != LBK_LMAP_R11G11B10F || pl.format[1] != LBK_LMAP_RGBA8)) {
            f[0] = pl.format[0], f[1] = pl.format[1];
            return 1;
        }
    }
    return 0;
}

/* One side a block-compressed pack of the other (lbk convert with a block profile: the same
 * objects and rectangles, block pages against 1.0 ones): its lightmap differences are the
 * compression's error, measured as lbk convert reports it. packed: 0 A, 1 B, -1 neither. */
typedef struct pack_side {
    int packed;
    uint32_t formats[2];
    tl_pack_error error;
} pack_side;

static void find_pack(const tl_bake bake[2], pack_side *ps)
{
    uint32_t f[2][2] = {{0, 0}, {0, 0}};
    const int ba = block_formats(&bake[0], f[0]), bb = block_formats(&bake[1], f[1]);
    char err[TL_ERR_LEN];
    ps->packed = -1;
    if (ba == bb) return;
    const int p = bb ? 1 : 0;
    if (tl_pack_error_compute(&bake[1 - p], &bake[p], &ps->error, err)) return; /* not a pack of it */
    ps->packed = p;
    memcpy(ps->formats, f[p], sizeof ps->formats);
}

static void print_pack(const pack_side *ps)
{
    const tl_pack_error *e = &ps->error;
    printf("compression: %s is a block-compressed pack of %s (%s + %s): its lightmap differences are the encoding's\n"
           "  error: luminance mean %.2f %%, p99 %.2f %%, max %.2f %%; seam texels p99 %.2f %%; chroma mean %.4f, p99 %.4f;\n"
           "  goal mean <= %g %%, p99 <= %g %%: %s (lbk convert reports the same)\n",
           ps->packed ? "B" : "A", ps->packed ? "A" : "B", tl_lmap_format_name(0, ps->formats[0]),
           tl_lmap_format_name(1, ps->formats[1]), 100 * e->all.lum.mean, 100 * e->all.lum.p99, 100 * e->all.lum.max,
           100 * e->seam.lum.p99, e->all.colour.mean, e->all.colour.p99, 100 * TL_PACK_GOAL_MEAN, 100 * TL_PACK_GOAL_P99,
           tl_pack_error_meets(&e->all.lum, TL_PACK_GOAL_MEAN, TL_PACK_GOAL_P99) ? "met" : "NOT met");
}

static cJSON *stats_json(const tl_pack_stats *s)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "mean", s->mean);
    cJSON_AddNumberToObject(j, "p99", s->p99);
    cJSON_AddNumberToObject(j, "max", s->max);
    return j;
}

/* diff's JSON with "compression" added (spec/diff-json.md); NULL when out of memory. */
static char *json_with_pack(const char *text, const pack_side *ps)
{
    cJSON *j = cJSON_Parse(text);
    if (!j) return NULL;
    if (ps->packed < 0) {
        cJSON_AddNullToObject(j, "compression");
    } else {
        const tl_pack_error *e = &ps->error;
        cJSON *c = cJSON_AddObjectToObject(j, "compression");
        cJSON_AddStringToObject(c, "pack", ps->packed ? "b" : "a");
        cJSON_AddStringToObject(c, "plane0", tl_lmap_format_name(0, ps->formats[0]));
        cJSON_AddStringToObject(c, "plane1", tl_lmap_format_name(1, ps->formats[1]));
        cJSON_AddNumberToObject(c, "texels", (double)e->texels);
        cJSON_AddItemToObject(c, "luminance", stats_json(&e->all.lum));
        cJSON_AddItemToObject(c, "colour", stats_json(&e->all.colour));
        cJSON_AddItemToObject(c, "seam_luminance", stats_json(&e->seam.lum));
        cJSON_AddBoolToObject(c, "goal_met", tl_pack_error_meets(&e->all.lum, TL_PACK_GOAL_MEAN, TL_PACK_GOAL_P99));
    }
    char *out = cJSON_Print(j); /* formatted, as tl_diff_json's */
    cJSON_Delete(j);
    return out;
}

static int parse_tol(const char *flag, const char *v, double *out)
{
    char *end;
    errno = 0;
    double x = strtod(v, &end);
    if (errno || end == v || *end || !isfinite(x) || x < 0) {
        fprintf(stderr, "lbk diff: %s needs a finite number >= 0, got '%s'\n", flag, v);
        return -1;
    }
    *out = x;
    return 0;
}

static int diff_main(int argc, char **argv, tl_guard *guard)
{
    const char *path[2] = {NULL, NULL}, *heat = NULL;
    int json = 0, verbose = 0, npath = 0;
    tl_diff_options o = {0};
    o.mode = TL_DIFF_MODE_AUTO;
    int mode_given = 0, tol_given = 0;
    uint64_t max_memory = 0;
    for (int i = 1; i < argc; i++) {
        const int mm = cli_max_memory_option("diff", argc, argv, &i, &max_memory);
        if (mm < 0) return LBK_EXIT_USAGE;
        if (mm) continue;
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return LBK_EXIT_OK;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "-v") || !strcmp(a, "--verbose")) {
            verbose = 1;
        } else if (!strcmp(a, "--abs-tol") || !strcmp(a, "--rel-tol") || !strcmp(a, "--heatmap") ||
                   !strcmp(a, "--mode") || !strcmp(a, "--false-alarm")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "lbk diff: %s needs a value\n", a);
                return LBK_EXIT_USAGE;
            }
            const char *v = argv[++i];
            if (!strcmp(a, "--heatmap")) {
                heat = v;
            } else if (!strcmp(a, "--mode")) {
                if (!strcmp(v, "noise")) o.mode = TL_DIFF_MODE_NOISE;
                else if (!strcmp(v, "tolerance")) o.mode = TL_DIFF_MODE_TOLERANCE;
                else {
                    fprintf(stderr, "lbk diff: --mode is noise or tolerance, got '%s'\n", v);
                    return LBK_EXIT_USAGE;
                }
                mode_given = 1;
            } else if (!strcmp(a, "--false-alarm")) {
                if (parse_tol(a, v, &o.false_alarm)) return LBK_EXIT_USAGE;
                if (!(o.false_alarm > 0 && o.false_alarm < 0.5)) {
                    fprintf(stderr, "lbk diff: --false-alarm needs 0 < P < 0.5, got '%s'\n", v);
                    return LBK_EXIT_USAGE;
                }
            } else {
                if (parse_tol(a, v, !strcmp(a, "--abs-tol") ? &o.abs_tol : &o.rel_tol)) return LBK_EXIT_USAGE;
                tol_given = 1;
            }
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk diff: unknown option '%s' (see lbk diff --help)\n", a);
            return LBK_EXIT_USAGE;
        } else if (npath < 2) {
            path[npath++] = a;
        } else {
            fprintf(stderr, "lbk diff: more than two inputs\n");
            return LBK_EXIT_USAGE;
        }
    }
    if (npath != 2) {
        fprintf(stderr, "lbk diff: need two containers A.lbk B.lbk (see lbk diff --help)\n");
        return LBK_EXIT_USAGE;
    }
    if (tol_given && !mode_given) o.mode = TL_DIFF_MODE_TOLERANCE;
    o.keep_error_maps = heat != NULL;
    char err[TL_ERR_LEN];
    /* the heatmaps may replace neither container nor a device (output_guard.h) */
    if (tl_guard_input(guard, path[0], "the container") || tl_guard_input(guard, path[1], "the container"))
        return LBK_EXIT_INTERNAL;
    if (heat && tl_guard_output_dir(guard, heat, NULL, "--heatmap", err)) {
        fprintf(stderr, "lbk diff: %s\n", err);
        return LBK_EXIT_USAGE;
    }
    tl_guard_activate(guard);
    tl_bake bake[2];
    for (int k = 0; k < 2; k++) {
        tl_open_status st = tl_bake_open_file_capped(path[k], max_memory, &bake[k], err);
        if (st != TL_OPEN_OK) {
            fprintf(stderr, "lbk diff: %s\n", err);
            if (k) tl_bake_close(&bake[0]);
            return st == TL_OPEN_IO ? LBK_EXIT_IO : st == TL_OPEN_INVALID ? LBK_EXIT_INPUT : LBK_EXIT_INTERNAL;
        }
    }
    tl_diff_result r;
    int rc = tl_diff_run(&bake[0], &bake[1], &o, &r, err);
    pack_side ps;
    memset(&ps, 0, sizeof ps);
    if (!rc) find_pack(bake, &ps);
    tl_bake_close(&bake[0]);
    tl_bake_close(&bake[1]);
    if (rc) {
        fprintf(stderr, "lbk diff: %s\n", err);
        return LBK_EXIT_INTERNAL;
    }
    int exit_code = r.differ ? LBK_EXIT_NEGATIVE : LBK_EXIT_OK;
    if (json) {
        char *diff_text = tl_diff_json(&r, path[0], path[1]);
        char *text = diff_text ? json_with_pack(diff_text, &ps) : NULL;
        free(diff_text);
        if (!text) {
            fprintf(stderr, "lbk diff: out of memory\n");
            exit_code = LBK_EXIT_INTERNAL;
        } else {
            printf("%s\n", text);
            cJSON_free(text);
        }
    } else {
        tl_diff_print(stdout, &r, verbose);
        if (ps.packed >= 0) print_pack(&ps);
    }
    if (ps.packed >= 0) tl_pack_error_free(&ps.error);
    if (heat && tl_diff_heatmaps(&r, heat, err)) {
        fprintf(stderr, "lbk diff: %s\n", err);
        exit_code = LBK_EXIT_IO;
    }
    tl_diff_free(&r);
    return exit_code;
}

int lbk_cmd_diff(int argc, char **argv) { return cli_run_guarded("diff", diff_main, argc, argv); }
