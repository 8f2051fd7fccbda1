/*
 * test_turns.c - the simulation's turn (rp_sim.h, RP_SIM_MOTION_TURN): the truth is the
 * continuous function rp_sim_turn_pose sampled at the frame times, deterministic per (seed,
 * run); the yaw passes +90, 180 and -90 degrees (so the paper's beta passes +-90 degrees) in a
 * default turn run of RP_SIM_TURN_FRAMES frames; the rig stays well inside the shell; every
 * camera sees features in every frame; per-frame motion stays in the paper's ranges; the pitch
 * control turns as far with beta far from +-90 degrees.
 *
 * The layouts hold through the turn (the acceptance test for an angle state that passes
 * beta = +-90 degrees, docs/rotation.md): stereo4, stereo2, cam1 and gc's filter (its window
 * adjustment off; gc as shipped is printed, not asserted) run through 3 turns and 3 pitches (the pitch turns as far at the same rates without the singularity); per layout the
 * turn's largest rotation error must be within 2x the pitch's (+ 0.1 degree), with no lost
 * frame. RP_TURN_LAYOUTS=print prints the figures without asserting. The full measurement of
 * every layout: host_tools/sim/README.md ("Turns"), rigpose-sim --motion turn ... --max-rot DEG.
 */
#include "rp_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo_gc.h"
#include "rigpose/rp_vo_mono.h"
#include "rigpose/rp_vo_stereo.h"
#include "rp_sim.h"

#define PI 3.14159265358979323846
#define N_RUNS 6

static void turn_cfg(rp_sim_cfg_t *cfg, uint32_t frames)
{
    rp_sim_default_cfg(cfg);
    cfg->motion = RP_SIM_MOTION_TURN;
    cfg->n_frames = frames;
}

/* Heading of cam1's forward axis about the world's y axis (rad, -pi..pi). */
static double heading(const double R[9]) { return atan2(R[2], R[8]); }

static void truth_is_the_continuous_pose_sampled_at_frame_times(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg, cfg_short;
    turn_cfg(&cfg, RP_SIM_TURN_FRAMES);
    turn_cfg(&cfg_short, 50);
    rp_sim_run_t a, b, c, s;
    assert_int_equal(rp_sim_run_init(&a, &cfg, 1, 3), 0);
    assert_int_equal(rp_sim_run_init(&b, &cfg, 1, 3), 0);
    assert_int_equal(rp_sim_run_init(&c, &cfg, 1, 4), 0);
    assert_int_equal(rp_sim_run_init(&s, &cfg_short, 1, 3), 0);
    /* Frame 0 is the identity. */
    for (int i = 0; i < 3; ++i) {
        assert_near(a.truth[i], 0.0, 1e-15);
    }
    for (int i = 0; i < 9; ++i) {
        assert_near(a.truth_R[i], (i % 4 == 0) ? 1.0 : 0.0, 1e-15);
    }
    int differs = 0;
    for (uint32_t j = 0; j < cfg.n_frames; ++j) {
        double d[3], R[9];
        rp_sim_turn_pose(&a, j * cfg.frame_dt, d, R);
        for (int i = 0; i < 3; ++i) {
            assert_true(d[i] == a.truth[6u * j + i]);
        }
        for (int i = 0; i < 9; ++i) {
            assert_true(R[i] == a.truth_R[9u * j + i]);
        }
        /* Deterministic per (seed, run), another run differs, the run's length does not
         * change its frames. */
        assert_memory_equal(&a.truth[6u * j], &b.truth[6u * j], 6 * sizeof(double));
        assert_memory_equal(&a.truth_R[9u * j], &b.truth_R[9u * j], 9 * sizeof(double));
        differs += memcmp(&a.truth[6u * j], &c.truth[6u * j], 6 * sizeof(double)) != 0;
        if (j < cfg_short.n_frames) {
            assert_memory_equal(&a.truth_R[9u * j], &s.truth_R[9u * j], 9 * sizeof(double));
        }
        /* The truth angles are R_j's angles. */
        rp_real abg[3], Rr[9];
        for (int i = 0; i < 3; ++i) {
            abg[i] = (rp_real)a.truth[6u * j + 3 + i];
        }
        rp_rot_from_angles(abg, Rr);
        for (int i = 0; i < 9; ++i) {
            assert_near(Rr[i], a.truth_R[9u * j + i], RP_TOL(1e-9, 1e-5));
        }
    }
    assert_true(differs > (int)cfg.n_frames - 2);
    /* Continuous between frames: half a frame away the pose is between its neighbours'. */
    double d0[3], d1[3], dh[3], R0[9], R1[9], Rh[9];
    rp_sim_turn_pose(&a, 40 * cfg.frame_dt, d0, R0);
    rp_sim_turn_pose(&a, 40.5 * cfg.frame_dt, dh, Rh);
    rp_sim_turn_pose(&a, 41 * cfg.frame_dt, d1, R1);
    for (int i = 0; i < 3; ++i) {
        assert_near(dh[i], 0.5 * (d0[i] + d1[i]), 2e-4);
    }
    for (int i = 0; i < 9; ++i) {
        assert_near(Rh[i], 0.5 * (R0[i] + R1[i]), 2e-3);
    }
    rp_sim_run_free(&a);
    rp_sim_run_free(&b);
    rp_sim_run_free(&c);
    rp_sim_run_free(&s);
}

static void yaw_passes_plus_and_minus_90_and_180_degrees(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    turn_cfg(&cfg, RP_SIM_TURN_FRAMES);
    int right = 0;
    for (uint32_t r = 0; r < N_RUNS; ++r) {
        rp_sim_run_t sr;
        assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, r), 0);
        double prev = 0.0, yaw = 0.0, beta_lo = 0.0, beta_hi = 0.0;
        uint32_t at90 = 0, at180 = 0, at270 = 0;
        for (uint32_t j = 1; j < cfg.n_frames; ++j) {
            const double h = heading(&sr.truth_R[9u * j]);
            double dh = h - prev;
            dh -= 2.0 * PI * floor((dh + PI) / (2.0 * PI));
            yaw += dh; /* unwrapped */
            prev = h;
            const double ay = fabs(yaw);
            at90 = (!at90 && ay >= 0.5 * PI) ? j : at90;
            at180 = (!at180 && ay >= PI) ? j : at180;
            at270 = (!at270 && ay >= 1.5 * PI) ? j : at270;
            beta_lo = fmin(beta_lo, sr.truth[6u * j + 4]);
            beta_hi = fmax(beta_hi, sr.truth[6u * j + 4]);
            /* The yaw alone is the wobble-free part of the heading: within the wobble. */
            assert_near(yaw, rp_sim_turn_yaw(&sr, j * cfg.frame_dt), 0.25);
        }
        right += yaw > 0.0;
        /* 90 degrees near frame 50, 180 near 95, 270 (= -90) near 140 (rp_sim.h). */
        assert_true(at90 >= 40 && at90 <= 60);
        assert_true(at180 >= 85 && at180 <= 105);
        assert_true(at270 >= 130 && at270 <= 150);
        assert_true(fabs(yaw) >= 2.0 * PI - 0.3); /* about a full turn by frame 199 */
        /* The paper's beta comes within 5 degrees of both singular values. */
        assert_true(beta_hi > 85.0 * PI / 180.0);
        assert_true(beta_lo < -85.0 * PI / 180.0);
        rp_sim_run_free(&sr);
    }
    assert_true(right > 0 && right < N_RUNS); /* both directions occur */
}

/* The control: the same turn about x keeps the paper's beta far from +-90 degrees, and its
 * angle is the turn's (the rotation about x of cam1's forward axis). */
static void pitch_turns_as_far_without_the_singularity(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    turn_cfg(&cfg, RP_SIM_TURN_FRAMES);
    cfg.motion = RP_SIM_MOTION_PITCH;
    for (uint32_t r = 0; r < N_RUNS; ++r) {
        rp_sim_run_t sr;
        assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, r), 0);
        double beta_max = 0.0;
        for (uint32_t j = 1; j < cfg.n_frames; ++j) {
            beta_max = fmax(beta_max, fabs(sr.truth[6u * j + 4]));
        }
        assert_true(beta_max < 0.45); /* |sin b| <= |sin g_w| + |sin b_w| <= 2 sin(0.2) */
        assert_true(fabs(rp_sim_turn_yaw(&sr, (cfg.n_frames - 1) * cfg.frame_dt)) > 2.0 * PI - 0.3);
        rp_sim_run_free(&sr);
    }
}

static void rig_stays_inside_the_shell_and_moves_like_the_paper(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    turn_cfg(&cfg, RP_SIM_TURN_FRAMES);
    double far = 0.0, step_t = 0.0, step_a = 0.0;
    for (uint32_t r = 0; r < N_RUNS; ++r) {
        rp_sim_run_t sr;
        assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, r), 0);
        for (uint32_t j = 0; j < cfg.n_frames; ++j) {
            const double *R = &sr.truth_R[9u * j], *d = &sr.truth[6u * j];
            for (int k = 0; k < RP_SIM_NCAMS; ++k) {
                const rp_rig_cam_t *c = &sr.rig.cam[k];
                double n2 = 0.0;
                for (int i = 0; i < 3; ++i) {
                    const double ci = d[i] + R[3 * i] * (double)c->D[0] +
                                      R[3 * i + 1] * (double)c->D[1] +
                                      R[3 * i + 2] * (double)c->D[2];
                    n2 += ci * ci;
                }
                far = fmax(far, sqrt(n2));
            }
            if (j > 0) {
                const double *A = &sr.truth_R[9u * (j - 1)], *d0 = &sr.truth[6u * (j - 1)];
                double tr = 0.0;
                for (int i = 0; i < 9; ++i) {
                    tr += A[i] * R[i];
                }
                step_a = fmax(step_a, acos(fmin(1.0, 0.5 * (tr - 1.0))));
                for (int i = 0; i < 3; ++i) {
                    step_t = fmax(step_t, fabs(d[i] - d0[i]));
                }
            }
        }
        rp_sim_run_free(&sr);
    }
    print_message("turn: cameras at most %.3f m from the start (shell from %.3f m); largest "
                  "per-frame step %.4f m per axis, %.4f rad\n", far, cfg.r_in, step_t, step_a);
    assert_true(far < 0.35);           /* 0.3 m or more from the nearest point of the shell */
    assert_true(step_t <= cfg.t_max);  /* the paper's per-axis translation at most */
    assert_true(step_a < 0.07);        /* turn 0.035 plus the wobble's ~0.02 per angle */
}

static void every_camera_sees_features_in_every_frame(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    turn_cfg(&cfg, RP_SIM_TURN_FRAMES);
    rp_frameset_t *fs = malloc(sizeof *fs);
    assert_non_null(fs);
    unsigned fewest = 1u << 30;
    for (uint32_t r = 0; r < 2; ++r) {
        rp_sim_run_t sr;
        assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, r), 0);
        for (uint32_t j = 0; j < cfg.n_frames; j += 3) {
            (void)rp_sim_frame(&sr, j, fs);
            for (int k = 0; k < RP_SIM_NCAMS; ++k) {
                fewest = fs->n[k] < fewest ? fs->n[k] : fewest;
            }
        }
        rp_sim_run_free(&sr);
    }
    print_message("turn: fewest features in a camera %u\n", fewest);
    assert_true(fewest >= 100);
    free(fs);
}

/* ---- opt-in: the layouts through the turn ---------------------------------------------------- */

typedef struct {
    const char *name;
    int asserted; /* 0: printed only (a known failure, host_tools/sim/README.md "Turns") */
    size_t size;
    rp_status_t (*init)(void *vo, const rp_rig_t *rig);
    rp_status_t (*step)(void *vo, const rp_frameset_t *fs, rp_estimate_t *est);
} layout_t;

static rp_status_t stereo4_init(void *vo, const rp_rig_t *rig)
{
    rp_vo_stereo_cfg_t c = rp_vo_stereo_default_cfg();
    c.n_pairs = 2;
    c.pair_a[0] = RP_SIM_CAM1;
    c.pair_b[0] = RP_SIM_CAM1B;
    c.pair_a[1] = RP_SIM_CAM3;
    c.pair_b[1] = RP_SIM_CAM3B;
    c.ekf.q_trans = c.ekf.q_rot = (rp_real)1.0; /* as rigpose-sim (RP_SIM_STEREO_Q) */
    c.ekf.sigma_px = (rp_real)0.5;
    return rp_vo_stereo_init(vo, rig, &c);
}

static rp_status_t stereo2_init(void *vo, const rp_rig_t *rig)
{
    rp_vo_stereo_cfg_t c = rp_vo_stereo_default_cfg();
    c.n_pairs = 1;
    c.pair_a[0] = RP_SIM_CAM1;
    c.pair_b[0] = RP_SIM_CAM1B;
    c.ekf.q_trans = c.ekf.q_rot = (rp_real)1.0; /* as rigpose-sim (RP_SIM_STEREO_Q) */
    c.ekf.sigma_px = (rp_real)0.5;
    return rp_vo_stereo_init(vo, rig, &c);
}

static rp_status_t stereo_step(void *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_stereo_step(vo, fs, est);
}

static rp_status_t gc_init(void *vo, const rp_rig_t *rig)
{
    rp_sim_cfg_t sim;
    rp_sim_default_cfg(&sim);
    const rp_vo_gc_cfg_t c = rp_sim_gc_cfg(&sim);
    return rp_vo_gc_init(vo, rig, &c);
}

/* gc's filter alone: its metric scale step (the window adjustment, rp_vo_gc.h step 6) off. */
static rp_status_t gc_filter_init(void *vo, const rp_rig_t *rig)
{
    rp_sim_cfg_t sim;
    rp_sim_default_cfg(&sim);
    rp_vo_gc_cfg_t c = rp_sim_gc_cfg(&sim);
    c.mscale_sigma = 0;
    return rp_vo_gc_init(vo, rig, &c);
}

static rp_status_t gc_step(void *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_gc_step(vo, fs, est);
}

static rp_status_t cam1_init(void *vo, const rp_rig_t *rig)
{
    rp_vo_mono_cfg_t c = rp_vo_mono_default_cfg();
    c.cam = RP_SIM_CAM1;
    c.init_depth_m = (rp_real)((0.667 + 1.0) / 2.0); /* as rigpose-sim */
    c.init_depth_sigma_m = (rp_real)0.15;
    c.ekf.sigma_px = (rp_real)0.5;
    return rp_vo_mono_init(vo, rig, &c);
}

static rp_status_t mono_step(void *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_mono_step(vo, fs, est, NULL);
}

/* The angle of R_true^T R(est) (rad). */
static double rot_error(const double R_true[9], const rp_real p[6])
{
    rp_real R[9];
    rp_rot_from_angles(&p[3], R);
    double tr = 0.0;
    for (int i = 0; i < 9; ++i) {
        tr += R_true[i] * (double)R[i];
    }
    const double c = 0.5 * (tr - 1.0);
    return isfinite(c) ? acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c) : PI;
}

static void layouts_hold_through_the_turn(void **state)
{
    (void)state;
    const char *opt = getenv("RP_TURN_LAYOUTS");
    const int strict = !(opt && !strcmp(opt, "print"));
    const layout_t layouts[] = {
        {"stereo4", 1, sizeof(rp_vo_stereo_t), stereo4_init, stereo_step},
        {"stereo2", 1, sizeof(rp_vo_stereo_t), stereo2_init, stereo_step},
        {"cam1", 1, sizeof(rp_vo_mono_t), cam1_init, mono_step},
        {"gc-filter", 1, sizeof(rp_vo_gc_t), gc_filter_init, gc_step},
        /* gc as shipped: its window adjustment's pose corrections are much larger in the turn
         * than in the pitch, on main as here (not the angle chart; host_tools/sim/README.md,
         * "Turns"): printed, not asserted, until that is understood */
        {"gc", 0, sizeof(rp_vo_gc_t), gc_init, gc_step},
    };
    rp_frameset_t *fs = malloc(sizeof *fs);
    assert_non_null(fs);
    int holds = 1;
    for (size_t l = 0; l < sizeof layouts / sizeof layouts[0]; ++l) {
        void *vo = calloc(1, layouts[l].size);
        assert_non_null(vo);
        double worst_deg[3] = {0, 0, 0};
        uint32_t lost_all = 0;
        for (int motion = RP_SIM_MOTION_TURN; motion <= RP_SIM_MOTION_PITCH; ++motion) {
            rp_sim_cfg_t cfg;
            turn_cfg(&cfg, RP_SIM_TURN_FRAMES);
            cfg.motion = (rp_sim_motion_t)motion;
            double worst = 0.0, sum = 0.0;
            uint32_t lost = 0, worst_run = 0, worst_frame = 0;
            for (uint32_t r = 0; r < 3; ++r) {
                rp_sim_run_t sr;
                assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, r), 0);
                assert_int_equal(layouts[l].init(vo, &sr.rig), RP_OK);
                for (uint32_t j = 0; j < cfg.n_frames; ++j) {
                    rp_estimate_t est;
                    (void)rp_sim_frame(&sr, j, fs);
                    const rp_status_t st = layouts[l].step(vo, fs, &est);
                    if (j == 0) {
                        continue;
                    }
                    lost += st != RP_OK;
                    /* published angles wrapped: alpha, gamma in [-pi, pi], beta in
                     * [-pi/2, pi/2] */
                    assert_true(fabs((double)est.p[3]) <= PI + 1e-6 &&
                                fabs((double)est.p[4]) <= PI / 2.0 + 1e-6 &&
                                fabs((double)est.p[5]) <= PI + 1e-6);
                    const double e = rot_error(&sr.truth_R[9u * j], est.p);
                    sum += e;
                    if (e > worst) {
                        worst = e;
                        worst_run = r;
                        worst_frame = j;
                    }
                }
                rp_sim_run_free(&sr);
            }
            worst_deg[motion] = worst * 180.0 / PI;
            lost_all += lost;
            print_message("%-9s %-5s: rotation error mean %.3f deg, largest %.3f deg (run %u frame "
                          "%u), %u lost frames (3 runs x %u frames, seed 1)\n",
                          layouts[l].name, motion == RP_SIM_MOTION_TURN ? "turn" : "pitch",
                          sum / (3.0 * (cfg.n_frames - 1)) * 180.0 / PI, worst_deg[motion],
                          worst_run, worst_frame, lost, cfg.n_frames);
        }
        const int ok = worst_deg[RP_SIM_MOTION_TURN] <=
                           2.0 * worst_deg[RP_SIM_MOTION_PITCH] + 0.1 && lost_all == 0;
        print_message("%-9s %s through the turn (largest %.3f deg, bound 2 x pitch + 0.1 = "
                      "%.3f)%s\n", layouts[l].name, ok ? "holds" : "does NOT hold",
                      worst_deg[RP_SIM_MOTION_TURN], 2.0 * worst_deg[RP_SIM_MOTION_PITCH] + 0.1,
                      layouts[l].asserted ? "" : " (not asserted)");
        holds = holds && (ok || !layouts[l].asserted);
        free(vo);
    }
    free(fs);
    if (strict) {
        assert_true(holds);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(truth_is_the_continuous_pose_sampled_at_frame_times),
        cmocka_unit_test(yaw_passes_plus_and_minus_90_and_180_degrees),
        cmocka_unit_test(pitch_turns_as_far_without_the_singularity),
        cmocka_unit_test(rig_stays_inside_the_shell_and_moves_like_the_paper),
        cmocka_unit_test(every_camera_sees_features_in_every_frame),
        cmocka_unit_test(layouts_hold_through_the_turn),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
