/*
 * rp_sim.h - the paper's simulation protocol (Table 1), as docs/design.md fixes it, for the
 * simulator, the benchmarks and the tests. Host code (may allocate), links the core only.
 *
 * Six cameras, all 640x480 with fx = fy = focal_px and the principal point at the centre:
 *   RP_SIM_CAM1  front, at the origin, looking +z (the reference camera)
 *   RP_SIM_CAM2  at (+0.0866, 0, -0.05), looking +x
 *   RP_SIM_CAM3  at (0, 0, -0.1), looking -z
 *   RP_SIM_CAM4  at (-0.0866, 0, -0.05), looking -x
 *   RP_SIM_CAM1B at (0.1, 0, 0), cam1's orientation: cam1's stereo partner
 *   RP_SIM_CAM3B at (0.1, 0, -0.1), cam3's orientation: cam3's stereo partner
 * n_points points uniformly in the spherical shell r_in..r_out around the start. Per frame the
 * rig moves by a translation per world axis of magnitude U[t_min, t_max] with random sign and
 * a rotation per angle of magnitude U[a_min, a_max] with random sign, composed in the rig's
 * frame: R_j = R_{j-1} Rz(dg) Ry(db) Rx(da). A point is visible to a camera when it is at
 * least min_depth in front and projects inside the image. Pixel noise: Gaussian, noise_px.
 * Everything is a function of (seed, run index): runs can be computed in any order.
 * cfg.motion = RP_SIM_MOTION_TURN replaces that random walk with a turn (rp_sim_turn_pose): a
 * smooth function of time, sampled at j * frame_dt, in the same scene and with the same noise;
 * RP_SIM_MOTION_SMOOTH with a smooth wander (sums of sinusoids, below).
 *
 * Camera clocks (cam_offset_s, cam_phase_s, cam_fps, jitter_s; all zero by default: every camera
 * captures at the set's time, and the frame sets are the synchronised ones, bit for bit). Camera
 * k free-runs at its own rate: its frame i (i = 0, 1, ...) carries the stamp
 *     stamp_us(k, i) = round(1e6 cam_phase_s[k]) + round(1e6 i P_k),  P_k = 1 / cam_fps[k]
 * (P_k = frame_dt when cam_fps[k] is 0), and was really captured at
 *     t_true(k, i) = 1e-6 round(1e6 cam_phase_s[k]) + i P_k + cam_offset_s[k] + e(k, i)  (s),
 * i.e. true capture time = stamp + offset + jitter (up to the stamp's rounding to 1 us). The
 * offset is the camera's clock error, unknown to the estimators (they estimate it relative to
 * cam1's; the tools keep cam1's at 0); e(k, i) ~ N(0, jitter_s^2) is unknown noise, a function of
 * (seed, run, k, i). The phase is known: it is in the stamps. Frame sets come at the rate of the
 * fastest camera (the smallest P_k; the lowest index among equals), set j being that camera's
 * frame j: utime_j = its stamp. Camera k is in set j when it has a frame stamped in
 * (utime_{j-1}, utime_j] (its latest): its features, cam_dt_us[k] = stamp - utime_j (<= 0); else
 * n[k] = 0 and RP_FS_NO_IMAGE. A camera at the fastest rate or slower (P_k = P_f, or
 * P_k >= P_f + 2 us, which rp_sim_run_init enforces) has at most one frame per set, so each of
 * its frames stamped after utime_{-1} is in exactly one set. A camera's features are the
 * projection of the true pose at ITS t_true; the truth arrays (what the tools score against)
 * are the pose at the set's time t_j = 1e-6 round(1e6 phase_f) + j P_f, and utime_j is t_j
 * rounded to 1 us. Clocks need a continuous motion (turn, pitch, smooth): the paper's random
 * walk has no pose between frames.
 * cam2's and cam4's placements (position and yaw) are configurable (cfg.cam2, cfg.cam4) for
 * the layout study (rp_sim_layout.h); the defaults are the paper's, above.
 */
#ifndef RP_SIM_H
#define RP_SIM_H

#ifdef __cplusplus
extern "C" {
#endif

#include <stdint.h>

#include "rigpose/rp_frame.h"
#include "rigpose/rp_rig.h"
#include "rigpose/rp_vo_gc.h"
#include "rigpose/rp_vo_stereo.h"

enum { RP_SIM_CAM1 = 0, RP_SIM_CAM2, RP_SIM_CAM3, RP_SIM_CAM4, RP_SIM_CAM1B, RP_SIM_CAM3B,
       RP_SIM_NCAMS };

/* Where a sideways camera sits on the rig: position in cam1's frame and a yaw about cam1's y
 * axis (down). yaw 0 looks forward (+z), +pi/2 right (+x), -pi/2 left, pi back. */
typedef struct {
    double D[3];           /* m, cam1's frame (x right, y down, z forward) */
    double yaw;            /* rad */
} rp_sim_place_t;

/* The rig's trajectory. */
typedef enum {
    RP_SIM_MOTION_PAPER = 0, /* the paper's random per-frame increments (above) */
    /* A turn on the spot: yaw (about the world's y axis, cam1's y at frame 0: down) psi(t) =
     * s turn_rate (t - turn_ramp_s / 2) after a smooth start (the rate rises from 0 to
     * turn_rate over turn_ramp_s, a cubic smoothstep), s = +-1 per run (+: turning right), and
     * on top a smooth wobble in all six degrees of freedom: per translation axis (world) and per
     * angle (rig frame) the sum of two sinusoids of amplitude wobble_t (m) / wobble_a (rad),
     * periods U[1, 3] s and random phases, minus their value at t = 0, so that the pose at t = 0
     * is the identity. R(t) = Ry(psi) Rz(g_w) Ry(b_w) Rx(a_w), d(t) = the translation wobble:
     * |d| <= 4 wobble_t per axis, so the rig stays well inside the shell. With the defaults
     * (1.05 rad/s = 0.035 rad per frame at 30 Hz: about the paper's largest per-frame rotation
     * |(0.02, 0.02, 0.02)| = 0.035 rad, and the KITTI clip's 98 degrees in 51 frames at 10 Hz)
     * the yaw passes 90 degrees at frame 50, 180 at frame 95, 270 (= -90) at frame 140 and 360
     * at frame 185, give or take the wobble; the per-frame steps reach about 11 mm per axis and
     * (turn and wobble together) 0.047 rad (test_turns.c), in the paper's ranges. */
    RP_SIM_MOTION_TURN = 1,
    /* The same turn about the world's x axis (cam1's x at frame 0: right), R(t) = Rx(psi) Rw:
     * a pitch through the same angles at the same rates, where the paper's angles are not
     * singular (beta stays near 0): the control for what the turn's beta = +-90 costs. */
    RP_SIM_MOTION_PITCH = 2,
    /* A smooth wander for the unsynchronised cameras (every time has a pose, and the motion is
     * quick enough for clock offsets to matter): per translation axis (world) and per angle
     * (R = Rz(g) Ry(b) Rx(a), as the paper's) the sum of three sinusoids, periods U[1, 2] s
     * (translation) and U[1, 4] s (angles), random phases, minus their value at t = 0 (the pose
     * at t = 0 is the identity). Each sinusoid's rate amplitude A w is a third of smooth_v_axis
     * (m/s) or smooth_w_axis (rad/s): per axis |v| <= 0.4 m/s, per angle |rate| <= 0.8 rad/s by
     * default, so |v| <= 0.69 m/s; the peaks actually reached in 300 frames are about 0.5 m/s
     * and 1 rad/s (0.43-0.54 m/s, 0.80-1.19 rad/s over seeds 1-8, test_simclock.c). The
     * displacement per axis is at most 2 sum A <= 2 (v_axis / 3) sum 1 / w <= 0.255 m, so
     * |d| <= 0.441 m and the farthest camera (0.141 m from cam1) stays 0.08 m inside r_in; the
     * angles stay within 1.02 rad (beta far from +-pi/2). */
    RP_SIM_MOTION_SMOOTH = 3,
} rp_sim_motion_t;

typedef struct {
    uint32_t n_points;     /* 10000 */
    double r_in, r_out;    /* 0.667, 1.0 m */
    double focal_px;       /* 800 */
    uint16_t width, height;/* 640, 480 */
    double noise_px;       /* 0.5 */
    double t_min, t_max;   /* 0.005, 0.015 m per frame per axis */
    double a_min, a_max;   /* 0.005, 0.02 rad per frame per angle */
    double min_depth;      /* 0.05 m */
    double frame_dt;       /* 1/30 s (timestamps only) */
    uint32_t n_frames;     /* 100 */
    rp_sim_place_t cam2;   /* (+0.0866, 0, -0.05), yaw +pi/2 (the paper's) */
    rp_sim_place_t cam4;   /* (-0.0866, 0, -0.05), yaw -pi/2 (the paper's) */
    rp_sim_motion_t motion;/* RP_SIM_MOTION_PAPER */
    double turn_rate;      /* rad/s, 1.05 (turn only) */
    double turn_ramp_s;    /* s, 1/3 (turn only) */
    double wobble_t;       /* m, 0.03 (turn only) */
    double wobble_a;       /* rad, 0.05 (turn only) */
    double smooth_v_axis;  /* m/s, 0.4 (smooth only): per world axis, the speed bound */
    double smooth_w_axis;  /* rad/s, 0.8 (smooth only): per angle, the rate bound */
    /* Camera clocks (above), per camera in RP_SIM_CAM1.. order; all 0: synchronised. */
    double cam_offset_s[RP_SIM_NCAMS]; /* s, true capture time minus stamp (unknown) */
    double cam_phase_s[RP_SIM_NCAMS];  /* s, 0..1: stamp of the camera's frame 0 (known) */
    double cam_fps[RP_SIM_NCAMS];      /* Hz, its frame rate; 0: 1 / frame_dt */
    double jitter_s;                   /* s, sigma of the Gaussian capture-time noise */
} rp_sim_cfg_t;

/* The number of frames a turn run takes by default in the tools: 200 (one full turn at the
 * default rate, with 15 frames to spare). */
#define RP_SIM_TURN_FRAMES 200u

void rp_sim_default_cfg(rp_sim_cfg_t *cfg);

/* The six-camera rig of the protocol, cam2 and cam4 where cfg places them. */
void rp_sim_make_rig(const rp_sim_cfg_t *cfg, rp_rig_t *rig);

/* gc as the simulator, its tests and the benchmark run it: cam1..cam4; new features start at
 * the shell's mid radius (r_in + r_out) / 2 along their rays, +- 0.15 m; the filter's pixel
 * sigma is cfg's noise (at least 0.01 px: the filter needs sigma > 0). */
rp_vo_gc_cfg_t rp_sim_gc_cfg(const rp_sim_cfg_t *cfg);

/* The stereo estimator's plant noise for the feature-level protocol (m^2/s^3, rad^2/s^3): the
 * Table 1 figures of rigpose-sim are measured with it. The core's default (3) is chosen on
 * rendered images (config/README.md, "Defaults that are measured"). */
#define RP_SIM_STEREO_Q 1.0

/* stereo4 (both_pairs 1: cam1/cam1b and cam3/cam3b) or stereo2 (0: the front pair) as the
 * simulator and rigpose-ba run them: the core's defaults with plant noise RP_SIM_STEREO_Q and the
 * filter's pixel sigma cfg's noise (at least 0.01 px). */
rp_vo_stereo_cfg_t rp_sim_stereo_cfg(const rp_sim_cfg_t *cfg, int both_pairs);

/* The paper's placement of cam2 (right = 1) or cam4 (right = 0); 0.0866 is exactly
 * 0.1 cos(30 deg), so every camera is 0.1 m from cam1. */
rp_sim_place_t rp_sim_paper_place(int right);

typedef struct {
    rp_sim_cfg_t cfg;
    uint64_t seed;
    uint32_t run;
    double *points;   /* n_points x 3, world, m */
    double *truth;    /* n_frames x 6: [tx ty tz alpha beta gamma] of cam1 per frame */
    double *truth_R;  /* n_frames x 9: R_j (exact, accumulated; angles are extracted from it) */
    rp_rig_t rig;
    /* The turn's random parameters (motion turn only): the direction, and per degree of
     * freedom (tx ty tz alpha beta gamma) two sinusoids' amplitude, angular rate (rad/s) and
     * phase. */
    double turn_sign;
    double wob[6][2][3];
    /* The smooth motion's (motion smooth only): per degree of freedom three sinusoids'
     * amplitude (m or rad), angular rate (rad/s) and phase. */
    double smooth[6][3][3];
    /* The clocks (from cfg): 1 if any is set; per camera the period P_k (s) and the stamp of
     * frame 0 (us); the camera whose frames make the sets. */
    int clocked;
    double cam_period_s[RP_SIM_NCAMS];
    int64_t cam_phase_us[RP_SIM_NCAMS];
    int set_cam;
} rp_sim_run_t;

/* Make run `run` of the experiment seeded by `seed`: the point cloud and the trajectory.
 * Returns 0; -1 if memory ran out; -2 for clocks that cannot be simulated: any with the paper's
 * motion, a rate other than 0 or 1..1000 Hz, a phase outside 0..1 s, |offset| > 1 s, jitter outside
 * 0..0.1 s, or a camera slower than the fastest by less than 2 us a frame (see above). */
int rp_sim_run_init(rp_sim_run_t *sr, const rp_sim_cfg_t *cfg, uint64_t seed, uint32_t run);
void rp_sim_run_free(rp_sim_run_t *sr);

/* The pose at time t (s, any real t, not only frame times) of a run made with a continuous
 * motion (turn, pitch, smooth): cam1's position d (world, m) and orientation R (row-major, cam1
 * to world). Set j's truth is this at the set's time (j * frame_dt without clocks). Returns 0;
 * -1 for the paper's motion, which has no pose between frames (d, R: the identity). */
int rp_sim_pose(const rp_sim_run_t *sr, double t, double d[3], double R[9]);

/* rp_sim_pose by its older name (the turn's callers), the status dropped. */
void rp_sim_turn_pose(const rp_sim_run_t *sr, double t, double d[3], double R[9]);

/* Camera k's frame in set j (the clocks above). */
typedef struct {
    int present;      /* 1: the camera has a frame in the set, else RP_FS_NO_IMAGE */
    int64_t index;    /* its frame number i (the camera's own count from 0); present only */
    int64_t stamp_us; /* its stamp: utime + cam_dt_us of the set; present only */
    double t_true;    /* s, when it was really captured (stamp + offset + jitter); present
                       * only */
} rp_sim_cam_frame_t;

/* Set j's time (s; its truth's) and stamp (us: the frame set's utime). */
double rp_sim_set_time(const rp_sim_run_t *sr, uint32_t j);
int64_t rp_sim_set_utime(const rp_sim_run_t *sr, uint32_t j);

/* Camera k's frame in set j, as rp_sim_frame makes it. */
void rp_sim_cam_frame(const rp_sim_run_t *sr, uint32_t j, int k, rp_sim_cam_frame_t *cf);

/* The turn's angle psi(t) alone (rad, unwrapped; without the wobble's part); 0 for the
 * paper's motion. */
double rp_sim_turn_yaw(const rp_sim_run_t *sr, double t);

/* The noisy features of frame j in all six cameras (ids = point index; the same point carries
 * the same id in every camera that sees it). The noise is a function of (seed, run, j) only.
 * A camera that sees more than RP_MAX_FEATS_PER_CAM points keeps the nearest ones.
 * utime = j * frame_dt, rounded to 1 us. With clocks: utime = rp_sim_set_utime, each camera's
 * features from the pose at its own t_true, cam_dt_us and RP_FS_NO_IMAGE as rp_sim_cam_frame
 * says. Returns the total feature count. */
uint32_t rp_sim_frame(const rp_sim_run_t *sr, uint32_t j, rp_frameset_t *fs);

/* Deterministic generator used by the simulation (splitmix64 seeding xoshiro256**). */
typedef struct { uint64_t s[4]; } rp_rng_t;
void rp_rng_seed(rp_rng_t *r, uint64_t seed);
uint64_t rp_rng_next(rp_rng_t *r);
double rp_rng_uniform(rp_rng_t *r);   /* [0, 1) */
double rp_rng_gauss(rp_rng_t *r);     /* N(0, 1) */

#ifdef __cplusplus
}
#endif

#endif /* RP_SIM_H */
