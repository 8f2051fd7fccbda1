/*
 * rp_hal_priv.h - inside the HAL: each source is a const table of functions over its own context
 * (static, one per process); rp_hal_common.c dispatches rp_hal_* to the table of cfg.kind.
 */
#ifndef RP_HAL_PRIV_H
#define RP_HAL_PRIV_H

#include <stddef.h>

#include "rigpose/rp_hal.h"

#define RP_HAL_ERR_MAX 320

/* err: the source object's message buffer (RP_HAL_ERR_MAX bytes), kept by the source for its
 * later calls; it writes there whenever it returns a failure. */
typedef struct {
    const char *name;
    rp_hal_payload_t payload; /* what its sets carry */
    rp_hal_status_t (*open)(void **ctx, const rp_hal_cfg_t *cfg, char *err);
    rp_hal_status_t (*start)(void *ctx);
    rp_hal_status_t (*grab)(void *ctx, rp_hal_set_t *set);
    rp_hal_status_t (*stop)(void *ctx);
    void (*close)(void *ctx);
} rp_hal_ops_t;

extern const rp_hal_ops_t rp_hal_v4l2_ops;
extern const rp_hal_ops_t rp_hal_replay_ops;
extern const rp_hal_ops_t rp_hal_sim_ops;

/* printf into err (RP_HAL_ERR_MAX bytes), truncating, with control characters and invalid UTF-8
 * escaped as \xNN (rp_esc.h: values echoed from files cannot move the terminal); returns st
 * so a failure is one line:
 * return rp_hal_fail(err, RP_HAL_E_OPEN, "%s: %s", path, strerror(errno)); */
rp_hal_status_t rp_hal_fail(char *err, rp_hal_status_t st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* An empty set of n cameras: every camera MISSING, no image, no truth, no features. */
void rp_hal_set_clear(rp_hal_set_t *set, uint8_t n);

#endif /* RP_HAL_PRIV_H */
