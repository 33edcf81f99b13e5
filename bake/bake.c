/* The bake pipeline (being assembled as the phases land). */
#include <stdio.h>

#include "bake/bake.h"
#include "cli/cli.h"

int bk_bake(const bk_bake_options *opt, bk_progress *progress, bk_bake_summary *summary, char *err,
            size_t err_len)
{
    (void)opt;
    (void)progress;
    (void)summary;
    snprintf(err, err_len, "the bake pipeline is not assembled yet");
    return LBK_EXIT_INTERNAL;
}
