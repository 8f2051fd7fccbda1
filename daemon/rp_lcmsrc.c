/*
 * rp_lcmsrc.c - frame sets from rigpose-frontend's feature messages (rp_lcmsrc.h).
 */
#include "rp_lcmsrc.h"

#include <stdio.h>
#include <string.h>

#include "rigpose/rp_pipe.h"
#include "rigpose/rp_track.h"
#include "rp_feats.h"

/* ---- track ids of restarted front ends ------------------------------------------------------- */

/* id as the estimator sees it: the serial moved by its camera's offset (rp_lcmsrc.h). */
static uint32_t map_id(rp_lsrc_t *s, uint32_t id, const int8_t instance[32])
{
    const uint8_t c = rp_track_id_cam(id);
    if (!s->id_known[c]) {
        s->id_known[c] = 1;
        memcpy(s->id_inst[c], instance, 32);
    } else if (memcmp(s->id_inst[c], instance, 32) != 0) {
        /* a new front end: its serials start again at 0; continue after the highest seen */
        s->id_off[c] = s->id_hi_set[c] ? (s->id_hi[c] + 1u) & RP_TRACK_SERIAL_MASK : 0u;
        memcpy(s->id_inst[c], instance, 32);
    }
    const uint32_t serial = (rp_track_id_serial(id) + s->id_off[c]) & RP_TRACK_SERIAL_MASK;
    if (!s->id_hi_set[c] || rp_track_serial_since(serial, s->id_hi[c])) {
        s->id_hi[c] = serial;
        s->id_hi_set[c] = 1;
    }
    return rp_track_id(c, serial);
}

/* ---- receiving ------------------------------------------------------------------------------- */

/* |a - b| in us, exact for any two int64_t (no overflow: the network sends any time). */
static uint64_t dist_us(int64_t a, int64_t b)
{
    return a > b ? (uint64_t)a - (uint64_t)b : (uint64_t)b - (uint64_t)a;
}

/* a > b + tol (tol >= 0), without overflow. */
static int later_than(int64_t a, int64_t b, int64_t tol)
{
    return a > b && dist_us(a, b) > (uint64_t)tol;
}

static int absent(const rp_lsrc_t *s, uint8_t k, int64_t now); /* below */

/* sets: latest: the set camera is live (set_camera given and not absent). */
static int set_cam_live(const rp_lsrc_t *s, int64_t now)
{
    return s->set_cam >= 0 && !absent(s, (uint8_t)s->set_cam, now);
}

/* sets: latest: frame (camera k, utime) makes the set ready, its time utime, if it is after the
 * last set's time and after the anchor so far. */
static void latest_anchor(rp_lsrc_t *s, uint8_t k, int64_t utime)
{
    if ((!s->any_out || utime > s->last_set_utime) && (!s->trigger || utime > s->anchor)) {
        s->trigger = 1;
        s->anchor = utime;
        s->anchor_cam = k;
    }
}

/* sets: latest. Camera k's image at utime (after everything it delivered or holds) goes into
 * the one set being filled, in place of an older one of k's not yet delivered (skipped: a slow
 * estimator skips frames rather than falls behind, rp_lsrc_grab drains the queue before a set
 * goes out), and makes the set ready when k is the set camera (or any camera: set_camera any,
 * or the set camera absent) and utime is after the last set's time: the set's time is then
 * utime. A frame that replaces the anchor's moves the anchor with it. */
static void latest_hold(rp_lsrc_t *s, uint8_t k, int64_t utime, int64_t now)
{
    rp_lsrc_pending_t *p = &s->pend[0];
    if (!p->used) {
        p->used = 1;
        p->utime = utime;
        p->first_rx_us = now;
        memset(p->have, 0, sizeof p->have);
        rp_frameset_reset(&p->fs, utime);
    }
    if (p->have[k]) {
        s->n_skipped++;
        p->have[k] = 0;
        if (s->trigger && s->anchor_cam == k) {
            s->anchor = utime; /* after the replaced frame's time, so after the last set's */
        }
    }
    if (!set_cam_live(s, now) || k == s->set_cam) {
        latest_anchor(s, k, utime);
    }
}

/* Camera c's front end was heard now, message m (a new instance: restarted). */
static void heard(rp_lsrc_t *s, rp_lsrc_cam_t *c, const rigpose_features_t *m, int64_t now)
{
    if (c->seen && memcmp(c->instance, m->instance, sizeof c->instance) != 0) {
        s->n_restarts++;
    }
    c->seen = 1;
    c->last_rx_us = now;
    memcpy(c->instance, m->instance, sizeof c->instance);
}

static void on_features(const lcm_recv_buf_t *rb, const char *channel, void *user)
{
    (void)channel;
    const rp_lsrc_hook_t *h = (const rp_lsrc_hook_t *)user;
    rp_lsrc_t *s = h->src;
    const uint8_t k = h->cam;
    rigpose_features_t *m = &s->msg;
    const char *why = NULL;
    s->n_msgs++;
    if (rigpose_features_t_decode(rb->data, 0, (int)rb->data_size, m) < 0) {
        s->n_bad++;
        return;
    }
    if (rp_feats_check(m, k, s->n_cams, &why) != 0) {
        s->n_bad++;
        return;
    }
    const int64_t now = rp_hal_now_us();
    rp_lsrc_cam_t *c = &s->cam[k];
    rp_lsrc_pending_t *hold = &s->pend[0]; /* sets: latest's one set being filled */
    if (s->latest && (m->state & RP_HAL_CAM_MISSING)) {
        /* latest: a front end's word that this camera had no image (a multi-camera front end
         * stamps it with its set's time): heard, but neither held, nor a set's time, nor a
         * bound on the camera's next frames */
        heard(s, c, m, now);
        return;
    }
    const int late =
        s->latest ? (c->out_any && m->utime <= c->out_utime) ||
                        (hold->used && hold->have[k] && m->utime <= hold->cam_utime[k])
                  : s->any_out && !later_than(m->utime, s->last_out_utime, s->tol_us);
    if (late) {
        /* Late (latest: not after this camera's frame delivered or held). Not counted as heard
         * either: a restarted front end catching up on the frames of the last timeout_ms would
         * otherwise hold every set back until it is current. */
        s->n_late++;
        return;
    }
    if (!c->seen || m->utime > c->last_utime ||
        memcmp(c->instance, m->instance, sizeof c->instance) != 0) {
        c->last_utime = m->utime;
    }
    heard(s, c, m, now);
    rp_lsrc_pending_t *p = NULL, *free_slot = NULL;
    if (s->latest) {
        latest_hold(s, k, m->utime, now);
        p = hold;
    }
    for (int i = 0; i < RP_LSRC_PENDING && p == NULL; ++i) {
        rp_lsrc_pending_t *q = &s->pend[i];
        if (q->used && dist_us(q->utime, m->utime) <= (uint64_t)s->tol_us) {
            p = q;
            break;
        }
        if (!q->used && free_slot == NULL) {
            free_slot = q;
        }
    }
    if (p == NULL) {
        if (free_slot == NULL) {
            s->n_full++;
            return;
        }
        p = free_slot;
        p->used = 1;
        p->utime = m->utime;
        p->first_rx_us = now;
        memset(p->have, 0, sizeof p->have);
        rp_frameset_reset(&p->fs, m->utime);
    }
    if (p->have[k]) {
        s->n_bad++; /* a second message of one camera for one set */
        return;
    }
    p->have[k] = 1;
    p->cam_utime[k] = m->utime;
    p->state[k] = (uint8_t)m->state;
    p->seq[k] = m->seq;
    p->drops[k] = m->drops;
    p->fs.n[k] = (uint16_t)m->n;
    for (int16_t i = 0; i < m->n; ++i) {
        rp_feat_t *f = &p->fs.f[k][i];
        f->id = map_id(s, (uint32_t)m->id[i], m->instance);
        f->uv[0] = (rp_real)m->u[i];
        f->uv[1] = (rp_real)m->v[i];
    }
}

/* ---- assembling ------------------------------------------------------------------------------ */

/* Camera k of the layout sends nothing now: silent for timeout_ms; never heard, once a set has
 * waited timeout_ms for it (so that front ends started together, or sets due later than
 * timeout_ms after the start, all make the first set), with sets: latest timeout_ms after
 * the source opened. */
static int absent(const rp_lsrc_t *s, uint8_t k, int64_t now)
{
    const rp_lsrc_cam_t *c = &s->cam[k];
    if (c->seen) {
        return now - c->last_rx_us > s->timeout_us;
    }
    /* latest: sets never wait, so never heard for timeout_ms since the source opened */
    return s->latest ? now - s->open_us > s->timeout_us : s->n_waited > 0;
}

static rp_lsrc_pending_t *oldest(rp_lsrc_t *s, int *n_used)
{
    rp_lsrc_pending_t *o = NULL;
    *n_used = 0;
    for (int i = 0; i < RP_LSRC_PENDING; ++i) {
        rp_lsrc_pending_t *q = &s->pend[i];
        if (q->used) {
            (*n_used)++;
            if (o == NULL || q->utime < o->utime) {
                o = q;
            }
        }
    }
    return o;
}

/* The oldest pending set if it may go out now, else NULL. */
static rp_lsrc_pending_t *ready(rp_lsrc_t *s, int64_t now)
{
    if (s->latest) {
        /* latest_hold; and when the set camera has turned absent since the frames now held
         * came, the newest of them makes the set, as the next message would */
        const rp_lsrc_pending_t *h = &s->pend[0];
        if (!s->trigger && h->used && !set_cam_live(s, now)) {
            for (uint8_t k = 0; k < s->n_cams; ++k) {
                if (h->have[k]) {
                    latest_anchor(s, k, h->cam_utime[k]); /* the newest after the last set */
                }
            }
        }
        return s->trigger ? &s->pend[0] : NULL;
    }
    int n_used = 0;
    rp_lsrc_pending_t *p = oldest(s, &n_used);
    if (p == NULL) {
        return NULL;
    }
    if (n_used == RP_LSRC_PENDING) {
        return p;
    }
    if (now - p->first_rx_us >= s->timeout_us) {
        s->n_waited++;
        return p;
    }
    for (uint8_t k = 0; k < s->n_cams; ++k) {
        const rp_lsrc_cam_t *c = &s->cam[k];
        if (s->want[k] && !p->have[k] && !absent(s, k, now) &&
            !(c->seen && later_than(c->last_utime, p->utime, s->tol_us))) {
            return NULL;
        }
    }
    return p;
}

/* When something may change without a message: the oldest set's wait ends, or a camera turns
 * absent. */
static int64_t next_event(const rp_lsrc_t *s, int64_t deadline)
{
    int64_t t = deadline;
    for (int i = 0; i < RP_LSRC_PENDING && !s->latest; ++i) { /* latest: sets do not wait */
        if (s->pend[i].used && s->pend[i].first_rx_us + s->timeout_us < t) {
            t = s->pend[i].first_rx_us + s->timeout_us;
        }
    }
    for (uint8_t k = 0; k < s->n_cams; ++k) {
        const int64_t base = s->cam[k].last_rx_us;
        if (s->want[k] && s->cam[k].seen && base + s->timeout_us + 1 < t) {
            t = base + s->timeout_us + 1;
        }
    }
    return t;
}

/* Each camera's state in a set (or, for a timeout, without one: p NULL). */
static void fill_cams(rp_lsrc_t *s, const rp_lsrc_pending_t *p, rp_hal_set_t *set, int64_t now)
{
    size_t len = 0;
    for (uint8_t k = 0; k < s->n_cams; ++k) {
        rp_hal_frame_t *fr = &set->cam[k];
        if (p != NULL && p->have[k]) {
            fr->flags = p->state[k] & (RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE | RP_HAL_CAM_DROPPED);
            fr->utime = p->cam_utime[k];
            fr->seq = (uint32_t)p->seq[k];
            fr->drops = (uint32_t)(p->drops[k] > 0 ? p->drops[k] : 0);
            continue;
        }
        const int gone = s->want[k] && absent(s, k, now);
        fr->flags = RP_HAL_CAM_MISSING | (gone ? RP_HAL_CAM_GONE : 0u);
        /* latest: a camera at its own rate without a new frame is its normal, not news */
        if (s->want[k] && p != NULL && (!s->latest || gone || !s->cam[k].seen) &&
            len + 1 < sizeof s->err) {
            const int n = snprintf(s->err + len, sizeof s->err - len,
                                   "%scamera %u: no features in this set (%s)", len ? "; " : "",
                                   (unsigned)k,
                                   !s->cam[k].seen ? "its front end not heard yet"
                                   : gone ? "its front end silent for longer than timeout_ms"
                                          : "its message did not come in time");
            len = n < 0 ? len : len + (size_t)n;
        }
    }
}

/* Camera k delivered an image into pending set p. */
static int has_image(const rp_lsrc_pending_t *p, uint8_t k)
{
    return p->have[k] && !(p->state[k] & RP_HAL_CAM_MISSING);
}

/* The set's time of p (rp_lcmsrc.h, Times), and each camera's time and flags into its frame set. */
static int64_t set_times(rp_lsrc_t *s, rp_lsrc_pending_t *p)
{
    int64_t t = p->utime;
    for (uint8_t k = 0; k < s->n_cams && !s->latest; ++k) {
        if (has_image(p, k)) {
            t = p->cam_utime[k];
            break;
        }
    }
    if (s->latest) {
        t = s->anchor; /* the frame that made the set (latest_hold) */
    } else if (s->any_out && t <= s->last_set_utime) {
        t = p->utime; /* after the last set's time: its grouping time is past sync_tol_us */
    }
    p->fs.utime = t;
    for (uint8_t k = 0; k < s->n_cams; ++k) {
        p->fs.cam_dt_us[k] = 0;
        /* matched: cannot fail, within 2 sync_tol_us of t, at most 2 s (rp_lsrc_open);
         * latest: a frame more than 35 min from the set's time (a broken stamp) is left out */
        if (p->have[k] && rp_pipe_cam_dt(p->cam_utime[k], t, &p->fs.cam_dt_us[k]) != RP_OK) {
            p->have[k] = 0;
            p->fs.n[k] = 0;
            s->n_bad++;
        }
        if (s->want[k] && !has_image(p, k)) {
            p->fs.cam_flags[k] |= RP_FS_NO_IMAGE;
        }
    }
    return t;
}

rp_hal_status_t rp_lsrc_grab(rp_lsrc_t *s, rp_hal_set_t *set)
{
    if (s == NULL || set == NULL || s->lcm == NULL) {
        return RP_HAL_E_ARG;
    }
    s->err[0] = '\0';
    memset(set, 0, sizeof *set);
    set->n_cams = s->n_cams;
    set->payload = RP_HAL_PAYLOAD_FEATS;
    const int64_t deadline = rp_hal_now_us() + s->timeout_us;
    for (;;) {
        const int64_t now = rp_hal_now_us();
        rp_lsrc_pending_t *p = ready(s, now);
        if (p != NULL && s->latest) {
            /* every message already queued first: a set camera's newer frame replaces the
             * one that made the set (a slow estimator skips frames, not falls behind) */
            int got = 1;
            for (int i = 0; i < RP_LSRC_DRAIN_MAX && got > 0; ++i) {
                got = lcm_handle_timeout(s->lcm, 0);
            }
            if (got < 0) {
                /* ignored: fits */
                (void)snprintf(s->err, sizeof s->err, "lcm: lcm_handle failed");
                return RP_HAL_E_IO;
            }
        }
        if (p != NULL) {
            const int64_t t = set_times(s, p);
            s->out = p->fs;
            set->feats = &s->out;
            set->utime = t;
            set->seq = s->set_seq++;
            fill_cams(s, p, set, now);
            s->any_out = 1;
            s->last_out_utime = p->utime;
            s->last_set_utime = t;
            for (uint8_t k = 0; k < s->n_cams; ++k) {
                if (p->have[k]) {
                    s->cam[k].out_any = 1;
                    s->cam[k].out_utime = p->cam_utime[k];
                }
            }
            p->used = 0;
            s->trigger = 0;
            return RP_HAL_OK;
        }
        if (now >= deadline) {
            set->feats = NULL;
            fill_cams(s, NULL, set, now);
            /* ignored: a message cut at RP_LSRC_ERR_MAX is still a message */
            (void)snprintf(s->err, sizeof s->err,
                           "lcm: no frame set from the front ends within %lld ms",
                           (long long)(s->timeout_us / 1000));
            return RP_HAL_E_TIMEOUT;
        }
        int64_t wait_us = next_event(s, deadline) - now;
        if (wait_us < 1000) {
            wait_us = 1000;
        }
        if (lcm_handle_timeout(s->lcm, (int)(wait_us / 1000)) < 0) {
            /* ignored: fits */
            (void)snprintf(s->err, sizeof s->err, "lcm: lcm_handle failed");
            return RP_HAL_E_IO;
        }
    }
}

rp_hal_status_t rp_lsrc_open(rp_lsrc_t *s, lcm_t *lcm, const rp_config_t *cfg)
{
    if (s == NULL) {
        return RP_HAL_E_ARG;
    }
    memset(s, 0, sizeof *s);
    if (lcm == NULL || cfg == NULL) {
        /* ignored: fits */
        (void)snprintf(s->err, sizeof s->err, "lcm: no LCM or configuration");
        return RP_HAL_E_ARG;
    }
    s->n_cams = cfg->rig.n_cams;
    if (rp_feats_layout_cams(&cfg->pipe, s->n_cams, s->want) == 0) {
        /* ignored: fits */
        (void)snprintf(s->err, sizeof s->err, "lcm: the layout uses no camera");
        return RP_HAL_E_ARG;
    }
    if (cfg->hal.sync_tol_us < 0 || cfg->hal.sync_tol_us > RP_LSRC_TOL_MAX_US) {
        /* ignored: fits */
        (void)snprintf(s->err, sizeof s->err, "lcm: sync_tol_us %lld outside 0..%d",
                       (long long)cfg->hal.sync_tol_us, RP_LSRC_TOL_MAX_US);
        return RP_HAL_E_ARG;
    }
    s->latest = cfg->hal.sets_latest;
    s->set_cam = cfg->hal.set_cam;
    s->open_us = rp_hal_now_us();
    if (s->latest && (s->set_cam < -1 || s->set_cam >= (int)s->n_cams)) {
        /* ignored: fits */
        (void)snprintf(s->err, sizeof s->err, "lcm: set_camera %d is not a camera of the rig",
                       (int)s->set_cam);
        return RP_HAL_E_ARG;
    }
    for (uint8_t k = 0; s->latest && s->set_cam >= 0 && !s->want[s->set_cam]; ++k) {
        if (s->want[k]) {
            s->set_cam = (int8_t)k; /* the source hears only the layout's cameras: its first */
        }
    }
    s->lcm = lcm;
    s->tol_us = cfg->hal.sync_tol_us;
    s->timeout_us = (int64_t)cfg->hal.timeout_ms * 1000;
    for (uint8_t k = 0; k < s->n_cams; ++k) {
        if (!s->want[k]) {
            continue;
        }
        char ch[RP_CFG_CHANNEL_MAX + 8];
        if (rp_feats_channel(cfg->features_channel, k, ch, sizeof ch) != 0) {
            /* ignored: fits */
            (void)snprintf(s->err, sizeof s->err, "lcm: lcm.features_channel too long");
            return RP_HAL_E_ARG;
        }
        s->hook[k].src = s;
        s->hook[k].cam = k;
        s->sub[k] = lcm_subscribe(lcm, ch, on_features, &s->hook[k]);
        if (s->sub[k] == NULL) {
            /* ignored: a message cut at RP_LSRC_ERR_MAX is still a message */
            (void)snprintf(s->err, sizeof s->err, "lcm: cannot subscribe to %s", ch);
            rp_lsrc_close(s);
            return RP_HAL_E_OPEN;
        }
        /* ignored: the default capacity, 30 messages (1 s at 30 Hz), then holds; 120 leaves
         * room for a stalled estimator */
        (void)lcm_subscription_set_queue_capacity(s->sub[k], 120);
    }
    return RP_HAL_OK;
}

const char *rp_lsrc_errmsg(const rp_lsrc_t *s) { return s != NULL ? s->err : ""; }

void rp_lsrc_close(rp_lsrc_t *s)
{
    if (s == NULL) {
        return;
    }
    for (uint8_t k = 0; k < RP_MAX_CAMS; ++k) {
        if (s->sub[k] != NULL && s->hook[k].src != NULL) {
            lcm_t *lcm = s->lcm;
            if (lcm != NULL) {
                /* ignored: closing anyway */
                (void)lcm_unsubscribe(lcm, s->sub[k]);
            }
            s->sub[k] = NULL;
        }
    }
    s->lcm = NULL;
}
