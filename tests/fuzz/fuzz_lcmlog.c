/*
 * fuzz_lcmlog.c - libFuzzer target: the LCM log reader of rigpose-eval and rigpose-log
 * (host_tools/common/rp_lcmlog.c) on any bytes as a log file (through fmemopen), strictly and
 * tolerantly. Checks what the reader promises: every event lies inside the file, after the
 * previous one, with the lengths its header gave; a strict read ends at the end or with one line
 * naming an offset; a tolerant read never fails and accounts for every byte (events + skipped).
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "rp_lcmlog.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void read_log(const uint8_t *data, size_t size, int tolerant)
{
    FILE *f = fmemopen((void *)data, size, "rb");
    if (f == NULL) {
        return;
    }
    rp_lcmlog_t log;
    if (rp_lcmlog_open_stream(&log, f, "fuzz.log", tolerant) != 0) {
        __builtin_trap();
    }
    rp_lcmlog_event_t ev;
    int64_t end = 0, bytes = 0;
    int r;
    while ((r = rp_lcmlog_next(&log, &ev)) > 0) {
        const int64_t n = RP_LCMLOG_HEADER + (int64_t)ev.channellen + ev.datalen;
        if (ev.offset < end || ev.offset + n > (int64_t)size || ev.channellen < 1 ||
            ev.channellen > RP_LCMLOG_CHANNEL_MAX || ev.datalen < 0 ||
            ev.channel[ev.channellen] != '\0' ||
            memcmp(ev.channel, data + ev.offset + RP_LCMLOG_HEADER, (size_t)ev.channellen) != 0 ||
            (ev.datalen > 0 && memcmp(ev.data, data + ev.offset + RP_LCMLOG_HEADER +
                                                   ev.channellen, (size_t)ev.datalen) != 0)) {
            __builtin_trap();
        }
        end = ev.offset + n;
        bytes += n;
    }
    if (r < 0 && (tolerant || strstr(log.err, "fuzz.log: offset ") != log.err ||
                  strchr(log.err, '\n') != NULL)) {
        __builtin_trap();
    }
    if (tolerant && bytes + log.skipped != (int64_t)size) {
        __builtin_trap();
    }
    rp_lcmlog_close(&log);
    fclose(f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) {
        return 0; /* fmemopen refuses a zero-byte buffer */
    }
    read_log(data, size, 0);
    read_log(data, size, 1);
    return 0;
}
