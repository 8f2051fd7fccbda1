#!/usr/bin/env bash
# test_lcm.sh BUILD - the rigpose daemon between processes, on this host only (udpm ttl=0, and
# LCM log files):
#   1. bad configuration files: the daemon refuses to start (exit 2) naming file:line: key;
#   2. a separate Python process (PyPI lcm + the lcm-gen types) receives every pose of a
#      300-frame run in order, no gap in seq;
#   3. lcm-logger records a run, lcm-logplayer replays the log into a subscriber: every pose;
#   4. a camera that vanishes mid-run is reported on the status channel and poses keep coming;
#   5. SIGTERM stops a running daemon cleanly (exit 0, summary printed);
#   6. so do SIGHUP and SIGPIPE (stdout into a reader that quit: the summary on stderr); an
#      unwritable --stats-json path is refused before the run (exit 1);
#   7. two daemons on one pose channel: each names the other's instance (pose_t.instance).
# Channels carry this process's id, so concurrent runs on the same host do not mix.
set -u
BUILD=${1:?usage: test_lcm.sh BUILD}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
DAEMON=$BUILD/release/rigpose
PY=${PY:-.venv/bin/python}
export PYTHONPATH=$BUILD/lcmgen/python
# recv_buf_size: room for a whole --fast run in every receiver's socket buffer (the kernel caps
# it at net.core.rmem_max), so a receiver starved of CPU on a loaded machine loses nothing.
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
TAG=T$$_$RANDOM
TMP=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$TMP"' EXIT
pass=0; fail=0

ok()  { echo "ok   $1"; pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); }

# Start the subscriber in the background and wait until it has subscribed.
start_sub() { # name args...
  local name=$1; shift
  rm -f "$TMP/$name.ready"
  "$PY" daemon/tests/lcm_sub.py --url "$URL" --ready "$TMP/$name.ready" "$@" \
      >"$TMP/$name.out" 2>&1 &
  SUB_PID=$!
  for _ in $(seq 100); do [ -e "$TMP/$name.ready" ] && return 0; sleep 0.1; done
  echo "subscriber $name did not start:"; cat "$TMP/$name.out"; return 1
}

# ---- 1. bad configuration files -------------------------------------------------------------
sed 's/^  method: stereo4/  method: stereo5/' config/sim.yaml >"$TMP/bad_method.yaml"
sed 's/^    intrinsics: \[800, 800, 319.5, 239.5\]   # fx fy cx cy, px/    intrinsics: [800, 800]/' \
    config/sim.yaml >"$TMP/bad_intrinsics.yaml"
grep -v '^version:' config/sim.yaml >"$TMP/no_version.yaml"
for case in "bad_method.yaml:estimator.method" "bad_intrinsics.yaml:cameras\[0\].intrinsics" \
            "no_version.yaml:version"; do
  f=${case%%:*}; key=${case#*:}
  "$DAEMON" --config "$TMP/$f" --frames 1 >"$TMP/out" 2>"$TMP/err"; rc=$?
  if [ $rc -eq 2 ] && grep -Eq "$TMP/$f:[0-9]+: $key: " "$TMP/err"; then
    ok "bad config $f: exit 2, $(cat "$TMP/err")"
  else
    bad "bad config $f: exit $rc, stderr: $(cat "$TMP/err")"
  fi
done
"$DAEMON" --config "$TMP/none.yaml" >/dev/null 2>"$TMP/err"; rc=$?
[ $rc -eq 2 ] && ok "missing config file: exit 2" || bad "missing config file: exit $rc"
"$DAEMON" --frames 3 >/dev/null 2>&1; rc=$?
[ $rc -eq 1 ] && ok "no --config: exit 1" || bad "no --config: exit $rc"

# ---- 2. 300 poses to a Python subscriber in another process ----------------------------------
if start_sub run300 --pose-channel "P_$TAG" --status-channel "S_$TAG" --expect 300; then
  "$DAEMON" --config config/sim.yaml --frames 300 --fast --quiet --lcm-url "$URL" \
      --pose-channel "P_$TAG" --status-channel "S_$TAG" >"$TMP/d300" 2>&1; drc=$?
  wait $SUB_PID; src=$?
  cat "$TMP/run300.out"; tail -2 "$TMP/d300"
  [ $drc -eq 0 ] && [ $src -eq 0 ] && ok "300-frame run: every pose received in order" \
    || bad "300-frame run: daemon exit $drc, subscriber exit $src"
else bad "300-frame run: no subscriber"; fi

# ---- 3. lcm-logger records, lcm-logplayer replays ---------------------------------------------
lcm-logger -f --lcm-url="$URL" --channel="P_${TAG}_LOG" "$TMP/run.lcmlog" >"$TMP/logger.out" 2>&1 &
LOGGER=$!
sleep 0.5
# Paced at the camera rate (30 Hz, 3.3 s) and replayed at that rate: lcm-logplayer bursting a
# --fast recording at several hundred messages a second lost a few on a loaded machine.
"$DAEMON" --config config/sim.yaml --frames 100 --quiet --lcm-url "$URL" \
    --pose-channel "P_${TAG}_LOG" --status-channel "S_${TAG}_LOG" >"$TMP/dlog" 2>&1; drc=$?
sleep 0.5
kill -INT $LOGGER; wait $LOGGER 2>/dev/null
logsize=$(stat -c %s "$TMP/run.lcmlog" 2>/dev/null || echo 0)
echo "lcm-logger wrote $logsize bytes"
if [ $drc -eq 0 ] && start_sub replay --pose-channel "P_${TAG}_LOG" --expect 100; then
  lcm-logplayer --speed=1 --lcm-url="$URL" "$TMP/run.lcmlog" >"$TMP/player.out" 2>&1; prc=$?
  wait $SUB_PID; src=$?
  cat "$TMP/replay.out"
  [ $prc -eq 0 ] && [ $src -eq 0 ] && ok "lcm-logger + lcm-logplayer: 100 poses replayed in order" \
    || bad "log replay: player exit $prc, subscriber exit $src"
else bad "log replay: daemon exit $drc or no subscriber"; fi

# ---- 4. a camera vanishes mid-run ----------------------------------------------------------
if start_sub drop --pose-channel "P_${TAG}_D" --status-channel "S_${TAG}_D" --expect 120 \
     --expect-gone 2; then
  "$DAEMON" --config config/sim.yaml --frames 120 --fast --quiet --sim-drop 2:40 \
      --lcm-url "$URL" --pose-channel "P_${TAG}_D" --status-channel "S_${TAG}_D" \
      >"$TMP/ddrop" 2>&1; drc=$?
  wait $SUB_PID; src=$?
  cat "$TMP/drop.out"; grep -m1 'camera 2 (cam3): gone' "$TMP/ddrop"; grc=$?
  [ $drc -eq 0 ] && [ $src -eq 0 ] && [ $grc -eq 0 ] && ok "camera 2 gone from set 40: reported on status, 120 poses" \
    || bad "camera drop: daemon exit $drc, subscriber exit $src, 'gone' printed: $grc (0 = yes)"
else bad "camera drop: no subscriber"; fi

# ---- 5. SIGTERM ------------------------------------------------------------------------------
"$DAEMON" --config config/sim.yaml --quiet --lcm-url "$URL" --pose-channel "P_${TAG}_T" \
    --status-channel "S_${TAG}_T" >"$TMP/dterm" 2>&1 &
DPID=$!
sleep 1.5
t0=$(date +%s%N)
kill -TERM $DPID; wait $DPID; rc=$?
ms=$(( ($(date +%s%N) - t0) / 1000000 ))
if [ $rc -eq 0 ] && grep -q 'stopped by signal' "$TMP/dterm"; then
  ok "SIGTERM: exit 0 after ${ms} ms; $(grep 'poses published' "$TMP/dterm")"
else
  bad "SIGTERM: exit $rc; $(cat "$TMP/dterm")"
fi

# ---- 6. SIGHUP, SIGPIPE, an unwritable --stats-json ----------------------------------------
"$DAEMON" --config config/sim.yaml --frames 100000 --quiet --lcm-url "$URL" \
    --pose-channel "P_${TAG}_H" --status-channel "S_${TAG}_H" >"$TMP/dhup" 2>&1 &
DPID=$!
sleep 1.5
kill -HUP $DPID; wait $DPID; rc=$?
if [ $rc -eq 0 ] && grep -q 'stopped by signal SIGHUP' "$TMP/dhup"; then
  ok "SIGHUP: exit 0, summary printed"
else
  bad "SIGHUP: exit $rc; $(cat "$TMP/dhup")"
fi
# stdout into a reader that quits after one line: SIGPIPE at the next pose line
set -o pipefail
"$DAEMON" --config config/sim.yaml --frames 100000 --lcm-url "$URL" \
    --pose-channel "P_${TAG}_P" --status-channel "S_${TAG}_P" 2>"$TMP/dpipe" | head -n 1 >/dev/null
rc=$?
set +o pipefail
if [ $rc -eq 0 ] && grep -q 'stopped by signal SIGPIPE' "$TMP/dpipe" && grep -q 'poses published' "$TMP/dpipe"; then
  ok "SIGPIPE: exit 0, the summary on stderr: $(grep 'poses published' "$TMP/dpipe" | cut -c1-60)..."
else
  bad "SIGPIPE: exit $rc; $(cat "$TMP/dpipe")"
fi
"$DAEMON" --config config/sim.yaml --frames 5 --quiet --lcm-url "$URL" \
    --pose-channel "P_${TAG}_J" --status-channel "S_${TAG}_J" \
    --stats-json /nonexistent-dir/stats.json >"$TMP/djson" 2>&1
rc=$?
if [ $rc -eq 1 ] && grep -q -- '--stats-json /nonexistent-dir/stats.json: No such file' "$TMP/djson" \
   && ! grep -q 'poses published' "$TMP/djson"; then
  ok "--stats-json to an unwritable path: exit 1 before running"
else
  bad "--stats-json unwritable: exit $rc; $(cat "$TMP/djson")"
fi

# ---- 7. two daemons on one pose channel ------------------------------------------------------
for i in 1 2; do
  "$DAEMON" --config config/sim.yaml --frames 60 --quiet --lcm-url "$URL" \
      --pose-channel "P_${TAG}_2" --status-channel "S_${TAG}_2" >"$TMP/dtwo$i" 2>&1 &
done
wait
i1=$(sed -n "s/.*instance '\([^']*\)', source.*/\1/p" "$TMP/dtwo1")
i2=$(sed -n "s/.*instance '\([^']*\)', source.*/\1/p" "$TMP/dtwo2")
if [ -n "$i1" ] && [ "$i1" != "$i2" ] && grep -q "another publisher (instance '$i2')" "$TMP/dtwo1" \
   && grep -q "another publisher (instance '$i1')" "$TMP/dtwo2" \
   && ! grep -q "another publisher" "$TMP/dterm" "$TMP/dhup"; then
  ok "two daemons on one pose channel: each names the other ($i1, $i2); one alone says nothing"
else
  bad "two daemons: $(cat "$TMP/dtwo1" "$TMP/dtwo2")"
fi

echo
if [ $fail -eq 0 ]; then echo "[  PASSED  ] $pass test(s)."; exit 0; fi
echo "[  PASSED  ] $pass test(s)."
echo "[  FAILED  ] $fail test(s)."
exit 1
