/*
 * frameset_driver.c - whole frame sets through the core's image pipeline (rp_pipe: a tracker
 * per camera, stereo matching for stereo layouts, the estimator) on bt_scene frames, for
 * callgrind: frame sets 0..warm-1 go through bt_warm(), the next `measure` through
 * bt_measured(), so that
 *   valgrind --tool=callgrind --toggle-collect=bt_measured frameset_driver ...
 * counts the instructions of steady-state frame sets only (divide by `measure`).
 *
 *   frameset_driver [--size 320|640] [--layout gc|stereo4] [--warm W] [--measure M] [--seed S]
 *                   [--win N] [--levels L] [--target N]
 * --win, --levels, --target override the trackers' defaults (21, 4, 150).
 * Prints the pose error of the last frame set (a sanity check that the pipeline tracked).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../common/rp_cfg_diff.h"
#include "bt_scene.h"
#include "rigpose/rp_pipe.h"

static rp_pipe_t pipe_state;

__attribute__((noinline)) rp_status_t bt_warm(const rp_image_t *const im[], int64_t utime,
                                              rp_estimate_t *est)
{
    return rp_pipe_step(&pipe_state, im, RP_MAX_CAMS, utime, est);
}

__attribute__((noinline)) rp_status_t bt_measured(const rp_image_t *const im[], int64_t utime,
                                                  rp_estimate_t *est)
{
    return rp_pipe_step(&pipe_state, im, RP_MAX_CAMS, utime, est);
}

int main(int argc, char **argv)
{
    int size = 320, warm = 5, measure = 10, win = 0, levels = 0, target = 0;
    uint64_t seed = 1;
    const char *layout = "gc";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--size") && i + 1 < argc) {
            size = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--layout") && i + 1 < argc) {
            layout = argv[++i];
        } else if (!strcmp(argv[i], "--warm") && i + 1 < argc) {
            warm = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--measure") && i + 1 < argc) {
            measure = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--win") && i + 1 < argc) {
            win = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--levels") && i + 1 < argc) {
            levels = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--target") && i + 1 < argc) {
            target = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--seed") && i + 1 < argc) {
            seed = strtoull(argv[++i], NULL, 10);
        } else {
            fprintf(stderr, "usage: %s [--size 320|640] [--layout gc|stereo4] [--warm W] "
                            "[--measure M] [--seed S] [--win N] [--levels L] [--target N]\n",
                    argv[0]);
            return 2;
        }
    }
    if ((size != 320 && size != 640) || warm < 1 || measure < 1) {
        fprintf(stderr, "need --size 320|640, --warm >= 1, --measure >= 1\n");
        return 2;
    }
    const int w = size, h = size * 3 / 4, n = warm + measure;
    rp_pipe_layout_t lay;
    rp_pipe_cfg_t cfg;
    bt_scene_t *sc = bt_scene_new(w, h, seed, n);
    uint8_t *img = malloc((size_t)n * RP_MAX_CAMS * w * h);
    if (sc == NULL || img == NULL || rp_pipe_layout_from_name(layout, &lay) != RP_OK ||
        rp_pipe_default_cfg(lay, &cfg) != RP_OK) {
        fprintf(stderr, "frameset_driver: setup failed (layout %s)\n", layout);
        return 1;
    }
    if (win > 0) {
        cfg.track.win = (uint8_t)win;
    }
    if (levels > 0) {
        cfg.track.levels = (uint8_t)levels;
    }
    if (target > 0) {
        cfg.track.target = (uint16_t)target;
        cfg.track.topup_below = (uint16_t)(target * 4 / 5);
    }
    static const char *const why[][2] = {{"track.", "--win / --levels / --target"},
                                         {NULL, NULL}};
    (void)rp_cfg_diff_print(stderr, "frameset_driver", &cfg, why);
    if (rp_pipe_init(&pipe_state, bt_scene_rig(sc), &cfg) != RP_OK) {
        fprintf(stderr, "frameset_driver: setup failed (layout %s)\n", layout);
        return 1;
    }
    const int n_cams = bt_scene_rig(sc)->n_cams < RP_MAX_CAMS ? bt_scene_rig(sc)->n_cams
                                                               : RP_MAX_CAMS;
    for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n_cams; ++k) {
            bt_scene_render(sc, j, k, img + ((size_t)j * RP_MAX_CAMS + k) * w * h);
        }
    }
    rp_estimate_t est;
    rp_status_t st = RP_OK;
    int fails = 0;
    for (int j = 0; j < n; ++j) {
        rp_image_t views[RP_MAX_CAMS];
        const rp_image_t *im[RP_MAX_CAMS];
        for (int k = 0; k < RP_MAX_CAMS; ++k) {
            views[k].data = img + ((size_t)j * RP_MAX_CAMS + k) * w * h;
            views[k].w = (uint16_t)w;
            views[k].h = (uint16_t)h;
            views[k].stride = (uint32_t)w;
            views[k].size = (uint32_t)(w * h);
            im[k] = k < n_cams ? &views[k] : NULL;
        }
        const int64_t utime = (int64_t)j * 33333;
        st = j < warm ? bt_warm(im, utime, &est) : bt_measured(im, utime, &est);
        fails += st != RP_OK;
    }
    const double *p = bt_scene_pose(sc, n - 1);
    printf("frameset_driver: %s %dx%d (window %d, %d levels, %d features), %d warm + %d measured "
           "frame sets, %d not OK; last position error %.4f m\n",
           layout, w, h, cfg.track.win, cfg.track.levels, cfg.track.target, warm, measure, fails,
           sqrt(pow((double)est.p[0] - p[0], 2) + pow((double)est.p[1] - p[1], 2) +
                pow((double)est.p[2] - p[2], 2)));
    free(img);
    bt_scene_free(sc);
    return 0;
}
