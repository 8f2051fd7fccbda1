/*
 * rigpose - the pose daemon: camera source (HAL) -> front end -> estimator -> LCM.
 *
 *   rigpose --config FILE [--frames N] [options]     (rigpose --help for all of them)
 *
 * Each frame set from the configured source becomes one rigpose.pose_t on the pose channel;
 * a rigpose.status_t goes out every lcm.status_every sets and whenever a camera changes state.
 * Every source goes through the HAL's rp_hal_open / rp_hal_grab, but `lcm` (the features of
 * rigpose-frontend processes, rp_lcmsrc.h), which has the same shape of calls. Sets of images
 * (v4l2, replay) go through the core's image pipeline (rp_pipe.h); sets of features (sim, lcm)
 * go to the same pipeline's estimator directly (rp_est.h). With a source that knows the truth (sim), every printed pose carries its error
 * against it, and the run ends with the mean absolute error per axis (as Table 1 of the paper
 * reports it).
 *
 * This file holds main and the loop; the pieces are
 *   rp_args.h     the command line and its overrides of the configuration
 *   rp_est.h      the configured estimator
 *   rp_publish.h  the LCM messages, encoded into static buffers
 *   rp_stats.h    what the status channel and the summary report
 *
 * Exit codes (daemon/README.md):
 *   0  done: --frames reached, the source ended, or SIGINT / SIGTERM / SIGHUP / SIGPIPE (the
 *      summary is printed; on SIGPIPE, stdout being gone, on stderr)
 *   1  usage error (bad command line)
 *   2  invalid configuration file (the message names file, line and key)
 *   3  LCM could not be set up (bad URL, no network for udpm)
 *   4  the camera source could not be opened or started (the HAL's message: device, file)
 *   5  the estimator refused the configuration (rig or method)
 *   6  the camera source failed for good while running (the last failure's message)
 *   7  the --stats-json file could not be written at the end (it is tried at start too: a
 *      path that cannot be written then is a usage error, 1)
 *
 * Every failure is said once, on stderr, in the HAL's words (rp_hal_errmsg: file and line,
 * camera, device, errno): a failed open or start; each failed grab and each set delivered
 * degraded for a reason (cameras missing: a replay image that could not be read, a v4l2 camera
 * lost; a malformed truth.csv row skipped), rate-limited (SAY_BURST lines, then one per SAY_EVERY_US, with the count of lines
 * not shown); and on stdout one line per change of a camera's state and of the estimator's
 * step status or LOST flag (rate-limited alike).
 *
 * No heap in the per-frame path: every buffer is static or on the stack.
 */
#include <errno.h>
#include <lcm/lcm.h>
#include <signal.h>
#include <unistd.h>
#include <stdio.h>
#include <string.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_esc.h"
#include "rigpose/rp_hal.h"
#include "rigpose/rp_hal_sim.h"
#include "rp_args.h"
#include "rp_est.h"
#include "rp_feats.h"
#include "rp_lcmsrc.h"
#include "rp_publish.h"
#include "rp_stats.h"

/* Grab errors in a row (not timeouts) after which the source counts as failed for good. */
#define MAX_GRAB_ERRORS 50

/* The rate limit of repeated messages (source failures, camera state changes): SAY_BURST
 * lines at once, then one more per SAY_EVERY_US. */
#define SAY_BURST 10
#define SAY_EVERY_US 5000000

/* ---- static state (the daemon's memory) ------------------------------------------------------ */

static volatile sig_atomic_t g_stop;
static rp_config_t g_cfg;
static rp_est_t g_est;      /* the image pipeline: images, or features from the sim source */
static rp_hal_set_t g_set;
static rp_lsrc_t g_lsrc;    /* source.kind lcm: frame sets from the front ends' messages */
static int g_lsrc_open;
static rp_stats_t g_stats;
/* The features' channel: the image channel's name + "_FEATURES" (lcm_types/rigpose_features_t). */
static char g_feat_channel[RP_CFG_CHANNEL_MAX + 16];

/* The estimator's clock offsets into a status message (rp_pipe_time_offsets). */
static void fill_offsets(rigpose_status_t *sm)
{
    rp_real off[RP_MAX_CAMS], sig[RP_MAX_CAMS];
    if (rp_pipe_time_offsets(&g_est.pipe, off, sig) == RP_OK) {
        rp_stats_fill_offsets(sm, off, sig, g_cfg.rig.n_cams);
    }
}

/* A token bucket: credit_us of waiting earned, at most SAY_BURST lines' worth. */
typedef struct {
    int64_t credit_us, t_us;
    uint32_t not_shown; /* lines held back since the last one shown */
    uint8_t started;
} say_limit_t;

static say_limit_t g_say_src;         /* the source's failure messages */
static say_limit_t g_say_cam;         /* camera state changes */
static say_limit_t g_say_est;         /* estimator changes */
static rp_status_t g_said_est_st;     /* the estimator step's status as last printed */
static uint8_t g_said_lost;           /* LOST as last printed */
static int8_t g_said_state[RP_MAX_CAMS]; /* each camera's state as last printed (0: ok) */
static uint32_t g_n_grab_failed, g_n_timeouts, g_n_degraded; /* for the closing line */

/* ---- who publishes: lcm.instance, and another daemon on the same pose channel ---------------- */

static int8_t g_instance[32];      /* pose_t.instance of this daemon, NUL-padded */
static uint32_t g_n_foreign;       /* poses heard from another instance on our pose channel */
static int g_listening;            /* subscribed to our own pose channel (udpm, memq) */
static int8_t g_said_foreign[32];  /* the other instance last warned about */

/* s with control characters and invalid UTF-8 written \xNN (rp_esc.h), for echoing what a
 * user or the file gave (paths, URLs, channel and camera names): a message cannot move the
 * terminal. One of 8 rotating buffers, so several may appear in one printf (main thread only). */
static const char *esc(const char *s)
{
    static char buf[8][4 * RP_CFG_URL_MAX];
    static unsigned k;
    char *b = buf[k++ % 8u];
    rp_esc_text(b, sizeof buf[0], s != NULL ? s : "(null)");
    return b;
}

/* This daemon's instance (NUL-padded, not terminated at 32 characters), escaped. */
static const char *instance_esc(void)
{
    char t[sizeof g_instance + 1];
    memcpy(t, g_instance, sizeof g_instance);
    t[sizeof g_instance] = '\0';
    return esc(t);
}


/* A pose heard on our own pose channel: ours (udpm loops back), or another daemon's. */
static void on_pose_heard(const lcm_recv_buf_t *rbuf, const char *channel,
                          const rigpose_pose_t *msg, void *user)
{
    (void)rbuf;
    (void)user;
    if (memcmp(msg->instance, g_instance, sizeof g_instance) == 0) {
        return;
    }
    g_n_foreign++;
    if (memcmp(msg->instance, g_said_foreign, sizeof g_said_foreign) != 0) {
        memcpy(g_said_foreign, msg->instance, sizeof g_said_foreign);
        char other[sizeof g_instance + 1];
        for (size_t i = 0; i < sizeof g_instance; ++i) { /* printable only: it comes from outside */
            const unsigned char ch = (unsigned char)msg->instance[i];
            other[i] = ch == 0 ? '\0' : (ch < 0x20 || ch >= 0x7f) ? '?' : (char)ch;
        }
        other[sizeof g_instance] = '\0';
        fprintf(stderr, "rigpose: another publisher (instance '%s') sends poses on %s, where this "
                "daemon ('%s') publishes: their poses mix; give each its own "
                "lcm.pose_channel (counted in status_t.n_foreign_poses)\n", other, esc(channel),
                instance_esc());
    }
}

static void on_signal(int sig)
{
    g_stop = sig; /* SIGINT, SIGTERM, SIGHUP, SIGPIPE: all non-zero */
}

/* The configured method: its name, and its code in the messages (pose_t.METHOD_*). */
static const char *method_name(const rp_config_t *cfg) { return rp_pipe_layout_name(cfg->pipe.layout); }
static int8_t method_code(const rp_config_t *cfg) { return (int8_t)cfg->pipe.layout; }

/* ---- saying what happened ----------------------------------------------------------------------- */

/* 1 if a line may go out now; else it is counted in l->not_shown. */
static int say_ok(say_limit_t *l, int64_t now_us)
{
    const int64_t full = (int64_t)SAY_BURST * SAY_EVERY_US;
    if (!l->started) {
        l->started = 1;
        l->credit_us = full;
    } else if (now_us > l->t_us) {
        const int64_t earned = now_us - l->t_us;
        l->credit_us = earned >= full - l->credit_us ? full : l->credit_us + earned;
    }
    l->t_us = now_us;
    if (l->credit_us >= SAY_EVERY_US) {
        l->credit_us -= SAY_EVERY_US;
        return 1;
    }
    l->not_shown++;
    return 0;
}

/* Appends how many lines of l were held back since its last line shown, if any. */
static void say_not_shown(FILE *f, say_limit_t *l)
{
    if (l->not_shown > 0) {
        fprintf(f, " (%u similar lines not shown before this one)", l->not_shown);
        l->not_shown = 0;
    }
}

/* The source's message after grab status hst of frame set seq (rate-limited); msg the HAL's
 * words. */
static void say_source(int32_t seq, rp_hal_status_t hst, const char *msg)
{
    if (!say_ok(&g_say_src, rp_hal_now_us())) {
        return;
    }
    if (hst == RP_HAL_OK) {
        fprintf(stderr, "rigpose: set %d: camera source: degraded set: %s", seq, msg);
    } else {
        fprintf(stderr, "rigpose: set %d: camera source: %s: %s", seq, rp_hal_status_str(hst),
                msg[0] != '\0' ? msg : "(no message)");
    }
    say_not_shown(stderr, &g_say_src);
    fputc('\n', stderr);
}

static const char *cam_state_str(int state); /* below, with the printing */

/* One line per camera whose state differs from the one last printed for it (rate-limited; a
 * change held back is said with the next line that goes out). */
static void say_cam_changes(const rp_hal_set_t *set, int32_t seq)
{
    for (uint8_t k = 0; k < g_cfg.rig.n_cams && k < set->n_cams; ++k) {
        const int8_t st = (int8_t)(set->cam[k].flags &
                                   (RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE | RP_HAL_CAM_DROPPED));
        if (st == g_said_state[k] || !say_ok(&g_say_cam, rp_hal_now_us())) {
            continue;
        }
        g_said_state[k] = st;
        printf("rigpose: set %d: camera %d (%s): %s (reported on the status channel)", seq, k,
               esc(g_cfg.cam_name[k]), cam_state_str(st));
        say_not_shown(stdout, &g_say_cam);
        putchar('\n');
    }
}

/* One line when the estimator's step status or its LOST flag changes (rate-limited). */
static void say_estimator_changes(int32_t seq, rp_status_t st, uint32_t flags)
{
    const uint8_t lost = (flags & RP_EST_LOST) != 0;
    if (st != g_said_est_st && say_ok(&g_say_est, rp_hal_now_us())) {
        if (st != RP_OK) {
            printf("rigpose: set %d: estimator: step failed: %s", seq, rp_status_str(st));
        } else {
            printf("rigpose: set %d: estimator: steps ok again (was: %s)", seq,
                   rp_status_str(g_said_est_st));
        }
        g_said_est_st = st;
        say_not_shown(stdout, &g_say_est);
        putchar('\n');
    }
    if (lost != g_said_lost && say_ok(&g_say_est, rp_hal_now_us())) {
        printf("rigpose: set %d: estimator: %s", seq,
               lost ? "LOST (the pose is not from the images; pose_t.flags)" : "tracking again");
        g_said_lost = lost;
        say_not_shown(stdout, &g_say_est);
        putchar('\n');
    }
}

/* ---- the camera source: every kind through the HAL ------------------------------------------- */

/* Open and start cfg's source; the sim's options (noise, a vanishing camera) from cfg->sim.
 * On failure the message names the source and what went wrong; *src is NULL. */
static rp_hal_status_t source_open(const rp_config_t *cfg, rp_hal_source_t **src)
{
    static rp_hal_sim_opts_t so; /* read by rp_hal_open only */
    rp_hal_cfg_t hc = cfg->hal;
    hc.partial_sets = 1; /* replay: an unreadable image costs its camera only, not the set */
    if (hc.kind == RP_HAL_SRC_SIM) {
        so = rp_hal_sim_default_opts();
        so.noise_px = cfg->sim.noise_px;
        so.drop_cam = cfg->sim.drop_cam;
        so.drop_from = cfg->sim.drop_from;
        so.motion = cfg->sim.motion;
        hc.sim_opts = &so;
    }
    rp_hal_status_t st = rp_hal_open(src, &hc);
    if (st != RP_HAL_OK) {
        fprintf(stderr, "rigpose: %s: camera source: %s: %s\n", esc(cfg->path),
                rp_hal_status_str(st), rp_hal_errmsg(NULL));
        return st;
    }
    st = rp_hal_start(*src);
    if (st != RP_HAL_OK) {
        fprintf(stderr, "rigpose: %s: camera source: %s: %s\n", esc(cfg->path),
                rp_hal_status_str(st), rp_hal_errmsg(*src));
        rp_hal_close(*src);
        *src = NULL;
    }
    return st;
}

/* Source kind lcm (not the HAL's): subscribe on the daemon's own LCM. */
static rp_hal_status_t source_open_lcm(const rp_config_t *cfg, lcm_t *lcm)
{
    const rp_hal_status_t st = rp_lsrc_open(&g_lsrc, lcm, cfg);
    if (st != RP_HAL_OK) {
        fprintf(stderr, "rigpose: %s: camera source: %s: %s\n", cfg->path,
                rp_hal_status_str(st), rp_lsrc_errmsg(&g_lsrc));
        return st;
    }
    g_lsrc_open = 1;
    return RP_HAL_OK;
}

static rp_hal_status_t source_grab(rp_hal_source_t *src, rp_hal_set_t *set)
{
    return g_lsrc_open ? rp_lsrc_grab(&g_lsrc, set) : rp_hal_grab(src, set);
}

static const char *source_errmsg(const rp_hal_source_t *src)
{
    return g_lsrc_open ? rp_lsrc_errmsg(&g_lsrc) : rp_hal_errmsg(src);
}

static void source_close(rp_hal_source_t *src)
{
    if (g_lsrc_open) {
        rp_lsrc_close(&g_lsrc);
        g_lsrc_open = 0;
    }
    if (src != NULL) {
        /* ignored: best effort before closing: the summary follows whatever it says */
        (void)rp_hal_stop(src);
        rp_hal_close(src);
    }
}

/* ---- the estimator: features directly, images through the pipeline --------------------------- */

/* Run the estimator on one set; fs_out receives the features it used (for the status). */
static rp_status_t estimator_step(const rp_hal_set_t *set, rp_estimate_t *est,
                                  const rp_frameset_t **fs_out)
{
    if (set->payload == RP_HAL_PAYLOAD_FEATS) {
        *fs_out = set->feats;
        return rp_est_step(&g_est, set->feats, est);
    }
    /* Each camera at its own capture time (v4l2's kernel stamp, replay's recorded time); the
     * set's time stays the HAL's. A camera without an image is flagged RP_FS_NO_IMAGE by the
     * pipeline. */
    const rp_image_t *img[RP_MAX_CAMS];
    int64_t cam_utime[RP_MAX_CAMS];
    for (uint8_t k = 0; k < RP_MAX_CAMS; ++k) {
        img[k] = (k < set->n_cams && set->cam[k].img.data != NULL) ? &set->cam[k].img : NULL;
        cam_utime[k] = img[k] != NULL ? set->cam[k].utime : set->utime;
    }
    return rp_est_step_images(&g_est, img, cam_utime, set->n_cams, set->utime, est, fs_out);
}

/* ---- printing -------------------------------------------------------------------------------- */

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

static void flag_names(uint32_t f, char *out, size_t cap)
{
    static const char *const names[] = {"INIT", "TRACK", "REINIT", "DEGRADED",
                                        "LOST", "GATED", "COVRESET", "SCALEWEAK", "HELD"};
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

static void print_header(void)
{
    printf("%6s %9s %9s %9s %9s %9s %9s  %-16s %5s %8s%s\n", "seq", "tx m", "ty m", "tz m",
           "alpha", "beta", "gamma", "flags", "feats", "lat ms", "   err_t m   err_r rad");
}

static void print_pose(int32_t seq, const rp_estimate_t *est, float lat_ms,
                       const rp_stats_set_t *r)
{
    char fl[64];
    flag_names(est->flags, fl, sizeof fl);
    unsigned feats = 0;
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        feats += est->n_used[k];
    }
    printf("%6d %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f  %-16s %5u %8.3f", seq, (double)est->p[0],
           (double)est->p[1], (double)est->p[2], (double)est->p[3], (double)est->p[4],
           (double)est->p[5], fl, feats, (double)lat_ms);
    if (r->has_err) {
        printf("  %9.6f %9.6f", r->err_t_m, r->err_r_rad);
    }
    printf("\n");
}

/* The run's figures on stdout and, if asked, in a JSON file. -1 if that file failed. */
static int print_summary(rp_stats_t *st, const char *channel, const char *stats_json)
{
    rp_stats_summary_t s;
    rp_stats_summary(st, &s);
    printf("rigpose: %u poses published on %s, %.1f sets/s, latency frame->publish p50 %.3f ms, "
           "p99 %.3f ms (all sets, 1 %% bins)%s\n",
           s.n_poses, esc(channel), s.fps, s.lat_p50_ms, s.lat_p99_ms,
           g_stop == SIGHUP ? " (stopped by signal SIGHUP)"
           : g_stop == SIGPIPE ? " (stopped by signal SIGPIPE: stdout closed)"
           : g_stop ? " (stopped by signal)" : "");
    if (s.n_err > 0) {
        printf("rigpose: mean abs error over sets 1..%u vs the source's truth: tx %.6f ty %.6f "
               "tz %.6f m, alpha %.6f beta %.6f gamma %.6f rad\n",
               s.n_err, s.err_mean[0], s.err_mean[1], s.err_mean[2], s.err_mean[3],
               s.err_mean[4], s.err_mean[5]);
    }
    if (stats_json == NULL) {
        return 0;
    }
    FILE *f = fopen(stats_json, "w");
    if (f == NULL) {
        fprintf(stderr, "rigpose: %s: %s\n", esc(stats_json), strerror(errno));
        return -1;
    }
    fprintf(f, "{\"daemon_latency_ms_p50\": %.4f, \"daemon_latency_ms_p99\": %.4f, "
               "\"daemon_fps\": %.1f}\n",
            s.lat_p50_ms, s.lat_p99_ms, s.fps);
    if (fclose(f) != 0) {
        fprintf(stderr, "rigpose: %s: %s\n", esc(stats_json), strerror(errno));
        return -1;
    }
    return 0;
}

/* ---- the loop ---------------------------------------------------------------------------------- */

static void publish_status(lcm_t *lcm, rigpose_status_t *m)
{
    memcpy(m->instance, g_instance, sizeof m->instance);
    m->n_foreign_poses = (int32_t)g_n_foreign;
    const rp_pub_status_t ps = rp_pub_status(lcm, g_cfg.status_channel, m);
    if (ps != RP_PUB_OK) {
        fprintf(stderr, "rigpose: LCM status on %s: %s\n", esc(g_cfg.status_channel),
                rp_pub_status_str(ps));
    }
}

/* Grab, estimate, publish until --frames, the source's end, a signal or the source failing for
 * good. Returns the exit code. */
static int run(const rp_args_t *o, rp_hal_source_t *src, lcm_t *lcm)
{
    rp_estimate_t est;
    memset(&est, 0, sizeof est);
    uint32_t grab_errors = 0;
    /* ignored: fits: 63 characters of channel and _FEATURES */
    (void)snprintf(g_feat_channel, sizeof g_feat_channel, "%s_FEATURES", g_cfg.image_channel);

    while (!g_stop && (o->frames == 0 || g_stats.n_sets < o->frames)) {
        const int32_t seq = (int32_t)g_stats.n_sets;
        const int64_t t_ask = rp_hal_now_us();
        const rp_hal_status_t hst = source_grab(src, &g_set);
        if (hst == RP_HAL_E_END) {
            break;
        }
        const int64_t t_grab = rp_hal_now_us();
        if (hst != RP_HAL_OK) {
            g_n_grab_failed++;
            g_n_timeouts += hst == RP_HAL_E_TIMEOUT;
            if (hst != RP_HAL_E_TIMEOUT && ++grab_errors > MAX_GRAB_ERRORS) {
                fprintf(stderr, "rigpose: %s: camera source failed for good (%d failing grabs in "
                        "a row), the last: %s: %s\n", esc(g_cfg.path), MAX_GRAB_ERRORS + 1,
                        rp_hal_status_str(hst), source_errmsg(src));
                return EXIT_SOURCE_FAILED;
            }
            say_source(seq, hst, source_errmsg(src));
            if (hst == RP_HAL_E_TIMEOUT) { /* the set tells which cameras came */
                say_cam_changes(&g_set, seq);
            }
            /* Tell listeners which cameras are missing; keep going (devices are retried). */
            rp_stats_grab_failed(&g_stats, &g_set);
            rigpose_status_t sm;
            rp_stats_fill_status(&g_stats, &sm, &g_set, hst, NULL, &est, 0.0f, 0.0f, t_grab);
            fill_offsets(&sm);
            publish_status(lcm, &sm);
            continue;
        }
        grab_errors = 0;
        if (source_errmsg(src)[0] != '\0') { /* a degraded set (cameras missing...), and why */
            g_n_degraded++;
            say_source(seq, hst, source_errmsg(src));
        }
        say_cam_changes(&g_set, seq);

        const rp_frameset_t *fs = NULL;
        const rp_status_t st = estimator_step(&g_set, &est, &fs);
        say_estimator_changes(seq, st, est.flags);

        rigpose_pose_t pm;
        rp_pub_fill_pose(&pm, &g_set, &est, st, seq, g_cfg.rig.n_cams, method_code(&g_cfg));
        memcpy(pm.instance, g_instance, sizeof pm.instance);
        const int64_t t_pub = rp_hal_now_us();
        pm.publish_utime = t_pub;
        const rp_pub_status_t ps = rp_pub_pose(lcm, g_cfg.pose_channel, &pm);
        if (ps != RP_PUB_OK) {
            fprintf(stderr, "rigpose: LCM publish on %s failed: %s\n", esc(g_cfg.pose_channel),
                    rp_pub_status_str(ps));
        }
        /* Latency from the frame's capture time, when the source stamps on the HAL clock
         * (v4l2, sim, paced replay); a source replaying recorded stamps as fast as it can is
         * timed from the moment its set was asked for. */
        const int64_t t_frame =
            (g_set.utime <= t_pub && g_set.utime >= t_ask - 60000000) ? g_set.utime : t_ask;
        const float lat_ms = (float)((double)(t_pub - t_frame) * 1e-3);
        if (g_cfg.image_channel[0] != '\0') {
            int bad_cam = -1;
            const rp_pub_status_t is =
                rp_pub_set_images(lcm, g_cfg.image_channel, &g_set, seq, &bad_cam);
            if (is != RP_PUB_OK) {
                fprintf(stderr, "rigpose: LCM image of camera %d (%s) on %s: %s\n", bad_cam,
                        bad_cam >= 0 ? esc(g_cfg.cam_name[bad_cam]) : "?", esc(g_cfg.image_channel),
                        rp_pub_status_str(is));
            }
            const rp_pub_status_t fst = fs == NULL ? RP_PUB_OK
                : rp_pub_set_features(lcm, g_feat_channel, fs, g_cfg.rig.n_cams, seq, &bad_cam);
            if (fst != RP_PUB_OK) {
                fprintf(stderr, "rigpose: LCM features of camera %d on %s: %s\n", bad_cam,
                        esc(g_feat_channel), rp_pub_status_str(fst));
            }
        }
        const float proc_ms = (float)((double)(t_pub - t_grab) * 1e-3);
        if (g_listening) {
            while (lcm_handle_timeout(lcm, 0) > 0) { /* what arrived on our pose channel */
            }
        }

        rp_stats_set_t r;
        /* ignored: only NULL arguments fail */
        (void)rp_stats_set(&g_stats, &g_set, &est, lat_ms, t_pub, &r);

        /* Status: every status_every sets, and at once when a camera changes state. */
        if (r.changed || (uint32_t)seq % g_cfg.status_every == 0) {
            rigpose_status_t sm;
            rp_stats_fill_status(&g_stats, &sm, &g_set, hst, fs, &est, lat_ms, proc_ms, t_pub);
            fill_offsets(&sm);
            publish_status(lcm, &sm);
        }
        if (!o->quiet && (uint32_t)seq % o->print_every == 0) {
            print_pose(seq, &est, lat_ms, &r);
        }
    }
    return EXIT_DONE;
}

/* ---- main -------------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    rp_args_t o;
    const rp_args_status_t ast = rp_args_parse(argc, argv, &o, stderr);
    if (ast == RP_ARGS_HELP) {
        rp_args_usage(stdout);
        return EXIT_DONE;
    }
    if (ast != RP_ARGS_OK) {
        rp_args_usage(stderr);
        return EXIT_USAGE;
    }
    setvbuf(stdout, NULL, _IOLBF, 0);

    char err[RP_CFG_ERR_MAX];
    const rp_cfg_status_t cst = rp_config_load(o.config, &g_cfg, err, sizeof err);
    if (cst != RP_CFG_OK) {
        fprintf(stderr, "rigpose: invalid configuration: %s\n", err);
        return EXIT_CONFIG;
    }
    if (rp_args_apply(&o, &g_cfg, stderr) != RP_ARGS_OK) {
        return EXIT_USAGE;
    }
    if (o.stats_json != NULL) { /* said now, not after the run */
        FILE *f = fopen(o.stats_json, "a");
        if (f == NULL) {
            fprintf(stderr, "rigpose: --stats-json %s: %s\n", esc(o.stats_json), strerror(errno));
            return EXIT_USAGE;
        }
        fclose(f);
    }

    const rp_status_t est_st = rp_est_init(&g_est, &g_cfg);
    if (est_st != RP_OK) {
        fprintf(stderr, "rigpose: %s: method %s refused the configuration: %s\n", esc(o.config),
                method_name(&g_cfg), rp_status_str(est_st));
        return EXIT_ESTIMATOR;
    }

    lcm_t *lcm = lcm_create(g_cfg.lcm_url);
    if (lcm == NULL) {
        fprintf(stderr, "rigpose: LCM: cannot use '%s'\n", esc(g_cfg.lcm_url));
        rp_est_close(&g_est);
        return EXIT_LCM;
    }
    rp_feats_instance(g_cfg.instance, g_instance);
    /* Listen on our own pose channel where a second publisher could be heard (not on a log
     * file being written). */
    if ((strncmp(g_cfg.lcm_url, "udpm://", 7) == 0 || strncmp(g_cfg.lcm_url, "memq://", 7) == 0) &&
        rigpose_pose_t_subscribe(lcm, g_cfg.pose_channel, on_pose_heard, NULL) != NULL) {
        g_listening = 1;
    }

    rp_hal_source_t *src = NULL;
    g_cfg.hal.run_jobs = rp_est_hal_jobs; /* each camera's image decoded on the same threads */
    g_cfg.hal.run_jobs_ctx = &g_est;
    if ((g_cfg.hal.kind == RP_HAL_SRC_LCM ? source_open_lcm(&g_cfg, lcm)
                                          : source_open(&g_cfg, &src)) != RP_HAL_OK) {
        lcm_destroy(lcm);
        rp_est_close(&g_est);
        return EXIT_SOURCE;
    }

    rp_feats_stop_signals(on_signal); /* SIGPIPE: the summary then goes to stderr (below) */

    printf("rigpose: %s: instance '%s', source %s, %u cameras, method %s, %u thread%s, "
           "LCM %s (%s, %s)\n",
           esc(o.config), instance_esc(),
           g_cfg.hal.kind == RP_HAL_SRC_SIM    ? "sim"
           : g_cfg.hal.kind == RP_HAL_SRC_V4L2 ? "v4l2"
           : g_cfg.hal.kind == RP_HAL_SRC_LCM  ? "lcm (rigpose-frontend features)"
                                               : "replay",
           g_cfg.rig.n_cams, method_name(&g_cfg), rp_est_threads(&g_est),
           rp_est_threads(&g_est) == 1 ? "" : "s", esc(g_cfg.lcm_url), esc(g_cfg.pose_channel),
           esc(g_cfg.status_channel));
    if (!o.quiet) {
        print_header();
    }

    /* ignored: only NULL arguments fail */
    (void)rp_stats_init(&g_stats, g_cfg.hal.kind, method_code(&g_cfg), g_cfg.rig.n_cams,
                        rp_hal_now_us());
    const int exit_code = run(&o, src, lcm);

    source_close(src);
    rp_est_close(&g_est);
    lcm_destroy(lcm);
    if (g_n_grab_failed > 0 || g_n_degraded > 0) {
        fprintf(stderr, "rigpose: camera source: %u failed grabs (%u of them timeouts), %u sets "
                "delivered degraded for a reason", g_n_grab_failed, g_n_timeouts, g_n_degraded);
        if (g_say_src.not_shown > 0) {
            fprintf(stderr, "; the last %u of these messages not shown (rate limit)",
                    g_say_src.not_shown);
        }
        fputc('\n', stderr);
    }
    if (g_stop == SIGPIPE) {
        (void)dup2(STDERR_FILENO, STDOUT_FILENO); /* the summary where someone still reads */
        clearerr(stdout);
    }
    if (print_summary(&g_stats, g_cfg.pose_channel, o.stats_json) != 0 && exit_code == EXIT_DONE) {
        return EXIT_STATS;
    }
    return exit_code;
}
