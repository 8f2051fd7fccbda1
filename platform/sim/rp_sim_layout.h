/*
 * rp_sim_layout.h - candidate placements of cam2 and cam4 for the layout study
 * (`rigpose-sim --layout-study [FILE]`): read from a file or a built-in grid, applied to the
 * simulation's configuration, ranked by the pose error they give.
 *
 * Placement file: one placement per line, '#' starts a comment, blank lines are skipped:
 *
 *     # name   cam2: x y z (m) yaw (deg)     cam4: x y z (m) yaw (deg)
 *     paper    0.0866 0 -0.05  90            -0.0866 0 -0.05 -90
 *     wide     0.25   0 -0.05  90            -0.25   0 -0.05 -90
 *
 * Positions are in cam1's frame (x right, y down, z forward), metres; yaw is about cam1's y
 * axis, degrees: 0 looks forward, 90 right, -90 left, 180 back. A name is at most
 * RP_SIM_LAYOUT_NAME - 1 characters without spaces. A placement within 0.1 mm and 0.01 degree
 * of the paper's is taken as exactly the paper's (so it reproduces the plain `gc` figures).
 */
#ifndef RP_SIM_LAYOUT_H
#define RP_SIM_LAYOUT_H

#ifdef __cplusplus
extern "C" {
#endif

#include <stddef.h>
#include <stdint.h>

#include "rp_sim.h"

#define RP_SIM_LAYOUT_NAME 32
#define RP_SIM_LAYOUT_MAX 256 /* placements per study */

typedef struct {
    char name[RP_SIM_LAYOUT_NAME];
    rp_sim_place_t cam2, cam4;
    int is_paper; /* 1: exactly the paper's placement */
} rp_sim_layout_t;

/* Parse one line of a placement file. Returns 1 and fills *out for a placement, 0 for a blank
 * or comment line, -1 for a malformed line with the reason in err (without the line number). */
int rp_sim_layout_parse_line(const char *line, rp_sim_layout_t *out, char *err, size_t err_len);

/* Read a placement file into out[0..max-1]. Returns the number of placements, or -1 with
 * "PATH:LINE: reason" in err (file missing, a malformed line, two placements with one name,
 * more than max, none at all). */
int rp_sim_layout_read(const char *path, rp_sim_layout_t *out, int max, char *err,
                       size_t err_len);

/* The built-in grid: cam2 at (x, 0, z) with yaw, cam4 mirrored at (-x, 0, z) with -yaw, for
 * x in {0.0866 (the paper), 0.15, 0.25} m, z in {-0.05 (the paper), 0.05, -0.15} m and yaw in
 * {90 (the paper), 60, 120} degrees: 27 placements, the paper's first. Returns the number
 * written (at most max). */
int rp_sim_layout_grid(rp_sim_layout_t *out, int max);

/* The paper's placement (named "paper"). */
rp_sim_layout_t rp_sim_layout_paper(void);

/* Put the placement into a simulation configuration. */
void rp_sim_layout_apply(const rp_sim_layout_t *l, rp_sim_cfg_t *cfg);

/* order[0..n-1] = indices of key[] from the smallest to the largest; equal keys keep their
 * index order; NaN keys last. */
void rp_sim_layout_rank(const double *key, uint32_t n, uint32_t *order);

#ifdef __cplusplus
}
#endif

#endif /* RP_SIM_LAYOUT_H */
