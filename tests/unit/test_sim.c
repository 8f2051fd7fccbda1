/*
 * test_sim.c - the simulator follows the paper's protocol (docs/design.md, Table 1) exactly, and is
 * a deterministic function of (seed, run, frame). The layout study's placements: files parse,
 * malformed lines are reported with their line, the ranking is sorted, and the paper's placement
 * reproduces the plain gc figures while another placement changes them.
 */
#include "rp_test.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rigpose/rp_rig.h"
#include "rigpose/rp_rot.h"
#include "rp_sim.h"
#include "rp_sim_layout.h"
#include "sim_fixture.h"

#define PI 3.14159265358979323846

static rp_frameset_t *new_frameset(void)
{
    rp_frameset_t *fs = malloc(sizeof *fs);
    assert_non_null(fs);
    return fs;
}

/* Equal frame sets (compared field by field: rp_feat_t has padding in double builds). */
static int frames_equal(const rp_frameset_t *a, const rp_frameset_t *b)
{
    if (a->utime != b->utime) {
        return 0;
    }
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        if (a->n[k] != b->n[k]) {
            return 0;
        }
        for (int i = 0; i < a->n[k]; ++i) {
            if (a->f[k][i].id != b->f[k][i].id || a->f[k][i].uv[0] != b->f[k][i].uv[0] ||
                a->f[k][i].uv[1] != b->f[k][i].uv[1]) {
                return 0;
            }
        }
    }
    return 1;
}

/* Camera-k coordinates of point M at frame j, in double, straight from eq. (2). */
static void cam_point(const rp_sim_run_t *sr, int k, uint32_t j, const double M[3], double P[3])
{
    const double *R = &sr->truth_R[9u * j], *d = &sr->truth[6u * j];
    const rp_rig_cam_t *c = &sr->rig.cam[k];
    double q[3], w[3];
    for (int i = 0; i < 3; ++i) {
        q[i] = M[i] - d[i] -
               (R[3 * i] * (double)c->D[0] + R[3 * i + 1] * (double)c->D[1] +
                R[3 * i + 2] * (double)c->D[2]);
    }
    for (int i = 0; i < 3; ++i) { /* w = R_j^T q */
        w[i] = R[i] * q[0] + R[3 + i] * q[1] + R[6 + i] * q[2];
    }
    for (int i = 0; i < 3; ++i) { /* P = R_k^T w */
        P[i] = (double)c->R[i] * w[0] + (double)c->R[3 + i] * w[1] + (double)c->R[6 + i] * w[2];
    }
}

/* 1 if point i is visible to camera k at frame j by the protocol's rule; pixel in uv. */
static int visible(const rp_sim_run_t *sr, int k, uint32_t j, uint32_t i, double uv[2])
{
    double P[3];
    const rp_camera_t *cam = &sr->rig.cam[k].cam;
    cam_point(sr, k, j, &sr->points[3u * i], P);
    if (P[2] < sr->cfg.min_depth) {
        return 0;
    }
    uv[0] = (double)cam->fx * P[0] / P[2] + (double)cam->cx;
    uv[1] = (double)cam->fy * P[1] / P[2] + (double)cam->cy;
    return uv[0] >= -0.5 && uv[0] < sr->cfg.width - 0.5 && uv[1] >= -0.5 &&
           uv[1] < sr->cfg.height - 0.5;
}

static const rp_feat_t *find_id(const rp_frameset_t *fs, int k, uint32_t id)
{
    for (int i = 0; i < fs->n[k]; ++i) {
        if (fs->f[k][i].id == id) {
            return &fs->f[k][i];
        }
    }
    return NULL;
}

/* ---- the generator ------------------------------------------------------------------------- */

static void rng_is_deterministic_and_well_spread(void **state)
{
    (void)state;
    rp_rng_t a, b, c;
    rp_rng_seed(&a, 42);
    rp_rng_seed(&b, 42);
    rp_rng_seed(&c, 43);
    int differ = 0;
    for (int i = 0; i < 100; ++i) {
        const uint64_t x = rp_rng_next(&a);
        assert_true(x == rp_rng_next(&b));
        differ += x != rp_rng_next(&c);
    }
    assert_true(differ > 95);

    /* Given 200k draws, then uniform mean 1/2, var 1/12; gauss mean 0, var 1. */
    const int n = 200000;
    double su = 0, su2 = 0, sg = 0, sg2 = 0;
    for (int i = 0; i < n; ++i) {
        const double u = rp_rng_uniform(&a);
        assert_true(u >= 0.0 && u < 1.0);
        su += u;
        su2 += u * u;
        const double g = rp_rng_gauss(&a);
        sg += g;
        sg2 += g * g;
    }
    assert_near(su / n, 0.5, 0.005);
    assert_near(su2 / n - (su / n) * (su / n), 1.0 / 12.0, 0.002);
    assert_near(sg / n, 0.0, 0.01);
    assert_near(sg2 / n, 1.0, 0.01);
}

/* ---- the rig ------------------------------------------------------------------------------- */

static void rig_matches_the_protocol(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_rig_t rig;
    rp_sim_default_cfg(&cfg);
    rp_sim_make_rig(&cfg, &rig);
    assert_ok(rp_rig_check(&rig));
    assert_int_equal(rig.n_cams, RP_SIM_NCAMS);

    /* Every camera 0.1 m from cam1; stereo baselines 0.1 m; cam2 to cam3 also 0.1 m. */
    const struct { int a, b; } dist01[] = {
        {RP_SIM_CAM1, RP_SIM_CAM2}, {RP_SIM_CAM1, RP_SIM_CAM3}, {RP_SIM_CAM1, RP_SIM_CAM4},
        {RP_SIM_CAM1, RP_SIM_CAM1B}, {RP_SIM_CAM3, RP_SIM_CAM3B}, {RP_SIM_CAM2, RP_SIM_CAM3},
        {RP_SIM_CAM4, RP_SIM_CAM3}};
    for (size_t p = 0; p < sizeof dist01 / sizeof dist01[0]; ++p) {
        const rp_real *A = rig.cam[dist01[p].a].D, *B = rig.cam[dist01[p].b].D;
        const double dx = (double)(A[0] - B[0]), dy = (double)(A[1] - B[1]),
                     dz = (double)(A[2] - B[2]);
        assert_near(sqrt(dx * dx + dy * dy + dz * dz), 0.1, RP_TOL(1e-12, 1e-6));
    }
    assert_near(rig.cam[RP_SIM_CAM2].D[0], 0.0866, 1e-4);
    assert_near(rig.cam[RP_SIM_CAM2].D[2], -0.05, RP_TOL(1e-12, 1e-7));
    assert_near(rig.cam[RP_SIM_CAM4].D[0], -0.0866, 1e-4);
    assert_near(rig.cam[RP_SIM_CAM3].D[2], -0.1, RP_TOL(1e-12, 1e-7));
    assert_near(rig.cam[RP_SIM_CAM1B].D[0], 0.1, RP_TOL(1e-12, 1e-7));
    assert_near(rig.cam[RP_SIM_CAM3B].D[0], 0.1, RP_TOL(1e-12, 1e-7));
    assert_near(rig.cam[RP_SIM_CAM3B].D[2], -0.1, RP_TOL(1e-12, 1e-7));

    /* Viewing directions (third column of R_k) and down (second column) in cam1's frame. */
    const double look[RP_SIM_NCAMS][3] = {
        [RP_SIM_CAM1] = {0, 0, 1}, [RP_SIM_CAM2] = {1, 0, 0}, [RP_SIM_CAM3] = {0, 0, -1},
        [RP_SIM_CAM4] = {-1, 0, 0}, [RP_SIM_CAM1B] = {0, 0, 1}, [RP_SIM_CAM3B] = {0, 0, -1}};
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        for (int i = 0; i < 3; ++i) {
            assert_near(rig.cam[k].R[3 * i + 2], look[k][i], 1e-12);
            assert_near(rig.cam[k].R[3 * i + 1], i == 1 ? 1.0 : 0.0, 1e-12);
        }
        const rp_camera_t *c = &rig.cam[k].cam;
        assert_int_equal(c->width, 640);
        assert_int_equal(c->height, 480);
        assert_near(c->fx, 800.0, 0.0);
        assert_near(c->fy, 800.0, 0.0);
        assert_near(c->cx, 319.5, 0.0);
        assert_near(c->cy, 239.5, 0.0);
        assert_near(c->k1, 0.0, 0.0);
    }
}

/* ---- the run: points and trajectory -------------------------------------------------------- */

static void points_fill_the_shell(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), 0);
    /* Uniform in volume: r^3 uniform in [r_in^3, r_out^3], so its mean is the middle. */
    double s3 = 0, sx = 0, sy = 0, sz = 0;
    for (uint32_t i = 0; i < cfg.n_points; ++i) {
        const double *M = &sr.points[3u * i];
        const double r = sqrt(M[0] * M[0] + M[1] * M[1] + M[2] * M[2]);
        assert_true(r >= cfg.r_in - 1e-12 && r <= cfg.r_out + 1e-12);
        s3 += r * r * r;
        sx += M[0] / r;
        sy += M[1] / r;
        sz += M[2] / r;
    }
    const double n = cfg.n_points;
    assert_near(s3 / n, 0.5 * (0.667 * 0.667 * 0.667 + 1.0), 0.01);
    assert_near(sx / n, 0.0, 0.03);
    assert_near(sy / n, 0.0, 0.03);
    assert_near(sz / n, 0.0, 0.03);
    rp_sim_run_free(&sr);
}

static void increments_stay_in_the_protocol_ranges(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 7, 3), 0);

    /* Frame 0 is the identity pose. */
    for (int i = 0; i < 6; ++i) {
        assert_near(sr.truth[i], 0.0, 0.0);
    }
    for (int i = 0; i < 9; ++i) {
        assert_near(sr.truth_R[i], (i % 4 == 0) ? 1.0 : 0.0, 0.0);
    }

    int neg_t = 0, neg_a = 0;
    for (uint32_t j = 1; j < cfg.n_frames; ++j) {
        const double *t0 = &sr.truth[6u * (j - 1)], *t1 = &sr.truth[6u * j];
        for (int i = 0; i < 3; ++i) { /* along the world axes */
            const double dt = t1[i] - t0[i];
            assert_true(fabs(dt) >= cfg.t_min - 1e-12 && fabs(dt) <= cfg.t_max + 1e-12);
            neg_t += dt < 0;
        }
        /* In the rig's frame: R_{j-1}^T R_j = Rz(dg) Ry(db) Rx(da). */
        const double *A = &sr.truth_R[9u * (j - 1)], *B = &sr.truth_R[9u * j];
        double I[9];
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                I[3 * r + c] = A[r] * B[c] + A[3 + r] * B[3 + c] + A[6 + r] * B[6 + c];
            }
        }
        const double inc[3] = {atan2(I[7], I[8]), -asin(I[6]), atan2(I[3], I[0])};
        for (int i = 0; i < 3; ++i) {
            assert_true(fabs(inc[i]) >= cfg.a_min - 1e-9 && fabs(inc[i]) <= cfg.a_max + 1e-9);
            neg_a += inc[i] < 0;
        }
        /* The truth angles are R_j's angles. */
        rp_real abg[3], R[9];
        for (int i = 0; i < 3; ++i) {
            abg[i] = (rp_real)t1[3 + i];
        }
        rp_rot_from_angles(abg, R);
        for (int i = 0; i < 9; ++i) {
            assert_near(R[i], B[i], RP_TOL(1e-12, 1e-5));
        }
    }
    /* Random signs: both seen often (297 draws each). */
    assert_true(neg_t > 100 && neg_t < 197);
    assert_true(neg_a > 100 && neg_a < 197);
    rp_sim_run_free(&sr);
}

/* ---- frames -------------------------------------------------------------------------------- */

static void same_seed_and_run_give_identical_frames(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.n_frames = 12;
    rp_sim_run_t a, b, c, d;
    assert_int_equal(rp_sim_run_init(&a, &cfg, 5, 2), 0);
    assert_int_equal(rp_sim_run_init(&b, &cfg, 5, 2), 0);
    assert_int_equal(rp_sim_run_init(&c, &cfg, 5, 3), 0);
    assert_int_equal(rp_sim_run_init(&d, &cfg, 6, 2), 0);
    assert_memory_equal(a.points, b.points, cfg.n_points * 3 * sizeof(double));
    assert_memory_equal(a.truth, b.truth, cfg.n_frames * 6 * sizeof(double));
    assert_memory_not_equal(a.points, c.points, cfg.n_points * 3 * sizeof(double));
    assert_memory_not_equal(a.truth, c.truth, cfg.n_frames * 6 * sizeof(double));
    assert_memory_not_equal(a.truth, d.truth, cfg.n_frames * 6 * sizeof(double));

    rp_frameset_t *fa = new_frameset(), *fb = new_frameset();
    /* Frames in any order, any number of times: the same features. */
    (void)rp_sim_frame(&b, 11, fb);
    (void)rp_sim_frame(&b, 4, fb);
    for (uint32_t j = 0; j < cfg.n_frames; ++j) {
        const uint32_t na = rp_sim_frame(&a, j, fa);
        const uint32_t nb = rp_sim_frame(&b, cfg.n_frames - 1 - j, fb);
        (void)nb;
        assert_true(na > 0);
        assert_int_equal(rp_sim_frame(&b, j, fb), na);
        assert_true(frames_equal(fa, fb));
        assert_int_equal(fa->utime, (int64_t)llround(j * 1e6 / 30.0));
        (void)rp_sim_frame(&c, j, fb);
        assert_false(frames_equal(fa, fb));
    }
    free(fa);
    free(fb);
    rp_sim_run_free(&a);
    rp_sim_run_free(&b);
    rp_sim_run_free(&c);
    rp_sim_run_free(&d);
}

/* Noise-free features agree with the core's measurement model (rp_rig_project, eq. 2). */
static void noise_free_features_match_the_core_model(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = 0.0;
    cfg.n_frames = 40;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 11, 0), 0);
    rp_frameset_t *fs = new_frameset();
    const uint32_t j = 39;
    (void)rp_sim_frame(&sr, j, fs);
    rp_real p[6];
    for (int i = 0; i < 6; ++i) {
        p[i] = (rp_real)sr.truth[6u * j + i];
    }
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p));
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        assert_true(fs->n[k] > 50);
        for (int i = 0; i < fs->n[k]; ++i) {
            const double *M = &sr.points[3u * fs->f[k][i].id];
            const rp_real Mr[3] = {(rp_real)M[0], (rp_real)M[1], (rp_real)M[2]};
            rp_real uv[2];
            assert_ok(rp_rig_project(&sr.rig, (uint8_t)k, &pl, Mr, uv, NULL, NULL));
            assert_near(uv[0], fs->f[k][i].uv[0], RP_TOL(1e-6, 0.05));
            assert_near(uv[1], fs->f[k][i].uv[1], RP_TOL(1e-6, 0.05));
        }
    }
    free(fs);
    rp_sim_run_free(&sr);
}

static void pixel_noise_has_the_configured_std(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    cfg.n_frames = 20;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 3, 1), 0);
    rp_frameset_t *fs = new_frameset();
    double s = 0, s2 = 0, cross = 0;
    uint32_t n = 0;
    for (uint32_t j = 15; j < 20; ++j) {
        (void)rp_sim_frame(&sr, j, fs);
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            for (int i = 0; i < fs->n[k]; ++i) {
                double uv[2];
                assert_true(visible(&sr, k, j, fs->f[k][i].id, uv));
                const double eu = (double)fs->f[k][i].uv[0] - uv[0];
                const double ev = (double)fs->f[k][i].uv[1] - uv[1];
                s += eu + ev;
                s2 += eu * eu + ev * ev;
                cross += eu * ev;
                n += 2;
            }
        }
    }
    assert_true(n > 10000);
    assert_near(s / n, 0.0, 0.02);
    assert_near(sqrt(s2 / n), cfg.noise_px, 0.02 * cfg.noise_px + RP_TOL(0.0, 1e-3));
    assert_near(cross / (n / 2), 0.0, 0.02); /* u and v noise independent */

    free(fs);
    rp_sim_run_free(&sr);
}

/* Every visible point is listed, nothing else, in id order, when no camera is over the limit. */
static void visibility_rule_is_respected(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    cfg.n_frames = 60;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 9, 4), 0);
    rp_frameset_t *fs = new_frameset();
    const uint32_t frames[] = {0, 30, 59};
    for (size_t f = 0; f < 3; ++f) {
        const uint32_t j = frames[f];
        (void)rp_sim_frame(&sr, j, fs);
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            uint32_t want = 0;
            int at = 0;
            for (uint32_t i = 0; i < cfg.n_points; ++i) {
                double uv[2];
                if (!visible(&sr, k, j, i, uv)) {
                    continue;
                }
                ++want;
                if (at < fs->n[k]) {
                    assert_int_equal(fs->f[k][at].id, i);
                    ++at;
                }
            }
            assert_true(want <= RP_MAX_FEATS_PER_CAM); /* the protocol's scene stays under */
            assert_int_equal(fs->n[k], want);
        }
        for (int k = RP_SIM_NCAMS; k < RP_MAX_CAMS; ++k) {
            assert_int_equal(fs->n[k], 0);
        }
    }
    free(fs);
    rp_sim_run_free(&sr);
}

/* A camera that sees more than RP_MAX_FEATS_PER_CAM points keeps the nearest ones. */
static void a_crowded_camera_keeps_the_nearest(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    cfg.n_points = 60000;
    cfg.n_frames = 2;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), 0);
    rp_frameset_t *fs = new_frameset();
    const uint32_t j = 1;
    (void)rp_sim_frame(&sr, j, fs);
    uint8_t *kept = calloc(cfg.n_points, 1);
    assert_non_null(kept);
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        assert_int_equal(fs->n[k], RP_MAX_FEATS_PER_CAM);
        memset(kept, 0, cfg.n_points);
        double far_kept = 0.0;
        for (int i = 0; i < fs->n[k]; ++i) {
            const uint32_t id = fs->f[k][i].id;
            if (i > 0) {
                assert_true(fs->f[k][i - 1].id < id);
            }
            double uv[2], P[3];
            assert_true(visible(&sr, k, j, id, uv));
            cam_point(&sr, k, j, &sr.points[3u * id], P);
            far_kept = fmax(far_kept, P[0] * P[0] + P[1] * P[1] + P[2] * P[2]);
            kept[id] = 1;
        }
        for (uint32_t i = 0; i < cfg.n_points; ++i) {
            double uv[2], P[3];
            if (kept[i] || !visible(&sr, k, j, i, uv)) {
                continue;
            }
            cam_point(&sr, k, j, &sr.points[3u * i], P);
            assert_true(P[0] * P[0] + P[1] * P[1] + P[2] * P[2] >= far_kept - 1e-12);
        }
    }
    free(kept);
    free(fs);
    rp_sim_run_free(&sr);
}

/* Stereo partners: a shared id is the same world point in both cameras. */
static void ids_are_consistent_between_stereo_partners(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    cfg.n_frames = 30;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 2, 8), 0);
    rp_frameset_t *fs = new_frameset();
    const int pairs[2][2] = {{RP_SIM_CAM1, RP_SIM_CAM1B}, {RP_SIM_CAM3, RP_SIM_CAM3B}};
    for (uint32_t j = 0; j < cfg.n_frames; j += 29) {
        (void)rp_sim_frame(&sr, j, fs);
        for (int p = 0; p < 2; ++p) {
            const int a = pairs[p][0], b = pairs[p][1];
            int shared = 0;
            for (int i = 0; i < fs->n[a]; ++i) {
                const rp_feat_t *fa = &fs->f[a][i];
                const rp_feat_t *fb = find_id(fs, b, fa->id);
                if (!fb) {
                    continue;
                }
                ++shared;
                /* Same point: both pixels within noise of that point's projections, and the
                 * disparity has the sign the baseline gives (cam b sits at +x of cam1's
                 * frame: +x of cam1, -x of cam3). */
                double ua[2], ub[2];
                assert_true(visible(&sr, a, j, fa->id, ua));
                assert_true(visible(&sr, b, j, fa->id, ub));
                assert_near(fa->uv[0], ua[0], 4.0);
                assert_near(fb->uv[0], ub[0], 4.0);
                assert_near(fa->uv[1], ua[1], 4.0);
                assert_near(fb->uv[1], ub[1], 4.0);
                const double disp = ua[0] - ub[0];
                assert_true(p == 0 ? disp > 0.0 : disp < 0.0);
                /* Independent noise in the two cameras. */
                assert_true(fa->uv[1] - (rp_real)ua[1] != fb->uv[1] - (rp_real)ub[1]);
            }
            assert_true(shared > 100);
        }
    }
    free(fs);
    rp_sim_run_free(&sr);
}

/* ---- layout study ---------------------------------------------------------------------- */

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_true(fputs(text, f) >= 0);
    assert_int_equal(fclose(f), 0);
}

static void layout_file_parses(void **state)
{
    (void)state;
    char path[] = "/tmp/rp_test_layout_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    write_file(path, "# name  cam2 x y z yaw   cam4 x y z yaw\n"
                     "\n"
                     "paper   0.0866 0 -0.05 90   -0.0866 0 -0.05 -90   # the paper's\n"
                     "wide\t0.25 0.01 -0.05 60 -0.25 0.01 -0.05 -60\r\n"
                     "   forward 0 0 0.1 0 0 0 -0.2 180\n");
    rp_sim_layout_t l[4];
    char err[200] = "";
    assert_int_equal(rp_sim_layout_read(path, l, 4, err, sizeof err), 3);
    assert_string_equal(l[0].name, "paper");
    assert_true(l[0].is_paper);
    const rp_sim_layout_t p = rp_sim_layout_paper();
    assert_memory_equal(&l[0].cam2, &p.cam2, sizeof p.cam2); /* snapped exactly */
    assert_memory_equal(&l[0].cam4, &p.cam4, sizeof p.cam4);
    assert_string_equal(l[1].name, "wide");
    assert_false(l[1].is_paper);
    assert_near(l[1].cam2.D[0], 0.25, 1e-15);
    assert_near(l[1].cam2.D[1], 0.01, 1e-15);
    assert_near(l[1].cam2.yaw, PI / 3.0, 1e-12);
    assert_near(l[1].cam4.yaw, -PI / 3.0, 1e-12);
    assert_string_equal(l[2].name, "forward");
    assert_near(l[2].cam4.D[2], -0.2, 1e-15);
    assert_near(l[2].cam4.yaw, PI, 1e-12);
    /* The placement reaches the rig: cam2 of "wide" looks 60 degrees right of forward. */
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    rp_sim_layout_apply(&l[1], &cfg);
    rp_rig_t rig;
    rp_sim_make_rig(&cfg, &rig);
    assert_near(rig.cam[RP_SIM_CAM2].D[0], 0.25, 1e-6);
    assert_near(rig.cam[RP_SIM_CAM2].R[2], sin(PI / 3.0), 1e-6); /* z axis, x component */
    assert_near(rig.cam[RP_SIM_CAM2].R[8], cos(PI / 3.0), 1e-6);
    assert_ok(rp_rig_check(&rig));
    remove(path);
}

/* A file whose line `bad_line` is `text`; the error must name path:line and contain `why`. */
static void expect_error(const char *lines, int bad_line, const char *why)
{
    char path[] = "/tmp/rp_test_layout_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    write_file(path, lines);
    rp_sim_layout_t l[4];
    char err[300] = "", want[300];
    assert_int_equal(rp_sim_layout_read(path, l, 4, err, sizeof err), -1);
    if (bad_line > 0) {
        snprintf(want, sizeof want, "%s:%d: ", path, bad_line);
    } else {
        snprintf(want, sizeof want, "%s: ", path);
    }
    print_message("  %s\n", err);
    assert_non_null(strstr(err, want));
    assert_non_null(strstr(err, why));
    remove(path);
}

static void malformed_lines_give_errors_naming_the_line(void **state)
{
    (void)state;
    const char *good = "a 0.1 0 0 90 -0.1 0 0 -90\n";
    char text[600];
    snprintf(text, sizeof text, "%s# comment\nb 0.1 0 0 90 -0.1 0 0\n", good);
    expect_error(text, 3, "got 8 fields");
    snprintf(text, sizeof text, "%s%sc 0.1 0 0 ninety -0.1 0 0 -90\n", good, "\n");
    expect_error(text, 3, "'ninety' is not a finite number");
    snprintf(text, sizeof text, "%sd 0.1 0 0 90 -0.1 0 0 -90 7\n", good);
    expect_error(text, 2, "got 10 fields");
    snprintf(text, sizeof text, "%sa 0.2 0 0 90 -0.2 0 0 -90\n", good);
    expect_error(text, 2, "'a' given twice");
    snprintf(text, sizeof text, "%se 0.1 0 0 nan -0.1 0 0 -90\n", good);
    expect_error(text, 2, "not a finite number");
    snprintf(text, sizeof text, "%sf 0.1 0 0 400 -0.1 0 0 -90\n", good);
    expect_error(text, 2, "yaw 400 out of range");
    snprintf(text, sizeof text, "%sg 50 0 0 90 -0.1 0 0 -90\n", good);
    expect_error(text, 2, "offset 50 out of range");
    snprintf(text, sizeof text, "%s0123456789012345678901234567890123 0.1 0 0 90 -0.1 0 0 -90\n",
             good);
    expect_error(text, 2, "longer than 31 characters");
    expect_error("# only a comment\n\n", 0, "no placements");
    char err[200];
    rp_sim_layout_t l[1];
    assert_int_equal(rp_sim_layout_read("/nonexistent/layout.txt", l, 1, err, sizeof err), -1);
    assert_non_null(strstr(err, "/nonexistent/layout.txt: cannot open"));
    /* more placements than the caller's array */
    char path[] = "/tmp/rp_test_layout_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    write_file(path, "a 0.1 0 0 90 -0.1 0 0 -90\nb 0.1 0 0 90 -0.1 0 0 -90\n");
    assert_int_equal(rp_sim_layout_read(path, l, 1, err, sizeof err), -1);
    assert_non_null(strstr(err, ":2: more than 1 placements"));
    remove(path);
}

static void ranking_is_sorted_ties_stable_nan_last(void **state)
{
    (void)state;
    enum { N = 40 };
    double key[N];
    uint32_t order[N];
    for (int i = 0; i < N; ++i) {
        key[i] = floor(rp_test_urand(0.0, 8.0)) * 1e-3; /* many ties */
    }
    key[5] = NAN;
    key[17] = NAN;
    rp_sim_layout_rank(key, N, order);
    uint8_t seen[N] = {0};
    for (int k = 0; k < N; ++k) {
        assert_true(order[k] < N);
        assert_false(seen[order[k]]);
        seen[order[k]] = 1;
        if (k == 0) continue;
        const double a = key[order[k - 1]], b = key[order[k]];
        if (isnan(a)) {
            assert_true(isnan(b));
            assert_true(order[k - 1] < order[k]);
        } else if (!isnan(b)) {
            assert_true(a <= b);
            if (a == b) assert_true(order[k - 1] < order[k]);
        }
    }
    assert_int_equal(order[N - 2], 5);
    assert_int_equal(order[N - 1], 17);
    /* The built-in grid: 27 placements, the paper's first and only once, names unique. */
    rp_sim_layout_t grid[RP_SIM_LAYOUT_MAX];
    const int n = rp_sim_layout_grid(grid, RP_SIM_LAYOUT_MAX);
    assert_int_equal(n, 27);
    int papers = 0;
    for (int i = 0; i < n; ++i) {
        papers += grid[i].is_paper;
        for (int j = 0; j < i; ++j) assert_string_not_equal(grid[i].name, grid[j].name);
    }
    assert_int_equal(papers, 1);
    assert_true(grid[0].is_paper);
    assert_int_equal(rp_sim_layout_grid(grid, 5), 5);
}

/* gc's mean errors over a few short runs of cfg. */
static void gc_errors(const rp_sim_cfg_t *cfg, double err[6])
{
    static rp_vo_gc_t vo;
    static rp_frameset_t fs;
    const rp_vo_gc_cfg_t gcfg = simfx_gc_cfg(cfg->noise_px);
    memset(err, 0, 6 * sizeof(double));
    for (uint32_t r = 0; r < 2; ++r) {
        rp_sim_run_t sr;
        assert_int_equal(rp_sim_run_init(&sr, cfg, 1, r), 0);
        assert_ok(rp_vo_gc_init(&vo, &sr.rig, &gcfg));
        for (uint32_t j = 0; j < cfg->n_frames; ++j) {
            rp_estimate_t est;
            rp_sim_frame(&sr, j, &fs);
            (void)rp_vo_gc_step(&vo, &fs, &est);
            for (int i = 0; j > 0 && i < 6; ++i) {
                double d = (double)est.p[i] - sr.truth[6 * j + i];
                if (i >= 3) d = (double)rp_angle_wrap((rp_real)d);
                err[i] += fabs(d);
            }
        }
        rp_sim_run_free(&sr);
    }
}

static void paper_placement_reproduces_the_plain_gc_figures(void **state)
{
    (void)state;
    rp_sim_cfg_t plain, paper, other;
    rp_sim_default_cfg(&plain);
    plain.n_frames = 30;
    paper = plain;
    other = plain;
    rp_sim_layout_t grid[RP_SIM_LAYOUT_MAX];
    assert_int_equal(rp_sim_layout_grid(grid, RP_SIM_LAYOUT_MAX), 27);
    rp_sim_layout_apply(&grid[0], &paper);
    rp_sim_layout_apply(&grid[26], &other);
    rp_rig_t a, b;
    rp_sim_make_rig(&plain, &a);
    rp_sim_make_rig(&paper, &b);
    assert_memory_equal(&a, &b, sizeof a); /* the very same rig */
    double e_plain[6], e_paper[6], e_other[6];
    gc_errors(&plain, e_plain);
    gc_errors(&paper, e_paper);
    gc_errors(&other, e_other);
    print_message("  gc tx over 2 x 30 frames: plain %.6e, paper placement %.6e, %s %.6e\n",
                  e_plain[0] / 58, e_paper[0] / 58, grid[26].name, e_other[0] / 58);
    for (int i = 0; i < 6; ++i) assert_true(e_plain[i] == e_paper[i]);
    int differs = 0;
    for (int i = 0; i < 6; ++i) differs |= e_other[i] != e_plain[i];
    assert_true(differs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(rng_is_deterministic_and_well_spread),
        cmocka_unit_test(rig_matches_the_protocol),
        cmocka_unit_test(points_fill_the_shell),
        cmocka_unit_test(increments_stay_in_the_protocol_ranges),
        cmocka_unit_test(same_seed_and_run_give_identical_frames),
        cmocka_unit_test(noise_free_features_match_the_core_model),
        cmocka_unit_test(pixel_noise_has_the_configured_std),
        cmocka_unit_test(visibility_rule_is_respected),
        cmocka_unit_test(a_crowded_camera_keeps_the_nearest),
        cmocka_unit_test(ids_are_consistent_between_stereo_partners),
        cmocka_unit_test(layout_file_parses),
        cmocka_unit_test(malformed_lines_give_errors_naming_the_line),
        cmocka_unit_test(ranking_is_sorted_ties_stable_nan_last),
        cmocka_unit_test(paper_placement_reproduces_the_plain_gc_figures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
