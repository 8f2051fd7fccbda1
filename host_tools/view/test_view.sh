#!/usr/bin/env bash
# test_view.sh - rigpose-view and the MCAP conversion (make test; under the multicast lock,
# SERIAL_TESTS: udpm ttl=0 keeps everything on this host, channels carry this process's id):
#   1. README's quick start, in its order: the daemon running on the simulated rig (30 s, as
#      `make run RUN_ARGS="--frames 900"`), then `rigpose-view --mcap run.mcap --poses 300`, then
#      the MCAP checked (300 consecutive poses, world -> cam1 transforms, Foxglove schemas);
#   2. every pose of a 300-set daemon run reaches the MCAP as a world -> cam1 transform, in
#      order, with Foxglove's schema names (decoded with PyPI mcap + mcap-protobuf-support);
#   3. the same run recorded as an LCM log (file://) and converted by `rigpose-log mcap`: every
#      transform equal to the recorded pose_t;
#   4. a WebSocket client on the live server (127.0.0.1) receives every pose of a 100-set run;
#   5. a rendered replay run with the image channel on: RawImage + ImageAnnotations per camera;
#   6. the Foxglove layout in the repo is what make_layout.py writes.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
VIEW=${RP_VIEW_BIN:-build/release/rigpose-view}
REL=$(dirname "$VIEW")
DAEMON=$REL/rigpose
PY=${PY:-.venv/bin/python}
export PYTHONPATH=$REL/../lcmgen/python
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
TAG=V$$_$RANDOM
CH=(--pose-channel "P_$TAG" --status-channel "S_$TAG")
TMP=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$TMP"' EXIT
pass=0; fail=0
ok()  { echo "[       OK ] $1"; pass=$((pass + 1)); }
bad() { echo "[  FAILED  ] $1"; fail=$((fail + 1)); }
wait_ready() { for _ in $(seq 150); do [ -e "$1" ] && return 0; sleep 0.1; done; return 1; }
check_mcap() { "$PY" host_tools/view/check_mcap.py "$@" > "$TMP/check.out" 2>&1; local rc=$?
               cat "$TMP/check.out"; return $rc; }

# ---- 1. README's quick start: daemon, then rigpose-view --mcap, then look -------------------------
"$DAEMON" --config config/sim.yaml --frames 900 --quiet --lcm-url "$URL" "${CH[@]}" \
    > "$TMP/d1.out" 2>&1 &
D1=$!
timeout 60 "$VIEW" --mcap "$TMP/run.mcap" --poses 300 --config config/sim.yaml --lcm-url "$URL" \
    "${CH[@]}" > "$TMP/v1.out" 2>&1; vrc=$?
kill -INT $D1 2>/dev/null; wait $D1
cat "$TMP/v1.out"
[ $vrc -eq 0 ] && check_mcap "$TMP/run.mcap" --expect 300 --first-seq -1 \
  && ok "quick start: daemon running, rigpose-view --mcap: 300 consecutive poses in the MCAP" \
  || bad "quick start (rigpose-view exit $vrc)"

# ---- 2. every pose of a 300-set run, live into an MCAP ----------------------------------------------
"$VIEW" --mcap "$TMP/live.mcap" --poses 300 --idle 5 --config config/sim.yaml --lcm-url "$URL" \
    --pose-channel "P2_$TAG" --status-channel "S2_$TAG" --ready "$TMP/v2.ready" \
    > "$TMP/v2.out" 2>&1 &
V2=$!
if wait_ready "$TMP/v2.ready"; then
  "$DAEMON" --config config/sim.yaml --frames 300 --fast --quiet --lcm-url "$URL" \
      --pose-channel "P2_$TAG" --status-channel "S2_$TAG" > "$TMP/d2.out" 2>&1; drc=$?
  wait $V2; vrc=$?
  cat "$TMP/v2.out"
  [ $drc -eq 0 ] && [ $vrc -eq 0 ] && check_mcap "$TMP/live.mcap" --expect 300 --first-seq 0 \
    && ok "300-set run: poses 0..299 as transforms in the MCAP, in order, Foxglove schemas" \
    || bad "300-set run to MCAP (daemon $drc, rigpose-view $vrc)"
else bad "rigpose-view did not start: $(cat "$TMP/v2.out")"; fi

# ---- 3. an LCM log converted by rigpose-log mcap -------------------------------------------------------
"$DAEMON" --config config/sim.yaml --frames 300 --fast --quiet \
    --lcm-url "file://$TMP/run.lcmlog?mode=w" > "$TMP/d3.out" 2>&1
"$REL/rigpose-log" mcap "$TMP/run.lcmlog" "$TMP/log.mcap" --config config/sim.yaml \
    > "$TMP/l3.out" 2>&1; lrc=$?
cat "$TMP/l3.out"
[ $lrc -eq 0 ] && check_mcap "$TMP/log.mcap" --expect 300 --lcm-log "$TMP/run.lcmlog" \
  && ok "rigpose-log mcap: the recording's 300 poses, each transform equal to its pose_t" \
  || bad "rigpose-log mcap (exit $lrc)"

# ---- 4. a WebSocket client on the live server -----------------------------------------------------
PORT=$("$PY" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$VIEW" --port "$PORT" --poses 100 --idle 10 --config config/sim.yaml --lcm-url "$URL" \
    --pose-channel "P4_$TAG" --status-channel "S4_$TAG" > "$TMP/v4.out" 2>&1 &
V4=$!
"$PY" host_tools/view/ws_client.py --port "$PORT" --expect 100 --ready "$TMP/ws.ready" \
    > "$TMP/ws.out" 2>&1 &
WS=$!
if wait_ready "$TMP/ws.ready"; then
  "$DAEMON" --config config/sim.yaml --frames 100 --fast --quiet --lcm-url "$URL" \
      --pose-channel "P4_$TAG" --status-channel "S4_$TAG" > "$TMP/d4.out" 2>&1; drc=$?
  wait $WS; wrc=$?; wait $V4; vrc=$?
  cat "$TMP/v4.out" "$TMP/ws.out"
  [ $drc -eq 0 ] && [ $wrc -eq 0 ] && [ $vrc -eq 0 ] \
    && ok "WebSocket client on ws://127.0.0.1:$PORT: 100 poses and transforms, schemas advertised" \
    || bad "WebSocket (daemon $drc, client $wrc, rigpose-view $vrc)"
else
  cat "$TMP/v4.out" "$TMP/ws.out"; bad "WebSocket client did not subscribe"
fi

# ---- 5. camera images of a rendered run ---------------------------------------------------------
if [ -x "$REL/rigpose-render" ]; then
  "$REL/rigpose-render" --out "$TMP/render" --frames 6 --width 320 --height 240 --face-px 256 \
      --ss 1 > "$TMP/r5.out" 2>&1
  "$DAEMON" --config "$TMP/render/rig.yaml" --fast --quiet --image-channel RIGPOSE_IMAGE \
      --lcm-url "file://$TMP/img.lcmlog?mode=w" > "$TMP/d5.out" 2>&1; drc=$?
  "$REL/rigpose-log" mcap "$TMP/img.lcmlog" "$TMP/img.mcap" --config "$TMP/render/rig.yaml" \
      > "$TMP/l5.out" 2>&1; lrc=$?
  cat "$TMP/l5.out"
  [ $drc -eq 0 ] && [ $lrc -eq 0 ] && check_mcap "$TMP/img.mcap" --expect 6 --images \
    && ok "rendered run with images: RawImage and ImageAnnotations per camera, 6 poses" \
    || bad "images (daemon $drc, rigpose-log $lrc)"
else
  bad "$REL/rigpose-render not built"
fi

# ---- 6. the layout file is what make_layout.py writes ------------------------------------------
"$PY" host_tools/view/make_layout.py "$TMP/layout.json" > /dev/null 2>&1 &&
  cmp -s "$TMP/layout.json" host_tools/view/rigpose.layout.json \
  && ok "host_tools/view/rigpose.layout.json is current (make view-layout)" \
  || bad "host_tools/view/rigpose.layout.json differs from make_layout.py's (make view-layout)"

echo
echo "[  PASSED  ] $pass test(s)."
[ $fail -eq 0 ] && exit 0
echo "[  FAILED  ] $fail test(s)."
exit 1
