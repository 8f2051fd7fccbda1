/*
 * rp_lmtab.h - the estimators' landmark table (no heap): every layout (rp_vo_stereo, rp_vo_mono,
 * rp_vo_gc) keeps its landmarks here.
 *
 * A landmark is a 3-D point with its covariance (rp_point3_t, refined by its structure EKF),
 * found by the feature id the tracker gave it, and owned by a group (the stereo pair that
 * triangulated it, or the camera that sees it). The table is an rp_idmap_t (id -> slot, groups,
 * marks) and the points by slot; a layout that keeps more per landmark (gc: its maturity) keeps
 * an array of its own indexed by the same slot. A slot never moves while its landmark lives.
 *
 * One frame's life of the table, as every layout uses it:
 *   rp_lmtab_gather     the observations of held landmarks in a frame set (rp_obs_t, for the
 *                       pose EKF and Lowe's method), with each observation's landmark id;
 *   rp_lmtab_mark_ids   mark the landmarks that were seen (or used by the update);
 *   rp_lmtab_drop_unmarked  drop the unmarked ones of some groups (lost or gated tracks);
 *   rp_lmtab_refine     each used observation updates its landmark's structure EKF.
 * Capacity: RP_IDMAP_MAX_SLOTS landmarks (rp_idmap.h).
 */
#ifndef RP_LMTAB_H
#define RP_LMTAB_H

#include "rp_frame.h"
#include "rp_idmap.h"
#include "rp_obs.h"
#include "rp_rig.h"
#include "rp_status.h"
#include "rp_struct.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    rp_idmap_t map;                    /* feature id -> slot; group; mark = seen this frame */
    rp_point3_t pt[RP_IDMAP_MAX_SLOTS]; /* each held slot's point: world position (m, in the
                                         * layout's world and unit) and covariance */
} rp_lmtab_t;

/* Empty the table. RP_E_ARG if t is NULL. */
rp_status_t rp_lmtab_clear(rp_lmtab_t *t);

/* Add landmark id of group with point *pt; its slot (unmarked) in *slot (may be NULL).
 * RP_E_ARG (NULL t or pt, id RP_IDMAP_EMPTY, group out of range, id already held), RP_E_FULL
 * (table full; nothing stored). */
rp_status_t rp_lmtab_insert(rp_lmtab_t *t, uint32_t id, uint8_t group, const rp_point3_t *pt,
                            uint16_t *slot);

/* Slot of landmark id in *slot. RP_E_NOT_FOUND if not held; RP_E_ARG on a NULL pointer. */
rp_status_t rp_lmtab_find(const rp_lmtab_t *t, uint32_t id, uint16_t *slot);

/* What slot holds: its id, group and point (each output may be NULL). RP_E_NOT_FOUND for a
 * free slot, RP_E_ARG (NULL t, slot >= RP_IDMAP_MAX_SLOTS). */
rp_status_t rp_lmtab_slot(const rp_lmtab_t *t, uint16_t slot, uint32_t *id, uint8_t *group,
                          rp_point3_t *pt);

/* Observations of the held landmarks in fs, camera by camera in the order cams[0..n_cams) and
 * feature by feature: a feature with a finite pixel whose id is held (and, with own_group, whose
 * landmark's group is that camera) gives obs[k] = {its pixel, the landmark's M, w = 1, the
 * camera} and ids[k] = its id. At most cap are written; *n gets their number. RP_E_ARG (NULL,
 * a camera >= RP_MAX_CAMS), RP_E_FULL (more than cap: the first cap are kept). */
rp_status_t rp_lmtab_gather(const rp_lmtab_t *t, const rp_frameset_t *fs, const uint8_t *cams,
                            uint8_t n_cams, uint8_t own_group, rp_obs_t *obs, uint32_t *ids,
                            uint32_t cap, uint32_t *n);

/* Mark the landmarks ids[0..n) that are held (with used non-NULL: only where used[i] != 0).
 * RP_E_ARG on a NULL t, or ids with n > 0. */
rp_status_t rp_lmtab_mark_ids(rp_lmtab_t *t, const uint32_t *ids, const uint8_t *used,
                              uint32_t n);

/* Drop every unmarked landmark whose group's bit is set in group_mask (bit g = group g;
 * RP_IDMAP_ALL_GROUPS: all; 0: none), then clear every mark. *n_dropped (may be NULL) gets how
 * many were dropped. RP_E_ARG if t is NULL. */
rp_status_t rp_lmtab_drop_unmarked(rp_lmtab_t *t, uint32_t group_mask, uint16_t *n_dropped);

/* Structure EKF step of every used observation: obs[i] (with used[i] != 0, or every one if used
 * is NULL) updates the point of landmark ids[i], seen by camera obs[i].cam of rig at pose p
 * ([t, angles] in the layout's world) moved to that camera's capture time: obs[i].dt +
 * toff[cam] seconds at rate xi (rp_pose_lin_at; xi or toff NULL: every camera at p, offsets
 * 0), with pixel noise sigma_px and gate gate_chi2 (rp_struct_update; a gated or failed update
 * leaves that point as it was). RP_E_ARG (NULL), rp_pose_lin_set's errors (nothing updated). */
rp_status_t rp_lmtab_refine(rp_lmtab_t *t, const rp_rig_t *rig, const rp_real p[6],
                            const rp_real xi[6], const rp_real toff[RP_MAX_CAMS],
                            const rp_obs_t *obs, const uint32_t *ids, const uint8_t *used,
                            uint32_t n, rp_real sigma_px, rp_real gate_chi2);

#ifdef __cplusplus
}
#endif

#endif /* RP_LMTAB_H */
