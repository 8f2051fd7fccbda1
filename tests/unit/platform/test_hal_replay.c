/*
 * test_hal_replay.c - the HAL's dispatch (rp_hal_common.c) and its replay source on folders the
 * test writes: PGM and PNG images, truth, pacing, and each kind of bad input with its error:
 * lines of any length (comments skipped whole, long rows refused naming file:line), FIFOs,
 * devices and folders listed as images refused without blocking, a missing image costing only
 * its camera, pacing at the ends of int64, control characters escaped in messages; each
 * camera's own capture time (utime_us_<column>) and its malformed values.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <png.h>

#include "rigpose/rp_hal.h"
#include "rp_test.h"

#define W 40
#define H 30

static char g_dir[64];

static void write_file(const char *name, const char *text)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", g_dir, name);
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* Pixel of image `id` at (u, v): distinct per image. */
static uint8_t pix(int id, int u, int v) { return (uint8_t)(id * 37 + u * 3 + v * 7); }

static void write_pgm(const char *name, int id, int w, int h)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", g_dir, name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    fprintf(f, "P5\n# written by test_hal_replay\n%d %d\n255\n", w, h);
    for (int v = 0; v < h; v++) {
        for (int u = 0; u < w; u++) {
            fputc(pix(id, u, v), f);
        }
    }
    fclose(f);
}

static void write_png(const char *name, int id)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", g_dir, name);
    static uint8_t img[W * H];
    for (int v = 0; v < H; v++) {
        for (int u = 0; u < W; u++) {
            img[v * W + u] = pix(id, u, v);
        }
    }
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = W;
    im.height = H;
    im.format = PNG_FORMAT_GRAY;
    assert_true(png_image_write_to_file(&im, p, 0, img, W, NULL));
}

static int setup_dir(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/rp_replay_XXXXXX");
    assert_non_null(mkdtemp(g_dir));
    return 0;
}

static int remove_dir(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    assert_int_equal(system(cmd), 0);
    return 0;
}

static rp_hal_cfg_t replay_cfg(uint8_t n)
{
    rp_hal_cfg_t c;
    memset(&c, 0, sizeof c);
    c.kind = RP_HAL_SRC_REPLAY;
    c.n_cams = n;
    c.timeout_ms = 1000;
    snprintf(c.replay_index, sizeof c.replay_index, "%s", g_dir);
    return c;
}

static void check_image(const rp_hal_frame_t *f, int id)
{
    assert_non_null(f->img.data);
    assert_int_equal(f->img.w, W);
    assert_int_equal(f->img.h, H);
    for (int v = 0; v < H; v++) {
        for (int u = 0; u < W; u++) {
            if (f->img.data[v * f->img.stride + u] != pix(id, u, v)) {
                fail_msg("image %d differs at (%d, %d)", id, u, v);
            }
        }
    }
}

/* Given a folder of PGM and PNG images with truth for some rows, every set comes back with its
 * pixels, times, sequence numbers and truth, then RP_HAL_E_END. */
static void test_replay_pgm_png_truth(void **state)
{
    (void)state;
    write_pgm("a0.pgm", 0, W, H);
    write_png("b0.png", 1);
    write_png("a1.png", 2);
    write_pgm("b1.pgm", 3, W, H);
    write_pgm("a2.pgm", 4, W, H);
    write_pgm("b2.pgm", 5, W, H);
    write_file("frames.csv", "utime_us,cam0,cam1\n1000,a0.pgm,b0.png\n\n# comment\n"
                             "34333,a1.png,b1.pgm\r\n67666, a2.pgm , b2.pgm\n");
    write_file("truth.csv", "utime_us,tx,ty,tz,alpha,beta,gamma\n1000,1,2,3,0.1,0.2,0.3\n"
                            "67666,4,5,6,0.4,0.5,0.6\n");
    rp_hal_cfg_t cfg = replay_cfg(2);
    cfg.cam[0].w = W;
    cfg.cam[0].h = H;
    rp_hal_source_t *src;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_payload(src), RP_HAL_PAYLOAD_IMAGES);
    rp_hal_set_t set;
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_STATE);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    const int64_t want_u[3] = {1000, 34333, 67666};
    for (int j = 0; j < 3; j++) {
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        assert_int_equal(set.payload, RP_HAL_PAYLOAD_IMAGES);
        assert_null(set.feats);
        assert_int_equal(set.n_cams, 2);
        assert_int_equal(set.seq, j);
        assert_true(set.utime == want_u[j]);
        for (int i = 0; i < 2; i++) {
            assert_int_equal(set.cam[i].flags, RP_HAL_CAM_OK);
            assert_int_equal(set.cam[i].seq, j);
            assert_true(set.cam[i].utime == want_u[j]);
            check_image(&set.cam[i], 2 * j + i);
        }
        assert_int_equal(set.has_truth, j != 1);
        if (j == 2) {
            assert_near(set.truth[0], 4.0, RP_TOL_TIGHT);
            assert_near(set.truth[5], 0.6, RP_TOL_TIGHT);
        }
    }
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
    assert_non_null(strstr(rp_hal_errmsg(src), "end after 3 sets"));
    assert_int_equal(rp_hal_stop(src), RP_HAL_OK);
    rp_hal_close(src);
}

/* Given a truth.csv with a malformed row, only that truth is lost: every set comes with its
 * images, the set whose truth row is malformed without truth and with a message naming
 * truth.csv's line, the sets after it with theirs. */
static void test_replay_malformed_truth_row_costs_only_the_truth(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    write_file("frames.csv", "utime_us,cam0\n10,x.pgm\n20,x.pgm\n30,x.pgm\n40,x.pgm\n");
    write_file("truth.csv", "utime_us,tx,ty,tz,alpha,beta,gamma\n10,1,0,0,0,0,0\n"
                            "20,2,0,zero,0,0,0\n30,3,0,0,0,0\n40,4,0,0,0,0,0\n");
    rp_hal_cfg_t cfg = replay_cfg(1);
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    static const int want_truth[4] = {1, 0, 0, 1};
    static const char *const want_msg[4] = {NULL, "truth.csv:3: want utime_us and 6 numbers",
                                            "truth.csv:4: want utime_us and 6 numbers", NULL};
    for (int j = 0; j < 4; j++) {
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        assert_int_equal(set.cam[0].flags, RP_HAL_CAM_OK);
        check_image(&set.cam[0], 0);
        assert_int_equal(set.has_truth, want_truth[j]);
        if (want_truth[j]) {
            assert_near(set.truth[0], j + 1.0, RP_TOL_TIGHT);
        }
        if (want_msg[j] != NULL) {
            printf("set %d: %s\n", j, rp_hal_errmsg(src));
            assert_non_null(strstr(rp_hal_errmsg(src), want_msg[j]));
            assert_non_null(strstr(rp_hal_errmsg(src), "no truth"));
        } else {
            assert_string_equal(rp_hal_errmsg(src), "");
        }
    }
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
    assert_int_equal(rp_hal_stop(src), RP_HAL_OK);
    rp_hal_close(src);
}

/* Given frames.csv naming an image that does not exist, the grab fails with E_OPEN naming the
 * file and line, and the next grab goes on with the next row. */
static void test_replay_missing_image(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    write_file("frames.csv", "utime_us,cam0\n10,x.pgm\n20,nothere.pgm\n30,x.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(1);
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_OPEN);
    printf("missing image: %s\n", rp_hal_errmsg(src));
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:3"));
    assert_non_null(strstr(rp_hal_errmsg(src), "nothere.pgm"));
    assert_int_equal(set.cam[0].flags, RP_HAL_CAM_MISSING);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == 30);
    assert_int_equal(set.cam[0].seq, 2);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
    rp_hal_close(src);
}

/* Each malformed frames.csv gives E_FORMAT with the file and line in the message. */
static void test_replay_malformed_csv(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    rp_hal_cfg_t cfg = replay_cfg(2);
    rp_hal_source_t *src;
    rp_hal_set_t set;

    write_file("frames.csv", "time,cam0,cam1\n10,x.pgm,x.pgm\n");
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_FORMAT);
    assert_null(src);
    printf("bad header: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "frames.csv:1"));

    write_file("frames.csv", "utime_us,cam0\n10,x.pgm\n");
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_FORMAT);
    assert_non_null(strstr(rp_hal_errmsg(NULL), "1 image columns, configured 2"));

    rp_hal_cfg_t named = cfg;
    snprintf(named.cam[1].device, sizeof named.cam[1].device, "left");
    write_file("frames.csv", "utime_us,cam0,cam1\n10,x.pgm,x.pgm\n");
    assert_int_equal(rp_hal_open(&src, &named), RP_HAL_E_FORMAT);
    printf("unknown column: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "no column 'left'"));

    const char *bad_rows[3] = {"10,x.pgm\n", "1x0,x.pgm,x.pgm\n", "5,x.pgm,x.pgm,x.pgm\n"};
    for (int k = 0; k < 3; k++) {
        char text[128];
        snprintf(text, sizeof text, "utime_us,cam0,cam1\n1,x.pgm,x.pgm\n%s", bad_rows[k]);
        write_file("frames.csv", text);
        assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
        assert_int_equal(rp_hal_start(src), RP_HAL_OK);
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
        printf("bad row %d: %s\n", k, rp_hal_errmsg(src));
        assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:3"));
        rp_hal_close(src);
    }

    write_file("frames.csv", "utime_us,cam0,cam1\n10,x.pgm,x.pgm\n10,x.pgm,x.pgm\n");
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    assert_non_null(strstr(rp_hal_errmsg(src), "not after"));
    rp_hal_close(src);

    remove("frames.csv");
    char p[128];
    snprintf(p, sizeof p, "%s/frames.csv", g_dir);
    remove(p);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_OPEN);
    assert_non_null(strstr(rp_hal_errmsg(NULL), "frames.csv"));
}

/* Malformed images (truncated PGM, 16-bit PGM, a text file, a wrong size, a cut PNG) give
 * E_FORMAT. */
static void test_replay_malformed_images(void **state)
{
    (void)state;
    write_pgm("ok.pgm", 0, W, H);
    write_pgm("small.pgm", 0, W / 2, H);
    write_file("short.pgm", "P5\n40 30\n255\nabc");
    write_file("deep.pgm", "P5\n40 30\n65535\n");
    write_file("text.png", "hello");
    write_file("cut.png", "\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR");
    write_file("frames.csv", "utime_us,cam0\n1,short.pgm\n2,deep.pgm\n3,text.png\n4,small.pgm\n"
                             "5,cut.png\n6,ok.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(1);
    cfg.cam[0].w = W;
    cfg.cam[0].h = H;
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    for (int k = 0; k < 5; k++) {
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
        printf("bad image %d: %s\n", k, rp_hal_errmsg(src));
    }
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    rp_hal_close(src);
}

/* replay_index naming a file reads that file, whatever its name; a renamed or missing index is
 * named in the error (frames.csv beside it is not read instead). */
static void test_replay_index_file_by_name(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    write_file("frames.csv", "utime_us,cam0\n10,x.pgm\n");
    write_file("index.csv", "utime_us,cam0\n20,x.pgm\nbad\n");
    rp_hal_cfg_t cfg = replay_cfg(1);
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s/index.csv", g_dir);
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == 20);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    assert_non_null(strstr(rp_hal_errmsg(src), "index.csv:3: want utime_us"));
    rp_hal_close(src);
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s/renamed.csv", g_dir);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_OPEN);
    printf("renamed index: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "renamed.csv: No such file or directory"));
}

/* Given cameras naming their columns, each reads its own column whatever the order; columns no
 * camera names are skipped. */
static void test_replay_named_columns(void **state)
{
    (void)state;
    write_pgm("l.pgm", 1, W, H);
    write_pgm("r.pgm", 2, W, H);
    write_pgm("d.pgm", 3, W, H);
    write_file("frames.csv", "utime_us,depth,right,left\n5,d.pgm,r.pgm,l.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(2);
    snprintf(cfg.cam[0].device, sizeof cfg.cam[0].device, "left");
    snprintf(cfg.cam[1].device, sizeof cfg.cam[1].device, "right");
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    check_image(&set.cam[0], 1);
    check_image(&set.cam[1], 2);
    rp_hal_close(src);
}

/* realtime live: the recorded times are the HAL clock's. A row due more than timeout_ms ago
 * is skipped (its image not even read: a missing file does not fail), a row due soon comes at
 * its time, not before; seq counts the rows delivered. */
static void test_replay_live(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    const int64_t now = rp_hal_now_us();
    char csv[512];
    snprintf(csv, sizeof csv, "utime_us,cam0\n%lld,gone.pgm\n%lld,x.pgm\n%lld,x.pgm\n",
             (long long)(now - 500000), (long long)(now + 60000), (long long)(now + 100000));
    write_file("frames.csv", csv);
    rp_hal_cfg_t cfg = replay_cfg(1);
    cfg.realtime = RP_HAL_PACE_LIVE;
    cfg.timeout_ms = 200;
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s/frames.csv", g_dir);
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    const int64_t t1 = rp_hal_now_us();
    printf("live replay: the set due at +60 ms came at +%.1f ms\n", (double)(t1 - now) / 1000.0);
    assert_true(set.utime == now + 60000 && set.seq == 0);
    assert_true(t1 >= now + 60000 && t1 < now + 300000);
    check_image(&set.cam[0], 0);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == now + 100000 && set.seq == 1);
    assert_true(rp_hal_now_us() >= now + 100000);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
    rp_hal_close(src);
}

/* With realtime, sets come at their recorded spacing (40 ms apart here). */
static void test_replay_realtime(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    write_file("frames.csv", "utime_us,cam0\n500000,x.pgm\n540000,x.pgm\n580000,x.pgm\n"
                             "830000,x.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(1);
    cfg.realtime = 1;
    cfg.timeout_ms = 100;
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s/frames.csv", g_dir);
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    const int64_t t0 = rp_hal_now_us();
    for (int j = 0; j < 3; j++) {
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    }
    const int64_t dt = rp_hal_now_us() - t0;
    printf("realtime replay: 3 sets 40 ms apart took %.1f ms\n", (double)dt / 1000.0);
    assert_true(dt >= 79000 && dt < 400000);
    /* A 250 ms gap with timeout_ms 100: E_TIMEOUT after 100 ms, then the set on time. */
    const int64_t t1 = rp_hal_now_us();
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_TIMEOUT);
    const int64_t waited = rp_hal_now_us() - t1;
    assert_int_equal(set.cam[0].flags, RP_HAL_CAM_MISSING);
    while (rp_hal_grab(src, &set) == RP_HAL_E_TIMEOUT) {
    }
    const int64_t gap = rp_hal_now_us() - t1;
    printf("realtime replay: 250 ms gap with timeout_ms 100: first grab %.1f ms, set after "
           "%.1f ms\n", (double)waited / 1000.0, (double)gap / 1000.0);
    assert_true(waited >= 100000 && waited < 200000);
    assert_true(set.utime == 830000 && set.seq == 3);
    /* pacing is relative to the first set's grab (just after t0), so the last set comes no
     * earlier than 330 ms after t0 however late the third grab returned on a loaded machine;
     * gap only bounds it from above */
    assert_true(rp_hal_now_us() - t0 >= 330000);
    assert_true(gap < 500000);
    rp_hal_close(src);
}

/* Every byte of the message is printable ASCII (control characters escaped). */
static void assert_printable(const char *msg)
{
    for (const unsigned char *p = (const unsigned char *)msg; *p != '\0'; p++) {
        if (*p < 0x20 || *p >= 0x7f) {
            fail_msg("byte 0x%02x in message: %s", *p, msg);
        }
    }
}

/* Comments are skipped whole however long (a 100 KB one, and one whose tail beyond 1,599
 * characters is a valid row; rows may have 1,791); a data row longer than the limit, or with a NUL byte, is refused
 * naming file:line, and the next grab goes on with the next row. */
static void test_replay_lines_of_any_length(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    char p[256];
    snprintf(p, sizeof p, "%s/frames.csv", g_dir);
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fputs("utime_us,cam0\n10,x.pgm\n#", f);                 /* lines 1, 2 */
    for (int i = 0; i < 100000; i++) {                       /* line 3: 100 KB comment */
        fputc('c', f);
    }
    fputs("\n20,x.pgm\n#", f);                               /* line 4 */
    for (int i = 0; i < 1598; i++) {                         /* line 5: tail is a row */
        fputc('c', f);
    }
    fputs("25,x.pgm\n30,x.pgm\n40,", f);                     /* line 6 */
    for (int i = 0; i < 2000; i++) {                         /* line 7: too long a row */
        fputc('a', f);
    }
    fputs("\n50,x.pgm\n60,x.p", f);                          /* line 8 */
    fputc('\0', f);                                          /* line 9: a NUL byte */
    fputs("gm\n70,x.pgm", f);                                /* line 10, no newline */
    fclose(f);
    rp_hal_cfg_t cfg = replay_cfg(1);
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    const int64_t want[3] = {10, 20, 30};
    for (int j = 0; j < 3; j++) {
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        assert_true(set.utime == want[j]);
        assert_string_equal(rp_hal_errmsg(src), "");
    }
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    printf("long row: %s\n", rp_hal_errmsg(src));
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:7: line longer than 1791 characters"));
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == 50);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    printf("NUL byte: %s\n", rp_hal_errmsg(src));
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:9: NUL byte"));
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == 70);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
    assert_non_null(strstr(rp_hal_errmsg(src), "end after 5 sets"));
    rp_hal_close(src);

    /* A header over the limit is refused at open, naming file:1. */
    f = fopen(p, "w");
    assert_non_null(f);
    fputs("utime_us", f);
    for (int i = 0; i < 1000; i++) {
        fputs(",c", f);
    }
    fputs("\n", f);
    fclose(f);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_FORMAT);
    printf("long header: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "frames.csv:1: line longer than"));
}

/* A FIFO, a device and a folder listed as images are refused without opening them for reading
 * (nothing blocks): their camera is MISSING in that set, the message names line, camera, file
 * and why, and the other camera's image comes. frames.csv and truth.csv that are not regular
 * files are refused at open. */
static void test_replay_only_regular_files(void **state)
{
    (void)state;
    alarm(20); /* a blocking open would hang: SIGALRM fails the test instead */
    write_pgm("x.pgm", 0, W, H);
    char p[256];
    snprintf(p, sizeof p, "%s/fifo.pgm", g_dir);
    assert_int_equal(mkfifo(p, 0600), 0);
    snprintf(p, sizeof p, "%s/dir.pgm", g_dir);
    assert_int_equal(mkdir(p, 0700), 0);
    write_file("frames.csv", "utime_us,cam0,cam1\n10,x.pgm,fifo.pgm\n20,/dev/zero,x.pgm\n"
                             "30,x.pgm,dir.pgm\n40,fifo.pgm,dir.pgm\n50,x.pgm,x.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(2);
    cfg.partial_sets = 1;
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    const struct {
        int bad;
        const char *what;
    } rows[3] = {{1, "frames.csv:2: camera 1: "}, {0, "frames.csv:3: camera 0: /dev/zero: is a device"},
                 {1, "frames.csv:4: camera 1: "}};
    for (int j = 0; j < 3; j++) {
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        printf("row %d: %s\n", j + 2, rp_hal_errmsg(src));
        assert_non_null(strstr(rp_hal_errmsg(src), rows[j].what));
        assert_int_equal(set.cam[rows[j].bad].flags, RP_HAL_CAM_MISSING);
        assert_null(set.cam[rows[j].bad].img.data);
        assert_int_equal(set.cam[1 - rows[j].bad].flags, RP_HAL_CAM_OK);
        check_image(&set.cam[1 - rows[j].bad], 0);
    }
    assert_non_null(strstr(rp_hal_errmsg(src), "dir.pgm: is a directory"));
    /* Neither image readable: the row fails, naming the first camera's file. */
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_OPEN);
    printf("row 5: %s\n", rp_hal_errmsg(src));
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:5: camera 0: "));
    assert_non_null(strstr(rp_hal_errmsg(src), "fifo.pgm: is a FIFO, not a regular file"));
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_string_equal(rp_hal_errmsg(src), "");
    assert_int_equal(set.cam[0].flags | set.cam[1].flags, RP_HAL_CAM_OK);
    rp_hal_close(src);

    /* frames.csv a folder, truth.csv a FIFO. */
    snprintf(p, sizeof p, "%s/sub", g_dir);
    assert_int_equal(mkdir(p, 0700), 0);
    snprintf(p, sizeof p, "%s/sub/frames.csv", g_dir);
    assert_int_equal(mkdir(p, 0700), 0);
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s/sub", g_dir);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_OPEN);
    printf("frames.csv a folder: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "sub/frames.csv: is a directory"));
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s/sub/frames.csv", g_dir);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_OPEN);
    printf("replay_index a folder named frames.csv: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "sub/frames.csv/frames.csv: No such file or "
                                                "directory (replay_index "));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "sub/frames.csv is a folder: its frames.csv"));
    snprintf(p, sizeof p, "%s/truth.csv", g_dir);
    assert_int_equal(mkfifo(p, 0600), 0);
    cfg = replay_cfg(2);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_OPEN);
    printf("truth.csv a FIFO: %s\n", rp_hal_errmsg(NULL));
    assert_non_null(strstr(rp_hal_errmsg(NULL), "truth.csv: is a FIFO"));
    alarm(0);
}

/* Pacing across the whole allowed range of times (+-2^61 us): no overflow (UBSan would stop
 * the test), the far set is a timeout after timeout_ms, never a sleep of millennia; times
 * beyond the range (differences could overflow in the estimators) are refused. */
static void test_replay_pacing_saturates(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    write_file("frames.csv", "utime_us,cam0\n-9223372036854775807,x.pgm\n"
                             "-2305843009213693952,x.pgm\n2305843009213693952,x.pgm\n"
                             "9223372036854775807,x.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(1);
    cfg.realtime = 1;
    cfg.timeout_ms = 50;
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    printf("too early: %s\n", rp_hal_errmsg(src));
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:2: utime_us -9223372036854775807 outside"));
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == -((int64_t)1 << 61));
    const int64_t t0 = rp_hal_now_us();
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_TIMEOUT);
    const int64_t dt = rp_hal_now_us() - t0;
    printf("far set: %s (after %.1f ms)\n", rp_hal_errmsg(src), (double)dt / 1000.0);
    assert_true(dt >= 50000 && dt < 1000000);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_TIMEOUT); /* still due in millennia */
    rp_hal_close(src);
    cfg.realtime = 0;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == ((int64_t)1 << 61));
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:5: utime_us 9223372036854775807"));
    rp_hal_close(src);
}

/* With partial_sets a missing image costs only its camera (without, the row fails); control
 * characters in a path come out escaped. */
static void test_replay_missing_image_one_camera(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    write_file("frames.csv", "utime_us,cam0,cam1\n10,x.pgm,x.pgm\n20,x.pgm,gone\x1b[31m\t.pgm\n"
                             "30,x.pgm,x.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(2);
    cfg.partial_sets = 1;
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    printf("missing image of camera 1: %s\n", rp_hal_errmsg(src));
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:3: camera 1: "));
    assert_non_null(strstr(rp_hal_errmsg(src), "gone\\x1b[31m\\x09.pgm: No such file"));
    assert_printable(rp_hal_errmsg(src));
    assert_true(set.utime == 20 && set.seq == 1);
    assert_int_equal(set.cam[0].flags, RP_HAL_CAM_OK);
    check_image(&set.cam[0], 0);
    assert_int_equal(set.cam[1].flags, RP_HAL_CAM_MISSING);
    assert_null(set.cam[1].img.data);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_string_equal(rp_hal_errmsg(src), "");
    assert_int_equal(set.cam[1].flags, RP_HAL_CAM_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
    rp_hal_close(src);
    /* Without partial_sets (a recorder wants whole sets) the row fails as a whole. */
    cfg.partial_sets = 0;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_OPEN);
    assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:3: camera 1: "));
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    assert_true(set.utime == 30);
    rp_hal_close(src);
}

/* Per-camera capture times: utime_us_<column> columns, anywhere after utime_us, give each
 * camera's utime; a column without one (depth) is at the set's utime_us, which stays set.utime.
 * Differences of -2^31 and 2^31 - 1 us are taken. With partial_sets a camera whose image cannot
 * be read is MISSING (no image) whatever its time. */
static void test_replay_camera_times(void **state)
{
    (void)state;
    write_pgm("l.pgm", 1, W, H);
    write_pgm("r.pgm", 2, W, H);
    write_pgm("d.pgm", 3, W, H);
    write_file("frames.csv", "utime_us,left,utime_us_right,right,utime_us_left,depth\n"
                             "1000,l.pgm,1012,r.pgm,990,d.pgm\n"
                             "# a camera 25 ms early, another 40 ms late\n"
                             "34333, l.pgm , 74333 ,r.pgm, 9333 ,d.pgm\r\n"
                             "67666,l.pgm,2147551313,r.pgm,-2147415982,d.pgm\n"
                             "100000,l.pgm,100001,gone.pgm,99999,d.pgm\n");
    rp_hal_cfg_t cfg = replay_cfg(3);
    cfg.partial_sets = 1;
    snprintf(cfg.cam[0].device, sizeof cfg.cam[0].device, "left");
    snprintf(cfg.cam[1].device, sizeof cfg.cam[1].device, "right");
    snprintf(cfg.cam[2].device, sizeof cfg.cam[2].device, "depth");
    rp_hal_source_t *src;
    rp_hal_set_t set;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    static const int64_t want[4][4] = {{1000, 990, 1012, 1000},
                                       {34333, 9333, 74333, 34333},
                                       {67666, 67666 - 2147483648LL, 67666 + 2147483647LL, 67666},
                                       {100000, 99999, 0, 100000}};
    for (int j = 0; j < 4; j++) {
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        assert_true(set.utime == want[j][0]);
        for (int i = 0; i < 3; i++) {
            if (set.cam[i].utime != want[j][1 + i]) {
                fail_msg("row %d camera %d: utime %lld, want %lld", j, i,
                         (long long)set.cam[i].utime, (long long)want[j][1 + i]);
            }
            if (j < 3 || i != 1) {
                check_image(&set.cam[i], i + 1);
            }
        }
    }
    assert_int_equal(set.cam[1].flags, RP_HAL_CAM_MISSING);
    assert_null(set.cam[1].img.data);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
    rp_hal_close(src);

    /* by position: the first image column is camera 0, whatever the time columns between */
    write_file("frames.csv", "utime_us,utime_us_cam1,cam0,cam1\n10,13,l.pgm,r.pgm\n");
    rp_hal_cfg_t pos = replay_cfg(2);
    assert_int_equal(rp_hal_open(&src, &pos), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
    check_image(&set.cam[0], 1);
    check_image(&set.cam[1], 2);
    assert_true(set.utime == 10 && set.cam[0].utime == 10 && set.cam[1].utime == 13);
    rp_hal_close(src);
}

/* Malformed per-camera times: a header whose time column names no image column, or one
 * twice, or with only time columns, or more than RP_MAX_CAMS image columns, is refused at open
 * (file:1); a row whose time is not an integer (text, empty, a fraction, an exponent, beyond
 * int64), beyond +-2^61 us, or more than an int32_t of microseconds from utime_us, is refused
 * naming file:line and the column, and the next grab goes on with the next row (the refused
 * row's utime_us is not taken: the next row may repeat it). */
static void test_replay_camera_times_malformed(void **state)
{
    (void)state;
    write_pgm("x.pgm", 0, W, H);
    rp_hal_cfg_t cfg = replay_cfg(2);
    rp_hal_source_t *src;
    rp_hal_set_t set;
    static const char *const bad_headers[5][2] = {
        {"utime_us,cam0,cam1,utime_us_cam2\n", "time column 'utime_us_cam2' names no image "
                                               "column 'cam2'"},
        {"utime_us,cam0,utime_us_cam0,cam1,utime_us_cam0\n", "two time columns 'utime_us_cam0'"},
        {"utime_us,utime_us_cam0\n", "header must be utime_us,cam0,cam1"},
        {"utime_us,a,b,c,d,e,f,g\n", "more than 6 image columns"},
        {"utime_us,a,b,c,d,e,f,utime_us_a,utime_us_b,utime_us_c,utime_us_d,utime_us_e,"
         "utime_us_f,utime_us_g\n", "more than 6 image columns and their times"}};
    for (int k = 0; k < 5; k++) {
        write_file("frames.csv", bad_headers[k][0]);
        assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_FORMAT);
        printf("bad header %d: %s\n", k, rp_hal_errmsg(NULL));
        assert_non_null(strstr(rp_hal_errmsg(NULL), "frames.csv:1: "));
        assert_non_null(strstr(rp_hal_errmsg(NULL), bad_headers[k][1]));
    }

    static const char *const bad_times[9][2] = {
        {"abc", "utime_us_cam1 'abc' is not a time"},
        {"", "utime_us_cam1 '' is not a time"},
        {"20.5", "utime_us_cam1 '20.5' is not a time"},
        {"2e3", "utime_us_cam1 '2e3' is not a time"},
        {"99999999999999999999", "is not a time"},
        {"2305843009213693953", "utime_us_cam1 2305843009213693953 more than 2^31 - 1 us"},
        {"2147483668",
         "utime_us_cam1 2147483668 more than 2^31 - 1 us (35 min) from utime_us 20"},
        {"-2147483629", "utime_us_cam1 -2147483629 more than 2^31 - 1 us"},
        {"\x1b[31m", "utime_us_cam1 '\\x1b[31m' is not a time"}};
    for (int k = 0; k < 9; k++) {
        char text[256];
        snprintf(text, sizeof text,
                 "utime_us,cam0,cam1,utime_us_cam1\n10,x.pgm,x.pgm,11\n20,x.pgm,x.pgm,%s\n"
                 "20,x.pgm,x.pgm,19\n",
                 bad_times[k][0]);
        write_file("frames.csv", text);
        assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
        assert_int_equal(rp_hal_start(src), RP_HAL_OK);
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        assert_true(set.cam[1].utime == 11);
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
        printf("bad time %d: %s\n", k, rp_hal_errmsg(src));
        assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv:3: "));
        assert_non_null(strstr(rp_hal_errmsg(src), bad_times[k][1]));
        assert_printable(rp_hal_errmsg(src));
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_OK);
        assert_true(set.utime == 20 && set.cam[0].utime == 20 && set.cam[1].utime == 19);
        assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_END);
        rp_hal_close(src);
    }

    /* a row short of its time column */
    write_file("frames.csv", "utime_us,cam0,cam1,utime_us_cam1\n10,x.pgm,x.pgm\n");
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &set), RP_HAL_E_FORMAT);
    printf("short row: %s\n", rp_hal_errmsg(src));
    assert_non_null(strstr(rp_hal_errmsg(src),
                           "frames.csv:2: want utime_us and 2 image paths and their times"));
    rp_hal_close(src);
}

/* 2,000 corrupted copies of a small frames.csv (1..6 bytes each replaced by a random byte, a
 * comma, a newline, '#', NUL, a path separator...; a fixed seed), each opened and grabbed to its
 * end: every failure has a printable message naming frames.csv, nothing crashes (ASan, UBSan)
 * or blocks, and at most one grab per line of the file. */
static void test_replay_corrupted_index_never_crashes(void **state)
{
    (void)state;
    alarm(120);
    write_pgm("a.pgm", 0, W, H);
    write_png("b.png", 1);
    static const char orig[] = "utime_us,cam0,cam1\n10,a.pgm,b.png\n# note\n20,b.png,a.pgm\n"
                               "\n30,a.pgm,a.pgm\n40,/dev/zero,b.png\n";
    static const char special[] = ",\n#\r /.\x1b\xff-9";
    const size_t n = sizeof orig - 1;
    char text[sizeof orig];
    uint32_t rng = 777u;
    unsigned sets = 0, failures = 0;
    rp_hal_cfg_t cfg = replay_cfg(2);
    cfg.partial_sets = 1;
    char p[256];
    snprintf(p, sizeof p, "%s/frames.csv", g_dir);
    for (int trial = 0; trial < 2000; ++trial) {
        memcpy(text, orig, n);
        rng = rng * 1664525u + 1013904223u;
        const unsigned edits = 1u + (rng >> 16) % 6u;
        for (unsigned e = 0; e < edits; ++e) {
            rng = rng * 1664525u + 1013904223u;
            const size_t at = (size_t)(rng >> 8) % n;
            rng = rng * 1664525u + 1013904223u;
            const unsigned pick = (rng >> 24) % 3u;
            text[at] = pick == 0 ? (char)(rng >> 16)
                       : pick == 1 ? '\0'
                                   : special[(rng >> 8) % (sizeof special - 1)];
        }
        FILE *f = fopen(p, "wb");
        assert_non_null(f);
        assert_int_equal(fwrite(text, 1, n, f), n);
        fclose(f);
        rp_hal_source_t *src;
        rp_hal_set_t set;
        const rp_hal_status_t so = rp_hal_open(&src, &cfg);
        if (so != RP_HAL_OK) {
            assert_non_null(strstr(rp_hal_errmsg(NULL), "frames.csv"));
            assert_printable(rp_hal_errmsg(NULL));
            failures++;
            continue;
        }
        assert_int_equal(rp_hal_start(src), RP_HAL_OK);
        int grabs = 0;
        rp_hal_status_t st;
        while ((st = rp_hal_grab(src, &set)) != RP_HAL_E_END) {
            assert_true(++grabs <= 12);
            assert_printable(rp_hal_errmsg(src));
            if (st == RP_HAL_OK) {
                sets++;
            } else {
                failures++;
                assert_non_null(strstr(rp_hal_errmsg(src), "frames.csv"));
            }
        }
        rp_hal_close(src);
    }
    alarm(0);
    printf("2000 corrupted frames.csv: %u sets delivered, %u failures, each with its message\n",
           sets, failures);
    assert_true(sets > 1000 && failures > 1000);
}

/* The dispatch: bad arguments, one source at a time, status strings. */
static void test_hal_dispatch(void **state)
{
    (void)state;
    rp_hal_source_t *src = NULL;
    rp_hal_cfg_t cfg = replay_cfg(0);
    assert_int_equal(rp_hal_open(NULL, &cfg), RP_HAL_E_ARG);
    assert_int_equal(rp_hal_open(&src, NULL), RP_HAL_E_ARG);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_hal_errmsg(NULL), "n_cams"));
    cfg.n_cams = 1;
    cfg.kind = (rp_hal_kind_t)7;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
    write_pgm("x.pgm", 0, W, H);
    write_file("frames.csv", "utime_us,cam0\n1,x.pgm\n");
    cfg = replay_cfg(1);
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    rp_hal_source_t *second;
    assert_int_equal(rp_hal_open(&second, &cfg), RP_HAL_E_STATE);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_E_STATE);
    assert_int_equal(rp_hal_grab(src, NULL), RP_HAL_E_ARG);
    rp_hal_close(src);
    rp_hal_close(NULL);
    assert_int_equal(rp_hal_start(NULL), RP_HAL_E_ARG);
    for (int s = RP_HAL_OK; s <= RP_HAL_E_STATE; s++) {
        assert_true(strlen(rp_hal_status_str((rp_hal_status_t)s)) > 1);
    }
    const int64_t a = rp_hal_now_us();
    rp_hal_sleep_us(2000);
    assert_true(rp_hal_now_us() - a >= 2000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_replay_pgm_png_truth, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_malformed_truth_row_costs_only_the_truth,
                                        setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_missing_image, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_malformed_csv, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_malformed_images, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_named_columns, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_camera_times, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_camera_times_malformed, setup_dir,
                                        remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_index_file_by_name, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_realtime, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_live, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_lines_of_any_length, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_only_regular_files, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_pacing_saturates, setup_dir, remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_missing_image_one_camera, setup_dir,
                                        remove_dir),
        cmocka_unit_test_setup_teardown(test_replay_corrupted_index_never_crashes, setup_dir,
                                        remove_dir),
        cmocka_unit_test_setup_teardown(test_hal_dispatch, setup_dir, remove_dir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
