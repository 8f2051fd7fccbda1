/*
 * rp_gcba.h - the generalised camera's metric scale from a window bundle adjustment.
 *
 * Why: gc (rp_vo_gc.h) holds its map in "map units". Landmarks are born at an assumed depth and
 * refined by parallax against the filter's own translations, so the map and the trajectory can
 * be wrong together by one factor, and the per-frame filter cannot see it (the landmarks have
 * already absorbed it). The only metric in a rig of single cameras is the cameras' known offsets
 * D_k: when the rig rotates, an offset camera moves by (R_j - R_i) D_k, which the map's unit
 * does not scale. That information lives in the joint problem (poses and landmarks free), not in
 * any one frame: for the paper's motion (0.005-0.02 rad per axis per frame, offsets 0.1 m,
 * 0.5 px) the Cramer-Rao bound of the scale over one run of 100 frames is 0.40 % with every
 * landmark unknown (41,000 observations), 2.3 % over one of gc's windows (6 keyframes 4 frames
 * apart, 80 landmarks per camera); host_tools/research/gcdiag/scale_crlb.py computes both.
 *
 * What: a ring of keyframes (the filter's pose in map units, and the pixels of a subset of its
 * landmarks). rp_gcba_scale() solves, in metres, for the poses of every keyframe but the oldest
 * (held at the filter's) and for the landmarks (triangulated from the keyframes' rays, then
 * free), Gauss-Newton with the landmarks eliminated per point (Schur complement) and a Huber
 * weight, and returns the map's unit that the solution implies,
 *   mu = sum_k (p_k - p_0) . (t_k - t_0) / sum_k |t_k - t_0|^2  (map units per metre),
 * p_k the filter's translations, t_k the solution's, with its variance from the reduced normal
 * matrix. The caller fuses it (rp_vo_gc: a scalar filter on mu).
 *
 * Arithmetic: the accumulators and the solve are double whatever rp_real is (an exception to
 * the one-scalar rule): the scale is the normal matrix's weakest direction, and the Schur
 * complement subtracts large nearly equal numbers to find it. Cortex-A53-class boards have
 * double-precision hardware; the pixels and Jacobians come from rp_rig_project in rp_real.
 */
#ifndef RP_GCBA_H
#define RP_GCBA_H

#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Keyframes in the window, at most (the oldest is held fixed). */
#ifndef RP_GCBA_MAX_KF
#define RP_GCBA_MAX_KF 8
#endif
/* Observations stored per keyframe, at most. */
#ifndef RP_GCBA_MAX_OBS_KF
#define RP_GCBA_MAX_OBS_KF 384
#endif
/* Landmarks in one adjustment, at most (a power of two). */
#ifndef RP_GCBA_MAX_LM
#define RP_GCBA_MAX_LM 512
#endif

RP_STATIC_ASSERT(RP_GCBA_MAX_KF >= 3 && RP_GCBA_MAX_KF <= 32, "RP_GCBA_MAX_KF: 3..32");
RP_STATIC_ASSERT((RP_GCBA_MAX_LM & (RP_GCBA_MAX_LM - 1)) == 0, "RP_GCBA_MAX_LM: power of 2");
RP_STATIC_ASSERT(RP_GCBA_MAX_OBS_KF >= 16 && RP_GCBA_MAX_OBS_KF <= 65535, "RP_GCBA_MAX_OBS_KF");

#define RP_GCBA_NP (6 * (RP_GCBA_MAX_KF - 1)) /* free pose parameters, at most */

typedef struct {
    uint32_t id;  /* feature id (the tracker's) */
    float uv[2];  /* measured pixel */
    uint8_t cam;  /* rig camera index */
} rp_gcba_obs_t;

typedef struct {
    rp_real p[6];   /* filter pose [t (map units), alpha beta gamma (rad)] of cam1 */
    rp_real rate[6];/* the filter's rate there [v (map units/s); omega (rad/s)] (rp_ekf.h) */
    rp_real cam_dt[RP_MAX_CAMS]; /* camera k's capture time minus the pose's, s: its images are
                     * seen from p [+] cam_dt[k] rate (rp_pose_lin_at); the adjustment moves p
                     * and keeps these */
    uint16_t n;     /* observations */
    rp_gcba_obs_t obs[RP_GCBA_MAX_OBS_KF];
} rp_gcba_kf_t;

typedef struct {
    uint8_t iterations;  /* Gauss-Newton tries at most, a shorter try along a step included
                          * (rp_gcba_step; it stops when the cost falls by under 1e-4 of
                          * itself), >= 1 */
    uint8_t min_obs;     /* a landmark needs this many keyframes (>= 2) */
    rp_real sigma_px;    /* pixel noise (1-sigma), > 0 */
    rp_real huber_px;    /* Huber threshold on a residual's length, px, > 0 */
    rp_real min_angle;   /* least angle between a landmark's outermost rays, rad, >= 0 */
} rp_gcba_cfg_t;

/* 8 iterations, 3 keyframes, 0.5 px, Huber 1.5 px, 0.5 deg. */
rp_gcba_cfg_t rp_gcba_default_cfg(void);

typedef struct {
    rp_real mu;       /* map units per metre implied by the window */
    rp_real mu_var;   /* its variance (from the reduced normal matrix) */
    uint16_t n_lm;    /* landmarks adjusted */
    uint16_t n_obs;   /* observations used */
    uint16_t n_kf;    /* keyframes */
    uint8_t iterations; /* Gauss-Newton tries (shorter ones along a step included) */
    rp_real rms0_px;  /* RMS residual per coordinate before and after, px */
    rp_real rms_px;
} rp_gcba_result_t;

typedef enum {
    RP_GCBA_IDLE = 0,   /* no adjustment under way: keyframes may be added */
    RP_GCBA_STARTED,    /* landmarks grouped and triangulated; normal equations not built */
    RP_GCBA_ITERATING,  /* equations built, Gauss-Newton steps to take */
    RP_GCBA_SOLVED      /* converged or out of iterations: rp_gcba_finish reports */
} rp_gcba_state_t;

typedef struct {
    rp_gcba_kf_t kf[RP_GCBA_MAX_KF]; /* ring */
    rp_gcba_state_t state;
    /* the adjustment under way (rp_gcba_start .. rp_gcba_finish) */
    const rp_rig_t *rig;
    rp_gcba_cfg_t cfg;
    rp_gcba_result_t res;
    double cost, sq;                 /* robust cost, sum of squared residuals (px^2) */
    uint16_t n_obs;
    uint8_t it;
    uint8_t cap;                     /* ring size (rp_gcba_reset), 3..RP_GCBA_MAX_KF */
    uint8_t n_kf;                    /* keyframes held */
    uint8_t head;                    /* index of the oldest */
    /* scratch of rp_gcba_scale */
    double x[RP_GCBA_MAX_KF][6];     /* keyframe poses in metres */
    double mu;                       /* the map's unit the adjustment started from */
    double mu_now;                   /* the unit its estimate implies now (prepare_poses) */
    rp_pose_lin_t pl[RP_GCBA_MAX_KF][RP_MAX_CAMS]; /* each camera's pose at its capture time
                                      * (rp_gcba_kf_t), prepared for projection */
    uint8_t pl_ok[RP_GCBA_MAX_KF][RP_MAX_CAMS];
    double X[RP_GCBA_MAX_LM][3];     /* landmarks, m */
    double x0[RP_GCBA_MAX_KF][6];    /* the estimate before a step (restored if it is worse) */
    double dX[RP_GCBA_MAX_LM][3];    /* the Gauss-Newton step of each landmark (rp_gcba_step) */
    double S0[RP_GCBA_NP * RP_GCBA_NP]; /* the equations at the estimate before a step: back */
    double g0[RP_GCBA_NP];           /*   in place if no length of it lowers the cost */
    double Vi0[RP_GCBA_MAX_LM][9];
    double v0[RP_GCBA_MAX_LM][3];
    double cost0, sq0;
    uint16_t n_obs0;
    double alpha;                    /* the share of it being tried (1: a new step) */
    double X0[RP_GCBA_MAX_LM][3];
    uint8_t ok0[RP_GCBA_MAX_LM];
    double Vi[RP_GCBA_MAX_LM][9];    /* inverse of each landmark's 3x3 block */
    double v[RP_GCBA_MAX_LM][3];     /* each landmark's gradient */
    uint16_t n_lm_tab;               /* landmarks of the last adjustment's table */
    uint32_t lm_id[RP_GCBA_MAX_LM];
    uint8_t lm_cam[RP_GCBA_MAX_LM];
    uint8_t lm_ok[RP_GCBA_MAX_LM];
    uint16_t lm_n[RP_GCBA_MAX_LM];   /* observations of each landmark */
    uint16_t lm_first[RP_GCBA_MAX_LM];
    uint16_t hash[2 * RP_GCBA_MAX_LM];            /* id -> landmark + 1 (0: empty) */
    uint16_t ob_kf[RP_GCBA_MAX_KF * RP_GCBA_MAX_OBS_KF];  /* grouped by landmark: keyframe */
    uint16_t ob_i[RP_GCBA_MAX_KF * RP_GCBA_MAX_OBS_KF];   /* and index in it */
    double S[RP_GCBA_NP * RP_GCBA_NP];            /* reduced normal matrix */
    double g[RP_GCBA_NP];
    double dx[RP_GCBA_NP];
} rp_gcba_t;

/* Empty the window, which then holds the newest max_kf keyframes (3..RP_GCBA_MAX_KF).
 * RP_E_ARG for NULL or max_kf out of range. */
rp_status_t rp_gcba_reset(rp_gcba_t *ba, uint8_t max_kf);

/* Append a keyframe (the oldest is dropped when the ring is full). n > RP_GCBA_MAX_OBS_KF keeps
 * the first RP_GCBA_MAX_OBS_KF. rate and cam_dt (both NULL: every camera at p) place each
 * camera's images at its capture time (rp_gcba_kf_t). RP_E_ARG (NULL, or never reset, or only
 * one of rate / cam_dt), RP_E_NAN (non-finite pose, rate or time: not added). */
rp_status_t rp_gcba_add_keyframe(rp_gcba_t *ba, const rp_real p[6], const rp_gcba_obs_t *obs,
                                 uint16_t n, const rp_real rate[6],
                                 const rp_real cam_dt[RP_MAX_CAMS]);

/* Adjust the window with rig (metres) starting from the keyframe poses divided by mu, and
 * report the map's unit it implies. The stored keyframes are left as they were (the solution:
 * rp_gcba_solved_pose, rp_gcba_landmark). RP_OK; RP_E_ARG (NULL, bad cfg, mu not > 0);
 * RP_E_TOO_FEW (fewer than 3 keyframes or than 12 usable landmarks); RP_E_DEGENERATE (the
 * keyframes' translations span nothing); RP_E_SINGULAR (the reduced normal matrix is not
 * positive definite); RP_E_NAN. rig must stay valid until it returns. */
rp_status_t rp_gcba_scale(rp_gcba_t *ba, const rp_rig_t *rig, rp_real mu,
                          const rp_gcba_cfg_t *cfg, rp_gcba_result_t *res);

/* The same in pieces, so that a caller can spread one adjustment over several frames:
 * rp_gcba_start (grouping, triangulation), then rp_gcba_step (the first normal equations, then
 * one Gauss-Newton step per call, each about one pass over the observations; a no-op once
 * solved), then rp_gcba_finish (any steps left, and the result). A step that raises the robust
 * cost is tried again at a quarter and a sixteenth of its length, one length per call
 * (backtracking along the Gauss-Newton direction, which descends the cost), before the
 * estimate is left where it was; every try counts against cfg.iterations, and each call costs
 * at most one pass over the observations. While an adjustment is under
 * way rp_gcba_add_keyframe refuses (RP_E_ARG); rig must stay valid until finish (cfg is copied).
 * Statuses as rp_gcba_scale's; a failed start or step leaves the window idle. */
rp_status_t rp_gcba_start(rp_gcba_t *ba, const rp_rig_t *rig, rp_real mu,
                          const rp_gcba_cfg_t *cfg);
rp_status_t rp_gcba_step(rp_gcba_t *ba);
rp_status_t rp_gcba_finish(rp_gcba_t *ba, rp_gcba_result_t *res);

/* Keyframe k of the window (0 = the oldest): its pose as stored (rp_gcba_add_keyframe or
 * rp_gcba_set_pose), or as the last rp_gcba_scale solved it (metres). RP_E_ARG: k out of range. */
rp_status_t rp_gcba_kf_pose(const rp_gcba_t *ba, uint8_t k, rp_real p[6]);
rp_status_t rp_gcba_solved_pose(const rp_gcba_t *ba, uint8_t k, rp_real p[6]);

/* Landmark i (0 <= i < ba->n_lm_tab) of the last rp_gcba_scale: its id, camera, position (m)
 * and covariance given the poses (packed xx xy xz yy yz zz, m^2). RP_E_ARG: i out of range;
 * RP_E_NOT_FOUND: that landmark took no part in the solution. */
rp_status_t rp_gcba_landmark(const rp_gcba_t *ba, uint16_t i, uint32_t *id, uint8_t *cam,
                             rp_real X[3], rp_real C[6]);

/* Where the window is: idle, or an adjustment started, iterating or solved. RP_E_ARG (NULL). */
rp_status_t rp_gcba_state(const rp_gcba_t *ba, rp_gcba_state_t *state);

/* Keyframes held in *n_kf, landmarks in the last adjustment's table (the i of
 * rp_gcba_landmark) in *n_lm; either may be NULL. RP_E_ARG (NULL ba). */
rp_status_t rp_gcba_counts(const rp_gcba_t *ba, uint8_t *n_kf, uint16_t *n_lm);

/* Replace keyframe k's stored pose (e.g. with the adjusted one). RP_E_ARG, RP_E_NAN. */
rp_status_t rp_gcba_set_pose(rp_gcba_t *ba, uint8_t k, const rp_real p[6]);

#ifdef __cplusplus
}
#endif

#endif /* RP_GCBA_H */
