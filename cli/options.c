#include <stdlib.h>
#include <errno.h>
#include "cli/options.h"

#include <stdio.h>
#include <string.h>

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
