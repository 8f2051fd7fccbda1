/*
 * rp_publish.c - LCM messages through static buffers (rp_publish.h).
 */
#include "rp_publish.h"

#include <string.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_pipe.h"
#include "rigpose/rp_rot.h"

/* The pose message's per-camera arrays hold RP_MAX_CAMS entries. */
RP_STATIC_ASSERT(RP_MAX_CAMS == 6, "lcm_types: per-camera arrays are of 6");
/* The messages carry the core's codes as they are. */
RP_STATIC_ASSERT(RIGPOSE_POSE_T_METHOD_STEREO4 == RP_PIPE_STEREO4 &&
                     RIGPOSE_POSE_T_METHOD_STEREO2 == RP_PIPE_STEREO2 &&
                     RIGPOSE_POSE_T_METHOD_GC == RP_PIPE_GC &&
                     RIGPOSE_POSE_T_METHOD_CAM1 == RP_PIPE_CAM1 &&
                     RIGPOSE_POSE_T_METHOD_CAM2 == RP_PIPE_CAM2 &&
                     RIGPOSE_POSE_T_METHOD_CAM3 == RP_PIPE_CAM3 &&
                     RIGPOSE_POSE_T_METHOD_CAM4 == RP_PIPE_CAM4 &&
                     RIGPOSE_POSE_T_METHOD_RC == RP_PIPE_RC && RP_PIPE_LAYOUT_COUNT_ == 8,
                 "pose_t.METHOD_* are rp_pipe_layout_t, all eight");
RP_STATIC_ASSERT(RIGPOSE_POSE_T_FLAG_LOST == RP_EST_LOST &&
                     RIGPOSE_POSE_T_FLAG_SCALE_WEAK == RP_EST_SCALE_WEAK &&
                     RIGPOSE_POSE_T_FLAG_HELD == RP_EST_HELD &&
                     RIGPOSE_POSE_T_FLAG_UNSYNCED == RP_EST_UNSYNCED &&
                     RIGPOSE_POSE_T_FLAG_CLOCK_JUMP == RP_EST_CLOCK_JUMP,
                 "pose_t.FLAG_* are RP_EST_*");
/* lcm-gen's sizes are int. */
RP_STATIC_ASSERT(RP_PUB_IMAGE_BYTES < 0x7fffffff, "image_t fits an int length");

static uint8_t g_pose_buf[RP_PUB_POSE_BYTES];
static uint8_t g_status_buf[RP_PUB_STATUS_BYTES];
static uint8_t g_image_buf[RP_PUB_IMAGE_BYTES];
static uint8_t g_feats_buf[RP_PUB_FEATS_BYTES];
static rigpose_features_t g_feats; /* 11 KB: static, not on the daemon's stack */
static uint8_t g_pack_buf[RP_HAL_MAX_W * RP_HAL_MAX_H]; /* an image with padded rows, packed */

const char *rp_pub_status_str(rp_pub_status_t s)
{
    switch (s) {
    case RP_PUB_OK: return "ok";
    case RP_PUB_E_ARG: return "bad argument";
    case RP_PUB_E_SIZE: return "message larger than its buffer";
    case RP_PUB_E_ENCODE: return "encoding failed";
    case RP_PUB_E_LCM: return "lcm_publish failed";
    }
    return "unknown publish status";
}

void rp_pub_fill_pose(rigpose_pose_t *m, const rp_hal_set_t *set, const rp_estimate_t *est,
                      rp_status_t st, int32_t seq, uint8_t n_cams, int8_t method)
{
    if (m == NULL || set == NULL || est == NULL) {
        return;
    }
    memset(m, 0, sizeof *m);
    m->utime = set->utime;
    m->seq = seq;
    m->frame = (int32_t)est->frame;
    m->method = method;
    rp_real R[9], q[4];
    rp_rot_from_angles(&est->p[3], R);
    rp_rot_to_quat(R, q);
    for (int i = 0; i < 3; ++i) {
        m->position[i] = (double)est->p[i];
        m->angles[i] = (double)est->p[3 + i];
        m->velocity[i] = (double)est->v[i];
        m->angle_rates[i] = (double)est->v[3 + i];
    }
    for (int i = 0; i < 4; ++i) {
        m->quaternion[i] = (double)q[i];
    }
    for (int i = 0; i < 36; ++i) {
        m->covariance[i] = (double)est->cov[i];
    }
    m->n_cams = (int8_t)n_cams;
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        m->features_used[k] = (int16_t)(k < n_cams ? est->n_used[k] : 0);
    }
    m->n_gated = (int16_t)est->n_gated;
    m->n_landmarks = (int16_t)est->n_landmarks;
    m->flags = (int32_t)est->flags;
    m->est_status = (int32_t)st;
    m->has_truth = set->has_truth ? 1 : 0;
    for (int i = 0; i < 6; ++i) {
        m->truth[i] = set->has_truth ? (double)set->truth[i] : 0.0;
    }
}

/* The encoded length (or a negative lcm-gen error) into buf of cap bytes, then lcm_publish. */
static rp_pub_status_t send(lcm_t *lcm, const char *channel, const uint8_t *buf, int size,
                            int encoded)
{
    if (encoded < 0 || encoded != size) {
        return RP_PUB_E_ENCODE;
    }
    return lcm_publish(lcm, channel, buf, (unsigned)encoded) == 0 ? RP_PUB_OK : RP_PUB_E_LCM;
}

rp_pub_status_t rp_pub_pose(lcm_t *lcm, const char *channel, const rigpose_pose_t *m)
{
    if (lcm == NULL || channel == NULL || channel[0] == '\0' || m == NULL) {
        return RP_PUB_E_ARG;
    }
    const int n = rigpose_pose_t_encoded_size(m);
    if (n < 0 || (size_t)n > sizeof g_pose_buf) {
        return RP_PUB_E_SIZE;
    }
    return send(lcm, channel, g_pose_buf, n,
                rigpose_pose_t_encode(g_pose_buf, 0, (int)sizeof g_pose_buf, m));
}

rp_pub_status_t rp_pub_status(lcm_t *lcm, const char *channel, const rigpose_status_t *m)
{
    if (lcm == NULL || channel == NULL || channel[0] == '\0' || m == NULL) {
        return RP_PUB_E_ARG;
    }
    const int n = rigpose_status_t_encoded_size(m);
    if (n < 0 || (size_t)n > sizeof g_status_buf) {
        return RP_PUB_E_SIZE;
    }
    return send(lcm, channel, g_status_buf, n,
                rigpose_status_t_encode(g_status_buf, 0, (int)sizeof g_status_buf, m));
}

rp_pub_status_t rp_pub_image(lcm_t *lcm, const char *channel, const rigpose_image_t *m)
{
    if (lcm == NULL || channel == NULL || channel[0] == '\0' || m == NULL || m->size < 0 ||
        (m->size > 0 && m->data == NULL)) {
        return RP_PUB_E_ARG;
    }
    const int n = rigpose_image_t_encoded_size(m);
    if (n < 0 || (size_t)n > sizeof g_image_buf) {
        return RP_PUB_E_SIZE;
    }
    return send(lcm, channel, g_image_buf, n,
                rigpose_image_t_encode(g_image_buf, 0, (int)sizeof g_image_buf, m));
}

rp_pub_status_t rp_pub_set_images(lcm_t *lcm, const char *channel, const rp_hal_set_t *set,
                                  int32_t seq, int *bad_cam)
{
    if (bad_cam != NULL) {
        *bad_cam = -1;
    }
    if (lcm == NULL || channel == NULL || set == NULL) {
        return RP_PUB_E_ARG;
    }
    rp_pub_status_t first = RP_PUB_OK;
    for (uint8_t k = 0; k < set->n_cams && k < RP_MAX_CAMS; ++k) {
        const rp_image_t *im = &set->cam[k].img;
        const size_t n = (size_t)im->w * im->h;
        if (im->data == NULL || n == 0) {
            continue; /* no image from this camera in the set */
        }
        rp_pub_status_t st = RP_PUB_OK;
        const uint8_t *packed = im->data;
        if (im->stride < im->w || (size_t)im->stride * (im->h - 1u) + im->w > im->size) {
            st = RP_PUB_E_ARG;
        } else if (n > sizeof g_pack_buf) {
            st = RP_PUB_E_SIZE;
        } else if (im->stride != im->w) {
            for (uint16_t y = 0; y < im->h; ++y) {
                memcpy(g_pack_buf + (size_t)y * im->w, im->data + (size_t)y * im->stride, im->w);
            }
            packed = g_pack_buf;
        }
        if (st == RP_PUB_OK) {
            rigpose_image_t m;
            m.utime = set->cam[k].utime;
            m.seq = seq;
            m.cam = (int8_t)k;
            m.width = (int16_t)im->w;
            m.height = (int16_t)im->h;
            m.size = (int32_t)n;
            m.data = (uint8_t *)(uintptr_t)packed;
            st = rp_pub_image(lcm, channel, &m);
        }
        if (st != RP_PUB_OK && first == RP_PUB_OK) {
            first = st;
            if (bad_cam != NULL) {
                *bad_cam = (int)k;
            }
        }
    }
    return first;
}

void rp_pub_fill_features(rigpose_features_t *m, uint8_t cam, int64_t utime, int32_t seq,
                          const rp_feat_t *f, uint16_t n)
{
    if (m == NULL) {
        return;
    }
    memset(m, 0, sizeof *m);
    if (f == NULL || n > RP_PUB_FEATS_MAX) {
        n = f == NULL ? 0 : (uint16_t)RP_PUB_FEATS_MAX;
    }
    m->utime = utime;
    m->seq = seq;
    m->cam = (int8_t)cam;
    m->n = (int16_t)n;
    for (uint16_t i = 0; i < n; ++i) {
        m->id[i] = (int32_t)f[i].id;
        m->u[i] = (double)f[i].uv[0];
        m->v[i] = (double)f[i].uv[1];
    }
}

rp_pub_status_t rp_pub_features(lcm_t *lcm, const char *channel, const rigpose_features_t *m)
{
    if (lcm == NULL || channel == NULL || channel[0] == '\0' || m == NULL) {
        return RP_PUB_E_ARG;
    }
    const int bytes = rigpose_features_t_encoded_size(m);
    if (bytes < 0 || (size_t)bytes > sizeof g_feats_buf) {
        return RP_PUB_E_SIZE;
    }
    return send(lcm, channel, g_feats_buf, bytes,
                rigpose_features_t_encode(g_feats_buf, 0, (int)sizeof g_feats_buf, m));
}

rp_pub_status_t rp_pub_set_features(lcm_t *lcm, const char *channel, const rp_frameset_t *fs,
                                    uint8_t n_cams, int32_t seq, int *bad_cam)
{
    if (bad_cam != NULL) {
        *bad_cam = -1;
    }
    if (lcm == NULL || channel == NULL || channel[0] == '\0' || fs == NULL) {
        return RP_PUB_E_ARG;
    }
    rp_pub_status_t first = RP_PUB_OK;
    for (uint8_t k = 0; k < n_cams && k < RP_MAX_CAMS; ++k) {
        rp_pub_fill_features(&g_feats, k, fs->utime, seq, fs->f[k], fs->n[k]);
        const rp_pub_status_t st = rp_pub_features(lcm, channel, &g_feats);
        if (st != RP_PUB_OK && first == RP_PUB_OK) {
            first = st;
            if (bad_cam != NULL) {
                *bad_cam = (int)k;
            }
        }
    }
    return first;
}
