/*
 * test_blackout.c - a lost pose looks lost (issue 18 item 2): every camera of the simulated
 * rig delivers nothing for 2 s (frame sets 30..89 at 30 Hz), through rp_pipe, for stereo4, gc,
 * cam1 and rc. While lost: no TRACKING flag, nothing counted as used, the published covariance
 * growing at every set; after max_predict_s (1 s) the pose is held (HELD), so the position stays
 * within v * max_predict_s of the last tracked one; when features return the layout tracks
 * again. A consumer that fuses the published position with an independent position fix by
 * their covariances is not misled: its fused error stays within a few sigma of the fix, in
 * and after the blackout. And the same with no image at all (rp_pipe_step with every image
 * NULL): the estimator predicts instead of repeating the last estimate.
 */
#include <math.h>
#include <string.h>

#include "rp_test.h"

#include "rigpose/rp_pipe.h"

#define N_SETS 150
#define OFF_FROM 30
#define OFF_TO 90 /* first set with features again */
#define FIX_SIGMA 0.05 /* the consumer's position fix, m per axis */

static rp_pipe_t pipe;
static rp_sim_run_t sr;
static rp_frameset_t fs;

static double trace3(const rp_real *cov)
{
    return (double)cov[0] + (double)cov[7] + (double)cov[14];
}

/* Fuse x_r (covariance C_r, 3x3 of the 6x6) with the fix x_g (sigma^2 I): the information-
 * weighted mean. Returns the fused position's error against truth. */
static double fused_error(const rp_real *p, const rp_real *cov, const double *x_g,
                          const double *truth)
{
    double C[9], Ci[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            C[i * 3 + j] = (double)cov[i * 6 + j];
        }
    }
    const double det = C[0] * (C[4] * C[8] - C[5] * C[7]) - C[1] * (C[3] * C[8] - C[5] * C[6]) +
                       C[2] * (C[3] * C[7] - C[4] * C[6]);
    assert_true(det > 0.0);
    Ci[0] = (C[4] * C[8] - C[5] * C[7]) / det;
    Ci[1] = (C[2] * C[7] - C[1] * C[8]) / det;
    Ci[2] = (C[1] * C[5] - C[2] * C[4]) / det;
    Ci[3] = (C[5] * C[6] - C[3] * C[8]) / det;
    Ci[4] = (C[0] * C[8] - C[2] * C[6]) / det;
    Ci[5] = (C[2] * C[3] - C[0] * C[5]) / det;
    Ci[6] = (C[3] * C[7] - C[4] * C[6]) / det;
    Ci[7] = (C[1] * C[6] - C[0] * C[7]) / det;
    Ci[8] = (C[0] * C[4] - C[1] * C[3]) / det;
    /* fused = (Ci + I/s2)^-1 (Ci x_r + x_g / s2) */
    const double ig = 1.0 / (FIX_SIGMA * FIX_SIGMA);
    double A[9], b[3];
    for (int i = 0; i < 3; ++i) {
        b[i] = ig * x_g[i];
        for (int j = 0; j < 3; ++j) {
            A[i * 3 + j] = Ci[i * 3 + j] + (i == j ? ig : 0.0);
            b[i] += Ci[i * 3 + j] * (double)p[j];
        }
    }
    const double dA = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
                      A[2] * (A[3] * A[7] - A[4] * A[6]);
    double e2 = 0.0;
    for (int i = 0; i < 3; ++i) { /* Cramer's rule */
        double M[9];
        memcpy(M, A, sizeof(M));
        for (int r = 0; r < 3; ++r) {
            M[r * 3 + i] = b[r];
        }
        const double di = M[0] * (M[4] * M[8] - M[5] * M[7]) -
                          M[1] * (M[3] * M[8] - M[5] * M[6]) + M[2] * (M[3] * M[7] - M[4] * M[6]);
        const double e = di / dA - truth[i];
        e2 += e * e;
    }
    return sqrt(e2);
}

static void run_blackout(rp_pipe_layout_t layout)
{
    rp_pipe_cfg_t cfg;
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.n_frames = N_SETS;
    assert_int_equal(rp_sim_run_init(&sr, &sc, 1, 0), 0);
    assert_ok(rp_pipe_default_cfg(layout, &cfg));
    cfg.gc = rp_sim_gc_cfg(&sc);
    assert_ok(rp_pipe_init(&pipe, &sr.rig, &cfg));
    const double max_predict_s = (double)cfg.stereo.ekf.max_predict_s;
    assert_true(max_predict_s == (double)cfg.gc.ekf.max_predict_s &&
                max_predict_s == (double)cfg.mono.ekf.max_predict_s);
    rp_rng_t rng;
    rp_rng_seed(&rng, 77);
    rp_estimate_t est;
    double last_tr = 0.0, p_good[3] = {0}, v_good = 0.0, worst_fused = 0.0;
    int tracked_after = 0, n_held = 0, first_track = -1;
    for (uint32_t j = 0; j < N_SETS; ++j) {
        rp_sim_frame(&sr, j, &fs);
        const int off = j >= OFF_FROM && j < OFF_TO;
        if (off) {
            memset(fs.n, 0, sizeof(fs.n));
        }
        (void)rp_pipe_step_feats(&pipe, &fs, &est);
        const double *truth = sr.truth + 6u * j;
        unsigned used = 0;
        for (int k = 0; k < RP_MAX_CAMS; ++k) {
            used += est.n_used[k];
        }
        if (j == OFF_FROM - 1) {
            assert_true(est.flags & RP_EST_TRACKING);
            v_good = sqrt((double)(est.v[0] * est.v[0] + est.v[1] * est.v[1] +
                                   est.v[2] * est.v[2]));
            for (int i = 0; i < 3; ++i) {
                p_good[i] = (double)est.p[i];
            }
        }
        if (off) {
            assert_true(est.flags & RP_EST_LOST);
            assert_false(est.flags & RP_EST_TRACKING);
            assert_int_equal(used, 0);
            assert_true(trace3(est.cov) > last_tr); /* grows with every predicted-only set */
            const double t_off = (double)(j - OFF_FROM + 1) / 30.0;
            if (t_off > max_predict_s + 0.04) {
                assert_true(est.flags & RP_EST_HELD);
                n_held++;
            }
            double d2 = 0.0;
            for (int i = 0; i < 3; ++i) {
                d2 += ((double)est.p[i] - p_good[i]) * ((double)est.p[i] - p_good[i]);
            }
            /* bounded: at most the last velocity for max_predict_s (and a frame) */
            assert_true(sqrt(d2) <= v_good * (max_predict_s + 0.04) + 1e-6);
        } else if (j >= OFF_TO) {
            assert_false((est.flags & RP_EST_TRACKING) && (est.flags & RP_EST_LOST));
            tracked_after += (est.flags & RP_EST_TRACKING) != 0;
            if (first_track < 0 && (est.flags & RP_EST_TRACKING)) {
                first_track = (int)(j - OFF_TO);
            }
        }
        last_tr = trace3(est.cov);
        if (j >= OFF_FROM - 1) {
            double x_g[3];
            for (int i = 0; i < 3; ++i) {
                x_g[i] = truth[i] + FIX_SIGMA * rp_rng_gauss(&rng);
            }
            const double ef = fused_error(est.p, est.cov, x_g, truth);
            worst_fused = ef > worst_fused ? ef : worst_fused;
        }
    }
    printf("  %-8s held %d sets; after: first update at set +%d, updates in %d of %d sets; "
           "worst fused error %.4f m (fix sigma %.2f m per axis)\n",
           rp_pipe_layout_name(layout), n_held, first_track, tracked_after, N_SETS - OFF_TO,
           worst_fused, FIX_SIGMA);
    assert_true(n_held > 0);
    /* tracks again: an update within 10 sets of the features' return, and updates in at least
     * a third of the sets after (gc's filter skips sets while its new landmarks' depths are
     * still priors, as at its start) */
    assert_true(first_track >= 0 && first_track < 10);
    assert_true(3 * tracked_after >= N_SETS - OFF_TO);
    /* not misled: within 5 sigma of the fix's own 3-D error (sigma sqrt(3)) */
    assert_true(worst_fused < 5.0 * FIX_SIGMA * sqrt(3.0));
    rp_sim_run_free(&sr);
}

static void test_stereo4_blackout(void **state)
{
    (void)state;
    run_blackout(RP_PIPE_STEREO4);
}

static void test_gc_blackout(void **state)
{
    (void)state;
    run_blackout(RP_PIPE_GC);
}

static void test_cam1_blackout(void **state)
{
    (void)state;
    run_blackout(RP_PIPE_CAM1);
}

/* No image at all from any camera (rp_pipe_step, every image NULL) after a tracked start on
 * features: RP_E_DEGENERATE, LOST without TRACKING, nothing used, the covariance growing, the
 * pose moving by the prediction (not repeated). */
static void test_no_images_predicts(void **state)
{
    (void)state;
    rp_pipe_cfg_t cfg;
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.n_frames = 20;
    assert_int_equal(rp_sim_run_init(&sr, &sc, 1, 0), 0);
    assert_ok(rp_pipe_default_cfg(RP_PIPE_STEREO4, &cfg));
    assert_ok(rp_pipe_init(&pipe, &sr.rig, &cfg));
    rp_estimate_t est, prev;
    for (uint32_t j = 0; j < 10; ++j) {
        rp_sim_frame(&sr, j, &fs);
        assert_ok(rp_pipe_step_feats(&pipe, &fs, &est));
    }
    assert_true(est.flags & RP_EST_TRACKING);
    const rp_image_t *none[RP_MAX_CAMS] = {NULL};
    for (uint32_t j = 10; j < 14; ++j) {
        prev = est;
        assert_status(rp_pipe_step(&pipe, none, RP_MAX_CAMS, (int64_t)j * 33333 + 1, &est),
                      RP_E_DEGENERATE);
        assert_true(est.flags & RP_EST_LOST);
        assert_false(est.flags & RP_EST_TRACKING);
        for (int k = 0; k < RP_MAX_CAMS; ++k) {
            assert_int_equal(est.n_used[k], 0);
        }
        assert_true(trace3(est.cov) > trace3(prev.cov));
        assert_true(memcmp(est.p, prev.p, sizeof(est.p)) != 0);
        assert_true(est.utime == (int64_t)j * 33333 + 1);
    }
    rp_sim_run_free(&sr);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stereo4_blackout),
        cmocka_unit_test(test_gc_blackout),
        cmocka_unit_test(test_cam1_blackout),
        cmocka_unit_test(test_no_images_predicts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
