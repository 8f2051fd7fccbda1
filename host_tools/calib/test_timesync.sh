#!/usr/bin/env bash
# test_timesync.sh - rigpose-timesync (each camera's clock offset from the rig's rotation) end to
# end, run by `make test`:
#  1. a rendered replay (rigpose-render, smooth motion, 320x240, 100 sets) whose cam1b images
#     are rendered 30 ms after their stamps: cam1b's offset found within 10 ms (a third of the
#     33 ms frame interval: a start the filter's offset states refine), and no camera reported
#     farther than that from its truth (the cameras that face across the motion in this near
#     scene are refused, not guessed);
#  2. rigpose-offsets --timesync-json writes it into a copy of rig.yaml as cam1b's
#     time_offset_s, which the daemon's parser reads back (rigpose-timesync prints it as the
#     configured value);
#  3. with the real data beside the repository (../shared/data or $RIGPOSE_DATA): EuRoC MH01's
#     right camera one frame (50 ms) late, as a replay folder from rigpose-realdata
#     --pair-shift 1: found within 3 of its sigmas, sigma under 5 ms.
set -u
root=$(cd "$(dirname "$0")/../.." && pwd)
rel=$root/build/release
bin=${RP_TIMESYNC_BIN:-$rel/rigpose-timesync}
# make exports a path relative to the repository; the runs below cd into their folders
case $bin in /*) ;; *) bin=$root/$bin ;; esac
data=${RIGPOSE_DATA:-$root/../shared/data}
work=$(mktemp -d /tmp/rp_timesync_XXXXXX)
trap 'rm -rf "$work"' EXIT
pass=0; fail=0; skip=0
ok() { pass=$((pass + 1)); echo "[       OK ] $1"; }
bad() { fail=$((fail + 1)); echo "[  FAILED  ] $1"; }

"$rel/rigpose-render" --out "$work/r" --motion smooth --frames 100 --width 320 --height 240 \
    --ss 1 --cam-offsets-ms 0,0,0,0,30,0 >"$work/render.log" 2>&1 || { cat "$work/render.log"; exit 1; }
(cd "$work/r" && "$bin" --config rig.yaml --json-out "$work/r.json") >"$work/ts.log" 2>&1
cat "$work/ts.log"
if python3 - "$work/r.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
truth = {"cam1b": 0.030}
found = dict(zip(d["cameras"], d["time_offset_s"]))
if found.get("cam1b") is None:
    sys.exit("cam1b not found")
for name, off in found.items():
    if off is not None and abs(off - truth.get(name, 0.0)) > 0.010:
        sys.exit("%s: %.4f s, truth %.4f s" % (name, off, truth.get(name, 0.0)))
EOF
then ok "rendered: cam1b's 30 ms found within 10 ms, no camera reported wrong"
else bad "rendered: cam1b's 30 ms offset"; fi

cp "$work/r/rig.yaml" "$work/r/rig_synced.yaml"
if "$rel/rigpose-offsets" --timesync-json "$work/r.json" --write "$work/r/rig_synced.yaml" \
     >"$work/off.log" 2>&1 &&
   (cd "$work/r" && "$bin" --config rig_synced.yaml --sets 3 2>&1 || true) |
     python3 -c 'import json, sys
want = 1e3 * json.load(open(sys.argv[1]))["time_offset_s"][4]
for line in sys.stdin:
    f = line.split()
    if f and f[0] == "cam1b":
        sys.exit(0 if abs(float(f[4]) - want) < 1e-3 else 1)
sys.exit(1)' "$work/r.json"; then
  ok "rigpose-offsets --timesync-json wrote cam1b's time_offset_s; the parser reads it back"
else cat "$work/off.log"; bad "rigpose-offsets --timesync-json --write"; fi

euroc=$data/euroc_mh01_000-149
if [ -d "$euroc" ]; then
  if "$rel/rigpose-realdata" --euroc "$euroc" --pair-shift 1 --replay-out "$work/e" --no-run \
       >"$work/e.log" 2>&1 &&
     (cd "$work/e" && "$bin" --config rig.yaml --json-out "$work/e.json") >"$work/ets.log" 2>&1 &&
     python3 - "$work/e.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
off, sd = d["time_offset_s"][1], d["sigma_s"][1]
print("EuRoC, right camera 50 ms late: %.2f +- %.2f ms" % (1e3 * off, 1e3 * sd))
sys.exit(0 if abs(off - 0.050) <= 3 * sd and sd < 0.005 else 1)
EOF
  then ok "EuRoC MH01, right camera one frame late: 50 ms found within 3 sigma"
  else cat "$work/e.log" "$work/ets.log" 2>/dev/null | tail -5; bad "EuRoC 50 ms"; fi
else
  skip=1; echo "[  SKIPPED ] 1 test(s): no euroc_mh01_000-149/ in $data (set RIGPOSE_DATA)"
fi
echo "[  PASSED  ] $pass test(s)."
if [ $fail -ne 0 ]; then echo "[  FAILED  ] $fail test(s)."; exit 1; fi
