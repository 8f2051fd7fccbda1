/*
 * rp_pool.h - a small fixed pool of worker threads (POSIX threads) that runs a batch of jobs
 * and waits for all of them: the daemon's one thread per camera (issue 17). core/ starts no
 * thread; the pool lives here, beside the HAL.
 *
 *   rp_pool_start(&pool, n)        n threads in all: the caller and n - 1 workers created now
 *   rp_pool_run(&pool, k, fn, arg) fn(arg, 0) .. fn(arg, k - 1), each exactly once, spread over
 *                                  the caller and the workers; returns when all have returned
 *   rp_pool_submit(&pool, k, fn, arg), later rp_pool_wait(&pool)
 *                                  the same batch in two halves: the workers start on it at
 *                                  once while the caller does something else, then the caller
 *                                  joins them on the jobs left and waits for the batch's end
 *   rp_pool_stop(&pool)            joins the workers
 *
 * A batch is handed out one job at a time (the next free job goes to the next free thread), so
 * a slow job does not hold back the others. Jobs of one batch must not touch each other's
 * memory; then the result is the same whatever thread ran what, and with n = 1 the jobs run in
 * order on the caller's thread (no thread is created; a submitted batch then runs in
 * rp_pool_wait). Everything a job writes is visible to the caller when rp_pool_run /
 * rp_pool_wait returns (a mutex orders it), and everything the caller wrote before
 * rp_pool_run / rp_pool_submit is visible to the jobs. Between rp_pool_submit and rp_pool_wait
 * the caller must not touch what the batch's jobs touch.
 *
 * No allocation after rp_pool_start (the threads' stacks are the only memory it takes), no
 * thread created or destroyed per batch. One caller at a time per pool, and one batch at a
 * time: rp_pool_run, rp_pool_submit and rp_pool_stop first wait for a batch still pending.
 */
#ifndef RP_POOL_H
#define RP_POOL_H

#include <pthread.h>
#include <stdint.h>

#include "rigpose/rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Threads of a pool, the caller's included. */
#ifndef RP_POOL_MAX_THREADS
#define RP_POOL_MAX_THREADS 16
#endif

typedef void (*rp_pool_fn_t)(void *arg, unsigned job);

/* Caller-owned; fields are private. */
typedef struct {
    uint8_t started;
    unsigned n_workers;               /* threads besides the caller */
    pthread_t th[RP_POOL_MAX_THREADS];
    pthread_mutex_t mu;
    pthread_cond_t go;                /* a new batch, or stop */
    pthread_cond_t done;              /* the batch's last job returned */
    unsigned batch;                   /* batches handed out so far */
    unsigned n_jobs, next, finished;  /* the current batch */
    rp_pool_fn_t fn;
    void *arg;
    uint8_t quit;
    uint8_t pending;                  /* a batch submitted, not yet waited for (the caller's) */
} rp_pool_t;

/* Starts a pool of n_threads threads in all (the caller is one of them; 1: no worker).
 * RP_E_ARG: NULL, n_threads 0 or above RP_POOL_MAX_THREADS, or the pool already started;
 * RP_E_FULL: the system refused a thread (the pool is then left stopped, nothing running). */
rp_status_t rp_pool_start(rp_pool_t *pool, unsigned n_threads);

/* Runs fn(arg, j) for j = 0 .. n_jobs - 1 and returns when every call has returned (n_jobs 0:
 * at once). RP_E_ARG: NULL pool or fn, or the pool not started. */
rp_status_t rp_pool_run(rp_pool_t *pool, unsigned n_jobs, rp_pool_fn_t fn, void *arg);

/* rp_pool_run in two halves. rp_pool_submit hands out fn(arg, 0) .. fn(arg, n_jobs - 1) to the
 * workers and returns at once (after waiting for a batch still pending); rp_pool_wait runs the
 * jobs no worker has taken yet on the caller's thread and returns when every job has returned
 * (at once if no batch is pending). With no worker (a pool of 1 thread) the jobs all run in
 * rp_pool_wait, in order. RP_E_ARG: NULL pool or fn, or the pool not started. */
rp_status_t rp_pool_submit(rp_pool_t *pool, unsigned n_jobs, rp_pool_fn_t fn, void *arg);
rp_status_t rp_pool_wait(rp_pool_t *pool);

/* Threads of the pool, the caller's included (0 if not started or NULL). */
unsigned rp_pool_threads(const rp_pool_t *pool);

/* Waits for a batch still pending, stops and joins the workers; the pool may be started again. NULL or not started: nothing. */
void rp_pool_stop(rp_pool_t *pool);

/* Cores online now (sysconf), at least 1. */
unsigned rp_pool_online_cores(void);

#ifdef __cplusplus
}
#endif

#endif /* RP_POOL_H */
