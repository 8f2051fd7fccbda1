"""rp_lcmlog.py - the LCM log reader of rp_lcmlog.h for the Python tools (rigpose-view --lcm-log,
which `rigpose-log mcap` runs): the same checks, the same messages.

PyPI lcm's EventLog reads with liblcm's C reader: a data length of 0x7fffffff kills the Python
process with SIGSEGV, a truncated log or garbage between events passes without a word. This reads
the eventlog format itself (28-byte big-endian header: sync word 0xEDA1DA01, event number,
timestamp, channel length, data length; then channel and data) and checks each header against
the bytes left in the file before it reads. The first bad header raises LogError("FILE: offset N:
what"); read tolerantly, it skips to the next sync word that starts a plausible event (or to the
end) and writes one line per skip to `warn`.
"""
import os
import struct

SYNC = 0xEDA1DA01
HEADER = 28
CHANNEL_MAX = 255  # as rp_lcmlog.h: LCM publishes at most 63, its eventlog writer takes any
_SYNC_BYTES = struct.pack(">I", SYNC)


class LogError(Exception):
    """A truncated or corrupt log: str() is "FILE: offset N: what", one line."""


def _bad_header(hd, left):
    """Why the header hd (28 bytes) with `left` bytes from its start is not an event, or None."""
    sync, _, _, cl, dl = struct.unpack(">Iqqii", hd)
    if sync != SYNC:
        return "no event header (sync word 0x%08x, want 0x%08X)" % (sync, SYNC)
    if cl < 1 or cl > CHANNEL_MAX:
        return "channel length %d outside 1..%d" % (cl, CHANNEL_MAX)
    if dl < 0:
        return "data length %d is negative" % dl
    need = HEADER + cl + dl
    if need > left:
        return ("event of %d bytes (channel %d, data %d) but only %d bytes left in the file: "
                "truncated or corrupt" % (need, cl, dl, left))
    return None


def _resync(f, frm, size):
    """Offset of the first sync word after frm that starts a plausible event, or size."""
    pos = frm + 1
    chunk = 65536
    while pos + HEADER <= size:
        f.seek(pos)
        buf = f.read(min(chunk, size - pos))
        i = buf.find(_SYNC_BYTES)
        while i >= 0:
            at = pos + i
            if at + HEADER <= size:
                f.seek(at)
                if _bad_header(f.read(HEADER), size - at) is None:
                    return at
            i = buf.find(_SYNC_BYTES, i + 1)
        if len(buf) < chunk:
            break
        pos += len(buf) - 3  # a sync word across the chunk boundary
    return size


def events(path, tolerant=False, warn=None, prog=None, with_data=True):
    """Yields (offset, eventnum, timestamp_us, channel, data) of each event of the log at path
    (data None without with_data). Raises LogError on the first bad event (strict), OSError if
    the file cannot be read."""
    if not os.path.isfile(path):
        raise LogError("%s: %s" % (path, "not a regular file" if os.path.exists(path)
                                   else "No such file or directory"))
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        off = 0
        while off < size:
            left = size - off
            if left < HEADER:
                bad = "truncated event header (%d of %d bytes)" % (left, HEADER)
            else:
                f.seek(off)
                hd = f.read(HEADER)
                bad = _bad_header(hd, left)
            if bad is not None:
                if not tolerant:
                    raise LogError("%s: offset %d: %s" % (path, off, bad))
                nxt = _resync(f, off, size)
                if warn is not None:
                    tail = ("skipped %d bytes to the next event at offset %d" % (nxt - off, nxt)
                            if nxt < size else "skipped the last %d bytes" % (nxt - off))
                    warn.write("%s%s: offset %d: %s; %s\n" % (prog + ": " if prog else "", path,
                                                              off, bad, tail))
                off = nxt
                continue
            _, num, ts, cl, dl = struct.unpack(">Iqqii", hd)
            channel = f.read(cl).decode("utf-8", "replace")
            data = f.read(dl) if with_data else None
            yield off, num, ts, channel, data
            off += HEADER + cl + dl


def check(path):
    """Raises LogError if the log at path is truncated or corrupt (reads the headers only)."""
    for _ in events(path, with_data=False):
        pass
