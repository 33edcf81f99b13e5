/* What `lbk bake`, `lbk plan`, `lbk bake-unit` and `lbk merge` share: the bake options parsed
 * from the command line (bake_options.c: one table of them) and the bake's end (messages, the
 * report, exit codes). */
#ifndef LBK_CLI_BAKE_OPTIONS_H
#define LBK_CLI_BAKE_OPTIONS_H

#include "lbk/bake.h"

typedef struct bake_args {
    lbk_bake_desc d;
    const char *input, *output, *json_report;
    /* a distributed bake's plan (cmd_dist.c) */
    const char *plan, *makefile, *sbatch;
    unsigned units;
    int continued;              /* --continue (--resume with a new stop) */
    /* lbk merge: cli_bake_run merges these parts instead of baking */
    int merge;
    uint64_t plan_hash;
    const void *const *parts;
    const size_t *part_sizes;
    size_t part_count;
    const char *cmd;            /* for messages: "bake" unless set */
} bake_args;

/* Parses `lbk bake` arguments (argv[0] is the command). Returns -1 when the bake should go on,
 * else the exit code (usage errors printed, --help printed: 0). */
int cli_bake_parse(int argc, char **argv, bake_args *o, int *quiet);
/* 1 for the options that take no value. */
int cli_bake_flag(const char *arg);
/* 1 for the options that change no byte of the container (output paths, threads, progress, the
 * plan's own): a plan leaves them out. */
int cli_bake_plan_neutral(const char *arg);
/* Bakes o->input into o->output as `lbk bake` does; the exit code. */
int cli_bake_run(bake_args *o, int quiet);
/* Writes the plan (and the Makefile / sbatch script) of a distributed bake; the exit code.
 * cmd names the command for messages. */
int cli_plan_write(const bake_args *o, int argc, char **argv, const char *cmd);

#endif
