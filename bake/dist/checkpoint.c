/* Checkpoints of a bake's transport runs (bake/dist/checkpoint.h). */
#include "bake/dist/checkpoint.h"

#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "lbk/sh.h"

#define XXH_INLINE_ALL
#include <xxhash.h>

#define CK_MAGIC "LBKCKPT\0"
#define CK_VERSION 3u /* 2: the rough marks of the cache cells; 3: adaptive blocks' weights, mean samples */
#define CK_HEADER 64u
#define CK_SAMPLE 112u
#define CK_SCALARS (8 * 6 + 4 * 6 + 4 * 2 + 8 * 6 + 8 * 6)

struct bk_ckpt {
    char dir[4096];
    int resume;
    uint64_t options_hash;
    int run;                 /* the run in progress (-1 before the first) */
    int resumed, skipped;
    bk_transport_checkpoint tc;
    lbk_result code;         /* of the first error */
    char err[512];
};

static int fail(bk_ckpt *c, lbk_result r, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail(bk_ckpt *c, lbk_result r, const char *fmt, ...)
{
    if (!c->err[0]) {
        c->code = r;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->err, sizeof c->err, fmt, ap);
        va_end(ap);
    }
    return (int)r;
}

static uint32_t mask_of(const bk_transport_state *s)
{
    return 1u | (s->direct ? 2u : 0) | (s->irradiance ? 4u : 0);
}

static size_t payload_size(size_t n, int passes, uint32_t mask, size_t cells, size_t blocks)
{
    size_t per = 4 * 8 + 27 * 4 + ((mask & 2) ? 27 * 4 : 0) + ((mask & 4) ? 3 * 4 : 0);
    return CK_SCALARS + (size_t)passes * CK_SAMPLE + n * per + cells + 8 * blocks;
}

typedef struct cur {
    uint8_t *p;
} cur;
static void w(cur *c, const void *v, size_t n) { memcpy(c->p, v, n), c->p += n; }
static void r(cur *c, void *v, size_t n) { memcpy(v, c->p, n), c->p += n; }

static void run_path(const bk_ckpt *c, int run, char *path, size_t size)
{
    snprintf(path, size, "%s/run-%d.ckpt", c->dir, run);
}

static lbk_result ck_save(void *user, const bk_transport_state *s)
{
    bk_ckpt *c = user;
    const uint32_t mask = mask_of(s);
    const size_t n = s->count, pay = payload_size(n, s->passes, mask, s->cells, s->blocks);
    uint8_t *buf = malloc(CK_HEADER + pay);
    if (!buf) return LBK_ERR_OUT_OF_MEMORY;
    cur k = {buf + CK_HEADER};
    w(&k, s->weight_sum, 24), w(&k, s->spp, 24), w(&k, s->active, 12), w(&k, s->stop, 12), w(&k, s->chain_bounces, 8);
    w(&k, s->chain_q, 16), w(&k, s->chain_tail, 16), w(&k, s->chain_total, 16);
    const uint64_t counts[6] = {s->cache_rays, s->cache_shadow, s->cache_nonfinite, s->rays, s->shadow, s->nonfinite};
    w(&k, counts, sizeof counts);
    for (int p = 0; p < s->passes; p++) {
        const bk_transport_sample *sm = &s->samples[p];
        w(&k, &sm->seconds, 8), w(&k, &sm->samples_per_receiver, 8), w(&k, &sm->est_rel_rmse, 8);
        int32_t ib[2] = {sm->bounces, sm->pass};
        w(&k, ib, 8), w(&k, sm->class_rel_rmse, 24), w(&k, &sm->probe_rel_rmse, 8), w(&k, sm->class_samples, 24);
        w(&k, sm->class_mean_samples, 24);
    }
    for (int h = 0; h < 2; h++) w(&k, s->x_acc[h], 8 * n), w(&k, s->b_acc[h], 8 * n);
    w(&k, s->radiance, n * sizeof(lbk_sh9_rgb));
    if (mask & 2) w(&k, s->direct, n * sizeof(lbk_sh9_rgb));
    if (mask & 4) w(&k, s->irradiance, 12 * n);
    if (s->cells) w(&k, s->rough, s->cells);
    if (s->blocks) w(&k, s->block_weight, 8 * s->blocks);
    memset(buf, 0, CK_HEADER);
    memcpy(buf, CK_MAGIC, 8);
    uint32_t u32[4] = {CK_VERSION, mask, (uint32_t)c->run, (uint32_t)s->passes};
    uint64_t u64[4] = {c->options_hash, n, pay, XXH64(buf + CK_HEADER, pay, 0)};
    memcpy(buf + 8, u32, 16);
    memcpy(buf + 24, u64, 32);
    uint64_t hh = XXH64(buf, 56, 0);
    memcpy(buf + 56, &hh, 8);
    char path[4200], tmp[4300];
    run_path(c, c->run, path, sizeof path);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    int ok = f && fwrite(buf, 1, CK_HEADER + pay, f) == CK_HEADER + pay && fflush(f) == 0 && fsync(fileno(f)) == 0;
    if (f && fclose(f) != 0) ok = 0;
    free(buf);
    if (!ok || rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        return (lbk_result)fail(c, LBK_ERR_IO, "checkpoint %s: %s", path, strerror(e));
    }
    return LBK_OK;
}

static int ck_load(void *user, bk_transport_state *s)
{
    bk_ckpt *c = user;
    c->run++;
    if (!c->resume) return 0;
    char path[4200];
    run_path(c, c->run, path, sizeof path);
    FILE *f = fopen(path, "rb");
    if (!f) return errno == ENOENT ? 0 : -fail(c, LBK_ERR_IO, "checkpoint %s: %s", path, strerror(errno));
    uint8_t h[CK_HEADER];
    int got = fread(h, 1, CK_HEADER, f) == CK_HEADER;
    uint32_t u32[4];
    uint64_t u64[4], hh;
    memcpy(u32, h + 8, 16), memcpy(u64, h + 24, 32), memcpy(&hh, h + 56, 8);
    const uint32_t mask = mask_of(s);
    if (!got || memcmp(h, CK_MAGIC, 8) || hh != XXH64(h, 56, 0) || u32[0] != CK_VERSION) {
        fclose(f);
        return -fail(c, LBK_ERR_BAD_INPUT, "checkpoint %s: not an lbk checkpoint, or corrupt", path);
    }
    if (u64[0] != c->options_hash || u64[1] != s->count || u32[1] != mask || u32[2] != (uint32_t)c->run) {
        fclose(f);
        return -fail(c, LBK_ERR_BAD_INPUT, "checkpoint %s is of another bake (other scene or options): bake without "
                     "--resume, or with the options it was made with", path);
    }
    const int passes = (int)u32[3];
    if (passes < 1 || passes > BK_TRANSPORT_MAX_PASSES || u64[2] != payload_size(s->count, passes, mask, s->cells, s->blocks)) {
        fclose(f);
        return -fail(c, LBK_ERR_BAD_INPUT, "checkpoint %s: corrupt", path);
    }
    uint8_t *buf = malloc(u64[2]);
    got = buf && fread(buf, 1, u64[2], f) == u64[2] && fgetc(f) == EOF;
    fclose(f);
    if (!got || XXH64(buf, u64[2], 0) != u64[3]) {
        free(buf);
        return -fail(c, LBK_ERR_BAD_INPUT, "checkpoint %s: truncated or corrupt", path);
    }
    const size_t n = s->count;
    cur k = {buf};
    s->passes = passes;
    r(&k, s->weight_sum, 24), r(&k, s->spp, 24), r(&k, s->active, 12), r(&k, s->stop, 12), r(&k, s->chain_bounces, 8);
    r(&k, s->chain_q, 16), r(&k, s->chain_tail, 16), r(&k, s->chain_total, 16);
    uint64_t counts[6];
    r(&k, counts, sizeof counts);
    s->cache_rays = counts[0], s->cache_shadow = counts[1], s->cache_nonfinite = counts[2];
    s->rays = counts[3], s->shadow = counts[4], s->nonfinite = counts[5];
    for (int p = 0; p < passes; p++) {
        bk_transport_sample *sm = &s->samples[p];
        r(&k, &sm->seconds, 8), r(&k, &sm->samples_per_receiver, 8), r(&k, &sm->est_rel_rmse, 8);
        int32_t ib[2];
        r(&k, ib, 8), r(&k, sm->class_rel_rmse, 24), r(&k, &sm->probe_rel_rmse, 8), r(&k, sm->class_samples, 24);
        r(&k, sm->class_mean_samples, 24);
        sm->bounces = ib[0], sm->pass = ib[1];
    }
    for (int hh2 = 0; hh2 < 2; hh2++) r(&k, s->x_acc[hh2], 8 * n), r(&k, s->b_acc[hh2], 8 * n);
    r(&k, s->radiance, n * sizeof(lbk_sh9_rgb));
    if (mask & 2) r(&k, s->direct, n * sizeof(lbk_sh9_rgb));
    if (mask & 4) r(&k, s->irradiance, 12 * n);
    if (s->cells) r(&k, s->rough, s->cells);
    if (s->blocks) r(&k, s->block_weight, 8 * s->blocks);
    free(buf);
    c->resumed++;
    c->skipped += passes;
    return 1;
}

/* A fresh bake's checkpoints must not be mistaken for the next resume's: remove run-*.ckpt. */
static void clear_runs(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d))) {
        int run;
        char tail[8];
        if (sscanf(e->d_name, "run-%d.ckp%1s", &run, tail) == 2 && !strcmp(tail, "t") && strlen(e->d_name) < 64) {
            char path[4200];
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            unlink(path);
        }
    }
    closedir(d);
}

lbk_result bk_ckpt_create(const char *dir, int resume, uint64_t options_hash, bk_ckpt **out, char *err, size_t err_len)
{
    *out = NULL;
    if (!dir || !*dir || strlen(dir) >= 4000) return LBK_ERR_INVALID_ARGUMENT;
    struct stat st;
    if (resume && stat(dir, &st) != 0) {
        snprintf(err, err_len, "--resume %s: %s (no checkpoint to resume from)", dir, strerror(errno));
        return LBK_ERR_IO;
    }
    if (!resume && mkdir(dir, 0755) != 0 && errno != EEXIST) {
        snprintf(err, err_len, "--checkpoint %s: %s", dir, strerror(errno));
        return LBK_ERR_IO;
    }
    bk_ckpt *c = calloc(1, sizeof *c);
    if (!c) return LBK_ERR_OUT_OF_MEMORY;
    snprintf(c->dir, sizeof c->dir, "%s", dir);
    if (!resume) clear_runs(dir);
    c->resume = resume;
    c->options_hash = options_hash;
    c->run = -1;
    c->tc.user = c;
    c->tc.save = ck_save;
    c->tc.load = ck_load;
    *out = c;
    return LBK_OK;
}

void bk_ckpt_destroy(bk_ckpt *c) { free(c); }
const bk_transport_checkpoint *bk_ckpt_transport(const bk_ckpt *c) { return &c->tc; }
const char *bk_ckpt_error(const bk_ckpt *c) { return c ? c->err : ""; }
lbk_result bk_ckpt_code(const bk_ckpt *c) { return c ? c->code : LBK_OK; }
void bk_ckpt_counts(const bk_ckpt *c, int *resumed_runs, int *skipped_passes)
{
    *resumed_runs = c->resumed;
    *skipped_passes = c->skipped;
}
