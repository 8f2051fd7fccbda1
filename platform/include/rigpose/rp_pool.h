/*
 * rp_pool.h - a small fixed pool of worker threads (POSIX threads) that runs a batch of jobs
 * and waits for all of them: the daemon's one thread per camera (issue 17). core/ starts no
 * thread; the pool lives here, beside the HAL.
 *
 *   rp_pool_start(&pool, n)        n threads in all: the caller and n - 1 workers created now
 *   rp_pool_run(&pool, k, fn, arg) fn(arg, 0) .. fn(arg, k - 1), each exactly once, spread over
 *                                  the caller and the workers; returns when all have returned
 *   rp_pool_stop(&pool)            joins the workers
 *
 * A batch is handed out one job at a time (the next free job goes to the next free thread), so
 * a slow job does not hold back the others. Jobs of one batch must not touch each other's
 * memory; then the result is the same whatever thread ran what, and with n = 1 the jobs run in
 * order on the caller's thread (no thread is created). Everything a job writes is visible to
 * the caller when rp_pool_run returns (a mutex orders it), and everything the caller wrote
 * before rp_pool_run is visible to the jobs.
 *
 * No allocation after rp_pool_start (the threads' stacks are the only memory it takes), no
 * thread created or destroyed per batch. One caller at a time per pool.
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

/* How long (us) a thread of the pool about to sleep first watches for a new batch (a worker)
 * or for its batch's end (the caller), without sleeping: a sleeping thread's wake-up costs
 * tens of microseconds on a virtual machine, a spin only the core's time while the pool
 * idles. 0: sleep at once. */
#ifndef RP_POOL_SPIN_US
#define RP_POOL_SPIN_US 200u
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
    unsigned batch;                   /* batches handed out so far (stop adds one more) */
    unsigned n_jobs, next, finished;  /* the current batch */
    rp_pool_fn_t fn;
    void *arg;
    uint8_t quit;
    unsigned spin_us;                 /* RP_POOL_SPIN_US */
} rp_pool_t;

/* Starts a pool of n_threads threads in all (the caller is one of them; 1: no worker).
 * RP_E_ARG: NULL, n_threads 0 or above RP_POOL_MAX_THREADS, or the pool already started;
 * RP_E_FULL: the system refused a thread (the pool is then left stopped, nothing running). */
rp_status_t rp_pool_start(rp_pool_t *pool, unsigned n_threads);

/* Runs fn(arg, j) for j = 0 .. n_jobs - 1 and returns when every call has returned (n_jobs 0:
 * at once). RP_E_ARG: NULL pool or fn, or the pool not started. */
rp_status_t rp_pool_run(rp_pool_t *pool, unsigned n_jobs, rp_pool_fn_t fn, void *arg);

/* Threads of the pool, the caller's included (0 if not started or NULL). */
unsigned rp_pool_threads(const rp_pool_t *pool);

/* Stops and joins the workers; the pool may be started again. NULL or not started: nothing. */
void rp_pool_stop(rp_pool_t *pool);

/* Cores online now (sysconf), at least 1. */
unsigned rp_pool_online_cores(void);

#ifdef __cplusplus
}
#endif

#endif /* RP_POOL_H */
