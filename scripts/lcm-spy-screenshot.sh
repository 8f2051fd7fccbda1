#!/usr/bin/env bash
# lcm-spy-screenshot.sh [BUILD] [OUT.png] - lcm-spy decoding the daemon's pose channel, as a
# picture: starts Xvfb, lcm-spy with the generated jar on CLASSPATH (as lcm-spy's manual says),
# the daemon on the simulated rig (udpm ttl=0: this host only), opens the RIGPOSE_POSE viewer
# with a double click (xdotool) and takes a screenshot of the screen (ImageMagick `import`).
# Default: build, docs/lcm-spy.png. Needs `make` first (the jar and the daemon).
#
# Debian 12's /usr/bin/lcm-spy passes -Xincgc, which Java 17 refuses;
# JDK_JAVA_OPTIONS=-XX:+IgnoreUnrecognizedVMOptions lets it start (README.md shows the command).
set -euo pipefail
BUILD=${1:-build}
OUT=${2:-docs/lcm-spy.png}
cd "$(dirname "$0")/.."
JAR=$BUILD/lcmgen/rigpose_lcm.jar
DAEMON=$BUILD/release/rigpose
for f in "$JAR" "$DAEMON"; do [ -e "$f" ] || { echo "lcm-spy-screenshot: $f missing (make)" >&2; exit 1; }; done
URL='udpm://239.255.76.67:7667?ttl=0'

inner() {
  set -euo pipefail
  JDK_JAVA_OPTIONS=-XX:+IgnoreUnrecognizedVMOptions CLASSPATH="$JAR" \
      lcm-spy --lcm-url="$URL" >"$TMP/spy.out" 2>&1 &
  local spy=$!
  "$DAEMON" --config config/sim.yaml --frames 900 --quiet >"$TMP/daemon.out" 2>&1 &
  local dmn=$!
  local win=""
  for _ in $(seq 100); do
    win=$(xdotool search --name "LCM Spy" 2>/dev/null | head -1) && [ -n "$win" ] && break
    sleep 0.1
  done
  [ -n "$win" ] || { echo "lcm-spy-screenshot: no lcm-spy window"; cat "$TMP/spy.out"; exit 1; }
  xdotool windowmove "$win" 0 0 windowsize "$win" 700 260
  sleep 3   # the channel list fills while the daemon publishes
  # Rows are sorted by channel: RIGPOSE_POSE is the first. A double click opens its viewer; on a
  # loaded machine the row may not be there yet: click again, up to 10 times.
  local viewer="" tries
  for tries in $(seq 10); do
    xdotool mousemove --window "$win" 60 28 click --repeat 2 --delay 80 1
    for _ in $(seq 20); do
      viewer=$(xdotool search --name "RIGPOSE_POSE" 2>/dev/null | head -1 || true)
      [ -n "$viewer" ] && break 2
      sleep 0.1
    done
  done
  [ -n "$viewer" ] && xdotool windowmove "$viewer" 0 280 windowsize "$viewer" 700 780
  sleep 2
  import -window root "$OUT"
  kill "$dmn" "$spy" 2>/dev/null || true
  wait 2>/dev/null || true
  local ntypes
  ntypes=$(ls lcm_types/*.lcm | wc -l)
  grep -q "Found $ntypes LCM types" "$TMP/spy.out" ||
    { echo "lcm-spy did not find the $ntypes rigpose types"; cat "$TMP/spy.out"; exit 1; }
  [ -n "$viewer" ] || { echo "lcm-spy-screenshot: no RIGPOSE_POSE viewer window"; exit 1; }
}
if [ "${RP_SPY_INNER:-}" = 1 ]; then inner; exit 0; fi
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
# Again, inside the X server (xvfb-run's /bin/sh does not pass bash functions on).
RP_SPY_INNER=1 TMP=$TMP xvfb-run -a -s "-screen 0 720x1080x24" "$PWD/scripts/lcm-spy-screenshot.sh" \
    "$BUILD" "$OUT"
echo "lcm-spy-screenshot: $OUT"
