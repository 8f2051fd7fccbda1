/*
 * cfg_check - loads configuration files with the daemon's parser (platform/src/rp_config.c), the
 * round trip of rigpose-calib's output. Prints "FILE: ok" or the parser's error; exit 0 when
 * every file loads.
 */
#include <stdio.h>

#include "rigpose/rp_config.h"

int main(int argc, char **argv)
{
    static rp_config_t cfg;
    char err[RP_CFG_ERR_MAX];
    int bad = 0;
    for (int i = 1; i < argc; ++i) {
        const rp_cfg_status_t s = rp_config_load(argv[i], &cfg, err, sizeof err);
        if (s == RP_CFG_OK) {
            printf("%s: ok (%u cameras, method %s)\n", argv[i], (unsigned)cfg.rig.n_cams,
                   rp_pipe_layout_name(cfg.pipe.layout));
        } else {
            printf("%s\n", err);
            bad = 1;
        }
    }
    return argc > 1 ? bad : 2;
}
