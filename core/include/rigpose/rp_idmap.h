/*
 * rp_idmap.h - feature id -> slot map for the estimators' landmark tables (no heap).
 *
 * The estimators keep one record per landmark (a 3-D point and its covariance, flags) in an
 * array they own, indexed by a slot number. rp_idmap_t hands out those slots and finds a slot
 * from the feature id the tracker gave the landmark:
 *  - the id -> slot lookup is an open-addressing hash table (linear probing, backward-shift
 *    deletion, so lookups never walk tombstones), never more than 3/4 full;
 *  - slots come from a free stack, so a record never moves while its landmark lives (a pointer
 *    into the caller's array stays valid until the landmark is removed);
 *  - each slot carries a group (the camera or stereo pair that made the landmark; counts per
 *    group are kept) and a mark ("observed this frame"), so the estimators' "drop every landmark
 *    not seen this frame" is one call.
 * Capacity is fixed at compile time: RP_IDMAP_MAX_SLOTS landmarks, from RP_MAX_LANDMARKS.
 */
#ifndef RP_IDMAP_H
#define RP_IDMAP_H

#include <stdint.h>

#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RP_IDMAP_CELLS RP_MAX_LANDMARKS                  /* hash cells, a power of two */
#define RP_IDMAP_MAX_SLOTS ((RP_IDMAP_CELLS / 4) * 3)    /* landmarks held at most */
#define RP_IDMAP_MAX_GROUPS RP_MAX_CAMS                  /* groups 0..RP_MAX_CAMS-1 */
#define RP_IDMAP_EMPTY 0xFFFFFFFFu                       /* no id: a free cell or slot */

RP_STATIC_ASSERT(RP_IDMAP_MAX_SLOTS <= 65535, "slots are uint16_t");
RP_STATIC_ASSERT(RP_IDMAP_MAX_GROUPS <= 32, "group masks are 32 bits");

typedef struct {
    uint32_t cell_id[RP_IDMAP_CELLS];       /* id held in each hash cell, or RP_IDMAP_EMPTY */
    uint16_t cell_slot[RP_IDMAP_CELLS];     /* slot of the id in the same cell */
    uint32_t slot_id[RP_IDMAP_MAX_SLOTS];   /* id held in each slot, or RP_IDMAP_EMPTY */
    uint8_t slot_group[RP_IDMAP_MAX_SLOTS]; /* group of each held slot */
    uint8_t slot_mark[RP_IDMAP_MAX_SLOTS];  /* 1: marked since the last drop */
    uint16_t free_slot[RP_IDMAP_MAX_SLOTS]; /* stack of free slots; top at n_free - 1 */
    uint16_t n_free;
    uint16_t n;                             /* ids held */
    uint16_t n_group[RP_IDMAP_MAX_GROUPS];  /* ids held per group */
} rp_idmap_t;

/* The hash of an id used for the cells (a 32-bit integer mix); also for callers' own small
 * id tables. */
uint32_t rp_idmap_hash(uint32_t id);

/* Empty the map: every slot free. RP_E_ARG if m is NULL. */
rp_status_t rp_idmap_clear(rp_idmap_t *m);

/* Add id in group and give its slot (unmarked) in *slot. RP_E_ARG: NULL pointer, id is
 * RP_IDMAP_EMPTY, group >= RP_IDMAP_MAX_GROUPS, or id already held (*slot then names its slot).
 * RP_E_FULL: RP_IDMAP_MAX_SLOTS ids held; nothing stored. */
rp_status_t rp_idmap_insert(rp_idmap_t *m, uint32_t id, uint8_t group, uint16_t *slot);

/* Slot of id in *slot. RP_E_NOT_FOUND if id is not held; RP_E_ARG on a NULL pointer. */
rp_status_t rp_idmap_find(const rp_idmap_t *m, uint32_t id, uint16_t *slot);

/* Remove id; its slot is free for a later insert. RP_E_NOT_FOUND if not held; RP_E_ARG. */
rp_status_t rp_idmap_remove(rp_idmap_t *m, uint32_t id);

/* Mark a held slot (e.g. "observed this frame"). RP_E_ARG: NULL, slot out of range or free. */
rp_status_t rp_idmap_mark(rp_idmap_t *m, uint16_t slot);

/* Remove every unmarked id whose group's bit is set in group_mask (bit g = group g), then
 * clear every mark. *n_dropped (may be NULL) gets the number removed. RP_E_ARG if m is NULL. */
rp_status_t rp_idmap_drop_unmarked(rp_idmap_t *m, uint32_t group_mask, uint16_t *n_dropped);

/* Clear every mark, removing nothing. RP_E_ARG if m is NULL. */
rp_status_t rp_idmap_clear_marks(rp_idmap_t *m);

#define RP_IDMAP_ALL_GROUPS 0xFFFFFFFFu

#ifdef __cplusplus
}
#endif

#endif /* RP_IDMAP_H */
