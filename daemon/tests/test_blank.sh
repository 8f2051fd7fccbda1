#!/usr/bin/env bash
# test_blank.sh BUILD - the daemon on a replay whose cameras all go blank (issue 18 item 2): a
# rendered replay folder (rigpose-render, 90 sets at 30 Hz, 320x240, stereo4) with every
# camera's image replaced by a uniform grey image in sets 20..64 (1.5 s, longer than the
# estimator's max_predict_s of 1 s); the poses go to an LCM log (file://, nothing on the
# network) and are read back with the lcm-gen Python types. While blank: LOST and never
# TRACKING, no feature counted as used, the published covariance growing at every set, HELD
# once the prediction has run max_predict_s, the position within |v| max_predict_s of the last
# tracked one. After: TRACKING again within 10 sets, every later pose without LOST | TRACKING
# together.
set -u
BUILD=${1:?usage: test_blank.sh BUILD}
. "$(dirname "$0")/../../tests/script_env.sh"

"$REL/rigpose-render" --out "$TMP/src" --frames 90 --width 320 --height 240 --face-px 256 \
    --ss 1 > "$TMP/render.out" 2>&1 || { cat "$TMP/render.out"; echo "FAIL render"; exit 1; }

# Blank: the same file names, one uniform grey image each (written by Python's zlib: a PNG).
"$PY" - "$TMP/src" 20 65 <<'PYEOF' || { echo "FAIL blanking"; exit 1; }
import csv, os, struct, sys, zlib
folder, first, end = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def png(path, w, h, grey):
    raw = b"".join(b"\x00" + bytes([grey]) * w for _ in range(h))
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
rows = [r for r in csv.reader(open(os.path.join(folder, "frames.csv"))) if r and not r[0].startswith("#")]
body = [r for r in rows if r[0].strip().lstrip("-").isdigit()]
n = 0
for j, r in enumerate(body):
    if first <= j < end:
        for p in r[1:]:
            assert p.strip().endswith(".png"), p
            png(os.path.join(folder, p.strip()), 320, 240, 128)
            n += 1
print("blanked", n, "images")
PYEOF

"$REL/rigpose" --config "$TMP/src/rig.yaml" --fast --quiet --lcm-url "file://$TMP/poses.log?mode=w" \
    > "$TMP/daemon.out" 2>&1
rc=$?
cat "$TMP/daemon.out"
[ $rc -eq 0 ] || { echo "FAIL daemon exit $rc"; exit 1; }

"$PY" - "$TMP/poses.log" 20 65 <<'PYEOF'
import math, sys, lcm
from rigpose import pose_t
log, first, end = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
P = [pose_t.decode(ev.data) for ev in lcm.EventLog(log, "r") if ev.channel == "RIGPOSE_POSE"]
L, T, H = pose_t.FLAG_LOST, pose_t.FLAG_TRACKING, pose_t.FLAG_HELD
fails = []
def check(name, ok):
    print(("ok   " if ok else "FAIL ") + name)
    if not ok:
        fails.append(name)
check("90 poses in the log (%d)" % len(P), len(P) == 90)
last = P[first - 1]
check("tracking before the blank sets (set %d flags %d)" % (first - 1, last.flags), last.flags & T)
v = math.sqrt(sum(x * x for x in last.velocity))
tr = lambda p: p.covariance[0] + p.covariance[7] + p.covariance[14]
blank = P[first:end]
check("blank sets: all LOST, none TRACKING",
      all(p.flags & L and not p.flags & T for p in blank))
check("blank sets: no feature used", all(sum(p.features_used) == 0 for p in blank))
grow = all(tr(b) > tr(a) for a, b in zip([last] + blank[:-1], blank))
check("blank sets: covariance trace grows every set (%.3g -> %.3g m^2)" % (tr(last), tr(blank[-1])), grow)
held = [j for j, p in enumerate(blank) if p.flags & H]
check("HELD from about 1 s of blank on (first at blank set %s)" % (held[0] if held else None),
      held and 28 <= held[0] <= 32 and held == list(range(held[0], len(blank))))
dmax = max(math.dist(p.position, last.position) for p in blank)
check("position bounded: %.4f m from the last tracked, |v| x 1 s = %.4f m" % (dmax, v * 1.04),
      dmax <= v * 1.04 + 1e-6)
after = P[end:]
firstT = next((j for j, p in enumerate(after) if p.flags & T), None)
check("tracking again %s sets after the images return" % firstT, firstT is not None and firstT < 10)
check("never LOST and TRACKING together", all(not (p.flags & L and p.flags & T) for p in P))
sys.exit(1 if fails else 0)
PYEOF
