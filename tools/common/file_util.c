/* Whole-file reading and atomic writing for the tools. */
#include "tools/common/file_util.h"
#include "tools/common/output_guard.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <time.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int tl_read_file(const char *path, void **data, size_t *size, char err[TL_ERR_LEN])
{
    *data = NULL;
    *size = 0;
    int fd = open(path, O_RDONLY);
    if (fd < 0) {
        snprintf(err, TL_ERR_LEN, "cannot open %s: %s", path, strerror(errno));
        return -1;
    }
    struct stat sb;
    if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        snprintf(err, TL_ERR_LEN, "%s is not a regular file", path);
        close(fd);
        return -1;
    }
    if ((uint64_t)sb.st_size > (uint64_t)SIZE_MAX - 1) {
        snprintf(err, TL_ERR_LEN, "%s is too large", path);
        close(fd);
        return -1;
    }
    size_t n = (size_t)sb.st_size;
    uint8_t *buf = malloc(n ? n : 1);
    if (!buf) {
        snprintf(err, TL_ERR_LEN, "out of memory reading %s (%zu bytes)", path, n);
        close(fd);
        return -1;
    }
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, buf + got, n - got);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) {
            snprintf(err, TL_ERR_LEN, "cannot read %s: %s", path, r < 0 ? strerror(errno) : "file shrank while reading");
            free(buf);
            close(fd);
            return -1;
        }
        got += (size_t)r;
    }
    close(fd);
    *data = buf;
    *size = n;
    return 0;
}

int tl_write_file_atomic(const char *path, const void *data, size_t size, char err[TL_ERR_LEN])
{
    if (tl_guard_replaceable(path, err) != 0 || tl_guard_check_active(path, err) != 0) return -1;
    tl_remove_stale_temps(path, 0, NULL, NULL); /* what a killed earlier write of it left */
    size_t plen = strlen(path);
    char *tmp = malloc(plen + 32);
    if (!tmp) {
        snprintf(err, TL_ERR_LEN, "out of memory");
        return -1;
    }
    snprintf(tmp, plen + 32, "%s.tmp.%ld", path, (long)getpid());
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        snprintf(err, TL_ERR_LEN, "cannot create %s: %s", tmp, strerror(errno));
        free(tmp);
        return -1;
    }
    const uint8_t *p = data;
    size_t done = 0;
    int ok = 1;
    while (done < size) {
        ssize_t w = write(fd, p + done, size - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            ok = 0;
            break;
        }
        done += (size_t)w;
    }
    if (ok && fsync(fd) != 0) ok = 0;
    int saved = errno;
    if (close(fd) != 0 && ok) ok = 0, saved = errno;
    if (ok && tl_guard_replaceable(path, err) != 0) { /* it became a device while we wrote */
        unlink(tmp);
        free(tmp);
        return -1;
    }
    if (ok && rename(tmp, path) != 0) ok = 0, saved = errno;
    if (!ok) {
        snprintf(err, TL_ERR_LEN, "cannot write %s: %s", path, strerror(saved));
        unlink(tmp);
        free(tmp);
        return -1;
    }
    free(tmp);
    return 0;
}

int tl_write_text(const char *path, const char *text, char err[TL_ERR_LEN])
{
    return tl_write_file_atomic(path, text, strlen(text), err);
}

double tl_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* "XXXXXX" of mkstemp: exactly six letters or digits. */
static int mkstemp_tail(const char *s)
{
    int n = 0;
    for (; s[n]; n++)
        if (!((s[n] >= 'a' && s[n] <= 'z') || (s[n] >= 'A' && s[n] <= 'Z') || (s[n] >= '0' && s[n] <= '9'))) return 0;
    return n == 6;
}

/* A decimal pid of a process that is gone (kill(pid, 0) says ESRCH). */
static int dead_pid_tail(const char *s)
{
    if (!*s || strlen(s) > 10) return 0;
    long pid = 0;
    for (const char *p = s; *p; p++) {
        if (*p < '0' || *p > '9') return 0;
        pid = pid * 10 + (*p - '0');
    }
    return pid > 0 && pid != (long)getpid() && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
}

int tl_remove_stale_temps(const char *path, time_t before, void (*removed)(void *user, const char *file), void *user)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    char dir[4096];
    if (slash) {
        size_t n = (size_t)(slash - path);
        if (n >= sizeof dir) return 0;
        memcpy(dir, path, n);
        dir[n ? n : 1] = 0;
        if (!n) dir[0] = '/';
    } else {
        strcpy(dir, ".");
    }
    const size_t blen = strlen(base);
    DIR *d = opendir(dir);
    if (!d || !blen) {
        if (d) closedir(d);
        return 0;
    }
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        const char *name = e->d_name;
        if (strncmp(name, base, blen) != 0) continue;
        const char *tail = name + blen;
        int lib = strncmp(tail, ".tmp-", 5) == 0 && mkstemp_tail(tail + 5);
        int tool = !lib && strncmp(tail, ".tmp.", 5) == 0 && dead_pid_tail(tail + 5);
        if (!lib && !tool) continue;
        char full[8192];
        snprintf(full, sizeof full, "%s/%s", dir, name);
        struct stat st;
        if (lstat(full, &st) != 0 || !S_ISREG(st.st_mode)) continue;
        if (lib && !(st.st_mtime < before)) continue; /* may belong to a write still running */
        if (unlink(full) == 0) {
            count++;
            if (removed) removed(user, full);
        }
    }
    closedir(d);
    return count;
}
