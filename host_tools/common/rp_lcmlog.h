/*
 * rp_lcmlog.h - reading LCM log files (lcm-logger's, `rigpose --lcm-url file://...`,
 * rigpose-log's) without trusting them: the one log reader of rigpose-eval and rigpose-log.
 *
 * The format (LCM's eventlog), every integer big-endian, events back to back:
 *   offset  0  int32  sync word 0xEDA1DA01
 *           4  int64  event number
 *          12  int64  timestamp, us
 *          20  int32  channel length (bytes, no NUL)
 *          24  int32  data length (bytes)
 *          28  channel, then data
 * liblcm's reader allocates whatever the header claims and reads into it unchecked (a data length
 * of 0x7fffffff makes Debian's liblcm 1.3.1 read into NULL), skips garbage silently and takes a
 * truncated event for the end of the log. This reader checks every header before it reads: the
 * sync word where an event must start, a channel length in 1..RP_LCMLOG_CHANNEL_MAX, a data
 * length >= 0, and both lengths against the bytes left in the file. The first violation is an
 * error, "FILE: offset N: what" (N the byte offset of the bad event), unless the log is read
 * tolerantly: then the reader skips to the next sync word that starts a plausible event (or to
 * the end), counts the bytes skipped and writes one warning line per skip to `warn`.
 *
 * Host code (stdio, heap for the event's bytes, bounded by the file's size); C99 and C++.
 */
#ifndef RP_LCMLOG_H
#define RP_LCMLOG_H

#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define RP_LCMLOG_SYNC 0xEDA1DA01u
#define RP_LCMLOG_HEADER 28        /* bytes of an event header */
/* Longest channel accepted. LCM itself publishes at most LCM_MAX_CHANNEL_NAME_LENGTH (63)
 * characters, its eventlog writer takes any length; 255 leaves room without letting a garbage
 * header pass for an event. */
#define RP_LCMLOG_CHANNEL_MAX 255
#define RP_LCMLOG_ERR_MAX 512

typedef struct {
    int64_t offset;       /* byte offset of the event's header in the file */
    int64_t eventnum;     /* as written (not checked: concatenated logs restart it) */
    int64_t timestamp;    /* us, as written */
    const char *channel;  /* channellen bytes and a NUL; valid until the next rp_lcmlog_next */
    int32_t channellen;
    const uint8_t *data;  /* datalen bytes; valid until the next rp_lcmlog_next */
    int32_t datalen;
} rp_lcmlog_event_t;

typedef struct {
    FILE *f;
    int own;              /* f opened by rp_lcmlog_open: closed by rp_lcmlog_close */
    char name[256];       /* the file's name in messages */
    int64_t origin;       /* where the log starts in f (0 for a file) */
    int64_t size;         /* bytes in the log when opened */
    int64_t off;          /* offset of the next event header */
    int tolerant;         /* skip bad stretches (warn) instead of failing */
    int failed;           /* a strict read failed: every later call fails too */
    FILE *warn;           /* tolerant: one line per skip goes here (NULL: counted only) */
    const char *prog;     /* prefix of warning lines ("rigpose-eval"), may be NULL */
    int64_t n_events;     /* events returned */
    int64_t n_skips;      /* tolerant: bad stretches skipped */
    int64_t skipped;      /* tolerant: bytes skipped */
    char *chan;           /* the current event's channel */
    uint8_t *data;        /* the current event's data */
    size_t chan_cap, data_cap;
    char err[RP_LCMLOG_ERR_MAX]; /* the error of a failing call: "FILE: offset N: what" */
} rp_lcmlog_t;

/* Opens the log at path (a regular file). 0, or -1 with log->err ("FILE: why"); either way
 * rp_lcmlog_close releases it. tolerant: see above. */
int rp_lcmlog_open(rp_lcmlog_t *log, const char *path, int tolerant);
/* The same over an open seekable stream (e.g. fmemopen), read from its current start to its
 * end; name stands for the file in messages. The stream stays the caller's. */
int rp_lcmlog_open_stream(rp_lcmlog_t *log, FILE *f, const char *name, int tolerant);

/* The next event into *ev. 1: an event; 0: the end of the log (exactly at the end of the last
 * event, or after skipping to the end when tolerant); -1: a bad event header or a read error,
 * log->err "FILE: offset N: what" (one line); the reader then stays at that error. */
int rp_lcmlog_next(rp_lcmlog_t *log, rp_lcmlog_event_t *ev);

void rp_lcmlog_close(rp_lcmlog_t *log);

#ifdef __cplusplus
}
#endif

#endif /* RP_LCMLOG_H */
