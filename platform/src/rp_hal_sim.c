/*
 * rp_hal_sim.c - the HAL's sim source (rp_hal_sim.h): frame sets of features and the true pose
 * from the feature-level simulation of the paper's protocol.
 */
#include "rigpose/rp_hal_sim.h"

#include <string.h>

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
};

/* One source per process (rp_hal.h): the state is static, as on the board. */
static rp_hal_sim_t g_sim;

rp_hal_sim_opts_t rp_hal_sim_default_opts(void)
{
    rp_hal_sim_opts_t o;
    o.noise_px = 0.5;
    o.drop_cam = -1;
    o.drop_from = 0;
    return o;
}

rp_hal_status_t rp_hal_sim_open(rp_hal_sim_t **sim, const rp_hal_cfg_t *cfg,
                                const rp_hal_sim_opts_t *opts)
{
    if (sim == NULL || cfg == NULL) {
        return RP_HAL_E_ARG;
    }
    *sim = NULL;
    const rp_hal_sim_opts_t o = opts != NULL ? *opts : rp_hal_sim_default_opts();
    if (cfg->kind != RP_HAL_SRC_SIM || cfg->n_cams != RP_SIM_NCAMS || !(o.noise_px >= 0.0) ||
        o.noise_px > 100.0 || o.drop_cam < -1 || o.drop_cam >= RP_SIM_NCAMS) {
        return RP_HAL_E_ARG;
    }
    if (g_sim.open) {
        return RP_HAL_E_ARG;
    }
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.noise_px = o.noise_px;
    if (cfg->sim_frames > 0) {
        sc.n_frames = cfg->sim_frames;
    }
    memset(&g_sim, 0, sizeof g_sim);
    if (rp_sim_run_init(&g_sim.run, &sc, cfg->sim_seed, 0) != 0) {
        return RP_HAL_E_OPEN;
    }
    g_sim.cfg = *cfg;
    g_sim.opts = o;
    g_sim.frame_us = (int64_t)(sc.frame_dt * 1e6 + 0.5);
    g_sim.open = 1;
    *sim = &g_sim;
    return RP_HAL_OK;
}

rp_hal_status_t rp_hal_sim_start(rp_hal_sim_t *sim)
{
    if (sim == NULL || !sim->open) {
        return RP_HAL_E_ARG;
    }
    if (sim->started) {
        return RP_HAL_E_STATE;
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
        return RP_HAL_E_STATE;
    }
    const uint32_t j = sim->next;
    if (j >= sim->run.cfg.n_frames) {
        return RP_HAL_E_END;
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
    (void)rp_sim_frame(&sim->run, j, &sim->fs);

    memset(set, 0, sizeof *set);
    set->utime = t;
    set->seq = sim->seq;
    set->n_cams = RP_SIM_NCAMS;
    for (uint8_t k = 0; k < RP_SIM_NCAMS; ++k) {
        rp_hal_frame_t *f = &set->cam[k];
        f->utime = t;
        f->seq = j;
        if (sim->opts.drop_cam == (int16_t)k && j >= sim->opts.drop_from) {
            sim->fs.n[k] = 0;
            f->flags = RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE;
            sim->drops[k]++;
        }
        f->drops = sim->drops[k];
    }
    set->has_feats = 1;
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
        return RP_HAL_E_STATE;
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
