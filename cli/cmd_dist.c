/* lbk plan, lbk bake-unit, lbk merge: a distributed bake (bake/dist/DIST.md) over
 * lbk/bake_dist.h. The plan names the scene and the bake options; every unit and the merge
 * re-read them from it, so they bake with exactly the options of the plan. */
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/bake_options.h"
#include "cli/cli.h"
#include "cli/options.h"
#include "tools/common/output_guard.h"
#include "lbk/bake_dist.h"
#include "tools/common/bake_plan.h"
#include "tools/common/file_util.h"

static int abs_path(const char *path, char *out, size_t size)
{
    if (path[0] == '/') return snprintf(out, size, "%s", path) < (int)size;
    char cwd[PATH_MAX];
    if (!getcwd(cwd, sizeof cwd)) return 0;
    return snprintf(out, size, "%s/%s", cwd, path) < (int)size;
}

/* Makefile lines must not hold spaces or make's specials in paths. */
static int make_safe(const char *s)
{
    for (; *s; s++)
        if (*s == ' ' || *s == '$' || *s == '#' || *s == ':' || *s == '%' || *s == '\\' || *s == '\'' || *s == '"') return 0;
    return 1;
}

static int write_makefile(const char *path, const char *lbk, const char *plan, const char *output, unsigned units,
                          char err[TL_ERR_LEN])
{
    size_t cap = 4096 + (size_t)units * (strlen(output) + 48);
    char *t = malloc(cap);
    if (!t) return snprintf(err, TL_ERR_LEN, "out of memory"), -1;
    size_t n = (size_t)snprintf(t, cap,
                                "# A distributed bake, written by lbk plan: make -j N -f THIS bakes the units in parallel\n"
                                "# and merges them. A killed unit leaves no part: running make again bakes only the\n"
                                "# missing ones. LBK= picks the lbk binary, UNIT_FLAGS= adds e.g. --threads 1.\n"
                                "LBK ?= %s\nPLAN := %s\nOUT := %s\nUNIT_FLAGS ?= -q\nPARTS :=",
                                lbk, plan, output);
    for (unsigned k = 0; k < units; k++) n += (size_t)snprintf(t + n, cap - n, " $(OUT).parts/part-%u.lbkpart", k);
    snprintf(t + n, cap - n,
             "\n\n$(OUT): $(PARTS)\n\t$(LBK) merge $(PLAN) $(PARTS) -o $@ -q\n\n"
             "$(OUT).parts/part-%%.lbkpart:\n\t@mkdir -p $(@D)\n\t$(LBK) bake-unit $(PLAN) $* -o $@ $(UNIT_FLAGS)\n\n"
             ".PHONY: all\nall: $(OUT)\n.DEFAULT_GOAL := $(OUT)\n");
    int r = tl_write_text(path, t, err);
    free(t);
    return r;
}

static int write_sbatch(const char *path, const char *lbk, const char *plan, const char *output, unsigned units,
                        char err[TL_ERR_LEN])
{
    size_t cap = 2048 + 3 * (strlen(lbk) + strlen(plan) + 4 * strlen(output));
    char *t = malloc(cap);
    if (!t) return snprintf(err, TL_ERR_LEN, "out of memory"), -1;
    snprintf(t, cap,
             "#!/bin/sh\n"
             "# A distributed bake on Slurm, written by lbk plan: `sh THIS` submits a job array of %u\n"
             "# units and a merge that runs when all of them succeeded (afterok). SBATCH_FLAGS adds\n"
             "# sbatch options (partition, account, time); LBK picks the lbk binary, UNIT_FLAGS the\n"
             "# units' options (default -q).\n"
             "set -e\n"
             "LBK=${LBK:-%s}\nPLAN=%s\nOUT=%s\nUNIT_FLAGS=${UNIT_FLAGS:--q}\n"
             "mkdir -p \"$OUT.parts\"\n"
             "unit=$(sbatch --parsable $SBATCH_FLAGS --job-name=lbk-unit --array=0-%u --output=\"$OUT.parts/unit-%%a.log\" \\\n"
             "  --wrap=\"$LBK bake-unit $PLAN \\$SLURM_ARRAY_TASK_ID -o $OUT.parts/part-\\$SLURM_ARRAY_TASK_ID.lbkpart $UNIT_FLAGS\")\n"
             "unit=${unit%%%%;*}\n"
             "merge=$(sbatch --parsable $SBATCH_FLAGS --job-name=lbk-merge --dependency=afterok:$unit \\\n"
             "  --output=\"$OUT.parts/merge.log\" --wrap=\"$LBK merge $PLAN $OUT.parts/part-*.lbkpart -o $OUT -q\")\n"
             "merge=${merge%%%%;*}\n"
             "echo \"lbk: units job $unit, merge job $merge\"\n",
             units, lbk, plan, output, units - 1);
    int r = tl_write_text(path, t, err);
    free(t);
    return r;
}

static void error_message(void *user, lbk_bake_severity severity, const char *message)
{
    if (severity == LBK_BAKE_SEVERITY_ERROR) fprintf(stderr, "lbk %s: %s\n", (const char *)user, message);
}

/* Every file the bake reads (the glTF, its buffers and images, a sky EXR), with its hash: units
 * and the merge refuse a changed one. -1 when done, else the exit code. */
static int plan_inputs(const char *cmd, const char *scene, const lbk_bake_desc *desc, tl_plan *p, uint32_t *runs)
{
    lbk_bake_desc d = *desc;
    d.message = error_message;
    d.user = (void *)cmd;
    d.progress = NULL;
    lbk_bake_input *in = NULL;
    size_t n = 0;
    lbk_result r = lbk_bake_inputs_from_file(scene, &d, &in, &n, runs);
    if (r) {
        if (r != LBK_ERR_BAD_INPUT && r != LBK_ERR_INVALID_ARGUMENT && r != LBK_ERR_IO)
            fprintf(stderr, "lbk %s: %s\n", cmd, lbk_result_message(r));
        return r == LBK_ERR_IO ? LBK_EXIT_IO : r == LBK_ERR_INVALID_ARGUMENT ? LBK_EXIT_USAGE : LBK_EXIT_INPUT;
    }
    if (n > TL_PLAN_MAX_INPUTS || !(p->inputs = calloc(n ? n : 1, sizeof *p->inputs))) {
        lbk_bake_inputs_free(in);
        fprintf(stderr, "lbk %s: %s\n", cmd, n > TL_PLAN_MAX_INPUTS ? "too many input files for a plan" : "out of memory");
        return LBK_EXIT_INTERNAL;
    }
    for (size_t i = 0; i < n; i++) {
        memcpy(p->inputs[i].path, in[i].path, sizeof p->inputs[i].path);
        memcpy(p->inputs[i].role, in[i].role, sizeof p->inputs[i].role);
        p->inputs[i].bytes = in[i].bytes;
        p->inputs[i].xxh3 = in[i].xxh3;
    }
    p->input_count = n;
    lbk_bake_inputs_free(in);
    return -1;
}

/* The units' shared cache folder: the one given, else the plan's default beside its output,
 * named by its hash. */
static void cache_dir_of(const char *given, const char *output, uint64_t plan_hash, char *out, size_t size)
{
    if (given) snprintf(out, size, "%s", given);
    else snprintf(out, size, "%s.cache-%016" PRIx64, output, plan_hash);
}

int cli_plan_write(const bake_args *o, int argc, char **argv, const char *cmd)
{
    if (!o->input || !o->output || !o->plan || !o->units) {
        fprintf(stderr, "lbk %s: a plan needs a scene, -o OUT.lbk, --plan PLAN.json and --units N (lbk plan --help)\n", cmd);
        return LBK_EXIT_USAGE;
    }
    if (o->d.time_limit > 0) {
        fprintf(stderr, "lbk %s: --time-limit cannot be distributed: the passes it allows depend on each machine's speed, so "
                        "the units would not bake the same passes\n", cmd);
        return LBK_EXIT_USAGE;
    }
    tl_plan p;
    memset(&p, 0, sizeof p);
    char scene[PATH_MAX], output[PATH_MAX], plan[PATH_MAX], err[TL_ERR_LEN];
    if (!realpath(o->input, scene)) {
        fprintf(stderr, "lbk %s: %s: %s\n", cmd, o->input, strerror(errno));
        return LBK_EXIT_IO;
    }
    if (!abs_path(o->output, output, sizeof output) || !abs_path(o->plan, plan, sizeof plan)) {
        fprintf(stderr, "lbk %s: path too long\n", cmd);
        return LBK_EXIT_USAGE;
    }
    p.scene = scene;
    p.output = output;
    p.units = o->units;
    if (tl_file_hash(scene, &p.scene_hash, err)) {
        fprintf(stderr, "lbk %s: %s\n", cmd, err);
        return LBK_EXIT_IO;
    }
    const char *plan_in[] = {"the sky", o->d.sky_exr, NULL, NULL};
    const char *plan_out[] = {"--plan", o->plan, "--makefile", o->makefile, "--sbatch", o->sbatch, "-o", o->output, NULL, NULL};
    int rc = cli_check_scene_outputs(cmd, scene, o->d.allow_outside, plan_in, plan_out);
    if (rc) return rc;
    uint32_t runs = 0;
    rc = plan_inputs(cmd, scene, &o->d, &p, &runs);
    if (rc >= 0) return rc;
    int seen_input = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int takes_value = a[0] == '-' && a[1] && !cli_bake_flag(a);
        if (a[0] != '-' || !a[1]) {
            if (!seen_input++) continue; /* the scene */
        }
        if (!cli_bake_plan_neutral(a)) {
            if (p.option_count + 2 > TL_PLAN_MAX_OPTIONS) {
                fprintf(stderr, "lbk %s: too many options for a plan\n", cmd);
                return LBK_EXIT_USAGE;
            }
            p.options[p.option_count++] = argv[i];
            if (takes_value && i + 1 < argc) p.options[p.option_count++] = argv[i + 1];
        }
        if (takes_value) i++;
    }
    char lbk[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", lbk, sizeof lbk - 1);
    snprintf(lbk + (n > 0 ? n : 0), sizeof lbk - (size_t)(n > 0 ? n : 0), "%s", n > 0 ? "" : "lbk");
    if ((o->makefile || o->sbatch) && (!make_safe(plan) || !make_safe(output) || !make_safe(lbk))) {
        fprintf(stderr, "lbk %s: the plan, output and lbk paths must not hold spaces or $#:%%\\'\" for a Makefile or sbatch script\n", cmd);
        return LBK_EXIT_USAGE;
    }
    if (tl_plan_write(&p, plan, err) || (o->makefile && write_makefile(o->makefile, lbk, plan, output, o->units, err)) ||
        (o->sbatch && write_sbatch(o->sbatch, lbk, plan, output, o->units, err))) {
        fprintf(stderr, "lbk %s: %s\n", cmd, err);
        free(p.inputs);
        return LBK_EXIT_IO;
    }
    printf("%s: %u units, %zu input files, plan hash %016" PRIx64 "\n", o->plan, o->units, p.input_count, tl_plan_hash(&p));
    if (o->units > runs) {
        char dir[PATH_MAX + 32];
        cache_dir_of(NULL, output, tl_plan_hash(&p), dir, sizeof dir);
        printf("  %u transport run%s for %u units: units sharing a run share its caches in %s (a folder every unit "
               "must see; bake-unit --cache-dir)\n", runs, runs == 1 ? "" : "s", o->units, dir);
    }
    free(p.inputs);
    return LBK_EXIT_OK;
}

static void plan_help(FILE *f)
{
    fputs("usage: lbk plan SCENE.gltf -o OUT.lbk --plan PLAN.json --units N [--samples S --target-error none]\n"
          "                [--makefile FILE] [--sbatch FILE] [bake options]\n"
          "\n"
          "Writes the plan of a distributed bake: the scene, its hash and the bake options, cut into N\n"
          "units. Run every unit (lbk bake-unit PLAN K, anywhere the scene files are), then lbk merge:\n"
          "the container is byte-identical to `lbk bake` with the same options. --makefile writes a\n"
          "Makefile for make -j; --sbatch a script that submits a Slurm job array and the merge.\n"
          "Any N, with the default error target or a fixed schedule (--samples N --target-error none),\n"
          "either door method and --octahedral. No --time-limit (the passes it allows depend on each\n"
          "machine's speed). Units sharing a transport run (more units than runs) share its radiosity\n"
          "caches through a folder beside the output (lbk bake-unit --help): a level without light\n"
          "sets is divided too.\n"
          "See bake/dist/DIST.md (xargs -P, Kubernetes).\n",
          f);
}

int lbk_cmd_plan(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return plan_help(stdout), LBK_EXIT_OK;
    bake_args o;
    int quiet = 0;
    int rc = cli_bake_parse(argc, argv, &o, &quiet);
    if (rc >= 0) return rc;
    return cli_plan_write(&o, argc, argv, "plan");
}

/* The plan, its scene checked against the hash, and the bake options it holds (+ extra). */
static int load_plan(const char *cmd, const char *path, const char *scene_override, tl_plan *p, bake_args *o, int *quiet,
                     int extra_count, char **extra)
{
    char err[TL_ERR_LEN];
    if (tl_plan_read(path, p, err)) {
        fprintf(stderr, "lbk %s: %s\n", cmd, err);
        return LBK_EXIT_INPUT;
    }
    const char *scene = scene_override ? scene_override : p->scene;
    uint64_t h = 0;
    if (tl_file_hash(scene, &h, err)) {
        fprintf(stderr, "lbk %s: %s\n", cmd, err);
        return LBK_EXIT_IO;
    }
    if (h != p->scene_hash) {
        fprintf(stderr, "lbk %s: %s changed since the plan was made (hash %016" PRIx64 ", the plan's %016" PRIx64
                        "): make a new plan\n", cmd, scene, h, p->scene_hash);
        return LBK_EXIT_INPUT;
    }
    char *args[2 + TL_PLAN_MAX_OPTIONS + 8];
    int n = 0;
    args[n++] = (char *)cmd;
    args[n++] = (char *)scene;
    for (int i = 0; i < p->option_count; i++) args[n++] = p->options[i];
    for (int i = 0; i < extra_count && n < (int)(sizeof args / sizeof args[0]); i++) args[n++] = extra[i];
    int rc = cli_bake_parse(n, args, o, quiet);
    if (rc >= 0) return rc == 0 ? LBK_EXIT_INPUT : rc;
    o->cmd = cmd;
    /* the bake compares what its import reads with the plan's files (lbk_bake_desc.expect_inputs) */
    lbk_bake_input *want = calloc(p->input_count ? p->input_count : 1, sizeof *want);
    if (!want) {
        fprintf(stderr, "lbk %s: out of memory\n", cmd);
        return LBK_EXIT_INTERNAL;
    }
    for (size_t i = 0; i < p->input_count; i++) {
        memcpy(want[i].path, p->inputs[i].path, sizeof want[i].path);
        memcpy(want[i].role, p->inputs[i].role, sizeof want[i].role);
        want[i].bytes = p->inputs[i].bytes;
        want[i].xxh3 = p->inputs[i].xxh3;
    }
    o->d.expect_inputs = want;
    o->d.expect_input_count = p->input_count;
    return -1;
}

static void unit_message(void *user, lbk_bake_severity severity, const char *message)
{
    const int quiet = *(const int *)user;
    if (severity == LBK_BAKE_SEVERITY_ERROR) fprintf(stderr, "lbk bake-unit: %s\n", message);
    else if (severity == LBK_BAKE_SEVERITY_WARNING) fprintf(stderr, "lbk bake-unit: warning: %s\n", message);
    else if (!quiet) fprintf(stderr, "  %s\n", message);
}

static void unit_help(FILE *f)
{
    fputs("usage: lbk bake-unit PLAN.json K -o PART.lbkpart [--threads N] [--scene PATH]\n"
          "                     [--cache-dir DIR | --no-shared-cache] [--cache-lease SECONDS] [-q]\n"
          "\n"
          "Bakes unit K (0-based) of a plan (lbk plan) into a part file, written atomically: a killed\n"
          "unit leaves none. --scene: where the plan's scene is on this machine (its hash is checked).\n"
          "\n"
          "Units that share a transport run (more units than runs: a level without light sets) share\n"
          "its radiosity caches: each bounce is cut into shares, a unit computes the shares nobody\n"
          "has claimed, publishes them in the cache folder and reads the others' (bake/dist/DIST.md\n"
          "§Shared caches). The folder must be one every unit sees; default: the plan's output\n"
          "followed by .cache-PLANHASH (when it cannot be made, the unit computes its caches whole).\n"
          "lbk merge removes it. The part's bytes are the same with or without sharing.\n"
          "--cache-lease: seconds a claimed share may stay unpublished before another unit computes\n"
          "it too (default 600; a claim of a process gone from this host is taken at once).\n",
          f);
}

static void print_share_stats(unsigned long k, const lbk_bake_unit_stats *st)
{
    if (!st->shares_computed && !st->shares_read) return;
    printf("unit %lu: cache shares computed %" PRIu64 " (%.2f s), read %" PRIu64 " (%.1f MB, %.2f s), waited %.2f s, "
           "published %.2f s\n", k, st->shares_computed, st->compute_seconds, st->shares_read, (double)st->bytes_read / 1e6,
           st->read_seconds, st->wait_seconds, st->publish_seconds);
}

int lbk_cmd_bake_unit(int argc, char **argv)
{
    const char *plan = NULL, *kstr = NULL, *out = NULL, *scene = NULL, *cache_dir = NULL, *lease_str = NULL;
    char *extra[4];
    int n_extra = 0, quiet = 0, no_share = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) return unit_help(stdout), LBK_EXIT_OK;
        if ((!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--threads") || !strcmp(a, "--scene") ||
             !strcmp(a, "--cache-dir") || !strcmp(a, "--cache-lease")) && i + 1 >= argc) {
            fprintf(stderr, "lbk bake-unit: %s needs a value\n", a);
            return LBK_EXIT_USAGE;
        }
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) out = argv[++i];
        else if (!strcmp(a, "--scene")) scene = argv[++i];
        else if (!strcmp(a, "--cache-dir")) cache_dir = argv[++i];
        else if (!strcmp(a, "--cache-lease")) lease_str = argv[++i];
        else if (!strcmp(a, "--no-shared-cache")) no_share = 1;
        else if (!strcmp(a, "--threads")) extra[n_extra++] = argv[i], extra[n_extra++] = argv[++i];
        else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) quiet = 1;
        else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk bake-unit: unknown option '%s' (lbk bake-unit --help)\n", a);
            return LBK_EXIT_USAGE;
        } else if (!plan) plan = a;
        else if (!kstr) kstr = a;
        else {
            fprintf(stderr, "lbk bake-unit: unexpected argument '%s'\n", a);
            return LBK_EXIT_USAGE;
        }
    }
    if (!plan || !kstr || !out) {
        fprintf(stderr, "lbk bake-unit: need PLAN.json K -o PART.lbkpart (lbk bake-unit --help)\n");
        return LBK_EXIT_USAGE;
    }
    char *end;
    errno = 0;
    unsigned long k = strtoul(kstr, &end, 10);
    if (errno || *end || kstr[0] < '0' || kstr[0] > '9') {
        fprintf(stderr, "lbk bake-unit: K: '%s' is not a unit number\n", kstr);
        return LBK_EXIT_USAGE;
    }
    double lease = 0;
    if (lease_str) {
        lease = strtod(lease_str, &end);
        if (*end || !(lease > 0) || lease > 1e7) {
            fprintf(stderr, "lbk bake-unit: --cache-lease: '%s' is not a number of seconds > 0\n", lease_str);
            return LBK_EXIT_USAGE;
        }
    }
    if (no_share && (cache_dir || lease_str)) {
        fprintf(stderr, "lbk bake-unit: --no-shared-cache with --cache-dir or --cache-lease\n");
        return LBK_EXIT_USAGE;
    }
    tl_plan p;
    bake_args o;
    int dummy = 0;
    int rc = load_plan("bake-unit", plan, scene, &p, &o, &dummy, n_extra, extra);
    if (rc >= 0) return rc;
    if (k >= p.units) {
        fprintf(stderr, "lbk bake-unit: unit %lu: the plan has units 0 to %u\n", k, p.units - 1);
        tl_plan_free(&p);
        free((void *)o.d.expect_inputs);
        return LBK_EXIT_USAGE;
    }
    const char *unit_in[] = {"the plan", plan, "the sky", o.d.sky_exr, NULL, NULL};
    const char *unit_out[] = {"-o", out, NULL, NULL};
    if ((rc = cli_check_scene_outputs("bake-unit", o.input, o.d.allow_outside, unit_in, unit_out))) {
        tl_plan_free(&p);
        free((void *)o.d.expect_inputs);
        return rc;
    }
    o.d.message = unit_message;
    o.d.user = &quiet;
    char dir[PATH_MAX + 32];
    lbk_bake_unit_desc sd = {sizeof sd, NULL, lease};
    if (!no_share) {
        cache_dir_of(cache_dir, p.output, p.hash, dir, sizeof dir);
        /* the default folder is a convenience: where it cannot be made the unit computes whole */
        if (cache_dir || mkdir(dir, 0777) == 0 || errno == EEXIST) sd.cache_dir = dir;
        else if (!quiet) fprintf(stderr, "lbk bake-unit: note: no shared cache (%s: %s): this unit computes its caches whole\n",
                                 dir, strerror(errno));
    }
    lbk_bake_unit_stats st;
    memset(&st, 0, sizeof st);
    st.size = sizeof st;
    void *part = NULL;
    size_t size = 0;
    lbk_result r = lbk_bake_unit_shared(o.input, &o.d, p.hash, p.units, (uint32_t)k, &sd, &st, &part, &size);
    tl_plan_free(&p);
    free((void *)o.d.expect_inputs);
    if (r) {
        if (r != LBK_ERR_BAD_INPUT && r != LBK_ERR_INVALID_ARGUMENT) fprintf(stderr, "lbk bake-unit: %s\n", lbk_result_message(r));
        return r == LBK_ERR_IO ? LBK_EXIT_IO : r == LBK_ERR_BAD_INPUT ? LBK_EXIT_INPUT : r == LBK_ERR_INVALID_ARGUMENT ? LBK_EXIT_USAGE : LBK_EXIT_INTERNAL;
    }
    char err[TL_ERR_LEN];
    int w = tl_write_file_atomic(out, part, size, err);
    lbk_bake_part_free(part);
    if (w) {
        fprintf(stderr, "lbk bake-unit: %s\n", err);
        return LBK_EXIT_IO;
    }
    if (!quiet) printf("%s: unit %lu, %zu bytes\n", out, k, size), print_share_stats(k, &st);
    return LBK_EXIT_OK;
}

static void merge_help(FILE *f)
{
    fputs("usage: lbk merge PLAN.json PART.lbkpart... [-o OUT.lbk] [--threads N] [--json-report FILE]\n"
          "                 [--scene PATH] [--cache-dir DIR] [--keep-cache] [-q]\n"
          "\n"
          "Checks that the parts are every unit of the plan, each once, uncorrupted and of this plan, then\n"
          "writes the container (default: the plan's output) atomically, byte-identical to `lbk bake`.\n"
          "Any bad part: a message and nothing written. Then removes the units' shared cache folder\n"
          "(--cache-dir DIR if they were given one; --keep-cache keeps it).\n",
          f);
}

int lbk_cmd_merge(int argc, char **argv)
{
    const char *plan = NULL, *out = NULL, *scene = NULL, *cache_dir = NULL;
    char *extra[8];
    int n_extra = 0, quiet = 0, keep_cache = 0;
    const char **files = calloc((size_t)argc, sizeof *files);
    size_t n_files = 0;
    if (!files) return LBK_EXIT_INTERNAL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) return free(files), merge_help(stdout), LBK_EXIT_OK;
        int valued = !strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--threads") || !strcmp(a, "--scene") ||
                     !strcmp(a, "--json-report") || !strcmp(a, "--cache-dir");
        if (valued && i + 1 >= argc) {
            fprintf(stderr, "lbk merge: %s needs a value\n", a);
            free(files);
            return LBK_EXIT_USAGE;
        }
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) out = argv[++i];
        else if (!strcmp(a, "--scene")) scene = argv[++i];
        else if (!strcmp(a, "--cache-dir")) cache_dir = argv[++i];
        else if (!strcmp(a, "--keep-cache")) keep_cache = 1;
        else if (valued) extra[n_extra++] = argv[i], extra[n_extra++] = argv[++i];
        else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) quiet = 1;
        else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk merge: unknown option '%s' (lbk merge --help)\n", a);
            free(files);
            return LBK_EXIT_USAGE;
        } else if (!plan) plan = a;
        else files[n_files++] = a;
    }
    if (!plan) {
        fprintf(stderr, "lbk merge: need PLAN.json and the parts (lbk merge --help)\n");
        free(files);
        return LBK_EXIT_USAGE;
    }
    if (quiet) extra[n_extra++] = "-q";
    tl_plan p;
    bake_args o;
    int rc = load_plan("merge", plan, scene, &p, &o, &quiet, n_extra, extra);
    if (rc >= 0) return free(files), rc;
    void **parts = calloc(n_files ? n_files : 1, sizeof *parts);
    size_t *sizes = calloc(n_files ? n_files : 1, sizeof *sizes);
    rc = parts && sizes ? -1 : LBK_EXIT_INTERNAL;
    char err[TL_ERR_LEN];
    for (size_t k = 0; rc < 0 && k < n_files; k++) {
        if (tl_read_file(files[k], &parts[k], &sizes[k], err)) {
            fprintf(stderr, "lbk merge: %s\n", err);
            rc = LBK_EXIT_IO;
            break;
        }
        lbk_bake_part_info info;
        char why[512];
        if (lbk_bake_part_check(parts[k], sizes[k], p.hash, p.units, &info, why, sizeof why)) {
            fprintf(stderr, "lbk merge: %s: %s; nothing written\n", files[k], why);
            rc = LBK_EXIT_INPUT;
        }
    }
    char output[PATH_MAX];
    snprintf(output, sizeof output, "%s", out ? out : p.output);
    if (rc < 0) {
        /* the container and the report may replace no part, the plan, the scene or its files */
        tl_guard g;
        tl_guard_init(&g, "merge");
        int bad = tl_guard_input(&g, plan, "the plan") || tl_guard_input(&g, o.d.sky_exr, "the sky") ||
                  tl_guard_scene(&g, o.input, o.d.allow_outside);
        for (size_t k = 0; !bad && k < n_files; k++) bad = tl_guard_input(&g, files[k], "the part");
        const char *outs[] = {"-o", output, "--json-report", o.json_report, NULL, NULL};
        rc = bad ? LBK_EXIT_INTERNAL : cli_check_outputs("merge", &g, outs);
        tl_guard_free(&g);
        if (!rc) rc = -1;
    }
    if (rc < 0) {
        o.output = output;
        o.merge = 1;
        o.plan_hash = p.hash;
        o.units = p.units;
        o.parts = (const void *const *)parts;
        o.part_sizes = sizes;
        o.part_count = n_files;
        rc = cli_bake_run(&o, quiet);
        char dir[PATH_MAX + 32];
        cache_dir_of(cache_dir, p.output, p.hash, dir, sizeof dir);
        if (rc == LBK_EXIT_OK && !keep_cache && lbk_bake_cache_dir_remove(dir) != LBK_OK)
            fprintf(stderr, "lbk merge: warning: could not remove the shared cache folder %s\n", dir);
    }
    for (size_t k = 0; parts && k < n_files; k++) free(parts[k]);
    free(parts);
    free(sizes);
    free(files);
    tl_plan_free(&p);
    free((void *)o.d.expect_inputs);
    return rc;
}
