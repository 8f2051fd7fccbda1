/*
 * test_rc.c - rigidity constraints (paper eqs. 3-7): the least squares recover known scales
 * exactly, the per-angle median rejects an outlying camera, degenerate geometry is flagged
 * instead of divided through, bad input is refused.
 */
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_frame.h"
#include "rigpose/rp_rc.h"
#include "rigpose/rp_rot.h"
#include "rp_sim.h"

static const uint8_t cams4[4] = {RP_SIM_CAM1, RP_SIM_CAM2, RP_SIM_CAM3, RP_SIM_CAM4};

static void make_rig(rp_rig_t *rig)
{
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    rp_sim_make_rig(&cfg, rig);
}

/* Own poses of the four cameras for rig pose p, each translation divided by its scale. */
static void own_poses(const rp_rig_t *rig, const rp_real p[6], const rp_real scale[4],
                      rp_real own[4][6])
{
    rp_real Rj[9];
    rp_rot_from_angles(&p[3], Rj);
    for (int i = 0; i < 4; ++i) {
        const rp_real *Rk = rig->cam[cams4[i]].R, *Dk = rig->cam[cams4[i]].D;
        rp_real r[9], t[3];
        rp_rot_mul_at_b(Rk, Rj, r);
        rp_rot_mul(r, Rk, r);
        rp_rot_apply(Rj, Dk, t);
        for (int c = 0; c < 3; ++c) t[c] += p[c] - Dk[c];
        rp_rot_apply_t(Rk, t, own[i]);
        for (int c = 0; c < 3; ++c) own[i][c] /= scale[i];
        assert_ok(rp_rot_to_angles(r, &own[i][3]));
    }
}

static void test_least_squares_recover_known_scales_exactly(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const rp_rc_params_t prm = rp_rc_default_params();
    const rp_real p[6] = {RP_C(0.12), RP_C(-0.07), RP_C(0.2), RP_C(0.15), RP_C(-0.25), RP_C(0.3)};
    const rp_real scale[4] = {RP_C(1.3), RP_C(0.8), RP_C(1.1), RP_C(2.0)};
    rp_real own[4][6], out[6], s[4];
    own_poses(&rig, p, scale, own);
    uint32_t flags = 0;
    assert_ok(rp_rc_fuse(&rig, cams4, 4, (const rp_real(*)[6])own, &prm, RP_C(1.0), out, s,
                         &flags));
    assert_int_equal(flags & RP_EST_SCALE_WEAK, 0);
    for (int i = 0; i < 4; ++i) assert_near(s[i], scale[i], RP_TOL(1e-9, 1e-3));
    for (int i = 0; i < 6; ++i) assert_near(out[i], p[i], RP_TOL(1e-9, 1e-4));
    /* two cameras (6x2 system) work the same */
    assert_ok(rp_rc_fuse(&rig, cams4, 2, (const rp_real(*)[6])own, &prm, RP_C(1.0), out, s,
                         NULL));
    assert_near(s[0], scale[0], RP_TOL(1e-9, 1e-3));
    assert_near(s[1], scale[1], RP_TOL(1e-9, 1e-3));
}

static void test_median_of_values_and_of_camera_angles(void **state)
{
    (void)state;
    rp_real m;
    const rp_real odd[5] = {5, 1, 4, 2, 3};
    assert_ok(rp_rc_median(odd, 5, &m));
    assert_near(m, 3, 0);
    const rp_real even[4] = {4, -1, 10, 2};
    assert_ok(rp_rc_median(even, 4, &m));
    assert_near(m, 3, 0);
    assert_status(rp_rc_median(odd, 0, &m), RP_E_ARG);
    const rp_real bad[2] = {1, (rp_real)NAN};
    assert_status(rp_rc_median(bad, 2, &m), RP_E_NAN);

    /* One camera's rotation far off: the per-angle median ignores it. */
    rp_rig_t rig;
    make_rig(&rig);
    const rp_rc_params_t prm = rp_rc_default_params();
    const rp_real p[6] = {RP_C(0.1), RP_C(0.05), RP_C(-0.1), RP_C(0.1), RP_C(0.2), RP_C(-0.3)};
    const rp_real one[4] = {1, 1, 1, 1};
    rp_real own[4][6], out[6];
    own_poses(&rig, p, one, own);
    own[3][3] += RP_C(0.5);
    own[3][5] -= RP_C(0.4);
    (void)rp_rc_fuse(&rig, cams4, 4, (const rp_real(*)[6])own, &prm, RP_C(1.0), out, NULL, NULL);
    for (int i = 3; i < 6; ++i) assert_near(out[i], p[i], RP_TOL(1e-9, 1e-4));

    /* Angles near +-pi are unwrapped before the median. */
    const rp_real q[6] = {RP_C(0.1), 0, RP_C(0.1), 0, 0, RP_C(3.14)};
    own_poses(&rig, q, one, own);
    assert_ok(rp_rc_fuse(&rig, cams4, 4, (const rp_real(*)[6])own, &prm, RP_C(1.0), out, NULL,
                         NULL));
    assert_near(rp_angle_wrap(out[5] - q[5]), 0, RP_TOL(1e-9, 1e-4));
}

static void test_pure_rotation_is_flagged_and_keeps_the_fallback_scale(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const rp_rc_params_t prm = rp_rc_default_params();
    const rp_real p[6] = {0, 0, 0, RP_C(0.1), RP_C(0.2), RP_C(-0.1)};
    const rp_real one[4] = {1, 1, 1, 1};
    rp_real own[4][6], out[6], s[4];
    own_poses(&rig, p, one, own);
    uint32_t flags = 0;
    assert_status(rp_rc_fuse(&rig, cams4, 4, (const rp_real(*)[6])own, &prm, RP_C(0.9), out, s,
                             &flags),
                  RP_E_DEGENERATE);
    assert_true(flags & RP_EST_SCALE_WEAK);
    assert_near(s[0], 0.9, RP_TOL(1e-15, 1e-6));
    for (int i = 0; i < 6; ++i) assert_true(isfinite((double)out[i]));
    for (int i = 0; i < 3; ++i) assert_near(out[i], 0, RP_TOL(1e-12, 1e-6));
    for (int i = 3; i < 6; ++i) assert_near(out[i], p[i], RP_TOL(1e-9, 1e-4));
}

static void test_rank_deficient_and_absurd_systems_are_flagged(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const rp_rc_params_t prm = rp_rc_default_params();
    const rp_real p[6] = {RP_C(0.1), RP_C(0.05), RP_C(0.1), RP_C(0.1), RP_C(0.2), RP_C(-0.1)};
    const rp_real one[4] = {1, 1, 1, 1};
    rp_real own[4][6], out[6], s[4];

    /* camera 3 reports no translation at all: its column of A is zero (rank deficient) */
    own_poses(&rig, p, one, own);
    own[2][0] = own[2][1] = own[2][2] = 0;
    uint32_t flags = 0;
    assert_status(rp_rc_fuse(&rig, cams4, 4, (const rp_real(*)[6])own, &prm, RP_C(1.0), out, s,
                             &flags),
                  RP_E_DEGENERATE);
    assert_true(flags & RP_EST_SCALE_WEAK);
    for (int i = 0; i < 3; ++i) assert_near(out[i], own[0][i], RP_TOL(1e-12, 1e-6));

    /* cam1's translation reversed: S_j comes out negative, which is refused */
    own_poses(&rig, p, one, own);
    for (int c = 0; c < 3; ++c) own[0][c] = -own[0][c];
    flags = 0;
    assert_status(rp_rc_fuse(&rig, cams4, 4, (const rp_real(*)[6])own, &prm, RP_C(1.0), out, s,
                             &flags),
                  RP_E_DEGENERATE);
    assert_true(flags & RP_EST_SCALE_WEAK);
    assert_near(s[0], 1.0, 0);

    /* inconsistent cameras (noise-like residual): the scale is too uncertain to use */
    own_poses(&rig, p, one, own);
    own[1][0] += RP_C(0.05);
    own[3][1] -= RP_C(0.05);
    own[2][2] += RP_C(0.05);
    flags = 0;
    assert_status(rp_rc_fuse(&rig, cams4, 4, (const rp_real(*)[6])own, &prm, RP_C(1.0), out, s,
                             &flags),
                  RP_E_DEGENERATE);
    assert_true(flags & RP_EST_SCALE_WEAK);
}

static void test_bad_input_is_refused(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const rp_rc_params_t prm = rp_rc_default_params();
    rp_real own[4][6] = {{0}}, out[6];
    const rp_real(*po)[6] = (const rp_real(*)[6])own;
    assert_status(rp_rc_fuse(&rig, cams4, 1, po, &prm, 1, out, NULL, NULL), RP_E_ARG);
    assert_status(rp_rc_fuse(&rig, cams4, 5, po, &prm, 1, out, NULL, NULL), RP_E_ARG);
    assert_status(rp_rc_fuse(&rig, cams4, 4, po, &prm, 0, out, NULL, NULL), RP_E_ARG);
    assert_status(rp_rc_fuse(NULL, cams4, 4, po, &prm, 1, out, NULL, NULL), RP_E_ARG);
    const uint8_t not_ref[4] = {RP_SIM_CAM2, RP_SIM_CAM1, RP_SIM_CAM3, RP_SIM_CAM4};
    assert_status(rp_rc_fuse(&rig, not_ref, 4, po, &prm, 1, out, NULL, NULL), RP_E_ARG);
    const uint8_t no_cam[4] = {RP_SIM_CAM1, 9, RP_SIM_CAM3, RP_SIM_CAM4};
    assert_status(rp_rc_fuse(&rig, no_cam, 4, po, &prm, 1, out, NULL, NULL), RP_E_ARG);
    rp_rc_params_t bad = prm;
    bad.max_scale = bad.min_scale;
    assert_status(rp_rc_fuse(&rig, cams4, 4, po, &bad, 1, out, NULL, NULL), RP_E_ARG);
    own[2][4] = (rp_real)NAN;
    assert_status(rp_rc_fuse(&rig, cams4, 4, po, &prm, 1, out, NULL, NULL), RP_E_NAN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_least_squares_recover_known_scales_exactly),
        cmocka_unit_test(test_median_of_values_and_of_camera_angles),
        cmocka_unit_test(test_pure_rotation_is_flagged_and_keeps_the_fallback_scale),
        cmocka_unit_test(test_rank_deficient_and_absurd_systems_are_flagged),
        cmocka_unit_test(test_bad_input_is_refused),
    };
    return cmocka_run_group_tests_name("rc", tests, NULL, NULL);
}
