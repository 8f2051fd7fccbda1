#!/usr/bin/env bash
# Runs test binaries (optionally through $RP_TEST_RUNNER, e.g. qemu-aarch64), shows each one's
# cmocka output, and ends with one summary line: "tests: N passed, N failed".
set -u
runner=${RP_TEST_RUNNER:-}
pass=0; fail=0; failed=()
for t in "$@"; do
  echo "== $t"
  if [ -n "$runner" ]; then out=$($runner "$t" 2>&1); rc=$?; else out=$("$t" 2>&1); rc=$?; fi
  echo "$out"
  n_ok=$(grep -Eo '^\[  PASSED  \] [0-9]+' <<<"$out" | grep -Eo '[0-9]+$' | tail -1)
  n_bad=$(grep -Eo '^\[  FAILED  \] [0-9]+' <<<"$out" | grep -Eo '[0-9]+$' | tail -1)
  pass=$((pass + ${n_ok:-0}))
  if [ $rc -ne 0 ]; then
    fail=$((fail + ${n_bad:-1})); failed+=("$t (exit $rc)")
  fi
done
echo
for f in "${failed[@]+"${failed[@]}"}"; do echo "FAILED: $f"; done
echo "tests: $pass passed, $fail failed"
[ $fail -eq 0 ] && [ $pass -gt 0 ]
