/*
 * rigpose - the pose daemon: camera source (HAL) -> front end -> estimator -> LCM.
 *
 *   rigpose --config FILE [--frames N] [options]     (rigpose --help for all of them)
 *
 * Each frame set from the configured source becomes one rigpose.pose_t on the pose channel;
 * a rigpose.status_t goes out every lcm.status_every sets and whenever a camera changes state.
 * Sources that deliver images (v4l2, replay) go through the core's image pipeline (rp_pipe.h);
 * the sim source delivers features, which go to the same pipeline's estimator directly
 * (rp_est.h). With a source that knows the truth (sim), every printed pose carries its error
 * against it, and the run ends with the mean absolute error per axis (as Table 1 of the paper
 * reports it).
 *
 * Exit codes (daemon/README.md):
 *   0  done: --frames reached, the source ended, or SIGINT / SIGTERM
 *   1  usage error (bad command line)
 *   2  invalid configuration file (the message names file, line and key)
 *   3  LCM could not be set up (bad URL, no network for udpm)
 *   4  the camera source could not be opened or started
 *   5  the estimator refused the configuration (rig or method)
 *   6  the camera source failed for good while running
 *
 * No heap in the per-frame path: every buffer is static or on the stack.
 */
#include <errno.h>
#include <lcm/lcm.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_hal.h"
#include "rigpose/rp_hal_sim.h"
#include "rigpose/rp_pipe.h"
#include "rigpose/rp_rot.h"
#include "rigpose_image_t.h"
#include "rigpose_pose_t.h"
#include "rigpose_status_t.h"
#include "rp_est.h"

enum {
    EXIT_DONE = 0,
    EXIT_USAGE = 1,
    EXIT_CONFIG = 2,
    EXIT_LCM = 3,
    EXIT_SOURCE = 4,
    EXIT_ESTIMATOR = 5,
    EXIT_SOURCE_FAILED = 6
};

/* The pose message's per-camera arrays hold RP_MAX_CAMS entries. */
RP_STATIC_ASSERT(RP_MAX_CAMS == 6, "lcm_types: per-camera arrays are of 6");
/* The messages carry the core's and the HAL's codes as they are. */
RP_STATIC_ASSERT(RIGPOSE_POSE_T_METHOD_STEREO4 == RP_PIPE_STEREO4 &&
                     RIGPOSE_POSE_T_METHOD_STEREO2 == RP_PIPE_STEREO2 &&
                     RIGPOSE_POSE_T_METHOD_GC == RP_PIPE_GC &&
                     RIGPOSE_POSE_T_METHOD_CAM1 == RP_PIPE_CAM1 &&
                     RIGPOSE_POSE_T_METHOD_CAM2 == RP_PIPE_CAM2 &&
                     RIGPOSE_POSE_T_METHOD_CAM3 == RP_PIPE_CAM3 &&
                     RIGPOSE_POSE_T_METHOD_CAM4 == RP_PIPE_CAM4 &&
                     RIGPOSE_POSE_T_METHOD_RC == RP_PIPE_RC && RP_PIPE_LAYOUT_COUNT_ == 8,
                 "pose_t.METHOD_* are rp_pipe_layout_t, all eight");
RP_STATIC_ASSERT(RIGPOSE_POSE_T_FLAG_LOST == RP_EST_LOST &&
                     RIGPOSE_POSE_T_FLAG_SCALE_WEAK == RP_EST_SCALE_WEAK,
                 "pose_t.FLAG_* are RP_EST_*");
RP_STATIC_ASSERT(RIGPOSE_STATUS_T_CAM_MISSING == RP_HAL_CAM_MISSING &&
                     RIGPOSE_STATUS_T_CAM_GONE == RP_HAL_CAM_GONE &&
                     RIGPOSE_STATUS_T_CAM_DROPPED == RP_HAL_CAM_DROPPED,
                 "status_t.CAM_* are RP_HAL_CAM_*");
#define CAM_STATE_BITS (RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE | RP_HAL_CAM_DROPPED)

/* One word for a camera's state bits, worst first: a vanished device, no frame in this set,
 * frames skipped by the driver before this one, or back to normal. */
static const char *cam_state_str(int state)
{
    if (state & RP_HAL_CAM_GONE) {
        return "gone";
    }
    if (state & RP_HAL_CAM_MISSING) {
        return "missing";
    }
    if (state & RP_HAL_CAM_DROPPED) {
        return "dropped frames";
    }
    return "ok again";
}

/* Grab errors in a row (not timeouts) after which the source counts as failed for good. */
#define MAX_GRAB_ERRORS 50
/* Latencies kept for the final percentiles (the first ones, if the run is longer). */
#define LAT_KEEP 65536

typedef struct {
    const char *config;
    uint32_t frames;        /* 0: until the source ends or a signal */
    const char *lcm_url;    /* overrides, NULL: the file's */
    const char *pose_channel;
    const char *status_channel;
    const char *image_channel;
    int fast;               /* 1: sim / replay as fast as possible (source.realtime off) */
    int drop_cam;           /* --sim-drop CAM:FRAME, -2: not given */
    uint32_t drop_from;
    int quiet;
    uint32_t print_every;
    const char *stats_json;
} opts_t;

/* ---- static state (the daemon's memory) ------------------------------------------------------ */

static volatile sig_atomic_t g_stop;
static rp_config_t g_cfg;
static rp_est_t g_est;      /* the image pipeline: images, or features from the sim source */
static rp_hal_set_t g_set;
static float g_lat_ms[LAT_KEEP];
static uint8_t g_img_buf[RP_HAL_MAX_W * RP_HAL_MAX_H]; /* an image with padded rows, packed */

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

/* ---- command line ---------------------------------------------------------------------------- */

static void usage(FILE *f)
{
    fprintf(f,
            "usage: rigpose --config FILE [--frames N] [options]\n"
            "  --config FILE         configuration (schema: config/README.md)\n"
            "  --frames N            stop after N frame sets (0: run until the source ends or\n"
            "                        SIGINT/SIGTERM; the sim source then simulates 300)\n"
            "  --lcm-url URL         override lcm.url (udpm://..., file://...?mode=w, memq://)\n"
            "  --pose-channel NAME   override lcm.pose_channel\n"
            "  --status-channel NAME override lcm.status_channel\n"
            "  --fast                sim / replay: as fast as possible (source.realtime: false)\n"
            "  --sim-drop CAM:FRAME  sim: camera CAM vanishes from frame set FRAME on\n"
            "  --print-every K       print every K-th pose (default 1)\n"
            "  --quiet               print no poses, only the summary\n"
            "  --image-channel NAME  also publish every camera image (rigpose.image_t) there\n"
            "  --stats-json FILE     write daemon_latency_ms_p50/_p99 and daemon_fps to FILE\n"
            "exit codes: 0 done, 1 usage, 2 bad configuration, 3 LCM, 4 source open/start,\n"
            "            5 estimator setup, 6 source failed while running\n");
}

static int parse_u32(const char *s, uint32_t *out)
{
    char *end = NULL;
    errno = 0;
    const unsigned long long v = strtoull(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || s[0] == '-' || v > 0xFFFFFFFFull) {
        return -1;
    }
    *out = (uint32_t)v;
    return 0;
}

static int parse_args(int argc, char **argv, opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->drop_cam = -2;
    o->print_every = 1;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            exit(EXIT_DONE);
        } else if (strcmp(a, "--fast") == 0) {
            o->fast = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            o->quiet = 1;
        } else if (v == NULL) {
            fprintf(stderr, "rigpose: %s: unknown option or missing value\n", a);
            return -1;
        } else if (strcmp(a, "--config") == 0) {
            o->config = v;
            ++i;
        } else if (strcmp(a, "--frames") == 0) {
            if (parse_u32(v, &o->frames) != 0) {
                fprintf(stderr, "rigpose: --frames: '%s' is not a count\n", v);
                return -1;
            }
            ++i;
        } else if (strcmp(a, "--lcm-url") == 0) {
            o->lcm_url = v;
            ++i;
        } else if (strcmp(a, "--pose-channel") == 0) {
            o->pose_channel = v;
            ++i;
        } else if (strcmp(a, "--status-channel") == 0) {
            o->status_channel = v;
            ++i;
        } else if (strcmp(a, "--image-channel") == 0) {
            o->image_channel = v;
            ++i;
        } else if (strcmp(a, "--print-every") == 0) {
            if (parse_u32(v, &o->print_every) != 0 || o->print_every == 0) {
                fprintf(stderr, "rigpose: --print-every: '%s' is not a positive count\n", v);
                return -1;
            }
            ++i;
        } else if (strcmp(a, "--stats-json") == 0) {
            o->stats_json = v;
            ++i;
        } else if (strcmp(a, "--sim-drop") == 0) {
            unsigned cam = 0, from = 0;
            char tail = 0;
            if (sscanf(v, "%u:%u%c", &cam, &from, &tail) != 2 || cam >= RP_MAX_CAMS) {
                fprintf(stderr, "rigpose: --sim-drop: '%s' is not CAM:FRAME (CAM < %d)\n", v,
                        RP_MAX_CAMS);
                return -1;
            }
            o->drop_cam = (int)cam;
            o->drop_from = from;
            ++i;
        } else {
            fprintf(stderr, "rigpose: %s: unknown option (--help)\n", a);
            return -1;
        }
    }
    if (o->config == NULL) {
        fprintf(stderr, "rigpose: --config FILE is required (--help)\n");
        return -1;
    }
    return 0;
}

/* Apply the command line's overrides to the loaded configuration. */
static int apply_overrides(const opts_t *o, rp_config_t *cfg)
{
    struct { const char *v; char *dst; size_t cap; const char *name; } s[] = {
        {o->lcm_url, cfg->lcm_url, sizeof cfg->lcm_url, "--lcm-url"},
        {o->pose_channel, cfg->pose_channel, sizeof cfg->pose_channel, "--pose-channel"},
        {o->status_channel, cfg->status_channel, sizeof cfg->status_channel, "--status-channel"},
        {o->image_channel, cfg->image_channel, sizeof cfg->image_channel, "--image-channel"},
    };
    for (size_t i = 0; i < sizeof s / sizeof s[0]; ++i) {
        if (s[i].v == NULL) {
            continue;
        }
        if (s[i].v[0] == '\0' || strlen(s[i].v) >= s[i].cap) {
            fprintf(stderr, "rigpose: %s: 1..%zu characters\n", s[i].name, s[i].cap - 1);
            return -1;
        }
        snprintf(s[i].dst, s[i].cap, "%s", s[i].v);
    }
    if (o->fast) {
        cfg->hal.realtime = 0;
    }
    if (o->drop_cam >= 0) {
        if (o->drop_cam >= cfg->rig.n_cams) {
            fprintf(stderr, "rigpose: --sim-drop: the rig has %u cameras\n", cfg->rig.n_cams);
            return -1;
        }
        cfg->sim.drop_cam = (int16_t)o->drop_cam;
        cfg->sim.drop_from = o->drop_from;
    }
    if (cfg->hal.kind == RP_HAL_SRC_SIM && cfg->hal.sim_frames == 0) {
        cfg->hal.sim_frames = o->frames > 0 ? o->frames : 300u;
    }
    return 0;
}

/* ---- the camera source: the sim directly, the others through the platform's rp_hal_open ---- */

typedef struct {
    rp_hal_sim_t *sim;
    rp_hal_source_t *hal;
} source_t;

static rp_hal_status_t source_open(source_t *s, const rp_config_t *cfg)
{
    memset(s, 0, sizeof *s);
    if (cfg->hal.kind == RP_HAL_SRC_SIM) {
        rp_hal_sim_opts_t so = rp_hal_sim_default_opts();
        so.noise_px = cfg->sim.noise_px;
        so.drop_cam = cfg->sim.drop_cam;
        so.drop_from = cfg->sim.drop_from;
        return rp_hal_sim_open(&s->sim, &cfg->hal, &so);
    }
    return rp_hal_open(&s->hal, &cfg->hal);
}

static rp_hal_status_t source_start(source_t *s)
{
    return s->sim != NULL ? rp_hal_sim_start(s->sim) : rp_hal_start(s->hal);
}

static rp_hal_status_t source_grab(source_t *s, rp_hal_set_t *set)
{
    return s->sim != NULL ? rp_hal_sim_grab(s->sim, set) : rp_hal_grab(s->hal, set);
}

static void source_close(source_t *s)
{
    if (s->sim != NULL) {
        (void)rp_hal_sim_stop(s->sim);
        rp_hal_sim_close(s->sim);
    } else if (s->hal != NULL) {
        (void)rp_hal_stop(s->hal);
        rp_hal_close(s->hal);
    }
    memset(s, 0, sizeof *s);
}

/* ---- the estimator: features directly, images through the pipeline --------------------------- */

static rp_status_t estimator_init(const rp_config_t *cfg)
{
    return rp_est_init(&g_est, cfg);
}

/* Run the estimator on one set; fs_out receives the features it used (for the status). */
static rp_status_t estimator_step(const rp_hal_set_t *set, rp_estimate_t *est,
                                  const rp_frameset_t **fs_out)
{
    if (set->has_feats && set->feats != NULL) {
        *fs_out = set->feats;
        return rp_est_step(&g_est, set->feats, est);
    }
    const rp_image_t *img[RP_MAX_CAMS];
    for (uint8_t k = 0; k < RP_MAX_CAMS; ++k) {
        img[k] = (k < set->n_cams && set->cam[k].img.data != NULL) ? &set->cam[k].img : NULL;
    }
    return rp_est_step_images(&g_est, img, set->n_cams, set->utime, est, fs_out);
}

/* ---- messages ---------------------------------------------------------------------------------- */

static void fill_pose(rigpose_pose_t *m, const rp_hal_set_t *set, const rp_estimate_t *est,
                      rp_status_t st, int32_t seq, uint8_t n_cams, rp_pipe_layout_t method)
{
    memset(m, 0, sizeof *m);
    m->utime = set->utime;
    m->seq = seq;
    m->frame = (int32_t)est->frame;
    m->method = (int8_t)method;
    rp_real R[9], q[4];
    rp_rot_from_angles(&est->p[3], R);
    rp_rot_to_quat(R, q);
    for (int i = 0; i < 3; ++i) {
        m->position[i] = (double)est->p[i];
        m->angles[i] = (double)est->p[3 + i];
        m->velocity[i] = (double)est->v[i];
        m->angle_rates[i] = (double)est->v[3 + i];
    }
    for (int i = 0; i < 4; ++i) {
        m->quaternion[i] = (double)q[i];
    }
    for (int i = 0; i < 36; ++i) {
        m->covariance[i] = (double)est->cov[i];
    }
    m->n_cams = (int8_t)n_cams;
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        m->features_used[k] = (int16_t)(k < n_cams ? est->n_used[k] : 0);
    }
    m->n_gated = (int16_t)est->n_gated;
    m->n_landmarks = (int16_t)est->n_landmarks;
    m->flags = (int32_t)est->flags;
    m->est_status = (int32_t)st;
    m->has_truth = set->has_truth ? 1 : 0;
    for (int i = 0; i < 6; ++i) {
        m->truth[i] = set->has_truth ? (double)set->truth[i] : 0.0;
    }
}

/* Each camera's image of the set on the image channel (packed rows), if one is configured. */
static void publish_images(lcm_t *lcm, const char *channel, const rp_hal_set_t *set, int32_t seq)
{
    for (uint8_t k = 0; k < set->n_cams; ++k) {
        const rp_image_t *im = &set->cam[k].img;
        const size_t n = (size_t)im->w * im->h;
        if (im->data == NULL || n == 0 || im->stride < im->w ||
            (size_t)im->stride * (im->h - 1u) + im->w > im->size) {
            continue;
        }
        const uint8_t *packed = im->data;
        if (im->stride != im->w) {
            if (n > sizeof g_img_buf) {
                continue;
            }
            for (uint16_t y = 0; y < im->h; ++y) {
                memcpy(g_img_buf + (size_t)y * im->w, im->data + (size_t)y * im->stride, im->w);
            }
            packed = g_img_buf;
        }
        rigpose_image_t m;
        m.utime = set->cam[k].utime;
        m.seq = seq;
        m.cam = (int8_t)k;
        m.width = (int16_t)im->w;
        m.height = (int16_t)im->h;
        m.size = (int32_t)n;
        m.data = (uint8_t *)(uintptr_t)packed;
        (void)rigpose_image_t_publish(lcm, channel, &m);
    }
}

/* Counters behind the status message. */
typedef struct {
    int32_t seq;
    int32_t frames[RP_MAX_CAMS];
    int32_t period_frames[RP_MAX_CAMS];
    uint32_t period_sets;
    int64_t period_start_us;
    float lat_max_ms;
    int32_t n_lost, n_reinit, n_cov_reset;
    int8_t cam_state[RP_MAX_CAMS];
} status_acc_t;

static void fill_status(rigpose_status_t *m, status_acc_t *a, const rp_config_t *cfg,
                        const rp_hal_set_t *set, rp_hal_status_t hal_st,
                        const rp_frameset_t *fs, const rp_estimate_t *est, int32_t last_pose,
                        float lat_ms, float proc_ms, int64_t now)
{
    memset(m, 0, sizeof *m);
    const double period_s = (double)(now - a->period_start_us) * 1e-6;
    m->utime = now;
    m->seq = a->seq++;
    m->last_pose_seq = last_pose;
    m->source = (int8_t)(cfg->hal.kind == RP_HAL_SRC_V4L2     ? RIGPOSE_STATUS_T_SOURCE_V4L2
                         : cfg->hal.kind == RP_HAL_SRC_REPLAY ? RIGPOSE_STATUS_T_SOURCE_REPLAY
                                                              : RIGPOSE_STATUS_T_SOURCE_SIM);
    m->method = (int8_t)cfg->pipe.layout;
    m->hal_status = (int32_t)hal_st;
    m->n_cams = (int8_t)cfg->rig.n_cams;
    for (int k = 0; k < cfg->rig.n_cams; ++k) {
        m->cam_state[k] = a->cam_state[k];
        m->fps[k] = period_s > 0.0 ? (float)(a->period_frames[k] / period_s) : 0.0f;
        m->frames[k] = a->frames[k];
        m->drops[k] = (int32_t)set->cam[k].drops;
        m->features[k] = (int16_t)(fs != NULL ? fs->n[k] : 0);
        m->features_used[k] = (int16_t)est->n_used[k];
        a->period_frames[k] = 0;
    }
    m->latency_ms = lat_ms;
    m->latency_ms_max = a->lat_max_ms;
    m->process_ms = proc_ms;
    m->set_rate_hz = period_s > 0.0 ? (float)(a->period_sets / period_s) : 0.0f;
    m->est_flags = (int32_t)est->flags;
    m->n_lost = a->n_lost;
    m->n_reinit = a->n_reinit;
    m->n_cov_reset = a->n_cov_reset;
    m->n_landmarks = (int16_t)est->n_landmarks;
    m->pos_sigma_m = (float)sqrt((double)(est->cov[0] + est->cov[7] + est->cov[14]));
    m->rot_sigma_rad = (float)sqrt((double)(est->cov[21] + est->cov[28] + est->cov[35]));
    a->period_sets = 0;
    a->period_start_us = now;
    a->lat_max_ms = 0.0f;
}

/* ---- printing -------------------------------------------------------------------------------- */

static void flag_names(uint32_t f, char *out, size_t cap)
{
    static const char *const names[] = {"INIT", "TRACK", "REINIT", "DEGRADED",
                                        "LOST", "GATED", "COVRESET", "SCALEWEAK"};
    out[0] = '\0';
    size_t used = 0;
    for (unsigned b = 0; b < sizeof names / sizeof names[0]; ++b) {
        if (f & (1u << b)) {
            const int n = snprintf(out + used, cap - used, "%s%s", used ? "," : "", names[b]);
            if (n < 0 || (size_t)n >= cap - used) {
                return;
            }
            used += (size_t)n;
        }
    }
    if (used == 0) {
        snprintf(out, cap, "-");
    }
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* ---- main -------------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    opts_t o;
    if (parse_args(argc, argv, &o) != 0) {
        usage(stderr);
        return EXIT_USAGE;
    }
    setvbuf(stdout, NULL, _IOLBF, 0);

    char err[RP_CFG_ERR_MAX];
    const rp_cfg_status_t cst = rp_config_load(o.config, &g_cfg, err, sizeof err);
    if (cst != RP_CFG_OK) {
        fprintf(stderr, "rigpose: invalid configuration: %s\n", err);
        return EXIT_CONFIG;
    }
    if (apply_overrides(&o, &g_cfg) != 0) {
        return EXIT_USAGE;
    }

    const rp_status_t est_st = estimator_init(&g_cfg);
    if (est_st != RP_OK) {
        fprintf(stderr, "rigpose: %s: method %s refused the configuration: %s\n", o.config,
                rp_pipe_layout_name(g_cfg.pipe.layout), rp_status_str(est_st));
        return EXIT_ESTIMATOR;
    }

    lcm_t *lcm = lcm_create(g_cfg.lcm_url);
    if (lcm == NULL) {
        fprintf(stderr, "rigpose: LCM: cannot use '%s'\n", g_cfg.lcm_url);
        return EXIT_LCM;
    }

    source_t src;
    rp_hal_status_t hst = source_open(&src, &g_cfg);
    if (hst == RP_HAL_OK) {
        hst = source_start(&src);
    }
    if (hst != RP_HAL_OK) {
        fprintf(stderr, "rigpose: camera source: %s\n", rp_hal_status_str(hst));
        source_close(&src);
        lcm_destroy(lcm);
        return EXIT_SOURCE;
    }

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    printf("rigpose: %s: source %s, %u cameras, method %s, LCM %s (%s, %s)\n", o.config,
           g_cfg.hal.kind == RP_HAL_SRC_SIM ? "sim" : g_cfg.hal.kind == RP_HAL_SRC_V4L2 ? "v4l2"
                                                                                     : "replay",
           g_cfg.rig.n_cams, rp_pipe_layout_name(g_cfg.pipe.layout), g_cfg.lcm_url,
           g_cfg.pose_channel, g_cfg.status_channel);
    if (!o.quiet) {
        printf("%6s %9s %9s %9s %9s %9s %9s  %-16s %5s %8s%s\n", "seq", "tx m", "ty m", "tz m",
               "alpha", "beta", "gamma", "flags", "feats", "lat ms",
               "   err_t m   err_r rad");
    }

    status_acc_t acc;
    memset(&acc, 0, sizeof acc);
    acc.period_start_us = rp_hal_now_us();
    int32_t pose_seq = 0;
    uint32_t n_lat = 0, grab_errors = 0, n_err = 0;
    double err_sum[6] = {0, 0, 0, 0, 0, 0};
    int exit_code = EXIT_DONE;
    int64_t t_first = 0, t_last = 0;
    rp_estimate_t est;
    memset(&est, 0, sizeof est);

    while (!g_stop && (o.frames == 0 || (uint32_t)pose_seq < o.frames)) {
        const int64_t t_ask = rp_hal_now_us();
        hst = source_grab(&src, &g_set);
        if (hst == RP_HAL_E_END) {
            break;
        }
        const int64_t t_grab = rp_hal_now_us();
        if (hst != RP_HAL_OK) {
            if (hst != RP_HAL_E_TIMEOUT && ++grab_errors > MAX_GRAB_ERRORS) {
                fprintf(stderr, "rigpose: camera source failed: %s\n", rp_hal_status_str(hst));
                exit_code = EXIT_SOURCE_FAILED;
                break;
            }
            /* Tell listeners which cameras are missing; keep going (devices are retried). */
            for (int k = 0; k < g_cfg.rig.n_cams; ++k) {
                acc.cam_state[k] = (int8_t)(g_set.cam[k].flags & CAM_STATE_BITS);
            }
            rigpose_status_t sm;
            fill_status(&sm, &acc, &g_cfg, &g_set, hst, NULL, &est, pose_seq - 1, 0.0f, 0.0f,
                        t_grab);
            (void)rigpose_status_t_publish(lcm, g_cfg.status_channel, &sm);
            continue;
        }
        grab_errors = 0;

        const rp_frameset_t *fs = NULL;
        const rp_status_t st = estimator_step(&g_set, &est, &fs);

        rigpose_pose_t pm;
        fill_pose(&pm, &g_set, &est, st, pose_seq, g_cfg.rig.n_cams, g_cfg.pipe.layout);
        const int64_t t_pub = rp_hal_now_us();
        pm.publish_utime = t_pub;
        if (rigpose_pose_t_publish(lcm, g_cfg.pose_channel, &pm) != 0) {
            fprintf(stderr, "rigpose: LCM publish on %s failed\n", g_cfg.pose_channel);
        }
        /* Latency from the frame's capture time, when the source stamps on the HAL clock
         * (v4l2, sim, paced replay); a source replaying recorded stamps as fast as it can is
         * timed from the moment its set was asked for. */
        const int64_t t_frame =
            (g_set.utime <= t_pub && g_set.utime >= t_ask - 60000000) ? g_set.utime : t_ask;
        const float lat_ms = (float)((double)(t_pub - t_frame) * 1e-3);
        if (g_cfg.image_channel[0] != '\0') {
            publish_images(lcm, g_cfg.image_channel, &g_set, pose_seq);
        }
        const float proc_ms = (float)((double)(t_pub - t_grab) * 1e-3);
        if (n_lat < LAT_KEEP) {
            g_lat_ms[n_lat++] = lat_ms;
        }
        if (pose_seq == 0) {
            t_first = t_pub;
        }
        t_last = t_pub;

        /* Status: every status_every sets, and at once when a camera changes state. */
        int changed = 0;
        int8_t prev_state[RP_MAX_CAMS];
        for (int k = 0; k < g_cfg.rig.n_cams; ++k) {
            const int8_t s = (int8_t)(g_set.cam[k].flags & CAM_STATE_BITS);
            prev_state[k] = acc.cam_state[k];
            changed |= s != acc.cam_state[k];
            acc.cam_state[k] = s;
            if (!(g_set.cam[k].flags & RP_HAL_CAM_MISSING)) {
                acc.frames[k]++;
                acc.period_frames[k]++;
            }
        }
        acc.period_sets++;
        acc.lat_max_ms = lat_ms > acc.lat_max_ms ? lat_ms : acc.lat_max_ms;
        acc.n_lost += (est.flags & RP_EST_LOST) ? 1 : 0;
        acc.n_reinit += (est.flags & RP_EST_REINIT) ? 1 : 0;
        acc.n_cov_reset += (est.flags & RP_EST_COV_RESET) ? 1 : 0;
        if (changed || (uint32_t)pose_seq % g_cfg.status_every == 0) {
            rigpose_status_t sm;
            fill_status(&sm, &acc, &g_cfg, &g_set, hst, fs, &est, pose_seq, lat_ms, proc_ms,
                        t_pub);
            (void)rigpose_status_t_publish(lcm, g_cfg.status_channel, &sm);
            if (changed && pose_seq > 0) {
                for (int k = 0; k < g_cfg.rig.n_cams; ++k) {
                    if (acc.cam_state[k] != prev_state[k]) {
                        printf("rigpose: camera %d (%s): %s (reported on the status channel)\n",
                               k, g_cfg.cam_name[k], cam_state_str(acc.cam_state[k]));
                    }
                }
            }
        }

        /* Error against the truth, per axis (frame 0 defines the world: left out). */
        double et = 0.0, er = 0.0;
        if (g_set.has_truth) {
            for (int i = 0; i < 6; ++i) {
                double d = (double)est.p[i] - (double)g_set.truth[i];
                if (i >= 3) {
                    d = remainder(d, 2.0 * 3.14159265358979323846); /* wrapped to [-pi, pi] */
                }
                if (pose_seq > 0) {
                    err_sum[i] += fabs(d);
                }
                if (i < 3) {
                    et += d * d;
                } else {
                    er += d * d;
                }
            }
            n_err += pose_seq > 0 ? 1u : 0u;
        }
        if (!o.quiet && (uint32_t)pose_seq % o.print_every == 0) {
            char fl[64];
            flag_names(est.flags, fl, sizeof fl);
            unsigned feats = 0;
            for (int k = 0; k < RP_MAX_CAMS; ++k) {
                feats += est.n_used[k];
            }
            printf("%6d %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f  %-16s %5u %8.3f", pose_seq,
                   (double)est.p[0], (double)est.p[1], (double)est.p[2], (double)est.p[3],
                   (double)est.p[4], (double)est.p[5], fl, feats, (double)lat_ms);
            if (g_set.has_truth) {
                printf("  %9.6f %9.6f", sqrt(et), sqrt(er));
            }
            printf("\n");
        }
        pose_seq++;
    }

    source_close(&src);
    lcm_destroy(lcm);

    /* Summary. */
    const double span_s = (double)(t_last - t_first) * 1e-6;
    const double fps = (pose_seq > 1 && span_s > 0.0) ? (double)(pose_seq - 1) / span_s : 0.0;
    double p50 = 0.0, p99 = 0.0;
    if (n_lat > 0) {
        qsort(g_lat_ms, n_lat, sizeof g_lat_ms[0], cmp_float);
        p50 = (double)g_lat_ms[(n_lat - 1) / 2];
        p99 = (double)g_lat_ms[(size_t)((double)(n_lat - 1) * 0.99 + 0.5)];
    }
    printf("rigpose: %d poses published on %s, %.1f sets/s, latency frame->publish p50 %.3f ms, "
           "p99 %.3f ms%s\n",
           pose_seq, g_cfg.pose_channel, fps, p50, p99, g_stop ? " (stopped by signal)" : "");
    if (n_err > 0) {
        printf("rigpose: mean abs error over sets 1..%u vs the source's truth: tx %.6f ty %.6f "
               "tz %.6f m, alpha %.6f beta %.6f gamma %.6f rad\n",
               n_err, err_sum[0] / n_err, err_sum[1] / n_err, err_sum[2] / n_err,
               err_sum[3] / n_err, err_sum[4] / n_err, err_sum[5] / n_err);
    }
    if (o.stats_json != NULL) {
        FILE *f = fopen(o.stats_json, "w");
        if (f == NULL) {
            fprintf(stderr, "rigpose: %s: %s\n", o.stats_json, strerror(errno));
        } else {
            fprintf(f, "{\"daemon_latency_ms_p50\": %.4f, \"daemon_latency_ms_p99\": %.4f, "
                       "\"daemon_fps\": %.1f}\n",
                    p50, p99, fps);
            fclose(f);
        }
    }
    return exit_code;
}
