/*
 * test_lcmlog.c - the LCM log reader (rp_lcmlog.h) on logs the test writes: what liblcm writes
 * reads back the same; a data length of 0x7fffffff, a truncated log, garbage between events, bad
 * lengths each fail with one line naming the byte offset; read tolerantly, the events after the
 * garbage come back and the bytes skipped are counted and said.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>
#include <lcm/eventlog.h>

#include "rp_lcmlog.h"

/* A log in memory. */
typedef struct {
    uint8_t b[4096];
    size_t n;
    size_t at[8]; /* offset of each event written */
    int n_ev;
} buf_t;

static void put32(buf_t *b, uint32_t v)
{
    for (int i = 3; i >= 0; i--) {
        b->b[b->n++] = (uint8_t)(v >> (8 * i));
    }
}

static void put64(buf_t *b, uint64_t v)
{
    put32(b, (uint32_t)(v >> 32));
    put32(b, (uint32_t)v);
}

/* Event k: channel "CH<k>", data k+3 bytes of value k. */
static void put_event(buf_t *b, int k)
{
    char ch[8];
    snprintf(ch, sizeof ch, "CH%d", k);
    b->at[b->n_ev++] = b->n;
    put32(b, RP_LCMLOG_SYNC);
    put64(b, (uint64_t)k);
    put64(b, 1000u * (uint64_t)k);
    put32(b, (uint32_t)strlen(ch));
    put32(b, (uint32_t)k + 3u);
    memcpy(b->b + b->n, ch, strlen(ch));
    b->n += strlen(ch);
    memset(b->b + b->n, k, (size_t)k + 3u);
    b->n += (size_t)k + 3u;
}

static void put_bytes(buf_t *b, uint8_t v, size_t n)
{
    memset(b->b + b->n, v, n);
    b->n += n;
}

/* Reads the whole log; returns the events read, *last the final return (0 end, -1 error). */
static int read_all(const buf_t *b, int tolerant, rp_lcmlog_t *log, int *last, FILE *warn)
{
    FILE *f = fmemopen((void *)b->b, b->n ? b->n : 1, "rb");
    assert_non_null(f);
    if (b->n == 0) { /* fmemopen needs one byte: an empty log is a stream at its end */
        fseek(f, 1, SEEK_SET);
    }
    assert_int_equal(rp_lcmlog_open_stream(log, f, "mem.log", tolerant), 0);
    log->warn = warn;
    log->prog = "test";
    rp_lcmlog_event_t ev;
    int n = 0, r;
    while ((r = rp_lcmlog_next(log, &ev)) > 0) {
        char ch[8];
        snprintf(ch, sizeof ch, "CH%d", (int)ev.eventnum);
        assert_string_equal(ev.channel, ch);
        assert_int_equal(ev.datalen, ev.eventnum + 3);
        assert_int_equal(ev.timestamp, 1000 * ev.eventnum);
        for (int i = 0; i < ev.datalen; i++) {
            assert_int_equal(ev.data[i], (uint8_t)ev.eventnum);
        }
        n++;
    }
    *last = r;
    rp_lcmlog_close(log);
    fclose(f);
    return n;
}

static void assert_one_line_at(const char *err, size_t offset)
{
    char want[64];
    snprintf(want, sizeof want, "mem.log: offset %zu: ", offset);
    if (strncmp(err, want, strlen(want)) != 0) {
        fail_msg("error '%s' does not start with '%s'", err, want);
    }
    assert_null(strchr(err, '\n'));
}

static void test_clean_log(void **state)
{
    (void)state;
    buf_t b = {0};
    for (int k = 0; k < 4; k++) {
        put_event(&b, k);
    }
    rp_lcmlog_t log;
    int last;
    assert_int_equal(read_all(&b, 0, &log, &last, NULL), 4);
    assert_int_equal(last, 0);
    b.n = 0;
    assert_int_equal(read_all(&b, 0, &log, &last, NULL), 0); /* empty: no events, no error */
    assert_int_equal(last, 0);
}

/* What liblcm writes, this reader reads back event for event. */
static void test_liblcm_written(void **state)
{
    (void)state;
    char path[] = "/tmp/rp_lcmlog_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    lcm_eventlog_t *w = lcm_eventlog_create(path, "w");
    assert_non_null(w);
    uint8_t data[300];
    for (int i = 0; i < 300; i++) {
        data[i] = (uint8_t)(i * 7);
    }
    for (int k = 0; k < 5; k++) {
        lcm_eventlog_event_t ev;
        memset(&ev, 0, sizeof ev);
        ev.timestamp = 123456789 + k;
        ev.channel = (char *)"RIGPOSE_POSE";
        ev.channellen = 12;
        ev.datalen = 60 * k;
        ev.data = data;
        assert_int_equal(lcm_eventlog_write_event(w, &ev), 0);
    }
    lcm_eventlog_destroy(w);
    rp_lcmlog_t log;
    assert_int_equal(rp_lcmlog_open(&log, path, 0), 0);
    rp_lcmlog_event_t ev;
    for (int k = 0; k < 5; k++) {
        assert_int_equal(rp_lcmlog_next(&log, &ev), 1);
        assert_int_equal(ev.eventnum, k);
        assert_int_equal(ev.timestamp, 123456789 + k);
        assert_string_equal(ev.channel, "RIGPOSE_POSE");
        assert_int_equal(ev.datalen, 60 * k);
        assert_memory_equal(ev.data, data, (size_t)ev.datalen);
    }
    assert_int_equal(rp_lcmlog_next(&log, &ev), 0);
    rp_lcmlog_close(&log);
    unlink(path);
}

/* The header of event 2 claims 0x7fffffff bytes of data (liblcm reads into NULL). */
static void test_huge_length(void **state)
{
    (void)state;
    buf_t b = {0};
    for (int k = 0; k < 4; k++) {
        put_event(&b, k);
    }
    const size_t at = b.at[2];
    b.b[at + 24] = 0x7f;
    b.b[at + 25] = b.b[at + 26] = b.b[at + 27] = 0xff;
    rp_lcmlog_t log;
    int last;
    assert_int_equal(read_all(&b, 0, &log, &last, NULL), 2);
    assert_int_equal(last, -1);
    assert_one_line_at(log.err, at);
    assert_non_null(strstr(log.err, "2147483647"));
    /* tolerant: event 2 is lost (its header lies), event 3 comes back */
    assert_int_equal(read_all(&b, 1, &log, &last, NULL), 3);
    assert_int_equal(last, 0);
    assert_int_equal(log.n_skips, 1);
    assert_int_equal(log.skipped, (int64_t)(b.at[3] - at));
}

/* Cut in the middle of event 2's data, and in the middle of its header. */
static void test_truncated(void **state)
{
    (void)state;
    buf_t b = {0};
    for (int k = 0; k < 3; k++) {
        put_event(&b, k);
    }
    const size_t full = b.n, at = b.at[2];
    rp_lcmlog_t log;
    int last;
    b.n = full - 2;
    assert_int_equal(read_all(&b, 0, &log, &last, NULL), 2);
    assert_int_equal(last, -1);
    assert_one_line_at(log.err, at);
    assert_non_null(strstr(log.err, "truncated"));
    b.n = at + 10;
    assert_int_equal(read_all(&b, 0, &log, &last, NULL), 2);
    assert_int_equal(last, -1);
    assert_one_line_at(log.err, at);
    assert_non_null(strstr(log.err, "truncated event header (10 of 28 bytes)"));
    /* tolerant: the two whole events, the tail skipped and counted */
    char said[512] = "";
    FILE *warn = fmemopen(said, sizeof said, "w");
    assert_int_equal(read_all(&b, 1, &log, &last, warn), 2);
    fclose(warn);
    assert_int_equal(last, 0);
    assert_int_equal(log.skipped, 10);
    assert_non_null(strstr(said, "skipped the last 10 bytes"));
}

/* 37 bytes of garbage between events 1 and 2, one of them a false sync word. */
static void test_garbage(void **state)
{
    (void)state;
    buf_t b = {0};
    put_event(&b, 0);
    put_event(&b, 1);
    const size_t at = b.n;
    put_bytes(&b, 0x55, 13);
    put32(&b, RP_LCMLOG_SYNC); /* followed by lengths that do not fit: not an event */
    put_bytes(&b, 0xff, 20);
    put_event(&b, 2);
    put_event(&b, 3);
    rp_lcmlog_t log;
    int last;
    assert_int_equal(read_all(&b, 0, &log, &last, NULL), 2);
    assert_int_equal(last, -1);
    assert_one_line_at(log.err, at);
    assert_non_null(strstr(log.err, "sync word 0x55555555"));
    char said[512] = "";
    FILE *warn = fmemopen(said, sizeof said, "w");
    assert_int_equal(read_all(&b, 1, &log, &last, warn), 4);
    fclose(warn);
    assert_int_equal(last, 0);
    assert_int_equal(log.n_skips, 1);
    assert_int_equal(log.skipped, 37);
    char want[160];
    snprintf(want, sizeof want, "test: mem.log: offset %zu: no event header (sync word 0x55555555, "
             "want 0xEDA1DA01); skipped 37 bytes to the next event at offset %zu\n", at, b.at[2]);
    assert_string_equal(said, want);
}

static void test_bad_lengths(void **state)
{
    (void)state;
    const struct {
        int byte;       /* header byte overwritten */
        uint32_t value; /* with this big-endian int32 */
        const char *why;
    } cases[] = {
        {20, 0, "channel length 0 outside 1..255"},
        {20, 256, "channel length 256 outside 1..255"},
        {20, 0x80000000u, "channel length -2147483648"},
        {24, 0xffffffffu, "data length -1 is negative"},
        {24, 1000, "but only"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        buf_t b = {0};
        put_event(&b, 0);
        put_event(&b, 1);
        uint8_t *p = b.b + b.at[1] + cases[c].byte;
        for (int i = 0; i < 4; i++) {
            p[i] = (uint8_t)(cases[c].value >> (24 - 8 * i));
        }
        rp_lcmlog_t log;
        int last;
        assert_int_equal(read_all(&b, 0, &log, &last, NULL), 1);
        assert_int_equal(last, -1);
        assert_one_line_at(log.err, b.at[1]);
        if (strstr(log.err, cases[c].why) == NULL) {
            fail_msg("case %zu: '%s' lacks '%s'", c, log.err, cases[c].why);
        }
    }
}

static void test_open_errors(void **state)
{
    (void)state;
    rp_lcmlog_t log;
    assert_int_equal(rp_lcmlog_open(&log, "/nonexistent/x.log", 0), -1);
    assert_non_null(strstr(log.err, "/nonexistent/x.log: No such file"));
    rp_lcmlog_event_t ev;
    assert_int_equal(rp_lcmlog_next(&log, &ev), -1);
    rp_lcmlog_close(&log);
    assert_int_equal(rp_lcmlog_open(&log, "/tmp", 0), -1);
    assert_string_equal(log.err, "/tmp: not a regular file");
    rp_lcmlog_close(&log);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clean_log),    cmocka_unit_test(test_liblcm_written),
        cmocka_unit_test(test_huge_length),  cmocka_unit_test(test_truncated),
        cmocka_unit_test(test_garbage),      cmocka_unit_test(test_bad_lengths),
        cmocka_unit_test(test_open_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
