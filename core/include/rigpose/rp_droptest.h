/*
 * rp_droptest.h - Page's CUSUM test that a landmark's track went wrong (a moving object, a track
 * slipped onto another surface), from whether each frame set's robust update took its
 * observations in; shared by the stereo layouts and gc (rp_vo_stereo.h, "Dropping a landmark",
 * has the reasoning).
 *
 * An update leaves out an observation either because its landmark's track is wrong (then its
 * observations stay out, but for the chance RP_DROP_PASS that one falls inside the consensus)
 * or because a sound track's pixel read wrong once, at the rate eps at which this frame set's
 * update left out the observations of landmarks that the previous update took in
 * (Krichevsky-Trofimov estimate, at most 1/2: the consensus is a majority; from all
 * observations while fewer than min_past have such a past). Per landmark,
 *   S = max(0, S + sum over its observations in this frame set of
 *                  log((1 - RP_DROP_PASS) / eps) if left out,
 *                  log(RP_DROP_PASS / (1 - eps)) if taken in),
 * and the landmark is dropped when S > log(odds).
 *
 * State per landmark slot of the caller's rp_lmtab_t (RP_IDMAP_MAX_SLOTS); no heap.
 */
#ifndef RP_DROPTEST_H
#define RP_DROPTEST_H

#include <stdint.h>

#include "rp_idmap.h"
#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RP_DROP_PASS RP_C(0.1)
#define RP_DROP_ODDS RP_C(100.0) /* stereo's default drop_odds: a landmark left out in both
                                  * cameras of its pair in one clean frame set goes */
#define RP_DROP_ODDS_ONE (RP_DROP_ODDS * RP_DROP_ODDS) /* the same evidence from one observation
                                  * per frame set (gc): two clean frame sets left out */

typedef struct {
    rp_real s[RP_IDMAP_MAX_SLOTS];   /* per landmark slot: S (above) */
    rp_real sum[RP_IDMAP_MAX_SLOTS]; /* scratch: this frame set's sum */
    uint8_t was_in[RP_IDMAP_MAX_SLOTS]; /* per slot: the last update took it in */
    uint8_t seen[RP_IDMAP_MAX_SLOTS];   /* scratch: 1 started this frame set, 2 and taken in */
} rp_droptest_t;

/* A new landmark in slot: no evidence yet. RP_E_ARG: NULL or slot out of range. */
rp_status_t rp_droptest_reset_slot(rp_droptest_t *dt, uint16_t slot);

/* This frame set's n observations: slot[i] their landmark's slot (RP_IDMAP_MAX_SLOTS or more:
 * none, ignored), in[i] 1 if the update took obs i in. keep[i] = 0 for an observation whose
 * landmark the test drops (the caller removes it), else 1 (in[i] for one without a slot).
 * min_past: the observations with a past that eps needs; odds > 1. RP_E_ARG: NULL with n > 0,
 * or odds not > 1. */
rp_status_t rp_droptest_run(rp_droptest_t *dt, const uint16_t *slot, const uint8_t *in,
                            uint32_t n, uint32_t min_past, rp_real odds, uint8_t *keep);

#ifdef __cplusplus
}
#endif

#endif /* RP_DROPTEST_H */
