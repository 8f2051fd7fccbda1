/*
 * rp_hal_common.c - rp_hal_open's dispatch to the sources' tables, status strings, clock, sleep.
 */
#include "rp_hal_priv.h"
#include "rigpose/rp_esc.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

const char *rp_hal_status_str(rp_hal_status_t s)
{
    switch (s) {
    case RP_HAL_OK: return "ok";
    case RP_HAL_E_ARG: return "bad argument or configuration";
    case RP_HAL_E_OPEN: return "device or file could not be opened";
    case RP_HAL_E_FORMAT: return "no usable format, or a malformed file";
    case RP_HAL_E_IO: return "I/O error";
    case RP_HAL_E_TIMEOUT: return "timeout: no complete frame set";
    case RP_HAL_E_END: return "end of the frames";
    case RP_HAL_E_STATE: return "call out of order";
    }
    return "unknown HAL status";
}

rp_hal_status_t rp_hal_fail(char *err, rp_hal_status_t st, const char *fmt, ...)
{
    char raw[RP_HAL_ERR_MAX];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(raw, sizeof raw, fmt, ap); /* cut at RP_HAL_ERR_MAX - 1: a message is a line */
    va_end(ap);
    rp_esc_text(err, RP_HAL_ERR_MAX, raw);
    return st;
}

void rp_hal_set_clear(rp_hal_set_t *set, uint8_t n)
{
    memset(set, 0, sizeof *set);
    set->n_cams = n;
    for (uint8_t i = 0; i < n; i++) {
        set->cam[i].flags = RP_HAL_CAM_MISSING;
    }
}

struct rp_hal_source {
    const rp_hal_ops_t *ops; /* NULL while closed */
    void *ctx;
    char err[RP_HAL_ERR_MAX];
};

/* One source per process (rp_hal.h). */
static rp_hal_source_t g_src;

rp_hal_status_t rp_hal_open(rp_hal_source_t **src, const rp_hal_cfg_t *cfg)
{
    if (src == NULL) {
        return RP_HAL_E_ARG;
    }
    *src = NULL;
    if (g_src.ops != NULL) {
        return RP_HAL_E_STATE;
    }
    g_src.err[0] = '\0';
    if (cfg == NULL) {
        return RP_HAL_E_ARG;
    }
    if (cfg->n_cams < 1 || cfg->n_cams > RP_MAX_CAMS) {
        /* ignored: it returns the status it was given: here only the message is wanted */
        (void)rp_hal_fail(g_src.err, RP_HAL_E_ARG, "n_cams %u out of 1..%d",
                          (unsigned)cfg->n_cams, RP_MAX_CAMS);
        return RP_HAL_E_ARG;
    }
    const rp_hal_ops_t *ops = NULL;
    switch (cfg->kind) {
    case RP_HAL_SRC_V4L2: ops = &rp_hal_v4l2_ops; break;
    case RP_HAL_SRC_REPLAY: ops = &rp_hal_replay_ops; break;
    case RP_HAL_SRC_SIM: ops = &rp_hal_sim_ops; break;
    case RP_HAL_SRC_LCM:
        return rp_hal_fail(g_src.err, RP_HAL_E_ARG, "source kind lcm is the daemon's "
                           "(rigpose-frontend messages), not a HAL source");
    }
    if (ops == NULL) {
        return rp_hal_fail(g_src.err, RP_HAL_E_ARG, "unknown source kind %d", (int)cfg->kind);
    }
    void *ctx = NULL;
    const rp_hal_status_t st = ops->open(&ctx, cfg, g_src.err);
    if (st != RP_HAL_OK) {
        return st;
    }
    g_src.ops = ops;
    g_src.ctx = ctx;
    *src = &g_src;
    return RP_HAL_OK;
}

rp_hal_status_t rp_hal_start(rp_hal_source_t *src)
{
    if (src == NULL || src->ops == NULL) {
        return RP_HAL_E_ARG;
    }
    src->err[0] = '\0';
    return src->ops->start(src->ctx);
}

rp_hal_status_t rp_hal_grab(rp_hal_source_t *src, rp_hal_set_t *set)
{
    if (src == NULL || src->ops == NULL || set == NULL) {
        return RP_HAL_E_ARG;
    }
    src->err[0] = '\0';
    return src->ops->grab(src->ctx, set);
}

rp_hal_status_t rp_hal_stop(rp_hal_source_t *src)
{
    if (src == NULL || src->ops == NULL) {
        return RP_HAL_E_ARG;
    }
    return src->ops->stop(src->ctx);
}

void rp_hal_close(rp_hal_source_t *src)
{
    if (src == NULL || src->ops == NULL) {
        return;
    }
    src->ops->close(src->ctx);
    src->ops = NULL;
    src->ctx = NULL;
}

rp_hal_payload_t rp_hal_payload(const rp_hal_source_t *src)
{
    if (src == NULL || src->ops == NULL) {
        return RP_HAL_PAYLOAD_IMAGES;
    }
    return src->ops->payload;
}

const char *rp_hal_errmsg(const rp_hal_source_t *src)
{
    if (src == NULL) {
        return g_src.err; /* a failed open leaves its reason here */
    }
    return src->err;
}

int64_t rp_hal_now_us(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) != 0) {
        return 0;
    }
    return (int64_t)ts.tv_sec * 1000000 + (int64_t)(ts.tv_nsec / 1000);
}

void rp_hal_sleep_us(int64_t us)
{
    if (us <= 0) {
        return;
    }
    struct timespec ts;
    ts.tv_sec = (time_t)(us / 1000000);
    ts.tv_nsec = (long)(us % 1000000) * 1000;
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}
