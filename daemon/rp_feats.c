/*
 * rp_feats.c - the front ends' and the daemon's shared conventions (rp_feats.h).
 */
#include "rp_feats.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

int rp_feats_channel(const char *prefix, uint8_t cam, char *out, size_t cap)
{
    if (prefix == NULL || out == NULL || cap == 0) {
        return -1;
    }
    const int n = snprintf(out, cap, "%s%u", prefix, (unsigned)cam);
    return (n < 0 || (size_t)n >= cap) ? -1 : 0;
}

static void mark(uint8_t want[RP_MAX_CAMS], uint8_t n_cams, uint8_t cam)
{
    if (cam < n_cams && cam < RP_MAX_CAMS) {
        want[cam] = 1;
    }
}

uint8_t rp_feats_layout_cams(const rp_pipe_cfg_t *cfg, uint8_t n_cams, uint8_t want[RP_MAX_CAMS])
{
    memset(want, 0, RP_MAX_CAMS);
    if (cfg == NULL) {
        return 0;
    }
    switch (cfg->layout) {
    case RP_PIPE_STEREO4:
    case RP_PIPE_STEREO2:
        for (uint8_t k = 0; k < cfg->stereo.n_pairs && k < RP_MAX_PAIRS; ++k) {
            mark(want, n_cams, cfg->stereo.pair_a[k]);
            mark(want, n_cams, cfg->stereo.pair_b[k]);
        }
        break;
    case RP_PIPE_GC:
        for (uint8_t i = 0; i < cfg->gc.n_cams && i < RP_MAX_CAMS; ++i) {
            mark(want, n_cams, cfg->gc.cams[i]);
        }
        break;
    case RP_PIPE_RC:
        for (uint8_t i = 0; i < cfg->rc_n && i < RP_RC_MAX_CAMS; ++i) {
            mark(want, n_cams, cfg->rc_cams[i]);
        }
        break;
    case RP_PIPE_CAM1:
    case RP_PIPE_CAM2:
    case RP_PIPE_CAM3:
    case RP_PIPE_CAM4:
        mark(want, n_cams, cfg->mono.cam);
        break;
    case RP_PIPE_LAYOUT_COUNT_:
        break;
    }
    uint8_t n = 0;
    for (uint8_t k = 0; k < RP_MAX_CAMS; ++k) {
        n = (uint8_t)(n + want[k]);
    }
    return n;
}

int rp_feats_partner(const rp_pipe_cfg_t *cfg, uint8_t cam)
{
    if (cfg == NULL || (cfg->layout != RP_PIPE_STEREO4 && cfg->layout != RP_PIPE_STEREO2)) {
        return -1;
    }
    for (uint8_t k = 0; k < cfg->stereo.n_pairs && k < RP_MAX_PAIRS; ++k) {
        if (cfg->stereo.pair_a[k] == cam) {
            return cfg->stereo.pair_b[k];
        }
        if (cfg->stereo.pair_b[k] == cam) {
            return cfg->stereo.pair_a[k];
        }
    }
    return -1;
}

int rp_feats_check(const rigpose_features_t *m, uint8_t cam, uint8_t n_cams, const char **why)
{
    const char *w = NULL;
    if (m == NULL) {
        w = "no message";
    } else if (m->cam < 0 || (uint8_t)m->cam != cam || cam >= n_cams) {
        w = "camera index not the channel's, or not of the rig";
    } else if (m->n < 0 || m->n > RP_MAX_FEATS_PER_CAM || m->n > 512) {
        w = "feature count out of 0..512 (and this build's RP_MAX_FEATS_PER_CAM)";
    } else {
        for (int16_t i = 0; i < m->n; ++i) {
            if (!isfinite(m->u[i]) || !isfinite(m->v[i])) {
                w = "a feature position is not finite";
                break;
            }
        }
    }
    if (why != NULL) {
        *why = w != NULL ? w : "";
    }
    return w != NULL ? -1 : 0;
}

void rp_feats_instance(const char *configured, int8_t out[32])
{
    char host[64] = "host";
    char name[33];
    if (configured != NULL && configured[0] != '\0') {
        snprintf(name, sizeof name, "%s", configured);
    } else {
        if (gethostname(host, sizeof host - 1) != 0) {
            snprintf(host, sizeof host, "host");
        }
        host[sizeof host - 1] = '\0';
        snprintf(name, sizeof name, "%.20s:%ld", host, (long)getpid());
    }
    memset(out, 0, 32);
    memcpy(out, name, strnlen(name, 31));
}

void rp_feats_stop_signals(void (*handler)(int))
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = handler;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
    sigaction(SIGPIPE, &sa, NULL);
}
