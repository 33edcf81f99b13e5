/* Weak placeholders for subcommands that have not landed; the real one overrides it.
 * Each owner deletes its line when its command lands. */
#include <stdio.h>

#include "cli/cli.h"

#define LBK_WEAK_COMMAND(fn, name)                                                   \
    __attribute__((weak)) int fn(int argc, char **argv)                               \
    {                                                                                 \
        (void)argc; (void)argv;                                                       \
        fprintf(stderr, "lbk %s: not available in this build\n", name);               \
        return LBK_EXIT_INTERNAL;                                                     \
    }

