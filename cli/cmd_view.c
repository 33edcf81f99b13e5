/* lbk view LEVEL.lbk SCENE.glb [--out DIR] [--port P]: the bake in a browser (tools/view/view.h). */
#define _XOPEN_SOURCE 700 /* nftw, mkdtemp */
#include <ftw.h>
#include <poll.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/options.h"
#include "tools/common/output_guard.h"
#include "tools/inspect/report.h"
#include "tools/view/view.h"

#define DEFAULT_PORT 8765

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lbk view LEVEL.lbk SCENE.gltf|.glb [--out DIR] [--port P] [--report BAKE.json] [-q]\n"
            "\n"
            "Shows the bake in a web browser: the level with its baked lighting decoded as a runtime does\n"
            "(AHD lightmaps in the shader, LLG objects per vertex, other objects from the global grid), an\n"
            "orbit camera (drag, wheel), exposure, views (albedo x irradiance, irradiance, texel grid, albedo),\n"
            "GLG probe glyphs, and a panel with the sections' sizes and the bake report. The page reads the\n"
            ".lbk itself (viewer/lbk_reader.js, written from spec/container.md); the panel also shows\n"
            "lbk inspect --json of LEVEL (memory per section and object). SCENE is the file the level\n"
            "was baked from (checked object by object, as lbk export --gltf does).\n"
            "\n"
            "  --out DIR   write the page into DIR (index.html, data.js with the level, the scripts, level.glb\n"
            "              and its lightmap images): it opens from disk with no server\n"
            "  --port P    serve the page on http://127.0.0.1:P/ (only this machine; Ctrl-C stops) [%d];\n"
            "              0 picks a free port. Without --out the page goes to a temporary folder that is\n"
            "              removed when the server stops. With --out and without --port: write only\n"
            "  --report F  the bake's report (lbk bake --json-report F): the page plots its error against\n"
            "              wall-clock time (without it: REPT's error against samples per texel)\n"
            "  -q, --quiet no summary\n"
            "  -h, --help  this text\n"
            "\n"
            "exit codes: 0 written / served until stopped, 2 usage, 3 I/O error (or the port is taken),\n"
            "            4 the input is not a valid container or SCENE is not the scene it was baked from,\n"
            "            5 internal error\n",
            DEFAULT_PORT);
}

static volatile int stop_flag;
static void on_signal(int sig) { (void)sig, stop_flag = 1; }

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st, (void)flag, (void)ftw;
    return remove(path);
}

static int parse_port(const char *s, long *out)
{
    unsigned long long v;
    if (!cli_parse_uint(s, 0, 65535, &v)) return -1; /* strtol took " 80" and "+80" */
    *out = (long)v;
    return 0;
}

static int serve(const char *dir, long port, int quiet)
{
    char err[TL_ERR_LEN];
    uint16_t bound = 0;
    const int fd = tl_view_listen((uint16_t)port, &bound, err);
    if (fd < 0) {
        fprintf(stderr, "lbk view: %s\n", err);
        return LBK_EXIT_IO;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    if (!quiet) printf("lbk view: http://127.0.0.1:%u/ (Ctrl-C stops)\n", (unsigned)bound);
    fflush(stdout);
    const int rc = tl_view_serve(fd, dir, &stop_flag, 0, err);
    close(fd);
    if (rc) fprintf(stderr, "lbk view: %s\n", err);
    return rc ? LBK_EXIT_IO : LBK_EXIT_OK;
}

static int view_main(int argc, char **argv, tl_guard *guard)
{
    tl_view_options o = {.container = NULL};
    long port = -1;
    int quiet = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return LBK_EXIT_OK;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            quiet = 1;
        } else if (!strcmp(a, "--out") || !strcmp(a, "--port") || !strcmp(a, "--report")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "lbk view: %s needs a value\n", a);
                return LBK_EXIT_USAGE;
            }
            const char *v = argv[++i];
            if (!strcmp(a, "--report")) {
                if (o.report_path) {
                    fprintf(stderr, "lbk view: --report given twice\n");
                    return LBK_EXIT_USAGE;
                }
                o.report_path = v;
            } else if (!strcmp(a, "--out")) {
                if (o.out_dir) {
                    fprintf(stderr, "lbk view: --out given twice\n");
                    return LBK_EXIT_USAGE;
                }
                o.out_dir = v;
            } else if (port >= 0 || parse_port(v, &port)) {
                fprintf(stderr, "lbk view: --port needs one number 0..65535, got '%s'\n", v);
                return LBK_EXIT_USAGE;
            }
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk view: unknown option '%s' (see lbk view --help)\n", a);
            return LBK_EXIT_USAGE;
        } else if (!o.container) {
            o.container = a;
        } else if (!o.scene) {
            o.scene = a;
        } else {
            fprintf(stderr, "lbk view: more than LEVEL.lbk and SCENE\n");
            return LBK_EXIT_USAGE;
        }
    }
    if (!o.container || !o.scene) {
        fprintf(stderr, "lbk view: need LEVEL.lbk and the SCENE it was baked from (see lbk view --help)\n");
        return LBK_EXIT_USAGE;
    }
    /* the page's files may replace neither the level, the scene (a level.glb in --out), a file the
     * scene reads, the report nor a device (output_guard.h) */
    if (tl_guard_input(guard, o.container, "the container") || tl_guard_scene(guard, o.scene, NULL) ||
        tl_guard_input(guard, o.report_path, "the report"))
        return LBK_EXIT_INTERNAL;
    if (o.out_dir) {
        static const char *const page[] = {"index.html", "data.js", "level.glb", NULL};
        char why[TL_ERR_LEN];
        if (tl_guard_output_dir(guard, o.out_dir, page, "--out", why)) {
            fprintf(stderr, "lbk view: %s\n", why);
            return LBK_EXIT_USAGE;
        }
    }
    tl_guard_activate(guard);
    char tmp[] = "/tmp/lbk-view-XXXXXX";
    if (!o.out_dir) {
        if (!mkdtemp(tmp)) {
            perror("lbk view: temporary folder");
            return LBK_EXIT_IO;
        }
        o.out_dir = tmp;
        if (port < 0) port = DEFAULT_PORT;
    }
    char err[TL_ERR_LEN];
    tl_view_stats s;
    char *inspect = NULL; /* the page then shows its own reader's section sizes */
    if (tl_inspect_file_json(o.container, 0, &inspect)) inspect = NULL;
    o.inspect_json = inspect;
    int rc = tl_view_write(&o, &s, err);
    free(inspect);
    if (rc) {
        fprintf(stderr, "lbk view: %s\n", err);
        rc = rc == TL_VIEW_IO ? LBK_EXIT_IO : rc == TL_VIEW_INPUT ? LBK_EXIT_INPUT : LBK_EXIT_INTERNAL;
    } else {
        if (!quiet && s.astc_pages)
            fprintf(stderr, "lbk view: %u ASTC lightmap page(s) decoded here and handed to the page as 1.0 texels "
                            "(R11G11B10F + RGBA8): the page has no ASTC decoder\n", s.astc_pages);
        if (!quiet && o.out_dir != tmp)
            printf("%s: %u files (data.js %llu bytes); open %s/index.html\n", o.out_dir, s.files,
                   (unsigned long long)s.data_bytes, o.out_dir);
        if (port >= 0) rc = serve(o.out_dir, port, quiet);
    }
    if (o.out_dir == tmp) nftw(tmp, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    return rc;
}

int lbk_cmd_view(int argc, char **argv) { return cli_run_guarded("view", view_main, argc, argv); }
