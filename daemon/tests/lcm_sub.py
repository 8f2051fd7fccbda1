#!/usr/bin/env python3
"""A separate LCM subscriber for the daemon's tests (PyPI `lcm` + the lcm-gen Python types).

Subscribes to the pose (and status) channels, touches --ready once subscribed, and checks:
  - exactly --expect poses arrive, with seq 0, 1, ..., expect-1 in that order (no gap, no
    repeat), each a unit quaternion matching its angles (R = Rz(gamma) Ry(beta) Rx(alpha)), a
    symmetric covariance, and (with the sim) a position within --max-err-m of the truth;
  - with --expect-gone CAM: some status message reports camera CAM gone, and poses keep coming
    after it (at least 10 more).
Exit 0 when every check holds, 1 otherwise (the reason printed); 2 on timeout.
"""
import argparse
import math
import os
import sys
import time

import lcm
from rigpose import pose_t, status_t


def quat_of_angles(a, b, g):
    """Unit quaternion (w, x, y, z) of Rz(g) Ry(b) Rx(a), w >= 0."""
    ca, sa = math.cos(a / 2), math.sin(a / 2)
    cb, sb = math.cos(b / 2), math.sin(b / 2)
    cg, sg = math.cos(g / 2), math.sin(g / 2)
    q = (cg * cb * ca + sg * sb * sa, cg * cb * sa - sg * sb * ca,
         cg * sb * ca + sg * cb * sa, sg * cb * ca - cg * sb * sa)
    return q if q[0] >= 0 else tuple(-x for x in q)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--url", required=True)
    ap.add_argument("--pose-channel", required=True)
    ap.add_argument("--status-channel")
    ap.add_argument("--expect", type=int, required=True)
    ap.add_argument("--expect-gone", type=int, default=-1)
    ap.add_argument("--max-err-m", type=float, default=0.01)
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--ready")
    a = ap.parse_args()

    poses, problems = [], []
    gone_at = [None]  # pose count when the status first said the camera was gone
    n_status = [0]

    def on_pose(channel, data):
        m = pose_t.decode(data)
        poses.append(m)
        i = len(poses) - 1
        if m.seq != i:
            problems.append("pose %d has seq %d" % (i, m.seq))
        qn = math.sqrt(sum(x * x for x in m.quaternion))
        if abs(qn - 1) > 1e-9:
            problems.append("seq %d: |q| = %.12f" % (m.seq, qn))
        qa = quat_of_angles(*m.angles)
        if max(abs(x - y) for x, y in zip(qa, m.quaternion)) > 1e-6:
            problems.append("seq %d: quaternion %s does not match angles %s"
                            % (m.seq, m.quaternion, m.angles))
        c = m.covariance
        if any(abs(c[6 * r + k] - c[6 * k + r]) > 1e-12 * (1 + abs(c[6 * r + k]))
               for r in range(6) for k in range(6)):
            problems.append("seq %d: covariance not symmetric" % m.seq)
        if m.has_truth:
            e = math.sqrt(sum((m.position[k] - m.truth[k]) ** 2 for k in range(3)))
            if e > a.max_err_m:
                problems.append("seq %d: position %.4f m off the truth" % (m.seq, e))

    def on_status(channel, data):
        m = status_t.decode(data)
        n_status[0] += 1
        if (a.expect_gone >= 0 and gone_at[0] is None
                and m.cam_state[a.expect_gone] & status_t.CAM_GONE):
            gone_at[0] = len(poses)
            print("status %d: camera %d gone (fps %.1f, drops %d), latest pose seq %d"
                  % (m.seq, a.expect_gone, m.fps[a.expect_gone], m.drops[a.expect_gone],
                     m.last_pose_seq))

    lc = lcm.LCM(a.url)
    lc.subscribe(a.pose_channel, on_pose)
    if a.status_channel:
        lc.subscribe(a.status_channel, on_status)
    if a.ready:
        open(a.ready, "w").close()

    deadline = time.monotonic() + a.timeout
    while len(poses) < a.expect and time.monotonic() < deadline:
        lc.handle_timeout(100)
    # Anything beyond the expected count is a problem too: drain briefly.
    end = time.monotonic() + 0.3
    while time.monotonic() < end:
        lc.handle_timeout(50)

    print("received %d poses (expected %d), %d status messages"
          % (len(poses), a.expect, n_status[0]))
    if len(poses) < a.expect:
        print("FAIL: timed out after %.0f s" % a.timeout)
        return 2
    if len(poses) > a.expect:
        problems.append("%d poses, more than expected" % len(poses))
    if a.expect_gone >= 0:
        if gone_at[0] is None:
            problems.append("no status reported camera %d gone" % a.expect_gone)
        elif len(poses) - gone_at[0] < 10:
            problems.append("only %d poses after camera %d went" % (len(poses) - gone_at[0],
                                                                    a.expect_gone))
    for p in problems[:10]:
        print("FAIL:", p)
    if not problems:
        print("ok: seq 0..%d in order, no gaps" % (len(poses) - 1))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
