/*
 * rp_obs.h - a 2-D/3-D correspondence: world point M seen by camera `cam` at pixel uv.
 * The measurement unit of Lowe's method and of the pose EKF.
 */
#ifndef RP_OBS_H
#define RP_OBS_H

#ifdef __cplusplus
extern "C" {
#endif

#include "rp_opts.h"

typedef struct {
    rp_real uv[2];  /* measured pixel (distorted), pixels */
    rp_real M[3];   /* world point, m */
    rp_real w;      /* weight: the measurement's standard deviation is sigma_px / sqrt(w); 1 = nominal */
    rp_real dt;     /* the camera's capture time minus the filter's state time, s, as stamped
                     * (rp_frameset_t.cam_dt_us); the pose EKF predicts the pose to it with its
                     * constant velocity (rp_ekf.h). 0: at the state's time. Lowe's method and
                     * RANSAC treat every observation as at the state's time. */
    uint8_t cam;    /* camera index in the rig */
} rp_obs_t;

#ifdef __cplusplus
}
#endif

#endif /* RP_OBS_H */
