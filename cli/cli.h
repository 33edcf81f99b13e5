/* The lbk command line: exit codes and the subcommand entry points. */
#ifndef LBK_CLI_H
#define LBK_CLI_H

/* Exit codes, the same for every subcommand (README "Exit codes"). */
enum {
    LBK_EXIT_OK = 0,        /* success; validate: valid; diff: equal within tolerance */
    LBK_EXIT_NEGATIVE = 1,  /* validate: the file is invalid; diff: the bakes differ; inspect --budget: over budget */
    LBK_EXIT_USAGE = 2,     /* bad command line */
    LBK_EXIT_IO = 3,        /* a file could not be read or written */
    LBK_EXIT_INPUT = 4,     /* an input is unusable (bad glTF, invalid container for a reader) */
    LBK_EXIT_INTERNAL = 5   /* out of memory or an internal error */
};

int lbk_cmd_bake(int argc, char **argv);
int lbk_cmd_inspect(int argc, char **argv);
int lbk_cmd_validate(int argc, char **argv);
int lbk_cmd_diff(int argc, char **argv);
int lbk_cmd_convert(int argc, char **argv);
int lbk_cmd_export(int argc, char **argv);
int lbk_cmd_render(int argc, char **argv);
int lbk_cmd_view(int argc, char **argv);
int lbk_cmd_plan(int argc, char **argv);
int lbk_cmd_bake_unit(int argc, char **argv);
int lbk_cmd_merge(int argc, char **argv);

#endif
