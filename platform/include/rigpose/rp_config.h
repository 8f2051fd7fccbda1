/*
 * rp_config.h - the rigpose configuration file (YAML, schema in config/README.md), read with
 * Debian's libyaml (document API) into the structures the daemon runs on: the rig, the
 * pipeline's configuration (layout, estimator, tracker), the HAL source's configuration and the
 * LCM URL and channels.
 *
 * The estimator and tracker settings have no defaults here: the parser starts from the core's
 * rp_pipe_default_cfg for the file's layout and overrides only the keys the file gives, so a
 * file that gives none runs exactly what the benchmarks measure (daemon/tests/test_config.c
 * checks it for every layout, and checks config/README.md's table of defaults against it).
 *
 * Not core code (it uses stdio and libyaml), but it keeps no heap after it returns: everything
 * lands in the caller's rp_config_t.
 *
 * Every error is one line "FILE:LINE: KEY: what is wrong" (KEY is the path from the top, e.g.
 * cameras[2].intrinsics); the first error found is reported and the load fails as a whole.
 * Control characters and invalid UTF-8 echoed from the file are written \xNN in the message.
 *
 * Hostile input: a file larger than RP_CFG_MAX_BYTES, nested deeper than RP_CFG_MAX_DEPTH
 * (anywhere, meta: included: libyaml's loader takes minutes on deep nesting, so a first pass
 * over libyaml's events stops at the limit), with more than RP_CFG_MAX_NODES nodes (1 MiB of
 * "1," under meta: took 83 MB to load) or holding a second YAML document is refused with
 * RP_CFG_E_SYNTAX before the document is built. Intrinsics outside a sane range and distortion
 * that folds or grossly stretches the image (checked over rays from the principal point to the
 * image border) are refused (RP_CFG_E_RANGE); config/README.md gives the rules.
 */
#ifndef RP_CONFIG_H
#define RP_CONFIG_H

#include <stddef.h>
#include <stdint.h>

#include "rigpose/rp_hal.h"
#include "rigpose/rp_pipe.h"
#include "rigpose/rp_pool.h"
#include "rigpose/rp_rig.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    RP_CFG_OK = 0,
    RP_CFG_E_ARG,     /* null pointer / no buffer */
    RP_CFG_E_OPEN,    /* the file could not be read */
    RP_CFG_E_SYNTAX,  /* not YAML, or not a mapping at the top */
    RP_CFG_E_MISSING, /* a required key is absent */
    RP_CFG_E_TYPE,    /* a value of the wrong type / shape (string for a number, 3 numbers for 4) */
    RP_CFG_E_RANGE,   /* a value outside its allowed range, or inconsistent with others */
    RP_CFG_E_UNKNOWN  /* a key the schema does not know */
} rp_cfg_status_t;

const char *rp_cfg_status_str(rp_cfg_status_t s);

#define RP_CFG_NAME_MAX 32     /* camera names, with the terminating NUL */
#define RP_CFG_CHANNEL_MAX 64  /* LCM channel names, with the NUL */
#define RP_CFG_URL_MAX 256     /* LCM URL, with the NUL */
#define RP_CFG_ERR_MAX 512     /* a useful size for the error buffer */
#define RP_CFG_MAX_BYTES (1024 * 1024) /* largest file read */
#define RP_CFG_MAX_DEPTH 32    /* deepest nesting of mappings and sequences */
#define RP_CFG_MAX_NODES 100000 /* scalars, sequences, mappings and aliases in the file */

/* The feature-level simulation behind the sim source (source.sim in the file). */
typedef struct {
    uint32_t seed;      /* run seed */
    uint32_t frames;    /* trajectory length, frame sets; 0: as the daemon asks */
    double noise_px;    /* Gaussian pixel noise, px */
    int16_t drop_cam;   /* camera that vanishes, -1: none */
    uint32_t drop_from; /* from this frame set on */
    int8_t motion;      /* rp_hal_sim_opts_t.motion: 0 paper, 1 turn, 2 pitch, 3 smooth */
} rp_cfg_sim_t;

typedef struct {
    char path[RP_HAL_PATH_MAX];            /* the file read */
    rp_rig_t rig;
    char cam_name[RP_MAX_CAMS][RP_CFG_NAME_MAX];
    rp_hal_cfg_t hal;                      /* kind, cameras, timeouts, sim seed/frames */
    rp_cfg_sim_t sim;
    rp_pipe_cfg_t pipe;                    /* the estimator: rp_pipe_default_cfg of the layout
                                            * estimator.method names, with the cameras and the
                                            * keys the file gives over it (estimator, tracker) */
    char lcm_url[RP_CFG_URL_MAX];
    char pose_channel[RP_CFG_CHANNEL_MAX];
    char status_channel[RP_CFG_CHANNEL_MAX];
    char image_channel[RP_CFG_CHANNEL_MAX]; /* "" = images not published */
    uint32_t status_every;                  /* frame sets between status messages, >= 1 */
    char features_channel[RP_CFG_CHANNEL_MAX]; /* lcm.features_channel: rigpose-frontend
                                             * publishes camera k's features on this + "k"
                                             * (the daemon with source.kind lcm listens);
                                             * at most RP_CFG_CHANNEL_MAX - 2 characters */
    char instance[32];                      /* lcm.instance: who publishes (pose_t.instance);
                                             * "" = the daemon's default, HOST:PID */
    uint8_t threads;                        /* threads of the image front end in all, the
                                             * daemon's included (1..RP_POOL_MAX_THREADS);
                                             * 0 = the daemon's default: the online cores, at
                                             * most one per camera (rp_pool.h) */
} rp_config_t;

/* Read and check the file at path. On failure cfg is unspecified and err (err_len bytes, may be
 * NULL) holds "path:line: key: message". Returns RP_CFG_OK or the kind of the first error. */
rp_cfg_status_t rp_config_load(const char *path, rp_config_t *cfg, char *err, size_t err_len);

/* The same from text in memory; `name` stands for the file name in messages and resolves
 * relative paths (replay_index) against its folder. */
rp_cfg_status_t rp_config_parse(const char *text, size_t len, const char *name, rp_config_t *cfg,
                                char *err, size_t err_len);

#ifdef __cplusplus
}
#endif

#endif /* RP_CONFIG_H */
