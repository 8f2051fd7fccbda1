/*
 * rp_est.c - the configured estimator: configuration -> rp_pipe (rp_est.h). The pipeline's
 * configuration is the parser's (rp_config.h: the core's defaults with the file's keys) as it is.
 */
#include "rp_est.h"

#include <string.h>

rp_status_t rp_est_init(rp_est_t *est, const rp_config_t *cfg)
{
    if (est == NULL || cfg == NULL) {
        return RP_E_ARG;
    }
    return rp_pipe_init(&est->pipe, &cfg->rig, &cfg->pipe);
}

rp_status_t rp_est_step(rp_est_t *est, const rp_frameset_t *fs, rp_estimate_t *out)
{
    if (est == NULL) {
        if (out != NULL) {
            memset(out, 0, sizeof *out);
            out->flags = RP_EST_LOST;
        }
        return RP_E_ARG;
    }
    return rp_pipe_step_feats(&est->pipe, fs, out);
}

rp_status_t rp_est_step_images(rp_est_t *est, const rp_image_t *const images[], uint8_t n,
                               int64_t utime, rp_estimate_t *out, const rp_frameset_t **fs_out)
{
    if (fs_out != NULL) {
        *fs_out = NULL;
    }
    if (est == NULL) {
        return RP_E_ARG;
    }
    const rp_status_t st = rp_pipe_step(&est->pipe, images, n, utime, out);
    if (fs_out != NULL && rp_pipe_frameset(&est->pipe, fs_out) != RP_OK) {
        *fs_out = NULL;
    }
    return st;
}
