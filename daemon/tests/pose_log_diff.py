"""pose_log_diff.py LOG_A LOG_B [CHANNEL] - are two LCM logs' poses (rigpose.pose_t) the same?

Compares every pose message on CHANNEL (default RIGPOSE_POSE) of two daemon runs field by field,
bit for bit, except what differs between any two runs: publish_utime (wall clock) and instance
(host:pid). Prints the count and the first difference; exit 0 if the logs hold the same
non-empty sequence of poses, 1 otherwise. Needs the lcm-gen Python types on PYTHONPATH
($(BUILD)/lcmgen/python)."""
import sys

import lcm
from rigpose import pose_t

IGNORED = {"publish_utime", "instance"}


def poses(path, channel):
    return [pose_t.decode(ev.data) for ev in lcm.EventLog(path, "r") if ev.channel == channel]


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    channel = sys.argv[3] if len(sys.argv) == 4 else "RIGPOSE_POSE"
    a, b = poses(sys.argv[1], channel), poses(sys.argv[2], channel)
    if not a or len(a) != len(b):
        print("pose_log_diff: %d poses against %d" % (len(a), len(b)))
        return 1
    for i, (x, y) in enumerate(zip(a, b)):
        for f in pose_t.__slots__:
            if f not in IGNORED and getattr(x, f) != getattr(y, f):
                print("pose_log_diff: pose %d (seq %d): %s differs: %r against %r"
                      % (i, x.seq, f, getattr(x, f), getattr(y, f)))
                return 1
    print("pose_log_diff: %d poses, identical" % len(a))
    return 0


if __name__ == "__main__":
    sys.exit(main())
