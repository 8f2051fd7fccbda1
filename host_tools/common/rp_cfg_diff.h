/*
 * rp_cfg_diff.h - what a tool's pipeline configuration changes from the core's defaults.
 *
 * Every tool runs the core's configuration for a layout (rp_pipe_default_cfg); a tool that
 * deliberately runs something else says so: rp_cfg_diff_print writes one line per field of
 * rp_pipe_cfg_t that the layout uses and that differs from the core's default,
 *
 *   TOOL: LAYOUT FIELD=VALUE (core default VALUE): WHY
 *
 * on the stream given (stderr: the tools' figures on stdout stay as they are). WHY comes from
 * the tool's table of reasons (field-name prefixes), "" if it has none.
 *
 * RP_PIPE_CFG_FIELDS lists every field of rp_pipe_cfg_t with the layouts that use it and its
 * kind; daemon/tests/test_config.c compares the parsed configuration field by field with it and
 * fails if the list misses a field. Header-only, C99 and C++, host code (stdio).
 */
#ifndef RP_CFG_DIFF_H
#define RP_CFG_DIFF_H

#include <stdio.h>
#include <string.h>

#include "rigpose/rp_pipe.h"

/* Which layouts use a field. */
#define RP_CD_ALL 0    /* every layout (the trackers: image input) */
#define RP_CD_STEREO 1 /* stereo4, stereo2 (the matcher and the stereo estimator) */
#define RP_CD_GC 2     /* gc */
#define RP_CD_MONO 3   /* cam1..cam4 and rc (their single-camera estimators) */
#define RP_CD_CAMK 4   /* cam1..cam4 only (rc overrides mono.cam with rc_cams) */
#define RP_CD_RC 5     /* rc */

/* X(field, use, kind): kind R rp_real, U unsigned integer, S signed integer, A uint8_t array,
 * V rp_real array, L the layout. */
#define RP_CD_EKF_FIELDS(X, e, use)                                                               \
    X(e.sigma_px, use, R) X(e.q_trans, use, R) X(e.q_rot, use, R) X(e.gate_chi2, use, R)         \
    X(e.iterations, use, U) X(e.min_features, use, U) X(e.max_predict_s, use, R)               \
    X(e.toff0_s, use, V) X(e.toff_estimate, use, U) X(e.toff_sigma_s, use, R)                    \
    X(e.toff_q, use, R) X(e.time_jitter_s, use, R)                                            \
    X(e.group_time_noise, use, U)
#define RP_PIPE_CFG_FIELDS(X)                                                                     \
    X(layout, RP_CD_ALL, L)                                                                       \
    X(track.cam, RP_CD_ALL, U) X(track.levels, RP_CD_ALL, U) X(track.win, RP_CD_ALL, U)          \
    X(track.max_iter, RP_CD_ALL, U) X(track.eps_q16, RP_CD_ALL, U)                               \
    X(track.min_eig, RP_CD_ALL, U) X(track.fb_max_q16, RP_CD_ALL, U)                             \
    X(track.target, RP_CD_ALL, U) X(track.topup_below, RP_CD_ALL, U)                             \
    X(track.min_dist, RP_CD_ALL, U) X(track.quality_q16, RP_CD_ALL, U)                           \
    X(track.min_response, RP_CD_ALL, U) X(track.grid_x, RP_CD_ALL, U)                            \
    X(track.grid_y, RP_CD_ALL, U) X(track.cell_cap, RP_CD_ALL, U)                                \
    X(track.min_contrast, RP_CD_ALL, U) X(track.max_err_q5, RP_CD_ALL, U)                        \
    X(track.reset_q8, RP_CD_ALL, U)                                                               \
    X(smatch.half_win, RP_CD_STEREO, U) X(smatch.min_zncc_q15, RP_CD_STEREO, S)                  \
    X(smatch.uniq_margin_q15, RP_CD_STEREO, S) X(smatch.min_std, RP_CD_STEREO, U)                \
    X(smatch.min_depth_m, RP_CD_STEREO, R) X(smatch.max_depth_m, RP_CD_STEREO, R)                \
    X(smatch.lr_max_px, RP_CD_STEREO, R) X(smatch.max_epipolar_px, RP_CD_STEREO, R)              \
    X(smatch.subpix_iter, RP_CD_STEREO, U) X(smatch.search_level, RP_CD_STEREO, U)               \
    X(stereo.n_pairs, RP_CD_STEREO, U) X(stereo.pair_a, RP_CD_STEREO, A)                         \
    X(stereo.pair_b, RP_CD_STEREO, A) RP_CD_EKF_FIELDS(X, stereo.ekf, RP_CD_STEREO)              \
    X(stereo.min_tracked, RP_CD_STEREO, U) X(stereo.max_epipolar_px, RP_CD_STEREO, R)            \
    X(stereo.min_depth_m, RP_CD_STEREO, R) X(stereo.max_depth_m, RP_CD_STEREO, R)                \
    X(stereo.max_reproj_px, RP_CD_STEREO, R) X(stereo.default_dt_s, RP_CD_STEREO, R)             \
    X(stereo.max_pair_skew_s, RP_CD_STEREO, R)                                                    \
    X(stereo.refine_structure, RP_CD_STEREO, U) X(stereo.ransac, RP_CD_STEREO, U)                \
    X(stereo.one_point, RP_CD_STEREO, U) X(stereo.drop_odds, RP_CD_STEREO, R)                    \
    X(stereo.retry_triangulation, RP_CD_STEREO, U)                                                \
    X(stereo.retire_outliers, RP_CD_STEREO, U) X(dormant_retired, RP_CD_STEREO, U)               \
    X(stereo.add_landmarks, RP_CD_STEREO, U)                                                      \
    X(gc.n_cams, RP_CD_GC, U) X(gc.cams, RP_CD_GC, A) RP_CD_EKF_FIELDS(X, gc.ekf, RP_CD_GC)      \
    X(gc.min_tracked, RP_CD_GC, U) X(gc.init_depth_m, RP_CD_GC, R)                               \
    X(gc.init_depth_sigma_m, RP_CD_GC, R) X(gc.init_on_sphere, RP_CD_GC, U)                      \
    X(gc.mature_frac, RP_CD_GC, R) X(gc.min_mature, RP_CD_GC, U)                                 \
    X(gc.default_dt_s, RP_CD_GC, R) X(gc.max_eff_obs, RP_CD_GC, R)                               \
    X(gc.scale_sigma, RP_CD_GC, R) X(gc.trans_drift_sigma, RP_CD_GC, R)                          \
    X(gc.rot_drift_sigma, RP_CD_GC, R) X(gc.mscale_sigma, RP_CD_GC, R)                           \
    X(gc.mscale_q, RP_CD_GC, R) X(gc.ba_stride, RP_CD_GC, U) X(gc.ba_kf, RP_CD_GC, U)            \
    X(gc.ba_every, RP_CD_GC, U) X(gc.ba_per_cam, RP_CD_GC, U) X(gc.ba_var_scale, RP_CD_GC, R)    \
    X(gc.ba.iterations, RP_CD_GC, U) X(gc.ba.min_obs, RP_CD_GC, U)                               \
    X(gc.ba.sigma_px, RP_CD_GC, R) X(gc.ba.huber_px, RP_CD_GC, R)                                \
    X(gc.ba.min_angle, RP_CD_GC, R) X(gc.one_point, RP_CD_GC, U) X(gc.ransac, RP_CD_GC, U)       \
    X(gc.drop_odds, RP_CD_GC, R)                                                                  \
    X(mono.cam, RP_CD_CAMK, U) RP_CD_EKF_FIELDS(X, mono.ekf, RP_CD_MONO)                         \
    X(mono.min_tracked, RP_CD_MONO, U) X(mono.init_depth_m, RP_CD_MONO, R)                       \
    X(mono.init_depth_sigma_m, RP_CD_MONO, R) X(mono.default_dt_s, RP_CD_MONO, R)                \
    X(mono.weight_by_structure, RP_CD_MONO, U) X(mono.one_point, RP_CD_MONO, U)                  \
    X(mono.ransac, RP_CD_MONO, U)                                                                 \
    X(rc_cams, RP_CD_RC, A) X(rc_n, RP_CD_RC, U) X(rc.min_trans_m, RP_CD_RC, R) X(rc.min_scale, RP_CD_RC, R)          \
    X(rc.max_scale, RP_CD_RC, R) X(rc.max_scale_se, RP_CD_RC, R)

/* 1 if layout l runs a field of that use. */
static inline int rp_cd_used(int use, rp_pipe_layout_t l)
{
    const int stereo = l == RP_PIPE_STEREO4 || l == RP_PIPE_STEREO2;
    const int camk = l >= RP_PIPE_CAM1 && l <= RP_PIPE_CAM4;
    switch (use) {
    case RP_CD_ALL: return 1;
    case RP_CD_STEREO: return stereo;
    case RP_CD_GC: return l == RP_PIPE_GC;
    case RP_CD_MONO: return camk || l == RP_PIPE_RC;
    case RP_CD_CAMK: return camk;
    case RP_CD_RC: return l == RP_PIPE_RC;
    default: return 0;
    }
}

static inline void rp_cd_fmt_R(char *s, size_t cap, const void *p, size_t size)
{
    rp_real v;
    memcpy(&v, p, size < sizeof v ? size : sizeof v);
    snprintf(s, cap, "%g", (double)v);
}

static inline void rp_cd_fmt_U(char *s, size_t cap, const void *p, size_t size)
{
    unsigned long v = 0;
    if (size == 1) {
        uint8_t x;
        memcpy(&x, p, 1);
        v = x;
    } else if (size == 2) {
        uint16_t x;
        memcpy(&x, p, 2);
        v = x;
    } else {
        uint32_t x;
        memcpy(&x, p, 4);
        v = x;
    }
    snprintf(s, cap, "%lu", v);
}

static inline void rp_cd_fmt_S(char *s, size_t cap, const void *p, size_t size)
{
    int16_t x = 0;
    memcpy(&x, p, size < sizeof x ? size : sizeof x);
    snprintf(s, cap, "%d", (int)x);
}

static inline void rp_cd_fmt_A(char *s, size_t cap, const void *p, size_t size)
{
    const uint8_t *a = (const uint8_t *)p;
    size_t n = 0;
    for (size_t i = 0; i < size && n + 5 < cap; ++i) {
        n += (size_t)snprintf(s + n, cap - n, "%s%u", i ? "," : "[", (unsigned)a[i]);
    }
    snprintf(s + n, cap - n, "]");
}

static inline void rp_cd_fmt_V(char *s, size_t cap, const void *p, size_t size)
{
    const unsigned char *a = (const unsigned char *)p;
    size_t n = 0;
    for (size_t i = 0; i + sizeof(rp_real) <= size && n + 16 < cap; i += sizeof(rp_real)) {
        rp_real v;
        memcpy(&v, a + i, sizeof v);
        n += (size_t)snprintf(s + n, cap - n, "%s%g", i ? "," : "[", (double)v);
    }
    snprintf(s + n, cap - n, "]");
}

static inline void rp_cd_fmt_L(char *s, size_t cap, const void *p, size_t size)
{
    rp_pipe_layout_t l;
    memcpy(&l, p, size < sizeof l ? size : sizeof l);
    snprintf(s, cap, "%s", rp_pipe_layout_name(l));
}

/* The reason for field `f` in why[] ({prefix, reason} pairs, ended by {NULL, NULL}; may be
 * NULL): the first whose prefix starts f. */
static inline const char *rp_cd_reason(const char *const (*why)[2], const char *f)
{
    for (size_t i = 0; why != NULL && why[i][0] != NULL; ++i) {
        if (strncmp(f, why[i][0], strlen(why[i][0])) == 0) {
            return why[i][1];
        }
    }
    return "";
}

/* One line on out per field that cfg's layout uses and that differs from
 * rp_pipe_default_cfg(cfg->layout); returns their count (0 also for a bad layout). */
static inline unsigned rp_cfg_diff_print(FILE *out, const char *tool, const rp_pipe_cfg_t *cfg,
                                         const char *const (*why)[2])
{
    rp_pipe_cfg_t def;
    if (rp_pipe_default_cfg(cfg->layout, &def) != RP_OK) {
        return 0;
    }
    unsigned n = 0;
    char a[96], b[96];
#define RP_CD_PRINT(f, use, kind)                                                                 \
    if (rp_cd_used(use, cfg->layout) && memcmp(&cfg->f, &def.f, sizeof cfg->f) != 0) {           \
        rp_cd_fmt_##kind(a, sizeof a, &cfg->f, sizeof cfg->f);                                    \
        rp_cd_fmt_##kind(b, sizeof b, &def.f, sizeof def.f);                                      \
        const char *r = rp_cd_reason(why, #f);                                                    \
        fprintf(out, "%s: %s %s=%s (core default %s)%s%s\n", tool,                                \
                rp_pipe_layout_name(cfg->layout), #f, a, b, r[0] ? ": " : "", r);                 \
        ++n;                                                                                      \
    }
    RP_PIPE_CFG_FIELDS(RP_CD_PRINT)
#undef RP_CD_PRINT
    return n;
}

#endif /* RP_CFG_DIFF_H */
