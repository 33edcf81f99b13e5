/* A test group's scratch directory: made in its setup, removed with everything in it in its
 * teardown, or kept (its path printed) when $LBK_TEST_KEEP is set, for a look with lbk inspect,
 * view or render. Header only (static inline), like scenes_dir.h. */
#ifndef TD_TMP_DIR_H
#define TD_TMP_DIR_H

#include <stdio.h>
#include <stdlib.h>

/* Makes /tmp/<prefix>_XXXXXX into dir (n bytes); 0, or -1 when it cannot. */
static inline int td_make(char *dir, size_t n, const char *prefix)
{
    snprintf(dir, n, "/tmp/%s_XXXXXX", prefix);
    return mkdtemp(dir) ? 0 : -1;
}

/* Removes dir and what it holds (kept under $LBK_TEST_KEEP); 0, or -1 when rm fails. */
static inline int td_remove(const char *dir)
{
    if (getenv("LBK_TEST_KEEP")) return printf("kept %s\n", dir), 0;
    char cmd[256];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

#endif
