/* lbk bake: the command line over liblbkbake (lbk/bake.h): options from flags, the progress
 * bar and messages on stderr, the container and the JSON report written, exit codes. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli/bake_options.h"
#include "cli/cli.h"
#include "cli/options.h"
#include "cli/progress.h"
#include "lbk/bake.h"
#include "lbk/bake_dist.h"
#include "tools/common/file_util.h"

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
          "  --target-error X|none   stop when the estimated relative RMSE drops below X (e.g. 0.02);\n"
          "                          none: run every pass --samples allows (a fixed schedule)\n"
          "  --time-limit S          one budget of S seconds for the whole bake (base, light sets,\n"
          "                          doors: equal shares of what is left), then write what converged\n"
          "  --samples N             sample budget per receiver (overrides the preset)\n"
          "  --max-bounces N         bounce cap before the analytic tail (overrides the preset)\n"
          "  --texel-density D       lightmap texels per metre (overrides the scene's lbk_texel_density)\n"
          "  --glg-spacing M         global light grid spacing in metres\n"
          "  --sky R,G,B | FILE.exr  sky radiance (overrides the scene's lbk_sky)\n"
          "  --no-glg                leave out the global light grid\n"
          "  --glg-lighting          global light grid denser where the lighting varies, coarser where it\n"
          "                          is smooth (a coarse probe pass first; bake/probes/PROBES.md)\n"
          "  --octahedral            also write a GIBS-style octahedral probe volume (OCTP, format 1.3):\n"
          "                          clip levels of 32^3 probes around the playable space (the level's\n"
          "                          centre without lbk_playable), each coarser level doubling the\n"
          "                          spacing, until one holds the whole level (bake/probes/PROBES.md)\n"
          "  --octp-levels N         at most N clip levels, 1-3 (default 3; 1: one level over the whole\n"
          "                          level, its spacing growing until it fits)\n"
          "  --octp-spacing M        the finest level's probe spacing in metres (default the GLG's, or\n"
          "                          the longest extent / 8 when finer)\n"
          "  --octp-clip N           probes per axis of a clip level, 2-32 (default 32)\n"
          "  --gather-limit M        final-gather rays from surfaces end after M metres and read the\n"
          "                          global light grid (baked first) where they hit nothing; off by\n"
          "                          default (bake/transport/TRANSPORT.md, measured)\n"
          "  --llg-connected         LLG props that meet end to end (touching bounding boxes, neither\n"
          "                          inside the other) get twice the probes per axis (seed 001)\n"
          "  --error-map             also write the per-texel error map (TERR, format 1.4): each lightmap\n"
          "                          texel's estimated relative standard error (lbk view's error mode,\n"
          "                          lbk export, lbk inspect); before denoising when denoised\n"
          "  --block-align           charts on 4-texel boundaries, so no 4x4 block of a block-compressed pack\n"
          "                          (lbk convert --profile console-current, handheld) holds two charts\n"
          "  --dls-threshold X       light sets and doors store a texel/probe only where their light\n"
          "                          exceeds X times the mean indirect light of the texels they light\n"
          "                          directly (default 0.01; 0 keeps every lit receiver)\n"
          "  --light-culling auto|on|off\n"
          "                          stochastic light culling of punctual lights (bake/transport/SLC.md;\n"
          "                          auto, the default: on with more than 32 positional lights)\n"
          "  --light-culling-delta X culling's delta relative to the mean punctual irradiance\n"
          "                          (default 0.1; smaller: more lights per texel, less noise)\n"
          "  --glossy-vpl auto|on|off\n"
          "                          glossy-to-diffuse light (caustics of metal floors) through VPLs:\n"
          "                          photons from point and spot lights, culled stochastically and\n"
          "                          gathered at the texels (bake/transport/VPL.md); auto, the default:\n"
          "                          on where the lights put >= 5 % of their flux into glossy surfaces\n"
          "                          of roughness <= 0.3\n"
          "  --glossy-vpl-photons N  photons per light and half in the first pass, doubling per pass\n"
          "                          (default 1024)\n"
          "  --glossy-vpl-delta X    the VPLs' culling delta relative to their mean irradiance at the texels\n"
          "                          (default 0.1; smaller: more VPLs per texel, less noise)\n"
          "  --adaptive on|off       adaptive sampling (default on): blocks of 64 texels or probes whose\n"
          "                          own estimate reached --target-error stop while the rest go on\n"
          "                          (bake/transport/TRANSPORT.md)\n"
          "  --door-method difference|guided\n"
          "                          how the light through an open door is baked: differences of\n"
          "                          full runs (default) or the seed's guided estimator (bake/sets/SETS.md)\n"
          "  --denoise auto|on|off   edge-aware denoising of lightmap texels and GLG probes, guided\n"
          "                          by the transport's own noise estimate; auto (the default, both\n"
          "                          presets) keeps it per class of the base and of each light set or\n"
          "                          door state only where it lowers the estimated error; on: always\n"
          "                          (bake/transport/DENOISE.md)\n"
          "  --threads N             worker threads (default: all cores)\n"
          "  --seed N                random seed (default 1)\n"
          "  --json-report FILE      write the error-against-time report as JSON\n"
          "  --revision STR          revision string stored in the provenance\n"
          "  --timestamp             store the bake time in the provenance (output no longer\n"
          "                          byte-identical across runs)\n"
          "  --allow-outside DIR     the scene may also read buffers/images/sky from DIR (by default\n"
          "                          every file it names must lie in its own folder)\n"
          "  -q, --quiet             no progress output\n"
          "  --checkpoint DIR        after every pass, the bake's state into DIR (atomically)\n"
          "  --resume DIR            continue a killed bake from its last finished pass: the result\n"
          "                          is byte-identical to an uninterrupted bake (same options)\n"
          "  --continue DIR          add passes to a finished bake's checkpoints, up to a lower\n"
          "                          --target-error or a larger --samples (bake/dist/DIST.md)\n"
          "  --plan PLAN.json --units N [--makefile FILE] [--sbatch FILE]\n"
          "                          bake nothing: write the plan of a distributed bake in N units\n"
          "                          (same as lbk plan; needs --samples N --target-error none)\n"
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

/* True when both paths name one existing file (the same inode: hard links count). */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return a && b && stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}


/* What the callbacks share: the bar, and the error text the CLI prints after the bake. */
typedef struct bake_ui {
    cli_progress bar;
    int phase;             /* the bar's current phase; -1 before the first */
    char error[1024];
} bake_ui;

static int on_progress(void *user, const lbk_bake_progress *p)
{
    bake_ui *ui = user;
    if ((int)p->phase != ui->phase) {
        ui->phase = (int)p->phase;
        cli_progress_phase(&ui->bar, lbk_bake_phase_name(p->phase));
    } else {
        cli_progress_update(&ui->bar, p->fraction);
    }
    return 0;
}

static void on_message(void *user, lbk_bake_severity severity, const char *message)
{
    bake_ui *ui = user;
    switch (severity) {
    case LBK_BAKE_SEVERITY_INFO: cli_progress_note(&ui->bar, "  %s", message); break;
    case LBK_BAKE_SEVERITY_NOTE: cli_progress_note(&ui->bar, "lbk bake: note: %s", message); break;
    case LBK_BAKE_SEVERITY_WARNING: cli_progress_note(&ui->bar, "lbk bake: warning: %s", message); break;
    default: snprintf(ui->error, sizeof ui->error, "%s", message); break;
    }
}

/* README "Exit codes". */
static int exit_code(lbk_result r)
{
    switch (r) {
    case LBK_OK: return LBK_EXIT_OK;
    case LBK_ERR_IO: return LBK_EXIT_IO;
    case LBK_ERR_BAD_INPUT: return LBK_EXIT_INPUT;
    default: return LBK_EXIT_INTERNAL;
    }
}

/* The JSON report into a new temporary file beside json_path (its name in tmp); 0 or -1 with
 * the cause printed. */
static int write_report_tmp(const lbk_bake_report *rep, const char *container, const char *json_path, char *tmp,
                            size_t tmp_size)
{
    char *text = NULL;
    size_t size = 0;
    lbk_result r = lbk_bake_report_json(rep, container, NULL, &text, &size);
    if (r) {
        fprintf(stderr, "lbk bake: the report: %s\n", lbk_result_message(r));
        return -1;
    }
    int n = snprintf(tmp, tmp_size, "%s.tmp-XXXXXX", json_path);
    int fd = n > 0 && (size_t)n < tmp_size ? mkstemp(tmp) : -1;
    int ok = fd >= 0;
    if (ok) {
        size_t done = 0;
        while (ok && done < size) {
            ssize_t w = write(fd, text + done, size - done);
            if (w < 0 && errno == EINTR) continue;
            ok = w > 0;
            if (ok) done += (size_t)w;
        }
        ok = ok && write(fd, "\n", 1) == 1 && fchmod(fd, 0644) == 0 && fsync(fd) == 0;
        int saved = errno;
        if (close(fd) != 0 && ok) ok = 0, saved = errno;
        if (!ok) unlink(tmp);
        errno = saved;
    }
    int saved = errno;
    lbk_free(NULL, text);
    if (!ok) {
        fprintf(stderr, "lbk bake: writing %s: %s\n", json_path, strerror(saved));
        tmp[0] = 0;
        return -1;
    }
    return 0;
}

static void say_removed(void *user, const char *file)
{
    fprintf(stderr, "lbk %s: removed %s, a temporary file an interrupted write left behind\n", (const char *)user, file);
}

/* Temporary files of earlier writes to our outputs that were killed between writing and renaming.
 * Only those older than a minute before this process started: a concurrent bake to the same
 * path may be writing its own right now. */
static void remove_stale(const bake_args *o, time_t started)
{
    tl_remove_stale_temps(o->output, started - 60, say_removed, "bake");
    if (o->json_report) tl_remove_stale_temps(o->json_report, started - 60, say_removed, "bake");
}

/* A hard link to the old report under a temporary name of the stale-temp pattern (so that a
 * crash leaves nothing tl_remove_stale_temps does not clean); 0 and name[0] = 0 when there is
 * no old report; -1 when the link cannot be made. */
static int keep_old_report(const char *json, char *name, size_t name_size)
{
    name[0] = 0;
    struct stat st;
    if (lstat(json, &st) != 0) return errno == ENOENT ? 0 : -1;
    for (int tries = 0; tries < 8; tries++) {
        int n = snprintf(name, name_size, "%s.tmp-XXXXXX", json);
        int fd = n > 0 && (size_t)n < name_size ? mkstemp(name) : -1;
        if (fd < 0) break;
        close(fd);
        unlink(name); /* mkstemp only picked a free name; the link takes it */
        if (link(json, name) == 0) return 0;
        if (errno != EEXIST) break;
    }
    name[0] = 0;
    return -1;
}

/* Puts the report (already complete in json_tmp, or NULL) and the container in place so that an
 * error leaves both old files: the report goes first, with the old one kept by a hard link, then
 * the container, the commit point; when the container cannot be written the old report is put
 * back. A kill between the two renames leaves the new report beside the old container (two
 * files cannot be replaced atomically together) and the link, which the next run removes. */
static int commit_outputs(const bake_args *o, lbk_bake_output *out, const char *json_tmp)
{
    char old_report[4096] = "";
    if (json_tmp && keep_old_report(o->json_report, old_report, sizeof old_report) != 0) {
        fprintf(stderr, "lbk bake: keeping the old report %s while writing: %s\n", o->json_report, strerror(errno));
        unlink(json_tmp);
        return LBK_EXIT_IO;
    }
    if (json_tmp && rename(json_tmp, o->json_report) != 0) {
        fprintf(stderr, "lbk bake: writing %s: %s\n", o->json_report, strerror(errno));
        unlink(json_tmp);
        if (old_report[0]) unlink(old_report);
        return LBK_EXIT_IO;
    }
    struct stat before;
    int had = stat(o->output, &before) == 0;
    lbk_result r = lbk_bake_output_write_file(out, o->output);
    int saved = errno;
    if (r == LBK_OK) {
        if (old_report[0]) unlink(old_report);
        return LBK_EXIT_OK;
    }
    /* the container's rename happened and only the sync of its folder failed: the new file is
     * complete and in place, and the new report belongs to it */
    struct stat after;
    if (r == LBK_ERR_IO && stat(o->output, &after) == 0 && (!had || after.st_ino != before.st_ino)) {
        if (old_report[0]) unlink(old_report);
        fprintf(stderr, "lbk bake: %s was written, but syncing its folder failed (it may not survive a power loss): %s\n",
                o->output, strerror(saved));
        return LBK_EXIT_IO;
    }
    if (json_tmp) {
        if (old_report[0] ? rename(old_report, o->json_report) != 0 : unlink(o->json_report) != 0)
            fprintf(stderr, "lbk bake: could not put the old report %s back: %s\n", o->json_report, strerror(errno));
    }
    if (r == LBK_ERR_IO)
        fprintf(stderr, "lbk bake: writing %s: %s\n", o->output, strerror(saved));
    else
        fprintf(stderr, "lbk bake: writing %s: %s\n", o->output, lbk_result_message(r));
    return exit_code(r == LBK_ERR_IO ? r : LBK_ERR_INTERNAL);
}

static int bake(bake_args *o, int quiet)
{
    const time_t started = time(NULL);
    bake_ui ui;
    memset(&ui, 0, sizeof ui);
    ui.phase = -1;
    cli_progress_init(&ui.bar, quiet);
    o->d.progress = on_progress;
    o->d.message = on_message;
    o->d.user = &ui;
    lbk_bake_output *out = NULL;
    const char *cmd = o->cmd ? o->cmd : "bake";
    lbk_result r = o->merge ? lbk_bake_merge_from_file(o->input, &o->d, o->plan_hash, o->units, o->parts, o->part_sizes,
                                                       o->part_count, &out)
                            : lbk_bake_from_file(o->input, &o->d, &out);
    if (r) {
        fprintf(stderr, "lbk %s: %s\n", cmd, ui.error[0] ? ui.error : lbk_result_message(r));
        return r == LBK_ERR_INVALID_ARGUMENT && o->merge ? LBK_EXIT_USAGE : exit_code(r);
    }
    /* Nothing is written on error, the report included (commit_outputs). */
    const lbk_bake_report *rep = lbk_bake_output_report(out);
    char json_tmp[4096] = "";
    if (o->json_report && write_report_tmp(rep, o->output, o->json_report, json_tmp, sizeof json_tmp)) {
        lbk_bake_output_free(out);
        return LBK_EXIT_IO;
    }
    remove_stale(o, started);
    int code = commit_outputs(o, out, json_tmp[0] ? json_tmp : NULL);
    if (code != LBK_EXIT_OK) {
        lbk_bake_output_free(out);
        return code;
    }
    cli_progress_done(&ui.bar);
    const lbk_bake_counts *c = &rep->counts;
    if (!quiet)
        printf("%s: %llu objects, %llu texels in %llu pages, %llu GLG probes, %llu LLG probes in %llu grids, "
               "%u dynamic sets (light sets and door states), %u doors; estimated error %.2f%%; %llu bytes\n",
               o->output, (unsigned long long)c->objects, (unsigned long long)c->texels,
               (unsigned long long)c->pages, (unsigned long long)c->glg_probes,
               (unsigned long long)c->llg_probes, (unsigned long long)c->llgs, c->light_sets, c->doors,
               100 * rep->transport.est_rel_rmse, (unsigned long long)c->file_bytes);
    lbk_bake_output_free(out);
    return LBK_EXIT_OK;
}

/* auto | on | off as lbk_bake_desc's tri-state fields take it (0, 1, -1); 0 after saying why. */
static int auto_on_off(const char *option, const char *v, int *out)
{
    if (!strcmp(v, "auto")) *out = 0;
    else if (!strcmp(v, "on")) *out = 1;
    else if (!strcmp(v, "off")) *out = -1;
    else {
        fprintf(stderr, "lbk bake: %s: '%s' is not auto, on or off\n", option, v);
        return 0;
    }
    return 1;
}

int cli_bake_flag(const char *a)
{
    return !strcmp(a, "--no-glg") || !strcmp(a, "--octahedral") || !strcmp(a, "--glg-lighting") || !strcmp(a, "--llg-connected") || !strcmp(a, "--error-map") || !strcmp(a, "--block-align") || !strcmp(a, "--timestamp") ||
           !strcmp(a, "-q") || !strcmp(a, "--quiet") || !strcmp(a, "-h") || !strcmp(a, "--help");
}

int cli_bake_parse(int argc, char **argv, bake_args *out, int *quiet_out)
{
    bake_args o;
    memset(&o, 0, sizeof o);
    o.d.size = sizeof o.d; /* this build's fields, block_align included */
    o.d.seed = 1;
    int quiet = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        double d;
        unsigned long long u;
#define NEED_VALUE                                                         \
    do {                                                                   \
        if (!v) {                                                          \
            fprintf(stderr, "lbk bake: %s needs a value\n", a);            \
            return LBK_EXIT_USAGE;                                         \
        }                                                                  \
        i++;                                                               \
    } while (0)
#define NEED_UINT(lo, hi)                                                                          \
    do {                                                                                           \
        NEED_VALUE;                                                                                \
        if (!cli_parse_uint(v, (lo), (hi), &u)) {                                                      \
            fprintf(stderr, "lbk bake: %s: '%s' is not a whole number in [%llu, %llu]\n", a, v,     \
                    (unsigned long long)(lo), (unsigned long long)(hi));                           \
            return LBK_EXIT_USAGE;                                                                 \
        }                                                                                          \
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
        } else if (!strcmp(a, "--target-error") && v && !strcmp(v, "none")) {
            i++;
            o.d.target_error = -1;
        } else if (!strcmp(a, "--checkpoint") || !strcmp(a, "--resume") || !strcmp(a, "--continue")) {
            NEED_VALUE;
            if (o.d.checkpoint_dir) {
                fprintf(stderr, "lbk bake: one of --checkpoint, --resume, --continue\n");
                return LBK_EXIT_USAGE;
            }
            o.d.checkpoint_dir = v;
            o.d.resume = strcmp(a, "--checkpoint") != 0;
            o.continued = !strcmp(a, "--continue");
        } else if (!strcmp(a, "--plan")) {
            NEED_VALUE;
            o.plan = v;
        } else if (!strcmp(a, "--units")) {
            NEED_UINT(1, 65536);
            o.units = (unsigned)u;
        } else if (!strcmp(a, "--makefile")) {
            NEED_VALUE;
            o.makefile = v;
        } else if (!strcmp(a, "--sbatch")) {
            NEED_VALUE;
            o.sbatch = v;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            NEED_VALUE;
            o.output = v;
        } else if (!strcmp(a, "--preset")) {
            NEED_VALUE;
            if (strcmp(v, "fast") && strcmp(v, "high")) {
                fprintf(stderr, "lbk bake: unknown preset '%s' (fast, high)\n", v);
                return LBK_EXIT_USAGE;
            }
            o.d.preset = strcmp(v, "high") ? LBK_BAKE_PRESET_FAST : LBK_BAKE_PRESET_HIGH;
        } else if (!strcmp(a, "--target-error")) {
            NEED_NUMBER(1e-6, 10);
            o.d.target_error = d;
        } else if (!strcmp(a, "--time-limit")) {
            NEED_NUMBER(0.001, 1e7);
            o.d.time_limit = d;
        } else if (!strcmp(a, "--samples")) {
            NEED_UINT(1, 1 << 24);
            o.d.max_samples = (int)u;
        } else if (!strcmp(a, "--max-bounces")) {
            NEED_UINT(1, 1000);
            o.d.max_bounces = (int)u;
        } else if (!strcmp(a, "--texel-density")) {
            NEED_NUMBER(1e-6, 1e7);
            o.d.texel_density = (float)d;
        } else if (!strcmp(a, "--glg-spacing")) {
            NEED_NUMBER(1e-6, 1e6);
            o.d.glg_spacing = (float)d;
        } else if (!strcmp(a, "--sky")) {
            NEED_VALUE;
            float r, g, b;
            char tail;
            if (sscanf(v, "%f,%f,%f%c", &r, &g, &b, &tail) == 3) {
                if (!(r >= 0 && g >= 0 && b >= 0 && r < 1e30f && g < 1e30f && b < 1e30f)) {
                    fprintf(stderr, "lbk bake: --sky: radiance must be finite and >= 0\n");
                    return LBK_EXIT_USAGE;
                }
                o.d.sky_override = 1;
                o.d.sky[0] = r, o.d.sky[1] = g, o.d.sky[2] = b;
            } else {
                o.d.sky_override = 1;
                o.d.sky_exr = v;
            }
        } else if (!strcmp(a, "--no-glg")) {
            o.d.no_glg = 1;
        } else if (!strcmp(a, "--octahedral")) {
            o.d.octahedral_probes = 1;
        } else if (!strcmp(a, "--gather-limit")) {
            NEED_NUMBER(1e-4, 1e6);
            o.d.gather_limit = (float)d;
        } else if (!strcmp(a, "--octp-levels")) {
            NEED_UINT(1, 3);
            o.d.octp_levels = (int)u;
        } else if (!strcmp(a, "--octp-spacing")) {
            NEED_NUMBER(1e-4, 1e4);
            o.d.octp_spacing = (float)d;
        } else if (!strcmp(a, "--octp-clip")) {
            NEED_UINT(2, 32);
            o.d.octp_clip = (int)u;
        } else if (!strcmp(a, "--llg-connected")) {
            o.d.llg_connected = 1;
        } else if (!strcmp(a, "--glg-lighting")) {
            o.d.glg_lighting = 1;
        } else if (!strcmp(a, "--block-align")) {
            o.d.block_align = 1;
        } else if (!strcmp(a, "--error-map")) {
            o.d.error_map = 1;
        } else if (!strcmp(a, "--dls-threshold")) {
            NEED_NUMBER(0, 1);
            o.d.dls_threshold = d > 0 ? d : -1;
        } else if (!strcmp(a, "--light-culling")) {
            NEED_VALUE;
            if (!auto_on_off(a, v, &o.d.light_culling)) return LBK_EXIT_USAGE;
        } else if (!strcmp(a, "--light-culling-delta")) {
            NEED_NUMBER(1e-9, 1e6);
            o.d.light_culling_delta = d;
        } else if (!strcmp(a, "--glossy-vpl")) {
            NEED_VALUE;
            if (!auto_on_off(a, v, &o.d.glossy_vpl)) return LBK_EXIT_USAGE;
        } else if (!strcmp(a, "--glossy-vpl-photons")) {
            NEED_UINT(1, 1 << 20);
            o.d.glossy_vpl_photons = (int)u;
        } else if (!strcmp(a, "--glossy-vpl-delta")) {
            NEED_NUMBER(1e-9, 1e6);
            o.d.glossy_vpl_delta = d;
        } else if (!strcmp(a, "--adaptive")) {
            NEED_VALUE;
            if (!strcmp(v, "on")) o.d.adaptive = 0;
            else if (!strcmp(v, "off")) o.d.adaptive = -1;
            else {
                fprintf(stderr, "lbk bake: --adaptive: '%s' is not on or off\n", v);
                return LBK_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--door-method")) {
            NEED_VALUE;
            if (!strcmp(v, "difference")) o.d.door_method = LBK_BAKE_DOOR_DIFFERENCE;
            else if (!strcmp(v, "guided")) o.d.door_method = LBK_BAKE_DOOR_GUIDED;
            else {
                fprintf(stderr, "lbk bake: unknown door method '%s' (difference, guided)\n", v);
                return LBK_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--denoise")) {
            NEED_VALUE;
            if (!strcmp(v, "auto")) o.d.denoise = LBK_BAKE_DENOISE_AUTO;
            else if (!strcmp(v, "off")) o.d.denoise = LBK_BAKE_DENOISE_OFF;
            else if (!strcmp(v, "on")) o.d.denoise = LBK_BAKE_DENOISE_ON;
            else {
                fprintf(stderr, "lbk bake: unknown denoise mode '%s' (auto, on, off)\n", v);
                return LBK_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--threads")) {
            NEED_UINT(1, 1024);
            o.d.threads = (int)u;
        } else if (!strcmp(a, "--seed")) {
            NEED_UINT(0, ULLONG_MAX);
            o.d.seed = u;
        } else if (!strcmp(a, "--allow-outside")) {
            NEED_VALUE;
            o.d.allow_outside = v;
        } else if (!strcmp(a, "--json-report")) {
            NEED_VALUE;
            o.json_report = v;
        } else if (!strcmp(a, "--revision")) {
            NEED_VALUE;
            o.d.revision = v;
        } else if (!strcmp(a, "--timestamp")) {
            o.d.timestamp = 1;
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
#undef NEED_UINT
    }
    *out = o;
    *quiet_out = quiet;
    return -1;
}

int lbk_cmd_bake(int argc, char **argv)
{
    bake_args o;
    int quiet = 0;
    int rc = cli_bake_parse(argc, argv, &o, &quiet);
    if (rc >= 0) return rc;
    if (o.plan || o.units || o.makefile || o.sbatch) {
        if (o.d.checkpoint_dir) {
            fprintf(stderr, "lbk bake: a plan's units write parts, not checkpoints: leave out --checkpoint/--resume/--continue\n");
            return LBK_EXIT_USAGE;
        }
        return cli_plan_write(&o, argc, argv, "bake");
    }
    if (o.continued && !(o.d.target_error > 0) && o.d.max_samples <= 0) {
        fprintf(stderr, "lbk bake: --continue needs the new stop: a lower --target-error and/or a larger --samples\n");
        return LBK_EXIT_USAGE;
    }
    if (!o.d.octahedral_probes && (o.d.octp_levels || o.d.octp_spacing > 0 || o.d.octp_clip)) {
        fprintf(stderr, "lbk bake: --octp-levels/--octp-spacing/--octp-clip shape the octahedral probe volume: add --octahedral\n");
        return LBK_EXIT_USAGE;
    }
    if (!o.input || !o.output) {
        fprintf(stderr, "lbk bake: need a scene and -o OUT.lbk (lbk bake --help)\n");
        return LBK_EXIT_USAGE;
    }
    /* An output must never replace an input (`-o scene.gltf` once destroyed the scene). */
    const char *inputs[] = {o.input, o.d.sky_exr};
    for (int k = 0; k < 2; k++) {
        if (same_file(o.output, inputs[k]) || same_file(o.json_report, inputs[k])) {
            fprintf(stderr, "lbk bake: refusing to overwrite the input %s with an output\n", inputs[k]);
            return LBK_EXIT_USAGE;
        }
    }
    if (o.json_report && (same_file(o.json_report, o.output) || !strcmp(o.json_report, o.output))) {
        fprintf(stderr, "lbk bake: --json-report and -o name the same file %s\n", o.output);
        return LBK_EXIT_USAGE;
    }
    return bake(&o, quiet);
}

int cli_bake_run(bake_args *o, int quiet) { return bake(o, quiet); }
