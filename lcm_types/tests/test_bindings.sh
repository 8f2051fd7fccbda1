#!/usr/bin/env bash
# test_bindings.sh BUILD - the LCM types in every generated language receive the daemon's poses,
# on this host only (udpm ttl=0; run under the multicast lock, SERIAL_TESTS):
#   1. a C++ subscriber (lcm-gen -x types, ASan + UBSan) and a Java decoder (the generated
#      rigpose_lcm.jar with Debian's lcm.jar) both receive every pose of a 300-set daemon run,
#      seq 0..299 in order;
#   2. the Python wheel installs with pip (into a scratch folder) and decodes a pose;
#   3. lcm-spy, started under Xvfb with the jar on CLASSPATH, finds the rigpose types and opens
#      the RIGPOSE_POSE viewer (scripts/lcm-spy-screenshot.sh, the command behind docs/lcm-spy.png).
set -u
BUILD=${1:?usage: test_bindings.sh BUILD}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
DAEMON=$BUILD/release/rigpose
GEN=$BUILD/lcmgen
PY=${PY:-.venv/bin/python}
LCMJAR=/usr/share/java/lcm.jar
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
JURL='udpm://239.255.76.67:7667?ttl=0'
TAG=B$$_$RANDOM
TMP=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$TMP"' EXIT
pass=0; fail=0
ok()  { echo "[       OK ] $1"; pass=$((pass + 1)); }
bad() { echo "[  FAILED  ] $1"; fail=$((fail + 1)); }
wait_ready() { for _ in $(seq 150); do [ -e "$1" ] && return 0; sleep 0.1; done; return 1; }

# ---- 1. C++ and Java subscribers ------------------------------------------------------------
"$BUILD/lcm_types/sub_cpp" "$URL" "P_$TAG" 300 "$TMP/cpp.ready" >"$TMP/cpp.out" 2>&1 &
CPP=$!
java -Djava.net.preferIPv4Stack=true -cp "$LCMJAR:$GEN/rigpose_lcm.jar:$BUILD/lcm_types" \
    SubJava "$JURL" "P_$TAG" 300 "$TMP/java.ready" >"$TMP/java.out" 2>&1 &
JAVA=$!
if wait_ready "$TMP/cpp.ready" && wait_ready "$TMP/java.ready"; then
  # Paced at the camera rate (30 Hz, 10 s): the Java provider's socket keeps the OS default
  # buffer, which a --fast burst of 300 poses can overrun on a loaded machine.
  "$DAEMON" --config config/sim.yaml --frames 300 --quiet --lcm-url "$URL" \
      --pose-channel "P_$TAG" --status-channel "S_$TAG" >"$TMP/d.out" 2>&1; drc=$?
  wait $CPP; crc=$?; wait $JAVA; jrc=$?
  cat "$TMP/cpp.out" "$TMP/java.out"
  [ $drc -eq 0 ] && [ $crc -eq 0 ] && ok "C++ subscriber (rigpose::pose_t): 300 poses in order" \
    || bad "C++ subscriber: daemon exit $drc, subscriber exit $crc"
  [ $drc -eq 0 ] && [ $jrc -eq 0 ] && ok "Java decoder (rigpose_lcm.jar): 300 poses in order" \
    || bad "Java decoder: daemon exit $drc, decoder exit $jrc"
else
  cat "$TMP/cpp.out" "$TMP/java.out"; bad "C++ / Java subscribers did not start"
fi

# ---- 2. the Python wheel --------------------------------------------------------------------
whl=$(ls "$GEN"/rigpose_lcm-*-py3-none-any.whl 2>/dev/null | head -1)
if [ -n "$whl" ] && "$PY" -m pip install -q --disable-pip-version-check --no-deps --no-index \
       --target "$TMP/site" "$whl" >"$TMP/pip.out" 2>&1 &&
   env -u PYTHONPATH PYTHONPATH="$TMP/site" "$PY" -c '
import rigpose, sys
assert rigpose.__file__.startswith(sys.argv[1]), rigpose.__file__
m = rigpose.pose_t(); m.seq = 7; m.quaternion = [1.0, 0.0, 0.0, 0.0]
assert rigpose.pose_t.decode(m.encode()).seq == 7
print("wheel: rigpose from", rigpose.__file__)' "$TMP/site"; then
  ok "pip installs $(basename "$whl"); pose_t round trip"
else
  cat "$TMP/pip.out"; bad "Python wheel"
fi

# ---- 3. lcm-spy decodes the pose channel ------------------------------------------------------
# The command that takes docs/lcm-spy.png, here into a scratch file: Xvfb, lcm-spy with the jar on
# CLASSPATH, the daemon publishing, the RIGPOSE_POSE viewer opened; it fails unless lcm-spy
# found the three rigpose types and the viewer window opened.
if scripts/lcm-spy-screenshot.sh "$BUILD" "$TMP/spy.png" >"$TMP/spy.out" 2>&1 &&
   [ "$(stat -c %s "$TMP/spy.png" 2>/dev/null || echo 0)" -gt 20000 ]; then
  ok "lcm-spy (CLASSPATH=rigpose_lcm.jar) decodes RIGPOSE_POSE: screenshot $(stat -c %s "$TMP/spy.png") bytes"
else
  cat "$TMP/spy.out"; bad "lcm-spy under Xvfb"
fi

echo
echo "[  PASSED  ] $pass test(s)."
[ $fail -eq 0 ] && exit 0
echo "[  FAILED  ] $fail test(s)."
exit 1
