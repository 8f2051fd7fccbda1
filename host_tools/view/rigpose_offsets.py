#!/usr/bin/env python3
"""rigpose-offsets - the cameras' clock offsets the daemon holds, printed and written back.

Reads the latest rigpose.status_t (cam_offset_ms, cam_offset_sigma_ms: docs/time.md) of a
recorded LCM log (--lcm-log FILE: the daemon's file:// URL, lcm-logger) or of a running daemon
(--lcm-url URL, default LCM's; waits at most --timeout s for one), or the offsets
rigpose-timesync found from the rig's rotation (--timesync-json FILE), prints one line per camera
and, with --write CONFIG, sets each estimated camera's `time_offset_s` in the configuration file
(cameras[i], in order; a camera whose offset is not estimated, sigma 0, is left as it is unless
--all). The file is edited line by line, comments and layout kept: an existing `time_offset_s:`
line of the camera is replaced, else one is added after its `name:` line. The daemon then starts
from these values (with estimator.estimate_time_offsets, as its estimates' start).

Exit status: 0; 1 no status message (or none with offsets) / a log or file that cannot be read;
2 bad arguments.
"""
import argparse
import os
import re
import sys

import lcm

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import rp_lcmlog  # noqa: E402  (host_tools/common/, beside this tool's folder)

try:
    from rigpose import status_t
except ImportError:  # the build's generated package beside this tool's folder
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                    "..", "..", "build", "lcmgen", "python"))
    from rigpose import status_t


def latest_from_log(path, channel):
    last = None
    for _, _, _, ch, data in rp_lcmlog.events(path):
        if ch == channel:
            last = status_t.decode(data)
    return last


def first_live(url, channel, timeout_s):
    lc = lcm.LCM(url) if url else lcm.LCM()
    got = []
    sub = lc.subscribe(channel, lambda ch, data: got.append(status_t.decode(data)))
    left = timeout_s
    while not got and left > 0:
        lc.handle_timeout(100)
        left -= 0.1
    lc.unsubscribe(sub)
    return got[0] if got else None


def set_offsets(text, offsets):
    """text with cameras[i].time_offset_s = offsets[i] (s) for each i in offsets."""
    lines = text.split("\n")
    out, in_cams, cam, item_indent = [], False, -1, None
    pending = {}  # camera index -> its value, until its item ends

    def close_item():
        if cam in pending:  # no time_offset_s line in the item: after its name line
            at, ind = name_at[cam]
            out.insert(at + 1, "%stime_offset_s: %s" % (" " * ind, fmt(pending.pop(cam))))

    name_at = {}
    for line in lines:
        stripped = line.strip()
        indent = len(line) - len(line.lstrip(" "))
        if re.match(r"^cameras:\s*(#.*)?$", line):
            in_cams = True
            out.append(line)
            continue
        if in_cams and stripped and not stripped.startswith("#") and indent == 0:
            close_item()
            in_cams = False
        if in_cams and re.match(r"^\s*-\s", line):
            close_item()
            cam += 1
            item_indent = indent + 2
            if cam in offsets:
                pending[cam] = offsets[cam]
            m = re.match(r"^(\s*-\s+)name:", line)
            if m:
                name_at[cam] = (len(out), len(m.group(1)))
            out.append(line)
            continue
        if in_cams and cam >= 0:
            if re.match(r"^\s*name:", line) and indent == item_indent:
                name_at[cam] = (len(out), indent)
            if re.match(r"^\s*time_offset_s:", line) and indent == item_indent and cam in pending:
                comment = re.search(r"\s+#.*$", line)
                line = "%stime_offset_s: %s%s" % (" " * indent, fmt(pending.pop(cam)),
                                                  comment.group(0) if comment else "")
        out.append(line)
    if in_cams:
        close_item()
    return "\n".join(out)


def fmt(v):
    return "%.6f" % v


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--lcm-log", metavar="FILE", help="a recorded LCM log")
    src.add_argument("--lcm-url", metavar="URL", help="a running daemon's LCM URL")
    src.add_argument("--timesync-json", metavar="FILE",
                     help="the offsets rigpose-timesync found (its --json-out)")
    ap.add_argument("--channel", default="RIGPOSE_STATUS", help="status channel (RIGPOSE_STATUS)")
    ap.add_argument("--timeout", type=float, default=5.0, help="live: seconds to wait (5)")
    ap.add_argument("--write", metavar="CONFIG", help="set cameras[i].time_offset_s in CONFIG")
    ap.add_argument("--all", action="store_true", help="also the cameras not estimated")
    a = ap.parse_args()
    if a.timesync_json:
        try:
            offsets = from_timesync(a.timesync_json, a.all)
        except (OSError, ValueError, KeyError, TypeError) as e:
            print("rigpose-offsets: %s: %s" % (a.timesync_json, e), file=sys.stderr)
            return 1
        return write_offsets(a.write, offsets)
    try:
        m = (latest_from_log(a.lcm_log, a.channel) if a.lcm_log
             else first_live(a.lcm_url, a.channel, a.timeout))
    except (rp_lcmlog.LogError, OSError) as e:
        print("rigpose-offsets: %s" % e, file=sys.stderr)
        return 1
    if m is None:
        print("rigpose-offsets: no status message on %s" % a.channel, file=sys.stderr)
        return 1
    offsets = {}
    for k in range(max(0, min(m.n_cams, 6))):
        est = m.cam_offset_sigma_ms[k] > 0.0
        print("camera %d: offset %+.3f ms, sigma %s" % (
            k, m.cam_offset_ms[k], "%.3f ms" % m.cam_offset_sigma_ms[k] if est
            else "- (not estimated)"))
        if est or a.all:
            offsets[k] = m.cam_offset_ms[k] * 1e-3
    return write_offsets(a.write, offsets)


def from_timesync(path, all_cams):
    """{camera index: offset s} from rigpose-timesync's JSON; the first camera (the reference,
    its configured offset) only with all_cams; a camera it could not tell (null) never."""
    import json
    with open(path) as f:
        d = json.load(f)
    offsets = {}
    for k, (name, off, sd) in enumerate(zip(d["cameras"], d["time_offset_s"], d["sigma_s"])):
        if off is None:
            print("camera %d (%s): not found by rigpose-timesync, left as it is" % (k, name))
            continue
        print("camera %d (%s): offset %+.3f ms, sigma %s" % (
            k, name, off * 1e3, "%.3f ms" % (sd * 1e3) if k else "- (the reference)"))
        if k or all_cams:
            offsets[k] = float(off)
    return offsets


def write_offsets(path, offsets):
    """Set cameras[k].time_offset_s = offsets[k] in the configuration file path (if given)."""
    if not path:
        return 0
    if not offsets:
        print("rigpose-offsets: no estimated offset to write (--all writes them all)",
              file=sys.stderr)
        return 1
    try:
        with open(path) as f:
            text = f.read()
        new = set_offsets(text, offsets)
        with open(path, "w") as f:
            f.write(new)
    except OSError as e:
        print("rigpose-offsets: %s" % e, file=sys.stderr)
        return 1
    print("rigpose-offsets: %s: time_offset_s of camera%s %s" % (
        path, "s" if len(offsets) > 1 else "", ", ".join(str(k) for k in sorted(offsets))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
