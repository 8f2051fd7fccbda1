#!/usr/bin/env bash
# test_log.sh - rigpose-log (make test) on a small rendered replay folder (rigpose-render, 12 sets
# of the six-camera rig), through the platform HAL's replay source:
#  - record into a replay folder and an LCM log: every set, the truth, a rig.yaml the daemon loads;
#  - the log is standard LCM (read by the lcm Python package: 72 rigpose.image_t);
#  - replay: the log back into a folder; the daemon gives the same poses on the source folder,
#    the recorded one and the replayed one (rigpose-eval: ATE 0);
#  - a missing image: the set is counted as lost and said, the rest recorded, exit 1;
#  - --listen: the daemon's poses, published on udpm (this host only), land in the log;
#  - a sim configuration (features, no images) and a missing file are refused (exit 2).
set -u
bin=${RP_LOG_BIN:-build/release/rigpose-log}
rel=$(dirname "$bin")
work=${RP_LOG_WORK:-build/log/work}
PY=${PY:-.venv/bin/python}
export PYTHONPATH=${RP_LCM_PY:-$rel/../lcmgen/python}
rm -rf "$work" && mkdir -p "$work"
pass=0; fail=0
check() { if eval "$2"; then echo "[       OK ] $1"; pass=$((pass+1)); else echo "[  FAILED  ] $1"; fail=$((fail+1)); fi; }
poses() { # folder log: the daemon's poses on a folder's rig.yaml into an LCM log
  "$rel/rigpose" --config "$1/rig.yaml" --fast --quiet --lcm-url "file://$2?mode=w" > /dev/null 2>&1
}

"$rel/rigpose-render" --out "$work/src" --frames 12 --width 320 --height 240 --face-px 256 --ss 1 \
    > /dev/null 2>&1
check "rendered source folder" '[ -s "$work/src/frames.csv" ]'

"$bin" record --config "$work/src/rig.yaml" --dir "$work/rec" --log "$work/rec.log" --fast \
    2> "$work/rec.err"; rc=$?
cat "$work/rec.err"
check "record: exit 0, 12 sets, nothing lost" '[ $rc -eq 0 ] && grep -q "done: 12 sets.*lost sets 0" "$work/rec.err"'
check "record: frames.csv has 12 sets" '[ $(($(wc -l < "$work/rec/frames.csv") - 1)) -eq 12 ]'
check "record: truth.csv as the source's" 'cmp -s "$work/rec/truth.csv" "$work/src/truth.csv"'
n=$("$PY" - "$work/rec.log" <<'PYEOF'
import sys, lcm
from rigpose import image_t
n = 0
for ev in lcm.EventLog(sys.argv[1], "r"):
    if ev.channel == "RIGPOSE_IMAGE":
        m = image_t.decode(ev.data)
        n += m.width == 320 and m.height == 240 and len(m.data) == 320 * 240
print(n)
PYEOF
)
check "LCM log read by the lcm package: $n of 72 rigpose.image_t 320x240" '[ "$n" = 72 ]'

"$bin" replay "$work/rec.log" --dir "$work/back" --config "$work/src/rig.yaml" 2> "$work/back.err"; rc=$?
cat "$work/back.err"
check "replay: the log back into a folder, exit 0" '[ $rc -eq 0 ] && [ -s "$work/back/rig.yaml" ]'

poses "$work/src" "$work/src.log"; poses "$work/rec" "$work/rec-poses.log"; poses "$work/back" "$work/back-poses.log"
for d in rec back; do
  "$rel/rigpose-eval" --truth "$work/src.log" --est "$d=$work/$d-poses.log" --json "$work/$d.json" > /dev/null
  ate=$(sed -n 's/.*"eval_'$d'_ate_rmse_m": \([^,]*\),.*/\1/p' "$work/$d.json")
  check "daemon on the $d folder: the source's 12 poses exactly (ATE $ate m)" \
    '[ "$ate" = 0 ] && grep -q "\b12 \b" <("$rel/rigpose-eval" --truth "$work/src.log" --est "$d=$work/$d-poses.log" | tail -1 | tr -s " ")'
done

cp -r "$work/src" "$work/broken" && rm -f "$work/broken/cam3/000005".*
"$bin" record --config "$work/broken/rig.yaml" --dir "$work/rec_broken" --fast 2> "$work/broken.err"; rc=$?
cat "$work/broken.err"
check "a missing image: exit 1, the set said lost, 11 recorded" \
  '[ $rc -eq 1 ] && grep -q "set lost.*000005" "$work/broken.err" && grep -q "done: 11 sets.*lost sets 1" "$work/broken.err"'

tag=L$$_$RANDOM
url='udpm://239.255.76.67:7667?ttl=0'
"$bin" record --config "$work/src/rig.yaml" --log "$work/listen.log" --fast --listen "$url" \
    --pose-channel "P_$tag" --status-channel "S_$tag" --linger-ms 4000 2> "$work/listen.err" &
logger=$!
sleep 1
"$rel/rigpose" --config "$work/src/rig.yaml" --fast --quiet --lcm-url "$url" \
    --pose-channel "P_$tag" --status-channel "S_$tag" > /dev/null 2>&1
wait $logger; rc=$?
cat "$work/listen.err"
np=$("$PY" -c "
import sys, lcm
print(sum(1 for ev in lcm.EventLog('$work/listen.log', 'r') if ev.channel == 'P_$tag'))")
check "--listen: the daemon's 12 poses in the log ($np)" '[ $rc -eq 0 ] && [ "$np" = 12 ]'

"$bin" record --config config/sim.yaml --dir "$work/simrec" > /dev/null 2>&1; rc=$?
check "sim configuration refused: exit 2" '[ $rc -eq 2 ]'
"$bin" record --config "$work/none.yaml" --dir "$work/x" > /dev/null 2>&1; rc=$?
check "missing configuration: exit 2" '[ $rc -eq 2 ]'
"$bin" > /dev/null 2>&1; rc=$?
check "no arguments: usage, exit 2" '[ $rc -eq 2 ]'

if [ $fail -eq 0 ]; then echo "[  PASSED  ] $pass test(s)."; else echo "[  FAILED  ] $fail test(s)."; exit 1; fi
