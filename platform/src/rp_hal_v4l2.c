/*
 * rp_hal_v4l2.c - the HAL's v4l2 source: Linux video capture devices, all streaming at once.
 *
 * open   each device: capabilities, the best pixel format it offers (GREY, then the planar YUV
 *        formats whose first plane is grey, then YUYV / UYVY, then MJPEG), the configured size
 *        (refused if the driver gives another), the rate (best effort), RP_HAL_V4L2_NBUF (6)
 *        mmap buffers.
 * grab   poll() on every live device; each device's ready frames are dequeued and held (up to
 *        RP_HAL_V4L2_HOLD per camera, the oldest given back when full). Frames are grouped by
 *        capture time (the kernel timestamp plus the camera's configured clock offset,
 *        rp_hal_cam_cfg_t.offset_us; each frame keeps its own stamp): the newest set in which
 *        every live camera has a frame within sync_tol_us (rp_hal_group); frames that no set
 *        can use go back to the driver. Free-running cameras at their own rates (sets_latest):
 *        a set each time the set camera delivers a frame, every camera with its newest frame not
 *        yet delivered (rp_hal_group_latest). A set's frames
 *        stay with the caller until the next grab: GREY and planar YUV images are the driver's
 *        buffers themselves (zero copy), YUYV / UYVY / MJPEG are converted to grey. A camera whose device fails (ENODEV: it
 *        was unplugged) or that delivers nothing for timeout_ms (stalled) is closed, flagged
 *        GONE | MISSING in every set, and reopened every retry_ms; the other cameras go on. A
 *        reopened camera holds no set back until it delivers a frame (then it rejoins); if it
 *        stays silent for timeout_ms it is closed again.
 */
#include "rp_hal_priv.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <setjmp.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jpeglib.h>
#include <linux/videodev2.h>

#include "rigpose/rp_hal_v4l2.h"

/* ---- pure parts (rp_hal_v4l2.h) -------------------------------------------------------------- */

static rp_hal_status_t pick_bytes(const uint8_t *src, uint32_t src_stride, uint16_t w,
                                  uint16_t h, uint8_t *dst, uint32_t dst_stride, uint32_t first)
{
    if (src == NULL || dst == NULL || src_stride < 2u * w || dst_stride < w) {
        return RP_HAL_E_ARG;
    }
    for (uint32_t v = 0; v < h; v++) {
        const uint8_t *s = src + (size_t)v * src_stride + first;
        uint8_t *d = dst + (size_t)v * dst_stride;
        for (uint32_t u = 0; u < w; u++) {
            d[u] = s[2u * u];
        }
    }
    return RP_HAL_OK;
}

rp_hal_status_t rp_hal_yuyv_to_grey(const uint8_t *src, uint32_t src_stride, uint16_t w,
                                    uint16_t h, uint8_t *dst, uint32_t dst_stride)
{
    return pick_bytes(src, src_stride, w, h, dst, dst_stride, 0);
}

rp_hal_status_t rp_hal_uyvy_to_grey(const uint8_t *src, uint32_t src_stride, uint16_t w,
                                    uint16_t h, uint8_t *dst, uint32_t dst_stride)
{
    return pick_bytes(src, src_stride, w, h, dst, dst_stride, 1);
}

/* libjpeg reports errors through error_exit, which must not return: jump back instead. */
typedef struct {
    struct jpeg_error_mgr mgr;
    jmp_buf jump;
} jpeg_err_t;

static void jpeg_error_jump(j_common_ptr cinfo)
{
    jpeg_err_t *e = (jpeg_err_t *)(void *)cinfo->err;
    longjmp(e->jump, 1);
}

/* Counts warnings (corrupt data: libjpeg pads the image and goes on) without printing. */
static void jpeg_quiet(j_common_ptr cinfo, int level)
{
    if (level < 0) {
        cinfo->err->num_warnings++;
    }
}

rp_hal_status_t rp_hal_jpeg_to_grey(const uint8_t *jpg, size_t n, uint16_t w, uint16_t h,
                                    uint8_t *dst, size_t cap)
{
    if (jpg == NULL || dst == NULL || n < 4 || cap < (size_t)w * h || n > 0x7fffffffu) {
        return RP_HAL_E_ARG;
    }
    struct jpeg_decompress_struct cinfo;
    jpeg_err_t jerr;
    cinfo.err = jpeg_std_error(&jerr.mgr);
    jerr.mgr.error_exit = jpeg_error_jump;
    jerr.mgr.emit_message = jpeg_quiet;
    if (setjmp(jerr.jump)) {
        jpeg_destroy_decompress(&cinfo);
        return RP_HAL_E_FORMAT;
    }
    jpeg_create_decompress(&cinfo);
    jpeg_mem_src(&cinfo, jpg, (unsigned long)n);
    if (jpeg_read_header(&cinfo, TRUE) != JPEG_HEADER_OK || cinfo.image_width != w ||
        cinfo.image_height != h) {
        jpeg_destroy_decompress(&cinfo);
        return RP_HAL_E_FORMAT;
    }
    cinfo.out_color_space = JCS_GRAYSCALE;
    jpeg_start_decompress(&cinfo);
    while (cinfo.output_scanline < cinfo.output_height) {
        JSAMPROW row = dst + (size_t)cinfo.output_scanline * w;
        /* ignored: the rows read: 1, a memory source never suspends */
        (void)jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);
    const long warnings = jerr.mgr.num_warnings;
    jpeg_destroy_decompress(&cinfo);
    return warnings == 0 ? RP_HAL_OK : RP_HAL_E_FORMAT; /* a damaged frame is not a frame */
}

uint32_t rp_hal_seq_update(rp_hal_seq_t *s, uint32_t seq)
{
    uint32_t skipped = 0;
    if (s->have && seq == s->last) {
        s->repeats++;
    } else if (s->have && seq > s->last) {
        skipped = seq - s->last - 1u;
    }
    s->drops += skipped;
    s->last = seq;
    s->have = 1;
    return skipped;
}

uint8_t rp_hal_group(const int64_t *t_us, const uint8_t *count, uint8_t n, uint8_t stride,
                     const uint8_t *need, int64_t tol_us, int8_t *pick, int64_t *anchor_us)
{
    int64_t best = 0;
    uint8_t found = 0;
    for (uint8_t i = 0; i < n; i++) {
        for (uint8_t k = 0; k < count[i]; k++) {
            const int64_t a = t_us[(size_t)i * stride + k];
            uint8_t ok = (uint8_t)(!found || a > best);
            for (uint8_t j = 0; j < n && ok; j++) {
                uint8_t has = (uint8_t)!need[j];
                for (uint8_t m = 0; m < count[j] && !has; m++) {
                    const int64_t t = t_us[(size_t)j * stride + m];
                    has = (uint8_t)(t >= a - tol_us && t <= a);
                }
                ok = has;
            }
            if (ok) {
                best = a;
                found = 1;
            }
        }
    }
    uint8_t picked = 0;
    for (uint8_t j = 0; j < n; j++) {
        pick[j] = -1;
        for (int k = (int)count[j] - 1; k >= 0 && found; k--) {
            const int64_t t = t_us[(size_t)j * stride + (size_t)k];
            if (t >= best - tol_us && t <= best) {
                pick[j] = (int8_t)k;
                picked++;
                break;
            }
        }
    }
    *anchor_us = found ? best : 0;
    return picked;
}

uint8_t rp_hal_group_latest(const int64_t *t_us, const uint8_t *count, uint8_t n, uint8_t stride,
                            int ref, int8_t *pick, int64_t *anchor_us)
{
    int64_t anchor = 0;
    uint8_t found = 0;
    for (uint8_t j = 0; j < n; j++) {
        pick[j] = -1;
        if ((ref < 0 || j == ref) && count[j] > 0) {
            const int64_t t = t_us[(size_t)j * stride + count[j] - 1];
            anchor = !found || t > anchor ? t : anchor;
            found = 1;
        }
    }
    uint8_t picked = 0;
    for (uint8_t j = 0; j < n && found; j++) {
        if (count[j] > 0) {
            pick[j] = (int8_t)(count[j] - 1);
            picked++;
        }
    }
    *anchor_us = found ? anchor : 0;
    return picked;
}

uint8_t rp_hal_group_hopeless(const int64_t *t_us, const uint8_t *count, uint8_t n,
                              uint8_t stride, const uint8_t *need, int64_t tol_us, uint8_t i)
{
    int64_t bound = 0; /* frames of camera i older than this are hopeless */
    uint8_t any = 0;
    for (uint8_t j = 0; j < n; j++) {
        if (j != i && need[j] && count[j] > 0) {
            const int64_t oldest = t_us[(size_t)j * stride];
            bound = !any || oldest > bound ? oldest : bound;
            any = 1;
        }
    }
    uint8_t h = 0;
    while (any && h < count[i] && t_us[(size_t)i * stride + h] + tol_us < bound) {
        h++;
    }
    return h;
}

/* ---- devices --------------------------------------------------------------------------------- */

typedef struct {
    const rp_hal_cam_cfg_t *cfg;
    int fd;                       /* -1 while closed */
    uint32_t fourcc;              /* negotiated pixel format */
    uint16_t w, h;                /* negotiated size, px */
    uint32_t bpl;                 /* bytes per line of the first plane */
    uint32_t nbuf;
    void *buf[RP_HAL_V4L2_NBUF];  /* mmap'd driver buffers */
    size_t len[RP_HAL_V4L2_NBUF];
    uint8_t streaming;
    uint8_t gone;                 /* vanished or stalled: closed, reopened at retry_at */
    uint8_t rejoining;            /* reopened, no frame delivered yet: holds no set back */
    int64_t retry_at;             /* HAL clock, us */
    int64_t last_frame;           /* HAL clock of the last frame dequeued, us */
    rp_hal_seq_t seq;
    struct {
        uint32_t idx;             /* driver buffer */
        int64_t t_us;             /* kernel timestamp, us */
        uint32_t seq;             /* driver sequence number */
        uint32_t used;            /* bytes of image in the buffer */
    } held[RP_HAL_V4L2_HOLD];     /* frames waiting for a set, oldest first */
    uint8_t n_held;
    int out_idx;                  /* buffer of the last delivered set (-1: none), given back
                                   * at the next grab */
    uint8_t dropped;              /* frames skipped since the last delivered set */
    /* the frame being delivered (fill_set): its buffer, bytes, and the conversion's outcome */
    const uint8_t *conv_p;
    size_t conv_used;
    rp_hal_frame_t *conv_out;
    rp_hal_status_t conv_st;
    uint8_t grey[(size_t)RP_HAL_MAX_W * RP_HAL_MAX_H]; /* converted image (non-grey formats) */
} v4l2_cam_t;

typedef struct {
    uint8_t open, started;
    rp_hal_cfg_t cfg;
    char *err;
    uint32_t set_seq;
    v4l2_cam_t cam[RP_MAX_CAMS];
} v4l2_src_t;

static v4l2_src_t g_v4l2;

static int xioctl(int fd, unsigned long req, void *arg)
{
    int r;
    do {
        r = ioctl(fd, req, arg);
    } while (r == -1 && errno == EINTR);
    return r;
}

/* A capture buffer descriptor for mmap buffer `index`. */
static struct v4l2_buffer mmap_buf(uint32_t index)
{
    struct v4l2_buffer b;
    memset(&b, 0, sizeof b);
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = index;
    return b;
}

/* Preference among the formats a device offers; 0 = unusable. */
static int fmt_rank(uint32_t f)
{
    switch (f) {
    case V4L2_PIX_FMT_GREY: return 6;
    case V4L2_PIX_FMT_YUV420: case V4L2_PIX_FMT_YVU420: return 5;
    case V4L2_PIX_FMT_NV12: case V4L2_PIX_FMT_NV21: return 5;
    case V4L2_PIX_FMT_YUYV: return 4;
    case V4L2_PIX_FMT_UYVY: return 3;
    case V4L2_PIX_FMT_MJPEG: case V4L2_PIX_FMT_JPEG: return 2;
    default: return 0;
    }
}

static void fourcc_str(uint32_t f, char s[5])
{
    for (int i = 0; i < 4; i++) {
        const char c = (char)((f >> (8 * i)) & 0xffu);
        s[i] = (c >= 32 && c < 127) ? c : '?';
    }
    s[4] = '\0';
}

static void cam_close(v4l2_cam_t *c)
{
    if (c->fd >= 0 && c->streaming) {
        enum v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        /* ignored: best effort while closing: nothing left to do on failure */
        (void)xioctl(c->fd, VIDIOC_STREAMOFF, &type);
    }
    for (uint32_t i = 0; i < c->nbuf; i++) {
        if (c->buf[i] != NULL && c->buf[i] != MAP_FAILED) {
            /* ignored: best effort while closing: nothing left to do on failure */
            (void)munmap(c->buf[i], c->len[i]);
        }
        c->buf[i] = NULL;
    }
    c->nbuf = 0;
    c->streaming = 0;
    c->n_held = 0;
    c->out_idx = -1;
    if (c->fd >= 0) {
        /* ignored: best effort while closing: nothing left to do on failure */
        (void)close(c->fd);
    }
    c->fd = -1;
}

/* Opens and configures one device; on failure it is left closed. */
static rp_hal_status_t cam_open(v4l2_cam_t *c, char *err)
{
    const char *path = c->cfg->device;
    c->fd = open(path, O_RDWR | O_NONBLOCK);
    if (c->fd < 0) {
        return rp_hal_fail(err, RP_HAL_E_OPEN, "%s: cannot open: %s", path, strerror(errno));
    }
    struct v4l2_capability cap;
    memset(&cap, 0, sizeof cap);
    if (xioctl(c->fd, VIDIOC_QUERYCAP, &cap) != 0) {
        const int e = errno;
        cam_close(c);
        return rp_hal_fail(err, RP_HAL_E_OPEN, "%s: not a V4L2 device: %s", path, strerror(e));
    }
    const uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps
                                                                    : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
        cam_close(c);
        return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s: no single-planar streaming capture",
                           path);
    }
    /* The best format on offer. */
    uint32_t best = 0;
    int best_rank = 0;
    for (uint32_t i = 0; i < 64; i++) {
        struct v4l2_fmtdesc d;
        memset(&d, 0, sizeof d);
        d.index = i;
        d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (xioctl(c->fd, VIDIOC_ENUM_FMT, &d) != 0) {
            break;
        }
        if (fmt_rank(d.pixelformat) > best_rank) {
            best_rank = fmt_rank(d.pixelformat);
            best = d.pixelformat;
        }
    }
    if (best_rank == 0) {
        cam_close(c);
        return rp_hal_fail(err, RP_HAL_E_FORMAT,
                           "%s: offers none of GREY, YU12, YV12, NV12, NV21, YUYV, UYVY, MJPG",
                           path);
    }
    struct v4l2_format f;
    memset(&f, 0, sizeof f);
    f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(c->fd, VIDIOC_G_FMT, &f) != 0) {
        const int e = errno;
        cam_close(c);
        return rp_hal_fail(err, RP_HAL_E_IO, "%s: VIDIOC_G_FMT: %s", path, strerror(e));
    }
    f.fmt.pix.pixelformat = best;
    if (c->cfg->w != 0 && c->cfg->h != 0) {
        f.fmt.pix.width = c->cfg->w;
        f.fmt.pix.height = c->cfg->h;
    }
    f.fmt.pix.field = V4L2_FIELD_NONE;
    f.fmt.pix.bytesperline = 0;
    if (xioctl(c->fd, VIDIOC_S_FMT, &f) != 0) {
        const int e = errno;
        cam_close(c);
        return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s: VIDIOC_S_FMT: %s", path, strerror(e));
    }
    char fs[5];
    fourcc_str(f.fmt.pix.pixelformat, fs);
    if (fmt_rank(f.fmt.pix.pixelformat) == 0 ||
        (c->cfg->w != 0 && (f.fmt.pix.width != c->cfg->w || f.fmt.pix.height != c->cfg->h)) ||
        f.fmt.pix.width > RP_HAL_MAX_W || f.fmt.pix.height > RP_HAL_MAX_H ||
        f.fmt.pix.width == 0 || f.fmt.pix.height == 0) {
        cam_close(c);
        return rp_hal_fail(err, RP_HAL_E_FORMAT,
                           "%s: driver gives %s %ux%u, wanted %ux%u (at most %dx%d)", path, fs,
                           (unsigned)f.fmt.pix.width, (unsigned)f.fmt.pix.height,
                           (unsigned)c->cfg->w, (unsigned)c->cfg->h, RP_HAL_MAX_W,
                           RP_HAL_MAX_H);
    }
    c->fourcc = f.fmt.pix.pixelformat;
    c->w = (uint16_t)f.fmt.pix.width;
    c->h = (uint16_t)f.fmt.pix.height;
    const uint32_t min_bpl = (c->fourcc == V4L2_PIX_FMT_YUYV || c->fourcc == V4L2_PIX_FMT_UYVY)
                                 ? 2u * c->w : c->w;
    c->bpl = f.fmt.pix.bytesperline >= min_bpl ? f.fmt.pix.bytesperline : min_bpl;
    if (c->cfg->fps != 0) {
        struct v4l2_streamparm p;
        memset(&p, 0, sizeof p);
        p.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        p.parm.capture.timeperframe.numerator = 1;
        p.parm.capture.timeperframe.denominator = c->cfg->fps;
        (void)xioctl(c->fd, VIDIOC_S_PARM, &p); /* best effort: not every driver sets rates */
    }
    struct v4l2_requestbuffers rb;
    memset(&rb, 0, sizeof rb);
    rb.count = RP_HAL_V4L2_NBUF;
    rb.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    rb.memory = V4L2_MEMORY_MMAP;
    if (xioctl(c->fd, VIDIOC_REQBUFS, &rb) != 0 || rb.count < 2) {
        cam_close(c);
        return rp_hal_fail(err, RP_HAL_E_IO, "%s: cannot get 2..%d mmap buffers", path,
                           RP_HAL_V4L2_NBUF);
    }
    c->nbuf = rb.count < RP_HAL_V4L2_NBUF ? rb.count : RP_HAL_V4L2_NBUF;
    for (uint32_t i = 0; i < c->nbuf; i++) {
        struct v4l2_buffer b = mmap_buf(i);
        if (xioctl(c->fd, VIDIOC_QUERYBUF, &b) != 0) {
            cam_close(c);
            return rp_hal_fail(err, RP_HAL_E_IO, "%s: VIDIOC_QUERYBUF", path);
        }
        c->len[i] = b.length;
        c->buf[i] = mmap(NULL, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, c->fd,
                         (off_t)b.m.offset);
        if (c->buf[i] == MAP_FAILED) {
            cam_close(c);
            return rp_hal_fail(err, RP_HAL_E_IO, "%s: mmap: %s", path, strerror(errno));
        }
    }
    return RP_HAL_OK;
}

static rp_hal_status_t cam_stream_on(v4l2_cam_t *c, char *err)
{
    for (uint32_t i = 0; i < c->nbuf; i++) {
        struct v4l2_buffer b = mmap_buf(i);
        if (xioctl(c->fd, VIDIOC_QBUF, &b) != 0) {
            return rp_hal_fail(err, RP_HAL_E_IO, "%s: VIDIOC_QBUF: %s", c->cfg->device,
                               strerror(errno));
        }
    }
    enum v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(c->fd, VIDIOC_STREAMON, &type) != 0) {
        return rp_hal_fail(err, RP_HAL_E_IO, "%s: VIDIOC_STREAMON: %s", c->cfg->device,
                           strerror(errno));
    }
    c->streaming = 1;
    c->seq.have = 0;
    c->last_frame = rp_hal_now_us();
    return RP_HAL_OK;
}

/* The grey image of a frame of `used` bytes at p: the driver's buffer itself for GREY and the
 * planar formats (zero copy, stride = bytes per line), else converted into the camera's grey
 * buffer. RP_HAL_E_FORMAT for a short or corrupt frame. */
static rp_hal_status_t cam_image(v4l2_cam_t *c, const uint8_t *p, size_t used, rp_image_t *img)
{
    const int packed = c->fourcc == V4L2_PIX_FMT_YUYV || c->fourcc == V4L2_PIX_FMT_UYVY;
    const size_t need = (size_t)c->bpl * (c->h - 1u) + (packed ? 2u * c->w : c->w);
    rp_hal_status_t st;
    img->w = c->w;
    img->h = c->h;
    img->data = c->grey;
    img->stride = c->w;
    img->size = (uint32_t)c->w * c->h;
    switch (c->fourcc) {
    case V4L2_PIX_FMT_MJPEG:
    case V4L2_PIX_FMT_JPEG:
        st = rp_hal_jpeg_to_grey(p, used, c->w, c->h, c->grey, sizeof c->grey);
        break;
    case V4L2_PIX_FMT_YUYV:
        st = used < need ? RP_HAL_E_FORMAT
                         : rp_hal_yuyv_to_grey(p, c->bpl, c->w, c->h, c->grey, c->w);
        break;
    case V4L2_PIX_FMT_UYVY:
        st = used < need ? RP_HAL_E_FORMAT
                         : rp_hal_uyvy_to_grey(p, c->bpl, c->w, c->h, c->grey, c->w);
        break;
    default: /* GREY, or the grey first plane of a planar YUV format */
        st = used < need ? RP_HAL_E_FORMAT : RP_HAL_OK;
        img->data = p;
        img->stride = c->bpl;
        img->size = (uint32_t)used;
        break;
    }
    if (st != RP_HAL_OK) {
        img->data = NULL;
    }
    return st;
}

static int64_t buf_time_us(const struct v4l2_buffer *b)
{
    if ((b->flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
        return (int64_t)b->timestamp.tv_sec * 1000000 + (int64_t)b->timestamp.tv_usec;
    }
    return rp_hal_now_us(); /* the driver's clock is not ours: stamp on arrival */
}

static int cam_requeue(v4l2_cam_t *c, uint32_t idx)
{
    struct v4l2_buffer q = mmap_buf(idx);
    return xioctl(c->fd, VIDIOC_QBUF, &q);
}

/* Gives camera c's k oldest held frames back to the driver. 0, or -1 if the device failed. */
static int cam_drop_held(v4l2_cam_t *c, uint8_t k)
{
    int rc = 0;
    for (uint8_t j = 0; j < k && j < c->n_held; j++) {
        rc |= cam_requeue(c, c->held[j].idx);
    }
    k = k < c->n_held ? k : c->n_held;
    memmove(c->held, c->held + k, (size_t)(c->n_held - k) * sizeof c->held[0]);
    c->n_held = (uint8_t)(c->n_held - k);
    return rc;
}

/* Takes every frame the driver has ready into the held list (the oldest goes back when it is
 * full). 1: new frames, 0: none, -1: the device failed (errno kept). */
static int cam_read(v4l2_cam_t *c)
{
    int got = 0;
    for (;;) {
        struct v4l2_buffer b = mmap_buf(0);
        if (xioctl(c->fd, VIDIOC_DQBUF, &b) != 0) {
            if (errno == EAGAIN) {
                break;
            }
            return -1;
        }
        if (b.index >= c->nbuf) {
            errno = EIO;
            return -1;
        }
        c->last_frame = rp_hal_now_us();
        if (rp_hal_seq_update(&c->seq, b.sequence) > 0) {
            c->dropped = 1;
        }
        if (b.flags & V4L2_BUF_FLAG_ERROR) {
            c->dropped = 1;
            if (cam_requeue(c, b.index) != 0) {
                return -1;
            }
            continue;
        }
        if (c->n_held == RP_HAL_V4L2_HOLD && cam_drop_held(c, 1) != 0) {
            return -1;
        }
        const size_t used = b.bytesused != 0 ? b.bytesused : c->len[b.index];
        c->held[c->n_held].idx = b.index;
        c->held[c->n_held].t_us = buf_time_us(&b);
        c->held[c->n_held].seq = b.sequence;
        c->held[c->n_held].used = (uint32_t)(used < c->len[b.index] ? used : c->len[b.index]);
        c->n_held++;
        got = 1;
    }
    return got;
}

static void cam_lost(v4l2_src_t *s, v4l2_cam_t *c, const char *why, int64_t now)
{
    /* ignored: it returns the status it was given: here only the message is wanted */
    (void)rp_hal_fail(s->err, RP_HAL_OK, "camera %u: %s: %s; reopening every %u ms",
                      (unsigned)(c - s->cam), c->cfg->device, why, (unsigned)s->cfg.retry_ms);
    cam_close(c);
    c->gone = 1;
    c->rejoining = 0;
    c->retry_at = now + (int64_t)s->cfg.retry_ms * 1000;
}

static void cam_retry(v4l2_src_t *s, v4l2_cam_t *c, int64_t now)
{
    char scratch[RP_HAL_ERR_MAX];
    if (cam_open(c, scratch) == RP_HAL_OK && cam_stream_on(c, scratch) == RP_HAL_OK) {
        c->gone = 0;
        c->rejoining = 1;
        return;
    }
    cam_close(c);
    c->retry_at = now + (int64_t)s->cfg.retry_ms * 1000;
}

/* ---- the source ------------------------------------------------------------------------------ */

static void v4l2_close(void *ctx)
{
    v4l2_src_t *s = (v4l2_src_t *)ctx;
    for (uint8_t i = 0; i < s->cfg.n_cams; i++) {
        cam_close(&s->cam[i]);
    }
    s->open = 0;
    s->started = 0;
}

static rp_hal_status_t v4l2_open(void **ctx, const rp_hal_cfg_t *cfg, char *err)
{
    v4l2_src_t *s = &g_v4l2;
    if (s->open) {
        return rp_hal_fail(err, RP_HAL_E_STATE, "v4l2: already open");
    }
    if (cfg->sync_tol_us < 0 || cfg->timeout_ms == 0 || cfg->retry_ms == 0 ||
        (cfg->sets_latest && cfg->set_cam >= (int)cfg->n_cams)) {
        return rp_hal_fail(err, RP_HAL_E_ARG,
                           "v4l2: need sync_tol_us >= 0, timeout_ms > 0, retry_ms > 0, a set "
                           "camera of the rig");
    }
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->err = err;
    for (uint8_t i = 0; i < cfg->n_cams; i++) {
        s->cam[i].fd = -1;
        s->cam[i].out_idx = -1;
        s->cam[i].cfg = &s->cfg.cam[i];
    }
    for (uint8_t i = 0; i < cfg->n_cams; i++) {
        if (memchr(cfg->cam[i].device, '\0', RP_HAL_PATH_MAX) == NULL ||
            cfg->cam[i].device[0] == '\0') {
            v4l2_close(s);
            return rp_hal_fail(err, RP_HAL_E_ARG, "v4l2: camera %u has no device path",
                               (unsigned)i);
        }
        const rp_hal_status_t st = cam_open(&s->cam[i], err);
        if (st != RP_HAL_OK) {
            v4l2_close(s);
            return st;
        }
    }
    s->open = 1;
    *ctx = s;
    return RP_HAL_OK;
}

static rp_hal_status_t v4l2_start(void *ctx)
{
    v4l2_src_t *s = (v4l2_src_t *)ctx;
    if (s->started) {
        return rp_hal_fail(s->err, RP_HAL_E_STATE, "v4l2: already started");
    }
    for (uint8_t i = 0; i < s->cfg.n_cams; i++) {
        v4l2_cam_t *c = &s->cam[i];
        if (c->fd < 0) {
            continue; /* gone while stopped: retried by grab */
        }
        const rp_hal_status_t st = cam_stream_on(c, s->err);
        if (st != RP_HAL_OK) {
            for (uint8_t j = 0; j <= i; j++) {
                if (s->cam[j].streaming) {
                    enum v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
                    /* ignored: best effort while closing: nothing left to do on failure */
                    (void)xioctl(s->cam[j].fd, VIDIOC_STREAMOFF, &type);
                    s->cam[j].streaming = 0;
                }
            }
            return st;
        }
    }
    s->started = 1;
    s->set_seq = 0;
    return RP_HAL_OK;
}

static rp_hal_status_t v4l2_stop(void *ctx)
{
    v4l2_src_t *s = (v4l2_src_t *)ctx;
    if (!s->started) {
        return rp_hal_fail(s->err, RP_HAL_E_STATE, "v4l2: not started");
    }
    for (uint8_t i = 0; i < s->cfg.n_cams; i++) {
        v4l2_cam_t *c = &s->cam[i];
        if (c->fd >= 0 && c->streaming) {
            enum v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            (void)xioctl(c->fd, VIDIOC_STREAMOFF, &type); /* returns every buffer to us */
        }
        c->streaming = 0;
        c->n_held = 0;
        c->out_idx = -1;
    }
    s->started = 0;
    return RP_HAL_OK;
}

/* Job `k` of a set (rp_hal_cfg_t.run_jobs): the k-th picked camera's frame to grey. */
typedef struct {
    v4l2_src_t *s;
    uint8_t cams[RP_MAX_CAMS]; /* the cameras with a picked frame */
} conv_jobs_t;

static void conv_job(void *arg, unsigned k)
{
    const conv_jobs_t *j = (const conv_jobs_t *)arg;
    v4l2_cam_t *c = &j->s->cam[j->cams[k]];
    c->conv_st = cam_image(c, c->conv_p, c->conv_used, &c->conv_out->img);
}

/* The set of the picked frames (rp_hal_group): each camera's picked frame is delivered (held
 * until the next grab), its older frames go back to the driver; a camera without a pick gives
 * back the frames older than the set's window. The picked frames are converted to grey after
 * the picking, one job per camera (in parallel with cfg.run_jobs). */
static void fill_set(v4l2_src_t *s, rp_hal_set_t *set, const int8_t pick[], int64_t anchor)
{
    rp_hal_set_clear(set, s->cfg.n_cams);
    conv_jobs_t jobs;
    jobs.s = s;
    unsigned n_conv = 0;
    for (uint8_t i = 0; i < s->cfg.n_cams; i++) {
        v4l2_cam_t *c = &s->cam[i];
        rp_hal_frame_t *f = &set->cam[i];
        f->drops = c->seq.drops;
        if (c->gone) {
            f->flags = RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE;
            continue;
        }
        if (pick[i] < 0) {
            uint8_t old = 0;
            while (old < c->n_held &&
                   c->held[old].t_us + s->cfg.cam[i].offset_us < anchor - s->cfg.sync_tol_us) {
                old++;
            }
            (void)cam_drop_held(c, old); /* a failing device shows at the next read */
            f->flags = c->rejoining ? RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE : RP_HAL_CAM_MISSING;
            continue;
        }
        /* ignored: a buffer the driver refuses back fails its next dequeue, which says so */
        (void)cam_drop_held(c, (uint8_t)pick[i]);
        const uint32_t idx = c->held[0].idx;
        f->utime = c->held[0].t_us;
        f->seq = c->held[0].seq;
        c->conv_p = (const uint8_t *)c->buf[idx];
        c->conv_used = c->held[0].used;
        c->conv_out = f;
        jobs.cams[n_conv++] = i;
        memmove(c->held, c->held + 1, (size_t)(c->n_held - 1) * sizeof c->held[0]);
        c->n_held--;
        c->out_idx = (int)idx;
        c->rejoining = 0;
    }
    if (s->cfg.run_jobs == NULL ||
        s->cfg.run_jobs(s->cfg.run_jobs_ctx, n_conv, conv_job, &jobs) != 0) {
        for (unsigned k = 0; k < n_conv; k++) {
            conv_job(&jobs, k);
        }
    }
    uint8_t first = 1;
    for (unsigned k = 0; k < n_conv; k++) {
        v4l2_cam_t *c = &s->cam[jobs.cams[k]];
        rp_hal_frame_t *f = c->conv_out;
        if (c->conv_st != RP_HAL_OK) { /* short or corrupt frame: this set goes without it */
            f->flags = RP_HAL_CAM_MISSING | RP_HAL_CAM_DROPPED;
            c->dropped = 0;
            continue;
        }
        f->flags = c->dropped ? RP_HAL_CAM_DROPPED : RP_HAL_CAM_OK;
        c->dropped = 0;
        if (first) {
            set->utime = f->utime;
            first = 0;
        }
    }
}

static rp_hal_status_t v4l2_grab(void *ctx, rp_hal_set_t *set)
{
    v4l2_src_t *s = (v4l2_src_t *)ctx;
    const uint8_t n = s->cfg.n_cams;
    if (!s->started) {
        return rp_hal_fail(s->err, RP_HAL_E_STATE, "v4l2: grab before start");
    }
    const int64_t timeout_us = (int64_t)s->cfg.timeout_ms * 1000;
    const int64_t deadline = rp_hal_now_us() + timeout_us;
    int64_t t[RP_MAX_CAMS * RP_HAL_V4L2_HOLD] = {0};
    uint8_t count[RP_MAX_CAMS] = {0}, need[RP_MAX_CAMS] = {0};
    int8_t pick[RP_MAX_CAMS];
    int64_t anchor;
    for (uint8_t i = 0; i < n; i++) { /* the last set's buffers go back to the drivers */
        v4l2_cam_t *c = &s->cam[i];
        if (!c->gone && c->out_idx >= 0 && cam_requeue(c, (uint32_t)c->out_idx) != 0) {
            cam_lost(s, c, strerror(errno), rp_hal_now_us());
        }
        c->out_idx = -1;
    }
    for (;;) {
        int64_t now = rp_hal_now_us();
        for (uint8_t i = 0; i < n; i++) {
            v4l2_cam_t *c = &s->cam[i];
            if (c->gone && now >= c->retry_at) {
                cam_retry(s, c, now);
            }
            if (!c->gone && cam_read(c) < 0) {
                cam_lost(s, c, errno == ENODEV ? "vanished" : strerror(errno), now);
            }
            if (!c->gone && now - c->last_frame >= timeout_us) {
                cam_lost(s, c, "stalled (no frame within timeout_ms)", now);
            }
        }
        for (uint8_t i = 0; i < n; i++) {
            const v4l2_cam_t *c = &s->cam[i];
            need[i] = (uint8_t)(!c->gone && !c->rejoining);
            count[i] = c->gone ? 0 : c->n_held;
            for (uint8_t k = 0; k < count[i]; k++) { /* by capture time: stamp + offset */
                t[i * RP_HAL_V4L2_HOLD + k] = c->held[k].t_us + s->cfg.cam[i].offset_us;
            }
        }
        if (s->cfg.sets_latest) {
            /* free-running: the set camera's frame makes the set; while it is gone (or
             * rejoining) any camera's does, so the other cameras go on */
            const int ref = s->cfg.set_cam >= 0 && s->cfg.set_cam < n &&
                                    need[s->cfg.set_cam]
                                ? s->cfg.set_cam
                                : -1;
            if (rp_hal_group_latest(t, count, n, RP_HAL_V4L2_HOLD, ref, pick, &anchor) > 0) {
                fill_set(s, set, pick, anchor);
                set->seq = s->set_seq++;
                return RP_HAL_OK;
            }
        } else if (rp_hal_group(t, count, n, RP_HAL_V4L2_HOLD, need, s->cfg.sync_tol_us, pick,
                                &anchor) > 0) {
            fill_set(s, set, pick, anchor);
            set->seq = s->set_seq++;
            return RP_HAL_OK;
        }
        for (uint8_t i = 0; i < n && !s->cfg.sets_latest; i++) { /* frames that can never be
                                                                    * in a set go back */
            const uint8_t h = rp_hal_group_hopeless(t, count, n, RP_HAL_V4L2_HOLD, need,
                                                    s->cfg.sync_tol_us, i);
            if (h > 0 && cam_drop_held(&s->cam[i], h) != 0) {
                cam_lost(s, &s->cam[i], strerror(errno), now);
            }
        }
        now = rp_hal_now_us();
        if (now >= deadline) {
            int len = snprintf(s->err, RP_HAL_ERR_MAX, "v4l2: no complete set in %u ms:",
                               (unsigned)s->cfg.timeout_ms);
            for (uint8_t i = 0; i < n && len > 0 && len < RP_HAL_ERR_MAX; i++) {
                const v4l2_cam_t *c = &s->cam[i];
                len += snprintf(s->err + len, (size_t)(RP_HAL_ERR_MAX - len), " cam%u %s",
                                (unsigned)i, c->gone ? "gone" : c->rejoining ? "rejoining"
                                             : c->n_held > 0 ? "waiting" : "no frame");
                need[i] = 0;
                count[i] = c->gone ? 0 : c->n_held;
                for (uint8_t k = 0; k < count[i]; k++) {
                    t[i * RP_HAL_V4L2_HOLD + k] = c->held[k].t_us + s->cfg.cam[i].offset_us;
                }
            }
            /* What there is: the newest frame held and those within the tolerance of it. */
            /* ignored: the count; pick[] says which cameras came (-1: none) */
            (void)rp_hal_group(t, count, n, RP_HAL_V4L2_HOLD, need, s->cfg.sync_tol_us, pick,
                               &anchor);
            fill_set(s, set, pick, anchor);
            return RP_HAL_E_TIMEOUT;
        }
        int64_t wait = deadline - now;
        struct pollfd pfd[RP_MAX_CAMS];
        nfds_t np = 0;
        for (uint8_t i = 0; i < n; i++) {
            const v4l2_cam_t *c = &s->cam[i];
            if (c->gone) {
                wait = c->retry_at - now < wait ? c->retry_at - now : wait;
                continue;
            }
            const int64_t stall_at = c->last_frame + timeout_us;
            wait = stall_at - now < wait ? stall_at - now : wait;
            pfd[np].fd = c->fd;
            pfd[np].events = POLLIN;
            pfd[np].revents = 0;
            np++;
        }
        const int ms = (int)(wait <= 0 ? 0 : (wait + 999) / 1000);
        if (np > 0) {
            (void)poll(pfd, np, ms); /* errors and hang-ups show in the next cam_read */
        } else {
            rp_hal_sleep_us((int64_t)ms * 1000);
        }
    }
}

rp_hal_status_t rp_hal_v4l2_describe(uint8_t cam, char *buf, size_t cap)
{
    const v4l2_src_t *s = &g_v4l2;
    if (!s->open) {
        return RP_HAL_E_STATE;
    }
    if (buf == NULL || cap == 0 || cam >= s->cfg.n_cams) {
        return RP_HAL_E_ARG;
    }
    const v4l2_cam_t *c = &s->cam[cam];
    char fs[5];
    fourcc_str(c->fourcc, fs);
    if (c->gone) {
        /* ignored: a message cut at RP_HAL_ERR_MAX is still a message */
        (void)snprintf(buf, cap, "%s: gone, retried every %u ms", c->cfg->device,
                       (unsigned)s->cfg.retry_ms);
    } else {
        /* ignored: a message cut at RP_HAL_ERR_MAX is still a message */
        (void)snprintf(buf, cap, "%s: %s %ux%u, %u bytes/line, %u mmap buffers", c->cfg->device,
                       fs, (unsigned)c->w, (unsigned)c->h, (unsigned)c->bpl, (unsigned)c->nbuf);
    }
    return RP_HAL_OK;
}

const rp_hal_ops_t rp_hal_v4l2_ops = {
    .name = "v4l2", .payload = RP_HAL_PAYLOAD_IMAGES, .open = v4l2_open, .start = v4l2_start,
    .grab = v4l2_grab, .stop = v4l2_stop, .close = v4l2_close};
