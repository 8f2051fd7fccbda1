/*
 * rp_vo_stereo.c - the overlapping (stereo) layout of the paper, section 2.2.1.
 * See rp_vo_stereo.h for the algorithm; the step numbers below are the paper's.
 */
#include <string.h>

#include "priv/rp_math.h"
#include "priv/rp_select.h"
#include "rigpose/rp_vo.h"
#include "rigpose/rp_vo_stereo.h"

#define MATCH_CAP (2 * RP_MAX_FEATS_PER_CAM)
/* robust_refine: rounds at most; Cauchy's constant (95 % efficiency on Gaussian residuals);
 * the median of chi-square with 2 degrees of freedom; a step (m, rad) that ends it */
#define ROBUST_ROUNDS 10
#define ROBUST_CAUCHY_C RP_C(2.3849)
#define ROBUST_CHI2_2_MEDIAN RP_C(1.3863)
#define ROBUST_STEP RP_C(1e-9) /* (float builds: ROBUST_ROUNDS ends it) */
/* chi-square quantile, 6 degrees of freedom, 99.9 % (predict_update's re-found pose) */
#define REFIND_CHI2_6 RP_C(22.46)
#define RANSAC_SEED 0x5EED5u /* any fixed value: the run is a function of its input */

rp_vo_stereo_cfg_t rp_vo_stereo_default_cfg(void)
{
    rp_vo_stereo_cfg_t c;
    memset(&c, 0, sizeof(c));
    c.ekf = rp_ekf_default_params();
    c.ekf.q_trans = RP_C(3.0); /* config/README.md, "Defaults that are measured" */
    c.ekf.q_rot = RP_C(3.0);
    c.min_tracked = 50;
    c.max_epipolar_px = RP_C(1.5);
    c.min_depth_m = RP_C(0.05);
    c.max_depth_m = RP_C(100.0);
    c.max_reproj_px = RP_C(1.5);
    c.default_dt_s = RP_C(1.0) / RP_C(30.0);
    c.max_pair_skew_s = RP_C(0.001); /* config/README.md, `max_pair_skew_s` */
    c.refine_structure = 1;
    c.ransac = 1;
    c.one_point = 1; /* config/README.md, `one_point`: its cost and gain */
    c.drop_odds = RP_DROP_ODDS; /* rp_vo_stereo.h, "Dropping a landmark" */
    c.retry_triangulation = 1;
    c.retire_outliers = 1; /* rp_vo_stereo.h: a track that lied once is not believed again */
    c.add_landmarks = 1;   /* rp_vo_stereo.h, step 5 */
    return c;
}

/* 1 if landmark id is held. */
static int lm_held(const rp_vo_stereo_t *vo, uint32_t id)
{
    uint16_t slot;
    return rp_lmtab_find(&vo->lm, id, &slot) == RP_OK;
}

/* ---- set-up ------------------------------------------------------------------------------ */

static void retired_rehash(rp_vo_stereo_t *vo);

rp_status_t rp_vo_stereo_init(rp_vo_stereo_t *vo, const rp_rig_t *rig,
                              const rp_vo_stereo_cfg_t *cfg)
{
    rp_ekf_t idle;
    rp_status_t st = vo && cfg ? rp_vo_init_filter(rig, &cfg->ekf, &idle) : RP_E_ARG;
    if (st != RP_OK) {
        return st;
    }
    if (cfg->n_pairs < 1 || cfg->n_pairs > RP_MAX_PAIRS || cfg->min_tracked < 6 ||
        !(cfg->max_epipolar_px > RP_C(0.0)) || !(cfg->min_depth_m > RP_C(0.0)) ||
        !(cfg->max_depth_m > cfg->min_depth_m) || !(cfg->max_reproj_px > RP_C(0.0)) ||
        !(cfg->max_pair_skew_s >= RP_C(0.0)) || !rp_finite(cfg->max_pair_skew_s) ||
        !(cfg->default_dt_s > RP_C(0.0)) || cfg->ransac > 1 || cfg->one_point > 1 ||
        !(cfg->drop_odds > RP_C(1.0)) || !rp_finite(cfg->drop_odds) ||
        cfg->retry_triangulation > 1 || cfg->retire_outliers > 1 || cfg->add_landmarks > 1) {
        return RP_E_ARG;
    }
    uint8_t in_use[RP_MAX_CAMS] = {0};
    for (uint8_t k = 0; k < cfg->n_pairs; ++k) {
        uint8_t a = cfg->pair_a[k], b = cfg->pair_b[k];
        if (a >= rig->n_cams || b >= rig->n_cams || a == b || in_use[a] || in_use[b]) {
            return RP_E_ARG;
        }
        in_use[a] = in_use[b] = 1;
    }
    memset(vo, 0, sizeof(*vo));
    vo->rig = rig;
    vo->cfg = *cfg;
    for (uint8_t k = 0; k < cfg->n_pairs; ++k) {
        st = rp_stereo_pair_init(rig, cfg->pair_a[k], cfg->pair_b[k], &vo->pair[k]);
        if (st != RP_OK) {
            return st;
        }
    }
    vo->ekf = idle;
    uint8_t cams = 0;
    for (uint8_t k = 0; k < cfg->n_pairs; ++k) {
        cams = (uint8_t)(cams | (1u << cfg->pair_a[k]) | (1u << cfg->pair_b[k]));
    }
    st = rp_vo_ekf_offsets(&vo->ekf, cams);
    if (st != RP_OK) {
        return st;
    }
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_clear(&vo->lm);
    vo->n_retired = 0;
    vo->refind_inl = 0;
    retired_rehash(vo);
    /* ignored: only NULL arguments fail */
    (void)rp_ransac_seed(&vo->rs, RANSAC_SEED);
    (void)rp_ekf1pt_seed(&vo->op, RANSAC_SEED);
    return RP_OK;
}

/* ---- step (1): match, check against F, triangulate, check, store ------------------------- */

static void match_map_build(rp_vo_stereo_t *vo, const rp_frameset_t *fs, uint8_t cam)
{
    for (uint32_t i = 0; i < MATCH_CAP; ++i) {
        vo->match_key[i] = RP_VO_EMPTY_ID;
    }
    for (uint16_t f = 0; f < fs->n[cam]; ++f) {
        uint32_t id = fs->f[cam][f].id;
        uint32_t i = rp_idmap_hash(id) & (MATCH_CAP - 1);
        while (vo->match_key[i] != RP_VO_EMPTY_ID && vo->match_key[i] != id) {
            i = (i + 1) & (MATCH_CAP - 1);
        }
        vo->match_key[i] = id;
        vo->match_idx[i] = f;
    }
}

static int match_map_find(const rp_vo_stereo_t *vo, uint32_t id, uint16_t *idx)
{
    uint32_t i = rp_idmap_hash(id) & (MATCH_CAP - 1);
    while (vo->match_key[i] != RP_VO_EMPTY_ID) {
        if (vo->match_key[i] == id) {
            *idx = vo->match_idx[i];
            return 1;
        }
        i = (i + 1) & (MATCH_CAP - 1);
    }
    return 0;
}

/* 1 if feature `id` is in either camera of pair sp in frame set fs. */
static int tracked_in(const rp_frameset_t *fs, const rp_stereo_pair_t *sp, uint32_t id)
{
    for (uint8_t c = 0; c < 2; ++c) {
        uint8_t cam = c == 0 ? sp->a : sp->b;
        for (uint16_t g = 0; g < fs->n[cam]; ++g) {
            if (fs->f[cam][g].id == id) {
                return 1;
            }
        }
    }
    return 0;
}

/* ---- retired tracks (rp_vo_stereo.h) ----------------------------------------------------- */

/* Pair of camera cam in the layout; n_pairs if none. */
static uint8_t pair_of_cam(const rp_vo_stereo_t *vo, uint8_t cam)
{
    uint8_t k = 0;
    while (k < vo->cfg.n_pairs && vo->pair[k].a != cam && vo->pair[k].b != cam) {
        ++k;
    }
    return k;
}

/* 1 if id is a retired track. */
static int retired(const rp_vo_stereo_t *vo, uint32_t id)
{
    uint32_t i = rp_idmap_hash(id) % RP_VO_RETIRED_CELLS;
    while (vo->retired_cell[i] != RP_VO_EMPTY_ID) {
        if (vo->retired_cell[i] == id) {
            return 1;
        }
        i = (i + 1u) % RP_VO_RETIRED_CELLS;
    }
    return 0;
}

rp_status_t rp_vo_stereo_is_retired(const rp_vo_stereo_t *vo, uint32_t id, uint8_t *is_retired)
{
    if (vo == NULL || is_retired == NULL) {
        return RP_E_ARG;
    }
    *is_retired = (uint8_t)(id != RP_VO_EMPTY_ID && retired(vo, id));
    return RP_OK;
}

/* The hash of the retired ids, from the list (at most half its cells are taken). */
static void retired_rehash(rp_vo_stereo_t *vo)
{
    for (uint32_t i = 0; i < RP_VO_RETIRED_CELLS; ++i) {
        vo->retired_cell[i] = RP_VO_EMPTY_ID;
    }
    for (uint16_t k = 0; k < vo->n_retired; ++k) {
        uint32_t i = rp_idmap_hash(vo->retired_id[k]) % RP_VO_RETIRED_CELLS;
        while (vo->retired_cell[i] != RP_VO_EMPTY_ID) {
            i = (i + 1u) % RP_VO_RETIRED_CELLS;
        }
        vo->retired_cell[i] = vo->retired_id[k];
    }
}

/* Keep the retired tracks that either camera of their pair still tracks in fs (ids are not
 * reused), and every one of a pair whose camera has no feature in fs (no image, or a blank
 * one: its tracker lost nothing). */
static void retired_prune(rp_vo_stereo_t *vo, const rp_frameset_t *fs)
{
    if (vo->n_retired == 0) {
        return;
    }
    memset(vo->retired_keep, 0, vo->n_retired);
    for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
        for (uint8_t c = 0; c < 2; ++c) {
            const uint8_t cam = c == 0 ? vo->pair[k].a : vo->pair[k].b;
            const int blind = fs->n[cam] == 0;
            if (!blind) {
                match_map_build(vo, fs, cam);
            }
            for (uint16_t i = 0; i < vo->n_retired; ++i) {
                uint16_t idx;
                if (vo->retired_pair[i] == k &&
                    (blind || match_map_find(vo, vo->retired_id[i], &idx))) {
                    vo->retired_keep[i] = 1;
                }
            }
        }
    }
    uint16_t kept = 0;
    for (uint16_t i = 0; i < vo->n_retired; ++i) {
        if (vo->retired_keep[i]) {
            vo->retired_id[kept] = vo->retired_id[i];
            vo->retired_pair[kept++] = vo->retired_pair[i];
        }
    }
    if (kept != vo->n_retired) {
        vo->n_retired = kept;
        retired_rehash(vo);
    }
}

static int pair_rejected(const rp_vo_stereo_t *vo, uint32_t n);

/* Retire the tracks of the n observations' landmarks that the last drop removed, if the update
 * could judge them (rp_vo_stereo.h): its inliers most of the n, from more than one pair when
 * the layout has several, and no pair mostly left out unless rig RANSAC confirmed it. */
static void retire_dropped(rp_vo_stereo_t *vo, uint32_t n)
{
    uint32_t n_used = 0;
    uint32_t pairs_used = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (vo->used[i]) {
            n_used++;
            pairs_used |= 1u << pair_of_cam(vo, vo->obs[i].cam);
        }
    }
    const int several = (pairs_used & (pairs_used - 1u)) != 0u;
    /* a pair mostly left out judges the prediction, unless rig RANSAC, which has none, found
     * no larger consensus than the one kept */
    const int judged = !pair_rejected(vo, n) || (vo->refind_inl > 0 && vo->refind_inl <= n_used);
    if (!vo->cfg.retire_outliers || 2u * n_used <= n || (vo->cfg.n_pairs > 1 && !several) ||
        !judged) {
        return;
    }
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t id = vo->obs_id[i];
        const uint8_t k = pair_of_cam(vo, vo->obs[i].cam);
        if (k >= vo->cfg.n_pairs || vo->obs[i].cam != vo->pair[k].a || lm_held(vo, id) ||
            retired(vo, id)) {
            continue;
        }
        if (vo->n_retired == RP_VO_RETIRED_MAX) { /* the first listed makes room */
            memmove(vo->retired_id, vo->retired_id + 1,
                    (RP_VO_RETIRED_MAX - 1u) * sizeof(vo->retired_id[0]));
            memmove(vo->retired_pair, vo->retired_pair + 1, RP_VO_RETIRED_MAX - 1u);
            vo->n_retired--;
            retired_rehash(vo);
        }
        vo->retired_id[vo->n_retired] = id;
        vo->retired_pair[vo->n_retired++] = k;
        uint32_t c = rp_idmap_hash(id) % RP_VO_RETIRED_CELLS;
        while (vo->retired_cell[c] != RP_VO_EMPTY_ID) {
            c = (c + 1u) % RP_VO_RETIRED_CELLS;
        }
        vo->retired_cell[c] = id;
    }
}

/* The entry of id on pair k's list of failed matches (sorted by id: rp_vo_stereo.h), or
 * NULL. */
static const rp_vo_retry_t *retry_listed(const rp_vo_stereo_t *vo, uint8_t k, uint32_t id)
{
    uint16_t lo = 0, hi = vo->n_retry[k];
    while (lo < hi) {
        const uint16_t mid = (uint16_t)((lo + hi) / 2u);
        if (vo->retry[k][mid].id < id) {
            lo = (uint16_t)(mid + 1u);
        } else {
            hi = mid;
        }
    }
    return lo < vo->n_retry[k] && vo->retry[k][lo].id == id ? &vo->retry[k][lo] : NULL;
}

/* Triangulate the matches of pair k in frame set fs at pose p and add them as landmarks.
 * If `only_in` is given, a match is used only when its id is also in that frame set (a
 * backtracked re-initialisation only wants features still tracked now). retry 0: every match,
 * and (cfg.retry_triangulation) the ones that fail the checks become the pair's list of failed
 * matches, with their pixels and pose p; 1: only the listed ones, each that succeeds also
 * updated with its listed pixels, and those that fail again (and are still matched) stay
 * listed. Returns how many were added. */
static uint16_t triangulate_pair(rp_vo_stereo_t *vo, uint8_t k, const rp_frameset_t *fs,
                                 const rp_real p[6], const rp_frameset_t *only_in, int retry)
{
    const rp_stereo_pair_t *sp = &vo->pair[k];
    const rp_vo_stereo_cfg_t *cfg = &vo->cfg;
    /* each camera's capture time relative to the state's (rp_ekf.h): the pair's two images
     * must be near-simultaneous; the points go into the world at camera a's pose then, from
     * the filter's constant velocity, which it has from its second frame set on (before, a
     * pair not at the state's time waits: RP_VO_START_SKEW_S) */
    const rp_real da = (rp_real)fs->cam_dt_us[sp->a] * RP_C(1e-6) + vo->ekf.toff[sp->a];
    const rp_real db = (rp_real)fs->cam_dt_us[sp->b] * RP_C(1e-6) + vo->ekf.toff[sp->b];
    if (!(rp_fabs(da - db) <= cfg->max_pair_skew_s) ||
        (vo->frame < 2 && vo->start_near && !(rp_fabs(da) <= RP_VO_START_SKEW_S))) {
        vo->skewed = 1;
        return 0;
    }
    rp_pose_lin_t pl;
    if (rp_pose_lin_at(&pl, p, vo->ekf.x + 6, da) != RP_OK) {
        return 0;
    }
    uint16_t added = 0, n_failed = 0;
    rp_vo_retry_t *failed = vo->retry_scratch; /* the new list; in place of the old when done */
    match_map_build(vo, fs, sp->b);
    for (uint16_t f = 0; f < fs->n[sp->a]; ++f) {
        const rp_feat_t *fa = &fs->f[sp->a][f];
        uint16_t jb;
        if (fa->id == RP_VO_EMPTY_ID || !match_map_find(vo, fa->id, &jb) ||
            lm_held(vo, fa->id) || retired(vo, fa->id)) {
            continue;
        }
        const rp_feat_t *fb = &fs->f[sp->b][jb];
        const rp_vo_retry_t *was = retry ? retry_listed(vo, k, fa->id) : NULL;
        if (!rp_all_finite(fa->uv, 2) || !rp_all_finite(fb->uv, 2) ||
            (only_in && !tracked_in(only_in, sp, fa->id)) || (retry && !was)) {
            continue;
        }
        /* listed, with the pixels that failed it first; taken back below if it becomes a
         * landmark */
        if (was) {
            failed[n_failed] = *was;
        } else {
            failed[n_failed].id = fa->id;
            memcpy(failed[n_failed].uv[0], fa->uv, sizeof(fa->uv));
            memcpy(failed[n_failed].uv[1], fb->uv, sizeof(fb->uv));
        }
        n_failed++;
        rp_real epi, Pa[3], reproj, M[3];
        if (rp_stereo_epipolar_px(vo->rig, sp, fa->uv, fb->uv, &epi) != RP_OK ||
            epi > cfg->max_epipolar_px) {
            continue;
        }
        if (rp_stereo_triangulate(vo->rig, sp, fa->uv, fb->uv, Pa, &reproj) != RP_OK ||
            reproj > cfg->max_reproj_px || Pa[2] < cfg->min_depth_m || Pa[2] > cfg->max_depth_m) {
            continue;
        }
        const uint8_t cams[2] = {sp->a, sp->b};
        rp_point3_t pt;
        if (rp_rig_world_point(vo->rig, sp->a, &pl, Pa, M) != RP_OK ||
            rp_struct_init(&pt, vo->rig, cams, 2, &pl, M, cfg->ekf.sigma_px) != RP_OK) {
            continue;
        }
        if (was) { /* the pixels that failed it first, at their pose (rp_vo_stereo.h) */
            for (int c = 0; c < 2; ++c) {
                /* ignored: the gate refuses the wrong pixel of the two (not a fault) */
                (void)rp_struct_update(&pt, vo->rig, cams[c], &vo->retry_pl[k], was->uv[c],
                                       cfg->ekf.sigma_px, cfg->ekf.gate_chi2);
            }
        }
        uint16_t slot;
        if (rp_lmtab_insert(&vo->lm, fa->id, k, &pt, &slot) != RP_OK) {
            break; /* table full: keep what we have */
        }
        n_failed--;
        /* ignored: slot is the table's own */
        (void)rp_droptest_reset_slot(&vo->drop, slot);
        added++;
    }
    if (!cfg->retry_triangulation) {
        return added;
    }
    /* the list sorted (insertion: at most RP_MAX_FEATS_PER_CAM ids, mostly in order) */
    for (uint16_t i = 1; i < n_failed; ++i) {
        const rp_vo_retry_t e = failed[i];
        uint16_t j = i;
        for (; j > 0 && failed[j - 1].id > e.id; --j) {
            failed[j] = failed[j - 1];
        }
        failed[j] = e;
    }
    memcpy(vo->retry[k], failed, n_failed * sizeof(failed[0]));
    vo->n_retry[k] = n_failed;
    if (!retry) {
        vo->retry_pl[k] = pl; /* the pose of the listed pixels */
    }
    return added;
}

/* ---- measurements ------------------------------------------------------------------------ */

/* Gather the observations of held landmarks in fs into vo->obs (the layout's cameras in rig
 * order). */
static uint32_t gather_obs(rp_vo_stereo_t *vo, const rp_frameset_t *fs)
{
    uint8_t cams[RP_MAX_CAMS], n_cams = 0;
    for (uint8_t cam = 0; cam < vo->rig->n_cams && cam < RP_MAX_CAMS; ++cam) {
        for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
            if (vo->pair[k].a == cam || vo->pair[k].b == cam) {
                cams[n_cams++] = cam;
                break;
            }
        }
    }
    uint32_t n = 0;
    /* ignored: cannot fill: the cap holds a whole frame set */
    (void)rp_lmtab_gather(&vo->lm, fs, cams, n_cams, 0, vo->obs, vo->obs_id,
                          RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM, &n);
    return n;
}

static void fill_estimate(const rp_vo_stereo_t *vo, const rp_frameset_t *fs, uint32_t flags,
                          rp_estimate_t *est)
{
    /* ignored: only NULL arguments fail */
    (void)rp_vo_fill_estimate(&vo->ekf, RP_C(1.0), fs ? fs->utime : vo->prev_utime, vo->frame,
                              flags | (vo->skewed ? RP_EST_UNSYNCED : 0u), vo->lm.map.n, est);
}

/* ---- the step ---------------------------------------------------------------------------- */

/* vo->keep[i] = 1 for an observation whose landmark is kept: the drop test of rp_vo_stereo.h
 * ("Dropping a landmark", rp_droptest.h) on this frame set's n observations (vo->used: taken
 * into the update) has not fired for it. */
static void drop_test(rp_vo_stereo_t *vo, uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i) {
        uint16_t slot;
        vo->obs_slot[i] = rp_lmtab_find(&vo->lm, vo->obs_id[i], &slot) == RP_OK
                              ? slot
                              : (uint16_t)RP_IDMAP_MAX_SLOTS;
    }
    /* ignored: the arrays are the estimator's own and drop_odds was checked at init */
    (void)rp_droptest_run(&vo->drop, vo->obs_slot, vo->used, n, vo->cfg.ekf.min_features,
                          vo->cfg.drop_odds, vo->keep);
}

static rp_status_t first_frame(rp_vo_stereo_t *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    /* Step (1) at frame 0: the world is cam1's frame now, so the pose is exactly zero. */
    static const rp_real zero[6] = {0};
    vo->skewed = 0;
    /* a pair not at the state's time waits for the filter's rate (triangulate_pair), unless
     * none is: then all start here, each as if at the state's time */
    vo->start_near = 0;
    for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
        const uint8_t a = vo->pair[k].a;
        const rp_real da = (rp_real)fs->cam_dt_us[a] * RP_C(1e-6) + vo->ekf.toff[a];
        vo->start_near = (uint8_t)(vo->start_near | (fs->n[a] > 0 &&
                                                     rp_fabs(da) <= RP_VO_START_SKEW_S));
    }
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_clear(&vo->lm);
    uint16_t added = 0;
    for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
        added = (uint16_t)(added + triangulate_pair(vo, k, fs, zero, NULL, 0));
    }
    (void)rp_lmtab_drop_unmarked(&vo->lm, 0, NULL); /* clears the marks */
    /* ignored: cannot fail: the parameters were checked at init */
    (void)rp_vo_ekf_at_origin(&vo->ekf, &vo->cfg.ekf);
    vo->frame = 1;
    vo->prev = *fs;
    memset(vo->prev_p, 0, sizeof(vo->prev_p));
    vo->prev_utime = fs->utime;
    uint32_t flags = RP_EST_INITIALISING;
    if (added < vo->cfg.min_tracked) {
        flags |= RP_EST_DEGRADED;
    }
    fill_estimate(vo, fs, flags, est);
    est->frame = 0;
    return added >= RP_VO_MIN_START ? RP_OK : RP_E_TOO_FEW;
}

/* select_lowest_real(h, NULL, n, want): priv/rp_select.h */
RP_DEFINE_SELECT_LOWEST(select_lowest_real, rp_real)

/* RANSAC's weights: 1 for its inliers (vo->inl), 0 for its outliers. */
static void inlier_weights(rp_vo_stereo_t *vo, uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i) {
        vo->obs[i].w = vo->inl[i] ? RP_C(1.0) : RP_C(0.0);
    }
}

/* The re-found pose p refined on RANSAC's inliers (vo->inl) by iteratively reweighted Lowe's
 * method, Cauchy weights w = 1 / (1 + |r|^2 / (c^2 s^2)) (c = ROBUST_CAUCHY_C: 95 % efficiency
 * on Gaussian residuals), s the inliers' own scale, s^2 = median |r|^2 / ROBUST_CHI2_2_MEDIAN
 * (2-D residuals) at the current pose, at most RANSAC's residual sigma (rp.sigma_px). Why:
 * RANSAC's gate (sigma_px sqrt(2 chi2), 2.6 px at the defaults) is set for the worst pixel
 * noise the filter assumes, and a moving object's near points a pixel or two off sit inside it
 * (rendered run 7's start: 23 of the front pair's 62 inliers, 0.36 m away, 1-4.6 px off the
 * truth, drew the pose 0.3 mm off, which the map then kept); on the inliers' own scale they
 * weigh next to nothing. At most ROBUST_ROUNDS rounds; the weights are 1 again on return and
 * cov is the last solve's. No change when the fit is exact (s = 0) or a solve fails. */
static void robust_refine(rp_vo_stereo_t *vo, uint32_t n, const rp_ransac_params_t *rp,
                          rp_real p[6], rp_real cov[36])
{
    const rp_real s2_max = rp->sigma_px * rp->sigma_px;
    for (int round = 0; round < ROBUST_ROUNDS; ++round) {
        rp_pose_lin_t pl;
        if (rp_pose_lin_set(&pl, p) != RP_OK) {
            break;
        }
        int m = 0;
        for (uint32_t i = 0; i < n; ++i) {
            rp_real uv[2];
            vo->res2[i] = RP_C(-1.0);
            if (vo->inl[i] &&
                rp_rig_project(vo->rig, vo->obs[i].cam, &pl, vo->obs[i].M, uv, NULL, NULL) ==
                    RP_OK) {
                const rp_real du = vo->obs[i].uv[0] - uv[0], dv = vo->obs[i].uv[1] - uv[1];
                vo->res2[i] = du * du + dv * dv;
                vo->sel2[m++] = vo->res2[i];
            }
        }
        if (m < (int)vo->cfg.ekf.min_features) {
            break;
        }
        select_lowest_real(vo->sel2, NULL, m, m / 2 + 1);
        rp_real s2 = vo->sel2[m / 2] / ROBUST_CHI2_2_MEDIAN;
        if (!(s2 > RP_C(0.0))) {
            break; /* an exact fit */
        }
        s2 = s2 < s2_max ? s2 : s2_max;
        const rp_real cs2 = ROBUST_CAUCHY_C * ROBUST_CAUCHY_C * s2;
        for (uint32_t i = 0; i < n; ++i) {
            vo->obs[i].w = vo->res2[i] >= RP_C(0.0) ? RP_C(1.0) / (RP_C(1.0) + vo->res2[i] / cs2)
                                                     : RP_C(0.0);
        }
        rp_real q[6], c[36];
        memcpy(q, p, sizeof q);
        const rp_status_t st = rp_lowe_solve(vo->rig, vo->obs, n, &rp->lowe, q, NULL, c);
        if ((st != RP_OK && st != RP_E_NO_CONVERGE) || !rp_all_finite(q, 6)) {
            break;
        }
        rp_real step = RP_C(0.0);
        for (int a = 0; a < 6; ++a) {
            const rp_real d = rp_fabs(q[a] - p[a]);
            step = d > step ? d : step;
        }
        memcpy(p, q, sizeof q);
        memcpy(cov, c, sizeof c);
        if (step < ROBUST_STEP) {
            break;
        }
    }
    inlier_weights(vo, n);
}

/* The pose from the images alone: rig RANSAC over every camera's n observations (rp_ransac.h),
 * then Lowe's method on the inliers from RANSAC's pose. RANSAC's gate is the filter's,
 * gate_chi2 on a residual of variance 2 sigma_px^2: a landmark triangulated from one frame
 * set's pixels reprojects into a nearby view with that frame's pixel noise again, besides the
 * current pixel's. On RP_OK p holds
 * the pose, cov its covariance per unit pixel variance, the outliers have w = 0 and vo->inl
 * marks the inliers. */
static rp_status_t robust_pose(rp_vo_stereo_t *vo, uint32_t n, rp_real p[6], rp_real cov[36],
                               uint32_t *n_inl)
{
    const rp_ransac_params_t rp = rp_vo_ransac_params(&vo->cfg.ekf);
    rp_ransac_result_t res;
    rp_status_t st = rp_ransac_solve(&vo->rs, vo->rig, vo->obs, n, &rp, vo->inl, &res);
    if (st != RP_OK) {
        return st;
    }
    for (uint32_t i = 0; i < n; ++i) {
        if (!vo->inl[i]) {
            vo->obs[i].w = RP_C(0.0);
        }
    }
    memcpy(p, res.p, 6 * sizeof(rp_real));
    uint32_t n_in = res.n_inliers;
    /* Rescue: the consensus of one camera's P3P poses can leave out a whole camera whose
     * observations pin a direction the inliers hardly see (the pose is off along it by more
     * than the pixel gate shows in that camera). Each round, Lowe's method on the inliers, then
     * every outlier whose innovation passes the filter's gate with the pose's uncertainty,
     * r^T (J s2 cov J^T + 2 s2 I)^-1 r <= chi2, joins (Civera et al.'s rescue of high-innovation
     * inliers, with Lowe's covariance as the posterior). Measured on the blind-direction test
     * (test_vo_stereo.c): without it the start kept 74 of 122 observations, none of camera 3's,
     * and was 3.4 mm off; with it all, and 0.6 mm, as Lowe's method on everything. */
    const rp_real s2 = rp.sigma_px * rp.sigma_px / RP_C(2.0); /* sigma_px^2 */
    for (int round = 0; round < 4; ++round) {
        st = rp_lowe_solve(vo->rig, vo->obs, n, &rp.lowe, p, NULL, cov);
        if ((st != RP_OK && st != RP_E_NO_CONVERGE) || !rp_all_finite(p, 6)) {
            return st != RP_OK ? st : RP_E_NAN;
        }
        rp_pose_lin_t pl;
        if (round == 3 || rp_pose_lin_set(&pl, p) != RP_OK) {
            break;
        }
        uint32_t added = 0;
        for (uint32_t i = 0; i < n; ++i) {
            rp_real uv[2], J[12];
            if (vo->inl[i] || !rp_all_finite(vo->obs[i].uv, 2) ||
                rp_rig_project(vo->rig, vo->obs[i].cam, &pl, vo->obs[i].M, uv, J, NULL) != RP_OK) {
                continue;
            }
            /* S = s2 (J cov J^T + 2 I): r^T S^-1 r = r^T (J cov J^T + 2 I)^-1 r / s2 */
            const rp_real r[2] = {vo->obs[i].uv[0] - uv[0], vo->obs[i].uv[1] - uv[1]};
            if (rp_ekf_mahalanobis2(J, cov, RP_C(2.0), r) / s2 <= rp.chi2) {
                vo->inl[i] = 1;
                vo->obs[i].w = RP_C(1.0);
                added++;
            }
        }
        if (added == 0) {
            break;
        }
        n_in += added;
    }
    robust_refine(vo, n, &rp, p, cov);
    *n_inl = n_in;
    return RP_OK;
}

/* Step (2): the second frame starts the filter with Lowe's method on all correspondences
 * (with cfg.ransac: on rig RANSAC's inliers); the velocity is the displacement over dt. */
static rp_status_t start_with_lowe(rp_vo_stereo_t *vo, uint32_t n, rp_real dt)
{
    rp_lowe_params_t lp = rp_lowe_default_params();
    rp_real p[6] = {0}, cov[36];
    uint32_t n_inl = 0;
    if (vo->cfg.ransac && robust_pose(vo, n, p, cov, &n_inl) == RP_OK) {
        memcpy(vo->used, vo->inl, n);
        return rp_vo_ekf_from_pose(&vo->ekf, &vo->cfg.ekf, p, cov, vo->prev_p, dt);
    }
    for (uint32_t i = 0; i < n; ++i) {
        vo->obs[i].w = RP_C(1.0); /* a failed RANSAC may have left weights */
    }
    for (int i = 0; i < 6; ++i) {
        p[i] = vo->ekf.x[i];
    }
    rp_status_t st = rp_lowe_solve(vo->rig, vo->obs, n, &lp, p, NULL, cov);
    if (st != RP_OK && st != RP_E_NO_CONVERGE) {
        return st;
    }
    const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
    /* Lowe's method has no gate: one mistracked feature moves this first pose, and the filter
     * keeps the offset. Leave out the observations the EKF's gate would reject at this pose
     * and solve again. */
    rp_pose_lin_t pl;
    uint32_t n_out = 0;
    if (vo->cfg.ekf.gate_chi2 > RP_C(0.0) && rp_pose_lin_set(&pl, p) == RP_OK) {
        for (uint32_t i = 0; i < n; ++i) {
            rp_real uv[2];
            vo->used[i] = 1;
            if (rp_rig_project(vo->rig, vo->obs[i].cam, &pl, vo->obs[i].M, uv, NULL, NULL) ==
                RP_OK) {
                const rp_real du = vo->obs[i].uv[0] - uv[0], dv = vo->obs[i].uv[1] - uv[1];
                if ((du * du + dv * dv) * vo->obs[i].w > vo->cfg.ekf.gate_chi2 * s2) {
                    vo->obs[i].w = RP_C(0.0);
                    vo->used[i] = 0;
                    n_out++;
                }
            }
        }
    }
    if (n_out > 0 && n - n_out >= vo->cfg.ekf.min_features) {
        st = rp_lowe_solve(vo->rig, vo->obs, n, &lp, p, NULL, cov);
        if (st != RP_OK && st != RP_E_NO_CONVERGE) {
            return st;
        }
    } else {
        memset(vo->used, 1, n);
    }
    return rp_vo_ekf_from_pose(&vo->ekf, &vo->cfg.ekf, p, cov, vo->prev_p, dt);
}

/* 1 if the last update gated most of some pair's observations (of a pair that offered at least
 * the EKF's minimum). Outlier tracks are independent events: a gate that rejects a whole pair
 * is judging the prior, not the features. */
static int pair_rejected(const rp_vo_stereo_t *vo, uint32_t n)
{
    uint16_t offered[RP_MAX_PAIRS] = {0}, kept[RP_MAX_PAIRS] = {0};
    for (uint32_t i = 0; i < n; ++i) {
        const uint8_t k = pair_of_cam(vo, vo->obs[i].cam);
        if (k < vo->cfg.n_pairs) {
            offered[k]++;
            kept[k] = (uint16_t)(kept[k] + vo->used[i]);
        }
    }
    for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
        if (offered[k] >= vo->cfg.ekf.min_features && 2u * kept[k] < offered[k]) {
            return 1;
        }
    }
    return 0;
}

/* The update redone from the prediction with the pose covariance widened by d d^T, d the gap
 * from the predicted pose to p (a pose found from the images), so that the velocity keeps its
 * correlation with the pose; through 1-point RANSAC with cfg.one_point. The update's status;
 * retry receives its report. */
static rp_status_t update_towards(rp_vo_stereo_t *vo, const rp_real p[6], uint32_t n,
                                  rp_ekf_info_t *retry)
{
    /* ignored: only NULL arguments fail */
    (void)rp_vo_ekf_towards(&vo->ekf_pred, p, &vo->ekf);
    if (vo->cfg.one_point) {
        /* the retry too keeps to the largest consensus: a self-consistent group (a moving
         * object) that the first update left out must not come back through it */
        rp_ekf1pt_info_t oi;
        const rp_status_t st =
            rp_ekf1pt_update(&vo->op, &vo->ekf, vo->rig, vo->obs, n, NULL, vo->used, &oi);
        *retry = oi.ekf;
        return st;
    }
    return rp_ekf_update(&vo->ekf, vo->rig, vo->obs, n, vo->used, retry);
}

/* Step (3): predict, then the iterated update over all cameras' features.
 *
 * The gate of the update's first iteration compares each feature with the prediction. The
 * constant-velocity prediction can be far off (the paper's motion draws independent
 * increments every frame), and when it is off along a direction one pair hardly sees (tx
 * against beta for a camera looking along z: a shift x = z beta), that pair's features all
 * agree with the prediction while the other pair's all disagree and are gated; the update then
 * slides along the first pair's blind direction and the other pair's landmarks are dropped as
 * outliers: the pose stays off for good. So when the gate rejects most of a pair, the update is
 * redone from the same prediction with its pose covariance widened by d d^T, d the gap between
 * the prediction and the pose Lowe's method finds from all observations; the retry is kept if
 * it uses more observations than the first update. */
static rp_status_t predict_update(rp_vo_stereo_t *vo, uint32_t n, rp_real dt,
                                  rp_ekf_info_t *info)
{
    vo->refind_inl = 0;
    rp_status_t st = rp_ekf_predict(&vo->ekf, dt);
    if (st != RP_OK) {
        return st;
    }
    vo->ekf_pred = vo->ekf;
    if (vo->cfg.one_point) {
        rp_ekf1pt_info_t oi;
        st = rp_ekf1pt_update(&vo->op, &vo->ekf, vo->rig, vo->obs, n, NULL, vo->used, &oi);
        *info = oi.ekf;
    } else {
        st = rp_ekf_update(&vo->ekf, vo->rig, vo->obs, n, vo->used, info);
    }
    /* "most features outside the gate": in its final test, also when the update then used them
     * all (rp_ekf.h), or no update for want of features that passed it */
    const int most_gated = st == RP_OK ? 2u * info->n_outside > n
                                       : n >= vo->cfg.ekf.min_features;
    if (!(st == RP_OK && pair_rejected(vo, n)) && !(vo->cfg.ransac && most_gated)) {
        return st;
    }
    /* keep the first update's result, to restore it if the retry is no better */
    const rp_ekf_t first = vo->ekf;
    const rp_ekf_info_t first_info = *info;
    /* observations that agree with the first update: used and inside its final gate test */
    const uint16_t first_n =
        st != RP_OK ? 0
        : (uint16_t)(first_info.n_used + first_info.n_gated > first_info.n_outside
                         ? first_info.n_used + first_info.n_gated - first_info.n_outside
                         : 0);
    uint8_t first_used[sizeof vo->used];
    memcpy(first_used, vo->used, n);
    if (vo->cfg.ransac) {
        /* The prediction is wrong: re-find the pose from the images. RANSAC's outliers get
         * w = 0 (so used = 0, and their landmarks are dropped); the update is redone on its
         * inliers from the prediction with the pose covariance widened by d d^T, d the gap to
         * the re-found pose (so the velocity keeps its correlation with the pose); if that
         * still uses fewer than RANSAC found, the filter restarts at the re-found pose. */
        rp_real p[6], cov[36], first_cost = RP_C(0.0), found_cost = RP_C(0.0);
        uint32_t n_inl = 0;
        const int costed =
            st == RP_OK &&
            rp_ekf1pt_cost(&vo->ekf, vo->rig, vo->obs, n, vo->ekf.x, &first_cost, NULL) == RP_OK;
        const rp_status_t sr = robust_pose(vo, n, p, cov, &n_inl);
        vo->refind_inl = sr == RP_OK ? n_inl : 0u;
        if (sr == RP_OK && costed) {
            /* the re-found pose's cost on every observation at weight 1 (as they all were
             * before robust_pose weighted its outliers 0) */
            for (uint32_t i = 0; i < n; ++i) {
                vo->obs[i].w = RP_C(1.0);
            }
            if (rp_ekf1pt_cost(&vo->ekf, vo->rig, vo->obs, n, p, &found_cost, NULL) != RP_OK) {
                found_cost = first_cost;
            }
            inlier_weights(vo, n);
        }
        /* Re-found if RANSAC holds more observations, or fits them better by more than a
         * pose error at the pixel noise explains: the first update's posterior lies off the
         * least-squares pose by its prior's pull, which raises the cost by about
         * chi2(6 dof) s2 (REFIND_CHI2_6, 99.9 %); a posterior that a coherent group of
         * outliers (a moving object) drew off costs far more. */
        const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
        if (sr == RP_OK &&
            (n_inl > first_n || (costed && found_cost + REFIND_CHI2_6 * s2 < first_cost))) {
            rp_ekf_info_t retry;
            vo->n_retried++;
            vo->n_refound++;
            if (update_towards(vo, p, n, &retry) == RP_OK && 2u * retry.n_used >= n_inl) {
                *info = retry;
                info->n_gated = (uint16_t)(info->n_gated + n - n_inl); /* RANSAC's outliers */
                return RP_OK;
            }
            if (rp_vo_ekf_from_pose(&vo->ekf, &vo->cfg.ekf, p, cov, vo->prev_p, dt) == RP_OK) {
                memcpy(vo->used, vo->inl, n);
                memset(info, 0, sizeof(*info));
                info->n_used = (uint16_t)n_inl;
                info->n_gated = (uint16_t)(n - n_inl);
                return RP_OK;
            }
            vo->n_retried--;
            vo->n_refound--;
        }
        for (uint32_t i = 0; i < n; ++i) {
            vo->obs[i].w = RP_C(1.0);
        }
        vo->ekf = first;
        memcpy(vo->used, first_used, n);
        *info = first_info;
        if (st != RP_OK) {
            return st;
        }
    }
    rp_lowe_params_t lp = rp_lowe_default_params();
    rp_real p[6];
    memcpy(p, vo->ekf_pred.x, sizeof(p));
    const rp_status_t sl = rp_lowe_solve(vo->rig, vo->obs, n, &lp, p, NULL, NULL);
    if ((sl != RP_OK && sl != RP_E_NO_CONVERGE) || !rp_all_finite(p, 6)) {
        return st;
    }
    rp_ekf_info_t retry;
    if (update_towards(vo, p, n, &retry) == RP_OK && retry.n_used > first_info.n_used) {
        vo->n_retried++;
        *info = retry;
        return RP_OK;
    }
    vo->ekf = first;
    memcpy(vo->used, first_used, n);
    *info = first_info;
    return st;
}

rp_status_t rp_vo_stereo_step(rp_vo_stereo_t *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    if (!vo || !est) {
        return RP_E_ARG;
    }
    memset(est, 0, sizeof(*est));
    rp_real dt;
    if (rp_vo_begin_step(vo->rig, fs, vo->prev_utime, vo->cfg.default_dt_s, &dt) != RP_OK) {
        fill_estimate(vo, NULL, RP_EST_LOST, est);
        return RP_E_ARG;
    }
    if (vo->frame == 0) {
        return first_frame(vo, fs, est);
    }
    vo->skewed = 0;
    vo->refind_inl = 0;
    uint32_t flags = 0;
    /* The pairs whose first camera delivered an image: a pair without one (a slower camera
     * between its frames: RP_FS_NO_IMAGE) keeps its landmarks for its next image. */
    uint32_t imaged = 0;
    for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
        imaged |= (fs->cam_flags[vo->pair[k].a] & RP_FS_NO_IMAGE) ? 0u : (1u << k);
    }

    retired_prune(vo, fs);
    /* Which landmarks are still tracked; lost ones are dropped. */
    uint32_t n = gather_obs(vo, fs);
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_mark_ids(&vo->lm, vo->obs_id, NULL, n);
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_drop_unmarked(&vo->lm, imaged, NULL);

    /* Step (5): a pair under its threshold is re-initialised from the previous frame set at
     * the previous pose (backtracking one frame), with matches still tracked now. */
    int reinit = 0;
    for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
        if (vo->lm.map.n_group[k] < vo->cfg.min_tracked && (imaged & (1u << k))) {
            /* ignored: the count is not needed here */
            (void)triangulate_pair(vo, k, &vo->prev, vo->prev_p, fs, 0);
            reinit = 1;
        }
    }
    if (reinit) {
        flags |= RP_EST_REINIT;
        n = gather_obs(vo, fs);
    }
    for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
        if (vo->lm.map.n_group[k] < vo->cfg.min_tracked) {
            flags |= RP_EST_DEGRADED;
        }
    }

    rp_status_t st;
    uint16_t n_gated = 0;
    if (vo->frame == 1) {
        st = start_with_lowe(vo, n, dt);
        for (uint32_t i = 0; st == RP_OK && vo->cfg.ransac && i < n; ++i) {
            n_gated = (uint16_t)(n_gated + !vo->used[i]); /* RANSAC's outliers are dropped */
        }
    } else {
        rp_ekf_info_t info;
        memset(&info, 0, sizeof(info));
        st = predict_update(vo, n, dt, &info);
        n_gated = info.n_gated;
        if (info.cov_reset) {
            flags |= RP_EST_COV_RESET;
        }
        if (info.toff_reset) {
            flags |= RP_EST_CLOCK_JUMP;
        }
    }

    for (uint8_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        est->n_used[cam] = 0;
    }
    if (st == RP_OK) {
        flags |= RP_EST_TRACKING;
        /* A landmark whose observations the updates leave out is an outlier track: drop it
         * (the drop test, rp_vo_stereo.h). */
        for (uint32_t i = 0; i < n; ++i) {
            if (vo->used[i]) {
                est->n_used[vo->obs[i].cam]++;
            }
        }
        drop_test(vo, n);
        /* ignored: only NULL arguments fail */
        (void)rp_lmtab_mark_ids(&vo->lm, vo->obs_id, vo->keep, n);
        if (vo->cfg.refine_structure) {
            /* step 4: each used observation updates its landmark at the new pose */
            /* ignored: a point its gate refuses stays as it was (the gate, not a fault) */
            (void)rp_lmtab_refine(&vo->lm, vo->rig, vo->ekf.x, vo->ekf.x + 6, vo->ekf.toff,
                                  vo->obs, vo->obs_id, vo->used, n, vo->cfg.ekf.sigma_px,
                                  vo->cfg.ekf.gate_chi2);
        }
        if (n_gated > 0) {
            flags |= RP_EST_GATED;
        }
        /* ignored: only NULL arguments fail */
        (void)rp_lmtab_drop_unmarked(&vo->lm, n_gated > 0 ? imaged : 0u, NULL);
        if (n_gated > 0) {
            retire_dropped(vo, n);
        }
        /* the failed matches listed before (with their first pixels), then (step 5,
         * add_landmarks) every other match not yet a landmark, which lists this frame set's
         * failures anew; both at the updated pose */
        for (uint8_t k = 0; k < vo->cfg.n_pairs; ++k) {
            if (!(imaged & (1u << k))) {
                continue;
            }
            if (vo->n_retry[k] > 0) {
                /* ignored: the count is not needed here */
                (void)triangulate_pair(vo, k, fs, vo->ekf.x, NULL, 1);
            }
            if (vo->cfg.add_landmarks) {
                /* ignored: the count is not needed here */
                (void)triangulate_pair(vo, k, fs, vo->ekf.x, NULL, 0);
            }
        }
    } else {
        flags |= RP_EST_LOST;
    }

    vo->prev = *fs;
    for (int i = 0; i < 6; ++i) {
        vo->prev_p[i] = vo->ekf.x[i];
    }
    fill_estimate(vo, fs, flags, est);
    return rp_vo_end_step(fs, n_gated, st, &vo->prev_utime, &vo->frame, est);
}
