/* Fault injection for the writers of the CLI (tests/tools/test_faults.c), as an LD_PRELOAD
 * library: it counts the calls of each file-writing operation and can make the N-th call of one
 * of them fail with a chosen errno, or kill the process right there (SIGKILL: no handler, no
 * cleanup, as a crash or an OOM kill would).
 *
 *   LBK_FAULT_OP     open | write | fsync | rename | mkdir   (what to hit; unset: only count)
 *   LBK_FAULT_AT     1-based index of the call of that operation to hit
 *   LBK_FAULT_KILL   1: SIGKILL instead of failing
 *   LBK_FAULT_COUNTS file the calls per operation are appended to at exit ("open N" lines)
 *
 * Operations: `open` is an open/openat/fopen/creat that can create or write a file; `write` is
 * write/pwrite/fwrite to anything but stdin/stdout/stderr; `fsync` is fsync/fdatasync;
 * `rename` is rename/renameat; `mkdir` is mkdir. The errno of a failure: ENOSPC (open, write,
 * mkdir), EIO (fsync), EXDEV (rename) — causes a user must be told by name.
 * Test code only: it keeps its counters in globals, which a library must not. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

enum { OP_OPEN, OP_WRITE, OP_FSYNC, OP_RENAME, OP_MKDIR, OP_COUNT };
static const char *const op_names[OP_COUNT] = {"open", "write", "fsync", "rename", "mkdir"};
static const int op_errno[OP_COUNT] = {ENOSPC, ENOSPC, EIO, EXDEV, ENOSPC};
static unsigned long calls[OP_COUNT];
static int target_op = -2; /* -2: environment not read yet; -1: count only */
static unsigned long target_at;
static int kill_mode;

static void read_env(void)
{
    if (target_op != -2) return;
    target_op = -1;
    const char *op = getenv("LBK_FAULT_OP"), *at = getenv("LBK_FAULT_AT"), *k = getenv("LBK_FAULT_KILL");
    for (int i = 0; op && i < OP_COUNT; i++)
        if (!strcmp(op, op_names[i])) target_op = i;
    target_at = at ? strtoul(at, NULL, 10) : 0;
    kill_mode = k && k[0] == '1';
}

/* Counts a call of `op`; non-zero when this call is the one to hit (errno is then set). */
static int hit(int op)
{
    read_env();
    unsigned long n = ++calls[op];
    if (op != target_op || n != target_at) return 0;
    if (kill_mode) raise(SIGKILL);
    errno = op_errno[op];
    return 1;
}

__attribute__((destructor)) static void write_counts(void)
{
    const char *path = getenv("LBK_FAULT_COUNTS");
    if (!path) return;
    __typeof__(&open) real_open = (__typeof__(&open))dlsym(RTLD_NEXT, "open");
    __typeof__(&write) real_write = (__typeof__(&write))dlsym(RTLD_NEXT, "write");
    int fd = real_open(path, O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd < 0) return;
    char line[64];
    for (int i = 0; i < OP_COUNT; i++) {
        int len = snprintf(line, sizeof line, "%s %lu\n", op_names[i], calls[i]);
        if (real_write(fd, line, (size_t)len) != len) break;
    }
    close(fd);
}

#define REAL(name)                                                                                 \
    static __typeof__(&name) real_##name;                                                          \
    if (!real_##name) real_##name = (__typeof__(&name))dlsym(RTLD_NEXT, #name)

static int writes_file(int flags) { return (flags & (O_WRONLY | O_RDWR | O_CREAT | O_TRUNC | O_APPEND)) != 0; }
static int fopen_writes(const char *mode) { return mode && (strchr(mode, 'w') || strchr(mode, 'a') || strchr(mode, '+')); }

/* open's third argument exists only with O_CREAT or O_TMPFILE (a macro: va_start must run in the
 * variadic function itself) */
#define OPEN_MODE(flags, mode)                                                                     \
    do {                                                                                           \
        if ((flags) & (O_CREAT | O_TMPFILE)) {                                                     \
            va_list ap;                                                                            \
            va_start(ap, flags);                                                                   \
            (mode) = (mode_t)va_arg(ap, int);                                                      \
            va_end(ap);                                                                            \
        }                                                                                          \
    } while (0)

int open(const char *path, int flags, ...)
{
    REAL(open);
    mode_t mode = 0;
    OPEN_MODE(flags, mode);
    if (writes_file(flags) && hit(OP_OPEN)) return -1;
    return real_open(path, flags, mode);
}

int open64(const char *path, int flags, ...)
{
    REAL(open64);
    mode_t mode = 0;
    OPEN_MODE(flags, mode);
    if (writes_file(flags) && hit(OP_OPEN)) return -1;
    return real_open64(path, flags, mode);
}

int openat(int dir, const char *path, int flags, ...)
{
    REAL(openat);
    mode_t mode = 0;
    OPEN_MODE(flags, mode);
    if (writes_file(flags) && hit(OP_OPEN)) return -1;
    return real_openat(dir, path, flags, mode);
}

int mkstemp(char *tmpl)
{
    REAL(mkstemp);
    if (hit(OP_OPEN)) return -1;
    return real_mkstemp(tmpl);
}

FILE *fopen(const char *path, const char *mode)
{
    REAL(fopen);
    if (fopen_writes(mode) && hit(OP_OPEN)) return NULL;
    return real_fopen(path, mode);
}

FILE *fopen64(const char *path, const char *mode)
{
    REAL(fopen64);
    if (fopen_writes(mode) && hit(OP_OPEN)) return NULL;
    return real_fopen64(path, mode);
}

ssize_t write(int fd, const void *buf, size_t n)
{
    REAL(write);
    if (fd > 2 && hit(OP_WRITE)) return -1;
    return real_write(fd, buf, n);
}

ssize_t pwrite(int fd, const void *buf, size_t n, off_t off)
{
    REAL(pwrite);
    if (fd > 2 && hit(OP_WRITE)) return -1;
    return real_pwrite(fd, buf, n, off);
}

ssize_t pwrite64(int fd, const void *buf, size_t n, off_t off)
{
    REAL(pwrite64);
    if (fd > 2 && hit(OP_WRITE)) return -1;
    return real_pwrite64(fd, buf, n, off);
}

size_t fwrite(const void *buf, size_t size, size_t n, FILE *f)
{
    REAL(fwrite);
    if (f != stdout && f != stderr && hit(OP_WRITE)) return 0; /* a short count, as stdio reports it */
    return real_fwrite(buf, size, n, f);
}

int fsync(int fd)
{
    REAL(fsync);
    if (hit(OP_FSYNC)) return -1;
    return real_fsync(fd);
}

int fdatasync(int fd)
{
    REAL(fdatasync);
    if (hit(OP_FSYNC)) return -1;
    return real_fdatasync(fd);
}

int rename(const char *a, const char *b)
{
    REAL(rename);
    if (hit(OP_RENAME)) return -1;
    return real_rename(a, b);
}

int renameat(int da, const char *a, int db, const char *b)
{
    REAL(renameat);
    if (hit(OP_RENAME)) return -1;
    return real_renameat(da, a, db, b);
}

int mkdir(const char *path, mode_t mode)
{
    REAL(mkdir);
    if (hit(OP_MKDIR)) return -1;
    return real_mkdir(path, mode);
}
