/*
 * rp_stats.c - the daemon's accounting (rp_stats.h).
 */
#include "rp_stats.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CAM_STATE_BITS (RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE | RP_HAL_CAM_DROPPED)

RP_STATIC_ASSERT(RIGPOSE_STATUS_T_CAM_MISSING == RP_HAL_CAM_MISSING &&
                     RIGPOSE_STATUS_T_CAM_GONE == RP_HAL_CAM_GONE &&
                     RIGPOSE_STATUS_T_CAM_DROPPED == RP_HAL_CAM_DROPPED,
                 "status_t.CAM_* are RP_HAL_CAM_*");
RP_STATIC_ASSERT(RIGPOSE_STATUS_T_SOURCE_V4L2 == RP_HAL_SRC_V4L2 &&
                     RIGPOSE_STATUS_T_SOURCE_REPLAY == RP_HAL_SRC_REPLAY &&
                     RIGPOSE_STATUS_T_SOURCE_SIM == RP_HAL_SRC_SIM &&
                     RIGPOSE_STATUS_T_SOURCE_LCM == RP_HAL_SRC_LCM,
                 "status_t.SOURCE_* are rp_hal_kind_t");

rp_status_t rp_stats_init(rp_stats_t *s, rp_hal_kind_t source, int8_t method, uint8_t n_cams,
                          int64_t now_us)
{
    if (s == NULL || n_cams < 1 || n_cams > RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    memset(s, 0, sizeof *s);
    s->source = (int8_t)source;
    s->method = method;
    s->n_cams = n_cams;
    s->period_start_us = now_us;
    return RP_OK;
}

void rp_stats_grab_failed(rp_stats_t *s, const rp_hal_set_t *set)
{
    if (s == NULL || set == NULL) {
        return;
    }
    for (uint8_t k = 0; k < s->n_cams; ++k) {
        s->cam_state[k] = (int8_t)(set->cam[k].flags & CAM_STATE_BITS);
    }
}

/* The histogram bin of a latency (ms): floor(log_ratio(lat / min)), clamped. */
static int lat_bin(float lat_ms)
{
    const double x = (double)lat_ms / RP_STATS_LAT_MIN_MS;
    if (!(x > 1.0)) {
        return 0; /* also NaN */
    }
    const double b = floor(log(x) / log(RP_STATS_LAT_RATIO));
    return b >= (double)(RP_STATS_LAT_BINS - 1) ? RP_STATS_LAT_BINS - 1 : (int)b;
}

rp_status_t rp_stats_set(rp_stats_t *s, const rp_hal_set_t *set, const rp_estimate_t *est,
                         float lat_ms, int64_t t_pub_us, rp_stats_set_t *out)
{
    if (s == NULL || set == NULL || est == NULL) {
        return RP_E_ARG;
    }
    rp_stats_set_t r;
    memset(&r, 0, sizeof r);
    if (s->n_lat < UINT32_MAX) {
        s->lat_hist[lat_bin(lat_ms)]++;
        s->n_lat++;
    }
    if (s->n_sets == 0) {
        s->t_first_us = t_pub_us;
    }
    s->t_last_us = t_pub_us;

    for (uint8_t k = 0; k < s->n_cams; ++k) {
        const int8_t st = (int8_t)(set->cam[k].flags & CAM_STATE_BITS);
        s->prev_state[k] = s->cam_state[k];
        r.changed |= st != s->cam_state[k];
        s->cam_state[k] = st;
        if (!(set->cam[k].flags & RP_HAL_CAM_MISSING)) {
            s->frames[k]++;
            s->period_frames[k]++;
        }
    }
    s->period_sets++;
    s->lat_max_ms = lat_ms > s->lat_max_ms ? lat_ms : s->lat_max_ms;
    s->n_lost += (est->flags & RP_EST_LOST) ? 1 : 0;
    s->n_reinit += (est->flags & RP_EST_REINIT) ? 1 : 0;
    s->n_cov_reset += (est->flags & RP_EST_COV_RESET) ? 1 : 0;

    if (set->has_truth) {
        double et = 0.0, er = 0.0;
        for (int i = 0; i < 6; ++i) {
            double d = (double)est->p[i] - (double)set->truth[i];
            if (i >= 3) {
                d = remainder(d, 2.0 * 3.14159265358979323846); /* wrapped to [-pi, pi] */
            }
            if (s->n_sets > 0) {
                s->err_sum[i] += fabs(d);
            }
            if (i < 3) {
                et += d * d;
            } else {
                er += d * d;
            }
        }
        s->n_err += s->n_sets > 0 ? 1u : 0u;
        r.has_err = 1;
        r.err_t_m = sqrt(et);
        r.err_r_rad = sqrt(er);
    }
    s->n_sets++;
    if (out != NULL) {
        *out = r;
    }
    return RP_OK;
}

void rp_stats_fill_status(rp_stats_t *s, rigpose_status_t *m, const rp_hal_set_t *set,
                          rp_hal_status_t hal_st, const rp_frameset_t *fs,
                          const rp_estimate_t *est, float lat_ms, float proc_ms, int64_t now_us)
{
    if (s == NULL || m == NULL || set == NULL || est == NULL) {
        return;
    }
    memset(m, 0, sizeof *m);
    const double period_s = (double)(now_us - s->period_start_us) * 1e-6;
    m->utime = now_us;
    m->seq = s->status_seq++;
    m->last_pose_seq = (int32_t)s->n_sets - 1;
    m->source = s->source;
    m->method = s->method;
    m->hal_status = (int32_t)hal_st;
    m->n_cams = (int8_t)s->n_cams;
    for (uint8_t k = 0; k < s->n_cams; ++k) {
        m->cam_state[k] = s->cam_state[k];
        m->fps[k] = period_s > 0.0 ? (float)(s->period_frames[k] / period_s) : 0.0f;
        m->frames[k] = s->frames[k];
        m->drops[k] = (int32_t)set->cam[k].drops;
        m->features[k] = (int16_t)(fs != NULL ? fs->n[k] : 0);
        m->features_used[k] = (int16_t)est->n_used[k];
        m->cam_dt_us[k] = (fs != NULL && !(fs->cam_flags[k] & RP_FS_NO_IMAGE)) ? fs->cam_dt_us[k]
                                                                              : 0;
        s->period_frames[k] = 0;
    }
    m->latency_ms = lat_ms;
    m->latency_ms_max = s->lat_max_ms;
    m->process_ms = proc_ms;
    m->set_rate_hz = period_s > 0.0 ? (float)(s->period_sets / period_s) : 0.0f;
    m->est_flags = (int32_t)est->flags;
    m->n_lost = s->n_lost;
    m->n_reinit = s->n_reinit;
    m->n_cov_reset = s->n_cov_reset;
    m->n_landmarks = (int16_t)est->n_landmarks;
    m->pos_sigma_m = (float)sqrt((double)(est->cov[0] + est->cov[7] + est->cov[14]));
    m->rot_sigma_rad = (float)sqrt((double)(est->cov[21] + est->cov[28] + est->cov[35]));
    s->period_sets = 0;
    s->period_start_us = now_us;
    s->lat_max_ms = 0.0f;
}

void rp_stats_fill_offsets(rigpose_status_t *m, const rp_real off_s[RP_MAX_CAMS],
                           const rp_real sigma_s[RP_MAX_CAMS], uint8_t n_cams)
{
    if (m == NULL || off_s == NULL || sigma_s == NULL) {
        return;
    }
    for (uint8_t k = 0; k < 6; ++k) {
        const int in = k < n_cams && k < RP_MAX_CAMS;
        m->cam_offset_ms[k] = in ? (float)(1e3 * (double)off_s[k]) : 0.0f;
        m->cam_offset_sigma_ms[k] = in ? (float)(1e3 * (double)sigma_s[k]) : 0.0f;
    }
}

/* The p-quantile of the histogram: the centre of the bin holding the latency of rank
 * floor(p (n - 1)) (0-based) in the sorted run. */
static double lat_quantile(const rp_stats_t *s, double p)
{
    const uint64_t rank = (uint64_t)(p * (double)(s->n_lat - 1));
    uint64_t cum = 0;
    int b = 0;
    for (; b < RP_STATS_LAT_BINS - 1; ++b) {
        cum += s->lat_hist[b];
        if (cum > rank) {
            break;
        }
    }
    return RP_STATS_LAT_MIN_MS * pow(RP_STATS_LAT_RATIO, (double)b + 0.5);
}

void rp_stats_summary(rp_stats_t *s, rp_stats_summary_t *out)
{
    if (s == NULL || out == NULL) {
        return;
    }
    memset(out, 0, sizeof *out);
    out->n_poses = s->n_sets;
    const double span_s = (double)(s->t_last_us - s->t_first_us) * 1e-6;
    out->fps = (s->n_sets > 1 && span_s > 0.0) ? (double)(s->n_sets - 1) / span_s : 0.0;
    if (s->n_lat > 0) {
        out->lat_p50_ms = lat_quantile(s, 0.5);
        out->lat_p99_ms = lat_quantile(s, 0.99);
    }
    out->n_err = s->n_err;
    for (int i = 0; i < 6 && s->n_err > 0; ++i) {
        out->err_mean[i] = s->err_sum[i] / s->n_err;
    }
}
