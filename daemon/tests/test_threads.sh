#!/usr/bin/env bash
# test_threads.sh BUILD - the release daemon's poses do not depend on its threads (issue 17
# item 1): a rendered replay (rigpose-render, 45 sets, 320x240) run with --threads 1, 2 and 4,
# stereo4 on the four cameras it uses and gc on cam1..cam4; every pose of every run is bit for
# bit the one-thread run's (pose_log_diff.py: all pose_t fields but the wall-clock publish time
# and the instance), and the runs track (the summary's error against the replay's truth is
# printed). Poses go to file:// logs: nothing on the network.
set -u
BUILD=${1:?usage: test_threads.sh BUILD}
. "$(dirname "$0")/../../tests/script_env.sh"

"$REL/rigpose-render" --out "$TMP/src" --frames 45 --width 320 --height 240 --face-px 256 \
    --ss 1 > "$TMP/render.out" 2>&1 || { cat "$TMP/render.out"; echo "FAIL render"; exit 1; }
"$PY" daemon/tests/rig_subset.py "$TMP/src/rig.yaml" "$TMP/src/stereo4.yaml" cam2 cam4 ||
    { echo "FAIL rig_subset"; exit 1; }
sed -e 's/^  method: stereo4$/  method: gc/' \
    -e 's/^  pairs: \[\[cam1, cam1b\], \[cam3, cam3b\]\]$/  cams: [cam1, cam2, cam3, cam4]/' \
    "$TMP/src/rig.yaml" > "$TMP/src/gc.yaml"
grep -q '^  method: gc$' "$TMP/src/gc.yaml" && grep -q '^  cams: ' "$TMP/src/gc.yaml" ||
    { echo "FAIL gc.yaml: the rendered estimator section changed"; exit 1; }

passed=0; failed=0
for m in stereo4 gc; do
  for n in 1 2 4; do
    "$REL/rigpose" --config "$TMP/src/$m.yaml" --fast --quiet --threads "$n" \
        --lcm-url "file://$TMP/$m.$n.log?mode=w" > "$TMP/$m.$n.out" 2>&1
    rc=$?
    if [ $rc -ne 0 ] || ! grep -q "method $m, $n thread" "$TMP/$m.$n.out"; then
      cat "$TMP/$m.$n.out"; echo "FAIL $m --threads $n: exit $rc"; failed=$((failed + 1)); continue
    fi
    [ "$n" = 1 ] && grep "mean abs error" "$TMP/$m.$n.out"
    [ "$n" = 1 ] && continue
    if "$PY" daemon/tests/pose_log_diff.py "$TMP/$m.1.log" "$TMP/$m.$n.log"; then
      echo "ok $m --threads $n: poses identical to --threads 1"; passed=$((passed + 1))
    else
      echo "FAIL $m --threads $n: poses differ from --threads 1"; failed=$((failed + 1))
    fi
  done
done
echo "[  PASSED  ] $passed test(s)."
[ $failed -eq 0 ] || { echo "[  FAILED  ] $failed test(s)."; exit 1; }
