/* Dynamic-chunk parallel-for; see parallel.h. */
#include "scene/parallel.h"

#include <pthread.h>
#include <stdatomic.h>
#include <unistd.h>

int bk_online_cores(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > BK_MAX_THREADS ? BK_MAX_THREADS : (int)n;
}

int bk_thread_count(int requested)
{
    if (requested <= 0) return bk_online_cores();
    return requested > BK_MAX_THREADS ? BK_MAX_THREADS : requested;
}

typedef struct pl_job {
    bk_chunk_fn fn;
    void *user;
    size_t end, chunk;
    atomic_size_t next;
} pl_job;

typedef struct pl_worker { pl_job *job; int thread; } pl_worker;

static void *worker_main(void *arg)
{
    pl_worker *w = (pl_worker *)arg;
    pl_job *j = w->job;
    for (;;) {
        size_t b = atomic_fetch_add(&j->next, j->chunk);
        if (b >= j->end) break;
        size_t e = b + j->chunk < j->end ? b + j->chunk : j->end;
        j->fn(j->user, b, e, w->thread);
    }
    return NULL;
}

void bk_parallel_chunks(size_t begin, size_t end, size_t chunk, int threads, bk_chunk_fn fn, void *user)
{
    if (end <= begin) return;
    size_t n = end - begin;
    pl_job job;
    job.fn = fn; job.user = user; job.end = end; job.chunk = chunk ? chunk : 1;
    atomic_init(&job.next, begin);
    int t = threads;
    if ((size_t)t > (n + job.chunk - 1) / job.chunk) t = (int)((n + job.chunk - 1) / job.chunk);
    if (t < 1) t = 1;
    pthread_t tids[BK_MAX_THREADS];
    pl_worker ws[BK_MAX_THREADS];
    int started = 0;
    for (int i = 1; i < t && i < BK_MAX_THREADS; i++) {
        ws[i].job = &job; ws[i].thread = i;
        if (pthread_create(&tids[i], NULL, worker_main, &ws[i]) != 0) break;
        started = i;
    }
    ws[0].job = &job; ws[0].thread = 0;
    worker_main(&ws[0]);
    for (int i = 1; i <= started; i++) pthread_join(tids[i], NULL);
}
