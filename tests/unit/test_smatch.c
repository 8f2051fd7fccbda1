/*
 * test_smatch.c - stereo matching from images (rp_smatch.h) on rendered views of a textured room
 * (img_fixture.h): matches lie on their epipolar lines, land on the true pixel and give the true
 * depth; a feature whose point is outside the right view, a repeated texture, a blank image
 * find no match; bad arguments give their status.
 *
 * Pairs: the paper's front pair (cam1 and its partner 0.1 m to the right, same orientation,
 * 320x240, f = 400 px), and a general one (the partner verged by 4 degrees about y and 2 about
 * x, offset in y and z too, both cameras with radial-tangential distortion).
 */
#include <string.h>
#include <time.h>

#include "rp_test.h"

#include "img_fixture.h"
#include "rigpose/rp_smatch.h"
#include "rigpose/rp_stereo.h"
#include "rigpose/rp_track.h"

/* The matcher built a second time with plain-C lane groups (RP_V8_SCALAR, priv/rp_v8.h), its
 * public functions renamed, to hold the library's vector kernels (SSE2 / NEON) to bit-identical
 * matches (test_vector_equals_scalar). */
#define RP_V8_SCALAR 1
#define rp_smatch_default_cfg rp_smatch_default_cfg_scalar
#define rp_smatch_init rp_smatch_init_scalar
#define rp_smatch_pair rp_smatch_pair_scalar
#include "../../core/src/frontend/rp_smatch.c"
#undef rp_smatch_default_cfg
#undef rp_smatch_init
#undef rp_smatch_pair

#define W 320
#define H 240

static rp_rig_t rig;
static rp_stereo_pair_t sp;
static uint8_t img_a[W * H], img_b[W * H];
static rp_pyr_t pyr_a, pyr_b;
static rp_tracker_t trk;
static rp_smatch_t sm;
static rp_feat_t fa[RP_MAX_FEATS_PER_CAM], fb[RP_MAX_FEATS_PER_CAM];

static void set_rot(rp_real R[9], double ry, double rx) /* Ry(ry) Rx(rx) */
{
    const double cy = cos(ry), sy = sin(ry), cx = cos(rx), sx = sin(rx);
    const double M[9] = {cy, sy * sx, sy * cx, 0, cx, -sx, -sy, cy * sx, cy * cx};
    for (int i = 0; i < 9; ++i) {
        R[i] = (rp_real)M[i];
    }
}

/* Two-camera rig: 0 = left at the origin, 1 = right. general: verged, offset, distorted. */
static void make_pair(int general)
{
    memset(&rig, 0, sizeof(rig));
    rig.n_cams = 2;
    for (int k = 0; k < 2; ++k) {
        rig.cam[k].cam = rp_cam_pinhole(W, H, RP_C(400.0), RP_C(400.0), RP_C(159.5), RP_C(119.5));
        set_rot(rig.cam[k].R, 0, 0);
    }
    rig.cam[1].D[0] = RP_C(0.1);
    if (general) {
        rig.cam[0].cam.k1 = RP_C(-0.12);
        rig.cam[0].cam.k2 = RP_C(0.03);
        rig.cam[0].cam.p1 = RP_C(0.001);
        rig.cam[1].cam.k1 = RP_C(-0.08);
        rig.cam[1].cam.p2 = RP_C(-0.001);
        rig.cam[1].cam.fx = RP_C(390.0);
        rig.cam[1].cam.cx = RP_C(162.0);
        rig.cam[1].D[1] = RP_C(0.01);
        rig.cam[1].D[2] = RP_C(0.02);
        set_rot(rig.cam[1].R, -0.07, 0.035);
    }
    assert_ok(rp_rig_check(&rig));
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
}

static void render_pair(const fx_room_t *rm, double noise)
{
    const rp_real p0[6] = {0, 0, 0, 0, 0, 0};
    uint64_t rs = 99;
    fx_render(&rig, 0, p0, rm, img_a, noise, &rs);
    fx_render(&rig, 1, p0, rm, img_b, noise, &rs);
    const rp_image_t a = fx_image(img_a, W, H), b = fx_image(img_b, W, H);
    assert_ok(rp_pyr_build(&pyr_a, &a, 4));
    assert_ok(rp_pyr_build(&pyr_b, &b, 4));
}

/* Corners of the left image, as the pipeline gets them (the tracker's first frame). */
static uint16_t detect_left(void)
{
    rp_track_cfg_t tc;
    assert_ok(rp_track_default_cfg(&tc));
    assert_ok(rp_track_init(&trk, &tc));
    const rp_image_t a = fx_image(img_a, W, H);
    uint16_t n = 0;
    assert_ok(rp_track_process(&trk, &a, 0, fa, RP_MAX_FEATS_PER_CAM, &n, NULL));
    assert_true(n >= 100);
    return n;
}

static void init_matcher(void)
{
    rp_smatch_cfg_t cfg;
    assert_ok(rp_smatch_default_cfg(&cfg));
    assert_ok(rp_smatch_init(&sm, &cfg));
}

/* Truth of a left feature: its right pixel and depth (camera a's z); 0 if not in the right
 * image. */
static int truth(const fx_room_t *rm, const rp_real uv_a[2], rp_real uv_b[2], double *z_a)
{
    const rp_real p0[6] = {0, 0, 0, 0, 0, 0};
    rp_real M[3];
    rp_pose_lin_t pl;
    rp_pose_lin_set(&pl, p0);
    if (fx_pixel_point(&rig, 0, p0, rm, uv_a, M) != 0 ||
        rp_rig_project(&rig, 1, &pl, M, uv_b, NULL, NULL) != RP_OK) {
        return 0;
    }
    *z_a = (double)M[2];
    /* the matcher's 9 x 9 window must fit (centre 4 px inside) */
    return uv_b[0] >= 4 && uv_b[1] >= 4 && uv_b[0] <= W - 5 && uv_b[1] <= H - 5;
}

typedef struct {
    int n, n_findable, n_matched;
    double err_mean, err_max, epi_mean, epi_max, depth_rel_mean, depth_rel_max, us_per_feat;
} figures_t;

static figures_t match_and_measure(const fx_room_t *rm, uint16_t n)
{
    figures_t f;
    memset(&f, 0, sizeof(f));
    f.n = n;
    for (uint16_t i = 0; i < n; ++i) {
        rp_real uvb[2];
        double z;
        f.n_findable += truth(rm, fa[i].uv, uvb, &z);
    }
    uint16_t nb = 0;
    rp_smatch_stats_t st;
    const clock_t t0 = clock();
    assert_ok(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb, RP_MAX_FEATS_PER_CAM, &nb,
                             &st));
    f.us_per_feat = (double)(clock() - t0) / CLOCKS_PER_SEC * 1e6 / n;
    assert_int_equal(st.n_in, n);
    assert_int_equal(st.n_matched + st.n_outside + st.n_flat + st.n_low_score + st.n_ambiguous +
                         st.n_lr_fail + st.n_epi_fail,
                     n);
    assert_int_equal(st.n_matched, nb);
    f.n_matched = nb;
    uint16_t j = 0;
    for (uint16_t i = 0; i < n && j < nb; ++i) {
        if (fa[i].id != fb[j].id) {
            continue; /* unmatched left feature; matches keep the order of fa */
        }
        rp_real uvb[2], P[3], rep;
        double z;
        assert_true(truth(rm, fa[i].uv, uvb, &z));
        const double e = hypot((double)(fb[j].uv[0] - uvb[0]), (double)(fb[j].uv[1] - uvb[1]));
        rp_real epi;
        assert_ok(rp_stereo_epipolar_px(&rig, &sp, fa[i].uv, fb[j].uv, &epi));
        assert_ok(rp_stereo_triangulate(&rig, &sp, fa[i].uv, fb[j].uv, P, &rep));
        const double dz = fabs((double)P[2] - z) / z;
        f.err_mean += e;
        f.err_max = e > f.err_max ? e : f.err_max;
        f.epi_mean += (double)epi;
        f.epi_max = (double)epi > f.epi_max ? (double)epi : f.epi_max;
        f.depth_rel_mean += dz;
        f.depth_rel_max = dz > f.depth_rel_max ? dz : f.depth_rel_max;
        ++j;
    }
    assert_int_equal(j, nb);
    if (nb > 0) {
        f.err_mean /= nb;
        f.epi_mean /= nb;
        f.depth_rel_mean /= nb;
    }
    return f;
}

static void print_figures(const char *what, const figures_t *f)
{
    printf("  %s: %d left corners, %d with the true match in the right view, %d matched; "
           "error vs truth mean %.3f px max %.3f px; epipolar mean %.4f px max %.4f px; depth "
           "error mean %.3f %% max %.3f %%; %.0f us per feature\n",
           what, f->n, f->n_findable, f->n_matched, f->err_mean, f->err_max, f->epi_mean,
           f->epi_max, 100 * f->depth_rel_mean, 100 * f->depth_rel_max, f->us_per_feat);
}

/* One case: the pair (general or the paper's), the room rendered with uniform noise +-noise
 * grey levels, the left image's corners matched and measured against the truth. */
static figures_t match_case(int general, double noise, const char *what)
{
    make_pair(general);
    const fx_room_t rm = fx_room_default();
    render_pair(&rm, noise);
    const uint16_t n = detect_left();
    init_matcher();
    const figures_t f = match_and_measure(&rm, n);
    print_figures(what, &f);
    return f;
}

/* Given the paper's front pair and a textured room, then most corners whose point the right
 * camera sees are matched within a tenth of a pixel of the truth (on average). */
static void test_front_pair_matches_truth(void **state)
{
    (void)state;
    const figures_t f = match_case(0, 0.0, "front pair");
    assert_true(f.n_matched >= 0.8 * f.n_findable);
    assert_true(f.err_mean < 0.1);
    assert_true(f.err_max < 0.5);
    /* the 2-D refinement may leave the line, by no more than the match's error: the truth lies
     * on it */
    assert_true(f.epi_max <= f.err_max + 1e-9);
    assert_true(f.depth_rel_mean < 0.005);
}

/* The same with pixel noise (+-4 grey levels, uniform): still accurate. */
static void test_front_pair_noisy(void **state)
{
    (void)state;
    const figures_t f = match_case(0, 4.0, "front pair, noise +-4");
    assert_true(f.n_matched >= 0.7 * f.n_findable);
    assert_true(f.err_mean < 0.15);
    assert_true(f.err_max < 1.0);
}

/* A verged, offset pair with distortion: the search follows the curved epipolar line. */
static void test_general_pair_with_distortion(void **state)
{
    (void)state;
    const figures_t f = match_case(1, 0.0, "verged distorted pair");
    assert_true(f.n_matched >= 0.7 * f.n_findable);
    assert_true(f.err_mean < 0.15);
    assert_true(f.err_max < 0.7);
    assert_true(f.epi_max <= f.err_max + 1e-9);
}

/* Given the verged distorted pair with noise, then the library's matcher (vector kernels where
 * the compiler has them) and the plain-C build give the same matches, pixels and counts, for
 * windows whose rows are shorter than, longer than and twice a lane group. */
static void test_vector_equals_scalar(void **state)
{
    (void)state;
    static rp_smatch_t ss;
    static rp_feat_t fs[RP_MAX_FEATS_PER_CAM];
    make_pair(1);
    const fx_room_t rm = fx_room_default();
    render_pair(&rm, 4.0);
    const uint16_t n = detect_left();
    static const uint8_t half_win[] = {3, 4, 7};
    int total = 0;
    for (unsigned k = 0; k < sizeof(half_win); ++k) {
        rp_smatch_cfg_t cfg;
        assert_ok(rp_smatch_default_cfg(&cfg));
        cfg.half_win = half_win[k];
        assert_ok(rp_smatch_init(&sm, &cfg));
        assert_ok(rp_smatch_init_scalar(&ss, &cfg));
        uint16_t nv = 0, ns = 0;
        rp_smatch_stats_t stv, sts;
        assert_ok(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb,
                                 RP_MAX_FEATS_PER_CAM, &nv, &stv));
        assert_ok(rp_smatch_pair_scalar(&ss, &rig, &sp, &pyr_a, &pyr_b, fa, n, fs,
                                        RP_MAX_FEATS_PER_CAM, &ns, &sts));
        assert_int_equal(nv, ns);
        assert_memory_equal(&stv, &sts, sizeof(stv));
        for (uint16_t i = 0; i < nv; ++i) {
            assert_int_equal(fb[i].id, fs[i].id);
            assert_true(fb[i].uv[0] == fs[i].uv[0] && fb[i].uv[1] == fs[i].uv[1]);
        }
        total += nv;
    }
    print_message("vector == scalar over %d matches\n", total);
    assert_true(total > 100);
}

/* Features near the left border whose points lie left of the right camera's view: no match. */
static void test_no_match_outside_right_view(void **state)
{
    (void)state;
    make_pair(0);
    const fx_room_t rm = fx_room_default();
    render_pair(&rm, 0.0);
    init_matcher();
    /* disparity is 400 * 0.1 / z >= 25 px in this room (z <= 1.6 m): u_a <= 12 puts the right
     * pixel at u_b < -12 */
    uint16_t n = 0;
    for (int v = 20; v < H - 20; v += 8) {
        for (int u = 6; u <= 12; u += 3) {
            fa[n].id = n;
            fa[n].uv[0] = (rp_real)u + RP_C(0.3);
            fa[n].uv[1] = (rp_real)v + RP_C(0.6);
            rp_real uvb[2];
            double z;
            assert_false(truth(&rm, fa[n].uv, uvb, &z));
            ++n;
        }
    }
    uint16_t nb = 7;
    rp_smatch_stats_t st;
    assert_ok(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb, RP_MAX_FEATS_PER_CAM, &nb,
                             &st));
    printf("  %u features outside the right view: %u matched, %u outside, %u low score, "
           "%u ambiguous, %u left-right\n",
           n, st.n_matched, st.n_outside, st.n_low_score, st.n_ambiguous, st.n_lr_fail);
    assert_int_equal(nb, 0);
}

/* A repeated texture (stripes) is ambiguous along the epipolar line: no (wrong) match. */
static void test_repeated_texture_is_ambiguous(void **state)
{
    (void)state;
    make_pair(0);
    fx_room_t rm = fx_room_default();
    rm.stripes = 1;
    rm.yaw = 0.0;
    render_pair(&rm, 2.0);
    init_matcher();
    uint16_t n = 0;
    for (int v = 30; v < H - 30; v += 20) {
        for (int u = 100; u < W - 30; u += 17) {
            fa[n].id = n;
            fa[n].uv[0] = (rp_real)u;
            fa[n].uv[1] = (rp_real)v;
            ++n;
        }
    }
    uint16_t nb = 0;
    rp_smatch_stats_t st;
    assert_ok(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb, RP_MAX_FEATS_PER_CAM, &nb,
                             &st));
    printf("  stripes: %u features, %u matched, %u ambiguous, %u left-right\n", n, nb,
           st.n_ambiguous, st.n_lr_fail);
    assert_int_equal(nb, 0);
    assert_true(st.n_ambiguous > n / 2);
}

/* A blank right image: every left patch finds only flat windows, nothing matches. A blank left
 * image: every feature is flat. */
static void test_blank_images_match_nothing(void **state)
{
    (void)state;
    make_pair(0);
    const fx_room_t rm = fx_room_default();
    render_pair(&rm, 0.0);
    const uint16_t n = detect_left();
    init_matcher();
    memset(img_b, 90, sizeof(img_b));
    rp_image_t b = fx_image(img_b, W, H);
    assert_ok(rp_pyr_build(&pyr_b, &b, 4));
    uint16_t nb = 1;
    rp_smatch_stats_t st;
    assert_ok(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb, RP_MAX_FEATS_PER_CAM, &nb,
                             &st));
    assert_int_equal(nb, 0);
    assert_int_equal(st.n_low_score + st.n_outside, n);
    assert_ok(rp_smatch_pair(&sm, &rig, &sp, &pyr_b, &pyr_b, fa, n, fb, RP_MAX_FEATS_PER_CAM, &nb,
                             &st));
    assert_int_equal(nb, 0);
    assert_int_equal(st.n_flat + st.n_outside, n);
}

static void test_bad_arguments(void **state)
{
    (void)state;
    make_pair(0);
    const fx_room_t rm = fx_room_default();
    render_pair(&rm, 0.0);
    const uint16_t n = detect_left();
    rp_smatch_cfg_t cfg;
    assert_status(rp_smatch_default_cfg(NULL), RP_E_ARG);
    assert_ok(rp_smatch_default_cfg(&cfg));
    assert_status(rp_smatch_init(NULL, &cfg), RP_E_ARG);
    assert_status(rp_smatch_init(&sm, NULL), RP_E_ARG);
    rp_smatch_cfg_t bad = cfg;
    bad.half_win = 1;
    assert_status(rp_smatch_init(&sm, &bad), RP_E_ARG);
    bad = cfg;
    bad.max_depth_m = bad.min_depth_m;
    assert_status(rp_smatch_init(&sm, &bad), RP_E_ARG);
    bad = cfg;
    bad.min_depth_m = RP_C(0.0);
    assert_status(rp_smatch_init(&sm, &bad), RP_E_ARG);
    bad = cfg;
    bad.search_level = RP_TRACK_MAX_LEVELS;
    assert_status(rp_smatch_init(&sm, &bad), RP_E_ARG);
    assert_ok(rp_smatch_init(&sm, &cfg));

    uint16_t nb = 0;
    assert_status(rp_smatch_pair(NULL, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb, 8, &nb, NULL),
                  RP_E_ARG);
    assert_status(rp_smatch_pair(&sm, &rig, &sp, NULL, &pyr_b, fa, n, fb, 8, &nb, NULL),
                  RP_E_ARG);
    assert_status(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, NULL, n, fb, 8, &nb, NULL),
                  RP_E_ARG);
    assert_status(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb, 8, NULL, NULL),
                  RP_E_ARG);
    /* a pyramid of another size than the calibration */
    static uint8_t small[160 * 120];
    memset(small, 0, sizeof(small));
    const rp_image_t s = fx_image(small, 160, 120);
    static rp_pyr_t pyr_s;
    assert_ok(rp_pyr_build(&pyr_s, &s, 3));
    assert_status(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_s, fa, n, fb, 8, &nb, NULL),
                  RP_E_ARG);
    /* a pair that is not the rig's */
    rp_stereo_pair_t bad_sp = sp;
    bad_sp.b = 3;
    assert_status(rp_smatch_pair(&sm, &rig, &bad_sp, &pyr_a, &pyr_b, fa, n, fb, 8, &nb, NULL),
                  RP_E_ARG);
    /* a non-finite feature is skipped, the others matched; a small cap fills up */
    fa[0].uv[0] = (rp_real)NAN;
    rp_smatch_stats_t st;
    assert_status(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa, n, fb, RP_MAX_FEATS_PER_CAM,
                                 &nb, &st),
                  RP_E_NAN);
    assert_true(nb > n / 2);
    for (uint16_t i = 0; i < nb; ++i) {
        assert_true(fb[i].id != fa[0].id);
    }
    assert_status(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fa + 1, (uint16_t)(n - 1), fb,
                                 5, &nb, &st),
                  RP_E_FULL);
    assert_int_equal(nb, 5);
    assert_true(st.n_matched > 5);
    /* nothing to match */
    assert_ok(rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, NULL, 0, fb, 5, &nb, &st));
    assert_int_equal(nb, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_front_pair_matches_truth),
        cmocka_unit_test(test_front_pair_noisy),
        cmocka_unit_test(test_general_pair_with_distortion),
        cmocka_unit_test(test_vector_equals_scalar),
        cmocka_unit_test(test_no_match_outside_right_view),
        cmocka_unit_test(test_repeated_texture_is_ambiguous),
        cmocka_unit_test(test_blank_images_match_nothing),
        cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
