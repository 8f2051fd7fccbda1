/*
 * rp_hal_sim.c - the HAL's sim source (rp_hal_sim.h): frame sets of features and the true pose
 * from the feature-level simulation of the paper's protocol. Its typed API (rp_hal_sim_*) and
 * its table for rp_hal_open (rp_hal_sim_ops) are the same functions.
 */
#include "rigpose/rp_hal_sim.h"

#include <string.h>

#include "rp_hal_priv.h"
#include "rp_sim.h"

struct rp_hal_sim {
    uint8_t open;      /* 1 between open and close */
    uint8_t started;   /* 1 between start and stop */
    rp_hal_cfg_t cfg;
    rp_hal_sim_opts_t opts;
    rp_sim_run_t run;  /* points and trajectory (allocated once, at open) */
    uint32_t next;     /* next frame set of the run */
    uint32_t seq;      /* sets delivered since start */
    int64_t t0_us;     /* HAL clock at start */
    int64_t frame_us;  /* simulated frame interval, us */
    uint32_t drops[RP_MAX_CAMS];
    rp_frameset_t fs;  /* the features of the last set (set->feats points here) */
    char *err;         /* where failures are told (RP_HAL_ERR_MAX bytes): the HAL source's
                        * buffer when opened through rp_hal_open, else g_err */
};

/* One source per process (rp_hal.h): the state is static, as on the board. */
static rp_hal_sim_t g_sim;
static char g_err[RP_HAL_ERR_MAX]; /* messages of the typed API's calls */

rp_hal_sim_opts_t rp_hal_sim_default_opts(void)
{
    rp_hal_sim_opts_t o;
    o.noise_px = 0.5;
    o.drop_cam = -1;
    o.drop_from = 0;
    o.motion = (int8_t)RP_SIM_MOTION_PAPER;
    return o;
}

/* Open into g_sim, telling a failure in err (RP_HAL_ERR_MAX bytes, kept for later calls). */
static rp_hal_status_t sim_open(rp_hal_sim_t **sim, const rp_hal_cfg_t *cfg,
                                const rp_hal_sim_opts_t *opts, char *err)
{
    if (sim == NULL || cfg == NULL) {
        return rp_hal_fail(err, RP_HAL_E_ARG, "sim: NULL argument");
    }
    *sim = NULL;
    const rp_hal_sim_opts_t o = opts != NULL ? *opts : rp_hal_sim_default_opts();
    if (cfg->kind != RP_HAL_SRC_SIM) {
        return rp_hal_fail(err, RP_HAL_E_ARG, "sim: source kind %d is not sim", (int)cfg->kind);
    }
    if (cfg->n_cams != RP_SIM_NCAMS) {
        return rp_hal_fail(err, RP_HAL_E_ARG, "sim: the simulated rig has %d cameras, not %u",
                           RP_SIM_NCAMS, (unsigned)cfg->n_cams);
    }
    if (!(o.noise_px >= 0.0) || o.noise_px > 100.0) {
        return rp_hal_fail(err, RP_HAL_E_ARG, "sim: noise_px %g out of 0..100 px", o.noise_px);
    }
    if (o.drop_cam < -1 || o.drop_cam >= RP_SIM_NCAMS) {
        return rp_hal_fail(err, RP_HAL_E_ARG, "sim: drop_cam %d out of -1..%d", (int)o.drop_cam,
                           RP_SIM_NCAMS - 1);
    }
    if (o.motion < (int8_t)RP_SIM_MOTION_PAPER || o.motion > (int8_t)RP_SIM_MOTION_SMOOTH) {
        return rp_hal_fail(err, RP_HAL_E_ARG, "sim: motion %d is not 0 (paper), 1 (turn), 2 "
                           "(pitch) or 3 (smooth)", (int)o.motion);
    }
    if (g_sim.open) {
        return rp_hal_fail(err, RP_HAL_E_ARG, "sim: already open (one source per process)");
    }
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.noise_px = o.noise_px;
    sc.motion = (rp_sim_motion_t)o.motion;
    if (cfg->sim_frames > 0) {
        sc.n_frames = cfg->sim_frames;
    }
    memset(&g_sim, 0, sizeof g_sim);
    if (rp_sim_run_init(&g_sim.run, &sc, cfg->sim_seed, 0) != 0) {
        return rp_hal_fail(err, RP_HAL_E_OPEN, "sim: cannot set up the run of %u frame sets "
                           "(seed %u)", (unsigned)sc.n_frames, (unsigned)cfg->sim_seed);
    }
    g_sim.cfg = *cfg;
    g_sim.cfg.sim_opts = NULL; /* read at open only */
    g_sim.opts = o;
    g_sim.frame_us = (int64_t)(sc.frame_dt * 1e6 + 0.5);
    g_sim.err = err;
    g_sim.open = 1;
    *sim = &g_sim;
    return RP_HAL_OK;
}

rp_hal_status_t rp_hal_sim_open(rp_hal_sim_t **sim, const rp_hal_cfg_t *cfg,
                                const rp_hal_sim_opts_t *opts)
{
    g_err[0] = '\0';
    return sim_open(sim, cfg, opts, g_err);
}

const char *rp_hal_sim_errmsg(void)
{
    return g_err;
}

rp_hal_status_t rp_hal_sim_start(rp_hal_sim_t *sim)
{
    if (sim == NULL || !sim->open) {
        return RP_HAL_E_ARG;
    }
    if (sim->started) {
        return rp_hal_fail(sim->err, RP_HAL_E_STATE, "sim: started twice");
    }
    sim->started = 1;
    sim->seq = 0;
    sim->t0_us = rp_hal_now_us();
    return RP_HAL_OK;
}

rp_hal_status_t rp_hal_sim_grab(rp_hal_sim_t *sim, rp_hal_set_t *set)
{
    if (sim == NULL || set == NULL || !sim->open) {
        return RP_HAL_E_ARG;
    }
    if (!sim->started) {
        return rp_hal_fail(sim->err, RP_HAL_E_STATE, "sim: grab before start");
    }
    const uint32_t j = sim->next;
    if (j >= sim->run.cfg.n_frames) {
        return rp_hal_fail(sim->err, RP_HAL_E_END, "sim: end after %u sets",
                           (unsigned)sim->run.cfg.n_frames);
    }
    int64_t t = rp_hal_now_us();
    if (sim->cfg.realtime) {
        /* Release the set at its place on the simulated clock (as a camera would). */
        const int64_t due = sim->t0_us + (int64_t)j * sim->frame_us;
        if (due > t) {
            rp_hal_sleep_us(due - t);
        }
        t = due;
    }
    /* ignored: returns the feature count; j < n_frames was checked above */
    (void)rp_sim_frame(&sim->run, j, &sim->fs);

    memset(set, 0, sizeof *set);
    set->utime = t;
    set->seq = sim->seq;
    set->n_cams = RP_SIM_NCAMS;
    for (uint8_t k = 0; k < RP_SIM_NCAMS; ++k) {
        rp_hal_frame_t *f = &set->cam[k];
        /* the camera's own stamp, as the simulation gives it (0 without clocks) */
        f->utime = t + sim->fs.cam_dt_us[k];
        f->seq = j;
        if (sim->fs.cam_flags[k] & RP_FS_NO_IMAGE) {
            f->flags = RP_HAL_CAM_MISSING; /* a slower camera without a new frame */
        }
        if (sim->opts.drop_cam == (int16_t)k && j >= sim->opts.drop_from) {
            sim->fs.n[k] = 0;
            sim->fs.cam_flags[k] |= RP_FS_NO_IMAGE;
            f->flags = RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE;
            sim->drops[k]++;
        }
        f->drops = sim->drops[k];
    }
    set->payload = RP_HAL_PAYLOAD_FEATS;
    set->feats = &sim->fs;
    set->has_truth = 1;
    for (int i = 0; i < 6; ++i) {
        set->truth[i] = (rp_real)sim->run.truth[6u * j + (unsigned)i];
    }
    sim->next = j + 1u;
    sim->seq++;
    return RP_HAL_OK;
}

rp_hal_status_t rp_hal_sim_stop(rp_hal_sim_t *sim)
{
    if (sim == NULL || !sim->open) {
        return RP_HAL_E_ARG;
    }
    if (!sim->started) {
        return rp_hal_fail(sim->err, RP_HAL_E_STATE, "sim: stop before start");
    }
    sim->started = 0;
    return RP_HAL_OK;
}

void rp_hal_sim_close(rp_hal_sim_t *sim)
{
    if (sim == NULL || !sim->open) {
        return;
    }
    rp_sim_run_free(&sim->run);
    memset(sim, 0, sizeof *sim);
}

/* ---- the table for rp_hal_open ----------------------------------------------------------------- */

static rp_hal_status_t ops_open(void **ctx, const rp_hal_cfg_t *cfg, char *err)
{
    rp_hal_sim_t *sim = NULL;
    const rp_hal_status_t st = sim_open(&sim, cfg, cfg->sim_opts, err);
    *ctx = sim;
    return st;
}
static rp_hal_status_t ops_start(void *ctx) { return rp_hal_sim_start((rp_hal_sim_t *)ctx); }
static rp_hal_status_t ops_grab(void *ctx, rp_hal_set_t *set)
{
    return rp_hal_sim_grab((rp_hal_sim_t *)ctx, set);
}
static rp_hal_status_t ops_stop(void *ctx) { return rp_hal_sim_stop((rp_hal_sim_t *)ctx); }
static void ops_close(void *ctx) { rp_hal_sim_close((rp_hal_sim_t *)ctx); }

const rp_hal_ops_t rp_hal_sim_ops = {
    .name = "sim", .payload = RP_HAL_PAYLOAD_FEATS, .open = ops_open, .start = ops_start,
    .grab = ops_grab, .stop = ops_stop, .close = ops_close};
