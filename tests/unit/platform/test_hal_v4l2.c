/*
 * test_hal_v4l2.c - the v4l2 source's pure parts (rp_hal_v4l2.h): YUYV / UYVY / JPEG to grey,
 * drop counting from sequence numbers, grouping by timestamp; and its errors without a device.
 * The source against a real driver is tests/vm/ (vivid in a VM).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>

#include "rigpose/rp_hal.h"
#include "rigpose/rp_hal_v4l2.h"
#include "rp_test.h"

static uint8_t rnd8(void) { return (uint8_t)rp_test_urand(0.0, 256.0); }

/* Given YUYV rows with padding, the grey image is exactly the Y bytes, for even and odd w. */
static void test_yuyv_uyvy_to_grey(void **state)
{
    (void)state;
    enum { MW = 37, MH = 5, STRIDE = 2 * MW + 6 };
    static uint8_t src[STRIDE * MH], dst[MW * MH];
    for (size_t i = 0; i < sizeof src; i++) {
        src[i] = rnd8();
    }
    const uint16_t widths[2] = {36, 37};
    for (int k = 0; k < 2; k++) {
        const uint16_t w = widths[k];
        memset(dst, 0, sizeof dst);
        assert_int_equal(rp_hal_yuyv_to_grey(src, STRIDE, w, MH, dst, w), RP_HAL_OK);
        for (int v = 0; v < MH; v++) {
            for (int u = 0; u < w; u++) {
                assert_int_equal(dst[v * w + u], src[v * STRIDE + 2 * u]);
            }
        }
        assert_int_equal(rp_hal_uyvy_to_grey(src, STRIDE, w, MH, dst, w), RP_HAL_OK);
        for (int v = 0; v < MH; v++) {
            for (int u = 0; u < w; u++) {
                assert_int_equal(dst[v * w + u], src[v * STRIDE + 2 * u + 1]);
            }
        }
    }
    assert_int_equal(rp_hal_yuyv_to_grey(src, 2 * MW - 1, MW, MH, dst, MW), RP_HAL_E_ARG);
    assert_int_equal(rp_hal_yuyv_to_grey(src, STRIDE, MW, MH, dst, MW - 1), RP_HAL_E_ARG);
    assert_int_equal(rp_hal_yuyv_to_grey(NULL, STRIDE, MW, MH, dst, MW), RP_HAL_E_ARG);
}

/* A JPEG of w x h made with libjpeg (grey, or colour as MJPEG cameras send). */
static size_t make_jpeg(const uint8_t *grey, int w, int h, int colour, uint8_t **out)
{
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr e;
    c.err = jpeg_std_error(&e);
    jpeg_create_compress(&c);
    unsigned long n = 0;
    *out = NULL;
    jpeg_mem_dest(&c, out, &n);
    c.image_width = (JDIMENSION)w;
    c.image_height = (JDIMENSION)h;
    c.input_components = colour ? 3 : 1;
    c.in_color_space = colour ? JCS_RGB : JCS_GRAYSCALE;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 95, TRUE);
    jpeg_start_compress(&c, TRUE);
    static uint8_t row[3 * 256];
    while (c.next_scanline < c.image_height) {
        const uint8_t *g = grey + (size_t)c.next_scanline * (size_t)w;
        for (int u = 0; u < w; u++) {
            for (int k = 0; k < 3; k++) {
                row[3 * u + k] = g[u];
            }
            if (!colour) {
                row[u] = g[u];
            }
        }
        JSAMPROW r = row;
        jpeg_write_scanlines(&c, &r, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    return (size_t)n;
}

/* Given a smooth image as grey and as colour JPEG, decoding gives it back within JPEG error;
 * another size or a cut stream is E_FORMAT. */
static void test_jpeg_to_grey(void **state)
{
    (void)state;
    enum { JW = 64, JH = 48 };
    static uint8_t img[JW * JH], dst[JW * JH];
    for (int v = 0; v < JH; v++) {
        for (int u = 0; u < JW; u++) {
            img[v * JW + u] = (uint8_t)(128.0 + 100.0 * sin(u * 0.2) * cos(v * 0.15));
        }
    }
    for (int colour = 0; colour < 2; colour++) {
        uint8_t *jpg;
        const size_t n = make_jpeg(img, JW, JH, colour, &jpg);
        assert_int_equal(rp_hal_jpeg_to_grey(jpg, n, JW, JH, dst, sizeof dst), RP_HAL_OK);
        int worst = 0;
        for (int i = 0; i < JW * JH; i++) {
            const int d = abs((int)dst[i] - (int)img[i]);
            worst = d > worst ? d : worst;
        }
        printf("jpeg (%s, %zu bytes) to grey: max error %d grey levels\n",
               colour ? "colour" : "grey", n, worst);
        assert_true(worst <= 8);
        assert_int_equal(rp_hal_jpeg_to_grey(jpg, n, JW - 2, JH, dst, sizeof dst),
                         RP_HAL_E_FORMAT);
        assert_int_equal(rp_hal_jpeg_to_grey(jpg, n / 3, JW, JH, dst, sizeof dst),
                         RP_HAL_E_FORMAT); /* cut: libjpeg warns and pads; we refuse */
        memset(jpg + 2, 0x55, 40); /* header destroyed */
        assert_int_equal(rp_hal_jpeg_to_grey(jpg, n, JW, JH, dst, sizeof dst), RP_HAL_E_FORMAT);
        free(jpg);
    }
    const uint8_t junk[16] = {1, 2, 3};
    assert_int_equal(rp_hal_jpeg_to_grey(junk, sizeof junk, 8, 8, dst, sizeof dst),
                     RP_HAL_E_FORMAT);
    assert_int_equal(rp_hal_jpeg_to_grey(junk, sizeof junk, 8, 8, dst, 10), RP_HAL_E_ARG);
}

/* Given sequence numbers with gaps, repeats and a restart, only the gaps count as drops. */
static void test_seq_drops(void **state)
{
    (void)state;
    rp_hal_seq_t s;
    memset(&s, 0, sizeof s);
    const uint32_t seq[10] = {7, 8, 9, 12, 12, 13, 20, 0, 1, 3};
    const uint32_t skipped[10] = {0, 0, 0, 2, 0, 0, 6, 0, 0, 1};
    for (int i = 0; i < 10; i++) {
        assert_int_equal(rp_hal_seq_update(&s, seq[i]), skipped[i]);
    }
    assert_int_equal(s.drops, 9);
    assert_int_equal(s.repeats, 1);
    assert_int_equal(s.last, 3);
}

#define HOLD RP_HAL_V4L2_HOLD

/* Given held frame times, the newest anchor that every needed camera can meet wins, each camera
 * takes its newest frame in the window, and frames no set can use are found. */
static void test_group(void **state)
{
    (void)state;
    int64_t t[4 * HOLD] = {0};
    uint8_t count[4] = {2, 1, 2, 0};
    const uint8_t all[4] = {1, 1, 1, 1}, three[4] = {1, 1, 1, 0}, none[4] = {0, 0, 0, 0};
    int8_t pick[4];
    int64_t anchor;
    t[0 * HOLD + 0] = 1000, t[0 * HOLD + 1] = 34000;  /* cam0: 1.0, 34.0 ms */
    t[1 * HOLD + 0] = 2000;                           /* cam1: 2.0 ms (arrives late) */
    t[2 * HOLD + 0] = 1500, t[2 * HOLD + 1] = 33500;  /* cam2: 1.5, 33.5 ms */
    /* cam3 needed but holds nothing: no set. */
    assert_int_equal(rp_hal_group(t, count, 4, HOLD, all, 5000, pick, &anchor), 0);
    assert_int_equal(pick[0], -1);
    assert_true(anchor == 0);
    /* Without cam3: the set at about 2 ms (cam1 has nothing near 34 ms yet). */
    assert_int_equal(rp_hal_group(t, count, 4, HOLD, three, 5000, pick, &anchor), 3);
    assert_true(anchor == 2000);
    assert_int_equal(pick[0], 0);
    assert_int_equal(pick[1], 0);
    assert_int_equal(pick[2], 0);
    assert_int_equal(pick[3], -1);
    /* cam1's 35 ms frame arrives: the newer set wins. */
    t[1 * HOLD + 1] = 35000;
    count[1] = 2;
    assert_int_equal(rp_hal_group(t, count, 4, HOLD, three, 5000, pick, &anchor), 3);
    assert_true(anchor == 35000);
    assert_int_equal(pick[0], 1);
    assert_int_equal(pick[1], 1);
    assert_int_equal(pick[2], 1);
    /* Nobody needed: the newest frame anchors, the others join within the tolerance. */
    assert_int_equal(rp_hal_group(t, count, 4, HOLD, none, 1000, pick, &anchor), 2);
    assert_true(anchor == 35000);
    assert_int_equal(pick[2], -1);
    /* Hopeless: cam0's 1 ms frame when cam1 holds only frames newer than 1 + 5 ms. */
    t[1 * HOLD + 0] = 30000;
    assert_int_equal(rp_hal_group_hopeless(t, count, 4, HOLD, three, 5000, 0), 1);
    assert_int_equal(rp_hal_group_hopeless(t, count, 4, HOLD, three, 5000, 1), 0);
    assert_int_equal(rp_hal_group_hopeless(t, count, 4, HOLD, none, 5000, 0), 0);
}

/* Simulated cameras at 25 fps with random phase, 1 ms jitter, 2 % of frames lost; camera 3's
 * frames arrive lag_ms late. The grab's policy (hold up to HOLD frames per camera, take the
 * newest set every camera can meet, give back frames no set can use) forms sets within the
 * tolerance at nearly the full rate, also when one camera lags more than a frame period (keeping
 * only each camera's newest frame, a camera that late rarely or never meets the others). */
static int simulate_grouping(int64_t lag_us, int64_t tol_us, int64_t *worst_spread)
{
    enum { NC = 4, PERIOD = 40000 };
    int64_t phase[NC], next[NC], t[NC * HOLD];
    uint8_t count[NC] = {0};
    uint32_t k_frame[NC] = {0};
    const uint8_t need[NC] = {1, 1, 1, 1};
    int8_t pick[NC];
    for (int i = 0; i < NC; i++) {
        phase[i] = (int64_t)rp_test_urand(0.0, PERIOD);
        next[i] = phase[i];
    }
    int sets = 0;
    *worst_spread = 0;
    for (int64_t now = 0; now < 20 * 1000000; now += 1000) {
        for (int i = 0; i < NC; i++) {
            const int64_t arrive = next[i] + (i == 3 ? lag_us : 0);
            if (now < arrive) {
                continue;
            }
            k_frame[i]++;
            if (rp_test_urand(0.0, 1.0) > 0.02) {
                if (count[i] == HOLD) { /* the oldest goes back */
                    memmove(&t[i * HOLD], &t[i * HOLD + 1], (HOLD - 1) * sizeof t[0]);
                    count[i]--;
                }
                t[i * HOLD + count[i]++] = next[i];
            }
            next[i] = phase[i] + (int64_t)k_frame[i] * PERIOD +
                      (int64_t)rp_test_urand(-1000.0, 1000.0);
        }
        int64_t anchor;
        if (rp_hal_group(t, count, NC, HOLD, need, tol_us, pick, &anchor) == NC) {
            int64_t lo = anchor;
            for (int i = 0; i < NC; i++) { /* picked and older frames are used up */
                const int64_t ti = t[i * HOLD + pick[i]];
                lo = ti < lo ? ti : lo;
                const int used = pick[i] + 1;
                memmove(&t[i * HOLD], &t[i * HOLD + used], (size_t)(count[i] - used) * sizeof t[0]);
                count[i] = (uint8_t)(count[i] - used);
            }
            *worst_spread = anchor - lo > *worst_spread ? anchor - lo : *worst_spread;
            sets++;
            continue;
        }
        for (int i = 0; i < NC; i++) {
            const uint8_t h = rp_hal_group_hopeless(t, count, NC, HOLD, need, tol_us, (uint8_t)i);
            memmove(&t[i * HOLD], &t[i * HOLD + h], (size_t)(count[i] - h) * sizeof t[0]);
            count[i] = (uint8_t)(count[i] - h);
        }
    }
    return sets;
}

static void test_group_free_running(void **state)
{
    (void)state;
    const int64_t lags[3] = {0, 50000, 100000};
    for (int k = 0; k < 3; k++) {
        int64_t spread;
        const int sets = simulate_grouping(lags[k], 40000, &spread);
        printf("grouping 4 free-running 25 fps cameras, one %lld ms late: %d sets in 20 s "
               "(500 max), worst spread %.1f ms\n", (long long)(lags[k] / 1000), sets,
               (double)spread / 1000.0);
        assert_true(spread <= 40000);
        assert_true(sets >= (lags[k] <= 50000 ? 440 : 300)); /* 2.5 periods late: fewer */
    }
}

/* sets: latest (free-running cameras at their own rates): three cameras at 30, 25 and 15 fps
 * with random phases, frames arriving as a driver would deliver them (checked every 1 ms), a
 * set whenever camera 0 holds a frame (rp_hal_group_latest), picked frames used up as the
 * source does. Every camera-0 frame makes exactly one set; every frame of the others is
 * delivered exactly once and at most one camera-0 period after it arrived (nothing skipped:
 * the consumer keeps up); with ref -1 every frame of every camera makes a set. */
static void test_group_latest(void **state)
{
    (void)state;
    enum { N = 3 };
    const int64_t period[N] = {33333, 40000, 66667};
    for (int ref = -1; ref <= 0; ref++) {
        int64_t t[N * HOLD] = {0}, next[N];
        uint8_t count[N] = {0};
        long frames[N] = {0}, delivered[N] = {0}, sets = 0;
        int64_t worst_wait = 0;
        for (int i = 0; i < N; i++) {
            next[i] = (int64_t)rp_test_urand(0.0, (double)period[i]);
        }
        for (int64_t now = 0; now < 10 * 1000000; now += 1000) {
            for (int i = 0; i < N; i++) {
                if (now >= next[i]) {
                    assert_true(count[i] < HOLD);
                    t[i * HOLD + count[i]++] = next[i];
                    frames[i]++;
                    next[i] += period[i];
                }
            }
            int8_t pick[N];
            int64_t anchor;
            const uint8_t got = rp_hal_group_latest(t, count, N, HOLD, ref, pick, &anchor);
            if (got == 0) {
                for (int i = 0; i < N; i++) {
                    assert_int_equal(pick[i], -1);
                }
                assert_true(ref < 0 || count[0] == 0);
                continue;
            }
            sets++;
            for (int i = 0; i < N; i++) {
                if (pick[i] < 0) {
                    assert_int_equal(count[i], 0);
                    continue;
                }
                assert_int_equal(pick[i], count[i] - 1); /* its newest */
                assert_int_equal(count[i], 1);           /* nothing skipped */
                const int64_t wait = now - t[i * HOLD + pick[i]];
                worst_wait = wait > worst_wait ? wait : worst_wait;
                delivered[i]++;
                count[i] = 0;
            }
        }
        printf("sets: latest, set camera %d: %ld sets in 10 s; frames delivered %ld/%ld, "
               "%ld/%ld, %ld/%ld; longest wait %.1f ms\n",
               ref, sets, delivered[0], frames[0], delivered[1], frames[1], delivered[2],
               frames[2], (double)worst_wait / 1000.0);
        for (int i = 0; i < N; i++) {
            assert_true(delivered[i] == frames[i] || delivered[i] == frames[i] - 1); /* the last
                                                                              * may wait */
        }
        if (ref == 0) {
            assert_true(sets == delivered[0]);
            assert_true(worst_wait <= period[0]);
        } else {
            assert_true(worst_wait <= 1000); /* a set as soon as any frame is there */
        }
    }
    /* nothing held by the set camera: no set, even with the others' frames */
    int64_t t[2 * HOLD] = {0};
    uint8_t count[2] = {0, 1};
    t[1 * HOLD] = 5000;
    int8_t pick[2];
    int64_t anchor = 7;
    assert_int_equal(rp_hal_group_latest(t, count, 2, HOLD, 0, pick, &anchor), 0);
    assert_true(anchor == 0 && pick[0] == -1 && pick[1] == -1);
    assert_int_equal(rp_hal_group_latest(t, count, 2, HOLD, -1, pick, &anchor), 1);
    assert_true(anchor == 5000 && pick[0] == -1 && pick[1] == 0);
}

/* Without a device: a missing node or a file that is no V4L2 device is E_OPEN naming it; a bad
 * configuration is E_ARG. */
static void test_v4l2_open_errors(void **state)
{
    (void)state;
    rp_hal_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.kind = RP_HAL_SRC_V4L2;
    cfg.n_cams = 1;
    cfg.sync_tol_us = 5000;
    cfg.timeout_ms = 100;
    cfg.retry_ms = 100;
    snprintf(cfg.cam[0].device, sizeof cfg.cam[0].device, "/dev/rigpose-no-such-video");
    rp_hal_source_t *src;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_OPEN);
    printf("v4l2 open: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "/dev/rigpose-no-such-video"));
    snprintf(cfg.cam[0].device, sizeof cfg.cam[0].device, "/dev/null");
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_OPEN);
    printf("v4l2 open: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "not a V4L2 device"));
    cfg.cam[0].device[0] = '\0';
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
    cfg.timeout_ms = 0;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_yuyv_uyvy_to_grey),
        cmocka_unit_test(test_jpeg_to_grey),
        cmocka_unit_test(test_seq_drops),
        cmocka_unit_test(test_group),
        cmocka_unit_test(test_group_free_running),
        cmocka_unit_test(test_group_latest),
        cmocka_unit_test(test_v4l2_open_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
