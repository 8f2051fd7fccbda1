/*
 * bt_scene.h - the tracker benchmark's scene: the paper's four single cameras (cam1..cam4 of
 * docs/design.md, fx = fy = 800 px at 640x480, scaled with the width, principal point at the centre)
 * inside a box room whose four walls carry natural-looking seeded textures, moving along the
 * paper's simulated trajectory (rp_sim: per-frame random translation and rotation). Each camera
 * sees its own wall (a plane), so every image is an exact plane-induced warp of its texture and
 * the true position of any tracked pixel in any other frame is known (bt_scene_transfer).
 * Host code (allocates); deterministic from the seed.
 */
#ifndef BT_SCENE_H
#define BT_SCENE_H

#include <stdint.h>

#include "rigpose/rp_rig.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BT_NCAMS 4 /* cam1..cam4 = rig cameras 0..3 */

typedef struct bt_scene bt_scene_t;

/* Scene of w x h images over n_frames frames, seeded. NULL if memory ran out. */
bt_scene_t *bt_scene_new(int w, int h, uint64_t seed, int n_frames);
void bt_scene_free(bt_scene_t *sc);

/* The rig (rigpose-sim's six cameras at w x h; cameras 0..3 are the ones rendered). */
const rp_rig_t *bt_scene_rig(const bt_scene_t *sc);

/* True pose [tx ty tz alpha beta gamma] of cam1 at frame j (the world is cam1 at frame 0). */
const double *bt_scene_pose(const bt_scene_t *sc, int frame);

/* Renders rig camera cam's (0..5; 4 and 5 are the stereo partners of cam1 and cam3, seeing their
 * walls) 8-bit grey image of frame j into img (w * h bytes, stride w). */
void bt_scene_render(bt_scene_t *sc, int frame, int cam, uint8_t *img);

/* Where the scene point seen by camera cam at pixel uv_a in frame fa appears in frame fb.
 * Returns 1, or 0 if it is not in front of the camera at fb. */
int bt_scene_transfer(const bt_scene_t *sc, int cam, int fa, const double uv_a[2], int fb,
                      double uv_b[2]);

#ifdef __cplusplus
}
#endif

#endif /* BT_SCENE_H */
