#!/usr/bin/env bash
# soak.sh BUILD N_FEAT N_IMG [OUT_JSON] - the release daemon run long, as fast as it goes
# (issue 18 item 8):
#   1. N_FEAT feature-level frame sets of the simulated rig on the turn (source.sim.motion:
#      turn, a turn on the spot with a wobble: it stays inside the scene for any length, where
#      the paper's random walk leaves it), stereo4;
#   2. N_IMG image-level frame sets: a rendered frame set of the six-camera rig (320x240)
#      replayed N_IMG times at 30 Hz stamps (a rig standing still), stereo4, through the
#      replay source, trackers and stereo matcher.
# Poses go to an LCM log (file://: nothing on the network, nothing lost to a slow reader); the
# daemon's resident set size is sampled every 0.02 s from /proc. Fails on: an exit other than
# 0, a pose count other than asked, a gap in seq, a non-finite pose or covariance, any LOST or
# COV_RESET flag (neither has a cause on these runs), resident memory growing by 1 % or more
# after the warm-up (the first fifth of the run's frame sets, told by the size of the pose log
# at each sample, not by time: a slow start on a loaded machine does not move memory that the
# early frame sets touch past it), compared with the largest sample of the warm-up's end.
# Prints the figures; OUT_JSON (optional) receives soak_frames, soak_image_frames,
# soak_rss_growth_pct (the larger of the two runs), soak_sets_per_s.
set -u
BUILD=${1:?usage: soak.sh BUILD N_FEAT N_IMG [OUT_JSON]}
N_FEAT=${2:?N_FEAT}
N_IMG=${3:?N_IMG}
OUT=${4:-}
. "$(dirname "$0")/../script_env.sh"
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$TMP"' EXIT
fail=0

# run NAME CONFIG N: the daemon with its RSS sampled; leaves $TMP/NAME.{log,rss,out,rc,secs}
run() {
  local name=$1 cfg=$2 n=$3
  local t0; t0=$(date +%s.%N)
  "$REL/rigpose" --config "$cfg" --frames "$n" --fast --quiet \
      --lcm-url "file://$TMP/$name.log?mode=w" >"$TMP/$name.out" 2>&1 &
  local pid=$!
  : >"$TMP/$name.rss"
  while kill -0 $pid 2>/dev/null; do
    # RSS (kB) and the pose log's size (bytes: frame sets done) at the same moment
    echo "$(awk '/^VmRSS:/ {print $2}' /proc/$pid/status 2>/dev/null)" \
         "$(stat -c %s "$TMP/$name.log" 2>/dev/null || echo 0)" >>"$TMP/$name.rss"
    sleep 0.02
  done
  wait $pid; echo $? >"$TMP/$name.rc"
  echo "$(date +%s.%N) - $t0" | bc >"$TMP/$name.secs"
}

# check NAME N: the log and the RSS samples; prints one line, sets fail; echoes growth %
check() {
  local name=$1 n=$2
  "$PY" - "$TMP/$name.log" "$TMP/$name.rss" "$n" "$(cat "$TMP/$name.rc")" \
      "$(cat "$TMP/$name.secs")" "$name" >"$TMP/$name.res" <<'PYEOF'
import math, sys, lcm
from rigpose import pose_t
log, rss_file, n, rc, secs, name = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]), sys.argv[6]
bad = []
count, expect_seq, gaps, nonfinite, lost, covreset = 0, 0, 0, 0, 0, 0
for ev in lcm.EventLog(log, "r"):
    if ev.channel != "RIGPOSE_POSE":
        continue
    p = pose_t.decode(ev.data)
    if p.seq != expect_seq:
        gaps += 1
    expect_seq = p.seq + 1
    count += 1
    vals = list(p.position) + list(p.angles) + list(p.quaternion) + list(p.covariance)
    if not all(math.isfinite(v) for v in vals):
        nonfinite += 1
    lost += (p.flags & pose_t.FLAG_LOST) != 0
    covreset += (p.flags & pose_t.FLAG_COV_RESET) != 0
import os
samples = [l.split() for l in open(rss_file) if len(l.split()) == 2]
rss = [int(a) for a, _ in samples]
size = [int(b) for _, b in samples]
total = os.path.getsize(log)
growth = float("nan")
w = sum(1 for b in size if b <= total // 5)  # samples within the first fifth of the sets
if len(rss) >= 10 and 1 <= w < len(rss):
    base = max(rss[max(0, w - 3):w])    # the warm-up's end
    growth = 100.0 * (max(rss[w:]) - base) / base
if rc != 0: bad.append("exit %d" % rc)
if count != n: bad.append("%d poses, not %d" % (count, n))
if gaps: bad.append("%d gaps in seq" % gaps)
if nonfinite: bad.append("%d non-finite poses" % nonfinite)
if lost: bad.append("%d LOST" % lost)
if covreset: bad.append("%d COV_RESET" % covreset)
if not (growth < 1.0): bad.append("RSS growth %.3f %% (samples %d, %d in the warm-up)" % (growth, len(rss), w))
print("%s %s: %d sets in %.1f s (%.0f sets/s), no gap %s, RSS %s kB after warm-up (%d of %d samples) -> max %s kB "
      "(growth %.3f %%), LOST %d, COV_RESET %d, non-finite %d%s" % (
      "ok  " if not bad else "FAIL", name, count, secs, count / secs if secs > 0 else 0,
      gaps == 0, rss[w - 1] if 1 <= w <= len(rss) else "-", w, len(rss), max(rss) if rss else "-",
      growth, lost, covreset, nonfinite, "" if not bad else ": " + "; ".join(bad)))
print("GROWTH %.6f" % growth)
print("RATE %.3f" % (count / secs if secs > 0 else 0))
sys.exit(1 if bad else 0)
PYEOF
  local prc=$?
  grep -v '^GROWTH\|^RATE' "$TMP/$name.res"
  [ $prc -eq 0 ] || { fail=1; cat "$TMP/$name.out"; }
}

# ---- 1. features: the simulated rig on the turn ---------------------------------------------
# status_every: one status per 1000 sets (the log holds the poses; the status is not checked)
with_status_every() { # FILE: sets lcm.status_every 1000 in FILE (an lcm section or not)
  if grep -q '^lcm:' "$1"; then sed -i 's/^lcm:.*/lcm:\n  status_every: 1000/' "$1"
  else printf 'lcm:\n  status_every: 1000\n' >>"$1"; fi
}
sed -e 's/^  realtime: true.*/  realtime: false/' -e 's/^    noise_px: 0.5/    noise_px: 0.5\n    motion: turn/' \
    config/sim.yaml >"$TMP/feat.yaml"
with_status_every "$TMP/feat.yaml"
grep -q 'motion: turn' "$TMP/feat.yaml" || { echo "FAIL could not write the turn's configuration"; exit 1; }
run feat "$TMP/feat.yaml" "$N_FEAT"
check feat "$N_FEAT"

# ---- 2. images: a rendered frame set replayed, the rig standing still -----------------------
"$REL/rigpose-render" --out "$TMP/src" --frames 1 --width 320 --height 240 --face-px 256 \
    --ss 1 >"$TMP/render.out" 2>&1 || { cat "$TMP/render.out"; echo "FAIL render"; exit 1; }
"$PY" - "$TMP/src" "$N_IMG" <<'PYEOF' || { echo "FAIL replay index"; exit 1; }
import os, sys
folder, n = sys.argv[1], int(sys.argv[2])
lines = [l for l in open(os.path.join(folder, "frames.csv")) if l.strip() and not l.startswith("#")]
head, row = lines[0], lines[1].rstrip("\n").split(",")
with open(os.path.join(folder, "soak.csv"), "w") as f:
    f.write(head)
    for j in range(n):
        f.write(",".join([str(j * 33333)] + row[1:]) + "\n")
PYEOF
sed -e 's/^  realtime: true.*/  realtime: false/' -e 's/frames\.csv/soak.csv/' "$TMP/src/rig.yaml" \
    >"$TMP/src/soak.yaml"
grep -q 'soak.csv' "$TMP/src/soak.yaml" || { echo "FAIL could not point the replay at soak.csv"; exit 1; }
with_status_every "$TMP/src/soak.yaml"
run img "$TMP/src/soak.yaml" "$N_IMG"
check img "$N_IMG"

if [ -n "$OUT" ] && [ $fail -eq 0 ]; then
  g1=$(sed -n 's/^GROWTH //p' "$TMP/feat.res"); g2=$(sed -n 's/^GROWTH //p' "$TMP/img.res")
  r1=$(sed -n 's/^RATE //p' "$TMP/feat.res")
  "$PY" -c "import json,sys; json.dump({'soak_frames': $N_FEAT, 'soak_image_frames': $N_IMG, \
'soak_rss_growth_pct': max($g1, $g2), 'soak_sets_per_s': $r1}, open(sys.argv[1], 'w'))" "$OUT"
fi
if [ $fail -eq 0 ]; then echo "[  PASSED  ] soak"; exit 0; fi
echo "[  FAILED  ] soak"; exit 1
