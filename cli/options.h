/* Options several subcommands share. */
#ifndef LBK_CLI_OPTIONS_H
#define LBK_CLI_OPTIONS_H

#include <stdint.h>

/* `--max-memory SIZE` (bytes, or with kB, KiB, MB, MiB, GB, GiB): the cap on the bytes a reader
 * may allocate for decoded sections, so an untrusted file cannot make it allocate far more than
 * it holds. When argv[*i] is that option, stores the size in *out, advances *i past the value and
 * returns 1; returns 0 for any other argument and -1 (message printed, prefixed with `cmd`) for a
 * missing or malformed value. Default 0: liblbk's cap, min(4 GiB, 1024 × file size + 64 MiB)
 * (spec/container.md §4.3). */
int cli_max_memory_option(const char *cmd, int argc, char **argv, int *i, uint64_t *out);

/* A decimal integer in [lo, hi] and nothing else: "1.5", "-1", " 3", "0x10", "1e3" are refused
 * (strtoull alone would turn "-1" into 2^64 - 1, atoi "1.5" into 1). 1 and *out set, or 0. */
int cli_parse_uint(const char *s, unsigned long long lo, unsigned long long hi, unsigned long long *out);

/* The output policy (tools/common/output_guard.h) at the command line: `outputs` holds pairs
 * {what, path} ("-o", "a.exr"; a NULL path is skipped), ended by {NULL, NULL}. Refuses an output
 * that is one of g's inputs, not a regular file, or the same file as another output, printing
 * "lbk CMD: ..." and returning LBK_EXIT_USAGE; 0 when every output may be written. */
struct tl_guard;
int cli_check_outputs(const char *cmd, const struct tl_guard *g, const char *const *outputs);

/* Runs fn with a fresh guard for `cmd` and deactivates and frees it afterwards, whatever fn
 * returns: the commands that keep their guard active while they write use this. */
int cli_run_guarded(const char *cmd, int (*fn)(int argc, char **argv, struct tl_guard *guard), int argc, char **argv);

/* cli_check_outputs for a command that reads a glTF scene: the scene, every file it references
 * (allow_outside as the bake resolves them) and `extra_inputs` (pairs {role, path}, ended by
 * {NULL, NULL}; NULL paths skipped) are the inputs. */
int cli_check_scene_outputs(const char *cmd, const char *scene, const char *allow_outside,
                            const char *const *extra_inputs, const char *const *outputs);

#define CLI_MAX_MEMORY_HELP                                                                          \
    "  --max-memory SIZE  refuse a file whose sections decode to more than SIZE (bytes, or kB, KiB, MB,\n" \
    "                     MiB, GB, GiB); default min(4 GiB, 1024 x file size + 64 MiB)\n"

#endif
