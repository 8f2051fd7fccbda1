/*
 * rp_track.h - the per-camera image front end: Gaussian pyramids, Shi-Tomasi corners with
 * non-maximum suppression, minimum distance and spatial bucketing, pyramidal Lucas-Kanade tracking
 * with a forward-backward check, and top-up detection. Integer / fixed-point image arithmetic;
 * rp_real only for the output positions. Caller-owned state: `static rp_tracker_t trk;` per camera.
 *
 * Fixed-point formats used throughout (named in the code):
 *   positions   int32 Q16 pixels (origin at the top-left pixel centre), level coordinates
 *   gradients   int16 Scharr ([3 10 3] x [-1 0 1]: 32x the derivative in grey levels / px)
 *   intensities interpolated in Q5 (grey level x 32) with Q7 bilinear weights, in int16 lanes;
 *               the sample points are rounded to 1/128 px and the estimate is corrected for it
 *               (results within about 0.001 px of OpenCV's Q14 weights, tests/integration/oracle_track.cpp)
 *   sums        int32 over chunks of at most 64 window pixels (|product| < 2^25), then int64
 *               (structure tensor, mismatch vector); detection responses int32
 * Speed: window rows are padded to multiples of 8 pixels and every inner loop runs over lane
 * groups of 8 int16 (GCC vector extensions on SSE2 / NEON, plain C elsewhere; bit-identical,
 * tests/test_track.c); interpolation and gradients run column group by column group with the rows
 * rolling in registers, straight from the pyramid away from the border. After the first 2 tracks
 * of a frame, a track starts from the displacement of the nearest track that passed before it
 * (its bucketing cell and the 8 around it) on the finest level only, and runs over all levels
 * from zero motion if there is none or that fails; the backward check starts at the original position on the finest
 * level and carries the residual test. Coarse levels stop at 16x the convergence step; detection
 * streams rows (no full-frame response map) and, on top-up, searches only the cells that lack
 * features.
 */
#ifndef RP_TRACK_H
#define RP_TRACK_H

#include "rp_frame.h"
#include "rp_image.h"
#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif


typedef struct {
    uint8_t cam;         /* camera index 0..RP_MAX_CAMS-1; ids: rp_track_id(cam, serial) */
    uint8_t levels;      /* pyramid levels incl. full resolution, 1..RP_TRACK_MAX_LEVELS (4) */
    uint8_t win;         /* LK window side, px, odd, 5..RP_TRACK_MAX_WIN (21) */
    uint8_t max_iter;    /* LK iterations per level (30) */
    uint32_t eps_q16;    /* LK convergence: step shorter than this, Q16 px (0.01 px = 655) */
    uint32_t min_eig;    /* drop a track whose gradient matrix has min eigenvalue / window area
                          * below this, Scharr units^2 / 2^20 (OpenCV's minEigThreshold * 2^20;
                          * 105 = its default 1e-4) */
    uint32_t fb_max_q16; /* forward-backward tolerance, Q16 px (1 px = 65536); 0 = no check */
    uint16_t target;     /* features wanted (150) */
    uint16_t topup_below; /* detect again when fewer tracks than this survive (0.8 target) */
    uint16_t min_dist;   /* smallest distance between features, px (10) */
    uint16_t quality_q16; /* corner response relative to the frame's best, Q16 (0.01 = 655) */
    uint32_t min_response; /* absolute floor on 2x the min eigenvalue of the 3x3 Sobel
                            * structure tensor (Sobel units^2); rejects noise on flat images */
    uint8_t grid_x, grid_y; /* bucketing grid, cells (grid_x * grid_y <= RP_TRACK_MAX_CELLS) */
    uint16_t cell_cap;   /* features per cell at most (0 = 2 * target / cells + 1) */
    uint8_t min_contrast; /* max - min grey level below this: a blank frame (skipped) */
    uint16_t max_err_q5; /* drop a track whose window still differs by more than this mean
                          * |J - I| after converging, grey levels Q5 (20 levels = 640); 0 = off */
    uint8_t reset_q8;    /* when at least this share (Q8: 205 = 80 %) of a frame's tracks that
                          * stayed inside the image failed, and at least RP_TRACK_RESET_MIN
                          * stayed inside, drop the survivors too and detect afresh: the
                          * image moved beyond the tracker's reach, and the few tracks that
                          * "passed" mostly landed on a look-alike (rendered discs: 6 of 10 over
                          * 3 px, 40 px mean). 0 = off */
} rp_track_cfg_t;

/* Tracks that stayed inside the image a frame needs before reset_q8 can drop its survivors. */
#define RP_TRACK_RESET_MIN 20

/* Events of one rp_track_process call, as flags. */
enum {
    RP_TRACK_FIRST     = 1u << 0, /* no previous image: features detected only */
    RP_TRACK_TOPPED_UP = 1u << 1, /* new features detected this frame */
    RP_TRACK_ALL_LOST  = 1u << 2, /* every track from the previous frame was lost (re-detected) */
    RP_TRACK_BLANK     = 1u << 3, /* blank frame: ignored, previous image and tracks kept */
    RP_TRACK_RESET     = 1u << 4  /* most tracks failed: the survivors were dropped too
                                   * (cfg.reset_q8; with RP_TRACK_ALL_LOST) */
};

typedef struct {
    uint32_t flags;     /* RP_TRACK_* */
    uint16_t n_prev;    /* tracks before this frame */
    uint16_t n_tracked; /* tracks that survived */
    uint16_t n_lost_fb; /* dropped by the forward-backward check */
    uint16_t n_lost;    /* dropped otherwise (left the image, low texture, LK out of bounds) */
    uint16_t n_reset;   /* tracks that passed but were dropped by the reset (RP_TRACK_RESET) */
    uint16_t n_new;     /* new features */
    uint16_t n_cached;  /* tracks whose first patch came from the patch cache (rp_tracker_t) */
} rp_track_info_t;

/* One level of a pyramid inside a tracker's buffer. */
typedef struct {
    uint32_t off;  /* byte offset of the level in the pyramid buffer */
    uint16_t w, h; /* pixels (level l is ceil(w_{l-1} / 2) like cv::pyrDown) */
} rp_pyr_level_t;

#define RP_TRACK_PYR_BYTES                                                                       \
    ((RP_TRACK_MAX_W * RP_TRACK_MAX_H * 4) / 3 + 2 * (RP_TRACK_MAX_W + RP_TRACK_MAX_H) +          \
     4 * RP_TRACK_MAX_LEVELS + 16)

typedef struct {
    uint8_t pix[RP_TRACK_PYR_BYTES];
    rp_pyr_level_t lev[RP_TRACK_MAX_LEVELS];
    uint8_t n_lev;
} rp_pyr_t;

typedef struct {
    int32_t r;     /* response */
    uint16_t x, y; /* pixel */
} rp_track_cand_t;

/* Track ids: the camera in the low RP_TRACK_CAM_BITS bits, a serial per camera above them,
 * id = serial << 4 | cam. Camera 15 is never a tracker's (RP_MAX_CAMS <= 15), so RP_IDMAP_EMPTY
 * (0xFFFFFFFF) is outside the id space. The serial counts modulo 2^28: after 268 M detections in
 * one camera it wraps, and an id comes back only after every track born with it is long gone
 * (a track lives for frames, not for 2^28 detections). Serials are compared wrap-safe
 * (rp_track_serial_since), never with < or >=. */
#define RP_TRACK_CAM_BITS 4u
#define RP_TRACK_SERIAL_MASK (0xFFFFFFFFu >> RP_TRACK_CAM_BITS)
RP_STATIC_ASSERT(RP_MAX_CAMS <= 15, "camera 15 is reserved: RP_IDMAP_EMPTY stays no id");

static inline uint32_t rp_track_id(uint8_t cam, uint32_t serial)
{
    return ((serial & RP_TRACK_SERIAL_MASK) << RP_TRACK_CAM_BITS) | (uint32_t)cam;
}
static inline uint8_t rp_track_id_cam(uint32_t id)
{
    return (uint8_t)(id & ((1u << RP_TRACK_CAM_BITS) - 1u));
}
static inline uint32_t rp_track_id_serial(uint32_t id) { return id >> RP_TRACK_CAM_BITS; }
/* 1 if serial s was issued at or after serial k, modulo 2^28: within half the serial space
 * ahead of k (wrap-safe, as TCP sequence numbers are compared). */
static inline int rp_track_serial_since(uint32_t s, uint32_t k)
{
    return ((s - k) & RP_TRACK_SERIAL_MASK) <= (RP_TRACK_SERIAL_MASK >> 1);
}

/* A cached level-0 patch's key: the image (rp_tracker_t.pyr_gen) and the level-0 position
 * (Q16 px) it was taken at, and the structure tensor of its gradients. */
typedef struct {
    uint32_t gen;     /* 0: empty */
    int32_t key[2];
    int64_t A[3];     /* sum Ix^2, Ix Iy, Iy^2 */
} rp_track_patch_key_t;

/* Per-camera tracker. Large (two pyramids, about 0.82 MB at 640x480, and the patch cache, 0.5 MB):
 * allocate it statically. */
typedef struct {
    rp_track_cfg_t cfg;
    rp_pyr_t pyr[2];
    uint8_t cur;      /* index of the pyramid holding the last accepted image */
    uint8_t has_prev; /* 1 once an image was accepted */
    int64_t utime;    /* time of the last accepted image, us */
    uint32_t next_k;  /* serial of the next new track (id rp_track_id(cfg.cam, next_k)); counts
                       * modulo 2^28 (RP_TRACK_SERIAL_MASK) */
    uint16_t n;       /* current tracks */
    uint16_t n_dormant; /* of those, dormant (rp_track_set_dormant) */
    uint8_t topup_turn; /* 1: the next rp_track_process may top up (rp_track_set_topup_turn) */
    uint32_t id[RP_MAX_FEATS_PER_CAM];
    int32_t pos_q16[RP_MAX_FEATS_PER_CAM][2]; /* level-0 position, Q16 px */
    uint8_t dormant[RP_MAX_FEATS_PER_CAM];    /* 1: tracked to hold its place only */
    /* scratch of detection: rows stream through small rings, no full-frame response map */
    int32_t prod[3][3][RP_TRACK_MAX_W]; /* Sobel products gx^2, gx gy, gy^2 of 3 image rows */
    int32_t vsum[3][RP_TRACK_MAX_W];    /* their vertical 3-sums on the response row */
    int32_t rrow[3][RP_TRACK_MAX_W];    /* responses (2 x min eigenvalue) of 3 rows */
    rp_track_cand_t cand[RP_TRACK_MAX_CELLS][RP_TRACK_CELL_CANDS];
    uint16_t n_cand[RP_TRACK_MAX_CELLS];
    rp_track_cand_t list[RP_TRACK_MAX_CELLS * RP_TRACK_CELL_CANDS];
    /* scratch of tracking: level-0 displacement of track k over the last frame, Q16 px (valid for
     * the tracks that survived it; the flow guess of the tracks after it in the same frame) */
    int32_t flow_q16[RP_MAX_FEATS_PER_CAM][2];
    /* Patch cache. The backward check of a track takes the level-0 patch (grey levels and
     * gradients) of the current image at the track's new position, which is exactly the patch
     * the next frame's forward pass starts from: slot k keeps the one of the track that ends up
     * at index k, found again only if its key (image generation, position) matches, so a hit
     * gives the same numbers as recomputing (the cache changes no result). */
    uint32_t pyr_gen[2];   /* generation of each pyramid's image (0: none) */
    uint32_t gen_next;     /* last generation given */
    uint16_t n_slots;      /* slots at cfg.win (rp_track_init) */
    uint32_t slot_len;     /* int16 per slot: 3 x win x (win rounded up to 8) */
    rp_track_patch_key_t slot_key[RP_MAX_FEATS_PER_CAM];
    int16_t slot_pix[RP_TRACK_PATCH_CACHE_BYTES / 2 > 0 ? RP_TRACK_PATCH_CACHE_BYTES / 2 : 1];
} rp_tracker_t;

/* Defaults like OpenCV's: 21x21 window, 4 levels (maxLevel 3), 30 iterations, eps 0.01 px,
 * minEigThreshold 1e-4, forward-backward 1 px, 150 features, min distance 10 px, quality 0.01,
 * 8x6 grid, residual 20 grey levels. Returns RP_E_ARG if cfg is NULL. */
rp_status_t rp_track_default_cfg(rp_track_cfg_t *cfg);

/* Resets trk with cfg (copied). RP_E_ARG: NULL or a cfg value out of range (see rp_track_cfg_t). */
rp_status_t rp_track_init(rp_tracker_t *trk, const rp_track_cfg_t *cfg);

/* Tracks the features of the previous image into img, drops the bad ones (forward-backward,
 * texture, left the image), tops up to cfg.target when fewer than cfg.topup_below remain and it
 * is the tracker's turn (rp_track_set_topup_turn; always when no track remains), searching
 * first the bucketing cells that hold fewer than ceil(target / cells) features, then, if the
 * count is still under topup_below, the other cells under their cap (the target and the counts
 * are of live tracks: dormant ones, rp_track_set_dormant, are not counted), and writes at most cap
 * features to out (*n_out of them). info (may be NULL) receives the events.
 * Returns:
 *   RP_OK         features in out (on RP_TRACK_ALL_LOST they are all new, re-detected)
 *   RP_E_ARG      NULL pointer; image larger than RP_TRACK_MAX_W x H or smaller than the window
 *                 plus its pyramid; stride < w; truncated (size too small); state untouched
 *   RP_E_DEGENERATE blank image (contrast < cfg.min_contrast): ignored, the previous image and
 *                 its tracks are kept and the next frame tracks from them; *n_out = 0
 *   RP_E_TOO_FEW  image accepted, but no feature at all survived or was found (*n_out = 0)
 *   RP_E_FULL     more features than cap: the first cap written, all kept by the tracker */
rp_status_t rp_track_process(rp_tracker_t *trk, const rp_image_t *img, int64_t utime,
                             rp_feat_t *out, uint16_t cap, uint16_t *n_out, rp_track_info_t *info);

/* ---- feeding a tracker: the second camera of a stereo pair (rp_pipe) runs a tracker that only
 * follows the features handed to it, matched from the pair's first camera. */

/* Keeps only the tracks whose id comes from camera owner (rp_track_id_cam(id) == owner), in
 * their order; *n_kept (may be NULL) gets how many remain.
 * RP_E_ARG (NULL trk, owner >= RP_MAX_CAMS). */
rp_status_t rp_track_keep_owned(rp_tracker_t *trk, uint8_t owner, uint16_t *n_kept);

/* Drops the tracks whose id is one of ids[0..n_ids-1] (the others keep their order); *n_dropped
 * (may be NULL) gets how many went. RP_E_ARG (NULL trk, or NULL ids with n_ids > 0). */
rp_status_t rp_track_drop_ids(rp_tracker_t *trk, const uint32_t *ids, uint16_t n_ids,
                              uint16_t *n_dropped);

/* Makes the tracks whose id is one of ids[0..n_ids-1] dormant: still tracked, reported and
 * holding their place (the detector keeps min_dist from them and counts them in the cell caps),
 * but no longer counted in the target and the top-up threshold, which count the live tracks
 * only. For tracks that the estimator has judged useless but that would come back if dropped:
 * a stereo layout's retired tracks (rp_vo_stereo.h) on an object that moves with the rig,
 * which otherwise fill the budget and keep the detector from the static scene. A track stays
 * dormant until it is lost. *n_marked (may be NULL) gets how many became dormant.
 * RP_E_ARG (NULL trk, or NULL ids with n_ids > 0). */
rp_status_t rp_track_set_dormant(rp_tracker_t *trk, const uint32_t *ids, uint16_t n_ids,
                                 uint16_t *n_marked);

/* Adopts feature f, found in the tracker's current image by other means (a stereo match), as a
 * track with f's id at f's pixel (rounded to Q16); the next rp_track_process tracks it.
 * RP_E_FULL (RP_MAX_FEATS_PER_CAM tracks held: nothing added), RP_E_NAN (non-finite pixel),
 * RP_E_ARG (NULL). */
rp_status_t rp_track_adopt(rp_tracker_t *trk, const rp_feat_t *f);

/* The current tracks as rp_track_process writes them (id, level-0 pixel): at most cap into out,
 * *n their number. RP_E_FULL (more than cap: the first cap written), RP_E_ARG (NULL). */
rp_status_t rp_track_features(const rp_tracker_t *trk, rp_feat_t *out, uint16_t cap,
                              uint16_t *n);

/* Whether the next rp_track_process may top up (turn 1, as after rp_track_init) or not (0:
 * it only tracks, unless no track remains, when it detects anew whatever the turn). A caller that
 * runs several trackers in one frame set gives the turn to one at a time (rp_pipe.h), so that
 * at most one camera pays for detection (and its new features' matching) per frame set.
 * RP_E_ARG (NULL). */
rp_status_t rp_track_set_topup_turn(rp_tracker_t *trk, uint8_t turn);

/* *k: the serial of the next new track (its id is rp_track_id(cfg.cam, *k)), so a track whose
 * rp_track_serial_since(rp_track_id_serial(id), *k) was born after this call. RP_E_ARG (NULL). */
rp_status_t rp_track_next_serial(const rp_tracker_t *trk, uint32_t *k);

/* Sets the serial of the next new track (a run resumed from a recording, and the tests that
 * cross the serial's wrap). RP_E_ARG (NULL, k > RP_TRACK_SERIAL_MASK). */
rp_status_t rp_track_set_next_serial(rp_tracker_t *trk, uint32_t k);

/* *pyr: the pyramid of the last accepted image (for matching features into it; before the
 * first image it holds nothing). RP_E_ARG (NULL). */
rp_status_t rp_track_current_pyr(const rp_tracker_t *trk, const rp_pyr_t **pyr);

/* Builds a Gaussian pyramid of img ([1 4 6 4 1]/16 separable, as cv::pyrDown, borders reflected
 * 101; sums in int32, result rounded: (sum + 128) >> 8). RP_E_ARG as rp_track_process. */
rp_status_t rp_pyr_build(rp_pyr_t *pyr, const rp_image_t *img, uint8_t levels);

#ifdef __cplusplus
}
#endif

#endif /* RP_TRACK_H */
