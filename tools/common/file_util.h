/* Whole-file reading and atomic writing for the tools. Return 0, or -1 with err filled in. */
#ifndef LBK_TOOLS_FILE_UTIL_H
#define LBK_TOOLS_FILE_UTIL_H

#include <stddef.h>
#include <time.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */

/* Reads a whole regular file into a malloc'ed buffer (at least 1 byte allocated). */
int tl_read_file(const char *path, void **data, size_t *size, char err[TL_ERR_LEN]);
/* Writes through a temp file beside path, fsync, rename: readers never see a partial file. A
 * device, FIFO, socket or directory at path is refused, never replaced (output_guard.h). */
int tl_write_file_atomic(const char *path, const void *data, size_t size, char err[TL_ERR_LEN]);
/* Removes the temporary files an interrupted write to `path` left beside it: `PATH.tmp-XXXXXX`
 * (liblbk's lbk_writer_to_file, six letters or digits) last modified before `before`, and
 * `PATH.tmp.PID` (tl_write_file_atomic, which removes those of `path` itself before it writes)
 * whose process no longer exists. Nothing else is touched
 * (other names, non-regular files). `removed` (may be NULL) gets each removed file's path.
 * Returns how many were removed. */
int tl_remove_stale_temps(const char *path, time_t before, void (*removed)(void *user, const char *file), void *user);
/* Writes a text file (for CSV/JSON listings); atomic like tl_write_file_atomic. */
int tl_write_text(const char *path, const char *text, char err[TL_ERR_LEN]);

/* Monotonic seconds (for the timings tools print; never stored in a file). */
double tl_seconds(void);

#endif
