#!/usr/bin/env bash
# test_offsets.sh BUILD - rigpose-offsets (host_tools/view/rigpose_offsets.py): a status log with
# estimated offsets for cameras 1 and 2 written back into a copy of config/sim.yaml (camera 1
# without a time_offset_s line: added after its name; camera 2 with one: replaced, its comment
# kept; the others untouched), again (the same file: no line added twice), and the daemon runs
# the result; a log without a status message and a missing log exit 1.
set -u
BUILD=${1:?usage: test_offsets.sh BUILD}
. "$(dirname "$0")/../../tests/script_env.sh"
TOOL=(env PYTHONPATH="$BUILD/lcmgen/python" "$PY" host_tools/view/rigpose_offsets.py)
pass=0; fail=0
ok()  { echo "[       OK ] $1"; pass=$((pass + 1)); }
bad() { echo "[  FAILED  ] $1"; fail=$((fail + 1)); }

PYTHONPATH="$BUILD/lcmgen/python" "$PY" - "$TMP/status.log" "$TMP/empty.log" <<'PYEOF'
import sys, lcm
from rigpose import status_t
m = status_t()
m.n_cams = 6
m.cam_offset_ms = [0.0, 12.25, -25.5, 0.0, 0.0, 0.0]
m.cam_offset_sigma_ms = [0.0, 0.2, 0.3, 0.0, 0.0, 0.0]
log = lcm.EventLog(sys.argv[1], "w", overwrite=True)
log.write_event(1, "RIGPOSE_STATUS", m.encode())
log.close()
log = lcm.EventLog(sys.argv[2], "w", overwrite=True)
log.write_event(1, "RIGPOSE_POSE", b"x")
log.close()
PYEOF
# camera 2 (cam3) gets a time_offset_s line with a comment to be replaced
awk '/name: cam3[ \t]/ {print; print "    time_offset_s: 0.5   # old"; next} {print}' config/sim.yaml \
    > "$TMP/rig.yaml"
for round in 1 2; do
  "${TOOL[@]}" --lcm-log "$TMP/status.log" --write "$TMP/rig.yaml" > "$TMP/out.$round" 2>&1 ||
      { cat "$TMP/out.$round"; bad "write-back round $round exits 0"; }
done
grep -q "camera 1: offset +12.250 ms, sigma 0.200 ms" "$TMP/out.1" && ok "prints the offsets" ||
    { cat "$TMP/out.1"; bad "prints the offsets"; }
n=$(grep -c "time_offset_s" "$TMP/rig.yaml")
[ "$n" = 2 ] && ok "two time_offset_s lines after two rounds" || bad "time_offset_s lines: $n, not 2"
"$PY" - "$TMP/rig.yaml" <<'PYEOF' && ok "cam2 0.012250 after its name, cam3 -0.025500 with its comment" || bad "values and places"
import sys
lines = open(sys.argv[1]).read().split("\n")
i = next(k for k, l in enumerate(lines) if "name: cam2" in l)
assert lines[i + 1] == "    time_offset_s: 0.012250", lines[i + 1]
j = next(k for k, l in enumerate(lines) if "name: cam3" in l)
assert lines[j + 1] == "    time_offset_s: -0.025500   # old", lines[j + 1]
PYEOF
sed -i 's/^  realtime: true.*/  realtime: false/' "$TMP/rig.yaml"
"$REL/rigpose" --config "$TMP/rig.yaml" --frames 3 --fast --quiet --lcm-url "file://$TMP/p.log?mode=w" \
    > "$TMP/d.out" 2>&1 && ok "the daemon runs the written file" || { cat "$TMP/d.out"; bad "the daemon runs the written file"; }
"${TOOL[@]}" --lcm-log "$TMP/empty.log" > "$TMP/e.out" 2>&1; rc=$?
[ $rc = 1 ] && grep -q "no status message" "$TMP/e.out" && ok "no status: exit 1" || bad "no status: exit $rc"
"${TOOL[@]}" --lcm-log "$TMP/none.log" > "$TMP/n.out" 2>&1; rc=$?
[ $rc = 1 ] && ok "a missing log: exit 1" || bad "a missing log: exit $rc"
echo "test_offsets: $pass passed, $fail failed"
[ $fail -eq 0 ]
