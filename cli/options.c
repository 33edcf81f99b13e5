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
