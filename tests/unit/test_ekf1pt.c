/*
 * test_ekf1pt.c - 1-point RANSAC around the pose EKF's update: gross outliers left out,
 * high-innovation inliers rescued, a group that fits one camera's wrong pose left out, the
 * same input giving the same output, bad input refused; the MSAC cost of a pose.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_ekf.h"
#include "rigpose/rp_ekf1pt.h"
#include "rp_sim.h"

#define N RP_EKF_N
#define CAP (RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM)

typedef struct {
    rp_sim_run_t sr;
    rp_frameset_t fs;
    rp_obs_t obs[CAP];
    uint8_t outlier[CAP];
    uint8_t used[CAP];
    rp_ekf1pt_t op;
    uint32_t n;
} fixture_t;

static uint64_t rng = 1;
static double u01(void)
{
    rng ^= rng >> 12;
    rng ^= rng << 25;
    rng ^= rng >> 27;
    return (double)((rng * 0x2545F4914F6CDD1Dull) >> 11) / 9007199254740992.0;
}

/* Frame 10 of run 0 (0.5 px noise), every camera, true structure; a share frac of the
 * observations replaced by uniform pixels over the 640 x 480 image. */
static fixture_t *fixture(double frac)
{
    fixture_t *fx = calloc(1, sizeof(*fx));
    assert_non_null(fx);
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.n_frames = 12;
    assert_int_equal(rp_sim_run_init(&fx->sr, &cfg, 7, 0), 0);
    rp_sim_frame(&fx->sr, 10, &fx->fs);
    rng = 0x9E3779B97F4A7C15ull;
    for (uint8_t k = 0; k < fx->sr.rig.n_cams; ++k) {
        for (uint16_t i = 0; i < fx->fs.n[k] && fx->n < CAP; ++i) {
            const rp_feat_t *f = &fx->fs.f[k][i];
            rp_obs_t *o = &fx->obs[fx->n];
            o->uv[0] = f->uv[0];
            o->uv[1] = f->uv[1];
            for (int a = 0; a < 3; ++a) o->M[a] = (rp_real)fx->sr.points[3 * f->id + (uint32_t)a];
            o->w = RP_C(1.0);
            o->cam = k;
            if (u01() < frac) {
                o->uv[0] = (rp_real)(640.0 * u01());
                o->uv[1] = (rp_real)(480.0 * u01());
                fx->outlier[fx->n] = 1;
            }
            fx->n++;
        }
    }
    assert_ok(rp_ekf1pt_seed(&fx->op, 1));
    return fx;
}

/* The filter at the truth of frame 10 moved by off (m, rad), pose sigma `ps`. */
static void make_ekf(const fixture_t *fx, const double off[6], rp_real ps, rp_ekf_t *ekf)
{
    rp_ekf_params_t prm = rp_ekf_default_params();
    rp_real x0[N] = {0}, P0[N];
    for (int i = 0; i < 6; ++i) {
        x0[i] = (rp_real)(fx->sr.truth[6u * 10 + (unsigned)i] + off[i]);
        P0[i] = ps * ps;
        P0[6 + i] = RP_C(1.0);
    }
    assert_ok(rp_ekf_init(ekf, &prm, x0, P0));
}

/* Two copies of that filter, for updates compared side by side. */
static void make_ekf_pair(const fixture_t *fx, const double off[6], rp_real ps, rp_ekf_t *a,
                          rp_ekf_t *b)
{
    make_ekf(fx, off, ps, a);
    *b = *a;
}

/* A prior off by 20 mm / 20 mrad in every component. */
static const double off20[6] = {0.02, -0.02, 0.02, 0.02, -0.02, 0.02};

static double pose_err(const fixture_t *fx, const rp_ekf_t *ekf)
{
    double e = 0.0;
    for (int i = 0; i < 6; ++i) e = fmax(e, fabs((double)ekf->x[i] - fx->sr.truth[60u + (unsigned)i]));
    return e;
}

/* 40 % gross outliers and a prior off by 20 mm / 20 mrad (sigma 30 mm): 1-point RANSAC uses
 * (almost) only inliers, all of them, and lands on the truth; the plain update's figure is
 * printed beside it. */
static void test_gross_outliers_are_left_out(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.4);
    rp_ekf_t plain, ekf;
    make_ekf_pair(fx, off20, RP_C(0.03), &plain, &ekf);
    rp_ekf_info_t pi;
    (void)rp_ekf_update(&plain, &fx->sr.rig, fx->obs, fx->n, NULL, &pi);
    rp_ekf1pt_info_t info;
    assert_ok(rp_ekf1pt_update(&fx->op, &ekf, &fx->sr.rig, fx->obs, fx->n, NULL, fx->used, &info));
    uint32_t in_used = 0, out_used = 0, inliers = 0;
    for (uint32_t i = 0; i < fx->n; ++i) {
        inliers += !fx->outlier[i];
        in_used += fx->used[i] && !fx->outlier[i];
        out_used += fx->used[i] && fx->outlier[i];
    }
    print_message("1-point RANSAC: %u hypotheses, %u low + %u rescued, inliers used %u of %u, "
                  "outliers used %u; pose error %.2e (plain update %.2e)\n",
                  info.n_hyp, info.n_low, info.n_rescued, in_used, inliers, out_used,
                  pose_err(fx, &ekf), pose_err(fx, &plain));
    assert_true(pose_err(fx, &ekf) < RP_TOL(2e-4, 1e-3));
    assert_true(in_used >= 95 * inliers / 100);
    assert_true(out_used <= fx->n / 100); /* a uniform pixel can land within the gate */
    assert_true(info.n_hyp >= 2 && info.n_hyp <= 200);
    assert_int_equal(info.ekf.n_used, in_used + out_used);
    rp_sim_run_free(&fx->sr);
    free(fx);
}

/* A prior off by 25 mm along x with sigma 30 mm, hypotheses of one observation (the paper's,
 * hyp_cams 1): the hypotheses' support misses the inliers that a single observation's partial
 * update leaves farthest off (the low-innovation set is a part), and the rescue against the
 * first posterior brings them back. */
static void test_high_innovation_inliers_are_rescued(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.3);
    static const double off[6] = {0.025, 0.0, 0.0, 0.0, 0.02, 0.0};
    rp_ekf_t ekf;
    make_ekf(fx, off, RP_C(0.03), &ekf);
    rp_ekf1pt_params_t prm = rp_ekf1pt_default_params();
    prm.hyp_cams = 1;
    rp_ekf1pt_info_t info;
    assert_ok(rp_ekf1pt_update(&fx->op, &ekf, &fx->sr.rig, fx->obs, fx->n, &prm, fx->used, &info));
    uint32_t inliers = 0, in_used = 0;
    for (uint32_t i = 0; i < fx->n; ++i) {
        inliers += !fx->outlier[i];
        in_used += fx->used[i] && !fx->outlier[i];
    }
    print_message("low %u, rescued %u, inliers used %u of %u, pose error %.2e\n", info.n_low,
                  info.n_rescued, in_used, inliers, pose_err(fx, &ekf));
    assert_true(info.n_rescued > 0);
    assert_true(info.n_low < inliers);
    assert_true(in_used >= 95 * inliers / 100);
    assert_true(pose_err(fx, &ekf) < RP_TOL(2e-4, 1e-3));
    rp_sim_run_free(&fx->sr);
    free(fx);
}

/* gc's start (rendered moving object, docs/results.md): landmarks still at an assumed depth
 * (each point moved along its ray by up to +-15 %, weight 0.05: a pixel sigma of 2.2 px) under
 * a prior off by 20 mm / 20 mrad (sigma 30 mm), and 40 % of camera 0's features on an object
 * that moves with the rig (their pixels where the prior puts them). A hypothesis of one
 * observation leaves four pose directions at the prior, one camera's features and the object
 * then fit one pose together, and that consensus can win; one observation of each of three
 * cameras fixes the pose, and the static scene of all cameras wins. 8 seeds: with the default
 * hypotheses no update takes the object and every pose is within 0.1 mm / mrad; with one
 * observation (hyp_cams 1) at least one takes it and is centimetres off. */
static void test_object_static_in_one_camera_loses_to_the_scene(void **state)
{
    (void)state;
    int taken[2] = {0, 0};
    double worst[2] = {0.0, 0.0};
    for (int v = 0; v < 2; ++v) {
        for (int trial = 0; trial < 8; ++trial) {
            fixture_t *fx = fixture(0.0);
            rp_ekf_t ekf;
            make_ekf(fx, off20, RP_C(0.03), &ekf);
            rp_pose_lin_t pt, p0;
            rp_real tp[6];
            for (int i = 0; i < 6; ++i) tp[i] = (rp_real)fx->sr.truth[60u + (unsigned)i];
            assert_ok(rp_pose_lin_set(&pt, tp));
            assert_ok(rp_pose_lin_set(&p0, ekf.x));
            rng = 0x1234567ull + (uint64_t)trial;
            uint8_t *grp = calloc(CAP, 1);
            assert_non_null(grp);
            for (uint32_t i = 0; i < fx->n; ++i) {
                rp_obs_t *o = &fx->obs[i];
                rp_real P[3];
                assert_ok(rp_rig_cam_point(&fx->sr.rig, o->cam, &pt, o->M, P));
                const rp_real f = (rp_real)(1.0 + 0.15 * (2.0 * u01() - 1.0));
                for (int a = 0; a < 3; ++a) P[a] *= f;
                assert_ok(rp_rig_world_point(&fx->sr.rig, o->cam, &pt, P, o->M));
                o->w = RP_C(0.05);
                rp_real uv[2];
                if (o->cam == 0 && u01() < 0.4 &&
                    rp_rig_project(&fx->sr.rig, 0, &p0, o->M, uv, NULL, NULL) == RP_OK) {
                    o->uv[0] = uv[0];
                    o->uv[1] = uv[1];
                    grp[i] = 1;
                }
            }
            rp_ekf1pt_params_t prm = rp_ekf1pt_default_params();
            prm.regroup = 0; /* as gc runs it (rp_vo_gc.c) */
            if (v == 1) {
                prm.hyp_cams = 1;
            }
            rp_ekf1pt_info_t info;
            assert_ok(rp_ekf1pt_seed(&fx->op, (uint64_t)trial + 1));
            assert_ok(rp_ekf1pt_update(&fx->op, &ekf, &fx->sr.rig, fx->obs, fx->n, &prm,
                                       fx->used, &info));
            uint32_t g_used = 0, g_n = 0;
            for (uint32_t i = 0; i < fx->n; ++i) {
                g_n += grp[i];
                g_used += grp[i] && fx->used[i];
            }
            print_message("hyp_cams %u, seed %d: %u hypotheses, consensus %u, used %u of %u, "
                          "object's used %u of %u, pose error %.2e\n",
                          prm.hyp_cams, trial + 1, info.n_hyp, info.n_low, info.ekf.n_used,
                          fx->n, g_used, g_n, pose_err(fx, &ekf));
            taken[v] += g_used > 0;
            worst[v] = fmax(worst[v], pose_err(fx, &ekf));
            free(grp);
            rp_sim_run_free(&fx->sr);
            free(fx);
        }
    }
    assert_int_equal(taken[0], 0);
    assert_true(worst[0] < RP_TOL(1e-4, 1e-3));
    assert_true(taken[1] > 0 && worst[1] > 5e-3); /* the test can fail */
}

/* Clean observations (true structure, 0.5 px noise) and a prior off by 20 mm / 20 mrad: the
 * rescue fits together, step 2b does not run, and the update is bit for bit the one with it
 * switched off (regroup 0). */
static void test_clean_rescue_is_not_redrawn(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0);
    rp_ekf_t a, b;
    make_ekf_pair(fx, off20, RP_C(0.03), &a, &b);
    rp_ekf1pt_params_t prm = rp_ekf1pt_default_params();
    assert_int_equal(prm.regroup, 1);
    rp_ekf1pt_info_t ia, ib;
    assert_ok(rp_ekf1pt_update(&fx->op, &a, &fx->sr.rig, fx->obs, fx->n, &prm, NULL, &ia));
    prm.regroup = 0;
    assert_ok(rp_ekf1pt_seed(&fx->op, 1));
    assert_ok(rp_ekf1pt_update(&fx->op, &b, &fx->sr.rig, fx->obs, fx->n, &prm, NULL, &ib));
    print_message("clean: low %u, rescued %u, redrawn %u\n", ia.n_low, ia.n_rescued,
                  ia.n_reconsensus);
    assert_int_equal(ia.n_reconsensus, 0);
    assert_int_equal(ia.n_hyp_regroup, 0);
    assert_memory_equal(a.x, b.x, sizeof(a.x));
    assert_memory_equal(a.P, b.P, sizeof(a.P));
    rp_sim_run_free(&fx->sr);
    free(fx);
}

/* rp_ekf1pt_cost against the sum written out: at the truth with 0.5 px noise every observation
 * of the fixture is inside the gate (13.8 x 0.25 px^2) or capped; one moved 10 px off adds the
 * cap whatever its residual, one weighted 0 or with a NaN pixel adds nothing, one behind its
 * camera adds the cap; the weights scale the residuals. Bad arguments are refused. */
static void test_cost_is_the_capped_sum(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0);
    static const double zero[6] = {0};
    rp_ekf_t ekf;
    make_ekf(fx, zero, RP_C(0.01), &ekf);
    rp_real tp[6];
    for (int i = 0; i < 6; ++i) tp[i] = (rp_real)fx->sr.truth[60u + (unsigned)i];
    rp_pose_lin_t pt;
    assert_ok(rp_pose_lin_set(&pt, tp));
    const uint32_t n = 40;
    assert_true(fx->n >= n);
    fx->obs[1].uv[0] += RP_C(10.0);                 /* far outside the gate */
    fx->obs[2].w = RP_C(0.0);                       /* left out */
    fx->obs[3].uv[1] = (rp_real)NAN;                /* left out */
    fx->obs[4].w = RP_C(4.0);                       /* residual counted 4x */
    rp_real P[3];                                   /* mirrored behind its camera */
    assert_ok(rp_rig_cam_point(&fx->sr.rig, fx->obs[5].cam, &pt, fx->obs[5].M, P));
    for (int a = 0; a < 3; ++a) P[a] = -P[a];
    assert_ok(rp_rig_world_point(&fx->sr.rig, fx->obs[5].cam, &pt, P, fx->obs[5].M));
    const double cap = 13.8 * 0.25;
    double want = 0.0;
    uint32_t want_in = 0, behind = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const rp_obs_t *o = &fx->obs[i];
        if (!(o->w > RP_C(0.0)) || !isfinite((double)o->uv[1])) continue;
        rp_real uv[2];
        if (rp_rig_project(&fx->sr.rig, o->cam, &pt, o->M, uv, NULL, NULL) != RP_OK) {
            assert_int_equal(i, 5); /* only the one behind its camera */
            behind++;
            want += cap;
            continue;
        }
        const double e2 = (double)o->w * (pow((double)(o->uv[0] - uv[0]), 2) +
                                          pow((double)(o->uv[1] - uv[1]), 2));
        want += fmin(e2, cap);
        want_in += e2 <= cap;
    }
    rp_real cost;
    uint32_t in;
    assert_ok(rp_ekf1pt_cost(&ekf, &fx->sr.rig, fx->obs, n, tp, &cost, &in));
    print_message("cost %.4f px^2 (written out %.4f), %u of %u inside the gate\n", (double)cost,
                  want, in, n);
    assert_true(fabs((double)cost - want) <= RP_TOL(1e-9, 1e-3) * want);
    assert_int_equal(in, want_in);
    assert_int_equal(behind, 1);
    assert_true(want_in <= n - 4 && want_in >= n - 10); /* the four left out or off are not */
    assert_ok(rp_ekf1pt_cost(&ekf, &fx->sr.rig, fx->obs, 0, tp, &cost, NULL));
    assert_true(cost == RP_C(0.0));
    assert_status(rp_ekf1pt_cost(NULL, &fx->sr.rig, fx->obs, n, tp, &cost, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_cost(&ekf, NULL, fx->obs, n, tp, &cost, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_cost(&ekf, &fx->sr.rig, NULL, n, tp, &cost, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_cost(&ekf, &fx->sr.rig, fx->obs, n, NULL, &cost, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_cost(&ekf, &fx->sr.rig, fx->obs, n, tp, NULL, NULL), RP_E_ARG);
    tp[2] = (rp_real)NAN;
    assert_status(rp_ekf1pt_cost(&ekf, &fx->sr.rig, fx->obs, n, tp, &cost, NULL), RP_E_ARG);
    rp_sim_run_free(&fx->sr);
    free(fx);
}

static void test_same_seed_same_output(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.3);
    static const double off[6] = {0.005, 0.0, 0.0, 0.0, 0.005, 0.0};
    rp_ekf_t a, b;
    make_ekf_pair(fx, off, RP_C(0.01), &a, &b);
    assert_ok(rp_ekf1pt_update(&fx->op, &a, &fx->sr.rig, fx->obs, fx->n, NULL, NULL, NULL));
    assert_ok(rp_ekf1pt_seed(&fx->op, 1));
    assert_ok(rp_ekf1pt_update(&fx->op, &b, &fx->sr.rig, fx->obs, fx->n, NULL, NULL, NULL));
    assert_memory_equal(a.x, b.x, sizeof(a.x));
    assert_memory_equal(a.P, b.P, sizeof(a.P));
    rp_sim_run_free(&fx->sr);
    free(fx);
}

static void test_bad_input_is_refused(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0);
    static const double off[6] = {0};
    rp_ekf_t ekf, before;
    make_ekf(fx, off, RP_C(0.01), &ekf);
    before = ekf;
    rp_ekf1pt_params_t prm = rp_ekf1pt_default_params();
    const rp_rig_t *rig = &fx->sr.rig;
    assert_status(rp_ekf1pt_update(NULL, &ekf, rig, fx->obs, fx->n, NULL, NULL, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_update(&fx->op, NULL, rig, fx->obs, fx->n, NULL, NULL, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, NULL, fx->obs, fx->n, NULL, NULL, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, NULL, fx->n, NULL, NULL, NULL), RP_E_ARG);
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, fx->obs, CAP + 1, NULL, NULL, NULL),
                  RP_E_ARG);
    prm.confidence = RP_C(1.0);
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, fx->obs, fx->n, &prm, NULL, NULL), RP_E_ARG);
    prm = rp_ekf1pt_default_params();
    prm.min_hyp = 300;
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, fx->obs, fx->n, &prm, NULL, NULL), RP_E_ARG);
    prm = rp_ekf1pt_default_params();
    prm.regroup = 2;
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, fx->obs, fx->n, &prm, NULL, NULL), RP_E_ARG);
    prm = rp_ekf1pt_default_params();
    prm.hyp_cams = 0;
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, fx->obs, fx->n, &prm, NULL, NULL), RP_E_ARG);
    prm.hyp_cams = RP_MAX_CAMS + 1;
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, fx->obs, fx->n, &prm, NULL, NULL), RP_E_ARG);
    assert_memory_equal(ekf.x, before.x, sizeof(ekf.x));
    assert_status(rp_ekf1pt_seed(NULL, 1), RP_E_ARG);
    /* too few observations: rp_ekf_update's answer, the state left as predicted */
    assert_status(rp_ekf1pt_update(&fx->op, &ekf, rig, fx->obs, 3, NULL, NULL, NULL), RP_E_TOO_FEW);
    assert_memory_equal(ekf.x, before.x, sizeof(ekf.x));
    rp_sim_run_free(&fx->sr);
    free(fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gross_outliers_are_left_out),
        cmocka_unit_test(test_high_innovation_inliers_are_rescued),
        cmocka_unit_test(test_object_static_in_one_camera_loses_to_the_scene),
        cmocka_unit_test(test_clean_rescue_is_not_redrawn),
        cmocka_unit_test(test_same_seed_same_output),
        cmocka_unit_test(test_bad_input_is_refused),
        cmocka_unit_test(test_cost_is_the_capped_sum),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
