/* The tools' failure reports: a failing convert/ function writes a one-line English reason into
 * the caller's char err[TL_ERR_LEN] and returns a status. */
#ifndef LBK_TOOLS_ERROR_UTIL_H
#define LBK_TOOLS_ERROR_UTIL_H

#include "tools/common/image_io.h" /* TL_ERR_LEN */

/* Formats the reason into err (nothing when err is NULL) and returns status, so a failing path
 * reads `return tl_fail(err, status, "...", ...)`. */
int tl_fail(char err[TL_ERR_LEN], int status, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

#endif
