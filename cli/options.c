#include <stdlib.h>
#include <errno.h>
#include "cli/options.h"

#include <stdio.h>
#include <string.h>

#include <sys/stat.h>

#include "cli/cli.h"
#include "tools/common/output_guard.h"
#include "tools/inspect/budget.h"

int cli_max_memory_option(const char *cmd, int argc, char **argv, int *i, uint64_t *out)
{
    if (strcmp(argv[*i], "--max-memory")) return 0;
    uint64_t v;
    if (*i + 1 >= argc || tl_budget_parse_size(argv[*i + 1], &v) || v == 0) {
        fprintf(stderr, "lbk %s: --max-memory needs a size above 0 (bytes, or with kB, KiB, MB, MiB, GB, GiB)\n", cmd);
        return -1;
    }
    *out = v;
    ++*i;
    return 1;
}

int cli_parse_uint(const char *s, unsigned long long lo, unsigned long long hi, unsigned long long *out)
{
    if (!s || !*s) return 0;
    for (const char *c = s; *c; c++)
        if (*c < '0' || *c > '9') return 0;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno || *end || v < lo || v > hi) return 0;
    *out = v;
    return 1;
}

/* Two outputs naming one file (by name, or by inode when it exists) would overwrite each other. */
static int same_output(const char *a, const char *b)
{
    struct stat sa, sb;
    if (!strcmp(a, b)) return 1;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

int cli_check_outputs(const char *cmd, const struct tl_guard *g, const char *const *outputs)
{
    char err[TL_ERR_LEN];
    for (size_t i = 0; outputs[i]; i += 2) {
        const char *what = outputs[i], *path = outputs[i + 1];
        if (!path) continue;
        if (tl_guard_output(g, path, what, err) != 0) {
            fprintf(stderr, "lbk %s: %s\n", cmd, err);
            return LBK_EXIT_USAGE;
        }
        for (size_t j = 0; j < i; j += 2)
            if (outputs[j + 1] && same_output(path, outputs[j + 1])) {
                fprintf(stderr, "lbk %s: %s and %s name the same file %s\n", cmd, outputs[j], what, path);
                return LBK_EXIT_USAGE;
            }
    }
    return 0;
}

int cli_check_scene_outputs(const char *cmd, const char *scene, const char *allow_outside,
                            const char *const *extra_inputs, const char *const *outputs)
{
    tl_guard g;
    tl_guard_init(&g, cmd);
    int rc = tl_guard_scene(&g, scene, allow_outside);
    for (size_t i = 0; !rc && extra_inputs && extra_inputs[i]; i += 2)
        rc = tl_guard_input(&g, extra_inputs[i + 1], extra_inputs[i]);
    rc = rc ? LBK_EXIT_INTERNAL : cli_check_outputs(cmd, &g, outputs);
    tl_guard_free(&g);
    return rc;
}

int cli_run_guarded(const char *cmd, int (*fn)(int argc, char **argv, struct tl_guard *guard), int argc, char **argv)
{
    tl_guard guard;
    tl_guard_init(&guard, cmd);
    const int code = fn(argc, argv, &guard);
    tl_guard_activate(NULL);
    tl_guard_free(&guard);
    return code;
}
