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
#include <time.h>
#include <unistd.h>

/* A thread about to sleep on a condition (a worker between batches, the caller waiting for
 * its batch's last job) first watches the counter it waits on for up to pool->spin_us,
 * without the mutex: waking a sleeping thread costs tens of microseconds on a virtual machine,
 * and the daemon runs two batches a frame set. The counters watched (batch, finished) are
 * written with __atomic stores, under the mutex as before, so that these unlocked reads are
 * not data races; whatever the spin sees, the thread then takes the mutex and decides under
 * it, as without the spin. rp_pool_stop bumps batch too, which ends a worker's spin at once. */
static unsigned load_u(const unsigned *v)
{
    return __atomic_load_n(v, __ATOMIC_ACQUIRE);
}

static int64_t now_ns(void)
{
    struct timespec t;
    /* ignored: CLOCK_MONOTONIC exists on every POSIX system this runs on */
    (void)clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

/* Watches *v until it is no longer `old` (1) or spin_us have passed (0); called without the
 * mutex. */
static int spin_while(const unsigned *v, unsigned old, unsigned spin_us)
{
    if (spin_us == 0) {
        return 0;
    }
    const int64_t end = now_ns() + (int64_t)spin_us * 1000;
    for (unsigned i = 1;; ++i) {
        if (load_u(v) != old) {
            return 1;
        }
        if ((i & 63u) == 0 && now_ns() >= end) {
            return 0;
        }
    }
}

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
        const unsigned finished = pool->finished + 1;
        __atomic_store_n(&pool->finished, finished, __ATOMIC_RELEASE);
        if (finished == pool->n_jobs) {
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
        if (pool->batch == seen && !pool->quit) {
            pthread_mutex_unlock(&pool->mu);
            /* ignored: only a hint; the mutex decides below */
            (void)spin_while(&pool->batch, seen, pool->spin_us);
            pthread_mutex_lock(&pool->mu);
        }
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
    pool->spin_us = RP_POOL_SPIN_US;
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
    __atomic_store_n(&pool->finished, 0u, __ATOMIC_RELEASE);
    __atomic_store_n(&pool->batch, pool->batch + 1, __ATOMIC_RELEASE);
    pthread_cond_broadcast(&pool->go);
    drain(pool);
    if (pool->finished < pool->n_jobs) { /* jobs still running on workers */
        const unsigned finished = pool->finished;
        pthread_mutex_unlock(&pool->mu);
        /* ignored: only a hint; the mutex decides below */
        (void)spin_while(&pool->finished, finished, pool->spin_us);
        pthread_mutex_lock(&pool->mu);
    }
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
    __atomic_store_n(&pool->batch, pool->batch + 1, __ATOMIC_RELEASE); /* ends a spin at once */
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
