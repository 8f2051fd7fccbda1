/*
 * test_publish.c - the daemon's per-frame publishing (daemon/rp_publish.c) and status
 * accounting (daemon/rp_stats.c):
 *   - the static buffers are exactly as large as lcm-gen's encodings of pose_t and status_t,
 *     and of image_t at the largest image; a larger image is refused, not truncated;
 *   - one frame set's publish path (fill the pose, encode and publish it, the images, the
 *     accounting, the status) allocates nothing: this program is linked with
 *     -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free and counts the calls made
 *     from the daemon's code and lcm-gen's (LCM's own library, inside lcm_publish, is not
 *     wrapped: memq:// queues a copy there). The same count sees lcm-gen's own
 *     rigpose_pose_t_publish allocate, so the check can fail;
 *   - what a memq:// subscriber receives decodes to what was published: the pose, the status,
 *     each image with its rows packed (one camera with padded rows);
 *   - bad arguments give their own status, a bad image names its camera.
 */
#include <lcm/lcm.h>
#include <stdlib.h>
#include <string.h>

#include "rp_publish.h"
#include "rp_stats.h"
#include "rp_test.h"

/* ---- allocation counter ------------------------------------------------------------------------ */

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t m);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);

static int g_counting;
static unsigned g_allocs;

void *__wrap_malloc(size_t n)
{
    g_allocs += g_counting ? 1u : 0u;
    return __real_malloc(n);
}
void *__wrap_calloc(size_t n, size_t m)
{
    g_allocs += g_counting ? 1u : 0u;
    return __real_calloc(n, m);
}
void *__wrap_realloc(void *p, size_t n)
{
    g_allocs += g_counting ? 1u : 0u;
    return __real_realloc(p, n);
}
void __wrap_free(void *p)
{
    __real_free(p);
}

/* ---- a frame set with two images and the truth ------------------------------------------------ */

#define W 64
#define H 48
#define PAD 16
static uint8_t g_img0[W * H];               /* packed */
static uint8_t g_img1[(W + PAD) * H];       /* rows padded to W + PAD bytes */
static rp_hal_set_t g_set;
static rp_stats_t g_stats;

static void make_set(int64_t utime)
{
    memset(&g_set, 0, sizeof g_set);
    g_set.utime = utime;
    g_set.n_cams = 4;
    for (size_t i = 0; i < sizeof g_img0; ++i) {
        g_img0[i] = (uint8_t)(i * 7u);
    }
    for (size_t i = 0; i < sizeof g_img1; ++i) {
        g_img1[i] = (uint8_t)(i % (W + PAD) < W ? i * 13u : 0xEEu);
    }
    g_set.cam[0].img = (rp_image_t){g_img0, W, H, W, sizeof g_img0};
    g_set.cam[1].img = (rp_image_t){g_img1, W, H, W + PAD, sizeof g_img1};
    for (int k = 0; k < 4; ++k) {
        g_set.cam[k].utime = utime;
        g_set.cam[k].flags = k >= 2 ? RP_HAL_CAM_MISSING : RP_HAL_CAM_OK;
        g_set.cam[k].drops = (uint32_t)k;
    }
    g_set.has_truth = 1;
    for (int i = 0; i < 6; ++i) {
        g_set.truth[i] = (rp_real)(0.01 * (i + 1));
    }
}

static void make_estimate(rp_estimate_t *e, uint32_t frame)
{
    memset(e, 0, sizeof *e);
    e->frame = frame;
    for (int i = 0; i < 6; ++i) {
        e->p[i] = (rp_real)(0.01 * (i + 1) + 0.001);
        e->v[i] = (rp_real)(0.1 * i);
        e->cov[7 * i] = (rp_real)1e-4;
    }
    e->n_used[0] = 100;
    e->n_used[1] = 90;
    e->n_landmarks = 150;
    e->flags = RP_EST_TRACKING;
}

/* ---- what a memq:// subscriber receives ------------------------------------------------------ */

typedef struct {
    unsigned poses, statuses, images;
    rigpose_pose_t pose;
    rigpose_status_t status;
    int images_ok;
} rx_t;

static void on_pose(const lcm_recv_buf_t *rb, const char *ch, void *user)
{
    (void)ch;
    rx_t *rx = user;
    assert_true(rigpose_pose_t_decode(rb->data, 0, (int)rb->data_size, &rx->pose) > 0);
    rx->poses++;
}
static void on_status(const lcm_recv_buf_t *rb, const char *ch, void *user)
{
    (void)ch;
    rx_t *rx = user;
    assert_true(rigpose_status_t_decode(rb->data, 0, (int)rb->data_size, &rx->status) > 0);
    rx->statuses++;
}
static void on_image(const lcm_recv_buf_t *rb, const char *ch, void *user)
{
    (void)ch;
    rx_t *rx = user;
    rigpose_image_t m;
    assert_true(rigpose_image_t_decode(rb->data, 0, (int)rb->data_size, &m) > 0);
    assert_true(m.cam == 0 || m.cam == 1);
    assert_int_equal(m.width, W);
    assert_int_equal(m.height, H);
    assert_int_equal(m.size, W * H);
    for (int y = 0; y < H; ++y) {
        const uint8_t *row = m.cam == 0 ? g_img0 + y * W : g_img1 + y * (W + PAD);
        rx->images_ok &= memcmp(m.data + y * W, row, W) == 0;
    }
    rigpose_image_t_decode_cleanup(&m);
    rx->images++;
}

static void drain(lcm_t *lcm)
{
    while (lcm_handle_timeout(lcm, 0) > 0) {
    }
}

/* ---- tests ------------------------------------------------------------------------------------ */

static void test_the_buffers_are_the_largest_encodings(void **state)
{
    (void)state;
    rigpose_pose_t p;
    rigpose_status_t s;
    memset(&p, 0, sizeof p);
    memset(&s, 0, sizeof s);
    assert_int_equal(rigpose_pose_t_encoded_size(&p), RP_PUB_POSE_BYTES);
    assert_int_equal(rigpose_status_t_encoded_size(&s), RP_PUB_STATUS_BYTES);
    static uint8_t big[RP_HAL_MAX_W * RP_HAL_MAX_H + 1];
    rigpose_image_t im = {0, 0, 0, RP_HAL_MAX_W, RP_HAL_MAX_H, RP_HAL_MAX_W * RP_HAL_MAX_H, big};
    assert_int_equal(rigpose_image_t_encoded_size(&im), RP_PUB_IMAGE_BYTES);

    lcm_t *lcm = lcm_create("memq://");
    assert_non_null(lcm);
    assert_int_equal(rp_pub_image(lcm, "IMG", &im), RP_PUB_OK);
    im.size += 1;
    assert_int_equal(rp_pub_image(lcm, "IMG", &im), RP_PUB_E_SIZE);
    lcm_destroy(lcm);
}

static void test_one_sets_publish_path_allocates_nothing(void **state)
{
    (void)state;
    lcm_t *lcm = lcm_create("memq://");
    assert_non_null(lcm);
    rx_t rx;
    memset(&rx, 0, sizeof rx);
    rx.images_ok = 1;
    lcm_subscribe(lcm, "POSE", on_pose, &rx);
    lcm_subscribe(lcm, "STATUS", on_status, &rx);
    lcm_subscribe(lcm, "IMAGE", on_image, &rx);
    assert_ok(rp_stats_init(&g_stats, RP_HAL_SRC_REPLAY, RIGPOSE_POSE_T_METHOD_STEREO2, 4, 0));

    const unsigned sets = 20;
    for (unsigned j = 0; j < sets; ++j) {
        rp_estimate_t est;
        make_set(1000000 + 33333 * (int64_t)j);
        make_estimate(&est, j);
        unsigned fails = 0;

        g_allocs = 0;
        g_counting = 1;
        rigpose_pose_t pm;
        rp_pub_fill_pose(&pm, &g_set, &est, RP_OK, (int32_t)j, 4, RIGPOSE_POSE_T_METHOD_STEREO2);
        pm.publish_utime = g_set.utime + 1000;
        fails += rp_pub_pose(lcm, "POSE", &pm) != RP_PUB_OK;
        int bad_cam = 0;
        fails += rp_pub_set_images(lcm, "IMAGE", &g_set, (int32_t)j, &bad_cam) != RP_PUB_OK;
        rp_stats_set_t r;
        fails += rp_stats_set(&g_stats, &g_set, &est, 1.0f, pm.publish_utime, &r) != RP_OK;
        rigpose_status_t sm;
        rp_stats_fill_status(&g_stats, &sm, &g_set, RP_HAL_OK, NULL, &est, 1.0f, 0.5f,
                             pm.publish_utime);
        fails += rp_pub_status(lcm, "STATUS", &sm) != RP_PUB_OK;
        g_counting = 0;

        assert_int_equal(fails, 0);
        assert_int_equal(bad_cam, -1);
        if (g_allocs != 0) {
            fail_msg("set %u: the publish path called malloc/calloc/realloc %u times", j,
                     g_allocs);
        }
        assert_true(r.has_err && r.err_t_m > 0.0);
        drain(lcm); /* decoding image_t allocates (data[size]): outside the count */
    }
    assert_int_equal(rx.poses, sets);
    assert_int_equal(rx.statuses, sets);
    assert_int_equal(rx.images, 2 * sets);
    assert_true(rx.images_ok);
    /* The last pose and status as the subscriber decoded them. */
    assert_int_equal(rx.pose.seq, (int32_t)sets - 1);
    assert_int_equal(rx.pose.frame, (int32_t)sets - 1);
    assert_int_equal(rx.pose.method, RIGPOSE_POSE_T_METHOD_STEREO2);
    assert_int_equal(rx.pose.n_cams, 4);
    assert_int_equal(rx.pose.features_used[0], 100);
    assert_int_equal(rx.pose.features_used[1], 90);
    assert_true(rx.pose.has_truth);
    assert_near(rx.pose.position[2], 0.031, 1e-6);
    assert_near(rx.pose.truth[5], 0.06, 1e-6);
    assert_near(rx.pose.quaternion[0] * rx.pose.quaternion[0] +
                    rx.pose.quaternion[1] * rx.pose.quaternion[1] +
                    rx.pose.quaternion[2] * rx.pose.quaternion[2] +
                    rx.pose.quaternion[3] * rx.pose.quaternion[3],
                1.0, 1e-6);
    assert_int_equal(rx.status.seq, (int32_t)sets - 1);
    assert_int_equal(rx.status.last_pose_seq, (int32_t)sets - 1);
    assert_int_equal(rx.status.source, RIGPOSE_STATUS_T_SOURCE_REPLAY);
    assert_int_equal(rx.status.cam_state[0], RIGPOSE_STATUS_T_CAM_OK);
    assert_int_equal(rx.status.cam_state[2], RIGPOSE_STATUS_T_CAM_MISSING);
    assert_int_equal(rx.status.frames[0], (int32_t)sets);
    assert_int_equal(rx.status.frames[2], 0);
    assert_int_equal(rx.status.drops[3], 3);
    assert_near(rx.status.pos_sigma_m, sqrt(3e-4), 1e-6);
    lcm_destroy(lcm);
}

/* rigpose_features_t: every camera's tracked features reach a subscriber, cut at 512, the
 * positions exactly as the estimator has them (Q16 fractions of a 640-px image: 26 significant
 * bits, more than a float's 24), and publishing them allocates nothing. */
typedef struct {
    unsigned n;
    rigpose_features_t m[2];
} feats_rx_t;
static void on_features(const lcm_recv_buf_t *rb, const char *ch, void *user)
{
    (void)ch;
    feats_rx_t *rx = user;
    assert_true(rx->n < 2);
    assert_true(rigpose_features_t_decode(rb->data, 0, (int)rb->data_size, &rx->m[rx->n]) > 0);
    rx->n++;
}
static void test_features_reach_a_subscriber_without_allocating(void **state)
{
    (void)state;
    static rp_frameset_t fs;
    memset(&fs, 0, sizeof fs);
    fs.utime = 123456;
    fs.n[0] = 3;
    fs.n[1] = RP_MAX_FEATS_PER_CAM;
    for (uint16_t i = 0; i < RP_MAX_FEATS_PER_CAM; ++i) {
        fs.f[0][i].id = 1000u + i;
        fs.f[0][i].uv[0] = (rp_real)(10 + i) + (rp_real)(i + 1) / (rp_real)65536;
        fs.f[0][i].uv[1] = (rp_real)(20 + i) - (rp_real)(i + 3) / (rp_real)65536;
        fs.f[1][i].id = 5000u + i;
        fs.f[1][i].uv[0] = (rp_real)0.5;
        fs.f[1][i].uv[1] = (rp_real)i + (rp_real)(i + 1) / (rp_real)65536;
    }
    rigpose_features_t empty;
    memset(&empty, 0, sizeof empty);
    assert_int_equal(rigpose_features_t_encoded_size(&empty), RP_PUB_FEATS_BYTES);

    lcm_t *lcm = lcm_create("memq://");
    assert_non_null(lcm);
    feats_rx_t rx;
    memset(&rx, 0, sizeof rx);
    lcm_subscribe(lcm, "IMAGE_FEATURES", on_features, &rx);
    int bad_cam = 0;
    g_allocs = 0;
    g_counting = 1;
    const rp_pub_status_t st = rp_pub_set_features(lcm, "IMAGE_FEATURES", &fs, 2, 7, &bad_cam);
    g_counting = 0;
    assert_int_equal(st, RP_PUB_OK);
    assert_int_equal(bad_cam, -1);
    assert_int_equal(g_allocs, 0);
    drain(lcm);
    assert_int_equal(rx.n, 2);
    assert_int_equal(rx.m[0].cam, 0);
    assert_int_equal(rx.m[0].seq, 7);
    assert_true(rx.m[0].utime == 123456);
    assert_int_equal(rx.m[0].n, 3);
    assert_int_equal(rx.m[0].id[2], 1002);
    assert_true(rx.m[0].u[2] == (double)fs.f[0][2].uv[0]);
    assert_true(rx.m[0].v[2] == (double)fs.f[0][2].uv[1]);
    assert_near(rx.m[0].u[2], 12.0 + 3.0 / 65536, 1e-6);
    assert_int_equal(rx.m[0].flags[0], 0);
    assert_int_equal(rx.m[0].state, 0);
    assert_int_equal(rx.m[0].id[3], 0); /* past n: zero */
    assert_int_equal(rx.m[1].cam, 1);
    assert_int_equal(rx.m[1].n, RP_MAX_FEATS_PER_CAM < RP_PUB_FEATS_MAX ? RP_MAX_FEATS_PER_CAM
                                                                      : RP_PUB_FEATS_MAX);
    assert_near(rx.m[1].v[rx.m[1].n - 1], (double)(rx.m[1].n - 1), 1e-2);
    /* 510 + 511 / 65536: 25 significant bits, more than a float's 24 (exact with double
     * rp_real; with float rp_real the value itself is the float's) */
    assert_true(rx.m[1].v[510] == (double)fs.f[1][510].uv[1]);
    assert_int_equal(rp_pub_set_features(lcm, "", &fs, 2, 0, &bad_cam), RP_PUB_E_ARG);
    assert_int_equal(rp_pub_set_features(lcm, "X", NULL, 2, 0, &bad_cam), RP_PUB_E_ARG);
    lcm_destroy(lcm);
}

static void test_the_count_sees_lcm_gens_own_publish_allocate(void **state)
{
    (void)state;
    lcm_t *lcm = lcm_create("memq://");
    assert_non_null(lcm);
    rigpose_pose_t pm;
    memset(&pm, 0, sizeof pm);
    g_allocs = 0;
    g_counting = 1;
    const int rc = rigpose_pose_t_publish(lcm, "POSE", &pm);
    g_counting = 0;
    assert_int_equal(rc, 0);
    assert_true(g_allocs >= 1); /* its buffer per message: why rp_pub_pose exists */
    lcm_destroy(lcm);
}

static void test_bad_arguments_have_their_own_status(void **state)
{
    (void)state;
    lcm_t *lcm = lcm_create("memq://");
    assert_non_null(lcm);
    rigpose_pose_t pm;
    rigpose_status_t sm;
    memset(&pm, 0, sizeof pm);
    memset(&sm, 0, sizeof sm);
    assert_int_equal(rp_pub_pose(NULL, "POSE", &pm), RP_PUB_E_ARG);
    assert_int_equal(rp_pub_pose(lcm, "", &pm), RP_PUB_E_ARG);
    assert_int_equal(rp_pub_pose(lcm, "POSE", NULL), RP_PUB_E_ARG);
    assert_int_equal(rp_pub_status(lcm, NULL, &sm), RP_PUB_E_ARG);
    rigpose_image_t im = {0, 0, 0, 2, 2, 4, NULL};
    assert_int_equal(rp_pub_image(lcm, "IMG", &im), RP_PUB_E_ARG);
    im.size = -1;
    assert_int_equal(rp_pub_image(lcm, "IMG", &im), RP_PUB_E_ARG);

    make_set(5);
    g_set.cam[1].img.stride = W - 1; /* rows overlap: refused, camera 1 named */
    int bad_cam = -1;
    assert_int_equal(rp_pub_set_images(lcm, "IMAGE", &g_set, 0, &bad_cam), RP_PUB_E_ARG);
    assert_int_equal(bad_cam, 1);
    g_set.cam[1].img.stride = W + PAD;
    g_set.cam[1].img.size = (W + PAD) * (H - 1); /* last row past the buffer */
    assert_int_equal(rp_pub_set_images(lcm, "IMAGE", &g_set, 0, &bad_cam), RP_PUB_E_ARG);
    assert_int_equal(bad_cam, 1);
    assert_string_equal(rp_pub_status_str(RP_PUB_E_SIZE), "message larger than its buffer");
    assert_string_equal(rp_pub_status_str((rp_pub_status_t)99), "unknown publish status");
    lcm_destroy(lcm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_buffers_are_the_largest_encodings),
        cmocka_unit_test(test_one_sets_publish_path_allocates_nothing),
        cmocka_unit_test(test_features_reach_a_subscriber_without_allocating),
        cmocka_unit_test(test_the_count_sees_lcm_gens_own_publish_allocate),
        cmocka_unit_test(test_bad_arguments_have_their_own_status),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
