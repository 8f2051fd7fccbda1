#!/usr/bin/env python3
"""restamp.py SRC OUT NAME LEAD_S TAG [METHOD] - a rendered replay (rigpose-render's folder SRC)
made a live run for rigpose-frontend and the daemon, with METHOD gc (default: the four single
cameras; the stereo partners cam1b, cam3b left out of the rig, so that no process reads images
nobody uses) or stereo4 (the render's own: both pairs, six cameras):

  OUT/NAME_frames.csv   SRC's frames, restamped to start LEAD_S seconds from now on this host's
                        CLOCK_MONOTONIC (Python's time.monotonic), same spacing (per-camera
                        utime_us_<column> times moved alike), absolute paths;
  OUT/NAME_replay.yaml  SRC's rig.yaml on it with source.realtime: live (front ends, and the
                        in-process daemon), timeout_ms 1000;
  OUT/NAME_lcm.yaml     the same with source.kind: lcm (the daemon on the front ends' features);

channels tagged with TAG (features FE_TAG_CAMk, POSE_TAG_NAME, STATUS_TAG_NAME)."""
import os
import re
import sys
import time

src, out, name, lead, tag = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), sys.argv[5]
method = sys.argv[6] if len(sys.argv) > 6 else "gc"
assert method in ("gc", "stereo4"), method
rows = [l.rstrip("\n").split(",") for l in open(os.path.join(src, "frames.csv"))]
t0 = int(time.monotonic() * 1e6 + lead * 1e6)
u0 = int(rows[1][0])
csv = os.path.join(out, name + "_frames.csv")
# time columns (utime_us, and each camera's utime_us_<column> when the cameras are stamped
# apart) move by the same offset; the others are image paths
is_time = [h == "utime_us" or h.startswith("utime_us_") for h in rows[0]]
with open(csv, "w") as f:
    f.write(",".join(rows[0]) + "\n")
    for r in rows[1:]:
        f.write(",".join(str(t0 + int(v) - u0) if t else os.path.join(src, v)
                         for v, t in zip(r, is_time)) + "\n")
y = open(os.path.join(src, "rig.yaml")).read()
y = y.replace("realtime: false", "realtime: live\n  timeout_ms: 1000")
y = y.replace("replay_index: frames.csv", "replay_index: " + csv)
# front ends in their own processes cannot see the estimator's retired tracks (stereo's and
# gc's; config/README.md, dormant_retired): the in-process daemon does as they do
if method == "gc":
    y, n = re.subn(r"method: stereo4\n  pairs: .*\n",
                   "method: gc\n  cams: [cam1, cam2, cam3, cam4]\n  dormant_retired: false\n", y)
    assert n == 1, "rig.yaml: no stereo4 estimator to replace"
    y, n = re.subn(r"  - name: cam[13]b\n(    .*\n)*", "", y)
    assert n == 2, "rig.yaml: cam1b and cam3b not found"
else:
    y, n = re.subn(r"(method: stereo4\n  pairs: .*\n)", r"\1  dormant_retired: false\n", y)
    assert n == 1, "rig.yaml: no stereo4 estimator"
y += "\nlcm: {features_channel: FE_%s_CAM, pose_channel: POSE_%s_%s, status_channel: STATUS_%s_%s}\n" % (
    tag, tag, name, tag, name)
open(os.path.join(out, name + "_replay.yaml"), "w").write(y)
open(os.path.join(out, name + "_lcm.yaml"), "w").write(y.replace("kind: replay", "kind: lcm"))
