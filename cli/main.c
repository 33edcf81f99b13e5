/* lbk: one binary, one table of subcommands; each lives in its own folder. */
#include <stdio.h>
#include <string.h>

#include "cli/cli.h"
#include "lbk/bake.h"
#include "lbk/lbk.h"

static const struct {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} commands[] = {
    {"bake", lbk_cmd_bake, "bake a glTF level into a container"},
    {"plan", lbk_cmd_plan, "cut a bake into units for make -j, xargs -P, Slurm"},
    {"bake-unit", lbk_cmd_bake_unit, "bake one unit of a plan into a part"},
    {"merge", lbk_cmd_merge, "merge a plan's parts into the container"},
    {"inspect", lbk_cmd_inspect, "memory per level: sections, texels, probes, sets"},
    {"validate", lbk_cmd_validate, "check a container against spec/validation.md"},
    {"diff", lbk_cmd_diff, "compare the lighting of two bakes"},
    {"convert", lbk_cmd_convert, "make a console-ready pack with a profile"},
    {"export", lbk_cmd_export, "write pages and probes as EXR/PNG/CSV"},
    {"render", lbk_cmd_render, "render a view of a baked level (reference renderer)"},
    {"view", lbk_cmd_view, "look at a bake in a browser (a page folder, or served on 127.0.0.1)"},
};

static void usage(FILE *f)
{
    fprintf(f, "usage: lbk <command> [options]   (lbk <command> --help for details)\n\ncommands:\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(f, "  %-9s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\nexit codes: 0 ok, 1 invalid/differ, 2 usage, 3 I/O, 4 unusable input, 5 internal\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return LBK_EXIT_USAGE;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(stdout);
        return LBK_EXIT_OK;
    }
    if (!strcmp(argv[1], "--version")) {
        /* liblbkbake is linked statically into lbk: its compile-time version is the one running. */
        printf("lbk %s (liblbk %s, liblbkbake %d.%d.%d, container format %d.%d)\n", lbk_version_string(),
               lbk_version_string(), LBK_BAKE_LIBRARY_VERSION_MAJOR, LBK_BAKE_LIBRARY_VERSION_MINOR,
               LBK_BAKE_LIBRARY_VERSION_PATCH, LBK_FORMAT_VERSION_MAJOR, LBK_FORMAT_VERSION_MINOR);
        return LBK_EXIT_OK;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name)) return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "lbk: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return LBK_EXIT_USAGE;
}
