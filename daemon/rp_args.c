/*
 * rp_args.c - the daemon's command line (rp_args.h).
 */
#include "rp_args.h"

#include "rigpose/rp_esc.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

void rp_args_usage(FILE *f)
{
    fprintf(f,
            "usage: rigpose --config FILE [--frames N] [options]\n"
            "  --config FILE         configuration (schema: config/README.md)\n"
            "  --frames N            stop after N frame sets (0: run until the source ends or\n"
            "                        SIGINT/SIGTERM; the sim source then simulates 300)\n"
            "  --lcm-url URL         override lcm.url (udpm://..., file://...?mode=w, memq://)\n"
            "  --pose-channel NAME   override lcm.pose_channel\n"
            "  --status-channel NAME override lcm.status_channel\n"
            "  --fast                sim / replay: as fast as possible (source.realtime: false)\n"
            "  --sim-drop CAM:FRAME  sim: camera CAM vanishes from frame set FRAME on\n"
            "  --print-every K       print every K-th pose (default 1)\n"
            "  --quiet               print no poses: only events (failures, changes) and the summary\n"
            "  --image-channel NAME  also publish every camera image (rigpose.image_t) there\n"
            "  --stats-json FILE     write daemon_latency_ms_p50/_p99 and daemon_fps to FILE\n"
            "  --threads N           override threads (1..16; 0: one per online core, at most\n"
            "                        one per camera); the poses are the same for every N\n"
            "exit codes: 0 done, 1 usage, 2 bad configuration, 3 LCM, 4 source open/start,\n"
            "            5 estimator setup, 6 source failed while running, 7 --stats-json not\n"
            "            written\n");
}

/* A command-line word as it may be echoed: control characters and invalid UTF-8 as \xNN
 * (rp_esc.h). Two buffers: a message may quote an option and its value. */
static const char *esc(const char *s)
{
    static char buf[2][1024];
    static unsigned k;
    char *b = buf[k++ % 2u];
    rp_esc_text(b, sizeof buf[0], s);
    return b;
}

/* A decimal count 0..2^32-1, nothing else (no sign, no trailing characters). */
static int parse_u32(const char *s, uint32_t *out)
{
    char *end = NULL;
    errno = 0;
    const unsigned long long v = strtoull(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || s[0] == '-' || v > 0xFFFFFFFFull) {
        return -1;
    }
    *out = (uint32_t)v;
    return 0;
}

rp_args_status_t rp_args_parse(int argc, char **argv, rp_args_t *o, FILE *err)
{
    if (o == NULL || err == NULL || (argc > 0 && argv == NULL)) {
        return RP_ARGS_E_USAGE;
    }
    memset(o, 0, sizeof *o);
    o->drop_cam = -2;
    o->print_every = 1;
    o->threads = -1;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            return RP_ARGS_HELP;
        } else if (strcmp(a, "--fast") == 0) {
            o->fast = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            o->quiet = 1;
        } else if (v == NULL) {
            fprintf(err, "rigpose: %s: unknown option or missing value\n", esc(a));
            return RP_ARGS_E_USAGE;
        } else if (strcmp(a, "--config") == 0) {
            o->config = v;
            ++i;
        } else if (strcmp(a, "--frames") == 0) {
            if (parse_u32(v, &o->frames) != 0) {
                fprintf(err, "rigpose: --frames: '%s' is not a count\n", esc(v));
                return RP_ARGS_E_USAGE;
            }
            ++i;
        } else if (strcmp(a, "--lcm-url") == 0) {
            o->lcm_url = v;
            ++i;
        } else if (strcmp(a, "--pose-channel") == 0) {
            o->pose_channel = v;
            ++i;
        } else if (strcmp(a, "--status-channel") == 0) {
            o->status_channel = v;
            ++i;
        } else if (strcmp(a, "--image-channel") == 0) {
            o->image_channel = v;
            ++i;
        } else if (strcmp(a, "--print-every") == 0) {
            if (parse_u32(v, &o->print_every) != 0 || o->print_every == 0) {
                fprintf(err, "rigpose: --print-every: '%s' is not a positive count\n", esc(v));
                return RP_ARGS_E_USAGE;
            }
            ++i;
        } else if (strcmp(a, "--threads") == 0) {
            uint32_t n = 0;
            if (parse_u32(v, &n) != 0 || n > RP_POOL_MAX_THREADS) {
                fprintf(err, "rigpose: --threads: '%s' is not a count 0..%d\n", esc(v),
                        RP_POOL_MAX_THREADS);
                return RP_ARGS_E_USAGE;
            }
            o->threads = (int)n;
            ++i;
        } else if (strcmp(a, "--stats-json") == 0) {
            o->stats_json = v;
            ++i;
        } else if (strcmp(a, "--sim-drop") == 0) {
            unsigned cam = 0, from = 0;
            char tail = 0;
            if (sscanf(v, "%u:%u%c", &cam, &from, &tail) != 2 || cam >= RP_MAX_CAMS) {
                fprintf(err, "rigpose: --sim-drop: '%s' is not CAM:FRAME (CAM < %d)\n", esc(v),
                        RP_MAX_CAMS);
                return RP_ARGS_E_USAGE;
            }
            o->drop_cam = (int)cam;
            o->drop_from = from;
            ++i;
        } else {
            fprintf(err, "rigpose: %s: unknown option (--help)\n", esc(a));
            return RP_ARGS_E_USAGE;
        }
    }
    if (o->config == NULL) {
        fprintf(err, "rigpose: --config FILE is required (--help)\n");
        return RP_ARGS_E_USAGE;
    }
    return RP_ARGS_OK;
}

rp_args_status_t rp_args_apply(const rp_args_t *o, rp_config_t *cfg, FILE *err)
{
    if (o == NULL || cfg == NULL || err == NULL) {
        return RP_ARGS_E_USAGE;
    }
    struct { const char *v; char *dst; size_t cap; const char *name; } s[] = {
        {o->lcm_url, cfg->lcm_url, sizeof cfg->lcm_url, "--lcm-url"},
        {o->pose_channel, cfg->pose_channel, sizeof cfg->pose_channel, "--pose-channel"},
        {o->status_channel, cfg->status_channel, sizeof cfg->status_channel, "--status-channel"},
        {o->image_channel, cfg->image_channel, sizeof cfg->image_channel, "--image-channel"},
    };
    for (size_t i = 0; i < sizeof s / sizeof s[0]; ++i) {
        if (s[i].v == NULL) {
            continue;
        }
        if (s[i].v[0] == '\0' || strlen(s[i].v) >= s[i].cap) {
            fprintf(err, "rigpose: %s: 1..%zu characters\n", s[i].name, s[i].cap - 1);
            return RP_ARGS_E_USAGE;
        }
        snprintf(s[i].dst, s[i].cap, "%s", s[i].v);
    }
    if (o->fast) {
        cfg->hal.realtime = 0;
    }
    if (o->threads >= 0) {
        cfg->threads = (uint8_t)o->threads;
    }
    if (o->drop_cam >= 0) {
        if (o->drop_cam >= cfg->rig.n_cams) {
            fprintf(err, "rigpose: --sim-drop: the rig has %u cameras\n", cfg->rig.n_cams);
            return RP_ARGS_E_USAGE;
        }
        cfg->sim.drop_cam = (int16_t)o->drop_cam;
        cfg->sim.drop_from = o->drop_from;
    }
    if (cfg->hal.kind == RP_HAL_SRC_SIM && cfg->hal.sim_frames == 0) {
        cfg->hal.sim_frames = o->frames > 0 ? o->frames : 300u;
    }
    return RP_ARGS_OK;
}
