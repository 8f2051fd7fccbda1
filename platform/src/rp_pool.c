/*
 * rp_pool.c - the fixed worker pool (rp_pool.h).
 *
 * One mutex guards the batch: which jobs are handed out (next), how many returned (finished)
 * and the batch counter the workers wait on. A job runs outside the mutex; taking and
 * returning a job are the only locked steps, a few per job (jobs are a camera's front end,
 * milliseconds each).
 */
#include "rigpose/rp_pool.h"

#include <string.h>
#include <unistd.h>

/* Takes and runs jobs of the current batch until none is left; called with pool->mu held,
 * returns with it held. */
static void drain(rp_pool_t *pool)
{
    while (pool->next < pool->n_jobs) {
        const unsigned j = pool->next++;
        const rp_pool_fn_t fn = pool->fn;
        void *arg = pool->arg;
        pthread_mutex_unlock(&pool->mu);
        fn(arg, j);
        pthread_mutex_lock(&pool->mu);
        if (++pool->finished == pool->n_jobs) {
            pthread_cond_signal(&pool->done);
        }
    }
}

static void *worker(void *p)
{
    rp_pool_t *pool = (rp_pool_t *)p;
    pthread_mutex_lock(&pool->mu);
    unsigned seen = pool->batch;
    for (;;) {
        while (pool->batch == seen && !pool->quit) {
            pthread_cond_wait(&pool->go, &pool->mu);
        }
        if (pool->quit) {
            break;
        }
        seen = pool->batch;
        drain(pool);
    }
    pthread_mutex_unlock(&pool->mu);
    return NULL;
}

rp_status_t rp_pool_start(rp_pool_t *pool, unsigned n_threads)
{
    if (pool == NULL || n_threads == 0 || n_threads > RP_POOL_MAX_THREADS ||
        pool->started == 1) {
        return RP_E_ARG;
    }
    memset(pool, 0, sizeof *pool);
    if (pthread_mutex_init(&pool->mu, NULL) != 0) {
        return RP_E_FULL;
    }
    if (pthread_cond_init(&pool->go, NULL) != 0) {
        pthread_mutex_destroy(&pool->mu);
        return RP_E_FULL;
    }
    if (pthread_cond_init(&pool->done, NULL) != 0) {
        pthread_cond_destroy(&pool->go);
        pthread_mutex_destroy(&pool->mu);
        return RP_E_FULL;
    }
    pool->started = 1;
    for (unsigned k = 0; k + 1 < n_threads; ++k) {
        if (pthread_create(&pool->th[k], NULL, worker, pool) != 0) {
            rp_pool_stop(pool); /* joins the ones created */
            return RP_E_FULL;
        }
        pool->n_workers = k + 1;
    }
    return RP_OK;
}

rp_status_t rp_pool_run(rp_pool_t *pool, unsigned n_jobs, rp_pool_fn_t fn, void *arg)
{
    if (pool == NULL || fn == NULL || pool->started != 1) {
        return RP_E_ARG;
    }
    if (pool->n_workers == 0) { /* in order, on this thread: the single-threaded run */
        for (unsigned j = 0; j < n_jobs; ++j) {
            fn(arg, j);
        }
        return RP_OK;
    }
    pthread_mutex_lock(&pool->mu);
    pool->fn = fn;
    pool->arg = arg;
    pool->n_jobs = n_jobs;
    pool->next = 0;
    pool->finished = 0;
    pool->batch++;
    pthread_cond_broadcast(&pool->go);
    drain(pool);
    while (pool->finished < pool->n_jobs) {
        pthread_cond_wait(&pool->done, &pool->mu);
    }
    pthread_mutex_unlock(&pool->mu);
    return RP_OK;
}

unsigned rp_pool_threads(const rp_pool_t *pool)
{
    return (pool != NULL && pool->started == 1) ? pool->n_workers + 1 : 0;
}

void rp_pool_stop(rp_pool_t *pool)
{
    if (pool == NULL || pool->started != 1) {
        return;
    }
    pthread_mutex_lock(&pool->mu);
    pool->quit = 1;
    pthread_cond_broadcast(&pool->go);
    pthread_mutex_unlock(&pool->mu);
    for (unsigned k = 0; k < pool->n_workers; ++k) {
        /* ignored: joining our own worker cannot fail (it exists and nobody else joins it) */
        (void)pthread_join(pool->th[k], NULL);
    }
    pthread_cond_destroy(&pool->done);
    pthread_cond_destroy(&pool->go);
    pthread_mutex_destroy(&pool->mu);
    pool->n_workers = 0;
    pool->started = 0;
}

unsigned rp_pool_online_cores(void)
{
    const long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1u : (unsigned)n;
}
