/*
 * rp_sim.c - the paper's simulation protocol (Table 1); see rp_sim.h and docs/design.md.
 *
 * Everything is computed in double and converted to rp_real only where it enters core types
 * (the rig, the frame set), so the simulator is the same in float and double builds up to that
 * final rounding. Randomness comes from counter-style keys: a run's points and trajectory from
 * hash(seed, run), the noise of one feature from hash(seed, run, frame, camera, point id). So a
 * run does not depend on the order or thread it is computed in, and a feature's noise does not
 * depend on which other points happen to be visible.
 */
#include "rp_sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rigpose/rp_camera.h"
#include "rigpose/rp_rot.h"

_Static_assert(RP_MAX_CAMS >= RP_SIM_NCAMS, "the protocol's rig needs 6 cameras");

#define SIM_PI 3.14159265358979323846

/* Stream domains: keep the point cloud, the trajectory and the noise independent. */
enum { DOM_POINTS = 1, DOM_TRAJ = 2, DOM_NOISE = 3, DOM_TURN = 4, DOM_SMOOTH = 5, DOM_CLOCK = 6 };

/* ---- random numbers ------------------------------------------------------------------------ */

/* splitmix64's output function: a bijective 64-bit mixer. */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Key of (seed, run, domain, index): a hash chain, so that nearby tuples give unrelated keys. */
static uint64_t sim_key(uint64_t seed, uint32_t run, uint32_t domain, uint64_t index)
{
    uint64_t h = mix64(seed + 0x9E3779B97F4A7C15ull);
    h = mix64(h ^ ((uint64_t)run + 0x632BE59BD9B4E019ull));
    h = mix64(h ^ (((uint64_t)domain << 56) + 0x8CB92BA72F3D8DD7ull));
    return mix64(h ^ index);
}

void rp_rng_seed(rp_rng_t *r, uint64_t seed)
{
    uint64_t x = seed;
    for (int i = 0; i < 4; ++i) {
        x += 0x9E3779B97F4A7C15ull; /* splitmix64 */
        r->s[i] = mix64(x);
    }
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t rp_rng_next(rp_rng_t *r)
{
    uint64_t *s = r->s; /* xoshiro256** */
    const uint64_t out = rotl(s[1] * 5u, 7) * 9u;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return out;
}

double rp_rng_uniform(rp_rng_t *r)
{
    return (double)(rp_rng_next(r) >> 11) * (1.0 / 9007199254740992.0); /* 53 bits / 2^53 */
}

double rp_rng_gauss(rp_rng_t *r)
{
    /* Box-Muller, cosine branch; u1 in (0, 1] keeps the log finite. */
    const double u1 = 1.0 - rp_rng_uniform(r);
    const double u2 = rp_rng_uniform(r);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * SIM_PI * u2);
}

/* Two independent N(0, 1) draws: both branches of Box-Muller. */
static void gauss_pair(rp_rng_t *r, double *g0, double *g1)
{
    const double u1 = 1.0 - rp_rng_uniform(r);
    const double u2 = rp_rng_uniform(r);
    const double rad = sqrt(-2.0 * log(u1));
    *g0 = rad * cos(2.0 * SIM_PI * u2);
    *g1 = rad * sin(2.0 * SIM_PI * u2);
}

/* Magnitude U[lo, hi] with a random sign. */
static double signed_mag(rp_rng_t *r, double lo, double hi)
{
    const double m = lo + (hi - lo) * rp_rng_uniform(r);
    return (rp_rng_next(r) >> 63) ? -m : m;
}

/* ---- small double rotation helpers (row-major 3x3) ----------------------------------------- */

static void mat_mul(const double A[9], const double B[9], double C[9])
{
    double T[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            T[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
        }
    }
    memcpy(C, T, sizeof T);
}

/* R = Rz(g) Ry(b) Rx(a), the paper's convention (rp_rot.h). */
static void rot_from_angles(double a, double b, double g, double R[9])
{
    const double ca = cos(a), sa = sin(a), cb = cos(b), sb = sin(b), cg = cos(g), sg = sin(g);
    R[0] = cg * cb;  R[1] = cg * sb * sa - sg * ca;  R[2] = cg * sb * ca + sg * sa;
    R[3] = sg * cb;  R[4] = sg * sb * sa + cg * ca;  R[5] = sg * sb * ca - cg * sa;
    R[6] = -sb;      R[7] = cb * sa;                 R[8] = cb * ca;
}

/* ---- configuration and rig ------------------------------------------------------------------ */

void rp_sim_default_cfg(rp_sim_cfg_t *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->n_points = 10000;
    cfg->r_in = 0.667;
    cfg->r_out = 1.0;
    cfg->focal_px = 800.0;
    cfg->width = 640;
    cfg->height = 480;
    cfg->noise_px = 0.5;
    cfg->t_min = 0.005;
    cfg->t_max = 0.015;
    cfg->a_min = 0.005;
    cfg->a_max = 0.02;
    cfg->min_depth = 0.05;
    cfg->frame_dt = 1.0 / 30.0;
    cfg->n_frames = 100;
    cfg->cam2 = rp_sim_paper_place(1);
    cfg->cam4 = rp_sim_paper_place(0);
    cfg->motion = RP_SIM_MOTION_PAPER;
    cfg->turn_rate = 1.05;
    cfg->turn_ramp_s = 1.0 / 3.0;
    cfg->wobble_t = 0.03;
    cfg->wobble_a = 0.05;
    cfg->smooth_v_axis = 0.4;
    cfg->smooth_w_axis = 0.8;
}

rp_vo_gc_cfg_t rp_sim_gc_cfg(const rp_sim_cfg_t *cfg)
{
    rp_vo_gc_cfg_t c = rp_vo_gc_default_cfg();
    c.n_cams = 4;
    c.cams[0] = RP_SIM_CAM1;
    c.cams[1] = RP_SIM_CAM2;
    c.cams[2] = RP_SIM_CAM3;
    c.cams[3] = RP_SIM_CAM4;
    c.init_depth_m = (rp_real)((cfg->r_in + cfg->r_out) / 2.0);
    c.init_depth_sigma_m = (rp_real)0.15;
    c.init_on_sphere = 1; /* the scene surrounds the rig: depth measured along the ray */
    c.ekf.sigma_px = (rp_real)(cfg->noise_px > 0.01 ? cfg->noise_px : 0.01);
    return c;
}

rp_vo_stereo_cfg_t rp_sim_stereo_cfg(const rp_sim_cfg_t *cfg, int both_pairs)
{
    rp_vo_stereo_cfg_t c = rp_vo_stereo_default_cfg();
    c.n_pairs = both_pairs ? 2 : 1;
    c.pair_a[0] = RP_SIM_CAM1;
    c.pair_b[0] = RP_SIM_CAM1B;
    if (both_pairs) {
        c.pair_a[1] = RP_SIM_CAM3;
        c.pair_b[1] = RP_SIM_CAM3B;
    }
    c.ekf.q_trans = (rp_real)RP_SIM_STEREO_Q;
    c.ekf.q_rot = (rp_real)RP_SIM_STEREO_Q;
    c.ekf.sigma_px = (rp_real)(cfg->noise_px > 0.01 ? cfg->noise_px : 0.01);
    return c;
}

rp_sim_place_t rp_sim_paper_place(int right)
{
    const double s = 0.05 * sqrt(3.0);
    rp_sim_place_t p = {{right ? s : -s, 0.0, -0.05}, right ? 0.5 * SIM_PI : -0.5 * SIM_PI};
    return p;
}

/* cos/sin snapped to 0 and +-1 near multiples of 90 degrees, so that the paper's placements
 * give exactly the rotations of the protocol. */
static double snap_unit(double v)
{
    if (fabs(v) < 1e-12) {
        return 0.0;
    }
    if (fabs(fabs(v) - 1.0) < 1e-12) {
        return v > 0.0 ? 1.0 : -1.0;
    }
    return v;
}

/* Camera-to-cam1 rotation of a placement: Ry(yaw) (columns: the camera's axes in cam1's
 * frame; y stays down). */
static void place_rotation(const rp_sim_place_t *p, double R[9])
{
    const double c = snap_unit(cos(p->yaw)), s = snap_unit(sin(p->yaw));
    const double Ry[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
    memcpy(R, Ry, sizeof Ry);
}

void rp_sim_make_rig(const rp_sim_cfg_t *cfg, rp_rig_t *rig)
{
    /* Camera-to-cam1 rotations (columns: the camera's x, y, z axes in cam1's frame). All
     * cameras keep y down; cam3 = Ry(180 deg); cam2 and cam4 as placed (the paper: Ry(+90 deg)
     * and Ry(-90 deg)). */
    static const double R_fwd[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const double R_back[9] = {-1, 0, 0, 0, 1, 0, 0, 0, -1};
    double R_cam2[9], R_cam4[9];
    place_rotation(&cfg->cam2, R_cam2);
    place_rotation(&cfg->cam4, R_cam4);
    const struct { const double *R; double D[3]; } geo[RP_SIM_NCAMS] = {
        [RP_SIM_CAM1] = {R_fwd, {0.0, 0.0, 0.0}},
        [RP_SIM_CAM2] = {R_cam2, {cfg->cam2.D[0], cfg->cam2.D[1], cfg->cam2.D[2]}},
        [RP_SIM_CAM3] = {R_back, {0.0, 0.0, -0.1}},
        [RP_SIM_CAM4] = {R_cam4, {cfg->cam4.D[0], cfg->cam4.D[1], cfg->cam4.D[2]}},
        [RP_SIM_CAM1B] = {R_fwd, {0.1, 0.0, 0.0}},
        [RP_SIM_CAM3B] = {R_back, {0.1, 0.0, -0.1}},
    };
    const double cx = 0.5 * (cfg->width - 1), cy = 0.5 * (cfg->height - 1); /* image centre */

    memset(rig, 0, sizeof *rig);
    rig->n_cams = RP_SIM_NCAMS;
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        for (int i = 0; i < 9; ++i) {
            rig->cam[k].R[i] = (rp_real)geo[k].R[i];
        }
        for (int i = 0; i < 3; ++i) {
            rig->cam[k].D[i] = (rp_real)geo[k].D[i];
        }
        rig->cam[k].cam = rp_cam_pinhole(cfg->width, cfg->height, (rp_real)cfg->focal_px,
                                         (rp_real)cfg->focal_px, (rp_real)cx, (rp_real)cy);
    }
}

/* Frame j's truth: R_j, and the pose [d, angles] with the angles what the core's own extraction
 * makes of R_j (rp_rot_to_angles: R_j is a rotation by construction, its status is not needed). */
static void store_truth(rp_sim_run_t *sr, uint32_t j, const double R[9], const double d[3])
{
    double *t = &sr->truth[6u * j];
    memcpy(&sr->truth_R[9u * j], R, 9 * sizeof R[0]);
    memcpy(t, d, 3 * sizeof d[0]);
    rp_real Rr[9], abg[3];
    for (int i = 0; i < 9; ++i) {
        Rr[i] = (rp_real)R[i];
    }
    /* ignored: only non-finite input fails; R is a product of rotations of finite angles */
    (void)rp_rot_to_angles(Rr, abg);
    for (int i = 0; i < 3; ++i) {
        t[3 + i] = (double)abg[i];
    }
}

/* ---- a run: points and trajectory ---------------------------------------------------------- */

/* The clocks of cfg into sr (rp_sim.h). Returns 0, or -2 for clocks it cannot simulate. */
static int clocks_init(rp_sim_run_t *sr, const rp_sim_cfg_t *cfg)
{
    int any = cfg->jitter_s != 0.0;
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        any |= cfg->cam_offset_s[k] != 0.0 || cfg->cam_phase_s[k] != 0.0 || cfg->cam_fps[k] != 0.0;
    }
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        const double fps = cfg->cam_fps[k];
        /* 0, or 1..1000 Hz: cam_dt_us (> -1 frame) fits its int32_t */
        if (!(fps == 0.0 || (fps >= 1.0 && fps <= 1000.0)) || !(cfg->cam_phase_s[k] >= 0.0) ||
            !(cfg->cam_phase_s[k] <= 1.0) || !(fabs(cfg->cam_offset_s[k]) <= 1.0)) {
            return -2;
        }
        sr->cam_period_s[k] = fps > 0.0 ? 1.0 / fps : cfg->frame_dt;
        sr->cam_phase_us[k] = (int64_t)llround(cfg->cam_phase_s[k] * 1e6);
        if (sr->cam_period_s[k] < sr->cam_period_s[sr->set_cam]) {
            sr->set_cam = k;
        }
    }
    if (!(cfg->jitter_s >= 0.0 && cfg->jitter_s <= 0.1) || !(cfg->frame_dt > 0.0)) {
        return -2;
    }
    /* Slower cameras: at least 2 us a frame slower, so that the stamps' rounding (+-0.5 us
     * each) never puts two of their frames between two sets'. */
    const double pf = sr->cam_period_s[sr->set_cam];
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        if (sr->cam_period_s[k] != pf && sr->cam_period_s[k] < pf + 2e-6) {
            return -2;
        }
    }
    if (any && cfg->motion == RP_SIM_MOTION_PAPER) {
        return -2; /* the random walk has no pose between frames */
    }
    sr->clocked = any;
    return 0;
}

int rp_sim_run_init(rp_sim_run_t *sr, const rp_sim_cfg_t *cfg, uint64_t seed, uint32_t run)
{
    memset(sr, 0, sizeof *sr);
    sr->cfg = *cfg;
    sr->seed = seed;
    sr->run = run;
    rp_sim_make_rig(cfg, &sr->rig);
    if (clocks_init(sr, cfg) != 0) {
        return -2;
    }

    const size_t nf = cfg->n_frames ? cfg->n_frames : 1u;
    sr->points = malloc((size_t)cfg->n_points * 3u * sizeof(double) + 1u);
    sr->truth = malloc(nf * 6u * sizeof(double));
    sr->truth_R = malloc(nf * 9u * sizeof(double));
    if (!sr->points || !sr->truth || !sr->truth_R) {
        rp_sim_run_free(sr);
        return -1;
    }

    /* Points: uniform in the shell's volume (r^3 uniform) and uniform in direction. */
    rp_rng_t rng;
    rp_rng_seed(&rng, sim_key(seed, run, DOM_POINTS, 0));
    const double r3_in = cfg->r_in * cfg->r_in * cfg->r_in;
    const double r3_out = cfg->r_out * cfg->r_out * cfg->r_out;
    for (uint32_t i = 0; i < cfg->n_points; ++i) {
        const double r = cbrt(r3_in + (r3_out - r3_in) * rp_rng_uniform(&rng));
        const double z = 2.0 * rp_rng_uniform(&rng) - 1.0;
        const double phi = 2.0 * SIM_PI * rp_rng_uniform(&rng);
        const double rho = sqrt(fmax(0.0, 1.0 - z * z));
        sr->points[3u * i] = r * rho * cos(phi);
        sr->points[3u * i + 1] = r * rho * sin(phi);
        sr->points[3u * i + 2] = r * z;
    }

    if (cfg->motion == RP_SIM_MOTION_TURN || cfg->motion == RP_SIM_MOTION_PITCH) {
        /* The turn's parameters from their own stream (the paper's motion's stream unused). */
        rp_rng_seed(&rng, sim_key(seed, run, DOM_TURN, 0));
        sr->turn_sign = (rp_rng_next(&rng) >> 63) ? -1.0 : 1.0;
        for (int q = 0; q < 6; ++q) {
            for (int h = 0; h < 2; ++h) {
                const double period = 1.0 + 2.0 * rp_rng_uniform(&rng); /* s */
                sr->wob[q][h][0] = q < 3 ? cfg->wobble_t : cfg->wobble_a;
                sr->wob[q][h][1] = 2.0 * SIM_PI / period;
                sr->wob[q][h][2] = 2.0 * SIM_PI * rp_rng_uniform(&rng);
            }
        }
        for (uint32_t j = 0; j < cfg->n_frames; ++j) {
            double R[9], d[3];
            rp_sim_turn_pose(sr, rp_sim_set_time(sr, j), d, R);
            store_truth(sr, j, R, d);
        }
        return 0;
    }

    if (cfg->motion == RP_SIM_MOTION_SMOOTH) {
        /* Three sinusoids per degree of freedom (rp_sim.h), each a third of the axis's rate
         * bound: A w = bound / 3. */
        rp_rng_seed(&rng, sim_key(seed, run, DOM_SMOOTH, 0));
        for (int q = 0; q < 6; ++q) {
            for (int h = 0; h < 3; ++h) {
                const double period = 1.0 + (q < 3 ? 1.0 : 3.0) * rp_rng_uniform(&rng); /* s */
                const double w = 2.0 * SIM_PI / period;
                sr->smooth[q][h][0] = (q < 3 ? cfg->smooth_v_axis : cfg->smooth_w_axis) / (3.0 * w);
                sr->smooth[q][h][1] = w;
                sr->smooth[q][h][2] = 2.0 * SIM_PI * rp_rng_uniform(&rng);
            }
        }
        for (uint32_t j = 0; j < cfg->n_frames; ++j) {
            double R[9], d[3];
            /* ignored: 0 for a continuous motion */
            (void)rp_sim_pose(sr, rp_sim_set_time(sr, j), d, R);
            store_truth(sr, j, R, d);
        }
        return 0;
    }

    /* Trajectory: frame 0 is the identity; translation increments along the world axes,
     * rotation increments composed in the rig's frame, R_j = R_{j-1} Rz(dg) Ry(db) Rx(da). */
    rp_rng_seed(&rng, sim_key(seed, run, DOM_TRAJ, 0));
    double d[3] = {0.0, 0.0, 0.0};
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (uint32_t j = 0; j < cfg->n_frames; ++j) {
        if (j > 0) {
            double dt[3], da[3];
            for (int i = 0; i < 3; ++i) {
                dt[i] = signed_mag(&rng, cfg->t_min, cfg->t_max);
            }
            for (int i = 0; i < 3; ++i) {
                da[i] = signed_mag(&rng, cfg->a_min, cfg->a_max);
            }
            double Rinc[9];
            rot_from_angles(da[0], da[1], da[2], Rinc);
            mat_mul(R, Rinc, R);
            for (int i = 0; i < 3; ++i) {
                d[i] += dt[i];
            }
        }
        store_truth(sr, j, R, d);
    }
    return 0;
}

double rp_sim_turn_yaw(const rp_sim_run_t *sr, double t)
{
    const rp_sim_cfg_t *c = &sr->cfg;
    if ((c->motion != RP_SIM_MOTION_TURN && c->motion != RP_SIM_MOTION_PITCH) || !(t > 0.0)) {
        return 0.0;
    }
    const double tau = c->turn_ramp_s;
    double psi;
    if (tau > 0.0 && t < tau) {
        /* rate w (3x^2 - 2x^3), x = t / tau: its integral w tau (x^3 - x^4 / 2) */
        const double x = t / tau;
        psi = c->turn_rate * tau * (x * x * x - 0.5 * x * x * x * x);
    } else {
        psi = c->turn_rate * (t - 0.5 * (tau > 0.0 ? tau : 0.0));
    }
    return sr->turn_sign * psi;
}

/* The smooth motion's pose at t (rp_sim.h). */
static void smooth_pose(const rp_sim_run_t *sr, double t, double d[3], double R[9])
{
    double w[6];
    for (int q = 0; q < 6; ++q) {
        w[q] = 0.0;
        for (int h = 0; h < 3; ++h) {
            const double *p = sr->smooth[q][h];
            w[q] += p[0] * (sin(p[1] * t + p[2]) - sin(p[2]));
        }
    }
    rot_from_angles(w[3], w[4], w[5], R);
    d[0] = w[0];
    d[1] = w[1];
    d[2] = w[2];
}

int rp_sim_pose(const rp_sim_run_t *sr, double t, double d[3], double R[9])
{
    if (sr->cfg.motion == RP_SIM_MOTION_SMOOTH) {
        smooth_pose(sr, t, d, R);
        return 0;
    }
    rp_sim_turn_pose(sr, t, d, R);
    return sr->cfg.motion == RP_SIM_MOTION_PAPER ? -1 : 0;
}

void rp_sim_turn_pose(const rp_sim_run_t *sr, double t, double d[3], double R[9])
{
    if (sr->cfg.motion == RP_SIM_MOTION_SMOOTH) {
        smooth_pose(sr, t, d, R);
        return;
    }
    double w[6];
    for (int q = 0; q < 6; ++q) {
        w[q] = 0.0;
        if (sr->cfg.motion == RP_SIM_MOTION_TURN || sr->cfg.motion == RP_SIM_MOTION_PITCH) {
            for (int h = 0; h < 2; ++h) {
                const double *p = sr->wob[q][h];
                w[q] += p[0] * (sin(p[1] * t + p[2]) - sin(p[2]));
            }
        }
    }
    const double psi = rp_sim_turn_yaw(sr, t);
    const double c = cos(psi), s = sin(psi);
    const double Ry[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
    const double Rx[9] = {1, 0, 0, 0, c, -s, 0, s, c};
    double Rw[9];
    rot_from_angles(w[3], w[4], w[5], Rw);
    mat_mul(sr->cfg.motion == RP_SIM_MOTION_PITCH ? Rx : Ry, Rw, R);
    d[0] = w[0];
    d[1] = w[1];
    d[2] = w[2];
}

/* ---- clocks -------------------------------------------------------------------------------- */

/* Camera k's stamp of its frame i (us; i may be negative: the frame before the first set). */
static int64_t cam_stamp_us(const rp_sim_run_t *sr, int k, int64_t i)
{
    return sr->cam_phase_us[k] + (int64_t)llround((double)i * sr->cam_period_s[k] * 1e6);
}

double rp_sim_set_time(const rp_sim_run_t *sr, uint32_t j)
{
    const int f = sr->set_cam;
    return (double)sr->cam_phase_us[f] * 1e-6 + (double)j * sr->cam_period_s[f];
}

int64_t rp_sim_set_utime(const rp_sim_run_t *sr, uint32_t j)
{
    return cam_stamp_us(sr, sr->set_cam, (int64_t)j);
}

void rp_sim_cam_frame(const rp_sim_run_t *sr, uint32_t j, int k, rp_sim_cam_frame_t *cf)
{
    memset(cf, 0, sizeof *cf);
    if (!sr->clocked) {
        cf->present = 1;
        cf->index = j;
        cf->stamp_us = rp_sim_set_utime(sr, j);
        cf->t_true = rp_sim_set_time(sr, j);
        return;
    }
    const int64_t ut = rp_sim_set_utime(sr, j);
    const int64_t prev = cam_stamp_us(sr, sr->set_cam, (int64_t)j - 1);
    /* The camera's latest frame stamped at or before ut (floor, then fixed for the rounding). */
    int64_t i = (int64_t)floor((double)(ut - sr->cam_phase_us[k]) * 1e-6 / sr->cam_period_s[k]);
    while (cam_stamp_us(sr, k, i + 1) <= ut) {
        ++i;
    }
    while (i >= 0 && cam_stamp_us(sr, k, i) > ut) {
        --i;
    }
    if (i < 0 || cam_stamp_us(sr, k, i) <= prev) {
        return; /* not started yet, or no new frame since the previous set */
    }
    cf->present = 1;
    cf->index = i;
    cf->stamp_us = cam_stamp_us(sr, k, i);
    double e = 0.0;
    if (sr->cfg.jitter_s > 0.0) {
        rp_rng_t rng;
        rp_rng_seed(&rng, sim_key(sr->seed, sr->run, DOM_CLOCK, ((uint64_t)k << 56) ^ (uint64_t)i));
        e = sr->cfg.jitter_s * rp_rng_gauss(&rng);
    }
    cf->t_true = (double)sr->cam_phase_us[k] * 1e-6 + (double)i * sr->cam_period_s[k] +
                 sr->cfg.cam_offset_s[k] + e;
}

void rp_sim_run_free(rp_sim_run_t *sr)
{
    free(sr->points);
    free(sr->truth);
    free(sr->truth_R);
    sr->points = sr->truth = sr->truth_R = NULL;
}

/* ---- a frame: visible, noisy features ------------------------------------------------------ */

typedef struct {
    double dist2; /* squared distance to the camera, m^2 (ranks "nearest") */
    uint32_t id;
    double u, v;  /* noise-free pixel */
} cand_t;

/* Max-heap on (dist2, id) holding the nearest candidates seen so far. */
static int cand_farther(const cand_t *a, const cand_t *b)
{
    return a->dist2 > b->dist2 || (a->dist2 == b->dist2 && a->id > b->id);
}

static void heap_sift_down(cand_t *h, uint32_t n, uint32_t i)
{
    for (;;) {
        uint32_t l = 2u * i + 1u, m = i;
        if (l < n && cand_farther(&h[l], &h[m])) {
            m = l;
        }
        if (l + 1u < n && cand_farther(&h[l + 1u], &h[m])) {
            m = l + 1u;
        }
        if (m == i) {
            return;
        }
        cand_t t = h[i];
        h[i] = h[m];
        h[m] = t;
        i = m;
    }
}

static int cand_by_id(const void *a, const void *b)
{
    const uint32_t x = ((const cand_t *)a)->id, y = ((const cand_t *)b)->id;
    return (x > y) - (x < y);
}

uint32_t rp_sim_frame(const rp_sim_run_t *sr, uint32_t j, rp_frameset_t *fs)
{
    const rp_sim_cfg_t *cfg = &sr->cfg;
    const double *Rj = &sr->truth_R[9u * j];
    const double *dj = &sr->truth[6u * j];
    double R_cam[9], d_cam[3]; /* with clocks: the pose at the camera's own capture time */
    const double w_max = cfg->width - 0.5, h_max = cfg->height - 0.5; /* rp_cam_in_image */
    const uint64_t frame_key = sim_key(sr->seed, sr->run, DOM_NOISE, j);
    static const uint32_t cap = RP_MAX_FEATS_PER_CAM;
    cand_t heap[RP_MAX_FEATS_PER_CAM];
    uint32_t total = 0;

    rp_frameset_reset(fs, rp_sim_set_utime(sr, j));

    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        const rp_rig_cam_t *rc = &sr->rig.cam[k];
        if (sr->clocked) {
            rp_sim_cam_frame_t cf;
            rp_sim_cam_frame(sr, j, k, &cf);
            if (!cf.present) {
                fs->cam_flags[k] |= RP_FS_NO_IMAGE;
                continue;
            }
            fs->cam_dt_us[k] = (int32_t)(cf.stamp_us - fs->utime);
            /* ignored: 0, rp_sim_run_init refuses clocks with the paper's motion */
            (void)rp_sim_pose(sr, cf.t_true, d_cam, R_cam);
            Rj = R_cam;
            dj = d_cam;
        }
        const double fx = (double)rc->cam.fx, fy = (double)rc->cam.fy;
        const double cx = (double)rc->cam.cx, cy = (double)rc->cam.cy;
        const double u_lo = -1.5 - cx, u_hi = w_max + 1.0 - cx; /* pre-test bounds, pixels */
        const double v_lo = -1.5 - cy, v_hi = h_max + 1.0 - cy;
        /* P = R_k^T R_j^T (M - c) with c = d_j + R_j D_k (eq. 2): A = (R_j R_k)^T. */
        double Rk[9], RjRk[9], c[3];
        for (int i = 0; i < 9; ++i) {
            Rk[i] = (double)rc->R[i];
        }
        mat_mul(Rj, Rk, RjRk);
        for (int i = 0; i < 3; ++i) {
            c[i] = dj[i] + Rj[3 * i] * (double)rc->D[0] + Rj[3 * i + 1] * (double)rc->D[1] +
                   Rj[3 * i + 2] * (double)rc->D[2];
        }
        /* Rows of A are the columns of R_j R_k: the camera's axes in the world. */
        const double ax[3] = {RjRk[0], RjRk[3], RjRk[6]};
        const double ay[3] = {RjRk[1], RjRk[4], RjRk[7]};
        const double az[3] = {RjRk[2], RjRk[5], RjRk[8]};

        uint32_t n = 0;
        int overflow = 0;
        for (uint32_t i = 0; i < cfg->n_points; ++i) {
            const double *M = &sr->points[3u * i];
            const double q0 = M[0] - c[0], q1 = M[1] - c[1], q2 = M[2] - c[2];
            const double Z = az[0] * q0 + az[1] * q1 + az[2] * q2;
            const double X = ax[0] * q0 + ax[1] * q1 + ax[2] * q2;
            const double Y = ay[0] * q0 + ay[1] * q1 + ay[2] * q2;
            /* Cheap branch-free pre-test, one pixel wider than the image (no division): most
             * points fail it, and a well-predicted branch skips them. */
            const int maybe = (Z >= cfg->min_depth) & (fx * X >= u_lo * Z) &
                              (fx * X <= u_hi * Z) & (fy * Y >= v_lo * Z) & (fy * Y <= v_hi * Z);
            if (!maybe) {
                continue;
            }
            /* The rule itself, as rp_cam_in_image states it. */
            const double u = fx * X / Z + cx;
            const double v = fy * Y / Z + cy;
            if (!(u >= -0.5 && u < w_max && v >= -0.5 && v < h_max)) {
                continue;
            }
            const cand_t cd = {X * X + Y * Y + Z * Z, i, u, v};
            if (n < cap) {
                heap[n++] = cd; /* in id order, not yet a heap */
                continue;
            }
            if (!overflow) {
                overflow = 1; /* more visible than the limit: keep the nearest cap */
                for (uint32_t m = cap / 2u; m-- > 0;) {
                    heap_sift_down(heap, n, m);
                }
            }
            if (cand_farther(&heap[0], &cd)) {
                heap[0] = cd;
                heap_sift_down(heap, n, 0);
            }
        }
        if (overflow) {
            qsort(heap, n, sizeof heap[0], cand_by_id);
        }

        for (uint32_t m = 0; m < n; ++m) {
            rp_rng_t rng;
            rp_rng_seed(&rng, frame_key ^ mix64(((uint64_t)k << 32) | heap[m].id));
            double nu, nv;
            gauss_pair(&rng, &nu, &nv);
            nu *= cfg->noise_px;
            nv *= cfg->noise_px;
            fs->f[k][m].id = heap[m].id;
            fs->f[k][m].uv[0] = (rp_real)(heap[m].u + nu);
            fs->f[k][m].uv[1] = (rp_real)(heap[m].v + nv);
        }
        fs->n[k] = (uint16_t)n;
        total += n;
    }
    return total;
}
