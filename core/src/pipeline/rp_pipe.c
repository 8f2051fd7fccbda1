/*
 * rp_pipe.c - the image pipeline: trackers per camera, stereo matching of new features, the
 * layout's estimator (rp_pipe.h has the data flow and the id scheme of stereo pairs).
 *
 * Second cameras of stereo pairs run an rp_tracker_t that is fed, not detecting: after every
 * rp_track_process the pipeline keeps only the features it handed over (ids of the pair's first
 * camera, rp_track_id_cam(id) == that camera, rp_track.h's id scheme) and appends each new match
 * to the tracker's list at its matched position (rp_track_keep_owned, rp_track_adopt,
 * rp_track_features).
 */
#include "rigpose/rp_pipe.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "priv/rp_math.h"

#define RP_PIPE_MAGIC 0x50495045u /* "PIPE" */

static const char *const layout_names[RP_PIPE_LAYOUT_COUNT_] = {
    "stereo4", "stereo2", "gc", "cam1", "cam2", "cam3", "cam4", "rc"};

const char *rp_pipe_layout_name(rp_pipe_layout_t layout)
{
    return (unsigned)layout < RP_PIPE_LAYOUT_COUNT_ ? layout_names[layout] : "?";
}

rp_status_t rp_pipe_layout_from_name(const char *name, rp_pipe_layout_t *layout)
{
    if (name == NULL || layout == NULL) {
        return RP_E_ARG;
    }
    for (unsigned i = 0; i < RP_PIPE_LAYOUT_COUNT_; ++i) {
        if (strcmp(name, layout_names[i]) == 0) {
            *layout = (rp_pipe_layout_t)i;
            return RP_OK;
        }
    }
    return RP_E_ARG;
}

static int is_stereo(rp_pipe_layout_t l) { return l == RP_PIPE_STEREO4 || l == RP_PIPE_STEREO2; }

static int is_single(rp_pipe_layout_t l) { return l >= RP_PIPE_CAM1 && l <= RP_PIPE_CAM4; }

rp_status_t rp_pipe_default_cfg(rp_pipe_layout_t layout, rp_pipe_cfg_t *cfg)
{
    if (cfg == NULL || (unsigned)layout >= RP_PIPE_LAYOUT_COUNT_) {
        return RP_E_ARG;
    }
    memset(cfg, 0, sizeof(*cfg));
    cfg->layout = layout;
    /* ignored: cannot fail: a default configuration */
    (void)rp_track_default_cfg(&cfg->track);
    /* ignored: cannot fail: a default configuration */
    (void)rp_smatch_default_cfg(&cfg->smatch);
    cfg->stereo = rp_vo_stereo_default_cfg();
    cfg->stereo.n_pairs = layout == RP_PIPE_STEREO4 ? 2 : 1;
    cfg->stereo.pair_a[0] = 0; /* cam1 */
    cfg->stereo.pair_b[0] = 4; /* cam1's partner */
#if RP_MAX_PAIRS > 1
    if (layout == RP_PIPE_STEREO4) { /* stereo2's unused second pair stays 0 */
        cfg->stereo.pair_a[1] = 2;   /* cam3 */
        cfg->stereo.pair_b[1] = 5;   /* cam3's partner */
    }
#endif
    cfg->gc = rp_vo_gc_default_cfg();
    cfg->gc.n_cams = 4;
    cfg->mono = rp_vo_mono_default_cfg();
    cfg->mono.cam = is_single(layout) ? (uint8_t)(layout - RP_PIPE_CAM1) : 0;
    for (uint8_t i = 0; i < 4; ++i) {
        cfg->gc.cams[i] = i;
        cfg->rc_cams[i] = i;
    }
    cfg->rc_n = RP_RC_MAX_CAMS;
    cfg->rc = rp_rc_default_params();
    cfg->dormant_retired = 1;
    return RP_OK;
}

/* ---- set-up ------------------------------------------------------------------------------- */

static rp_status_t add_tracker(rp_pipe_t *pipe, uint8_t cam, uint8_t right)
{
    if (cam >= pipe->rig->n_cams || pipe->cam_trk[cam] >= 0 ||
        pipe->n_trk >= RP_PIPE_MAX_TRACKERS) {
        return RP_E_ARG;
    }
    const rp_camera_t *c = &pipe->rig->cam[cam].cam;
    if (c->width > RP_TRACK_MAX_W || c->height > RP_TRACK_MAX_H) {
        return RP_E_ARG;
    }
    rp_track_cfg_t tc = pipe->cfg.track;
    tc.cam = cam;
    if (right) {
        /* never tops up; on an empty list it detects one feature, which is dropped */
        tc.target = 1;
        tc.topup_below = 0;
    }
    const rp_status_t st = rp_track_init(&pipe->trk[pipe->n_trk], &tc);
    if (st != RP_OK) {
        return st;
    }
    pipe->trk_cam[pipe->n_trk] = cam;
    pipe->trk_right[pipe->n_trk] = right;
    pipe->cam_trk[cam] = (int8_t)pipe->n_trk;
    pipe->n_trk++;
    return RP_OK;
}

static rp_status_t init_trackers(rp_pipe_t *pipe)
{
    const rp_pipe_cfg_t *cfg = &pipe->cfg;
    rp_status_t st = RP_OK;
    if (is_stereo(cfg->layout)) {
        const uint8_t want = cfg->layout == RP_PIPE_STEREO4 ? 2 : 1;
        if (cfg->stereo.n_pairs != want || want > RP_MAX_PAIRS) {
            return RP_E_ARG;
        }
        for (uint8_t k = 0; k < want && st == RP_OK; ++k) {
            st = add_tracker(pipe, cfg->stereo.pair_a[k], 0);
            if (st == RP_OK) {
                st = add_tracker(pipe, cfg->stereo.pair_b[k], 1);
            }
            if (st == RP_OK) {
                st = rp_stereo_pair_init(pipe->rig, cfg->stereo.pair_a[k],
                                         cfg->stereo.pair_b[k], &pipe->pair[k]);
            }
        }
    } else if (cfg->layout == RP_PIPE_GC) {
        if (cfg->gc.n_cams < 1 || cfg->gc.n_cams > RP_PIPE_MAX_TRACKERS) {
            return RP_E_ARG;
        }
        for (uint8_t i = 0; i < cfg->gc.n_cams && st == RP_OK; ++i) {
            st = add_tracker(pipe, cfg->gc.cams[i], 0);
        }
    } else if (is_single(cfg->layout)) {
        st = add_tracker(pipe, cfg->mono.cam, 0);
    } else {
        if (cfg->rc_n < 2 || cfg->rc_n > RP_RC_MAX_CAMS || cfg->rc_n > RP_PIPE_MAX_TRACKERS) {
            return RP_E_ARG;
        }
        for (uint8_t i = 0; i < cfg->rc_n && st == RP_OK; ++i) {
            st = add_tracker(pipe, cfg->rc_cams[i], 0);
        }
    }
    return st;
}

static rp_status_t init_estimator(rp_pipe_t *pipe)
{
    const rp_pipe_cfg_t *cfg = &pipe->cfg;
    if (is_stereo(cfg->layout)) {
        return rp_vo_stereo_init(&pipe->est.stereo, pipe->rig, &cfg->stereo);
    }
    if (cfg->layout == RP_PIPE_GC) {
        return rp_vo_gc_init(&pipe->est.gc, pipe->rig, &cfg->gc);
    }
    if (is_single(cfg->layout)) {
        return rp_vo_mono_init(&pipe->est.single.mono[0], pipe->rig, &cfg->mono);
    }
    for (uint8_t i = 0; i < cfg->rc_n; ++i) {
        rp_vo_mono_cfg_t mc = cfg->mono;
        mc.cam = cfg->rc_cams[i];
        const rp_status_t st = rp_vo_mono_init(&pipe->est.single.mono[i], pipe->rig, &mc);
        if (st != RP_OK) {
            return st;
        }
    }
    pipe->est.single.last_scale = RP_C(1.0);
    return RP_OK;
}

rp_status_t rp_pipe_init(rp_pipe_t *pipe, const rp_rig_t *rig, const rp_pipe_cfg_t *cfg)
{
    if (pipe == NULL) {
        return RP_E_ARG;
    }
    pipe->magic = 0;
    if (rig == NULL || cfg == NULL || (unsigned)cfg->layout >= RP_PIPE_LAYOUT_COUNT_) {
        return RP_E_ARG;
    }
    rp_status_t st = rp_rig_check(rig);
    if (st != RP_OK) {
        return st;
    }
    pipe->rig = rig;
    pipe->cfg = *cfg;
    pipe->n_trk = 0;
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        pipe->cam_trk[k] = -1;
    }
    st = init_trackers(pipe);
    if (st == RP_OK) {
        for (uint8_t k = 0; k < RP_MAX_PAIRS && st == RP_OK; ++k) {
            st = rp_smatch_init(&pipe->pm[k].sm, &cfg->smatch);
        }
    }
    if (st == RP_OK) {
        st = init_estimator(pipe);
    }
    if (st != RP_OK) {
        return st;
    }
    memset(&pipe->fs, 0, sizeof(pipe->fs));
    memset(&pipe->last, 0, sizeof(pipe->last));
    memset(pipe->held_cov, 0, sizeof(pipe->held_cov));
    memset(pipe->anchor_cov, 0, sizeof(pipe->anchor_cov));
    pipe->was_held = 0;
    pipe->in_step = 0;
    memset(&pipe->info, 0, sizeof(pipe->info));
    pipe->last_utime = 0;
    pipe->magic = RP_PIPE_MAGIC;
    return RP_OK;
}

/* ---- second cameras of pairs ---------------------------------------------------------------- */

static int image_taken(uint8_t state)
{
    return state == RP_PIPE_CAM_OK || state == RP_PIPE_CAM_NO_FEATURES;
}

/* Matches pair k's features born this step (left camera) into the right image and hands the
 * matches to the right tracker and the frame set. */
static void match_new(rp_pipe_t *pipe, uint8_t k)
{
    const rp_stereo_pair_t *sp = &pipe->pair[k];
    rp_pipe_pairmatch_t *pm = &pipe->pm[k];
    const int ta = pipe->cam_trk[sp->a], tb = pipe->cam_trk[sp->b];
    rp_pipe_info_t *info = &pipe->info;
    if (!image_taken(info->cam_state[sp->a])) {
        return;
    }
    rp_tracker_t *B = &pipe->trk[tb];
    uint16_t n_new = 0;
    for (uint16_t i = 0; i < pipe->fs.n[sp->a]; ++i) {
        const rp_feat_t *f = &pipe->fs.f[sp->a][i];
        if (rp_track_serial_since(rp_track_id_serial(f->id), pipe->born_k[ta])) {
            pm->scratch_a[n_new++] = *f;
        }
    }
    if (n_new == 0) {
        return;
    }
    uint16_t nb = 0, n_adopted = 0;
    if (image_taken(info->cam_state[sp->b])) {
        const rp_pyr_t *pa, *pb;
        /* ignored: cannot fail: the pipeline's own tracker, checked at init */
        (void)rp_track_current_pyr(&pipe->trk[ta], &pa);
        /* ignored: cannot fail: the pipeline's own tracker, checked at init */
        (void)rp_track_current_pyr(B, &pb);
        /* ignored: counted in pipe->info.match; no match adds nothing */
        (void)rp_smatch_pair(&pm->sm, pipe->rig, sp, pa, pb, pm->scratch_a, n_new,
                             pm->scratch_b, RP_MAX_FEATS_PER_CAM, &nb, &info->match[k]);
        while (n_adopted < nb && rp_track_adopt(B, &pm->scratch_b[n_adopted]) == RP_OK) {
            ++n_adopted;
        }
    }
    /* A new left feature without a match gives the stereo estimator nothing (it triangulates
     * matches only) and would hold its cell in the left tracker for as long as it is tracked,
     * keeping the tracker above its top-up threshold: drop it, so that the next top-up can look
     * for a feature there again (the matcher walks both lists in input order). So are all of
     * them when the right camera has no image in this set: they can never be matched (the right
     * tracker takes features only at their birth), and the left tracker, full of them, would
     * not detect again until they are lost. */
    uint16_t n_lost = 0;
    for (uint16_t i = 0, j = 0; i < n_new; ++i) {
        if (j < n_adopted && pm->scratch_b[j].id == pm->scratch_a[i].id) {
            ++j;
        } else {
            pm->drop_ids[n_lost++] = pm->scratch_a[i].id;
        }
    }
    if (n_lost > 0) {
        rp_tracker_t *A = &pipe->trk[ta];
        /* ignored: cannot fail: the pipeline's own tracker, checked at init */
        (void)rp_track_drop_ids(A, pm->drop_ids, n_lost, NULL);
        /* ignored: RP_E_FULL keeps the frame set's own limit */
        (void)rp_track_features(A, pipe->fs.f[sp->a], RP_MAX_FEATS_PER_CAM, &pipe->fs.n[sp->a]);
    }
    /* ignored: RP_E_FULL keeps the frame set's own limit */
    (void)rp_track_features(B, pipe->fs.f[sp->b], RP_MAX_FEATS_PER_CAM, &pipe->fs.n[sp->b]);
}

/* ---- the step ------------------------------------------------------------------------------- */

/* Runs tracker t on its camera's image (or notes why there is none). */
static void track_one(rp_pipe_t *pipe, uint8_t t, const rp_image_t *img, int64_t utime)
{
    const uint8_t cam = pipe->trk_cam[t];
    rp_tracker_t *trk = &pipe->trk[t];
    rp_pipe_info_t *info = &pipe->info;
    const rp_camera_t *c = &pipe->rig->cam[cam].cam;
    /* ignored: cannot fail: the pipeline's own tracker, checked at init */
    (void)rp_track_next_serial(trk, &pipe->born_k[t]);
    pipe->fs.n[cam] = 0;
    if (img == NULL || img->data == NULL) {
        pipe->fs.cam_flags[cam] |= RP_FS_NO_IMAGE;
        info->cam_state[cam] = RP_PIPE_CAM_MISSING;
        info->cam_status[cam] = RP_E_ARG;
        return;
    }
    if (img->w != c->width || img->h != c->height) {
        info->cam_state[cam] = RP_PIPE_CAM_BAD_IMAGE;
        info->cam_status[cam] = RP_E_ARG;
        return;
    }
    uint16_t n = 0;
    rp_status_t st = rp_track_process(trk, img, utime, pipe->fs.f[cam], RP_MAX_FEATS_PER_CAM,
                                      &n, &info->track[cam]);
    info->cam_status[cam] = st;
    if (st == RP_E_DEGENERATE) {
        info->cam_state[cam] = RP_PIPE_CAM_BLANK;
        return;
    }
    if (st != RP_OK && st != RP_E_TOO_FEW && st != RP_E_FULL) {
        info->cam_state[cam] = RP_PIPE_CAM_BAD_IMAGE;
        return;
    }
    if (pipe->trk_right[t]) {
        /* the pair's first camera is the one whose tracker precedes this one */
        /* ignored: cannot fail: the pipeline's own tracker, checked at init */
        (void)rp_track_keep_owned(trk, pipe->trk_cam[t - 1], NULL);
        /* ignored: RP_E_FULL keeps the frame set's own limit */
        (void)rp_track_features(trk, pipe->fs.f[cam], RP_MAX_FEATS_PER_CAM, &n);
    }
    pipe->fs.n[cam] = n;
    info->cam_state[cam] = n > 0 ? RP_PIPE_CAM_OK : RP_PIPE_CAM_NO_FEATURES;
}

/* rc: the rc_n cameras' own estimators fused by the rigidity constraints (rp_rc.h); a
 * degenerate frame keeps the last accepted scale. */
static rp_status_t rc_step(rp_pipe_t *pipe, rp_estimate_t *est)
{
    rp_real p_own[RP_RC_MAX_CAMS][6];
    rp_status_t st_ref = RP_OK;
    uint16_t n_used[RP_MAX_CAMS] = {0};
    for (uint8_t i = 0; i < pipe->cfg.rc_n; ++i) {
        rp_estimate_t rig_est, own;
        const uint8_t cam = pipe->cfg.rc_cams[i];
        const rp_status_t st = rp_vo_mono_step(&pipe->est.single.mono[i], &pipe->fs, &rig_est,
                                               &own);
        if (i == 0) {
            st_ref = st;
            *est = own; /* the reference camera's own pose is the rig pose up to scale */
        }
        n_used[cam] = rig_est.n_used[cam];
        memcpy(p_own[i], own.p, sizeof(p_own[i]));
    }
    memcpy(est->n_used, n_used, sizeof(n_used));
    rp_real s[RP_RC_MAX_CAMS];
    uint32_t flags = est->flags & ~(uint32_t)RP_EST_SCALE_WEAK;
    if (rp_rc_fuse(pipe->rig, pipe->cfg.rc_cams, pipe->cfg.rc_n, (const rp_real(*)[6])p_own,
                   &pipe->cfg.rc, pipe->est.single.last_scale, est->p, s, &flags) == RP_OK) {
        pipe->est.single.last_scale = s[0];
    }
    est->flags = flags;
    return st_ref;
}

static rp_status_t run_estimator(rp_pipe_t *pipe, rp_estimate_t *est)
{
    const rp_pipe_layout_t l = pipe->cfg.layout;
    if (is_stereo(l)) {
        return rp_vo_stereo_step(&pipe->est.stereo, &pipe->fs, est);
    }
    if (l == RP_PIPE_GC) {
        return rp_vo_gc_step(&pipe->est.gc, &pipe->fs, est);
    }
    if (is_single(l)) {
        return rp_vo_mono_step(&pipe->est.single.mono[0], &pipe->fs, est, NULL);
    }
    return rc_step(pipe, est);
}

/* 1 if the layout's estimator retired track id (stereo's or gc's list). */
static int is_retired(const rp_pipe_t *pipe, uint32_t id)
{
    uint8_t r = 0;
    /* ignored: cannot fail: the pipeline's own estimator */
    (void)(pipe->cfg.layout == RP_PIPE_GC ? rp_vo_gc_is_retired(&pipe->est.gc, id, &r)
                                           : rp_vo_stereo_is_retired(&pipe->est.stereo, id, &r));
    return r;
}

/* Tracker T's retired tracks that are not dormant yet go dormant (scratch: RP_MAX_FEATS_PER_CAM
 * ids). */
static void make_dormant(const rp_pipe_t *pipe, rp_tracker_t *T, uint32_t *scratch)
{
    uint16_t m = 0;
    for (uint16_t i = 0; i < T->n; ++i) {
        if (!T->dormant[i] && is_retired(pipe, T->id[i])) {
            scratch[m++] = T->id[i];
        }
    }
    /* ignored: cannot fail: the pipeline's own tracker */
    (void)rp_track_set_dormant(T, scratch, m, NULL);
}

/* Stereo layouts and gc: the tracks the estimator retired (rp_vo_stereo.h, rp_vo_gc.h step 3b)
 * go dormant in their pair's first tracker (gc: their camera's; rp_track_set_dormant): they
 * keep their place, so the detector does not put a new feature on the same spot of a moving
 * object, but no longer fill the tracker's budget, so that it tops up from the rest of the
 * view. (An object that moves with the rig keeps its
 * retired tracks for good; counted, they held the front pair's tracker above its top-up
 * threshold while the scene's tracks left the view, and the pair re-initialised every frame
 * from the few left.) The right trackers are fed, not detecting: nothing to do there. A track
 * stays dormant until it is lost, also when the retired list, full, forgets it. */
static void retired_dormant(rp_pipe_t *pipe)
{
    if (pipe->cfg.layout == RP_PIPE_GC) {
        /* gc: every camera's own tracker, its step 3b's retired tracks (rp_vo_gc.h); pair 0's
         * scratch (gc has no pairs) */
        for (uint8_t t = 0; t < pipe->n_trk; ++t) {
            make_dormant(pipe, &pipe->trk[t], pipe->pm[0].drop_ids);
        }
        return;
    }
    for (uint8_t k = 0; k < pipe->cfg.stereo.n_pairs; ++k) {
        make_dormant(pipe, &pipe->trk[pipe->cam_trk[pipe->pair[k].a]], pipe->pm[k].drop_ids);
    }
}

/* What every step publishes, after the layout's estimator: a LOST estimate says TRACKING and
 * its counts no more (the layout's own rule, kept here for every layout, rc's fusion too); and
 * the covariance of a pose re-found after a blackout keeps the blackout's uncertainty. A held
 * filter (RP_EST_HELD) rebuilds its structure at a pose it does not know, and later updates,
 * which measure the rig against that structure, cannot tell where the structure is: so from
 * the first update after a hold the held covariance (the last one published while held) is
 * added to every published covariance, until the pipeline is set up again (a later hold adds
 * its own). */
static void finish(rp_pipe_t *pipe, rp_estimate_t *est)
{
    if (est->flags & RP_EST_LOST) {
        est->flags &= ~(uint32_t)RP_EST_TRACKING;
        memset(est->n_used, 0, sizeof(est->n_used));
    }
    if (est->flags & RP_EST_HELD) {
        memcpy(pipe->held_cov, est->cov, sizeof(pipe->held_cov));
        pipe->was_held = 1;
    } else if (pipe->was_held && (est->flags & RP_EST_TRACKING)) {
        for (int i = 0; i < 36; ++i) {
            pipe->anchor_cov[i] += pipe->held_cov[i];
        }
        pipe->was_held = 0;
    }
    for (int i = 0; i < 36; ++i) {
        est->cov[i] += pipe->anchor_cov[i];
    }
    pipe->last = *est;
}

/* The checks every step starts with (arguments, time order); on success a fresh report for
 * this step. RP_OK or the status to return (est, if given, then filled as rp_pipe.h says). A
 * phased step left unfinished (rp_pipe_begin without rp_pipe_estimate) is dropped. */
static rp_status_t step_begin(rp_pipe_t *pipe, int args_ok, int64_t utime, rp_estimate_t *est)
{
    if (pipe == NULL || pipe->magic != RP_PIPE_MAGIC || !args_ok) {
        if (est != NULL) {
            memset(est, 0, sizeof(*est));
            est->flags = RP_EST_LOST;
        }
        return RP_E_ARG;
    }
    pipe->in_step = 0;
    if (pipe->info.frame > 0 && utime <= pipe->last_utime) {
        if (est != NULL) {
            *est = pipe->last;
            est->flags |= RP_EST_LOST;
        }
        return RP_E_RANGE;
    }
    rp_pipe_info_t *info = &pipe->info;
    const uint32_t frame = info->frame;
    memset(info, 0, sizeof(*info));
    info->frame = frame + 1;
    pipe->last_utime = utime;
    return RP_OK;
}

rp_status_t rp_pipe_begin(rp_pipe_t *pipe, int64_t utime, rp_estimate_t *est)
{
    const rp_status_t st0 = step_begin(pipe, 1, utime, est);
    if (st0 != RP_OK) {
        return st0;
    }
    rp_frameset_reset(&pipe->fs, utime);
    /* top-up turns (rp_pipe.h): the d-th detecting tracker on frame sets d modulo their count */
    uint8_t n_det = 0;
    for (uint8_t t = 0; t < pipe->n_trk; ++t) {
        n_det = (uint8_t)(n_det + !pipe->trk_right[t]);
    }
    pipe->turn_trk = pipe->n_trk;
    for (uint8_t t = 0, d = 0; t < pipe->n_trk; ++t) {
        if (!pipe->trk_right[t]) {
            const uint8_t turn = (uint8_t)(pipe->info.frame % n_det == d);
            /* ignored: cannot fail: the pipeline's own tracker */
            (void)rp_track_set_topup_turn(&pipe->trk[t], turn);
            pipe->turn_trk = turn ? t : pipe->turn_trk;
            ++d;
        }
    }
    for (uint8_t k = 0; k < RP_MAX_PAIRS; ++k) {
        pipe->pm[k].done = 0;
    }
    pipe->in_step = 1;
    return RP_OK;
}

rp_status_t rp_pipe_cam_dt(int64_t cam_utime, int64_t utime, int32_t *dt_us)
{
    if (dt_us == NULL) {
        return RP_E_ARG;
    }
    /* cam_utime - utime overflows int64_t exactly when these hold */
    if ((utime < 0 && cam_utime > INT64_MAX + utime) ||
        (utime > 0 && cam_utime < INT64_MIN + utime)) {
        return RP_E_RANGE;
    }
    const int64_t d = cam_utime - utime;
    if (d < INT32_MIN || d > INT32_MAX) {
        return RP_E_RANGE;
    }
    *dt_us = (int32_t)d;
    return RP_OK;
}

rp_status_t rp_pipe_cam_time(rp_pipe_t *pipe, uint8_t cam, int64_t utime_us)
{
    if (pipe == NULL || pipe->magic != RP_PIPE_MAGIC || pipe->in_step == 0 ||
        cam >= pipe->rig->n_cams) {
        return RP_E_ARG;
    }
    return rp_pipe_cam_dt(utime_us, pipe->fs.utime, &pipe->fs.cam_dt_us[cam]);
}

rp_status_t rp_pipe_track(rp_pipe_t *pipe, uint8_t t, const rp_image_t *const images[],
                          uint8_t n)
{
    if (pipe == NULL || pipe->magic != RP_PIPE_MAGIC || pipe->in_step != 1 || t >= pipe->n_trk ||
        images == NULL || n > RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    const uint8_t cam = pipe->trk_cam[t];
    track_one(pipe, t, cam < n ? images[cam] : NULL, pipe->fs.utime + pipe->fs.cam_dt_us[cam]);
    return RP_OK;
}

rp_status_t rp_pipe_match_pair(rp_pipe_t *pipe, uint8_t k)
{
    if (pipe == NULL || pipe->magic != RP_PIPE_MAGIC || pipe->in_step != 1 ||
        !is_stereo(pipe->cfg.layout) || k >= pipe->cfg.stereo.n_pairs) {
        return RP_E_ARG;
    }
    if (pipe->pm[k].done) {
        return RP_OK;
    }
    match_new(pipe, k);
    rp_pipe_info_t *info = &pipe->info;
    const uint8_t b = pipe->pair[k].b;
    if (info->cam_state[b] == RP_PIPE_CAM_NO_FEATURES && pipe->fs.n[b] > 0) {
        info->cam_state[b] = RP_PIPE_CAM_OK;
    }
    pipe->pm[k].done = 1;
    return RP_OK;
}

uint8_t rp_pipe_n_pairs(const rp_pipe_t *pipe)
{
    return (pipe != NULL && pipe->magic == RP_PIPE_MAGIC && is_stereo(pipe->cfg.layout))
               ? pipe->cfg.stereo.n_pairs
               : 0;
}

rp_status_t rp_pipe_match(rp_pipe_t *pipe)
{
    if (pipe == NULL || pipe->magic != RP_PIPE_MAGIC || pipe->in_step != 1) {
        return RP_E_ARG;
    }
    for (uint8_t k = 0; k < rp_pipe_n_pairs(pipe); ++k) {
        /* ignored: k is a pair of the layout and the step is begun: RP_OK */
        (void)rp_pipe_match_pair(pipe, k);
    }
    pipe->in_step = 2;
    return RP_OK;
}

rp_status_t rp_pipe_estimate(rp_pipe_t *pipe, rp_estimate_t *est)
{
    if (pipe == NULL || pipe->magic != RP_PIPE_MAGIC || pipe->in_step != 2 || est == NULL) {
        if (est != NULL) {
            memset(est, 0, sizeof(*est));
            est->flags = RP_EST_LOST;
        }
        return RP_E_ARG;
    }
    pipe->in_step = 0;
    rp_pipe_info_t *info = &pipe->info;
    uint8_t taken = 0, lacking = 0;
    for (uint8_t t = 0; t < pipe->n_trk; ++t) {
        const uint8_t s = info->cam_state[pipe->trk_cam[t]];
        taken = (uint8_t)(taken + image_taken(s));
        lacking = (uint8_t)(lacking + (s != RP_PIPE_CAM_OK));
    }
    /* No image at all: the estimator still runs, on an empty frame set, so that it predicts
     * to utime (the covariance grows, the prediction is bounded: rp_ekf_predict) and reports
     * LOST with nothing used, as for blank images. */
    const rp_status_t st = run_estimator(pipe, est);
    if ((is_stereo(pipe->cfg.layout) || pipe->cfg.layout == RP_PIPE_GC) &&
        pipe->cfg.dormant_retired) {
        retired_dormant(pipe);
    }
    if (lacking > 0) {
        est->flags |= RP_EST_DEGRADED;
    }
    if (taken == 0) {
        est->flags |= RP_EST_LOST; /* nothing measured, whatever the layout says (its start) */
    }
    info->est_status = st;
    finish(pipe, est);
    return taken == 0 ? RP_E_DEGENERATE : st;
}

/* Camera k has an image in images[0..n-1] whose time the step takes (a camera of the rig). */
static int timed_image(const rp_pipe_t *pipe, const rp_image_t *const images[], uint8_t k)
{
    return k < pipe->rig->n_cams && images[k] != NULL && images[k]->data != NULL;
}

rp_status_t rp_pipe_step(rp_pipe_t *pipe, const rp_image_t *const images[], uint8_t n,
                         int64_t utime, rp_estimate_t *est)
{
    return rp_pipe_step_timed(pipe, images, NULL, n, utime, est);
}

rp_status_t rp_pipe_step_timed(rp_pipe_t *pipe, const rp_image_t *const images[],
                               const int64_t cam_utime[], uint8_t n, int64_t utime,
                               rp_estimate_t *est)
{
    if (images == NULL || n > RP_MAX_CAMS || est == NULL || pipe == NULL ||
        pipe->magic != RP_PIPE_MAGIC) {
        /* ignored: RP_E_ARG whatever the pipe; it fills est, if given, as rp_pipe.h says */
        (void)step_begin(pipe, 0, utime, est);
        return RP_E_ARG;
    }
    for (uint8_t k = 0; cam_utime != NULL && k < n; ++k) {
        int32_t dt;
        if (timed_image(pipe, images, k) && rp_pipe_cam_dt(cam_utime[k], utime, &dt) != RP_OK) {
            *est = pipe->last; /* nothing done, as for a utime out of order */
            est->flags |= RP_EST_LOST;
            return RP_E_RANGE;
        }
    }
    rp_status_t st = rp_pipe_begin(pipe, utime, est);
    for (uint8_t k = 0; st == RP_OK && cam_utime != NULL && k < n; ++k) {
        if (timed_image(pipe, images, k)) {
            /* ignored: the step is begun, k a camera of the rig, the time checked above */
            (void)rp_pipe_cam_time(pipe, k, cam_utime[k]);
        }
    }
    for (uint8_t t = 0; st == RP_OK && t < pipe->n_trk; ++t) {
        st = rp_pipe_track(pipe, t, images, n);
    }
    if (st == RP_OK) {
        st = rp_pipe_match(pipe);
    }
    return st == RP_OK ? rp_pipe_estimate(pipe, est) : st;
}

rp_status_t rp_pipe_step_feats(rp_pipe_t *pipe, const rp_frameset_t *fs, rp_estimate_t *est)
{
    const rp_status_t st0 =
        step_begin(pipe, fs != NULL && est != NULL, fs != NULL ? fs->utime : 0, est);
    if (st0 != RP_OK) {
        return st0;
    }
    pipe->fs = *fs;
    for (uint8_t t = 0; t < pipe->n_trk; ++t) {
        const uint8_t cam = pipe->trk_cam[t];
        pipe->info.cam_state[cam] = fs->n[cam] > 0 ? RP_PIPE_CAM_OK : RP_PIPE_CAM_NO_FEATURES;
    }
    const rp_status_t st = run_estimator(pipe, est);
    pipe->info.est_status = st;
    finish(pipe, est);
    return st;
}

uint8_t rp_pipe_topup_tracker(const rp_pipe_t *pipe)
{
    if (pipe == NULL || pipe->magic != RP_PIPE_MAGIC) {
        return 0;
    }
    return pipe->in_step == 1 ? pipe->turn_trk : pipe->n_trk;
}

uint8_t rp_pipe_n_trackers(const rp_pipe_t *pipe)
{
    return (pipe != NULL && pipe->magic == RP_PIPE_MAGIC) ? pipe->n_trk : 0;
}

rp_status_t rp_pipe_tracker_cam(const rp_pipe_t *pipe, uint8_t t, uint8_t *cam)
{
    if (pipe == NULL || cam == NULL || pipe->magic != RP_PIPE_MAGIC || t >= pipe->n_trk) {
        return RP_E_ARG;
    }
    *cam = pipe->trk_cam[t];
    return RP_OK;
}

rp_status_t rp_pipe_pair_trackers(const rp_pipe_t *pipe, uint8_t k, uint8_t *ta, uint8_t *tb)
{
    if (ta == NULL || tb == NULL || k >= rp_pipe_n_pairs(pipe)) {
        return RP_E_ARG;
    }
    *ta = (uint8_t)pipe->cam_trk[pipe->pair[k].a];
    *tb = (uint8_t)pipe->cam_trk[pipe->pair[k].b];
    return RP_OK;
}

rp_status_t rp_pipe_frameset(const rp_pipe_t *pipe, const rp_frameset_t **fs)
{
    if (pipe == NULL || fs == NULL || pipe->magic != RP_PIPE_MAGIC) {
        return RP_E_ARG;
    }
    *fs = &pipe->fs;
    return RP_OK;
}

rp_status_t rp_pipe_info(const rp_pipe_t *pipe, const rp_pipe_info_t **info)
{
    if (pipe == NULL || info == NULL || pipe->magic != RP_PIPE_MAGIC) {
        return RP_E_ARG;
    }
    *info = &pipe->info;
    return RP_OK;
}

rp_status_t rp_pipe_time_offsets(const rp_pipe_t *pipe, rp_real off_s[RP_MAX_CAMS],
                                 rp_real sigma_s[RP_MAX_CAMS])
{
    if (pipe == NULL || off_s == NULL || sigma_s == NULL || pipe->magic != RP_PIPE_MAGIC) {
        return RP_E_ARG;
    }
    const rp_pipe_layout_t l = pipe->cfg.layout;
    const rp_ekf_t *ekf = l == RP_PIPE_STEREO4 || l == RP_PIPE_STEREO2 ? &pipe->est.stereo.ekf
                          : l == RP_PIPE_GC                            ? &pipe->est.gc.ekf
                                                                       : NULL;
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        sigma_s[k] = RP_C(0.0);
        if (ekf == NULL) {
            off_s[k] = pipe->cfg.mono.ekf.toff0_s[k]; /* camK, rc: the configured offsets */
            continue;
        }
        off_s[k] = ekf->toff[k];
        if (ekf->toff_mask & (1u << k)) {
            const rp_real v = ekf->Poo[k * RP_MAX_CAMS + k];
            sigma_s[k] = v > RP_C(0.0) ? rp_sqrt(v) : RP_C(0.0);
        }
    }
    return RP_OK;
}
