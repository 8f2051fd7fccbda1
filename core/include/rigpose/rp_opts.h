/*
 * rp_opts.h - every compile-time limit and numeric choice of the core, in one place.
 *
 * Each value has an #ifndef default that a build may override with -D (the Makefile does, for
 * the float/double variants and the board build). Invariants are checked with _Static_assert.
 */
#ifndef RP_OPTS_H
#define RP_OPTS_H

#include <stdint.h>

/* ---- scalar type of the estimator ------------------------------------------------------- */
/* RP_REAL_IS_FLOAT=1: float (the board's default); 0: double (the host's default). */
#ifndef RP_REAL_IS_FLOAT
#define RP_REAL_IS_FLOAT 0
#endif

#if RP_REAL_IS_FLOAT
typedef float rp_real;
#define RP_REAL_EPS 1.1920929e-7f
#else
typedef double rp_real;
#define RP_REAL_EPS 2.220446049250313e-16
#endif

/* A literal of the scalar type: RP_C(0.5) is 0.5f in float builds, no double promotion. */
#define RP_C(x) ((rp_real)(x))

/* Linear-algebra backend: 1 = C++ shim over Eigen fixed-size matrices, 0 = plain C. */
#ifndef RP_LINALG_EIGEN
#define RP_LINALG_EIGEN 1
#endif

/* ---- sizes --------------------------------------------------------------------------------- */
/* Cameras on one rig (the paper's simulation uses 6: 4 single cameras + 2 stereo partners). */
#ifndef RP_MAX_CAMS
#define RP_MAX_CAMS 6
#endif

/* Stereo pairs on one rig. */
#ifndef RP_MAX_PAIRS
#define RP_MAX_PAIRS 2
#endif

/* Tracked features per camera per frame. */
#ifndef RP_MAX_FEATS_PER_CAM
#define RP_MAX_FEATS_PER_CAM 512
#endif

/* 3-D landmarks one estimator holds at once (all pairs / cameras together). */
#ifndef RP_MAX_LANDMARKS
#define RP_MAX_LANDMARKS 2048
#endif

/* Largest row or column count a decomposition (Cholesky, QR, SVD) accepts: 16, or the pose
 * EKF's 12 states plus one clock offset per camera but the reference (rp_ekf.h) if more. */
#ifndef RP_LA_MAX_DIM
#define RP_LA_MAX_DIM (RP_MAX_CAMS + 11 > 16 ? RP_MAX_CAMS + 11 : 16)
#endif

/* Smallest depth (m, along the camera's z axis) at which a point counts as in front. */
#ifndef RP_MIN_DEPTH
#define RP_MIN_DEPTH 1e-3
#endif

/* ---- image front end (tracker) ------------------------------------------------------------- */
/* Largest grey image a tracker accepts, pixels. */
#ifndef RP_TRACK_MAX_W
#define RP_TRACK_MAX_W 640
#endif
#ifndef RP_TRACK_MAX_H
#define RP_TRACK_MAX_H 480
#endif

/* Pyramid levels including the full-resolution one (OpenCV's maxLevel + 1). */
#ifndef RP_TRACK_MAX_LEVELS
#define RP_TRACK_MAX_LEVELS 4
#endif

/* Largest Lucas-Kanade window side, pixels (odd). */
#ifndef RP_TRACK_MAX_WIN
#define RP_TRACK_MAX_WIN 31
#endif

/* Per tracker, bytes of the cache of level-0 Lucas-Kanade patches (rp_track.h, rp_tracker_t):
 * a track whose patch is cached skips one patch of its next frame. Each slot holds
 * 3 x win x (win rounded up to 8) int16 (3,024 bytes at the default 21); tracks past the slots
 * are tracked the same way, only slower. 0: no cache. */
#ifndef RP_TRACK_PATCH_CACHE_BYTES
#define RP_TRACK_PATCH_CACHE_BYTES (160 * 3024)
#endif

/* Detection: largest bucketing grid (cells) and candidates kept per cell. */
#ifndef RP_TRACK_MAX_CELLS
#define RP_TRACK_MAX_CELLS 64
#endif
#ifndef RP_TRACK_CELL_CANDS
#define RP_TRACK_CELL_CANDS 24
#endif

/* C11 _Static_assert / C++ static_assert (the headers are also read by C++ host tools). */
#ifdef __cplusplus
#define RP_STATIC_ASSERT(cond, msg) static_assert(cond, msg)
#else
#define RP_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#endif

RP_STATIC_ASSERT(RP_MAX_CAMS >= 1 && RP_MAX_CAMS <= 15, "RP_MAX_CAMS out of range (track ids: rp_track.h)");
RP_STATIC_ASSERT(RP_MAX_PAIRS * 2 <= RP_MAX_CAMS, "each stereo pair needs two cameras");
RP_STATIC_ASSERT(RP_MAX_FEATS_PER_CAM >= 8 && RP_MAX_FEATS_PER_CAM <= 65535, "feature limit");
RP_STATIC_ASSERT(RP_MAX_LANDMARKS >= RP_MAX_FEATS_PER_CAM, "landmark table smaller than a camera");
RP_STATIC_ASSERT((RP_MAX_LANDMARKS & (RP_MAX_LANDMARKS - 1)) == 0, "RP_MAX_LANDMARKS: power of 2");
RP_STATIC_ASSERT(RP_LA_MAX_DIM >= 12 + RP_MAX_CAMS - 1,
                 "the pose EKF with clock offsets needs (12 + cameras - 1)^2 decompositions");
RP_STATIC_ASSERT(RP_TRACK_MAX_W >= 32 && RP_TRACK_MAX_W <= 4096, "RP_TRACK_MAX_W out of range");
RP_STATIC_ASSERT(RP_TRACK_MAX_H >= 32 && RP_TRACK_MAX_H <= 4096, "RP_TRACK_MAX_H out of range");
RP_STATIC_ASSERT(RP_TRACK_MAX_LEVELS >= 1 && RP_TRACK_MAX_LEVELS <= 6, "pyramid levels 1..6");
RP_STATIC_ASSERT(RP_TRACK_MAX_WIN >= 5 && RP_TRACK_MAX_WIN <= 63 && (RP_TRACK_MAX_WIN & 1),
                 "LK window: odd, 5..63");
RP_STATIC_ASSERT(RP_TRACK_MAX_CELLS >= 1 && RP_TRACK_CELL_CANDS >= 1, "detection grid");

#endif /* RP_OPTS_H */
