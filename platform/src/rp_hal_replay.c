/*
 * rp_hal_replay.c - the HAL's replay source: recorded or rendered frame sets from a folder.
 *
 * The folder (written by rigpose-render, or converted from KITTI / EuRoC by host_tools/research/realdata);
 * cfg.replay_index is the folder (its frames.csv is read) or the index file itself, whatever
 * its name (messages name the file read):
 *   frames.csv  header `utime_us,cam0,cam1,...`, then one row per frame set: the set's time in
 *               microseconds (strictly increasing) and each column's image, a path relative to
 *               the folder (or absolute). Camera i reads the column named cfg.cam[i].device, or
 *               with an empty device the i-th image column.
 *               Cameras that are not simultaneous: a column `utime_us_<name>`, anywhere after
 *               utime_us, is the capture time (us) of image column <name> (e.g. utime_us_cam0
 *               for cam0), which then differs from the row's utime_us by at most 2^31 - 1 us
 *               (rp_frameset_t.cam_dt_us is an int32_t); an image column without one is at
 *               utime_us, so a file without them reads as every camera at the set's time.
 *               Every row has a value in every column; a time that is not an integer, or out
 *               of range, refuses the row (file:line, the column). Only utime_us must increase.
 *               Blank lines and lines starting with '#' are skipped, however long; any other
 *               line longer than LINE_MAX_CHARS is refused (file:line) and the next grab goes on
 *               after it.
 *   truth.csv   optional, header `utime_us,tx,ty,tz,alpha,beta,gamma`: the pose of cam1 in the
 *               world (as rp_estimate_t.p); a set gets the row with its exact utime, if any.
 *               A malformed row is skipped: the set it belongs to comes without truth, with
 *               RP_HAL_OK and the row (file:line) named in the source's message.
 *   images      8-bit grey PNG (libpng; colour or 16-bit PNGs are converted to 8-bit grey) or
 *               binary PGM (P5, maxval <= 255), at most RP_HAL_MAX_W x RP_HAL_MAX_H, and of the
 *               configured size if one is given.
 * Sets come as fast as they are asked for, or with cfg.realtime at their recorded spacing
 * (the first one at once; a gap longer than timeout_ms gives RP_HAL_E_TIMEOUT after timeout_ms
 * and the set comes at a later grab, so grab never blocks longer than timeout_ms), or with
 * RP_HAL_PACE_LIVE at their recorded times read as HAL clock times (a recording stamped on this
 * host's CLOCK_MONOTONIC plays like live cameras: several processes reading it deliver each set
 * at the same moment, and one started late skips the sets due more than timeout_ms ago).
 * set.utime is the row's utime_us, each camera's utime its utime_us_<name> (else utime_us); pacing
 * follows utime_us. seq is the
 * row's index among the data rows. With cfg.partial_sets, a row whose image cannot be read for
 * some cameras is delivered with those cameras MISSING (no image) and RP_HAL_OK, the reason
 * (file:line, camera, file, why) left in the source's message; a row none of whose images can be
 * read (any, without partial_sets), or a malformed row, returns its error naming file and line;
 * the next grab goes on with the next row.
 * Only regular files are read (frames.csv, truth.csv, images): a FIFO, device or directory
 * listed as an image is refused without opening it for reading, so nothing blocks. utime_us
 * must lie within +-2^61 (any two differ by less than INT64_MAX); the pacing arithmetic
 * saturates.
 */
#include "rp_hal_priv.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <png.h>

/* A path and a time per camera, and the set's time: 1792 with the defaults */
#define LINE_MAX_CHARS (RP_MAX_CAMS * (RP_HAL_PATH_MAX + 32) + 64)
/* Fields of a frames.csv line: utime_us, an image and a time column per camera. */
#define MAX_FIELDS (2 * RP_MAX_CAMS + 1)
/* Prefix of a camera's time column: utime_us_<image column>. */
#define TIME_PREFIX "utime_us_"
/* Largest |utime_us| of a row: the difference of any two fits int64_t (the estimators take
 * the time between sets as a difference of utimes). */
#define RP_HAL_UTIME_MAX ((int64_t)1 << 61)

typedef struct {
    uint8_t open, started;
    rp_hal_cfg_t cfg;
    char *err;
    char dir[RP_HAL_PATH_MAX];   /* folder of the index (image paths are relative to it) */
    char index[2 * RP_HAL_PATH_MAX]; /* the index: DIR/frames.csv, or the file given */
    FILE *frames, *truth;
    uint32_t line, tline;        /* lines read so far in frames.csv / truth.csv */
    uint32_t row;                /* data rows read */
    uint32_t set_seq;
    int64_t last_u;              /* utime of the last row read */
    uint8_t any_row;
    int64_t u0, clock0;          /* realtime pacing: first set's utime and HAL clock */
    uint8_t paced;
    uint8_t truth_have;          /* a truth row is buffered */
    int64_t truth_u;
    rp_real truth_p[6];
    rp_hal_set_t ready;          /* the next set, read but not delivered yet */
    uint8_t have_ready;
    char ready_msg[RP_HAL_ERR_MAX]; /* why cameras of the ready set are missing ("" if none) */
    char buf[LINE_MAX_CHARS];
    /* Each camera's image of the row being read: its column's text, path, outcome and message
     * (one camera's load touches only its own entries: cameras may load in parallel jobs). */
    const char *rel[RP_MAX_CAMS];
    char path[RP_MAX_CAMS][2 * RP_HAL_PATH_MAX];
    rp_hal_status_t load_st[RP_MAX_CAMS];
    char load_err[RP_MAX_CAMS][RP_HAL_ERR_MAX];
    uint8_t n_cols;              /* image columns in frames.csv */
    uint8_t n_fields;            /* fields of every line: utime_us, images, times */
    uint8_t img_field[RP_MAX_CAMS];  /* field of image column j */
    uint8_t time_field[RP_MAX_CAMS]; /* field of image column j's time (0: none, at utime_us) */
    char time_name[RP_MAX_CAMS][RP_HAL_PATH_MAX]; /* header name of that time column */
    uint8_t col[RP_MAX_CAMS];    /* camera i's image column */
    uint16_t w[RP_MAX_CAMS], h[RP_MAX_CAMS];
    uint8_t grey[RP_MAX_CAMS][(size_t)RP_HAL_MAX_W * RP_HAL_MAX_H];
} replay_src_t;

static replay_src_t g_replay;

/* next_line's results besides 1 (a line) and 0 (end of file). */
enum { LINE_TOO_LONG = -1, LINE_NUL = -2, LINE_IO = -3 };

/* Next meaningful line of f into buf (cap bytes) without its end of line and trailing spaces.
 * Blank lines and lines starting with '#' are skipped whatever their length. 1: a line,
 * 0: end of file, LINE_TOO_LONG: a line of cap or more characters (read to its end, so the next
 * call goes on after it), LINE_NUL: a NUL byte in the line, LINE_IO: a read error (errno).
 * *line counts every line read. */
static int next_line(FILE *f, char *buf, size_t cap, uint32_t *line)
{
    for (;;) {
        size_t n = 0;
        int c, first = EOF, too_long = 0, nul = 0;
        while ((c = getc(f)) != EOF && c != '\n') {
            if (first == EOF) {
                first = c;
            }
            if (first == '#') {
                continue; /* a comment: skipped however long */
            }
            nul |= c == '\0';
            if (n + 1 < cap) {
                buf[n++] = (char)c;
            } else {
                too_long = 1;
            }
        }
        if (c == EOF && first == EOF) {
            return ferror(f) ? LINE_IO : 0;
        }
        (*line)++;
        buf[n] = '\0';
        if (too_long) {
            return LINE_TOO_LONG;
        }
        if (nul) {
            return LINE_NUL;
        }
        while (n > 0 && (buf[n - 1] == '\r' || buf[n - 1] == ' ')) {
            buf[--n] = '\0';
        }
        if (n > 0 && first != '#') {
            return 1;
        }
    }
}

/* Why next_line gave r < 1, for a message. */
static const char *line_why(int r)
{
    switch (r) {
    case LINE_TOO_LONG: {
        static char b[64];
        /* ignored: a message cut at RP_HAL_ERR_MAX is still a message */
        (void)snprintf(b, sizeof b, "line longer than %d characters", LINE_MAX_CHARS - 1);
        return b;
    }
    case LINE_NUL: return "NUL byte in the line";
    case LINE_IO: return strerror(errno);
    default: return "no line";
    }
}

/* Opens path for reading only if it is a regular file: stat first (a FIFO or device is never
 * opened), then open without blocking and check the opened file again (it may have been
 * replaced in between). NULL with *why set on failure. */
static FILE *open_regular(const char *path, const char **why)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        *why = strerror(errno);
        return NULL;
    }
    const int fd = S_ISREG(st.st_mode) ? open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY) : -1;
    if (fd < 0 && S_ISREG(st.st_mode)) {
        *why = strerror(errno);
        return NULL;
    }
    if (fd >= 0 && (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))) {
        close(fd);
    } else if (fd >= 0) {
        FILE *f = fdopen(fd, "rb");
        if (f == NULL) {
            *why = strerror(errno);
            close(fd);
        }
        return f;
    }
    *why = S_ISDIR(st.st_mode) ? "is a directory, not a file"
           : S_ISFIFO(st.st_mode) ? "is a FIFO, not a regular file"
           : (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) ? "is a device, not a regular file"
                                                          : "not a regular file";
    return NULL;
}

/* a + b and a - b, saturating at the ends of int64_t. */
static int64_t sat_add(int64_t a, int64_t b)
{
    if (b > 0 && a > INT64_MAX - b) {
        return INT64_MAX;
    }
    if (b < 0 && a < INT64_MIN - b) {
        return INT64_MIN;
    }
    return a + b;
}

static int64_t sat_sub(int64_t a, int64_t b)
{
    if (b < 0 && a > INT64_MAX + b) {
        return INT64_MAX;
    }
    if (b > 0 && a < INT64_MIN + b) {
        return INT64_MIN;
    }
    return a - b;
}

/* Splits buf at commas in place (spaces around fields trimmed). Returns the field count, or
 * max + 1 if there are more than max. */
static unsigned split(char *buf, char *fields[], unsigned max)
{
    unsigned k = 0;
    char *p = buf;
    for (;;) {
        while (*p == ' ') {
            p++;
        }
        if (k == max) {
            return max + 1;
        }
        fields[k++] = p;
        char *c = strchr(p, ',');
        char *end = c != NULL ? c : p + strlen(p);
        while (end > p && end[-1] == ' ') {
            end--;
        }
        if (c == NULL) {
            *end = '\0';
            return k;
        }
        *end = '\0';
        p = c + 1;
    }
}

static int parse_i64(const char *s, int64_t *v)
{
    char *end;
    errno = 0;
    const long long x = strtoll(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0') {
        return 0;
    }
    *v = (int64_t)x;
    return 1;
}

static int parse_real(const char *s, rp_real *v)
{
    char *end;
    errno = 0;
    const double x = strtod(s, &end);
    if (errno != 0 || end == s || *end != '\0' || !(x == x)) {
        return 0;
    }
    *v = (rp_real)x;
    return 1;
}

/* Binary PGM (P5): header tokens with '#' comments, then w * h bytes. */
static int pgm_token(FILE *f, unsigned *v)
{
    int c = fgetc(f);
    for (;;) {
        while (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
            c = fgetc(f);
        }
        if (c != '#') {
            break;
        }
        while (c != '\n' && c != EOF) {
            c = fgetc(f);
        }
    }
    if (c < '0' || c > '9') {
        return 0;
    }
    unsigned x = 0;
    while (c >= '0' && c <= '9') {
        if (x > 100000u) {
            return 0;
        }
        x = x * 10u + (unsigned)(c - '0');
        c = fgetc(f);
    }
    *v = x;
    return c == ' ' || c == '\t' || c == '\n' || c == '\r'; /* one whitespace ends a token */
}

static const char *read_pgm(FILE *f, uint8_t *dst, uint16_t *w, uint16_t *h)
{
    unsigned pw, ph, maxval;
    if (fgetc(f) != 'P' || fgetc(f) != '5' || !pgm_token(f, &pw) || !pgm_token(f, &ph) ||
        !pgm_token(f, &maxval)) {
        return "not a binary PGM (P5) header";
    }
    if (maxval == 0 || maxval > 255) {
        return "PGM maxval must be 1..255 (8-bit)";
    }
    if (pw == 0 || ph == 0 || pw > RP_HAL_MAX_W || ph > RP_HAL_MAX_H) {
        return "image size 0 or above RP_HAL_MAX_W x RP_HAL_MAX_H";
    }
    if (fread(dst, 1, (size_t)pw * ph, f) != (size_t)pw * ph) {
        return "PGM pixel data truncated";
    }
    *w = (uint16_t)pw;
    *h = (uint16_t)ph;
    return NULL;
}

static const char *read_png(FILE *f, uint8_t *dst, uint16_t *w, uint16_t *h)
{
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_stdio(&im, f)) {
        return "malformed PNG";
    }
    if (im.width == 0 || im.height == 0 || im.width > RP_HAL_MAX_W ||
        im.height > RP_HAL_MAX_H) {
        png_image_free(&im);
        return "image size 0 or above RP_HAL_MAX_W x RP_HAL_MAX_H";
    }
    im.format = PNG_FORMAT_GRAY;
    if (!png_image_finish_read(&im, NULL, dst, (png_int_32)im.width, NULL)) {
        png_image_free(&im);
        return "malformed PNG data";
    }
    *w = (uint16_t)im.width;
    *h = (uint16_t)im.height;
    return NULL;
}

/* One image (PNG or PGM, told apart by their first bytes) into the camera's buffer. Messages
 * (in the camera's own load_err) name frames.csv's line, the camera, the file and what is
 * wrong. */
static rp_hal_status_t load_image(replay_src_t *s, uint8_t cam, const char *rel)
{
    char *path = s->path[cam];
    char *err = s->load_err[cam];
    const size_t cap = sizeof s->path[cam];
    const int n = rel[0] == '/' ? snprintf(path, cap, "%s", rel)
                                : snprintf(path, cap, "%s/%s", s->dir, rel);
    if (n < 0 || (size_t)n >= cap || rel[0] == '\0') {
        return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s:%u: camera %u: %s path",
                           s->index, (unsigned)s->line, (unsigned)cam,
                           rel[0] == '\0' ? "empty" : "too long a");
    }
    const char *why = NULL;
    FILE *f = open_regular(path, &why);
    if (f == NULL) {
        return rp_hal_fail(err, RP_HAL_E_OPEN, "%s:%u: camera %u: %s: %s", s->index,
                           (unsigned)s->line, (unsigned)cam, path, why);
    }
    unsigned char magic[4] = {0, 0, 0, 0};
    const size_t got = fread(magic, 1, 4, f);
    rewind(f);
    if (got == 4 && magic[0] == 0x89 && magic[1] == 'P' && magic[2] == 'N' && magic[3] == 'G') {
        why = read_png(f, s->grey[cam], &s->w[cam], &s->h[cam]);
    } else {
        why = read_pgm(f, s->grey[cam], &s->w[cam], &s->h[cam]);
    }
    fclose(f);
    if (why != NULL) {
        return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s:%u: camera %u: %s: %s", s->index,
                           (unsigned)s->line, (unsigned)cam, path, why);
    }
    const rp_hal_cam_cfg_t *cc = &s->cfg.cam[cam];
    if (cc->w != 0 && (s->w[cam] != cc->w || s->h[cam] != cc->h)) {
        return rp_hal_fail(err, RP_HAL_E_FORMAT,
                           "%s:%u: camera %u: %s: %ux%u, configured %ux%u", s->index,
                           (unsigned)s->line, (unsigned)cam, path, (unsigned)s->w[cam],
                           (unsigned)s->h[cam], (unsigned)cc->w, (unsigned)cc->h);
    }
    return RP_HAL_OK;
}

/* Job `cam` of a row (rp_hal_cfg_t.run_jobs): that camera's image. */
static void load_job(void *arg, unsigned cam)
{
    replay_src_t *s = (replay_src_t *)arg;
    s->load_st[cam] = load_image(s, (uint8_t)cam, s->rel[cam]);
}

static void replay_close(void *ctx)
{
    replay_src_t *s = (replay_src_t *)ctx;
    if (s->frames != NULL) {
        fclose(s->frames);
    }
    if (s->truth != NULL) {
        fclose(s->truth);
    }
    s->frames = s->truth = NULL;
    s->open = 0;
}

/* The header's k fields f (f[0] is utime_us): image columns, and the time column
 * utime_us_<name> of some of them (rp_hal_replay.c's format). */
static rp_hal_status_t parse_header(replay_src_t *s, char *f[], unsigned k, const char *csv,
                                    char *err)
{
    const size_t pl = strlen(TIME_PREFIX);
    if (k > MAX_FIELDS) {
        return rp_hal_fail(err, RP_HAL_E_FORMAT,
                           "%s:%u: more than %d image columns and their times", csv,
                           (unsigned)s->line, RP_MAX_CAMS);
    }
    s->n_cols = 0;
    s->n_fields = (uint8_t)k;
    for (unsigned i = 1; i < k; i++) {
        if (strncmp(f[i], TIME_PREFIX, pl) == 0) {
            continue;
        }
        if (s->n_cols == RP_MAX_CAMS) {
            return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s:%u: more than %d image columns", csv,
                               (unsigned)s->line, RP_MAX_CAMS);
        }
        s->time_field[s->n_cols] = 0;
        s->img_field[s->n_cols++] = (uint8_t)i;
    }
    if (s->n_cols == 0) {
        return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s:%u: header must be utime_us,cam0,cam1,...",
                           csv, (unsigned)s->line);
    }
    for (unsigned i = 1; i < k; i++) {
        if (strncmp(f[i], TIME_PREFIX, pl) != 0) {
            continue;
        }
        unsigned j = 0;
        while (j < s->n_cols && strcmp(f[s->img_field[j]], f[i] + pl) != 0) {
            j++;
        }
        if (j == s->n_cols) {
            return rp_hal_fail(err, RP_HAL_E_FORMAT,
                               "%s:%u: time column '%s' names no image column '%s'", csv,
                               (unsigned)s->line, f[i], f[i] + pl);
        }
        if (s->time_field[j] != 0) {
            return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s:%u: two time columns '%s'", csv,
                               (unsigned)s->line, f[i]);
        }
        s->time_field[j] = (uint8_t)i;
        /* ignored: a name cut at RP_HAL_PATH_MAX only shortens messages */
        (void)snprintf(s->time_name[j], sizeof s->time_name[j], "%s", f[i]);
    }
    return RP_HAL_OK;
}

static rp_hal_status_t replay_open(void **ctx, const rp_hal_cfg_t *cfg, char *err)
{
    replay_src_t *s = &g_replay;
    if (s->open) {
        return rp_hal_fail(err, RP_HAL_E_STATE, "replay: already open");
    }
    const char *idx = cfg->replay_index;
    if (memchr(idx, '\0', RP_HAL_PATH_MAX) == NULL || idx[0] == '\0') {
        return rp_hal_fail(err, RP_HAL_E_ARG, "replay: no replay_index (frames.csv or folder)");
    }
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->err = err;
    char csv[2 * RP_HAL_PATH_MAX];
    struct stat st;
    const int is_dir = stat(idx, &st) == 0 && S_ISDIR(st.st_mode);
    if (is_dir) {
        /* ignored: a path cut short fails to open, which says so */
        (void)snprintf(s->dir, sizeof s->dir, "%s", idx);
    } else {
        const char *slash = strrchr(idx, '/');
        if (slash == NULL) {
            /* ignored: a path cut short fails to open, which says so */
            (void)snprintf(s->dir, sizeof s->dir, ".");
        } else {
            /* ignored: a path cut short fails to open, which says so */
            (void)snprintf(s->dir, sizeof s->dir, "%.*s", (int)(slash - idx), idx);
        }
    }
    size_t dl = strlen(s->dir);
    while (dl > 1 && s->dir[dl - 1] == '/') {
        s->dir[--dl] = '\0';
    }
    if (is_dir) {
        /* ignored: a path cut short fails to open, which says so */
        (void)snprintf(s->index, sizeof s->index, "%s/frames.csv", s->dir);
    } else { /* the file given, whatever its name (a renamed index is not silently replaced) */
        /* ignored: a path cut short fails to open, which says so */
        (void)snprintf(s->index, sizeof s->index, "%s", idx);
    }
    /* ignored: a path cut short fails to open, which says so */
    (void)snprintf(csv, sizeof csv, "%s", s->index);
    const char *why = NULL;
    s->frames = open_regular(csv, &why);
    if (s->frames == NULL) {
        return rp_hal_fail(err, RP_HAL_E_OPEN, "%s: %s%s%s%s", csv, why,
                           is_dir ? " (replay_index " : "", is_dir ? idx : "",
                           is_dir ? " is a folder: its frames.csv is read)" : "");
    }
    char *f[MAX_FIELDS + 1];
    const int r = next_line(s->frames, s->buf, sizeof s->buf, &s->line);
    const unsigned k = r > 0 ? split(s->buf, f, MAX_FIELDS) : 0;
    if (r < 0) {
        replay_close(s);
        return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s:%u: %s", csv, (unsigned)s->line,
                           line_why(r));
    }
    if (r == 0 || k < 2 || strcmp(f[0], "utime_us") != 0) {
        replay_close(s);
        return rp_hal_fail(err, RP_HAL_E_FORMAT,
                           "%s:%u: header must be utime_us,cam0,cam1,...", csv,
                           (unsigned)s->line);
    }
    const rp_hal_status_t hst = parse_header(s, f, k, csv, err);
    if (hst != RP_HAL_OK) {
        replay_close(s);
        return hst;
    }
    for (uint8_t i = 0; i < cfg->n_cams; i++) {
        const char *name = cfg->cam[i].device;
        if (memchr(name, '\0', RP_HAL_PATH_MAX) == NULL) {
            replay_close(s);
            return rp_hal_fail(err, RP_HAL_E_ARG, "replay: camera %u: device not terminated",
                               (unsigned)i);
        }
        unsigned c = name[0] == '\0' ? i : RP_MAX_CAMS;
        for (unsigned j = 0; j < s->n_cols && name[0] != '\0'; j++) {
            c = strcmp(f[s->img_field[j]], name) == 0 ? j : c;
        }
        if (c >= s->n_cols) {
            replay_close(s);
            if (name[0] == '\0') {
                return rp_hal_fail(err, RP_HAL_E_FORMAT,
                                   "%s:%u: %u image columns, configured %u cameras", csv,
                                   (unsigned)s->line, (unsigned)s->n_cols, (unsigned)cfg->n_cams);
            }
            return rp_hal_fail(err, RP_HAL_E_FORMAT, "%s:%u: no column '%s' (camera %u)", csv,
                               (unsigned)s->line, name, (unsigned)i);
        }
        s->col[i] = (uint8_t)c;
    }
    /* ignored: a path cut short fails to open, which says so */
    (void)snprintf(csv, sizeof csv, "%s/truth.csv", s->dir);
    struct stat tst;
    if (stat(csv, &tst) == 0 || errno != ENOENT) { /* truth.csv is optional */
        s->truth = open_regular(csv, &why);
        if (s->truth == NULL) {
            replay_close(s);
            return rp_hal_fail(err, RP_HAL_E_OPEN, "%s: %s", csv, why);
        }
    }
    if (s->truth != NULL) {
        static const char *const want[7] = {"utime_us", "tx", "ty", "tz", "alpha", "beta",
                                            "gamma"};
        const int rt = next_line(s->truth, s->buf, sizeof s->buf, &s->tline);
        unsigned kt = rt > 0 ? split(s->buf, f, 7) : 0;
        for (unsigned i = 0; i < kt && kt == 7; i++) {
            kt = strcmp(f[i], want[i]) == 0 ? kt : 0;
        }
        if (kt != 7) {
            replay_close(s);
            return rp_hal_fail(err, RP_HAL_E_FORMAT,
                               "%s:%u: header must be utime_us,tx,ty,tz,alpha,beta,gamma", csv,
                               (unsigned)s->tline);
        }
    }
    s->open = 1;
    *ctx = s;
    return RP_HAL_OK;
}

static rp_hal_status_t replay_start(void *ctx)
{
    replay_src_t *s = (replay_src_t *)ctx;
    if (s->started) {
        return rp_hal_fail(s->err, RP_HAL_E_STATE, "replay: already started");
    }
    s->started = 1;
    s->paced = 0;
    return RP_HAL_OK;
}

static rp_hal_status_t replay_stop(void *ctx)
{
    replay_src_t *s = (replay_src_t *)ctx;
    if (!s->started) {
        return rp_hal_fail(s->err, RP_HAL_E_STATE, "replay: not started");
    }
    s->started = 0;
    return RP_HAL_OK;
}

/* Advances truth.csv to the row of utime u. 1: found (into p), 0: none, -1: malformed. */
static int truth_at(replay_src_t *s, int64_t u)
{
    while (s->truth != NULL && (!s->truth_have || s->truth_u < u)) {
        char *f[8];
        const int r = next_line(s->truth, s->buf, sizeof s->buf, &s->tline);
        if (r == 0) {
            fclose(s->truth);
            s->truth = NULL;
            s->truth_have = 0;
            return 0;
        }
        if (r < 0 || split(s->buf, f, 7) != 7 || !parse_i64(f[0], &s->truth_u)) {
            s->truth_have = 0; /* the row is skipped: no half-read truth is used */
            return -1;
        }
        for (unsigned i = 0; i < 6; i++) {
            if (!parse_real(f[i + 1], &s->truth_p[i])) {
                s->truth_have = 0;
                return -1;
            }
        }
        s->truth_have = 1;
    }
    return s->truth_have && s->truth_u == u;
}

/* Each camera's capture time of a row (fields f, the set's time u) into cam_u: its image
 * column's time column, else u. A time that is not an integer, or more than an int32_t of
 * microseconds from u, refuses the row (file:line and the column). */
static rp_hal_status_t cam_times(replay_src_t *s, char *f[], int64_t u, int64_t cam_u[])
{
    for (uint8_t i = 0; i < s->cfg.n_cams; i++) {
        const uint8_t tf = s->time_field[s->col[i]];
        cam_u[i] = u;
        if (tf == 0) {
            continue;
        }
        const char *name = s->time_name[s->col[i]];
        if (!parse_i64(f[tf], &cam_u[i])) {
            return rp_hal_fail(s->err, RP_HAL_E_FORMAT,
                               "%s:%u: %s '%.40s' is not a time in microseconds", s->index,
                               (unsigned)s->line, name, f[tf]);
        }
        /* |u| <= 2^61 (checked before): the difference is taken only for |cam_u| <= 2^61 */
        if (cam_u[i] < -RP_HAL_UTIME_MAX || cam_u[i] > RP_HAL_UTIME_MAX ||
            cam_u[i] - u < INT32_MIN || cam_u[i] - u > INT32_MAX) {
            return rp_hal_fail(s->err, RP_HAL_E_FORMAT,
                               "%s:%u: %s %" PRId64 " more than 2^31 - 1 us (35 min) from "
                               "utime_us %" PRId64, s->index, (unsigned)s->line, name,
                               cam_u[i], u);
        }
    }
    return RP_HAL_OK;
}

/* Reads and loads the next row into the ready set (s->ready). */
static rp_hal_status_t read_row(replay_src_t *s)
{
    const uint8_t n = s->cfg.n_cams;
    char *f[MAX_FIELDS + 1];
    int64_t u = 0;
    int64_t cam_u[RP_MAX_CAMS];
    uint32_t row = 0;
    for (;;) {
        const int r = next_line(s->frames, s->buf, sizeof s->buf, &s->line);
        if (r == 0) {
            return rp_hal_fail(s->err, RP_HAL_E_END, "%s: end after %u sets", s->index,
                               (unsigned)s->row);
        }
        if (r < 0) {
            return rp_hal_fail(s->err, RP_HAL_E_FORMAT, "%s:%u: %s", s->index,
                               (unsigned)s->line, line_why(r));
        }
        const unsigned k = split(s->buf, f, MAX_FIELDS);
        u = 0;
        if (k != s->n_fields || !parse_i64(f[0], &u)) {
            const unsigned n_times = (unsigned)s->n_fields - 1u - s->n_cols;
            return rp_hal_fail(s->err, RP_HAL_E_FORMAT,
                               "%s:%u: want utime_us and %u image paths%s", s->index,
                               (unsigned)s->line, (unsigned)s->n_cols,
                               n_times > 0 ? " and their times" : "");
        }
        if (u < -RP_HAL_UTIME_MAX || u > RP_HAL_UTIME_MAX) {
            return rp_hal_fail(s->err, RP_HAL_E_FORMAT,
                               "%s:%u: utime_us %" PRId64 " outside +-2^61 us (73,000 "
                               "years: beyond it the time between two sets overflows)",
                               s->index, (unsigned)s->line, u);
        }
        if (s->any_row && u <= s->last_u) {
            return rp_hal_fail(s->err, RP_HAL_E_FORMAT,
                               "%s:%u: utime_us %" PRId64 " not after %" PRId64, s->index,
                               (unsigned)s->line, u, s->last_u);
        }
        const rp_hal_status_t tst = cam_times(s, f, u, cam_u);
        if (tst != RP_HAL_OK) {
            return tst;
        }
        s->any_row = 1;
        s->last_u = u;
        row = s->row++;
        /* live: a set due more than timeout_ms ago is skipped here, its images never read */
        if (s->cfg.realtime != RP_HAL_PACE_LIVE ||
            sat_sub(rp_hal_now_us(), u) <= (int64_t)s->cfg.timeout_ms * 1000) {
            break;
        }
    }
    /* Each camera's image; one that cannot be read leaves its camera MISSING in this set. */
    uint8_t ok[RP_MAX_CAMS];
    unsigned n_bad = 0;
    rp_hal_status_t first_bad = RP_HAL_OK;
    s->ready_msg[0] = '\0';
    for (uint8_t i = 0; i < n; i++) {
        s->rel[i] = f[s->img_field[s->col[i]]];
    }
    if (s->cfg.run_jobs == NULL || s->cfg.run_jobs(s->cfg.run_jobs_ctx, n, load_job, s) != 0) {
        for (uint8_t i = 0; i < n; i++) {
            load_job(s, i);
        }
    }
    for (uint8_t i = 0; i < n; i++) { /* in camera order: the first failure is the message */
        const rp_hal_status_t st = s->load_st[i];
        ok[i] = st == RP_HAL_OK;
        if (st != RP_HAL_OK && n_bad++ == 0) {
            first_bad = st;
            memcpy(s->ready_msg, s->load_err[i], RP_HAL_ERR_MAX);
        }
    }
    if (n_bad == n || (n_bad > 0 && !s->cfg.partial_sets)) { /* the row fails (first reason) */
        memcpy(s->err, s->ready_msg, RP_HAL_ERR_MAX);
        s->ready_msg[0] = '\0';
        return first_bad;
    }
    if (n_bad > 1) {
        const size_t len = strlen(s->ready_msg);
        /* ignored: a message cut at RP_HAL_ERR_MAX is still a message */
        (void)snprintf(s->ready_msg + len, RP_HAL_ERR_MAX - len, " (and %u more cameras)",
                       n_bad - 1);
    }
    /* A malformed truth.csv row costs only the truth: the set comes without it, the message
     * says which row was skipped (the images are good). */
    const int tr = truth_at(s, u);
    if (tr < 0 && s->ready_msg[0] == '\0') {
        /* ignored: it returns the status it was given: here only the message is wanted */
        (void)rp_hal_fail(s->ready_msg, RP_HAL_E_FORMAT,
                          "%s/truth.csv:%u: want utime_us and 6 numbers: row skipped, set %u "
                          "has no truth", s->dir, (unsigned)s->tline, (unsigned)row);
    }
    rp_hal_set_t *set = &s->ready;
    rp_hal_set_clear(set, n);
    for (uint8_t i = 0; i < n; i++) {
        if (!ok[i]) {
            continue; /* MISSING, no image (rp_hal_set_clear) */
        }
        rp_hal_frame_t *fr = &set->cam[i];
        fr->img.data = s->grey[i];
        fr->img.w = s->w[i];
        fr->img.h = s->h[i];
        fr->img.stride = s->w[i];
        fr->img.size = (uint32_t)s->w[i] * s->h[i];
        fr->utime = cam_u[i];
        fr->seq = row;
        fr->flags = RP_HAL_CAM_OK;
    }
    set->utime = u;
    if (tr > 0) {
        set->has_truth = 1;
        memcpy(set->truth, s->truth_p, sizeof set->truth);
    }
    s->have_ready = 1;
    return RP_HAL_OK;
}

static rp_hal_status_t replay_grab(void *ctx, rp_hal_set_t *set)
{
    replay_src_t *s = (replay_src_t *)ctx;
    if (!s->started) {
        return rp_hal_fail(s->err, RP_HAL_E_STATE, "replay: grab before start");
    }
    rp_hal_set_clear(set, s->cfg.n_cams);
    if (!s->have_ready) {
        const rp_hal_status_t st = read_row(s);
        if (st != RP_HAL_OK) {
            return st;
        }
    }
    const int64_t limit = (int64_t)s->cfg.timeout_ms * 1000;
    if (s->cfg.realtime == RP_HAL_PACE_LIVE) {
        /* A camera never delivers the past: sets due more than timeout_ms ago are skipped. */
        while (sat_sub(rp_hal_now_us(), s->ready.utime) > limit) {
            s->have_ready = 0;
            const rp_hal_status_t st = read_row(s);
            if (st != RP_HAL_OK) {
                return st;
            }
        }
    }
    if (s->cfg.realtime) {
        const int64_t u = s->ready.utime;
        if (!s->paced) {
            /* live: the recorded times are the HAL clock's */
            s->u0 = u;
            s->clock0 = s->cfg.realtime == RP_HAL_PACE_LIVE ? u : rp_hal_now_us();
            s->paced = 1;
        }
        const int64_t wait = sat_sub(sat_add(s->clock0, sat_sub(u, s->u0)), rp_hal_now_us());
        if (s->cfg.timeout_ms > 0 && wait > limit) { /* a gap in the recording: keep the set */
            rp_hal_sleep_us(limit);
            return rp_hal_fail(s->err, RP_HAL_E_TIMEOUT,
                               "replay: next set due in %.3f s, more than timeout_ms",
                               (double)wait * 1e-6);
        }
        rp_hal_sleep_us(wait);
    }
    *set = s->ready;
    set->seq = s->set_seq++;
    s->have_ready = 0;
    if (s->ready_msg[0] != '\0') { /* cameras missing from this set: say why */
        memcpy(s->err, s->ready_msg, RP_HAL_ERR_MAX);
    }
    return RP_HAL_OK;
}

const rp_hal_ops_t rp_hal_replay_ops = {
    .name = "replay", .payload = RP_HAL_PAYLOAD_IMAGES, .open = replay_open,
    .start = replay_start, .grab = replay_grab, .stop = replay_stop, .close = replay_close};
