/*
 * rp_args.h - the daemon's command line: parsing it (rp_args_parse) and laying its overrides
 * over the loaded configuration file (rp_args_apply). No heap; the strings point into argv.
 * The options are listed by rp_args_usage and in daemon/README.md.
 */
#ifndef RP_ARGS_H
#define RP_ARGS_H

#include <stdint.h>
#include <stdio.h>

#include "rigpose/rp_config.h"

typedef enum {
    RP_ARGS_OK = 0,  /* parsed: run */
    RP_ARGS_HELP,    /* --help / -h: print rp_args_usage on stdout and exit 0 */
    RP_ARGS_E_USAGE  /* a bad command line: the message is on the error stream already */
} rp_args_status_t;

typedef struct {
    const char *config;         /* --config FILE (required) */
    uint32_t frames;            /* --frames N; 0: until the source ends or a signal */
    const char *lcm_url;        /* overrides of the file's lcm.*, NULL: the file's */
    const char *pose_channel;
    const char *status_channel;
    const char *image_channel;
    int fast;                   /* --fast: sim / replay as fast as possible (source.realtime off) */
    int drop_cam;               /* --sim-drop CAM:FRAME, -2: not given */
    uint32_t drop_from;
    int quiet;                  /* --quiet: no pose lines, only the summary */
    uint32_t print_every;       /* --print-every K, >= 1 */
    const char *stats_json;     /* --stats-json FILE, NULL: none */
    int threads;                /* --threads N (cfg->threads), -1: not given */
} rp_args_t;

/* The usage text (every option and the exit codes) on f. */
void rp_args_usage(FILE *f);

/* Parse argv[1..argc-1] into a. Messages about a bad command line go to err (one line, naming
 * the option and the value). RP_ARGS_HELP for --help; RP_ARGS_E_USAGE for an unknown option, a
 * missing or malformed value, or no --config. */
rp_args_status_t rp_args_parse(int argc, char **argv, rp_args_t *a, FILE *err);

/* Lay a's overrides over cfg: LCM URL and channels, --fast (cfg->hal.realtime = 0), --threads,
 * --sim-drop (cfg->sim), and the sim source's run length when the file leaves it open
 * (--frames, else 300). RP_ARGS_E_USAGE (message on err) for a string too long for its field or
 * a --sim-drop camera the rig does not have; cfg may then be partly changed. */
rp_args_status_t rp_args_apply(const rp_args_t *a, rp_config_t *cfg, FILE *err);

#endif /* RP_ARGS_H */
