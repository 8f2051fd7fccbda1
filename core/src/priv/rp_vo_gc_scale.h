/*
 * priv/rp_vo_gc_scale.h - gc's metric-scale machinery (rp_vo_gc.h, step 6), apart from the
 * filter: rp_vo_gc_scale.c. Core-internal: used by rp_vo_gc.c only.
 */
#ifndef RP_PRIV_VO_GC_SCALE_H
#define RP_PRIV_VO_GC_SCALE_H

#include "rigpose/rp_vo_gc.h"

/* The map's unit: mu map units per metre; vo->rig_m becomes the rig with offsets D_k * mu. The
 * landmarks are not moved. */
void rp_vo_gc_set_mu(rp_vo_gc_t *vo, rp_real mu);

/* At the first frame set: mu = 1 with its prior variance mscale_sigma^2, the keyframe window
 * empty, the counters zero. */
void rp_vo_gc_scale_reset(rp_vo_gc_t *vo);

/* After the pose update of frame set fs (no-op while mscale_sigma is 0): advance an adjustment
 * under way by one piece (not when busy: the frame set re-found its pose, step 2, and the
 * piece waits for the next one) and take it when solved; every ba_stride frames keep a
 * keyframe, every ba_every keyframes start an adjustment. A taken adjustment changes mu, the
 * landmarks and the filter's pose (rp_vo_gc.h, step 6). */
void rp_vo_gc_scale_step(rp_vo_gc_t *vo, const rp_frameset_t *fs, int busy);

#endif /* RP_PRIV_VO_GC_SCALE_H */
