/*
 * rp_stats.h - the daemon's accounting: what the status channel reports (per-camera states,
 * frame counts and rates over the status period, latency, estimator events since start), the
 * run's latency record for the final percentiles, and the error against the source's truth.
 *
 * One rp_stats_t per run, kept static by the caller (it holds the latency histogram, 7.4 KiB).
 * No heap. The loop calls rp_stats_set for every published pose, rp_stats_grab_failed for every
 * failed grab, rp_stats_fill_status whenever it sends a status, rp_stats_summary at the end.
 */
#ifndef RP_STATS_H
#define RP_STATS_H

#include <stdint.h>

#include "rigpose/rp_frame.h"
#include "rigpose/rp_hal.h"
#include "rigpose/rp_status.h"
#include "rigpose_status_t.h"

/* The run's latencies for the final percentiles: a histogram over the whole run, whatever its
 * length, with bins growing by RP_STATS_LAT_RATIO from RP_STATS_LAT_MIN_MS (below it: the first
 * bin; above the last bin's edge, about 160 s: the last bin). A percentile is reported as its
 * bin's geometric centre, within half a bin (0.5 %) of every latency in that bin. */
#define RP_STATS_LAT_BINS 1900
#define RP_STATS_LAT_MIN_MS 0.001
#define RP_STATS_LAT_RATIO 1.01

typedef struct {
    /* what the status message says about the source (set at init) */
    int8_t source;                      /* status_t.SOURCE_* */
    int8_t method;                      /* pose_t.METHOD_* */
    uint8_t n_cams;
    /* status period: reset by each rp_stats_fill_status */
    int32_t status_seq;                 /* status messages filled so far */
    int32_t period_frames[RP_MAX_CAMS]; /* frames per camera in the period */
    uint32_t period_sets;
    int64_t period_start_us;            /* HAL clock, us */
    float lat_max_ms;
    /* since start */
    int32_t frames[RP_MAX_CAMS];        /* frames received per camera */
    int32_t n_lost, n_reinit, n_cov_reset;
    int8_t cam_state[RP_MAX_CAMS];      /* RP_HAL_CAM_{MISSING,GONE,DROPPED} of the latest set */
    int8_t prev_state[RP_MAX_CAMS];     /* the same before the latest rp_stats_set */
    uint32_t n_sets;                    /* poses accounted (the next pose's seq) */
    int64_t t_first_us, t_last_us;      /* publish times of the first and latest pose */
    uint32_t n_lat;                     /* latencies in lat_hist (saturates at UINT32_MAX) */
    uint32_t lat_hist[RP_STATS_LAT_BINS]; /* capture -> publish per pose, counts per bin */
    double err_sum[6];                  /* sum |estimate - truth| per axis over sets 1.. */
    uint32_t n_err;                     /* sets in err_sum */
} rp_stats_t;

/* What one set added. */
typedef struct {
    int changed;        /* a camera's state differs from the set before */
    int has_err;        /* the set carried the truth: err_t, err_r are filled */
    double err_t_m;     /* |position error|, m */
    double err_r_rad;   /* |angle error| (each angle wrapped to [-pi, pi]), rad */
} rp_stats_set_t;

typedef struct {
    uint32_t n_poses;
    double fps;              /* poses per second between the first and the last publish */
    double lat_p50_ms, lat_p99_ms;
    uint32_t n_err;          /* sets behind err_mean (0: the source knew no truth) */
    double err_mean[6];      /* mean |estimate - truth| per axis over sets 1..: m, rad */
} rp_stats_summary_t;

/* Start a run: source (rp_hal_kind_t), method (pose_t.METHOD_*) and n_cams for the status
 * messages, now on the HAL clock. RP_E_ARG for a NULL s or n_cams outside 1..RP_MAX_CAMS. */
rp_status_t rp_stats_init(rp_stats_t *s, rp_hal_kind_t source, int8_t method, uint8_t n_cams,
                          int64_t now_us);

/* A grab failed (not RP_HAL_E_END): the cameras' states are taken from set as it came back. */
void rp_stats_grab_failed(rp_stats_t *s, const rp_hal_set_t *set);

/* The pose of set (estimate est, published at t_pub_us, lat_ms after capture) went out: camera
 * states and frame counts, estimator events, the latency record, and the error against
 * set->truth (frame 0 defines the world: left out of the mean). out (optional) says what the
 * set changed. RP_E_ARG for a NULL argument. */
rp_status_t rp_stats_set(rp_stats_t *s, const rp_hal_set_t *set, const rp_estimate_t *est,
                         float lat_ms, int64_t t_pub_us, rp_stats_set_t *out);

/* Fill the status message m for now_us and start a new status period. set: the latest grab's
 * (its drop counts); hal_st its status; fs the features the front end delivered (NULL: none);
 * est the latest estimate; lat_ms / proc_ms the latest set's latency and processing time
 * (0 after a failed grab). last_pose_seq is the accounted poses minus one. */
void rp_stats_fill_status(rp_stats_t *s, rigpose_status_t *m, const rp_hal_set_t *set,
                          rp_hal_status_t hal_st, const rp_frameset_t *fs,
                          const rp_estimate_t *est, float lat_ms, float proc_ms, int64_t now_us);

/* The cameras' clock offsets into m (cam_offset_ms, cam_offset_sigma_ms) from the estimator's
 * (rp_pipe_time_offsets: s), n_cams of them; the rest zero. */
void rp_stats_fill_offsets(rigpose_status_t *m, const rp_real off_s[RP_MAX_CAMS],
                           const rp_real sigma_s[RP_MAX_CAMS], uint8_t n_cams);

/* The run's figures (sorts the latency record in place). */
void rp_stats_summary(rp_stats_t *s, rp_stats_summary_t *out);

#endif /* RP_STATS_H */
