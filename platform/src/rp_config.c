/*
 * rp_config.c - the configuration file (schema: config/README.md), read with libyaml's document
 * API. The schema lives in the parse_* functions below, one per mapping of the file, each
 * listing the keys it knows; every value goes through one typed getter that checks type and
 * range and reports "FILE:LINE: KEY: message" on the first error.
 */
#include "rigpose/rp_config.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <yaml.h>

#include "rigpose/rp_camera.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_esc.h"

const char *rp_cfg_status_str(rp_cfg_status_t s)
{
    switch (s) {
    case RP_CFG_OK: return "ok";
    case RP_CFG_E_ARG: return "bad argument";
    case RP_CFG_E_OPEN: return "cannot read file";
    case RP_CFG_E_SYNTAX: return "YAML syntax";
    case RP_CFG_E_MISSING: return "missing key";
    case RP_CFG_E_TYPE: return "wrong type";
    case RP_CFG_E_RANGE: return "value out of range";
    case RP_CFG_E_UNKNOWN: return "unknown key";
    }
    return "unknown status";
}

/* ---- context and error reporting ----------------------------------------------------------- */

/* printf into err (err_len bytes, may be NULL / 0), control characters escaped (rp_esc.h). */
static void set_err(char *err, size_t err_len, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static void set_err(char *err, size_t err_len, const char *fmt, ...)
{
    if (err == NULL || err_len == 0) {
        return;
    }
    char raw[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(raw, sizeof raw, fmt, ap);
    va_end(ap);
    rp_esc_text(err, err_len, raw);
}

typedef struct {
    const char *file;
    yaml_document_t *doc;
    char *err;
    size_t err_len;
    rp_cfg_status_t st; /* first error; RP_CFG_OK while none */
} ctx_t;

#define KEY_MAX 96 /* longest key path in a message */

/* Record the first error, at node `at` (its line) for key path `key`. Returns -1. */
static int fail(ctx_t *c, rp_cfg_status_t st, const yaml_node_t *at, const char *key,
                const char *fmt, ...)
{
    if (c->st != RP_CFG_OK) {
        return -1;
    }
    c->st = st;
    if (c->err != NULL && c->err_len > 0) {
        char msg[256];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, sizeof msg, fmt, ap);
        va_end(ap);
        const unsigned long line = at != NULL ? (unsigned long)at->start_mark.line + 1u : 0u;
        set_err(c->err, c->err_len, "%s:%lu: %s: %s", c->file, line, key, msg);
    }
    return -1;
}

/* out = "path.key" (or "key" at the top), cut at KEY_MAX - 1 characters. */
static void key_path(char *out, const char *path, const char *key)
{
    size_t n = 0;
    for (const char *s = path; *s != '\0' && n < KEY_MAX - 1; ++s) {
        out[n++] = *s;
    }
    if (n > 0 && n < KEY_MAX - 1) {
        out[n++] = '.';
    }
    for (const char *s = key; *s != '\0' && n < KEY_MAX - 1; ++s) {
        out[n++] = *s;
    }
    out[n] = '\0';
}

static yaml_node_t *node(ctx_t *c, int index)
{
    return yaml_document_get_node(c->doc, index);
}

static const char *node_kind(const yaml_node_t *n)
{
    switch (n->type) {
    case YAML_SCALAR_NODE: return "a scalar";
    case YAML_SEQUENCE_NODE: return "a sequence";
    case YAML_MAPPING_NODE: return "a mapping";
    default: return "nothing";
    }
}

static const char *scalar(const yaml_node_t *n)
{
    return (const char *)n->data.scalar.value;
}

/* Value of `key` in mapping map, NULL if absent. */
static yaml_node_t *map_get(ctx_t *c, const yaml_node_t *map, const char *key)
{
    for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top;
         ++p) {
        const yaml_node_t *k = node(c, p->key);
        if (k != NULL && k->type == YAML_SCALAR_NODE && strcmp(scalar(k), key) == 0) {
            return node(c, p->value);
        }
    }
    return NULL;
}

/* Every key of map must be a scalar in `known` (NULL-terminated) and appear once. */
static int check_keys(ctx_t *c, const yaml_node_t *map, const char *path,
                      const char *const *known)
{
    char kp[KEY_MAX];
    for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top;
         ++p) {
        const yaml_node_t *k = node(c, p->key);
        if (k == NULL || k->type != YAML_SCALAR_NODE) {
            return fail(c, RP_CFG_E_TYPE, k, path[0] ? path : "(top)", "a key must be a scalar");
        }
        key_path(kp, path, scalar(k));
        int found = 0;
        for (const char *const *q = known; *q != NULL; ++q) {
            found |= strcmp(*q, scalar(k)) == 0;
        }
        if (!found) {
            return fail(c, RP_CFG_E_UNKNOWN, k, kp, "unknown key (schema: config/README.md)");
        }
        for (yaml_node_pair_t *o = map->data.mapping.pairs.start; o < p; ++o) {
            const yaml_node_t *ko = node(c, o->key);
            if (ko != NULL && ko->type == YAML_SCALAR_NODE && strcmp(scalar(ko), scalar(k)) == 0) {
                return fail(c, RP_CFG_E_RANGE, k, kp, "key given twice");
            }
        }
    }
    return 0;
}

/* A mapping child: *out = the node, or NULL if absent and optional. */
static int get_map(ctx_t *c, const yaml_node_t *map, const char *path, const char *key,
                   int required, yaml_node_t **out)
{
    char kp[KEY_MAX];
    key_path(kp, path, key);
    *out = map_get(c, map, key);
    if (*out == NULL) {
        return required ? fail(c, RP_CFG_E_MISSING, map, kp, "missing (required mapping)") : 0;
    }
    if ((*out)->type != YAML_MAPPING_NODE) {
        return fail(c, RP_CFG_E_TYPE, *out, kp, "expected a mapping, got %s", node_kind(*out));
    }
    return 0;
}

/* ---- scalars -------------------------------------------------------------------------------- */

static int is_plain_scalar(const yaml_node_t *n)
{
    return n->type == YAML_SCALAR_NODE && n->data.scalar.style != YAML_SINGLE_QUOTED_SCALAR_STYLE &&
           n->data.scalar.style != YAML_DOUBLE_QUOTED_SCALAR_STYLE;
}

static int scalar_int(const yaml_node_t *n, long long *v)
{
    if (!is_plain_scalar(n) || n->data.scalar.length == 0) {
        return -1;
    }
    char *end = NULL;
    errno = 0;
    *v = strtoll(scalar(n), &end, 10);
    return (errno == 0 && end != NULL && *end == '\0') ? 0 : -1;
}

static int scalar_num(const yaml_node_t *n, double *v)
{
    if (!is_plain_scalar(n) || n->data.scalar.length == 0) {
        return -1;
    }
    char *end = NULL;
    errno = 0;
    *v = strtod(scalar(n), &end);
    return (errno == 0 && end != NULL && *end == '\0' && isfinite(*v)) ? 0 : -1;
}

static int get_int(ctx_t *c, const yaml_node_t *map, const char *path, const char *key,
                   int required, long long def, long long lo, long long hi, long long *out)
{
    char kp[KEY_MAX];
    key_path(kp, path, key);
    const yaml_node_t *n = map_get(c, map, key);
    if (n == NULL) {
        *out = def;
        return required ? fail(c, RP_CFG_E_MISSING, map, kp, "missing (required integer)") : 0;
    }
    if (scalar_int(n, out) != 0) {
        return fail(c, RP_CFG_E_TYPE, n, kp, "expected an integer, got %s%s%s", node_kind(n),
                    n->type == YAML_SCALAR_NODE ? " " : "",
                    n->type == YAML_SCALAR_NODE ? scalar(n) : "");
    }
    if (*out < lo || *out > hi) {
        return fail(c, RP_CFG_E_RANGE, n, kp, "%lld is outside %lld..%lld", *out, lo, hi);
    }
    return 0;
}

/* A number in [lo, hi]; lo_open / hi_open make that end exclusive. */
static int get_num(ctx_t *c, const yaml_node_t *map, const char *path, const char *key,
                   int required, double def, double lo, int lo_open, double hi, double *out)
{
    char kp[KEY_MAX];
    key_path(kp, path, key);
    const yaml_node_t *n = map_get(c, map, key);
    if (n == NULL) {
        *out = def;
        return required ? fail(c, RP_CFG_E_MISSING, map, kp, "missing (required number)") : 0;
    }
    if (scalar_num(n, out) != 0) {
        return fail(c, RP_CFG_E_TYPE, n, kp, "expected a finite number, got %s%s%s",
                    node_kind(n), n->type == YAML_SCALAR_NODE ? " " : "",
                    n->type == YAML_SCALAR_NODE ? scalar(n) : "");
    }
    if (*out < lo || (lo_open && *out == lo) || *out > hi) {
        return fail(c, RP_CFG_E_RANGE, n, kp, "%g is outside %s%g, %g]", *out,
                    lo_open ? "(" : "[", lo, hi);
    }
    return 0;
}

static int get_bool(ctx_t *c, const yaml_node_t *map, const char *path, const char *key,
                    int def, uint8_t *out)
{
    char kp[KEY_MAX];
    key_path(kp, path, key);
    const yaml_node_t *n = map_get(c, map, key);
    *out = (uint8_t)def;
    if (n == NULL) {
        return 0;
    }
    if (is_plain_scalar(n) && (strcmp(scalar(n), "true") == 0 || strcmp(scalar(n), "True") == 0)) {
        *out = 1;
        return 0;
    }
    if (is_plain_scalar(n) &&
        (strcmp(scalar(n), "false") == 0 || strcmp(scalar(n), "False") == 0)) {
        *out = 0;
        return 0;
    }
    return fail(c, RP_CFG_E_TYPE, n, kp, "expected true or false");
}

/* A string of 1..cap-1 characters (0..cap-1 if allow_empty). */
static int get_str(ctx_t *c, const yaml_node_t *map, const char *path, const char *key,
                   int required, const char *def, int allow_empty, char *out, size_t cap)
{
    char kp[KEY_MAX];
    key_path(kp, path, key);
    const yaml_node_t *n = map_get(c, map, key);
    if (n == NULL) {
        snprintf(out, cap, "%s", def);
        return required ? fail(c, RP_CFG_E_MISSING, map, kp, "missing (required string)") : 0;
    }
    if (n->type != YAML_SCALAR_NODE) {
        return fail(c, RP_CFG_E_TYPE, n, kp, "expected a string, got %s", node_kind(n));
    }
    if (n->data.scalar.length >= cap) {
        return fail(c, RP_CFG_E_RANGE, n, kp, "longer than %zu characters", cap - 1);
    }
    if (n->data.scalar.length == 0 && !allow_empty) {
        return fail(c, RP_CFG_E_RANGE, n, kp, "must not be empty");
    }
    for (size_t i = 0; i < n->data.scalar.length; ++i) {
        const unsigned char ch = n->data.scalar.value[i];
        if (ch < 0x20 || ch == 0x7f) { /* names, paths and channels get printed and logged */
            return fail(c, RP_CFG_E_RANGE, n, kp,
                        "control character 0x%02x at %zu: '%s' (names, paths and channels are "
                        "printed)", ch, i, scalar(n));
        }
    }
    memcpy(out, scalar(n), n->data.scalar.length);
    out[n->data.scalar.length] = '\0';
    return 0;
}

/* A sequence of exactly n finite numbers. *present = 0 if absent (then out is untouched). */
static int get_nums(ctx_t *c, const yaml_node_t *map, const char *path, const char *key,
                    int required, size_t n, double *out, int *present)
{
    char kp[KEY_MAX];
    key_path(kp, path, key);
    const yaml_node_t *s = map_get(c, map, key);
    *present = s != NULL;
    if (s == NULL) {
        return required ? fail(c, RP_CFG_E_MISSING, map, kp, "missing (required list of %zu numbers)",
                               n)
                        : 0;
    }
    if (s->type != YAML_SEQUENCE_NODE) {
        return fail(c, RP_CFG_E_TYPE, s, kp, "expected a list of %zu numbers, got %s", n,
                    node_kind(s));
    }
    const size_t got = (size_t)(s->data.sequence.items.top - s->data.sequence.items.start);
    if (got != n) {
        return fail(c, RP_CFG_E_TYPE, s, kp, "expected %zu numbers, got %zu", n, got);
    }
    for (size_t i = 0; i < n; ++i) {
        const yaml_node_t *e = node(c, s->data.sequence.items.start[i]);
        if (e == NULL || scalar_num(e, &out[i]) != 0) {
            return fail(c, RP_CFG_E_TYPE, e != NULL ? e : s, kp,
                        "element %zu: expected a finite number", i);
        }
    }
    return 0;
}

/* ---- cameras ------------------------------------------------------------------------------- */

/* Sane intrinsics: fx, fy within these multiples of the larger image side (a horizontal field
 * of view between about 0.6 and 157 degrees), and fy / fx within 1/ASPECT..ASPECT. */
#define RP_CFG_F_MIN 0.1
#define RP_CFG_F_MAX 100.0
#define RP_CFG_ASPECT_MAX 4.0
/* Distortion's local stretch: the singular values of d xd / d xn inside the image within
 * 1/STRETCH..STRETCH (a real lens's radial-tangential model stays well inside; beyond it the
 * model is near a fold, or maps a pixel to a ray several times off the pinhole's). */
#define RP_CFG_STRETCH_MAX 5.0
#define RP_CFG_RAY_STEPS 16   /* samples along each ray from the principal point */
#define RP_CFG_BORDER_PTS 256 /* rays, to points spread along the image border */

/* Point k of n spread evenly along the border of the image [0, w-1] x [0, h-1], clockwise
 * from the top-left corner. */
static void border_point(const rp_camera_t *cam, int k, int n, double uv[2])
{
    const double W = (double)cam->width - 1.0, H = (double)cam->height - 1.0;
    double t = 2.0 * (W + H) * (double)k / (double)n;
    if (t < W) {
        uv[0] = t;
        uv[1] = 0.0;
    } else if ((t -= W) < H) {
        uv[0] = W;
        uv[1] = t;
    } else if ((t -= H) < W) {
        uv[0] = W - t;
        uv[1] = H;
    } else {
        uv[0] = 0.0;
        uv[1] = H - (t - W);
    }
}

/* 1 (and why) if the distortion folds inside the image or stretches it beyond
 * RP_CFG_STRETCH_MAX: along rays from the principal point to RP_CFG_BORDER_PTS points of the
 * border (and the four corners), every sampled pixel must undistort (rp_cam_unproject), its
 * normalised radius must grow along the ray and point the ray's way, and the distortion's
 * Jacobian there must keep its orientation with singular values in 1/STRETCH..STRETCH. */
static int distortion_unusable(const rp_camera_t *cam, char *why, size_t cap)
{
    if (cam->k1 == 0 && cam->k2 == 0 && cam->p1 == 0 && cam->p2 == 0 && cam->k3 == 0) {
        return 0;
    }
    const int n_rays = RP_CFG_BORDER_PTS + 4;
    for (int k = 0; k < n_rays; ++k) {
        double b[2];
        if (k < RP_CFG_BORDER_PTS) {
            border_point(cam, k, RP_CFG_BORDER_PTS, b);
        } else {
            b[0] = (k - RP_CFG_BORDER_PTS) & 1 ? (double)cam->width - 1.0 : 0.0;
            b[1] = (k - RP_CFG_BORDER_PTS) & 2 ? (double)cam->height - 1.0 : 0.0;
        }
        const double cx = (double)cam->cx, cy = (double)cam->cy;
        const double dx = (b[0] - cx) / (double)cam->fx, dy = (b[1] - cy) / (double)cam->fy;
        double r_prev = 0.0;
        for (int s = 1; s <= RP_CFG_RAY_STEPS; ++s) {
            const double t = (double)s / RP_CFG_RAY_STEPS;
            const double u = cx + t * (b[0] - cx), v = cy + t * (b[1] - cy);
            if (fabs(u - cx) + fabs(v - cy) < 1e-9) {
                continue; /* the principal point itself (a corner ray of length 0) */
            }
            const rp_real uv[2] = {(rp_real)u, (rp_real)v};
            rp_real xn[2], xd[2], J[4];
            if (rp_cam_unproject(cam, uv, xn) != RP_OK ||
                rp_cam_distort(cam, xn, xd, J) != RP_OK) {
                snprintf(why, cap, "folds inside the image: pixel (%.0f, %.0f) has no ray "
                         "(the model does not invert there)", u, v);
                return 1;
            }
            const double x = (double)xn[0], y = (double)xn[1];
            const double r = sqrt(x * x + y * y);
            if (!(r > r_prev) || x * dx + y * dy <= 0.0) {
                snprintf(why, cap, "folds inside the image: the rays turn back before pixel "
                         "(%.0f, %.0f)", u, v);
                return 1;
            }
            r_prev = r;
            /* Singular values of the 2x2 J from its Gram matrix's eigenvalues. */
            const double a = (double)J[0], bb = (double)J[1], cc = (double)J[2], d = (double)J[3];
            const double det = a * d - bb * cc;
            const double fro = a * a + bb * bb + cc * cc + d * d;
            const double disc = sqrt(fmax(fro * fro - 4.0 * det * det, 0.0));
            const double s_max = sqrt(0.5 * (fro + disc));
            const double s_min = fabs(det) / fmax(s_max, 1e-300);
            if (!(det > 0.0)) {
                snprintf(why, cap, "folds inside the image at pixel (%.0f, %.0f)", u, v);
                return 1;
            }
            if (s_max > RP_CFG_STRETCH_MAX || s_min < 1.0 / RP_CFG_STRETCH_MAX) {
                const int stretch = s_max > RP_CFG_STRETCH_MAX;
                snprintf(why, cap, "%s the image %.3g times at pixel (%.0f, %.0f) (at most %g: "
                         "no real lens; the model is near a fold or far from the pinhole)",
                         stretch ? "stretches" : "squeezes", stretch ? s_max : 1.0 / s_min, u, v,
                         RP_CFG_STRETCH_MAX);
                return 1;
            }
        }
    }
    return 0;
}

static int parse_camera(ctx_t *c, const yaml_node_t *m, unsigned i, rp_config_t *cfg)
{
    static const char *const known[] = {"name",     "device",   "width",    "height",
                                        "fps",      "intrinsics", "distortion", "position",
                                        "rotation", "angles",   "time_offset_s", NULL};
    char path[KEY_MAX], kp[KEY_MAX];
    snprintf(path, sizeof path, "cameras[%u]", i);
    if (m->type != YAML_MAPPING_NODE) {
        return fail(c, RP_CFG_E_TYPE, m, path, "expected a mapping, got %s", node_kind(m));
    }
    if (check_keys(c, m, path, known) != 0) {
        return -1;
    }
    rp_rig_cam_t *rc = &cfg->rig.cam[i];
    rp_hal_cam_cfg_t *hc = &cfg->hal.cam[i];
    long long w, h, fps;
    double in[4], dist[5] = {0, 0, 0, 0, 0}, pos[3], rot[9], abg[3];
    int have_rot = 0, have_abg = 0, present = 0;
    if (get_str(c, m, path, "name", 1, "", 0, cfg->cam_name[i], RP_CFG_NAME_MAX) ||
        get_str(c, m, path, "device", 1, "", 0, hc->device, sizeof hc->device) ||
        get_int(c, m, path, "width", 1, 0, 16, 4096, &w) ||
        get_int(c, m, path, "height", 1, 0, 16, 4096, &h) ||
        get_int(c, m, path, "fps", 0, 30, 1, 1000, &fps) ||
        get_nums(c, m, path, "intrinsics", 1, 4, in, &present) ||
        get_nums(c, m, path, "distortion", 0, 5, dist, &present) ||
        get_nums(c, m, path, "position", 1, 3, pos, &present) ||
        get_nums(c, m, path, "rotation", 0, 9, rot, &have_rot) ||
        get_nums(c, m, path, "angles", 0, 3, abg, &have_abg) ||
        get_num(c, m, path, "time_offset_s", 0, 0.0, -1.0, 0, 1.0, &cfg->cam_time_offset_s[i])) {
        return -1;
    }
    hc->offset_us = (int64_t)llround(cfg->cam_time_offset_s[i] * 1e6);
    for (unsigned j = 0; j < i; ++j) {
        if (strcmp(cfg->cam_name[j], cfg->cam_name[i]) == 0) {
            key_path(kp, path, "name");
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "name"), kp,
                        "'%s' is already the name of cameras[%u]", cfg->cam_name[i], j);
        }
    }
    key_path(kp, path, "intrinsics");
    const yaml_node_t *n_in = map_get(c, m, "intrinsics");
    const double side = (double)(w > h ? w : h);
    if (!(in[0] >= RP_CFG_F_MIN * side && in[0] <= RP_CFG_F_MAX * side &&
          in[1] >= RP_CFG_F_MIN * side && in[1] <= RP_CFG_F_MAX * side)) {
        return fail(c, RP_CFG_E_RANGE, n_in, kp,
                    "fx, fy (%g, %g) must be in [%g, %g] px (%g to %g times the larger image "
                    "side)", in[0], in[1], RP_CFG_F_MIN * side, RP_CFG_F_MAX * side, RP_CFG_F_MIN,
                    RP_CFG_F_MAX);
    }
    if (!(in[1] >= in[0] / RP_CFG_ASPECT_MAX && in[1] <= in[0] * RP_CFG_ASPECT_MAX)) {
        return fail(c, RP_CFG_E_RANGE, n_in, kp, "fy / fx = %g is outside [1/%g, %g]",
                    in[1] / in[0], RP_CFG_ASPECT_MAX, RP_CFG_ASPECT_MAX);
    }
    if (!(in[2] >= 0.0 && in[2] < (double)w && in[3] >= 0.0 && in[3] < (double)h)) {
        return fail(c, RP_CFG_E_RANGE, n_in, kp, "principal point (%g, %g) outside the %lldx%lld image",
                    in[2], in[3], w, h);
    }
    for (int k = 0; k < 5; ++k) {
        if (fabs(dist[k]) >= 100.0) {
            key_path(kp, path, "distortion");
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "distortion"), kp,
                        "coefficient %d (%g) is not in (-100, 100)", k, dist[k]);
        }
    }
    {
        rp_camera_t cam = rp_cam_pinhole((uint16_t)w, (uint16_t)h, (rp_real)in[0], (rp_real)in[1],
                                         (rp_real)in[2], (rp_real)in[3]);
        cam.k1 = (rp_real)dist[0];
        cam.k2 = (rp_real)dist[1];
        cam.p1 = (rp_real)dist[2];
        cam.p2 = (rp_real)dist[3];
        cam.k3 = (rp_real)dist[4];
        char why[160];
        if (distortion_unusable(&cam, why, sizeof why)) {
            key_path(kp, path, "distortion");
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "distortion"), kp, "%s", why);
        }
    }
    for (int k = 0; k < 3; ++k) {
        if (fabs(pos[k]) >= 100.0) {
            key_path(kp, path, "position");
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "position"), kp,
                        "coordinate %d (%g m) is not in (-100, 100) m", k, pos[k]);
        }
    }
    if (have_rot && have_abg) {
        key_path(kp, path, "angles");
        return fail(c, RP_CFG_E_RANGE, map_get(c, m, "angles"), kp,
                    "give either rotation or angles, not both");
    }
    if (!have_rot && !have_abg) {
        key_path(kp, path, "rotation");
        return fail(c, RP_CFG_E_MISSING, m, kp, "missing (rotation: 9 numbers, or angles: 3)");
    }
    if (have_abg) {
        /* R = Rz(gamma) Ry(beta) Rx(alpha), in double here: the check below is in double. */
        const double ca = cos(abg[0]), sa = sin(abg[0]), cb = cos(abg[1]), sb = sin(abg[1]);
        const double cg = cos(abg[2]), sg = sin(abg[2]);
        const double R[9] = {cg * cb, cg * sb * sa - sg * ca, cg * sb * ca + sg * sa,
                             sg * cb, sg * sb * sa + cg * ca, sg * sb * ca - cg * sa,
                             -sb,     cb * sa,                cb * ca};
        memcpy(rot, R, sizeof R);
    } else {
        double worst = 0.0;
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) {
                double d = 0.0;
                for (int k = 0; k < 3; ++k) {
                    d += rot[3 * k + a] * rot[3 * k + b];
                }
                worst = fmax(worst, fabs(d - (a == b ? 1.0 : 0.0)));
            }
        }
        const double det = rot[0] * (rot[4] * rot[8] - rot[5] * rot[7]) -
                           rot[1] * (rot[3] * rot[8] - rot[5] * rot[6]) +
                           rot[2] * (rot[3] * rot[7] - rot[4] * rot[6]);
        if (worst > 1e-6 || det < 0.0) {
            key_path(kp, path, "rotation");
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "rotation"), kp,
                        "not a rotation (R^T R off the identity by %.2g, det %.6g)", worst, det);
        }
    }
    if (i == 0) {
        double off = fabs(pos[0]) + fabs(pos[1]) + fabs(pos[2]);
        for (int k = 0; k < 9; ++k) {
            off += fabs(rot[k] - ((k % 4) == 0 ? 1.0 : 0.0));
        }
        if (off > 1e-9) {
            return fail(c, RP_CFG_E_RANGE, m, path,
                        "the first camera is the reference (cam1): position [0, 0, 0] and the "
                        "identity rotation");
        }
    }
    for (int k = 0; k < 9; ++k) {
        rc->R[k] = (rp_real)rot[k];
    }
    rp_rot_orthonormalize(rc->R);
    for (int k = 0; k < 3; ++k) {
        rc->D[k] = (rp_real)pos[k];
    }
    rc->cam = rp_cam_pinhole((uint16_t)w, (uint16_t)h, (rp_real)in[0], (rp_real)in[1],
                             (rp_real)in[2], (rp_real)in[3]);
    rc->cam.k1 = (rp_real)dist[0];
    rc->cam.k2 = (rp_real)dist[1];
    rc->cam.p1 = (rp_real)dist[2];
    rc->cam.p2 = (rp_real)dist[3];
    rc->cam.k3 = (rp_real)dist[4];
    hc->w = (uint16_t)w;
    hc->h = (uint16_t)h;
    hc->fps = (uint16_t)fps;
    return 0;
}

static int parse_cameras(ctx_t *c, const yaml_node_t *root, rp_config_t *cfg)
{
    const yaml_node_t *s = map_get(c, root, "cameras");
    if (s == NULL) {
        return fail(c, RP_CFG_E_MISSING, root, "cameras", "missing (required list of cameras)");
    }
    if (s->type != YAML_SEQUENCE_NODE) {
        return fail(c, RP_CFG_E_TYPE, s, "cameras", "expected a list of cameras, got %s",
                    node_kind(s));
    }
    const long n = (long)(s->data.sequence.items.top - s->data.sequence.items.start);
    if (n < 1 || n > RP_MAX_CAMS) {
        return fail(c, RP_CFG_E_RANGE, s, "cameras", "%ld cameras; this build takes 1..%d", n,
                    RP_MAX_CAMS);
    }
    cfg->rig.n_cams = (uint8_t)n;
    cfg->hal.n_cams = (uint8_t)n;
    for (long i = 0; i < n; ++i) {
        if (parse_camera(c, node(c, s->data.sequence.items.start[i]), (unsigned)i, cfg) != 0) {
            return -1;
        }
    }
    if (rp_rig_check(&cfg->rig) != RP_OK) {
        return fail(c, RP_CFG_E_RANGE, s, "cameras", "the rig is not usable (rp_rig_check)");
    }
    return 0;
}

/* ---- source -------------------------------------------------------------------------------- */

/* replay_index relative to the configuration file's folder. */
static int resolve_path(ctx_t *c, const yaml_node_t *at, const char *rel, char *out, size_t cap)
{
    const char *slash = strrchr(c->file, '/');
    int n;
    if (rel[0] == '/' || slash == NULL) {
        n = snprintf(out, cap, "%s", rel);
    } else {
        n = snprintf(out, cap, "%.*s/%s", (int)(slash - c->file), c->file, rel);
    }
    if (n < 0 || (size_t)n >= cap) {
        return fail(c, RP_CFG_E_RANGE, at, "source.replay_index", "path longer than %zu characters",
                    cap - 1);
    }
    return 0;
}

/* source.realtime: true / false, or live (RP_HAL_PACE_*). */
static int get_pace(ctx_t *c, const yaml_node_t *m, uint8_t *out)
{
    const yaml_node_t *n = map_get(c, m, "realtime");
    if (n != NULL && is_plain_scalar(n) && strcmp(scalar(n), "live") == 0) {
        *out = RP_HAL_PACE_LIVE;
        return 0;
    }
    if (n != NULL && n->type == YAML_SCALAR_NODE && !(is_plain_scalar(n) &&
        (strcmp(scalar(n), "true") == 0 || strcmp(scalar(n), "True") == 0 ||
         strcmp(scalar(n), "false") == 0 || strcmp(scalar(n), "False") == 0))) {
        return fail(c, RP_CFG_E_TYPE, n, "source.realtime", "expected true, false or live");
    }
    return get_bool(c, m, "source", "realtime", 0, out);
}

static int parse_source(ctx_t *c, const yaml_node_t *root, rp_config_t *cfg)
{
    static const char *const known[] = {"kind",     "timeout_ms",   "sync_tol_us", "retry_ms",
                                        "realtime", "replay_index", "sim",         "sets",
                                        "set_camera", NULL};
    static const char *const sim_known[] = {"seed", "frames", "noise_px", "drop_cam",
                                            "drop_from", "motion", NULL};
    yaml_node_t *m, *sm;
    char kind[16], rel[RP_HAL_PATH_MAX], motion[16] = "paper", sets[16] = "matched";
    char set_cam[RP_CFG_NAME_MAX] = "";
    long long to, tol, retry, seed, frames, drop_cam, drop_from;
    if (get_map(c, root, "", "source", 1, &m) ||
        check_keys(c, m, "source", known) ||
        get_str(c, m, "source", "kind", 1, "", 0, kind, sizeof kind) ||
        get_int(c, m, "source", "timeout_ms", 0, 1000, 1, 60000, &to) ||
        get_int(c, m, "source", "sync_tol_us", 0, 5000, 0, 1000000, &tol) ||
        get_int(c, m, "source", "retry_ms", 0, 1000, 10, 60000, &retry) ||
        get_pace(c, m, &cfg->hal.realtime) ||
        get_str(c, m, "source", "replay_index", 0, "", 0, rel, sizeof rel) ||
        get_str(c, m, "source", "sets", 0, "matched", 0, sets, sizeof sets) ||
        get_str(c, m, "source", "set_camera", 0, "", 0, set_cam, sizeof set_cam) ||
        get_map(c, m, "source", "sim", 0, &sm)) {
        return -1;
    }
    if (strcmp(kind, "sim") == 0) {
        cfg->hal.kind = RP_HAL_SRC_SIM;
    } else if (strcmp(kind, "v4l2") == 0) {
        cfg->hal.kind = RP_HAL_SRC_V4L2;
    } else if (strcmp(kind, "replay") == 0) {
        cfg->hal.kind = RP_HAL_SRC_REPLAY;
    } else if (strcmp(kind, "lcm") == 0) {
        cfg->hal.kind = RP_HAL_SRC_LCM;
    } else {
        return fail(c, RP_CFG_E_RANGE, map_get(c, m, "kind"), "source.kind",
                    "'%s' is not one of sim, v4l2, replay, lcm", kind);
    }
    cfg->hal.timeout_ms = (uint32_t)to;
    cfg->hal.sync_tol_us = tol;
    /* sets: matched (frames within sync_tol_us) or latest (free-running cameras: a set per
     * frame of set_camera, the first camera by default, or of any camera) */
    if (strcmp(sets, "matched") == 0 || strcmp(sets, "latest") == 0) {
        cfg->hal.sets_latest = (uint8_t)(sets[0] == 'l');
    } else {
        return fail(c, RP_CFG_E_RANGE, map_get(c, m, "sets"), "source.sets",
                    "'%s' is not one of matched, latest", sets);
    }
    cfg->hal.set_cam = 0;
    if (set_cam[0] != '\0') {
        if (!cfg->hal.sets_latest) {
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "set_camera"), "source.set_camera",
                        "only with sets: latest");
        }
        cfg->hal.set_cam = -2;
        if (strcmp(set_cam, "any") == 0) {
            cfg->hal.set_cam = -1;
        }
        for (uint8_t j = 0; j < cfg->rig.n_cams && cfg->hal.set_cam == -2; ++j) {
            if (strcmp(cfg->cam_name[j], set_cam) == 0) {
                cfg->hal.set_cam = (int8_t)j;
            }
        }
        if (cfg->hal.set_cam == -2) {
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "set_camera"), "source.set_camera",
                        "no camera is named '%s' (or give any)", set_cam);
        }
    }
    cfg->hal.retry_ms = (uint32_t)retry;
    if (cfg->hal.kind == RP_HAL_SRC_REPLAY) {
        if (rel[0] == '\0') {
            return fail(c, RP_CFG_E_MISSING, m, "source.replay_index",
                        "missing (required with kind: replay)");
        }
        if (resolve_path(c, map_get(c, m, "replay_index"), rel, cfg->hal.replay_index,
                         sizeof cfg->hal.replay_index) != 0) {
            return -1;
        }
    }
    const int n = cfg->rig.n_cams;
    if (sm == NULL) {
        seed = 1;
        frames = 0;
        cfg->sim.noise_px = 0.5;
        drop_cam = -1;
        drop_from = 0;
    } else if (check_keys(c, sm, "source.sim", sim_known) ||
               get_str(c, sm, "source.sim", "motion", 0, "paper", 0, motion, sizeof motion) ||
               get_int(c, sm, "source.sim", "seed", 0, 1, 0, 4294967295LL, &seed) ||
               get_int(c, sm, "source.sim", "frames", 0, 0, 0, 100000, &frames) ||
               get_num(c, sm, "source.sim", "noise_px", 0, 0.5, 0.0, 0, 10.0, &cfg->sim.noise_px) ||
               get_int(c, sm, "source.sim", "drop_cam", 0, -1, -1, n - 1, &drop_cam) ||
               get_int(c, sm, "source.sim", "drop_from", 0, 0, 0, 4294967295LL, &drop_from)) {
        return -1;
    }
    cfg->sim.seed = (uint32_t)seed;
    cfg->sim.frames = (uint32_t)frames;
    cfg->sim.drop_cam = (int16_t)drop_cam;
    cfg->sim.drop_from = (uint32_t)drop_from;
    static const char *const motions[] = {"paper", "turn", "pitch", "smooth"}; /* rp_sim.h */
    cfg->sim.motion = -1;
    for (int8_t mi = 0; mi < (int8_t)(sizeof motions / sizeof motions[0]); ++mi) {
        if (strcmp(motion, motions[mi]) == 0) {
            cfg->sim.motion = mi;
        }
    }
    if (cfg->sim.motion < 0) {
        return fail(c, RP_CFG_E_RANGE, map_get(c, sm, "motion"), "source.sim.motion",
                    "'%s' is not one of paper, turn, pitch, smooth", motion);
    }
    cfg->hal.sim_seed = cfg->sim.seed;
    cfg->hal.sim_frames = cfg->sim.frames;

    const yaml_node_t *cams = map_get(c, root, "cameras");
    if (cfg->hal.kind == RP_HAL_SRC_SIM && n != 6) {
        return fail(c, RP_CFG_E_RANGE, cams, "cameras",
                    "the sim source simulates the protocol's 6 cameras (cam1, cam2, cam3, cam4, "
                    "cam1b, cam3b); %d given",
                    n);
    }
    if (cfg->hal.kind != RP_HAL_SRC_SIM) {
        for (int i = 0; i < n; ++i) {
            if (cfg->hal.cam[i].w > RP_TRACK_MAX_W || cfg->hal.cam[i].h > RP_TRACK_MAX_H) {
                char kp[KEY_MAX];
                snprintf(kp, sizeof kp, "cameras[%d].width", i);
                return fail(c, RP_CFG_E_RANGE, node(c, cams->data.sequence.items.start[i]), kp,
                            "%ux%u is larger than this build's tracker takes (%dx%d)",
                            cfg->hal.cam[i].w, cfg->hal.cam[i].h, RP_TRACK_MAX_W, RP_TRACK_MAX_H);
            }
        }
    }
    return 0;
}

/* ---- estimator ----------------------------------------------------------------------------- */

/* Camera index of the name in scalar node n. */
static int cam_index(ctx_t *c, const rp_config_t *cfg, const yaml_node_t *n, const char *kp,
                     uint8_t *idx)
{
    if (n == NULL || n->type != YAML_SCALAR_NODE) {
        return fail(c, RP_CFG_E_TYPE, n, kp, "expected a camera name");
    }
    for (uint8_t k = 0; k < cfg->rig.n_cams; ++k) {
        if (strcmp(cfg->cam_name[k], scalar(n)) == 0) {
            *idx = k;
            return 0;
        }
    }
    return fail(c, RP_CFG_E_RANGE, n, kp, "no camera is named '%s'", scalar(n));
}

/* A list of camera names (sequence node s) into idx[]; lengths lo..hi; all distinct from each
 * other and from taken[] (a camera in two pairs). */
static int name_list(ctx_t *c, const rp_config_t *cfg, const yaml_node_t *s, const char *kp,
                     size_t lo, size_t hi, uint8_t *idx, size_t *n_out, uint8_t *taken)
{
    if (s->type != YAML_SEQUENCE_NODE) {
        return fail(c, RP_CFG_E_TYPE, s, kp, "expected a list of camera names, got %s",
                    node_kind(s));
    }
    const size_t n = (size_t)(s->data.sequence.items.top - s->data.sequence.items.start);
    if (n < lo || n > hi) {
        return fail(c, RP_CFG_E_TYPE, s, kp, "expected %zu..%zu camera names, got %zu", lo, hi, n);
    }
    for (size_t i = 0; i < n; ++i) {
        const yaml_node_t *e = node(c, s->data.sequence.items.start[i]);
        if (cam_index(c, cfg, e, kp, &idx[i]) != 0) {
            return -1;
        }
        if (taken[idx[i]]) {
            return fail(c, RP_CFG_E_RANGE, e, kp, "camera '%s' is used twice", scalar(e));
        }
        taken[idx[i]] = 1;
    }
    *n_out = n;
    return 0;
}

/* The estimator's keys with one value each: every one overrides, where the file gives it, the
 * fields of the core's default configuration it names (the same setting of the stereo, gc and
 * mono estimators; only the layout's own estimator runs). No defaults here: absent keys keep
 * rp_pipe_default_cfg's values. */
typedef enum { K_REAL, K_U8, K_U16, K_BOOL } key_type_t;
typedef struct {
    const char *key;
    key_type_t type;
    double lo, hi;    /* range; integers and numbers */
    uint8_t lo_open;  /* numbers: lo excluded */
    uint8_t n;        /* fields set */
    size_t off[3];    /* offsets of the fields in rp_pipe_cfg_t */
} est_key_t;

#define F(member) offsetof(rp_pipe_cfg_t, member)
#define ALL3(member) 3, {F(stereo.member), F(gc.member), F(mono.member)}
static const est_key_t est_keys[] = {
    {"sigma_px", K_REAL, 0.0, 100.0, 1, ALL3(ekf.sigma_px)},
    {"q_trans", K_REAL, 0.0, 1e6, 0, ALL3(ekf.q_trans)},
    {"q_rot", K_REAL, 0.0, 1e6, 0, ALL3(ekf.q_rot)},
    {"gate_chi2", K_REAL, -1e6, 1e6, 0, ALL3(ekf.gate_chi2)},
    {"iterations", K_U8, 1, 20, 0, ALL3(ekf.iterations)},
    {"min_features", K_U16, 3, RP_MAX_FEATS_PER_CAM, 0, ALL3(ekf.min_features)},
    {"max_predict_s", K_REAL, 0.0, 1e6, 1, ALL3(ekf.max_predict_s)},
    {"min_tracked", K_U16, 6, RP_MAX_FEATS_PER_CAM, 0, ALL3(min_tracked)},
    {"default_dt_s", K_REAL, 0.0, 10.0, 1, ALL3(default_dt_s)},
    {"max_epipolar_px", K_REAL, 0.0, 100.0, 1, 1, {F(stereo.max_epipolar_px)}},
    {"min_depth_m", K_REAL, 0.0, 1e6, 1, 1, {F(stereo.min_depth_m)}},
    {"max_depth_m", K_REAL, 0.0, 1e6, 1, 1, {F(stereo.max_depth_m)}},
    {"max_reproj_px", K_REAL, 0.0, 100.0, 1, 1, {F(stereo.max_reproj_px)}},
    {"max_pair_skew_s", K_REAL, 0.0, 1.0, 0, 1, {F(stereo.max_pair_skew_s)}},
    {"refine_structure", K_BOOL, 0, 1, 0, 1, {F(stereo.refine_structure)}},
    {"ransac", K_BOOL, 0, 1, 0, ALL3(ransac)},
    {"one_point", K_BOOL, 0, 1, 0, ALL3(one_point)},
    {"drop_odds", K_REAL, 1.0, 1e12, 1, 1, {F(stereo.drop_odds)}},
    {"retry_triangulation", K_BOOL, 0, 1, 0, 1, {F(stereo.retry_triangulation)}},
    {"retire_outliers", K_BOOL, 0, 1, 0, 1, {F(stereo.retire_outliers)}},
    {"add_landmarks", K_BOOL, 0, 1, 0, 1, {F(stereo.add_landmarks)}},
    {"dormant_retired", K_BOOL, 0, 1, 0, 1, {F(dormant_retired)}},
    {"init_depth_m", K_REAL, 0.0, 1e4, 1, 2, {F(gc.init_depth_m), F(mono.init_depth_m)}},
    {"init_depth_sigma_m", K_REAL, 0.0, 1e4, 1, 2,
     {F(gc.init_depth_sigma_m), F(mono.init_depth_sigma_m)}},
    {"init_on_sphere", K_BOOL, 0, 1, 0, 1, {F(gc.init_on_sphere)}},
    {"metric_scale_sigma", K_REAL, 0.0, 10.0, 0, 1, {F(gc.mscale_sigma)}},
    {"estimate_time_offsets", K_BOOL, 0, 1, 0, ALL3(ekf.toff_estimate)},
    {"time_offset_sigma_s", K_REAL, 0.0, 1.0, 1, ALL3(ekf.toff_sigma_s)},
    {"time_offset_q", K_REAL, 0.0, 1.0, 0, ALL3(ekf.toff_q)},
    {"time_jitter_s", K_REAL, 0.0, 1.0, 0, ALL3(ekf.time_jitter_s)},
    {"group_time_noise", K_BOOL, 0, 1, 0, ALL3(ekf.group_time_noise)},
};
#undef ALL3
#undef F
#define N_EST_KEYS (sizeof est_keys / sizeof est_keys[0])

/* Key k of mapping m, if given, into its fields of pipe. */
static int set_est_key(ctx_t *c, const yaml_node_t *m, const char *P, const est_key_t *k,
                       rp_pipe_cfg_t *pipe)
{
    if (map_get(c, m, k->key) == NULL) {
        return 0;
    }
    double v = 0.0;
    long long i = 0;
    uint8_t b = 0;
    if ((k->type == K_REAL && get_num(c, m, P, k->key, 1, 0.0, k->lo, k->lo_open, k->hi, &v)) ||
        ((k->type == K_U8 || k->type == K_U16) &&
         get_int(c, m, P, k->key, 1, 0, (long long)k->lo, (long long)k->hi, &i)) ||
        (k->type == K_BOOL && get_bool(c, m, P, k->key, 0, &b))) {
        return -1;
    }
    for (uint8_t f = 0; f < k->n; ++f) {
        unsigned char *at = (unsigned char *)pipe + k->off[f];
        switch (k->type) {
        case K_REAL: *(rp_real *)(void *)at = (rp_real)v; break;
        case K_U8: *at = (uint8_t)i; break;
        case K_U16: *(uint16_t *)(void *)at = (uint16_t)i; break;
        case K_BOOL: *at = b; break;
        }
    }
    return 0;
}

static int parse_estimator(ctx_t *c, const yaml_node_t *root, rp_config_t *cfg)
{
    static const char *const known[] = {
        "method",      "pairs",        "cams",          "sigma_px",         "q_trans",
        "q_rot",       "gate_chi2",    "iterations",    "min_features",     "min_tracked",
        "max_epipolar_px", "min_depth_m", "max_depth_m", "max_reproj_px",   "refine_structure",
        "ransac",      "one_point",    "drop_odds",     "retry_triangulation", "retire_outliers",
        "dormant_retired", "add_landmarks",
        "init_depth_m", "init_depth_sigma_m", "init_on_sphere", "default_dt_s",
        "metric_scale_sigma", "max_predict_s", "estimate_time_offsets", "time_offset_sigma_s",
        "time_offset_q", "max_pair_skew_s", "time_jitter_s", "group_time_noise", NULL};
    const char *P = "estimator";
    yaml_node_t *m;
    char method[16];
    rp_pipe_layout_t layout;
    if (get_map(c, root, "", "estimator", 1, &m) || check_keys(c, m, P, known) ||
        get_str(c, m, P, "method", 1, "", 0, method, sizeof method)) {
        return -1;
    }
    if (rp_pipe_layout_from_name(method, &layout) != RP_OK) {
        char names[128];
        size_t len = 0;
        for (int l = 0; l < RP_PIPE_LAYOUT_COUNT_ && len < sizeof names; ++l) {
            len += (size_t)snprintf(names + len, sizeof names - len, "%s%s", l ? ", " : "",
                                    rp_pipe_layout_name((rp_pipe_layout_t)l));
        }
        return fail(c, RP_CFG_E_RANGE, map_get(c, m, "method"), "estimator.method",
                    "'%s' is not one of %s", method, names);
    }
    rp_pipe_cfg_t *pc = &cfg->pipe;
    /* ignored: cannot fail: a layout the parser has just checked */
    (void)rp_pipe_default_cfg(layout, pc);
    for (size_t k = 0; k < N_EST_KEYS; ++k) {
        if (set_est_key(c, m, P, &est_keys[k], pc) != 0) {
            return -1;
        }
    }
    /* each camera's configured clock offset (cameras[i].time_offset_s) */
    for (unsigned i = 0; i < RP_MAX_CAMS; ++i) {
        const rp_real o = (rp_real)cfg->cam_time_offset_s[i];
        pc->stereo.ekf.toff0_s[i] = pc->gc.ekf.toff0_s[i] = pc->mono.ekf.toff0_s[i] = o;
    }
    if (pc->stereo.min_depth_m >= pc->stereo.max_depth_m) {
        const yaml_node_t *at = map_get(c, m, "max_depth_m");
        return at != NULL ? fail(c, RP_CFG_E_RANGE, at, "estimator.max_depth_m",
                                 "must be larger than min_depth_m (%g)",
                                 (double)pc->stereo.min_depth_m)
                          : fail(c, RP_CFG_E_RANGE, map_get(c, m, "min_depth_m"),
                                 "estimator.min_depth_m", "must be smaller than max_depth_m (%g)",
                                 (double)pc->stereo.max_depth_m);
    }

    uint8_t taken[RP_MAX_CAMS] = {0};
    uint8_t idx[RP_MAX_CAMS];
    size_t n = 0;
    const yaml_node_t *pairs = map_get(c, m, "pairs");
    const yaml_node_t *cams = map_get(c, m, "cams");
    const int stereo = layout == RP_PIPE_STEREO4 || layout == RP_PIPE_STEREO2;
    if (stereo) {
        const size_t want = pc->stereo.n_pairs;
        if (pairs == NULL) {
            return fail(c, RP_CFG_E_MISSING, m, "estimator.pairs",
                        "missing (method %s needs %zu stereo pair%s)", method, want,
                        want > 1 ? "s" : "");
        }
        if (pairs->type != YAML_SEQUENCE_NODE ||
            (size_t)(pairs->data.sequence.items.top - pairs->data.sequence.items.start) != want) {
            return fail(c, RP_CFG_E_TYPE, pairs, "estimator.pairs",
                        "expected a list of %zu pair%s [left, right]", want, want > 1 ? "s" : "");
        }
        for (size_t p = 0; p < want; ++p) {
            char kp[KEY_MAX];
            snprintf(kp, sizeof kp, "estimator.pairs[%zu]", p);
            if (name_list(c, cfg, node(c, pairs->data.sequence.items.start[p]), kp, 2, 2, idx,
                          &n, taken) != 0) {
                return -1;
            }
            pc->stereo.pair_a[p] = idx[0];
            pc->stereo.pair_b[p] = idx[1];
        }
    } else if (layout == RP_PIPE_GC) {
        if (cams == NULL) {
            return fail(c, RP_CFG_E_MISSING, m, "estimator.cams",
                        "missing (method gc needs its list of single cameras)");
        }
        if (name_list(c, cfg, cams, "estimator.cams", 1, RP_MAX_CAMS, idx, &n, taken) != 0) {
            return -1;
        }
        memset(pc->gc.cams, 0, sizeof pc->gc.cams);
        pc->gc.n_cams = (uint8_t)n;
        memcpy(pc->gc.cams, idx, n);
    } else {
        /* cam1..cam4 and rc: by default the cameras named cam1..cam4. */
        static const char *const defaults[4] = {"cam1", "cam2", "cam3", "cam4"};
        const size_t want = layout == RP_PIPE_RC ? RP_RC_MAX_CAMS : 1;
        const size_t first = layout == RP_PIPE_RC ? 0 : (size_t)(layout - RP_PIPE_CAM1);
        if (cams != NULL) {
            /* rc: 2..RP_RC_MAX_CAMS cameras, the first the reference */
            if (name_list(c, cfg, cams, "estimator.cams", layout == RP_PIPE_RC ? 2 : want, want,
                          idx, &n, taken) != 0) {
                return -1;
            }
        } else {
            n = want;
            for (size_t k = 0; k < want; ++k) {
                int found = 0;
                for (uint8_t j = 0; j < cfg->rig.n_cams; ++j) {
                    if (strcmp(cfg->cam_name[j], defaults[first + k]) == 0) {
                        idx[k] = j;
                        found = 1;
                    }
                }
                if (!found) {
                    return fail(c, RP_CFG_E_MISSING, m, "estimator.cams",
                                "missing, and no camera is named '%s' (method %s)",
                                defaults[first + k], method);
                }
            }
        }
        if (layout == RP_PIPE_RC) {
            memset(pc->rc_cams, 0, sizeof pc->rc_cams);
            memcpy(pc->rc_cams, idx, n);
            pc->rc_n = (uint8_t)n;
        } else {
            pc->mono.cam = idx[0];
        }
    }
    cfg->hal.sim_layout = (uint8_t)(stereo ? 0 : 1);
    return 0;
}

/* ---- tracker, lcm ---------------------------------------------------------------------------- */

/* The tracker's keys override, where given, the core's defaults in cfg->pipe.track (set with
 * the layout by parse_estimator). */
static int parse_tracker(ctx_t *c, const yaml_node_t *root, rp_config_t *cfg)
{
    static const char *const known[] = {"target", "levels", "win", "min_dist",
                                        "fb_max_px", "grid", "reset_share", NULL};
    const char *P = "tracker";
    rp_track_cfg_t *t = &cfg->pipe.track;
    yaml_node_t *m;
    if (get_map(c, root, "", "tracker", 0, &m) != 0) {
        return -1;
    }
    if (m == NULL) {
        return 0;
    }
    long long v;
    double x, grid[2];
    int present;
    if (check_keys(c, m, P, known)) {
        return -1;
    }
    if (map_get(c, m, "target") != NULL) {
        if (get_int(c, m, P, "target", 1, 0, 8, RP_MAX_FEATS_PER_CAM, &v)) {
            return -1;
        }
        t->target = (uint16_t)v;
        t->topup_below = (uint16_t)(t->target * 4 / 5); /* rp_track_default_cfg's share */
    }
    if (map_get(c, m, "levels") != NULL) {
        if (get_int(c, m, P, "levels", 1, 0, 1, RP_TRACK_MAX_LEVELS, &v)) {
            return -1;
        }
        t->levels = (uint8_t)v;
    }
    if (map_get(c, m, "win") != NULL) {
        if (get_int(c, m, P, "win", 1, 0, 5, RP_TRACK_MAX_WIN, &v)) {
            return -1;
        }
        if ((v & 1) == 0) {
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "win"), "tracker.win", "%lld is even", v);
        }
        t->win = (uint8_t)v;
    }
    if (map_get(c, m, "min_dist") != NULL) {
        if (get_int(c, m, P, "min_dist", 1, 0, 1, 1000, &v)) {
            return -1;
        }
        t->min_dist = (uint16_t)v;
    }
    if (map_get(c, m, "fb_max_px") != NULL) {
        if (get_num(c, m, P, "fb_max_px", 1, 0.0, 0.0, 0, 100.0, &x)) {
            return -1;
        }
        t->fb_max_q16 = (uint32_t)lround(x * 65536.0);
    }
    if (get_nums(c, m, P, "grid", 0, 2, grid, &present)) {
        return -1;
    }
    if (present) {
        if (grid[0] < 1 || grid[1] < 1 || grid[0] != floor(grid[0]) ||
            grid[1] != floor(grid[1]) || grid[0] * grid[1] > RP_TRACK_MAX_CELLS) {
            return fail(c, RP_CFG_E_RANGE, map_get(c, m, "grid"), "tracker.grid",
                        "two positive integers with a product <= %d", RP_TRACK_MAX_CELLS);
        }
        t->grid_x = (uint8_t)grid[0];
        t->grid_y = (uint8_t)grid[1];
    }
    if (map_get(c, m, "reset_share") != NULL) {
        if (get_num(c, m, P, "reset_share", 1, 0.0, 0.0, 0, 0.99, &x)) {
            return -1;
        }
        t->reset_q8 = (uint8_t)lround(x * 256.0);
    }
    return 0;
}

static int parse_lcm(ctx_t *c, const yaml_node_t *root, rp_config_t *cfg)
{
    static const char *const known[] = {"url", "pose_channel", "status_channel", "status_every",
                                        "image_channel", "instance", "features_channel",
                                        NULL};
    const char *P = "lcm";
    static const yaml_node_t none = {.type = YAML_MAPPING_NODE};
    yaml_node_t *m;
    long long every;
    if (get_map(c, root, "", "lcm", 0, &m) != 0) {
        return -1;
    }
    const yaml_node_t *mm = m != NULL ? m : &none;
    if ((m != NULL && check_keys(c, m, P, known)) ||
        get_str(c, mm, P, "url", 0, "udpm://239.255.76.67:7667?ttl=0", 0, cfg->lcm_url,
                sizeof cfg->lcm_url) ||
        get_str(c, mm, P, "pose_channel", 0, "RIGPOSE_POSE", 0, cfg->pose_channel,
                sizeof cfg->pose_channel) ||
        get_str(c, mm, P, "status_channel", 0, "RIGPOSE_STATUS", 0, cfg->status_channel,
                sizeof cfg->status_channel) ||
        get_str(c, mm, P, "image_channel", 0, "", 1, cfg->image_channel,
                sizeof cfg->image_channel) ||
        get_str(c, mm, P, "instance", 0, "", 1, cfg->instance, sizeof cfg->instance) ||
        get_str(c, mm, P, "features_channel", 0, "RIGPOSE_FEATURES_CAM", 0,
                cfg->features_channel, sizeof cfg->features_channel - 1) ||
        get_int(c, mm, P, "status_every", 0, 1, 1, 10000, &every)) {
        return -1;
    }
    cfg->status_every = (uint32_t)every;
    return 0;
}

/* ---- entry points ---------------------------------------------------------------------------- */

static rp_cfg_status_t parse_doc(ctx_t *c, rp_config_t *cfg)
{
    static const char *const known[] = {"version", "source", "cameras", "estimator",
                                        "tracker", "lcm",    "meta",    "threads", NULL};
    const yaml_node_t *root = yaml_document_get_root_node(c->doc);
    if (root == NULL) {
        /* ignored: it returns the status it was given: here only the message is wanted */
        (void)fail(c, RP_CFG_E_SYNTAX, NULL, "(top)", "empty file");
        return c->st;
    }
    if (root->type != YAML_MAPPING_NODE) {
        /* ignored: it returns the status it was given: here only the message is wanted */
        (void)fail(c, RP_CFG_E_SYNTAX, root, "(top)", "expected a mapping, got %s",
                   node_kind(root));
        return c->st;
    }
    long long version, threads;
    if (check_keys(c, root, "", known) || get_int(c, root, "", "version", 1, 0, 1, 1, &version) ||
        get_int(c, root, "", "threads", 0, 0, 0, RP_POOL_MAX_THREADS, &threads) ||
        parse_cameras(c, root, cfg) || parse_source(c, root, cfg) ||
        parse_estimator(c, root, cfg) || parse_tracker(c, root, cfg) || parse_lcm(c, root, cfg)) {
        return c->st;
    }
    cfg->threads = (uint8_t)threads;
    return RP_CFG_OK;
}

static rp_cfg_status_t yaml_error(const yaml_parser_t *parser, const char *text, size_t len,
                                  const char *name, char *err, size_t err_len)
{
    if (parser->error == YAML_READER_ERROR) { /* bad encoding: libyaml gives a byte offset */
        const size_t at = parser->problem_offset < len ? parser->problem_offset : len;
        unsigned long line = 1;
        for (size_t i = 0; i < at; ++i) {
            line += text[i] == '\n';
        }
        set_err(err, err_len, "%s:%lu: (yaml): %s at byte %zu", name, line,
                parser->problem ? parser->problem : "unreadable text", at);
        return RP_CFG_E_SYNTAX;
    }
    set_err(err, err_len, "%s:%lu: (yaml): %s%s%s", name,
            (unsigned long)parser->problem_mark.line + 1u,
            parser->problem ? parser->problem : "syntax error", parser->context ? " " : "",
            parser->context ? parser->context : "");
    return RP_CFG_E_SYNTAX;
}

/* The first pass, over libyaml's events only (no document built, so it stops early and cheap):
 * nesting at most RP_CFG_MAX_DEPTH, at most RP_CFG_MAX_NODES nodes, one document. */
static rp_cfg_status_t check_stream(const char *text, size_t len, const char *name, char *err,
                                    size_t err_len)
{
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser)) {
        return RP_CFG_E_ARG;
    }
    yaml_parser_set_input_string(&parser, (const unsigned char *)text, len);
    rp_cfg_status_t st = RP_CFG_OK;
    int depth = 0, docs = 0, done = 0;
    long nodes = 0;
    while (!done && st == RP_CFG_OK) {
        yaml_event_t e;
        if (!yaml_parser_parse(&parser, &e)) {
            st = yaml_error(&parser, text, len, name, err, err_len);
            break;
        }
        const unsigned long line = (unsigned long)e.start_mark.line + 1u;
        switch (e.type) {
        case YAML_SEQUENCE_START_EVENT:
        case YAML_MAPPING_START_EVENT:
            if (++depth > RP_CFG_MAX_DEPTH) {
                set_err(err, err_len, "%s:%lu: (yaml): nested deeper than %d levels", name, line,
                        RP_CFG_MAX_DEPTH);
                st = RP_CFG_E_SYNTAX;
            }
            break;
        case YAML_SEQUENCE_END_EVENT:
        case YAML_MAPPING_END_EVENT: --depth; break;
        default: break;
        }
        switch (e.type) {
        case YAML_SCALAR_EVENT:
        case YAML_ALIAS_EVENT:
        case YAML_SEQUENCE_START_EVENT:
        case YAML_MAPPING_START_EVENT:
            if (st == RP_CFG_OK && ++nodes > RP_CFG_MAX_NODES) {
                set_err(err, err_len, "%s:%lu: (yaml): more than %d nodes", name, line,
                        RP_CFG_MAX_NODES);
                st = RP_CFG_E_SYNTAX;
            }
            break;
        case YAML_DOCUMENT_START_EVENT:
            if (++docs > 1) {
                set_err(err, err_len, "%s:%lu: (yaml): a second document; a configuration is "
                        "one document", name, line);
                st = RP_CFG_E_SYNTAX;
            }
            break;
        case YAML_STREAM_END_EVENT: done = 1; break;
        default: break;
        }
        yaml_event_delete(&e);
    }
    yaml_parser_delete(&parser);
    return st;
}

rp_cfg_status_t rp_config_parse(const char *text, size_t len, const char *name, rp_config_t *cfg,
                                char *err, size_t err_len)
{
    if (err != NULL && err_len > 0) {
        err[0] = '\0';
    }
    if (text == NULL || cfg == NULL) {
        return RP_CFG_E_ARG;
    }
    name = name != NULL ? name : "(string)";
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->path, sizeof cfg->path, "%s", name);
    if (len > RP_CFG_MAX_BYTES) {
        set_err(err, err_len, "%s:0: (file): larger than %d bytes", name, RP_CFG_MAX_BYTES);
        return RP_CFG_E_SYNTAX;
    }
    rp_cfg_status_t st = check_stream(text, len, name, err, err_len);
    if (st != RP_CFG_OK) {
        return st;
    }
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser)) {
        return RP_CFG_E_ARG;
    }
    yaml_parser_set_input_string(&parser, (const unsigned char *)text, len);
    yaml_document_t doc;
    if (!yaml_parser_load(&parser, &doc)) {
        st = yaml_error(&parser, text, len, name, err, err_len);
    } else {
        ctx_t c = {name, &doc, err, err_len, RP_CFG_OK};
        st = parse_doc(&c, cfg);
        yaml_document_delete(&doc);
    }
    yaml_parser_delete(&parser);
    return st;
}

rp_cfg_status_t rp_config_load(const char *path, rp_config_t *cfg, char *err, size_t err_len)
{
    if (err != NULL && err_len > 0) {
        err[0] = '\0';
    }
    if (path == NULL || cfg == NULL) {
        return RP_CFG_E_ARG;
    }
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        set_err(err, err_len, "%s:0: (file): %s", path, strerror(errno));
        return RP_CFG_E_OPEN;
    }
    struct stat st_f;
    if (fstat(fileno(f), &st_f) == 0 && S_ISDIR(st_f.st_mode)) {
        fclose(f);
        set_err(err, err_len, "%s:0: (file): is a directory", path);
        return RP_CFG_E_OPEN;
    }
    /* The whole file, at most RP_CFG_MAX_BYTES (one byte more tells a larger file; a pipe or
     * device is read up to there, never without end). Not the per-frame path: heap is fine. */
    char *text = malloc((size_t)RP_CFG_MAX_BYTES + 1u);
    if (text == NULL) {
        fclose(f);
        set_err(err, err_len, "%s:0: (file): out of memory", path);
        return RP_CFG_E_OPEN;
    }
    const size_t len = fread(text, 1, (size_t)RP_CFG_MAX_BYTES + 1u, f);
    const int read_error = ferror(f);
    const int e = errno;
    fclose(f);
    rp_cfg_status_t st;
    if (read_error) {
        set_err(err, err_len, "%s:0: (file): %s", path, strerror(e));
        st = RP_CFG_E_OPEN;
    } else {
        st = rp_config_parse(text, len, path, cfg, err, err_len);
    }
    free(text);
    return st;
}
