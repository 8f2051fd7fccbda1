/*
 * rigpose-sim - the paper's simulation protocol (Table 1) run through rigpose's estimators.
 *
 * Each run is one random scene and trajectory (rp_sim.h); its frames are generated once and fed
 * to every selected method, so all methods see the same noisy measurements. For every frame
 * j >= 1 (frame 0 defines the world) the absolute error of each pose column is taken:
 * |t_est - t_true| for tx ty tz, |wrap(angle_est - angle_true)| for alpha beta gamma; the table
 * shows the means over all frames of all runs beside the paper's Table 1 row, plus the median
 * and worst per-run means (the tails matter). Runs are spread over threads; the results do not
 * depend on the thread count (only the timings do).
 *
 * usage: rigpose-sim [--methods LIST] [--runs N] [--frames N] [--seed S] [--focal-px F]
 *                    [--noise-px S] [--motion paper|turn|pitch|smooth] [--cam-offsets-ms LIST]
 *                    [--jitter-ms S] [--cam-fps LIST] [--cam-phase-ms LIST] [--threads N]
 *                    [--json] [--help]
 *        rigpose-sim --layout-study [FILE] [same options]
 *
 * --motion turn (rp_sim.h) runs a turn on the spot instead of the paper's random walk (200
 * frames unless --frames: one full turn) and adds to each row the rotation error as one angle
 * (the geodesic distance between the estimated and the true rotation, which does not depend on
 * the angles' parametrisation), overall, within 10 degrees of yaw +-90 (where the paper's
 * angles are singular) and its largest frame. --motion smooth (rp_sim.h) is a smooth wander
 * (sums of sinusoids, about 0.5 m/s and 1 rad/s at their peaks) with the rotation error too; with
 * a continuous motion the cameras can have their own clocks (--cam-offsets-ms, --jitter-ms,
 * --cam-fps, --cam-phase-ms: rp_sim.h), which the estimators see only through the stamps.
 *
 * The layout study runs the selected methods (default gc,rc; 20 runs) once per candidate
 * placement of cam2 and cam4 (from FILE, format in rp_sim_layout.h, or the built-in grid) and
 * prints the placements ranked by the first method's mean translation error.
 */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "rigpose/rp_pipe.h"
#include "rigpose/rp_rc.h"
#include "rigpose/rp_vo_gc.h"
#include "rigpose/rp_vo_mono.h"
#include "rigpose/rp_vo_stereo.h"
#include "../common/rp_cfg_diff.h"
#include "rp_sim.h"
#include "rp_sim_layout.h"

#define SIM_PI 3.14159265358979323846
#define MAX_METHODS 16
#define MAX_THREADS 256
#define NCOL 6

static const char *const col_name[NCOL] = {"tx", "ty", "tz", "alpha", "beta", "gamma"};
_Static_assert(NCOL == RP_SIM_NCAMS, "print_cols prints the per-camera clocks too");

/* ---- the paper's Table 1 (docs/design.md) ------------------------------------------------------- */

typedef struct {
    const char *name;
    double v[NCOL]; /* mean absolute error per frame: m (tx ty tz), rad (alpha beta gamma) */
} paper_row_t;

static const paper_row_t paper_rows[] = {
    {"4 cameras", {.0005, .0005, .0021, .0005, .0004, .0015}},
    {"2 cameras", {.0055, .0132, .0042, .0137, .0055, .0026}},
    {"cam 1", {.0252, .0206, .0337, .0204, .0260, .0040}},
    {"cam 2", {.2973, .3731, .3828, .0864, .2724, .2791}},
    {"cam 3", {.0238, .0211, .0390, .0203, .0249, .0045}},
    {"cam 4", {.2846, .3740, .3770, .0879, .2750, .2825}},
    {"RC", {.0211, .0694, .0746, .0288, .0624, .0553}},
};

static const paper_row_t *paper_row(const char *name)
{
    for (size_t i = 0; i < sizeof paper_rows / sizeof paper_rows[0]; ++i) {
        if (strcmp(paper_rows[i].name, name) == 0) {
            return &paper_rows[i];
        }
    }
    return NULL;
}

/* ---- methods ------------------------------------------------------------------------------- */

typedef struct {
    double noise_px; /* simulated pixel noise, px (the filters' measurement sigma) */
    unsigned ekf_iterations; /* Gauss-Newton iterations of the EKF update; 0 = the default */
    int no_refine;           /* 1: keep the first triangulation (the paper's structure) */
    int est_offsets;         /* 1: the filters estimate the cameras' clock offsets */
    const double *known_off_s; /* --known-offsets: the true offsets configured, else NULL */
    double model_jitter_s;     /* --model-jitter: the clocks' jitter as the filters' (s), or 0 */
    int time_noise_per_feature; /* --time-noise-per-feature: rp_ekf_params_t.group_time_noise 0 */
    int plain_update;           /* --plain-update: no 1-point RANSAC and no RANSAC re-find */
    int paper_map;              /* --paper-map: stereo add_landmarks 0 */
} method_opts_t;

/* --estimate-offsets, --known-offsets on a layout's filter parameters. */
static void offsets_opt(const method_opts_t *o, rp_ekf_params_t *e)
{
    if (o->est_offsets) {
        e->toff_estimate = 1;
    }
    for (int k = 0; o->known_off_s != NULL && k < RP_SIM_NCAMS; ++k) {
        e->toff0_s[k] = (rp_real)o->known_off_s[k];
    }
    if (o->model_jitter_s > 0.0) {
        e->time_jitter_s = (rp_real)o->model_jitter_s;
    }
    if (o->time_noise_per_feature) {
        e->group_time_noise = 0;
    }
}

/* One estimator as the simulator drives it. `state_size` bytes are allocated once per thread
 * (zeroed); `init` starts a run on that memory (the rig outlives the run); `step` processes one
 * frame set and always fills est. Adding a method = writing its two adapters and one entry. */
typedef struct {
    rp_pipe_layout_t layout; /* its name (rp_pipe_layout_name) is the --methods token */
    const char *paper;     /* Table 1 row it is compared with */
    size_t state_size;
    rp_status_t (*init)(void *state, const rp_rig_t *rig, const method_opts_t *o);
    rp_status_t (*step)(void *state, const rp_frameset_t *fs, rp_estimate_t *est);
    /* the method's pose filter (its clock-offset states), or NULL if it has none */
    const rp_ekf_t *(*filter)(const void *state);
} method_t;

/* stereo4 / stereo2 as rp_sim_stereo_cfg says (plant noise RP_SIM_STEREO_Q), with the
 * ablation options on top. */
static rp_vo_stereo_cfg_t stereo_cfg(const method_opts_t *o, int both_pairs)
{
    rp_sim_cfg_t sim;
    rp_sim_default_cfg(&sim);
    sim.noise_px = o->noise_px;
    rp_vo_stereo_cfg_t cfg = rp_sim_stereo_cfg(&sim, both_pairs);
    if (o->ekf_iterations) {
        cfg.ekf.iterations = (uint8_t)o->ekf_iterations;
    }
    if (o->no_refine) {
        cfg.refine_structure = 0;
    }
    if (o->plain_update) {
        cfg.one_point = 0;
        cfg.ransac = 0;
    }
    if (o->paper_map) {
        cfg.add_landmarks = 0;
    }
    offsets_opt(o, &cfg.ekf);
    return cfg;
}

static rp_status_t stereo_init(void *state, const rp_rig_t *rig, const method_opts_t *o,
                               int both_pairs)
{
    const rp_vo_stereo_cfg_t cfg = stereo_cfg(o, both_pairs);
    return rp_vo_stereo_init((rp_vo_stereo_t *)state, rig, &cfg);
}

static rp_status_t stereo4_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    return stereo_init(state, rig, o, 1);
}

static rp_status_t stereo2_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    return stereo_init(state, rig, o, 0);
}

static rp_status_t stereo_step(void *state, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_stereo_step((rp_vo_stereo_t *)state, fs, est);
}

static const rp_ekf_t *stereo_filter(const void *state)
{
    return &((const rp_vo_stereo_t *)state)->ekf;
}

/* gc: the generalised camera over the four single cameras (rp_vo_gc.h), configured as
 * rp_sim_gc_cfg says (new features at the shell's mid radius along their rays). */
static rp_vo_gc_cfg_t gc_cfg(const method_opts_t *o)
{
    rp_sim_cfg_t sim;
    rp_sim_default_cfg(&sim);
    sim.noise_px = o->noise_px;
    rp_vo_gc_cfg_t cfg = rp_sim_gc_cfg(&sim);
    if (o->ekf_iterations) {
        cfg.ekf.iterations = (uint8_t)o->ekf_iterations;
    }
    if (o->plain_update) {
        cfg.one_point = 0;
        cfg.ransac = 0;
    }
    offsets_opt(o, &cfg.ekf);
    return cfg;
}

static rp_status_t gc_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    const rp_vo_gc_cfg_t cfg = gc_cfg(o);
    return rp_vo_gc_init((rp_vo_gc_t *)state, rig, &cfg);
}

static rp_status_t gc_step(void *state, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_gc_step((rp_vo_gc_t *)state, fs, est);
}

static const rp_ekf_t *gc_filter(const void *state)
{
    return &((const rp_vo_gc_t *)state)->ekf;
}

/* cam1..cam4: one camera alone (rp_vo_mono.h), reporting its pose mapped to the rig frame.
 * Features start on the plane z = the shell's mid depth (0.667 + 1) / 2 m. */
static rp_vo_mono_cfg_t mono_cfg(uint8_t cam, const method_opts_t *o)
{
    rp_vo_mono_cfg_t cfg = rp_vo_mono_default_cfg();
    cfg.cam = cam;
    cfg.init_depth_m = (rp_real)((0.667 + 1.0) / 2.0);
    cfg.init_depth_sigma_m = (rp_real)0.15;
    cfg.ekf.sigma_px = (rp_real)(o->noise_px > 0.01 ? o->noise_px : 0.01);
    if (o->ekf_iterations) {
        cfg.ekf.iterations = (uint8_t)o->ekf_iterations;
    }
    if (o->plain_update) {
        cfg.one_point = 0;
        cfg.ransac = 0;
    }
    return cfg;
}

static rp_status_t mono_init(void *state, const rp_rig_t *rig, const method_opts_t *o, uint8_t cam)
{
    const rp_vo_mono_cfg_t cfg = mono_cfg(cam, o);
    return rp_vo_mono_init((rp_vo_mono_t *)state, rig, &cfg);
}

static rp_status_t cam1_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    return mono_init(state, rig, o, RP_SIM_CAM1);
}

static rp_status_t cam2_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    return mono_init(state, rig, o, RP_SIM_CAM2);
}

static rp_status_t cam3_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    return mono_init(state, rig, o, RP_SIM_CAM3);
}

static rp_status_t cam4_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    return mono_init(state, rig, o, RP_SIM_CAM4);
}

static rp_status_t mono_step(void *state, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_mono_step((rp_vo_mono_t *)state, fs, est, NULL);
}

/* rc: four single cameras (their own mono estimators, duplicating cam1..cam4's work) fused by
 * the rigidity constraints (rp_rc.h). A degenerate frame keeps the last accepted scale S_j. */
typedef struct {
    rp_vo_mono_t mono[4];
    rp_rc_params_t prm;
    rp_real last_scale;
} rc_state_t;

static rp_status_t rc_init(void *state, const rp_rig_t *rig, const method_opts_t *o)
{
    rc_state_t *rc = state;
    static const uint8_t cams[4] = {RP_SIM_CAM1, RP_SIM_CAM2, RP_SIM_CAM3, RP_SIM_CAM4};
    for (int i = 0; i < 4; ++i) {
        const rp_vo_mono_cfg_t cfg = mono_cfg(cams[i], o);
        const rp_status_t st = rp_vo_mono_init(&rc->mono[i], rig, &cfg);
        if (st != RP_OK) {
            return st;
        }
    }
    rc->prm = rp_rc_default_params();
    rc->last_scale = (rp_real)1.0;
    return RP_OK;
}

static rp_status_t rc_step(void *state, const rp_frameset_t *fs, rp_estimate_t *est)
{
    rc_state_t *rc = state;
    static const uint8_t cams[4] = {RP_SIM_CAM1, RP_SIM_CAM2, RP_SIM_CAM3, RP_SIM_CAM4};
    rp_real p_own[4][6];
    rp_status_t st1 = RP_OK;
    for (int i = 0; i < 4; ++i) {
        rp_estimate_t rig_est, own;
        const rp_status_t st = rp_vo_mono_step(&rc->mono[i], fs, &rig_est, &own);
        if (i == 0) {
            st1 = st;
            *est = own; /* cam1's own pose is the rig pose up to scale */
        }
        memcpy(p_own[i], own.p, sizeof(p_own[i]));
    }
    rp_real s[4];
    uint32_t flags = est->flags & ~(uint32_t)RP_EST_SCALE_WEAK;
    const rp_status_t st = rp_rc_fuse(rc->mono[0].rig, cams, 4, (const rp_real(*)[6])p_own,
                                      &rc->prm, rc->last_scale, est->p, s, &flags);
    if (st == RP_OK) {
        rc->last_scale = s[0];
    }
    est->flags = flags;
    return st1;
}

static const method_t methods[] = {
    {RP_PIPE_STEREO4, "4 cameras", sizeof(rp_vo_stereo_t), stereo4_init, stereo_step,
     stereo_filter},
    {RP_PIPE_STEREO2, "2 cameras", sizeof(rp_vo_stereo_t), stereo2_init, stereo_step,
     stereo_filter},
    {RP_PIPE_CAM1, "cam 1", sizeof(rp_vo_mono_t), cam1_init, mono_step, NULL},
    {RP_PIPE_CAM2, "cam 2", sizeof(rp_vo_mono_t), cam2_init, mono_step, NULL},
    {RP_PIPE_CAM3, "cam 3", sizeof(rp_vo_mono_t), cam3_init, mono_step, NULL},
    {RP_PIPE_CAM4, "cam 4", sizeof(rp_vo_mono_t), cam4_init, mono_step, NULL},
    {RP_PIPE_RC, "RC", sizeof(rc_state_t), rc_init, rc_step, NULL},
    /* cam1..cam4 -> "cam 1".."cam 4", rc -> "RC", gc -> "2 cameras" (no paper row) */
    {RP_PIPE_GC, "2 cameras", sizeof(rp_vo_gc_t), gc_init, gc_step, gc_filter},
};
#define N_KNOWN_METHODS (sizeof methods / sizeof methods[0])

/* ---- options ------------------------------------------------------------------------------- */

typedef struct {
    const method_t *m[MAX_METHODS];
    unsigned n_methods;
    uint32_t runs, frames;
    uint64_t seed;
    double focal_px, noise_px;
    unsigned threads;
    int json;
    uint32_t ekf_iterations;
    int no_refine;
    int est_offsets;
    int known_offsets;
    int model_jitter;
    int time_noise_per_feature; /* --time-noise-per-feature */
    int plain_update;         /* --plain-update */
    int paper_map;            /* --paper-map */
    int layout_study;         /* --layout-study given */
    const char *layout_file;  /* its FILE, or NULL for the built-in grid */
    int methods_given, runs_given, frames_given;
    rp_sim_motion_t motion;
    /* the clocks (rp_sim.h), per camera in rp_sim's order (cam1 cam2 cam3 cam4 cam1b cam3b) */
    double cam_offset_ms[RP_SIM_NCAMS], cam_phase_ms[RP_SIM_NCAMS], cam_fps[RP_SIM_NCAMS];
    double cam_offset_s[RP_SIM_NCAMS]; /* cam_offset_ms in s */
    double jitter_ms;
    double outliers;          /* --outliers FRAC: share of every camera's features replaced by
                               * uniform pixels, drawn anew every frame (0: none) */
    int clocks_given;
    double max_rot;           /* --max-rot DEG (rad here): fail above it; 0: no check */
    int64_t trace_run;        /* --trace R: per-frame lines of run R on stderr; -1: none, -2: all */
} opts_t;

static void usage(FILE *out, const char *argv0)
{
    fprintf(out,
            "usage: %s [options]\n"
            "Runs the paper's simulation protocol (Table 1) and compares with the paper.\n"
            "  --methods LIST   comma-separated methods (default stereo4,stereo2); known:",
            argv0);
    for (size_t i = 0; i < N_KNOWN_METHODS; ++i) {
        fprintf(out, " %s", rp_pipe_layout_name(methods[i].layout));
    }
    fprintf(out,
            "\n"
            "  --runs N         runs (default 1500)\n"
            "  --frames N       frames per run, >= 2 (default 100; frame 0 is not scored)\n"
            "  --seed S         experiment seed (default 1)\n"
            "  --focal-px F     fx = fy in pixels, principal point at the image centre "
            "(default 800)\n"
            "  --noise-px S     Gaussian pixel noise sigma (default 0.5)\n"
            "  --motion M       paper (default): the paper's random per-frame motion; turn: a\n"
            "                   turn on the spot, 0.035 rad/frame of yaw plus a smooth wobble\n"
            "                   (rp_sim.h), 200 frames unless --frames; adds the rotation error\n"
            "                   as one angle (rot), near yaw +-90 deg (rot90) and its worst frame;\n"
            "                   the angle columns compare each estimate with the nearer of the\n"
            "                   truth's two angle triples (a, b, g) and (a+pi, pi-b, g+pi);\n"
            "                   pitch: the same turn about cam1's x axis (beta stays near 0);\n"
            "                   smooth: a smooth wander, sums of sinusoids per axis, peaks about\n"
            "                   0.5 m/s and 1 rad/s (rp_sim.h), 100 frames unless --frames;\n"
            "                   adds rot and rot_max\n"
            "  Camera clocks (need --motion turn, pitch or smooth; LIST: up to 6 numbers, one per\n"
            "  camera in rp_sim's order cam1,cam2,cam3,cam4,cam1b,cam3b, missing ones 0; the\n"
            "  estimators see only the stamps):\n"
            "  --cam-offsets-ms LIST  each camera's clock offset, unknown to the estimators:\n"
            "                   true capture time = stamp + offset (e.g. 0,12,-25,40,0,0)\n"
            "  --jitter-ms S    sigma of a Gaussian capture-time noise per camera frame, not in\n"
            "                   the stamps\n"
            "  --cam-fps LIST   each camera's frame rate (0: the rig's 30); frame sets come at\n"
            "                   the fastest camera's rate, a camera without a new frame since the\n"
            "                   previous set has none in it (e.g. 30,25,15,30,25,15)\n"
            "  --cam-phase-ms LIST  each camera's first stamp, 0..1000 (known: in the stamps)\n"
            "  --max-rot DEG    with --motion turn/pitch/smooth: exit status 1 if a method's\n"
            "                   largest rotation error (rot_max) or a lost frame exceeds DEG /\n"
            "                   occurs\n"
            "  --trace R|all    one line per frame of run R (or of every run) on stderr: the\n"
            "                   turn's angle and the true beta (deg), per method its status,\n"
            "                   geodesic rotation error (deg), |tx| (m) and its flags (hex,\n"
            "                   rp_frame.h RP_EST_*)\n"
            "  --outliers FRAC  gross outliers: each feature of every camera is, with\n"
            "                   probability FRAC (0..1), replaced by a pixel uniform over the\n"
            "                   image, drawn anew every frame from the run's seed (the same for\n"
            "                   every method)\n"
            "  --plain-update   every layout's plain gated EKF update: no 1-point RANSAC, no\n"
            "                   RANSAC re-find (one_point 0, ransac 0), for ablation\n"
            "  --paper-map      stereo layouts: landmarks only at (re-)initialisations and as\n"
            "                   retried failed matches (add_landmarks 0), the paper's map\n"
            "  --threads N      worker threads (default: online CPUs)\n"
            "  --ekf-iterations N  Gauss-Newton iterations of the EKF update (default 3;\n"
            "                   1 = the plain EKF), for ablation\n"
            "  --no-refine      keep each landmark's first triangulation (the paper's\n"
            "                   structure) instead of refining it, for ablation\n"
            "  --estimate-offsets  the filters estimate each camera's clock offset but cam1's\n"
            "                   (estimator.estimate_time_offsets; stereo and gc); prints\n"
            "                   their mean and largest |error| to cam1 at frame 50 and the\n"
            "                   last (JSON: offset_err_ms_f50[_max], offset_err_ms_last[_max])\n"
            "  --known-offsets  the filters are given the true --cam-offsets-ms (their start\n"
            "                   value with --estimate-offsets): the ceiling of compensation\n"
            "  --model-jitter   the filters' estimator.time_jitter_s is --jitter-ms\n"
            "  --time-noise-per-feature  the filters take the extrapolated pose's error as\n"
            "                   independent noise per feature (rp_ekf_params_t\n"
            "                   group_time_noise 0; default: shared per capture time)\n"
            "  --layout-study [FILE]  rank placements of cam2/cam4 (FILE: one per line,\n"
            "                   'name x2 y2 z2 yaw2_deg x4 y4 z4 yaw4_deg', cam1's frame, m;\n"
            "                   no FILE: the built-in grid of 27 around the paper's) by the\n"
            "                   first method's mean translation error; methods default to\n"
            "                   gc,rc and runs to 20\n"
            "  --json           print one JSON object instead of the table\n"
            "  --help           this text\n");
}

static int parse_u64(const char *s, uint64_t *out)
{
    char *end;
    if (!s || !*s || *s == '-') {
        return -1;
    }
    errno = 0;
    unsigned long long v = strtoull(s, &end, 0);
    if (errno || *end) {
        return -1;
    }
    *out = (uint64_t)v;
    return 0;
}

static int parse_u32(const char *s, uint32_t lo, uint32_t hi, uint32_t *out)
{
    uint64_t v;
    if (parse_u64(s, &v) || v < lo || v > hi) {
        return -1;
    }
    *out = (uint32_t)v;
    return 0;
}

static int parse_double(const char *s, double lo, double hi, double *out)
{
    char *end;
    if (!s || !*s) {
        return -1;
    }
    errno = 0;
    double v = strtod(s, &end);
    if (errno || *end || !(v >= lo && v <= hi)) {
        return -1;
    }
    *out = v;
    return 0;
}

/* A comma-separated list of 1..RP_SIM_NCAMS numbers in lo..hi into out (the rest 0). */
static int parse_cam_list(const char *s, double lo, double hi, double out[RP_SIM_NCAMS])
{
    if (!s || !*s) {
        return -1;
    }
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        out[k] = 0.0;
    }
    for (int k = 0;; ++k) {
        char *end;
        if (k == RP_SIM_NCAMS) {
            return -1;
        }
        errno = 0;
        const double v = strtod(s, &end);
        if (errno || end == s || (*end != ',' && *end != '\0') || !(v >= lo && v <= hi)) {
            return -1;
        }
        out[k] = v;
        if (*end == '\0') {
            return 0;
        }
        s = end + 1;
    }
}

static const char *motion_name(rp_sim_motion_t m)
{
    return m == RP_SIM_MOTION_TURN     ? "turn"
           : m == RP_SIM_MOTION_PITCH  ? "pitch"
           : m == RP_SIM_MOTION_SMOOTH ? "smooth"
                                       : "paper";
}

static int parse_methods(const char *list, opts_t *o)
{
    o->n_methods = 0;
    const char *p = list;
    if (!p || !*p) {
        return -1;
    }
    for (;;) {
        const char *comma = strchr(p, ',');
        const size_t len = comma ? (size_t)(comma - p) : strlen(p);
        const method_t *found = NULL;
        for (size_t i = 0; i < N_KNOWN_METHODS; ++i) {
            const char *name = rp_pipe_layout_name(methods[i].layout);
            if (strlen(name) == len && strncmp(name, p, len) == 0) {
                found = &methods[i];
            }
        }
        if (!found) {
            fprintf(stderr, "rigpose-sim: unknown method '%.*s'\n", (int)len, p);
            return -1;
        }
        for (unsigned i = 0; i < o->n_methods; ++i) {
            if (o->m[i] == found) {
                fprintf(stderr, "rigpose-sim: method '%s' given twice\n",
                        rp_pipe_layout_name(found->layout));
                return -1;
            }
        }
        if (o->n_methods == MAX_METHODS) {
            return -1;
        }
        o->m[o->n_methods++] = found;
        if (!comma) {
            return 0;
        }
        p = comma + 1;
    }
}

/* 0 on success, 1 if --help was asked, -1 on a bad option (message printed). */
static int parse_args(int argc, char **argv, opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->runs = 1500;
    o->frames = 100;
    o->seed = 1;
    o->focal_px = 800.0;
    o->noise_px = 0.5;
    o->trace_run = -1;
    const long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    o->threads = ncpu < 1 ? 1u : ncpu > MAX_THREADS ? MAX_THREADS : (unsigned)ncpu;
    if (parse_methods("stereo4,stereo2", o)) {
        return -1;
    }

    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) {
            return 1;
        }
        if (strcmp(arg, "--json") == 0) {
            o->json = 1;
            continue;
        }
        if (strcmp(arg, "--no-refine") == 0) {
            o->no_refine = 1;
            continue;
        }
        if (strcmp(arg, "--estimate-offsets") == 0) {
            o->est_offsets = 1;
            continue;
        }
        if (strcmp(arg, "--known-offsets") == 0) {
            o->known_offsets = 1;
            continue;
        }
        if (strcmp(arg, "--model-jitter") == 0) {
            o->model_jitter = 1;
            continue;
        }
        if (strcmp(arg, "--plain-update") == 0) {
            o->plain_update = 1;
            continue;
        }
        if (strcmp(arg, "--paper-map") == 0) {
            o->paper_map = 1;
            continue;
        }
        if (strcmp(arg, "--time-noise-per-feature") == 0) {
            o->time_noise_per_feature = 1;
            continue;
        }
        if (strcmp(arg, "--layout-study") == 0) {
            o->layout_study = 1;
            if (i + 1 < argc && strncmp(argv[i + 1], "--", 2) != 0) {
                o->layout_file = argv[++i];
            }
            continue;
        }
        if (strncmp(arg, "--layout-study=", 15) == 0) {
            o->layout_study = 1;
            o->layout_file = arg + 15;
            continue;
        }
        /* --name value or --name=value */
        char name[32];
        const char *val;
        const char *eq = strchr(arg, '=');
        if (strncmp(arg, "--", 2) != 0) {
            fprintf(stderr, "rigpose-sim: unexpected argument '%s'\n", arg);
            return -1;
        }
        if (eq) {
            const size_t len = (size_t)(eq - arg);
            if (len >= sizeof name) {
                fprintf(stderr, "rigpose-sim: unknown option '%s'\n", arg);
                return -1;
            }
            memcpy(name, arg, len);
            name[len] = '\0';
            val = eq + 1;
        } else {
            if (strlen(arg) >= sizeof name) {
                fprintf(stderr, "rigpose-sim: unknown option '%s'\n", arg);
                return -1;
            }
            strcpy(name, arg);
            val = (i + 1 < argc) ? argv[++i] : NULL;
        }
        int bad;
        uint32_t threads = 0;
        if (strcmp(name, "--methods") == 0) {
            bad = parse_methods(val, o);
            o->methods_given = 1;
        } else if (strcmp(name, "--runs") == 0) {
            bad = parse_u32(val, 1, 100000000u, &o->runs);
            o->runs_given = 1;
        } else if (strcmp(name, "--frames") == 0) {
            bad = parse_u32(val, 2, 1000000u, &o->frames);
            o->frames_given = 1;
        } else if (strcmp(name, "--max-rot") == 0) {
            bad = parse_double(val, 1e-6, 180.0, &o->max_rot);
            o->max_rot *= SIM_PI / 180.0;
        } else if (strcmp(name, "--trace") == 0) {
            uint32_t tr = 0;
            bad = !(val && strcmp(val, "all") == 0) && parse_u32(val, 0, 100000000u, &tr);
            o->trace_run = (val && strcmp(val, "all") == 0) ? -2 : (int64_t)tr;
        } else if (strcmp(name, "--motion") == 0) {
            bad = !val || (strcmp(val, "paper") != 0 && strcmp(val, "turn") != 0 &&
                           strcmp(val, "pitch") != 0 && strcmp(val, "smooth") != 0);
            o->motion = !val                        ? RP_SIM_MOTION_PAPER
                        : strcmp(val, "turn") == 0   ? RP_SIM_MOTION_TURN
                        : strcmp(val, "pitch") == 0  ? RP_SIM_MOTION_PITCH
                        : strcmp(val, "smooth") == 0 ? RP_SIM_MOTION_SMOOTH
                                                     : RP_SIM_MOTION_PAPER;
        } else if (strcmp(name, "--cam-offsets-ms") == 0) {
            bad = parse_cam_list(val, -1000.0, 1000.0, o->cam_offset_ms);
            o->clocks_given = 1;
        } else if (strcmp(name, "--cam-phase-ms") == 0) {
            bad = parse_cam_list(val, 0.0, 1000.0, o->cam_phase_ms);
            o->clocks_given = 1;
        } else if (strcmp(name, "--cam-fps") == 0) {
            bad = parse_cam_list(val, 0.0, 1000.0, o->cam_fps);
            o->clocks_given = 1;
        } else if (strcmp(name, "--jitter-ms") == 0) {
            bad = parse_double(val, 0.0, 100.0, &o->jitter_ms);
            o->clocks_given = 1;
        } else if (strcmp(name, "--outliers") == 0) {
            bad = parse_double(val, 0.0, 1.0, &o->outliers);
        } else if (strcmp(name, "--seed") == 0) {
            bad = parse_u64(val, &o->seed);
        } else if (strcmp(name, "--focal-px") == 0) {
            bad = parse_double(val, 1.0, 1e6, &o->focal_px);
        } else if (strcmp(name, "--noise-px") == 0) {
            bad = parse_double(val, 0.0, 100.0, &o->noise_px);
        } else if (strcmp(name, "--ekf-iterations") == 0) {
            bad = parse_u32(val, 1, 20, &o->ekf_iterations);
        } else if (strcmp(name, "--threads") == 0) {
            bad = parse_u32(val, 1, MAX_THREADS, &threads);
            o->threads = threads;
        } else {
            fprintf(stderr, "rigpose-sim: unknown option '%s'\n", name);
            return -1;
        }
        if (bad) {
            fprintf(stderr, "rigpose-sim: bad value for %s: '%s'\n", name, val ? val : "");
            return -1;
        }
    }
    if (o->max_rot > 0.0 && o->motion == RP_SIM_MOTION_PAPER) {
        fprintf(stderr, "rigpose-sim: --max-rot needs --motion turn, pitch or smooth\n");
        return -1;
    }
    if (o->clocks_given && o->motion == RP_SIM_MOTION_PAPER) {
        fprintf(stderr, "rigpose-sim: camera clocks need a motion with a pose at every time: "
                        "--motion turn, pitch or smooth\n");
        return -1;
    }
    if ((o->motion == RP_SIM_MOTION_TURN || o->motion == RP_SIM_MOTION_PITCH) &&
        !o->frames_given) {
        o->frames = RP_SIM_TURN_FRAMES;
    }
    if (o->layout_study) {
        if (!o->methods_given && parse_methods("gc,rc", o)) {
            return -1;
        }
        if (!o->runs_given) {
            o->runs = 20;
        }
    }
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        o->cam_offset_s[k] = o->cam_offset_ms[k] * 1e-3;
    }
    return 0;
}

/* ---- the experiment ------------------------------------------------------------------------ */

/* What one method made of one run. */
typedef struct {
    double err_sum[NCOL]; /* sum over frames 1..frames-1 of the absolute errors, m / rad */
    uint32_t lost;        /* scored frames whose step did not return RP_OK */
    uint64_t step_ns;     /* time spent in step(), all frames */
    /* motion turn only: geodesic rotation error (rad), summed over all scored frames, over
     * those within 10 degrees of yaw +-90 (and their count), and the largest */
    double rot_sum, rot90_sum, rot_max;
    uint32_t n90, lost90; /* frames near yaw +-90, and those of them lost */
    /* --estimate-offsets: |estimated - true| clock offset (ms) of each camera whose offset is
     * a state of the filter, relative to cam1 (the reference, not estimated), at frame
     * OFF_CHECK_FRAME ([0]) and at the last frame ([1]): sum, largest, count */
    double off_sum[2], off_max[2];
    uint32_t n_off[2];
    /* consistency of the published covariance (rp_estimate_t.cov) on the frames stepped OK:
     * sums of the normalised estimation error squared e^T C^-1 e, e = truth [-] estimate in
     * the pose chart (rp_rig.h), over the pose (6 dof), the translation block (3) and the
     * rotation block (3); nees_n frames, nees_bad of them with a covariance not positive
     * definite (not in the sums) */
    double nees_sum[3];
    uint32_t nees_n, nees_bad;
} run_result_t;

/* e^T C^-1 e for the n x n block of the 6x6 covariance c starting at row / column o, by
 * Cholesky in double; -1 if that block is not positive definite. */
static double nees_block(const rp_real c[36], const double e[6], int o, int n)
{
    double L[36], y[6];
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j <= i; ++j) {
            double acc = (double)c[(o + i) * 6 + o + j];
            for (int k = 0; k < j; ++k) {
                acc -= L[i * 6 + k] * L[j * 6 + k];
            }
            if (i == j) {
                if (!(acc > 0.0)) {
                    return -1.0;
                }
                L[i * 6 + i] = sqrt(acc);
            } else {
                L[i * 6 + j] = acc / L[j * 6 + j];
            }
        }
    }
    double q = 0.0;
    for (int i = 0; i < n; ++i) {
        double acc = e[o + i];
        for (int k = 0; k < i; ++k) {
            acc -= L[i * 6 + k] * y[k];
        }
        y[i] = acc / L[i * 6 + i];
        q += y[i] * y[i];
    }
    return q;
}

/* Adds frame's NEES (estimate est against the true pose truth[6]) to res. */
static void score_nees(const rp_estimate_t *est, const double truth[6], run_result_t *res)
{
    rp_real t[6], d[6];
    for (int c = 0; c < 6; ++c) {
        t[c] = (rp_real)truth[c];
    }
    rp_pose_minus(t, est->p, d); /* truth = est [+] d */
    double e[6];
    for (int c = 0; c < 6; ++c) {
        e[c] = (double)d[c];
    }
    const double q6 = nees_block(est->cov, e, 0, 6), qt = nees_block(est->cov, e, 0, 3),
                 qr = nees_block(est->cov, e, 3, 3);
    res->nees_n += 1;
    if (q6 < 0.0 || qt < 0.0 || qr < 0.0 || !isfinite(q6)) {
        res->nees_bad += 1;
        return;
    }
    res->nees_sum[0] += q6;
    res->nees_sum[1] += qt;
    res->nees_sum[2] += qr;
}

/* The frame at which the estimated clock offsets are scored (issue 15: within 0.5 ms of the
 * truth after 50 frames). */
#define OFF_CHECK_FRAME 50u

/* Score the filter's offset states against the simulated clocks (cam_offset_s, rp_sim.h's
 * camera order = the rig's): each state camera's offset relative to cam1's, in ms. */
static void score_offsets(const rp_ekf_t *e, const double *cam_offset_s, run_result_t *res,
                          int slot)
{
    for (int c = 1; c < RP_SIM_NCAMS && c < RP_MAX_CAMS; ++c) {
        if (!(e->toff_mask & (1u << c))) {
            continue;
        }
        const double est = (double)e->toff[c] - (double)e->toff[0];
        const double err = fabs(est - (cam_offset_s[c] - cam_offset_s[0])) * 1e3;
        res->off_sum[slot] += err;
        res->off_max[slot] = fmax(res->off_max[slot], isnan(err) ? INFINITY : err);
        res->n_off[slot] += 1;
    }
}

typedef struct {
    const opts_t *o;
    rp_sim_cfg_t cfg;
    run_result_t *res; /* [method][run] */
    pthread_mutex_t lock;
    uint32_t next_run; /* under lock */
    int failed;        /* under lock: a run could not be set up */
    char why[160];
} job_t;

/* --outliers: each feature of every camera replaced, with probability frac, by a pixel uniform
 * over the image (issue 14's gross outliers). */
static void gross_outliers(rp_frameset_t *fs, const rp_sim_cfg_t *cfg, double frac, rp_rng_t *rng)
{
    for (int c = 0; c < RP_MAX_CAMS; ++c) {
        for (uint16_t i = 0; i < fs->n[c]; ++i) {
            if (rp_rng_uniform(rng) < frac) {
                fs->f[c][i].uv[0] = (rp_real)(cfg->width * rp_rng_uniform(rng));
                fs->f[c][i].uv[1] = (rp_real)(cfg->height * rp_rng_uniform(rng));
            }
        }
    }
}

static double wrap_angle(double x)
{
    x = fmod(x + SIM_PI, 2.0 * SIM_PI);
    if (x < 0.0) {
        x += 2.0 * SIM_PI;
    }
    return x - SIM_PI;
}

static uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static void job_fail(job_t *job, const char *fmt, const char *a, const char *b)
{
    pthread_mutex_lock(&job->lock);
    if (!job->failed) {
        job->failed = 1;
        snprintf(job->why, sizeof job->why, fmt, a, b);
    }
    pthread_mutex_unlock(&job->lock);
}

/* R = Rz(g) Ry(b) Rx(a) (the paper's convention), double. */
static void angles_to_R(const double abg[3], double R[9])
{
    const double ca = cos(abg[0]), sa = sin(abg[0]), cb = cos(abg[1]), sb = sin(abg[1]);
    const double cg = cos(abg[2]), sg = sin(abg[2]);
    R[0] = cg * cb;  R[1] = cg * sb * sa - sg * ca;  R[2] = cg * sb * ca + sg * sa;
    R[3] = sg * cb;  R[4] = sg * sb * sa + cg * ca;  R[5] = sg * sb * ca - cg * sa;
    R[6] = -sb;      R[7] = cb * sa;                 R[8] = cb * ca;
}

/* The angle of R_true^T R_est (rad, 0..pi). */
static double geodesic(const double R_true[9], const rp_real p_est[6])
{
    double abg[3] = {(double)p_est[3], (double)p_est[4], (double)p_est[5]}, Re[9], tr = 0.0;
    angles_to_R(abg, Re);
    for (int i = 0; i < 9; ++i) {
        tr += R_true[i] * Re[i]; /* trace(A^T B) = sum of the elementwise products */
    }
    const double c = 0.5 * (tr - 1.0);
    return isfinite(c) ? acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c) : SIM_PI;
}

static void *worker(void *arg)
{
    job_t *job = arg;
    const opts_t *o = job->o;
    const method_opts_t mo = {o->noise_px, o->ekf_iterations, o->no_refine, o->est_offsets,
                               o->known_offsets ? o->cam_offset_s : NULL,
                               o->model_jitter ? o->jitter_ms * 1e-3 : 0.0,
                               o->time_noise_per_feature, o->plain_update,
                               o->paper_map};
    void *state[MAX_METHODS] = {NULL};
    rp_frameset_t *fs = malloc(sizeof *fs);
    rp_rig_t rig;
    rp_sim_make_rig(&job->cfg, &rig);
    int ok = fs != NULL;
    for (unsigned m = 0; ok && m < o->n_methods; ++m) {
        state[m] = calloc(1, o->m[m]->state_size); /* big: never on the stack */
        ok = state[m] != NULL;
    }
    if (!ok) {
        job_fail(job, "out of memory%s%s", "", "");
    }

    while (ok) {
        pthread_mutex_lock(&job->lock);
        const uint32_t r = job->next_run++;
        const int stop = job->failed || r >= o->runs;
        pthread_mutex_unlock(&job->lock);
        if (stop) {
            break;
        }
        rp_sim_run_t sr;
        rp_rng_t out_rng; /* --outliers: this run's own stream */
        rp_rng_seed(&out_rng, o->seed * 0x9E3779B97F4A7C15ull + r + 1u);
        if (rp_sim_run_init(&sr, &job->cfg, o->seed, r) != 0) {
            job_fail(job, "out of memory%s%s", "", ""); /* the clocks were checked in main */
            break;
        }
        for (unsigned m = 0; ok && m < o->n_methods; ++m) {
            const rp_status_t st = o->m[m]->init(state[m], &rig, &mo);
            if (st != RP_OK) {
                job_fail(job, "%s: init failed: %s", rp_pipe_layout_name(o->m[m]->layout),
                         rp_status_str(st));
                ok = 0;
            }
        }
        for (uint32_t j = 0; ok && j < o->frames; ++j) {
            (void)rp_sim_frame(&sr, j, fs); /* once, for every method */
            if (o->outliers > 0.0) {
                gross_outliers(fs, &job->cfg, o->outliers, &out_rng);
            }
            const double *truth = &sr.truth[6u * j];
            const double *truth_R = &sr.truth_R[9u * j];
            /* the turn's angle (yaw, or pitch), wrapped; near +-90 degrees: the crossings */
            const double yaw = wrap_angle(rp_sim_turn_yaw(&sr, rp_sim_set_time(&sr, j)));
            const int near90 = o->motion != RP_SIM_MOTION_PAPER &&
                               fabs(fabs(yaw) - 0.5 * SIM_PI) < 10.0 * SIM_PI / 180.0;
            char trace[2048];
            int trace_len = 0;
            if ((int64_t)r == o->trace_run || o->trace_run == -2) {
                trace_len = snprintf(trace, sizeof trace, "trace run %u frame %u yaw %.2f beta %.2f",
                                     r, j, yaw * 180.0 / SIM_PI, truth[4] * 180.0 / SIM_PI);
            }
            for (unsigned m = 0; m < o->n_methods; ++m) {
                run_result_t *res = &job->res[(size_t)m * o->runs + r];
                rp_estimate_t est;
                const uint64_t t0 = now_ns();
                const rp_status_t st = o->m[m]->step(state[m], fs, &est);
                res->step_ns += now_ns() - t0;
                const rp_ekf_t *filt = o->m[m]->filter ? o->m[m]->filter(state[m]) : NULL;
                if (o->est_offsets && filt != NULL && (j == OFF_CHECK_FRAME || j + 1 == o->frames)) {
                    score_offsets(filt, o->cam_offset_s, res, j == OFF_CHECK_FRAME ? 0 : 1);
                }
                if (j == 0) {
                    continue; /* frame 0 defines the world */
                }
                res->lost += st != RP_OK;
                if (st == RP_OK) {
                    score_nees(&est, truth, res);
                }
                for (int c = 0; c < 3; ++c) {
                    res->err_sum[c] += fabs((double)est.p[c] - truth[c]);
                }
                double ea[3], eb[3];
                for (int c = 3; c < NCOL; ++c) {
                    ea[c - 3] = fabs(wrap_angle((double)est.p[c] - truth[c]));
                }
                /* Through a turn the same rotation is also (a + pi, pi - b, g + pi): compare
                 * with the nearer triple (the paper's motion keeps |b| far from pi / 2, where
                 * the two meet, and is scored as before). */
                eb[0] = fabs(wrap_angle((double)est.p[3] - truth[3] - SIM_PI));
                eb[1] = fabs(wrap_angle((double)est.p[4] - (SIM_PI - truth[4])));
                eb[2] = fabs(wrap_angle((double)est.p[5] - truth[5] - SIM_PI));
                const int alt = o->motion != RP_SIM_MOTION_PAPER &&
                                eb[0] + eb[1] + eb[2] < ea[0] + ea[1] + ea[2];
                for (int c = 3; c < NCOL; ++c) {
                    res->err_sum[c] += alt ? eb[c - 3] : ea[c - 3];
                }
                if ((int64_t)r == o->trace_run || o->trace_run == -2) {
                    trace_len += snprintf(trace + trace_len, sizeof trace - trace_len,
                                          " | %s %d %.3f %.5f 0x%x", rp_pipe_layout_name(o->m[m]->layout),
                                          (int)st, geodesic(truth_R, est.p) * 180.0 / SIM_PI,
                                          fabs((double)est.p[0] - truth[0]), (unsigned)est.flags);
                    if (trace_len >= (int)sizeof trace) {
                        trace_len = (int)sizeof trace - 1;
                    }
                }
                if (o->motion != RP_SIM_MOTION_PAPER) {
                    const double g = geodesic(truth_R, est.p);
                    res->rot_sum += g;
                    res->rot_max = fmax(res->rot_max, g);
                    if (near90) {
                        res->rot90_sum += g;
                        res->n90 += 1;
                        res->lost90 += st != RP_OK;
                    }
                }
            }
            if (trace_len > 0 && j > 0) {
                fprintf(stderr, "%s\n", trace);
            }
        }
        rp_sim_run_free(&sr);
    }

    for (unsigned m = 0; m < o->n_methods; ++m) {
        free(state[m]);
    }
    free(fs);
    return NULL;
}

/* ---- summary and output -------------------------------------------------------------------- */

typedef struct {
    double mean[NCOL];       /* over all scored frames of all runs */
    double median_run[NCOL]; /* median over runs of the per-run mean */
    double worst_run[NCOL];  /* largest per-run mean */
    uint32_t worst_run_tx;   /* index of the run with the largest tx mean */
    uint64_t lost;
    double us_per_frame;     /* mean time of one step() call, microseconds */
    double rot, rot90, rot_max; /* motion turn: geodesic rotation error, rad (run_result_t) */
    uint32_t lost_runs;      /* runs with at least one lost frame */
    uint64_t lost90, n90;    /* motion turn: frames near yaw +-90 lost, and all of them */
    double off_mean[2], off_max[2]; /* --estimate-offsets (run_result_t): mean and largest
                                     * |offset error|, ms, at OFF_CHECK_FRAME and the last */
    uint64_t n_off[2];
    double nees[3];          /* mean NEES over the frames stepped OK: pose, translation,
                              * rotation (run_result_t) */
    uint64_t nees_n, nees_bad;
} summary_t;

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void summarise(const opts_t *o, const run_result_t *res, double *scratch, summary_t *s)
{
    const double per_run = (double)(o->frames - 1);
    uint64_t ns = 0;
    memset(s, 0, sizeof *s);
    double rot = 0.0, rot90 = 0.0;
    uint64_t n90 = 0;
    for (uint32_t r = 0; r < o->runs; ++r) {
        ns += res[r].step_ns;
        s->lost += res[r].lost;
        s->lost_runs += res[r].lost > 0;
        rot += res[r].rot_sum;
        rot90 += res[r].rot90_sum;
        n90 += res[r].n90;
        s->lost90 += res[r].lost90;
        s->rot_max = fmax(s->rot_max, res[r].rot_max);
    }
    s->rot = rot / (per_run * o->runs);
    s->rot90 = n90 ? rot90 / (double)n90 : 0.0;
    s->n90 = n90;
    double worst_tx = -1.0;
    for (uint32_t r = 0; r < o->runs; ++r) {
        const double v = res[r].err_sum[0] / per_run;
        if (v > worst_tx || isnan(v)) {
            worst_tx = v;
            s->worst_run_tx = r;
            if (isnan(v)) {
                break;
            }
        }
    }
    for (int c = 0; c < NCOL; ++c) {
        double sum = 0.0;
        for (uint32_t r = 0; r < o->runs; ++r) {
            scratch[r] = res[r].err_sum[c] / per_run;
            sum += res[r].err_sum[c];
        }
        s->mean[c] = sum / (per_run * o->runs);
        qsort(scratch, o->runs, sizeof *scratch, cmp_double);
        const uint32_t h = o->runs / 2u;
        s->median_run[c] = (o->runs % 2u) ? scratch[h] : 0.5 * (scratch[h - 1] + scratch[h]);
        s->worst_run[c] = scratch[o->runs - 1];
    }
    s->us_per_frame = (double)ns / 1e3 / ((double)o->runs * o->frames);
    for (int k = 0; k < 2; ++k) {
        double sum = 0.0;
        for (uint32_t r = 0; r < o->runs; ++r) {
            sum += res[r].off_sum[k];
            s->off_max[k] = fmax(s->off_max[k], res[r].off_max[k]);
            s->n_off[k] += res[r].n_off[k];
        }
        s->off_mean[k] = s->n_off[k] ? sum / (double)s->n_off[k] : 0.0;
    }
    double ns3[3] = {0.0, 0.0, 0.0};
    for (uint32_t r = 0; r < o->runs; ++r) {
        for (int k = 0; k < 3; ++k) {
            ns3[k] += res[r].nees_sum[k];
        }
        s->nees_n += res[r].nees_n;
        s->nees_bad += res[r].nees_bad;
    }
    const uint64_t good = s->nees_n - s->nees_bad;
    for (int k = 0; k < 3; ++k) {
        s->nees[k] = good ? ns3[k] / (double)good : NAN;
    }
}

static void json_num(const char *key, double v, int comma)
{
    if (isfinite(v)) {
        printf("\"%s\": %.6g%s", key, v, comma ? ", " : "");
    } else {
        printf("\"%s\": null%s", key, comma ? ", " : "");
    }
}

static void print_json(const opts_t *o, const summary_t *s)
{
    printf("{\"runs\": %u, \"frames\": %u, \"seed\": %llu, \"focal_px\": %.6g, "
           "\"noise_px\": %.6g, ",
           o->runs, o->frames, (unsigned long long)o->seed, o->focal_px, o->noise_px);
    if (o->motion != RP_SIM_MOTION_PAPER) {
        printf("\"motion\": \"%s\", ", motion_name(o->motion));
    }
    if (o->outliers > 0.0) {
        printf("\"outliers\": %.6g, ", o->outliers);
    }
    if (o->plain_update) {
        printf("\"plain_update\": 1, ");
    }
    if (o->paper_map) {
        printf("\"paper_map\": 1, ");
    }
    if (o->clocks_given) {
        const struct { const char *key; const double *v; } lists[] = {
            {"cam_offsets_ms", o->cam_offset_ms}, {"cam_phase_ms", o->cam_phase_ms},
            {"cam_fps", o->cam_fps}};
        for (size_t l = 0; l < sizeof lists / sizeof lists[0]; ++l) {
            printf("\"%s\": [", lists[l].key);
            for (int k = 0; k < RP_SIM_NCAMS; ++k) {
                printf("%s%.6g", k ? ", " : "", lists[l].v[k]);
            }
            printf("], ");
        }
        printf("\"jitter_ms\": %.6g, ", o->jitter_ms);
    }
    printf("\"rows\": [");
    for (unsigned m = 0; m < o->n_methods; ++m) {
        printf("%s{\"method\": \"%s\", ", m ? ", " : "", rp_pipe_layout_name(o->m[m]->layout));
        for (int c = 0; c < NCOL; ++c) {
            json_num(col_name[c], s[m].mean[c], 1);
        }
        json_num("us_per_frame", s[m].us_per_frame, 1);
        printf("\"lost_frames\": %llu, ", (unsigned long long)s[m].lost);
        if (o->motion != RP_SIM_MOTION_PAPER) {
            json_num("rot", s[m].rot, 1);
            if (o->motion == RP_SIM_MOTION_SMOOTH) {
                json_num("rot_max", s[m].rot_max, 1);
                printf("\"lost_runs\": %u, ", s[m].lost_runs);
            } else {
                json_num("rot90", s[m].rot90, 1);
                json_num("rot_max", s[m].rot_max, 1);
                printf("\"lost_runs\": %u, \"lost90\": %llu, \"frames90\": %llu, ",
                       s[m].lost_runs, (unsigned long long)s[m].lost90,
                       (unsigned long long)s[m].n90);
            }
        }
        if (s[m].n_off[0] > 0) {
            json_num("offset_err_ms_f50", s[m].off_mean[0], 1);
            json_num("offset_err_ms_f50_max", s[m].off_max[0], 1);
        }
        if (s[m].n_off[1] > 0) {
            json_num("offset_err_ms_last", s[m].off_mean[1], 1);
            json_num("offset_err_ms_last_max", s[m].off_max[1], 1);
        }
        json_num("nees", s[m].nees[0], 1);
        json_num("nees_t", s[m].nees[1], 1);
        json_num("nees_r", s[m].nees[2], 1);
        printf("\"nees_frames\": %llu, \"nees_not_pd\": %llu, ",
               (unsigned long long)s[m].nees_n, (unsigned long long)s[m].nees_bad);
        json_num("worst_run_tx", s[m].worst_run[0], 1);
        json_num("median_run_tx", s[m].median_run[0], 1);
        printf("\"worst_run_index\": %u}", s[m].worst_run_tx);
    }
    printf("]}\n");
}

static void print_cols(const char *label, const double v[NCOL], const char *fmt)
{
    printf("  %-22s", label);
    for (int c = 0; c < NCOL; ++c) {
        printf(fmt, v[c]);
    }
}

static void print_table(const opts_t *o, const rp_sim_cfg_t *cfg, const summary_t *s)
{
    printf("rigpose-sim: the paper's simulation protocol (Table 1)\n"
           "  %u runs x %u frames, seed %llu, %u thread%s\n"
           "  6 cameras %ux%u, fx = fy = %g px, principal point at the image centre\n"
           "  %u points in a shell %g..%g m; pixel noise sigma %g px\n"
           "  mean absolute error per frame over frames 1..%u of every run (frame 0 defines "
           "the world); m and rad\n\n",
           o->runs, o->frames, (unsigned long long)o->seed, o->threads,
           o->threads == 1 ? "" : "s", cfg->width, cfg->height, o->focal_px, cfg->n_points,
           cfg->r_in, cfg->r_out, o->noise_px, o->frames - 1);
    if (o->motion == RP_SIM_MOTION_TURN || o->motion == RP_SIM_MOTION_PITCH) {
        printf("  motion: a %s, %.3g rad/frame plus a smooth wobble (rp_sim.h); the "
               "paper's row is for its own motion\n\n",
               o->motion == RP_SIM_MOTION_TURN ? "turn (yaw)" : "pitch (the turn's control)",
               cfg->turn_rate * cfg->frame_dt);
    }
    if (o->motion == RP_SIM_MOTION_SMOOTH) {
        printf("  motion: smooth, three sinusoids per axis, |v| <= %g m/s per axis and |rate| <= "
               "%g rad/s per angle\n  (peaks about 0.5 m/s and 1 rad/s; rp_sim.h); the paper's "
               "row is for its own motion\n\n",
               cfg->smooth_v_axis, cfg->smooth_w_axis);
    }
    if (o->clocks_given) {
        static const char *const cam_name[RP_SIM_NCAMS] = {"cam1", "cam2", "cam3", "cam4",
                                                            "cam1b", "cam3b"};
        double fps[RP_SIM_NCAMS];
        printf("  camera clocks (rp_sim.h; the estimators get the stamps only, not the offsets "
               "or the jitter):\n  %-22s", "");
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            printf("%10s", cam_name[k]);
            fps[k] = o->cam_fps[k] > 0.0 ? o->cam_fps[k] : 1.0 / cfg->frame_dt;
        }
        printf("\n");
        print_cols("offset (ms, unknown)", o->cam_offset_ms, "%10.3f");
        printf("\n");
        print_cols("phase (ms, stamped)", o->cam_phase_ms, "%10.3f");
        printf("\n");
        print_cols("frame rate (Hz)", fps, "%10.3f");
        printf("\n  capture-time jitter: Gaussian, sigma %g ms per camera frame (unknown); "
               "frame sets at the fastest camera's rate\n\n", o->jitter_ms);
    }
    if (o->outliers > 0.0) {
        printf("  gross outliers: %.3g of every camera's features replaced by uniform pixels, "
               "anew every frame\n\n", o->outliers);
    }
    if (o->plain_update) {
        printf("  ablation: the plain gated update (no 1-point RANSAC, no re-find)\n\n");
    }
    if (o->paper_map) {
        printf("  ablation: the paper's stereo map (landmarks only at (re-)initialisations)\n\n");
    }
    if (o->ekf_iterations || o->no_refine) {
        printf("  ablation: EKF iterations %u, structure refinement %s\n\n",
               o->ekf_iterations ? o->ekf_iterations : 3u, o->no_refine ? "off" : "on");
    }
    printf("  %-22s", "");
    for (int c = 0; c < NCOL; ++c) {
        printf("%10s", col_name[c]);
    }
    printf("%10s%8s\n", "us/frame", "lost");
    for (unsigned m = 0; m < o->n_methods; ++m) {
        const method_t *me = o->m[m];
        const paper_row_t *pr = paper_row(me->paper);
        char label[64];
        snprintf(label, sizeof label, "%s", rp_pipe_layout_name(me->layout));
        print_cols(label, s[m].mean, "%10.6f");
        printf("%10.1f%8llu\n", s[m].us_per_frame, (unsigned long long)s[m].lost);
        if (pr) {
            double ratio[NCOL];
            snprintf(label, sizeof label, "paper, %s", pr->name);
            print_cols(label, pr->v, "%10.4f");
            printf("\n");
            for (int c = 0; c < NCOL; ++c) {
                ratio[c] = s[m].mean[c] / pr->v[c];
            }
            print_cols("ours / paper", ratio, "%10.2f");
            printf("\n");
        }
        print_cols("per-run mean, median", s[m].median_run, "%10.6f");
        printf("\n");
        print_cols("per-run mean, worst", s[m].worst_run, "%10.6f");
        printf("  (worst tx: run %u)\n", s[m].worst_run_tx);
        printf("  %-22s%10.3g%10.3g%10.3g  (mean; 6, 3, 3 for a consistent covariance; %llu "
               "frames, %llu not positive definite)\n",
               "NEES: pose, t, rotation", s[m].nees[0], s[m].nees[1], s[m].nees[2],
               (unsigned long long)(s[m].nees_n), (unsigned long long)s[m].nees_bad);
        if (s[m].n_off[0] > 0 || s[m].n_off[1] > 0) {
            printf("  %-22s%10.3f%10.3f  (ms, |estimated - true| offset to cam1 of the %llu "
                   "state cameras x runs)\n  %-22s%10.3f%10.3f\n",
                   "offsets f50: mean, max", s[m].off_mean[0], s[m].off_max[0],
                   (unsigned long long)s[m].n_off[0], "offsets last: mean, max",
                   s[m].off_mean[1], s[m].off_max[1]);
        }
        if (o->motion == RP_SIM_MOTION_SMOOTH) {
            printf("  %-22s%10.6f%10.6f  (rad; %u of %u runs lost frames)\n", "rotation: all, max",
                   s[m].rot, s[m].rot_max, s[m].lost_runs, o->runs);
        } else if (o->motion != RP_SIM_MOTION_PAPER) {
            printf("  %-22s%10.6f%10.6f%10.6f  (rad; %u of %u runs lost frames; %llu of the "
                   "%llu frames near yaw +-90 lost)\n",
                   "rotation: all, yaw+-90, max", s[m].rot, s[m].rot90, s[m].rot_max,
                   s[m].lost_runs, o->runs, (unsigned long long)s[m].lost90,
                   (unsigned long long)s[m].n90);
        }
        printf("\n");
    }
}

/* Run every (method, run) of o on the simulation cfg into res[method][run], on o->threads
 * threads. Returns the number of threads used (>= 1), or 0 with the reason printed. */
static unsigned run_experiment(const opts_t *o, const rp_sim_cfg_t *cfg, run_result_t *res)
{
    job_t job;
    memset(&job, 0, sizeof job);
    job.o = o;
    job.cfg = *cfg;
    job.res = res;
    memset(res, 0, (size_t)o->n_methods * o->runs * sizeof *res);
    pthread_mutex_init(&job.lock, NULL);

    pthread_t tid[MAX_THREADS];
    unsigned started = 0;
    for (unsigned t = 0; t < o->threads; ++t) {
        if (pthread_create(&tid[t], NULL, worker, &job) != 0) {
            break;
        }
        ++started;
    }
    if (started == 0) {
        worker(&job); /* no threads to be had: do it here */
    }
    for (unsigned t = 0; t < started; ++t) {
        pthread_join(tid[t], NULL);
    }
    pthread_mutex_destroy(&job.lock);
    if (job.failed) {
        fprintf(stderr, "rigpose-sim: %s\n", job.why);
        return 0;
    }
    return started ? started : 1;
}

/* ---- the layout study ---------------------------------------------------------------------- */

/* One method on one placement: mean translation / rotation error over all scored frames (the
 * mean of tx ty tz, of alpha beta gamma) and the worst run's. */
typedef struct {
    double t, r;             /* m, rad */
    double worst_t, worst_r; /* largest per-run means, m, rad */
    double tx;               /* mean |tx error|, m */
    uint64_t lost;
} layout_score_t;

static void layout_score(const opts_t *o, const run_result_t *res, layout_score_t *sc)
{
    const double per_run = (double)(o->frames - 1);
    memset(sc, 0, sizeof *sc);
    for (uint32_t r = 0; r < o->runs; ++r) {
        const double t = (res[r].err_sum[0] + res[r].err_sum[1] + res[r].err_sum[2]) / 3.0;
        const double a = (res[r].err_sum[3] + res[r].err_sum[4] + res[r].err_sum[5]) / 3.0;
        sc->t += t;
        sc->r += a;
        sc->tx += res[r].err_sum[0];
        sc->worst_t = fmax(sc->worst_t, t / per_run);
        sc->worst_r = fmax(sc->worst_r, a / per_run);
        sc->lost += res[r].lost;
    }
    sc->t /= per_run * o->runs;
    sc->r /= per_run * o->runs;
    sc->tx /= per_run * o->runs;
}

static void print_place(const rp_sim_place_t *p)
{
    printf(" %7.4f %7.4f %7.4f %5.0f", p->D[0], p->D[1], p->D[2], p->yaw * 180.0 / SIM_PI);
}

static void print_layout_json(const opts_t *o, const rp_sim_layout_t *lay, uint32_t n,
                              const layout_score_t *sc, const uint32_t *order)
{
    printf("{\"runs\": %u, \"frames\": %u, \"seed\": %llu, \"source\": \"%s\", "
           "\"ranked_by\": \"%s mean translation error\", \"placements\": [",
           o->runs, o->frames, (unsigned long long)o->seed,
           o->layout_file ? o->layout_file : "grid", rp_pipe_layout_name(o->m[0]->layout));
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t i = order[k];
        const rp_sim_layout_t *l = &lay[i];
        printf("%s{\"rank\": %u, \"name\": \"%s\", \"paper\": %s, "
               "\"cam2\": [%.6g, %.6g, %.6g, %.6g], \"cam4\": [%.6g, %.6g, %.6g, %.6g]",
               k ? ", " : "", k + 1, l->name, l->is_paper ? "true" : "false", l->cam2.D[0],
               l->cam2.D[1], l->cam2.D[2], l->cam2.yaw * 180.0 / SIM_PI, l->cam4.D[0],
               l->cam4.D[1], l->cam4.D[2], l->cam4.yaw * 180.0 / SIM_PI);
        for (unsigned m = 0; m < o->n_methods; ++m) {
            const layout_score_t *s = &sc[(size_t)i * o->n_methods + m];
            printf(", \"%s\": {", rp_pipe_layout_name(o->m[m]->layout));
            json_num("t", s->t, 1);
            json_num("r", s->r, 1);
            json_num("tx", s->tx, 1);
            json_num("worst_run_t", s->worst_t, 1);
            json_num("worst_run_r", s->worst_r, 1);
            printf("\"lost_frames\": %llu}", (unsigned long long)s->lost);
        }
        printf("}");
    }
    printf("]}\n");
}

static void print_layout_table(const opts_t *o, const rp_sim_layout_t *lay, uint32_t n,
                               const layout_score_t *sc, const uint32_t *order)
{
    printf("rigpose-sim --layout-study: %u placements of cam2/cam4 (%s), ranked by %s's mean "
           "translation error\n"
           "  %u runs x %u frames per placement, seed %llu, %u thread%s; t = mean of |tx|,|ty|,"
           "|tz| (m), r = mean of |alpha|,|beta|,|gamma| (rad),\n"
           "  worst = the worst run's mean; * = the paper's placement\n\n",
           n, o->layout_file ? o->layout_file : "built-in grid",
           rp_pipe_layout_name(o->m[0]->layout), o->runs,
           o->frames, (unsigned long long)o->seed, o->threads, o->threads == 1 ? "" : "s");
    printf("%-4s  %-22s %-29s %-29s", "rank", "placement", "  cam2: x       y       z  yaw",
           "  cam4: x       y       z  yaw");
    for (unsigned m = 0; m < o->n_methods; ++m) {
        printf(" | %-6s%9s%9s%9s%9s", rp_pipe_layout_name(o->m[m]->layout), "t", "r", "worst t",
               "worst r");
    }
    printf("\n");
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t i = order[k];
        printf("%3u%s  %-22s", k + 1, lay[i].is_paper ? "*" : " ", lay[i].name);
        print_place(&lay[i].cam2);
        print_place(&lay[i].cam4);
        for (unsigned m = 0; m < o->n_methods; ++m) {
            const layout_score_t *s = &sc[(size_t)i * o->n_methods + m];
            printf(" | %-6s%9.6f%9.6f%9.6f%9.6f", "", s->t, s->r, s->worst_t, s->worst_r);
        }
        printf("\n");
    }
}

static int layout_study(opts_t *o, const rp_sim_cfg_t *base, run_result_t *res)
{
    static rp_sim_layout_t lay[RP_SIM_LAYOUT_MAX];
    char err[300];
    int n = o->layout_file ? rp_sim_layout_read(o->layout_file, lay, RP_SIM_LAYOUT_MAX, err,
                                                sizeof err)
                           : rp_sim_layout_grid(lay, RP_SIM_LAYOUT_MAX);
    if (n < 0) {
        fprintf(stderr, "rigpose-sim: %s\n", err);
        return 2;
    }
    layout_score_t *sc = calloc((size_t)n * o->n_methods, sizeof *sc);
    double *key = calloc((size_t)n, sizeof *key);
    uint32_t *order = calloc((size_t)n, sizeof *order);
    if (!sc || !key || !order) {
        fprintf(stderr, "rigpose-sim: out of memory\n");
        return 1;
    }
    unsigned used = 1;
    for (int i = 0; i < n; ++i) {
        rp_sim_cfg_t cfg = *base;
        rp_sim_layout_apply(&lay[i], &cfg);
        used = run_experiment(o, &cfg, res);
        if (used == 0) {
            return 1;
        }
        for (unsigned m = 0; m < o->n_methods; ++m) {
            layout_score(o, &res[(size_t)m * o->runs], &sc[(size_t)i * o->n_methods + m]);
        }
        key[i] = sc[(size_t)i * o->n_methods].t;
        if (!o->json) {
            fprintf(stderr, "\r  placement %d/%d", i + 1, n);
        }
    }
    if (!o->json) {
        fprintf(stderr, "\n");
    }
    o->threads = used;
    rp_sim_layout_rank(key, (uint32_t)n, order);
    if (o->json) {
        print_layout_json(o, lay, (uint32_t)n, sc, order);
    } else {
        print_layout_table(o, lay, (uint32_t)n, sc, order);
    }
    free(order);
    free(key);
    free(sc);
    return 0;
}

/* ---- deviations from the core's defaults --------------------------------------------------- */

static const char *const sim_why[][2] = {
    {"stereo.ekf.q_", "the feature-level protocol's Table 1 figures are measured with 1; the "
                      "core's 3 is chosen on rendered images (config/README.md)"},
    {"stereo.ekf.sigma_px", "the simulation's pixel noise (--noise-px)"},
    {"gc.ekf.sigma_px", "the simulation's pixel noise (--noise-px)"},
    {"mono.ekf.sigma_px", "the simulation's pixel noise (--noise-px)"},
    {"stereo.ekf.iterations", "--ekf-iterations"},
    {"gc.ekf.iterations", "--ekf-iterations"},
    {"mono.ekf.iterations", "--ekf-iterations"},
    {"stereo.refine_structure", "--no-refine"},
    {"stereo.ekf.toff_estimate", "--estimate-offsets"},
    {"gc.ekf.toff_estimate", "--estimate-offsets"},
    {"stereo.ekf.toff0_s", "--known-offsets"},
    {"gc.ekf.toff0_s", "--known-offsets"},
    {"mono.ekf.toff0_s", "--known-offsets"},
    {"stereo.ekf.time_jitter_s", "--model-jitter: the clocks' --jitter-ms"},
    {"gc.ekf.time_jitter_s", "--model-jitter: the clocks' --jitter-ms"},
    {"gc.init_on_sphere", "the scene surrounds the rig: depth along the ray"},
    {"gc.init_depth", "the simulated shell's mid radius (0.667 + 1) / 2 m, +- 0.15 m "
                      "(rp_sim_gc_cfg)"},
    {"mono.init_depth", "the simulated shell's mid depth (0.667 + 1) / 2 m, +- 0.15 m"},
    {NULL, NULL}};

/* Every setting in which the selected methods' estimators differ from the core's defaults for
 * their layout (rp_pipe_default_cfg; the simulator numbers the cameras as it does), one line
 * each on stderr: the figures on stdout are measured with them. */
static void print_deviations(const opts_t *o)
{
    const method_opts_t mo = {o->noise_px, o->ekf_iterations, o->no_refine, o->est_offsets,
                               o->known_offsets ? o->cam_offset_s : NULL,
                               o->model_jitter ? o->jitter_ms * 1e-3 : 0.0,
                               o->time_noise_per_feature, o->plain_update,
                               o->paper_map};
    for (unsigned i = 0; i < o->n_methods; ++i) {
        const rp_pipe_layout_t l = o->m[i]->layout;
        rp_pipe_cfg_t cfg;
        if (rp_pipe_default_cfg(l, &cfg) != RP_OK) {
            continue;
        }
        if (l == RP_PIPE_STEREO4 || l == RP_PIPE_STEREO2) {
            cfg.stereo = stereo_cfg(&mo, l == RP_PIPE_STEREO4);
        } else if (l == RP_PIPE_GC) {
            cfg.gc = gc_cfg(&mo);
        } else {
            /* camK: camera K-1 (RP_SIM_CAM1.. are 0..3); rc: four of mono_cfg, rc_cams 0..3 */
            cfg.mono = mono_cfg(l == RP_PIPE_RC ? RP_SIM_CAM1 : (uint8_t)(l - RP_PIPE_CAM1), &mo);
        }
        (void)rp_cfg_diff_print(stderr, "rigpose-sim", &cfg, sim_why);
    }
}

int main(int argc, char **argv)
{
    opts_t o;
    const int pa = parse_args(argc, argv, &o);
    if (pa != 0) {
        usage(pa > 0 ? stdout : stderr, argv[0]);
        return pa > 0 ? 0 : 2;
    }
    if (o.threads > o.runs) {
        o.threads = o.runs;
    }
    print_deviations(&o);

    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.focal_px = o.focal_px;
    cfg.noise_px = o.noise_px;
    cfg.n_frames = o.frames;
    cfg.motion = o.motion;
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        cfg.cam_offset_s[k] = o.cam_offset_ms[k] * 1e-3;
        cfg.cam_phase_s[k] = o.cam_phase_ms[k] * 1e-3;
        cfg.cam_fps[k] = o.cam_fps[k];
    }
    cfg.jitter_s = o.jitter_ms * 1e-3;
    if (o.clocks_given) {
        rp_sim_run_t probe; /* the clocks are checked here, once, not in the workers */
        const int st = rp_sim_run_init(&probe, &cfg, o.seed, 0);
        rp_sim_run_free(&probe);
        if (st != 0) {
            fprintf(stderr, "rigpose-sim: %s\n", st == -2 ? "these camera clocks cannot be "
                    "simulated: rates 0 or 1..1000 Hz, each camera at the fastest one's rate or at "
                    "least 2 us a frame slower, phases 0..1000 ms, offsets within 1000 ms, jitter "
                    "up to 100 ms (rp_sim.h)" : "out of memory");
            return 2;
        }
    }
    run_result_t *res = calloc((size_t)o.n_methods * o.runs, sizeof *res);
    double *scratch = malloc((size_t)o.runs * sizeof *scratch);
    summary_t *sum = calloc(o.n_methods, sizeof *sum);
    if (!res || !scratch || !sum) {
        fprintf(stderr, "rigpose-sim: out of memory\n");
        return 1;
    }
    int rc = 0;
    if (o.layout_study) {
        rc = layout_study(&o, &cfg, res);
    } else {
        const unsigned used = run_experiment(&o, &cfg, res);
        if (used == 0) {
            rc = 1;
        } else {
            o.threads = used;
            for (unsigned m = 0; m < o.n_methods; ++m) {
                summarise(&o, &res[(size_t)m * o.runs], scratch, &sum[m]);
            }
            if (o.json) {
                print_json(&o, sum);
            } else {
                print_table(&o, &cfg, sum);
            }
            for (unsigned m = 0; o.max_rot > 0.0 && m < o.n_methods; ++m) {
                if (!(sum[m].rot_max <= o.max_rot) || sum[m].lost > 0) {
                    fprintf(stderr, "rigpose-sim: %s does not hold through the %s: largest "
                            "rotation error %.3f deg (bound %.3f), %llu lost frames\n",
                            rp_pipe_layout_name(o.m[m]->layout),
                            motion_name(o.motion),
                            sum[m].rot_max * 180.0 / SIM_PI, o.max_rot * 180.0 / SIM_PI,
                            (unsigned long long)sum[m].lost);
                    rc = 1;
                }
            }
        }
    }
    free(sum);
    free(scratch);
    free(res);
    return rc;
}
