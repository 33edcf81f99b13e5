/* lbk bake: the command line over liblbkbake (lbk/bake.h): the options (parsed by the table of
 * bake_options.c), the progress bar and messages on stderr, the container and the JSON report
 * written, exit codes. */
#include <errno.h>
#include <math.h>
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


/* The path check's line (bake/transport/TRANSPORT.md §Path check): the error measured against
 * unbiased paths and the object that carries the most of it beyond the noise estimate. */
static void print_path_check(const lbk_bake_report *rep)
{
    if (rep->size < offsetof(lbk_bake_report, check) + sizeof rep->check || !rep->check.receivers ||
        !rep->object_checks)
        return;
    size_t worst = SIZE_MAX;
    double worst_ratio = 0;
    for (size_t i = 0; i < rep->object_estimate_count; i++) {
        const double noise = hypot(rep->object_estimates[i].noise, rep->object_estimates[i].bias);
        const double ratio = rep->object_checks[i].rel_rmse / (noise > 1e-6 ? noise : 1e-6);
        if (rep->object_checks[i].receivers && ratio > worst_ratio) worst_ratio = ratio, worst = i;
    }
    printf("path check: %.2f%% measured against unbiased paths at %u texels (%u paths each)", 100 * rep->check.rel_rmse,
           rep->check.receivers, rep->check.samples);
    if (worst != SIZE_MAX && worst_ratio > 2)
        printf("; %s carries %.1f%%, %.1fx its noise estimate", rep->object_estimates[worst].name,
               100 * rep->object_checks[worst].rel_rmse, worst_ratio);
    printf("\n");
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
    if (!quiet) print_path_check(rep);
    lbk_bake_output_free(out);
    return LBK_EXIT_OK;
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
    /* An output must never replace an input (`-o scene.gltf` once destroyed the scene), a file
     * the scene reads, or a device (output_guard.h). */
    const char *extra[] = {"the sky", o.d.sky_exr, NULL, NULL};
    const char *outs[] = {"-o", o.output, "--json-report", o.json_report, NULL, NULL};
    int guarded = cli_check_scene_outputs("bake", o.input, o.d.allow_outside, extra, outs);
    if (guarded) return guarded;
    return bake(&o, quiet);
}

int cli_bake_run(bake_args *o, int quiet) { return bake(o, quiet); }
