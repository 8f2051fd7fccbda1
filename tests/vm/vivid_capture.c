/*
 * vivid_capture.c - runs inside the test VM (tests/vm/vivid_test.sh), linked static: captures
 * frame sets from several V4L2 devices at once through the HAL's v4l2 source and checks them.
 *
 *   vivid_capture [--sets N] [--size WxH] [--fps F] [--tol-ms T] DEVICE...
 *
 * Checks every set: all cameras present at the asked size, their kernel timestamps within the
 * tolerance of each other and near CLOCK_MONOTONIC now (at most 1 s old, at most two frame
 * periods ahead: vivid stamps the end of the frame period), set and camera times strictly
 * increasing, images not blank. Prints one `key=value` line per figure, then `PASS` or
 * `FAIL: reason`; exit 0 only on PASS.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/resource.h>

#include "rigpose/rp_hal.h"
#include "rigpose/rp_hal_v4l2.h"

static int fail(const char *what, unsigned set)
{
    printf("FAIL: %s (set %u)\n", what, set);
    return 1;
}

int main(int argc, char **argv)
{
    unsigned n_sets = 50, w = 640, h = 480, fps = 25, tol_ms = 40;
    rp_hal_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.kind = RP_HAL_SRC_V4L2;
    for (int a = 1; a < argc; a++) {
        if (strcmp(argv[a], "--sets") == 0 && a + 1 < argc) {
            n_sets = (unsigned)atoi(argv[++a]);
        } else if (strcmp(argv[a], "--size") == 0 && a + 1 < argc) {
            if (sscanf(argv[++a], "%ux%u", &w, &h) != 2) {
                return fail("bad --size", 0);
            }
        } else if (strcmp(argv[a], "--fps") == 0 && a + 1 < argc) {
            fps = (unsigned)atoi(argv[++a]);
        } else if (strcmp(argv[a], "--tol-ms") == 0 && a + 1 < argc) {
            tol_ms = (unsigned)atoi(argv[++a]);
        } else if (argv[a][0] != '-' && cfg.n_cams < RP_MAX_CAMS) {
            snprintf(cfg.cam[cfg.n_cams].device, RP_HAL_PATH_MAX, "%s", argv[a]);
            cfg.n_cams++;
        } else {
            printf("usage: vivid_capture [--sets N] [--size WxH] [--fps F] [--tol-ms T] DEV...\n");
            return 2;
        }
    }
    const uint8_t n = cfg.n_cams;
    for (uint8_t i = 0; i < n; i++) {
        cfg.cam[i].w = (uint16_t)w;
        cfg.cam[i].h = (uint16_t)h;
        cfg.cam[i].fps = (uint16_t)fps;
    }
    cfg.sync_tol_us = (int64_t)tol_ms * 1000;
    cfg.timeout_ms = 2000;
    cfg.retry_ms = 500;
    rp_hal_source_t *src;
    rp_hal_status_t st = rp_hal_open(&src, &cfg);
    if (st != RP_HAL_OK) {
        printf("open: %s: %s\n", rp_hal_status_str(st), rp_hal_errmsg(NULL));
        return fail("rp_hal_open", 0);
    }
    if ((st = rp_hal_start(src)) != RP_HAL_OK) {
        printf("start: %s: %s\n", rp_hal_status_str(st), rp_hal_errmsg(src));
        return fail("rp_hal_start", 0);
    }
    printf("cameras=%u size=%ux%u fps=%u tol_ms=%u sets=%u\n", (unsigned)n, w, h, fps, tol_ms,
           n_sets);
    for (uint8_t i = 0; i < n; i++) {
        char d[160];
        if (rp_hal_v4l2_describe(i, d, sizeof d) == RP_HAL_OK) {
            printf("%s\n", d);
        }
    }
    int64_t last_set = 0, last_cam[RP_MAX_CAMS] = {0}, first_set = 0;
    int64_t worst_spread = 0, worst_age = 0, most_ahead = 0;
    unsigned timeouts = 0, got = 0, dropped_sets = 0;
    rp_hal_set_t set;
    int rc = 0;
    while (got < n_sets && rc == 0) {
        st = rp_hal_grab(src, &set);
        const int64_t now = rp_hal_now_us();
        if (st == RP_HAL_E_TIMEOUT) {
            printf("timeout: %s\n", rp_hal_errmsg(src));
            if (++timeouts > 2) {
                rc = fail("more than 2 grab timeouts", got);
            }
            continue;
        }
        if (st != RP_HAL_OK) {
            printf("grab: %s: %s\n", rp_hal_status_str(st), rp_hal_errmsg(src));
            rc = fail("rp_hal_grab", got);
            break;
        }
        if (set.n_cams != n || set.seq != got) {
            rc = fail("set size or sequence", got);
            break;
        }
        if (got > 0 && set.utime <= last_set) {
            rc = fail("set time not increasing", got);
            break;
        }
        int64_t lo = set.cam[0].utime, hi = set.cam[0].utime;
        for (uint8_t i = 0; i < n && rc == 0; i++) {
            const rp_hal_frame_t *f = &set.cam[i];
            if (f->flags & (RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE)) {
                rc = fail("camera missing from a set", got);
                break;
            }
            if (f->img.data == NULL || f->img.w != w || f->img.h != h || f->img.stride < w) {
                rc = fail("image size", got);
                break;
            }
            if (got > 0 && f->utime <= last_cam[i]) {
                rc = fail("camera time not increasing", got);
                break;
            }
            last_cam[i] = f->utime;
            lo = f->utime < lo ? f->utime : lo;
            hi = f->utime > hi ? f->utime : hi;
            uint8_t mn = 255, mx = 0;
            for (uint32_t k = 0; k < (uint32_t)w * h; k += 97) {
                const uint8_t p = f->img.data[(k / w) * f->img.stride + k % w];
                mn = p < mn ? p : mn;
                mx = p > mx ? p : mx;
            }
            if (mx - mn < 16) {
                rc = fail("blank image", got);
                break;
            }
            dropped_sets += (f->flags & RP_HAL_CAM_DROPPED) ? 1u : 0u;
        }
        if (rc != 0) {
            break;
        }
        if (hi - lo > cfg.sync_tol_us) {
            rc = fail("cameras of a set further apart than the tolerance", got);
            break;
        }
        /* vivid stamps the ideal end of each frame period, which can be up to one period after
         * the frame reached us: allow that much "future". */
        const int64_t age = now - set.utime;
        const int64_t ahead_max = 2 * 1000000 / (int64_t)(fps > 0 ? fps : 1);
        if (age < -ahead_max || age > 1000000) {
            printf("set time %lld us, now %lld us\n", (long long)set.utime, (long long)now);
            rc = fail("kernel timestamp not on CLOCK_MONOTONIC near now", got);
            break;
        }
        worst_spread = hi - lo > worst_spread ? hi - lo : worst_spread;
        worst_age = age > worst_age ? age : worst_age;
        most_ahead = -age > most_ahead ? -age : most_ahead;
        if (got == 0) {
            first_set = set.utime;
        }
        last_set = set.utime;
        got++;
    }
    struct rusage ru;
    if (got > 0 && getrusage(RUSAGE_SELF, &ru) == 0) {
        const double cpu = (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                           (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
        printf("cpu_ms_per_set=%.2f\n", cpu * 1000.0 / got);
    }
    if (got > 1) {
        printf("set_rate_hz=%.2f\n", (double)(got - 1) * 1e6 / (double)(last_set - first_set));
    }
    printf("sets_ok=%u timeouts=%u worst_spread_ms=%.2f worst_age_ms=%.2f stamp_ahead_ms=%.2f\n",
           got, timeouts, (double)worst_spread / 1000.0, (double)worst_age / 1000.0,
           (double)most_ahead / 1000.0);
    for (uint8_t i = 0; i < n; i++) {
        printf("cam%u device=%s drops=%u\n", (unsigned)i, cfg.cam[i].device,
               (unsigned)set.cam[i].drops);
    }
    printf("camera_frames_flagged_dropped=%u\n", dropped_sets);
    (void)rp_hal_stop(src);
    rp_hal_close(src);
    if (rc == 0) {
        printf("PASS\n");
    }
    return rc;
}
