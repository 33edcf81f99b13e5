/* lbk view --port: a small HTTP/1.0 file server for the page folder, bound to 127.0.0.1 only.
 * Everything a request says is untrusted: the request line is parsed strictly, the path is checked
 * character by character before it touches the file system, files are opened relative to the
 * folder without following symbolic links, and only regular files are sent. One request per
 * connection (Connection: close), one connection at a time: the viewer loads a dozen files. */
#include "tools/view/view.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define REQUEST_MAX 8192
#define REQUEST_TIMEOUT_MS 5000

int tl_view_listen(uint16_t port, uint16_t *bound_port, char err[TL_ERR_LEN])
{
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        snprintf(err, TL_ERR_LEN, "socket: %s", strerror(errno));
        return -1;
    }
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK); /* never another interface */
    socklen_t n = sizeof a;
    if (bind(fd, (struct sockaddr *)&a, sizeof a) || listen(fd, 16) || getsockname(fd, (struct sockaddr *)&a, &n)) {
        snprintf(err, TL_ERR_LEN, "127.0.0.1:%u: %s", (unsigned)port, strerror(errno));
        close(fd);
        return -1;
    }
    if (bound_port) *bound_port = ntohs(a.sin_port);
    return fd;
}

static long now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long)t.tv_sec * 1000 + t.tv_nsec / 1000000;
}

/* Reads until the end of the header block ("\r\n\r\n"); returns its length, or -1 (too long,
 * too slow, closed). */
static int read_request(int fd, char *buf)
{
    size_t n = 0;
    const long deadline = now_ms() + REQUEST_TIMEOUT_MS;
    for (;;) {
        const long left = deadline - now_ms();
        if (left <= 0) return -1;
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, (int)left) <= 0) return -1;
        const ssize_t r = recv(fd, buf + n, REQUEST_MAX - n, 0);
        if (r <= 0) return -1;
        n += (size_t)r;
        buf[n] = 0;
        if (strstr(buf, "\r\n\r\n") || strstr(buf, "\n\n")) return (int)n;
        if (n == REQUEST_MAX) return -1;
    }
}

static void send_all(int fd, const void *data, size_t size)
{
    const char *p = data;
    while (size) {
        const ssize_t w = send(fd, p, size, MSG_NOSIGNAL);
        if (w <= 0) return; /* the client went away: nothing to do */
        p += w, size -= (size_t)w;
    }
}

static void send_status(int fd, int code, const char *reason)
{
    char h[256];
    const int n = snprintf(h, sizeof h,
                           "HTTP/1.0 %d %s\r\nContent-Type: text/plain\r\nContent-Length: %zu\r\nConnection: close\r\n\r\n%s\n",
                           code, reason, strlen(reason) + 1, reason);
    send_all(fd, h, (size_t)n);
}

static const char *content_type(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot) return "application/octet-stream";
    if (!strcmp(dot, ".html")) return "text/html; charset=utf-8";
    if (!strcmp(dot, ".js")) return "text/javascript; charset=utf-8";
    if (!strcmp(dot, ".png")) return "image/png";
    if (!strcmp(dot, ".glb")) return "model/gltf-binary";
    return "application/octet-stream";
}

/* The request target as a relative path of dir, or NULL when it is not one this server hands out:
 * '/'-separated segments of [A-Za-z0-9._-], none empty, "." or "..", none starting with '.'. */
static const char *safe_path(char *target)
{
    if (target[0] != '/') return NULL;
    char *q = strpbrk(target, "?#");
    if (q) *q = 0; /* the page's own parameters live in the hash */
    if (!strcmp(target, "/")) return "index.html";
    const char *rel = target + 1;
    const char *seg = rel;
    for (const char *c = rel;; c++) {
        if (*c == '/' || *c == 0) {
            if (c == seg || *seg == '.') return NULL;
            if (*c == 0) break;
            seg = c + 1;
            continue;
        }
        const int ok = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') || *c == '.' ||
                       *c == '_' || *c == '-';
        if (!ok) return NULL;
    }
    return strlen(rel) < 1024 ? rel : NULL;
}

/* Opens rel under dir_fd segment by segment with O_NOFOLLOW: no symbolic link anywhere on the way. */
static int open_beneath(int dir_fd, const char *rel)
{
    char part[1024];
    int cur = dup(dir_fd);
    while (cur >= 0) {
        const char *slash = strchr(rel, '/');
        const size_t n = slash ? (size_t)(slash - rel) : strlen(rel);
        memcpy(part, rel, n);
        part[n] = 0;
        const int next = openat(cur, part, (slash ? O_DIRECTORY : 0) | O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
        close(cur);
        if (!slash) return next;
        cur = next;
        rel = slash + 1;
    }
    return -1;
}

static void answer(int fd, int dir_fd)
{
    char buf[REQUEST_MAX + 1];
    if (read_request(fd, buf) < 0) return;
    char method[8], target[2048], version[16];
    if (sscanf(buf, "%7s %2047s %15s", method, target, version) != 3 || strncmp(version, "HTTP/1.", 7)) {
        send_status(fd, 400, "Bad Request");
        return;
    }
    const int head = !strcmp(method, "HEAD");
    if (strcmp(method, "GET") && !head) {
        send_status(fd, 405, "Method Not Allowed");
        return;
    }
    const char *rel = safe_path(target);
    if (!rel) {
        send_status(fd, 403, "Forbidden");
        return;
    }
    const int f = open_beneath(dir_fd, rel);
    struct stat st;
    if (f < 0 || fstat(f, &st) || !S_ISREG(st.st_mode)) {
        if (f >= 0) close(f);
        send_status(fd, 404, "Not Found");
        return;
    }
    char h[512];
    const int n = snprintf(h, sizeof h,
                           "HTTP/1.0 200 OK\r\nContent-Type: %s\r\nContent-Length: %lld\r\nCache-Control: no-store\r\n"
                           "X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
                           content_type(rel), (long long)st.st_size);
    send_all(fd, h, (size_t)n);
    char chunk[65536];
    ssize_t r;
    while (!head && (r = read(f, chunk, sizeof chunk)) > 0) send_all(fd, chunk, (size_t)r);
    close(f);
}

int tl_view_serve(int listen_fd, const char *dir, volatile int *stop, unsigned max_requests, char err[TL_ERR_LEN])
{
    const int dir_fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir_fd < 0) {
        snprintf(err, TL_ERR_LEN, "%s: %s", dir, strerror(errno));
        return -1;
    }
    unsigned served = 0;
    while (!(stop && *stop) && (!max_requests || served < max_requests)) {
        struct pollfd p = {listen_fd, POLLIN, 0};
        const int pr = poll(&p, 1, 200);
        if (pr < 0 && errno == EINTR) continue;
        if (pr < 0) {
            snprintf(err, TL_ERR_LEN, "poll: %s", strerror(errno));
            close(dir_fd);
            return -1;
        }
        if (pr == 0) continue;
        const int c = accept(listen_fd, NULL, NULL);
        if (c < 0) continue; /* a client that gave up; keep serving */
        answer(c, dir_fd);
        close(c);
        served++;
    }
    close(dir_fd);
    return 0;
}
