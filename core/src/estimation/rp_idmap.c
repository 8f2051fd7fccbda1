/*
 * rp_idmap.c - feature id -> slot map (see rp_idmap.h).
 */
#include <string.h>

#include "rigpose/rp_idmap.h"

#define MASK (RP_IDMAP_CELLS - 1u)

RP_STATIC_ASSERT((RP_IDMAP_CELLS & (RP_IDMAP_CELLS - 1)) == 0, "cells: a power of two");

uint32_t rp_idmap_hash(uint32_t id)
{
    id ^= id >> 16;
    id *= 0x7feb352dU;
    id ^= id >> 15;
    id *= 0x846ca68bU;
    id ^= id >> 16;
    return id;
}

rp_status_t rp_idmap_clear(rp_idmap_t *m)
{
    if (!m) {
        return RP_E_ARG;
    }
    for (uint32_t i = 0; i < RP_IDMAP_CELLS; ++i) {
        m->cell_id[i] = RP_IDMAP_EMPTY;
    }
    /* Slot 0 on top of the stack, so a fresh map hands out 0, 1, 2, ... */
    for (uint32_t s = 0; s < RP_IDMAP_MAX_SLOTS; ++s) {
        m->slot_id[s] = RP_IDMAP_EMPTY;
        m->free_slot[s] = (uint16_t)(RP_IDMAP_MAX_SLOTS - 1 - s);
    }
    memset(m->cell_slot, 0, sizeof(m->cell_slot));
    memset(m->slot_group, 0, sizeof(m->slot_group));
    memset(m->slot_mark, 0, sizeof(m->slot_mark));
    memset(m->n_group, 0, sizeof(m->n_group));
    m->n_free = RP_IDMAP_MAX_SLOTS;
    m->n = 0;
    return RP_OK;
}

/* Cell holding id, or the empty cell ending its probe run. */
static uint32_t probe(const rp_idmap_t *m, uint32_t id)
{
    uint32_t i = rp_idmap_hash(id) & MASK;
    while (m->cell_id[i] != RP_IDMAP_EMPTY && m->cell_id[i] != id) {
        i = (i + 1u) & MASK;
    }
    return i;
}

/* 1 and its cell in *cell if id is held, else 0. */
static int held_at(const rp_idmap_t *m, uint32_t id, uint32_t *cell)
{
    if (id == RP_IDMAP_EMPTY) {
        return 0;
    }
    *cell = probe(m, id);
    return m->cell_id[*cell] == id;
}

rp_status_t rp_idmap_insert(rp_idmap_t *m, uint32_t id, uint8_t group, uint16_t *slot)
{
    if (!m || !slot || id == RP_IDMAP_EMPTY || group >= RP_IDMAP_MAX_GROUPS) {
        return RP_E_ARG;
    }
    uint32_t i = probe(m, id);
    if (m->cell_id[i] == id) {
        *slot = m->cell_slot[i];
        return RP_E_ARG; /* already held */
    }
    if (m->n_free == 0) {
        return RP_E_FULL;
    }
    uint16_t s = m->free_slot[--m->n_free];
    m->cell_id[i] = id;
    m->cell_slot[i] = s;
    m->slot_id[s] = id;
    m->slot_group[s] = group;
    m->slot_mark[s] = 0;
    m->n++;
    m->n_group[group]++;
    *slot = s;
    return RP_OK;
}

rp_status_t rp_idmap_find(const rp_idmap_t *m, uint32_t id, uint16_t *slot)
{
    if (!m || !slot) {
        return RP_E_ARG;
    }
    uint32_t i;
    if (!held_at(m, id, &i)) {
        return RP_E_NOT_FOUND;
    }
    *slot = m->cell_slot[i];
    return RP_OK;
}

/* Empty cell i, shifting later members of its probe run back so lookups stay correct: an
 * entry at j may fill the hole unless its home cell lies cyclically inside (hole, j]. */
static void remove_cell(rp_idmap_t *m, uint32_t i)
{
    uint16_t s = m->cell_slot[i];
    m->n--;
    m->n_group[m->slot_group[s]]--;
    m->slot_id[s] = RP_IDMAP_EMPTY;
    m->slot_mark[s] = 0;
    m->free_slot[m->n_free++] = s;
    uint32_t hole = i;
    uint32_t j = i;
    for (;;) {
        j = (j + 1u) & MASK;
        if (m->cell_id[j] == RP_IDMAP_EMPTY) {
            break;
        }
        uint32_t home = rp_idmap_hash(m->cell_id[j]) & MASK;
        int in_range = hole <= j ? (home > hole && home <= j) : (home > hole || home <= j);
        if (!in_range) {
            m->cell_id[hole] = m->cell_id[j];
            m->cell_slot[hole] = m->cell_slot[j];
            hole = j;
        }
    }
    m->cell_id[hole] = RP_IDMAP_EMPTY;
}

rp_status_t rp_idmap_remove(rp_idmap_t *m, uint32_t id)
{
    if (!m) {
        return RP_E_ARG;
    }
    uint32_t i;
    if (!held_at(m, id, &i)) {
        return RP_E_NOT_FOUND;
    }
    remove_cell(m, i);
    return RP_OK;
}

rp_status_t rp_idmap_mark(rp_idmap_t *m, uint16_t slot)
{
    if (!m || slot >= RP_IDMAP_MAX_SLOTS || m->slot_id[slot] == RP_IDMAP_EMPTY) {
        return RP_E_ARG;
    }
    m->slot_mark[slot] = 1;
    return RP_OK;
}

rp_status_t rp_idmap_drop_unmarked(rp_idmap_t *m, uint32_t group_mask, uint16_t *n_dropped)
{
    if (!m) {
        return RP_E_ARG;
    }
    uint16_t n = 0;
    for (uint32_t s = 0; s < RP_IDMAP_MAX_SLOTS; ++s) {
        uint32_t id = m->slot_id[s];
        if (id != RP_IDMAP_EMPTY && !m->slot_mark[s] &&
            ((group_mask >> m->slot_group[s]) & 1u)) {
            remove_cell(m, probe(m, id));
            ++n;
        }
    }
    memset(m->slot_mark, 0, sizeof(m->slot_mark));
    if (n_dropped) {
        *n_dropped = n;
    }
    return RP_OK;
}

rp_status_t rp_idmap_clear_marks(rp_idmap_t *m)
{
    if (!m) {
        return RP_E_ARG;
    }
    memset(m->slot_mark, 0, sizeof(m->slot_mark));
    return RP_OK;
}
