/* test_track.c - the image front end (rp_track.h): sub-pixel tracking of shifted synthetic
 * textures (several window sizes), checkerboard corners, the forward-backward check on an
 * occluded patch, new ids, top-up of emptied cells, tiny images, the state's size, and the
 * status codes of bad images. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rp_test.h"

#include "rigpose/rp_track.h"

/* The tracker built a second time with plain-C lane groups (RP_TRACK_SCALAR), its public
 * functions renamed, to hold the library's vector kernels (SSE2 / NEON) to bit-identical results
 * (test_vector_equals_scalar). */
#define RP_TRACK_SCALAR 1
#define rp_track_default_cfg rp_track_default_cfg_scalar
#define rp_track_init rp_track_init_scalar
#define rp_track_process rp_track_process_scalar
#define rp_pyr_build rp_pyr_build_scalar
#define rp_track_set_topup_turn rp_track_set_topup_turn_scalar
#include "../../core/src/frontend/rp_track.c"
#undef rp_track_default_cfg
#undef rp_track_init
#undef rp_track_process
#undef rp_pyr_build
#undef rp_track_set_topup_turn
rp_status_t rp_track_default_cfg_scalar(rp_track_cfg_t *cfg);
rp_status_t rp_track_init_scalar(rp_tracker_t *trk, const rp_track_cfg_t *cfg);
rp_status_t rp_track_process_scalar(rp_tracker_t *trk, const rp_image_t *img, int64_t utime,
                                    rp_feat_t *out, uint16_t cap, uint16_t *n_out,
                                    rp_track_info_t *info);
rp_status_t rp_pyr_build_scalar(rp_pyr_t *pyr, const rp_image_t *img, uint8_t levels);

#define W 320
#define H 240
#define NWAVE 24

/* A smooth texture: a sum of plane waves (wavelengths 6..40 px), deterministic per seed. */
typedef struct {
    double kx[NWAVE], ky[NWAVE], ph[NWAVE], amp[NWAVE];
} texture_t;

static void texture_make(texture_t *t)
{
    for (int i = 0; i < NWAVE; ++i) {
        const double lam = rp_test_urand(6.0, 40.0), th = rp_test_urand(0.0, 6.283185307);
        t->kx[i] = 6.283185307 / lam * cos(th);
        t->ky[i] = 6.283185307 / lam * sin(th);
        t->ph[i] = rp_test_urand(0.0, 6.283185307);
        t->amp[i] = rp_test_urand(0.3, 1.0);
    }
}

static double texture_at(const texture_t *t, double x, double y)
{
    double s = 0, a = 0;
    for (int i = 0; i < NWAVE; ++i) {
        s += t->amp[i] * sin(t->kx[i] * x + t->ky[i] * y + t->ph[i]);
        a += t->amp[i];
    }
    return 128.0 + 110.0 * s / sqrt(a * a / NWAVE * 2.0) * 0.8;
}

static uint8_t to_u8(double v) { return (uint8_t)(v < 0 ? 0 : (v > 255 ? 255 : v + 0.5)); }

/* img(u, v) = texture(u - dx, v - dy): the scene moved by (+dx, +dy). */
static void render(const texture_t *t, double dx, double dy, uint8_t *img)
{
    for (int v = 0; v < H; ++v) {
        for (int u = 0; u < W; ++u) {
            img[v * W + u] = to_u8(texture_at(t, u - dx, v - dy));
        }
    }
}

static rp_image_t view(const uint8_t *p, int w, int h)
{
    rp_image_t im;
    im.data = p;
    im.w = (uint16_t)w;
    im.h = (uint16_t)h;
    im.stride = (uint32_t)w;
    im.size = (uint32_t)(w * h);
    return im;
}

static rp_tracker_t trk;
static uint8_t img0[W * H], img1[W * H];
static rp_feat_t f0[RP_MAX_FEATS_PER_CAM], f1[RP_MAX_FEATS_PER_CAM];

static void init_default(void)
{
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    assert_ok(rp_track_init(&trk, &cfg));
}

static const rp_feat_t *find_id(const rp_feat_t *f, int n, uint32_t id)
{
    for (int i = 0; i < n; ++i) {
        if (f[i].id == id) {
            return &f[i];
        }
    }
    return NULL;
}

/* Given a texture moved by a known sub-pixel shift, then tracks follow it within 0.1 px (mean
 * within 0.05 px) and almost all survive. */
static void check_shift(double dx, double dy)
{
    texture_t t;
    texture_make(&t);
    render(&t, 0, 0, img0);
    render(&t, dx, dy, img1);
    init_default();
    uint16_t n0 = 0, n1 = 0;
    rp_track_info_t info;
    rp_image_t a = view(img0, W, H), b = view(img1, W, H);
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, &info));
    assert_true(info.flags & RP_TRACK_FIRST);
    assert_true(n0 >= 100);
    assert_ok(rp_track_process(&trk, &b, 33000, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
    double sum = 0, worst = 0;
    int m = 0, n_in = 0;
    for (int i = 0; i < n0; ++i) {
        /* only where the window sees the same scene in both frames (border replicated) */
        const double u = (double)f0[i].uv[0], v = (double)f0[i].uv[1];
        const double margin = 11.0 + fmax(fabs(dx), fabs(dy)) * 1.5;
        if (u < margin || v < margin || u > W - 1 - margin || v > H - 1 - margin) {
            continue;
        }
        ++n_in;
        const rp_feat_t *g = find_id(f1, n1, f0[i].id);
        if (g == NULL) {
            continue;
        }
        const double ex = (double)g->uv[0] - (double)f0[i].uv[0] - dx;
        const double ey = (double)g->uv[1] - (double)f0[i].uv[1] - dy;
        const double e = sqrt(ex * ex + ey * ey);
        sum += e;
        worst = e > worst ? e : worst;
        ++m;
    }
    print_message("shift (%.2f, %.2f): %d of %d interior tracked, mean error %.4f px, max %.4f px\n",
                  dx, dy, m, n_in, sum / m, worst);
    assert_true(n_in >= 50);
    assert_true(m >= (int)(0.9 * n_in));
    assert_true(sum / m < 0.05);
    assert_true(worst < 0.1);
}

static void test_subpixel_shift_small(void **s)
{
    (void)s;
    check_shift(0.37, -0.61);
}

static void test_subpixel_shift_medium(void **s)
{
    (void)s;
    check_shift(3.25, 1.8);
}

static void test_subpixel_shift_large(void **s)
{
    (void)s;
    check_shift(-9.6, 7.3); /* needs the pyramid: beyond a 21x21 window's reach */
}

/* Given a checkerboard of 20 px squares, then the detected corners sit within 1 px of the
 * squares' corners (x.5 between pixels) and most corners are found. */
static void test_checkerboard_corners(void **s)
{
    (void)s;
    const int sq = 20;
    for (int v = 0; v < H; ++v) {
        for (int u = 0; u < W; ++u) {
            img0[v * W + u] = (uint8_t)((((u / sq) + (v / sq)) & 1) ? 200 : 50);
        }
    }
    init_default();
    rp_image_t a = view(img0, W, H);
    uint16_t n = 0;
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n, NULL));
    const int n_corners = (W / sq - 1) * (H / sq - 1);
    print_message("checkerboard: %d features, %d corners\n", n, n_corners);
    assert_true(n >= (int)(0.9 * n_corners));
    for (int i = 0; i < n; ++i) {
        const double cu = floor((double)f0[i].uv[0] / sq + 0.5) * sq - 0.5;
        const double cv = floor((double)f0[i].uv[1] / sq + 0.5) * sq - 0.5;
        assert_true(fabs((double)f0[i].uv[0] - cu) <= 1.0);
        assert_true(fabs((double)f0[i].uv[1] - cv) <= 1.0);
        assert_true(cu > 0 && cu < W - 1 && cv > 0 && cv < H - 1);
    }
}

/* Given a square of the scene covered by another texture in the second frame, then no track that
 * started well inside the square survives, and tracks far from it do. */
static void test_fb_drops_occluded(void **s)
{
    (void)s;
    texture_t t, o;
    texture_make(&t);
    texture_make(&o);
    render(&t, 0, 0, img0);
    render(&t, 1.5, 0.5, img1);
    const int x0 = 100, y0 = 60, side = 100;
    for (int v = y0; v < y0 + side; ++v) {
        for (int u = x0; u < x0 + side; ++u) {
            img1[v * W + u] = to_u8(texture_at(&o, u, v));
        }
    }
    init_default();
    rp_image_t a = view(img0, W, H), b = view(img1, W, H);
    uint16_t n0 = 0, n1 = 0;
    rp_track_info_t info;
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, NULL));
    assert_ok(rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
    int inside = 0, far_total = 0, far_kept = 0;
    for (int i = 0; i < n0; ++i) {
        const double u = (double)f0[i].uv[0], v = (double)f0[i].uv[1];
        const rp_feat_t *g = find_id(f1, n1, f0[i].id);
        if (u > x0 + 12 && u < x0 + side - 12 && v > y0 + 12 && v < y0 + side - 12) {
            ++inside;
            if (g != NULL) {
                print_message("  survivor %u (%.1f, %.1f) -> (%.1f, %.1f)\n", f0[i].id, u, v,
                              (double)g->uv[0], (double)g->uv[1]);
            }
            assert_null(g);
        } else if (u < x0 - 25 || u > x0 + side + 25 || v < y0 - 25 || v > y0 + side + 25) {
            ++far_total;
            far_kept += g != NULL;
        }
    }
    print_message("occlusion: %d inside dropped, lost fb %d other %d; far kept %d of %d\n", inside,
                  info.n_lost_fb, info.n_lost, far_kept, far_total);
    assert_true(inside >= 5);
    assert_true(info.n_lost_fb > 0);
    assert_true(far_kept >= (int)(0.9 * far_total));
}

/* Given a frame of another scene, then every track is lost, reported, and new features with new
 * ids replace them; ids are never reused. */
static void test_all_lost_redetects_new_ids(void **s)
{
    (void)s;
    texture_t t, o;
    texture_make(&t);
    texture_make(&o);
    render(&t, 0, 0, img0);
    render(&o, 0, 0, img1);
    init_default();
    rp_image_t a = view(img0, W, H), b = view(img1, W, H);
    uint16_t n0 = 0, n1 = 0;
    rp_track_info_t info;
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, NULL));
    uint32_t max0 = 0;
    for (int i = 0; i < n0; ++i) {
        max0 = f0[i].id > max0 ? f0[i].id : max0;
    }
    assert_ok(rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
    print_message("other scene: %d of %d survived (fb %d, other %d), %d new\n", info.n_tracked,
                  info.n_prev, info.n_lost_fb, info.n_lost, info.n_new);
    assert_true(info.n_tracked <= n0 / 20); /* a chance survivor or two at most */
    assert_true(info.n_tracked > 0 || (info.flags & RP_TRACK_ALL_LOST));
    assert_true(n1 >= 100);
    assert_true(info.flags & RP_TRACK_TOPPED_UP);
    for (int i = info.n_tracked; i < n1; ++i) {
        assert_true(f1[i].id > max0);
        assert_int_equal(rp_track_id_cam(f1[i].id), 0);
    }
    /* all lost for sure: a frame of a third, unrelated scene far off */
    render(&t, 0, 0, img0);
    for (int i = 0; i < W * H; ++i) {
        img0[i] = (uint8_t)(255 - img0[i]);
    }
    a = view(img0, W, H);
    assert_ok(rp_track_process(&trk, &a, 2, f0, RP_MAX_FEATS_PER_CAM, &n0, &info));
    print_message("inverted scene: %d survived, flags 0x%x\n", info.n_tracked, info.flags);
    assert_true(info.n_tracked == 0 ? (info.flags & RP_TRACK_ALL_LOST) != 0 : 1);
}

/* Runs frame img0 then img1 (img0 with everything right of column keep_w replaced by another
 * scene) through a tracker with reset_q8 = reset; returns the second frame's info. */
static rp_track_info_t mass_loss_frame(uint8_t reset, int keep_w, uint16_t *n_before)
{
    texture_t t, o;
    texture_make(&t);
    texture_make(&o);
    render(&t, 0, 0, img0);
    render(&o, 0, 0, img1);
    for (int v = 0; v < H; ++v) {
        memcpy(img1 + v * W, img0 + v * W, (size_t)keep_w);
    }
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    cfg.reset_q8 = reset;
    assert_ok(rp_track_init(&trk, &cfg));
    rp_image_t a = view(img0, W, H), b = view(img1, W, H);
    uint16_t n1 = 0;
    rp_track_info_t info;
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, n_before, NULL));
    assert_ok(rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
    return info;
}

/* Given a frame where most of the image became another scene (only a strip on the left kept its
 * content), then by default the strip's surviving tracks are dropped too and reported
 * (RP_TRACK_RESET, n_reset) and fresh features replace them; with reset_q8 = 0 the survivors are
 * kept; and a frame where fewer than 80 % failed keeps its survivors. */
static void test_reset_drops_survivors_of_mass_loss(void **s)
{
    (void)s;
    uint16_t n0 = 0;
    rp_track_info_t off = mass_loss_frame(0, W / 10, &n0);
    print_message("strip of 1/10, reset off: %d of %d survived, flags 0x%x\n", off.n_tracked, n0,
                  off.flags);
    assert_true(off.n_tracked >= 5);
    assert_false(off.flags & RP_TRACK_RESET);
    assert_int_equal(off.n_reset, 0);

    rp_track_cfg_t def;
    assert_ok(rp_track_default_cfg(&def));
    rp_track_info_t on = mass_loss_frame(def.reset_q8, W / 10, &n0);
    print_message("strip of 1/10, reset on: %d survived, %d dropped by the reset, %d new, "
                  "flags 0x%x\n", on.n_tracked, on.n_reset, on.n_new, on.flags);
    assert_int_equal(on.n_tracked, 0);
    assert_true(on.n_reset >= 5);
    assert_true((on.flags & RP_TRACK_RESET) && (on.flags & RP_TRACK_ALL_LOST));
    assert_true(on.n_new >= 100);
    assert_int_equal(on.n_reset + on.n_lost + on.n_lost_fb, on.n_prev);

    rp_track_info_t half = mass_loss_frame(def.reset_q8, W / 2, &n0);
    print_message("strip of 1/2, reset on: %d of %d survived, flags 0x%x\n", half.n_tracked, n0,
                  half.flags);
    assert_true(half.n_tracked >= n0 / 4);
    assert_false(half.flags & RP_TRACK_RESET);
}

/* Given a blank frame between two good ones, then it is reported and skipped, and tracking goes
 * on from the last good frame. */
static void test_blank_frame_skipped(void **s)
{
    (void)s;
    texture_t t;
    texture_make(&t);
    render(&t, 0, 0, img0);
    init_default();
    rp_image_t a = view(img0, W, H);
    uint16_t n0 = 0, n1 = 0;
    rp_track_info_t info;
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, NULL));
    memset(img1, 77, sizeof(img1));
    rp_image_t b = view(img1, W, H);
    assert_status(rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info),
                  RP_E_DEGENERATE);
    assert_int_equal(n1, 0);
    assert_true(info.flags & RP_TRACK_BLANK);
    render(&t, 0.5, 0.25, img1);
    assert_ok(rp_track_process(&trk, &b, 2, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
    assert_true(info.n_tracked >= (int)(0.9 * n0));
}

static void test_bad_images(void **s)
{
    (void)s;
    init_default();
    uint16_t n = 0;
    rp_image_t a = view(img0, W, H);
    assert_status(rp_track_process(NULL, &a, 0, f0, 10, &n, NULL), RP_E_ARG);
    assert_status(rp_track_process(&trk, NULL, 0, f0, 10, &n, NULL), RP_E_ARG);
    assert_status(rp_track_process(&trk, &a, 0, f0, 10, NULL, NULL), RP_E_ARG);
    assert_status(rp_track_process(&trk, &a, 0, NULL, 10, &n, NULL), RP_E_ARG);
    rp_image_t tiny = view(img0, 16, 16); /* smaller than the 21x21 window */
    assert_status(rp_track_process(&trk, &tiny, 0, f0, 10, &n, NULL), RP_E_ARG);
    rp_image_t trunc = a;
    trunc.size = W * (H - 1);
    assert_status(rp_track_process(&trk, &trunc, 0, f0, 10, &n, NULL), RP_E_ARG);
    rp_image_t big = a;
    big.w = RP_TRACK_MAX_W + 1;
    big.size = 0xffffffffu;
    big.stride = RP_TRACK_MAX_W + 1;
    assert_status(rp_track_process(&trk, &big, 0, f0, 10, &n, NULL), RP_E_ARG);
    rp_image_t narrow = a;
    narrow.stride = W - 1;
    assert_status(rp_track_process(&trk, &narrow, 0, f0, 10, &n, NULL), RP_E_ARG);
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    cfg.win = 20;
    assert_status(rp_track_init(&trk, &cfg), RP_E_ARG);
    assert_status(rp_track_init(&trk, NULL), RP_E_ARG);
    assert_status(rp_track_default_cfg(NULL), RP_E_ARG);
}

/* Given a noisy but flat-ish image (contrast above the blank limit, no structure), then no
 * feature is found and that is reported. */
static void test_no_texture_too_few(void **s)
{
    (void)s;
    for (int i = 0; i < W * H; ++i) {
        img0[i] = (uint8_t)(100 + (i % 7 == 0 ? 10 : 0) * ((i / W) % 2));
    }
    init_default();
    rp_image_t a = view(img0, W, H);
    uint16_t n = 0;
    rp_status_t st = rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n, NULL);
    print_message("weak pattern: status %s, %d features\n", rp_status_str(st), n);
    assert_true(st == RP_OK || st == RP_E_TOO_FEW);
    assert_true(st == RP_OK ? n > 0 : n == 0);
}

/* Given more features than the caller's buffer, then RP_E_FULL and the buffer is filled. */
static void test_cap_full(void **s)
{
    (void)s;
    texture_t t;
    texture_make(&t);
    render(&t, 0, 0, img0);
    init_default();
    rp_image_t a = view(img0, W, H);
    uint16_t n = 0;
    assert_status(rp_track_process(&trk, &a, 0, f0, 5, &n, NULL), RP_E_FULL);
    assert_int_equal(n, 5);
}

/* The pyramid halves like cv::pyrDown: sizes ceil(w/2), flat stays flat. */
static void test_pyramid(void **s)
{
    (void)s;
    static rp_pyr_t pyr;
    memset(img0, 90, sizeof(img0));
    rp_image_t a = view(img0, 101, 75);
    assert_ok(rp_pyr_build(&pyr, &a, 4));
    assert_int_equal(pyr.n_lev, 4);
    assert_int_equal(pyr.lev[1].w, 51);
    assert_int_equal(pyr.lev[1].h, 38);
    assert_int_equal(pyr.lev[3].w, 13);
    assert_int_equal(pyr.lev[3].h, 10);
    for (int i = 0; i < 13 * 10; ++i) {
        assert_int_equal(pyr.pix[pyr.lev[3].off + i], 90);
    }
}


/* Given windows of other sizes (7: one padded block of 8; 31: the largest, 32 wide), then the
 * shift is still tracked sub-pixel: the padding of window rows adds nothing to the sums. (A 7x7
 * window sees little texture: OpenCV's error is as large there, about 0.05 px.) */
static void test_window_sizes(void **s)
{
    (void)s;
    static const uint8_t wins[] = {7, 31};
    static const double max_mean[] = {0.1, 0.05};
    texture_t t;
    texture_make(&t);
    render(&t, 0, 0, img0);
    render(&t, 1.3, -0.7, img1);
    for (unsigned k = 0; k < sizeof(wins); ++k) {
        rp_track_cfg_t cfg;
        assert_ok(rp_track_default_cfg(&cfg));
        cfg.win = wins[k];
        assert_ok(rp_track_init(&trk, &cfg));
        uint16_t n0 = 0, n1 = 0;
        rp_image_t a = view(img0, W, H), b = view(img1, W, H);
        assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, NULL));
        assert_ok(rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, NULL));
        double sum = 0;
        int m = 0;
        for (int i = 0; i < n0; ++i) {
            const double u = (double)f0[i].uv[0], v = (double)f0[i].uv[1];
            const rp_feat_t *g = find_id(f1, n1, f0[i].id);
            if (g == NULL || u < 20 || v < 20 || u > W - 21 || v > H - 21) {
                continue;
            }
            sum += hypot((double)g->uv[0] - u - 1.3, (double)g->uv[1] - v + 0.7);
            ++m;
        }
        print_message("window %d: %d interior tracks, mean error %.4f px\n", wins[k], m, sum / m);
        assert_true(m >= 50);
        assert_true(sum / m < max_mean[k]);
    }
}

/* Given an image barely larger than the window (every window touches the border at every
 * level), then tracking runs on replicated borders without reading outside the image. */
static void test_tiny_image(void **s)
{
    (void)s;
    const int w = 24, h = 22;
    texture_t t;
    texture_make(&t);
    for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
            img0[v * w + u] = to_u8(texture_at(&t, u, v));
            img1[v * w + u] = to_u8(texture_at(&t, u - 0.5, v - 0.25));
        }
    }
    init_default();
    uint16_t n0 = 0, n1 = 0;
    rp_image_t a = view(img0, w, h), b = view(img1, w, h);
    const rp_status_t s0 = rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, NULL);
    const rp_status_t s1 = rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, NULL);
    print_message("tiny %dx%d: %s %d features, then %s %d\n", w, h, rp_status_str(s0), n0,
                  rp_status_str(s1), n1);
    assert_true(s0 == RP_OK || s0 == RP_E_TOO_FEW);
    assert_true(s1 == RP_OK || s1 == RP_E_TOO_FEW);
}

/* Given a scene shifted left by 12 px (features of the left edge leave, a band on the right is
 * new) and a tracker that tops up whenever it lacks any feature, then the new features go
 * mostly to the emptied cells of the right edge, and the count is back at the target. */
static void test_topup_refills_emptied_cells(void **s)
{
    (void)s;
    texture_t t;
    texture_make(&t);
    render(&t, 0, 0, img0);
    render(&t, -12, 0, img1);
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    cfg.topup_below = cfg.target;
    assert_ok(rp_track_init(&trk, &cfg));
    uint16_t n0 = 0, n1 = 0;
    rp_track_info_t info;
    rp_image_t a = view(img0, W, H), b = view(img1, W, H);
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, NULL));
    assert_ok(rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
    int new_right = 0, new_total = 0;
    for (int i = info.n_tracked; i < n1; ++i) {
        ++new_total;
        new_right += (double)f1[i].uv[0] >= W - W / cfg.grid_x;
    }
    print_message("shift 12 px: %d tracked (lost fb %d, other %d), %d new, %d of them in the "
                  "rightmost cells, %d in all\n", info.n_tracked, info.n_lost_fb, info.n_lost,
                  info.n_new, new_right, n1);
    assert_true(info.flags & RP_TRACK_TOPPED_UP);
    assert_true(info.n_tracked >= 100);
    assert_true(n1 >= 140 && n1 <= 150);
    assert_true(new_total > 0 && new_right >= new_total / 2);
}

/* Given the same shift and a tracker that would top up, then without its turn
 * (rp_track_set_topup_turn 0) it only tracks, and with the turn back it tops up; the first
 * image detects whatever the turn (no track to follow). */
static void test_topup_waits_for_its_turn(void **s)
{
    (void)s;
    texture_t t;
    texture_make(&t);
    render(&t, 0, 0, img0);
    render(&t, -12, 0, img1);
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    cfg.topup_below = cfg.target;
    assert_ok(rp_track_init(&trk, &cfg));
    assert_status(rp_track_set_topup_turn(NULL, 1), RP_E_ARG);
    assert_ok(rp_track_set_topup_turn(&trk, 0));
    uint16_t n0 = 0, n1 = 0, n2 = 0;
    rp_track_info_t info;
    rp_image_t a = view(img0, W, H), b = view(img1, W, H);
    assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, &info));
    assert_true(info.flags & RP_TRACK_TOPPED_UP);
    assert_true(n0 >= 140);
    assert_ok(rp_track_process(&trk, &b, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
    assert_false(info.flags & RP_TRACK_TOPPED_UP);
    assert_int_equal(info.n_new, 0);
    assert_int_equal(n1, info.n_tracked);
    assert_true(n1 < n0);
    assert_ok(rp_track_set_topup_turn(&trk, 1));
    assert_ok(rp_track_process(&trk, &a, 2, f1, RP_MAX_FEATS_PER_CAM, &n2, &info));
    assert_true(info.flags & RP_TRACK_TOPPED_UP);
    assert_true(n2 > info.n_tracked);
}

/* Given a full tracker on a still scene, when half of its tracks are made dormant
 * (rp_track_set_dormant), then the next frame tops up although every track survived: the live
 * ones are under the threshold; the dormant ones are still tracked and reported, and no new
 * feature lands within min_dist of one; without the marking the same frame only tracks.
 * Dormancy survives tracking and ends when the track is lost; bad arguments are refused. */
static void test_dormant_tracks_leave_the_budget(void **s)
{
    (void)s;
    texture_t t;
    texture_make(&t);
    render(&t, 0, 0, img0);
    rp_image_t a = view(img0, W, H);
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    uint16_t n0 = 0, n1 = 0;
    rp_track_info_t info;
    for (int mark = 0; mark < 2; ++mark) {
        assert_ok(rp_track_init(&trk, &cfg));
        assert_ok(rp_track_process(&trk, &a, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, &info));
        assert_true(n0 >= cfg.topup_below);
        uint32_t ids[RP_MAX_FEATS_PER_CAM];
        uint16_t n_ids = 0, marked = 0;
        for (uint16_t i = 0; i < n0; i += 2) {
            ids[n_ids++] = f0[i].id;
        }
        if (mark) {
            assert_ok(rp_track_set_dormant(&trk, ids, n_ids, &marked));
            assert_int_equal(marked, n_ids);
            assert_int_equal(trk.n_dormant, n_ids);
            assert_ok(rp_track_set_dormant(&trk, ids, n_ids, &marked)); /* already dormant */
            assert_int_equal(marked, 0);
        }
        assert_ok(rp_track_process(&trk, &a, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info));
        assert_int_equal(info.n_tracked, n0);
        print_message("%s: %u tracked, %u new\n", mark ? "half dormant" : "none dormant",
                      info.n_tracked, info.n_new);
        if (!mark) {
            assert_int_equal(info.n_new, 0);
            continue;
        }
        assert_true(info.flags & RP_TRACK_TOPPED_UP);
        assert_true(info.n_new > 0);
        assert_int_equal(trk.n_dormant, n_ids);
        for (uint16_t j = 0; j < n_ids; ++j) {
            const rp_feat_t *d = find_id(f1, n1, ids[j]);
            assert_non_null(d);
            for (int i = info.n_tracked; i < n1; ++i) {
                const double dx = (double)(f1[i].uv[0] - d->uv[0]);
                const double dy = (double)(f1[i].uv[1] - d->uv[1]);
                assert_true(dx * dx + dy * dy >= (double)cfg.min_dist * cfg.min_dist - 1.0);
            }
        }
        /* losing them: dropped tracks take their dormancy with them */
        uint16_t dropped = 0;
        assert_ok(rp_track_drop_ids(&trk, ids, n_ids, &dropped));
        assert_int_equal(dropped, n_ids);
        assert_int_equal(trk.n_dormant, 0);
    }
    assert_status(rp_track_set_dormant(NULL, NULL, 0, NULL), RP_E_ARG);
    assert_status(rp_track_set_dormant(&trk, NULL, 3, NULL), RP_E_ARG);
    assert_ok(rp_track_set_dormant(&trk, NULL, 0, NULL));
}

/* Two frames' reports equal field by field (not by memcmp: the struct has padding); n_cached
 * too if with_cached. */
static void assert_info_equal(const rp_track_info_t *a, const rp_track_info_t *b, int with_cached)
{
    assert_int_equal(a->flags, b->flags);
    assert_int_equal(a->n_prev, b->n_prev);
    assert_int_equal(a->n_tracked, b->n_tracked);
    assert_int_equal(a->n_lost_fb, b->n_lost_fb);
    assert_int_equal(a->n_lost, b->n_lost);
    assert_int_equal(a->n_reset, b->n_reset);
    assert_int_equal(a->n_new, b->n_new);
    if (with_cached) {
        assert_int_equal(a->n_cached, b->n_cached);
    }
}

/* Two trackers' outputs (n features each) and track positions equal bit for bit. */
static void assert_tracks_equal(const rp_feat_t *fa, const rp_feat_t *fb, uint16_t n,
                                const rp_tracker_t *a, const rp_tracker_t *b)
{
    for (int i = 0; i < n; ++i) {
        assert_int_equal(fa[i].id, fb[i].id);
        assert_true(fa[i].uv[0] == fb[i].uv[0] && fa[i].uv[1] == fb[i].uv[1]);
    }
    assert_int_equal(a->n, b->n);
    assert_memory_equal(a->pos_q16, b->pos_q16, sizeof(a->pos_q16[0]) * a->n);
}

/* Step k of a sequence into img1: the texture moved by shift[k] (k < blank), a blank image
 * (k == blank: every tracker skips it), shift[k - 1] after it. */
static void render_step(const texture_t *t, const double (*shift)[2], unsigned k, unsigned blank)
{
    if (k == blank) {
        memset(img1, 77, sizeof(img1));
        return;
    }
    const unsigned j = k < blank ? k : k - 1;
    render(t, shift[j][0], shift[j][1], img1);
}

/* Given a textured scene moving (sub-pixel shifts, up to 9 px a frame, a blank frame, a jump that
 * loses tracks at the border), then the library's tracker (vector kernels where the compiler has
 * them) and the plain-C build give bit-identical pyramids, features, positions and events. */
static void test_vector_equals_scalar(void **s)
{
    (void)s;
    static rp_tracker_t tv, ts;
    static rp_pyr_t pv, ps;
    static rp_feat_t fv[RP_MAX_FEATS_PER_CAM], fs[RP_MAX_FEATS_PER_CAM];
    static const double shift[][2] = {{0, 0},     {0.37, -0.21}, {3.9, 2.2},  {-8.7, 5.3},
                                      {-8.7, 5.3}, {0.1, 9.05},  {-30.5, 1.25}, {-31.0, 2.0}};
    texture_t t;
    texture_make(&t);
    /* pyramid of an odd-sized image (row tails and reflected borders) */
    render(&t, 0.3, 0.6, img0);
    const rp_image_t odd = view(img0, 101, 75);
    assert_ok(rp_pyr_build(&pv, &odd, 4));
    assert_ok(rp_pyr_build_scalar(&ps, &odd, 4));
    assert_int_equal(pv.n_lev, ps.n_lev);
    const uint32_t bytes = pv.lev[pv.n_lev - 1].off +
                           (uint32_t)pv.lev[pv.n_lev - 1].w * pv.lev[pv.n_lev - 1].h;
    assert_memory_equal(pv.pix, ps.pix, bytes);

    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    assert_ok(rp_track_init(&tv, &cfg));
    assert_ok(rp_track_init_scalar(&ts, &cfg));
    int total = 0;
    for (unsigned k = 0; k < sizeof(shift) / sizeof(shift[0]) + 1; ++k) {
        render_step(&t, shift, k, 4);
        const rp_image_t im = view(img1, W, H);
        uint16_t nv = 0, ns = 0;
        rp_track_info_t iv, is;
        const rp_status_t sv =
            rp_track_process(&tv, &im, (int64_t)k * 33000, fv, RP_MAX_FEATS_PER_CAM, &nv, &iv);
        const rp_status_t ss = rp_track_process_scalar(&ts, &im, (int64_t)k * 33000, fs,
                                                       RP_MAX_FEATS_PER_CAM, &ns, &is);
        assert_int_equal(sv, ss);
        assert_int_equal(nv, ns);
        assert_info_equal(&iv, &is, 1);
        assert_tracks_equal(fv, fs, nv, &tv, &ts);
        total += nv;
    }
    print_message("vector == scalar over %d features\n", total);
    assert_true(total > 500);
}

/* Every slot of t that holds a patch of its current image made stale: in its generation (what =
 * 0) or its position (what = 1), its pixels scribbled over. Returns how many. */
static int poison_slots(rp_tracker_t *t, int what)
{
    int n = 0;
    for (int i = 0; i < RP_MAX_FEATS_PER_CAM; ++i) {
        rp_track_patch_key_t *k = &t->slot_key[i];
        if (k->gen == 0 || k->gen != t->pyr_gen[t->cur]) {
            continue;
        }
        if (what == 0) {
            k->gen ^= 0x80000000u;
        } else {
            k->key[0] += 1;
        }
        n++;
    }
    for (size_t i = 0; i < sizeof(t->slot_pix) / sizeof(t->slot_pix[0]); ++i) {
        t->slot_pix[i] = (int16_t)(i * 7919u);
    }
    return n;
}

/* The patch cache (rp_tracker_t) changes no result: a tracker whose cache is emptied before
 * every frame gives the same tracks, ids and counts bit for bit, over sub-pixel and large shifts
 * (the full-pyramid path), a blank frame and top-ups; and the cache is used. A slot whose key
 * is stale in its image generation or in its position (its pixels scribbled over) is not used:
 * copies of the cached tracker with such slots give the same results without a hit. */
static void test_patch_cache_changes_nothing(void **s)
{
    (void)s;
    static rp_tracker_t ta, tb, tc, tb2;
    static rp_feat_t fa[RP_MAX_FEATS_PER_CAM], fb[RP_MAX_FEATS_PER_CAM];
    static const double shift[][2] = {{0, 0},      {0.37, -0.21}, {1.1, 0.4},  {3.9, 2.2},
                                      {-8.7, 5.3}, {-8.2, 5.9},   {0.1, 9.05}, {-30.5, 1.25},
                                      {-31.0, 2.0}, {-29.6, 3.1}};
    texture_t t;
    texture_make(&t);
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    assert_ok(rp_track_init(&ta, &cfg));
    assert_ok(rp_track_init(&tb, &cfg));
    int total = 0, cached = 0, poisoned = 0;
    for (unsigned k = 0; k < sizeof(shift) / sizeof(shift[0]) + 1; ++k) {
        render_step(&t, shift, k, 5);
        const rp_image_t im = view(img1, W, H);
        const int64_t ut = (int64_t)k * 33000;
        memset(tb.slot_key, 0, sizeof(tb.slot_key));
        for (int what = 0; what < 2 && k >= 2 && k != 5; ++what) {
            tc = ta;
            poisoned += poison_slots(&tc, what);
            uint16_t nc = 0, nb = 0;
            rp_track_info_t ic, ib;
            tb2 = tb;
            assert_int_equal(rp_track_process(&tc, &im, ut, fa, RP_MAX_FEATS_PER_CAM, &nc, &ic),
                             rp_track_process(&tb2, &im, ut, fb, RP_MAX_FEATS_PER_CAM, &nb, &ib));
            assert_int_equal(ic.n_cached, 0);
            assert_info_equal(&ic, &ib, 1);
            assert_int_equal(nc, nb);
            assert_memory_equal(tc.pos_q16, tb2.pos_q16, sizeof(tc.pos_q16[0]) * tc.n);
        }
        uint16_t na = 0, nb = 0;
        rp_track_info_t ia, ib;
        const rp_status_t sa = rp_track_process(&ta, &im, ut, fa, RP_MAX_FEATS_PER_CAM, &na, &ia);
        const rp_status_t sb = rp_track_process(&tb, &im, ut, fb, RP_MAX_FEATS_PER_CAM, &nb, &ib);
        assert_int_equal(sa, sb);
        assert_int_equal(na, nb);
        assert_int_equal(ib.n_cached, 0);
        cached += ia.n_cached;
        assert_info_equal(&ia, &ib, 0);
        assert_tracks_equal(fa, fb, na, &ta, &tb);
        total += na;
    }
    print_message("patch cache: %d of %d tracks started from a cached patch (%u slots), "
                  "results equal; %d stale slots never used\n",
                  cached, total, (unsigned)ta.n_slots, poisoned);
    assert_true(total > 500);
    if (ta.n_slots >= cfg.target) { /* the default RP_TRACK_PATCH_CACHE_BYTES */
        assert_true(cached > total / 2 && poisoned > 500);
    } else if (ta.n_slots == 0) {
        assert_int_equal(cached, 0);
    }
}

/* Feeding a tracker as rp_pipe does for a pair's second camera: adopted features become tracks
 * at their (Q16-rounded) pixels, only the owner camera's ids survive keep_owned, drop_ids takes
 * out the listed ones (rp_pipe: a pair's new features left unmatched), and the next serial says
 * which ids are born later. */
static rp_tracker_t fed;

static void test_feeding_a_tracker(void **s)
{
    (void)s;
    rp_track_cfg_t cfg;
    assert_ok(rp_track_default_cfg(&cfg));
    cfg.cam = 1;
    assert_ok(rp_track_init(&fed, &cfg));
    uint32_t k0 = 99;
    assert_ok(rp_track_next_serial(&fed, &k0));
    assert_int_equal(k0, 0);
    const rp_pyr_t *pyr = NULL;
    assert_ok(rp_track_current_pyr(&fed, &pyr));
    assert_non_null(pyr);
    const rp_feat_t a = {rp_track_id(0, 5), {(rp_real)10.25, (rp_real)20.5}}; /* camera 0's */
    const rp_feat_t b = {rp_track_id(2, 7), {(rp_real)30.0, (rp_real)40.0}};  /* camera 2's */
    rp_feat_t bad = a;
    bad.uv[0] = (rp_real)NAN;
    assert_ok(rp_track_adopt(&fed, &a));
    assert_ok(rp_track_adopt(&fed, &b));
    assert_status(rp_track_adopt(&fed, &bad), RP_E_NAN);
    rp_feat_t out[4];
    uint16_t n = 0;
    assert_ok(rp_track_features(&fed, out, 4, &n));
    assert_int_equal(n, 2);
    assert_int_equal(out[0].id, a.id);
    assert_true(out[0].uv[0] == a.uv[0] && out[0].uv[1] == a.uv[1]); /* exact in Q16 */
    assert_status(rp_track_features(&fed, out, 1, &n), RP_E_FULL);
    assert_int_equal(n, 1);
    uint16_t kept = 0;
    assert_ok(rp_track_keep_owned(&fed, 0, &kept));
    assert_int_equal(kept, 1);
    assert_ok(rp_track_features(&fed, out, 4, &n));
    assert_int_equal(n, 1);
    assert_int_equal(out[0].id, a.id);
    /* drop_ids: the listed ids go, the others keep their order; an id not held changes nothing */
    const rp_feat_t c = {rp_track_id(0, 6), {(rp_real)50.0, (rp_real)60.0}};
    const rp_feat_t d = {rp_track_id(0, 8), {(rp_real)70.0, (rp_real)80.0}};
    assert_ok(rp_track_adopt(&fed, &c));
    assert_ok(rp_track_adopt(&fed, &d));
    const uint32_t gone[2] = {c.id, b.id}; /* b is no longer held */
    uint16_t n_dropped = 99;
    assert_ok(rp_track_drop_ids(&fed, gone, 2, &n_dropped));
    assert_int_equal(n_dropped, 1);
    assert_ok(rp_track_features(&fed, out, 4, &n));
    assert_int_equal(n, 2);
    assert_int_equal(out[0].id, a.id);
    assert_int_equal(out[1].id, d.id);
    assert_true(out[1].uv[0] == d.uv[0] && out[1].uv[1] == d.uv[1]);
    assert_ok(rp_track_drop_ids(&fed, NULL, 0, NULL));
    assert_status(rp_track_drop_ids(&fed, NULL, 1, NULL), RP_E_ARG);
    assert_status(rp_track_drop_ids(NULL, gone, 2, NULL), RP_E_ARG);
    assert_ok(rp_track_drop_ids(&fed, &d.id, 1, NULL));
    /* full: RP_MAX_FEATS_PER_CAM tracks, the next is refused */
    for (uint32_t i = 1; i < RP_MAX_FEATS_PER_CAM; ++i) {
        rp_feat_t f = a;
        f.id = rp_track_id(0, 5 + i);
        assert_ok(rp_track_adopt(&fed, &f));
    }
    assert_status(rp_track_adopt(&fed, &b), RP_E_FULL);
    assert_status(rp_track_keep_owned(&fed, RP_MAX_CAMS, NULL), RP_E_ARG);
    assert_status(rp_track_adopt(NULL, &a), RP_E_ARG);
    assert_status(rp_track_features(&fed, NULL, 1, &n), RP_E_ARG);
    assert_status(rp_track_next_serial(NULL, &k0), RP_E_ARG);
    assert_status(rp_track_current_pyr(&fed, NULL), RP_E_ARG);
}

/* Every sub-pixel weight pair: the Q7 bilinear weights are each in 0..128, within 1/2 of the
 * exact bilinear weight of the rounded fractions, and sum to exactly 128; and an all-255 patch
 * interpolates to exactly 255 x 128 at every pair (no int16 lane overflows: UBSan would stop
 * the test). fx, fy run over every Q16 fraction that rounds to a distinct Q7 value and its
 * neighbours (the rounding edges), all 65536 fx values for the corner rows b = 0, 1, 64, 127,
 * 128. */
static void check_weight_pair(int32_t fx, int32_t fy)
{
    v8_t w[4];
    weights_q7(fx, fy, w);
    int16_t e[4][8];
    int sum = 0;
    const double a = (double)((fx + 256) >> 9), b = (double)((fy + 256) >> 9);
    const double exact[4] = {(128 - a) * (128 - b) / 128, a * (128 - b) / 128,
                             (128 - a) * b / 128, a * b / 128};
    for (int i = 0; i < 4; ++i) {
        v8_st(e[i], w[i]);
        assert_true(e[i][0] >= 0 && e[i][0] <= 128);
        assert_true(fabs((double)e[i][0] - exact[i]) <= 0.5 + 1e-12);
        sum += e[i][0];
    }
    assert_int_equal(sum, 128);
    /* a saturated patch: 2 rows x 9 columns read, 1 row x 8 columns written */
    uint8_t src[2 * 16];
    memset(src, 255, sizeof src);
    int16_t out[8], q3[8];
    interp_q7_q3(src, 16, 1, 8, 8, w, 0, out, q3);
    for (int k = 0; k < 8; ++k) {
        assert_int_equal(out[k], 255 * 128);
        assert_int_equal(q3[k], (255 * 128 + 8) >> 4);
    }
}

static void test_weights_every_subpixel_pair(void **s)
{
    (void)s;
    for (int32_t qa = 0; qa <= 128; ++qa) {
        for (int32_t qb = 0; qb <= 128; ++qb) {
            for (int da = -1; da <= 1; ++da) {
                for (int db = -1; db <= 1; ++db) {
                    const int32_t fx = qa * 512 - 256 + da, fy = qb * 512 - 256 + db;
                    if (fx >= 0 && fx <= 0xffff && fy >= 0 && fy <= 0xffff) {
                        check_weight_pair(fx, fy);
                    }
                    if (qa * 512 <= 0xffff && qb * 512 <= 0xffff) {
                        check_weight_pair(qa * 512, qb * 512);
                    }
                }
            }
        }
    }
    static const int32_t rows[5] = {0, 1, 64, 127, 128};
    for (int r = 0; r < 5; ++r) {
        const int32_t fy = rows[r] * 512 > 0xffff ? 0xffff : rows[r] * 512;
        for (int32_t fx = 0; fx <= 0xffff; ++fx) {
            check_weight_pair(fx, fy);
            check_weight_pair(fy, fx);
        }
    }
}

/* The tracker's state: two pyramids, the patch cache and small row rings, no full-frame
 * response map. */
static void test_state_size(void **s)
{
    (void)s;
    print_message("sizeof(rp_tracker_t) = %zu bytes (pyramids %zu, patch cache %zu)\n",
                  sizeof(rp_tracker_t), 2 * sizeof(rp_pyr_t),
                  sizeof(trk.slot_pix) + sizeof(trk.slot_key));
    assert_true(sizeof(rp_tracker_t) <
                2 * sizeof(rp_pyr_t) + sizeof(trk.slot_pix) + sizeof(trk.slot_key) + 128 * 1024);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pyramid),
        cmocka_unit_test(test_feeding_a_tracker),
        cmocka_unit_test(test_subpixel_shift_small),
        cmocka_unit_test(test_subpixel_shift_medium),
        cmocka_unit_test(test_subpixel_shift_large),
        cmocka_unit_test(test_checkerboard_corners),
        cmocka_unit_test(test_fb_drops_occluded),
        cmocka_unit_test(test_all_lost_redetects_new_ids),
        cmocka_unit_test(test_reset_drops_survivors_of_mass_loss),
        cmocka_unit_test(test_blank_frame_skipped),
        cmocka_unit_test(test_bad_images),
        cmocka_unit_test(test_no_texture_too_few),
        cmocka_unit_test(test_cap_full),
        cmocka_unit_test(test_window_sizes),
        cmocka_unit_test(test_tiny_image),
        cmocka_unit_test(test_topup_refills_emptied_cells),
        cmocka_unit_test(test_topup_waits_for_its_turn),
        cmocka_unit_test(test_dormant_tracks_leave_the_budget),
        cmocka_unit_test(test_weights_every_subpixel_pair),
        cmocka_unit_test(test_state_size),
        cmocka_unit_test(test_vector_equals_scalar),
        cmocka_unit_test(test_patch_cache_changes_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
