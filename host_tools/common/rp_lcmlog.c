/*
 * rp_lcmlog.c - see rp_lcmlog.h.
 */
#include "rp_lcmlog.h"

#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
}

static uint64_t be64(const uint8_t *p)
{
    return (uint64_t)be32(p) << 32 | be32(p + 4);
}

static int fail(rp_lcmlog_t *log, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static int fail(rp_lcmlog_t *log, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(log->err, sizeof log->err, fmt, ap); /* a cut message is still one line */
    va_end(ap);
    log->failed = 1;
    return -1;
}

static int setup(rp_lcmlog_t *log, FILE *f, const char *name, int tolerant)
{
    (void)snprintf(log->name, sizeof log->name, "%s", name != NULL ? name : "(log)");
    log->f = f;
    log->tolerant = tolerant;
    const off_t start = ftello(f);
    if (start < 0 || fseeko(f, 0, SEEK_END) != 0) {
        return fail(log, "%s: cannot seek (not a regular file?)", log->name);
    }
    const off_t end = ftello(f);
    if (end < start || fseeko(f, start, SEEK_SET) != 0) {
        return fail(log, "%s: cannot seek (not a regular file?)", log->name);
    }
    log->origin = (int64_t)start; /* offsets in messages count from here */
    log->size = (int64_t)(end - start);
    log->off = 0;
    return 0;
}

int rp_lcmlog_open(rp_lcmlog_t *log, const char *path, int tolerant)
{
    memset(log, 0, sizeof *log);
    (void)snprintf(log->name, sizeof log->name, "%s", path);
    struct stat st;
    if (stat(path, &st) != 0) {
        return fail(log, "%s: %s", path, strerror(errno));
    }
    if (!S_ISREG(st.st_mode)) {
        return fail(log, "%s: not a regular file", path);
    }
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return fail(log, "%s: %s", path, strerror(errno));
    }
    log->own = 1;
    return setup(log, f, path, tolerant);
}

int rp_lcmlog_open_stream(rp_lcmlog_t *log, FILE *f, const char *name, int tolerant)
{
    memset(log, 0, sizeof *log);
    if (f == NULL) {
        return fail(log, "%s: no stream", name != NULL ? name : "(log)");
    }
    return setup(log, f, name, tolerant);
}

void rp_lcmlog_close(rp_lcmlog_t *log)
{
    if (log->own && log->f != NULL) {
        fclose(log->f);
    }
    free(log->chan);
    free(log->data);
    log->f = NULL;
    log->chan = NULL;
    log->data = NULL;
    log->chan_cap = log->data_cap = 0;
}

/* n bytes at byte offset at of the log (offsets from where the log started). */
static int read_at(rp_lcmlog_t *log, int64_t at, void *dst, size_t n)
{
    return fseeko(log->f, (off_t)(log->origin + at), SEEK_SET) == 0 && fread(dst, 1, n, log->f) == n;
}

/* Why the event header hd at offset at is not a valid event, or NULL. left: bytes in the file
 * from at on. */
static const char *check_header(const uint8_t *hd, int64_t left, char *why, size_t cap)
{
    const uint32_t sync = be32(hd);
    const int32_t cl = (int32_t)be32(hd + 20), dl = (int32_t)be32(hd + 24);
    if (sync != RP_LCMLOG_SYNC) {
        (void)snprintf(why, cap, "no event header (sync word 0x%08" PRIx32 ", want 0x%08X)", sync,
                       RP_LCMLOG_SYNC);
        return why;
    }
    if (cl < 1 || cl > RP_LCMLOG_CHANNEL_MAX) {
        (void)snprintf(why, cap, "channel length %" PRId32 " outside 1..%d", cl,
                       RP_LCMLOG_CHANNEL_MAX);
        return why;
    }
    if (dl < 0) {
        (void)snprintf(why, cap, "data length %" PRId32 " is negative", dl);
        return why;
    }
    const int64_t need = (int64_t)RP_LCMLOG_HEADER + cl + dl;
    if (need > left) {
        (void)snprintf(why, cap,
                       "event of %" PRId64 " bytes (channel %" PRId32 ", data %" PRId32
                       ") but only %" PRId64 " bytes left in the file: truncated or corrupt",
                       need, cl, dl, left);
        return why;
    }
    return NULL;
}

/* Tolerant: the offset of the first sync word after `from` that starts a plausible event, or the
 * end of the file. -1 on a read error. */
static int64_t resync(rp_lcmlog_t *log, int64_t from)
{
    enum { CHUNK = 65536 };
    static const uint8_t sync[4] = {0xED, 0xA1, 0xDA, 0x01};
    uint8_t buf[CHUNK];
    int64_t pos = from + 1;
    while (pos + RP_LCMLOG_HEADER <= log->size) {
        const int64_t left = log->size - pos;
        const size_t n = (size_t)(left < CHUNK ? left : CHUNK);
        if (!read_at(log, pos, buf, n)) {
            return -1;
        }
        for (size_t i = 0; i + 4 <= n; i++) {
            if (memcmp(buf + i, sync, 4) != 0) {
                continue;
            }
            const int64_t at = pos + (int64_t)i;
            uint8_t hd[RP_LCMLOG_HEADER];
            char why[160];
            if (at + RP_LCMLOG_HEADER <= log->size && read_at(log, at, hd, sizeof hd) &&
                check_header(hd, log->size - at, why, sizeof why) == NULL) {
                return at;
            }
        }
        if ((int64_t)n < CHUNK) {
            break;
        }
        pos += (int64_t)n - 3; /* a sync word across the chunk boundary */
    }
    return log->size;
}

static int grow(void **buf, size_t *cap, size_t need)
{
    if (need <= *cap) {
        return 1;
    }
    void *p = realloc(*buf, need);
    if (p == NULL) {
        return 0;
    }
    *buf = p;
    *cap = need;
    return 1;
}

int rp_lcmlog_next(rp_lcmlog_t *log, rp_lcmlog_event_t *ev)
{
    if (log->f == NULL || log->failed) {
        return log->err[0] != '\0' ? -1 : fail(log, "%s: not open", log->name);
    }
    for (;;) {
        if (log->off == log->size) {
            return 0;
        }
        const int64_t at = log->off, left = log->size - at;
        uint8_t hd[RP_LCMLOG_HEADER];
        char why[200];
        const char *bad = NULL;
        if (left < RP_LCMLOG_HEADER) {
            (void)snprintf(why, sizeof why, "truncated event header (%" PRId64 " of %d bytes)",
                           left, RP_LCMLOG_HEADER);
            bad = why;
        } else if (!read_at(log, at, hd, sizeof hd)) {
            return fail(log, "%s: offset %" PRId64 ": read failed", log->name, at);
        } else {
            bad = check_header(hd, left, why, sizeof why);
        }
        if (bad != NULL) {
            if (!log->tolerant) {
                return fail(log, "%s: offset %" PRId64 ": %s", log->name, at, bad);
            }
            const int64_t next = resync(log, at);
            if (next < 0) {
                return fail(log, "%s: offset %" PRId64 ": read failed", log->name, at);
            }
            log->n_skips++;
            log->skipped += next - at;
            if (log->warn != NULL) {
                if (next < log->size) {
                    fprintf(log->warn, "%s%s%s: offset %" PRId64 ": %s; skipped %" PRId64
                                       " bytes to the next event at offset %" PRId64 "\n",
                            log->prog ? log->prog : "", log->prog ? ": " : "", log->name, at, bad,
                            next - at, next);
                } else {
                    fprintf(log->warn, "%s%s%s: offset %" PRId64 ": %s; skipped the last %" PRId64
                                       " bytes\n",
                            log->prog ? log->prog : "", log->prog ? ": " : "", log->name, at, bad,
                            next - at);
                }
            }
            log->off = next;
            continue;
        }
        const int32_t cl = (int32_t)be32(hd + 20), dl = (int32_t)be32(hd + 24);
        if (!grow((void **)&log->chan, &log->chan_cap, (size_t)cl + 1) ||
            !grow((void **)&log->data, &log->data_cap, (size_t)dl + 1)) {
            return fail(log, "%s: offset %" PRId64 ": out of memory for %" PRId32 " bytes",
                        log->name, at, dl);
        }
        if (fread(log->chan, 1, (size_t)cl, log->f) != (size_t)cl ||
            fread(log->data, 1, (size_t)dl, log->f) != (size_t)dl) {
            return fail(log, "%s: offset %" PRId64 ": read failed", log->name, at);
        }
        log->chan[cl] = '\0';
        ev->offset = at;
        ev->eventnum = (int64_t)be64(hd + 4);
        ev->timestamp = (int64_t)be64(hd + 12);
        ev->channel = log->chan;
        ev->channellen = cl;
        ev->data = log->data;
        ev->datalen = dl;
        log->off = at + RP_LCMLOG_HEADER + cl + dl;
        log->n_events++;
        return 1;
    }
}
