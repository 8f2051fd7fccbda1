/*
 * rp_est.c - the configured estimator: configuration -> rp_pipe, its trackers on a pool of
 * threads (rp_est.h). The pipeline's configuration is the parser's (rp_config.h: the core's
 * defaults with the file's keys) as it is.
 */
#include "rp_est.h"

#include <string.h>

#include "rp_prefault.h"

unsigned rp_est_threads_for(const rp_config_t *cfg, unsigned online_cores)
{
    if (cfg == NULL) {
        return 1;
    }
    if (cfg->threads > 0) {
        return cfg->threads <= RP_POOL_MAX_THREADS ? cfg->threads : RP_POOL_MAX_THREADS;
    }
    if (cfg->hal.kind == RP_HAL_SRC_SIM || cfg->hal.kind == RP_HAL_SRC_LCM) {
        return 1; /* features, no images: no tracker runs, no job for another thread */
    }
    /* one per tracker: stereo layouts track both cameras of each pair, gc and rc their
     * cameras, camK one */
    const rp_pipe_layout_t l = cfg->pipe.layout;
    unsigned cams = l == RP_PIPE_STEREO4 ? 4u
                    : l == RP_PIPE_STEREO2 ? 2u
                    : l == RP_PIPE_GC      ? cfg->pipe.gc.n_cams
                    : l == RP_PIPE_RC      ? (unsigned)cfg->pipe.rc_n
                                           : 1u;
    unsigned n = online_cores < cams ? online_cores : cams;
    return n < 1 ? 1u : n > RP_POOL_MAX_THREADS ? RP_POOL_MAX_THREADS : n;
}

rp_status_t rp_est_init(rp_est_t *est, const rp_config_t *cfg)
{
    if (est == NULL || cfg == NULL) {
        return RP_E_ARG;
    }
    rp_est_close(est);
    const rp_status_t st = rp_pipe_init(&est->pipe, &cfg->rig, &cfg->pipe);
    if (st != RP_OK) {
        return st;
    }
    rp_prefault(&est->pipe, sizeof(est->pipe)); /* before the pool's threads start */
    for (uint8_t t = 0; t < RP_PIPE_MAX_TRACKERS; ++t) {
        est->trk_pair[t] = -1;
    }
    for (uint8_t k = 0; k < rp_pipe_n_pairs(&est->pipe); ++k) {
        uint8_t ta, tb;
        /* ignored: k is a pair of the layout: RP_OK */
        (void)rp_pipe_pair_trackers(&est->pipe, k, &ta, &tb);
        est->trk_pair[ta] = (int8_t)k;
        est->trk_pair[tb] = (int8_t)k;
    }
    if (pthread_mutex_init(&est->mu, NULL) != 0) {
        return RP_E_FULL;
    }
    est->mu_ok = 1;
    return rp_pool_start(&est->pool, rp_est_threads_for(cfg, rp_pool_online_cores()));
}

void rp_est_close(rp_est_t *est)
{
    if (est != NULL) {
        rp_pool_stop(&est->pool);
        if (est->mu_ok) {
            pthread_mutex_destroy(&est->mu);
            est->mu_ok = 0;
        }
    }
}

unsigned rp_est_threads(const rp_est_t *est)
{
    const unsigned n = est != NULL ? rp_pool_threads(&est->pool) : 0;
    return n > 0 ? n : 1;
}

int rp_est_hal_jobs(void *ctx, unsigned n_jobs, void (*fn)(void *arg, unsigned job), void *arg)
{
    rp_est_t *est = (rp_est_t *)ctx;
    if (est == NULL || fn == NULL) {
        return -1;
    }
    return rp_pool_run(&est->pool, n_jobs, fn, arg) == RP_OK ? 0 : -1;
}

rp_status_t rp_est_step(rp_est_t *est, const rp_frameset_t *fs, rp_estimate_t *out)
{
    if (est == NULL) {
        if (out != NULL) {
            memset(out, 0, sizeof *out);
            out->flags = RP_EST_LOST;
        }
        return RP_E_ARG;
    }
    return rp_pipe_step_feats(&est->pipe, fs, out);
}

/* Job j of a set: tracker order[j] on its camera's image; if that was the last of a stereo
 * pair's two trackers to return, the pair's matching too (rp_pipe.h: a pair waits only for
 * its own trackers), so no thread waits for a separate matching batch. */
static void track_job(void *arg, unsigned j)
{
    rp_est_t *est = (rp_est_t *)arg;
    const uint8_t t = est->order[j];
    /* ignored: RP_E_ARG only for a step not begun or t out of range, which the caller rules
     * out; the tracker's own outcome is in the pipeline's report */
    (void)rp_pipe_track(&est->pipe, t, est->images, est->n_images);
    const int8_t k = est->trk_pair[t];
    if (k < 0) {
        return;
    }
    pthread_mutex_lock(&est->mu);
    const uint8_t left = --est->pair_left[k];
    pthread_mutex_unlock(&est->mu);
    if (left == 0) {
        /* ignored: RP_E_ARG only for a step not begun or k out of range, which the caller
         * rules out; the matcher's counts are in the pipeline's report */
        (void)rp_pipe_match_pair(&est->pipe, (uint8_t)k);
    }
}

/* The trackers in the order their jobs are handed out: the one whose top-up turn it is (it
 * may detect: the longest job) first, so that the others fill the other threads meanwhile
 * (longest job first); the rest in index order. The order changes only which thread runs
 * what, never a result (rp_pipe.h). */
static uint8_t track_order(rp_est_t *est)
{
    const uint8_t n = rp_pipe_n_trackers(&est->pipe);
    const uint8_t first = rp_pipe_topup_tracker(&est->pipe);
    uint8_t k = 0;
    if (first < n) {
        est->order[k++] = first;
    }
    for (uint8_t t = 0; t < n; ++t) {
        if (t != first) {
            est->order[k++] = t;
        }
    }
    return n;
}

/* What rp_pipe_step_timed checks before it begins (the phased path does the same): every
 * camera with an image has a time within an int32_t of microseconds of utime. RP_OK, or
 * RP_E_RANGE with out the last estimate, LOST (rp_pipe_step_timed's answer). */
static rp_status_t cam_times_fit(rp_est_t *est, const rp_image_t *const images[],
                                 const int64_t cam_utime[], uint8_t n, int64_t utime,
                                 rp_estimate_t *out)
{
    for (uint8_t k = 0; cam_utime != NULL && k < n; ++k) {
        if (k >= est->pipe.rig->n_cams || images[k] == NULL || images[k]->data == NULL) {
            continue; /* not read */
        }
        int32_t dt;
        if (rp_pipe_cam_dt(cam_utime[k], utime, &dt) != RP_OK) {
            *out = est->pipe.last;
            out->flags |= RP_EST_LOST;
            return RP_E_RANGE;
        }
    }
    return RP_OK;
}

rp_status_t rp_est_step_images(rp_est_t *est, const rp_image_t *const images[],
                               const int64_t cam_utime[], uint8_t n, int64_t utime,
                               rp_estimate_t *out, const rp_frameset_t **fs_out)
{
    if (fs_out != NULL) {
        *fs_out = NULL;
    }
    if (est == NULL) {
        if (out != NULL) {
            memset(out, 0, sizeof *out);
            out->flags = RP_EST_LOST;
        }
        return RP_E_ARG;
    }
    rp_status_t st;
    if (rp_pool_threads(&est->pool) <= 1 || images == NULL || n > RP_MAX_CAMS || out == NULL) {
        /* its argument checks */
        st = rp_pipe_step_timed(&est->pipe, images, cam_utime, n, utime, out);
    } else {
        st = cam_times_fit(est, images, cam_utime, n, utime, out);
        if (st == RP_OK) {
            st = rp_pipe_begin(&est->pipe, utime, out); /* fills out on failure */
        }
        for (uint8_t k = 0; st == RP_OK && cam_utime != NULL && k < n; ++k) {
            if (k < est->pipe.rig->n_cams && images[k] != NULL && images[k]->data != NULL) {
                /* ignored: the step is begun, k a rig camera, the time checked above: RP_OK */
                (void)rp_pipe_cam_time(&est->pipe, k, cam_utime[k]);
            }
        }
        if (st == RP_OK) {
            est->images = images;
            est->n_images = n;
            for (uint8_t k = 0; k < rp_pipe_n_pairs(&est->pipe); ++k) {
                est->pair_left[k] = 2; /* the jobs see it: rp_pool_run orders it before them */
            }
            if (rp_pool_run(&est->pool, track_order(est), track_job, est) == RP_OK) {
                /* ignored: RP_E_ARG only for a step not begun; rp_pipe_estimate then says so */
                (void)rp_pipe_match(&est->pipe); /* every pair matched: the step moves on */
            }
            est->images = NULL;
            st = rp_pipe_estimate(&est->pipe, out); /* RP_E_ARG, out LOST, if not matched */
        }
    }
    if (fs_out != NULL && rp_pipe_frameset(&est->pipe, fs_out) != RP_OK) {
        *fs_out = NULL;
    }
    return st;
}
