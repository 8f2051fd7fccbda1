/*
 * rigpose-frontend - one front end of a distributed rig: some of the rig's cameras in, their
 * tracked features out over LCM, for the estimator in another process (the daemon with
 * source.kind lcm, daemon/rp_lcmsrc.h), on this machine or another.
 *
 *   rigpose-frontend --config FILE --cameras LIST [--frames N] [--lcm-url URL] [--fast]
 *                    [--clock monotonic|realtime] [--quiet]
 *
 * It reads the cameras of LIST (rig indices or names, comma-separated) through the HAL
 * (v4l2 or replay: FILE's source, with only those cameras opened), runs on them the very
 * trackers and stereo matcher of the in-process daemon, and publishes one rigpose.features_t
 * per camera image on that camera's channel (lcm.features_channel + index, rp_feats.h): the
 * camera's own capture time (the HAL's per-camera stamp; a camera without an image in the set:
 * the set's time), the camera's frame counter, every tracked feature with its id, position and
 * FEAT_NEW / FEAT_MATCHED flags. A stereo layout's front end must own both cameras of each
 * pair it touches (the matcher needs both images). Since the trackers are the pipeline's, the
 * daemon's frame sets are those of the in-process run, and so are its poses
 * (daemon/tests/test_frontend.sh).
 *
 * Time: the daemon groups the cameras' frames by capture time, so all front ends must stamp on
 * one clock. The HAL stamps on this machine's CLOCK_MONOTONIC (v4l2: the kernel's stamps), which
 * is common to the processes of one machine only; with --clock realtime the front end sends
 * capture time + (CLOCK_REALTIME - CLOCK_MONOTONIC) read at that moment, the wall clock that
 * PTP or chrony keeps common to the boards of a robot (daemon/README.md, "Five boards").
 *
 * How: an rp_pipe_t of FILE's layout runs the front-end phases of its step (rp_pipe.h:
 * rp_pipe_begin, rp_pipe_track for the trackers of LIST's cameras only, rp_pipe_match for the
 * pairs LIST holds) and never its estimator: the same trackers and matcher, set up and fed the
 * same way, as the daemon's in-process pipeline.
 *
 * Exit codes as the daemon's (daemon/README.md): 0 done (the source ended, --frames reached,
 * SIGINT / SIGTERM / SIGHUP), 1 usage, 2 configuration, 3 LCM, 4 source open / start, 5 the
 * pipeline refused the configuration, 6 the source failed for good (50 failing grabs in a row).
 *
 * No heap in the per-frame path: the pipeline, the message and the sets are static.
 */
#include <errno.h>
#include <lcm/lcm.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_hal.h"
#include "rigpose/rp_pipe.h"
#include "rp_feats.h"
#include "rp_prefault.h"
#include "rp_publish.h"


#define MAX_GRAB_ERRORS 50

static volatile sig_atomic_t g_stop;
static rp_config_t g_cfg;
static rp_pipe_t g_pipe;   /* the pipeline: its front end, fed this front end's images */
static rp_hal_set_t g_set;
static rigpose_features_t g_msg;
static int8_t g_instance[32];

/* This front end's cameras: own[i] is rig camera cam[i], HAL camera i. */
static uint8_t g_n_own;
static uint8_t g_cam[RP_MAX_CAMS];
static char g_channel[RP_MAX_CAMS][RP_CFG_CHANNEL_MAX + 8];
static int32_t g_seq[RP_MAX_CAMS];

/* Each own camera's ids of the previous image, and its partner's of this one, sorted. */
static uint32_t g_prev_ids[RP_MAX_CAMS][RP_MAX_FEATS_PER_CAM];
static uint16_t g_n_prev[RP_MAX_CAMS];
static uint8_t g_have_prev[RP_MAX_CAMS];
static uint32_t g_sorted[RP_MAX_FEATS_PER_CAM];

static void on_signal(int sig) { g_stop = sig; }

static void usage(FILE *f)
{
    fprintf(f,
            "usage: rigpose-frontend --config FILE --cameras LIST [options]\n"
            "  --config FILE    the rig's configuration (source v4l2 or replay; config/README.md)\n"
            "  --cameras LIST   the cameras this front end reads: rig indices or names, e.g. 0,4\n"
            "                   or cam1,cam1b (a stereo layout: both cameras of each pair)\n"
            "  --frames N       stop after N images per camera (0: until the source ends)\n"
            "  --lcm-url URL    override lcm.url\n"
            "  --fast           replay: as fast as possible (source.realtime: false)\n"
            "  --clock CLOCK    monotonic (default: the HAL's stamps, one machine) or realtime\n"
            "                   (the stamps moved to CLOCK_REALTIME: front ends on several\n"
            "                   boards whose clocks PTP or chrony keeps together)\n"
            "  --quiet          no line per image: only events and the summary\n"
            "exit codes: 0 done, 1 usage, 2 bad configuration, 3 LCM, 4 source open/start,\n"
            "            5 pipeline setup, 6 source failed while running\n");
}

/* ---- camera list ----------------------------------------------------------------------------- */

/* LIST into g_cam (rig order kept as given), checked against the layout. -1 with a message. */
static int parse_cameras(const char *list)
{
    uint8_t want[RP_MAX_CAMS], mine[RP_MAX_CAMS] = {0};
    /* ignored: a layout without cameras is refused by rp_pipe_init before this */
    (void)rp_feats_layout_cams(&g_cfg.pipe, g_cfg.rig.n_cams, want);
    char buf[256];
    if (strlen(list) >= sizeof buf) {
        fprintf(stderr, "rigpose-frontend: --cameras: list too long\n");
        return -1;
    }
    memcpy(buf, list, strlen(list) + 1);
    g_n_own = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok != NULL;
         tok = strtok_r(NULL, ",", &save)) {
        int k = -1;
        for (uint8_t i = 0; i < g_cfg.rig.n_cams; ++i) {
            if (strcmp(tok, g_cfg.cam_name[i]) == 0) {
                k = i;
            }
        }
        char *end = NULL;
        const long v = strtol(tok, &end, 10);
        if (k < 0 && end != tok && *end == '\0' && v >= 0 && v < g_cfg.rig.n_cams) {
            k = (int)v;
        }
        if (k < 0) {
            fprintf(stderr, "rigpose-frontend: --cameras: '%s' is neither a camera name nor an "
                    "index 0..%d of %s\n", tok, g_cfg.rig.n_cams - 1, g_cfg.path);
            return -1;
        }
        if (!want[k]) {
            fprintf(stderr, "rigpose-frontend: --cameras: camera %d (%s) is not used by method "
                    "%s\n", k, g_cfg.cam_name[k], rp_pipe_layout_name(g_cfg.pipe.layout));
            return -1;
        }
        if (mine[k] || g_n_own >= RP_MAX_CAMS) {
            fprintf(stderr, "rigpose-frontend: --cameras: camera %d given twice\n", k);
            return -1;
        }
        mine[k] = 1;
        g_cam[g_n_own++] = (uint8_t)k;
    }
    if (g_n_own == 0) {
        fprintf(stderr, "rigpose-frontend: --cameras: no camera\n");
        return -1;
    }
    for (uint8_t i = 0; i < g_n_own; ++i) {
        const int q = rp_feats_partner(&g_cfg.pipe, g_cam[i]);
        if (q >= 0 && !mine[q]) {
            fprintf(stderr, "rigpose-frontend: --cameras: camera %u (%s) is in a stereo pair with "
                    "camera %d (%s): a front end reads both (the matcher needs both images)\n",
                    g_cam[i], g_cfg.cam_name[g_cam[i]], q, g_cfg.cam_name[q]);
            return -1;
        }
    }
    return 0;
}

/* ---- flags of a camera's features ------------------------------------------------------------ */

static int cmp_u32(const void *a, const void *b)
{
    const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

static int has_id(const uint32_t *sorted, uint16_t n, uint32_t id)
{
    return bsearch(&id, sorted, n, sizeof *sorted, cmp_u32) != NULL;
}

/* FEAT_NEW: not in this camera's previous image; FEAT_MATCHED: in the pair partner's image. */
static void set_flags(uint8_t own, const rp_frameset_t *fs, rigpose_features_t *m)
{
    const uint8_t cam = g_cam[own];
    const int q = rp_feats_partner(&g_cfg.pipe, cam);
    uint16_t n_q = 0;
    if (q >= 0) {
        n_q = fs->n[q];
        for (uint16_t i = 0; i < n_q; ++i) {
            g_sorted[i] = fs->f[q][i].id;
        }
        qsort(g_sorted, n_q, sizeof g_sorted[0], cmp_u32);
    }
    for (int16_t i = 0; i < m->n; ++i) {
        const uint32_t id = (uint32_t)m->id[i];
        int8_t fl = 0;
        if (!g_have_prev[own] || !has_id(g_prev_ids[own], g_n_prev[own], id)) {
            fl = (int8_t)(fl | RIGPOSE_FEATURES_T_FEAT_NEW);
        }
        if (q >= 0 && has_id(g_sorted, n_q, id)) {
            fl = (int8_t)(fl | RIGPOSE_FEATURES_T_FEAT_MATCHED);
        }
        m->flags[i] = fl;
    }
    g_n_prev[own] = (uint16_t)m->n;
    for (int16_t i = 0; i < m->n; ++i) {
        g_prev_ids[own][i] = (uint32_t)m->id[i];
    }
    qsort(g_prev_ids[own], g_n_prev[own], sizeof g_prev_ids[own][0], cmp_u32);
    g_have_prev[own] = 1;
}

/* ---- tracking -------------------------------------------------------------------------------- */

/* Does this front end own rig camera cam? */
static int owns(uint8_t cam)
{
    for (uint8_t i = 0; i < g_n_own; ++i) {
        if (g_cam[i] == cam) {
            return 1;
        }
    }
    return 0;
}

/* This front end's images of one set through the pipeline's front end: the trackers of its
 * cameras, each at its own capture time cam_utime[cam], then the matching of its pairs (a
 * pair of other cameras has no image and is not matched); *fs their features. RP_OK, or
 * RP_E_RANGE when utime is not after the last set's or a camera's time is more than an
 * int32_t of microseconds from it (nothing tracked). */
static rp_status_t track(const rp_image_t *const img[RP_MAX_CAMS],
                         const int64_t cam_utime[RP_MAX_CAMS], int64_t utime,
                         const rp_frameset_t **fs)
{
    for (uint8_t cam = 0; cam < g_cfg.rig.n_cams; ++cam) {
        int32_t dt;
        if (img[cam] != NULL && rp_pipe_cam_dt(cam_utime[cam], utime, &dt) != RP_OK) {
            return RP_E_RANGE;
        }
    }
    if (rp_pipe_begin(&g_pipe, utime, NULL) != RP_OK) {
        return RP_E_RANGE;
    }
    for (uint8_t cam = 0; cam < g_cfg.rig.n_cams; ++cam) {
        if (img[cam] != NULL) {
            /* ignored: the step is begun, cam a rig camera, its time checked above */
            (void)rp_pipe_cam_time(&g_pipe, cam, cam_utime[cam]);
        }
    }
    for (uint8_t t = 0; t < rp_pipe_n_trackers(&g_pipe); ++t) {
        uint8_t cam = 0;
        if (rp_pipe_tracker_cam(&g_pipe, t, &cam) == RP_OK && owns(cam)) {
            /* ignored: cannot fail: the step is begun, t is a tracker; the tracker's outcome
             * is in the pipeline's report */
            (void)rp_pipe_track(&g_pipe, t, img, g_cfg.rig.n_cams);
        }
    }
    /* ignored: cannot fail: the step is begun */
    (void)rp_pipe_match(&g_pipe);
    /* ignored: cannot fail: the pipeline was set up */
    (void)rp_pipe_frameset(&g_pipe, fs);
    return RP_OK;
}

/* ---- the loop -------------------------------------------------------------------------------- */

static rp_hal_status_t source_open(rp_hal_source_t **src)
{
    rp_hal_cfg_t hc = g_cfg.hal;
    hc.partial_sets = 1; /* replay: an unreadable image costs its camera only */
    hc.n_cams = g_n_own;
    for (uint8_t i = 0; i < g_n_own; ++i) {
        hc.cam[i] = g_cfg.hal.cam[g_cam[i]];
    }
    rp_hal_status_t st = rp_hal_open(src, &hc);
    if (st != RP_HAL_OK) {
        fprintf(stderr, "rigpose-frontend: %s: camera source: %s: %s\n", g_cfg.path,
                rp_hal_status_str(st), rp_hal_errmsg(NULL));
        return st;
    }
    st = rp_hal_start(*src);
    if (st != RP_HAL_OK) {
        fprintf(stderr, "rigpose-frontend: %s: camera source: %s: %s\n", g_cfg.path,
                rp_hal_status_str(st), rp_hal_errmsg(*src));
        rp_hal_close(*src);
        *src = NULL;
    }
    return st;
}

typedef struct {
    uint32_t frames;
    int quiet;
    int realtime; /* --clock realtime */
} fe_opts_t;

/* CLOCK_REALTIME - CLOCK_MONOTONIC now, us (the HAL's clock is CLOCK_MONOTONIC). */
static int64_t realtime_offset_us(void)
{
    struct timespec r, m;
    /* ignored: both clocks exist on every Linux */
    (void)clock_gettime(CLOCK_MONOTONIC, &m);
    /* ignored: as above */
    (void)clock_gettime(CLOCK_REALTIME, &r);
    return ((int64_t)r.tv_sec - (int64_t)m.tv_sec) * 1000000 +
           ((int64_t)r.tv_nsec - (int64_t)m.tv_nsec) / 1000;
}

static int run(const fe_opts_t *o, rp_hal_source_t *src, lcm_t *lcm, uint32_t *n_sets,
               uint32_t *n_failed)
{
    uint32_t grab_errors = 0;
    while (!g_stop && (o->frames == 0 || *n_sets < o->frames)) {
        const rp_hal_status_t hst = rp_hal_grab(src, &g_set);
        if (hst == RP_HAL_E_END) {
            break;
        }
        if (hst != RP_HAL_OK) {
            (*n_failed)++;
            if (hst != RP_HAL_E_TIMEOUT && ++grab_errors > MAX_GRAB_ERRORS) {
                fprintf(stderr, "rigpose-frontend: %s: camera source failed for good (%d failing "
                        "grabs in a row), the last: %s: %s\n", g_cfg.path, MAX_GRAB_ERRORS + 1,
                        rp_hal_status_str(hst), rp_hal_errmsg(src));
                return EXIT_SOURCE_FAILED;
            }
            if (hst != RP_HAL_E_TIMEOUT) {
                fprintf(stderr, "rigpose-frontend: camera source: %s: %s\n",
                        rp_hal_status_str(hst), rp_hal_errmsg(src));
            }
            continue;
        }
        grab_errors = 0;
        const rp_image_t *img[RP_MAX_CAMS] = {NULL};
        int64_t cam_utime[RP_MAX_CAMS] = {0};
        for (uint8_t i = 0; i < g_n_own && i < g_set.n_cams; ++i) {
            img[g_cam[i]] = g_set.cam[i].img.data != NULL ? &g_set.cam[i].img : NULL;
            cam_utime[g_cam[i]] = img[g_cam[i]] != NULL ? g_set.cam[i].utime : g_set.utime;
        }
        const rp_frameset_t *fs = NULL;
        if (track(img, cam_utime, g_set.utime, &fs) != RP_OK) { /* nothing tracked */
            fprintf(stderr, "rigpose-frontend: set at %lld us: not after the last one, or a "
                    "camera's time 35 min from it: not tracked\n", (long long)g_set.utime);
            continue;
        }
        const int64_t clock_off = o->realtime ? realtime_offset_us() : 0;
        for (uint8_t i = 0; i < g_n_own; ++i) {
            const uint8_t cam = g_cam[i];
            /* each camera's own capture time (a camera without an image: the set's) */
            const int64_t stamp = cam_utime[cam] + clock_off;
            rp_pub_fill_features(&g_msg, cam, stamp, g_seq[i]++, fs->f[cam], fs->n[cam]);
            g_msg.state = (int8_t)(g_set.cam[i].flags &
                                   (RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE | RP_HAL_CAM_DROPPED));
            g_msg.drops = (int32_t)g_set.cam[i].drops;
            memcpy(g_msg.instance, g_instance, sizeof g_msg.instance);
            set_flags(i, fs, &g_msg);
            const rp_pub_status_t ps = rp_pub_features(lcm, g_channel[i], &g_msg);
            if (ps != RP_PUB_OK) {
                fprintf(stderr, "rigpose-frontend: LCM publish on %s failed: %s\n", g_channel[i],
                        rp_pub_status_str(ps));
            }
            if (!o->quiet) {
                printf("rigpose-frontend: utime %lld camera %u: %d features\n",
                       (long long)stamp, cam, g_msg.n);
            }
        }
        (*n_sets)++;
    }
    return EXIT_DONE;
}

int main(int argc, char **argv)
{
    const char *config = NULL, *cameras = NULL, *url = NULL;
    fe_opts_t o = {0, 0, 0};
    int fast = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return EXIT_DONE;
        } else if (strcmp(a, "--fast") == 0) {
            fast = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            o.quiet = 1;
        } else if (v != NULL && strcmp(a, "--config") == 0) {
            config = v;
            ++i;
        } else if (v != NULL && strcmp(a, "--cameras") == 0) {
            cameras = v;
            ++i;
        } else if (v != NULL && strcmp(a, "--clock") == 0 &&
                   (strcmp(v, "monotonic") == 0 || strcmp(v, "realtime") == 0)) {
            o.realtime = v[0] == 'r';
            ++i;
        } else if (v != NULL && strcmp(a, "--lcm-url") == 0) {
            url = v;
            ++i;
        } else if (v != NULL && strcmp(a, "--frames") == 0) {
            char *end = NULL;
            errno = 0;
            const unsigned long long n = strtoull(v, &end, 10);
            if (errno != 0 || end == v || *end != '\0' || v[0] == '-' || n > 0xFFFFFFFFull) {
                fprintf(stderr, "rigpose-frontend: --frames: '%s' is not a count\n", v);
                usage(stderr);
                return EXIT_USAGE;
            }
            o.frames = (uint32_t)n;
            ++i;
        } else {
            fprintf(stderr, "rigpose-frontend: %s: unknown option or missing value\n", a);
            usage(stderr);
            return EXIT_USAGE;
        }
    }
    if (config == NULL || cameras == NULL) {
        fprintf(stderr, "rigpose-frontend: --config and --cameras are required\n");
        usage(stderr);
        return EXIT_USAGE;
    }
    setvbuf(stdout, NULL, _IOLBF, 0);

    char err[RP_CFG_ERR_MAX];
    if (rp_config_load(config, &g_cfg, err, sizeof err) != RP_CFG_OK) {
        fprintf(stderr, "rigpose-frontend: invalid configuration: %s\n", err);
        return EXIT_CONFIG;
    }
    if (g_cfg.hal.kind != RP_HAL_SRC_V4L2 && g_cfg.hal.kind != RP_HAL_SRC_REPLAY) {
        fprintf(stderr, "rigpose-frontend: %s: source.kind must be v4l2 or replay (images) for a "
                "front end\n", config);
        return EXIT_CONFIG;
    }
    if (url != NULL) {
        if (strlen(url) >= sizeof g_cfg.lcm_url) {
            fprintf(stderr, "rigpose-frontend: --lcm-url: too long\n");
            return EXIT_USAGE;
        }
        memcpy(g_cfg.lcm_url, url, strlen(url) + 1);
    }
    if (fast) {
        g_cfg.hal.realtime = RP_HAL_PACE_FAST;
    }
    const rp_status_t pst = rp_pipe_init(&g_pipe, &g_cfg.rig, &g_cfg.pipe);
    if (pst != RP_OK) {
        fprintf(stderr, "rigpose-frontend: %s: method %s refused the configuration: %s\n", config,
                rp_pipe_layout_name(g_cfg.pipe.layout), rp_status_str(pst));
        return EXIT_ESTIMATOR;
    }
    rp_prefault(&g_pipe, sizeof(g_pipe));
    if (parse_cameras(cameras) != 0) {
        usage(stderr);
        return EXIT_USAGE;
    }
    for (uint8_t i = 0; i < g_n_own; ++i) {
        /* ignored: cannot fail: rp_config keeps the prefix 2 characters short of the field */
        (void)rp_feats_channel(g_cfg.features_channel, g_cam[i], g_channel[i],
                               sizeof g_channel[i]);
    }

    lcm_t *lcm = lcm_create(g_cfg.lcm_url);
    if (lcm == NULL) {
        fprintf(stderr, "rigpose-frontend: LCM: cannot use '%s'\n", g_cfg.lcm_url);
        return EXIT_LCM;
    }
    /* HOST:PID: a restarted front end is a new instance (rp_lcmsrc.h) */
    rp_feats_instance(NULL, g_instance);

    rp_hal_source_t *src = NULL;
    if (source_open(&src) != RP_HAL_OK) {
        lcm_destroy(lcm);
        return EXIT_SOURCE;
    }
    rp_feats_stop_signals(on_signal);

    printf("rigpose-frontend: %s: instance '%.32s', cameras", config, (const char *)g_instance);
    for (uint8_t i = 0; i < g_n_own; ++i) {
        printf(" %u (%s) on %s", g_cam[i], g_cfg.cam_name[g_cam[i]], g_channel[i]);
    }
    printf(", method %s, LCM %s, stamps on CLOCK_%s\n", rp_pipe_layout_name(g_cfg.pipe.layout),
           g_cfg.lcm_url, o.realtime ? "REALTIME" : "MONOTONIC");

    uint32_t n_sets = 0, n_failed = 0;
    const int code = run(&o, src, lcm, &n_sets, &n_failed);
    /* ignored: best effort before closing */
    (void)rp_hal_stop(src);
    rp_hal_close(src);
    lcm_destroy(lcm);
    printf("rigpose-frontend: %u images per camera published, %u failed grabs%s\n", n_sets,
           n_failed, g_stop ? " (stopped by signal)" : "");
    return code;
}
