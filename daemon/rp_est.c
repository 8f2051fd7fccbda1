/*
 * rp_est.c - the configured estimator behind one init / step pair (rp_est.h).
 */
#include "rp_est.h"

#include <string.h>

rp_status_t rp_est_init(rp_est_t *est, const rp_config_t *cfg)
{
    if (est == NULL || cfg == NULL) {
        return RP_E_ARG;
    }
    memset(est, 0, sizeof *est);
    est->method = cfg->method;
    est->rig = &cfg->rig;
    switch (cfg->method) {
    case RP_METHOD_STEREO4:
    case RP_METHOD_STEREO2:
        return rp_vo_stereo_init(&est->u.stereo, &cfg->rig, &cfg->stereo);
    case RP_METHOD_GC:
        return rp_vo_gc_init(&est->u.gc, &cfg->rig, &cfg->gc);
    case RP_METHOD_CAM1:
    case RP_METHOD_CAM2:
    case RP_METHOD_CAM3:
    case RP_METHOD_CAM4:
    case RP_METHOD_RC:
        if (cfg->n_mono < 1 || cfg->n_mono > RP_RC_MAX_CAMS) {
            return RP_E_ARG;
        }
        est->u.single.n = cfg->n_mono;
        est->u.single.prm = rp_rc_default_params();
        est->u.single.last_scale = RP_C(1.0);
        for (uint8_t i = 0; i < cfg->n_mono; ++i) {
            est->u.single.cams[i] = cfg->mono[i].cam;
            const rp_status_t st = rp_vo_mono_init(&est->u.single.mono[i], &cfg->rig, &cfg->mono[i]);
            if (st != RP_OK) {
                return st;
            }
        }
        return RP_OK;
    }
    return RP_E_ARG;
}

/* rc: every camera's own estimator, then the rigidity constraints (eqs. 3-7) on their poses. */
static rp_status_t rc_step(rp_est_t *est, const rp_frameset_t *fs, rp_estimate_t *out)
{
    rp_real p_own[RP_RC_MAX_CAMS][6];
    rp_status_t st_ref = RP_OK;
    uint16_t n_used[RP_MAX_CAMS] = {0};
    for (uint8_t i = 0; i < est->u.single.n; ++i) {
        rp_estimate_t rig_est, own;
        const rp_status_t st = rp_vo_mono_step(&est->u.single.mono[i], fs, &rig_est, &own);
        if (i == 0) {
            st_ref = st;
            *out = own; /* the reference camera's own pose is the rig pose up to scale */
        }
        n_used[est->u.single.cams[i]] = rig_est.n_used[est->u.single.cams[i]];
        memcpy(p_own[i], own.p, sizeof p_own[i]);
    }
    memcpy(out->n_used, n_used, sizeof n_used);
    rp_real s[RP_RC_MAX_CAMS];
    uint32_t flags = out->flags & ~(uint32_t)RP_EST_SCALE_WEAK;
    const rp_status_t st = rp_rc_fuse(est->rig, est->u.single.cams, est->u.single.n,
                                      (const rp_real(*)[6])p_own, &est->u.single.prm,
                                      est->u.single.last_scale, out->p, s, &flags);
    if (st == RP_OK) {
        est->u.single.last_scale = s[0];
    }
    out->flags = flags;
    return st_ref;
}

rp_status_t rp_est_step(rp_est_t *est, const rp_frameset_t *fs, rp_estimate_t *out)
{
    if (est == NULL || fs == NULL || out == NULL) {
        return RP_E_ARG;
    }
    switch (est->method) {
    case RP_METHOD_STEREO4:
    case RP_METHOD_STEREO2:
        return rp_vo_stereo_step(&est->u.stereo, fs, out);
    case RP_METHOD_GC:
        return rp_vo_gc_step(&est->u.gc, fs, out);
    case RP_METHOD_CAM1:
    case RP_METHOD_CAM2:
    case RP_METHOD_CAM3:
    case RP_METHOD_CAM4:
        return rp_vo_mono_step(&est->u.single.mono[0], fs, out, NULL);
    case RP_METHOD_RC:
        return rc_step(est, fs, out);
    }
    memset(out, 0, sizeof *out);
    out->flags = RP_EST_LOST;
    return RP_E_ARG;
}
