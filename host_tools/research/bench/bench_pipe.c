/*
 * bench_pipe.c - `make bench` section "pipe": stereo matching (rp_smatch) and the image pipeline
 * (rp_pipe) on rendered frames of the paper's six-camera rig in a textured room (img_fixture.h),
 * release core (double, Eigen, -O2), one thread.
 *
 * Per image size (320x240 at f = 400 px, 640x480 at f = 800 px): the rig takes a random walk
 * with the paper's per-frame steps (translation per world axis U[5, 15] mm, rotation per angle
 * U[5, 20] mrad, random signs, composed in the rig frame), frames rendered with +-2 grey levels
 * of uniform noise. Figures:
 *   matching at frame 0, both pairs: match rate (matched / left corners whose point the right
 *   camera sees), error against the true right pixel, epipolar residual, depth error of the
 *   triangulated matches, time per left feature (rp_smatch_pair alone);
 *   the pipeline: time per frame set (rp_pipe_step: trackers, matching, estimator) and the mean
 *   absolute pose error over frames 1.. for stereo4 and gc.
 * usage: bench_pipe [--frames N] [--seed S] [--out FILE.json] [--verbose] [--size 320|640]
 *   --verbose prints every frame set (flags, landmarks, features per camera, errors).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../../common/rp_cfg_diff.h"
#include "img_fixture.h"
#include "rigpose/rp_pipe.h"
#include "rigpose/rp_rot.h"
#include "rp_sim.h"

#define NCAM RP_SIM_NCAMS
#define MAXW 640
#define MAXH 480

static uint8_t img[NCAM][MAXW * MAXH];
static rp_pipe_t pipes[2];
static rp_pyr_t pyr_a, pyr_b;
static rp_smatch_t sm;
static rp_feat_t fb[RP_MAX_FEATS_PER_CAM];
static int verbose = 0;

static double now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e6 + (double)ts.tv_nsec * 1e-3;
}

typedef struct {
    double match_rate, err_px, epi_px_max, depth_pct, us_per_feat;
    double us_step[2], err[2][6];
    int n_ok[2];
} result_t;

/* Matching figures of pair (a, b) of frame set fs at pose p; adds to the sums. */
static void match_figures(const rp_rig_t *rig, const rp_frameset_t *fs, uint8_t a, uint8_t b,
                          const rp_real p[6], const fx_room_t *rm, double sum[5])
{
    rp_stereo_pair_t sp;
    rp_pose_lin_t pl;
    rp_stereo_pair_init(rig, a, b, &sp);
    rp_pose_lin_set(&pl, p);
    for (uint16_t i = 0; i < fs->n[a]; ++i) {
        rp_real M[3], uvb[2];
        if (fx_pixel_point(rig, a, p, rm, fs->f[a][i].uv, M) != 0 ||
            rp_rig_project(rig, b, &pl, M, uvb, NULL, NULL) != RP_OK ||
            !rp_cam_in_image(&rig->cam[b].cam, uvb)) {
            continue;
        }
        sum[0] += 1; /* findable */
        for (uint16_t j = 0; j < fs->n[b]; ++j) {
            if (fs->f[b][j].id != fs->f[a][i].id) {
                continue;
            }
            rp_real epi, P[3], Pt[3];
            rp_stereo_epipolar_px(rig, &sp, fs->f[a][i].uv, fs->f[b][j].uv, &epi);
            rp_stereo_triangulate(rig, &sp, fs->f[a][i].uv, fs->f[b][j].uv, P, NULL);
            rp_rig_cam_point(rig, a, &pl, M, Pt);
            sum[1] += 1;
            sum[2] += hypot((double)(fs->f[b][j].uv[0] - uvb[0]),
                            (double)(fs->f[b][j].uv[1] - uvb[1]));
            sum[3] = fmax(sum[3], (double)epi);
            sum[4] += fabs((double)(P[2] - Pt[2])) / (double)Pt[2];
        }
    }
}

static void render_all(const rp_rig_t *rig, const rp_real p[6], const fx_room_t *rm,
                       uint64_t *rs)
{
    for (int k = 0; k < NCAM; ++k) {
        fx_render(rig, k, p, rm, img[k], 2.0, rs);
    }
}

static result_t run_size(uint16_t w, uint16_t h, double f, int n_frames, uint64_t seed)
{
    result_t r;
    memset(&r, 0, sizeof(r));
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.width = w;
    sc.height = h;
    sc.focal_px = f;
    static rp_rig_t rig;
    rp_sim_make_rig(&sc, &rig);
    const fx_room_t rm = fx_room_default();
    static const rp_pipe_layout_t layouts[2] = {RP_PIPE_STEREO4, RP_PIPE_GC};
    for (int m = 0; m < 2; ++m) {
        rp_pipe_cfg_t cfg;
        rp_pipe_default_cfg(layouts[m], &cfg);
        cfg.gc.init_depth_m = RP_C(1.2); /* the room's typical range */
        cfg.gc.init_depth_sigma_m = RP_C(0.3);
        cfg.gc.init_on_sphere = 1;
        static int said[2];
        if (!said[m]) {
            static const char *const why[][2] = {
                {"gc.init_", "the rendered room's typical range, along the ray"}, {NULL, NULL}};
            (void)rp_cfg_diff_print(stderr, "bench_pipe", &cfg, why);
            said[m] = 1;
        }
        if (rp_pipe_init(&pipes[m], &rig, &cfg) != RP_OK) {
            fprintf(stderr, "bench_pipe: rp_pipe_init failed\n");
            exit(1);
        }
    }
    rp_rng_t rng;
    rp_rng_seed(&rng, seed);
    rp_real p[6] = {0, 0, 0, 0, 0, 0}, R[9];
    rp_rot_from_angles(p + 3, R);
    uint64_t rs = seed;
    double msum[5] = {0, 0, 0, 0, 0};
    for (int j = 0; j < n_frames; ++j) {
        if (j > 0) {
            rp_real d[3], Rd[9], Rn[9];
            for (int i = 0; i < 3; ++i) {
                const double s = rp_rng_uniform(&rng) < 0.5 ? -1.0 : 1.0;
                p[i] += (rp_real)(s * (0.005 + 0.010 * rp_rng_uniform(&rng)));
            }
            for (int i = 0; i < 3; ++i) {
                const double s = rp_rng_uniform(&rng) < 0.5 ? -1.0 : 1.0;
                d[i] = (rp_real)(s * (0.005 + 0.015 * rp_rng_uniform(&rng)));
            }
            rp_rot_from_angles(d, Rd);
            rp_rot_mul(R, Rd, Rn);
            memcpy(R, Rn, sizeof(R));
            rp_rot_to_angles(R, p + 3);
        }
        render_all(&rig, p, &rm, &rs);
        rp_image_t im[NCAM];
        const rp_image_t *ptr[NCAM];
        for (int k = 0; k < NCAM; ++k) {
            im[k] = fx_image(img[k], w, h);
            ptr[k] = &im[k];
        }
        for (int m = 0; m < 2; ++m) {
            rp_estimate_t est;
            const double t0 = now_us();
            const rp_status_t st = rp_pipe_step(&pipes[m], ptr, NCAM, (int64_t)j * 33333, &est);
            r.us_step[m] += (now_us() - t0) / n_frames;
            r.n_ok[m] += st == RP_OK;
            for (int i = 0; j > 0 && i < 6; ++i) {
                double e = fabs((double)(est.p[i] - p[i]));
                e = i >= 3 && e > 3.14159265358979 ? 2 * 3.14159265358979 - e : e;
                r.err[m][i] += e / (n_frames - 1);
            }
            if (verbose) {
                const rp_frameset_t *vf;
                rp_pipe_frameset(&pipes[m], &vf);
                printf("  %s %3d st %d flags 0x%02x lm %4u feats %3u %3u %3u %3u %3u %3u "
                       "err t %+.5f %+.5f %+.5f a %+.5f %+.5f %+.5f\n",
                       rp_pipe_layout_name(layouts[m]), j, (int)st, est.flags, est.n_landmarks,
                       vf->n[0], vf->n[1], vf->n[2], vf->n[3], vf->n[4], vf->n[5],
                       (double)(est.p[0] - p[0]), (double)(est.p[1] - p[1]),
                       (double)(est.p[2] - p[2]), (double)(est.p[3] - p[3]),
                       (double)(est.p[4] - p[4]), (double)(est.p[5] - p[5]));
            }
        }
        if (j == 0) {
            const rp_frameset_t *fs;
            rp_pipe_frameset(&pipes[0], &fs);
            match_figures(&rig, fs, RP_SIM_CAM1, RP_SIM_CAM1B, p, &rm, msum);
            match_figures(&rig, fs, RP_SIM_CAM3, RP_SIM_CAM3B, p, &rm, msum);
            /* matching alone: pair (cam1, partner), the frame's left features, 5 repeats */
            rp_smatch_cfg_t mc;
            rp_smatch_default_cfg(&mc);
            rp_smatch_init(&sm, &mc);
            rp_stereo_pair_t sp;
            rp_stereo_pair_init(&rig, RP_SIM_CAM1, RP_SIM_CAM1B, &sp);
            rp_pyr_build(&pyr_a, &im[RP_SIM_CAM1], 4);
            rp_pyr_build(&pyr_b, &im[RP_SIM_CAM1B], 4);
            const double t0 = now_us();
            for (int rep = 0; rep < 5; ++rep) {
                uint16_t nb;
                rp_smatch_pair(&sm, &rig, &sp, &pyr_a, &pyr_b, fs->f[RP_SIM_CAM1],
                               fs->n[RP_SIM_CAM1], fb, RP_MAX_FEATS_PER_CAM, &nb, NULL);
            }
            r.us_per_feat = (now_us() - t0) / 5.0 / fs->n[RP_SIM_CAM1];
        }
    }
    r.match_rate = msum[0] > 0 ? msum[1] / msum[0] : 0;
    r.err_px = msum[1] > 0 ? msum[2] / msum[1] : 0;
    r.epi_px_max = msum[3];
    r.depth_pct = msum[1] > 0 ? 100.0 * msum[4] / msum[1] : 0;
    return r;
}

int main(int argc, char **argv)
{
    int n_frames = 30;
    uint64_t seed = 1;
    const char *out = NULL;
    int only = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--frames") && i + 1 < argc) {
            n_frames = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--seed") && i + 1 < argc) {
            seed = strtoull(argv[++i], NULL, 10);
        } else if (!strcmp(argv[i], "--verbose")) {
            verbose = 1;
        } else if (!strcmp(argv[i], "--size") && i + 1 < argc) {
            only = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--out") && i + 1 < argc) {
            out = argv[++i];
        } else {
            fprintf(stderr,
                    "usage: %s [--frames N>=2] [--seed S] [--out FILE.json] [--verbose] "
                    "[--size 320|640]\n",
                    argv[0]);
            return 2;
        }
    }
    if (n_frames < 2) {
        fprintf(stderr, "bench_pipe: --frames must be at least 2\n");
        return 2;
    }
    static const struct {
        uint16_t w, h;
        double f;
        const char *tag;
    } sizes[2] = {{320, 240, 400.0, "320"}, {640, 480, 800.0, "640"}};
    result_t res[2];
    printf("pipe: rendered room, the paper's rig and motion, %d frames, seed %llu, release "
           "core, one thread\n",
           n_frames, (unsigned long long)seed);
    printf("| size | match rate | err vs truth px | epipolar max px | depth err %% | match "
           "us/feature | stereo4 us/frameset | gc us/frameset | stereo4 tx m | gc tx m |\n"
           "|---|---|---|---|---|---|---|---|---|---|\n");
    memset(res, 0, sizeof(res));
    for (int s = 0; s < 2; ++s) {
        if (only && only != sizes[s].w) {
            continue;
        }
        res[s] = run_size(sizes[s].w, sizes[s].h, sizes[s].f, n_frames, seed);
        const result_t *r = &res[s];
        printf("| %ux%u | %.3f | %.3f | %.4f | %.3f | %.1f | %.0f | %.0f | %.5f | %.5f |\n",
               sizes[s].w, sizes[s].h, r->match_rate, r->err_px, r->epi_px_max, r->depth_pct,
               r->us_per_feat, r->us_step[0], r->us_step[1], r->err[0][0], r->err[1][0]);
        printf("    stereo4 %d/%d steps OK, errors tx ty tz %.5f %.5f %.5f m, angles %.5f %.5f "
               "%.5f rad; gc %d/%d OK, %.5f %.5f %.5f m, %.5f %.5f %.5f rad\n",
               r->n_ok[0], n_frames, r->err[0][0], r->err[0][1], r->err[0][2], r->err[0][3],
               r->err[0][4], r->err[0][5], r->n_ok[1], n_frames, r->err[1][0], r->err[1][1],
               r->err[1][2], r->err[1][3], r->err[1][4], r->err[1][5]);
    }
    if (out != NULL) {
        FILE *fp = fopen(out, "w");
        if (fp == NULL) {
            perror(out);
            return 1;
        }
        fprintf(fp, "{");
        int first = 1;
        for (int s = 0; s < 2; ++s) {
            if (only && only != sizes[s].w) {
                continue;
            }
            const result_t *r = &res[s];
            const char *t = sizes[s].tag;
            fprintf(fp,
                    "%s\"smatch_match_rate_%s\": %.4f, \"smatch_err_px_%s\": %.4f, "
                    "\"smatch_epipolar_px_max_%s\": %.5f, \"smatch_depth_err_pct_%s\": %.4f, "
                    "\"smatch_us_per_feature_%s\": %.2f, \"pipe_stereo4_us_per_frameset_%s\": "
                    "%.1f, \"pipe_gc_us_per_frameset_%s\": %.1f, \"pipe_room_stereo4_tx_m_%s\": "
                    "%.6f, \"pipe_room_stereo4_gamma_rad_%s\": %.6f, \"pipe_room_gc_tx_m_%s\": "
                    "%.6f, \"pipe_room_gc_gamma_rad_%s\": %.6f",
                    first ? "" : ", ", t, r->match_rate, t, r->err_px, t, r->epi_px_max, t,
                    r->depth_pct, t, r->us_per_feat, t, r->us_step[0], t, r->us_step[1], t,
                    r->err[0][0], t, r->err[0][5], t, r->err[1][0], t, r->err[1][5]);
            first = 0;
        }
        fprintf(fp, "}\n");
        fclose(fp);
    }
    return 0;
}
