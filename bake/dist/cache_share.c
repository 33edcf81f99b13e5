/* Shared radiosity caches between the units of a distributed run (cache_share.h, DIST.md
 * §Shared caches, spec/part.md §3 for the share file). */
#include "bake/dist/cache_share.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "lbk/byteorder.h"
#include "scene/clock.h"

#define XXH_INLINE_ALL
#include <xxhash.h>

#define CS_MAGIC "LBKCSHR\0"
#define CS_VERSION 1u
#define CS_HEADER 144u
#define CS_KEY 88u /* the header bytes that name the bounce and share */
#define CS_SUFFIX ".lbkcache"

struct bk_cache_share {
    char dir[4096];
    char host[256];
    uint64_t plan_hash, options_hash;
    double lease;
    lbk_bake_unit_stats st; /* (its size unused) */
};

static lbk_result say(char *err, size_t len, lbk_result r, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static lbk_result say(char *err, size_t len, lbk_result r, const char *fmt, ...)
{
    if (err && len) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, len, fmt, ap);
        va_end(ap);
    }
    return r;
}

lbk_result bk_cache_share_open(const char *dir, uint64_t plan_hash, uint64_t options_hash, double lease,
                               bk_cache_share **out, char *err, size_t err_len)
{
    *out = NULL;
    if (!dir || !dir[0] || strlen(dir) >= sizeof ((bk_cache_share *)0)->dir - 128) return LBK_ERR_INVALID_ARGUMENT;
    if (mkdir(dir, 0777) != 0 && errno != EEXIST)
        return say(err, err_len, LBK_ERR_IO, "cannot make the shared cache folder %s: %s", dir, strerror(errno));
    struct stat sb;
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode))
        return say(err, err_len, LBK_ERR_IO, "the shared cache folder %s is not a folder", dir);
    bk_cache_share *s = calloc(1, sizeof *s);
    if (!s) return LBK_ERR_OUT_OF_MEMORY;
    snprintf(s->dir, sizeof s->dir, "%s", dir);
    if (gethostname(s->host, sizeof s->host - 1) != 0) snprintf(s->host, sizeof s->host, "?");
    s->plan_hash = plan_hash;
    s->options_hash = options_hash;
    s->lease = lease > 0 ? lease : 600;
    *out = s;
    return LBK_OK;
}

void bk_cache_share_close(bk_cache_share *s) { free(s); }

void bk_cache_share_get_stats(const bk_cache_share *s, lbk_bake_unit_stats *st)
{
    const size_t size = st->size;
    if (s) *st = s->st;
    else memset(st, 0, sizeof *st);
    st->size = size;
}

typedef struct cs_key {
    uint32_t run, share, shares;
    const bk_cache_bounce *b;
    size_t begin, end; /* the share's cells */
} cs_key;

static void share_path(const bk_cache_share *s, const cs_key *k, const char *tail, char *path, size_t size)
{
    snprintf(path, size, "%s/r%u-p%d-h%d-b%d-s%uof%u%s%s", s->dir, k->run, k->b->pass, k->b->half, k->b->bounce,
             k->share, k->shares, CS_SUFFIX, tail);
}

/* ---- claims ------------------------------------------------------------------------------- */

/* A claim that no unit will publish: older than the lease, or made by a process of this host
 * that no longer runs. */
static int claim_stale(const bk_cache_share *s, const char *claim)
{
    struct stat sb;
    if (stat(claim, &sb) != 0) return errno == ENOENT;
    if (difftime(time(NULL), sb.st_mtime) > s->lease) return 1;
    FILE *f = fopen(claim, "r");
    if (!f) return 0;
    char host[256] = "";
    long pid = 0;
    int n = fscanf(f, "LBKCLAIM %255s %ld", host, &pid); /* (the share's bytes once it is being written) */
    fclose(f);
    return n == 2 && pid > 0 && !strcmp(host, s->host) && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
}

/* The claim's file, open (>= 0): this process computes the share and writes it there; -1:
 * another does (or did). One file per share: the claim becomes the share when it is renamed. */
static int claim(const bk_cache_share *s, const cs_key *k)
{
    char path[4352];
    share_path(s, k, ".claim", path, sizeof path);
    for (int attempt = 0; attempt < 2; attempt++) {
        int fd = open(path, O_RDWR | O_CREAT | O_EXCL, 0666);
        if (fd >= 0) {
            /* the claim is gone once its share is published (renamed): a share published between
             * this unit's look and its claim is read, not computed again */
            char done[4352];
            share_path(s, k, "", done, sizeof done);
            if (access(done, F_OK) == 0) {
                close(fd);
                unlink(path);
                return -1;
            }
            char line[300];
            int n = snprintf(line, sizeof line, "LBKCLAIM %s %ld\n", s->host, (long)getpid());
            ssize_t w = write(fd, line, (size_t)n);
            (void)w; /* the claim is the file; its text only names the owner */
            return fd;
        }
        /* a dead claim: computed again (same bytes; at worst two units both compute it) */
        if (errno != EEXIST || !claim_stale(s, path) || (unlink(path) != 0 && errno != ENOENT)) return -1;
    }
    return -1;
}

/* ---- share files -------------------------------------------------------------------------- */

static void put_header(const bk_cache_share *s, const cs_key *k, const uint64_t counts[3], double seconds,
                       uint8_t *h, const uint8_t *payload, size_t pay)
{
    memset(h, 0, CS_HEADER);
    memcpy(h, CS_MAGIC, 8);
    lbk_wr32(h + 8, CS_VERSION);
    lbk_wr32(h + 12, CS_HEADER);
    lbk_wr64(h + 16, s->plan_hash);
    lbk_wr64(h + 24, s->options_hash);
    lbk_wr32(h + 32, k->run);
    lbk_wr32(h + 36, (uint32_t)k->b->pass);
    lbk_wr32(h + 40, (uint32_t)k->b->half);
    lbk_wr32(h + 44, (uint32_t)k->b->bounce);
    lbk_wr32(h + 48, (uint32_t)k->b->rays);
    lbk_wr32(h + 52, k->share);
    lbk_wr32(h + 56, k->shares);
    lbk_wr64(h + 64, k->b->cells);
    lbk_wr64(h + 72, k->begin);
    lbk_wr64(h + 80, k->end);
    for (int a = 0; a < 3; a++) lbk_wr64(h + 88 + 8 * a, counts[a]);
    lbk_wrf64(h + 112, seconds);
    lbk_wr64(h + 120, XXH64(payload, pay, 0));
    lbk_wr64(h + 136, XXH64(h, 136, 0));
}

/* Writes the share into its claim's file fd and renames it onto the share's name; fd < 0 (a
 * damaged share computed again): through a temporary file. */
static lbk_result publish(bk_cache_share *s, const cs_key *k, int fd, const uint64_t counts[3], double seconds,
                          char *err, size_t err_len)
{
    const size_t nf = 3 * (k->end - k->begin), pay = 4 * nf;
    uint8_t *buf = malloc(CS_HEADER + (pay ? pay : 1));
    if (!buf) return LBK_ERR_OUT_OF_MEMORY;
    const float *src = k->b->out + 3 * k->begin;
    for (size_t i = 0; i < nf; i++) lbk_wrf32(buf + CS_HEADER + 4 * i, src[i]);
    put_header(s, k, counts, seconds, buf, buf + CS_HEADER, pay);
    char path[4352], tmp[4700];
    share_path(s, k, "", path, sizeof path);
    if (fd >= 0) share_path(s, k, ".claim", tmp, sizeof tmp);
    else snprintf(tmp, sizeof tmp, "%s.tmp.%s.%ld", path, s->host, (long)getpid());
    if (fd < 0) fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    /* no fsync: a share lost or damaged in a crash fails its checksum and is computed again */
    const size_t size = CS_HEADER + pay;
    int ok = fd >= 0 && pwrite(fd, buf, size, 0) == (ssize_t)size && ftruncate(fd, (off_t)size) == 0;
    if (fd >= 0 && close(fd) != 0) ok = 0;
    free(buf);
    /* ENOENT: a unit took the claim over as stale (this one outlived its lease) and publishes it */
    if (!ok || (rename(tmp, path) != 0 && errno != ENOENT)) {
        int e = errno;
        remove(tmp);
        return say(err, err_len, LBK_ERR_IO, "cannot write the cache share %s: %s", path, strerror(e));
    }
    s->st.shares_computed++;
    s->st.bytes_written += CS_HEADER + pay;
    return LBK_OK;
}

/* Reads a published share into b->out and adds its counts: 1 done, 0 not published yet (or
 * damaged: then *damaged = 1, and it is computed again), else a negated lbk_result. */
static int fetch(bk_cache_share *s, const cs_key *k, int *damaged, char *err, size_t err_len)
{
    *damaged = 0;
    char path[4352];
    share_path(s, k, "", path, sizeof path);
    FILE *f = fopen(path, "rb");
    if (!f) return errno == ENOENT ? 0 : -(int)say(err, err_len, LBK_ERR_IO, "%s: %s", path, strerror(errno));
    const double t0 = bk_now();
    const size_t nf = 3 * (k->end - k->begin), pay = 4 * nf;
    uint8_t *buf = malloc(CS_HEADER + pay + 1);
    size_t got = buf ? fread(buf, 1, CS_HEADER + pay + 1, f) : 0;
    fclose(f);
    if (!buf) return -(int)LBK_ERR_OUT_OF_MEMORY;
    uint8_t want[CS_HEADER];
    const uint64_t zero[3] = {0, 0, 0};
    if (!(got == CS_HEADER + pay && !memcmp(buf, CS_MAGIC, 8) && lbk_rd64(buf + 136) == XXH64(buf, 136, 0))) {
        free(buf);
        *damaged = 1;
        return 0;
    }
    put_header(s, k, zero, 0, want, buf + CS_HEADER, pay);
    if (memcmp(buf, want, CS_KEY)) { /* a whole file, of another bake */
        free(buf);
        return -(int)say(err, err_len, LBK_ERR_BAD_INPUT,
                         "the cache share %s is another bake's (another plan, options or lbk version): give each "
                         "plan and lbk build its own --cache-dir", path);
    }
    if (lbk_rd64(buf + 120) != lbk_rd64(want + 120)) {
        free(buf);
        *damaged = 1;
        return 0;
    }
    float *dst = k->b->out + 3 * k->begin;
    for (size_t i = 0; i < nf; i++) dst[i] = lbk_rdf32(buf + CS_HEADER + 4 * i);
    const uint64_t counts[3] = {lbk_rd64(buf + 88), lbk_rd64(buf + 96), lbk_rd64(buf + 104)};
    k->b->add_counts(k->b->ctx, counts);
    free(buf);
    s->st.shares_read++;
    s->st.bytes_read += CS_HEADER + pay;
    s->st.read_seconds += bk_now() - t0;
    return 1;
}

static lbk_result compute(bk_cache_share *s, const cs_key *k, int fd, char *err, size_t err_len)
{
    uint64_t counts[3];
    const double t0 = bk_now();
    lbk_result r = k->b->compute(k->b->ctx, k->begin, k->end, counts);
    const double dt = bk_now() - t0;
    s->st.compute_seconds += dt;
    if (!r) {
        const double t1 = bk_now();
        r = publish(s, k, fd, counts, dt, err, err_len);
        s->st.publish_seconds += bk_now() - t1;
        return r;
    }
    if (fd >= 0) { /* leaves no claim behind */
        char path[4352];
        share_path(s, k, ".claim", path, sizeof path);
        close(fd);
        unlink(path);
    }
    return r;
}

lbk_result bk_cache_share_bounce(bk_cache_share *s, uint32_t run, uint32_t shares, uint32_t mine,
                                 const bk_cache_bounce *b, char *err, size_t err_len)
{
    if (shares < 2 || shares > 65536) return LBK_ERR_INVALID_ARGUMENT;
    uint8_t *done = calloc(shares, 1);
    if (!done) return LBK_ERR_OUT_OF_MEMORY;
    const uint32_t first = mine < shares ? mine : 0;
    uint32_t left = shares;
    long nap_us = 500;
    lbk_result r = LBK_OK;
    while (left && !r) {
        int progress = 0;
        for (uint32_t j = 0; j < shares && !r; j++) {
            const uint32_t sh = (first + j) % shares;
            if (done[sh]) continue;
            cs_key k = {run, sh, shares, b, (size_t)((uint64_t)b->cells * sh / shares),
                        (size_t)((uint64_t)b->cells * (sh + 1) / shares)};
            int damaged, fd = -1, got = fetch(s, &k, &damaged, err, err_len);
            if (got < 0) r = (lbk_result)-got;
            else if (got == 0) {
                const double t0 = bk_now();
                if (!damaged) fd = claim(s, &k);
                if (fd >= 0) s->st.publish_seconds += bk_now() - t0; /* a file made: a share's cost */
                if (damaged || fd >= 0) r = compute(s, &k, fd, err, err_len), got = 1;
            }
            if (got == 1 && !r) done[sh] = 1, left--, progress = 1;
        }
        if (left && !progress && !r) { /* every missing share is being computed by a live unit */
            const double t0 = bk_now();
            struct timespec ts = {0, nap_us * 1000};
            nanosleep(&ts, NULL);
            s->st.wait_seconds += bk_now() - t0;
            if (nap_us < 50000) nap_us *= 2;
        } else {
            nap_us = 500;
        }
    }
    free(done);
    return r;
}

static int ours(const char *name)
{
    return name[0] == 'r' && (strstr(name, CS_SUFFIX ".claim") || strstr(name, CS_SUFFIX ".tmp.") ||
                              (strlen(name) > strlen(CS_SUFFIX) &&
                               !strcmp(name + strlen(name) - strlen(CS_SUFFIX), CS_SUFFIX)));
}

int bk_cache_share_remove(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return errno == ENOENT ? 0 : errno;
    int e = 0;
    struct dirent *de;
    char path[4608];
    while ((de = readdir(d))) {
        if (!ours(de->d_name)) continue;
        snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
        if (unlink(path) != 0 && errno != ENOENT) e = errno;
    }
    closedir(d);
    if (!e && rmdir(dir) != 0 && errno != ENOTEMPTY && errno != EEXIST) e = errno;
    return e;
}
